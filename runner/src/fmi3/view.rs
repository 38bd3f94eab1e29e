//! An FMI 3.0 description as the FMI 2.0 one the runner reads ([`as_fmi2`]; see [`super`]), and
//! every variable as the typed calls get and set it ([`Var3`]).

use md_reader::Causality;
use md_reader::fmi2 as d2;
use md_reader::fmi3 as d3;
use std::collections::HashSet;

/// An FMI 3.0 description read as the runner's FMI 2.0 one, and what was left out of it.
pub struct Fmi3Parts {
    pub description: d2::ModelDescription,
    /// Value references of the Enumeration variables (fmi3GetInt64 / fmi3SetInt64).
    pub int64: HashSet<u32>,
    /// Every variable but the independent one and the clocks, of every type, scalar or array:
    /// what connections, parameters and records of the types FMI 2.0 lacks go through.
    pub typed: Vec<Var3>,
    /// (name, what) of the variables the runner does not read or set: clocks, and the clocked
    /// variables it does not connect (see `fmi3/clocks.rs`).
    pub skipped: Vec<(String, String)>,
    /// The clocks and their clocked variables (the Float64 scalars are in `description` as Real
    /// ones, the others in `typed`); None: no event mode.
    pub clocks: Option<super::ClockPlan>,
    /// The inputs of every type some output depends on directly (ModelStructure `<Output
    /// dependencies>`; an output without the attribute depends on every input).
    pub feedthrough: Vec<u32>,
    /// The number of continuous states: the elements of the `<ContinuousStateDerivative>`s
    /// (an array derivative counts each; FMI 3.0, 2.4.8).
    pub states: usize,
    /// `<CoSimulation hasEventMode>`: it may be instantiated with eventModeUsed.
    pub has_event_mode: bool,
}

/// An FMI 3.0 variable as the runner gets and sets it ([`crate::values::Values`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Var3 {
    pub name: String,
    pub vr: u32,
    pub ty: d3::Type,
    pub causality: Causality,
    /// Its dimensions' sizes, outermost first (empty: a scalar): a fixed size, or the value of
    /// the structural parameter that sets it: its start value in the FMU's variables, the value
    /// in force in a component's ([`Var3::sized`]: the system sets it in Configuration Mode).
    pub shape: Vec<usize>,
    /// For each dimension, the structural parameter (or constant) that sets it, (value
    /// reference, name); None: a fixed size.
    pub dims: Vec<Option<(u32, String)>>,
    pub start: Option<String>,
    pub unit: Option<String>,
    /// Its `declaredType` (an Enumeration's type, whose items an SSV value names).
    pub declared_type: Option<String>,
}

impl Var3 {
    /// The number of values (an array's elements, 1 for a scalar).
    pub fn count(&self) -> usize {
        self.shape.iter().product()
    }

    /// This variable in an instance whose structural parameters have the values `sizes`
    /// ((value reference, value); a parameter not among them keeps its start value): each
    /// dimension a structural parameter sets takes its value.
    pub fn sized(&self, sizes: &[(u32, usize)]) -> Var3 {
        let mut v = self.clone();
        for (n, dim) in v.shape.iter_mut().zip(&self.dims) {
            if let Some((vr, _)) = dim
                && let Some(&(_, size)) = sizes.iter().find(|(p, _)| p == vr)
            {
                *n = size;
            }
        }
        v
    }

    /// Its dimensions as they resolve, each set by a structural parameter named with its value:
    /// `[n = 2,m = 3]`, `[3]`; empty for a scalar.
    pub fn dimensions(&self) -> String {
        if self.shape.is_empty() {
            return String::new();
        }
        let dims: Vec<String> = self
            .shape
            .iter()
            .zip(&self.dims)
            .map(|(n, d)| match d {
                Some((_, name)) => format!("{name} = {n}"),
                None => n.to_string(),
            })
            .collect();
        format!("[{}]", dims.join(","))
    }

    /// Its type and shape as messages say them: `Float64`, `Float64[3,3]`.
    pub fn kind(&self) -> String {
        if self.shape.is_empty() {
            self.ty.name().to_owned()
        } else {
            let dims: Vec<String> = self.shape.iter().map(|n| n.to_string()).collect();
            format!("{}[{}]", self.ty.name(), dims.join(","))
        }
    }
}

/// The sizes of `v`'s dimensions (fixed, or its structural parameters' start values).
fn shape(d: &d3::ModelDescription, v: &d3::Variable) -> Result<Vec<usize>, String> {
    v.dimensions
        .iter()
        .map(|dim| match dim {
            d3::Dimension::Fixed(n) => usize::try_from(*n).map_err(|_| format!("dimension {n} is too large")),
            d3::Dimension::Parameter(vr) => {
                let p = d
                    .by_vr(*vr)
                    .ok_or_else(|| format!("its dimension names value reference {vr}, which does not exist"))?;
                p.start
                    .as_deref()
                    .and_then(|s| s.trim().parse::<usize>().ok())
                    .ok_or_else(|| format!("its dimension's structural parameter '{}' has no integer start", p.name))
            }
        })
        .collect()
}

/// `v` into `typed`, or (a clock, a clocked variable, an array of unknown size) `skipped`.
fn sort(
    d: &d3::ModelDescription,
    v: &d3::Variable,
    admitted: bool,
    typed: &mut Vec<Var3>,
    skipped: &mut Vec<(String, String)>,
) {
    if v.ty == d3::Type::Clock || (!v.clocks.is_empty() && !admitted) {
        let what = if v.ty == d3::Type::Clock {
            match v.clock.as_ref() {
                Some(c) => format!("Clock ({}, interval {})", v.causality.name(), c.interval_variability),
                None => "Clock".to_owned(),
            }
        } else {
            format!("{} clocked variable (a clock of it is none of the FMU's)", v.ty)
        };
        skipped.push((v.name.clone(), what));
        return;
    }
    match shape(d, v) {
        Ok(shape) => typed.push(Var3 {
            name: v.name.clone(),
            vr: v.vr,
            ty: v.ty,
            causality: v.causality,
            dims: v
                .dimensions
                .iter()
                .map(|dim| match dim {
                    d3::Dimension::Parameter(vr) => {
                        Some((*vr, d.by_vr(*vr).map_or_else(String::new, |p| p.name.clone())))
                    }
                    d3::Dimension::Fixed(_) => None,
                })
                .collect(),
            shape,
            start: v.start.clone(),
            unit: v.unit.clone(),
            declared_type: v.declared_type.clone(),
        }),
        Err(why) => skipped.push((v.name.clone(), format!("{} array ({why})", v.ty))),
    }
}

/// The FMI 3.0 description `d` as the FMI 2.0 one the runner reads (see the module).
pub fn as_fmi2(d: &d3::ModelDescription) -> Fmi3Parts {
    let mut variables = Vec::new();
    let mut int64 = HashSet::new();
    let mut skipped = Vec::new();
    let mut typed = Vec::new();
    let mut clocks = super::clocks::plan(d);
    for v in &d.variables {
        // A clocked variable: set and read while its clocks tick, between ticks held; a Float64
        // scalar as a Real, the others through the typed calls.
        let admitted = !v.clocks.is_empty() && clocks.as_mut().is_some_and(|p| super::clocks::admit(p, v));
        let real = admitted && super::clocks::is_real(v);
        if v.causality != Causality::Independent && !real {
            sort(d, v, admitted, &mut typed, &mut skipped);
        }
        if v.ty == d3::Type::Clock || (!v.clocks.is_empty() && !real) {
            continue;
        }
        let ty = match v.ty {
            d3::Type::Float64 => Some(d2::Type::Real),
            d3::Type::Int32 => Some(d2::Type::Integer),
            d3::Type::Enumeration => Some(d2::Type::Enumeration),
            d3::Type::Boolean => Some(d2::Type::Boolean),
            d3::Type::String => Some(d2::Type::String),
            _ => None,
        };
        let Some(ty) = ty.filter(|_| v.dimensions.is_empty() && !v.array && (v.clocks.is_empty() || real)) else {
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
    // An array among the derivatives or the event indicators counts its elements (FMI 3.0, 2.4.8).
    let elements = |list: &[d3::Unknown]| -> usize {
        list.iter()
            .map(|u| typed.iter().find(|v| v.vr == u.vr).map_or(1, Var3::count))
            .sum()
    };
    let states = elements(&d.derivatives);
    let description = d2::ModelDescription {
        fmi_version: d.fmi_version.clone(),
        model_name: d.model_name.clone(),
        guid: d.token.clone(),
        description: d.description.clone(),
        version: d.version.clone(),
        generation_tool: d.generation_tool.clone(),
        number_of_event_indicators: elements(&d.event_indicators),
        cs,
        me,
        // The items an ssv:Enumeration names (set through fmi3SetInt64; an item beyond the
        // FMI 2.0 view's 32 bits is left out, and naming it is refused as an unknown item).
        enumerations: d
            .enumerations
            .iter()
            .map(|e| d2::Enumeration {
                name: e.name.clone(),
                items: e
                    .items
                    .iter()
                    .filter_map(|(n, v)| Some((n.clone(), i32::try_from(*v).ok()?)))
                    .collect(),
            })
            .collect(),
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
    let inputs: Vec<u32> = typed
        .iter()
        .filter(|v| v.causality == Causality::Input)
        .map(|v| v.vr)
        .collect();
    let mut feedthrough = Vec::new();
    // An output clock's dependencies say what its ticks depend on, not a value's: the runner
    // ticks clocks before any value is exchanged (`sim/clocks.rs`), so they close no loop.
    let is_clock = |vr: u32| d.by_vr(vr).is_some_and(|v| v.ty == d3::Type::Clock);
    for o in d.outputs.iter().filter(|o| !is_clock(o.vr)) {
        match &o.dependencies {
            None => feedthrough.extend(&inputs),
            Some(deps) => feedthrough.extend(deps.iter().filter(|k| inputs.contains(k))),
        }
    }
    Fmi3Parts {
        description,
        int64,
        typed,
        skipped,
        clocks,
        feedthrough,
        states,
        has_event_mode: d.cs.as_ref().is_some_and(|cs| cs.has_event_mode),
    }
}
