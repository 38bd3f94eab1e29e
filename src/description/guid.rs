//! The GUID (FMI 2.0) and instantiation token (FMI 3.0): a name-based UUID of the encoded
//! description, computed in const evaluation.

/// `{xxxxxxxx-xxxx-5xxx-yxxx-xxxxxxxxxxxx}`: a name-based SHA-1 UUID (RFC 4122, version 5) of
/// the encoded description; `MAGIC` at its start plays the namespace's part.
pub const fn guid(encoded: &[u8]) -> [u8; 38] {
    let digest = const_sha1::sha1(encoded).as_bytes();
    let mut b = [0u8; 16];
    let mut i = 0;
    while i < 16 {
        b[i] = digest[i];
        i += 1;
    }
    b[6] = (b[6] & 0x0f) | 0x50;
    b[8] = (b[8] & 0x3f) | 0x80;
    const HEX: &[u8; 16] = b"0123456789abcdef";
    let mut out = [0u8; 38];
    out[0] = b'{';
    let mut at = 1;
    let mut i = 0;
    while i < 16 {
        if i == 4 || i == 6 || i == 8 || i == 10 {
            out[at] = b'-';
            at += 1;
        }
        out[at] = HEX[(b[i] >> 4) as usize];
        out[at + 1] = HEX[(b[i] & 0xf) as usize];
        at += 2;
        i += 1;
    }
    out[37] = b'}';
    out
}

/// [`guid`] as text.
pub fn guid_string(encoded: &[u8]) -> String {
    String::from_utf8_lossy(&guid(encoded)).into_owned()
}
