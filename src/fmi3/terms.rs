//! How FMI 3.0 says what the core speaks of: its function names, its state names (Step Mode
//! for 2.0's StepComplete, Step Discarded for StepFailed), and `instantiationToken`.

use crate::core::machine::State;
use crate::core::{Function, Terms, Version, table};

pub static TERMS: Terms = Terms {
    version: Version::Fmi3,
    functions: table!(function, Function),
    states: table!(state, State),
    token: "instantiationToken",
    fmu_state: "FMUState",
};

const fn function(f: Function) -> &'static str {
    match f {
        Function::SetDebugLogging => "fmi3SetDebugLogging",
        // FMI 3.0 has no fmi3SetupExperiment: the experiment comes with this call.
        Function::SetupExperiment => "fmi3EnterInitializationMode",
        Function::EnterInitializationMode => "fmi3EnterInitializationMode",
        Function::ExitInitializationMode => "fmi3ExitInitializationMode",
        Function::Terminate => "fmi3Terminate",
        Function::Reset => "fmi3Reset",
        Function::FreeInstance => "fmi3FreeInstance",
        Function::GetString => "fmi3GetString",
        Function::SetString => "fmi3SetString",
        Function::DoStep => "fmi3DoStep",
        Function::EnterEventMode => "fmi3EnterEventMode",
        Function::NewDiscreteStates => "fmi3UpdateDiscreteStates",
        Function::EnterContinuousTimeMode => "fmi3EnterContinuousTimeMode",
        Function::CompletedIntegratorStep => "fmi3CompletedIntegratorStep",
        Function::SetTime => "fmi3SetTime",
        Function::SetContinuousStates => "fmi3SetContinuousStates",
        Function::GetContinuousStates => "fmi3GetContinuousStates",
        Function::GetDerivatives => "fmi3GetContinuousStateDerivatives",
        Function::GetNominalsOfContinuousStates => "fmi3GetNominalsOfContinuousStates",
        Function::GetEventIndicators => "fmi3GetEventIndicators",
        Function::GetDirectionalDerivative => "fmi3GetDirectionalDerivative",
        Function::GetFmuState => "fmi3GetFMUState",
        Function::SetFmuState => "fmi3SetFMUState",
        Function::FreeFmuState => "fmi3FreeFMUState",
        Function::SerializedFmuStateSize => "fmi3SerializedFMUStateSize",
        Function::SerializeFmuState => "fmi3SerializeFMUState",
        Function::DeserializeFmuState => "fmi3DeserializeFMUState",
    }
}

/// FMI 3.0 renames two co-simulation states; the others are named as in 2.0. (The core's
/// `StepCanceled` is no state of FMI 3.0, which has no fmi3CancelStep: an instance of 3.0 never
/// enters it.)
const fn state(s: State) -> &'static str {
    match s {
        State::StepComplete => "StepMode",
        State::StepFailed => "StepDiscarded",
        other => other.name(),
    }
}

// The core answers in its own status values; they are FMI 3.0's.
const _: () = {
    use super::abi::*;
    use crate::core::*;
    assert!(fmi3OK == OK && fmi3Warning == WARNING && fmi3Discard == DISCARD);
    assert!(fmi3Error == ERROR && fmi3Fatal == FATAL);
};
