//! The Reference-FMUs' Stair (modelica/Reference-FMUs, `Stair/`) written with rustfmu: the same
//! model identifier, variable names, value references, causalities, variabilities and start
//! values; a counter that time events increment every second, from 1 to 10, when the model asks
//! to end the simulation.

use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// This model generates a stair signal using time events
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct Stair {
    /// Simulation time
    #[variable(vr = 0, independent)]
    pub time: f64,
    /// counts the seconds
    #[variable(vr = 1, output, discrete, initial = exact, start = 1, max = 10)]
    pub counter: i32,
}

impl Model for Stair {
    fn update(&mut self, event: &mut Event) -> Result<(), String> {
        if event.time_event() {
            self.counter += 1;
        }
        if self.counter >= 10 {
            event.terminate(format!(
                "the counter reached {} at t = {} s",
                self.counter,
                event.time()
            ));
        }
        // The next whole second.
        event.schedule(event.time().floor() + 1.0);
        Ok(())
    }
}

impl CoSimulation for Stair {}

rustfmu::export_fmu!(Stair);
