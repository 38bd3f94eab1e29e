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

/// A unit with a temperature exponent `k` (kelvin).
const fn t(kg: i32, m: i32, s: i32, k: i32) -> Base {
    Base {
        exps: [kg, m, s, 0, k, 0, 0, 0],
        factor: 1.0,
        offset: 0.0,
    }
}

pub const DEFAULT_UNITS: &[(&str, Base)] = &[
    ("1", b(0, 0, 0, 0, 0)),
    ("s", b(0, 0, 1, 0, 0)),
    ("1/s", b(0, 0, -1, 0, 0)),
    ("Hz", b(0, 0, -1, 0, 0)),
    ("kg", b(1, 0, 0, 0, 0)),
    ("kg/s", b(1, 0, -1, 0, 0)),
    ("m", b(0, 1, 0, 0, 0)),
    ("m2", b(0, 2, 0, 0, 0)),
    ("m3", b(0, 3, 0, 0, 0)),
    ("kg/m3", b(1, -3, 0, 0, 0)),
    ("m/s", b(0, 1, -1, 0, 0)),
    ("m/s2", b(0, 1, -2, 0, 0)),
    ("N", b(1, 1, -2, 0, 0)),
    ("Pa", b(1, -1, -2, 0, 0)),
    ("rad", b(0, 0, 0, 0, 1)),
    ("rad/s", b(0, 0, -1, 0, 1)),
    ("rad/s2", b(0, 0, -2, 0, 1)),
    ("rad.s", b(0, 0, 1, 0, 1)),
    ("A/s", b(0, 0, -1, 1, 0)),
    ("N.m", b(1, 2, -2, 0, 0)),
    ("J", b(1, 2, -2, 0, 0)),
    ("W", b(1, 2, -3, 0, 0)),
    ("W/m2", b(1, 0, -3, 0, 0)),
    ("A", b(0, 0, 0, 1, 0)),
    ("C", b(0, 0, 1, 1, 0)),
    ("V", b(1, 2, -3, -1, 0)),
    ("Ohm", b(1, 2, -3, -2, 0)),
    ("S", b(-1, -2, 3, 2, 0)),
    ("F", b(-1, -2, 4, 2, 0)),
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
    ("K", t(0, 0, 0, 1)),
    // Celsius: a value in K is the value in degC + 273.15 (FMI: factor · value + offset).
    (
        "degC",
        Base {
            offset: 273.15,
            ..t(0, 0, 0, 1)
        },
    ),
    ("K/s", t(0, 0, -1, 1)),
    ("J/K", t(1, 2, -2, -1)),
    ("J/(kg.K)", t(0, 2, -2, -1)),
    ("W/K", t(1, 2, -3, -1)),
    ("K/W", t(-1, -2, 3, 1)),
    ("W/(m.K)", t(1, 1, -3, -1)),
    ("W/(m2.K)", t(1, 0, -3, -1)),
];

pub fn default_unit(name: &str) -> Option<Base> {
    DEFAULT_UNITS.iter().find(|(n, _)| *n == name).map(|(_, b)| *b)
}

/// A display unit of a unit: a value `v` in the unit is shown as `factor · v + offset`, or, with
/// `inverse` (FMI 3.0 only, and then without offset), as `factor / v`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Display {
    pub factor: f64,
    pub offset: f64,
    pub inverse: bool,
}

const fn shown(factor: f64, offset: f64) -> Display {
    Display {
        factor,
        offset,
        inverse: false,
    }
}

/// The display units every model may show a runtime unit's values in without declaring them:
/// (unit, display unit, conversion). A model declares further ones with
/// `#[fmu(display_unit(unit = "m", name = "ft", factor = 3.280839895))]`. The description carries
/// one of these only where a variable or an alias uses it.
pub const DEFAULT_DISPLAY_UNITS: &[(&str, &str, Display)] = &[
    ("rad", "deg", shown(180.0 / std::f64::consts::PI, 0.0)),
    ("rad/s", "deg/s", shown(180.0 / std::f64::consts::PI, 0.0)),
    ("rad/s", "rpm", shown(30.0 / std::f64::consts::PI, 0.0)),
    ("m/s", "km/h", shown(3.6, 0.0)),
    ("K", "degC", shown(1.0, -273.15)),
];

/// The built-in display unit `name` of unit `unit`.
pub fn default_display_unit(unit: &str, name: &str) -> Option<Display> {
    DEFAULT_DISPLAY_UNITS
        .iter()
        .find(|(u, n, _)| *u == unit && *n == name)
        .map(|(_, _, d)| *d)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// value in base units = factor · value + offset, each unit's exponents as SI defines it.
    #[test]
    fn the_thermal_units_are_built_in_with_kelvin_as_their_base() {
        let k = default_unit("K").expect("K is a runtime unit");
        assert_eq!(k.exps, [0, 0, 0, 0, 1, 0, 0, 0], "K: kelvin to the first power");
        assert_eq!((k.factor, k.offset), (1.0, 0.0));
        let c = default_unit("degC").expect("degC is a runtime unit");
        assert_eq!(c.exps, k.exps, "degC measures temperature");
        assert_eq!(c.offset, 273.15, "0 degC = 273.15 K");
        // G = P / ΔT and C = E / ΔT: W/K and J/K are W and J over K.
        let (w, j) = (default_unit("W").unwrap(), default_unit("J").unwrap());
        let over_k = |b: Base| Base {
            exps: std::array::from_fn(|i| b.exps[i] - k.exps[i]),
            ..b
        };
        assert_eq!(default_unit("W/K"), Some(over_k(w)));
        assert_eq!(default_unit("J/K"), Some(over_k(j)));
        // Ohm's inverse and the farad: S = A/V, F = C/V = A s/V.
        let (v, a) = (default_unit("V").unwrap(), default_unit("A").unwrap());
        let s_exps: [i32; 8] = std::array::from_fn(|i| a.exps[i] - v.exps[i]);
        assert_eq!(default_unit("S").unwrap().exps, s_exps);
        let f_exps: [i32; 8] = std::array::from_fn(|i| s_exps[i] + [0, 0, 1, 0, 0, 0, 0, 0][i]);
        assert_eq!(default_unit("F").unwrap().exps, f_exps);
    }

    #[test]
    fn no_runtime_unit_is_listed_twice() {
        for (i, (name, _)) in DEFAULT_UNITS.iter().enumerate() {
            assert!(
                !DEFAULT_UNITS[..i].iter().any(|(n, _)| n == name),
                "'{name}' is listed twice in DEFAULT_UNITS"
            );
        }
    }
}
