//! The FMI 3.0 smoke run: 0.1 s of co-simulation from the start values (Event Mode handled
//! where the FMU has clocks), then the declared `depends` through FMI 3.0.

use super::FMI3_FUNCTIONS;
use super::run::{add_reports, load_exporting, run_problems};
use rustfmu::description::FmiVersion;
use std::ffi::{CStr, CString, c_char, c_void};
use std::path::Path;

/// Messages the FMU logged during the smoke run, collected through the logger's environment.
struct Log(Vec<String>);

/// The importer's logger of FMI 3.0 (not variadic: the message comes formatted).
unsafe extern "C" fn collect_log3(env: *mut c_void, status: i32, category: *const c_char, message: *const c_char) {
    // SAFETY: env is the &mut Log given to fmi3InstantiateCoSimulation; strings are
    // NUL-terminated or NULL.
    unsafe {
        let log = &mut *(env as *mut Log);
        let text = |p: *const c_char| {
            if p.is_null() {
                String::new()
            } else {
                CStr::from_ptr(p).to_string_lossy().into_owned()
            }
        };
        log.0
            .push(format!("[status {status}, {}] {}", text(category), text(message)));
    }
}

/// FMI 3.0: loads the binary, checks that it exports every fmi3 function of the standard and no
/// fmi2 one, and runs 0.1 s of co-simulation from the start values. `event_mode`: with
/// eventModeUsed (an FMU with clocks requires it), its events handled in Event Mode (no clock
/// activated: the smoke run checks that the FMU steps, not its clocks).
pub fn smoke_run3(so: &Path, token: &str, real_vrs: &[u32], resources: &Path, event_mode: bool) -> Vec<String> {
    type Instance = *mut c_void;
    type LogMessage = unsafe extern "C" fn(*mut c_void, i32, *const c_char, *const c_char);
    // fmi3InstantiateCoSimulationTYPE: instanceName, instantiationToken, resourcePath, visible,
    // loggingOn, eventModeUsed, earlyReturnAllowed, requiredIntermediateVariables, their number,
    // instanceEnvironment, logMessage, intermediateUpdate.
    type InstantiateCoSimulation = unsafe extern "C" fn(
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
        Option<LogMessage>,
        *const c_void,
    ) -> Instance;
    let lib = match load_exporting(so, FMI3_FUNCTIONS) {
        Ok(lib) => lib,
        Err(problems) => return problems,
    };
    let mut problems = Vec::new();
    // SAFETY: the signatures are those of fmi3FunctionTypes.h (fmi3Boolean is C bool,
    // fmi3Status an int, fmi3ValueReference uint32_t).
    unsafe {
        let version: libloading::Symbol<unsafe extern "C" fn() -> *const c_char> = lib.get(b"fmi3GetVersion").unwrap();
        let v = CStr::from_ptr(version()).to_string_lossy().into_owned();
        if v != "3.0" {
            problems.push(format!("fmi3GetVersion returns '{v}', not '3.0'"));
        }
        let instantiate: libloading::Symbol<InstantiateCoSimulation> = lib.get(b"fmi3InstantiateCoSimulation").unwrap();
        let enter_init: libloading::Symbol<unsafe extern "C" fn(Instance, bool, f64, f64, bool, f64) -> i32> =
            lib.get(b"fmi3EnterInitializationMode").unwrap();
        let unary =
            |name: &[u8]| -> libloading::Symbol<unsafe extern "C" fn(Instance) -> i32> { lib.get(name).unwrap() };
        let do_step: libloading::Symbol<
            unsafe extern "C" fn(Instance, f64, f64, bool, *mut bool, *mut bool, *mut bool, *mut f64) -> i32,
        > = lib.get(b"fmi3DoStep").unwrap();
        let get_float64: libloading::Symbol<unsafe extern "C" fn(Instance, *const u32, usize, *mut f64, usize) -> i32> =
            lib.get(b"fmi3GetFloat64").unwrap();
        let free: libloading::Symbol<unsafe extern "C" fn(Instance)> = lib.get(b"fmi3FreeInstance").unwrap();
        type Update =
            unsafe extern "C" fn(Instance, *mut bool, *mut bool, *mut bool, *mut bool, *mut bool, *mut f64) -> i32;
        let update: libloading::Symbol<Update> = lib.get(b"fmi3UpdateDiscreteStates").unwrap();
        // Event Mode (after initialization and after a step that needs it): the updates, then Step Mode.
        let handle_events = |c: Instance| -> i32 {
            let (mut again, mut term, mut nominals, mut values, mut defined, mut next) =
                (true, false, false, false, false, 0.0);
            let mut status = 0;
            let mut rounds = 0;
            while again && status == 0 && rounds < 100 {
                status = update(
                    c,
                    &mut again,
                    &mut term,
                    &mut nominals,
                    &mut values,
                    &mut defined,
                    &mut next,
                );
                rounds += 1;
            }
            status.max(unary(b"fmi3EnterStepMode")(c))
        };

        let mut log = Log(Vec::new());
        let name = CString::new("fmu-build-validate").unwrap();
        let token = CString::new(token).unwrap_or_default();
        // FMI 3.0's resourcePath: the native path of the folder, with a trailing separator.
        let resource_path =
            CString::new(format!("{}{}", resources.display(), std::path::MAIN_SEPARATOR)).unwrap_or_default();
        let c = instantiate(
            name.as_ptr(),
            token.as_ptr(),
            resource_path.as_ptr(),
            false,
            false,
            event_mode,
            false,
            std::ptr::null(),
            0,
            &mut log as *mut Log as *mut c_void,
            Some(collect_log3),
            std::ptr::null(),
        );
        if c.is_null() {
            problems.push(format!(
                "fmi3InstantiateCoSimulation returned NULL: {}",
                log.0.join("; ")
            ));
            return problems;
        }
        let mut status = enter_init(c, false, 0.0, 0.0, true, 1.0);
        status = status.max(unary(b"fmi3ExitInitializationMode")(c));
        if event_mode && status == 0 {
            status = handle_events(c);
        }
        let mut flags = [false; 3];
        let mut reached = 0.0;
        for i in 0..10 {
            let t = i as f64 * 0.01;
            let [event, terminate, early] = &mut flags;
            status = status.max(do_step(c, t, 0.01, true, event, terminate, early, &mut reached));
            if status == 0 && (reached - (t + 0.01)).abs() > 1e-12 {
                problems.push(format!(
                    "fmi3DoStep from {t} by 0.01 returned fmi3OK with lastSuccessfulTime {reached}"
                ));
                break;
            }
            if event_mode && flags == [true, false, false] && status == 0 {
                status = unary(b"fmi3EnterEventMode")(c).max(handle_events(c));
                continue;
            }
            if flags.iter().any(|f| *f) {
                problems.push(format!(
                    "fmi3DoStep from {t}: eventHandlingNeeded, terminateSimulation, earlyReturn = {flags:?} (this FMU has no events and no early return)"
                ));
                break;
            }
        }
        let mut values = vec![0.0; real_vrs.len()];
        status = status.max(get_float64(
            c,
            real_vrs.as_ptr(),
            real_vrs.len(),
            values.as_mut_ptr(),
            values.len(),
        ));
        status = status.max(unary(b"fmi3Terminate")(c));
        free(c);
        problems.extend(run_problems(
            "fmi3",
            status.into(),
            &log.0.join("; "),
            "Float64",
            real_vrs,
            &values,
        ));
    }
    if problems.is_empty() {
        problems.extend(depends_problems(so, token, resources));
    }
    problems
}

/// The declared `depends` against the model (a rustfmu library carries its declarations):
/// through FMI 3.0 where the library has no FMI 2.0 (whose smoke run checks them otherwise),
/// and the clocked outputs' always (FMI 3.0 only has clocks).
fn depends_problems(so: &Path, token: &str, resources: &Path) -> Vec<String> {
    let mut problems = Vec::new();
    if let Ok(binary) = std::fs::read(so)
        && let Ok(lib3) = crate::library::read_library(&binary, FmiVersion::V3)
    {
        let path = format!("{}{}", resources.display(), std::path::MAIN_SEPARATOR);
        let has_fmi2 = crate::library::read_library(&binary, FmiVersion::V2).is_ok();
        let api = crate::depends_fmi3::Api3::load(
            so,
            &lib3.description,
            token,
            &path,
            lib3.interfaces.model_exchange,
            lib3.interfaces.co_simulation,
        );
        let reports = if has_fmi2 {
            api.map(|api| vec![crate::depends_fmi3::check_clocked(&api, &lib3.description)])
                .unwrap_or_default()
        } else {
            crate::depends_fmi3::check_all(api, &lib3.description)
        };
        add_reports(reports, &mut problems);
    }
    problems
}
