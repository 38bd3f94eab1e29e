//! FMI 3.0 random call sequences against a model of the state machine, generated from the seed
//! [`crate::seed`] (`$RUSTFMU_SEED`, else drawn), which the report and a failure message print.

use super::*;

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

// Over ~150 lines: the shadow of the state machine and the loop that drives it share the locals the
// shadow's rules read.
pub fn fmi3_random_call_sequences_never_crash_and_keep_status_consistent(fmu: &Fmu3) {
    use proptest::prelude::*;
    use proptest::test_runner::{Config, TestRunner};
    // First, so that the report shows the seed whatever happens next.
    info(crate::seed_note());
    let cases = crate::random_sequences().clamp(1, 2000) / 4 + 1;
    let op = prop_oneof![
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
    ];
    let strategy = (any::<bool>(), proptest::collection::vec(op, 1..40));
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
                        (api.completed_integrator_step)(c, true, &mut 0, &mut 0)
                    }),
                    Op::Step => inst.do_step(h).0,
                    Op::EnterEventMode => inst.unary("fmi3EnterEventMode", api.enter_event_mode),
                    Op::EnterCtm => inst.unary("fmi3EnterContinuousTimeMode", api.enter_continuous_time_mode),
                    Op::Terminate => inst.unary("fmi3Terminate", api.terminate),
                    _ => fmi3Error,
                };
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
                            (api.completed_integrator_step)(c, true, &mut 0, &mut 0)
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
                        let [a, b, cc, d, e] = &mut f;
                        (api.update_discrete_states)(c, a, b, cc, d, e, &mut t)
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
    });
    if let Err(e) = result {
        panic!("{}: random call sequence: {e}\n{}", fmu.id, crate::seed_note());
    }
    info(format!("{cases} random call sequences"));
}
