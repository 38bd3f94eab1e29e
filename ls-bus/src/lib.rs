//! FMI-LS-BUS 1.0.0 bus operations for CAN, CAN FD and CAN XL (the Low Cut of the layered
//! standard's chapter "CAN, CAN FD, CAN XL"), as typed Rust values.
//!
//! A network FMU exchanges *bus operations* through FMI 3.0 Binary variables (`Tx_Data`,
//! `Rx_Data`): one buffer holds any number of operations one after the other, each
//! `OP Code (4 bytes) | Length (4 bytes, the whole operation) | arguments`, every number
//! little-endian ("Numbers shall be transmitted with little-endian byte order", FMI-LS-BUS 1.0.0,
//! Layered Standard Bus Protocol). What a model sees is [`Operation`]: "transmit this frame",
//! "this frame was confirmed", "arbitration lost", never raw bytes.
//!
//! - Writing: [`TxBuffer::push`] checks an operation against the standard (booleans, identifier
//!   range, data length of the CAN format, enumerations) and appends its bytes if it fits the
//!   buffer's capacity (the Binary variable's `maxSize`); otherwise nothing is written.
//! - Reading: [`operations`] walks a received buffer operation by operation; [`decode_all`] reads
//!   a whole buffer or refuses it whole, with the offset and the rule broken ([`FormatError`]),
//!   so that an FMU applies nothing of a buffer with one malformed operation (and can answer with
//!   the standard's Format Error operation carrying the offending bytes, [`FormatError::bytes`]).
//!
//! The layout is the one of the standard's C headers `fmi3LsBus.h` and `fmi3LsBusCan.h`
//! (`#pragma pack(1)` structs, OP codes, argument sizes): `tests/c_headers.rs` compiles the
//! headers' own macros (`fmi3LsBusUtilCan.h`) and compares their bytes with ours, both ways, for
//! every operation. Written by hand rather than with a serialization crate: the format is a few
//! fixed little-endian fields per operation, and the refusals must name the standard's rules.

use std::fmt;

pub mod bus;

/// The OP codes of FMI-LS-BUS 1.0.0 (`fmi3LsBus.h`, `fmi3LsBusCan.h`).
pub mod op_code {
    /// Format Error (common to every bus type).
    pub const FORMAT_ERROR: u32 = 0x0001;
    /// CAN Transmit.
    pub const CAN_TRANSMIT: u32 = 0x0010;
    /// CAN FD Transmit.
    pub const CANFD_TRANSMIT: u32 = 0x0011;
    /// CAN XL Transmit.
    pub const CANXL_TRANSMIT: u32 = 0x0012;
    /// Confirm.
    pub const CONFIRM: u32 = 0x0020;
    /// Arbitration Lost.
    pub const ARBITRATION_LOST: u32 = 0x0030;
    /// Bus Error.
    pub const BUS_ERROR: u32 = 0x0031;
    /// Configuration.
    pub const CONFIGURATION: u32 = 0x0040;
    /// Status.
    pub const STATUS: u32 = 0x0041;
    /// Wake Up.
    pub const WAKEUP: u32 = 0x0042;
}

/// FMI-LS-BUS 1.0.0, "MIME Types": the `mimeType` of the Tx/Rx data variables of a CAN network
/// (CAN, CAN FD and CAN XL). `#[fmu(can_network(..))]` gives it to them.
pub const CAN_MIME_TYPE: &str = "application/org.fmi-standard.fmi-ls-bus.can; version=\"1.0.0\"";

/// OP Code and Length: every operation starts with them (`fmi3LsBusOperationHeader`, 8 bytes).
pub const HEADER_LEN: usize = 8;

/// The largest identifier of a standard (11-bit) CAN frame.
pub const MAX_STANDARD_ID: u32 = 0x7FF;
/// The largest identifier of an extended (29-bit) CAN frame.
pub const MAX_EXTENDED_ID: u32 = 0x1FFF_FFFF;
/// The data lengths a CAN FD frame can have (ISO 11898-1: DLC 0..15 → 0..8, 12, 16, 20, 24, 32,
/// 48, 64 bytes); "the valid length of the data depends on the CAN FD Format" (CAN FD Transmit).
pub const CANFD_DATA_LENGTHS: [usize; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64];
/// The longest data field of a classic CAN frame, in bytes.
pub const CAN_MAX_DATA: usize = 8;
/// The longest data field of a CAN XL frame, in bytes (its shortest is 1).
pub const CANXL_MAX_DATA: usize = 2048;

/// A classic CAN frame to transmit (CAN Transmit, OP code 0x10, `Length = 16 + Data Length`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CanFrame<'a> {
    /// The identifier, a plain number (11 bits if `!ide`, 29 bits if `ide`).
    pub id: u32,
    /// Extended (29-bit) identifier.
    pub ide: bool,
    /// Remote Transmission Request.
    pub rtr: bool,
    /// The data, 0 to 8 bytes.
    pub data: &'a [u8],
}

/// A CAN FD frame to transmit (CAN FD Transmit, OP code 0x11, `Length = 17 + Data Length`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CanFdFrame<'a> {
    /// The identifier (11 bits if `!ide`, 29 bits if `ide`).
    pub id: u32,
    /// Extended (29-bit) identifier.
    pub ide: bool,
    /// Bit Rate Switch.
    pub brs: bool,
    /// Error State Indicator.
    pub esi: bool,
    /// The data, one of [`CANFD_DATA_LENGTHS`] bytes (padding included).
    pub data: &'a [u8],
}

/// A CAN XL frame to transmit (CAN XL Transmit, OP code 0x12, `Length = 22 + Data Length`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CanXlFrame<'a> {
    /// The identifier (11 bits if `!ide`, 29 bits if `ide`).
    pub id: u32,
    /// Extended (29-bit) identifier.
    pub ide: bool,
    /// Simple Extended Content.
    pub sec: bool,
    /// SDU type: the structure of the data field's content.
    pub sdt: u8,
    /// Virtual CAN network ID.
    pub vcid: u8,
    /// Acceptance Field.
    pub af: u32,
    /// The data, 1 to 2048 bytes.
    pub data: &'a [u8],
}

/// Bus Error's Error Code (`FMI3_LS_BUS_CAN_BUSERROR_PARAM_ERROR_CODE_*`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[repr(u8)]
pub enum ErrorCode {
    /// The sender read back a bit other than the one it sent.
    BitError = 1,
    /// Six consecutive bits of equal value on the bus.
    BitStuffingError = 2,
    /// The End-of-Frame format violated.
    FormError = 3,
    /// The frame's data and checksum disagree.
    CrcError = 4,
    /// No receiver acknowledged the frame.
    AckError = 5,
    /// An invalid transmission of an Error frame.
    BrokenErrorFrame = 6,
}

/// Bus Error's Error Flag (`FMI3_LS_BUS_CAN_BUSERROR_PARAM_ERROR_FLAG_*`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[repr(u8)]
pub enum ErrorFlag {
    /// This network FMU detected the error first.
    Primary = 1,
    /// This network FMU reacts to an error another detected.
    Secondary = 2,
}

/// The CAN node state a network FMU reports (Status, `FMI3_LS_BUS_CAN_STATUS_PARAM_STATUS_KIND_*`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[repr(u8)]
pub enum Status {
    /// ERROR ACTIVE (the default a bus simulation assumes).
    ErrorActive = 1,
    /// ERROR PASSIVE.
    ErrorPassive = 2,
    /// Bus-Off: the node transmits nothing.
    BusOff = 3,
}

/// What a bus simulation does with a frame that lost arbitration (Configuration parameter 0x04).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[repr(u8)]
pub enum ArbitrationLostBehavior {
    /// Keep the frame and send it when the bus is free; no Arbitration Lost operation.
    BufferAndRetransmit = 1,
    /// Drop the frame and send Arbitration Lost to its sender.
    DiscardAndNotify = 2,
}

/// One parameter of a Configuration operation (OP code 0x40; one parameter per operation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Configuration {
    /// CAN baud rate, bit/s (parameter type 0x01).
    CanBaudrate(u32),
    /// CAN FD (data phase) baud rate, bit/s (parameter type 0x02).
    CanFdBaudrate(u32),
    /// CAN XL (data phase) baud rate, bit/s (parameter type 0x03).
    CanXlBaudrate(u32),
    /// Arbitration Lost Behavior (parameter type 0x04).
    ArbitrationLostBehavior(ArbitrationLostBehavior),
}

/// One FMI-LS-BUS CAN bus operation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Operation<'a> {
    /// Transmit a classic CAN frame (network FMU → bus simulation or other network FMUs).
    CanTransmit(CanFrame<'a>),
    /// Transmit a CAN FD frame.
    CanFdTransmit(CanFdFrame<'a>),
    /// Transmit a CAN XL frame.
    CanXlTransmit(CanXlFrame<'a>),
    /// The frame `id` was received by at least one network FMU (bus simulation → sender).
    Confirm {
        /// The confirmed frame's identifier.
        id: u32,
    },
    /// The frame `id` lost arbitration and was discarded (bus simulation → sender).
    ArbitrationLost {
        /// The frame's identifier.
        id: u32,
    },
    /// A simulated bus error during the transmission of frame `id` (bus simulation → every node).
    BusError {
        /// The frame on the bus when the error happened.
        id: u32,
        /// What went wrong.
        error_code: ErrorCode,
        /// Whether this node detected it first.
        error_flag: ErrorFlag,
        /// Whether this node sent the frame.
        is_sender: bool,
    },
    /// A configuration parameter for the bus simulation (network FMU → bus simulation).
    Configuration(Configuration),
    /// The node's CAN state (network FMU → bus simulation).
    Status(Status),
    /// A bus wake-up (to every participant but its initiator).
    Wakeup,
    /// A corrupt operation was received; `data` is the complete operation that caused it.
    FormatError {
        /// The offending operation's bytes.
        data: &'a [u8],
    },
}

/// What an operation to write breaks, or why it does not fit.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PushError {
    /// The operation breaks a rule of the standard (the message names it).
    Invalid(String),
    /// The buffer has `free` bytes left; the operation needs `needed`.
    Full {
        /// Bytes the operation takes.
        needed: usize,
        /// Bytes left in the buffer.
        free: usize,
    },
}

impl fmt::Display for PushError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PushError::Invalid(why) => f.write_str(why),
            PushError::Full { needed, free } => write!(
                f,
                "the operation takes {needed} bytes and the buffer has {free} left (its Binary variable's maxSize): nothing was written"
            ),
        }
    }
}

impl std::error::Error for PushError {}

/// A received operation that does not match the standard's format: where, what, and the bytes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FormatError<'a> {
    /// The offset of the operation in the buffer.
    pub offset: usize,
    /// The rule broken, in words.
    pub reason: String,
    /// The operation's bytes as far as they could be delimited (for a Format Error reply).
    pub bytes: &'a [u8],
}

impl fmt::Display for FormatError<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "bus operation at byte {}: {}", self.offset, self.reason)
    }
}

impl std::error::Error for FormatError<'_> {}

const STD: &str = "FMI-LS-BUS 1.0.0";

fn check_bool(name: &str, op: &str, v: u8) -> Result<bool, String> {
    match v {
        0 => Ok(false),
        1 => Ok(true),
        _ => Err(format!(
            "{op}: {name} is {v:#04x}; {STD} ({op}) says the boolean values TRUE (0x01) and FALSE (0x00) shall be used"
        )),
    }
}

fn check_id(op: &str, id: u32, ide: bool) -> Result<(), String> {
    let (max, kind) = if ide {
        (MAX_EXTENDED_ID, "an extended (29-bit)")
    } else {
        (MAX_STANDARD_ID, "a standard (11-bit)")
    };
    if id > max {
        return Err(format!(
            "{op}: ID {id:#x} does not fit {kind} identifier (at most {max:#x}; Ide = {})",
            if ide { "TRUE" } else { "FALSE" }
        ));
    }
    Ok(())
}

fn check_data_len(op: &str, n: usize) -> Result<(), String> {
    let ok = match op {
        "CAN Transmit" => n <= CAN_MAX_DATA,
        "CAN FD Transmit" => CANFD_DATA_LENGTHS.contains(&n),
        _ => (1..=CANXL_MAX_DATA).contains(&n),
    };
    if ok {
        return Ok(());
    }
    let allowed = match op {
        "CAN Transmit" => "0 to 8 bytes".to_string(),
        "CAN FD Transmit" => format!("one of {CANFD_DATA_LENGTHS:?} bytes, padding included"),
        _ => "1 to 2048 bytes".to_string(),
    };
    Err(format!(
        "{op}: {n} data bytes; the data length of this CAN format is {allowed} ({STD}, {op}: \"the valid length of the data depends on the CAN format\")"
    ))
}

impl ErrorCode {
    fn from_u8(v: u8) -> Result<Self, String> {
        Ok(match v {
            1 => Self::BitError,
            2 => Self::BitStuffingError,
            3 => Self::FormError,
            4 => Self::CrcError,
            5 => Self::AckError,
            6 => Self::BrokenErrorFrame,
            _ => {
                return Err(format!(
                    "Bus Error: Error Code {v:#04x} is none of the standard's 0x01..0x06"
                ));
            }
        })
    }
}

impl ErrorFlag {
    fn from_u8(v: u8) -> Result<Self, String> {
        Ok(match v {
            1 => Self::Primary,
            2 => Self::Secondary,
            _ => {
                return Err(format!(
                    "Bus Error: Error Flag {v:#04x} is neither PRIMARY_ERROR_FLAG (0x01) nor SECONDARY_ERROR_FLAG (0x02)"
                ));
            }
        })
    }
}

impl Status {
    fn from_u8(v: u8) -> Result<Self, String> {
        Ok(match v {
            1 => Self::ErrorActive,
            2 => Self::ErrorPassive,
            3 => Self::BusOff,
            _ => {
                return Err(format!(
                    "Status: {v:#04x} is none of ERROR_ACTIVE (0x01), ERROR_PASSIVE (0x02), BUS_OFF (0x03)"
                ));
            }
        })
    }
}

impl ArbitrationLostBehavior {
    fn from_u8(v: u8) -> Result<Self, String> {
        Ok(match v {
            1 => Self::BufferAndRetransmit,
            2 => Self::DiscardAndNotify,
            _ => {
                return Err(format!(
                    "Configuration: Arbitration Lost Behavior {v:#04x} is neither BUFFER_AND_RETRANSMIT (0x01) nor DISCARD_AND_NOTIFY (0x02)"
                ));
            }
        })
    }
}

impl Operation<'_> {
    /// The operation's OP code.
    pub fn op_code(&self) -> u32 {
        match self {
            Operation::CanTransmit(_) => op_code::CAN_TRANSMIT,
            Operation::CanFdTransmit(_) => op_code::CANFD_TRANSMIT,
            Operation::CanXlTransmit(_) => op_code::CANXL_TRANSMIT,
            Operation::Confirm { .. } => op_code::CONFIRM,
            Operation::ArbitrationLost { .. } => op_code::ARBITRATION_LOST,
            Operation::BusError { .. } => op_code::BUS_ERROR,
            Operation::Configuration(_) => op_code::CONFIGURATION,
            Operation::Status(_) => op_code::STATUS,
            Operation::Wakeup => op_code::WAKEUP,
            Operation::FormatError { .. } => op_code::FORMAT_ERROR,
        }
    }

    /// The operation's name in the standard.
    pub fn name(&self) -> &'static str {
        match self {
            Operation::CanTransmit(_) => "CAN Transmit",
            Operation::CanFdTransmit(_) => "CAN FD Transmit",
            Operation::CanXlTransmit(_) => "CAN XL Transmit",
            Operation::Confirm { .. } => "Confirm",
            Operation::ArbitrationLost { .. } => "Arbitration Lost",
            Operation::BusError { .. } => "Bus Error",
            Operation::Configuration(_) => "Configuration",
            Operation::Status(_) => "Status",
            Operation::Wakeup => "Wake Up",
            Operation::FormatError { .. } => "Format Error",
        }
    }

    /// The operation's Length field: its whole size in bytes, header included.
    pub fn encoded_len(&self) -> usize {
        HEADER_LEN
            + match self {
                Operation::CanTransmit(f) => 8 + f.data.len(),
                Operation::CanFdTransmit(f) => 9 + f.data.len(),
                Operation::CanXlTransmit(f) => 14 + f.data.len(),
                Operation::Confirm { .. } | Operation::ArbitrationLost { .. } => 4,
                Operation::BusError { .. } => 7,
                Operation::Configuration(Configuration::ArbitrationLostBehavior(_)) => 2,
                Operation::Configuration(_) => 5,
                Operation::Status(_) => 1,
                Operation::Wakeup => 0,
                Operation::FormatError { data } => 2 + data.len(),
            }
    }

    /// Whether the operation keeps the standard's rules (the checks [`TxBuffer::push`] makes).
    pub fn validate(&self) -> Result<(), String> {
        let name = self.name();
        match self {
            Operation::CanTransmit(f) => {
                check_id(name, f.id, f.ide)?;
                check_data_len(name, f.data.len())
            }
            Operation::CanFdTransmit(f) => {
                check_id(name, f.id, f.ide)?;
                check_data_len(name, f.data.len())
            }
            Operation::CanXlTransmit(f) => {
                check_id(name, f.id, f.ide)?;
                check_data_len(name, f.data.len())
            }
            Operation::FormatError { data } if data.len() > u16::MAX as usize => Err(format!(
                "Format Error: {} bytes of data; its Data Length field has 2 bytes (at most 65535)",
                data.len()
            )),
            _ => Ok(()),
        }
    }

    /// Appends the operation's bytes (little-endian, the headers' packed layout) to `out`.
    fn write(&self, out: &mut Vec<u8>) {
        let len = u32::try_from(self.encoded_len()).expect("validated: data lengths are at most 65535");
        out.extend_from_slice(&self.op_code().to_le_bytes());
        out.extend_from_slice(&len.to_le_bytes());
        let data_len = |d: &[u8]| {
            u16::try_from(d.len())
                .expect("validated: data lengths are at most 65535")
                .to_le_bytes()
        };
        match *self {
            Operation::CanTransmit(f) => {
                out.extend_from_slice(&f.id.to_le_bytes());
                out.extend_from_slice(&[f.ide as u8, f.rtr as u8]);
                out.extend_from_slice(&data_len(f.data));
                out.extend_from_slice(f.data);
            }
            Operation::CanFdTransmit(f) => {
                out.extend_from_slice(&f.id.to_le_bytes());
                out.extend_from_slice(&[f.ide as u8, f.brs as u8, f.esi as u8]);
                out.extend_from_slice(&data_len(f.data));
                out.extend_from_slice(f.data);
            }
            Operation::CanXlTransmit(f) => {
                out.extend_from_slice(&f.id.to_le_bytes());
                out.extend_from_slice(&[f.ide as u8, f.sec as u8, f.sdt, f.vcid]);
                out.extend_from_slice(&f.af.to_le_bytes());
                out.extend_from_slice(&data_len(f.data));
                out.extend_from_slice(f.data);
            }
            Operation::Confirm { id } | Operation::ArbitrationLost { id } => out.extend_from_slice(&id.to_le_bytes()),
            Operation::BusError {
                id,
                error_code,
                error_flag,
                is_sender,
            } => {
                out.extend_from_slice(&id.to_le_bytes());
                out.extend_from_slice(&[error_code as u8, error_flag as u8, is_sender as u8]);
            }
            Operation::Configuration(c) => match c {
                Configuration::CanBaudrate(b) => {
                    out.push(0x01);
                    out.extend_from_slice(&b.to_le_bytes());
                }
                Configuration::CanFdBaudrate(b) => {
                    out.push(0x02);
                    out.extend_from_slice(&b.to_le_bytes());
                }
                Configuration::CanXlBaudrate(b) => {
                    out.push(0x03);
                    out.extend_from_slice(&b.to_le_bytes());
                }
                Configuration::ArbitrationLostBehavior(b) => out.extend_from_slice(&[0x04, b as u8]),
            },
            Operation::Status(s) => out.push(s as u8),
            Operation::Wakeup => {}
            Operation::FormatError { data } => {
                out.extend_from_slice(&data_len(data));
                out.extend_from_slice(data);
            }
        }
    }
}

/// The operations a network FMU sends in one Binary variable (`Tx_Data`): at most `capacity`
/// bytes (the variable's `maxSize`), appended one after the other.
#[derive(Clone, Debug)]
pub struct TxBuffer {
    bytes: Vec<u8>,
    capacity: usize,
}

impl TxBuffer {
    /// An empty buffer of at most `capacity` bytes (allocated once, here).
    pub fn with_capacity(capacity: usize) -> Self {
        Self {
            bytes: Vec::with_capacity(capacity),
            capacity,
        }
    }

    /// Appends `op` if it keeps the standard's rules and fits; otherwise writes nothing and says why.
    pub fn push(&mut self, op: &Operation<'_>) -> Result<(), PushError> {
        push_into(&mut self.bytes, self.capacity, op)
    }

    /// The bytes written so far: the Binary variable's value.
    pub fn as_bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// No operation waiting.
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }

    /// Forgets every operation (after the importer has read them).
    pub fn clear(&mut self) {
        self.bytes.clear();
    }

    /// The buffer's capacity in bytes.
    pub fn capacity(&self) -> usize {
        self.capacity
    }
}

/// Appends `op` to `bytes` (a Binary variable's value, a model's `Vec<u8>` field) if it keeps the
/// standard's rules and `bytes` stays within `capacity` (the variable's `maxSize`); otherwise
/// writes nothing and says why. [`TxBuffer::push`] is this on its own buffer.
pub fn push_into(bytes: &mut Vec<u8>, capacity: usize, op: &Operation<'_>) -> Result<(), PushError> {
    op.validate().map_err(PushError::Invalid)?;
    let needed = op.encoded_len();
    let free = capacity.saturating_sub(bytes.len());
    if needed > free {
        return Err(PushError::Full { needed, free });
    }
    op.write(bytes);
    Ok(())
}

/// The operations of a received buffer, in order ([`operations`]).
#[derive(Clone, Debug)]
pub struct Operations<'a> {
    bytes: &'a [u8],
    pos: usize,
}

/// Reads the operations of `bytes` one by one. An operation whose content breaks the standard is
/// an `Err` and reading goes on with the next (its Length delimits it); a header that cannot be
/// read, or a Length shorter than a header or longer than the buffer, ends the reading (nothing
/// after it can be delimited).
pub fn operations(bytes: &[u8]) -> Operations<'_> {
    Operations { bytes, pos: 0 }
}

/// Every operation of `bytes`, or the first malformed one: the whole buffer refused, nothing of it
/// to apply.
pub fn decode_all(bytes: &[u8]) -> Result<Vec<Operation<'_>>, FormatError<'_>> {
    operations(bytes).collect()
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn u16_at(b: &[u8], at: usize) -> usize {
    u16::from_le_bytes([b[at], b[at + 1]]) as usize
}

/// The content of one operation, `b` from its OP code to the end its Length gives.
fn parse(b: &[u8]) -> Result<Operation<'_>, String> {
    let code = u32_at(b, 0);
    let len = b.len();
    // The fixed part (header included) of an operation with data, and where Data Length is.
    let with_data = |name: &str, fixed: usize| -> Result<&[u8], String> {
        if len < fixed {
            return Err(format!(
                "{name}: Length {len} is shorter than its {fixed} bytes of fixed arguments"
            ));
        }
        let n = u16_at(b, fixed - 2);
        if len != fixed + n {
            return Err(format!(
                "{name}: Length {len} disagrees with Data Length {n} (the standard's Length = {fixed} + Data Length)"
            ));
        }
        Ok(&b[fixed..])
    };
    let fixed_len = |name: &str, want: usize| -> Result<(), String> {
        if len != want {
            return Err(format!("{name}: Length {len}; the standard's Length = {want}"));
        }
        Ok(())
    };
    let op = match code {
        op_code::CAN_TRANSMIT => {
            let name = "CAN Transmit";
            let data = with_data(name, 16)?;
            let frame = CanFrame {
                id: u32_at(b, 8),
                ide: check_bool("Ide", name, b[12])?,
                rtr: check_bool("Rtr", name, b[13])?,
                data,
            };
            Operation::CanTransmit(frame)
        }
        op_code::CANFD_TRANSMIT => {
            let name = "CAN FD Transmit";
            let data = with_data(name, 17)?;
            Operation::CanFdTransmit(CanFdFrame {
                id: u32_at(b, 8),
                ide: check_bool("Ide", name, b[12])?,
                brs: check_bool("Brs", name, b[13])?,
                esi: check_bool("Esi", name, b[14])?,
                data,
            })
        }
        op_code::CANXL_TRANSMIT => {
            let name = "CAN XL Transmit";
            let data = with_data(name, 22)?;
            Operation::CanXlTransmit(CanXlFrame {
                id: u32_at(b, 8),
                ide: check_bool("Ide", name, b[12])?,
                sec: check_bool("Sec", name, b[13])?,
                sdt: b[14],
                vcid: b[15],
                af: u32_at(b, 16),
                data,
            })
        }
        op_code::CONFIRM => {
            fixed_len("Confirm", 12)?;
            Operation::Confirm { id: u32_at(b, 8) }
        }
        op_code::ARBITRATION_LOST => {
            fixed_len("Arbitration Lost", 12)?;
            Operation::ArbitrationLost { id: u32_at(b, 8) }
        }
        op_code::BUS_ERROR => {
            fixed_len("Bus Error", 15)?;
            Operation::BusError {
                id: u32_at(b, 8),
                error_code: ErrorCode::from_u8(b[12])?,
                error_flag: ErrorFlag::from_u8(b[13])?,
                is_sender: check_bool("Is Sender", "Bus Error", b[14])?,
            }
        }
        op_code::CONFIGURATION => {
            if len < 9 {
                return Err(format!(
                    "Configuration: Length {len} leaves no Parameter Type (Length = 9 + parameter)"
                ));
            }
            let c = match b[8] {
                t @ 1..=3 => {
                    fixed_len("Configuration (baud rate)", 13)?;
                    let rate = u32_at(b, 9);
                    match t {
                        1 => Configuration::CanBaudrate(rate),
                        2 => Configuration::CanFdBaudrate(rate),
                        _ => Configuration::CanXlBaudrate(rate),
                    }
                }
                4 => {
                    fixed_len("Configuration (Arbitration Lost Behavior)", 10)?;
                    Configuration::ArbitrationLostBehavior(ArbitrationLostBehavior::from_u8(b[9])?)
                }
                t => {
                    return Err(format!(
                        "Configuration: Parameter Type {t:#04x} is none of CAN_BAUDRATE, CAN_FD_BAUDRATE, CAN_XL_BAUDRATE, ARBITRATION_LOST_BEHAVIOR (0x01..0x04)"
                    ));
                }
            };
            Operation::Configuration(c)
        }
        op_code::STATUS => {
            fixed_len("Status", 9)?;
            Operation::Status(Status::from_u8(b[8])?)
        }
        op_code::WAKEUP => {
            fixed_len("Wake Up", 8)?;
            Operation::Wakeup
        }
        op_code::FORMAT_ERROR => {
            let data = with_data("Format Error", 10)?;
            Operation::FormatError { data }
        }
        other => {
            return Err(format!(
                "unknown OP Code {other:#06x} (not an operation of {STD} for CAN)"
            ));
        }
    };
    op.validate()?;
    Ok(op)
}

impl<'a> Iterator for Operations<'a> {
    type Item = Result<Operation<'a>, FormatError<'a>>;

    fn next(&mut self) -> Option<Self::Item> {
        let rest = &self.bytes[self.pos..];
        if rest.is_empty() {
            return None;
        }
        let offset = self.pos;
        let fail = |reason: String, bytes: &'a [u8]| Some(Err(FormatError { offset, reason, bytes }));
        if rest.len() < HEADER_LEN {
            self.pos = self.bytes.len();
            return fail(
                format!(
                    "{} bytes left, fewer than an operation's 8-byte header (OP Code, Length)",
                    rest.len()
                ),
                rest,
            );
        }
        let len = u32_at(rest, 4) as usize;
        if len < HEADER_LEN || len > rest.len() {
            self.pos = self.bytes.len();
            return fail(
                format!(
                    "OP Code {:#06x} with Length {len}, {} (the Length covers OP Code, Length and arguments); nothing after it can be read",
                    u32_at(rest, 0),
                    if len < HEADER_LEN {
                        "shorter than its own 8-byte header".to_string()
                    } else {
                        format!("longer than the {} bytes left in the buffer", rest.len())
                    }
                ),
                rest,
            );
        }
        let this = &rest[..len];
        self.pos += len;
        Some(parse(this).map_err(|reason| FormatError {
            offset,
            reason,
            bytes: this,
        }))
    }
}

/// Every CAN operation, the fixture tests/c_headers.rs uses too.
#[cfg(test)]
#[path = "../tests/common/every_operation.rs"]
mod every_operation;

#[cfg(test)]
mod tests {
    use super::every_operation::every_operation;
    use super::*;

    #[test]
    fn every_operation_reads_back_as_written_and_its_length_is_the_standards() {
        let mut tx = TxBuffer::with_capacity(4096);
        let ops = every_operation();
        for op in &ops {
            let before = tx.as_bytes().len();
            tx.push(op).unwrap();
            let written = &tx.as_bytes()[before..];
            assert_eq!(written.len(), op.encoded_len(), "{op:?}");
            assert_eq!(u32_at(written, 4) as usize, written.len(), "{op:?}");
        }
        assert_eq!(decode_all(tx.as_bytes()).unwrap(), ops);
        // The standard's Length formulas: 16 + DL, 17 + DL, 22 + DL, 12, 12, 15, 13, 10, 9, 8, 10 + DL.
        let lens: Vec<usize> = ops.iter().map(Operation::encoded_len).collect();
        assert_eq!(
            lens,
            [24, 16, 29, 122, 12, 12, 15, 15, 13, 13, 13, 10, 10, 9, 9, 9, 8, 19]
        );
    }

    #[test]
    fn a_frame_that_breaks_a_rule_or_does_not_fit_writes_nothing() {
        let mut tx = TxBuffer::with_capacity(30);
        tx.push(&Operation::Confirm { id: 1 }).unwrap();
        let before = tx.as_bytes().to_vec();
        let bad = [
            (
                Operation::CanTransmit(CanFrame {
                    id: 0x800,
                    ide: false,
                    rtr: false,
                    data: &[],
                }),
                "does not fit a standard (11-bit)",
            ),
            (
                Operation::CanTransmit(CanFrame {
                    id: 0x2000_0000,
                    ide: true,
                    rtr: false,
                    data: &[],
                }),
                "extended (29-bit)",
            ),
            (
                Operation::CanTransmit(CanFrame {
                    id: 1,
                    ide: false,
                    rtr: false,
                    data: &[0; 9],
                }),
                "9 data bytes",
            ),
            (
                Operation::CanFdTransmit(CanFdFrame {
                    id: 1,
                    ide: false,
                    brs: false,
                    esi: false,
                    data: &[0; 9],
                }),
                "padding included",
            ),
            (
                Operation::CanXlTransmit(CanXlFrame {
                    id: 1,
                    ide: false,
                    sec: false,
                    sdt: 0,
                    vcid: 0,
                    af: 0,
                    data: &[],
                }),
                "1 to 2048",
            ),
        ];
        for (op, words) in bad {
            let e = tx.push(&op).unwrap_err();
            assert!(matches!(&e, PushError::Invalid(m) if m.contains(words)), "{op:?}: {e}");
            assert_eq!(tx.as_bytes(), before);
        }
        let e = tx
            .push(&Operation::CanTransmit(CanFrame {
                id: 1,
                ide: false,
                rtr: false,
                data: &[0; 8],
            }))
            .unwrap_err();
        assert_eq!(e, PushError::Full { needed: 24, free: 18 });
        assert_eq!(tx.as_bytes(), before);
    }

    fn refused(bytes: &[u8], words: &str) {
        let e = decode_all(bytes).unwrap_err();
        assert!(e.reason.contains(words), "{bytes:02x?}: {e}");
    }

    #[test]
    fn every_malformed_operation_is_refused_with_where_and_why() {
        let mut ok = TxBuffer::with_capacity(64);
        ok.push(&Operation::Confirm { id: 5 }).unwrap();
        let good = ok.as_bytes().to_vec();
        let with = |tail: &[u8]| [good.as_slice(), tail].concat();
        // Truncated header, a Length too short or too long.
        let short = with(&[0x20, 0, 0]);
        let e = decode_all(&short).unwrap_err();
        assert_eq!(e.offset, 12);
        assert!(e.reason.contains("fewer than an operation's 8-byte header"), "{e}");
        refused(
            &with(&[0x20, 0, 0, 0, 4, 0, 0, 0]),
            "shorter than its own 8-byte header",
        );
        refused(
            &with(&[0x20, 0, 0, 0, 13, 0, 0, 0, 1, 0, 0, 0]),
            "longer than the 12 bytes left",
        );
        // Unknown OP code; a fixed-size operation with another Length.
        refused(&[0x13, 0, 0, 0, 8, 0, 0, 0], "unknown OP Code 0x0013");
        refused(
            &[0x20, 0, 0, 0, 13, 0, 0, 0, 1, 0, 0, 0, 0],
            "Confirm: Length 13; the standard's Length = 12",
        );
        refused(&[0x42, 0, 0, 0, 9, 0, 0, 0, 0], "Wake Up: Length 9");
        // Data Length against Length; booleans; identifiers; data lengths.
        refused(
            &[0x10, 0, 0, 0, 17, 0, 0, 0, 1, 0, 0, 0, 0, 0, 2, 0, 7],
            "disagrees with Data Length 2",
        );
        refused(&[0x10, 0, 0, 0, 16, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0], "Ide is 0x02");
        refused(
            &[0x10, 0, 0, 0, 16, 0, 0, 0, 0, 8, 0, 0, 0, 0, 0, 0],
            "ID 0x800 does not fit a standard",
        );
        let mut nine = vec![0x10, 0, 0, 0, 25, 0, 0, 0, 1, 0, 0, 0, 0, 0, 9, 0];
        nine.extend([0; 9]);
        refused(&nine, "9 data bytes");
        refused(&[0x11, 0, 0, 0, 17, 0, 0, 0, 1, 0, 0, 0, 0, 0, 9, 0, 0], "Esi is 0x09");
        // Enumerations.
        refused(&[0x31, 0, 0, 0, 15, 0, 0, 0, 1, 0, 0, 0, 7, 1, 0], "Error Code 0x07");
        refused(&[0x31, 0, 0, 0, 15, 0, 0, 0, 1, 0, 0, 0, 1, 3, 0], "Error Flag 0x03");
        refused(&[0x31, 0, 0, 0, 15, 0, 0, 0, 1, 0, 0, 0, 1, 1, 2], "Is Sender is 0x02");
        refused(&[0x41, 0, 0, 0, 9, 0, 0, 0, 0], "Status: 0x00");
        refused(&[0x40, 0, 0, 0, 9, 0, 0, 0, 5], "Parameter Type 0x05");
        refused(
            &[0x40, 0, 0, 0, 10, 0, 0, 0, 1, 0],
            "Configuration (baud rate): Length 10",
        );
        refused(&[0x40, 0, 0, 0, 10, 0, 0, 0, 4, 3], "Arbitration Lost Behavior 0x03");
        refused(&[0x40, 0, 0, 0, 8, 0, 0, 0], "leaves no Parameter Type");
    }

    #[test]
    fn reading_goes_on_after_an_operation_its_length_delimits() {
        let mut tx = TxBuffer::with_capacity(64);
        tx.push(&Operation::Confirm { id: 5 }).unwrap();
        let mut bytes = tx.as_bytes().to_vec();
        let bad = [0x41, 0, 0, 0, 9, 0, 0, 0, 9];
        bytes.extend(bad);
        bytes.extend(tx.as_bytes());
        let all: Vec<_> = operations(&bytes).collect();
        assert_eq!(all.len(), 3);
        assert_eq!(all[0], Ok(Operation::Confirm { id: 5 }));
        let e = all[1].clone().unwrap_err();
        assert_eq!((e.offset, e.bytes), (12, &bad[..]));
        assert_eq!(all[2], Ok(Operation::Confirm { id: 5 }));
        // The Format Error reply carries the offending operation whole.
        let mut reply = TxBuffer::with_capacity(64);
        reply.push(&Operation::FormatError { data: e.bytes }).unwrap();
        assert_eq!(
            decode_all(reply.as_bytes()).unwrap(),
            [Operation::FormatError { data: &bad }]
        );
    }
}
