//! The units every model may use without declaring them, with their SI base-unit exponents.
//! A model declares further units with `#[fmu(unit(name = "..", m = 1, s = -1))]`.
//! Names follow Modelica's unit syntax (`N.m`, `rad/s`, `kg.m2`).

/// kg, m, s, A, K, mol, cd, rad exponents; factor; offset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Base {
    pub exps: [i32; 8],
    pub factor: f64,
    pub offset: f64,
}

pub const EXPONENT_NAMES: [&str; 8] = ["kg", "m", "s", "A", "K", "mol", "cd", "rad"];

const fn b(kg: i32, m: i32, s: i32, a: i32, rad: i32) -> Base {
    Base {
        exps: [kg, m, s, a, 0, 0, 0, rad],
        factor: 1.0,
        offset: 0.0,
    }
}

pub const DEFAULT_UNITS: &[(&str, Base)] = &[
    ("1", b(0, 0, 0, 0, 0)),
    ("s", b(0, 0, 1, 0, 0)),
    ("1/s", b(0, 0, -1, 0, 0)),
    ("kg", b(1, 0, 0, 0, 0)),
    ("m", b(0, 1, 0, 0, 0)),
    ("m/s", b(0, 1, -1, 0, 0)),
    ("m/s2", b(0, 1, -2, 0, 0)),
    ("N", b(1, 1, -2, 0, 0)),
    ("rad", b(0, 0, 0, 0, 1)),
    ("rad/s", b(0, 0, -1, 0, 1)),
    ("rad/s2", b(0, 0, -2, 0, 1)),
    ("rad.s", b(0, 0, 1, 0, 1)),
    ("A/s", b(0, 0, -1, 1, 0)),
    ("N.m", b(1, 2, -2, 0, 0)),
    ("J", b(1, 2, -2, 0, 0)),
    ("W", b(1, 2, -3, 0, 0)),
    ("A", b(0, 0, 0, 1, 0)),
    ("V", b(1, 2, -3, -1, 0)),
    ("Ohm", b(1, 2, -3, -2, 0)),
    ("H", b(1, 2, -2, -2, 0)),
    ("N.m/A", b(1, 2, -2, -1, 0)),
    ("V.s/rad", b(1, 2, -2, -1, -1)),
    ("kg.m2", b(1, 2, 0, 0, 0)),
    ("N.m.s/rad", b(1, 2, -1, 0, -1)),
    ("N.m/rad", b(1, 2, -2, 0, -1)),
    ("N.m/(rad/s)", b(1, 2, -1, 0, -1)),
    ("V/rad", b(1, 2, -3, -1, -1)),
    ("V/(rad/s)", b(1, 2, -2, -1, -1)),
    ("V/(rad.s)", b(1, 2, -4, -1, -1)),
    ("N.m/(rad.s)", b(1, 2, -3, 0, -1)),
];

pub fn default_unit(name: &str) -> Option<Base> {
    DEFAULT_UNITS.iter().find(|(n, _)| *n == name).map(|(_, b)| *b)
}
