//! The `CanController` FMU (FMI 3.0, FMI-LS-BUS 1.0.0): the controller ECU of the networked
//! pendulum. It receives the measured state x = (α1, ω1, α2, ω2) in the sensor node's CAN frames
//! (identifier `sensor_id`; layout and scaling: holonomic::models::can_messages), and at every
//! tick of its Tx clock (a countdown it sets to `period` again at each tick) runs the paper's
//! control law on the last measurement that arrived, the LQR of eq. (14), M = -K (x - x_ref),
//! with the gain K of the paper's design (Q = C'C, R = I; the design parameters
//! ../../design_parameters.rs, shared with the Controller and SampledController FMUs), turns the
//! torques into the motors' voltages U1, U2 and sends each in its own CAN frame (`motor1_id`,
//! `motor2_id`) to the motor-drive nodes.
//!
//! The law is holonomic's [`ControlLaw::tick`], as the SampledController ticks it: at tick k the
//! memory (PID modes) advances over `period`, then the command for the measurement. Where the
//! SampledController uses the measurement of its previous tick, the ECU uses the last one the bus
//! brought: with the sensor sampling at the same period and phase, that is the same sample, and
//! the bus adds the time its frames take. Before the first measurement arrives the ECU computes
//! with x = 0 (it sends U = 0); a measurement frame that does not arrive leaves the last one.

#![allow(non_snake_case)] // the paper's symbols: M1, U1, K, ...

#[macro_use]
#[path = "../../design_parameters.rs"]
mod design_parameters;

// Not every node uses every helper of the shared file.
#[allow(dead_code)]
#[macro_use]
#[path = "../../can_node.rs"]
mod can_node;

use can_node::{Notified, RX_MAX_SIZE, TX_MAX_SIZE, bad_frame, received, send};
use holonomic::models::can_messages::{CommandFrame, Measurement, MeasurementFrame, Signal};
use holonomic::models::controller::{ControlLaw, ControllerState, DEFAULT_PID, Mode, PidGains, lqr_gain};
use holonomic::models::dc_motor::DcMotorParams;
use holonomic::models::pendulum::PendulumParams;
use nalgebra::{Matrix2, Matrix4, SMatrix, Vector2, Vector4};
use rustfmu::ls_bus::{CanFrame, Operation};
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

control_mode!(
    /// The control law (`mode`), as the Controller's.
);

can_node! {
    network: "The CAN bus the measurement comes on and the commands go on";
    log_bus: "Bus operations refused, frames ignored";
    /// The networked pendulum's controller ECU: the paper's LQR (eq. (14)) every period on the measurement of the CAN bus, the motor voltages sent in CAN frames
    pub struct CanController {
        /// Angle alpha1 of the last measurement frame received (0 until one arrives)
        #[variable(vr = 1, output, discrete, initial = exact, start = 0.0, unit = "rad", depends = [])]
        pub alpha1: f64,
        /// Angular velocity omega1 of the last measurement frame received
        #[variable(vr = 2, output, discrete, initial = exact, start = 0.0, unit = "rad/s", depends = [])]
        pub omega1: f64,
        /// Absolute angle alpha2 of the last measurement frame received
        #[variable(vr = 3, output, discrete, initial = exact, start = 0.0, unit = "rad", depends = [])]
        pub alpha2: f64,
        /// Angular velocity omega2 of the last measurement frame received
        #[variable(vr = 4, output, discrete, initial = exact, start = 0.0, unit = "rad/s", depends = [])]
        pub omega2: f64,
        /// Reference for alpha1, read at each tick (0 = upright)
        #[variable(vr = 5, input, start = 0.0, unit = "rad")]
        pub alpha1_ref: f64,
        /// Reference for alpha2, read at each tick (0 = upright)
        #[variable(vr = 6, input, start = 0.0, unit = "rad")]
        pub alpha2_ref: f64,
        /// Torque demand M1 of the last tick, limited to +-M_max
        #[variable(vr = 10, output, discrete, initial = exact, start = 0.0, unit = "N.m", depends = [])]
        pub M1: f64,
        /// Torque demand M2 of the last tick, limited to +-M_max
        #[variable(vr = 11, output, discrete, initial = exact, start = 0.0, unit = "N.m", depends = [])]
        pub M2: f64,
        /// Voltage command U1 sent at the last tick (before its 16-bit scaling), limited to +-U_max
        #[variable(vr = 12, output, discrete, initial = exact, start = 0.0, unit = "V", depends = [])]
        pub U1: f64,
        /// Voltage command U2 sent at the last tick, as U1
        #[variable(vr = 13, output, discrete, initial = exact, start = 0.0, unit = "V", depends = [])]
        pub U2: f64,
        /// Sample period: the interval of CAN.Tx_Clock, the first tick one period after the start
        #[variable(vr = 31, parameter, fixed, start = 0.01, unit = "s", min > 0.0)]
        pub period: f64,
        /// Identifier of the sensor's measurement frames (standard, 11 bits)
        #[variable(vr = 32, parameter, fixed, start = 0x020, min = 0, max = 0x7FF)]
        pub sensor_id: i32,
        /// Identifier of the command frames for motor 1 (standard, 11 bits)
        #[variable(vr = 33, parameter, fixed, start = 0x010, min = 0, max = 0x7FF)]
        pub motor1_id: i32,
        /// Identifier of the command frames for motor 2 (standard, 11 bits)
        #[variable(vr = 34, parameter, fixed, start = 0x011, min = 0, max = 0x7FF)]
        pub motor2_id: i32,
        /// Angle resolution of the measurement frames (as the sensor's)
        #[variable(vr = 35, parameter, fixed, start = 1e-4, unit = "rad", min > 0.0)]
        pub angle_resolution: f64,
        /// Angular velocity resolution of the measurement frames (as the sensor's)
        #[variable(vr = 36, parameter, fixed, start = 1e-3, unit = "rad/s", min > 0.0)]
        pub rate_resolution: f64,
        /// Voltage resolution of the command frames (as the drives')
        #[variable(vr = 37, parameter, fixed, start = 1e-3, unit = "V", min > 0.0)]
        pub voltage_resolution: f64,
        bus_notifications(vr = 38),
        terminal {
            /// Ticks every period (a countdown the node sets to period at each tick): the samples
            tx_clock: input, clock(countdown);
            tx_data: depends = [alpha1_ref, alpha2_ref];
        },
        /// Measurement frames received and applied
        count frames_received(vr = 70),
        /// Command frames sent (two a tick)
        count frames_sent(vr = 71),
        /// Frames sensor_id ignored: their data is not a measurement (another data length)
        count bad_frames(vr = 72),
        notifications(confirmed = 73, arbitration_lost = 74, ours = "motor1_id and motor2_id"),
        bus_errors_and_format_errors(vr = 75, 76),
        /// Commands sent limited to their 16-bit range
        count signals_limited(vr = 77),
    }
    // The design parameters (`mode` .. `U_max`, ../../design_parameters.rs), then:
    with_design_parameters(sampled) {
        /// LQR gain K of eq. (14), 2 x 4, computed at initialization (row i: the torque M_i)
        #[variable(vr = 110, calculated_parameter, fixed, initial_depends = [m1, m2, l1, l2, g, J1, J2, Q11, Q22, Q33, Q44, R11, R22])]
        pub K: [[f64; 4]; 2],
        /// The PID memory (integrals, derivative filters), advanced at the ticks.
        pub memory: ControllerState,
        /// Ticks since initialization.
        pub ticks: u64,
    }
}

impl CanController {
    /// The control law of the parameters with the gain K.
    fn law(&self) -> ControlLaw {
        self.law_with_gain(SMatrix::<f64, 2, 4>::from_fn(|i, j| self.K[i][j]))
    }

    fn measurement_frame(&self) -> MeasurementFrame {
        MeasurementFrame {
            angle: Signal {
                resolution: self.angle_resolution,
            },
            rate: Signal {
                resolution: self.rate_resolution,
            },
        }
    }

    /// Applies the measurement frames and counts the notifications of one received buffer.
    fn receive(&mut self, event: &Event) {
        let layout = self.measurement_frame();
        let mut notified = Notified {
            confirmed: self.confirmed,
            arbitration_lost: self.arbitration_lost,
            bus_errors: self.bus_errors,
        };
        let ours = [self.motor1_id, self.motor2_id];
        for op in received(&self.rx_data, &mut self.tx_data, event, &mut self.format_errors) {
            match op {
                Operation::CanTransmit(CanFrame { id, data, .. }) if i64::from(id) == i64::from(self.sensor_id) => {
                    match layout.decode(data) {
                        Ok(Measurement {
                            alpha1,
                            omega1,
                            alpha2,
                            omega2,
                        }) => {
                            [self.alpha1, self.omega1, self.alpha2, self.omega2] = [alpha1, omega1, alpha2, omega2];
                            self.frames_received += 1;
                        }
                        Err(why) => bad_frame(event, id, &why, &mut self.bad_frames),
                    }
                }
                other => notified.count(&other, &ours),
            }
        }
        (self.confirmed, self.arbitration_lost, self.bus_errors) =
            (notified.confirmed, notified.arbitration_lost, notified.bus_errors);
    }
}

impl Model for CanController {
    fn initialize(&mut self, _ctx: &Context) -> Result<(), String> {
        self.K = self.lqr_gain_rows()?;
        let x = Vector4::new(self.alpha1, self.omega1, self.alpha2, self.omega2);
        self.memory = self.law().initial_state(&x);
        self.ticks = 0;
        self.tx_clock.set_interval(self.period);
        Ok(())
    }

    fn update(&mut self, event: &mut Event) -> Result<(), String> {
        self.forget_sent();
        if self.rx_clock.is_active() {
            self.receive(event);
        }
        if self.tx_clock.is_active() {
            let x = Vector4::new(self.alpha1, self.omega1, self.alpha2, self.omega2);
            let reference = Vector2::new(self.alpha1_ref, self.alpha2_ref);
            let out = self
                .law()
                .tick(&mut self.memory, &x, &reference, self.period, self.ticks == 0);
            [self.M1, self.M2] = [out.m[0], out.m[1]];
            [self.U1, self.U2] = [out.u[0], out.u[1]];
            let layout = CommandFrame {
                voltage: Signal {
                    resolution: self.voltage_resolution,
                },
            };
            for (id, u) in [(self.motor1_id, self.U1), (self.motor2_id, self.U2)] {
                let (data, limited) = layout.encode(u);
                send(&mut self.tx_data, id, &data)?;
                self.signals_limited += i32::from(limited);
                self.frames_sent += 1;
            }
            self.ticks += 1;
            self.sent = true;
            self.tx_clock.set_interval(self.period);
        }
        Ok(())
    }
}

impl CoSimulation for CanController {}

rustfmu::export_fmi3!(CanController);
