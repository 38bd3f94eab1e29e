//! The rules of FMI 2.0 section 2.2.7 (FMI 3.0: 2.4.7), checked once more before a description
//! is written.

use super::array_sizes;
use fmi_standard::TypeKind;
use rustfmu::description::{Causality, FmiVersion, Initial, ModelDescription, Start, VarType};
use std::collections::BTreeSet;

/// Checks a decoded description against the rules of FMI 2.0 section 2.2.7 (FMI 3.0: 2.4.7)
/// once more (the derive macro enforces them at compile time; a description from elsewhere is
/// re-checked), with the same rules (`fmi-standard`) the derive uses. Structural parameters and
/// the arrays they size are FMI 3.0's only.
pub fn check_description(d: &ModelDescription, version: FmiVersion) -> Result<(), String> {
    let decls = d.variables;
    for name in d.event_indicators {
        match d.by_name(name) {
            Some(v)
                if v.var_type == VarType::Real && v.variability == rustfmu::description::Variability::Continuous => {}
            Some(v) => {
                return Err(format!(
                    "event indicator '{name}' (vr {}) is not a continuous Real variable",
                    v.value_reference
                ));
            }
            None => return Err(format!("event indicator '{name}' is no variable of the model")),
        }
    }
    let mut seen_names = BTreeSet::new();
    let mut seen_vrs = BTreeSet::new();
    for v in decls {
        let at = format!("variable '{}' (vr {})", v.name, v.value_reference);
        if !seen_names.insert(v.name) {
            return Err(format!("{at}: the name is declared twice"));
        }
        if !seen_vrs.insert(v.value_reference) {
            return Err(format!("{at}: the value reference is used twice"));
        }
        rustfmu::description::check_values(v).map_err(|e| format!("{at}: {}", e.message()))?;
        let kind = if v.var_type.is_float() {
            TypeKind::Real
        } else {
            TypeKind::Other
        };
        if !fmi_standard::legal_variability_for_type(kind, v.variability) {
            return Err(format!("{at}: only Real variables may be continuous"));
        }
        if !v.unit.is_empty() && !d.units.iter().any(|u| u.name == v.unit) {
            return Err(format!("{at}: unit '{}' is not declared", v.unit));
        }
        if v.var_type == VarType::Enumeration && v.enumeration.is_none() {
            return Err(format!("{at}: an Enumeration variable without its type"));
        }
        if version == FmiVersion::V2 && !v.causality.in_fmi2() {
            // FMI 2.0 has no structural parameters (a model with some is FMI 3.0 only).
            return Err(format!("{at}: causality {:?} is FMI 3.0's only", v.causality));
        }
        if v.is_sized() {
            if version == FmiVersion::V2 {
                return Err(format!(
                    "{at}: an array sized by structural parameters is FMI 3.0's only"
                ));
            }
            array_sizes(d, v).map_err(|e| format!("{at}: {e}"))?;
        }
        if !fmi_standard::legal_variability(v.causality, v.variability) {
            return Err(format!(
                "{at}: causality {:?} with variability {:?} is not allowed",
                v.causality, v.variability
            ));
        }
        if let Some(i) = v.initial
            && !fmi_standard::legal_initial(v.causality, v.variability, i)
        {
            return Err(format!(
                "{at}: initial {:?} is not allowed with causality {:?} and variability {:?}",
                v.initial, v.causality, v.variability
            ));
        }
        if v.has_start() == matches!(v.start, Start::None) {
            return Err(format!(
                "{at}: a start value must be given exactly where the standard asks for one"
            ));
        }
        // The knowns of ModelStructure: inputs and continuous states.
        for dep in v.depends_on.unwrap_or(&[]) {
            if !decls
                .iter()
                .any(|o| o.name == *dep && (o.causality == Causality::Input || d.is_state(o)))
            {
                return Err(format!(
                    "{at}: depends on '{dep}', which is neither an input nor a continuous state"
                ));
            }
        }
        // The knowns of Initialization Mode: inputs, the independent variable and the variables
        // with initial = exact (parameters among them).
        for dep in v.initial_depends_on.unwrap_or(&[]) {
            if !decls.iter().any(|o| {
                o.name == *dep
                    && (matches!(o.causality, Causality::Input | Causality::Independent)
                        || o.effective_initial() == Some(Initial::Exact))
            }) {
                return Err(format!(
                    "{at}: initially depends on '{dep}', which is neither an input nor a variable with initial = exact"
                ));
            }
        }
        if v.initial_depends_on.is_some() && !d.is_initial_unknown(v) {
            return Err(format!(
                "{at}: declares initial dependencies but is no unknown of Initialization Mode"
            ));
        }
        if let Some(state) = v.derivative_of
            && !decls.iter().any(|o| o.name == state)
        {
            return Err(format!("{at}: derivative of '{state}', which is not declared"));
        }
    }
    check_display_units_and_aliases(d, version)
}

/// The display units and aliases once more: a unit's display units have distinct names, an
/// inverse one (FMI 3.0 only) has no offset; a variable and its aliases show their value in a
/// display unit of the variable's unit; alias names are unique among variables and aliases.
fn check_display_units_and_aliases(d: &ModelDescription, version: FmiVersion) -> Result<(), String> {
    for u in d.units {
        for (i, du) in u.display_units.iter().enumerate() {
            let at = format!("display unit '{}' of unit '{}'", du.name, u.name);
            if u.display_units[..i].iter().any(|o| o.name == du.name) {
                return Err(format!("{at}: declared twice"));
            }
            if du.inverse && version == FmiVersion::V2 {
                return Err(format!("{at}: inverse, which FMI 2.0 has not"));
            }
            if du.inverse && du.offset != 0.0 {
                return Err(format!("{at}: inverse with an offset (FMI 3.0, 2.4.3)"));
            }
            if !du.factor.is_finite() || du.factor == 0.0 || !du.offset.is_finite() {
                return Err(format!("{at}: factor and offset are finite numbers, the factor not 0"));
            }
        }
    }
    let mut names: BTreeSet<&str> = d.variables.iter().map(|v| v.name).collect();
    for v in d.variables {
        let shows = |du: &str, who: &str| -> Result<(), String> {
            if du.is_empty() {
                return Ok(());
            }
            match d.units.iter().find(|u| u.name == v.unit && !v.unit.is_empty()) {
                Some(u) if u.display_units.iter().any(|x| x.name == du) => Ok(()),
                _ => Err(format!(
                    "{who}: display unit '{du}' is no display unit of the variable's unit '{}'",
                    v.unit
                )),
            }
        };
        let at = format!("variable '{}' (vr {})", v.name, v.value_reference);
        shows(v.display_unit, &at)?;
        for a in v.aliases {
            let who = format!("alias '{}' of {at}", a.name);
            if !names.insert(a.name) {
                return Err(format!("{who}: the name of another variable or alias"));
            }
            shows(a.display_unit, &who)?;
        }
    }
    Ok(())
}
