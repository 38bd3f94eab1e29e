//! The `CanMotorDrive` FMU (FMI 3.0, FMI-LS-BUS 1.0.0): a motor-drive node of the networked
//! pendulum. From the frames the bus brings it takes those of identifier `rx_id`, reads the
//! voltage command in them (a signed 16-bit signal in units of `voltage_resolution`: the layout
//! of holonomic::models::can_messages) and outputs it as `U`, held until the next one: a frame
//! that does not arrive (lost, late, or refused) leaves the last voltage. Connect `U` to a
//! DCMotor's `U`. The two motors of the pendulum are two instances, `rx_id` = the Controller
//! ECU's `motor1_id` and `motor2_id`.
//!
//! The node sends nothing of its own; its Tx clock (a countdown) ticks only to answer a malformed
//! received buffer with a Format Error, `reply_delay` after it (../can_node.rs).

#![allow(non_snake_case)] // the paper's symbol U

// Not every node uses every helper of the shared file.
#[allow(dead_code)]
#[macro_use]
#[path = "../../can_node.rs"]
mod can_node;

use can_node::{Notified, RX_MAX_SIZE, TX_MAX_SIZE, bad_frame, received};
use holonomic::models::can_messages::{CommandFrame, Signal};
use rustfmu::ls_bus::{CanFrame, Operation};
use rustfmu::prelude::*;

can_node! {
    network: "The CAN bus the voltage command comes on";
    log_bus: "Bus operations refused, frames ignored";
    /// The networked pendulum's motor-drive node: outputs the voltage command of the CAN frames rx_id, held until the next one
    pub struct CanMotorDrive {
        /// Voltage command U of the last frame rx_id received, held (0 until one arrives; connect to DCMotor.U)
        #[variable(vr = 1, output, discrete, initial = exact, start = 0.0, unit = "V", depends = [])]
        pub U: f64,
        /// Identifier of the command frames for this motor (standard, 11 bits)
        #[variable(vr = 10, parameter, fixed, start = 0x010, min = 0, max = 0x7FF)]
        pub rx_id: i32,
        /// Voltage resolution: the value of one bit of the 16-bit signal U
        #[variable(vr = 11, parameter, fixed, start = 1e-3, unit = "V", min > 0.0)]
        pub voltage_resolution: f64,
        /// Time from a refused buffer to the Tx tick that answers it with a Format Error
        #[variable(vr = 12, parameter, fixed, start = 1e-6, unit = "s", min > 0.0)]
        pub reply_delay: f64,
        bus_notifications(vr = 13),
        terminal {
            /// Ticks reply_delay after a refused buffer, to send its Format Error (a countdown)
            tx_clock: input, clock(countdown);
            /// The bus operations this node sends (FMI-LS-BUS CAN): Format Errors only
            tx_data: depends = [];
        },
        /// Command frames rx_id received and applied
        count frames_received(vr = 20),
        /// Frames rx_id ignored: their data is not a command (another data length)
        count bad_frames(vr = 21),
        bus_errors_and_format_errors(vr = 24, 25),
    }
}

impl Model for CanMotorDrive {
    fn update(&mut self, event: &mut Event) -> Result<(), String> {
        self.forget_sent();
        if self.tx_clock.is_active() {
            self.sent = !self.tx_data.is_empty();
        }
        if self.rx_clock.is_active() {
            let layout = CommandFrame {
                voltage: Signal {
                    resolution: self.voltage_resolution,
                },
            };
            let replies = self.tx_data.len();
            let mut notified = Notified {
                bus_errors: self.bus_errors,
                ..Notified::default()
            };
            for op in received(&self.rx_data, &mut self.tx_data, event, &mut self.format_errors) {
                match op {
                    Operation::CanTransmit(CanFrame { id, data, .. }) if i64::from(id) == i64::from(self.rx_id) => {
                        match layout.decode(data) {
                            Ok(u) => {
                                self.U = u;
                                self.frames_received += 1;
                            }
                            Err(why) => bad_frame(event, id, &why, &mut self.bad_frames),
                        }
                    }
                    other => notified.count(&other, &[]),
                }
            }
            self.bus_errors = notified.bus_errors;
            if self.tx_data.len() > replies {
                self.tx_clock.set_interval(self.reply_delay);
            }
        }
        Ok(())
    }
}

impl CoSimulation for CanMotorDrive {}

rustfmu::export_fmi3!(CanMotorDrive);
