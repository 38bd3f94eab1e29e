//! When the Controller's outputs follow its inputs: at once by default (direct feedthrough, the
//! paper's continuous state feedback), one communication step later with `sampled = true` (a
//! digital controller with computation delay), which model exchange refuses.

mod common;
use common::*;
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

#[test]
fn sampled_is_refused_in_model_exchange() {
    let c = Fmu::instantiate(fmi2ModelExchange);
    assert_eq!(c.set_boolean("sampled", true), fmi2OK);
    let status = c.exit_init();
    let messages = c.messages();
    assert_ne!(status, fmi2OK, "model exchange accepted sampled = true: {messages:?}");
    assert!(
        messages
            .iter()
            .any(|(_, m)| m.contains("sampled = true") && m.contains("model exchange")),
        "the refusal should name sampled and model exchange: {messages:?}"
    );
}

#[test]
fn model_exchange_outputs_follow_the_inputs() {
    let c = Fmu::instantiate(fmi2ModelExchange);
    set_state(&c, X0);
    assert_eq!(c.exit_init(), fmi2OK, "{:?}", c.messages());
    set_state(&c, X1);
    assert_torques(&c, lqr(&c, X1), "model exchange, x1 set in event mode");
}
