use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    #[variable(vr = 1, input, max_size = 8)]
    pub x: f64,
}

fn main() {}
