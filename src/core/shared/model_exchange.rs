//! The lifecycle's transitions and the model-exchange functions of both versions, one body each:
//! each version's exported functions are rows over them (`export_fmi2!`, `export_fmi3!`).
//! fmi2NewDiscreteStates and fmi3UpdateDiscreteStates keep a body each (`fmi2::api`,
//! `fmi3::api`): their outputs differ in form (one struct against six pointers), and a shared
//! body with a writer cost a clock tick 22 instructions.
//!
//! # Safety
//! As for [`super`]: each `unsafe fn` has the contract of the C function it implements.
#![allow(clippy::missing_safety_doc)]

use crate::core::guard::{Component, slice, slice_mut, with_instance};
use crate::core::machine::Call;
use crate::core::{Function, Status, Terms, Version};
use crate::model::CoSimulation;

#[inline(always)]
pub unsafe fn set_continuous_states<M: CoSimulation>(
    terms: &'static Terms,
    c: Option<&Component<M>>,
    x: *const f64,
    nx: usize,
) -> Status {
    let f = terms.name(Function::SetContinuousStates);
    with_instance(c, Call::SetContinuousStates, f, |inst| {
        // SAFETY: `slice` checks NULL; the contract makes `x` hold `nx` values.
        match unsafe { slice(x, nx) } {
            Some(x) => inst.set_continuous_states(f, x),
            None => inst.error(&format!("{f}: x is NULL with nx = {nx}")),
        }
    })
}

/// The model-exchange functions that fill an output array of the instance's size:
/// the continuous states, their derivatives, their nominals, the event indicators.
#[derive(Debug, Clone, Copy)]
pub enum Vector {
    ContinuousStates,
    Derivatives,
    Nominals,
    EventIndicators,
}

/// Inlined into each exported function, so that `which` is a constant there.
#[inline(always)]
pub unsafe fn get_vector<M: CoSimulation>(
    terms: &'static Terms,
    which: Vector,
    c: Option<&Component<M>>,
    out: *mut f64,
    n: usize,
) -> Status {
    let (function, call, arg) = match which {
        Vector::ContinuousStates => (Function::GetContinuousStates, Call::GetContinuousStates, "x"),
        Vector::Derivatives => (Function::GetDerivatives, Call::GetDerivatives, "derivatives"),
        Vector::Nominals => (
            Function::GetNominalsOfContinuousStates,
            Call::GetNominalsOfContinuousStates,
            "x_nominal",
        ),
        Vector::EventIndicators => (
            Function::GetEventIndicators,
            Call::GetEventIndicators,
            "eventIndicators",
        ),
    };
    let f = terms.name(function);
    with_instance(c, call, f, |inst| {
        // SAFETY: `slice_mut` checks NULL; the contract makes `out` hold `n` writable values.
        match unsafe { slice_mut(out, n) } {
            Some(out) => match which {
                Vector::ContinuousStates => inst.get_continuous_states(f, out),
                Vector::Derivatives => inst.get_derivatives(f, out),
                Vector::Nominals => inst.get_nominals(f, out),
                Vector::EventIndicators => inst.get_event_indicators_mut(f, out),
            },
            None => inst.error(&format!("{f}: {arg} is NULL with n = {n}")),
        }
    })
}

/// The calls that take nothing but the instance: the lifecycle's and model exchange's
/// transitions.
#[derive(Debug, Clone, Copy)]
pub enum Transition {
    EnterInitializationMode,
    ExitInitializationMode,
    Terminate,
    Reset,
    EnterEventMode,
    EnterContinuousTimeMode,
}

/// fmi2EnterInitializationMode (3.0's takes the experiment: `fmi3::api`), fmiXExitInitializationMode,
/// fmiXTerminate, fmiXReset, fmiXEnterEventMode, fmiXEnterContinuousTimeMode. Inlined into each
/// exported function, so that `which` is a constant there.
#[inline(always)]
pub fn transition<M: CoSimulation>(terms: &'static Terms, which: Transition, c: Option<&Component<M>>) -> Status {
    let (function, call) = match which {
        Transition::EnterInitializationMode => (Function::EnterInitializationMode, Call::EnterInitializationMode),
        Transition::ExitInitializationMode => (Function::ExitInitializationMode, Call::ExitInitializationMode),
        Transition::Terminate => (Function::Terminate, Call::Terminate),
        Transition::Reset => (Function::Reset, Call::Reset),
        Transition::EnterEventMode => (Function::EnterEventMode, Call::EnterEventMode),
        Transition::EnterContinuousTimeMode => (Function::EnterContinuousTimeMode, Call::EnterContinuousTimeMode),
    };
    let f = terms.name(function);
    // The debug log names every call but FMI 2.0's two model-exchange transitions (as it
    // always has: 2.0 traced its lifecycle calls only).
    let model_exchange = matches!(which, Transition::EnterEventMode | Transition::EnterContinuousTimeMode);
    let traced = terms.version == Version::Fmi3 || !model_exchange;
    with_instance(c, call, f, |inst| {
        if traced {
            inst.trace(|| format!("{f}()"));
        }
        match which {
            Transition::EnterInitializationMode => inst.enter_initialization_mode(),
            Transition::ExitInitializationMode => inst.exit_initialization_mode(),
            Transition::Terminate => inst.terminate(),
            Transition::Reset => inst.reset(),
            Transition::EnterEventMode => inst.enter_event_mode(),
            Transition::EnterContinuousTimeMode => inst.enter_continuous_time_mode(),
        }
    })
}

pub fn set_time<M: CoSimulation>(terms: &'static Terms, c: Option<&Component<M>>, time: f64) -> Status {
    with_instance(c, Call::SetTime, terms.name(Function::SetTime), |inst| {
        inst.set_time(time)
    })
}

/// fmiXCompletedIntegratorStep; `B` is the version's boolean (`fmi2Boolean`, an int, or
/// `fmi3Boolean`, a C `bool`).
pub unsafe fn completed_integrator_step<M: CoSimulation, B: From<bool>>(
    terms: &'static Terms,
    c: Option<&Component<M>>,
    _no_set_fmu_state_prior: B,
    enter_event_mode: *mut B,
    terminate_simulation: *mut B,
) -> Status {
    let f = terms.name(Function::CompletedIntegratorStep);
    with_instance(c, Call::CompletedIntegratorStep, f, |inst| {
        if enter_event_mode.is_null() || terminate_simulation.is_null() {
            return inst.error(&format!("{f}: enterEventMode or terminateSimulation is NULL"));
        }
        let (status, event, terminate) = inst.completed_integrator_step();
        // SAFETY: neither is NULL (checked above); the contract makes both writable. Written
        // through the raw pointers, which need not be distinct.
        unsafe {
            *enter_event_mode = B::from(event);
            *terminate_simulation = B::from(terminate);
        }
        status
    })
}
