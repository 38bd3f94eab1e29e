//! The `Pendulum` FMU: the paper's nonlinear plant, equations (6)–(7), integrated with error
//! control inside each communication step.

use crate::fmi2::model::{CoSimModel, DefaultExperiment, ModelInfo, StepFailure};
use crate::fmi2::variables::{Value, VarDecl};
use crate::fmi2_variables;
use crate::models::pendulum::PendulumParams;
use crate::numerics::ode::{Dopri5, Tolerances};
use nalgebra::{Vector2, Vector4};
use serde::{Deserialize, Serialize};

fmi2_variables! {
    /// Variables of the Pendulum FMU, in `ModelVariables` order.
    pub struct PendulumVariables {
        /// Generalized torque M1 at joint 1 (pivot), eq. (6)
        M1: f64 = 0.0, vr = 0, Input, Continuous, unit = "N.m";
        /// Generalized torque M2 at joint 2 (between the links), eq. (7)
        M2: f64 = 0.0, vr = 1, Input, Continuous, unit = "N.m";
        /// Angle alpha1 of link 1 from the upward vertical; the start value is the initial state
        alpha1: f64 = 0.0, vr = 2, Output, Continuous, initial = Exact, unit = "rad", depends = [];
        /// Angular velocity of link 1, d(alpha1)/dt; the start value is the initial state
        omega1: f64 = 0.0, vr = 3, Output, Continuous, initial = Exact, unit = "rad/s", depends = [];
        /// Angle alpha2 of link 2 from the upward vertical (absolute, not relative to link 1); the start value is the initial state
        alpha2: f64 = 0.0, vr = 4, Output, Continuous, initial = Exact, unit = "rad", depends = [];
        /// Angular velocity of link 2, d(alpha2)/dt; the start value is the initial state
        omega2: f64 = 0.0, vr = 5, Output, Continuous, initial = Exact, unit = "rad/s", depends = [];
        /// Total energy E = Ek1 + Ek2 + Ep1 + Ep2, eqs. (2)-(5); constant when M1 = M2 = 0
        energy: f64 = 0.0, vr = 6, Output, Continuous, unit = "J", depends = [];
        /// Horizontal position of joint 2 (end of link 1), pivot at the origin
        x1: f64 = 0.0, vr = 7, Output, Continuous, unit = "m", depends = [];
        /// Height of joint 2 (end of link 1) above the pivot
        y1: f64 = 0.0, vr = 8, Output, Continuous, unit = "m", depends = [];
        /// Horizontal position of the tip of link 2
        x2: f64 = 0.0, vr = 9, Output, Continuous, unit = "m", depends = [];
        /// Height of the tip of link 2 above the pivot
        y2: f64 = 0.0, vr = 10, Output, Continuous, unit = "m", depends = [];
        /// Mass m1 of link 1 (uniform rod), > 0
        m1: f64 = 0.5, vr = 20, Parameter, Fixed, unit = "kg";
        /// Mass m2 of link 2 (uniform rod), > 0
        m2: f64 = 0.5, vr = 21, Parameter, Fixed, unit = "kg";
        /// Length l1 of link 1, > 0
        l1: f64 = 1.0, vr = 22, Parameter, Fixed, unit = "m";
        /// Length l2 of link 2, > 0
        l2: f64 = 1.0, vr = 23, Parameter, Fixed, unit = "m";
        /// Gravitational acceleration g
        g: f64 = 9.81, vr = 24, Parameter, Fixed, unit = "m/s2";
        /// Relative error tolerance of the integrator (Dormand-Prince 5(4)) inside fmi2DoStep
        rtol: f64 = 1e-10, vr = 30, Parameter, Tunable, min = 1e-14, max = 0.1;
        /// Absolute error tolerance of the integrator inside fmi2DoStep (angles in rad, rates in rad/s)
        atol: f64 = 1e-10, vr = 31, Parameter, Tunable, min = 0.0, max = 1.0;
    }
}

/// The plant FMU's model: variables, and the integrator's memory between steps.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Pendulum {
    pub v: PendulumVariables,
    pub ode: Dopri5,
    /// Relative tolerance the importer asked for in fmi2SetupExperiment, if any.
    pub importer_tolerance: Option<f64>,
}

impl Pendulum {
    pub fn params(&self) -> PendulumParams {
        PendulumParams {
            m1: self.v.m1,
            m2: self.v.m2,
            l1: self.v.l1,
            l2: self.v.l2,
            g: self.v.g,
        }
    }

    pub fn state(&self) -> Vector4<f64> {
        Vector4::new(self.v.alpha1, self.v.omega1, self.v.alpha2, self.v.omega2)
    }

    /// Tolerances in force: the parameters, tightened (never loosened) by the importer's.
    pub fn tolerances(&self) -> Tolerances {
        let rtol = self
            .importer_tolerance
            .map_or(self.v.rtol, |t| t.min(self.v.rtol).max(1e-14));
        Tolerances {
            rtol,
            atol: self.v.atol,
        }
    }

    fn set_state(&mut self, x: &Vector4<f64>) {
        let p = self.params();
        (self.v.alpha1, self.v.omega1, self.v.alpha2, self.v.omega2) = (x[0], x[1], x[2], x[3]);
        self.v.energy = p.energy(x);
        let [(x1, y1), (x2, y2)] = p.positions(x);
        (self.v.x1, self.v.y1, self.v.x2, self.v.y2) = (x1, y1, x2, y2);
    }
}

impl CoSimModel for Pendulum {
    type Vars = PendulumVariables;
    const INFO: ModelInfo = ModelInfo {
        identifier: "Pendulum",
        description: "Double inverted pendulum with actuators at both joints: the nonlinear \
                      Lagrangian model of Liptak et al., 'The control of holonomic system', eqs. (6)-(7)",
        author: "rustfmu",
        version: env!("CARGO_PKG_VERSION"),
        default_experiment: Some(DefaultExperiment {
            start_time: 0.0,
            stop_time: 2.0,
            step_size: 1e-3,
        }),
        documentation_html: include_str!("pendulum.html"),
    };

    fn new() -> Self {
        Pendulum {
            v: PendulumVariables::default(),
            ode: Dopri5::default(),
            importer_tolerance: None,
        }
    }

    fn vars(&self) -> &PendulumVariables {
        &self.v
    }

    fn vars_mut(&mut self) -> &mut PendulumVariables {
        &mut self.v
    }

    fn check(&self, decl: &VarDecl, value: Value) -> Result<(), String> {
        let Value::Real(x) = value else {
            return Ok(());
        };
        match decl.name {
            "m1" | "m2" if x <= 0.0 => Err(format!("a mass must be > 0, not {x} kg")),
            "l1" | "l2" if x <= 0.0 => Err(format!("a length must be > 0, not {x} m")),
            _ => Ok(()),
        }
    }

    fn initialize(&mut self, _start_time: f64, tolerance: Option<f64>) -> Result<(), String> {
        self.params().validate()?;
        self.importer_tolerance = tolerance;
        self.ode.restart();
        let x = self.state();
        self.set_state(&x);
        Ok(())
    }

    fn do_step(&mut self, t: f64, h: f64) -> Result<(), StepFailure> {
        let p = self.params();
        let u = Vector2::new(self.v.M1, self.v.M2);
        let mut x = self.state();
        let tol = self.tolerances();
        let result = self
            .ode
            .integrate(|_, x: &Vector4<f64>| p.derivative(x, &u), t, &mut x, t + h, tol);
        self.set_state(&x);
        result.map_err(|e| StepFailure {
            reached_time: e.time(),
            message: e.to_string(),
        })
    }
}
