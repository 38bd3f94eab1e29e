//! The rows of the export table that FMI 2.0 and FMI 3.0 share: the functions both versions
//! forward to the same runtime function (`crate::core::shared`), with only their C names and
//! C types told apart. [`__rustfmu_shared_exports!`] writes them for
//! [`export_fmi2!`](crate::export_fmi2) and [`export_fmi3!`](crate::export_fmi3), through
//! `__rustfmu_extern_c!` like every other row (`crate::core::trampolines`).

/// The rows both versions share, for the version whose C names and types are given (its
/// `TERMS`, `shared` and `component` in scope, as in the export macros): the state transitions
/// without arguments, the FMU state functions, model exchange's state vector and vectors. The
/// parameters are named as `fmi3Functions.h` names them. Not part of the API.
#[doc(hidden)]
#[macro_export]
macro_rules! __rustfmu_shared_exports {
    (
        for $model:ty: instance $instance:ty, status $status:ty, boolean $boolean:ty, real $real:ty,
            byte $byte:ty, FMU state $fmu_state:ty;
        transitions: $($transition:ident => $which:ident),*;
        FMU state: $get:ident, $set:ident, $free:ident, $size:ident, $serialize:ident, $deserialize:ident;
        vectors: $($vector:ident => $kind:ident),*;
        model exchange: $completed:ident, $set_time:ident, $set_states:ident;
    ) => {
        $crate::__rustfmu_extern_c! {
            $(
                $transition(instance: $instance) -> $status =>
                    shared::transition::<$model>(&TERMS, shared::Transition::$which, component(instance));
            )*
            $get(instance: $instance, FMUState: *mut $fmu_state) -> $status =>
                shared::get_fmu_state::<$model>(&TERMS, component(instance), FMUState);
            $set(instance: $instance, FMUState: $fmu_state) -> $status =>
                shared::set_fmu_state::<$model>(&TERMS, component(instance), FMUState);
            $free(instance: $instance, FMUState: *mut $fmu_state) -> $status =>
                shared::free_fmu_state::<$model>(&TERMS, component(instance), FMUState);
            $size(instance: $instance, FMUState: $fmu_state, size: *mut usize) -> $status =>
                shared::serialized_fmu_state_size::<$model>(&TERMS, component(instance), FMUState, size);
            $serialize(
                instance: $instance,
                FMUState: $fmu_state,
                serializedState: *mut $byte,
                size: usize,
            ) -> $status =>
                shared::serialize_fmu_state::<$model>(&TERMS, component(instance), FMUState, serializedState.cast(), size);
            $deserialize(
                instance: $instance,
                serializedState: *const $byte,
                size: usize,
                FMUState: *mut $fmu_state,
            ) -> $status =>
                shared::deserialize_fmu_state::<$model>(&TERMS, component(instance), serializedState.cast(), size, FMUState);
            $completed(
                instance: $instance,
                noSetFMUStatePriorToCurrentPoint: $boolean,
                enterEventMode: *mut $boolean,
                terminateSimulation: *mut $boolean,
            ) -> $status =>
                shared::completed_integrator_step::<$model, $boolean>(
                    &TERMS,
                    component(instance),
                    noSetFMUStatePriorToCurrentPoint,
                    enterEventMode,
                    terminateSimulation,
                );
            $set_time(instance: $instance, time: $real) -> $status =>
                shared::set_time::<$model>(&TERMS, component(instance), time);
            $set_states(instance: $instance, continuousStates: *const $real, nContinuousStates: usize) -> $status =>
                shared::set_continuous_states::<$model>(&TERMS, component(instance), continuousStates, nContinuousStates);
            $(
                $vector(instance: $instance, values: *mut $real, nValues: usize) -> $status =>
                    shared::get_vector::<$model>(&TERMS, shared::Vector::$kind, component(instance), values, nValues);
            )*
        }
    };
}

/// The model's encoded description for one version (`V2`, `V3`; the interfaces' options
/// given), embedded in the library where `cargo fmu` finds it (`DESCRIPTION`, see
/// `rustfmu::description::find_encoded`), and its token computed from it at compile time (FMI
/// 2.0's GUID, FMI 3.0's instantiationToken: `pub const $token`).
/// Not part of the API.
#[doc(hidden)]
#[macro_export]
macro_rules! __rustfmu_embedded_description {
    (
        $model:ty,
        $version:ident,
        can_interpolate_inputs: $can_interpolate_inputs:expr,
        scheduled_execution: $scheduled_execution:expr,
        $token:ident,
        $token_text:ident,
        $not_ascii:literal $(,)?
    ) => {
        const INTERFACES: $crate::description::Interfaces = $crate::description::Interfaces {
            co_simulation: <$model as $crate::Variables>::CO_SIMULATION,
            model_exchange: <$model as $crate::Variables>::MODEL_EXCHANGE,
            version: $crate::description::FmiVersion::$version,
            can_interpolate_inputs: $can_interpolate_inputs,
            scheduled_execution: $scheduled_execution,
        };
        const LEN: usize = $crate::description::encoded_len(&<$model as $crate::Variables>::DESCRIPTION, INTERFACES);
        const ENCODED: [u8; LEN] = $crate::description::encode(&<$model as $crate::Variables>::DESCRIPTION, INTERFACES);
        const $token_text: [u8; 38] = $crate::description::guid(&ENCODED);
        pub const $token: &str = match ::core::str::from_utf8(&$token_text) {
            Ok(s) => s,
            Err(_) => panic!($not_ascii),
        };
        /// The description, where `cargo fmu` finds it (see `rustfmu::description::find_encoded`).
        #[used]
        static DESCRIPTION: [u8; LEN] = ENCODED;
    };
}
