//! The Reference-FMUs' Dahlquist (modelica/Reference-FMUs, `Dahlquist/`) written with rustfmu:
//! the same model identifier, variable names, value references, causalities, variabilities and
//! start values; the test equation der(x) = -k x, x(t) = exp(-k t).

use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// This model implements the Dahlquist test equation
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct Dahlquist {
    /// Simulation time
    #[variable(vr = 0, independent)]
    pub time: f64,
    /// the only state
    #[variable(vr = 1, output, continuous, initial = exact, start = 1.0, depends = [x])]
    pub x: f64,
    /// der(x) = -k x
    #[variable(vr = 2, name = "der(x)", local, derivative_of = x, depends = [x], initial_depends = [x, k])]
    pub der_x: f64,
    /// k
    #[variable(vr = 3, parameter, fixed, start = 1.0)]
    pub k: f64,
}

impl Model for Dahlquist {
    fn derivatives<D: Real>(&self, _t: D, v: &mut DahlquistContinuous<D>) {
        v.der_x = -(v.x * self.k);
    }
}

impl CoSimulation for Dahlquist {}

rustfmu::export_fmu!(Dahlquist);
