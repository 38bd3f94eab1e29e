use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// a parameter
    #[variable(vr = 1, parameter, start = 1.0)]
    pub k: f64,
    /// an output
    #[variable(vr = 2, output, depends = [k])]
    pub y: f64,
}

fn main() {}
