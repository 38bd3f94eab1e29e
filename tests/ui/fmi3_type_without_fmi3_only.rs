use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// FMI 2.0 has no Int64: the variable or the model must say it is FMI 3.0 only
    #[variable(vr = 1, input, discrete)]
    pub count: i64,
}

fn main() {}
