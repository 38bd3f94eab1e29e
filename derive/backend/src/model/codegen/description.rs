//! The model's description as the runtime's const `ModelDescription`: the model's metadata, its
//! units with their display units, log categories, variables and terminals.

use super::values::{array_value, option};
use crate::metadata::Metadata;
use crate::model::decl::{Kind, Var, fmi_name};
use crate::model::model_attr::ModelAttr;
use crate::model::variable_attr::{ClockAttr, ClockInterval};
use crate::units::{self, Base};
use proc_macro2::{Span, TokenStream};
use quote::quote;
use syn::{DeriveInput, Expr, Ident};

fn variant(rt: &TokenStream, ty: &str, v: &str) -> TokenStream {
    let ty = Ident::new(ty, Span::call_site());
    let v = Ident::new(v, Span::call_site());
    quote!(#rt::description::#ty::#v)
}

/// The model's `ModelDescription { .. }`: `input` with its `#[fmu]` attribute `model`, its
/// variables, its internal state (the fields that are no variables) and the crate's metadata.
pub(crate) fn model_description(
    rt: &TokenStream,
    input: &DeriveInput,
    model: &ModelAttr,
    vars: &[Var],
    internal: &[String],
    meta: &Metadata,
) -> TokenStream {
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
    let default_experiment = option(meta.default_experiment.map(|[start, stop, tol, step]| {
        let (start, stop, tol, step) = (option(start), option(stop), option(tol), option(step));
        quote!(#rt::description::DefaultExperiment {
            start_time: #start, stop_time: #stop, tolerance: #tol, step_size: #step,
        })
    }));
    let unit_tokens = unit_tokens(rt, model, vars);
    let category_tokens = model
        .categories
        .iter()
        .map(|(n, d, _)| quote!(#rt::description::LogCategory { name: #n, description: #d }));
    let variable_tokens: Vec<_> = vars.iter().map(|v| variable_tokens(rt, v, vars)).collect();
    let indicator_names = vars
        .iter()
        .filter(|v| v.event_indicator.is_some())
        .map(|v| v.name.clone());
    fn terminal(rt: &TokenStream, vars: &[Var], t: &crate::model::model_attr::TerminalAttr) -> TokenStream {
        let (name, kind, rule, description) = (&t.name, &t.kind, &t.matching_rule, &t.description);
        let members = t.members.iter().map(|(variable, member, kind, _)| {
            let variable = fmi_name(vars, variable);
            quote!(#rt::description::TerminalMember { variable: #variable, member: #member, kind: #kind })
        });
        let nested = t.terminals.iter().map(|n| terminal(rt, vars, n));
        quote!(#rt::description::Terminal {
            name: #name,
            kind: #kind,
            matching_rule: #rule,
            description: #description,
            members: &[#(#members),*],
            terminals: &[#(#nested),*],
        })
    }
    let terminal_tokens = model.terminals.iter().map(|t| terminal(rt, vars, t));
    let bus_simulation = model.bus_simulation.is_some();

    quote! {
        #rt::description::ModelDescription {
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
            bus_simulation: #bus_simulation,
        }
    }
}

/// Every unit the variables use, in order of first use, with its base units and display units.
fn unit_tokens(rt: &TokenStream, model: &ModelAttr, vars: &[Var]) -> Vec<TokenStream> {
    // Every unit the variables use, in order of first use, with its base units.
    let mut used: Vec<(String, Base)> = Vec::new();
    for v in vars {
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
    used.iter()
        .map(|(name, b)| {
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
    })
    .collect()
}

/// One variable's `Variable { .. }`.
fn variable_tokens(rt: &TokenStream, v: &Var, vars: &[Var]) -> TokenStream {
    let name = &v.name;
    let vr = v.vr;
    let causality = variant(rt, "Causality", &format!("{:?}", v.causality));
    let variability = variant(rt, "Variability", &format!("{:?}", v.variability));
    let initial = option(v.initial.map(|i| variant(rt, "Initial", &format!("{i:?}"))));
    let start = start_tokens(rt, v);
    let fmi3_only = v.fmi3_only || !v.kind.in_fmi2();
    let max_size = option(v.max_size.as_ref());
    let mime_type = v.mime_type.as_ref().map(|m| m.value()).unwrap_or_default();
    let dims = &v.dims;
    // The value references of the structural parameters that set the lengths (checked).
    let sized_by: Vec<u32> = v
        .sized_by
        .iter()
        .map(|(p, _)| vars.iter().find(|x| x.is_named(p)).map_or(u32::MAX, |x| x.vr))
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
    let bound = |b: &Option<(Expr, bool)>| {
        option(b.as_ref().map(|(e, exclusive)| {
            quote!(#rt::description::Bound {
                value: (#e) as f64,
                exclusive: #exclusive,
            })
        }))
    };
    let (min, max) = (bound(&v.min), bound(&v.max));
    let nominal = option(v.nominal.as_ref().map(|e| quote!((#e) as f64)));
    // The FMI names of the variables named (by FMI name or by field).
    let names = |deps: &Option<Vec<(String, Span)>>| {
        option(deps.as_ref().map(|deps| {
            let names = deps.iter().map(|(d, _)| fmi_name(vars, d));
            quote!(&[#(#names),*])
        }))
    };
    let (depends, initial_depends) = (names(&v.depends), names(&v.initial_depends));
    let derivative_of = option(v.derivative_of.as_ref().map(|(d, _)| fmi_name(vars, d)));
    let clock = option(v.clock.as_ref().map(|c| clock_tokens(rt, c, vars)));
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

/// The variable's start value in the description: the runtime's `Start` of its kind, an array's
/// elements row-major (computed at compile time from the field's start).
fn start_tokens(rt: &TokenStream, v: &Var) -> TokenStream {
    let ty = &v.ty;
    if !v.has_start() {
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
    }
}

/// A Clock's declaration: `ClockDecl { .. }`.
fn clock_tokens(rt: &TokenStream, c: &ClockAttr, vars: &[Var]) -> TokenStream {
    let iv = variant(rt, "IntervalVariability", &{
        let mut n = c.variability.0.clone();
        n[..1].make_ascii_uppercase();
        n
    });
    let (interval, parameter) = match &c.interval {
        Some(ClockInterval::Value(e)) => (Some(quote!((#e) as f64)), String::new()),
        Some(ClockInterval::Parameter(p, _)) => (None, fmi_name(vars, p)),
        None => (None, String::new()),
    };
    let interval = option(interval);
    let shift = match &c.shift {
        Some(e) => quote!((#e) as f64),
        None => quote!(0.0),
    };
    let can = c.can_be_deactivated;
    let priority = option(c.priority.map(|(p, _)| p));
    quote!(#rt::description::ClockDecl {
        interval_variability: #iv,
        interval: #interval,
        interval_parameter: #parameter,
        shift: #shift,
        can_be_deactivated: #can,
        priority: #priority,
    })
}
