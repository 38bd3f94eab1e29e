use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// a UInt8 cannot reach 300
    #[variable(vr = 1, input, discrete, fmi3_only, max = 300)]
    pub x: u8,
}

fn main() {}
