//! The co-simulation step (fmi2DoStep, fmi3DoStep): its arguments checked, the model's step
//! run in a [`Context`] the step fills ([`crate::step`] integrates), and its outcome: the new
//! time, an event for the importer's Event Mode, an early return, or a discarded step with
//! every variable back where it was.

use super::{Instance, Outcome};
use crate::core::logging::Category;
use crate::core::machine::State;
use crate::core::{DISCARD, Function, OK, Status, Version};
use crate::model::{CoSimulation, Context, ReturnAtEvents};
use crate::step::{evaluate, non_finite, oversized_binary};

impl<M: CoSimulation> Instance<M> {
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

    /// fmi2DoStep's and fmi3DoStep's arguments: a finite step that advances time, from the
    /// instance's time, not past the stop time.
    #[inline]
    fn check_step(&self, f: &str, t: f64, h: f64) -> Outcome {
        if !(h.is_finite() && h > 0.0) {
            return Err(self.error(&format!(
                "{f}: communicationStepSize = {h} must be finite and > 0; time stays {}",
                self.sim.time
            )));
        }
        if !t.is_finite() || !self.time_matches(t, h) {
            return Err(self.error(&format!(
                "{f}: currentCommunicationPoint = {t} does not match the FMU's time {}",
                self.sim.time
            )));
        }
        let end = t + h;
        if end <= t {
            return Err(self.error(&format!(
                "{f}: communicationStepSize = {h} is too small to advance time from {t}"
            )));
        }
        if let Some(stop) = self.sim.stop_time
            && end > stop + 1e-8 * stop.abs().max(h)
        {
            return Err(self.error(&format!(
                "{f}: the step from {t} by {h} ends after stopTime = {stop} set in {}",
                self.terms.name(Function::SetupExperiment)
            )));
        }
        Ok(())
    }

    pub fn do_step(&mut self, t: f64, h: f64) -> Status {
        let f = self.terms.name(Function::DoStep);
        if let Err(status) = self.check_step(f, t, h) {
            return status;
        }
        let end = t + h;
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

    /// fmi3EnterStepMode (co-simulation with event mode): the events handled, stepping resumes.
    pub fn enter_step_mode(&mut self) -> Status {
        self.end_ticks();
        self.sim.state = State::StepComplete;
        self.sim.events.initial = false;
        self.sim.solver.restart();
        self.step_event = false;
        OK
    }
}
