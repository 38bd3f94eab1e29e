use rustfmu::prelude::*;

#[derive(FmuEnum, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub enum Mode {
    /// one
    A = 1,
}

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// a mode
    #[variable(vr = 1, parameter)]
    pub mode: Mode,
}

fn main() {}
