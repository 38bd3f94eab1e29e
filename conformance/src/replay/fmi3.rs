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
    "fmi3EvaluateDiscreteStates",
];

/// The other FMI 3.0 calls the replay makes, with the arguments the call log records, besides
/// the getters and setters of [`replays_values_of`], every function of the FMU state and the
/// calls of no variable ([`takes_no_variable`]).
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
    "fmi3GetOutputDerivatives",
    "fmi3ActivateModelPartition",
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
    let listed = FMI3_WITH_ARGUMENTS.contains(&name) || takes_no_variable(name).is_some();
    (no_arguments || values || state || listed).then_some((name, no_arguments))
}

/// `function` as the standard names it where [`crate::fmi3::Inst::with_no_variable`] calls it: a
/// getter or setter of the values of a type (Strings, Binaries and Clocks too), of intervals or of
/// shifts.
pub fn takes_no_variable(function: &str) -> Option<&'static str> {
    let name = *fmi_standard::functions::FMI3_FUNCTIONS
        .iter()
        .find(|f| **f == function)?;
    let rest = name.strip_prefix("fmi3Get").or_else(|| name.strip_prefix("fmi3Set"))?;
    let of_type = md_reader::fmi3::Type::ALL.iter().any(|t| t.name() == rest);
    (of_type || rest.starts_with("Interval") || rest.starts_with("Shift")).then_some(name)
}
