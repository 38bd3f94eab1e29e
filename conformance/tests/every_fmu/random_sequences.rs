//! Random call sequences through the C API of every packaged FMU, checked against a shadow
//! model of the state machine (the checks are `fmi_conformance::checks::random_sequences`;
//! `PROPTEST_CASES` sequences per FMU, default 2000).
//!
//! Thin callers: each test runs its check on every FMU of target/fmu, strictly (a skip or a
//! part left untested fails: these are this exporter's FMUs).

use fmi_conformance::checks::on_every_fmu;

#[test]
fn random_call_sequences_keep_every_fmu_conformant() {
    on_every_fmu("random_call_sequences_keep_every_fmu_conformant");
}

#[test]
fn regressions_found_by_random_sequences() {
    on_every_fmu("regressions_found_by_random_sequences");
}

#[test]
fn random_model_exchange_call_sequences_keep_every_fmu_conformant() {
    on_every_fmu("random_model_exchange_call_sequences_keep_every_fmu_conformant");
}
