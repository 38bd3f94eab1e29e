//! Writing variables: all-or-nothing (every value is checked before the first is stored),
//! numbers, strings and binaries, scalars and arrays, and FMI 2.0's input derivatives; after a
//! set, a tunable parameter's change reaches the model.

use super::checks::{Refusal, refusal, refusal_as};
use super::{Instance, Outcome, any_array, any_fmi2_element};
use crate::core::logging::Category;
use crate::core::machine::State;
use crate::core::{Function, OK, Status, WARNING};
use crate::description::{Causality, Initial, VarType, Variability, Variable};
use crate::model::CoSimulation;
use crate::step::{non_finite, oversized_binary};
use crate::value::{FmiType, Value};

impl<M: CoSimulation> Instance<M> {
    /// [`Instance::set_value_list`] of an FMI 2.0 call that names array elements: all or none.
    #[cold]
    fn set_fmi2_elements(&mut self, function: &str, vrs: &[u32], values: &[Value]) -> Status {
        let mut parameter_changed = false;
        for (vr, value) in vrs.iter().zip(values) {
            let (decl, element) = match self.fmi2_resolve(function, *vr, value.api_type()) {
                Ok(found) => found,
                Err(status) => return status,
            };
            if let Err(status) = self.check_settable_as(function, decl, element) {
                return status;
            }
            let (name, element_vr) = Self::name_and_vr(decl, element);
            match refusal_as(&self.sim.model, decl, *value, &name, element_vr) {
                None => {}
                Some(Refusal::Rule(why)) => {
                    return self.error(&format!("{function}: {why}; refused, value unchanged"));
                }
                Some(Refusal::Model(why)) => return self.error(&format!("{function}: {why}")),
            }
            parameter_changed |= decl.causality == Causality::Parameter;
        }
        let previous = (parameter_changed && self.between_steps()).then(|| self.sim.model.clone());
        for (vr, value) in vrs.iter().zip(values) {
            match M::DESCRIPTION.fmi2_element(*vr) {
                Some((i, k)) => {
                    self.sim
                        .model
                        .set_element(M::DESCRIPTION.variables[i].value_reference, k, *value);
                }
                None => {
                    self.sim.model.set(*vr, *value);
                }
            }
        }
        self.after_set(function, previous)
    }

    pub fn set_strings(&mut self, vrs: &[u32], values: &[String]) -> Status {
        if const { M::DESCRIPTION.has_clocks() } {
            self.reopen_tick();
        }
        let f = self.terms.name(Function::SetString);
        let mut parameter_changed = false;
        for vr in vrs {
            let decl = match self.lookup(f, *vr, VarType::String) {
                Ok(d) => d,
                Err(status) => return status,
            };
            if let Err(status) = self.check_settable(f, decl) {
                return status;
            }
            parameter_changed |= decl.causality == Causality::Parameter;
        }
        let previous = (parameter_changed && self.between_steps()).then(|| self.sim.model.clone());
        for (vr, v) in vrs.iter().zip(values) {
            self.sim.model.set_string(*vr, v);
        }
        self.after_set(f, previous)
    }

    /// Whether the standard lets this variable be set in the current state (FMI 2.0, 4.2.4).
    fn settable(&self, decl: &Variable) -> bool {
        let initial_exact_or_approx = matches!(decl.effective_initial(), Some(Initial::Exact | Initial::Approx));
        if decl.variability == Variability::Constant {
            return false;
        }
        if decl.causality == Causality::StructuralParameter
            || matches!(self.sim.state, State::ConfigurationMode | State::ReconfigurationMode)
        {
            // Structural parameters are set in (Re)configuration Mode, and nothing else is there.
            return self.settable_in_configuration(decl);
        }
        match self.sim.state {
            State::Instantiated => initial_exact_or_approx || decl.causality == Causality::Input,
            State::InitializationMode => {
                decl.causality == Causality::Input || decl.effective_initial() == Some(Initial::Exact)
            }
            State::StepComplete | State::EventMode | State::ClockActivationMode => {
                decl.causality == Causality::Input
                    || (decl.causality == Causality::Parameter && decl.variability == Variability::Tunable)
            }
            // Model exchange between events: continuous inputs only (states through
            // fmi2SetContinuousStates).
            State::ContinuousTimeMode => {
                decl.causality == Causality::Input && decl.variability == Variability::Continuous
            }
            _ => false,
        }
    }

    fn check_settable(&self, function: &str, decl: &Variable) -> Outcome {
        self.check_settable_as(function, decl, None)
    }

    /// [`Instance::check_settable`] of a variable, or of element `k` of an array in FMI 2.0.
    fn check_settable_as(&self, function: &str, decl: &Variable, element: Option<usize>) -> Outcome {
        if M::DESCRIPTION.has_clocks() && decl.is_clocked() {
            self.clocked_access(function, decl, true)?;
        }
        if self.settable(decl) {
            return Ok(());
        }
        if decl.causality == Causality::StructuralParameter
            || matches!(self.sim.state, State::ConfigurationMode | State::ReconfigurationMode)
        {
            return Err(self.error(&format!(
                "{function}: '{}' (vr {}, causality {:?}, variability {:?}) cannot be set in state {}: structural \
                 parameters are set in Configuration Mode (fixed and tunable ones, after fmi3EnterConfigurationMode \
                 in Instantiated) and Reconfiguration Mode (tunable ones, from Step Mode or model exchange's Event \
                 Mode), and nothing else is set there",
                decl.name,
                decl.value_reference,
                decl.causality,
                decl.variability,
                self.terms.state_name(self.sim.state)
            )));
        }
        let (name, vr) = Self::name_and_vr(decl, element);
        Err(self.error(&format!(
            "{function}: '{name}' (vr {vr}, causality {:?}, variability {:?}) cannot be set in state {:?}",
            decl.causality, decl.variability, self.sim.state
        )))
    }

    fn check_one(&self, function: &str, vr: u32, value: Value) -> Result<&'static Variable, Status> {
        let decl = self.lookup(function, vr, value.api_type())?;
        self.check_settable(function, decl)?;
        match refusal(&self.sim.model, decl, value) {
            None if const { M::DESCRIPTION.has_structural_parameters() } => {
                self.check_structural(function, decl, value)?;
                Ok(decl)
            }
            None => Ok(decl),
            Some(Refusal::Rule(why)) => Err(self.error(&format!("{function}: {why}; refused, value unchanged"))),
            Some(Refusal::Model(why)) => Err(self.error(&format!("{function}: {why}"))),
        }
    }

    /// fmi2SetRealInputDerivatives (a model that declares `CoSimulation::INTERPOLATES_INPUTS`):
    /// the first time derivatives of continuous Real inputs, all or none. Refused: order 0 or
    /// less (FMI 2.0: "0 is not allowed"), a variable that is no continuous Real input, a value
    /// that is not finite, or a state where the input could not be set. Higher orders are legal
    /// calls the runtime's linear interpolation does not use: ignored, with fmi2Warning saying so.
    pub fn set_input_derivatives(&mut self, function: &str, vrs: &[u32], orders: &[i32], values: &[f64]) -> Status {
        for ((vr, order), value) in vrs.iter().zip(orders).zip(values) {
            let decl = match self.lookup(function, *vr, VarType::Real) {
                Ok(d) => d,
                Err(status) => return status,
            };
            if decl.causality != Causality::Input || decl.variability != Variability::Continuous {
                return self.error(&format!(
                    "{function}: '{}' (vr {vr}) is no continuous Real input; refused, nothing changed",
                    decl.name
                ));
            }
            if *order < 1 {
                return self.error(&format!(
                    "{function}: order {order} for '{}' (vr {vr}): derivative orders start at 1 (0 is not allowed); \
                     refused, nothing changed",
                    decl.name
                ));
            }
            if !value.is_finite() {
                return self.error(&format!(
                    "{function}: {value} for the derivative of '{}' (vr {vr}) is not finite; refused, nothing changed",
                    decl.name
                ));
            }
            if let Err(status) = self.check_settable(function, decl) {
                return status;
            }
        }
        let mut ignored = vec![];
        for ((vr, order), value) in vrs.iter().zip(orders).zip(values) {
            if *order > 1 {
                ignored.push(format!("order {order} of vr {vr}"));
                continue;
            }
            match self.input_slopes.iter_mut().find(|(v, _)| v == vr) {
                Some(slot) => slot.1 = *value,
                None => self.input_slopes.push((*vr, *value)),
            }
        }
        if ignored.is_empty() {
            return OK;
        }
        self.logger.log(
            WARNING,
            Category::StatusWarning,
            &format!(
                "{function}: {} ignored: the inputs are interpolated linearly over a step (first derivatives only)",
                ignored.join(", ")
            ),
        );
        WARNING
    }

    /// Sets all values or none: each is checked before any is stored.
    pub fn set_values<T: FmiType>(&mut self, function: &str, vrs: &[u32], values: &[T]) -> Status {
        if const { M::DESCRIPTION.has_clocks() } {
            self.reopen_tick();
        }
        if const { M::DESCRIPTION.has_structural_parameters() } {
            self.keep_before_configuration();
        }
        if !any_array::<M>(vrs) && !any_fmi2_element::<M>(self.version, vrs) {
            // One value per value reference, checked in place: no allocation on the hot path
            // (fmi2SetReal before every step; tests/hot_path_does_not_allocate.rs).
            let mut parameter_changed = false;
            for (vr, v) in vrs.iter().zip(values) {
                let Some(value) = v.to_value() else {
                    return self.error(&format!("{function}: value reference {vr}: not a numeric value"));
                };
                match self.check_one(function, *vr, value) {
                    Ok(decl) => parameter_changed |= decl.causality == Causality::Parameter,
                    Err(status) => return status,
                }
            }
            let previous = (parameter_changed && self.between_steps()).then(|| self.sim.model.clone());
            for (vr, v) in vrs.iter().zip(values) {
                if let Some(value) = v.to_value() {
                    self.sim.model.set(*vr, value);
                }
            }
            return self.after_set(function, previous);
        }
        let mut list = Vec::with_capacity(values.len());
        for (i, v) in values.iter().enumerate() {
            match v.to_value() {
                Some(value) => list.push(value),
                None => return self.error(&format!("{function}: values[{i}] is not a numeric value")),
            }
        }
        self.set_value_list(function, vrs, &list)
    }

    /// [`Instance::set_values`] of values that may differ in type (FMI 3.0's fmi3SetInt64
    /// reaches Int64 and Enumeration variables in one call): all or none.
    pub fn set_value_list(&mut self, function: &str, vrs: &[u32], values: &[Value]) -> Status {
        if const { M::DESCRIPTION.has_clocks() } {
            self.reopen_tick();
        }
        if const { M::DESCRIPTION.has_structural_parameters() } {
            self.keep_before_configuration();
        }
        if any_fmi2_element::<M>(self.version, vrs) {
            return self.set_fmi2_elements(function, vrs, values);
        }
        if any_array::<M>(vrs) {
            return self.set_with_arrays(function, vrs, values);
        }
        let mut parameter_changed = false;
        for (vr, value) in vrs.iter().zip(values) {
            match self.check_one(function, *vr, *value) {
                Ok(decl) => parameter_changed |= decl.causality == Causality::Parameter,
                Err(status) => return status,
            }
        }
        let previous = (parameter_changed && self.between_steps()).then(|| self.sim.model.clone());
        for (vr, value) in vrs.iter().zip(values) {
            self.sim.model.set(*vr, *value);
        }
        self.after_set(function, previous)
    }

    /// [`Instance::set_value_list`] of a model with array variables: `values` holds each
    /// array's elements in row-major order; every element is checked before any is stored.
    fn set_with_arrays(&mut self, function: &str, vrs: &[u32], values: &[Value]) -> Status {
        let mut parameter_changed = false;
        let mut at = 0;
        let mut spans = Vec::with_capacity(vrs.len());
        for vr in vrs {
            let n = crate::step::structural::count_of(&self.sim.model, *vr);
            let Some(elements) = values.get(at..at + n) else {
                return self.error(&format!(
                    "{function}: the values array ends before the elements of value reference {vr}"
                ));
            };
            for (i, value) in elements.iter().enumerate() {
                match self.check_one(function, *vr, *value) {
                    Ok(decl) => parameter_changed |= decl.causality == Causality::Parameter,
                    Err(status) => {
                        if n > 1 {
                            self.trace(|| format!("{function}: (element {i} of value reference {vr})"));
                        }
                        return status;
                    }
                }
            }
            spans.push((*vr, at, n));
            at += n;
        }
        let previous = (parameter_changed && self.between_steps()).then(|| self.sim.model.clone());
        for (vr, at, n) in spans {
            let decl = M::variable_index(vr).map(|i| &M::DESCRIPTION.variables[i]);
            let is_array = decl.is_some_and(|d| d.is_array());
            for (i, value) in values[at..at + n].iter().enumerate() {
                if let (true, Some(d)) = (is_array, decl) {
                    let k = crate::step::structural::storage_index(&self.sim.model, d, i);
                    self.sim.model.set_element(vr, k, *value);
                } else {
                    self.sim.model.set(vr, *value);
                }
            }
        }
        self.after_set(function, previous)
    }

    /// The Binary setter (FMI 3.0): all or none; a value longer than the variable's `maxSize`
    /// is refused.
    pub fn set_binaries(&mut self, function: &str, vrs: &[u32], values: &[&[u8]]) -> Status {
        if const { M::DESCRIPTION.has_clocks() } {
            self.reopen_tick();
        }
        let mut parameter_changed = false;
        for (vr, bytes) in vrs.iter().zip(values) {
            let decl = match self.lookup(function, *vr, VarType::Binary) {
                Ok(d) => d,
                Err(status) => return status,
            };
            if let Err(status) = self.check_settable(function, decl) {
                return status;
            }
            if let Some(max) = decl.fmi3.max_size
                && bytes.len() > max as usize
            {
                return self.error(&format!(
                    "{function}: {} bytes for '{}' (vr {vr}) exceed its maxSize = {max}; refused, values unchanged",
                    bytes.len(),
                    decl.name
                ));
            }
            parameter_changed |= decl.causality == Causality::Parameter;
        }
        let previous = (parameter_changed && self.between_steps()).then(|| self.sim.model.clone());
        for (vr, bytes) in vrs.iter().zip(values) {
            self.sim.model.set_binary(*vr, bytes);
        }
        self.after_set(function, previous)
    }

    /// After values were stored: stale calculated variables in initialization mode; between
    /// steps, a tunable parameter change the model may still refuse (then nothing changes).
    fn after_set(&mut self, function: &str, previous: Option<M>) -> Status {
        if self.sim.state == State::InitializationMode {
            self.sim.init_dirty = true;
        }
        self.sim.stale_derivatives = true;
        self.sim.stale_outputs = true;
        if let Some(previous) = previous {
            let (sim, ctx) = self.sim_and_context();
            let outcome = sim.model.parameters_changed(&ctx).and_then(|()| {
                non_finite(&sim.model)
                    .or_else(|| oversized_binary(&sim.model))
                    .map_or(Ok(()), Err)
            });
            if let Err(why) = outcome {
                self.sim.model = previous;
                return self.error(&format!(
                    "{function}: parameter change refused: {why}; values unchanged"
                ));
            }
            self.sim.solver.restart();
            self.event(|| format!("{function}: tunable parameters changed at t = {}", self.sim.time));
        }
        OK
    }
}
