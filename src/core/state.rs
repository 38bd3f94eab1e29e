//! Serialized FMU state: versioned, position-independent (no pointers), and checked.
//!
//! Layout, all integers little-endian:
//! `b"RFMUSTAT"` | format version u32 | GUID length u16 | GUID bytes | payload length u32 |
//! payload (postcard encoding of [`Sim`]) | CRC-32 of everything before it, u32.

use super::Terms;
use super::instance::Sim;
use crate::model::CoSimulation;

pub const MAGIC: &[u8; 8] = b"RFMUSTAT";
/// Bump whenever [`Sim`] or a model's serialized fields change shape.
pub const FORMAT_VERSION: u32 = 1;

pub fn serialize<M: CoSimulation>(guid: &str, sim: &Sim<M>) -> Result<Vec<u8>, String> {
    let payload = postcard::to_allocvec(sim).map_err(|e| format!("cannot encode the state: {e}"))?;
    let guid = guid.as_bytes();
    let mut out = Vec::with_capacity(8 + 4 + 2 + guid.len() + 4 + payload.len() + 4);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(guid.len() as u16).to_le_bytes());
    out.extend_from_slice(guid);
    out.extend_from_slice(&(payload.len() as u32).to_le_bytes());
    out.extend_from_slice(&payload);
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    Ok(out)
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self
            .at
            .checked_add(n)
            .filter(|e| *e <= self.bytes.len())
            .ok_or_else(|| {
                format!(
                    "truncated: {what} needs {n} bytes at offset {}, but the state has {} bytes",
                    self.at,
                    self.bytes.len()
                )
            })?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u16(&mut self, what: &str) -> Result<u16, String> {
        Ok(u16::from_le_bytes(self.take(2, what)?.try_into().expect("2 bytes")))
    }
    fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4, what)?.try_into().expect("4 bytes")))
    }
}

/// Decodes a state written by [`serialize`] for the same model (same GUID) and format.
pub fn deserialize<M: CoSimulation>(terms: &Terms, guid: &str, bytes: &[u8]) -> Result<Sim<M>, String> {
    let mut r = Reader { bytes, at: 0 };
    if r.take(8, "the header")? != MAGIC {
        return Err("not a serialized state of this exporter (wrong magic bytes)".into());
    }
    let version = r.u32("the format version")?;
    if version != FORMAT_VERSION {
        return Err(format!(
            "format version {version}, but this FMU reads version {FORMAT_VERSION}"
        ));
    }
    let token = terms.token;
    let n = r.u16(&format!("the {token} length"))? as usize;
    let their_guid = r.take(n, &format!("the {token}"))?;
    if their_guid != guid.as_bytes() {
        return Err(format!(
            "the state belongs to {token} {}, this FMU is {guid}",
            String::from_utf8_lossy(their_guid)
        ));
    }
    let n = r.u32("the payload length")? as usize;
    let payload = r.take(n, "the payload")?;
    let body_end = r.at;
    let crc = r.u32("the checksum")?;
    if r.at != bytes.len() {
        return Err(format!("{} unexpected bytes after the checksum", bytes.len() - r.at));
    }
    if crc32fast::hash(&bytes[..body_end]) != crc {
        return Err("checksum mismatch: the state was altered or damaged".into());
    }
    postcard::from_bytes(payload).map_err(|e| format!("cannot decode the payload: {e}"))
}
