//! Time-based input clocks of an FMI 3.0 co-simulation instance, scheduled by the runner: the
//! instance runs with eventModeUsed = true; its clocks tick at communication points, where it is
//! in Event Mode; its clocked Float64 variables are set and read while one of their clocks ticks
//! and held between the ticks (FMI 3.0.2: Clocks; Co-Simulation's Event Mode).
//!
//! The order of a communication point t with a tick (the one of the tests' own fmpy scheduler,
//! `examples/cosim/master.py`): the step that reaches t ends, fmi3EnterEventMode,
//! fmi3SetClock(the clocks due); the master propagates the connections (clocked inputs set,
//! clocked outputs read) and records; at the next fmi3DoStep the instance first calls
//! fmi3UpdateDiscreteStates until no new discrete states are needed, then fmi3EnterStepMode.
//! After fmi3ExitInitializationMode the instance is in Event Mode and the same sequence runs at
//! the start time. The state machine lives in the instance, so a system's order, its isolated
//! children and its model of a communication point are unchanged, and an instance without
//! clocks costs one test of an `Option` a call.

use md_reader::Causality;
use md_reader::fmi3 as d3;
use std::collections::HashMap;

/// How a clock's ticks are known (its `intervalVariability`, FMI 3.0.2, the Clock element).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interval {
    /// `constant`: interval and shift from the description.
    Constant,
    /// `fixed`, `calculated`: read once, in Initialization Mode (fmi3GetIntervalDecimal,
    /// fmi3GetShiftDecimal).
    Fixed,
    /// `tunable`: as fixed, and read again after each Event Mode (a changed interval counts from
    /// the last tick).
    Tunable,
    /// `changing`, `countdown`: aperiodic; after each Event Mode, an interval the FMU says is
    /// changed is the time from then to the next tick.
    Aperiodic,
    /// `triggered` input clock: ticks when the clock connected to it ticks (a clock connection
    /// of the system), never by itself.
    Triggered,
    /// An output clock: the FMU ticks it (fmi3GetClock in Event Mode says when).
    Output,
}

impl Interval {
    /// Whether the runner plans its ticks from intervals (a time-based input clock).
    pub fn time_based(self) -> bool {
        !matches!(self, Interval::Triggered | Interval::Output)
    }
}

/// One input clock the runner ticks.
#[derive(Debug, Clone)]
pub struct ClockDecl {
    pub name: String,
    pub vr: u32,
    pub interval: Interval,
    /// `intervalDecimal`, `shiftDecimal` of the description (a constant clock's).
    pub declared: (Option<f64>, Option<f64>),
    /// `priority` (Scheduled Execution: the partitions due at one time run in its order, 0 first).
    pub priority: Option<u32>,
}

/// The clocks of an FMU: its input clocks (time-based ones the runner schedules, triggered ones
/// a clock connection ticks) and its output clocks (`inputs` holds them all, despite its name),
/// and its clocked variables.
#[derive(Debug, Clone, Default)]
pub struct ClockPlan {
    pub inputs: Vec<ClockDecl>,
    /// value reference -> the indices (in `inputs`) of its clocks.
    pub clocked: HashMap<u32, Vec<usize>>,
    /// The clocked Float64 scalars (read and set as Real ones; the others through the typed calls).
    pub reals: Vec<u32>,
    /// The clocked outputs of the typed calls (other types, arrays of a fixed size): value
    /// reference and an empty buffer of its type and size.
    pub typed_outputs: Vec<(u32, crate::values::Values)>,
}

impl ClockPlan {
    /// The clock `name` (its index in `inputs`).
    pub fn clock(&self, name: &str) -> Option<usize> {
        self.inputs.iter().position(|c| c.name == name)
    }

    /// Whether the system must step to its ticks: a clock whose ticks no fixed grid can meet
    /// (aperiodic), or one that ticks by events (triggered, output).
    pub fn has_events(&self) -> bool {
        self.inputs
            .iter()
            .any(|c| matches!(c.interval, Interval::Aperiodic | Interval::Triggered | Interval::Output))
    }
}

/// The clocks of `d` (input clocks of every `intervalVariability`, output clocks), or None when
/// it has none (it then runs without event mode, as before).
pub fn plan(d: &d3::ModelDescription) -> Option<ClockPlan> {
    let mut inputs = Vec::new();
    for v in &d.variables {
        let Some(attrs) = v
            .clock
            .as_ref()
            .filter(|_| v.ty == d3::Type::Clock && matches!(v.causality, Causality::Input | Causality::Output))
        else {
            continue;
        };
        let interval = match attrs.interval_variability.as_str() {
            _ if v.causality == Causality::Output => Interval::Output,
            "constant" => Interval::Constant,
            "fixed" | "calculated" => Interval::Fixed,
            "tunable" => Interval::Tunable,
            "changing" | "countdown" => Interval::Aperiodic,
            "triggered" => Interval::Triggered,
            _ => continue,
        };
        inputs.push(ClockDecl {
            name: v.name.clone(),
            vr: v.vr,
            interval,
            declared: (attrs.interval_decimal, attrs.shift_decimal),
            priority: attrs.priority,
        });
    }
    if inputs.is_empty() {
        return None;
    }
    Some(ClockPlan {
        inputs,
        clocked: HashMap::new(),
        reals: Vec::new(),
        typed_outputs: Vec::new(),
    })
}

/// Whether the clocked variable `v` is one the runner sets and reads: every clock of it one of
/// `plan`; its entry in `plan.clocked` made (and in `plan.reals` for a Float64 scalar).
pub fn admit(plan: &mut ClockPlan, v: &d3::Variable) -> bool {
    let idx: Option<Vec<usize>> = v
        .clocks
        .iter()
        .map(|c| plan.inputs.iter().position(|k| k.vr == *c))
        .collect();
    match idx {
        Some(idx) if !idx.is_empty() => {
            plan.clocked.insert(v.vr, idx);
            if is_real(v) {
                plan.reals.push(v.vr);
            } else if v.causality == Causality::Output {
                let fixed: Option<usize> = v
                    .dimensions
                    .iter()
                    .map(|d| match d {
                        d3::Dimension::Fixed(n) => usize::try_from(*n).ok(),
                        d3::Dimension::Parameter(_) => None,
                    })
                    .product();
                if let Some(buf) = fixed.and_then(|n| crate::values::Values::zeros(v.ty, n)) {
                    plan.typed_outputs.push((v.vr, buf));
                }
            }
            true
        }
        _ => false,
    }
}

/// Whether `v` is read and set as a Real (a Float64 scalar).
pub fn is_real(v: &d3::Variable) -> bool {
    v.ty == d3::Type::Float64 && !v.array && v.dimensions.is_empty()
}

/// The run-time state of an instance's clocks (see the module).
#[derive(Debug, Clone)]
pub struct ClockState {
    pub plan: std::sync::Arc<ClockPlan>,
    /// Each clock's next tick (None: not known), its interval, its last tick.
    pub next: Vec<Option<f64>>,
    pub interval: Vec<f64>,
    pub last: Vec<Option<f64>>,
    /// In Event Mode (after fmi3ExitInitializationMode, at a tick, at an event fmi3DoStep reports).
    pub event_mode: bool,
    /// Its output clocks read in this Event Mode ([`Instance3::poll_output_clocks`]).
    pub polled: bool,
    /// Its tick evaluated in this round (output clocks or a clocked variable read): a clock set
    /// now begins a second round ([`Instance3::trigger`]).
    pub evaluated: bool,
    /// The clocked variables read in this round (a read may empty a Binary: FMI-LS-BUS Tx_Data).
    pub fresh: std::collections::HashSet<u32>,
    /// Instantiated with earlyReturnAllowed; where its last step returned early.
    pub early_allowed: bool,
    pub early_at: Option<f64>,
    /// Which clocks tick now (all in Initialization Mode, where clocked variables are free).
    pub active: Vec<bool>,
    pub initializing: bool,
    /// A Scheduled Execution instance (`fmi3/scheduled.rs`): "Event Mode" is the round of a
    /// time's activations, a clock that ticks is activated, not set.
    pub scheduled: bool,
    /// Scheduled Execution: the clocks that tick now whose partitions are not activated yet.
    pub pending: Vec<bool>,
    /// The last value set or read of each clocked variable: what a read between ticks gives.
    pub held: HashMap<u32, f64>,
    /// The same for the clocked variables of the typed calls (every type, arrays whole).
    pub held_typed: HashMap<u32, crate::values::Values>,
    /// Scratch for the unclocked part of a call.
    pub vrs: Vec<u32>,
    pub vals: Vec<f64>,
}

impl ClockState {
    /// A round of Event Mode ended: no clock ticks any more, and nothing is polled, evaluated or
    /// fresh for the next one.
    pub(super) fn end_round(&mut self) {
        self.active.iter_mut().for_each(|a| *a = false);
        self.polled = false;
        self.evaluated = false;
        self.fresh.clear();
    }

    pub fn new(plan: std::sync::Arc<ClockPlan>) -> ClockState {
        let n = plan.inputs.len();
        ClockState {
            plan,
            next: vec![None; n],
            interval: vec![0.0; n],
            last: vec![None; n],
            event_mode: false,
            polled: false,
            evaluated: false,
            fresh: Default::default(),
            early_allowed: false,
            early_at: None,
            active: vec![false; n],
            initializing: false,
            scheduled: false,
            pending: vec![false; n],
            held: HashMap::new(),
            held_typed: HashMap::new(),
            vrs: Vec::new(),
            vals: Vec::new(),
        }
    }

    /// Back to the state of a fresh instance (fmi3Reset).
    pub fn reset(&mut self) {
        let (plan, early, scheduled) = (self.plan.clone(), self.early_allowed, self.scheduled);
        *self = ClockState::new(plan);
        self.early_allowed = early;
        self.scheduled = scheduled;
    }

    /// Whether the variable `vr` may be set or read now (not clocked, or one of its clocks ticks).
    pub fn free(&self, vr: u32) -> bool {
        self.initializing
            || match self.plan.clocked.get(&vr) {
                None => true,
                Some(idx) => idx.iter().any(|&i| self.active[i]),
            }
    }

    /// Whether every clocked variable among `vrs` may be set or read now.
    pub fn all_free(&self, vrs: &[u32]) -> bool {
        vrs.iter().all(|v| self.free(*v))
    }

    /// The clocks whose tick is at `t` (within a relative 1e-9 of the time: ticks computed from
    /// intervals, communication points from steps).
    pub fn due(&self, t: f64) -> Vec<usize> {
        (0..self.next.len())
            .filter(|&i| self.next[i].is_some_and(|n| (n - t).abs() <= close(t)))
            .collect()
    }

    /// The first tick before `end` (beyond the rounding of [`ClockState::due`]): (clock, time).
    pub fn inside(&self, end: f64) -> Option<(usize, f64)> {
        (0..self.next.len())
            .filter_map(|i| self.next[i].map(|n| (i, n)))
            .find(|&(_, n)| n < end - close(end))
    }

    /// After the clocks `due` ticked at `t`: the next tick of each periodic one.
    pub fn advance(&mut self, due: &[usize], t: f64) {
        for &i in due {
            self.last[i] = Some(t);
            self.next[i] = match self.plan.inputs[i].interval {
                Interval::Aperiodic | Interval::Triggered | Interval::Output => None,
                _ => Some(t + self.interval[i]),
            };
        }
    }

    /// An interval read after an Event Mode at `t` (fmi3GetIntervalDecimal's qualifier: 2 =
    /// fmi3IntervalChanged).
    pub fn changed(&mut self, i: usize, interval: f64, qualifier: i32, t: f64) {
        if qualifier != 2 {
            return;
        }
        self.interval[i] = interval;
        self.next[i] = match self.plan.inputs[i].interval {
            Interval::Tunable => Some(self.last[i].unwrap_or(t) + interval),
            Interval::Aperiodic => Some(t + interval),
            _ => self.next[i],
        };
    }
}

/// The tolerance of a tick's time at `t`.
fn close(t: f64) -> f64 {
    1e-9 * t.abs().max(1.0)
}

use super::{Fmi2Error, Instance3, check};
use rustfmu::fmi3::abi::*;

impl Instance3 {
    fn events(&self) -> &super::EventApi {
        self.library
            .api
            .events
            .as_ref()
            .expect("checked by Fmi3Import::with_clocks")
    }

    pub(super) fn state_mut(&mut self) -> &mut ClockState {
        self.state()
    }

    /// Where its last step returned early, not taken.
    pub fn early_return(&self) -> Option<f64> {
        self.clocks.as_ref().and_then(|s| s.early_at)
    }

    /// Where its last step returned early (taken: None until the next early return).
    pub fn take_early_return(&mut self) -> Option<f64> {
        self.clocks.as_mut().and_then(|s| s.early_at.take())
    }

    /// Whether the importer keeps clocks for it (input clocks it ticks, or Event Mode).
    pub fn has_clock_state(&self) -> bool {
        self.clocks.is_some()
    }

    /// The importer's side of its clocks now (ticks planned, Event Mode, held values), kept with
    /// an FMU state to take a step back ([`Instance3::restore_clocks`]).
    pub fn clock_snapshot(&self) -> Option<ClockState> {
        self.clocks.as_deref().cloned()
    }

    /// Its clocks as [`Instance3::clock_snapshot`] kept them, with fmi3SetFMUState of the FMU
    /// state taken then.
    pub fn restore_clocks(&mut self, snapshot: &ClockState) {
        if let Some(c) = &mut self.clocks {
            c.as_mut().clone_from(snapshot);
        }
    }

    fn state(&mut self) -> &mut ClockState {
        self.clocks.as_mut().expect("an instance with clocks")
    }

    /// In Initialization Mode: the clocked outputs' values (what a read gives until the first
    /// tick), each clock's interval and shift; then fmi3ExitInitializationMode, which leaves the
    /// instance in Event Mode (FMI 3.0.2: with eventModeUsed), and the clocks due at the
    /// start time tick.
    #[cold]
    #[inline(never)]
    pub(super) fn exit_initialization_clocked(&mut self) -> Result<(), Fmi2Error> {
        let start = self.experiment.1;
        let plan = self.state().plan.clone();
        let vrs: Vec<u32> = plan.reals.clone();
        let mut values = vec![0.0; vrs.len()];
        if !vrs.is_empty() {
            self.get_float64(&vrs, &mut values)?;
        }
        self.state()
            .held
            .extend(vrs.iter().copied().zip(values.iter().copied()));
        for (i, c) in plan.inputs.iter().enumerate() {
            let (interval, shift) = match c.interval {
                Interval::Triggered | Interval::Output => continue,
                Interval::Constant => match c.declared {
                    (Some(h), s) => (Some(h), s.unwrap_or(0.0)),
                    (None, _) => {
                        return Err(Fmi2Error::Importer(format!(
                            "clock '{}' is constant but declares no intervalDecimal",
                            c.name
                        )));
                    }
                },
                Interval::Fixed | Interval::Tunable | Interval::Aperiodic => {
                    let (mut h, mut q, mut s) = (0.0, 0 as fmi3IntervalQualifier, 0.0);
                    let f = self.events().get_interval;
                    // SAFETY: a live instance; one value reference, one interval, one qualifier.
                    check(unsafe { f(self.c, &c.vr, 1, &mut h, &mut q) }).map_err(|e| {
                        Fmi2Error::Importer(format!("fmi3GetIntervalDecimal of clock '{}': {e}", c.name))
                    })?;
                    if c.interval != Interval::Aperiodic {
                        let f = self.events().get_shift;
                        // SAFETY: as above, one shift.
                        check(unsafe { f(self.c, &c.vr, 1, &mut s) }).map_err(|e| {
                            Fmi2Error::Importer(format!("fmi3GetShiftDecimal of clock '{}': {e}", c.name))
                        })?;
                    }
                    // fmi3IntervalNotYetKnown (0): an aperiodic clock with no tick planned yet.
                    if q == 0 { (None, 0.0) } else { (Some(h), s) }
                }
            };
            let least = if c.interval == Interval::Aperiodic {
                0.0
            } else {
                f64::MIN_POSITIVE
            };
            if let Some(h) = interval
                && !(h >= least && h.is_finite() && shift >= 0.0 && shift.is_finite())
            {
                return Err(Fmi2Error::Importer(format!(
                    "clock '{}': interval {h} s, shift {shift} s: the interval must be a positive number (>= 0 for a countdown), the shift a number >= 0",
                    c.name
                )));
            }
            let state = self.state();
            state.interval[i] = interval.unwrap_or(0.0);
            // An aperiodic clock's interval is the time from now to its tick (FMI 3.0.2,
            // fmi3GetIntervalDecimal: countdown clocks); a periodic one ticks first at its shift.
            state.next[i] = interval.map(|h| {
                if c.interval == Interval::Aperiodic {
                    start + h
                } else {
                    start + shift
                }
            });
        }
        // SAFETY: a live instance.
        check(unsafe { (self.api().exit_initialization_mode)(self.c) })?;
        let state = self.state();
        state.initializing = false;
        // Scheduled Execution: Clock Activation Mode; a round opens when a clock ticks.
        state.event_mode = !state.scheduled;
        self.tick(start)
    }

    /// At `t`, in Event Mode: fmi3SetClock of the clocks due (they tick until the Event Mode ends).
    pub(super) fn tick(&mut self, t: f64) -> Result<(), Fmi2Error> {
        let due = self.state().due(t);
        if due.is_empty() {
            return Ok(());
        }
        if self.state().scheduled {
            self.arm(&due, t);
            return Ok(());
        }
        let plan = self.state().plan.clone();
        let vrs: Vec<u32> = due.iter().map(|&i| plan.inputs[i].vr).collect();
        let on = vec![true; vrs.len()];
        let f = self.events().set_clock;
        // SAFETY: a live instance in Event Mode; both arrays hold vrs.len() elements.
        check(unsafe { f(self.c, vrs.as_ptr(), vrs.len(), on.as_ptr()) }).map_err(|e| {
            let names: Vec<&str> = due.iter().map(|&i| plan.inputs[i].name.as_str()).collect();
            Fmi2Error::Importer(format!("fmi3SetClock({}) at t = {t}: {e}", names.join(", ")))
        })?;
        let state = self.state();
        for &i in &due {
            state.active[i] = true;
        }
        state.advance(&due, t);
        Ok(())
    }

    /// Before the step from `t` of `h`: an Event Mode ends (fmi3UpdateDiscreteStates until the
    /// FMU needs no more, the intervals of tunable and aperiodic clocks read again,
    /// fmi3EnterStepMode); a tick inside the step is refused.
    #[cold]
    #[inline(never)]
    pub(super) fn end_event_mode(&mut self, t: f64, h: f64) -> Result<(), Fmi2Error> {
        self.settle(t)?;
        if let Some((i, at)) = self.state().inside(t + h) {
            let name = self.state().plan.inputs[i].name.clone();
            return Err(Fmi2Error::Importer(format!(
                "clock '{name}' ticks at t = {at}, inside the communication step from {t} to {}: the runner ticks clocks at communication points; choose a step that divides the clock's interval and shift",
                t + h
            )));
        }
        Ok(())
    }

    /// At `t`, an Event Mode ends (fmi3UpdateDiscreteStates until the FMU needs no more, the
    /// intervals of tunable and aperiodic clocks read again, fmi3EnterStepMode); nothing
    /// outside Event Mode.
    pub fn settle(&mut self, t: f64) -> Result<(), Fmi2Error> {
        if self.clocks.is_none() {
            return Ok(());
        }
        if self.state().scheduled {
            return self.settle_scheduled(t);
        }
        if self.state().event_mode {
            self.poll_output_clocks(t)?;
            self.update_round(t)?;
            let plan = self.state().plan.clone();
            for (i, c) in plan.inputs.iter().enumerate() {
                if matches!(c.interval, Interval::Tunable | Interval::Aperiodic) {
                    let (mut h, mut q) = (0.0, 0 as fmi3IntervalQualifier);
                    let f = self.events().get_interval;
                    // SAFETY: a live instance in Event Mode; one value each.
                    check(unsafe { f(self.c, &c.vr, 1, &mut h, &mut q) }).map_err(|e| {
                        Fmi2Error::Importer(format!("fmi3GetIntervalDecimal of clock '{}': {e}", c.name))
                    })?;
                    self.state().changed(i, h, q as i32, t);
                }
            }
            let f = self.events().enter_step_mode;
            // SAFETY: a live instance in Event Mode.
            check(unsafe { f(self.c) })?;
            let state = self.state();
            state.event_mode = false;
            state.end_round();
        }
        Ok(())
    }

    /// Before an Event Mode ends: the clocked outputs whose clocks tick are read, so that what a
    /// read gives until their next tick (a record, a connection) is the value of this tick.
    pub(super) fn hold_outputs(&mut self) -> Result<(), Fmi2Error> {
        let plan = self.state().plan.clone();
        let vrs: Vec<u32> = plan
            .reals
            .iter()
            .copied()
            .filter(|v| self.state().free(*v) && !self.state().fresh.contains(v))
            .collect();
        if !vrs.is_empty() {
            let mut x = vec![0.0; vrs.len()];
            self.get_float64(&vrs, &mut x)?;
            self.state().held.extend(vrs.iter().copied().zip(x));
        }
        for (vr, buf) in &plan.typed_outputs {
            if self.state().free(*vr) && !self.state().fresh.contains(vr) {
                let mut out = buf.clone();
                self.get_typed(&[*vr], &mut out)?;
            }
        }
        Ok(())
    }

    /// The tick of this Event Mode ends: its clocked outputs held, fmi3UpdateDiscreteStates
    /// until the FMU needs no more; its clocks then tick no more (a clock set after this starts
    /// another round of the same Event Mode, FMI 3.0.2: super-dense time).
    fn update_round(&mut self, t: f64) -> Result<(), Fmi2Error> {
        self.hold_outputs()?;
        let f = self.events().update_discrete_states;
        for _ in 0..1000 {
            let (status, super::Discrete { update, terminate, .. }) = self.update_discrete_states(f);
            check(status).map_err(|e| Fmi2Error::Importer(format!("fmi3UpdateDiscreteStates at t = {t}: {e}")))?;
            if terminate {
                // FMI 3.0.2 3.2.1 (fmi3UpdateDiscreteStates): the FMU asks to end the simulation.
                return Err(Fmi2Error::Terminate(t));
            }
            if !update {
                break;
            }
        }
        self.state().end_round();
        Ok(())
    }

    /// The next tick of its time-based clocks (None: none planned, or no clocks).
    pub fn next_tick(&self) -> Option<f64> {
        let state = self.clocks.as_ref()?;
        state.next.iter().flatten().copied().reduce(f64::min)
    }

    /// Whether its clock `vr` ticks now (an input clock set, an output clock the FMU ticks).
    pub fn clock_active(&self, vr: u32) -> bool {
        self.clocks
            .as_ref()
            .is_some_and(|s| s.event_mode && s.plan.inputs.iter().zip(&s.active).any(|(c, a)| c.vr == vr && *a))
    }

    /// At `t`: the clocks due tick (Event Mode entered for them): a countdown of interval 0, or
    /// a tick the system stepped to without this instance's step ending there.
    pub fn tick_now(&mut self, t: f64) -> Result<(), Fmi2Error> {
        if self.clocks.is_none() || self.state().due(t).is_empty() {
            return Ok(());
        }
        self.enter_event(t)?;
        self.tick(t)
    }

    /// The input clock `vr` ticks at `t`, because the clock connected to it ticks (Event Mode
    /// entered for it where the instance is in Step Mode); then its output clocks read.
    pub fn trigger(&mut self, vr: u32, t: f64) -> Result<(), Fmi2Error> {
        let Some(i) = self
            .clocks
            .as_ref()
            .and_then(|s| s.plan.inputs.iter().position(|c| c.vr == vr))
        else {
            return Err(Fmi2Error::Importer(format!(
                "value reference {vr} is no clock of the FMU"
            )));
        };
        if self.state().scheduled {
            self.arm(&[i], t);
            return Ok(());
        }
        self.enter_event(t)?;
        if self.state().evaluated {
            // Its tick was evaluated (its output clocks read): the new clock ticks in a second
            // round of this Event Mode, after the first ends (its outputs held).
            self.update_round(t)?;
        }
        let f = self.events().set_clock;
        // SAFETY: a live instance in Event Mode; one value reference, one value.
        check(unsafe { f(self.c, &vr, 1, &true) }).map_err(|e| {
            let name = &self.clocks.as_ref().expect("clocks").plan.inputs[i].name;
            Fmi2Error::Importer(format!("fmi3SetClock({name}) at t = {t}: {e}"))
        })?;
        self.state().active[i] = true;
        Ok(())
    }

    /// fmi3EnterEventMode at `t` unless in Event Mode.
    fn enter_event(&mut self, t: f64) -> Result<(), Fmi2Error> {
        if self.state().scheduled {
            self.state().event_mode = true;
            return Ok(());
        }
        if !self.state().event_mode {
            let f = self.events().enter_event_mode;
            // SAFETY: a live instance in Step Mode.
            check(unsafe { f(self.c) })
                .map_err(|e| Fmi2Error::Importer(format!("fmi3EnterEventMode at t = {t}: {e}")))?;
            self.state().event_mode = true;
        }
        Ok(())
    }

    /// In Event Mode, once its input clocks are all set (the system asks it after the clock
    /// connections into it ticked): fmi3GetClock of its output clocks, once an Event Mode; those
    /// that tick are active until the Event Mode ends (FMI 3.0.2, fmi3GetClock: an output
    /// clock's tick is reported once). Asking earlier would evaluate the tick before a triggered
    /// input clock is set, which the FMU may refuse.
    pub fn poll_output_clocks(&mut self, t: f64) -> Result<(), Fmi2Error> {
        if self
            .clocks
            .as_ref()
            .is_none_or(|s| !s.event_mode || s.polled || s.scheduled)
        {
            return Ok(());
        }
        let state = self.state();
        state.polled = true;
        state.evaluated |= state.plan.inputs.iter().any(|c| c.interval == Interval::Output);
        self.output_clocks(t)
    }

    fn output_clocks(&mut self, t: f64) -> Result<(), Fmi2Error> {
        let plan = self.state().plan.clone();
        for (i, c) in plan.inputs.iter().enumerate() {
            if c.interval != Interval::Output || self.state().active[i] {
                continue;
            }
            let mut on = false;
            let f = self.events().get_clock;
            // SAFETY: a live instance in Event Mode; one value reference, one value.
            check(unsafe { f(self.c, &c.vr, 1, &mut on) })
                .map_err(|e| Fmi2Error::Importer(format!("fmi3GetClock({}) at t = {t}: {e}", c.name)))?;
            self.state().active[i] = on;
        }
        Ok(())
    }

    /// After a step that reached `t`: Event Mode where a clock ticks at `t` or the FMU asked for
    /// it (eventHandlingNeeded), and the clocks due set.
    #[cold]
    #[inline(never)]
    pub(super) fn begin_event_mode(&mut self, t: f64, event: bool) -> Result<(), Fmi2Error> {
        if event || !self.state().due(t).is_empty() {
            self.enter_event(t)?;
            self.tick(t)?;
        }
        Ok(())
    }

    /// fmi3GetFloat64 of the variables that may be read now; the others' held values.
    #[cold]
    #[inline(never)]
    pub(super) fn get_clocked(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), Fmi2Error> {
        let state = self.clocks.as_mut().expect("an instance with clocks");
        if state.all_free(vrs) {
            self.get_float64(vrs, out)?;
            let state = self.state();
            for v in vrs.iter().filter(|v| state.plan.clocked.contains_key(v)) {
                state.evaluated = true;
                state.fresh.insert(*v);
            }
            for (vr, x) in vrs.iter().zip(out.iter()) {
                if state.plan.clocked.contains_key(vr) {
                    state.held.insert(*vr, *x);
                }
            }
            return Ok(());
        }
        let (mut v, mut x) = (std::mem::take(&mut state.vrs), std::mem::take(&mut state.vals));
        v.clear();
        v.extend(vrs.iter().copied().filter(|vr| state.free(*vr)));
        x.clear();
        x.resize(v.len(), 0.0);
        let r = if v.is_empty() {
            Ok(())
        } else {
            self.get_float64(&v, &mut x)
        };
        let state = self.state();
        let mut k = 0;
        for (vr, o) in vrs.iter().zip(out.iter_mut()) {
            if state.free(*vr) {
                *o = x[k];
                k += 1;
                if state.plan.clocked.contains_key(vr) {
                    state.held.insert(*vr, *o);
                    state.evaluated = true;
                    state.fresh.insert(*vr);
                }
            } else {
                *o = state.held.get(vr).copied().unwrap_or(0.0);
            }
        }
        (state.vrs, state.vals) = (v, x);
        r
    }

    /// fmi3SetFloat64 of the variables that may be set now; a clocked one whose clocks do not
    /// tick keeps its value until they do (the master sets it again at the tick).
    #[cold]
    #[inline(never)]
    pub(super) fn set_clocked(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), Fmi2Error> {
        let state = self.clocks.as_mut().expect("an instance with clocks");
        if state.all_free(vrs) {
            for (vr, x) in vrs.iter().zip(values) {
                if state.plan.clocked.contains_key(vr) {
                    state.held.insert(*vr, *x);
                }
            }
            return self.set_float64(vrs, values);
        }
        let (mut v, mut x) = (std::mem::take(&mut state.vrs), std::mem::take(&mut state.vals));
        v.clear();
        x.clear();
        for (vr, value) in vrs.iter().zip(values) {
            if state.free(*vr) {
                v.push(*vr);
                x.push(*value);
            }
        }
        let r = if v.is_empty() { Ok(()) } else { self.set_float64(&v, &x) };
        let state = self.state();
        (state.vrs, state.vals) = (v, x);
        r
    }
}
