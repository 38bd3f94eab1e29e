//! `export_fmi3!(Model)`: the FMI 3.0 functions of a model (usually through
//! [`export_fmu!`](crate::export_fmu), which exports both versions).

/// Rows for [`__rustfmu_extern_c!`](crate::__rustfmu_extern_c) of the FMI 3.0 functions that
/// refuse, written from shorter rows: the C name of a refusal says what it refuses (passed on
/// with `stringify!`), and every one of a kind has the same parameters. Not part of the API.
#[doc(hidden)]
#[macro_export]
macro_rules! __rustfmu_fmi3_refusals {
    // `fmi3GetX, fmi3SetX(fmi3X);`: the getter and the setter of an FMI 3.0 numeric type
    // without a 2.0 counterpart, through the runtime's generic ones.
    (typed for $model:ty: $($get:ident, $set:ident($t:ty);)*) => {
        $crate::__rustfmu_extern_c! {
            $(
                $get(
                    instance: $crate::__private::abi3::fmi3Instance,
                    valueReferences: *const $crate::__private::abi3::fmi3ValueReference,
                    nValueReferences: usize,
                    values: *mut $t,
                    nValues: usize,
                ) -> $crate::__private::abi3::fmi3Status =>
                    $crate::__private::api3::get_typed::<$model, $t>(
                        component(instance),
                        stringify!($get),
                        valueReferences,
                        nValueReferences,
                        values,
                        nValues,
                    );
                $set(
                    instance: $crate::__private::abi3::fmi3Instance,
                    valueReferences: *const $crate::__private::abi3::fmi3ValueReference,
                    nValueReferences: usize,
                    values: *const $t,
                    nValues: usize,
                ) -> $crate::__private::abi3::fmi3Status =>
                    $crate::__private::api3::set_typed::<$model, $t>(
                        component(instance),
                        stringify!($set),
                        valueReferences,
                        nValueReferences,
                        values,
                        nValues,
                    );
            )*
        }
    };
    // `fmi3X(parameters after the instance) => why;`: a function of a feature this FMU does not
    // have; fmi3Error with `why`, in any state.
    (not_provided for $model:ty: $($name:ident($($arg:ident: $ty:ty),* $(,)?) => $why:expr;)*) => {
        $crate::__rustfmu_extern_c! {
            $(
                $name(instance: $crate::__private::abi3::fmi3Instance, $($arg: $ty),*)
                    -> $crate::__private::abi3::fmi3Status =>
                    $crate::__private::api3::not_provided::<$model>(component(instance), stringify!($name), $why);
            )*
        }
    };
}

/// Exports `Model` as an FMI 3.0 FMU for model exchange and co-simulation in one binary:
/// defines every function of the FMI 3.0 standard (`fmi3Functions.h`) as an unmangled
/// `extern "C"` symbol with its exact signature, forwarded to the runtime, and embeds the
/// model's encoded description (marked FMI 3.0), where `cargo fmu` reads it. The
/// `instantiationToken` is computed here, at compile time, from that description.
#[macro_export]
macro_rules! export_fmi3 {
    ($model:ty) => {
        #[allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]
        #[doc(hidden)]
        pub mod __rustfmu_fmi3_exports {
            use super::*;
            use $crate::__private::abi3::*;
            use $crate::__private::api3;
            use $crate::__private::{TERMS3 as TERMS, shared};
            use $crate::core::guard::component;
            type __RustfmuModel = $model;

            const INTERFACES: $crate::description::Interfaces = $crate::description::Interfaces {
                co_simulation: <__RustfmuModel as $crate::Variables>::CO_SIMULATION,
                model_exchange: <__RustfmuModel as $crate::Variables>::MODEL_EXCHANGE,
                version: $crate::description::FmiVersion::V3,
                // FMI 3.0 has no input derivatives.
                can_interpolate_inputs: false,
                scheduled_execution: <__RustfmuModel as $crate::Variables>::SCHEDULED_EXECUTION,
            };
            const LEN: usize =
                $crate::description::encoded_len(&<__RustfmuModel as $crate::Variables>::DESCRIPTION, INTERFACES);
            const ENCODED: [u8; LEN] =
                $crate::description::encode(&<__RustfmuModel as $crate::Variables>::DESCRIPTION, INTERFACES);
            const TOKEN_TEXT: [u8; 38] = $crate::description::guid(&ENCODED);
            pub const TOKEN: &str = match ::core::str::from_utf8(&TOKEN_TEXT) {
                Ok(s) => s,
                Err(_) => panic!("the token is ASCII"),
            };
            /// The description, where `cargo fmu` finds it (see `rustfmu::description::find_encoded`).
            #[used]
            static DESCRIPTION: [u8; LEN] = ENCODED;

            #[unsafe(no_mangle)]
            pub extern "C" fn fmi3GetVersion() -> *const ::std::os::raw::c_char {
                api3::get_version()
            }
            // One row per C function: its name, its parameters as fmi3Functions.h names them, and
            // the runtime function it forwards to (see `rustfmu::core::trampolines`).
            $crate::__rustfmu_extern_c! {
                fmi3SetDebugLogging(
                    instance: fmi3Instance,
                    loggingOn: fmi3Boolean,
                    nCategories: usize,
                    categories: *const fmi3String,
                ) -> fmi3Status =>
                    shared::set_debug_logging::<__RustfmuModel>(&TERMS, component(instance), loggingOn, nCategories, categories);
                fmi3InstantiateModelExchange(
                    instanceName: fmi3String,
                    instantiationToken: fmi3String,
                    resourcePath: fmi3String,
                    visible: fmi3Boolean,
                    loggingOn: fmi3Boolean,
                    instanceEnvironment: fmi3InstanceEnvironment,
                    logMessage: fmi3LogMessageCallback,
                ) -> fmi3Instance =>
                    api3::instantiate_model_exchange::<__RustfmuModel>(
                        TOKEN,
                        &DESCRIPTION,
                        instanceName,
                        instantiationToken,
                        resourcePath,
                        visible,
                        loggingOn,
                        instanceEnvironment,
                        logMessage,
                    );
                fmi3InstantiateCoSimulation(
                    instanceName: fmi3String,
                    instantiationToken: fmi3String,
                    resourcePath: fmi3String,
                    visible: fmi3Boolean,
                    loggingOn: fmi3Boolean,
                    eventModeUsed: fmi3Boolean,
                    earlyReturnAllowed: fmi3Boolean,
                    requiredIntermediateVariables: *const fmi3ValueReference,
                    nRequiredIntermediateVariables: usize,
                    instanceEnvironment: fmi3InstanceEnvironment,
                    logMessage: fmi3LogMessageCallback,
                    intermediateUpdate: fmi3IntermediateUpdateCallback,
                ) -> fmi3Instance =>
                    api3::instantiate_co_simulation::<__RustfmuModel>(
                        TOKEN,
                        &DESCRIPTION,
                        instanceName,
                        instantiationToken,
                        resourcePath,
                        visible,
                        loggingOn,
                        eventModeUsed,
                        earlyReturnAllowed,
                        requiredIntermediateVariables,
                        nRequiredIntermediateVariables,
                        instanceEnvironment,
                        logMessage,
                        intermediateUpdate,
                    );
                fmi3InstantiateScheduledExecution(
                    instanceName: fmi3String,
                    instantiationToken: fmi3String,
                    resourcePath: fmi3String,
                    _visible: fmi3Boolean,
                    loggingOn: fmi3Boolean,
                    instanceEnvironment: fmi3InstanceEnvironment,
                    logMessage: fmi3LogMessageCallback,
                    clockUpdate: fmi3ClockUpdateCallback,
                    _lockPreemption: fmi3LockPreemptionCallback,
                    _unlockPreemption: fmi3UnlockPreemptionCallback,
                ) -> fmi3Instance =>
                    api3::instantiate_scheduled_execution::<__RustfmuModel>(
                        TOKEN,
                        &DESCRIPTION,
                        instanceName,
                        instantiationToken,
                        resourcePath,
                        loggingOn,
                        instanceEnvironment,
                        logMessage,
                        clockUpdate,
                    );
                fmi3ActivateModelPartition(
                    instance: fmi3Instance,
                    clockReference: fmi3ValueReference,
                    activationTime: fmi3Float64,
                ) -> fmi3Status =>
                    api3::activate_model_partition::<__RustfmuModel>(component(instance), clockReference, activationTime);
                fmi3FreeInstance(instance: fmi3Instance) =>
                    shared::free_instance::<__RustfmuModel>(&TERMS, instance);
                fmi3EnterInitializationMode(
                    instance: fmi3Instance,
                    toleranceDefined: fmi3Boolean,
                    tolerance: fmi3Float64,
                    startTime: fmi3Float64,
                    stopTimeDefined: fmi3Boolean,
                    stopTime: fmi3Float64,
                ) -> fmi3Status =>
                    api3::enter_initialization_mode::<__RustfmuModel>(
                        component(instance),
                        toleranceDefined,
                        tolerance,
                        startTime,
                        stopTimeDefined,
                        stopTime,
                    );
                fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status =>
                    shared::transition::<__RustfmuModel>(&TERMS, shared::Transition::ExitInitializationMode, component(instance));
                fmi3EnterEventMode(instance: fmi3Instance) -> fmi3Status =>
                    shared::transition::<__RustfmuModel>(&TERMS, shared::Transition::EnterEventMode, component(instance));
                fmi3Terminate(instance: fmi3Instance) -> fmi3Status =>
                    shared::transition::<__RustfmuModel>(&TERMS, shared::Transition::Terminate, component(instance));
                fmi3Reset(instance: fmi3Instance) -> fmi3Status =>
                    shared::transition::<__RustfmuModel>(&TERMS, shared::Transition::Reset, component(instance));
                fmi3GetFloat64(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    values: *mut fmi3Float64,
                    nValues: usize,
                ) -> fmi3Status =>
                    api3::get_float64::<__RustfmuModel>(component(instance), valueReferences, nValueReferences, values, nValues);
                fmi3GetInt32(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    values: *mut fmi3Int32,
                    nValues: usize,
                ) -> fmi3Status =>
                    api3::get_int32::<__RustfmuModel>(component(instance), valueReferences, nValueReferences, values, nValues);
                fmi3GetInt64(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    values: *mut fmi3Int64,
                    nValues: usize,
                ) -> fmi3Status =>
                    api3::get_int64::<__RustfmuModel>(component(instance), valueReferences, nValueReferences, values, nValues);
                fmi3GetBoolean(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    values: *mut fmi3Boolean,
                    nValues: usize,
                ) -> fmi3Status =>
                    api3::get_boolean::<__RustfmuModel>(component(instance), valueReferences, nValueReferences, values, nValues);
                fmi3GetString(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    values: *mut fmi3String,
                    nValues: usize,
                ) -> fmi3Status =>
                    api3::get_string::<__RustfmuModel>(component(instance), valueReferences, nValueReferences, values, nValues);
                fmi3SetFloat64(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    values: *const fmi3Float64,
                    nValues: usize,
                ) -> fmi3Status =>
                    api3::set_float64::<__RustfmuModel>(component(instance), valueReferences, nValueReferences, values, nValues);
                fmi3SetInt32(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    values: *const fmi3Int32,
                    nValues: usize,
                ) -> fmi3Status =>
                    api3::set_int32::<__RustfmuModel>(component(instance), valueReferences, nValueReferences, values, nValues);
                fmi3SetInt64(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    values: *const fmi3Int64,
                    nValues: usize,
                ) -> fmi3Status =>
                    api3::set_int64::<__RustfmuModel>(component(instance), valueReferences, nValueReferences, values, nValues);
                fmi3SetBoolean(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    values: *const fmi3Boolean,
                    nValues: usize,
                ) -> fmi3Status =>
                    api3::set_boolean::<__RustfmuModel>(component(instance), valueReferences, nValueReferences, values, nValues);
                fmi3SetString(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    values: *const fmi3String,
                    nValues: usize,
                ) -> fmi3Status =>
                    api3::set_string::<__RustfmuModel>(component(instance), valueReferences, nValueReferences, values, nValues);
                fmi3GetBinary(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    valueSizes: *mut usize,
                    values: *mut fmi3Binary,
                    nValues: usize,
                ) -> fmi3Status =>
                    api3::get_binary::<__RustfmuModel>(
                        component(instance),
                        valueReferences,
                        nValueReferences,
                        valueSizes,
                        values,
                        nValues,
                    );
                fmi3SetBinary(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    valueSizes: *const usize,
                    values: *const fmi3Binary,
                    nValues: usize,
                ) -> fmi3Status =>
                    api3::set_binary::<__RustfmuModel>(
                        component(instance),
                        valueReferences,
                        nValueReferences,
                        valueSizes,
                        values,
                        nValues,
                    );
                fmi3GetFMUState(instance: fmi3Instance, FMUState: *mut fmi3FMUState) -> fmi3Status =>
                    shared::get_fmu_state::<__RustfmuModel>(&TERMS, component(instance), FMUState);
                fmi3SetFMUState(instance: fmi3Instance, FMUState: fmi3FMUState) -> fmi3Status =>
                    shared::set_fmu_state::<__RustfmuModel>(&TERMS, component(instance), FMUState);
                fmi3FreeFMUState(instance: fmi3Instance, FMUState: *mut fmi3FMUState) -> fmi3Status =>
                    shared::free_fmu_state::<__RustfmuModel>(&TERMS, component(instance), FMUState);
                fmi3SerializedFMUStateSize(
                    instance: fmi3Instance,
                    FMUState: fmi3FMUState,
                    size: *mut usize,
                ) -> fmi3Status =>
                    shared::serialized_fmu_state_size::<__RustfmuModel>(&TERMS, component(instance), FMUState, size);
                fmi3SerializeFMUState(
                    instance: fmi3Instance,
                    FMUState: fmi3FMUState,
                    serializedState: *mut fmi3Byte,
                    size: usize,
                ) -> fmi3Status =>
                    shared::serialize_fmu_state::<__RustfmuModel>(
                        &TERMS,
                        component(instance),
                        FMUState,
                        serializedState.cast(),
                        size,
                    );
                fmi3DeserializeFMUState(
                    instance: fmi3Instance,
                    serializedState: *const fmi3Byte,
                    size: usize,
                    FMUState: *mut fmi3FMUState,
                ) -> fmi3Status =>
                    shared::deserialize_fmu_state::<__RustfmuModel>(
                        &TERMS,
                        component(instance),
                        serializedState.cast(),
                        size,
                        FMUState,
                    );
                fmi3GetDirectionalDerivative(
                    instance: fmi3Instance,
                    unknowns: *const fmi3ValueReference,
                    nUnknowns: usize,
                    knowns: *const fmi3ValueReference,
                    nKnowns: usize,
                    seed: *const fmi3Float64,
                    nSeed: usize,
                    sensitivity: *mut fmi3Float64,
                    nSensitivity: usize,
                ) -> fmi3Status =>
                    api3::get_derivative::<__RustfmuModel>(
                        false,
                        component(instance),
                        unknowns,
                        nUnknowns,
                        knowns,
                        nKnowns,
                        seed,
                        nSeed,
                        sensitivity,
                        nSensitivity,
                    );
                fmi3GetAdjointDerivative(
                    instance: fmi3Instance,
                    unknowns: *const fmi3ValueReference,
                    nUnknowns: usize,
                    knowns: *const fmi3ValueReference,
                    nKnowns: usize,
                    seed: *const fmi3Float64,
                    nSeed: usize,
                    sensitivity: *mut fmi3Float64,
                    nSensitivity: usize,
                ) -> fmi3Status =>
                    api3::get_derivative::<__RustfmuModel>(
                        true,
                        component(instance),
                        unknowns,
                        nUnknowns,
                        knowns,
                        nKnowns,
                        seed,
                        nSeed,
                        sensitivity,
                        nSensitivity,
                    );
                fmi3EvaluateDiscreteStates(instance: fmi3Instance) -> fmi3Status =>
                    api3::evaluate_discrete_states::<__RustfmuModel>(component(instance));
                fmi3UpdateDiscreteStates(
                    instance: fmi3Instance,
                    discreteStatesNeedUpdate: *mut fmi3Boolean,
                    terminateSimulation: *mut fmi3Boolean,
                    nominalsOfContinuousStatesChanged: *mut fmi3Boolean,
                    valuesOfContinuousStatesChanged: *mut fmi3Boolean,
                    nextEventTimeDefined: *mut fmi3Boolean,
                    nextEventTime: *mut fmi3Float64,
                ) -> fmi3Status =>
                    api3::update_discrete_states::<__RustfmuModel>(
                        component(instance),
                        discreteStatesNeedUpdate,
                        terminateSimulation,
                        nominalsOfContinuousStatesChanged,
                        valuesOfContinuousStatesChanged,
                        nextEventTimeDefined,
                        nextEventTime,
                    );
                fmi3EnterContinuousTimeMode(instance: fmi3Instance) -> fmi3Status =>
                    shared::transition::<__RustfmuModel>(&TERMS, shared::Transition::EnterContinuousTimeMode, component(instance));
                fmi3CompletedIntegratorStep(
                    instance: fmi3Instance,
                    noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
                    enterEventMode: *mut fmi3Boolean,
                    terminateSimulation: *mut fmi3Boolean,
                ) -> fmi3Status =>
                    shared::completed_integrator_step::<__RustfmuModel, fmi3Boolean>(
                        &TERMS,
                        component(instance),
                        noSetFMUStatePriorToCurrentPoint,
                        enterEventMode,
                        terminateSimulation,
                    );
                fmi3SetTime(instance: fmi3Instance, time: fmi3Float64) -> fmi3Status =>
                    shared::set_time::<__RustfmuModel>(&TERMS, component(instance), time);
                fmi3SetContinuousStates(
                    instance: fmi3Instance,
                    continuousStates: *const fmi3Float64,
                    nContinuousStates: usize,
                ) -> fmi3Status =>
                    shared::set_continuous_states::<__RustfmuModel>(&TERMS, component(instance), continuousStates, nContinuousStates);
                fmi3GetContinuousStateDerivatives(
                    instance: fmi3Instance,
                    derivatives: *mut fmi3Float64,
                    n: usize,
                ) -> fmi3Status =>
                    shared::get_vector::<__RustfmuModel>(&TERMS, shared::Vector::Derivatives, component(instance), derivatives, n);
                fmi3GetEventIndicators(
                    instance: fmi3Instance,
                    eventIndicators: *mut fmi3Float64,
                    n: usize,
                ) -> fmi3Status =>
                    shared::get_vector::<__RustfmuModel>(
                        &TERMS,
                        shared::Vector::EventIndicators,
                        component(instance),
                        eventIndicators,
                        n,
                    );
                fmi3GetContinuousStates(
                    instance: fmi3Instance,
                    continuousStates: *mut fmi3Float64,
                    n: usize,
                ) -> fmi3Status =>
                    shared::get_vector::<__RustfmuModel>(
                        &TERMS,
                        shared::Vector::ContinuousStates,
                        component(instance),
                        continuousStates,
                        n,
                    );
                fmi3GetNominalsOfContinuousStates(
                    instance: fmi3Instance,
                    nominals: *mut fmi3Float64,
                    n: usize,
                ) -> fmi3Status =>
                    shared::get_vector::<__RustfmuModel>(&TERMS, shared::Vector::Nominals, component(instance), nominals, n);
                fmi3GetNumberOfEventIndicators(instance: fmi3Instance, n: *mut usize) -> fmi3Status =>
                    api3::get_number_of_event_indicators::<__RustfmuModel>(component(instance), n);
                fmi3GetNumberOfContinuousStates(instance: fmi3Instance, n: *mut usize) -> fmi3Status =>
                    api3::get_number_of_continuous_states::<__RustfmuModel>(component(instance), n);
                // Configuration Mode: an FMU without structural parameters refuses both with the
                // reason (`enter_configuration_mode`).
                fmi3EnterConfigurationMode(instance: fmi3Instance) -> fmi3Status =>
                    api3::enter_configuration_mode::<__RustfmuModel>(component(instance));
                fmi3ExitConfigurationMode(instance: fmi3Instance) -> fmi3Status =>
                    api3::exit_configuration_mode::<__RustfmuModel>(component(instance));
                fmi3EnterStepMode(instance: fmi3Instance) -> fmi3Status =>
                    api3::enter_step_mode::<__RustfmuModel>(component(instance));
                fmi3GetOutputDerivatives(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    orders: *const fmi3Int32,
                    values: *mut fmi3Float64,
                    nValues: usize,
                ) -> fmi3Status =>
                    api3::get_output_derivatives::<__RustfmuModel>(
                        component(instance),
                        valueReferences,
                        nValueReferences,
                        orders,
                        values,
                        nValues,
                    );
                fmi3GetNumberOfVariableDependencies(
                    instance: fmi3Instance,
                    dependent: fmi3ValueReference,
                    nDependencies: *mut usize,
                ) -> fmi3Status =>
                    api3::get_number_of_variable_dependencies::<__RustfmuModel>(component(instance), dependent, nDependencies);
                fmi3GetVariableDependencies(
                    instance: fmi3Instance,
                    dependent: fmi3ValueReference,
                    elementIndicesOfDependent: *mut usize,
                    independents: *mut fmi3ValueReference,
                    elementIndicesOfIndependents: *mut usize,
                    dependencyKinds: *mut fmi3DependencyKind,
                    nDependencies: usize,
                ) -> fmi3Status =>
                    api3::get_variable_dependencies::<__RustfmuModel>(
                        component(instance),
                        dependent,
                        elementIndicesOfDependent,
                        independents,
                        elementIndicesOfIndependents,
                        dependencyKinds,
                        nDependencies,
                    );
                fmi3DoStep(
                    instance: fmi3Instance,
                    currentCommunicationPoint: fmi3Float64,
                    communicationStepSize: fmi3Float64,
                    noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
                    eventHandlingNeeded: *mut fmi3Boolean,
                    terminateSimulation: *mut fmi3Boolean,
                    earlyReturn: *mut fmi3Boolean,
                    lastSuccessfulTime: *mut fmi3Float64,
                ) -> fmi3Status =>
                    api3::do_step::<__RustfmuModel>(
                        component(instance),
                        currentCommunicationPoint,
                        communicationStepSize,
                        noSetFMUStatePriorToCurrentPoint,
                        eventHandlingNeeded,
                        terminateSimulation,
                        earlyReturn,
                        lastSuccessfulTime,
                    );
                // Clocks (a model without any refuses each call with that reason).
                fmi3SetClock(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    values: *const fmi3Clock,
                ) -> fmi3Status =>
                    api3::set_clock::<__RustfmuModel>(component(instance), valueReferences, nValueReferences, values);
                fmi3GetClock(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    values: *mut fmi3Clock,
                ) -> fmi3Status =>
                    api3::get_clock::<__RustfmuModel>(component(instance), valueReferences, nValueReferences, values);
                fmi3GetIntervalDecimal(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    intervals: *mut fmi3Float64,
                    qualifiers: *mut fmi3IntervalQualifier,
                ) -> fmi3Status =>
                    api3::get_interval_decimal::<__RustfmuModel>(
                        component(instance),
                        valueReferences,
                        nValueReferences,
                        intervals,
                        qualifiers,
                    );
                fmi3GetShiftDecimal(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    shifts: *mut fmi3Float64,
                ) -> fmi3Status =>
                    api3::get_shift_decimal::<__RustfmuModel>(component(instance), valueReferences, nValueReferences, shifts);
                fmi3SetIntervalDecimal(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    intervals: *const fmi3Float64,
                ) -> fmi3Status =>
                    api3::set_interval_decimal::<__RustfmuModel>(component(instance), valueReferences, nValueReferences, intervals);
                fmi3SetShiftDecimal(
                    instance: fmi3Instance,
                    valueReferences: *const fmi3ValueReference,
                    nValueReferences: usize,
                    shifts: *const fmi3Float64,
                ) -> fmi3Status =>
                    api3::set_shift_decimal::<__RustfmuModel>(component(instance), valueReferences, nValueReferences, shifts);
            }
            // The getters and setters of the FMI 3.0 types without a 2.0 counterpart.
            $crate::__rustfmu_fmi3_refusals! {
                typed for __RustfmuModel:
                fmi3GetFloat32, fmi3SetFloat32(fmi3Float32);
                fmi3GetInt8, fmi3SetInt8(fmi3Int8);
                fmi3GetUInt8, fmi3SetUInt8(fmi3UInt8);
                fmi3GetInt16, fmi3SetInt16(fmi3Int16);
                fmi3GetUInt16, fmi3SetUInt16(fmi3UInt16);
                fmi3GetUInt32, fmi3SetUInt32(fmi3UInt32);
                fmi3GetUInt64, fmi3SetUInt64(fmi3UInt64);
            }
            const NO_FRACTIONS: &str = "its clocks have supportsFraction = false: use the Decimal functions";
            // The functions of the features this FMU does not have, each with the reason.
            $crate::__rustfmu_fmi3_refusals! {
                not_provided for __RustfmuModel:
                fmi3GetIntervalFraction(
                    _valueReferences: *const fmi3ValueReference,
                    _nValueReferences: usize,
                    _counters: *mut fmi3UInt64,
                    _resolutions: *mut fmi3UInt64,
                    _qualifiers: *mut fmi3IntervalQualifier,
                ) => NO_FRACTIONS;
                fmi3GetShiftFraction(
                    _valueReferences: *const fmi3ValueReference,
                    _nValueReferences: usize,
                    _counters: *mut fmi3UInt64,
                    _resolutions: *mut fmi3UInt64,
                ) => NO_FRACTIONS;
                fmi3SetIntervalFraction(
                    _valueReferences: *const fmi3ValueReference,
                    _nValueReferences: usize,
                    _counters: *const fmi3UInt64,
                    _resolutions: *const fmi3UInt64,
                ) => NO_FRACTIONS;
                fmi3SetShiftFraction(
                    _valueReferences: *const fmi3ValueReference,
                    _nValueReferences: usize,
                    _counters: *const fmi3UInt64,
                    _resolutions: *const fmi3UInt64,
                ) => NO_FRACTIONS;
            }
        }
    };
}
