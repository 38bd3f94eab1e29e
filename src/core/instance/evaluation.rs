//! What the equations computed, brought up to date before a value leaves: the initialization in
//! Initialization Mode, else the equations once something they depend on changed; a result that
//! is not finite is refused and leaves nothing changed.

use super::{Instance, Outcome};
use crate::core::logging::Category;
use crate::core::machine::State;
use crate::core::{DISCARD, Status};
use crate::model::CoSimulation;
use crate::step::{evaluate, non_finite, oversized_binary};

impl<M: CoSimulation> Instance<M> {
    /// Brings the calculated variables up to date with what was set in initialization mode
    /// (always when `force`, else only if something was set since). All or nothing: when the
    /// model refuses, it is put back as it was, so a call answering ERROR changes nothing.
    pub(super) fn initialize_model(&mut self, function: &str, force: bool) -> Outcome {
        if !force && !self.sim.init_dirty {
            return Ok(());
        }
        let before = self.sim.model.clone();
        let (sim, ctx) = self.sim_and_context();
        let outcome = sim
            .model
            .initialize(&ctx)
            .map(|()| evaluate(&mut sim.model, sim.start_time))
            .and_then(
                |()| match non_finite(&sim.model).or_else(|| oversized_binary(&sim.model)) {
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

    /// Brings every computed variable up to date before values leave: the initialization in
    /// initialization mode, else the equations if something they depend on changed. A result
    /// that is not finite leaves nothing changed and is refused: DISCARD in model exchange
    /// (the standard's answer for "outside the model's domain, try a smaller step"), ERROR
    /// in co-simulation.
    pub(super) fn up_to_date(&mut self, function: &str) -> Outcome {
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

    pub(super) fn not_finite(&self, function: &str, what: &str) -> Status {
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
}
