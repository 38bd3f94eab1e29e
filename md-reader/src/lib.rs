//! `modelDescription.xml` of FMI 2.0 ([`fmi2`]) and FMI 3.0 ([`fmi3`]) read into typed structs,
//! the way an importer reads it. One reader for every tool of the workspace: `cargo fmu`
//! (`validate`, `info`, the composed systems), the SSP runner and the conformance suite (after
//! rust-fmi's fmi-schema: one description model that importer and exporter share).
//!
//! It reads what it is given and depends on nothing of the exporter, so the conformance suite
//! that uses it still checks an FMU against the standard, not against the runtime's own tables.
//! Writing descriptions stays in `fmu-build` (`xml.rs`), from the runtime's typed description
//! the binary carries.
//!
//! What the reader refuses is what no importer could use: XML that is not well-formed, a
//! variable without a valid value reference, name or type element, a causality, variability or
//! initial the version does not define, an enumeration item without an integer value, an FMI
//! 2.0 Enumeration variable without its type. What it reads but does not judge (an `<Unknown>`
//! whose index does not parse, a missing `<CoSimulation>`) it keeps for the caller to report:
//! each tool has its own rule there.
//!
//! ```
//! let xml = r#"<fmiModelDescription fmiVersion="2.0" modelName="M" guid="{x}">
//!   <CoSimulation modelIdentifier="M"/>
//!   <ModelVariables>
//!     <ScalarVariable name="y" valueReference="0" causality="output"><Real/></ScalarVariable>
//!   </ModelVariables>
//!   <ModelStructure><Outputs><Unknown index="1"/></Outputs></ModelStructure>
//! </fmiModelDescription>"#;
//! let md_reader::ModelDescription::Fmi2(d) = md_reader::parse(xml).unwrap() else {
//!     panic!("an FMI 2.0 description")
//! };
//! assert_eq!(d.model_identifier(), "M");
//! assert_eq!(d.variables[0].causality, md_reader::Causality::Output);
//! ```

mod common;
pub mod fmi2;
pub mod fmi3;
mod read;

pub use common::{Causality, DefaultExperiment, Initial, Variability};

/// A description of either version, as its `fmiVersion` says.
#[derive(Debug, Clone)]
pub enum ModelDescription {
    Fmi2(fmi2::ModelDescription),
    Fmi3(fmi3::ModelDescription),
}

/// The FMI versions this crate reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Version {
    Fmi2,
    Fmi3,
}

impl Version {
    /// The version of an `fmiVersion` attribute: "2.0" is FMI 2.0, "3.0" and "3.x" FMI 3.0.
    pub fn of(fmi_version: &str) -> Option<Version> {
        match fmi_version {
            "2.0" => Some(Version::Fmi2),
            v if v == "3.0" || v.starts_with("3.") => Some(Version::Fmi3),
            _ => None,
        }
    }
}

/// Reads a description of either version, chosen by its `fmiVersion`.
pub fn parse(xml: &str) -> Result<ModelDescription, String> {
    let version = fmi_version(xml)?;
    match Version::of(&version) {
        Some(Version::Fmi2) => fmi2::ModelDescription::parse(xml).map(ModelDescription::Fmi2),
        Some(Version::Fmi3) => fmi3::ModelDescription::parse(xml).map(ModelDescription::Fmi3),
        None => Err(format!("fmiVersion is '{version}', expected '2.0' or '3.0'")),
    }
}

/// The `fmiVersion` attribute of the root element (empty if it has none), read without reading
/// the rest: what a tool looks at first, to pick a reader or refuse a version it does not run.
pub fn fmi_version(xml: &str) -> Result<String, String> {
    let mut events = read::Events::new(xml);
    loop {
        match events.next()? {
            read::Node::Start(e, _) if e.name == b"fmiModelDescription" => {
                return Ok(e.attr("fmiVersion").unwrap_or_default().to_owned());
            }
            read::Node::Eof => return Err("modelDescription.xml: no <fmiModelDescription>".into()),
            _ => {}
        }
    }
}

/// Line and column (both 1-based; the column counts characters) of a byte offset into `text`.
pub fn line_column(text: &str, byte: usize) -> (usize, usize) {
    let mut byte = byte.min(text.len());
    while !text.is_char_boundary(byte) {
        byte -= 1;
    }
    let before = &text[..byte];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[start..].chars().count() + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_version_picks_the_reader() {
        let two = r#"<fmiModelDescription fmiVersion="2.0" guid="g"><CoSimulation modelIdentifier="A"/></fmiModelDescription>"#;
        let three = r#"<fmiModelDescription fmiVersion="3.0" instantiationToken="t"><CoSimulation modelIdentifier="B"/></fmiModelDescription>"#;
        assert!(matches!(parse(two), Ok(ModelDescription::Fmi2(d)) if d.guid == "g"));
        assert!(matches!(parse(three), Ok(ModelDescription::Fmi3(d)) if d.token == "t"));
        let one = r#"<fmiModelDescription fmiVersion="1.0"/>"#;
        assert_eq!(parse(one).unwrap_err(), "fmiVersion is '1.0', expected '2.0' or '3.0'");
        assert_eq!(fmi_version(one).unwrap(), "1.0");
    }

    #[test]
    fn line_and_column_count_lines_and_characters() {
        let t = "ab\ncäd\ne";
        assert_eq!(line_column(t, 0), (1, 1));
        assert_eq!(line_column(t, 2), (1, 3));
        assert_eq!(line_column(t, 3), (2, 1));
        // 'ä' is two bytes, one column; an offset inside it counts from its start
        assert_eq!(line_column(t, 5), (2, 2));
        assert_eq!(line_column(t, 100), (3, 2));
    }
}
