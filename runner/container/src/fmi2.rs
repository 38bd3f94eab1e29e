//! The FMI 2.0 co-simulation functions of a container: each checks its C arguments and calls
//! the version-neutral [`crate::Container`].

use crate::export::exports;
use crate::*;
use rustfmu::fmi2::abi::*;

fn with2(c: fmi2Component, function: &str, f: impl FnOnce(&mut Container) -> Outcome) -> fmi2Status {
    with(c, function, f)
}

exports! {
    fmi2GetTypesPlatform() -> *const c_char =>
        TYPES_PLATFORM.as_ptr();
    fmi2GetVersion() -> *const c_char =>
        VERSION.as_ptr();
    fmi2Instantiate(
        instanceName: fmi2String,
        fmuType: fmi2Type,
        fmuGUID: fmi2String,
        fmuResourceLocation: fmi2String,
        functions: *const fmi2CallbackFunctions,
        _visible: fmi2Boolean,
        loggingOn: fmi2Boolean,
    ) -> fmi2Component =>
        instantiate2(instanceName, fmuType, fmuGUID, fmuResourceLocation, functions, loggingOn);
    fmi2FreeInstance(c: fmi2Component) =>
        free_instance(c);
    fmi2SetDebugLogging(
        c: fmi2Component,
        loggingOn: fmi2Boolean,
        nCategories: usize,
        categories: *const fmi2String,
    ) -> fmi2Status =>
        with2(c, F, |me| {
            if nCategories > 0 && categories.is_null() {
                me.check(Call::SetDebugLogging, F)?;
                return Err(me.error(&format!("{F}: {nCategories} categories in a NULL array")));
            }
            me.set_debug_logging(F, loggingOn != fmi2False, slice(categories, nCategories))
        });
    fmi2SetupExperiment(
        c: fmi2Component,
        toleranceDefined: fmi2Boolean,
        tolerance: fmi2Real,
        startTime: fmi2Real,
        stopTimeDefined: fmi2Boolean,
        stopTime: fmi2Real,
    ) -> fmi2Status =>
        with2(c, F, |me| {
            me.check(Call::SetupExperiment, F)?;
            let tol = (toleranceDefined != fmi2False).then_some(tolerance);
            let stop = (stopTimeDefined != fmi2False).then_some(stopTime);
            me.setup(F, tol, startTime, stop)?;
            Ok(fmi2OK)
        });
    fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status =>
        with2(c, F, |me| {
            me.check(Call::EnterInitializationMode, F)?;
            me.enter_initialization_mode(F)
        });
    fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status =>
        with2(c, F, |me| {
            me.exit_initialization_mode(F)
        });
    fmi2Terminate(c: fmi2Component) -> fmi2Status =>
        with2(c, F, |me| me.terminate(F));
    fmi2Reset(c: fmi2Component) -> fmi2Status =>
        with2(c, F, |me| me.reset(F));
}

/// fmi2Instantiate: a co-simulation instance only, with the importer's logger.
fn instantiate2(
    instanceName: fmi2String,
    fmuType: fmi2Type,
    fmuGUID: fmi2String,
    fmuResourceLocation: fmi2String,
    functions: *const fmi2CallbackFunctions,
    loggingOn: fmi2Boolean,
) -> fmi2Component {
    const F: &str = "fmi2Instantiate";
    let r = catch_unwind(AssertUnwindSafe(|| {
        let functions = read(functions)?;
        let name = text(instanceName);
        let sink = Box::new(Sink {
            logger: Logger::V2 {
                logger: functions.logger,
                environment: functions.componentEnvironment,
                name: CString::new(name.clone().unwrap_or_default()).unwrap_or_default(),
            },
            logging_on: Cell::new(loggingOn != fmi2False),
        });
        if fmuType != fmi2CoSimulation {
            sink.log(
                fmi2Error,
                "logStatusError",
                &format!("fmi2Instantiate: fmuType = {fmuType}: a container is a co-simulation FMU only (fmi2CoSimulation = 1)"),
            );
            return None;
        }
        instantiate(
            sink,
            Request {
                version: Version::Fmi2,
                function: F,
                name,
                token: text(fmuGUID),
                resources: resources_of_uri(text(fmuResourceLocation)),
                logging_on: loggingOn != fmi2False,
            },
        )
    }));
    match r {
        Ok(Some(c)) => Box::into_raw(c) as fmi2Component,
        _ => std::ptr::null_mut(),
    }
}

/// The value references and values of a getter or setter, NULL arrays refused.
fn arrays<'a, T>(
    me: &Container,
    function: &str,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const T,
) -> Result<(&'a [u32], usize), Status> {
    if nvr > 0 && (vr.is_null() || value.is_null()) {
        return Err(me.error(&format!("{function}: {nvr} values with a NULL array")));
    }
    Ok((slice(vr, nvr), nvr))
}

fn get2<T: Scalar>(
    c: fmi2Component,
    function: &'static str,
    ty: Type,
    vr: *const fmi2ValueReference,
    nvr: usize,
    out: *mut T,
    get: impl Fn(&mut InstanceCS, &[u32], &mut [T]) -> Result<(), Fmi2Error>,
    finite: impl Fn(&T) -> bool,
) -> fmi2Status {
    with2(c, function, |me| {
        me.check(Call::GetValues, function)?;
        let (vrs, n) = arrays(me, function, vr, nvr, out as *const T)?;
        me.get_values(function, ty, ty.name(), vrs, slice_mut(out, n), get, finite, |_| None)
    })
}

exports! {
    fmi2GetReal(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *mut fmi2Real,
    ) -> fmi2Status =>
        get2(
            c,
            F,
            Type::Real,
            vr,
            nvr,
            value,
            |i, v, out| i.get_real(v, out),
            |x| x.is_finite(),
        );
    fmi2GetInteger(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *mut fmi2Integer,
    ) -> fmi2Status =>
        get2(
            c,
            F,
            Type::Integer,
            vr,
            nvr,
            value,
            |i, v, out| i.get_integer(v, out),
            |_| true,
        );
    fmi2GetBoolean(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *mut fmi2Boolean,
    ) -> fmi2Status =>
        get2(
            c,
            F,
            Type::Boolean,
            vr,
            nvr,
            value,
            |i, v, out| i.get_boolean(v, out),
            |_| true,
        );
    fmi2GetString(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *mut fmi2String,
    ) -> fmi2Status =>
        with2(c, F, |me| {
            me.check(Call::GetValues, F)?;
            let (vrs, n) = arrays(me, F, vr, nvr, value as *const fmi2String)?;
            me.get_strings(F, vrs)?;
            let out = slice_mut(value, n);
            for (k, s) in me.strings.iter().enumerate() {
                out[k] = s.as_ptr();
            }
            Ok(fmi2OK)
        });
}

fn set2<T: Scalar>(
    c: fmi2Component,
    function: &'static str,
    ty: Type,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const T,
    number: impl Fn(&T) -> Option<f64>,
    set: impl Fn(&mut InstanceCS, u32, T) -> Result<(), Fmi2Error>,
) -> fmi2Status {
    with2(c, function, |me| {
        let (vrs, n) = arrays(me, function, vr, nvr, value)?;
        me.set_values(function, ty, ty.name(), vrs, slice(value, n), number, set)
    })
}

exports! {
    fmi2SetReal(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *const fmi2Real,
    ) -> fmi2Status =>
        set2(
            c,
            F,
            Type::Real,
            vr,
            nvr,
            value,
            |x| Some(*x),
            |i, v, x| i.set_real(&[v], &[x]).map(|_| ()),
        );
    fmi2SetInteger(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *const fmi2Integer,
    ) -> fmi2Status =>
        set2(
            c,
            F,
            Type::Integer,
            vr,
            nvr,
            value,
            |x| Some(f64::from(*x)),
            |i, v, x| i.set_integer(&[v], &[x]).map(|_| ()),
        );
    fmi2SetBoolean(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *const fmi2Boolean,
    ) -> fmi2Status =>
        set2(
            c,
            F,
            Type::Boolean,
            vr,
            nvr,
            value,
            |_| None,
            |i, v, x| i.set_boolean(&[v], &[x]).map(|_| ()),
        );
    fmi2SetString(
        c: fmi2Component,
        vr: *const fmi2ValueReference,
        nvr: usize,
        value: *const fmi2String,
    ) -> fmi2Status =>
        with2(c, F, |me| {
            let (vrs, n) = arrays(me, F, vr, nvr, value)?;
            me.set_strings(F, vrs, slice(value, n))
        });
    fmi2DoStep(
        c: fmi2Component,
        currentCommunicationPoint: fmi2Real,
        communicationStepSize: fmi2Real,
        _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
    ) -> fmi2Status =>
        with2(c, F, |me| {
            me.do_step(F, currentCommunicationPoint, communicationStepSize)
        });
    fmi2CancelStep(c: fmi2Component) -> fmi2Status =>
        with2(c, F, |me| {
            me.check(Call::CancelStep, F)?;
            Ok(fmi2OK)
        });
}

/// fmi2Get*Status (`function`) into `value`: the status kind this type answers (`known`: the
/// kind and its value), any other unavailable.
fn get_status<T>(
    me: &Container,
    function: &str,
    s: fmi2StatusKind,
    value: *mut T,
    known: Option<(fmi2StatusKind, T)>,
) -> Outcome {
    me.check(Call::GetStatus, function)?;
    if value.is_null() {
        return Err(me.error(&format!("{function}: value is NULL")));
    }
    match known {
        Some((kind, answer)) if s == kind => {
            put(value, answer);
            Ok(fmi2OK)
        }
        _ => status_unavailable(me, function, s),
    }
}

/// The standard's answer for a status a container does not have: fmi2Discard, with the reason.
fn status_unavailable(me: &Container, function: &str, kind: fmi2StatusKind) -> Outcome {
    let what = match kind {
        fmi2DoStepStatus | fmi2PendingStatus => "there is no asynchronous step (fmi2DoStep never returns fmi2Pending)",
        fmi2LastSuccessfulTime => "fmi2LastSuccessfulTime is a Real status (fmi2GetRealStatus)",
        fmi2Terminated => "fmi2Terminated is a Boolean status (fmi2GetBooleanStatus)",
        _ => "unknown fmi2StatusKind",
    };
    me.sink.log(
        fmi2Discard,
        "logStatusDiscard",
        &format!("{function}(kind = {kind}): not available: {what}"),
    );
    Err(fmi2Discard)
}

exports! {
    fmi2GetStatus(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2Status) -> fmi2Status =>
        with2(c, F, |me| get_status(me, F, s, value, None));
    fmi2GetRealStatus(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2Real) -> fmi2Status =>
        with2(c, F, |me| get_status(me, F, s, value, Some((fmi2LastSuccessfulTime, me.last_successful))));
    fmi2GetIntegerStatus(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2Integer) -> fmi2Status =>
        with2(c, F, |me| get_status(me, F, s, value, None));
    fmi2GetBooleanStatus(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2Boolean) -> fmi2Status =>
        with2(c, F, |me| get_status(me, F, s, value, Some((fmi2Terminated, fmi2False))));
    fmi2GetStringStatus(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2String) -> fmi2Status =>
        with2(c, F, |me| get_status(me, F, s, value, None));
    fmi2SetRealInputDerivatives(
        c: fmi2Component,
        _vr: *const fmi2ValueReference,
        _nvr: usize,
        _order: *const fmi2Integer,
        _value: *const fmi2Real,
    ) -> fmi2Status =>
        with2(c, F, |me| {
            Err(me.error(
                "fmi2SetRealInputDerivatives: a container does not interpolate inputs (canInterpolateInputs = false)",
            ))
        });
    fmi2GetRealOutputDerivatives(
        c: fmi2Component,
        _vr: *const fmi2ValueReference,
        _nvr: usize,
        _order: *const fmi2Integer,
        _value: *mut fmi2Real,
    ) -> fmi2Status =>
        with2(c, F, |me| {
            Err(me.error(
                "fmi2GetRealOutputDerivatives: a container gives no output derivatives (maxOutputDerivativeOrder = 0)",
            ))
        });
    fmi2GetDirectionalDerivative(
        c: fmi2Component,
        _u: *const fmi2ValueReference,
        _nu: usize,
        _z: *const fmi2ValueReference,
        _nz: usize,
        _du: *const fmi2Real,
        _dz: *mut fmi2Real,
    ) -> fmi2Status =>
        with2(c, F, |me| {
            Err(me.error("fmi2GetDirectionalDerivative: a container gives no directional derivatives (providesDirectionalDerivative = false)"))
        });
    fmi2GetFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status =>
        with2(c, F, |me| me.get_fmu_state(F, state));
    fmi2SetFMUstate(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status =>
        with2(c, F, |me| me.set_fmu_state(F, state));
    fmi2FreeFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status =>
        with2(c, F, |me| me.free_fmu_state(F, state));
    fmi2SerializedFMUstateSize(
        c: fmi2Component,
        state: fmi2FMUstate,
        size: *mut usize,
    ) -> fmi2Status =>
        with2(c, F, |me| {
            me.serialized_size(F, state, size)
        });
    fmi2SerializeFMUstate(
        c: fmi2Component,
        state: fmi2FMUstate,
        bytes: *mut fmi2Byte,
        size: usize,
    ) -> fmi2Status =>
        with2(c, F, |me| {
            me.serialize_state(F, state, bytes as *mut u8, size)
        });
    fmi2DeSerializeFMUstate(
        c: fmi2Component,
        bytes: *const fmi2Byte,
        size: usize,
        state: *mut fmi2FMUstate,
    ) -> fmi2Status =>
        with2(c, F, |me| {
            me.deserialize_state(F, bytes as *const u8, size, state)
        });
}
