use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// speed
    #[variable(vr = 1, input, unit = "furlong/fortnight")]
    pub v: f64,
}

fn main() {}
