//! The CAN signal node the `CanSignal` and `CanSignalTriggered` FMUs are both made of (FMI 3.0,
//! FMI-LS-BUS 1.0.0), declared once: they differ only in their Tx clock, which the layered
//! standard lets a network FMU choose ("The causality of Tx_Clock depends on the selected Clock
//! type", FMI-LS-BUS 1.0.0, Low Cut: Tx Clocks):
//!
//! - `CanSignal`: a time-based input clock (`countdown`) that the node sets to `period` at each
//!   tick; the importer schedules it and adapts its steps (the standard's own example).
//! - `CanSignalTriggered`: a triggered output clock that the node ticks itself at its time events,
//!   every `period`: the form FMU Manipulation Toolbox 2.0's containers connect to a bus
//!   simulation (its builder never activates a bus simulation's Rx_Clock connected to a
//!   time-based Tx_Clock).
//!
//! Both crates include this file with `#[path]` (an FMU crate is a `cdylib`: one cannot depend on
//! the other), as the controllers share `design_parameters.rs`; it includes can_node.rs, the
//! network FMU every node is.

// Not every node uses every helper of the shared file.
#[allow(dead_code)]
#[macro_use]
#[path = "can_node.rs"]
pub mod can_node;

pub use can_node::{RX_MAX_SIZE, TX_MAX_SIZE};

/// `can_signal_node! { <doc comment> pub struct Name; period: <doc and #[variable]>;
/// tx_clock: <doc> input | output, clock(<kind>); }`: the node's struct (a network FMU of
/// can_node.rs) with every variable but those two as both FMUs declare them, and what both do
/// with a bus: `receive` (an Rx tick) and `send` (a Tx tick).
macro_rules! can_signal_node {
    (
        $(# $doc:tt)*
        pub struct $name:ident;
        period: $(# $period_attr:tt)*;
        tx_clock: $(# $tx_clock_doc:tt)* $tx_clock_causality:ident, clock($tx_clock_kind:ident);
    ) => {
        can_node! {
            network: "The CAN bus the signal travels on";
            log_bus: "Bus operations received and sent, and refused buffers";
            $(# $doc)*
            pub struct $name {
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
                $(# $period_attr)*
                pub period: f64,
                bus_notifications(vr = 13),
                terminal {
                    $(# $tx_clock_doc)* tx_clock: $tx_clock_causality, clock($tx_clock_kind);
                    tx_data: depends = [u];
                },
                /// Frames sent
                count frames_sent(vr = 20),
                /// Frames rx_id received
                count frames_received(vr = 21),
                notifications(confirmed = 22, arbitration_lost = 23, ours = "tx_id"),
                bus_errors_and_format_errors(vr = 24, 25),
            }
        }

        use $crate::can_signal_node::can_node::{Notified, received, send};
        use rustfmu::ls_bus::{CanFrame, Operation};

        impl $name {
            /// Applies one received buffer: every operation, or none (a Format Error reply queued).
            fn receive(&mut self, event: &Event) {
                let mut notified = Notified {
                    confirmed: self.confirmed,
                    arbitration_lost: self.arbitration_lost,
                    bus_errors: self.bus_errors,
                };
                for op in received(&self.rx_data, &mut self.tx_data, event, &mut self.format_errors) {
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
                        other => notified.count(&other, &[self.tx_id]),
                    }
                }
                (self.confirmed, self.arbitration_lost, self.bus_errors) =
                    (notified.confirmed, notified.arbitration_lost, notified.bus_errors);
            }

            /// A Tx tick: the frame tx_id with `u` (8 bytes, the f64 little-endian) joins what
            /// Tx_Data holds, which the importer reads at this tick and the next event empties.
            fn send(&mut self) -> Result<(), String> {
                send(&mut self.tx_data, self.tx_id, &self.u.to_le_bytes())?;
                self.frames_sent += 1;
                self.sent = true;
                Ok(())
            }
        }
    };
}
