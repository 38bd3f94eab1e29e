//! FMU states (the same in both versions: FMI 3.0 renamed FMUstate to FMUState): every
//! component's own state plus the container's time and mode, and their serialized form.

use crate::*;

// FMU states (the same in both versions: FMI 3.0 renamed FMUstate to FMUState).
impl Container {
    pub(crate) fn can_state(&self, function: &str) -> Result<(), Status> {
        if self.sim.steps_to_clock_ticks() {
            return Err(self.error(&format!(
                "{function}: this system steps to its components' clock ticks, and the importer's side of their \
                 clocks (ticks planned, Event Mode, held values) is not part of the container's FMU state \
                 (canGetAndSetFMUstate = false)"
            )));
        }
        if self.all_components(|cs| cs.can_get_and_set_fmu_state) {
            Ok(())
        } else {
            Err(self.error(&format!(
                "{function}: a component cannot get and set its FMU state (canGetAndSetFMUstate = false)"
            )))
        }
    }

    pub(crate) fn can_serialize(&self, function: &str) -> Result<(), Status> {
        self.can_state(function)?;
        if self.all_components(|cs| cs.can_serialize_fmu_state) {
            Ok(())
        } else {
            Err(self.error(&format!(
                "{function}: a component cannot serialize its FMU state (canSerializeFMUstate = false)"
            )))
        }
    }

    /// The state `state` points to, if it is a live state of this container (any instance).
    pub(crate) fn saved(&self, state: *mut c_void, function: &str) -> Result<&'static mut Saved, Status> {
        let live = !state.is_null() && states().contains(&(state as usize));
        if !live {
            return Err(self.error(&format!(
                "{function}: {state:?} is not an FMU state of a live container (never given, or freed)"
            )));
        }
        // SAFETY: `state` is one of the live states of STATES: a `Box<Saved>` this library leaked
        // and has not freed; the importer uses it from one thread at a time.
        let saved = unsafe { &mut *(state as *mut Saved) };
        if saved.guid != self.spec.guid {
            return Err(self.error(&format!(
                "{function}: the FMU state is one of the container {}, not of this one ({})",
                saved.guid, self.spec.guid
            )));
        }
        Ok(saved)
    }

    pub(crate) fn component_refused(&mut self, function: &str, i: usize, e: Fmi2Error) -> Status {
        let name = self.sim.component_descriptions()[i].0.to_owned();
        let t = self.time;
        let e = Error::fmi(&name, function, &e, Some(t), "");
        self.refused(function, e)
    }

    /// Every component's current FMU state, in `slots` (updated) or in new ones.
    pub(crate) fn take_components(
        &mut self,
        function: &str,
        slots: Option<Vec<FmuState>>,
    ) -> Result<Vec<FmuState>, Status> {
        match slots {
            Some(slots) => {
                for (i, slot) in slots.iter().enumerate() {
                    if let Err(e) = self.sim.instance_mut(i).update_fmu_state(slot) {
                        self.free.push(slots);
                        return Err(self.component_refused(function, i, e));
                    }
                }
                Ok(slots)
            }
            None => {
                let mut slots = Vec::with_capacity(self.sim.len());
                for i in 0..self.sim.len() {
                    match self.sim.instance_mut(i).get_fmu_state() {
                        Ok(s) => slots.push(s),
                        Err(e) => return Err(self.component_refused(function, i, e)),
                    }
                }
                Ok(slots)
            }
        }
    }

    /// The serialized form of every component's state in `slots` (None where one cannot).
    pub(crate) fn serialize_components(
        &mut self,
        function: &str,
        slots: &[FmuState],
    ) -> Result<Option<Vec<Vec<u8>>>, Status> {
        if !self.all_components(|cs| cs.can_serialize_fmu_state) {
            return Ok(None);
        }
        let mut out = Vec::with_capacity(slots.len());
        for (i, slot) in slots.iter().enumerate() {
            match self.sim.instance_mut(i).serialize_fmu_state(slot) {
                Ok(b) => out.push(b),
                Err(e) => return Err(self.component_refused(function, i, e)),
            }
        }
        Ok(Some(out))
    }

    pub(crate) fn get_fmu_state(&mut self, function: &str, state: *mut *mut c_void) -> Outcome {
        self.check(Call::FmuState, function)?;
        self.can_state(function)?;
        if state.is_null() {
            return Err(self.error(&format!("{function}: the FMU state pointer is NULL")));
        }
        let existing = read(state).unwrap_or(std::ptr::null_mut());
        if !existing.is_null() {
            // With *FMUstate != NULL: that state is overwritten.
            let saved = self.saved(existing, function)?;
            let mine = saved.owner == self.id;
            let slots = if mine {
                Some(std::mem::take(&mut saved.components))
            } else {
                self.free.pop()
            };
            let components = self.take_components(function, slots)?;
            let bytes = self.serialize_components(function, &components)?;
            // (Its GUID is this container's: `saved` checked it.)
            *saved = self.saved_now(components, bytes);
            return Ok(fmi2OK);
        }
        let slots = self.free.pop();
        let components = self.take_components(function, slots)?;
        let bytes = self.serialize_components(function, &components)?;
        hand_out(state, self.saved_now(components, bytes))
    }

    /// An FMU state of the container as it is now, its components' states `components`
    /// (serialized: `bytes`).
    fn saved_now(&self, components: Vec<FmuState>, bytes: Option<Vec<Vec<u8>>>) -> Saved {
        Saved {
            owner: self.id,
            guid: self.spec.guid.clone(),
            components,
            bytes,
            time: self.time,
            state: self.state,
            dirty: self.dirty,
            last_successful: self.last_successful,
            stop_time: self.stop_time,
        }
    }

    pub(crate) fn set_fmu_state(&mut self, function: &str, state: *mut c_void) -> Outcome {
        self.check(Call::FmuState, function)?;
        self.can_state(function)?;
        let saved = self.saved(state, function)?;
        if saved.owner == self.id {
            for i in 0..self.sim.len() {
                if let Err(e) = self.sim.instance_mut(i).set_fmu_state(&saved.components[i]) {
                    return Err(self.component_refused(function, i, e));
                }
            }
        } else {
            // Another instance's state: taken up from its serialized form.
            let Some(bytes) = &saved.bytes else {
                return Err(self.error(&format!(
                    "{function}: the FMU state is another instance's, and a component cannot serialize its state to carry it over"
                )));
            };
            for (i, b) in bytes.iter().enumerate() {
                let r = self.sim.instance_mut(i).deserialize_fmu_state(b);
                let slot = match r {
                    Ok(slot) => slot,
                    Err(e) => return Err(self.component_refused(function, i, e)),
                };
                let set = self.sim.instance_mut(i).set_fmu_state(&slot);
                let _ = self.sim.instance_mut(i).free_fmu_state(slot);
                if let Err(e) = set {
                    return Err(self.component_refused(function, i, e));
                }
            }
        }
        self.time = saved.time;
        self.state = saved.state;
        self.dirty = saved.dirty;
        self.last_successful = saved.last_successful;
        self.stop_time = saved.stop_time;
        Ok(fmi2OK)
    }

    pub(crate) fn free_fmu_state(&mut self, function: &str, state: *mut *mut c_void) -> Outcome {
        self.check(Call::FmuState, function)?;
        let p = read(state).unwrap_or(std::ptr::null_mut());
        if p.is_null() {
            return Ok(fmi2OK);
        }
        let saved = self.saved(p, function)?;
        {
            let mut live = states();
            live.retain(|s| *s != p as usize);
            if live.is_empty() {
                // No heap block left behind when the library is unloaded (valgrind).
                *live = Vec::new();
            }
        }
        // SAFETY: a live state (checked by `saved`), just taken out of STATES: freed once, here.
        let saved = unsafe { Box::from_raw(saved as *mut Saved) };
        if saved.owner == self.id {
            self.free.push(saved.components);
        }
        put(state, std::ptr::null_mut());
        Ok(fmi2OK)
    }

    pub(crate) fn serialized_size(&mut self, function: &str, state: *mut c_void, size: *mut usize) -> Outcome {
        self.check(Call::FmuState, function)?;
        self.can_serialize(function)?;
        let saved = self.saved(state, function)?;
        if size.is_null() {
            return Err(self.error(&format!("{function}: size is NULL")));
        }
        let bytes = serialize(self, saved, function)?;
        put(size, bytes.len());
        Ok(fmi2OK)
    }

    pub(crate) fn serialize_state(
        &mut self,
        function: &str,
        state: *mut c_void,
        bytes: *mut u8,
        size: usize,
    ) -> Outcome {
        self.check(Call::FmuState, function)?;
        self.can_serialize(function)?;
        let saved = self.saved(state, function)?;
        let data = serialize(self, saved, function)?;
        if bytes.is_null() || size < data.len() {
            return Err(self.error(&format!(
                "{function}: the buffer holds {size} bytes, the state needs {} (the serialized size)",
                data.len()
            )));
        }
        slice_mut(bytes, data.len()).copy_from_slice(&data);
        Ok(fmi2OK)
    }

    pub(crate) fn deserialize_state(
        &mut self,
        function: &str,
        bytes: *const u8,
        size: usize,
        state: *mut *mut c_void,
    ) -> Outcome {
        self.check(Call::FmuState, function)?;
        self.can_serialize(function)?;
        if state.is_null() || (bytes.is_null() && size > 0) {
            return Err(self.error(&format!("{function}: NULL pointer")));
        }
        let data = slice(bytes, size);
        let parsed = parse_state(self, data).map_err(|e| self.error(&format!("{function}: {e}; nothing changed")))?;
        let mut components = Vec::with_capacity(parsed.parts.len());
        for (i, part) in parsed.parts.iter().enumerate() {
            match self.sim.instance_mut(i).deserialize_fmu_state(part) {
                Ok(s) => components.push(s),
                Err(e) => return Err(self.component_refused(function, i, e)),
            }
        }
        let saved = Saved {
            time: parsed.time,
            state: parsed.state,
            dirty: parsed.dirty,
            last_successful: parsed.last_successful,
            stop_time: parsed.stop_time,
            ..self.saved_now(components, Some(parsed.parts))
        };
        hand_out(state, saved)
    }
}

/// `saved` as a new FMU state of the container, kept in the list of live states and written to
/// the caller's `state`.
fn hand_out(state: *mut *mut c_void, saved: Saved) -> Outcome {
    let p = Box::into_raw(Box::new(saved));
    states().push(p as usize);
    put(state, p as *mut c_void);
    Ok(fmi2OK)
}

/// A serialized container state: this magic, the container's GUID, time, last successful time,
/// mode, the stop time (a flag and the value), then each component's serialized state with its length.
pub(crate) const MAGIC: &[u8; 8] = b"RFMUCNT2";

pub(crate) fn serialize(me: &Container, saved: &Saved, function: &str) -> Result<Vec<u8>, Status> {
    let Some(parts) = &saved.bytes else {
        return Err(me.error(&format!("{function}: a component cannot serialize its FMU state")));
    };
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    let guid = me.spec.guid.as_bytes();
    out.extend_from_slice(&(guid.len() as u32).to_le_bytes());
    out.extend_from_slice(guid);
    out.extend_from_slice(&saved.time.to_le_bytes());
    out.extend_from_slice(&saved.last_successful.to_le_bytes());
    out.push(saved.state as u8);
    out.push(u8::from(saved.dirty));
    out.push(u8::from(saved.stop_time.is_some()));
    out.extend_from_slice(&saved.stop_time.unwrap_or(0.0).to_le_bytes());
    out.extend_from_slice(&(parts.len() as u32).to_le_bytes());
    for part in parts {
        out.extend_from_slice(&(part.len() as u64).to_le_bytes());
        out.extend_from_slice(part);
    }
    Ok(out)
}

/// A serialized container state read back (the components' parts not yet checked: each
/// component checks its own).
pub(crate) struct Parsed {
    pub(crate) time: f64,
    pub(crate) last_successful: f64,
    pub(crate) stop_time: Option<f64>,
    pub(crate) state: State,
    pub(crate) dirty: bool,
    pub(crate) parts: Vec<Vec<u8>>,
}

pub(crate) fn parse_state(me: &Container, data: &[u8]) -> Result<Parsed, String> {
    let mut at = 0usize;
    let mut take = |n: usize| -> Result<&[u8], String> {
        let end = at.checked_add(n).ok_or("a length past the end")?;
        let s = data
            .get(at..end)
            .ok_or_else(|| format!("the state is {} bytes long, it names {end}", data.len()))?;
        at = end;
        Ok(s)
    };
    if take(8)? != MAGIC {
        return Err("not a serialized container state (its first bytes)".into());
    }
    let n = u32::from_le_bytes(take(4)?.try_into().expect("4")) as usize;
    let guid = take(n)?;
    if guid != me.spec.guid.as_bytes() {
        return Err(format!(
            "a state of the container '{}', not of this one ({})",
            String::from_utf8_lossy(guid),
            me.spec.guid
        ));
    }
    let time = f64::from_le_bytes(take(8)?.try_into().expect("8"));
    let last_successful = f64::from_le_bytes(take(8)?.try_into().expect("8"));
    let code = take(1)?[0];
    let state = [
        State::Instantiated,
        State::InitializationMode,
        State::StepComplete,
        State::StepFailed,
        State::Terminated,
        State::Error,
    ]
    .into_iter()
    .find(|s| *s as u8 == code)
    .ok_or_else(|| format!("mode code {code} is not one of a container"))?;
    let dirty = match take(1)?[0] {
        0 => false,
        1 => true,
        x => return Err(format!("flag {x} is not 0 or 1")),
    };
    let has_stop = match take(1)?[0] {
        0 => false,
        1 => true,
        x => return Err(format!("flag {x} is not 0 or 1")),
    };
    let stop = f64::from_le_bytes(take(8)?.try_into().expect("8"));
    let stop_time = has_stop.then_some(stop);
    let count = u32::from_le_bytes(take(4)?.try_into().expect("4")) as usize;
    if count != me.sim.len() {
        return Err(format!(
            "the state has {count} components, the container {}",
            me.sim.len()
        ));
    }
    let mut parts = Vec::with_capacity(count);
    for _ in 0..count {
        let len = u64::from_le_bytes(take(8)?.try_into().expect("8"));
        let len = usize::try_from(len).map_err(|_| format!("a component's length {len}"))?;
        parts.push(take(len)?.to_vec());
    }
    if at != data.len() {
        return Err(format!("{} bytes after the state", data.len() - at));
    }
    if !time.is_finite() || !last_successful.is_finite() || !stop.is_finite() {
        return Err(format!(
            "time {time}, last successful time {last_successful}, stop time {stop}"
        ));
    }
    Ok(Parsed {
        time,
        last_successful,
        stop_time,
        state,
        dirty,
        parts,
    })
}
