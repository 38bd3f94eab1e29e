//! What an FMI 3.0 container refuses, each function saying why: the getters and setters of the
//! types it has no variable of, and the functions of the interfaces and modes it does not have
//! (model exchange, scheduled execution, event mode, configuration mode, clocks, derivatives).

use super::*;

/// A getter or setter of a type no variable of a container has: every value reference refused
/// (it is no variable, or a variable of another type); none at all is fine.
fn no_such_type(me: &Container, call: Call, function: &str, asked: &str, vrs: &[u32]) -> Outcome {
    me.check(call, function)?;
    match vrs.first() {
        None => Ok(fmi2OK),
        Some(&vr) => {
            let Some(p) = me.ports.get(vr as usize) else {
                return Err(me.error(&format!(
                    "{function}: value reference {vr} is not a variable of {} (0 .. {})",
                    me.spec.model_identifier,
                    me.ports.len().saturating_sub(1)
                )));
            };
            Err(me.error(&format!(
                "{function}: '{}' (vr {vr}) is {}, not {asked} (a container's variables are its components' FMI 2.0 types)",
                me.name(vr),
                type_name(Version::Fmi3, p.ty)
            )))
        }
    }
}

/// The getter of a type no variable of a container has.
fn refuse_get<T>(
    instance: fmi3Instance,
    function: &str,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut T,
    n_values: usize,
    asked: &str,
) -> fmi3Status {
    with3(instance, function, |me| {
        let vrs = arrays(me, function, vr, nvr, values as *const T, n_values)?;
        no_such_type(me, Call::GetValues, function, asked, vrs)
    })
}

/// The setter of a type no variable of a container has.
fn refuse_set<T>(
    instance: fmi3Instance,
    function: &str,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const T,
    n_values: usize,
    asked: &str,
) -> fmi3Status {
    with3(instance, function, |me| {
        let vrs = arrays(me, function, vr, nvr, values, n_values)?;
        no_such_type(me, Call::SetDiscreteValues, function, asked, vrs)
    })
}

/// The getter and setter rows of each type a container has no variable of.
macro_rules! no_such_types {
    ($($get:ident, $set:ident, $ty:ty, $name:literal;)*) => {
        value_functions! {
            $(
                $get(values: *mut $ty) => refuse_get($name);
                $set(values: *const $ty) => refuse_set($name);
            )*
        }
    };
}

no_such_types! {
    fmi3GetFloat32, fmi3SetFloat32, fmi3Float32, "Float32";
    fmi3GetInt8, fmi3SetInt8, fmi3Int8, "Int8";
    fmi3GetUInt8, fmi3SetUInt8, fmi3UInt8, "UInt8";
    fmi3GetInt16, fmi3SetInt16, fmi3Int16, "Int16";
    fmi3GetUInt16, fmi3SetUInt16, fmi3UInt16, "UInt16";
    fmi3GetUInt32, fmi3SetUInt32, fmi3UInt32, "UInt32";
    fmi3GetUInt64, fmi3SetUInt64, fmi3UInt64, "UInt64";
}

exports! {
    fmi3GetBinary(
        instance: fmi3Instance,
        valueReferences: *const fmi3ValueReference,
        nValueReferences: usize,
        _valueSizes: *mut usize,
        values: *mut fmi3Binary,
        nValues: usize,
    ) -> fmi3Status =>
        with3(instance, F, |me| {
            let vrs = arrays(
                me,
                F,
                valueReferences,
                nValueReferences,
                values as *const fmi3Binary,
                nValues,
            )?;
            no_such_type(me, Call::GetValues, F, "Binary", vrs)
        });
    fmi3SetBinary(
        instance: fmi3Instance,
        valueReferences: *const fmi3ValueReference,
        nValueReferences: usize,
        _valueSizes: *const usize,
        values: *const fmi3Binary,
        nValues: usize,
    ) -> fmi3Status =>
        with3(instance, F, |me| {
            let vrs = arrays(me, F, valueReferences, nValueReferences, values, nValues)?;
            no_such_type(me, Call::SetDiscreteValues, F, "Binary", vrs)
        });
    fmi3DoStep(
        instance: fmi3Instance,
        currentCommunicationPoint: fmi3Float64,
        communicationStepSize: fmi3Float64,
        _noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
        eventHandlingNeeded: *mut fmi3Boolean,
        terminateSimulation: *mut fmi3Boolean,
        earlyReturn: *mut fmi3Boolean,
        lastSuccessfulTime: *mut fmi3Float64,
    ) -> fmi3Status =>
        with3(instance, F, |me| {
            if eventHandlingNeeded.is_null()
                || terminateSimulation.is_null()
                || earlyReturn.is_null()
                || lastSuccessfulTime.is_null()
            {
                me.check(Call::DoStep, F)?;
                return Err(me.error(&format!(
                    "{F}: eventHandlingNeeded, terminateSimulation, earlyReturn and lastSuccessfulTime must not be NULL"
                )));
            }
            let r = me.do_step(F, currentCommunicationPoint, communicationStepSize);
            put(eventHandlingNeeded, false);
            put(terminateSimulation, false);
            put(earlyReturn, false);
            put(lastSuccessfulTime, me.last_successful);
            r
        });
}

// What a container does not offer: each function says why.

fn not_offered(instance: fmi3Instance, function: &str, why: &str) -> fmi3Status {
    with3(instance, function, |me| Err(me.error(&format!("{function}: {why}"))))
}

/// Rows of functions a container refuses, each row one or more C names of one signature
/// (after `instance`) and the reason: `name, ...(param: Type, ...) => why;`. After `@vrs`, the
/// rows of functions whose first parameters are value references and their number (the clocks').
macro_rules! refusals {
    (@vrs $($($name:ident),+ ($($param:ident: $ty:ty),* $(,)?) => $why:expr;)*) => {
        refusals! {
            $(
                $($name),+ (_valueReferences: *const fmi3ValueReference, _nValueReferences: usize, $($param: $ty),*)
                    => $why;
            )*
        }
    };
    ($($($name:ident),+ ($($params:tt)*) => $why:expr;)*) => {
        $(refusals!(@row [$($name),+] ($($params)*) $why);)*
    };
    (@row [$name:ident $(, $more:ident)*] $params:tt $why:expr) => {
        refusals!(@one $name $params $why);
        refusals!(@row [$($more),*] $params $why);
    };
    (@row [] $params:tt $why:expr) => {};
    (@one $name:ident ($($param:ident: $ty:ty),* $(,)?) $why:expr) => {
        exports! {
            $name(instance: fmi3Instance, $($param: $ty),*) -> fmi3Status => not_offered(instance, F, $why);
        }
    };
}

const NO_EVENT_MODE: &str = "a container has no event mode (hasEventMode = false)";
const NO_MODEL_EXCHANGE: &str = "a container is a co-simulation FMU only (no <ModelExchange> element)";
const NO_CLOCKS: &str = "a container has no clocks";
const NO_DERIVATIVES: &str = "a container gives no directional or adjoint derivatives (providesDirectionalDerivatives = false, providesAdjointDerivatives = false)";

refusals! {
    fmi3EnterEventMode() => NO_EVENT_MODE;
    fmi3EnterStepMode() => "a container leaves Initialization Mode into Step Mode itself (it has no event mode)";
    fmi3EvaluateDiscreteStates() => NO_EVENT_MODE;
    fmi3UpdateDiscreteStates(
        _discreteStatesNeedUpdate: *mut fmi3Boolean,
        _terminateSimulation: *mut fmi3Boolean,
        _nominalsOfContinuousStatesChanged: *mut fmi3Boolean,
        _valuesOfContinuousStatesChanged: *mut fmi3Boolean,
        _nextEventTimeDefined: *mut fmi3Boolean,
        _nextEventTime: *mut fmi3Float64,
    ) => NO_EVENT_MODE;
    fmi3EnterConfigurationMode, fmi3ExitConfigurationMode() =>
        "a container has no structural parameters, so there is no configuration mode";
    fmi3GetDirectionalDerivative, fmi3GetAdjointDerivative(
        _unknowns: *const fmi3ValueReference,
        _nUnknowns: usize,
        _knowns: *const fmi3ValueReference,
        _nKnowns: usize,
        _seed: *const fmi3Float64,
        _nSeed: usize,
        _sensitivity: *mut fmi3Float64,
        _nSensitivity: usize,
    ) => NO_DERIVATIVES;
    fmi3GetOutputDerivatives(
        _valueReferences: *const fmi3ValueReference,
        _nValueReferences: usize,
        _orders: *const fmi3Int32,
        _values: *mut fmi3Float64,
        _nValues: usize,
    ) => "a container gives no output derivatives (maxOutputDerivativeOrder = 0)";
    fmi3EnterContinuousTimeMode() => NO_MODEL_EXCHANGE;
    fmi3CompletedIntegratorStep(
        _noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
        _enterEventMode: *mut fmi3Boolean,
        _terminateSimulation: *mut fmi3Boolean,
    ) => NO_MODEL_EXCHANGE;
    fmi3SetTime(_time: fmi3Float64) => NO_MODEL_EXCHANGE;
    fmi3SetContinuousStates(_continuousStates: *const fmi3Float64, _nContinuousStates: usize) => NO_MODEL_EXCHANGE;
    fmi3GetContinuousStateDerivatives,
    fmi3GetEventIndicators,
    fmi3GetContinuousStates,
    fmi3GetNominalsOfContinuousStates(_values: *mut fmi3Float64, _n: usize) => NO_MODEL_EXCHANGE;
    fmi3GetNumberOfEventIndicators, fmi3GetNumberOfContinuousStates(_n: *mut usize) => NO_MODEL_EXCHANGE;
    fmi3ActivateModelPartition(
        _clockReference: fmi3ValueReference,
        _activationTime: fmi3Float64,
    ) => "a container is a co-simulation FMU only (no <ScheduledExecution> element)";
}

refusals! {
    @vrs
    fmi3SetClock(_values: *const fmi3Clock) => NO_CLOCKS;
    fmi3GetClock(_values: *mut fmi3Clock) => NO_CLOCKS;
    fmi3GetIntervalDecimal(_intervals: *mut fmi3Float64, _qualifiers: *mut fmi3IntervalQualifier) => NO_CLOCKS;
    fmi3GetIntervalFraction(
        _counters: *mut fmi3UInt64,
        _resolutions: *mut fmi3UInt64,
        _qualifiers: *mut fmi3IntervalQualifier,
    ) => NO_CLOCKS;
    fmi3GetShiftDecimal(_shifts: *mut fmi3Float64) => NO_CLOCKS;
    fmi3GetShiftFraction(_counters: *mut fmi3UInt64, _resolutions: *mut fmi3UInt64) => NO_CLOCKS;
    fmi3SetIntervalDecimal(_intervals: *const fmi3Float64) => NO_CLOCKS;
    fmi3SetIntervalFraction, fmi3SetShiftFraction(_counters: *const fmi3UInt64, _resolutions: *const fmi3UInt64) =>
        NO_CLOCKS;
    fmi3SetShiftDecimal(_shifts: *const fmi3Float64) => NO_CLOCKS;
}
