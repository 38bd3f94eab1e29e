//! Reading variables: numbers, strings and binaries, scalars and arrays (FMI 2.0's array
//! elements), each after the state and clock checks and with the computed values up to date.

use super::{Instance, Outcome, any_array, any_fmi2_element};
use crate::core::machine::State;
use crate::core::{Function, OK, Status};
use crate::description::{Causality, VarType, Variable};
use crate::model::CoSimulation;
use crate::value::{FmiType, Value};

impl<M: CoSimulation> Instance<M> {
    pub fn get_values<T: FmiType>(&mut self, function: &str, vrs: &[u32], out: &mut [T]) -> Status {
        if any_fmi2_element::<M>(self.version, vrs) {
            return self.get_fmi2_elements(function, vrs, out);
        }
        // A clock's tick first (whether a variable is readable depends on it), then every
        // reference is checked before anything is computed: a refused get changes nothing.
        if let Err(status) = self.evaluate_tick_for(function, vrs) {
            return status;
        }
        for vr in vrs {
            if let Err(status) = self
                .lookup(function, *vr, T::TYPE)
                .and_then(|v| self.check_gettable(function, v))
            {
                return status;
            }
        }
        if let Err(status) = self.up_to_date(function) {
            return status;
        }
        if any_array::<M>(vrs) {
            return self.get_with_arrays(function, vrs, out);
        }
        for (vr, slot) in vrs.iter().zip(out.iter_mut()) {
            // The independent variable is the instance's time, whatever the model's field holds.
            let value = match M::declaration(*vr, T::TYPE) {
                Some(d) if d.causality == Causality::Independent => Some(Value::Real(self.sim.time)),
                _ => self.sim.model.get(*vr),
            };
            match value.and_then(T::from_value) {
                Some(v) => *slot = v,
                None => return self.error(&format!("{function}: value reference {vr} has no {:?} value", T::TYPE)),
            }
        }
        OK
    }

    /// [`Instance::get_values`] of an FMI 2.0 call that names array elements.
    #[cold]
    fn get_fmi2_elements<T: FmiType>(&mut self, function: &str, vrs: &[u32], out: &mut [T]) -> Status {
        for vr in vrs {
            if let Err(status) = self
                .fmi2_resolve(function, *vr, T::TYPE)
                .and_then(|(d, k)| self.check_gettable_as(function, d, k))
            {
                return status;
            }
        }
        if let Err(status) = self.up_to_date(function) {
            return status;
        }
        for (vr, slot) in vrs.iter().zip(out.iter_mut()) {
            let (d, element) = match self.fmi2_resolve(function, *vr, T::TYPE) {
                Ok(found) => found,
                Err(status) => return status,
            };
            let value = match element {
                Some(k) => self.sim.model.get_element(d.value_reference, k),
                None if d.causality == Causality::Independent => Some(Value::Real(self.sim.time)),
                None => self.sim.model.get(*vr),
            };
            match value.and_then(T::from_value) {
                Some(v) => *slot = v,
                None => return self.error(&format!("{function}: value reference {vr} has no {:?} value", T::TYPE)),
            }
        }
        OK
    }

    /// [`Instance::get_values`] of a model with array variables: each array's elements in
    /// row-major order, one after the other (`out` holds the sum of the element counts; the
    /// FMI 3.0 layer checked nValues).
    fn get_with_arrays<T: FmiType>(&mut self, function: &str, vrs: &[u32], out: &mut [T]) -> Status {
        let mut at = 0;
        for vr in vrs {
            let Some(d) = M::declaration(*vr, T::TYPE) else {
                return self.error(&format!("{function}: value reference {vr} has no {:?} value", T::TYPE));
            };
            let n = crate::step::structural::element_count(&self.sim.model, d);
            let Some(slots) = out.get_mut(at..at + n) else {
                return self.error(&format!(
                    "{function}: the values array ends before the elements of '{}'",
                    d.name
                ));
            };
            for (i, slot) in slots.iter_mut().enumerate() {
                let value = if d.causality == Causality::Independent {
                    Some(Value::Real(self.sim.time))
                } else if d.is_array() {
                    let k = crate::step::structural::storage_index(&self.sim.model, d, i);
                    self.sim.model.get_element(*vr, k)
                } else {
                    self.sim.model.get(*vr)
                };
                match value.and_then(T::from_value) {
                    Some(v) => *slot = v,
                    None => {
                        return self.error(&format!(
                            "{function}: '{}' has no {:?} value at element {i}",
                            d.name,
                            T::TYPE
                        ));
                    }
                }
            }
            at += n;
        }
        OK
    }

    /// The get-string function: the returned pointers stay valid until the next call on this
    /// instance.
    pub fn get_strings(&mut self, vrs: &[u32], out: &mut [*const std::os::raw::c_char]) -> Status {
        let f = self.terms.name(Function::GetString);
        // A clock's tick first (as in `get_values`), then the checks.
        if let Err(status) = self.evaluate_tick_for(f, vrs) {
            return status;
        }
        for vr in vrs {
            if let Err(status) = self
                .lookup(f, *vr, VarType::String)
                .and_then(|v| self.check_gettable(f, v))
            {
                return status;
            }
        }
        if let Err(status) = self.up_to_date(f) {
            return status;
        }
        self.strings.clear();
        for vr in vrs {
            let text = self.sim.model.get_string(*vr).unwrap_or_default();
            self.strings.push(crate::core::logging::to_cstring(text));
        }
        for (slot, s) in out.iter_mut().zip(&self.strings) {
            *slot = s.as_ptr();
        }
        OK
    }

    /// Before initialization (FMI 3.0's Instantiated; FMI 2.0 allows no get there) a variable has
    /// a value only if the description gives it a start value: an input, or initial exact or
    /// approx. A calculated variable is computed from the start values during initialization,
    /// so reading it here is refused rather than answered with a number that means nothing.
    fn check_gettable(&self, function: &str, decl: &Variable) -> Outcome {
        self.check_gettable_as(function, decl, None)
    }

    /// [`Instance::check_gettable`] of a variable, or of element `k` of an array in FMI 2.0
    /// (the message names the element and its value reference).
    fn check_gettable_as(&self, function: &str, decl: &Variable, element: Option<usize>) -> Outcome {
        if M::DESCRIPTION.has_clocks() && decl.is_clocked() {
            self.clocked_access(function, decl, false)?;
        }
        if !matches!(self.sim.state, State::Instantiated | State::ConfigurationMode) || decl.has_start() {
            return Ok(());
        }
        let (name, vr) = Self::name_and_vr(decl, element);
        Err(self.error(&format!(
            "{function}: '{name}' (vr {vr}, causality {:?}, initial calculated) has no value before initialization: \
             in state Instantiated only start values can be read (inputs, initial exact or approx)",
            decl.causality
        )))
    }

    /// The Binary getter (FMI 3.0): the returned pointers stay valid until the next call on
    /// this instance (the bytes are copied, as the strings are).
    pub fn get_binaries(&mut self, function: &str, vrs: &[u32], sizes: &mut [usize], out: &mut [*const u8]) -> Status {
        // A clock's tick first (as in `get_values`), then the checks.
        if let Err(status) = self.evaluate_tick_for(function, vrs) {
            return status;
        }
        for vr in vrs {
            if let Err(status) = self
                .lookup(function, *vr, VarType::Binary)
                .and_then(|v| self.check_gettable(function, v))
            {
                return status;
            }
        }
        if let Err(status) = self.up_to_date(function) {
            return status;
        }
        // Every place the model's code runs checks what it wrote (`oversized_binary`); this is
        // the last word, should a value have come in another way.
        for vr in vrs {
            let decl = M::variable_index(*vr).map(|i| &M::DESCRIPTION.variables[i]);
            if let (Some(d), Some(max)) = (decl, decl.and_then(|d| d.fmi3.max_size))
                && let Some(n) = self.sim.model.get_binary(*vr).map(<[u8]>::len)
                && n > max as usize
            {
                return self.error(&format!(
                    "{function}: '{}' (vr {vr}) holds {n} bytes, more than its maxSize = {max}; nothing returned",
                    d.name
                ));
            }
        }
        self.binaries.clear();
        for vr in vrs {
            self.binaries
                .push(self.sim.model.get_binary(*vr).unwrap_or_default().to_vec());
        }
        for ((slot, size), b) in out.iter_mut().zip(sizes.iter_mut()).zip(&self.binaries) {
            *slot = b.as_ptr();
            *size = b.len();
        }
        OK
    }
}
