//! An instance's life: debug logging, the experiment's setup, Initialization Mode and its end
//! (the initial event iteration), terminate and reset.

use super::{EventInfo, Instance, Sim};
use crate::core::machine::State;
use crate::core::{Function, OK, Status};
use crate::model::{CoSimulation, EventClock};

impl<M: CoSimulation> Instance<M> {
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
}
