//! How FMI 3.0 says what the core speaks of: its function names (the second column of the
//! core's table of both versions' names), its state names (Step Mode for 2.0's StepComplete,
//! Step Discarded for StepFailed), and `instantiationToken`.

use crate::core::machine::State;
use crate::core::{Terms, Version};

/// The functions' names of `crate::core::c_names`. FMI 3.0 renames two co-simulation states;
/// the others are named as in 2.0. (The core's `StepCanceled` is no state of FMI 3.0, which has
/// no fmi3CancelStep: an instance of 3.0 never enters it.)
pub static TERMS: Terms = Terms::of(
    Version::Fmi3,
    "instantiationToken",
    "FMUState",
    &[(State::StepComplete, "StepMode"), (State::StepFailed, "StepDiscarded")],
);

// The core answers in its own status values; they are FMI 3.0's.
const _: () = {
    use super::abi::*;
    use crate::core::*;
    assert!(fmi3OK == OK && fmi3Warning == WARNING && fmi3Discard == DISCARD);
    assert!(fmi3Error == ERROR && fmi3Fatal == FATAL);
};
