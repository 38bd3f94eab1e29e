//! Issue 26: FMI 2.0 input derivatives (fmi2SetRealInputDerivatives, canInterpolateInputs). A
//! model whose step is the runtime's integrator declares `CoSimulation::INTERPOLATES_INPUTS`;
//! over a step from t_c each input with a derivative is u + du (t - t_c), and is u + du h at the
//! step's end. Exported here with `export_fmi2!`: x' = u, y = x + u.

use rustfmu::__private::abi::*;

use rustfmu::testing::fmi2;

mod model {
    use rustfmu::prelude::*;

    /// An integrator.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    pub struct Integrator {
        /// the input
        #[variable(vr = 1, input, continuous, start = 0.0)]
        pub u: f64,
        /// the state
        #[variable(vr = 2, output, continuous, start = 0.0, initial = exact, depends = [])]
        pub x: f64,
        /// its derivative
        #[variable(vr = 3, local, continuous, derivative_of = x, depends = [u])]
        pub der_x: f64,
        /// x + u
        #[variable(vr = 4, output, continuous, depends = [x, u])]
        pub y: f64,
        /// a discrete input
        #[variable(vr = 5, input, discrete, start = 0)]
        pub n: i32,
    }

    impl Model for Integrator {
        fn derivatives<D: Real>(&self, _t: D, v: &mut IntegratorContinuous<D>) {
            v.der_x = v.u;
        }
        fn outputs<D: Real>(&self, _t: D, v: &mut IntegratorContinuous<D>) {
            v.y = v.x + v.u;
        }
    }

    impl CoSimulation for Integrator {
        const INTERPOLATES_INPUTS: bool = true;
        fn tolerances(&self, _ctx: &Context) -> rustfmu::solver::Tolerances {
            rustfmu::solver::Tolerances {
                rtol: 1e-12,
                atol: 1e-14,
            }
        }
    }

    rustfmu::export_fmi2!(Integrator);
}
use model::__rustfmu_fmi2_exports as e2;

fn last(log: &rustfmu::testing::Log) -> String {
    log.entries().last().map(|e| e.text.clone()).unwrap_or_default()
}

/// An initialized instance with a log of its own: the tests run on threads at once, and the last
/// message of a log they shared could be another test's.
fn initialized() -> (fmi2Component, &'static rustfmu::testing::Log) {
    let log = rustfmu::testing::Log::leak();
    let c = fmi2::cs_instance(e2::fmi2Instantiate, e2::GUID, c"integrator", log);
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(e2::fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
        assert_eq!(e2::fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(e2::fmi2ExitInitializationMode(c), fmi2OK);
    }
    (c, log)
}

fn get(c: fmi2Component, vr: u32) -> f64 {
    let mut x = f64::NAN;
    // SAFETY: a live instance; locals.
    assert_eq!(unsafe { e2::fmi2GetReal(c, &vr, 1, &mut x) }, fmi2OK);
    x
}

#[test]
fn the_step_follows_the_input_derivative_and_ends_at_its_value() {
    let (c, _) = initialized();
    // SAFETY: a live instance; locals.
    unsafe {
        assert_eq!(e2::fmi2SetReal(c, &1, 1, &1.0), fmi2OK);
        assert_eq!(e2::fmi2SetRealInputDerivatives(c, &1, 1, &1, &2.0), fmi2OK);
        assert_eq!(e2::fmi2DoStep(c, 0.0, 0.5, fmi2True), fmi2OK);
    }
    // x(0.5) = u h + du h^2 / 2 = 0.5 + 0.25; u at the step's end 1 + 2 h = 2; y = x + u.
    assert!((get(c, 2) - 0.75).abs() < 1e-12, "{}", get(c, 2));
    assert_eq!(get(c, 1), 2.0);
    assert!((get(c, 4) - 2.75).abs() < 1e-12);
    // The derivative holds: the next step continues the ramp from u = 2 (x += 2 h + h^2).
    // SAFETY: a live instance.
    assert_eq!(unsafe { e2::fmi2DoStep(c, 0.5, 0.5, fmi2True) }, fmi2OK);
    assert!((get(c, 2) - 2.0).abs() < 1e-12, "{}", get(c, 2));
    assert_eq!(get(c, 1), 3.0);
    // 0 ends it: the input is held.
    // SAFETY: a live instance; locals.
    unsafe {
        assert_eq!(e2::fmi2SetRealInputDerivatives(c, &1, 1, &1, &0.0), fmi2OK);
        assert_eq!(e2::fmi2DoStep(c, 1.0, 0.5, fmi2True), fmi2OK);
    }
    assert!((get(c, 2) - 3.5).abs() < 1e-12, "{}", get(c, 2));
    assert_eq!(get(c, 1), 3.0);
    // SAFETY: a live instance.
    unsafe { e2::fmi2FreeInstance(c) };
}

/// A call on an instance, for the table of refusals.
type Call = Box<dyn Fn(fmi2Component) -> fmi2Status>;

#[test]
fn bad_input_derivatives_are_refused_with_the_reason() {
    let cases: [(&str, Call); 5] = [
        (
            "0 is not allowed",
            // SAFETY: the live instance the loop passes; one reference, order and value.
            Box::new(|c| unsafe { e2::fmi2SetRealInputDerivatives(c, &1, 1, &0, &1.0) }),
        ),
        (
            "is no continuous Real input",
            // SAFETY: the live instance the loop passes; one reference, order and value.
            Box::new(|c| unsafe { e2::fmi2SetRealInputDerivatives(c, &2, 1, &1, &1.0) }),
        ),
        (
            "is not finite",
            // SAFETY: the live instance the loop passes; one reference, order and value.
            Box::new(|c| unsafe { e2::fmi2SetRealInputDerivatives(c, &1, 1, &1, &f64::NAN) }),
        ),
        (
            "value reference 99",
            // SAFETY: the live instance the loop passes; one reference, order and value.
            Box::new(|c| unsafe { e2::fmi2SetRealInputDerivatives(c, &99, 1, &1, &1.0) }),
        ),
        (
            "is NULL",
            // SAFETY: the live instance the loop passes; one reference, order and value.
            Box::new(|c| unsafe { e2::fmi2SetRealInputDerivatives(c, std::ptr::null(), 1, &1, &1.0) }),
        ),
    ];
    for (why, call) in cases {
        let (c, log) = initialized();
        assert_eq!(call(c), fmi2Error, "{why}");
        assert!(last(log).contains(why), "'{}' does not say '{why}'", last(log));
        // Refused: the step holds the input.
        // SAFETY: a live instance.
        unsafe { e2::fmi2FreeInstance(c) };
    }
}

#[test]
fn a_higher_order_is_ignored_with_a_warning() {
    let (c, log) = initialized();
    // SAFETY: a live instance; locals (two inputs' worth: u's first and second derivative).
    unsafe {
        assert_eq!(e2::fmi2SetReal(c, &1, 1, &1.0), fmi2OK);
        let (vrs, orders, values) = ([1, 1], [1, 2], [2.0, 5.0]);
        assert_eq!(
            e2::fmi2SetRealInputDerivatives(c, vrs.as_ptr(), 2, orders.as_ptr(), values.as_ptr()),
            fmi2Warning
        );
        assert!(last(log).contains("order 2 of vr 1 ignored"), "{}", last(log));
        assert_eq!(e2::fmi2DoStep(c, 0.0, 0.5, fmi2True), fmi2OK);
    }
    // The first derivative was taken: x = 0.75 as without the second.
    assert!((get(c, 2) - 0.75).abs() < 1e-12, "{}", get(c, 2));
    // SAFETY: a live instance.
    unsafe { e2::fmi2FreeInstance(c) };
}

#[test]
fn the_description_says_it_can_interpolate_inputs() {
    use rustfmu::Variables;
    use rustfmu::description::{Interfaces, decode, encode_to_vec};
    let both = Interfaces {
        can_interpolate_inputs: <model::Integrator as rustfmu::CoSimulation>::INTERPOLATES_INPUTS,
        scheduled_execution: false,
        ..Interfaces::BOTH
    };
    let (_, back) = decode(&encode_to_vec(&model::Integrator::DESCRIPTION, both)).unwrap();
    assert!(
        back.can_interpolate_inputs,
        "the flag survives the encoding cargo fmu reads"
    );
    let (_, plain) = decode(&encode_to_vec(&model::Integrator::DESCRIPTION, Interfaces::BOTH)).unwrap();
    assert!(!plain.can_interpolate_inputs);
}
