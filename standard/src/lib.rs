//! A variable's `causality`, `variability` and `initial`, and the standard's rules on how they
//! combine, written once for every crate of the exporter: the derive macro checks declarations
//! with them, the runtime fills in defaults with them, `cargo fmu` re-checks a description with
//! them before writing XML, and `md-reader` reads XML into these types.
//!
//! The rules are the table "combinations of variability and causality" and the table of
//! `initial` of FMI 2.0 section 2.2.7 (`ScalarVariable`). FMI 3.0 (section 2.4.7.4) keeps both
//! tables for every combination FMI 2.0 has and adds one causality, `structuralParameter`
//! (a parameter that may change the FMU's structure, array sizes; set in Configuration Mode),
//! which the tables treat as `parameter`: variability `fixed` or `tunable`, `initial = exact`.
//! FMI 3.0's other additions around variables (clocks, arrays, `intermediateUpdate`) are not
//! modelled here: the exporter declares none of them.
//!
//! The conformance suite (`fmi-conformance`) does not use these rules for its own checks: it is
//! the check of the exporter and keeps an independent copy written from the standard's text.
//!
//! Everything is `const`: the runtime evaluates the defaults in constant expressions.
//!
//! The crate also holds what the standard's C headers declare, once for the exporter and the
//! importers: the ABI's C types ([`fmi2`], [`fmi3`]) and the names of the functions
//! ([`functions`]). The conformance suite uses these (they are the headers, which the workspace's
//! tests compare with fmi-sys's bindgen output), never the rules above.

#![no_std]

/// A C enum of the headers, `typedef enum { A, B, ... } T;`, as `pub type T = c_uint;` and
/// `pub const A: T = 0; pub const B: T = 1; ...` (numbered from 0, as C numbers them).
/// C enums are `unsigned int` on the supported platforms (what bindgen emits for them); kept as
/// plain integers, not a Rust enum: the other side (an importer calling the runtime, an FMU
/// answering the conformance suite) may pass any value, and a Rust enum would make an
/// out-of-range value undefined behaviour.
macro_rules! c_enum {
    ($(#[$doc:meta])* $ty:ident { $($name:ident),* $(,)? }) => {
        $(#[$doc])*
        pub type $ty = core::ffi::c_uint;
        c_enum!(@numbered $ty, 0, $($name,)*);
    };
    (@numbered $ty:ident, $n:expr, $first:ident, $($rest:ident,)*) => {
        pub const $first: $ty = $n;
        c_enum!(@numbered $ty, $n + 1, $($rest,)*);
    };
    (@numbered $ty:ident, $n:expr,) => {};
}

pub mod fmi2;
pub mod fmi3;
pub mod functions;

/// `causality` of a variable (FMI 2.0 section 2.2.7; FMI 3.0 section 2.4.7.4). The
/// discriminants are the codes of the exporter's encoded description: keep them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Causality {
    /// Set by the environment before initialization (and, if tunable, between steps).
    Parameter = 0,
    /// Computed from parameters during initialization (or when tunable parameters change).
    CalculatedParameter = 1,
    /// Set by the environment during the simulation.
    Input = 2,
    /// Computed by the FMU, for use outside it.
    Output = 3,
    /// Computed by the FMU, not for connections (the default where none is written).
    Local = 4,
    /// The independent variable, usually time.
    Independent = 5,
    /// FMI 3.0 only: a parameter that may change the FMU's structure (e.g. array sizes).
    StructuralParameter = 6,
}

/// `variability` of a variable. The discriminants are the codes of the encoded description.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Variability {
    /// Never changes.
    Constant = 0,
    /// Fixed after initialization.
    Fixed = 1,
    /// Changes only at events (when a tunable parameter is set).
    Tunable = 2,
    /// Changes only at events.
    Discrete = 3,
    /// May change at any time; Real (Float) variables only.
    Continuous = 4,
}

/// `initial` of a variable: how its start value is meant. The discriminants are the codes of
/// the encoded description.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Initial {
    /// The start value is the value at initialization.
    Exact = 0,
    /// The start value is a guess (an iteration variable of the initialization).
    Approx = 1,
    /// The FMU computes the value at initialization; no start value.
    Calculated = 2,
}

/// The kind of a variable's type as far as the rules care: only Real (FMI 3.0: Float32,
/// Float64) variables may be `continuous`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TypeKind {
    /// Real (FMI 3.0: Float32, Float64).
    Real,
    /// Integer, Boolean, String, Enumeration (and FMI 3.0's other non-float types).
    Other,
}

impl Causality {
    /// Every causality, in the order of the codes.
    pub const ALL: [Causality; 7] = [
        Causality::Parameter,
        Causality::CalculatedParameter,
        Causality::Input,
        Causality::Output,
        Causality::Local,
        Causality::Independent,
        Causality::StructuralParameter,
    ];

    /// As the XML writes it.
    pub const fn name(self) -> &'static str {
        match self {
            Causality::Parameter => "parameter",
            Causality::CalculatedParameter => "calculatedParameter",
            Causality::StructuralParameter => "structuralParameter",
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Local => "local",
            Causality::Independent => "independent",
        }
    }

    /// The causality the XML name `s` stands for (`structuralParameter` included: whether the
    /// version has it is the reader's question, see [`Causality::in_fmi2`]).
    pub fn from_name(s: &str) -> Option<Causality> {
        Causality::ALL.into_iter().find(|c| c.name() == s)
    }

    /// Whether FMI 2.0 has this causality (all but `structuralParameter`).
    pub const fn in_fmi2(self) -> bool {
        !matches!(self, Causality::StructuralParameter)
    }

    /// The code of the encoded description.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// The causality of code `c`.
    pub const fn from_code(c: u8) -> Option<Causality> {
        Some(match c {
            0 => Causality::Parameter,
            1 => Causality::CalculatedParameter,
            2 => Causality::Input,
            3 => Causality::Output,
            4 => Causality::Local,
            5 => Causality::Independent,
            6 => Causality::StructuralParameter,
            _ => return None,
        })
    }
}

impl Variability {
    /// Every variability, in the order of the codes.
    pub const ALL: [Variability; 5] = [
        Variability::Constant,
        Variability::Fixed,
        Variability::Tunable,
        Variability::Discrete,
        Variability::Continuous,
    ];

    /// As the XML writes it.
    pub const fn name(self) -> &'static str {
        match self {
            Variability::Constant => "constant",
            Variability::Fixed => "fixed",
            Variability::Tunable => "tunable",
            Variability::Discrete => "discrete",
            Variability::Continuous => "continuous",
        }
    }

    /// The variability the XML name `s` stands for.
    pub fn from_name(s: &str) -> Option<Variability> {
        Variability::ALL.into_iter().find(|v| v.name() == s)
    }

    /// The code of the encoded description.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// The variability of code `c`.
    pub const fn from_code(c: u8) -> Option<Variability> {
        Some(match c {
            0 => Variability::Constant,
            1 => Variability::Fixed,
            2 => Variability::Tunable,
            3 => Variability::Discrete,
            4 => Variability::Continuous,
            _ => return None,
        })
    }
}

impl Initial {
    /// Every initial, in the order of the codes.
    pub const ALL: [Initial; 3] = [Initial::Exact, Initial::Approx, Initial::Calculated];

    /// As the XML writes it.
    pub const fn name(self) -> &'static str {
        match self {
            Initial::Exact => "exact",
            Initial::Approx => "approx",
            Initial::Calculated => "calculated",
        }
    }

    /// The initial the XML name `s` stands for.
    pub fn from_name(s: &str) -> Option<Initial> {
        Initial::ALL.into_iter().find(|i| i.name() == s)
    }

    /// The code of the encoded description.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// The initial of code `c`.
    pub const fn from_code(c: u8) -> Option<Initial> {
        Some(match c {
            0 => Initial::Exact,
            1 => Initial::Approx,
            2 => Initial::Calculated,
            _ => return None,
        })
    }
}

impl core::fmt::Display for Causality {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

impl core::fmt::Display for Variability {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

impl core::fmt::Display for Initial {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

/// Whether the standard allows `variability` with `causality` (FMI 2.0 section 2.2.7, the table
/// of combinations of variability and causality; FMI 3.0 section 2.4.7.4):
///
/// | causality                                   | legal variabilities                  |
/// |---------------------------------------------|--------------------------------------|
/// | parameter, calculatedParameter, structuralParameter | fixed, tunable               |
/// | input                                       | discrete, continuous                 |
/// | output                                      | constant, discrete, continuous       |
/// | local                                       | every one                            |
/// | independent                                 | continuous                           |
///
/// (a constant parameter or input makes no sense, a parameter does not depend on time, a fixed or
/// tunable input or output is a parameter, the independent variable is continuous.)
pub const fn legal_variability(causality: Causality, variability: Variability) -> bool {
    use Causality as C;
    use Variability as V;
    match causality {
        C::Parameter | C::CalculatedParameter | C::StructuralParameter => matches!(variability, V::Fixed | V::Tunable),
        C::Input => matches!(variability, V::Discrete | V::Continuous),
        C::Output => matches!(variability, V::Constant | V::Discrete | V::Continuous),
        C::Local => true,
        C::Independent => matches!(variability, V::Continuous),
    }
}

/// Whether `initial` may be written on a variable of `causality` and `variability` (a legal
/// combination of the two), by the cases of FMI 2.0 section 2.2.7's table of `initial`:
///
/// | case | variability × causality                                  | legal `initial`               | default       |
/// |------|----------------------------------------------------------|-------------------------------|---------------|
/// | A    | constant output, constant local                          | exact                         | exact         |
/// | B    | fixed/tunable parameter (3.0: and structuralParameter)   | exact                         | exact         |
/// | C    | fixed/tunable calculatedParameter, fixed/tunable local   | calculated, approx            | calculated    |
/// | D    | discrete/continuous input, continuous independent        | none: `initial` is not written | none          |
/// | E    | discrete/continuous output, discrete/continuous local    | calculated, exact, approx     | calculated    |
///
/// For an illegal combination of causality and variability the answer says nothing (false
/// where no case applies).
pub const fn legal_initial(causality: Causality, variability: Variability, initial: Initial) -> bool {
    use Causality as C;
    use Variability as V;
    if !legal_variability(causality, variability) {
        return false;
    }
    match (causality, variability) {
        // D
        (C::Input | C::Independent, _) => false,
        // A, B
        (C::Parameter | C::StructuralParameter, _) | (_, V::Constant) => matches!(initial, Initial::Exact),
        // C
        (C::CalculatedParameter, _) | (C::Local, V::Fixed | V::Tunable) => !matches!(initial, Initial::Exact),
        // E
        (C::Output | C::Local, _) => true,
    }
}

/// The `initial` in force where none is written (the "default" column of the table at
/// [`legal_initial`]; FMI 2.0 section 2.2.7, FMI 3.0 section 2.4.7.4). `None` where `initial` is
/// not defined: inputs and the independent variable.
pub const fn default_initial(causality: Causality, variability: Variability) -> Option<Initial> {
    use Causality as C;
    match (causality, variability) {
        (C::Input | C::Independent, _) => None,
        (_, Variability::Constant) => Some(Initial::Exact),
        (C::Parameter | C::StructuralParameter, _) => Some(Initial::Exact),
        (C::CalculatedParameter | C::Output | C::Local, _) => Some(Initial::Calculated),
    }
}

/// The `initial` in force: the declared one, or [`default_initial`].
pub const fn effective_initial(
    causality: Causality,
    variability: Variability,
    declared: Option<Initial>,
) -> Option<Initial> {
    match declared {
        Some(i) => Some(i),
        None => default_initial(causality, variability),
    }
}

/// Whether the variable has a `start` value: required for inputs (FMI 2.0 section 2.2.7: "if
/// causality = input, a start value must be provided") and wherever the `initial` in force is
/// `exact` or `approx`; not allowed where it is `calculated` and for the independent variable.
pub const fn has_start(causality: Causality, variability: Variability, declared: Option<Initial>) -> bool {
    matches!(causality, Causality::Input)
        || matches!(
            effective_initial(causality, variability, declared),
            Some(Initial::Exact | Initial::Approx)
        )
}

/// The variability a declaration gets where it names none. The XML's default is `continuous`
/// (FMI 2.0 section 2.2.7; FMI 3.0 gives Float variables `continuous` and all others `discrete`),
/// which is illegal for parameters and for non-Real types; the exporter's declarations default
/// to the legal variability nearest to the XML's: `fixed` for every parameter, `continuous` for
/// Real variables and the independent variable, `discrete` for the rest.
pub const fn default_variability(causality: Causality, kind: TypeKind) -> Variability {
    match (causality, kind) {
        (Causality::Parameter | Causality::CalculatedParameter | Causality::StructuralParameter, _) => {
            Variability::Fixed
        }
        (_, TypeKind::Real) | (Causality::Independent, _) => Variability::Continuous,
        _ => Variability::Discrete,
    }
}

/// Whether a variable of `kind` may have `variability`: only Real variables are `continuous`
/// (FMI 2.0 section 2.2.7: "only variables of type Real can be continuous"; FMI 3.0: Float32 and
/// Float64).
pub const fn legal_variability_for_type(kind: TypeKind, variability: Variability) -> bool {
    matches!(kind, TypeKind::Real) || !matches!(variability, Variability::Continuous)
}

#[cfg(test)]
mod tests;
