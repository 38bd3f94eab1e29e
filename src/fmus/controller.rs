//! The `Controller` FMU: the paper's LQR (equation (14)) and PID (equation (16)) as a sampled
//! controller, with torque outputs for the plant and voltage outputs for the DC motors.

use crate::fmi2::model::{CoSimModel, DefaultExperiment, ModelInfo, StepFailure};
use crate::fmi2::variables::{Value, VarDecl};
use crate::fmi2_variables;
use crate::models::controller::{Command, ControlLaw, ControllerState, DEFAULT_PID, Mode, PidGains, lqr_gain};
use crate::models::dc_motor::DcMotorParams;
use crate::models::pendulum::PendulumParams;
use nalgebra::{Matrix2, Matrix4, SMatrix, Vector2, Vector4};
use serde::{Deserialize, Serialize};

fmi2_variables! {
    /// Variables of the Controller FMU, in `ModelVariables` order.
    pub struct ControllerVariables {
        /// Measured angle alpha1 of link 1 from the upward vertical (connect to Pendulum.alpha1)
        alpha1: f64 = 0.0, vr = 0, Input, Continuous, unit = "rad";
        /// Measured angular velocity omega1 of link 1 (connect to Pendulum.omega1)
        omega1: f64 = 0.0, vr = 1, Input, Continuous, unit = "rad/s";
        /// Measured absolute angle alpha2 of link 2 (connect to Pendulum.alpha2)
        alpha2: f64 = 0.0, vr = 2, Input, Continuous, unit = "rad";
        /// Measured angular velocity omega2 of link 2 (connect to Pendulum.omega2)
        omega2: f64 = 0.0, vr = 3, Input, Continuous, unit = "rad/s";
        /// Reference for alpha1 (0 = upright)
        alpha1_ref: f64 = 0.0, vr = 4, Input, Continuous, unit = "rad";
        /// Reference for alpha2 (0 = upright)
        alpha2_ref: f64 = 0.0, vr = 5, Input, Continuous, unit = "rad";
        /// Torque demand M1 for joint 1, limited to +-M_max; computed from the inputs of the previous communication point (sampled, no direct feedthrough)
        M1: f64 = 0.0, vr = 10, Output, Discrete, unit = "N.m", depends = [];
        /// Torque demand M2 for joint 2, limited to +-M_max; sampled like M1
        M2: f64 = 0.0, vr = 11, Output, Discrete, unit = "N.m", depends = [];
        /// Voltage command U1 for the motor of joint 1: U = R/(n km) (M1 + n^2 B omega1) + n kb omega1, limited to +-U_max; sampled like M1
        U1: f64 = 0.0, vr = 12, Output, Discrete, unit = "V", depends = [];
        /// Voltage command U2 for the motor of joint 2, as U1; sampled like M1
        U2: f64 = 0.0, vr = 13, Output, Discrete, unit = "V", depends = [];
        /// Control law: 1 = LQR (M = -K (x - x_ref)), 2 = PID per joint, 3 = LQR + PID
        mode: i32 = 1, vr = 20, Parameter, Tunable, min = 1.0, max = 3.0;
        /// PID proportional gain of joint 1
        Kp1: f64 = DEFAULT_PID[0].kp, vr = 21, Parameter, Tunable, unit = "N.m/rad";
        /// PID integral gain of joint 1
        Ki1: f64 = DEFAULT_PID[0].ki, vr = 22, Parameter, Tunable, unit = "N.m/(rad.s)";
        /// PID derivative gain of joint 1 (acts on the filtered measured speed)
        Kd1: f64 = DEFAULT_PID[0].kd, vr = 23, Parameter, Tunable, unit = "N.m.s/rad";
        /// PID proportional gain of joint 2
        Kp2: f64 = DEFAULT_PID[1].kp, vr = 24, Parameter, Tunable, unit = "N.m/rad";
        /// PID integral gain of joint 2
        Ki2: f64 = DEFAULT_PID[1].ki, vr = 25, Parameter, Tunable, unit = "N.m/(rad.s)";
        /// PID derivative gain of joint 2 (acts on the filtered measured speed)
        Kd2: f64 = DEFAULT_PID[1].kd, vr = 26, Parameter, Tunable, unit = "N.m.s/rad";
        /// Time constant Tf of the derivative filter Kd s/(Tf s + 1); 0 = no filter
        Tf: f64 = 0.01, vr = 27, Parameter, Tunable, unit = "s", min = 0.0;
        /// Torque limit M_max of M1, M2 (anti-windup: the integrators stop growing into it)
        M_max: f64 = 20.0, vr = 28, Parameter, Tunable, unit = "N.m";
        /// True when U1, U2 drive the plant through motors: the voltage limit then also stops the integrators
        drives_motors: bool = false, vr = 29, Parameter, Fixed;
        /// Mass m1 of link 1 of the plant the LQR gain is designed for
        m1: f64 = 0.5, vr = 40, Parameter, Fixed, unit = "kg";
        /// Mass m2 of link 2 of the plant the LQR gain is designed for
        m2: f64 = 0.5, vr = 41, Parameter, Fixed, unit = "kg";
        /// Length l1 of link 1 of the plant the LQR gain is designed for
        l1: f64 = 1.0, vr = 42, Parameter, Fixed, unit = "m";
        /// Length l2 of link 2 of the plant the LQR gain is designed for
        l2: f64 = 1.0, vr = 43, Parameter, Fixed, unit = "m";
        /// Gravitational acceleration g of the plant the LQR gain is designed for
        g: f64 = 9.81, vr = 44, Parameter, Fixed, unit = "m/s2";
        /// LQR state weight Q(1,1) on alpha1 (Q is diagonal; the paper's Q = C'C gives 1, 0, 1, 0)
        Q11: f64 = 1.0, vr = 50, Parameter, Fixed, min = 0.0;
        /// LQR state weight Q(2,2) on omega1
        Q22: f64 = 0.0, vr = 51, Parameter, Fixed, min = 0.0;
        /// LQR state weight Q(3,3) on alpha2
        Q33: f64 = 1.0, vr = 52, Parameter, Fixed, min = 0.0;
        /// LQR state weight Q(4,4) on omega2
        Q44: f64 = 0.0, vr = 53, Parameter, Fixed, min = 0.0;
        /// LQR input weight R(1,1) on M1 (R is diagonal; the paper's R = I), > 0
        R11: f64 = 1.0, vr = 54, Parameter, Fixed;
        /// LQR input weight R(2,2) on M2, > 0
        R22: f64 = 1.0, vr = 55, Parameter, Fixed;
        /// Armature resistance R of the motors the voltages are computed for
        motor_R: f64 = 2.22, vr = 60, Parameter, Fixed, unit = "Ohm";
        /// Torque constant km of the motors
        motor_km: f64 = 0.00449, vr = 61, Parameter, Fixed, unit = "N.m/A";
        /// Back-EMF constant kb of the motors
        motor_kb: f64 = 0.00448, vr = 62, Parameter, Fixed, unit = "V.s/rad";
        /// Viscous friction B of the motors, at the rotor (compensated in U)
        motor_B: f64 = 9.0946, vr = 63, Parameter, Fixed, unit = "N.m.s/rad";
        /// Gear ratio n of the motors (rotor speed / joint speed)
        gear_ratio: f64 = 1.0, vr = 64, Parameter, Fixed;
        /// Supply voltage: U1, U2 are limited to +-U_max
        U_max: f64 = 6.0, vr = 65, Parameter, Fixed, unit = "V";
        /// LQR gain K(1,1), computed at initialization by solving the Riccati equation for the plant linearized upright (paper eq. (14): 14.0666)
        K11: f64 = 0.0, vr = 70, CalculatedParameter, Fixed, unit = "N.m/rad";
        /// LQR gain K(1,2) (paper: 2.8816)
        K12: f64 = 0.0, vr = 71, CalculatedParameter, Fixed, unit = "N.m.s/rad";
        /// LQR gain K(1,3) (paper: 1.1348)
        K13: f64 = 0.0, vr = 72, CalculatedParameter, Fixed, unit = "N.m/rad";
        /// LQR gain K(1,4) (paper: 1.0010)
        K14: f64 = 0.0, vr = 73, CalculatedParameter, Fixed, unit = "N.m.s/rad";
        /// LQR gain K(2,1) (paper: -3.1814)
        K21: f64 = 0.0, vr = 74, CalculatedParameter, Fixed, unit = "N.m/rad";
        /// LQR gain K(2,2) (paper: 0.1161)
        K22: f64 = 0.0, vr = 75, CalculatedParameter, Fixed, unit = "N.m.s/rad";
        /// LQR gain K(2,3) (paper: 4.8456)
        K23: f64 = 0.0, vr = 76, CalculatedParameter, Fixed, unit = "N.m/rad";
        /// LQR gain K(2,4) (paper: 0.9957)
        K24: f64 = 0.0, vr = 77, CalculatedParameter, Fixed, unit = "N.m.s/rad";
    }
}

/// The controller FMU's model: variables and the sampled controller's memory.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Controller {
    pub v: ControllerVariables,
    pub state: ControllerState,
}

impl Controller {
    fn plant(&self) -> PendulumParams {
        let v = &self.v;
        PendulumParams {
            m1: v.m1,
            m2: v.m2,
            l1: v.l1,
            l2: v.l2,
            g: v.g,
        }
    }

    fn k(&self) -> SMatrix<f64, 2, 4> {
        let v = &self.v;
        SMatrix::<f64, 2, 4>::new(v.K11, v.K12, v.K13, v.K14, v.K21, v.K22, v.K23, v.K24)
    }

    fn law(&self) -> Result<ControlLaw, String> {
        let v = &self.v;
        let law = ControlLaw {
            mode: Mode::from_code(v.mode)?,
            k: self.k(),
            pid: [
                PidGains {
                    kp: v.Kp1,
                    ki: v.Ki1,
                    kd: v.Kd1,
                },
                PidGains {
                    kp: v.Kp2,
                    ki: v.Ki2,
                    kd: v.Kd2,
                },
            ],
            tf: v.Tf,
            m_max: v.M_max,
            motor: DcMotorParams {
                r: v.motor_R,
                km: v.motor_km,
                kb: v.motor_kb,
                b: v.motor_B,
                gear_ratio: v.gear_ratio,
                u_max: v.U_max,
                ..DcMotorParams::default()
            },
            drives_motors: v.drives_motors,
        };
        law.validate()?;
        Ok(law)
    }

    fn measurement(&self) -> (Vector4<f64>, Vector2<f64>) {
        let v = &self.v;
        (
            Vector4::new(v.alpha1, v.omega1, v.alpha2, v.omega2),
            Vector2::new(v.alpha1_ref, v.alpha2_ref),
        )
    }

    fn set_outputs(&mut self, c: &Command) {
        (self.v.M1, self.v.M2, self.v.U1, self.v.U2) = (c.m[0], c.m[1], c.u[0], c.u[1]);
    }
}

impl CoSimModel for Controller {
    type Vars = ControllerVariables;
    const INFO: ModelInfo = ModelInfo {
        identifier: "Controller",
        description: "Sampled LQR / PID controller of the double inverted pendulum (Liptak et al., \
                      'The control of holonomic system', eqs. (14), (16)); torque and motor-voltage outputs",
        author: "rustfmu",
        version: env!("CARGO_PKG_VERSION"),
        default_experiment: Some(DefaultExperiment {
            start_time: 0.0,
            stop_time: 5.0,
            step_size: 1e-3,
        }),
        documentation_html: include_str!("controller.html"),
    };

    fn new() -> Self {
        Controller {
            v: ControllerVariables::default(),
            state: ControllerState::default(),
        }
    }

    fn vars(&self) -> &ControllerVariables {
        &self.v
    }

    fn vars_mut(&mut self) -> &mut ControllerVariables {
        &mut self.v
    }

    fn check(&self, decl: &VarDecl, value: Value) -> Result<(), String> {
        match (decl.name, value) {
            ("mode", Value::Integer(m)) => Mode::from_code(m).map(|_| ()),
            (
                "m1" | "m2" | "l1" | "l2" | "R11" | "R22" | "motor_R" | "gear_ratio" | "U_max" | "M_max",
                Value::Real(x),
            ) if x <= 0.0 => Err(format!("{} must be > 0, not {x}", decl.name)),
            _ => Ok(()),
        }
    }

    fn initialize(&mut self, _start_time: f64, _tolerance: Option<f64>) -> Result<(), String> {
        let v = &self.v;
        let q = Matrix4::from_diagonal(&Vector4::new(v.Q11, v.Q22, v.Q33, v.Q44));
        let r = Matrix2::from_diagonal(&Vector2::new(v.R11, v.R22));
        let k = lqr_gain(&self.plant(), &q, &r)?;
        (self.v.K11, self.v.K12, self.v.K13, self.v.K14) = (k[(0, 0)], k[(0, 1)], k[(0, 2)], k[(0, 3)]);
        (self.v.K21, self.v.K22, self.v.K23, self.v.K24) = (k[(1, 0)], k[(1, 1)], k[(1, 2)], k[(1, 3)]);
        let law = self.law()?;
        let (x, reference) = self.measurement();
        self.state = law.initial_state(&x);
        let c = law.command(&self.state, &x, &reference);
        self.set_outputs(&c);
        Ok(())
    }

    fn parameters_changed(&mut self) -> Result<(), String> {
        self.law().map(|_| ())
    }

    fn do_step(&mut self, t: f64, h: f64) -> Result<(), StepFailure> {
        let law = self.law().map_err(|message| StepFailure {
            reached_time: t,
            message,
        })?;
        let (x, reference) = self.measurement();
        let now = law.command(&self.state, &x, &reference);
        self.state = law.advance(&self.state, &x, &reference, &now, h);
        let next = law.command(&self.state, &x, &reference);
        self.set_outputs(&next);
        Ok(())
    }
}
