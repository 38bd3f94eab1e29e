//! `#[variable(...)]` on a field, and the `clock(..)` and `alias(..)` inside it: each a table of
//! keys on the one grammar of [`super::grammar`].

use super::grammar::{
    Grammar, Key, Parser, any_ident, assigned, assigned_u32, bound, ident, key_names, name_or_ident, names, nested,
    once, one_of, set, unknown_key,
};
use fmi_standard::{Causality, Initial, Variability};
use proc_macro2::Span;
use syn::parse::{Parse, ParseStream};
use syn::{Error, Expr, Ident, LitStr, Result, Token};

/// What `#[variable(...)]` says, before defaults are filled in.
#[derive(Default)]
pub(crate) struct VarAttr {
    pub vr: Option<u32>,
    pub name: Option<String>,
    pub causality: Option<(Causality, Span)>,
    pub variability: Option<(Variability, Span)>,
    pub initial: Option<(Initial, Span)>,
    pub start: Option<Expr>,
    pub unit: Option<LitStr>,
    pub min: Option<(Expr, bool)>,
    pub max: Option<(Expr, bool)>,
    pub nominal: Option<Expr>,
    pub depends: Option<Vec<(String, Span)>>,
    pub initial_depends: Option<Vec<(String, Span)>>,
    pub derivative_of: Option<(String, Span)>,
    pub event_indicator: Option<Span>,
    pub fmi3_only: Option<Span>,
    pub max_size: Option<Expr>,
    pub mime_type: Option<LitStr>,
    pub clock: Option<(ClockAttr, Span)>,
    pub clocks: Option<Vec<(String, Span)>>,
    pub dims: Option<Vec<(String, Span)>>,
    pub display_unit: Option<LitStr>,
    pub aliases: Vec<AliasAttr>,
}

/// Every key of `#[variable(...)]`, in the order the "unknown declaration" error lists them.
/// docs/declarations.md's table lists exactly these (`docs_tests.rs`).
#[rustfmt::skip] // a table: one key a line
const VARIABLE_GRAMMAR: [Key<Parser<VarAttr>>; 32] = [
    Key { name: "vr", parse: |a, k, i| once(&mut a.vr, k, i, |i| Ok(assigned_u32(i)?.0)) },
    Key {
        name: "name",
        parse: |a, k, i| {
            once(&mut a.name, k, i, |i| {
                let s: LitStr = assigned(i)?;
                if s.value().is_empty() {
                    return Err(Error::new(s.span(), "a variable name cannot be empty"));
                }
                Ok(s.value())
            })
        },
    },
    Key { name: "input", parse: |a, k, _| one_of(&mut a.causality, Causality::Input, k, "causalities") },
    Key { name: "output", parse: |a, k, _| one_of(&mut a.causality, Causality::Output, k, "causalities") },
    Key { name: "parameter", parse: |a, k, _| one_of(&mut a.causality, Causality::Parameter, k, "causalities") },
    Key { name: "calculated_parameter", parse: |a, k, _| one_of(&mut a.causality, Causality::CalculatedParameter, k, "causalities") },
    Key { name: "structural_parameter", parse: |a, k, _| one_of(&mut a.causality, Causality::StructuralParameter, k, "causalities") },
    Key { name: "local", parse: |a, k, _| one_of(&mut a.causality, Causality::Local, k, "causalities") },
    Key { name: "independent", parse: |a, k, _| one_of(&mut a.causality, Causality::Independent, k, "causalities") },
    Key { name: "constant", parse: |a, k, _| one_of(&mut a.variability, Variability::Constant, k, "variabilities") },
    Key { name: "fixed", parse: |a, k, _| one_of(&mut a.variability, Variability::Fixed, k, "variabilities") },
    Key { name: "tunable", parse: |a, k, _| one_of(&mut a.variability, Variability::Tunable, k, "variabilities") },
    Key { name: "discrete", parse: |a, k, _| one_of(&mut a.variability, Variability::Discrete, k, "variabilities") },
    Key { name: "continuous", parse: |a, k, _| one_of(&mut a.variability, Variability::Continuous, k, "variabilities") },
    Key { name: "initial", parse: |a, k, i| once(&mut a.initial, k, i, initial) },
    Key { name: "start", parse: |a, k, i| once(&mut a.start, k, i, assigned) },
    Key { name: "unit", parse: |a, k, i| once(&mut a.unit, k, i, assigned) },
    Key { name: "min", parse: |a, k, i| once(&mut a.min, k, i, |i| bound(k, i)) },
    Key { name: "max", parse: |a, k, i| once(&mut a.max, k, i, |i| bound(k, i)) },
    Key { name: "nominal", parse: |a, k, i| once(&mut a.nominal, k, i, assigned) },
    Key { name: "depends", parse: |a, k, i| once(&mut a.depends, k, i, names) },
    Key { name: "initial_depends", parse: |a, k, i| once(&mut a.initial_depends, k, i, names) },
    Key {
        name: "derivative_of",
        parse: |a, k, i| {
            once(&mut a.derivative_of, k, i, |i| {
                i.parse::<Token![=]>()?;
                name_or_ident(i)
            })
        },
    },
    Key { name: "event_indicator", parse: |a, k, i| once(&mut a.event_indicator, k, i, |_| Ok(k.span())) },
    Key { name: "fmi3_only", parse: |a, k, i| once(&mut a.fmi3_only, k, i, |_| Ok(k.span())) },
    Key { name: "max_size", parse: |a, k, i| once(&mut a.max_size, k, i, assigned) },
    Key { name: "mime_type", parse: |a, k, i| once(&mut a.mime_type, k, i, assigned) },
    Key { name: "clock(..)", parse: |a, k, i| once(&mut a.clock, k, i, |i| Ok((nested(i)?, k.span()))) },
    Key { name: "clocks", parse: |a, k, i| once(&mut a.clocks, k, i, names) },
    Key { name: "dims", parse: |a, k, i| once(&mut a.dims, k, i, names) },
    Key { name: "display_unit", parse: |a, k, i| once(&mut a.display_unit, k, i, assigned) },
    // `alias = "h_ft"`, or `alias(name = "h_ft", description = "..", display_unit = "ft")`; once
    // per alias.
    Key {
        name: "alias(..)",
        parse: |a, _, i| {
            a.aliases.push(if i.peek(Token![=]) {
                AliasAttr {
                    name: assigned(i)?,
                    description: String::new(),
                    display_unit: None,
                }
            } else {
                nested(i)?
            });
            Ok(())
        },
    },
];

pub(crate) const VARIABLE_KEYS: &[&str] = &key_names(&VARIABLE_GRAMMAR);

impl Parse for VarAttr {
    fn parse(input: ParseStream) -> Result<Self> {
        Grammar {
            keys: &VARIABLE_GRAMMAR,
            key: any_ident,
            unknown: |key, _| unknown_key(key.span(), "declaration", &key.to_string(), VARIABLE_KEYS),
        }
        .parse(input)
    }
}

/// `= exact | approx | calculated`.
fn initial(input: ParseStream) -> Result<(Initial, Span)> {
    let i: Ident = assigned(input)?;
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
    Ok((v, i.span()))
}

/// One `alias(...)` (or `alias = ".."`) of a variable: another name of the same value.
pub(crate) struct AliasAttr {
    pub name: LitStr,
    pub description: String,
    pub display_unit: Option<LitStr>,
}

/// What `alias(...)` says: each key's value is a string, read before the key is looked at.
#[derive(Default)]
struct AliasKeys {
    name: Option<LitStr>,
    description: String,
    display_unit: Option<LitStr>,
}

#[rustfmt::skip] // a table: one key a line
const ALIAS_GRAMMAR: [Key<Parser<AliasKeys>>; 3] = [
    Key {
        name: "name",
        parse: |a, k, i| {
            let v = assigned(i)?;
            once(&mut a.name, k, i, |_| Ok(v))
        },
    },
    Key { name: "description", parse: |a, _, i| set(&mut a.description, assigned::<LitStr>(i)?.value()) },
    Key {
        name: "display_unit",
        parse: |a, k, i| {
            let v = assigned(i)?;
            once(&mut a.display_unit, k, i, |_| Ok(v))
        },
    },
];

impl Parse for AliasAttr {
    fn parse(input: ParseStream) -> Result<Self> {
        let a = Grammar {
            keys: &ALIAS_GRAMMAR,
            key: ident,
            unknown: |key, input| match assigned::<LitStr>(input) {
                Err(e) => e,
                Ok(_) => Error::new(
                    key.span(),
                    format!("unknown alias declaration `{key}`; known: name, description, display_unit"),
                ),
            },
        }
        .parse(input)?;
        let name = a
            .name
            .ok_or_else(|| Error::new(input.span(), "an alias needs `name = \"...\"`"))?;
        Ok(AliasAttr {
            name,
            description: a.description,
            display_unit: a.display_unit,
        })
    }
}

/// `clock(constant | fixed | tunable | changing | countdown | triggered, interval = .., shift = ..,
/// can_be_deactivated)`.
#[derive(Clone)]
pub(crate) struct ClockAttr {
    /// The intervalVariability's name and its span.
    pub variability: (String, Span),
    /// `interval = 0.01` (a number: intervalDecimal) or `interval = Ts` (a parameter's name).
    pub interval: Option<ClockInterval>,
    pub shift: Option<Expr>,
    pub can_be_deactivated: bool,
    /// `priority = N` (FMI 3.0 `priority`; every clock of a Scheduled Execution model has one).
    pub priority: Option<(u32, Span)>,
}

#[derive(Clone)]
pub(crate) enum ClockInterval {
    Value(Expr),
    Parameter(String, Span),
}

/// What `clock(...)` says, before its intervalVariability is required.
#[derive(Default)]
struct ClockKeys {
    variability: Option<(String, Span)>,
    interval: Option<ClockInterval>,
    shift: Option<Expr>,
    can_be_deactivated: bool,
    priority: Option<(u32, Span)>,
}

/// `constant`, `fixed`, ..: the clock's intervalVariability, given once.
fn interval_variability(c: &mut ClockKeys, key: &Ident, _: ParseStream) -> Result<()> {
    if c.variability.is_some() {
        return Err(Error::new(key.span(), "a clock has one intervalVariability"));
    }
    c.variability = Some((key.to_string(), key.span()));
    Ok(())
}

/// Every key of `clock(...)` (as [`VARIABLE_KEYS`]): an intervalVariability, then its settings.
#[rustfmt::skip] // a table: one key a line
const CLOCK_GRAMMAR: [Key<Parser<ClockKeys>>; 10] = [
    Key { name: "constant", parse: interval_variability },
    Key { name: "fixed", parse: interval_variability },
    Key { name: "tunable", parse: interval_variability },
    Key { name: "changing", parse: interval_variability },
    Key { name: "countdown", parse: interval_variability },
    Key { name: "triggered", parse: interval_variability },
    Key {
        name: "interval",
        parse: |c, _, input| {
            input.parse::<Token![=]>()?;
            c.interval = Some(
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
            Ok(())
        },
    },
    Key { name: "shift", parse: |c, _, i| set(&mut c.shift, Some(assigned(i)?)) },
    Key { name: "can_be_deactivated", parse: |c, _, _| set(&mut c.can_be_deactivated, true) },
    Key { name: "priority", parse: |c, _, i| set(&mut c.priority, Some(assigned_u32(i)?)) },
];

pub(crate) const CLOCK_KEYS: &[&str] = &key_names(&CLOCK_GRAMMAR);

impl Parse for ClockAttr {
    fn parse(input: ParseStream) -> Result<Self> {
        let c = Grammar {
            keys: &CLOCK_GRAMMAR,
            key: ident,
            unknown: |key, _| {
                Error::new(
                    key.span(),
                    format!(
                        "unknown clock declaration `{key}`; known: {} (constant .. triggered: its intervalVariability; \
                         interval = <seconds or a parameter>, shift = <seconds>, priority = <0 highest>)",
                        CLOCK_KEYS.join(", ")
                    ),
                )
            },
        }
        .parse(input)?;
        let variability = c.variability.ok_or_else(|| {
            Error::new(
                input.span(),
                "a clock needs its intervalVariability: clock(constant | fixed | tunable | changing | countdown | triggered, ..)",
            )
        })?;
        Ok(ClockAttr {
            variability,
            interval: c.interval,
            shift: c.shift,
            can_be_deactivated: c.can_be_deactivated,
            priority: c.priority,
        })
    }
}
