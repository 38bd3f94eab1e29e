// A continuous array state in a model that also exports FMI 2.0: the runtime offers arrays in
// the equations in FMI 3.0 only.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct Lags {
    /// The states
    #[variable(vr = 0, output, initial = exact, start = [0.0; 2])]
    pub x: [f64; 2],
    /// Their derivatives
    #[variable(vr = 2, name = "der(x)", local, derivative_of = x)]
    pub der_x: [f64; 2],
}

impl Model for Lags {}
impl CoSimulation for Lags {}

fn main() {}
