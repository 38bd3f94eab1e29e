use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// a state
    #[variable(vr = 1, output, initial = exact, start = 0.0)]
    pub x: f64,
    /// its derivative
    #[variable(vr = 2, name = "der(x)", local, derivative_of = x)]
    pub der_x: f64,
    /// another one
    #[variable(vr = 3, local, derivative_of = x)]
    pub der_x_again: f64,
}

fn main() {}
