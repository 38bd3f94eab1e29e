//! The `CanSignal` FMU (FMI 3.0, FMI-LS-BUS 1.0.0): a node of a CAN network that carries one
//! signal. At every tick of its Tx clock (a countdown it sets to `period` again at each tick) it sends its input `u` in a CAN frame of
//! identifier `tx_id` (8 data bytes: the f64, little-endian); from the frames it receives it
//! takes those of identifier `rx_id` and outputs their value as `y`. A sensor node (the
//! pendulum's angles onto the bus) and an actuator node (a motor command off the bus) are each
//! one of these.
//!
//! The network terminal, the variables' MIME types and the layered standard's manifest come from
//! one declaration, `#[fmu(can_network(..))]`; the model sees bus operations as
//! [`rustfmu::ls_bus::Operation`]s, never bytes. A received buffer with a malformed operation is
//! applied not at all: the node logs what was wrong and where, counts it in `format_errors`, and
//! answers with the standard's Format Error operation (carrying the offending bytes) at its next
//! Tx tick ("A Format Error operation will be sent by a network participant if a corrupt Bus
//! Operation was received", FMI-LS-BUS 1.0.0, Format Error).

use rustfmu::ls_bus::{CanFrame, Operation, decode_all, push_into};
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// The bytes a Tx_Data value may hold (`maxSize`): a frame and a few replies.
pub const TX_MAX_SIZE: u32 = 512;
/// The bytes an Rx_Data value may hold (`maxSize`): many frames of one bus communication point.
pub const RX_MAX_SIZE: u32 = 4096;

/// One signal over a CAN bus: sent in frame tx_id every period, received from frame rx_id
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(
    fmi3_only,
    co_simulation_only,
    log_category(name = "logBus", description = "Bus operations received and sent, and refused buffers"),
    can_network(
        name = "CAN",
        description = "The CAN bus the signal travels on",
        rx_clock = rx_clock,
        rx_data = rx_data,
        tx_clock = tx_clock,
        tx_data = tx_data,
        bus_notifications = bus_notifications,
    )
)]
pub struct CanSignal {
    /// Simulation time
    #[variable(vr = 0, independent, unit = "s")]
    pub time: f64,
    /// The signal to send (sampled at each Tx tick)
    #[variable(vr = 1, input, start = 0.0)]
    pub u: f64,
    /// The signal of the last frame rx_id received (start until one arrives)
    #[variable(vr = 2, output, discrete, initial = exact, start = 0.0, depends = [])]
    pub y: f64,
    /// Identifier of the frames sent (standard, 11 bits)
    #[variable(vr = 10, parameter, fixed, start = 0x100, min = 0, max = 0x7FF)]
    pub tx_id: i32,
    /// Identifier of the frames whose signal is y (standard, 11 bits)
    #[variable(vr = 11, parameter, fixed, start = 0x100, min = 0, max = 0x7FF)]
    pub rx_id: i32,
    /// Send period: the interval of Tx_Clock
    #[variable(vr = 12, parameter, fixed, start = 0.01, unit = "s", min > 0.0)]
    pub period: f64,
    /// Whether the node waits for Confirm, Arbitration Lost and Bus Error (FMI-LS-BUS BusNotifications)
    #[variable(vr = 13, name = "BusNotifications", parameter, fixed, start = false)]
    pub bus_notifications: bool,
    /// Ticks when the importer delivers bus operations to this node
    #[variable(vr = 1002, name = "CAN.Rx_Clock", input, clock(triggered))]
    pub rx_clock: Clock,
    /// The bus operations delivered (FMI-LS-BUS CAN)
    #[variable(vr = 1001, name = "CAN.Rx_Data", input, discrete, clocks = [rx_clock], max_size = RX_MAX_SIZE)]
    pub rx_data: Vec<u8>,
    /// Ticks every period (a countdown the node sets to period at each tick): its bus communication points for sending
    #[variable(vr = 1004, name = "CAN.Tx_Clock", input, clock(countdown))]
    pub tx_clock: Clock,
    /// The bus operations this node sends (FMI-LS-BUS CAN)
    #[variable(vr = 1003, name = "CAN.Tx_Data", output, discrete, clocks = [tx_clock], max_size = TX_MAX_SIZE, depends = [])]
    pub tx_data: Vec<u8>,
    /// Frames sent
    #[variable(vr = 20, output, discrete, initial = exact, start = 0, depends = [])]
    pub frames_sent: i32,
    /// Frames rx_id received
    #[variable(vr = 21, output, discrete, initial = exact, start = 0, depends = [])]
    pub frames_received: i32,
    /// Confirm operations for tx_id received
    #[variable(vr = 22, output, discrete, initial = exact, start = 0, depends = [])]
    pub confirmed: i32,
    /// Arbitration Lost operations for tx_id received
    #[variable(vr = 23, output, discrete, initial = exact, start = 0, depends = [])]
    pub arbitration_lost: i32,
    /// Bus Error operations received
    #[variable(vr = 24, output, discrete, initial = exact, start = 0, depends = [])]
    pub bus_errors: i32,
    /// Received buffers refused as malformed (each answered with a Format Error operation)
    #[variable(vr = 25, output, discrete, initial = exact, start = 0, depends = [])]
    pub format_errors: i32,
    /// Tx_Data was read at the last Tx tick: it is emptied at the next event
    sent: bool,
}

impl CanSignal {
    /// Applies one received buffer: every operation, or none (a Format Error reply queued).
    fn receive(&mut self, event: &Event) -> Result<(), String> {
        let ops = match decode_all(&self.rx_data) {
            Ok(ops) => ops,
            Err(e) => {
                let reason = format!("CAN.Rx_Data refused, nothing of it applied: {e}");
                event.context().log("logBus", &reason);
                self.format_errors += 1;
                let data = &e.bytes[..e.bytes.len().min(TX_MAX_SIZE as usize - 10)];
                // A reply that does not fit is dropped: the refusal is logged and counted above.
                let _ = push_into(
                    &mut self.tx_data,
                    TX_MAX_SIZE as usize,
                    &Operation::FormatError { data },
                );
                return Ok(());
            }
        };
        let ours = |id: u32| i64::from(id) == i64::from(self.tx_id);
        for op in ops {
            match op {
                Operation::CanTransmit(CanFrame { id, data, .. }) if i64::from(id) == i64::from(self.rx_id) => {
                    match <[u8; 8]>::try_from(data) {
                        Ok(bytes) => {
                            self.y = f64::from_le_bytes(bytes);
                            self.frames_received += 1;
                        }
                        Err(_) => event.context().log(
                            "logBus",
                            &format!(
                                "frame {id:#x} with {} data bytes ignored: this node's signal is 8 bytes",
                                data.len()
                            ),
                        ),
                    }
                }
                Operation::Confirm { id } if ours(id) => self.confirmed += 1,
                Operation::ArbitrationLost { id } if ours(id) => self.arbitration_lost += 1,
                Operation::BusError { .. } => self.bus_errors += 1,
                _ => {}
            }
        }
        Ok(())
    }
}

impl Model for CanSignal {
    fn initialize(&mut self, _ctx: &Context) -> Result<(), String> {
        // The first Tx tick one period after the start. A countdown clock rather than a periodic
        // one: an importer with a bus simulation schedules countdown clocks (the layered standard's
        // example, "a time-based Tx_Clock with intervalVariability=countdown"; FMU Manipulation
        // Toolbox's containers tick countdown clocks, not periodic ones).
        self.tx_clock.set_interval(self.period);
        Ok(())
    }

    fn update(&mut self, event: &mut Event) -> Result<(), String> {
        // What the importer read at the last Tx tick is gone: an empty Tx_Data means nothing to
        // send ("the size of the corresponding binary Tx_Data variable shall be set to zero").
        if self.sent {
            self.tx_data.clear();
            self.sent = false;
        }
        if self.rx_clock.is_active() {
            self.receive(event)?;
        }
        if self.tx_clock.is_active() {
            let frame = CanFrame {
                id: self.tx_id as u32,
                ide: false,
                rtr: false,
                data: &self.u.to_le_bytes(),
            };
            push_into(&mut self.tx_data, TX_MAX_SIZE as usize, &Operation::CanTransmit(frame))
                .map_err(|e| format!("CAN.Tx_Data: frame {:#x} not sent: {e}", self.tx_id))?;
            self.frames_sent += 1;
            self.sent = true;
            self.tx_clock.set_interval(self.period);
        }
        Ok(())
    }
}

impl CoSimulation for CanSignal {}

rustfmu::export_fmi3!(CanSignal);
