//! The C entry points whose bodies are the same in FMI 2.0 and 3.0 (freeing an instance, debug
//! logging, FMU state, the model-exchange vectors), generic over the model. Each takes the
//! calling layer's [`Terms`], so that its messages name the function the importer called; the
//! layers convert their own argument types (`fmi3Boolean`, `fmi3Byte`) before calling.
//!
//! # Safety
//! Every `unsafe fn` here has the contract of the C function it implements, which the standard
//! puts on the importer: the instance handle is NULL or one this library's instantiation
//! function returned for model `M` and did not free; every other pointer is NULL or valid as
//! the standard describes it (an array of the length passed beside it, a NUL-terminated string,
//! a writable output). Each `unsafe` block below says which part of that, and which check, makes
//! its pointer operation sound.
#![allow(clippy::missing_safety_doc)]

use super::guard::{Component, slice, slice_mut, text, with_instance};
use super::logging::Category;
use super::machine::Call;
use super::{ERROR, Function, OK, Status, Terms, instance, snapshots, state};
use crate::model::CoSimulation;
use std::os::raw::{c_char, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::ptr;
use std::sync::atomic::Ordering;

/// The importer's instance handle (`fmi2Component`, `fmi3Instance`) and FMU state handle
/// (`fmi2FMUstate`, `fmi3FMUState`): both `void *` in both versions.
pub type Handle = *mut c_void;

pub unsafe fn free_instance<M: CoSimulation>(terms: &'static Terms, c: Handle) {
    if c.is_null() {
        return;
    }
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: returned by an instantiation function as a Box<Component<M>> and not freed
        // (the standard forbids using a freed instance).
        let component = unsafe { &*(c as *const Component<M>) };
        if component.in_callback.load(Ordering::Acquire) {
            // From the importer's clockUpdate callback: fmi3ActivateModelPartition still has the
            // instance to finish when the callback returns.
            component.refusals.log(
                ERROR,
                Category::StatusError,
                &format!(
                    "{}: called from the clockUpdate callback (Clock Update Mode), inside fmi3ActivateModelPartition; \
                     the instance is not freed",
                    terms.name(Function::FreeInstance)
                ),
            );
            return;
        }
        if component.busy.swap(true, Ordering::Acquire) {
            // Freeing it now would pull the instance from under the call that is running.
            component.refusals.log(
                ERROR,
                Category::StatusError,
                &format!(
                    "{}: called while a call into this instance is still running; the instance is not freed",
                    terms.name(Function::FreeInstance)
                ),
            );
            return;
        }
        // SAFETY: as above, and no call is inside: freed once.
        drop(unsafe { Box::from_raw(c as *mut Component<M>) });
    }));
}

pub unsafe fn set_debug_logging<M: CoSimulation>(
    terms: &'static Terms,
    c: Handle,
    logging_on: bool,
    n: usize,
    categories: *const *const c_char,
) -> Status {
    let f = terms.name(Function::SetDebugLogging);
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::SetDebugLogging, f, |inst| {
        // SAFETY: `slice` checks NULL; the contract makes `categories` hold `n` strings.
        let Some(cats) = (unsafe { slice(categories, n) }) else {
            return inst.error(&format!("{f}: categories is NULL with nCategories = {n}"));
        };
        let mut names = Vec::with_capacity(n);
        for (i, s) in cats.iter().enumerate() {
            // SAFETY: `text` checks NULL; the contract makes each category NUL-terminated.
            match unsafe { text(*s) } {
                Some(t) => names.push(t.into_owned()),
                None => return inst.error(&format!("{f}: categories[{i}] is NULL")),
            }
        }
        inst.set_debug_logging(f, logging_on, &names)
    })
}

pub unsafe fn get_fmu_state<M: CoSimulation>(terms: &'static Terms, c: Handle, state: *mut Handle) -> Status {
    let (f, arg) = (terms.name(Function::GetFmuState), terms.fmu_state);
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::FmuState, f, |inst| {
        // SAFETY: `as_mut` checks NULL; the contract makes a non-NULL `state` point to the
        // importer's writable FMU state variable.
        let Some(state) = (unsafe { state.as_mut() }) else {
            return inst.error(&format!("{f}: {arg} is NULL"));
        };
        let sim = inst.state_to_save();
        if state.is_null() {
            *state = snapshots::adopt(inst.guid, sim.into_owned());
            return OK;
        }
        // A non-NULL *FMUstate is overwritten in place: it must be one of this FMU's.
        match snapshots::with::<M, _>(terms, inst.guid, *state, |s| s.sim.clone_from(&sim)) {
            Ok(()) => OK,
            Err(why) => inst.error(&format!("{f}: *{arg}: {why}; refused, nothing changed")),
        }
    })
}

pub unsafe fn set_fmu_state<M: CoSimulation>(terms: &'static Terms, c: Handle, state: Handle) -> Status {
    let (f, arg) = (terms.name(Function::SetFmuState), terms.fmu_state);
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::FmuState, f, |inst| {
        if state.is_null() {
            return inst.error(&format!("{f}: {arg} is NULL"));
        }
        let fits = |s: &mut snapshots::Snapshot<M>| s.sim.state;
        match snapshots::with::<M, _>(terms, inst.guid, state, fits) {
            Ok(s) if !inst.state_fits(s) => {
                return inst.error(&format!(
                    "{f}: the state was saved in {}, a state of the other interface \
                     (this instance is {}); refused, nothing changed",
                    terms.state_name(s),
                    if inst.model_exchange {
                        "model exchange"
                    } else {
                        "co-simulation"
                    }
                ));
            }
            Ok(_) => {}
            Err(why) => return inst.error(&format!("{f}: {why}; refused, nothing changed")),
        }
        match snapshots::with::<M, _>(terms, inst.guid, state, |s| inst.sim.clone_from(&s.sim)) {
            Ok(()) => {
                inst.restored();
                OK
            }
            Err(why) => inst.error(&format!("{f}: {why}; refused, nothing changed")),
        }
    })
}

pub unsafe fn free_fmu_state<M: CoSimulation>(terms: &'static Terms, c: Handle, state: *mut Handle) -> Status {
    let f = terms.name(Function::FreeFmuState);
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::FmuState, f, |inst| {
        // SAFETY: `as_mut` checks NULL; the contract makes a non-NULL `state` point to the
        // importer's writable FMU state variable.
        let Some(state) = (unsafe { state.as_mut() }) else {
            return OK;
        };
        if state.is_null() {
            return OK;
        }
        match snapshots::release::<M>(terms, inst.guid, *state) {
            Ok(()) => {
                *state = ptr::null_mut();
                OK
            }
            Err(why) => inst.error(&format!("{f}: {why}; refused, nothing freed")),
        }
    })
}

pub unsafe fn serialized_fmu_state_size<M: CoSimulation>(
    terms: &'static Terms,
    c: Handle,
    state: Handle,
    size: *mut usize,
) -> Status {
    let (f, arg) = (terms.name(Function::SerializedFmuStateSize), terms.fmu_state);
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::FmuState, f, |inst| {
        if state.is_null() || size.is_null() {
            return inst.error(&format!("{f}: {arg} or size is NULL"));
        }
        match snapshots::with::<M, _>(terms, inst.guid, state, |s| state::serialize(inst.guid, &s.sim)) {
            Ok(Ok(bytes)) => {
                // SAFETY: not NULL (checked above); the contract makes `size` writable.
                unsafe { *size = bytes.len() };
                OK
            }
            Ok(Err(why)) | Err(why) => inst.error(&format!("{f}: {why}")),
        }
    })
}

pub unsafe fn serialize_fmu_state<M: CoSimulation>(
    terms: &'static Terms,
    c: Handle,
    state: Handle,
    bytes: *mut c_char,
    size: usize,
) -> Status {
    let (f, arg) = (terms.name(Function::SerializeFmuState), terms.fmu_state);
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::FmuState, f, |inst| {
        if state.is_null() || bytes.is_null() {
            return inst.error(&format!("{f}: {arg} or serializedState is NULL"));
        }
        match snapshots::with::<M, _>(terms, inst.guid, state, |s| state::serialize(inst.guid, &s.sim)) {
            Ok(Ok(data)) if data.len() == size => {
                // SAFETY: `bytes` is not NULL (checked above) and the contract makes it hold
                // `size` bytes, exactly as many as are written; `data` is this library's own.
                unsafe { ptr::copy_nonoverlapping(data.as_ptr(), bytes as *mut u8, size) };
                OK
            }
            Ok(Ok(data)) => inst.error(&format!(
                "{f}: size = {size}, but the state takes {} bytes (ask {})",
                data.len(),
                terms.name(Function::SerializedFmuStateSize)
            )),
            Ok(Err(why)) | Err(why) => inst.error(&format!("{f}: {why}")),
        }
    })
}

pub unsafe fn deserialize_fmu_state<M: CoSimulation>(
    terms: &'static Terms,
    c: Handle,
    bytes: *const c_char,
    size: usize,
    state: *mut Handle,
) -> Status {
    let (f, arg) = (terms.name(Function::DeserializeFmuState), terms.fmu_state);
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::FmuState, f, |inst| {
        // SAFETY: `as_mut` checks NULL; the contract makes a non-NULL `state` point to the
        // importer's writable FMU state variable.
        let Some(state) = (unsafe { state.as_mut() }) else {
            return inst.error(&format!("{f}: {arg} is NULL"));
        };
        // SAFETY: `slice` checks NULL; the contract makes `serializedState` hold `size` bytes.
        let Some(data) = (unsafe { slice(bytes as *const u8, size) }) else {
            return inst.error(&format!("{f}: serializedState is NULL with size = {size}"));
        };
        let restored = state::deserialize::<M>(terms, inst.guid, data)
            .and_then(|sim| instance::check_restored(&sim).map(|()| sim));
        let sim = match restored {
            Ok(sim) => sim,
            Err(e) => return inst.error(&format!("{f}: refused ({size} bytes): {e}")),
        };
        if state.is_null() {
            *state = snapshots::adopt(inst.guid, sim);
            return OK;
        }
        match snapshots::with::<M, _>(terms, inst.guid, *state, |s| s.sim = sim) {
            Ok(()) => OK,
            Err(why) => inst.error(&format!("{f}: *{arg}: {why}; refused, nothing changed")),
        }
    })
}

#[inline(always)]
pub unsafe fn set_continuous_states<M: CoSimulation>(
    terms: &'static Terms,
    c: Handle,
    x: *const f64,
    nx: usize,
) -> Status {
    let f = terms.name(Function::SetContinuousStates);
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::SetContinuousStates, f, |inst| {
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
    c: Handle,
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
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, call, f, |inst| {
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
