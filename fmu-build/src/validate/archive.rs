//! `validate`: the archive's entries and platform folders, the packaged description against the
//! one its binary carries, then each binary's checks ([`super::binary`], [`super::pe`],
//! [`super::macho`]) and the smoke run of this machine's binary ([`super::smoke`]).

use super::{
    architecture_problems, array_problems, export_problems, ls_bus_problems, macho_problems, pe_problems,
    smoke_run_in_child, terminal_problems,
};
use md_reader::{ModelDescription, fmi2, fmi3};
use rustfmu::description::FmiVersion;
use std::collections::BTreeSet;
use std::path::Path;

/// What validation needs of the packaged description, read by the workspace's one reader
/// (`md_reader`). The checks of the archive itself (entry names, the XML's encoding and
/// well-formedness, with line and column) are the conformance suite's archive module's, and
/// the comparison with the description the binary carries compares the raw XML text.
pub(super) struct Description {
    pub(super) version: FmiVersion,
    pub(super) model_identifier: String,
    /// The GUID (FMI 2.0) or instantiationToken (FMI 3.0).
    pub(super) guid: String,
    pub(super) real_vrs: Vec<u32>,
    /// FMI 3.0 with clocks: co-simulation needs eventModeUsed (the smoke run then handles Event Mode).
    pub(super) clocks: bool,
    /// What is wrong with the description itself ([`array_problems`]).
    pub(super) problems: Vec<String>,
}

fn read_description(xml: &str) -> Result<Description, String> {
    let (version, cs, guid, real_vrs, clocks, problems) = match md_reader::parse(xml)? {
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
    // FMI-LS-BUS: the manifest and every network terminal's rules (nothing where neither is).
    let read = |p: std::path::PathBuf| std::fs::read_to_string(p).ok();
    problems.extend(ls_bus_problems(
        read(terminals.clone()).as_deref(),
        &xml,
        read(dir.path().join(crate::xml::LS_BUS_MANIFEST)).as_deref(),
    ));
    for (folder, bin_name) in &binaries {
        let so = dir.path().join(bin_name);
        let binary = std::fs::read(&so).map_err(|e| format!("{bin_name}: {e}"))?;
        // A binary made by rustfmu describes itself: the packaged description must be what it says.
        if let Ok(all) = crate::library::library_versions(&binary) {
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
                Some(me) => match crate::library::model_description(me) {
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
