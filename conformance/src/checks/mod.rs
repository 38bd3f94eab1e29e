//! The named checks, by group. Each is a `fn(&Fmu)` that returns when the FMU passed and
//! panics with what was expected and what came instead when it did not (see [`crate::outcome`]
//! for skips and limitations).

pub mod calls;
pub mod directional_derivatives;
pub mod fmu_state;
pub mod instances;
pub mod memory;
pub mod model_exchange;
pub mod native;
pub mod random_sequences;
pub mod reference_results;
pub mod state_machine;

use crate::outcome::Outcome;
pub use crate::registry::{Check, Group, Run};
use crate::registry::{Checked, registry};
use crate::{Fmu, Fmu3, Version};

/// Every check of both versions, in report order: the FMI 2.0 ones, then the FMI 3.0 ones.
pub fn all_checks() -> &'static [Check] {
    static ALL: std::sync::OnceLock<Vec<Check>> = std::sync::OnceLock::new();
    ALL.get_or_init(|| [FMI2, crate::fmi3::checks::FMI3].concat())
}

registry! {
    /// The FMI 2.0 checks.
    const FMI2 = Fmi2 {
        Calls: calls::{
            instantiate_refuses_a_wrong_null_or_empty_guid_with_a_message,
            instantiate_refuses_a_null_or_empty_instance_name_with_a_message,
            instantiate_refuses_model_exchange_and_unknown_types_with_a_message,
            instantiate_without_callbacks_or_logger_returns_null_without_crashing,
            instantiate_accepts_every_resource_location_form_and_a_missing_folder,
            unknown_value_references_are_refused_with_a_message_naming_them,
            zero_values_with_null_arrays_are_fine_and_null_arrays_with_values_are_refused,
            each_variable_can_be_set_exactly_where_the_standard_allows_it,
            nan_and_infinite_values_are_refused_with_a_message_and_change_nothing,
            a_tunable_parameter_set_between_steps_takes_effect_at_the_next_step,
            do_step_refuses_a_step_size_that_is_not_finite_and_positive,
            do_step_compares_the_communication_point_with_a_relative_tolerance,
            do_step_beyond_the_stop_time_is_refused,
            a_huge_step_completes_or_is_discarded_and_the_status_functions_tell_the_truth,
            status_functions_report_the_last_successful_time_and_no_termination_request,
            getters_write_no_value_past_the_array_they_are_given,
            do_step_advances_time_by_the_step,
            free_instance_frees_an_instance_in_every_state_without_crashing,
            the_binary_knows_every_variable_its_description_declares,
            reset_from_every_state_then_a_rerun_is_bit_identical,
            the_log_categories_importers_look_for_are_declared,
            debug_logging_follows_logging_on_and_set_debug_logging,
            set_debug_logging_refuses_unknown_categories_and_null_arrays,
            a_percent_sign_in_a_message_reaches_the_logger_verbatim,
            each_instance_logs_to_its_own_component_environment,
            output_derivatives_agree_with_finite_differences_of_the_outputs,
        };
        StateMachine: state_machine::{
            every_function_in_every_state_answers_as_the_standard_says,
            a_null_component_is_refused_by_every_function,
            version_and_platform_are_the_standards,
            terminate_twice_is_refused_with_a_message,
        };
        StateMachine: directional_derivatives::{
            directional_derivative_flag_is_either_value_and_false_means_refused,
        };
        FmuState: fmu_state::{
            every_fmu_declares_it_can_get_set_and_serialize_its_state,
            get_set_free_round_trip_continues_bit_identically,
            a_saved_state_is_a_complete_copy_independent_of_the_instance,
            serialize_deserialize_round_trip_continues_bit_identically,
            serialized_state_fits_its_announced_size,
            the_serialized_state_holds_no_pointers_and_is_versioned,
            damaged_serialized_states_are_refused_with_a_message,
            a_state_serialized_here_restores_in_another_process_and_continues_identically,
        };
        Instances: instances::{
            interleaved_instances_do_not_affect_each_other,
            instances_on_their_own_threads_match_sequential_runs_bit_for_bit,
            the_library_can_be_unloaded_after_the_last_free_and_loaded_again,
        };
        Memory: memory::{
            ten_thousand_instantiate_free_cycles_leave_memory_flat,
        };
        RandomSequences: random_sequences::{
            random_call_sequences_keep_every_fmu_conformant,
            random_model_exchange_call_sequences_keep_every_fmu_conformant,
            regressions_found_by_random_sequences,
        };
        Calls: reference_results::{
            reference_results_are_reproduced_by_the_default_experiment,
        };
        Native: native::{
            a_c_host_runs_every_fmu_with_the_same_results_as_the_rust_importer,
            a_whole_run_of_every_fmu_is_clean_under_valgrind_memcheck,
            the_binary_exports_the_fmi2_functions_and_no_others,
            the_binary_needs_only_the_c_runtime,
        };
        ModelExchange: model_exchange::{
            model_exchange_every_function_in_every_state_answers_as_the_standard_says,
            a_co_simulation_instance_refuses_every_model_exchange_function,
            model_exchange_functions_refuse_a_null_component,
            model_exchange_bad_arguments_are_refused_with_a_message_and_change_nothing,
            model_exchange_each_variable_can_be_set_exactly_where_the_standard_allows_it,
            model_exchange_states_and_derivatives_are_declared_consistent_and_deterministic,
            model_exchange_new_discrete_states_fills_the_event_info_sensibly,
            model_exchange_an_explicit_euler_run_gives_finite_outputs,
            model_exchange_events_are_reached_settle_and_follow_the_states,
            model_exchange_fmu_states_in_event_and_continuous_time_mode_continue_bit_identically,
        };
        DirectionalDerivatives: directional_derivatives::{
            co_simulation_directional_derivatives_match_finite_differences,
            model_exchange_directional_derivatives_match_finite_differences,
            directional_derivatives_refuse_unknown_references_and_null_arrays,
        };
    }
}

/// The checks of one FMI version, in report order.
pub fn checks_of(version: Version) -> impl Iterator<Item = &'static Check> {
    all_checks().iter().filter(move |c| c.version() == version)
}

/// The check of that name (of either version: the FMI 3.0 checks' names begin with `fmi3_`).
pub fn find(name: &str) -> Option<&'static Check> {
    all_checks().iter().find(|c| c.name == name)
}

/// Runs the check of that name on every packaged FMU of its FMI version ([`crate::all`]),
/// strictly, for the workspace's `#[test]`s: every FMU there is this exporter's, so a warning
/// (as under `--strict`), a skip or a limitation is a failure too (but for a skip because the FMU does not declare what the check
/// is about, [`crate::outcome::NOT_DECLARED`]). Panics with every FMU's failure; prints the
/// checks' info lines.
pub fn on_every_fmu(name: &str) {
    let check = find(name).unwrap_or_else(|| panic!("no check named {name} in all_checks()"));
    match check.version() {
        Version::Fmi2 => on_every::<Fmu>(check),
        Version::Fmi3 => on_every::<Fmu3>(check),
    }
}

fn on_every<F: Checked>(check: &Check) {
    // This exporter's FMUs are held to `--strict`.
    crate::outcome::set_strict(true);
    let name = check.name;
    let mut failures = vec![];
    for fmu in crate::all::<F>() {
        let id = fmu.id();
        let (outcome, findings) = check.run_on(fmu);
        for line in &findings.info {
            println!("{id}: {line}");
        }
        match outcome {
            // A part not tested because the FMU declares nothing it is about (no Real input to
            // differentiate by) is the FMU's choice, as a skip for that reason is.
            Outcome::Pass
                if findings.limitations.iter().all(|l| {
                    l.starts_with(crate::outcome::NOT_DECLARED) || l.starts_with(crate::outcome::NOT_EXERCISED)
                }) => {}
            Outcome::Pass => failures.push(format!(
                "{id}: {name} tested only partly: {}",
                findings.limitations.join("; ")
            )),
            // The FMU does not declare the optional interface the check is about.
            Outcome::Skip(why) if why.starts_with(crate::outcome::NOT_DECLARED) => {
                println!("{id}: {name} skipped: {why}")
            }
            Outcome::Skip(why) => failures.push(format!("{id}: {name} skipped: {why}")),
            // Strictly: this exporter's FMUs leave the standard's open cases no warning.
            Outcome::Warn(warnings) => failures.push(format!(
                "{id}: {name} warned (a failure here, as under --strict):\n{warnings}"
            )),
            Outcome::Fail(message) => failures.push(message),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// The failures of a state-table check, one line per function and cause with every state it
/// happened in and the log of the first: one cause (an instance that cannot initialize, say) is
/// reported once, not once per state. `kind`: the states' kind ("model-exchange " or "").
pub(crate) fn one_line_per_cause<S: std::fmt::Debug>(
    fmu_id: &str,
    kind: &str,
    failures: Vec<(&str, String, S, String)>,
) -> Vec<String> {
    let mut grouped: Vec<(&str, String, Vec<S>, String)> = vec![];
    for (function, what, s, log) in failures {
        match grouped.iter_mut().find(|g| g.0 == function && g.1 == what) {
            Some(g) => g.2.push(s),
            None => grouped.push((function, what, vec![s], log)),
        }
    }
    grouped
        .iter()
        .map(|(function, what, states, log)| {
            let many = states.len() > 1;
            format!(
                "{fmu_id}: {function} in {kind}state{} {}: {what}; log{}: {log}",
                if many { "s" } else { "" },
                states.iter().map(|s| format!("{s:?}")).collect::<Vec<_>>().join(", "),
                if many { " (in the first)" } else { "" }
            )
        })
        .collect()
}
