//! Every function of the co-simulation interface in every state of the FMI 2.0 state machine,
//! for every packaged FMU (the checks are `fmi_conformance::checks::state_machine`).
//!
//! Thin callers: each test runs its check on every FMU of target/fmu, strictly (a skip or a
//! part left untested fails: these are this exporter's FMUs).

use fmi_conformance::checks::on_every_fmu;

#[test]
fn every_function_in_every_state_answers_as_the_standard_says() {
    on_every_fmu("every_function_in_every_state_answers_as_the_standard_says");
}

#[test]
fn a_null_component_is_refused_by_every_function() {
    on_every_fmu("a_null_component_is_refused_by_every_function");
}

#[test]
fn version_and_platform_are_the_standards() {
    on_every_fmu("version_and_platform_are_the_standards");
}

#[test]
fn directional_derivative_flag_is_either_value_and_false_means_refused() {
    on_every_fmu("directional_derivative_flag_is_either_value_and_false_means_refused");
}

#[test]
fn terminate_twice_is_refused_with_a_message() {
    on_every_fmu("terminate_twice_is_refused_with_a_message");
}
