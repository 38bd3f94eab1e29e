//! Checks on a packaged FMU, each reported as a readable problem (an empty list: valid).
//! Archive layout, the description against the declarations it came from, the binary's
//! exported functions, and a short run through the C API as an importer makes it.

use quick_xml::Reader;
use quick_xml::events::Event;
use rustfmu::__private::abi::*;
use std::ffi::{CStr, CString, c_char};
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

/// Problems with an FMU file (an empty list: valid). The smoke run happens in a child process
/// (this program run as `__smoke-run`), so an FMU that crashes is reported, not shared.
pub fn validate(fmu: &Path) -> Vec<String> {
    match validate_inner(fmu) {
        Ok(problems) => problems,
        Err(e) => vec![e],
    }
}

fn validate_inner(fmu: &Path) -> Result<Vec<String>, String> {
    use fmi2_conformance::archive;
    // The file is untrusted: opened, read and unpacked only through the conformance suite's
    // archive module (no `..`, absolute names, backslashes, links; bounded sizes; the XML's
    // errors with line and column), into a private folder removed afterwards.
    let mut problems = Vec::new();
    let mut zip = archive::open(fmu)?;
    for name in zip.entry_names() {
        if let Err(e) = archive::check_entry_name(name.as_bytes()) {
            problems.push(format!("archive entry '{name}': {e}"));
        }
        if name.starts_with("./") {
            problems.push(format!("archive entry '{name}' must not start with './'"));
        }
    }
    let xml = archive::read_model_description(&mut zip)?;
    let d = read_description(&xml)?;
    let (folder, ext) = crate::bundle::platform()?;
    let bin_name = format!("binaries/{folder}/{}.{ext}", d.model_identifier);
    if !zip.has_entry(&bin_name) {
        return Err(format!(
            "no {bin_name} (the binary is named after modelIdentifier, without a 'lib' prefix)"
        ));
    }
    let dir = archive::extract_private(&mut zip, &std::env::temp_dir(), &archive::Limits::default())?;
    let so = dir.path().join(&bin_name);
    let binary = std::fs::read(&so).map_err(|e| format!("{bin_name}: {e}"))?;
    // A binary made by rustfmu describes itself: the packaged description must be what it says.
    if let Ok(me) = crate::bundle::read_library(&binary) {
        match crate::xml::fmi2(&me.description, me.interfaces, &me.guid) {
            Ok(generated) if generated == xml => {}
            Ok(_) => problems.push(format!(
                "modelDescription.xml differs from the description {bin_name} carries (stale package?)"
            )),
            Err(e) => problems.push(format!("the description {bin_name} carries is invalid: {e}")),
        }
    }
    problems.extend(smoke_run_in_child(&so, &d));
    drop(dir);
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

fn smoke_run_in_child(so: &Path, d: &Description) -> Vec<String> {
    let vrs: Vec<String> = d.real_vrs.iter().map(|v| v.to_string()).collect();
    let exe = match std::env::current_exe() {
        Ok(e) if e.file_stem().is_some_and(|s| s == "cargo-fmu" || s == "fmu-build") => e,
        // Called from elsewhere (tests): run in this process.
        _ => return smoke_run(so, &d.guid, &d.real_vrs),
    };
    match std::process::Command::new(&exe)
        .arg("__smoke-run")
        .arg(so)
        .arg(&d.guid)
        .arg(vrs.join(","))
        .output()
    {
        Ok(out) if out.status.success() => vec![],
        Ok(out) => {
            let said = String::from_utf8_lossy(&out.stdout)
                .lines()
                .map(str::to_string)
                .collect::<Vec<_>>();
            if said.is_empty() {
                let err = String::from_utf8_lossy(&out.stderr);
                let tail: Vec<&str> = err
                    .lines()
                    .rev()
                    .take(5)
                    .collect::<Vec<_>>()
                    .into_iter()
                    .rev()
                    .collect();
                vec![format!("the smoke run crashed ({}): {}", out.status, tail.join(" | "))]
            } else {
                said
            }
        }
        Err(e) => vec![format!("cannot start the smoke run ({}): {e}", exe.display())],
    }
}

/// Loads the binary, checks its exports, and runs 0.1 s from the start values.
pub fn smoke_run(so: &Path, guid: &str, real_vrs: &[u32]) -> Vec<String> {
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
        let guid = CString::new(guid).unwrap_or_default();
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
        let mut values = vec![0.0; real_vrs.len()];
        status = status.max(get_real(c, real_vrs.as_ptr(), real_vrs.len(), values.as_mut_ptr()));
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
                real_vrs[i], values[i]
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

/// `cargo fmu info`: what an FMU file offers, from its archive and description.
pub fn info(fmu: &Path) -> Result<String, String> {
    let at = |e: &dyn std::fmt::Display| format!("{}: {e}", fmu.display());
    let mut zip = fmi2_conformance::archive::open(fmu)?;
    let mut platforms = std::collections::BTreeSet::new();
    for name in zip.entry_names() {
        let parts: Vec<&str> = name.split('/').collect();
        if parts.len() == 3 && parts[0] == "binaries" && !parts[2].is_empty() {
            platforms.insert(format!("{} ({})", parts[1], parts[2]));
        }
    }
    let xml = fmi2_conformance::archive::read_model_description(&mut zip)?;
    let mut reader = Reader::from_str(&xml);
    let mut out = String::new();
    let mut counts: std::collections::BTreeMap<String, usize> = Default::default();
    let mut interfaces = Vec::new();
    let mut variables = Vec::new();
    let mut current: Option<(String, String, String)> = None;
    loop {
        match reader.read_event() {
            Err(e) => {
                return Err(at(&format!(
                    "modelDescription.xml is not well-formed at byte {}: {e}",
                    reader.error_position()
                )));
            }
            Ok(Event::Eof) => break,
            Ok(Event::Start(e) | Event::Empty(e)) => {
                let attr = |name: &[u8]| -> String {
                    e.attributes()
                        .flatten()
                        .find(|a| a.key.as_ref() == name)
                        .and_then(|a| a.unescape_value().ok())
                        .map(|v| v.into_owned())
                        .unwrap_or_default()
                };
                match e.name().as_ref() {
                    b"fmiModelDescription" => {
                        out.push_str(&format!(
                            "{}: FMI {}, model '{}', version '{}'\n  GUID/token {}\n  generated by {}\n  {}\n",
                            fmu.display(),
                            attr(b"fmiVersion"),
                            attr(b"modelName"),
                            attr(b"version"),
                            attr(b"guid"),
                            attr(b"generationTool"),
                            attr(b"description")
                        ));
                    }
                    b"CoSimulation" | b"ModelExchange" => interfaces.push(format!(
                        "{} ({})",
                        String::from_utf8_lossy(e.name().as_ref()),
                        attr(b"modelIdentifier")
                    )),
                    b"DefaultExperiment" => {
                        let parts: Vec<String> = [
                            ("start", b"startTime".as_slice()),
                            ("stop", b"stopTime"),
                            ("step", b"stepSize"),
                            ("tolerance", b"tolerance"),
                        ]
                        .iter()
                        .filter_map(|(label, key)| {
                            let v = attr(key);
                            (!v.is_empty()).then(|| format!("{label} {v}"))
                        })
                        .collect();
                        out.push_str(&format!("  default experiment: {}\n", parts.join(", ")));
                    }
                    b"ScalarVariable" => {
                        let causality = match attr(b"causality") {
                            c if c.is_empty() => "local".to_string(),
                            c => c,
                        };
                        *counts.entry(causality.clone()).or_default() += 1;
                        current = Some((attr(b"name"), causality, attr(b"valueReference")));
                    }
                    b"Real" | b"Integer" | b"Boolean" | b"String" | b"Enumeration" => {
                        if let Some((name, causality, vr)) = current.take() {
                            let unit = attr(b"unit");
                            variables.push(format!(
                                "    {vr:>5} {name} ({causality}, {}{})",
                                String::from_utf8_lossy(e.name().as_ref()),
                                if unit.is_empty() {
                                    String::new()
                                } else {
                                    format!(", {unit}")
                                }
                            ));
                        }
                    }
                    _ => {}
                }
            }
            Ok(_) => {}
        }
    }
    out.push_str(&format!("  interfaces: {}\n", interfaces.join(", ")));
    out.push_str(&format!(
        "  platforms: {}\n",
        if platforms.is_empty() {
            "none".to_string()
        } else {
            platforms.into_iter().collect::<Vec<_>>().join(", ")
        }
    ));
    let counts: Vec<String> = counts.iter().map(|(k, v)| format!("{v} {k}")).collect();
    out.push_str(&format!("  variables: {} ({})\n", variables.len(), counts.join(", ")));
    for v in variables {
        out.push_str(&v);
        out.push('\n');
    }
    Ok(out)
}
