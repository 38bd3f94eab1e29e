//! For code that hosts an FMU's FMI 2.0 C functions in its own process: a model crate's tests
//! and benchmarks (the crate's `rlib` linked in, `fmi2Instantiate` called directly), and tools
//! that load an FMU's binary. The callbacks an instance needs, with a logger that records what
//! the FMU logs or one that drops it. One copy of the C-variadic logger for all of them.
//!
//! ```
//! use rustfmu::testing::{Log, callbacks};
//!
//! let log = Log::leak();
//! let functions = callbacks(log); // for fmi2Instantiate(..., functions, ...)
//! assert!(functions.logger.is_some());
//! // What the FMU logged, as (status, text):
//! assert!(log.texts().is_empty());
//! ```
//!
//! Why the logger is sound: FMI 2.0's logger is C-variadic (`message` is a printf format). A
//! rustfmu FMU always logs with the format `"%s"` and the text as the one variadic argument; on
//! every ABI this project builds for (x86-64 System V and Windows, AArch64 Linux) a variadic
//! argument that follows the fixed ones is passed where a fixed sixth pointer argument would
//! be, so a function with six fixed arguments reads it. The recording logger reads the text
//! only when the format is exactly `"%s"` and records any other format as it is. On Apple
//! silicon variadic arguments go on the stack: there it records the format, never the argument. The FMI
//! conformance suite (`conformance/`) keeps a logger of its own on purpose: it must not
//! trust anything of the runtime it checks.

use crate::fmi2::abi::*;
use std::ffi::{CStr, c_char};
use std::sync::Mutex;

/// One message the FMU logged.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LogEntry {
    pub status: fmi2Status,
    pub category: String,
    /// The message: the `"%s"` argument, or the format itself when it is another one.
    pub text: String,
}

/// What an instance logged, reached through its `componentEnvironment`.
#[derive(Debug, Default)]
pub struct Log {
    entries: Mutex<Vec<LogEntry>>,
}

impl Log {
    /// A log that lives as long as the process: an instance may log until it is freed, and
    /// tests free instances late or never.
    pub fn leak() -> &'static Log {
        Box::leak(Box::default())
    }

    /// Records a message (for a logger of a test's own that also records).
    pub fn push(&self, entry: LogEntry) {
        self.lock().push(entry);
    }

    /// Every message so far.
    pub fn entries(&self) -> Vec<LogEntry> {
        self.lock().clone()
    }

    /// Every message so far, removed from the log.
    pub fn take(&self) -> Vec<LogEntry> {
        std::mem::take(&mut *self.lock())
    }

    /// Every message so far as (status, text).
    pub fn texts(&self) -> Vec<(fmi2Status, String)> {
        self.lock().iter().map(|e| (e.status, e.text.clone())).collect()
    }

    /// Every message so far as (status, text), removed from the log.
    pub fn take_texts(&self) -> Vec<(fmi2Status, String)> {
        self.take().into_iter().map(|e| (e.status, e.text)).collect()
    }

    /// Forgets what was logged.
    pub fn clear(&self) {
        self.lock().clear();
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<LogEntry>> {
        // A test that panicked while holding the lock leaves the entries as they were.
        self.entries.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// The text of a C string the FMU passed (empty for NULL).
///
/// # Safety
/// `s` is NULL or a NUL-terminated string alive for the call.
unsafe fn text(s: *const c_char) -> String {
    if s.is_null() {
        return String::new();
    }
    // SAFETY: not NULL, and NUL-terminated and alive by the caller's contract (the FMU's).
    unsafe { CStr::from_ptr(s) }.to_string_lossy().into_owned()
}

/// The recording logger with its variadic argument read as a fixed one (see the module's
/// documentation). Never unwinds into the FMU: nothing here panics.
unsafe extern "C" fn record(
    env: fmi2ComponentEnvironment,
    _instance: fmi2String,
    status: fmi2Status,
    category: fmi2String,
    message: fmi2String,
    argument: *const c_char,
) {
    if env.is_null() {
        return;
    }
    // SAFETY: the strings are the FMU's, valid for the call; the argument is read only when the
    // format says there is one string argument.
    let (category, format) = unsafe { (text(category), text(message)) };
    let text = if format == "%s" && !cfg!(all(target_vendor = "apple", target_arch = "aarch64")) {
        // SAFETY: as above: "%s" means the first variadic argument is a string.
        unsafe { self::text(argument) }
    } else {
        format
    };
    // SAFETY: `callbacks` is the only way this function gets to an FMU, and it passes a
    // `&'static Log` as componentEnvironment.
    let log = unsafe { &*(env as *const Log) };
    log.lock().push(LogEntry { status, category, text });
}

unsafe extern "C" fn ignore(
    _env: fmi2ComponentEnvironment,
    _instance: fmi2String,
    _status: fmi2Status,
    _category: fmi2String,
    _message: fmi2String,
) {
}

type Recorder =
    unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, *const c_char);
type Ignorer = unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String);
type Variadic = unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...);

/// Callbacks whose logger records into `log` (the instance's `componentEnvironment`), without
/// memory callbacks (FMI 2.0 lets an FMU allocate with its own). Leaked, like the log: they
/// must outlive the instance.
pub fn callbacks(log: &'static Log) -> &'static fmi2CallbackFunctions {
    Box::leak(Box::new(fmi2CallbackFunctions {
        // SAFETY: same fixed arguments; the sixth is where the ABIs pass the first variadic
        // argument (module documentation), and `record` reads it only after a "%s".
        logger: Some(unsafe { std::mem::transmute::<Recorder, Variadic>(record as Recorder) }),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: log as *const Log as fmi2ComponentEnvironment,
    }))
}

/// Callbacks whose logger drops every message and allocates nothing (benchmarks, and tests
/// that count allocations).
pub fn silent_callbacks() -> &'static fmi2CallbackFunctions {
    Box::leak(Box::new(fmi2CallbackFunctions {
        // SAFETY: a callee that reads fewer arguments than the caller passes is sound in C's
        // calling conventions; `ignore` reads none of them.
        logger: Some(unsafe { std::mem::transmute::<Ignorer, Variadic>(ignore as Ignorer) }),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: std::ptr::null_mut(),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_recording_logger_keeps_status_category_and_text_and_ignores_a_null_environment() {
        let log = Log::leak();
        let cb = callbacks(log);
        let logger = cb.logger.expect("a logger");
        // SAFETY: the logger called the way an FMU calls it: "%s" and one string.
        unsafe {
            logger(
                cb.componentEnvironment,
                c"i".as_ptr(),
                fmi2Warning,
                c"logAll".as_ptr(),
                c"%s".as_ptr(),
                c"hello".as_ptr(),
            );
            logger(
                cb.componentEnvironment,
                c"i".as_ptr(),
                fmi2OK,
                c"logAll".as_ptr(),
                c"plain".as_ptr(),
            );
            logger(
                std::ptr::null_mut(),
                c"i".as_ptr(),
                fmi2OK,
                c"logAll".as_ptr(),
                c"%s".as_ptr(),
                c"lost".as_ptr(),
            );
        }
        assert_eq!(
            log.entries(),
            vec![
                LogEntry {
                    status: fmi2Warning,
                    category: "logAll".into(),
                    text: "hello".into()
                },
                LogEntry {
                    status: fmi2OK,
                    category: "logAll".into(),
                    text: "plain".into()
                },
            ]
        );
        assert_eq!(log.take().len(), 2);
        assert!(log.texts().is_empty());
    }
}

/// A global allocator that counts the heap allocations of the thread that armed it
/// ([`allocations_in`]), for tests that a hot path allocates nothing. A test binary installs it:
/// `#[global_allocator] static A: rustfmu::testing::CountingAllocator = rustfmu::testing::CountingAllocator;`
pub struct CountingAllocator;

thread_local! {
    static ARMED: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    static COUNT: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

fn note_allocation() {
    // try_with: thread-local storage may already be gone while a thread exits.
    let _ = ARMED.try_with(|armed| {
        if armed.get() {
            let _ = COUNT.try_with(|c| c.set(c.get() + 1));
        }
    });
}

// SAFETY: forwards to the system allocator unchanged; only counts.
unsafe impl std::alloc::GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        note_allocation();
        // SAFETY: the caller's contract is passed on.
        unsafe { std::alloc::System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: std::alloc::Layout) -> *mut u8 {
        note_allocation();
        // SAFETY: as above.
        unsafe { std::alloc::System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, new_size: usize) -> *mut u8 {
        note_allocation();
        // SAFETY: as above.
        unsafe { std::alloc::System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        // SAFETY: as above.
        unsafe { std::alloc::System.dealloc(ptr, layout) }
    }
}

/// Heap allocations `f` makes on this thread (counted where [`CountingAllocator`] is the
/// global allocator; 0 elsewhere).
pub fn allocations_in(f: impl FnOnce()) -> u64 {
    COUNT.with(|c| c.set(0));
    ARMED.with(|a| a.set(true));
    f();
    ARMED.with(|a| a.set(false));
    COUNT.with(|c| c.get())
}
