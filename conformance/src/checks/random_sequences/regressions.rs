//! Sequences the random runs found once, kept as a check of their own, and the huge-gravity
//! step they led to.

use super::Vr;
use super::co_simulation::{Op, When, execute, note_limitations};
use crate::fmi2::*;
use crate::instance::{Args, Instance, status_name};
use crate::{Fmu, Type};
use md_reader::Causality;

/// Sequences that failed once (found by the random run above, shrunk by proptest), kept as
/// tests of their own for every FMU.
pub fn regressions_found_by_random_sequences(fmu: &Fmu) {
    note_limitations(fmu);
    let init = [
        Op::Setup {
            tolerance: None,
            start: 0.0,
            stop: None,
        },
        Op::EnterInit,
    ];
    let mut cases: Vec<(&str, Vec<Op>)> = vec![
        (
            // fmi2GetReal of an unknown reference in initialization mode answered fmi2Error
            // after it had already run the model's initialization (the FMU state changed).
            "unknown reference read in initialization mode",
            [
                &init[..],
                &[Op::GetReal {
                    vrs: vec![Vr::Raw(u32::MAX)],
                    null: false,
                }],
            ]
            .concat(),
        ),
        (
            // At t = 0 a step of 1e9 s accepted a communication point 5 s off: the tolerance
            // scaled with the step size.
            "a huge step from a wrong communication point",
            [
                &init[..],
                &[
                    Op::ExitInit,
                    Op::DoStep {
                        when: When::At(5.0),
                        h: 1e9,
                    },
                ],
            ]
            .concat(),
        ),
    ];
    let vars = &fmu.md.variables;
    if let (Some(b), Some(r)) = (
        vars.iter().position(|v| v.ty == Type::Boolean),
        vars.iter().position(|v| v.ty == Type::Real),
    ) {
        // fmi2GetBoolean of a Boolean then a Real in initialization mode: one reference at
        // a time, the first one initialized the model before the second was refused.
        cases.push((
            "a Boolean and a Real read as Booleans in initialization mode",
            [
                &init[..],
                &[Op::GetBoolean {
                    vrs: vec![Vr::Known(b), Vr::Known(r)],
                }],
            ]
            .concat(),
        ));
    }
    for (what, ops) in &cases {
        for logging_on in [false, true] {
            if let Err(e) = execute(fmu, logging_on, ops) {
                let note = super::text::write(
                    fmu,
                    "regressions_found_by_random_sequences",
                    "co-simulation",
                    &format!("fmi2Instantiate fmuType=CoSimulation loggingOn={logging_on}"),
                    &super::text::record_cs(fmu, logging_on, ops),
                    &format!("{what}: {e}"),
                );
                panic!("{}: {what}: {e}\n{note}", fmu.id);
            }
        }
    }
    // Issue 49: on BouncingBall, g = -2.249e194 (a Real parameter without bounds, as in the
    // Reference FMUs) and one fmi2DoStep(0, 0.0044) took 14-32 s, answered fmi2Discard ("more
    // than 100000 events in one step") and left h = -3.8e168 and v = -5.8e181 behind. Not of any
    // FMU (what a huge value of some parameter means is the model's business): of each one with a
    // Real parameter named g. It asserts behaviour, not time.
    if let Some(g) = fmu
        .md
        .variables
        .iter()
        .find(|v| v.name == "g" && v.ty == Type::Real && v.causality == Causality::Parameter)
    {
        for logging_on in [false, true] {
            if let Err(e) = huge_g_then_a_step(fmu, g, logging_on) {
                panic!(
                    "{}: g = {HUGE_G:e}, then fmi2DoStep(0, {HUGE_G_STEP}) (logging {}): {e}",
                    fmu.id,
                    if logging_on { "on" } else { "off" }
                );
            }
        }
    }
}

/// The value of g and the step of [`huge_g_then_a_step`] (issue 49).
pub(super) const HUGE_G: f64 = -2.249e194;
pub(super) const HUGE_G_STEP: f64 = 0.0044;

/// A co-simulation instance, `g` set to [`HUGE_G`] in Instantiated (where the standard lets a
/// parameter be set), initialized, then `fmi2DoStep(0, HUGE_G_STEP)`. The FMU may refuse the
/// value where a declared bound excludes it (at the setter), or refuse it at
/// fmi2ExitInitializationMode with fmi2Error and a message (the model's initialization finds it
/// meaningless); either is a pass. Otherwise the step must return fmi2OK or fmi2Discard, every
/// Real must be finite afterwards, and after fmi2Discard `fmi2LastSuccessfulTime` is a time t in
/// [0, HUGE_G_STEP] and the variables are those of t: the same bits as before the step for t =
/// 0, the independent variable t, and close (a relative 1e-3: integrators differ) to those of
/// a fresh instance stepped from 0 to t where that step answers fmi2OK.
pub(super) fn huge_g_then_a_step(fmu: &Fmu, g: &crate::Variable, logging_on: bool) -> Result<(), String> {
    let args = Args {
        logging_on,
        ..Args::valid(fmu)
    };
    let initialized = |set_g: bool| -> Result<Option<Instance>, String> {
        let mut inst = Instance::with(fmu, &args).map_err(|log| format!("fmi2Instantiate refused: {log:?}"))?;
        if set_g {
            let s = inst.set_real(&[g.vr], &[HUGE_G]);
            let log = inst.log_text();
            let outside = g.min.is_some_and(|lo| HUGE_G < lo) || g.max.is_some_and(|hi| HUGE_G > hi);
            match s {
                fmi2OK | fmi2Warning => {}
                fmi2Error if outside => return Ok(None),
                _ => {
                    return Err(format!(
                        "fmi2SetReal in Instantiated answered {} although g declares no bound that excludes it; log: {log}",
                        status_name(s)
                    ));
                }
            }
        }
        let s = [inst.setup(0.0, None), inst.enter_init()];
        if s != [fmi2OK; 2] {
            return Err(format!(
                "fmi2SetupExperiment, fmi2EnterInitializationMode answered {:?}; log: {}",
                s.map(status_name),
                inst.log_text()
            ));
        }
        let s = inst.exit_init();
        let log = inst.log();
        match s {
            fmi2OK | fmi2Warning => Ok(Some(inst)),
            fmi2Error if set_g && log.iter().any(|e| e.status == fmi2Error) => Ok(None),
            _ => Err(format!(
                "fmi2ExitInitializationMode answered {}; log: {log:?}",
                status_name(s)
            )),
        }
    };
    let Some(mut inst) = initialized(true)? else {
        return Ok(());
    };
    let reals = fmu.md.vrs_of_type(Type::Real);
    let (s, before) = inst.get_real(&reals);
    if s != fmi2OK {
        return Err(format!(
            "fmi2GetReal of every Real after initialization answered {}; log: {}",
            status_name(s),
            inst.log_text()
        ));
    }
    let step = inst.do_step(0.0, HUGE_G_STEP);
    // (Its end: a step that handles events one by one may log each of them.)
    let log = inst.log_text();
    let log = match log.char_indices().rev().nth(2000) {
        Some((i, _)) => format!("...{}", &log[i..]),
        None => log,
    };
    if !matches!(step, fmi2OK | fmi2Discard) {
        return Err(format!(
            "the step answered {}, not fmi2OK or fmi2Discard; log: {log}",
            status_name(step)
        ));
    }
    let (s, after) = inst.get_real(&reals);
    if s != fmi2OK {
        return Err(format!(
            "after the step answered {}, fmi2GetReal of every Real answered {}; log: {}",
            status_name(step),
            status_name(s),
            inst.log_text()
        ));
    }
    let name = |vr: u32| {
        fmu.md
            .variables
            .iter()
            .find(|v| v.ty == Type::Real && v.vr == vr)
            .map_or("?", |v| v.name.as_str())
    };
    let not_finite: Vec<String> = reals
        .iter()
        .zip(&after)
        .filter(|(_, x)| !x.is_finite())
        .map(|(vr, x)| format!("{} = {x}", name(*vr)))
        .collect();
    if !not_finite.is_empty() {
        return Err(format!(
            "after the step answered {}, not finite: {}; step's log: {log}",
            status_name(step),
            not_finite.join(", ")
        ));
    }
    if step == fmi2OK {
        return Ok(());
    }
    let (s, t) = inst.last_successful_time();
    if s != fmi2OK || !(0.0..=HUGE_G_STEP).contains(&t) {
        return Err(format!(
            "after fmi2Discard, fmi2GetRealStatus(fmi2LastSuccessfulTime) answered {} and {t}, not a time in [0, {HUGE_G_STEP}]; step's log: {log}",
            status_name(s)
        ));
    }
    let independent = fmu
        .md
        .variables
        .iter()
        .find(|v| v.ty == Type::Real && v.causality == Causality::Independent);
    // The variables of time t: at t = 0 those before the step, bit for bit; later ones compared
    // with a fresh instance stepped from 0 to t.
    let expected = if t == 0.0 {
        Some((before, true))
    } else {
        let mut fresh = initialized(true)?.ok_or("a fresh instance refused what the first accepted")?;
        match (fresh.do_step(0.0, t), fresh.get_real(&reals)) {
            (fmi2OK, (fmi2OK, x)) => Some((x, false)),
            _ => None,
        }
    };
    let wrong: Vec<String> = reals
        .iter()
        .enumerate()
        .filter_map(|(i, vr)| {
            let x = after[i];
            let want = match (&expected, independent) {
                (_, Some(v)) if v.vr == *vr => t,
                (Some((e, _)), _) => e[i],
                (None, _) => return None,
            };
            let exact = expected.as_ref().is_some_and(|e| e.1) || independent.is_some_and(|v| v.vr == *vr);
            let close = if exact {
                x.to_bits() == want.to_bits()
            } else {
                (x - want).abs() <= 1e-3 * x.abs().max(want.abs()) + 1e-9
            };
            (!close).then(|| format!("{} = {x:e}, at t = {t:e} {want:e}", name(*vr)))
        })
        .collect();
    if !wrong.is_empty() {
        return Err(format!(
            "after fmi2Discard (fmi2LastSuccessfulTime {t:e}) the variables are not those of that time: {}; step's log: {log}",
            wrong.join(", ")
        ));
    }
    Ok(())
}
