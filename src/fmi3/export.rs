//! `export_fmi3!(Model)`: the FMI 3.0 functions of a model (usually through
//! [`export_fmu!`](crate::export_fmu), which exports both versions).

/// Rows for [`__rustfmu_extern_c!`](crate::__rustfmu_extern_c) of the FMI 3.0 getters and
/// setters and of the functions that refuse, written from shorter rows: the C name of a typed
/// getter or a refusal says what it gets or refuses (passed on with `stringify!`), and every one
/// of a kind has the same parameters. Not part of the API.
#[doc(hidden)]
#[macro_export]
macro_rules! __rustfmu_fmi3_rows {
    // `fmi3GetX => get_x, fmi3SetX => set_x(fmi3X);`: the getter and the setter of a type with
    // runtime functions of its own.
    // Binaries have their sizes too: `(fmi3Binary, valueSizes)`.
    (values for $model:ty: $($get:ident => $getter:ident, $set:ident => $setter:ident($t:ty $(, $sizes:ident)?);)*) => {
        $crate::__rustfmu_fmi3_rows! {
            @values
            $(
                $get(mut $t $(, $sizes)?) => [$crate::__private::api3::$getter::<$model>] [];
                $set(const $t $(, $sizes)?) => [$crate::__private::api3::$setter::<$model>] [];
            )*
        }
    };
    // `fmi3GetX, fmi3SetX(fmi3X);`: the getter and the setter of an FMI 3.0 numeric type
    // without a 2.0 counterpart, through the runtime's generic ones.
    (typed for $model:ty: $($get:ident, $set:ident($t:ty);)*) => {
        $crate::__rustfmu_fmi3_rows! {
            @values
            $(
                $get(mut $t) => [$crate::__private::api3::get_typed::<$model, $t>] [stringify!($get)];
                $set(const $t) => [$crate::__private::api3::set_typed::<$model, $t>] [stringify!($set)];
            )*
        }
    };
    // `fmi3XValues(mut or const, the element type[, the sizes' parameter]) => [runtime function]
    // [its name, if it takes it];`: every getter and setter has the same parameters (`values`
    // and the sizes are `*mut` for a getter, `*const` for a setter).
    (@values $($name:ident($ptr:tt $t:ty $(, $sizes:ident)?) => [$($callee:tt)*] [$($label:expr)?];)*) => {
        $crate::__rustfmu_extern_c! {
            $(
                $name(
                    instance: $crate::__private::abi3::fmi3Instance,
                    valueReferences: *const $crate::__private::abi3::fmi3ValueReference,
                    nValueReferences: usize,
                    $($sizes: *$ptr usize,)?
                    values: *$ptr $t,
                    nValues: usize,
                ) -> $crate::__private::abi3::fmi3Status =>
                    $($callee)*(
                        component(instance),
                        $($label,)?
                        valueReferences,
                        nValueReferences,
                        $($sizes,)?
                        values,
                        nValues,
                    );
            )*
        }
    };
    // `fmi3GetXDerivative => adjoint;`: the two partial derivatives, one runtime function
    // (`adjoint`: Jᵀ seed, else J seed).
    (derivatives for $model:ty: $($name:ident => $adjoint:literal;)*) => {
        $crate::__rustfmu_extern_c! {
            $(
                $name(
                    instance: $crate::__private::abi3::fmi3Instance,
                    unknowns: *const $crate::__private::abi3::fmi3ValueReference,
                    nUnknowns: usize,
                    knowns: *const $crate::__private::abi3::fmi3ValueReference,
                    nKnowns: usize,
                    seed: *const $crate::__private::abi3::fmi3Float64,
                    nSeed: usize,
                    sensitivity: *mut $crate::__private::abi3::fmi3Float64,
                    nSensitivity: usize,
                ) -> $crate::__private::abi3::fmi3Status =>
                    $crate::__private::api3::get_derivative::<$model>(
                        $adjoint,
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
            )*
        }
    };
    // `fmi3InstantiateX(parameters after loggingOn; parameters after logMessage) =>
    // instantiate_x(arguments after the shared ones);`: the three instantiation functions, whose
    // shared parameters go to the runtime as one `Instantiation` (with the binary's `TOKEN` and
    // `DESCRIPTION`).
    (instantiate for $model:ty: $(
        $name:ident($($middle:ident: $middle_ty:ty),*; $($end:ident: $end_ty:ty),*) => $runtime:ident($($arg:expr),*);
    )*) => {
        $crate::__rustfmu_extern_c! {
            $(
                $name(
                    instanceName: $crate::__private::abi3::fmi3String,
                    instantiationToken: $crate::__private::abi3::fmi3String,
                    resourcePath: $crate::__private::abi3::fmi3String,
                    _visible: $crate::__private::abi3::fmi3Boolean,
                    loggingOn: $crate::__private::abi3::fmi3Boolean,
                    $($middle: $middle_ty,)*
                    instanceEnvironment: $crate::__private::abi3::fmi3InstanceEnvironment,
                    logMessage: $crate::__private::abi3::fmi3LogMessageCallback,
                    $($end: $end_ty,)*
                ) -> $crate::__private::abi3::fmi3Instance =>
                    $crate::__private::api3::$runtime::<$model>(
                        $crate::__private::api3::Instantiation {
                            own_token: TOKEN,
                            description: &DESCRIPTION,
                            instance_name: instanceName,
                            token: instantiationToken,
                            resource_path: resourcePath,
                            logging_on: loggingOn,
                            environment: instanceEnvironment,
                            log_message: logMessage,
                        },
                        $($arg),*
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

            $crate::__rustfmu_embedded_description!(
                __RustfmuModel,
                V3,
                // FMI 3.0 has no input derivatives.
                can_interpolate_inputs: false,
                scheduled_execution: <__RustfmuModel as $crate::Variables>::SCHEDULED_EXECUTION,
                TOKEN,
                TOKEN_TEXT,
                "the token is ASCII"
            );

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
            $crate::__rustfmu_shared_exports! {
                for __RustfmuModel: instance fmi3Instance, status fmi3Status, boolean fmi3Boolean, real fmi3Float64,
                    byte fmi3Byte, FMU state fmi3FMUState;
                transitions: fmi3ExitInitializationMode => ExitInitializationMode, fmi3EnterEventMode => EnterEventMode,
                    fmi3Terminate => Terminate, fmi3Reset => Reset,
                    fmi3EnterContinuousTimeMode => EnterContinuousTimeMode;
                FMU state: fmi3GetFMUState, fmi3SetFMUState, fmi3FreeFMUState, fmi3SerializedFMUStateSize,
                    fmi3SerializeFMUState, fmi3DeserializeFMUState;
                vectors: fmi3GetContinuousStateDerivatives => Derivatives, fmi3GetEventIndicators => EventIndicators,
                    fmi3GetContinuousStates => ContinuousStates, fmi3GetNominalsOfContinuousStates => Nominals;
                model exchange: fmi3CompletedIntegratorStep, fmi3SetTime, fmi3SetContinuousStates;
            }
            $crate::__rustfmu_fmi3_rows! {
                instantiate for __RustfmuModel:
                fmi3InstantiateModelExchange(;) => instantiate_model_exchange();
                fmi3InstantiateCoSimulation(
                    eventModeUsed: fmi3Boolean,
                    earlyReturnAllowed: fmi3Boolean,
                    requiredIntermediateVariables: *const fmi3ValueReference,
                    nRequiredIntermediateVariables: usize;
                    intermediateUpdate: fmi3IntermediateUpdateCallback
                ) => instantiate_co_simulation(
                    eventModeUsed,
                    earlyReturnAllowed,
                    requiredIntermediateVariables,
                    nRequiredIntermediateVariables,
                    intermediateUpdate
                );
                fmi3InstantiateScheduledExecution(;
                    clockUpdate: fmi3ClockUpdateCallback,
                    _lockPreemption: fmi3LockPreemptionCallback,
                    _unlockPreemption: fmi3UnlockPreemptionCallback
                ) => instantiate_scheduled_execution(clockUpdate);
            }
            $crate::__rustfmu_fmi3_rows! {
                derivatives for __RustfmuModel:
                fmi3GetDirectionalDerivative => false;
                fmi3GetAdjointDerivative => true;
            }
            // The getters and setters of the types with runtime functions of their own (Enumerations
            // are Int64).
            $crate::__rustfmu_fmi3_rows! {
                values for __RustfmuModel:
                fmi3GetFloat64 => get_float64, fmi3SetFloat64 => set_float64(fmi3Float64);
                fmi3GetInt32 => get_int32, fmi3SetInt32 => set_int32(fmi3Int32);
                fmi3GetInt64 => get_int64, fmi3SetInt64 => set_int64(fmi3Int64);
                fmi3GetBoolean => get_boolean, fmi3SetBoolean => set_boolean(fmi3Boolean);
                fmi3GetString => get_string, fmi3SetString => set_string(fmi3String);
                fmi3GetBinary => get_binary, fmi3SetBinary => set_binary(fmi3Binary, valueSizes);
            }
            // The getters and setters of the FMI 3.0 types without a 2.0 counterpart.
            $crate::__rustfmu_fmi3_rows! {
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
            $crate::__rustfmu_fmi3_rows! {
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
