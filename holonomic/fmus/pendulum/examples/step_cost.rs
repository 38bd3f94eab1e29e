//! The Pendulum's cost per fmi2DoStep through the C API, and its final state, for comparing
//! builds: `cargo run --release -p pendulum-fmu --example step_cost`.
//!
//! 30 runs of 4000 steps of 1 ms from (alpha1, omega1, alpha2, omega2) = (2.5, 0, -1, 0), or
//! from `X0=a,b,c,d`; prints the fastest run's time per step and the state after the last run
//! (after 4 s). With `STEPS=n` one run of n steps, state only.

use pendulum_fmu::*;
use rustfmu::__private::abi::*;
use rustfmu::Variables;
use std::ffi::CString;
use std::time::Instant;

fn vr(name: &str) -> u32 {
    Pendulum::DESCRIPTION.by_name(name).unwrap().value_reference
}

fn start() -> [f64; 4] {
    match std::env::var("X0") {
        Ok(v) => {
            let x: Vec<f64> = v.split(',').map(|s| s.trim().parse().expect("X0=a,b,c,d")).collect();
            [x[0], x[1], x[2], x[3]]
        }
        Err(_) => [2.5, 0.0, -1.0, 0.0],
    }
}

/// Seconds per step, and the state after `steps` steps.
fn run(steps: usize) -> (f64, [f64; 4]) {
    let callbacks = *rustfmu::testing::silent_callbacks();
    let guid = CString::new(pendulum_fmu::__rustfmu_fmi2_exports::GUID).unwrap();
    let state = ["alpha1", "omega1", "alpha2", "omega2"].map(vr);
    // SAFETY: valid strings and callbacks that outlive the instance; arrays as long as passed.
    unsafe {
        let c = fmi2Instantiate(
            c"step_cost".as_ptr(),
            fmi2CoSimulation,
            guid.as_ptr(),
            std::ptr::null(),
            &callbacks,
            fmi2False,
            fmi2False,
        );
        assert!(!c.is_null());
        assert_eq!(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        let initial = ["alpha1_0", "omega1_0", "alpha2_0", "omega2_0"].map(vr);
        assert_eq!(fmi2SetReal(c, initial.as_ptr(), 4, start().as_ptr()), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK);
        let h = 1e-3;
        let started = Instant::now();
        for k in 0..steps {
            assert_eq!(fmi2DoStep(c, k as f64 * h, h, fmi2True), fmi2OK, "step {k}");
        }
        let seconds = started.elapsed().as_secs_f64() / steps as f64;
        let mut x = [0.0; 4];
        assert_eq!(fmi2GetReal(c, state.as_ptr(), 4, x.as_mut_ptr()), fmi2OK);
        fmi2FreeInstance(c);
        (seconds, x)
    }
}

fn main() {
    if let Some(steps) = std::env::var("STEPS").ok().and_then(|s| s.parse().ok()) {
        println!("{:?}", run(steps).1);
        return;
    }
    let (mut best, mut x) = (f64::INFINITY, [0.0; 4]);
    for _ in 0..30 {
        let (seconds, state) = run(4000);
        (best, x) = (best.min(seconds), state);
    }
    println!("{:.1} ns per fmi2DoStep; state after 4 s {x:?}", best * 1e9);
}
