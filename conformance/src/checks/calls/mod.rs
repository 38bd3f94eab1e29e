//! Bad and edge-case arguments of every kind an importer can pass, for every packaged FMU:
//! fmi2Instantiate, get/set, fmi2DoStep, fmi2Reset and logging. Each refusal must come with
//! fmi2Error, a logged reason, and the FMU state exactly as it was (compared through what the
//! getters show; byte for byte through the serialized FMU state on this exporter's FMUs and
//! under `--strict`). Verdicts: these calls are the importer's mistakes, which FMI 2.0.5 leaves
//! undefined (§2.1.3: after fmi2Error "the simulation cannot be continued with this FMU
//! instance"), so what the FMU does with them is a warning (`refused`,
//! [`Instance::warn_if_changed`]), never a failure; a failure stays for what the standard
//! requires of a legal call.
//!
//! On another exporter's FMU, the wording of the messages and this exporter's log categories
//! are not required, and fmi2Reset is tried from the states an importer can reach.

#![allow(non_upper_case_globals)] // fmi2OK etc. are the standard's names, matched on

use crate::Fmu;
use crate::fmi2::*;
use crate::instance::{Instance, status_name};
use crate::outcome::convention;

mod do_step;
mod get_set;
mod instantiate;
mod logging;
mod named_defects;
mod output_derivatives;
pub use do_step::*;
pub use get_set::*;
pub use instantiate::*;
pub use logging::*;
pub use named_defects::*;
pub use output_derivatives::*;

/// An importer's mistake made on purpose (`what`) should be refused with fmi2Error and a message:
/// a warning otherwise. FMI 2.0.5 requires no detection of an importer's mistakes (§2.1.3: on
/// fmi2Error "the simulation cannot be continued with this FMU instance"); an FMU that detects
/// them tells its user what went wrong instead of computing on garbage.
fn refused(inst: &Instance, what: &str, status: fmi2Status, must_say: &[&str]) {
    let log = inst.log();
    if status != fmi2Error {
        crate::outcome::warn(format!(
            "{}: {what}: expected fmi2Error, got {} (an importer's mistake the FMU did not detect; FMI 2.0.5 leaves it undefined)",
            inst.fmu.id,
            status_name(status)
        ));
    } else if !inst.says(&log, fmi2Error, must_say) {
        crate::outcome::warn(format!(
            "{}: {what}: refused without a message containing {must_say:?} (the user is not told why); log: {log:?}",
            inst.fmu.id
        ));
    }
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
