//! The Reference-FMUs' VanDerPol (modelica/Reference-FMUs, `VanDerPol/`) written with rustfmu:
//! the same model identifier, variable names, value references, causalities, variabilities and
//! start values; the van der Pol oscillator der(x0) = x1, der(x1) = mu (1 - x0^2) x1 - x0.

use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// This model implements the van der Pol oscillator
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct VanDerPol {
    /// Simulation time
    #[variable(vr = 0, independent)]
    pub time: f64,
    /// the first state
    #[variable(vr = 1, output, continuous, initial = exact, start = 2.0, depends = [x0])]
    pub x0: f64,
    /// der(x0) = x1
    #[variable(vr = 2, name = "der(x0)", local, derivative_of = x0, depends = [x1], initial_depends = [x1])]
    pub der_x0: f64,
    /// the second state
    #[variable(vr = 3, output, continuous, initial = exact, start = 0.0, depends = [x1])]
    pub x1: f64,
    /// der(x1) = mu (1 - x0^2) x1 - x0
    #[variable(vr = 4, name = "der(x1)", local, derivative_of = x1, depends = [x0, x1], initial_depends = [x0, x1, mu])]
    pub der_x1: f64,
    /// mu
    #[variable(vr = 5, parameter, fixed, start = 1.0)]
    pub mu: f64,
}

impl Model for VanDerPol {
    fn derivatives<D: Real>(&self, _t: D, v: &mut VanDerPolContinuous<D>) {
        v.der_x0 = v.x1;
        v.der_x1 = (-(v.x0 * v.x0) + 1.0) * v.x1 * self.mu - v.x0;
    }
}

impl CoSimulation for VanDerPol {}

rustfmu::export_fmu!(VanDerPol);
