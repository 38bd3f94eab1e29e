use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// a
    #[variable(vr = 1, input)]
    pub a: f64,
    /// b
    #[variable(vr = 1, output)]
    pub b: f64,
}

fn main() {}
