//! The FMU state functions of both versions: get, set and free an in-memory state
//! ([`crate::core::snapshots`]), and its serialized form ([`crate::core::state`]).
//!
//! # Safety
//! As for [`super`]: each `unsafe fn` has the contract of the C function it implements.
#![allow(clippy::missing_safety_doc)]

use super::Handle;
use crate::core::guard::{Component, slice, with_instance};
use crate::core::instance::{Instance, Sim};
use crate::core::machine::Call;
use crate::core::{Function, OK, Status, Terms, instance, snapshots, state};
use crate::model::CoSimulation;
use std::borrow::Cow;
use std::os::raw::c_char;
use std::ptr;

pub unsafe fn get_fmu_state<M: CoSimulation>(
    terms: &'static Terms,
    c: Option<&Component<M>>,
    state: *mut Handle,
) -> Status {
    // SAFETY: this function's contract is `with_state_variable`'s.
    unsafe {
        with_state_variable(terms, c, Function::GetFmuState, state, |inst, f, state| {
            store(terms, inst, f, state, inst.state_to_save())
        })
    }
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
    let write = |_: &mut Instance<M>, _: &str, data: Vec<u8>| {
        // SAFETY: not NULL (checked before `serialized` calls this); the contract makes `size`
        // writable.
        unsafe { *size = data.len() };
        OK
    };
    serialized(
        terms,
        c,
        Function::SerializedFmuStateSize,
        state,
        (size.is_null(), "size"),
        write,
    )
}

pub unsafe fn serialize_fmu_state<M: CoSimulation>(
    terms: &'static Terms,
    c: Option<&Component<M>>,
    state: Handle,
    bytes: *mut c_char,
    size: usize,
) -> Status {
    let write = |inst: &mut Instance<M>, f: &str, data: Vec<u8>| {
        if data.len() != size {
            return inst.error(&format!(
                "{f}: size = {size}, but the state takes {} bytes (ask {})",
                data.len(),
                terms.name(Function::SerializedFmuStateSize)
            ));
        }
        // SAFETY: `bytes` is not NULL (checked before `serialized` calls this) and the contract
        // makes it hold `size` bytes, exactly as many as are written; `data` is this library's own.
        unsafe { ptr::copy_nonoverlapping(data.as_ptr(), bytes as *mut u8, size) };
        OK
    };
    let out = (bytes.is_null(), "serializedState");
    serialized(terms, c, Function::SerializeFmuState, state, out, write)
}

/// What the two serializing functions share, as `function`: `state` and the output (whether its
/// pointer is NULL, its name) checked, then `body` with the state's serialized form.
fn serialized<M: CoSimulation>(
    terms: &'static Terms,
    c: Option<&Component<M>>,
    function: Function,
    state: Handle,
    (out_is_null, out): (bool, &str),
    body: impl FnOnce(&mut Instance<M>, &str, Vec<u8>) -> Status,
) -> Status {
    let (f, arg) = (terms.name(function), terms.fmu_state);
    with_instance(c, Call::FmuState, f, |inst| {
        if state.is_null() || out_is_null {
            return inst.error(&format!("{f}: {arg} or {out} is NULL"));
        }
        match snapshots::with::<M, _>(terms, inst.guid, state, |s| state::serialize(inst.guid, &s.sim)) {
            Ok(Ok(data)) => body(inst, f, data),
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
    let deserialize = |inst: &mut Instance<M>, f: &str, state: &mut Handle| {
        // SAFETY: `slice` checks NULL; the contract makes `serializedState` hold `size` bytes.
        let Some(data) = (unsafe { slice(bytes as *const u8, size) }) else {
            return inst.error(&format!("{f}: serializedState is NULL with size = {size}"));
        };
        let restored = state::deserialize::<M>(terms, inst.guid, data)
            .and_then(|sim| instance::check_restored(&sim).map(|()| sim));
        match restored {
            Ok(sim) => store(terms, inst, f, state, Cow::Owned(sim)),
            Err(e) => inst.error(&format!("{f}: refused ({size} bytes): {e}")),
        }
    };
    // SAFETY: this function's contract is `with_state_variable`'s.
    unsafe { with_state_variable(terms, c, Function::DeserializeFmuState, state, deserialize) }
}

/// What get and deserialize run as `function`: `body` on the instance with the importer's FMU
/// state variable, refused when the pointer to it is NULL.
///
/// # Safety
/// `state` is NULL or points to the importer's writable FMU state variable.
#[inline(always)]
unsafe fn with_state_variable<M: CoSimulation>(
    terms: &'static Terms,
    c: Option<&Component<M>>,
    function: Function,
    state: *mut Handle,
    body: impl FnOnce(&mut Instance<M>, &str, &mut Handle) -> Status,
) -> Status {
    let f = terms.name(function);
    with_instance(c, Call::FmuState, f, |inst| {
        // SAFETY: `as_mut` checks NULL; the contract makes a non-NULL `state` point to the
        // importer's writable FMU state variable.
        match unsafe { state.as_mut() } {
            Some(state) => body(inst, f, state),
            None => inst.error(&format!("{f}: {} is NULL", terms.fmu_state)),
        }
    })
}

/// Puts `sim` into the importer's FMU state variable (get and deserialize): a new state where
/// it is NULL, else over the state it holds, which must be one of this FMU's (a non-NULL
/// `*FMUstate` is overwritten in place).
fn store<M: CoSimulation>(
    terms: &Terms,
    inst: &Instance<M>,
    f: &str,
    state: &mut Handle,
    sim: Cow<'_, Sim<M>>,
) -> Status {
    if state.is_null() {
        *state = snapshots::adopt(inst.guid, sim.into_owned());
        return OK;
    }
    let put = |s: &mut snapshots::Snapshot<M>| match sim {
        Cow::Owned(sim) => s.sim = sim,
        Cow::Borrowed(sim) => s.sim.clone_from(sim),
    };
    match snapshots::with::<M, _>(terms, inst.guid, *state, put) {
        Ok(()) => OK,
        Err(why) => inst.error(&format!("{f}: *{}: {why}; refused, nothing changed", terms.fmu_state)),
    }
}
