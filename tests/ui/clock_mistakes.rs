// A clocked output that is continuous, and a Clock without its intervalVariability.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(fmi3_only)]
pub struct Sampled {
    /// Ticks every 0.1 s
    #[variable(vr = 0, input, clock(constant, interval = 0.1))]
    pub tick: Clock,
    /// Continuous, so it cannot be clocked
    #[variable(vr = 1, output, continuous, clocks = [tick])]
    pub y: f64,
}

impl Model for Sampled {}
impl CoSimulation for Sampled {}

fn main() {}
