use rustfmu::prelude::*;

#[derive(Model, Clone, serde::Serialize, serde::Deserialize)]
pub struct M {
    /// a parameter cannot change sign between events
    #[variable(vr = 1, parameter, start = 1.0, event_indicator)]
    pub k: f64,
}

fn main() {}
