use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
#[fmu(fmi3_only)]
pub struct M {
    #[variable(vr = 1, input, discrete)]
    pub frame: Vec<u8>,
}

impl Model for M {}
impl CoSimulation for M {}

// export_fmu! exports FMI 2.0 too, which this model has declared it has not.
rustfmu::export_fmu!(M);

fn main() {}
