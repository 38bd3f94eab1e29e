//! A variable's declaration: its type, start, bounds, units, the FMI 3.0 additions (clocks,
//! arrays, display units, aliases).

use super::*;

/// FMI base types. FMI 3.0's `Float64`, `Int32` are FMI 2.0's `Real`, `Integer` (the names
/// here are 2.0's); the others exist in FMI 3.0 only ([`VarType::in_fmi2`]). The discriminants
/// are the codes of the encoded description.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum VarType {
    Real = 0,
    Integer = 1,
    Boolean = 2,
    String = 3,
    Enumeration = 4,
    Float32 = 5,
    Int8 = 6,
    UInt8 = 7,
    Int16 = 8,
    UInt16 = 9,
    UInt32 = 10,
    Int64 = 11,
    UInt64 = 12,
    Binary = 13,
    /// FMI 3.0 `Clock`: no value of its own; active or not ([`crate::Clock`]).
    Clock = 14,
}

impl VarType {
    /// Whether FMI 2.0 has this type (Real, Integer, Boolean, String, Enumeration).
    pub const fn in_fmi2(self) -> bool {
        (self as u8) <= 4
    }

    /// Float32 or Float64 (Real): the types that may be continuous.
    pub const fn is_float(self) -> bool {
        matches!(self, VarType::Real | VarType::Float32)
    }

    /// The integer types (Int8 .. UInt64, Int32 = Integer), not Enumeration.
    pub const fn is_integer(self) -> bool {
        matches!(
            self,
            VarType::Integer
                | VarType::Int8
                | VarType::UInt8
                | VarType::Int16
                | VarType::UInt16
                | VarType::UInt32
                | VarType::Int64
                | VarType::UInt64
        )
    }

    /// The range of an integer type (Enumerations: Int32's... FMI 3.0 Enumerations are Int64).
    pub const fn integer_range(self) -> Option<(i128, i128)> {
        Some(match self {
            VarType::Int8 => (i8::MIN as i128, i8::MAX as i128),
            VarType::UInt8 => (0, u8::MAX as i128),
            VarType::Int16 => (i16::MIN as i128, i16::MAX as i128),
            VarType::UInt16 => (0, u16::MAX as i128),
            VarType::Integer | VarType::Enumeration => (i32::MIN as i128, i32::MAX as i128),
            VarType::UInt32 => (0, u32::MAX as i128),
            VarType::Int64 => (i64::MIN as i128, i64::MAX as i128),
            VarType::UInt64 => (0, u64::MAX as i128),
            _ => return None,
        })
    }

    /// The FMI 3.0 element name (`Float64`, `Int32`, ...).
    pub const fn fmi3_name(self) -> &'static str {
        match self {
            VarType::Real => "Float64",
            VarType::Integer => "Int32",
            VarType::Boolean => "Boolean",
            VarType::String => "String",
            VarType::Enumeration => "Enumeration",
            VarType::Float32 => "Float32",
            VarType::Int8 => "Int8",
            VarType::UInt8 => "UInt8",
            VarType::Int16 => "Int16",
            VarType::UInt16 => "UInt16",
            VarType::UInt32 => "UInt32",
            VarType::Int64 => "Int64",
            VarType::UInt64 => "UInt64",
            VarType::Binary => "Binary",
            VarType::Clock => "Clock",
        }
    }

    pub(super) const fn from_code(c: u8) -> Option<VarType> {
        Some(match c {
            0 => VarType::Real,
            1 => VarType::Integer,
            2 => VarType::Boolean,
            3 => VarType::String,
            4 => VarType::Enumeration,
            5 => VarType::Float32,
            6 => VarType::Int8,
            7 => VarType::UInt8,
            8 => VarType::Int16,
            9 => VarType::UInt16,
            10 => VarType::UInt32,
            11 => VarType::Int64,
            12 => VarType::UInt64,
            13 => VarType::Binary,
            14 => VarType::Clock,
            _ => return None,
        })
    }
}

/// `causality`, `variability` and `initial`, and the standard's rules on them (FMI 2.0 section
/// 2.2.7): the types of `fmi-standard`, the one copy of those rules that the derive macro,
/// this runtime, `cargo fmu` and the description reader share. Their discriminants are the codes
/// of the encoded description.
pub use fmi_standard::{Causality, Initial, Variability};

/// A declared start value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start {
    /// No start value (only where the standard forbids one: `initial = calculated`).
    None,
    Real(f64),
    /// Integer and Enumeration variables.
    Integer(i32),
    Boolean(bool),
    String(&'static str),
    /// Int8, UInt8, Int16, UInt16, UInt32 and Int64 variables (FMI 3.0). Float32 start values
    /// are `Real` (every f32 is an f64).
    Int64(i64),
    /// UInt64 variables (FMI 3.0).
    UInt64(u64),
    /// Binary variables (FMI 3.0): the bytes.
    Binary(&'static [u8]),
    /// An array (FMI 3.0): each element's start, row-major.
    Array(&'static [Start]),
}

/// A bound of a variable's legal range: `value` itself is legal unless `exclusive`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bound {
    pub value: f64,
    pub exclusive: bool,
}

impl Bound {
    /// Whether `x` lies on the legal side of this bound taken as a minimum.
    pub fn admits_above(&self, x: f64) -> bool {
        if self.exclusive {
            x > self.value
        } else {
            x >= self.value
        }
    }
    /// Whether `x` lies on the legal side of this bound taken as a maximum.
    pub fn admits_below(&self, x: f64) -> bool {
        if self.exclusive {
            x < self.value
        } else {
            x <= self.value
        }
    }
}

/// One item of an enumeration type.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnumItem {
    pub name: &'static str,
    pub value: i32,
    pub description: &'static str,
}

/// An enumeration type (`<TypeDefinitions><SimpleType><Enumeration>` in FMI 2.0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnumType {
    pub name: &'static str,
    pub description: &'static str,
    pub items: &'static [EnumItem],
}

impl EnumType {
    pub fn item(&self, value: i32) -> Option<&'static EnumItem> {
        self.items.iter().find(|i| i.value == value)
    }
}

/// SI base-unit exponents, factor and offset, as in `<BaseUnit kg=".." m=".." factor=".."/>`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaseUnit {
    pub kg: i32,
    pub m: i32,
    pub s: i32,
    pub a: i32,
    pub k: i32,
    pub mol: i32,
    pub cd: i32,
    pub rad: i32,
    pub factor: f64,
    pub offset: f64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unit {
    pub name: &'static str,
    pub base: BaseUnit,
    /// The unit's `<DisplayUnit>`s that the description carries (those a variable or an alias
    /// shows its value in, and those the model declares).
    pub display_units: &'static [DisplayUnit],
}

/// A `<DisplayUnit>` of a [`Unit`]: a value `v` in the unit is shown as `factor · v + offset`,
/// or, `inverse` (FMI 3.0 only), as `factor / v` (FMI 2.0, 2.2.2; FMI 3.0, 2.4.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DisplayUnit {
    pub name: &'static str,
    pub factor: f64,
    pub offset: f64,
    pub inverse: bool,
}

/// Another name of a variable (FMI 3.0 `<Alias>`; in FMI 2.0 a `<ScalarVariable>` of the same
/// value reference): the same value, read and written through the same value reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Alias {
    pub name: &'static str,
    /// Empty for none (the variable's own is meant).
    pub description: &'static str,
    /// The display unit the alias shows the value in (a float variable's only); empty for none.
    pub display_unit: &'static str,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogCategory {
    pub name: &'static str,
    pub description: &'static str,
}

/// `<DefaultExperiment>`: every attribute optional.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DefaultExperiment {
    pub start_time: Option<f64>,
    pub stop_time: Option<f64>,
    pub tolerance: Option<f64>,
    pub step_size: Option<f64>,
}

/// One model variable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Variable {
    pub name: &'static str,
    pub value_reference: u32,
    pub var_type: VarType,
    pub causality: Causality,
    pub variability: Variability,
    /// `None`: the standard's default for this causality and variability.
    pub initial: Option<Initial>,
    pub start: Start,
    /// Unit name, declared in [`ModelDescription::units`]; empty for none.
    pub unit: &'static str,
    /// The display unit the value is shown in by default, one of the unit's
    /// [`Unit::display_units`]; empty for none.
    pub display_unit: &'static str,
    /// The variable's other names.
    pub aliases: &'static [Alias],
    pub description: &'static str,
    pub min: Option<Bound>,
    pub max: Option<Bound>,
    /// Nominal value (FMI `nominal`), for states and scaling.
    pub nominal: Option<f64>,
    /// For outputs (and, with Model Exchange, derivatives): the inputs this variable depends on
    /// directly, by name. `Some(&[])`: none; `None`: every input (the attribute is left out).
    pub depends_on: Option<&'static [&'static str]>,
    /// For an unknown of Initialization Mode (FMI 2.0 `InitialUnknowns`): the knowns it is
    /// computed from at initialization (inputs and variables with initial = exact, parameters
    /// among them), by name. `None`: every known (the attribute is left out).
    pub initial_depends_on: Option<&'static [&'static str]>,
    /// For a derivative: the name of the state variable it is the derivative of.
    pub derivative_of: Option<&'static str>,
    pub enumeration: Option<&'static EnumType>,
    /// What only FMI 3.0 has; [`Fmi3Extras::NONE`] for most variables.
    pub fmi3: Fmi3Extras,
}

/// A variable's declarations that only FMI 3.0 has.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fmi3Extras {
    /// The variable exists in FMI 3.0 only: left out of the FMI 2.0 description, and unknown to
    /// the FMI 2.0 functions. Every variable of a type FMI 2.0 lacks is one.
    pub only: bool,
    /// A Binary's `maxSize` in bytes.
    pub max_size: Option<u32>,
    /// A Binary's `mimeType`; empty for the default (`application/octet-stream`).
    pub mime_type: &'static str,
    /// An array's `<Dimension start="..">`s, outermost first (`[[f64; 4]; 2]`: `[2, 4]`);
    /// empty for a scalar. The values are in row-major order.
    pub dimensions: &'static [u32],
    /// An array's sizes set by structural parameters (FMI 3.0 `<Dimension valueReference="..">`):
    /// per dimension, the value reference of the UInt64 structural parameter that sets its length
    /// ([`NOT_SIZED`] for a fixed length); empty when every length is fixed. `dimensions` are then
    /// the capacities (the Rust array's lengths): the parameter's value is at most that.
    pub sized_by: &'static [u32],
    /// A Clock's declaration (`<Clock>`'s attributes); `None` for every other variable.
    pub clock: Option<ClockDecl>,
    /// A clocked variable's clocks (FMI 3.0 `clocks`), by name: it is set and read while one of
    /// them is active (and in Initialization Mode). Empty: not clocked.
    pub clocks: &'static [&'static str],
}

/// FMI 3.0 `intervalVariability` of a Clock (FMI 3.0, 2.2.9.1). The first five are time-based
/// (the importer activates them at the times their interval and shift say), `Triggered` ticks
/// when the importer says so. The discriminants are the codes of the encoded description.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum IntervalVariability {
    /// Periodic; the interval is `intervalDecimal` and nobody changes it.
    Constant = 0,
    /// Periodic; the interval is fixed at initialization (a fixed parameter, or set by the
    /// importer in Initialization Mode when the description gives a default).
    Fixed = 1,
    /// Periodic; the interval may change at events (a tunable parameter, or set by the importer).
    Tunable = 2,
    /// Aperiodic: after each tick the model says the interval to the next one.
    Changing = 3,
    /// Aperiodic: the model says the time to the next tick whenever it knows it.
    Countdown = 4,
    /// Not time-based: ticks when the importer activates it.
    Triggered = 5,
}

impl IntervalVariability {
    /// The attribute's value in the XML.
    pub const fn text(self) -> &'static str {
        match self {
            IntervalVariability::Constant => "constant",
            IntervalVariability::Fixed => "fixed",
            IntervalVariability::Tunable => "tunable",
            IntervalVariability::Changing => "changing",
            IntervalVariability::Countdown => "countdown",
            IntervalVariability::Triggered => "triggered",
        }
    }

    /// Periodic clocks: constant, fixed, tunable (they have a shift).
    pub const fn periodic(self) -> bool {
        matches!(
            self,
            IntervalVariability::Constant | IntervalVariability::Fixed | IntervalVariability::Tunable
        )
    }

    /// Clocks whose interval the model sets as it runs: changing, countdown.
    pub const fn model_timed(self) -> bool {
        matches!(self, IntervalVariability::Changing | IntervalVariability::Countdown)
    }

    pub(super) const fn from_code(c: u8) -> Option<IntervalVariability> {
        Some(match c {
            0 => IntervalVariability::Constant,
            1 => IntervalVariability::Fixed,
            2 => IntervalVariability::Tunable,
            3 => IntervalVariability::Changing,
            4 => IntervalVariability::Countdown,
            5 => IntervalVariability::Triggered,
            _ => return None,
        })
    }
}

/// A Clock variable's declaration (FMI 3.0 `<Clock>`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClockDecl {
    pub interval_variability: IntervalVariability,
    /// `intervalDecimal`: the interval of a constant clock; of a fixed or tunable one, the
    /// default the importer may set another value for (`fmi3SetIntervalDecimal`).
    pub interval: Option<f64>,
    /// A fixed or tunable clock without `interval`: the name of the Float64 parameter whose
    /// value is its interval (the importer reads it with `fmi3GetIntervalDecimal`); else empty.
    pub interval_parameter: &'static str,
    /// `shiftDecimal`: the first tick of a periodic clock is at start time + shift.
    pub shift: f64,
    /// `canBeDeactivated`.
    pub can_be_deactivated: bool,
    /// `priority` (`clock(.., priority = N)`; required by Scheduled Execution): 0 is the
    /// highest.
    pub priority: Option<u32>,
}

impl Fmi3Extras {
    pub const NONE: Fmi3Extras = Fmi3Extras {
        only: false,
        max_size: None,
        mime_type: "",
        dimensions: &[],
        sized_by: &[],
        clock: None,
        clocks: &[],
    };

    pub(super) const fn is_none(&self) -> bool {
        !self.only
            && self.max_size.is_none()
            && self.mime_type.is_empty()
            && self.dimensions.is_empty()
            && !self.has_clock_part()
    }

    /// Whether the variable is a Clock or clocked (the encoding's clocks block).
    pub(super) const fn has_clock_part(&self) -> bool {
        self.clock.is_some() || !self.clocks.is_empty()
    }
}

impl Variable {
    /// How many values the variable has: 1 for a scalar, the product of the dimensions for an
    /// array.
    pub const fn element_count(&self) -> usize {
        let mut n = 1usize;
        let mut i = 0;
        while i < self.fmi3.dimensions.len() {
            n = n.saturating_mul(self.fmi3.dimensions[i] as usize);
            i += 1;
        }
        n
    }

    /// Whether a structural parameter sets one of the array's lengths (then its number of
    /// elements is a run-time value: `Instance::element_count`).
    pub const fn is_sized(&self) -> bool {
        !self.fmi3.sized_by.is_empty()
    }

    /// Whether the variable is an array (FMI 3.0 `<Dimension>`s).
    pub const fn is_array(&self) -> bool {
        !self.fmi3.dimensions.is_empty()
    }

    /// The FMI 2.0 name of element `k` (row-major) of an array: the standard's structured
    /// name with indices from 1 (FMI 2.0, 2.2.9: `K[2,3]` of `[[f64; 4]; 2]` is element 6).
    pub fn element_name(&self, k: usize) -> String {
        let mut indices = Vec::with_capacity(self.fmi3.dimensions.len());
        let mut rest = k;
        for d in self.fmi3.dimensions.iter().rev() {
            let d = (*d as usize).max(1);
            indices.push(rest % d + 1);
            rest /= d;
        }
        let indices: Vec<String> = indices.iter().rev().map(|i| i.to_string()).collect();
        format!("{}[{}]", self.name, indices.join(","))
    }

    /// Whether the description of FMI `version` has this variable.
    pub const fn in_version(&self, version: FmiVersion) -> bool {
        match version {
            FmiVersion::V2 => !self.fmi3.only && self.var_type.in_fmi2(),
            FmiVersion::V3 => true,
        }
    }

    /// The `initial` in force: the declared one, or the standard's default (FMI 2.0, 2.2.7;
    /// [`fmi_standard::effective_initial`]).
    pub const fn effective_initial(&self) -> Option<Initial> {
        fmi_standard::effective_initial(self.causality, self.variability, self.initial)
    }

    /// Whether the description carries a `start` value (required for inputs and exact/approx,
    /// forbidden for calculated and the independent variable; [`fmi_standard::has_start`]).
    pub const fn has_start(&self) -> bool {
        !matches!(self.var_type, VarType::Clock)
            && fmi_standard::has_start(self.causality, self.variability, self.initial)
    }

    /// Whether the variable is clocked (FMI 3.0 `clocks`).
    pub const fn is_clocked(&self) -> bool {
        !self.fmi3.clocks.is_empty()
    }
}
