//! `#[derive(Model)]`: parses the declarations, checks them against the standard's rules, and
//! generates the typed description, the start values and the get/set dispatch.

use crate::units::{self, Base};
use fmi_standard::{Causality, Initial, TypeKind, Variability};
use proc_macro2::{Span, TokenStream};
use quote::{quote, quote_spanned};
use std::collections::BTreeMap;
use syn::parse::{Parse, ParseStream};
use syn::spanned::Spanned;
use syn::{Data, DeriveInput, Error, Expr, Fields, Ident, LitStr, Token, Type};

type Result<T> = std::result::Result<T, Error>;

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Kind {
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
    fn in_fmi2(self) -> bool {
        matches!(
            self,
            Kind::Real | Kind::Integer | Kind::Boolean | Kind::Str | Kind::Enum
        )
    }
    fn is_float(self) -> bool {
        matches!(self, Kind::Real | Kind::Float32)
    }
}

/// One `#[variable(...)]` and the field it sits on.
struct Var {
    field: Ident,
    ty: Type,
    kind: Kind,
    /// An array's element type (the field's type for a scalar).
    elem: Type,
    /// An array's lengths, outermost first (`[[f64; 4]; 2]`: `2, 4`); empty for a scalar.
    dims: Vec<Expr>,
    span: Span,
    name: String,
    vr: u32,
    causality: Causality,
    variability: Variability,
    initial: Option<Initial>,
    start: Option<Expr>,
    unit: Option<LitStr>,
    min: Option<(Expr, bool)>,
    max: Option<(Expr, bool)>,
    nominal: Option<Expr>,
    depends: Option<Vec<(String, Span)>>,
    initial_depends: Option<Vec<(String, Span)>>,
    derivative_of: Option<(String, Span)>,
    /// Declared `event_indicator` (at this span).
    event_indicator: Option<Span>,
    /// Declared `fmi3_only`, or of a type only FMI 3.0 has.
    fmi3_only: bool,
    max_size: Option<Expr>,
    mime_type: Option<LitStr>,
    /// A Clock's declaration (`clock(..)`).
    clock: Option<ClockAttr>,
    /// A clocked variable's clocks (`clocks = [..]`).
    clocks: Vec<(String, Span)>,
    /// An array's lengths set by structural parameters (`dims = [n, m]`, one name per
    /// dimension); empty: the Rust array's lengths.
    sized_by: Vec<(String, Span)>,
    description: String,
    /// `display_unit = ".."`: the display unit the value is shown in by default.
    display_unit: Option<LitStr>,
    /// `alias = ".."` / `alias(name = .., description = .., display_unit = ..)`, in order.
    aliases: Vec<AliasAttr>,
}

/// One `alias(...)` (or `alias = ".."`) of a variable: another name of the same value.
struct AliasAttr {
    name: LitStr,
    description: String,
    display_unit: Option<LitStr>,
}

impl Parse for AliasAttr {
    fn parse(input: ParseStream) -> Result<Self> {
        let (mut name, mut description, mut display_unit) = (None, String::new(), None);
        while !input.is_empty() {
            let key: Ident = input.parse()?;
            input.parse::<Token![=]>()?;
            let value: LitStr = input.parse()?;
            match key.to_string().as_str() {
                "name" if name.is_none() => name = Some(value),
                "description" => description = value.value(),
                "display_unit" if display_unit.is_none() => display_unit = Some(value),
                "name" | "display_unit" => {
                    return Err(Error::new(key.span(), format!("`{key}` is given twice")));
                }
                other => {
                    return Err(Error::new(
                        key.span(),
                        format!("unknown alias declaration `{other}`; known: name, description, display_unit"),
                    ));
                }
            }
            if input.is_empty() {
                break;
            }
            input.parse::<Token![,]>()?;
        }
        let name = name.ok_or_else(|| Error::new(input.span(), "an alias needs `name = \"...\"`"))?;
        Ok(AliasAttr {
            name,
            description,
            display_unit,
        })
    }
}

/// `clock(constant | fixed | tunable | changing | countdown | triggered, interval = .., shift = ..,
/// can_be_deactivated)`.
#[derive(Clone)]
struct ClockAttr {
    /// The intervalVariability's name and its span.
    variability: (String, Span),
    /// `interval = 0.01` (a number: intervalDecimal) or `interval = Ts` (a parameter's name).
    interval: Option<ClockInterval>,
    shift: Option<Expr>,
    can_be_deactivated: bool,
    /// `priority = N` (FMI 3.0 `priority`; every clock of a Scheduled Execution model has one).
    priority: Option<(u32, Span)>,
}

#[derive(Clone)]
enum ClockInterval {
    Value(Expr),
    Parameter(String, Span),
}

/// Every key `clock(...)` accepts (as [`VARIABLE_KEYS`]): an intervalVariability, then its settings.
pub(crate) const CLOCK_KEYS: &[&str] = &[
    "constant",
    "fixed",
    "tunable",
    "changing",
    "countdown",
    "triggered",
    "interval",
    "shift",
    "can_be_deactivated",
    "priority",
];

fn unknown_clock_key(span: Span, key: &str) -> Error {
    Error::new(
        span,
        format!(
            "unknown clock declaration `{key}`; known: {} (constant .. triggered: its intervalVariability; \
             interval = <seconds or a parameter>, shift = <seconds>, priority = <0 highest>)",
            CLOCK_KEYS.join(", ")
        ),
    )
}

impl Parse for ClockAttr {
    fn parse(input: ParseStream) -> Result<Self> {
        let mut variability = None;
        let mut interval = None;
        let mut shift = None;
        let mut can_be_deactivated = false;
        let mut priority = None;
        while !input.is_empty() {
            let key: Ident = input.parse()?;
            let k = key.to_string();
            if !has_key(CLOCK_KEYS, &k) {
                return Err(unknown_clock_key(key.span(), &k));
            }
            match k.as_str() {
                "constant" | "fixed" | "tunable" | "changing" | "countdown" | "triggered" => {
                    if variability.is_some() {
                        return Err(Error::new(key.span(), "a clock has one intervalVariability"));
                    }
                    variability = Some((k, key.span()));
                }
                "interval" => {
                    input.parse::<Token![=]>()?;
                    interval = Some(
                        if input.peek(Ident) && !input.peek2(Token![::]) && !input.peek2(syn::token::Paren) {
                            let i: Ident = input.parse()?;
                            ClockInterval::Parameter(i.to_string(), i.span())
                        } else if input.peek(LitStr) {
                            let s: LitStr = input.parse()?;
                            ClockInterval::Parameter(s.value(), s.span())
                        } else {
                            ClockInterval::Value(input.parse()?)
                        },
                    );
                }
                "shift" => {
                    input.parse::<Token![=]>()?;
                    shift = Some(input.parse()?);
                }
                "can_be_deactivated" => can_be_deactivated = true,
                "priority" => {
                    input.parse::<Token![=]>()?;
                    let n: syn::LitInt = input.parse()?;
                    priority = Some((n.base10_parse::<u32>()?, n.span()));
                }
                other => return Err(unknown_clock_key(key.span(), other)),
            }
            if input.is_empty() {
                break;
            }
            input.parse::<Token![,]>()?;
        }
        let variability = variability.ok_or_else(|| {
            Error::new(
                input.span(),
                "a clock needs its intervalVariability: clock(constant | fixed | tunable | changing | countdown | triggered, ..)",
            )
        })?;
        Ok(ClockAttr {
            variability,
            interval,
            shift,
            can_be_deactivated,
            priority,
        })
    }
}

/// What `#[variable(...)]` says, before defaults are filled in.
#[derive(Default)]
struct VarAttr {
    vr: Option<u32>,
    name: Option<String>,
    causality: Option<(Causality, Span)>,
    variability: Option<(Variability, Span)>,
    initial: Option<(Initial, Span)>,
    start: Option<Expr>,
    unit: Option<LitStr>,
    min: Option<(Expr, bool)>,
    max: Option<(Expr, bool)>,
    nominal: Option<Expr>,
    depends: Option<Vec<(String, Span)>>,
    initial_depends: Option<Vec<(String, Span)>>,
    derivative_of: Option<(String, Span)>,
    event_indicator: Option<Span>,
    fmi3_only: Option<Span>,
    max_size: Option<Expr>,
    mime_type: Option<LitStr>,
    clock: Option<(ClockAttr, Span)>,
    clocks: Option<Vec<(String, Span)>>,
    dims: Option<Vec<(String, Span)>>,
    display_unit: Option<LitStr>,
    aliases: Vec<AliasAttr>,
}

/// `= [a, "b.c", d]`: the names of `depends` and `initial_depends`.
fn names_list(input: ParseStream) -> Result<Vec<(String, Span)>> {
    input.parse::<Token![=]>()?;
    let content;
    syn::bracketed!(content in input);
    let list = content.parse_terminated(name_or_ident, Token![,])?;
    Ok(list.into_iter().collect())
}

fn name_or_ident(input: ParseStream) -> Result<(String, Span)> {
    if input.peek(LitStr) {
        let s: LitStr = input.parse()?;
        Ok((s.value(), s.span()))
    } else {
        let i: Ident = input.parse()?;
        Ok((i.to_string(), i.span()))
    }
}

/// Every key `#[variable(...)]` accepts, in the order the "unknown declaration" error lists them;
/// a key with a parenthesized list is written `key(..)`. The parser takes no other key, and
/// docs/declarations.md's table lists exactly these (`docs_tests.rs`).
pub(crate) const VARIABLE_KEYS: &[&str] = &[
    "vr",
    "name",
    "input",
    "output",
    "parameter",
    "calculated_parameter",
    "structural_parameter",
    "local",
    "independent",
    "constant",
    "fixed",
    "tunable",
    "discrete",
    "continuous",
    "initial",
    "start",
    "unit",
    "min",
    "max",
    "nominal",
    "depends",
    "initial_depends",
    "derivative_of",
    "event_indicator",
    "fmi3_only",
    "max_size",
    "mime_type",
    "clock(..)",
    "clocks",
    "dims",
    "display_unit",
    "alias(..)",
];

/// Every key `#[fmu(...)]` on a model struct accepts (as [`VARIABLE_KEYS`]).
pub(crate) const FMU_KEYS: &[&str] = &[
    "identifier",
    "description",
    "co_simulation_only",
    "model_exchange_only",
    "fmi3_only",
    "scheduled_execution",
    "unit(..)",
    "log_category(..)",
    "terminal(..)",
    "display_unit(..)",
];

/// Whether `keys` has `key`, written bare or as `key(..)`.
pub(crate) fn has_key(keys: &[&str], key: &str) -> bool {
    keys.iter().any(|k| k.strip_suffix("(..)").unwrap_or(k) == key)
}

/// "unknown declaration `x`; known: a, b, ..": one message for each list of keys.
pub(crate) fn unknown_key(span: Span, what: &str, key: &str, keys: &[&str]) -> Error {
    Error::new(span, format!("unknown {what} `{key}`; known: {}", keys.join(", ")))
}

impl Parse for VarAttr {
    fn parse(input: ParseStream) -> Result<Self> {
        let mut a = VarAttr::default();
        while !input.is_empty() {
            let key: Ident = input.call(syn::ext::IdentExt::parse_any)?;
            let k = key.to_string();
            if !has_key(VARIABLE_KEYS, &k) {
                return Err(unknown_key(key.span(), "declaration", &k, VARIABLE_KEYS));
            }
            let once = |taken: bool| -> Result<()> {
                if taken {
                    Err(Error::new(key.span(), format!("`{k}` is given twice")))
                } else {
                    Ok(())
                }
            };
            let set_c = |a: &mut VarAttr, c: Causality| -> Result<()> {
                if let Some((prev, _)) = a.causality {
                    return Err(Error::new(
                        key.span(),
                        format!("two causalities: {prev:?} and {c:?}; a variable has one"),
                    ));
                }
                a.causality = Some((c, key.span()));
                Ok(())
            };
            let set_v = |a: &mut VarAttr, v: Variability| -> Result<()> {
                if let Some((prev, _)) = a.variability {
                    return Err(Error::new(
                        key.span(),
                        format!("two variabilities: {prev:?} and {v:?}; a variable has one"),
                    ));
                }
                a.variability = Some((v, key.span()));
                Ok(())
            };
            match k.as_str() {
                "parameter" => set_c(&mut a, Causality::Parameter)?,
                "calculated_parameter" => set_c(&mut a, Causality::CalculatedParameter)?,
                "structural_parameter" => set_c(&mut a, Causality::StructuralParameter)?,
                "input" => set_c(&mut a, Causality::Input)?,
                "output" => set_c(&mut a, Causality::Output)?,
                "local" => set_c(&mut a, Causality::Local)?,
                "independent" => set_c(&mut a, Causality::Independent)?,
                "constant" => set_v(&mut a, Variability::Constant)?,
                "fixed" => set_v(&mut a, Variability::Fixed)?,
                "tunable" => set_v(&mut a, Variability::Tunable)?,
                "discrete" => set_v(&mut a, Variability::Discrete)?,
                "continuous" => set_v(&mut a, Variability::Continuous)?,
                "vr" => {
                    once(a.vr.is_some())?;
                    input.parse::<Token![=]>()?;
                    let lit: syn::LitInt = input.parse()?;
                    a.vr = Some(lit.base10_parse()?);
                }
                "name" => {
                    once(a.name.is_some())?;
                    input.parse::<Token![=]>()?;
                    let s: LitStr = input.parse()?;
                    if s.value().is_empty() {
                        return Err(Error::new(s.span(), "a variable name cannot be empty"));
                    }
                    a.name = Some(s.value());
                }
                "initial" => {
                    once(a.initial.is_some())?;
                    input.parse::<Token![=]>()?;
                    let i: Ident = input.parse()?;
                    let v = match i.to_string().as_str() {
                        "exact" => Initial::Exact,
                        "approx" => Initial::Approx,
                        "calculated" => Initial::Calculated,
                        other => {
                            return Err(Error::new(
                                i.span(),
                                format!("initial = {other}: expected exact, approx or calculated"),
                            ));
                        }
                    };
                    a.initial = Some((v, i.span()));
                }
                "start" => {
                    once(a.start.is_some())?;
                    input.parse::<Token![=]>()?;
                    a.start = Some(input.parse()?);
                }
                "unit" => {
                    once(a.unit.is_some())?;
                    input.parse::<Token![=]>()?;
                    a.unit = Some(input.parse()?);
                }
                "nominal" => {
                    once(a.nominal.is_some())?;
                    input.parse::<Token![=]>()?;
                    a.nominal = Some(input.parse()?);
                }
                "min" => {
                    once(a.min.is_some())?;
                    let exclusive = if input.peek(Token![>=]) {
                        input.parse::<Token![>=]>()?;
                        false
                    } else if input.peek(Token![>]) {
                        input.parse::<Token![>]>()?;
                        true
                    } else {
                        input.parse::<Token![=]>().map_err(|e| {
                            Error::new(
                                e.span(),
                                "expected `min = x` (x is legal), `min >= x` or `min > x` (x is not)",
                            )
                        })?;
                        false
                    };
                    a.min = Some((input.parse()?, exclusive));
                }
                "max" => {
                    once(a.max.is_some())?;
                    let exclusive = if input.peek(Token![<=]) {
                        input.parse::<Token![<=]>()?;
                        false
                    } else if input.peek(Token![<]) {
                        input.parse::<Token![<]>()?;
                        true
                    } else {
                        input.parse::<Token![=]>().map_err(|e| {
                            Error::new(
                                e.span(),
                                "expected `max = x` (x is legal), `max <= x` or `max < x` (x is not)",
                            )
                        })?;
                        false
                    };
                    a.max = Some((input.parse()?, exclusive));
                }
                "depends" => {
                    once(a.depends.is_some())?;
                    a.depends = Some(names_list(input)?);
                }
                "initial_depends" => {
                    once(a.initial_depends.is_some())?;
                    a.initial_depends = Some(names_list(input)?);
                }
                "event_indicator" => {
                    once(a.event_indicator.is_some())?;
                    a.event_indicator = Some(key.span());
                }
                "fmi3_only" => {
                    once(a.fmi3_only.is_some())?;
                    a.fmi3_only = Some(key.span());
                }
                "max_size" => {
                    once(a.max_size.is_some())?;
                    input.parse::<Token![=]>()?;
                    a.max_size = Some(input.parse()?);
                }
                "mime_type" => {
                    once(a.mime_type.is_some())?;
                    input.parse::<Token![=]>()?;
                    a.mime_type = Some(input.parse()?);
                }
                "clock" => {
                    once(a.clock.is_some())?;
                    let content;
                    syn::parenthesized!(content in input);
                    a.clock = Some((content.parse()?, key.span()));
                }
                "clocks" => {
                    once(a.clocks.is_some())?;
                    a.clocks = Some(names_list(input)?);
                }
                "dims" => {
                    once(a.dims.is_some())?;
                    a.dims = Some(names_list(input)?);
                }
                "display_unit" => {
                    once(a.display_unit.is_some())?;
                    input.parse::<Token![=]>()?;
                    a.display_unit = Some(input.parse()?);
                }
                // `alias = "h_ft"`, or `alias(name = "h_ft", description = "..", display_unit = "ft")`;
                // once per alias.
                "alias" => {
                    if input.peek(Token![=]) {
                        input.parse::<Token![=]>()?;
                        a.aliases.push(AliasAttr {
                            name: input.parse()?,
                            description: String::new(),
                            display_unit: None,
                        });
                    } else {
                        let content;
                        syn::parenthesized!(content in input);
                        a.aliases.push(content.parse()?);
                    }
                }
                "derivative_of" => {
                    once(a.derivative_of.is_some())?;
                    input.parse::<Token![=]>()?;
                    a.derivative_of = Some(name_or_ident(input)?);
                }
                other => return Err(unknown_key(key.span(), "declaration", other, VARIABLE_KEYS)),
            }
            if input.is_empty() {
                break;
            }
            input.parse::<Token![,]>()?;
        }
        Ok(a)
    }
}

pub(crate) const TYPES: &str = "f64 (Float64/Real), i32 (Int32/Integer), bool (Boolean), String, a #[derive(FmuEnum)] enum \
     (Enumeration), and FMI 3.0 only: f32 (Float32), i8, u8, i16, u16, u32, i64, u64 (Int8 .. UInt64), Vec<u8> (Binary)";

/// A field type's element type and lengths: `[[f64; 4]; 2]` is `f64` and `[2, 4]`; a scalar
/// is itself and `[]`. Two dimensions at most.
fn array_parts(ty: &Type) -> Result<(Type, Vec<Expr>)> {
    let mut dims = Vec::new();
    let mut t = ty;
    while let Type::Array(a) = t {
        dims.push(a.len.clone());
        t = &a.elem;
    }
    if dims.len() > 2 {
        return Err(Error::new(
            ty.span(),
            "arrays have one or two dimensions (`[T; N]`, `[[T; M]; N]`)",
        ));
    }
    Ok((t.clone(), dims))
}

fn kind_of(ty: &Type) -> Result<Kind> {
    let Type::Path(p) = ty else {
        return Err(Error::new(ty.span(), format!("a variable's type is one of {TYPES}")));
    };
    let Some(seg) = p.path.segments.last() else {
        return Err(Error::new(ty.span(), format!("a variable's type is one of {TYPES}")));
    };
    let last = seg.ident.to_string();
    Ok(match last.as_str() {
        "f64" => Kind::Real,
        "i32" => Kind::Integer,
        "bool" => Kind::Boolean,
        "String" => Kind::Str,
        "f32" => Kind::Float32,
        "i8" | "u8" | "i16" | "u16" | "u32" | "i64" => Kind::Int3,
        "u64" => Kind::UInt64,
        "Clock" => Kind::Clock,
        "Vec" => {
            let is_bytes = matches!(&seg.arguments, syn::PathArguments::AngleBracketed(a)
                if a.args.len() == 1
                    && matches!(a.args.first(), Some(syn::GenericArgument::Type(Type::Path(t)))
                        if t.path.is_ident("u8")));
            if !is_bytes {
                return Err(Error::new(
                    ty.span(),
                    "a Vec variable is a Binary: Vec<u8> (arrays of values are not variables yet)",
                ));
            }
            Kind::Binary
        }
        "i128" | "u128" | "isize" | "usize" | "str" | "char" => {
            return Err(Error::new(ty.span(), format!("{last} is not an FMI type: use {TYPES}")));
        }
        _ => Kind::Enum,
    })
}

/// A variable's type as the standard's rules see it (only Reals may be continuous).
fn type_kind(kind: Kind) -> TypeKind {
    if kind.is_float() {
        TypeKind::Real
    } else {
        TypeKind::Other
    }
}

/// Whether the description carries a start value for `v` (`fmi_standard::has_start`; a Clock
/// has none).
fn has_start(v: &Var) -> bool {
    v.kind != Kind::Clock && fmi_standard::has_start(v.causality, v.variability, v.initial)
}

fn parse_var(field: &syn::Field, attr: &syn::Attribute) -> Result<Var> {
    let ident = field.ident.clone().expect("named field");
    let a: VarAttr = attr.parse_args()?;
    // An array field (`[T; N]`, `[[T; M]; N]`): an FMI 3.0 array of T.
    let (elem, dims) = array_parts(&field.ty)?;
    let kind = kind_of(&elem)?;
    if !dims.is_empty() && matches!(kind, Kind::Str | Kind::Binary | Kind::Clock) {
        return Err(Error::new(
            field.ty.span(),
            "arrays are of numbers, Booleans and enumerations (not String, Binary or Clock)",
        ));
    }
    let span = ident.span();
    let vr =
        a.vr.ok_or_else(|| Error::new(attr.span(), "every variable needs a value reference: `vr = N`"))?;
    let (causality, _) = a.causality.ok_or_else(|| {
        Error::new(
            attr.span(),
            "every variable needs a causality: input, output, parameter, calculated_parameter, structural_parameter, local or independent",
        )
    })?;
    let variability = match a.variability {
        Some((v, s)) => {
            if !fmi_standard::legal_variability(causality, v) {
                return Err(Error::new(
                    s,
                    format!("causality {causality:?} with variability {v:?} is not allowed (FMI 2.0, section 2.2.7)"),
                ));
            }
            if !fmi_standard::legal_variability_for_type(type_kind(kind), v) {
                return Err(Error::new(
                    s,
                    "only Float64 (f64) and Float32 (f32) variables may be continuous; integer, Boolean, String, Binary and Enumeration variables are discrete",
                ));
            }
            v
        }
        None => fmi_standard::default_variability(causality, type_kind(kind)),
    };
    if causality == Causality::Independent && kind != Kind::Real {
        return Err(Error::new(span, "the independent variable (time) is a Real (f64)"));
    }
    if let Some((i, s)) = a.initial
        && !fmi_standard::legal_initial(causality, variability, i)
    {
        return Err(Error::new(
            s,
            format!(
                "initial = {} is not allowed with causality {causality:?} and variability {variability:?} (FMI 2.0, section 2.2.7)",
                format!("{i:?}").to_lowercase()
            ),
        ));
    }
    clock_rules(&a, kind, causality, variability, span)?;
    let mut depends = a.depends;
    if let (Some(deps), Some(clocks)) = (&mut depends, &a.clocks) {
        // "All dependencies must be listed, also the dependencies of clocked variables on their
        // input Clocks" (FMI 3.0, 2.4.8): a clocked variable depends on its clocks.
        for c in clocks {
            if !deps.iter().any(|(d, _)| *d == c.0) {
                deps.push(c.clone());
            }
        }
    }
    if kind == Kind::Enum
        && a.start.is_none()
        && fmi_standard::has_start(causality, variability, a.initial.map(|(i, _)| i))
    {
        return Err(Error::new(
            span,
            "an Enumeration variable needs `start = Enum::Item` (its value before initialization)",
        ));
    }
    if (a.min.is_some() || a.max.is_some()) && matches!(kind, Kind::Boolean | Kind::Str | Kind::Binary) {
        return Err(Error::new(
            span,
            "min and max are for numeric (float and integer) and Enumeration variables",
        ));
    }
    if a.unit.is_some() && !kind.is_float() {
        return Err(Error::new(
            span,
            "only Float64 (f64) and Float32 (f32) variables have a unit",
        ));
    }
    if let Some(du) = a
        .display_unit
        .as_ref()
        .or_else(|| a.aliases.iter().find_map(|x| x.display_unit.as_ref()))
    {
        if !kind.is_float() {
            return Err(Error::new(
                du.span(),
                "only Float64 (f64) and Float32 (f32) variables (and their aliases) have a display unit",
            ));
        }
        if a.unit.is_none() {
            return Err(Error::new(
                du.span(),
                format!(
                    "display unit '{}' needs the variable's `unit`: a display unit shows a value of its unit \
                     (FMI 3.0, 2.4.7.4: \"If displayUnit is defined a unit must also be defined\")",
                    du.value()
                ),
            ));
        }
    }
    if let Some(alias) = a.aliases.first()
        && !dims.is_empty()
    {
        return Err(Error::new(
            alias.name.span(),
            "aliases are declared on scalar variables only (an array's alias would be one alias per element in FMI 2.0)",
        ));
    }
    if a.nominal.is_some() && !kind.is_float() {
        return Err(Error::new(
            span,
            "only Float64 (f64) and Float32 (f32) variables have a nominal value",
        ));
    }
    if (a.max_size.is_some() || a.mime_type.is_some()) && kind != Kind::Binary {
        return Err(Error::new(
            span,
            "max_size and mime_type are for Binary (Vec<u8>) variables",
        ));
    }
    let var = Var {
        name: a.name.unwrap_or_else(|| ident.to_string()),
        field: ident,
        ty: field.ty.clone(),
        kind,
        elem,
        dims,
        span,
        vr,
        causality,
        variability,
        initial: a.initial.map(|(i, _)| i),
        start: a.start,
        unit: a.unit,
        min: a.min,
        max: a.max,
        nominal: a.nominal,
        depends,
        initial_depends: a.initial_depends,
        derivative_of: a.derivative_of,
        event_indicator: a.event_indicator,
        fmi3_only: a.fmi3_only.is_some(),
        max_size: a.max_size,
        mime_type: a.mime_type,
        clock: a.clock.map(|(c, _)| c),
        clocks: a.clocks.unwrap_or_default(),
        sized_by: a.dims.unwrap_or_default(),
        description: crate::doc_text(&field.attrs),
        display_unit: a.display_unit,
        aliases: a.aliases,
    };
    if let Some(span) = var.event_indicator
        && (!in_equations(&var) || !var.dims.is_empty())
    {
        return Err(Error::new(
            span,
            "an event indicator is a continuous scalar Real (f64) input, output or local variable: a state or \
             a value the equations compute, whose change of sign (z > 0 to z <= 0 or back) is a state event",
        ));
    }
    if let Some(start) = &var.start
        && !has_start(&var)
    {
        let why = if causality == Causality::Independent {
            "the independent variable has no start value".to_string()
        } else {
            format!(
                "{} with initial = calculated has no start value (FMI 2.0, section 2.2.7); \
                 declare initial = exact or approx to give one",
                match causality {
                    Causality::Output => "an output",
                    Causality::Local => "a local variable",
                    _ => "a calculated parameter",
                }
            )
        };
        return Err(Error::new(start.span(), why));
    }
    Ok(var)
}

/// The rules of FMI 3.0 (2.4.7.6, `<Clock>`, `clocks`) on a Clock field and a clocked variable.
fn clock_rules(a: &VarAttr, kind: Kind, causality: Causality, variability: Variability, span: Span) -> Result<()> {
    if kind != Kind::Clock {
        if let Some((_, s)) = &a.clock {
            return Err(Error::new(
                *s,
                "clock(..) declares a Clock: the field's type is rustfmu::Clock",
            ));
        }
        if let Some(clocks) = &a.clocks
            && !matches!(variability, Variability::Discrete | Variability::Tunable)
        {
            let s = clocks.first().map_or(span, |c| c.1);
            return Err(Error::new(
                s,
                "a clocked variable is discrete (or a tunable parameter): its value changes at its clocks' ticks \
                 only (FMI 3.0, 2.4.7.6)",
            ));
        }
        return Ok(());
    }
    let Some((clock, _)) = &a.clock else {
        return Err(Error::new(
            span,
            "a Clock needs clock(constant | fixed | tunable | changing | countdown | triggered, ..): its intervalVariability",
        ));
    };
    let triggered = clock.variability.0 == "triggered";
    match causality {
        Causality::Input => {}
        // "The attribute intervalVariability must be triggered for output Clocks" (FMI 3.0, 2.4.7.6).
        Causality::Output if triggered => {}
        Causality::Output => {
            return Err(Error::new(
                clock.variability.1,
                "an output clock is triggered (FMI 3.0: \"intervalVariability must be triggered for output Clocks\"): \
                 clock(triggered); the model ticks it with Clock::tick in update",
            ));
        }
        _ => {
            return Err(Error::new(
                span,
                "a Clock is an input clock (the importer activates it) or a triggered output clock (the model ticks \
                 it); local clocks are not supported",
            ));
        }
    }
    if a.start.is_some() || a.unit.is_some() || a.min.is_some() || a.max.is_some() || a.clocks.is_some() {
        return Err(Error::new(span, "a Clock has no start, unit, min, max or clocks"));
    }
    if let Some((_, s)) = a.variability
        && variability != Variability::Discrete
    {
        return Err(Error::new(
            s,
            "a Clock is discrete (FMI 3.0: \"Clocks are discrete variables\")",
        ));
    }
    let (v, vspan) = (&clock.variability.0, clock.variability.1);
    let periodic = matches!(v.as_str(), "constant" | "fixed" | "tunable");
    match (v.as_str(), &clock.interval) {
        ("constant", Some(ClockInterval::Value(_))) => {}
        ("constant", _) => {
            return Err(Error::new(
                vspan,
                "a constant clock declares its interval in seconds: clock(constant, interval = 0.01)",
            ));
        }
        ("fixed" | "tunable", Some(_)) => {}
        ("fixed" | "tunable", None) => {
            return Err(Error::new(
                vspan,
                format!(
                    "a {v} clock has an interval: a default in seconds the importer may set another value for \
                     (interval = 0.01), or the parameter that is its interval (interval = Ts)"
                ),
            ));
        }
        (_, Some(_)) => {
            return Err(Error::new(
                vspan,
                format!(
                    "a {v} clock has no declared interval: {}",
                    if v == "triggered" {
                        "it ticks when the importer activates it"
                    } else {
                        "the model gives it with Clock::set_interval"
                    }
                ),
            ));
        }
        _ => {}
    }
    if clock.shift.is_some() && !periodic {
        return Err(Error::new(
            vspan,
            "only periodic clocks (constant, fixed, tunable) have a shift",
        ));
    }
    Ok(())
}

/// `#[fmu(...)]` on the struct.
#[derive(Default)]
struct ModelAttr {
    identifier: Option<LitStr>,
    description: Option<String>,
    /// `co_simulation_only` / `model_exchange_only`: (model exchange, co-simulation) offered.
    interfaces: Option<(bool, bool, Span)>,
    /// `fmi3_only`: the model has no FMI 2.0 export.
    fmi3_only: Option<Span>,
    /// `scheduled_execution`: the FMU offers FMI 3.0 Scheduled Execution too.
    scheduled_execution: Option<Span>,
    units: Vec<(String, Base, Span)>,
    /// `display_unit(unit = .., name = .., factor = .., offset = .., inverse)`: (unit, name,
    /// conversion, span).
    display_units: Vec<(String, String, units::Display, Span)>,
    categories: Vec<(String, String, Span)>,
    terminals: Vec<TerminalAttr>,
}

/// `terminal(name = .., kind = .., matching_rule = .., description = .., member(..), ..)`.
struct TerminalAttr {
    name: String,
    kind: String,
    matching_rule: String,
    description: String,
    /// (variable, memberName, variableKind, span of the variable)
    members: Vec<(String, String, String, Span)>,
    span: Span,
}

fn parse_model_attr(attrs: &[syn::Attribute]) -> Result<ModelAttr> {
    let mut m = ModelAttr::default();
    for attr in attrs.iter().filter(|a| a.path().is_ident("fmu")) {
        attr.parse_nested_meta(|meta| {
            let key = meta.path.get_ident().map(|i| i.to_string()).unwrap_or_default();
            if !has_key(FMU_KEYS, &key) {
                return Err(unknown_key(meta.path.span(), "#[fmu] attribute", &key, FMU_KEYS));
            }
            if meta.path.is_ident("identifier") {
                let s: LitStr = meta.value()?.parse()?;
                let v = s.value();
                let ok = v.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
                    && v.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
                if !ok {
                    return Err(Error::new(
                        s.span(),
                        "the model identifier names the binary (<identifier>.so, .dll): letters, digits and _ only, not starting with a digit",
                    ));
                }
                m.identifier = Some(s);
            } else if meta.path.is_ident("description") {
                let s: LitStr = meta.value()?.parse()?;
                m.description = Some(s.value());
            } else if meta.path.is_ident("co_simulation_only") || meta.path.is_ident("model_exchange_only") {
                if m.interfaces.is_some() {
                    return Err(meta.error("co_simulation_only and model_exchange_only exclude each other and are given once"));
                }
                let cs_only = meta.path.is_ident("co_simulation_only");
                m.interfaces = Some((!cs_only, cs_only, meta.path.span()));
            } else if meta.path.is_ident("scheduled_execution") {
                if m.scheduled_execution.is_some() {
                    return Err(meta.error("scheduled_execution is given twice"));
                }
                m.scheduled_execution = Some(meta.path.span());
            } else if meta.path.is_ident("fmi3_only") {
                if m.fmi3_only.is_some() {
                    return Err(meta.error("fmi3_only is given twice"));
                }
                m.fmi3_only = Some(meta.path.span());
            } else if meta.path.is_ident("unit") {
                let span = meta.path.span();
                let mut name = None;
                let mut base = Base {
                    exps: [0; 8],
                    factor: 1.0,
                    offset: 0.0,
                };
                meta.parse_nested_meta(|u| {
                    let key = u.path.get_ident().map(|i| i.to_string()).unwrap_or_default();
                    if key == "name" {
                        name = Some(u.value()?.parse::<LitStr>()?.value());
                    } else if key == "factor" || key == "offset" {
                        let e: Expr = u.value()?.parse()?;
                        let x = number(&e)?;
                        if key == "factor" {
                            base.factor = x;
                        } else {
                            base.offset = x;
                        }
                    } else if let Some(i) = units::EXPONENT_NAMES.iter().position(|n| *n == key) {
                        let e: Expr = u.value()?.parse()?;
                        let x = number(&e)?;
                        if x.fract() != 0.0 {
                            return Err(Error::new(e.span(), "a base-unit exponent is an integer"));
                        }
                        base.exps[i] = x as i32;
                    } else {
                        return Err(u.error(format!(
                            "unknown unit attribute `{key}`; known: name, {}, factor, offset",
                            units::EXPONENT_NAMES.join(", ")
                        )));
                    }
                    Ok(())
                })?;
                let name = name.ok_or_else(|| Error::new(span, "a unit needs `name = \"...\"`"))?;
                if m.units.iter().any(|(n, _, _)| *n == name) {
                    return Err(Error::new(span, format!("unit '{name}' is declared twice")));
                }
                m.units.push((name, base, span));
            } else if meta.path.is_ident("display_unit") {
                let span = meta.path.span();
                let (mut unit, mut name) = (None, None);
                let mut d = units::Display {
                    factor: 1.0,
                    offset: 0.0,
                    inverse: false,
                };
                meta.parse_nested_meta(|u| {
                    let key = u.path.get_ident().map(|i| i.to_string()).unwrap_or_default();
                    match key.as_str() {
                        "unit" => unit = Some(u.value()?.parse::<LitStr>()?.value()),
                        "name" => name = Some(u.value()?.parse::<LitStr>()?.value()),
                        "factor" | "offset" => {
                            let e: Expr = u.value()?.parse()?;
                            let x = number(&e)?;
                            if !x.is_finite() || (key == "factor" && x == 0.0) {
                                return Err(Error::new(e.span(), format!("a display unit's {key} is a finite number{}", if key == "factor" { ", not 0" } else { "" })));
                            }
                            if key == "factor" {
                                d.factor = x;
                            } else {
                                d.offset = x;
                            }
                        }
                        "inverse" => d.inverse = true,
                        _ => {
                            return Err(u.error(format!(
                                "unknown display unit attribute `{key}`; known: unit, name, factor, offset, inverse"
                            )));
                        }
                    }
                    Ok(())
                })?;
                let unit = unit.ok_or_else(|| Error::new(span, "a display unit names its unit: `unit = \"m\"`"))?;
                let name = name.ok_or_else(|| Error::new(span, "a display unit needs `name = \"...\"`"))?;
                if d.inverse && d.offset != 0.0 {
                    return Err(Error::new(
                        span,
                        "an inverse display unit has no offset (FMI 3.0, 2.4.3: inverse = true only with offset = 0)",
                    ));
                }
                if m.display_units.iter().any(|(u, n, _, _)| *u == unit && *n == name)
                    || units::default_display_unit(&unit, &name).is_some()
                {
                    return Err(Error::new(
                        span,
                        format!("display unit '{name}' of unit '{unit}' is declared twice (or is built in)"),
                    ));
                }
                m.display_units.push((unit, name, d, span));
            } else if meta.path.is_ident("log_category") {
                let span = meta.path.span();
                let (mut name, mut description) = (None, String::new());
                meta.parse_nested_meta(|c| {
                    if c.path.is_ident("name") {
                        name = Some(c.value()?.parse::<LitStr>()?.value());
                    } else if c.path.is_ident("description") {
                        description = c.value()?.parse::<LitStr>()?.value();
                    } else {
                        return Err(c.error("a log category has `name` and `description`"));
                    }
                    Ok(())
                })?;
                let name = name.ok_or_else(|| Error::new(span, "a log category needs `name = \"...\"`"))?;
                if RUNTIME_CATEGORIES.contains(&name.as_str()) || m.categories.iter().any(|(n, _, _)| *n == name) {
                    return Err(Error::new(span, format!("log category '{name}' is declared twice (the runtime declares {})", RUNTIME_CATEGORIES.join(", "))));
                }
                m.categories.push((name, description, span));
            } else if meta.path.is_ident("terminal") {
                let span = meta.path.span();
                let mut t = TerminalAttr {
                    name: String::new(),
                    kind: String::new(),
                    matching_rule: "plug".into(),
                    description: String::new(),
                    members: Vec::new(),
                    span,
                };
                meta.parse_nested_meta(|c| {
                    if c.path.is_ident("name") {
                        t.name = c.value()?.parse::<LitStr>()?.value();
                    } else if c.path.is_ident("kind") {
                        t.kind = c.value()?.parse::<LitStr>()?.value();
                    } else if c.path.is_ident("matching_rule") {
                        t.matching_rule = c.value()?.parse::<LitStr>()?.value();
                    } else if c.path.is_ident("description") {
                        t.description = c.value()?.parse::<LitStr>()?.value();
                    } else if c.path.is_ident("member") {
                        let (mut variable, mut member, mut kind) = (None, None, "signal".to_string());
                        let mut vspan = c.path.span();
                        c.parse_nested_meta(|m| {
                            if m.path.is_ident("variable") {
                                let v = m.value()?;
                                let (name, sp) = name_or_ident(v)?;
                                vspan = sp;
                                variable = Some(name);
                            } else if m.path.is_ident("name") {
                                member = Some(m.value()?.parse::<LitStr>()?.value());
                            } else if m.path.is_ident("kind") {
                                kind = m.value()?.parse::<LitStr>()?.value();
                                if !matches!(kind.as_str(), "signal" | "inflow" | "outflow") {
                                    return Err(m.error("a member's kind is \"signal\", \"inflow\" or \"outflow\" (FMI 3.0's variableKind)"));
                                }
                            } else {
                                return Err(m.error("a terminal member has `variable`, `name` and `kind`"));
                            }
                            Ok(())
                        })?;
                        let variable = variable.ok_or_else(|| Error::new(vspan, "a terminal member needs `variable = field_or_name`"))?;
                        let member = member.unwrap_or_else(|| variable.clone());
                        t.members.push((variable, member, kind, vspan));
                    } else {
                        return Err(c.error("a terminal has `name`, `kind`, `matching_rule`, `description` and `member(..)`s"));
                    }
                    Ok(())
                })?;
                if t.name.is_empty() {
                    return Err(Error::new(span, "a terminal needs `name = \"...\"`"));
                }
                if t.members.is_empty() {
                    return Err(Error::new(span, "a terminal needs at least one `member(variable = .., name = \"..\")`"));
                }
                if m.terminals.iter().any(|o| o.name == t.name) {
                    return Err(Error::new(span, format!("terminal '{}' is declared twice", t.name)));
                }
                m.terminals.push(t);
            } else {
                return Err(unknown_key(meta.path.span(), "#[fmu] attribute", &key, FMU_KEYS));
            }
            Ok(())
        })?;
    }
    Ok(m)
}

/// The runtime's categories (`rustfmu::description::RUNTIME_LOG_CATEGORIES`).
const RUNTIME_CATEGORIES: &[&str] = &[
    "logEvents",
    "logStatusWarning",
    "logStatusDiscard",
    "logStatusError",
    "logStatusFatal",
    "logCalls",
    "logAll",
];

/// A numeric literal, possibly negated.
fn number(e: &Expr) -> Result<f64> {
    match e {
        Expr::Lit(syn::ExprLit {
            lit: syn::Lit::Float(f),
            ..
        }) => f.base10_parse(),
        Expr::Lit(syn::ExprLit {
            lit: syn::Lit::Int(i), ..
        }) => i.base10_parse::<i64>().map(|n| n as f64),
        Expr::Unary(syn::ExprUnary {
            op: syn::UnOp::Neg(_),
            expr,
            ..
        }) => number(expr).map(|x| -x),
        _ => Err(Error::new(e.span(), "expected a number")),
    }
}

fn check_declarations(vars: &[Var], model: &ModelAttr) -> Result<()> {
    if let Some(span) = model.scheduled_execution {
        // FMI 3.0, chapter 5: the importer activates the model partitions of the input clocks,
        // in the order of their priorities.
        if model.fmi3_only.is_none() {
            return Err(Error::new(
                span,
                "scheduled_execution is FMI 3.0: the model is #[fmu(fmi3_only)] (rustfmu::export_fmi3!)",
            ));
        }
        let clocks: Vec<&Var> = vars.iter().filter(|v| v.kind == Kind::Clock).collect();
        if !clocks.iter().any(|v| v.causality == Causality::Input) {
            return Err(Error::new(
                span,
                "scheduled_execution needs an input clock: each input clock's activation \
                 (fmi3ActivateModelPartition) runs a model partition",
            ));
        }
        for v in &clocks {
            if v.clock.as_ref().is_some_and(|c| c.priority.is_none()) {
                return Err(Error::new(
                    v.span,
                    format!(
                        "'{}': every clock of a scheduled_execution model has a priority: clock(.., priority = N), \
                         0 the highest",
                        v.name
                    ),
                ));
            }
        }
    }
    for t in &model.terminals {
        let mut seen = Vec::new();
        for (variable, member, _, span) in &t.members {
            if !vars.iter().any(|v| v.name == *variable || v.field == variable) {
                return Err(Error::new(
                    *span,
                    format!(
                        "terminal '{}': member variable '{variable}' is no variable of the model",
                        t.name
                    ),
                ));
            }
            if seen.contains(&member) {
                return Err(Error::new(
                    *span,
                    format!("terminal '{}': member name '{member}' is used twice", t.name),
                ));
            }
            seen.push(member);
        }
        let _ = t.span;
    }
    let mut names: BTreeMap<&str, &Var> = BTreeMap::new();
    let mut vrs: BTreeMap<u32, &Var> = BTreeMap::new();
    for v in vars {
        if !v.kind.in_fmi2()
            && v.kind != Kind::Clock
            && v.causality != Causality::StructuralParameter
            && !v.fmi3_only
            && model.fmi3_only.is_none()
        {
            let ty = &v.ty;
            return Err(Error::new(
                v.span,
                format!(
                    "'{}' has type {}, which FMI 2.0 does not have: declare the variable `fmi3_only` (it is left out \
                     of the FMI 2.0 description), or the model #[fmu(fmi3_only)] (no FMI 2.0 export: \
                     rustfmu::export_fmi3! instead of export_fmu!)",
                    v.name,
                    quote!(#ty)
                ),
            ));
        }
        if let Some(first) = names.insert(&v.name, v) {
            return Err(Error::new(
                v.span,
                format!(
                    "the name '{}' is declared twice (first on field `{}`)",
                    v.name, first.field
                ),
            ));
        }
        if let Some(first) = vrs.insert(v.vr, v) {
            return Err(Error::new(
                v.span,
                format!(
                    "value reference {} is used twice (first by '{}'); value references are unique in a model",
                    v.vr, first.name
                ),
            ));
        }
    }
    if vars.iter().filter(|v| v.causality == Causality::Independent).count() > 1 {
        return Err(Error::new(vars[1].span, "a model has at most one independent variable"));
    }
    let by_name = |n: &str| {
        vars.iter()
            .find(|v| v.name == n)
            .or_else(|| vars.iter().find(|v| v.field == n))
    };
    for v in vars {
        if let Some(deps) = &v.depends {
            if v.causality != Causality::Output && v.derivative_of.is_none() && v.event_indicator.is_none() {
                return Err(Error::new(
                    v.span,
                    "only outputs, derivatives and event indicators declare `depends`: it becomes their `dependencies` in ModelStructure",
                ));
            }
            for (d, span) in deps {
                match by_name(d) {
                    Some(dep) if dep.causality == Causality::Input || is_state(vars, dep) => {}
                    Some(dep) => {
                        return Err(Error::new(
                            *span,
                            format!(
                                "'{}' depends on '{d}', which is neither an input nor a continuous state (it is a {:?}); \
                                 `depends` lists the knowns it is computed from: inputs and states",
                                v.name, dep.causality
                            ),
                        ));
                    }
                    None => {
                        return Err(Error::new(
                            *span,
                            format!("'{}' depends on '{d}', which is not declared", v.name),
                        ));
                    }
                }
            }
        }
        if let Some(deps) = &v.initial_depends {
            let effective = |x: &Var| fmi_standard::effective_initial(x.causality, x.variability, x.initial);
            // The unknowns of Initialization Mode (FMI 2.0 `InitialUnknowns`, FMI 3.0
            // `InitialUnknown`): outputs, states and derivatives that are approx or calculated,
            // and calculated parameters.
            let initial_unknown =
                ((v.causality == Causality::Output || v.derivative_of.is_some() || is_state(vars, v))
                    && matches!(effective(v), Some(Initial::Approx | Initial::Calculated)))
                    || v.causality == Causality::CalculatedParameter;
            if !initial_unknown || !v.clocks.is_empty() {
                return Err(Error::new(
                    v.span,
                    "only the unknowns of Initialization Mode (outputs, states and derivatives that are \
                     calculated or approx, calculated parameters; not clocked variables) declare `initial_depends`: it becomes their \
                     `dependencies` in InitialUnknowns",
                ));
            }
            for (d, span) in deps {
                match by_name(d) {
                    Some(dep)
                        if dep.causality == Causality::Input
                            || dep.causality == Causality::Independent
                            || effective(dep) == Some(Initial::Exact) => {}
                    Some(dep) => {
                        return Err(Error::new(
                            *span,
                            format!(
                                "'{}' initially depends on '{d}', which is not known in Initialization Mode (it is a \
                                 {:?} whose initial is not exact); `initial_depends` lists inputs and variables with \
                                 initial = exact, parameters among them",
                                v.name, dep.causality
                            ),
                        ));
                    }
                    None => {
                        return Err(Error::new(
                            *span,
                            format!("'{}' initially depends on '{d}', which is not declared", v.name),
                        ));
                    }
                }
            }
        }
        if let Some((d, span)) = &v.derivative_of {
            if let Some(other) = vars.iter().take_while(|o| !std::ptr::eq(*o, v)).find(|o| {
                o.derivative_of
                    .as_ref()
                    .is_some_and(|(o, _)| by_name(o).map(|s| &s.name) == by_name(d).map(|s| &s.name))
            }) {
                return Err(Error::new(
                    *span,
                    format!("'{d}' already has a derivative: '{}'", other.name),
                ));
            }
            match by_name(d) {
                Some(state)
                    if matches!(
                        state.causality,
                        Causality::Input
                            | Causality::Parameter
                            | Causality::CalculatedParameter
                            | Causality::Independent
                    ) =>
                {
                    return Err(Error::new(
                        *span,
                        format!(
                            "'{d}' has causality {:?}: a continuous state is an output or a local, which the equations integrate",
                            state.causality
                        ),
                    ));
                }
                Some(state)
                    if state.kind == Kind::Real
                        && state.dims.len() <= 1
                        && state.variability == Variability::Continuous =>
                {
                    // An array state: its derivative is an array of its shape, sized alike.
                    let same_shape = state.dims.len() == v.dims.len()
                        && state
                            .dims
                            .iter()
                            .zip(&v.dims)
                            .all(|(a, b)| quote!(#a).to_string() == quote!(#b).to_string())
                        && state.sized_by.iter().map(|s| &s.0).eq(v.sized_by.iter().map(|s| &s.0));
                    if !same_shape {
                        return Err(Error::new(
                            *span,
                            format!(
                                "'{}' is the derivative of '{d}': it has its shape (the same array lengths and `dims`)",
                                v.name
                            ),
                        ));
                    }
                }
                Some(_) => {
                    return Err(Error::new(
                        *span,
                        format!("'{d}' is not a continuous Real variable: it cannot have a derivative"),
                    ));
                }
                None => {
                    return Err(Error::new(
                        *span,
                        format!("derivative_of = {d}: no variable of that name"),
                    ));
                }
            }
            if v.kind != Kind::Real || v.dims.len() > 1 || v.variability != Variability::Continuous {
                return Err(Error::new(
                    v.span,
                    "a derivative is a continuous Real variable, a scalar or a one-dimensional array ([f64; N])",
                ));
            }
        }
        if v.causality == Causality::StructuralParameter {
            if model.fmi3_only.is_none() {
                return Err(Error::new(
                    v.span,
                    format!(
                        "'{}' is a structural parameter: FMI 2.0 has none, so the model is FMI 3.0 only: \
                         #[fmu(fmi3_only)] on the struct, and rustfmu::export_fmi3! instead of export_fmu!",
                        v.name
                    ),
                ));
            }
            if !v.dims.is_empty() || !v.clocks.is_empty() {
                return Err(Error::new(v.span, "a structural parameter is a scalar, not clocked"));
            }
        }
        if !v.sized_by.is_empty() {
            if v.sized_by.len() != v.dims.len() {
                return Err(Error::new(
                    v.sized_by[0].1,
                    format!(
                        "`dims` names one structural parameter per dimension of the array: '{}' has {} dimension(s), `dims` {}",
                        v.name,
                        v.dims.len(),
                        v.sized_by.len()
                    ),
                ));
            }
            for (p, span) in &v.sized_by {
                match by_name(p) {
                    Some(x) if x.causality == Causality::StructuralParameter && x.kind == Kind::UInt64 => {
                        if x.max.is_none() {
                            return Err(Error::new(
                                *span,
                                format!(
                                    "'{p}' sets a length of '{}': it declares `max` (at most the Rust array's length, \
                                     the capacity)",
                                    v.name
                                ),
                            ));
                        }
                    }
                    Some(_) => {
                        return Err(Error::new(
                            *span,
                            format!(
                                "'{}' is sized by '{p}', which is not a u64 structural parameter (FMI 3.0, 2.4.7.6: a \
                                 <Dimension valueReference> names a structural parameter of type UInt64)",
                                v.name
                            ),
                        ));
                    }
                    None => {
                        return Err(Error::new(
                            *span,
                            format!("'{}' is sized by '{p}', which is not declared", v.name),
                        ));
                    }
                }
            }
        }
        if in_equations(v) && !v.dims.is_empty() && model.fmi3_only.is_none() && !v.fmi3_only {
            return Err(Error::new(
                v.span,
                format!(
                    "'{}' is an array in the equations (a continuous input, output, state, derivative or local): \
                     the runtime offers those in FMI 3.0 only (FMI 2.0's structured names are for arrays outside the \
                     equations); declare the model #[fmu(fmi3_only)] (rustfmu::export_fmi3!)",
                    v.name
                ),
            ));
        }
        if (v.kind == Kind::Clock || !v.clocks.is_empty()) && model.fmi3_only.is_none() {
            return Err(Error::new(
                v.span,
                format!(
                    "'{}' is a Clock or clocked: FMI 2.0 has no clocks, so the model is FMI 3.0 only: \
                     #[fmu(fmi3_only)] on the struct, and rustfmu::export_fmi3! instead of export_fmu!",
                    v.name
                ),
            ));
        }
        for (c, span) in &v.clocks {
            match by_name(c) {
                Some(clock) if clock.kind == Kind::Clock => {}
                Some(_) => {
                    return Err(Error::new(
                        *span,
                        format!("'{}' is clocked by '{c}', which is no Clock", v.name),
                    ));
                }
                None => {
                    return Err(Error::new(
                        *span,
                        format!("'{}' is clocked by '{c}', which is not declared", v.name),
                    ));
                }
            }
        }
        if let Some(ClockAttr {
            variability: (cv, _),
            interval: Some(ClockInterval::Parameter(p, span)),
            ..
        }) = &v.clock
        {
            let fits = |x: &Var| {
                x.kind == Kind::Real
                    && x.dims.is_empty()
                    && matches!(
                        (x.causality, x.variability, cv.as_str()),
                        (Causality::Parameter, Variability::Fixed, _)
                            | (Causality::Parameter, Variability::Tunable, "tunable")
                            | (Causality::Local, Variability::Constant, _)
                    )
            };
            match by_name(p) {
                Some(x) if fits(x) => {}
                Some(_) => {
                    return Err(Error::new(
                        *span,
                        format!(
                            "the interval of {cv} clock '{}' is '{p}', which is not a scalar f64 parameter of its \
                             variability (a fixed clock: a fixed parameter; a tunable clock: a fixed or tunable one)",
                            v.name
                        ),
                    ));
                }
                None => {
                    return Err(Error::new(
                        *span,
                        format!("the interval of clock '{}' is '{p}', which is not declared", v.name),
                    ));
                }
            }
        }
        if let Some(unit) = &v.unit {
            let u = unit.value();
            if units::default_unit(&u).is_none() && !model.units.iter().any(|(n, _, _)| *n == u) {
                return Err(Error::new(
                    unit.span(),
                    format!(
                        "unit '{u}' is not declared: declare it on the struct with #[fmu(unit(name = \"{u}\", m = .., s = ..))] \
                         or use one of the runtime's units ({})",
                        units::DEFAULT_UNITS
                            .iter()
                            .map(|(n, _)| *n)
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                ));
            }
        }
    }
    check_display_units_and_aliases(vars, model)
}

/// Whether unit `unit` is one the model may use: the runtime's or declared on the struct.
fn unit_known(model: &ModelAttr, unit: &str) -> bool {
    units::default_unit(unit).is_some() || model.units.iter().any(|(n, _, _)| *n == unit)
}

/// The conversion of display unit `name` of unit `unit`: declared on the struct, or built in.
fn display_unit_of(model: &ModelAttr, unit: &str, name: &str) -> Option<units::Display> {
    model
        .display_units
        .iter()
        .find(|(u, n, _, _)| *u == unit && *n == name)
        .map(|(_, _, d, _)| *d)
        .or_else(|| units::default_display_unit(unit, name))
}

/// The display units (`#[fmu(display_unit(..))]`, `display_unit = ".."`) and the aliases: each
/// display unit belongs to a unit the model may use, each one a variable shows its value in is a
/// display unit of the variable's own unit, and an alias's name is no other variable's or
/// alias's.
fn check_display_units_and_aliases(vars: &[Var], model: &ModelAttr) -> Result<()> {
    for (unit, name, d, span) in &model.display_units {
        if !unit_known(model, unit) {
            return Err(Error::new(
                *span,
                format!(
                    "display unit '{name}' is of unit '{unit}', which is not declared: declare it with \
                     #[fmu(unit(name = \"{unit}\", ..))] or use one of the runtime's units"
                ),
            ));
        }
        if d.inverse && model.fmi3_only.is_none() {
            return Err(Error::new(
                *span,
                format!(
                    "display unit '{name}' is inverse, which FMI 2.0 has not: the model is #[fmu(fmi3_only)], \
                     or the display unit not inverse"
                ),
            ));
        }
    }
    let check = |v: &Var, du: &LitStr| -> Result<()> {
        let unit = v.unit.as_ref().map(|u| u.value()).unwrap_or_default();
        let name = du.value();
        if display_unit_of(model, &unit, &name).is_some() {
            return Ok(());
        }
        let elsewhere: Vec<String> = model
            .display_units
            .iter()
            .map(|(u, n, _, _)| (u.as_str(), n.as_str()))
            .chain(units::DEFAULT_DISPLAY_UNITS.iter().map(|(u, n, _)| (*u, *n)))
            .filter(|(_, n)| *n == name)
            .map(|(u, _)| format!("'{u}'"))
            .collect();
        let own: Vec<&str> = model
            .display_units
            .iter()
            .filter(|(u, _, _, _)| *u == unit)
            .map(|(_, n, _, _)| n.as_str())
            .chain(
                units::DEFAULT_DISPLAY_UNITS
                    .iter()
                    .filter(|(u, _, _)| *u == unit)
                    .map(|(_, n, _)| *n),
            )
            .collect();
        let known = if own.is_empty() {
            "it has none yet".to_string()
        } else {
            format!("its display units are {}", own.join(", "))
        };
        Err(Error::new(
            du.span(),
            if elsewhere.is_empty() {
                format!(
                    "'{}': display unit '{name}' is not declared for unit '{unit}' ({known}): declare it on the \
                     struct with #[fmu(display_unit(unit = \"{unit}\", name = \"{name}\", factor = .., offset = ..))]",
                    v.name
                )
            } else {
                format!(
                    "'{}': display unit '{name}' is a display unit of {}, not of '{unit}' (the variable's unit; \
                     {known}): a display unit shows a value of its own unit's quantity",
                    v.name,
                    elsewhere.join(", ")
                )
            },
        ))
    };
    let mut names: BTreeMap<String, String> = vars.iter().map(|v| (v.name.clone(), v.name.clone())).collect();
    for v in vars {
        if let Some(du) = &v.display_unit {
            check(v, du)?;
        }
        for a in &v.aliases {
            let name = a.name.value();
            if name.is_empty() {
                return Err(Error::new(a.name.span(), "an alias's name cannot be empty"));
            }
            if let Some(owner) = names.get(&name) {
                return Err(Error::new(
                    a.name.span(),
                    if *owner == name {
                        format!(
                            "alias '{name}' of '{}' is the name of a variable: names are unique among variables and aliases",
                            v.name
                        )
                    } else {
                        format!(
                            "alias '{name}' of '{}' is already an alias of '{owner}': names are unique among variables and aliases",
                            v.name
                        )
                    },
                ));
            }
            names.insert(name, v.name.clone());
            if let Some(du) = &a.display_unit {
                check(v, du)?;
            }
        }
    }
    Ok(())
}

/// Whether `v` is a continuous state: some variable is declared its derivative.
fn is_state(vars: &[Var], v: &Var) -> bool {
    vars.iter().any(|d| {
        d.derivative_of
            .as_ref()
            .is_some_and(|(n, _)| *n == v.name || v.field == n)
    })
}

/// The variables of the equations' struct: continuous Reals that are not parameters.
fn in_equations(v: &Var) -> bool {
    v.kind == Kind::Real
        && v.variability == Variability::Continuous
        && matches!(v.causality, Causality::Input | Causality::Output | Causality::Local)
}

fn variant(rt: &TokenStream, ty: &str, v: &str) -> TokenStream {
    let ty = Ident::new(ty, Span::call_site());
    let v = Ident::new(v, Span::call_site());
    quote!(#rt::description::#ty::#v)
}

fn opt_f64(x: Option<f64>) -> TokenStream {
    match x {
        Some(x) => quote!(::core::option::Option::Some(#x)),
        None => quote!(::core::option::Option::None),
    }
}

/// The FMI name of the variable `n` refers to, by its FMI name or its field (checked to exist).
fn fmi_name(vars: &[Var], n: &str) -> String {
    vars.iter()
        .find(|v| v.name == n)
        .or_else(|| vars.iter().find(|v| v.field == n))
        .map_or_else(|| n.to_string(), |v| v.name.clone())
}

/// A scalar zero of the variable's element kind (an enumeration's first item).
fn zero_of(rt: &TokenStream, v: &Var) -> TokenStream {
    let elem = &v.elem;
    match v.kind {
        Kind::Real | Kind::Float32 => quote!(0.0),
        Kind::Integer | Kind::Int3 | Kind::UInt64 => quote!(0),
        Kind::Boolean => quote!(false),
        Kind::Enum => quote!(<#elem as #rt::FmuEnum>::FIRST),
        Kind::Str => quote!(::std::string::String::new()),
        Kind::Binary => quote!(::std::vec::Vec::new()),
        Kind::Clock => quote!(#rt::Clock::default()),
    }
}

/// An array variable's value before initialization: its `start`, else zeros of its shape.
fn array_value(rt: &TokenStream, v: &Var) -> TokenStream {
    if let Some(e) = &v.start {
        return quote!(#e);
    }
    let mut value = zero_of(rt, v);
    for len in v.dims.iter().rev() {
        value = quote!([#value; #len]);
    }
    value
}

fn variable_tokens(rt: &TokenStream, v: &Var, vars: &[Var]) -> TokenStream {
    let name = &v.name;
    let vr = v.vr;
    let ty = &v.ty;
    let causality = variant(rt, "Causality", &format!("{:?}", v.causality));
    let variability = variant(rt, "Variability", &format!("{:?}", v.variability));
    let initial = match v.initial {
        Some(i) => {
            let i = variant(rt, "Initial", &format!("{i:?}"));
            quote!(::core::option::Option::Some(#i))
        }
        None => quote!(::core::option::Option::None),
    };
    let start = if !has_start(v) {
        quote!(#rt::description::Start::None)
    } else if !v.dims.is_empty() {
        let (elem, value) = (&v.elem, array_value(rt, v));
        let flat = if v.dims.len() == 2 {
            quote!(V.as_flattened())
        } else {
            quote!(&V)
        };
        let conv = match v.kind {
            Kind::Real => quote!(#rt::description::Start::Real(x)),
            Kind::Float32 => quote!(#rt::description::Start::Real(x as f64)),
            Kind::Integer => quote!(#rt::description::Start::Integer(x)),
            Kind::Int3 => quote!(#rt::description::Start::Int64(x as i64)),
            Kind::UInt64 => quote!(#rt::description::Start::UInt64(x)),
            Kind::Boolean => quote!(#rt::description::Start::Boolean(x)),
            Kind::Enum => quote!(#rt::description::Start::Integer(x as i32)),
            Kind::Str | Kind::Binary | Kind::Clock => unreachable!("checked: no arrays of these"),
        };
        // The elements' starts, row-major, computed at compile time from the field's start.
        quote!(#rt::description::Start::Array(&{
            const V: #ty = #value;
            const N: usize = ::core::mem::size_of::<#ty>() / ::core::mem::size_of::<#elem>();
            const S: [#rt::description::Start; N] = {
                let flat: &[#elem] = #flat;
                let mut out = [#rt::description::Start::None; N];
                let mut i = 0;
                while i < N {
                    let x = flat[i];
                    out[i] = #conv;
                    i += 1;
                }
                out
            };
            S
        }))
    } else {
        match (v.kind, &v.start) {
            (Kind::Real, Some(e)) => quote!(#rt::description::Start::Real(#e)),
            (Kind::Real, None) => quote!(#rt::description::Start::Real(0.0)),
            (Kind::Integer, Some(e)) => quote!(#rt::description::Start::Integer(#e)),
            (Kind::Integer, None) => quote!(#rt::description::Start::Integer(0)),
            (Kind::Boolean, Some(e)) => quote!(#rt::description::Start::Boolean(#e)),
            (Kind::Boolean, None) => quote!(#rt::description::Start::Boolean(false)),
            (Kind::Str, Some(e)) => quote!(#rt::description::Start::String(#e)),
            (Kind::Str, None) => quote!(#rt::description::Start::String("")),
            (Kind::Enum, Some(e)) => quote!(#rt::description::Start::Integer((#e) as i32)),
            (Kind::Enum, None) => unreachable!("checked: enumerations have a start"),
            (Kind::Float32, Some(e)) => quote!(#rt::description::Start::Real((#e) as f32 as f64)),
            (Kind::Float32, None) => quote!(#rt::description::Start::Real(0.0)),
            (Kind::Int3, Some(e)) => quote!(#rt::description::Start::Int64({ let x: #ty = #e; x as i64 })),
            (Kind::Int3, None) => quote!(#rt::description::Start::Int64(0)),
            (Kind::UInt64, Some(e)) => quote!(#rt::description::Start::UInt64(#e)),
            (Kind::UInt64, None) => quote!(#rt::description::Start::UInt64(0)),
            (Kind::Binary, Some(e)) => quote!(#rt::description::Start::Binary(#e)),
            (Kind::Binary, None) => quote!(#rt::description::Start::Binary(&[])),
            (Kind::Clock, _) => unreachable!("a Clock has no start"),
        }
    };
    let fmi3_only = v.fmi3_only || !v.kind.in_fmi2();
    let max_size = match &v.max_size {
        Some(e) => quote!(::core::option::Option::Some(#e)),
        None => quote!(::core::option::Option::None),
    };
    let mime_type = v.mime_type.as_ref().map(|m| m.value()).unwrap_or_default();
    let dims = &v.dims;
    // The value references of the structural parameters that set the lengths (checked).
    let sized_by: Vec<u32> = v
        .sized_by
        .iter()
        .map(|(p, _)| {
            vars.iter()
                .find(|x| x.name == *p || x.field == p)
                .map_or(u32::MAX, |x| x.vr)
        })
        .collect();
    let elem = &v.elem;
    let unit = v.unit.as_ref().map(|u| u.value()).unwrap_or_default();
    let display_unit = v.display_unit.as_ref().map(|u| u.value()).unwrap_or_default();
    let aliases = v.aliases.iter().map(|a| {
        let (name, description) = (a.name.value(), &a.description);
        let du = a.display_unit.as_ref().map(|u| u.value()).unwrap_or_default();
        quote!(#rt::description::Alias { name: #name, description: #description, display_unit: #du })
    });
    let description = &v.description;
    let bound = |b: &Option<(Expr, bool)>| match b {
        Some((e, exclusive)) => quote!(::core::option::Option::Some(#rt::description::Bound {
            value: (#e) as f64,
            exclusive: #exclusive,
        })),
        None => quote!(::core::option::Option::None),
    };
    let (min, max) = (bound(&v.min), bound(&v.max));
    let nominal = match &v.nominal {
        Some(e) => quote!(::core::option::Option::Some((#e) as f64)),
        None => quote!(::core::option::Option::None),
    };
    let depends = match &v.depends {
        Some(deps) => {
            // The FMI names of the variables named (by FMI name or by field).
            let names: Vec<String> = deps.iter().map(|(d, _)| fmi_name(vars, d)).collect();
            quote!(::core::option::Option::Some(&[#(#names),*]))
        }
        None => quote!(::core::option::Option::None),
    };
    let initial_depends = match &v.initial_depends {
        Some(deps) => {
            let names: Vec<String> = deps.iter().map(|(d, _)| fmi_name(vars, d)).collect();
            quote!(::core::option::Option::Some(&[#(#names),*]))
        }
        None => quote!(::core::option::Option::None),
    };
    let derivative_of = match &v.derivative_of {
        Some((d, _)) => {
            let d = fmi_name(vars, d);
            quote!(::core::option::Option::Some(#d))
        }
        None => quote!(::core::option::Option::None),
    };
    let clock = match &v.clock {
        Some(c) => {
            let iv = variant(rt, "IntervalVariability", &{
                let mut n = c.variability.0.clone();
                n[..1].make_ascii_uppercase();
                n
            });
            let (interval, parameter) = match &c.interval {
                Some(ClockInterval::Value(e)) => (quote!(::core::option::Option::Some((#e) as f64)), String::new()),
                Some(ClockInterval::Parameter(p, _)) => (quote!(::core::option::Option::None), fmi_name(vars, p)),
                None => (quote!(::core::option::Option::None), String::new()),
            };
            let shift = match &c.shift {
                Some(e) => quote!((#e) as f64),
                None => quote!(0.0),
            };
            let can = c.can_be_deactivated;
            let priority = match c.priority {
                Some((p, _)) => quote!(::core::option::Option::Some(#p)),
                None => quote!(::core::option::Option::None),
            };
            quote!(::core::option::Option::Some(#rt::description::ClockDecl {
                interval_variability: #iv,
                interval: #interval,
                interval_parameter: #parameter,
                shift: #shift,
                can_be_deactivated: #can,
                priority: #priority,
            }))
        }
        None => quote!(::core::option::Option::None),
    };
    let clocks: Vec<String> = v.clocks.iter().map(|(c, _)| fmi_name(vars, c)).collect();
    let (var_type, enumeration) = if v.kind == Kind::Clock {
        (
            quote!(#rt::description::VarType::Clock),
            quote!(::core::option::Option::None),
        )
    } else {
        (
            quote!(<#elem as #rt::FmiType>::TYPE),
            quote!(<#elem as #rt::FmiType>::ENUMERATION),
        )
    };
    quote! {
        #rt::description::Variable {
            name: #name,
            value_reference: #vr,
            var_type: #var_type,
            causality: #causality,
            variability: #variability,
            initial: #initial,
            start: #start,
            unit: #unit,
            display_unit: #display_unit,
            aliases: &[#(#aliases),*],
            description: #description,
            min: #min,
            max: #max,
            nominal: #nominal,
            depends_on: #depends,
            initial_depends_on: #initial_depends,
            derivative_of: #derivative_of,
            enumeration: #enumeration,
            fmi3: #rt::description::Fmi3Extras {
                only: #fmi3_only,
                max_size: #max_size,
                mime_type: #mime_type,
                dimensions: &[#((#dims) as u32),*],
                sized_by: &[#(#sized_by),*],
                clock: #clock,
                clocks: &[#(#clocks),*],
            },
        }
    }
}

/// What `#[derive(Model)]` makes of a struct: the generated code (where the declarations parse
/// and the generator gets past them) and the mistake in the declarations, if any.
pub(crate) struct Expansion {
    pub generated: Option<TokenStream>,
    pub error: Option<Error>,
}

/// The derive's output: the generated code, followed by the mistake's `compile_error!` if there
/// is one; or the mistake alone where nothing can be generated.
pub fn expand(input: DeriveInput) -> Result<TokenStream> {
    match expand_parts(input) {
        Expansion {
            generated: Some(generated),
            error: None,
        } => Ok(generated),
        Expansion {
            generated: Some(generated),
            error: Some(problem),
        } => {
            let error = problem.to_compile_error();
            Ok(quote!(#generated #error))
        }
        Expansion {
            error: Some(problem), ..
        } => Err(problem),
        Expansion {
            generated: None,
            error: None,
        } => unreachable!("an expansion has code or an error"),
    }
}

pub(crate) fn expand_parts(input: DeriveInput) -> Expansion {
    expand_checked(input).unwrap_or_else(|e| Expansion {
        generated: None,
        error: Some(e),
    })
}

fn expand_checked(input: DeriveInput) -> Result<Expansion> {
    let rt = crate::runtime_path();
    let Data::Struct(data) = &input.data else {
        return Err(Error::new(input.ident.span(), "#[derive(Model)] is for structs"));
    };
    let Fields::Named(fields) = &data.fields else {
        return Err(Error::new(
            input.ident.span(),
            "#[derive(Model)] needs a struct with named fields",
        ));
    };
    if !input.generics.params.is_empty() {
        return Err(Error::new(
            input.generics.span(),
            "a model struct cannot be generic: an FMU is one concrete model",
        ));
    }
    let model = parse_model_attr(&input.attrs)?;
    let mut vars = Vec::new();
    let mut others = Vec::new();
    let mut internal = Vec::new();
    for f in &fields.named {
        let attrs: Vec<_> = f.attrs.iter().filter(|a| a.path().is_ident("variable")).collect();
        match attrs.as_slice() {
            [] => {
                let ty = &f.ty;
                internal.push(format!(
                    "{}: {}",
                    f.ident.as_ref().expect("named"),
                    quote!(#ty).to_string().replace(' ', "")
                ));
                others.push(f.ident.clone().expect("named"))
            }
            [a] => vars.push(parse_var(f, a)?),
            [_, second, ..] => return Err(Error::new(second.span(), "one #[variable(...)] per field")),
        }
    }
    if vars.is_empty() {
        return Err(Error::new(
            input.ident.span(),
            "a model declares at least one #[variable(...)]",
        ));
    }
    // A declaration the standard forbids is one compile error at the field. The code is still
    // generated when it can be (the declarations parsed), so that the model's own impls and
    // `export_fmu!` do not add "the trait bound `M: Variables` is not satisfied" errors after it
    // (issue 23); a mistake the generator cannot get past (it panics on it) gives the error alone.
    let problem = check_declarations(&vars, &model).err();
    let generate = || -> Result<TokenStream> {
        let meta = crate::metadata::read().map_err(|e| Error::new(input.ident.span(), e))?;

        let internal_state = internal.join("; ");
        let ident = &input.ident;
        let identifier = model
            .identifier
            .as_ref()
            .map(|s| s.value())
            .unwrap_or_else(|| ident.to_string());
        let description = model.description.clone().unwrap_or_else(|| {
            let doc = crate::doc_text(&input.attrs);
            if doc.is_empty() { meta.description.clone() } else { doc }
        });
        let (author, version, copyright, license) = (&meta.author, &meta.version, &meta.copyright, &meta.license);
        let generation_tool = format!("rustfmu {}", env!("CARGO_PKG_VERSION"));
        let default_experiment = match meta.default_experiment {
            Some([start, stop, tol, step]) => {
                let (start, stop, tol, step) = (opt_f64(start), opt_f64(stop), opt_f64(tol), opt_f64(step));
                quote!(::core::option::Option::Some(#rt::description::DefaultExperiment {
                    start_time: #start, stop_time: #stop, tolerance: #tol, step_size: #step,
                }))
            }
            None => quote!(::core::option::Option::None),
        };
        // Every unit the variables use, in order of first use, with its base units.
        let mut used: Vec<(String, Base)> = Vec::new();
        for v in &vars {
            if let Some(u) = &v.unit {
                let name = u.value();
                if used.iter().any(|(n, _)| *n == name) {
                    continue;
                }
                let base = model
                    .units
                    .iter()
                    .find(|(n, _, _)| *n == name)
                    .map(|(_, b, _)| *b)
                    .or_else(|| units::default_unit(&name))
                    .expect("checked");
                used.push((name, base));
            }
        }
        let unit_tokens = used.iter().map(|(name, b)| {
            let [kg, m, s, a, k, mol, cd, rad] = b.exps;
            let (factor, offset) = (b.factor, b.offset);
            // The unit's display units: those declared on the struct, then the built-in ones
            // that a variable or an alias of the unit shows its value in.
            let mut shown: Vec<(String, units::Display)> = model
                .display_units
                .iter()
                .filter(|(u, _, _, _)| u == name)
                .map(|(_, n, d, _)| (n.clone(), *d))
                .collect();
            for (u, n, d) in units::DEFAULT_DISPLAY_UNITS {
                let used_by = |v: &Var| {
                    v.unit.as_ref().is_some_and(|x| x.value() == *u)
                        && v.display_unit
                            .iter()
                            .chain(v.aliases.iter().filter_map(|a| a.display_unit.as_ref()))
                            .any(|du| du.value() == *n)
                };
                if u == name && vars.iter().any(used_by) {
                    shown.push((n.to_string(), *d));
                }
            }
            let display_tokens = shown.iter().map(|(n, d)| {
                let (factor, offset, inverse) = (d.factor, d.offset, d.inverse);
                quote!(#rt::description::DisplayUnit { name: #n, factor: #factor, offset: #offset, inverse: #inverse })
            });
            quote!(#rt::description::Unit {
                name: #name,
                base: #rt::description::BaseUnit { kg: #kg, m: #m, s: #s, a: #a, k: #k, mol: #mol, cd: #cd, rad: #rad, factor: #factor, offset: #offset },
                display_units: &[#(#display_tokens),*],
            })
        });
        let category_tokens = model
            .categories
            .iter()
            .map(|(n, d, _)| quote!(#rt::description::LogCategory { name: #n, description: #d }));
        let variable_tokens: Vec<_> = vars.iter().map(|v| variable_tokens(&rt, v, &vars)).collect();
        // Value reference -> index in DESCRIPTION.variables: a match, not a search per call.
        let index_arms = vars.iter().enumerate().map(|(i, v)| {
            let vr = v.vr;
            quote!(#vr => ::core::option::Option::Some(#i))
        });

        let start_fields = vars.iter().map(|v| {
            let f = &v.field;
            if !v.dims.is_empty() {
                let value = array_value(&rt, v);
                return quote!(#f: #value);
            }
            let value = match (v.kind, &v.start) {
                (Kind::Str, Some(e)) => quote!(::std::string::String::from(#e)),
                (Kind::Str, None) => quote!(::std::string::String::new()),
                (Kind::Binary, Some(e)) => quote!(::std::vec::Vec::from(&(#e)[..])),
                (Kind::Binary, None) => quote!(::std::vec::Vec::new()),
                (Kind::Clock, _) => quote!(#rt::Clock::default()),
                (_, Some(e)) => quote!(#e),
                (Kind::Real | Kind::Float32, None) => quote!(0.0),
                (Kind::Integer | Kind::Int3 | Kind::UInt64, None) => quote!(0),
                (Kind::Boolean, None) => quote!(false),
                // A calculated Enumeration: its first item until the model computes it.
                (Kind::Enum, None) => {
                    let ty = &v.ty;
                    quote!(<#ty as #rt::FmuEnum>::FIRST)
                }
            };
            quote!(#f: #value)
        });
        let other_fields = others.iter().map(|f| {
            let ty = fields.named.iter().find(|x| x.ident.as_ref() == Some(f)).map(|x| &x.ty);
            let value = crate::long_arrays::default_value(ty);
            quote!(#f: #value)
        });
        let numeric: Vec<&Var> = vars
            .iter()
            .filter(|v| !matches!(v.kind, Kind::Str | Kind::Binary | Kind::Clock) && v.dims.is_empty())
            .collect();
        let clock_fields: Vec<&Var> = vars.iter().filter(|v| v.kind == Kind::Clock).collect();
        let clock_arms = clock_fields.iter().map(|v| {
            let (f, vr) = (&v.field, v.vr);
            quote!(#vr => ::core::option::Option::Some(&self.#f))
        });
        let clock_mut_arms = clock_fields.iter().map(|v| {
            let (f, vr) = (&v.field, v.vr);
            quote!(#vr => ::core::option::Option::Some(&mut self.#f))
        });
        let deactivate = clock_fields.iter().map(|v| {
            let f = &v.field;
            quote!(self.#f.__set_active(false);)
        });
        let arrays: Vec<&Var> = vars.iter().filter(|v| !v.dims.is_empty()).collect();
        let flat = |v: &Var, mutable: bool| {
            let f = &v.field;
            match (v.dims.len(), mutable) {
                (2, false) => quote!(self.#f.as_flattened()),
                (2, true) => quote!(self.#f.as_flattened_mut()),
                (_, false) => quote!(self.#f.as_slice()),
                (_, true) => quote!(self.#f.as_mut_slice()),
            }
        };
        let get_elem_arms = arrays.iter().map(|v| {
            let (vr, flat) = (v.vr, flat(v, false));
            quote!(#vr => #flat.get(i).and_then(#rt::FmiType::to_value))
        });
        let set_elem_arms = arrays.iter().map(|v| {
            let (vr, flat, elem) = (v.vr, flat(v, true), &v.elem);
            quote!(#vr => match (#flat.get_mut(i), <#elem as #rt::FmiType>::from_value(value)) {
                (::core::option::Option::Some(slot), ::core::option::Option::Some(x)) => { *slot = x; true }
                _ => false,
            })
        });
        let strings: Vec<&Var> = vars.iter().filter(|v| v.kind == Kind::Str).collect();
        let binaries: Vec<&Var> = vars.iter().filter(|v| v.kind == Kind::Binary).collect();
        let get_bin_arms = binaries.iter().map(|v| {
            let (f, vr) = (&v.field, v.vr);
            quote!(#vr => ::core::option::Option::Some(self.#f.as_slice()))
        });
        let set_bin_arms = binaries.iter().map(|v| {
            let (f, vr) = (&v.field, v.vr);
            quote!(#vr => { self.#f = ::std::vec::Vec::from(value); true })
        });
        let get_arms = numeric.iter().map(|v| {
            let (f, vr) = (&v.field, v.vr);
            quote!(#vr => #rt::FmiType::to_value(&self.#f))
        });
        let set_arms = numeric.iter().map(|v| {
            let (f, vr, ty) = (&v.field, v.vr, &v.ty);
            quote!(#vr => match <#ty as #rt::FmiType>::from_value(value) {
                ::core::option::Option::Some(v) => { self.#f = v; true }
                ::core::option::Option::None => false,
            })
        });
        let get_str_arms = strings.iter().map(|v| {
            let (f, vr) = (&v.field, v.vr);
            quote!(#vr => ::core::option::Option::Some(self.#f.as_str()))
        });
        let set_str_arms = strings.iter().map(|v| {
            let (f, vr) = (&v.field, v.vr);
            quote!(#vr => { self.#f = ::std::string::String::from(value); true })
        });
        // The Real variables the model computes (inputs and parameters are checked when set): the
        // runtime asks after every step.
        let computed: Vec<(usize, &Ident)> = vars
            .iter()
            .enumerate()
            .filter(|(_, v)| {
                v.kind.is_float()
                    && matches!(
                        v.causality,
                        Causality::Output | Causality::Local | Causality::CalculatedParameter | Causality::Independent
                    )
            })
            .map(|(i, v)| (i, &v.field))
            .collect();
        let finite_checks = computed.iter().map(|(i, f)| {
            let v = &vars[*i];
            if v.dims.is_empty() {
                quote!(if !self.#f.is_finite() {
                    return ::core::option::Option::Some(#i);
                })
            } else {
                let flat = flat(v, false);
                quote!(if !#flat.iter().all(|x| x.is_finite()) {
                    return ::core::option::Option::Some(#i);
                })
            }
        });
        // Checks that need the values of the declarations (start within bounds, integral bounds
        // for Integers), evaluated at compile time and reported at the field.
        let value_checks = vars.iter().enumerate().map(|(i, v)| {
            let span = v.span;
            let prefix = format!("variable '{}' (field `{}`): ", v.name, v.field);
            quote_spanned! {span=>
                const _: () = match #rt::description::check_values(&<#ident as #rt::Variables>::DESCRIPTION.variables[#i]) {
                    ::core::result::Result::Ok(()) => (),
                    ::core::result::Result::Err(#rt::description::ValueError::MinNotFinite) => panic!(concat!(#prefix, "min is not a finite number")),
                    ::core::result::Result::Err(#rt::description::ValueError::MaxNotFinite) => panic!(concat!(#prefix, "max is not a finite number")),
                    ::core::result::Result::Err(#rt::description::ValueError::MinAboveMax) => panic!(concat!(#prefix, "min is above max")),
                    ::core::result::Result::Err(#rt::description::ValueError::IntegerMin) => panic!(concat!(#prefix, "an Integer's min must be an integer within i32")),
                    ::core::result::Result::Err(#rt::description::ValueError::IntegerMax) => panic!(concat!(#prefix, "an Integer's max must be an integer within i32")),
                    ::core::result::Result::Err(#rt::description::ValueError::StartNotFinite) => panic!(concat!(#prefix, "the start value is not a finite number")),
                    ::core::result::Result::Err(#rt::description::ValueError::StartBelowMin) => panic!(concat!(#prefix, "the start value is below min")),
                    ::core::result::Result::Err(#rt::description::ValueError::StartAboveMax) => panic!(concat!(#prefix, "the start value is above max")),
                    ::core::result::Result::Err(#rt::description::ValueError::Nominal) => panic!(concat!(#prefix, "nominal must be finite and > 0")),
                    ::core::result::Result::Err(#rt::description::ValueError::StartNotAnItem) => panic!(concat!(#prefix, "the start value is no item of the enumeration")),
                    ::core::result::Result::Err(#rt::description::ValueError::IntegerTypeMin) => panic!(concat!(#prefix, "an integer's min must be an integer of its type, within ±2^53")),
                    ::core::result::Result::Err(#rt::description::ValueError::IntegerTypeMax) => panic!(concat!(#prefix, "an integer's max must be an integer of its type, within ±2^53")),
                };
            }
        });
        // A type the derive does not know by name is taken for a #[derive(FmuEnum)] enum; make sure it
        // is one (a type alias such as `type Real = f64` would otherwise get an Integer start).
        let enum_checks = vars.iter().filter(|v| v.kind == Kind::Enum).map(|v| {
            let (ty, span) = (&v.elem, v.ty.span());
            let message = format!(
                "variable '{}': its type is read as a #[derive(FmuEnum)] enumeration; write f64, i32, bool or String by name (no alias)",
                v.name
            );
            quote_spanned! {span=>
                const _: () = if !matches!(<#ty as #rt::FmiType>::TYPE, #rt::description::VarType::Enumeration) {
                    panic!(#message)
                };
            }
        });
        // The equations: every continuous Real that is not a parameter, as a struct generic over
        // the number type; states in the order of their derivatives' declarations.
        let vis = &input.vis;
        let cont_ident = Ident::new(&format!("{ident}Continuous"), ident.span());
        let cont: Vec<&Var> = vars.iter().filter(|v| in_equations(v)).collect();
        // An array of the equations is an array of D of its lengths (its capacity, when a
        // structural parameter sets them: the model's loops run to the parameter's value).
        let d_type = |v: &Var| match v.dims.as_slice() {
            [] => quote!(D),
            [n] => quote!([D; #n]),
            [n, m] => quote!([[D; #m]; #n]),
            _ => unreachable!("two dimensions at most"),
        };
        let cont_fields = cont.iter().map(|v| {
            let f = &v.field;
            let doc = format!("'{}' (vr {})", v.name, v.vr);
            let ty = d_type(v);
            quote!(#[doc = #doc] pub #f: #ty)
        });
        let cont_doc = format!(
            "The continuous variables of [`{ident}`] in the number type `D` (generated by `#[derive(Model)]`): what its equations are given (inputs, states) and compute (derivatives, outputs, locals)."
        );
        let derivs: Vec<&Var> = vars.iter().filter(|v| v.derivative_of.is_some()).collect();
        let states: Vec<&Var> = derivs
            .iter()
            .map(|d| {
                let n = &d.derivative_of.as_ref().expect("filtered").0;
                vars.iter()
                    .find(|v| v.name == *n)
                    .or_else(|| vars.iter().find(|v| v.field == n))
                    .expect("checked")
            })
            .collect();
        // The state vector: each scalar state one entry, each array state its elements (all of
        // its capacity; the runtime gives the importer the first `n` of a sized one).
        let len_of = |v: &Var| match v.dims.first() {
            Some(n) => quote!((#n)),
            None => quote!(1usize),
        };
        let lens: Vec<TokenStream> = states.iter().map(|v| len_of(v)).collect();
        let n_states = quote!(0usize #(+ #lens)*);
        // A const array of the state vector's length, element k of state variable i given by
        // `each(i)` (a const expression of `j`, the element's index).
        let per_element = |ty: TokenStream, zero: TokenStream, each: &dyn Fn(usize) -> TokenStream| {
            let fills = (0..states.len()).map(|i| {
                let (len, value) = (&lens[i], each(i));
                quote!({
                    let mut j = 0usize;
                    while j < #len {
                        a[k] = #value;
                        k += 1;
                        j += 1;
                    }
                })
            });
            quote!(&{
                let mut a: [#ty; #n_states] = [#zero; #n_states];
                let mut k = 0usize;
                #(#fills)*
                let _ = k;
                a
            })
        };
        // Scalar states only (every model before arrays could be states): the lists as literals.
        let scalar_states = states.iter().all(|v| v.dims.is_empty());
        let state_vrs = per_element(quote!(u32), quote!(0u32), &|i| {
            let vr = states[i].vr;
            quote!({ let _ = j; #vr })
        });
        let state_elements = per_element(quote!(u32), quote!(0u32), &|_| quote!(j as u32));
        let deriv_vrs = per_element(quote!(u32), quote!(0u32), &|i| {
            let vr = derivs[i].vr;
            quote!({ let _ = j; #vr })
        });
        let nominals = per_element(quote!(f64), quote!(0.0f64), &|i| {
            let nominal = match &states[i].nominal {
                Some(e) => quote!((#e) as f64),
                None => quote!(1.0),
            };
            quote!({ let _ = j; #nominal })
        });
        // Copies between the state vector and the fields: `x[k]` and a field's element.
        let copy_out = |from: TokenStream, vars: &[&Var]| {
            let parts = vars.iter().map(|v| {
                let f = &v.field;
                if v.dims.is_empty() {
                    quote!(x[k] = #from.#f; k += 1;)
                } else {
                    quote!(for e in #from.#f.iter() { x[k] = *e; k += 1; })
                }
            });
            quote!({
                let mut x = [0.0f64; #n_states];
                let mut k = 0usize;
                #(#parts)*
                let _ = k;
                x
            })
        };
        let copy_in = |to: TokenStream| {
            let parts = states.iter().map(|v| {
                let f = &v.field;
                if v.dims.is_empty() {
                    quote!(#to.#f = x[k]; k += 1;)
                } else {
                    quote!(for e in #to.#f.iter_mut() { *e = x[k]; k += 1; })
                }
            });
            quote!({
                let mut k = 0usize;
                #(#parts)*
                let _ = k;
            })
        };
        let (
            state_vrs,
            state_elements,
            deriv_vrs,
            nominals,
            states_self,
            states_c,
            derivs_c,
            set_states_self,
            set_states_c,
        ) = if scalar_states {
            let (svrs, dvrs) = (states.iter().map(|v| v.vr), derivs.iter().map(|v| v.vr));
            let zeros = states.iter().map(|_| 0u32);
            let noms = states.iter().map(|v| match &v.nominal {
                Some(e) => quote!((#e) as f64),
                None => quote!(1.0),
            });
            let sf: Vec<&Ident> = states.iter().map(|v| &v.field).collect();
            let df: Vec<&Ident> = derivs.iter().map(|v| &v.field).collect();
            let idx: Vec<usize> = (0..states.len()).collect();
            (
                quote!(&[#(#svrs),*]),
                quote!(&[#(#zeros),*]),
                quote!(&[#(#dvrs),*]),
                quote!(&[#(#noms),*]),
                quote!([#(self.#sf),*]),
                quote!([#(c.#sf),*]),
                quote!([#(c.#df),*]),
                quote!(#(self.#sf = x[#idx];)*),
                quote!(#(c.#sf = x[#idx];)*),
            )
        } else {
            (
                state_vrs,
                state_elements,
                deriv_vrs,
                nominals,
                copy_out(quote!(self), &states),
                copy_out(quote!(c), &states),
                copy_out(quote!(c), &derivs),
                copy_in(quote!(self)),
                copy_in(quote!(c)),
            )
        };
        let n_states = if scalar_states {
            let n = states.len();
            quote!(#n)
        } else {
            n_states
        };
        let known = |v: &Var| v.causality == Causality::Input || is_state(&vars, v);
        let cont_gather = cont.iter().map(|v| {
            let f = &v.field;
            match v.dims.len() {
                0 => quote!(#f: <D as ::core::convert::From<f64>>::from(self.#f)),
                1 => quote!(#f: self.#f.map(<D as ::core::convert::From<f64>>::from)),
                _ => quote!(#f: self.#f.map(|row| row.map(<D as ::core::convert::From<f64>>::from))),
            }
        });
        let cont_store = cont.iter().filter(|v| !known(v)).map(|v| {
            let f = &v.field;
            quote!(self.#f = c.#f;)
        });
        let cont_slots = cont.iter().filter(|v| v.dims.is_empty()).map(|v| {
            let (f, vr) = (&v.field, v.vr);
            quote!(#vr => ::core::option::Option::Some(&mut c.#f))
        });
        let cont_element_slots = cont.iter().map(|v| {
            let (f, vr) = (&v.field, v.vr);
            match v.dims.len() {
                0 => quote!(#vr if i == 0 => ::core::option::Option::Some(&mut c.#f)),
                1 => quote!(#vr => c.#f.get_mut(i)),
                _ => quote!(#vr => c.#f.as_flattened_mut().get_mut(i)),
            }
        });
        let known_vrs: Vec<u32> = cont.iter().filter(|v| known(v)).map(|v| v.vr).collect();
        let known_check = if known_vrs.is_empty() {
            quote!(false)
        } else {
            quote!(matches!(vr, #(#known_vrs)|*))
        };

        // The event indicators, in declaration order.
        let indicators: Vec<&Var> = vars.iter().filter(|v| v.event_indicator.is_some()).collect();
        let indicator_vrs = indicators.iter().map(|v| v.vr);
        let indicator_names: Vec<String> = indicators.iter().map(|v| v.name.clone()).collect();
        let indicator_fields: Vec<&Ident> = indicators.iter().map(|v| &v.field).collect();
        let indicator_idx: Vec<usize> = (0..indicators.len()).collect();
        let (offers_me, offers_cs) = match model.interfaces {
            Some((me, cs, _)) => (me, cs),
            None => (true, true),
        };
        let model_fmi3_only = model.fmi3_only.is_some();
        let offers_se = model.scheduled_execution.is_some();
        let terminal_tokens = model.terminals.iter().map(|t| {
            let (name, kind, rule, description) = (&t.name, &t.kind, &t.matching_rule, &t.description);
            let members = t.members.iter().map(|(variable, member, kind, _)| {
                let variable = fmi_name(&vars, variable);
                quote!(#rt::description::TerminalMember { variable: #variable, member: #member, kind: #kind })
            });
            quote!(#rt::description::Terminal {
                name: #name,
                kind: #kind,
                matching_rule: #rule,
                description: #description,
                members: &[#(#members),*],
            })
        });

        // FMI 2.0 has no arrays: an array is its elements there, scalars with the value
        // references vr, vr + 1, ..; none may be another variable's (checked where the sizes are
        // known: at compile time, by the compiler).
        let element_checks = vars.iter().enumerate().filter(|(_, v)| !v.dims.is_empty() && !v.fmi3_only && model.fmi3_only.is_none()).map(|(i, v)| {
            let message = format!(
                "'{}' (vr {}) is an array, which FMI 2.0 lists as its elements `{}[i,j]` with the value references {} to {} + (elements - 1): \
                 one of them is another variable's. Leave that range free (a vr above it), or declare the array `fmi3_only`",
                v.name, v.vr, v.name, v.vr, v.vr
            );
            quote_spanned!(v.span =>
                const _: () = ::core::assert!(
                    !<#ident as #rt::Variables>::DESCRIPTION.fmi2_elements_overlap(#i),
                    #message
                );
            )
        });

        // A structural parameter's max is at most the length of every array dimension it sets
        // (the Rust array's: its capacity). Lengths may be constants: the compiler checks.
        let capacity_checks = vars.iter().flat_map(|v| {
            v.sized_by.iter().zip(&v.dims).filter_map(|((p, span), cap)| {
                let i = vars.iter().position(|x| x.name == *p || x.field == p)?;
                // (A sizing variable that is no structural parameter with a max has its own
                // compile error.)
                if vars[i].causality != Causality::StructuralParameter || vars[i].max.is_none() {
                    return None;
                }
                let message = format!(
                    "'{p}' sets a length of '{}', whose Rust array holds fewer elements along that dimension than \
                     '{p}''s max: make max at most the array's length",
                    v.name
                );
                Some(quote_spanned!(*span =>
                    #[allow(clippy::unnecessary_cast)]
                    const _: () = ::core::assert!(
                        match <#ident as #rt::Variables>::DESCRIPTION.variables[#i].max {
                            ::core::option::Option::Some(b) => b.value <= (#cap) as f64,
                            ::core::option::Option::None => false,
                        },
                        #message
                    );
                ))
            })
        });
        let capacity_checks: Vec<TokenStream> = capacity_checks.collect();
        let manifest = meta.manifest.as_ref().map(|p| {
            let p = p.display().to_string();
            quote!(
                const _: &[u8] = include_bytes!(#p);
            )
        });

        Ok(quote! {
            #[doc = #cont_doc]
            #[allow(non_snake_case)]
            #[derive(Clone, Copy, Debug, PartialEq)]
            #vis struct #cont_ident<D> {
                #(#cont_fields,)*
                #[doc(hidden)]
                pub _number_type: ::core::marker::PhantomData<D>,
            }

            #[allow(unused_mut, unused_assignments, clippy::identity_op)]
            impl #rt::Variables for #ident {
                type Continuous<D: ::core::marker::Copy> = #cont_ident<D>;
                type States = [f64; #n_states];
                const STATES: &'static [u32] = #state_vrs;
                const STATE_ELEMENTS: &'static [u32] = #state_elements;
                const DERIVATIVES: &'static [u32] = #deriv_vrs;
                const NOMINALS: &'static [f64] = #nominals;

                #[inline]
                fn continuous<D: #rt::Real>(&self) -> #cont_ident<D> {
                    #cont_ident { #(#cont_gather,)* _number_type: ::core::marker::PhantomData }
                }

                #[inline]
                fn store_continuous(&mut self, c: &#cont_ident<f64>) {
                    let _ = c;
                    #(#cont_store)*
                }

                #[inline]
                fn continuous_slot<D: ::core::marker::Copy>(c: &mut #cont_ident<D>, vr: u32) -> ::core::option::Option<&mut D> {
                    let _ = &c;
                    match vr {
                        #(#cont_slots,)*
                        _ => ::core::option::Option::None,
                    }
                }

                #[inline]
                fn continuous_element<D: ::core::marker::Copy>(c: &mut #cont_ident<D>, vr: u32, i: usize) -> ::core::option::Option<&mut D> {
                    let _ = (&c, i);
                    match vr {
                        #(#cont_element_slots,)*
                        _ => ::core::option::Option::None,
                    }
                }

                const INDICATORS: &'static [u32] = &[#(#indicator_vrs),*];
                const MODEL_EXCHANGE: bool = #offers_me;
                const FMI3_ONLY: bool = #model_fmi3_only;
                const CO_SIMULATION: bool = #offers_cs;
                const SCHEDULED_EXECUTION: bool = #offers_se;

                #[inline]
                fn indicators_of<D: ::core::marker::Copy>(c: &#cont_ident<D>, z: &mut [D]) {
                    let _ = (c, &z);
                    #(z[#indicator_idx] = c.#indicator_fields;)*
                }

                #[inline]
                fn is_known(vr: u32) -> bool {
                    #known_check
                }

                #[inline]
                fn states(&self) -> [f64; #n_states] {
                    #states_self
                }

                #[inline]
                fn set_states(&mut self, x: &[f64; #n_states]) {
                    let _ = x;
                    #set_states_self
                }

                #[inline]
                fn states_of(c: &#cont_ident<f64>) -> [f64; #n_states] {
                    let _ = c;
                    #states_c
                }

                #[inline]
                fn set_states_of(c: &mut #cont_ident<f64>, x: &[f64; #n_states]) {
                    let _ = (&c, x);
                    #set_states_c
                }

                #[inline]
                fn derivatives_of(c: &#cont_ident<f64>) -> [f64; #n_states] {
                    let _ = c;
                    #derivs_c
                }

                const DESCRIPTION: #rt::description::ModelDescription = #rt::description::ModelDescription {
                    model_identifier: #identifier,
                    description: #description,
                    author: #author,
                    version: #version,
                    copyright: #copyright,
                    license: #license,
                    generation_tool: #generation_tool,
                    default_experiment: #default_experiment,
                    units: &[#(#unit_tokens),*],
                    log_categories: &[#(#category_tokens),*],
                    variables: &[#(#variable_tokens),*],
                    internal_state: #internal_state,
                    event_indicators: &[#(#indicator_names),*],
                    terminals: &[#(#terminal_tokens),*],
                };

                fn start() -> Self {
                    Self { #(#start_fields,)* #(#other_fields,)* }
                }

                #[inline]
                fn variable_index(vr: u32) -> ::core::option::Option<usize> {
                    match vr {
                        #(#index_arms,)*
                        _ => ::core::option::Option::None,
                    }
                }

                #[inline]
                fn get(&self, vr: u32) -> ::core::option::Option<#rt::Value> {
                    match vr {
                        #(#get_arms,)*
                        _ => ::core::option::Option::None,
                    }
                }

                #[inline]
                fn set(&mut self, vr: u32, value: #rt::Value) -> bool {
                    let _ = &value;
                    match vr {
                        #(#set_arms,)*
                        _ => false,
                    }
                }

                #[inline]
                fn non_finite_computed(&self) -> ::core::option::Option<usize> {
                    // One scalar test per field (an OR of them all, vectorized, read the fields the
                    // step had just written through wider loads and stalled store forwarding).
                    #(#finite_checks)*
                    ::core::option::Option::None
                }

                fn get_string(&self, vr: u32) -> ::core::option::Option<&str> {
                    match vr {
                        #(#get_str_arms,)*
                        _ => ::core::option::Option::None,
                    }
                }

                fn set_string(&mut self, vr: u32, value: &str) -> bool {
                    let _ = value;
                    match vr {
                        #(#set_str_arms,)*
                        _ => false,
                    }
                }

                fn get_element(&self, vr: u32, i: usize) -> ::core::option::Option<#rt::Value> {
                    let _ = i;
                    match vr {
                        #(#get_elem_arms,)*
                        _ => ::core::option::Option::None,
                    }
                }

                fn set_element(&mut self, vr: u32, i: usize, value: #rt::Value) -> bool {
                    let _ = (i, value);
                    match vr {
                        #(#set_elem_arms,)*
                        _ => false,
                    }
                }

                fn get_binary(&self, vr: u32) -> ::core::option::Option<&[u8]> {
                    match vr {
                        #(#get_bin_arms,)*
                        _ => ::core::option::Option::None,
                    }
                }

                fn set_binary(&mut self, vr: u32, value: &[u8]) -> bool {
                    let _ = value;
                    match vr {
                        #(#set_bin_arms,)*
                        _ => false,
                    }
                }
                fn clock(&self, vr: u32) -> ::core::option::Option<&#rt::Clock> {
                    match vr {
                        #(#clock_arms,)*
                        _ => ::core::option::Option::None,
                    }
                }
                fn clock_mut(&mut self, vr: u32) -> ::core::option::Option<&mut #rt::Clock> {
                    match vr {
                        #(#clock_mut_arms,)*
                        _ => ::core::option::Option::None,
                    }
                }
                fn deactivate_clocks(&mut self) {
                    #(#deactivate)*
                }
            }

            #(#value_checks)*
            #(#enum_checks)*
            #(#element_checks)*
            #(#capacity_checks)*
            #manifest
        })
    };
    let generated = match std::panic::catch_unwind(std::panic::AssertUnwindSafe(generate)) {
        Ok(generated) => generated,
        Err(panic) if problem.is_none() => std::panic::resume_unwind(panic),
        Err(_) => {
            return Ok(Expansion {
                generated: None,
                error: problem,
            });
        }
    };
    Ok(match (generated, problem) {
        (Ok(generated), problem) => Expansion {
            generated: Some(generated),
            error: problem,
        },
        (Err(e), None) => return Err(e),
        (Err(_), Some(problem)) => Expansion {
            generated: None,
            error: Some(problem),
        },
    })
}
