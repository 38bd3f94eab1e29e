//! What every C entry point of both versions runs through: the instance handle the importer
//! holds ([`Component`], converted once by the unsafe [`component`]), then, in safe
//! code, the NULL check, the re-entrancy refusal, the state check and `catch_unwind`
//! (`with_instance`, `Component::run`); and the conversions of the importer's other
//! pointers into slices and text (`slice`, `slice_mut`, `text`), each an `unsafe fn`
//! whose contract the caller's `SAFETY:` line answers.

use super::instance::Instance;
use super::logging::{Category, Logger};
use super::machine::{Call, State};
use super::{ERROR, FATAL, Status, Version};
use crate::model::CoSimulation;
use std::cell::UnsafeCell;
use std::ffi::CStr;
use std::os::raw::{c_char, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The importer's instance handle (`fmi2Component`, `fmi3Instance`) and FMU state handle
/// (`fmi2FMUstate`, `fmi3FMUState`): both `void *` in both versions.
pub type Handle = *mut c_void;

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
    /// Scheduled Execution only: calls into the instance from different threads (a scheduler
    /// that would preempt one partition by another) wait for each other here instead of being
    /// refused; a nested call on the thread that holds it (from the importer's clockUpdate
    /// callback) goes through. No preemption inside an instance: the runtime serializes.
    pub(crate) serial: Option<std::sync::Mutex<()>>,
    /// The thread holding `serial` (its mark, [`this_thread`]); 0: none.
    pub(crate) owner: AtomicUsize,
    /// Scheduled Execution: the importer's clockUpdate callback is running (called by
    /// fmi3ActivateModelPartition, which still has the instance to finish afterwards): the
    /// instance is not freed from inside it.
    pub(crate) in_callback: AtomicBool,
}

/// The component behind the importer's instance handle; `None` for NULL (which cannot be
/// logged to: [`with_instance`] answers it with an error status). The one conversion of the
/// handle: each exported function's row calls it in its one `unsafe` block
/// ([`crate::core::trampolines`]), and hands the runtime function the result.
///
/// # Safety
/// `c` is NULL or a handle that this library's instantiation function returned for model `M`
/// and that was not freed since (what the standard allows an importer to pass), and it is not
/// freed while the reference lives (the call it came with).
#[doc(hidden)]
#[inline(always)]
pub unsafe fn component<'a, M: CoSimulation>(c: Handle) -> Option<&'a Component<M>> {
    // SAFETY: the caller's promise: NULL (`as_ref` gives `None`) or a live Box<Component<M>>.
    // Only shared: a call already inside holds the instance, which is in the UnsafeCell.
    unsafe { (c as *const Component<M>).as_ref() }
}

/// A number that identifies the calling thread while it lives (the address of a thread-local).
fn this_thread() -> usize {
    thread_local!(static MARK: u8 = const { 0 });
    MARK.with(|m| m as *const u8 as usize)
}

impl<M: CoSimulation> Component<M> {
    /// A new instance, boxed, as the handle the instantiation functions hand out (freed by
    /// `shared::free_instance`); `serialized` for Scheduled Execution (see `serial`).
    pub(crate) fn into_handle(inst: Instance<M>, serialized: bool) -> Handle {
        Box::into_raw(Box::new(Component {
            busy: AtomicBool::new(false),
            refusals: inst.logger.clone(),
            instance: UnsafeCell::new(inst),
            serial: serialized.then(|| std::sync::Mutex::new(())),
            owner: AtomicUsize::new(0),
            in_callback: AtomicBool::new(false),
        })) as Handle
    }

    /// Runs `f` while this thread holds the instance's `serial` lock (Scheduled Execution: a
    /// call from another thread waits until `f` is done); directly when the instance has none,
    /// or when this thread holds it already.
    pub(crate) fn exclusive<R>(&self, f: impl FnOnce() -> R) -> R {
        let Some(serial) = &self.serial else {
            return f();
        };
        let me = this_thread();
        if self.owner.load(Ordering::Acquire) == me {
            return f();
        }
        let _lock = serial.lock().unwrap_or_else(|e| e.into_inner());
        self.owner.store(me, Ordering::Release);
        // Released also when `f` unwinds (it does not: its callers catch panics).
        struct Release<'a>(&'a AtomicUsize);
        impl Drop for Release<'_> {
            fn drop(&mut self) {
                self.0.store(0, Ordering::Release);
            }
        }
        let _release = Release(&self.owner);
        f()
    }

    /// Runs `f` on the instance after the state check for `call`: refused while another call
    /// is inside the instance, under `catch_unwind` (a panic makes the instance fatal).
    /// (Scheduled Execution's serialization of threads is `with_instance`'s, around this.)
    pub(crate) fn run(&self, call: Call, function: &str, f: impl FnOnce(&mut Instance<M>) -> Status) -> Status {
        self.run_checked(call, function, f)
    }

    /// Runs `f` on the instance without a state check (the runtime's own step after a callback
    /// to the importer returned): not while another call is inside (then it is not run: false),
    /// under `catch_unwind`.
    pub(crate) fn run_internal(&self, function: &str, f: impl FnOnce(&mut Instance<M>)) -> bool {
        self.exclusive(|| {
            if self.busy.swap(true, Ordering::Acquire) {
                return false;
            }
            let instance = self.instance.get();
            // SAFETY: this call set `busy`, so no other reference to the instance exists until it
            // clears it below.
            let result = catch_unwind(AssertUnwindSafe(|| f(unsafe { &mut *instance })));
            if let Err(payload) = result {
                let what = panic_text(&*payload);
                // SAFETY: as above; the closure's borrow ended with the unwind.
                let inst = unsafe { &mut *instance };
                let _ = catch_unwind(AssertUnwindSafe(|| inst.fatal(function, &what)));
            }
            self.busy.store(false, Ordering::Release);
            true
        })
    }

    fn run_checked(&self, call: Call, function: &str, f: impl FnOnce(&mut Instance<M>) -> Status) -> Status {
        if self.busy.swap(true, Ordering::Acquire) {
            self.refusals.log(
                ERROR,
                Category::StatusError,
                &format!(
                    "{function}: called while a call into this instance is still running (from a \
                     callback of that call, or from another thread); refused, nothing changed"
                ),
            );
            return ERROR;
        }
        let instance = self.instance.get();
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
            if inst.version == Version::Fmi3 && status == ERROR && inst.sim.state != State::Fatal {
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
        self.busy.store(false, Ordering::Release);
        status
    }
}

/// Runs `f` on the instance of `component` (from [`component`]) after the state
/// check for `call`; a NULL instance cannot be logged to: the answer is an error status.
#[inline]
pub(crate) fn with_instance<M: CoSimulation>(
    component: Option<&Component<M>>,
    call: Call,
    function: &str,
    f: impl FnOnce(&mut Instance<M>) -> Status,
) -> Status {
    match component {
        None => ERROR,
        // Scheduled Execution: calls from other threads wait (`Component::exclusive`). Model
        // exchange and co-simulation keep the direct path (through `exclusive`'s closure for
        // every instance, a call cost up to 30 instructions more: bench/callgrind.sh).
        Some(component) if component.serial.is_some() => component.exclusive(|| component.run(call, function, f)),
        Some(component) => component.run(call, function, f),
    }
}

/// An importer's array argument: NULL is fine only when it is empty.
///
/// # Safety
/// `p` is NULL or points to `n` valid elements that nothing else changes while the slice
/// lives: what the standard asks of an importer's array of length `n`.
pub(crate) unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        Some(&[])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: not NULL, and the caller's promise: `n` valid elements.
        Some(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

/// An importer's output array: NULL is fine only when it is empty.
///
/// # Safety
/// As for `slice`, and no other reference reads or writes the elements meanwhile.
pub(crate) unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        Some(&mut [])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: not NULL, and the caller's promise: `n` valid elements, not aliased.
        Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
}

/// An importer's string: `None` for NULL.
///
/// # Safety
/// `s` is NULL or points to a NUL-terminated string that lives as long as the result.
pub(crate) unsafe fn text<'a>(s: *const c_char) -> Option<std::borrow::Cow<'a, str>> {
    if s.is_null() {
        None
    } else {
        // SAFETY: not NULL, and the caller's promise: NUL-terminated.
        Some(unsafe { CStr::from_ptr(s) }.to_string_lossy())
    }
}

/// The state an instance is in, for tests written against the runtime in Rust (not while a
/// call is inside it).
///
/// # Safety
/// `c` is NULL or a live instance of model `M` (as for [`component`]), and no
/// call is inside it.
pub unsafe fn state_of<M: CoSimulation>(c: *mut c_void) -> Option<State> {
    // SAFETY: as in `with_instance`; no call is inside (the caller's promise).
    unsafe { (c as *const Component<M>).as_ref().map(|c| (*c.instance.get()).state()) }
}
