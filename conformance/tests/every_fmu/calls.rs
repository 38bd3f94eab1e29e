//! Bad and edge-case arguments of every kind an importer can pass, for every packaged FMU
//! (the checks are `fmi_conformance::checks::calls`).
//!
//! Thin callers: each test runs its check on every FMU of target/fmu, strictly (a skip or a
//! part left untested fails: these are this exporter's FMUs).

use fmi_conformance::checks::on_every_fmu;

#[test]
fn instantiate_refuses_a_wrong_null_or_empty_guid_with_a_message() {
    on_every_fmu("instantiate_refuses_a_wrong_null_or_empty_guid_with_a_message");
}

#[test]
fn instantiate_refuses_a_null_or_empty_instance_name_with_a_message() {
    on_every_fmu("instantiate_refuses_a_null_or_empty_instance_name_with_a_message");
}

#[test]
fn instantiate_refuses_model_exchange_and_unknown_types_with_a_message() {
    on_every_fmu("instantiate_refuses_model_exchange_and_unknown_types_with_a_message");
}

#[test]
fn instantiate_without_callbacks_or_logger_returns_null_without_crashing() {
    on_every_fmu("instantiate_without_callbacks_or_logger_returns_null_without_crashing");
}

#[test]
fn instantiate_accepts_every_resource_location_form_and_a_missing_folder() {
    on_every_fmu("instantiate_accepts_every_resource_location_form_and_a_missing_folder");
}

#[test]
fn unknown_value_references_are_refused_with_a_message_naming_them() {
    on_every_fmu("unknown_value_references_are_refused_with_a_message_naming_them");
}

#[test]
fn zero_values_with_null_arrays_are_fine_and_null_arrays_with_values_are_refused() {
    on_every_fmu("zero_values_with_null_arrays_are_fine_and_null_arrays_with_values_are_refused");
}

#[test]
fn each_variable_can_be_set_exactly_where_the_standard_allows_it() {
    on_every_fmu("each_variable_can_be_set_exactly_where_the_standard_allows_it");
}

#[test]
fn nan_and_infinite_values_are_refused_with_a_message_and_change_nothing() {
    on_every_fmu("nan_and_infinite_values_are_refused_with_a_message_and_change_nothing");
}

#[test]
fn a_tunable_parameter_set_between_steps_takes_effect_at_the_next_step() {
    on_every_fmu("a_tunable_parameter_set_between_steps_takes_effect_at_the_next_step");
}

#[test]
fn do_step_refuses_a_step_size_that_is_not_finite_and_positive() {
    on_every_fmu("do_step_refuses_a_step_size_that_is_not_finite_and_positive");
}

#[test]
fn do_step_compares_the_communication_point_with_a_relative_tolerance() {
    on_every_fmu("do_step_compares_the_communication_point_with_a_relative_tolerance");
}

#[test]
fn do_step_beyond_the_stop_time_is_refused() {
    on_every_fmu("do_step_beyond_the_stop_time_is_refused");
}

#[test]
fn a_huge_step_completes_or_is_discarded_and_the_status_functions_tell_the_truth() {
    on_every_fmu("a_huge_step_completes_or_is_discarded_and_the_status_functions_tell_the_truth");
}

#[test]
fn status_functions_report_the_last_successful_time_and_no_termination_request() {
    on_every_fmu("status_functions_report_the_last_successful_time_and_no_termination_request");
}

#[test]
fn reset_from_every_state_then_a_rerun_is_bit_identical() {
    on_every_fmu("reset_from_every_state_then_a_rerun_is_bit_identical");
}

#[test]
fn the_log_categories_importers_look_for_are_declared() {
    on_every_fmu("the_log_categories_importers_look_for_are_declared");
}

#[test]
fn debug_logging_follows_logging_on_and_set_debug_logging() {
    on_every_fmu("debug_logging_follows_logging_on_and_set_debug_logging");
}

#[test]
fn set_debug_logging_refuses_unknown_categories_and_null_arrays() {
    on_every_fmu("set_debug_logging_refuses_unknown_categories_and_null_arrays");
}

#[test]
fn a_percent_sign_in_a_message_reaches_the_logger_verbatim() {
    on_every_fmu("a_percent_sign_in_a_message_reaches_the_logger_verbatim");
}

#[test]
fn each_instance_logs_to_its_own_component_environment() {
    on_every_fmu("each_instance_logs_to_its_own_component_environment");
}

#[test]
fn reference_results_are_reproduced_by_the_default_experiment() {
    on_every_fmu("reference_results_are_reproduced_by_the_default_experiment");
}

#[test]
fn free_instance_frees_an_instance_in_every_state_without_crashing() {
    on_every_fmu("free_instance_frees_an_instance_in_every_state_without_crashing");
}

#[test]
fn the_binary_knows_every_variable_its_description_declares() {
    on_every_fmu("the_binary_knows_every_variable_its_description_declares");
}
