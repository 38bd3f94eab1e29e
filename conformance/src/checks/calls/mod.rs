//! Bad and edge-case arguments of every kind an importer can pass, for every packaged FMU:
//! fmi2Instantiate, get/set, fmi2DoStep, fmi2Reset and logging. Each refusal must come with
//! fmi2Error, a logged reason, and the FMU state exactly as it was (compared byte for byte
//! through the serialized FMU state).
//!
//! On another exporter's FMU, the wording of the messages and this exporter's log categories
//! are not required, and fmi2Reset is tried from the states an importer can reach.

#![allow(non_upper_case_globals)] // fmi2OK etc. are the standard's names, matched on

use crate::Fmu;
use crate::fmi2::*;
use crate::instance::{Instance, status_name};
use crate::outcome::convention;

/// `(name, status)` of a raw call of the C API, with a breadcrumb naming it first (so that a
/// crash in it is reported with the call).
macro_rules! raw {
    ($name:literal, $call:expr) => {{
        crate::outcome::breadcrumb(concat!($name, ": ", stringify!($call)));
        ($name, $call)
    }};
}

mod do_step;
mod get_set;
mod instantiate;
mod logging;
mod output_derivatives;
pub use do_step::*;
pub use get_set::*;
pub use instantiate::*;
pub use logging::*;
pub use output_derivatives::*;

fn refused(inst: &Instance, what: &str, status: fmi2Status, must_say: &[&str]) {
    let log = inst.log();
    assert_eq!(
        status,
        fmi2Error,
        "{}: {what}: expected fmi2Error, got {}",
        inst.fmu.id,
        status_name(status)
    );
    assert!(
        inst.says(&log, fmi2Error, must_say),
        "{}: {what}: expected an error message containing {must_say:?}; log: {log:#?}",
        inst.fmu.id
    );
}

// ---- get and set ---------------------------------------------------------------------------

/// [`Instance::says`] for a log taken without an instance (a refused fmi2Instantiate).
fn says(fmu: &Fmu, log: &[crate::LogEntry], status: fmi2Status, words: &[&str]) -> bool {
    log.iter()
        .any(|e| e.status == status && words.iter().all(|w| e.text.contains(w)))
        || (!convention(fmu, "the wording of messages (which words name what is wrong)")
            && log.iter().any(|e| e.status == status))
}

fn initialized(fmu: &Fmu) -> Instance<'_> {
    let mut inst = Instance::new(fmu);
    inst.initialize();
    inst
}
