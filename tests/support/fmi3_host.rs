//! What the FMI 3.0 tests of this folder share as a host: a logger that keeps the messages, and
//! a co-simulation instance of the model the test binary exports, taken through initialization
//! when asked. (`mod support;` in the test file; the model's exported functions are passed in,
//! since each test binary exports its own.)

use rustfmu::__private::abi3::*;
use std::ffi::{CStr, CString, c_char, c_void};
use std::ptr::null;
use std::sync::Mutex;

/// The messages an instance logged.
#[derive(Default)]
pub struct Log(pub Mutex<Vec<String>>);

impl Log {
    /// The last message, or "".
    pub fn last(&self) -> String {
        self.0.lock().unwrap().last().cloned().unwrap_or_default()
    }
}

unsafe extern "C" fn collect(env: *mut c_void, _status: fmi3Status, _category: fmi3String, message: fmi3String) {
    // SAFETY: env is the leaked &Log given at instantiation; the string is the runtime's.
    let (log, message) = unsafe { (&*(env as *const Log), CStr::from_ptr(message)) };
    log.0.lock().unwrap().push(message.to_string_lossy().into_owned());
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

/// A co-simulation instance named `name` of the model whose `instantiate` and `token` these are.
pub fn instance(instantiate: InstantiateCs, token: &str, name: &str) -> (fmi3Instance, &'static Log) {
    let log: &'static Log = Box::leak(Box::default());
    let (token, name) = (CString::new(token).unwrap(), CString::new(name).unwrap());
    // SAFETY: valid strings and a logger whose environment outlives the instance.
    let c = unsafe {
        instantiate(
            name.as_ptr(),
            token.as_ptr(),
            null(),
            false,
            false,
            false,
            false,
            null(),
            0,
            log as *const Log as *mut c_void,
            Some(collect),
            None,
        )
    };
    assert!(!c.is_null(), "instantiation failed: {:?}", log.0.lock().unwrap());
    (c, log)
}

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

/// A model-exchange instance named `name` of the model whose `instantiate` and `token` these are.
#[allow(dead_code)]
pub fn me_instance(instantiate: InstantiateMe, token: &str, name: &str) -> (fmi3Instance, &'static Log) {
    let log: &'static Log = Box::leak(Box::default());
    let (token, name) = (CString::new(token).unwrap(), CString::new(name).unwrap());
    // SAFETY: valid strings and a logger whose environment outlives the instance.
    let c = unsafe {
        instantiate(
            name.as_ptr(),
            token.as_ptr(),
            null(),
            false,
            false,
            log as *const Log as *mut c_void,
            Some(collect),
        )
    };
    assert!(!c.is_null(), "instantiation failed: {:?}", log.0.lock().unwrap());
    (c, log)
}
