//! Many instances of every packaged FMU, in one process and on threads, and unloading the
//! library (the checks are `fmi_conformance::checks::instances`).
//!
//! Thin callers: each test runs its check on every FMU of target/fmu, strictly (a skip or a
//! part left untested fails: these are this exporter's FMUs).

use fmi_conformance::checks::on_every_fmu;

#[test]
fn interleaved_instances_do_not_affect_each_other() {
    on_every_fmu("interleaved_instances_do_not_affect_each_other");
}

#[test]
fn instances_on_their_own_threads_match_sequential_runs_bit_for_bit() {
    on_every_fmu("instances_on_their_own_threads_match_sequential_runs_bit_for_bit");
}

#[test]
fn the_library_can_be_unloaded_after_the_last_free_and_loaded_again() {
    on_every_fmu("the_library_can_be_unloaded_after_the_last_free_and_loaded_again");
}
