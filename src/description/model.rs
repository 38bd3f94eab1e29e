//! The model's declaration: its variables with what an FMU offers (the interfaces, the
//! version), its terminals, its log categories, and what the runtime asks of it.

use super::*;

/// An FMI version. A binary made with `rustfmu::export_fmu!` implements both (its `fmi2*` and
/// its `fmi3*` functions, and one encoded description per version); `export_fmi2!` or
/// `export_fmi3!` alone gives a binary of one version.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum FmiVersion {
    V2,
    V3,
}

impl FmiVersion {
    /// `fmiVersion` of the model description.
    pub const fn text(self) -> &'static str {
        match self {
            FmiVersion::V2 => "2.0",
            FmiVersion::V3 => "3.0",
        }
    }
}

/// What an FMU offers besides its variables; set by the export macro.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Interfaces {
    pub co_simulation: bool,
    pub model_exchange: bool,
    pub version: FmiVersion,
    /// FMI 2.0 co-simulation `canInterpolateInputs`: the step follows the first derivatives of
    /// the Real inputs given with fmi2SetRealInputDerivatives
    /// ([`crate::CoSimulation::INTERPOLATES_INPUTS`]).
    pub can_interpolate_inputs: bool,
    /// FMI 3.0 Scheduled Execution (`<ScheduledExecution>`, `#[fmu(scheduled_execution)]`).
    pub scheduled_execution: bool,
}

impl Interfaces {
    pub const CO_SIMULATION: Interfaces = Interfaces {
        co_simulation: true,
        model_exchange: false,
        version: FmiVersion::V2,
        can_interpolate_inputs: false,
        scheduled_execution: false,
    };
    /// Model exchange and co-simulation in one binary: what `export_fmi2!` exports.
    pub const BOTH: Interfaces = Interfaces {
        co_simulation: true,
        model_exchange: true,
        version: FmiVersion::V2,
        can_interpolate_inputs: false,
        scheduled_execution: false,
    };
    /// ... and what `export_fmi3!` exports.
    pub const BOTH_FMI3: Interfaces = Interfaces {
        co_simulation: true,
        model_exchange: true,
        version: FmiVersion::V3,
        can_interpolate_inputs: false,
        scheduled_execution: false,
    };
}

/// Everything the model description says, as declared.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelDescription {
    /// `modelName`, and `modelIdentifier`: the binary is `<identifier>.so` / `.dll`.
    pub model_identifier: &'static str,
    pub description: &'static str,
    pub author: &'static str,
    pub version: &'static str,
    pub copyright: &'static str,
    pub license: &'static str,
    pub generation_tool: &'static str,
    pub default_experiment: Option<DefaultExperiment>,
    /// Every unit the variables use, with its base units.
    pub units: &'static [Unit],
    /// The model's own log categories; the runtime's ([`RUNTIME_LOG_CATEGORIES`]) come first.
    pub log_categories: &'static [LogCategory],
    /// In `ModelVariables` order.
    pub variables: &'static [Variable],
    /// The model's other fields (`name: Type; ...`): part of the FMU state, so part of the GUID
    /// (a changed internal state changes the GUID, and old serialized states are refused).
    pub internal_state: &'static str,
    /// The event indicators (variables declared `event_indicator`), by name, in declaration
    /// order: FMI 2.0's `numberOfEventIndicators` and the order of `fmi2GetEventIndicators`,
    /// FMI 3.0's `<EventIndicator>` elements.
    pub event_indicators: &'static [&'static str],
    /// FMI 3.0 terminals (`terminalsAndIcons/terminalsAndIcons.xml`): named groups of
    /// variables an importer connects as one (a mechanical flange: angle, speed, torque).
    pub terminals: &'static [Terminal],
    /// An FMI-LS-BUS bus simulation FMU (`#[fmu(bus_simulation)]`): the manifest says
    /// `isBusSimulationFMU="true"`.
    pub bus_simulation: bool,
}

/// An FMI 3.0 `<Terminal>` (FMI 3.0, 2.4.9): variables that belong together.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Terminal {
    pub name: &'static str,
    /// `terminalKind`: what kind of connector it is, for the importer to match (e.g.
    /// `org.modelica.Modelica.Mechanics.Rotational.Interfaces.Flange_a`); empty for none.
    pub kind: &'static str,
    /// `matchingRule`: `plug` (connect members of the same name), `bus` or `sequence`.
    pub matching_rule: &'static str,
    pub description: &'static str,
    pub members: &'static [TerminalMember],
    /// Nested `<Terminal>`s (after the members, as `fmi3Terminal.xsd` orders them): an
    /// FMI-LS-BUS network terminal's `Configuration` terminal.
    pub terminals: &'static [Terminal],
}

/// A `<TerminalMemberVariable>`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TerminalMember {
    /// The model variable's name.
    pub variable: &'static str,
    /// `memberName`: its name in the terminal (what a `plug` matches).
    pub member: &'static str,
    /// `variableKind`: `signal` (a potential or signal: angle, speed), `inflow` or `outflow`
    /// (a flow, positive into resp. out of the FMU: torque).
    pub kind: &'static str,
}

/// Whether some variable of `$d` satisfies the condition (a `const fn` cannot take a closure:
/// the loop is written once here).
macro_rules! any_variable {
    ($d:expr, |$v:ident| $cond:expr) => {{
        let mut i = 0;
        let mut found = false;
        while i < $d.variables.len() {
            let $v = &$d.variables[i];
            if $cond {
                found = true;
                break;
            }
            i += 1;
        }
        found
    }};
}

impl ModelDescription {
    pub fn variable(&self, vr: u32, ty: VarType) -> Option<&'static Variable> {
        self.variables
            .iter()
            .find(|v| v.value_reference == vr && same_api_type(v.var_type, ty))
    }

    pub fn by_name(&self, name: &str) -> Option<&'static Variable> {
        self.variables.iter().find(|v| v.name == name)
    }

    /// Every declared enumeration type, once each, in the order the variables first use them.
    pub fn enumerations(&self) -> Vec<&'static EnumType> {
        let mut out: Vec<&'static EnumType> = Vec::new();
        for v in self.variables {
            if let Some(e) = v.enumeration
                && !out.iter().any(|o| o.name == e.name)
            {
                out.push(e);
            }
        }
        out
    }

    /// FMI 3.0 requires the independent variable among the variables: a declared
    /// `independent` one, or else `time` with the value reference one above the highest
    /// declared (the runtime answers it with the current time). Its value reference.
    /// (`const`: the runtime evaluates it at compile time.)
    pub const fn time_value_reference(&self) -> u32 {
        let mut next = 0u32;
        let mut i = 0;
        while i < self.variables.len() {
            let v = &self.variables[i];
            if let Causality::Independent = v.causality {
                return v.value_reference;
            }
            if v.value_reference.saturating_add(1) > next {
                next = v.value_reference.saturating_add(1);
            }
            i += 1;
        }
        next
    }

    /// Whether some variable exists in FMI 3.0 only (a type 2.0 lacks, an array, `fmi3_only`).
    pub const fn has_fmi3_only(&self) -> bool {
        any_variable!(self, |v| !v.in_version(FmiVersion::V2))
    }

    /// Whether some array variable is in the FMI 2.0 description (as its elements, scalars of
    /// structured names: [`Variable::element_name`]). (`const`: the FMI 2.0 functions of a model
    /// without one never look for elements.)
    pub const fn has_fmi2_arrays(&self) -> bool {
        any_variable!(self, |v| v.is_array() && v.in_version(FmiVersion::V2))
    }

    /// FMI 2.0's view of an array: the array variable (its index in `variables`) and the
    /// element (row-major) that the FMI 2.0 value reference `vr` names. An array of FMI 2.0 is
    /// its elements, scalars with the value references `vr, vr + 1, ..` of the array's `vr`
    /// (the derive keeps that range free of other variables). `None`: `vr` names no element.
    pub fn fmi2_element(&self, vr: u32) -> Option<(usize, usize)> {
        self.variables.iter().enumerate().find_map(|(i, v)| {
            let k = vr.checked_sub(v.value_reference)? as usize;
            (v.is_array() && k < v.element_count() && v.in_version(FmiVersion::V2)).then_some((i, k))
        })
    }

    /// Whether the FMI 2.0 value references of the elements of array `variables[i]` (its `vr`
    /// to `vr + n - 1`) take another variable's value reference. (`const`: the derive asserts
    /// at compile time that they do not.)
    pub const fn fmi2_elements_overlap(&self, i: usize) -> bool {
        let a = &self.variables[i];
        if !a.is_array() || !a.in_version(FmiVersion::V2) {
            return false;
        }
        let (first, n) = (a.value_reference as u64, a.element_count() as u64);
        let mut j = 0;
        while j < self.variables.len() {
            let v = &self.variables[j];
            let vr = v.value_reference as u64;
            if j != i {
                // The other's own range (its elements too, if it is an array of FMI 2.0).
                let m = if v.is_array() && v.in_version(FmiVersion::V2) {
                    v.element_count() as u64
                } else {
                    1
                };
                if vr < first + n && first < vr + m {
                    return true;
                }
            }
            j += 1;
        }
        false
    }

    /// Whether some variable is a Clock. (`const`: the clock functions of a model without one
    /// refuse every call at compile time.)
    pub const fn has_clocks(&self) -> bool {
        any_variable!(self, |v| v.fmi3.clock.is_some())
    }

    /// Whether some variable is an output Clock (a triggered clock the model ticks itself).
    pub const fn has_output_clocks(&self) -> bool {
        any_variable!(self, |v| v.fmi3.clock.is_some()
            && matches!(v.causality, Causality::Output))
    }

    /// Whether some variable is an array (FMI 3.0 `<Dimension>`s). (`const`: the runtime takes
    /// the scalar-only paths of a model without arrays at compile time.)
    pub const fn has_arrays(&self) -> bool {
        any_variable!(self, |v| v.is_array())
    }

    /// Whether some Binary variable has a `maxSize`. (`const`: a model without one skips the
    /// check of what it wrote into its Binaries at compile time.)
    pub const fn has_max_sizes(&self) -> bool {
        any_variable!(self, |v| v.fmi3.max_size.is_some())
    }

    /// Whether some variable is a structural parameter (FMI 3.0): then the FMU has
    /// Configuration Mode (`fmi3EnterConfigurationMode`).
    pub const fn has_structural_parameters(&self) -> bool {
        any_variable!(self, |v| matches!(v.causality, Causality::StructuralParameter))
    }

    /// Whether some array's length is set by a structural parameter.
    pub const fn has_sized_arrays(&self) -> bool {
        any_variable!(self, |v| v.is_sized())
    }

    /// Whether the model declares its independent variable itself (else FMI 3.0 adds `time`).
    pub const fn declares_independent(&self) -> bool {
        any_variable!(self, |v| matches!(v.causality, Causality::Independent))
    }

    /// Whether `v` is a continuous state: some variable is declared its derivative.
    pub fn is_state(&self, v: &Variable) -> bool {
        self.variables.iter().any(|d| d.derivative_of == Some(v.name))
    }

    /// The unknowns of Initialization Mode (FMI 2.0 `InitialUnknowns`, FMI 3.0
    /// `InitialUnknown`, the same rule in both): outputs, continuous states and their
    /// derivatives whose `initial` is approx or calculated, and every calculated parameter.
    /// Clocked variables are not among them (FMI 3.0, 2.4.8: they are initialized at their
    /// clocks' first tick).
    pub fn is_initial_unknown(&self, v: &Variable) -> bool {
        let computed = v.causality == Causality::Output || v.derivative_of.is_some() || self.is_state(v);
        let unknown = (computed && matches!(v.effective_initial(), Some(Initial::Approx | Initial::Calculated)))
            || v.causality == Causality::CalculatedParameter;
        unknown && !v.is_clocked()
    }

    /// The value references `vr` depends on as `<ModelStructure>` says (FMI 3.0
    /// `fmi3GetVariableDependencies`): in Initialization Mode (`initialization`) those of an
    /// `<InitialUnknown>`, else those of an `<Output>`, `<ContinuousStateDerivative>` or
    /// `<EventIndicator>`; where the declaration names none, every known (run time: the
    /// inputs and continuous states; Initialization Mode: the inputs, the independent variable
    /// `time_vr`, and the variables with initial = exact). In ascending order. `None`: `vr` is
    /// no unknown there.
    pub fn dependencies(&self, vr: u32, initialization: bool, time_vr: u32) -> Option<Vec<u32>> {
        let v = self.variables.iter().find(|v| v.value_reference == vr)?;
        let declared = if initialization {
            if !self.is_initial_unknown(v) {
                return None;
            }
            v.initial_depends_on
        } else {
            let unknown = v.causality == Causality::Output
                || v.derivative_of.is_some()
                || self.event_indicators.contains(&v.name);
            if !unknown {
                return None;
            }
            v.depends_on
        };
        let mut out: Vec<u32> = match declared {
            Some(names) => names
                .iter()
                .filter_map(|n| self.by_name(n))
                .map(|d| d.value_reference)
                .collect(),
            None if initialization => self
                .variables
                .iter()
                .filter(|d| {
                    matches!(d.causality, Causality::Input | Causality::Independent)
                        || d.effective_initial() == Some(Initial::Exact)
                })
                .map(|d| d.value_reference)
                .chain((!self.declares_independent()).then_some(time_vr))
                .collect(),
            None => self
                .variables
                .iter()
                .filter(|d| d.causality == Causality::Input || self.is_state(d))
                .map(|d| d.value_reference)
                .collect(),
        };
        out.sort_unstable();
        out.dedup();
        Some(out)
    }

    /// Runtime categories first, then the model's own.
    pub fn all_log_categories(&self) -> impl Iterator<Item = &'static LogCategory> {
        RUNTIME_LOG_CATEGORIES.iter().chain(self.log_categories.iter())
    }
}

/// Enumerations travel through `fmi2GetInteger`/`fmi2SetInteger`.
pub fn same_api_type(declared: VarType, asked: VarType) -> bool {
    declared == asked || (declared == VarType::Enumeration && asked == VarType::Integer)
}

/// The categories every FMU of this runtime logs under, in the runtime's order.
pub const RUNTIME_LOG_CATEGORIES: &[LogCategory] = &[
    LogCategory {
        name: "logEvents",
        description: "Initialization, steps that change the solver's course, parameter changes",
    },
    LogCategory {
        name: "logStatusWarning",
        description: "Messages that come with fmi2Warning",
    },
    LogCategory {
        name: "logStatusDiscard",
        description: "Messages that come with fmi2Discard: a step that could not be completed",
    },
    LogCategory {
        name: "logStatusError",
        description: "Messages that come with fmi2Error: a refused call or argument",
    },
    LogCategory {
        name: "logStatusFatal",
        description: "Messages that come with fmi2Fatal: the instance cannot be used any more",
    },
    LogCategory {
        name: "logCalls",
        description: "Every call of an fmi2 function, with its arguments",
    },
    LogCategory {
        name: "logAll",
        description: "All of the above",
    },
];
