//! `cargo fmu` and `fmu-build`: build any crate whose cdylib exports a rustfmu model into an
//! FMU, package it, validate and inspect FMU files, run the conformance suite on them, and write
//! SSP files of composed systems.
//!
//! The packager needs no knowledge of a model's Rust types: it reads the typed description
//! that the built library carries (`rustfmu::description`) and writes `modelDescription.xml`
//! from it.

pub mod bundle;
pub mod cargo;
pub mod cli;
pub mod container;
pub mod depends;
pub mod depends_fmi2;
pub mod depends_fmi3;
pub mod docs;
pub mod library;
pub mod new;
pub mod plot;
pub mod progress;
pub mod ssp;
pub mod systems;
pub mod systems_fmi3;
pub mod target;
pub mod validate;
pub mod xml;

/// What the unit tests of several modules share.
#[cfg(test)]
pub(crate) mod test_support {
    /// Each element of the JSON array `bad` refused by `parse` (the one accepted named).
    pub(crate) fn refuses_each<T, E>(parse: impl Fn(&serde_json::Value) -> Result<T, E>, bad: &str) {
        let bad: Vec<serde_json::Value> = serde_json::from_str(bad).unwrap();
        for b in bad {
            assert!(parse(&b).is_err(), "{b} was accepted");
        }
    }
}
