//! The FMUs' log messages, kept per thread for error reports.
//!
//! The `fmi` crate's fmi2CallbackLogger hands every message of an FMU to the `log` crate
//! (target: the instance name, level: from the status). [`install`] sets a logger that keeps
//! the last [`KEEP`] of them per thread, as "[instance: Status] message" (the form of the
//! project's fmpy master); a run takes the ones its own calls produced (an FMU logs from inside
//! the call, so on the calling thread). Another logger installed first by the program wins; the
//! runner then reports errors without the FMUs' messages.

use std::cell::RefCell;
use std::collections::VecDeque;

/// Messages kept per thread.
pub const KEEP: usize = 20;

thread_local! {
    static MESSAGES: RefCell<VecDeque<String>> = const { RefCell::new(VecDeque::new()) };
}

struct Keeper;

impl log::Log for Keeper {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        metadata.level() <= log::Level::Trace
    }

    fn log(&self, record: &log::Record) {
        // The fmi crate's C logger shim marks the FMUs' messages with module path "logger".
        if record.module_path() != Some("logger") {
            return;
        }
        let status = match record.level() {
            log::Level::Info | log::Level::Debug => "OK",
            log::Level::Warn => "Warning",
            log::Level::Trace => "Discard",
            log::Level::Error => "Error",
        };
        let text = format!("[{}: {status}] {}", record.target(), record.args());
        MESSAGES.with(|m| {
            let mut m = m.borrow_mut();
            if m.len() == KEEP {
                m.pop_front();
            }
            m.push_back(text);
        });
    }

    fn flush(&self) {}
}

static KEEPER: Keeper = Keeper;

/// Installs the keeper as the `log` crate's logger (once; false when another logger is set).
pub fn install() -> bool {
    static INSTALLED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *INSTALLED.get_or_init(|| {
        let ok = log::set_logger(&KEEPER).is_ok();
        if ok {
            log::set_max_level(log::LevelFilter::Trace);
        }
        ok
    })
}

/// Forgets this thread's messages.
pub fn clear() {
    MESSAGES.with(|m| m.borrow_mut().clear());
}

/// This thread's messages since the last [`clear`], oldest first.
pub fn take() -> Vec<String> {
    MESSAGES.with(|m| m.borrow_mut().drain(..).collect())
}
