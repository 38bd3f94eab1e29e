use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
#[fmu(co_simulation_only, model_exchange_only)]
pub struct M {
    /// an input
    #[variable(vr = 1, input, start = 0.0)]
    pub u: f64,
}

fn main() {}
