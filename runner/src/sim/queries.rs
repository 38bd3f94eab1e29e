//! What a built [`Simulation`] tells about its system: components, connections, outputs,
//! parameters, start values, the evaluation order (for the container, the Python module and an
//! isolated system's child).

use super::*;

impl Simulation {
    /// The system's own connectors (an SSD's `ssd:System/ssd:Connectors`) with the component
    /// variables they are connected to.
    pub fn system_connectors(&self) -> &[crate::ssp::SystemConnector] {
        &self.system_connectors
    }

    /// Each component's name and its FMU's description, in the system's order.
    pub fn component_descriptions(&self) -> Vec<(&str, &md_reader::fmi2::ModelDescription)> {
        self.slaves
            .iter()
            .map(|s| (s.name.as_str(), &self.fmus[s.fmu].description))
            .collect()
    }

    /// Whether a connection drives input `variable` of `component`.
    pub fn is_connected_input(&self, component: &str, variable: &str) -> bool {
        self.source_of(component, variable).is_some()
    }

    /// The output (component, variable) connected to input `variable` of `component`.
    pub fn source_of(&self, component: &str, variable: &str) -> Option<(String, String)> {
        self.connections
            .iter()
            .find(|k| k.end.0 == component && k.end.1 == variable)
            .map(|k| k.start.clone())
    }

    /// The inputs of `component` its variable `output` depends on directly (ModelStructure;
    /// an output without `dependencies` depends on every input, as in fmpy).
    pub fn direct_inputs(&self, component: &str, output: &str) -> Vec<String> {
        let Ok(i) = self.slave_index(component) else {
            return Vec::new();
        };
        let d = &self.fmu_of(i).description;
        let inputs = || {
            d.variables
                .iter()
                .filter(|v| v.causality == Causality::Input)
                .map(|v| v.name.clone())
                .collect::<Vec<_>>()
        };
        let Some(index) = d.variables.iter().position(|v| v.name == output) else {
            return Vec::new();
        };
        match d.model_structure.outputs.iter().find(|u| u.index == index + 1) {
            None => Vec::new(),
            Some(u) => match &u.dependencies {
                None => inputs(),
                Some(deps) => deps
                    .iter()
                    .filter_map(|k| d.by_index(*k))
                    .filter(|v| v.causality == Causality::Input)
                    .map(|v| v.name.clone())
                    .collect(),
            },
        }
    }

    /// The system's own value of `component.variable` (its parameter set), as an XML start value.
    pub fn start_value(&self, component: &str, variable: &str) -> Option<String> {
        let key = format!("{component}.{variable}");
        self.starts.iter().find(|(k, _, _)| *k == key).map(|(_, _, s)| match s {
            Setter::Real(x) => format!("{x:?}"),
            Setter::Integer(x) => x.to_string(),
            Setter::Boolean(x) => x.to_string(),
            Setter::String(s) => s.to_string_lossy().into_owned(),
            Setter::Values(v) => v.to_string(),
        })
    }

    /// The components in the order [`Scheme::GaussSeidel`] evaluates them.
    pub fn evaluation_order(&self) -> Vec<&str> {
        self.steps.iter().map(|(i, _)| self.slaves[*i].name.as_str()).collect()
    }

    /// The components: (instance name, the FMU's model identifier).
    /// Whether component `i` (in [`Simulation::components`] order) is an FMI 3.0 FMU.
    pub fn is_fmi3(&self, i: usize) -> bool {
        self.slaves[i].v3
    }

    pub fn components(&self) -> Vec<(&str, &str)> {
        self.slaves
            .iter()
            .map(|s| (s.name.as_str(), self.fmus[s.fmu].model_identifier()))
            .collect()
    }

    /// The outputs of every component, "component.variable" (what the command line records by default).
    pub fn outputs(&self) -> Vec<String> {
        let mut out = Vec::new();
        for s in &self.slaves {
            for v in &self.fmus[s.fmu].description.variables {
                if v.causality == Causality::Output
                    && matches!(v.ty, Type::Real | Type::Integer | Type::Boolean | Type::Enumeration)
                {
                    out.push(format!("{}.{}", s.name, v.name));
                }
            }
        }
        self.typed_outputs_list(&mut out);
        out
    }

    /// The system's parameter and start values, "component.variable".
    pub fn parameters(&self) -> Vec<&str> {
        self.starts.iter().map(|(k, _, _)| k.as_str()).collect()
    }
}
