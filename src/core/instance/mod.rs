//! One FMU instance of either FMI version: the state check, argument checks, and the calls into
//! the model, worded in the instance's [`Terms`]. Safe Rust: the C boundary (pointers, panics)
//! is in [`super::guard`] and the C layers.
//!
//! One `impl Instance` per concern, each in its own file, the lower ones first (each uses only
//! what is above it in this list): this file, the instance and what every call needs (the state
//! check, messages, looking up a variable); `evaluation`, the equations and the initialization
//! brought up to date before a value leaves; `events`, Event Mode, clocks and Scheduled
//! Execution; `lifecycle`, setup, initialization, terminate and reset; `get` and `set`,
//! the values of variables (with `checks`, the rules every value passes); `co_simulation`,
//! the communication step; `model_exchange`, the vectors an importer's integrator reads and
//! writes; `derivatives`, directional and output derivatives. The model's own step (the
//! integrator, event location, the structural mask) is `crate::step`'s, below all of this.

use super::logging::{Category, Logger};
use super::machine::{Call, State, contains, state_names};
use super::{ERROR, FATAL, OK, Status, Terms, Version};
use crate::description::{VarType, Variable};
use crate::model::{CoSimulation, Context, EventClock, StateVector};
use std::ffi::CString;

mod checks;
mod co_simulation;
mod derivatives;
mod evaluation;
mod events;
mod get;
mod lifecycle;
mod model_exchange;
mod set;
mod sim;

pub use checks::check_restored;
pub use sim::Sim;

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

    /// The instance's state and the context a model's hooks run in outside a communication step
    /// (initialization, an event, a parameter change: no integrator, the instance's logger),
    /// borrowed together so that the model can change while the context is held.
    pub(crate) fn sim_and_context(&mut self) -> (&mut Sim<M>, Context<'_>) {
        let ctx = Context::outside_step(
            self.sim.start_time,
            self.sim.tolerance,
            Some(&self.logger),
            self.resources.as_deref(),
            self.model_exchange,
        );
        (&mut self.sim, ctx)
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
}
