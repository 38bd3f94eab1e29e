use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// a count has no nominal value
    #[variable(vr = 1, input, nominal = 10)]
    pub n: i32,
}

fn main() {}
