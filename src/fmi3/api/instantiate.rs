//! The three instantiation functions of FMI 3.0 (model exchange, co-simulation, Scheduled
//! Execution): the checks of the importer's arguments, then the instance.
//!
//! # Safety
//! As for [`super`]: every `unsafe fn` has the contract of the `fmi3*` function it implements.

use super::*;

/// `resourcePath`: a native absolute path of the unpacked `resources/` folder (FMI 3.0 2.2.4),
/// usually with a trailing separator.
fn resource_dir(path: &str) -> Option<std::path::PathBuf> {
    let p = std::path::PathBuf::from(path);
    p.is_absolute().then_some(p)
}

/// What every instantiation function is given: this binary's token and embedded description
/// (from `export_fmi3!`), and the importer's arguments the three functions share.
#[derive(Clone, Copy)]
pub struct Instantiation {
    pub own_token: &'static str,
    pub description: &'static [u8],
    pub instance_name: fmi3String,
    pub token: fmi3String,
    pub resource_path: fmi3String,
    pub logging_on: fmi3Boolean,
    pub environment: fmi3InstanceEnvironment,
    pub log_message: fmi3LogMessageCallback,
}

/// The three instantiation functions: checks, then the instance.
///
/// # Safety
/// The strings of `given` are NULL or NUL-terminated (the instantiation function's contract).
unsafe fn instantiate<M: CoSimulation>(
    function: &str,
    given: Instantiation,
    model_exchange: bool,
    refusal: Option<String>,
    warning: Option<String>,
    event_mode: (bool, bool),
    intermediate_update: Option<Box<dyn FnMut(f64) -> Option<f64>>>,
    scheduled: Option<Option<std::rc::Rc<dyn Fn()>>>,
) -> fmi3Instance {
    let Instantiation {
        own_token,
        description,
        instance_name,
        token,
        resource_path,
        logging_on,
        environment,
        log_message,
    } = given;
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
        let serialized = scheduled.is_some();
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
        Component::into_handle(inst, serialized)
    }));
    made.unwrap_or(ptr::null_mut())
}

pub unsafe fn instantiate_model_exchange<M: CoSimulation>(given: Instantiation) -> fmi3Instance {
    // SAFETY: the strings come with this function's contract, which is `instantiate`'s.
    unsafe {
        instantiate::<M>(
            "fmi3InstantiateModelExchange",
            given,
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
    given: Instantiation,
    event_mode_used: fmi3Boolean,
    early_return_allowed: fmi3Boolean,
    required_intermediate_variables: *const fmi3ValueReference,
    n_required_intermediate_variables: usize,
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
    let (can_return_early, environment) = (early_return_allowed, given.environment);
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
            given,
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
    given: Instantiation,
    clock_update: fmi3ClockUpdateCallback,
) -> fmi3Instance {
    let environment = given.environment;
    if !M::SCHEDULED_EXECUTION {
        let _ = catch_unwind(AssertUnwindSafe(|| {
            // SAFETY: a NUL-terminated string from the importer, or NULL.
            let name = unsafe { text(given.instance_name) };
            let logger = Logger::new(
                Callback::Message(given.log_message),
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
            given,
            false,
            None,
            None,
            (false, false),
            None,
            Some(notify),
        )
    }
}
