//! The `CanBus` FMU (FMI 3.0, FMI-LS-BUS 1.0.0): a bus simulation FMU for up to four CAN network
//! FMUs. Each port is a network terminal (`can_network(..)`): the node's Tx_Data goes into the
//! port's Rx_Data at the node's Tx tick; the bus arbitrates the frames by identifier, keeps each on
//! the bus for its length in bits at its sender's baud rate (CAN's bit stream with its stuff bits,
//! [`rustfmu::ls_bus::bus::frame_bits`]), then delivers it to every other node and confirms it to
//! its sender through the ports' Tx_Data, at the ticks of their countdown Tx clocks, which the
//! model sets to the end of the frame on the bus. Losers wait (or get Arbitration Lost if their
//! node configured DISCARD_AND_NOTIFY); every `error_every`-th transmission is hit by a CRC error
//! (Bus Error to every node, the frame sent again). The bus itself is [`Bus`], plain Rust.
//!
//! `baud_rate` is every node's baud rate until it configures its own (a CAN Configuration
//! operation). `background_load` > 0 adds the rest of a vehicle's traffic: a frame of identifier
//! `background_id` (8 data bytes) every T, T chosen so that these frames alone keep the bus busy
//! that share of the time at `baud_rate`; they take part in the arbitration as any frame (with
//! the default identifier 0 they win it against every other) and are delivered to every port, whose
//! nodes take no frame of that identifier.

use rustfmu::ls_bus::bus::{Bus, frame_bits};
use rustfmu::ls_bus::{CanFrame, Operation, decode_all};
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// The bytes a port's Rx_Data and Tx_Data may hold (`maxSize`).
pub const MAX_SIZE: u32 = 4096;
/// Ports: network FMUs this bus connects.
pub const PORTS: usize = 4;
/// The bus's node that sends the background frames (after the ports).
const BACKGROUND: usize = PORTS;
/// The background frames' data.
const BACKGROUND_DATA: [u8; 8] = [0x55; 8];

/// A CAN bus simulation for four network FMUs (FMI-LS-BUS 1.0.0)
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(
    fmi3_only,
    co_simulation_only,
    bus_simulation,
    log_category(name = "logBus", description = "Refused buffers of the network FMUs"),
    can_network(
        name = "Node1",
        description = "The network FMU on port 1: its Tx into this Rx, this Tx into its Rx",
        rx_clock = rx_clock1,
        rx_data = rx_data1,
        tx_clock = tx_clock1,
        tx_data = tx_data1,
        bus_notifications = notifications1,
    ),
    can_network(
        name = "Node2",
        description = "The network FMU on port 2: its Tx into this Rx, this Tx into its Rx",
        rx_clock = rx_clock2,
        rx_data = rx_data2,
        tx_clock = tx_clock2,
        tx_data = tx_data2,
        bus_notifications = notifications2,
    ),
    can_network(
        name = "Node3",
        description = "The network FMU on port 3: its Tx into this Rx, this Tx into its Rx",
        rx_clock = rx_clock3,
        rx_data = rx_data3,
        tx_clock = tx_clock3,
        tx_data = tx_data3,
        bus_notifications = notifications3,
    ),
    can_network(
        name = "Node4",
        description = "The network FMU on port 4: its Tx into this Rx, this Tx into its Rx",
        rx_clock = rx_clock4,
        rx_data = rx_data4,
        tx_clock = tx_clock4,
        tx_data = tx_data4,
        bus_notifications = notifications4,
    ),
)]
pub struct CanBus {
    /// Simulation time
    #[variable(vr = 0, independent, unit = "s")]
    pub time: f64,
    /// Ticks when network FMU 1 sends (connect its Tx_Clock)
    #[variable(vr = 1012, name = "Node1.Rx_Clock", input, clock(triggered))]
    pub rx_clock1: Clock,
    /// The bus operations network FMU 1 sent (connect its Tx_Data)
    #[variable(vr = 1011, name = "Node1.Rx_Data", input, discrete, clocks = [rx_clock1], max_size = MAX_SIZE)]
    pub rx_data1: Vec<u8>,
    /// Ticks when the bus delivers to network FMU 1: at the end of a frame (countdown)
    #[variable(vr = 1014, name = "Node1.Tx_Clock", input, clock(countdown))]
    pub tx_clock1: Clock,
    /// The bus operations delivered to network FMU 1 (connect its Rx_Data)
    #[variable(vr = 1013, name = "Node1.Tx_Data", output, discrete, clocks = [tx_clock1], max_size = MAX_SIZE, depends = [])]
    pub tx_data1: Vec<u8>,
    /// This bus simulation provides Confirm, Arbitration Lost and Bus Error to network FMU 1
    #[variable(vr = 1015, name = "Node1.BusNotifications", output, constant, start = true)]
    pub notifications1: bool,
    /// Ticks when network FMU 2 sends (connect its Tx_Clock)
    #[variable(vr = 1022, name = "Node2.Rx_Clock", input, clock(triggered))]
    pub rx_clock2: Clock,
    /// The bus operations network FMU 2 sent (connect its Tx_Data)
    #[variable(vr = 1021, name = "Node2.Rx_Data", input, discrete, clocks = [rx_clock2], max_size = MAX_SIZE)]
    pub rx_data2: Vec<u8>,
    /// Ticks when the bus delivers to network FMU 2: at the end of a frame (countdown)
    #[variable(vr = 1024, name = "Node2.Tx_Clock", input, clock(countdown))]
    pub tx_clock2: Clock,
    /// The bus operations delivered to network FMU 2 (connect its Rx_Data)
    #[variable(vr = 1023, name = "Node2.Tx_Data", output, discrete, clocks = [tx_clock2], max_size = MAX_SIZE, depends = [])]
    pub tx_data2: Vec<u8>,
    /// This bus simulation provides Confirm, Arbitration Lost and Bus Error to network FMU 2
    #[variable(vr = 1025, name = "Node2.BusNotifications", output, constant, start = true)]
    pub notifications2: bool,
    /// Ticks when network FMU 3 sends (connect its Tx_Clock)
    #[variable(vr = 1032, name = "Node3.Rx_Clock", input, clock(triggered))]
    pub rx_clock3: Clock,
    /// The bus operations network FMU 3 sent (connect its Tx_Data)
    #[variable(vr = 1031, name = "Node3.Rx_Data", input, discrete, clocks = [rx_clock3], max_size = MAX_SIZE)]
    pub rx_data3: Vec<u8>,
    /// Ticks when the bus delivers to network FMU 3: at the end of a frame (countdown)
    #[variable(vr = 1034, name = "Node3.Tx_Clock", input, clock(countdown))]
    pub tx_clock3: Clock,
    /// The bus operations delivered to network FMU 3 (connect its Rx_Data)
    #[variable(vr = 1033, name = "Node3.Tx_Data", output, discrete, clocks = [tx_clock3], max_size = MAX_SIZE, depends = [])]
    pub tx_data3: Vec<u8>,
    /// This bus simulation provides Confirm, Arbitration Lost and Bus Error to network FMU 3
    #[variable(vr = 1035, name = "Node3.BusNotifications", output, constant, start = true)]
    pub notifications3: bool,
    /// Ticks when network FMU 4 sends (connect its Tx_Clock)
    #[variable(vr = 1042, name = "Node4.Rx_Clock", input, clock(triggered))]
    pub rx_clock4: Clock,
    /// The bus operations network FMU 4 sent (connect its Tx_Data)
    #[variable(vr = 1041, name = "Node4.Rx_Data", input, discrete, clocks = [rx_clock4], max_size = MAX_SIZE)]
    pub rx_data4: Vec<u8>,
    /// Ticks when the bus delivers to network FMU 4: at the end of a frame (countdown)
    #[variable(vr = 1044, name = "Node4.Tx_Clock", input, clock(countdown))]
    pub tx_clock4: Clock,
    /// The bus operations delivered to network FMU 4 (connect its Rx_Data)
    #[variable(vr = 1043, name = "Node4.Tx_Data", output, discrete, clocks = [tx_clock4], max_size = MAX_SIZE, depends = [])]
    pub tx_data4: Vec<u8>,
    /// This bus simulation provides Confirm, Arbitration Lost and Bus Error to network FMU 4
    #[variable(vr = 1045, name = "Node4.BusNotifications", output, constant, start = true)]
    pub notifications4: bool,
    /// Every error_every-th transmission is hit by a CRC error (0: none)
    #[variable(vr = 100, parameter, fixed, start = 0, min = 0)]
    pub error_every: i32,
    /// Baud rate [bit/s] of every node that does not configure its own
    #[variable(vr = 101, parameter, fixed, start = 500000, min = 1)]
    pub baud_rate: i32,
    /// Share of the bus's time taken by background frames of identifier background_id (0: none)
    #[variable(vr = 102, parameter, fixed, start = 0.0, min = 0.0, max = 0.95)]
    pub background_load: f64,
    /// Identifier of the background frames (standard, 11 bits; 0 wins every arbitration)
    #[variable(vr = 103, parameter, fixed, start = 0, min = 0, max = 0x7FF)]
    pub background_id: i32,
    /// Share of the time the bus was busy, since the start
    #[variable(vr = 110, output, discrete, initial = exact, start = 0.0, depends = [])]
    pub bus_load: f64,
    /// Frames delivered
    #[variable(vr = 111, output, discrete, initial = exact, start = 0, depends = [])]
    pub frames_delivered: i32,
    /// Transmissions hit by an injected bus error
    #[variable(vr = 112, output, discrete, initial = exact, start = 0, depends = [])]
    pub bus_errors: i32,
    /// Arbitration Lost operations sent
    #[variable(vr = 113, output, discrete, initial = exact, start = 0, depends = [])]
    pub arbitration_losses: i32,
    /// The bus (its queue, the frame on it, what each node is to receive)
    bus: Bus,
    /// Which ports' Tx_Data were read at the last delivery: emptied at the next event
    sent: [bool; PORTS],
    /// The start time (for the bus load)
    start: f64,
    /// When the next background frame is queued, and the time between two (0: none)
    next_background: f64,
    background_period: f64,
}

impl CanBus {
    fn rx(&mut self, k: usize) -> (&Clock, &[u8]) {
        match k {
            0 => (&self.rx_clock1, &self.rx_data1),
            1 => (&self.rx_clock2, &self.rx_data2),
            2 => (&self.rx_clock3, &self.rx_data3),
            _ => (&self.rx_clock4, &self.rx_data4),
        }
    }

    fn background_frame(&self) -> Operation<'static> {
        Operation::CanTransmit(CanFrame {
            id: self.background_id as u32,
            ide: false,
            rtr: false,
            data: &BACKGROUND_DATA,
        })
    }

    fn tx(&mut self, k: usize) -> (&mut Clock, &mut Vec<u8>) {
        match k {
            0 => (&mut self.tx_clock1, &mut self.tx_data1),
            1 => (&mut self.tx_clock2, &mut self.tx_data2),
            2 => (&mut self.tx_clock3, &mut self.tx_data3),
            _ => (&mut self.tx_clock4, &mut self.tx_data4),
        }
    }
}

impl Model for CanBus {
    fn initialize(&mut self, ctx: &Context) -> Result<(), String> {
        self.bus = Bus::new(PORTS + 1, MAX_SIZE as usize);
        self.bus.error_every =
            u64::try_from(self.error_every).map_err(|_| format!("error_every = {} < 0", self.error_every))?;
        let baud = u32::try_from(self.baud_rate).map_err(|_| format!("baud_rate = {} < 1", self.baud_rate))?;
        for n in 0..=PORTS {
            self.bus.node_mut(n).can_baudrate = baud;
        }
        self.start = ctx.start_time();
        self.background_period = if self.background_load > 0.0 {
            let (bits, _) = frame_bits(&self.background_frame()).expect("a Transmit");
            f64::from(bits) / f64::from(baud) / self.background_load
        } else {
            0.0
        };
        self.next_background = self.start + self.background_period;
        if self.background_period > 0.0 {
            // The first background frame: the bus's first communication point.
            let first = self.background_period;
            for k in 0..PORTS {
                self.tx(k).0.set_interval(first);
            }
        }
        Ok(())
    }

    fn update(&mut self, event: &mut Event) -> Result<(), String> {
        let t = event.time();
        for k in 0..PORTS {
            if self.sent[k] {
                self.tx(k).1.clear();
                self.sent[k] = false;
            }
        }
        // Frames that ended by now are delivered (into the outboxes), then what the nodes sent.
        self.bus.advance(t);
        if self.background_period > 0.0 {
            while self.next_background <= t + 1e-12 * t.abs().max(1.0) {
                self.bus.enqueue(BACKGROUND, &[self.background_frame()]);
                self.next_background += self.background_period;
            }
        }
        // What the bus delivers to the background node goes nowhere.
        self.bus.clear_outbox(BACKGROUND);
        for k in 0..PORTS {
            let (clock, data) = self.rx(k);
            if !clock.is_active() {
                continue;
            }
            let data = data.to_vec();
            match decode_all(&data) {
                Ok(ops) => self.bus.enqueue(k, &ops),
                Err(e) => {
                    event.context().log(
                        "logBus",
                        &format!("Node{}.Rx_Data refused, nothing of it applied: {e}", k + 1),
                    );
                    let n = e.bytes.len().min(MAX_SIZE as usize - 10);
                    self.bus.post(k, &Operation::FormatError { data: &e.bytes[..n] });
                }
            }
        }
        // The frames of this instant meet in one arbitration (whichever port's came first).
        self.bus.arbitrate(t);
        // The ports whose clock ticks now get their operations.
        for k in 0..PORTS {
            let outbox = self.bus.outbox(k).to_vec();
            let (clock, data) = self.tx(k);
            if clock.is_active() {
                *data = outbox;
                self.bus.clear_outbox(k);
                self.sent[k] = true;
            }
        }
        // The next delivery: the end of the frame on the bus, or (replies waiting, the bus idle)
        // one bit time at the default 500 kbit/s from now.
        let mut next = match (self.bus.next_event(), self.bus.has_mail()) {
            (Some(end), _) => Some(end),
            (None, true) => Some(t + 2e-6),
            (None, false) => None,
        };
        if self.background_period > 0.0 {
            next = Some(next.map_or(self.next_background, |at| at.min(self.next_background)));
        }
        if let Some(at) = next {
            let dt = (at - t).max(1e-9);
            for k in 0..PORTS {
                self.tx(k).0.set_interval(dt);
            }
        }
        self.frames_delivered = self.bus.delivered as i32;
        self.bus_errors = self.bus.bus_errors as i32;
        self.arbitration_losses = self.bus.arbitration_lost as i32;
        self.bus_load = if t > self.start {
            (self.bus.busy / (t - self.start)).min(1.0)
        } else {
            0.0
        };
        Ok(())
    }
}

impl CoSimulation for CanBus {}

rustfmu::export_fmi3!(CanBus);
