//! For code that hosts an FMU's C functions in its own process: the tests and benchmarks of this
//! workspace (a model's `rlib` linked in, its `fmi2Instantiate` or `fmi3Instantiate...` called
//! directly), and tools that load an FMU's binary. One host for both versions: [`fmi2`] (the
//! callbacks, with the one copy of the C-variadic logger) and [`fmi3`] (a logger through the
//! instance environment), both recording into the same [`Log`]; and an allocator that counts,
//! for tests that a hot path allocates nothing.
//!
//! ```
//! use rustfmu::testing::{Log, fmi2};
//!
//! let log = Log::leak();
//! let functions = fmi2::callbacks(log); // for fmi2Instantiate(..., functions, ...)
//! assert!(functions.logger.is_some());
//! // What the FMU logged, as (status, text):
//! assert!(log.texts().is_empty());
//! ```
//!
//! The FMI conformance suite (`conformance/`) keeps a logger of its own on purpose: it must not
//! trust anything of the runtime it checks.

pub mod fmi2;
pub mod fmi3;

/// The FMI 2.0 callbacks, where most hosts of this workspace look for them.
pub use fmi2::{callbacks, silent_callbacks};

use std::ffi::{CStr, c_char, c_uint};
use std::sync::Mutex;

/// One message the FMU logged.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LogEntry {
    /// An `fmi2Status` or an `fmi3Status` (the same numbers, both `c_uint`).
    pub status: c_uint,
    pub category: String,
    /// The message (FMI 2.0: the `"%s"` argument, or the format itself when it is another one).
    pub text: String,
}

/// What an instance logged, reached through its `componentEnvironment` (FMI 2.0) or its
/// instance environment (FMI 3.0).
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
    pub fn texts(&self) -> Vec<(c_uint, String)> {
        self.lock().iter().map(|e| (e.status, e.text.clone())).collect()
    }

    /// Every message so far as (status, text), removed from the log.
    pub fn take_texts(&self) -> Vec<(c_uint, String)> {
        self.take().into_iter().map(|e| (e.status, e.text)).collect()
    }

    /// The text of every message so far.
    pub fn messages(&self) -> Vec<String> {
        self.lock().iter().map(|e| e.text.clone()).collect()
    }

    /// The text of the last message, or "".
    pub fn last(&self) -> String {
        self.lock().last().map(|e| e.text.clone()).unwrap_or_default()
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

/// This thread's log (leaked, one per thread): the tests of a binary run on threads at once, and
/// the last message of a log they shared could be another test's.
pub fn thread_log() -> &'static Log {
    thread_local! {
        static LOG: &'static Log = Log::leak();
    }
    LOG.with(|l| *l)
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
