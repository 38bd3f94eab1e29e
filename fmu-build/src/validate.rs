//! Checks on a packaged FMU, each reported as a readable problem (an empty list: valid).
//! Archive layout, the description against the declarations it came from, the binary's
//! exported functions, and a short run through the C API as an importer makes it.

use quick_xml::Reader;
use quick_xml::events::Event;
use rustfmu::fmi2::abi::*;
use std::ffi::{CStr, CString, c_char};
use std::io::Read;
use std::path::Path;

/// Every function of the FMI 2.0 co-simulation interface.
pub const FMI2_CS_FUNCTIONS: &[&str] = &[
    "fmi2GetTypesPlatform",
    "fmi2GetVersion",
    "fmi2SetDebugLogging",
    "fmi2Instantiate",
    "fmi2FreeInstance",
    "fmi2SetupExperiment",
    "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode",
    "fmi2Terminate",
    "fmi2Reset",
    "fmi2GetReal",
    "fmi2GetInteger",
    "fmi2GetBoolean",
    "fmi2GetString",
    "fmi2SetReal",
    "fmi2SetInteger",
    "fmi2SetBoolean",
    "fmi2SetString",
    "fmi2GetFMUstate",
    "fmi2SetFMUstate",
    "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize",
    "fmi2SerializeFMUstate",
    "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative",
    "fmi2SetRealInputDerivatives",
    "fmi2GetRealOutputDerivatives",
    "fmi2DoStep",
    "fmi2CancelStep",
    "fmi2GetStatus",
    "fmi2GetRealStatus",
    "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus",
    "fmi2GetStringStatus",
];

struct Description {
    model_identifier: String,
    guid: String,
    real_vrs: Vec<u32>,
}

fn read_description(xml: &str) -> Result<Description, String> {
    let mut reader = Reader::from_str(xml);
    let mut d = Description {
        model_identifier: String::new(),
        guid: String::new(),
        real_vrs: vec![],
    };
    let mut fmi_version = String::new();
    let mut in_var: Option<u32> = None;
    loop {
        match reader.read_event() {
            Err(e) => {
                return Err(format!(
                    "modelDescription.xml is not well-formed at byte {}: {e}",
                    reader.error_position()
                ));
            }
            Ok(Event::Eof) => break,
            Ok(Event::Start(e) | Event::Empty(e)) => {
                let attr = |name: &[u8]| -> Option<String> {
                    e.attributes()
                        .flatten()
                        .find(|a| a.key.as_ref() == name)
                        .and_then(|a| a.unescape_value().ok())
                        .map(|v| v.into_owned())
                };
                match e.name().as_ref() {
                    b"fmiModelDescription" => {
                        fmi_version = attr(b"fmiVersion").unwrap_or_default();
                        d.guid = attr(b"guid").unwrap_or_default();
                    }
                    b"CoSimulation" => d.model_identifier = attr(b"modelIdentifier").unwrap_or_default(),
                    b"ScalarVariable" => in_var = attr(b"valueReference").and_then(|v| v.parse().ok()),
                    b"Real" => {
                        if let Some(vr) = in_var.take() {
                            d.real_vrs.push(vr);
                        }
                    }
                    _ => {}
                }
            }
            Ok(_) => {}
        }
    }
    if fmi_version != "2.0" {
        return Err(format!("fmiVersion is '{fmi_version}', expected '2.0'"));
    }
    if d.model_identifier.is_empty() {
        return Err("no <CoSimulation modelIdentifier=...>".into());
    }
    Ok(d)
}

pub fn validate(fmu: &Path) -> Vec<String> {
    match validate_inner(fmu) {
        Ok(problems) => problems,
        Err(e) => vec![e],
    }
}

fn validate_inner(fmu: &Path) -> Result<Vec<String>, String> {
    let mut problems = Vec::new();
    let file = std::fs::File::open(fmu).map_err(|e| format!("cannot open: {e}"))?;
    let mut zip = zip::ZipArchive::new(file).map_err(|e| format!("not a zip archive: {e}"))?;
    let names: Vec<String> = zip
        .file_names()
        .map(|n| n.map(|s| s.into_owned()))
        .collect::<Result<_, _>>()
        .map_err(|e| format!("unreadable archive entry name: {e}"))?;
    for name in names {
        if name.contains('\\') || name.starts_with('/') || name.starts_with("./") {
            problems.push(format!(
                "archive entry '{name}' must use forward slashes and no leading '/' or './'"
            ));
        }
    }
    let mut xml = String::new();
    zip.by_name("modelDescription.xml")
        .map_err(|_| "no modelDescription.xml at the archive's root".to_string())?
        .read_to_string(&mut xml)
        .map_err(|e| format!("modelDescription.xml: {e}"))?;
    let d = read_description(&xml)?;
    match rustfmu::fmus::ALL
        .iter()
        .find(|e| e.info.identifier == d.model_identifier)
    {
        Some(entry) => match (entry.model_description)() {
            Ok(generated) if generated == xml => {}
            Ok(_) => problems
                .push("modelDescription.xml differs from what the declarations generate (stale package?)".into()),
            Err(e) => problems.push(format!("the declarations are invalid: {e}")),
        },
        None => problems.push(format!(
            "modelIdentifier '{}' is not an FMU of this workspace",
            d.model_identifier
        )),
    }
    let (folder, ext) = crate::package::platform()?;
    let bin_name = format!("binaries/{folder}/{}.{ext}", d.model_identifier);
    let mut binary = Vec::new();
    zip.by_name(&bin_name)
        .map_err(|_| format!("no {bin_name} (the binary is named after modelIdentifier, without a 'lib' prefix)"))?
        .read_to_end(&mut binary)
        .map_err(|e| format!("{bin_name}: {e}"))?;
    let dir = std::env::temp_dir().join(format!(
        "fmu-build-validate-{}-{}",
        std::process::id(),
        d.model_identifier
    ));
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let so = dir.join(format!("{}.{ext}", d.model_identifier));
    std::fs::write(&so, &binary).map_err(|e| format!("{}: {e}", so.display()))?;
    problems.extend(smoke_run(&so, &d));
    let _ = std::fs::remove_dir_all(&dir);
    Ok(problems)
}

/// Messages the FMU logged during the smoke run, collected through the logger's environment.
struct Log(Vec<String>);

/// The importer's logger. FMI declares it variadic; Rust cannot define variadic functions on
/// stable, and under the x86-64 and AArch64 C calling conventions a callee with the fixed
/// arguments only reads them correctly (fmpy's ctypes logger relies on the same). The message
/// is always the format "%s" here, so the text is the first variadic argument: read it as such.
unsafe extern "C" fn collect_log(
    env: fmi2ComponentEnvironment,
    _name: fmi2String,
    status: fmi2Status,
    category: fmi2String,
    message: fmi2String,
    arg: *const c_char,
) {
    // SAFETY: env is the &mut Log given to fmi2Instantiate; strings are NUL-terminated.
    unsafe {
        let log = &mut *(env as *mut Log);
        let fmt = CStr::from_ptr(message).to_string_lossy();
        let text = if fmt == "%s" && !arg.is_null() {
            CStr::from_ptr(arg).to_string_lossy().into_owned()
        } else {
            fmt.into_owned()
        };
        let cat = if category.is_null() {
            "".into()
        } else {
            CStr::from_ptr(category).to_string_lossy()
        };
        log.0.push(format!("[status {status}, {cat}] {text}"));
    }
}

fn smoke_run(so: &Path, d: &Description) -> Vec<String> {
    let mut problems = Vec::new();
    // SAFETY: loading our own freshly built FMU binary; its initializers are Rust std's only.
    let lib = match unsafe { libloading::Library::new(so) } {
        Ok(l) => l,
        Err(e) => return vec![format!("the binary does not load: {e}")],
    };
    for f in FMI2_CS_FUNCTIONS {
        // SAFETY: only the symbol's presence is checked.
        if unsafe { lib.get::<*const ()>(f.as_bytes()) }.is_err() {
            problems.push(format!("the binary does not export {f}"));
        }
    }
    if !problems.is_empty() {
        return problems;
    }
    // SAFETY: the signatures are the standard's (proved against fmi-sys in the rustfmu tests).
    unsafe {
        let version: libloading::Symbol<unsafe extern "C" fn() -> fmi2String> = lib.get(b"fmi2GetVersion").unwrap();
        let v = CStr::from_ptr(version()).to_string_lossy().into_owned();
        if v != "2.0" {
            problems.push(format!("fmi2GetVersion returns '{v}', not '2.0'"));
        }
        let instantiate: libloading::Symbol<
            unsafe extern "C" fn(
                fmi2String,
                fmi2Type,
                fmi2String,
                fmi2String,
                *const fmi2CallbackFunctions,
                fmi2Boolean,
                fmi2Boolean,
            ) -> fmi2Component,
        > = lib.get(b"fmi2Instantiate").unwrap();
        let setup: libloading::Symbol<
            unsafe extern "C" fn(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real) -> fmi2Status,
        > = lib.get(b"fmi2SetupExperiment").unwrap();
        let unary = |name: &[u8]| -> libloading::Symbol<unsafe extern "C" fn(fmi2Component) -> fmi2Status> {
            lib.get(name).unwrap()
        };
        let do_step: libloading::Symbol<
            unsafe extern "C" fn(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean) -> fmi2Status,
        > = lib.get(b"fmi2DoStep").unwrap();
        let get_real: libloading::Symbol<
            unsafe extern "C" fn(fmi2Component, *const u32, usize, *mut f64) -> fmi2Status,
        > = lib.get(b"fmi2GetReal").unwrap();
        let free: libloading::Symbol<unsafe extern "C" fn(fmi2Component)> = lib.get(b"fmi2FreeInstance").unwrap();

        let mut log = Log(Vec::new());
        let callbacks = fmi2CallbackFunctions {
            logger: Some(std::mem::transmute::<
                unsafe extern "C" fn(
                    fmi2ComponentEnvironment,
                    fmi2String,
                    fmi2Status,
                    fmi2String,
                    fmi2String,
                    *const c_char,
                ),
                unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...),
            >(collect_log)),
            allocateMemory: None,
            freeMemory: None,
            stepFinished: None,
            componentEnvironment: &mut log as *mut Log as fmi2ComponentEnvironment,
        };
        let name = CString::new("fmu-build-validate").unwrap();
        let guid = CString::new(d.guid.as_str()).unwrap_or_default();
        let c = instantiate(
            name.as_ptr(),
            fmi2CoSimulation,
            guid.as_ptr(),
            c"file:///nonexistent/resources".as_ptr(),
            &callbacks,
            fmi2False,
            fmi2False,
        );
        if c.is_null() {
            problems.push(format!("fmi2Instantiate returned NULL: {}", log.0.join("; ")));
            return problems;
        }
        let mut status = setup(c, fmi2False, 0.0, 0.0, fmi2True, 1.0);
        for f in [&b"fmi2EnterInitializationMode"[..], b"fmi2ExitInitializationMode"] {
            status = status.max(unary(f)(c));
        }
        for i in 0..10 {
            status = status.max(do_step(c, i as f64 * 0.01, 0.01, fmi2True));
        }
        let mut values = vec![0.0; d.real_vrs.len()];
        status = status.max(get_real(c, d.real_vrs.as_ptr(), d.real_vrs.len(), values.as_mut_ptr()));
        status = status.max(unary(b"fmi2Terminate")(c));
        free(c);
        if status != fmi2OK {
            problems.push(format!(
                "a 0.1 s run from the start values did not return fmi2OK (worst status {status}): {}",
                log.0.join("; ")
            ));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            problems.push(format!(
                "Real value reference {} is {} after the run",
                d.real_vrs[i], values[i]
            ));
        }
    }
    problems
}

/// fmpy's validator, run with the given Python.
pub fn fmpy_validate(python: &Path, fmu: &Path) -> Vec<String> {
    let script = "import sys\nfrom fmpy.validation import validate_fmu\np = validate_fmu(sys.argv[1])\nprint('\\n'.join(p))\nsys.exit(1 if p else 0)";
    match std::process::Command::new(python)
        .arg("-c")
        .arg(script)
        .arg(fmu)
        .output()
    {
        Ok(out) if out.status.success() => vec![],
        Ok(out) => vec![format!(
            "fmpy's validate_fmu: {}{}",
            String::from_utf8_lossy(&out.stdout).trim(),
            String::from_utf8_lossy(&out.stderr).trim()
        )],
        Err(e) => vec![format!("cannot run {}: {e}", python.display())],
    }
}
