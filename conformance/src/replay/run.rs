//! Running a reproducer again ([`replay`]): a named check's through [`crate::replay_calls`], a
//! random sequence's through its check's own replay.

use super::{ReplayReport, parse_file};
use std::path::Path;

/// Replays the reproducer `file` on the FMU file `fmu` in this process, printing each call as it
/// goes through `out`. Err: the file or the FMU could not be read.
pub fn replay(file: &Path, fmu: &Path, out: &mut dyn FnMut(&str)) -> Result<ReplayReport, String> {
    let text = std::fs::read_to_string(file).map_err(|e| format!("{}: {e}", file.display()))?;
    let lines = parse_file(&text).map_err(|e| format!("{}: {e}", file.display()))?;
    let root = crate::unpack_root()?;
    let version = crate::file_version(fmu)?;
    let first = &lines[0];
    // The checks' own assertions panic: a panic is a difference too, with its message.
    let caught = |run: &mut dyn FnMut() -> Result<ReplayReport, String>| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(run)).unwrap_or_else(|payload| {
            let message = payload
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "a panic without a message".into());
            Ok(ReplayReport {
                lines: vec![],
                difference: Some(message),
            })
        })
    };
    // A named check's reproducer names its instance; a random sequence's does not.
    let named = first.has("instanceName");
    let report = match (version, first.function.as_str()) {
        (crate::Version::Fmi2, "fmi2Instantiate") if named => {
            let loaded = crate::Fmu::load(fmu, &root)?;
            caught(&mut || crate::replay_calls::replay2(&loaded, &lines, out))
        }
        (crate::Version::Fmi3, "fmi3InstantiateCoSimulation" | "fmi3InstantiateModelExchange") if named => {
            let loaded = crate::Fmu3::load(fmu, &root)?;
            caught(&mut || crate::replay_calls::replay3(&loaded, &lines, out))
        }
        (crate::Version::Fmi2, "fmi2Instantiate") => {
            let loaded = crate::Fmu::load(fmu, &root)?;
            caught(&mut || crate::checks::random_sequences::replay(&loaded, &lines, out))
        }
        (crate::Version::Fmi3, "fmi3InstantiateCoSimulation" | "fmi3InstantiateModelExchange") => {
            let loaded = crate::Fmu3::load(fmu, &root)?;
            caught(&mut || crate::fmi3::checks::replay(&loaded, &lines, out))
        }
        (v, f) => Err(format!(
            "{}: the first call is {f}, which does not instantiate an FMU of {} (FMI {})",
            file.display(),
            fmu.display(),
            match v {
                crate::Version::Fmi2 => "2.0: fmi2Instantiate",
                crate::Version::Fmi3 => "3.0: fmi3InstantiateCoSimulation or fmi3InstantiateModelExchange",
            }
        )),
    };
    report.map_err(|e| format!("{}: {e}", file.display()))
}
