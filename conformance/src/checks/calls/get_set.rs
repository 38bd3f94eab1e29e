//! Get and set: unknown value references, NULL arrays, where each variable may be set, NaN and
//! infinite values, tunable parameters between steps.

#![allow(non_upper_case_globals)] // fmi2OK etc. are the standard's names, matched on

use super::{initialized, refused};
use crate::fmi2::*;
use crate::instance::{Instance, Status, excitation, excite, run, status_name, step_size};
use crate::outcome::{convention, info};
use crate::state::{State, name};
use crate::{Fmu, Type};
use md_reader::{Causality, Variability};

/// Verdict: warned, never failed. An unknown value reference is the importer's mistake; FMI 2.0.5
/// requires no detection of it (§2.1.3: on fmi2Error "the simulation cannot be continued with this
/// FMU instance"), so an FMU that answers fmi2OK, refuses without a message or changes what its
/// getters show is warned (a wrong value reference then goes unnoticed by the user).
pub fn unknown_value_references_are_refused_with_a_message_naming_them(fmu: &Fmu) {
    let mut inst = initialized(fmu);
    for vr in [fmu.md.unknown_vr(), u32::MAX] {
        let before = inst.fingerprint();
        let n = vr.to_string();
        let s = inst.get_real(&[vr]).0;
        refused(&inst, "fmi2GetReal(unknown vr)", s, &["fmi2GetReal", &n]);
        let s = inst.get_integer(&[vr]).0;
        refused(&inst, "fmi2GetInteger(unknown vr)", s, &["fmi2GetInteger", &n]);
        let s = inst.get_boolean(&[vr]).0;
        refused(&inst, "fmi2GetBoolean(unknown vr)", s, &["fmi2GetBoolean", &n]);
        let s = inst.set_real(&[vr], &[1.0]);
        refused(&inst, "fmi2SetReal(unknown vr)", s, &["fmi2SetReal", &n]);
        let s = inst.set_integer(&[vr], &[1]);
        refused(&inst, "fmi2SetInteger(unknown vr)", s, &["fmi2SetInteger", &n]);
        let s = inst.set_boolean(&[vr], &[true]);
        refused(&inst, "fmi2SetBoolean(unknown vr)", s, &["fmi2SetBoolean", &n]);
        let s = inst.get_string(&[vr]).0;
        refused(&inst, "fmi2GetString(unknown vr)", s, &["fmi2GetString", &n]);
        let s = inst.set_string(&[vr], &["x".into()]);
        refused(&inst, "fmi2SetString(unknown vr)", s, &["fmi2SetString", &n]);
        inst.warn_if_changed(
            &before,
            fmi2Error,
            format_args!("the calls with unknown value reference {vr}"),
        );
    }
    // A known vr of another type.
    let real = fmu.md.vrs_of_type(Type::Real)[0];
    if !fmu.md.vrs_of_type(Type::Integer).contains(&real) {
        let s = inst.get_integer(&[real]).0;
        refused(
            &inst,
            "fmi2GetInteger(a Real vr)",
            s,
            &["fmi2GetInteger", &real.to_string()],
        );
    }
}

/// Verdict: nvr = 0 with NULL arrays must answer fmi2OK (a failure otherwise: the call is legal,
/// FMI 2.0.5 §2.1.7 gives the arrays nvr elements); NULL arrays with nvr > 0 are the importer's
/// mistake, which the standard leaves undefined: not refusing them, or crashing on them, is a
/// warning (a crash takes the importer down).
pub fn zero_values_with_null_arrays_are_fine_and_null_arrays_with_values_are_refused(fmu: &Fmu) {
    use crate::instance_calls::ARRAY_PROBES;
    let mut inst = initialized(fmu);
    let vr = [fmu.md.vrs_of_type(Type::Real)[0]];
    // Through the call log (Instance::array_probe), so that a failure leaves a reproducer with
    // these calls, which `cargo fmu replay` makes again.
    let empty = ARRAY_PROBES.map(|f| {
        let s = inst.array_probe(f, None, 0, false);
        // FMI 2.0.5 §2.1.7: the arrays have nvr elements; with nvr = 0 the call is legal.
        crate::calllog::standard_requires(crate::replay::Expected::OK);
        s
    });
    assert_eq!(empty, [fmi2OK; 8], "{}: nvr = 0 with NULL arrays", fmu.id);
    {
        // Each call alone is the importer's mistake (outcome::on_purpose): a crash in it is a
        // warning.
        let null_cases: Vec<(&str, Status)> = ARRAY_PROBES
            .iter()
            .flat_map(|&f| {
                [
                    (f, crate::outcome::on_purpose(|| inst.array_probe(f, None, 1, true))),
                    (
                        f,
                        crate::outcome::on_purpose(|| inst.array_probe(f, Some(&vr[..]), 1, false)),
                    ),
                ]
            })
            .collect();
        // NULL arrays with nvr > 0 are the importer's mistake (FMI 2.0.5 §2.1.7 gives the
        // arrays nvr elements): detecting them is beyond the standard, a warning otherwise.
        let log = inst.log();
        for (f, s) in null_cases {
            crate::outcome::warn_unless(s == fmi2Error, || {
                format!(
                    "{}: {f} with a NULL array and nvr = 1 answered {}, not fmi2Error (an importer's mistake not detected)",
                    fmu.id,
                    status_name(s)
                )
            });
            let messages = log
                .iter()
                .filter(|e| e.text.contains(f) && e.text.contains("NULL"))
                .count();
            if s == fmi2Error && convention(fmu, "one message naming the function and NULL per refused call") {
                crate::outcome::warn_unless(messages == 2, || {
                    format!("{}: {f}: one message per refused call expected: {log:?}", fmu.id)
                });
            }
        }
    }
    inst.time = 0.0;
    let s = inst.step(step_size(fmu));
    crate::outcome::warn_unless(s == fmi2OK, || {
        format!(
            "{}: a step after the refused NULL arrays answered {} (going on after fmi2Error is beyond FMI 2.0.5 §2.1.3)",
            fmu.id,
            status_name(s)
        )
    });
}

/// For every variable, in each state where fmi2SetXXX is allowed, the FMU accepts exactly the
/// variables the standard lets an importer set there; a refusal names the variable and leaves
/// the FMU state as it was. Covers outputs, calculated parameters, fixed parameters after
/// initialization, and tunable parameters between steps.
///
/// Verdict: refusing a set the standard allows (FMI 2.0.5 §4.2.4, the variables fmi2SetXXX may be
/// called on in each state) fails; accepting a set it does not allow, or changing the instance
/// while refusing it, is the importer's mistake undetected, a warning (the standard asks no
/// detection).
pub fn each_variable_can_be_set_exactly_where_the_standard_allows_it(fmu: &Fmu) {
    let mut failures = vec![];
    for state in [State::Instantiated, State::InitializationMode, State::StepComplete] {
        for v in fmu
            .md
            .variables
            .iter()
            // An alias is checked through the first variable of its set.
            .filter(|v| v.ty != Type::String && !crate::standard::aliases_an_earlier(&fmu.md.variables, v))
        {
            let mut inst = Instance::new(fmu);
            match state {
                State::Instantiated => {}
                State::InitializationMode => assert_eq!([inst.setup(0.0, None), inst.enter_init()], [fmi2OK; 2]),
                _ => inst.initialize(),
            }
            let before = inst.fingerprint();
            let s = match v.ty {
                Type::Real => inst.set_real(&[v.vr], &[v.start_real().unwrap_or(0.0)]),
                Type::Integer | Type::Enumeration => inst.set_integer(&[v.vr], &[v.start_integer().unwrap_or(0)]),
                Type::Boolean => inst.set_boolean(&[v.vr], &[v.start_boolean().unwrap_or(false)]),
                Type::String => unreachable!(),
            };
            let log = inst.log();
            let want = crate::standard::settable_in(v, &name(state));
            let at = format!(
                "{}: set '{}' ({} {}, initial {:?}) in {state:?}",
                fmu.id,
                v.name,
                v.causality,
                v.variability,
                crate::standard::initial(v.causality, v.variability, v.declared_initial)
            );
            if want && s != fmi2OK {
                failures.push(format!(
                    "{at}: allowed by the standard, got {}: {log:?}",
                    status_name(s)
                ));
            }
            // Setting a variable where the standard does not allow it is the importer's mistake
            // (FMI 2.0.5 §3.2.3/§4.2.4 say where fmi2SetXXX may be called on which variables; they
            // ask no detection of the FMU): a warning when it is accepted or changes the instance.
            if !want {
                if s != fmi2Error {
                    crate::outcome::warn(format!(
                        "{at}: not allowed by the standard, got {} (an importer's mistake not detected)",
                        status_name(s)
                    ));
                } else if !inst.says(&log, fmi2Error, &[&format!("'{}'", v.name)]) {
                    crate::outcome::warn(format!("{at}: the refusal does not name the variable: {log:?}"));
                }
                inst.warn_if_changed(&before, s, &at);
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Verdict: warned, never failed. FMI 2.0.5 does not forbid NaN or infinity in an fmi2Real
/// (§2.2.7 defines min/max, and leaves values outside to the FMU); setting one is the importer's
/// mistake, and refusing it is good practice (a NaN input otherwise spreads silently).
pub fn nan_and_infinite_values_are_refused_with_a_message_and_change_nothing(fmu: &Fmu) {
    for state in [State::Instantiated, State::InitializationMode, State::StepComplete] {
        let mut inst = Instance::new(fmu);
        match state {
            State::Instantiated => {}
            State::InitializationMode => assert_eq!([inst.setup(0.0, None), inst.enter_init()], [fmi2OK; 2]),
            _ => inst.initialize(),
        }
        let settable: Vec<_> = fmu
            .md
            .of_type(Type::Real)
            .filter(|v| crate::standard::settable_in(v, &name(state)))
            .collect();
        for v in &settable {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                let before = inst.fingerprint();
                let s = inst.set_real(&[v.vr], &[bad]);
                refused(
                    &inst,
                    &format!("set '{}' = {bad} in {state:?}", v.name),
                    s,
                    &[&format!("'{}'", v.name)],
                );
                inst.warn_if_changed(&before, s, format_args!("'{}' = {bad} in {state:?}", v.name));
            }
        }
        // All or nothing: a good value next to a bad one is not stored either.
        if let Some(first) = settable.first() {
            let before = inst.fingerprint();
            let s = inst.set_real(&[first.vr, first.vr], &[excite(first), f64::NAN]);
            refused(&inst, "a batch with one NaN", s, &["NaN"]);
            inst.warn_if_changed(&before, s, "a batch with one NaN");
        }
    }
}

/// Values to retune a Real parameter to, best first: other values than its start value, inside
/// [min, max] and where a parameter can matter, halfway from the start value towards a declared
/// bound, else twice and half the start value (1 and -1 for a start value of 0). Never a bound
/// itself: a bound is a legal value, not a meaningful one (min = 5e-324, "positive", makes a
/// time constant's derivative infinite), and a model is right to answer it with an error.
pub(super) fn retune_values(v: &crate::Variable) -> Vec<f64> {
    let start = v.start_real().unwrap_or(0.0);
    let (lo, hi) = (v.min.unwrap_or(f64::NEG_INFINITY), v.max.unwrap_or(f64::INFINITY));
    let mut candidates = vec![];
    if hi.is_finite() && hi > start {
        candidates.push(start + (hi - start) / 2.0);
    }
    if lo.is_finite() && lo < start {
        candidates.push(start - (start - lo) / 2.0);
    }
    if start != 0.0 {
        // start / 100 last: a limit (a torque bound, a saturation) that the excited run stays
        // far from acts only once it is small (a composed system's, whose excitation cannot
        // reach the limit through its inner connections).
        candidates.extend([start * 2.0, start / 2.0, -start, start / 100.0]);
    } else {
        candidates.extend([1.0, -1.0, 0.5, -0.5]);
    }
    let mut values: Vec<f64> = vec![];
    for x in candidates {
        // Inside the bounds, not on them, not a denormal-sized value next to one.
        let inside = x > lo && x < hi && x.is_finite() && x != start;
        let meaningful = x == 0.0 || x.abs() > 1e-300;
        if inside && meaningful && !values.contains(&x) {
            values.push(x);
        }
    }
    values
}

/// Another value for an input than the one [`excitation`] gives it, within [min, max]: the
/// input steps there between two steps.
pub(super) fn stepped(v: &crate::Variable) -> f64 {
    let x = excite(v);
    let clamp = |y: f64| {
        let y = v.max.map_or(y, |m| y.min(m));
        v.min.map_or(y, |m| y.max(m))
    };
    [x * 2.0, x + 1.0, x - 1.0, v.start_real().unwrap_or(0.0)]
        .into_iter()
        .map(clamp)
        .find(|y| *y != x)
        .unwrap_or(x)
}

/// The values a tunable parameter is retuned to, one per attempt: Reals from
/// [`retune_values`], Integers one above and one below the start value (an integer mode has a
/// few legal values), a Boolean its negation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Retune {
    Real(f64),
    Integer(i32),
    Boolean(bool),
}

pub(super) fn retunes(p: &crate::Variable) -> Vec<Retune> {
    match p.ty {
        Type::Real => retune_values(p).into_iter().map(Retune::Real).collect(),
        Type::Integer => {
            let start = p.start_integer().unwrap_or(0);
            [start.checked_add(1), start.checked_sub(1)]
                .into_iter()
                .flatten()
                .filter(|x| p.min.is_none_or(|m| f64::from(*x) >= m) && p.max.is_none_or(|m| f64::from(*x) <= m))
                .map(Retune::Integer)
                .collect()
        }
        Type::Boolean => vec![Retune::Boolean(!p.start_boolean().unwrap_or(false))],
        _ => vec![],
    }
}

/// Sets a tunable parameter to `value`: whether the model accepted it (a refusal is an
/// fmi2Error; anything else but fmi2OK fails the check).
pub(super) fn retune(inst: &mut Instance, p: &crate::Variable, value: Retune) -> bool {
    let s = match value {
        Retune::Real(x) => inst.set_real(&[p.vr], &[x]),
        Retune::Integer(x) => inst.set_integer(&[p.vr], &[x]),
        Retune::Boolean(x) => inst.set_boolean(&[p.vr], &[x]),
    };
    inst.log();
    if s != fmi2OK {
        assert_eq!(s, fmi2Error, "{}: setting '{}' to {value:?}", inst.fmu.id, p.name);
    }
    s == fmi2OK
}

/// A tunable parameter set between steps changes the trajectory from the next step on, and
/// not before. "Changes" is tried first from the excited run as it goes on; a parameter that
/// cannot matter there (a time constant of a lag at its steady state: the excitation sets the
/// input and the initial state alike) is tried again with the inputs stepped to other values
/// at the same step, compared with a run whose inputs step there too and whose parameter
/// stays. At least one tunable parameter must change something.
pub fn a_tunable_parameter_set_between_steps_takes_effect_at_the_next_step(fmu: &Fmu) {
    let tunables: Vec<_> = fmu
        .md
        .variables
        .iter()
        .filter(|v| v.causality == Causality::Parameter && v.variability == Variability::Tunable)
        .filter(|v| matches!(v.ty, Type::Real | Type::Integer | Type::Boolean))
        .collect();
    // The order of Instance::observe: Reals, then Integers, then Booleans.
    let observed: Vec<u32> = [Type::Real, Type::Integer, Type::Boolean]
        .iter()
        .flat_map(|t| fmu.md.vrs_of_type(*t))
        .collect();
    let inputs: Vec<(u32, f64)> = fmu
        .md
        .of_type(Type::Real)
        .filter(|v| v.causality == Causality::Input && v.variability != Variability::Constant)
        .map(|v| (v.vr, stepped(v)))
        .collect();
    // Steps long enough for a solver tolerance to matter (within 1 ms it rarely does).
    let h = 0.1;
    let (k, n) = (5, 10);
    // An excited run of n steps; before step k, the inputs step (`step_inputs`) and the
    // parameter is set (`p`, to a value). The observations if the model took the value: it may
    // refuse it when it is set (fmi2Error), or by failing a step after it (a value that makes the
    // model's derivative non-finite is the model's to refuse; `None` either way).
    let trajectory = |p: Option<(&crate::Variable, Retune)>, step_inputs: bool| -> Option<Vec<Vec<u64>>> {
        let mut inst = Instance::new(fmu);
        let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(fmu).into_iter().unzip();
        assert_eq!(inst.set_real(&vrs, &vals), fmi2OK);
        inst.initialize();
        let mut out = vec![inst.observe()];
        for step in 0..n {
            if step == k {
                if step_inputs {
                    let (vrs, vals): (Vec<u32>, Vec<f64>) = inputs.iter().copied().unzip();
                    assert_eq!(
                        inst.set_real(&vrs, &vals),
                        fmi2OK,
                        "{}: stepping the inputs: {}",
                        fmu.id,
                        inst.log_text()
                    );
                }
                if let Some((p, value)) = p
                    && !retune(&mut inst, p, value)
                {
                    return None;
                }
            }
            let s = inst.step(h);
            if s != fmi2OK
                && step >= k
                && let Some((p, value)) = p
            {
                info(format!(
                    "'{}' = {value:?} set at t = {:.1} s: the model answered the next steps with {} ({}); \
                     taken as its refusal of that value",
                    p.name,
                    k as f64 * h,
                    status_name(s),
                    inst.log_text()
                ));
                return None;
            }
            assert_eq!(s, fmi2OK, "{}: {}", fmu.id, inst.log_text());
            out.push(inst.observe());
        }
        Some(out)
    };
    let reference = run(fmu, n, h);
    let stepped_reference = (!inputs.is_empty()).then(|| trajectory(None, true).expect("no parameter set"));
    let mut effective = vec![];
    for p in &tunables {
        // Identical up to the change (only the parameter's own value differs), different after.
        let pi = observed.iter().position(|vr| *vr == p.vr).unwrap();
        let strip = |o: &Vec<u64>| {
            let mut o = o.clone();
            o.remove(pi);
            o
        };
        let differs = |out: &[Vec<u64>], reference: &[Vec<u64>]| {
            for step in 0..=k {
                assert_eq!(
                    strip(&out[step]),
                    strip(&reference[step]),
                    "{}: '{}' acted before it was set",
                    fmu.id,
                    p.name
                );
            }
            (k + 1..=n).any(|s| strip(&out[s]) != strip(&reference[s]))
        };
        // A value the model takes acts in the excited run, or else with the inputs stepped at
        // the same step; the values are tried in turn until one acts.
        for value in retunes(p) {
            let Some(out) = trajectory(Some((p, value)), false) else {
                continue;
            };
            let acts = differs(&out, &reference)
                || stepped_reference.as_ref().is_some_and(|stepped_reference| {
                    trajectory(Some((p, value)), true).is_some_and(|out| differs(&out, stepped_reference))
                });
            if acts {
                effective.push(p.name.clone());
                break;
            }
        }
    }
    // A parameter the FMU declares to change nothing: every <InitialUnknowns> element lists its
    // dependencies and none lists the parameter (the Reference-FMUs' Feedthrough stores its
    // tunable parameter and uses it nowhere). Such parameters need not act; they were checked
    // not to act before they were set like the others.
    let ms = &fmu.md.model_structure;
    let declared_inert = |p: &crate::Variable| {
        let index = fmu
            .md
            .variables
            .iter()
            .position(|v| v.vr == p.vr && v.name == p.name)
            .map(|i| i + 1);
        ms.initial_unknowns.iter().all(|u| {
            u.dependencies
                .as_ref()
                .is_some_and(|d| index.is_none_or(|i| !d.contains(&i)))
        })
    };
    let must_act: Vec<_> = tunables.iter().filter(|p| !declared_inert(p)).collect();
    if must_act.is_empty() && !tunables.is_empty() {
        info(format!(
            "tunable parameters {:?}: no <InitialUnknowns> element depends on them, so nothing was required to change",
            tunables.iter().map(|p| &p.name).collect::<Vec<_>>()
        ));
    }
    // Not seeing a change is no proof the FMU ignored the value: a tolerance the integration
    // already meets (the networked pendulum container's `pendulum.rtol`: its 1 ms steps' error is
    // below both values tried), or a parameter that acts only in conditions these steps do not
    // reach. FMI 2.0.5 §4.2.4 lets tunable parameters be set between steps; it does not require
    // that they change the outputs. A warning, with the values tried.
    crate::outcome::warn_unless(must_act.is_empty() || !effective.is_empty(), || {
        format!(
            "{}: none of the tunable parameters {:?} changed anything after it was set between steps \
             (neither in the excited run nor with the inputs {:?} stepped at the same step): either the FMU \
             ignores them or they act only where these steps did not go",
            fmu.id,
            must_act.iter().map(|p| &p.name).collect::<Vec<_>>(),
            inputs
        )
    });
}
