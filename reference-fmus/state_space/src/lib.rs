//! The Reference-FMUs' StateSpace (modelica/Reference-FMUs v0.0.41, `StateSpace/`) written with
//! rustfmu: the same model identifier, variable names, value references, types, causalities,
//! variabilities and start values; a linear time-invariant system
//!
//!   dx/dt = A x + B u,   y = C x + D u,   x(0) = x0,
//!
//! with m inputs, n states and r outputs, the sizes being structural parameters an importer
//! changes in Configuration Mode (FMI 3.0 only: FMI 2.0 has no structural parameters). The
//! arrays hold up to 5 of each (the Reference-FMUs' M_MAX, N_MAX, R_MAX), which is `max` of m, n
//! and r; the model computes with the first m, n, r.
//!
//! Where this model differs from theirs on purpose (theirs is not what the equations say):
//! x starts at x0 (theirs at 0, whatever x0 is), B·u sums over the m inputs (theirs over r
//! columns, right only when m = r), and D·u over m (theirs too).

use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// The largest m, n and r: the arrays' capacity.
pub const MAX: usize = 5;

/// The identity of the capacity: the start of A, B, C and D (the identity of every size).
pub const IDENTITY: [[f64; MAX]; MAX] = {
    let mut a = [[0.0; MAX]; MAX];
    let mut i = 0;
    while i < MAX {
        a[i][i] = 1.0;
        i += 1;
    }
    a
};

/// This model implements a linear time-invariant (LTI) system
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(fmi3_only)]
pub struct StateSpace {
    /// Simulation time
    #[variable(vr = 0, independent)]
    pub time: f64,
    /// Number of inputs
    #[variable(vr = 1, structural_parameter, tunable, start = 3, min = 0, max = 5)]
    pub m: u64,
    /// Number of states
    #[variable(vr = 2, structural_parameter, tunable, start = 3, min = 0, max = 5)]
    pub n: u64,
    /// Number of outputs
    #[variable(vr = 3, structural_parameter, tunable, start = 3, min = 0, max = 5)]
    pub r: u64,
    /// Matrix coefficient A (n × n)
    #[variable(vr = 4, name = "A", parameter, tunable, dims = [n, n], start = IDENTITY)]
    pub a: [[f64; MAX]; MAX],
    /// Matrix coefficient B (n × m)
    #[variable(vr = 5, name = "B", parameter, tunable, dims = [n, m], start = IDENTITY)]
    pub b: [[f64; MAX]; MAX],
    /// Matrix coefficient C (r × n)
    #[variable(vr = 6, name = "C", parameter, tunable, dims = [r, n], start = IDENTITY)]
    pub c: [[f64; MAX]; MAX],
    /// Matrix coefficient D (r × m)
    #[variable(vr = 7, name = "D", parameter, tunable, dims = [r, m], start = IDENTITY)]
    pub d: [[f64; MAX]; MAX],
    /// Initial state vector
    #[variable(vr = 8, parameter, tunable, dims = [n], start = [0.0; MAX])]
    pub x0: [f64; MAX],
    /// Input vector
    #[variable(vr = 9, input, dims = [m], start = [1.0, 2.0, 3.0, 4.0, 5.0])]
    pub u: [f64; MAX],
    /// Output vector
    #[variable(vr = 10, output, dims = [r], depends = [u, x])]
    pub y: [f64; MAX],
    /// State vector
    #[variable(vr = 11, local, dims = [n], initial_depends = [x0])]
    pub x: [f64; MAX],
    /// Derivative of the state vector
    #[variable(vr = 12, name = "der(x)", local, derivative_of = x, dims = [n], depends = [u, x])]
    pub der_x: [f64; MAX],
}

/// A row of [P Q] times [x; u]: sum_j P_j x_j + sum_j Q_j u_j, over the states and inputs given
/// (the first n and m), in that order: row i of dx/dt with A, B, of y with C, D.
fn row_times<D: Real>(p: &[f64; MAX], x: &[D], q: &[f64; MAX], u: &[D]) -> D {
    let mut sum = D::from(0.0);
    for (j, &xj) in x.iter().enumerate() {
        sum += xj * p[j];
    }
    for (j, &uj) in u.iter().enumerate() {
        sum += uj * q[j];
    }
    sum
}

impl StateSpace {
    fn sizes(&self) -> (usize, usize, usize) {
        (self.m as usize, self.n as usize, self.r as usize)
    }
}

impl Model for StateSpace {
    /// x(0) = x0.
    fn initialize(&mut self, _ctx: &Context) -> Result<(), String> {
        self.x = self.x0;
        Ok(())
    }

    /// dx/dt = A x + B u.
    fn derivatives<D: Real>(&self, _t: D, v: &mut StateSpaceContinuous<D>) {
        let (m, n, _) = self.sizes();
        for i in 0..n {
            v.der_x[i] = row_times(&self.a[i], &v.x[..n], &self.b[i], &v.u[..m]);
        }
    }

    /// y = C x + D u.
    fn outputs<D: Real>(&self, _t: D, v: &mut StateSpaceContinuous<D>) {
        let (m, n, r) = self.sizes();
        for i in 0..r {
            v.y[i] = row_times(&self.c[i], &v.x[..n], &self.d[i], &v.u[..m]);
        }
    }
}

impl CoSimulation for StateSpace {}

rustfmu::export_fmi3!(StateSpace);
