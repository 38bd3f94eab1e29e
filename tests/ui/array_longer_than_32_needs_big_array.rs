// Only #[derive(Model)]'s messages are pinned here: serde's own errors about the same fields
// (which follow them in a real model) name serde's private paths, which change between its
// releases. tests/big_arrays.rs has a model with the attribute that compiles and runs.
use rustfmu::prelude::*;

const CELLS: usize = 40;

/// A heat rod of 50 cells, and an internal buffer whose length is a constant
#[derive(Model, Debug, Clone)]
#[fmu(fmi3_only)]
pub struct Rod {
    /// cell temperatures
    #[variable(vr = 1, parameter, fixed)]
    pub t: [f64; 50],
    /// 32 is serde's own
    #[variable(vr = 3, parameter, fixed)]
    pub k: [[f64; 32]; 2],
    /// rows longer than 32
    #[variable(vr = 4, parameter, fixed)]
    pub grid: [[f32; 33]; 2],
    pub buffer: [u8; CELLS],
}

fn main() {}
