//! An FMI 2.0 host: the callbacks an instance needs (a logger that records into a [`Log`], or one
//! that drops everything) and the instantiation every test repeats.
//!
//! Why the recording logger is sound: FMI 2.0's logger is C-variadic (`message` is a printf
//! format). A rustfmu FMU always logs with the format `"%s"` and the text as the one variadic
//! argument; on every ABI this project builds for (x86-64 System V and Windows, AArch64 Linux) a
//! variadic argument that follows the fixed ones is passed where a fixed sixth pointer argument
//! would be, so a function with six fixed arguments reads it. The recording logger reads the text
//! only when the format is exactly `"%s"` and records any other format as it is. On Apple silicon
//! variadic arguments go on the stack: there it records the format, never the argument.

use super::{Log, LogEntry, text};
use crate::fmi2::abi::*;
use std::ffi::{CStr, CString, c_char};

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
        unsafe { super::text(argument) }
    } else {
        format
    };
    // SAFETY: `callbacks` is the only way this function gets to an FMU, and it passes a
    // `&'static Log` as componentEnvironment.
    let log = unsafe { &*(env as *const Log) };
    log.push(LogEntry { status, category, text });
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

/// The signature of `fmi2Instantiate`: the model's own (a test binary's export, or a symbol of a
/// loaded binary).
pub type Instantiate = fmi2InstantiateTYPE;

/// The arguments of `fmi2Instantiate` a host chooses (the GUID is the model's, the callbacks
/// record into a [`Log`]).
#[derive(Debug, Clone, Copy)]
pub struct Instantiation<'a> {
    pub name: &'a CStr,
    pub kind: fmi2Type,
    /// `fmuResourceLocation`, or NULL.
    pub resource_location: Option<&'a CStr>,
    pub logging_on: bool,
}

impl<'a> Instantiation<'a> {
    /// An instance of `kind` named `name`, no resources, logging off.
    pub fn new(kind: fmi2Type, name: &'a CStr) -> Self {
        Instantiation {
            name,
            kind,
            resource_location: None,
            logging_on: false,
        }
    }

    /// Calls `instantiate` with these arguments, the model's `guid` and callbacks that record
    /// into `log`: the instance, or NULL when the FMU refused (`log` says why).
    pub fn call(&self, instantiate: Instantiate, guid: &str, log: &'static Log) -> fmi2Component {
        self.call_with(instantiate, guid, callbacks(log))
    }

    /// [`call`](Self::call) with callbacks of the caller's (e.g. [`silent_callbacks`]).
    pub fn call_with(
        &self,
        instantiate: Instantiate,
        guid: &str,
        callbacks: &'static fmi2CallbackFunctions,
    ) -> fmi2Component {
        let guid = CString::new(guid).expect("a GUID without NUL");
        // SAFETY: `instantiate` is an fmi2Instantiate (the type says so, the caller took it from
        // the model); the strings are valid for the call, the callbacks outlive the instance
        // (`'static`).
        unsafe {
            instantiate(
                self.name.as_ptr(),
                self.kind,
                guid.as_ptr(),
                self.resource_location.map_or(std::ptr::null(), CStr::as_ptr),
                callbacks,
                fmi2False,
                self.logging_on as fmi2Boolean,
            )
        }
    }
}

/// An instance of `kind` named `name` of the model whose `fmi2Instantiate` and GUID these are,
/// logging into `log`; panics with what was logged if the FMU refused.
pub fn instance(instantiate: Instantiate, guid: &str, kind: fmi2Type, name: &CStr, log: &'static Log) -> fmi2Component {
    let c = Instantiation::new(kind, name).call(instantiate, guid, log);
    assert!(!c.is_null(), "fmi2Instantiate refused {name:?}: {:?}", log.texts());
    c
}

/// A co-simulation instance: [`instance`] with `fmi2CoSimulation`.
pub fn cs_instance(instantiate: Instantiate, guid: &str, name: &CStr, log: &'static Log) -> fmi2Component {
    instance(instantiate, guid, fmi2CoSimulation, name, log)
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
