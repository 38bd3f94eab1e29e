use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// an input
    #[variable(vr = 1, input)]
    pub u: f64,
    /// its derivative?
    #[variable(vr = 2, local, derivative_of = u)]
    pub der_u: f64,
}

fn main() {}
