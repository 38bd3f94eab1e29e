//! Issue 49: an event storm is bounded and leaves the FMU where it was.
//!
//! The random call sequences of CI set BouncingBall's unbounded `g` to -2.249e194 and stepped
//! 4.4 ms: the ball bounces every ~1e-12 s (the event tolerance) with a speed that never falls,
//! and one fmi2DoStep took 25–32 s to reach the runtime's 100,000 events, then answered
//! fmi2Discard with h = -3.8e168 and v = -5.8e181: the ball far below the floor, inside the
//! storm. Now a step stops at `MAX_EVENTS_PER_STEP` events and at the integrator's `max_steps`
//! for the whole step, and a step refused at either bound ends right after the last event it
//! handled: every variable finite, the ball on or above the floor, `lastSuccessfulTime` that
//! event's time. (What one such call costs is measured by `bench/python/step_bound.py`, not here:
//! tests assert behaviour.)

use rustfmu::__private::abi::*;

use rustfmu::testing::{fmi2, thread_log as log};

mod model {
    use rustfmu::prelude::*;

    /// The Reference-FMUs' BouncingBall, as reference-fmus/bouncing_ball has it.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    pub struct Ball {
        /// Height
        #[variable(vr = 1, output, continuous, initial = exact, start = 1.0, unit = "m", depends = [h], event_indicator)]
        pub h: f64,
        /// dh/dt
        #[variable(vr = 2, name = "der(h)", local, derivative_of = h, unit = "m/s", depends = [v], initial_depends = [v])]
        pub der_h: f64,
        /// Velocity
        #[variable(vr = 3, output, continuous, initial = exact, start = 0.0, unit = "m/s", depends = [v])]
        pub v: f64,
        /// dv/dt
        #[variable(vr = 4, name = "der(v)", local, derivative_of = v, unit = "m/s2", depends = [], initial_depends = [g])]
        pub der_v: f64,
        /// Gravity (unbounded, as in the Reference)
        #[variable(vr = 5, parameter, fixed, start = -9.81, unit = "m/s2")]
        pub g: f64,
        /// Coefficient of restitution
        #[variable(vr = 6, parameter, tunable, start = 0.7, min = 0.5, max = 1.0)]
        pub e: f64,
        /// At rest on the floor
        pub resting: bool,
    }

    impl Model for Ball {
        fn derivatives<D: Real>(&self, _t: D, x: &mut BallContinuous<D>) {
            let g = if self.resting { 0.0 } else { self.g };
            x.der_h = x.v;
            x.der_v = x.v * 0.0 + g;
        }

        fn update(&mut self, _event: &mut Event) -> Result<(), String> {
            if self.h <= 0.0 && self.v < 0.0 {
                self.h = f64::MIN_POSITIVE;
                self.v *= -self.e;
                if self.v < 0.1 {
                    self.v = 0.0;
                    self.resting = true;
                }
            }
            Ok(())
        }
    }

    impl CoSimulation for Ball {}

    rustfmu::export_fmi2!(Ball);
}
use model::__rustfmu_fmi2_exports::*;

/// A co-simulation ball with gravity `g`, initialized.
fn ball(g: f64) -> fmi2Component {
    let c = fmi2::cs_instance(fmi2Instantiate, GUID, c"ball", log());
    // SAFETY: a live instance, one value.
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(fmi2SetReal(c, &5, 1, &g), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK);
    }
    c
}

fn reals(c: fmi2Component) -> [f64; 6] {
    let vrs = [1, 2, 3, 4, 5, 6];
    let mut out = [f64::NAN; 6];
    // SAFETY: a live instance, six value references and slots.
    assert_eq!(unsafe { fmi2GetReal(c, vrs.as_ptr(), 6, out.as_mut_ptr()) }, fmi2OK);
    out
}

#[test]
fn a_chattering_step_is_discarded_after_the_last_event_it_handled_with_every_value_finite_and_physical() {
    let c = ball(-2.249e194);
    // SAFETY: a live instance.
    let status = unsafe { fmi2DoStep(c, 0.0, 0.0044, fmi2True) };
    assert_eq!(status, fmi2Discard);
    let said = log().texts().last().map(|(_, m)| m.clone()).unwrap_or_default();
    // Whichever bound comes first: here the integrator's steps (one or a few between bounces).
    assert!(
        said.contains("internal steps of the integrator in one communication step")
            || said.contains("events in one step (chattering") && said.contains("after the last event handled"),
        "{said}"
    );
    let [h, der_h, v, der_v, g, e] = reals(c);
    assert!(
        [h, der_h, v, der_v, g, e].iter().all(|x| x.is_finite()),
        "{:?}",
        [h, der_h, v, der_v, g, e]
    );
    // Right after a bounce: on the floor, going up.
    assert!(h >= 0.0 && v >= 0.0, "h = {h}, v = {v}");
    let mut last = f64::NAN;
    // SAFETY: a live instance, one slot.
    let status = unsafe { fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &mut last) };
    assert_eq!(status, fmi2OK);
    assert!((0.0..0.0044).contains(&last), "lastSuccessfulTime {last}");
    // SAFETY: a live instance.
    unsafe { fmi2FreeInstance(c) };
}

#[test]
fn a_bouncing_ball_with_earths_gravity_still_comes_to_rest_in_one_long_step() {
    // The bound is far above what a physical ball needs: 1 m, e = 0.7, at rest after ~16
    // bounces in 2.6 s.
    let c = ball(-9.81);
    // SAFETY: a live instance.
    let status = unsafe { fmi2DoStep(c, 0.0, 3.0, fmi2True) };
    assert_eq!(status, fmi2OK, "{:?}", log().texts().last());
    let [h, _, v, ..] = reals(c);
    assert!((0.0..1e-6).contains(&h) && v == 0.0, "h = {h}, v = {v}");
    // SAFETY: a live instance.
    unsafe { fmi2FreeInstance(c) };
}
