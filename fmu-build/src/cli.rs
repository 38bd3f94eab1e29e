//! The command line shared by `cargo fmu` and `fmu-build`.

use crate::cargo::{self, Workspace};
use clap::{Parser, Subcommand};
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    version,
    about = "Build, package, validate, inspect and check FMI FMUs made with rustfmu"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Cmd>,
}

#[derive(Subcommand)]
enum Cmd {
    /// Write a new FMU crate: a first-order lag with an input, an output, a tunable time
    /// constant and a test, that builds into a valid FMU unchanged.
    New {
        /// Crate name (also the folder, and in CamelCase the model identifier).
        name: String,
        /// Where to create the crate folder (default: the current folder).
        #[arg(long)]
        path: Option<PathBuf>,
        /// The rustfmu checkout to depend on by path (default: the one this cargo-fmu was
        /// built from, if it still exists; else the crates.io version).
        #[arg(long)]
        rustfmu_path: Option<PathBuf>,
    },
    /// Build FMU crates (release) and package target/fmu/<modelIdentifier>.fmu, then validate.
    Build {
        /// Cargo.toml of the crate or workspace (default: the one cargo finds from here).
        #[arg(long)]
        manifest_path: Option<PathBuf>,
        /// Only these packages.
        #[arg(short = 'p', long = "package")]
        packages: Vec<String>,
        /// Every FMU crate of the workspace (the default for a virtual manifest).
        #[arg(long)]
        workspace: bool,
        /// Also run fmpy's validator with this Python (needs `fmpy` installed there).
        #[arg(long)]
        python: Option<PathBuf>,
    },
    /// Validate FMU files: archive layout, description, binary, a smoke run in a child process.
    Validate {
        fmus: Vec<PathBuf>,
        /// Also run fmpy's validator with this Python (needs `fmpy` installed there).
        #[arg(long)]
        python: Option<PathBuf>,
    },
    /// Describe an FMU file: version, interfaces, platforms, variables.
    Info { fmu: PathBuf },
    /// Run the black-box FMI 2.0 / FMI 3.0 conformance suite (by the file's fmiVersion) on an FMU file (ours or any
    /// other exporter's): every call in every state, bad arguments, FMU state, instances and
    /// threads, memory, random call sequences, a C host; each check in a child process, so an
    /// FMU that crashes or hangs is reported, not shared. Ends with `N passed, N failed, N skipped`.
    Check {
        fmu: Option<PathBuf>,
        /// Only checks whose name or group contains this text.
        #[arg(long)]
        filter: Option<String>,
        /// Longest a check may take, in seconds (default 600).
        #[arg(long)]
        timeout: Option<f64>,
        /// Random call sequences per FMU (default 2000).
        #[arg(long, default_value_t = 0)]
        random_sequences: u32,
        /// List the checks and exit.
        #[arg(long)]
        list: bool,
    },
    /// Compare (or with --write, refresh) the committed model descriptions of the workspace
    /// (`[workspace.metadata.fmu] model-descriptions`) with the packaged FMUs.
    Xml {
        /// Write the packaged descriptions into the folder instead of comparing.
        #[arg(long)]
        write: bool,
        #[arg(long)]
        manifest_path: Option<PathBuf>,
    },
    /// Write target/fmu/<system>.ssp for the composed systems of a systems file (default: the
    /// files in `[workspace.metadata.fmu] systems`), from the packaged FMUs.
    Ssp {
        /// A systems file (TOML); default: those the workspace names.
        #[arg(long)]
        systems: Option<PathBuf>,
        /// Where the FMUs are and the SSP files go (default: target/fmu).
        #[arg(long)]
        fmu_dir: Option<PathBuf>,
        #[arg(long)]
        manifest_path: Option<PathBuf>,
    },
    /// Internal: the smoke run of `validate`, in a child process.
    #[command(hide = true, name = "__smoke-run")]
    SmokeRun {
        library: PathBuf,
        guid: String,
        vrs: String,
    },
}

fn run(cmd: Cmd, tool: &str) -> Result<(), String> {
    match cmd {
        Cmd::New {
            name,
            path,
            rustfmu_path,
        } => {
            let dir = crate::new::create(&name, path.as_deref(), rustfmu_path.as_deref())?;
            eprintln!(
                "{tool}: created {} — next: `cd {}` and `cargo fmu build`",
                dir.display(),
                dir.display()
            );
            Ok(())
        }
        Cmd::Build {
            manifest_path,
            packages,
            workspace,
            python,
        } => build(manifest_path.as_deref(), &packages, workspace, python.as_deref()).map(|_| ()),
        Cmd::Validate { fmus, python } => validate_all(&fmus, python.as_deref()),
        Cmd::Check {
            fmu,
            filter,
            timeout,
            random_sequences,
            list,
        } => check(fmu.as_deref(), filter, timeout, random_sequences, list),
        Cmd::Info { fmu } => {
            print!("{}", crate::validate::info(&fmu)?);
            Ok(())
        }
        Cmd::Xml { write, manifest_path } => {
            let ws = cargo::workspace(manifest_path.as_deref())?;
            committed_descriptions(&ws, !write)
        }
        Cmd::Ssp {
            systems,
            fmu_dir,
            manifest_path,
        } => {
            let ws = cargo::workspace(manifest_path.as_deref())?;
            write_ssp(&ws, systems.as_deref(), fmu_dir.as_deref())
        }
        Cmd::SmokeRun { library, guid, vrs } => {
            let vrs: Vec<u32> = vrs
                .split(',')
                .filter(|s| !s.is_empty())
                .filter_map(|s| s.parse().ok())
                .collect();
            let problems = crate::validate::smoke_run(&library, &guid, &vrs);
            for p in &problems {
                println!("{p}");
            }
            if problems.is_empty() {
                Ok(())
            } else {
                Err(String::new())
            }
        }
    }
}

fn check(
    fmu: Option<&Path>,
    filter: Option<String>,
    timeout: Option<f64>,
    random_sequences: u32,
    list: bool,
) -> Result<(), String> {
    use fmi2_conformance::runner::{RunOptions, run_with};
    if list {
        for c in fmi2_conformance::checks::all_checks() {
            println!("{} / {}", c.group, c.name);
        }
        for c in fmi2_conformance::fmi3::checks::all_checks() {
            println!("FMI 3.0: {} / {}", c.group, c.name);
        }
        return Ok(());
    }
    let fmu = fmu.ok_or("which FMU? `cargo fmu check X.fmu`")?;
    let exe = std::env::current_exe().map_err(|e| format!("cannot find my own executable: {e}"))?;
    let mut opts = RunOptions::new(exe, vec![CHECK_WORKER.into()]);
    opts.filter = filter;
    opts.random_sequences = random_sequences;
    if let Some(t) = timeout {
        if !(t.is_finite() && t > 0.0) {
            return Err(format!("--timeout {t}: seconds > 0"));
        }
        opts.timeout = std::time::Duration::from_secs_f64(t);
    }
    if opts.selected().is_empty() && opts.selected_fmi3().is_empty() {
        return Err("no check matches the filter (`cargo fmu check --list` shows them)".into());
    }
    // Progress on stderr while it runs; the report on stdout.
    let report = run_with(fmu, &opts, &mut |c| eprintln!("{}", c.line()));
    println!("{report}");
    if report.success() { Ok(()) } else { Err(String::new()) }
}

/// The hidden subcommand a `check` child runs (fmi2_conformance::runner::worker_main).
const CHECK_WORKER: &str = "__check-worker";

/// Builds and packages the selected crates; for a whole workspace also refreshes the committed
/// descriptions named in `[workspace.metadata.fmu]`. Returns the packaged files.
pub fn build(
    manifest_path: Option<&Path>,
    packages: &[String],
    all: bool,
    python: Option<&Path>,
) -> Result<Vec<PathBuf>, String> {
    let ws = cargo::workspace(manifest_path)?;
    let crates = ws.select(packages, all)?;
    cargo::build(&ws, &crates)?;
    let mut built = Vec::new();
    for c in &crates {
        let p = crate::bundle::package(c, &ws.library(c), &ws.fmu_dir())?;
        eprintln!("fmu: packaged {}", p.fmu.display());
        built.push(p.fmu);
    }
    validate_all(&built, python)?;
    if all && packages.is_empty() {
        committed_descriptions(&ws, false)?;
        write_ssp(&ws, None, None)?;
    }
    Ok(built)
}

/// The SSP files of a systems file, or of those the workspace names.
fn write_ssp(ws: &Workspace, systems_file: Option<&Path>, fmu_dir: Option<&Path>) -> Result<(), String> {
    let files = match systems_file {
        Some(f) => vec![f.to_path_buf()],
        None => crate::systems::workspace_files(&ws.root)?,
    };
    let dir = fmu_dir.map_or_else(|| ws.fmu_dir(), Path::to_path_buf);
    for file in files {
        let systems = crate::systems::Systems::load(&file)?;
        for path in crate::ssp::write_all(&systems, &dir, &dir)? {
            eprintln!("fmu: wrote {}", path.display());
        }
    }
    Ok(())
}

/// The committed copy of every packaged description, if the workspace keeps one.
fn committed_descriptions(ws: &Workspace, check: bool) -> Result<(), String> {
    let Some(dir) = ws.metadata_path("model-descriptions") else {
        return if check {
            Err("the workspace names no [workspace.metadata.fmu] model-descriptions folder".into())
        } else {
            Ok(())
        };
    };
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut stale = Vec::new();
    for c in &ws.crates {
        let binary = std::fs::read(ws.library(c)).map_err(|e| {
            format!(
                "{}: {e} (build first: cargo run --release -p fmu-build)",
                ws.library(c).display()
            )
        })?;
        let me = crate::bundle::read_library(&binary)?;
        let xml = crate::xml::fmi2(&me.description, me.interfaces, &me.guid)?;
        let path = dir.join(format!("{}.xml", me.description.model_identifier));
        let old = std::fs::read_to_string(&path).unwrap_or_default();
        if old != xml {
            if check {
                stale.push(path.display().to_string());
            } else {
                std::fs::write(&path, xml).map_err(|err| format!("{}: {err}", path.display()))?;
                eprintln!("fmu: wrote {}", path.display());
            }
        }
    }
    if stale.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "these files differ from what the built libraries describe: {}; run `cargo run --release -p fmu-build` and commit them",
            stale.join(", ")
        ))
    }
}

fn validate_all(fmus: &[PathBuf], python: Option<&Path>) -> Result<(), String> {
    if fmus.is_empty() {
        return Err("no FMU file given".into());
    }
    let mut failures = Vec::new();
    for f in fmus {
        let mut problems = crate::validate::validate(f);
        if problems.is_empty()
            && let Some(py) = python
        {
            problems.extend(crate::validate::fmpy_validate(py, f));
        }
        if problems.is_empty() {
            eprintln!("fmu: {} is valid", f.display());
        } else {
            for p in &problems {
                eprintln!("fmu: {}: {p}", f.display());
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

/// Entry point of both binaries; `tool` is how the messages name the program.
pub fn main(args: Vec<OsString>, tool: &str) -> ExitCode {
    if args.get(1).is_some_and(|a| a == CHECK_WORKER) {
        return fmi2_conformance::runner::worker_main(
            args.into_iter().skip(2).map(|a| a.to_string_lossy().into_owned()),
        );
    }
    let cli = match Cli::try_parse_from(args) {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() {
                ExitCode::from(2)
            } else {
                ExitCode::SUCCESS
            };
        }
    };
    let cmd = cli.command.unwrap_or(Cmd::Build {
        manifest_path: None,
        packages: vec![],
        workspace: true,
        python: None,
    });
    match run(cmd, tool) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is_empty() => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("{tool}: error: {e}");
            ExitCode::FAILURE
        }
    }
}
