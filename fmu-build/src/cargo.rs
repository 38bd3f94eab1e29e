//! Which crates are FMUs, and building them: `cargo metadata` and `cargo build`.
//!
//! An FMU crate is any package with a `cdylib` library that depends on `rustfmu` (under any
//! name in its Cargo.toml). Its `[package.metadata.fmu]` may name `documentation` (an HTML
//! fragment for documentation/index.html) and `resources` (a folder copied to resources/;
//! default `resources` when it exists) and `fmi-versions` (which FMI versions `cargo fmu build`
//! makes of it: `["2.0", "3.0"]`, the default, or one of them) and `targets` (the Rust target
//! triples whose binaries go into each FMU; default: the host's only) and `example` (`true`: an
//! example, not a product: `cargo fmu build --examples-on-host` builds it for the host only). The workspace's `[workspace.metadata.fmu]` may name
//! `model-descriptions` (a folder that keeps a committed copy of every description) and
//! `systems` (files of composed systems to write as SSP).

use cargo_metadata::{Metadata, MetadataCommand, Package};
use rustfmu::description::FmiVersion;
use std::collections::BTreeSet;
use std::io::{BufRead, IsTerminal, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};

/// One crate to build into an FMU.
#[derive(Debug, Clone)]
pub struct FmuCrate {
    pub package: String,
    pub manifest_dir: PathBuf,
    /// The library target's name (`lib<name>.so` in the target folder).
    pub lib_name: String,
    pub documentation: Option<PathBuf>,
    pub resources: Option<PathBuf>,
    /// `[package.metadata.fmu] fmi-versions`: `None` when not given (both versions), else the
    /// versions named, or what is wrong with the entry.
    pub fmi_versions: Option<Result<BTreeSet<FmiVersion>, String>>,
    /// `[package.metadata.fmu] targets`: `None` when not given (the host only), else the
    /// triples named, or what is wrong with the entry.
    pub targets: Option<Result<Vec<String>, String>>,
    /// `[package.metadata.fmu] documentation-start = { name = value, .. }`: start values the
    /// documentation page's run of the default experiment sets (a model whose own start values
    /// are an equilibrium would plot flat lines), or what is wrong with the entry.
    pub documentation_start: Result<Vec<(String, f64)>, String>,
    /// `[package.metadata.fmu] example = true`: an example (the Reference-FMU re-makes), which
    /// `cargo fmu build --examples-on-host` builds for the host only.
    pub example: bool,
}

/// `documentation-start = { alpha1_0 = 0.1, on = true }`: variable names and numbers (a Boolean
/// as true or false).
pub fn parse_documentation_start(value: &serde_json::Value) -> Result<Vec<(String, f64)>, String> {
    let table = value
        .as_object()
        .ok_or("documentation-start must be a table of start values such as { alpha1_0 = 0.1 }")?;
    table
        .iter()
        .map(|(name, v)| {
            let x = v
                .as_f64()
                .or_else(|| v.as_bool().map(|b| b as u8 as f64))
                .ok_or_else(|| format!("documentation-start: {name} = {v} is not a number or a Boolean"))?;
            Ok((name.clone(), x))
        })
        .collect()
}

/// `"2.0"`, `"3.0"` (also `"2"`, `"3"`) as an FMI version.
pub fn parse_fmi_version(text: &str) -> Result<FmiVersion, String> {
    match text.trim() {
        "2" | "2.0" => Ok(FmiVersion::V2),
        "3" | "3.0" => Ok(FmiVersion::V3),
        other => Err(format!(
            "'{other}' is no FMI version this tool builds (\"2.0\" or \"3.0\")"
        )),
    }
}

/// `fmi-versions = ["2.0", "3.0"]` of `[package.metadata.fmu]`.
pub fn parse_fmi_versions(value: &serde_json::Value) -> Result<BTreeSet<FmiVersion>, String> {
    let items = value
        .as_array()
        .ok_or("fmi-versions must be a list such as [\"2.0\", \"3.0\"]")?;
    let mut out = BTreeSet::new();
    for item in items {
        let text = item
            .as_str()
            .ok_or_else(|| format!("fmi-versions: {item} is not a text such as \"3.0\""))?;
        out.insert(parse_fmi_version(text).map_err(|e| format!("fmi-versions: {e}"))?);
    }
    if out.is_empty() {
        return Err("fmi-versions is empty: name at least one of \"2.0\", \"3.0\"".into());
    }
    Ok(out)
}

/// What `cargo metadata` says about the workspace.
#[derive(Debug, Clone)]
pub struct Workspace {
    pub root: PathBuf,
    pub target_dir: PathBuf,
    /// `[workspace.metadata.fmu]`, if any.
    pub fmu_metadata: serde_json::Value,
    pub crates: Vec<FmuCrate>,
    /// The package the manifest path names, when it is not a virtual manifest.
    pub root_package: Option<String>,
}

/// A cdylib that depends on rustfmu, unless its `[package.metadata.fmu] model = false` says it
/// exports no model (the container FMUs' binary, which uses rustfmu's ABI types only).
fn is_fmu_crate(p: &Package) -> bool {
    let not_a_model = p
        .metadata
        .get("fmu")
        .and_then(|m| m.get("model"))
        .is_some_and(|v| v == &serde_json::Value::Bool(false));
    !not_a_model
        && p.dependencies.iter().any(|d| d.name == "rustfmu")
        && p.targets
            .iter()
            .any(|t| t.crate_types.iter().any(|c| c.to_string() == "cdylib"))
}

fn fmu_crate(p: &Package) -> FmuCrate {
    let dir = p
        .manifest_path
        .parent()
        .map(|d| d.as_std_path().to_path_buf())
        .unwrap_or_default();
    let meta = p.metadata.get("fmu");
    let path_of = |key: &str| {
        meta.and_then(|m| m.get(key))
            .and_then(|v| v.as_str())
            .map(|s| dir.join(s))
    };
    let resources = path_of("resources").or_else(|| Some(dir.join("resources")).filter(|d| d.is_dir()));
    let lib = p
        .targets
        .iter()
        .find(|t| t.crate_types.iter().any(|c| c.to_string() == "cdylib"))
        .expect("checked by is_fmu_crate");
    FmuCrate {
        package: p.name.to_string(),
        manifest_dir: dir.clone(),
        lib_name: lib.name.replace('-', "_"),
        documentation: path_of("documentation"),
        resources,
        fmi_versions: meta.and_then(|m| m.get("fmi-versions")).map(parse_fmi_versions),
        targets: meta.and_then(|m| m.get("targets")).map(crate::target::parse_targets),
        documentation_start: meta
            .and_then(|m| m.get("documentation-start"))
            .map_or(Ok(vec![]), parse_documentation_start),
        example: meta
            .and_then(|m| m.get("example"))
            .is_some_and(|v| v == &serde_json::Value::Bool(true)),
    }
}

pub fn workspace(manifest_path: Option<&Path>) -> Result<Workspace, String> {
    let mut cmd = MetadataCommand::new();
    cmd.no_deps();
    if let Some(p) = manifest_path {
        cmd.manifest_path(p);
    }
    let m: Metadata = cmd.exec().map_err(|e| format!("cargo metadata: {e}"))?;
    let members: Vec<&Package> = m.workspace_packages();
    let fmu_metadata = m
        .workspace_metadata
        .get("fmu")
        .cloned()
        .unwrap_or(serde_json::Value::Null);
    // `[workspace.metadata.fmu] targets`: the targets of every crate that names none itself.
    let workspace_targets = fmu_metadata
        .get("targets")
        .map(|t| crate::target::parse_targets(t).map_err(|e| format!("[workspace.metadata.fmu] {e}")));
    let crates = members
        .iter()
        .filter(|p| is_fmu_crate(p))
        .map(|p| {
            let mut c = fmu_crate(p);
            if c.targets.is_none() {
                c.targets = workspace_targets.clone();
            }
            c
        })
        .collect();
    Ok(Workspace {
        root: m.workspace_root.as_std_path().to_path_buf(),
        target_dir: m.target_directory.as_std_path().to_path_buf(),
        fmu_metadata,
        crates,
        root_package: m.root_package().map(|p| p.name.to_string()),
    })
}

impl Workspace {
    /// The crates to build: those named, else the manifest's own package, else (a virtual
    /// manifest, or `all`) every FMU crate of the workspace.
    pub fn select(&self, names: &[String], all: bool) -> Result<Vec<FmuCrate>, String> {
        let known = || {
            self.crates
                .iter()
                .map(|c| c.package.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        if !names.is_empty() {
            return names
                .iter()
                .map(|n| {
                    self.crates.iter().find(|c| c.package == *n).cloned().ok_or_else(|| {
                        format!(
                            "package '{n}' is not an FMU crate of this workspace (a cdylib depending on rustfmu); FMU crates: {}",
                            known()
                        )
                    })
                })
                .collect();
        }
        if !all && let Some(root) = &self.root_package {
            return match self.crates.iter().find(|c| c.package == *root) {
                Some(c) => Ok(vec![c.clone()]),
                None => Err(format!(
                    "package '{root}' is not an FMU crate: it needs `crate-type = [\"cdylib\"]` in [lib] and a dependency on rustfmu \
                     (FMU crates in this workspace: {})",
                    if self.crates.is_empty() { "none".into() } else { known() }
                )),
            };
        }
        if self.crates.is_empty() {
            return Err("this workspace has no FMU crate (a cdylib depending on rustfmu)".into());
        }
        Ok(self.crates.clone())
    }

    /// A path from `[workspace.metadata.fmu]`, relative to the workspace root.
    pub fn metadata_path(&self, key: &str) -> Option<PathBuf> {
        self.fmu_metadata
            .get(key)
            .and_then(|v| v.as_str())
            .map(|s| self.root.join(s))
    }

    pub fn metadata_paths(&self, key: &str) -> Vec<PathBuf> {
        match self.fmu_metadata.get(key) {
            Some(serde_json::Value::String(s)) => vec![self.root.join(s)],
            Some(serde_json::Value::Array(a)) => {
                a.iter().filter_map(|v| v.as_str()).map(|s| self.root.join(s)).collect()
            }
            _ => vec![],
        }
    }

    pub fn fmu_dir(&self) -> PathBuf {
        self.target_dir.join("fmu")
    }

    /// Where `cargo fmu build` keeps a copy of each built library of the host, per FMI version:
    /// cargo's own `target/release/lib<name>.so` is overwritten by the build of the other version.
    pub fn built_library(&self, c: &FmuCrate, version: FmiVersion) -> PathBuf {
        let file = self.library(c);
        let name = file.file_name().expect("a file name").to_owned();
        self.target_dir
            .join("fmu-build")
            .join(version_folder(version))
            .join(name)
    }

    /// A copy the last `cargo fmu build` kept of a crate's library for `version`, of any target
    /// (the host's first): every target's carries the same description.
    pub fn any_built_library(&self, c: &FmuCrate, version: FmiVersion) -> Option<PathBuf> {
        let host = self.built_library(c, version);
        if host.is_file() {
            return Some(host);
        }
        let dir = self.target_dir.join("fmu-build").join(version_folder(version));
        let mut triples: Vec<String> = std::fs::read_dir(&dir)
            .ok()?
            .filter_map(|e| e.ok())
            .filter(|e| e.file_type().is_ok_and(|t| t.is_dir()))
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        triples.sort();
        triples.into_iter().find_map(|t| {
            let file = crate::target::platform(&t).ok()?.cdylib_file(&c.lib_name);
            let path = dir.join(&t).join(file);
            path.is_file().then_some(path)
        })
    }

    /// [`Workspace::built_library`] of any target: the host's where it always was, another
    /// target's in `target/fmu-build/fmi{2,3}/<triple>/`.
    pub fn built_library_for(
        &self,
        c: &FmuCrate,
        version: FmiVersion,
        triple: &str,
        host: &str,
    ) -> Result<PathBuf, String> {
        if triple == host {
            return Ok(self.built_library(c, version));
        }
        let file = crate::target::platform(triple)?.cdylib_file(&c.lib_name);
        Ok(self
            .target_dir
            .join("fmu-build")
            .join(version_folder(version))
            .join(triple)
            .join(file))
    }

    /// Whether the workspace's manifest defines `[profile.fmu-release]` itself.
    pub fn defines_fmu_profile(&self) -> bool {
        let manifest = self.root.join("Cargo.toml");
        std::fs::read_to_string(&manifest)
            .ok()
            .and_then(|t| t.parse::<toml::Table>().ok())
            .is_some_and(|t| t.get("profile").and_then(|p| p.get(FMU_PROFILE)).is_some())
    }

    /// The built library of a crate ([`FMU_PROFILE`], host target).
    pub fn library(&self, c: &FmuCrate) -> PathBuf {
        let (prefix, ext) = match std::env::consts::OS {
            "windows" => ("", "dll"),
            "macos" => ("lib", "dylib"),
            _ => ("lib", "so"),
        };
        self.target_dir
            .join(FMU_PROFILE)
            .join(format!("{prefix}{}.{ext}", c.lib_name))
    }

    /// The cargo target folder of a target's FMU builds: the workspace's own for the host, one of
    /// its own for every other (`target/fmu-build/cargo/<triple>/`), so that the targets build
    /// side by side (cargo locks its folder for one invocation at a time).
    pub fn cargo_dir(&self, triple: &str, host: &str) -> PathBuf {
        if triple == host {
            self.target_dir.clone()
        } else {
            self.target_dir.join("fmu-build").join("cargo").join(triple)
        }
    }

    /// The library cargo builds of a crate for a target: the host's in `target/fmu-release/`,
    /// another's (`--target <triple>`) in `target/fmu-build/cargo/<triple>/<triple>/fmu-release/`.
    pub fn library_for(&self, c: &FmuCrate, triple: &str, host: &str) -> Result<PathBuf, String> {
        if triple == host {
            return Ok(self.library(c));
        }
        let file = crate::target::platform(triple)?.cdylib_file(&c.lib_name);
        // cargo-zigbuild's `x86_64-unknown-linux-gnu.2.17` builds into x86_64-unknown-linux-gnu/.
        let folder = crate::target::split_glibc(triple).0;
        Ok(self.cargo_dir(triple, host).join(folder).join(FMU_PROFILE).join(file))
    }
}

fn version_folder(version: FmiVersion) -> &'static str {
    match version {
        FmiVersion::V2 => "fmi2",
        FmiVersion::V3 => "fmi3",
    }
}

/// The cargo profile FMU binaries are built with: `release` without symbols and with whole-program
/// link-time optimisation, as FMU binaries are shipped. Measured on the Controller's Windows DLL
/// (`bash bench/binary-sizes.sh`, docs/platforms.md "Size"): release 2,394,642 bytes; `strip`
/// 1,860,608; with thin LTO 982,528; with fat LTO 805,888 (codegen-units 16, the default) or
/// 825,344 (codegen-units 1, slower to build too). Its own output folder (`target/fmu-release/`, and one cargo folder per
/// other target), so that the tests' `cargo build --release` units are not rebuilt by it and it is
/// not by them.
pub const FMU_PROFILE: &str = "fmu-release";

/// [`FMU_PROFILE`] where the workspace's manifest does not define it (then its own settings
/// are taken as they are). `panic` stays `unwind` (release's default): every C entry point
/// catches panics and turns them into an error status, which `panic = "abort"` would make a
/// crash of the importer.
pub const FMU_PROFILE_SETTINGS: &[&str] = &["inherits=\"release\"", "strip=true", "lto=\"fat\"", "panic=\"unwind\""];

/// `cargo rustc --profile fmu-release --lib --crate-type cdylib -p ...` of each of `crates` for
/// one target (`None`: the host; `Some(triple)`: `--target <triple>`, with the linker
/// [`crate::target::build_env`] names), in that target's cargo folder
/// ([`Workspace::cargo_dir`]): the library of each crate, one binary of both FMI versions
/// (`export_fmu!`). With `zig`, the invocations are `cargo-zigbuild rustc` (macOS, Linux with a
/// glibc version), which links with zig.
///
/// `--crate-type cdylib`: an FMU crate is `["cdylib", "rlib"]` (its tests use it as a library), and
/// rustc runs no link-time optimisation for a build that also emits an rlib, so the profile's
/// `lto` would do nothing. Without it nothing removed the Rust code no FMI function reaches from
/// the Windows DLL (GNU ld's `--gc-sections` removed no section of it) or from the macOS dylib
/// (zig ignores the export list, so every global symbol is a root): the DCMotor's DLL was
/// 2,043,103 bytes, 713,071 with `--crate-type cdylib` (docs/platforms.md). cargo takes
/// `--crate-type` for one package and one target at a time: one invocation per crate, the
/// dependencies built by the first.
pub fn build(
    ws: &Workspace,
    crates: &[FmuCrate],
    triple: Option<&str>,
    host: &str,
    zig: Option<&crate::target::Zig>,
    job: &mut crate::progress::Job,
) -> Result<(), String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut common: Vec<String> = vec!["rustc".into(), "--profile".into(), FMU_PROFILE.into()];
    if !ws.defines_fmu_profile() {
        for setting in FMU_PROFILE_SETTINGS {
            common.extend(["--config".into(), format!("profile.{FMU_PROFILE}.{setting}")]);
        }
    }
    let mut env = vec![(
        "CARGO_TARGET_DIR".to_string(),
        ws.cargo_dir(triple.unwrap_or(host), host).display().to_string(),
    )];
    if let Some(t) = triple {
        common.extend(["--target".into(), t.to_string()]);
        env.extend(crate::target::build_env(t));
    }
    common.extend(["--lib".into(), "--crate-type".into(), "cdylib".into()]);
    let verbose = job.verbose();
    if !verbose {
        // cargo's own progress line, read for the display (cargo draws it only on a terminal
        // unless told).
        env.extend([
            ("CARGO_TERM_PROGRESS_WHEN".to_string(), "always".to_string()),
            ("CARGO_TERM_PROGRESS_WIDTH".to_string(), "100".to_string()),
            ("CARGO_TERM_COLOR".to_string(), "never".to_string()),
        ]);
    }
    for c in crates {
        let mut args = common.clone();
        args.extend(["-p".into(), c.package.clone()]);
        let mut cmd = match zig {
            None => Command::new(&cargo),
            Some(z) => {
                let mut cmd = Command::new(&z.cargo_zigbuild);
                if let Some(path) = z.path() {
                    cmd.env("PATH", path);
                }
                cmd
            }
        };
        let shown = format!("{} {}", cmd.get_program().to_string_lossy(), args.join(" "));
        if verbose {
            eprintln!("fmu: {shown}");
        }
        cmd.current_dir(&ws.root).args(&args).envs(env.iter().cloned());
        let program = cmd.get_program().to_string_lossy().into_owned();
        let cannot_run = |e: std::io::Error| format!("cannot run {program}: {e}");
        let macos = zig.is_some() && triple.is_some_and(|t| t.contains("-apple-darwin"));
        let started = std::time::Instant::now();
        job.start(&c.package);
        let status = if !verbose {
            // cargo's messages kept, shown only if the build fails; its progress line read.
            let mut child = cmd.stderr(Stdio::piped()).spawn().map_err(cannot_run)?;
            let mut from = child.stderr.take().expect("stderr is piped");
            let kept = read_cargo(&mut from, |done, of, names| job.units(&c.package, done, of, names));
            let status = child.wait().map_err(cannot_run)?;
            let mut shown_lines = Vec::new();
            let _ = without_xcrun_warning(&mut std::io::Cursor::new(&kept), &mut shown_lines);
            let text = String::from_utf8_lossy(&shown_lines);
            if !status.success() {
                job.println(&format!("fmu: {shown}\n{}", text.trim_end()));
            } else {
                let warnings = text
                    .lines()
                    .filter(|l| l.starts_with("warning") && !l.contains(" generated "))
                    .count();
                if warnings > 0 {
                    job.println(&format!(
                        "fmu: {} for {}: cargo printed {warnings} warning{} (`-v` shows cargo's messages)",
                        c.package,
                        job.target,
                        if warnings == 1 { "" } else { "s" }
                    ));
                }
            }
            status
        } else if macos {
            // rustc's xcrun warning means nothing here: cargo's messages through a filter.
            if std::io::stderr().is_terminal() && std::env::var_os("CARGO_TERM_COLOR").is_none() {
                cmd.env("CARGO_TERM_COLOR", "always");
            }
            let mut child = cmd.stderr(Stdio::piped()).spawn().map_err(cannot_run)?;
            let mut from = std::io::BufReader::new(child.stderr.take().expect("stderr is piped"));
            let left_out = without_xcrun_warning(&mut from, &mut std::io::stderr()).unwrap_or_else(|_| {
                // Our stderr failed: read the rest, so that cargo never waits on a full pipe.
                let _ = std::io::copy(&mut from, &mut std::io::sink());
                0
            });
            if left_out > 0 && !XCRUN_EXPLAINED.swap(true, Ordering::Relaxed) {
                eprintln!("{XCRUN_NOTE}");
            }
            child.wait().map_err(cannot_run)?
        } else {
            cmd.status().map_err(cannot_run)?
        };
        if !status.success() {
            let on = triple.map(|t| format!(" for {t}")).unwrap_or_default();
            return Err(format!("cargo rustc of {}{on} failed ({status})", c.package));
        }
        job.crate_done(&c.package, started.elapsed().as_secs_f64());
    }
    Ok(())
}

/// Reads cargo's stderr to its end: its progress lines (`\r`-drawn) go to `progress` as units
/// done, units in all and the names being compiled; every other line is returned.
fn read_cargo(from: &mut impl Read, mut progress: impl FnMut(usize, usize, &str)) -> Vec<u8> {
    let mut kept = Vec::new();
    let mut segment = Vec::new();
    let mut buf = [0u8; 8192];
    let mut end_segment = |segment: &mut Vec<u8>, newline: bool, kept: &mut Vec<u8>| {
        let text = plain(segment);
        match crate::progress::cargo_progress(&text) {
            Some((done, of, names)) => progress(done, of, &names),
            None if newline || !text.trim().is_empty() => {
                kept.extend_from_slice(segment);
                kept.push(b'\n');
            }
            None => {}
        }
        segment.clear();
    };
    loop {
        let n = match from.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => n,
        };
        for &b in &buf[..n] {
            match b {
                b'\n' => end_segment(&mut segment, true, &mut kept),
                b'\r' => end_segment(&mut segment, false, &mut kept),
                _ => segment.push(b),
            }
        }
    }
    if !segment.is_empty() {
        end_segment(&mut segment, true, &mut kept);
    }
    kept
}

/// [`build`] of each target's crates (`jobs`: a target and its crates), every target in a cargo
/// folder of its own, as many side by side as the machine has cores: a target's build is a chain
/// of `cargo rustc` invocations, one per crate, whose last step (the link-time optimisation of the
/// whole library) runs on one core. The host's target (no `--target`) where a job's triple is the
/// host; `zig` links those [`crate::target::uses_zig`] names. Shows the progress
/// ([`crate::progress`]) and ends with a summary of `what` was built (the first error otherwise).
pub fn build_targets(
    ws: &Workspace,
    jobs: &[(String, Vec<FmuCrate>)],
    host: &str,
    zig: Option<&crate::target::Zig>,
    verbose: bool,
    what: &str,
) -> Result<(), String> {
    let progress = crate::progress::Progress::new(verbose, jobs.iter().map(|(_, c)| c.len()).sum());
    let workers = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(jobs.len())
        .max(1);
    let next = std::sync::atomic::AtomicUsize::new(0);
    let outcomes: std::sync::Mutex<Vec<(usize, Result<(), String>)>> = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| {
                loop {
                    let j = next.fetch_add(1, Ordering::SeqCst);
                    let Some((t, crates)) = jobs.get(j) else { break };
                    let triple = (t != host).then_some(t.as_str());
                    let linker = if crate::target::uses_zig(t, host) { zig } else { None };
                    let mut job = progress.job(t, crates.len());
                    let outcome = build(ws, crates, triple, host, linker, &mut job);
                    job.finish();
                    outcomes.lock().unwrap_or_else(|e| e.into_inner()).push((j, outcome));
                }
            });
        }
    });
    let mut outcomes = outcomes.into_inner().unwrap_or_else(|e| e.into_inner());
    outcomes.sort_by_key(|(j, _)| *j);
    if let Some((_, Err(e))) = outcomes.iter().find(|(_, o)| o.is_err()) {
        return Err(e.clone());
    }
    progress.summary(what);
    Ok(())
}

/// The start of rustc's warning when it cannot ask `xcrun` for Apple's SDK, which it prints at
/// every link of a macOS library on a machine without Xcode (and cargo again for every library it
/// did not rebuild): ``warning: invoking `"xcrun" "--sdk" "macosx" "--show-sdk-path"` to find
/// MacOSX.sdk failed: No such file or directory (os error 2)``, with notes and help below it.
const XCRUN_WARNING: &str =
    "warning: invoking `\"xcrun\" \"--sdk\" \"macosx\" \"--show-sdk-path\"` to find MacOSX.sdk failed";

/// What `cargo fmu` says, once, in place of rustc's xcrun warning.
const XCRUN_NOTE: &str = "fmu: rustc's warning that `xcrun --sdk macosx --show-sdk-path` failed was left out of the macOS \
                          builds: it looks for Apple's SDK, which zig does not need to link a macOS library on a machine \
                          that is not a Mac (zig carries the stubs of macOS's system libraries); `cargo fmu validate` \
                          checks every macOS binary (docs/platforms.md)";

/// Whether [`XCRUN_NOTE`] was printed.
static XCRUN_EXPLAINED: AtomicBool = AtomicBool::new(false);

/// A line of cargo's output without its colours (ANSI escape sequences `ESC [ ... letter`).
fn plain(line: &[u8]) -> String {
    let text = String::from_utf8_lossy(line);
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            for d in chars.by_ref() {
                if d.is_ascii_alphabetic() {
                    break;
                }
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// Copies cargo's messages from `from` to `to`, line by line, leaving out rustc's xcrun warning
/// ([`XCRUN_WARNING`], its indented notes and the empty line that ends it) and cargo's
/// "`crate` (lib) generated 1 warning" after it when that warning was the only one. Every other
/// line, warnings included, is copied as it is. Returns how many warnings it left out.
fn without_xcrun_warning(from: &mut impl BufRead, to: &mut impl Write) -> std::io::Result<usize> {
    // Where a line is: in the warning, or right after an empty line of it (the empty line that
    // ends it, or one between paragraphs of a help, whose lines are indented by 10 spaces, as
    // "  = help: ", where cargo's own lines are indented by at most 7).
    #[derive(PartialEq)]
    enum At {
        Outside,
        Within,
        AfterEmpty,
    }
    let mut at = At::Outside;
    let mut left_out = 0;
    // Warnings left out since cargo's last "generated" line.
    let mut since_summary = 0;
    let mut line = Vec::new();
    loop {
        line.clear();
        if from.read_until(b'\n', &mut line)? == 0 {
            break;
        }
        let text = plain(&line);
        let indented = |n: usize| text.len() > n && text.bytes().take(n).all(|b| b == b' ');
        match at {
            At::Within if text.trim_end_matches(['\n', '\r']).is_empty() => {
                at = At::AfterEmpty;
                continue;
            }
            At::Within if text.starts_with(' ') => continue,
            At::AfterEmpty if indented(10) => {
                at = At::Within;
                continue;
            }
            _ => at = At::Outside,
        }
        if text.starts_with(XCRUN_WARNING) {
            at = At::Within;
            left_out += 1;
            since_summary += 1;
            continue;
        }
        if text.starts_with("warning: `") && text.contains(" generated ") {
            let only_it = since_summary > 0 && text.trim_end().ends_with(" generated 1 warning");
            since_summary = 0;
            if only_it {
                continue;
            }
        }
        to.write_all(&line)?;
        to.flush()?;
    }
    Ok(left_out)
}

/// Copies the library cargo just built (`target/fmu-release/lib<name>.so`) to
/// [`Workspace::built_library`] before the next build overwrites it. Removed first and copied,
/// never written through: cargo's file is a hard link to its own artifact.
pub fn keep_library(
    ws: &Workspace,
    c: &FmuCrate,
    version: FmiVersion,
    triple: &str,
    host: &str,
) -> Result<PathBuf, String> {
    let from = ws.library_for(c, triple, host)?;
    let to = ws.built_library_for(c, version, triple, host)?;
    let dir = to.parent().expect("a folder");
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let _ = std::fs::remove_file(&to);
    std::fs::copy(&from, &to).map_err(|e| format!("{} -> {}: {e}", from.display(), to.display()))?;
    Ok(to)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// rustc 1.95's warning as cargo prints it (coloured, as on a terminal, and plain), between
    /// other messages that stay.
    #[test]
    fn the_xcrun_warning_and_only_it_is_left_out() {
        let warning = "warning: invoking `\"xcrun\" \"--sdk\" \"macosx\" \"--show-sdk-path\"` to find MacOSX.sdk failed: \
                       No such file or directory (os error 2)\n  |\n  = note: the SDK is needed by the linker to know where \
                       to find symbols in system libraries and for embedding the SDK version in the final object file\n  = \
                       help: pass the path to the SDK using the SDKROOT environment variable\n  = help: the SDK can be \
                       downloaded and extracted from https://developer.apple.com/download/all/?q=xcode (requires an Apple \
                       ID).\n          \n          The full Xcode bundle should contain the SDK in \
                       Xcode.app/Contents/Developer/Platforms/MacOSX.platform/Developer/SDKs/MacOSX.sdk.\n\n";
        let coloured = warning.replacen("warning:", "\u{1b}[1m\u{1b}[33mwarning\u{1b}[0m\u{1b}[1m:", 1);
        let other = "warning: unused variable: `x`\n --> src/lib.rs:1:5\n  |\n1 | let x = 1;\n  |     ^\n\n";
        let input = format!(
            "   Compiling pendulum-fmu v0.1.0\n{warning}warning: `pendulum-fmu` (lib) generated 1 warning\n\
             {coloured}{other}warning: `dc-motor-fmu` (lib) generated 2 warnings\n\
             \u{1b}[1m\u{1b}[32m    Finished\u{1b}[0m `fmu-release` profile\n"
        );
        let mut out = Vec::new();
        let n = without_xcrun_warning(&mut input.as_bytes(), &mut out).unwrap();
        assert_eq!(n, 2);
        assert_eq!(
            String::from_utf8(out).unwrap(),
            format!(
                "   Compiling pendulum-fmu v0.1.0\n{other}warning: `dc-motor-fmu` (lib) generated 2 warnings\n\
                 \u{1b}[1m\u{1b}[32m    Finished\u{1b}[0m `fmu-release` profile\n"
            )
        );
        // Nothing to leave out: every byte as it came.
        let mut out = Vec::new();
        let text = format!("{other}warning: `x` (lib) generated 1 warning\nno newline at the end");
        assert_eq!(without_xcrun_warning(&mut text.as_bytes(), &mut out).unwrap(), 0);
        assert_eq!(out, text.as_bytes());
    }

    #[test]
    fn fmi_versions_are_read_from_the_metadata() {
        let both = parse_fmi_versions(&serde_json::json!(["2.0", "3.0"])).unwrap();
        assert_eq!(
            both.into_iter().collect::<Vec<_>>(),
            vec![FmiVersion::V2, FmiVersion::V3]
        );
        let three = parse_fmi_versions(&serde_json::json!(["3.0"])).unwrap();
        assert_eq!(three.into_iter().collect::<Vec<_>>(), vec![FmiVersion::V3]);
        crate::test_support::refuses_each(parse_fmi_versions, r#"["3.0", [], ["1.0"], [3]]"#);
    }
}
