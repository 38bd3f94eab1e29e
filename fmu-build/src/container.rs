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
    /// `-v`: cargo's messages as they come (else a progress line per target).
    pub verbose: bool,
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
///
/// One function of ~200 lines, kept whole: reading the system, building the container's binary
/// for every target and packaging each version run in order on the same request, targets and
/// binaries; each step is marked by a comment.
pub fn container(req: &Request) -> Result<Vec<PathBuf>, String> {
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

    let main = System::read(req.ssp, sim, req.step)?;
    // The FMI 3.0 container of FMI 2.0 components is made of their FMI 3.0 twins where `cargo
    // fmu build` wrote them: FMI 2.0 names no folder for aarch64 Linux, so FMI 2.0 components
    // carry no aarch64-linux binary, and a container of them could not run there.
    let twin = if req.versions.contains(&FmiVersion::V3) && main.has_fmi2_component() {
        fmi3_twin(req.ssp, &main)?
    } else {
        None
    };
    let system_of = |v: FmiVersion| match (v, &twin) {
        (FmiVersion::V3, Some(t)) => t,
        _ => &main,
    };

    // Which binaries: the targets asked for, else the rustfmu workspace's FMU targets, those
    // every component has a binary for (in its own version's folder), for each version apart.
    let ws = rustfmu_workspace()?;
    let host = crate::target::host_triple()?;
    let platform = crate::target::platform;
    // Whether version `v` has a folder for target `t`, and if so why its system cannot run
    // there (a component without a binary for it): Ok(None) = it can.
    let misfit = |v: FmiVersion, t: &str| -> Result<Option<String>, String> {
        Ok(match platform(t)?.folder(v) {
            Ok(_) => system_of(v).lacking(t),
            Err(_) => Some(format!("FMI {} names no folder for it", v.text())),
        })
    };
    // (target, the versions whose container gets its binary)
    let mut wanted: Vec<(String, Vec<FmiVersion>)> = Vec::new();
    if req.targets.is_empty() {
        let all = match ws.fmu_metadata.get("targets") {
            Some(v) => crate::target::parse_targets(v)?,
            None => vec![host.clone()],
        };
        for v in req.versions {
            let mut why = Vec::new();
            for t in &all {
                match misfit(*v, t)? {
                    None => match wanted.iter_mut().find(|(w, _)| w == t) {
                        Some((_, vs)) => vs.push(*v),
                        None => wanted.push((t.clone(), vec![*v])),
                    },
                    Some(e) => why.push(format!("{t}: {e}")),
                }
            }
            if !wanted.iter().any(|(_, vs)| vs.contains(v)) {
                return Err(format!(
                    "{}: no platform has a binary in every component FMU, so a container cannot run anywhere ({})",
                    system_of(*v).shown,
                    why.join("; ")
                ));
            }
        }
        // In the workspace's order of targets.
        wanted.sort_by_key(|(t, _)| all.iter().position(|a| a == t));
    } else {
        for t in req.targets {
            let p = platform(t)?;
            p.folder(FmiVersion::V3).map_err(|e| format!("target {t}: {e}"))?;
            let mut versions = Vec::new();
            for v in req.versions {
                if p.folder(*v).is_err() {
                    continue;
                }
                if let Some(why) = system_of(*v).lacking(t) {
                    return Err(format!("target {t}: {why}"));
                }
                versions.push(*v);
            }
            if versions.is_empty() {
                return Err(format!(
                    "target {t}: FMI {} names no folder for it",
                    req.versions.iter().map(|v| v.text()).collect::<Vec<_>>().join(" and ")
                ));
            }
            wanted.push((t.clone(), versions));
        }
    }
    for (t, _) in &wanted {
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
        documentation_start: Ok(vec![]),
        example: false,
    };
    let zig = if wanted.iter().any(|(t, _)| crate::target::uses_zig(t, &host)) {
        Some(crate::target::Zig::find(req.python)?)
    } else {
        None
    };
    // One binary serves both versions (it exports the fmi2* and the fmi3* functions), every target
    // built side by side as `cargo fmu build` builds FMU crates.
    let jobs: Vec<(String, Vec<FmuCrate>)> = wanted.iter().map(|(t, _)| (t.clone(), vec![krate.clone()])).collect();
    cargo::build_targets(&ws, &jobs, &host, zig.as_ref(), req.verbose, "container binaries")?;
    let mut built: Vec<(String, String, Vec<u8>)> = Vec::new();
    let mut built3: Vec<(String, String, Vec<u8>)> = Vec::new();
    for (t, versions) in &wanted {
        let p = platform(t)?;
        let lib = ws.library_for(&krate, t, &host)?;
        let bytes = std::fs::read(&lib).map_err(|e| format!("{}: {e}", lib.display()))?;
        for v in versions {
            let folder = p.folder(*v).map_err(|e| format!("target {t}: {e}"))?;
            let name = format!("binaries/{folder}/{}.{}", main.spec.model_identifier, p.extension());
            match v {
                FmiVersion::V2 => built.push((name, t.clone(), bytes.clone())),
                FmiVersion::V3 => built3.push((name, t.clone(), bytes.clone())),
            }
        }
    }
    let binaries2 = crate::bundle::merge_universal(built)?;
    let binaries3 = crate::bundle::merge_universal(built3)?;
    let mut written = Vec::new();
    for (version, out) in &outs {
        let system = system_of(*version);
        let (xml, binaries) = match version {
            FmiVersion::V2 => (&system.xml2, &binaries2),
            FmiVersion::V3 => (&system.xml3, &binaries3),
        };
        let package = Package {
            xml,
            binaries,
            spec: &system.spec,
            files: &system.files,
            sources: &system.sources,
            system_name: &system.system_name,
            components: &system.components,
        };
        write_fmu(out, &package, &system.shown)?;
        eprintln!(
            "fmu: wrote {} (FMI {}; {} variables: {} components of {}, internal step {} s; binaries: {})",
            out.display(),
            version.text(),
            system.spec.variables.len(),
            system.components.len(),
            system.shown,
            system.spec.step,
            binaries.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join(", ")
        );
        written.push(out.clone());
    }
    Ok(written)
}

/// One SSP file read for a container: what its FMUs are written from.
struct System {
    /// The SSP file, as shown to the user.
    shown: String,
    spec: Spec,
    /// The container's modelDescription.xml in FMI 2.0 and in FMI 3.0.
    xml2: String,
    xml3: String,
    /// The SSP archive's files.
    files: Vec<(String, Vec<u8>)>,
    /// The component FMUs' names among them.
    sources: Vec<String>,
    system_name: String,
    components: Vec<String>,
    /// Each component's FMI version and the binary folders its FMU has.
    carried: Vec<(String, FmiVersion, Vec<String>)>,
}

impl System {
    /// Reads `ssp` (`sim`: its simulation, already read); the internal step is `step`, else the
    /// step the SSD names for a fixed-step master (the OMSimulator annotation `cargo fmu` writes:
    /// `<oms:FixedStepMaster stepSize=...>`).
    fn read(ssp: &Path, sim: Simulation, step: Option<f64>) -> Result<System, String> {
        let shown = ssp.display().to_string();
        let files = entries(ssp)?;
        let mut archive = rustfmu_runner::ssp::Archive::open(ssp).map_err(|e| e.message)?;
        let system_name = archive.ssd.name.clone();
        let components: Vec<String> = archive.ssd.components.iter().map(|c| c.name.clone()).collect();
        // The components' descriptions as written, their FMI versions and binary folders.
        let mut xmls = Vec::new();
        let mut carried = Vec::new();
        for c in &components {
            let bytes = archive.fmu_bytes(c).map_err(|e| e.message)?;
            let xml = model_description_of(&bytes).map_err(|e| format!("{shown}: component '{c}': {e}"))?;
            let version = match md_reader::fmi_version(&xml) {
                Ok(v) if v.starts_with("3.") => FmiVersion::V3,
                _ => FmiVersion::V2,
            };
            let folders = platforms_of(&bytes).map_err(|e| format!("{shown}: component '{c}': {e}"))?;
            carried.push((c.clone(), version, folders));
            xmls.push((c.clone(), xml));
        }
        let ssd_text = files
            .iter()
            .find(|(n, _)| n == "SystemStructure.ssd")
            .map(|(_, b)| String::from_utf8_lossy(b).into_owned())
            .unwrap_or_default();
        let step = match step {
            Some(h) => h,
            None => fixed_step_of(&ssd_text).ok_or_else(|| {
                format!("{shown}: the SSD names no fixed step size (oms:FixedStepMaster stepSize): give the container's internal step with --step")
            })?,
        };
        let spec = Spec::new(&sim, step).map_err(|e| e.message)?;
        let experiment = (archive.ssd.start_time, archive.ssd.stop_time);
        let xml2 = spec.model_description(&sim, &system_name, &xmls, experiment);
        let xml3 = spec.model_description3(&sim, &system_name, &xmls, experiment);
        let sources = archive
            .ssd
            .components
            .iter()
            .map(|c| c.source.trim_start_matches("./").to_owned())
            .collect();
        Ok(System {
            shown,
            spec,
            xml2,
            xml3,
            files,
            sources,
            system_name,
            components,
            carried,
        })
    }

    /// Why the system cannot run on target `t`: a component without a binary for it (in its
    /// own version's folder); `None` if it can.
    fn lacking(&self, t: &str) -> Option<String> {
        let p = match crate::target::platform(t) {
            Ok(p) => p,
            Err(e) => return Some(e),
        };
        self.carried.iter().find_map(|(c, v, folders)| match p.folder(*v) {
            Ok(f) if folders.contains(&f) => None,
            Ok(f) => Some(format!(
                "component '{c}' has no {f} binary (it has: {})",
                folders.join(", ")
            )),
            Err(e) => Some(format!("component '{c}': {e}")),
        })
    }

    fn has_fmi2_component(&self) -> bool {
        self.carried.iter().any(|(_, v, _)| *v == FmiVersion::V2)
    }
}

/// The FMI 3.0 twin of `ssp`, which `cargo fmu build` writes beside every SSP file of FMI 2.0
/// FMUs (`fmi3/<file>.ssp`: the same system of the same crates' FMI 3.0 FMUs), read, if there is
/// one and it is the same system as `main` (the container's variables alike but for the FMI 3.0
/// names of the types): the FMI 3.0 container is made of it. None (and a line saying why) if it
/// differs.
fn fmi3_twin(ssp: &Path, main: &System) -> Result<Option<System>, String> {
    let Some(file) = ssp.file_name() else {
        return Ok(None);
    };
    let path = ssp.with_file_name("fmi3").join(file);
    if !path.is_file() {
        return Ok(None);
    }
    let sim = Simulation::from_ssp(&path).map_err(|e| e.message)?;
    let twin = System::read(&path, sim, Some(main.spec.step))?;
    let key = |s: &System| -> Vec<(String, String, String, String, Option<String>)> {
        s.spec
            .variables
            .iter()
            .map(|e| {
                (
                    e.name.clone(),
                    e.ty.clone(),
                    e.causality.clone(),
                    e.variability.clone(),
                    e.start.clone(),
                )
            })
            .collect()
    };
    if twin.has_fmi2_component() || twin.spec.model_identifier != main.spec.model_identifier || key(&twin) != key(main)
    {
        eprintln!(
            "fmu: {} is not the same system of FMI 3.0 FMUs as {} (another name, an FMI 2.0 component or other \
             variables): the FMI 3.0 container is made of {}'s components",
            twin.shown, main.shown, main.shown
        );
        return Ok(None);
    }
    eprintln!(
        "fmu: the FMI 3.0 container is made of {}, the same system of FMI 3.0 FMUs (FMI 2.0 names no folder \
         for some of their platforms, aarch64 Linux)",
        twin.shown
    );
    Ok(Some(twin))
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
