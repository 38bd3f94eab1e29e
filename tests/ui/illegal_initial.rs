use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// a parameter is exact
    #[variable(vr = 1, parameter, initial = calculated)]
    pub k: f64,
}

fn main() {}
