//! Model Exchange: the modes an importer's integrator switches between, its time, and the
//! vectors it reads and writes (continuous states, nominals, event indicators, derivatives),
//! of the entries a structural parameter leaves visible.

use super::{Instance, Outcome};
use crate::core::machine::State;
use crate::core::{Function, OK, Status};
use crate::description::VarType;
use crate::model::{CoSimulation, StateVector};

impl<M: CoSimulation> Instance<M> {
    pub fn enter_continuous_time_mode(&mut self) -> Status {
        self.end_ticks();
        self.sim.state = State::ContinuousTimeMode;
        self.sim.events.initial = false;
        OK
    }

    /// Returns (enterEventMode, terminateSimulation): the models here have no step events
    /// (their state and time events are found by the importer).
    pub fn completed_integrator_step(&mut self) -> (Status, bool, bool) {
        self.sim.last_successful_time = self.sim.time;
        (OK, false, false)
    }

    pub fn set_time(&mut self, t: f64) -> Status {
        if !t.is_finite() {
            return self.error(&format!(
                "{}: time = {t} is not finite; time stays {}",
                self.terms.name(Function::SetTime),
                self.sim.time
            ));
        }
        self.sim.time = t;
        self.sim.stale_derivatives = true;
        self.sim.stale_outputs = true;
        OK
    }

    #[inline]
    fn check_states_len(&self, function: &str, n: usize) -> Outcome {
        if n == crate::step::structural::number_of_states(&self.sim.model) {
            return Ok(());
        }
        Err(self.wrong_states_len(function, n))
    }

    /// Before a vector of `n` continuous states or derivatives is read: its length checked, and in
    /// Initialization Mode the initialization run, so that it reads the initial values.
    #[inline]
    fn states_to_read(&mut self, function: &str, n: usize) -> Outcome {
        self.check_states_len(function, n)?;
        if self.sim.state == State::InitializationMode {
            self.initialize_model(function, false)?;
        }
        Ok(())
    }

    #[cold]
    fn wrong_states_len(&self, function: &str, n: usize) -> Status {
        self.error(&format!(
            "{function}: nx = {n}, but {} has {} continuous states (numberOfContinuousStates{})",
            M::DESCRIPTION.model_identifier,
            crate::step::structural::number_of_states(&self.sim.model),
            if const { M::DESCRIPTION.has_sized_arrays() } {
                ", with the structural parameters as they are now"
            } else {
                ""
            }
        ))
    }

    /// The entry of the state vector that is the importer's state `i`.
    #[inline]
    fn state_entry(&self, i: usize) -> usize {
        if !const { M::DESCRIPTION.has_sized_arrays() } {
            return i;
        }
        crate::step::structural::active_states(&self.sim.model)
            .nth(i)
            .unwrap_or(i)
    }

    /// The name of the importer's state `i` (an element of an array state: `x[2]`).
    fn name_of_state(&self, i: usize) -> std::borrow::Cow<'static, str> {
        Self::entry_name(self.state_entry(i))
    }

    /// The name of entry `k` of the whole state vector.
    fn entry_name(k: usize) -> std::borrow::Cow<'static, str> {
        let vr = M::STATES[k];
        match M::variable_index(vr).map(|j| &M::DESCRIPTION.variables[j]) {
            Some(v) if v.is_array() => v.element_name(M::STATE_ELEMENTS[k] as usize).into(),
            Some(v) => v.name.into(),
            None => "?".into(),
        }
    }

    /// The importer's state vector (or derivatives, nominals) from the whole one: the entries
    /// it sees ([`crate::step::structural::active_states`]).
    #[inline]
    fn gather(&self, full: &[f64], out: &mut [f64]) {
        if !const { M::DESCRIPTION.has_sized_arrays() } {
            out.copy_from_slice(full);
            return;
        }
        for (slot, k) in out
            .iter_mut()
            .zip(crate::step::structural::active_states(&self.sim.model))
        {
            *slot = full[k];
        }
    }

    pub fn set_continuous_states(&mut self, function: &str, x: &[f64]) -> Status {
        if let Err(status) = self.check_states_len(function, x.len()) {
            return status;
        }
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return self.error(&format!(
                "{function}: x[{i}] ('{}') = {} is not a finite number; refused, states unchanged",
                self.name_of_state(i),
                x[i]
            ));
        }
        let mut states = if const { M::DESCRIPTION.has_sized_arrays() } {
            self.sim.model.states()
        } else {
            <M::States as StateVector>::zeros()
        };
        if const { M::DESCRIPTION.has_sized_arrays() } {
            for (k, v) in crate::step::structural::active_states(&self.sim.model).zip(x) {
                states.as_mut_slice()[k] = *v;
            }
        } else {
            states.as_mut_slice().copy_from_slice(x);
        }
        self.sim.model.set_states(&states);
        self.sim.stale_derivatives = true;
        self.sim.stale_outputs = true;
        OK
    }

    pub fn get_continuous_states(&mut self, function: &str, x: &mut [f64]) -> Status {
        if let Err(status) = self.states_to_read(function, x.len()) {
            return status;
        }
        let full = self.sim.model.states();
        self.gather(full.as_slice(), x);
        OK
    }

    pub fn get_nominals(&mut self, function: &str, x: &mut [f64]) -> Status {
        if let Err(status) = self.check_states_len(function, x.len()) {
            return status;
        }
        self.gather(M::NOMINALS, x);
        OK
    }

    pub fn get_event_indicators_mut(&mut self, function: &str, z: &mut [f64]) -> Status {
        if z.len() != M::INDICATORS.len() {
            return self.error(&format!(
                "{function}: ni = {}, but {} has {} event indicators (numberOfEventIndicators)",
                z.len(),
                M::DESCRIPTION.model_identifier,
                M::INDICATORS.len()
            ));
        }
        if z.is_empty() {
            return OK;
        }
        if self.sim.state == State::InitializationMode
            && let Err(status) = self.initialize_model(function, false)
        {
            return status;
        }
        let mut c = self.sim.model.continuous::<f64>();
        self.sim.model.derivatives(self.sim.time, &mut c);
        self.sim.model.outputs(self.sim.time, &mut c);
        M::indicators_of(&c, z);
        if let Some(i) = z.iter().position(|v| !v.is_finite()) {
            let vr = M::INDICATORS[i];
            let name = M::declaration(vr, VarType::Real).map_or("?", |v| v.name);
            return self.not_finite(
                function,
                &format!("event indicator {i} ('{name}', vr {vr}) is {}", z[i]),
            );
        }
        OK
    }

    /// The get-derivatives function: the right-hand side only (the outputs stay for when they are read).
    #[inline]
    pub fn get_derivatives(&mut self, function: &str, dx: &mut [f64]) -> Status {
        if let Err(status) = self.states_to_read(function, dx.len()) {
            return status;
        }
        if self.sim.stale_derivatives {
            let mut c = self.sim.model.continuous::<f64>();
            self.sim.model.derivatives(self.sim.time, &mut c);
            let mut d = M::derivatives_of(&c);
            if const { M::DESCRIPTION.has_sized_arrays() } {
                let mask = crate::step::structural::active_mask(&self.sim.model);
                crate::step::structural::hide(&mut d, mask.as_ref());
            }
            if let Some(i) = d.as_slice().iter().position(|v| !v.is_finite()) {
                let what = format!("the derivative of '{}' is {}", Self::entry_name(i), d.as_slice()[i]);
                return self.not_finite(function, &what);
            }
            self.derivatives = d;
            self.sim.stale_derivatives = false;
        } else if !self.sim.stale_outputs {
            // Computed with everything else: the model's own der(..) variables hold them.
            let c = self.sim.model.continuous::<f64>();
            self.derivatives = M::derivatives_of(&c);
        }
        let d = self.derivatives;
        self.gather(d.as_slice(), dx);
        OK
    }
}
