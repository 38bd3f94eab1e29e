//! What every C entry point of both versions runs through: the instance handle the importer
//! holds ([`Component`]), the NULL check, the re-entrancy refusal, the state check and
//! `catch_unwind` ([`with_instance`]), and the conversions of the importer's pointers into
//! slices and text. Each `unsafe` block says why it is sound.

use super::instance::Instance;
use super::logging::{Category, Logger};
use super::machine::{Call, State};
use super::{ERROR, FATAL, Status, Version};
use crate::model::CoSimulation;
use std::cell::UnsafeCell;
use std::ffi::CStr;
use std::os::raw::{c_char, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, Ordering};

pub(crate) fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        format!("panic: {s}")
    } else if let Some(s) = payload.downcast_ref::<String>() {
        format!("panic: {s}")
    } else {
        "panic".into()
    }
}

/// What the instantiation functions hand out as the `fmi2Component` / `fmi3Instance`: the
/// instance, and what a call needs before it may touch it.
pub struct Component<M: CoSimulation> {
    /// Set while a call is inside the instance. A call that arrives meanwhile (made by the
    /// importer's logger during that call, or from another thread) is refused: it would work on
    /// an instance in the middle of a change (a nested do-step advanced the model twice
    /// while the clock said once).
    pub(crate) busy: AtomicBool,
    /// Logs those refusals. A copy taken at instantiation: error messages pass the logger
    /// whatever its switches, so later set-debug-logging calls do not matter to it.
    pub(crate) refusals: Logger,
    pub(crate) instance: UnsafeCell<Instance<M>>,
}

/// Runs `f` on the instance behind `c`, after the state check for `call`.
/// A NULL instance cannot be logged to: the answer is an error status.
pub(crate) unsafe fn with_instance<M: CoSimulation>(
    c: *mut c_void,
    call: Call,
    function: &str,
    f: impl FnOnce(&mut Instance<M>) -> Status,
) -> Status {
    if c.is_null() {
        return ERROR;
    }
    // SAFETY: a non-NULL component is one this library returned from an instantiation function and that
    // was not freed (the standard forbids any other). Only shared: a call already inside holds
    // the instance, which is in the UnsafeCell.
    let component = unsafe { &*(c as *const Component<M>) };
    if component.busy.swap(true, Ordering::Acquire) {
        component.refusals.log(
            ERROR,
            Category::StatusError,
            &format!(
                "{function}: called while a call into this instance is still running (from a \
                 callback of that call, or from another thread); refused, nothing changed"
            ),
        );
        return ERROR;
    }
    let instance = component.instance.get();
    let result = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: this call set `busy`, so no other reference to the instance exists until it
        // clears it below.
        let inst = unsafe { &mut *instance };
        let status = match inst.check_state(call, function) {
            Ok(()) => f(inst),
            Err(status) => status,
        };
        // FMI 3.0, 2.3.1: "If any function called in super state FMU State Setable returns
        // fmi3Error, the FMU enters state Terminated" (from there fmi3Reset or fmi3SetFMUState
        // lead back). FMI 2.0 has no such rule: its instances stay where they were.
        if inst.terms.version == Version::Fmi3 && status == ERROR && inst.sim.state != State::Fatal {
            inst.sim.state = State::Terminated;
        }
        status
    }));
    let status = match result {
        Ok(status) => status,
        Err(payload) => {
            let what = panic_text(&*payload);
            // SAFETY: as above; the closure's borrow ended with the unwind.
            let inst = unsafe { &mut *instance };
            let _ = catch_unwind(AssertUnwindSafe(|| inst.fatal(function, &what)));
            FATAL
        }
    };
    component.busy.store(false, Ordering::Release);
    status
}

/// An importer's array argument: NULL is fine only when it is empty.
pub(crate) unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        Some(&[])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: the standard makes the importer pass n valid elements.
        Some(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

pub(crate) unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        Some(&mut [])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: as for `slice`.
        Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
}

pub(crate) unsafe fn text<'a>(s: *const c_char) -> Option<std::borrow::Cow<'a, str>> {
    if s.is_null() {
        None
    } else {
        // SAFETY: the importer passes NUL-terminated strings.
        Some(unsafe { CStr::from_ptr(s) }.to_string_lossy())
    }
}

/// The state an instance is in, for tests written against the runtime in Rust (not while a
/// call is inside it).
pub unsafe fn state_of<M: CoSimulation>(c: *mut c_void) -> Option<State> {
    // SAFETY: as in `with_instance`; no call is inside (the caller's promise).
    unsafe { (c as *const Component<M>).as_ref().map(|c| (*c.instance.get()).state()) }
}
