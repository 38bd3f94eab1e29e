//! The `Pendulum` FMU: the paper's nonlinear plant, equations (6)–(7). Model exchange gives the
//! importer's integrator the right-hand side; co-simulation integrates it with the runtime's
//! error-controlled Dormand-Prince 5(4) inside each communication step.
//! `binaries/<platform>/Pendulum.so`.

#![allow(non_snake_case)] // the paper's symbols: M1, M2

use holonomic::models::pendulum::PendulumParams;
use nalgebra::Vector4;
use rustfmu::prelude::*;
use rustfmu::solver::Tolerances;
use serde::{Deserialize, Serialize};

/// Double inverted pendulum with actuators at both joints: the nonlinear Lagrangian model of
/// Liptak et al., 'The control of holonomic system', eqs. (6)-(7)
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
// The joints as FMI 3.0 terminals, rotational flanges as Modelica's (angle and speed are
// signals, the torque a flow into the FMU). Joint 2's angle is link 2's absolute angle: M2 acts
// between the links, whose support is link 1 (alpha1).
#[fmu(terminal(
    name = "joint1",
    kind = "org.modelica.Modelica.Mechanics.Rotational.Interfaces.Flange_a",
    description = "The pivot: link 1's angle and speed, the torque M1 applied to it",
    member(variable = alpha1, name = "phi", kind = "signal"),
    member(variable = omega1, name = "w", kind = "signal"),
    member(variable = M1, name = "tau", kind = "inflow"),
))]
#[fmu(terminal(
    name = "joint2",
    kind = "org.modelica.Modelica.Mechanics.Rotational.Interfaces.Flange_a",
    description = "The joint between the links: link 2's absolute angle and speed, the torque M2 between the links",
    member(variable = alpha2, name = "phi", kind = "signal"),
    member(variable = omega2, name = "w", kind = "signal"),
    member(variable = M2, name = "tau", kind = "inflow"),
))]
pub struct Pendulum {
    /// Generalized torque M1 at joint 1 (pivot), eq. (6)
    #[variable(vr = 0, input, continuous, start = 0.0, unit = "N.m")]
    pub M1: f64,
    /// Generalized torque M2 at joint 2 (between the links), eq. (7)
    #[variable(vr = 1, input, continuous, start = 0.0, unit = "N.m")]
    pub M2: f64,
    /// Angle alpha1 of link 1 from the upward vertical; starts at alpha1_0
    #[variable(vr = 2, output, continuous, initial = calculated, unit = "rad", depends = [alpha1], initial_depends = [alpha1_0])]
    pub alpha1: f64,
    /// Angular velocity of link 1, d(alpha1)/dt; starts at omega1_0
    #[variable(vr = 3, output, continuous, initial = calculated, unit = "rad/s", depends = [omega1], initial_depends = [omega1_0])]
    pub omega1: f64,
    /// Angle alpha2 of link 2 from the upward vertical (absolute, not relative to link 1); starts at alpha2_0
    #[variable(vr = 4, output, continuous, initial = calculated, unit = "rad", depends = [alpha2], initial_depends = [alpha2_0])]
    pub alpha2: f64,
    /// Angular velocity of link 2, d(alpha2)/dt; starts at omega2_0
    #[variable(vr = 5, output, continuous, initial = calculated, unit = "rad/s", depends = [omega2], initial_depends = [omega2_0])]
    pub omega2: f64,
    /// Total energy E = Ek1 + Ek2 + Ep1 + Ep2, eqs. (2)-(5); constant when M1 = M2 = 0
    #[variable(vr = 6, output, continuous, unit = "J", depends = [alpha1, omega1, alpha2, omega2], initial_depends = [m1, m2, l1, l2, g, J1, J2, alpha1_0, omega1_0, alpha2_0, omega2_0])]
    pub energy: f64,
    /// Horizontal position of joint 2 (end of link 1), pivot at the origin
    #[variable(vr = 7, output, continuous, unit = "m", depends = [alpha1], initial_depends = [l1, alpha1_0])]
    pub x1: f64,
    /// Height of joint 2 (end of link 1) above the pivot
    #[variable(vr = 8, output, continuous, unit = "m", depends = [alpha1], initial_depends = [l1, alpha1_0])]
    pub y1: f64,
    /// Horizontal position of the tip of link 2
    #[variable(vr = 9, output, continuous, unit = "m", depends = [alpha1, alpha2], initial_depends = [l1, l2, alpha1_0, alpha2_0])]
    pub x2: f64,
    /// Height of the tip of link 2 above the pivot
    #[variable(vr = 10, output, continuous, unit = "m", depends = [alpha1, alpha2], initial_depends = [l1, l2, alpha1_0, alpha2_0])]
    pub y2: f64,
    /// d(alpha1)/dt = omega1
    #[variable(vr = 12, name = "der(alpha1)", local, continuous, unit = "rad/s", derivative_of = alpha1, depends = [omega1], initial_depends = [omega1_0])]
    pub der_alpha1: f64,
    /// d(omega1)/dt: the angular acceleration of link 1, eqs. (6)-(7) solved for it
    #[variable(vr = 13, name = "der(omega1)", local, continuous, unit = "rad/s2", derivative_of = omega1, depends = [M1, M2, alpha1, omega1, alpha2, omega2], initial_depends = [M1, M2, m1, m2, l1, l2, g, J1, J2, alpha1_0, omega1_0, alpha2_0, omega2_0])]
    pub der_omega1: f64,
    /// d(alpha2)/dt = omega2
    #[variable(vr = 14, name = "der(alpha2)", local, continuous, unit = "rad/s", derivative_of = alpha2, depends = [omega2], initial_depends = [omega2_0])]
    pub der_alpha2: f64,
    /// d(omega2)/dt: the angular acceleration of link 2, eqs. (6)-(7) solved for it
    #[variable(vr = 15, name = "der(omega2)", local, continuous, unit = "rad/s2", derivative_of = omega2, depends = [M1, M2, alpha1, omega1, alpha2, omega2], initial_depends = [M1, M2, m1, m2, l1, l2, g, J1, J2, alpha1_0, omega1_0, alpha2_0, omega2_0])]
    pub der_omega2: f64,
    /// Mass m1 of link 1 (uniform rod)
    #[variable(vr = 20, parameter, fixed, start = 0.5, unit = "kg", min > 0.0)]
    pub m1: f64,
    /// Mass m2 of link 2 (uniform rod)
    #[variable(vr = 21, parameter, fixed, start = 0.5, unit = "kg", min > 0.0)]
    pub m2: f64,
    /// Length l1 of link 1
    #[variable(vr = 22, parameter, fixed, start = 1.0, unit = "m", min > 0.0)]
    pub l1: f64,
    /// Length l2 of link 2
    #[variable(vr = 23, parameter, fixed, start = 1.0, unit = "m", min > 0.0)]
    pub l2: f64,
    /// Gravitational acceleration g (any finite value: 0 without gravity, < 0 pulls upwards)
    #[variable(vr = 24, parameter, fixed, start = 9.81, unit = "m/s2")]
    pub g: f64,
    /// Extra inertia J1 at joint 1, added to the (1,1) entry of the mass matrix of eqs. (6)-(7): a rotor geared to alpha1 (n^2 J of a motor with gear ratio n and rotor inertia J; 0 in the paper). The kinetic energy gains J1 omega1^2/2
    #[variable(vr = 25, parameter, fixed, start = 0.0, unit = "kg.m2", min = 0.0)]
    pub J1: f64,
    /// Extra inertia J2 at joint 2, added to the (2,2) entry of the mass matrix: a rotor geared to the absolute angle alpha2 (0 in the paper). The kinetic energy gains J2 omega2^2/2
    #[variable(vr = 26, parameter, fixed, start = 0.0, unit = "kg.m2", min = 0.0)]
    pub J2: f64,
    /// Relative error tolerance of the integrator (Dormand-Prince 5(4)) inside fmi2DoStep (co-simulation; in model exchange the importer integrates)
    #[variable(vr = 30, parameter, tunable, start = 1e-10, min = 1e-14, max = 0.1)]
    pub rtol: f64,
    /// Absolute error tolerance of the integrator inside fmi2DoStep (angles in rad, rates in rad/s); > 0: the states are exactly 0 at rest, where a purely relative error is undefined (a tiny atol gives relative control elsewhere)
    #[variable(vr = 31, parameter, tunable, start = 1e-10, min > 0.0, max = 1.0)]
    pub atol: f64,
    /// Initial value of alpha1 (at the start time): a parameter, so that importers that apply
    /// parameters only (libcosim, fmpy.ssp, Ecos) set the initial state from an SSP file
    #[variable(vr = 40, parameter, fixed, start = 0.0, unit = "rad")]
    pub alpha1_0: f64,
    /// Initial value of omega1
    #[variable(vr = 41, parameter, fixed, start = 0.0, unit = "rad/s")]
    pub omega1_0: f64,
    /// Initial value of alpha2
    #[variable(vr = 42, parameter, fixed, start = 0.0, unit = "rad")]
    pub alpha2_0: f64,
    /// Initial value of omega2
    #[variable(vr = 43, parameter, fixed, start = 0.0, unit = "rad/s")]
    pub omega2_0: f64,
}

impl Pendulum {
    pub fn params(&self) -> PendulumParams {
        PendulumParams {
            m1: self.m1,
            m2: self.m2,
            l1: self.l1,
            l2: self.l2,
            g: self.g,
            j1: self.J1,
            j2: self.J2,
        }
    }

    pub fn state(&self) -> Vector4<f64> {
        Vector4::new(self.alpha1, self.omega1, self.alpha2, self.omega2)
    }
}

impl Model for Pendulum {
    // The parameters' domains are declared (m1, m2, l1, l2 > 0; g any finite value) and the
    // runtime enforces them: nothing to check.

    /// The initial state is the parameters alpha1_0..omega2_0.
    fn initialize(&mut self, _ctx: &Context) -> Result<(), String> {
        (self.alpha1, self.omega1, self.alpha2, self.omega2) =
            (self.alpha1_0, self.omega1_0, self.alpha2_0, self.omega2_0);
        Ok(())
    }

    /// Equations (6)-(7) solved for the accelerations.
    fn derivatives<D: Real>(&self, _t: D, v: &mut PendulumContinuous<D>) {
        let [da1, dw1, da2, dw2] = self
            .params()
            .rhs([v.alpha1, v.omega1, v.alpha2, v.omega2], [v.M1, v.M2]);
        (v.der_alpha1, v.der_omega1, v.der_alpha2, v.der_omega2) = (da1, dw1, da2, dw2);
    }

    /// Energy, eqs. (2)-(5), and the positions of the joint and the tip.
    fn outputs<D: Real>(&self, _t: D, v: &mut PendulumContinuous<D>) {
        let p = self.params();
        let x = [v.alpha1, v.omega1, v.alpha2, v.omega2];
        v.energy = p.energy_of(x);
        let [(x1, y1), (x2, y2)] = p.positions_of(x);
        (v.x1, v.y1, v.x2, v.y2) = (x1, y1, x2, y2);
    }
}

impl CoSimulation for Pendulum {
    // The step: the runtime's Dormand-Prince 5(4) on `derivatives`, at these tolerances. It
    // follows the torques' derivatives an importer gives (fmi2SetRealInputDerivatives): M1, M2
    // vary linearly over the step (canInterpolateInputs="true").
    const INTERPOLATES_INPUTS: bool = true;

    /// The parameters rtol and atol, the relative one tightened (never loosened) by the
    /// importer's tolerance from fmi2SetupExperiment.
    fn tolerances(&self, ctx: &Context) -> Tolerances {
        let rtol = ctx.tolerance().map_or(self.rtol, |t| t.min(self.rtol).max(1e-14));
        Tolerances { rtol, atol: self.atol }
    }
}

rustfmu::export_fmu!(Pendulum);
