//! The states of the FMI 2.0 co-simulation state machine and the states in which the standard
//! allows each function (section 4.2.4; the Reference FMUs encode the same masks). Written from
//! the standard, independently of any exporter's own table.
//!
//! The suite keeps its own copy of the standard's rules (here the default `initial` too), written
//! from the standard's text, and does not use `fmi-standard`, the exporter's one copy: the suite
//! is the check of the exporter, and a mistake shared by both would pass unnoticed.

use crate::{Type, Variable};
use State::*;
use md_reader::{Causality, Initial, Variability};

/// `pub enum $ty` of the states of a state machine, numbered from 0 in the order written, and
/// `pub const $all`, every state, indexed by its discriminant (co-simulation here, model
/// exchange in [`crate::me`]).
macro_rules! state_machine {
    ($(#[$doc:meta])* $ty:ident, $all:ident: [$($state:ident),* $(,)?]) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum $ty {
            $($state,)*
        }

        /// Every state, indexed by its discriminant.
        pub const $all: [$ty; [$($ty::$state),*].len()] = [$($ty::$state),*];
    };
}
pub(crate) use state_machine;

state_machine!(
    /// A state of the co-simulation state machine. The discriminants (0 to 7, in this order) are
    /// also the numbering of the state byte in this exporter's serialized FMU state (see
    /// [`crate::state`]).
    State,
    STATES: [
        Instantiated,
        InitializationMode,
        StepComplete,
        StepFailed,
        StepCanceled,
        Terminated,
        Error,
        Fatal,
    ]
);

/// The states an importer reaches on any FMU by the standard's calls alone. StepFailed needs a
/// step the model cannot do, StepCanceled an asynchronous step, Error and Fatal an FMU that
/// failed: only an FMU whose serialized state the suite can rewrite is put there on purpose.
pub const REACHABLE: [State; 4] = [Instantiated, InitializationMode, StepComplete, Terminated];

/// Every state but Fatal (the last).
pub const ALL_BUT_FATAL: &[State] = STATES.split_at(7).0;
/// Every state but Instantiated (the first) and Fatal.
pub const GETTERS: &[State] = ALL_BUT_FATAL.split_at(1).1;
pub const SETTERS: &[State] = &[Instantiated, InitializationMode, StepComplete];
pub const STATUS: &[State] = &[StepComplete, StepFailed, Terminated];

/// Where `function` may be called. fmi2CancelStep only in StepInProgress, which a synchronous
/// FMU never enters; fmi2Terminate not after fmi2CancelStep (StepCanceled).
pub fn allowed_states(function: &str) -> &'static [State] {
    match function {
        "fmi2SetDebugLogging"
        | "fmi2Reset"
        | "fmi2GetFMUstate"
        | "fmi2SetFMUstate"
        | "fmi2FreeFMUstate"
        | "fmi2SerializedFMUstateSize"
        | "fmi2SerializeFMUstate"
        | "fmi2DeSerializeFMUstate" => ALL_BUT_FATAL,
        "fmi2SetupExperiment" | "fmi2EnterInitializationMode" => &[Instantiated],
        "fmi2ExitInitializationMode" => &[InitializationMode],
        "fmi2Terminate" => &[StepComplete, StepFailed],
        "fmi2GetReal" | "fmi2GetInteger" | "fmi2GetBoolean" | "fmi2GetString" | "fmi2GetDirectionalDerivative" => {
            GETTERS
        }
        "fmi2SetReal" | "fmi2SetInteger" | "fmi2SetBoolean" | "fmi2SetString" | "fmi2SetRealInputDerivatives" => {
            SETTERS
        }
        "fmi2GetRealOutputDerivatives" => &[StepComplete, StepFailed, StepCanceled, Terminated, Error],
        "fmi2DoStep" => &[StepComplete],
        "fmi2CancelStep" => &[],
        "fmi2GetStatus"
        | "fmi2GetRealStatus"
        | "fmi2GetIntegerStatus"
        | "fmi2GetBooleanStatus"
        | "fmi2GetStringStatus" => STATUS,
        other => panic!("{other} is not a co-simulation function with a state"),
    }
}

/// The `initial` in force: the written one, or the default of the table causality ×
/// variability (FMI 2.0 section 2.2.7: exact for constants and parameters, calculated for
/// calculated parameters, outputs and locals; none for inputs and the independent variable; FMI
/// 3.0 section 2.4.7.4 the same, and exact for structural parameters). The suite's own copy.
pub fn initial(causality: Causality, variability: Variability, written: Option<Initial>) -> Option<Initial> {
    written.or(match (causality, variability) {
        (Causality::Input | Causality::Independent, _) => None,
        (_, Variability::Constant) | (Causality::Parameter | Causality::StructuralParameter, _) => Some(Initial::Exact),
        (Causality::CalculatedParameter | Causality::Output | Causality::Local, _) => Some(Initial::Calculated),
    })
}

/// Whether `v` is an alias of a variable listed before it in `all`: the same value reference and
/// the same C type (FMI 2.0, 2.2.7: a value reference is unique per base type "with exception of
/// variables that have identical values (such variables are also called alias variables)"). The
/// FMU sees one variable through all the names of an alias set, so where it may be set is checked
/// once, on the first of them; that an importer must not set the others where their own
/// attributes forbid it is the importer's part.
pub fn aliases_an_earlier(all: &[Variable], v: &Variable) -> bool {
    let c_type = |t: Type| match t {
        Type::Enumeration => Type::Integer,
        other => other,
    };
    all.iter()
        .take_while(|o| !std::ptr::eq(*o, v))
        .any(|o| o.vr == v.vr && c_type(o.ty) == c_type(v.ty))
}

/// Whether FMI 2.0 (section 4.2.4, the conditions on fmi2SetXXX in the co-simulation state
/// table) lets an importer set this variable in the state of that name. Written here from
/// the standard, independently of the runtime's own rule.
pub fn settable_in(v: &Variable, state: &str) -> bool {
    if v.variability == Variability::Constant {
        return false;
    }
    let input = v.causality == Causality::Input;
    match state {
        // "variability != constant that have initial = exact or approx" (and inputs, whose
        // start values an importer sets before initialization)
        "Instantiated" => {
            input
                || matches!(
                    crate::standard::initial(v.causality, v.variability, v.declared_initial),
                    Some(Initial::Exact | Initial::Approx)
                )
        }
        // "variability != constant that have initial = exact, or causality = input"
        "InitializationMode" => {
            input || crate::standard::initial(v.causality, v.variability, v.declared_initial) == Some(Initial::Exact)
        }
        // "causality = input, or causality = parameter and variability = tunable"
        "StepComplete" => input || (v.causality == Causality::Parameter && v.variability == Variability::Tunable),
        _ => false,
    }
}

/// Whether FMI 2.0 (section 3.2.3, the conditions on fmi2SetXXX in the model-exchange state
/// table) lets an importer set this variable in that model-exchange state. Instantiated and
/// InitializationMode are as in co-simulation; EventMode as StepComplete; in
/// ContinuousTimeMode only continuous Real inputs.
pub fn settable_in_me(v: &Variable, state: &str) -> bool {
    match state {
        "EventMode" => settable_in(v, "StepComplete"),
        "ContinuousTimeMode" => {
            v.ty == Type::Real && v.causality == Causality::Input && v.variability == Variability::Continuous
        }
        other => settable_in(v, other),
    }
}
