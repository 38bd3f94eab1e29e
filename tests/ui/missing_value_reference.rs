use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// no vr
    #[variable(input)]
    pub u: f64,
}

fn main() {}
