//! The `SampledController` FMU (FMI 3.0): the Controller FMU's `sampled = true` mode (the paper's
//! LQR, eq. (14), and PID, eq. (16), as a digital controller with one sample of computation
//! delay) with its sample rate declared as what it is in FMI 3.0: a periodic input clock
//! `sample` whose interval is the parameter `Ts`. Its measurement inputs and its torque and
//! voltage outputs are clocked: the importer sets the inputs and reads the outputs at the ticks
//! (Event Mode, `fmi3SetClock`), and nothing changes between them.
//!
//! At tick k (t = start + k Ts) the outputs are the law's for the measurement of tick k - 1 and
//! the PID memory advanced over Ts from it (tick 0: the measurement of tick 0, the memory's
//! start), exactly what the Controller's `sampled` model exchange computes at its time events:
//! the two agree at the ticks (tests/python/test_sampled_controller.py). A separate FMU rather
//! than a mode of the Controller: which variables are clocked is part of the model description,
//! and the Controller's outputs are continuous in its default (feedthrough) mode.

#![allow(non_snake_case)] // the paper's symbols: M1, U1, K11, ...

#[macro_use]
#[path = "../../design_parameters.rs"]
mod design_parameters;

use holonomic::models::controller::{ControlLaw, ControllerState, DEFAULT_PID, Mode, PidGains, lqr_gain};
use holonomic::models::dc_motor::DcMotorParams;
use holonomic::models::pendulum::PendulumParams;
use nalgebra::{Matrix2, Matrix4, SMatrix, Vector2, Vector4};
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

control_mode!(
    /// The control law (`mode`), as the Controller's.
);

with_design_parameters! {
    sampled;
    /// Digital LQR / PID controller of the double inverted pendulum (Liptak et al., 'The control of
    /// holonomic system', eqs. (14), (16)), sampled at the ticks of the clock `sample` (every Ts)
    #[derive(Model, Debug, Clone, Serialize, Deserialize)]
    #[fmu(fmi3_only, scheduled_execution)]
    pub struct SampledController {
        /// The sample clock: ticks at start + k Ts (the importer activates it in Event Mode, or
        /// its model partition in Scheduled Execution)
        #[variable(vr = 200, input, clock(fixed, interval = Ts, priority = 0))]
        pub sample: Clock,
        /// Sample period Ts: the interval of `sample`
        #[variable(vr = 31, name = "Ts", parameter, fixed, start = 0.01, unit = "s", min > 0.0)]
        pub Ts: f64,
        /// Measured angle alpha1 at the tick (connect to Pendulum.alpha1)
        #[variable(vr = 0, input, discrete, clocks = [sample], start = 0.0, unit = "rad")]
        pub alpha1: f64,
        /// Measured angular velocity omega1 at the tick
        #[variable(vr = 1, input, discrete, clocks = [sample], start = 0.0, unit = "rad/s")]
        pub omega1: f64,
        /// Measured absolute angle alpha2 at the tick
        #[variable(vr = 2, input, discrete, clocks = [sample], start = 0.0, unit = "rad")]
        pub alpha2: f64,
        /// Measured angular velocity omega2 at the tick
        #[variable(vr = 3, input, discrete, clocks = [sample], start = 0.0, unit = "rad/s")]
        pub omega2: f64,
        /// Reference for alpha1 at the tick (0 = upright)
        #[variable(vr = 4, input, discrete, clocks = [sample], start = 0.0, unit = "rad")]
        pub alpha1_ref: f64,
        /// Reference for alpha2 at the tick (0 = upright)
        #[variable(vr = 5, input, discrete, clocks = [sample], start = 0.0, unit = "rad")]
        pub alpha2_ref: f64,
        /// Torque demand M1, limited to +-M_max, from the measurement of the previous tick (held between ticks)
        #[variable(vr = 10, output, discrete, clocks = [sample], unit = "N.m", depends = [])]
        pub M1: f64,
        /// Torque demand M2, as M1
        #[variable(vr = 11, output, discrete, clocks = [sample], unit = "N.m", depends = [])]
        pub M2: f64,
        /// Voltage command U1 for the motor of joint 1, limited to +-U_max, as M1
        #[variable(vr = 12, output, discrete, clocks = [sample], unit = "V", depends = [])]
        pub U1: f64,
        /// Voltage command U2, as U1
        #[variable(vr = 13, output, discrete, clocks = [sample], unit = "V", depends = [])]
        pub U2: f64,
    }
    // The design parameters (`mode` .. `U_max`, ../../design_parameters.rs), then:
    {
        /// LQR gain K of eq. (14), 2 x 4, computed at initialization (row i: the torque M_i)
        #[variable(vr = 110, calculated_parameter, fixed, initial_depends = [m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22])]
        pub K: [[f64; 4]; 2],
        /// The PID memory (integrals, derivative filters), advanced at the ticks.
        pub memory: ControllerState,
        /// The measurement of the last tick (alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref),
        /// which the next tick's outputs use (the one sample of delay).
        pub pending: [f64; 6],
        /// Ticks since initialization.
        pub ticks: u64,
    }
}

impl SampledController {
    /// The control law of the parameters (`law_with_gain`) with the gain K.
    fn law(&self) -> ControlLaw {
        self.law_with_gain(SMatrix::<f64, 2, 4>::from_fn(|i, j| self.K[i][j]))
    }

    /// The clocked inputs as they are: (x, x_ref).
    fn measurement(&self) -> [f64; 6] {
        [
            self.alpha1,
            self.omega1,
            self.alpha2,
            self.omega2,
            self.alpha1_ref,
            self.alpha2_ref,
        ]
    }
}

/// (x, x_ref) of a held measurement.
fn split(p: &[f64; 6]) -> (Vector4<f64>, Vector2<f64>) {
    (Vector4::new(p[0], p[1], p[2], p[3]), Vector2::new(p[4], p[5]))
}

impl Model for SampledController {
    fn initialize(&mut self, _ctx: &Context) -> Result<(), String> {
        self.K = self.lqr_gain_rows()?;
        // The memory's start: integrals 0, filters at the measured speeds (no derivative kick).
        let (x, _) = split(&self.measurement());
        self.memory = self.law().initial_state(&x);
        self.ticks = 0;
        Ok(())
    }

    /// At a tick of `sample`: the memory advances over Ts from the measurement of the previous
    /// tick, which the outputs then use; this tick's measurement waits for the next one (tick 0:
    /// the outputs of this measurement and the memory's start).
    fn update(&mut self, _event: &mut Event) -> Result<(), String> {
        if !self.sample.is_active() {
            return Ok(());
        }
        let law = self.law();
        let now = self.measurement();
        let held = if self.ticks == 0 { now } else { self.pending };
        let (x, reference) = split(&held);
        let out = law.tick(&mut self.memory, &x, &reference, self.Ts, self.ticks == 0);
        [self.M1, self.M2] = [out.m[0], out.m[1]];
        [self.U1, self.U2] = [out.u[0], out.u[1]];
        self.pending = now;
        self.ticks += 1;
        Ok(())
    }
}

impl CoSimulation for SampledController {}

rustfmu::export_fmi3!(SampledController);
