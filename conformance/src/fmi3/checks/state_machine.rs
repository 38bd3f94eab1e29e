//! The FMI 3.0 state machine: every function in every state (the table of [`super::table`]),
//! a NULL instance, fmi3Reset from every state, and the Terminated state after fmi3Error.

use super::table::{Expect, TABLE};
use super::*;
use State::*;

/// Every row of [`TABLE`] in every state of the interface, each call on an instance of its own
/// brought into the state.
fn state_table(fmu: &Fmu3, me: bool) {
    let states: &[State] = if me { &State::ME } else { &State::CS };
    let mut failures = vec![];
    let mut mistakes = vec![];
    let mut open = vec![];
    let mut n = 0;
    for row in TABLE {
        let name = row.f.name();
        for &state in states {
            let inst = in_state(fmu, me, state);
            crate::outcome::breadcrumb(&format!("{name} in {state:?}"));
            let s = row.f.call(&inst);
            n += 1;
            let mut want = row.expect(state, me);
            // An FMU with clocks is instantiated with eventModeUsed (the standard requires it):
            // fmi3EnterEventMode is allowed in Step Mode then.
            if !me && fmu.has_clocks() && state == StepMode && row.f.name() == "fmi3EnterEventMode" {
                want = Expect::Ok;
            }
            // A derivative function of an FMU that does not provide it (FMI 3.0, 2.2.2: it is
            // not to be called): refused with the reason, in every state.
            let interface = if me { fmu.md.me.as_ref() } else { fmu.md.cs.as_ref() };
            let provided = match row.f.name() {
                "fmi3GetDirectionalDerivative" => interface.is_some_and(|x| x.provides_directional_derivatives),
                "fmi3GetAdjointDerivative" => interface.is_some_and(|x| x.provides_adjoint_derivatives),
                _ => true,
            };
            if !provided {
                want = Expect::Error;
            }
            // The FMU-state functions of an FMU that does not declare canGetAndSetFMUState (and
            // canSerializeFMUState for the serializing ones) are not to be called (FMI 3.0.2
            // §2.2.6.4): the FMU may refuse them or answer them, as FMI 2.0's check skips them.
            let state_offered = match row.f.name() {
                "fmi3GetFMUState" | "fmi3SetFMUState" | "fmi3FreeFMUState" => {
                    interface.is_some_and(|x| x.can_get_and_set_fmu_state)
                }
                "fmi3SerializedFMUStateSize" | "fmi3SerializeFMUState" | "fmi3DeserializeFMUState" => {
                    interface.is_some_and(|x| x.can_get_and_set_fmu_state && x.can_serialize_fmu_state)
                }
                _ => true,
            };
            if !state_offered && want == Expect::Ok {
                want = Expect::Either;
            }
            // fmi3EvaluateDiscreteStates is offered where the FMU declares
            // providesEvaluateDiscreteStates (FMI 3.0.2 §3.2.1): otherwise the FMU may refuse it
            // or answer it.
            if row.f.name() == "fmi3EvaluateDiscreteStates"
                && want == Expect::Ok
                && !interface.is_some_and(|x| x.provides_evaluate_discrete_states)
            {
                want = Expect::Either;
            }
            if !want.allows(s) && want == Expect::Error {
                // A call the state machine does not allow is the importer's mistake: FMI 3.0.2
                // §2.2.4 requires fmi3Error "when detecting ... a function call not allowed in the
                // current state", not the detection: a warning.
                mistakes.push(format!(
                    "{name} in {state:?}: {}, expected {:?} ({})",
                    status_name(s),
                    want,
                    inst.log_text()
                ));
            } else if !want.allows(s) {
                failures.push(format!(
                    "{name} in {state:?}: {}, expected {:?} ({})",
                    status_name(s),
                    want,
                    inst.log_text()
                ));
            } else if want == Expect::Either {
                open.push(format!("{name} in {state:?}: {}", status_name(s)));
            }
            drop(inst);
        }
    }
    // The C API also says fmi3GetVersion works without an instance and FreeInstance(NULL) is a no-op.
    // SAFETY: fmi3FreeInstance(NULL) must be a no-op (FMI 3.0 section 2.3.1); nothing of ours is
    // passed.
    unsafe { (fmu.api.free_instance)(null_mut()) };
    if !mistakes.is_empty() {
        crate::outcome::warn(format!(
            "{}: {} of {n} calls not allowed by the FMI 3.0 state machine ({}) were not refused (an importer's mistake not detected):\n{}",
            fmu.id,
            mistakes.len(),
            if me { "Model Exchange" } else { "Co-Simulation" },
            mistakes.join("\n")
        ));
    }
    assert!(
        failures.is_empty(),
        "{}: {} of {n} calls answered against the FMI 3.0 state machine ({}):\n{}",
        fmu.id,
        failures.len(),
        if me { "Model Exchange" } else { "Co-Simulation" },
        failures.join("\n")
    );
    info(format!("{n} (function, state) calls as the standard says"));
    info(format!(
        "cells the standard leaves to the FMU's capabilities, as answered: {}",
        open.join("; ")
    ));
    // StepDiscarded and the error states cannot be reached by an importer with valid calls on
    // an FMU that never discards: they are not in the table (see the README).
    info(
        "states not in the table: StepDiscarded, the error states (an importer cannot bring a conformant FMU there on purpose)",
    );
}

pub fn fmi3_co_simulation_every_function_in_every_state_answers_as_the_standard_says(fmu: &Fmu3) {
    cs_only(fmu);
    state_table(fmu, false);
}

pub fn fmi3_model_exchange_every_function_in_every_state_answers_as_the_standard_says(fmu: &Fmu3) {
    me_only(fmu);
    state_table(fmu, true);
}

/// Every function that takes an instance answers fmi3Error to a NULL one, without a crash
/// (there is no instance, so no logger either); fmi3FreeInstance(NULL) is a no-op (FMI 3.0,
/// 2.3.1). The calls are the state table's, plus the serialization functions.
pub fn fmi3_a_null_instance_is_refused_by_every_function(fmu: &Fmu3) {
    let inst = Inst::null(fmu, fmu.md.cs.is_none());
    let api = &fmu.api;
    let mut answers: Vec<(&str, fmi3Status)> = TABLE.iter().map(|row| (row.f.name(), row.f.call(&inst))).collect();
    let mut size = 0usize;
    let mut st: fmi3FMUState = null_mut();
    let mut buf = [0u8; 64];
    // SAFETY: valid pointers; the FMU must check the instance before touching anything.
    unsafe {
        answers.push((
            "fmi3SerializedFMUStateSize",
            crate::guard::fill_state_size3(&mut size, "fmi3SerializedFMUStateSize", |p| {
                (api.serialized_fmu_state_size)(null_mut(), null_mut(), p)
            }),
        ));
        answers.push((
            "fmi3SerializeFMUState",
            crate::guard::fill(
                &mut buf,
                "fmi3SerializeFMUState",
                "size",
                crate::guard::STATE_RULE3,
                |p| (api.serialize_fmu_state)(null_mut(), null_mut(), p, 64),
            ),
        ));
        answers.push((
            "fmi3DeserializeFMUState",
            crate::guard::fill_state3(&mut st, "fmi3DeserializeFMUState", |q| {
                (api.deserialize_fmu_state)(null_mut(), buf.as_ptr(), buf.len(), q)
            }),
        ));
        (api.free_instance)(null_mut());
    }
    let wrong: Vec<String> = answers
        .iter()
        .filter(|(_, s)| *s != fmi3Error)
        .map(|(f, s)| format!("{f}(NULL, ...): {}", status_name(*s)))
        .collect();
    assert!(
        st.is_null(),
        "{}: fmi3DeserializeFMUState(NULL, ...) wrote a state",
        fmu.id
    );
    assert!(
        wrong.is_empty(),
        "{}: expected fmi3Error for a NULL instance:\n{}",
        fmu.id,
        wrong.join("\n")
    );
    info(format!("{} functions refuse a NULL instance", answers.len()));
}

pub fn fmi3_reset_from_every_state_then_a_rerun_is_bit_identical(fmu: &Fmu3) {
    let h = fmu.step_size();
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) {
            continue;
        }
        let reference = run(fmu, me, 20, h);
        let states: &[State] = if me { &State::ME } else { &State::CS };
        for &state in states {
            let mut i = in_state(fmu, me, state);
            if matches!(state, StepMode | ContinuousTimeMode) {
                excite(&i);
                i.step(h);
            }
            let s = i.unary("fmi3Reset", fmu.api.reset);
            assert_eq!(s, fmi3OK, "{}: fmi3Reset in {state:?}: {}", fmu.id, i.log_text());
            i.time = 0.0;
            excite(&i);
            i.initialize();
            let again: Vec<Vec<u64>> = (0..20)
                .map(|_| {
                    i.step(h);
                    i.observe()
                })
                .collect();
            assert!(
                again == reference,
                "{}: after fmi3Reset in {state:?} ({}), a rerun differs from a run of a new instance",
                fmu.id,
                if me { "ME" } else { "CS" }
            );
        }
    }
}

/// FMI 3.0 section 2.3.1 (super state FMU State Setable): "If any function called in super
/// state FMU State Setable returns fmi3Error, the FMU enters state Terminated." So after a
/// refused call, only what Terminated allows is allowed (getters; fmi3Reset, FMU state
/// functions, fmi3FreeInstance); fmi3DoStep / fmi3EnterEventMode / fmi3Terminate are not.
/// fmi3Reset and fmi3SetFMUState bring the instance back.
pub fn fmi3_after_fmi3_error_the_instance_is_terminated_until_reset_or_set_fmu_state(fmu: &Fmu3) {
    let h = fmu.step_size();
    let api = &fmu.api;
    let mut failures = vec![];
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) {
            continue;
        }
        let what = if me { "ME" } else { "CS" };
        let running = if me { ContinuousTimeMode } else { StepMode };
        // A refused call: an unknown value reference.
        let mut i = in_state(fmu, me, running);
        let saved = fmu.can_snapshot(me).then(|| i.snapshot());
        let bad = fmu.md.unknown_vr();
        assert_eq!(
            i.set_f64(&[bad], &[1.0]),
            fmi3Error,
            "{}: setting an unknown vr",
            fmu.id
        );
        let (s, _) = i.get_f64(&fmu.md.vrs_of_type(Type::Float64));
        if s != fmi3OK {
            failures.push(format!(
                "{what}: fmi3GetFloat64 after an fmi3Error (Terminated allows getters): {}",
                status_name(s)
            ));
        }
        let s = if me {
            i.unary("fmi3EnterEventMode", api.enter_event_mode)
        } else {
            i.do_step(h).0
        };
        if s != fmi3Error {
            failures.push(format!(
                "{what}: {} after an fmi3Error in {running:?} answered {}: the FMU is Terminated then and must refuse it",
                if me { "fmi3EnterEventMode" } else { "fmi3DoStep" },
                status_name(s)
            ));
        }
        let s = i.unary("fmi3Terminate", api.terminate);
        if s != fmi3Error {
            failures.push(format!(
                "{what}: fmi3Terminate after an fmi3Error answered {}: the FMU is Terminated then",
                status_name(s)
            ));
        }
        // Back: fmi3SetFMUState of a state taken before, then steps.
        if let Some(bytes) = saved {
            let mut j = in_state(fmu, me, running);
            let _ = j.set_f64(&[bad], &[1.0]);
            let s = j.restore(&bytes);
            assert_eq!(
                s,
                fmi3OK,
                "{}: {what}: restoring a state after an fmi3Error: {}",
                fmu.id,
                j.log_text()
            );
            j.step(h);
        }
        // Back: fmi3Reset, then a whole run.
        let s = i.unary("fmi3Reset", api.reset);
        assert_eq!(
            s,
            fmi3OK,
            "{}: {what}: fmi3Reset after an fmi3Error: {}",
            fmu.id,
            i.log_text()
        );
        i.time = 0.0;
        i.initialize();
        i.step(h);
    }
    assert!(
        failures.is_empty(),
        "{}: after fmi3Error:\n{}",
        fmu.id,
        failures.join("\n")
    );
}
