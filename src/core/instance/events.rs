//! Event Mode (the event iteration the importer drives), FMI 3.0 clocks (a clocked variable
//! read or written only while its clock ticks; the tick evaluated before
//! fmi3UpdateDiscreteStates when a clocked value is read first) and Scheduled Execution
//! (fmi3ActivateModelPartition).

use super::{EventInfo, Instance, Outcome};
use crate::core::machine::State;
use crate::core::{Function, OK, Status};
use crate::description::{Causality, Variable};
use crate::model::CoSimulation;
use crate::step::oversized_binary;

impl<M: CoSimulation> Instance<M> {
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
    pub(super) fn clocked_access(&self, function: &str, decl: &Variable, setting: bool) -> Outcome {
        let clocks = decl.fmi3.clocks;
        let names = || clocks.iter().map(|c| format!("'{c}'")).collect::<Vec<_>>().join(", ");
        match self.sim.state {
            State::Instantiated | State::InitializationMode => Ok(()),
            // Scheduled Execution: a partition's clocked inputs are set before its activation and
            // its clocked outputs read after it (FMI 3.0, 5.2: between activations, and in the
            // clockUpdate callback).
            State::ClockActivationMode => Ok(()),
            State::ClockUpdateMode if !setting => Ok(()),
            // A clocked input set after the tick was evaluated: the setter took the evaluation
            // back first ([`Instance::reopen_tick`]).
            State::EventMode if clocks.iter().any(|c| self.clock_active(c)) => Ok(()),
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
    pub(super) fn evaluate_tick_for(&mut self, function: &str, vrs: &[u32]) -> Outcome {
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

    /// Before an input is set in Event Mode after the active clocks' tick was evaluated (a
    /// clocked variable read, a clock asked for, or fmi3EvaluateDiscreteStates): the evaluation is
    /// taken back (the model and its clock as before it, kept in `tick_before`), so that the next
    /// clocked read or fmi3UpdateDiscreteStates evaluates the tick again with the new value, and
    /// the event's round is still taken once. FMI 3.0.2 §3.2.1: "during Initialization, Event
    /// Mode, and Continuous-Time Mode, input variables can be set with fmi3Set{VariableType} and
    /// output variables can be retrieved with fmi3Get{VariableType} interchangeably according to
    /// the model structure", and a set "re-initialize[s] caching of variables that depend on these
    /// variables". (Refused before: an importer that reads a node's Tx_Data, then sets the inputs
    /// it depends on, FMU Manipulation Toolbox's container, stopped there.)
    pub(super) fn reopen_tick(&mut self) {
        if self.sim.state != State::EventMode || self.evaluated_tick.is_none() {
            return;
        }
        if let Some(before) = &self.tick_before {
            (self.sim.model, self.sim.events) = (before.0.clone(), before.1);
            self.evaluated_tick = None;
            self.sim.stale_outputs = true;
            self.sim.stale_derivatives = true;
            self.trace(|| {
                format!(
                    "an input set after the tick at t = {} was evaluated: evaluated again when read",
                    self.sim.time
                )
            });
        }
    }

    /// The clocks' activity ends with the event's update (FMI 3.0, 2.2.9: "Any Clock active
    /// during fmi3UpdateDiscreteStates must be deactivated by the FMU itself"), or with Event Mode.
    pub(super) fn end_ticks(&mut self) {
        if M::DESCRIPTION.has_clocks() {
            self.sim.model.deactivate_clocks();
            // (`tick_before` keeps its allocation for the next tick; without an evaluated tick
            // it means nothing.)
            self.evaluated_tick = None;
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
    pub(super) fn event_iteration(&mut self, function: &str, info: &mut EventInfo, all_rounds: bool) -> Status {
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
        let (sim, ctx) = self.sim_and_context();
        let time = sim.time;
        let outcome = if all_rounds {
            crate::step::events::iterate(&mut sim.model, &ctx, time, &mut sim.events).map(|(changed, terminate)| {
                crate::step::events::Round {
                    again: false,
                    terminate,
                    states_changed: changed,
                }
            })
        } else {
            crate::step::events::update_round(&mut sim.model, &ctx, time, &mut sim.events)
        };
        let outcome = outcome.and_then(|round| match oversized_binary(&sim.model) {
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
}
