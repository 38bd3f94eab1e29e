//! Model exchange, where the FMU declares it, for every packaged FMU (the checks are
//! `fmi_conformance::checks::model_exchange`).
//!
//! Thin callers: each test runs its check on every FMU of target/fmu, strictly (a part left
//! untested fails; a skip only where the FMU declares no <ModelExchange>).

use fmi_conformance::checks::on_every_fmu;

#[test]
fn model_exchange_every_function_in_every_state_answers_as_the_standard_says() {
    on_every_fmu("model_exchange_every_function_in_every_state_answers_as_the_standard_says");
}

#[test]
fn a_co_simulation_instance_refuses_every_model_exchange_function() {
    on_every_fmu("a_co_simulation_instance_refuses_every_model_exchange_function");
}

#[test]
fn model_exchange_functions_refuse_a_null_component() {
    on_every_fmu("model_exchange_functions_refuse_a_null_component");
}

#[test]
fn model_exchange_bad_arguments_are_refused_with_a_message_and_change_nothing() {
    on_every_fmu("model_exchange_bad_arguments_are_refused_with_a_message_and_change_nothing");
}

#[test]
fn model_exchange_each_variable_can_be_set_exactly_where_the_standard_allows_it() {
    on_every_fmu("model_exchange_each_variable_can_be_set_exactly_where_the_standard_allows_it");
}

#[test]
fn model_exchange_states_and_derivatives_are_declared_consistent_and_deterministic() {
    on_every_fmu("model_exchange_states_and_derivatives_are_declared_consistent_and_deterministic");
}

#[test]
fn model_exchange_new_discrete_states_fills_the_event_info_sensibly() {
    on_every_fmu("model_exchange_new_discrete_states_fills_the_event_info_sensibly");
}

#[test]
fn model_exchange_an_explicit_euler_run_gives_finite_outputs() {
    on_every_fmu("model_exchange_an_explicit_euler_run_gives_finite_outputs");
}

#[test]
fn model_exchange_events_are_reached_settle_and_follow_the_states() {
    on_every_fmu("model_exchange_events_are_reached_settle_and_follow_the_states");
}

#[test]
fn model_exchange_fmu_states_in_event_and_continuous_time_mode_continue_bit_identically() {
    on_every_fmu("model_exchange_fmu_states_in_event_and_continuous_time_mode_continue_bit_identically");
}
