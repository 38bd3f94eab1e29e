//! The `Controller` FMU: the paper's LQR (equation (14)) and PID (equation (16)), with torque
//! outputs for the plant and voltage outputs for the DC motors. In co-simulation the PID memory
//! (integrals, derivative filters) advances at communication points (a sampled controller); in
//! model exchange it is four continuous states. Both compute the outputs from the inputs and
//! that memory through the same law: from the inputs as they are (direct feedthrough, the
//! default), or, with `sampled = true`, from the inputs held at the last sample, a digital
//! controller with one sample of computation delay: its samples are the communication points in
//! co-simulation and time events every `Ts` in model exchange. Its torque and voltage limits are
//! event indicators (`M1_margin` .. `U2_margin`), so a model-exchange importer stops where the
//! law switches.

#![allow(non_snake_case)] // the paper's symbols: M1, U1, K11, ...

#[macro_use]
#[path = "../../design_parameters.rs"]
mod design_parameters;

use holonomic::models::controller::{ControlLaw, ControllerState, DEFAULT_PID, Knowns, Mode, PidGains, lqr_gain};
use holonomic::models::dc_motor::DcMotorParams;
use holonomic::models::pendulum::PendulumParams;
use nalgebra::{Matrix2, Matrix4, SMatrix, Vector2, Vector4};
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

control_mode!(
    /// The control law (`mode`).
);

with_design_parameters! {
    controller;
    /// LQR / PID controller of the double inverted pendulum (Liptak et al., 'The control of
    /// holonomic system', eqs. (14), (16)); torque and motor-voltage outputs
    #[derive(Model, Debug, Clone, Serialize, Deserialize)]
    pub struct Controller {
        /// Measured angle alpha1 of link 1 from the upward vertical (connect to Pendulum.alpha1)
        #[variable(vr = 0, input, continuous, start = 0.0, unit = "rad")]
        pub alpha1: f64,
        /// Measured angular velocity omega1 of link 1 (connect to Pendulum.omega1)
        #[variable(vr = 1, input, continuous, start = 0.0, unit = "rad/s")]
        pub omega1: f64,
        /// Measured absolute angle alpha2 of link 2 (connect to Pendulum.alpha2)
        #[variable(vr = 2, input, continuous, start = 0.0, unit = "rad")]
        pub alpha2: f64,
        /// Measured angular velocity omega2 of link 2 (connect to Pendulum.omega2)
        #[variable(vr = 3, input, continuous, start = 0.0, unit = "rad/s")]
        pub omega2: f64,
        /// Reference for alpha1 (0 = upright)
        #[variable(vr = 4, input, continuous, start = 0.0, unit = "rad")]
        pub alpha1_ref: f64,
        /// Reference for alpha2 (0 = upright)
        #[variable(vr = 5, input, continuous, start = 0.0, unit = "rad")]
        pub alpha2_ref: f64,
        /// Torque demand M1 for joint 1, limited to +-M_max: -K (x - x_ref) and/or the PID, from the inputs and the PID memory as they are (with sampled = true, from the inputs held at the last communication point)
        #[variable(vr = 10, output, continuous, unit = "N.m", depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral1, rate_filter1], initial_depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral1, mode, Kp1, Ki1, Kd1, M_max, m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22])]
        pub M1: f64,
        /// Torque demand M2 for joint 2, limited to +-M_max; as M1
        #[variable(vr = 11, output, continuous, unit = "N.m", depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral2, rate_filter2], initial_depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral2, mode, Kp2, Ki2, Kd2, M_max, m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22])]
        pub M2: f64,
        /// Voltage command U1 for the motor of joint 1: U = R/(n km) (M1 + n^2 B omega1) + n kb omega1, limited to +-U_max; computed like M1
        #[variable(vr = 12, output, continuous, unit = "V", depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral1, rate_filter1], initial_depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral1, mode, Kp1, Ki1, Kd1, m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22, motor_R, motor_km, motor_kb, motor_B, gear_ratio, U_max])]
        pub U1: f64,
        /// Voltage command U2 for the motor of joint 2, as U1
        #[variable(vr = 13, output, continuous, unit = "V", depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral2, rate_filter2], initial_depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral2, mode, Kp2, Ki2, Kd2, m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22, motor_R, motor_km, motor_kb, motor_B, gear_ratio, U_max])]
        pub U2: f64,
        /// PID memory of joint 1: the integral of the control error e1 = alpha1_ref - alpha1 (a continuous state in model exchange; advanced at communication points in co-simulation)
        #[variable(vr = 14, local, continuous, initial = exact, start = 0.0, unit = "rad.s")]
        pub integral1: f64,
        /// PID memory of joint 2: the integral of e2 = alpha2_ref - alpha2
        #[variable(vr = 15, local, continuous, initial = exact, start = 0.0, unit = "rad.s")]
        pub integral2: f64,
        /// Filtered speed of joint 1, Tf d(rate_filter1)/dt = omega1 - rate_filter1, starting at the measured omega1 (the derivative term's input; unused when Tf = 0)
        #[variable(vr = 16, local, continuous, initial = calculated, unit = "rad/s", initial_depends = [omega1])]
        pub rate_filter1: f64,
        /// Filtered speed of joint 2, as rate_filter1
        #[variable(vr = 17, local, continuous, initial = calculated, unit = "rad/s", initial_depends = [omega2])]
        pub rate_filter2: f64,
        /// d(integral1)/dt = e1, 0 while the command is at a limit in the direction of e1 (anti-windup)
        #[variable(vr = 80, name = "der(integral1)", local, continuous, unit = "rad", derivative_of = integral1, depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral1, rate_filter1], initial_depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral1, mode, Kp1, Ki1, Kd1, M_max, drives_motors, m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22, motor_R, motor_km, motor_kb, motor_B, gear_ratio, U_max])]
        pub der_integral1: f64,
        /// d(integral2)/dt = e2, as der(integral1)
        #[variable(vr = 81, name = "der(integral2)", local, continuous, unit = "rad", derivative_of = integral2, depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral2, rate_filter2], initial_depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral2, mode, Kp2, Ki2, Kd2, M_max, drives_motors, m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22, motor_R, motor_km, motor_kb, motor_B, gear_ratio, U_max])]
        pub der_integral2: f64,
        /// d(rate_filter1)/dt = (omega1 - rate_filter1)/Tf (0 when Tf = 0)
        #[variable(vr = 82, name = "der(rate_filter1)", local, continuous, unit = "rad/s2", derivative_of = rate_filter1, depends = [omega1, rate_filter1], initial_depends = [])]
        pub der_rate_filter1: f64,
        /// d(rate_filter2)/dt = (omega2 - rate_filter2)/Tf (0 when Tf = 0)
        #[variable(vr = 83, name = "der(rate_filter2)", local, continuous, unit = "rad/s2", derivative_of = rate_filter2, depends = [omega2, rate_filter2], initial_depends = [])]
        pub der_rate_filter2: f64,
        /// The measurement alpha1 the Controller held at the last communication point (the inputs at the start of the last fmi2DoStep; before the first step, at initialization): with sampled = true the outputs use these
        #[variable(vr = 90, local, discrete, unit = "rad")]
        pub alpha1_sample: f64,
        /// omega1 held at the last communication point, as alpha1_sample
        #[variable(vr = 91, local, discrete, unit = "rad/s")]
        pub omega1_sample: f64,
        /// alpha2 held at the last communication point, as alpha1_sample
        #[variable(vr = 92, local, discrete, unit = "rad")]
        pub alpha2_sample: f64,
        /// omega2 held at the last communication point, as alpha1_sample
        #[variable(vr = 93, local, discrete, unit = "rad/s")]
        pub omega2_sample: f64,
        /// alpha1_ref held at the last communication point, as alpha1_sample
        #[variable(vr = 94, local, discrete, unit = "rad")]
        pub alpha1_ref_sample: f64,
        /// alpha2_ref held at the last communication point, as alpha1_sample
        #[variable(vr = 95, local, discrete, unit = "rad")]
        pub alpha2_ref_sample: f64,
        /// false (default): M, U follow the inputs as they are set (direct feedthrough, the paper's continuous state feedback). true: a digital controller with one sample of computation delay: M, U at a sample instant come from the inputs held at the previous one (alpha1_sample, ...) and the PID memory advances from sample to sample. The samples are the communication points in co-simulation, and every Ts in model exchange (time events)
        #[variable(vr = 30, parameter, fixed, start = false)]
        pub sampled: bool,
        /// Sample period of sampled = true in model exchange (time events at start + k Ts); co-simulation samples at its communication points
        #[variable(vr = 31, name = "Ts", parameter, fixed, start = 0.01, unit = "s", min > 0.0)]
        pub Ts: f64,
        /// Distance of the demand for joint 1 from the torque limit, M_max - |M1 before the limit|: > 0 inside, <= 0 at the limit (an event indicator: where it changes sign, M1 is held and the integrator stops)
        #[variable(vr = 100, local, continuous, unit = "N.m", event_indicator, depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral1, rate_filter1])]
        pub M1_margin: f64,
        /// M_max - |M2 before the limit|, as M1_margin
        #[variable(vr = 101, local, continuous, unit = "N.m", event_indicator, depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral2, rate_filter2])]
        pub M2_margin: f64,
        /// Distance of the voltage for joint 1 from the supply limit, U_max - |U1 before the limit| (an event indicator)
        #[variable(vr = 102, local, continuous, unit = "V", event_indicator, depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral1, rate_filter1])]
        pub U1_margin: f64,
        /// U_max - |U2 before the limit|, as U1_margin
        #[variable(vr = 103, local, continuous, unit = "V", event_indicator, depends = [alpha1, omega1, alpha2, omega2, alpha1_ref, alpha2_ref, integral2, rate_filter2])]
        pub U2_margin: f64,
    }
    // The design parameters (`mode` .. `U_max`, ../../design_parameters.rs), then:
    {
        /// LQR gain K(1,1), computed at initialization by solving the Riccati equation for the plant linearized upright (paper eq. (14): 14.0666)
        #[variable(vr = 70, calculated_parameter, fixed, unit = "N.m/rad", initial_depends = [m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22])]
        pub K11: f64,
        /// LQR gain K(1,2) (paper: 2.8816)
        #[variable(vr = 71, calculated_parameter, fixed, unit = "N.m.s/rad", initial_depends = [m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22])]
        pub K12: f64,
        /// LQR gain K(1,3) (paper: 1.1348)
        #[variable(vr = 72, calculated_parameter, fixed, unit = "N.m/rad", initial_depends = [m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22])]
        pub K13: f64,
        /// LQR gain K(1,4) (paper: 1.0010)
        #[variable(vr = 73, calculated_parameter, fixed, unit = "N.m.s/rad", initial_depends = [m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22])]
        pub K14: f64,
        /// LQR gain K(2,1) (paper: -3.1814)
        #[variable(vr = 74, calculated_parameter, fixed, unit = "N.m/rad", initial_depends = [m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22])]
        pub K21: f64,
        /// LQR gain K(2,2) (paper: 0.1161)
        #[variable(vr = 75, calculated_parameter, fixed, unit = "N.m.s/rad", initial_depends = [m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22])]
        pub K22: f64,
        /// LQR gain K(2,3) (paper: 4.8456)
        #[variable(vr = 76, calculated_parameter, fixed, unit = "N.m/rad", initial_depends = [m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22])]
        pub K23: f64,
        /// LQR gain K(2,4) (paper: 0.9957)
        #[variable(vr = 77, calculated_parameter, fixed, unit = "N.m.s/rad", initial_depends = [m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22])]
        pub K24: f64,
        /// LQR gain K of eq. (14) as one 2 x 4 matrix (row i: the torque M_i; columns alpha1,
        /// omega1, alpha2, omega2; mixed units, N.m/rad and N.m.s/rad): K11 .. K24 as one array (FMI
        /// 3.0: one variable with <Dimension>s 2 and 4; FMI 2.0: the scalars K[1,1] .. K[2,4], value
        /// references 110 .. 117)
        #[variable(vr = 110, calculated_parameter, fixed, initial_depends = [m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22])]
        pub K: [[f64; 4]; 2],
        /// Sampled in model exchange: the memory changes at the samples only (time events).
        pub sampled_events: bool,
        /// The measurement at the last sample instant (alpha1, omega1, alpha2, omega2, alpha1_ref,
        /// alpha2_ref), which the next sample uses (the one sample of delay).
        pub pending: [f64; 6],
        /// Samples taken since initialization (model exchange).
        pub samples_taken: u64,
    }
}

impl Controller {
    fn k(&self) -> SMatrix<f64, 2, 4> {
        let v = self;
        SMatrix::<f64, 2, 4>::new(v.K11, v.K12, v.K13, v.K14, v.K21, v.K22, v.K23, v.K24)
    }

    /// The control law of the parameters (`law_with_gain`) with the gain K11 .. K24.
    fn law(&self) -> ControlLaw {
        self.law_with_gain(self.k())
    }

    fn measurement(&self) -> (Vector4<f64>, Vector2<f64>) {
        let v = self;
        (
            Vector4::new(v.alpha1, v.omega1, v.alpha2, v.omega2),
            Vector2::new(v.alpha1_ref, v.alpha2_ref),
        )
    }

    /// Holds the measurement as it is now (the sample for `sampled`).
    fn hold(&mut self) {
        let (x, reference) = self.measurement();
        (
            self.alpha1_sample,
            self.omega1_sample,
            self.alpha2_sample,
            self.omega2_sample,
        ) = (x[0], x[1], x[2], x[3]);
        (self.alpha1_ref_sample, self.alpha2_ref_sample) = (reference[0], reference[1]);
    }

    fn memory(&self) -> ControllerState {
        ControllerState {
            integral: [self.integral1, self.integral2],
            rate_filter: [self.rate_filter1, self.rate_filter2],
        }
    }

    fn set_memory(&mut self, s: &ControllerState) {
        [self.integral1, self.integral2] = s.integral;
        [self.rate_filter1, self.rate_filter2] = s.rate_filter;
    }
}

/// The equations' view of the law: the memory, the measurement and the references as they are.
fn knowns<D: Copy>(v: &ControllerContinuous<D>) -> Knowns<D> {
    Knowns {
        integral: [v.integral1, v.integral2],
        rate_filter: [v.rate_filter1, v.rate_filter2],
        x: [v.alpha1, v.omega1, v.alpha2, v.omega2],
        reference: [v.alpha1_ref, v.alpha2_ref],
    }
}

impl Model for Controller {
    fn initialize(&mut self, ctx: &Context) -> Result<(), String> {
        self.sampled_events = self.sampled && ctx.model_exchange();
        self.samples_taken = 0;
        self.hold();
        self.K = self.lqr_gain_rows()?;
        [
            [self.K11, self.K12, self.K13, self.K14],
            [self.K21, self.K22, self.K23, self.K24],
        ] = self.K;
        // The filters start at the measured speeds (no derivative kick); the integrals at
        // their start values.
        let (x, _) = self.measurement();
        let start = self.law().initial_state(&x);
        [self.rate_filter1, self.rate_filter2] = start.rate_filter;
        Ok(())
    }

    /// The PID memory in continuous time (model exchange); sampled, it changes at the samples only.
    fn derivatives<D: Real>(&self, _t: D, v: &mut ControllerContinuous<D>) {
        let k = knowns(v);
        if self.sampled_events {
            let zero = k.integral[0] * 0.0;
            [v.der_integral1, v.der_integral2, v.der_rate_filter1, v.der_rate_filter2] = [zero; 4];
            return;
        }
        let (d_integral, d_filter) = self.law().rates_of(k);
        [v.der_integral1, v.der_integral2] = d_integral;
        [v.der_rate_filter1, v.der_rate_filter2] = d_filter;
    }

    /// M and U from the inputs (sampled: from the inputs held at the last communication point)
    /// and the memory: eqs. (14), (16), limited.
    fn outputs<D: Real>(&self, _t: D, v: &mut ControllerContinuous<D>) {
        let mut k = knowns(v);
        if self.sampled {
            k.x = [
                self.alpha1_sample,
                self.omega1_sample,
                self.alpha2_sample,
                self.omega2_sample,
            ]
            .map(D::from);
            k.reference = [self.alpha1_ref_sample, self.alpha2_ref_sample].map(D::from);
        }
        let law = self.law();
        let (m, u, _) = law.command_of(k);
        [v.M1, v.M2] = m;
        [v.U1, v.U2] = u;
        // The event indicators: where a command reaches or leaves its limit.
        let (m_margin, u_margin) = law.limit_margins_of(k);
        [v.M1_margin, v.M2_margin] = m_margin;
        [v.U1_margin, v.U2_margin] = u_margin;
    }

    /// Sampled in model exchange, at the sample instants start + k Ts (time events): the memory
    /// advances over Ts from the measurement of the previous sample, which becomes the one the
    /// outputs use; the measurement now waits for the next sample. This is what a co-simulation
    /// step of h = Ts does ([`CoSimulation::do_step`] below), so both agree at the samples. At
    /// a limit's event (an indicator) nothing is stored: the law switches by itself.
    fn update(&mut self, event: &mut Event) -> Result<(), String> {
        if !self.sampled_events {
            return Ok(());
        }
        let (x, reference) = self.measurement();
        let now = [x[0], x[1], x[2], x[3], reference[0], reference[1]];
        if event.time_event() {
            let p = self.pending;
            let (x_prev, ref_prev) = (Vector4::new(p[0], p[1], p[2], p[3]), Vector2::new(p[4], p[5]));
            let law = self.law();
            let s = self.memory();
            let command = law.command(&s, &x_prev, &ref_prev);
            self.set_memory(&law.advance(&s, &x_prev, &ref_prev, &command, self.Ts));
            (
                self.alpha1_sample,
                self.omega1_sample,
                self.alpha2_sample,
                self.omega2_sample,
                self.alpha1_ref_sample,
                self.alpha2_ref_sample,
            ) = (p[0], p[1], p[2], p[3], p[4], p[5]);
            self.samples_taken += 1;
        }
        if event.initial() || event.time_event() {
            self.pending = now;
            let start = event.context().start_time();
            event.schedule(start + (self.samples_taken + 1) as f64 * self.Ts);
        }
        Ok(())
    }
}

impl CoSimulation for Controller {
    /// The memory advances over the step with the inputs of its start (the integral by e h, the
    /// filter exactly), and those inputs are held as the sample; the runtime then computes the
    /// outputs.
    fn do_step(&mut self, _t: f64, h: f64, _ctx: &mut Context) -> Result<(), StepFailure> {
        let law = self.law();
        let (x, reference) = self.measurement();
        let s = self.memory();
        let now = law.command(&s, &x, &reference);
        self.set_memory(&law.advance(&s, &x, &reference, &now, h));
        self.hold();
        Ok(())
    }
}

rustfmu::export_fmu!(Controller);
