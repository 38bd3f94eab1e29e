//! One field and its `#[variable(...)]`: the field's type read as an FMI type (and array shape),
//! the attribute's keys given their defaults, and every rule of the standard that one declaration
//! can break on its own (the rules between declarations are [`super::check`]'s).

use super::decl::{Kind, Var, type_kind};
use super::variable_attr::{ClockInterval, VarAttr};
use fmi_standard::{Causality, Variability};
use proc_macro2::Span;
use syn::spanned::Spanned;
use syn::{Error, Expr, Result, Type};

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

/// The declaration of `field`, whose `#[variable(...)]` is `attr`.
pub(crate) fn parse_var(field: &syn::Field, attr: &syn::Attribute) -> Result<Var> {
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
    let variability = variability_of(&a, causality, kind)?;
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
    attribute_kinds(&a, kind, &dims, causality, variability, span)?;
    let mut depends = a.depends;
    if let (Some(deps), Some(clocks)) = (&mut depends, &a.clocks) {
        // "All dependencies must be listed, also the dependencies of clocked variables on their
        // input Clocks" (FMI 3.0, 2.4.8): a clocked variable depends on its clocks (the output
        // clocks among them are taken out again by [`output_clocks_are_no_dependencies`], once
        // every clock's causality is known).
        for c in clocks {
            if !deps.iter().any(|(d, _)| *d == c.0) {
                deps.push(c.clone());
            }
        }
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
    value_rules(&var)?;
    Ok(var)
}

/// The variability: declared (where the causality and the type allow it), else the standard's
/// default.
fn variability_of(a: &VarAttr, causality: Causality, kind: Kind) -> Result<Variability> {
    Ok(match a.variability {
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
    })
}

/// The keys that only some types have (a start for an Enumeration, min and max, unit, display
/// unit, nominal, max_size and mime_type), and aliases only on scalars.
fn attribute_kinds(
    a: &VarAttr,
    kind: Kind,
    dims: &[Expr],
    causality: Causality,
    variability: Variability,
    span: Span,
) -> Result<()> {
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
    Ok(())
}

/// The rules on the variable as declared: which variables are event indicators, which may have
/// a start value.
fn value_rules(var: &Var) -> Result<()> {
    let causality = var.causality;
    if let Some(span) = var.event_indicator
        && (!var.in_equations() || !var.dims.is_empty())
    {
        return Err(Error::new(
            span,
            "an event indicator is a continuous scalar Real (f64) input, output or local variable: a state or \
             a value the equations compute, whose change of sign (z > 0 to z <= 0 or back) is a state event",
        ));
    }
    if let Some(start) = &var.start
        && !var.has_start()
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
    Ok(())
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

/// Takes the output clocks out of the `depends` a clocked variable was given by its `clocks`:
/// only input clocks are knowns ("the dependencies of clocked variables on their input Clocks",
/// FMI 3.0, 2.4.8); an output clocked by an output clock (an FMI-LS-BUS Tx_Data with a triggered
/// Tx_Clock) depends on what it is computed from, not on the clock it raises.
pub(crate) fn output_clocks_are_no_dependencies(vars: &mut [Var]) {
    let output_clocks: Vec<(String, String)> = vars
        .iter()
        .filter(|v| v.kind == Kind::Clock && v.causality == Causality::Output)
        .map(|v| (v.name.clone(), v.field.to_string()))
        .collect();
    for v in vars.iter_mut() {
        let clocks = &v.clocks;
        if let Some(deps) = &mut v.depends {
            deps.retain(|(d, _)| {
                let own_clock = clocks.iter().any(|(c, _)| c == d);
                !(own_clock && output_clocks.iter().any(|(name, field)| d == name || d == field))
            });
        }
    }
}
