use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// single precision is no FMI 2.0 type
    #[variable(vr = 1, input)]
    pub x: f32,
}

fn main() {}
