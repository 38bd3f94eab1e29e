use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// a misspelt causality
    #[variable(vr = 1, inptu)]
    pub u: f64,
}

fn main() {}
