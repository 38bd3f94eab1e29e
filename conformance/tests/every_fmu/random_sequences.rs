//! Random call sequences through the C API of every packaged FMU, checked against a shadow
//! model of the state machine (the checks are `fmi_conformance::checks::random_sequences`;
//! `PROPTEST_CASES` sequences per FMU, default 2000).
//!
//! Thin callers: each test runs its check on every FMU of target/fmu, strictly (a skip or a
//! part left untested fails: these are this exporter's FMUs).
//!
//! The sequences come from one seed per test process, `$RUSTFMU_SEED` or drawn
//! (`fmi_conformance::seed`): each random test writes it to stderr before it starts, past the
//! test harness's capture, so that the log of a CI run shows it even when the test process dies
//! inside an FMU; a failure message names it too.

use fmi_conformance::checks::on_every_fmu;
use std::io::Write;

/// Writes the seed of the random test `test` to stderr (not captured by the test harness).
pub fn announce_seed(test: &str) {
    let line = format!("{test}: {}\n", fmi_conformance::seed_note());
    let _ = std::io::stderr().write_all(line.as_bytes());
}

#[test]
fn random_call_sequences_keep_every_fmu_conformant() {
    announce_seed("random_call_sequences_keep_every_fmu_conformant");
    on_every_fmu("random_call_sequences_keep_every_fmu_conformant");
}

#[test]
fn regressions_found_by_random_sequences() {
    on_every_fmu("regressions_found_by_random_sequences");
}

#[test]
fn random_model_exchange_call_sequences_keep_every_fmu_conformant() {
    announce_seed("random_model_exchange_call_sequences_keep_every_fmu_conformant");
    on_every_fmu("random_model_exchange_call_sequences_keep_every_fmu_conformant");
}
