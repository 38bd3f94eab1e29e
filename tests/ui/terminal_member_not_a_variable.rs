use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
#[fmu(terminal(name = "flange", member(variable = phi, name = "phi"), member(variable = torque, name = "tau", kind = "inflow")))]
pub struct M {
    #[variable(vr = 1, output)]
    pub phi: f64,
}

fn main() {}
