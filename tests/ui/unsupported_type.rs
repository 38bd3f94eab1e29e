use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// a pointer-sized integer is no FMI type
    #[variable(vr = 1, input)]
    pub x: usize,
}

fn main() {}
