//! The smoke run: a short run of this machine's binary through the C API as an importer makes
//! it (FMI 2.0 in [`super::smoke2`], FMI 3.0 in [`super::smoke3`]), in a child process.

use super::archive::Description;
use super::run::NOTE;
use super::{smoke_run, smoke_run3};
use rustfmu::description::FmiVersion;
use std::path::Path;

/// `resources`: the unpacked archive's `resources/` folder, given to the instance as an importer
/// gives it after unpacking (a model that reads its resources at instantiation must find them).
pub(super) fn smoke_run_in_child(so: &Path, d: &Description, resources: &Path) -> Vec<String> {
    let vrs: Vec<String> = d.real_vrs.iter().map(|v| v.to_string()).collect();
    let exe = match std::env::current_exe() {
        Ok(e) if e.file_stem().is_some_and(|s| s == "cargo-fmu" || s == "fmu-build") => e,
        // Called from elsewhere (tests): run in this process.
        _ => return smoke_run_version(d.version, so, &d.guid, &d.real_vrs, resources, d.clocks),
    };
    let mut command = std::process::Command::new(&exe);
    command
        .arg("__smoke-run")
        .arg(so)
        .arg(&d.guid)
        .arg(vrs.join(","))
        .arg("--fmi-version")
        .arg(d.version.text())
        .arg("--resources")
        .arg(resources);
    if d.clocks {
        command.arg("--event-mode");
    }
    match command.output() {
        Ok(out) if out.status.success() => {
            forward_notes(&out.stderr);
            vec![]
        }
        Ok(out) => {
            forward_notes(&out.stderr);
            let said = String::from_utf8_lossy(&out.stdout)
                .lines()
                .map(str::to_string)
                .collect::<Vec<_>>();
            if said.is_empty() {
                let err = String::from_utf8_lossy(&out.stderr);
                let tail: Vec<&str> = err
                    .lines()
                    .rev()
                    .take(5)
                    .collect::<Vec<_>>()
                    .into_iter()
                    .rev()
                    .collect();
                vec![format!("the smoke run crashed ({}): {}", out.status, tail.join(" | "))]
            } else {
                said
            }
        }
        Err(e) => vec![format!("cannot start the smoke run ({}): {e}", exe.display())],
    }
}

/// The child's notes ([`NOTE`]), printed by the parent.
fn forward_notes(stderr: &[u8]) {
    for line in String::from_utf8_lossy(stderr).lines().filter(|l| l.starts_with(NOTE)) {
        eprintln!("{line}");
    }
}

/// [`smoke_run`] (FMI 2.0) or [`smoke_run3`] (FMI 3.0).
pub fn smoke_run_version(
    version: FmiVersion,
    so: &Path,
    guid: &str,
    real_vrs: &[u32],
    resources: &Path,
    event_mode: bool,
) -> Vec<String> {
    match version {
        FmiVersion::V2 => smoke_run(so, guid, real_vrs, resources),
        FmiVersion::V3 => smoke_run3(so, guid, real_vrs, resources, event_mode),
    }
}
