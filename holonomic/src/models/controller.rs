//! The paper's controller, sampled: full-state LQR feedback (section 3, equation (14)), a PID
//! per joint (equation (16)), or both, and the conversion of torque demands to motor voltages.
//!
//! Measured: x = (α1, ω1, α2, ω2) [rad, rad/s]; references α1_ref, α2_ref [rad].
//! Control errors e_i = α_i,ref − α_i.
//!
//! ```text
//! M_LQR = −K (x − x_ref),  x_ref = (α1_ref, 0, α2_ref, 0)                     (14)
//! M_PID,i = Kp_i e_i + Ki_i ∫e_i dt − Kd_i ω_f,i                               (16)
//! ```
//!
//! The derivative acts on the measurement, not on the error (no kick when a reference jumps),
//! through the first-order filter Tf dω_f/dt = ω − ω_f, i.e. Kd s/(Tf s + 1) on −α. With the
//! references piecewise constant this is the derivative term of (16) with a filter.
//! M = M_LQR and/or M_PID, limited to ±M_max.
//!
//! Voltages for the DC motors: each motor i drives the generalized coordinate α_i through a
//! gear of ratio n (see `dc_motor`), so the demanded torque needs the steady-state voltage
//! (the current settles in L/R ≈ 55 µs, far below the sampling period)
//! ```text
//! U_i = R/(n km) · (M_i + n² B ω_i) + n kb ω_i,    limited to ±U_max.
//! ```
//!
//! Anti-windup by conditional integration: while M_i (or, driving motors, U_i) is at its limit, ∫e_i stops growing
//! in the direction that pushes further into the limit; and it is clamped so that Ki_i ∫e_i never
//! exceeds ±M_max on its own, so no input, however large or long, leaves it wound beyond what the
//! actuator can use.
//!
//! Any finite measurement gives finite, limited commands: where the sums of (14) and (16)
//! overflow `f64` (α1 = 1.7e308), they are computed again with a wider exponent ([`Wide`]) and
//! then limited.
//!
//! Two ways in time, from the same command ([`ControlLaw::command_of`], generic over dual numbers
//! so that its exact derivatives come from it too):
//! - sampled (co-simulation): the memory advances at communication points: during the step to
//!   t_k + h the integral by e_i(t_k)·h and the filter exactly (ω held), both following the
//!   actual step size h ([`ControlLaw::advance`]);
//! - continuous (model exchange): the integrals and filters are continuous states with
//!   d∫e_i/dt = e_i (0 into a limit) and Tf dω_f/dt = ω − ω_f ([`ControlLaw::rates_of`]).
//!
//! With Tf = 0 the derivative term uses ω itself (no filter).

use super::dc_motor::DcMotorParams;
use super::pendulum::PendulumParams;
use crate::numerics::lqr::lqr;
use crate::numerics::wide::Wide;
use nalgebra::{Matrix2, Matrix4, SMatrix, Vector2, Vector4};
use num_dual::DualNum;
use serde::{Deserialize, Serialize};

/// Which feedback the controller applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Mode {
    /// M = −K (x − x_ref)
    Lqr = 1,
    /// M = PID per joint
    Pid = 2,
    /// M = −K (x − x_ref) + PID per joint
    LqrPid = 3,
}

impl Mode {
    pub fn from_code(code: i32) -> Result<Mode, String> {
        match code {
            1 => Ok(Mode::Lqr),
            2 => Ok(Mode::Pid),
            3 => Ok(Mode::LqrPid),
            _ => Err(format!("mode = {code} is not one of 1 (LQR), 2 (PID), 3 (LQR+PID)")),
        }
    }
    fn lqr(self) -> bool {
        self != Mode::Pid
    }
    fn pid(self) -> bool {
        self != Mode::Lqr
    }
}

/// PID gains of one joint.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PidGains {
    /// Proportional gain [N·m/rad]
    pub kp: f64,
    /// Integral gain [N·m/(rad·s)]
    pub ki: f64,
    /// Derivative gain [N·m·s/rad]
    pub kd: f64,
}

/// Default PID gains (joint 1, joint 2). Tuned on the linearized plant (12) with the derivative
/// filter: a grid search over Kp, Ki, Kd maximizing the decay rate of the slowest eigenvalue of
/// the closed loop in both PID and LQR+PID modes, with damping ratio ≥ 0.5, then rounded.
/// Kp_i must exceed the gravity stiffness (7.3575 and 2.4525 N·m/rad) for PID alone to hold
/// the pendulum up. The test `pid_defaults_stabilize_the_linearized_plant` checks them.
pub const DEFAULT_PID: [PidGains; 2] = [
    PidGains {
        kp: 30.0,
        ki: 15.0,
        kd: 5.0,
    },
    PidGains {
        kp: 10.0,
        ki: 5.0,
        kd: 5.0,
    },
];

/// Everything the control law needs, fixed during a run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlLaw {
    pub mode: Mode,
    /// LQR gain [N·m/rad, N·m·s/rad, N·m/rad, N·m·s/rad] per row
    pub k: SMatrix<f64, 2, 4>,
    pub pid: [PidGains; 2],
    /// Derivative filter time constant Tf [s]; 0 uses ω unfiltered
    pub tf: f64,
    /// Torque limit M_max [N·m]
    pub m_max: f64,
    /// The motors the voltages are computed for
    pub motor: DcMotorParams,
    /// Whether U1, U2 drive the plant (through motors): then the voltage limit also stops the
    /// integrators; when M1, M2 drive it directly only M_max does.
    pub drives_motors: bool,
}

/// The controller's memory between samples.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ControllerState {
    /// ∫ e_i dt [rad·s]
    pub integral: [f64; 2],
    /// Filtered joint speeds ω_f [rad/s]
    pub rate_filter: [f64; 2],
}

/// What the law reads at one instant, in any number type (f64, or dual numbers for directional
/// derivatives): its memory, the measurement x = (α1, ω1, α2, ω2) and the references for α1, α2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Knowns<D> {
    /// ∫ e_i dt [rad·s]
    pub integral: [D; 2],
    /// Filtered joint speeds ω_f [rad/s]
    pub rate_filter: [D; 2],
    /// The measured state (α1, ω1, α2, ω2)
    pub x: [D; 4],
    /// The references for α1, α2
    pub reference: [D; 2],
}

/// One sample of the outputs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Command {
    /// Torque demands M1, M2 [N·m], limited to ±M_max
    pub m: Vector2<f64>,
    /// Voltage commands U1, U2 [V], limited to ±U_max
    pub u: Vector2<f64>,
    /// Whether joint i's command is at a limit that stops its integrator
    pub saturated: [bool; 2],
}

/// The paper's LQR design for a plant: Q, R as given, linearized at the upright rest position
/// from the same model code the Pendulum FMU integrates.
pub fn lqr_gain(plant: &PendulumParams, q: &Matrix4<f64>, r: &Matrix2<f64>) -> Result<SMatrix<f64, 2, 4>, String> {
    plant.validate()?;
    let (a, b) = plant.linearize(&Vector4::zeros(), &Vector2::zeros());
    lqr(&a, &b, q, r).map_err(|e| format!("LQR design failed: {e}"))
}

const ANGLE: [usize; 2] = [0, 2];
const RATE: [usize; 2] = [1, 3];

impl ControlLaw {
    pub fn validate(&self) -> Result<(), String> {
        self.motor.validate()?;
        if !(self.tf.is_finite() && self.tf >= 0.0) {
            return Err(format!("Tf = {} must be a finite number >= 0", self.tf));
        }
        if !(self.m_max.is_finite() && self.m_max > 0.0) {
            return Err(format!("M_max = {} must be a finite number > 0", self.m_max));
        }
        Ok(())
    }

    /// The filter state that makes the derivative term start without a transient.
    pub fn initial_state(&self, x: &Vector4<f64>) -> ControllerState {
        ControllerState {
            integral: [0.0; 2],
            rate_filter: [x[1], x[3]],
        }
    }

    /// The outputs for measurement `x`, references `reference` and memory `s`.
    pub fn command(&self, s: &ControllerState, x: &Vector4<f64>, reference: &Vector2<f64>) -> Command {
        let (m, u, saturated) = self.command_of(Knowns {
            integral: s.integral,
            rate_filter: s.rate_filter,
            x: [x[0], x[1], x[2], x[3]],
            reference: [reference[0], reference[1]],
        });
        Command {
            m: Vector2::from(m),
            u: Vector2::from(u),
            saturated,
        }
    }

    /// [`command`](Self::command) in any number type: (M, U, whether joint i is at a limit that
    /// stops its integrator). On `f64` the operations are those of eqs. (14), (16) in the order
    /// written; the limits are taken on the value (a limited command does not depend on the
    /// inputs), and where a sum overflows it is recomputed wide (value only).
    pub fn command_of<D: DualNum<Primitive = f64> + Copy>(&self, k: Knowns<D>) -> ([D; 2], [D; 2], [bool; 2]) {
        let (demand, limited, volts) = self.demands_of(k);
        let mut saturated = [false; 2];
        let mut u = [D::from(0.0); 2];
        for i in 0..2 {
            u[i] = limit(volts[i], self.motor.u_max);
            // At a limit from its value on (|M| >= M_max), as the event indicators'
            // domains have it (limit_margins_of <= 0): at an event located on the limit the
            // law is already the saturated one.
            saturated[i] =
                demand[i].re().abs() >= self.m_max || (self.drives_motors && volts[i].re().abs() >= self.motor.u_max);
        }
        (limited, u, saturated)
    }

    /// How far each command is from its limit: (M_max − |M_i|, U_max − |U_i|) with M_i the
    /// demand before its limit and U_i the voltage before its limit. Positive inside the limits,
    /// ≤ 0 at or beyond one; where one changes sign the law switches (the command is held, the
    /// integrator stops): the event indicators of model exchange.
    pub fn limit_margins_of<D: DualNum<Primitive = f64> + Copy>(&self, k: Knowns<D>) -> ([D; 2], [D; 2]) {
        let (demand, _, volts) = self.demands_of(k);
        // A demand beyond f64 (a measurement near ±f64::MAX) is as far beyond its limit as f64
        // goes: the margin stays finite, as every value that leaves the FMU must.
        let margin = |v: D, bound: f64| {
            let m = if v.re() < 0.0 { v + bound } else { -v + bound };
            if m.re().is_finite() { m } else { D::from(-f64::MAX) }
        };
        (
            [margin(demand[0], self.m_max), margin(demand[1], self.m_max)],
            [margin(volts[0], self.motor.u_max), margin(volts[1], self.motor.u_max)],
        )
    }

    /// The demands M_i before their limit (eqs. (14), (16)), the limited torques, and the
    /// voltages for those before the voltage limit.
    fn demands_of<D: DualNum<Primitive = f64> + Copy>(&self, k: Knowns<D>) -> ([D; 2], [D; 2], [D; 2]) {
        let Knowns {
            integral,
            rate_filter,
            x,
            reference,
        } = k;
        let zero = D::from(0.0);
        let mut m = [zero; 2];
        if self.mode.lqr() {
            let x_ref = [reference[0], zero, reference[1], zero];
            for (i, mi) in m.iter_mut().enumerate() {
                // −K (x − x_ref), row i, summed over the columns in order (as nalgebra does).
                let mut sum = (x[0] - x_ref[0]) * self.k[(i, 0)];
                for j in 1..4 {
                    sum += (x[j] - x_ref[j]) * self.k[(i, j)];
                }
                *mi -= sum;
            }
        }
        if self.mode.pid() {
            for i in 0..2 {
                let e = reference[i] - x[ANGLE[i]];
                let g = self.pid[i];
                let rate = if self.tf > 0.0 { rate_filter[i] } else { x[RATE[i]] };
                m[i] += e * g.kp + integral[i] * g.ki - rate * g.kd;
            }
        }
        let re = |v: &[D]| v.iter().map(|d| d.re()).collect::<Vec<f64>>();
        let mut limited = [zero; 2];
        let mut volts = [zero; 2];
        let p = &self.motor;
        let n = p.gear_ratio;
        for i in 0..2 {
            if !m[i].re().is_finite() {
                let state = ControllerState {
                    integral: [integral[0].re(), integral[1].re()],
                    rate_filter: [rate_filter[0].re(), rate_filter[1].re()],
                };
                let xs = re(&x);
                let x = Vector4::new(xs[0], xs[1], xs[2], xs[3]);
                let r = Vector2::new(reference[0].re(), reference[1].re());
                m[i] = D::from(self.wide_demand(i, &state, &x, &r).to_f64());
            }
            limited[i] = limit(m[i], self.m_max);
            let omega = x[RATE[i]];
            volts[i] = (limited[i] + omega * (n * n * p.b)) * (p.r / (n * p.km)) + omega * (n * p.kb);
            if !volts[i].re().is_finite() {
                volts[i] = D::from(self.wide_voltage(limited[i].re(), omega.re()).to_f64());
            }
        }
        (m, limited, volts)
    }

    /// The continuous-time memory's rates: (d∫e_i/dt, dω_f,i/dt). Conditional integration: no
    /// growth into a limit, nor beyond the bound that keeps Ki ∫e within ±M_max.
    pub fn rates_of<D: DualNum<Primitive = f64> + Copy>(&self, k: Knowns<D>) -> ([D; 2], [D; 2]) {
        let (m, _, saturated) = self.command_of(k);
        let zero = D::from(0.0);
        let (mut d_integral, mut d_filter) = ([zero; 2], [zero; 2]);
        for i in 0..2 {
            let e = k.reference[i] - k.x[ANGLE[i]];
            let into_limit = saturated[i] && e.re() * m[i].re() > 0.0;
            let bound = (self.m_max / self.pid[i].ki.abs()).min(f64::MAX);
            let at_bound =
                (k.integral[i].re() >= bound && e.re() > 0.0) || (k.integral[i].re() <= -bound && e.re() < 0.0);
            // Rates beyond f64 (a measurement near ±f64::MAX) are limited to ±f64::MAX: the
            // memory is bounded anyway, and a rate must not be infinite.
            if self.mode.pid() && !into_limit && !at_bound {
                d_integral[i] = within_f64(e);
            }
            if self.tf > 0.0 {
                d_filter[i] = within_f64((k.x[RATE[i]] - k.rate_filter[i]) / self.tf);
            }
        }
        (d_integral, d_filter)
    }

    /// The demand of joint i, before the limit, as `command` computes it, where that overflows.
    fn wide_demand(&self, i: usize, s: &ControllerState, x: &Vector4<f64>, reference: &Vector2<f64>) -> Wide {
        let w = Wide::from;
        let mut m = Wide::ZERO;
        if self.mode.lqr() {
            let x_ref = [reference[0], 0.0, reference[1], 0.0];
            for j in 0..4 {
                m = m - w(self.k[(i, j)]) * (w(x[j]) - w(x_ref[j]));
            }
        }
        if self.mode.pid() {
            let e = w(reference[i]) - w(x[ANGLE[i]]);
            let g = self.pid[i];
            m = m + w(g.kp) * e + w(g.ki) * w(s.integral[i]) - w(g.kd) * w(s.rate_filter[i]);
        }
        m
    }

    /// The voltage for torque `limited` at joint speed `omega`, as `command` computes it,
    /// where that overflows.
    fn wide_voltage(&self, limited: f64, omega: f64) -> Wide {
        let w = Wide::from;
        let p = &self.motor;
        let n = w(p.gear_ratio);
        w(p.r) / (n * w(p.km)) * (w(limited) + n * n * w(p.b) * w(omega)) + n * w(p.kb) * w(omega)
    }

    /// One sample of the law as a digital controller that samples every `h` (s): except at the
    /// first sample, the memory first advances over `h` from `x` ([`advance`](Self::advance),
    /// with the command of the memory before), then the command for `x` from the advanced
    /// memory. The SampledController FMU ticks it with the measurement of its previous tick; the
    /// networked pendulum's Controller ECU with the last measurement the bus brought.
    pub fn tick(
        &self,
        memory: &mut ControllerState,
        x: &Vector4<f64>,
        reference: &Vector2<f64>,
        h: f64,
        first: bool,
    ) -> Command {
        if !first {
            let before = self.command(memory, x, reference);
            *memory = self.advance(memory, x, reference, &before, h);
        }
        self.command(memory, x, reference)
    }

    /// The memory after a step of `h` [s] from a sample with measurement `x` and command `c`.
    pub fn advance(
        &self,
        s: &ControllerState,
        x: &Vector4<f64>,
        reference: &Vector2<f64>,
        c: &Command,
        h: f64,
    ) -> ControllerState {
        let mut next = *s;
        for i in 0..2 {
            let e = reference[i] - x[ANGLE[i]];
            // Conditional integration: no growth into a limit. The sign of the command tells
            // which limit; integrating e > 0 raises the command when Ki > 0.
            let into_limit = c.saturated[i] && e * c.m[i] > 0.0;
            if self.mode.pid() && !into_limit {
                // Ki ∫e alone never beyond ±M_max (and never infinite, even with Ki = 0).
                let bound = (self.m_max / self.pid[i].ki.abs()).min(f64::MAX);
                next.integral[i] = (next.integral[i] + e * h).clamp(-bound, bound);
            }
            let omega = x[RATE[i]];
            // Exactly ω + (ω_f − ω) e^(−h/Tf), as a weighted mean that cannot overflow. exp and
            // expm1 from `libm`: the same bits on every platform and thread (Cargo.toml says why).
            next.rate_filter[i] = if self.tf > 0.0 {
                let decay = -h / self.tf;
                s.rate_filter[i] * libm::exp(decay) - omega * libm::expm1(decay)
            } else {
                omega
            };
        }
        next
    }
}

/// `v`, or ±f64::MAX (without derivative) where its value overflowed.
fn within_f64<D: DualNum<Primitive = f64> + Copy>(v: D) -> D {
    let re = v.re();
    if re.is_finite() {
        v
    } else if re > 0.0 {
        D::from(f64::MAX)
    } else if re < 0.0 {
        D::from(-f64::MAX)
    } else {
        D::from(0.0)
    }
}

/// `v` limited to ±`bound`, taken on the value: a limited command is the bound, with no
/// derivative.
fn limit<D: DualNum<Primitive = f64> + Copy>(v: D, bound: f64) -> D {
    if v.re() > bound {
        D::from(bound)
    } else if v.re() < -bound {
        D::from(-bound)
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SMatrix;

    fn law(mode: Mode) -> ControlLaw {
        law_for(&PendulumParams::default(), mode)
    }

    /// The paper's weights Q = CᵀC, R = I, the gain designed for `plant`.
    fn law_for(plant: &PendulumParams, mode: Mode) -> ControlLaw {
        let c = PendulumParams::output_matrix();
        ControlLaw {
            mode,
            k: lqr_gain(plant, &(c.transpose() * c), &Matrix2::identity()).unwrap(),
            pid: DEFAULT_PID,
            tf: 0.01,
            m_max: 1e3,
            motor: DcMotorParams::default(),
            drives_motors: false,
        }
    }

    /// The linearized loop: plant (12) + controller with the integrals and filters as states,
    /// z = (x, ∫e1, ∫e2, ω_f1, ω_f2), continuous time.
    fn closed_loop(l: &ControlLaw) -> SMatrix<f64, 8, 8> {
        closed_loop_of(&PendulumParams::default(), l)
    }

    /// As [`closed_loop`], around `plant`.
    fn closed_loop_of(plant: &PendulumParams, l: &ControlLaw) -> SMatrix<f64, 8, 8> {
        let (a, b) = plant.linearize(&Vector4::zeros(), &Vector2::zeros());
        let mut f = SMatrix::<f64, 8, 8>::zeros();
        f.fixed_view_mut::<4, 4>(0, 0).copy_from(&a);
        let mut gain = SMatrix::<f64, 2, 8>::zeros();
        if l.mode.lqr() {
            gain.fixed_view_mut::<2, 4>(0, 0).copy_from(&(-l.k));
        }
        for i in 0..2 {
            if l.mode.pid() {
                gain[(i, ANGLE[i])] -= l.pid[i].kp;
                gain[(i, 4 + i)] += l.pid[i].ki;
                gain[(i, 6 + i)] -= l.pid[i].kd;
            }
            f[(4 + i, ANGLE[i])] = -1.0;
            f[(6 + i, RATE[i])] = 1.0 / l.tf;
            f[(6 + i, 6 + i)] = -1.0 / l.tf;
        }
        let bg = b * gain;
        let mut top = f.fixed_view_mut::<4, 8>(0, 0);
        top += bg;
        f
    }

    #[test]
    fn pid_defaults_stabilize_the_linearized_plant() {
        for mode in [Mode::Pid, Mode::LqrPid] {
            let eig = closed_loop(&law(mode)).complex_eigenvalues();
            let slowest = eig.iter().map(|l| l.re).fold(f64::NEG_INFINITY, f64::max);
            let damping = eig.iter().map(|l| -l.re / l.norm()).fold(f64::INFINITY, f64::min);
            assert!(
                slowest < -0.45,
                "{mode:?}: slowest eigenvalue should decay faster than -0.45/s: {eig}"
            );
            assert!(damping > 0.5, "{mode:?}: damping ratio should exceed 0.5: {eig}");
        }
    }

    #[test]
    fn the_gain_designed_for_the_plant_with_rotors_stabilizes_it() {
        // The full loop's plant: n² J = 200² · 2.18e-5 = 0.872 kg·m² at each joint. The gain
        // designed for it (the Controller with J1 = J2 = 0.872) stabilizes it, alone and with
        // the default PID; the slowest eigenvalues are printed for docs/composition.md.
        let heavy = PendulumParams {
            j1: 0.872,
            j2: 0.872,
            ..PendulumParams::default()
        };
        for mode in [Mode::Lqr, Mode::LqrPid] {
            for (name, designed_for) in [("rotors", heavy), ("paper", PendulumParams::default())] {
                let l = law_for(&designed_for, mode);
                let eig = closed_loop_of(&heavy, &l).complex_eigenvalues();
                // In LQR mode the PID states are decoupled integrators (eigenvalue 0): left out.
                let eig: Vec<_> = eig.iter().filter(|l| l.norm() > 1e-9).map(|l| (l.re, l.im)).collect();
                let slowest = eig.iter().map(|l| l.0).fold(f64::NEG_INFINITY, f64::max);
                println!(
                    "{mode:?}, K for the {name} plant, around the plant with rotors: slowest Re = {slowest:.4}, {eig:.3?}"
                );
                if name == "rotors" {
                    assert!(
                        slowest < -0.1,
                        "{mode:?}: the loop around the plant with rotors should be stable: {eig:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn lqr_command_is_minus_k_x() {
        let l = law(Mode::Lqr);
        let x = Vector4::new(0.1, 0.2, -0.05, 0.3);
        let c = l.command(&l.initial_state(&x), &x, &Vector2::zeros());
        let want = -l.k * x;
        assert!((c.m - want).norm() < 1e-12, "expected M = {want}, got {}", c.m);
    }

    #[test]
    fn voltage_is_the_steady_state_inverse_of_the_motor() {
        let mut l = law(Mode::Lqr);
        l.motor = DcMotorParams {
            gear_ratio: 200.0,
            b: 1e-6,
            ..DcMotorParams::default()
        };
        let x = Vector4::new(0.01, 0.2, -0.01, -0.1);
        let c = l.command(&l.initial_state(&x), &x, &Vector2::zeros());
        for i in 0..2 {
            let omega_m = 200.0 * x[RATE[i]];
            let current = (c.u[i] - l.motor.kb * omega_m) / l.motor.r;
            let torque = 200.0 * (l.motor.km * current - l.motor.b * omega_m);
            assert!(
                (torque - c.m[i]).abs() < 1e-12,
                "joint {i}: motor would give {torque} N.m for demand {}",
                c.m[i]
            );
        }
    }

    #[test]
    fn integral_stops_growing_into_the_limit() {
        let mut l = law(Mode::Pid);
        l.m_max = 1.0;
        let x = Vector4::new(-0.5, 0.0, 0.0, 0.0); // e1 = +0.5 rad: M1 = 15 N.m, limited to 1
        let mut s = l.initial_state(&x);
        for _ in 0..100 {
            let c = l.command(&s, &x, &Vector2::zeros());
            assert!(c.saturated[0], "M1 should be at its limit");
            s = l.advance(&s, &x, &Vector2::zeros(), &c, 0.01);
        }
        assert_eq!(
            s.integral[0], 0.0,
            "the integral of joint 1 wound up to {}",
            s.integral[0]
        );
    }

    #[test]
    fn integral_stays_bounded_while_the_lqr_part_holds_the_limit() {
        // The LQR part (ω1 = -1e12) holds M1 at +M_max while e1 = -1e10 rad pulls away from it:
        // conditional integration lets the integral grow, the clamp keeps Ki ∫e1 within M_max.
        let mut l = law(Mode::LqrPid);
        l.m_max = 20.0;
        let x = Vector4::new(1e10, -1e12, 0.0, 0.0);
        let mut s = l.initial_state(&x);
        for _ in 0..1000 {
            let c = l.command(&s, &x, &Vector2::zeros());
            s = l.advance(&s, &x, &Vector2::zeros(), &c, 1e-3);
        }
        let contribution = l.pid[0].ki * s.integral[0];
        assert!(
            contribution.abs() <= l.m_max,
            "Ki ∫e1 = {contribution} N.m after 1 s, beyond M_max = {}",
            l.m_max
        );
    }

    #[test]
    fn the_rate_filter_stays_finite_between_opposite_extremes() {
        let l = law(Mode::Pid);
        let s = ControllerState {
            integral: [0.0; 2],
            rate_filter: [f64::MAX, -f64::MAX],
        };
        let x = Vector4::new(0.0, -f64::MAX, 0.0, f64::MAX);
        let c = l.command(&s, &x, &Vector2::zeros());
        let next = l.advance(&s, &x, &Vector2::zeros(), &c, 1e-3);
        assert!(
            next.rate_filter.iter().all(|w| w.is_finite()),
            "filter {:?} from {:?} towards ω = (-MAX, MAX)",
            next.rate_filter,
            s.rate_filter
        );
    }

    #[test]
    fn integral_and_filter_follow_the_actual_step() {
        let l = law(Mode::LqrPid);
        let x = Vector4::new(0.01, 1.0, 0.0, 0.0);
        let s0 = ControllerState::default();
        let c = l.command(&s0, &x, &Vector2::zeros());
        let one = l.advance(&s0, &x, &Vector2::zeros(), &c, 0.004);
        let mut two = l.advance(&s0, &x, &Vector2::zeros(), &c, 0.001);
        two = l.advance(&two, &x, &Vector2::zeros(), &c, 0.003);
        for i in 0..2 {
            assert!(
                (one.integral[i] - two.integral[i]).abs() < 1e-15,
                "integral: {one:?} vs {two:?}"
            );
            assert!(
                (one.rate_filter[i] - two.rate_filter[i]).abs() < 1e-15,
                "filter: {one:?} vs {two:?}"
            );
        }
        assert!((one.integral[0] + 0.01 * 0.004).abs() < 1e-15);
        assert!((one.rate_filter[0] - (1.0 - (-0.4f64).exp())).abs() < 1e-12);
    }
}
