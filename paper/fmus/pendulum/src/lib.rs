//! The `Pendulum` FMU: the paper's nonlinear plant, equations (6)–(7), integrated with error
//! control inside each communication step. `binaries/<platform>/Pendulum.so`.

#![allow(non_snake_case)] // the paper's symbols: M1, M2

use holonomic::models::pendulum::PendulumParams;
use holonomic::numerics::ode::{Dopri5, Tolerances};
use nalgebra::{Vector2, Vector4};
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// Double inverted pendulum with actuators at both joints: the nonlinear Lagrangian model of
/// Liptak et al., 'The control of holonomic system', eqs. (6)-(7)
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct Pendulum {
    /// Generalized torque M1 at joint 1 (pivot), eq. (6)
    #[variable(vr = 0, input, continuous, start = 0.0, unit = "N.m")]
    pub M1: f64,
    /// Generalized torque M2 at joint 2 (between the links), eq. (7)
    #[variable(vr = 1, input, continuous, start = 0.0, unit = "N.m")]
    pub M2: f64,
    /// Angle alpha1 of link 1 from the upward vertical; the start value is the initial state
    #[variable(vr = 2, output, continuous, initial = exact, start = 0.0, unit = "rad", depends = [])]
    pub alpha1: f64,
    /// Angular velocity of link 1, d(alpha1)/dt; the start value is the initial state
    #[variable(vr = 3, output, continuous, initial = exact, start = 0.0, unit = "rad/s", depends = [])]
    pub omega1: f64,
    /// Angle alpha2 of link 2 from the upward vertical (absolute, not relative to link 1); the start value is the initial state
    #[variable(vr = 4, output, continuous, initial = exact, start = 0.0, unit = "rad", depends = [])]
    pub alpha2: f64,
    /// Angular velocity of link 2, d(alpha2)/dt; the start value is the initial state
    #[variable(vr = 5, output, continuous, initial = exact, start = 0.0, unit = "rad/s", depends = [])]
    pub omega2: f64,
    /// Total energy E = Ek1 + Ek2 + Ep1 + Ep2, eqs. (2)-(5); constant when M1 = M2 = 0
    #[variable(vr = 6, output, continuous, unit = "J", depends = [])]
    pub energy: f64,
    /// Horizontal position of joint 2 (end of link 1), pivot at the origin
    #[variable(vr = 7, output, continuous, unit = "m", depends = [])]
    pub x1: f64,
    /// Height of joint 2 (end of link 1) above the pivot
    #[variable(vr = 8, output, continuous, unit = "m", depends = [])]
    pub y1: f64,
    /// Horizontal position of the tip of link 2
    #[variable(vr = 9, output, continuous, unit = "m", depends = [])]
    pub x2: f64,
    /// Height of the tip of link 2 above the pivot
    #[variable(vr = 10, output, continuous, unit = "m", depends = [])]
    pub y2: f64,
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
    /// Relative error tolerance of the integrator (Dormand-Prince 5(4)) inside fmi2DoStep
    #[variable(vr = 30, parameter, tunable, start = 1e-10, min = 1e-14, max = 0.1)]
    pub rtol: f64,
    /// Absolute error tolerance of the integrator inside fmi2DoStep (angles in rad, rates in rad/s); > 0: the states are exactly 0 at rest, where a purely relative error is undefined (a tiny atol gives relative control elsewhere)
    #[variable(vr = 31, parameter, tunable, start = 1e-10, min > 0.0, max = 1.0)]
    pub atol: f64,
    /// The integrator's memory between steps (step size, error history).
    pub ode: Dopri5,
    /// Relative tolerance the importer asked for in fmi2SetupExperiment, if any.
    pub importer_tolerance: Option<f64>,
}

impl Pendulum {
    pub fn params(&self) -> PendulumParams {
        PendulumParams {
            m1: self.m1,
            m2: self.m2,
            l1: self.l1,
            l2: self.l2,
            g: self.g,
        }
    }

    pub fn state(&self) -> Vector4<f64> {
        Vector4::new(self.alpha1, self.omega1, self.alpha2, self.omega2)
    }

    /// Tolerances in force: the parameters, tightened (never loosened) by the importer's.
    pub fn tolerances(&self) -> Tolerances {
        let rtol = self
            .importer_tolerance
            .map_or(self.rtol, |t| t.min(self.rtol).max(1e-14));
        Tolerances { rtol, atol: self.atol }
    }

    fn set_state(&mut self, x: &Vector4<f64>) {
        let p = self.params();
        (self.alpha1, self.omega1, self.alpha2, self.omega2) = (x[0], x[1], x[2], x[3]);
        self.energy = p.energy(x);
        let [(x1, y1), (x2, y2)] = p.positions(x);
        (self.x1, self.y1, self.x2, self.y2) = (x1, y1, x2, y2);
    }
}

impl Model for Pendulum {
    // The parameters' domains are declared (m1, m2, l1, l2 > 0; g any finite value) and the
    // runtime enforces them: nothing to check here.
    fn initialize(&mut self, ctx: &Context) -> Result<(), String> {
        self.importer_tolerance = ctx.tolerance();
        self.ode.restart();
        let x = self.state();
        self.set_state(&x);
        Ok(())
    }

    fn check_internal_state(&self) -> Result<(), String> {
        self.ode.validate()?;
        match self.importer_tolerance {
            Some(t) if !(t.is_finite() && t > 0.0) => {
                Err(format!("the importer's tolerance {t} must be finite and > 0"))
            }
            _ => Ok(()),
        }
    }
}

impl CoSimulation for Pendulum {
    fn do_step(&mut self, t: f64, h: f64, _ctx: &Context) -> Result<(), StepFailure> {
        let p = self.params();
        let u = Vector2::new(self.M1, self.M2);
        let mut x = self.state();
        let tol = self.tolerances();
        let result = self
            .ode
            .integrate(|_, x: &Vector4<f64>| p.derivative(x, &u), t, h, &mut x, tol);
        self.set_state(&x);
        result.map_err(|e| StepFailure {
            reached_time: e.time(),
            message: e.to_string(),
        })
    }
}

rustfmu::export_fmi2!(Pendulum);
