//! `fmu-build`: builds every FMU of the workspace in release mode, writes its
//! modelDescription.xml (also into `modelDescription/`, for review), packages
//! `target/fmu/<modelIdentifier>.fmu`, and validates what it packaged; then writes the SSP
//! files of the systems the workspace's systems files describe (`fmu_build::ssp`).

mod docs;
mod package;
mod validate;

use clap::{Parser, Subcommand};
use fmu_build::{ssp, systems};
use rustfmu::fmi2::FmuEntry;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

#[derive(Parser)]
#[command(version, about = "Build, describe, package and validate the workspace's FMUs")]
struct Cli {
    #[command(subcommand)]
    command: Option<Cmd>,
}

#[derive(Subcommand)]
enum Cmd {
    /// Build every FMU (release), refresh modelDescription/, package target/fmu/*.fmu and
    /// validate them (the default); with no names, also write the SSP files of the composed systems.
    Build {
        /// Only these FMUs (model identifiers); all when none is given.
        names: Vec<String>,
        /// Also run fmpy's validator with this Python (needs `fmpy` installed there).
        #[arg(long)]
        python: Option<PathBuf>,
    },
    /// Write modelDescription/<id>.xml from the model declarations.
    Xml {
        /// Write nothing; fail if a committed file differs from the generated one.
        #[arg(long)]
        check: bool,
    },
    /// Write <fmu-dir>/<system>.ssp for the composed systems (needs the packaged FMUs).
    Ssp {
        /// Systems file; default: those the workspace's Cargo.toml names in
        /// `[workspace.metadata.fmu] systems`.
        #[arg(long)]
        systems: Option<PathBuf>,
        /// Where the packaged FMUs are, and the SSP files go; default: target/fmu.
        #[arg(long)]
        fmu_dir: Option<PathBuf>,
    },
    /// Validate packaged FMUs: archive layout, description, binary symbols, a smoke run.
    Validate {
        /// FMU files; all of target/fmu when none is given.
        fmus: Vec<PathBuf>,
        /// Also run fmpy's validator with this Python (needs `fmpy` installed there).
        #[arg(long)]
        python: Option<PathBuf>,
    },
}

pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("fmu-build lives in the workspace")
        .to_path_buf()
}

pub fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_root().join("target"))
}

fn fmu_dir() -> PathBuf {
    target_dir().join("fmu")
}

fn select(names: &[String]) -> Result<Vec<&'static FmuEntry>, String> {
    let all = rustfmu::fmus::ALL;
    if names.is_empty() {
        return Ok(all.iter().collect());
    }
    names
        .iter()
        .map(|n| {
            all.iter().find(|e| e.info.identifier == n).ok_or_else(|| {
                let known: Vec<_> = all.iter().map(|e| e.info.identifier).collect();
                format!("no FMU named '{n}' (known: {})", known.join(", "))
            })
        })
        .collect()
}

fn cargo_build(entries: &[&FmuEntry]) -> Result<(), String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(&cargo);
    cmd.current_dir(workspace_root()).args(["build", "--release"]);
    for e in entries {
        cmd.args(["-p", e.package]);
    }
    eprintln!(
        "fmu-build: {cargo} build --release {}",
        entries
            .iter()
            .map(|e| format!("-p {}", e.package))
            .collect::<Vec<_>>()
            .join(" ")
    );
    let status = cmd.status().map_err(|e| format!("cannot run {cargo}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("cargo build failed ({status})"))
    }
}

fn write_xml(check: bool) -> Result<(), String> {
    let dir = workspace_root().join("modelDescription");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut stale = Vec::new();
    for e in rustfmu::fmus::ALL {
        let xml = (e.model_description)().map_err(|m| format!("{}: {m}", e.info.identifier))?;
        let path = dir.join(format!("{}.xml", e.info.identifier));
        let old = std::fs::read_to_string(&path).unwrap_or_default();
        if old != xml {
            if check {
                stale.push(path.display().to_string());
            } else {
                std::fs::write(&path, xml).map_err(|err| format!("{}: {err}", path.display()))?;
                eprintln!("fmu-build: wrote {}", path.display());
            }
        }
    }
    if stale.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "these files differ from what the declarations generate: {}; run `cargo run -p fmu-build -- xml`",
            stale.join(", ")
        ))
    }
}

fn build(names: &[String], python: Option<&Path>) -> Result<(), String> {
    let entries = select(names)?;
    cargo_build(&entries)?;
    write_xml(false)?;
    std::fs::create_dir_all(fmu_dir()).map_err(|e| format!("{}: {e}", fmu_dir().display()))?;
    let mut built = Vec::new();
    for e in &entries {
        let so = target_dir().join("release").join(format!("lib{}.so", e.lib_name));
        let out = fmu_dir().join(format!("{}.fmu", e.info.identifier));
        package::package(e, &so, &out)?;
        eprintln!("fmu-build: packaged {}", out.display());
        built.push(out);
    }
    validate_all(&built, python)?;
    if names.is_empty() {
        write_ssp(None, None)?;
    }
    Ok(())
}

/// Writes the SSP files of the systems in `systems_file` (default: the workspace's systems
/// files) from the FMUs packaged in `fmu_dir` (default: target/fmu), into the same folder.
fn write_ssp(systems_file: Option<&Path>, fmu_dir: Option<&Path>) -> Result<(), String> {
    let files = match systems_file {
        Some(f) => vec![f.to_path_buf()],
        None => systems::workspace_files(&workspace_root())?,
    };
    let dir = fmu_dir.map_or_else(self::fmu_dir, Path::to_path_buf);
    for file in files {
        let systems = systems::Systems::load(&file)?;
        for path in ssp::write_all(&systems, &dir, &dir)? {
            eprintln!("fmu-build: wrote {}", path.display());
        }
    }
    Ok(())
}

fn validate_all(fmus: &[PathBuf], python: Option<&Path>) -> Result<(), String> {
    let mut failures = Vec::new();
    for f in fmus {
        let mut problems = validate::validate(f);
        if problems.is_empty()
            && let Some(py) = python
        {
            problems.extend(validate::fmpy_validate(py, f));
        }
        if problems.is_empty() {
            eprintln!("fmu-build: {} is valid", f.display());
        } else {
            for p in &problems {
                eprintln!("fmu-build: {}: {p}", f.display());
            }
            failures.push(f.display().to_string());
        }
    }
    if failures.is_empty() {
        Ok(())
    } else {
        Err(format!("invalid: {}", failures.join(", ")))
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command.unwrap_or(Cmd::Build {
        names: vec![],
        python: None,
    }) {
        Cmd::Build { names, python } => build(&names, python.as_deref()),
        Cmd::Xml { check } => write_xml(check),
        Cmd::Ssp { systems, fmu_dir } => write_ssp(systems.as_deref(), fmu_dir.as_deref()),
        Cmd::Validate { fmus, python } => {
            let fmus = if fmus.is_empty() {
                rustfmu::fmus::ALL
                    .iter()
                    .map(|e| fmu_dir().join(format!("{}.fmu", e.info.identifier)))
                    .collect()
            } else {
                fmus
            };
            validate_all(&fmus, python.as_deref())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("fmu-build: error: {e}");
            ExitCode::FAILURE
        }
    }
}
