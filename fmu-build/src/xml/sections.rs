//! The elements both versions write (alike, or nearly: the log categories name the version's
//! statuses, an enumeration type is named differently).

use super::{Xml, close, empty, open, real_text};
use rustfmu::description::{FmiVersion, ModelDescription, RUNTIME_LOG_CATEGORIES};

/// What stands between the interfaces and the variables, in both versions' schema order: the
/// units, the enumeration types, the log categories, the default experiment.
pub(super) fn definitions(w: &mut Xml, d: &ModelDescription, version: FmiVersion) -> Result<(), String> {
    unit_definitions(w, d)?;
    type_definitions(w, d, version)?;
    log_categories(w, d, version)?;
    default_experiment(w, d)
}

/// `<UnitDefinitions>` (the same in FMI 2.0 and 3.0): the units the variables use, in name order.
fn unit_definitions(w: &mut Xml, d: &ModelDescription) -> Result<(), String> {
    let decls = d.variables;
    // Units in name order, as before (the derive lists them in order of first use).
    let mut units: Vec<_> = d
        .units
        .iter()
        .filter(|u| decls.iter().any(|v| v.unit == u.name))
        .collect();
    units.sort_by(|a, b| a.name.cmp(b.name));
    if !units.is_empty() {
        open(w, "UnitDefinitions", &[])?;
        for unit in &units {
            let b = unit.base;
            open(w, "Unit", &[("name", unit.name)])?;
            let exps = [
                ("kg", b.kg),
                ("m", b.m),
                ("s", b.s),
                ("A", b.a),
                ("K", b.k),
                ("mol", b.mol),
                ("cd", b.cd),
                ("rad", b.rad),
            ];
            let mut texts: Vec<(&str, String)> = exps
                .iter()
                .filter(|(_, e)| *e != 0)
                .map(|(k, e)| (*k, e.to_string()))
                .collect();
            if b.factor != 1.0 {
                texts.push(("factor", real_text(b.factor)));
            }
            if b.offset != 0.0 {
                texts.push(("offset", real_text(b.offset)));
            }
            let attrs: Vec<(&str, &str)> = texts.iter().map(|(k, v)| (*k, v.as_str())).collect();
            empty(w, "BaseUnit", &attrs)?;
            // display = factor · value + offset (FMI 3.0 also: inverse, factor / value).
            for du in unit.display_units {
                let (factor, offset) = (real_text(du.factor), real_text(du.offset));
                let mut attrs = vec![("name", du.name)];
                if du.factor != 1.0 {
                    attrs.push(("factor", &factor));
                }
                if du.offset != 0.0 {
                    attrs.push(("offset", &offset));
                }
                if du.inverse {
                    attrs.push(("inverse", "true"));
                }
                empty(w, "DisplayUnit", &attrs)?;
            }
            close(w, "Unit")?;
        }
        close(w, "UnitDefinitions")?;
    }

    Ok(())
}

/// `<LogCategories>`: the runtime's, then the model's. The runtime's say which status they come
/// with, in the names of the version the binary implements.
fn log_categories(w: &mut Xml, d: &ModelDescription, version: FmiVersion) -> Result<(), String> {
    open(w, "LogCategories", &[])?;
    for (i, c) in d.all_log_categories().enumerate() {
        let description = match version {
            FmiVersion::V3 if i < RUNTIME_LOG_CATEGORIES.len() => c.description.replace("fmi2", "fmi3"),
            _ => c.description.to_string(),
        };
        empty(w, "Category", &[("name", c.name), ("description", &description)])?;
    }
    close(w, "LogCategories")
}

/// `<DefaultExperiment>` (the same in FMI 2.0 and 3.0), if the model declares one.
fn default_experiment(w: &mut Xml, d: &ModelDescription) -> Result<(), String> {
    if let Some(e) = d.default_experiment {
        let texts: Vec<(&str, String)> = [
            ("startTime", e.start_time),
            ("stopTime", e.stop_time),
            ("tolerance", e.tolerance),
            ("stepSize", e.step_size),
        ]
        .into_iter()
        .filter_map(|(k, v)| v.map(|v| (k, real_text(v))))
        .collect();
        let attrs: Vec<(&str, &str)> = texts.iter().map(|(k, v)| (*k, v.as_str())).collect();
        empty(w, "DefaultExperiment", &attrs)?;
    }
    Ok(())
}

/// `<TypeDefinitions>`: the enumerations the variables use (FMI 2.0: a `<SimpleType>` holding an
/// `<Enumeration>`; FMI 3.0: an `<EnumerationType>`), none without one.
fn type_definitions(w: &mut Xml, d: &ModelDescription, version: FmiVersion) -> Result<(), String> {
    let enums = d.enumerations();
    if enums.is_empty() {
        return Ok(());
    }
    open(w, "TypeDefinitions", &[])?;
    for e in &enums {
        let mut attrs = vec![("name", e.name)];
        if !e.description.is_empty() {
            attrs.push(("description", e.description));
        }
        match version {
            FmiVersion::V2 => {
                open(w, "SimpleType", &attrs)?;
                open(w, "Enumeration", &[])?;
            }
            FmiVersion::V3 => open(w, "EnumerationType", &attrs)?,
        }
        for item in e.items {
            let value = item.value.to_string();
            let mut attrs = vec![("name", item.name), ("value", value.as_str())];
            if !item.description.is_empty() {
                attrs.push(("description", item.description));
            }
            empty(w, "Item", &attrs)?;
        }
        match version {
            FmiVersion::V2 => {
                close(w, "Enumeration")?;
                close(w, "SimpleType")?;
            }
            FmiVersion::V3 => close(w, "EnumerationType")?,
        }
    }
    close(w, "TypeDefinitions")
}
