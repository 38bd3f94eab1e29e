//! A component that asks to end the simulation ends the run (FMI 2.0.5 4.2.3: fmi2DoStep's
//! fmi2Discard with fmi2GetBooleanStatus(fmi2Terminated) true; FMI 3.0.2 4.2.1: fmi3DoStep's
//! `terminateSimulation`): the C Reference-FMUs' Stair, which asks at t = 9 s, beside their
//! Dahlquist. Needs `../shared/independent/reference-fmus` (v0.0.41).

// rustfmu_runner::Error is large (it carries the details of a failure), on the cold path only.
#![allow(clippy::result_large_err)]

use rustfmu_runner::fmu::Fmu;
use rustfmu_runner::isolate::Isolation;
use rustfmu_runner::{RunOptions, RunResult, Simulation};
use std::path::{Path, PathBuf};

fn reference(version: &str, name: &str) -> PathBuf {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/independent/reference-fmus")
        .join(version)
        .join(format!("{name}.fmu"));
    assert!(
        p.exists(),
        "{} is missing (the C Reference-FMUs v0.0.41 of shared/independent)",
        p.display()
    );
    p
}

/// Stair and Dahlquist of FMI `version`, in the order `order` names them, run 10 s at `step`.
fn run(version: &str, order: [&str; 2], step: f64) -> RunResult {
    run_with(version, order, step, None, &["stair.counter", "d.x"])
}

/// [`run`], each component in a child process with `isolation`, `record` recorded.
fn run_with(version: &str, order: [&str; 2], step: f64, isolation: Option<Isolation>, record: &[&str]) -> RunResult {
    let fmus = order
        .iter()
        .map(|c| {
            let name = if *c == "stair" { "Stair" } else { "Dahlquist" };
            Fmu::from_path(c, &reference(version, name)).unwrap_or_else(|e| panic!("{e}"))
        })
        .collect();
    let components = order.iter().enumerate().map(|(i, c)| (c.to_string(), i)).collect();
    let mut sim =
        Simulation::new_with("S", fmus, components, &[], Vec::new(), isolation).unwrap_or_else(|e| panic!("{e}"));
    let mut opts = RunOptions::new(10.0, step);
    opts.record = record.iter().map(|r| r.to_string()).collect();
    sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"))
}

#[test]
fn stair_asking_to_end_at_9_s_ends_the_run_there_with_its_last_row() {
    for version in ["2.0", "3.0"] {
        // Stair first: its step from 8.8 s reaches 9 s (0.2 s) or stops there (0.4 s, its last
        // successful time), and Dahlquist is stepped to it.
        for step in [0.2, 0.4] {
            let r = run(version, ["stair", "d"], step);
            let end = r.terminated.as_ref().expect("Stair asks to end the simulation");
            assert_eq!((end.component.as_str(), end.time), ("stair", 9.0), "{version} {step}");
            assert!(
                end.message
                    .contains("component 'stair' asked to terminate the simulation at t = 9 s")
                    && end.message.ends_with("the run ends there; the rows end at t = 9 s"),
                "{}",
                end.message
            );
            assert_eq!(*r.time.last().unwrap(), 9.0, "{version} {step}");
            let counter = r.column(0);
            assert_eq!(counter[counter.len() - 1], 10.0);
            assert_eq!(counter[counter.len() - 2], 9.0);
            // Dahlquist (dx/dt = -x, x(0) = 1, explicit Euler inside) reached 9 s too.
            let x = *r.column(1).last().unwrap();
            assert!(x > 0.0 && x < (-8.8f64).exp(), "{x}");
        }
        // Stair after Dahlquist, 0.4 s: Dahlquist is at 9.2 s when Stair stops at 9 s, and is not
        // taken back; the rows end at 8.8 s, and the message says why.
        let r = run(version, ["d", "stair"], 0.4);
        let end = r.terminated.as_ref().expect("Stair asks to end the simulation");
        assert_eq!(*r.time.last().unwrap(), 8.8);
        assert!(
            end.message.contains("the rows end at t = 8.8 s (no row at t = 9 s"),
            "{}",
            end.message
        );
    }
}

#[test]
fn an_isolated_stair_asking_to_end_ends_the_run_in_the_step_it_asked_in() {
    // An unclocked isolated component's step is not waited for when it is sent; its request to
    // end comes back once every component's step is sent, and ends the run in that step as in
    // process: no row after 9 s, even where nothing of Stair is read at the points after it.
    let isolated = || {
        Some(Isolation {
            worker: env!("CARGO_BIN_EXE_rustfmu-runner").into(),
            timeout: None,
        })
    };
    for version in ["2.0", "3.0"] {
        for record in [&["stair.counter", "d.x"][..], &["d.x"][..]] {
            // Both at 9 s after the step from 8.8 s: the same rows as in process.
            let here = run_with(version, ["stair", "d"], 0.2, None, record);
            let there = run_with(version, ["stair", "d"], 0.2, isolated(), record);
            assert_eq!(
                (&there.time, &there.values),
                (&here.time, &here.values),
                "{version} {record:?}"
            );
            let end = there.terminated.as_ref().expect("Stair asks to end the simulation");
            assert_eq!(
                (end.component.as_str(), end.time),
                ("stair", 9.0),
                "{version} {record:?}"
            );
            // Stair stops at 9 s in the step from 8.8 s to 9.2 s, Dahlquist (stepped at once, in
            // its process) reaches 9.2 s: no time both are at, the rows end at 8.8 s.
            let there = run_with(version, ["stair", "d"], 0.4, isolated(), record);
            let end = there.terminated.as_ref().expect("Stair asks to end the simulation");
            assert_eq!(
                *there.time.last().unwrap(),
                8.8,
                "{version} {record:?}: {}",
                end.message
            );
            assert!(
                end.message.contains("the rows end at t = 8.8 s (no row at t = 9 s"),
                "{version} {record:?}: {}",
                end.message
            );
        }
    }
}
