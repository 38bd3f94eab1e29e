//! An FMI 3.0 host: a logger that records into a [`Log`] (FMI 3.0's logger is not variadic: the
//! message is the text), reached through the instance environment, and the instantiations the
//! tests repeat. A test whose callbacks keep more than the messages (an intermediate-update or a
//! clock-update callback) gives its own environment type that implements [`Host`].

use super::{Log, LogEntry, text};
use crate::fmi3::abi::*;
use std::ffi::{CString, c_char, c_void};
use std::ptr::null;

/// What an instance's environment is: anything that holds the [`Log`] the logger records into.
pub trait Host: Sync + 'static {
    fn log(&self) -> &Log;
}

impl Host for Log {
    fn log(&self) -> &Log {
        self
    }
}

/// The logger for an instance whose environment is a `&'static H` (as [`environment`] gives it).
/// Never unwinds into the FMU: nothing here panics.
///
/// # Safety
/// `env` is NULL or [`environment::<H>`]'s pointer; `category` and `message` are NULL or
/// NUL-terminated strings alive for the call (what an FMU passes).
pub unsafe extern "C" fn logger<H: Host>(
    env: *mut c_void,
    status: fmi3Status,
    category: fmi3String,
    message: fmi3String,
) {
    if env.is_null() {
        return;
    }
    // SAFETY: the environment of an instance made with this logger is a `&'static H`
    // (`environment::<H>`, the only pairing the instantiations here make).
    let host = unsafe { &*(env as *const H) };
    // SAFETY: the strings are the FMU's, NULL or NUL-terminated and valid for the call.
    let (category, text) = unsafe { (text(category), text(message)) };
    host.log().push(LogEntry { status, category, text });
}

/// `host` as an instance environment, for [`logger::<H>`] and the test's own callbacks.
pub fn environment<H: Host>(host: &'static H) -> *mut c_void {
    host as *const H as *mut c_void
}

/// The signature of `fmi3InstantiateCoSimulation`.
pub type InstantiateCs = unsafe extern "C" fn(
    *const c_char,
    *const c_char,
    *const c_char,
    bool,
    bool,
    bool,
    bool,
    *const u32,
    usize,
    *mut c_void,
    fmi3LogMessageCallback,
    fmi3IntermediateUpdateCallback,
) -> fmi3Instance;

/// The signature of `fmi3InstantiateModelExchange`.
pub type InstantiateMe = unsafe extern "C" fn(
    *const c_char,
    *const c_char,
    *const c_char,
    bool,
    bool,
    *mut c_void,
    fmi3LogMessageCallback,
) -> fmi3Instance;

/// The signature of `fmi3InstantiateScheduledExecution`.
pub type InstantiateSe = unsafe extern "C" fn(
    *const c_char,
    *const c_char,
    *const c_char,
    bool,
    bool,
    *mut c_void,
    fmi3LogMessageCallback,
    fmi3ClockUpdateCallback,
    fmi3LockPreemptionCallback,
    fmi3UnlockPreemptionCallback,
) -> fmi3Instance;

/// The arguments of an `fmi3Instantiate...` a host chooses (no resources, not visible; the
/// token is the model's, the logger records into the host's [`Log`]).
#[derive(Debug, Clone, Copy)]
pub struct Instantiation<'a> {
    pub name: &'a str,
    pub logging_on: bool,
    /// Co-simulation only.
    pub event_mode_used: bool,
    /// Co-simulation only.
    pub early_return_allowed: bool,
    /// Co-simulation only.
    pub required_intermediate_variables: &'a [fmi3ValueReference],
}

impl<'a> Instantiation<'a> {
    /// An instance named `name`, logging off, no Event Mode, no early return.
    pub fn new(name: &'a str) -> Self {
        Instantiation {
            name,
            logging_on: false,
            event_mode_used: false,
            early_return_allowed: false,
            required_intermediate_variables: &[],
        }
    }

    /// A co-simulation instance (NULL when refused) whose environment is `host`.
    pub fn co_simulation<H: Host>(
        &self,
        instantiate: InstantiateCs,
        token: &str,
        host: &'static H,
        intermediate_update: fmi3IntermediateUpdateCallback,
    ) -> fmi3Instance {
        let (name, token) = c_strings(self.name, token);
        let required = self.required_intermediate_variables;
        // SAFETY: `instantiate` is an fmi3InstantiateCoSimulation (the type says so, the caller
        // took it from the model); the strings are valid for the call, the required references
        // as many as passed, and the environment outlives the instance (leaked) and is what
        // `logger::<H>` (and the test's callback) read it as.
        unsafe {
            instantiate(
                name.as_ptr(),
                token.as_ptr(),
                null(),
                false,
                self.logging_on,
                self.event_mode_used,
                self.early_return_allowed,
                if required.is_empty() { null() } else { required.as_ptr() },
                required.len(),
                environment(host),
                Some(logger::<H>),
                intermediate_update,
            )
        }
    }

    /// A model-exchange instance (NULL when refused) whose environment is `host`.
    pub fn model_exchange<H: Host>(&self, instantiate: InstantiateMe, token: &str, host: &'static H) -> fmi3Instance {
        let (name, token) = c_strings(self.name, token);
        // SAFETY: as in `co_simulation`, for an fmi3InstantiateModelExchange.
        unsafe {
            instantiate(
                name.as_ptr(),
                token.as_ptr(),
                null(),
                false,
                self.logging_on,
                environment(host),
                Some(logger::<H>),
            )
        }
    }

    /// A scheduled-execution instance (NULL when refused) whose environment is `host`, without
    /// preemption callbacks.
    pub fn scheduled_execution<H: Host>(
        &self,
        instantiate: InstantiateSe,
        token: &str,
        host: &'static H,
        clock_update: fmi3ClockUpdateCallback,
    ) -> fmi3Instance {
        let (name, token) = c_strings(self.name, token);
        // SAFETY: as in `co_simulation`, for an fmi3InstantiateScheduledExecution.
        unsafe {
            instantiate(
                name.as_ptr(),
                token.as_ptr(),
                null(),
                false,
                self.logging_on,
                environment(host),
                Some(logger::<H>),
                clock_update,
                None,
                None,
            )
        }
    }
}

fn c_strings(name: &str, token: &str) -> (CString, CString) {
    (
        CString::new(name).expect("a name without NUL"),
        CString::new(token).expect("a token without NUL"),
    )
}

/// A co-simulation instance named `name` of the model whose `instantiate` and `token` these
/// are, and the log it records into; panics with what was logged if the FMU refused.
pub fn instance(instantiate: InstantiateCs, token: &str, name: &str) -> (fmi3Instance, &'static Log) {
    let log = Log::leak();
    let c = Instantiation::new(name).co_simulation(instantiate, token, log, None);
    assert!(!c.is_null(), "instantiation failed: {:?}", log.messages());
    (c, log)
}

/// A model-exchange instance named `name`, as [`instance`].
pub fn me_instance(instantiate: InstantiateMe, token: &str, name: &str) -> (fmi3Instance, &'static Log) {
    let log = Log::leak();
    let c = Instantiation::new(name).model_exchange(instantiate, token, log);
    assert!(!c.is_null(), "instantiation failed: {:?}", log.messages());
    (c, log)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_logger_records_status_category_and_message_into_the_hosts_log() {
        struct Probe {
            log: Log,
        }
        impl Host for Probe {
            fn log(&self) -> &Log {
                &self.log
            }
        }
        let probe: &'static Probe = Box::leak(Box::new(Probe { log: Log::default() }));
        // SAFETY: called as an FMU calls it, with the environment `environment` gives.
        unsafe {
            logger::<Probe>(environment(probe), fmi3Warning, c"logAll".as_ptr(), c"hello".as_ptr());
            logger::<Probe>(std::ptr::null_mut(), fmi3OK, c"logAll".as_ptr(), c"lost".as_ptr());
        }
        assert_eq!(
            probe.log.entries(),
            vec![LogEntry {
                status: fmi3Warning,
                category: "logAll".into(),
                text: "hello".into()
            }]
        );
        assert_eq!(probe.log.last(), "hello");
    }
}
