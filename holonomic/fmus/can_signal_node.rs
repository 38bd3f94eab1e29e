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
//! the other), as the controllers share `design_parameters.rs`.

/// The bytes a Tx_Data value may hold (`maxSize`): a frame and a few replies.
pub const TX_MAX_SIZE: u32 = 512;
/// The bytes an Rx_Data value may hold (`maxSize`): many frames of one bus communication point.
pub const RX_MAX_SIZE: u32 = 4096;

/// `can_signal_node! { <attributes> pub struct Name; period: <doc and #[variable]>;
/// tx_clock: <doc and #[variable]>; }`: the node's struct with every variable but those two as
/// both FMUs declare them, and what both do with a bus: `receive` (an Rx tick) and `send` (a Tx
/// tick).
macro_rules! can_signal_node {
    (
        $(# $attr:tt)*
        pub struct $name:ident;
        period: $(# $period_attr:tt)*;
        tx_clock: $(# $tx_clock_attr:tt)*;
    ) => {
        $(# $attr)*
        pub struct $name {
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
            $(# $period_attr)*
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
            $(# $tx_clock_attr)*
            pub tx_clock: Clock,
            /// The bus operations this node sends (FMI-LS-BUS CAN)
            #[variable(vr = 1003, name = "CAN.Tx_Data", output, discrete, clocks = [tx_clock], max_size = TX_MAX_SIZE, depends = [u])]
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

        impl $name {
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

        impl $name {
            /// A Tx tick: the frame tx_id with `u` (8 bytes, the f64 little-endian) joins what
            /// Tx_Data holds, which the importer reads at this tick and the next event empties.
            fn send(&mut self) -> Result<(), String> {
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
                Ok(())
            }

            /// What the importer read at the last Tx tick is gone: an empty Tx_Data means nothing
            /// to send ("the size of the corresponding binary Tx_Data variable shall be set to
            /// zero").
            fn forget_sent(&mut self) {
                if self.sent {
                    self.tx_data.clear();
                    self.sent = false;
                }
            }
        }
    };
}
