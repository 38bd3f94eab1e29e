//! The importer's logger, called the way the standard requires: FMI 2.0's printf-style callback
//! always with the format `"%s"`, FMI 3.0's message callback with the instance name in front.
//! The messages are passed on exactly as the core and the model wrote them.

use super::{DISCARD, ERROR, FATAL, OK, Status, WARNING};
use crate::description::{LogCategory, RUNTIME_LOG_CATEGORIES};
use std::ffi::{CStr, CString};
use std::os::raw::{c_char, c_void};

/// The runtime's own categories, in [`RUNTIME_LOG_CATEGORIES`] order (a category's
/// discriminant, its place in the declaration, is its index there); a model's declared
/// categories follow them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Category {
    Events,
    StatusWarning,
    StatusDiscard,
    StatusError,
    StatusFatal,
    Calls,
    All,
}

const RUNTIME_NAMES: [&CStr; 7] = [
    c"logEvents",
    c"logStatusWarning",
    c"logStatusDiscard",
    c"logStatusError",
    c"logStatusFatal",
    c"logCalls",
    c"logAll",
];

const _: () = assert!(RUNTIME_NAMES.len() == RUNTIME_LOG_CATEGORIES.len());

impl Category {
    pub fn for_status(status: Status) -> Category {
        match status {
            WARNING => Category::StatusWarning,
            DISCARD => Category::StatusDiscard,
            ERROR => Category::StatusError,
            FATAL => Category::StatusFatal,
            _ => Category::Events,
        }
    }
}

/// `fmi2CallbackLogger` without its `Option`: environment, instance name, status, category,
/// printf format, arguments.
pub type PrintfCallback = unsafe extern "C" fn(*mut c_void, *const c_char, Status, *const c_char, *const c_char, ...);
/// `fmi3LogMessageCallback` without its `Option`: environment, status, category, message.
pub type MessageCallback = unsafe extern "C" fn(*mut c_void, Status, *const c_char, *const c_char);

/// The importer's callback: the two shapes the standard has.
#[derive(Debug, Clone, Copy)]
pub enum Callback {
    /// FMI 2.0's: a printf-style function that takes the instance name.
    Printf(PrintfCallback),
    /// FMI 3.0's: a finished message; NULL is allowed (nothing is logged).
    Message(Option<MessageCallback>),
}

/// The callback with what it needs: environment pointer, instance name, logging switches.
#[derive(Debug, Clone)]
pub struct Logger {
    callback: Callback,
    environment: *mut c_void,
    instance_name: CString,
    logging_on: bool,
    /// Bit i: category i of runtime ++ model categories is enabled.
    enabled: u64,
    model_categories: &'static [LogCategory],
}

impl Logger {
    /// The importer's `callback` with its `environment` pointer, for the instance named
    /// `instance_name`: every message passes while `logging_on`, until a set-debug-logging
    /// call narrows the categories.
    pub fn new(
        callback: Callback,
        environment: *mut c_void,
        instance_name: &str,
        logging_on: bool,
        model_categories: &'static [LogCategory],
    ) -> Logger {
        Logger {
            callback,
            environment,
            instance_name: to_cstring(instance_name),
            logging_on,
            enabled: u64::MAX,
            model_categories,
        }
    }

    pub fn instance_name(&self) -> &str {
        self.instance_name.to_str().unwrap_or("")
    }

    /// Index of a category by name: runtime categories first, then the model's.
    pub fn category_index(&self, name: &str) -> Option<usize> {
        RUNTIME_LOG_CATEGORIES
            .iter()
            .chain(self.model_categories)
            .position(|c| c.name == name)
    }

    pub fn category_names(&self) -> Vec<&'static str> {
        RUNTIME_LOG_CATEGORIES
            .iter()
            .chain(self.model_categories)
            .map(|c| c.name)
            .collect()
    }

    /// Set debug logging: no categories means all of them.
    pub fn set_debug_logging(&mut self, logging_on: bool, categories: &[usize]) {
        self.logging_on = logging_on;
        if categories.is_empty() || categories.contains(&(Category::All as usize)) {
            self.enabled = u64::MAX;
        } else {
            self.enabled = categories.iter().fold(0, |m, c| m | (1u64 << (*c as u32 % 64)));
        }
    }

    fn enabled_index(&self, status: Status, index: usize) -> bool {
        status != OK || (self.logging_on && self.enabled & (1u64 << (index as u32 % 64)) != 0)
    }

    /// Whether a message of this category reaches the importer. Messages that explain a
    /// non-OK status are always passed on: the standard asks for a reason with every one.
    pub fn wants(&self, status: Status, category: Category) -> bool {
        self.enabled_index(status, category as usize)
    }

    pub fn log(&self, status: Status, category: Category, message: &str) {
        if self.wants(status, category) {
            self.emit(status, RUNTIME_NAMES[category as usize], message);
        }
    }

    /// For models: whether an OK message under the named category would reach the importer.
    pub fn wants_named(&self, name: &str) -> bool {
        let index = self.category_index(name).unwrap_or(Category::Events as usize);
        self.enabled_index(OK, index)
    }

    /// For models: an OK message under a category given by name (see [`crate::Context::log`]).
    pub fn log_named(&self, name: &str, message: &str) {
        match self.category_index(name) {
            Some(i) if self.enabled_index(OK, i) => self.emit(OK, &to_cstring(name), message),
            Some(_) => {}
            None => {
                if self.wants(OK, Category::Events) {
                    let text = format!("[undeclared log category '{name}'] {message}");
                    self.emit(OK, RUNTIME_NAMES[0], &text);
                }
            }
        }
    }

    fn emit(&self, status: Status, category: &CStr, message: &str) {
        match self.callback {
            Callback::Printf(callback) => {
                let text = to_cstring(message);
                // SAFETY: the callback came from the importer's fmi2CallbackFunctions; its
                // message is a printf format, so the text goes as the argument of a literal "%s".
                unsafe {
                    callback(
                        self.environment,
                        self.instance_name.as_ptr(),
                        status,
                        category.as_ptr(),
                        c"%s".as_ptr(),
                        text.as_ptr(),
                    )
                }
            }
            Callback::Message(None) => {}
            Callback::Message(Some(callback)) => {
                // FMI 3.0 has no instance name in the callback: the message starts with it.
                let text = to_cstring(&format!("[{}] {}", self.instance_name(), message));
                // SAFETY: the importer's fmi3LogMessageCallback; the message is plain text.
                unsafe { callback(self.environment, status, category.as_ptr(), text.as_ptr()) }
            }
        }
    }
}

/// A C string from any Rust text: interior NULs become '?' rather than cutting the message.
pub fn to_cstring(text: &str) -> CString {
    CString::new(text.replace('\0', "?")).unwrap_or_default()
}
