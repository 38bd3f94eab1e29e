//! `#[fmu(...)]` on the model struct: the model's identifier, description and interfaces, and
//! the units, display units, log categories and terminals it declares; a table of keys on the
//! grammar of [`super::grammar`], each nested list its own small parser.

use super::grammar::{Key, MetaParser, find, key_names, name_or_ident, unknown_key};
use super::model_attr::{ModelAttr, TerminalAttr};
use crate::units::{self, Base};
use proc_macro2::Span;
use syn::meta::ParseNestedMeta;
use syn::spanned::Spanned;
use syn::{Error, Expr, LitStr, Result};

/// Every key of `#[fmu(...)]` on a model struct, in the order the error lists them.
const FMU_GRAMMAR: [Key<MetaParser<ModelAttr>>; 12] = [
    Key {
        name: "identifier",
        parse: |m, meta| {
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
            Ok(())
        },
    },
    Key {
        name: "description",
        parse: |m, meta| {
            m.description = Some(string(meta)?);
            Ok(())
        },
    },
    Key {
        name: "co_simulation_only",
        parse: interfaces,
    },
    Key {
        name: "model_exchange_only",
        parse: interfaces,
    },
    Key {
        name: "fmi3_only",
        parse: |m, meta| flag(&mut m.fmi3_only, meta, "fmi3_only is given twice"),
    },
    Key {
        name: "scheduled_execution",
        parse: |m, meta| flag(&mut m.scheduled_execution, meta, "scheduled_execution is given twice"),
    },
    Key {
        name: "unit(..)",
        parse: unit,
    },
    Key {
        name: "log_category(..)",
        parse: log_category,
    },
    Key {
        name: "terminal(..)",
        parse: terminal,
    },
    Key {
        name: "can_network(..)",
        parse: super::network::can_network,
    },
    Key {
        name: "bus_simulation",
        parse: |m, meta| flag(&mut m.bus_simulation, meta, "bus_simulation is given twice"),
    },
    Key {
        name: "display_unit(..)",
        parse: display_unit,
    },
];

pub(crate) const FMU_KEYS: &[&str] = &key_names(&FMU_GRAMMAR);

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

pub(crate) fn parse_model_attr(attrs: &[syn::Attribute]) -> Result<ModelAttr> {
    let mut m = ModelAttr::default();
    for attr in attrs.iter().filter(|a| a.path().is_ident("fmu")) {
        attr.parse_nested_meta(|meta| {
            let key = meta.path.get_ident().map(|i| i.to_string()).unwrap_or_default();
            match find(&FMU_GRAMMAR, &key) {
                Some(parse) => parse(&mut m, &meta),
                None => Err(unknown_key(meta.path.span(), "#[fmu] attribute", &key, FMU_KEYS)),
            }
        })?;
    }
    Ok(m)
}

/// `key = ".."`: the string.
fn string(meta: &ParseNestedMeta) -> Result<String> {
    Ok(meta.value()?.parse::<LitStr>()?.value())
}

/// A key that is its own value, given once.
fn flag(slot: &mut Option<Span>, meta: &ParseNestedMeta, twice: &str) -> Result<()> {
    if slot.is_some() {
        return Err(meta.error(twice));
    }
    *slot = Some(meta.path.span());
    Ok(())
}

/// `co_simulation_only` or `model_exchange_only`: one of them.
fn interfaces(m: &mut ModelAttr, meta: &ParseNestedMeta) -> Result<()> {
    if m.interfaces.is_some() {
        return Err(meta.error("co_simulation_only and model_exchange_only exclude each other and are given once"));
    }
    let cs_only = meta.path.is_ident("co_simulation_only");
    m.interfaces = Some((!cs_only, cs_only, meta.path.span()));
    Ok(())
}

/// `unit(name = .., kg = .., m = .., .., factor = .., offset = ..)`.
fn unit(m: &mut ModelAttr, meta: &ParseNestedMeta) -> Result<()> {
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
            name = Some(string(&u)?);
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
    Ok(())
}

/// `display_unit(unit = .., name = .., factor = .., offset = .., inverse)`.
fn display_unit(m: &mut ModelAttr, meta: &ParseNestedMeta) -> Result<()> {
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
            "unit" => unit = Some(string(&u)?),
            "name" => name = Some(string(&u)?),
            "factor" | "offset" => {
                let e: Expr = u.value()?.parse()?;
                let x = number(&e)?;
                if !x.is_finite() || (key == "factor" && x == 0.0) {
                    return Err(Error::new(
                        e.span(),
                        format!(
                            "a display unit's {key} is a finite number{}",
                            if key == "factor" { ", not 0" } else { "" }
                        ),
                    ));
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
    Ok(())
}

/// `log_category(name = .., description = ..)`.
fn log_category(m: &mut ModelAttr, meta: &ParseNestedMeta) -> Result<()> {
    let span = meta.path.span();
    let (mut name, mut description) = (None, String::new());
    meta.parse_nested_meta(|c| {
        if c.path.is_ident("name") {
            name = Some(string(&c)?);
        } else if c.path.is_ident("description") {
            description = string(&c)?;
        } else {
            return Err(c.error("a log category has `name` and `description`"));
        }
        Ok(())
    })?;
    let name = name.ok_or_else(|| Error::new(span, "a log category needs `name = \"...\"`"))?;
    if RUNTIME_CATEGORIES.contains(&name.as_str()) || m.categories.iter().any(|(n, _, _)| *n == name) {
        return Err(Error::new(
            span,
            format!(
                "log category '{name}' is declared twice (the runtime declares {})",
                RUNTIME_CATEGORIES.join(", ")
            ),
        ));
    }
    m.categories.push((name, description, span));
    Ok(())
}

/// `terminal(name = .., kind = .., matching_rule = .., description = .., member(..), terminal(..), ..)`.
fn terminal(m: &mut ModelAttr, meta: &ParseNestedMeta) -> Result<()> {
    let span = meta.path.span();
    let t = parse_terminal(meta)?;
    if m.terminals.iter().any(|o| o.name == t.name) {
        return Err(Error::new(span, format!("terminal '{}' is declared twice", t.name)));
    }
    m.terminals.push(t);
    Ok(())
}

/// One terminal and the terminals nested in it.
fn parse_terminal(meta: &ParseNestedMeta) -> Result<TerminalAttr> {
    let span = meta.path.span();
    let mut t = TerminalAttr {
        name: String::new(),
        kind: String::new(),
        matching_rule: "plug".into(),
        description: String::new(),
        members: Vec::new(),
        terminals: Vec::new(),
    };
    meta.parse_nested_meta(|c| {
        if c.path.is_ident("name") {
            t.name = string(&c)?;
        } else if c.path.is_ident("kind") {
            t.kind = string(&c)?;
        } else if c.path.is_ident("matching_rule") {
            t.matching_rule = string(&c)?;
        } else if c.path.is_ident("description") {
            t.description = string(&c)?;
        } else if c.path.is_ident("member") {
            t.members.push(member(&c)?);
        } else if c.path.is_ident("terminal") {
            let nested = parse_terminal(&c)?;
            if t.terminals.iter().any(|o| o.name == nested.name) {
                return Err(c.error(format!("terminal '{}' is nested twice", nested.name)));
            }
            t.terminals.push(nested);
        } else {
            return Err(c.error(
                "a terminal has `name`, `kind`, `matching_rule`, `description`, `member(..)`s and nested `terminal(..)`s",
            ));
        }
        Ok(())
    })?;
    if t.name.is_empty() {
        return Err(Error::new(span, "a terminal needs `name = \"...\"`"));
    }
    if t.members.is_empty() && t.terminals.is_empty() {
        return Err(Error::new(
            span,
            "a terminal needs at least one `member(variable = .., name = \"..\")` or nested `terminal(..)`",
        ));
    }
    Ok(t)
}

/// A terminal's `member(variable = .., name = .., kind = ..)`: (variable, memberName,
/// variableKind, span of the variable).
fn member(c: &ParseNestedMeta) -> Result<(String, String, String, Span)> {
    let (mut variable, mut member, mut kind) = (None, None, "signal".to_string());
    let mut vspan = c.path.span();
    c.parse_nested_meta(|m| {
        if m.path.is_ident("variable") {
            let v = m.value()?;
            let (name, sp) = name_or_ident(v)?;
            vspan = sp;
            variable = Some(name);
        } else if m.path.is_ident("name") {
            member = Some(string(&m)?);
        } else if m.path.is_ident("kind") {
            kind = string(&m)?;
            if !matches!(kind.as_str(), "signal" | "inflow" | "outflow") {
                return Err(
                    m.error("a member's kind is \"signal\", \"inflow\" or \"outflow\" (FMI 3.0's variableKind)")
                );
            }
        } else {
            return Err(m.error("a terminal member has `variable`, `name` and `kind`"));
        }
        Ok(())
    })?;
    let variable = variable.ok_or_else(|| Error::new(vspan, "a terminal member needs `variable = field_or_name`"))?;
    let member = member.unwrap_or_else(|| variable.clone());
    Ok((variable, member, kind, vspan))
}

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
