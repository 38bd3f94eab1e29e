//! Issue 52, item 3: arrays of more than 32 elements (serde derives up to 32; the FMU state
//! serializes the model). A heat rod of n cells, n a structural parameter with a capacity of 50,
//! and a weight per cell of a 100-element parameter array, through this test binary's FMI 3.0
//! functions: the cells against the exact solution in co-simulation for n = 50 and n = 20,
//! the derivatives of all 50 in model exchange, and the FMU state (taken, serialized,
//! deserialized, restored) with every element.

use rustfmu::__private::abi3::*;
use rustfmu::testing::{Log, fmi3};

#[macro_use]
mod common;

mod model {
    use rustfmu::prelude::*;

    /// A rod of n cells: dT_i/dt = a (T_{i-1} - 2 T_i + T_{i+1}), T_{-1} = u (the heated left
    /// end), T_n = T_{n-1} (the right end insulated).
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    #[fmu(fmi3_only)]
    pub struct Rod {
        /// number of cells
        #[variable(vr = 1, structural_parameter, tunable, start = 50, min = 1, max = 50)]
        pub n: u64,
        /// conductance between cells over a cell's capacity
        #[variable(vr = 2, parameter, fixed, start = 100.0, min > 0.0, unit = "1/s")]
        pub a: f64,
        /// temperature of the left end
        #[variable(vr = 3, input, start = 1.0)]
        pub u: f64,
        /// cell temperatures
        #[variable(vr = 4, name = "T", output, dims = [n], initial = exact, start = [0.0; 50], depends = [t])]
        #[serde(with = "rustfmu::BigArray")]
        pub t: [f64; 50],
        /// their derivatives
        #[variable(vr = 5, name = "der(T)", local, derivative_of = t, dims = [n], depends = [u, t])]
        #[serde(with = "rustfmu::BigArray")]
        pub der_t: [f64; 50],
        /// a weight for each cell (of more than the rod may have)
        #[variable(vr = 6, parameter, tunable, start = [1.0; 100])]
        #[serde(with = "rustfmu::BigArray")]
        pub w: [f64; 100],
        /// sum of w_i T_i over the cells
        #[variable(vr = 7, output, depends = [t])]
        pub y: f64,
    }

    impl Model for Rod {
        fn derivatives<D: Real>(&self, _t: D, v: &mut RodContinuous<D>) {
            let n = self.n as usize;
            let a = D::from(self.a);
            for i in 0..n {
                let left = if i == 0 { v.u } else { v.t[i - 1] };
                let right = if i + 1 == n { v.t[i] } else { v.t[i + 1] };
                v.der_t[i] = a * (left - v.t[i] * 2.0 + right);
            }
        }
        fn outputs<D: Real>(&self, _t: D, v: &mut RodContinuous<D>) {
            let mut y = D::from(0.0);
            for i in 0..self.n as usize {
                y += v.t[i] * self.w[i];
            }
            v.y = y;
        }
    }

    impl CoSimulation for Rod {}

    rustfmu::export_fmi3!(Rod);
}
use model::__rustfmu_fmi3_exports::*;

fmi3_serialized_states!();

const A: f64 = 100.0;

/// The slowest mode of a rod of n cells: v_i = sin(θ (i + 1)), θ = π / (2n + 1) (zero at the
/// left end's ghost cell, equal at the insulated right end), decaying at
/// λ = 4 a sin²(θ / 2). T_i(t) = u - e^{-λ t} v_i solves the equations exactly.
fn mode(n: usize) -> (Vec<f64>, f64) {
    let theta = std::f64::consts::PI / (2 * n + 1) as f64;
    let v = (0..n).map(|i| (theta * (i + 1) as f64).sin()).collect();
    (v, 4.0 * A * (theta / 2.0).sin().powi(2))
}

fn get(c: fmi3Instance, vr: u32, count: usize) -> Vec<f64> {
    let mut x = vec![f64::NAN; count];
    // SAFETY: an array of `count` values.
    assert_eq!(unsafe { fmi3GetFloat64(c, &vr, 1, x.as_mut_ptr(), count) }, fmi3OK);
    x
}

fn set(c: fmi3Instance, vr: u32, values: &[f64]) -> fmi3Status {
    // SAFETY: an array of values.len() values.
    unsafe { fmi3SetFloat64(c, &vr, 1, values.as_ptr(), values.len()) }
}

/// Configured with `n` cells, in Initialization Mode (tolerance 1e-10), each cell at the
/// slowest mode's start.
fn started(c: fmi3Instance, log: &Log, n: usize) {
    // SAFETY: a live instance.
    unsafe {
        if n != 50 {
            assert_eq!(fmi3EnterConfigurationMode(c), fmi3OK, "{}", log.last());
            assert_eq!(fmi3SetUInt64(c, &1, 1, &(n as u64), 1), fmi3OK, "{}", log.last());
            assert_eq!(fmi3ExitConfigurationMode(c), fmi3OK, "{}", log.last());
        }
        assert_eq!(fmi3EnterInitializationMode(c, true, 1e-10, 0.0, false, 0.0), fmi3OK);
    }
    let (v, _) = mode(n);
    let start: Vec<f64> = v.iter().map(|v| 1.0 - v).collect();
    assert_eq!(set(c, 4, &start), fmi3OK, "{}", log.last());
}

#[test]
fn a_rod_of_50_and_of_20_cells_follows_its_exact_solution_in_co_simulation() {
    for n in [50, 20] {
        let (c, log) = fmi3::instance(fmi3InstantiateCoSimulation, TOKEN, "rod");
        started(c, log, n);
        let (v, lambda) = mode(n);
        let (mut event, mut terminate, mut early, mut reached) = (false, false, false, 0.0);
        // SAFETY: for every call, a live instance, output arguments that are locals.
        unsafe {
            assert_eq!(fmi3ExitInitializationMode(c), fmi3OK, "{}", log.last());
            for k in 0..10 {
                let t = 0.1 * k as f64;
                let status = fmi3DoStep(c, t, 0.1, true, &mut event, &mut terminate, &mut early, &mut reached);
                assert_eq!(status, fmi3OK, "{}", log.last());
            }
        }
        let cells = get(c, 4, n);
        let decay = (-lambda * 1.0).exp();
        for (i, (cell, v)) in cells.iter().zip(&v).enumerate() {
            let exact = 1.0 - decay * v;
            assert!((cell - exact).abs() < 1e-8, "n = {n}, T[{i}] = {cell}, exact {exact}");
        }
        // y weighs every cell by 1.
        let y = get(c, 7, 1)[0];
        assert!((y - cells.iter().sum::<f64>()).abs() < 1e-12, "{y}");
        // SAFETY: a live instance.
        unsafe { fmi3FreeInstance(c) };
    }
}

#[test]
fn model_exchange_has_50_states_and_their_exact_derivatives() {
    let (c, log) = fmi3::me_instance(fmi3InstantiateModelExchange, TOKEN, "rod");
    started(c, log, 50);
    let (v, lambda) = mode(50);
    // SAFETY: for every call, a live instance, arrays of the lengths passed.
    unsafe {
        assert_eq!(fmi3ExitInitializationMode(c), fmi3OK, "{}", log.last());
        let mut count = 0usize;
        assert_eq!(fmi3GetNumberOfContinuousStates(c, &mut count), fmi3OK);
        assert_eq!(count, 50);
        let mut der = vec![f64::NAN; 50];
        assert_eq!(fmi3GetContinuousStateDerivatives(c, der.as_mut_ptr(), 50), fmi3OK);
        for (i, (d, v)) in der.iter().zip(&v).enumerate() {
            assert!((d - lambda * v).abs() < 1e-9, "der(T)[{i}] = {d}, exact {}", lambda * v);
        }
        fmi3FreeInstance(c);
    }
}

#[test]
fn the_fmu_state_carries_every_element_of_the_long_arrays() {
    let (c, log) = fmi3::instance(fmi3InstantiateCoSimulation, TOKEN, "rod");
    started(c, log, 50);
    let mut weights: Vec<f64> = (0..100).map(|i| 0.5 + i as f64).collect();
    assert_eq!(set(c, 6, &weights), fmi3OK, "{}", log.last());
    let (mut event, mut terminate, mut early, mut reached) = (false, false, false, 0.0);
    // SAFETY: for every call, a live instance, output arguments that are locals, buffers of the
    // sizes passed.
    unsafe {
        assert_eq!(fmi3ExitInitializationMode(c), fmi3OK, "{}", log.last());
        assert_eq!(
            fmi3DoStep(c, 0.0, 0.5, true, &mut event, &mut terminate, &mut early, &mut reached),
            fmi3OK
        );
        let at_half = get(c, 4, 50);
        let bytes = serialized_state(c, log);
        let size = bytes.len();
        assert!(
            size > 200 * 8,
            "a state of {size} bytes cannot hold 200 Float64 elements"
        );

        // Move on and change the weights; then back to the deserialized state.
        assert_eq!(
            fmi3DoStep(c, 0.5, 0.5, true, &mut event, &mut terminate, &mut early, &mut reached),
            fmi3OK
        );
        assert_ne!(get(c, 4, 50), at_half);
        assert_eq!(set(c, 6, &[2.0; 100]), fmi3OK, "{}", log.last());
        set_serialized_state(c, &bytes, log);
        assert_eq!(get(c, 4, 50), at_half);
        assert_eq!(get(c, 6, 100), weights);
        let y = get(c, 7, 1)[0];
        let expected: f64 = at_half.iter().zip(&weights).map(|(t, w)| t * w).sum();
        assert!((y - expected).abs() < 1e-9 * expected.abs(), "{y} vs {expected}");
        // The last element is the state's too.
        weights[99] = -1.0;
        assert_eq!(set(c, 6, &weights), fmi3OK);
        assert_eq!(get(c, 6, 100)[99], -1.0);
        fmi3FreeInstance(c);
    }
}
