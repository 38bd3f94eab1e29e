//! One FMU instance of either FMI version: the state check, argument checks, and the calls into
//! the model, worded in the instance's [`Terms`]. Safe Rust: the C boundary (pointers, panics)
//! is in [`super::guard`] and the C layers.

use super::logging::{Category, Logger};
use super::machine::{Call, State, contains, state_names};
use super::{DISCARD, ERROR, FATAL, Function, OK, Status, Terms, Version, WARNING};
use crate::description::{Causality, Initial, VarType, Variability, Variable};
use crate::model::{CoSimulation, Context, EventClock, ReturnAtEvents, StateVector};
use crate::solver::Dopri5;
use crate::step::{evaluate, non_finite, oversized_binary};
use crate::value::{FmiType, Value};
use serde::{Deserialize, Serialize};
use std::ffi::CString;

/// Everything an FMU state snapshot holds: the model and the runtime's own bookkeeping.
/// The logger and the importer's callbacks are not part of it.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Sim<M> {
    pub state: State,
    pub model: M,
    pub start_time: f64,
    pub stop_time: Option<f64>,
    pub tolerance: Option<f64>,
    pub time: f64,
    pub last_successful_time: f64,
    pub terminate_requested: bool,
    /// Calculated variables are stale in initialization mode after a set.
    pub init_dirty: bool,
    /// The co-simulation integrator's memory (step size, error history).
    pub solver: Dopri5,
    /// The pending time event, the initial event iteration, the event count.
    pub events: EventClock,
    /// Something the derivatives depend on (a state, an input, time, a parameter) changed
    /// since they were computed. A cache flag, not part of the serialized state (a restored
    /// state recomputes on demand).
    #[serde(skip, default = "stale")]
    pub stale_derivatives: bool,
    /// ... and the outputs and locals the equations compute.
    #[serde(skip, default = "stale")]
    pub stale_outputs: bool,
}

fn stale() -> bool {
    true
}

impl<M: CoSimulation> Sim<M> {
    pub fn new() -> Self {
        Sim {
            state: State::Instantiated,
            model: M::start(),
            start_time: 0.0,
            stop_time: None,
            tolerance: None,
            time: 0.0,
            last_successful_time: 0.0,
            terminate_requested: false,
            init_dirty: true,
            solver: Dopri5::default(),
            events: EventClock::default(),
            stale_derivatives: true,
            stale_outputs: true,
        }
    }
}

impl<M: CoSimulation> Default for Sim<M> {
    fn default() -> Self {
        Self::new()
    }
}

pub struct Instance<M: CoSimulation> {
    pub logger: Logger,
    pub guid: &'static str,
    pub sim: Sim<M>,
    /// Instantiated for model exchange (else co-simulation).
    pub model_exchange: bool,
    /// The derivatives the get-derivatives function computed last (valid while `!sim.stale_derivatives`):
    /// it computes only those, and leaves the model's `der(..)` variables to the next full
    /// evaluation.
    derivatives: M::States,
    /// The model as it was before the step in progress, to go back to when the step leaves
    /// something that is not finite. Kept here so that a step does not allocate a copy.
    before_step: M,
    /// What the get-string function last returned: valid until the next call, as the standard
    /// allows.
    strings: Vec<CString>,
    /// What the last fmi3GetBinary returned, valid until the next call.
    binaries: Vec<Vec<u8>>,
    /// The unpacked `resources/` folder, from `fmuResourceLocation` (not part of the FMU state).
    pub resources: Option<std::path::PathBuf>,
    /// The words of the FMI version this instance was instantiated through; its
    /// `version` picks the state table.
    pub terms: &'static Terms,
    /// `terms.version`, kept here: the state check reads it on every call.
    pub version: Version,
    /// FMI 3.0 co-simulation with event mode (`eventModeUsed`): the importer handles the events
    /// in Event Mode (fmi3EnterEventMode, fmi3UpdateDiscreteStates, fmi3EnterStepMode).
    pub event_mode_used: bool,
    /// ... and `earlyReturnAllowed`: fmi3DoStep returns at an event inside the step.
    pub early_return_allowed: bool,
    /// The last step ended at an event the importer is to handle (fmi3DoStep's
    /// `eventHandlingNeeded`).
    pub step_event: bool,
    /// FMI 3.0 co-simulation's intermediate update: the importer's callback, called by the
    /// runtime's integrator at the end of each accepted internal step; `Some(t_r)` when the
    /// importer asked to return early at `t_r` (only where it may: earlyReturnAllowed).
    pub intermediate_update: Option<Box<dyn FnMut(f64) -> Option<f64>>>,
    /// The last step returned early, as the importer asked in the intermediate update.
    pub returned_early: bool,
    /// FMI 3.0 clocks: the tick of the clocks active in this Event Mode was evaluated before
    /// fmi3UpdateDiscreteStates (a clocked variable was read, or fmi3EvaluateDiscreteStates
    /// ran): the event round's answers, which fmi3UpdateDiscreteStates then gives.
    pub evaluated_tick: Option<EventInfo>,
    /// ... and the model and its event clock before that evaluation: an FMU state taken until
    /// fmi3UpdateDiscreteStates is this one (restored, the tick is evaluated again, once).
    tick_before: Option<Box<(M, EventClock)>>,
    /// FMI 2.0 input derivatives (fmi2SetRealInputDerivatives, first order): (input's value
    /// reference, du/dt). The runtime's integrator makes each input u + du (t - t_c) over a
    /// step from t_c and leaves it at u + du h; a derivative holds until it is set again (0 ends
    /// it) or fmi2Reset, whatever order the importer sets values and derivatives in.
    pub input_slopes: Vec<(u32, f64)>,
    /// The state fmi3EnterConfigurationMode was called in (fmi3ExitConfigurationMode returns to it).
    pub(crate) reconfigured_from: State,
    /// The model before the first structural parameter of a reconfiguration was set.
    pub(crate) before_configuration: Option<Box<M>>,
    /// FMI 3.0 Scheduled Execution (fmi3InstantiateScheduledExecution): Clock Activation Mode
    /// after initialization, partitions activated with fmi3ActivateModelPartition; the
    /// model-exchange and co-simulation functions are refused.
    pub scheduled: bool,
    /// ... and the importer's clockUpdate callback, if it gave one: called by the C layer after
    /// an activation that ticked an output clock or gave a countdown clock its interval, once the
    /// call has left the instance (the importer calls back into it from the callback).
    pub clock_update: Option<std::rc::Rc<dyn Fn()>>,
}

/// Whether one of `vrs` is an array variable (then each has its element count of values). A
/// model without arrays answers at compile time; one with arrays looks at the references, so
/// a call on scalars only keeps the scalar paths (no allocation: the Controller's hot path).
#[inline]
fn any_array<M: CoSimulation>(vrs: &[u32]) -> bool {
    let has_arrays = const { M::DESCRIPTION.has_arrays() };
    has_arrays
        && vrs
            .iter()
            .any(|vr| M::variable_index(*vr).is_some_and(|i| M::DESCRIPTION.variables[i].is_array()))
}

/// Whether an FMI 2.0 call names an element of an array (FMI 2.0 has no arrays: an array is its
/// elements there, `K[1,1]` .. with the value references vr, vr + 1, ..). A model without
/// arrays in its FMI 2.0 description answers at compile time; one with them looks up each
/// reference, so calls on scalars keep the scalar paths.
#[inline]
fn any_fmi2_element<M: CoSimulation>(version: Version, vrs: &[u32]) -> bool {
    let has_fmi2_arrays = const { M::DESCRIPTION.has_fmi2_arrays() };
    has_fmi2_arrays
        && version == Version::Fmi2
        && vrs.iter().any(|vr| match M::variable_index(*vr) {
            Some(i) => M::DESCRIPTION.variables[i].is_array(),
            None => M::DESCRIPTION.fmi2_element(*vr).is_some(),
        })
}

/// "an Int32", "a Float64", "an Enumeration" (as the type names are read aloud).
fn with_article(name: &str) -> String {
    let article = if name.starts_with(['I', 'E']) { "an" } else { "a" };
    format!("{article} {name}")
}

type Outcome = Result<(), Status>;

/// A model's [`Context::log`](crate::Context::log) goes to the importer's logger.
impl crate::model::Log for Logger {
    fn wants_named(&self, category: &str) -> bool {
        Logger::wants_named(self, category)
    }
    fn log_named(&self, category: &str, message: &str) {
        Logger::log_named(self, category, message)
    }
}

impl<M: CoSimulation> Instance<M> {
    pub fn new(terms: &'static Terms, logger: Logger, guid: &'static str, model_exchange: bool) -> Self {
        Instance {
            logger,
            guid,
            sim: Sim::new(),
            model_exchange,
            derivatives: <M::States as StateVector>::zeros(),
            before_step: M::start(),
            strings: Vec::new(),
            binaries: Vec::new(),
            resources: None,
            terms,
            version: terms.version,
            event_mode_used: false,
            evaluated_tick: None,
            tick_before: None,
            input_slopes: Vec::new(),
            reconfigured_from: State::Instantiated,
            before_configuration: None,
            early_return_allowed: false,
            step_event: false,
            intermediate_update: None,
            returned_early: false,
            scheduled: false,
            clock_update: None,
        }
    }

    pub fn state(&self) -> State {
        self.sim.state
    }

    pub fn model(&self) -> &M {
        &self.sim.model
    }

    pub fn error(&self, message: &str) -> Status {
        self.logger.log(ERROR, Category::StatusError, message);
        ERROR
    }

    pub fn event(&self, message: impl FnOnce() -> String) {
        if self.logger.wants(OK, Category::Events) {
            self.logger.log(OK, Category::Events, &message());
        }
    }

    pub fn trace(&self, message: impl FnOnce() -> String) {
        if self.logger.wants(OK, Category::Calls) {
            self.logger.log(OK, Category::Calls, &message());
        }
    }

    /// A panic was caught at the boundary: nothing about this instance can be trusted any more.
    pub fn fatal(&mut self, function: &str, what: &str) {
        self.sim.state = State::Fatal;
        self.logger.log(
            FATAL,
            Category::StatusFatal,
            &format!("{function}: internal error ({what}); this instance can only be freed"),
        );
    }

    /// The one place where the state machine is enforced.
    #[inline(always)]
    pub fn check_state(&self, call: Call, function: &str) -> Outcome {
        let right_interface = match call.interface() {
            Some(model_exchange) => {
                !self.scheduled && (model_exchange == self.model_exchange || self.cs_event_mode_call(call))
            }
            None => true,
        } && (call != Call::EnterStepMode || self.event_mode_used)
            && (call != Call::ActivateModelPartition || self.scheduled);
        if right_interface && contains(call.allowed(self.version), self.sim.state) {
            return Ok(());
        }
        Err(self.refuse_call(call, function))
    }

    /// The calls of Event Mode that an FMI 3.0 co-simulation instance with event mode makes too.
    #[inline]
    fn cs_event_mode_call(&self, call: Call) -> bool {
        self.event_mode_used && matches!(call, Call::EnterEventMode | Call::NewDiscreteStates)
    }

    /// Why `call` is refused here, logged.
    #[cold]
    fn refuse_call(&self, call: Call, function: &str) -> Status {
        let interface = || {
            if self.scheduled {
                "scheduled execution"
            } else if self.model_exchange {
                "model exchange"
            } else {
                "co-simulation"
            }
        };
        if self.scheduled
            && let Some(model_exchange) = call.interface()
        {
            return self.error(&format!(
                "{function} is a {} function; this instance was instantiated for scheduled execution \
                 (fmi3InstantiateScheduledExecution: partitions are activated with fmi3ActivateModelPartition)",
                if model_exchange {
                    "model-exchange"
                } else {
                    "co-simulation"
                }
            ));
        }
        if call == Call::ActivateModelPartition && !self.scheduled {
            return self.error(&format!(
                "{function} is a scheduled-execution function; this instance was instantiated for {}",
                interface()
            ));
        }
        if self.scheduled && call == Call::SetClock {
            return self.error(&format!(
                "{function}: in scheduled execution the importer activates an input clock with \
                 fmi3ActivateModelPartition (state {})",
                self.terms.state_name(self.sim.state)
            ));
        }
        if !self.model_exchange
            && !self.event_mode_used
            && self.version == Version::Fmi3
            && matches!(
                call,
                Call::EnterEventMode | Call::NewDiscreteStates | Call::EnterStepMode
            )
        {
            return self.error(&format!(
                "{function} is for co-simulation with event mode: this instance was made with eventModeUsed = false"
            ));
        }
        if let Some(model_exchange) = call.interface()
            && model_exchange != self.model_exchange
        {
            return self.error(&format!(
                "{function} is a {} function; this instance was instantiated for {}",
                if model_exchange {
                    "model-exchange"
                } else {
                    "co-simulation"
                },
                if self.model_exchange {
                    "model exchange"
                } else {
                    "co-simulation"
                }
            ));
        }
        let allowed = call.allowed(self.terms.version);
        self.error(&format!(
            "{function} is not allowed in state {} (allowed in: {})",
            self.terms.state_name(self.sim.state),
            state_names(self.terms, allowed)
        ))
    }

    pub fn set_debug_logging(&mut self, function: &str, logging_on: bool, categories: &[String]) -> Status {
        let mut known = Vec::with_capacity(categories.len());
        for name in categories {
            match self.logger.category_index(name) {
                Some(c) => known.push(c),
                None => {
                    return self.error(&format!(
                        "{function}: unknown log category '{name}' (declared: {})",
                        self.logger.category_names().join(", ")
                    ));
                }
            }
        }
        self.logger.set_debug_logging(logging_on, &known);
        OK
    }

    pub fn setup_experiment(&mut self, tolerance: Option<f64>, start: f64, stop: Option<f64>) -> Status {
        let f = self.terms.name(Function::SetupExperiment);
        if !start.is_finite() {
            return self.error(&format!("{f}: startTime = {start} is not finite"));
        }
        if let Some(tol) = tolerance
            && !(tol.is_finite() && tol > 0.0)
        {
            return self.error(&format!("{f}: tolerance = {tol} must be finite and > 0"));
        }
        if let Some(stop) = stop
            && !(stop.is_finite() && stop >= start)
        {
            return self.error(&format!(
                "{f}: stopTime = {stop} must be finite and not before startTime = {start}"
            ));
        }
        self.sim.tolerance = tolerance;
        self.sim.start_time = start;
        self.sim.stop_time = stop;
        self.sim.time = start;
        self.sim.last_successful_time = start;
        OK
    }

    pub fn enter_initialization_mode(&mut self) -> Status {
        self.sim.state = State::InitializationMode;
        self.sim.init_dirty = true;
        OK
    }

    /// Brings the calculated variables up to date with what was set in initialization mode
    /// (always when `force`, else only if something was set since). All or nothing: when the
    /// model refuses, it is put back as it was, so a call answering ERROR changes nothing.
    fn initialize_model(&mut self, function: &str, force: bool) -> Outcome {
        if !force && !self.sim.init_dirty {
            return Ok(());
        }
        let before = self.sim.model.clone();
        let ctx = Context::outside_step(
            self.sim.start_time,
            self.sim.tolerance,
            Some(&self.logger),
            self.resources.as_deref(),
            self.model_exchange,
        );
        let outcome = self
            .sim
            .model
            .initialize(&ctx)
            .map(|()| evaluate(&mut self.sim.model, self.sim.start_time))
            .and_then(
                |()| match non_finite(&self.sim.model).or_else(|| oversized_binary(&self.sim.model)) {
                    None => Ok(()),
                    Some(what) => Err(format!("{what} (computed from the start values and parameters)")),
                },
            );
        match outcome {
            Ok(()) => {
                self.sim.init_dirty = false;
                self.sim.stale_derivatives = false;
                self.sim.stale_outputs = false;
                Ok(())
            }
            Err(message) => {
                self.sim.model = before;
                Err(self.error(&format!("{function}: initialization failed: {message}")))
            }
        }
    }

    pub fn exit_initialization_mode(&mut self) -> Status {
        // All or nothing: a refused initial event leaves the instance as the call found it.
        let before = (!self.model_exchange).then(|| self.sim.clone());
        if let Err(status) = self.initialize_model(self.terms.name(Function::ExitInitializationMode), true) {
            return status;
        }
        self.sim.time = self.sim.start_time;
        self.sim.last_successful_time = self.sim.start_time;
        self.sim.events = EventClock {
            initial: true,
            ..EventClock::default()
        };
        if self.scheduled {
            // Scheduled Execution: no event iteration at the start; the partitions run when the
            // importer activates them.
            self.sim.events.initial = false;
            self.sim.state = State::ClockActivationMode;
            self.event(|| format!("initialized at t = {}: Clock Activation Mode", self.sim.start_time));
            return OK;
        }
        if !self.model_exchange && !self.event_mode_used {
            // Co-simulation without event mode: the event iteration at the start runs here
            // (Model Exchange and FMI 3.0's event mode: the importer's first
            // new-discrete-states calls), all or nothing.
            let f = self.terms.name(Function::ExitInitializationMode);
            let mut info = EventInfo::default();
            let status = self.event_iteration(f, &mut info, true);
            self.sim.events.initial = false;
            if status != OK {
                if let Some(before) = before {
                    self.sim = before;
                }
                return status;
            }
            if info.terminate_simulation {
                self.sim.terminate_requested = true;
            }
        }
        self.sim.state = if self.model_exchange || self.event_mode_used {
            State::EventMode
        } else {
            State::StepComplete
        };
        self.sim.solver.restart();
        self.event(|| format!("initialized at t = {}", self.sim.start_time));
        OK
    }

    pub fn terminate(&mut self) -> Status {
        self.sim.state = State::Terminated;
        self.event(|| format!("terminated at t = {}", self.sim.time));
        OK
    }

    pub fn reset(&mut self) -> Status {
        self.sim = Sim::new();
        self.input_slopes.clear();
        self.evaluated_tick = None;
        self.tick_before = None;
        self.event(|| "reset: every variable is back at its start value".into());
        OK
    }

    /// A type's name in this instance's FMI version (2.0's `Real`, 3.0's `Float64`).
    fn type_name(&self, ty: VarType) -> String {
        match self.terms.version {
            Version::Fmi2 => format!("{ty:?}"),
            Version::Fmi3 => ty.fmi3_name().to_string(),
        }
    }

    /// The declaration of `vr` as a variable of C API type `ty`, or the logged refusal. (The
    /// found case is inlined into every getter and setter; the refusal's message is not.)
    #[inline]
    fn lookup(&self, function: &str, vr: u32, ty: VarType) -> Result<&'static Variable, Status> {
        // Only a model with FMI-3.0-only variables has declarations the 2.0 functions must not see.
        let fmi3_only = const { M::DESCRIPTION.has_fmi3_only() };
        if let Some(v) = M::declaration(vr, ty)
            && (!fmi3_only || self.terms.version != Version::Fmi2 || v.in_version(crate::description::FmiVersion::V2))
        {
            return Ok(v);
        }
        Err(self.lookup_refusal(function, vr, ty))
    }

    #[cold]
    #[inline(never)]
    fn lookup_refusal(&self, function: &str, vr: u32, ty: VarType) -> Status {
        let fmi2 = self.terms.version == Version::Fmi2;
        match M::variable_index(vr).map(|i| &M::DESCRIPTION.variables[i]) {
            Some(other) if fmi2 && !other.in_version(crate::description::FmiVersion::V2) => self.error(&format!(
                "{function}: value reference {vr} is not a variable of {} in FMI 2.0 ('{}' is a {} variable of its FMI 3.0 description only)",
                M::DESCRIPTION.model_identifier,
                other.name,
                other.var_type.fmi3_name()
            )),
            Some(other) => self.error(&format!(
                "{function}: value reference {vr} ('{}') is {} variable, not {}",
                other.name,
                with_article(&self.type_name(other.var_type)),
                with_article(&self.type_name(ty))
            )),
            None => self.error(&format!(
                "{function}: value reference {vr} is not {} variable of {} (see modelDescription.xml)",
                with_article(&self.type_name(ty)),
                M::DESCRIPTION.model_identifier
            )),
        }
    }

    pub fn get_values<T: FmiType>(&mut self, function: &str, vrs: &[u32], out: &mut [T]) -> Status {
        if any_fmi2_element::<M>(self.version, vrs) {
            return self.get_fmi2_elements(function, vrs, out);
        }
        // A clock's tick first (whether a variable is readable depends on it), then every
        // reference is checked before anything is computed: a refused get changes nothing.
        if let Err(status) = self.evaluate_tick_for(function, vrs) {
            return status;
        }
        for vr in vrs {
            if let Err(status) = self
                .lookup(function, *vr, T::TYPE)
                .and_then(|v| self.check_gettable(function, v))
            {
                return status;
            }
        }
        if let Err(status) = self.up_to_date(function) {
            return status;
        }
        if any_array::<M>(vrs) {
            return self.get_with_arrays(function, vrs, out);
        }
        for (vr, slot) in vrs.iter().zip(out.iter_mut()) {
            // The independent variable is the instance's time, whatever the model's field holds.
            let value = match M::declaration(*vr, T::TYPE) {
                Some(d) if d.causality == Causality::Independent => Some(Value::Real(self.sim.time)),
                _ => self.sim.model.get(*vr),
            };
            match value.and_then(T::from_value) {
                Some(v) => *slot = v,
                None => return self.error(&format!("{function}: value reference {vr} has no {:?} value", T::TYPE)),
            }
        }
        OK
    }

    /// FMI 2.0's view of an array variable: value reference `vr + k` is its element `k`
    /// (row-major), a scalar named `name[i,j]`; any other reference is looked up as usual. The
    /// declaration, and the element if it is one.
    fn fmi2_resolve(&self, function: &str, vr: u32, ty: VarType) -> Result<(&'static Variable, Option<usize>), Status> {
        if let Some((i, k)) = M::DESCRIPTION.fmi2_element(vr) {
            let d = &M::DESCRIPTION.variables[i];
            if crate::description::same_api_type(d.var_type, ty) {
                return Ok((d, Some(k)));
            }
            return Err(self.error(&format!(
                "{function}: value reference {vr} ('{}') is {} variable, not {}",
                d.element_name(k),
                with_article(&self.type_name(d.var_type)),
                with_article(&self.type_name(ty))
            )));
        }
        self.lookup(function, vr, ty).map(|d| (d, None))
    }

    /// [`Instance::get_values`] of an FMI 2.0 call that names array elements.
    #[cold]
    fn get_fmi2_elements<T: FmiType>(&mut self, function: &str, vrs: &[u32], out: &mut [T]) -> Status {
        for vr in vrs {
            if let Err(status) = self
                .fmi2_resolve(function, *vr, T::TYPE)
                .and_then(|(d, k)| self.check_gettable_as(function, d, k))
            {
                return status;
            }
        }
        if let Err(status) = self.up_to_date(function) {
            return status;
        }
        for (vr, slot) in vrs.iter().zip(out.iter_mut()) {
            let (d, element) = match self.fmi2_resolve(function, *vr, T::TYPE) {
                Ok(found) => found,
                Err(status) => return status,
            };
            let value = match element {
                Some(k) => self.sim.model.get_element(d.value_reference, k),
                None if d.causality == Causality::Independent => Some(Value::Real(self.sim.time)),
                None => self.sim.model.get(*vr),
            };
            match value.and_then(T::from_value) {
                Some(v) => *slot = v,
                None => return self.error(&format!("{function}: value reference {vr} has no {:?} value", T::TYPE)),
            }
        }
        OK
    }

    /// [`Instance::set_value_list`] of an FMI 2.0 call that names array elements: all or none.
    #[cold]
    fn set_fmi2_elements(&mut self, function: &str, vrs: &[u32], values: &[Value]) -> Status {
        let mut parameter_changed = false;
        for (vr, value) in vrs.iter().zip(values) {
            let (decl, element) = match self.fmi2_resolve(function, *vr, value.api_type()) {
                Ok(found) => found,
                Err(status) => return status,
            };
            if let Err(status) = self.check_settable_as(function, decl, element) {
                return status;
            }
            let (name, element_vr) = Self::name_and_vr(decl, element);
            match refusal_as(&self.sim.model, decl, *value, &name, element_vr) {
                None => {}
                Some(Refusal::Rule(why)) => {
                    return self.error(&format!("{function}: {why}; refused, value unchanged"));
                }
                Some(Refusal::Model(why)) => return self.error(&format!("{function}: {why}")),
            }
            parameter_changed |= decl.causality == Causality::Parameter;
        }
        let previous = (parameter_changed && self.between_steps()).then(|| self.sim.model.clone());
        for (vr, value) in vrs.iter().zip(values) {
            match M::DESCRIPTION.fmi2_element(*vr) {
                Some((i, k)) => {
                    self.sim
                        .model
                        .set_element(M::DESCRIPTION.variables[i].value_reference, k, *value);
                }
                None => {
                    self.sim.model.set(*vr, *value);
                }
            }
        }
        self.after_set(function, previous)
    }

    /// [`Instance::get_values`] of a model with array variables: each array's elements in
    /// row-major order, one after the other (`out` holds the sum of the element counts; the
    /// FMI 3.0 layer checked nValues).
    fn get_with_arrays<T: FmiType>(&mut self, function: &str, vrs: &[u32], out: &mut [T]) -> Status {
        let mut at = 0;
        for vr in vrs {
            let Some(d) = M::declaration(*vr, T::TYPE) else {
                return self.error(&format!("{function}: value reference {vr} has no {:?} value", T::TYPE));
            };
            let n = crate::step::structural::element_count(&self.sim.model, d);
            let Some(slots) = out.get_mut(at..at + n) else {
                return self.error(&format!(
                    "{function}: the values array ends before the elements of '{}'",
                    d.name
                ));
            };
            for (i, slot) in slots.iter_mut().enumerate() {
                let value = if d.causality == Causality::Independent {
                    Some(Value::Real(self.sim.time))
                } else if d.is_array() {
                    let k = crate::step::structural::storage_index(&self.sim.model, d, i);
                    self.sim.model.get_element(*vr, k)
                } else {
                    self.sim.model.get(*vr)
                };
                match value.and_then(T::from_value) {
                    Some(v) => *slot = v,
                    None => {
                        return self.error(&format!(
                            "{function}: '{}' has no {:?} value at element {i}",
                            d.name,
                            T::TYPE
                        ));
                    }
                }
            }
            at += n;
        }
        OK
    }

    /// The get-string function: the returned pointers stay valid until the next call on this
    /// instance.
    pub fn get_strings(&mut self, vrs: &[u32], out: &mut [*const std::os::raw::c_char]) -> Status {
        let f = self.terms.name(Function::GetString);
        // A clock's tick first (as in `get_values`), then the checks.
        if let Err(status) = self.evaluate_tick_for(f, vrs) {
            return status;
        }
        for vr in vrs {
            if let Err(status) = self
                .lookup(f, *vr, VarType::String)
                .and_then(|v| self.check_gettable(f, v))
            {
                return status;
            }
        }
        if let Err(status) = self.up_to_date(f) {
            return status;
        }
        self.strings.clear();
        for vr in vrs {
            let text = self.sim.model.get_string(*vr).unwrap_or_default();
            self.strings.push(super::logging::to_cstring(text));
        }
        for (slot, s) in out.iter_mut().zip(&self.strings) {
            *slot = s.as_ptr();
        }
        OK
    }

    pub fn set_strings(&mut self, vrs: &[u32], values: &[String]) -> Status {
        let f = self.terms.name(Function::SetString);
        let mut parameter_changed = false;
        for vr in vrs {
            let decl = match self.lookup(f, *vr, VarType::String) {
                Ok(d) => d,
                Err(status) => return status,
            };
            if let Err(status) = self.check_settable(f, decl) {
                return status;
            }
            parameter_changed |= decl.causality == Causality::Parameter;
        }
        let previous = (parameter_changed && self.between_steps()).then(|| self.sim.model.clone());
        for (vr, v) in vrs.iter().zip(values) {
            self.sim.model.set_string(*vr, v);
        }
        self.after_set(f, previous)
    }

    /// Before initialization (FMI 3.0's Instantiated; FMI 2.0 allows no get there) a variable has
    /// a value only if the description gives it a start value: an input, or initial exact or
    /// approx. A calculated variable is computed from the start values during initialization,
    /// so reading it here is refused rather than answered with a number that means nothing.
    fn check_gettable(&self, function: &str, decl: &Variable) -> Outcome {
        self.check_gettable_as(function, decl, None)
    }

    /// [`Instance::check_gettable`] of a variable, or of element `k` of an array in FMI 2.0
    /// (the message names the element and its value reference).
    fn check_gettable_as(&self, function: &str, decl: &Variable, element: Option<usize>) -> Outcome {
        if M::DESCRIPTION.has_clocks() && decl.is_clocked() {
            self.clocked_access(function, decl, false)?;
        }
        if !matches!(self.sim.state, State::Instantiated | State::ConfigurationMode) || decl.has_start() {
            return Ok(());
        }
        let (name, vr) = Self::name_and_vr(decl, element);
        Err(self.error(&format!(
            "{function}: '{name}' (vr {vr}, causality {:?}, initial calculated) has no value before initialization: \
             in state Instantiated only start values can be read (inputs, initial exact or approx)",
            decl.causality
        )))
    }

    /// Whether the Clock named `name` is active.
    fn clock_active(&self, name: &str) -> bool {
        M::DESCRIPTION
            .by_name(name)
            .and_then(|c| self.sim.model.clock(c.value_reference))
            .is_some_and(|c| c.is_active())
    }

    /// Whether some Clock is active.
    pub fn any_clock_active(&self) -> bool {
        M::DESCRIPTION
            .variables
            .iter()
            .filter(|v| v.fmi3.clock.is_some())
            .any(|v| self.sim.model.clock(v.value_reference).is_some_and(|c| c.is_active()))
    }

    /// FMI 3.0, 2.2.9: "setting and getting of clocked variables is only allowed during Event
    /// Mode when their respective Clocks are active, and during Initialization Mode irrespective
    /// of Clock activation status" (and their start values before). A clocked input is set
    /// before the tick is evaluated: the first read of a clocked variable (or
    /// fmi3EvaluateDiscreteStates) computes the tick from the inputs set until then.
    fn clocked_access(&self, function: &str, decl: &Variable, setting: bool) -> Outcome {
        let clocks = decl.fmi3.clocks;
        let names = || clocks.iter().map(|c| format!("'{c}'")).collect::<Vec<_>>().join(", ");
        match self.sim.state {
            State::Instantiated | State::InitializationMode => Ok(()),
            // Scheduled Execution: a partition's clocked inputs are set before its activation and
            // its clocked outputs read after it (FMI 3.0, 5.2: between activations, and in the
            // clockUpdate callback).
            State::ClockActivationMode => Ok(()),
            State::ClockUpdateMode if !setting => Ok(()),
            State::EventMode if clocks.iter().any(|c| self.clock_active(c)) => {
                if setting && self.evaluated_tick.is_some() {
                    return Err(self.error(&format!(
                        "{function}: '{}' (vr {}) is set after the tick of its clock {} was evaluated (a clocked \
                         variable was read, or fmi3EvaluateDiscreteStates ran): set the clocked inputs first; refused, \
                         value unchanged",
                        decl.name,
                        decl.value_reference,
                        names()
                    )));
                }
                Ok(())
            }
            state => Err(self.error(&format!(
                "{function}: '{}' (vr {}) is clocked by {}, which is not active{}: a clocked variable is {} in Event \
                 Mode while one of its clocks is active (fmi3SetClock), and in Initialization Mode (FMI 3.0, 2.2.9)",
                decl.name,
                decl.value_reference,
                names(),
                if state == State::EventMode {
                    String::new()
                } else {
                    format!(" (state {})", self.terms.state_name(state))
                },
                if setting { "set" } else { "read" }
            ))),
        }
    }

    /// Before a clocked variable is read in Event Mode: the tick of the active clocks, computed
    /// once (one round of the event iteration, whose answers fmi3UpdateDiscreteStates gives).
    /// `force`: also without an active input clock (the importer asks whether an output clock
    /// ticks, or reads a variable it clocks: the model's update decides that).
    pub fn evaluate_tick(&mut self, function: &str, force: bool) -> Outcome {
        if !M::DESCRIPTION.has_clocks()
            || self.sim.state != State::EventMode
            || self.evaluated_tick.is_some()
            || !(force || self.any_clock_active())
        {
            return Ok(());
        }
        let mut info = EventInfo::default();
        match self.event_iteration_keeping(function, &mut info, false, true) {
            OK => {
                self.evaluated_tick = Some(info);
                Ok(())
            }
            status => Err(status),
        }
    }

    /// [`Instance::evaluate_tick`] when one of `vrs` is a clocked variable (forced when one of its
    /// clocks is an output clock).
    fn evaluate_tick_for(&mut self, function: &str, vrs: &[u32]) -> Outcome {
        if !M::DESCRIPTION.has_clocks() {
            return Ok(());
        }
        let mut clocked = false;
        let mut by_output_clock = false;
        for vr in vrs {
            if let Some(v) = M::variable_index(*vr).map(|i| &M::DESCRIPTION.variables[i])
                && v.is_clocked()
            {
                clocked = true;
                by_output_clock |= v.fmi3.clocks.iter().any(|c| {
                    M::DESCRIPTION
                        .by_name(c)
                        .is_some_and(|c| c.causality == Causality::Output)
                });
            }
        }
        if clocked {
            self.evaluate_tick(function, by_output_clock)?;
        }
        Ok(())
    }

    /// The clocks' activity ends with the event's update (FMI 3.0, 2.2.9: "Any Clock active
    /// during fmi3UpdateDiscreteStates must be deactivated by the FMU itself"), or with Event Mode.
    fn end_ticks(&mut self) {
        if M::DESCRIPTION.has_clocks() {
            self.sim.model.deactivate_clocks();
            // (`tick_before` keeps its allocation for the next tick; without an evaluated tick
            // it means nothing.)
            self.evaluated_tick = None;
        }
    }

    /// What an FMU state holds: the simulation, or, between the evaluation of a clock's tick and
    /// fmi3UpdateDiscreteStates, the simulation before that evaluation (the tick is a function of
    /// it; restored, the next read or update evaluates it again).
    pub fn state_to_save(&self) -> std::borrow::Cow<'_, Sim<M>> {
        match (&self.evaluated_tick, &self.tick_before) {
            (Some(_), Some(before)) => {
                let mut sim = self.sim.clone();
                (sim.model, sim.events) = (before.0.clone(), before.1);
                std::borrow::Cow::Owned(sim)
            }
            _ => std::borrow::Cow::Borrowed(&self.sim),
        }
    }

    /// A variable's name and value reference, or those FMI 2.0 gives element `k` of an array.
    fn name_and_vr(decl: &Variable, element: Option<usize>) -> (std::borrow::Cow<'static, str>, u32) {
        match element {
            Some(k) => (decl.element_name(k).into(), decl.value_reference + k as u32),
            None => (decl.name.into(), decl.value_reference),
        }
    }

    /// Whether the standard lets this variable be set in the current state (FMI 2.0, 4.2.4).
    fn settable(&self, decl: &Variable) -> bool {
        let initial_exact_or_approx = matches!(decl.effective_initial(), Some(Initial::Exact | Initial::Approx));
        if decl.variability == Variability::Constant {
            return false;
        }
        if decl.causality == Causality::StructuralParameter
            || matches!(self.sim.state, State::ConfigurationMode | State::ReconfigurationMode)
        {
            // Structural parameters are set in (Re)configuration Mode, and nothing else is there.
            return self.settable_in_configuration(decl);
        }
        match self.sim.state {
            State::Instantiated => initial_exact_or_approx || decl.causality == Causality::Input,
            State::InitializationMode => {
                decl.causality == Causality::Input || decl.effective_initial() == Some(Initial::Exact)
            }
            State::StepComplete | State::EventMode | State::ClockActivationMode => {
                decl.causality == Causality::Input
                    || (decl.causality == Causality::Parameter && decl.variability == Variability::Tunable)
            }
            // Model exchange between events: continuous inputs only (states through
            // fmi2SetContinuousStates).
            State::ContinuousTimeMode => {
                decl.causality == Causality::Input && decl.variability == Variability::Continuous
            }
            _ => false,
        }
    }

    fn check_settable(&self, function: &str, decl: &Variable) -> Outcome {
        self.check_settable_as(function, decl, None)
    }

    /// [`Instance::check_settable`] of a variable, or of element `k` of an array in FMI 2.0.
    fn check_settable_as(&self, function: &str, decl: &Variable, element: Option<usize>) -> Outcome {
        if M::DESCRIPTION.has_clocks() && decl.is_clocked() {
            self.clocked_access(function, decl, true)?;
        }
        if M::DESCRIPTION.has_clocks() && self.evaluated_tick.is_some() && self.sim.state == State::EventMode {
            // The event's update already ran (for a clock's tick): a value set now would be missing
            // from it.
            return Err(self.error(&format!(
                "{function}: '{}' (vr {}) is set after this event was evaluated (a clock was asked for, or a \
                 clocked variable read): set the inputs first; refused, value unchanged",
                decl.name, decl.value_reference
            )));
        }
        if self.settable(decl) {
            return Ok(());
        }
        if decl.causality == Causality::StructuralParameter
            || matches!(self.sim.state, State::ConfigurationMode | State::ReconfigurationMode)
        {
            return Err(self.error(&format!(
                "{function}: '{}' (vr {}, causality {:?}, variability {:?}) cannot be set in state {}: structural \
                 parameters are set in Configuration Mode (fixed and tunable ones, after fmi3EnterConfigurationMode \
                 in Instantiated) and Reconfiguration Mode (tunable ones, from Step Mode or model exchange's Event \
                 Mode), and nothing else is set there",
                decl.name,
                decl.value_reference,
                decl.causality,
                decl.variability,
                self.terms.state_name(self.sim.state)
            )));
        }
        let (name, vr) = Self::name_and_vr(decl, element);
        Err(self.error(&format!(
            "{function}: '{name}' (vr {vr}, causality {:?}, variability {:?}) cannot be set in state {:?}",
            decl.causality, decl.variability, self.sim.state
        )))
    }

    fn check_one(&self, function: &str, vr: u32, value: Value) -> Result<&'static Variable, Status> {
        let decl = self.lookup(function, vr, value.api_type())?;
        self.check_settable(function, decl)?;
        match refusal(&self.sim.model, decl, value) {
            None if const { M::DESCRIPTION.has_structural_parameters() } => {
                self.check_structural(function, decl, value)?;
                Ok(decl)
            }
            None => Ok(decl),
            Some(Refusal::Rule(why)) => Err(self.error(&format!("{function}: {why}; refused, value unchanged"))),
            Some(Refusal::Model(why)) => Err(self.error(&format!("{function}: {why}"))),
        }
    }

    /// fmi2SetRealInputDerivatives (a model that declares `CoSimulation::INTERPOLATES_INPUTS`):
    /// the first time derivatives of continuous Real inputs, all or none. Refused: order 0 or
    /// less (FMI 2.0: "0 is not allowed"), a variable that is no continuous Real input, a value
    /// that is not finite, or a state where the input could not be set. Higher orders are legal
    /// calls the runtime's linear interpolation does not use: ignored, with fmi2Warning saying so.
    pub fn set_input_derivatives(&mut self, function: &str, vrs: &[u32], orders: &[i32], values: &[f64]) -> Status {
        for ((vr, order), value) in vrs.iter().zip(orders).zip(values) {
            let decl = match self.lookup(function, *vr, VarType::Real) {
                Ok(d) => d,
                Err(status) => return status,
            };
            if decl.causality != Causality::Input || decl.variability != Variability::Continuous {
                return self.error(&format!(
                    "{function}: '{}' (vr {vr}) is no continuous Real input; refused, nothing changed",
                    decl.name
                ));
            }
            if *order < 1 {
                return self.error(&format!(
                    "{function}: order {order} for '{}' (vr {vr}): derivative orders start at 1 (0 is not allowed); \
                     refused, nothing changed",
                    decl.name
                ));
            }
            if !value.is_finite() {
                return self.error(&format!(
                    "{function}: {value} for the derivative of '{}' (vr {vr}) is not finite; refused, nothing changed",
                    decl.name
                ));
            }
            if let Err(status) = self.check_settable(function, decl) {
                return status;
            }
        }
        let mut ignored = vec![];
        for ((vr, order), value) in vrs.iter().zip(orders).zip(values) {
            if *order > 1 {
                ignored.push(format!("order {order} of vr {vr}"));
                continue;
            }
            match self.input_slopes.iter_mut().find(|(v, _)| v == vr) {
                Some(slot) => slot.1 = *value,
                None => self.input_slopes.push((*vr, *value)),
            }
        }
        if ignored.is_empty() {
            return OK;
        }
        self.logger.log(
            WARNING,
            Category::StatusWarning,
            &format!(
                "{function}: {} ignored: the inputs are interpolated linearly over a step (first derivatives only)",
                ignored.join(", ")
            ),
        );
        WARNING
    }

    /// Sets all values or none: each is checked before any is stored.
    pub fn set_values<T: FmiType>(&mut self, function: &str, vrs: &[u32], values: &[T]) -> Status {
        if const { M::DESCRIPTION.has_structural_parameters() } {
            self.keep_before_configuration();
        }
        if !any_array::<M>(vrs) && !any_fmi2_element::<M>(self.version, vrs) {
            // One value per value reference, checked in place: no allocation on the hot path
            // (fmi2SetReal before every step; tests/hot_path_does_not_allocate.rs).
            let mut parameter_changed = false;
            for (vr, v) in vrs.iter().zip(values) {
                let Some(value) = v.to_value() else {
                    return self.error(&format!("{function}: value reference {vr}: not a numeric value"));
                };
                match self.check_one(function, *vr, value) {
                    Ok(decl) => parameter_changed |= decl.causality == Causality::Parameter,
                    Err(status) => return status,
                }
            }
            let previous = (parameter_changed && self.between_steps()).then(|| self.sim.model.clone());
            for (vr, v) in vrs.iter().zip(values) {
                if let Some(value) = v.to_value() {
                    self.sim.model.set(*vr, value);
                }
            }
            return self.after_set(function, previous);
        }
        let mut list = Vec::with_capacity(values.len());
        for (i, v) in values.iter().enumerate() {
            match v.to_value() {
                Some(value) => list.push(value),
                None => return self.error(&format!("{function}: values[{i}] is not a numeric value")),
            }
        }
        self.set_value_list(function, vrs, &list)
    }

    /// [`Instance::set_values`] of values that may differ in type (FMI 3.0's fmi3SetInt64
    /// reaches Int64 and Enumeration variables in one call): all or none.
    pub fn set_value_list(&mut self, function: &str, vrs: &[u32], values: &[Value]) -> Status {
        if const { M::DESCRIPTION.has_structural_parameters() } {
            self.keep_before_configuration();
        }
        if any_fmi2_element::<M>(self.version, vrs) {
            return self.set_fmi2_elements(function, vrs, values);
        }
        if any_array::<M>(vrs) {
            return self.set_with_arrays(function, vrs, values);
        }
        let mut parameter_changed = false;
        for (vr, value) in vrs.iter().zip(values) {
            match self.check_one(function, *vr, *value) {
                Ok(decl) => parameter_changed |= decl.causality == Causality::Parameter,
                Err(status) => return status,
            }
        }
        let previous = (parameter_changed && self.between_steps()).then(|| self.sim.model.clone());
        for (vr, value) in vrs.iter().zip(values) {
            self.sim.model.set(*vr, *value);
        }
        self.after_set(function, previous)
    }

    /// [`Instance::set_value_list`] of a model with array variables: `values` holds each
    /// array's elements in row-major order; every element is checked before any is stored.
    fn set_with_arrays(&mut self, function: &str, vrs: &[u32], values: &[Value]) -> Status {
        let mut parameter_changed = false;
        let mut at = 0;
        let mut spans = Vec::with_capacity(vrs.len());
        for vr in vrs {
            let n = crate::step::structural::count_of(&self.sim.model, *vr);
            let Some(elements) = values.get(at..at + n) else {
                return self.error(&format!(
                    "{function}: the values array ends before the elements of value reference {vr}"
                ));
            };
            for (i, value) in elements.iter().enumerate() {
                match self.check_one(function, *vr, *value) {
                    Ok(decl) => parameter_changed |= decl.causality == Causality::Parameter,
                    Err(status) => {
                        if n > 1 {
                            self.trace(|| format!("{function}: (element {i} of value reference {vr})"));
                        }
                        return status;
                    }
                }
            }
            spans.push((*vr, at, n));
            at += n;
        }
        let previous = (parameter_changed && self.between_steps()).then(|| self.sim.model.clone());
        for (vr, at, n) in spans {
            let decl = M::variable_index(vr).map(|i| &M::DESCRIPTION.variables[i]);
            let is_array = decl.is_some_and(|d| d.is_array());
            for (i, value) in values[at..at + n].iter().enumerate() {
                if let (true, Some(d)) = (is_array, decl) {
                    let k = crate::step::structural::storage_index(&self.sim.model, d, i);
                    self.sim.model.set_element(vr, k, *value);
                } else {
                    self.sim.model.set(vr, *value);
                }
            }
        }
        self.after_set(function, previous)
    }

    /// The Binary getter (FMI 3.0): the returned pointers stay valid until the next call on
    /// this instance (the bytes are copied, as the strings are).
    pub fn get_binaries(&mut self, function: &str, vrs: &[u32], sizes: &mut [usize], out: &mut [*const u8]) -> Status {
        // A clock's tick first (as in `get_values`), then the checks.
        if let Err(status) = self.evaluate_tick_for(function, vrs) {
            return status;
        }
        for vr in vrs {
            if let Err(status) = self
                .lookup(function, *vr, VarType::Binary)
                .and_then(|v| self.check_gettable(function, v))
            {
                return status;
            }
        }
        if let Err(status) = self.up_to_date(function) {
            return status;
        }
        // Every place the model's code runs checks what it wrote (`oversized_binary`); this is
        // the last word, should a value have come in another way.
        for vr in vrs {
            let decl = M::variable_index(*vr).map(|i| &M::DESCRIPTION.variables[i]);
            if let (Some(d), Some(max)) = (decl, decl.and_then(|d| d.fmi3.max_size))
                && let Some(n) = self.sim.model.get_binary(*vr).map(<[u8]>::len)
                && n > max as usize
            {
                return self.error(&format!(
                    "{function}: '{}' (vr {vr}) holds {n} bytes, more than its maxSize = {max}; nothing returned",
                    d.name
                ));
            }
        }
        self.binaries.clear();
        for vr in vrs {
            self.binaries
                .push(self.sim.model.get_binary(*vr).unwrap_or_default().to_vec());
        }
        for ((slot, size), b) in out.iter_mut().zip(sizes.iter_mut()).zip(&self.binaries) {
            *slot = b.as_ptr();
            *size = b.len();
        }
        OK
    }

    /// The Binary setter (FMI 3.0): all or none; a value longer than the variable's `maxSize`
    /// is refused.
    pub fn set_binaries(&mut self, function: &str, vrs: &[u32], values: &[&[u8]]) -> Status {
        let mut parameter_changed = false;
        for (vr, bytes) in vrs.iter().zip(values) {
            let decl = match self.lookup(function, *vr, VarType::Binary) {
                Ok(d) => d,
                Err(status) => return status,
            };
            if let Err(status) = self.check_settable(function, decl) {
                return status;
            }
            if let Some(max) = decl.fmi3.max_size
                && bytes.len() > max as usize
            {
                return self.error(&format!(
                    "{function}: {} bytes for '{}' (vr {vr}) exceed its maxSize = {max}; refused, values unchanged",
                    bytes.len(),
                    decl.name
                ));
            }
            parameter_changed |= decl.causality == Causality::Parameter;
        }
        let previous = (parameter_changed && self.between_steps()).then(|| self.sim.model.clone());
        for (vr, bytes) in vrs.iter().zip(values) {
            self.sim.model.set_binary(*vr, bytes);
        }
        self.after_set(function, previous)
    }

    /// After values were stored: stale calculated variables in initialization mode; between
    /// steps, a tunable parameter change the model may still refuse (then nothing changes).
    fn after_set(&mut self, function: &str, previous: Option<M>) -> Status {
        if self.sim.state == State::InitializationMode {
            self.sim.init_dirty = true;
        }
        self.sim.stale_derivatives = true;
        self.sim.stale_outputs = true;
        if let Some(previous) = previous {
            let ctx = Context::outside_step(
                self.sim.start_time,
                self.sim.tolerance,
                Some(&self.logger),
                self.resources.as_deref(),
                self.model_exchange,
            );
            let outcome = self.sim.model.parameters_changed(&ctx).and_then(|()| {
                non_finite(&self.sim.model)
                    .or_else(|| oversized_binary(&self.sim.model))
                    .map_or(Ok(()), Err)
            });
            if let Err(why) = outcome {
                self.sim.model = previous;
                return self.error(&format!(
                    "{function}: parameter change refused: {why}; values unchanged"
                ));
            }
            self.sim.solver.restart();
            self.event(|| format!("{function}: tunable parameters changed at t = {}", self.sim.time));
        }
        OK
    }

    /// Importers compute communication points as start + n·h or by summing h, so the point
    /// is compared with a tolerance rather than exactly. The round-off is relative to the size
    /// of the times involved (the FMU's time and the start time), so that is what the tolerance
    /// scales with; the step size only adds a few of its own ulps. (Scaling with h, as before,
    /// let a huge step accept any point: at t = 0 a step of 1e9 s accepted a point 5 s off.)
    fn time_matches(&self, t: f64, h: f64) -> bool {
        let scale = self.sim.time.abs().max(self.sim.start_time.abs());
        let tol = 1e-8 * scale + 4.0 * f64::EPSILON * h;
        (t - self.sim.time).abs() <= tol
    }

    pub fn do_step(&mut self, t: f64, h: f64) -> Status {
        let f = self.terms.name(Function::DoStep);
        if !(h.is_finite() && h > 0.0) {
            return self.error(&format!(
                "{f}: communicationStepSize = {h} must be finite and > 0; time stays {}",
                self.sim.time
            ));
        }
        if !t.is_finite() || !self.time_matches(t, h) {
            return self.error(&format!(
                "{f}: currentCommunicationPoint = {t} does not match the FMU's time {}",
                self.sim.time
            ));
        }
        let end = t + h;
        if end <= t {
            return self.error(&format!(
                "{f}: communicationStepSize = {h} is too small to advance time from {t}"
            ));
        }
        if let Some(stop) = self.sim.stop_time
            && end > stop + 1e-8 * stop.abs().max(h)
        {
            return self.error(&format!(
                "{f}: the step from {t} by {h} ends after stopTime = {stop} set in {}",
                self.terms.name(Function::SetupExperiment)
            ));
        }
        self.trace(|| format!("{f}(currentCommunicationPoint = {t}, communicationStepSize = {h})"));
        self.before_step.clone_from(&self.sim.model);
        let before_solver = self.sim.solver;
        let before_events = self.sim.events;
        let terminate_before = self.sim.terminate_requested;
        let mut ctx = Context {
            start_time: self.sim.start_time,
            tolerance: self.sim.tolerance,
            logger: Some(&self.logger),
            resources: self.resources.as_deref(),
            solver: Some(&mut self.sim.solver),
            refreshed: false,
            model_exchange: self.model_exchange,
            events: Some(&mut self.sim.events),
            return_at_events: match (self.event_mode_used, self.early_return_allowed) {
                (true, true) => ReturnAtEvents::Each,
                (true, false) => ReturnAtEvents::AtStepEnd,
                (false, _) => ReturnAtEvents::Never,
            },
            intermediate: self.intermediate_update.as_deref_mut(),
            input_slopes: &self.input_slopes,
        };
        self.step_event = false;
        let mut outcome = self.sim.model.do_step(t, h, &mut ctx);
        let refreshed = ctx.refreshed;
        if self.sim.events.terminated {
            self.sim.terminate_requested = true;
        }
        if !refreshed {
            // The model's own step advanced the states: its outputs follow from them.
            let reached = match &outcome {
                Ok(()) => end,
                Err(failure) => failure.reached_time,
            };
            evaluate(&mut self.sim.model, reached);
        }
        if let Some(what) = oversized_binary(&self.sim.model) {
            // A mistake in the model's code, which a smaller step would repeat: refused, not discarded.
            std::mem::swap(&mut self.sim.model, &mut self.before_step);
            self.sim.solver = before_solver;
            self.sim.events = before_events;
            self.sim.terminate_requested = terminate_before;
            self.sim.stale_derivatives = true;
            self.sim.stale_outputs = true;
            return self.error(&format!(
                "{f}: the step from t = {t} left {what}; refused, every variable is back at its value at t = {t}"
            ));
        }
        self.sim.stale_derivatives = false;
        self.sim.stale_outputs = false;
        if outcome.is_ok() && self.sim.solver.validate().is_err() {
            outcome = Err(crate::model::StepFailure {
                reached_time: t,
                message: format!(
                    "the integrator's memory became unusable: {}",
                    self.sim.solver.validate().err().unwrap_or_default()
                ),
            });
            self.sim.solver = before_solver;
            self.sim.solver.restart();
        }
        let stopped_at = self.sim.events.stopped_at.take();
        let returned_early_at = self.sim.events.returned_early_at.take();
        self.returned_early = false;
        match (outcome, non_finite(&self.sim.model)) {
            (Ok(()), None) if returned_early_at.is_some() && stopped_at.is_none() => {
                // The importer asked for it in the intermediate update (FMI 3.0, 4.2.2).
                let at = returned_early_at.unwrap_or(end).clamp(t, end);
                self.sim.time = at;
                self.sim.last_successful_time = at;
                self.returned_early = at < end;
                self.event(|| format!("{f}: returning early at t = {at}, as the intermediate update asked"));
                OK
            }
            (Ok(()), None) if stopped_at.is_some() => {
                // FMI 3.0 event mode: the step ends at the event (with early return, at the
                // first one; without, at its end, after the events inside it were handled
                // there), which the importer handles in Event Mode.
                let at = stopped_at.unwrap_or(end).clamp(t, end);
                self.sim.time = at;
                self.sim.last_successful_time = at;
                self.step_event = true;
                self.event(|| format!("{f}: eventHandlingNeeded at t = {at}, for the importer's Event Mode"));
                OK
            }
            (Ok(()), None) => {
                self.sim.time = end;
                self.sim.last_successful_time = end;
                OK
            }
            (Err(failure), None) if self.sim.events.terminated && self.version == Version::Fmi3 => {
                // FMI 3.0: the step ends where the model ended the simulation, with fmi3OK,
                // terminateSimulation and lastSuccessfulTime (FMI 2.0: fmi2Discard and the
                // fmi2Terminated status).
                let reached = if failure.reached_time.is_finite() {
                    failure.reached_time.clamp(t, end)
                } else {
                    t
                };
                self.sim.time = reached;
                self.sim.last_successful_time = reached;
                self.event(|| format!("{f}: {}", failure.message));
                OK
            }
            (Err(failure), None) => {
                // A model's claim outside the step is no time it reached.
                let reached = if failure.reached_time.is_finite() {
                    failure.reached_time.clamp(t, end)
                } else {
                    t
                };
                self.discard_step(t, h, reached, &failure.message)
            }
            (outcome, Some(what)) => {
                std::mem::swap(&mut self.sim.model, &mut self.before_step);
                self.sim.solver = before_solver;
                self.sim.events = before_events;
                let model_said = match outcome {
                    Ok(()) => String::new(),
                    Err(failure) => format!(" (the model reported: {})", failure.message),
                };
                self.discard_step(
                    t,
                    h,
                    t,
                    &format!("{what}{model_said}; every variable is back at its value at t = {t}"),
                )
            }
        }
    }

    fn discard_step(&mut self, t: f64, h: f64, reached: f64, why: &str) -> Status {
        self.sim.time = reached;
        self.sim.last_successful_time = reached;
        self.sim.state = State::StepFailed;
        self.logger.log(
            DISCARD,
            Category::StatusDiscard,
            &format!(
                "{} from t = {t} by h = {h} discarded at t = {reached}: {why}",
                self.terms.name(Function::DoStep)
            ),
        );
        DISCARD
    }
}

/// Why a value may not be stored, as a message: `<value> for '<name>' (vr <n>) <reason>`.
enum Refusal {
    /// A rule of the runtime: finite, within the declared bounds, an item of the enumeration.
    Rule(String),
    /// The model's own check refused it.
    Model(String),
}

/// The rules every value passes before it is stored, whether set through the API or restored
/// from a serialized state: a finite number, within the declared bounds, an item of its
/// enumeration, accepted by the model's own check (with the other values of `model`).
fn refusal<M: CoSimulation>(model: &M, decl: &Variable, value: Value) -> Option<Refusal> {
    refusal_as(model, decl, value, decl.name, decl.value_reference)
}

/// [`refusal`], the messages naming the variable `name` (vr `vr`): FMI 2.0's element of an array.
fn refusal_as<M: CoSimulation>(model: &M, decl: &Variable, value: Value, name: &str, vr: u32) -> Option<Refusal> {
    if !value.is_finite() {
        return Some(Refusal::Rule(format!(
            "{} for '{name}' (vr {vr}) is not a finite number",
            value.as_f64().unwrap_or(f64::NAN)
        )));
    }
    if !value.within(decl.min, decl.max) {
        let x = match value.as_i128() {
            Some(n) => n.to_string(),
            None => value.as_f64().map(|x| x.to_string()).unwrap_or_default(),
        };
        return Some(Refusal::Rule(format!(
            "{x} for '{name}' (vr {vr}) is outside {}",
            range_text(decl)
        )));
    }
    if let (Some(e), Value::Integer(code)) = (decl.enumeration, value)
        && e.item(code).is_none()
    {
        let items: Vec<String> = e.items.iter().map(|i| format!("{} = {}", i.name, i.value)).collect();
        return Some(Refusal::Rule(format!(
            "{code} for '{name}' (vr {vr}) is no item of the enumeration {} ({})",
            e.name,
            items.join(", ")
        )));
    }
    if let Err(why) = model.check(decl, value) {
        return Some(Refusal::Model(format!(
            "{value:?} for '{name}' (vr {vr}) refused: {why}"
        )));
    }
    None
}

/// What a deserialized state must be before it is accepted: every value as a setter would
/// accept it, the model's internal state usable, and the runtime's own bookkeeping sound.
/// (The serialized form's magic, GUID, length and checksum only say who wrote it and that it
/// is intact, not that its content is one this FMU can run from.)
pub fn check_restored<M: CoSimulation>(sim: &Sim<M>) -> Result<(), String> {
    for decl in M::DESCRIPTION.variables {
        if let Some(value) = sim.model.get(decl.value_reference)
            && let Some(Refusal::Rule(why) | Refusal::Model(why)) = refusal(&sim.model, decl, value)
        {
            return Err(format!("the state's {why}"));
        }
        if let (Some(max), Some(bytes)) = (decl.fmi3.max_size, sim.model.get_binary(decl.value_reference))
            && bytes.len() > max as usize
        {
            return Err(format!(
                "the state's '{}' has {} bytes, more than its maxSize = {max}",
                decl.name,
                bytes.len()
            ));
        }
        if decl.is_array() {
            for i in 0..decl.element_count() {
                if let Some(value) = sim.model.get_element(decl.value_reference, i)
                    && let Some(Refusal::Rule(why) | Refusal::Model(why)) = refusal(&sim.model, decl, value)
                {
                    return Err(format!("the state's element {i}: {why}"));
                }
            }
        }
    }
    if let Some(what) = non_finite(&sim.model) {
        return Err(format!("in the state, {what}"));
    }
    sim.solver.validate().map_err(|e| format!("in the state, {e}"))?;
    if let Some(te) = sim.events.next_event_time
        && !te.is_finite()
    {
        return Err(format!("the state's next time event {te} is not finite"));
    }
    let times = [
        ("startTime", sim.start_time),
        ("time", sim.time),
        ("last successful time", sim.last_successful_time),
    ];
    for (what, t) in times {
        if !t.is_finite() {
            return Err(format!("the state's {what} = {t} is not finite"));
        }
    }
    if let Some(tol) = sim.tolerance
        && !(tol.is_finite() && tol > 0.0)
    {
        return Err(format!("the state's tolerance = {tol} must be finite and > 0"));
    }
    if let Some(stop) = sim.stop_time
        && !(stop.is_finite() && stop >= sim.start_time)
    {
        return Err(format!(
            "the state's stopTime = {stop} must be finite and not before its startTime = {}",
            sim.start_time
        ));
    }
    Ok(())
}

/// `[min, max]` with exclusive ends as `(`/`)`, for messages; an undeclared end of an integer
/// type is the type's own (`[0, 200]` for a UInt8 with max = 200, not `(-inf, 200]`).
fn range_text(v: &Variable) -> String {
    let own = v.var_type.integer_range();
    let lo = match (v.min, own) {
        (Some(b), _) => format!("{}{}", if b.exclusive { "(" } else { "[" }, b.value),
        (None, Some((lo, _))) => format!("[{lo}"),
        (None, None) => "(-inf".into(),
    };
    let hi = match (v.max, own) {
        (Some(b), _) => format!("{}{}", b.value, if b.exclusive { ")" } else { "]" }),
        (None, Some((_, hi))) => format!("{hi}]"),
        (None, None) => "inf)".into(),
    };
    format!("{lo}, {hi}")
}

/// What the new-discrete-states function reports (`fmi2EventInfo`'s fields; fmi3UpdateDiscreteStates'
/// output arguments).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EventInfo {
    pub new_discrete_states_needed: bool,
    pub terminate_simulation: bool,
    pub nominals_changed: bool,
    pub values_changed: bool,
    pub next_event_time: Option<f64>,
}

impl<M: CoSimulation> Instance<M> {
    /// Where a tunable parameter may change: between co-simulation steps, or at an event.
    fn between_steps(&self) -> bool {
        matches!(
            self.sim.state,
            State::StepComplete | State::EventMode | State::ClockActivationMode
        )
    }

    /// Whether `state` belongs to the interface this instance was made for (an FMU state of a
    /// model-exchange instance restored into a co-simulation one would leave it in a state
    /// its interface does not have).
    pub fn state_fits(&self, state: State) -> bool {
        let scheduled_only = matches!(state, State::ClockActivationMode | State::ClockUpdateMode);
        if self.scheduled {
            return scheduled_only
                || matches!(
                    state,
                    State::Instantiated | State::InitializationMode | State::Terminated | State::Error
                );
        }
        if scheduled_only {
            return false;
        }
        let me_only = match state {
            State::ContinuousTimeMode => true,
            State::EventMode => !self.event_mode_used,
            _ => false,
        };
        let cs_only = matches!(state, State::StepComplete | State::StepFailed | State::StepCanceled);
        if self.model_exchange { !cs_only } else { !me_only }
    }

    /// After an FMU state was restored: what the equations computed is recomputed on demand.
    pub fn restored(&mut self) {
        self.evaluated_tick = None;
        self.tick_before = None;
        self.sim.stale_derivatives = true;
        self.sim.stale_outputs = true;
    }

    /// Brings every computed variable up to date before values leave: the initialization in
    /// initialization mode, else the equations if something they depend on changed. A result
    /// that is not finite leaves nothing changed and is refused: DISCARD in model exchange
    /// (the standard's answer for "outside the model's domain, try a smaller step"), ERROR
    /// in co-simulation.
    fn up_to_date(&mut self, function: &str) -> Outcome {
        if self.sim.state == State::InitializationMode {
            return self.initialize_model(function, false);
        }
        if !self.sim.stale_outputs || matches!(self.sim.state, State::Instantiated | State::ConfigurationMode) {
            return Ok(());
        }
        let before = self.sim.model.continuous::<f64>();
        // What `calculate` writes into a Binary is no continuous value: a model with a `maxSize`
        // keeps a whole copy to go back to.
        let before_binaries = const { M::DESCRIPTION.has_max_sizes() }.then(|| self.sim.model.clone());
        evaluate(&mut self.sim.model, self.sim.time);
        if let Some(what) = oversized_binary(&self.sim.model) {
            if let Some(model) = before_binaries {
                self.sim.model = model;
            }
            return Err(self.error(&format!(
                "{function}: at t = {}, the equations left {what} (computed from the current states, inputs and \
                 parameters); nothing returned",
                self.sim.time
            )));
        }
        if let Some(what) = non_finite(&self.sim.model) {
            self.sim.model.store_continuous(&before);
            return Err(self.not_finite(function, &what));
        }
        self.sim.stale_derivatives = false;
        self.sim.stale_outputs = false;
        Ok(())
    }

    fn not_finite(&self, function: &str, what: &str) -> Status {
        let message = format!(
            "{function}: at t = {}, {what} (computed from the current states, inputs and parameters); nothing returned",
            self.sim.time
        );
        if self.model_exchange {
            self.logger.log(DISCARD, Category::StatusDiscard, &message);
            DISCARD
        } else {
            self.error(&message)
        }
    }

    pub fn enter_event_mode(&mut self) -> Status {
        self.end_ticks();
        self.sim.state = State::EventMode;
        self.trace(|| format!("{} at t = {}", self.terms.name(Function::EnterEventMode), self.sim.time));
        OK
    }

    /// fmi2NewDiscreteStates / fmi3UpdateDiscreteStates: one round of the event iteration
    /// ([`Model::update`](crate::Model::update)); the importer calls again while
    /// `new_discrete_states_needed`.
    pub fn new_discrete_states(&mut self, info: &mut EventInfo) -> Status {
        let f = self.terms.name(Function::NewDiscreteStates);
        let status = match self.evaluated_tick.take() {
            // The clocks' tick was computed when a clocked variable was read: that round.
            Some(round) => {
                *info = round;
                OK
            }
            None => self.event_iteration(f, info, false),
        };
        if status == OK {
            self.sim.last_successful_time = self.sim.time;
            self.end_ticks();
        }
        status
    }

    /// One round (`all_rounds`: every round, as co-simulation runs it) of the event iteration
    /// at the current time, all or nothing: on a refusal the model and its clock are as before.
    fn event_iteration(&mut self, function: &str, info: &mut EventInfo, all_rounds: bool) -> Status {
        self.event_iteration_keeping(function, info, all_rounds, false)
    }

    /// [`Instance::event_iteration`]; `keep`: the model and clock from before the round go to
    /// [`Instance::tick_before`] (a clock's tick evaluated before fmi3UpdateDiscreteStates),
    /// reusing its allocation.
    fn event_iteration_keeping(
        &mut self,
        function: &str,
        info: &mut EventInfo,
        all_rounds: bool,
        keep: bool,
    ) -> Status {
        *info = EventInfo::default();
        if let Err(status) = self.up_to_date(function) {
            return status;
        }
        let before = (self.sim.model.clone(), self.sim.events);
        let ctx = Context::outside_step(
            self.sim.start_time,
            self.sim.tolerance,
            Some(&self.logger),
            self.resources.as_deref(),
            self.model_exchange,
        );
        let time = self.sim.time;
        let outcome = if all_rounds {
            crate::step::events::iterate(&mut self.sim.model, &ctx, time, &mut self.sim.events).map(
                |(changed, terminate)| crate::step::events::Round {
                    again: false,
                    terminate,
                    states_changed: changed,
                },
            )
        } else {
            crate::step::events::update_round(&mut self.sim.model, &ctx, time, &mut self.sim.events)
        };
        let outcome = outcome.and_then(|round| match oversized_binary(&self.sim.model) {
            None => Ok(round),
            Some(what) => Err(format!("the update left {what}")),
        });
        match outcome {
            Ok(round) => {
                self.sim.stale_derivatives = false;
                self.sim.stale_outputs = false;
                if round.states_changed {
                    self.sim.solver.restart();
                }
                info.new_discrete_states_needed = round.again;
                info.values_changed = round.states_changed;
                info.next_event_time = self.sim.events.next_event_time;
                if let Some(reason) = &round.terminate {
                    self.sim.events.terminated = true;
                    info.terminate_simulation = true;
                    self.event(|| format!("{function}: the model ends the simulation at t = {time}: {reason}"));
                }
                self.event(|| {
                    format!(
                        "{function}: event at t = {time}{}{}{}",
                        if round.states_changed {
                            ", continuous states changed"
                        } else {
                            ""
                        },
                        if round.again { ", another round asked for" } else { "" },
                        match info.next_event_time {
                            Some(te) => format!(", next time event at t = {te}"),
                            None => String::new(),
                        }
                    )
                });
                if keep {
                    match &mut self.tick_before {
                        Some(b) => **b = before,
                        None => self.tick_before = Some(Box::new(before)),
                    }
                }
                OK
            }
            Err(why) => {
                (self.sim.model, self.sim.events) = before;
                self.sim.stale_derivatives = true;
                self.sim.stale_outputs = true;
                self.error(&format!(
                    "{function}: at t = {time}: {why}; the model is as before the event"
                ))
            }
        }
    }

    /// fmi3ActivateModelPartition (Scheduled Execution, FMI 3.0 5.2): the input clock
    /// `clock_reference` ticks at `activation_time`: the instance's time moves there, the model's
    /// `update` runs once with that clock active, and the input clock is inactive again. `Ok(true)`:
    /// the activation ticked an output clock or gave a countdown (or changing) clock a new
    /// interval, so the importer is to be told (its clockUpdate callback; the output clocks stay
    /// ticked until [`Instance::end_clock_update`]).
    pub fn activate_model_partition(&mut self, function: &str, clock_reference: u32, t: f64) -> Result<bool, Status> {
        use crate::description::IntervalVariability as I;
        let Some(decl) = M::variable_index(clock_reference).map(|i| &M::DESCRIPTION.variables[i]) else {
            return Err(self.error(&format!(
                "{function}: clockReference {clock_reference} is no variable of this FMU"
            )));
        };
        if decl.fmi3.clock.is_none() || decl.causality != Causality::Input {
            return Err(self.error(&format!(
                "{function}: clockReference {clock_reference} ('{}') is {}: a model partition is activated by its \
                 input Clock",
                decl.name,
                if decl.fmi3.clock.is_some() {
                    "an output Clock (the FMU ticks it)".to_string()
                } else {
                    format!("a {} variable, not a Clock", self.type_name(decl.var_type))
                }
            )));
        }
        if !t.is_finite() || t < self.sim.time {
            return Err(self.error(&format!(
                "{function}: activationTime = {t} for '{}': a finite time not before the instance's time {}",
                decl.name, self.sim.time
            )));
        }
        // Output clocks an earlier activation ticked (without a clockUpdate callback the importer
        // read them after that call) end with this one.
        self.sim.model.deactivate_clocks();
        let before_time = self.sim.time;
        if t != self.sim.time {
            self.sim.time = t;
            self.sim.stale_derivatives = true;
            self.sim.stale_outputs = true;
        }
        if let Some(k) = self.sim.model.clock_mut(clock_reference) {
            k.__set_active(true);
        }
        self.trace(|| {
            format!(
                "{function}(clockReference = {clock_reference} ('{}'), activationTime = {t})",
                decl.name
            )
        });
        let mut info = EventInfo::default();
        let status = self.event_iteration(function, &mut info, false);
        if let Some(k) = self.sim.model.clock_mut(clock_reference) {
            k.__set_active(false);
        }
        if status != OK {
            // The model is as before the round (`event_iteration`); so is the time.
            self.sim.time = before_time;
            return Err(status);
        }
        self.sim.last_successful_time = t;
        if info.terminate_simulation {
            self.sim.terminate_requested = true;
        }
        // What the importer is to hear of: an output clock that ticked, a model-timed clock's
        // new interval (not taken: fmi3GetIntervalDecimal reports it).
        let notify = M::DESCRIPTION.variables.iter().any(|v| match v.fmi3.clock {
            Some(c) => {
                let k = self.sim.model.clock(v.value_reference);
                (v.causality == Causality::Output && k.is_some_and(|k| k.ticked()))
                    || (matches!(c.interval_variability, I::Countdown | I::Changing) && k.is_some_and(|k| k.__fresh()))
            }
            None => false,
        });
        Ok(notify)
    }

    /// After the importer's clockUpdate callback returned: back to Clock Activation Mode (unless a
    /// call from the callback ended elsewhere), the output clocks inactive.
    pub fn end_clock_update(&mut self) {
        if self.sim.state == State::ClockUpdateMode {
            self.sim.state = State::ClockActivationMode;
        }
        self.sim.model.deactivate_clocks();
    }

    /// fmi3EnterStepMode (co-simulation with event mode): the events handled, stepping resumes.
    pub fn enter_step_mode(&mut self) -> Status {
        self.end_ticks();
        self.sim.state = State::StepComplete;
        self.sim.events.initial = false;
        self.sim.solver.restart();
        self.step_event = false;
        OK
    }

    pub fn enter_continuous_time_mode(&mut self) -> Status {
        self.end_ticks();
        self.sim.state = State::ContinuousTimeMode;
        self.sim.events.initial = false;
        OK
    }

    /// Returns (enterEventMode, terminateSimulation): the models here have no step events
    /// (their state and time events are found by the importer).
    pub fn completed_integrator_step(&mut self) -> (Status, bool, bool) {
        self.sim.last_successful_time = self.sim.time;
        (OK, false, false)
    }

    pub fn set_time(&mut self, t: f64) -> Status {
        if !t.is_finite() {
            return self.error(&format!(
                "{}: time = {t} is not finite; time stays {}",
                self.terms.name(Function::SetTime),
                self.sim.time
            ));
        }
        self.sim.time = t;
        self.sim.stale_derivatives = true;
        self.sim.stale_outputs = true;
        OK
    }

    #[inline]
    fn check_states_len(&self, function: &str, n: usize) -> Outcome {
        if n == crate::step::structural::number_of_states(&self.sim.model) {
            return Ok(());
        }
        Err(self.wrong_states_len(function, n))
    }

    #[cold]
    fn wrong_states_len(&self, function: &str, n: usize) -> Status {
        self.error(&format!(
            "{function}: nx = {n}, but {} has {} continuous states (numberOfContinuousStates{})",
            M::DESCRIPTION.model_identifier,
            crate::step::structural::number_of_states(&self.sim.model),
            if const { M::DESCRIPTION.has_sized_arrays() } {
                ", with the structural parameters as they are now"
            } else {
                ""
            }
        ))
    }

    /// The entry of the state vector that is the importer's state `i`.
    #[inline]
    fn state_entry(&self, i: usize) -> usize {
        if !const { M::DESCRIPTION.has_sized_arrays() } {
            return i;
        }
        crate::step::structural::active_states(&self.sim.model)
            .nth(i)
            .unwrap_or(i)
    }

    /// The name of the importer's state `i` (an element of an array state: `x[2]`).
    fn state_name(&self, i: usize) -> std::borrow::Cow<'static, str> {
        Self::entry_name(self.state_entry(i))
    }

    /// The name of entry `k` of the whole state vector.
    fn entry_name(k: usize) -> std::borrow::Cow<'static, str> {
        let vr = M::STATES[k];
        match M::variable_index(vr).map(|j| &M::DESCRIPTION.variables[j]) {
            Some(v) if v.is_array() => v.element_name(M::STATE_ELEMENTS[k] as usize).into(),
            Some(v) => v.name.into(),
            None => "?".into(),
        }
    }

    /// The importer's state vector (or derivatives, nominals) from the whole one: the entries
    /// it sees ([`crate::step::structural::active_states`]).
    #[inline]
    fn gather(&self, full: &[f64], out: &mut [f64]) {
        if !const { M::DESCRIPTION.has_sized_arrays() } {
            out.copy_from_slice(full);
            return;
        }
        for (slot, k) in out
            .iter_mut()
            .zip(crate::step::structural::active_states(&self.sim.model))
        {
            *slot = full[k];
        }
    }

    pub fn set_continuous_states(&mut self, function: &str, x: &[f64]) -> Status {
        if let Err(status) = self.check_states_len(function, x.len()) {
            return status;
        }
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return self.error(&format!(
                "{function}: x[{i}] ('{}') = {} is not a finite number; refused, states unchanged",
                self.state_name(i),
                x[i]
            ));
        }
        let mut states = if const { M::DESCRIPTION.has_sized_arrays() } {
            self.sim.model.states()
        } else {
            <M::States as StateVector>::zeros()
        };
        if const { M::DESCRIPTION.has_sized_arrays() } {
            for (k, v) in crate::step::structural::active_states(&self.sim.model).zip(x) {
                states.as_mut_slice()[k] = *v;
            }
        } else {
            states.as_mut_slice().copy_from_slice(x);
        }
        self.sim.model.set_states(&states);
        self.sim.stale_derivatives = true;
        self.sim.stale_outputs = true;
        OK
    }

    pub fn get_continuous_states(&mut self, function: &str, x: &mut [f64]) -> Status {
        if let Err(status) = self.check_states_len(function, x.len()) {
            return status;
        }
        if self.sim.state == State::InitializationMode
            && let Err(status) = self.initialize_model(function, false)
        {
            return status;
        }
        let full = self.sim.model.states();
        self.gather(full.as_slice(), x);
        OK
    }

    pub fn get_nominals(&mut self, function: &str, x: &mut [f64]) -> Status {
        if let Err(status) = self.check_states_len(function, x.len()) {
            return status;
        }
        self.gather(M::NOMINALS, x);
        OK
    }

    pub fn get_event_indicators_mut(&mut self, function: &str, z: &mut [f64]) -> Status {
        if z.len() != M::INDICATORS.len() {
            return self.error(&format!(
                "{function}: ni = {}, but {} has {} event indicators (numberOfEventIndicators)",
                z.len(),
                M::DESCRIPTION.model_identifier,
                M::INDICATORS.len()
            ));
        }
        if z.is_empty() {
            return OK;
        }
        if self.sim.state == State::InitializationMode
            && let Err(status) = self.initialize_model(function, false)
        {
            return status;
        }
        let mut c = self.sim.model.continuous::<f64>();
        self.sim.model.derivatives(self.sim.time, &mut c);
        self.sim.model.outputs(self.sim.time, &mut c);
        M::indicators_of(&c, z);
        if let Some(i) = z.iter().position(|v| !v.is_finite()) {
            let vr = M::INDICATORS[i];
            let name = M::declaration(vr, VarType::Real).map_or("?", |v| v.name);
            return self.not_finite(
                function,
                &format!("event indicator {i} ('{name}', vr {vr}) is {}", z[i]),
            );
        }
        OK
    }

    /// The get-derivatives function: the right-hand side only (the outputs stay for when they are read).
    #[inline]
    pub fn get_derivatives(&mut self, function: &str, dx: &mut [f64]) -> Status {
        if let Err(status) = self.check_states_len(function, dx.len()) {
            return status;
        }
        if self.sim.state == State::InitializationMode
            && let Err(status) = self.initialize_model(function, false)
        {
            return status;
        }
        if self.sim.stale_derivatives {
            let mut c = self.sim.model.continuous::<f64>();
            self.sim.model.derivatives(self.sim.time, &mut c);
            let mut d = M::derivatives_of(&c);
            if const { M::DESCRIPTION.has_sized_arrays() } {
                let mask = crate::step::structural::active_mask(&self.sim.model);
                crate::step::structural::hide(&mut d, mask.as_ref());
            }
            if let Some(i) = d.as_slice().iter().position(|v| !v.is_finite()) {
                let what = format!("the derivative of '{}' is {}", Self::entry_name(i), d.as_slice()[i]);
                return self.not_finite(function, &what);
            }
            self.derivatives = d;
            self.sim.stale_derivatives = false;
        } else if !self.sim.stale_outputs {
            // Computed with everything else: the model's own der(..) variables hold them.
            let c = self.sim.model.continuous::<f64>();
            self.derivatives = M::derivatives_of(&c);
        }
        let d = self.derivatives;
        self.gather(d.as_slice(), dx);
        OK
    }

    /// The first time derivatives of Real outputs at the instance's time
    /// (fmi2GetRealOutputDerivatives, fmi3GetOutputDerivatives; maxOutputDerivativeOrder = 1):
    /// exact, from the model's equations in dual numbers, with time moving at rate 1, each
    /// continuous state at its derivative, and the inputs held (canInterpolateInputs = false:
    /// they are constant over a step). A discrete output's derivative is 0 (it changes at
    /// events only). All references are checked before anything is computed.
    pub fn output_derivatives(&mut self, function: &str, vrs: &[u32], orders: &[i32], out: &mut [f64]) -> Status {
        use num_dual::Dual64;
        let mut probe = self.sim.model.continuous::<f64>();
        for (vr, order) in vrs.iter().zip(orders) {
            let decl = match self.lookup(function, *vr, VarType::Real) {
                Ok(d) => d,
                Err(status) => return status,
            };
            if decl.causality != Causality::Output {
                return self.error(&format!(
                    "{function}: '{}' (vr {vr}) is a {:?}, not an output: output derivatives are those of outputs",
                    decl.name, decl.causality
                ));
            }
            if *order != 1 {
                return self.error(&format!(
                    "{function}: order {order} for '{}' (vr {vr}): this FMU gives first derivatives only (maxOutputDerivativeOrder = 1)",
                    decl.name
                ));
            }
            let held = decl.variability == Variability::Discrete;
            if !held && M::continuous_slot(&mut probe, *vr).is_none() {
                return self.error(&format!(
                    "{function}: '{}' (vr {vr}) is computed outside the equations (Model::calculate): it has no derivative",
                    decl.name
                ));
            }
        }
        if let Err(status) = self.up_to_date(function) {
            return status;
        }
        let t = self.sim.time;
        let mut c = self.sim.model.continuous::<f64>();
        self.sim.model.derivatives(t, &mut c);
        let x_dot = M::derivatives_of(&c);
        let mut d = self.sim.model.continuous::<Dual64>();
        for ((vr, k), rate) in M::STATES.iter().zip(M::STATE_ELEMENTS).zip(x_dot.as_slice()) {
            if let Some(slot) = M::continuous_element(&mut d, *vr, *k as usize) {
                slot.eps = *rate;
            }
        }
        let t = Dual64::new(t, 1.0);
        self.sim.model.derivatives(t, &mut d);
        self.sim.model.outputs(t, &mut d);
        for (vr, slot) in vrs.iter().zip(out.iter_mut()) {
            let rate = M::continuous_slot(&mut d, *vr).map_or(0.0, |x| x.eps);
            if !rate.is_finite() {
                let name = M::declaration(*vr, VarType::Real).map_or("?", |v| v.name);
                return self.not_finite(
                    function,
                    &format!("the time derivative of '{name}' (vr {vr}) is {rate}"),
                );
            }
            *slot = rate;
        }
        OK
    }

    /// fmi2GetDirectionalDerivative: dv_unknown = (d unknowns / d knowns) dv_known, exact, by
    /// running the equations once on dual numbers seeded with dv_known. Knowns: the
    /// continuous states (model exchange) and the Real inputs; unknowns: what the equations
    /// compute (derivatives, outputs, locals), or a known itself. In Initialization Mode also
    /// the InitialUnknowns with respect to the knowns of that mode (inputs, parameters and
    /// start values with initial = exact: `super::initial_derivatives`). An array (FMI 3.0)
    /// counts each of its elements: `dv_known` holds one value per element of the knowns,
    /// row-major, `dv_unknown` one per element of the unknowns (the counting of FMI 3.0's nSeed
    /// and nSensitivity; a sized array's elements within its lengths now).
    pub fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        dv_known: &[f64],
        dv_unknown: &mut [f64],
    ) -> Status {
        let f = self.terms.name(Function::GetDirectionalDerivative);
        use num_dual::Dual64;
        let mut probe = self.sim.model.continuous::<f64>();
        let initialization = self.sim.state == State::InitializationMode;
        let mut at = 0;
        for vr in knowns {
            let Some((decl, n)) = self.derivative_declaration(*vr, initialization) else {
                return self.error(&format!(
                    "{f}: known value reference {vr} is not a Real variable of {}",
                    M::DESCRIPTION.model_identifier
                ));
            };
            let is_state = M::STATES.contains(vr);
            let allowed = decl.causality == Causality::Input && decl.variability == Variability::Continuous
                || (is_state && self.model_exchange);
            let allowed = allowed && M::continuous_element(&mut probe, *vr, 0).is_some()
                || initialization && Self::is_initial_known(decl);
            if !allowed {
                return self.error(&format!(
                    "{f}: '{}' (vr {vr}) is not a known of the equations in {}: the knowns are the continuous Real inputs{}{}",
                    decl.name,
                    if self.model_exchange { "model exchange" } else { "co-simulation" },
                    if self.model_exchange { " and the continuous states" } else { "" },
                    if initialization {
                        ", and in Initialization Mode the Real inputs and the Real variables with initial = exact \
                         (parameters, start values) the InitialUnknowns depend on"
                    } else {
                        ""
                    }
                ));
            }
            for (i, dv) in dv_known.iter().skip(at).take(n).enumerate() {
                if !dv.is_finite() {
                    let what = if decl.is_array() {
                        format!(" element {i}")
                    } else {
                        String::new()
                    };
                    return self.error(&format!(
                        "{f}: dvKnown for '{}'{what} (vr {vr}) = {dv} is not finite",
                        decl.name
                    ));
                }
            }
            at += n;
        }
        for vr in unknowns {
            let Some((decl, _)) = self.derivative_declaration(*vr, initialization) else {
                return self.error(&format!(
                    "{f}: unknown value reference {vr} is not a Real variable of {}",
                    M::DESCRIPTION.model_identifier
                ));
            };
            // A discrete output is held between events: its derivative with respect to the
            // continuous knowns is 0 (answered below: it has no slot in the equations).
            let held = decl.causality == Causality::Output && decl.variability == Variability::Discrete;
            let initial_unknown = initialization && M::DESCRIPTION.is_initial_unknown(decl);
            if !held && !initial_unknown && M::continuous_element(&mut probe, *vr, 0).is_none() {
                return self.error(&format!(
                    "{f}: '{}' (vr {vr}) is not computed by the equations (a parameter, or not continuous){}: no derivative",
                    decl.name,
                    if initialization { " nor an InitialUnknown" } else { "" }
                ));
            }
        }
        if initialization {
            if let Err(status) = self.initialize_model(f, false) {
                return status;
            }
            return self.initial_directional_derivative(f, unknowns, knowns, dv_known, dv_unknown);
        }
        let model = &self.sim.model;
        let elements = |vr: u32| {
            let decl = M::variable_index(vr).map(|i| &M::DESCRIPTION.variables[i]);
            let n = decl.map_or(1, |d| crate::step::structural::element_count(model, d));
            (0..n).map(move |i| decl.map_or(i, |d| crate::step::structural::storage_index(model, d, i)))
        };
        let mut c = model.continuous::<Dual64>();
        let mut seed = dv_known.iter();
        for vr in knowns {
            for k in elements(*vr) {
                let dv = seed.next().copied().unwrap_or(0.0);
                if let Some(slot) = M::continuous_element(&mut c, *vr, k) {
                    slot.eps += dv;
                }
            }
        }
        let t = Dual64::from(self.sim.time);
        model.derivatives(t, &mut c);
        model.outputs(t, &mut c);
        let mut out = dv_unknown.iter_mut();
        for vr in unknowns {
            for k in elements(*vr) {
                let d = M::continuous_element(&mut c, *vr, k).map_or(0.0, |d| d.eps);
                if !d.is_finite() {
                    let name = M::declaration(*vr, VarType::Real).map_or("?", |v| v.name);
                    return self.not_finite(f, &format!("the derivative of '{name}' (vr {vr}) is {d}"));
                }
                if let Some(slot) = out.next() {
                    *slot = d;
                }
            }
        }
        OK
    }
}
