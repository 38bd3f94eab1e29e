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
            const INTERFACES: $crate::description::Interfaces = $crate::description::Interfaces {
                co_simulation: <__RustfmuModel as $crate::Variables>::CO_SIMULATION,
                model_exchange: <__RustfmuModel as $crate::Variables>::MODEL_EXCHANGE,
                version: $crate::description::FmiVersion::V2,
                can_interpolate_inputs: <__RustfmuModel as $crate::CoSimulation>::INTERPOLATES_INPUTS,
                scheduled_execution: false,
            };
            const LEN: usize =
                $crate::description::encoded_len(&<__RustfmuModel as $crate::Variables>::DESCRIPTION, INTERFACES);
            const ENCODED: [u8; LEN] =
                $crate::description::encode(&<__RustfmuModel as $crate::Variables>::DESCRIPTION, INTERFACES);
            const GUID_TEXT: [u8; 38] = $crate::description::guid(&ENCODED);
            pub const GUID: &str = match ::core::str::from_utf8(&GUID_TEXT) {
                Ok(s) => s,
                Err(_) => panic!("the GUID is ASCII"),
            };
            /// The description, where `cargo fmu` finds it (see `rustfmu::description::find_encoded`).
            #[used]
            static DESCRIPTION: [u8; LEN] = ENCODED;

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
                fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status =>
                    shared::transition::<__RustfmuModel>(&TERMS, shared::Transition::EnterInitializationMode, component(c));
                fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status =>
                    shared::transition::<__RustfmuModel>(&TERMS, shared::Transition::ExitInitializationMode, component(c));
                fmi2Terminate(c: fmi2Component) -> fmi2Status =>
                    shared::transition::<__RustfmuModel>(&TERMS, shared::Transition::Terminate, component(c));
                fmi2Reset(c: fmi2Component) -> fmi2Status =>
                    shared::transition::<__RustfmuModel>(&TERMS, shared::Transition::Reset, component(c));
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
                fmi2GetFMUstate(c: fmi2Component, FMUstate: *mut fmi2FMUstate) -> fmi2Status =>
                    shared::get_fmu_state::<__RustfmuModel>(&TERMS, component(c), FMUstate);
                fmi2SetFMUstate(c: fmi2Component, FMUstate: fmi2FMUstate) -> fmi2Status =>
                    shared::set_fmu_state::<__RustfmuModel>(&TERMS, component(c), FMUstate);
                fmi2FreeFMUstate(c: fmi2Component, FMUstate: *mut fmi2FMUstate) -> fmi2Status =>
                    shared::free_fmu_state::<__RustfmuModel>(&TERMS, component(c), FMUstate);
                fmi2SerializedFMUstateSize(c: fmi2Component, FMUstate: fmi2FMUstate, size: *mut usize) -> fmi2Status =>
                    shared::serialized_fmu_state_size::<__RustfmuModel>(&TERMS, component(c), FMUstate, size);
                fmi2SerializeFMUstate(
                    c: fmi2Component,
                    FMUstate: fmi2FMUstate,
                    serializedState: *mut fmi2Byte,
                    size: usize,
                ) -> fmi2Status =>
                    shared::serialize_fmu_state::<__RustfmuModel>(&TERMS, component(c), FMUstate, serializedState, size);
                fmi2DeSerializeFMUstate(
                    c: fmi2Component,
                    serializedState: *const fmi2Byte,
                    size: usize,
                    FMUstate: *mut fmi2FMUstate,
                ) -> fmi2Status =>
                    shared::deserialize_fmu_state::<__RustfmuModel>(&TERMS, component(c), serializedState, size, FMUstate);
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
                fmi2EnterEventMode(c: fmi2Component) -> fmi2Status =>
                    shared::transition::<__RustfmuModel>(&TERMS, shared::Transition::EnterEventMode, component(c));
                fmi2NewDiscreteStates(c: fmi2Component, fmi2eventInfo: *mut fmi2EventInfo) -> fmi2Status =>
                    api::new_discrete_states::<__RustfmuModel>(component(c), fmi2eventInfo);
                fmi2EnterContinuousTimeMode(c: fmi2Component) -> fmi2Status =>
                    shared::transition::<__RustfmuModel>(&TERMS, shared::Transition::EnterContinuousTimeMode, component(c));
                fmi2CompletedIntegratorStep(
                    c: fmi2Component,
                    noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
                    enterEventMode: *mut fmi2Boolean,
                    terminateSimulation: *mut fmi2Boolean,
                ) -> fmi2Status =>
                    shared::completed_integrator_step::<__RustfmuModel, fmi2Boolean>(
                        &TERMS,
                        component(c),
                        noSetFMUStatePriorToCurrentPoint,
                        enterEventMode,
                        terminateSimulation,
                    );
                fmi2SetTime(c: fmi2Component, time: fmi2Real) -> fmi2Status =>
                    shared::set_time::<__RustfmuModel>(&TERMS, component(c), time);
                fmi2SetContinuousStates(c: fmi2Component, x: *const fmi2Real, nx: usize) -> fmi2Status =>
                    shared::set_continuous_states::<__RustfmuModel>(&TERMS, component(c), x, nx);
                fmi2GetDerivatives(c: fmi2Component, derivatives: *mut fmi2Real, nx: usize) -> fmi2Status =>
                    shared::get_vector::<__RustfmuModel>(&TERMS, shared::Vector::Derivatives, component(c), derivatives, nx);
                fmi2GetEventIndicators(c: fmi2Component, eventIndicators: *mut fmi2Real, ni: usize) -> fmi2Status =>
                    shared::get_vector::<__RustfmuModel>(
                        &TERMS,
                        shared::Vector::EventIndicators,
                        component(c),
                        eventIndicators,
                        ni,
                    );
                fmi2GetContinuousStates(c: fmi2Component, x: *mut fmi2Real, nx: usize) -> fmi2Status =>
                    shared::get_vector::<__RustfmuModel>(&TERMS, shared::Vector::ContinuousStates, component(c), x, nx);
                fmi2GetNominalsOfContinuousStates(
                    c: fmi2Component,
                    x_nominal: *mut fmi2Real,
                    nx: usize,
                ) -> fmi2Status =>
                    shared::get_vector::<__RustfmuModel>(&TERMS, shared::Vector::Nominals, component(c), x_nominal, nx);
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
        }
        pub use __rustfmu_fmi2_exports::*;
    };
}
