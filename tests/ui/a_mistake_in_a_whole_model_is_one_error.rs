// Issue 23: a duplicated value reference in a model that is used (its impls, export_fmu!) gave the
// right error and then four "the trait bound `Msd: Variables` is not satisfied". One error here.
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// A mass-spring-damper
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct Msd {
    /// Position x
    #[variable(vr = 0, output, initial = exact, start = 0.1, depends = [x])]
    pub x: f64,
    /// Velocity v: the same value reference by mistake
    #[variable(vr = 0, output, initial = exact, start = 0.0, depends = [v])]
    pub v: f64,
    /// dx/dt = v
    #[variable(vr = 2, name = "der(x)", local, derivative_of = x, depends = [v])]
    pub der_x: f64,
    /// dv/dt = -x - 0.1 v
    #[variable(vr = 3, name = "der(v)", local, derivative_of = v, depends = [x, v])]
    pub der_v: f64,
}

impl Model for Msd {
    fn derivatives<D: Real>(&self, _t: D, c: &mut MsdContinuous<D>) {
        c.der_x = c.v;
        c.der_v = -c.x - c.v * 0.1;
    }
}

impl CoSimulation for Msd {}

rustfmu::export_fmu!(Msd);

fn main() {}
