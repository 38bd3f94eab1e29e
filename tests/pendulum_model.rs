//! The Pendulum FMU's model stepped in Rust (no C ABI): energy, parameter checks, step sizes.

use rustfmu::fmi2::model::CoSimModel;
use rustfmu::fmi2::variables::{Value, VariableSet};
use rustfmu::fmus::pendulum::{Pendulum, PendulumVariables};

fn pendulum(alpha1: f64, omega1: f64, alpha2: f64, omega2: f64) -> Pendulum {
    let mut p = Pendulum::new();
    (p.v.alpha1, p.v.omega1, p.v.alpha2, p.v.omega2) = (alpha1, omega1, alpha2, omega2);
    p.initialize(0.0, None).unwrap();
    p
}

#[test]
fn energy_is_conserved_without_torque() {
    let mut p = pendulum(2.5, 1.0, -1.0, -3.0);
    let e0 = p.v.energy;
    let mut worst: f64 = 0.0;
    for n in 0..5000 {
        p.do_step(n as f64 * 1e-3, 1e-3).unwrap();
        worst = worst.max((p.v.energy - e0).abs());
    }
    assert!(worst < 1e-8, "energy drifted by {worst} J over 5 s (E0 = {e0} J)");
}

#[test]
fn result_does_not_depend_on_the_communication_step() {
    // Same 0.1 s with h = 1e-6 ... 0.1: the error control makes them agree to ~tolerance.
    let mut finals = Vec::new();
    for h in [1e-6_f64, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1] {
        let mut p = pendulum(0.3, 0.0, -0.2, 1.0);
        let n = (0.1 / h).round() as usize;
        for k in 0..n {
            p.do_step(k as f64 * h, h).unwrap();
        }
        finals.push((h, p.state()));
    }
    let (_, reference) = finals[3];
    for (h, x) in &finals {
        let err = (x - reference).abs().max();
        assert!(err < 1e-8, "h = {h}: state {x} differs from the h = 1e-3 run by {err}");
    }
}

#[test]
fn nonsense_parameters_are_refused_naming_the_variable() {
    let p = Pendulum::new();
    for (var, quantity) in [("m1", "mass"), ("m2", "mass"), ("l1", "length"), ("l2", "length")] {
        let decl = PendulumVariables::DECLS.iter().find(|d| d.name == var).unwrap();
        for bad in [0.0, -1.0] {
            let e = p
                .check(decl, Value::Real(bad))
                .expect_err("accepted a nonsense parameter");
            assert!(e.contains(quantity), "message '{e}' should say which quantity is wrong");
        }
        assert!(p.check(decl, Value::Real(0.3)).is_ok());
    }
}

#[test]
fn torque_accelerates_as_eq12_b_says_at_rest() {
    // From rest upright, a small step of M1 = 1 N.m: α̈1 = 6, α̈2 = -6 (columns of B).
    let mut p = pendulum(0.0, 0.0, 0.0, 0.0);
    p.v.M1 = 1.0;
    p.do_step(0.0, 1e-4).unwrap();
    assert!((p.v.omega1 / 1e-4 - 6.0).abs() < 1e-3, "α̈1 ≈ {}", p.v.omega1 / 1e-4);
    assert!((p.v.omega2 / 1e-4 + 6.0).abs() < 1e-3, "α̈2 ≈ {}", p.v.omega2 / 1e-4);
}
