// A Clock in a model that also exports FMI 2.0, which has no clocks.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct Sampled {
    /// Ticks every Ts
    #[variable(vr = 0, input, clock(fixed, interval = Ts))]
    pub tick: Clock,
    /// Sample period
    #[variable(vr = 1, name = "Ts", parameter, fixed, start = 0.1, unit = "s")]
    pub ts: f64,
}

impl Model for Sampled {}
impl CoSimulation for Sampled {}

fn main() {}
