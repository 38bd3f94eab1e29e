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

/// The status an FMU's message was logged with (the importers' loggers log each as the `log`
/// crate's level: fmi2OK Info, fmi2Warning Warn, fmi2Discard Trace, fmi2Error and fmi2Fatal Error).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    Ok,
    Warning,
    Discard,
    Error,
}

/// A `log` crate logger that hands every FMU message (module path "logger", target the instance
/// name) to its function: (instance, status, message); other records are dropped. The keeper
/// here, and the isolated child's and the container's loggers.
pub struct FmuMessages(pub fn(&str, Status, &std::fmt::Arguments));

impl log::Log for FmuMessages {
    fn enabled(&self, _: &log::Metadata) -> bool {
        true
    }

    fn log(&self, record: &log::Record) {
        // The importers' C logger shims mark the FMUs' messages with module path "logger".
        if record.module_path() != Some("logger") {
            return;
        }
        let status = match record.level() {
            log::Level::Info | log::Level::Debug => Status::Ok,
            log::Level::Warn => Status::Warning,
            log::Level::Trace => Status::Discard,
            log::Level::Error => Status::Error,
        };
        (self.0)(record.target(), status, record.args());
    }

    fn flush(&self) {}
}

/// Keeps `message` as "[instance: Status] message", the last [`KEEP`] of this thread.
fn keep(instance: &str, status: Status, message: &std::fmt::Arguments) {
    let status = match status {
        Status::Ok => "OK",
        Status::Warning => "Warning",
        Status::Discard => "Discard",
        Status::Error => "Error",
    };
    let text = format!("[{instance}: {status}] {message}");
    MESSAGES.with(|m| {
        let mut m = m.borrow_mut();
        if m.len() == KEEP {
            m.pop_front();
        }
        m.push_back(text);
    });
}

static KEEPER: FmuMessages = FmuMessages(keep);

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
