//! The Pendulum FMU's model stepped in Rust (no C ABI): energy, parameter checks, step sizes.

use pendulum_fmu::Pendulum;
use rustfmu::description::Bound;
use rustfmu::{Standalone, Variables};

/// The Pendulum as the runtime runs it, without the C ABI.
struct P(Standalone<Pendulum>);

impl std::ops::Deref for P {
    type Target = Pendulum;
    fn deref(&self) -> &Pendulum {
        &self.0.model
    }
}

impl P {
    fn do_step(&mut self, t: f64, h: f64) -> Result<(), rustfmu::StepFailure> {
        assert!((self.0.time - t).abs() <= 1e-9 * t.abs().max(1.0));
        self.0.do_step(h)
    }
}

fn pendulum(alpha1: f64, omega1: f64, alpha2: f64, omega2: f64) -> P {
    let mut p = Pendulum::start();
    (p.alpha1_0, p.omega1_0, p.alpha2_0, p.omega2_0) = (alpha1, omega1, alpha2, omega2);
    let mut sim = Standalone::new(p, 0.0, None);
    sim.initialize().unwrap();
    P(sim)
}

#[test]
fn energy_is_conserved_without_torque() {
    let mut p = pendulum(2.5, 1.0, -1.0, -3.0);
    let e0 = p.energy;
    let mut worst: f64 = 0.0;
    for n in 0..5000 {
        p.do_step(n as f64 * 1e-3, 1e-3).unwrap();
        worst = worst.max((p.energy - e0).abs());
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
fn masses_and_lengths_are_declared_positive() {
    // The runtime refuses other values (tests/robustness.rs); the model does not check them again.
    for var in ["m1", "m2", "l1", "l2"] {
        let decl = Pendulum::DESCRIPTION.by_name(var).unwrap();
        assert_eq!(
            decl.min,
            Some(Bound {
                value: 0.0,
                exclusive: true
            }),
            "{var} is declared > 0"
        );
    }
}

#[test]
fn torque_accelerates_as_eq12_b_says_at_rest() {
    // From rest upright, a small step of M1 = 1 N.m: α̈1 = 6, α̈2 = -6 (columns of B).
    let mut p = pendulum(0.0, 0.0, 0.0, 0.0);
    p.0.model.M1 = 1.0;
    p.do_step(0.0, 1e-4).unwrap();
    assert!((p.omega1 / 1e-4 - 6.0).abs() < 1e-3, "α̈1 ≈ {}", p.omega1 / 1e-4);
    assert!((p.omega2 / 1e-4 + 6.0).abs() < 1e-3, "α̈2 ≈ {}", p.omega2 / 1e-4);
}
