//! Issue 25: structural parameters and Configuration Mode (FMI 3.0), arrays in the equations.
//! A chain of first-order lags whose number n is a tunable structural parameter: the state x
//! and the time constants tau are arrays of n (capacity 4); `k`, a fixed structural parameter,
//! sizes a parameter array w. Checked here through the C API of this test binary's export:
//! which variables are set in which mode, the element counts following the parameters, the
//! model-exchange state vector of n entries, directional and adjoint derivatives over array
//! elements, co-simulation against the exact solution, reconfiguration, the FMU state.

use rustfmu::__private::abi3::*;
use rustfmu::testing::Log;

#[macro_use]
mod common;

mod model {
    use rustfmu::prelude::*;

    /// dx_i/dt = (u - x_i) / tau_i, i < n; y = sum of x.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    #[fmu(fmi3_only)]
    pub struct Lags {
        /// number of lags
        #[variable(vr = 1, structural_parameter, tunable, start = 2, min = 0, max = 4)]
        pub n: u64,
        /// length of w
        #[variable(vr = 2, structural_parameter, fixed, start = 1, max = 3)]
        pub k: u64,
        /// time constants
        #[variable(vr = 3, parameter, tunable, dims = [n], start = [1.0, 2.0, 4.0, 8.0], min > 0.0, unit = "s")]
        pub tau: [f64; 4],
        /// weights (unused by the equations)
        #[variable(vr = 4, parameter, fixed, dims = [k], start = [0.5, 1.5, 2.5])]
        pub w: [f64; 3],
        /// the input
        #[variable(vr = 5, input, start = 1.0)]
        pub u: f64,
        /// the lags' states
        #[variable(vr = 6, output, dims = [n], initial = exact, start = [0.0; 4], depends = [x])]
        pub x: [f64; 4],
        /// their derivatives
        #[variable(vr = 7, name = "der(x)", local, derivative_of = x, dims = [n], depends = [u, x])]
        pub der_x: [f64; 4],
        /// sum of x
        #[variable(vr = 8, output, depends = [x])]
        pub y: f64,
    }

    impl Model for Lags {
        fn derivatives<D: Real>(&self, _t: D, v: &mut LagsContinuous<D>) {
            for i in 0..self.n as usize {
                v.der_x[i] = (v.u - v.x[i]) / self.tau[i];
            }
        }
        fn outputs<D: Real>(&self, _t: D, v: &mut LagsContinuous<D>) {
            let mut y = D::from(0.0);
            for i in 0..self.n as usize {
                y += v.x[i];
            }
            v.y = y;
        }
    }

    impl CoSimulation for Lags {}

    rustfmu::export_fmi3!(Lags);
}
use model::__rustfmu_fmi3_exports::*;

fmi3_instances!("lags");

fn get(c: fmi3Instance, vr: u32, n: usize) -> (fmi3Status, Vec<f64>) {
    let mut v = vec![f64::NAN; n];
    // SAFETY: an array of n values.
    let s = unsafe { fmi3GetFloat64(c, &vr, 1, v.as_mut_ptr(), n) };
    (s, v)
}

fn set_u64(c: fmi3Instance, vr: u32, value: u64) -> fmi3Status {
    // SAFETY: one value.
    unsafe { fmi3SetUInt64(c, &vr, 1, &value, 1) }
}

#[test]
fn the_description_names_the_structural_parameters_of_each_dimension() {
    let d = <model::Lags as rustfmu::Variables>::DESCRIPTION;
    assert!(d.has_structural_parameters() && d.has_sized_arrays());
    assert_eq!(d.by_name("tau").unwrap().fmi3.sized_by, &[1]);
    assert_eq!(d.by_name("tau").unwrap().fmi3.dimensions, &[4]);
    assert_eq!(d.by_name("w").unwrap().fmi3.sized_by, &[2]);
    assert!(!d.by_name("u").unwrap().is_sized());
    assert_eq!(<model::Lags as rustfmu::Variables>::STATES, &[6, 6, 6, 6]);
    assert_eq!(<model::Lags as rustfmu::Variables>::STATE_ELEMENTS, &[0, 1, 2, 3]);
}

/// A co-simulation instance with n = `n` (set in Configuration Mode).
fn configured(n: u64) -> (fmi3Instance, &'static Log) {
    let (c, log) = cs();
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(fmi3EnterConfigurationMode(c), fmi3OK);
        assert_eq!(set_u64(c, 1, n), fmi3OK);
        assert_eq!(fmi3ExitConfigurationMode(c), fmi3OK);
    }
    (c, log)
}

/// An FMI 3.0 call that fails leaves the instance in Terminated (FMI 3.0, 2.3.1): each refusal
/// is tried on its own instance.
fn refused(what: &str, make: impl Fn() -> (fmi3Instance, &'static Log), call: impl Fn(fmi3Instance) -> fmi3Status) {
    let (c, log) = make();
    assert_eq!(call(c), fmi3Error);
    assert!(log.last().contains(what), "{what}: {}", log.last());
    // SAFETY: a live instance.
    unsafe { fmi3FreeInstance(c) };
}

#[test]
fn structural_parameters_are_set_in_configuration_mode_and_nothing_else_is() {
    // SAFETY: for every call, a live instance, arrays of the lengths passed.
    unsafe {
        // In Instantiated: refused, with where it is set.
        refused("structural parameters are set in Configuration Mode", cs, |c| {
            set_u64(c, 1, 3)
        });
        // Two values of tau now.
        let (c, _) = cs();
        assert_eq!(get(c, 3, 2), (fmi3OK, vec![1.0, 2.0]));
        fmi3FreeInstance(c);
        refused("nValues = 4, but the 1 value references have 2 values", cs, |c| {
            get(c, 3, 4).0
        });
        let config = || {
            let (c, log) = cs();
            assert_eq!(fmi3EnterConfigurationMode(c), fmi3OK);
            (c, log)
        };
        // Beyond max (and the capacity): refused.
        refused("5 for 'n' (vr 1) is outside", config, |c| set_u64(c, 1, 5));
        // Nothing but structural parameters in Configuration Mode.
        refused("nothing else is set there", config, |c| {
            let tau = [1.0, 1.0];
            fmi3SetFloat64(c, &3, 1, tau.as_ptr(), 2)
        });
        // Not in Configuration Mode twice, and no initialization from it.
        refused("not allowed in state ConfigurationMode", config, |c| {
            fmi3EnterConfigurationMode(c)
        });
        refused("not allowed in state ConfigurationMode", config, |c| {
            fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0)
        });
        let (c, log) = config();
        assert_eq!(set_u64(c, 1, 3), fmi3OK);
        assert_eq!(set_u64(c, 2, 3), fmi3OK);
        assert_eq!(fmi3ExitConfigurationMode(c), fmi3OK);
        // Three values of tau, the start values of the capacity.
        assert_eq!(get(c, 3, 3), (fmi3OK, vec![1.0, 2.0, 4.0]));
        assert_eq!(get(c, 4, 3), (fmi3OK, vec![0.5, 1.5, 2.5]));
        let tau = [0.5, 0.25, 0.125];
        assert_eq!(fmi3SetFloat64(c, &3, 1, tau.as_ptr(), 3), fmi3OK);
        init(c);
        assert_eq!(get(c, 3, 3), (fmi3OK, tau.to_vec()));
        // A tunable structural parameter changes in Reconfiguration Mode (from Step Mode).
        assert_eq!(fmi3EnterConfigurationMode(c), fmi3OK, "{:?}", log.messages());
        assert_eq!(set_u64(c, 1, 1), fmi3OK);
        assert_eq!(fmi3ExitConfigurationMode(c), fmi3OK);
        assert_eq!(get(c, 3, 1), (fmi3OK, vec![0.5]));
        assert_eq!(get(c, 6, 1).0, fmi3OK);
        assert_eq!(
            fmi3DoStep(c, 0.0, 0.1, true, &mut false, &mut false, &mut false, &mut 0.0),
            fmi3OK
        );
        fmi3FreeInstance(c);
        // A fixed one does not.
        let stepping = || {
            let (c, log) = configured(3);
            init(c);
            assert_eq!(fmi3EnterConfigurationMode(c), fmi3OK);
            (c, log)
        };
        refused("cannot be set in state ReconfigurationMode", stepping, |c| {
            set_u64(c, 2, 1)
        });
    }
}

#[test]
fn co_simulation_integrates_the_n_lags_and_leaves_the_others_still() {
    let (c, log) = configured(3);
    // SAFETY: for every call, a live instance, arrays of the lengths passed.
    unsafe {
        init(c);
        let mut t = 0.0;
        for _ in 0..20 {
            let (mut a, mut b, mut e, mut l) = (false, false, false, 0.0);
            assert_eq!(fmi3DoStep(c, t, 0.1, true, &mut a, &mut b, &mut e, &mut l), fmi3OK);
            t += 0.1;
        }
        let (s, x) = get(c, 6, 3);
        assert_eq!(s, fmi3OK);
        for (x, tau) in x.iter().zip([1.0f64, 2.0, 4.0]) {
            let exact = 1.0 - (-t / tau).exp();
            assert!((x - exact).abs() < 1e-5, "{x} vs {exact}");
        }
        let (_, y) = get(c, 8, 1);
        assert!((y[0] - x.iter().sum::<f64>()).abs() < 1e-14);
        // The lag outside n did not move: seen again after a reconfiguration to n = 4.
        assert_eq!(fmi3EnterConfigurationMode(c), fmi3OK, "{:?}", log.messages());
        assert_eq!(set_u64(c, 1, 4), fmi3OK);
        assert_eq!(fmi3ExitConfigurationMode(c), fmi3OK);
        let (_, x4) = get(c, 6, 4);
        assert_eq!(x4[3], 0.0);
        assert_eq!(&x4[..3], &x[..]);
        fmi3FreeInstance(c);
    }
}

#[test]
fn model_exchange_has_n_states_and_exact_derivatives_over_the_elements() {
    // A model-exchange instance with n = 3 in Continuous-Time Mode.
    let make = || {
        let (c, log) = me();
        // SAFETY: a live instance.
        unsafe {
            assert_eq!(fmi3EnterConfigurationMode(c), fmi3OK);
            assert_eq!(set_u64(c, 1, 3), fmi3OK);
            assert_eq!(fmi3ExitConfigurationMode(c), fmi3OK);
            init(c);
            assert_eq!(fmi3EnterContinuousTimeMode(c), fmi3OK);
        }
        (c, log)
    };
    let (c, _) = make();
    // SAFETY: for every call, a live instance, arrays of the lengths passed.
    unsafe {
        let mut n = 0usize;
        assert_eq!(fmi3GetNumberOfContinuousStates(c, &mut n), fmi3OK);
        assert_eq!(n, 3);
        let x = [0.5, 0.25, -1.0];
        assert_eq!(fmi3SetContinuousStates(c, x.as_ptr(), 3), fmi3OK);
        refused("nx = 4, but Lags has 3 continuous states", make, |c| {
            fmi3SetContinuousStates(c, [0.0; 4].as_ptr(), 4)
        });
        let mut x4 = [0.0; 4];
        assert_eq!(fmi3GetContinuousStates(c, x4.as_mut_ptr(), 3), fmi3OK);
        assert_eq!(&x4[..3], &x);
        let mut dx = [0.0; 3];
        assert_eq!(fmi3GetContinuousStateDerivatives(c, dx.as_mut_ptr(), 3), fmi3OK);
        assert_eq!(dx, [(1.0 - 0.5) / 1.0, (1.0 - 0.25) / 2.0, (1.0 + 1.0) / 4.0]);
        let mut nominals = [0.0; 3];
        assert_eq!(fmi3GetNominalsOfContinuousStates(c, nominals.as_mut_ptr(), 3), fmi3OK);
        assert_eq!(nominals, [1.0; 3]);
        // d der(x) / d x: seeds and sensitivities one per element (nSeed = 3, nSensitivity = 3).
        let (unknown, known) = (7u32, 6u32);
        for j in 0..3 {
            let mut seed = [0.0; 3];
            seed[j] = 1.0;
            let mut out = [f64::NAN; 3];
            assert_eq!(
                fmi3GetDirectionalDerivative(c, &unknown, 1, &known, 1, seed.as_ptr(), 3, out.as_mut_ptr(), 3),
                fmi3OK
            );
            let tau = [1.0, 2.0, 4.0];
            let want: Vec<f64> = (0..3).map(|i| if i == j { -1.0 / tau[i] } else { 0.0 }).collect();
            assert_eq!(out.to_vec(), want);
        }
        // d (y, der(x)) / d (u, x): 4 sensitivities from 4 seeds.
        let (unknowns, knowns) = ([8u32, 7], [5u32, 6]);
        let seed = [1.0, 0.0, 1.0, 0.0];
        let mut out = [f64::NAN; 4];
        assert_eq!(
            fmi3GetDirectionalDerivative(
                c,
                unknowns.as_ptr(),
                2,
                knowns.as_ptr(),
                2,
                seed.as_ptr(),
                4,
                out.as_mut_ptr(),
                4
            ),
            fmi3OK
        );
        // du = 1, dx = (0, 1, 0): dy = 1, d der(x) = ((1 - 0) / 1, (1 - 1) / 2, (1 - 0) / 4).
        assert_eq!(out, [1.0, 1.0, 0.0, 0.25]);
        // A count that ignores the elements is refused with the counts.
        refused("an array counts each element", make, |c| {
            fmi3GetDirectionalDerivative(c, &unknown, 1, &known, 1, [1.0].as_ptr(), 1, [0.0].as_mut_ptr(), 1)
        });
        // The adjoint: Jᵀ w for J = d der(x) / d x = diag(-1/tau).
        let w = [1.0, 2.0, 4.0];
        let mut out = [f64::NAN; 3];
        assert_eq!(
            fmi3GetAdjointDerivative(c, &unknown, 1, &known, 1, w.as_ptr(), 3, out.as_mut_ptr(), 3),
            fmi3OK
        );
        assert_eq!(out, [-1.0, -1.0, -1.0]);
        // Reconfiguration from Event Mode: n = 1 state.
        assert_eq!(fmi3EnterEventMode(c), fmi3OK);
        assert_eq!(fmi3EnterConfigurationMode(c), fmi3OK);
        assert_eq!(set_u64(c, 1, 1), fmi3OK);
        assert_eq!(fmi3ExitConfigurationMode(c), fmi3OK);
        assert_eq!(fmi3GetNumberOfContinuousStates(c, &mut n), fmi3OK);
        assert_eq!(n, 1);
        let mut x1 = [0.0];
        assert_eq!(fmi3GetContinuousStates(c, x1.as_mut_ptr(), 1), fmi3OK);
        assert_eq!(x1, [0.5]);
        fmi3FreeInstance(c);
    }
}

#[test]
fn an_fmu_state_carries_the_structural_parameters() {
    let (c, log) = cs();
    // SAFETY: for every call, a live instance, arrays of the lengths passed.
    unsafe {
        init(c);
        let mut state: fmi3FMUState = std::ptr::null_mut();
        assert_eq!(fmi3GetFMUState(c, &mut state), fmi3OK, "{:?}", log.messages());
        assert_eq!(fmi3EnterConfigurationMode(c), fmi3OK, "{:?}", log.messages());
        assert_eq!(set_u64(c, 1, 4), fmi3OK);
        assert_eq!(fmi3ExitConfigurationMode(c), fmi3OK);
        assert_eq!(get(c, 3, 4).0, fmi3OK);
        assert_eq!(fmi3SetFMUState(c, state), fmi3OK);
        assert_eq!(get(c, 3, 2), (fmi3OK, vec![1.0, 2.0]));
        assert_eq!(get(c, 3, 4).0, fmi3Error);
        assert_eq!(fmi3FreeFMUState(c, &mut state), fmi3OK);
        fmi3FreeInstance(c);
        // No FMU state is taken in the middle of a configuration.
        let reconfiguring = || {
            let (c, log) = initialized();
            assert_eq!(fmi3EnterConfigurationMode(c), fmi3OK);
            (c, log)
        };
        refused("not allowed in state ReconfigurationMode", reconfiguring, |c| {
            let mut state: fmi3FMUState = std::ptr::null_mut();
            fmi3GetFMUState(c, &mut state)
        });
    }
}
