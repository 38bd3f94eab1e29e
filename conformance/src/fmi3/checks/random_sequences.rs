//! FMI 3.0 random call sequences against a model of the state machine, generated from the seed
//! [`crate::seed`] (`$RUSTFMU_SEED`, else drawn), which the report and a failure message print.

use super::*;
use crate::replay::write::Recorded;
use crate::replay::{Expected, Line, ReplayReport, replay_line};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

// ---------------------------------------------------------------------------------------------
// Random call sequences

#[derive(Debug, Clone, Copy)]
enum Op {
    EnterInit,
    ExitInit,
    Step,
    EnterEventMode,
    UpdateDiscrete,
    EnterCtm,
    SetInput(u8),
    GetAll,
    Terminate,
    Reset,
    SaveState,
    RestoreState,
    BadSet,
}

/// The state the standard puts the instance in after `op` returned fmi3OK (None: refused).
/// `cs_events`: a co-simulation instance made with eventModeUsed (an FMU with clocks), which may
/// enter Event Mode from Step Mode and update its discrete states there.
fn model(state: State, me: bool, cs_events: bool, op: Op) -> Option<State> {
    use State::*;
    match (op, state) {
        (Op::EnterEventMode, StepMode) if cs_events => Some(EventMode),
        (Op::UpdateDiscrete, EventMode) if cs_events => Some(EventMode),
        (Op::EnterInit, Instantiated) => Some(InitializationMode),
        (Op::ExitInit, InitializationMode) => Some(if me { EventMode } else { StepMode }),
        (Op::Step, StepMode) if !me => Some(StepMode),
        (Op::Step, ContinuousTimeMode) if me => Some(ContinuousTimeMode),
        (Op::EnterEventMode, ContinuousTimeMode) if me => Some(EventMode),
        (Op::UpdateDiscrete, EventMode) if me => Some(EventMode),
        (Op::EnterCtm, EventMode) if me => Some(ContinuousTimeMode),
        (Op::SetInput(_), Instantiated | InitializationMode | EventMode | ContinuousTimeMode | StepMode) => Some(state),
        (Op::GetAll, InitializationMode | EventMode | ContinuousTimeMode | StepMode | Terminated) => Some(state),
        (Op::Terminate, EventMode | ContinuousTimeMode | StepMode) => Some(Terminated),
        (Op::Reset, _) => Some(Instantiated),
        (Op::SaveState, _) => Some(state),
        (Op::RestoreState, _) => None, // depends on the saved state: handled in the loop
        (Op::BadSet, _) => None,
        _ => None,
    }
}

/// A random call.
fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        Just(Op::EnterInit),
        Just(Op::ExitInit),
        Just(Op::Step),
        Just(Op::Step),
        Just(Op::EnterEventMode),
        Just(Op::UpdateDiscrete),
        Just(Op::EnterCtm),
        any::<u8>().prop_map(Op::SetInput),
        Just(Op::GetAll),
        Just(Op::Terminate),
        Just(Op::Reset),
        Just(Op::SaveState),
        Just(Op::RestoreState),
        Just(Op::BadSet),
    ]
}

pub fn fmi3_random_call_sequences_never_crash_and_keep_status_consistent(fmu: &Fmu3) {
    use proptest::test_runner::{Config, TestRunner};
    // First, so that the report shows the seed whatever happens next.
    info(crate::seed_note());
    let cases = crate::random_sequences().clamp(1, 2000) / 4 + 1;

    let strategy = (any::<bool>(), proptest::collection::vec(op(), 1..40));
    // The RNG seeded from crate::seed ($RUSTFMU_SEED, else drawn once per process): the same
    // seed and number of sequences repeat the same calls.
    let mut runner = TestRunner::new(crate::seeded(Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    }));
    let result = runner.run(&strategy, |(me_pick, ops)| {
        let me = match (fmu.md.cs.is_some(), fmu.md.me.is_some()) {
            (true, true) => me_pick,
            (false, true) => true,
            _ => false,
        };
        run_sequence(fmu, me, &ops, &mut |_, _, _, _, _| Ok(()))
    });
    if let Err(e) = result {
        let note = match &e {
            proptest::test_runner::TestError::Fail(reason, (me_pick, ops)) => {
                let me = match (fmu.md.cs.is_some(), fmu.md.me.is_some()) {
                    (true, true) => *me_pick,
                    (false, true) => true,
                    _ => false,
                };
                write_reproducer(fmu, me, ops, reason.message())
            }
            proptest::test_runner::TestError::Abort(_) => String::new(),
        };
        panic!("{}: random call sequence: {e}\n{}\n{note}", fmu.id, crate::seed_note());
    }
    info(format!("{cases} random call sequences"));
}

/// What [`run_sequence`] tells about each call it made, before it checks the answer: the call's
/// index in the sequence, the call, the status, what the standard requires there, the instance.
type Hook<'h> = &'h mut dyn FnMut(usize, &Op, fmi3Status, Expected, &Inst) -> Result<(), TestCaseError>;

/// One sequence on a new instance (`me`: model exchange), its calls checked against the model of
/// the state machine.
// Over ~150 lines: the shadow of the state machine and the loop that drives it share the locals the
// shadow's rules read.
fn run_sequence(fmu: &Fmu3, me: bool, ops: &[Op], hook: Hook) -> Result<(), TestCaseError> {
    let snap = fmu.can_snapshot(me);
    let mut inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
    let api = &fmu.api;
    let mut state = State::Instantiated;
    let mut saved: Option<(Vec<u8>, State, f64)> = None;
    let inputs = float_inputs(fmu);
    // Every Float64 but the clocked ones, every element of the arrays.
    let all_f64: Vec<&Variable> = fmu
        .md
        .variables
        .iter()
        .filter(|v| v.ty == Type::Float64 && v.clocks.is_empty())
        .collect();
    let h = fmu.step_size();
    // After an fmi3Error the standard puts the FMU in Terminated (checked on its own by
    // fmi3_after_fmi3_error_the_instance_is_terminated_until_reset_or_set_fmu_state):
    // until fmi3Reset or fmi3SetFMUState, calls are only required not to crash nor answer
    // fmi3Fatal.
    let mut errored = false;
    for (k, op) in ops.iter().enumerate() {
        if errored && !matches!(op, Op::Reset | Op::RestoreState) {
            let s = match op {
                Op::GetAll => inst.get_f64_of(&all_f64).0,
                Op::EnterInit => inst.enter_init(0.0),
                Op::ExitInit => inst.exit_init(),
                // SAFETY: the standard's function from the library the FMU keeps loaded, on
                // this instance's live handle; each pointer we pass is to a live local of at
                // least the length passed (or is an FMU state, the FMU's own handle).
                Op::Step if me => inst.call("fmi3CompletedIntegratorStep", |c| unsafe {
                    crate::guard::fill_integrator_step3(&mut 0, &mut 0, |qa, qb| {
                        (api.completed_integrator_step)(c, true, qa, qb)
                    })
                }),
                Op::Step => inst.do_step(h).0,
                Op::EnterEventMode => inst.unary("fmi3EnterEventMode", api.enter_event_mode),
                Op::EnterCtm => inst.unary("fmi3EnterContinuousTimeMode", api.enter_continuous_time_mode),
                Op::Terminate => inst.unary("fmi3Terminate", api.terminate),
                // Not called in this state: nothing to record.
                _ => continue,
            };
            hook(k, op, s, Expected::ANY, &inst)?;
            prop_assert!(
                s != fmi3Fatal,
                "{}: ops {:?}: fmi3Fatal after an fmi3Error: {}",
                fmu.id,
                &ops[..=k],
                inst.log_text()
            );
            continue;
        }
        if matches!(op, Op::GetAll) && state == State::Instantiated {
            // Only start values can be read before initialization (FMI 3.0.2).
            let s = inst.get_f64(&start_vrs(fmu, Type::Float64)).0;
            hook(k, op, s, Expected::OK, &inst)?;
            prop_assert!(
                s == fmi3OK,
                "{}: ops {:?}: fmi3GetFloat64 of the Float64 variables with a start value in Instantiated: {}: {}",
                fmu.id,
                &ops[..=k],
                status_name(s),
                inst.log_text()
            );
            continue;
        }
        let expected = model(state, me, !me && fmu.has_clocks(), *op);
        let s = match op {
            Op::EnterInit => inst.enter_init(0.0),
            Op::ExitInit => inst.exit_init(),
            Op::Step if me => {
                if state == State::ContinuousTimeMode {
                    euler_step(&mut inst, h);
                    fmi3OK
                } else {
                    // SAFETY: the standard's function from the library the FMU keeps loaded, on
                    // this instance's live handle; each pointer we pass is to a live local of
                    // at least the length passed (or is an FMU state, the FMU's own handle).
                    inst.call("fmi3CompletedIntegratorStep", |c| unsafe {
                        crate::guard::fill_integrator_step3(&mut 0, &mut 0, |qa, qb| {
                            (api.completed_integrator_step)(c, true, qa, qb)
                        })
                    })
                }
            }
            Op::Step => inst.do_step(h).0,
            Op::EnterEventMode => inst.unary("fmi3EnterEventMode", api.enter_event_mode),
            Op::UpdateDiscrete => {
                let mut f = [0u8; 5];
                let mut t = 0.0;
                // SAFETY: the standard's function from the library the FMU keeps loaded, on
                // this instance's live handle; each pointer we pass is to a live local of at
                // least the length passed (or is an FMU state, the FMU's own handle).
                inst.call("fmi3UpdateDiscreteStates", |c| unsafe {
                    crate::guard::fill_outputs("fmi3UpdateDiscreteStates", &mut f, &mut t, |[a, b, cc, d, e], t| {
                        (api.update_discrete_states)(c, a, b, cc, d, e, t)
                    })
                })
            }
            Op::EnterCtm => inst.unary("fmi3EnterContinuousTimeMode", api.enter_continuous_time_mode),
            // (An array input: every element set to the value.)
            Op::SetInput(x) => match inputs.get(*x as usize % inputs.len().max(1)) {
                Some(v) => inst.set_f64(&[v.vr], &vec![(*x as f64 - 128.0) / 256.0; fmu.element_count(v)]),
                None => inst.set_f64(&[], &[]),
            },
            Op::GetAll => inst.get_f64_of(&all_f64).0,
            Op::Terminate => inst.unary("fmi3Terminate", api.terminate),
            Op::Reset => {
                inst.time = 0.0;
                inst.unary("fmi3Reset", api.reset)
            }
            Op::SaveState => {
                if snap {
                    saved = Some((inst.snapshot(), state, inst.time));
                }
                fmi3OK
            }
            Op::RestoreState => match &saved {
                Some((b, st, t)) => {
                    let s = inst.restore(b);
                    hook(k, op, s, Expected::OK, &inst)?;
                    prop_assert_eq!(
                        s,
                        fmi3OK,
                        "{}: restoring a saved state (op {}): {}",
                        fmu.id,
                        k,
                        inst.log_text()
                    );
                    state = *st;
                    inst.time = *t;
                    errored = false;
                    continue;
                }
                None => continue,
            },
            Op::BadSet => {
                let vr = fmu.md.unknown_vr();
                let s = inst.set_f64(&[vr], &[1.0]);
                hook(k, op, s, Expected::ERROR, &inst)?;
                prop_assert_eq!(
                    s,
                    fmi3Error,
                    "{}: op {}: setting an unknown vr in {:?}",
                    fmu.id,
                    k,
                    state
                );
                errored = true;
                continue;
            }
        };
        let standard = if expected.is_some() {
            Expected::OK_OR_WARNING
        } else {
            Expected::ERROR
        };
        hook(k, op, s, standard, &inst)?;
        prop_assert!(
            s != fmi3Fatal,
            "{}: op {} {:?} in {:?}: fmi3Fatal: {}",
            fmu.id,
            k,
            op,
            state,
            inst.log_text()
        );
        match expected {
            Some(next) => {
                prop_assert!(
                    s == fmi3OK || s == fmi3Warning,
                    "{}: ops {:?}: op {} {:?} in {:?} answered {}, the standard allows it: {}",
                    fmu.id,
                    &ops[..=k],
                    k,
                    op,
                    state,
                    status_name(s),
                    inst.log_text()
                );
                state = next;
                if matches!(op, Op::Reset) {
                    errored = false;
                }
            }
            None => {
                errored = true;
                // A call the state machine does not allow: FMI 3.0.2 §2.2.4 requires fmi3Error
                // only "when detecting" it; judged on this exporter's FMUs and under --strict
                // (the state-machine check warns about it on any FMU).
                if !(fmu.own_state_format() || crate::outcome::strict()) {
                    continue;
                }
                prop_assert_eq!(
                    s,
                    fmi3Error,
                    "{}: ops {:?}: op {} {:?} in {:?} answered {}, the standard does not allow it",
                    fmu.id,
                    &ops[..=k],
                    k,
                    op,
                    state,
                    status_name(s)
                );
            }
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Reproducers (crate::replay): a call as a line and back

/// The line of a call. Some are several calls (conformance/README.md, "Reproducers"): a step of
/// model exchange in Continuous-Time Mode is an explicit Euler step of the FMU's step size, then
/// fmi3CompletedIntegratorStep; fmi3SerializeFMUState keeps the bytes of the FMU state (got,
/// serialized, freed) that fmi3DeserializeFMUState restores (deserialized, set, freed).
fn line_of(me: bool, op: &Op) -> String {
    match op {
        Op::EnterInit => "fmi3EnterInitializationMode".into(),
        Op::ExitInit => "fmi3ExitInitializationMode".into(),
        Op::Step if me => "fmi3CompletedIntegratorStep".into(),
        Op::Step => "fmi3DoStep".into(),
        Op::EnterEventMode => "fmi3EnterEventMode".into(),
        Op::UpdateDiscrete => "fmi3UpdateDiscreteStates".into(),
        Op::EnterCtm => "fmi3EnterContinuousTimeMode".into(),
        Op::SetInput(x) => format!("fmi3SetFloat64 input={x}"),
        Op::GetAll => "fmi3GetFloat64 all".into(),
        Op::Terminate => "fmi3Terminate".into(),
        Op::Reset => "fmi3Reset".into(),
        Op::SaveState => "fmi3SerializeFMUState".into(),
        Op::RestoreState => "fmi3DeserializeFMUState".into(),
        Op::BadSet => "fmi3SetFloat64 unknownVr".into(),
    }
}

fn op_of(l: &Line) -> Result<Op, String> {
    Ok(match l.function.as_str() {
        "fmi3EnterInitializationMode" => Op::EnterInit,
        "fmi3ExitInitializationMode" => Op::ExitInit,
        "fmi3CompletedIntegratorStep" | "fmi3DoStep" => Op::Step,
        "fmi3EnterEventMode" => Op::EnterEventMode,
        "fmi3UpdateDiscreteStates" => Op::UpdateDiscrete,
        "fmi3EnterContinuousTimeMode" => Op::EnterCtm,
        "fmi3SetFloat64" if l.words.iter().any(|w| w == "unknownVr") => Op::BadSet,
        "fmi3SetFloat64" => Op::SetInput(l.parse("input")?),
        "fmi3GetFloat64" => Op::GetAll,
        "fmi3Terminate" => Op::Terminate,
        "fmi3Reset" => Op::Reset,
        "fmi3SerializeFMUState" => Op::SaveState,
        "fmi3DeserializeFMUState" => Op::RestoreState,
        f => return Err(l.error(format!("{f} is no call of the FMI 3.0 random sequences"))),
    })
}

fn instantiate_line(me: bool) -> &'static str {
    if me {
        "fmi3InstantiateModelExchange"
    } else {
        "fmi3InstantiateCoSimulation"
    }
}

/// Runs the failing sequence once more, recording its calls, and writes its reproducer; the
/// sentence for the failure message.
fn write_reproducer(fmu: &Fmu3, me: bool, ops: &[Op], failure: &str) -> String {
    let mut calls = vec![];
    let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        run_sequence(fmu, me, ops, &mut |_, op, status, expected, _| {
            calls.push(Recorded {
                call: line_of(me, op),
                expected,
                status,
            });
            Ok(())
        })
    }));
    let interface = if me { "model-exchange" } else { "co-simulation" };
    let about = [
        format!("FMU: {} (model {}, FMI 3.0 {interface})", fmu.archive.display(), fmu.id),
        format!(
            "check: fmi3_random_call_sequences_never_crash_and_keep_status_consistent; {}",
            crate::seed_note()
        ),
    ];
    let text = crate::replay::write::reproducer_text(&about, instantiate_line(me), &calls, failure);
    let written = crate::replay::write::write_reproducer(&format!("{}-fmi3-{interface}", fmu.id), &text);
    crate::replay::write::reproducer_note(written, &fmu.archive)
}

/// Replays the lines of a reproducer (the first one fmi3InstantiateCoSimulation or
/// fmi3InstantiateModelExchange) on `fmu`.
pub fn replay(fmu: &Fmu3, lines: &[Line], out: &mut dyn FnMut(&str)) -> Result<ReplayReport, String> {
    let me = lines[0].function == instantiate_line(true);
    if me && fmu.md.me.is_none() || !me && fmu.md.cs.is_none() {
        return Err(lines[0].error(format!("{} does not declare that interface", fmu.id)));
    }
    let calls = &lines[1..];
    let ops = calls.iter().map(op_of).collect::<Result<Vec<_>, _>>()?;
    let mut report = ReplayReport::default();
    let head = format!(
        "replaying {} calls on {} (FMI 3.0 {})",
        calls.len(),
        fmu.id,
        if me { "model exchange" } else { "co-simulation" }
    );
    out(&head);
    report.lines.push(head);
    crate::replay_calls::next_line(calls, 0);
    let result = run_sequence(fmu, me, &ops, &mut |k, op, status, standard, inst| {
        let line = &calls[k];
        let expected = line.expected.unwrap_or(standard);
        let text = replay_line(line, &line_of(me, op), status, expected);
        out(&text);
        report.lines.push(text);
        if !expected.contains(status) {
            return Err(TestCaseError::fail(format!(
                "line {}: {} answered {}, the file expects {expected}; the FMU's log: {}",
                line.number,
                line_of(me, op),
                crate::replay::status_word(status),
                inst.log_text()
            )));
        }
        crate::replay_calls::next_line(calls, k + 1);
        Ok(())
    });
    report.difference = result.err().map(|e| match e {
        TestCaseError::Fail(reason) | TestCaseError::Reject(reason) => reason.message().to_string(),
    });
    Ok(report)
}

/// A reproducer of one random sequence (co-simulation, or `me`: model exchange) drawn from
/// `seed`, written as a failing sequence's would be: for tests of the replay on an FMU the
/// sequence passes on.
pub fn reproducer_of_a_random_sequence(fmu: &Fmu3, me: bool, seed: u64) -> String {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::{Config, RngSeed, TestRunner};
    let mut runner = TestRunner::new(Config {
        rng_seed: RngSeed::Fixed(seed),
        ..Config::default()
    });
    let ops = proptest::collection::vec(op(), 20..60)
        .new_tree(&mut runner)
        .map(|t| t.current())
        .unwrap_or_default();
    let mut calls = vec![];
    let _ = run_sequence(fmu, me, &ops, &mut |_, op, status, expected, _| {
        calls.push(Recorded {
            call: line_of(me, op),
            expected,
            status,
        });
        Ok(())
    });
    let about = [format!(
        "FMU: {} (a test's sequence, seed {seed})",
        fmu.archive.display()
    )];
    crate::replay::write::reproducer_text(&about, instantiate_line(me), &calls, "none (the sequence of a test)")
}
