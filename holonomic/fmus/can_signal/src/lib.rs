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

#[macro_use]
#[path = "../../can_signal_node.rs"]
mod can_signal_node;

pub use can_signal_node::{RX_MAX_SIZE, TX_MAX_SIZE};
use rustfmu::prelude::*;

can_signal_node! {
    /// One signal over a CAN bus: sent in frame tx_id every period, received from frame rx_id
    pub struct CanSignal;
    period:
        /// Send period: the interval of Tx_Clock
        #[variable(vr = 12, parameter, fixed, start = 0.01, unit = "s", min > 0.0)];
    tx_clock:
        /// Ticks every period (a countdown the node sets to period at each tick): its bus communication points for sending
        input, clock(countdown);
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
        self.forget_sent();
        if self.rx_clock.is_active() {
            self.receive(event);
        }
        if self.tx_clock.is_active() {
            self.send()?;
            self.tx_clock.set_interval(self.period);
        }
        Ok(())
    }
}

impl CoSimulation for CanSignal {}

rustfmu::export_fmi3!(CanSignal);
