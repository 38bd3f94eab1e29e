//! The exported C ABI, proved equal at compile time to the official FMI 2.0 headers as bindgen
//! translates them in `fmi-sys`. The runtime declares its own ABI types so that building an FMU
//! needs no libclang; this test is where the two must agree. If a signature drifts, this file
//! stops compiling.

use fmi_sys::fmi2 as sys;
use std::mem::{align_of, offset_of, size_of};

// The export macro expanded into this test binary, for a model of one variable: the very
// functions every FMU exports.
mod model {
    use rustfmu::prelude::*;

    /// A constant output.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    pub struct Probe {
        /// An output
        #[variable(vr = 0, output, initial = exact, start = 1.0, depends = [])]
        pub y: f64,
    }

    impl Model for Probe {}
    impl CoSimulation for Probe {
        fn do_step(&mut self, _t: f64, _h: f64, _ctx: &mut Context) -> Result<(), StepFailure> {
            Ok(())
        }
    }

    rustfmu::export_fmi2!(Probe);
}
use model::*;

macro_rules! same_signature {
    ($($f:ident: $t:ident),* $(,)?) => {
        $(const _: sys::$t = Some($f);)*
    };
}

same_signature!(
    fmi2GetTypesPlatform: fmi2GetTypesPlatformTYPE,
    fmi2GetVersion: fmi2GetVersionTYPE,
    fmi2SetDebugLogging: fmi2SetDebugLoggingTYPE,
    fmi2FreeInstance: fmi2FreeInstanceTYPE,
    fmi2SetupExperiment: fmi2SetupExperimentTYPE,
    fmi2EnterInitializationMode: fmi2EnterInitializationModeTYPE,
    fmi2ExitInitializationMode: fmi2ExitInitializationModeTYPE,
    fmi2Terminate: fmi2TerminateTYPE,
    fmi2Reset: fmi2ResetTYPE,
    fmi2GetReal: fmi2GetRealTYPE,
    fmi2GetInteger: fmi2GetIntegerTYPE,
    fmi2GetBoolean: fmi2GetBooleanTYPE,
    fmi2GetString: fmi2GetStringTYPE,
    fmi2SetReal: fmi2SetRealTYPE,
    fmi2SetInteger: fmi2SetIntegerTYPE,
    fmi2SetBoolean: fmi2SetBooleanTYPE,
    fmi2SetString: fmi2SetStringTYPE,
    fmi2GetFMUstate: fmi2GetFMUstateTYPE,
    fmi2SetFMUstate: fmi2SetFMUstateTYPE,
    fmi2FreeFMUstate: fmi2FreeFMUstateTYPE,
    fmi2SerializedFMUstateSize: fmi2SerializedFMUstateSizeTYPE,
    fmi2SerializeFMUstate: fmi2SerializeFMUstateTYPE,
    fmi2DeSerializeFMUstate: fmi2DeSerializeFMUstateTYPE,
    fmi2GetDirectionalDerivative: fmi2GetDirectionalDerivativeTYPE,
    fmi2SetRealInputDerivatives: fmi2SetRealInputDerivativesTYPE,
    fmi2GetRealOutputDerivatives: fmi2GetRealOutputDerivativesTYPE,
    fmi2DoStep: fmi2DoStepTYPE,
    fmi2CancelStep: fmi2CancelStepTYPE,
    fmi2GetStatus: fmi2GetStatusTYPE,
    fmi2GetRealStatus: fmi2GetRealStatusTYPE,
    fmi2GetIntegerStatus: fmi2GetIntegerStatusTYPE,
    fmi2GetBooleanStatus: fmi2GetBooleanStatusTYPE,
    fmi2GetStringStatus: fmi2GetStringStatusTYPE,
);

// fmi2Instantiate takes a pointer to the callbacks struct, a nominal type that differs between
// the two declarations; everything else about it must be identical. The struct is proved
// layout-identical field by field below, and every field's type identical.
type OurInstantiate = unsafe extern "C" fn(
    sys::fmi2String,
    sys::fmi2Type,
    sys::fmi2String,
    sys::fmi2String,
    *const rustfmu::__private::abi::fmi2CallbackFunctions,
    sys::fmi2Boolean,
    sys::fmi2Boolean,
) -> sys::fmi2Component;
const _: OurInstantiate = fmi2Instantiate;

// The function types an importer loads (rustfmu::fmi2::abi's `fmi2...TYPE`, what rustfmu-runner's
// importer and the container FMU use) are the header's: each `None` of ours is a value of theirs.
macro_rules! same_type {
    ($($ours:ty => $theirs:ident),* $(,)?) => {
        $(const _: sys::$theirs = None::<$ours>;)*
    };
}
mod abi_types {
    use super::sys;
    use rustfmu::fmi2::abi::*;
    same_type!(
        fmi2FreeInstanceTYPE => fmi2FreeInstanceTYPE,
        fmi2SetDebugLoggingTYPE => fmi2SetDebugLoggingTYPE,
        fmi2SetupExperimentTYPE => fmi2SetupExperimentTYPE,
        fmi2ComponentFunctionTYPE => fmi2EnterInitializationModeTYPE,
        fmi2ComponentFunctionTYPE => fmi2ExitInitializationModeTYPE,
        fmi2ComponentFunctionTYPE => fmi2TerminateTYPE,
        fmi2ComponentFunctionTYPE => fmi2ResetTYPE,
        fmi2GetTYPE<fmi2Real> => fmi2GetRealTYPE,
        fmi2GetTYPE<fmi2Integer> => fmi2GetIntegerTYPE,
        fmi2GetTYPE<fmi2Boolean> => fmi2GetBooleanTYPE,
        fmi2GetTYPE<fmi2String> => fmi2GetStringTYPE,
        fmi2SetTYPE<fmi2Real> => fmi2SetRealTYPE,
        fmi2SetTYPE<fmi2Integer> => fmi2SetIntegerTYPE,
        fmi2SetTYPE<fmi2Boolean> => fmi2SetBooleanTYPE,
        fmi2SetTYPE<fmi2String> => fmi2SetStringTYPE,
        fmi2DoStepTYPE => fmi2DoStepTYPE,
        fmi2GetFMUstateTYPE => fmi2GetFMUstateTYPE,
        fmi2GetFMUstateTYPE => fmi2FreeFMUstateTYPE,
        fmi2SetFMUstateTYPE => fmi2SetFMUstateTYPE,
        fmi2SerializedFMUstateSizeTYPE => fmi2SerializedFMUstateSizeTYPE,
        fmi2SerializeFMUstateTYPE => fmi2SerializeFMUstateTYPE,
        fmi2DeSerializeFMUstateTYPE => fmi2DeSerializeFMUstateTYPE,
    );
    // fmi2Instantiate: as above, the callbacks struct is ours.
    const _: Option<super::OurInstantiate> = None::<fmi2InstantiateTYPE>;
}

const fn same<T>(_: &T, _: &T) {}

#[test]
fn callback_struct_has_the_headers_layout() {
    use rustfmu::__private::abi::fmi2CallbackFunctions as Ours;
    use sys::fmi2CallbackFunctions as Theirs;
    assert_eq!(size_of::<Ours>(), size_of::<Theirs>());
    assert_eq!(align_of::<Ours>(), align_of::<Theirs>());
    assert_eq!(offset_of!(Ours, logger), offset_of!(Theirs, logger));
    assert_eq!(offset_of!(Ours, allocateMemory), offset_of!(Theirs, allocateMemory));
    assert_eq!(offset_of!(Ours, freeMemory), offset_of!(Theirs, freeMemory));
    assert_eq!(offset_of!(Ours, stepFinished), offset_of!(Theirs, stepFinished));
    assert_eq!(
        offset_of!(Ours, componentEnvironment),
        offset_of!(Theirs, componentEnvironment)
    );
    let ours = Ours {
        logger: None,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: std::ptr::null_mut(),
    };
    let theirs = Theirs {
        logger: None,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: std::ptr::null_mut(),
    };
    same(&ours.logger, &theirs.logger);
    same(&ours.allocateMemory, &theirs.allocateMemory);
    same(&ours.freeMemory, &theirs.freeMemory);
    same(&ours.stepFinished, &theirs.stepFinished);
    same(&ours.componentEnvironment, &theirs.componentEnvironment);
}

#[test]
fn enum_constants_match_the_headers() {
    use rustfmu::__private::abi as ours;
    assert_eq!(ours::fmi2OK, sys::fmi2Status_fmi2OK);
    assert_eq!(ours::fmi2Warning, sys::fmi2Status_fmi2Warning);
    assert_eq!(ours::fmi2Discard, sys::fmi2Status_fmi2Discard);
    assert_eq!(ours::fmi2Error, sys::fmi2Status_fmi2Error);
    assert_eq!(ours::fmi2Fatal, sys::fmi2Status_fmi2Fatal);
    assert_eq!(ours::fmi2Pending, sys::fmi2Status_fmi2Pending);
    assert_eq!(ours::fmi2ModelExchange, sys::fmi2Type_fmi2ModelExchange);
    assert_eq!(ours::fmi2CoSimulation, sys::fmi2Type_fmi2CoSimulation);
    assert_eq!(ours::fmi2DoStepStatus, sys::fmi2StatusKind_fmi2DoStepStatus);
    assert_eq!(ours::fmi2PendingStatus, sys::fmi2StatusKind_fmi2PendingStatus);
    assert_eq!(ours::fmi2LastSuccessfulTime, sys::fmi2StatusKind_fmi2LastSuccessfulTime);
    assert_eq!(ours::fmi2Terminated, sys::fmi2StatusKind_fmi2Terminated);
}
