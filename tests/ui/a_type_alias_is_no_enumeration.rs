use rustfmu::prelude::*;

type Real = f64;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// an alias is read as an enumeration: refused
    #[variable(vr = 1, parameter, start = 0.5)]
    pub k: Real,
}

fn main() {}
