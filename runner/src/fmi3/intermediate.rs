//! Intermediate update (FMI 3.0.2, Co-Simulation, Intermediate Update Mode): an instance made
//! with the intermediateUpdate callback and the variables it is to give there
//! (requiredIntermediateVariables). Inside fmi3DoStep the FMU calls the callback at its internal
//! points; where it allows reading (intermediateVariableGetAllowed) the runner reads those
//! Float64 variables (fmi3GetFloat64 inside the callback): a sample of the component between two
//! communication points. `rustfmu-runner run --record-intermediate-values` records them as rows
//! of their own, as fmusim's option of the same name does for one FMU
//! (`../shared/independent/bin/fmusim`). The runner never asks for an early return there
//! (earlyReturnRequested false): its steps end at the times its system agrees on.

use super::{Env, Fmi2Error, Fmi3Import, Instance3, check};
use rustfmu::fmi3::abi::*;

/// What the intermediateUpdate callback reads (kept in the instance's [`Env`]).
pub(super) struct Samples {
    /// The instance (null until fmi3InstantiateCoSimulation returned).
    c: fmi3Instance,
    get_float64: super::Get<f64>,
    vrs: Vec<fmi3ValueReference>,
    /// (intermediateUpdateTime, the values of `vrs`) of each callback that allowed reading.
    rows: Vec<(f64, Vec<f64>)>,
    /// The first failure of a read in the callback.
    error: Option<String>,
}

/// The intermediateUpdate callback of an instance made by
/// [`Fmi3Import::instantiate_cs_intermediate`].
unsafe extern "C" fn intermediate_update(
    env: fmi3InstanceEnvironment,
    time: fmi3Float64,
    _set_requested: fmi3Boolean,
    get_allowed: fmi3Boolean,
    _step_finished: fmi3Boolean,
    _can_return_early: fmi3Boolean,
    early_return_requested: *mut fmi3Boolean,
    _early_return_time: *mut fmi3Float64,
) {
    let _ = std::panic::catch_unwind(|| {
        if !early_return_requested.is_null() {
            // SAFETY: the FMU passes a pointer to its fmi3Boolean (checked non-null).
            unsafe { *early_return_requested = false };
        }
        if env.is_null() || !get_allowed {
            return;
        }
        // SAFETY: `env` is the Env this instance was given; it outlives the instance.
        let env = unsafe { &*(env as *const Env) };
        let Ok(mut slot) = env.samples.try_borrow_mut() else {
            return;
        };
        let Some(s) = slot.as_mut() else {
            return;
        };
        if s.c.is_null() {
            return;
        }
        let mut x = vec![0.0; s.vrs.len()];
        // SAFETY: a live instance in Intermediate Update Mode, which allows reading; both arrays
        // hold vrs.len() elements, passed as nValueReferences and nValues.
        match check(unsafe { (s.get_float64)(s.c, s.vrs.as_ptr(), s.vrs.len(), x.as_mut_ptr(), x.len()) }) {
            Ok(()) => s.rows.push((time, x)),
            Err(e) => {
                s.error.get_or_insert(format!(
                    "fmi3GetFloat64 of value references {:?} in the intermediateUpdate callback at t = {time}: {e}",
                    s.vrs
                ));
            }
        }
    });
}

impl Fmi3Import {
    /// fmi3InstantiateCoSimulation(name, ...) with the intermediateUpdate callback and `vrs`
    /// (Float64 variables with intermediateUpdate="true") as the requiredIntermediateVariables;
    /// eventModeUsed and earlyReturnAllowed as `events` says (`--event-mode`), else as
    /// [`Fmi3Import::instantiate_cs`].
    pub fn instantiate_cs_intermediate(&self, name: &str, vrs: &[u32], events: bool) -> Result<Instance3, String> {
        if events && self.library.api.events.is_none() {
            return Err("its binary lacks the Event Mode functions".into());
        }
        let get_float64 = self.library.api.get_float64;
        let samples = Samples {
            c: std::ptr::null_mut(),
            get_float64,
            vrs: vrs.to_vec(),
            rows: Vec::new(),
            error: None,
        };
        let event_mode = events || self.clocks.is_some();
        let inst = self.instantiate_with(
            name,
            false,
            false,
            event_mode,
            events,
            Some((vrs, Some(intermediate_update), samples)),
        )?;
        Ok(inst)
    }
}

impl Instance3 {
    /// The samples the intermediateUpdate callback took since the last call (time order), or
    /// the first read that failed there.
    pub fn take_intermediate(&mut self) -> Result<Vec<(f64, Vec<f64>)>, Fmi2Error> {
        let mut slot = self.env.samples.borrow_mut();
        let Some(s) = slot.as_mut() else {
            return Ok(Vec::new());
        };
        if let Some(e) = s.error.take() {
            s.rows.clear();
            return Err(Fmi2Error::Importer(e));
        }
        Ok(std::mem::take(&mut s.rows))
    }

    /// The instance pointer the callback reads with, once fmi3InstantiateCoSimulation returned.
    pub(super) fn arm_intermediate(&mut self) {
        let c = self.c;
        if let Some(s) = self.env.samples.borrow_mut().as_mut() {
            s.c = c;
        }
    }
}
