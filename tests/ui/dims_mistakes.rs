// `dims` naming what is no u64 structural parameter, a structural parameter without max, and
// a max beyond the array's length.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(fmi3_only)]
pub struct NotStructural {
    /// Number of gains
    #[variable(vr = 0, parameter, fixed, start = 2)]
    pub n: u64,
    /// Gains
    #[variable(vr = 1, parameter, fixed, dims = [n], start = [1.0; 4])]
    pub k: [f64; 4],
}
impl Model for NotStructural {}
impl CoSimulation for NotStructural {}

#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(fmi3_only)]
pub struct NoMax {
    /// Number of gains
    #[variable(vr = 0, structural_parameter, start = 2)]
    pub n: u64,
    /// Gains
    #[variable(vr = 1, parameter, fixed, dims = [n], start = [1.0; 4])]
    pub k: [f64; 4],
}
impl Model for NoMax {}
impl CoSimulation for NoMax {}

#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(fmi3_only)]
pub struct BeyondCapacity {
    /// Number of gains
    #[variable(vr = 0, structural_parameter, start = 2, max = 5)]
    pub n: u64,
    /// Gains
    #[variable(vr = 1, parameter, fixed, dims = [n], start = [1.0; 4])]
    pub k: [f64; 4],
}
impl Model for BeyondCapacity {}
impl CoSimulation for BeyondCapacity {}

fn main() {}
