//! The Reference-FMUs' BouncingBall (modelica/Reference-FMUs, `BouncingBall/`) written with
//! rustfmu: the same model identifier, variable names, value references, causalities,
//! variabilities, start values and units, and its alias `h_ft` of `h` shown in feet; the
//! equations written here from its description.
//!
//! A ball falls from h = 1 m under gravity g; where it reaches the floor (the event indicator h
//! changes sign) it bounces back with its speed times the coefficient of restitution e; once the
//! speed after a bounce is below v_min it stays at rest on the floor.
//!
//! Differences from the C original, on purpose: the ball at rest keeps `g` (the original sets the
//! fixed parameter g to 0); it is held by an internal flag instead. The event indicator is `h`
//! itself (FMI 3.0 names a variable); after a bounce `h` is set to the smallest positive number,
//! as in the original, so that the ball leaving the floor is no new event.

use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// This model calculates the trajectory, over time, of a ball dropped from a height of 1 m
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
#[fmu(display_unit(unit = "m", name = "ft", factor = 3.280839895))]
pub struct BouncingBall {
    /// Simulation time
    #[variable(vr = 0, independent)]
    pub time: f64,
    /// Position of the ball
    #[variable(vr = 1, output, continuous, initial = exact, start = 1.0, unit = "m", depends = [h], event_indicator,
               alias(name = "h_ft", description = "Position in feet", display_unit = "ft"))]
    pub h: f64,
    /// Derivative of h
    #[variable(vr = 2, name = "der(h)", local, derivative_of = h, unit = "m/s", depends = [v], initial_depends = [v])]
    pub der_h: f64,
    /// Velocity of the ball
    #[variable(vr = 3, output, continuous, initial = exact, start = 0.0, unit = "m/s", depends = [v])]
    pub v: f64,
    /// Derivative of v
    #[variable(vr = 4, name = "der(v)", local, derivative_of = v, unit = "m/s2", depends = [], initial_depends = [g])]
    pub der_v: f64,
    /// Gravity acting on the ball
    #[variable(vr = 5, parameter, fixed, start = -9.81, unit = "m/s2")]
    pub g: f64,
    /// Coefficient of restitution
    #[variable(vr = 6, parameter, tunable, start = 0.7, min = 0.5, max = 1.0)]
    pub e: f64,
    /// Velocity below which the ball stops bouncing
    #[variable(vr = 7, local, constant, start = 0.1, unit = "m/s")]
    pub v_min: f64,
    /// The ball lies on the floor (after a bounce slower than v_min).
    pub resting: bool,
}

impl Model for BouncingBall {
    fn derivatives<D: Real>(&self, _t: D, x: &mut BouncingBallContinuous<D>) {
        // At rest nothing moves; else free fall: dh/dt = v, dv/dt = g.
        let g = if self.resting { 0.0 } else { self.g };
        x.der_h = x.v;
        x.der_v = x.v * 0.0 + g;
    }

    fn update(&mut self, _event: &mut Event) -> Result<(), String> {
        if self.h <= 0.0 && self.v < 0.0 {
            // The bounce: just above the floor, the speed reversed and reduced by e.
            self.h = f64::MIN_POSITIVE;
            self.v *= -self.e;
            if self.v < self.v_min {
                self.v = 0.0;
                self.resting = true;
            }
        }
        Ok(())
    }
}

impl CoSimulation for BouncingBall {}

rustfmu::export_fmu!(BouncingBall);
