//! The command line shared by `cargo fmu` and `fmu-build`.

use crate::cargo::{self, FmuCrate, Workspace};
use clap::{Parser, Subcommand};
use rustfmu::description::FmiVersion;
use std::collections::BTreeSet;
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
    /// Build FMU crates (release) and package target/fmu/<modelIdentifier>.fmu (FMI 2.0) and
    /// target/fmu/fmi3/<modelIdentifier>.fmu (FMI 3.0), then validate.
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
        /// Which FMI versions to make: 2, 3 or both (repeatable, or a comma list; default: both,
        /// or what a crate's `[package.metadata.fmu] fmi-versions` names).
        #[arg(long = "fmi-version", value_delimiter = ',', value_name = "2|3|both")]
        fmi_versions: Vec<String>,
        /// A Rust target triple whose binary goes into each FMU (repeatable, or a comma list;
        /// default: a crate's `[package.metadata.fmu] targets`, else the host only), e.g.
        /// `--target x86_64-unknown-linux-gnu --target x86_64-pc-windows-gnu`.
        #[arg(long = "target", value_delimiter = ',', value_name = "TRIPLE")]
        targets: Vec<String>,
        /// Build the examples (crates whose `[package.metadata.fmu]` says `example = true`: the
        /// Reference-FMU re-makes) for the host only, the other crates for all their targets: the
        /// main job's build (examples/run.sh). Without it, every crate for all its targets.
        #[arg(long)]
        examples_on_host: bool,
        /// With `--examples-on-host`: these example packages are built for all their targets all
        /// the same (repeatable, or a comma list). The tests' build (tests/run.sh): the examples
        /// whose foreign binaries a test reads or runs, the others for the host.
        #[arg(
            long = "examples-everywhere",
            value_delimiter = ',',
            value_name = "PACKAGE",
            requires = "examples_on_host"
        )]
        examples_everywhere: Vec<String>,
        /// Show cargo's messages as they come (default: a progress line per target, cargo's
        /// messages only for a build that failed).
        #[arg(short, long)]
        verbose: bool,
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
    /// FMU that crashes or hangs is reported, not shared. A check fails where the FMU breaks a requirement of
    /// the standard (the message names the section), warns where the standard leaves the case undefined
    /// or to the FMU, is skipped where the FMU does not declare what it is about. Ends with `N passed, N
    /// failed, N warned, N skipped`.
    Check {
        fmu: Option<PathBuf>,
        #[command(flatten)]
        options: CheckOptions,
    },
    /// Replay a reproducer (the calls of a failed check, one a line, as `cargo fmu check` writes
    /// them) on an FMU, in a child process as the checks run (`--in-process`: in this one, so
    /// that it runs under a debugger): prints each call, its status and the values it returned;
    /// exits 1 when a status or value is not the one the file expects, a buffer's guard was
    /// overwritten, a check of the sequence fails, or the FMU crashes (the line and the signal
    /// said).
    Replay {
        /// The reproducer (conformance/README.md, "Reproducers").
        file: PathBuf,
        fmu: PathBuf,
        /// Load this library (RTLD_GLOBAL) before the FMU's binary (repeatable; also
        /// RUSTFMU_RUNNER_PRELOAD), as `cargo fmu check --preload-lib`.
        #[arg(long = "preload-lib", value_name = "PATH")]
        preload_lib: Vec<PathBuf>,
        /// Replay in this process, not a child (a crash of the FMU ends it; under a debugger,
        /// it stops in the FMU).
        #[arg(long)]
        in_process: bool,
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
    /// Write a composed system (an SSP file) as one FMI 2.0 and/or 3.0 co-simulation FMU: the
    /// component FMUs in its resources, rustfmu-runner's master inside at the internal step, the
    /// SSD's own connectors (or else the system's unconnected inputs and all outputs,
    /// `component.variable`) and the components' parameters as its variables, the SSP's
    /// parameter set as their start values.
    Container {
        ssp: PathBuf,
        /// The FMU to write (default: <system>.fmu beside the SSP file).
        #[arg(short = 'o', long = "output")]
        out: Option<PathBuf>,
        /// The components' internal communication step, s (default: the SSD's fixed-step master
        /// step, oms:FixedStepMaster stepSize). An importer's step is cut into ceil(H / step)
        /// equal steps.
        #[arg(long)]
        step: Option<f64>,
        /// The FMI version of the container: 2, 3 or both (default both: FMI 2.0 at the output
        /// path, FMI 3.0 in fmi3/ beside it; one version alone goes to the output path).
        #[arg(long = "fmi-version", value_delimiter = ',', value_name = "2|3|both")]
        fmi_versions: Vec<String>,
        /// A Rust target triple whose binary goes into the container (repeatable, or a comma
        /// list; default: the rustfmu workspace's FMU targets that every component has a binary for).
        #[arg(long = "target", value_delimiter = ',', value_name = "TRIPLE")]
        targets: Vec<String>,
        /// The venv Python whose zig links macOS and old-glibc Linux targets.
        #[arg(long)]
        python: Option<PathBuf>,
        /// Show cargo's messages as they come (default: a progress line per target, cargo's
        /// messages only for a build that failed).
        #[arg(short, long)]
        verbose: bool,
    },
    /// Internal: the default experiment's picture for `build`, in a child process (SVG on stdout).
    #[command(hide = true, name = "__plot")]
    Plot {
        library: PathBuf,
        resource_uri: String,
        /// `name=value`: the crate's documentation-start.
        starts: Vec<String>,
    },
    /// Internal: the smoke run of `validate`, in a child process.
    #[command(hide = true, name = "__smoke-run")]
    SmokeRun {
        library: PathBuf,
        guid: String,
        vrs: String,
        #[arg(long = "fmi-version", default_value = "2.0")]
        fmi_version: String,
        /// The unpacked FMU's resources/ folder.
        #[arg(long)]
        resources: PathBuf,
        /// Instantiate with eventModeUsed (FMI 3.0 FMUs with clocks).
        #[arg(long = "event-mode")]
        event_mode: bool,
    },
}

fn run(cmd: Cmd, tool: &str) -> Result<(), String> {
    match cmd {
        Cmd::Container {
            ssp,
            out,
            step,
            fmi_versions,
            targets,
            python,
            verbose,
        } => {
            let versions: Vec<FmiVersion> = parse_version_choice(&fmi_versions)?
                .map_or_else(|| vec![FmiVersion::V2, FmiVersion::V3], |v| v.into_iter().collect());
            let outs = crate::container::container(&crate::container::Request {
                ssp: &ssp,
                out: out.as_deref(),
                step,
                targets: &targets,
                python: python.as_deref(),
                versions: &versions,
                verbose,
            })?;
            for out in outs {
                println!("{}", out.display());
            }
            Ok(())
        }
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
            fmi_versions,
            targets,
            examples_on_host,
            examples_everywhere,
            verbose,
        } => {
            let versions = parse_version_choice(&fmi_versions)?;
            // Before a build of minutes, not after it as "invalid: <a good FMU>".
            if let Some(py) = &python {
                crate::validate::fmpy_ready(py)?;
            }
            build_versions(
                manifest_path.as_deref(),
                &packages,
                workspace,
                python.as_deref(),
                versions.as_ref(),
                &Choice {
                    targets: &targets,
                    examples_on_host,
                    examples_everywhere: &examples_everywhere,
                    verbose,
                },
            )
            .map(|_| ())
        }
        Cmd::Validate { fmus, python } => {
            if let Some(py) = &python {
                crate::validate::fmpy_ready(py)?;
            }
            validate_all(&fmus, python.as_deref(), false)
        }
        Cmd::Check { fmu, options } => check(fmu.as_deref(), options),
        Cmd::Replay {
            file,
            fmu,
            preload_lib,
            in_process,
        } => replay(&file, &fmu, preload_lib, in_process),
        Cmd::Info { fmu } => {
            print!("{}", crate::validate::info(&fmu)?);
            Ok(())
        }
        Cmd::Xml { write, manifest_path } => {
            let ws = cargo::workspace(manifest_path.as_deref())?;
            committed_descriptions(&ws, !write, None)
        }
        Cmd::Ssp {
            systems,
            fmu_dir,
            manifest_path,
        } => {
            let ws = cargo::workspace(manifest_path.as_deref())?;
            write_ssp(&ws, systems.as_deref(), fmu_dir.as_deref())
        }
        Cmd::Plot {
            library,
            resource_uri,
            starts,
        } => {
            let starts: Vec<(String, f64)> = starts
                .iter()
                .filter_map(|s| s.split_once('='))
                .map(|(n, v)| Ok((n.to_string(), v.parse::<f64>().map_err(|e| format!("{n}={v}: {e}"))?)))
                .collect::<Result<_, String>>()?;
            print!(
                "{}",
                crate::plot::default_experiment_svg(&library, &resource_uri, &starts)?
            );
            Ok(())
        }
        Cmd::SmokeRun {
            library,
            guid,
            vrs,
            fmi_version,
            resources,
            event_mode,
        } => {
            let version = cargo::parse_fmi_version(&fmi_version)?;
            let vrs: Vec<u32> = vrs
                .split(',')
                .filter(|s| !s.is_empty())
                .filter_map(|s| s.parse().ok())
                .collect();
            let problems = crate::validate::smoke_run_version(version, &library, &guid, &vrs, &resources, event_mode);
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

/// The options of `cargo fmu check` (its flags: clap flattens them into the subcommand).
#[derive(clap::Args)]
struct CheckOptions {
    /// Only checks whose name or group contains this text.
    #[arg(long)]
    filter: Option<String>,
    /// Longest a check may take, in seconds (default 30); its process is then killed and the
    /// check fails.
    #[arg(long)]
    timeout: Option<f64>,
    /// Random call sequences per FMU (default 2000).
    #[arg(long, default_value_t = 0)]
    random_sequences: u32,
    /// List the checks and exit.
    #[arg(long)]
    list: bool,
    /// Make every warning a failure: what rustfmu's own FMUs must pass.
    #[arg(long)]
    strict: bool,
    /// Where a failed check leaves its reproducer (default: the system's temp folder,
    /// fmu-check-reproducers/); `cargo fmu replay` runs it again.
    #[arg(long, value_name = "DIR")]
    reproducers: Option<PathBuf>,
    /// Also write the report as JUnit XML (a test suite per group, a test case per check).
    #[arg(long, value_name = "FILE")]
    junit: Option<PathBuf>,
    /// Also write the report as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Load this library (RTLD_GLOBAL) before the FMU's binary, in every check (repeatable; also
    /// RUSTFMU_RUNNER_PRELOAD, paths separated by ':'), as `rustfmu-runner --preload-lib`: the
    /// libpython a PythonFMU binary expects its importer to have loaded. Without it, such a
    /// binary gets the libpython of `python3` on PATH (or RUSTFMU_RUNNER_PYTHON).
    #[arg(long = "preload-lib", value_name = "PATH")]
    preload_lib: Vec<PathBuf>,
}

fn check(fmu: Option<&Path>, o: CheckOptions) -> Result<(), String> {
    let CheckOptions {
        filter,
        timeout,
        random_sequences,
        list,
        strict,
        reproducers,
        junit,
        json,
        preload_lib,
    } = o;
    use fmi_conformance::runner::{RunOptions, run_with};
    if list {
        for c in fmi_conformance::checks::all_checks() {
            println!("{}", c.list_line());
        }
        return Ok(());
    }
    let fmu = fmu.ok_or("which FMU? `cargo fmu check X.fmu`")?;
    // An FMU `cargo fmu build` found invalid was moved aside (see `quarantine`): say so.
    if !fmu.exists()
        && let (Some(dir), Some(name)) = (fmu.parent(), fmu.file_name())
        && dir.join("invalid").join(name).exists()
    {
        return Err(format!(
            "{}: no such file: `cargo fmu build` found this FMU invalid and moved it to {} (its problems are in \
             the build's output; `cargo fmu validate {}` lists them again)",
            fmu.display(),
            dir.join("invalid").join(name).display(),
            dir.join("invalid").join(name).display()
        ));
    }
    let exe = std::env::current_exe().map_err(|e| format!("cannot find my own executable: {e}"))?;
    let mut opts = RunOptions::new(exe, vec![CHECK_WORKER.into()]);
    opts.filter = filter;
    opts.random_sequences = random_sequences;
    opts.strict = strict;
    opts.reproducers = reproducers;
    opts.preload = preload_lib;
    if let Some(t) = timeout {
        if !(t.is_finite() && t > 0.0) {
            return Err(format!("--timeout {t}: seconds > 0"));
        }
        opts.timeout = std::time::Duration::from_secs_f64(t);
    }
    if opts.selected().is_empty() {
        return Err("no check matches the filter (`cargo fmu check --list` shows them)".into());
    }
    // Progress on stderr while it runs; the report on stdout.
    let report = run_with(fmu, &opts, &mut |c| eprintln!("{}", c.line()));
    println!("{report}");
    let reproducers: Vec<PathBuf> = report
        .checks
        .iter()
        .filter_map(|c| match &c.outcome {
            fmi_conformance::outcome::Outcome::Fail(m) | fmi_conformance::outcome::Outcome::Warn(m) => {
                Some(fmi_conformance::replay::write::reproducer_paths(m))
            }
            _ => None,
        })
        .flatten()
        .collect();
    if !reproducers.is_empty() {
        println!(
            "reproducers of the failures and warnings (the calls that show each, one a line; `cargo fmu replay FILE {}` runs one \
             again, under a debugger if you like):",
            fmu.display()
        );
        for r in &reproducers {
            println!("  {}", r.display());
        }
    }
    fmi_conformance::report::write_files(&report, junit.as_deref(), json.as_deref())?;
    if report.success() { Ok(()) } else { Err(String::new()) }
}

/// `cargo fmu replay FILE FMU`: the calls on stdout as they are made (by a child process, or
/// `in_process` by this one), then whether the FMU answered as the file expects (Err: it did not,
/// it crashed, or the file or FMU could not be read).
fn replay(file: &Path, fmu: &Path, preload: Vec<PathBuf>, in_process: bool) -> Result<(), String> {
    use fmi_conformance::runner::{DEFAULT_REPLAY_TIMEOUT_SECONDS, Replayed, RunOptions, replay_in_worker};
    let replayed = if in_process {
        fmi_conformance::preload_libraries(&preload)?;
        let report = fmi_conformance::replay::run::replay(file, fmu, &mut |line| println!("{line}"))?;
        report.difference.map_or(Replayed::AsExpected, Replayed::Differs)
    } else {
        let exe = std::env::current_exe().map_err(|e| format!("cannot find my own executable: {e}"))?;
        let mut opts = RunOptions::new(exe, vec![CHECK_WORKER.into()]);
        opts.preload = preload;
        opts.timeout = std::time::Duration::from_secs(DEFAULT_REPLAY_TIMEOUT_SECONDS);
        replay_in_worker(file, fmu, &opts)?
    };
    match replayed {
        Replayed::AsExpected => {
            println!("replay: every call answered as {} expects", file.display());
            Ok(())
        }
        Replayed::Differs(d) => Err(format!("replay: the failure reproduces: {d}")),
    }
}

/// The hidden subcommand a `check` child runs (fmi_conformance::runner::worker_main).
const CHECK_WORKER: &str = "__check-worker";

/// `--fmi-version 2,3` / `--fmi-version both` ...: `None` when not given.
pub fn parse_version_choice(args: &[String]) -> Result<Option<BTreeSet<FmiVersion>>, String> {
    if args.is_empty() {
        return Ok(None);
    }
    let mut out = BTreeSet::new();
    for a in args {
        match a.trim() {
            "both" | "all" => out.extend([FmiVersion::V2, FmiVersion::V3]),
            v => {
                out.insert(cargo::parse_fmi_version(v).map_err(|e| format!("--fmi-version: {e}, or both"))?);
            }
        }
    }
    Ok(Some(out))
}

/// The versions to build of a crate: what `--fmi-version` asks for among those the crate's
/// `fmi-versions` names (default: both).
fn versions_of(c: &FmuCrate, asked: Option<&BTreeSet<FmiVersion>>) -> Result<BTreeSet<FmiVersion>, String> {
    let both = BTreeSet::from([FmiVersion::V2, FmiVersion::V3]);
    let own = match &c.fmi_versions {
        None => both,
        Some(Ok(v)) => v.clone(),
        Some(Err(e)) => return Err(format!("{}: [package.metadata.fmu] {e}", c.package)),
    };
    Ok(match asked {
        None => own,
        Some(asked) => own.intersection(asked).copied().collect(),
    })
}

fn version_list(v: &BTreeSet<FmiVersion>) -> String {
    v.iter().map(|v| v.text()).collect::<Vec<_>>().join(" and ")
}

/// Builds and packages the selected crates in both FMI versions; for a whole workspace also
/// refreshes the committed descriptions named in `[workspace.metadata.fmu]`. Returns the
/// packaged files.
pub fn build(
    manifest_path: Option<&Path>,
    packages: &[String],
    all: bool,
    python: Option<&Path>,
) -> Result<Vec<PathBuf>, String> {
    build_versions(manifest_path, packages, all, python, None, &Choice::default())
}

/// What else a build is asked for, besides crates and versions.
#[derive(Default)]
pub struct Choice<'a> {
    /// `--target`: the targets of every crate (empty: what each crate names, else the host).
    pub targets: &'a [String],
    /// `--examples-on-host`: example crates for the host only.
    pub examples_on_host: bool,
    /// `--examples-everywhere`: examples built for all their targets despite `examples_on_host`.
    pub examples_everywhere: &'a [String],
    /// `-v`: cargo's messages as they come.
    pub verbose: bool,
}

impl Choice<'_> {
    /// Whether `c`'s targets are cut to the host's: an example under `--examples-on-host`, unless
    /// `--examples-everywhere` names it.
    fn on_host_only(&self, c: &FmuCrate) -> bool {
        self.examples_on_host && c.example && !self.examples_everywhere.contains(&c.package)
    }
}

/// The targets of a crate: `--target` if given, else its `[package.metadata.fmu] targets`,
/// else the host; the host first when it is among them. With `on_host_only` (an example under
/// `--examples-on-host`, [`Choice::on_host_only`]) they are cut to the host's: the crate's own
/// entry for the host (with a glibc version, as the other crates' Linux binaries), else the host.
fn targets_of(c: &FmuCrate, asked: &[String], host: &str, on_host_only: bool) -> Result<Vec<String>, String> {
    let mut t: Vec<String> = if !asked.is_empty() {
        let mut out: Vec<String> = Vec::new();
        for a in asked {
            crate::target::platform(a).map_err(|e| format!("--target: {e}"))?;
            if !out.contains(a) {
                out.push(a.clone());
            }
        }
        out
    } else {
        match &c.targets {
            None => vec![host.to_string()],
            Some(Ok(t)) => t.clone(),
            Some(Err(e)) => return Err(format!("{}: [package.metadata.fmu] {e}", c.package)),
        }
    };
    if on_host_only {
        t.retain(|x| crate::target::split_glibc(x).0 == host);
        if t.is_empty() {
            t.push(host.to_string());
        }
    }
    t.sort_by_key(|x| x != host);
    Ok(t)
}

/// Whether FMI `version` names a binaries folder for target `triple`.
fn has_folder(triple: &str, version: FmiVersion) -> bool {
    crate::target::platform(triple).is_ok_and(|p| p.folder(version).is_ok())
}

/// [`build`] of the FMI versions asked for (`None`: both, or what each crate names) and the
/// targets asked for (empty: what each crate names, else the host).
///
/// First every target is checked ([`crate::target::preflight`]: its standard library and
/// linker), so that a missing piece stops the build before anything is built. Then for each
/// target: one `cargo build --release [--target T] -p ...` of every crate (one binary serves
/// both FMI versions), each library copied aside right after its build (to
/// `target/fmu-build/fmi{2,3}/`, one copy per version packaged), checked to implement each version
/// asked for; and each
/// crate and version packaged with the binaries of all its targets: FMI 2.0 as
/// `target/fmu/<id>.fmu`, FMI 3.0 as `target/fmu/fmi3/<id>.fmu`.
///
/// One function of ~210 lines, kept whole: its phases (the plan, the preflight, the parallel
/// builds, the notes on versions, the packaging) run in order and hand each other the plan, the
/// jobs and the built libraries; each phase is marked by a comment.
pub fn build_versions(
    manifest_path: Option<&Path>,
    packages: &[String],
    all: bool,
    python: Option<&Path>,
    asked: Option<&BTreeSet<FmiVersion>>,
    choice: &Choice,
) -> Result<Vec<PathBuf>, String> {
    let ws = cargo::workspace(manifest_path)?;
    let crates = ws.select(packages, all)?;
    for name in choice.examples_everywhere {
        match crates.iter().find(|c| &c.package == name) {
            Some(c) if c.example => {}
            Some(_) => {
                return Err(format!(
                    "--examples-everywhere {name}: not an example crate (`example = true` in [package.metadata.fmu]): \
                     it is built for all its targets anyway"
                ));
            }
            None => {
                return Err(format!(
                    "--examples-everywhere {name}: no FMU crate of that name among those built ({})",
                    crates.iter().map(|c| c.package.as_str()).collect::<Vec<_>>().join(", ")
                ));
            }
        }
    }
    let host = crate::target::host_triple()?;
    let mut plan: Vec<(FmuCrate, BTreeSet<FmiVersion>, Vec<String>)> = Vec::new();
    for c in crates {
        let versions = versions_of(&c, asked)?;
        if versions.is_empty() {
            let own = match &c.fmi_versions {
                Some(Ok(v)) => version_list(v),
                _ => "2.0 and 3.0".into(),
            };
            eprintln!(
                "fmu: warning: {} is skipped: it is built as FMI {own} ([package.metadata.fmu] fmi-versions), --fmi-version asks for FMI {}",
                c.package,
                version_list(asked.expect("empty only by the choice"))
            );
            continue;
        }
        let targets = targets_of(&c, choice.targets, &host, choice.on_host_only(&c))?;
        // A target without a folder in a version (aarch64 Linux in FMI 2.0) is left out of that
        // version's FMU; a version left with no target is an error.
        for v in &versions {
            let (with, without): (Vec<&String>, Vec<&String>) = targets.iter().partition(|t| has_folder(t, *v));
            if with.is_empty() {
                let e = crate::target::platform(without[0])?.folder(*v).expect_err("no folder");
                return Err(format!("{}: target {}: {e}", c.package, without[0]));
            }
            for t in without {
                eprintln!(
                    "fmu: note: {}: the FMI {} FMU has no {t} binary (FMI {} names no folder for it)",
                    c.package,
                    v.text(),
                    v.text()
                );
            }
        }
        plan.push((c, versions, targets));
    }
    if plan.is_empty() {
        return Err("nothing to build for the FMI versions asked for".into());
    }
    let mut all_targets: Vec<String> = Vec::new();
    for (_, _, ts) in &plan {
        for t in ts {
            if !all_targets.contains(t) {
                all_targets.push(t.clone());
            }
        }
    }
    all_targets.sort_by_key(|x| *x != host);
    let missing: Vec<String> = all_targets
        .iter()
        .filter_map(|t| crate::target::preflight(t, &host, python).err())
        .collect();
    if !missing.is_empty() {
        return Err(format!(
            "this machine cannot build every target asked for; nothing was built:\n  {}",
            missing.join("\n  ")
        ));
    }
    let mut libraries: Vec<(FmuCrate, FmiVersion, String, PathBuf)> = Vec::new();
    // What each target builds: every crate this target is for, one `cargo rustc` each (one binary
    // per crate serves both FMI versions: `export_fmu!` exports the fmi2* and the fmi3* functions).
    let mut jobs: Vec<(String, Vec<CrateVersions>)> = Vec::new();
    for t in &all_targets {
        let mine: Vec<(FmuCrate, Vec<FmiVersion>)> = plan
            .iter()
            .filter(|(_, _, ts)| ts.contains(t))
            .map(|(c, vs, _)| {
                (
                    c.clone(),
                    vs.iter().copied().filter(|v| has_folder(t, *v)).collect::<Vec<_>>(),
                )
            })
            .filter(|(_, vs)| !vs.is_empty())
            .collect();
        if !mine.is_empty() {
            jobs.push((t.clone(), mine));
        }
    }
    // Every target in a cargo folder of its own, as many side by side as the machine has cores:
    // a target's build is a chain of `cargo rustc` invocations, one per crate, whose last step (the
    // link-time optimisation of the whole library) runs on one core.
    let zig = if jobs.iter().any(|(t, _)| crate::target::uses_zig(t, &host)) {
        Some(crate::target::Zig::find(python)?)
    } else {
        None
    };
    let work: Vec<(String, Vec<FmuCrate>)> = jobs
        .iter()
        .map(|(t, mine)| (t.clone(), mine.iter().map(|(c, _)| c.clone()).collect()))
        .collect();
    cargo::build_targets(&ws, &work, &host, zig.as_ref(), choice.verbose, "libraries")?;
    // Versions a crate's library does not implement, where nobody asked for them by name (no
    // --fmi-version, no fmi-versions in its Cargo.toml): built as the library says, with a note.
    let mut not_implemented: BTreeSet<(String, FmiVersion)> = BTreeSet::new();
    for (t, mine) in &jobs {
        for (c, versions) in mine {
            for v in versions {
                if not_implemented.contains(&(c.package.clone(), *v)) {
                    continue;
                }
                let kept = cargo::keep_library(&ws, c, *v, t, &host)?;
                match check_built_version(c, *v, &kept) {
                    Err(e) if asked.is_some() || c.fmi_versions.is_some() => return Err(e),
                    Err(_) => {
                        let got = other_version(*v);
                        // A model that could export both is told how; an FMI 3.0-only one is not
                        // (export_fmu! would not compile for it).
                        let fmi3_only = std::fs::read(&kept)
                            .ok()
                            .and_then(|b| crate::library::library_versions(&b).ok())
                            .is_some_and(|has| has.iter().any(|me| me.description.has_fmi3_only()));
                        let both = if fmi3_only {
                            String::new()
                        } else {
                            "`rustfmu::export_fmu!(YourModel)` exports both versions from one binary; ".into()
                        };
                        eprintln!(
                            "fmu: note: {} implements FMI {} only (it calls rustfmu::export_fmi{}!): FMI {} is not built; \
                             {both}`fmi-versions = [\"{}\"]` in [package.metadata.fmu] of its Cargo.toml says FMI {} only \
                             and silences this note",
                            c.package,
                            got.text(),
                            &got.text()[..1],
                            v.text(),
                            got.text(),
                            got.text()
                        );
                        not_implemented.insert((c.package.clone(), *v));
                    }
                    Ok(()) => libraries.push((c.clone(), *v, t.clone(), kept)),
                }
            }
        }
    }
    // Each target is built once; its library is copied to target/fmu-build/fmi{2,3}/ for each
    // version packaged (the same bytes in both), so that a later build of another crate set
    // cannot change what was checked.
    let mut built = Vec::new();
    for (c, versions, _) in &plan {
        for version in versions {
            if not_implemented.contains(&(c.package.clone(), *version)) {
                continue;
            }
            let mut mine: Vec<(String, PathBuf)> = Vec::new();
            for (lc, lv, t, library) in &libraries {
                if lc.package == c.package && lv == version {
                    mine.push((t.clone(), library.clone()));
                }
            }
            let p = crate::bundle::package(c, *version, &mine, &ws.fmu_dir())?;
            let platforms: Vec<&str> = mine.iter().map(|(t, _)| t.as_str()).collect();
            eprintln!(
                "fmu: packaged {} (FMI {}; {})",
                p.fmu.display(),
                p.version.text(),
                platforms.join(", ")
            );
            built.push(p.fmu);
        }
    }
    validate_all(&built, python, true)?;
    if all && packages.is_empty() {
        // Every target's library carries the same description (bundle::package checked it):
        // the second of a crate and version finds its file already written.
        let libs: Vec<(PathBuf, Option<FmiVersion>)> =
            libraries.iter().map(|(_, v, _, l)| (l.clone(), Some(*v))).collect();
        committed_descriptions(&ws, false, Some(&libs))?;
        write_ssp(&ws, None, None)?;
    }
    Ok(built)
}

/// The version that is not `v`.
fn other_version(v: FmiVersion) -> FmiVersion {
    match v {
        FmiVersion::V2 => FmiVersion::V3,
        FmiVersion::V3 => FmiVersion::V2,
    }
}

/// A crate and the FMI versions one target's build of it is packaged for.
type CrateVersions = (FmuCrate, Vec<FmiVersion>);

/// The library built for `version` must implement that version: a crate that calls
/// `export_fmi2!` (or `export_fmi3!`) itself instead of `export_fmu!` gives one version only.
fn check_built_version(c: &FmuCrate, version: FmiVersion, library: &Path) -> Result<(), String> {
    let binary = std::fs::read(library).map_err(|e| format!("{}: {e}", library.display()))?;
    let has =
        crate::library::library_versions(&binary).map_err(|e| format!("{}: {}: {e}", c.package, library.display()))?;
    if has.iter().any(|me| me.interfaces.version == version) {
        return Ok(());
    }
    let got = has[0].interfaces.version;
    let (called, other) = match got {
        FmiVersion::V2 => ("rustfmu::export_fmi2!", "2.0"),
        FmiVersion::V3 => ("rustfmu::export_fmi3!", "3.0"),
    };
    // A model with FMI 3.0-only declarations (clocks, arrays, `#[fmu(fmi3_only)]`) cannot call
    // export_fmu!: the hint says so instead of suggesting a compile error.
    let fmi3_only = got == FmiVersion::V3 && has[0].description.has_fmi3_only();
    let both = if fmi3_only {
        "The model declares what FMI 2.0 does not have (clocks, arrays or #[fmu(fmi3_only)]), so it is FMI 3.0 only: "
            .to_string()
    } else {
        "Call `rustfmu::export_fmu!(YourModel)` instead (both versions from one line, in one binary), or ".to_string()
    };
    Err(format!(
        "{}: FMI {} was asked for, but the library implements FMI {} only: the crate calls `{called}` itself. \
         {both}build FMI {other} only: `fmi-versions = [\"{other}\"]` in [package.metadata.fmu] of its \
         Cargo.toml, or `cargo fmu build --fmi-version {}`",
        c.package,
        version.text(),
        got.text(),
        &other[..1],
    ))
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

/// The committed copy of every packaged description, if the workspace keeps one: FMI 2.0 as
/// `<folder>/<id>.xml`, FMI 3.0 as `<folder>/fmi3/<id>.xml`. `libraries`: the libraries just
/// built; `None`: the copies the last `cargo fmu build` kept (else cargo's own library).
fn committed_descriptions(
    ws: &Workspace,
    check: bool,
    libraries: Option<&[(PathBuf, Option<FmiVersion>)]>,
) -> Result<(), String> {
    let Some(dir) = ws.metadata_path("model-descriptions") else {
        return if check {
            Err("the workspace names no [workspace.metadata.fmu] model-descriptions folder".into())
        } else {
            Ok(())
        };
    };
    // (library, the version of it to describe; `None`: every version it implements).
    let libraries: Vec<(PathBuf, Option<FmiVersion>)> = match libraries {
        Some(l) => l.to_vec(),
        None => ws
            .crates
            .iter()
            .flat_map(|c| {
                let kept: Vec<(PathBuf, Option<FmiVersion>)> = [FmiVersion::V2, FmiVersion::V3]
                    .into_iter()
                    .filter_map(|v| ws.any_built_library(c, v).map(|p| (p, Some(v))))
                    .collect();
                if kept.is_empty() {
                    vec![(ws.library(c), None)]
                } else {
                    kept
                }
            })
            .collect(),
    };
    let mut stale = Vec::new();
    for (library, version) in &libraries {
        let binary = std::fs::read(library)
            .map_err(|e| format!("{}: {e} (build first: cargo fmu build --workspace)", library.display()))?;
        let all = crate::library::library_versions(&binary).map_err(|e| format!("{}: {e}", library.display()))?;
        for me in all
            .into_iter()
            .filter(|me| version.is_none_or(|v| v == me.interfaces.version))
        {
            let xml = crate::library::model_description(&me)?;
            let folder = match me.interfaces.version {
                FmiVersion::V2 => dir.clone(),
                FmiVersion::V3 => dir.join("fmi3"),
            };
            std::fs::create_dir_all(&folder).map_err(|e| format!("{}: {e}", folder.display()))?;
            let path = folder.join(format!("{}.xml", me.description.model_identifier));
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
    }
    if stale.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "these files differ from what the built libraries describe: {}; run `cargo fmu build --workspace` and commit them",
            stale.join(", ")
        ))
    }
}

/// `report_glibc`: also say the oldest glibc each Linux binary loads with (`cargo fmu validate`;
/// `cargo fmu build` keeps its output to the verdicts).
/// `built`: the FMUs `cargo fmu build` just made (else the user's files of `cargo fmu validate`):
/// an invalid one is moved out of the FMU folder into its `invalid/` folder, so that nothing
/// (`cargo fmu check`, an SSP file, a user's importer) takes it for a good one.
fn validate_all(fmus: &[PathBuf], python: Option<&Path>, built: bool) -> Result<(), String> {
    let report_glibc = !built;
    if fmus.is_empty() {
        return Err("no FMU file given".into());
    }
    // Each file's checks (smoke runs in child processes, fmpy's validator) side by side, as many as
    // the machine has cores; reported in the order given.
    let next = std::sync::atomic::AtomicUsize::new(0);
    let found: std::sync::Mutex<Vec<(usize, Vec<String>)>> = std::sync::Mutex::new(Vec::new());
    let workers = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(fmus.len());
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                    let Some(f) = fmus.get(i) else { break };
                    let mut problems = crate::validate::validate(f);
                    if problems.is_empty()
                        && let Some(py) = python
                    {
                        problems.extend(crate::validate::fmpy_validate(py, f));
                    }
                    found.lock().unwrap_or_else(|e| e.into_inner()).push((i, problems));
                }
            });
        }
    });
    let mut found = found.into_inner().unwrap_or_else(|e| e.into_inner());
    found.sort_by_key(|(i, _)| *i);
    let mut failures = Vec::new();
    for (f, (_, problems)) in fmus.iter().zip(found) {
        if problems.is_empty() {
            eprintln!("fmu: {} is valid", f.display());
            // What the Linux binaries need of the system: the oldest glibc they load with.
            let requirements = if report_glibc {
                crate::validate::glibc_requirements(f).unwrap_or_default()
            } else {
                Vec::new()
            };
            for (name, needed) in requirements {
                if let Some((major, minor)) = needed {
                    eprintln!("fmu: {}: {name} needs glibc >= {major}.{minor}", f.display());
                }
            }
            // The macOS binaries: built here, checked structurally, never run here.
            if report_glibc {
                for (name, slices) in crate::validate::macos_binaries(f).unwrap_or_default() {
                    eprintln!(
                        "fmu: {}: {name}: {slices}; checked (exports, imports, architecture), not run on this machine",
                        f.display()
                    );
                }
            }
        } else {
            for p in &problems {
                eprintln!("fmu: {}: {p}", f.display());
            }
            failures.push(f.display().to_string());
            if built {
                failures.extend(quarantine(f));
            }
        }
    }
    if failures.is_empty() {
        Ok(())
    } else {
        Err(format!("invalid: {}", failures.join(", ")))
    }
}

/// Moves a built FMU that failed validation to `invalid/` beside it (replacing an older one
/// there); what went wrong, when it cannot be moved (then it is removed, or said to be left).
fn quarantine(fmu: &Path) -> Option<String> {
    let dir = fmu.parent()?.join("invalid");
    let to = dir.join(fmu.file_name()?);
    let moved = std::fs::create_dir_all(&dir).and_then(|()| std::fs::rename(fmu, &to));
    match moved {
        Ok(()) => {
            eprintln!(
                "fmu: moved the invalid {} to {} (kept for inspection; no tool takes it from there)",
                fmu.display(),
                to.display()
            );
            None
        }
        Err(e) => match std::fs::remove_file(fmu) {
            Ok(()) => {
                eprintln!(
                    "fmu: removed the invalid {} (it could not be moved: {e})",
                    fmu.display()
                );
                None
            }
            Err(e2) => Some(format!(
                "(the invalid {} is left in place: it could neither be moved ({e}) nor removed ({e2}))",
                fmu.display()
            )),
        },
    }
}

/// Entry point of both binaries; `tool` is how the messages name the program.
pub fn main(args: Vec<OsString>, tool: &str) -> ExitCode {
    if args.get(1).is_some_and(|a| a == CHECK_WORKER) {
        return fmi_conformance::runner::worker_main(
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
        fmi_versions: vec![],
        targets: vec![],
        examples_on_host: false,
        examples_everywhere: vec![],
        verbose: false,
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

#[cfg(test)]
mod tests {
    use super::*;

    fn example(package: &str) -> FmuCrate {
        FmuCrate {
            package: package.into(),
            manifest_dir: PathBuf::from("x"),
            lib_name: package.replace('-', "_"),
            documentation: None,
            resources: None,
            fmi_versions: None,
            targets: Some(Ok(vec![
                "x86_64-unknown-linux-gnu.2.17".into(),
                "x86_64-pc-windows-gnu".into(),
                "aarch64-apple-darwin".into(),
            ])),
            documentation_start: Ok(vec![]),
            example: true,
        }
    }

    #[test]
    fn examples_everywhere_needs_examples_on_host() {
        let parse = |args: &[&str]| Cli::try_parse_from(["cargo-fmu"].iter().chain(args));
        assert!(parse(&["build", "--examples-everywhere", "a-fmu"]).is_err());
        let Ok(Cli {
            command:
                Some(Cmd::Build {
                    examples_on_host,
                    examples_everywhere,
                    ..
                }),
        }) = parse(&["build", "--examples-on-host", "--examples-everywhere", "a-fmu,b-fmu"])
        else {
            panic!("--examples-on-host --examples-everywhere a-fmu,b-fmu did not parse");
        };
        assert!(examples_on_host);
        assert_eq!(examples_everywhere, ["a-fmu", "b-fmu"]);
    }

    #[test]
    fn an_example_named_by_examples_everywhere_keeps_all_its_targets() {
        let host = "x86_64-unknown-linux-gnu";
        let everywhere = ["b-fmu".to_string()];
        let choice = Choice {
            examples_on_host: true,
            examples_everywhere: &everywhere,
            ..Choice::default()
        };
        let (a, b) = (example("a-fmu"), example("b-fmu"));
        let mut product = example("c-fmu");
        product.example = false;
        assert!(choice.on_host_only(&a) && !choice.on_host_only(&b) && !choice.on_host_only(&product));
        assert!(!Choice::default().on_host_only(&a));
        let cut = targets_of(&a, &[], host, choice.on_host_only(&a)).unwrap();
        assert_eq!(cut, ["x86_64-unknown-linux-gnu.2.17"]);
        assert_eq!(targets_of(&b, &[], host, choice.on_host_only(&b)).unwrap().len(), 3);
    }
}
