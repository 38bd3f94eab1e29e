//! [`Standalone`]: a model run the way the runtime runs it, outside any FMU.

use crate::model::{CoSimulation, Context, EventClock, StepFailure};
use crate::solver::Dopri5;

/// A model run outside any FMU the way the runtime runs it: its integrator memory, time, and
/// the equations evaluated after initialization and after every step. For tests and
/// benchmarks that call a model directly; results equal the FMU's to the bit.
#[derive(Debug, Clone)]
pub struct Standalone<M> {
    pub model: M,
    pub solver: Dopri5,
    pub time: f64,
    pub start_time: f64,
    pub tolerance: Option<f64>,
    /// The model's pending time event and event count.
    pub events: EventClock,
}

impl<M: CoSimulation> Standalone<M> {
    /// `model` (start values as set) at `start_time`, with the importer's `tolerance`.
    pub fn new(model: M, start_time: f64, tolerance: Option<f64>) -> Self {
        Standalone {
            model,
            solver: Dopri5::default(),
            time: start_time,
            start_time,
            tolerance,
            events: EventClock::default(),
        }
    }

    /// What fmi2ExitInitializationMode does: `Model::initialize`, then the equations.
    pub fn initialize(&mut self) -> Result<(), String> {
        let ctx = Context::standalone(self.start_time, self.tolerance);
        self.model.initialize(&ctx)?;
        self.solver.restart();
        self.time = self.start_time;
        self.refresh();
        self.events = EventClock {
            initial: true,
            ..EventClock::default()
        };
        let outcome = super::events::iterate(&mut self.model, &ctx, self.time, &mut self.events);
        self.events.initial = false;
        outcome.map(|_| ())
    }

    /// Recomputes what the equations compute (after inputs were changed by hand).
    pub fn refresh(&mut self) {
        super::evaluate(&mut self.model, self.time);
    }

    /// What fmi2DoStep does: [`CoSimulation::do_step`] from the current time over `h`, then
    /// the outputs.
    pub fn do_step(&mut self, h: f64) -> Result<(), StepFailure> {
        let t = self.time;
        let mut ctx = Context::standalone_with_solver(self.start_time, self.tolerance, &mut self.solver);
        ctx.events = Some(&mut self.events);
        let outcome = self.model.do_step(t, h, &mut ctx);
        let refreshed = ctx.refreshed;
        let reached = match &outcome {
            Ok(()) => t + h,
            Err(f) => f.reached_time,
        };
        if !refreshed {
            super::evaluate(&mut self.model, reached);
        }
        self.time = reached;
        outcome
    }
}
