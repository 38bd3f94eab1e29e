//! What a built rustfmu library says about itself, read without loading it (the description of
//! each FMI version it carries, and the `modelDescription.xml` written from it), and how an
//! importer hands a loaded library its resources. Below every room that reads a library:
//! packaging ([`crate::bundle`]), validation ([`crate::validate`]) and the documentation's
//! picture ([`crate::plot`]).

use rustfmu::description::{self, FmiVersion, Interfaces, ModelDescription};
use std::path::Path;

/// `modelDescription.xml` of a built library, in the version the library implements.
pub fn model_description(me: &SelfDescription) -> Result<String, String> {
    match me.interfaces.version {
        FmiVersion::V2 => crate::xml::fmi2(&me.description, me.interfaces, &me.guid),
        FmiVersion::V3 => crate::xml::fmi3(&me.description, me.interfaces, &me.guid),
    }
}

/// What a built library says about itself.
pub struct SelfDescription {
    pub description: ModelDescription,
    pub interfaces: Interfaces,
    pub guid: String,
}

/// Reads the description of FMI `version` a rustfmu library carries.
pub fn read_library(binary: &[u8], version: FmiVersion) -> Result<SelfDescription, String> {
    self_description(description::find_encoded_for(binary, version)?)
}

/// Every description a rustfmu library carries: one per FMI version it implements (both for
/// `export_fmu!`), in the order they appear.
pub fn library_versions(binary: &[u8]) -> Result<Vec<SelfDescription>, String> {
    description::find_all_encoded(binary)?
        .into_iter()
        .map(self_description)
        .collect()
}

fn self_description(encoded: &[u8]) -> Result<SelfDescription, String> {
    let (d, interfaces) = description::decode(encoded)?;
    Ok(SelfDescription {
        description: d,
        interfaces,
        guid: description::guid_string(encoded),
    })
}

/// FMI 2.0's fmuResourceLocation of a folder: a `file:` URI of its absolute path, every byte
/// but the unreserved ones and `/` percent-encoded (RFC 3986; a Windows path as `file:///C:/...`).
pub fn file_uri(dir: &Path) -> String {
    let abs = std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf());
    let path = abs.to_string_lossy().replace('\\', "/");
    let mut uri = String::from(if path.starts_with('/') { "file://" } else { "file:///" });
    for b in path.bytes() {
        match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' | b'/' | b':' => uri.push(b as char),
            _ => uri.push_str(&format!("%{b:02X}")),
        }
    }
    uri
}
