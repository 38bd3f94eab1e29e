//! Checks on a packaged FMU, each reported as a readable problem (an empty list: valid).
//! Archive layout, the description against the declarations it came from, the binary's
//! exported functions, and a short run through the C API as an importer makes it.

use fmi_description::{Causality, ModelDescription, fmi2, fmi3};
use rustfmu::__private::abi::*;
use rustfmu::description::FmiVersion;
use std::collections::BTreeSet;
use std::ffi::{CStr, CString, c_char, c_void};
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

/// Every function of the FMI 2.0 standard (model exchange and co-simulation), as
/// `fmi2Functions.h` declares them: an FMI 3.0 binary exports all of them (a binary of both
/// versions) or none.
pub const FMI2_FUNCTIONS: &[&str] = &[
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
    "fmi2EnterEventMode",
    "fmi2NewDiscreteStates",
    "fmi2EnterContinuousTimeMode",
    "fmi2CompletedIntegratorStep",
    "fmi2SetTime",
    "fmi2SetContinuousStates",
    "fmi2GetDerivatives",
    "fmi2GetEventIndicators",
    "fmi2GetContinuousStates",
    "fmi2GetNominalsOfContinuousStates",
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

/// Every function of the FMI 3.0 standard, as `fmi3Functions.h` declares them (75): an FMI 3.0
/// binary exports all of them (those it does not support refuse with fmi3Error), an FMI 2.0
/// binary all of them (a binary of both versions) or none.
pub const FMI3_FUNCTIONS: &[&str] = &[
    "fmi3GetVersion",
    "fmi3SetDebugLogging",
    "fmi3InstantiateModelExchange",
    "fmi3InstantiateCoSimulation",
    "fmi3InstantiateScheduledExecution",
    "fmi3FreeInstance",
    "fmi3EnterInitializationMode",
    "fmi3ExitInitializationMode",
    "fmi3EnterEventMode",
    "fmi3Terminate",
    "fmi3Reset",
    "fmi3GetFloat32",
    "fmi3GetFloat64",
    "fmi3GetInt8",
    "fmi3GetUInt8",
    "fmi3GetInt16",
    "fmi3GetUInt16",
    "fmi3GetInt32",
    "fmi3GetUInt32",
    "fmi3GetInt64",
    "fmi3GetUInt64",
    "fmi3GetBoolean",
    "fmi3GetString",
    "fmi3GetBinary",
    "fmi3GetClock",
    "fmi3SetFloat32",
    "fmi3SetFloat64",
    "fmi3SetInt8",
    "fmi3SetUInt8",
    "fmi3SetInt16",
    "fmi3SetUInt16",
    "fmi3SetInt32",
    "fmi3SetUInt32",
    "fmi3SetInt64",
    "fmi3SetUInt64",
    "fmi3SetBoolean",
    "fmi3SetString",
    "fmi3SetBinary",
    "fmi3SetClock",
    "fmi3GetNumberOfVariableDependencies",
    "fmi3GetVariableDependencies",
    "fmi3GetFMUState",
    "fmi3SetFMUState",
    "fmi3FreeFMUState",
    "fmi3SerializedFMUStateSize",
    "fmi3SerializeFMUState",
    "fmi3DeserializeFMUState",
    "fmi3GetDirectionalDerivative",
    "fmi3GetAdjointDerivative",
    "fmi3EnterConfigurationMode",
    "fmi3ExitConfigurationMode",
    "fmi3GetIntervalDecimal",
    "fmi3GetIntervalFraction",
    "fmi3GetShiftDecimal",
    "fmi3GetShiftFraction",
    "fmi3SetIntervalDecimal",
    "fmi3SetIntervalFraction",
    "fmi3SetShiftDecimal",
    "fmi3SetShiftFraction",
    "fmi3EvaluateDiscreteStates",
    "fmi3UpdateDiscreteStates",
    "fmi3EnterContinuousTimeMode",
    "fmi3CompletedIntegratorStep",
    "fmi3SetTime",
    "fmi3SetContinuousStates",
    "fmi3GetContinuousStateDerivatives",
    "fmi3GetEventIndicators",
    "fmi3GetContinuousStates",
    "fmi3GetNominalsOfContinuousStates",
    "fmi3GetNumberOfEventIndicators",
    "fmi3GetNumberOfContinuousStates",
    "fmi3EnterStepMode",
    "fmi3GetOutputDerivatives",
    "fmi3DoStep",
    "fmi3ActivateModelPartition",
];

/// What validation needs of the packaged description, read by the workspace's one reader
/// (`fmi_description`). The checks of the archive itself (entry names, the XML's encoding and
/// well-formedness, with line and column) are the conformance suite's archive module's, and
/// the comparison with the description the binary carries compares the raw XML text.
struct Description {
    version: FmiVersion,
    model_identifier: String,
    /// The GUID (FMI 2.0) or instantiationToken (FMI 3.0).
    guid: String,
    real_vrs: Vec<u32>,
    /// FMI 3.0 with clocks: co-simulation needs eventModeUsed (the smoke run then handles Event Mode).
    clocks: bool,
    /// What is wrong with the description itself ([`array_problems`]).
    problems: Vec<String>,
}

fn read_description(xml: &str) -> Result<Description, String> {
    let (version, cs, guid, real_vrs, clocks, problems) = match fmi_description::parse(xml)? {
        ModelDescription::Fmi2(d) => (
            FmiVersion::V2,
            d.cs.as_ref().map(|cs| cs.model_identifier.clone()),
            d.guid.clone(),
            d.vrs_of_type(fmi2::Type::Real),
            false,
            Vec::new(),
        ),
        // FMI 3.0: every scalar Float64 (one value each; the arrays' elements are the
        // conformance suite's to read).
        ModelDescription::Fmi3(d) => (
            FmiVersion::V3,
            d.cs.as_ref().map(|cs| cs.model_identifier.clone()),
            d.token.clone(),
            // (Clocked ones are read while their clock ticks only: not here.)
            d.variables
                .iter()
                .filter(|v| v.ty == fmi3::Type::Float64 && !v.array && v.clocks.is_empty())
                .map(|v| v.vr)
                .collect(),
            d.variables.iter().any(|v| v.ty == fmi3::Type::Clock),
            array_problems(&d),
        ),
    };
    match cs {
        Some(model_identifier) if !model_identifier.is_empty() => Ok(Description {
            version,
            model_identifier,
            guid,
            real_vrs,
            clocks,
            problems,
        }),
        _ => Err("no <CoSimulation modelIdentifier=...>".into()),
    }
}

/// The length of an FMI 3.0 array's dimension at the start: a fixed one, or the start value of
/// the variable its `valueReference` names; `Err` says what is wrong with that variable.
fn dimension_length(d: &fmi3::ModelDescription, dim: &fmi3::Dimension) -> Result<u64, String> {
    let vr = match *dim {
        fmi3::Dimension::Fixed(n) => return Ok(n),
        fmi3::Dimension::Parameter(vr) => vr,
    };
    let p = d
        .by_vr(vr)
        .ok_or_else(|| format!("<Dimension valueReference=\"{vr}\"> names no variable"))?;
    if p.ty != fmi3::Type::UInt64
        || !(p.causality == Causality::StructuralParameter || p.variability == fmi_description::Variability::Constant)
    {
        return Err(format!(
            "<Dimension valueReference=\"{vr}\"> names '{}', a {} {}; a length is set by a UInt64 structuralParameter \
             or constant (FMI 3.0, 2.4.7.6)",
            p.name,
            p.causality.name(),
            p.ty.name()
        ));
    }
    p.start
        .as_deref()
        .and_then(|s| s.trim().parse::<u64>().ok())
        .ok_or_else(|| format!("'{}', which sets a length (vr {vr}), has no UInt64 start value", p.name))
}

/// What is wrong with the arrays of an FMI 3.0 description: a `<Dimension valueReference>` that
/// names no UInt64 structural parameter (or constant), or a `start` list whose length is
/// neither 1 (every element's) nor the number of elements at the start lengths (those of the
/// structural parameters at their start values).
pub fn array_problems(d: &fmi3::ModelDescription) -> Vec<String> {
    let mut problems = Vec::new();
    for v in d.variables.iter().filter(|v| v.array) {
        let lengths: Result<Vec<u64>, String> = v.dimensions.iter().map(|dim| dimension_length(d, dim)).collect();
        let lengths = match lengths {
            Ok(l) => l,
            Err(e) => {
                problems.push(format!("variable '{}' (vr {}): {e}", v.name, v.vr));
                continue;
            }
        };
        // A String's or Binary's start values are <Start> children (the reader keeps the first).
        if matches!(v.ty, fmi3::Type::String | fmi3::Type::Binary) {
            continue;
        }
        let count = lengths.iter().try_fold(1u64, |n, &k| n.checked_mul(k));
        if let (Some(start), Some(count)) = (&v.start, count) {
            let given = start.split_whitespace().count() as u64;
            if given != 1 && given != count {
                let shape: Vec<String> = lengths.iter().map(u64::to_string).collect();
                problems.push(format!(
                    "variable '{}' (vr {}): {given} start values for {count} elements (the lengths at the start: {})",
                    v.name,
                    v.vr,
                    shape.join(" x ")
                ));
            }
        }
    }
    problems
}

/// What is wrong with `terminalsAndIcons.xml` against the model description (FMI 3.0, 2.4.9):
/// not well-formed, another root or `fmiVersion`, a terminal without `name` or
/// `matchingRule`, a member without `variableName` or `variableKind`, or naming no variable.
pub fn terminal_problems(terminals: &str, model_description: &str) -> Vec<String> {
    use quick_xml::events::Event;
    let names: BTreeSet<String> = match fmi_description::parse(model_description) {
        Ok(ModelDescription::Fmi3(d)) => d.variables.iter().map(|v| v.name.clone()).collect(),
        _ => return vec!["terminalsAndIcons.xml beside a description that is not FMI 3.0".into()],
    };
    let mut problems = Vec::new();
    let mut reader = quick_xml::Reader::from_str(terminals);
    let mut root_seen = false;
    loop {
        let e = match reader.read_event() {
            Ok(Event::Eof) => break,
            Ok(Event::Start(e) | Event::Empty(e)) => e,
            Ok(_) => continue,
            Err(err) => {
                problems.push(format!(
                    "terminalsAndIcons.xml is not well-formed at byte {}: {err}",
                    reader.error_position()
                ));
                break;
            }
        };
        let attr = |name: &str| {
            e.try_get_attribute(name)
                .ok()
                .flatten()
                .and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
        };
        match e.name().as_ref() {
            b"fmiTerminalsAndIcons" => {
                root_seen = true;
                if !attr("fmiVersion").is_some_and(|v| v.starts_with("3.")) {
                    problems.push("terminalsAndIcons.xml: fmiVersion is not 3.x".into());
                }
            }
            b"Terminal" if attr("name").is_none() || attr("matchingRule").is_none() => {
                problems.push("terminalsAndIcons.xml: a <Terminal> without name or matchingRule".into());
            }
            b"TerminalMemberVariable" => match (attr("variableName"), attr("variableKind")) {
                (Some(v), Some(_)) if names.contains(&v) => {}
                (Some(v), Some(_)) => problems.push(format!(
                    "terminalsAndIcons.xml: member variable '{v}' is no variable of modelDescription.xml"
                )),
                _ => problems.push(
                    "terminalsAndIcons.xml: a <TerminalMemberVariable> without variableName or variableKind".into(),
                ),
            },
            _ => {}
        }
    }
    if !root_seen && problems.is_empty() {
        problems.push("terminalsAndIcons.xml: the root is not <fmiTerminalsAndIcons>".into());
    }
    problems
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
    use fmi_conformance::archive;
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
    problems.extend(d.problems.iter().cloned());
    // Every binary of a platform this FMI version names: `binaries/<folder>/<id>.<ext>`.
    let names = zip.entry_names();
    let binaries: Vec<(String, String)> = crate::target::known_folders(d.version)
        .into_iter()
        .map(|(folder, ext)| {
            (
                folder.clone(),
                format!("binaries/{folder}/{}.{ext}", d.model_identifier),
            )
        })
        .filter(|(_, name)| zip.has_entry(name))
        .collect();
    let here = crate::target::this_machine().and_then(|p| p.folder(d.version).ok());
    if binaries.is_empty() {
        let found: Vec<&String> = names
            .iter()
            .filter(|n| n.starts_with("binaries/") && !n.ends_with('/'))
            .collect();
        return Err(format!(
            "no binary binaries/<platform>/{}.<so|dll|dylib> in a platform folder of FMI {} (named after modelIdentifier, \
             without a 'lib' prefix; found {found:?})",
            d.model_identifier,
            d.version.text()
        ));
    }
    // A folder of the other version's names (linux64 in an FMI 3.0 FMU, x86_64-linux in 2.0).
    let other_version = match d.version {
        FmiVersion::V2 => FmiVersion::V3,
        FmiVersion::V3 => FmiVersion::V2,
    };
    let own: BTreeSet<String> = crate::target::known_folders(d.version)
        .into_iter()
        .map(|(f, _)| f)
        .collect();
    for (other, _) in crate::target::known_folders(other_version) {
        if !own.contains(&other) && names.iter().any(|n| n.starts_with(&format!("binaries/{other}/"))) {
            problems.push(format!(
                "binaries/{other}/ is a folder name of FMI {}; an FMI {} FMU names its platforms {}",
                other_version.text(),
                d.version.text(),
                own.iter().cloned().collect::<Vec<_>>().join(", ")
            ));
        }
    }
    let dir = archive::extract_private(&mut zip, &std::env::temp_dir(), &archive::Limits::default())?;
    let terminals = dir.path().join("terminalsAndIcons/terminalsAndIcons.xml");
    if terminals.exists() {
        match (d.version, std::fs::read_to_string(&terminals)) {
            (FmiVersion::V2, _) => {
                problems.push("terminalsAndIcons/terminalsAndIcons.xml is FMI 3.0's; an FMI 2.0 FMU has none".into())
            }
            (_, Err(e)) => problems.push(format!("terminalsAndIcons/terminalsAndIcons.xml: {e}")),
            (_, Ok(text)) => problems.extend(terminal_problems(&text, &xml)),
        }
    }
    for (folder, bin_name) in &binaries {
        let so = dir.path().join(bin_name);
        let binary = std::fs::read(&so).map_err(|e| format!("{bin_name}: {e}"))?;
        // A binary made by rustfmu describes itself: the packaged description must be what it says.
        if let Ok(all) = crate::bundle::library_versions(&binary) {
            let of_version = all.iter().find(|me| me.interfaces.version == d.version);
            match of_version {
                None => problems.push(format!(
                    "modelDescription.xml says FMI {}, {bin_name} implements FMI {} only",
                    d.version.text(),
                    all.iter()
                        .map(|me| me.interfaces.version.text())
                        .collect::<Vec<_>>()
                        .join(" and ")
                )),
                Some(me) if me.guid != d.guid => problems.push(format!(
                    "the {} in modelDescription.xml is {}, {bin_name} expects {}",
                    match d.version {
                        FmiVersion::V2 => "guid",
                        FmiVersion::V3 => "instantiationToken",
                    },
                    d.guid,
                    me.guid
                )),
                Some(me) => match crate::bundle::model_description(me) {
                    Ok(generated) if generated == xml => {}
                    Ok(_) => problems.push(format!(
                        "modelDescription.xml differs from the description {bin_name} carries (stale package?)"
                    )),
                    Err(e) => problems.push(format!("the description {bin_name} carries is invalid: {e}")),
                },
            }
        }
        problems.extend(export_problems(&binary, d.version, bin_name));
        problems.extend(pe_problems(&binary, d.version, bin_name));
        problems.extend(macho_problems(&binary, d.version, folder, bin_name));
        problems.extend(architecture_problems(&binary, folder, bin_name));
        // The smoke run loads the binary of the machine this runs on; the others are loaded by
        // their own hosts (tests/python/test_windows.py runs the Windows one under wine).
        if here.as_deref() == Some(folder.as_str()) {
            problems.extend(smoke_run_in_child(&so, &d, &dir.path().join("resources")));
        }
    }
    drop(dir);
    Ok(problems)
}

/// The DLLs of Windows itself that a Windows binary may import: every other DLL (MinGW's
/// `libgcc_s_seh-1.dll`, `libwinpthread-1.dll`, `libstdc++-6.dll`, ...) would have to be shipped
/// with the FMU, which it is not.
const WINDOWS_SYSTEM_DLLS: &[&str] = &[
    "kernel32.dll",
    "ntdll.dll",
    "msvcrt.dll",
    "ucrtbase.dll",
    "userenv.dll",
    "ws2_32.dll",
    "bcrypt.dll",
    "bcryptprimitives.dll",
    "advapi32.dll",
    "user32.dll",
    "shell32.dll",
    "ole32.dll",
    "oleaut32.dll",
    "secur32.dll",
    "crypt32.dll",
    "dbghelp.dll",
    "synchronization.dll",
];

/// What the export and import tables of a PE (Windows) binary say.
#[derive(Debug, Clone)]
pub struct PeTables {
    /// The exported names.
    pub exports: Vec<String>,
    /// The DLLs it imports from, each once, sorted.
    pub imports: Vec<String>,
}

/// The export and import tables of a PE (Windows) binary; `None` for another format.
pub fn pe_tables(binary: &[u8]) -> Option<Result<PeTables, String>> {
    use object::Object;
    let kind = object::FileKind::parse(binary).ok()?;
    if !matches!(kind, object::FileKind::Pe32 | object::FileKind::Pe64) {
        return None;
    }
    let read = || -> Result<PeTables, String> {
        let file = object::File::parse(binary).map_err(|e| format!("not a readable PE file: {e}"))?;
        let exports = file
            .exports()
            .map_err(|e| format!("its export table: {e}"))?
            .iter()
            .map(|e| String::from_utf8_lossy(e.name()).into_owned())
            .collect();
        let mut imports: Vec<String> = file
            .imports()
            .map_err(|e| format!("its import table: {e}"))?
            .iter()
            .map(|i| String::from_utf8_lossy(i.library()).into_owned())
            .collect();
        imports.sort_by_key(|d| d.to_ascii_lowercase());
        imports.dedup_by(|a, b| a.eq_ignore_ascii_case(b));
        Ok(PeTables { exports, imports })
    };
    Some(read())
}

/// The DLLs of a list that are not part of Windows (an FMU would have to ship them).
pub fn not_windows_dlls(dlls: &[String]) -> Vec<&str> {
    dlls.iter()
        .map(String::as_str)
        .filter(|d| {
            let l = d.to_ascii_lowercase();
            !(WINDOWS_SYSTEM_DLLS.contains(&l.as_str()) || l.starts_with("api-ms-win-") || l.starts_with("ext-ms-win-"))
        })
        .collect()
}

/// What a Windows binary exports and imports: every function of its FMI version's standard,
/// the other version's only whole ([`check_exports`]), nothing but FMI functions, and DLLs of
/// Windows only (the FMU ships no other DLL).
pub fn pe_problems(binary: &[u8], version: FmiVersion, bin_name: &str) -> Vec<String> {
    let PeTables { exports, imports } = match pe_tables(binary) {
        None => return vec![],
        Some(Err(e)) => return vec![format!("{bin_name}: {e}")],
        Some(Ok(t)) => t,
    };
    let mut problems = check_exports(&exports, version, bin_name);
    // check_exports judged the fmi2*/fmi3* names; nothing else may be exported.
    let other: Vec<&str> = exports
        .iter()
        .map(String::as_str)
        .filter(|n| !n.starts_with("fmi2") && !n.starts_with("fmi3"))
        .collect();
    if !other.is_empty() {
        problems.push(format!(
            "{bin_name} exports {}: an FMU's binary exports FMI functions only",
            other.join(", ")
        ));
    }
    let foreign = not_windows_dlls(&imports);
    if !foreign.is_empty() {
        problems.push(format!(
            "{bin_name} needs {}, which Windows does not have and the FMU does not ship (link the MinGW runtime statically)",
            foreign.join(", ")
        ));
    }
    problems
}

/// The libraries of macOS itself a Mach-O binary may load: libSystem (the C library, libm,
/// pthreads, dyld's API: all Rust's standard library needs) and the libraries below
/// `/usr/lib/system/` it is made of. Any other would have to be on the user's Mac.
fn macos_system_library(path: &str) -> bool {
    path == "/usr/lib/libSystem.B.dylib" || path.starts_with("/usr/lib/system/")
}

/// The names a macOS dylib linked by zig exports besides the FMI functions, and why it may:
/// zig's Mach-O linker (0.17) ignores the `-exported_symbols_list` rustc passes (ziglang/zig#24662;
/// measured here: a two-function C library exports both with a list naming one), so the global
/// symbols that survive link-time optimisation stay exported: two the linker makes
/// (`__dso_handle`, `_mh_dylib_header`) and two of Rust's runtime
/// (`rust_eh_personality`, the unwinder's; `std::panicking::EMPTY_PANIC`, a constant). macOS binds
/// symbols per library (two-level namespace): they do not collide with the importer's. Any other
/// name is refused.
fn macos_runtime_export(name: &str) -> bool {
    matches!(name, "__dso_handle" | "_mh_dylib_header" | "rust_eh_personality")
        || (name.contains("std9panicking") && name.ends_with("EMPTY_PANIC"))
}

/// One architecture of a Mach-O binary: what [`macho_slices`] reads off it.
#[derive(Debug, Clone)]
pub struct MachOSlice {
    pub architecture: object::Architecture,
    /// Exported names, without the leading underscore of Mach-O symbols.
    pub exports: Vec<String>,
    /// The libraries it loads (LC_LOAD_DYLIB and its weak, re-exported, lazy and upward kinds).
    pub libraries: Vec<String>,
    /// The oldest macOS it loads on (LC_BUILD_VERSION or LC_VERSION_MIN_MACOSX), (major, minor).
    pub min_macos: Option<(u32, u32)>,
    /// Whether it carries a code signature (LC_CODE_SIGNATURE): macOS on Apple silicon runs no
    /// unsigned code; zig signs arm64 binaries ad hoc, as Apple's linker does.
    pub signed: bool,
}

/// The architectures of a Mach-O binary, thin or universal ("fat"); `None` for another format.
pub fn macho_slices(binary: &[u8]) -> Option<Result<Vec<MachOSlice>, String>> {
    use object::read::macho::{FatArch32, FatArch64};
    let kind = object::FileKind::parse(binary).ok()?;
    let read = || -> Result<Vec<MachOSlice>, String> {
        match kind {
            object::FileKind::MachO64 => Ok(vec![macho_slice(binary)?]),
            object::FileKind::MachOFat32 => universal_slices::<FatArch32>(binary),
            object::FileKind::MachOFat64 => universal_slices::<FatArch64>(binary),
            _ => Err(format!("a Mach-O file of kind {kind:?}, not a 64-bit shared library")),
        }
    };
    match kind {
        object::FileKind::MachO32
        | object::FileKind::MachO64
        | object::FileKind::MachOFat32
        | object::FileKind::MachOFat64 => Some(read()),
        _ => None,
    }
}

/// [`macho_slice`] of each architecture of a universal binary (32- or 64-bit fat header).
fn universal_slices<Fat: object::read::macho::FatArch>(binary: &[u8]) -> Result<Vec<MachOSlice>, String> {
    object::read::macho::MachOFatFile::<Fat>::parse(binary)
        .map_err(|e| format!("not a readable universal binary: {e}"))?
        .arches()
        .iter()
        .map(|a| {
            macho_slice(
                a.data(binary)
                    .map_err(|e| format!("a slice of the universal binary: {e}"))?,
            )
        })
        .collect()
}

fn macho_slice(data: &[u8]) -> Result<MachOSlice, String> {
    use object::macho;
    use object::read::macho::{LoadCommandVariant, MachOFile64};
    use object::{Object, ObjectKind};
    let file =
        MachOFile64::<object::Endianness>::parse(data).map_err(|e| format!("not a readable Mach-O file: {e}"))?;
    if file.kind() != ObjectKind::Dynamic {
        return Err(format!("a Mach-O file of kind {:?}, not a shared library", file.kind()));
    }
    let exports = file
        .exports()
        .map_err(|e| format!("its export trie: {e}"))?
        .iter()
        .map(|e| {
            let n = String::from_utf8_lossy(e.name());
            n.strip_prefix('_').unwrap_or(&n).to_string()
        })
        .collect();
    let endian = file.endian();
    let mut libraries = Vec::new();
    let mut min_macos = None;
    let mut signed = false;
    let mut commands = file
        .macho_load_commands()
        .map_err(|e| format!("its load commands: {e}"))?;
    let version = |v: u32| (v >> 16, (v >> 8) & 0xff);
    while let Some(c) = commands.next().map_err(|e| format!("its load commands: {e}"))? {
        match c.variant().map_err(|e| format!("its load commands: {e}"))? {
            LoadCommandVariant::Dylib(d)
                if matches!(
                    c.cmd(),
                    macho::LC_LOAD_DYLIB
                        | macho::LC_LOAD_WEAK_DYLIB
                        | macho::LC_REEXPORT_DYLIB
                        | macho::LC_LAZY_LOAD_DYLIB
                        | macho::LC_LOAD_UPWARD_DYLIB
                ) =>
            {
                let name = c
                    .string(endian, d.dylib.name)
                    .map_err(|e| format!("a library name of its load commands: {e}"))?;
                libraries.push(String::from_utf8_lossy(name).into_owned());
            }
            LoadCommandVariant::BuildVersion(b) if b.platform.get(endian) == macho::PLATFORM_MACOS => {
                min_macos = Some(version(b.minos.get(endian)));
            }
            LoadCommandVariant::VersionMin(v) if c.cmd() == macho::LC_VERSION_MIN_MACOSX => {
                min_macos = Some(version(v.version.get(endian)));
            }
            LoadCommandVariant::LinkeditData(_) if c.cmd() == macho::LC_CODE_SIGNATURE => signed = true,
            _ => {}
        }
    }
    Ok(MachOSlice {
        architecture: file.architecture(),
        exports,
        libraries,
        min_macos,
        signed,
    })
}

/// What a macOS binary is, exports and loads: the architecture(s) its folder names
/// (`x86_64-darwin`: x86_64; `aarch64-darwin`: arm64; FMI 2.0's `darwin64`: x86_64, arm64 or a
/// universal binary of both), every function of its FMI version and no other name
/// ([`check_exports`]), macOS's own libraries only. Built here, never run here: these checks are
/// what this machine can say of a macOS binary.
pub fn macho_problems(binary: &[u8], version: FmiVersion, folder: &str, bin_name: &str) -> Vec<String> {
    use object::Architecture::{Aarch64, X86_64};
    let slices = match macho_slices(binary) {
        None => {
            return if folder.contains("darwin") {
                vec![format!(
                    "{bin_name} is no Mach-O binary, which binaries/{folder}/ holds"
                )]
            } else {
                vec![]
            };
        }
        Some(Err(e)) => return vec![format!("{bin_name}: {e}")],
        Some(Ok(s)) => s,
    };
    let mut problems = Vec::new();
    let allowed: &[object::Architecture] = match folder {
        "x86_64-darwin" => &[X86_64],
        "aarch64-darwin" => &[Aarch64],
        "darwin64" => &[X86_64, Aarch64],
        other => {
            return vec![format!("{bin_name} is a macOS (Mach-O) binary in binaries/{other}/")];
        }
    };
    for s in &slices {
        let arch = format!("{:?}", s.architecture).to_lowercase();
        if !allowed.contains(&s.architecture) {
            problems.push(format!(
                "{bin_name} holds a {arch} binary, which binaries/{folder}/ is not for"
            ));
        }
        let name = if slices.len() > 1 {
            format!("{bin_name} ({arch})")
        } else {
            bin_name.to_string()
        };
        problems.extend(check_exports(&s.exports, version, &name));
        let other: Vec<&str> = s
            .exports
            .iter()
            .map(String::as_str)
            .filter(|n| !n.starts_with("fmi2") && !n.starts_with("fmi3") && !macos_runtime_export(n))
            .collect();
        if !other.is_empty() {
            let shown: Vec<&str> = other.iter().copied().take(8).collect();
            problems.push(format!(
                "{name} exports {} name{} besides the FMI functions ({}{}): an FMU's binary exports FMI functions only \
                 (built without link-time optimisation? `cargo fmu build` builds with `--crate-type cdylib`)",
                other.len(),
                if other.len() == 1 { "" } else { "s" },
                shown.join(", "),
                if other.len() > shown.len() { ", ..." } else { "" }
            ));
        }
        let foreign: Vec<&str> = s
            .libraries
            .iter()
            .map(String::as_str)
            .filter(|l| !macos_system_library(l))
            .collect();
        if !foreign.is_empty() {
            problems.push(format!(
                "{name} loads {}, which macOS does not have and the FMU does not ship",
                foreign.join(", ")
            ));
        }
    }
    let mut archs: Vec<_> = slices.iter().map(|s| s.architecture).collect();
    archs.sort_by_key(|a| format!("{a:?}"));
    archs.dedup();
    if archs.len() != slices.len() {
        problems.push(format!("{bin_name} holds one architecture twice"));
    }
    problems
}

/// The architecture of an ELF or PE binary against its folder (`x86_64-linux`, `linux64`,
/// `aarch64-linux`, `win64`, ...): a binary of another architecture does not load there.
pub fn architecture_problems(binary: &[u8], folder: &str, bin_name: &str) -> Vec<String> {
    use object::Object;
    let Ok(kind) = object::FileKind::parse(binary) else {
        return vec![];
    };
    if !matches!(
        kind,
        object::FileKind::Elf64 | object::FileKind::Elf32 | object::FileKind::Pe32 | object::FileKind::Pe64
    ) {
        return vec![];
    }
    let Ok(file) = object::File::parse(binary) else {
        return vec![];
    };
    let want = match folder {
        "linux64" | "win64" | "x86_64-linux" | "x86_64-windows" => object::Architecture::X86_64,
        "linux32" | "win32" | "x86-linux" | "x86-windows" => object::Architecture::I386,
        "aarch64-linux" | "aarch64-windows" => object::Architecture::Aarch64,
        _ => return vec![],
    };
    if file.architecture() == want {
        vec![]
    } else {
        vec![format!(
            "{bin_name} is a {:?} binary, which binaries/{folder}/ is not for ({want:?})",
            file.architecture()
        )]
    }
}

/// The names an ELF shared library exports (defined global or weak symbols of `.dynsym`);
/// `None` for another format (PE, Mach-O) or a file this reader does not understand.
pub fn elf_exports(bin: &[u8]) -> Option<Vec<String>> {
    let u16_at = |o: usize| Some(u16::from_le_bytes(bin.get(o..o + 2)?.try_into().ok()?));
    let u32_at = |o: usize| Some(u32::from_le_bytes(bin.get(o..o + 4)?.try_into().ok()?));
    let u64_at = |o: usize| Some(u64::from_le_bytes(bin.get(o..o + 8)?.try_into().ok()?) as usize);
    // ELF, 64-bit, little-endian.
    if bin.get(..6)? != b"\x7fELF\x02\x01" {
        return None;
    }
    let (shoff, shentsize, shnum) = (u64_at(0x28)?, u16_at(0x3a)? as usize, u16_at(0x3c)? as usize);
    let section = |i: usize| shoff.checked_add(i.checked_mul(shentsize)?);
    let mut out = Vec::new();
    for i in 0..shnum {
        let sh = section(i)?;
        if u32_at(sh + 4)? != 11 {
            continue; // not SHT_DYNSYM
        }
        let (off, size, link, entsize) = (
            u64_at(sh + 0x18)?,
            u64_at(sh + 0x20)?,
            u32_at(sh + 0x28)? as usize,
            u64_at(sh + 0x38)?,
        );
        let strtab = section(link)?;
        let (str_off, str_size) = (u64_at(strtab + 0x18)?, u64_at(strtab + 0x20)?);
        let strings = bin.get(str_off..str_off.checked_add(str_size)?)?;
        if entsize < 24 {
            return None;
        }
        for k in 0..size / entsize {
            let sym = off.checked_add(k * entsize)?;
            let (name, info, shndx) = (u32_at(sym)? as usize, *bin.get(sym + 4)?, u16_at(sym + 6)?);
            let binding = info >> 4;
            if shndx == 0 || !(binding == 1 || binding == 2) {
                continue; // undefined, or local
            }
            let rest = strings.get(name..)?;
            let end = rest.iter().position(|b| *b == 0)?;
            out.push(String::from_utf8_lossy(&rest[..end]).into_owned());
        }
    }
    Some(out)
}

/// What a binary exports against what its FMI version asks: every function of the standard of
/// its version, the other version's functions only all of them (a binary of both versions), no
/// other `fmi2`/`fmi3` name. (ELF here;
/// PE in [`pe_problems`]; the smoke run looks every function up on this machine's binary.)
pub fn export_problems(binary: &[u8], version: FmiVersion, bin_name: &str) -> Vec<String> {
    let Some(exports) = elf_exports(binary) else {
        return vec![];
    };
    check_exports(&exports, version, bin_name)
}

/// [`export_problems`] of a list of exported names (of an ELF or a PE binary).
pub fn check_exports(exports: &[String], version: FmiVersion, bin_name: &str) -> Vec<String> {
    let (own, own_prefix, other, other_prefix) = match version {
        FmiVersion::V2 => (FMI2_FUNCTIONS, "fmi2", FMI3_FUNCTIONS, "fmi3"),
        FmiVersion::V3 => (FMI3_FUNCTIONS, "fmi3", FMI2_FUNCTIONS, "fmi2"),
    };
    let mut problems = Vec::new();
    let exported: BTreeSet<&str> = exports.iter().map(String::as_str).collect();
    // FMI 2.0: the co-simulation functions are required (model exchange ones where offered).
    let required: &[&str] = match version {
        FmiVersion::V2 => FMI2_CS_FUNCTIONS,
        FmiVersion::V3 => FMI3_FUNCTIONS,
    };
    let missing: Vec<&str> = required.iter().copied().filter(|f| !exported.contains(f)).collect();
    if !missing.is_empty() {
        problems.push(format!("{bin_name} does not export {}", missing.join(", ")));
    }
    // A binary may implement the other version too (`rustfmu::export_fmu!` exports both): then
    // all of that version's required functions and no other name of its prefix.
    let foreign: Vec<&str> = exported
        .iter()
        .copied()
        .filter(|n| n.starts_with(other_prefix) || other.contains(n))
        .collect();
    let other_required: &[&str] = match version {
        FmiVersion::V2 => FMI3_FUNCTIONS,
        FmiVersion::V3 => FMI2_CS_FUNCTIONS,
    };
    let whole_other = other_required.iter().all(|f| exported.contains(f)) && foreign.iter().all(|n| other.contains(n));
    if !foreign.is_empty() && !whole_other {
        problems.push(format!(
            "{bin_name} is an FMI {} binary and exports {}: a binary may implement the other FMI version \
             too, but then every function that version requires and no name its standard does not define",
            version.text(),
            foreign.join(", ")
        ));
    }
    let unknown: Vec<&str> = exported
        .iter()
        .copied()
        .filter(|n| n.starts_with(own_prefix) && !own.contains(n))
        .collect();
    if !unknown.is_empty() {
        problems.push(format!(
            "{bin_name} exports {}, which the FMI {} standard does not define",
            unknown.join(", "),
            version.text()
        ));
    }
    problems
}

/// Messages the FMU logged during the smoke run, collected through the logger's environment.
struct Log(Vec<String>);

/// The messages of a recording log as one line.
fn joined(log: &rustfmu::testing::Log) -> String {
    log.entries()
        .iter()
        .map(|e| format!("[status {}, {}] {}", e.status, e.category, e.text))
        .collect::<Vec<_>>()
        .join("; ")
}

/// `resources`: the unpacked archive's `resources/` folder, given to the instance as an importer
/// gives it after unpacking (a model that reads its resources at instantiation must find them).
fn smoke_run_in_child(so: &Path, d: &Description, resources: &Path) -> Vec<String> {
    let vrs: Vec<String> = d.real_vrs.iter().map(|v| v.to_string()).collect();
    let exe = match std::env::current_exe() {
        Ok(e) if e.file_stem().is_some_and(|s| s == "cargo-fmu" || s == "fmu-build") => e,
        // Called from elsewhere (tests): run in this process.
        _ => return smoke_run_version(d.version, so, &d.guid, &d.real_vrs, resources, d.clocks),
    };
    let mut command = std::process::Command::new(&exe);
    command
        .arg("__smoke-run")
        .arg(so)
        .arg(&d.guid)
        .arg(vrs.join(","))
        .arg("--fmi-version")
        .arg(d.version.text())
        .arg("--resources")
        .arg(resources);
    if d.clocks {
        command.arg("--event-mode");
    }
    match command.output() {
        Ok(out) if out.status.success() => {
            forward_notes(&out.stderr);
            vec![]
        }
        Ok(out) => {
            forward_notes(&out.stderr);
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

/// The child's notes ([`NOTE`]), printed by the parent.
fn forward_notes(stderr: &[u8]) {
    for line in String::from_utf8_lossy(stderr).lines().filter(|l| l.starts_with(NOTE)) {
        eprintln!("{line}");
    }
}

/// [`smoke_run`] (FMI 2.0) or [`smoke_run3`] (FMI 3.0).
pub fn smoke_run_version(
    version: FmiVersion,
    so: &Path,
    guid: &str,
    real_vrs: &[u32],
    resources: &Path,
    event_mode: bool,
) -> Vec<String> {
    match version {
        FmiVersion::V2 => smoke_run(so, guid, real_vrs, resources),
        FmiVersion::V3 => smoke_run3(so, guid, real_vrs, resources, event_mode),
    }
}

/// FMI 2.0's fmuResourceLocation of a folder: a `file:` URI of its absolute path, every byte
/// but the unreserved ones and `/` percent-encoded (RFC 3986; a Windows path as `file:///C:/...`).
pub fn file_uri(dir: &Path) -> String {
    let abs = std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf());
    let path = abs.to_string_lossy().replace('\\', "/");
    let mut uri = String::from(if path.starts_with('/') { "file://" } else { "file:///" });
    for b in path.bytes() {
        match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' | b'/' | b':' => uri.push(b as char),
            _ => uri.push_str(&format!("%{b:02X}")),
        }
    }
    uri
}

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
    let mut problems = Vec::new();
    // SAFETY: loading our own freshly built FMU binary; its initializers are Rust std's only.
    let lib = match unsafe { libloading::Library::new(so) } {
        Ok(l) => l,
        Err(e) => return vec![format!("the binary does not load: {e}")],
    };
    for f in FMI3_FUNCTIONS {
        // SAFETY: only the symbol's presence is checked.
        if unsafe { lib.get::<*const ()>(f.as_bytes()) }.is_err() {
            problems.push(format!("the binary does not export {f}"));
        }
    }
    if !problems.is_empty() {
        return problems;
    }
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
        if status != 0 {
            problems.push(format!(
                "a 0.1 s run from the start values did not return fmi3OK (worst status {status}): {}",
                log.0.join("; ")
            ));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            problems.push(format!(
                "Float64 value reference {} is {} after the run",
                real_vrs[i], values[i]
            ));
        }
    }
    // The declared `depends` against the model (a rustfmu library carries its declarations):
    // through FMI 3.0 where the library has no FMI 2.0 (whose smoke run checks them otherwise),
    // and the clocked outputs' always (FMI 3.0 only has clocks).
    if problems.is_empty()
        && let Ok(binary) = std::fs::read(so)
        && let Ok(lib3) = crate::bundle::read_library(&binary, FmiVersion::V3)
    {
        let path = format!("{}{}", resources.display(), std::path::MAIN_SEPARATOR);
        let has_fmi2 = crate::bundle::read_library(&binary, FmiVersion::V2).is_ok();
        let reports = if has_fmi2 {
            crate::depends_fmi3::Api3::load(
                so,
                &lib3.description,
                token,
                &path,
                lib3.interfaces.model_exchange,
                lib3.interfaces.co_simulation,
            )
            .map(|api| vec![crate::depends_fmi3::check_clocked(&api, &lib3.description)])
            .unwrap_or_default()
        } else {
            crate::depends_fmi3::check_all(
                so,
                &lib3.description,
                token,
                &path,
                lib3.interfaces.model_exchange,
                lib3.interfaces.co_simulation,
            )
        };
        for report in reports {
            for note in &report.notes {
                eprintln!("{NOTE}{note}");
            }
            problems.extend(report.problems);
        }
    }
    problems
}

/// Loads the binary, checks its exports, and runs 0.1 s from the start values.
pub fn smoke_run(so: &Path, guid: &str, real_vrs: &[u32], resources: &Path) -> Vec<String> {
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
        if status != fmi2OK {
            problems.push(format!(
                "a 0.1 s run from the start values did not return fmi2OK (worst status {status}): {}",
                joined(log)
            ));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            problems.push(format!(
                "Real value reference {} is {} after the run",
                real_vrs[i], values[i]
            ));
        }
    }
    // The declared `depends` against the model's exact directional derivatives (a rustfmu
    // library carries its declarations; another FMU's binary is not checked here).
    if problems.is_empty()
        && let Ok(binary) = std::fs::read(so)
        && let Ok(me) = crate::bundle::read_library(&binary, FmiVersion::V2)
    {
        let uri = file_uri(resources);
        let mut reports = vec![crate::depends::check_initial(
            so,
            &me.description,
            guid,
            &uri,
            me.interfaces.co_simulation,
        )];
        if me.interfaces.model_exchange {
            reports.push(crate::depends::check(so, &me.description, guid, &uri));
        }
        for report in reports {
            for note in &report.notes {
                eprintln!("{NOTE}{note}");
            }
            problems.extend(report.problems);
        }
    }
    problems
}

/// How a smoke run (in the child process too) says what is worth knowing but no problem: on
/// stderr, a line each, forwarded by [`smoke_run_in_child`].
pub const NOTE: &str = "fmu: note: ";

/// Whether `python` (`--python`) can run fmpy's validator: an interpreter without fmpy is the
/// environment's problem, said as such before anything is built or judged, not an invalid FMU.
pub fn fmpy_ready(python: &Path) -> Result<(), String> {
    let p = python.display();
    let out = std::process::Command::new(python)
        .arg("-c")
        .arg("import fmpy.validation")
        .output()
        .map_err(|e| format!("--python {p}: cannot run this interpreter: {e}"))?;
    if out.status.success() {
        return Ok(());
    }
    let stderr = String::from_utf8_lossy(&out.stderr);
    let why = stderr
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("no message")
        .trim();
    Err(format!(
        "--python {p}: this interpreter cannot import fmpy ({why}), which runs fmpy's validator on the FMUs; \
         install it there (`{p} -m pip install fmpy`), give an interpreter that has it, or leave out --python"
    ))
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
    let mut zip = fmi_conformance::archive::open(fmu)?;
    let mut platforms = std::collections::BTreeSet::new();
    for name in zip.entry_names() {
        let parts: Vec<&str> = name.split('/').collect();
        if parts.len() == 3 && parts[0] == "binaries" && !parts[2].is_empty() {
            platforms.insert(format!("{} ({})", parts[1], parts[2]));
        }
    }
    let xml = fmi_conformance::archive::read_model_description(&mut zip)?;
    let md = fmi_description::parse(&xml).map_err(|e| at(&e))?;
    let mut out = String::new();
    let mut counts: std::collections::BTreeMap<&str, usize> = Default::default();
    let mut interfaces = Vec::new();
    let mut variables = Vec::new();
    // (value reference, name, causality, type, unit) of every variable, in order.
    let listed: Vec<(u32, &str, Causality, String, Option<&str>)> = match &md {
        ModelDescription::Fmi2(d) => {
            out.push_str(&head(
                fmu,
                &d.fmi_version,
                &d.model_name,
                &d.version,
                &d.guid,
                &d.generation_tool,
                &d.description,
            ));
            out.push_str(&experiment(&d.default_experiment));
            interfaces.extend(d.me.as_ref().map(|i| format!("ModelExchange ({})", i.model_identifier)));
            interfaces.extend(d.cs.as_ref().map(|i| format!("CoSimulation ({})", i.model_identifier)));
            let v = d.variables.iter();
            v.map(|v| {
                (
                    v.vr,
                    v.name.as_str(),
                    v.causality,
                    v.ty.name().to_string(),
                    v.unit.as_deref(),
                )
            })
            .collect()
        }
        ModelDescription::Fmi3(d) => {
            out.push_str(&head(
                fmu,
                &d.fmi_version,
                &d.model_name,
                &d.version,
                &d.token,
                &d.generation_tool,
                &d.description,
            ));
            out.push_str(&experiment(&d.default_experiment));
            interfaces.extend(d.me.as_ref().map(|i| format!("ModelExchange ({})", i.model_identifier)));
            interfaces.extend(d.cs.as_ref().map(|i| format!("CoSimulation ({})", i.model_identifier)));
            // An array's type with its dimensions: Float64[2,4]; a length set by a structural
            // parameter by the parameter's name: Float64[n,n].
            d.variables
                .iter()
                .map(|v| {
                    let ty = if v.array {
                        let dims: Vec<String> = v
                            .dimensions
                            .iter()
                            .map(|dim| match dim {
                                fmi3::Dimension::Fixed(n) => n.to_string(),
                                // Set by a structural parameter: its name (Float64[n,n]).
                                fmi3::Dimension::Parameter(vr) => match d.by_vr(*vr) {
                                    Some(p) => p.name.clone(),
                                    None => format!("vr {vr}"),
                                },
                            })
                            .collect();
                        format!("{}[{}]", v.ty.name(), dims.join(","))
                    } else {
                        v.ty.name().to_string()
                    };
                    (v.vr, v.name.as_str(), v.causality, ty, v.unit.as_deref())
                })
                .collect()
        }
    };
    // FMI 3.0 terminals: their names and members.
    let terminals: Vec<String> = match zip.read_entry("terminalsAndIcons/terminalsAndIcons.xml") {
        Ok(Some(text)) => terminal_lines(&String::from_utf8_lossy(&text)),
        _ => Vec::new(),
    };
    for (vr, name, causality, ty, unit) in listed {
        *counts.entry(causality.name()).or_default() += 1;
        let unit = unit.map(|u| format!(", {u}")).unwrap_or_default();
        variables.push(format!("    {vr:>5} {name} ({causality}, {ty}{unit})"));
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
    // The oldest glibc each Linux binary loads with.
    for (name, needed) in glibc_requirements(fmu)? {
        if let Some((major, minor)) = needed {
            out.push_str(&format!("  {name} needs glibc >= {major}.{minor}\n"));
        }
    }
    // The architectures of each macOS binary and the oldest macOS each loads on.
    for (name, slices) in macos_binaries(fmu)? {
        out.push_str(&format!("  {name}: {slices}\n"));
    }
    let counts: Vec<String> = counts.iter().map(|(k, v)| format!("{v} {k}")).collect();
    out.push_str(&format!("  variables: {} ({})\n", variables.len(), counts.join(", ")));
    for v in variables {
        out.push_str(&v);
        out.push('\n');
    }
    if !terminals.is_empty() {
        out.push_str(&format!("  terminals: {}\n", terminals.len()));
        for t in terminals {
            out.push_str(&format!("    {t}\n"));
        }
    }
    Ok(out)
}

/// A glibc version: (major, minor).
pub type GlibcVersion = (u32, u32);

/// The highest `GLIBC_x.y` symbol version an ELF binary references (its `.gnu.version_r`
/// needs): the oldest glibc it loads with. `None` for a binary that is no ELF or needs no
/// glibc version.
pub fn glibc_needed(binary: &[u8]) -> Option<GlibcVersion> {
    use object::read::elf::{ElfFile64, FileHeader};
    let elf = ElfFile64::<object::Endianness>::parse(binary).ok()?;
    let endian = elf.endian();
    let sections = elf.elf_header().sections(endian, binary).ok()?;
    let (mut needs, link) = sections.gnu_verneed(endian, binary).ok()??;
    let strings = sections.strings(endian, binary, link).ok()?;
    let mut highest = None;
    while let Ok(Some((_, mut auxes))) = needs.next() {
        while let Ok(Some(aux)) = auxes.next() {
            let Ok(name) = aux.name(endian, strings) else { continue };
            let Some(version) = std::str::from_utf8(name).ok().and_then(|n| n.strip_prefix("GLIBC_")) else {
                continue;
            };
            let mut parts = version.split('.').map(|p| p.parse::<u32>());
            if let (Some(Ok(major)), Some(Ok(minor))) = (parts.next(), parts.next()) {
                highest = highest.max(Some((major, minor)));
            }
        }
    }
    highest
}

/// For each Linux binary of an FMU (`binaries/<folder>/<id>.so`): its path in the archive and
/// the glibc it needs at least ([`glibc_needed`]).
pub fn glibc_requirements(fmu: &Path) -> Result<Vec<(String, Option<GlibcVersion>)>, String> {
    let mut zip = fmi_conformance::archive::open(fmu)?;
    let mut out = Vec::new();
    for name in zip.entry_names() {
        if name.starts_with("binaries/") && name.ends_with(".so") {
            let bytes = zip.read_entry_within(&name, 1 << 30)?.unwrap_or_default();
            out.push((name, glibc_needed(&bytes)));
        }
    }
    Ok(out)
}

/// For each macOS binary of an FMU: its path in the archive and its architectures with the
/// oldest macOS each loads on (`x86_64 (macOS >= 10.12), aarch64 (macOS >= 11.0)`), or what is
/// wrong with it.
pub fn macos_binaries(fmu: &Path) -> Result<Vec<(String, String)>, String> {
    let mut zip = fmi_conformance::archive::open(fmu)?;
    let mut out = Vec::new();
    for name in zip.entry_names() {
        if name.starts_with("binaries/") && name.ends_with(".dylib") {
            let bytes = zip.read_entry_within(&name, 1 << 30)?.unwrap_or_default();
            let text = match macho_slices(&bytes) {
                None => "no Mach-O binary".to_string(),
                Some(Err(e)) => e,
                Some(Ok(slices)) => slices
                    .iter()
                    .map(|s| {
                        let arch = format!("{:?}", s.architecture).to_lowercase();
                        let other = s
                            .exports
                            .iter()
                            .filter(|n| !n.starts_with("fmi2") && !n.starts_with("fmi3") && !macos_runtime_export(n))
                            .count();
                        let other = if other > 0 {
                            format!(", {other} non-FMI exports")
                        } else {
                            String::new()
                        };
                        match s.min_macos {
                            Some((major, minor)) => format!("{arch} (macOS >= {major}.{minor}{other})"),
                            None => format!("{arch}{other}"),
                        }
                    })
                    .collect::<Vec<_>>()
                    .join(", "),
            };
            out.push((name, text));
        }
    }
    Ok(out)
}

/// One line per `<Terminal>` of terminalsAndIcons.xml: `name (kind): member = variable (kind), ...`.
fn terminal_lines(text: &str) -> Vec<String> {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_str(text);
    let mut out: Vec<String> = Vec::new();
    let mut members: Vec<String> = Vec::new();
    let mut current: Option<String> = None;
    loop {
        let (e, empty) = match reader.read_event() {
            Ok(Event::Start(e)) => (e, false),
            Ok(Event::Empty(e)) => (e, true),
            Ok(Event::End(e)) if e.name().as_ref() == b"Terminal" => {
                if let Some(t) = current.take() {
                    out.push(format!("{t}: {}", members.join(", ")));
                    members.clear();
                }
                continue;
            }
            Ok(Event::Eof) | Err(_) => break,
            Ok(_) => continue,
        };
        let attr = |name: &str| {
            e.try_get_attribute(name)
                .ok()
                .flatten()
                .and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
                .unwrap_or_default()
        };
        match e.name().as_ref() {
            b"Terminal" => {
                let kind = attr("terminalKind");
                current = Some(if kind.is_empty() {
                    attr("name")
                } else {
                    format!("{} ({kind})", attr("name"))
                });
                if empty {
                    out.extend(current.take());
                }
            }
            b"TerminalMemberVariable" => members.push(format!(
                "{} = {} ({})",
                attr("memberName"),
                attr("variableName"),
                attr("variableKind")
            )),
            _ => {}
        }
    }
    out
}

/// The first lines of `cargo fmu info`.
fn head(
    fmu: &Path,
    fmi_version: &str,
    name: &str,
    version: &str,
    token: &str,
    tool: &str,
    description: &str,
) -> String {
    format!(
        "{}: FMI {fmi_version}, model '{name}', version '{version}'\n  GUID/token {token}\n  generated by {tool}\n  {description}\n",
        fmu.display()
    )
}

/// `cargo fmu info`'s line of the default experiment, its values as written (none without one).
fn experiment(e: &fmi_description::DefaultExperiment) -> String {
    let parts: Vec<String> = [
        ("start", &e.start_time),
        ("stop", &e.stop_time),
        ("step", &e.step_size),
        ("tolerance", &e.tolerance),
    ]
    .iter()
    .filter_map(|(label, v)| v.as_ref().filter(|v| !v.is_empty()).map(|v| format!("{label} {v}")))
    .collect();
    if parts.is_empty() {
        String::new()
    } else {
        format!("  default experiment: {}\n", parts.join(", "))
    }
}

#[cfg(test)]
mod terminal_tests {
    use super::terminal_problems;

    const MD: &str = r#"<fmiModelDescription fmiVersion="3.0" modelName="M" instantiationToken="{x}">
  <CoSimulation modelIdentifier="M"/>
  <ModelVariables><Float64 name="phi" valueReference="1" causality="output"/></ModelVariables>
  <ModelStructure><Output valueReference="1"/></ModelStructure>
</fmiModelDescription>"#;

    fn terminals(member: &str) -> String {
        format!(
            r#"<fmiTerminalsAndIcons fmiVersion="3.0"><Terminals><Terminal name="f" matchingRule="plug">{member}</Terminal></Terminals></fmiTerminalsAndIcons>"#
        )
    }

    #[test]
    fn members_must_name_variables_and_have_a_kind() {
        let good = terminals(r#"<TerminalMemberVariable variableName="phi" memberName="phi" variableKind="signal"/>"#);
        assert!(terminal_problems(&good, MD).is_empty());
        let unknown =
            terminals(r#"<TerminalMemberVariable variableName="tau" memberName="tau" variableKind="inflow"/>"#);
        assert_eq!(
            terminal_problems(&unknown, MD),
            ["terminalsAndIcons.xml: member variable 'tau' is no variable of modelDescription.xml"]
        );
        let kindless = terminals(r#"<TerminalMemberVariable variableName="phi"/>"#);
        assert_eq!(terminal_problems(&kindless, MD).len(), 1);
        assert_eq!(terminal_problems("<x", MD).len(), 1);
        assert_eq!(
            terminal_problems(&good.replace("3.0", "2.0"), MD),
            ["terminalsAndIcons.xml: fmiVersion is not 3.x"]
        );
    }
}

#[cfg(test)]
mod array_tests {
    use super::array_problems;
    use fmi_description::fmi3::ModelDescription;

    /// A description with a structural parameter `n` (start 2), a Float64 parameter `k` and
    /// the array `a` (its attributes after `valueReference`, its `<Dimension>`s).
    fn problems(a: &str, dims: &str) -> Vec<String> {
        let xml = format!(
            r#"<fmiModelDescription fmiVersion="3.0" modelName="M" instantiationToken="{{x}}">
  <CoSimulation modelIdentifier="M"/>
  <ModelVariables>
    <UInt64 name="n" valueReference="1" causality="structuralParameter" variability="fixed" start="2"/>
    <Float64 name="k" valueReference="2" causality="parameter" variability="fixed" start="2"/>
    <Float64 name="a" valueReference="3" {a}>{dims}</Float64>
  </ModelVariables>
</fmiModelDescription>"#
        );
        array_problems(&ModelDescription::parse(&xml).unwrap())
    }

    #[test]
    fn a_length_is_set_by_a_uint64_structural_parameter_and_the_start_lists_the_start_size() {
        let p = r#"causality="parameter" variability="fixed""#;
        // n x 3 at the start: 2 x 3 = 6 values, or one for all.
        let sized = r#"<Dimension valueReference="1"/><Dimension start="3"/>"#;
        assert!(problems(&format!(r#"{p} start="1 2 3 4 5 6""#), sized).is_empty());
        assert!(problems(&format!(r#"{p} start="7""#), sized).is_empty());
        assert_eq!(
            problems(&format!(r#"{p} start="1 2 3""#), sized),
            ["variable 'a' (vr 3): 3 start values for 6 elements (the lengths at the start: 2 x 3)"]
        );
        // A fixed array counts the same way.
        assert!(!problems(&format!(r#"{p} start="1 2 3""#), r#"<Dimension start="2"/>"#).is_empty());
        // No start (an output): nothing to count.
        assert!(problems(r#"causality="output""#, sized).is_empty());
        // A length set by a Float64 parameter, or by no variable.
        let by_k = problems(&format!(r#"{p} start="1""#), r#"<Dimension valueReference="2"/>"#);
        assert_eq!(by_k.len(), 1);
        assert!(by_k[0].contains("names 'k', a parameter Float64"), "{by_k:?}");
        let by_none = problems(&format!(r#"{p} start="1""#), r#"<Dimension valueReference="9"/>"#);
        assert_eq!(
            by_none,
            ["variable 'a' (vr 3): <Dimension valueReference=\"9\"> names no variable"]
        );
    }
}

#[cfg(test)]
mod glibc_tests {
    #[test]
    fn the_highest_glibc_version_of_this_test_binary_is_read() {
        // This test executable is an ELF linked against glibc (x86_64 and aarch64 Linux, where
        // the project builds): it references GLIBC_2.x versions.
        let me = std::fs::read(std::env::current_exe().unwrap()).unwrap();
        let (major, minor) = super::glibc_needed(&me).expect("a glibc version");
        assert_eq!(major, 2);
        assert!(minor >= 2, "GLIBC_2.{minor}");
        assert_eq!(super::glibc_needed(b"not an ELF file"), None);
    }
}
