//! The importer's logger, called the way the standard requires.
#![allow(non_upper_case_globals)]

use super::abi::*;
use crate::description::{LogCategory, RUNTIME_LOG_CATEGORIES};
use std::ffi::{CStr, CString};

/// The runtime's own categories, in [`RUNTIME_LOG_CATEGORIES`] order; a model's declared
/// categories follow them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Category {
    Events = 0,
    StatusWarning = 1,
    StatusDiscard = 2,
    StatusError = 3,
    StatusFatal = 4,
    Calls = 5,
    All = 6,
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
    pub fn for_status(status: fmi2Status) -> Category {
        match status {
            fmi2Warning => Category::StatusWarning,
            fmi2Discard => Category::StatusDiscard,
            fmi2Error => Category::StatusError,
            fmi2Fatal => Category::StatusFatal,
            _ => Category::Events,
        }
    }
}

/// The importer's callback, of either version.
#[derive(Debug, Clone, Copy)]
enum Callback {
    /// `fmi2CallbackLogger`: a printf-style function with the instance name.
    Fmi2(unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...)),
    /// `fmi3LogMessageCallback`: a finished message; NULL is allowed (nothing is logged).
    Fmi3(crate::fmi3::abi::fmi3LogMessageCallback),
}

/// The callback with what it needs: environment pointer, instance name, logging switches.
#[derive(Debug, Clone)]
pub struct Logger {
    callback: Callback,
    environment: fmi2ComponentEnvironment,
    instance_name: CString,
    logging_on: bool,
    /// Bit i: category i of runtime ++ model categories is enabled.
    enabled: u64,
    model_categories: &'static [LogCategory],
}

impl Logger {
    /// `None` when the importer gave no logger: the standard then asks for a NULL instance.
    pub fn new(
        callbacks: &fmi2CallbackFunctions,
        instance_name: &str,
        logging_on: bool,
        model_categories: &'static [LogCategory],
    ) -> Option<Logger> {
        Some(Logger {
            callback: Callback::Fmi2(callbacks.logger?),
            environment: callbacks.componentEnvironment,
            instance_name: to_cstring(instance_name),
            logging_on,
            enabled: u64::MAX,
            model_categories,
        })
    }

    /// The FMI 3.0 logger: `logMessage` may be NULL (then nothing reaches the importer).
    pub fn new_fmi3(
        callback: crate::fmi3::abi::fmi3LogMessageCallback,
        environment: crate::fmi3::abi::fmi3InstanceEnvironment,
        instance_name: &str,
        logging_on: bool,
        model_categories: &'static [LogCategory],
    ) -> Logger {
        Logger {
            callback: Callback::Fmi3(callback),
            environment,
            instance_name: to_cstring(instance_name),
            logging_on,
            enabled: u64::MAX,
            model_categories,
        }
    }

    /// Whether this is an FMI 3.0 instance's logger.
    pub fn is_fmi3(&self) -> bool {
        matches!(self.callback, Callback::Fmi3(_))
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

    /// `fmi2SetDebugLogging`: no categories means all of them.
    pub fn set_debug_logging(&mut self, logging_on: bool, categories: &[usize]) {
        self.logging_on = logging_on;
        if categories.is_empty() || categories.contains(&(Category::All as usize)) {
            self.enabled = u64::MAX;
        } else {
            self.enabled = categories.iter().fold(0, |m, c| m | (1u64 << (*c as u32 % 64)));
        }
    }

    fn enabled_index(&self, status: fmi2Status, index: usize) -> bool {
        status != fmi2OK || (self.logging_on && self.enabled & (1u64 << (index as u32 % 64)) != 0)
    }

    /// Whether a message of this category reaches the importer. Messages that explain a
    /// non-OK status are always passed on: the standard asks for a reason with every one.
    pub fn wants(&self, status: fmi2Status, category: Category) -> bool {
        self.enabled_index(status, category as usize)
    }

    pub fn log(&self, status: fmi2Status, category: Category, message: &str) {
        if self.wants(status, category) {
            self.emit(status, RUNTIME_NAMES[category as usize], message);
        }
    }

    /// For models: whether an OK message under the named category would reach the importer.
    pub fn wants_named(&self, name: &str) -> bool {
        let index = self.category_index(name).unwrap_or(Category::Events as usize);
        self.enabled_index(fmi2OK, index)
    }

    /// For models: an OK message under a category given by name (see [`crate::Context::log`]).
    pub fn log_named(&self, name: &str, message: &str) {
        match self.category_index(name) {
            Some(i) if self.enabled_index(fmi2OK, i) => self.emit(fmi2OK, &to_cstring(name), message),
            Some(_) => {}
            None => {
                if self.wants(fmi2OK, Category::Events) {
                    let text = format!("[undeclared log category '{name}'] {message}");
                    self.emit(fmi2OK, RUNTIME_NAMES[0], &text);
                }
            }
        }
    }

    fn emit(&self, status: fmi2Status, category: &CStr, message: &str) {
        match self.callback {
            Callback::Fmi2(callback) => {
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
            Callback::Fmi3(None) => {}
            Callback::Fmi3(Some(callback)) => {
                // FMI 3.0 has no instance name in the callback: the message starts with it.
                let text = to_cstring(&format!("[{}] {}", self.instance_name(), in_fmi3_terms(message)));
                // SAFETY: the importer's fmi3LogMessageCallback; the message is plain text.
                unsafe { callback(self.environment, status, category.as_ptr(), text.as_ptr()) }
            }
        }
    }
}

/// The instance core ([`super::instance`]) words its messages in FMI 2.0's names; an FMI 3.0
/// instance's logger says them in FMI 3.0's: the renamed functions, the other `fmi2*` names
/// with their `fmi3` prefix, the co-simulation states' 3.0 names.
pub fn in_fmi3_terms(message: &str) -> String {
    const RENAMED: [(&str, &str); 14] = [
        ("fmi2GetReal", "fmi3GetFloat64"),
        ("fmi2SetReal", "fmi3SetFloat64"),
        ("fmi2GetInteger", "fmi3GetInt32"),
        ("fmi2SetInteger", "fmi3SetInt32"),
        ("fmi2GetDerivatives", "fmi3GetContinuousStateDerivatives"),
        ("fmi2NewDiscreteStates", "fmi3UpdateDiscreteStates"),
        ("fmi2SetupExperiment", "fmi3EnterInitializationMode"),
        ("fmi2GetFMUstate", "fmi3GetFMUState"),
        ("fmi2SetFMUstate", "fmi3SetFMUState"),
        ("fmi2FreeFMUstate", "fmi3FreeFMUState"),
        ("fmi2SerializedFMUstateSize", "fmi3SerializedFMUStateSize"),
        ("fmi2SerializeFMUstate", "fmi3SerializeFMUState"),
        ("fmi2DeSerializeFMUstate", "fmi3DeserializeFMUState"),
        ("fmi2GetRealOutputDerivatives", "fmi3GetOutputDerivatives"),
    ];
    const STATES: [(&str, &str); 3] = [
        ("StepComplete", "StepMode"),
        ("StepFailed", "StepDiscarded"),
        ("GUID", "instantiationToken"),
    ];
    if !message.contains("fmi2") && !STATES.iter().any(|(a, _)| message.contains(a)) {
        return message.to_string();
    }
    let mut out = String::with_capacity(message.len() + 16);
    let mut rest = message;
    while let Some(at) = rest.find("fmi2") {
        out.push_str(&rest[..at]);
        let word_len = rest[at..]
            .find(|c: char| !c.is_ascii_alphanumeric())
            .unwrap_or(rest.len() - at);
        let word = &rest[at..at + word_len];
        match RENAMED.iter().find(|(a, _)| *a == word) {
            Some((_, b)) => out.push_str(b),
            None => {
                out.push_str("fmi3");
                out.push_str(&word[4..]);
            }
        }
        rest = &rest[at + word_len..];
    }
    out.push_str(rest);
    for (a, b) in STATES {
        if out.contains(a) {
            out = out.replace(a, b);
        }
    }
    out
}

/// A C string from any Rust text: interior NULs become '?' rather than cutting the message.
pub fn to_cstring(text: &str) -> CString {
    CString::new(text.replace('\0', "?")).unwrap_or_default()
}
