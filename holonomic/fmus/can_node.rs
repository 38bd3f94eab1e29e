//! What every network FMU of the networked pendulum (can_sensor, can_controller,
//! can_motor_drive) does with its `CAN.Rx_Data` and `CAN.Tx_Data`, written once; each crate
//! includes this file with `#[path]` (an FMU crate is a `cdylib` of exported C functions: one
//! cannot depend on another). As the CanSignal node (holonomic/fmus/can_signal):
//!
//! - a received buffer is applied whole or not at all: one malformed operation, and the node
//!   logs what was wrong and where, counts it in `format_errors`, and answers with the standard's
//!   Format Error operation (carrying the offending bytes) at its next Tx tick ("A Format Error
//!   operation will be sent by a network participant if a corrupt Bus Operation was received",
//!   FMI-LS-BUS 1.0.0, Format Error);
//! - a frame of the node's identifier whose data the message layout cannot read (another data
//!   length: holonomic::models::can_messages) is logged, counted in `bad_frames` and ignored;
//! - a frame that does not arrive changes nothing: the node keeps the last value it received.

use rustfmu::ls_bus::{Operation, decode_all, push_into};
use rustfmu::prelude::*;

/// The bytes a Tx_Data value may hold (`maxSize`): a few frames and a reply.
pub const TX_MAX_SIZE: u32 = 512;
/// The bytes an Rx_Data value may hold (`maxSize`): the frames of one bus communication point.
pub const RX_MAX_SIZE: u32 = 4096;

/// The operations of a received Rx_Data value, or none: a malformed buffer is logged, counted
/// in `format_errors` and answered with a Format Error queued in `tx`.
pub fn received<'a>(rx: &'a [u8], tx: &mut Vec<u8>, event: &Event, format_errors: &mut i32) -> Vec<Operation<'a>> {
    match decode_all(rx) {
        Ok(ops) => ops,
        Err(e) => {
            event
                .context()
                .log("logBus", &format!("CAN.Rx_Data refused, nothing of it applied: {e}"));
            *format_errors += 1;
            let data = &e.bytes[..e.bytes.len().min(TX_MAX_SIZE as usize - 10)];
            // A reply that does not fit is dropped: the refusal is logged and counted above.
            let _ = push_into(tx, TX_MAX_SIZE as usize, &Operation::FormatError { data });
            Vec::new()
        }
    }
}

/// The bus's notifications about the node's own frames, counted.
#[derive(Debug, Clone, Copy, Default)]
pub struct Notified {
    pub confirmed: i32,
    pub arbitration_lost: i32,
    pub bus_errors: i32,
}

impl Notified {
    /// Counts `op` if it is a notification about one of `ours` (Bus Errors: every one).
    pub fn count(&mut self, op: &Operation<'_>, ours: &[i32]) {
        let ours = |id: u32| ours.iter().any(|&o| i64::from(o) == i64::from(id));
        match op {
            Operation::Confirm { id } if ours(*id) => self.confirmed += 1,
            Operation::ArbitrationLost { id } if ours(*id) => self.arbitration_lost += 1,
            Operation::BusError { .. } => self.bus_errors += 1,
            _ => {}
        }
    }
}

/// Logs a frame of the node's identifier that the layout cannot read, and counts it.
pub fn bad_frame(event: &Event, id: u32, why: &str, bad_frames: &mut i32) {
    event
        .context()
        .log("logBus", &format!("frame {id:#x} ignored, the last value kept: {why}"));
    *bad_frames += 1;
}

/// Appends a classic CAN data frame to `tx`, or says why it could not.
pub fn send(tx: &mut Vec<u8>, id: i32, data: &[u8]) -> Result<(), String> {
    let frame = rustfmu::ls_bus::CanFrame {
        id: id as u32,
        ide: false,
        rtr: false,
        data,
    };
    push_into(tx, TX_MAX_SIZE as usize, &Operation::CanTransmit(frame))
        .map_err(|e| format!("CAN.Tx_Data: frame {id:#x} not sent: {e}"))
}
