//! Isolation needs Linux (shared memory and futexes): elsewhere a system process cannot start.

use super::options::{Isolation, SystemInfo};
use crate::Error;
use std::path::Path;

/// Isolation needs Linux (shared memory and futexes): elsewhere a system cannot be started.
pub struct SystemProcess(SystemInfo);

impl SystemProcess {
    pub fn spawn(_iso: Isolation, ssp: &Path, _jacobi: bool, _event_mode: &[String]) -> Result<SystemProcess, Error> {
        Err(Error::unsupported(
            None,
            None,
            format!("{}: isolation (child processes) runs on Linux only", ssp.display()),
        ))
    }
    pub fn info(&self) -> &SystemInfo {
        &self.0
    }
    pub fn run(&mut self, _opts: &crate::RunOptions) -> Result<crate::RunResult, crate::sim::Failure> {
        unreachable!("never spawned")
    }
}
