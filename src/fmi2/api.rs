//! The FMI 2.0 C boundary: the `fmi2*` functions that FMI 3.0 does not share, generic over
//! the model (the shared ones are [`crate::core::shared`], called with [`TERMS`]). The export
//! macro ([`export_fmi2!`](crate::export_fmi2)) forwards the `#[no_mangle]` symbols of an FMU
//! crate here. Pointers from the importer are checked for NULL and turned into slices and
//! references ([`crate::core::guard`]), and every call runs under `catch_unwind`, so no panic
//! crosses into the host.
//!
//! # Safety
//! Every `unsafe fn` here has the contract of the `fmi2*` function it implements, which the
//! standard puts on the importer: the instance handle is NULL or one that [`instantiate`]
//! returned for model `M` and that was not freed; every other pointer is NULL or valid as the
//! standard describes it (an array of the length passed beside it, a NUL-terminated string, a
//! writable output). Each `unsafe` block says which part of that, and which check, makes its
//! pointer operation sound.
#![allow(clippy::missing_safety_doc, clippy::too_many_arguments, non_upper_case_globals)]

use super::TERMS;
use super::abi::*;
use crate::core::guard::{Component, slice, slice_mut, text, with_instance};
use crate::core::instance::{EventInfo, Instance};
use crate::core::logging::{Callback, Category, Logger};
use crate::core::machine::Call;
use crate::core::resources::resource_dir;
use crate::model::CoSimulation;
use crate::value::FmiType;
use std::cell::UnsafeCell;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::ptr;
use std::sync::atomic::AtomicBool;

pub fn get_types_platform() -> fmi2String {
    TYPES_PLATFORM.as_ptr()
}

pub fn get_version() -> fmi2String {
    VERSION.as_ptr()
}

/// Why an instance of the interface asked for cannot be made: the model declares the other
/// interface only (`#[fmu(co_simulation_only)]`, `#[fmu(model_exchange_only)]`).
pub fn offered<M: CoSimulation>(model_exchange: bool) -> Option<String> {
    let (offered, name, declared) = if model_exchange {
        (M::MODEL_EXCHANGE, "Model Exchange", "co_simulation_only")
    } else {
        (M::CO_SIMULATION, "Co-Simulation", "model_exchange_only")
    };
    (!offered).then(|| {
        format!(
            "{} offers no {name} (declared #[fmu({declared})]; modelDescription.xml has no <{}> element)",
            M::DESCRIPTION.model_identifier,
            name.replace([' ', '-'], "")
        )
    })
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
        let Some(callback) = callbacks.logger else {
            return ptr::null_mut();
        };
        let logger = Logger::new(
            Callback::Printf(callback),
            callbacks.componentEnvironment,
            name.as_deref().unwrap_or(""),
            logging_on != fmi2False,
            M::DESCRIPTION.log_categories,
        );
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
        if let Some(why) = offered::<M>(fmu_type == fmi2ModelExchange) {
            return refuse(why);
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
        let inst = Instance::<M>::new(&TERMS, logger, own_guid, fmu_type == fmi2ModelExchange);
        let mut inst = inst;
        inst.resources = resources.as_deref().and_then(resource_dir).filter(|d| d.is_dir());
        inst.event(|| match resources.as_deref().map(resource_dir) {
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
            serial: None,
            owner: std::sync::atomic::AtomicUsize::new(0),
            in_callback: AtomicBool::new(false),
        })) as fmi2Component
    }));
    made.unwrap_or(ptr::null_mut())
}

pub unsafe fn setup_experiment<M: CoSimulation>(
    c: fmi2Component,
    tolerance_defined: fmi2Boolean,
    tolerance: fmi2Real,
    start_time: fmi2Real,
    stop_time_defined: fmi2Boolean,
    stop_time: fmi2Real,
) -> fmi2Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::SetupExperiment, "fmi2SetupExperiment", |inst| {
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

macro_rules! simple_call {
    ($fn_name:ident, $call:ident, $c_name:literal, $method:ident) => {
        pub unsafe fn $fn_name<M: CoSimulation>(c: fmi2Component) -> fmi2Status {
            // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
            let component = unsafe { Component::<M>::from_handle(c) };
            with_instance(component, Call::$call, $c_name, |inst| {
                inst.trace(|| concat!($c_name, "()").to_string());
                inst.$method()
            })
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
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetValues, function, |inst| {
        // SAFETY: `slice` and `slice_mut` check NULL; the contract makes `vr` and `value` hold
        // `nvr` elements each.
        match unsafe { (slice(vr, nvr), slice_mut(value, nvr)) } {
            (Some(vrs), Some(out)) => inst.get_values(function, vrs, out),
            _ => inst.error(&format!("{function}: vr or value is NULL with nvr = {nvr}")),
        }
    })
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
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, call, function, |inst| {
        // SAFETY: `slice` checks NULL; the contract makes `vr` and `value` hold `nvr` elements
        // each.
        match unsafe { (slice(vr, nvr), slice(value, nvr)) } {
            (Some(vrs), Some(values)) => inst.set_values(function, vrs, values),
            _ => inst.error(&format!("{function}: vr or value is NULL with nvr = {nvr}")),
        }
    })
}

/// Booleans cross the ABI as `fmi2Boolean` (int): converted to and from `bool` here.
pub unsafe fn get_boolean<M: CoSimulation>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetValues, "fmi2GetBoolean", |inst| {
        // SAFETY: `slice` and `slice_mut` check NULL; the contract makes `vr` and `value` hold
        // `nvr` elements each.
        match unsafe { (slice(vr, nvr), slice_mut(value, nvr)) } {
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

pub unsafe fn set_boolean<M: CoSimulation>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::SetDiscreteValues, "fmi2SetBoolean", |inst| {
        // SAFETY: `slice` checks NULL; the contract makes `vr` and `value` hold `nvr` elements
        // each.
        match unsafe { (slice(vr, nvr), slice(value, nvr)) } {
            (Some(vrs), Some(values)) => {
                let values: Vec<bool> = values.iter().map(|v| *v != fmi2False).collect();
                inst.set_values("fmi2SetBoolean", vrs, &values)
            }
            _ => inst.error(&format!("fmi2SetBoolean: vr or value is NULL with nvr = {nvr}")),
        }
    })
}

pub unsafe fn get_string<M: CoSimulation>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetValues, "fmi2GetString", |inst| {
        // SAFETY: `slice` and `slice_mut` check NULL; the contract makes `vr` and `value` hold
        // `nvr` elements each.
        match unsafe { (slice(vr, nvr), slice_mut(value, nvr)) } {
            (Some(vrs), Some(out)) => inst.get_strings(vrs, out),
            _ => inst.error(&format!("fmi2GetString: vr or value is NULL with nvr = {nvr}")),
        }
    })
}

pub unsafe fn set_string<M: CoSimulation>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::SetDiscreteValues, "fmi2SetString", |inst| {
        // SAFETY: `slice` checks NULL; the contract makes `vr` and `value` hold `nvr` elements
        // each.
        match unsafe { (slice(vr, nvr), slice(value, nvr)) } {
            (Some(vrs), Some(values)) => {
                let mut texts = Vec::with_capacity(values.len());
                for (i, p) in values.iter().enumerate() {
                    // SAFETY: `text` checks NULL; the contract makes each string NUL-terminated.
                    match unsafe { text(*p) } {
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
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetDirectionalDerivative, F, |inst| {
        // SAFETY: `slice` and `slice_mut` check NULL; the contract makes the unknowns' arrays
        // hold `nUnknown` elements and the knowns' `nKnown`.
        let (Some(unknowns), Some(knowns), Some(dv), Some(out)) = (unsafe {
            (
                slice(unknown_refs, n_unknown),
                slice(known_refs, n_known),
                slice(dv_known, n_known),
                slice_mut(dv_unknown, n_unknown),
            )
        }) else {
            return inst.error(&format!(
                "{F}: vUnknown_ref, vKnown_ref, dvKnown or dvUnknown is NULL (nUnknown = {n_unknown}, nKnown = {n_known})"
            ));
        };
        inst.directional_derivative(unknowns, knowns, dv, out)
    })
}

/// The model-exchange functions without arguments besides the instance.
macro_rules! me_transition {
    ($fn_name:ident, $call:ident, $name:literal, $method:ident) => {
        pub unsafe fn $fn_name<M: CoSimulation>(c: fmi2Component) -> fmi2Status {
            // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
            let component = unsafe { Component::<M>::from_handle(c) };
            with_instance(component, Call::$call, $name, |inst| inst.$method())
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
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::NewDiscreteStates, "fmi2NewDiscreteStates", |inst| {
        // SAFETY: `as_mut` checks NULL; the contract makes a non-NULL `info` writable.
        let Some(info) = (unsafe { info.as_mut() }) else {
            return inst.error("fmi2NewDiscreteStates: fmi2EventInfo is NULL");
        };
        let mut e = EventInfo::default();
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

pub unsafe fn completed_integrator_step<M: CoSimulation>(
    c: fmi2Component,
    _no_set_fmu_state_prior: fmi2Boolean,
    enter_event_mode: *mut fmi2Boolean,
    terminate_simulation: *mut fmi2Boolean,
) -> fmi2Status {
    const F: &str = "fmi2CompletedIntegratorStep";
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::CompletedIntegratorStep, F, |inst| {
        if enter_event_mode.is_null() || terminate_simulation.is_null() {
            return inst.error(&format!("{F}: enterEventMode or terminateSimulation is NULL"));
        }
        let (status, event, terminate) = inst.completed_integrator_step();
        // SAFETY: neither is NULL (checked above); the contract makes both writable. Written
        // through the raw pointers, which may even be the same one.
        unsafe {
            *enter_event_mode = if event { fmi2True } else { fmi2False };
            *terminate_simulation = if terminate { fmi2True } else { fmi2False };
        }
        status
    })
}

pub unsafe fn set_time<M: CoSimulation>(c: fmi2Component, time: fmi2Real) -> fmi2Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::SetTime, "fmi2SetTime", |inst| inst.set_time(time))
}

pub unsafe fn set_real_input_derivatives<M: CoSimulation>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *const fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2SetRealInputDerivatives";
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::SetRealInputDerivatives, F, |inst| {
        if nvr == 0 {
            return fmi2OK;
        }
        if !M::INTERPOLATES_INPUTS {
            return inst.error(&format!(
                "{F}: inputs are held constant over a step (canInterpolateInputs=\"false\")"
            ));
        }
        // SAFETY: each array is NULL or nvr long (this function's contract); `slice` checks NULL.
        match unsafe { (slice(vr, nvr), slice(order, nvr), slice(value, nvr)) } {
            (Some(vrs), Some(orders), Some(values)) => inst.set_input_derivatives(F, vrs, orders, values),
            _ => inst.error(&format!("{F}: vr, order or value is NULL with nvr = {nvr}")),
        }
    })
}

/// # Safety
/// `c` is NULL or a live instance of this library; `vr`, `order` and `value` NULL or `nvr`
/// long, `value` writable.
pub unsafe fn get_real_output_derivatives<M: CoSimulation>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *mut fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2GetRealOutputDerivatives";
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetRealOutputDerivatives, F, |inst| {
        // SAFETY: the arrays are NULL or nvr long (this function's contract).
        match unsafe { (slice(vr, nvr), slice(order, nvr), slice_mut(value, nvr)) } {
            (Some(vrs), Some(orders), Some(out)) => inst.output_derivatives(F, vrs, orders, out),
            _ => inst.error(&format!("{F}: vr, order or value is NULL with nvr = {nvr}")),
        }
    })
}

pub unsafe fn do_step<M: CoSimulation>(
    c: fmi2Component,
    current_communication_point: fmi2Real,
    communication_step_size: fmi2Real,
    _no_set_fmu_state_prior_to_current_point: fmi2Boolean,
) -> fmi2Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::DoStep, "fmi2DoStep", |inst| {
        inst.do_step(current_communication_point, communication_step_size)
    })
}

pub unsafe fn cancel_step<M: CoSimulation>(c: fmi2Component) -> fmi2Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::CancelStep, "fmi2CancelStep", |_| {
        unreachable!("CancelStep is allowed in no state of a synchronous FMU")
    })
}

pub unsafe fn get_status<M: CoSimulation>(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2Status,
) -> fmi2Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetStatus, "fmi2GetStatus", |inst| {
        if value.is_null() {
            return inst.error("fmi2GetStatus: value is NULL");
        }
        status_unavailable(inst, "fmi2GetStatus", kind)
    })
}

pub unsafe fn get_real_status<M: CoSimulation>(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2Real,
) -> fmi2Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetStatus, "fmi2GetRealStatus", |inst| {
        // SAFETY: `as_mut` checks NULL; the contract makes a non-NULL `value` writable.
        match unsafe { value.as_mut() } {
            Some(v) => real_status(inst, kind, v),
            None => inst.error("fmi2GetRealStatus: value is NULL"),
        }
    })
}

pub unsafe fn get_integer_status<M: CoSimulation>(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2Integer,
) -> fmi2Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetStatus, "fmi2GetIntegerStatus", |inst| {
        if value.is_null() {
            return inst.error("fmi2GetIntegerStatus: value is NULL");
        }
        status_unavailable(inst, "fmi2GetIntegerStatus", kind)
    })
}

pub unsafe fn get_boolean_status<M: CoSimulation>(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetStatus, "fmi2GetBooleanStatus", |inst| {
        // SAFETY: `as_mut` checks NULL; the contract makes a non-NULL `value` writable.
        match unsafe { value.as_mut() } {
            Some(v) => boolean_status(inst, kind, v),
            None => inst.error("fmi2GetBooleanStatus: value is NULL"),
        }
    })
}

pub unsafe fn get_string_status<M: CoSimulation>(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2String,
) -> fmi2Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetStatus, "fmi2GetStringStatus", |inst| {
        if value.is_null() {
            return inst.error("fmi2GetStringStatus: value is NULL");
        }
        status_unavailable(inst, "fmi2GetStringStatus", kind)
    })
}

fn real_status<M: CoSimulation>(inst: &Instance<M>, kind: fmi2StatusKind, value: &mut f64) -> fmi2Status {
    if kind == fmi2LastSuccessfulTime {
        *value = inst.sim.last_successful_time;
        return fmi2OK;
    }
    status_unavailable(inst, "fmi2GetRealStatus", kind)
}

fn boolean_status<M: CoSimulation>(inst: &Instance<M>, kind: fmi2StatusKind, value: &mut fmi2Boolean) -> fmi2Status {
    if kind == fmi2Terminated {
        *value = if inst.sim.terminate_requested {
            fmi2True
        } else {
            fmi2False
        };
        return fmi2OK;
    }
    status_unavailable(inst, "fmi2GetBooleanStatus", kind)
}

/// The standard's answer for a status this FMU does not have: fmi2Discard.
fn status_unavailable<M: CoSimulation>(inst: &Instance<M>, function: &str, kind: fmi2StatusKind) -> fmi2Status {
    let what = match kind {
        fmi2DoStepStatus | fmi2PendingStatus => "there is no asynchronous step (fmi2DoStep never returns fmi2Pending)",
        fmi2LastSuccessfulTime => "fmi2LastSuccessfulTime is a Real status (fmi2GetRealStatus)",
        fmi2Terminated => "fmi2Terminated is a Boolean status (fmi2GetBooleanStatus)",
        _ => "unknown fmi2StatusKind",
    };
    inst.logger.log(
        fmi2Discard,
        Category::StatusDiscard,
        &format!("{function}(kind = {kind}): not available: {what}"),
    );
    fmi2Discard
}
