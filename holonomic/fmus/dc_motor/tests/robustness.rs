//! The DCMotor FMU through its C API (linked into this test binary): declared parameter
//! domains, and formulas that stay accurate at their ends.

use dc_motor_fmu::DcMotor;
use dc_motor_fmu::*;
use rustfmu::__private::abi::*;
use rustfmu::Variables;
use rustfmu::testing::Log;

fn vr(name: &str) -> u32 {
    DcMotor::DESCRIPTION.by_name(name).unwrap().value_reference
}

/// An instance in initialization mode, and its log.
fn instance() -> (fmi2Component, &'static Log) {
    let log = Log::leak();
    let c = rustfmu::testing::fmi2::cs_instance(
        fmi2Instantiate,
        dc_motor_fmu::__rustfmu_fmi2_exports::GUID,
        c"robustness",
        log,
    );
    // SAFETY: a live instance.
    assert_eq!(unsafe { fmi2EnterInitializationMode(c) }, fmi2OK);
    (c, log)
}

fn set(c: fmi2Component, name: &str, x: f64) -> fmi2Status {
    // SAFETY: one reference, one value.
    unsafe { fmi2SetReal(c, &vr(name), 1, &x) }
}

#[test]
fn a_zero_torque_constant_is_outside_the_declared_domain() {
    let (c, log) = instance();
    assert_eq!(set(c, "km", 0.0), fmi2Error, "km = 0 must be refused");
    let entries = log.take_texts();
    assert!(
        entries
            .iter()
            .any(|(s, t)| *s == fmi2Error && t.contains("'km'") && t.contains("outside (0, inf)")),
        "expected a refusal naming km: {entries:?}"
    );
    // SAFETY: from fmi2Instantiate, freed once.
    unsafe { fmi2FreeInstance(c) };
}

#[test]
fn a_tiny_resistance_gives_the_right_current() {
    let (c, log) = instance();
    // SAFETY: c is a live instance; arrays of one.
    unsafe {
        // Coupled: the rotor turns at the joint's 2 rad/s (n = 1) whatever the current.
        assert_eq!(fmi2SetBoolean(c, &vr("coupled"), 1, &fmi2True), fmi2OK);
        assert_eq!(set(c, "R", 1e-20), fmi2OK, "R = 1e-20 is > 0");
        assert_eq!(set(c, "U", 6.0), fmi2OK);
        assert_eq!(set(c, "omega", 2.0), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK, "{:?}", log.texts());
        for k in 0..15 {
            assert_eq!(fmi2DoStep(c, k as f64 * 1e-3, 1e-3, fmi2True), fmi2OK);
        }
        let mut i = 0.0;
        assert_eq!(fmi2GetReal(c, &vr("i"), 1, &mut i), fmi2OK);
        // R -> 0: L di/dt = U - kb omega_m, i = (6 - 0.00448 * 2) * 0.015 / 0.000121.
        assert!(
            (i - 742.6909090909).abs() < 1e-6,
            "after 15 ms at 6 V and 2 rad/s with R = 1e-20 Ohm: expected 742.69 A, got {i} A"
        );
        fmi2FreeInstance(c);
    }
}

#[test]
fn an_unloaded_step_of_any_length_returns() {
    // The paper's motor, unloaded, one step of 1e40 s: nalgebra's exp squared 2^64 times (a
    // hang); now the steady state.
    let (c, log) = instance();
    // SAFETY: c is a live instance; arrays of one.
    unsafe {
        assert_eq!(fmi2SetBoolean(c, &vr("coupled"), 1, &fmi2False), fmi2OK);
        assert_eq!(set(c, "U", 6.0), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK);
        let s = fmi2DoStep(c, 0.0, 1e40, fmi2True);
        let entries = log.take_texts();
        assert_eq!(s, fmi2OK, "h = 1e40: {entries:?}");
        let mut w = f64::NAN;
        assert_eq!(fmi2GetReal(c, &vr("omega_m"), 1, &mut w), fmi2OK);
        assert!(w.is_finite(), "omega_m = {w}");
        fmi2FreeInstance(c);
    }
}

#[test]
fn an_inductance_whose_current_rate_is_beyond_f64_is_refused_at_initialization() {
    // L = 5e-324 H (legal: > 0): di/dt = 6 V / L is beyond f64, so the equations have no
    // finite derivative (and the step's transition matrix none either). The initialization
    // says so, naming the derivative, instead of handing an importer an infinite rate.
    let (c, log) = instance();
    // SAFETY: c is a live instance; arrays of one.
    unsafe {
        assert_eq!(fmi2SetBoolean(c, &vr("coupled"), 1, &fmi2False), fmi2OK);
        assert_eq!(set(c, "L", 5e-324), fmi2OK);
        assert_eq!(set(c, "U", 6.0), fmi2OK);
        let s = fmi2ExitInitializationMode(c);
        let entries = log.take_texts();
        assert_eq!(s, fmi2Error, "{entries:?}");
        assert!(
            entries
                .iter()
                .any(|(s, t)| *s == fmi2Error && t.contains("'der(i)'") && t.contains("not a finite number")),
            "{entries:?}"
        );
        fmi2FreeInstance(c);
    }
}
