//! FMI 3.0 Scheduled Execution (FMI 3.0.2, chapter 5): an instance made with
//! fmi3InstantiateScheduledExecution, whose time advances only through the activations of its
//! model partitions. Each input clock is a partition; at a tick of the clock the importer sets
//! the partition's inputs, calls fmi3ActivateModelPartition(clock, tick time) and reads its
//! outputs. The ticks are planned as for a co-simulation instance's input clocks (`clocks.rs`:
//! constant, fixed, calculated and tunable clocks from their intervals and shifts, countdown
//! and changing ones from the interval read when the FMU says it is known, triggered ones by a
//! clock connection); `ClockState::event_mode` is here the round of one time's activations,
//! opened by the first clock that ticks and closed by [`Instance3::settle`].
//!
//! From inside the FMU's clockUpdate callback (Clock Update Mode: once it returns, the FMU's
//! output clocks are inactive again) the runner reads the output clocks (fmi3GetClock) and the
//! intervals of the countdown, changing and tunable clocks (fmi3GetIntervalDecimal); after the
//! activation returns, the output clocks that ticked tick for the clock connections at that time,
//! and the intervals plan the next ticks. A countdown clock given the interval 0 ticks at the
//! same time, after the partition that set it. Clocked variables of output clocks are not read
//! in the callback (none of the FMUs tried has them).
//!
//! Preemption: the runner has one thread; the partitions due at one time run one after the
//! other in the order of their clocks' `priority` (0 first; equal priorities in the order of the
//! description), each to its end, so no partition is ever preempted, and the lockPreemption /
//! unlockPreemption callbacks the runner gives have nothing to lock.

use super::clocks::Interval;
use super::{Env, Fmi2Error, Fmi3Import, Instance3, check, log_message};
use rustfmu::fmi3::abi::*;
use std::ffi::{CString, c_void};
use std::sync::Arc;

type GetClock = unsafe extern "C" fn(fmi3Instance, *const fmi3ValueReference, usize, *mut fmi3Clock) -> fmi3Status;
type GetInterval = unsafe extern "C" fn(
    fmi3Instance,
    *const fmi3ValueReference,
    usize,
    *mut fmi3Float64,
    *mut fmi3IntervalQualifier,
) -> fmi3Status;

/// What the clockUpdate callback needs and reads (kept in the instance's [`Env`]).
pub(super) struct Updates {
    /// The instance (null until fmi3InstantiateScheduledExecution returned).
    c: fmi3Instance,
    get_clock: GetClock,
    get_interval: GetInterval,
    /// The output clocks; the countdown, changing and tunable input clocks.
    outputs: Vec<fmi3ValueReference>,
    intervals: Vec<fmi3ValueReference>,
    /// Read in the callbacks since the last activation: the output clocks that ticked, the
    /// intervals (clock, interval, qualifier), the first failure.
    ticked: Vec<fmi3ValueReference>,
    changed: Vec<(fmi3ValueReference, f64, i32)>,
    error: Option<String>,
}

impl Updates {
    /// In Clock Update Mode: the output clocks and intervals read.
    fn read(&mut self) {
        for &vr in &self.outputs {
            let mut on = false;
            // SAFETY: a live instance in Clock Update Mode; one value reference, one value.
            match check(unsafe { (self.get_clock)(self.c, &vr, 1, &mut on) }) {
                Ok(()) if on => self.ticked.push(vr),
                Ok(()) => {}
                Err(e) => {
                    self.error
                        .get_or_insert(format!("fmi3GetClock({vr}) in the clockUpdate callback: {e}"));
                }
            }
        }
        for &vr in &self.intervals {
            let (mut h, mut q) = (0.0, 0 as fmi3IntervalQualifier);
            // SAFETY: as above, one interval and one qualifier.
            match check(unsafe { (self.get_interval)(self.c, &vr, 1, &mut h, &mut q) }) {
                Ok(()) => self.changed.push((vr, h, q as i32)),
                Err(e) => {
                    self.error
                        .get_or_insert(format!("fmi3GetIntervalDecimal({vr}) in the clockUpdate callback: {e}"));
                }
            }
        }
    }
}

/// The clockUpdate callback: an output clock ticks or an interval is known; read now.
unsafe extern "C" fn clock_update(env: fmi3InstanceEnvironment) {
    let _ = std::panic::catch_unwind(|| {
        if env.is_null() {
            return;
        }
        // SAFETY: `env` is the Env this instance was given, alive until after fmi3FreeInstance;
        // the callback runs on the thread that called fmi3ActivateModelPartition.
        let env = unsafe { &*(env as *const Env) };
        if let Ok(mut slot) = env.updates.try_borrow_mut()
            && let Some(u) = slot.as_mut()
            && !u.c.is_null()
        {
            u.read();
        }
    });
}

/// lockPreemption / unlockPreemption: one thread runs every partition (see the module).
unsafe extern "C" fn no_preemption() {}

impl Fmi3Import {
    /// Whether its binary exports fmi3InstantiateScheduledExecution and fmi3ActivateModelPartition.
    pub fn has_scheduled_execution(&self) -> bool {
        self.library.api.scheduled.is_some()
    }

    /// fmi3InstantiateScheduledExecution(name, ...) with the runner's logger, clockUpdate and
    /// preemption callbacks; its input clocks' partitions activated by the runner.
    pub fn instantiate_scheduled(&self, name: &str) -> Result<Instance3, String> {
        let (instantiate, _) = self
            .library
            .api
            .scheduled
            .ok_or("its binary lacks fmi3InstantiateScheduledExecution or fmi3ActivateModelPartition")?;
        if self.library.api.events.is_none() {
            return Err("its binary lacks fmi3GetClock or fmi3GetIntervalDecimal (or another clock function)".into());
        }
        let plan = match &self.clocks {
            Some(p) if p.inputs.iter().any(|c| c.interval != Interval::Output) => p.clone(),
            _ => return Err("it declares no input clock: no model partition to activate".into()),
        };
        let name_c = CString::new(name).map_err(|_| format!("instance name '{name}' has a NUL"))?;
        let events = self.library.api.events.as_ref().expect("checked above");
        let of = |keep: fn(Interval) -> bool| -> Vec<u32> {
            plan.inputs.iter().filter(|c| keep(c.interval)).map(|c| c.vr).collect()
        };
        let env = Box::new(Env {
            instance: name_c.clone(),
            updates: std::cell::RefCell::new(Some(Updates {
                c: std::ptr::null_mut(),
                get_clock: events.get_clock,
                get_interval: events.get_interval,
                outputs: of(|i| i == Interval::Output),
                intervals: of(|i| matches!(i, Interval::Tunable | Interval::Aperiodic)),
                ticked: Vec::new(),
                changed: Vec::new(),
                error: None,
            })),
            samples: Default::default(),
        });
        // SAFETY: valid C strings; the environment outlives the instance (dropped after
        // fmi3FreeInstance); the callbacks have the signatures of fmi3FunctionTypes.h.
        let c = unsafe {
            instantiate(
                name_c.as_ptr(),
                self.token.as_ptr(),
                self.resource_path.as_ptr(),
                false,
                false,
                &*env as *const Env as *mut c_void,
                Some(log_message),
                Some(clock_update),
                Some(no_preemption),
                Some(no_preemption),
            )
        };
        if c.is_null() {
            return Err("fmi3InstantiateScheduledExecution returned NULL".into());
        }
        if let Some(u) = env.updates.borrow_mut().as_mut() {
            u.c = c;
        }
        let mut inst = self.instance(c, env, Some(Arc::clone(&plan)));
        inst.state_mut().scheduled = true;
        Ok(inst)
    }
}

impl Instance3 {
    /// The clocks `due` tick at `t`: their partitions wait for [`Instance3::activate_pending`].
    pub(super) fn arm(&mut self, due: &[usize], t: f64) {
        let state = self.state_mut();
        for &i in due {
            state.active[i] = true;
            state.pending[i] = true;
        }
        state.advance(due, t);
        state.event_mode = true;
    }

    /// At `t`, once the inputs are set: fmi3ActivateModelPartition of every clock that ticks and
    /// is not activated yet, highest priority first, each followed by what its clockUpdate
    /// callback announced; nothing for an instance not in Scheduled Execution. Whether a
    /// partition was activated.
    pub fn activate_pending(&mut self, t: f64) -> Result<bool, Fmi2Error> {
        if !self.clocks.as_ref().is_some_and(|s| s.scheduled && s.event_mode) {
            return Ok(false);
        }
        let mut any = false;
        let plan = Arc::clone(&self.state_mut().plan);
        let (_, activate) = self
            .library
            .api
            .scheduled
            .expect("instantiated for Scheduled Execution");
        for _ in 0..1000 {
            let state = self.state_mut();
            let Some(i) = (0..plan.inputs.len())
                .filter(|&i| state.pending[i])
                .min_by_key(|&i| (plan.inputs[i].priority.unwrap_or(u32::MAX), i))
            else {
                return Ok(any);
            };
            state.pending[i] = false;
            any = true;
            let c = &plan.inputs[i];
            // SAFETY: a live instance in Clock Activation Mode; an input clock of its description.
            check(unsafe { activate(self.c, c.vr, t) })
                .map_err(|e| Fmi2Error::Importer(format!("fmi3ActivateModelPartition({}, {t}): {e}", c.name)))?;
            self.clock_updates(t)?;
            // Read again what the partition computed.
            self.state_mut().fresh.clear();
        }
        Err(Fmi2Error::Importer(format!(
            "1000 partitions activated at t = {t} s without the time advancing (a countdown clock of interval 0 set again at every tick)"
        )))
    }

    /// After an activation at `t`: what its clockUpdate callbacks read: the output clocks that
    /// tick, the intervals of the countdown, changing and tunable clocks (a countdown of
    /// interval 0 ticks now).
    fn clock_updates(&mut self, t: f64) -> Result<(), Fmi2Error> {
        let (ticked, changed, error) = match self.env.updates.borrow_mut().as_mut() {
            Some(u) => (
                std::mem::take(&mut u.ticked),
                std::mem::take(&mut u.changed),
                u.error.take(),
            ),
            None => return Ok(()),
        };
        if let Some(e) = error {
            return Err(Fmi2Error::Importer(format!("at t = {t}: {e}")));
        }
        let plan = Arc::clone(&self.state_mut().plan);
        let index = |vr: u32| {
            plan.inputs
                .iter()
                .position(|c| c.vr == vr)
                .expect("a clock of the plan")
        };
        for vr in ticked {
            self.state_mut().active[index(vr)] = true;
        }
        for (vr, h, q) in changed {
            self.state_mut().changed(index(vr), h, q, t);
        }
        let due = self.state_mut().due(t);
        let due: Vec<usize> = due.into_iter().filter(|&i| !self.state_mut().pending[i]).collect();
        if !due.is_empty() {
            self.arm(&due, t);
        }
        Ok(())
    }

    /// The round at `t` ends: the partitions not activated yet are, the clocked outputs of
    /// every clock that ticked are held (what a read gives until their next tick).
    pub(super) fn settle_scheduled(&mut self, t: f64) -> Result<(), Fmi2Error> {
        if !self.state_mut().event_mode {
            return Ok(());
        }
        self.activate_pending(t)?;
        self.hold_outputs()?;
        let state = self.state_mut();
        state.event_mode = false;
        state.end_round();
        state.pending.iter_mut().for_each(|a| *a = false);
        Ok(())
    }

    /// The system's step from `t` of `h`: no FMU call (time advances only through
    /// activations); the round at `t` ends, and the clocks due at `t + h` tick.
    pub(super) fn step_scheduled(&mut self, t: f64, h: f64) -> Result<(), Fmi2Error> {
        self.end_event_mode(t, h)?;
        self.tick(t + h)
    }
}
