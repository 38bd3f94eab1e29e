//! FMI 3.0 Scheduled Execution (chapter 5): the suite is a scheduler. It instantiates the FMU
//! with fmi3InstantiateScheduledExecution and a clockUpdate callback, reads the periodic input
//! clocks' intervals in Initialization Mode, then activates the model partitions with
//! fmi3ActivateModelPartition in time order (priority order at equal times, 0 first): the
//! periodic input clocks at their ticks, the countdown and changing clocks where an interval was
//! signalled, the triggered ones at times it chooses. From inside the clockUpdate callback (Clock
//! Update Mode) it asks fmi3GetClock of every output clock and fmi3GetIntervalDecimal of every
//! countdown or changing input clock, as the standard's importer does. Checked: the intervals as
//! the description declares them; every activation and read fmi3OK; no ticking output clock or
//! new interval left unsignalled; the refusals (fmi3ActivateModelPartition before Clock
//! Activation Mode, of an output clock, of an unknown value reference, at a time before the
//! current one; the Co-Simulation and Model Exchange functions); the same clocked values on a
//! rerun and after an FMU state restored into a new instance.

use super::clocks::{CHANGED, UNCHANGED, interval, periodic_interval, periodic_shift};
use super::*;
use crate::fmi3::{LogSink, Variable, api, c_size};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

const NOT_YET_KNOWN: u32 = 0;

/// Activations at most (a tiny interval must not make the check run forever).
const MAX_ACTIVATIONS: usize = 2000;

/// What the clockUpdate callback saw in one call (Clock Update Mode).
#[derive(Debug, Clone, Default)]
struct Update {
    /// The time of the activation it was called in; whether it was called inside one.
    time: f64,
    inside: bool,
    /// fmi3GetClock of each output clock: (vr, status, value).
    outs: Vec<(u32, fmi3Status, u8)>,
    /// The variables of each ticking output clock: (vr, status, bytes).
    values: Vec<(u32, fmi3Status, Vec<u8>)>,
    /// fmi3GetIntervalDecimal of each countdown/changing input clock: (vr, status, interval,
    /// qualifier).
    intervals: Vec<(u32, fmi3Status, f64, u32)>,
    /// A call of the callback that wrote past the array it was given (the guard's message:
    /// recorded, as a panic may not leave the callback, and failed by the check).
    overruns: Vec<String>,
}

/// What the callback of one instance needs and records.
struct Probe {
    fmu: usize,
    instance: AtomicUsize,
    inside: AtomicBool,
    now: Mutex<f64>,
    updates: Mutex<Vec<Update>>,
}

/// The probes of the live instances, by their environment (the log sink's address).
static PROBES: Mutex<Vec<(usize, Arc<Probe>)>> = Mutex::new(Vec::new());

fn probe_of(env: usize) -> Option<Arc<Probe>> {
    PROBES
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .iter()
        .find(|(e, _)| *e == env)
        .map(|(_, p)| p.clone())
}

fn output_clocks(fmu: &Fmu3) -> impl Iterator<Item = &Variable> {
    fmu.md
        .variables
        .iter()
        .filter(|v| v.ty == Type::Clock && v.causality == Causality::Output)
}

fn variability(v: &Variable) -> &str {
    v.clock.as_ref().map_or("", |c| c.interval_variability.as_str())
}

/// The input clocks whose interval the FMU gives (countdown, changing).
fn aperiodic(fmu: &Fmu3) -> impl Iterator<Item = &Variable> {
    fmu.md.variables.iter().filter(|v| {
        v.ty == Type::Clock && v.causality == Causality::Input && matches!(variability(v), "countdown" | "changing")
    })
}

/// The variables a clock clocks that the suite reads (scalars and fixed-size arrays, no String
/// or Binary).
fn clocked_by(fmu: &Fmu3, clock: u32) -> impl Iterator<Item = &Variable> {
    fmu.md.variables.iter().filter(move |v| {
        v.clocks.contains(&clock) && v.fixed_count().is_some() && !matches!(v.ty, Type::String | Type::Binary)
    })
}

/// A getter call without [`Inst::call`] (nothing here may panic: it runs in the callback).
///
/// # Safety
///
/// `c` is a live instance of `api`'s FMU.
unsafe fn get_plain(api: &api::Api, c: fmi3Instance, v: &Variable) -> (fmi3Status, Result<Vec<u8>, String>) {
    let n = v.fixed_count().unwrap_or(1) as usize;
    let mut words = crate::guard::Guarded::aligned_bytes(n * c_size(v.ty));
    let p = words.as_mut_ptr();
    let vr = &v.vr;
    // SAFETY: `c` is a live instance of `api`'s FMU (this function's contract); `words` holds `n`
    // values of any of the types, 8-byte aligned (and the guard after them).
    let s = unsafe { api.get_values(c, v.ty, vr, p, n) };
    let what = || format!("fmi3Get{:?} with nValues = {n}", v.ty);
    let bytes = words.try_values(what, crate::guard::GETTER_RULE3).map(|words| {
        words
            .iter()
            .flat_map(|w| w.to_ne_bytes())
            .take(n * c_size(v.ty))
            .collect()
    });
    (s, bytes)
}

/// The importer's fmi3ClockUpdateCallback: Clock Update Mode. Asks fmi3GetClock of every output
/// clock (and reads the variables of those that tick) and fmi3GetIntervalDecimal of every
/// countdown or changing input clock; records it all in the instance's [`Probe`].
unsafe extern "C" fn clock_update(env: fmi3InstanceEnvironment) {
    let _ = std::panic::catch_unwind(|| {
        let Some(p) = probe_of(env as usize) else {
            return;
        };
        // SAFETY: the Fmu3 of the check, alive as long as its instances (and their probes).
        let fmu = unsafe { &*(p.fmu as *const Fmu3) };
        let c = p.instance.load(Ordering::Acquire) as fmi3Instance;
        let mut u = Update {
            time: *p.now.lock().unwrap_or_else(|e| e.into_inner()),
            inside: p.inside.load(Ordering::Acquire),
            ..Update::default()
        };
        if !c.is_null() {
            use crate::guard::{CLOCK_RULE3, Guarded};
            let api = &fmu.api;
            // A guard overwritten is recorded (the check fails with it), not panicked on here.
            fn checked<T>(r: Result<Vec<T>, String>, u: &mut Update) -> Vec<T> {
                r.unwrap_or_else(|e| {
                    u.overruns.push(e);
                    vec![]
                })
            }
            for oc in output_clocks(fmu) {
                let mut on = Guarded::new(1, 7u8);
                // SAFETY: a live instance, one value reference, one value (and the guard after it).
                let s = unsafe { (api.get_clock)(c, &oc.vr, 1, on.as_mut_ptr()) };
                let on = checked(
                    on.try_values(|| "fmi3GetClock with nValues = 1".into(), CLOCK_RULE3),
                    &mut u,
                );
                let on = on.first().copied().unwrap_or(7);
                u.outs.push((oc.vr, s, on));
                if s == fmi3OK && on == 1 {
                    for v in clocked_by(fmu, oc.vr) {
                        // SAFETY: a live instance.
                        let (s, bytes) = unsafe { get_plain(api, c, v) };
                        match bytes {
                            Ok(bytes) => u.values.push((v.vr, s, bytes)),
                            Err(e) => u.overruns.push(e),
                        }
                    }
                }
            }
            for ic in aperiodic(fmu) {
                let (mut h, mut q) = (Guarded::new(1, f64::NAN), Guarded::new(1, 99u32));
                // SAFETY: a live instance, one value reference, one value each (and the guards).
                let s = unsafe { (api.get_interval_decimal)(c, &ic.vr, 1, h.as_mut_ptr(), q.as_mut_ptr()) };
                let what = |a: &'static str| move || format!("fmi3GetIntervalDecimal ({a}) with nValueReferences = 1");
                let h = checked(h.try_values(what("intervals"), CLOCK_RULE3), &mut u);
                let q = checked(q.try_values(what("qualifiers"), CLOCK_RULE3), &mut u);
                u.intervals.push((
                    ic.vr,
                    s,
                    h.first().copied().unwrap_or(f64::NAN),
                    q.first().copied().unwrap_or(99),
                ));
            }
        }
        p.updates.lock().unwrap_or_else(|e| e.into_inner()).push(u);
    });
}

/// A Scheduled Execution instance with the callback, and its probe.
struct Se<'a> {
    inst: Inst<'a>,
    probe: Arc<Probe>,
}

impl Drop for Se<'_> {
    fn drop(&mut self) {
        let env = self.inst.sink.env() as usize;
        PROBES
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .retain(|(e, _)| *e != env);
    }
}

/// fmi3InstantiateScheduledExecution with the log and clockUpdate callbacks (no preemption
/// callbacks: the suite preempts nothing); NULL as None.
fn instantiate(fmu: &Fmu3, callback: bool) -> Option<(fmi3Instance, Box<LogSink>)> {
    let sink = Box::<LogSink>::default();
    let name = CString::new("se").unwrap();
    let token = CString::new(fmu.md.token.as_str()).unwrap();
    let res = CString::new(fmu.resource_path()).unwrap();
    crate::outcome::breadcrumb("fmi3InstantiateScheduledExecution");
    // SAFETY: valid strings and callbacks; the sink outlives the instance.
    let c = unsafe {
        (fmu.api.instantiate_scheduled_execution)(
            name.as_ptr(),
            token.as_ptr(),
            res.as_ptr(),
            false,
            false,
            sink.env(),
            Some(crate::fmi3::log_message),
            if callback { Some(clock_update) } else { None },
            None,
            None,
        )
    };
    (!c.is_null()).then_some((c, sink))
}

fn se(fmu: &Fmu3) -> Se<'_> {
    let (c, sink) =
        instantiate(fmu, true).unwrap_or_else(|| panic!("{}: fmi3InstantiateScheduledExecution returned NULL", fmu.id));
    let probe = Arc::new(Probe {
        fmu: fmu as *const Fmu3 as usize,
        instance: AtomicUsize::new(c as usize),
        inside: AtomicBool::new(false),
        now: Mutex::new(0.0),
        updates: Mutex::new(vec![]),
    });
    PROBES
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .push((sink.env() as usize, probe.clone()));
    Se {
        inst: Inst::scheduled_execution(fmu, c, sink),
        probe,
    }
}

impl Se<'_> {
    fn activate(&self, vr: u32, t: f64) -> fmi3Status {
        *self.probe.now.lock().unwrap() = t;
        self.probe.inside.store(true, Ordering::Release);
        // SAFETY: a live instance; each pointer is to a live local of the length passed, or is an
        // FMU state.
        let s = self.inst.call("fmi3ActivateModelPartition", |c| unsafe {
            (self.inst.api().activate_model_partition)(c, vr, t)
        });
        self.probe.inside.store(false, Ordering::Release);
        s
    }
    fn updates(&self) -> usize {
        self.probe.updates.lock().unwrap().len()
    }
}

/// An input clock the scheduler activates.
#[derive(Debug, Clone)]
struct Input {
    vr: u32,
    name: String,
    priority: u32,
    variability: String,
    /// A periodic clock's (shift, interval), read in Initialization Mode.
    periodic: Option<(f64, f64)>,
}

/// The scheduler's own state: the pending activations (time, priority, clock) and the last
/// interval of each changing clock.
#[derive(Debug, Clone, Default)]
struct Queue {
    pending: Vec<(f64, u32, u32)>,
    last_interval: Vec<(u32, f64)>,
    done: usize,
}

impl Queue {
    fn push(&mut self, t: f64, priority: u32, vr: u32, stop: f64) {
        if t < stop - 1e-12 {
            self.pending.push((t, priority, vr));
        }
    }
    /// The earliest pending activation; the highest priority (smallest number) at equal times.
    fn pop(&mut self) -> Option<(f64, u32, u32)> {
        let i = (0..self.pending.len()).min_by(|a, b| {
            let (x, y) = (self.pending[*a], self.pending[*b]);
            x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(a.cmp(b))
        })?;
        Some(self.pending.remove(i))
    }
}

fn stop_time(fmu: &Fmu3) -> f64 {
    fmu.md
        .default_experiment
        .stop_time()
        .filter(|t| t.is_finite() && *t > 0.0)
        .unwrap_or(10.0)
}

/// Enters and exits Initialization Mode, reading the input clocks (periodic ones' intervals and
/// shifts, checked against the description) in between.
fn initialize(s: &mut Se) -> Vec<Input> {
    let inst = &mut s.inst;
    let fmu = inst.fmu;
    let id = &fmu.id;
    assert_eq!(
        inst.enter_init(0.0),
        fmi3OK,
        "{id}: fmi3EnterInitializationMode: {}",
        inst.log_text()
    );
    let mut out = vec![];
    for v in fmu
        .md
        .variables
        .iter()
        .filter(|v| v.ty == Type::Clock && v.causality == Causality::Input)
    {
        let c = v.clock.as_ref().expect("a Clock's attributes");
        let priority = c.priority.unwrap_or_else(|| {
            panic!(
                "{id}: input clock '{}' has no priority (FMI 3.0, 2.4.7.6: required for Scheduled Execution)",
                v.name
            )
        });
        let iv = c.interval_variability.as_str();
        let mut input = Input {
            vr: v.vr,
            name: v.name.clone(),
            priority,
            variability: iv.to_string(),
            periodic: None,
        };
        // A constant or fixed clock's interval and shift are in the description (intervalDecimal,
        // shiftDecimal), where an importer reads them. On another exporter's FMU the schedule takes
        // them from there and does not ask fmi3GetIntervalDecimal/fmi3GetShiftDecimal: the Reference
        // FMUs' Clocks (v0.0.41) answers fmi3Error for its constant clock, which then ends the
        // instance (fmi3Error: "the simulation must not be continued", FMI 3.0.2 §2.2.4); FMI
        // 3.0.2 §2.2.9 only allows an importer to ask ("For input Clocks it is allowed to call this
        // function"). This exporter's FMUs are asked, and their answers checked, below.
        if let Some(d) = c.interval_decimal
            && matches!(iv, "constant" | "fixed")
            && !fmu.own_state_format()
        {
            crate::outcome::limitation(
                "the intervals and shifts of constant and fixed input clocks are taken from the description, not asked of the FMU",
            );
            input.periodic = Some((c.shift_decimal.unwrap_or(0.0), d));
            out.push(input);
            continue;
        }
        if matches!(iv, "constant" | "fixed" | "tunable") {
            let (h, q) = periodic_interval(inst, v, " in Initialization Mode");
            if let Some(d) = c.interval_decimal
                && matches!(iv, "constant" | "fixed")
            {
                assert_eq!(
                    h, d,
                    "{id}: the interval of {iv} clock '{}' is not its intervalDecimal",
                    v.name
                );
            }
            if iv == "constant" {
                assert_eq!(q, UNCHANGED, "{id}: a constant clock's interval is unchanged");
            }
            let shift = periodic_shift(inst, v);
            if matches!(iv, "constant" | "fixed") {
                assert_eq!(
                    shift,
                    c.shift_decimal.unwrap_or(0.0),
                    "{id}: the shift of '{}' is not its shiftDecimal",
                    v.name
                );
            }
            input.periodic = Some((shift, h));
        }
        out.push(input);
    }
    assert_eq!(
        inst.unary("fmi3ExitInitializationMode", inst.api().exit_initialization_mode),
        fmi3OK,
        "{id}: fmi3ExitInitializationMode: {}",
        inst.log_text()
    );
    out
}

/// The first schedule: each periodic clock at its ticks, each triggered one at 0, a quarter, a
/// half and four fifths of the stop time (countdown and changing clocks wait for an interval).
fn first_schedule(inputs: &[Input], stop: f64) -> Queue {
    let mut q = Queue::default();
    for c in inputs {
        if let Some((shift, h)) = c.periodic {
            let mut k = 0u32;
            while shift + k as f64 * h < stop - 1e-12 && (k as usize) < MAX_ACTIVATIONS {
                q.push(shift + k as f64 * h, c.priority, c.vr, stop);
                k += 1;
            }
        } else if c.variability == "triggered" {
            for f in [0.0, 0.25, 0.5, 0.8] {
                q.push(f * stop, c.priority, c.vr, stop);
            }
        }
    }
    q
}

/// What one run read: per activation, the time, the clock, the clocked values and what the
/// callback saw (bit patterns).
type Trace = Vec<(u64, u32, Vec<u8>)>;
/// An FMU state after an activation: its bytes, the scheduler's queue, the activation's number.
type Snapshot = (Vec<u8>, Queue, usize);

/// One run of the schedule; `snapshot_at`: an FMU state after that activation (and the queue);
/// `restore`: continue from such a state in this new instance.
// Over ~150 lines: one run of the schedule against one instance, whose queue, time and trace are
// this function's locals from the first activation to the snapshot.
fn run(fmu: &Fmu3, snapshot_at: Option<usize>, restore: Option<&Snapshot>) -> (Trace, Option<Snapshot>, usize) {
    let id = &fmu.id;
    let stop = stop_time(fmu);
    let mut s = se(fmu);
    let inputs = initialize(&mut s);
    let mut q = first_schedule(&inputs, stop);
    if let Some((bytes, queue, _)) = restore {
        assert_eq!(
            s.inst.restore(bytes),
            fmi3OK,
            "{id}: fmi3SetFMUState of a state taken in Clock Activation Mode: {}",
            s.inst.log_text()
        );
        q = queue.clone();
    }
    let by_vr = |vr: u32| inputs.iter().find(|c| c.vr == vr).expect("an input clock");
    let mut trace = vec![];
    let mut snap = None;
    let mut callbacks = 0;
    while let Some((t, _, vr)) = q.pop() {
        assert!(
            q.done < MAX_ACTIVATIONS,
            "{id}: more than {MAX_ACTIVATIONS} activations before {stop} s"
        );
        let clock = by_vr(vr);
        // The clock's clocked Float64 inputs: a value that changes from activation to activation.
        for v in clocked_by(fmu, vr).filter(|v| v.causality == Causality::Input && v.ty == Type::Float64 && !v.array) {
            let x = 0.01 * ((q.done % 7) as f64 + 1.0);
            assert_eq!(
                s.inst.set_f64(&[v.vr], &[x]),
                fmi3OK,
                "{id}: setting clocked input '{}' before its partition: {}",
                v.name,
                s.inst.log_text()
            );
        }
        let before = s.updates();
        let st = s.activate(vr, t);
        assert_eq!(
            st,
            fmi3OK,
            "{id}: fmi3ActivateModelPartition('{}', {t}): {}",
            clock.name,
            s.inst.log_text()
        );
        s.inst.time = t;
        let mut values = vec![];
        // The clocked variables, not the clocks among them (a clock's own `clocks`: an input
        // clock is not read with fmi3GetClock, FMI 3.0.2 §2.2.9).
        for v in clocked_by(fmu, vr).filter(|v| v.ty != Type::Clock) {
            let (st, bytes) = s.inst.get_raw(v);
            assert_eq!(
                st,
                fmi3OK,
                "{id}: reading '{}' after the activation of its clock '{}' at {t}: {}",
                v.name,
                clock.name,
                s.inst.log_text()
            );
            values.extend(bytes);
        }
        // What the callback saw during this activation.
        let new: Vec<Update> = s.probe.updates.lock().unwrap()[before..].to_vec();
        callbacks += new.len();
        for u in &new {
            assert!(
                u.overruns.is_empty(),
                "{id}: in clockUpdate (activation of '{}' at {t}): {}",
                clock.name,
                u.overruns.join("; ")
            );
            assert!(
                u.inside && u.time == t,
                "{id}: clockUpdate was called outside fmi3ActivateModelPartition (activation of '{}' at {t})",
                clock.name
            );
            for (ovr, st, on) in &u.outs {
                assert!(
                    *st == fmi3OK && *on <= 1,
                    "{id}: fmi3GetClock of output clock {ovr} in Clock Update Mode (t = {t}): status {}, value {on}: {}",
                    status_name(*st),
                    s.inst.log_text()
                );
                values.push(*on);
            }
            for (v, st, bytes) in &u.values {
                assert_eq!(
                    *st,
                    fmi3OK,
                    "{id}: reading {v} (clocked by a ticking output clock) in Clock Update Mode (t = {t}): {}",
                    s.inst.log_text()
                );
                values.extend(bytes);
            }
            for (ivr, st, h, qual) in &u.intervals {
                let name = &by_vr(*ivr).name;
                assert!(
                    *st == fmi3OK && [NOT_YET_KNOWN, UNCHANGED, CHANGED].contains(qual),
                    "{id}: fmi3GetIntervalDecimal of '{name}' in Clock Update Mode (t = {t}): status {}, qualifier {qual}: {}",
                    status_name(*st),
                    s.inst.log_text()
                );
                values.extend(h.to_bits().to_le_bytes());
                values.push(*qual as u8);
                if *qual == CHANGED {
                    // 0 is an interval: the clock ticks again at this time (the C Reference
                    // FMUs' Clocks so schedules inClock3 at 4 s). See the check's verdict.
                    assert!(
                        h.is_finite() && *h >= 0.0,
                        "{id}: '{name}' was given the interval {h} at {t} (FMI 3.0.2 §2.2.9, countdown and changing \
                         aperiodic Clocks: \"T_interval,i >= 0\")"
                    );
                    let c = by_vr(*ivr);
                    if c.variability == "changing" {
                        q.pending.retain(|p| p.2 != *ivr);
                        q.last_interval.retain(|l| l.0 != *ivr);
                        q.last_interval.push((*ivr, *h));
                    }
                    q.push(t + h, c.priority, *ivr, stop);
                }
            }
        }
        // Nothing left unsignalled: a ticking output clock or a new interval seen now, in
        // Clock Activation Mode, without a callback in this activation.
        let api = s.inst.api();
        for oc in output_clocks(fmu) {
            let mut on = 7u8;
            let st = s
                .inst
                // SAFETY: a live instance; each pointer is to a live local of the length passed, or
                // is an FMU state.
                .call("fmi3GetClock", |c| unsafe {
                    crate::guard::fill_one(&mut on, "fmi3GetClock", "nValues", crate::guard::CLOCK_RULE3, |p| {
                        (api.get_clock)(c, &oc.vr, 1, p)
                    })
                });
            assert!(
                st == fmi3OK && on <= 1,
                "{id}: fmi3GetClock of output clock '{}' in Clock Activation Mode (t = {t}): status {}, value {on}: {}",
                oc.name,
                status_name(st),
                s.inst.log_text()
            );
            assert!(
                !(on == 1 && new.is_empty()),
                "{id}: output clock '{}' ticks after the activation of '{}' at {t}, but clockUpdate was not called",
                oc.name,
                clock.name
            );
        }
        for ic in aperiodic(fmu) {
            let (st, h, qual) = interval(&s.inst, ic.vr);
            assert_eq!(
                st,
                fmi3OK,
                "{id}: fmi3GetIntervalDecimal of '{}' in Clock Activation Mode (t = {t}): {}",
                ic.name,
                s.inst.log_text()
            );
            assert!(
                !(qual == CHANGED && new.is_empty()),
                "{id}: '{}' was given the interval {h} at {t}, but clockUpdate was not called",
                ic.name
            );
        }
        // A changing clock keeps ticking at its last interval.
        if clock.variability == "changing"
            && !q.pending.iter().any(|p| p.2 == vr)
            && let Some((_, h)) = q.last_interval.iter().find(|l| l.0 == vr)
        {
            let h = *h;
            q.push(t + h, clock.priority, vr, stop);
        }
        trace.push((t.to_bits(), vr, values));
        q.done += 1;
        if snapshot_at == Some(q.done - 1) {
            snap = Some((s.inst.snapshot(), q.clone(), q.done - 1));
        }
    }
    (trace, snap, callbacks)
}

/// A fresh instance, initialized (Clock Activation Mode), and its input clocks.
fn ready(fmu: &Fmu3) -> (Se<'_>, Vec<Input>) {
    let mut s = se(fmu);
    let inputs = initialize(&mut s);
    (s, inputs)
}

fn expect_error(s: &Se, what: &str, f: impl FnOnce(fmi3Instance) -> fmi3Status) {
    let st = s.inst.call(what, f);
    assert_eq!(
        st,
        fmi3Error,
        "{}: {what}: expected fmi3Error, got {}",
        s.inst.fmu.id,
        status_name(st)
    );
}

fn refusals(fmu: &Fmu3) -> usize {
    let id = &fmu.id;
    let api = &fmu.api;
    let first_input = fmu
        .md
        .variables
        .iter()
        .find(|v| v.ty == Type::Clock && v.causality == Causality::Input)
        .unwrap_or_else(|| panic!("{id}: <ScheduledExecution> without an input clock"));
    let vr = first_input.vr;
    let mut n = 0;
    // In Instantiated and in Initialization Mode.
    {
        let s = se(fmu);
        // SAFETY: a call the FMU must refuse here, with values and pointers to live locals.
        expect_error(&s, "fmi3ActivateModelPartition in Instantiated", |c| unsafe {
            (api.activate_model_partition)(c, vr, 0.0)
        });
        n += 1;
    }
    {
        let mut s = se(fmu);
        assert_eq!(s.inst.enter_init(0.0), fmi3OK, "{id}: {}", s.inst.log_text());
        // SAFETY: a call the FMU must refuse here, with values and pointers to live locals.
        expect_error(&s, "fmi3ActivateModelPartition in Initialization Mode", |c| unsafe {
            (api.activate_model_partition)(c, vr, 0.0)
        });
        n += 1;
    }
    // An output clock: an importer's mistake, warned where not refused. FMI 3.0.2 §5.2.1
    // (fmi3ActivateModelPartition): "The fmi3ActivateModelPartition function must not be called on
    // output Clocks of an FMU" binds the scheduler; no sentence requires the FMU to detect it (the
    // reading of the instantiation token's and the earlier activation time's verdicts).
    if let Some(oc) = output_clocks(fmu).next() {
        let (s, _) = ready(fmu);
        let what = format!("fmi3ActivateModelPartition of output clock '{}'", oc.name);
        let activate = api.activate_model_partition;
        // SAFETY: a call the FMU should refuse here, with values and pointers to live locals.
        let st = crate::outcome::on_purpose(|| s.inst.call(&what, |c| unsafe { activate(c, oc.vr, 0.0) }));
        if st == fmi3Error {
            n += 1;
        } else {
            crate::outcome::warn(format!(
                "{id}: {what} answered {}, not fmi3Error: the activation of an output clock (the scheduler's \
                 mistake, FMI 3.0.2 §5.2.1: \"The fmi3ActivateModelPartition function must not be called on \
                 output Clocks of an FMU\") is not detected",
                status_name(st)
            ));
        }
    }
    // An unknown value reference.
    {
        let (s, _) = ready(fmu);
        let unknown = fmu.md.unknown_vr();
        expect_error(
            &s,
            &format!("fmi3ActivateModelPartition of unknown value reference {unknown}"),
            // SAFETY: a call the FMU must refuse here, with values and pointers to live locals.
            |c| unsafe { (api.activate_model_partition)(c, unknown, 0.0) },
        );
        n += 1;
    }
    // A time before the current one: the schedule up to its first activation after 0, then the
    // same clock half way back.
    {
        let (s, inputs) = ready(fmu);
        let mut q = first_schedule(&inputs, stop_time(fmu));
        let mut earlier = None;
        while let Some((t, _, cvr)) = q.pop() {
            assert_eq!(
                s.activate(cvr, t),
                fmi3OK,
                "{id}: activation at {t}: {}",
                s.inst.log_text()
            );
            if t > 0.0 {
                earlier = Some((cvr, t));
                break;
            }
        }
        if let Some((cvr, t)) = earlier {
            // An importer's mistake, warned where not refused: FMI 3.0.2 §5.2.1
            // (fmi3ActivateModelPartition): "Consecutive calls to fmi3ActivateModelPartition for a
            // clockReference must have strictly monotonically increasing activationTime" binds the
            // scheduler; no sentence requires the FMU to detect an earlier one.
            let what = format!("fmi3ActivateModelPartition at {} after one at {t}", t / 2.0);
            let activate = api.activate_model_partition;
            // SAFETY: a call the FMU should refuse here, with values and pointers to live locals.
            let st = s.inst.call(&what, |c| unsafe { activate(c, cvr, t / 2.0) });
            if st == fmi3Error {
                n += 1;
            } else {
                crate::outcome::warn(format!(
                    "{id}: {what} answered {}, not fmi3Error: an activation time before the clock's last one (the \
                     scheduler's mistake, FMI 3.0.2 §5.2.1: \"must have strictly monotonically increasing \
                     activationTime\") is not detected",
                    status_name(st)
                ));
            }
        } else {
            limitation("fmi3ActivateModelPartition at an earlier time: no activation after 0 in the schedule");
        }
    }
    // The Co-Simulation and Model Exchange functions.
    {
        let (s, _) = ready(fmu);
        let (mut flags, mut last) = ([9u8; 3], f64::NAN);
        // SAFETY: a call the FMU must refuse here, with values and pointers to live locals.
        expect_error(&s, "fmi3DoStep on a Scheduled Execution instance", |c| unsafe {
            crate::guard::fill_outputs("fmi3DoStep", &mut flags, &mut last, |[a, b, c3], l| {
                (api.do_step)(c, 0.0, fmu.step_size(), true, a, b, c3, l)
            })
        });
        n += 1;
    }
    {
        let (s, _) = ready(fmu);
        // SAFETY: a call the FMU must refuse here, with values and pointers to live locals.
        expect_error(&s, "fmi3EnterEventMode on a Scheduled Execution instance", |c| unsafe {
            (api.enter_event_mode)(c)
        });
        n += 1;
    }
    n
}

/// The suite as a scheduler of the FMU's model partitions (see the module documentation).
///
/// Verdict on the intervals the FMU gives its countdown and changing input clocks
/// (fmi3GetIntervalDecimal with fmi3IntervalChanged, from inside clockUpdate): a negative or
/// non-finite interval fails, an interval of 0 is an interval (the clock ticks again at the
/// current time; the scheduler activates it next, after the partitions of higher priority).
/// FMI 3.0.2 §2.2.9, "Countdown aperiodic Clock", Restrictions: "T_interval,i >= 0, i = 1,2,3,...:
/// The time interval starting at the current Event Mode or Clock Update Mode when fmi3GetInterval
/// is called" (for a changing aperiodic Clock likewise "T_interval,i >= 0"); and of
/// fmi3IntervalChanged: "In Scheduled Execution fmi3IntervalChanged means that the corresponding
/// model partition must be scheduled or re-scheduled". Only periodic Clocks have "T_interval,i >
/// 0". Until 2026-12-07 the check failed interval 0 (the C Reference FMUs' Clocks gives inClock3
/// interval 0 at 4 s): the checker's mistake, not the FMU's.
///
/// Verdict on the refusals: an activation at a time before the clock's last one not refused is
/// warned (the scheduler's obligation, FMI 3.0.2 §5.2.1: "Consecutive calls to
/// fmi3ActivateModelPartition for a clockReference must have strictly monotonically increasing
/// activationTime"), and so is an activation of an output clock not refused (ibid.: "The
/// fmi3ActivateModelPartition function must not be called on output Clocks of an FMU", the
/// scheduler's obligation too); the others fail where not refused with fmi3Error.
pub fn fmi3_scheduled_execution_activates_the_partitions_at_their_clocks_and_signals_the_clock_updates(fmu: &Fmu3) {
    let id = &fmu.id;
    if !fmu.md.se {
        // Not offered: NULL (with a message) is the expected answer; an instance is legal too.
        if let Some((c, _sink)) = instantiate(fmu, false) {
            // SAFETY: the instance just made, freed once.
            unsafe { (fmu.api.free_instance)(c) };
        }
        skip_not_declared("<ScheduledExecution>");
    }
    let (a, _, callbacks) = run(fmu, None, None);
    assert!(!a.is_empty(), "{id}: the schedule activated nothing");
    let k = a.len() / 2;
    let can = fmu
        .md
        .se_interface
        .as_ref()
        .is_some_and(|i| i.can_get_and_set_fmu_state && i.can_serialize_fmu_state);
    let (b, snap, _) = run(fmu, can.then_some(k), None);
    assert_eq!(
        a, b,
        "{id}: two runs of the same schedule read different clocked values"
    );
    info(format!(
        "{} activations over {} s in time and priority order, the clocked values read after each and identical on a rerun; {callbacks} clockUpdate calls, each asking the output clocks and the countdown/changing intervals from inside the activation",
        a.len(),
        stop_time(fmu)
    ));
    if let Some(snap) = snap {
        let (c, _, _) = run(fmu, None, Some(&snap));
        assert_eq!(
            &a[k + 1..],
            &c[..],
            "{id}: after an FMU state taken after activation {k} and restored into a new instance, other clocked values"
        );
        info(format!(
            "an FMU state taken after activation {k} and restored into a new instance continues bit-identically"
        ));
    } else {
        limitation("FMU state: <ScheduledExecution> does not declare canGetAndSetFMUState and canSerializeFMUState");
    }
    let n = refusals(fmu);
    info(format!(
        "{n} refusals with fmi3Error, each on a new instance: fmi3ActivateModelPartition in Instantiated, in Initialization Mode, of an output clock (where refused), of an unknown value reference, at an earlier time (where refused); fmi3DoStep and fmi3EnterEventMode"
    ));
}
