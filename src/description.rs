//! The typed description of a model: what `#[derive(Model)]` declares, fixed at compile time.
//!
//! One description feeds every output: the runtime dispatches and checks values with it, the
//! export macro encodes it into the binary (so the built library describes itself), and
//! `cargo fmu` decodes it from the binary and writes `modelDescription.xml` (FMI 2.0, later 3.0)
//! and the SSP files from it. The GUID is a name-based (SHA-1) UUID of the encoded description,
//! computed at compile time: the binary carries no XML writer and no hashing code.
//!
//! Every item here is `const`-constructible: the derive macro writes a `ModelDescription`
//! literal, and [`encode`] runs in const evaluation.

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

    const fn from_code(c: u8) -> Option<VarType> {
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

    const fn from_code(c: u8) -> Option<IntervalVariability> {
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

    const fn is_none(&self) -> bool {
        !self.only
            && self.max_size.is_none()
            && self.mime_type.is_empty()
            && self.dimensions.is_empty()
            && !self.has_clock_part()
    }

    /// Whether the variable is a Clock or clocked (the encoding's clocks block).
    const fn has_clock_part(&self) -> bool {
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

/// An FMI version. A binary made with `rustfmu::export_fmu!` implements both (its `fmi2*` and
/// its `fmi3*` functions, and one encoded description per version); `export_fmi2!` or
/// `export_fmi3!` alone gives a binary of one version.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum FmiVersion {
    V2,
    V3,
}

impl FmiVersion {
    /// `fmiVersion` of the model description.
    pub const fn text(self) -> &'static str {
        match self {
            FmiVersion::V2 => "2.0",
            FmiVersion::V3 => "3.0",
        }
    }
}

/// What an FMU offers besides its variables; set by the export macro.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Interfaces {
    pub co_simulation: bool,
    pub model_exchange: bool,
    pub version: FmiVersion,
    /// FMI 2.0 co-simulation `canInterpolateInputs`: the step follows the first derivatives of
    /// the Real inputs given with fmi2SetRealInputDerivatives
    /// ([`crate::CoSimulation::INTERPOLATES_INPUTS`]).
    pub can_interpolate_inputs: bool,
    /// FMI 3.0 Scheduled Execution (`<ScheduledExecution>`, `#[fmu(scheduled_execution)]`).
    pub scheduled_execution: bool,
}

impl Interfaces {
    pub const CO_SIMULATION: Interfaces = Interfaces {
        co_simulation: true,
        model_exchange: false,
        version: FmiVersion::V2,
        can_interpolate_inputs: false,
        scheduled_execution: false,
    };
    /// Model exchange and co-simulation in one binary: what `export_fmi2!` exports.
    pub const BOTH: Interfaces = Interfaces {
        co_simulation: true,
        model_exchange: true,
        version: FmiVersion::V2,
        can_interpolate_inputs: false,
        scheduled_execution: false,
    };
    /// ... and what `export_fmi3!` exports.
    pub const BOTH_FMI3: Interfaces = Interfaces {
        co_simulation: true,
        model_exchange: true,
        version: FmiVersion::V3,
        can_interpolate_inputs: false,
        scheduled_execution: false,
    };
}

/// Everything the model description says, as declared.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelDescription {
    /// `modelName`, and `modelIdentifier`: the binary is `<identifier>.so` / `.dll`.
    pub model_identifier: &'static str,
    pub description: &'static str,
    pub author: &'static str,
    pub version: &'static str,
    pub copyright: &'static str,
    pub license: &'static str,
    pub generation_tool: &'static str,
    pub default_experiment: Option<DefaultExperiment>,
    /// Every unit the variables use, with its base units.
    pub units: &'static [Unit],
    /// The model's own log categories; the runtime's ([`RUNTIME_LOG_CATEGORIES`]) come first.
    pub log_categories: &'static [LogCategory],
    /// In `ModelVariables` order.
    pub variables: &'static [Variable],
    /// The model's other fields (`name: Type; ...`): part of the FMU state, so part of the GUID
    /// (a changed internal state changes the GUID, and old serialized states are refused).
    pub internal_state: &'static str,
    /// The event indicators (variables declared `event_indicator`), by name, in declaration
    /// order: FMI 2.0's `numberOfEventIndicators` and the order of `fmi2GetEventIndicators`,
    /// FMI 3.0's `<EventIndicator>` elements.
    pub event_indicators: &'static [&'static str],
    /// FMI 3.0 terminals (`terminalsAndIcons/terminalsAndIcons.xml`): named groups of
    /// variables an importer connects as one (a mechanical flange: angle, speed, torque).
    pub terminals: &'static [Terminal],
}

/// An FMI 3.0 `<Terminal>` (FMI 3.0, 2.4.9): variables that belong together.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Terminal {
    pub name: &'static str,
    /// `terminalKind`: what kind of connector it is, for the importer to match (e.g.
    /// `org.modelica.Modelica.Mechanics.Rotational.Interfaces.Flange_a`); empty for none.
    pub kind: &'static str,
    /// `matchingRule`: `plug` (connect members of the same name), `bus` or `sequence`.
    pub matching_rule: &'static str,
    pub description: &'static str,
    pub members: &'static [TerminalMember],
}

/// A `<TerminalMemberVariable>`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TerminalMember {
    /// The model variable's name.
    pub variable: &'static str,
    /// `memberName`: its name in the terminal (what a `plug` matches).
    pub member: &'static str,
    /// `variableKind`: `signal` (a potential or signal: angle, speed), `inflow` or `outflow`
    /// (a flow, positive into resp. out of the FMU: torque).
    pub kind: &'static str,
}

/// Whether some variable of `$d` satisfies the condition (a `const fn` cannot take a closure:
/// the loop is written once here).
macro_rules! any_variable {
    ($d:expr, |$v:ident| $cond:expr) => {{
        let mut i = 0;
        let mut found = false;
        while i < $d.variables.len() {
            let $v = &$d.variables[i];
            if $cond {
                found = true;
                break;
            }
            i += 1;
        }
        found
    }};
}

impl ModelDescription {
    pub fn variable(&self, vr: u32, ty: VarType) -> Option<&'static Variable> {
        self.variables
            .iter()
            .find(|v| v.value_reference == vr && same_api_type(v.var_type, ty))
    }

    pub fn by_name(&self, name: &str) -> Option<&'static Variable> {
        self.variables.iter().find(|v| v.name == name)
    }

    /// Every declared enumeration type, once each, in the order the variables first use them.
    pub fn enumerations(&self) -> Vec<&'static EnumType> {
        let mut out: Vec<&'static EnumType> = Vec::new();
        for v in self.variables {
            if let Some(e) = v.enumeration
                && !out.iter().any(|o| o.name == e.name)
            {
                out.push(e);
            }
        }
        out
    }

    /// FMI 3.0 requires the independent variable among the variables: a declared
    /// `independent` one, or else `time` with the value reference one above the highest
    /// declared (the runtime answers it with the current time). Its value reference.
    /// (`const`: the runtime evaluates it at compile time.)
    pub const fn time_value_reference(&self) -> u32 {
        let mut next = 0u32;
        let mut i = 0;
        while i < self.variables.len() {
            let v = &self.variables[i];
            if let Causality::Independent = v.causality {
                return v.value_reference;
            }
            if v.value_reference.saturating_add(1) > next {
                next = v.value_reference.saturating_add(1);
            }
            i += 1;
        }
        next
    }

    /// Whether some variable exists in FMI 3.0 only (a type 2.0 lacks, an array, `fmi3_only`).
    pub const fn has_fmi3_only(&self) -> bool {
        any_variable!(self, |v| !v.in_version(FmiVersion::V2))
    }

    /// Whether some array variable is in the FMI 2.0 description (as its elements, scalars of
    /// structured names: [`Variable::element_name`]). (`const`: the FMI 2.0 functions of a model
    /// without one never look for elements.)
    pub const fn has_fmi2_arrays(&self) -> bool {
        any_variable!(self, |v| v.is_array() && v.in_version(FmiVersion::V2))
    }

    /// FMI 2.0's view of an array: the array variable (its index in `variables`) and the
    /// element (row-major) that the FMI 2.0 value reference `vr` names. An array of FMI 2.0 is
    /// its elements, scalars with the value references `vr, vr + 1, ..` of the array's `vr`
    /// (the derive keeps that range free of other variables). `None`: `vr` names no element.
    pub fn fmi2_element(&self, vr: u32) -> Option<(usize, usize)> {
        self.variables.iter().enumerate().find_map(|(i, v)| {
            let k = vr.checked_sub(v.value_reference)? as usize;
            (v.is_array() && k < v.element_count() && v.in_version(FmiVersion::V2)).then_some((i, k))
        })
    }

    /// Whether the FMI 2.0 value references of the elements of array `variables[i]` (its `vr`
    /// to `vr + n - 1`) take another variable's value reference. (`const`: the derive asserts
    /// at compile time that they do not.)
    pub const fn fmi2_elements_overlap(&self, i: usize) -> bool {
        let a = &self.variables[i];
        if !a.is_array() || !a.in_version(FmiVersion::V2) {
            return false;
        }
        let (first, n) = (a.value_reference as u64, a.element_count() as u64);
        let mut j = 0;
        while j < self.variables.len() {
            let v = &self.variables[j];
            let vr = v.value_reference as u64;
            if j != i {
                // The other's own range (its elements too, if it is an array of FMI 2.0).
                let m = if v.is_array() && v.in_version(FmiVersion::V2) {
                    v.element_count() as u64
                } else {
                    1
                };
                if vr < first + n && first < vr + m {
                    return true;
                }
            }
            j += 1;
        }
        false
    }

    /// Whether some variable is a Clock. (`const`: the clock functions of a model without one
    /// refuse every call at compile time.)
    pub const fn has_clocks(&self) -> bool {
        any_variable!(self, |v| v.fmi3.clock.is_some())
    }

    /// Whether some variable is an array (FMI 3.0 `<Dimension>`s). (`const`: the runtime takes
    /// the scalar-only paths of a model without arrays at compile time.)
    pub const fn has_arrays(&self) -> bool {
        any_variable!(self, |v| v.is_array())
    }

    /// Whether some Binary variable has a `maxSize`. (`const`: a model without one skips the
    /// check of what it wrote into its Binaries at compile time.)
    pub const fn has_max_sizes(&self) -> bool {
        any_variable!(self, |v| v.fmi3.max_size.is_some())
    }

    /// Whether some variable is a structural parameter (FMI 3.0): then the FMU has
    /// Configuration Mode (`fmi3EnterConfigurationMode`).
    pub const fn has_structural_parameters(&self) -> bool {
        any_variable!(self, |v| matches!(v.causality, Causality::StructuralParameter))
    }

    /// Whether some array's length is set by a structural parameter.
    pub const fn has_sized_arrays(&self) -> bool {
        any_variable!(self, |v| v.is_sized())
    }

    /// Whether the model declares its independent variable itself (else FMI 3.0 adds `time`).
    pub const fn declares_independent(&self) -> bool {
        any_variable!(self, |v| matches!(v.causality, Causality::Independent))
    }

    /// Whether `v` is a continuous state: some variable is declared its derivative.
    pub fn is_state(&self, v: &Variable) -> bool {
        self.variables.iter().any(|d| d.derivative_of == Some(v.name))
    }

    /// The unknowns of Initialization Mode (FMI 2.0 `InitialUnknowns`, FMI 3.0
    /// `InitialUnknown`, the same rule in both): outputs, continuous states and their
    /// derivatives whose `initial` is approx or calculated, and every calculated parameter.
    /// Clocked variables are not among them (FMI 3.0, 2.4.8: they are initialized at their
    /// clocks' first tick).
    pub fn is_initial_unknown(&self, v: &Variable) -> bool {
        let computed = v.causality == Causality::Output || v.derivative_of.is_some() || self.is_state(v);
        let unknown = (computed && matches!(v.effective_initial(), Some(Initial::Approx | Initial::Calculated)))
            || v.causality == Causality::CalculatedParameter;
        unknown && !v.is_clocked()
    }

    /// The value references `vr` depends on as `<ModelStructure>` says (FMI 3.0
    /// `fmi3GetVariableDependencies`): in Initialization Mode (`initialization`) those of an
    /// `<InitialUnknown>`, else those of an `<Output>`, `<ContinuousStateDerivative>` or
    /// `<EventIndicator>`; where the declaration names none, every known (run time: the
    /// inputs and continuous states; Initialization Mode: the inputs, the independent variable
    /// `time_vr`, and the variables with initial = exact). In ascending order. `None`: `vr` is
    /// no unknown there.
    pub fn dependencies(&self, vr: u32, initialization: bool, time_vr: u32) -> Option<Vec<u32>> {
        let v = self.variables.iter().find(|v| v.value_reference == vr)?;
        let declared = if initialization {
            if !self.is_initial_unknown(v) {
                return None;
            }
            v.initial_depends_on
        } else {
            let unknown = v.causality == Causality::Output
                || v.derivative_of.is_some()
                || self.event_indicators.contains(&v.name);
            if !unknown {
                return None;
            }
            v.depends_on
        };
        let mut out: Vec<u32> = match declared {
            Some(names) => names
                .iter()
                .filter_map(|n| self.by_name(n))
                .map(|d| d.value_reference)
                .collect(),
            None if initialization => self
                .variables
                .iter()
                .filter(|d| {
                    matches!(d.causality, Causality::Input | Causality::Independent)
                        || d.effective_initial() == Some(Initial::Exact)
                })
                .map(|d| d.value_reference)
                .chain((!self.declares_independent()).then_some(time_vr))
                .collect(),
            None => self
                .variables
                .iter()
                .filter(|d| d.causality == Causality::Input || self.is_state(d))
                .map(|d| d.value_reference)
                .collect(),
        };
        out.sort_unstable();
        out.dedup();
        Some(out)
    }

    /// Runtime categories first, then the model's own.
    pub fn all_log_categories(&self) -> impl Iterator<Item = &'static LogCategory> {
        RUNTIME_LOG_CATEGORIES.iter().chain(self.log_categories.iter())
    }
}

/// Enumerations travel through `fmi2GetInteger`/`fmi2SetInteger`.
pub fn same_api_type(declared: VarType, asked: VarType) -> bool {
    declared == asked || (declared == VarType::Enumeration && asked == VarType::Integer)
}

/// The categories every FMU of this runtime logs under, in the runtime's order.
pub const RUNTIME_LOG_CATEGORIES: &[LogCategory] = &[
    LogCategory {
        name: "logEvents",
        description: "Initialization, steps that change the solver's course, parameter changes",
    },
    LogCategory {
        name: "logStatusWarning",
        description: "Messages that come with fmi2Warning",
    },
    LogCategory {
        name: "logStatusDiscard",
        description: "Messages that come with fmi2Discard: a step that could not be completed",
    },
    LogCategory {
        name: "logStatusError",
        description: "Messages that come with fmi2Error: a refused call or argument",
    },
    LogCategory {
        name: "logStatusFatal",
        description: "Messages that come with fmi2Fatal: the instance cannot be used any more",
    },
    LogCategory {
        name: "logCalls",
        description: "Every call of an fmi2 function, with its arguments",
    },
    LogCategory {
        name: "logAll",
        description: "All of the above",
    },
];

// ---- encoding ---------------------------------------------------------------------------------

/// Marks the encoded description inside a built library, where `cargo fmu` finds it.
pub const MAGIC: &[u8; 24] = b"\0RUSTFMU-DESCRIPTION-V1\0";
/// Bump when the encoding changes shape.
pub const FORMAT_VERSION: u32 = 1;

/// A const-evaluable byte writer; with an empty buffer it only counts.
struct Enc<'a> {
    buf: &'a mut [u8],
    pos: usize,
}

impl Enc<'_> {
    const fn u8(&mut self, b: u8) {
        if self.pos < self.buf.len() {
            self.buf[self.pos] = b;
        }
        self.pos += 1;
    }
    const fn bytes(&mut self, b: &[u8]) {
        let mut i = 0;
        while i < b.len() {
            self.u8(b[i]);
            i += 1;
        }
    }
    const fn u32(&mut self, x: u32) {
        self.bytes(&x.to_le_bytes());
    }
    const fn i32(&mut self, x: i32) {
        self.bytes(&x.to_le_bytes());
    }
    const fn f64(&mut self, x: f64) {
        self.bytes(&x.to_bits().to_le_bytes());
    }
    const fn str(&mut self, s: &str) {
        self.u32(s.len() as u32);
        self.bytes(s.as_bytes());
    }
    const fn opt_f64(&mut self, x: Option<f64>) {
        match x {
            None => self.u8(0),
            Some(x) => {
                self.u8(1);
                self.f64(x);
            }
        }
    }
    const fn opt_str(&mut self, x: Option<&str>) {
        match x {
            None => self.u8(0),
            Some(s) => {
                self.u8(1);
                self.str(s);
            }
        }
    }
    const fn bound(&mut self, b: Option<Bound>) {
        match b {
            None => self.u8(0),
            Some(b) => {
                self.u8(if b.exclusive { 2 } else { 1 });
                self.f64(b.value);
            }
        }
    }
    const fn enum_type(&mut self, e: &EnumType) {
        self.str(e.name);
        self.str(e.description);
        self.u32(e.items.len() as u32);
        let mut i = 0;
        while i < e.items.len() {
            self.str(e.items[i].name);
            self.i32(e.items[i].value);
            self.str(e.items[i].description);
            i += 1;
        }
    }
    const fn variable(&mut self, d: &ModelDescription, version: FmiVersion, v: &Variable) {
        self.str(v.name);
        self.u32(v.value_reference);
        self.rest(d, version, v, &v.start);
    }
    /// Element `k` of an array, as the scalar FMI 2.0 makes of it: `name[i,j]` (indices from 1),
    /// value reference `vr + k`, the element's start, the array's other attributes.
    const fn element(&mut self, d: &ModelDescription, v: &Variable, k: usize) {
        self.element_name_only(v, k);
        self.u32(v.value_reference + k as u32);
        let start = match v.start {
            Start::Array(items) if k < items.len() => items[k],
            _ => Start::None,
        };
        self.rest(d, FmiVersion::V2, v, &start);
    }
    /// The name of element `k` of array `v` (as [`Enc::str`] writes a name): `name[i,j]`.
    const fn element_name_only(&mut self, v: &Variable, k: usize) {
        let dims = v.fmi3.dimensions;
        // The indices, outermost first (at most 2 dimensions: the derive refuses more), and the
        // name's length.
        let mut indices = [0usize; 8];
        let mut len = v.name.len() + 1;
        let mut rest = k;
        let mut j = dims.len();
        while j > 0 {
            j -= 1;
            let n = if dims[j] == 0 { 1 } else { dims[j] as usize };
            indices[j] = rest % n + 1;
            rest /= n;
            len += digits(indices[j]) + 1;
        }
        self.u32(len as u32);
        self.bytes(v.name.as_bytes());
        self.u8(b'[');
        let mut j = 0;
        while j < dims.len() {
            if j > 0 {
                self.u8(b',');
            }
            self.decimal(indices[j]);
            j += 1;
        }
        self.u8(b']');
    }
    const fn decimal(&mut self, x: usize) {
        let mut div = 1;
        while x / div >= 10 {
            div *= 10;
        }
        while div > 0 {
            self.u8(b'0' + (x / div % 10) as u8);
            div /= 10;
        }
    }
    /// A variable's attributes after its name and value reference.
    const fn rest(&mut self, d: &ModelDescription, version: FmiVersion, v: &Variable, start: &Start) {
        self.u8(v.var_type as u8);
        self.u8(v.causality as u8);
        self.u8(v.variability as u8);
        match v.initial {
            None => self.u8(255),
            Some(i) => self.u8(i as u8),
        }
        self.start(start);
        self.str(v.unit);
        self.str(v.description);
        self.bound(v.min);
        self.bound(v.max);
        self.opt_f64(v.nominal);
        self.dependency_names(d, version, v.depends_on);
        self.dependency_names(d, version, v.initial_depends_on);
        self.opt_str(v.derivative_of);
        match v.enumeration {
            None => self.u8(0),
            Some(e) => {
                self.u8(1);
                self.enum_type(e);
            }
        }
    }
    /// [`Enc::names`] of dependencies; in FMI 2.0 an array named there is each of its elements.
    const fn dependency_names(&mut self, d: &ModelDescription, version: FmiVersion, names: Option<&[&str]>) {
        let Some(deps) = names else {
            return self.names(None);
        };
        if matches!(version, FmiVersion::V3) || !d.has_fmi2_arrays() {
            return self.names(names);
        }
        let mut n = 0;
        let mut i = 0;
        while i < deps.len() {
            n += match fmi2_array_named(d, deps[i]) {
                Some(a) => a.element_count(),
                None => 1,
            };
            i += 1;
        }
        self.u8(1);
        self.u32(n as u32);
        let mut i = 0;
        while i < deps.len() {
            match fmi2_array_named(d, deps[i]) {
                Some(a) => {
                    let mut k = 0;
                    while k < a.element_count() {
                        self.element_name_only(a, k);
                        k += 1;
                    }
                }
                None => self.str(deps[i]),
            }
            i += 1;
        }
    }
    const fn start(&mut self, start: &Start) {
        match *start {
            Start::None => self.u8(0),
            Start::Real(x) => {
                self.u8(1);
                self.f64(x);
            }
            Start::Integer(x) => {
                self.u8(2);
                self.i32(x);
            }
            Start::Boolean(x) => {
                self.u8(3);
                self.u8(x as u8);
            }
            Start::String(s) => {
                self.u8(4);
                self.str(s);
            }
            Start::Int64(x) => {
                self.u8(5);
                self.bytes(&x.to_le_bytes());
            }
            Start::UInt64(x) => {
                self.u8(6);
                self.bytes(&x.to_le_bytes());
            }
            Start::Binary(b) => {
                self.u8(7);
                self.u32(b.len() as u32);
                self.bytes(b);
            }
            Start::Array(items) => {
                self.u8(8);
                self.u32(items.len() as u32);
                let mut i = 0;
                while i < items.len() {
                    self.start(&items[i]);
                    i += 1;
                }
            }
        }
    }
    /// An optional list of names (`depends`, `initial_depends`).
    const fn names(&mut self, names: Option<&[&str]>) {
        match names {
            None => self.u8(0),
            Some(deps) => {
                self.u8(1);
                self.u32(deps.len() as u32);
                let mut i = 0;
                while i < deps.len() {
                    self.str(deps[i]);
                    i += 1;
                }
            }
        }
    }
    const fn description(&mut self, d: &ModelDescription, interfaces: Interfaces) {
        self.str(d.model_identifier);
        self.str(d.description);
        self.str(d.author);
        self.str(d.version);
        self.str(d.copyright);
        self.str(d.license);
        self.str(d.generation_tool);
        self.u8(interfaces.co_simulation as u8);
        self.u8(interfaces.model_exchange as u8);
        match d.default_experiment {
            None => self.u8(0),
            Some(e) => {
                self.u8(1);
                self.opt_f64(e.start_time);
                self.opt_f64(e.stop_time);
                self.opt_f64(e.tolerance);
                self.opt_f64(e.step_size);
            }
        }
        self.u32(d.units.len() as u32);
        let mut i = 0;
        while i < d.units.len() {
            let u = &d.units[i];
            self.str(u.name);
            let b = u.base;
            self.i32(b.kg);
            self.i32(b.m);
            self.i32(b.s);
            self.i32(b.a);
            self.i32(b.k);
            self.i32(b.mol);
            self.i32(b.cd);
            self.i32(b.rad);
            self.f64(b.factor);
            self.f64(b.offset);
            i += 1;
        }
        self.u32(d.log_categories.len() as u32);
        let mut i = 0;
        while i < d.log_categories.len() {
            self.str(d.log_categories[i].name);
            self.str(d.log_categories[i].description);
            i += 1;
        }
        // A version's description holds the variables of that version (FMI 2.0 leaves out the
        // FMI-3.0-only ones).
        // FMI 2.0 has no arrays: an array is its elements there, scalars of structured names
        // (`K[1,2]`) with the value references vr, vr + 1, .. ([`Variable::element_name`]).
        let version = interfaces.version;
        let mut n = 0u32;
        let mut extras = 0u32;
        let mut i = 0;
        while i < d.variables.len() {
            let v = &d.variables[i];
            if v.in_version(version) {
                if v.is_array() && matches!(version, FmiVersion::V2) {
                    n += v.element_count() as u32;
                } else {
                    n += 1;
                    if !v.fmi3.is_none() {
                        extras += 1;
                    }
                }
            }
            i += 1;
        }
        self.u32(n);
        let mut i = 0;
        while i < d.variables.len() {
            let v = &d.variables[i];
            if v.in_version(version) {
                if v.is_array() && matches!(version, FmiVersion::V2) {
                    let mut k = 0;
                    while k < v.element_count() {
                        self.element(d, v, k);
                        k += 1;
                    }
                } else {
                    self.variable(d, version, v);
                }
            }
            i += 1;
        }
        self.str(d.internal_state);
        // Only models with event indicators carry the block: the encodings (and GUIDs) of the
        // models without events are those before events existed.
        if !d.event_indicators.is_empty() {
            self.u8(EVENT_INDICATORS_TAG);
            self.names(Some(d.event_indicators));
        }
        // The terminals: FMI 3.0 only, and only where there are some.
        if !d.terminals.is_empty() && matches!(version, FmiVersion::V3) {
            self.u8(TERMINALS_TAG);
            self.u32(d.terminals.len() as u32);
            let mut i = 0;
            while i < d.terminals.len() {
                let t = &d.terminals[i];
                self.str(t.name);
                self.str(t.kind);
                self.str(t.matching_rule);
                self.str(t.description);
                self.u32(t.members.len() as u32);
                let mut j = 0;
                while j < t.members.len() {
                    self.str(t.members[j].variable);
                    self.str(t.members[j].member);
                    self.str(t.members[j].kind);
                    j += 1;
                }
                i += 1;
            }
        }
        // Likewise the FMI 3.0 declarations: only where some variable has one.
        if extras > 0 {
            self.u8(FMI3_EXTRAS_TAG);
            self.u32(extras);
            let (mut i, mut at) = (0, 0u32);
            while i < d.variables.len() {
                let v = &d.variables[i];
                if v.in_version(version) && v.is_array() && matches!(version, FmiVersion::V2) {
                    at += v.element_count() as u32;
                } else if v.in_version(version) {
                    if !v.fmi3.is_none() {
                        self.u32(at);
                        self.u8(v.fmi3.only as u8);
                        match v.fmi3.max_size {
                            None => self.u8(0),
                            Some(m) => {
                                self.u8(1);
                                self.u32(m);
                            }
                        }
                        self.str(v.fmi3.mime_type);
                        self.u32(v.fmi3.dimensions.len() as u32);
                        let mut k = 0;
                        while k < v.fmi3.dimensions.len() {
                            self.u32(v.fmi3.dimensions[k]);
                            k += 1;
                        }
                    }
                    at += 1;
                }
                i += 1;
            }
        }
        // The clocks and the clocked variables (FMI 3.0): only where there are some, so the
        // encodings (and instantiation tokens) of the models without clocks are those before.
        let mut clocked = 0u32;
        let mut i = 0;
        while i < d.variables.len() {
            if d.variables[i].in_version(version) && d.variables[i].fmi3.has_clock_part() {
                clocked += 1;
            }
            i += 1;
        }
        if clocked > 0 {
            self.u8(CLOCKS_TAG);
            self.u32(clocked);
            let (mut i, mut at) = (0, 0u32);
            while i < d.variables.len() {
                let v = &d.variables[i];
                if v.in_version(version) && v.is_array() && matches!(version, FmiVersion::V2) {
                    at += v.element_count() as u32;
                } else if v.in_version(version) {
                    if v.fmi3.has_clock_part() {
                        self.u32(at);
                        match v.fmi3.clock {
                            None => self.u8(0),
                            Some(c) => {
                                self.u8(1);
                                self.u8(c.interval_variability as u8);
                                self.opt_f64(c.interval);
                                self.str(c.interval_parameter);
                                self.f64(c.shift);
                                self.u8(c.can_be_deactivated as u8);
                            }
                        }
                        self.names(Some(v.fmi3.clocks));
                    }
                    at += 1;
                }
                i += 1;
            }
        }
        // The arrays sized by structural parameters: only where there are some, so the other
        // encodings are those before.
        let mut sized = 0u32;
        let mut i = 0;
        while i < d.variables.len() {
            if d.variables[i].in_version(version) && d.variables[i].is_sized() {
                sized += 1;
            }
            i += 1;
        }
        if sized > 0 {
            self.u8(SIZED_TAG);
            self.u32(sized);
            let (mut i, mut at) = (0, 0u32);
            while i < d.variables.len() {
                let v = &d.variables[i];
                if v.in_version(version) && v.is_array() && matches!(version, FmiVersion::V2) {
                    at += v.element_count() as u32;
                } else if v.in_version(version) {
                    if v.is_sized() {
                        self.u32(at);
                        self.u32(v.fmi3.sized_by.len() as u32);
                        let mut k = 0;
                        while k < v.fmi3.sized_by.len() {
                            self.u32(v.fmi3.sized_by[k]);
                            k += 1;
                        }
                    }
                    at += 1;
                }
                i += 1;
            }
        }
        // canInterpolateInputs: only where it is true, so the other encodings are those before.
        if interfaces.can_interpolate_inputs {
            self.u8(INTERPOLATES_INPUTS_TAG);
        }
        // The clocks' priorities (FMI 3.0): only where a clock has one, so the other encodings
        // are those before.
        let mut prioritized = 0u32;
        let mut i = 0;
        while i < d.variables.len() {
            if d.variables[i].in_version(version)
                && let Some(ClockDecl { priority: Some(_), .. }) = d.variables[i].fmi3.clock
            {
                prioritized += 1;
            }
            i += 1;
        }
        if prioritized > 0 {
            self.u8(PRIORITIES_TAG);
            self.u32(prioritized);
            let (mut i, mut at) = (0, 0u32);
            while i < d.variables.len() {
                let v = &d.variables[i];
                if v.in_version(version) && v.is_array() && matches!(version, FmiVersion::V2) {
                    at += v.element_count() as u32;
                } else if v.in_version(version) {
                    if let Some(ClockDecl { priority: Some(p), .. }) = v.fmi3.clock {
                        self.u32(at);
                        self.u32(p);
                    }
                    at += 1;
                }
                i += 1;
            }
        }
        // Scheduled Execution: only where it is offered.
        if interfaces.scheduled_execution {
            self.u8(SCHEDULED_EXECUTION_TAG);
        }
        // Display units and aliases: only where there are some, so the other encodings are
        // those before.
        self.display_units_and_aliases(d, version);
        // FMI 3.0 binaries end with the version; FMI 2.0 encodings (and so their GUIDs) are
        // those of the releases before FMI 3.0 existed.
        if let FmiVersion::V3 = interfaces.version {
            self.u8(3);
        }
    }
}

impl Enc<'_> {
    /// The block of display units and aliases ([`DISPLAY_TAG`]): the units' display units (by
    /// the unit's index), then each variable's display unit and aliases (by its index in the
    /// version's variables; in FMI 2.0 an array's display unit is each element's, and an array
    /// has no aliases there). Left out where the model declares none.
    const fn display_units_and_aliases(&mut self, d: &ModelDescription, version: FmiVersion) {
        let mut units = 0u32;
        let mut i = 0;
        while i < d.units.len() {
            if !d.units[i].display_units.is_empty() {
                units += 1;
            }
            i += 1;
        }
        let mut entries = 0u32;
        let mut i = 0;
        while i < d.variables.len() {
            let v = &d.variables[i];
            if v.in_version(version) {
                if v.is_array() && matches!(version, FmiVersion::V2) {
                    if !v.display_unit.is_empty() {
                        entries += v.element_count() as u32;
                    }
                } else if !v.display_unit.is_empty() || !v.aliases.is_empty() {
                    entries += 1;
                }
            }
            i += 1;
        }
        if units == 0 && entries == 0 {
            return;
        }
        self.u8(DISPLAY_TAG);
        self.u32(units);
        let mut i = 0;
        while i < d.units.len() {
            let du = d.units[i].display_units;
            if !du.is_empty() {
                self.u32(i as u32);
                self.u32(du.len() as u32);
                let mut k = 0;
                while k < du.len() {
                    self.str(du[k].name);
                    self.f64(du[k].factor);
                    self.f64(du[k].offset);
                    self.u8(du[k].inverse as u8);
                    k += 1;
                }
            }
            i += 1;
        }
        self.u32(entries);
        let (mut i, mut at) = (0, 0u32);
        while i < d.variables.len() {
            let v = &d.variables[i];
            if v.in_version(version) && v.is_array() && matches!(version, FmiVersion::V2) {
                let mut k = 0;
                while k < v.element_count() {
                    if !v.display_unit.is_empty() {
                        self.u32(at);
                        self.str(v.display_unit);
                        self.u32(0);
                    }
                    at += 1;
                    k += 1;
                }
            } else if v.in_version(version) {
                if !v.display_unit.is_empty() || !v.aliases.is_empty() {
                    self.u32(at);
                    self.str(v.display_unit);
                    self.u32(v.aliases.len() as u32);
                    let mut k = 0;
                    while k < v.aliases.len() {
                        self.str(v.aliases[k].name);
                        self.str(v.aliases[k].description);
                        self.str(v.aliases[k].display_unit);
                        k += 1;
                    }
                }
                at += 1;
            }
            i += 1;
        }
    }
}

/// How many decimal digits `x` has.
const fn digits(x: usize) -> usize {
    let mut n = 1;
    let mut x = x;
    while x >= 10 {
        x /= 10;
        n += 1;
    }
    n
}

/// The array variable of FMI 2.0's description named `name`, if any.
const fn fmi2_array_named(d: &ModelDescription, name: &str) -> Option<&'static Variable> {
    let mut i = 0;
    while i < d.variables.len() {
        let v = &d.variables[i];
        if v.is_array() && v.in_version(FmiVersion::V2) && str_eq(v.name, name) {
            return Some(v);
        }
        i += 1;
    }
    None
}

const fn str_eq(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

const HEADER: usize = MAGIC.len() + 4 + 4;
/// Marks the event indicators' block after the internal state (distinct from the version tag 3).
const EVENT_INDICATORS_TAG: u8 = 0xE1;
/// Marks the block of FMI 3.0 declarations ([`Fmi3Extras`]) after that.
const FMI3_EXTRAS_TAG: u8 = 0xE2;
/// Marks the terminals' block (FMI 3.0 encodings only), before the FMI 3.0 declarations.
const TERMINALS_TAG: u8 = 0xE3;
/// Marks the block of the clocks and clocked variables, after the FMI 3.0 declarations.
const CLOCKS_TAG: u8 = 0xE4;
/// Marks a co-simulation step that follows input derivatives (canInterpolateInputs), last.
const INTERPOLATES_INPUTS_TAG: u8 = 0xE5;
/// Marks the block of arrays sized by structural parameters, after the clocks.
const SIZED_TAG: u8 = 0xE6;
/// Marks the clocks' priorities.
const PRIORITIES_TAG: u8 = 0xE7;
/// Marks an FMU that offers Scheduled Execution.
const SCHEDULED_EXECUTION_TAG: u8 = 0xE8;
/// Marks the block of display units and aliases, after Scheduled Execution.
const DISPLAY_TAG: u8 = 0xE9;
/// [`Fmi3Extras::sized_by`] of a dimension of fixed length.
pub const NOT_SIZED: u32 = u32::MAX;

const fn write(d: &ModelDescription, interfaces: Interfaces, buf: &mut [u8]) -> usize {
    let mut body = Enc { buf, pos: 0 };
    body.bytes(MAGIC);
    body.u32(FORMAT_VERSION);
    body.u32(0); // payload length, filled in below
    body.description(d, interfaces);
    let total = body.pos;
    let len = ((total - HEADER) as u32).to_le_bytes();
    if body.buf.len() >= HEADER {
        let mut i = 0;
        while i < 4 {
            body.buf[MAGIC.len() + 4 + i] = len[i];
            i += 1;
        }
    }
    total
}

/// Length of [`encode`]'s output, for the array it is written into.
pub const fn encoded_len(d: &ModelDescription, interfaces: Interfaces) -> usize {
    write(d, interfaces, &mut [])
}

/// The description as bytes: [`MAGIC`], format version, payload length, payload.
/// `N` must be [`encoded_len`] of the same arguments.
pub const fn encode<const N: usize>(d: &ModelDescription, interfaces: Interfaces) -> [u8; N] {
    let mut out = [0u8; N];
    let n = write(d, interfaces, &mut out);
    assert!(n == N, "encode: N is not encoded_len of the same description");
    out
}

/// [`encode`] at run time, for tools and tests.
pub fn encode_to_vec(d: &ModelDescription, interfaces: Interfaces) -> Vec<u8> {
    let mut out = vec![0u8; encoded_len(d, interfaces)];
    write(d, interfaces, &mut out);
    out
}

/// `{xxxxxxxx-xxxx-5xxx-yxxx-xxxxxxxxxxxx}`: a name-based SHA-1 UUID (RFC 4122, version 5) of
/// the encoded description; [`MAGIC`] at its start plays the namespace's part.
pub const fn guid(encoded: &[u8]) -> [u8; 38] {
    let digest = const_sha1::sha1(encoded).as_bytes();
    let mut b = [0u8; 16];
    let mut i = 0;
    while i < 16 {
        b[i] = digest[i];
        i += 1;
    }
    b[6] = (b[6] & 0x0f) | 0x50;
    b[8] = (b[8] & 0x3f) | 0x80;
    const HEX: &[u8; 16] = b"0123456789abcdef";
    let mut out = [0u8; 38];
    out[0] = b'{';
    let mut at = 1;
    let mut i = 0;
    while i < 16 {
        if i == 4 || i == 6 || i == 8 || i == 10 {
            out[at] = b'-';
            at += 1;
        }
        out[at] = HEX[(b[i] >> 4) as usize];
        out[at + 1] = HEX[(b[i] & 0xf) as usize];
        at += 2;
        i += 1;
    }
    out[37] = b'}';
    out
}

/// [`guid`] as text.
pub fn guid_string(encoded: &[u8]) -> String {
    String::from_utf8_lossy(&guid(encoded)).into_owned()
}

// ---- decoding (for cargo fmu; the FMU itself never decodes) ---------------------------------

/// Finds the first encoded description in a built library (ELF, PE or Mach-O alike: it looks
/// for [`MAGIC`]) and returns exactly its bytes. A binary of both FMI versions carries two:
/// [`find_all_encoded`], [`find_encoded_for`].
pub fn find_encoded(binary: &[u8]) -> Result<&[u8], String> {
    Ok(find_all_encoded(binary)?[0])
}

/// The encoded description that starts at `at` (where [`MAGIC`] is).
fn encoded_at(binary: &[u8], at: usize) -> Result<&[u8], String> {
    let rest = &binary[at..];
    if rest.len() < HEADER {
        return Err("the embedded description is truncated".into());
    }
    let version = u32::from_le_bytes(rest[MAGIC.len()..MAGIC.len() + 4].try_into().expect("4 bytes"));
    if version != FORMAT_VERSION {
        return Err(format!(
            "the embedded description has format version {version}; this cargo-fmu reads version {FORMAT_VERSION} (use the cargo-fmu of the same rustfmu release)"
        ));
    }
    let len = u32::from_le_bytes(rest[MAGIC.len() + 4..HEADER].try_into().expect("4 bytes")) as usize;
    rest.get(..HEADER + len)
        .ok_or_else(|| "the embedded description is truncated".to_string())
}

/// Every encoded description in a built library, in the order they appear: one per FMI version
/// it exports (two for `export_fmu!`). [`MAGIC`] can also occur as a constant of the code (a
/// Windows DLL keeps rustfmu's own copy of it): an occurrence that does not decode is not a
/// description. An error when there is none: the reason the first occurrence did not decode
/// (an older format, a damaged file), or that there is no occurrence at all.
pub fn find_all_encoded(binary: &[u8]) -> Result<Vec<&[u8]>, String> {
    let mut out = Vec::new();
    let mut first_error = None;
    let mut from = 0;
    while let Some(at) = binary[from..].windows(MAGIC.len()).position(|w| w == MAGIC) {
        let at = from + at;
        match encoded_at(binary, at).and_then(|e| decode(e).map(|_| e)) {
            Ok(e) => {
                out.push(e);
                from = at + e.len();
            }
            Err(why) => {
                first_error.get_or_insert(why);
                from = at + 1;
            }
        }
    }
    if out.is_empty() {
        return Err(first_error.unwrap_or_else(|| {
            "the library carries no rustfmu description (is it a cdylib that calls rustfmu::export_fmu!, export_fmi2! or export_fmi3!?)".into()
        }));
    }
    Ok(out)
}

/// The encoded description of FMI `version` in a built library, or why there is none.
pub fn find_encoded_for(binary: &[u8], version: FmiVersion) -> Result<&[u8], String> {
    let all = find_all_encoded(binary)?;
    let mut has = Vec::new();
    for e in all {
        let (_, interfaces) = decode(e)?;
        if interfaces.version == version {
            return Ok(e);
        }
        has.push(interfaces.version.text());
    }
    Err(format!(
        "the library implements FMI {} only, not FMI {} (it calls rustfmu::export_fmi{}! itself; \
         rustfmu::export_fmu! exports both versions)",
        has.join(" and "),
        version.text(),
        &has[0][..1]
    ))
}

struct Dec<'a> {
    b: &'a [u8],
    at: usize,
}

fn leak(s: String) -> &'static str {
    Box::leak(s.into_boxed_str())
}

fn leak_slice<T>(v: Vec<T>) -> &'static [T] {
    Box::leak(v.into_boxed_slice())
}

impl Dec<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        let end = self.at.checked_add(n).filter(|e| *e <= self.b.len()).ok_or_else(|| {
            format!(
                "the embedded description ends early (wanted {n} bytes at offset {})",
                self.at
            )
        })?;
        let s = &self.b[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
    }
    fn i32(&mut self) -> Result<i32, String> {
        Ok(i32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
    }
    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_bits(u64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        )))
    }
    fn str(&mut self) -> Result<&'static str, String> {
        let n = self.u32()? as usize;
        let bytes = self.take(n)?.to_vec();
        String::from_utf8(bytes)
            .map(leak)
            .map_err(|_| "a text in the embedded description is not UTF-8".to_string())
    }
    fn opt_f64(&mut self) -> Result<Option<f64>, String> {
        Ok(if self.u8()? == 0 { None } else { Some(self.f64()?) })
    }
    fn bound(&mut self) -> Result<Option<Bound>, String> {
        Ok(match self.u8()? {
            0 => None,
            tag => Some(Bound {
                value: self.f64()?,
                exclusive: tag == 2,
            }),
        })
    }
    fn names(&mut self) -> Result<Option<&'static [&'static str]>, String> {
        Ok(match self.u8()? {
            0 => None,
            _ => {
                let n = self.count()?;
                let names = (0..n).map(|_| self.str()).collect::<Result<Vec<_>, _>>()?;
                Some(leak_slice(names))
            }
        })
    }
    fn count(&mut self) -> Result<usize, String> {
        let n = self.u32()? as usize;
        // Every element takes at least one byte: a larger count is corrupt, not a huge model.
        if n > self.b.len() - self.at {
            return Err(format!(
                "the embedded description claims {n} elements at offset {}",
                self.at
            ));
        }
        Ok(n)
    }
    fn start(&mut self, name: &str) -> Result<Start, String> {
        Ok(match self.u8()? {
            0 => Start::None,
            1 => Start::Real(self.f64()?),
            2 => Start::Integer(self.i32()?),
            3 => Start::Boolean(self.u8()? != 0),
            4 => Start::String(self.str()?),
            5 => Start::Int64(i64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes"))),
            6 => Start::UInt64(u64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes"))),
            7 => {
                let n = self.count()?;
                Start::Binary(leak_slice(self.take(n)?.to_vec()))
            }
            8 => {
                let n = self.count()?;
                let items = (0..n).map(|_| self.start(name)).collect::<Result<Vec<_>, _>>()?;
                Start::Array(leak_slice(items))
            }
            t => return Err(format!("'{name}': unknown start code {t}")),
        })
    }
    fn variable(&mut self) -> Result<Variable, String> {
        let name = self.str()?;
        let value_reference = self.u32()?;
        let t = self.u8()?;
        let var_type = VarType::from_code(t).ok_or_else(|| format!("'{name}': unknown type code {t}"))?;
        let c = self.u8()?;
        let causality = Causality::from_code(c).ok_or_else(|| format!("'{name}': unknown causality code {c}"))?;
        let v = self.u8()?;
        let variability = Variability::from_code(v).ok_or_else(|| format!("'{name}': unknown variability code {v}"))?;
        let initial = match self.u8()? {
            255 => None,
            i => Some(Initial::from_code(i).ok_or_else(|| format!("'{name}': unknown initial code {i}"))?),
        };
        let start = self.start(name)?;
        let unit = self.str()?;
        let description = self.str()?;
        let min = self.bound()?;
        let max = self.bound()?;
        let nominal = self.opt_f64()?;
        let depends_on = self.names()?;
        let initial_depends_on = self.names()?;
        let derivative_of = if self.u8()? == 0 { None } else { Some(self.str()?) };
        let enumeration = if self.u8()? == 0 {
            None
        } else {
            let name = self.str()?;
            let description = self.str()?;
            let n = self.count()?;
            let mut items = Vec::with_capacity(n);
            for _ in 0..n {
                items.push(EnumItem {
                    name: self.str()?,
                    value: self.i32()?,
                    description: self.str()?,
                });
            }
            Some(&*Box::leak(Box::new(EnumType {
                name,
                description,
                items: leak_slice(items),
            })))
        };
        Ok(Variable {
            name,
            value_reference,
            var_type,
            causality,
            variability,
            initial,
            start,
            unit,
            display_unit: "",
            aliases: &[],
            description,
            min,
            max,
            nominal,
            depends_on,
            initial_depends_on,
            derivative_of,
            enumeration,
            fmi3: Fmi3Extras::NONE,
        })
    }
}

/// Decodes what [`encode`] wrote (as [`find_encoded`] returns it). The texts are leaked: this is
/// for short-lived tools such as `cargo fmu`, never for the FMU itself.
pub fn decode(encoded: &[u8]) -> Result<(ModelDescription, Interfaces), String> {
    if encoded.len() < HEADER || &encoded[..MAGIC.len()] != MAGIC {
        return Err("not an encoded rustfmu description".into());
    }
    let mut d = Dec {
        b: &encoded[HEADER..],
        at: 0,
    };
    let model_identifier = d.str()?;
    let description = d.str()?;
    let author = d.str()?;
    let version = d.str()?;
    let copyright = d.str()?;
    let license = d.str()?;
    let generation_tool = d.str()?;
    let mut interfaces = Interfaces {
        co_simulation: d.u8()? != 0,
        model_exchange: d.u8()? != 0,
        version: FmiVersion::V2,
        can_interpolate_inputs: false,
        scheduled_execution: false,
    };
    let default_experiment = if d.u8()? == 0 {
        None
    } else {
        Some(DefaultExperiment {
            start_time: d.opt_f64()?,
            stop_time: d.opt_f64()?,
            tolerance: d.opt_f64()?,
            step_size: d.opt_f64()?,
        })
    };
    let n = d.count()?;
    let mut units = Vec::with_capacity(n);
    for _ in 0..n {
        units.push(Unit {
            name: d.str()?,
            base: BaseUnit {
                kg: d.i32()?,
                m: d.i32()?,
                s: d.i32()?,
                a: d.i32()?,
                k: d.i32()?,
                mol: d.i32()?,
                cd: d.i32()?,
                rad: d.i32()?,
                factor: d.f64()?,
                offset: d.f64()?,
            },
            display_units: &[],
        });
    }
    let n = d.count()?;
    let mut log_categories = Vec::with_capacity(n);
    for _ in 0..n {
        log_categories.push(LogCategory {
            name: d.str()?,
            description: d.str()?,
        });
    }
    let n = d.count()?;
    let mut variables = Vec::with_capacity(n);
    for _ in 0..n {
        variables.push(d.variable()?);
    }
    let internal_state = d.str()?;
    let mut event_indicators: &'static [&'static str] = &[];
    if d.at < d.b.len() && d.b[d.at] == EVENT_INDICATORS_TAG {
        d.u8()?;
        event_indicators = d.names()?.unwrap_or(&[]);
    }
    let mut terminals: Vec<Terminal> = Vec::new();
    if d.at < d.b.len() && d.b[d.at] == TERMINALS_TAG {
        d.u8()?;
        let n = d.count()?;
        for _ in 0..n {
            let (name, kind, matching_rule, description) = (d.str()?, d.str()?, d.str()?, d.str()?);
            let m = d.count()?;
            let members = (0..m)
                .map(|_| {
                    Ok(TerminalMember {
                        variable: d.str()?,
                        member: d.str()?,
                        kind: d.str()?,
                    })
                })
                .collect::<Result<Vec<_>, String>>()?;
            terminals.push(Terminal {
                name,
                kind,
                matching_rule,
                description,
                members: leak_slice(members),
            });
        }
    }
    if d.at < d.b.len() && d.b[d.at] == FMI3_EXTRAS_TAG {
        d.u8()?;
        let n = d.count()?;
        for _ in 0..n {
            let at = d.u32()? as usize;
            let only = d.u8()? != 0;
            let max_size = if d.u8()? == 0 { None } else { Some(d.u32()?) };
            let mime_type = d.str()?;
            let n_dims = d.count()?;
            let dimensions = leak_slice((0..n_dims).map(|_| d.u32()).collect::<Result<Vec<_>, _>>()?);
            let v = variables
                .get_mut(at)
                .ok_or_else(|| format!("FMI 3.0 declarations of variable {at}, beyond the variables"))?;
            v.fmi3 = Fmi3Extras {
                only,
                max_size,
                mime_type,
                dimensions,
                sized_by: &[],
                clock: None,
                clocks: &[],
            };
        }
    }
    if d.at < d.b.len() && d.b[d.at] == CLOCKS_TAG {
        d.u8()?;
        let n = d.count()?;
        for _ in 0..n {
            let at = d.u32()? as usize;
            let clock = if d.u8()? == 0 {
                None
            } else {
                let c = d.u8()?;
                let interval_variability = IntervalVariability::from_code(c)
                    .ok_or_else(|| format!("variable {at}: unknown intervalVariability code {c}"))?;
                Some(ClockDecl {
                    interval_variability,
                    interval: d.opt_f64()?,
                    interval_parameter: d.str()?,
                    shift: d.f64()?,
                    can_be_deactivated: d.u8()? != 0,
                    priority: None,
                })
            };
            let clocks = d.names()?.unwrap_or(&[]);
            let v = variables
                .get_mut(at)
                .ok_or_else(|| format!("the clocks of variable {at}, beyond the variables"))?;
            v.fmi3.clock = clock;
            v.fmi3.clocks = clocks;
        }
    }
    if d.at < d.b.len() && d.b[d.at] == SIZED_TAG {
        d.u8()?;
        let n = d.count()?;
        for _ in 0..n {
            let at = d.u32()? as usize;
            let n_dims = d.count()?;
            let sized_by = leak_slice((0..n_dims).map(|_| d.u32()).collect::<Result<Vec<_>, _>>()?);
            let v = variables
                .get_mut(at)
                .ok_or_else(|| format!("the sizes of variable {at}, beyond the variables"))?;
            v.fmi3.sized_by = sized_by;
        }
    }
    if d.at < d.b.len() && d.b[d.at] == INTERPOLATES_INPUTS_TAG {
        d.u8()?;
        interfaces.can_interpolate_inputs = true;
    }
    if d.at < d.b.len() && d.b[d.at] == PRIORITIES_TAG {
        d.u8()?;
        let n = d.count()?;
        for _ in 0..n {
            let at = d.u32()? as usize;
            let p = d.u32()?;
            match variables.get_mut(at).and_then(|v| v.fmi3.clock.as_mut()) {
                Some(c) => c.priority = Some(p),
                None => return Err(format!("a priority for variable {at}, which is no Clock")),
            }
        }
    }
    if d.at < d.b.len() && d.b[d.at] == SCHEDULED_EXECUTION_TAG {
        d.u8()?;
        interfaces.scheduled_execution = true;
    }
    // The last byte of an FMI 3.0 encoding is its version tag, never this block's tag.
    if d.at + 1 < d.b.len() && d.b[d.at] == DISPLAY_TAG {
        d.u8()?;
        let n = d.count()?;
        for _ in 0..n {
            let at = d.u32()? as usize;
            let k = d.count()?;
            let mut list = Vec::with_capacity(k);
            for _ in 0..k {
                list.push(DisplayUnit {
                    name: d.str()?,
                    factor: d.f64()?,
                    offset: d.f64()?,
                    inverse: d.u8()? != 0,
                });
            }
            let u = units
                .get_mut(at)
                .ok_or_else(|| format!("display units of unit {at}, beyond the units"))?;
            u.display_units = leak_slice(list);
        }
        let n = d.count()?;
        for _ in 0..n {
            let at = d.u32()? as usize;
            let display_unit = d.str()?;
            let k = d.count()?;
            let mut aliases = Vec::with_capacity(k);
            for _ in 0..k {
                aliases.push(Alias {
                    name: d.str()?,
                    description: d.str()?,
                    display_unit: d.str()?,
                });
            }
            let v = variables
                .get_mut(at)
                .ok_or_else(|| format!("the display unit and aliases of variable {at}, beyond the variables"))?;
            v.display_unit = display_unit;
            v.aliases = leak_slice(aliases);
        }
    }
    if d.at + 1 == d.b.len() {
        match d.u8()? {
            3 => interfaces.version = FmiVersion::V3,
            other => {
                return Err(format!(
                    "unknown FMI version tag {other} after the embedded description"
                ));
            }
        }
    }
    if d.at != d.b.len() {
        return Err(format!(
            "{} unexpected bytes after the embedded description",
            d.b.len() - d.at
        ));
    }
    Ok((
        ModelDescription {
            model_identifier,
            description,
            author,
            version,
            copyright,
            license,
            generation_tool,
            default_experiment,
            units: leak_slice(units),
            log_categories: leak_slice(log_categories),
            variables: leak_slice(variables),
            internal_state,
            event_indicators,
            terminals: leak_slice(terminals),
        },
        interfaces,
    ))
}

// ---- checks at compile time ---------------------------------------------------------------

/// What [`check_values`] finds wrong.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ValueError {
    /// min is not a finite number
    MinNotFinite,
    /// max is not a finite number
    MaxNotFinite,
    /// min is above max
    MinAboveMax,
    /// an Integer's min must be an integer within i32
    IntegerMin,
    /// an Integer's max must be an integer within i32
    IntegerMax,
    /// the start value is not a finite number
    StartNotFinite,
    /// the start value is below min
    StartBelowMin,
    /// the start value is above max
    StartAboveMax,
    /// nominal must be finite and > 0
    Nominal,
    /// the start value is no item of the enumeration
    StartNotAnItem,
    /// an integer's min must be an integer of its type, within ±2^53
    IntegerTypeMin,
    /// an integer's max must be an integer of its type, within ±2^53
    IntegerTypeMax,
}

impl ValueError {
    /// The same words as the compile error of `#[derive(Model)]`.
    pub const fn message(self) -> &'static str {
        match self {
            ValueError::MinNotFinite => "min is not a finite number",
            ValueError::MaxNotFinite => "max is not a finite number",
            ValueError::MinAboveMax => "min is above max",
            ValueError::IntegerMin => "an Integer's min must be an integer within i32",
            ValueError::IntegerMax => "an Integer's max must be an integer within i32",
            ValueError::StartNotFinite => "the start value is not a finite number",
            ValueError::StartBelowMin => "the start value is below min",
            ValueError::StartAboveMax => "the start value is above max",
            ValueError::Nominal => "nominal must be finite and > 0",
            ValueError::StartNotAnItem => "the start value is no item of the enumeration",
            ValueError::IntegerTypeMin => "an integer's min must be an integer of its type, within ±2^53",
            ValueError::IntegerTypeMax => "an integer's max must be an integer of its type, within ±2^53",
        }
    }
}

/// Checks of a declaration that need its values; `#[derive(Model)]` evaluates this for every
/// variable at compile time, so a violation is a compile error naming the variable.
pub const fn check_values(v: &Variable) -> Result<(), ValueError> {
    const fn finite(x: f64) -> bool {
        x.is_finite()
    }
    if let Some(b) = v.min
        && !finite(b.value)
    {
        return Err(ValueError::MinNotFinite);
    }
    if let Some(b) = v.max
        && !finite(b.value)
    {
        return Err(ValueError::MaxNotFinite);
    }
    if let (Some(l), Some(h)) = (v.min, v.max)
        && l.value > h.value
    {
        return Err(ValueError::MinAboveMax);
    }
    if matches!(v.var_type, VarType::Integer | VarType::Enumeration) {
        if let Some(l) = v.min
            && l.value != (l.value as i32) as f64
        {
            return Err(ValueError::IntegerMin);
        }
        if let Some(h) = v.max
            && h.value != (h.value as i32) as f64
        {
            return Err(ValueError::IntegerMax);
        }
    }
    // The other integer types: integral bounds within the type's range and exact in f64
    // (the runtime compares integers with them exactly).
    if let (true, Some((lo, hi))) = (
        v.var_type.is_integer() && !matches!(v.var_type, VarType::Integer),
        v.var_type.integer_range(),
    ) {
        const EXACT: f64 = 9007199254740992.0; // 2^53
        const fn fits(x: f64, lo: i128, hi: i128) -> bool {
            // (an integral value within ±2^53 converts to i128 and back unchanged)
            x.abs() <= EXACT && (x as i128) as f64 == x && (x as i128) >= lo && (x as i128) <= hi
        }
        if let Some(l) = v.min
            && !fits(l.value, lo, hi)
        {
            return Err(ValueError::IntegerTypeMin);
        }
        if let Some(h) = v.max
            && !fits(h.value, lo, hi)
        {
            return Err(ValueError::IntegerTypeMax);
        }
    }
    // A scalar's start, or each element's of an array.
    let starts: &[Start] = match &v.start {
        Start::Array(items) => items,
        one => core::slice::from_ref(one),
    };
    let mut k = 0;
    while k < starts.len() {
        let x = match starts[k] {
            Start::Int64(n) => Some(n as f64),
            Start::UInt64(n) => Some(n as f64),
            Start::Real(x) => {
                if !finite(x) {
                    return Err(ValueError::StartNotFinite);
                }
                Some(x)
            }
            Start::Integer(n) => Some(n as f64),
            _ => None,
        };
        if let Some(x) = x {
            if let Some(l) = v.min
                && !(if l.exclusive { x > l.value } else { x >= l.value })
            {
                return Err(ValueError::StartBelowMin);
            }
            if let Some(h) = v.max
                && !(if h.exclusive { x < h.value } else { x <= h.value })
            {
                return Err(ValueError::StartAboveMax);
            }
        }
        k += 1;
    }
    if let Some(n) = v.nominal
        && !(finite(n) && n > 0.0)
    {
        return Err(ValueError::Nominal);
    }
    if let (Some(e), Start::Integer(code)) = (v.enumeration, v.start) {
        let mut i = 0;
        while i < e.items.len() {
            if e.items[i].value == code {
                return Ok(());
            }
            i += 1;
        }
        return Err(ValueError::StartNotAnItem);
    }
    Ok(())
}
