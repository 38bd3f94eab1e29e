//! What an FMU state snapshot holds: the model and the runtime's own bookkeeping.

use crate::core::machine::State;
use crate::model::{CoSimulation, EventClock};
use crate::solver::Dopri5;
use serde::{Deserialize, Serialize};

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
