//! The permanent-magnet DC motor of the paper's section 4 (equation (17)), with a gearbox.
//!
//! Armature circuit and rotor, motor side (ω_m rotor speed [rad/s], i armature current [A]):
//!
//! ```text
//! L di/dt   = U − R i − kb ω_m
//! J dω_m/dt = km i − B ω_m − τ_load/n
//! ```
//!
//! Unloaded (τ_load = 0) the speed answers the voltage with
//! ```text
//! ω_m/U = km / (J L s² + (J R + B L) s + (B R + km kb))                        (17)
//! ```
//! The paper prints 27.19 for the constant term; its own parameters give
//! B R + km kb = 9.0946 · 2.22 + 0.00449 · 0.00448 = 20.19.
//!
//! Coupled to a pendulum joint through a rigid gear of ratio n (ω_m = n ω_joint) the motor takes
//! the joint speed as input and gives the joint torque τ = n (km i − B ω_m). The rotor inertia
//! then acts on the joint as n² J, and an acceleration-dependent torque cannot be computed from
//! a speed input without differentiating it (which, coupled explicitly, is unstable as soon as
//! n² J exceeds the link's inertia), so in coupled mode J is not part of the motor's dynamics:
//! the plant carries it (the Pendulum's J1, J2 = n² J, on the diagonal of its mass matrix);
//! see docs/composition.md.
//!
//! Numerics: the electrical time constant L/R is 55 µs with the paper's values, far below any
//! useful communication step, and with the paper's B the mechanical one is 2.4 µs. Both modes are
//! linear with the inputs held over a step, so they are advanced by the EXACT zero-order-hold
//! discretization: e^(−R h/L) for the current alone (coupled), the matrix exponential of the
//! 2×2 system (free). No step-size limit, no error but round-off, for h from 1e-9 s to hours.

use nalgebra::{Matrix3, Vector2};
use serde::{Deserialize, Serialize};

/// Motor and gearbox parameters. Defaults: the paper's motor (section 4) with a direct drive.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DcMotorParams {
    /// Armature inductance L [H]
    pub l: f64,
    /// Armature resistance R [Ω]
    pub r: f64,
    /// Torque constant km [N·m/A]
    pub km: f64,
    /// Back-EMF constant kb [V·s/rad]
    pub kb: f64,
    /// Rotor inertia J [kg·m²]
    pub j: f64,
    /// Viscous friction B at the rotor [N·m·s/rad]
    pub b: f64,
    /// Gear ratio n = rotor speed / joint speed [1]
    pub gear_ratio: f64,
    /// Supply voltage: |U| is limited to it [V]
    pub u_max: f64,
}

impl Default for DcMotorParams {
    fn default() -> Self {
        DcMotorParams {
            l: 0.000121,
            r: 2.22,
            km: 0.00449,
            kb: 0.00448,
            j: 2.18e-5,
            b: 9.0946,
            gear_ratio: 1.0,
            u_max: 6.0,
        }
    }
}

/// The motor's state.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct DcMotorState {
    /// Armature current i [A]
    pub i: f64,
    /// Rotor speed ω_m [rad/s]
    pub omega_m: f64,
}

impl DcMotorParams {
    /// Refuses parameters the equations cannot use, naming the parameter.
    pub fn validate(&self) -> Result<(), String> {
        for (name, v) in [
            ("L", self.l),
            ("R", self.r),
            ("J", self.j),
            ("gear_ratio", self.gear_ratio),
            ("U_max", self.u_max),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{name} = {v} must be a finite number > 0"));
            }
        }
        if !(self.km.is_finite() && self.km > 0.0) {
            return Err(format!("km = {} must be a finite number > 0", self.km));
        }
        for (name, v) in [("kb", self.kb), ("B", self.b)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("{name} = {v} must be a finite number >= 0"));
            }
        }
        Ok(())
    }

    /// The terminal voltage the supply can give: U clamped to ±U_max [V].
    pub fn applied_voltage(&self, u: f64) -> f64 {
        u.clamp(-self.u_max, self.u_max)
    }

    /// Torque on the joint [N·m]: n (km i − B ω_m).
    pub fn joint_torque(&self, s: &DcMotorState) -> f64 {
        self.gear_ratio * (self.km * s.i - self.b * s.omega_m)
    }

    /// Denominator of equation (17), highest power first:
    /// [J L, J R + B L, B R + km kb].
    pub fn speed_transfer_denominator(&self) -> [f64; 3] {
        [
            self.j * self.l,
            self.j * self.r + self.b * self.l,
            self.b * self.r + self.km * self.kb,
        ]
    }

    /// Stall torque at the rotor at full supply voltage [N·m]: km U_max / R.
    pub fn stall_torque(&self) -> f64 {
        self.km * self.u_max / self.r
    }

    /// Coupled to a joint turning at `omega_joint` [rad/s] (held over the step): the rotor turns
    /// at n ω_joint and the current relaxes exactly towards (U − kb ω_m)/R:
    /// i(h) = i e^(−x) + (U − kb ω_m) (1 − e^(−x))/R with x = R h/L.
    ///
    /// (1 − e^(−x))/R is computed as −expm1(−x)/R, and for x ≤ 1 as (h/L)·(−expm1(−x)/x): the
    /// closed form i_steady + (i − i_steady) e^(−x) cancels to exactly 0 when x is below the
    /// rounding of 1 (R = 1e-20 Ω: 0 A where (U − kb ω_m) h/L = 742.69 A after 15 ms), and
    /// (U − kb ω_m)/R overflows for a subnormal R. exp and expm1 come from `libm`: the same bits on
    /// every platform and thread (the workspace Cargo.toml says why).
    pub fn step_coupled(&self, s: &DcMotorState, u: f64, omega_joint: f64, h: f64) -> DcMotorState {
        let omega_m = self.gear_ratio * omega_joint;
        let drive = self.applied_voltage(u) - self.kb * omega_m;
        let x = self.r * h / self.l;
        let gain = if x > 1.0 {
            -libm::expm1(-x) / self.r
        } else if x > 0.0 {
            h / self.l * (-libm::expm1(-x) / x)
        } else {
            h / self.l
        };
        DcMotorState {
            i: s.i * libm::exp(-x) + drive * gain,
            omega_m,
        }
    }

    /// Unloaded: x = (i, ω_m), ẋ = F x + g U with U held; x(t+h) = Φ x + Γ U from the matrix
    /// exponential of [F g; 0 0]·h (Van Loan), which is exact for this linear system. An error
    /// when that exponential is beyond `f64` (parameters and step such as L = 5e-324 H).
    pub fn step_free(&self, s: &DcMotorState, u: f64, h: f64) -> Result<DcMotorState, String> {
        let (l, r, km, kb, j, b) = (self.l, self.r, self.km, self.kb, self.j, self.b);
        #[rustfmt::skip]
        let augmented = Matrix3::new(
            -r / l, -kb / l, 1.0 / l,
            km / j, -b / j,  0.0,
            0.0,    0.0,     0.0,
        ) * h;
        let e = expm(&augmented).ok_or_else(|| {
            format!("the unloaded motor's transition matrix over h = {h} s is beyond f64 (F h = {augmented})")
        })?;
        let x = e.fixed_view::<2, 2>(0, 0) * Vector2::new(s.i, s.omega_m)
            + e.fixed_view::<2, 1>(0, 2) * self.applied_voltage(u);
        Ok(DcMotorState { i: x[0], omega_m: x[1] })
    }
}

/// e^A, or `None` when A or e^A is not finite.
///
/// nalgebra's `exp` picks its number of squarings from norms of A⁴ … A¹⁰: beyond |A| ≈ 1e30
/// they overflow, and an infinite estimate makes it square 2⁶⁴ times (it hung). Such an A is
/// scaled by a power of two to norm ≤ 1 first and squared back as often (at most ~1030 times).
/// Smaller ones go to nalgebra unchanged, so their results are as before.
fn expm(a: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let finite = |m: &Matrix3<f64>| m.iter().all(|x| x.is_finite());
    if !finite(a) {
        return None;
    }
    let largest = a.amax();
    let e = if largest <= 1e29 {
        a.exp()
    } else {
        // |A| ≤ 3 max|a_ij| ≤ 2^(s), s ≤ 1026; scaled in two exact halves.
        let s = largest.log2().ceil() as i32 + 2;
        let half = libm::scalbn(1.0, -(s / 2));
        let rest = libm::scalbn(1.0, -(s - s / 2));
        let mut e = (a * half * rest).exp();
        for _ in 0..s {
            e = e * e;
        }
        e
    };
    finite(&e).then_some(e)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Step response of km / (a s² + b s + c) to U0 from rest, by the partial fractions of its
    /// two real poles (both motor parameter sets here are overdamped).
    fn eq17_step(p: &DcMotorParams, u0: f64, t: f64) -> f64 {
        let [a, b, c] = p.speed_transfer_denominator();
        let disc = (b * b - 4.0 * a * c).sqrt();
        let (p1, p2) = ((-b + disc) / (2.0 * a), (-b - disc) / (2.0 * a));
        let gain = p.km * u0 / c;
        gain * (1.0 + (p2 * (p1 * t).exp() - p1 * (p2 * t).exp()) / (p1 - p2))
    }

    /// A small motor with realistic friction and inertia (the demo's), overdamped.
    fn realistic() -> DcMotorParams {
        DcMotorParams {
            b: 1e-6,
            j: 1e-6,
            ..DcMotorParams::default()
        }
    }

    #[test]
    fn paper_constant_term_is_20_19_not_27_19() {
        let c = DcMotorParams::default().speed_transfer_denominator();
        assert!(
            (c[0] - 2.6378e-9).abs() < 1e-13,
            "J L: expected 2.6378e-9, got {}",
            c[0]
        );
        assert!(
            (c[1] - 1.1488426e-3).abs() < 1e-9,
            "J R + B L: expected 1.1488426e-3, got {}",
            c[1]
        );
        assert!(
            (c[2] - 20.19003).abs() < 1e-5,
            "B R + km kb: expected 20.19003, got {}",
            c[2]
        );
    }

    #[test]
    fn free_speed_step_response_matches_eq17_for_any_step_from_1us_to_10ms() {
        for p in [DcMotorParams::default(), realistic()] {
            for h in [1e-6f64, 1e-5, 1e-4, 1e-3, 1e-2] {
                let mut s = DcMotorState::default();
                let n = (0.02 / h).round() as usize;
                let scale = p.km * 6.0 / p.speed_transfer_denominator()[2];
                for k in 1..=n {
                    s = p.step_free(&s, 6.0, h).unwrap();
                    let t = k as f64 * h;
                    let want = eq17_step(&p, 6.0, t);
                    assert!(
                        (s.omega_m - want).abs() <= 1e-9 * scale,
                        "B = {}, h = {h}: at t = {t} expected ω = {want}, got {}",
                        p.b,
                        s.omega_m
                    );
                }
            }
        }
    }

    #[test]
    fn coupled_current_is_exact_and_stable_for_any_step() {
        let p = DcMotorParams {
            gear_ratio: 200.0,
            ..realistic()
        };
        for h in [1e-6f64, 1e-4, 1e-2] {
            let mut s = DcMotorState::default();
            let steps = (0.01 / h).round() as i32;
            for _ in 0..steps {
                s = p.step_coupled(&s, 3.0, 0.5, h);
            }
            let i_steady = (3.0 - p.kb * 200.0 * 0.5) / p.r;
            let want = i_steady * (1.0 - (-p.r * 0.01 / p.l).exp());
            assert!((s.i - want).abs() < 1e-12, "h = {h}: expected i = {want}, got {}", s.i);
        }
    }

    #[test]
    fn a_tiny_resistance_gives_the_inductive_current_not_zero() {
        // R → 0: L di/dt = U − kb ω_m, so i(h) = (U − kb ω_m) h/L to first order in R h/L.
        let p = DcMotorParams {
            r: 1e-20,
            ..DcMotorParams::default()
        };
        let mut s = DcMotorState::default();
        for _ in 0..15 {
            s = p.step_coupled(&s, 6.0, 2.0, 1e-3);
        }
        let want = (6.0 - p.kb * 2.0) * 0.015 / p.l;
        assert!(
            (s.i - want).abs() < 1e-9 * want,
            "R = 1e-20 Ohm: after 15 ms expected i = {want} A (742.69), got {} A",
            s.i
        );
        // And a subnormal R does not overflow.
        let p = DcMotorParams { r: 5e-324, ..p };
        let s = p.step_coupled(&DcMotorState::default(), 6.0, 2.0, 0.015);
        assert!((s.i - want).abs() < 1e-9 * want, "R = 5e-324: {} A", s.i);
    }

    #[test]
    fn the_unloaded_step_returns_for_any_parameters_and_step() {
        // Parameters and steps that overflow F h or its powers.
        let cases = [
            (
                DcMotorParams {
                    l: 5e-324,
                    ..realistic()
                },
                1e-3,
            ),
            (
                DcMotorParams {
                    j: 1e-310,
                    ..realistic()
                },
                1e-3,
            ),
            (realistic(), 1e300),
            (
                DcMotorParams {
                    r: 1e300,
                    ..realistic()
                },
                10.0,
            ),
        ];
        for (p, h) in cases {
            match p.step_free(&DcMotorState::default(), 6.0, h) {
                Ok(s) => assert!(s.i.is_finite() && s.omega_m.is_finite(), "L = {}, h = {h}: {s:?}", p.l),
                Err(e) => assert!(e.contains("beyond f64"), "{e}"),
            }
        }
        // Far beyond every time constant the unloaded motor is at its steady state. The paper's
        // motor over 1e35 ... 1e45 s hung nalgebra's exp; the demo's over 1e50 s and more gave NaN.
        for (p, h) in [(DcMotorParams::default(), 1e40), (realistic(), 1e60)] {
            let s = p.step_free(&DcMotorState::default(), 6.0, h).unwrap();
            let [_, _, c] = p.speed_transfer_denominator();
            let speed = p.km * 6.0 / c;
            assert!(
                (s.omega_m - speed).abs() < 1e-6 * speed,
                "B = {}, after {h:e} s: {} rad/s, steady {speed}",
                p.b,
                s.omega_m
            );
        }
    }

    #[test]
    fn supply_voltage_limits_the_current() {
        let p = DcMotorParams::default();
        let s = p.step_coupled(&DcMotorState::default(), 100.0, 0.0, 1.0);
        assert!(
            (s.i - 6.0 / 2.22).abs() < 1e-12,
            "expected the 6 V stall current 2.7027 A, got {}",
            s.i
        );
        assert!((p.stall_torque() - 0.012135).abs() < 1e-6);
    }
}
