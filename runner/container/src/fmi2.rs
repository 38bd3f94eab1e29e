//! The FMI 2.0 co-simulation functions of a container: each checks its C arguments and calls
//! the version-neutral [`crate::Container`].

use crate::*;
use rustfmu::fmi2::abi::*;

fn with2(c: fmi2Component, function: &str, f: impl FnOnce(&mut Container) -> Outcome) -> fmi2Status {
    with(c, function, f)
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    TYPES_PLATFORM.as_ptr()
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    VERSION.as_ptr()
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instanceName: fmi2String,
    fmuType: fmi2Type,
    fmuGUID: fmi2String,
    fmuResourceLocation: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    loggingOn: fmi2Boolean,
) -> fmi2Component {
    let r = catch_unwind(AssertUnwindSafe(|| {
        if functions.is_null() {
            return None;
        }
        let functions = unsafe { *functions };
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
                function: "fmi2Instantiate",
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

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    free_instance(c)
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    loggingOn: fmi2Boolean,
    nCategories: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    const F: &str = "fmi2SetDebugLogging";
    with2(c, F, |me| {
        if nCategories > 0 && categories.is_null() {
            me.check(Call::SetDebugLogging, F)?;
            return Err(me.error(&format!("{F}: {nCategories} categories in a NULL array")));
        }
        me.set_debug_logging(F, loggingOn != fmi2False, slice(categories, nCategories))
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    toleranceDefined: fmi2Boolean,
    tolerance: fmi2Real,
    startTime: fmi2Real,
    stopTimeDefined: fmi2Boolean,
    stopTime: fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2SetupExperiment";
    with2(c, F, |me| {
        me.check(Call::SetupExperiment, F)?;
        let tol = (toleranceDefined != fmi2False).then_some(tolerance);
        let stop = (stopTimeDefined != fmi2False).then_some(stopTime);
        me.setup(F, tol, startTime, stop)?;
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    const F: &str = "fmi2EnterInitializationMode";
    with2(c, F, |me| {
        me.check(Call::EnterInitializationMode, F)?;
        me.enter_initialization_mode(F)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    with2(c, "fmi2ExitInitializationMode", |me| {
        me.exit_initialization_mode("fmi2ExitInitializationMode")
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    with2(c, "fmi2Terminate", |me| me.terminate("fmi2Terminate"))
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    with2(c, "fmi2Reset", |me| me.reset("fmi2Reset"))
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

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    get2(
        c,
        "fmi2GetReal",
        Type::Real,
        vr,
        nvr,
        value,
        |i, v, out| i.get_real(v, out),
        |x| x.is_finite(),
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    get2(
        c,
        "fmi2GetInteger",
        Type::Integer,
        vr,
        nvr,
        value,
        |i, v, out| i.get_integer(v, out),
        |_| true,
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    get2(
        c,
        "fmi2GetBoolean",
        Type::Boolean,
        vr,
        nvr,
        value,
        |i, v, out| i.get_boolean(v, out),
        |_| true,
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    const F: &str = "fmi2GetString";
    with2(c, F, |me| {
        me.check(Call::GetValues, F)?;
        let (vrs, n) = arrays(me, F, vr, nvr, value as *const fmi2String)?;
        me.get_strings(F, vrs)?;
        let out = slice_mut(value, n);
        for (k, s) in me.strings.iter().enumerate() {
            out[k] = s.as_ptr();
        }
        Ok(fmi2OK)
    })
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

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    set2(
        c,
        "fmi2SetReal",
        Type::Real,
        vr,
        nvr,
        value,
        |x| Some(*x),
        |i, v, x| i.set_real(&[v], &[x]).map(|_| ()),
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    set2(
        c,
        "fmi2SetInteger",
        Type::Integer,
        vr,
        nvr,
        value,
        |x| Some(f64::from(*x)),
        |i, v, x| i.set_integer(&[v], &[x]).map(|_| ()),
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    set2(
        c,
        "fmi2SetBoolean",
        Type::Boolean,
        vr,
        nvr,
        value,
        |_| None,
        |i, v, x| i.set_boolean(&[v], &[x]).map(|_| ()),
    )
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    const F: &str = "fmi2SetString";
    with2(c, F, |me| {
        let (vrs, n) = arrays(me, F, vr, nvr, value)?;
        me.set_strings(F, vrs, slice(value, n))
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DoStep(
    c: fmi2Component,
    currentCommunicationPoint: fmi2Real,
    communicationStepSize: fmi2Real,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
) -> fmi2Status {
    with2(c, "fmi2DoStep", |me| {
        me.do_step("fmi2DoStep", currentCommunicationPoint, communicationStepSize)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    with2(c, "fmi2CancelStep", |me| {
        me.check(Call::CancelStep, "fmi2CancelStep")?;
        Ok(fmi2OK)
    })
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

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStatus(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2Status) -> fmi2Status {
    with2(c, "fmi2GetStatus", |me| {
        me.check(Call::GetStatus, "fmi2GetStatus")?;
        if value.is_null() {
            return Err(me.error("fmi2GetStatus: value is NULL"));
        }
        status_unavailable(me, "fmi2GetStatus", s)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealStatus(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2Real) -> fmi2Status {
    with2(c, "fmi2GetRealStatus", |me| {
        me.check(Call::GetStatus, "fmi2GetRealStatus")?;
        if value.is_null() {
            return Err(me.error("fmi2GetRealStatus: value is NULL"));
        }
        if s != fmi2LastSuccessfulTime {
            return status_unavailable(me, "fmi2GetRealStatus", s);
        }
        unsafe { *value = me.last_successful };
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Integer,
) -> fmi2Status {
    with2(c, "fmi2GetIntegerStatus", |me| {
        me.check(Call::GetStatus, "fmi2GetIntegerStatus")?;
        if value.is_null() {
            return Err(me.error("fmi2GetIntegerStatus: value is NULL"));
        }
        status_unavailable(me, "fmi2GetIntegerStatus", s)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    with2(c, "fmi2GetBooleanStatus", |me| {
        me.check(Call::GetStatus, "fmi2GetBooleanStatus")?;
        if value.is_null() {
            return Err(me.error("fmi2GetBooleanStatus: value is NULL"));
        }
        if s != fmi2Terminated {
            return status_unavailable(me, "fmi2GetBooleanStatus", s);
        }
        unsafe { *value = fmi2False };
        Ok(fmi2OK)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2String,
) -> fmi2Status {
    with2(c, "fmi2GetStringStatus", |me| {
        me.check(Call::GetStatus, "fmi2GetStringStatus")?;
        if value.is_null() {
            return Err(me.error("fmi2GetStringStatus: value is NULL"));
        }
        status_unavailable(me, "fmi2GetStringStatus", s)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *const fmi2Real,
) -> fmi2Status {
    with2(c, "fmi2SetRealInputDerivatives", |me| {
        Err(me.error(
            "fmi2SetRealInputDerivatives: a container does not interpolate inputs (canInterpolateInputs = false)",
        ))
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *mut fmi2Real,
) -> fmi2Status {
    with2(c, "fmi2GetRealOutputDerivatives", |me| {
        Err(me.error(
            "fmi2GetRealOutputDerivatives: a container gives no output derivatives (maxOutputDerivativeOrder = 0)",
        ))
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    _u: *const fmi2ValueReference,
    _nu: usize,
    _z: *const fmi2ValueReference,
    _nz: usize,
    _du: *const fmi2Real,
    _dz: *mut fmi2Real,
) -> fmi2Status {
    with2(c, "fmi2GetDirectionalDerivative", |me| {
        Err(me.error("fmi2GetDirectionalDerivative: a container gives no directional derivatives (providesDirectionalDerivative = false)"))
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    with2(c, "fmi2GetFMUstate", |me| me.get_fmu_state("fmi2GetFMUstate", state))
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status {
    with2(c, "fmi2SetFMUstate", |me| me.set_fmu_state("fmi2SetFMUstate", state))
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    with2(c, "fmi2FreeFMUstate", |me| me.free_fmu_state("fmi2FreeFMUstate", state))
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    state: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    with2(c, "fmi2SerializedFMUstateSize", |me| {
        me.serialized_size("fmi2SerializedFMUstateSize", state, size)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    state: fmi2FMUstate,
    bytes: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    with2(c, "fmi2SerializeFMUstate", |me| {
        me.serialize_state("fmi2SerializeFMUstate", state, bytes as *mut u8, size)
    })
}

#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    bytes: *const fmi2Byte,
    size: usize,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    with2(c, "fmi2DeSerializeFMUstate", |me| {
        me.deserialize_state("fmi2DeSerializeFMUstate", bytes as *const u8, size, state)
    })
}
