//! The C entry points whose bodies are the same in FMI 2.0 and 3.0, generic over the model:
//! freeing an instance and debug logging (here), the lifecycle's transitions and model exchange
//! (`model_exchange`), the FMU state (`fmu_state`). Each takes the calling layer's
//! [`Terms`], so that its messages name the function the importer called; the layers convert
//! their own argument types (`fmi3Boolean`, `fmi3Byte`) before calling, and the instance handle
//! is converted once, in the exported function ([`crate::core::guard::component`]).
//!
//! # Safety
//! Every `unsafe fn` here has the contract of the C function it implements, which the standard
//! puts on the importer: the instance handle is NULL or one this library's instantiation
//! function returned for model `M` and did not free; every other pointer is NULL or valid as
//! the standard describes it (an array of the length passed beside it, a NUL-terminated string,
//! a writable output). Each `unsafe` block below says which part of that, and which check, makes
//! its pointer operation sound.
#![allow(clippy::missing_safety_doc)]

mod fmu_state;
mod model_exchange;

pub use super::guard::Handle;
pub use fmu_state::*;
pub use model_exchange::*;

use super::guard::{Component, slice, text, with_instance};
use super::logging::Category;
use super::machine::Call;
use super::{ERROR, Function, Status, Terms};
use crate::model::CoSimulation;
use std::os::raw::c_char;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::Ordering;

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
    c: Option<&Component<M>>,
    logging_on: bool,
    n: usize,
    categories: *const *const c_char,
) -> Status {
    let f = terms.name(Function::SetDebugLogging);
    with_instance(c, Call::SetDebugLogging, f, |inst| {
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
