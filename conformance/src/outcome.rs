//! What a check found, and whose obligation it was. A check is a function that returns when the
//! FMU passed and panics (an `assert!` message: what was expected, what came instead) when it
//! failed. A failure is kept for what the standard requires ("shall", "must", "is required"): its
//! message names the document and section (FMI 2.0.5 §x.y, FMI 3.0.2 §x.y) and the requirement in
//! a few words. While it runs a check may record:
//!
//! - a **warning** ([`warn`], [`warned`]): a finding the standard does not make a requirement of
//!   the FMU: what it leaves undefined or to the FMU (detecting an importer's mistake such as NaN
//!   set for a Real, robustness beyond the standard, leaks, hangs on absurd input, portability and
//!   hygiene such as extra exported symbols), each with why it matters. A check with warnings
//!   and no failure is *warned*; `--strict` ([`Outcome::strict`]) makes it a failure, which is
//!   what this exporter's own FMUs must pass;
//! - a **limitation** ([`limitation`], [`convention`]): a part it could not test on this FMU,
//!   such as the states only this exporter's FMUs can be forced into. A pass with limitations
//!   is reported as a partial pass, never as a plain one;
//! - **info** ([`info`]): figures for the report (cases run, memory measured);
//! - a **skip** ([`skip`]): nothing of the check applies (a tool is missing, the FMU does not
//!   declare the capability the check is about).
//!
//! [`capture`] runs a check and turns all of that into an [`Outcome`] and [`Findings`].

use crate::Fmu;
use std::any::Any;
use std::cell::RefCell;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Mutex;

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Outcome {
    Pass,
    /// The failure message: a normative requirement of the standard the FMU broke.
    Fail(String),
    /// No failure, but warnings (one a line): see [`warn`].
    Warn(String),
    /// Why the check does not apply.
    Skip(String),
}

/// How a warning turned into a failure by `--strict` ([`Outcome::strict`]) starts.
pub const STRICT_PREFIX: &str = "warned (a failure under --strict):\n";

impl Outcome {
    /// The verdict's word in reports: `pass`, `fail`, `warn`, `skip`.
    pub fn word(&self) -> &'static str {
        match self {
            Outcome::Pass => "pass",
            Outcome::Fail(_) => "fail",
            Outcome::Warn(_) => "warn",
            Outcome::Skip(_) => "skip",
        }
    }

    /// The outcome under `--strict`: a warning is a failure (what this exporter's own FMUs must
    /// pass: they detect the importer's mistakes, leak nothing, export only FMI functions, and
    /// serialize their state deterministically); everything else as it is.
    pub fn strict(self) -> Outcome {
        match self {
            Outcome::Warn(m) => Outcome::Fail(format!("{STRICT_PREFIX}{m}")),
            other => other,
        }
    }
}

/// What a check recorded besides its outcome.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Findings {
    pub limitations: Vec<String>,
    pub info: Vec<String>,
    /// What the standard leaves undefined or to the FMU that this FMU does not do: see [`warn`].
    pub warnings: Vec<String>,
}

thread_local! {
    static FINDINGS: RefCell<Findings> = RefCell::new(Findings::default());
    static PANIC_AT: RefCell<Option<String>> = const { RefCell::new(None) };
}

static STRICT: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether this run is strict (`--strict`, and the workspace's own tests): then the checks also
/// compare what only this exporter's determinism promises, such as the bytes of serialized FMU
/// states before and after a refused call.
pub fn strict() -> bool {
    STRICT.load(std::sync::atomic::Ordering::Relaxed)
}

/// Sets [`strict`] for this process (a worker of a `--strict` run; the workspace's tests).
pub fn set_strict(on: bool) {
    STRICT.store(on, std::sync::atomic::Ordering::Relaxed);
}

/// How a breadcrumb ([`breadcrumb`]) starts when the call it names is an importer's mistake
/// or absurd input made on purpose (a NULL array with n > 0, a damaged buffer, a step of 1e300 s):
/// the standard leaves what the FMU then does undefined, so a crash or a hang there is a warning,
/// not a failure ([`on_purpose`]).
pub const IMPORTERS_MISTAKE: &str = "[an importer's mistake or absurd input, on purpose] ";

static ON_PURPOSE: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Runs `f`, whose calls are an importer's mistakes or absurd input made on purpose: their
/// breadcrumbs start with [`IMPORTERS_MISTAKE`], so that a crash or hang in them is a warning.
pub fn on_purpose<R>(f: impl FnOnce() -> R) -> R {
    let was = ON_PURPOSE.swap(true, std::sync::atomic::Ordering::Relaxed);
    let r = f();
    ON_PURPOSE.store(was, std::sync::atomic::Ordering::Relaxed);
    r
}

/// Whether the calls made now are an importer's mistakes on purpose (inside [`on_purpose`]).
pub fn is_on_purpose() -> bool {
    ON_PURPOSE.load(std::sync::atomic::Ordering::Relaxed)
}

/// The warning for a worker that died or hung (`how`) during a call whose breadcrumb starts
/// with [`IMPORTERS_MISTAKE`].
pub fn crash_on_a_mistake(how: &str) -> String {
    format!(
        "the check's process {how}: the call was an importer's mistake or absurd input, whose outcome the \
         standard leaves undefined (FMI 2.0.5 §2.1.3, FMI 3.0.2 §2.2.4: an FMU that detects it returns an \
         error); a crash or hang takes the importer down with it. The rest of the check did not run"
    )
}

/// Whether two times are the same within a tolerance relative to the step `h` (and to their
/// size): FMI 2.0.5 and 3.0.2 promise no bit identity of times an FMU computes (FMI 3.0.2
/// fmi3DoStep: `lastSuccessfulTime` is the FMU's own time; t + h summed in another order, or an
/// internal step summed n times, differs by rounding). A millionth of the step (as the C hosts
/// allow), at least 64 ulps of the larger time.
pub fn same_time(a: f64, b: f64, h: f64) -> bool {
    a == b || (a - b).abs() <= time_tolerance(a.abs().max(b.abs()), h)
}

/// The tolerance of [`same_time`] for times of size `t` and the step `h`.
pub fn time_tolerance(t: f64, h: f64) -> f64 {
    (1e-6 * h.abs()).max(64.0 * f64::EPSILON * t.abs())
}

/// The payload of [`skip`].
struct Skipped(String);

/// The payload of [`warned`].
struct Warned;

/// What a new warning also does: the call log ([`crate::calllog::begin`] installs it) notes the
/// call the warning followed. A hook, so that the call log stays above this file.
static ON_WARNING: std::sync::OnceLock<fn()> = std::sync::OnceLock::new();

/// Installs [`ON_WARNING`] (once: later calls change nothing).
pub fn on_warning(hook: fn()) {
    let _ = ON_WARNING.set(hook);
}

/// Records a warning and lets the check go on: a finding the standard does not make a
/// requirement of the FMU (it leaves the case undefined or to the FMU, or it is portability and
/// hygiene advice), with why it matters. The check is then *warned* unless it also fails; under
/// `--strict` a failure. Once per text.
pub fn warn(text: impl Into<String>) {
    let text = text.into();
    FINDINGS.with(|f| {
        let mut f = f.borrow_mut();
        if !f.warnings.contains(&text) {
            f.warnings.push(text);
            // The call the first warning followed ends a warned check's reproducer.
            if let Some(hook) = ON_WARNING.get() {
                hook();
            }
        }
    });
}

/// Records a warning ([`warn`]) and ends the check: what comes after it in the check cannot be
/// tested once that happened.
pub fn warned(text: impl Into<String>) -> ! {
    warn(text);
    std::panic::resume_unwind(Box::new(Warned))
}

/// `warn(text)` unless `ok`: the [`warn`] counterpart of `assert!` (the text is built only when
/// it is needed).
pub fn warn_unless(ok: bool, text: impl FnOnce() -> String) {
    if !ok {
        warn(text());
    }
}

/// Ends the check as skipped: nothing of it applies to this FMU or on this machine.
pub fn skip(reason: impl Into<String>) -> ! {
    std::panic::resume_unwind(Box::new(Skipped(reason.into())))
}

/// How the reason of a skip starts when the FMU does not declare the optional interface or
/// capability the check is about (Model Exchange, directional derivatives): such a skip is
/// the FMU's choice, not a gap of the suite, and the workspace's strict runs accept it.
pub const NOT_DECLARED: &str = "not declared by the FMU: ";

/// How a limitation starts when the FMU declares what a part of the check is about, but its run
/// (the default experiment, within the check's step budget) never made it happen: an event
/// indicator that never changed domain. The model's behaviour, not a gap of the suite: the
/// workspace's strict runs accept it as they accept [`NOT_DECLARED`].
pub const NOT_EXERCISED: &str = "not exercised by the run: ";

/// The longest run (in steps) of the checks that simulate the default experiment: its stop
/// time, cut to this many steps (at the check's step size) so that a check stays within its
/// timeout.
pub const MAX_RUN_STEPS: f64 = 50_000.0;

/// The stop time of a run of the default experiment at step size `h`: its stop time (1 s where
/// it has none), at least one step, at most [`MAX_RUN_STEPS`] steps.
pub fn run_stop(stop_time: Option<f64>, h: f64) -> f64 {
    stop_time.unwrap_or(1.0).clamp(h, MAX_RUN_STEPS * h)
}

/// The run the event checks (of both versions) report on: `run(false)`, from the start values
/// first (what the FMU's user runs); where it saw no event (`events`) and the FMU has inputs to
/// move (`excitable`), `run(true)`, with the inputs moved off their start values (a model whose
/// events depend on an input). The run, and how it was made, for the report.
pub fn event_run<R>(excitable: bool, events: impl Fn(&R) -> usize, run: impl Fn(bool) -> R) -> (R, &'static str) {
    let first = run(false);
    if events(&first) == 0 && excitable {
        (
            run(true),
            "with the inputs moved off their start values (none happened from the start values)",
        )
    } else {
        (first, "from the start values")
    }
}

/// Ends the check as skipped because the FMU does not declare `what` (see [`NOT_DECLARED`]).
pub fn skip_not_declared(what: impl std::fmt::Display) -> ! {
    skip(format!("{NOT_DECLARED}{what}"))
}

/// Records a part of the check that could not be tested on this FMU (once per text).
pub fn limitation(text: impl Into<String>) {
    let text = text.into();
    FINDINGS.with(|f| {
        let mut f = f.borrow_mut();
        if !f.limitations.contains(&text) {
            f.limitations.push(text);
        }
    });
}

/// Records a line for the report.
pub fn info(text: impl Into<String>) {
    FINDINGS.with(|f| f.borrow_mut().info.push(text.into()));
}

/// Whether to require `what`, a convention of this exporter's runtime that the standard does
/// not demand (the wording of its messages, its log categories, the features it leaves out).
/// Yes for this exporter's FMUs; for another's, no, and that is recorded as a limitation.
pub fn convention(fmu: &Fmu, what: &str) -> bool {
    if fmu.own_state_format() {
        true
    } else {
        limitation(format!("not required of another exporter's FMU: {what}"));
        false
    }
}

static BREADCRUMB: Mutex<Option<memmap2::MmapMut>> = Mutex::new(None);
static BREADCRUMBS_ON: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
pub const BREADCRUMB_BYTES: usize = 1024;

/// Where [`breadcrumb`] writes (a worker's file, which the runner reads if the worker dies):
/// mapped into memory, so that the breadcrumb the call log writes before every FMI call is a
/// copy and no system call (what a process writes into a shared mapping is in the file for
/// every reader, after the process was killed too).
pub fn set_breadcrumb_file(path: &std::path::Path) -> std::io::Result<()> {
    let f = std::fs::OpenOptions::new()
        .create(true)
        .truncate(true)
        .read(true)
        .write(true)
        .open(path)?;
    f.set_len(BREADCRUMB_BYTES as u64)?;
    // SAFETY: the worker's own file, which no other process writes or truncates while it runs
    // (the runner reads it only after the worker ended).
    let map = unsafe { memmap2::MmapMut::map_mut(&f) }?;
    *BREADCRUMB.lock().unwrap_or_else(|e| e.into_inner()) = Some(map);
    BREADCRUMBS_ON.store(true, std::sync::atomic::Ordering::Relaxed);
    Ok(())
}

/// Whether breadcrumbs are recorded (to skip formatting them when not).
pub fn breadcrumbs_on() -> bool {
    BREADCRUMBS_ON.load(std::sync::atomic::Ordering::Relaxed)
}

/// Records what the check is about to do, so that a crash inside the FMU can say where it
/// happened (a copy into the mapped breadcrumb file; nothing without one).
pub fn breadcrumb(text: &str) {
    if !breadcrumbs_on() {
        return;
    }
    let marked;
    let text = if ON_PURPOSE.load(std::sync::atomic::Ordering::Relaxed) && !text.starts_with(IMPORTERS_MISTAKE) {
        marked = format!("{IMPORTERS_MISTAKE}{text}");
        marked.as_str()
    } else {
        text
    };
    let within;
    let text = if CONTEXT_ON.load(std::sync::atomic::Ordering::Relaxed) {
        let context = CONTEXT.lock().unwrap_or_else(|e| e.into_inner());
        within = if text.is_empty() {
            context.clone()
        } else {
            format!("{context}: {text}")
        };
        within.as_str()
    } else {
        text
    };
    let mut guard = BREADCRUMB.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(map) = guard.as_mut() {
        let n = text.len().min(BREADCRUMB_BYTES);
        map[..n].copy_from_slice(&text.as_bytes()[..n]);
        // The reader stops at the first NUL.
        if n < BREADCRUMB_BYTES {
            map[n] = 0;
        }
    }
}

static CONTEXT: Mutex<String> = Mutex::new(String::new());
static CONTEXT_ON: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// What every breadcrumb after it is part of, written before it (`line 7: fmi2FreeInstance
/// component=NULL`: the line of a reproducer the replay makes, [`crate::replay_calls`]), and at
/// once as the breadcrumb; the empty text: nothing.
pub fn breadcrumb_context(text: &str) {
    if !breadcrumbs_on() {
        return;
    }
    *CONTEXT.lock().unwrap_or_else(|e| e.into_inner()) = text.to_string();
    CONTEXT_ON.store(!text.is_empty(), std::sync::atomic::Ordering::Relaxed);
    breadcrumb("");
}

/// The last breadcrumb in a breadcrumb file, if any.
pub fn read_breadcrumb(path: &std::path::Path) -> Option<String> {
    let bytes = std::fs::read(path).ok()?;
    let end = bytes.iter().position(|b| *b == 0).unwrap_or(bytes.len());
    let text = String::from_utf8_lossy(&bytes[..end]).trim().to_string();
    (!text.is_empty()).then_some(text)
}

/// Installs a panic hook that remembers where a check failed (for the report) and then does
/// what the previous hook did. For processes that run checks through [`capture`].
pub fn remember_panic_locations() {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if let Some(l) = info.location() {
            PANIC_AT.with(|p| *p.borrow_mut() = Some(format!("{}:{}", l.file(), l.line())));
        }
        previous(info);
    }));
}

/// Runs `f` (a check on one FMU) and returns its outcome and findings.
pub fn capture(f: impl FnOnce()) -> (Outcome, Findings) {
    FINDINGS.with(|x| *x.borrow_mut() = Findings::default());
    PANIC_AT.with(|p| *p.borrow_mut() = None);
    let result = catch_unwind(AssertUnwindSafe(f));
    let findings = FINDINGS.with(|x| std::mem::take(&mut *x.borrow_mut()));
    let outcome = match result {
        Ok(()) => Outcome::Pass,
        Err(payload) => from_payload(payload),
    };
    // A failure outranks warnings; warnings outrank a pass or a skip (they are findings about the
    // FMU, made before the check found nothing more to test).
    let outcome = match outcome {
        Outcome::Pass | Outcome::Skip(_) | Outcome::Warn(_) if !findings.warnings.is_empty() => {
            Outcome::Warn(findings.warnings.join("\n"))
        }
        other => other,
    };
    (outcome, findings)
}

fn from_payload(payload: Box<dyn Any + Send>) -> Outcome {
    let payload = match payload.downcast::<Skipped>() {
        Ok(s) => return Outcome::Skip(s.0),
        Err(p) => p,
    };
    let payload = match payload.downcast::<Warned>() {
        // Its text is among the findings' warnings.
        Ok(_) => return Outcome::Warn(String::new()),
        Err(p) => p,
    };
    let mut message = if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else if let Some(s) = payload.downcast_ref::<&str>() {
        s.to_string()
    } else {
        "the check panicked with a payload that is no message".to_string()
    };
    if let Some(at) = PANIC_AT.with(|p| p.borrow_mut().take()) {
        message.push_str(&format!("\n(check failed at {at})"));
    }
    Outcome::Fail(message)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failure_outranks_warnings_and_warnings_outrank_a_pass_or_a_skip() {
        let (o, f) = capture(|| {
            warn("w1");
            warn("w1");
            warn("w2");
        });
        assert_eq!(o, Outcome::Warn("w1\nw2".into()));
        assert_eq!(f.warnings, ["w1", "w2"]);
        let (o, _) = capture(|| {
            warn("w");
            panic!("FMI 2.0.5 §2.1.3: broken");
        });
        assert!(
            matches!(&o, Outcome::Fail(m) if m.starts_with("FMI 2.0.5 §2.1.3: broken")),
            "{o:?}"
        );
        let (o, _) = capture(|| {
            warn("w");
            skip("nothing else to test")
        });
        assert_eq!(o, Outcome::Warn("w".into()));
        let (o, f) = capture(|| {
            warned("stops here");
            #[allow(unreachable_code)]
            {
                panic!("not reached")
            }
        });
        assert_eq!(
            (o, f.warnings),
            (Outcome::Warn("stops here".into()), vec!["stops here".to_string()])
        );
        let (o, _) = capture(|| warn_unless(true, || unreachable!()));
        assert_eq!(o, Outcome::Pass);
    }

    #[test]
    fn strict_makes_a_warning_a_failure_and_nothing_else() {
        assert_eq!(
            Outcome::Warn("w".into()).strict(),
            Outcome::Fail(format!("{STRICT_PREFIX}w"))
        );
        for o in [Outcome::Pass, Outcome::Fail("f".into()), Outcome::Skip("s".into())] {
            assert_eq!(o.clone().strict(), o);
        }
    }
}
