//! fmi2DoStep (step sizes, communication points, the stop time, a huge step, the status
//! functions) and fmi2Reset from every state.

#![allow(non_upper_case_globals)] // fmi2OK etc. are the standard's names, matched on

use super::{initialized, refused};
use crate::fmi2::*;
use crate::instance::{Instance, excitation, run, run_on, status_name, step_size};
use crate::outcome::{convention, limitation};
use crate::standard::REACHABLE;
use crate::state::{STATES, State};
use crate::{Fmu, Type};
use md_reader::{Causality, Initial};

pub fn do_step_refuses_a_step_size_that_is_not_finite_and_positive(fmu: &Fmu) {
    let h = step_size(fmu);
    let reference = run(fmu, 2, h);
    let mut inst = Instance::new(fmu);
    let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(fmu).into_iter().unzip();
    assert_eq!(inst.set_real(&vrs, &vals), fmi2OK);
    inst.initialize();
    assert_eq!(inst.step(h), fmi2OK);
    for bad in [
        0.0,
        -0.0,
        -h,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::MIN_POSITIVE / 4.0,
    ] {
        let before = inst.fingerprint();
        let s = inst.do_step(inst.time, bad);
        refused(&inst, &format!("fmi2DoStep(h = {bad:e})"), s, &["fmi2DoStep"]);
        inst.warn_if_changed(&before, s, format_args!("a step of h = {bad}"));
        let last = inst.last_successful_time();
        crate::outcome::warn_unless(last == (fmi2OK, inst.time), || {
            format!(
                "{}: after a refused step of h = {bad}: fmi2GetRealStatus(fmi2LastSuccessfulTime) = {last:?}, expected (fmi2OK, {})",
                fmu.id, inst.time
            )
        });
    }
    // Going on after fmi2Error is beyond FMI 2.0.5 (§2.1.3: "the simulation cannot be continued
    // with this FMU instance"): a warning when the instance cannot.
    let s = inst.step(h);
    if s != fmi2OK {
        crate::outcome::warn(format!(
            "{}: a good step after the refused ones: {} ({}): the instance cannot go on after refusing an importer's mistake",
            fmu.id,
            status_name(s),
            inst.log_text()
        ));
    } else {
        crate::outcome::warn_unless(inst.observe() == reference[2], || {
            format!("{}: the refused steps changed the trajectory", fmu.id)
        });
    }
}

pub fn do_step_compares_the_communication_point_with_a_relative_tolerance(fmu: &Fmu) {
    let h = 0.1;
    let mut inst = initialized(fmu);
    // An importer summing h: t = 0.1 + 0.1 + ... is not exactly n·h.
    let mut summed = 0.0;
    for n in 0..10 {
        let t = n as f64 * h;
        let s = inst.do_step(t, h);
        assert_eq!(
            s,
            fmi2OK,
            "{}: step {n} at t = {t:?} (summed {summed:?}): {}",
            fmu.id,
            inst.log_text()
        );
        summed += h;
    }
    inst.time = 10.0 * h;
    assert_ne!(summed, inst.time, "the round-off case this test is about");
    let s = inst.do_step(summed, h);
    assert_eq!(
        s,
        fmi2OK,
        "{}: t = {summed:?} where the FMU is at {:?}: {}",
        fmu.id,
        inst.time,
        inst.log_text()
    );
    inst.time = summed + h;
    // A real mismatch is refused, whatever the step size.
    for (dt, h) in [(1e-3, 0.1), (-1e-3, 0.1), (5.0, 1e9), (-0.5, 1e9)] {
        let before = inst.fingerprint();
        let s = inst.do_step(inst.time + dt, h);
        refused(
            &inst,
            &format!("fmi2DoStep off by {dt} with h = {h}"),
            s,
            &["currentCommunicationPoint"],
        );
        inst.warn_if_changed(&before, s, format_args!("a step off by {dt} with h = {h}"));
    }
}

pub fn do_step_beyond_the_stop_time_is_refused(fmu: &Fmu) {
    let mut inst = Instance::new(fmu);
    assert_eq!(
        [inst.setup(0.0, Some(0.05)), inst.enter_init(), inst.exit_init()],
        [fmi2OK; 3]
    );
    let s = inst.do_step(0.0, 0.1);
    refused(&inst, "a step past stopTime", s, &["stopTime"]);
    // A fresh instance: after fmi2Error the first one may not go on (FMI 2.0.5 §2.1.3).
    let mut inst = Instance::new(fmu);
    assert_eq!(
        [inst.setup(0.0, Some(0.05)), inst.enter_init(), inst.exit_init()],
        [fmi2OK; 3]
    );
    assert_eq!(
        inst.do_step(0.0, 0.05),
        fmi2OK,
        "{}: a step to stopTime: {}",
        fmu.id,
        inst.log_text()
    );
}

/// A huge step must end within bounded time with fmi2OK or fmi2Discard; after a discard the
/// status functions answer truthfully, another step is refused, and restoring an earlier FMU
/// state makes the instance usable again.
///
/// Verdict: a step of 1e6, 1e300 or f64::MAX seconds is absurd input; FMI 2.0.5 bounds neither
/// its time nor how exactly the FMU's clock lands on t + h, so a hang, a crash or a drifting
/// fmi2LastSuccessfulTime is a warning. Failures stay for what §4.2.3 requires of the answers:
/// a status other than fmi2OK/fmi2Discard/fmi2Error, fmi2LastSuccessfulTime outside the step
/// after fmi2Discard.
pub fn a_huge_step_completes_or_is_discarded_and_the_status_functions_tell_the_truth(fmu: &Fmu) {
    for huge in [1e6, 1e300, f64::MAX] {
        let mut inst = Instance::new(fmu);
        let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(fmu).into_iter().unzip();
        assert_eq!(inst.set_real(&vrs, &vals), fmi2OK);
        inst.initialize();
        let h = step_size(fmu);
        assert_eq!(inst.step(h), fmi2OK);
        let saved = fmu.can_snapshot().then(|| inst.snapshot());
        let t0 = inst.time;
        let clock = std::time::Instant::now();
        // Absurd input: a crash or a hang in it is a warning (outcome::on_purpose).
        let s = crate::outcome::on_purpose(|| inst.do_step(t0, huge));
        let took = clock.elapsed();
        crate::outcome::warn_unless(took.as_secs() < 20, || {
            format!(
                "{}: a step of {huge:e} s took {took:?} (a hang on absurd input)",
                fmu.id
            )
        });
        let log = inst.log();
        match s {
            fmi2OK => {
                // A step this large is absurd input: how close the FMU's clock ends to t0 + h is
                // numerics (an internal fixed step summed 10^8 times drifts), which FMI 2.0.5
                // does not bound; a warning beyond a tolerance relative to the step.
                let (st, last) = inst.last_successful_time();
                assert_eq!(st, fmi2OK, "{}: fmi2GetRealStatus(fmi2LastSuccessfulTime)", fmu.id);
                crate::outcome::warn_unless(crate::outcome::same_time(last, t0 + huge, huge), || {
                    format!(
                        "{}: a completed step of {huge:e} from {t0}: fmi2LastSuccessfulTime = {last}, not t + h = {} within a tolerance relative to the step (the FMU's clock drifts on absurd steps)",
                        fmu.id,
                        t0 + huge
                    )
                });
                if fmu.own_state_format() {
                    assert_eq!(inst.machine_state(), State::StepComplete);
                }
            }
            fmi2Discard => {
                let category = |e: &crate::LogEntry| {
                    e.category == "logStatusDiscard"
                        || !convention(fmu, "a discarded step's message under category logStatusDiscard")
                };
                // FMI 2.0.5 asks no message with fmi2Discard ("should"): a warning.
                crate::outcome::warn_unless(log.iter().any(|e| e.status == fmi2Discard && category(e)), || {
                    format!("{}: fmi2Discard without a message: {log:?}", fmu.id)
                });
                if fmu.own_state_format() {
                    assert_eq!(inst.machine_state(), State::StepFailed);
                }
                let (st, reached) = inst.last_successful_time();
                assert_eq!(st, fmi2OK);
                assert!(
                    reached >= t0 && reached < t0 + huge,
                    "{}: fmi2LastSuccessfulTime = {reached} after a discarded step from {t0} by {huge:e}",
                    fmu.id
                );
                // fmi2Terminated: true only where the model ended the simulation in the step.
                let (st, terminated) = inst.terminated();
                assert_eq!(st, fmi2OK, "{}: fmi2GetBooleanStatus(fmi2Terminated)", fmu.id);
                // A message saying why is this exporter's wording and FMI 2.0.5's "should" (the
                // logger is called with fmi2Discard: §2.1.3, not a requirement): a warning.
                if terminated == fmi2True {
                    crate::outcome::warn_unless(
                        log.iter().any(|e| {
                            e.status == fmi2Discard
                                && (e.text.contains("ended the simulation")
                                    || !convention(fmu, "the wording of messages (which words name what is wrong)"))
                        }),
                        || {
                            format!(
                                "{}: fmi2Terminated after a discarded step, but no message says the model ended the simulation: {log:?}",
                                fmu.id
                            )
                        },
                    );
                }
                let values = inst.get_real(&fmu.md.vrs_of_type(Type::Real));
                assert_eq!(values.0, fmi2OK);
                assert!(
                    values.1.iter().all(|v| v.is_finite()),
                    "{}: values at the last successful time are not finite: {:?}",
                    fmu.id,
                    values.1
                );
                // No step after a discarded one until the state is restored.
                let s = inst.do_step(reached, h);
                refused(&inst, "a step after a discarded one", s, &["fmi2DoStep", "StepFailed"]);
                let Some(saved) = &saved else {
                    limitation(
                        "the FMU cannot serialize its state: restoring the state before a discarded step is not tried",
                    );
                    continue;
                };
                inst.restore(saved);
                inst.time = t0;
                assert_eq!(
                    inst.step(h),
                    fmi2OK,
                    "{}: a step after restoring: {}",
                    fmu.id,
                    inst.log_text()
                );
                assert_eq!(inst.terminate(), fmi2OK);
            }
            other => panic!(
                "{}: a step of {huge:e} answered {}: {log:?}",
                fmu.id,
                status_name(other)
            ),
        }
    }
}

/// After completed steps the status functions answer: fmi2LastSuccessfulTime with fmi2OK,
/// fmi2Terminated false; kinds of another getter are answered fmi2Discard; a NULL `value` is
/// refused.
///
/// Verdict: FMI 2.0.5 §4.2.3 (fmi2Get*Status "Informs the master about the actual status of the
/// simulation run"; "If a status is required which cannot be retrieved by the slave it returns
/// fmi2Discard"): a status other than those fails. Whether fmi2LastSuccessfulTime is t + h after
/// fmi2OK is what fmi2OK means (§4.2.2): `do_step_advances_time_by_the_step` carries that verdict
/// (one defect, one failure); here a differing time is noted, not failed. A NULL `value` is the
/// importer's mistake: not refused, or a crash in it, is a warning.
pub fn status_functions_report_the_last_successful_time_and_no_termination_request(fmu: &Fmu) {
    let mut inst = initialized(fmu);
    let h = step_size(fmu);
    for _ in 0..3 {
        assert_eq!(inst.step(h), fmi2OK);
        // FMI 2.0.5 §4.2.3: fmi2LastSuccessfulTime is "the end time of the last successfully
        // completed communication step". Whether that is t + h after fmi2OK is what fmi2OK means
        // (§4.2.2), the verdict of `do_step_advances_time_by_the_step`, which compares the same
        // value: one defect, one failure. Here the status function must answer.
        let (st, last) = inst.last_successful_time();
        assert_eq!(
            st,
            fmi2OK,
            "{}: fmi2GetRealStatus(fmi2LastSuccessfulTime) answered {} after a completed step to {} (FMI 2.0.5 §4.2.3: the end time of the last successfully completed communication step)",
            fmu.id,
            status_name(st),
            inst.time
        );
        if !crate::outcome::same_time(last, inst.time, h) {
            crate::outcome::info(format!(
                "fmi2LastSuccessfulTime is {last} after a completed step to {}: judged by do_step_advances_time_by_the_step",
                inst.time
            ));
        }
        assert_eq!(inst.terminated(), (fmi2OK, fmi2False));
    }
    // Kinds that belong to another getter: fmi2Discard with a message, value untouched. Through
    // the call log, so that a failure leaves a reproducer ending with the call.
    let discard = crate::replay::Expected(1 << fmi2Discard);
    let (s, r) = inst.real_status(fmi2Terminated, Some(-1.0));
    crate::calllog::standard_requires(discard);
    assert_eq!(
        (s, r),
        (fmi2Discard, -1.0),
        "{}: fmi2GetRealStatus(fmi2Terminated)",
        fmu.id
    );
    let (s, b) = inst.boolean_status(99);
    crate::calllog::standard_requires(discard);
    assert_eq!((s, b), (fmi2Discard, -1), "{}: fmi2GetBooleanStatus(99)", fmu.id);
    // A NULL out pointer is the importer's mistake (FMI 2.0.5 §4.2.3 has the importer provide
    // `value`): a crash in it is a warning.
    let s = crate::outcome::on_purpose(|| inst.real_status(fmi2LastSuccessfulTime, None).0);
    refused(&inst, "fmi2GetRealStatus(NULL)", s, &["NULL"]);
    assert_eq!(inst.terminate(), fmi2OK);
    // The time itself: do_step_advances_time_by_the_step's verdict (see above).
    let (st, last) = inst.last_successful_time();
    assert_eq!(
        st,
        fmi2OK,
        "{}: fmi2GetRealStatus(fmi2LastSuccessfulTime) after fmi2Terminate answered {}",
        fmu.id,
        status_name(st)
    );
    if !crate::outcome::same_time(last, inst.time, h) {
        crate::outcome::info(format!(
            "fmi2LastSuccessfulTime is {last} after fmi2Terminate at {}: judged by do_step_advances_time_by_the_step",
            inst.time
        ));
    }
}

// ---- fmi2Reset -----------------------------------------------------------------------------

/// From every state but Fatal; on another exporter's FMU from the states an importer reaches
/// by calls (the others need a forged FMU state).
pub fn reset_from_every_state_then_a_rerun_is_bit_identical(fmu: &Fmu) {
    let h = step_size(fmu);
    let reference = run(fmu, 20, h);
    let own = fmu.own_state_format();
    if !own {
        limitation(
            "fmi2Reset from StepFailed, StepCanceled and Error is not tried: only this exporter's FMUs can be put there",
        );
    }
    for s in STATES
        .into_iter()
        .filter(|s| *s != State::Fatal && (own || REACHABLE.contains(s)))
    {
        let mut inst = Instance::new(fmu);
        let first = run_on(&mut inst, 20, h);
        assert_eq!(first, reference, "{}: two fresh runs differ", fmu.id);
        if own && s != State::StepComplete {
            inst.force_state(s);
        } else {
            let calls = match s {
                State::Instantiated => vec![inst.reset()],
                State::InitializationMode => vec![inst.reset(), inst.setup(0.0, None), inst.enter_init()],
                State::Terminated => vec![inst.terminate()],
                _ => vec![],
            };
            assert!(
                calls.iter().all(|c| *c == fmi2OK),
                "{}: reaching {s:?} by calls: {calls:?}: {}",
                fmu.id,
                inst.log_text()
            );
        }
        assert_eq!(
            inst.reset(),
            fmi2OK,
            "{}: fmi2Reset from {s:?}: {}",
            fmu.id,
            inst.log_text()
        );
        if own {
            assert_eq!(inst.machine_state(), State::Instantiated);
        }
        // Every variable with a start value is back at it.
        assert_eq!([inst.setup(0.0, None), inst.enter_init()], [fmi2OK; 2]);
        for v in fmu.md.of_type(Type::Real).filter(|v| {
            v.causality != Causality::Output
                || crate::standard::initial(v.causality, v.variability, v.declared_initial) == Some(Initial::Exact)
        }) {
            if let Some(start) = v.start_real() {
                let (st, got) = inst.get_real(&[v.vr]);
                assert_eq!(
                    (st, got[0].to_bits()),
                    (fmi2OK, start.to_bits()),
                    "{}: '{}' after reset from {s:?}",
                    fmu.id,
                    v.name
                );
            }
        }
        assert_eq!(inst.reset(), fmi2OK);
        let again = run_on(&mut inst, 20, h);
        assert_eq!(
            again, reference,
            "{}: the run after fmi2Reset from {s:?} differs",
            fmu.id
        );
    }
}
