//! FMI 3.0 Scheduled Execution components in the runner (FMI 3.0.2, chapter 5; `fmi3/scheduled.rs`):
//! the C Reference-FMUs' Clocks (Scheduled Execution only) alone against the model's own
//! definition; our Clocks and our SampledController (closing the Pendulum's loop), each run in
//! Scheduled Execution and in event-mode co-simulation, row for row; an SSD's
//! `implementation="ScheduledExecution"`; the refusal of a component without it.
//! Needs target/fmu (Pendulum, Clocks, SampledController: `cargo fmu build`) and the C
//! Reference-FMUs of ../shared/independent.

// rustfmu_runner::Error is large (it carries the details of a failure), on the cold path only.
#![allow(clippy::result_large_err)]

mod support;

use rustfmu_runner::{RunOptions, RunResult, Simulation};
use std::path::{Path, PathBuf};
use support::{COUNTERS, archive, first_difference, ours, system, theirs, two_clocks_ssp};

fn run(sim: &mut Simulation, stop: f64, step: f64, record: &[&str]) -> RunResult {
    let mut opts = RunOptions::new(stop, step);
    opts.record = record.iter().map(|r| r.to_string()).collect();
    sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"))
}

#[test]
fn the_reference_clocks_alone_runs_its_partitions_at_their_ticks_as_the_model_defines_them() {
    // Clocks (C, v0.0.41) declares only <ScheduledExecution>: the runner runs it so.
    for step in [1.0, 0.5, 0.25] {
        let mut sim = system(&[("clocks", &theirs("3.0", "Clocks"))], &[], Vec::new());
        assert!(sim.is_scheduled("clocks"));
        let record: Vec<String> = COUNTERS.iter().map(|v| format!("clocks.{v}")).collect();
        let record: Vec<&str> = record.iter().map(String::as_str).collect();
        let r = run(&mut sim, 10.0, step, &record);
        let n = (10.0 / step) as usize;
        assert_eq!(
            r.time,
            (0..=n).map(|k| k as f64 * step).collect::<Vec<_>>(),
            "step {step}"
        );
        for (k, &t) in r.time.iter().enumerate() {
            // The model (its model.c): inClock1 (constant, 1 s, priority 0) counts its ticks at
            // 0, 1, ..., and at t = 4 gives the countdown inClock3 the interval 0: inClock3 ticks
            // once, at 4, after inClock1's partition, and sets output3 to 1000. inClock2 is
            // triggered, and nothing triggers it here.
            let ticks1 = t.floor() + 1.0;
            let ticks3 = if t >= 4.0 { 1.0 } else { 0.0 };
            let want = [ticks1, 0.0, ticks3, ticks1 + ticks3, 0.0, 1000.0 * ticks3];
            let got: Vec<f64> = (0..COUNTERS.len()).map(|i| r.column(i)[k]).collect();
            assert_eq!(got, want, "t = {t}, step {step}: {COUNTERS:?}");
        }
    }
}

#[test]
fn our_clocks_in_scheduled_execution_equals_its_event_mode_co_simulation_row_for_row() {
    // Our Clocks offers both; its countdown inClock3 ticks 0.5 s after inClock1's tick at 4 (a
    // communication point of its own).
    let record: Vec<String> = ["a", "b"]
        .iter()
        .flat_map(|c| COUNTERS.iter().map(move |v| format!("{c}.{v}")))
        .collect();
    let record: Vec<&str> = record.iter().map(String::as_str).collect();
    let runs: Vec<RunResult> = ["CoSimulation", "ScheduledExecution"]
        .iter()
        .map(|implementation| {
            let ssp = two_clocks_ssp(implementation, implementation);
            let mut sim = Simulation::from_ssp(&ssp).unwrap_or_else(|e| panic!("{e}"));
            std::fs::remove_dir_all(ssp.parent().unwrap()).ok();
            let scheduled = *implementation == "ScheduledExecution";
            assert_eq!((sim.is_scheduled("a"), sim.is_scheduled("b")), (scheduled, scheduled));
            run(&mut sim, 10.0, 1.0, &record)
        })
        .collect();
    let (event_mode, scheduled) = (&runs[0], &runs[1]);
    assert_eq!(first_difference(scheduled, event_mode), None);
    assert!(scheduled.time.contains(&4.5), "{:?}", scheduled.time);
    // Something went through the clock connection: b's inClock2 ticked and took a's output3.
    let col = |n: &str| scheduled.column(record.iter().position(|r| *r == n).unwrap());
    assert!(
        col("b.inClock2Ticks").last().unwrap() > &0.0,
        "{:?}",
        col("b.inClock2Ticks")
    );
    assert!(col("b.result2").last().unwrap() >= &1000.0, "{:?}", col("b.result2"));
}

#[test]
fn the_sampled_controller_in_scheduled_execution_closes_the_pendulum_loop_as_in_event_mode() {
    for step in [1e-3, 1e-2] {
        let (mut a, record) = support::sampled_loop(None);
        let (mut b, _) = support::sampled_loop(None);
        b.use_scheduled_execution("controller").unwrap();
        let event_mode = run(&mut a, 2.0, step, &record);
        let scheduled = run(&mut b, 2.0, step, &record);
        assert_eq!(first_difference(&scheduled, &event_mode), None, "step {step}");
        // The loop is closed: the controller's torque moves and the pendulum is brought back.
        let m1 = scheduled.column(4);
        assert!(m1.iter().any(|x| x.abs() > 1e-3), "{m1:?}");
        let alpha1 = scheduled.column(0);
        assert!(alpha1.last().unwrap().abs() < 0.1 * alpha1[0].abs(), "{alpha1:?}");
    }
    // A tick inside a communication step is refused as in event mode (Ts = 10 ms, step 15 ms).
    let (mut b, record) = support::sampled_loop(None);
    b.use_scheduled_execution("controller").unwrap();
    let mut opts = RunOptions::new(0.1, 0.015);
    opts.record = record.iter().map(|r| r.to_string()).collect();
    let f = b.run(&opts, &mut |_, _| {}).expect_err("a tick inside a step");
    assert!(
        f.error.message.contains("clock 'sample' ticks at t = 0.01"),
        "{}",
        f.error.message
    );
}

/// An SSP file of the one component `name` from `fmu`, with `implementation` on it.
fn one_component_ssp(dir: &str, name: &str, fmu: &Path, implementation: &str) -> PathBuf {
    let ssd = format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
  xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" version="2.0" name="One">
<ssd:System name="One"><ssd:Elements>
<ssd:Component name="{name}" source="resources/X.fmu" type="application/x-fmu-sharedlibrary" implementation="{implementation}"/>
</ssd:Elements></ssd:System></ssd:SystemStructureDescription>"#
    );
    archive(dir, "One", &ssd, &[("X", fmu)])
}

#[test]
fn an_ssd_asking_for_scheduled_execution_gets_it_and_a_component_without_it_is_refused_by_name() {
    let ssp = one_component_ssp("clocks", "clocks", &ours("Clocks", true), "ScheduledExecution");
    let sim = Simulation::from_ssp(&ssp).unwrap_or_else(|e| panic!("{e}"));
    assert!(sim.is_scheduled("clocks"));
    let ssp = one_component_ssp("clocks-cs", "clocks", &ours("Clocks", true), "CoSimulation");
    assert!(!Simulation::from_ssp(&ssp).unwrap().is_scheduled("clocks"));
    std::fs::remove_dir_all(ssp.parent().unwrap()).ok();

    let ssp = one_component_ssp("pendulum", "plant", &ours("Pendulum", true), "ScheduledExecution");
    let e = Simulation::from_ssp(&ssp)
        .err()
        .expect("the Pendulum has no Scheduled Execution");
    assert_eq!(e.component.as_deref(), Some("plant"));
    assert!(
        e.message.contains(
            "component 'plant' (Pendulum): no Scheduled Execution: its modelDescription.xml has no <ScheduledExecution>"
        ),
        "{}",
        e.message
    );
    std::fs::remove_dir_all(ssp.parent().unwrap()).ok();
    // The same through the API; the component keeps running as before.
    let mut sim = system(&[("plant", &ours("Pendulum", true))], &[], Vec::new());
    let e = sim.use_scheduled_execution("plant").expect_err("refused");
    assert!(
        e.message
            .contains("component 'plant' (Pendulum): no Scheduled Execution"),
        "{}",
        e.message
    );
    assert!(!sim.is_scheduled("plant"));
    let r = run(&mut sim, 0.01, 1e-3, &["plant.alpha1"]);
    assert_eq!(r.time.len(), 11);
}

#[test]
fn an_ssd_asking_for_co_simulation_of_an_fmu_of_scheduled_execution_only_is_refused() {
    // SSP (SystemStructureDescription.xsd, ssd:Component/@implementation): "It is an error if the
    // specified type of FMU implementation is not present in the FMU". The C Clocks has only
    // <ScheduledExecution>: with "any" the runner runs it so; with "CoSimulation" it refuses.
    let ssp = one_component_ssp("c-clocks-any", "clocks", &theirs("3.0", "Clocks"), "any");
    assert!(
        Simulation::from_ssp(&ssp)
            .unwrap_or_else(|e| panic!("{e}"))
            .is_scheduled("clocks")
    );
    std::fs::remove_dir_all(ssp.parent().unwrap()).ok();
    let ssp = one_component_ssp("c-clocks-cs", "clocks", &theirs("3.0", "Clocks"), "CoSimulation");
    let e = Simulation::from_ssp(&ssp)
        .err()
        .expect("the C Clocks has no co-simulation");
    assert_eq!(e.component.as_deref(), Some("clocks"));
    assert!(
        e.message
            .contains("component 'clocks' (Clocks): implementation=\"CoSimulation\", but its modelDescription.xml has no <CoSimulation>"),
        "{}",
        e.message
    );
    std::fs::remove_dir_all(ssp.parent().unwrap()).ok();
}
