//! The FMI 2.0 smoke run: 0.1 s of co-simulation from the start values, then the declared
//! `depends` against the model's directional derivatives.

use super::FMI2_CS_FUNCTIONS;
use super::run::{add_reports, load_exporting, run_problems};
use crate::library::file_uri;
use rustfmu::__private::abi::*;
use rustfmu::description::FmiVersion;
use std::ffi::{CStr, CString};
use std::path::Path;

/// The messages of a recording log as one line.
fn joined(log: &rustfmu::testing::Log) -> String {
    log.entries()
        .iter()
        .map(|e| format!("[status {}, {}] {}", e.status, e.category, e.text))
        .collect::<Vec<_>>()
        .join("; ")
}

/// Loads the binary, checks its exports, and runs 0.1 s from the start values.
pub fn smoke_run(so: &Path, guid: &str, real_vrs: &[u32], resources: &Path) -> Vec<String> {
    let lib = match load_exporting(so, FMI2_CS_FUNCTIONS) {
        Ok(lib) => lib,
        Err(problems) => return problems,
    };
    let mut problems = Vec::new();
    // SAFETY: the signatures are the standard's (proved against fmi-sys in the rustfmu tests).
    unsafe {
        let version: libloading::Symbol<unsafe extern "C" fn() -> fmi2String> = lib.get(b"fmi2GetVersion").unwrap();
        let v = CStr::from_ptr(version()).to_string_lossy().into_owned();
        if v != "2.0" {
            problems.push(format!("fmi2GetVersion returns '{v}', not '2.0'"));
        }
        // The function types of fmi2FunctionTypes.h, as the runtime's ABI names them.
        let instantiate: libloading::Symbol<fmi2InstantiateTYPE> = lib.get(b"fmi2Instantiate").unwrap();
        let setup: libloading::Symbol<fmi2SetupExperimentTYPE> = lib.get(b"fmi2SetupExperiment").unwrap();
        let unary = |name: &[u8]| -> libloading::Symbol<fmi2ComponentFunctionTYPE> { lib.get(name).unwrap() };
        let do_step: libloading::Symbol<fmi2DoStepTYPE> = lib.get(b"fmi2DoStep").unwrap();
        let get_real: libloading::Symbol<fmi2GetTYPE<fmi2Real>> = lib.get(b"fmi2GetReal").unwrap();
        let free: libloading::Symbol<fmi2FreeInstanceTYPE> = lib.get(b"fmi2FreeInstance").unwrap();

        // The smoke run's one instance: its log and callbacks are leaked (a few hundred bytes).
        let log = rustfmu::testing::Log::leak();
        let callbacks = rustfmu::testing::callbacks(log);
        let name = CString::new("fmu-build-validate").unwrap();
        let guid = CString::new(guid).unwrap_or_default();
        let location = CString::new(file_uri(resources)).unwrap_or_default();
        let c = instantiate(
            name.as_ptr(),
            fmi2CoSimulation,
            guid.as_ptr(),
            location.as_ptr(),
            callbacks,
            fmi2False,
            fmi2False,
        );
        if c.is_null() {
            problems.push(format!("fmi2Instantiate returned NULL: {}", joined(log)));
            return problems;
        }
        let mut status = setup(c, fmi2False, 0.0, 0.0, fmi2True, 1.0);
        for f in [&b"fmi2EnterInitializationMode"[..], b"fmi2ExitInitializationMode"] {
            status = status.max(unary(f)(c));
        }
        for i in 0..10 {
            status = status.max(do_step(c, i as f64 * 0.01, 0.01, fmi2True));
        }
        let mut values = vec![0.0; real_vrs.len()];
        status = status.max(get_real(c, real_vrs.as_ptr(), real_vrs.len(), values.as_mut_ptr()));
        status = status.max(unary(b"fmi2Terminate")(c));
        free(c);
        problems.extend(run_problems(
            "fmi2",
            status.into(),
            &joined(log),
            "Real",
            real_vrs,
            &values,
        ));
    }
    if problems.is_empty() {
        problems.extend(depends_problems(so, guid, resources));
    }
    problems
}

/// The declared `depends` against the model's exact directional derivatives (a rustfmu
/// library carries its declarations; another FMU's binary is not checked here).
fn depends_problems(so: &Path, guid: &str, resources: &Path) -> Vec<String> {
    let mut problems = Vec::new();
    if let Ok(binary) = std::fs::read(so)
        && let Ok(me) = crate::library::read_library(&binary, FmiVersion::V2)
    {
        let uri = file_uri(resources);
        let mut reports = vec![crate::depends_fmi2::check_initial(
            so,
            &me.description,
            guid,
            &uri,
            me.interfaces.co_simulation,
        )];
        if me.interfaces.model_exchange {
            reports.push(crate::depends_fmi2::check(so, &me.description, guid, &uri));
        }
        add_reports(reports, &mut problems);
    }
    problems
}
