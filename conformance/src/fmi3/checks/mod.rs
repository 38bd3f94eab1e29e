//! The FMI 3.0 checks, by concern, as the FMI 2.0 ones in [`crate::checks`] (whose
//! [`crate::checks::all_checks`] lists both; what a check is: [`crate::registry`]). Each is a
//! `fn(&Fmu3)` that returns when the FMU passed and panics with what was expected and what came
//! instead when it did not (skips and limitations as in [`crate::outcome`]). Written from the FMI 3.0 standard: the state machine
//! of section 4.2.x / 3.2.x (Co-Simulation, Model Exchange; its table is [`table`]), the
//! function descriptions of section 2.3, the model description of section 2.4; nothing here
//! knows rustfmu or a particular model.
//!
//! This module holds what several of them use: bringing an instance into a state, the inputs'
//! excitation, a whole run.

pub mod calls;
pub mod clocks;
pub mod co_simulation;
pub mod directional_derivatives;
pub mod fmu_state;
pub mod instances;
pub mod memory;
pub mod model_exchange;
pub mod native;
pub mod random_sequences;
pub mod reference_results;
pub mod scheduled_execution;
pub mod state_machine;
pub mod structural;
pub mod table;
pub mod types;

pub use random_sequences::replay;

use super::standard::{State, settable_in};
use super::types::*;
use super::{Fmu3, Inst, Type, Variable, euler_step};
use crate::outcome::{info, limitation, skip, skip_not_declared};
use md_reader::{Causality, Initial, Variability};
use std::ffi::CString;
use std::ptr::{null, null_mut};

crate::registry::registry! {
    /// The FMI 3.0 checks.
    const FMI3 = Fmi3 {
        Native: native::{
            fmi3_the_binary_exports_every_fmi3_function_and_no_others,
        };
        Calls: calls::{
            fmi3_get_version_is_3_0,
            fmi3_instantiate_refuses_a_wrong_or_null_token_or_name_and_event_mode_with_null,
            fmi3_bad_arguments_are_refused_with_a_message_and_change_nothing,
            fmi3_each_variable_can_be_set_exactly_where_the_standard_allows_it,
            fmi3_start_values_are_readable_in_instantiated,
            fmi3_the_time_variable_reads_the_current_time_and_cannot_be_set,
            fmi3_do_step_output_arguments_are_truthful,
            fmi3_getters_write_no_value_past_the_array_they_are_given,
            fmi3_do_step_advances_time_by_the_step,
            fmi3_free_instance_frees_an_instance_in_every_state_without_crashing,
            fmi3_the_binary_knows_every_variable_its_description_declares,
            fmi3_intermediate_update_names_times_inside_the_step_and_returns_early_where_asked,
            fmi3_output_derivatives_agree_with_finite_differences_of_the_outputs,
            fmi3_set_debug_logging_refuses_unknown_categories,
        };
        Calls: types::{
            fmi3_every_type_reads_its_start_sets_reads_back_and_refuses_outside_its_bounds,
            fmi3_variable_dependencies_equal_the_model_structure,
        };
        StateMachine: state_machine::{
            fmi3_co_simulation_every_function_in_every_state_answers_as_the_standard_says,
            fmi3_model_exchange_every_function_in_every_state_answers_as_the_standard_says,
            fmi3_reset_from_every_state_then_a_rerun_is_bit_identical,
            fmi3_after_fmi3_error_the_instance_is_terminated_until_reset_or_set_fmu_state,
            fmi3_a_null_instance_is_refused_by_every_function,
        };
        StateMachine: structural::{
            fmi3_structural_parameters_are_set_in_configuration_mode_and_size_the_arrays,
        };
        ModelExchange: model_exchange::{
            fmi3_model_exchange_states_and_derivatives_are_consistent,
            fmi3_model_exchange_an_explicit_euler_run_follows_the_co_simulation_run,
            fmi3_model_exchange_events_are_reached_settle_and_follow_the_states,
            fmi3_co_simulation_event_mode_hands_the_events_to_the_importer,
        };
        ModelExchange: clocks::{
            fmi3_clocks_tick_where_their_intervals_say_and_clocked_variables_are_read_at_the_ticks,
        };
        StateMachine: scheduled_execution::{
            fmi3_scheduled_execution_activates_the_partitions_at_their_clocks_and_signals_the_clock_updates,
        };
        DirectionalDerivatives: directional_derivatives::{
            fmi3_co_simulation_directional_derivatives_match_finite_differences_and_the_adjoint_is_the_transpose,
            fmi3_model_exchange_directional_derivatives_match_finite_differences_and_the_adjoint_is_the_transpose,
        };
        FmuState: fmu_state::{
            fmi3_fmu_state_get_set_and_serialize_round_trips_continue_bit_identically,
            fmi3_serialized_state_fits_its_announced_size,
            fmi3_damaged_serialized_states_and_states_of_other_fmus_are_refused,
            fmi3_a_state_serialized_here_restores_in_another_process_and_continues_identically,
        };
        Instances: instances::{
            fmi3_interleaved_instances_and_instances_on_threads_match_a_single_run,
        };
        Memory: memory::{
            fmi3_ten_thousand_instantiate_free_cycles_leave_memory_flat,
        };
        RandomSequences: random_sequences::{
            fmi3_random_call_sequences_never_crash_and_keep_status_consistent,
        };
        Calls: reference_results::{
            fmi3_reference_results_are_reproduced_by_the_default_experiment,
        };
        Native: native::{
            fmi3_a_c_host_runs_co_simulation_and_model_exchange_clean_under_valgrind,
        };
    }
}

// ---------------------------------------------------------------------------------------------
// Helpers

fn cs_only(fmu: &Fmu3) {
    if fmu.md.cs.is_none() {
        skip_not_declared("<CoSimulation>");
    }
}
fn me_only(fmu: &Fmu3) {
    if fmu.md.me.is_none() {
        skip_not_declared("<ModelExchange>");
    }
}

/// An instance of the interface brought into `state`.
fn in_state(fmu: &Fmu3, me: bool, state: State) -> Inst<'_> {
    let mut i = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
    let id = &fmu.id;
    let api = &fmu.api;
    if state == State::Instantiated {
        return i;
    }
    assert_eq!(
        i.enter_init(0.0),
        fmi3OK,
        "{id}: fmi3EnterInitializationMode: {}",
        i.log_text()
    );
    if state == State::InitializationMode {
        return i;
    }
    assert_eq!(
        i.exit_init(),
        fmi3OK,
        "{id}: fmi3ExitInitializationMode: {}",
        i.log_text()
    );
    if me {
        i.event_iteration();
        if state == State::ContinuousTimeMode {
            assert_eq!(
                i.unary("fmi3EnterContinuousTimeMode", api.enter_continuous_time_mode),
                fmi3OK
            );
        }
    }
    if state == State::Terminated {
        assert_eq!(
            i.unary("fmi3Terminate", api.terminate),
            fmi3OK,
            "{id}: fmi3Terminate: {}",
            i.log_text()
        );
    }
    i
}

/// The continuous Float64 inputs (not clocked): the scalars, then the arrays (each element a
/// value, the structural parameters at their starts).
fn float_inputs(fmu: &Fmu3) -> Vec<&Variable> {
    let continuous_input = |v: &&Variable| v.causality == Causality::Input && v.variability == Variability::Continuous;
    fmu.md
        .of_type(Type::Float64)
        .filter(continuous_input)
        .chain(
            fmu.md
                .variables
                .iter()
                .filter(|v| v.ty == Type::Float64 && v.array && v.clocks.is_empty())
                .filter(continuous_input),
        )
        .collect()
}

/// A name for each value of the variables, one after the other: the name of a scalar, the name
/// and the 1-based indices of each element of an array, row-major (`A[2,1]`), at the start sizes.
fn element_labels(fmu: &Fmu3, vars: &[&Variable]) -> Vec<String> {
    let mut out = vec![];
    for v in vars {
        if !v.array {
            out.push(v.name.clone());
            continue;
        }
        let dims = fmu.dims_at(v, fmu.start_sizes());
        for k in 0..fmu.element_count(v) {
            let (mut rest, mut index) = (k as u64, vec![0; dims.len()]);
            for (d, n) in dims.iter().enumerate().rev() {
                index[d] = rest % n + 1;
                rest /= n;
            }
            let index: Vec<String> = index.iter().map(u64::to_string).collect();
            out.push(format!("{}[{}]", v.name, index.join(",")));
        }
    }
    out
}

/// A moderate excitation of every continuous Float64 input (inside min/max): 0.1, 0.2, ... one
/// after the other over the inputs of [`float_inputs`] and their elements.
fn excitation(fmu: &Fmu3) -> Vec<(&Variable, Vec<f64>)> {
    let mut k = 0;
    float_inputs(fmu)
        .into_iter()
        .map(|v| {
            let values = (0..fmu.element_count(v))
                .map(|_| {
                    k += 1;
                    let mut x = 0.1 * k as f64;
                    if let Some(lo) = v.min {
                        x = x.max(lo);
                    }
                    if let Some(hi) = v.max {
                        x = x.min(hi);
                    }
                    x
                })
                .collect();
            (v, values)
        })
        .collect()
}

/// Sets the [`excitation`] (one fmi3SetFloat64 of every input's elements).
fn excite(inst: &Inst) {
    set_excitation(inst, true);
}

/// [`excite`] of the scalar inputs only (the structural-parameter check sets the arrays with
/// the sizes it gave them).
fn excite_scalars(inst: &Inst) {
    set_excitation(inst, false);
}

fn set_excitation(inst: &Inst, arrays: bool) {
    let (vrs, vals): (Vec<u32>, Vec<Vec<f64>>) = excitation(inst.fmu)
        .into_iter()
        .filter(|(v, _)| arrays || !v.array)
        .map(|(v, x)| (v.vr, x))
        .unzip();
    assert_eq!(
        inst.set_f64(&vrs, &vals.concat()),
        fmi3OK,
        "{}: setting the inputs: {}",
        inst.fmu.id,
        inst.log_text()
    );
}

/// A run: excitation, initialization, `steps` steps of `h`; every Float64 after each step.
fn run(fmu: &Fmu3, me: bool, steps: usize, h: f64) -> Vec<Vec<u64>> {
    let mut i = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
    excite(&i);
    i.initialize();
    (0..steps)
        .map(|_| {
            i.step(h);
            i.observe()
        })
        .collect()
}

/// Runs `call`, an importer's mistake made on purpose through a method of [`Inst`] that records
/// its arguments in the call log (so that a failure or warning after it leaves a reproducer that
/// makes it again), which should be refused with fmi3Error, with a message; then the Float64
/// values should be what they were (`what` says what was passed). Warnings, not failures: FMI
/// 3.0.2 §2.2.4 says "When detecting illegal arguments or a function call not allowed in the
/// current state according to the respective state machine, the FMU must return fmi3Error" and
/// leaves the detection to the FMU; after fmi3Error "the simulation cannot be continued" with the
/// instance, so what it shows then is beyond the standard too. A crash in `call` is a warning
/// ([`crate::outcome::on_purpose`]). A warning's reproducer expects fmi3Error of the call.
fn refused_by(inst: &Inst, what: &str, call: impl FnOnce() -> fmi3Status) {
    let before = inst.observe();
    let s = crate::outcome::on_purpose(call);
    if s != fmi3Error {
        crate::calllog::warning_requires(crate::replay::Expected::ERROR);
        crate::outcome::warn(format!(
            "{}: {what}: expected fmi3Error, got {} (an importer's mistake not detected)",
            inst.fmu.id,
            status_name(s)
        ));
        return;
    }
    crate::outcome::warn_unless(inst.observe() == before, || {
        format!(
            "{}: {what} was refused but changed values (robustness beyond FMI 3.0.2 §2.2.4, which leaves the instance undefined after fmi3Error)",
            inst.fmu.id
        )
    });
}

/// The scalar variables of element `ty` that have a start value in the description (FMI 3.0,
/// 2.4.7.4: inputs, and initial exact or approx; never the independent variable).
fn with_start(fmu: &Fmu3, ty: Type) -> impl Iterator<Item = &Variable> {
    fmu.md.of_type(ty).filter(|v| {
        !v.array
            && v.causality != Causality::Independent
            && v.start.is_some()
            && (v.causality == Causality::Input
                || matches!(
                    crate::standard::initial(v.causality, v.variability, v.declared_initial),
                    Some(Initial::Exact | Initial::Approx)
                ))
    })
}

fn start_vrs(fmu: &Fmu3, ty: Type) -> Vec<u32> {
    with_start(fmu, ty).map(|v| v.vr).collect()
}
