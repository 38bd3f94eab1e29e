//! docs/writing-an-fmu.md, "Numbers in the equations: `D` and `f64`": the model it shows
//! compiles (it is copied here, and the test checks the copy is the page's), gives the values
//! in `f64` and the exact derivative in dual numbers. tests/ui/real_f64_minus_d.rs pins the
//! error of the form the page warns about (`self.t_high - t`).

use num_dual::Dual64;
use rustfmu::Variables;
use rustfmu::prelude::*;
use serde::{Deserialize, Serialize};

/// A room heated towards t_high: C dT/dt = k (t_high - T) - G (T - t_out) below t_high
#[derive(Model, Debug, Clone, Serialize, Deserialize)]
pub struct Room {
    /// Room temperature T
    #[variable(vr = 0, name = "T", output, initial = exact, start = 15.0, unit = "degC", depends = [T])]
    pub t_room: f64,
    /// dT/dt
    #[variable(vr = 1, name = "der(T)", local, derivative_of = t_room, depends = [T])]
    pub der_t_room: f64,
    /// Set point t_high
    #[variable(vr = 2, parameter, start = 21.0, unit = "degC")]
    pub t_high: f64,
    /// Outside temperature t_out
    #[variable(vr = 3, parameter, start = 5.0, unit = "degC")]
    pub t_out: f64,
    /// Heater gain k
    #[variable(vr = 4, parameter, start = 50.0, unit = "W/K", min >= 0.0)]
    pub k: f64,
    /// Loss conductance G
    #[variable(vr = 5, parameter, start = 10.0, unit = "W/K", min >= 0.0)]
    pub g: f64,
    /// Heat capacity C
    #[variable(vr = 6, parameter, start = 1e4, unit = "J/K", min > 0.0)]
    pub c: f64,
}

impl Model for Room {
    fn derivatives<D: Real>(&self, _t: D, v: &mut RoomContinuous<D>) {
        let t = v.t_room; // a D: an f64 for values, a dual number for derivatives
        // D with D, and D with an f64 on the right: + - * / as usual.
        let loss = (t - self.t_out) * self.g;
        // `self.t_high - t` does not compile (cannot subtract `D` from `f64`): make the f64 a D.
        let gap = D::from(self.t_high) - t;
        // Compare values with .re(), the f64 inside a D (`t < self.t_high` compiles too).
        let heating = if t.re() < self.t_high {
            gap * self.k
        } else {
            D::from(0.0)
        };
        v.der_t_room = (heating - loss) / self.c;
    }
}

/// d(der T)/dT at `t_room` in dual numbers, and der T in f64.
fn slope_and_value(room: &Room) -> (f64, f64) {
    let mut c = room.continuous::<Dual64>();
    c.t_room = Dual64::new(room.t_room, 1.0);
    room.derivatives(Dual64::from(0.0), &mut c);
    let mut v = room.continuous::<f64>();
    room.derivatives(0.0, &mut v);
    assert_eq!(c.der_t_room.re, v.der_t_room, "the dual number's value is the f64 one");
    (c.der_t_room.eps, v.der_t_room)
}

#[test]
fn the_pages_model_gives_the_values_and_the_exact_slope_on_each_side_of_the_set_point() {
    let mut room = Room::start();
    // Below t_high: C dT/dt = k (t_high - T) - G (T - t_out), slope -(k + G)/C.
    let (slope, value) = slope_and_value(&room);
    assert_eq!(value, (50.0 * (21.0 - 15.0) - 10.0 * (15.0 - 5.0)) / 1e4);
    assert_eq!(slope, -(50.0 + 10.0) / 1e4);
    // Above: the heater is off, C dT/dt = -G (T - t_out), slope -G/C.
    room.t_room = 25.0;
    let (slope, value) = slope_and_value(&room);
    assert_eq!(value, -10.0 * (25.0 - 5.0) / 1e4);
    assert_eq!(slope, -10.0 / 1e4);
}

#[test]
fn the_model_here_is_the_one_docs_writing_an_fmu_md_shows() {
    let page = include_str!("../docs/writing-an-fmu.md");
    let start = page.find("### Numbers in the equations").expect("the section");
    let code = &page[start..];
    let code = &code[code.find("```rust\n").expect("its example") + "```rust\n".len()..];
    let code = &code[..code.find("```").expect("the example's end")];
    assert!(
        include_str!("real_arithmetic.rs").contains(code),
        "tests/real_arithmetic.rs no longer holds the example of docs/writing-an-fmu.md; copy it:\n{code}"
    );
}
