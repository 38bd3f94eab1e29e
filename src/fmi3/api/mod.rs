//! The C boundary of FMI 3.0: the `fmi3*` functions that FMI 2.0 does not share, generic over
//! the model (the shared ones are [`crate::core::shared`], called with [`TERMS`]). The export
//! macro ([`export_fmi3!`](crate::export_fmi3)) forwards the `#[no_mangle]` symbols here. The
//! instance core and the guard around every call (NULL checks, the re-entrancy refusal,
//! `catch_unwind`) are the version-neutral [`crate::core`]'s; what differs in 3.0 is here: the
//! instantiation functions and their callback, typed getters and setters with `nValues`, the
//! independent variable `time`, Int64 enumerations, C `bool` booleans, the output arguments of
//! fmi3DoStep and fmi3UpdateDiscreteStates, and the adjoint derivative.
//!
//! # Safety
//! Every `unsafe fn` here has the contract of the `fmi3*` function it implements, which the
//! standard puts on the importer: the instance handle is NULL or one that an instantiation
//! function of this library returned for model `M` and that was not freed; every other pointer
//! is NULL or valid as the standard describes it (an array of the length passed beside it, a
//! NUL-terminated string, a writable output). Each `unsafe` block says which part of that, and
//! which check, makes its pointer operation sound.
//!
//! One file per concern: instantiation (`instantiate`), the typed getters and setters
//! (`values`), dependencies and derivatives (`derivatives`), clocks (`clocks`); here the
//! lifecycle, the step and the model-exchange functions whose form is 3.0's own.
#![allow(clippy::missing_safety_doc, clippy::too_many_arguments)]

mod clocks;
mod derivatives;
mod instantiate;
mod values;

pub use clocks::*;
pub use derivatives::*;
pub use instantiate::*;
pub use values::*;

use super::TERMS;
use super::abi::*;
use crate::core::guard::{Component, slice, slice_mut, text, with_instance};
use crate::core::instance::{EventInfo, Instance};
use crate::core::logging::{Callback, Category, Logger};
use crate::core::machine::{Call, State};
use crate::description::VarType;
use crate::model::CoSimulation;
use crate::value::{FmiType, Value};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::ptr;

pub fn get_version() -> *const std::os::raw::c_char {
    VERSION.as_ptr()
}

/// fmi3ActivateModelPartition (Scheduled Execution): the partition of input clock
/// `clock_reference` runs at `activation_time` (`Instance::activate_model_partition`). When it
/// ticked an output clock or gave a countdown clock its interval, the importer's clockUpdate
/// callback is called after the call has left the instance, in Clock Update Mode: from inside it
/// the importer reads fmi3GetClock, fmi3GetIntervalDecimal and the variables; when it returns, the
/// instance is back in Clock Activation Mode and the output clocks are inactive. Another thread's
/// call waits until all of this is done.
pub unsafe fn activate_model_partition<M: CoSimulation>(
    c: Option<&Component<M>>,
    clock_reference: fmi3ValueReference,
    activation_time: fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3ActivateModelPartition";
    let Some(component) = c else {
        return fmi3Error;
    };
    component.exclusive(|| {
        let mut notify = None;
        let status = component.run(Call::ActivateModelPartition, F, |inst| {
            match inst.activate_model_partition(F, clock_reference, activation_time) {
                Ok(true) => {
                    if let Some(callback) = &inst.clock_update {
                        inst.sim.state = State::ClockUpdateMode;
                        notify = Some(callback.clone());
                    }
                    fmi3OK
                }
                Ok(false) => fmi3OK,
                Err(status) => status,
            }
        });
        if let Some(callback) = notify {
            component.in_callback.store(true, std::sync::atomic::Ordering::Release);
            let _ = catch_unwind(AssertUnwindSafe(|| callback()));
            component.in_callback.store(false, std::sync::atomic::Ordering::Release);
            component.run_internal(F, |inst| inst.end_clock_update());
        }
        status
    })
}

pub fn enter_initialization_mode<M: CoSimulation>(
    c: Option<&Component<M>>,
    tolerance_defined: fmi3Boolean,
    tolerance: fmi3Float64,
    start_time: fmi3Float64,
    stop_time_defined: fmi3Boolean,
    stop_time: fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3EnterInitializationMode";
    with_instance(c, Call::EnterInitializationMode, F, |inst| {
        inst.trace(|| {
            format!(
                "{F}(toleranceDefined = {tolerance_defined}, tolerance = {tolerance}, startTime = {start_time}, \
                 stopTimeDefined = {stop_time_defined}, stopTime = {stop_time})"
            )
        });
        let status = inst.setup_experiment(
            tolerance_defined.then_some(tolerance),
            start_time,
            stop_time_defined.then_some(stop_time),
        );
        if status != fmi3OK {
            return status;
        }
        inst.enter_initialization_mode()
    })
}

/// A function of a feature this FMU does not have (clocks, configuration mode, variable
/// dependencies at run time): fmi3Error with the reason, in any state.
pub fn not_provided<M: CoSimulation>(
    c: Option<&Component<M>>,
    function: &'static str,
    why: &'static str,
) -> fmi3Status {
    with_instance(c, Call::SetDebugLogging, function, |inst| {
        inst.error(&format!("{function}: {why}"))
    })
}

pub fn evaluate_discrete_states<M: CoSimulation>(c: Option<&Component<M>>) -> fmi3Status {
    with_instance(
        c,
        Call::EvaluateDiscreteStates,
        "fmi3EvaluateDiscreteStates",
        // The tick of the active clocks, if there is one to compute (else nothing to evaluate).
        |inst| match inst.evaluate_tick("fmi3EvaluateDiscreteStates", false) {
            Ok(()) => fmi3OK,
            Err(status) => status,
        },
    )
}

const NO_CONFIGURATION: &str = "this FMU has no structural parameters, so there is no configuration mode";

/// fmi3EnterConfigurationMode of an FMU with structural parameters (one without has none: the
/// export refuses the call with the reason).
pub fn enter_configuration_mode<M: CoSimulation>(c: Option<&Component<M>>) -> fmi3Status {
    configuration_mode(
        c,
        "fmi3EnterConfigurationMode",
        Call::EnterConfigurationMode,
        Instance::enter_configuration_mode,
    )
}

/// fmi3ExitConfigurationMode.
pub fn exit_configuration_mode<M: CoSimulation>(c: Option<&Component<M>>) -> fmi3Status {
    configuration_mode(
        c,
        "fmi3ExitConfigurationMode",
        Call::ExitConfigurationMode,
        Instance::exit_configuration_mode,
    )
}

/// Entering or leaving Configuration Mode (`change`, the state table's row `call`): refused with
/// the reason by an FMU without structural parameters.
fn configuration_mode<M: CoSimulation>(
    c: Option<&Component<M>>,
    function: &'static str,
    call: Call,
    change: fn(&mut Instance<M>, &str) -> fmi3Status,
) -> fmi3Status {
    if !const { M::DESCRIPTION.has_structural_parameters() } {
        return not_provided::<M>(c, function, NO_CONFIGURATION);
    }
    with_instance(c, call, function, |inst| change(inst, function))
}

pub fn enter_step_mode<M: CoSimulation>(c: Option<&Component<M>>) -> fmi3Status {
    with_instance(c, Call::EnterStepMode, "fmi3EnterStepMode", |inst| {
        inst.enter_step_mode()
    })
}

/// fmi3UpdateDiscreteStates: the event iteration's answers through the importer's six pointers.
/// Its own body, not one shared with fmi2NewDiscreteStates through a writer closure: that cost a
/// clock tick 22 instructions (bench/callgrind.sh).
pub unsafe fn update_discrete_states<M: CoSimulation>(
    c: Option<&Component<M>>,
    discrete_states_need_update: *mut fmi3Boolean,
    terminate_simulation: *mut fmi3Boolean,
    nominals_changed: *mut fmi3Boolean,
    values_changed: *mut fmi3Boolean,
    next_event_time_defined: *mut fmi3Boolean,
    next_event_time: *mut fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3UpdateDiscreteStates";
    with_instance(c, Call::NewDiscreteStates, F, |inst| {
        if discrete_states_need_update.is_null()
            || terminate_simulation.is_null()
            || nominals_changed.is_null()
            || values_changed.is_null()
            || next_event_time_defined.is_null()
            || next_event_time.is_null()
        {
            return inst.error(&format!("{F}: an output argument is NULL"));
        }
        let mut e = EventInfo::default();
        let status = inst.new_discrete_states(&mut e);
        // SAFETY: none is NULL (checked above); the contract makes each writable. Written
        // through the raw pointers, which need not be distinct.
        unsafe {
            *discrete_states_need_update = e.new_discrete_states_needed;
            *terminate_simulation = e.terminate_simulation;
            *nominals_changed = e.nominals_changed;
            *values_changed = e.values_changed;
            *next_event_time_defined = e.next_event_time.is_some();
            *next_event_time = e.next_event_time.unwrap_or(0.0);
        }
        status
    })
}

pub unsafe fn get_number_of_continuous_states<M: CoSimulation>(c: Option<&Component<M>>, n: *mut usize) -> fmi3Status {
    // With the structural parameters as they are now (a sized array state).
    let count = |inst: &Instance<M>| crate::core::structural::number_of_states(&inst.sim.model);
    // SAFETY: this function's contract is `number_of`'s.
    unsafe { number_of(c, "fmi3GetNumberOfContinuousStates", "nContinuousStates", n, count) }
}

pub unsafe fn get_number_of_event_indicators<M: CoSimulation>(c: Option<&Component<M>>, n: *mut usize) -> fmi3Status {
    // SAFETY: this function's contract is `number_of`'s.
    unsafe {
        number_of(c, "fmi3GetNumberOfEventIndicators", "nEventIndicators", n, |_| {
            M::INDICATORS.len()
        })
    }
}

/// `function`'s answer `count` written to its output `n` (its parameter `name`).
///
/// # Safety
/// `c` NULL or a live instance of this library for `M`; `n` NULL or writable.
unsafe fn number_of<M: CoSimulation>(
    c: Option<&Component<M>>,
    function: &'static str,
    name: &str,
    n: *mut usize,
    count: impl FnOnce(&Instance<M>) -> usize,
) -> fmi3Status {
    with_instance(c, Call::GetNumberOf, function, |inst| {
        // SAFETY: `as_mut` checks NULL; the contract makes a non-NULL `n` writable.
        match unsafe { n.as_mut() } {
            Some(n) => {
                *n = count(inst);
                fmi3OK
            }
            None => inst.error(&format!("{function}: {name} is NULL")),
        }
    })
}

pub unsafe fn get_output_derivatives<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    orders: *const fmi3Int32,
    values: *mut fmi3Float64,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetOutputDerivatives";
    with_instance(c, Call::GetRealOutputDerivatives, F, |inst| {
        // The outputs of the equations are scalars: one value per value reference.
        if n_values != nvr {
            return inst.error(&format!(
                "{F}: nValues = {n_values} for {nvr} value references: the outputs with derivatives are scalars, one value each"
            ));
        }
        // SAFETY: the arrays are NULL or nvr long (this function's contract).
        match unsafe { (slice(vr, nvr), slice(orders, nvr), slice_mut(values, nvr)) } {
            (Some(vrs), Some(orders), Some(out)) => inst.output_derivatives(F, vrs, orders, out),
            _ => inst.error(&format!(
                "{F}: valueReferences, orders or values is NULL with nValueReferences = {nvr}"
            )),
        }
    })
}

pub unsafe fn do_step<M: CoSimulation>(
    c: Option<&Component<M>>,
    current_communication_point: fmi3Float64,
    communication_step_size: fmi3Float64,
    _no_set_fmu_state_prior_to_current_point: fmi3Boolean,
    event_handling_needed: *mut fmi3Boolean,
    terminate_simulation: *mut fmi3Boolean,
    early_return: *mut fmi3Boolean,
    last_successful_time: *mut fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3DoStep";
    with_instance(c, Call::DoStep, F, |inst| {
        if event_handling_needed.is_null()
            || terminate_simulation.is_null()
            || early_return.is_null()
            || last_successful_time.is_null()
        {
            return inst.error(&format!(
                "{F}: eventHandlingNeeded, terminateSimulation, earlyReturn or lastSuccessfulTime is NULL; no step"
            ));
        }
        let status = inst.do_step(current_communication_point, communication_step_size);
        // An event to handle only with event mode and early return (the step then ends at it).
        let end = current_communication_point + communication_step_size;
        let early = (inst.step_event || inst.returned_early) && inst.sim.last_successful_time < end;
        // SAFETY: none is NULL (checked above); the contract makes each writable. Written
        // through the raw pointers, which need not be distinct.
        unsafe {
            *event_handling_needed = inst.step_event;
            *terminate_simulation = inst.sim.terminate_requested;
            *early_return = early;
            *last_successful_time = inst.sim.last_successful_time;
        }
        status
    })
}
