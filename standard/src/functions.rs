//! The functions each FMI standard declares (`fmi2Functions.h`, `fmi3Functions.h`), by name:
//! what a binary must export (`cargo fmu` checks a built binary against these lists) and what an
//! importer looks up (the conformance suite).

/// The getters and setters of variables' values, of both FMI 2.0 interfaces.
pub const FMI2_VALUE_FUNCTIONS: [&str; 8] = [
    "fmi2GetReal",
    "fmi2GetInteger",
    "fmi2GetBoolean",
    "fmi2GetString",
    "fmi2SetReal",
    "fmi2SetInteger",
    "fmi2SetBoolean",
    "fmi2SetString",
];

/// The functions FMI 2.0's co-simulation and model exchange interfaces share
/// (`fmi2Functions.h`, "common functions").
pub const FMI2_COMMON_FUNCTIONS: &[&str] = &concat::<25>(
    &concat::<18>(
        &[
            "fmi2GetTypesPlatform",
            "fmi2GetVersion",
            "fmi2SetDebugLogging",
            "fmi2Instantiate",
            "fmi2FreeInstance",
            "fmi2SetupExperiment",
            "fmi2EnterInitializationMode",
            "fmi2ExitInitializationMode",
            "fmi2Terminate",
            "fmi2Reset",
        ],
        &FMI2_VALUE_FUNCTIONS,
    ),
    &[
        "fmi2GetFMUstate",
        "fmi2SetFMUstate",
        "fmi2FreeFMUstate",
        "fmi2SerializedFMUstateSize",
        "fmi2SerializeFMUstate",
        "fmi2DeSerializeFMUstate",
        "fmi2GetDirectionalDerivative",
    ],
);

/// The functions of FMI 2.0's co-simulation interface that model exchange does not have: an
/// instance of fmuType fmi2ModelExchange refuses them in every state.
pub const FMI2_CS_ONLY_FUNCTIONS: &[&str] = &[
    "fmi2SetRealInputDerivatives",
    "fmi2GetRealOutputDerivatives",
    "fmi2DoStep",
    "fmi2CancelStep",
    "fmi2GetStatus",
    "fmi2GetRealStatus",
    "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus",
    "fmi2GetStringStatus",
];

/// Every function of the FMI 2.0 co-simulation interface.
pub const FMI2_CS_FUNCTIONS: &[&str] = &concat::<34>(FMI2_COMMON_FUNCTIONS, FMI2_CS_ONLY_FUNCTIONS);

/// The functions of FMI 2.0's model exchange interface that co-simulation does not have.
pub const FMI2_ME_ONLY_FUNCTIONS: &[&str] = &[
    "fmi2EnterEventMode",
    "fmi2NewDiscreteStates",
    "fmi2EnterContinuousTimeMode",
    "fmi2CompletedIntegratorStep",
    "fmi2SetTime",
    "fmi2SetContinuousStates",
    "fmi2GetDerivatives",
    "fmi2GetEventIndicators",
    "fmi2GetContinuousStates",
    "fmi2GetNominalsOfContinuousStates",
];

/// Every function of the FMI 2.0 standard (model exchange and co-simulation), as
/// `fmi2Functions.h` declares them: an FMI 3.0 binary exports all of them (a binary of both
/// versions) or none.
pub const FMI2_FUNCTIONS: &[&str] = &concat::<44>(FMI2_CS_FUNCTIONS, FMI2_ME_ONLY_FUNCTIONS);

/// `a` then `b`, as one array of `N` (their lengths' sum: another `N` fails to compile).
const fn concat<const N: usize>(a: &[&'static str], b: &[&'static str]) -> [&'static str; N] {
    assert!(a.len() + b.len() == N);
    let mut out = [""; N];
    let mut i = 0;
    while i < N {
        out[i] = if i < a.len() { a[i] } else { b[i - a.len()] };
        i += 1;
    }
    out
}

/// `all` without the functions of `leave_out`, in order, as one array of `N` (how many are left:
/// another `N` fails to compile).
pub const fn without<const N: usize>(all: &[&'static str], leave_out: &[&str]) -> [&'static str; N] {
    /// `a == b` (which a const fn cannot write for `&str`).
    const fn same(a: &str, b: &str) -> bool {
        let (a, b) = (a.as_bytes(), b.as_bytes());
        let mut i = 0;
        while i < a.len() && i < b.len() && a[i] == b[i] {
            i += 1;
        }
        i == a.len() && i == b.len()
    }
    let mut out = [""; N];
    let (mut i, mut n) = (0, 0);
    while i < all.len() {
        let mut j = 0;
        while j < leave_out.len() && !same(all[i], leave_out[j]) {
            j += 1;
        }
        if j == leave_out.len() {
            out[n] = all[i];
            n += 1;
        }
        i += 1;
    }
    assert!(n == N);
    out
}

/// Every function of the FMI 3.0 standard, as `fmi3Functions.h` declares them (75): an FMI 3.0
/// binary exports all of them (those it does not support refuse with fmi3Error), an FMI 2.0
/// binary all of them (a binary of both versions) or none.
pub const FMI3_FUNCTIONS: &[&str] = &[
    "fmi3GetVersion",
    "fmi3SetDebugLogging",
    "fmi3InstantiateModelExchange",
    "fmi3InstantiateCoSimulation",
    "fmi3InstantiateScheduledExecution",
    "fmi3FreeInstance",
    "fmi3EnterInitializationMode",
    "fmi3ExitInitializationMode",
    "fmi3EnterEventMode",
    "fmi3Terminate",
    "fmi3Reset",
    "fmi3GetFloat32",
    "fmi3GetFloat64",
    "fmi3GetInt8",
    "fmi3GetUInt8",
    "fmi3GetInt16",
    "fmi3GetUInt16",
    "fmi3GetInt32",
    "fmi3GetUInt32",
    "fmi3GetInt64",
    "fmi3GetUInt64",
    "fmi3GetBoolean",
    "fmi3GetString",
    "fmi3GetBinary",
    "fmi3GetClock",
    "fmi3SetFloat32",
    "fmi3SetFloat64",
    "fmi3SetInt8",
    "fmi3SetUInt8",
    "fmi3SetInt16",
    "fmi3SetUInt16",
    "fmi3SetInt32",
    "fmi3SetUInt32",
    "fmi3SetInt64",
    "fmi3SetUInt64",
    "fmi3SetBoolean",
    "fmi3SetString",
    "fmi3SetBinary",
    "fmi3SetClock",
    "fmi3GetNumberOfVariableDependencies",
    "fmi3GetVariableDependencies",
    "fmi3GetFMUState",
    "fmi3SetFMUState",
    "fmi3FreeFMUState",
    "fmi3SerializedFMUStateSize",
    "fmi3SerializeFMUState",
    "fmi3DeserializeFMUState",
    "fmi3GetDirectionalDerivative",
    "fmi3GetAdjointDerivative",
    "fmi3EnterConfigurationMode",
    "fmi3ExitConfigurationMode",
    "fmi3GetIntervalDecimal",
    "fmi3GetIntervalFraction",
    "fmi3GetShiftDecimal",
    "fmi3GetShiftFraction",
    "fmi3SetIntervalDecimal",
    "fmi3SetIntervalFraction",
    "fmi3SetShiftDecimal",
    "fmi3SetShiftFraction",
    "fmi3EvaluateDiscreteStates",
    "fmi3UpdateDiscreteStates",
    "fmi3EnterContinuousTimeMode",
    "fmi3CompletedIntegratorStep",
    "fmi3SetTime",
    "fmi3SetContinuousStates",
    "fmi3GetContinuousStateDerivatives",
    "fmi3GetEventIndicators",
    "fmi3GetContinuousStates",
    "fmi3GetNominalsOfContinuousStates",
    "fmi3GetNumberOfEventIndicators",
    "fmi3GetNumberOfContinuousStates",
    "fmi3EnterStepMode",
    "fmi3GetOutputDerivatives",
    "fmi3DoStep",
    "fmi3ActivateModelPartition",
];
