//! What the FMI 2.0 tests of this folder share as a host: a co-simulation instance of the
//! model the test binary exports, logging into a leaked `rustfmu::testing::Log`. (`mod
//! fmi2_host;` in the test file; the model's exported `fmi2Instantiate` and GUID are passed in,
//! since each test binary exports its own.)

use rustfmu::__private::abi::*;
use std::ffi::{CStr, CString};

/// The signature of `fmi2Instantiate`.
pub type Instantiate = unsafe extern "C" fn(
    fmi2String,
    fmi2Type,
    fmi2String,
    fmi2String,
    *const fmi2CallbackFunctions,
    fmi2Boolean,
    fmi2Boolean,
) -> fmi2Component;

/// A co-simulation instance named `name` of the model whose `fmi2Instantiate` and GUID these
/// are, logging into `log`; panics if it is NULL.
pub fn cs_instance(
    instantiate: Instantiate,
    guid: &str,
    name: &CStr,
    log: &'static rustfmu::testing::Log,
) -> fmi2Component {
    let guid = CString::new(guid).unwrap();
    // SAFETY: valid strings and callbacks that outlive the instance (leaked).
    let c = unsafe {
        instantiate(
            name.as_ptr(),
            fmi2CoSimulation,
            guid.as_ptr(),
            std::ptr::null(),
            rustfmu::testing::callbacks(log),
            fmi2False,
            fmi2False,
        )
    };
    assert!(!c.is_null());
    c
}
