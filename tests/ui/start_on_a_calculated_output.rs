use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// calculated: no start value
    #[variable(vr = 1, output, start = 1.0)]
    pub y: f64,
}

fn main() {}
