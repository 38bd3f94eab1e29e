//! The rules between declarations: names and value references unique, `depends`,
//! `initial_depends`, `derivative_of`, `dims`, `clocks` and clock intervals naming variables
//! that may be named there, the FMI 3.0 features of a model exported for FMI 2.0 too, units and
//! display units declared, alias names unique. The first broken rule is the one error.

use super::decl::{Kind, Var, by_name, is_state};
use super::model_attr::ModelAttr;
use super::variable_attr::{ClockAttr, ClockInterval};
use crate::units;
use fmi_standard::{Causality, Initial, Variability};
use proc_macro2::Span;
use quote::quote;
use std::collections::BTreeMap;
use syn::{Error, LitStr, Result};

/// A rule on one variable among the others.
type Rule = fn(&Var, &[Var], &ModelAttr) -> Result<()>;

/// The rules on each variable, in the order they are checked (a variable's first broken rule is
/// its error).
const VARIABLE_RULES: [Rule; 10] = [
    depends,
    initial_depends,
    derivative,
    structural_parameter,
    sized_by,
    array_in_equations,
    clock_needs_fmi3,
    clocked_by,
    clock_interval,
    unit,
];

pub(crate) fn check_declarations(vars: &[Var], model: &ModelAttr) -> Result<()> {
    scheduled_execution(vars, model)?;
    terminals(vars, model)?;
    unique(vars, model)?;
    if vars.iter().filter(|v| v.causality == Causality::Independent).count() > 1 {
        return Err(Error::new(vars[1].span, "a model has at most one independent variable"));
    }
    for v in vars {
        for rule in VARIABLE_RULES {
            rule(v, vars, model)?;
        }
    }
    check_display_units_and_aliases(vars, model)
}

/// `#[fmu(scheduled_execution)]`: FMI 3.0, an input clock, every clock with a priority.
fn scheduled_execution(vars: &[Var], model: &ModelAttr) -> Result<()> {
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
    Ok(())
}

/// A terminal's members (and its nested terminals'): variables of the model, each member name
/// once in its terminal; the FMI-LS-BUS rules of every `can_network` first (their messages name
/// the role of the variable).
fn terminals(vars: &[Var], model: &ModelAttr) -> Result<()> {
    fn members(vars: &[Var], t: &super::model_attr::TerminalAttr) -> Result<()> {
        let mut seen = Vec::new();
        for (variable, member, _, span) in &t.members {
            if !vars.iter().any(|v| v.is_named(variable)) {
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
        t.terminals.iter().try_for_each(|n| members(vars, n))
    }
    super::network::check(vars, model)?;
    model.terminals.iter().try_for_each(|t| members(vars, t))
}

/// Each variable of a type FMI 2.0 has (or left out of it), each name and value reference once.
fn unique(vars: &[Var], model: &ModelAttr) -> Result<()> {
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
    Ok(())
}

/// The variables `depends` lists: inputs and continuous states, of outputs, derivatives and event
/// indicators.
fn depends(v: &Var, vars: &[Var], _: &ModelAttr) -> Result<()> {
    if let Some(deps) = &v.depends {
        if v.causality != Causality::Output && v.derivative_of.is_none() && v.event_indicator.is_none() {
            return Err(Error::new(
                v.span,
                "only outputs, derivatives and event indicators declare `depends`: it becomes their `dependencies` in ModelStructure",
            ));
        }
        for (d, span) in deps {
            let dep = declared(vars, d, *span, || format!("'{}' depends on", v.name))?;
            if dep.causality != Causality::Input && !is_state(vars, dep) {
                return Err(Error::new(
                    *span,
                    format!(
                        "'{}' depends on '{d}', which is neither an input nor a continuous state (it is a {:?}); \
                         `depends` lists the knowns it is computed from: inputs and states",
                        v.name, dep.causality
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The variables `initial_depends` lists: known in Initialization Mode, of its unknowns.
fn initial_depends(v: &Var, vars: &[Var], _: &ModelAttr) -> Result<()> {
    if let Some(deps) = &v.initial_depends {
        let effective = |x: &Var| fmi_standard::effective_initial(x.causality, x.variability, x.initial);
        // The unknowns of Initialization Mode (FMI 2.0 `InitialUnknowns`, FMI 3.0
        // `InitialUnknown`): outputs, states and derivatives that are approx or calculated,
        // and calculated parameters.
        let initial_unknown = ((v.causality == Causality::Output || v.derivative_of.is_some() || is_state(vars, v))
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
            let dep = declared(vars, d, *span, || format!("'{}' initially depends on", v.name))?;
            let known = dep.causality == Causality::Input
                || dep.causality == Causality::Independent
                || effective(dep) == Some(Initial::Exact);
            if !known {
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
        }
    }
    Ok(())
}

/// The variable `name` (at `span`) that a declaration refers to: declared, else the error
/// "`says` '`name`', which is not declared".
fn declared<'a>(vars: &'a [Var], name: &str, span: Span, says: impl FnOnce() -> String) -> Result<&'a Var> {
    by_name(vars, name).ok_or_else(|| Error::new(span, format!("{} '{name}', which is not declared", says())))
}

/// A derivative: of a continuous Real state (one per state), of the state's shape.
fn derivative(v: &Var, vars: &[Var], _: &ModelAttr) -> Result<()> {
    if let Some((d, span)) = &v.derivative_of {
        if let Some(other) = vars.iter().take_while(|o| !std::ptr::eq(*o, v)).find(|o| {
            o.derivative_of
                .as_ref()
                .is_some_and(|(o, _)| by_name(vars, o).map(|s| &s.name) == by_name(vars, d).map(|s| &s.name))
        }) {
            return Err(Error::new(
                *span,
                format!("'{d}' already has a derivative: '{}'", other.name),
            ));
        }
        match by_name(vars, d) {
            Some(state)
                if matches!(
                    state.causality,
                    Causality::Input | Causality::Parameter | Causality::CalculatedParameter | Causality::Independent
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
    Ok(())
}

/// A structural parameter: FMI 3.0 only, a scalar, not clocked.
fn structural_parameter(v: &Var, _: &[Var], model: &ModelAttr) -> Result<()> {
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
    Ok(())
}

/// The structural parameters of `dims`: one per dimension, u64, with a `max`.
fn sized_by(v: &Var, vars: &[Var], _: &ModelAttr) -> Result<()> {
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
            let x = declared(vars, p, *span, || format!("'{}' is sized by", v.name))?;
            if x.causality != Causality::StructuralParameter || x.kind != Kind::UInt64 {
                return Err(Error::new(
                    *span,
                    format!(
                        "'{}' is sized by '{p}', which is not a u64 structural parameter (FMI 3.0, 2.4.7.6: a \
                         <Dimension valueReference> names a structural parameter of type UInt64)",
                        v.name
                    ),
                ));
            }
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
    }
    Ok(())
}

/// An array in the equations: FMI 3.0 only.
fn array_in_equations(v: &Var, _: &[Var], model: &ModelAttr) -> Result<()> {
    if v.in_equations() && !v.dims.is_empty() && model.fmi3_only.is_none() && !v.fmi3_only {
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
    Ok(())
}

/// A Clock or clocked variable: FMI 3.0 only.
fn clock_needs_fmi3(v: &Var, _: &[Var], model: &ModelAttr) -> Result<()> {
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
    Ok(())
}

/// The clocks of `clocks = [..]`: declared Clocks.
fn clocked_by(v: &Var, vars: &[Var], _: &ModelAttr) -> Result<()> {
    for (c, span) in &v.clocks {
        if declared(vars, c, *span, || format!("'{}' is clocked by", v.name))?.kind != Kind::Clock {
            return Err(Error::new(
                *span,
                format!("'{}' is clocked by '{c}', which is no Clock", v.name),
            ));
        }
    }
    Ok(())
}

/// A clock's interval parameter: a scalar f64 parameter of the clock's variability.
fn clock_interval(v: &Var, vars: &[Var], _: &ModelAttr) -> Result<()> {
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
        let x = declared(vars, p, *span, || format!("the interval of clock '{}' is", v.name))?;
        if !fits(x) {
            return Err(Error::new(
                *span,
                format!(
                    "the interval of {cv} clock '{}' is '{p}', which is not a scalar f64 parameter of its \
                     variability (a fixed clock: a fixed parameter; a tunable clock: a fixed or tunable one)",
                    v.name
                ),
            ));
        }
    }
    Ok(())
}

/// The variable's unit: the runtime's or declared on the struct.
fn unit(v: &Var, _: &[Var], model: &ModelAttr) -> Result<()> {
    if let Some(unit) = &v.unit {
        let u = unit.value();
        if !unit_known(model, &u) {
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
    Ok(())
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
