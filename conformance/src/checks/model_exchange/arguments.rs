//! Refusals: the model-exchange functions on a co-simulation instance and on a NULL component,
//! bad arguments, and each variable set only where the standard allows it.

#![allow(non_upper_case_globals)] // fmi2OK etc. are the standard's names, matched on

use super::{advanced, me_observe, refusal_logged, set_function, start_states};
use crate::fmi2::*;
use crate::instance::{Instance, status_name};
use crate::me::{self, MeState::*, needs_me};
use crate::outcome::{limitation, skip_not_declared};
use crate::standard::REACHABLE;
use crate::state::{STATES, State};
use crate::{Fmu, Type};

/// The model-exchange functions, for [`one_me_call`].
pub(super) const ME_CALLS: usize = 10;

pub fn a_co_simulation_instance_refuses_every_model_exchange_function(fmu: &Fmu) {
    if fmu.api.me.is_err() {
        if fmu.md.me.is_some() {
            needs_me(fmu);
        }
        skip_not_declared("<ModelExchange>, and the binary does not export the model-exchange functions");
    }
    let own = fmu.own_state_format();
    if !own {
        limitation(
            "called only in Instantiated, InitializationMode, StepComplete and Terminated; the state after each call is not observed",
        );
    }
    let mut failures = vec![];
    for s in STATES.into_iter().filter(|s| own || REACHABLE.contains(s)) {
        for k in 0..ME_CALLS {
            // One call per fresh instance: an FMU that wrongly accepts one must not spoil the
            // next.
            let mut inst = crate::checks::state_machine::instance_in(fmu, s);
            let before = if s != State::Fatal { inst.fingerprint() } else { None };
            let (function, status) = one_me_call(&mut inst, k);
            let log = inst.log();
            let at = format!("{}: {function} in co-simulation state {s:?}", fmu.id);
            // A model-exchange function called on a co-simulation instance is the importer's
            // mistake (FMI 2.0.5 §2.1.5: the instance offers the interface of its fmuType): not
            // refusing it is a warning.
            if status != fmi2Error {
                crate::outcome::warn(format!(
                    "{at}: expected fmi2Error, got {} (an importer's mistake not detected); log {log:?}",
                    status_name(status)
                ));
            } else if !refusal_logged(&inst, &log, function) {
                crate::outcome::warn(format!(
                    "{at}: refused without an fmi2Error message naming the function: {log:?}"
                ));
            }
            if s != State::Fatal && status == fmi2Error {
                inst.warn_if_changed(&before, status, &at);
                if own && inst.machine_state() != s {
                    failures.push(format!("{at}: refused, but the state machine left {s:?}"));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// The k-th model-exchange function with valid arguments: (name, status).
pub(super) fn one_me_call(inst: &mut Instance, k: usize) -> (&'static str, fmi2Status) {
    let x = start_states(inst.fmu);
    let t = inst.time;
    match k {
        0 => ("fmi2EnterEventMode", inst.enter_event_mode()),
        1 => ("fmi2NewDiscreteStates", inst.new_discrete_states().0),
        2 => ("fmi2EnterContinuousTimeMode", inst.enter_continuous_time_mode()),
        3 => ("fmi2CompletedIntegratorStep", inst.completed_integrator_step().status),
        4 => ("fmi2SetTime", inst.set_time(t)),
        5 => ("fmi2SetContinuousStates", inst.set_continuous_states(&x)),
        6 => ("fmi2GetDerivatives", inst.get_derivatives().0),
        7 => ("fmi2GetEventIndicators", inst.get_event_indicators().0),
        8 => ("fmi2GetContinuousStates", inst.get_continuous_states().0),
        _ => ("fmi2GetNominalsOfContinuousStates", inst.get_nominals().0),
    }
}

/// Fails unless the last call was refused with fmi2Error and a logged message (naming the
/// function, on this exporter's FMUs).
///
/// Verdict: the calls are the importer's mistakes (wrong sizes, NULL, NaN time), which FMI 2.0.5
/// leaves undefined: not refusing them is a warning.
pub(super) fn refused(inst: &Instance, function: &str, what: &str, status: fmi2Status) {
    let log = inst.log();
    if status != fmi2Error {
        crate::calllog::warning_requires(crate::replay::Expected::ERROR);
        crate::outcome::warn(format!(
            "{}: {function} with {what}: expected fmi2Error, got {} (an importer's mistake not detected); log {log:?}",
            inst.fmu.id,
            status_name(status)
        ));
    } else if !refusal_logged(inst, &log, function) {
        crate::outcome::warn(format!(
            "{}: {function} with {what}: refused without an fmi2Error message naming the function: {log:?}",
            inst.fmu.id
        ));
    }
}

/// Verdict: warned, never failed: wrong vector sizes, NULL arrays and non-finite times are the
/// importer's mistakes, which FMI 2.0.5 leaves undefined (the helper `refused`).
pub fn model_exchange_bad_arguments_are_refused_with_a_message_and_change_nothing(fmu: &Fmu) {
    needs_me(fmu);
    let (mut inst, _) = advanced(fmu, 10);
    let (nx, ni) = (inst.nx(), inst.ni());
    let getters: [(&'static str, usize); 4] = [
        ("fmi2GetContinuousStates", nx),
        ("fmi2GetDerivatives", nx),
        ("fmi2GetNominalsOfContinuousStates", nx),
        ("fmi2GetEventIndicators", ni),
    ];
    let reference = me_observe(&inst);
    let check_unchanged = |inst: &mut Instance, what: &str, before: &Option<Vec<u8>>| {
        inst.warn_if_changed(before, fmi2Error, what);
        crate::outcome::warn_unless(me_observe(inst) == reference, || {
            format!(
                "{}: after the refused {what}, the instance shows other values ({})",
                fmu.id,
                crate::instance::REFUSED_CHANGED_WHY
            )
        });
    };
    let mut sizes: Vec<usize> = vec![];
    for (function, n) in getters {
        // Wrong lengths, with a buffer of that length; NULL with the right length.
        sizes.clear();
        sizes.extend([n + 1, n + 7]);
        if n > 0 {
            sizes.push(n - 1);
        }
        for m in sizes.iter().copied() {
            let before = inst.fingerprint();
            // Through the call log (a guard after the m values): `fmi2GetDerivatives n=M`.
            let s = crate::outcome::on_purpose(|| inst.get_vector_n(function, m).0);
            let what = format!("n = {m} (the FMU has {n})");
            refused(&inst, function, &what, s);
            check_unchanged(&mut inst, &format!("{function}({what})"), &before);
        }
        let before = inst.fingerprint();
        let m = n.max(1);
        // NULL with n > 0, which the FMU must refuse: `fmi2GetDerivatives n=M values=NULL`.
        let s = crate::outcome::on_purpose(|| inst.get_vector_null(function, m));
        refused(&inst, function, &format!("NULL and n = {m}"), s);
        check_unchanged(&mut inst, &format!("{function}(NULL, {m})"), &before);
    }
    // fmi2SetContinuousStates: lengths, NULL, non-finite values (each position).
    let (_, x) = inst.get_continuous_states();
    let mut bad_states: Vec<(String, Vec<f64>, bool)> = vec![
        (
            format!("n = {} (the FMU has {nx})", nx + 1),
            [&x[..], &[0.0]].concat(),
            false,
        ),
        (format!("NULL and n = {}", nx.max(1)), vec![], true),
    ];
    if nx > 0 {
        bad_states.push((
            format!("n = {} (the FMU has {nx})", nx - 1),
            x[..nx - 1].to_vec(),
            false,
        ));
    }
    for j in 0..nx {
        for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut y = x.clone();
            y[j] = v;
            bad_states.push((format!("x[{j}] = {v}"), y, false));
        }
    }
    for (what, y, null) in bad_states {
        let before = inst.fingerprint();
        let s = if null {
            crate::outcome::on_purpose(|| inst.set_continuous_states_null(nx.max(1)))
        } else {
            crate::outcome::on_purpose(|| inst.set_continuous_states(&y))
        };
        refused(&inst, "fmi2SetContinuousStates", &what, s);
        check_unchanged(&mut inst, &format!("fmi2SetContinuousStates({what})"), &before);
    }
    // fmi2SetTime: not finite.
    let t = inst.time;
    for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let before = inst.fingerprint();
        let s = inst.set_time(v);
        refused(&inst, "fmi2SetTime", &format!("time = {v}"), s);
        check_unchanged(&mut inst, &format!("fmi2SetTime({v})"), &before);
    }
    inst.time = t;
    // fmi2CompletedIntegratorStep: NULL out pointers.
    for (what, enter_null) in [("enterEventMode NULL", true), ("terminateSimulation NULL", false)] {
        let before = inst.fingerprint();
        let s = crate::outcome::on_purpose(|| inst.completed_integrator_step_null(enter_null));
        refused(&inst, "fmi2CompletedIntegratorStep", what, s);
        check_unchanged(&mut inst, &format!("fmi2CompletedIntegratorStep({what})"), &before);
    }
    // fmi2NewDiscreteStates(NULL), in EventMode, on a fresh instance: after fmi2Error the first
    // one may not go on (FMI 2.0.5 §2.1.3).
    let (mut inst, _) = advanced(fmu, 10);
    assert_eq!(inst.enter_event_mode(), fmi2OK, "{}", inst.log_text());
    inst.log();
    let before = inst.fingerprint();
    // What the valid call answers without the refused one before it: on a twin instance.
    let (mut twin, _) = advanced(fmu, 10);
    assert_eq!(twin.enter_event_mode(), fmi2OK, "{}", twin.log_text());
    let (s_ref, info_ref) = twin.new_discrete_states();
    // On purpose: its breadcrumb says so, and a crash in it is a warning.
    let s = crate::outcome::on_purpose(|| inst.new_discrete_states_null());
    refused(&inst, "fmi2NewDiscreteStates", "eventInfo NULL", s);
    inst.warn_if_changed(&before, s, "fmi2NewDiscreteStates(NULL)");
    let (s, info) = inst.new_discrete_states();
    crate::outcome::warn_unless((s, info) == (s_ref, info_ref), || {
        format!(
            "{}: fmi2NewDiscreteStates after the refused one answers otherwise ({})",
            fmu.id,
            crate::instance::REFUSED_CHANGED_WHY
        )
    });
    if before.is_none() {
        limitation(
            "<ModelExchange> does not declare canGetAndSetFMUstate and canSerializeFMUstate: the FMU state is not compared",
        );
    }
}

/// Verdict: refusing a set the standard allows (FMI 2.0.5 §3.2.3) fails; accepting one it does
/// not allow, or NaN/infinity, is the importer's mistake undetected: a warning.
pub fn model_exchange_each_variable_can_be_set_exactly_where_the_standard_allows_it(fmu: &Fmu) {
    needs_me(fmu);
    let mut failures = vec![];
    for state in [Instantiated, InitializationMode, EventMode, ContinuousTimeMode] {
        for v in fmu
            .md
            .variables
            .iter()
            // An alias is checked through the first variable of its set.
            .filter(|v| v.ty != Type::String && !crate::standard::aliases_an_earlier(&fmu.md.variables, v))
        {
            let mut inst = me::instance_in(fmu, state);
            let before = inst.fingerprint();
            let s = match v.ty {
                Type::Real => inst.set_real(&[v.vr], &[v.start_real().unwrap_or(0.0)]),
                Type::Integer | Type::Enumeration => inst.set_integer(&[v.vr], &[v.start_integer().unwrap_or(0)]),
                Type::Boolean => inst.set_boolean(&[v.vr], &[v.start_boolean().unwrap_or(false)]),
                Type::String => unreachable!(),
            };
            let log = inst.log();
            let want = crate::standard::settable_in_me(v, &format!("{state:?}"));
            let at = format!(
                "{}: set '{}' ({:?} {} {}, initial {:?}) in model-exchange state {state:?}",
                fmu.id,
                v.name,
                v.ty,
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
            if !want {
                let function_allowed = me::allowed_states(set_function(v.ty)).contains(&state);
                // The importer's mistake (FMI 2.0.5 §3.2.3 says where each variable may be set):
                // undetected, a warning.
                if s != fmi2Error {
                    crate::outcome::warn(format!(
                        "{at}: not allowed by the standard, got {} (an importer's mistake not detected)",
                        status_name(s)
                    ));
                } else if function_allowed && !inst.says(&log, fmi2Error, &[&format!("'{}'", v.name)]) {
                    crate::outcome::warn(format!("{at}: the refusal does not name the variable: {log:?}"));
                } else if !log.iter().any(|e| e.status == fmi2Error) {
                    crate::outcome::warn(format!("{at}: refused without a message"));
                }
                inst.warn_if_changed(&before, s, &at);
            }
            // A settable Real refuses NaN and infinities.
            if want && v.ty == Type::Real {
                for bad in [f64::NAN, f64::INFINITY] {
                    let before = inst.fingerprint();
                    let s = inst.set_real(&[v.vr], &[bad]);
                    let log = inst.log();
                    // NaN and infinity: the importer's mistake, a warning (see
                    // nan_and_infinite_values_are_refused_with_a_message_and_change_nothing).
                    if s != fmi2Error || !log.iter().any(|e| e.status == fmi2Error) {
                        crate::outcome::warn(format!(
                            "{at}: = {bad}: expected fmi2Error with a message, got {} (an importer's mistake not detected)",
                            status_name(s)
                        ));
                    }
                    inst.warn_if_changed(&before, s, format_args!("{at} = {bad}"));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

pub fn model_exchange_functions_refuse_a_null_component(fmu: &Fmu) {
    if fmu.api.me.is_err() {
        if fmu.md.me.is_some() {
            needs_me(fmu);
        }
        skip_not_declared("<ModelExchange>, and the binary does not export the model-exchange functions")
    }
    // Through the call log of a live instance (made first and given to no call; model exchange
    // where the description declares it), so that a failure leaves a reproducer with them:
    // `fmi2SetTime component=NULL -> Error`.
    let args = crate::instance::Args {
        fmu_type: if fmu.md.me.is_some() {
            fmi2ModelExchange
        } else {
            fmi2CoSimulation
        },
        ..crate::instance::Args::valid(fmu)
    };
    let inst = Instance::with(fmu, &args).unwrap_or_else(|log| panic!("{}: fmi2Instantiate refused: {log:?}", fmu.id));
    crate::outcome::breadcrumb("model-exchange functions with a NULL component");
    let answers: Vec<_> = crate::instance_calls::ME_NULL_COMPONENT_PROBES
        .iter()
        .map(|f| {
            let s = inst.null_component(f);
            crate::calllog::standard_requires(crate::replay::Expected::ERROR);
            (f, s)
        })
        .collect();
    for (f, s) in answers {
        assert_eq!(s, fmi2Error, "{}: {f}(NULL, ...) answered {}", fmu.id, status_name(s));
    }
}
