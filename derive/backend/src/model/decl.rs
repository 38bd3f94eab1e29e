//! The declarations as the checks and the generator see them: each `#[variable]` field a
//! [`Var`] of a [`Kind`], and the lookups among them.

use super::variable_attr::{AliasAttr, ClockAttr};
use fmi_standard::{Causality, Initial, TypeKind, Variability};
use proc_macro2::Span;
use syn::{Expr, Ident, LitStr, Type};

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Kind {
    Real,
    Integer,
    Boolean,
    Str,
    Enum,
    /// FMI 3.0 only: f32.
    Float32,
    /// FMI 3.0 only: i8, u8, i16, u16, u32, i64 (start values through `Start::Int64`).
    Int3,
    /// FMI 3.0 only: u64.
    UInt64,
    /// FMI 3.0 only: `Vec<u8>`.
    Binary,
    /// FMI 3.0 only: `Clock`.
    Clock,
}

impl Kind {
    /// A type FMI 2.0 has.
    pub fn in_fmi2(self) -> bool {
        matches!(
            self,
            Kind::Real | Kind::Integer | Kind::Boolean | Kind::Str | Kind::Enum
        )
    }
    pub fn is_float(self) -> bool {
        matches!(self, Kind::Real | Kind::Float32)
    }
}

/// One `#[variable(...)]` and the field it sits on.
pub(crate) struct Var {
    pub field: Ident,
    pub ty: Type,
    pub kind: Kind,
    /// An array's element type (the field's type for a scalar).
    pub elem: Type,
    /// An array's lengths, outermost first (`[[f64; 4]; 2]`: `2, 4`); empty for a scalar.
    pub dims: Vec<Expr>,
    pub span: Span,
    pub name: String,
    pub vr: u32,
    pub causality: Causality,
    pub variability: Variability,
    pub initial: Option<Initial>,
    pub start: Option<Expr>,
    pub unit: Option<LitStr>,
    pub min: Option<(Expr, bool)>,
    pub max: Option<(Expr, bool)>,
    pub nominal: Option<Expr>,
    pub depends: Option<Vec<(String, Span)>>,
    pub initial_depends: Option<Vec<(String, Span)>>,
    pub derivative_of: Option<(String, Span)>,
    /// Declared `event_indicator` (at this span).
    pub event_indicator: Option<Span>,
    /// Declared `fmi3_only`, or of a type only FMI 3.0 has.
    pub fmi3_only: bool,
    pub max_size: Option<Expr>,
    pub mime_type: Option<LitStr>,
    /// A Clock's declaration (`clock(..)`).
    pub clock: Option<ClockAttr>,
    /// A clocked variable's clocks (`clocks = [..]`).
    pub clocks: Vec<(String, Span)>,
    /// An array's lengths set by structural parameters (`dims = [n, m]`, one name per
    /// dimension); empty: the Rust array's lengths.
    pub sized_by: Vec<(String, Span)>,
    pub description: String,
    /// `display_unit = ".."`: the display unit the value is shown in by default.
    pub display_unit: Option<LitStr>,
    /// `alias = ".."` / `alias(name = .., description = .., display_unit = ..)`, in order.
    pub aliases: Vec<AliasAttr>,
}

impl Var {
    /// Whether the description carries a start value (`fmi_standard::has_start`; a Clock has
    /// none).
    pub fn has_start(&self) -> bool {
        self.kind != Kind::Clock && fmi_standard::has_start(self.causality, self.variability, self.initial)
    }

    /// A variable of the equations' struct: a continuous Real that is not a parameter.
    pub fn in_equations(&self) -> bool {
        self.kind == Kind::Real
            && self.variability == Variability::Continuous
            && matches!(self.causality, Causality::Input | Causality::Output | Causality::Local)
    }

    /// Whether `self` is named `n`: by its FMI name or its field.
    pub fn is_named(&self, n: &str) -> bool {
        self.name == n || self.field == n
    }
}

/// A variable's type as the standard's rules see it (only Reals may be continuous).
pub(crate) fn type_kind(kind: Kind) -> TypeKind {
    if kind.is_float() {
        TypeKind::Real
    } else {
        TypeKind::Other
    }
}

/// The variable `n` names: the one of that FMI name, else the one of that field.
pub(crate) fn by_name<'v>(vars: &'v [Var], n: &str) -> Option<&'v Var> {
    vars.iter()
        .find(|v| v.name == n)
        .or_else(|| vars.iter().find(|v| v.field == n))
}

/// The FMI name of the variable `n` refers to, by its FMI name or its field (checked to exist).
pub(crate) fn fmi_name(vars: &[Var], n: &str) -> String {
    by_name(vars, n).map_or_else(|| n.to_string(), |v| v.name.clone())
}

/// Whether `v` is a continuous state: some variable is declared its derivative.
pub(crate) fn is_state(vars: &[Var], v: &Var) -> bool {
    vars.iter()
        .any(|d| d.derivative_of.as_ref().is_some_and(|(n, _)| v.is_named(n)))
}
