// A structural parameter in a model that also exports FMI 2.0, which has none.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct Sized {
    /// Number of gains
    #[variable(vr = 0, structural_parameter, start = 2, max = 4)]
    pub n: u64,
    /// Gains
    #[variable(vr = 1, parameter, fixed, dims = [n], start = [1.0; 4])]
    pub k: [f64; 4],
}

impl Model for Sized {}
impl CoSimulation for Sized {}

fn main() {}
