//! The `DCMotor` FMU: the paper's DC motor (equation (17)) with a gearbox and a supply-voltage
//! limit; joint speed in, joint torque out.

use crate::fmi2::model::{CoSimModel, DefaultExperiment, ModelInfo, StepFailure};
use crate::fmi2::variables::{Value, VarDecl};
use crate::fmi2_variables;
use crate::models::dc_motor::{DcMotorParams, DcMotorState};
use serde::{Deserialize, Serialize};

fmi2_variables! {
    /// Variables of the DCMotor FMU, in `ModelVariables` order.
    pub struct DcMotorVariables {
        /// Terminal voltage command U; the supply limits it to +-U_max (connect to Controller.U1 or U2)
        U: f64 = 0.0, vr = 0, Input, Continuous, unit = "V";
        /// Speed of the driven joint, the generalized velocity conjugate to the torque output (connect to Pendulum.omega1 or omega2); ignored when coupled = false
        omega: f64 = 0.0, vr = 1, Input, Continuous, unit = "rad/s";
        /// Torque on the joint, tau = n (km i - B omega_m) (connect to Pendulum.M1 or M2); 0 when coupled = false (unloaded)
        tau: f64 = 0.0, vr = 10, Output, Continuous, unit = "N.m", depends = [];
        /// Armature current i; the start value is the initial state
        i: f64 = 0.0, vr = 11, Output, Continuous, initial = Exact, unit = "A", depends = [];
        /// Rotor speed omega_m (= n omega when coupled); the start value is the initial state
        omega_m: f64 = 0.0, vr = 12, Output, Continuous, initial = Exact, unit = "rad/s", depends = [];
        /// Voltage actually applied: U limited to +-U_max
        U_applied: f64 = 0.0, vr = 13, Output, Continuous, unit = "V", depends = [];
        /// Armature inductance L, > 0
        L: f64 = 0.000121, vr = 20, Parameter, Fixed, unit = "H";
        /// Armature resistance R, > 0
        R: f64 = 2.22, vr = 21, Parameter, Fixed, unit = "Ohm";
        /// Torque constant km
        km: f64 = 0.00449, vr = 22, Parameter, Fixed, unit = "N.m/A", min = 0.0;
        /// Back-EMF constant kb
        kb: f64 = 0.00448, vr = 23, Parameter, Fixed, unit = "V.s/rad", min = 0.0;
        /// Rotor inertia J (used when coupled = false; coupled, the rotor follows the joint rigidly), > 0
        J: f64 = 2.18e-5, vr = 24, Parameter, Fixed, unit = "kg.m2";
        /// Viscous friction B at the rotor (the paper's 9.0946 is about six orders of magnitude above small DC motors)
        B: f64 = 9.0946, vr = 25, Parameter, Fixed, unit = "N.m.s/rad", min = 0.0;
        /// Gear ratio n = rotor speed / joint speed, > 0
        gear_ratio: f64 = 1.0, vr = 26, Parameter, Fixed;
        /// Supply voltage: |U| is limited to U_max, > 0
        U_max: f64 = 6.0, vr = 27, Parameter, Fixed, unit = "V";
        /// True: the rotor drives a joint through the gear (omega in, tau out); false: the motor runs unloaded and omega_m follows eq. (17)
        coupled: bool = true, vr = 28, Parameter, Fixed;
    }
}

/// The motor FMU's model.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DcMotor {
    pub v: DcMotorVariables,
}

impl DcMotor {
    pub fn params(&self) -> DcMotorParams {
        let v = &self.v;
        DcMotorParams {
            l: v.L,
            r: v.R,
            km: v.km,
            kb: v.kb,
            j: v.J,
            b: v.B,
            gear_ratio: v.gear_ratio,
            u_max: v.U_max,
        }
    }

    fn set_state(&mut self, p: &DcMotorParams, s: &DcMotorState) {
        self.v.i = s.i;
        self.v.omega_m = s.omega_m;
        self.v.tau = if self.v.coupled { p.joint_torque(s) } else { 0.0 };
        self.v.U_applied = p.applied_voltage(self.v.U);
    }
}

impl CoSimModel for DcMotor {
    type Vars = DcMotorVariables;
    const INFO: ModelInfo = ModelInfo {
        identifier: "DCMotor",
        description: "Permanent-magnet DC motor with gearbox and supply-voltage limit (Liptak et al., \
                      'The control of holonomic system', eq. (17)); joint speed in, joint torque out",
        author: "rustfmu",
        version: env!("CARGO_PKG_VERSION"),
        default_experiment: Some(DefaultExperiment {
            start_time: 0.0,
            stop_time: 0.01,
            step_size: 1e-5,
        }),
        documentation_html: include_str!("dc_motor.html"),
    };

    fn new() -> Self {
        DcMotor {
            v: DcMotorVariables::default(),
        }
    }

    fn vars(&self) -> &DcMotorVariables {
        &self.v
    }

    fn vars_mut(&mut self) -> &mut DcMotorVariables {
        &mut self.v
    }

    fn check(&self, decl: &VarDecl, value: Value) -> Result<(), String> {
        let Value::Real(x) = value else {
            return Ok(());
        };
        match decl.name {
            "L" | "R" | "J" | "gear_ratio" | "U_max" if x <= 0.0 => Err(format!("{} must be > 0, not {x}", decl.name)),
            _ => Ok(()),
        }
    }

    fn initialize(&mut self, _start_time: f64, _tolerance: Option<f64>) -> Result<(), String> {
        let p = self.params();
        p.validate()?;
        let mut s = DcMotorState {
            i: self.v.i,
            omega_m: self.v.omega_m,
        };
        if self.v.coupled {
            s.omega_m = p.gear_ratio * self.v.omega;
        }
        self.set_state(&p, &s);
        Ok(())
    }

    fn do_step(&mut self, _t: f64, h: f64) -> Result<(), StepFailure> {
        let p = self.params();
        let s = DcMotorState {
            i: self.v.i,
            omega_m: self.v.omega_m,
        };
        let next = if self.v.coupled {
            p.step_coupled(&s, self.v.U, self.v.omega, h)
        } else {
            p.step_free(&s, self.v.U, h)
        };
        self.set_state(&p, &next);
        Ok(())
    }
}
