//! The importer's logger callback, recording every message with what came with it.
//!
//! FMI declares the logger variadic (`message` is a printf format). Stable Rust cannot define a
//! variadic function, but under the x86-64 and AArch64 C calling conventions a callee that
//! declares the fixed arguments plus one pointer reads the first variadic pointer argument
//! correctly (fmpy's ctypes logger relies on the same convention; `fmu-build`'s validator does
//! the same). This exporter's runtime always passes the format `"%s"` with the text as that
//! argument; the recorded [`LogEntry::format`] lets the checks require exactly that of it, so
//! that a printf-style logger in a C host can never misread a `%` in a message. Another
//! exporter's messages with other formats are recorded as their format, unformatted.

use crate::fmi2::*;
use std::ffi::{CStr, c_char};
use std::sync::Mutex;

#[derive(Debug, Clone, PartialEq)]
pub struct LogEntry {
    /// The componentEnvironment the FMU passed back.
    pub env: usize,
    pub instance: String,
    pub status: fmi2Status,
    pub category: String,
    /// The `message` argument: the printf format.
    pub format: String,
    /// The message with the format applied (`"%s"` + its argument).
    pub text: String,
}

/// What the logger's componentEnvironment points to: one per instance.
#[derive(Debug, Default)]
pub struct LogSink {
    pub entries: Mutex<Vec<LogEntry>>,
}

impl LogSink {
    pub fn env(&self) -> fmi2ComponentEnvironment {
        self as *const LogSink as fmi2ComponentEnvironment
    }

    pub fn take(&self) -> Vec<LogEntry> {
        std::mem::take(&mut *self.entries.lock().unwrap_or_else(|e| e.into_inner()))
    }
}

unsafe extern "C" fn record(
    env: fmi2ComponentEnvironment,
    instance: fmi2String,
    status: fmi2Status,
    category: fmi2String,
    message: fmi2String,
    arg: *const c_char,
) {
    let text = |p: *const c_char| {
        if p.is_null() {
            "<NULL>".to_string()
        } else {
            // SAFETY: the FMU passes NUL-terminated strings (or NULL, handled above).
            unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
        }
    };
    let format = text(message);
    // Only the format "%s" has an argument to read; any other format is recorded as is (a check
    // of this exporter's FMUs then fails on it, since its runtime must always use "%s").
    let applied = if format == "%s" { text(arg) } else { format.clone() };
    let entry = LogEntry {
        env: env as usize,
        instance: text(instance),
        status,
        category: text(category),
        format,
        text: applied,
    };
    if env.is_null() {
        panic_free_eprint(&entry);
        return;
    }
    // SAFETY: every instance the harness creates passes a live &LogSink as componentEnvironment
    // (tests that pass another environment check `env` before it could be dereferenced: they
    // pass the address of a LogSink too).
    let sink = unsafe { &*(env as *const LogSink) };
    sink.entries.lock().unwrap_or_else(|e| e.into_inner()).push(entry);
}

fn panic_free_eprint(entry: &LogEntry) {
    eprintln!("log message with a NULL componentEnvironment: {entry:?}");
}

/// The logger as the FMI type (a variadic function pointer).
pub fn logger() -> fmi2CallbackLogger {
    type Fixed =
        unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, *const c_char);
    type Variadic = unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
    // SAFETY: same arguments in the same registers/stack slots for the fixed part; see the
    // module documentation for why reading the first variadic argument this way is sound here.
    Some(unsafe { std::mem::transmute::<Fixed, Variadic>(record as Fixed) })
}

/// Callbacks with the recording logger and the given environment.
pub fn callbacks(env: fmi2ComponentEnvironment) -> fmi2CallbackFunctions {
    fmi2CallbackFunctions {
        logger: logger(),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: env,
    }
}
