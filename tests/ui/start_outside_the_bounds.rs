use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// must be positive, starts at 0
    #[variable(vr = 1, parameter, start = 0.0, min > 0.0)]
    pub k: f64,
}

fn main() {}
