//! How FMI 2.0 says what the core speaks of: its function names, its state names (the
//! standard's, section 4.2.4 and 3.2.3), and `GUID`.

use crate::core::machine::State;
use crate::core::{Function, Terms, Version, table};

pub static TERMS: Terms = Terms {
    version: Version::Fmi2,
    functions: table!(function, Function),
    states: table!(state, State),
    token: "GUID",
    fmu_state: "FMUstate",
};

const fn function(f: Function) -> &'static str {
    match f {
        Function::SetDebugLogging => "fmi2SetDebugLogging",
        Function::SetupExperiment => "fmi2SetupExperiment",
        Function::EnterInitializationMode => "fmi2EnterInitializationMode",
        Function::ExitInitializationMode => "fmi2ExitInitializationMode",
        Function::Terminate => "fmi2Terminate",
        Function::Reset => "fmi2Reset",
        Function::FreeInstance => "fmi2FreeInstance",
        Function::GetString => "fmi2GetString",
        Function::SetString => "fmi2SetString",
        Function::DoStep => "fmi2DoStep",
        Function::EnterEventMode => "fmi2EnterEventMode",
        Function::NewDiscreteStates => "fmi2NewDiscreteStates",
        Function::EnterContinuousTimeMode => "fmi2EnterContinuousTimeMode",
        Function::CompletedIntegratorStep => "fmi2CompletedIntegratorStep",
        Function::SetTime => "fmi2SetTime",
        Function::SetContinuousStates => "fmi2SetContinuousStates",
        Function::GetContinuousStates => "fmi2GetContinuousStates",
        Function::GetDerivatives => "fmi2GetDerivatives",
        Function::GetNominalsOfContinuousStates => "fmi2GetNominalsOfContinuousStates",
        Function::GetEventIndicators => "fmi2GetEventIndicators",
        Function::GetDirectionalDerivative => "fmi2GetDirectionalDerivative",
        Function::GetFmuState => "fmi2GetFMUstate",
        Function::SetFmuState => "fmi2SetFMUstate",
        Function::FreeFmuState => "fmi2FreeFMUstate",
        Function::SerializedFmuStateSize => "fmi2SerializedFMUstateSize",
        Function::SerializeFmuState => "fmi2SerializeFMUstate",
        Function::DeserializeFmuState => "fmi2DeSerializeFMUstate",
    }
}

/// The core's state names are FMI 2.0's.
const fn state(s: State) -> &'static str {
    s.name()
}

// The core answers in its own status values; they are FMI 2.0's.
const _: () = {
    use super::abi::*;
    use crate::core::*;
    assert!(fmi2OK == OK && fmi2Warning == WARNING && fmi2Discard == DISCARD);
    assert!(fmi2Error == ERROR && fmi2Fatal == FATAL);
};
