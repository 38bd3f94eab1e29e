//! Reading and forging serialized FMU states of FMUs made by this exporter (rustfmu).
//!
//! The runtime's format: magic `RFMUSTAT` | version u32 | GUID length u16 | GUID | payload
//! length u32 | payload | CRC-32, little-endian, and the payload's first byte is the
//! state-machine state (the numbering of [`State`]). The suite reads that byte to observe the
//! state machine from outside, and writes it to put an instance in a state that its model
//! cannot reach on its own (StepFailed of an FMU whose steps never fail, StepCanceled, Error,
//! Fatal). [`parse`] checks every field, so a change of the format fails the suite loudly.
//!
//! Nothing of this applies to another exporter's FMU: its serialized state is opaque. The
//! checks find out with [`crate::Fmu::own_state_format`] and test such an FMU only in the states
//! an importer can reach ([`crate::standard::REACHABLE`]).

pub use crate::standard::{STATES, State};

/// The magic bytes that start this exporter's serialized FMU states.
pub const MAGIC: &[u8; 8] = b"RFMUSTAT";
/// The format version this suite reads.
pub const FORMAT_VERSION: u32 = 1;

pub fn name(s: State) -> String {
    format!("{s:?}")
}

/// Where the fields of a serialized state are.
#[derive(Debug, Clone, Copy)]
pub struct Layout {
    pub version_at: usize,
    pub guid_at: usize,
    pub guid_len: usize,
    pub payload_at: usize,
    pub payload_len: usize,
    pub crc_at: usize,
}

pub fn parse(bytes: &[u8]) -> Result<Layout, String> {
    let u16_at = |i: usize| bytes.get(i..i + 2).map(|b| u16::from_le_bytes([b[0], b[1]]) as usize);
    let u32_at = |i: usize| {
        bytes
            .get(i..i + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    if bytes.get(..8) != Some(&MAGIC[..]) {
        return Err("serialized state does not start with the runtime's magic bytes".into());
    }
    if u32_at(8) != Some(FORMAT_VERSION as usize) {
        return Err(format!("serialized state is not format version {FORMAT_VERSION}"));
    }
    let guid_len = u16_at(12).ok_or("truncated")?;
    let payload_len = u32_at(14 + guid_len).ok_or("truncated")?;
    let payload_at = 18 + guid_len;
    let crc_at = payload_at + payload_len;
    if bytes.len() != crc_at + 4 {
        return Err(format!(
            "serialized state has {} bytes, its fields say {}",
            bytes.len(),
            crc_at + 4
        ));
    }
    if crc32fast::hash(&bytes[..crc_at]) as usize != u32_at(crc_at).unwrap_or(usize::MAX) {
        return Err("serialized state's CRC does not match".into());
    }
    if payload_len == 0 {
        return Err("serialized state has an empty payload".into());
    }
    Ok(Layout {
        version_at: 8,
        guid_at: 14,
        guid_len,
        payload_at,
        payload_len,
        crc_at,
    })
}

/// The state-machine state recorded in a serialized FMU state.
pub fn machine_state(bytes: &[u8]) -> Result<State, String> {
    let l = parse(bytes)?;
    let b = bytes[l.payload_at];
    STATES
        .get(b as usize)
        .copied()
        .ok_or_else(|| format!("state byte {b} is no State"))
}

/// The raw state byte (the state machine's state as the runtime numbers it), for the
/// model-exchange states, whose numbers the suite learns from the FMU ([`crate::me`]).
pub fn state_byte(bytes: &[u8]) -> Result<u8, String> {
    let l = parse(bytes)?;
    Ok(bytes[l.payload_at])
}

/// The same serialized state with another raw state byte, correctly sealed.
pub fn forge_byte(bytes: &[u8], byte: u8) -> Vec<u8> {
    let l = parse(bytes).unwrap_or_else(|e| panic!("{e}"));
    let mut out = bytes.to_vec();
    out[l.payload_at] = byte;
    reseal(&mut out, &l);
    out
}

/// Recomputes the trailing CRC after an edit.
pub fn reseal(bytes: &mut [u8], l: &Layout) {
    let crc = crc32fast::hash(&bytes[..l.crc_at]);
    bytes[l.crc_at..].copy_from_slice(&crc.to_le_bytes());
}

/// The same serialized state with another state-machine state, correctly sealed.
pub fn forge(bytes: &[u8], state: State) -> Vec<u8> {
    let l = parse(bytes).unwrap_or_else(|e| panic!("{e}"));
    let mut out = bytes.to_vec();
    out[l.payload_at] = state as u8;
    reseal(&mut out, &l);
    out
}
