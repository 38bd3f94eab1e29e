//! A first-order lag, T dy/dt = u - y, as an FMU. `cargo fmu build` packages it as
//! `target/fmu/{{Model}}.fmu`.

use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// A first-order lag: T dy/dt = u - y
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct {{Model}} {
    /// Input u
    #[variable(vr = 0, input, start = 0.0)]
    pub u: f64,
    /// Output y; its start value is the initial state
    #[variable(vr = 1, output, initial = exact, start = 0.0, depends = [])]
    pub y: f64,
    /// Time constant T
    #[variable(vr = 2, name = "T", parameter, tunable, start = 0.1, unit = "s", min > 0.0)]
    pub time_constant: f64,
}

impl Model for {{Model}} {}

impl CoSimulation for {{Model}} {
    /// The exact solution for an input held over the step: y(t + h) = u + (y(t) - u) e^(-h/T).
    fn do_step(&mut self, _t: f64, h: f64, _ctx: &Context) -> Result<(), StepFailure> {
        self.y = self.u + (self.y - self.u) * (-h / self.time_constant).exp();
        Ok(())
    }
}

rustfmu::export_fmi2!({{Model}});

#[cfg(test)]
mod tests {
    use super::*;
    use rustfmu::Variables;

    #[test]
    fn a_unit_step_rises_to_63_percent_after_one_time_constant() {
        let mut lag = {{Model}}::start();
        lag.u = 1.0;
        let ctx = Context::standalone(0.0, None);
        let h = 0.001;
        for k in 0..100 {
            lag.do_step(k as f64 * h, h, &ctx).unwrap();
        }
        let expected = 1.0 - (-1.0f64).exp();
        assert!((lag.y - expected).abs() < 1e-12, "y(T) = {}, expected {expected}", lag.y);
    }
}
