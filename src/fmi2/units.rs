//! The units the models may use, with their SI base-unit exponents for `<UnitDefinitions>`.
//!
//! A model names a unit by its string; the description writer refuses a unit that is not listed
//! here, so every unit in a modelDescription.xml is declared with its base units.

/// SI base-unit exponents and factor, as in `<BaseUnit kg=".." m=".." .../>`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BaseUnit {
    pub kg: i32,
    pub m: i32,
    pub s: i32,
    pub a: i32,
    pub rad: i32,
}

const fn bu(kg: i32, m: i32, s: i32, a: i32, rad: i32) -> BaseUnit {
    BaseUnit { kg, m, s, a, rad }
}

/// Known units. Names follow Modelica's unit syntax (`N.m`, `rad/s`, `kg.m2`).
pub const UNITS: &[(&str, BaseUnit)] = &[
    ("s", bu(0, 0, 1, 0, 0)),
    ("kg", bu(1, 0, 0, 0, 0)),
    ("m", bu(0, 1, 0, 0, 0)),
    ("m/s2", bu(0, 1, -2, 0, 0)),
    ("rad", bu(0, 0, 0, 0, 1)),
    ("rad/s", bu(0, 0, -1, 0, 1)),
    ("rad/s2", bu(0, 0, -2, 0, 1)),
    ("N.m", bu(1, 2, -2, 0, 0)),
    ("J", bu(1, 2, -2, 0, 0)),
    ("A", bu(0, 0, 0, 1, 0)),
    ("V", bu(1, 2, -3, -1, 0)),
    ("Ohm", bu(1, 2, -3, -2, 0)),
    ("H", bu(1, 2, -2, -2, 0)),
    ("N.m/A", bu(1, 2, -2, -1, 0)),
    ("V.s/rad", bu(1, 2, -2, -1, -1)),
    ("kg.m2", bu(1, 2, 0, 0, 0)),
    ("N.m.s/rad", bu(1, 2, -1, 0, -1)),
    ("N.m/rad", bu(1, 2, -2, 0, -1)),
    ("N.m/(rad/s)", bu(1, 2, -1, 0, -1)),
    ("V/rad", bu(1, 2, -3, -1, -1)),
    ("V/(rad/s)", bu(1, 2, -2, -1, -1)),
    ("V/(rad.s)", bu(1, 2, -4, -1, -1)),
    ("N.m/(rad.s)", bu(1, 2, -3, 0, -1)),
    ("1/s", bu(0, 0, -1, 0, 0)),
];

pub fn base_unit(name: &str) -> Option<BaseUnit> {
    UNITS.iter().find(|(n, _)| *n == name).map(|(_, b)| *b)
}
