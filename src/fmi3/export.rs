//! `export_fmi3!(Model)`: the FMI 3.0 functions of a model (usually through
//! [`export_fmu!`](crate::export_fmu), which exports both versions).

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
            type __RustfmuModel = $model;

            const INTERFACES: $crate::description::Interfaces = $crate::description::Interfaces::BOTH_FMI3;
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
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetDebugLogging(
                instance: fmi3Instance,
                loggingOn: fmi3Boolean,
                nCategories: usize,
                categories: *const fmi3String,
            ) -> fmi3Status {
                unsafe { api3::set_debug_logging::<__RustfmuModel>(instance, loggingOn, nCategories, categories) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3InstantiateModelExchange(
                instanceName: fmi3String,
                instantiationToken: fmi3String,
                resourcePath: fmi3String,
                visible: fmi3Boolean,
                loggingOn: fmi3Boolean,
                instanceEnvironment: fmi3InstanceEnvironment,
                logMessage: fmi3LogMessageCallback,
            ) -> fmi3Instance {
                unsafe {
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
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
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
            ) -> fmi3Instance {
                unsafe {
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
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
                instanceName: fmi3String,
                _instantiationToken: fmi3String,
                _resourcePath: fmi3String,
                _visible: fmi3Boolean,
                _loggingOn: fmi3Boolean,
                instanceEnvironment: fmi3InstanceEnvironment,
                logMessage: fmi3LogMessageCallback,
                _clockUpdate: fmi3ClockUpdateCallback,
                _lockPreemption: fmi3LockPreemptionCallback,
                _unlockPreemption: fmi3UnlockPreemptionCallback,
            ) -> fmi3Instance {
                unsafe {
                    api3::instantiate_scheduled_execution::<__RustfmuModel>(
                        instanceName,
                        instanceEnvironment,
                        logMessage,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3FreeInstance(instance: fmi3Instance) {
                unsafe { shared::free_instance::<__RustfmuModel>(&TERMS, instance) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3EnterInitializationMode(
                instance: fmi3Instance,
                toleranceDefined: fmi3Boolean,
                tolerance: fmi3Float64,
                startTime: fmi3Float64,
                stopTimeDefined: fmi3Boolean,
                stopTime: fmi3Float64,
            ) -> fmi3Status {
                unsafe {
                    api3::enter_initialization_mode::<__RustfmuModel>(
                        instance,
                        toleranceDefined,
                        tolerance,
                        startTime,
                        stopTimeDefined,
                        stopTime,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status {
                unsafe { api3::exit_initialization_mode::<__RustfmuModel>(instance) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3EnterEventMode(instance: fmi3Instance) -> fmi3Status {
                unsafe { api3::enter_event_mode::<__RustfmuModel>(instance) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3Terminate(instance: fmi3Instance) -> fmi3Status {
                unsafe { api3::terminate::<__RustfmuModel>(instance) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3Reset(instance: fmi3Instance) -> fmi3Status {
                unsafe { api3::reset::<__RustfmuModel>(instance) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetFloat32(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *mut fmi3Float32,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_none::<__RustfmuModel>(
                        instance,
                        "fmi3GetFloat32",
                        "Float32",
                        valueReferences,
                        nValueReferences,
                        values.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetInt8(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *mut fmi3Int8,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_none::<__RustfmuModel>(
                        instance,
                        "fmi3GetInt8",
                        "Int8",
                        valueReferences,
                        nValueReferences,
                        values.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetUInt8(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *mut fmi3UInt8,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_none::<__RustfmuModel>(
                        instance,
                        "fmi3GetUInt8",
                        "UInt8",
                        valueReferences,
                        nValueReferences,
                        values.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetInt16(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *mut fmi3Int16,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_none::<__RustfmuModel>(
                        instance,
                        "fmi3GetInt16",
                        "Int16",
                        valueReferences,
                        nValueReferences,
                        values.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetUInt16(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *mut fmi3UInt16,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_none::<__RustfmuModel>(
                        instance,
                        "fmi3GetUInt16",
                        "UInt16",
                        valueReferences,
                        nValueReferences,
                        values.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetUInt32(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *mut fmi3UInt32,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_none::<__RustfmuModel>(
                        instance,
                        "fmi3GetUInt32",
                        "UInt32",
                        valueReferences,
                        nValueReferences,
                        values.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetUInt64(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *mut fmi3UInt64,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_none::<__RustfmuModel>(
                        instance,
                        "fmi3GetUInt64",
                        "UInt64",
                        valueReferences,
                        nValueReferences,
                        values.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetFloat64(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *mut fmi3Float64,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_float64::<__RustfmuModel>(instance, valueReferences, nValueReferences, values, nValues)
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetInt32(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *mut fmi3Int32,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_int32::<__RustfmuModel>(instance, valueReferences, nValueReferences, values, nValues)
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetInt64(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *mut fmi3Int64,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_int64::<__RustfmuModel>(instance, valueReferences, nValueReferences, values, nValues)
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetBoolean(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *mut fmi3Boolean,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_boolean::<__RustfmuModel>(instance, valueReferences, nValueReferences, values, nValues)
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetString(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *mut fmi3String,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_string::<__RustfmuModel>(instance, valueReferences, nValueReferences, values, nValues)
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetFloat32(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *const fmi3Float32,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::set_none::<__RustfmuModel>(
                        instance,
                        "fmi3SetFloat32",
                        "Float32",
                        valueReferences,
                        nValueReferences,
                        values.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetInt8(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *const fmi3Int8,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::set_none::<__RustfmuModel>(
                        instance,
                        "fmi3SetInt8",
                        "Int8",
                        valueReferences,
                        nValueReferences,
                        values.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetUInt8(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *const fmi3UInt8,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::set_none::<__RustfmuModel>(
                        instance,
                        "fmi3SetUInt8",
                        "UInt8",
                        valueReferences,
                        nValueReferences,
                        values.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetInt16(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *const fmi3Int16,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::set_none::<__RustfmuModel>(
                        instance,
                        "fmi3SetInt16",
                        "Int16",
                        valueReferences,
                        nValueReferences,
                        values.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetUInt16(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *const fmi3UInt16,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::set_none::<__RustfmuModel>(
                        instance,
                        "fmi3SetUInt16",
                        "UInt16",
                        valueReferences,
                        nValueReferences,
                        values.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetUInt32(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *const fmi3UInt32,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::set_none::<__RustfmuModel>(
                        instance,
                        "fmi3SetUInt32",
                        "UInt32",
                        valueReferences,
                        nValueReferences,
                        values.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetUInt64(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *const fmi3UInt64,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::set_none::<__RustfmuModel>(
                        instance,
                        "fmi3SetUInt64",
                        "UInt64",
                        valueReferences,
                        nValueReferences,
                        values.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetFloat64(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *const fmi3Float64,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::set_float64::<__RustfmuModel>(instance, valueReferences, nValueReferences, values, nValues)
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetInt32(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *const fmi3Int32,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::set_int32::<__RustfmuModel>(instance, valueReferences, nValueReferences, values, nValues)
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetInt64(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *const fmi3Int64,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::set_int64::<__RustfmuModel>(instance, valueReferences, nValueReferences, values, nValues)
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetBoolean(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *const fmi3Boolean,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::set_boolean::<__RustfmuModel>(instance, valueReferences, nValueReferences, values, nValues)
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetString(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                values: *const fmi3String,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::set_string::<__RustfmuModel>(instance, valueReferences, nValueReferences, values, nValues)
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetBinary(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                valueSizes: *mut usize,
                values: *mut fmi3Binary,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_none::<__RustfmuModel>(
                        instance,
                        "fmi3GetBinary",
                        "Binary",
                        valueReferences,
                        nValueReferences,
                        values.is_null() || valueSizes.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetBinary(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                valueSizes: *const usize,
                values: *const fmi3Binary,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::set_none::<__RustfmuModel>(
                        instance,
                        "fmi3SetBinary",
                        "Binary",
                        valueReferences,
                        nValueReferences,
                        values.is_null() || valueSizes.is_null(),
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetClock(
                instance: fmi3Instance,
                _valueReferences: *const fmi3ValueReference,
                _nValueReferences: usize,
                _values: *mut fmi3Clock,
            ) -> fmi3Status {
                unsafe { api3::not_provided::<__RustfmuModel>(instance, "fmi3GetClock", NO_CLOCKS) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetClock(
                instance: fmi3Instance,
                _valueReferences: *const fmi3ValueReference,
                _nValueReferences: usize,
                _values: *const fmi3Clock,
            ) -> fmi3Status {
                unsafe { api3::not_provided::<__RustfmuModel>(instance, "fmi3SetClock", NO_CLOCKS) }
            }
            const NO_CLOCKS: &str = "this FMU has no clocks";
            const NO_DEPENDENCIES: &str =
                "not provided at run time: the dependencies are in modelDescription.xml's ModelStructure";
            const NO_CONFIGURATION: &str = "this FMU has no structural parameters, so there is no configuration mode";
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetNumberOfVariableDependencies(
                instance: fmi3Instance,
                _valueReference: fmi3ValueReference,
                _nDependencies: *mut usize,
            ) -> fmi3Status {
                unsafe {
                    api3::not_provided::<__RustfmuModel>(
                        instance,
                        "fmi3GetNumberOfVariableDependencies",
                        NO_DEPENDENCIES,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetVariableDependencies(
                instance: fmi3Instance,
                _dependent: fmi3ValueReference,
                _elementIndicesOfDependent: *mut usize,
                _independents: *mut fmi3ValueReference,
                _elementIndicesOfIndependents: *mut usize,
                _dependencyKinds: *mut fmi3DependencyKind,
                _nDependencies: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::not_provided::<__RustfmuModel>(instance, "fmi3GetVariableDependencies", NO_DEPENDENCIES)
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetFMUState(
                instance: fmi3Instance,
                FMUState: *mut fmi3FMUState,
            ) -> fmi3Status {
                unsafe { shared::get_fmu_state::<__RustfmuModel>(&TERMS, instance, FMUState) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetFMUState(instance: fmi3Instance, FMUState: fmi3FMUState) -> fmi3Status {
                unsafe { shared::set_fmu_state::<__RustfmuModel>(&TERMS, instance, FMUState) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3FreeFMUState(
                instance: fmi3Instance,
                FMUState: *mut fmi3FMUState,
            ) -> fmi3Status {
                unsafe { shared::free_fmu_state::<__RustfmuModel>(&TERMS, instance, FMUState) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
                instance: fmi3Instance,
                FMUState: fmi3FMUState,
                size: *mut usize,
            ) -> fmi3Status {
                unsafe { shared::serialized_fmu_state_size::<__RustfmuModel>(&TERMS, instance, FMUState, size) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SerializeFMUState(
                instance: fmi3Instance,
                FMUState: fmi3FMUState,
                serializedState: *mut fmi3Byte,
                size: usize,
            ) -> fmi3Status {
                unsafe {
                    shared::serialize_fmu_state::<__RustfmuModel>(
                        &TERMS,
                        instance,
                        FMUState,
                        serializedState.cast(),
                        size,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3DeserializeFMUState(
                instance: fmi3Instance,
                serializedState: *const fmi3Byte,
                size: usize,
                FMUState: *mut fmi3FMUState,
            ) -> fmi3Status {
                unsafe {
                    shared::deserialize_fmu_state::<__RustfmuModel>(
                        &TERMS,
                        instance,
                        serializedState.cast(),
                        size,
                        FMUState,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetDirectionalDerivative(
                instance: fmi3Instance,
                unknowns: *const fmi3ValueReference,
                nUnknowns: usize,
                knowns: *const fmi3ValueReference,
                nKnowns: usize,
                seed: *const fmi3Float64,
                nSeed: usize,
                sensitivity: *mut fmi3Float64,
                nSensitivity: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_directional_derivative::<__RustfmuModel>(
                        instance,
                        unknowns,
                        nUnknowns,
                        knowns,
                        nKnowns,
                        seed,
                        nSeed,
                        sensitivity,
                        nSensitivity,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetAdjointDerivative(
                instance: fmi3Instance,
                unknowns: *const fmi3ValueReference,
                nUnknowns: usize,
                knowns: *const fmi3ValueReference,
                nKnowns: usize,
                seed: *const fmi3Float64,
                nSeed: usize,
                sensitivity: *mut fmi3Float64,
                nSensitivity: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_adjoint_derivative::<__RustfmuModel>(
                        instance,
                        unknowns,
                        nUnknowns,
                        knowns,
                        nKnowns,
                        seed,
                        nSeed,
                        sensitivity,
                        nSensitivity,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3EnterConfigurationMode(instance: fmi3Instance) -> fmi3Status {
                unsafe {
                    api3::not_provided::<__RustfmuModel>(instance, "fmi3EnterConfigurationMode", NO_CONFIGURATION)
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3ExitConfigurationMode(instance: fmi3Instance) -> fmi3Status {
                unsafe { api3::not_provided::<__RustfmuModel>(instance, "fmi3ExitConfigurationMode", NO_CONFIGURATION) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetIntervalDecimal(
                instance: fmi3Instance,
                _valueReferences: *const fmi3ValueReference,
                _nValueReferences: usize,
                _intervals: *mut fmi3Float64,
                _qualifiers: *mut fmi3IntervalQualifier,
            ) -> fmi3Status {
                unsafe { api3::not_provided::<__RustfmuModel>(instance, "fmi3GetIntervalDecimal", NO_CLOCKS) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetIntervalFraction(
                instance: fmi3Instance,
                _valueReferences: *const fmi3ValueReference,
                _nValueReferences: usize,
                _counters: *mut fmi3UInt64,
                _resolutions: *mut fmi3UInt64,
                _qualifiers: *mut fmi3IntervalQualifier,
            ) -> fmi3Status {
                unsafe { api3::not_provided::<__RustfmuModel>(instance, "fmi3GetIntervalFraction", NO_CLOCKS) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetShiftDecimal(
                instance: fmi3Instance,
                _valueReferences: *const fmi3ValueReference,
                _nValueReferences: usize,
                _shifts: *mut fmi3Float64,
            ) -> fmi3Status {
                unsafe { api3::not_provided::<__RustfmuModel>(instance, "fmi3GetShiftDecimal", NO_CLOCKS) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetShiftFraction(
                instance: fmi3Instance,
                _valueReferences: *const fmi3ValueReference,
                _nValueReferences: usize,
                _counters: *mut fmi3UInt64,
                _resolutions: *mut fmi3UInt64,
            ) -> fmi3Status {
                unsafe { api3::not_provided::<__RustfmuModel>(instance, "fmi3GetShiftFraction", NO_CLOCKS) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetIntervalDecimal(
                instance: fmi3Instance,
                _valueReferences: *const fmi3ValueReference,
                _nValueReferences: usize,
                _intervals: *const fmi3Float64,
            ) -> fmi3Status {
                unsafe { api3::not_provided::<__RustfmuModel>(instance, "fmi3SetIntervalDecimal", NO_CLOCKS) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetIntervalFraction(
                instance: fmi3Instance,
                _valueReferences: *const fmi3ValueReference,
                _nValueReferences: usize,
                _counters: *const fmi3UInt64,
                _resolutions: *const fmi3UInt64,
            ) -> fmi3Status {
                unsafe { api3::not_provided::<__RustfmuModel>(instance, "fmi3SetIntervalFraction", NO_CLOCKS) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetShiftDecimal(
                instance: fmi3Instance,
                _valueReferences: *const fmi3ValueReference,
                _nValueReferences: usize,
                _shifts: *const fmi3Float64,
            ) -> fmi3Status {
                unsafe { api3::not_provided::<__RustfmuModel>(instance, "fmi3SetShiftDecimal", NO_CLOCKS) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetShiftFraction(
                instance: fmi3Instance,
                _valueReferences: *const fmi3ValueReference,
                _nValueReferences: usize,
                _counters: *const fmi3UInt64,
                _resolutions: *const fmi3UInt64,
            ) -> fmi3Status {
                unsafe { api3::not_provided::<__RustfmuModel>(instance, "fmi3SetShiftFraction", NO_CLOCKS) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3EvaluateDiscreteStates(instance: fmi3Instance) -> fmi3Status {
                unsafe { api3::evaluate_discrete_states::<__RustfmuModel>(instance) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3UpdateDiscreteStates(
                instance: fmi3Instance,
                discreteStatesNeedUpdate: *mut fmi3Boolean,
                terminateSimulation: *mut fmi3Boolean,
                nominalsOfContinuousStatesChanged: *mut fmi3Boolean,
                valuesOfContinuousStatesChanged: *mut fmi3Boolean,
                nextEventTimeDefined: *mut fmi3Boolean,
                nextEventTime: *mut fmi3Float64,
            ) -> fmi3Status {
                unsafe {
                    api3::update_discrete_states::<__RustfmuModel>(
                        instance,
                        discreteStatesNeedUpdate,
                        terminateSimulation,
                        nominalsOfContinuousStatesChanged,
                        valuesOfContinuousStatesChanged,
                        nextEventTimeDefined,
                        nextEventTime,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3EnterContinuousTimeMode(instance: fmi3Instance) -> fmi3Status {
                unsafe { api3::enter_continuous_time_mode::<__RustfmuModel>(instance) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3CompletedIntegratorStep(
                instance: fmi3Instance,
                noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
                enterEventMode: *mut fmi3Boolean,
                terminateSimulation: *mut fmi3Boolean,
            ) -> fmi3Status {
                unsafe {
                    api3::completed_integrator_step::<__RustfmuModel>(
                        instance,
                        noSetFMUStatePriorToCurrentPoint,
                        enterEventMode,
                        terminateSimulation,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetTime(instance: fmi3Instance, time: fmi3Float64) -> fmi3Status {
                unsafe { api3::set_time::<__RustfmuModel>(instance, time) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3SetContinuousStates(
                instance: fmi3Instance,
                continuousStates: *const fmi3Float64,
                nContinuousStates: usize,
            ) -> fmi3Status {
                unsafe { api3::set_continuous_states::<__RustfmuModel>(instance, continuousStates, nContinuousStates) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetContinuousStateDerivatives(
                instance: fmi3Instance,
                derivatives: *mut fmi3Float64,
                n: usize,
            ) -> fmi3Status {
                unsafe {
                    shared::get_vector::<__RustfmuModel>(&TERMS, shared::Vector::Derivatives, instance, derivatives, n)
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetEventIndicators(
                instance: fmi3Instance,
                eventIndicators: *mut fmi3Float64,
                n: usize,
            ) -> fmi3Status {
                unsafe {
                    shared::get_vector::<__RustfmuModel>(
                        &TERMS,
                        shared::Vector::EventIndicators,
                        instance,
                        eventIndicators,
                        n,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetContinuousStates(
                instance: fmi3Instance,
                continuousStates: *mut fmi3Float64,
                n: usize,
            ) -> fmi3Status {
                unsafe {
                    shared::get_vector::<__RustfmuModel>(
                        &TERMS,
                        shared::Vector::ContinuousStates,
                        instance,
                        continuousStates,
                        n,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetNominalsOfContinuousStates(
                instance: fmi3Instance,
                nominals: *mut fmi3Float64,
                n: usize,
            ) -> fmi3Status {
                unsafe { shared::get_vector::<__RustfmuModel>(&TERMS, shared::Vector::Nominals, instance, nominals, n) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetNumberOfEventIndicators(
                instance: fmi3Instance,
                n: *mut usize,
            ) -> fmi3Status {
                unsafe { api3::get_number_of_event_indicators::<__RustfmuModel>(instance, n) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetNumberOfContinuousStates(
                instance: fmi3Instance,
                n: *mut usize,
            ) -> fmi3Status {
                unsafe { api3::get_number_of_continuous_states::<__RustfmuModel>(instance, n) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3EnterStepMode(instance: fmi3Instance) -> fmi3Status {
                unsafe { api3::enter_step_mode::<__RustfmuModel>(instance) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3GetOutputDerivatives(
                instance: fmi3Instance,
                valueReferences: *const fmi3ValueReference,
                nValueReferences: usize,
                orders: *const fmi3Int32,
                values: *mut fmi3Float64,
                nValues: usize,
            ) -> fmi3Status {
                unsafe {
                    api3::get_output_derivatives::<__RustfmuModel>(
                        instance,
                        valueReferences,
                        nValueReferences,
                        orders,
                        values,
                        nValues,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3DoStep(
                instance: fmi3Instance,
                currentCommunicationPoint: fmi3Float64,
                communicationStepSize: fmi3Float64,
                noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
                eventHandlingNeeded: *mut fmi3Boolean,
                terminateSimulation: *mut fmi3Boolean,
                earlyReturn: *mut fmi3Boolean,
                lastSuccessfulTime: *mut fmi3Float64,
            ) -> fmi3Status {
                unsafe {
                    api3::do_step::<__RustfmuModel>(
                        instance,
                        currentCommunicationPoint,
                        communicationStepSize,
                        noSetFMUStatePriorToCurrentPoint,
                        eventHandlingNeeded,
                        terminateSimulation,
                        earlyReturn,
                        lastSuccessfulTime,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi3ActivateModelPartition(
                instance: fmi3Instance,
                _clockReference: fmi3ValueReference,
                _activationTime: fmi3Float64,
            ) -> fmi3Status {
                unsafe { api3::not_provided::<__RustfmuModel>(instance, "fmi3ActivateModelPartition", NO_CLOCKS) }
            }
        }
    };
}
