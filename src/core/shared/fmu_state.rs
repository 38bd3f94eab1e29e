//! The FMU state functions of both versions: get, set and free an in-memory state
//! ([`crate::core::snapshots`]), and its serialized form ([`crate::core::state`]).
//!
//! # Safety
//! As for [`super`]: each `unsafe fn` has the contract of the C function it implements.
#![allow(clippy::missing_safety_doc)]

use super::Handle;
use crate::core::guard::{Component, slice, with_instance};
use crate::core::machine::Call;
use crate::core::{Function, OK, Status, Terms, instance, snapshots, state};
use crate::model::CoSimulation;
use std::os::raw::c_char;
use std::ptr;

pub unsafe fn get_fmu_state<M: CoSimulation>(
    terms: &'static Terms,
    c: Option<&Component<M>>,
    state: *mut Handle,
) -> Status {
    let (f, arg) = (terms.name(Function::GetFmuState), terms.fmu_state);
    with_instance(c, Call::FmuState, f, |inst| {
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

pub fn set_fmu_state<M: CoSimulation>(terms: &'static Terms, c: Option<&Component<M>>, state: Handle) -> Status {
    let (f, arg) = (terms.name(Function::SetFmuState), terms.fmu_state);
    with_instance(c, Call::FmuState, f, |inst| {
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

pub unsafe fn free_fmu_state<M: CoSimulation>(
    terms: &'static Terms,
    c: Option<&Component<M>>,
    state: *mut Handle,
) -> Status {
    let f = terms.name(Function::FreeFmuState);
    with_instance(c, Call::FmuState, f, |inst| {
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
    c: Option<&Component<M>>,
    state: Handle,
    size: *mut usize,
) -> Status {
    let (f, arg) = (terms.name(Function::SerializedFmuStateSize), terms.fmu_state);
    with_instance(c, Call::FmuState, f, |inst| {
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
    c: Option<&Component<M>>,
    state: Handle,
    bytes: *mut c_char,
    size: usize,
) -> Status {
    let (f, arg) = (terms.name(Function::SerializeFmuState), terms.fmu_state);
    with_instance(c, Call::FmuState, f, |inst| {
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
    c: Option<&Component<M>>,
    bytes: *const c_char,
    size: usize,
    state: *mut Handle,
) -> Status {
    let (f, arg) = (terms.name(Function::DeserializeFmuState), terms.fmu_state);
    with_instance(c, Call::FmuState, f, |inst| {
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
