use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// an Integer is never continuous
    #[variable(vr = 1, input, continuous)]
    pub n: i32,
}

fn main() {}
