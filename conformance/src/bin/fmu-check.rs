//! `fmu-check X.fmu [--filter TEXT] [--timeout SECONDS] [--random-sequences N]`: checks an FMI
//! 2.0 FMU with the FMI 2.0 checks, an FMI 3.0 FMU with the FMI 3.0 ones (by the fmiVersion of
//! its model description), each in a child process, and prints a report. Exits 1 when a check failed, 2 on a usage error. `fmu-check --list` lists the checks;
//! `--as-foreign` checks even this exporter's FMU as another exporter's (to test the checks);
//! `--strict` makes every warning a failure (what this exporter's own FMUs must pass);
//! `--reproducers DIR`: where failing random sequences leave their reproducers.
//! `fmu-check --replay FILE X.fmu` replays a reproducer in a worker process (as `cargo fmu
//! replay`, [`fmi_conformance::runner::replay_in_worker`]; `--in-process`: in this process, for a
//! debugger): exits 1 when the FMU does not answer as the file expects or crashes (the line and
//! the signal said), 2 when the file or the FMU cannot be read. `--timeout` limits the replay too
//! (default 300 s).
//! `--junit FILE` and `--json FILE` write the report for CI systems too
//! ([`fmi_conformance::report`]). `--preload-lib PATH` (repeatable; also
//! `$RUSTFMU_RUNNER_PRELOAD`) loads a library before the FMU's binary, as the runner's option.
//!
//! `fmu-check __worker ...` is the child's side ([`fmi_conformance::runner::worker_main`]).

use fmi_conformance::checks::all_checks;
use fmi_conformance::runner::{RunOptions, run_with, worker_main};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

const USAGE: &str = "usage: fmu-check X.fmu [--filter TEXT] [--timeout SECONDS] [--random-sequences N] [--as-foreign] [--strict] [--reproducers DIR] [--junit FILE] [--json FILE] [--preload-lib PATH]... | --list | --replay FILE X.fmu [--in-process] [--timeout SECONDS] [--preload-lib PATH]...";

struct Args {
    fmu: Option<PathBuf>,
    filter: Option<String>,
    timeout: Option<Duration>,
    random_sequences: u32,
    list: bool,
    as_foreign: bool,
    strict: bool,
    reproducers: Option<PathBuf>,
    replay: Option<PathBuf>,
    in_process: bool,
    junit: Option<PathBuf>,
    json: Option<PathBuf>,
    preload: Vec<PathBuf>,
}

fn parse(args: impl Iterator<Item = String>) -> Result<Args, String> {
    let mut a = Args {
        fmu: None,
        filter: None,
        timeout: None,
        random_sequences: 0,
        list: false,
        as_foreign: false,
        strict: false,
        reproducers: None,
        replay: None,
        in_process: false,
        junit: None,
        json: None,
        preload: vec![],
    };
    let mut it = args;
    while let Some(arg) = it.next() {
        let mut value = |what: &str| it.next().ok_or(format!("{what} needs a value"));
        match arg.as_str() {
            "--filter" => a.filter = Some(value("--filter")?),
            "--timeout" => {
                let s: f64 = value("--timeout")?.parse().map_err(|e| format!("--timeout: {e}"))?;
                if !(s.is_finite() && s > 0.0) {
                    return Err("--timeout: seconds > 0".into());
                }
                a.timeout = Some(Duration::from_secs_f64(s));
            }
            "--random-sequences" => {
                a.random_sequences = value("--random-sequences")?
                    .parse()
                    .map_err(|e| format!("--random-sequences: {e}"))?
            }
            "--list" => a.list = true,
            "--as-foreign" => a.as_foreign = true,
            "--strict" => a.strict = true,
            "--reproducers" => a.reproducers = Some(PathBuf::from(value("--reproducers")?)),
            "--replay" => a.replay = Some(PathBuf::from(value("--replay")?)),
            "--in-process" => a.in_process = true,
            "--junit" => a.junit = Some(PathBuf::from(value("--junit")?)),
            "--json" => a.json = Some(PathBuf::from(value("--json")?)),
            "--preload-lib" => a.preload.push(PathBuf::from(value("--preload-lib")?)),
            "-h" | "--help" => return Err(String::new()),
            s if s.starts_with('-') => return Err(format!("unknown option {s}")),
            s if a.fmu.is_none() => a.fmu = Some(PathBuf::from(s)),
            s => return Err(format!("one FMU at a time ({s})")),
        }
    }
    Ok(a)
}

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1).peekable();
    if args.peek().map(String::as_str) == Some("__worker") {
        args.next();
        return worker_main(args);
    }
    let a = match parse(args) {
        Ok(a) => a,
        Err(e) => {
            if !e.is_empty() {
                eprintln!("fmu-check: {e}");
            }
            eprintln!("{USAGE}");
            return ExitCode::from(2);
        }
    };
    if a.list {
        for c in all_checks() {
            println!("{}", c.list_line());
        }
        return ExitCode::SUCCESS;
    }
    let Some(fmu) = a.fmu.clone() else {
        eprintln!("{USAGE}");
        return ExitCode::from(2);
    };
    if let Some(file) = &a.replay {
        return replay(file, &fmu, &a);
    }
    let exe = match std::env::current_exe() {
        Ok(e) => e,
        Err(e) => {
            eprintln!("fmu-check: cannot find my own executable: {e}");
            return ExitCode::from(2);
        }
    };
    let mut opts = RunOptions::new(exe, vec!["__worker".into()]);
    opts.filter = a.filter;
    opts.random_sequences = a.random_sequences;
    opts.as_foreign = a.as_foreign;
    opts.strict = a.strict;
    opts.reproducers = a.reproducers;
    opts.preload = a.preload;
    if let Some(t) = a.timeout {
        opts.timeout = t;
    }
    if opts.selected().is_empty() {
        eprintln!("fmu-check: no check matches the filter (fmu-check --list shows them)");
        return ExitCode::from(2);
    }
    // Progress on stderr while it runs; the report on stdout.
    let report = run_with(&fmu, &opts, &mut |c| eprintln!("{}", c.line()));
    println!("{report}");
    if let Err(e) = fmi_conformance::report::write_files(&report, a.junit.as_deref(), a.json.as_deref()) {
        eprintln!("fmu-check: {e}");
        return ExitCode::from(2);
    }
    if report.success() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

/// `--replay FILE X.fmu`: in a worker process (a crash of the FMU is a difference, exit 1), or
/// `--in-process` in this one (under a debugger: it stops in the FMU).
fn replay(file: &std::path::Path, fmu: &std::path::Path, a: &Args) -> ExitCode {
    use fmi_conformance::runner::{DEFAULT_REPLAY_TIMEOUT_SECONDS, Replayed, replay_in_worker};
    let replayed = if a.in_process {
        // Loaded now, before the FMU's binary (the replay runs in this process).
        if let Err(e) = rustfmu_libpython::preload(&a.preload, "--preload-lib") {
            eprintln!("fmu-check: {e}");
            return ExitCode::from(2);
        }
        fmi_conformance::replay::run::replay(file, fmu, &mut |line| println!("{line}"))
            .map(|r| r.difference.map_or(Replayed::AsExpected, Replayed::Differs))
    } else {
        match std::env::current_exe() {
            Ok(exe) => {
                let mut opts = RunOptions::new(exe, vec!["__worker".into()]);
                opts.preload = a.preload.clone();
                opts.timeout = a.timeout.unwrap_or(Duration::from_secs(DEFAULT_REPLAY_TIMEOUT_SECONDS));
                replay_in_worker(file, fmu, &opts)
            }
            Err(e) => Err(format!("cannot find my own executable: {e}")),
        }
    };
    match replayed {
        Ok(Replayed::AsExpected) => {
            println!("replay: every call answered as {} expects", file.display());
            ExitCode::SUCCESS
        }
        Ok(Replayed::Differs(d)) => {
            eprintln!("fmu-check: replay: the failure reproduces: {d}");
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("fmu-check: {e}");
            ExitCode::from(2)
        }
    }
}
