//! The FMI 3.0 checks (`fmi_conformance::fmi3::checks`) on every packaged FMI 3.0 FMU of
//! `target/fmu/fmi3` (`cargo run --release -p fmu-build -- build --workspace` makes them).
//!
//! Thin callers: each test runs its check on every FMI 3.0 FMU, strictly (a skip other than
//! "not declared by the FMU", or a part left untested, fails: these are this exporter's FMUs).
//! It fails when `target/fmu/fmi3` holds no FMU.

use fmi_conformance::checks::on_every_fmu;

#[test]
fn fmi3_the_binary_exports_every_fmi3_function_and_no_others() {
    on_every_fmu("fmi3_the_binary_exports_every_fmi3_function_and_no_others");
}

#[test]
fn fmi3_get_version_is_3_0() {
    on_every_fmu("fmi3_get_version_is_3_0");
}

#[test]
fn fmi3_instantiate_refuses_a_wrong_or_null_token_or_name_and_event_mode_with_null() {
    on_every_fmu("fmi3_instantiate_refuses_a_wrong_or_null_token_or_name_and_event_mode_with_null");
}

#[test]
fn fmi3_bad_arguments_are_refused_with_a_message_and_change_nothing() {
    on_every_fmu("fmi3_bad_arguments_are_refused_with_a_message_and_change_nothing");
}

#[test]
fn fmi3_each_variable_can_be_set_exactly_where_the_standard_allows_it() {
    on_every_fmu("fmi3_each_variable_can_be_set_exactly_where_the_standard_allows_it");
}

#[test]
fn fmi3_start_values_are_readable_in_instantiated() {
    on_every_fmu("fmi3_start_values_are_readable_in_instantiated");
}

#[test]
fn fmi3_the_time_variable_reads_the_current_time_and_cannot_be_set() {
    on_every_fmu("fmi3_the_time_variable_reads_the_current_time_and_cannot_be_set");
}

#[test]
fn fmi3_do_step_output_arguments_are_truthful() {
    on_every_fmu("fmi3_do_step_output_arguments_are_truthful");
}

#[test]
fn fmi3_set_debug_logging_refuses_unknown_categories() {
    on_every_fmu("fmi3_set_debug_logging_refuses_unknown_categories");
}

#[test]
fn fmi3_co_simulation_every_function_in_every_state_answers_as_the_standard_says() {
    on_every_fmu("fmi3_co_simulation_every_function_in_every_state_answers_as_the_standard_says");
}

#[test]
fn fmi3_model_exchange_every_function_in_every_state_answers_as_the_standard_says() {
    on_every_fmu("fmi3_model_exchange_every_function_in_every_state_answers_as_the_standard_says");
}

#[test]
fn fmi3_reset_from_every_state_then_a_rerun_is_bit_identical() {
    on_every_fmu("fmi3_reset_from_every_state_then_a_rerun_is_bit_identical");
}

#[test]
fn fmi3_after_fmi3_error_the_instance_is_terminated_until_reset_or_set_fmu_state() {
    on_every_fmu("fmi3_after_fmi3_error_the_instance_is_terminated_until_reset_or_set_fmu_state");
}

#[test]
fn fmi3_a_null_instance_is_refused_by_every_function() {
    on_every_fmu("fmi3_a_null_instance_is_refused_by_every_function");
}

#[test]
fn fmi3_structural_parameters_are_set_in_configuration_mode_and_size_the_arrays() {
    on_every_fmu("fmi3_structural_parameters_are_set_in_configuration_mode_and_size_the_arrays");
}

#[test]
fn fmi3_scheduled_execution_activates_the_partitions_at_their_clocks_and_signals_the_clock_updates() {
    on_every_fmu("fmi3_scheduled_execution_activates_the_partitions_at_their_clocks_and_signals_the_clock_updates");
}

#[test]
fn fmi3_model_exchange_states_and_derivatives_are_consistent() {
    on_every_fmu("fmi3_model_exchange_states_and_derivatives_are_consistent");
}

#[test]
fn fmi3_model_exchange_an_explicit_euler_run_follows_the_co_simulation_run() {
    on_every_fmu("fmi3_model_exchange_an_explicit_euler_run_follows_the_co_simulation_run");
}

#[test]
fn fmi3_model_exchange_events_are_reached_settle_and_follow_the_states() {
    on_every_fmu("fmi3_model_exchange_events_are_reached_settle_and_follow_the_states");
}

#[test]
fn fmi3_co_simulation_event_mode_hands_the_events_to_the_importer() {
    on_every_fmu("fmi3_co_simulation_event_mode_hands_the_events_to_the_importer");
}

#[test]
fn fmi3_co_simulation_directional_derivatives_match_finite_differences_and_the_adjoint_is_the_transpose() {
    on_every_fmu(
        "fmi3_co_simulation_directional_derivatives_match_finite_differences_and_the_adjoint_is_the_transpose",
    );
}

#[test]
fn fmi3_model_exchange_directional_derivatives_match_finite_differences_and_the_adjoint_is_the_transpose() {
    on_every_fmu(
        "fmi3_model_exchange_directional_derivatives_match_finite_differences_and_the_adjoint_is_the_transpose",
    );
}

#[test]
fn fmi3_fmu_state_get_set_and_serialize_round_trips_continue_bit_identically() {
    on_every_fmu("fmi3_fmu_state_get_set_and_serialize_round_trips_continue_bit_identically");
}

#[test]
fn fmi3_damaged_serialized_states_and_states_of_other_fmus_are_refused() {
    on_every_fmu("fmi3_damaged_serialized_states_and_states_of_other_fmus_are_refused");
}

/// The other process is this crate's `fmu-check`, started as a worker.
#[test]
fn fmi3_a_state_serialized_here_restores_in_another_process_and_continues_identically() {
    fmi_conformance::set_worker(fmi_conformance::Worker {
        exe: env!("CARGO_BIN_EXE_fmu-check").into(),
        args_prefix: vec!["__worker".into()],
    });
    on_every_fmu("fmi3_a_state_serialized_here_restores_in_another_process_and_continues_identically");
}

#[test]
fn fmi3_interleaved_instances_and_instances_on_threads_match_a_single_run() {
    on_every_fmu("fmi3_interleaved_instances_and_instances_on_threads_match_a_single_run");
}

#[test]
fn fmi3_random_call_sequences_never_crash_and_keep_status_consistent() {
    crate::random_sequences::announce_seed("fmi3_random_call_sequences_never_crash_and_keep_status_consistent");
    on_every_fmu("fmi3_random_call_sequences_never_crash_and_keep_status_consistent");
}

#[test]
fn fmi3_a_c_host_runs_co_simulation_and_model_exchange_clean_under_valgrind() {
    on_every_fmu("fmi3_a_c_host_runs_co_simulation_and_model_exchange_clean_under_valgrind");
}

/// The runner picks the FMI 3.0 checks for an FMI 3.0 file by its fmiVersion (what `cargo fmu
/// check X.fmu` and `fmu-check X.fmu` do), each in a worker process.
#[test]
fn the_runner_checks_a_3_0_file_with_the_3_0_checks() {
    use fmi_conformance::outcome::Outcome;
    use fmi_conformance::runner::{RunOptions, run};
    let fmu = fmi_conformance::all::<fmi_conformance::Fmu3>()
        .first()
        .expect("an FMI 3.0 FMU")
        .archive
        .clone();
    let mut o = RunOptions::new(env!("CARGO_BIN_EXE_fmu-check"), vec!["__worker".into()]);
    o.filter = Some("fmi3_get_version".into());
    let report = run(&fmu, &o);
    assert!(report.load_error.is_none(), "{report}");
    assert_eq!(report.checks.len(), 1, "{report}");
    assert_eq!(report.checks[0].name, "fmi3_get_version_is_3_0", "{report}");
    assert_eq!(report.checks[0].outcome, Outcome::Pass, "{report}");
    assert!(report.about.iter().any(|l| l.contains("FMI 3.0")), "{report}");
}

#[test]
fn fmi3_reference_results_are_reproduced_by_the_default_experiment() {
    on_every_fmu("fmi3_reference_results_are_reproduced_by_the_default_experiment");
}

#[test]
fn fmi3_free_instance_frees_an_instance_in_every_state_without_crashing() {
    on_every_fmu("fmi3_free_instance_frees_an_instance_in_every_state_without_crashing");
}

#[test]
fn fmi3_the_binary_knows_every_variable_its_description_declares() {
    on_every_fmu("fmi3_the_binary_knows_every_variable_its_description_declares");
}
