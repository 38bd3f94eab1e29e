//! FMI 3.0 clocks (section 2.2.9, and the Event Mode of Model Exchange and of Co-Simulation with
//! eventModeUsed): the suite is an importer that activates the FMU's input clocks at the ticks
//! their intervals and shifts say, sets the clocked inputs and reads the clocked variables
//! there, and checks what the standard says of it: the intervals answered as the description
//! declares them, every clock inactive again after fmi3UpdateDiscreteStates, clocked variables
//! refused between the ticks, the same values on a rerun and after an FMU state restored at a tick.

use super::*;

/// The interval qualifiers of fmi3GetIntervalDecimal (`fmi3IntervalQualifier`) the clock checks
/// (here and in Scheduled Execution) tell apart.
pub(super) const UNCHANGED: u32 = 1;
pub(super) const CHANGED: u32 = 2;

/// An input clock the suite activates: its value reference, name, and when it ticks.
struct Ticking {
    vr: u32,
    name: String,
    /// Periodic: (shift, interval); else the interval the FMU last gave (countdown, changing),
    /// from the tick it was given at; `None` for a triggered clock.
    periodic: Option<(f64, f64)>,
    aperiodic: Option<f64>,
    triggered: bool,
    /// A countdown clock: it ticks once per interval the FMU gives (a changing one keeps
    /// ticking at its last interval).
    countdown: bool,
    last: Option<f64>,
}

impl Ticking {
    fn next_after(&self, t: f64) -> Option<f64> {
        match (self.periodic, self.aperiodic, self.triggered) {
            (Some((shift, h)), _, _) => {
                let k = ((t - shift) / h).floor() + 1.0;
                Some(shift + k.max(0.0) * h)
            }
            (None, Some(h), _) => Some(self.last.unwrap_or(0.0) + h),
            // A triggered clock: every third tick of the others (any time is legal).
            _ => None,
        }
    }
    fn due(&self, t: f64) -> bool {
        let tol = 1e-9 * t.abs().max(1.0);
        match (self.periodic, self.aperiodic) {
            (Some((shift, h)), _) => {
                let k = ((t - shift) / h).round();
                k >= 0.0 && (t - (shift + k * h)).abs() <= tol
            }
            (None, Some(h)) => (t - (self.last.unwrap_or(0.0) + h)).abs() <= tol,
            _ => false,
        }
    }
}

/// fmi3GetIntervalDecimal of one clock: (status, interval, qualifier).
pub(super) fn interval(inst: &Inst, vr: u32) -> (fmi3Status, f64, u32) {
    let (mut h, mut q) = (f64::NAN, 99u32);
    inst.args(vec![("vr", crate::calllog::Val::U32s(vec![vr]))]);
    // SAFETY: a live instance; each pointer is to a live local of the length passed, or is an FMU
    // state.
    let s = inst.call("fmi3GetIntervalDecimal", |c| unsafe {
        use crate::guard::{CLOCK_RULE3 as R, fill_one};
        fill_one(
            &mut h,
            "fmi3GetIntervalDecimal (intervals)",
            "nValueReferences",
            R,
            |ph| {
                fill_one(
                    &mut q,
                    "fmi3GetIntervalDecimal (qualifiers)",
                    "nValueReferences",
                    R,
                    |pq| (inst.api().get_interval_decimal)(c, &vr, 1, ph, pq),
                )
            },
        )
    });
    (s, h, q)
}

/// fmi3GetIntervalDecimal of the periodic clock `v` in Initialization Mode, checked: fmi3OK, a
/// finite positive interval, the qualifier unchanged or changed (`when` ends that message).
pub(super) fn periodic_interval(inst: &Inst, v: &crate::fmi3::Variable, when: &str) -> (f64, u32) {
    let id = &inst.fmu.id;
    let (s, h, q) = interval(inst, v.vr);
    assert_eq!(
        s,
        fmi3OK,
        "{id}: fmi3GetIntervalDecimal of '{}' in Initialization Mode: {}",
        v.name,
        inst.log_text()
    );
    assert!(h.is_finite() && h > 0.0, "{id}: the interval of '{}' is {h}", v.name);
    assert!(
        q == UNCHANGED || q == CHANGED,
        "{id}: '{}': qualifier {q} for a periodic clock{when}",
        v.name
    );
    (h, q)
}

/// fmi3GetShiftDecimal of the periodic clock `v`, checked: fmi3OK, finite, not negative.
pub(super) fn periodic_shift(inst: &Inst, v: &crate::fmi3::Variable) -> f64 {
    let id = &inst.fmu.id;
    let mut shift = f64::NAN;
    inst.args(vec![("vr", crate::calllog::Val::U32s(vec![v.vr]))]);
    // SAFETY: a live instance; each pointer is to a live local of the length passed, or is an FMU
    // state.
    let s = inst.call("fmi3GetShiftDecimal", |cc| unsafe {
        crate::guard::fill_one(
            &mut shift,
            "fmi3GetShiftDecimal",
            "nValueReferences",
            crate::guard::CLOCK_RULE3,
            |p| (inst.api().get_shift_decimal)(cc, &v.vr, 1, p),
        )
    });
    assert_eq!(
        s,
        fmi3OK,
        "{id}: fmi3GetShiftDecimal of '{}': {}",
        v.name,
        inst.log_text()
    );
    assert!(
        shift.is_finite() && shift >= 0.0,
        "{id}: the shift of '{}' is {shift}",
        v.name
    );
    shift
}

/// The clocks to tick, their intervals read in Initialization Mode as the standard says.
fn clocks(inst: &Inst) -> Vec<Ticking> {
    let id = &inst.fmu.id;
    let mut out = vec![];
    for v in inst.fmu.md.variables.iter().filter(|v| v.ty == Type::Clock) {
        let Some(c) = &v.clock else { continue };
        if v.causality == Causality::Local {
            limitation(format!(
                "local clock '{}': the FMU's own, not the importer's to see",
                v.name
            ));
            continue;
        }
        if v.causality != Causality::Input {
            // Output clocks: asked for at every event (in `run`).
            continue;
        }
        let iv = c.interval_variability.as_str();
        let mut t = Ticking {
            vr: v.vr,
            name: v.name.clone(),
            periodic: None,
            aperiodic: None,
            triggered: iv == "triggered",
            countdown: iv == "countdown",
            last: None,
        };
        if matches!(iv, "constant" | "fixed" | "tunable") {
            let (h, q) = periodic_interval(inst, v, "");
            if let Some(d) = c.interval_decimal
                && iv == "constant"
            {
                assert_eq!(
                    (h, q),
                    (d, UNCHANGED),
                    "{id}: a constant clock's interval is its intervalDecimal, unchanged"
                );
            }
            let shift = periodic_shift(inst, v);
            t.periodic = Some((shift, h));
        }
        out.push(t);
    }
    out
}

/// An FMU state taken at a tick: its bytes, the time, each clock's last tick and the interval
/// the FMU last gave an aperiodic one (what the importer knows of its schedule then), the
/// tick's number.
type TickState = (Vec<u8>, f64, Vec<(Option<f64>, Option<f64>)>, usize);

/// One run of `ticks` ticks: the clocked values read at each tick (bit patterns). `snapshot_at`:
/// take an FMU state after that tick; `restore`: start from that state instead.
// Over ~150 lines: one run against one instance, whose schedule, time and values are this
// function's locals from the first tick to the snapshot.
fn run(
    fmu: &Fmu3,
    me: bool,
    ticks: usize,
    snapshot_at: Option<usize>,
    restore: Option<&TickState>,
) -> (Vec<Vec<u64>>, Option<TickState>) {
    let id = &fmu.id;
    let mut inst = if me {
        Inst::me(fmu)
    } else {
        Inst::try_new_with(fmu, false, "cs-clocks", true).unwrap_or_else(|e| panic!("{id}: {e}"))
    };
    let api = inst.api();
    assert_eq!(
        inst.enter_init(0.0),
        fmi3OK,
        "{id}: fmi3EnterInitializationMode: {}",
        inst.log_text()
    );
    let mut clocks = clocks(&inst);
    assert_eq!(
        inst.unary("fmi3ExitInitializationMode", api.exit_initialization_mode),
        fmi3OK,
        "{id}: {}",
        inst.log_text()
    );
    let mut first = 0;
    let mut snap = None;
    if let Some((bytes, t, lasts, k)) = restore {
        assert_eq!(
            inst.restore(bytes),
            fmi3OK,
            "{id}: fmi3SetFMUState at a tick: {}",
            inst.log_text()
        );
        inst.time = *t;
        for (c, (l, h)) in clocks.iter_mut().zip(lasts) {
            (c.last, c.aperiodic) = (*l, *h);
        }
        first = k + 1;
    }
    let mut seen = vec![];
    let mut t = inst.time;
    for k in first..ticks {
        if k > 0 {
            // The next tick of any clock, then there in Event Mode.
            let next = clocks
                .iter()
                .filter_map(|c| c.next_after(t))
                .fold(f64::INFINITY, f64::min);
            let next = if next.is_finite() { next } else { t + fmu.step_size() };
            if me {
                assert_eq!(
                    inst.unary("fmi3EnterContinuousTimeMode", api.enter_continuous_time_mode),
                    fmi3OK
                );
                while inst.time < next - 1e-12 {
                    let h = fmu.step_size().min(next - inst.time);
                    euler_step(&mut inst, h);
                }
                inst.time = next;
                inst.args(vec![("time", crate::calllog::Val::F64(next))]);
                // SAFETY: a live instance; each pointer is to a live local of the length passed, or
                // is an FMU state.
                assert_eq!(inst.call("fmi3SetTime", |c| unsafe { (api.set_time)(c, next) }), fmi3OK);
            } else {
                assert_eq!(
                    inst.unary("fmi3EnterStepMode", api.enter_step_mode),
                    fmi3OK,
                    "{id}: {}",
                    inst.log_text()
                );
                while inst.time < next - 1e-12 {
                    let h = next - inst.time;
                    let (s, flags, last) = inst.do_step(h);
                    assert_eq!(s, fmi3OK, "{id}: fmi3DoStep to the tick at {next}: {}", inst.log_text());
                    if flags[2] == 1 {
                        inst.time = last;
                    }
                    if flags[0] == 1 && inst.time < next - 1e-12 {
                        assert_eq!(inst.unary("fmi3EnterEventMode", api.enter_event_mode), fmi3OK);
                        inst.event_iteration();
                        assert_eq!(inst.unary("fmi3EnterStepMode", api.enter_step_mode), fmi3OK);
                    }
                }
                inst.time = next;
            }
            assert_eq!(
                inst.unary("fmi3EnterEventMode", api.enter_event_mode),
                fmi3OK,
                "{id}: {}",
                inst.log_text()
            );
            t = next;
        }
        // The clocks due now (a triggered one every third tick).
        let due: Vec<usize> = (0..clocks.len())
            .filter(|i| clocks[*i].due(t) || (clocks[*i].triggered && k % 3 == 1))
            .collect();
        for &i in &due {
            let vr = clocks[i].vr;
            inst.args(vec![
                ("vr", crate::calllog::Val::U32s(vec![vr])),
                ("values", crate::calllog::Val::I64s(vec![1])),
            ]);
            assert_eq!(
                // SAFETY: a live instance; each pointer is to a live local of the length passed, or
                // is an FMU state.
                inst.call("fmi3SetClock", |c| unsafe { (api.set_clock)(c, &vr, 1, &true) }),
                fmi3OK,
                "{id}: fmi3SetClock('{}') at its tick t = {t}: {}",
                clocks[i].name,
                inst.log_text()
            );
        }
        let active: Vec<u32> = due.iter().map(|i| clocks[*i].vr).collect();
        let clocked = |v: &&md_reader::fmi3::Variable| {
            v.clocks.iter().any(|c| active.contains(c))
                && v.fixed_count().is_some()
                && !matches!(v.ty, Type::String | Type::Binary)
        };
        // The clocked inputs of the active clocks: a value that changes from tick to tick.
        for v in fmu
            .md
            .variables
            .iter()
            .filter(clocked)
            .filter(|v| v.causality == Causality::Input && v.ty == Type::Float64 && !v.array)
        {
            let x = 0.01 * ((k % 7) as f64 + 1.0) * if v.vr % 2 == 0 { 1.0 } else { -1.0 };
            assert_eq!(
                inst.set_f64(&[v.vr], &[x]),
                fmi3OK,
                "{id}: setting clocked input '{}' at its tick: {}",
                v.name,
                inst.log_text()
            );
        }
        // Every variable of the active clocks, readable now.
        let mut values = vec![];
        for v in fmu.md.variables.iter().filter(clocked) {
            let (s, bytes) = inst.get_raw(v);
            assert_eq!(
                s,
                fmi3OK,
                "{id}: reading clocked '{}' at a tick of its clock (t = {t}): {}",
                v.name,
                inst.log_text()
            );
            values.extend(bytes);
        }
        // The output clocks: whether each ticks at this event, and then what it clocks.
        for oc in fmu
            .md
            .variables
            .iter()
            .filter(|v| v.ty == Type::Clock && v.causality == Causality::Output)
        {
            let mut on = 7u8;
            inst.args(vec![("vr", crate::calllog::Val::U32s(vec![oc.vr]))]);
            // SAFETY: a live instance; each pointer is to a live local of the length passed, or is
            // an FMU state.
            let s = inst.call("fmi3GetClock", |c| unsafe {
                crate::guard::fill_one(&mut on, "fmi3GetClock", "nValues", crate::guard::CLOCK_RULE3, |p| {
                    (api.get_clock)(c, &oc.vr, 1, p)
                })
            });
            assert!(
                s == fmi3OK && on <= 1,
                "{id}: fmi3GetClock of output clock '{}' at t = {t}: status {s}, value {on}: {}",
                oc.name,
                inst.log_text()
            );
            values.push(on);
            if on == 1 {
                for v in fmu.md.variables.iter().filter(|v| {
                    v.clocks.contains(&oc.vr)
                        && v.fixed_count().is_some()
                        && !matches!(v.ty, Type::String | Type::Binary)
                }) {
                    let (s, bytes) = inst.get_raw(v);
                    assert_eq!(
                        s,
                        fmi3OK,
                        "{id}: reading '{}' where its output clock '{}' ticks (t = {t}): {}",
                        v.name,
                        oc.name,
                        inst.log_text()
                    );
                    values.extend(bytes);
                }
            }
        }
        seen.push(
            values
                .chunks(8)
                .map(|c| {
                    let mut b = [0u8; 8];
                    b[..c.len()].copy_from_slice(c);
                    u64::from_le_bytes(b)
                })
                .collect(),
        );
        inst.event_iteration();
        // Every clock inactive after the update (FMI 3.0, 2.2.9); the aperiodic ones' next interval.
        for i in &due {
            let vr = clocks[*i].vr;
            let mut on = 7u8;
            inst.args(vec![("vr", crate::calllog::Val::U32s(vec![vr]))]);
            // SAFETY: a live instance; each pointer is to a live local of the length passed, or is
            // an FMU state.
            let s = inst.call("fmi3GetClock", |c| unsafe {
                crate::guard::fill_one(&mut on, "fmi3GetClock", "nValues", crate::guard::CLOCK_RULE3, |p| {
                    (api.get_clock)(c, &vr, 1, p)
                })
            });
            assert!(
                s == fmi3OK && on == 0,
                "{id}: '{}' after fmi3UpdateDiscreteStates: status {s}, active {on} (expected inactive)",
                clocks[*i].name
            );
            clocks[*i].last = Some(t);
            if clocks[*i].countdown {
                // Ticked: the next tick waits for a new interval.
                clocks[*i].aperiodic = None;
            }
        }
        for c in clocks.iter_mut().filter(|c| c.periodic.is_none() && !c.triggered) {
            let (s, h, q) = interval(&inst, c.vr);
            assert_eq!(
                s,
                fmi3OK,
                "{id}: fmi3GetIntervalDecimal of '{}' at t = {t}: {}",
                c.name,
                inst.log_text()
            );
            if q == CHANGED {
                assert!(h.is_finite() && h > 0.0, "{id}: '{}' gave the interval {h}", c.name);
                c.aperiodic = Some(h);
                c.last = Some(t);
            }
        }
        if snapshot_at == Some(k) {
            snap = Some((
                inst.snapshot(),
                t,
                clocks.iter().map(|c| (c.last, c.aperiodic)).collect(),
                k,
            ));
        }
    }
    (seen, snap)
}

pub fn fmi3_clocks_tick_where_their_intervals_say_and_clocked_variables_are_read_at_the_ticks(fmu: &Fmu3) {
    let id = &fmu.id;
    if !fmu.has_clocks() {
        skip_not_declared("<Clock> variables");
    }
    let ticks = 12;
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) {
            continue;
        }
        let which = if me {
            "Model Exchange"
        } else {
            "Co-Simulation (eventModeUsed)"
        };
        let (a, _) = run(fmu, me, ticks, None, None);
        let (b, snap) = run(fmu, me, ticks, fmu.can_snapshot(me).then_some(ticks / 2), None);
        assert_eq!(
            a, b,
            "{id}: {which}: two runs read different clocked values at the ticks"
        );
        if let Some(snap) = snap {
            let (c, _) = run(fmu, me, ticks, None, Some(&snap));
            assert_eq!(
                &a[ticks / 2 + 1..],
                &c[..],
                "{id}: {which}: after an FMU state restored at a tick, other clocked values"
            );
            info(format!(
                "{which}: an FMU state taken at tick {} and restored continues bit-identically",
                ticks / 2
            ));
        }
        info(format!(
            "{which}: {ticks} ticks; the clocked values read at each, identical on a rerun; every clock inactive after fmi3UpdateDiscreteStates"
        ));
        // Between the ticks a clocked variable is not readable (FMI 3.0, 2.2.9).
        if let Some(v) =
            fmu.md.variables.iter().find(|v| {
                !v.clocks.is_empty() && v.fixed_count().is_some() && !matches!(v.ty, Type::String | Type::Binary)
            })
        {
            let mut inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
            inst.initialize();
            inst.step(fmu.step_size());
            let (s, _) = inst.get_raw(v);
            assert_eq!(
                s, fmi3Error,
                "{id}: {which}: reading clocked '{}' between the ticks of its clocks: expected fmi3Error",
                v.name
            );
            info(format!("{which}: reading clocked '{}' between ticks refused", v.name));
        }
    }
}
