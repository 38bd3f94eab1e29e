//! Issue 26: exact output derivatives (fmi2GetRealOutputDerivatives, fmi3GetOutputDerivatives;
//! maxOutputDerivativeOrder = 1), from the equations in dual numbers: time at rate 1, each state
//! at its derivative, inputs held. A model exported here with `export_fmu!` (both versions):
//! x' = -x + u, y = 2 x + sin(t) u, so dy/dt = 2 (-x + u) + cos(t) u.

use rustfmu::__private::abi::*;
use rustfmu::__private::abi3 as v3;
use rustfmu::testing::thread_log as log;
use std::ffi::CString;

use rustfmu::testing::fmi2;

mod model {
    use rustfmu::prelude::*;

    /// A lag and an output that depends on time.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    pub struct Lag {
        /// the input
        #[variable(vr = 1, input, continuous, start = 0.5)]
        pub u: f64,
        /// the state
        #[variable(vr = 2, output, continuous, start = 1.0, initial = exact, depends = [])]
        pub x: f64,
        /// its derivative
        #[variable(vr = 3, local, continuous, derivative_of = x, depends = [x, u])]
        pub der_x: f64,
        /// 2 x + sin(t) u
        #[variable(vr = 4, output, continuous, depends = [x, u])]
        pub y: f64,
        /// a gain (not an output)
        #[variable(vr = 5, parameter, fixed, start = 2.0)]
        pub k: f64,
        /// a discrete output
        #[variable(vr = 6, output, discrete, depends = [])]
        pub n: f64,
    }

    impl Model for Lag {
        fn derivatives<D: Real>(&self, _t: D, v: &mut LagContinuous<D>) {
            v.der_x = -v.x + v.u;
        }
        fn outputs<D: Real>(&self, t: D, v: &mut LagContinuous<D>) {
            v.y = v.x * self.k + t.sin() * v.u;
        }
    }

    impl CoSimulation for Lag {}

    rustfmu::export_fmu!(Lag);
}
use model::{__rustfmu_fmi2_exports as e2, __rustfmu_fmi3_exports as e3};

fn last() -> String {
    log().last()
}

fn expected(x: f64, u: f64, t: f64) -> f64 {
    2.0 * (-x + u) + t.cos() * u
}

#[test]
fn fmi2_output_derivatives_are_those_of_the_equations() {
    let c = fmi2::cs_instance(e2::fmi2Instantiate, e2::GUID, c"lag", log());
    // SAFETY: a live instance; each array as long as its count.
    unsafe {
        assert_eq!(e2::fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
        assert_eq!(e2::fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(e2::fmi2ExitInitializationMode(c), fmi2OK);
        let mut out = [f64::NAN; 3];
        let (vrs, orders) = ([2, 4, 6], [1, 1, 1]);
        for k in 0..5 {
            let t = 0.3 * k as f64;
            if k > 0 {
                assert_eq!(e2::fmi2DoStep(c, t - 0.3, 0.3, fmi2True), fmi2OK);
            }
            assert_eq!(
                e2::fmi2GetRealOutputDerivatives(c, vrs.as_ptr(), 3, orders.as_ptr(), out.as_mut_ptr()),
                fmi2OK
            );
            let mut x = 0.0;
            assert_eq!(e2::fmi2GetReal(c, &2, 1, &mut x), fmi2OK);
            assert_eq!(out[0], -x + 0.5, "dx/dt at t = {t}");
            assert!(
                (out[1] - expected(x, 0.5, t)).abs() < 1e-15,
                "dy/dt at t = {t}: {out:?}"
            );
            assert_eq!(out[2], 0.0, "a discrete output is held");
        }
        // The input changes the derivatives at once.
        assert_eq!(e2::fmi2SetReal(c, &1, 1, &2.0), fmi2OK);
        assert_eq!(e2::fmi2GetRealOutputDerivatives(c, &4, 1, &1, out.as_mut_ptr()), fmi2OK);
        let mut x = 0.0;
        assert_eq!(e2::fmi2GetReal(c, &2, 1, &mut x), fmi2OK);
        assert!((out[0] - expected(x, 2.0, 1.2)).abs() < 1e-15);

        // Refusals: order 2, not an output, NULL arrays; nothing written.
        out = [7.0; 3];
        assert_eq!(
            e2::fmi2GetRealOutputDerivatives(c, &4, 1, &2, out.as_mut_ptr()),
            fmi2Error
        );
        assert!(last().contains("order 2 for 'y' (vr 4)"), "{}", last());
        assert_eq!(
            e2::fmi2GetRealOutputDerivatives(c, &5, 1, &1, out.as_mut_ptr()),
            fmi2Error
        );
        assert!(
            last().contains("'k' (vr 5) is a Parameter, not an output"),
            "{}",
            last()
        );
        assert_eq!(
            e2::fmi2GetRealOutputDerivatives(c, &4, 1, std::ptr::null(), out.as_mut_ptr()),
            fmi2Error
        );
        assert_eq!(out, [7.0; 3]);
        e2::fmi2FreeInstance(c);
    }
}

#[test]
fn fmi3_output_derivatives_are_those_of_the_equations() {
    let token = CString::new(e3::TOKEN).unwrap();
    // SAFETY: valid strings; no logger; each array as long as its count.
    unsafe {
        let c = e3::fmi3InstantiateCoSimulation(
            c"lag3".as_ptr(),
            token.as_ptr(),
            std::ptr::null(),
            false,
            false,
            false,
            false,
            std::ptr::null(),
            0,
            std::ptr::null_mut(),
            None,
            None,
        );
        assert!(!c.is_null());
        assert_eq!(
            e3::fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0),
            fmi3_ok()
        );
        assert_eq!(e3::fmi3ExitInitializationMode(c), fmi3_ok());
        let (mut a, mut b, mut d, mut last) = (false, false, false, 0.0);
        assert_eq!(
            e3::fmi3DoStep(c, 0.0, 0.7, false, &mut a, &mut b, &mut d, &mut last),
            fmi3_ok()
        );
        let mut out = [f64::NAN; 2];
        assert_eq!(
            e3::fmi3GetOutputDerivatives(c, [2, 4].as_ptr(), 2, [1, 1].as_ptr(), out.as_mut_ptr(), 2),
            fmi3_ok()
        );
        let mut x = 0.0;
        assert_eq!(e3::fmi3GetFloat64(c, &2, 1, &mut x, 1), fmi3_ok());
        assert_eq!(out[0], -x + 0.5);
        assert!((out[1] - expected(x, 0.5, 0.7)).abs() < 1e-15, "{out:?}");
        // nValues must count one value per reference.
        assert_ne!(
            e3::fmi3GetOutputDerivatives(c, [2, 4].as_ptr(), 2, [1, 1].as_ptr(), out.as_mut_ptr(), 3),
            fmi3_ok()
        );
        e3::fmi3FreeInstance(c);
    }
}

fn fmi3_ok() -> v3::fmi3Status {
    v3::fmi3OK
}
