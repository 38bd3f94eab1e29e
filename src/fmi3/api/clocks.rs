//! Clocks (FMI 3.0, 2.2.9): setting and reading them, their intervals and shifts.
//!
//! # Safety
//! As for [`super`]: every `unsafe fn` has the contract of the `fmi3*` function it implements.

use super::values::fmi3_type_name;
use super::*;

// Input clocks, activated by the importer in Event Mode.

const FMI3_INTERVAL_NOT_YET_KNOWN: fmi3IntervalQualifier = 0;
const FMI3_INTERVAL_UNCHANGED: fmi3IntervalQualifier = 1;
const FMI3_INTERVAL_CHANGED: fmi3IntervalQualifier = 2;

/// The Clock declared with value reference `vr`, or the refusal naming what `vr` is.
fn clock_of<M: CoSimulation>(
    inst: &Instance<M>,
    function: &str,
    vr: u32,
) -> Result<(&'static crate::description::Variable, crate::description::ClockDecl), fmi3Status> {
    match M::variable_index(vr).map(|i| &M::DESCRIPTION.variables[i]) {
        Some(v) => match v.fmi3.clock {
            Some(c) => Ok((v, c)),
            None => Err(inst.error(&format!(
                "{function}: value reference {vr} ('{}') is {}, not a Clock",
                v.name,
                fmi3_type_name(v.var_type)
            ))),
        },
        None => Err(inst.error(&format!("{function}: value reference {vr} is no variable of this FMU"))),
    }
}

/// What every clock function does first: the instance and the state check, the value
/// references (NULL, each a Clock); `body` then does the function's part with the declarations.
///
/// # Safety
/// The clock function's contract: `c` NULL or a live instance of this library for `M`; `vr`
/// NULL or `nvr` elements.
#[inline(always)]
unsafe fn clock_call<M: CoSimulation>(
    function: &'static str,
    call: Call,
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    body: impl FnOnce(
        &mut Instance<M>,
        &[(&'static crate::description::Variable, crate::description::ClockDecl)],
    ) -> fmi3Status,
) -> fmi3Status {
    with_instance(c, call, function, |inst| {
        if !M::DESCRIPTION.has_clocks() {
            return inst.error(&format!("{function}: this FMU has no clocks"));
        }
        // SAFETY: `slice` checks NULL; the contract makes `vr` hold `nvr` elements.
        let Some(vrs) = (unsafe { slice(vr, nvr) }) else {
            return inst.error(&format!(
                "{function}: valueReferences is NULL with nValueReferences = {nvr}"
            ));
        };
        let mut clocks = Vec::with_capacity(vrs.len());
        for vr in vrs {
            match clock_of(inst, function, *vr) {
                Ok(c) => clocks.push(c),
                Err(status) => return status,
            }
        }
        body(inst, &clocks)
    })
}

/// The interval of a periodic clock now: the importer's (set in Initialization Mode), the
/// declared `intervalDecimal`, or the value of the parameter that is its interval.
fn periodic_interval<M: CoSimulation>(
    inst: &Instance<M>,
    v: &crate::description::Variable,
    c: &crate::description::ClockDecl,
) -> Option<f64> {
    let set = inst
        .sim
        .model
        .clock(v.value_reference)
        .and_then(|k| k.__importer_values().0);
    set.or(c.interval).or_else(|| {
        let p = M::DESCRIPTION.by_name(c.interval_parameter)?;
        match inst.sim.model.get(p.value_reference)? {
            Value::Real(x) => Some(x),
            _ => None,
        }
    })
}

/// The shift of a periodic clock: the importer's, else the declared `shiftDecimal`.
fn periodic_shift<M: CoSimulation>(
    inst: &Instance<M>,
    v: &crate::description::Variable,
    c: &crate::description::ClockDecl,
) -> f64 {
    inst.sim
        .model
        .clock(v.value_reference)
        .and_then(|k| k.__importer_values().1)
        .unwrap_or(c.shift)
}

pub unsafe fn set_clock<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Clock,
) -> fmi3Status {
    const F: &str = "fmi3SetClock";
    // SAFETY: the arguments come with this function's contract, which is `clock_call`'s.
    unsafe {
        clock_call::<M>(F, Call::SetClock, c, vr, nvr, |inst, clocks| {
            // SAFETY: `slice` checks NULL; the contract makes `values` hold `nvr` elements.
            let Some(values) = slice(values, nvr) else {
                return inst.error(&format!("{F}: values is NULL with nValueReferences = {nvr}"));
            };
            // Every value is checked before any clock changes (all or nothing).
            for ((v, decl), active) in clocks.iter().zip(values) {
                if v.causality != crate::description::Causality::Input {
                    return inst.error(&format!(
                        "{F}: '{}' (vr {}) is an output clock: the FMU ticks it (fmi3GetClock tells); no clock changed",
                        v.name, v.value_reference
                    ));
                }
                if inst.evaluated_tick.is_some() {
                    return inst.error(&format!(
                        "{F}: '{}' (vr {}): the tick of this Event Mode was already evaluated (a clocked variable was \
                         read, or fmi3EvaluateDiscreteStates ran): set the clocks, then the clocked inputs, then read; \
                         refused, no clock changed",
                        v.name, v.value_reference
                    ));
                }
                if !*active && !decl.can_be_deactivated {
                    return inst.error(&format!(
                        "{F}: '{}' (vr {}) cannot be deactivated (canBeDeactivated = false); no clock changed",
                        v.name, v.value_reference
                    ));
                }
                if *active && decl.interval_variability.periodic() {
                    // A periodic clock ticks at start + shift + k interval only.
                    let (t, t0) = (inst.sim.time, inst.sim.start_time + periodic_shift(inst, v, decl));
                    if let Some(h) = periodic_interval(inst, v, decl).filter(|h| h.is_finite() && *h > 0.0) {
                        let k = ((t - t0) / h).round();
                        let tol = 1e-9 * t.abs().max(h).max(1.0);
                        if k < 0.0 || (t - (t0 + k * h)).abs() > tol {
                            return inst.error(&format!(
                                "{F}: '{}' (vr {}) is activated at t = {t}, but this periodic clock ticks at {t0} + k * {h} \
                                 (its shift and interval); no clock changed",
                                v.name, v.value_reference
                            ));
                        }
                    }
                }
            }
            for ((v, _), active) in clocks.iter().zip(values) {
                if let Some(k) = inst.sim.model.clock_mut(v.value_reference) {
                    k.__set_active(*active);
                }
            }
            let t = inst.sim.time;
            inst.event(|| {
                let names: Vec<String> = clocks
                    .iter()
                    .zip(values)
                    .map(|((v, _), a)| format!("{} {}", v.name, if *a { "active" } else { "inactive" }))
                    .collect();
                format!("{F}: {} at t = {t}", names.join(", "))
            });
            fmi3OK
        })
    }
}

pub unsafe fn get_clock<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Clock,
) -> fmi3Status {
    const F: &str = "fmi3GetClock";
    // SAFETY: the arguments come with this function's contract, which is `clock_call`'s.
    unsafe {
        clock_call::<M>(F, Call::GetClock, c, vr, nvr, |inst, clocks| {
            // SAFETY: `slice_mut` checks NULL; the contract makes `values` hold `nvr` writable elements.
            let Some(out) = slice_mut(values, nvr) else {
                return inst.error(&format!("{F}: values is NULL with nValueReferences = {nvr}"));
            };
            // Whether an output clock ticks at this event is the model's update's to say: it runs
            // now if it has not (its answers are those fmi3UpdateDiscreteStates then gives).
            if clocks
                .iter()
                .any(|(v, _)| v.causality == crate::description::Causality::Output)
                && let Err(status) = inst.evaluate_tick(F, true)
            {
                return status;
            }
            for ((v, _), slot) in clocks.iter().zip(out.iter_mut()) {
                *slot = inst.sim.model.clock(v.value_reference).is_some_and(|k| k.is_active());
            }
            fmi3OK
        })
    }
}

pub unsafe fn get_interval_decimal<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    intervals: *mut fmi3Float64,
    qualifiers: *mut fmi3IntervalQualifier,
) -> fmi3Status {
    use crate::description::IntervalVariability as I;
    const F: &str = "fmi3GetIntervalDecimal";
    // SAFETY: the arguments come with this function's contract, which is `clock_call`'s.
    unsafe {
        clock_call::<M>(F, Call::GetInterval, c, vr, nvr, |inst, clocks| {
            // SAFETY: `slice_mut` checks NULL; the contract makes both hold `nvr` writable elements.
            let (Some(out), Some(qs)) = (slice_mut(intervals, nvr), slice_mut(qualifiers, nvr)) else {
                return inst.error(&format!(
                    "{F}: intervals or qualifiers is NULL with nValueReferences = {nvr}"
                ));
            };
            // Checked first: a refusal reports nothing (the reports below are taken).
            for (v, decl) in clocks {
                if decl.interval_variability == I::Triggered {
                    return inst.error(&format!(
                        "{F}: '{}' (vr {}) is a triggered clock: it has no interval (it ticks when activated)",
                        v.name, v.value_reference
                    ));
                }
                if decl.interval_variability.periodic()
                    && !periodic_interval(inst, v, decl).is_some_and(|h| h.is_finite() && h > 0.0)
                {
                    return inst.error(&format!(
                        "{F}: the interval of '{}' (vr {}) is {:?}, not a finite time > 0",
                        v.name,
                        v.value_reference,
                        periodic_interval(inst, v, decl)
                    ));
                }
                let given = inst.sim.model.clock(v.value_reference).and_then(|k| k.interval());
                if decl.interval_variability.model_timed() && given.is_some_and(|h| !(h.is_finite() && h > 0.0)) {
                    return inst.error(&format!(
                        "{F}: the model gave '{}' (vr {}) the interval {:?}, not a finite time > 0",
                        v.name, v.value_reference, given
                    ));
                }
                if decl.interval_variability == I::Changing && given.is_none() {
                    return inst.error(&format!(
                        "{F}: the model has not given the interval of changing clock '{}' (vr {}) yet",
                        v.name, v.value_reference
                    ));
                }
            }
            for (((v, decl), slot), q) in clocks.iter().zip(out.iter_mut()).zip(qs.iter_mut()) {
                let vr = v.value_reference;
                let periodic = periodic_interval(inst, v, decl);
                let Some(k) = inst.sim.model.clock_mut(vr) else {
                    continue;
                };
                (*slot, *q) = match decl.interval_variability {
                    // Declared in the description (or set by the importer): nothing to report.
                    I::Constant => (decl.interval.unwrap_or(f64::NAN), FMI3_INTERVAL_UNCHANGED),
                    I::Fixed | I::Tunable if decl.interval_parameter.is_empty() => {
                        (periodic.unwrap_or(f64::NAN), FMI3_INTERVAL_UNCHANGED)
                    }
                    // The value of a parameter: "changed" the first time and after it changed.
                    I::Fixed | I::Tunable => {
                        let h = periodic.unwrap_or(f64::NAN);
                        let changed = k.__report(h);
                        (
                            h,
                            if changed {
                                FMI3_INTERVAL_CHANGED
                            } else {
                                FMI3_INTERVAL_UNCHANGED
                            },
                        )
                    }
                    I::Changing | I::Countdown => match k.__take_interval() {
                        (Some(h), true) => (h, FMI3_INTERVAL_CHANGED),
                        (Some(h), false) => (h, FMI3_INTERVAL_UNCHANGED),
                        (None, _) => (0.0, FMI3_INTERVAL_NOT_YET_KNOWN),
                    },
                    I::Triggered => (0.0, FMI3_INTERVAL_NOT_YET_KNOWN),
                };
            }
            fmi3OK
        })
    }
}

pub unsafe fn get_shift_decimal<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    shifts: *mut fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3GetShiftDecimal";
    // SAFETY: the arguments come with this function's contract, which is `clock_call`'s.
    unsafe {
        clock_call::<M>(F, Call::GetInterval, c, vr, nvr, |inst, clocks| {
            // SAFETY: `slice_mut` checks NULL; the contract makes `shifts` hold `nvr` writable elements.
            let Some(out) = slice_mut(shifts, nvr) else {
                return inst.error(&format!("{F}: shifts is NULL with nValueReferences = {nvr}"));
            };
            for (v, decl) in clocks {
                if !decl.interval_variability.periodic() {
                    return inst.error(&format!(
                        "{F}: '{}' (vr {}) is a {} clock: only periodic clocks (constant, fixed, tunable) have a shift",
                        v.name,
                        v.value_reference,
                        decl.interval_variability.text()
                    ));
                }
            }
            for ((v, decl), slot) in clocks.iter().zip(out.iter_mut()) {
                *slot = periodic_shift(inst, v, decl);
            }
            fmi3OK
        })
    }
}

/// fmi3SetIntervalDecimal (`shift` false) and fmi3SetShiftDecimal (`shift` true): for periodic
/// clocks whose description gives a default (`intervalDecimal`) that the importer may replace:
/// a fixed clock's in Initialization Mode, a tunable clock's interval also in Event Mode.
unsafe fn set_interval_or_shift<M: CoSimulation>(
    function: &'static str,
    call: Call,
    shift: bool,
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Float64,
) -> fmi3Status {
    use crate::description::IntervalVariability as I;
    // SAFETY: the arguments come with this function's contract, which is `clock_call`'s.
    unsafe {
        clock_call::<M>(function, call, c, vr, nvr, |inst, clocks| {
            // SAFETY: `slice` checks NULL; the contract makes `values` hold `nvr` elements.
            let Some(values) = slice(values, nvr) else {
                return inst.error(&format!("{function}: values is NULL with nValueReferences = {nvr}"));
            };
            let what = if shift { "shift" } else { "interval" };
            for ((v, decl), x) in clocks.iter().zip(values) {
                let settable = matches!(decl.interval_variability, I::Fixed | I::Tunable) && decl.interval.is_some();
                if !settable {
                    let why = if !decl.interval_parameter.is_empty() {
                        format!("its interval is the parameter '{}': set that", decl.interval_parameter)
                    } else {
                        format!(
                            "only fixed and tunable clocks with an intervalDecimal take one from the importer ('{}' is {})",
                            v.name,
                            decl.interval_variability.text()
                        )
                    };
                    return inst.error(&format!(
                        "{function}: '{}' (vr {}): {why}; nothing changed",
                        v.name, v.value_reference
                    ));
                }
                if matches!(inst.sim.state, State::EventMode | State::ClockActivationMode)
                    && (shift || decl.interval_variability == I::Fixed)
                {
                    return inst.error(&format!(
                        "{function}: '{}' (vr {}): a {} clock's {what} is set in Initialization Mode only; nothing changed",
                        v.name,
                        v.value_reference,
                        decl.interval_variability.text()
                    ));
                }
                let ok = if shift {
                    x.is_finite() && *x >= 0.0
                } else {
                    x.is_finite() && *x > 0.0
                };
                if !ok {
                    return inst.error(&format!(
                        "{function}: {x} for '{}' (vr {}): a {what} is a finite time {}; nothing changed",
                        v.name,
                        v.value_reference,
                        if shift { ">= 0" } else { "> 0" }
                    ));
                }
            }
            for ((v, _), x) in clocks.iter().zip(values) {
                if let Some(k) = inst.sim.model.clock_mut(v.value_reference) {
                    let (interval, s) = k.__set_by_importer();
                    *(if shift { s } else { interval }) = Some(*x);
                }
            }
            fmi3OK
        })
    }
}

pub unsafe fn set_interval_decimal<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    intervals: *const fmi3Float64,
) -> fmi3Status {
    // SAFETY: the arguments come with this function's contract, which is the callee's.
    unsafe {
        set_interval_or_shift::<M>(
            "fmi3SetIntervalDecimal",
            Call::SetInterval,
            false,
            c,
            vr,
            nvr,
            intervals,
        )
    }
}

pub unsafe fn set_shift_decimal<M: CoSimulation>(
    c: Option<&Component<M>>,
    vr: *const fmi3ValueReference,
    nvr: usize,
    shifts: *const fmi3Float64,
) -> fmi3Status {
    // SAFETY: the arguments come with this function's contract, which is the callee's.
    unsafe { set_interval_or_shift::<M>("fmi3SetShiftDecimal", Call::SetShift, true, c, vr, nvr, shifts) }
}
