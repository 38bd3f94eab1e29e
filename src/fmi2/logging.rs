//! The importer's logger, called the way the standard requires.
#![allow(non_upper_case_globals)]

use super::abi::*;
use std::ffi::{CStr, CString};

/// Log categories declared in `<LogCategories>`; every message is logged under one of them.
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

/// (name, description) of each category, in [`Category`] order.
pub const CATEGORIES: &[(&str, &str)] = &[
    (
        "logEvents",
        "Initialization, steps that change the solver's course, parameter changes",
    ),
    ("logStatusWarning", "Messages that come with fmi2Warning"),
    (
        "logStatusDiscard",
        "Messages that come with fmi2Discard: a step that could not be completed",
    ),
    (
        "logStatusError",
        "Messages that come with fmi2Error: a refused call or argument",
    ),
    (
        "logStatusFatal",
        "Messages that come with fmi2Fatal: the instance cannot be used any more",
    ),
    ("logCalls", "Every call of an fmi2 function, with its arguments"),
    ("logAll", "All of the above"),
];

const CATEGORY_NAMES: [&CStr; 7] = [
    c"logEvents",
    c"logStatusWarning",
    c"logStatusDiscard",
    c"logStatusError",
    c"logStatusFatal",
    c"logCalls",
    c"logAll",
];

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

    pub fn from_name(name: &str) -> Option<Category> {
        CATEGORIES.iter().position(|(n, _)| *n == name).map(|i| match i {
            0 => Category::Events,
            1 => Category::StatusWarning,
            2 => Category::StatusDiscard,
            3 => Category::StatusError,
            4 => Category::StatusFatal,
            5 => Category::Calls,
            _ => Category::All,
        })
    }

    fn bit(self) -> u32 {
        1 << (self as u8)
    }
}

/// The callback with what it needs: environment pointer, instance name, logging switches.
#[derive(Debug)]
pub struct Logger {
    callback: unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...),
    environment: fmi2ComponentEnvironment,
    instance_name: CString,
    logging_on: bool,
    enabled: u32,
}

const ALL_CATEGORIES: u32 = (1 << CATEGORIES.len()) - 1;

impl Logger {
    /// `None` when the importer gave no logger: the standard then asks for a NULL instance.
    pub fn new(callbacks: &fmi2CallbackFunctions, instance_name: &str, logging_on: bool) -> Option<Logger> {
        Some(Logger {
            callback: callbacks.logger?,
            environment: callbacks.componentEnvironment,
            instance_name: to_cstring(instance_name),
            logging_on,
            enabled: ALL_CATEGORIES,
        })
    }

    pub fn instance_name(&self) -> &str {
        self.instance_name.to_str().unwrap_or("")
    }

    /// `fmi2SetDebugLogging`: no categories means all of them.
    pub fn set_debug_logging(&mut self, logging_on: bool, categories: &[Category]) {
        self.logging_on = logging_on;
        if categories.is_empty() || categories.contains(&Category::All) {
            self.enabled = ALL_CATEGORIES;
        } else {
            self.enabled = categories.iter().fold(0, |m, c| m | c.bit());
        }
    }

    /// Whether a message of this category reaches the importer. Messages that explain a
    /// non-OK status are always passed on: the standard asks for a reason with every one.
    pub fn wants(&self, status: fmi2Status, category: Category) -> bool {
        status != fmi2OK || (self.logging_on && self.enabled & (category.bit() | Category::All.bit()) != 0)
    }

    pub fn log(&self, status: fmi2Status, category: Category, message: &str) {
        if !self.wants(status, category) {
            return;
        }
        let text = to_cstring(message);
        let category_name = CATEGORY_NAMES[category as usize];
        // SAFETY: the callback came from the importer's fmi2CallbackFunctions; its message is a
        // printf format, so the text goes as the argument of a literal "%s".
        unsafe {
            (self.callback)(
                self.environment,
                self.instance_name.as_ptr(),
                status,
                category_name.as_ptr(),
                c"%s".as_ptr(),
                text.as_ptr(),
            )
        }
    }
}

/// A C string from any Rust text: interior NULs become '?' rather than cutting the message.
pub fn to_cstring(text: &str) -> CString {
    CString::new(text.replace('\0', "?")).unwrap_or_default()
}
