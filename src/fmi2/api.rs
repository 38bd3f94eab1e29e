//! The C boundary: every `fmi2*` function, generic over the model. The export macro
//! ([`export_fmi2!`](crate::export_fmi2)) forwards the `#[no_mangle]`
//! symbols of an FMU crate here. This is the one module with `unsafe`: pointers from the importer
//! are checked for NULL and turned into slices and references, and every call runs under
//! `catch_unwind`, so no panic crosses into the host.
#![allow(clippy::missing_safety_doc, clippy::too_many_arguments)]

use super::abi::*;
use super::instance::{Call, Instance, State};
use super::logging::{Category, Logger};
use super::snapshots;
use crate::model::CoSimulation;
use crate::value::FmiType;
use std::cell::UnsafeCell;
use std::ffi::CStr;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::ptr;
use std::sync::atomic::{AtomicBool, Ordering};

pub(crate) fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        format!("panic: {s}")
    } else if let Some(s) = payload.downcast_ref::<String>() {
        format!("panic: {s}")
    } else {
        "panic".into()
    }
}

/// What fmi2Instantiate hands out as the `fmi2Component`: the instance, and what a call needs
/// before it may touch it.
pub struct Component<M: CoSimulation> {
    /// Set while a call is inside the instance. A call that arrives meanwhile (made by the
    /// importer's logger during that call, or from another thread) is refused: it would work on
    /// an instance in the middle of a change (a nested fmi2DoStep advanced the model twice
    /// while the clock said once).
    pub(crate) busy: AtomicBool,
    /// Logs those refusals. A copy taken at instantiation: error messages pass the logger
    /// whatever its switches, so later fmi2SetDebugLogging calls do not matter to it.
    pub(crate) refusals: Logger,
    pub(crate) instance: UnsafeCell<Instance<M>>,
}

/// Runs `f` on the instance behind `c`, after the state check for `call`.
/// A NULL instance cannot be logged to: the answer is fmi2Error.
pub(crate) unsafe fn with_instance<M: CoSimulation>(
    c: fmi2Component,
    call: Call,
    function: &str,
    f: impl FnOnce(&mut Instance<M>) -> fmi2Status,
) -> fmi2Status {
    if c.is_null() {
        return fmi2Error;
    }
    // SAFETY: a non-NULL component is one this library returned from fmi2Instantiate and that
    // was not freed (the standard forbids any other). Only shared: a call already inside holds
    // the instance, which is in the UnsafeCell.
    let component = unsafe { &*(c as *const Component<M>) };
    if component.busy.swap(true, Ordering::Acquire) {
        component.refusals.log(
            fmi2Error,
            Category::StatusError,
            &format!(
                "{function}: called while a call into this instance is still running (from a \
                 callback of that call, or from another thread); refused, nothing changed"
            ),
        );
        return fmi2Error;
    }
    let instance = component.instance.get();
    let result = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: this call set `busy`, so no other reference to the instance exists until it
        // clears it below.
        let inst = unsafe { &mut *instance };
        let status = match inst.check_state(call, function) {
            Ok(()) => f(inst),
            Err(status) => status,
        };
        // FMI 3.0, 2.3.1: "If any function called in super state FMU State Setable returns
        // fmi3Error, the FMU enters state Terminated" (from there fmi3Reset or fmi3SetFMUState
        // lead back). FMI 2.0 has no such rule: its instances stay where they were.
        if inst.fmi3 && status == fmi2Error && inst.sim.state != State::Fatal {
            inst.sim.state = State::Terminated;
        }
        status
    }));
    let status = match result {
        Ok(status) => status,
        Err(payload) => {
            let what = panic_text(&*payload);
            // SAFETY: as above; the closure's borrow ended with the unwind.
            let inst = unsafe { &mut *instance };
            let _ = catch_unwind(AssertUnwindSafe(|| inst.fatal(function, &what)));
            fmi2Fatal
        }
    };
    component.busy.store(false, Ordering::Release);
    status
}

/// An importer's array argument: NULL is fine only when it is empty.
pub(crate) unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        Some(&[])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: the standard makes the importer pass n valid elements.
        Some(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

pub(crate) unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        Some(&mut [])
    } else if p.is_null() {
        None
    } else {
        // SAFETY: as for `slice`.
        Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
}

pub(crate) unsafe fn text<'a>(s: fmi2String) -> Option<std::borrow::Cow<'a, str>> {
    if s.is_null() {
        None
    } else {
        // SAFETY: the importer passes NUL-terminated strings.
        Some(unsafe { CStr::from_ptr(s) }.to_string_lossy())
    }
}

pub fn get_types_platform() -> fmi2String {
    TYPES_PLATFORM.as_ptr()
}

pub fn get_version() -> fmi2String {
    VERSION.as_ptr()
}

pub unsafe fn instantiate<M: CoSimulation>(
    own_guid: &'static str,
    description: &'static [u8],
    instance_name: fmi2String,
    fmu_type: fmi2Type,
    guid: fmi2String,
    resource_location: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    logging_on: fmi2Boolean,
) -> fmi2Component {
    let made = catch_unwind(AssertUnwindSafe(|| {
        if functions.is_null() {
            return ptr::null_mut();
        }
        // SAFETY: non-NULL, and the standard makes it point to the importer's callbacks.
        let callbacks = unsafe { *functions };
        // SAFETY: NUL-terminated strings from the importer, or NULL.
        let (name, guid, resources) = unsafe { (text(instance_name), text(guid), text(resource_location)) };
        // The embedded description stays in the binary for `cargo fmu` to read: this use keeps
        // the linker from discarding it.
        std::hint::black_box(description.len());
        let Some(logger) = Logger::new(
            &callbacks,
            name.as_deref().unwrap_or(""),
            logging_on != fmi2False,
            M::DESCRIPTION.log_categories,
        ) else {
            return ptr::null_mut();
        };
        let refuse = |why: String| {
            logger.log(fmi2Error, Category::StatusError, &format!("fmi2Instantiate: {why}"));
            ptr::null_mut()
        };
        match name.as_deref() {
            None => return refuse("instanceName is NULL; an instance needs a name".into()),
            Some("") => return refuse("instanceName is empty; an instance needs a name".into()),
            // FMI 2.0, 2.1.5: "a non-empty string ... at least one non-white-space character".
            Some(n) if n.trim().is_empty() => {
                return refuse(format!(
                    "instanceName {n:?} is only white space; an instance needs a name with at least one \
                     non-white-space character (FMI 2.0, 2.1.5)"
                ));
            }
            Some(_) => {}
        }
        if fmu_type != fmi2CoSimulation && fmu_type != fmi2ModelExchange {
            return refuse(format!(
                "fmuType = {fmu_type} is neither fmi2ModelExchange (0) nor fmi2CoSimulation (1)"
            ));
        }
        match guid.as_deref() {
            None => return refuse(format!("GUID is NULL; expected {own_guid}")),
            Some(g) if g != own_guid => {
                return refuse(format!(
                    "GUID '{g}' does not match this binary's {own_guid}: modelDescription.xml and \
                     binaries/ come from different builds of {}",
                    M::DESCRIPTION.model_identifier
                ));
            }
            Some(_) => {}
        }
        let inst = Instance::<M>::new(logger, own_guid, fmu_type == fmi2ModelExchange);
        let mut inst = inst;
        inst.resources = resources
            .as_deref()
            .and_then(super::resources::resource_dir)
            .filter(|d| d.is_dir());
        inst.event(|| match resources.as_deref().map(super::resources::resource_dir) {
            Some(Some(dir)) if dir.is_dir() => format!("resourceLocation resolves to {}", dir.display()),
            Some(Some(dir)) => format!(
                "resourceLocation resolves to {}, which does not exist (the model sees no resources)",
                dir.display()
            ),
            Some(None) => format!("resourceLocation {resources:?} is not a file URI (the model sees no resources)"),
            None => "resourceLocation is NULL (the model sees no resources)".into(),
        });
        Box::into_raw(Box::new(Component {
            busy: AtomicBool::new(false),
            refusals: inst.logger.clone(),
            instance: UnsafeCell::new(inst),
        })) as fmi2Component
    }));
    made.unwrap_or(ptr::null_mut())
}

pub unsafe fn free_instance<M: CoSimulation>(c: fmi2Component) {
    if c.is_null() {
        return;
    }
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: returned by fmi2Instantiate as a Box<Component<M>> and not freed (standard).
        let component = unsafe { &*(c as *const Component<M>) };
        if component.busy.swap(true, Ordering::Acquire) {
            // Freeing it now would pull the instance from under the call that is running.
            component.refusals.log(
                fmi2Error,
                Category::StatusError,
                "fmi2FreeInstance: called while a call into this instance is still running; \
                 the instance is not freed",
            );
            return;
        }
        // SAFETY: as above, and no call is inside: freed once.
        drop(unsafe { Box::from_raw(c as *mut Component<M>) });
    }));
}

pub unsafe fn set_debug_logging<M: CoSimulation>(
    c: fmi2Component,
    logging_on: fmi2Boolean,
    n: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::SetDebugLogging, "fmi2SetDebugLogging", |inst| {
            let Some(cats) = slice(categories, n) else {
                return inst.error(&format!(
                    "fmi2SetDebugLogging: categories is NULL with nCategories = {n}"
                ));
            };
            let mut names = Vec::with_capacity(n);
            for (i, s) in cats.iter().enumerate() {
                match text(*s) {
                    Some(t) => names.push(t.into_owned()),
                    None => return inst.error(&format!("fmi2SetDebugLogging: categories[{i}] is NULL")),
                }
            }
            inst.set_debug_logging(logging_on != fmi2False, &names)
        })
    }
}

pub unsafe fn setup_experiment<M: CoSimulation>(
    c: fmi2Component,
    tolerance_defined: fmi2Boolean,
    tolerance: fmi2Real,
    start_time: fmi2Real,
    stop_time_defined: fmi2Boolean,
    stop_time: fmi2Real,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::SetupExperiment, "fmi2SetupExperiment", |inst| {
            inst.trace(|| {
                format!(
                    "fmi2SetupExperiment(toleranceDefined = {tolerance_defined}, tolerance = {tolerance}, \
                     startTime = {start_time}, stopTimeDefined = {stop_time_defined}, stopTime = {stop_time})"
                )
            });
            inst.setup_experiment(
                (tolerance_defined != fmi2False).then_some(tolerance),
                start_time,
                (stop_time_defined != fmi2False).then_some(stop_time),
            )
        })
    }
}

macro_rules! simple_call {
    ($fn_name:ident, $call:ident, $c_name:literal, $method:ident) => {
        pub unsafe fn $fn_name<M: CoSimulation>(c: fmi2Component) -> fmi2Status {
            unsafe {
                with_instance::<M>(c, Call::$call, $c_name, |inst| {
                    inst.trace(|| concat!($c_name, "()").to_string());
                    inst.$method()
                })
            }
        }
    };
}

simple_call!(
    enter_initialization_mode,
    EnterInitializationMode,
    "fmi2EnterInitializationMode",
    enter_initialization_mode
);
simple_call!(
    exit_initialization_mode,
    ExitInitializationMode,
    "fmi2ExitInitializationMode",
    exit_initialization_mode
);
simple_call!(terminate, Terminate, "fmi2Terminate", terminate);
simple_call!(reset, Reset, "fmi2Reset", reset);

pub unsafe fn get<M: CoSimulation, T: FmiType + Copy>(
    c: fmi2Component,
    function: &'static str,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut T,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::GetValues, function, |inst| {
            match (slice(vr, nvr), slice_mut(value, nvr)) {
                (Some(vrs), Some(out)) => inst.get_values(function, vrs, out),
                _ => inst.error(&format!("{function}: vr or value is NULL with nvr = {nvr}")),
            }
        })
    }
}

pub unsafe fn set<M: CoSimulation, T: FmiType + Copy>(
    c: fmi2Component,
    function: &'static str,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const T,
) -> fmi2Status {
    let call = if T::TYPE == crate::description::VarType::Real {
        Call::SetValues
    } else {
        Call::SetDiscreteValues
    };
    unsafe {
        with_instance::<M>(c, call, function, |inst| match (slice(vr, nvr), slice(value, nvr)) {
            (Some(vrs), Some(values)) => inst.set_values(function, vrs, values),
            _ => inst.error(&format!("{function}: vr or value is NULL with nvr = {nvr}")),
        })
    }
}

/// Booleans cross the ABI as `fmi2Boolean` (int): converted to and from `bool` here.
pub unsafe fn get_boolean<M: CoSimulation>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::GetValues, "fmi2GetBoolean", |inst| {
            match (slice(vr, nvr), slice_mut(value, nvr)) {
                (Some(vrs), Some(out)) => {
                    // One call for all references, so that they are all checked before anything
                    // is computed (one call per reference initialized the model, then refused
                    // the next reference).
                    let mut values = vec![false; vrs.len()];
                    let status = inst.get_values("fmi2GetBoolean", vrs, &mut values);
                    if status == fmi2OK {
                        for (o, v) in out.iter_mut().zip(values) {
                            *o = if v { fmi2True } else { fmi2False };
                        }
                    }
                    status
                }
                _ => inst.error(&format!("fmi2GetBoolean: vr or value is NULL with nvr = {nvr}")),
            }
        })
    }
}

pub unsafe fn set_boolean<M: CoSimulation>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::SetDiscreteValues, "fmi2SetBoolean", |inst| {
            match (slice(vr, nvr), slice(value, nvr)) {
                (Some(vrs), Some(values)) => {
                    let values: Vec<bool> = values.iter().map(|v| *v != fmi2False).collect();
                    inst.set_values("fmi2SetBoolean", vrs, &values)
                }
                _ => inst.error(&format!("fmi2SetBoolean: vr or value is NULL with nvr = {nvr}")),
            }
        })
    }
}

pub unsafe fn get_string<M: CoSimulation>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::GetValues, "fmi2GetString", |inst| {
            match (slice(vr, nvr), slice_mut(value, nvr)) {
                (Some(vrs), Some(out)) => inst.get_strings(vrs, out),
                _ => inst.error(&format!("fmi2GetString: vr or value is NULL with nvr = {nvr}")),
            }
        })
    }
}

pub unsafe fn set_string<M: CoSimulation>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::SetDiscreteValues, "fmi2SetString", |inst| {
            match (slice(vr, nvr), slice(value, nvr)) {
                (Some(vrs), Some(values)) => {
                    let mut texts = Vec::with_capacity(values.len());
                    for (i, p) in values.iter().enumerate() {
                        match text(*p) {
                            Some(t) => texts.push(t.into_owned()),
                            None => return inst.error(&format!("fmi2SetString: value[{i}] is NULL")),
                        }
                    }
                    inst.set_strings(vrs, &texts)
                }
                _ => inst.error(&format!("fmi2SetString: vr or value is NULL with nvr = {nvr}")),
            }
        })
    }
}

pub unsafe fn get_fmu_state<M: CoSimulation>(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::FmuState, "fmi2GetFMUstate", |inst| {
            if state.is_null() {
                return inst.error("fmi2GetFMUstate: FMUstate is NULL");
            }
            if (*state).is_null() {
                *state = snapshots::adopt(inst.guid, inst.sim.clone());
                return fmi2OK;
            }
            // A non-NULL *FMUstate is overwritten in place: it must be one of this FMU's.
            match snapshots::with::<M, _>(inst.guid, *state, |s| s.sim.clone_from(&inst.sim)) {
                Ok(()) => fmi2OK,
                Err(why) => inst.error(&format!("fmi2GetFMUstate: *FMUstate: {why}; refused, nothing changed")),
            }
        })
    }
}

pub unsafe fn set_fmu_state<M: CoSimulation>(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::FmuState, "fmi2SetFMUstate", |inst| {
            if state.is_null() {
                return inst.error("fmi2SetFMUstate: FMUstate is NULL");
            }
            let fits = |s: &mut snapshots::Snapshot<M>| s.sim.state;
            match snapshots::with::<M, _>(inst.guid, state, fits) {
                Ok(s) if !inst.state_fits(s) => {
                    return inst.error(&format!(
                        "fmi2SetFMUstate: the state was saved in {s:?}, a state of the other interface \
                         (this instance is {}); refused, nothing changed",
                        if inst.model_exchange {
                            "model exchange"
                        } else {
                            "co-simulation"
                        }
                    ));
                }
                Ok(_) => {}
                Err(why) => return inst.error(&format!("fmi2SetFMUstate: {why}; refused, nothing changed")),
            }
            match snapshots::with::<M, _>(inst.guid, state, |s| inst.sim.clone_from(&s.sim)) {
                Ok(()) => {
                    inst.restored();
                    fmi2OK
                }
                Err(why) => inst.error(&format!("fmi2SetFMUstate: {why}; refused, nothing changed")),
            }
        })
    }
}

pub unsafe fn free_fmu_state<M: CoSimulation>(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::FmuState, "fmi2FreeFMUstate", |inst| {
            if state.is_null() || (*state).is_null() {
                return fmi2OK;
            }
            match snapshots::release::<M>(inst.guid, *state) {
                Ok(()) => {
                    *state = ptr::null_mut();
                    fmi2OK
                }
                Err(why) => inst.error(&format!("fmi2FreeFMUstate: {why}; refused, nothing freed")),
            }
        })
    }
}

pub unsafe fn serialized_fmu_state_size<M: CoSimulation>(
    c: fmi2Component,
    state: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::FmuState, "fmi2SerializedFMUstateSize", |inst| {
            if state.is_null() || size.is_null() {
                return inst.error("fmi2SerializedFMUstateSize: FMUstate or size is NULL");
            }
            match snapshots::with::<M, _>(inst.guid, state, |s| super::state::serialize(inst.guid, &s.sim)) {
                Ok(Ok(bytes)) => {
                    *size = bytes.len();
                    fmi2OK
                }
                Ok(Err(why)) | Err(why) => inst.error(&format!("fmi2SerializedFMUstateSize: {why}")),
            }
        })
    }
}

pub unsafe fn serialize_fmu_state<M: CoSimulation>(
    c: fmi2Component,
    state: fmi2FMUstate,
    bytes: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::FmuState, "fmi2SerializeFMUstate", |inst| {
            if state.is_null() || bytes.is_null() {
                return inst.error("fmi2SerializeFMUstate: FMUstate or serializedState is NULL");
            }
            match snapshots::with::<M, _>(inst.guid, state, |s| super::state::serialize(inst.guid, &s.sim)) {
                Ok(Ok(data)) if data.len() == size => {
                    ptr::copy_nonoverlapping(data.as_ptr(), bytes as *mut u8, size);
                    fmi2OK
                }
                Ok(Ok(data)) => inst.error(&format!(
                    "fmi2SerializeFMUstate: size = {size}, but the state takes {} bytes \
                     (ask fmi2SerializedFMUstateSize)",
                    data.len()
                )),
                Ok(Err(why)) | Err(why) => inst.error(&format!("fmi2SerializeFMUstate: {why}")),
            }
        })
    }
}

pub unsafe fn deserialize_fmu_state<M: CoSimulation>(
    c: fmi2Component,
    bytes: *const fmi2Byte,
    size: usize,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::FmuState, "fmi2DeSerializeFMUstate", |inst| {
            if state.is_null() {
                return inst.error("fmi2DeSerializeFMUstate: FMUstate is NULL");
            }
            let Some(data) = slice(bytes as *const u8, size) else {
                return inst.error(&format!(
                    "fmi2DeSerializeFMUstate: serializedState is NULL with size = {size}"
                ));
            };
            let restored = super::state::deserialize::<M>(inst.guid, data)
                .and_then(|sim| super::instance::check_restored(&sim).map(|()| sim));
            let sim = match restored {
                Ok(sim) => sim,
                Err(e) => return inst.error(&format!("fmi2DeSerializeFMUstate: refused ({size} bytes): {e}")),
            };
            if (*state).is_null() {
                *state = snapshots::adopt(inst.guid, sim);
                return fmi2OK;
            }
            match snapshots::with::<M, _>(inst.guid, *state, |s| s.sim = sim) {
                Ok(()) => fmi2OK,
                Err(why) => inst.error(&format!(
                    "fmi2DeSerializeFMUstate: *FMUstate: {why}; refused, nothing changed"
                )),
            }
        })
    }
}

pub unsafe fn get_directional_derivative<M: CoSimulation>(
    c: fmi2Component,
    unknown_refs: *const fmi2ValueReference,
    n_unknown: usize,
    known_refs: *const fmi2ValueReference,
    n_known: usize,
    dv_known: *const fmi2Real,
    dv_unknown: *mut fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2GetDirectionalDerivative";
    unsafe {
        with_instance::<M>(c, Call::GetDirectionalDerivative, F, |inst| {
            let (Some(unknowns), Some(knowns), Some(dv), Some(out)) = (
                slice(unknown_refs, n_unknown),
                slice(known_refs, n_known),
                slice(dv_known, n_known),
                slice_mut(dv_unknown, n_unknown),
            ) else {
                return inst.error(&format!(
                    "{F}: vUnknown_ref, vKnown_ref, dvKnown or dvUnknown is NULL (nUnknown = {n_unknown}, nKnown = {n_known})"
                ));
            };
            inst.directional_derivative(unknowns, knowns, dv, out)
        })
    }
}

/// The model-exchange functions without arguments besides the instance.
macro_rules! me_transition {
    ($fn_name:ident, $call:ident, $name:literal, $method:ident) => {
        pub unsafe fn $fn_name<M: CoSimulation>(c: fmi2Component) -> fmi2Status {
            unsafe { with_instance::<M>(c, Call::$call, $name, |inst| inst.$method()) }
        }
    };
}
me_transition!(enter_event_mode, EnterEventMode, "fmi2EnterEventMode", enter_event_mode);
me_transition!(
    enter_continuous_time_mode,
    EnterContinuousTimeMode,
    "fmi2EnterContinuousTimeMode",
    enter_continuous_time_mode
);

pub unsafe fn new_discrete_states<M: CoSimulation>(c: fmi2Component, info: *mut fmi2EventInfo) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::NewDiscreteStates, "fmi2NewDiscreteStates", |inst| {
            if info.is_null() {
                return inst.error("fmi2NewDiscreteStates: fmi2EventInfo is NULL");
            }
            let mut e = super::instance::EventInfo::default();
            let status = inst.new_discrete_states(&mut e);
            let b = |v: bool| if v { fmi2True } else { fmi2False };
            *info = fmi2EventInfo {
                newDiscreteStatesNeeded: b(e.new_discrete_states_needed),
                terminateSimulation: b(e.terminate_simulation),
                nominalsOfContinuousStatesChanged: b(e.nominals_changed),
                valuesOfContinuousStatesChanged: b(e.values_changed),
                nextEventTimeDefined: b(e.next_event_time.is_some()),
                nextEventTime: e.next_event_time.unwrap_or(0.0),
            };
            status
        })
    }
}

pub unsafe fn completed_integrator_step<M: CoSimulation>(
    c: fmi2Component,
    _no_set_fmu_state_prior: fmi2Boolean,
    enter_event_mode: *mut fmi2Boolean,
    terminate_simulation: *mut fmi2Boolean,
) -> fmi2Status {
    const F: &str = "fmi2CompletedIntegratorStep";
    unsafe {
        with_instance::<M>(c, Call::CompletedIntegratorStep, F, |inst| {
            if enter_event_mode.is_null() || terminate_simulation.is_null() {
                return inst.error(&format!("{F}: enterEventMode or terminateSimulation is NULL"));
            }
            let (status, event, terminate) = inst.completed_integrator_step();
            *enter_event_mode = if event { fmi2True } else { fmi2False };
            *terminate_simulation = if terminate { fmi2True } else { fmi2False };
            status
        })
    }
}

pub unsafe fn set_time<M: CoSimulation>(c: fmi2Component, time: fmi2Real) -> fmi2Status {
    unsafe { with_instance::<M>(c, Call::SetTime, "fmi2SetTime", |inst| inst.set_time(time)) }
}

pub unsafe fn set_continuous_states<M: CoSimulation>(c: fmi2Component, x: *const fmi2Real, nx: usize) -> fmi2Status {
    const F: &str = "fmi2SetContinuousStates";
    unsafe {
        with_instance::<M>(c, Call::SetContinuousStates, F, |inst| match slice(x, nx) {
            Some(x) => inst.set_continuous_states(x),
            None => inst.error(&format!("{F}: x is NULL with nx = {nx}")),
        })
    }
}

/// fmi2GetContinuousStates, fmi2GetDerivatives, fmi2GetNominalsOfContinuousStates,
/// fmi2GetEventIndicators: an output array of the instance's size.
macro_rules! me_vector {
    ($fn_name:ident, $call:ident, $name:literal, $arg:literal, $method:ident) => {
        pub unsafe fn $fn_name<M: CoSimulation>(c: fmi2Component, out: *mut fmi2Real, n: usize) -> fmi2Status {
            unsafe {
                with_instance::<M>(c, Call::$call, $name, |inst| match slice_mut(out, n) {
                    Some(out) => inst.$method(out),
                    None => inst.error(&format!(concat!($name, ": ", $arg, " is NULL with n = {}"), n)),
                })
            }
        }
    };
}
me_vector!(
    get_continuous_states,
    GetContinuousStates,
    "fmi2GetContinuousStates",
    "x",
    get_continuous_states
);
me_vector!(
    get_derivatives,
    GetDerivatives,
    "fmi2GetDerivatives",
    "derivatives",
    get_derivatives
);
me_vector!(
    get_nominals_of_continuous_states,
    GetNominalsOfContinuousStates,
    "fmi2GetNominalsOfContinuousStates",
    "x_nominal",
    get_nominals
);
me_vector!(
    get_event_indicators,
    GetEventIndicators,
    "fmi2GetEventIndicators",
    "eventIndicators",
    get_event_indicators_mut
);

pub unsafe fn set_real_input_derivatives<M: CoSimulation>(c: fmi2Component, nvr: usize) -> fmi2Status {
    unsafe {
        with_instance::<M>(
            c,
            Call::SetRealInputDerivatives,
            "fmi2SetRealInputDerivatives",
            |inst| {
                if nvr == 0 {
                    return fmi2OK;
                }
                inst.error("fmi2SetRealInputDerivatives: inputs are held constant over a step (canInterpolateInputs=\"false\")")
            },
        )
    }
}

pub unsafe fn get_real_output_derivatives<M: CoSimulation>(c: fmi2Component, nvr: usize) -> fmi2Status {
    unsafe {
        with_instance::<M>(
            c,
            Call::GetRealOutputDerivatives,
            "fmi2GetRealOutputDerivatives",
            |inst| {
                if nvr == 0 {
                    return fmi2OK;
                }
                inst.error("fmi2GetRealOutputDerivatives: not provided (maxOutputDerivativeOrder=\"0\")")
            },
        )
    }
}

pub unsafe fn do_step<M: CoSimulation>(
    c: fmi2Component,
    current_communication_point: fmi2Real,
    communication_step_size: fmi2Real,
    _no_set_fmu_state_prior_to_current_point: fmi2Boolean,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::DoStep, "fmi2DoStep", |inst| {
            inst.do_step(current_communication_point, communication_step_size)
        })
    }
}

pub unsafe fn cancel_step<M: CoSimulation>(c: fmi2Component) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::CancelStep, "fmi2CancelStep", |_| {
            unreachable!("CancelStep is allowed in no state of a synchronous FMU")
        })
    }
}

pub unsafe fn get_status<M: CoSimulation>(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2Status,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::GetStatus, "fmi2GetStatus", |inst| {
            if value.is_null() {
                return inst.error("fmi2GetStatus: value is NULL");
            }
            inst.status_unavailable("fmi2GetStatus", kind)
        })
    }
}

pub unsafe fn get_real_status<M: CoSimulation>(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2Real,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::GetStatus, "fmi2GetRealStatus", |inst| match value.as_mut() {
            Some(v) => inst.real_status(kind, v),
            None => inst.error("fmi2GetRealStatus: value is NULL"),
        })
    }
}

pub unsafe fn get_integer_status<M: CoSimulation>(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2Integer,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::GetStatus, "fmi2GetIntegerStatus", |inst| {
            if value.is_null() {
                return inst.error("fmi2GetIntegerStatus: value is NULL");
            }
            inst.status_unavailable("fmi2GetIntegerStatus", kind)
        })
    }
}

pub unsafe fn get_boolean_status<M: CoSimulation>(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::GetStatus, "fmi2GetBooleanStatus", |inst| {
            match value.as_mut() {
                Some(v) => inst.boolean_status(kind, v),
                None => inst.error("fmi2GetBooleanStatus: value is NULL"),
            }
        })
    }
}

pub unsafe fn get_string_status<M: CoSimulation>(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2String,
) -> fmi2Status {
    unsafe {
        with_instance::<M>(c, Call::GetStatus, "fmi2GetStringStatus", |inst| {
            if value.is_null() {
                return inst.error("fmi2GetStringStatus: value is NULL");
            }
            inst.status_unavailable("fmi2GetStringStatus", kind)
        })
    }
}

/// The state an instance is in, for tests written against the runtime in Rust (not while a
/// call is inside it).
pub unsafe fn state_of<M: CoSimulation>(c: fmi2Component) -> Option<State> {
    // SAFETY: as in `with_instance`; no call is inside (the caller's promise).
    unsafe { (c as *const Component<M>).as_ref().map(|c| (*c.instance.get()).state()) }
}
