//! Checking one FMU file with every check, each in a child process of its own.
//!
//! An FMU is native code that runs inside the process that loads it: one that segfaults, aborts
//! or hangs would take a checker down with it. [`run`] therefore starts a worker process per
//! check (and one to probe the FMU first), with a timeout; a worker that dies or is killed
//! fails its check with the signal or exit code and the tail of its stderr, and the run goes
//! on. The runner itself only reads the archive ([`crate::archive`]); it never loads the
//! binary.
//!
//! The worker is any executable that calls [`worker_main`] with the arguments after its own
//! prefix: `fmu-check __worker ...` for this crate's binary, a hidden subcommand of a host
//! binary such as `cargo fmu` ([`RunOptions::worker_exe`], [`RunOptions::worker_args_prefix`]).
//! Each worker unpacks the FMU into a private folder of its own (under a private folder of the
//! run, removed at the end even if a worker crashed) and removes it when done.

use crate::archive::PrivateDir;
use crate::checks::{Check, Group, all_checks, find};
use crate::outcome::{self, Findings, Outcome};
use crate::registry::Checked;
use crate::{Fmu, Fmu3, Loaded, Version, Worker};
use std::fmt::Write as _;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// How to run the checks.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// The executable that runs [`worker_main`].
    pub worker_exe: PathBuf,
    /// Arguments before the worker's own (the host binary's hidden subcommand).
    pub worker_args_prefix: Vec<String>,
    /// Longest a check may take; its worker is then killed and the check fails.
    pub timeout: Duration,
    /// Only checks whose name or group contains this text.
    pub filter: Option<String>,
    /// Random call sequences per FMU for the random-sequence checks (0: the default, 2000).
    pub random_sequences: u32,
    /// Where the run's private folder goes (default: the system's temp folder).
    pub temp_dir: Option<PathBuf>,
    /// Check even this exporter's FMUs as another exporter's ([`crate::set_as_foreign`]).
    pub as_foreign: bool,
    /// Warnings are failures ([`Outcome::strict`]): what this exporter's own FMUs must pass.
    pub strict: bool,
    /// Where a failing random check writes its reproducer (passed to the workers in
    /// `$RUSTFMU_REPRODUCERS`; default [`crate::replay::write::default_reproducers_dir`]).
    pub reproducers: Option<PathBuf>,
    /// Libraries loaded (`RTLD_GLOBAL`) before the FMU's binary, in every worker (the runner's
    /// `--preload-lib`: a PythonFMU binary's libpython; passed to the workers in
    /// `$RUSTFMU_RUNNER_PRELOAD`, after the libraries that variable already names).
    pub preload: Vec<PathBuf>,
}

impl RunOptions {
    /// Defaults: a timeout of 30 s per check (the slowest check of this project's FMUs takes
    /// 9 s natively; a hanging FMU should not cost minutes), every check, 2000 random sequences.
    pub fn new(worker_exe: impl Into<PathBuf>, worker_args_prefix: Vec<String>) -> RunOptions {
        RunOptions {
            worker_exe: worker_exe.into(),
            worker_args_prefix,
            timeout: Duration::from_secs(DEFAULT_TIMEOUT_SECONDS),
            filter: None,
            random_sequences: 0,
            temp_dir: None,
            as_foreign: false,
            strict: false,
            reproducers: None,
            preload: vec![],
        }
    }

    /// The checks the filter selects, of both FMI versions, in report order.
    pub fn selected(&self) -> Vec<&'static Check> {
        all_checks()
            .iter()
            .filter(|c| self.filter.as_deref().is_none_or(|f| c.matches(f)))
            .collect()
    }

    /// The checks selected for an FMU of that FMI version.
    pub fn selected_for(&self, version: Version) -> Vec<&'static Check> {
        self.selected().into_iter().filter(|c| c.version() == version).collect()
    }
}

/// What one check found.
#[derive(Debug, Clone)]
pub struct CheckReport {
    pub name: String,
    pub group: Group,
    pub outcome: Outcome,
    /// Parts not tested on this FMU: a pass with limitations is a partial pass.
    pub limitations: Vec<String>,
    pub info: Vec<String>,
    /// What the standard leaves undefined or to the FMU that this FMU does not do
    /// ([`outcome::warn`]); the outcome is [`Outcome::Warn`] (under `--strict`, a failure) when
    /// there are some and nothing failed.
    pub warnings: Vec<String>,
    pub duration: Duration,
}

impl CheckReport {
    pub fn partial(&self) -> bool {
        self.outcome == Outcome::Pass && !self.limitations.is_empty()
    }

    /// The report's line for this check.
    pub fn line(&self) -> String {
        let took = format!("({:.2} s)", self.duration.as_secs_f64());
        match &self.outcome {
            Outcome::Pass if self.partial() => format!(
                "PASS  {} / {}  {took}  partial: {} part(s) not tested, listed below",
                self.group,
                self.name,
                self.limitations.len()
            ),
            Outcome::Pass => format!("PASS  {} / {}  {took}", self.group, self.name),
            Outcome::Fail(m) => format!("FAIL  {} / {}  {took}  {}", self.group, self.name, summary(m)),
            Outcome::Warn(_) => format!(
                "WARN  {} / {}  {took}  {} warning(s), listed below",
                self.group,
                self.name,
                self.warnings.len()
            ),
            Outcome::Skip(why) => format!("SKIP  {} / {}: {why}", self.group, self.name),
        }
    }
}

/// A failure message on one line: its first three lines whole (an `assert_eq!` says what came and
/// what was expected on the two after the first), never cut; the whole message is under
/// "Failures:" at the end of the report.
fn summary(message: &str) -> String {
    let lines: Vec<&str> = message
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with("(check failed at"))
        .collect();
    let mut s = lines.iter().take(3).copied().collect::<Vec<_>>().join(" | ");
    if lines.len() > 3 {
        s.push_str(&format!(" | ({} more lines under Failures)", lines.len() - 3));
    }
    s
}

/// The default longest time of one check, in seconds (`--timeout` changes it).
pub const DEFAULT_TIMEOUT_SECONDS: u64 = 30;

/// What [`run`] found.
#[derive(Debug, Clone)]
pub struct Report {
    pub fmu: PathBuf,
    /// What the FMU is (model, GUID, tool, state format), for the report's head.
    pub about: Vec<String>,
    /// Why the FMU could not be checked at all (then every check is skipped).
    pub load_error: Option<String>,
    pub checks: Vec<CheckReport>,
    /// Run with `--strict` (warnings made failures).
    pub strict: bool,
}

impl Report {
    pub fn passed(&self) -> usize {
        self.checks.iter().filter(|c| c.outcome == Outcome::Pass).count()
    }

    /// Passes with limitations (counted in [`Report::passed`] too).
    pub fn partial(&self) -> usize {
        self.checks.iter().filter(|c| c.partial()).count()
    }

    /// Failed checks; an FMU that could not be loaded counts as one.
    pub fn failed(&self) -> usize {
        self.checks
            .iter()
            .filter(|c| matches!(c.outcome, Outcome::Fail(_)))
            .count()
            + self.load_error.is_some() as usize
    }

    pub fn skipped(&self) -> usize {
        self.checks
            .iter()
            .filter(|c| matches!(c.outcome, Outcome::Skip(_)))
            .count()
    }

    /// Warned checks: no failure, but warnings (none under `--strict`: failures there).
    pub fn warned(&self) -> usize {
        self.checks
            .iter()
            .filter(|c| matches!(c.outcome, Outcome::Warn(_)))
            .count()
    }

    /// No failure (and the FMU loaded).
    pub fn success(&self) -> bool {
        self.failed() == 0
    }

    /// The closing line: `N passed, N failed, N warned, N skipped`.
    pub fn totals(&self) -> String {
        format!(
            "{} passed, {} failed, {} warned, {} skipped",
            self.passed(),
            self.failed(),
            self.warned(),
            self.skipped()
        )
    }
}

impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "{}", self.fmu.display())?;
        for line in &self.about {
            writeln!(f, "  {line}")?;
        }
        if let Some(e) = &self.load_error {
            writeln!(f, "FAIL  the FMU cannot be checked: {e}")?;
        }
        if self.strict {
            writeln!(f, "  --strict: a warning is a failure")?;
        }
        for c in &self.checks {
            writeln!(f, "{}", c.line())?;
            for l in &c.warnings {
                let mut lines = l.lines();
                writeln!(f, "        warning: {}", lines.next().unwrap_or(""))?;
                for more in lines {
                    writeln!(f, "          {more}")?;
                }
            }
            for l in &c.limitations {
                writeln!(f, "        not tested: {l}")?;
            }
            for l in &c.info {
                writeln!(f, "        {l}")?;
            }
        }
        // The summary, by verdict: what the FMU must fix (the standard's requirements), then
        // what it should consider (warnings), then what was not checked and why.
        let of =
            |word: &str| -> Vec<&CheckReport> { self.checks.iter().filter(|c| c.outcome.word() == word).collect() };
        let failures = of("fail");
        if !failures.is_empty() {
            writeln!(
                f,
                "\nFailures ({}): requirements of the standard the FMU does not meet",
                failures.len()
            )?;
            for c in failures {
                if let Outcome::Fail(m) = &c.outcome {
                    writeln!(f, "\n--- {} / {}", c.group, c.name)?;
                    for line in m.lines() {
                        writeln!(f, "    {line}")?;
                    }
                }
            }
            writeln!(f)?;
        }
        let warned = of("warn");
        if !warned.is_empty() {
            writeln!(
                f,
                "\nWarnings ({}): what the standard leaves undefined or to the FMU (--strict makes them failures)",
                warned.len()
            )?;
            for c in warned {
                writeln!(f, "\n--- {} / {}", c.group, c.name)?;
                for w in &c.warnings {
                    for (i, line) in w.lines().enumerate() {
                        writeln!(f, "    {}{line}", if i == 0 { "- " } else { "  " })?;
                    }
                }
            }
            writeln!(f)?;
        }
        let skipped = of("skip");
        if !skipped.is_empty() {
            writeln!(f, "\nSkipped ({}):", skipped.len())?;
            for c in skipped {
                if let Outcome::Skip(why) = &c.outcome {
                    writeln!(f, "    {} / {}: {why}", c.group, c.name)?;
                }
            }
            writeln!(f)?;
        }
        if self.partial() > 0 {
            writeln!(
                f,
                "{} of the passes are partial: what was not tested is listed under them",
                self.partial()
            )?;
        }
        write!(f, "{}", self.totals())
    }
}

/// Checks the FMU at `fmu_path` with every check `opts` selects, each in a worker process.
pub fn run(fmu_path: &Path, opts: &RunOptions) -> Report {
    run_with(fmu_path, opts, &mut |_| {})
}

/// As [`run`], calling `progress` with each check's report as soon as it is done.
// Over ~150 lines: the parent's loop over the checks (spawn, time out, collect), whose locals serve
// every branch.
pub fn run_with(fmu_path: &Path, opts: &RunOptions, progress: &mut dyn FnMut(&CheckReport)) -> Report {
    // FMI 3.0 files get the FMI 3.0 checks; everything else the FMI 2.0 ones.
    let version = file_version(fmu_path);
    let selected = opts.selected_for(version);
    let mut report = Report {
        fmu: fmu_path.to_path_buf(),
        about: vec![],
        load_error: None,
        checks: vec![],
        strict: opts.strict,
    };
    let skip_all = |report: &mut Report, why: &str| {
        report.checks = selected
            .iter()
            .map(|c| CheckReport {
                name: c.name.to_string(),
                group: c.group,
                outcome: Outcome::Skip(why.to_string()),
                limitations: vec![],
                info: vec![],
                warnings: vec![],
                duration: Duration::ZERO,
            })
            .collect();
    };
    // The libraries given with --preload-lib must load (in this process first: an error is then
    // one, not one per check); the workers load them before the FMU's binary.
    if let Err(e) = rustfmu_libpython::preload(&opts.preload, "--preload-lib") {
        report.load_error = Some(e);
        skip_all(&mut report, "the FMU cannot be checked");
        return report;
    }
    // What the archive says, read here (no FMU code runs in this process).
    let about = match version {
        Version::Fmi2 => Fmu::describe(fmu_path),
        Version::Fmi3 => Fmu3::describe(fmu_path),
    };
    match about {
        Ok(about) => report.about = about,
        Err(e) => {
            report.load_error = Some(e);
            skip_all(&mut report, "the FMU cannot be checked");
            return report;
        }
    }
    // One seed for the run's random checks, named at the head of the report and handed to every
    // worker ($RUSTFMU_SEED as given, else drawn here): a worker that dies still has its seed
    // printed.
    let seed = if selected.iter().any(|c| c.group == Group::RandomSequences) {
        match crate::seed_from_env() {
            Ok(_) => {
                let seed = crate::seed();
                report.about.push(format!(
                    "random call sequences: seed {seed} ({}); rerun with {}={seed} (and the same --random-sequences) to repeat them",
                    if std::env::var_os(crate::SEED_VAR).is_some() {
                        "from $RUSTFMU_SEED"
                    } else {
                        "drawn for this run"
                    },
                    crate::SEED_VAR
                ));
                Some(seed)
            }
            Err(e) => {
                report.load_error = Some(e);
                skip_all(&mut report, "the FMU cannot be checked");
                return report;
            }
        }
    } else {
        None
    };
    let base = opts.temp_dir.clone().unwrap_or_else(std::env::temp_dir);
    let run_dir = match PrivateDir::new_in(&base) {
        Ok(d) => d,
        Err(e) => {
            report.load_error = Some(e);
            skip_all(&mut report, "the FMU cannot be checked");
            return report;
        }
    };
    // Loaded once in a worker: a binary that does not load (or crashes on load) fails here.
    let probe = run_worker(
        opts,
        run_dir.path(),
        &["probe".into(), fmu_path.display().to_string()],
        seed,
        false,
    );
    match probe.result.clone() {
        Some(r) if r.outcome == Outcome::Pass => {
            report.about.extend(r.info);
            if let Some(crash) = &probe.crash {
                // It loads, but its process dies on the way out: every check will say so.
                report
                    .about
                    .push(format!("after loading it, the worker process {crash}"));
            }
        }
        Some(Parsed {
            outcome: Outcome::Fail(m) | Outcome::Skip(m),
            ..
        }) if probe.crash.is_none() => report.load_error = Some(m),
        // The probe crashed (in the binary's initializers, or serializing a new instance's
        // state): a crash is the FMU's failure, never a reason to skip. Every check runs, each in
        // a process of its own, and fails with the call it crashed in where it meets the crash.
        _ => report.about.push(format!(
            "the preflight (loading the FMU, serializing a new instance's state) crashed: its worker process {}; \
             every check runs, and fails where it meets the crash",
            probe.describe_crash()
        )),
    }
    if report.load_error.is_some() {
        skip_all(&mut report, "the FMU cannot be checked");
        return report;
    }
    for check in selected {
        let (name, group) = (check.name, check.group);
        let mut args = vec![
            "check".to_string(),
            fmu_path.display().to_string(),
            name.to_string(),
            "--random-sequences".into(),
            opts.random_sequences.to_string(),
            "--self".into(),
            opts.worker_exe.display().to_string(),
        ];
        for a in &opts.worker_args_prefix {
            args.extend(["--self-arg".to_string(), a.clone()]);
        }
        let w = run_worker(opts, run_dir.path(), &args, seed, false);
        // A random check whose worker died wrote no report: its failure names the seed.
        let seed_note = match seed {
            Some(s) if group == Group::RandomSequences => format!(
                "\n(random seed {s}; rerun with {}={s} and --random-sequences {} to repeat the sequences)",
                crate::SEED_VAR,
                match opts.random_sequences {
                    0 => crate::random_sequences(),
                    n => n,
                }
            ),
            _ => String::new(),
        };
        let mut c = CheckReport {
            name: name.to_string(),
            group,
            outcome: Outcome::Pass,
            limitations: vec![],
            info: vec![],
            warnings: vec![],
            duration: w.duration,
        };
        match (w.result.clone(), &w.crash) {
            (Some(r), None) => {
                c.outcome = r.outcome;
                c.limitations = r.limitations;
                c.info = r.info;
                c.warnings = r.warnings;
            }
            (Some(r), Some(_)) => {
                c.outcome = Outcome::Fail(format!(
                    "the check ended ({}), but then its process {}{seed_note}",
                    match &r.outcome {
                        Outcome::Pass => "passed".to_string(),
                        Outcome::Fail(m) => format!("failed: {m}"),
                        Outcome::Warn(m) => format!("warned: {m}"),
                        Outcome::Skip(m) => format!("skipped: {m}"),
                    },
                    w.describe_crash()
                ))
            }
            // Died in a call the check made as an importer's mistake on purpose: what the FMU does
            // then is undefined by the standard, a warning.
            (None, Some(_))
                if w.breadcrumb
                    .as_deref()
                    .is_some_and(|b| b.starts_with(outcome::IMPORTERS_MISTAKE)) =>
            {
                let text = outcome::crash_on_a_mistake(&w.describe_crash());
                c.warnings = vec![text.clone()];
                c.outcome = Outcome::Warn(text);
            }
            (None, _) => c.outcome = Outcome::Fail(format!("the check's process {}{seed_note}", w.describe_crash())),
        }
        if w.restarted {
            c.info.push(
                "its process was started twice: the first start ended with STATUS_DLL_INIT_FAILED before the check began"
                    .into(),
            );
        }
        if opts.strict {
            c.outcome = c.outcome.strict();
        }
        progress(&c);
        report.checks.push(c);
    }
    report
}

/// A worker's result file, parsed.
#[derive(Debug, Clone)]
struct Parsed {
    outcome: Outcome,
    limitations: Vec<String>,
    info: Vec<String>,
    warnings: Vec<String>,
}

struct WorkerRun {
    result: Option<Parsed>,
    /// The last thing the worker said it was about to do ([`outcome::breadcrumb`]).
    breadcrumb: Option<String>,
    /// How the process ended, when not with exit code 0.
    crash: Option<String>,
    stderr: String,
    duration: Duration,
    /// Started a second time: the first start ended with STATUS_DLL_INIT_FAILED (see [`run_worker`]).
    restarted: bool,
}

impl WorkerRun {
    fn describe_crash(&self) -> String {
        let mut how = self.crash.clone().unwrap_or_else(|| "wrote no result".into());
        if let Some(b) = &self.breadcrumb {
            how.push_str(&format!(" while doing: {b}"));
        }
        let tail = tail(&self.stderr, 25, 3000);
        if tail.is_empty() {
            format!("{how}; its stderr is empty")
        } else {
            format!("{how}; the end of its stderr:\n{tail}")
        }
    }
}

/// The last `lines` lines of `text`, at most `chars` characters.
fn tail(text: &str, lines: usize, chars: usize) -> String {
    let all: Vec<&str> = text.trim_end().lines().collect();
    let mut t = all[all.len().saturating_sub(lines)..].join("\n");
    if t.chars().count() > chars {
        t = t.chars().skip(t.chars().count() - chars).collect();
        t.insert_str(0, "...");
    }
    t
}

#[cfg(unix)]
unsafe extern "C" {
    fn kill(pid: i32, sig: i32) -> i32;
}
#[cfg(unix)]
const SIGKILL: i32 = 9;

#[cfg(unix)]
fn signal_name(s: i32) -> &'static str {
    match s {
        1 => "SIGHUP",
        2 => "SIGINT",
        3 => "SIGQUIT",
        4 => "SIGILL",
        5 => "SIGTRAP",
        6 => "SIGABRT",
        7 => "SIGBUS",
        8 => "SIGFPE",
        9 => "SIGKILL",
        11 => "SIGSEGV",
        13 => "SIGPIPE",
        15 => "SIGTERM",
        31 => "SIGSYS",
        _ => "a signal",
    }
}

/// Reads a pipe to its end in a thread, keeping the last 256 KiB.
fn drain(mut pipe: impl Read + Send + 'static) -> Arc<Mutex<(Vec<u8>, bool)>> {
    let buf = Arc::new(Mutex::new((Vec::new(), false)));
    let b = buf.clone();
    std::thread::spawn(move || {
        let mut chunk = [0u8; 8192];
        loop {
            match pipe.read(&mut chunk) {
                Ok(0) | Err(_) => break,
                Ok(n) => {
                    let mut g = b.lock().unwrap_or_else(|e| e.into_inner());
                    g.0.extend_from_slice(&chunk[..n]);
                    let len = g.0.len();
                    if len > 256 * 1024 {
                        g.0.drain(..len - 256 * 1024);
                    }
                }
            }
        }
        b.lock().unwrap_or_else(|e| e.into_inner()).1 = true;
    });
    buf
}

/// Windows' STATUS_DLL_INIT_FAILED (0xC0000142) as an exit code: the process ended while its
/// DLLs were loaded, before its `main` ran.
const STATUS_DLL_INIT_FAILED: i32 = 0xC000_0142_u32 as i32;

/// Runs a worker; `seed`: the random checks' seed, passed in `$RUSTFMU_SEED`; `stdout`: the
/// worker writes to this process's stdout (a replay's lines, as it makes the calls), else into a
/// pipe this process reads and leaves.
///
/// A worker that ended with STATUS_DLL_INIT_FAILED before it wrote a breadcrumb never reached
/// the FMU (wine answered so once in about 2,000 process starts of a CI run, for a check that
/// passes on every other start): it is started once more, and the report says so.
/// Any other ending, and that one after the check began, is the FMU's.
fn run_worker(opts: &RunOptions, run_dir: &Path, args: &[String], seed: Option<u64>, stdout: bool) -> WorkerRun {
    let first = run_worker_once(opts, run_dir, args, seed, stdout);
    let never_started = first.result.is_none()
        && first.breadcrumb.is_none()
        && first.crash.as_deref() == Some(&*format!("exited with code {STATUS_DLL_INIT_FAILED}"));
    if !never_started {
        return first;
    }
    let mut again = run_worker_once(opts, run_dir, args, seed, stdout);
    again.restarted = true;
    again.duration += first.duration;
    again
}

fn run_worker_once(opts: &RunOptions, run_dir: &Path, args: &[String], seed: Option<u64>, stdout: bool) -> WorkerRun {
    #[cfg(unix)]
    use std::os::unix::process::{CommandExt, ExitStatusExt};
    static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let result_file = run_dir.join(format!("result-{n}.txt"));
    let crumb_file = run_dir.join(format!("breadcrumb-{n}"));
    let clock = Instant::now();
    let mut cmd = Command::new(&opts.worker_exe);
    cmd.args(&opts.worker_args_prefix).args(args);
    if opts.as_foreign {
        cmd.arg("--as-foreign");
    }
    if opts.strict {
        cmd.arg("--strict");
    }
    if let Some(seed) = seed {
        cmd.env(crate::SEED_VAR, seed.to_string());
    }
    if let Some(dir) = &opts.reproducers {
        cmd.env(crate::replay::write::REPRODUCERS_VAR, dir);
    }
    if let Some(libraries) = rustfmu_libpython::for_child() {
        cmd.env(rustfmu_libpython::ENV, libraries);
    }
    cmd.arg("--tmp")
        .arg(run_dir)
        .arg("--result")
        .arg(&result_file)
        .arg("--breadcrumb")
        .arg(&crumb_file)
        .stdin(Stdio::null())
        .stdout(if stdout { Stdio::inherit() } else { Stdio::piped() })
        .stderr(Stdio::piped());
    // A group of its own, so that a timeout kills whatever the worker started too.
    #[cfg(unix)]
    cmd.process_group(0);
    // Starting the worker can fail for reasons of the machine, not of the FMU (wine's
    // CreateProcess answered "Internal error" (os error 1359) once in a few hundred starts in a CI
    // run): one more try after a pause, and only then the start is reported as a failure.
    let spawned = cmd.spawn().or_else(|_| {
        std::thread::sleep(std::time::Duration::from_millis(500));
        cmd.spawn()
    });
    let mut child = match spawned {
        Ok(c) => c,
        Err(e) => {
            return WorkerRun {
                result: None,
                breadcrumb: None,
                crash: Some(format!("could not be started ({}: {e})", opts.worker_exe.display())),
                stderr: String::new(),
                duration: clock.elapsed(),
                restarted: false,
            };
        }
    };
    let out = match child.stdout.take() {
        Some(pipe) => drain(pipe),
        // This process's stdout: nothing to read.
        None => Arc::new(Mutex::new((Vec::new(), true))),
    };
    let err = drain(child.stderr.take().expect("piped"));
    let mut crash = None;
    loop {
        match child.try_wait() {
            Ok(Some(status)) => {
                #[cfg(unix)]
                let signal = status.signal().map(|sig| {
                    let core = if status.core_dumped() { ", core dumped" } else { "" };
                    format!("was killed by signal {sig} ({}{core})", signal_name(sig))
                });
                #[cfg(not(unix))]
                let signal: Option<String> = None;
                if let Some(s) = signal {
                    crash = Some(s);
                } else if status.code() != Some(0) {
                    crash = Some(format!("exited with code {}", status.code().unwrap_or(-1)));
                }
                break;
            }
            Ok(None) if clock.elapsed() > opts.timeout => {
                #[cfg(unix)]
                // SAFETY: kill(2) on the process group of a child not yet reaped (its id is
                // still ours); SIGKILL ends the worker and whatever it started.
                unsafe {
                    kill(-(child.id() as i32), SIGKILL)
                };
                let _ = child.kill();
                let _ = child.wait();
                crash = Some(format!(
                    "timed out after {} s and was killed (a slow model may need more: --timeout SECONDS)",
                    opts.timeout.as_secs_f64()
                ));
                break;
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(10)),
            Err(e) => {
                crash = Some(format!("could not be waited for: {e}"));
                break;
            }
        }
    }
    let duration = clock.elapsed();
    // The pipes close when the worker's last descendant is gone; wait for that a little.
    let until = Instant::now() + Duration::from_secs(2);
    while Instant::now() < until && !(out.lock().map_or(true, |g| g.1) && err.lock().map_or(true, |g| g.1)) {
        std::thread::sleep(Duration::from_millis(5));
    }
    let stderr = String::from_utf8_lossy(&err.lock().unwrap_or_else(|e| e.into_inner()).0).into_owned();
    let result = std::fs::read_to_string(&result_file)
        .ok()
        .and_then(|t| parse_result(&t));
    let _ = std::fs::remove_file(&result_file);
    let breadcrumb = outcome::read_breadcrumb(&crumb_file);
    let _ = std::fs::remove_file(&crumb_file);
    WorkerRun {
        result,
        breadcrumb,
        crash,
        stderr,
        duration,
        restarted: false,
    }
}

fn escape(s: &str) -> String {
    s.replace('\\', "\\\\").replace('\n', "\\n").replace('\r', "\\r")
}

fn unescape(s: &str) -> String {
    let mut out = String::new();
    let mut chars = s.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            match chars.next() {
                Some('n') => out.push('\n'),
                Some('r') => out.push('\r'),
                Some(other) => out.push(other),
                None => {}
            }
        } else {
            out.push(c);
        }
    }
    out
}

fn format_result(outcome: &Outcome, findings: &Findings) -> String {
    let mut t = match outcome {
        Outcome::Pass => "pass\n".to_string(),
        Outcome::Fail(m) => format!("fail {}\n", escape(m)),
        Outcome::Warn(m) => format!("warn {}\n", escape(m)),
        Outcome::Skip(m) => format!("skip {}\n", escape(m)),
    };
    for l in &findings.warnings {
        let _ = writeln!(t, "warning {}", escape(l));
    }
    for l in &findings.limitations {
        let _ = writeln!(t, "limitation {}", escape(l));
    }
    for l in &findings.info {
        let _ = writeln!(t, "info {}", escape(l));
    }
    t.push_str("end\n");
    t
}

fn parse_result(text: &str) -> Option<Parsed> {
    let mut lines = text.lines();
    let first = lines.next()?;
    let (kind, rest) = first.split_once(' ').unwrap_or((first, ""));
    let outcome = match kind {
        "pass" => Outcome::Pass,
        "fail" => Outcome::Fail(unescape(rest)),
        "warn" => Outcome::Warn(unescape(rest)),
        "skip" => Outcome::Skip(unescape(rest)),
        _ => return None,
    };
    let mut p = Parsed {
        outcome,
        limitations: vec![],
        info: vec![],
        warnings: vec![],
    };
    let mut complete = false;
    for l in lines {
        let (kind, rest) = l.split_once(' ').unwrap_or((l, ""));
        match kind {
            "limitation" => p.limitations.push(unescape(rest)),
            "info" => p.info.push(unescape(rest)),
            "warning" => p.warnings.push(unescape(rest)),
            "end" => complete = true,
            _ => return None,
        }
    }
    complete.then_some(p)
}

/// The worker's side: what a host binary runs when it is called with its worker subcommand,
/// with the arguments after it. Modes (the runner passes `--tmp DIR --result FILE` to each):
///
/// - `probe <fmu>`: load the FMU, report what its state format is;
/// - `check <fmu> <check> [--random-sequences N] [--self EXE] [--self-arg A]...`: run one check
///   (`--self`: how a check starts a worker of its own);
/// - `replay <file> <fmu>`: replay a reproducer ([`replay_in_worker`]);
/// - `state-child <fmu> <state file> <steps> <step size>`: restore a serialized state, then
///   print the re-serialized state (hex) and the observations after each step (for the check
///   of restoring a state in another process).
///
/// `--as-foreign`: [`crate::set_as_foreign`]. `--strict`: [`outcome::set_strict`]. `--breadcrumb FILE`: where the checks record what they are about to do (read by the runner
/// when the worker dies). The result goes to the result file; the exit code is 0 whenever a result was written
/// (whatever it says), 2 for a usage error.
pub fn worker_main(args: impl IntoIterator<Item = String>) -> ExitCode {
    let mut positional = vec![];
    let mut tmp = None;
    let mut result = None;
    let mut random = 0u32;
    let mut self_exe = None;
    let mut self_args = vec![];
    let mut it = args.into_iter();
    while let Some(a) = it.next() {
        let mut value = |name: &str| {
            it.next().unwrap_or_else(|| {
                eprintln!("worker: {name} needs a value");
                std::process::exit(2)
            })
        };
        match a.as_str() {
            "--tmp" => tmp = Some(PathBuf::from(value("--tmp"))),
            "--result" => result = Some(PathBuf::from(value("--result"))),
            "--random-sequences" => {
                random = value("--random-sequences").parse().unwrap_or_else(|e| {
                    eprintln!("worker: --random-sequences: {e}");
                    std::process::exit(2)
                })
            }
            "--self" => self_exe = Some(PathBuf::from(value("--self"))),
            "--self-arg" => self_args.push(value("--self-arg")),
            "--as-foreign" => crate::set_as_foreign(true),
            "--strict" => outcome::set_strict(true),
            "--breadcrumb" => {
                let path = value("--breadcrumb");
                if let Err(e) = outcome::set_breadcrumb_file(Path::new(&path)) {
                    eprintln!("worker: {path}: {e}");
                }
            }
            _ => positional.push(a),
        }
    }
    let tmp = tmp.unwrap_or_else(std::env::temp_dir);
    if let Some(exe) = self_exe {
        crate::set_worker(Worker {
            exe,
            args_prefix: self_args,
        });
    }
    crate::set_random_sequences(random);
    let usage = || {
        eprintln!(
            "usage: worker probe <fmu> | check <fmu> <check> | state-child <fmu> <state file> <steps> <h> [cs|me <time> (FMI 3.0)]  [--tmp DIR] [--result FILE]"
        );
        ExitCode::from(2)
    };
    let write = |outcome: Outcome, findings: Findings| -> ExitCode {
        let text = format_result(&outcome, &findings);
        match &result {
            Some(file) => {
                if let Err(e) = std::fs::write(file, text) {
                    eprintln!("worker: {}: {e}", file.display());
                    return ExitCode::from(3);
                }
            }
            None => print!("{text}"),
        }
        ExitCode::SUCCESS
    };
    match positional.iter().map(String::as_str).collect::<Vec<_>>().as_slice() {
        ["probe", fmu] => match file_version(Path::new(fmu)) {
            Version::Fmi2 => probe::<Fmu>(Path::new(fmu), &tmp, write),
            Version::Fmi3 => probe::<Fmu3>(Path::new(fmu), &tmp, write),
        },
        ["check", fmu, name] => {
            let Some(check) = find(name) else {
                eprintln!("worker: no check named {name}");
                return ExitCode::from(2);
            };
            let version = file_version(Path::new(fmu));
            if check.version() != version {
                eprintln!("worker: {name} checks {:?} FMUs, {fmu} is {version:?}", check.version());
                return ExitCode::from(2);
            }
            outcome::remember_panic_locations();
            match version {
                Version::Fmi2 => check_in_worker::<Fmu>(check, Path::new(fmu), &tmp, write),
                Version::Fmi3 => check_in_worker::<Fmu3>(check, Path::new(fmu), &tmp, write),
            }
        }
        ["replay", file, fmu] => {
            // The replay's lines on stdout as the calls are made; what it found in the result
            // (pass: every call as the file expects; fail: the difference; skip: the file or the
            // FMU could not be read).
            let outcome = match crate::replay::run::replay(Path::new(file), Path::new(fmu), &mut |l| println!("{l}")) {
                Ok(report) => report.difference.map_or(Outcome::Pass, Outcome::Fail),
                Err(e) => Outcome::Skip(e),
            };
            write(outcome, Findings::default())
        }
        ["state-child", fmu, file, steps, h, interface, t] if is_fmi3_file(fmu) => {
            match state_child3(Path::new(fmu), &tmp, file, steps, h, interface, t) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("state-child: {e}");
                    ExitCode::from(1)
                }
            }
        }
        ["state-child", fmu, file, steps, h] => match state_child(Path::new(fmu), &tmp, file, steps, h, None) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("state-child: {e}");
                ExitCode::FAILURE
            }
        },
        ["state-child", fmu, file, steps, h, t] => match state_child(Path::new(fmu), &tmp, file, steps, h, Some(t)) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("state-child: {e}");
                ExitCode::FAILURE
            }
        },
        _ => usage(),
    }
}

/// The longest a replay in a worker may take by default ([`replay_in_worker`]): a reproducer
/// holds at most one instance's calls, which the check made within its own timeout.
pub const DEFAULT_REPLAY_TIMEOUT_SECONDS: u64 = 300;

/// What [`replay_in_worker`] found.
#[derive(Debug, Clone, PartialEq)]
pub enum Replayed {
    /// The FMU answered every call as the file expects.
    AsExpected,
    /// Where it did not: a status, a value, a guard overwritten, or the worker process that died
    /// or hung (which line, which signal or exit code, the end of its stderr).
    Differs(String),
}

/// `cargo fmu replay FILE X.fmu` (`fmu-check --replay`): replays the reproducer `file` on `fmu`
/// ([`crate::replay::run::replay`]) in a worker process, as [`run`] runs each check (`opts`: the
/// worker, the timeout, the libraries to preload; the worker's lines go to this process's
/// stdout as it makes the calls), so that an FMU that crashes, aborts or hangs during the replay
/// is reported as a crash in a check is: the line it died in (the worker's breadcrumb), the
/// signal or exit code, the end of its stderr. Err: the file or the FMU could not be read.
pub fn replay_in_worker(file: &Path, fmu: &Path, opts: &RunOptions) -> Result<Replayed, String> {
    rustfmu_libpython::preload(&opts.preload, "--preload-lib")?;
    let base = opts.temp_dir.clone().unwrap_or_else(std::env::temp_dir);
    let run_dir = PrivateDir::new_in(&base)?;
    let args = [
        "replay".to_string(),
        file.display().to_string(),
        fmu.display().to_string(),
    ];
    let w = run_worker(opts, run_dir.path(), &args, None, true);
    match (w.result.clone(), &w.crash) {
        (Some(r), None) => match r.outcome {
            Outcome::Pass => Ok(Replayed::AsExpected),
            Outcome::Fail(d) | Outcome::Warn(d) => Ok(Replayed::Differs(d)),
            Outcome::Skip(e) => Err(e),
        },
        (Some(r), Some(_)) => Ok(Replayed::Differs(format!(
            "the replay ended ({}), but then its process {}",
            match r.outcome {
                Outcome::Pass => "every call as the file expects".to_string(),
                Outcome::Fail(d) | Outcome::Warn(d) | Outcome::Skip(d) => d,
            },
            w.describe_crash()
        ))),
        (None, _) => Ok(Replayed::Differs(format!(
            "the FMU crashed: the replay's process {}",
            w.describe_crash()
        ))),
    }
}

/// Whether the file at `path` is an FMI 3.0 FMU (by its model description's fmiVersion).
fn is_fmi3_file(path: &str) -> bool {
    file_version(Path::new(path)) == Version::Fmi3
}

/// The version whose checks an FMU file gets: FMI 3.0 for an FMI 3.0 model description, else
/// FMI 2.0 (whose loading then says what is wrong with the file).
fn file_version(path: &Path) -> Version {
    match crate::file_version(path) {
        Ok(Version::Fmi3) => Version::Fmi3,
        _ => Version::Fmi2,
    }
}

/// The worker's `probe`: loads the FMU; its info lines say what it is.
fn probe<F: Checked>(fmu: &Path, tmp: &Path, write: impl Fn(Outcome, Findings) -> ExitCode) -> ExitCode {
    let f = match F::load(fmu, tmp) {
        Ok(f) => f,
        Err(e) => return write(Outcome::Fail(e), Findings::default()),
    };
    // The libpython loaded for a PythonFMU binary: every worker loads it the same way.
    let mut info: Vec<String> = rustfmu_libpython::loaded();
    if F::VERSION == Version::Fmi3 {
        info.push(format!(
            "an FMI 3.0 FMU: its binary exports the {} functions of fmi3Functions.h",
            crate::fmi3::api::FUNCTIONS.len()
        ));
    }
    info.push(match f.state_format() {
        Ok(()) => "made by this exporter (rustfmu's serialized state format): every check runs in full".to_string(),
        Err(why) => format!(
            "another exporter's FMU ({why}): the checks test what an importer can reach and list what they could not test"
        ),
    });
    // Written before the FMU is unloaded: a binary that crashes on the way out still loads (the
    // runner then says so in the report's head, and every check will fail on it).
    let code = write(
        Outcome::Pass,
        Findings {
            info,
            ..Findings::default()
        },
    );
    drop(f);
    code
}

/// The worker's `check`: loads the FMU and runs the check on it.
fn check_in_worker<F: Checked>(
    check: &Check,
    fmu: &Path,
    tmp: &Path,
    write: impl Fn(Outcome, Findings) -> ExitCode,
) -> ExitCode {
    let fmu = match F::load(fmu, tmp) {
        Ok(f) => f,
        Err(e) => {
            return write(
                Outcome::Fail(format!("the FMU does not load: {e}")),
                Findings::default(),
            );
        }
    };
    let (outcome, findings) = check.run_on(&fmu);
    let code = write(outcome, findings);
    drop(fmu);
    code
}

fn hex(values: impl IntoIterator<Item = u64>) -> String {
    values.into_iter().fold(String::new(), |mut s, b| {
        let _ = write!(s, "{b:x} ");
        s
    })
}

/// The FMI 3.0 [`state_child`]: an instance of the interface `cs` or `me`, the state restored,
/// its time `t` given by the parent (FMI 3.0 has no status function that tells it).
fn state_child3(
    fmu: &Path,
    tmp: &Path,
    file: &str,
    steps: &str,
    h: &str,
    interface: &str,
    t: &str,
) -> Result<(), String> {
    let steps: usize = steps.parse().map_err(|e| format!("steps: {e}"))?;
    let h: f64 = h.parse().map_err(|e| format!("step size: {e}"))?;
    let t: f64 = t.parse().map_err(|e| format!("time: {e}"))?;
    let me = match interface {
        "me" => true,
        "cs" => false,
        other => return Err(format!("interface '{other}': cs or me")),
    };
    let bytes = std::fs::read(file).map_err(|e| format!("{file}: {e}"))?;
    let fmu = crate::fmi3::Fmu3::load(fmu, tmp)?;
    let (outcome, _) = outcome::capture(|| {
        let mut inst = if me {
            crate::fmi3::Inst::me(&fmu)
        } else {
            crate::fmi3::Inst::cs(&fmu)
        };
        let s = inst.restore(&bytes);
        assert_eq!(
            s,
            crate::fmi3::types::fmi3OK,
            "restoring the state: {}",
            inst.log_text()
        );
        inst.time = t;
        println!("{}", hex(inst.snapshot().into_iter().map(u64::from)));
        for _ in 0..steps {
            inst.step(h);
            println!("{}", hex(inst.observe()));
        }
    });
    match outcome {
        Outcome::Pass => Ok(()),
        Outcome::Fail(m) | Outcome::Warn(m) | Outcome::Skip(m) => Err(m),
    }
}

/// Loads the FMU afresh, restores the serialized state in `file`, prints the re-serialized
/// state as hex on the first line, then one line of observations (hex bit patterns) after each
/// of `steps` steps of `h`.
fn state_child(fmu: &Path, tmp: &Path, file: &str, steps: &str, h: &str, t: Option<&str>) -> Result<(), String> {
    use crate::fmi2::fmi2OK;
    // The state's time as the parent knows it (else the FMU's fmi2LastSuccessfulTime): the
    // communication point of the next step, so that a wrong status answer is not taken for a
    // state that did not restore.
    let t: Option<f64> = t.map(|t| t.parse().map_err(|e| format!("time: {e}"))).transpose()?;
    let steps: usize = steps.parse().map_err(|e| format!("steps: {e}"))?;
    let h: f64 = h.parse().map_err(|e| format!("step size: {e}"))?;
    let bytes = std::fs::read(file).map_err(|e| format!("{file}: {e}"))?;
    let fmu = Fmu::load(fmu, tmp)?;
    let (outcome, _) = outcome::capture(|| {
        let mut inst = crate::Instance::new(&fmu);
        inst.restore(&bytes);
        inst.time = t.unwrap_or_else(|| inst.last_successful_time().1);
        println!("{}", hex(inst.snapshot().into_iter().map(u64::from)));
        for _ in 0..steps {
            let s = inst.step(h);
            assert_eq!(s, fmi2OK, "step at t = {}: status {s}: {}", inst.time, inst.log_text());
            println!("{}", hex(inst.observe()));
        }
    });
    match outcome {
        Outcome::Pass => Ok(()),
        Outcome::Fail(m) | Outcome::Warn(m) | Outcome::Skip(m) => Err(m),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 23: a failure's text was cut at 300 characters in the report's line for the check.
    #[test]
    fn a_failures_line_keeps_its_text_whole_and_points_to_the_rest() {
        let long = format!("'T' = {}: the model refused it", "x".repeat(500));
        let message = format!("{long}\n  left: 1\n right: 2\nmore\nand more\n(check failed at src/x.rs:1)");
        let c = CheckReport {
            name: "a_check".into(),
            group: crate::checks::Group::Calls,
            outcome: Outcome::Fail(message),
            limitations: vec![],
            info: vec![],
            warnings: vec![],
            duration: Duration::from_millis(10),
        };
        let line = c.line();
        assert!(line.contains(&long), "{line}");
        assert!(
            line.contains("left: 1 | right: 2 | (2 more lines under Failures)"),
            "{line}"
        );
        assert!(!line.contains("..."), "{line}");
    }
}
