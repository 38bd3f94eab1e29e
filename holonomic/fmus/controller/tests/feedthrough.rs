//! When the Controller's outputs follow its inputs: at once by default (direct feedthrough, the
//! paper's continuous state feedback), one communication step later with `sampled = true` (a
//! digital controller with computation delay; in model exchange the samples are time events).

mod common;
use common::*;
use controller_fmu::__rustfmu_fmi2_exports::{
    fmi2EnterContinuousTimeMode, fmi2EnterEventMode, fmi2NewDiscreteStates, fmi2SetTime,
};
use rustfmu::__private::abi::*;

const STATE: [&str; 4] = ["alpha1", "omega1", "alpha2", "omega2"];
const K: [&str; 8] = ["K11", "K12", "K13", "K14", "K21", "K22", "K23", "K24"];

fn set_state(c: &Fmu, x: [f64; 4]) {
    let values: Vec<(&str, f64)> = STATE.iter().copied().zip(x).collect();
    assert_eq!(c.set(&values), fmi2OK, "{:?}", c.messages());
}

/// The LQR law of the instance's own gain, -K x.
fn lqr(c: &Fmu, x: [f64; 4]) -> [f64; 2] {
    let k = c.get(&K);
    [0, 1].map(|i| -(0..4).map(|j| k[4 * i + j] * x[j]).sum::<f64>())
}

fn assert_torques(c: &Fmu, want: [f64; 2], when: &str) {
    let m = c.get(&["M1", "M2"]);
    let ok = (0..2).all(|i| (m[i] - want[i]).abs() <= 1e-12 * (1.0 + want[i].abs()));
    assert!(ok, "{when}: expected (M1, M2) = {want:?}, got {m:?}");
}

const X0: [f64; 4] = [0.1, 0.0, -0.05, 0.0];
const X1: [f64; 4] = [0.02, -0.3, 0.01, 0.2];
const X2: [f64; 4] = [-0.01, 0.1, 0.03, -0.4];

#[test]
fn outputs_follow_the_inputs_set_at_the_same_communication_point() {
    let mut c = Fmu::new();
    set_state(&c, X0);
    assert_eq!(c.exit_init(), fmi2OK, "{:?}", c.messages());
    assert_torques(&c, lqr(&c, X0), "after initialization from x0");
    set_state(&c, X1);
    assert_torques(&c, lqr(&c, X1), "x1 set at t = 0");
    assert_eq!(c.step(1e-3), fmi2OK);
    assert_torques(&c, lqr(&c, X1), "after a step, inputs unchanged");
    set_state(&c, X2);
    assert_torques(&c, lqr(&c, X2), "x2 set at t = 1 ms");
}

#[test]
fn sampled_outputs_come_from_the_inputs_of_the_previous_communication_point() {
    let mut c = Fmu::new();
    assert_eq!(c.set_boolean("sampled", true), fmi2OK);
    set_state(&c, X0);
    assert_eq!(c.exit_init(), fmi2OK, "{:?}", c.messages());
    assert_torques(&c, lqr(&c, X0), "after initialization from x0");
    set_state(&c, X1);
    assert_torques(
        &c,
        lqr(&c, X0),
        "x1 set at t = 0: still the sample taken at initialization",
    );
    assert_eq!(c.step(1e-3), fmi2OK);
    assert_torques(&c, lqr(&c, X1), "t = 1 ms: the inputs held at t = 0");
    set_state(&c, X2);
    assert_torques(&c, lqr(&c, X1), "x2 set at t = 1 ms: still the inputs of t = 0");
    assert_eq!(c.step(1e-3), fmi2OK);
    assert_torques(&c, lqr(&c, X2), "t = 2 ms: the inputs held at t = 1 ms");
    let held = c.get(&["alpha1_sample", "omega1_sample", "alpha2_sample", "omega2_sample"]);
    assert_eq!(held, X2.to_vec(), "the sample held at t = 1 ms");
}

/// fmi2NewDiscreteStates: (status, nextEventTime if defined, valuesOfContinuousStatesChanged).
fn new_discrete_states(c: &Fmu) -> (fmi2Status, Option<f64>, bool) {
    let mut info = fmi2EventInfo {
        newDiscreteStatesNeeded: 0,
        terminateSimulation: 0,
        nominalsOfContinuousStatesChanged: 0,
        valuesOfContinuousStatesChanged: 0,
        nextEventTimeDefined: 0,
        nextEventTime: 0.0,
    };
    // SAFETY: a live instance and a writable event info.
    let s = unsafe { fmi2NewDiscreteStates(c.c, &mut info) };
    (
        s,
        (info.nextEventTimeDefined == fmi2True).then_some(info.nextEventTime),
        info.valuesOfContinuousStatesChanged == fmi2True,
    )
}

#[test]
fn sampled_model_exchange_samples_on_time_events_every_ts() {
    let c = Fmu::instantiate(fmi2ModelExchange);
    assert_eq!(c.set_boolean("sampled", true), fmi2OK);
    assert_eq!(c.set(&[("Ts", 0.02)]), fmi2OK);
    set_state(&c, X0);
    assert_eq!(c.exit_init(), fmi2OK, "{:?}", c.messages());
    // The initial event: the first sample at Ts; the outputs use the measurement of the start.
    assert_eq!(new_discrete_states(&c), (fmi2OK, Some(0.02), false));
    // SAFETY: a live instance.
    assert_eq!(unsafe { fmi2EnterContinuousTimeMode(c.c) }, fmi2OK);
    set_state(&c, X1);
    assert_torques(&c, lqr(&c, X0), "x1 set between the samples: still the sample of t = 0");
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(fmi2SetTime(c.c, 0.02), fmi2OK);
        assert_eq!(fmi2EnterEventMode(c.c), fmi2OK);
    }
    // The sample at Ts: the outputs now use the measurement of the previous sample (x0, one
    // sample of delay), and x1 waits for the next one.
    let (s, next, _) = new_discrete_states(&c);
    assert_eq!((s, next), (fmi2OK, Some(0.04)), "{:?}", c.messages());
    assert_torques(&c, lqr(&c, X0), "at the first sample: the measurement of t = 0");
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(fmi2EnterContinuousTimeMode(c.c), fmi2OK);
        assert_eq!(fmi2SetTime(c.c, 0.04), fmi2OK);
        assert_eq!(fmi2EnterEventMode(c.c), fmi2OK);
    }
    assert_eq!(new_discrete_states(&c).1, Some(0.06));
    assert_torques(&c, lqr(&c, X1), "at the second sample: the measurement of the first");
}

#[test]
fn model_exchange_outputs_follow_the_inputs() {
    let c = Fmu::instantiate(fmi2ModelExchange);
    set_state(&c, X0);
    assert_eq!(c.exit_init(), fmi2OK, "{:?}", c.messages());
    set_state(&c, X1);
    assert_torques(&c, lqr(&c, X1), "model exchange, x1 set in event mode");
}
