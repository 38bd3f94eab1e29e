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
//!
//! The variables every node declares alike (its network terminal, the bus's notifications it
//! counts) are declared here too, by [`can_node!`]; the crates include this file with
//! `#[macro_use]`.

use rustfmu::ls_bus::{Operation, decode_all, push_into};
use rustfmu::prelude::*;

/// The bytes a Tx_Data value may hold (`maxSize`): a few frames and a reply.
pub const TX_MAX_SIZE: u32 = 512;
/// The bytes an Rx_Data value may hold (`maxSize`): the frames of one bus communication point.
pub const RX_MAX_SIZE: u32 = 4096;

/// `can_node! { network: "<terminal description>"; log_bus: "<log category description>";
/// <attributes> pub struct Name { <fields and rows> } }`: a network FMU (FMI 3.0, Co-Simulation)
/// with one CAN terminal, `CAN`, and the log category `logBus`. The struct is `time` (vr 0), the
/// fields as written, then `sent` (Tx_Data was read at the last Tx tick). Among the fields, these
/// rows stand for the variables every node declares alike, where the node has them:
///
/// - `bus_notifications(vr = N),`: the parameter `BusNotifications` (FMI-LS-BUS Configuration
///   terminal);
/// - `terminal { <doc> tx_clock: input | output, clock(<kind>); [<doc>] tx_data: depends = [..]; },`:
///   the members of the terminal, `CAN.Rx_Clock` (vr 1002), `CAN.Rx_Data` (vr 1001), `CAN.Tx_Clock`
///   (vr 1004; its causality, kind and description are the node's own) and `CAN.Tx_Data`
///   (vr 1003; described as the bus operations the node sends unless the node says more);
/// - `<doc> count name(vr = N),`: a count the node outputs (Int32, discrete, from 0, depending on
///   nothing);
/// - `notifications(confirmed = N, arbitration_lost = N, ours = "<its frames>"),`: the counts of
///   Confirm and Arbitration Lost operations for the node's own frames (`Notified`);
/// - `bus_errors_and_format_errors(vr = N, N),`: the counts of Bus Error operations and of
///   received buffers refused (`received`).
///
/// `forget_sent()` empties the Tx_Data the importer read at the last Tx tick.
///
/// `with_design_parameters!(..)` takes the struct instead of the compiler when the fields are
/// followed by `with_design_parameters(which) { <fields after> }` (../design_parameters.rs).
macro_rules! can_node {
    (
        network: $network:tt;
        log_bus: $log:tt;
        $(# $attr:tt)*
        pub struct $name:ident { $($fields:tt)* }
        $(with_design_parameters($which:ident) { $($tail:tt)* })?
    ) => {
        can_node!(@row { $network $log [$(# $attr)*] $name [$($which { $($tail)* })?] } [] $($fields)*);
    };

    (@row $node:tt [$($done:tt)*] bus_notifications(vr = $vr:tt), $($rest:tt)*) => {
        can_node!(@row $node [$($done)*
            /// Whether the node waits for Confirm, Arbitration Lost and Bus Error (FMI-LS-BUS BusNotifications)
            #[variable(vr = $vr, name = "BusNotifications", parameter, fixed, start = false)]
            pub bus_notifications: bool,
        ] $($rest)*);
    };
    (@row $node:tt [$($done:tt)*] terminal {
        $(# $clock_doc:tt)* tx_clock: $causality:ident, clock($kind:ident);
        tx_data: depends = $depends:tt;
    }, $($rest:tt)*) => {
        can_node!(@row $node [$($done)*] terminal {
            $(# $clock_doc)* tx_clock: $causality, clock($kind);
            /// The bus operations this node sends (FMI-LS-BUS CAN)
            tx_data: depends = $depends;
        }, $($rest)*);
    };
    (@row $node:tt [$($done:tt)*] terminal {
        $(# $clock_doc:tt)* tx_clock: $causality:ident, clock($kind:ident);
        $(# $data_doc:tt)+ tx_data: depends = $depends:tt;
    }, $($rest:tt)*) => {
        can_node!(@row $node [$($done)*
            /// Ticks when the importer delivers bus operations to this node
            #[variable(vr = 1002, name = "CAN.Rx_Clock", input, clock(triggered))]
            pub rx_clock: Clock,
            /// The bus operations delivered (FMI-LS-BUS CAN)
            #[variable(vr = 1001, name = "CAN.Rx_Data", input, discrete, clocks = [rx_clock], max_size = RX_MAX_SIZE)]
            pub rx_data: Vec<u8>,
            $(# $clock_doc)*
            #[variable(vr = 1004, name = "CAN.Tx_Clock", $causality, clock($kind))]
            pub tx_clock: Clock,
            $(# $data_doc)*
            #[variable(vr = 1003, name = "CAN.Tx_Data", output, discrete, clocks = [tx_clock], max_size = TX_MAX_SIZE, depends = $depends)]
            pub tx_data: Vec<u8>,
        ] $($rest)*);
    };
    (@row $node:tt [$($done:tt)*] $(# $doc:tt)* count $field:ident(vr = $vr:tt), $($rest:tt)*) => {
        can_node!(@row $node [$($done)*
            $(# $doc)*
            #[variable(vr = $vr, output, discrete, initial = exact, start = 0, depends = [])]
            pub $field: i32,
        ] $($rest)*);
    };
    (@row $node:tt [$($done:tt)*]
        notifications(confirmed = $confirmed:tt, arbitration_lost = $lost:tt, ours = $ours:tt), $($rest:tt)*) => {
        can_node!(@row $node [$($done)*
            // The derive joins the lines of a description with a space.
            /// Confirm operations for
            #[doc = $ours]
            /// received
            #[variable(vr = $confirmed, output, discrete, initial = exact, start = 0, depends = [])]
            pub confirmed: i32,
            /// Arbitration Lost operations for
            #[doc = $ours]
            /// received
            #[variable(vr = $lost, output, discrete, initial = exact, start = 0, depends = [])]
            pub arbitration_lost: i32,
        ] $($rest)*);
    };
    (@row $node:tt [$($done:tt)*] bus_errors_and_format_errors(vr = $bus:tt, $format:tt), $($rest:tt)*) => {
        can_node!(@row $node [$($done)*
            /// Bus Error operations received
            #[variable(vr = $bus, output, discrete, initial = exact, start = 0, depends = [])]
            pub bus_errors: i32,
            /// Received buffers refused as malformed (each answered with a Format Error operation)
            #[variable(vr = $format, output, discrete, initial = exact, start = 0, depends = [])]
            pub format_errors: i32,
        ] $($rest)*);
    };
    // A field as written (token trees, not a `ty` fragment: the derive reads the type's tokens).
    (@row $node:tt [$($done:tt)*] $(# $a:tt)* pub $field:ident : $ty:tt $(<$arg:tt>)?, $($rest:tt)*) => {
        can_node!(@row $node [$($done)* $(# $a)* pub $field: $ty $(<$arg>)?,] $($rest)*);
    };

    // Every row written: the struct, then `sent` after the fields (after the design parameters'
    // fields when there are design parameters).
    (@row { $network:tt $log:tt [$($attr:tt)*] $name:ident [$($which:ident { $($tail:tt)* })?] } [$($fields:tt)*]) => {
        can_node!(@struct [$($which)?]
            {
                $($($tail)*)?
                /// Tx_Data was read at the last Tx tick: it is emptied at the next event
                sent: bool,
            }
            $($attr)*
            #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
            #[fmu(
                fmi3_only,
                co_simulation_only,
                log_category(name = "logBus", description = $log),
                can_network(
                    name = "CAN",
                    description = $network,
                    rx_clock = rx_clock,
                    rx_data = rx_data,
                    tx_clock = tx_clock,
                    tx_data = tx_data,
                    bus_notifications = bus_notifications,
                )
            )]
            pub struct $name {
                /// Simulation time
                #[variable(vr = 0, independent, unit = "s")]
                pub time: f64,
                $($fields)*
            }
        );
        can_node!(@forget_sent $name);
    };
    (@struct [] { $($tail:tt)* } $(# $attr:tt)* pub struct $name:ident { $($fields:tt)* }) => {
        $(# $attr)* pub struct $name { $($fields)* $($tail)* }
    };
    (@struct [$which:ident] { $($tail:tt)* } $(# $attr:tt)* pub struct $name:ident { $($fields:tt)* }) => {
        with_design_parameters! { $which; $(# $attr)* pub struct $name { $($fields)* } { $($tail)* } }
    };
    (@forget_sent $name:ident) => {
        impl $name {
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
