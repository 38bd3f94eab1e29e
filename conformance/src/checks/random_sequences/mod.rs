//! Random call sequences with random arguments through the C API of every packaged FMU
//! (proptest). A shadow model of the FMI 2.0 state machine predicts, for each call, whether it
//! is allowed and which state follows; the FMU must agree, and:
//! - never answer fmi2Fatal (a caught panic) or anything but OK/Warning/Discard/Error;
//! - refuse every call the state does not allow with fmi2Error and a message;
//! - change nothing when it answers fmi2Error (serialized FMU state compared byte for byte);
//! - refuse non-finite or non-positive step sizes, mismatched communication points, NULL
//!   FMU states and damaged serialized states;
//! - finish every call within 10 s (no hang);
//! - log only under declared categories, with "%s", to the right componentEnvironment.
//!
//! Cases: [`crate::random_sequences`] per FMU (`PROPTEST_CASES`, default 2000 sequences of up
//! to 99 calls: seconds per FMU), generated from the seed [`crate::seed`] (`$RUSTFMU_SEED`, else
//! drawn): each check records it in its report and in its failure message ([`crate::seed_note`]),
//! so that a failure in CI is repeated with `RUSTFMU_SEED=<seed>` and the same number of
//! sequences. A failing sequence is shrunk, printed, and then belongs in
//! `regressions_found_by_random_sequences` below.
//!
//! On another exporter's FMU the state machine is not read from the FMU (only this exporter's
//! serialized state shows it), serialized states are damaged only by truncation (bit flips may
//! be accepted by a format without checksum, and would then put the FMU in a state the shadow
//! cannot know), fmi2SetDebugLogging may answer anything for categories of this exporter, the
//! wording of refusals is not required, and calls of FMU-state functions the FMU does not
//! declare are left out.

#![allow(non_upper_case_globals)] // fmi2OK etc. are the standard's names, matched on

use crate::Fmu;
use proptest::prelude::*;
use proptest::test_runner::Config;

mod checks;
mod co_simulation;
mod model_exchange;
mod regressions;
mod text;
pub use checks::*;
pub use regressions::*;
pub use text::{replay, reproducer_of_a_random_sequence};

const SLOTS: usize = 3;

/// A value reference: one of the FMU's variables (by index, modulo their number) or any number.
#[derive(Debug, Clone, Copy)]
enum Vr {
    Known(usize),
    Raw(u32),
}

fn vr() -> impl Strategy<Value = Vr> {
    prop_oneof![
        8 => (0..64usize).prop_map(Vr::Known),
        1 => any::<u32>().prop_map(Vr::Raw),
    ]
}

fn real() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -2.0..2.0f64,
        1 => Just(0.0),
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => any::<f64>(),
        1 => -1e-14..1e-14f64,
    ]
}

fn resolve(fmu: &Fmu, v: Vr) -> u32 {
    match v {
        Vr::Known(i) => fmu.md.variables[i % fmu.md.variables.len()].vr,
        Vr::Raw(r) => r,
    }
}

/// What the shadow knows about the answer of an allowed call, beyond the state machine.
enum Expect {
    Anything,
    /// The arguments are invalid whatever the FMU: it must refuse.
    Refused,
    /// A valid call that must succeed (fmi2OK; for a step also fmi2Discard).
    Succeeds,
}

/// The runner's configuration: [`crate::random_sequences`] cases, the RNG seeded from
/// [`crate::seed`] (`$RUSTFMU_SEED`, else drawn once per process and printed).
fn config() -> Config {
    let cases = crate::random_sequences();
    crate::seeded(Config {
        cases,
        max_shrink_iters: 4096,
        failure_persistence: None,
        ..Config::default()
    })
}
