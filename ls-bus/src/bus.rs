//! A CAN bus as a bus simulation sees it (FMI-LS-BUS 1.0.0, "Transmission and Acknowledge",
//! "Arbitration", "Error Handling", "Configuration of Bus Simulation"): frames queued by the
//! network nodes, arbitrated by identifier, on the bus for their length in bits at the baud rate,
//! then delivered to the other nodes and confirmed to their sender; Arbitration Lost to the losers
//! that asked for it; injected bus errors (the frame is sent again, as CAN does); Bus-Off nodes
//! neither send nor receive. Plain Rust, no FMI: the `CanBus` FMU (holonomic/fmus/can_bus) moves
//! its operations in and out of Binary variables and its clocks.
//!
//! A frame's length ([`frame_bits`]) is CAN's own for classic frames: the bit stream from start of
//! frame to the end of the CRC built (identifier, control field, data, CRC-15 of ISO 11898-1),
//! stuffed (a bit of opposite value after five equal ones), then CRC delimiter, ACK slot and
//! delimiter, end of frame and intermission (13 bits). CAN FD and CAN XL frames: the unstuffed
//! fields of ISO 11898-1:2015 / CiA 610-1 with the worst-case dynamic stuffing bound, their data
//! phase at the data baud rate when the frame switches (BRS; CAN XL always).

use crate::{
    ArbitrationLostBehavior, CanFdFrame, CanFrame, CanXlFrame, Configuration, ErrorCode, ErrorFlag, Operation, Status,
    push_into,
};

/// The CRC-15 of classic CAN (ISO 11898-1: x^15 + x^14 + x^10 + x^8 + x^7 + x^4 + x^3 + 1).
const CRC15_POLY: u16 = 0x4599;

fn push_bits(bits: &mut Vec<bool>, value: u32, n: u32) {
    for i in (0..n).rev() {
        bits.push((value >> i) & 1 == 1);
    }
}

/// The stuff bits CAN inserts into `bits`: after five consecutive bits of equal value, one of the
/// opposite value (which starts the next run).
pub fn stuff_bits(bits: &[bool]) -> u32 {
    let (mut stuffed, mut run, mut last) = (0, 0, None);
    for &b in bits {
        if Some(b) == last {
            run += 1;
        } else {
            run = 1;
            last = Some(b);
        }
        if run == 5 {
            stuffed += 1;
            last = Some(!b);
            run = 1;
        }
    }
    stuffed
}

/// The bits of a classic CAN data or remote frame from start of frame to the last CRC bit,
/// unstuffed: what the CRC and the stuffing are computed over.
pub fn classic_bits(f: &CanFrame<'_>) -> Vec<bool> {
    let mut bits = vec![false]; // start of frame (dominant)
    let dlc = f.data.len() as u32;
    if f.ide {
        push_bits(&mut bits, f.id >> 18, 11); // base identifier
        bits.push(true); // SRR
        bits.push(true); // IDE
        push_bits(&mut bits, f.id & 0x3_FFFF, 18); // identifier extension
        bits.push(f.rtr); // RTR
        bits.extend([false, false]); // r1, r0
    } else {
        push_bits(&mut bits, f.id, 11);
        bits.push(f.rtr); // RTR
        bits.extend([false, false]); // IDE, r0
    }
    push_bits(&mut bits, dlc, 4);
    if !f.rtr {
        for b in f.data {
            push_bits(&mut bits, u32::from(*b), 8);
        }
    }
    let mut crc: u16 = 0;
    for &b in &bits {
        let next = b ^ ((crc >> 14) & 1 == 1);
        crc = (crc << 1) & 0x7FFF;
        if next {
            crc ^= CRC15_POLY;
        }
    }
    push_bits(&mut bits, u32::from(crc), 15);
    bits
}

/// CRC delimiter, ACK slot, ACK delimiter, end of frame (7), intermission (3).
const TRAILER_BITS: u32 = 13;

/// Bits on the bus of a frame: (at the nominal rate, at the data rate). A classic frame's are
/// exact (its stuff bits counted); CAN FD's and CAN XL's take the worst-case dynamic stuffing.
pub fn frame_bits(op: &Operation<'_>) -> Option<(u32, u32)> {
    Some(match op {
        Operation::CanTransmit(f) => {
            let bits = classic_bits(f);
            (bits.len() as u32 + stuff_bits(&bits) + TRAILER_BITS, 0)
        }
        Operation::CanFdTransmit(CanFdFrame { ide, brs, data, .. }) => {
            // Arbitration phase: SOF, identifier (11, or 11 + SRR + IDE + 18), RRS, IDE, FDF,
            // res, BRS; data phase: ESI, DLC, data, stuff count (4), CRC (17 up to 16 bytes, else
            // 21) with its fixed stuff bits (one per 4 bits + 1), CRC delimiter.
            let arbitration = if *ide {
                1 + 11 + 2 + 18 + 1 + 3
            } else {
                1 + 11 + 1 + 1 + 3
            };
            let dynamic = 1 + 4 + 8 * data.len() as u32;
            let crc = if data.len() <= 16 { 17 } else { 21 };
            let data_phase = dynamic + (arbitration + dynamic - 1) / 4 + 4 + crc + crc.div_ceil(4) + 1;
            // ACK slot and delimiter, EOF, intermission at the nominal rate.
            if *brs {
                (arbitration + 2 + 7 + 3, data_phase)
            } else {
                (arbitration + data_phase + 2 + 7 + 3, 0)
            }
        }
        Operation::CanXlTransmit(CanXlFrame { data, .. }) => {
            // Arbitration phase: SOF, priority identifier (11), RRS, IDE, FDF, XLF, resXL, ADH
            // (and the data phase from DH1 on, always switched): SDT (8), SEC, DLC (11), SBC (3),
            // PCRC (13), VCID (8), AF (32), data, FCRC (32), FCP (4), then DAH, AH1, ADS back at
            // the nominal rate with the ACK field, EOF and intermission.
            let arbitration = 1 + 11 + 6;
            let fields = 8 + 1 + 11 + 3 + 13 + 8 + 32 + 8 * data.len() as u32 + 32 + 4;
            // Fixed stuff bits every 10 bits in the data phase (CiA 610-1).
            let data_phase = fields + fields / 10;
            (arbitration + arbitration / 4 + 3 + 2 + 7 + 3, data_phase)
        }
        _ => return None,
    })
}

/// What a node has told the bus simulation (Configuration and Status operations); the defaults
/// are the bus simulation's own ("the Bus Simulation shall choose a default behavior by itself").
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct NodeConfig {
    /// CAN (nominal) baud rate, bit/s.
    pub can_baudrate: u32,
    /// CAN FD data phase baud rate, bit/s.
    pub fd_baudrate: u32,
    /// CAN XL data phase baud rate, bit/s.
    pub xl_baudrate: u32,
    pub arbitration_lost: ArbitrationLostBehavior,
    pub status: Status,
}

impl NodeConfig {
    /// 500 kbit/s nominal, 2 Mbit/s CAN FD, 10 Mbit/s CAN XL; buffered retransmission; error active.
    pub const DEFAULT: NodeConfig = NodeConfig {
        can_baudrate: 500_000,
        fd_baudrate: 2_000_000,
        xl_baudrate: 10_000_000,
        arbitration_lost: ArbitrationLostBehavior::BufferAndRetransmit,
        status: Status::ErrorActive,
    };
}

/// A frame waiting for the bus: its sender, its Transmit operation's bytes, its identifier.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
struct Pending {
    node: usize,
    bytes: Vec<u8>,
    id: u32,
    /// Order of arrival: among equal identifiers, the first queued goes first.
    seq: u64,
}

/// The frame on the bus.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
struct OnBus {
    frame: Pending,
    end: f64,
}

/// The bus: its nodes, the frames waiting, the one being sent, and what each node is to receive.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Bus {
    nodes: Vec<NodeConfig>,
    waiting: Vec<Pending>,
    on_bus: Option<OnBus>,
    seq: u64,
    /// Every `error_every`-th transmission hits a CRC error (0: none).
    pub error_every: u64,
    transmissions: u64,
    outbox: Vec<Vec<u8>>,
    capacity: usize,
    /// Frames delivered, bus errors, arbitration losses notified, operations dropped (a full outbox).
    pub delivered: u64,
    pub bus_errors: u64,
    pub arbitration_lost: u64,
    pub dropped: u64,
    /// Seconds the bus was busy (for the bus load).
    pub busy: f64,
}

impl Default for Bus {
    /// A bus without nodes (a model's start value, before it knows its ports).
    fn default() -> Self {
        Bus::new(0, 0)
    }
}

impl Bus {
    /// A bus of `nodes` nodes, each receiving at most `capacity` bytes per delivery (the Rx_Data
    /// variable's size).
    pub fn new(nodes: usize, capacity: usize) -> Self {
        Bus {
            nodes: vec![NodeConfig::DEFAULT; nodes],
            waiting: Vec::new(),
            on_bus: None,
            seq: 0,
            error_every: 0,
            transmissions: 0,
            outbox: vec![Vec::new(); nodes],
            capacity,
            delivered: 0,
            bus_errors: 0,
            arbitration_lost: 0,
            dropped: 0,
            busy: 0.0,
        }
    }

    /// What node `n` has configured.
    pub fn node(&self, n: usize) -> &NodeConfig {
        &self.nodes[n]
    }

    /// What node `n` has configured, to change (a bus simulation's own defaults, e.g. its baud
    /// rate, before the nodes configure anything).
    pub fn node_mut(&mut self, n: usize) -> &mut NodeConfig {
        &mut self.nodes[n]
    }

    fn send(&mut self, to: usize, op: &Operation<'_>) {
        if push_into(&mut self.outbox[to], self.capacity, op).is_err() {
            self.dropped += 1;
        }
    }

    /// The operations node `from` sent at time `t` (its Tx_Data, read): Transmits queue, a
    /// Configuration or Status changes the node, a Wake Up goes to every other node; the bus
    /// then starts the next frame if it is idle.
    pub fn receive(&mut self, from: usize, t: f64, ops: &[Operation<'_>]) {
        self.enqueue(from, ops);
        self.start(t);
    }

    /// As [`receive`](Self::receive), without starting a frame: for the operations of several
    /// nodes at one instant, so that their frames meet in one arbitration
    /// ([`arbitrate`](Self::arbitrate) after the last).
    pub fn enqueue(&mut self, from: usize, ops: &[Operation<'_>]) {
        for op in ops {
            match op {
                Operation::CanTransmit(CanFrame { id, .. })
                | Operation::CanFdTransmit(CanFdFrame { id, .. })
                | Operation::CanXlTransmit(CanXlFrame { id, .. }) => {
                    // "the specified Network FMU shall not provide any new Transmission
                    // operations" in Bus-Off; one that does is not put on the bus.
                    if self.nodes[from].status == Status::BusOff {
                        self.dropped += 1;
                        continue;
                    }
                    let mut bytes = Vec::new();
                    push_into(&mut bytes, usize::MAX, op).expect("a decoded operation is valid");
                    self.seq += 1;
                    self.waiting.push(Pending {
                        node: from,
                        bytes,
                        id: *id,
                        seq: self.seq,
                    });
                }
                Operation::Configuration(c) => {
                    let n = &mut self.nodes[from];
                    match *c {
                        Configuration::CanBaudrate(b) if b > 0 => n.can_baudrate = b,
                        Configuration::CanFdBaudrate(b) if b > 0 => n.fd_baudrate = b,
                        Configuration::CanXlBaudrate(b) if b > 0 => n.xl_baudrate = b,
                        Configuration::ArbitrationLostBehavior(a) => n.arbitration_lost = a,
                        _ => self.dropped += 1,
                    }
                }
                Operation::Status(s) => self.nodes[from].status = *s,
                Operation::Wakeup => {
                    for to in (0..self.nodes.len()).filter(|&to| to != from) {
                        self.send(to, &Operation::Wakeup);
                    }
                }
                _ => {}
            }
        }
    }

    /// If the bus is idle at time `t` and frames wait: the arbitration, the winner on the bus
    /// from `t`.
    pub fn arbitrate(&mut self, t: f64) {
        self.start(t);
    }

    /// Seconds the frame takes at its sender's baud rates.
    fn duration(&self, p: &Pending) -> f64 {
        let op = crate::decode_all(&p.bytes).expect("queued bytes are one valid operation")[0];
        let (nominal, data) = frame_bits(&op).expect("a Transmit");
        let c = &self.nodes[p.node];
        let data_rate = match op {
            Operation::CanXlTransmit(_) => c.xl_baudrate,
            _ => c.fd_baudrate,
        };
        f64::from(nominal) / f64::from(c.can_baudrate) + f64::from(data) / f64::from(data_rate)
    }

    /// If the bus is idle and frames wait: arbitration. The winner is the lowest identifier
    /// (error-active nodes before error-passive ones: "the Bus Simulation shall prefer Network
    /// FMUs whose status is ERROR_ACTIVE"); a loser whose node asked DISCARD_AND_NOTIFY is
    /// dropped with an Arbitration Lost, the others stay queued (BUFFER_AND_RETRANSMIT).
    fn start(&mut self, t: f64) {
        if self.on_bus.is_some() || self.waiting.is_empty() {
            return;
        }
        let key = |p: &Pending, nodes: &[NodeConfig]| (nodes[p.node].status != Status::ErrorActive, p.id, p.seq);
        let winner = (0..self.waiting.len())
            .min_by_key(|&i| key(&self.waiting[i], &self.nodes))
            .expect("not empty");
        let frame = self.waiting.remove(winner);
        let mut i = 0;
        while i < self.waiting.len() {
            let loser = &self.waiting[i];
            if self.nodes[loser.node].arbitration_lost == ArbitrationLostBehavior::DiscardAndNotify {
                let (to, id) = (loser.node, loser.id);
                self.waiting.remove(i);
                self.arbitration_lost += 1;
                self.send(to, &Operation::ArbitrationLost { id });
            } else {
                i += 1;
            }
        }
        let d = self.duration(&frame);
        self.busy += d;
        self.on_bus = Some(OnBus { frame, end: t + d });
    }

    /// When the frame on the bus ends: the next time the bus delivers something.
    pub fn next_event(&self) -> Option<f64> {
        self.on_bus.as_ref().map(|b| b.end)
    }

    /// Runs the bus to time `t`: every frame that ends by `t` (to a relative 1e-12 of it) is
    /// delivered, or hit by an injected error; the next one starts where it ended.
    pub fn advance(&mut self, t: f64) {
        while let Some(b) = &self.on_bus {
            if b.end > t + 1e-12 * t.abs().max(1.0) {
                return;
            }
            let OnBus { frame, end } = self.on_bus.take().expect("some");
            self.transmissions += 1;
            let others: Vec<usize> = (0..self.nodes.len())
                .filter(|&n| n != frame.node && self.nodes[n].status != Status::BusOff)
                .collect();
            if self.error_every > 0 && self.transmissions.is_multiple_of(self.error_every) {
                // A CRC error: the first receiver detects it (primary), the others and the sender
                // follow its error flag (secondary); CAN sends the frame again.
                self.bus_errors += 1;
                for (k, &n) in others.iter().enumerate() {
                    let flag = if k == 0 {
                        ErrorFlag::Primary
                    } else {
                        ErrorFlag::Secondary
                    };
                    let op = Operation::BusError {
                        id: frame.id,
                        error_code: ErrorCode::CrcError,
                        error_flag: flag,
                        is_sender: false,
                    };
                    self.send(n, &op);
                }
                let op = Operation::BusError {
                    id: frame.id,
                    error_code: ErrorCode::CrcError,
                    error_flag: ErrorFlag::Secondary,
                    is_sender: true,
                };
                self.send(frame.node, &op);
                if self.nodes[frame.node].status != Status::BusOff {
                    self.waiting.push(frame);
                }
            } else {
                let op = crate::decode_all(&frame.bytes).expect("valid")[0];
                for &n in &others {
                    self.send(n, &op);
                }
                self.delivered += 1;
                // No confirmation when every other node is Bus-Off (or there is none).
                if !others.is_empty() {
                    self.send(frame.node, &Operation::Confirm { id: frame.id });
                }
            }
            self.start(end);
        }
    }

    /// Puts `op` in node `n`'s outbox (a bus simulation's own reply, e.g. a Format Error).
    pub fn post(&mut self, n: usize, op: &Operation<'_>) {
        self.send(n, op);
    }

    /// Whether some node has operations waiting for its next delivery.
    pub fn has_mail(&self) -> bool {
        self.outbox.iter().any(|o| !o.is_empty())
    }

    /// The operations waiting for node `n` (its Rx_Data at its next delivery).
    pub fn outbox(&self, n: usize) -> &[u8] {
        &self.outbox[n]
    }

    /// Empties node `n`'s outbox after the importer has read it.
    pub fn clear_outbox(&mut self, n: usize) {
        self.outbox[n].clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decode_all;

    fn transmit(id: u32, data: &[u8]) -> Operation<'_> {
        Operation::CanTransmit(CanFrame {
            id,
            ide: false,
            rtr: false,
            data,
        })
    }

    #[test]
    fn a_classic_frame_has_the_bits_can_defines() {
        // Unstuffed: 44 + 8n bits (SOF .. CRC delimiter .. EOF), + 3 intermission.
        for n in 0..=8 {
            let data = vec![0x55u8; n]; // alternating bits: no stuffing in the data
            let f = CanFrame {
                id: 0x2AA,
                ide: false,
                rtr: false,
                data: &data,
            };
            let bits = classic_bits(&f);
            assert_eq!(bits.len() as u32 + TRAILER_BITS, 44 + 8 * n as u32 + 3);
            // The worst case bound of the literature: floor((34 + 8n - 1) / 4) stuff bits.
            let stuffed = stuff_bits(&bits);
            assert!(stuffed <= (34 + 8 * n as u32 - 1) / 4, "{n}: {stuffed}");
        }
        // Extended: 29-bit identifier, SRR, IDE, r1: 20 bits more.
        let f = CanFrame {
            id: 0x1555_5555,
            ide: true,
            rtr: false,
            data: &[],
        };
        assert_eq!(classic_bits(&f).len(), 34 + 20);
        // Eight zero bytes after identifier 0: long runs of dominant bits, many stuff bits.
        let zeros = CanFrame {
            id: 0,
            ide: false,
            rtr: false,
            data: &[0; 8],
        };
        let (bits, _) = frame_bits(&Operation::CanTransmit(zeros)).unwrap();
        assert!(bits > 111 + 15 && bits <= 135, "{bits}");
    }

    #[test]
    fn stuffing_inserts_a_bit_after_five_equal_ones_which_starts_the_next_run() {
        let b = |s: &str| s.chars().map(|c| c == '1').collect::<Vec<_>>();
        assert_eq!(stuff_bits(&b("11110")), 0);
        assert_eq!(stuff_bits(&b("11111")), 1);
        assert_eq!(stuff_bits(&b("1111100000")), 2); // 11111 [0] 0000 [1] 0: the stuffed 0 counts in the run
        assert_eq!(stuff_bits(&b("0000000000")), 2);
    }

    #[test]
    fn the_lowest_identifier_wins_and_is_delivered_after_its_length_at_the_baud_rate() {
        let mut bus = Bus::new(3, 256);
        bus.receive(0, 0.0, &[transmit(0x200, &[1; 8]), transmit(0x100, &[2; 8])]);
        // 0x100 won: on the bus from 0 for its bits at 500 kbit/s.
        let (bits, _) = frame_bits(&transmit(0x100, &[2; 8])).unwrap();
        let end = f64::from(bits) / 500_000.0;
        assert_eq!(bus.next_event(), Some(end));
        bus.advance(end);
        let to1 = decode_all(bus.outbox(1)).unwrap();
        assert_eq!(to1, [transmit(0x100, &[2; 8])]);
        assert_eq!(decode_all(bus.outbox(0)).unwrap(), [Operation::Confirm { id: 0x100 }]);
        // The loser (buffered, the default) goes next, right after.
        let (bits2, _) = frame_bits(&transmit(0x200, &[1; 8])).unwrap();
        assert!((bus.next_event().unwrap() - (end + f64::from(bits2) / 500_000.0)).abs() < 1e-15);
    }

    #[test]
    fn frames_enqueued_at_one_instant_meet_in_one_arbitration_whoever_came_first() {
        let mut bus = Bus::new(2, 256);
        bus.enqueue(0, &[transmit(0x300, &[1])]);
        bus.enqueue(1, &[transmit(0x010, &[2])]);
        assert_eq!(bus.next_event(), None, "nothing on the bus before the arbitration");
        bus.arbitrate(0.0);
        let (bits, _) = frame_bits(&transmit(0x010, &[2])).unwrap();
        assert_eq!(
            bus.next_event(),
            Some(f64::from(bits) / 500_000.0),
            "the lower identifier first"
        );
    }

    #[test]
    fn discard_and_notify_losers_get_arbitration_lost_and_error_passive_nodes_yield() {
        let discard = Operation::Configuration(Configuration::ArbitrationLostBehavior(
            ArbitrationLostBehavior::DiscardAndNotify,
        ));
        // Three frames contend at t = 0: node 2 (error passive) has the lowest identifier but
        // yields to node 0; node 1 loses and asked to be told.
        let mut b = Bus::new(3, 256);
        b.receive(1, 0.0, &[discard]);
        b.receive(2, 0.0, &[Operation::Status(Status::ErrorPassive)]);
        b.waiting.push(Pending {
            node: 2,
            bytes: bytes(&transmit(0x010, &[])),
            id: 0x010,
            seq: 1,
        });
        b.waiting.push(Pending {
            node: 1,
            bytes: bytes(&transmit(0x040, &[])),
            id: 0x040,
            seq: 2,
        });
        b.waiting.push(Pending {
            node: 0,
            bytes: bytes(&transmit(0x030, &[])),
            id: 0x030,
            seq: 3,
        });
        b.start(0.0);
        assert_eq!(
            b.on_bus.as_ref().unwrap().frame.node,
            0,
            "the error-active node with the lowest identifier"
        );
        assert_eq!(
            decode_all(b.outbox(1)).unwrap(),
            [Operation::ArbitrationLost { id: 0x040 }]
        );
        assert_eq!(b.waiting.len(), 1, "node 2's frame stays buffered");
    }

    fn bytes(op: &Operation<'_>) -> Vec<u8> {
        let mut v = Vec::new();
        push_into(&mut v, 1 << 20, op).unwrap();
        v
    }

    #[test]
    fn an_injected_error_reaches_every_node_once_as_primary_and_the_frame_is_sent_again() {
        let mut bus = Bus::new(3, 256);
        bus.error_every = 1;
        bus.receive(0, 0.0, &[transmit(0x100, &[7])]);
        let end = bus.next_event().unwrap();
        bus.advance(end);
        let errors: Vec<_> = (0..3).map(|n| decode_all(bus.outbox(n)).unwrap()).collect();
        assert_eq!(
            errors[0],
            [Operation::BusError {
                id: 0x100,
                error_code: ErrorCode::CrcError,
                error_flag: ErrorFlag::Secondary,
                is_sender: true
            }]
        );
        assert!(matches!(
            errors[1][0],
            Operation::BusError {
                error_flag: ErrorFlag::Primary,
                is_sender: false,
                ..
            }
        ));
        assert!(matches!(
            errors[2][0],
            Operation::BusError {
                error_flag: ErrorFlag::Secondary,
                is_sender: false,
                ..
            }
        ));
        assert_eq!((bus.bus_errors, bus.delivered), (1, 0));
        assert!(bus.next_event().unwrap() > end, "sent again");
    }

    #[test]
    fn bus_off_nodes_neither_send_nor_receive_and_a_lone_sender_gets_no_confirm() {
        let mut bus = Bus::new(2, 256);
        bus.receive(1, 0.0, &[Operation::Status(Status::BusOff), transmit(0x300, &[])]);
        assert_eq!((bus.next_event(), bus.dropped), (None, 1));
        bus.receive(0, 0.0, &[transmit(0x100, &[])]);
        bus.advance(1.0);
        assert!(
            bus.outbox(1).is_empty() && bus.outbox(0).is_empty(),
            "no receiver, no confirm"
        );
        assert_eq!(bus.delivered, 1);
    }

    #[test]
    fn a_wake_up_goes_to_every_other_node() {
        let mut bus = Bus::new(3, 256);
        bus.receive(1, 0.0, &[Operation::Wakeup]);
        assert!(bus.outbox(1).is_empty());
        for n in [0, 2] {
            assert_eq!(decode_all(bus.outbox(n)).unwrap(), [Operation::Wakeup]);
        }
    }
}
