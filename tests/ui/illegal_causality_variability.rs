use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// an input cannot be fixed
    #[variable(vr = 1, input, fixed)]
    pub a: f64,
}

fn main() {}
