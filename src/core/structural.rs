//! Structural parameters (FMI 3.0, 2.4.7.6 and 3.2/4.2's Configuration Mode): UInt64 parameters
//! that set the lengths of arrays. A sized array is stored at its capacity (the Rust array's
//! lengths, the parameter's `max` at most); what the importer sees of it is the first
//! `n` (`n × m`) elements, row-major, and of an array state the first `n` entries. The
//! continuous state vector keeps its compile-time length (every capacity): the entries outside
//! the lengths are constant zero-derivative states the importer never sees, and the integrator's
//! error norm is taken over the visible ones ([`active_mask`], [`scaled_tolerances`]).

use super::instance::Instance;
use super::machine::State;
use super::{OK, Status};
use crate::description::{Causality, NOT_SIZED, Variability, Variable};
use crate::model::{CoSimulation, StateVector, Variables};
use crate::solver::Tolerances;
use crate::value::Value;

/// The length of one dimension now: the structural parameter's value (at most the capacity), or
/// the fixed length.
#[inline]
fn length<M: Variables>(model: &M, sized_by: u32, capacity: u32) -> usize {
    if sized_by == NOT_SIZED {
        return capacity as usize;
    }
    match model.get(sized_by) {
        Some(Value::UInt64(n)) => n.min(capacity as u64) as usize,
        _ => capacity as usize,
    }
}

/// How many values `decl` has now: 1 for a scalar, the product of its lengths for an array
/// (a sized array's from its structural parameters' values).
#[inline]
pub fn element_count<M: Variables>(model: &M, decl: &Variable) -> usize {
    if !decl.is_sized() {
        return decl.element_count();
    }
    decl.fmi3
        .sized_by
        .iter()
        .zip(decl.fmi3.dimensions)
        .map(|(s, c)| length(model, *s, *c))
        .product()
}

/// Where element `k` (row-major over the lengths now) of `decl` is stored (row-major over the
/// capacity): of a sized `[[T; C]; R]` with lengths (r, c), element (i, j) is `i C + j`.
#[inline]
pub fn storage_index<M: Variables>(model: &M, decl: &Variable, k: usize) -> usize {
    if !decl.is_sized() || decl.fmi3.dimensions.len() < 2 {
        return k;
    }
    let cols = length(model, decl.fmi3.sized_by[1], decl.fmi3.dimensions[1]).max(1);
    (k / cols) * decl.fmi3.dimensions[1] as usize + k % cols
}

/// The number of values of `vr` (1 for a scalar or an unknown reference).
#[inline]
pub fn count_of<M: Variables>(model: &M, vr: u32) -> usize {
    M::variable_index(vr).map_or(1, |i| element_count(model, &M::DESCRIPTION.variables[i]))
}

/// Whether entry `i` of the state vector is one the importer sees: a scalar state, or an
/// element of an array state within its length now.
#[inline]
fn state_active<M: Variables>(model: &M, i: usize) -> bool {
    let decl = M::variable_index(M::STATES[i]).map(|k| &M::DESCRIPTION.variables[k]);
    match decl {
        Some(d) if d.is_sized() => (M::STATE_ELEMENTS[i] as usize) < element_count(model, d),
        _ => true,
    }
}

/// The entries of the state vector the importer sees, in order (all of them unless a
/// structural parameter sizes an array state).
pub fn active_states<M: Variables>(model: &M) -> impl Iterator<Item = usize> + '_ {
    let sized = const { M::DESCRIPTION.has_sized_arrays() };
    (0..M::STATES.len()).filter(move |i| !sized || state_active(model, *i))
}

/// The number of continuous states now (numberOfContinuousStates of FMI 3.0's
/// fmi3GetNumberOfContinuousStates).
#[inline]
pub fn number_of_states<M: Variables>(model: &M) -> usize {
    if !const { M::DESCRIPTION.has_sized_arrays() } {
        return <M::States as StateVector>::LEN;
    }
    active_states(model).count()
}

/// 1 for the entries of the state vector the importer sees, 0 for the others; `None` when all
/// are seen.
pub fn active_mask<M: Variables>(model: &M) -> Option<M::States> {
    if !const { M::DESCRIPTION.has_sized_arrays() } {
        return None;
    }
    let mut mask = <M::States as StateVector>::zeros();
    for i in active_states(model) {
        mask.as_mut_slice()[i] = 1.0;
    }
    Some(mask)
}

/// Zeroes the derivatives of the entries the mask hides: they stay as they are.
#[inline]
pub fn hide<X: StateVector>(dx: &mut X, mask: Option<&X>) {
    if let Some(mask) = mask {
        for (d, m) in dx.as_mut_slice().iter_mut().zip(mask.as_slice()) {
            if *m == 0.0 {
                *d = 0.0;
            }
        }
    }
}

/// The integrator's error norm is the root mean square over the whole state vector; with `n`
/// of its `N` entries seen, tolerances scaled by sqrt(n / N) make it the root mean square over
/// those `n` (the hidden entries' errors are 0).
pub fn scaled_tolerances<X: StateVector>(tol: Tolerances, mask: Option<&X>) -> Tolerances {
    let Some(mask) = mask else { return tol };
    let seen = mask.as_slice().iter().filter(|m| **m != 0.0).count().max(1);
    let f = (seen as f64 / X::LEN.max(1) as f64).sqrt();
    Tolerances {
        rtol: tol.rtol * f,
        atol: tol.atol * f,
    }
}

impl<M: CoSimulation> Instance<M> {
    /// fmi3EnterConfigurationMode: from Instantiated into Configuration Mode (fixed and tunable
    /// structural parameters may be set), from Step Mode (co-simulation) or Event Mode (model
    /// exchange) into Reconfiguration Mode (tunable ones). The state check ran.
    pub fn enter_configuration_mode(&mut self, function: &str) -> Status {
        let next = match self.sim.state {
            State::Instantiated => State::ConfigurationMode,
            State::StepComplete if !self.model_exchange => State::ReconfigurationMode,
            State::EventMode if self.model_exchange => State::ReconfigurationMode,
            state => {
                return self.error(&format!(
                    "{function}: not in state {} of {}: Reconfiguration Mode is entered from Step Mode in \
                     co-simulation and from Event Mode in model exchange",
                    self.terms.state_name(state),
                    if self.model_exchange {
                        "model exchange"
                    } else {
                        "co-simulation"
                    }
                ));
            }
        };
        self.reconfigured_from = self.sim.state;
        self.sim.state = next;
        OK
    }

    /// fmi3ExitConfigurationMode: back to the state Configuration Mode was entered from. After a
    /// reconfiguration the model's `parameters_changed` sees the new sizes (it may refuse them:
    /// then the parameters are as before and the call fails), the integrator restarts, and the
    /// derivatives and outputs are computed anew.
    pub fn exit_configuration_mode(&mut self, function: &str) -> Status {
        let state = self.sim.state;
        self.sim.state = self.reconfigured_from;
        self.sim.stale_derivatives = true;
        self.sim.stale_outputs = true;
        if state == State::ReconfigurationMode {
            let status = self.reconfigured(function);
            if status != OK {
                return status;
            }
        }
        OK
    }

    fn reconfigured(&mut self, function: &str) -> Status {
        let Some(before) = self.before_configuration.take() else {
            return OK;
        };
        let ctx = crate::model::Context::outside_step(
            self.sim.start_time,
            self.sim.tolerance,
            Some(&self.logger),
            self.resources.as_deref(),
            self.model_exchange,
        );
        let outcome = self.sim.model.parameters_changed(&ctx).and_then(|()| {
            super::instance::oversized_binary(&self.sim.model).map_or(Ok(()), |what| Err(format!("it left {what}")))
        });
        if let Err(why) = outcome {
            self.sim.model = *before;
            return self.error(&format!(
                "{function}: the new structural parameters were refused: {why}; they are as before"
            ));
        }
        self.sim.solver.restart();
        OK
    }

    /// Whether `decl` may be set in Configuration or Reconfiguration Mode: a structural parameter
    /// (in Reconfiguration Mode a tunable one). Only those.
    pub(crate) fn settable_in_configuration(&self, decl: &Variable) -> bool {
        decl.causality == Causality::StructuralParameter
            && match self.sim.state {
                State::ConfigurationMode => true,
                State::ReconfigurationMode => decl.variability == Variability::Tunable,
                _ => false,
            }
    }

    /// Before a structural parameter is set: its value fits every array it sizes.
    pub(crate) fn check_structural(&self, function: &str, decl: &Variable, value: Value) -> Result<(), Status> {
        if decl.causality != Causality::StructuralParameter {
            return Ok(());
        }
        let Value::UInt64(n) = value else { return Ok(()) };
        for v in M::DESCRIPTION.variables {
            for (s, cap) in v.fmi3.sized_by.iter().zip(v.fmi3.dimensions) {
                if *s == decl.value_reference && n > *cap as u64 {
                    return Err(self.error(&format!(
                        "{function}: {n} for '{}' (vr {}) is more than the {cap} elements '{}' holds along that \
                         dimension; refused, value unchanged",
                        decl.name, decl.value_reference, v.name
                    )));
                }
            }
        }
        Ok(())
    }

    /// Keeps the model as it is before the first structural parameter of a reconfiguration is
    /// set (for `parameters_changed` to refuse the new sizes).
    pub(crate) fn keep_before_configuration(&mut self) {
        if self.sim.state == State::ReconfigurationMode && self.before_configuration.is_none() {
            self.before_configuration = Some(Box::new(self.sim.model.clone()));
        }
    }
}
