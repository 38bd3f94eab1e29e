//! `export_fmi2!(Model)`: the one line an FMU crate needs.

/// Exports `Model` as an FMI 2.0 FMU for model exchange and co-simulation in one binary:
/// defines every function of both interfaces as an unmangled `extern "C"` symbol with the
/// standard's exact signature (forwarded to the runtime), and embeds the model's encoded description in the library, where `cargo fmu`
/// reads it. The GUID is computed here, at compile time, from that description.
///
/// ```ignore
/// rustfmu::export_fmi2!(Lag);
/// ```
#[macro_export]
macro_rules! export_fmi2 {
    ($model:ty) => {
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        #[doc(hidden)]
        pub mod __rustfmu_fmi2_exports {
            use super::*;
            use $crate::__private::abi::*;
            use $crate::__private::api;
            use $crate::__private::{TERMS2 as TERMS, shared};
            use $crate::core::guard::component;
            type __RustfmuModel = $model;
            const _: () = assert!(
                !<__RustfmuModel as $crate::Variables>::FMI3_ONLY,
                "this model is #[fmu(fmi3_only)]: it has no FMI 2.0 export; use rustfmu::export_fmi3! instead of export_fmu! or export_fmi2!"
            );

            // Input derivatives are applied by the runtime's integrator on its plain path; a model
            // with event indicators takes the path that locates state events, which does not.
            const _: () = assert!(
                !<__RustfmuModel as $crate::CoSimulation>::INTERPOLATES_INPUTS
                    || <__RustfmuModel as $crate::Variables>::INDICATORS.is_empty(),
                "CoSimulation::INTERPOLATES_INPUTS with event indicators is not supported: the step that locates state events holds the inputs"
            );
            $crate::__rustfmu_embedded_description!(
                __RustfmuModel,
                V2,
                can_interpolate_inputs: <__RustfmuModel as $crate::CoSimulation>::INTERPOLATES_INPUTS,
                scheduled_execution: false,
                GUID,
                GUID_TEXT,
                "the GUID is ASCII"
            );

            #[unsafe(no_mangle)]
            pub extern "C" fn fmi2GetTypesPlatform() -> fmi2String {
                api::get_types_platform()
            }
            #[unsafe(no_mangle)]
            pub extern "C" fn fmi2GetVersion() -> fmi2String {
                api::get_version()
            }
            // One row per C function: its name, its parameters as fmi2Functions.h names them, and
            // the runtime function it forwards to (see `rustfmu::core::trampolines`).
            $crate::__rustfmu_extern_c! {
                fmi2SetDebugLogging(
                    c: fmi2Component,
                    loggingOn: fmi2Boolean,
                    nCategories: usize,
                    categories: *const fmi2String,
                ) -> fmi2Status =>
                    shared::set_debug_logging::<__RustfmuModel>(
                        &TERMS,
                        component(c),
                        loggingOn != fmi2False,
                        nCategories,
                        categories,
                    );
                fmi2Instantiate(
                    instanceName: fmi2String,
                    fmuType: fmi2Type,
                    fmuGUID: fmi2String,
                    fmuResourceLocation: fmi2String,
                    functions: *const fmi2CallbackFunctions,
                    visible: fmi2Boolean,
                    loggingOn: fmi2Boolean,
                ) -> fmi2Component =>
                    api::instantiate::<__RustfmuModel>(
                        GUID,
                        &DESCRIPTION,
                        instanceName,
                        fmuType,
                        fmuGUID,
                        fmuResourceLocation,
                        functions,
                        visible,
                        loggingOn,
                    );
                fmi2FreeInstance(c: fmi2Component) =>
                    shared::free_instance::<__RustfmuModel>(&TERMS, c);
                fmi2SetupExperiment(
                    c: fmi2Component,
                    toleranceDefined: fmi2Boolean,
                    tolerance: fmi2Real,
                    startTime: fmi2Real,
                    stopTimeDefined: fmi2Boolean,
                    stopTime: fmi2Real,
                ) -> fmi2Status =>
                    api::setup_experiment::<__RustfmuModel>(
                        component(c),
                        toleranceDefined,
                        tolerance,
                        startTime,
                        stopTimeDefined,
                        stopTime,
                    );
                fmi2GetReal(
                    c: fmi2Component,
                    vr: *const fmi2ValueReference,
                    nvr: usize,
                    value: *mut fmi2Real,
                ) -> fmi2Status =>
                    api::get::<__RustfmuModel, f64>(component(c), "fmi2GetReal", vr, nvr, value);
                fmi2GetInteger(
                    c: fmi2Component,
                    vr: *const fmi2ValueReference,
                    nvr: usize,
                    value: *mut fmi2Integer,
                ) -> fmi2Status =>
                    api::get::<__RustfmuModel, i32>(component(c), "fmi2GetInteger", vr, nvr, value);
                fmi2GetBoolean(
                    c: fmi2Component,
                    vr: *const fmi2ValueReference,
                    nvr: usize,
                    value: *mut fmi2Boolean,
                ) -> fmi2Status =>
                    api::get_boolean::<__RustfmuModel>(component(c), vr, nvr, value);
                fmi2GetString(
                    c: fmi2Component,
                    vr: *const fmi2ValueReference,
                    nvr: usize,
                    value: *mut fmi2String,
                ) -> fmi2Status =>
                    api::get_string::<__RustfmuModel>(component(c), vr, nvr, value);
                fmi2SetReal(
                    c: fmi2Component,
                    vr: *const fmi2ValueReference,
                    nvr: usize,
                    value: *const fmi2Real,
                ) -> fmi2Status =>
                    api::set::<__RustfmuModel, f64>(component(c), "fmi2SetReal", vr, nvr, value);
                fmi2SetInteger(
                    c: fmi2Component,
                    vr: *const fmi2ValueReference,
                    nvr: usize,
                    value: *const fmi2Integer,
                ) -> fmi2Status =>
                    api::set::<__RustfmuModel, i32>(component(c), "fmi2SetInteger", vr, nvr, value);
                fmi2SetBoolean(
                    c: fmi2Component,
                    vr: *const fmi2ValueReference,
                    nvr: usize,
                    value: *const fmi2Boolean,
                ) -> fmi2Status =>
                    api::set_boolean::<__RustfmuModel>(component(c), vr, nvr, value);
                fmi2SetString(
                    c: fmi2Component,
                    vr: *const fmi2ValueReference,
                    nvr: usize,
                    value: *const fmi2String,
                ) -> fmi2Status =>
                    api::set_string::<__RustfmuModel>(component(c), vr, nvr, value);
                fmi2GetDirectionalDerivative(
                    c: fmi2Component,
                    vUnknown_ref: *const fmi2ValueReference,
                    nUnknown: usize,
                    vKnown_ref: *const fmi2ValueReference,
                    nKnown: usize,
                    dvKnown: *const fmi2Real,
                    dvUnknown: *mut fmi2Real,
                ) -> fmi2Status =>
                    api::get_directional_derivative::<__RustfmuModel>(
                        component(c),
                        vUnknown_ref,
                        nUnknown,
                        vKnown_ref,
                        nKnown,
                        dvKnown,
                        dvUnknown,
                    );
                fmi2NewDiscreteStates(c: fmi2Component, fmi2eventInfo: *mut fmi2EventInfo) -> fmi2Status =>
                    api::new_discrete_states::<__RustfmuModel>(component(c), fmi2eventInfo);
                fmi2SetRealInputDerivatives(
                    c: fmi2Component,
                    vr: *const fmi2ValueReference,
                    nvr: usize,
                    order: *const fmi2Integer,
                    value: *const fmi2Real,
                ) -> fmi2Status =>
                    api::set_real_input_derivatives::<__RustfmuModel>(component(c), vr, nvr, order, value);
                fmi2GetRealOutputDerivatives(
                    c: fmi2Component,
                    vr: *const fmi2ValueReference,
                    nvr: usize,
                    order: *const fmi2Integer,
                    value: *mut fmi2Real,
                ) -> fmi2Status =>
                    api::get_real_output_derivatives::<__RustfmuModel>(component(c), vr, nvr, order, value);
                fmi2DoStep(
                    c: fmi2Component,
                    currentCommunicationPoint: fmi2Real,
                    communicationStepSize: fmi2Real,
                    noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
                ) -> fmi2Status =>
                    api::do_step::<__RustfmuModel>(
                        component(c),
                        currentCommunicationPoint,
                        communicationStepSize,
                        noSetFMUStatePriorToCurrentPoint,
                    );
                fmi2CancelStep(c: fmi2Component) -> fmi2Status =>
                    api::cancel_step::<__RustfmuModel>(component(c));
                fmi2GetStatus(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2Status) -> fmi2Status =>
                    api::get_status::<__RustfmuModel, fmi2Status>(component(c), "fmi2GetStatus", s, value, api::unavailable);
                fmi2GetRealStatus(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2Real) -> fmi2Status =>
                    api::get_status::<__RustfmuModel, fmi2Real>(component(c), "fmi2GetRealStatus", s, value, api::last_successful_time);
                fmi2GetIntegerStatus(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2Integer) -> fmi2Status =>
                    api::get_status::<__RustfmuModel, fmi2Integer>(component(c), "fmi2GetIntegerStatus", s, value, api::unavailable);
                fmi2GetBooleanStatus(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2Boolean) -> fmi2Status =>
                    api::get_status::<__RustfmuModel, fmi2Boolean>(component(c), "fmi2GetBooleanStatus", s, value, api::terminated);
                fmi2GetStringStatus(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2String) -> fmi2Status =>
                    api::get_status::<__RustfmuModel, fmi2String>(component(c), "fmi2GetStringStatus", s, value, api::unavailable);
            }
            $crate::__rustfmu_shared_exports! {
                for __RustfmuModel: instance fmi2Component, status fmi2Status, boolean fmi2Boolean, real fmi2Real,
                    byte fmi2Byte, FMU state fmi2FMUstate;
                transitions: fmi2EnterInitializationMode => EnterInitializationMode,
                    fmi2ExitInitializationMode => ExitInitializationMode, fmi2Terminate => Terminate,
                    fmi2Reset => Reset, fmi2EnterEventMode => EnterEventMode,
                    fmi2EnterContinuousTimeMode => EnterContinuousTimeMode;
                FMU state: fmi2GetFMUstate, fmi2SetFMUstate, fmi2FreeFMUstate, fmi2SerializedFMUstateSize,
                    fmi2SerializeFMUstate, fmi2DeSerializeFMUstate;
                vectors: fmi2GetDerivatives => Derivatives, fmi2GetEventIndicators => EventIndicators,
                    fmi2GetContinuousStates => ContinuousStates, fmi2GetNominalsOfContinuousStates => Nominals;
                model exchange: fmi2CompletedIntegratorStep, fmi2SetTime, fmi2SetContinuousStates;
            }
        }
        pub use __rustfmu_fmi2_exports::*;
    };
}
