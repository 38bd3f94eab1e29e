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
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::ptr;

pub fn get_types_platform() -> fmi2String {
    TYPES_PLATFORM.as_ptr()
}

pub fn get_version() -> fmi2String {
    VERSION.as_ptr()
}

/// Why an instance of the interface asked for cannot be made: the model declares the other
/// interface only (`#[fmu(co_simulation_only)]`, `#[fmu(model_exchange_only)]`).
/// A getter's Booleans (2.0's and 3.0's): read for all of `vrs` in one call, so that they are all
/// checked before anything is computed (one call per reference initialized the model, then
/// refused the next reference); written to the importer's array `out` as `c_value` makes them,
/// only when the read succeeded.
pub(crate) fn get_booleans<M: CoSimulation, C>(
    inst: &mut Instance<M>,
    function: &str,
    vrs: &[u32],
    out: &mut [C],
    c_value: impl Fn(bool) -> C,
) -> fmi2Status {
    let mut values = vec![false; out.len()];
    let status = inst.get_values(function, vrs, &mut values);
    if status == fmi2OK {
        for (o, v) in out.iter_mut().zip(values) {
            *o = c_value(v);
        }
    }
    status
}

/// A setter's strings (2.0's and 3.0's) as Rust strings, or the index of the first NULL one.
///
/// # Safety
/// Each pointer of `values` is NULL or a NUL-terminated string.
pub(crate) unsafe fn texts(values: &[*const std::os::raw::c_char]) -> Result<Vec<String>, usize> {
    let mut texts = Vec::with_capacity(values.len());
    for (i, p) in values.iter().enumerate() {
        // SAFETY: `text` checks NULL; the caller's contract makes each string NUL-terminated.
        match unsafe { text(*p) } {
            Some(t) => texts.push(t.into_owned()),
            None => return Err(i),
        }
    }
    Ok(texts)
}

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
        Component::into_handle(inst, false)
    }));
    made.unwrap_or(ptr::null_mut())
}

pub fn setup_experiment<M: CoSimulation>(
    c: Option<&Component<M>>,
    tolerance_defined: fmi2Boolean,
    tolerance: fmi2Real,
    start_time: fmi2Real,
    stop_time_defined: fmi2Boolean,
    stop_time: fmi2Real,
) -> fmi2Status {
    with_instance(c, Call::SetupExperiment, "fmi2SetupExperiment", |inst| {
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

/// What every 2.0 getter does before its type's own part: the instance and the state check
/// (`with_instance`), the two arrays' NULL checks; `read` then fills `value` for the value
/// references. Each getter below is its type's conversion only.
///
/// # Safety
/// The getter's contract: `vr` and `value` NULL or `nvr` elements, `value` writable.
#[inline(always)]
unsafe fn getter<M: CoSimulation, T>(
    c: Option<&Component<M>>,
    function: &'static str,
    (vr, nvr): (*const fmi2ValueReference, usize),
    value: *mut T,
    read: impl FnOnce(&mut Instance<M>, &[u32], &mut [T]) -> fmi2Status,
) -> fmi2Status {
    with_instance(c, Call::GetValues, function, |inst| {
        // SAFETY: `slice` and `slice_mut` check NULL; the contract makes `vr` and `value` hold
        // `nvr` elements each.
        match unsafe { (slice(vr, nvr), slice_mut(value, nvr)) } {
            (Some(vrs), Some(out)) => read(inst, vrs, out),
            _ => inst.error(&format!("{function}: vr or value is NULL with nvr = {nvr}")),
        }
    })
}

/// What every 2.0 setter does before its type's own part (as [`getter`]); `call` is the state
/// table's row: Reals may be set where continuous inputs may, the other types where discrete
/// ones may.
///
/// # Safety
/// The setter's contract: `vr` and `value` NULL or `nvr` elements.
#[inline(always)]
unsafe fn setter<M: CoSimulation, T>(
    c: Option<&Component<M>>,
    call: Call,
    function: &'static str,
    (vr, nvr): (*const fmi2ValueReference, usize),
    value: *const T,
    write: impl FnOnce(&mut Instance<M>, &[u32], &[T]) -> fmi2Status,
) -> fmi2Status {
    with_instance(c, call, function, |inst| {
        // SAFETY: `slice` checks NULL; the contract makes `vr` and `value` hold `nvr` elements
        // each.
        match unsafe { (slice(vr, nvr), slice(value, nvr)) } {
            (Some(vrs), Some(values)) => write(inst, vrs, values),
            _ => inst.error(&format!("{function}: vr or value is NULL with nvr = {nvr}")),
        }
    })
}

/// fmi2GetReal, fmi2GetInteger: the C array is the Rust type's.
pub unsafe fn get<M: CoSimulation, T: FmiType + Copy>(
    c: Option<&Component<M>>,
    function: &'static str,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut T,
) -> fmi2Status {
    let read = |inst: &mut Instance<M>, vrs: &[u32], out: &mut [T]| inst.get_values(function, vrs, out);
    // SAFETY: this function's contract is `getter`'s.
    unsafe { getter(c, function, (vr, nvr), value, read) }
}

/// fmi2SetReal, fmi2SetInteger.
pub unsafe fn set<M: CoSimulation, T: FmiType + Copy>(
    c: Option<&Component<M>>,
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
    let write = |inst: &mut Instance<M>, vrs: &[u32], values: &[T]| inst.set_values(function, vrs, values);
    // SAFETY: this function's contract is `setter`'s.
    unsafe { setter(c, call, function, (vr, nvr), value, write) }
}

/// Booleans cross the ABI as `fmi2Boolean` (int): converted to and from `bool` here.
pub unsafe fn get_boolean<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    const F: &str = "fmi2GetBoolean";
    let read = |inst: &mut Instance<M>, vrs: &[u32], out: &mut [fmi2Boolean]| {
        get_booleans(inst, F, vrs, out, |v| if v { fmi2True } else { fmi2False })
    };
    // SAFETY: this function's contract is `getter`'s.
    unsafe { getter(c, F, (vr, nvr), value, read) }
}

pub unsafe fn set_boolean<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    const F: &str = "fmi2SetBoolean";
    let write = |inst: &mut Instance<M>, vrs: &[u32], values: &[fmi2Boolean]| {
        let values: Vec<bool> = values.iter().map(|v| *v != fmi2False).collect();
        inst.set_values(F, vrs, &values)
    };
    // SAFETY: this function's contract is `setter`'s.
    unsafe { setter(c, Call::SetDiscreteValues, F, (vr, nvr), value, write) }
}

pub unsafe fn get_string<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    let read = |inst: &mut Instance<M>, vrs: &[u32], out: &mut [fmi2String]| inst.get_strings(vrs, out);
    // SAFETY: this function's contract is `getter`'s.
    unsafe { getter(c, "fmi2GetString", (vr, nvr), value, read) }
}

pub unsafe fn set_string<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    const F: &str = "fmi2SetString";
    let write = |inst: &mut Instance<M>, vrs: &[u32], values: &[fmi2String]| {
        // SAFETY: the contract makes each string NUL-terminated.
        match unsafe { texts(values) } {
            Ok(texts) => inst.set_strings(vrs, &texts),
            Err(i) => inst.error(&format!("{F}: value[{i}] is NULL")),
        }
    };
    // SAFETY: this function's contract is `setter`'s.
    unsafe { setter(c, Call::SetDiscreteValues, F, (vr, nvr), value, write) }
}

pub unsafe fn get_directional_derivative<M: CoSimulation>(
    c: Option<&Component<M>>,
    unknown_refs: *const fmi2ValueReference,
    n_unknown: usize,
    known_refs: *const fmi2ValueReference,
    n_known: usize,
    dv_known: *const fmi2Real,
    dv_unknown: *mut fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2GetDirectionalDerivative";
    with_instance(c, Call::GetDirectionalDerivative, F, |inst| {
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

/// fmi2NewDiscreteStates: the event iteration's answers in the importer's `fmi2EventInfo`.
pub unsafe fn new_discrete_states<M: CoSimulation>(c: Option<&Component<M>>, info: *mut fmi2EventInfo) -> fmi2Status {
    with_instance(c, Call::NewDiscreteStates, "fmi2NewDiscreteStates", |inst| {
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

pub unsafe fn set_real_input_derivatives<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *const fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2SetRealInputDerivatives";
    with_instance(c, Call::SetRealInputDerivatives, F, |inst| {
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
    c: Option<&Component<M>>,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *mut fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2GetRealOutputDerivatives";
    with_instance(c, Call::GetRealOutputDerivatives, F, |inst| {
        // SAFETY: the arrays are NULL or nvr long (this function's contract).
        match unsafe { (slice(vr, nvr), slice(order, nvr), slice_mut(value, nvr)) } {
            (Some(vrs), Some(orders), Some(out)) => inst.output_derivatives(F, vrs, orders, out),
            _ => inst.error(&format!("{F}: vr, order or value is NULL with nvr = {nvr}")),
        }
    })
}

pub fn do_step<M: CoSimulation>(
    c: Option<&Component<M>>,
    current_communication_point: fmi2Real,
    communication_step_size: fmi2Real,
    _no_set_fmu_state_prior_to_current_point: fmi2Boolean,
) -> fmi2Status {
    with_instance(c, Call::DoStep, "fmi2DoStep", |inst| {
        inst.do_step(current_communication_point, communication_step_size)
    })
}

pub fn cancel_step<M: CoSimulation>(c: Option<&Component<M>>) -> fmi2Status {
    with_instance(c, Call::CancelStep, "fmi2CancelStep", |_| {
        unreachable!("CancelStep is allowed in no state of a synchronous FMU")
    })
}

/// The fmi2GetXStatus functions: `answer` gives the status `kind` of the function's type if this
/// FMU has it (written to `value`); else fmi2Discard with the reason.
pub unsafe fn get_status<M: CoSimulation, T>(
    c: Option<&Component<M>>,
    function: &'static str,
    kind: fmi2StatusKind,
    value: *mut T,
    answer: fn(&Instance<M>, fmi2StatusKind) -> Option<T>,
) -> fmi2Status {
    with_instance(c, Call::GetStatus, function, |inst| {
        // SAFETY: `as_mut` checks NULL; the contract makes a non-NULL `value` writable.
        let Some(value) = (unsafe { value.as_mut() }) else {
            return inst.error(&format!("{function}: value is NULL"));
        };
        match answer(inst, kind) {
            Some(v) => {
                *value = v;
                fmi2OK
            }
            None => status_unavailable(inst, function, kind),
        }
    })
}

/// fmi2GetRealStatus's one status: the time the last step reached.
pub fn last_successful_time<M: CoSimulation>(inst: &Instance<M>, kind: fmi2StatusKind) -> Option<fmi2Real> {
    (kind == fmi2LastSuccessfulTime).then_some(inst.sim.last_successful_time)
}

/// fmi2GetBooleanStatus's one status: whether the model asked to end the simulation.
pub fn terminated<M: CoSimulation>(inst: &Instance<M>, kind: fmi2StatusKind) -> Option<fmi2Boolean> {
    (kind == fmi2Terminated).then_some(if inst.sim.terminate_requested {
        fmi2True
    } else {
        fmi2False
    })
}

/// The status functions of the other types: there is no such status here.
pub fn unavailable<M: CoSimulation, T>(_: &Instance<M>, _: fmi2StatusKind) -> Option<T> {
    None
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
