//! The states of the FMI 3.0 state machine the suite drives an instance through, and the
//! conditions on setting a variable in each. Written from the standard, independently of any
//! exporter's own table.

use super::Variable;
use md_reader::{Causality, Initial, Variability};

/// The states of the FMI 3.0 state machine an importer can bring an instance into (without
/// event mode, clocks or structural parameters), for ME and CS.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum State {
    Instantiated,
    InitializationMode,
    EventMode,
    ContinuousTimeMode,
    StepMode,
    Terminated,
}

impl State {
    pub const ME: [State; 5] = [
        State::Instantiated,
        State::InitializationMode,
        State::EventMode,
        State::ContinuousTimeMode,
        State::Terminated,
    ];
    pub const CS: [State; 4] = [
        State::Instantiated,
        State::InitializationMode,
        State::StepMode,
        State::Terminated,
    ];
}

/// Whether FMI 3.0 lets an importer set this variable in that state (the conditions on
/// fmi3Set{VariableType} in the state machine: Instantiated: variability != constant with
/// initial exact or approx, and inputs; InitializationMode: initial exact, and inputs;
/// EventMode and StepMode: inputs and tunable parameters; ContinuousTimeMode: continuous
/// inputs).
pub fn settable_in(v: &Variable, state: State) -> bool {
    if v.variability == Variability::Constant || v.causality == Causality::Independent {
        return false;
    }
    let input = v.causality == Causality::Input;
    let tunable = v.causality == Causality::Parameter && v.variability == Variability::Tunable;
    match state {
        State::Instantiated => {
            input
                || matches!(
                    crate::standard::initial(v.causality, v.variability, v.declared_initial),
                    Some(Initial::Exact | Initial::Approx)
                )
        }
        State::InitializationMode => {
            input || crate::standard::initial(v.causality, v.variability, v.declared_initial) == Some(Initial::Exact)
        }
        State::EventMode | State::StepMode => input || tunable,
        State::ContinuousTimeMode => input && v.variability == Variability::Continuous && v.ty.is_float(),
        State::Terminated => false,
    }
}
