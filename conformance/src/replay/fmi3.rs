//! Which FMI 3.0 calls a reproducer can hold: the FMI 3.0 instance ([`crate::fmi3::Inst`])
//! records the others as not replayable, and [`crate::replay_calls`] makes these again.

/// The FMI 3.0 calls the replay makes that take no argument but the instance (their outputs are
/// printed), so that such a call made without [`crate::fmi3::Inst::args`] is replayable.
const FMI3_NO_ARGUMENTS: &[&str] = &[
    "fmi3ExitInitializationMode",
    "fmi3EnterEventMode",
    "fmi3EnterContinuousTimeMode",
    "fmi3EnterStepMode",
    "fmi3EnterConfigurationMode",
    "fmi3ExitConfigurationMode",
    "fmi3Terminate",
    "fmi3Reset",
    "fmi3UpdateDiscreteStates",
    "fmi3GetNumberOfContinuousStates",
    "fmi3GetNumberOfEventIndicators",
];

/// The other FMI 3.0 calls the replay makes, with the arguments the call log records, besides
/// the getters and setters of [`replays_values_of`] and every function of the FMU state.
const FMI3_WITH_ARGUMENTS: &[&str] = &[
    "fmi3EnterInitializationMode",
    "fmi3GetContinuousStates",
    "fmi3GetContinuousStateDerivatives",
    "fmi3GetEventIndicators",
    "fmi3GetNominalsOfContinuousStates",
    "fmi3SetTime",
    "fmi3SetContinuousStates",
    "fmi3CompletedIntegratorStep",
    "fmi3DoStep",
    "fmi3GetDirectionalDerivative",
    "fmi3GetAdjointDerivative",
    "fmi3GetString",
    "fmi3GetClock",
    "fmi3SetClock",
    "fmi3GetIntervalDecimal",
    "fmi3GetShiftDecimal",
    "fmi3GetBinary",
    "fmi3GetNumberOfVariableDependencies",
    "fmi3GetVariableDependencies",
    "fmi3SetDebugLogging",
];

/// Whether the replay gets and sets values of the type called `name`: the numbers and Boolean
/// (not String, Binary or Clock; an Enumeration's values are Int64's).
pub fn replays_values_of(name: &str) -> bool {
    use md_reader::fmi3::Type;
    Type::ALL
        .iter()
        .any(|t| t.name() == name && !matches!(t, Type::String | Type::Binary | Type::Enumeration | Type::Clock))
}

/// An FMI 3.0 call the replay makes, as the standard names it, and whether it takes no argument
/// but the instance ([`FMI3_NO_ARGUMENTS`]); `None` for a call the replay does not make (the call
/// log records it as not replayable).
pub fn fmi3_call(function: &str) -> Option<(&'static str, bool)> {
    let name = *fmi_standard::functions::FMI3_FUNCTIONS
        .iter()
        .find(|f| **f == function)?;
    let values = ["fmi3Get", "fmi3Set"]
        .iter()
        .any(|prefix| name.strip_prefix(prefix).is_some_and(replays_values_of));
    let no_arguments = FMI3_NO_ARGUMENTS.contains(&name);
    let state = name.contains("FMUState");
    (no_arguments || values || state || FMI3_WITH_ARGUMENTS.contains(&name)).then_some((name, no_arguments))
}
