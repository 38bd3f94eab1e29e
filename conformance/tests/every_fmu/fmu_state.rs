//! FMU state get/set/serialize for every packaged FMU, and a state restored in another process
//! (the checks are `fmi_conformance::checks::fmu_state`).
//!
//! Thin callers: each test runs its check on every FMU of target/fmu, strictly (a skip or a
//! part left untested fails: these are this exporter's FMUs).

/// The check of restoring in another process starts this crate's `fmu-check` as its worker.
fn on_every_fmu(name: &str) {
    fmi_conformance::set_worker(fmi_conformance::Worker {
        exe: env!("CARGO_BIN_EXE_fmu-check").into(),
        args_prefix: vec!["__worker".into()],
    });
    fmi_conformance::checks::on_every_fmu(name);
}

#[test]
fn every_fmu_declares_it_can_get_set_and_serialize_its_state() {
    on_every_fmu("every_fmu_declares_it_can_get_set_and_serialize_its_state");
}

#[test]
fn get_set_free_round_trip_continues_bit_identically() {
    on_every_fmu("get_set_free_round_trip_continues_bit_identically");
}

#[test]
fn a_saved_state_is_a_complete_copy_independent_of_the_instance() {
    on_every_fmu("a_saved_state_is_a_complete_copy_independent_of_the_instance");
}

#[test]
fn serialize_deserialize_round_trip_continues_bit_identically() {
    on_every_fmu("serialize_deserialize_round_trip_continues_bit_identically");
}

#[test]
fn the_serialized_state_holds_no_pointers_and_is_versioned() {
    on_every_fmu("the_serialized_state_holds_no_pointers_and_is_versioned");
}

#[test]
fn damaged_serialized_states_are_refused_with_a_message() {
    on_every_fmu("damaged_serialized_states_are_refused_with_a_message");
}

#[test]
fn a_state_serialized_here_restores_in_another_process_and_continues_identically() {
    on_every_fmu("a_state_serialized_here_restores_in_another_process_and_continues_identically");
}
