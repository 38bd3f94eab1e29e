//! The double inverted pendulum with actuators at both joints, as the paper models it:
//! Lipták, Kelemen, Gmitterko, Virgala, Hroncová, "The control of holonomic system".
//!
//! State x = (α1, α̇1, α2, α̇2): α1 and α2 are ABSOLUTE angles of links 1 and 2 from the upward
//! vertical [rad] (the coupling terms use cos(α1 − α2)); inputs u = (M1, M2) are the generalized
//! torques [N·m] of equations (6) and (7). The right-hand side is generic over dual numbers, so
//! the Jacobian of equation (12) comes from this same code, exactly, not from finite differences.

use nalgebra::{Matrix2, SMatrix, SVector, Vector2, Vector4};
use num_dual::{DualNum, DualSVec64, jacobian};
use serde::{Deserialize, Serialize};

/// Physical parameters. Paper defaults (section 3): m1 = m2 = 0.5 kg, l1 = l2 = 1 m; no extra
/// inertia at the joints (J1 = J2 = 0), which leaves every result of equations (6)–(7) unchanged.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PendulumParams {
    /// Mass of link 1 [kg]
    pub m1: f64,
    /// Mass of link 2 [kg]
    pub m2: f64,
    /// Length of link 1 [m]
    pub l1: f64,
    /// Length of link 2 [m]
    pub l2: f64,
    /// Gravitational acceleration [m/s²]
    pub g: f64,
    /// Extra inertia J1 at joint 1 [kg·m²], added to the (1,1) entry of the mass matrix: a rotor
    /// geared to α1 (n² J of a motor with rotor inertia J and gear ratio n). Not in the paper: 0.
    #[serde(default)]
    pub j1: f64,
    /// Extra inertia J2 at joint 2 [kg·m²], added to the (2,2) entry: a rotor geared to the
    /// absolute angle α2 (a drive whose stator is grounded). Not in the paper: 0.
    #[serde(default)]
    pub j2: f64,
}

impl Default for PendulumParams {
    fn default() -> Self {
        PendulumParams {
            m1: 0.5,
            m2: 0.5,
            l1: 1.0,
            l2: 1.0,
            g: 9.81,
            j1: 0.0,
            j2: 0.0,
        }
    }
}

/// Indices into the state vector.
pub const ALPHA1: usize = 0;
pub const OMEGA1: usize = 1;
pub const ALPHA2: usize = 2;
pub const OMEGA2: usize = 3;

impl PendulumParams {
    /// Refuses a parameter set the equations cannot use, naming the parameter.
    pub fn validate(&self) -> Result<(), String> {
        for (name, v) in [("m1", self.m1), ("m2", self.m2), ("l1", self.l1), ("l2", self.l2)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{name} = {v} must be a finite number > 0"));
            }
        }
        if !self.g.is_finite() {
            return Err(format!("g = {} must be finite", self.g));
        }
        for (name, v) in [("J1", self.j1), ("J2", self.j2)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("{name} = {v} must be a finite number >= 0"));
            }
        }
        Ok(())
    }

    /// Mass matrix M(α) of equations (6)–(7), with the joints' extra inertias J1, J2 on the
    /// diagonal (the paper's matrix when J1 = J2 = 0):
    /// [ (m1+m2) l1²/3 + J1       m2 l1 l2 cos(α1−α2)/3 ]
    /// [ m2 l1 l2 cos(α1−α2)/3    m2 l2²/3 + J2         ]
    /// J is added last, so at J = 0 every entry is the paper's to the bit.
    pub fn mass_matrix<D: DualNum<Primitive = f64> + Copy>(&self, alpha1: D, alpha2: D) -> [[D; 2]; 2] {
        self.mass_matrix_at((alpha1 - alpha2).cos())
    }

    /// [`mass_matrix`](Self::mass_matrix) from c = cos(α1 − α2), which `rhs` has already.
    #[inline]
    fn mass_matrix_at<D: DualNum<Primitive = f64> + Copy>(&self, c: D) -> [[D; 2]; 2] {
        let m12 = c * (self.m2 * self.l1 * self.l2 / 3.0);
        [
            [D::from((self.m1 + self.m2) * self.l1 * self.l1 / 3.0 + self.j1), m12],
            [m12, D::from(self.m2 * self.l2 * self.l2 / 3.0 + self.j2)],
        ]
    }

    /// ẋ = f(x, u): equations (6) and (7) solved for the angular accelerations.
    ///
    /// With s = sin(α1 − α2), the velocity terms of (6) reduce to +m2 l1 l2 α̇2² s / 3 and those
    /// of (7) to −m2 l1 l2 α̇1² s / 3; gravity gives −(m1 g l1/2 + m2 g l1) sin α1 in (6) and
    /// −m2 g l2/2 sin α2 in (7). Moving them to the right: M(α) α̈ = r.
    pub fn rhs<D: DualNum<Primitive = f64> + Copy>(&self, x: [D; 4], u: [D; 2]) -> [D; 4] {
        let [alpha1, omega1, alpha2, omega2] = x;
        let [torque1, torque2] = u;
        // sin and cos of the one angle difference of (6)-(7) side by side, so that they are one
        // sincos call wherever the compiler inlines this (bench/callgrind.sh).
        let (s, c) = (alpha1 - alpha2).sin_cos();
        let k = self.m2 * self.l1 * self.l2 / 3.0;
        let gravity1 = alpha1.sin() * (self.m1 * self.g * self.l1 / 2.0 + self.m2 * self.g * self.l1);
        let gravity2 = alpha2.sin() * (self.m2 * self.g * self.l2 / 2.0);
        let r1 = torque1 - omega2 * omega2 * s * k + gravity1; // eq. (6)
        let r2 = torque2 + omega1 * omega1 * s * k + gravity2; // eq. (7)
        let [[m11, m12], [m21, m22]] = self.mass_matrix_at(c);
        // 2×2 solve by Cramer's rule: det M = m2 l1² l2² (m1 + m2 sin²(α1−α2)) / 9
        // + J1 m2 l2²/3 + J2 (m1 + m2) l1²/3 + J1 J2 > 0 always (masses and lengths > 0, J ≥ 0).
        let det = m11 * m22 - m12 * m21;
        let acc1 = (r1 * m22 - r2 * m12) / det;
        let acc2 = (r2 * m11 - r1 * m21) / det;
        [omega1, acc1, omega2, acc2]
    }

    /// `rhs` on nalgebra vectors, for the integrator.
    #[inline]
    pub fn derivative(&self, x: &Vector4<f64>, u: &Vector2<f64>) -> Vector4<f64> {
        Vector4::from(self.rhs([x[0], x[1], x[2], x[3]], [u[0], u[1]]))
    }

    /// Total energy, equations (2)–(5) [J], with the kinetic energy of the joints' extra
    /// inertias: E = Ek1 + Ek2 + Ep1 + Ep2 + J1 α̇1²/2 + J2 α̇2²/2. Conserved when M1 = M2 = 0.
    pub fn energy(&self, x: &Vector4<f64>) -> f64 {
        self.energy_of([x[ALPHA1], x[OMEGA1], x[ALPHA2], x[OMEGA2]])
    }

    /// [`energy`](Self::energy), generic over dual numbers. Products are formed in the order
    /// of the formulas (parameters first), so that on `f64` the result is the same to the bit;
    /// the rotors' term is added last and is +0 when J1 = J2 = 0, so the paper's E is unchanged.
    pub fn energy_of<D: DualNum<Primitive = f64> + Copy>(&self, x: [D; 4]) -> D {
        let [a1, w1, a2, w2] = x;
        let (m1, m2, l1, l2, g) = (self.m1, self.m2, self.l1, self.l2, self.g);
        let ek1 = w1 * (m1 * l1 * l1) * w1 / 6.0; // (2)
        let ek2 = w1 * (m2 * l1 * l1) * w1 / 6.0
            + w2 * (m2 * l2 * l2) * w2 / 6.0
            + w1 * (m2 * l1 * l2) * w2 * (a1 - a2).cos() / 3.0; // (3)
        let ep1 = a1.cos() * (m1 * g * l1 / 2.0); // (4)
        let ep2 = (a1.cos() * l1 + a2.cos() * (l2 / 2.0)) * (m2 * g); // (5)
        let ek_rotors = w1 * self.j1 * w1 / 2.0 + w2 * self.j2 * w2 / 2.0; // J1 α̇1²/2 + J2 α̇2²/2
        ek1 + ek2 + ep1 + ep2 + ek_rotors
    }

    /// Joint 2 (tip of link 1) and tip of link 2, (x, y) [m], pivot at the origin, y up.
    pub fn positions(&self, x: &Vector4<f64>) -> [(f64, f64); 2] {
        self.positions_of([x[ALPHA1], x[OMEGA1], x[ALPHA2], x[OMEGA2]])
    }

    /// [`positions`](Self::positions), generic over dual numbers.
    pub fn positions_of<D: DualNum<Primitive = f64> + Copy>(&self, x: [D; 4]) -> [(D, D); 2] {
        let joint = (x[ALPHA1].sin() * self.l1, x[ALPHA1].cos() * self.l1);
        let tip = (joint.0 + x[ALPHA2].sin() * self.l2, joint.1 + x[ALPHA2].cos() * self.l2);
        [joint, tip]
    }

    /// Exact Jacobians A = ∂f/∂x and B = ∂f/∂u at (x0, u0), by forward-mode dual numbers.
    /// At the upright rest position with zero torques this is equation (12).
    pub fn linearize(&self, x0: &Vector4<f64>, u0: &Vector2<f64>) -> (SMatrix<f64, 4, 4>, SMatrix<f64, 4, 2>) {
        let z = SVector::<f64, 6>::new(x0[0], x0[1], x0[2], x0[3], u0[0], u0[1]);
        let (_, j) = jacobian(
            |z: SVector<DualSVec64<6>, 6>| {
                let f = self.rhs([z[0], z[1], z[2], z[3]], [z[4], z[5]]);
                SVector::from(f)
            },
            &z,
        );
        (
            j.fixed_view::<4, 4>(0, 0).into_owned(),
            j.fixed_view::<4, 2>(0, 4).into_owned(),
        )
    }

    /// Output matrix of equation (12): the two angles are measured.
    pub fn output_matrix() -> SMatrix<f64, 2, 4> {
        SMatrix::<f64, 2, 4>::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0)
    }

    /// Mass matrix at rest, for documentation and tests.
    pub fn mass_matrix_upright(&self) -> Matrix2<f64> {
        let [[a, b], [c, d]] = self.mass_matrix(0.0, 0.0);
        Matrix2::new(a, b, c, d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn energy_rate_is_zero_without_torque() {
        // dE/dt = ∇E · f(x) must vanish for the paper's Lagrangian system.
        let p = PendulumParams::default();
        let x = Vector4::new(0.7, -1.3, -2.1, 2.4);
        let f = p.derivative(&x, &Vector2::zeros());
        let h = 1e-6;
        let mut de = 0.0;
        for i in 0..4 {
            let mut xp = x;
            let mut xm = x;
            xp[i] += h;
            xm[i] -= h;
            de += (p.energy(&xp) - p.energy(&xm)) / (2.0 * h) * f[i];
        }
        assert!(de.abs() < 1e-7, "dE/dt = {de}");
    }

    /// The demo's rotor inertia at each joint: n² J with n = 200, J = 2.18e-5 kg·m².
    const ROTORS: PendulumParams = PendulumParams {
        m1: 0.5,
        m2: 0.5,
        l1: 1.0,
        l2: 1.0,
        g: 9.81,
        j1: 0.872,
        j2: 0.872,
    };

    /// dE/dt = ∇E · f(x) at x, with the exact (dual-number) gradient of `energy_of`.
    fn energy_rate(p: &PendulumParams, x: Vector4<f64>, u: Vector2<f64>) -> f64 {
        let (_, grad) = num_dual::gradient(|z: SVector<DualSVec64<4>, 4>| p.energy_of([z[0], z[1], z[2], z[3]]), &x);
        grad.dot(&p.derivative(&x, &u))
    }

    #[test]
    fn energy_with_rotor_inertia_is_conserved_without_torque() {
        // The extended mass matrix must still come from the extended kinetic energy: dE/dt = 0
        // with J1 = J2 = 0.872 kg·m², and also with only one of them, far from upright.
        for (j1, j2) in [(0.872, 0.872), (0.872, 0.0), (0.0, 0.3)] {
            let p = PendulumParams { j1, j2, ..ROTORS };
            for x in [Vector4::new(0.7, -1.3, -2.1, 2.4), Vector4::new(3.0, 0.2, 0.1, -5.0)] {
                let f = p.derivative(&x, &Vector2::zeros());
                let scale = 1.0 + f.norm() * 10.0;
                let de = energy_rate(&p, x, Vector2::zeros());
                assert!(
                    de.abs() < 1e-12 * scale,
                    "J1 = {j1}, J2 = {j2}, x = {x:?}: dE/dt = {de}, expected 0"
                );
            }
        }
    }

    #[test]
    fn with_rotor_inertia_torques_do_work_at_the_joint_speeds() {
        // dE/dt = M1 ω1 + M2 ω2: the torques are the generalized forces of α1 and α2, rotors or not.
        let p = ROTORS;
        let (x, u) = (Vector4::new(0.4, 1.1, -0.3, -0.7), Vector2::new(2.0, -1.5));
        let de = energy_rate(&p, x, u);
        let power = u[0] * x[OMEGA1] + u[1] * x[OMEGA2];
        assert!((de - power).abs() < 1e-12, "dE/dt = {de}, expected M·ω = {power}");
    }

    #[test]
    fn rotor_inertia_adds_to_the_diagonal_of_the_mass_matrix() {
        let (paper, rotors) = (PendulumParams::default(), ROTORS);
        for (a1, a2) in [(0.0, 0.0), (0.3, -1.2)] {
            let m = paper.mass_matrix(a1, a2);
            let mj = rotors.mass_matrix(a1, a2);
            assert_eq!(mj[0][0], m[0][0] + 0.872, "(1,1) at ({a1}, {a2})");
            assert_eq!(mj[1][1], m[1][1] + 0.872, "(2,2) at ({a1}, {a2})");
            assert_eq!((mj[0][1], mj[1][0]), (m[0][1], m[1][0]), "off-diagonal at ({a1}, {a2})");
        }
    }

    #[test]
    fn zero_rotor_inertia_changes_no_bit() {
        // J = 0 is the paper's model: the right-hand side and the energy are those of the
        // formulas without J, to the bit (J is added last; 0 added changes nothing).
        let p = PendulumParams::default();
        let x = Vector4::new(0.7, -1.3, -2.1, 2.4);
        let (a1, w1, a2, w2) = (x[0], x[1], x[2], x[3]);
        let (s, c) = ((a1 - a2).sin(), (a1 - a2).cos());
        let k = 0.5 * 1.0 * 1.0 / 3.0;
        let r1 = 1.5 - w2 * w2 * s * k + a1.sin() * (0.5 * 9.81 * 1.0 / 2.0 + 0.5 * 9.81 * 1.0);
        let r2 = -0.5 + w1 * w1 * s * k + a2.sin() * (0.5 * 9.81 * 1.0 / 2.0);
        let (m11, m12, m22) = ((0.5 + 0.5) * 1.0 * 1.0 / 3.0, c * k, 0.5 * 1.0 * 1.0 / 3.0);
        let det = m11 * m22 - m12 * m12;
        let want = [w1, (r1 * m22 - r2 * m12) / det, w2, (r2 * m11 - r1 * m12) / det];
        let got = p.rhs([a1, w1, a2, w2], [1.5, -0.5]);
        assert_eq!(
            got.map(f64::to_bits),
            want.map(f64::to_bits),
            "rhs: {got:?}, expected {want:?}"
        );
        let e = w1 * (0.5 * 1.0 * 1.0) * w1 / 6.0
            + (w1 * (0.5 * 1.0 * 1.0) * w1 / 6.0
                + w2 * (0.5 * 1.0 * 1.0) * w2 / 6.0
                + w1 * (0.5 * 1.0 * 1.0) * w2 * c / 3.0)
            + a1.cos() * (0.5 * 9.81 * 1.0 / 2.0)
            + (a1.cos() * 1.0 + a2.cos() * (1.0 / 2.0)) * (0.5 * 9.81);
        assert_eq!(
            p.energy(&x).to_bits(),
            e.to_bits(),
            "energy {}, expected {e}",
            p.energy(&x)
        );
    }

    #[test]
    fn linearized_input_columns_are_the_inverse_of_the_extended_mass_matrix() {
        // Upright, B's acceleration rows are M⁻¹ with M = [I1 + J1, k; k, I2 + J2]
        // (I1 = (m1+m2) l1²/3 = 1/3, I2 = m2 l2²/3 = 1/6, k = m2 l1 l2/3 = 1/6), and A's are
        // M⁻¹ times the gravity stiffness diag(7.3575, 2.4525).
        let (i1, i2, k) = (1.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0);
        for (j1, j2) in [(0.0, 0.0), (0.872, 0.872), (0.872, 0.0), (0.0, 0.872)] {
            let p = PendulumParams { j1, j2, ..ROTORS };
            let (a, b) = p.linearize(&Vector4::zeros(), &Vector2::zeros());
            let det = (i1 + j1) * (i2 + j2) - k * k;
            let inv = Matrix2::new(i2 + j2, -k, -k, i1 + j1) / det;
            let stiffness = Matrix2::new(7.3575, 0.0, 0.0, 2.4525);
            let acc = inv * stiffness;
            for (row, r) in [(OMEGA1, 0), (OMEGA2, 1)] {
                for col in 0..2 {
                    let (got, want) = (b[(row, col)], inv[(r, col)]);
                    assert!(
                        (got - want).abs() < 1e-14,
                        "J = ({j1}, {j2}): B[{row}][{col}] = {got}, expected {want}"
                    );
                    let (got, want) = (a[(row, 2 * col)], acc[(r, col)]);
                    assert!(
                        (got - want).abs() < 1e-13,
                        "J = ({j1}, {j2}): A[{row}][{}] = {got}, expected {want}",
                        2 * col
                    );
                }
            }
        }
        // The paper's B (eq. (12)) has acceleration rows [6 -6; -6 12]. With 0.872 kg·m² at each
        // joint they are [0.8485 -0.1361; -0.1361 0.9846]: each joint 7.1 and 12.2 times harder
        // to accelerate, and the coupling down from 100 % to 16 % of the direct term.
        let (_, b) = ROTORS.linearize(&Vector4::zeros(), &Vector2::zeros());
        let rows = [b[(OMEGA1, 0)], b[(OMEGA1, 1)], b[(OMEGA2, 0)], b[(OMEGA2, 1)]];
        for (got, want) in rows.iter().zip([0.84847, -0.13615, -0.13615, 0.98462]) {
            assert!(
                (got - want).abs() < 1e-5,
                "B's acceleration rows {rows:?}, expected about {want}"
            );
        }
    }
}
