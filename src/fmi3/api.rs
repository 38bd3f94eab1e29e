//! The C boundary of FMI 3.0: the `fmi3*` functions that FMI 2.0 does not share, generic over
//! the model (the shared ones are [`crate::core::shared`], called with [`TERMS`]). The export
//! macro ([`export_fmi3!`](crate::export_fmi3)) forwards the `#[no_mangle]` symbols here. The
//! instance core and the guard around every call (NULL checks, the re-entrancy refusal,
//! `catch_unwind`) are the version-neutral [`crate::core`]'s; what differs in 3.0 is here: the
//! instantiation functions and their callback, typed getters and setters with `nValues`, the
//! independent variable `time`, Int64 enumerations, C `bool` booleans, the output arguments of
//! fmi3DoStep and fmi3UpdateDiscreteStates, and the adjoint derivative.
//!
//! # Safety
//! Every `unsafe fn` here has the contract of the `fmi3*` function it implements, which the
//! standard puts on the importer: the instance handle is NULL or one that an instantiation
//! function of this library returned for model `M` and that was not freed; every other pointer
//! is NULL or valid as the standard describes it (an array of the length passed beside it, a
//! NUL-terminated string, a writable output). Each `unsafe` block says which part of that, and
//! which check, makes its pointer operation sound.
#![allow(clippy::missing_safety_doc, clippy::too_many_arguments)]

use super::TERMS;
use super::abi::*;
use crate::core::guard::{Component, slice, slice_mut, text, with_instance};
use crate::core::instance::{EventInfo, Instance};
use crate::core::logging::{Callback, Category, Logger};
use crate::core::machine::{Call, State};
use crate::core::shared;
use crate::description::VarType;
use crate::model::CoSimulation;
use crate::value::{FmiType, Value};
use std::cell::UnsafeCell;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::ptr;
use std::sync::atomic::AtomicBool;

pub fn get_version() -> *const std::os::raw::c_char {
    VERSION.as_ptr()
}

/// `resourcePath`: a native absolute path of the unpacked `resources/` folder (FMI 3.0 2.2.4),
/// usually with a trailing separator.
fn resource_dir(path: &str) -> Option<std::path::PathBuf> {
    let p = std::path::PathBuf::from(path);
    p.is_absolute().then_some(p)
}

/// Both instantiation functions: checks, then the instance.
unsafe fn instantiate<M: CoSimulation>(
    function: &str,
    own_token: &'static str,
    description: &'static [u8],
    instance_name: fmi3String,
    token: fmi3String,
    resource_path: fmi3String,
    logging_on: bool,
    environment: fmi3InstanceEnvironment,
    log_message: fmi3LogMessageCallback,
    model_exchange: bool,
    refusal: Option<String>,
    warning: Option<String>,
    event_mode: (bool, bool),
    intermediate_update: Option<Box<dyn FnMut(f64) -> Option<f64>>>,
    scheduled: Option<Option<std::rc::Rc<dyn Fn()>>>,
) -> fmi3Instance {
    let made = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: NUL-terminated strings from the importer, or NULL.
        let (name, token, resources) = unsafe { (text(instance_name), text(token), text(resource_path)) };
        // The embedded description stays in the binary for `cargo fmu` to read.
        std::hint::black_box(description.len());
        let logger = Logger::new(
            Callback::Message(log_message),
            environment,
            name.as_deref().unwrap_or(""),
            logging_on,
            M::DESCRIPTION.log_categories,
        );
        let refuse = |why: String| {
            logger.log(fmi3Error, Category::StatusError, &format!("{function}: {why}"));
            ptr::null_mut()
        };
        let offered = || {
            if scheduled.is_some() {
                None
            } else {
                crate::fmi2::api::offered::<M>(model_exchange)
            }
        };
        if let Some(why) = refusal.or_else(offered) {
            return refuse(why);
        }
        match name.as_deref() {
            None => return refuse("instanceName is NULL; an instance needs a name".into()),
            Some(n) if n.trim().is_empty() => {
                return refuse(format!(
                    "instanceName {n:?} is empty or only white space; an instance needs a name"
                ));
            }
            Some(_) => {}
        }
        match token.as_deref() {
            None => return refuse(format!("instantiationToken is NULL; expected {own_token}")),
            Some(t) if t != own_token => {
                return refuse(format!(
                    "instantiationToken '{t}' does not match this binary's {own_token}: \
                     modelDescription.xml and binaries/ come from different builds of {}",
                    M::DESCRIPTION.model_identifier
                ));
            }
            Some(_) => {}
        }
        if let Some(what) = warning {
            logger.log(fmi3Warning, Category::StatusWarning, &format!("{function}: {what}"));
        }
        let mut inst = Instance::<M>::new(&TERMS, logger, own_token, model_exchange);
        (inst.event_mode_used, inst.early_return_allowed) = event_mode;
        inst.intermediate_update = intermediate_update;
        let serial = scheduled.is_some().then(|| std::sync::Mutex::new(()));
        if let Some(clock_update) = scheduled {
            inst.scheduled = true;
            inst.clock_update = clock_update;
        }
        inst.resources = resources.as_deref().and_then(resource_dir).filter(|d| d.is_dir());
        inst.event(|| match resources.as_deref().map(|r| (r, resource_dir(r))) {
            Some((_, Some(dir))) if dir.is_dir() => format!("resourcePath is {}", dir.display()),
            Some((r, _)) => format!("resourcePath {r:?} is no folder here (the model sees no resources)"),
            None => "resourcePath is NULL (the model sees no resources)".into(),
        });
        Box::into_raw(Box::new(Component {
            busy: AtomicBool::new(false),
            refusals: inst.logger.clone(),
            instance: UnsafeCell::new(inst),
            serial,
            owner: std::sync::atomic::AtomicUsize::new(0),
            in_callback: AtomicBool::new(false),
        })) as fmi3Instance
    }));
    made.unwrap_or(ptr::null_mut())
}

pub unsafe fn instantiate_model_exchange<M: CoSimulation>(
    own_token: &'static str,
    description: &'static [u8],
    instance_name: fmi3String,
    token: fmi3String,
    resource_path: fmi3String,
    _visible: fmi3Boolean,
    logging_on: fmi3Boolean,
    environment: fmi3InstanceEnvironment,
    log_message: fmi3LogMessageCallback,
) -> fmi3Instance {
    // SAFETY: the strings come with this function's contract, which is `instantiate`'s.
    unsafe {
        instantiate::<M>(
            "fmi3InstantiateModelExchange",
            own_token,
            description,
            instance_name,
            token,
            resource_path,
            logging_on,
            environment,
            log_message,
            true,
            None,
            None,
            (false, false),
            None,
            None,
        )
    }
}

pub unsafe fn instantiate_co_simulation<M: CoSimulation>(
    own_token: &'static str,
    description: &'static [u8],
    instance_name: fmi3String,
    token: fmi3String,
    resource_path: fmi3String,
    _visible: fmi3Boolean,
    logging_on: fmi3Boolean,
    event_mode_used: fmi3Boolean,
    early_return_allowed: fmi3Boolean,
    required_intermediate_variables: *const fmi3ValueReference,
    n_required_intermediate_variables: usize,
    environment: fmi3InstanceEnvironment,
    log_message: fmi3LogMessageCallback,
    intermediate_update: fmi3IntermediateUpdateCallback,
) -> fmi3Instance {
    // With eventModeUsed the importer handles the events in Event Mode; with earlyReturnAllowed
    // too, fmi3DoStep returns at each event (hasEventMode="true", mightReturnEarlyFromDoStep="true").
    //
    // Intermediate update (providesIntermediateUpdate="true", canReturnEarlyAfterIntermediateUpdate
    // ="true"): the runtime's integrator calls the importer's callback at the end of each accepted
    // internal step, with intermediateStepFinished = true, and neither asks for inputs nor lets the
    // importer read outputs there (intermediateVariableSetRequested = intermediateVariableGetAllowed
    // = false: no variable is declared intermediateUpdate="true", as reading one would mean
    // computing outputs in the middle of fmi3DoStep; a call from inside the callback is refused
    // as one while another runs). With earlyReturnAllowed the importer may ask the step to return
    // early (canReturnEarly = true): at the time it names if that is later in the step, else at the
    // internal step's end it was told. So no required intermediate variable can be honoured.
    // FMI 3.0 (2.3.1) has the importer list only variables declared intermediateUpdate="true";
    // one that lists others (fmusim's --intermediate-update lists every output) is told in the
    // log which it will not get there, and the instance is made all the same: refusing would
    // make the FMU unusable for an option that costs the importer nothing to lose (issue 49).
    let warning = (n_required_intermediate_variables > 0).then(|| {
        // SAFETY: NULL or nRequiredIntermediateVariables value references (the contract).
        let listed = unsafe { slice(required_intermediate_variables, n_required_intermediate_variables) };
        let names = match listed {
            Some(vrs) => vrs
                .iter()
                .map(
                    |&vr| match M::DESCRIPTION.variables.iter().find(|v| v.value_reference == vr) {
                        Some(v) => format!("'{}' (vr {vr})", v.name),
                        None => format!("vr {vr} (no such variable)"),
                    },
                )
                .collect::<Vec<_>>()
                .join(", "),
            None => "(the array is NULL)".to_string(),
        };
        format!(
            "{n_required_intermediate_variables} requiredIntermediateVariables given: {names}; no variable of {} is \
             declared intermediateUpdate=\"true\", so none of them is updated in Intermediate Update Mode (its \
             intermediate update reports the time and takes early-return requests); instantiating all the same",
            M::DESCRIPTION.model_identifier
        )
    });
    let refusal = if M::DESCRIPTION.has_clocks() && !event_mode_used {
        // FMI 3.0, 4.2.1 (eventModeUsed): "For FMUs that have clocks, eventModeUsed == fmi3True
        // is required." The importer activates the clocks in Event Mode.
        Some(format!(
            "{} has clocks, so it is instantiated with eventModeUsed = true (FMI 3.0: the importer activates the \
             clocks in Event Mode with fmi3SetClock); eventModeUsed = false was given",
            M::DESCRIPTION.model_identifier
        ))
    } else {
        None
    };
    let can_return_early = early_return_allowed;
    let intermediate = intermediate_update.map(|callback| {
        let hook = move |t: f64| -> Option<f64> {
            let (mut requested, mut at) = (false, t);
            // SAFETY: the importer's callback with its own environment pointer, as the
            // standard's signature has it; the two outputs point to locals.
            unsafe {
                callback(
                    environment,
                    t,
                    false,
                    false,
                    true,
                    can_return_early,
                    &mut requested,
                    &mut at,
                )
            };
            // A time that is no number is no time to return at: return at this step's end.
            (can_return_early && requested).then_some(if at.is_nan() { t } else { at })
        };
        Box::new(hook) as Box<dyn FnMut(f64) -> Option<f64>>
    });
    // SAFETY: the strings come with this function's contract, which is `instantiate`'s.
    unsafe {
        instantiate::<M>(
            "fmi3InstantiateCoSimulation",
            own_token,
            description,
            instance_name,
            token,
            resource_path,
            logging_on,
            environment,
            log_message,
            false,
            refusal,
            warning,
            (event_mode_used, event_mode_used && early_return_allowed),
            intermediate,
            None,
        )
    }
}

/// fmi3InstantiateScheduledExecution: an instance for Scheduled Execution (FMI 3.0, chapter 5)
/// when the model declares it (`#[fmu(scheduled_execution)]`, `<ScheduledExecution>`); else NULL,
/// with the reason through the importer's logger. `lockPreemption` and `unlockPreemption` are
/// not called: the runtime serializes the calls into one instance (a call from another thread
/// waits until the one inside is done), so nothing inside an instance is preempted.
pub unsafe fn instantiate_scheduled_execution<M: CoSimulation>(
    own_token: &'static str,
    description: &'static [u8],
    instance_name: fmi3String,
    token: fmi3String,
    resource_path: fmi3String,
    logging_on: fmi3Boolean,
    environment: fmi3InstanceEnvironment,
    log_message: fmi3LogMessageCallback,
    clock_update: fmi3ClockUpdateCallback,
) -> fmi3Instance {
    if !M::SCHEDULED_EXECUTION {
        let _ = catch_unwind(AssertUnwindSafe(|| {
            // SAFETY: a NUL-terminated string from the importer, or NULL.
            let name = unsafe { text(instance_name) };
            let logger = Logger::new(
                Callback::Message(log_message),
                environment,
                name.as_deref().unwrap_or(""),
                true,
                M::DESCRIPTION.log_categories,
            );
            logger.log(
                fmi3Error,
                Category::StatusError,
                &format!(
                    "fmi3InstantiateScheduledExecution: {} offers no scheduled execution (not declared \
                     #[fmu(scheduled_execution)]; modelDescription.xml has no <ScheduledExecution> element)",
                    M::DESCRIPTION.model_identifier
                ),
            );
        }));
        return ptr::null_mut();
    }
    let notify = clock_update.map(|callback| {
        // SAFETY: the importer's callback with its own environment pointer, as the standard's
        // signature has it.
        std::rc::Rc::new(move || unsafe { callback(environment) }) as std::rc::Rc<dyn Fn()>
    });
    // SAFETY: the strings come with this function's contract, which is `instantiate`'s.
    unsafe {
        instantiate::<M>(
            "fmi3InstantiateScheduledExecution",
            own_token,
            description,
            instance_name,
            token,
            resource_path,
            logging_on,
            environment,
            log_message,
            false,
            None,
            None,
            (false, false),
            None,
            Some(notify),
        )
    }
}

/// fmi3ActivateModelPartition (Scheduled Execution): the partition of input clock
/// `clock_reference` runs at `activation_time` (`Instance::activate_model_partition`). When it
/// ticked an output clock or gave a countdown clock its interval, the importer's clockUpdate
/// callback is called after the call has left the instance, in Clock Update Mode: from inside it
/// the importer reads fmi3GetClock, fmi3GetIntervalDecimal and the variables; when it returns, the
/// instance is back in Clock Activation Mode and the output clocks are inactive. Another thread's
/// call waits until all of this is done.
pub unsafe fn activate_model_partition<M: CoSimulation>(
    c: fmi3Instance,
    clock_reference: fmi3ValueReference,
    activation_time: fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3ActivateModelPartition";
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let Some(component) = (unsafe { Component::<M>::from_handle(c) }) else {
        return fmi3Error;
    };
    component.exclusive(|| {
        let mut notify = None;
        let status = component.run(Call::ActivateModelPartition, F, |inst| {
            match inst.activate_model_partition(F, clock_reference, activation_time) {
                Ok(true) => {
                    if let Some(callback) = &inst.clock_update {
                        inst.sim.state = State::ClockUpdateMode;
                        notify = Some(callback.clone());
                    }
                    fmi3OK
                }
                Ok(false) => fmi3OK,
                Err(status) => status,
            }
        });
        if let Some(callback) = notify {
            component.in_callback.store(true, std::sync::atomic::Ordering::Release);
            let _ = catch_unwind(AssertUnwindSafe(|| callback()));
            component.in_callback.store(false, std::sync::atomic::Ordering::Release);
            component.run_internal(F, |inst| inst.end_clock_update());
        }
        status
    })
}

pub unsafe fn set_debug_logging<M: CoSimulation>(
    c: fmi3Instance,
    logging_on: fmi3Boolean,
    n: usize,
    categories: *const fmi3String,
) -> fmi3Status {
    // SAFETY: the arguments come with this function's contract, which is the callee's.
    unsafe { shared::set_debug_logging::<M>(&TERMS, c, logging_on, n, categories) }
}

pub unsafe fn enter_initialization_mode<M: CoSimulation>(
    c: fmi3Instance,
    tolerance_defined: fmi3Boolean,
    tolerance: fmi3Float64,
    start_time: fmi3Float64,
    stop_time_defined: fmi3Boolean,
    stop_time: fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3EnterInitializationMode";
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::EnterInitializationMode, F, |inst| {
        inst.trace(|| {
            format!(
                "{F}(toleranceDefined = {tolerance_defined}, tolerance = {tolerance}, startTime = {start_time}, \
                 stopTimeDefined = {stop_time_defined}, stopTime = {stop_time})"
            )
        });
        let status = inst.setup_experiment(
            tolerance_defined.then_some(tolerance),
            start_time,
            stop_time_defined.then_some(stop_time),
        );
        if status != fmi3OK {
            return status;
        }
        inst.enter_initialization_mode()
    })
}

macro_rules! simple_call {
    ($fn_name:ident, $call:ident, $c_name:literal, $method:ident) => {
        pub unsafe fn $fn_name<M: CoSimulation>(c: fmi3Instance) -> fmi3Status {
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
    exit_initialization_mode,
    ExitInitializationMode,
    "fmi3ExitInitializationMode",
    exit_initialization_mode
);
simple_call!(terminate, Terminate, "fmi3Terminate", terminate);
simple_call!(reset, Reset, "fmi3Reset", reset);
simple_call!(enter_event_mode, EnterEventMode, "fmi3EnterEventMode", enter_event_mode);
simple_call!(
    enter_continuous_time_mode,
    EnterContinuousTimeMode,
    "fmi3EnterContinuousTimeMode",
    enter_continuous_time_mode
);

/// The value reference FMI 3.0's added `time` variable has, if the model does not declare its
/// own independent variable.
#[inline]
fn added_time_vr<M: CoSimulation>() -> Option<u32> {
    const {
        if M::DESCRIPTION.declares_independent() {
            None
        } else {
            Some(M::DESCRIPTION.time_value_reference())
        }
    }
}

/// The checks every 3.0 getter and setter makes of its arrays first.
fn arrays<'a, M: CoSimulation, T>(
    inst: &Instance<M>,
    function: &str,
    vrs: Option<&'a [u32]>,
    n_values: usize,
    values: Option<T>,
) -> Result<(&'a [u32], T), fmi3Status> {
    match (vrs, values) {
        (Some(vrs), Some(values)) if n_values == value_count::<M>(&inst.sim.model, vrs) => Ok((vrs, values)),
        (Some(vrs), Some(_)) if !M::DESCRIPTION.has_arrays() => Err(inst.error(&format!(
            "{function}: nValues = {n_values}, but nValueReferences = {} (every variable of this FMU is a scalar)",
            vrs.len()
        ))),
        (Some(vrs), Some(_)) => Err(inst.error(&format!(
            "{function}: nValues = {n_values}, but the {} value references have {} values (an array counts each element)",
            vrs.len(),
            value_count::<M>(&inst.sim.model, vrs)
        ))),
        _ => Err(inst.error(&format!(
            "{function}: valueReferences or values is NULL with nValueReferences = {}, nValues = {n_values}",
            vrs.map_or(0, |v| v.len())
        ))),
    }
}

/// How many values the variables of `vrs` have (FMI 3.0's nValues): one per scalar, every
/// element of an array (an unknown value reference counts one; it is refused afterwards).
/// A sized array's elements within its lengths now (the structural parameters' values).
fn value_count<M: CoSimulation>(model: &M, vrs: &[u32]) -> usize {
    if !const { M::DESCRIPTION.has_arrays() } {
        return vrs.len();
    }
    vrs.iter().map(|vr| count_of::<M>(model, *vr)).sum()
}

/// The number of values of one value reference (1 for a scalar or an unknown one).
fn count_of<M: CoSimulation>(model: &M, vr: u32) -> usize {
    crate::core::structural::count_of(model, vr)
}

/// Refuses a value reference whose variable is declared with another 3.0 type: Int32 is
/// `Integer`, Int64 the enumerations (2.0 reads both as fmi2Integer).
fn check_declared<M: CoSimulation>(
    inst: &Instance<M>,
    function: &str,
    vrs: &[u32],
    want: VarType,
) -> Result<(), fmi3Status> {
    for vr in vrs {
        if let Some(v) = M::variable_index(*vr).map(|i| &M::DESCRIPTION.variables[i])
            && v.var_type != want
            && crate::description::same_api_type(v.var_type, want)
        {
            return Err(inst.error(&format!(
                "{function}: value reference {vr} ('{}') is {}, read and written with {}",
                v.name,
                fmi3_type_name(v.var_type),
                accessor(v.var_type)
            )));
        }
    }
    Ok(())
}

fn fmi3_type_name(t: VarType) -> String {
    let name = t.fmi3_name();
    let article = if matches!(name.as_bytes()[0], b'E' | b'I') {
        "an"
    } else {
        "a"
    };
    format!("{article} {name} variable")
}

fn accessor(t: VarType) -> String {
    let name = match t {
        // FMI 3.0's Enumerations are Int64 values.
        VarType::Enumeration => "Int64",
        other => other.fmi3_name(),
    };
    format!("fmi3Get{name}/fmi3Set{name}")
}

/// What every 3.0 getter does before its type's own part: the instance and the state check
/// (`with_instance`), the two arrays (NULL and length checks, [`arrays`]); `read` then fills
/// `values` for the value references. One copy for every type (issue 22); each getter below is
/// its type's conversion only.
///
/// # Safety
/// The getter's contract: `c` NULL or a live instance of this library for `M`; `vr` NULL or
/// `nvr` elements; `values` NULL or `n_values` writable elements of `T`.
#[inline(always)]
unsafe fn getter<M: CoSimulation, T>(
    function: &'static str,
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut T,
    n_values: usize,
    read: impl FnOnce(&mut Instance<M>, &[u32], &mut [T]) -> fmi3Status,
) -> fmi3Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetValues, function, |inst| {
        // SAFETY: `slice` and `slice_mut` check NULL; the contract makes `vr` hold `nvr`
        // elements and `values` `n_values`.
        let (vrs, given) = unsafe { (slice(vr, nvr), slice_mut(values, n_values)) };
        match arrays(inst, function, vrs, n_values, given) {
            Ok((vrs, out)) => read(inst, vrs, out),
            Err(status) => status,
        }
    })
}

/// What every 3.0 setter does before its type's own part (as [`getter`]); `call` is the state
/// table's row: Float64 may be set where continuous inputs may, the other types where discrete
/// ones may.
///
/// # Safety
/// The setter's contract: `c` NULL or a live instance of this library for `M`; `vr` NULL or
/// `nvr` elements; `values` NULL or `n_values` elements of `T`.
#[inline(always)]
unsafe fn setter<M: CoSimulation, T>(
    function: &'static str,
    call: Call,
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const T,
    n_values: usize,
    write: impl FnOnce(&mut Instance<M>, &[u32], &[T]) -> fmi3Status,
) -> fmi3Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, call, function, |inst| {
        // SAFETY: `slice` checks NULL; the contract makes `vr` hold `nvr` elements and `values`
        // `n_values`.
        let (vrs, given) = unsafe { (slice(vr, nvr), slice(values, n_values)) };
        match arrays(inst, function, vrs, n_values, given) {
            Ok((vrs, values)) => write(inst, vrs, values),
            Err(status) => status,
        }
    })
}

pub unsafe fn get_float64<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Float64,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetFloat64";
    let read = |inst: &mut Instance<M>, vrs: &[u32], out: &mut [f64]| match added_time_vr::<M>() {
        Some(time) if vrs.contains(&time) && inst.state() == State::Instantiated => inst.error(&format!(
            "{F}: value reference {time} is 'time', the independent variable: it has no start value and no \
             value before fmi3EnterInitializationMode sets the start time"
        )),
        Some(time) if vrs.contains(&time) => {
            let others: Vec<u32> = vrs.iter().copied().filter(|v| *v != time).collect();
            let mut got = vec![0.0; value_count::<M>(&inst.sim.model, &others)];
            let status = inst.get_values(F, &others, &mut got);
            if status != fmi3OK {
                return status;
            }
            let mut got = got.into_iter();
            let mut slots = out.iter_mut();
            for vr in vrs {
                if *vr == time {
                    if let Some(slot) = slots.next() {
                        *slot = inst.sim.time;
                    }
                    continue;
                }
                for _ in 0..count_of::<M>(&inst.sim.model, *vr) {
                    if let Some(slot) = slots.next() {
                        *slot = got.next().unwrap_or(f64::NAN);
                    }
                }
            }
            fmi3OK
        }
        _ => inst.get_values(F, vrs, out),
    };
    // SAFETY: this function's contract is `getter`'s.
    unsafe { getter::<M, _>(F, c, vr, nvr, values, n_values, read) }
}

pub unsafe fn set_float64<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Float64,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3SetFloat64";
    let write = |inst: &mut Instance<M>, vrs: &[u32], values: &[f64]| {
        if let Some(time) = added_time_vr::<M>()
            && vrs.contains(&time)
        {
            return inst.error(&format!(
                "{F}: value reference {time} is 'time', the independent variable: it cannot be set \
                 (fmi3EnterInitializationMode sets the start time, fmi3SetTime the time in model exchange); nothing set"
            ));
        }
        inst.set_values(F, vrs, values)
    };
    // SAFETY: this function's contract is `setter`'s.
    unsafe { setter::<M, _>(F, Call::SetValues, c, vr, nvr, values, n_values, write) }
}

pub unsafe fn get_int32<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Int32,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetInt32";
    let read =
        |inst: &mut Instance<M>, vrs: &[u32], out: &mut [i32]| match check_declared(inst, F, vrs, VarType::Integer) {
            Ok(()) => inst.get_values(F, vrs, out),
            Err(status) => status,
        };
    // SAFETY: this function's contract is `getter`'s.
    unsafe { getter::<M, _>(F, c, vr, nvr, values, n_values, read) }
}

pub unsafe fn set_int32<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Int32,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3SetInt32";
    let write =
        |inst: &mut Instance<M>, vrs: &[u32], values: &[i32]| match check_declared(inst, F, vrs, VarType::Integer) {
            Ok(()) => inst.set_values(F, vrs, values),
            Err(status) => status,
        };
    // SAFETY: this function's contract is `setter`'s.
    unsafe { setter::<M, _>(F, Call::SetDiscreteValues, c, vr, nvr, values, n_values, write) }
}

/// Int64 variables and Enumerations (fmi3GetInt64 is their 3.0 type's accessor; the values
/// are the items' `value`s), in one call if need be.
pub unsafe fn get_int64<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Int64,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetInt64";
    let read = |inst: &mut Instance<M>, vrs: &[u32], out: &mut [i64]| {
        let enums = match int64_or_enumerations(inst, F, vrs) {
            Ok(e) => e,
            Err(status) => return status,
        };
        if !enums.iter().any(|e| *e) {
            return inst.get_values(F, vrs, out);
        }
        // Both kinds read into their own arrays, copied out only when both succeeded.
        let pick = |want: bool| -> Vec<u32> {
            vrs.iter()
                .zip(&enums)
                .filter(|(_, e)| **e == want)
                .map(|(v, _)| *v)
                .collect()
        };
        let (e_vrs, i_vrs) = (pick(true), pick(false));
        let mut e_got = vec![0i32; value_count::<M>(&inst.sim.model, &e_vrs)];
        let mut i_got = vec![0i64; value_count::<M>(&inst.sim.model, &i_vrs)];
        let status = inst.get_values(F, &e_vrs, &mut e_got);
        if status != fmi3OK {
            return status;
        }
        let status = inst.get_values(F, &i_vrs, &mut i_got);
        if status != fmi3OK {
            return status;
        }
        let (mut e_got, mut i_got) = (e_got.into_iter(), i_got.into_iter());
        let mut slots = out.iter_mut();
        for (vr, e) in vrs.iter().zip(enums) {
            for _ in 0..count_of::<M>(&inst.sim.model, *vr) {
                if let Some(o) = slots.next() {
                    *o = if e {
                        e_got.next().map(i64::from).unwrap_or_default()
                    } else {
                        i_got.next().unwrap_or_default()
                    };
                }
            }
        }
        fmi3OK
    };
    // SAFETY: this function's contract is `getter`'s.
    unsafe { getter::<M, _>(F, c, vr, nvr, values, n_values, read) }
}

pub unsafe fn set_int64<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Int64,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3SetInt64";
    let write = |inst: &mut Instance<M>, vrs: &[u32], values: &[i64]| {
        let enums = match int64_or_enumerations(inst, F, vrs) {
            Ok(e) => e,
            Err(status) => return status,
        };
        let mut list = Vec::with_capacity(values.len());
        let mut given = values.iter();
        for (vr, e) in vrs.iter().zip(enums) {
            for v in given.by_ref().take(count_of::<M>(&inst.sim.model, *vr)) {
                if !e {
                    list.push(Value::Int64(*v));
                    continue;
                }
                match i32::try_from(*v) {
                    Ok(x) => list.push(Value::Integer(x)),
                    Err(_) => {
                        return inst.error(&format!(
                            "{F}: {v} for value reference {vr} is no item of its enumeration (every item's value is an Int32); nothing set"
                        ));
                    }
                }
            }
        }
        inst.set_value_list(F, vrs, &list)
    };
    // SAFETY: this function's contract is `setter`'s.
    unsafe { setter::<M, _>(F, Call::SetDiscreteValues, c, vr, nvr, values, n_values, write) }
}

/// For each value reference of an fmi3GetInt64/fmi3SetInt64 call: whether it is an Enumeration
/// (else an Int64); a variable of another type is refused with its accessor named.
fn int64_or_enumerations<M: CoSimulation>(
    inst: &Instance<M>,
    function: &str,
    vrs: &[u32],
) -> Result<Vec<bool>, fmi3Status> {
    let mut out = Vec::with_capacity(vrs.len());
    for vr in vrs {
        match M::variable_index(*vr).map(|i| &M::DESCRIPTION.variables[i]) {
            Some(v) if v.var_type == VarType::Enumeration => out.push(true),
            Some(v) if v.var_type == VarType::Int64 => out.push(false),
            Some(v) => {
                return Err(inst.error(&format!(
                    "{function}: value reference {vr} ('{}') is {}, read and written with {}",
                    v.name,
                    fmi3_type_name(v.var_type),
                    accessor(v.var_type)
                )));
            }
            None => {
                return Err(inst.error(&format!(
                    "{function}: value reference {vr} is not an Int64 or Enumeration variable of {} (see modelDescription.xml)",
                    M::DESCRIPTION.model_identifier
                )));
            }
        }
    }
    Ok(out)
}

/// The getter of an FMI 3.0 numeric type without a 2.0 counterpart (Float32, Int8, UInt8,
/// Int16, UInt16, UInt32, UInt64): the C array is the Rust type's.
pub unsafe fn get_typed<M: CoSimulation, T: FmiType + Copy>(
    c: fmi3Instance,
    function: &'static str,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut T,
    n_values: usize,
) -> fmi3Status {
    let read = |inst: &mut Instance<M>, vrs: &[u32], out: &mut [T]| inst.get_values(function, vrs, out);
    // SAFETY: this function's contract is `getter`'s.
    unsafe { getter::<M, T>(function, c, vr, nvr, values, n_values, read) }
}

pub unsafe fn set_typed<M: CoSimulation, T: FmiType + Copy>(
    c: fmi3Instance,
    function: &'static str,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const T,
    n_values: usize,
) -> fmi3Status {
    let write = |inst: &mut Instance<M>, vrs: &[u32], values: &[T]| inst.set_values(function, vrs, values);
    // Float32 may be continuous, so set where continuous inputs may be; the integers are discrete.
    let call = if T::TYPE.is_float() {
        Call::SetValues
    } else {
        Call::SetDiscreteValues
    };
    // SAFETY: this function's contract is `setter`'s.
    unsafe { setter::<M, T>(function, call, c, vr, nvr, values, n_values, write) }
}

pub unsafe fn get_binary<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    value_sizes: *mut usize,
    values: *mut fmi3Binary,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetBinary";
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetValues, F, |inst| {
        // SAFETY: `slice` and `slice_mut` check NULL; the contract makes `vr` hold `nvr`
        // elements, and `valueSizes` and `values` `n_values` each.
        let (vrs, sizes, out) = unsafe {
            (
                slice(vr, nvr),
                slice_mut(value_sizes, n_values),
                slice_mut(values, n_values),
            )
        };
        let both = sizes.zip(out);
        match arrays(inst, F, vrs, n_values, both) {
            Ok((vrs, (sizes, out))) => inst.get_binaries(F, vrs, sizes, out),
            Err(status) => status,
        }
    })
}

pub unsafe fn set_binary<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    value_sizes: *const usize,
    values: *const fmi3Binary,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3SetBinary";
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::SetDiscreteValues, F, |inst| {
        // SAFETY: `slice` checks NULL; the contract makes `vr` hold `nvr` elements, and
        // `valueSizes` and `values` `n_values` each.
        let (vrs, sizes, ptrs) = unsafe { (slice(vr, nvr), slice(value_sizes, n_values), slice(values, n_values)) };
        let (vrs, (sizes, ptrs)) = match arrays(inst, F, vrs, n_values, sizes.zip(ptrs)) {
            Ok(a) => a,
            Err(status) => return status,
        };
        let mut bytes = Vec::with_capacity(vrs.len());
        for (i, (size, p)) in sizes.iter().zip(ptrs).enumerate() {
            // SAFETY: `slice` checks NULL (a size of 0 with NULL is an empty value); the
            // contract makes `values[i]` hold `valueSizes[i]` bytes.
            match unsafe { slice(*p, *size) } {
                Some(b) => bytes.push(b),
                None => {
                    return inst.error(&format!(
                        "{F}: values[{i}] is NULL with valueSizes[{i}] = {size}; nothing set"
                    ));
                }
            }
        }
        inst.set_binaries(F, vrs, &bytes)
    })
}

pub unsafe fn get_boolean<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Boolean,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetBoolean";
    // Written as bytes 0 and 1: the importer's array is C `bool` (one byte).
    let read = |inst: &mut Instance<M>, vrs: &[u32], out: &mut [u8]| {
        let mut got = vec![false; out.len()];
        let status = inst.get_values(F, vrs, &mut got);
        if status == fmi3OK {
            for (o, v) in out.iter_mut().zip(got) {
                *o = u8::from(v);
            }
        }
        status
    };
    // SAFETY: this function's contract is `getter`'s.
    unsafe { getter::<M, u8>(F, c, vr, nvr, values as *mut u8, n_values, read) }
}

pub unsafe fn set_boolean<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Boolean,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3SetBoolean";
    // Read as bytes: any non-zero byte is true (a C caller may pass other values).
    let write = |inst: &mut Instance<M>, vrs: &[u32], values: &[u8]| {
        let values: Vec<bool> = values.iter().map(|b| *b != 0).collect();
        inst.set_values(F, vrs, &values)
    };
    // SAFETY: this function's contract is `setter`'s.
    unsafe {
        setter::<M, u8>(
            F,
            Call::SetDiscreteValues,
            c,
            vr,
            nvr,
            values as *const u8,
            n_values,
            write,
        )
    }
}

pub unsafe fn get_string<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3String,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetString";
    let read = |inst: &mut Instance<M>, vrs: &[u32], out: &mut [fmi3String]| inst.get_strings(vrs, out);
    // SAFETY: this function's contract is `getter`'s.
    unsafe { getter::<M, _>(F, c, vr, nvr, values, n_values, read) }
}

pub unsafe fn set_string<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3String,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3SetString";
    let write = |inst: &mut Instance<M>, vrs: &[u32], values: &[fmi3String]| {
        let mut texts = Vec::with_capacity(values.len());
        for (i, p) in values.iter().enumerate() {
            // SAFETY: `text` checks NULL; the contract makes each string NUL-terminated.
            match unsafe { text(*p) } {
                Some(t) => texts.push(t.into_owned()),
                None => return inst.error(&format!("{F}: values[{i}] is NULL; nothing set")),
            }
        }
        inst.set_strings(vrs, &texts)
    };
    // SAFETY: this function's contract is `setter`'s.
    unsafe { setter::<M, _>(F, Call::SetDiscreteValues, c, vr, nvr, values, n_values, write) }
}

/// The dependencies of `dependent` in the instance's state, from the declarations (the same
/// ones `<ModelStructure>` lists), or the logged refusal.
fn dependencies_of<M: CoSimulation>(
    inst: &Instance<M>,
    function: &str,
    dependent: u32,
) -> Result<Vec<u32>, fmi3Status> {
    let initialization = matches!(inst.state(), State::Instantiated | State::InitializationMode);
    let time_vr = M::DESCRIPTION.time_value_reference();
    M::DESCRIPTION
        .dependencies(dependent, initialization, time_vr)
        .ok_or_else(|| {
            let what = match M::variable_index(dependent) {
                Some(i) => format!("'{}'", M::DESCRIPTION.variables[i].name),
                None if added_time_vr::<M>() == Some(dependent) => "'time'".to_string(),
                None => {
                    return inst.error(&format!(
                        "{function}: value reference {dependent} is no variable of {}",
                        M::DESCRIPTION.model_identifier
                    ));
                }
            };
            inst.error(&format!(
                "{function}: {what} (vr {dependent}) is no unknown {}: it has no dependencies to report",
                if initialization {
                    "of Initialization Mode (<InitialUnknown>)"
                } else {
                    "of <ModelStructure> (an output, a state derivative or an event indicator)"
                }
            ))
        })
}

pub unsafe fn get_number_of_variable_dependencies<M: CoSimulation>(
    c: fmi3Instance,
    dependent: fmi3ValueReference,
    n: *mut usize,
) -> fmi3Status {
    const F: &str = "fmi3GetNumberOfVariableDependencies";
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::SetDebugLogging, F, |inst| {
        if n.is_null() {
            return inst.error(&format!("{F}: nDependencies is NULL"));
        }
        match dependencies_of(inst, F, dependent) {
            Ok(deps) => {
                // SAFETY: not NULL; the contract makes it point to one size_t.
                unsafe { *n = deps.len() };
                fmi3OK
            }
            Err(status) => status,
        }
    })
}

pub unsafe fn get_variable_dependencies<M: CoSimulation>(
    c: fmi3Instance,
    dependent: fmi3ValueReference,
    element_indices_of_dependent: *mut usize,
    independents: *mut fmi3ValueReference,
    element_indices_of_independents: *mut usize,
    kinds: *mut fmi3DependencyKind,
    n: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetVariableDependencies";
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::SetDebugLogging, F, |inst| {
        let deps = match dependencies_of(inst, F, dependent) {
            Ok(deps) => deps,
            Err(status) => return status,
        };
        if n != deps.len() {
            return inst.error(&format!(
                "{F}: nDependencies = {n}, but '{dependent}' has {} (fmi3GetNumberOfVariableDependencies)",
                deps.len()
            ));
        }
        // SAFETY: `slice_mut` checks NULL; the contract makes each array hold `n` elements.
        let arrays = unsafe {
            (
                slice_mut(element_indices_of_dependent, n),
                slice_mut(independents, n),
                slice_mut(element_indices_of_independents, n),
                slice_mut(kinds, n),
            )
        };
        let (Some(e_dep), Some(ind), Some(e_ind), Some(k)) = arrays else {
            return inst.error(&format!("{F}: an output array is NULL with nDependencies = {n}"));
        };
        for (i, vr) in deps.into_iter().enumerate() {
            // Every variable is a scalar: element index 0 (the whole variable); the kind is not
            // analysed further than "depends".
            e_dep[i] = 0;
            ind[i] = vr;
            e_ind[i] = 0;
            k[i] = fmi3Dependent;
        }
        fmi3OK
    })
}

/// A function of a feature this FMU does not have (clocks, configuration mode, variable
/// dependencies at run time): fmi3Error with the reason, in any state.
pub unsafe fn not_provided<M: CoSimulation>(c: fmi3Instance, function: &'static str, why: &'static str) -> fmi3Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::SetDebugLogging, function, |inst| {
        inst.error(&format!("{function}: {why}"))
    })
}

pub unsafe fn evaluate_discrete_states<M: CoSimulation>(c: fmi3Instance) -> fmi3Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(
        component,
        Call::EvaluateDiscreteStates,
        "fmi3EvaluateDiscreteStates",
        // The tick of the active clocks, if there is one to compute (else nothing to evaluate).
        |inst| match inst.evaluate_tick("fmi3EvaluateDiscreteStates", false) {
            Ok(()) => fmi3OK,
            Err(status) => status,
        },
    )
}

const NO_CONFIGURATION: &str = "this FMU has no structural parameters, so there is no configuration mode";

/// fmi3EnterConfigurationMode of an FMU with structural parameters (one without has none: the
/// export refuses the call with the reason).
pub unsafe fn enter_configuration_mode<M: CoSimulation>(c: fmi3Instance) -> fmi3Status {
    const F: &str = "fmi3EnterConfigurationMode";
    if !const { M::DESCRIPTION.has_structural_parameters() } {
        // SAFETY: this function's contract.
        return unsafe { not_provided::<M>(c, F, NO_CONFIGURATION) };
    }
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::EnterConfigurationMode, F, |inst| {
        inst.enter_configuration_mode(F)
    })
}

/// fmi3ExitConfigurationMode.
pub unsafe fn exit_configuration_mode<M: CoSimulation>(c: fmi3Instance) -> fmi3Status {
    const F: &str = "fmi3ExitConfigurationMode";
    if !const { M::DESCRIPTION.has_structural_parameters() } {
        // SAFETY: this function's contract.
        return unsafe { not_provided::<M>(c, F, NO_CONFIGURATION) };
    }
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::ExitConfigurationMode, F, |inst| {
        inst.exit_configuration_mode(F)
    })
}

pub unsafe fn enter_step_mode<M: CoSimulation>(c: fmi3Instance) -> fmi3Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::EnterStepMode, "fmi3EnterStepMode", |inst| {
        inst.enter_step_mode()
    })
}

pub unsafe fn update_discrete_states<M: CoSimulation>(
    c: fmi3Instance,
    discrete_states_need_update: *mut fmi3Boolean,
    terminate_simulation: *mut fmi3Boolean,
    nominals_changed: *mut fmi3Boolean,
    values_changed: *mut fmi3Boolean,
    next_event_time_defined: *mut fmi3Boolean,
    next_event_time: *mut fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3UpdateDiscreteStates";
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::NewDiscreteStates, F, |inst| {
        if discrete_states_need_update.is_null()
            || terminate_simulation.is_null()
            || nominals_changed.is_null()
            || values_changed.is_null()
            || next_event_time_defined.is_null()
            || next_event_time.is_null()
        {
            return inst.error(&format!("{F}: an output argument is NULL"));
        }
        let mut e = EventInfo::default();
        let status = inst.new_discrete_states(&mut e);
        // SAFETY: none is NULL (checked above); the contract makes each writable. Written
        // through the raw pointers, which need not be distinct.
        unsafe {
            *discrete_states_need_update = e.new_discrete_states_needed;
            *terminate_simulation = e.terminate_simulation;
            *nominals_changed = e.nominals_changed;
            *values_changed = e.values_changed;
            *next_event_time_defined = e.next_event_time.is_some();
            *next_event_time = e.next_event_time.unwrap_or(0.0);
        }
        status
    })
}

pub unsafe fn completed_integrator_step<M: CoSimulation>(
    c: fmi3Instance,
    _no_set_fmu_state_prior: fmi3Boolean,
    enter_event_mode: *mut fmi3Boolean,
    terminate_simulation: *mut fmi3Boolean,
) -> fmi3Status {
    const F: &str = "fmi3CompletedIntegratorStep";
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::CompletedIntegratorStep, F, |inst| {
        if enter_event_mode.is_null() || terminate_simulation.is_null() {
            return inst.error(&format!("{F}: enterEventMode or terminateSimulation is NULL"));
        }
        let (status, event, terminate) = inst.completed_integrator_step();
        // SAFETY: neither is NULL (checked above); the contract makes both writable. Written
        // through the raw pointers, which need not be distinct.
        unsafe {
            *enter_event_mode = event;
            *terminate_simulation = terminate;
        }
        status
    })
}

pub unsafe fn set_time<M: CoSimulation>(c: fmi3Instance, time: fmi3Float64) -> fmi3Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::SetTime, "fmi3SetTime", |inst| inst.set_time(time))
}

pub unsafe fn set_continuous_states<M: CoSimulation>(c: fmi3Instance, x: *const fmi3Float64, nx: usize) -> fmi3Status {
    // SAFETY: the arguments come with this function's contract, which is the callee's.
    unsafe { shared::set_continuous_states::<M>(&TERMS, c, x, nx) }
}

pub unsafe fn get_number_of_continuous_states<M: CoSimulation>(c: fmi3Instance, n: *mut usize) -> fmi3Status {
    const F: &str = "fmi3GetNumberOfContinuousStates";
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetNumberOf, F, |inst| {
        // SAFETY: `as_mut` checks NULL; the contract makes a non-NULL `n` writable.
        match unsafe { n.as_mut() } {
            Some(n) => {
                // With the structural parameters as they are now (a sized array state).
                *n = crate::core::structural::number_of_states(&inst.sim.model);
                fmi3OK
            }
            None => inst.error(&format!("{F}: nContinuousStates is NULL")),
        }
    })
}

pub unsafe fn get_number_of_event_indicators<M: CoSimulation>(c: fmi3Instance, n: *mut usize) -> fmi3Status {
    const F: &str = "fmi3GetNumberOfEventIndicators";
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetNumberOf, F, |inst| {
        // SAFETY: `as_mut` checks NULL; the contract makes a non-NULL `n` writable.
        match unsafe { n.as_mut() } {
            Some(n) => {
                *n = M::INDICATORS.len();
                fmi3OK
            }
            None => inst.error(&format!("{F}: nEventIndicators is NULL")),
        }
    })
}

pub unsafe fn get_output_derivatives<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    orders: *const fmi3Int32,
    values: *mut fmi3Float64,
    n_values: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetOutputDerivatives";
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetRealOutputDerivatives, F, |inst| {
        // The outputs of the equations are scalars: one value per value reference.
        if n_values != nvr {
            return inst.error(&format!(
                "{F}: nValues = {n_values} for {nvr} value references: the outputs with derivatives are scalars, one value each"
            ));
        }
        // SAFETY: the arrays are NULL or nvr long (this function's contract).
        match unsafe { (slice(vr, nvr), slice(orders, nvr), slice_mut(values, nvr)) } {
            (Some(vrs), Some(orders), Some(out)) => inst.output_derivatives(F, vrs, orders, out),
            _ => inst.error(&format!(
                "{F}: valueReferences, orders or values is NULL with nValueReferences = {nvr}"
            )),
        }
    })
}

pub unsafe fn do_step<M: CoSimulation>(
    c: fmi3Instance,
    current_communication_point: fmi3Float64,
    communication_step_size: fmi3Float64,
    _no_set_fmu_state_prior_to_current_point: fmi3Boolean,
    event_handling_needed: *mut fmi3Boolean,
    terminate_simulation: *mut fmi3Boolean,
    early_return: *mut fmi3Boolean,
    last_successful_time: *mut fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3DoStep";
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::DoStep, F, |inst| {
        if event_handling_needed.is_null()
            || terminate_simulation.is_null()
            || early_return.is_null()
            || last_successful_time.is_null()
        {
            return inst.error(&format!(
                "{F}: eventHandlingNeeded, terminateSimulation, earlyReturn or lastSuccessfulTime is NULL; no step"
            ));
        }
        let status = inst.do_step(current_communication_point, communication_step_size);
        // An event to handle only with event mode and early return (the step then ends at it).
        let end = current_communication_point + communication_step_size;
        let early = (inst.step_event || inst.returned_early) && inst.sim.last_successful_time < end;
        // SAFETY: none is NULL (checked above); the contract makes each writable. Written
        // through the raw pointers, which need not be distinct.
        unsafe {
            *event_handling_needed = inst.step_event;
            *terminate_simulation = inst.sim.terminate_requested;
            *early_return = early;
            *last_successful_time = inst.sim.last_successful_time;
        }
        status
    })
}

/// What the directional and the adjoint derivative share: the instance and the state check,
/// the array lengths (`seed` has one element per known and `sensitivity` one per unknown for
/// the directional derivative, the other way round for the adjoint), the four arrays' NULL
/// checks; `compute(inst, unknowns, knowns, seed, sensitivity)` then does the function's part.
///
/// # Safety
/// The contract of fmi3GetDirectionalDerivative / fmi3GetAdjointDerivative: `c` NULL or a live
/// instance of this library for `M`; each array NULL or as long as the count beside it,
/// `sensitivity` writable.
#[inline(always)]
unsafe fn derivative<M: CoSimulation>(
    function: &'static str,
    adjoint: bool,
    c: fmi3Instance,
    (unknowns, n_unknowns): (*const fmi3ValueReference, usize),
    (knowns, n_knowns): (*const fmi3ValueReference, usize),
    (seed, n_seed): (*const fmi3Float64, usize),
    (sensitivity, n_sensitivity): (*mut fmi3Float64, usize),
    compute: impl FnOnce(&mut Instance<M>, &[u32], &[u32], &[f64], &mut [f64]) -> fmi3Status,
) -> fmi3Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, Call::GetDirectionalDerivative, function, |inst| {
        // An array counts each of its elements (FMI 3.0, 2.2.11: nSeed and nSensitivity are
        // the numbers of elements of the knowns and unknowns).
        let (n_unknown_values, n_known_values) = if const { M::DESCRIPTION.has_arrays() } {
            // SAFETY: as below.
            let count = |vrs: *const fmi3ValueReference, n: usize| match unsafe { slice(vrs, n) } {
                Some(vrs) => value_count::<M>(&inst.sim.model, vrs),
                None => n,
            };
            (count(unknowns, n_unknowns), count(knowns, n_knowns))
        } else {
            (n_unknowns, n_knowns)
        };
        let ((seed_of, n_seed_of), (sensitivity_of, n_sensitivity_of)) = if adjoint {
            (
                ("the unknowns' values", n_unknown_values),
                ("the knowns' values", n_known_values),
            )
        } else {
            (
                ("the knowns' values", n_known_values),
                ("the unknowns' values", n_unknown_values),
            )
        };
        if n_seed != n_seed_of || n_sensitivity != n_sensitivity_of {
            return inst.error(&format!(
                "{function}: nSeed = {n_seed} must equal the number of {seed_of} = {n_seed_of} and nSensitivity = \
                 {n_sensitivity} that of {sensitivity_of} = {n_sensitivity_of} (nUnknowns = {n_unknowns}, nKnowns = \
                 {n_knowns}; an array counts each element)"
            ));
        }
        // SAFETY: `slice` and `slice_mut` check NULL; the contract makes each array as long as
        // the count beside it.
        let arrays = unsafe {
            (
                slice(unknowns, n_unknowns),
                slice(knowns, n_knowns),
                slice(seed, n_seed),
                slice_mut(sensitivity, n_sensitivity),
            )
        };
        match arrays {
            (Some(unknowns), Some(knowns), Some(seed), Some(out)) => compute(inst, unknowns, knowns, seed, out),
            _ => inst.error(&format!(
                "{function}: unknowns, knowns, seed or sensitivity is NULL (nUnknowns = {n_unknowns}, nKnowns = {n_knowns})"
            )),
        }
    })
}

/// fmi3GetDirectionalDerivative: sensitivity = J seed, exact (dual numbers); in Initialization
/// Mode the InitialUnknowns' over the knowns of that mode (`core::initial_derivatives`).
pub unsafe fn get_directional_derivative<M: CoSimulation>(
    c: fmi3Instance,
    unknowns: *const fmi3ValueReference,
    n_unknowns: usize,
    knowns: *const fmi3ValueReference,
    n_knowns: usize,
    seed: *const fmi3Float64,
    n_seed: usize,
    sensitivity: *mut fmi3Float64,
    n_sensitivity: usize,
) -> fmi3Status {
    let compute = |inst: &mut Instance<M>, unknowns: &[u32], knowns: &[u32], seed: &[f64], out: &mut [f64]| {
        let mut got = vec![0.0; out.len()];
        let status = inst.directional_derivative(unknowns, knowns, seed, &mut got);
        if status == fmi3OK {
            out.copy_from_slice(&got);
        }
        status
    };
    // SAFETY: this function's contract is `derivative`'s.
    unsafe {
        derivative::<M>(
            "fmi3GetDirectionalDerivative",
            false,
            c,
            (unknowns, n_unknowns),
            (knowns, n_knowns),
            (seed, n_seed),
            (sensitivity, n_sensitivity),
            compute,
        )
    }
}

/// fmi3GetAdjointDerivative: sensitivity = Jᵀ seed, J = d unknowns / d knowns, exact: each
/// column of J from one run of the equations on dual numbers (one per known); in
/// Initialization Mode each column as fmi3GetDirectionalDerivative gives it there.
pub unsafe fn get_adjoint_derivative<M: CoSimulation>(
    c: fmi3Instance,
    unknowns: *const fmi3ValueReference,
    n_unknowns: usize,
    knowns: *const fmi3ValueReference,
    n_knowns: usize,
    seed: *const fmi3Float64,
    n_seed: usize,
    sensitivity: *mut fmi3Float64,
    n_sensitivity: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetAdjointDerivative";
    let compute = |inst: &mut Instance<M>, unknowns: &[u32], knowns: &[u32], seed: &[f64], out: &mut [f64]| {
        if let Some((i, s)) = seed.iter().enumerate().find(|(_, s)| !s.is_finite()) {
            return inst.error(&format!("{F}: seed[{i}] = {s} is not finite"));
        }
        // Element counts (an array counts each element): `derivative` checked them.
        let mut result = vec![0.0; out.len()];
        let mut unit = vec![0.0; out.len()];
        let mut column = vec![0.0; seed.len()];
        // Checks the references even when there is no known (no column is computed then).
        if knowns.is_empty() {
            let status = inst.directional_derivative(unknowns, knowns, &[], &mut column);
            if status != fmi3OK {
                return status;
            }
        }
        for j in 0..unit.len() {
            unit.fill(0.0);
            unit[j] = 1.0;
            let status = inst.directional_derivative(unknowns, knowns, &unit, &mut column);
            if status != fmi3OK {
                return status;
            }
            result[j] = column.iter().zip(seed).map(|(d, s)| d * s).sum();
        }
        out.copy_from_slice(&result);
        fmi3OK
    };
    // SAFETY: this function's contract is `derivative`'s.
    unsafe {
        derivative::<M>(
            F,
            true,
            c,
            (unknowns, n_unknowns),
            (knowns, n_knowns),
            (seed, n_seed),
            (sensitivity, n_sensitivity),
            compute,
        )
    }
}

// ---------------------------------------------------------------------------------------------
// Clocks (FMI 3.0, 2.2.9): input clocks, activated by the importer in Event Mode.

const FMI3_INTERVAL_NOT_YET_KNOWN: fmi3IntervalQualifier = 0;
const FMI3_INTERVAL_UNCHANGED: fmi3IntervalQualifier = 1;
const FMI3_INTERVAL_CHANGED: fmi3IntervalQualifier = 2;

/// The Clock declared with value reference `vr`, or the refusal naming what `vr` is.
fn clock_of<M: CoSimulation>(
    inst: &Instance<M>,
    function: &str,
    vr: u32,
) -> Result<(&'static crate::description::Variable, crate::description::ClockDecl), fmi3Status> {
    match M::variable_index(vr).map(|i| &M::DESCRIPTION.variables[i]) {
        Some(v) => match v.fmi3.clock {
            Some(c) => Ok((v, c)),
            None => Err(inst.error(&format!(
                "{function}: value reference {vr} ('{}') is {}, not a Clock",
                v.name,
                fmi3_type_name(v.var_type)
            ))),
        },
        None => Err(inst.error(&format!("{function}: value reference {vr} is no variable of this FMU"))),
    }
}

/// What every clock function does first: the instance and the state check, the value
/// references (NULL, each a Clock); `body` then does the function's part with the declarations.
///
/// # Safety
/// The clock function's contract: `c` NULL or a live instance of this library for `M`; `vr`
/// NULL or `nvr` elements.
#[inline(always)]
unsafe fn clock_call<M: CoSimulation>(
    function: &'static str,
    call: Call,
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    body: impl FnOnce(
        &mut Instance<M>,
        &[(&'static crate::description::Variable, crate::description::ClockDecl)],
    ) -> fmi3Status,
) -> fmi3Status {
    // SAFETY: `c` is NULL or a live instance of this library (this function's contract).
    let component = unsafe { Component::<M>::from_handle(c) };
    with_instance(component, call, function, |inst| {
        if !M::DESCRIPTION.has_clocks() {
            return inst.error(&format!("{function}: this FMU has no clocks"));
        }
        // SAFETY: `slice` checks NULL; the contract makes `vr` hold `nvr` elements.
        let Some(vrs) = (unsafe { slice(vr, nvr) }) else {
            return inst.error(&format!(
                "{function}: valueReferences is NULL with nValueReferences = {nvr}"
            ));
        };
        let mut clocks = Vec::with_capacity(vrs.len());
        for vr in vrs {
            match clock_of(inst, function, *vr) {
                Ok(c) => clocks.push(c),
                Err(status) => return status,
            }
        }
        body(inst, &clocks)
    })
}

/// The interval of a periodic clock now: the importer's (set in Initialization Mode), the
/// declared `intervalDecimal`, or the value of the parameter that is its interval.
fn periodic_interval<M: CoSimulation>(
    inst: &Instance<M>,
    v: &crate::description::Variable,
    c: &crate::description::ClockDecl,
) -> Option<f64> {
    let set = inst
        .sim
        .model
        .clock(v.value_reference)
        .and_then(|k| k.__importer_values().0);
    set.or(c.interval).or_else(|| {
        let p = M::DESCRIPTION.by_name(c.interval_parameter)?;
        match inst.sim.model.get(p.value_reference)? {
            Value::Real(x) => Some(x),
            _ => None,
        }
    })
}

/// The shift of a periodic clock: the importer's, else the declared `shiftDecimal`.
fn periodic_shift<M: CoSimulation>(
    inst: &Instance<M>,
    v: &crate::description::Variable,
    c: &crate::description::ClockDecl,
) -> f64 {
    inst.sim
        .model
        .clock(v.value_reference)
        .and_then(|k| k.__importer_values().1)
        .unwrap_or(c.shift)
}

pub unsafe fn set_clock<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Clock,
) -> fmi3Status {
    const F: &str = "fmi3SetClock";
    // SAFETY: the arguments come with this function's contract, which is `clock_call`'s.
    unsafe {
        clock_call::<M>(F, Call::SetClock, c, vr, nvr, |inst, clocks| {
            // SAFETY: `slice` checks NULL; the contract makes `values` hold `nvr` elements.
            let Some(values) = slice(values, nvr) else {
                return inst.error(&format!("{F}: values is NULL with nValueReferences = {nvr}"));
            };
            // Every value is checked before any clock changes (all or nothing).
            for ((v, decl), active) in clocks.iter().zip(values) {
                if v.causality != crate::description::Causality::Input {
                    return inst.error(&format!(
                        "{F}: '{}' (vr {}) is an output clock: the FMU ticks it (fmi3GetClock tells); no clock changed",
                        v.name, v.value_reference
                    ));
                }
                if inst.evaluated_tick.is_some() {
                    return inst.error(&format!(
                        "{F}: '{}' (vr {}): the tick of this Event Mode was already evaluated (a clocked variable was \
                         read, or fmi3EvaluateDiscreteStates ran): set the clocks, then the clocked inputs, then read; \
                         refused, no clock changed",
                        v.name, v.value_reference
                    ));
                }
                if !*active && !decl.can_be_deactivated {
                    return inst.error(&format!(
                        "{F}: '{}' (vr {}) cannot be deactivated (canBeDeactivated = false); no clock changed",
                        v.name, v.value_reference
                    ));
                }
                if *active && decl.interval_variability.periodic() {
                    // A periodic clock ticks at start + shift + k interval only.
                    let (t, t0) = (inst.sim.time, inst.sim.start_time + periodic_shift(inst, v, decl));
                    if let Some(h) = periodic_interval(inst, v, decl).filter(|h| h.is_finite() && *h > 0.0) {
                        let k = ((t - t0) / h).round();
                        let tol = 1e-9 * t.abs().max(h).max(1.0);
                        if k < 0.0 || (t - (t0 + k * h)).abs() > tol {
                            return inst.error(&format!(
                                "{F}: '{}' (vr {}) is activated at t = {t}, but this periodic clock ticks at {t0} + k * {h} \
                                 (its shift and interval); no clock changed",
                                v.name, v.value_reference
                            ));
                        }
                    }
                }
            }
            for ((v, _), active) in clocks.iter().zip(values) {
                if let Some(k) = inst.sim.model.clock_mut(v.value_reference) {
                    k.__set_active(*active);
                }
            }
            let t = inst.sim.time;
            inst.event(|| {
                let names: Vec<String> = clocks
                    .iter()
                    .zip(values)
                    .map(|((v, _), a)| format!("{} {}", v.name, if *a { "active" } else { "inactive" }))
                    .collect();
                format!("{F}: {} at t = {t}", names.join(", "))
            });
            fmi3OK
        })
    }
}

pub unsafe fn get_clock<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Clock,
) -> fmi3Status {
    const F: &str = "fmi3GetClock";
    // SAFETY: the arguments come with this function's contract, which is `clock_call`'s.
    unsafe {
        clock_call::<M>(F, Call::GetClock, c, vr, nvr, |inst, clocks| {
            // SAFETY: `slice_mut` checks NULL; the contract makes `values` hold `nvr` writable elements.
            let Some(out) = slice_mut(values, nvr) else {
                return inst.error(&format!("{F}: values is NULL with nValueReferences = {nvr}"));
            };
            // Whether an output clock ticks at this event is the model's update's to say: it runs
            // now if it has not (its answers are those fmi3UpdateDiscreteStates then gives).
            if clocks
                .iter()
                .any(|(v, _)| v.causality == crate::description::Causality::Output)
                && let Err(status) = inst.evaluate_tick(F, true)
            {
                return status;
            }
            for ((v, _), slot) in clocks.iter().zip(out.iter_mut()) {
                *slot = inst.sim.model.clock(v.value_reference).is_some_and(|k| k.is_active());
            }
            fmi3OK
        })
    }
}

pub unsafe fn get_interval_decimal<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    intervals: *mut fmi3Float64,
    qualifiers: *mut fmi3IntervalQualifier,
) -> fmi3Status {
    use crate::description::IntervalVariability as I;
    const F: &str = "fmi3GetIntervalDecimal";
    // SAFETY: the arguments come with this function's contract, which is `clock_call`'s.
    unsafe {
        clock_call::<M>(F, Call::GetInterval, c, vr, nvr, |inst, clocks| {
            // SAFETY: `slice_mut` checks NULL; the contract makes both hold `nvr` writable elements.
            let (Some(out), Some(qs)) = (slice_mut(intervals, nvr), slice_mut(qualifiers, nvr)) else {
                return inst.error(&format!(
                    "{F}: intervals or qualifiers is NULL with nValueReferences = {nvr}"
                ));
            };
            // Checked first: a refusal reports nothing (the reports below are taken).
            for (v, decl) in clocks {
                if decl.interval_variability == I::Triggered {
                    return inst.error(&format!(
                        "{F}: '{}' (vr {}) is a triggered clock: it has no interval (it ticks when activated)",
                        v.name, v.value_reference
                    ));
                }
                if decl.interval_variability.periodic()
                    && !periodic_interval(inst, v, decl).is_some_and(|h| h.is_finite() && h > 0.0)
                {
                    return inst.error(&format!(
                        "{F}: the interval of '{}' (vr {}) is {:?}, not a finite time > 0",
                        v.name,
                        v.value_reference,
                        periodic_interval(inst, v, decl)
                    ));
                }
                let given = inst.sim.model.clock(v.value_reference).and_then(|k| k.interval());
                if decl.interval_variability.model_timed() && given.is_some_and(|h| !(h.is_finite() && h > 0.0)) {
                    return inst.error(&format!(
                        "{F}: the model gave '{}' (vr {}) the interval {:?}, not a finite time > 0",
                        v.name, v.value_reference, given
                    ));
                }
                if decl.interval_variability == I::Changing && given.is_none() {
                    return inst.error(&format!(
                        "{F}: the model has not given the interval of changing clock '{}' (vr {}) yet",
                        v.name, v.value_reference
                    ));
                }
            }
            for (((v, decl), slot), q) in clocks.iter().zip(out.iter_mut()).zip(qs.iter_mut()) {
                let vr = v.value_reference;
                let periodic = periodic_interval(inst, v, decl);
                let Some(k) = inst.sim.model.clock_mut(vr) else {
                    continue;
                };
                (*slot, *q) = match decl.interval_variability {
                    // Declared in the description (or set by the importer): nothing to report.
                    I::Constant => (decl.interval.unwrap_or(f64::NAN), FMI3_INTERVAL_UNCHANGED),
                    I::Fixed | I::Tunable if decl.interval_parameter.is_empty() => {
                        (periodic.unwrap_or(f64::NAN), FMI3_INTERVAL_UNCHANGED)
                    }
                    // The value of a parameter: "changed" the first time and after it changed.
                    I::Fixed | I::Tunable => {
                        let h = periodic.unwrap_or(f64::NAN);
                        let changed = k.__report(h);
                        (
                            h,
                            if changed {
                                FMI3_INTERVAL_CHANGED
                            } else {
                                FMI3_INTERVAL_UNCHANGED
                            },
                        )
                    }
                    I::Changing | I::Countdown => match k.__take_interval() {
                        (Some(h), true) => (h, FMI3_INTERVAL_CHANGED),
                        (Some(h), false) => (h, FMI3_INTERVAL_UNCHANGED),
                        (None, _) => (0.0, FMI3_INTERVAL_NOT_YET_KNOWN),
                    },
                    I::Triggered => (0.0, FMI3_INTERVAL_NOT_YET_KNOWN),
                };
            }
            fmi3OK
        })
    }
}

pub unsafe fn get_shift_decimal<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    shifts: *mut fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3GetShiftDecimal";
    // SAFETY: the arguments come with this function's contract, which is `clock_call`'s.
    unsafe {
        clock_call::<M>(F, Call::GetInterval, c, vr, nvr, |inst, clocks| {
            // SAFETY: `slice_mut` checks NULL; the contract makes `shifts` hold `nvr` writable elements.
            let Some(out) = slice_mut(shifts, nvr) else {
                return inst.error(&format!("{F}: shifts is NULL with nValueReferences = {nvr}"));
            };
            for (v, decl) in clocks {
                if !decl.interval_variability.periodic() {
                    return inst.error(&format!(
                        "{F}: '{}' (vr {}) is a {} clock: only periodic clocks (constant, fixed, tunable) have a shift",
                        v.name,
                        v.value_reference,
                        decl.interval_variability.text()
                    ));
                }
            }
            for ((v, decl), slot) in clocks.iter().zip(out.iter_mut()) {
                *slot = periodic_shift(inst, v, decl);
            }
            fmi3OK
        })
    }
}

/// fmi3SetIntervalDecimal (`shift` false) and fmi3SetShiftDecimal (`shift` true): for periodic
/// clocks whose description gives a default (`intervalDecimal`) that the importer may replace:
/// a fixed clock's in Initialization Mode, a tunable clock's interval also in Event Mode.
unsafe fn set_interval_or_shift<M: CoSimulation>(
    function: &'static str,
    call: Call,
    shift: bool,
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Float64,
) -> fmi3Status {
    use crate::description::IntervalVariability as I;
    // SAFETY: the arguments come with this function's contract, which is `clock_call`'s.
    unsafe {
        clock_call::<M>(function, call, c, vr, nvr, |inst, clocks| {
            // SAFETY: `slice` checks NULL; the contract makes `values` hold `nvr` elements.
            let Some(values) = slice(values, nvr) else {
                return inst.error(&format!("{function}: values is NULL with nValueReferences = {nvr}"));
            };
            let what = if shift { "shift" } else { "interval" };
            for ((v, decl), x) in clocks.iter().zip(values) {
                let settable = matches!(decl.interval_variability, I::Fixed | I::Tunable) && decl.interval.is_some();
                if !settable {
                    let why = if !decl.interval_parameter.is_empty() {
                        format!("its interval is the parameter '{}': set that", decl.interval_parameter)
                    } else {
                        format!(
                            "only fixed and tunable clocks with an intervalDecimal take one from the importer ('{}' is {})",
                            v.name,
                            decl.interval_variability.text()
                        )
                    };
                    return inst.error(&format!(
                        "{function}: '{}' (vr {}): {why}; nothing changed",
                        v.name, v.value_reference
                    ));
                }
                if matches!(inst.sim.state, State::EventMode | State::ClockActivationMode)
                    && (shift || decl.interval_variability == I::Fixed)
                {
                    return inst.error(&format!(
                        "{function}: '{}' (vr {}): a {} clock's {what} is set in Initialization Mode only; nothing changed",
                        v.name,
                        v.value_reference,
                        decl.interval_variability.text()
                    ));
                }
                let ok = if shift {
                    x.is_finite() && *x >= 0.0
                } else {
                    x.is_finite() && *x > 0.0
                };
                if !ok {
                    return inst.error(&format!(
                        "{function}: {x} for '{}' (vr {}): a {what} is a finite time {}; nothing changed",
                        v.name,
                        v.value_reference,
                        if shift { ">= 0" } else { "> 0" }
                    ));
                }
            }
            for ((v, _), x) in clocks.iter().zip(values) {
                if let Some(k) = inst.sim.model.clock_mut(v.value_reference) {
                    let (interval, s) = k.__set_by_importer();
                    *(if shift { s } else { interval }) = Some(*x);
                }
            }
            fmi3OK
        })
    }
}

pub unsafe fn set_interval_decimal<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    intervals: *const fmi3Float64,
) -> fmi3Status {
    // SAFETY: the arguments come with this function's contract, which is the callee's.
    unsafe {
        set_interval_or_shift::<M>(
            "fmi3SetIntervalDecimal",
            Call::SetInterval,
            false,
            c,
            vr,
            nvr,
            intervals,
        )
    }
}

pub unsafe fn set_shift_decimal<M: CoSimulation>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    shifts: *const fmi3Float64,
) -> fmi3Status {
    // SAFETY: the arguments come with this function's contract, which is the callee's.
    unsafe { set_interval_or_shift::<M>("fmi3SetShiftDecimal", Call::SetShift, true, c, vr, nvr, shifts) }
}
