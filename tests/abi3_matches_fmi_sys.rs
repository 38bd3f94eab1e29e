//! The exported FMI 3.0 C ABI, proved equal at compile time to the official FMI 3.0 headers as
//! bindgen translates them in `fmi-sys` (as `abi_matches_fmi_sys.rs` does for FMI 2.0): every
//! one of the standard's 75 functions, with its exact signature. If one drifts, this
//! file stops compiling.

use fmi_sys::fmi3 as sys;

// The FMI 3.0 export macro expanded into this test binary, for a model of one variable.
mod model {
    use rustfmu::prelude::*;

    /// A constant output.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    pub struct Probe3 {
        /// An output
        #[variable(vr = 0, output, initial = exact, start = 1.0, depends = [])]
        pub y: f64,
    }

    impl Model for Probe3 {}
    impl CoSimulation for Probe3 {
        fn do_step(&mut self, _t: f64, _h: f64, _ctx: &mut Context) -> Result<(), StepFailure> {
            Ok(())
        }
    }

    rustfmu::export_fmi3!(Probe3);
}
use model::__rustfmu_fmi3_exports::*;

macro_rules! same_signature {
    ($($f:ident: $t:ident),* $(,)?) => {
        $(const _: sys::$t = Some($f);)*
    };
}

same_signature!(
    fmi3GetVersion: fmi3GetVersionTYPE,
    fmi3SetDebugLogging: fmi3SetDebugLoggingTYPE,
    fmi3InstantiateModelExchange: fmi3InstantiateModelExchangeTYPE,
    fmi3InstantiateCoSimulation: fmi3InstantiateCoSimulationTYPE,
    fmi3InstantiateScheduledExecution: fmi3InstantiateScheduledExecutionTYPE,
    fmi3FreeInstance: fmi3FreeInstanceTYPE,
    fmi3EnterInitializationMode: fmi3EnterInitializationModeTYPE,
    fmi3ExitInitializationMode: fmi3ExitInitializationModeTYPE,
    fmi3EnterEventMode: fmi3EnterEventModeTYPE,
    fmi3Terminate: fmi3TerminateTYPE,
    fmi3Reset: fmi3ResetTYPE,
    fmi3GetFloat32: fmi3GetFloat32TYPE,
    fmi3GetInt8: fmi3GetInt8TYPE,
    fmi3GetUInt8: fmi3GetUInt8TYPE,
    fmi3GetInt16: fmi3GetInt16TYPE,
    fmi3GetUInt16: fmi3GetUInt16TYPE,
    fmi3GetUInt32: fmi3GetUInt32TYPE,
    fmi3GetUInt64: fmi3GetUInt64TYPE,
    fmi3GetFloat64: fmi3GetFloat64TYPE,
    fmi3GetInt32: fmi3GetInt32TYPE,
    fmi3GetInt64: fmi3GetInt64TYPE,
    fmi3GetBoolean: fmi3GetBooleanTYPE,
    fmi3GetString: fmi3GetStringTYPE,
    fmi3SetFloat32: fmi3SetFloat32TYPE,
    fmi3SetInt8: fmi3SetInt8TYPE,
    fmi3SetUInt8: fmi3SetUInt8TYPE,
    fmi3SetInt16: fmi3SetInt16TYPE,
    fmi3SetUInt16: fmi3SetUInt16TYPE,
    fmi3SetUInt32: fmi3SetUInt32TYPE,
    fmi3SetUInt64: fmi3SetUInt64TYPE,
    fmi3SetFloat64: fmi3SetFloat64TYPE,
    fmi3SetInt32: fmi3SetInt32TYPE,
    fmi3SetInt64: fmi3SetInt64TYPE,
    fmi3SetBoolean: fmi3SetBooleanTYPE,
    fmi3SetString: fmi3SetStringTYPE,
    fmi3GetBinary: fmi3GetBinaryTYPE,
    fmi3SetBinary: fmi3SetBinaryTYPE,
    fmi3GetClock: fmi3GetClockTYPE,
    fmi3SetClock: fmi3SetClockTYPE,
    fmi3GetNumberOfVariableDependencies: fmi3GetNumberOfVariableDependenciesTYPE,
    fmi3GetVariableDependencies: fmi3GetVariableDependenciesTYPE,
    fmi3GetFMUState: fmi3GetFMUStateTYPE,
    fmi3SetFMUState: fmi3SetFMUStateTYPE,
    fmi3FreeFMUState: fmi3FreeFMUStateTYPE,
    fmi3SerializedFMUStateSize: fmi3SerializedFMUStateSizeTYPE,
    fmi3SerializeFMUState: fmi3SerializeFMUStateTYPE,
    fmi3DeserializeFMUState: fmi3DeserializeFMUStateTYPE,
    fmi3GetDirectionalDerivative: fmi3GetDirectionalDerivativeTYPE,
    fmi3GetAdjointDerivative: fmi3GetAdjointDerivativeTYPE,
    fmi3EnterConfigurationMode: fmi3EnterConfigurationModeTYPE,
    fmi3ExitConfigurationMode: fmi3ExitConfigurationModeTYPE,
    fmi3GetIntervalDecimal: fmi3GetIntervalDecimalTYPE,
    fmi3GetIntervalFraction: fmi3GetIntervalFractionTYPE,
    fmi3GetShiftDecimal: fmi3GetShiftDecimalTYPE,
    fmi3GetShiftFraction: fmi3GetShiftFractionTYPE,
    fmi3SetIntervalDecimal: fmi3SetIntervalDecimalTYPE,
    fmi3SetIntervalFraction: fmi3SetIntervalFractionTYPE,
    fmi3SetShiftDecimal: fmi3SetShiftDecimalTYPE,
    fmi3SetShiftFraction: fmi3SetShiftFractionTYPE,
    fmi3EvaluateDiscreteStates: fmi3EvaluateDiscreteStatesTYPE,
    fmi3UpdateDiscreteStates: fmi3UpdateDiscreteStatesTYPE,
    fmi3EnterContinuousTimeMode: fmi3EnterContinuousTimeModeTYPE,
    fmi3CompletedIntegratorStep: fmi3CompletedIntegratorStepTYPE,
    fmi3SetTime: fmi3SetTimeTYPE,
    fmi3SetContinuousStates: fmi3SetContinuousStatesTYPE,
    fmi3GetContinuousStateDerivatives: fmi3GetContinuousStateDerivativesTYPE,
    fmi3GetEventIndicators: fmi3GetEventIndicatorsTYPE,
    fmi3GetContinuousStates: fmi3GetContinuousStatesTYPE,
    fmi3GetNominalsOfContinuousStates: fmi3GetNominalsOfContinuousStatesTYPE,
    fmi3GetNumberOfEventIndicators: fmi3GetNumberOfEventIndicatorsTYPE,
    fmi3GetNumberOfContinuousStates: fmi3GetNumberOfContinuousStatesTYPE,
    fmi3EnterStepMode: fmi3EnterStepModeTYPE,
    fmi3GetOutputDerivatives: fmi3GetOutputDerivativesTYPE,
    fmi3DoStep: fmi3DoStepTYPE,
    fmi3ActivateModelPartition: fmi3ActivateModelPartitionTYPE,
);

#[test]
fn the_fmi3_types_are_the_headers() {
    use rustfmu::__private::abi3 as ours;
    use std::mem::size_of;
    assert_eq!(size_of::<ours::fmi3Boolean>(), size_of::<sys::fmi3Boolean>());
    assert_eq!(size_of::<ours::fmi3Status>(), size_of::<sys::fmi3Status>());
    assert_eq!(ours::fmi3Error, sys::fmi3Status_fmi3Error);
    assert_eq!(ours::fmi3Discard, sys::fmi3Status_fmi3Discard);
    assert_eq!(ours::fmi3Fatal, sys::fmi3Status_fmi3Fatal);
}

#[test]
fn the_version_is_3_0() {
    // SAFETY: fmi3GetVersion returns a static NUL-terminated string.
    let v = unsafe { std::ffi::CStr::from_ptr(fmi3GetVersion()) };
    assert_eq!(v.to_str().unwrap(), "3.0");
    assert!(
        TOKEN.starts_with('{') && TOKEN.ends_with('}') && TOKEN.len() == 38,
        "{TOKEN}"
    );
}
