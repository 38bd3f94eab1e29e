//! The Controller FMU through its C API (linked into this test binary): commands that stay
//! finite and limited for any finite input, integrators that stay bounded, parameter domains.

mod common;
use common::*;
use rustfmu::__private::abi::*;

const INPUTS: [&str; 6] = ["alpha1", "omega1", "alpha2", "omega2", "alpha1_ref", "alpha2_ref"];
const COMMANDS: [&str; 4] = ["M1", "M2", "U1", "U2"];

/// M1, M2 within ±M_max = 20 N·m and U1, U2 within ±U_max = 6 V, all finite.
fn assert_limited(c: &Fmu, when: &str) {
    let v = c.get(&COMMANDS);
    let ok = v[..2].iter().all(|m| m.abs() <= 20.0) && v[2..].iter().all(|u| u.abs() <= 6.0);
    assert!(
        ok,
        "{when}: (M1, M2, U1, U2) = {v:?} must be finite and within the limits"
    );
}

#[test]
fn commands_are_finite_and_limited_for_any_finite_input() {
    let max = f64::MAX;
    let cases: Vec<Vec<f64>> = vec![
        vec![1.7e308, -1.7e308, 0.0, 0.0, 0.0, 0.0],
        vec![max, -max, max, -max, -max, max],
        vec![-max, max, -max, max, max, -max],
        vec![max, max, max, max, max, max],
        vec![1e300, 0.0, -1e300, 1e300, 0.0, 5e-324],
    ];
    for mode in [1, 2, 3] {
        for drives_motors in [false, true] {
            for inputs in &cases {
                let mut c = Fmu::new();
                assert_eq!(c.set_integer("mode", mode), fmi2OK);
                assert_eq!(c.set_boolean("drives_motors", drives_motors), fmi2OK);
                let values: Vec<(&str, f64)> = INPUTS.iter().copied().zip(inputs.iter().copied()).collect();
                assert_eq!(c.set(&values), fmi2OK);
                let when = format!("mode {mode}, drives_motors = {drives_motors}, inputs {inputs:?}");
                assert_eq!(c.exit_init(), fmi2OK, "{when}: {:?}", c.messages());
                assert_limited(&c, &format!("{when}, initialized"));
                for k in 0..50 {
                    assert_eq!(c.step(1e-3), fmi2OK, "{when}, step {k}: {:?}", c.messages());
                    assert_limited(&c, &format!("{when}, after step {k}"));
                }
            }
        }
    }
}

#[test]
fn the_pid_integrators_do_not_wind_up_on_huge_inputs() {
    for mode in [2, 3] {
        let mut c = Fmu::new();
        assert_eq!(c.set_integer("mode", mode), fmi2OK);
        assert_eq!(c.exit_init(), fmi2OK);
        // One second of a broken sensor, then twenty seconds of the pendulum upright at rest.
        assert_eq!(c.set(&[("alpha1", 1.7e308), ("omega1", -1.7e308)]), fmi2OK);
        for _ in 0..1000 {
            assert_eq!(c.step(1e-3), fmi2OK, "{:?}", c.messages());
        }
        assert_eq!(c.set(&[("alpha1", 0.0), ("omega1", 0.0)]), fmi2OK);
        for _ in 0..20_000 {
            assert_eq!(c.step(1e-3), fmi2OK, "{:?}", c.messages());
        }
        let m = c.get(&["M1", "M2"]);
        assert!(
            m.iter().all(|m| m.abs() < 1e-9),
            "mode {mode}: after 20 s of zero inputs (M1, M2) = {m:?}: the integrators wound up"
        );
    }
}

#[test]
fn motor_and_gain_parameters_outside_their_declared_domains_are_refused() {
    // motor_km = 0 made U = R/(n km) (...) = NaN at rest; negative friction, back-EMF and gains
    // have no meaning (and would turn the anti-windup around).
    let cases = [
        ("motor_km", 0.0, "outside (0, inf)"),
        ("motor_km", -1e-3, "outside (0, inf)"),
        ("motor_kb", -1e-3, "outside [0, inf)"),
        ("motor_B", -1.0, "outside [0, inf)"),
        ("Kp1", -1.0, "outside [0, inf)"),
        ("Ki2", -1.0, "outside [0, inf)"),
        ("Kd1", -5e-324, "outside [0, inf)"),
    ];
    for (name, bad, why) in cases {
        let c = Fmu::new();
        assert_eq!(c.set(&[(name, bad)]), fmi2Error, "{name} = {bad} must be refused");
        let log = c.messages();
        assert!(
            log.iter()
                .any(|(s, t)| *s == fmi2Error && t.contains(&format!("'{name}'")) && t.contains(why)),
            "{name} = {bad}: expected a refusal saying {why}: {log:?}"
        );
        assert_eq!(c.exit_init(), fmi2OK, "the refusal changed nothing");
        assert_limited(&c, "at the defaults");
    }
}
