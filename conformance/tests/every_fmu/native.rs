//! Every packaged FMU in a C host, under valgrind memcheck, and its binary's dynamic symbols
//! (the checks are `fmi_conformance::checks::native`).
//!
//! Thin callers: each test runs its check on every FMU of target/fmu, strictly (a skip or a
//! part left untested fails: these are this exporter's FMUs).

use fmi_conformance::checks::on_every_fmu;

#[test]
fn a_c_host_runs_every_fmu_with_the_same_results_as_the_rust_importer() {
    on_every_fmu("a_c_host_runs_every_fmu_with_the_same_results_as_the_rust_importer");
}

#[test]
fn a_whole_run_of_every_fmu_is_clean_under_valgrind_memcheck() {
    on_every_fmu("a_whole_run_of_every_fmu_is_clean_under_valgrind_memcheck");
}

#[test]
fn the_binary_exports_the_fmi2_functions_and_no_others() {
    on_every_fmu("the_binary_exports_the_fmi2_functions_and_no_others");
}

#[test]
fn the_binary_needs_only_the_c_runtime() {
    on_every_fmu("the_binary_needs_only_the_c_runtime");
}
