//! How a system is isolated ([`Isolation`], [`Granularity`]), the binary its children run
//! ([`find_worker`]), and the crumbs where there are no children (not Linux).

use crate::Error;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Where an isolated system's child is (nothing outside one; Linux only).
#[cfg(not(target_os = "linux"))]
#[inline]
pub fn crumb(_instance: usize, _method: &'static str) {}

/// The time of the calls that follow (an isolated system's child).
#[cfg(not(target_os = "linux"))]
#[inline]
pub fn crumb_time(_t: f64) {}

/// What a system's child tells about the system it loaded.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct SystemInfo {
    pub name: String,
    pub evaluation_order: Vec<String>,
    pub components: Vec<(String, String)>,
    pub outputs: Vec<String>,
    pub parameters: Vec<String>,
}

/// How much of the system a child process holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Granularity {
    /// Each component in a process of its own: one FMU cannot touch another's memory.
    Component,
    /// The whole system (every FMU and the master) in one process per run of it: the runner
    /// lives on, a crash is reported at the component, function and time it happened in.
    System,
}

/// How an isolated component is instantiated in its process.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interface {
    /// Co-simulation (FMI 3.0: eventModeUsed where the runner ticks its input clocks).
    CoSimulation,
    /// Model exchange, integrated by the runner in the child ([`crate::me`]).
    ModelExchange,
    /// FMI 3.0 co-simulation with eventModeUsed and earlyReturnAllowed
    /// ([`crate::Simulation::use_event_mode`]).
    EventMode,
    /// FMI 3.0 Scheduled Execution: the partitions activated by the child's importer
    /// ([`crate::Simulation::use_scheduled_execution`]).
    ScheduledExecution,
}

/// How the components of a system are isolated.
#[derive(Debug, Clone)]
pub struct Isolation {
    /// The `rustfmu-runner` binary that serves a component ([`find_worker`]).
    pub worker: PathBuf,
    /// The longest a single call may take before its process is killed (None: no limit).
    pub timeout: Option<Duration>,
}

/// The runner binary a child process runs: `explicit`, else $RUSTFMU_RUNNER, else
/// `rustfmu-runner` beside this program, in `also` (a Python environment's scripts folder), or
/// on PATH.
pub fn find_worker(explicit: Option<&Path>, also: &[PathBuf]) -> Result<PathBuf, Error> {
    let name = format!("rustfmu-runner{}", std::env::consts::EXE_SUFFIX);
    if let Some(p) = explicit {
        return if p.is_file() {
            Ok(p.to_path_buf())
        } else {
            Err(Error::usage(format!(
                "isolation: the worker {} is not a file (the rustfmu-runner binary)",
                p.display()
            )))
        };
    }
    let mut tried = Vec::new();
    let mut candidates: Vec<PathBuf> = Vec::new();
    if let Some(p) = std::env::var_os("RUSTFMU_RUNNER") {
        candidates.push(PathBuf::from(p));
    }
    if let Ok(exe) = std::env::current_exe()
        && let Some(dir) = exe.parent()
    {
        candidates.push(dir.join(&name));
    }
    candidates.extend(also.iter().map(|d| d.join(&name)));
    if let Some(path) = std::env::var_os("PATH") {
        candidates.extend(std::env::split_paths(&path).map(|d| d.join(&name)));
    }
    for c in candidates {
        if c.is_file() {
            return Ok(c);
        }
        tried.push(c.display().to_string());
    }
    Err(Error::usage(format!(
        "isolation needs the rustfmu-runner binary (each component runs in a child process of it): \
         set RUSTFMU_RUNNER to it, or put it on PATH (`cargo install --path runner`); looked at {}",
        tried.join(", ")
    )))
}
