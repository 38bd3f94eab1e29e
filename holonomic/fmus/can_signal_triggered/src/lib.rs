//! The `CanSignalTriggered` FMU (FMI 3.0, FMI-LS-BUS 1.0.0): the `CanSignal` node (one signal
//! over a CAN bus: `u` sent in frame `tx_id` every `period`, `y` from the frames `rx_id`; the same
//! variables, value references and Format Error replies) with a **triggered output** Tx clock
//! instead of a countdown input clock. The node keeps its own send times as time events: at each
//! one, which ends the importer's step with `eventHandlingNeeded`, it ticks `CAN.Tx_Clock` in the
//! importer's Event Mode and Tx_Data holds the frame.
//!
//! Why a second node: FMI-LS-BUS 1.0.0 lets a network FMU choose its Tx clock (Low Cut, Tx
//! Clocks: time-based or triggered), and importers differ in what they connect. FMU Manipulation
//! Toolbox 2.0's containers activate a bus simulation's Rx_Clock only from a triggered output
//! clock: linked to a time-based Tx_Clock (CanSignal's), the bus simulation receives nothing
//! (`container/builder.py`: an input-clock link "will be fed directly by importer" when its
//! target is a bus simulation FMU). The standard allows that connection ("it is allowed to connect
//! both, since a time-based Clock of an FMU is considered only to be a request to the importer to
//! provide a corresponding Clock source", Time-based Tx Clocks).
//!
//! A triggered Tx_Clock "must only be set when returning from fmi3DoStep with the earlyReturn
//! argument set to fmi3False" (FMI-LS-BUS 1.0.0, Triggered Tx Clocks): the bus communication
//! points are the importer's communication points. A send time at a communication point ticks
//! there; one strictly inside a step (an importer whose grid moved) is signalled at the end of
//! that step ("Pending Tx data shall be signaled by returning from fmi3DoStep with the
//! eventHandlingNeeded arguments set to fmi3True"), the next send still a period after it.

#[macro_use]
#[path = "../../can_signal_node.rs"]
mod can_signal_node;

pub use can_signal_node::{RX_MAX_SIZE, TX_MAX_SIZE};
use rustfmu::prelude::*;

can_signal_node! {
    /// One signal over a CAN bus, the node ticking its Tx clock itself: sent in frame tx_id every period, received from frame rx_id
    pub struct CanSignalTriggered;
    period:
        /// Send period: the time between the node's time events, each a tick of Tx_Clock (a multiple of the importer's step)
        #[variable(vr = 12, parameter, fixed, start = 0.01, unit = "s", min > 0.0)];
    tx_clock:
        /// Ticks every period, at the node's time events (the first one period after the start): its bus communication points for sending
        output, clock(triggered);
}

impl Model for CanSignalTriggered {
    fn update(&mut self, event: &mut Event) -> Result<(), String> {
        self.forget_sent();
        if event.initial() {
            // The first send one period after the start, as CanSignal's countdown.
            event.schedule(event.time() + self.period);
        }
        if self.rx_clock.is_active() {
            self.receive(event);
        }
        if event.time_event() {
            self.send()?;
            self.tx_clock.tick();
            // From the time the event was scheduled for, not the importer's (t += h drifts).
            event.schedule(event.time() + self.period);
        }
        Ok(())
    }
}

impl CoSimulation for CanSignalTriggered {}

rustfmu::export_fmi3!(CanSignalTriggered);
