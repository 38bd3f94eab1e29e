// Scheduled Execution without fmi3_only, without an input clock, and with a clock without a
// priority.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(scheduled_execution)]
pub struct NotFmi3Only {
    /// Counts
    #[variable(vr = 1, output, discrete)]
    pub n: i32,
}
impl Model for NotFmi3Only {}
impl CoSimulation for NotFmi3Only {}

#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(fmi3_only, scheduled_execution)]
pub struct NoInputClock {
    /// Counts
    #[variable(vr = 1, output, discrete)]
    pub n: i32,
}
impl Model for NoInputClock {}
impl CoSimulation for NoInputClock {}

#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(fmi3_only, scheduled_execution)]
pub struct NoPriority {
    /// Ticks every second
    #[variable(vr = 0, input, clock(constant, interval = 1.0))]
    pub tick: Clock,
    /// Counts the ticks
    #[variable(vr = 1, output, discrete, clocks = [tick])]
    pub n: i32,
}
impl Model for NoPriority {}
impl CoSimulation for NoPriority {}

fn main() {}
