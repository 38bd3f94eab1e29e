//! `cargo fmu container SYSTEM.ssp`: a composed system as one FMI 2.0 or 3.0 co-simulation FMU.
//!
//! The container is the system's SSP tree (unchanged, under `resources/system/`), a spec of
//! what it exposes (`resources/container.toml`, `rustfmu_runner::container::Spec`), a
//! `modelDescription.xml` written from the spec and the components' descriptions, and the
//! binary of `runner/container` (rustfmu-runner's master behind the FMI 2.0 and 3.0 APIs) built for
//! every platform all the components carry (or the `--target`s given), named after the
//! container's model identifier.

use crate::cargo::{self, FmuCrate};
use rustfmu::description::FmiVersion;
use rustfmu_runner::Simulation;
use rustfmu_runner::container::{SPEC_FILE, SYSTEM_FOLDER, Spec};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use zip::write::SimpleFileOptions;

/// What `cargo fmu container` was asked for.
pub struct Request<'a> {
    pub ssp: &'a Path,
    pub out: Option<&'a Path>,
    pub step: Option<f64>,
    pub targets: &'a [String],
    pub python: Option<&'a Path>,
    /// The FMI versions to write: FMI 2.0 to `out`, FMI 3.0 to `out` when it is the only one,
    /// else to `fmi3/` beside it (as `cargo fmu build` places FMI 3.0 FMUs).
    pub versions: &'a [FmiVersion],
}

/// The archive's entries: (name, bytes).
fn entries(path: &Path) -> Result<Vec<(String, Vec<u8>)>, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut zip = zip::ZipArchive::new(file).map_err(|e| format!("{}: not a zip archive: {e}", path.display()))?;
    let mut out = Vec::new();
    for i in 0..zip.len() {
        let mut f = zip.by_index(i).map_err(|e| format!("{}: {e}", path.display()))?;
        if f.is_dir() {
            continue;
        }
        let name = f.name().map_err(|e| format!("{}: {e}", path.display()))?.into_owned();
        let mut bytes = Vec::new();
        f.read_to_end(&mut bytes)
            .map_err(|e| format!("{}: {name}: {e}", path.display()))?;
        out.push((name, bytes));
    }
    Ok(out)
}

/// The files of a zip archive in memory: (name, bytes); names that would leave the folder refused.
fn entries_of(bytes: &[u8]) -> Result<Vec<(String, Vec<u8>)>, String> {
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes)).map_err(|e| format!("not a zip archive: {e}"))?;
    let mut out = Vec::new();
    for i in 0..zip.len() {
        let mut f = zip.by_index(i).map_err(|e| e.to_string())?;
        if f.is_dir() {
            continue;
        }
        let name = f
            .enclosed_name()
            .ok_or_else(|| format!("entry {i} has a name that leaves the archive's folder"))?
            .to_string_lossy()
            .replace('\\', "/");
        let mut data = Vec::new();
        f.read_to_end(&mut data).map_err(|e| format!("{name}: {e}"))?;
        out.push((name, data));
    }
    Ok(out)
}

/// The FMI 2.0 platform folders an FMU archive has binaries for.
fn platforms_of(fmu: &[u8]) -> Result<Vec<String>, String> {
    let zip = zip::ZipArchive::new(std::io::Cursor::new(fmu)).map_err(|e| e.to_string())?;
    let mut out: Vec<String> = Vec::new();
    for name in zip.file_names() {
        let Ok(name) = name else { continue };
        if let Some(rest) = name.strip_prefix("binaries/")
            && let Some((folder, file)) = rest.split_once('/')
            && !file.is_empty()
            && !out.iter().any(|f| f == folder)
        {
            out.push(folder.to_owned());
        }
    }
    Ok(out)
}

fn model_description_of(fmu: &[u8]) -> Result<String, String> {
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(fmu)).map_err(|e| e.to_string())?;
    let mut xml = String::new();
    zip.by_name("modelDescription.xml")
        .map_err(|e| e.to_string())?
        .read_to_string(&mut xml)
        .map_err(|e| e.to_string())?;
    Ok(xml)
}

/// The stepSize of the SSD's fixed-step master annotation (`<oms:FixedStepMaster stepSize="..."/>`).
fn fixed_step_of(ssd: &str) -> Option<f64> {
    let at = ssd.find("FixedStepMaster")?;
    let rest = &ssd[at..ssd[at..].find('>').map_or(ssd.len(), |e| at + e)];
    let key = "stepSize=\"";
    let i = rest.find(key)? + key.len();
    let j = rest[i..].find('"')?;
    rest[i..i + j]
        .trim()
        .parse()
        .ok()
        .filter(|h: &f64| *h > 0.0 && h.is_finite())
}

/// The rustfmu workspace this cargo-fmu was built from: the container's binary is built there.
fn rustfmu_workspace() -> Result<cargo::Workspace, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .ok_or("no rustfmu workspace")?
        .to_path_buf();
    let manifest = root.join("Cargo.toml");
    if !root.join("runner/container/Cargo.toml").is_file() {
        return Err(format!(
            "the container's binary is built from rustfmu's sources (runner/container), and this cargo-fmu was built from {}, \
             which has no runner/container any more",
            root.display()
        ));
    }
    cargo::workspace(Some(&manifest))
}

/// Writes the container FMUs of `req.ssp` (one per FMI version asked); returns their paths.
pub fn container(req: &Request) -> Result<Vec<PathBuf>, String> {
    let shown = req.ssp.display().to_string();
    let sim = Simulation::from_ssp(req.ssp).map_err(|e| e.message)?;
    let name = rustfmu_runner::container::identifier(&sim.name);
    let out = match req.out {
        Some(p) => p.to_path_buf(),
        None => req.ssp.with_file_name(format!("{}.fmu", name)),
    };
    if out.extension().is_none_or(|e| e != "fmu") {
        return Err(format!("{}: the container's file name must end in .fmu", out.display()));
    }
    if req.versions.is_empty() {
        return Err("no FMI version to write".into());
    }
    let outs: Vec<(FmiVersion, PathBuf)> = req
        .versions
        .iter()
        .map(|&v| {
            let path = if v == FmiVersion::V3 && req.versions.len() > 1 {
                let name = out.file_name().expect("a file name ending in .fmu");
                out.with_file_name("fmi3").join(name)
            } else {
                out.clone()
            };
            (v, path)
        })
        .collect();
    // Never over another FMU (a system named like one of its components, beside it).
    for (_, out) in &outs {
        if out.exists() {
            let bytes = std::fs::read(out).map_err(|e| format!("{}: {e}", out.display()))?;
            let ours = model_description_of(&bytes).is_ok_and(|x| x.contains("generationTool=\"rustfmu-container"));
            if !ours {
                return Err(format!(
                    "{} exists and is not a container FMU: name another file with -o",
                    out.display()
                ));
            }
        }
    }

    let files = entries(req.ssp)?;
    let mut archive = rustfmu_runner::ssp::Archive::open(req.ssp).map_err(|e| e.message)?;
    let system_name = archive.ssd.name.clone();
    let components: Vec<String> = archive.ssd.components.iter().map(|c| c.name.clone()).collect();
    // The components' descriptions as written, their FMI versions and binary folders.
    let mut xmls = Vec::new();
    let mut carried: Vec<(String, FmiVersion, Vec<String>)> = Vec::new();
    for c in &components {
        let bytes = archive.fmu_bytes(c).map_err(|e| e.message)?;
        let xml = model_description_of(&bytes).map_err(|e| format!("{shown}: component '{c}': {e}"))?;
        let version = match fmi_description::fmi_version(&xml) {
            Ok(v) if v.starts_with("3.") => FmiVersion::V3,
            _ => FmiVersion::V2,
        };
        let folders = platforms_of(&bytes).map_err(|e| format!("{shown}: component '{c}': {e}"))?;
        carried.push((c.clone(), version, folders));
        xmls.push((c.clone(), xml));
    }
    // Whether every component has a binary for target `t` (in its own version's folder).
    let lacking = |t: &str| -> Option<String> {
        let p = crate::target::platform(t).ok()?;
        carried.iter().find_map(|(c, v, folders)| match p.folder(*v) {
            Ok(f) if folders.contains(&f) => None,
            Ok(f) => Some(format!(
                "component '{c}' has no {f} binary (it has: {})",
                folders.join(", ")
            )),
            Err(e) => Some(format!("component '{c}': {e}")),
        })
    };
    // The internal step: --step, else the step the SSD names for a fixed-step master (the
    // OMSimulator annotation `cargo fmu` writes: <oms:FixedStepMaster stepSize=...>).
    let ssd_text = files
        .iter()
        .find(|(n, _)| n == "SystemStructure.ssd")
        .map(|(_, b)| String::from_utf8_lossy(b).into_owned())
        .unwrap_or_default();
    let step = match req.step {
        Some(h) => h,
        None => fixed_step_of(&ssd_text).ok_or_else(|| {
            format!("{shown}: the SSD names no fixed step size (oms:FixedStepMaster stepSize): give the container's internal step with --step")
        })?,
    };
    let spec = Spec::new(&sim, step).map_err(|e| e.message)?;
    let experiment = (archive.ssd.start_time, archive.ssd.stop_time);
    let xml2 = spec.model_description(&sim, &system_name, &xmls, experiment);
    let xml3 = spec.model_description3(&sim, &system_name, &xmls, experiment);
    drop(sim);

    // Which binaries: the targets asked for, else the rustfmu workspace's FMU targets, those
    // every component has a binary for (in its own version's folder).
    let ws = rustfmu_workspace()?;
    let host = crate::target::host_triple()?;
    let wanted: Vec<String> = if req.targets.is_empty() {
        let all = match ws.fmu_metadata.get("targets") {
            Some(v) => crate::target::parse_targets(v)?,
            None => vec![host.clone()],
        };
        let (fit, misfit): (Vec<String>, Vec<String>) = all.into_iter().partition(|t| lacking(t).is_none());
        if fit.is_empty() {
            let why: Vec<String> = misfit
                .iter()
                .map(|t| format!("{t}: {}", lacking(t).unwrap_or_default()))
                .collect();
            return Err(format!(
                "{shown}: no platform has a binary in every component FMU, so a container cannot run anywhere ({})",
                why.join("; ")
            ));
        }
        fit
    } else {
        for t in req.targets {
            crate::target::platform(t)?;
            if let Some(why) = lacking(t) {
                return Err(format!("target {t}: {why}"));
            }
        }
        req.targets.to_vec()
    };
    // (target, FMI 2.0 binary name if FMI 2.0 has a folder for it, FMI 3.0 binary name)
    let mut binaries: Vec<(String, Option<String>, String)> = Vec::new();
    for t in &wanted {
        let p = crate::target::platform(t)?;
        let folder3 = p.folder(FmiVersion::V3).map_err(|e| format!("target {t}: {e}"))?;
        binaries.push((
            t.clone(),
            p.folder(FmiVersion::V2)
                .ok()
                .map(|f| format!("binaries/{f}/{}.{}", spec.model_identifier, p.extension())),
            format!("binaries/{folder3}/{}.{}", spec.model_identifier, p.extension()),
        ));
    }
    for t in &wanted {
        crate::target::preflight(t, &host, req.python)?;
    }
    let krate = FmuCrate {
        package: "rustfmu-container".into(),
        manifest_dir: ws.root.join("runner/container"),
        lib_name: "rustfmu_container".into(),
        documentation: None,
        resources: None,
        fmi_versions: None,
        targets: None,
    };
    let zig = if wanted.iter().any(|t| crate::target::uses_zig(t, &host)) {
        Some(crate::target::Zig::find(req.python)?)
    } else {
        None
    };
    // One binary serves both versions (it exports the fmi2* and the fmi3* functions).
    let mut built: Vec<(String, String, Vec<u8>)> = Vec::new();
    let mut built3: Vec<(String, String, Vec<u8>)> = Vec::new();
    for (t, name, name3) in &binaries {
        let triple = (t != &host).then_some(t.as_str());
        let linker = if crate::target::uses_zig(t, &host) {
            zig.as_ref()
        } else {
            None
        };
        cargo::build(&ws, std::slice::from_ref(&krate), triple, &host, linker)?;
        let lib = ws.library_for(&krate, t, &host)?;
        let bytes = std::fs::read(&lib).map_err(|e| format!("{}: {e}", lib.display()))?;
        built3.push((name3.clone(), t.clone(), bytes.clone()));
        if let Some(name) = name {
            built.push((name.clone(), t.clone(), bytes));
        }
    }
    let binaries2 = crate::bundle::merge_universal(built)?;
    let binaries3 = crate::bundle::merge_universal(built3)?;
    let sources: Vec<String> = archive
        .ssd
        .components
        .iter()
        .map(|c| c.source.trim_start_matches("./").to_owned())
        .collect();
    let mut written = Vec::new();
    for (version, out) in &outs {
        let (xml, binaries) = match version {
            FmiVersion::V2 => (&xml2, &binaries2),
            FmiVersion::V3 => (&xml3, &binaries3),
        };
        let package = Package {
            xml,
            binaries,
            spec: &spec,
            files: &files,
            sources: &sources,
            system_name: &system_name,
            components: &components,
        };
        write_fmu(out, &package, &shown)?;
        eprintln!(
            "fmu: wrote {} (FMI {}; {} variables: {} components of {shown}, internal step {} s; binaries: {})",
            out.display(),
            version.text(),
            spec.variables.len(),
            components.len(),
            spec.step,
            binaries.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join(", ")
        );
        written.push(out.clone());
    }
    Ok(written)
}

/// What goes into one container FMU.
struct Package<'a> {
    xml: &'a str,
    binaries: &'a [(String, Vec<u8>)],
    spec: &'a Spec,
    /// The SSP archive's files.
    files: &'a [(String, Vec<u8>)],
    /// The component FMUs' names among them.
    sources: &'a [String],
    system_name: &'a str,
    components: &'a [String],
}

/// Writes the FMU `out` (through a partial file renamed at the end).
fn write_fmu(out: &Path, p: &Package, shown: &str) -> Result<(), String> {
    let Package {
        xml,
        binaries,
        spec,
        files,
        sources,
        system_name,
        components,
    } = *p;
    if let Some(dir) = out.parent()
        && !dir.as_os_str().is_empty()
    {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }

    let tmp = out.with_extension("fmu.partial");
    let file = std::fs::File::create(&tmp).map_err(|e| format!("{}: {e}", tmp.display()))?;
    let mut zip = zip::ZipWriter::new(file);
    let deflate = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    let zip_err = |e: &dyn std::fmt::Display| format!("{}: {e}", tmp.display());
    let mut add = |name: &str, bytes: &[u8], exec: bool| -> Result<(), String> {
        let options = if exec { deflate.unix_permissions(0o755) } else { deflate };
        zip.start_file(name, options).map_err(|e| zip_err(&e))?;
        zip.write_all(bytes).map_err(|e| zip_err(&e))
    };
    add("modelDescription.xml", xml.as_bytes(), false)?;
    for (name, bytes) in binaries {
        add(name, bytes, true)?;
    }
    add(&format!("resources/{SPEC_FILE}"), spec.to_toml().as_bytes(), false)?;
    // The system's files; each component FMU unpacked into a folder of its file's name, which
    // the container's binary loads without unpacking it again at every instantiation.
    for (name, bytes) in files {
        if sources.contains(name) {
            for (inner, data) in entries_of(bytes).map_err(|e| format!("{shown}: {name}: {e}"))? {
                let exec = inner.starts_with("binaries/");
                add(&format!("resources/{SYSTEM_FOLDER}/{name}/{inner}"), &data, exec)?;
            }
        } else {
            add(&format!("resources/{SYSTEM_FOLDER}/{name}"), bytes, false)?;
        }
    }
    let names: Vec<String> = spec
        .variables
        .iter()
        .map(|e| format!("{} {} {}", e.causality, e.ty, e.name))
        .collect();
    add(
        "documentation/index.html",
        format!(
            "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{id}</title></head><body>\n<h1>{id}</h1>\n\
             <p>The system {system} (components {components}) as one co-simulation FMU, made by <code>cargo fmu container</code>: \
             rustfmu-runner's Gauss-Seidel master steps the components at {step} s inside.</p>\n<h2>Variables</h2>\n<ul>\n{vars}\n</ul>\n</body></html>\n",
            id = spec.model_identifier,
            system = quick_xml::escape::escape(system_name),
            components = quick_xml::escape::escape(components.join(", ")),
            step = spec.step,
            vars = names
                .iter()
                .map(|n| format!("<li>{}</li>", quick_xml::escape::escape(n)))
                .collect::<Vec<_>>()
                .join("\n")
        )
        .as_bytes(),
        false,
    )?;
    zip.finish().map_err(|e| zip_err(&e))?;
    std::fs::rename(&tmp, out).map_err(|e| format!("{}: {e}", out.display()))?;
    Ok(())
}
