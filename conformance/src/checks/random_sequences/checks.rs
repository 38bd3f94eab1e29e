//! The two checks of this room: random co-simulation and model-exchange call sequences run
//! against the FMU, and the reproducer a failing sequence leaves. Above the sequences' machinery
//! ([`super::co_simulation`], [`super::model_exchange`]) and their lines ([`super::text`]), which
//! the reproducer needs: the sequences themselves never write one.

use super::co_simulation::{CALLS, OK_CALLS, OK_STEPS, SEQUENCE_BUDGET_S, execute, note_limitations, op};
use super::model_exchange::{ME_CALLS, me_execute, me_op};
use super::{config, text};
use crate::Fmu;
use crate::me::needs_me;
use crate::outcome::{info, limitation};
use crate::state::{self, State};
use proptest::prelude::*;
use proptest::test_runner::{TestError, TestRunner};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

pub fn random_call_sequences_keep_every_fmu_conformant(fmu: &Fmu) {
    // First, so that the report shows the seed whatever happens next.
    info(crate::seed_note());
    note_limitations(fmu);
    let clock = Instant::now();
    let mut runner = TestRunner::new(config());
    let strategy = (any::<bool>(), prop::collection::vec(op(), 1..100));
    let ran = AtomicUsize::new(0);
    let result = runner.run(&strategy, |(logging_on, ops)| {
        if clock.elapsed().as_secs_f64() > SEQUENCE_BUDGET_S {
            return Ok(());
        }
        ran.fetch_add(1, Ordering::Relaxed);
        execute(fmu, logging_on, &ops)
    });
    if let Err(e) = result {
        let note = match &e {
            TestError::Fail(reason, (logging_on, ops)) => text::write(
                fmu,
                "random_call_sequences_keep_every_fmu_conformant",
                "co-simulation",
                &format!("fmi2Instantiate fmuType=CoSimulation loggingOn={logging_on}"),
                &text::record_cs(fmu, *logging_on, ops),
                reason.message(),
            ),
            TestError::Abort(_) => String::new(),
        };
        panic!("{}: {e}\n{}\n{note}", fmu.id, crate::seed_note());
    }
    let ran = ran.into_inner();
    if ran < config().cases as usize {
        limitation(format!(
            "{ran} of {} random sequences ran in the {SEQUENCE_BUDGET_S} s budget (the FMU's long steps are slow)",
            config().cases
        ));
    }
    let counts = |c: &[AtomicUsize; 8]| -> Vec<usize> { c.iter().map(|x| x.swap(0, Ordering::Relaxed)).collect() };
    let (calls, ok) = (counts(&CALLS), counts(&OK_CALLS));
    info(format!(
        "{} random sequences in {:.1} s; calls per state {:?}: {:?}, of which fmi2OK {:?}; {} steps done",
        config().cases,
        clock.elapsed().as_secs_f64(),
        state::STATES,
        calls,
        ok,
        OK_STEPS.swap(0, Ordering::Relaxed)
    ));
    // The sequences must reach the states where the interesting calls are allowed.
    let states = [
        State::Instantiated,
        State::InitializationMode,
        State::StepComplete,
        State::Terminated,
    ];
    every_state_reached(fmu, &calls, states.map(|s| (s, s as usize)));
}

pub fn random_model_exchange_call_sequences_keep_every_fmu_conformant(fmu: &Fmu) {
    needs_me(fmu);
    if fmu.me_state_codes().is_err() {
        limitation(
            "the state machine is not read from the FMU after each call (only this exporter's serialized state shows it)",
        );
    }
    if !crate::me::can_snapshot_me(fmu) {
        limitation(
            "<ModelExchange> does not declare canGetAndSetFMUstate and canSerializeFMUstate: that a refused call changes nothing is not checked",
        );
    }
    info(crate::seed_note());
    let clock = Instant::now();
    let mut runner = TestRunner::new(config());
    let strategy = prop::collection::vec(me_op(), 1..100);
    if let Err(e) = runner.run(&strategy, |ops| me_execute(fmu, &ops)) {
        let note = match &e {
            TestError::Fail(reason, ops) => text::write(
                fmu,
                "random_model_exchange_call_sequences_keep_every_fmu_conformant",
                "model-exchange",
                "fmi2Instantiate fmuType=ModelExchange",
                &text::record_me(fmu, ops),
                reason.message(),
            ),
            TestError::Abort(_) => String::new(),
        };
        panic!("{}: {e}\n{}\n{note}", fmu.id, crate::seed_note());
    }
    let calls: Vec<usize> = ME_CALLS.iter().map(|x| x.swap(0, Ordering::Relaxed)).collect();
    info(format!(
        "{} random model-exchange sequences in {:.1} s; calls per state {:?}: {:?}",
        config().cases,
        clock.elapsed().as_secs_f64(),
        crate::me::ME_STATES,
        calls
    ));
    every_state_reached(fmu, &calls, crate::me::ME_REACHABLE.map(|s| (s, s as usize)));
}

/// The random calls must have reached each of `states` (a state, its index in `calls`). On
/// another exporter's FMU a sequence ends at its first fmi2Error (see `run_ops`, `me_run_ops`):
/// a state no sequence reached is a limitation there, not a failure.
fn every_state_reached<S: std::fmt::Debug>(fmu: &Fmu, calls: &[usize], states: impl IntoIterator<Item = (S, usize)>) {
    let own = fmu.own_state_format() || crate::outcome::strict();
    for (s, i) in states {
        if !own && calls[i] == 0 {
            limitation(format!(
                "no random call was made in {s:?} (the sequences end at the FMU's first fmi2Error)"
            ));
            continue;
        }
        assert!(
            calls[i] > 0,
            "{}: no random call was made in {s:?}\n{}",
            fmu.id,
            crate::seed_note()
        );
    }
}
