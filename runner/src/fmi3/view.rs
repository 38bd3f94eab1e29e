//! An FMI 3.0 description as the FMI 2.0 one the runner reads ([`as_fmi2`]; see [`super`]).

use md_reader::Causality;
use md_reader::fmi2 as d2;
use md_reader::fmi3 as d3;
use std::collections::HashSet;

/// An FMI 3.0 description read as the runner's FMI 2.0 one, and what was left out of it.
pub struct Fmi3Parts {
    pub description: d2::ModelDescription,
    /// Value references of the Enumeration variables (fmi3GetInt64 / fmi3SetInt64).
    pub int64: HashSet<u32>,
    /// (name, FMI 3.0 type) of the variables the runner does not read: other types, arrays.
    pub skipped: Vec<(String, String)>,
}

/// The FMI 3.0 description `d` as the FMI 2.0 one the runner reads (see the module).
pub fn as_fmi2(d: &d3::ModelDescription) -> Fmi3Parts {
    let mut variables = Vec::new();
    let mut int64 = HashSet::new();
    let mut skipped = Vec::new();
    for v in &d.variables {
        let ty = match v.ty {
            d3::Type::Float64 => Some(d2::Type::Real),
            d3::Type::Int32 => Some(d2::Type::Integer),
            d3::Type::Enumeration => Some(d2::Type::Enumeration),
            d3::Type::Boolean => Some(d2::Type::Boolean),
            d3::Type::String => Some(d2::Type::String),
            _ => None,
        };
        let Some(ty) = ty.filter(|_| v.dimensions.is_empty() && !v.array && v.clocks.is_empty()) else {
            if v.causality != Causality::Independent {
                let what = if v.dimensions.is_empty() && !v.array {
                    format!("{:?}", v.ty)
                } else {
                    format!("{:?} array", v.ty)
                };
                skipped.push((v.name.clone(), what));
            }
            continue;
        };
        if ty == d2::Type::Enumeration {
            int64.insert(v.vr);
        }
        variables.push(d2::Variable {
            name: v.name.clone(),
            vr: v.vr,
            ty,
            causality: v.causality,
            variability: v.variability,
            declared_initial: v.declared_initial,
            start: v.start.clone(),
            min: v.min,
            max: v.max,
            derivative: None,
            declared_type: v.declared_type.clone(),
            unit: v.unit.clone(),
            description: v.description.clone(),
        });
    }
    let index = |vr: u32| variables.iter().position(|x: &d2::Variable| x.vr == vr).map(|i| i + 1);
    // ModelStructure's elements in FMI 2.0's form: indices into the variables kept.
    let unknowns = |list: &[d3::Unknown]| -> Vec<d2::Unknown> {
        list.iter()
            .filter_map(|u| {
                Some(d2::Unknown {
                    index: index(u.vr)?,
                    dependencies: u
                        .dependencies
                        .as_ref()
                        .map(|deps| deps.iter().filter_map(|&k| index(k)).collect()),
                })
            })
            .collect()
    };
    let outputs = unknowns(&d.outputs);
    let derivatives = unknowns(&d.derivatives);
    let me = d.me.as_ref().map(|me| d2::ModelExchange {
        model_identifier: me.model_identifier.clone(),
        can_get_and_set_fmu_state: me.can_get_and_set_fmu_state,
        can_serialize_fmu_state: me.can_serialize_fmu_state,
        provides_directional_derivative: me.provides_directional_derivatives,
        completed_integrator_step_not_needed: false,
    });
    let cs = d.cs.as_ref().map(|cs| d2::CoSimulation {
        model_identifier: cs.model_identifier.clone(),
        can_get_and_set_fmu_state: cs.can_get_and_set_fmu_state,
        can_serialize_fmu_state: cs.can_serialize_fmu_state,
        provides_directional_derivative: cs.provides_directional_derivatives,
        can_handle_variable_step: cs.can_handle_variable_step,
        can_interpolate_inputs: false,
        max_output_derivative_order: cs.max_output_derivative_order,
        can_run_asynchronuously: false,
    });
    let description = d2::ModelDescription {
        fmi_version: d.fmi_version.clone(),
        model_name: d.model_name.clone(),
        guid: d.token.clone(),
        description: d.description.clone(),
        version: d.version.clone(),
        generation_tool: d.generation_tool.clone(),
        number_of_event_indicators: d.event_indicators.len(),
        cs,
        me,
        enumerations: Vec::new(),
        log_categories: d.log_categories.clone(),
        default_experiment: d.default_experiment.clone(),
        variables,
        model_structure: d2::ModelStructure {
            outputs,
            derivatives,
            initial_unknowns: Vec::new(),
            errors: d.errors.clone(),
        },
    };
    Fmi3Parts {
        description,
        int64,
        skipped,
    }
}
