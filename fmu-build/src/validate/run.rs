//! What both smoke runs ([`super::smoke2`], [`super::smoke3`]) do alike: load the binary and
//! look its functions up, judge the end of the run, add the `depends` reports.

use crate::depends::Report;
use std::path::Path;

/// How a smoke run (in the child process too) says what is worth knowing but no problem: on
/// stderr, a line each, forwarded by [`super::smoke::smoke_run_in_child`].
pub const NOTE: &str = "fmu: note: ";

/// Loads a binary and looks up every function of `functions`: the library, or what is wrong
/// (it does not load, or the functions it does not export).
pub(super) fn load_exporting(so: &Path, functions: &[&str]) -> Result<libloading::Library, Vec<String>> {
    // SAFETY: loading the FMU's binary runs its initializers, the code under test: the smoke run
    // exists to run it, in a child process of its own (`smoke_run_in_child`) so that a crash is
    // reported rather than shared.
    let lib = unsafe { libloading::Library::new(so) }.map_err(|e| vec![format!("the binary does not load: {e}")])?;
    let missing: Vec<String> = functions
        .iter()
        // SAFETY: only the symbol's presence is checked; the pointer is never called.
        .filter(|f| unsafe { lib.get::<*const ()>(f.as_bytes()) }.is_err())
        .map(|f| format!("the binary does not export {f}"))
        .collect();
    if missing.is_empty() { Ok(lib) } else { Err(missing) }
}

/// The `depends` reports of a smoke run: their notes said on stderr ([`NOTE`]), their problems
/// added to the run's.
pub(super) fn add_reports(reports: Vec<Report>, problems: &mut Vec<String>) {
    for report in reports {
        for note in &report.notes {
            eprintln!("{NOTE}{note}");
        }
        problems.extend(report.problems);
    }
}

/// What the end of a 0.1 s run says: its worst status where it is not OK (0), with what the FMU
/// logged, and the first value that is not finite. `prefix`: `fmi2` or `fmi3`; `ty`: the name
/// of the values' type in that version (Real, Float64).
pub(super) fn run_problems(prefix: &str, worst: i64, log: &str, ty: &str, vrs: &[u32], values: &[f64]) -> Vec<String> {
    let mut problems = Vec::new();
    if worst != 0 {
        problems.push(format!(
            "a 0.1 s run from the start values did not return {prefix}OK (worst status {worst}): {log}"
        ));
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        problems.push(format!(
            "{ty} value reference {} is {} after the run",
            vrs[i], values[i]
        ));
    }
    problems
}
