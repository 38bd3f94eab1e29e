//! FMI 3.0 clocks and Event Mode with each component in a child process of its own
//! (`--isolate`, `src/isolate/`): the same systems give the same rows as in this process, bit for
//! bit — the SampledController closing the Pendulum's loop (a periodic clock; also with Event
//! Mode), two of our Clocks connected by a clock, the LS-BUS networked pendulum (clock
//! connections and Binary frames), the BouncingBall's events and early returns (two of them: one
//! set back with its clocks); and a crash or hang of an isolated event-mode component fails the
//! run naming the component, the call and the time. Scheduled Execution components too: the
//! child's importer activates the partitions (ACTIVATE on the wire), with the same rows.
//! Needs target/fmu/fmi3 (Pendulum, SampledController, Clocks, BouncingBall, VanDerPol, the CAN
//! FMUs and NetworkedPendulum.ssp: `cargo fmu build`).

// rustfmu_runner::Error is large (it carries the details of a failure), on the cold path only.
#![allow(clippy::result_large_err)]

mod support;

use rustfmu_runner::isolate::Isolation;
use rustfmu_runner::{RunOptions, RunResult, Simulation, Value};
use std::time::Duration;
use support::{COUNTERS, first_difference, ours, sampled_loop, system_isolated, theirs, two_clocks_ssp};

/// Each component in a child process of the runner built with these tests.
fn isolation(timeout: Option<Duration>) -> Isolation {
    Isolation {
        worker: env!("CARGO_BIN_EXE_rustfmu-runner").into(),
        timeout,
    }
}

fn run(sim: &mut Simulation, stop: f64, step: f64, record: &[&str]) -> RunResult {
    let mut opts = RunOptions::new(stop, step);
    opts.record = record.iter().map(|r| r.to_string()).collect();
    sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"))
}

/// `make(isolation)` run in this process and isolated: the same rows, bit for bit; the rows.
fn same_rows_isolated(
    what: &str,
    stop: f64,
    step: f64,
    record: &[&str],
    make: impl Fn(Option<Isolation>) -> Simulation,
) -> RunResult {
    let here = run(&mut make(None), stop, step, record);
    let there = run(&mut make(Some(isolation(None))), stop, step, record);
    assert_eq!(
        first_difference(&there, &here),
        None,
        "{what}: isolated against in process"
    );
    here
}

#[test]
fn the_clocked_sampled_controller_loop_isolated_gives_the_in_process_rows_bit_for_bit() {
    for events in [false, true] {
        let (_, record) = sampled_loop(None);
        let r = same_rows_isolated("sampled loop", 0.5, 1e-3, &record, |iso| {
            let (mut sim, _) = sampled_loop(iso);
            if events {
                sim.use_event_mode("controller").unwrap_or_else(|e| panic!("{e}"));
            }
            sim
        });
        // The loop is closed: the controller's torque moves.
        assert!(r.column(4).iter().any(|x| x.abs() > 1e-3), "{:?}", r.column(4));
    }
}

#[test]
fn two_clocks_connected_by_a_clock_isolated_give_the_in_process_rows_bit_for_bit() {
    let record: Vec<String> = ["a", "b"]
        .iter()
        .flat_map(|c| COUNTERS.iter().map(move |v| format!("{c}.{v}")))
        .collect();
    let record: Vec<&str> = record.iter().map(String::as_str).collect();
    let ssp = two_clocks_ssp("isolated", "CoSimulation");
    let r = same_rows_isolated("two clocks", 10.0, 1.0, &record, |iso| {
        match iso {
            Some(iso) => Simulation::from_ssp_isolated(&ssp, iso),
            None => Simulation::from_ssp(&ssp),
        }
        .unwrap_or_else(|e| panic!("{e}"))
    });
    std::fs::remove_dir_all(ssp.parent().unwrap()).ok();
    // The countdown's tick at 4.5 s is a point of its own, and b's inClock2 ticked through the
    // clock connection and took a's output3.
    assert!(r.time.contains(&4.5), "{:?}", r.time);
    let col = |n: &str| r.column(record.iter().position(|x| *x == n).unwrap());
    assert!(
        *col("b.inClock2Ticks").last().unwrap() > 0.0,
        "{:?}",
        col("b.inClock2Ticks")
    );
    assert!(*col("b.result2").last().unwrap() >= 1000.0, "{:?}", col("b.result2"));
}

#[test]
fn the_ls_bus_networked_pendulum_isolated_gives_the_in_process_rows_bit_for_bit() {
    let ssp = ours("Pendulum", true).with_file_name("NetworkedPendulum.ssp");
    assert!(
        ssp.exists(),
        "{} is missing: `cargo fmu build` writes it",
        ssp.display()
    );
    let record = [
        "pendulum.alpha1",
        "pendulum.alpha2",
        "motor1.tau",
        "motor2.tau",
        "drive1.U",
        "drive2.U",
    ];
    let r = same_rows_isolated("networked pendulum", 0.3, 1e-3, &record, |iso| {
        match iso {
            Some(iso) => Simulation::from_ssp_isolated(&ssp, iso),
            None => Simulation::from_ssp(&ssp),
        }
        .unwrap_or_else(|e| panic!("{e}"))
    });
    // Frames went over the bus: the drives' voltages moved.
    assert!(r.column(4).iter().any(|u| *u != 0.0), "{:?}", r.column(4));
}

/// Two of our BouncingBalls with Event Mode, `b` dropped from 0.9 m (`a` from 1 m), isolated
/// with `iso`: in the step from 0.4 s, `a` returns early at its bounce, then `b` at its earlier
/// one, and `a` is set back (its FMU state and its clocks) and steps again.
fn two_balls(iso: Option<Isolation>) -> Simulation {
    let ball = ours("BouncingBall", true);
    let mut sim = system_isolated(
        &[("a", &ball), ("b", &ball)],
        &[],
        vec![("b".into(), "h".into(), Value::Real(0.9))],
        iso,
    );
    sim.use_event_mode("a").unwrap_or_else(|e| panic!("{e}"));
    sim.use_event_mode("b").unwrap_or_else(|e| panic!("{e}"));
    sim
}

#[test]
fn events_and_early_returns_isolated_give_the_in_process_rows_bit_for_bit() {
    let (ball, vdp) = (ours("BouncingBall", true), ours("VanDerPol", true));
    let record = ["ball.h", "ball.v", "vdp.x0"];
    let r = same_rows_isolated("ball beside vdp", 3.0, 0.1, &record, |iso| {
        let mut sim = system_isolated(&[("ball", &ball), ("vdp", &vdp)], &[], Vec::new(), iso);
        sim.use_event_mode("ball").unwrap_or_else(|e| panic!("{e}"));
        sim
    });
    assert!(r.time.len() > 31, "no bounce became a point: {:?}", r.time);
    let r = same_rows_isolated("two balls", 1.5, 0.1, &["a.h", "a.v", "b.h", "b.v"], two_balls);
    // Both first bounces are points, at the free fall's times (g = 9.81 m/s^2).
    for h0 in [1.0f64, 0.9] {
        let t1 = (2.0 * h0 / 9.81).sqrt();
        assert!(r.time.iter().any(|t| (t - t1).abs() < 1e-9), "{h0}: {:?}", r.time);
    }
}

/// The process of the isolated component `name` of this test process (its pid).
fn child_of(name: &str) -> i32 {
    let me = std::process::id().to_string();
    for entry in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(pid) = entry.file_name().to_string_lossy().parse::<i32>() else {
            continue;
        };
        let stat = std::fs::read_to_string(entry.path().join("stat")).unwrap_or_default();
        // pid (comm) state ppid ...
        let ppid = stat.rsplit(')').next().and_then(|s| s.split_whitespace().nth(1));
        let cmdline = std::fs::read(entry.path().join("cmdline")).unwrap_or_default();
        let args: Vec<&[u8]> = cmdline.split(|b| *b == 0).collect();
        let named = args.windows(2).any(|w| w[0] == b"--name" && w[1] == name.as_bytes());
        if ppid == Some(me.as_str()) && named && args.iter().any(|a| *a == b"serve-component") {
            return pid;
        }
    }
    panic!("no child process of component '{name}'");
}

/// The sampled loop with the controller in Event Mode, isolated (calls time out after
/// `timeout`), run 0.2 s: `signal` is sent to the controller's process after the row at 0.1 s.
fn loop_with_signal(signal: i32, timeout: Option<Duration>) -> rustfmu_runner::Error {
    let (mut sim, record) = sampled_loop(Some(isolation(timeout)));
    sim.use_event_mode("controller").unwrap_or_else(|e| panic!("{e}"));
    let mut opts = RunOptions::new(0.2, 1e-3);
    opts.record = record.iter().map(|r| r.to_string()).collect();
    let mut sent = false;
    let failure = sim
        .run(&opts, &mut |k, _| {
            if k >= 100 && !sent {
                sent = true;
                let pid = child_of("controller");
                // SAFETY: a signal to a process this test started (through the Simulation).
                assert_eq!(unsafe { libc::kill(pid, signal) }, 0);
            }
        })
        .expect_err("the controller's process is gone");
    assert!(sent);
    failure.error
}

#[test]
fn a_crash_or_hang_of_an_isolated_event_mode_component_fails_the_run_naming_the_call() {
    // The controller's process dies of SIGABRT after the row at 0.1 s: the next call the runner
    // makes of it, the end of its Event Mode before the step from 0.1 s, fails naming it.
    let e = loop_with_signal(libc::SIGABRT, None);
    assert_eq!(e.component.as_deref(), Some("controller"), "{e}");
    assert_eq!(
        (e.function.as_deref(), e.time),
        (Some("fmi3UpdateDiscreteStates"), Some(0.1)),
        "{e}"
    );
    assert!(
        e.message
            .contains("fmi3UpdateDiscreteStates at t = 0.1 s did not return")
            && e.message.contains("died of signal 6 (SIGABRT"),
        "{}",
        e.message
    );
    // Stopped (a hang): killed after the call timeout, the same call named.
    let hang = loop_with_signal(libc::SIGSTOP, Some(Duration::from_millis(500)));
    assert_eq!(hang.component.as_deref(), Some("controller"), "{hang}");
    assert!(hang.message.contains("did not return within 0.5 s"), "{}", hang.message);
    assert_eq!((&hang.function, hang.time), (&e.function, e.time), "{hang}");
}

#[test]
fn scheduled_execution_components_isolated_give_the_in_process_rows_bit_for_bit() {
    // Two of our Clocks in Scheduled Execution, a's output clock ticking b's inClock2 (the
    // countdown's point at 4.5 s).
    let record: Vec<String> = ["a", "b"]
        .iter()
        .flat_map(|c| COUNTERS.iter().map(move |v| format!("{c}.{v}")))
        .collect();
    let record: Vec<&str> = record.iter().map(String::as_str).collect();
    let ssp = two_clocks_ssp("isolated-se", "ScheduledExecution");
    let r = same_rows_isolated("two clocks in Scheduled Execution", 10.0, 1.0, &record, |iso| {
        let sim = match iso {
            Some(iso) => Simulation::from_ssp_isolated(&ssp, iso),
            None => Simulation::from_ssp(&ssp),
        }
        .unwrap_or_else(|e| panic!("{e}"));
        assert!(sim.is_scheduled("a") && sim.is_scheduled("b"));
        sim
    });
    assert!(r.time.contains(&4.5), "{:?}", r.time);
    let col = |n: &str| r.column(record.iter().position(|r| *r == n).unwrap());
    assert!(
        *col("b.inClock2Ticks").last().unwrap() > 0.0,
        "{:?}",
        col("b.inClock2Ticks")
    );
    assert!(*col("b.result2").last().unwrap() >= 1000.0, "{:?}", col("b.result2"));

    // The command line: the same CSV bytes with --isolate as in process.
    let csv = |isolate: bool| {
        let out = ssp.with_file_name(format!("rows-{isolate}.csv"));
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_rustfmu-runner"));
        cmd.arg("run")
            .arg(&ssp)
            .args(["--stop-time", "10", "--step", "1", "--no-progress", "-o"]);
        cmd.arg(&out);
        for r in &record {
            cmd.args(["--record", r]);
        }
        if isolate {
            cmd.arg("--isolate");
        }
        let status = cmd.status().unwrap();
        assert!(status.success(), "isolate {isolate}: {status}");
        std::fs::read(&out).unwrap()
    };
    let (here, there) = (csv(false), csv(true));
    assert!(here.len() > 100, "{}", String::from_utf8_lossy(&here));
    assert_eq!(String::from_utf8_lossy(&there), String::from_utf8_lossy(&here));
    std::fs::remove_dir_all(ssp.parent().unwrap()).ok();

    // The C Reference-FMUs' Clocks (Scheduled Execution only) alone, and the SampledController
    // in Scheduled Execution closing the Pendulum's loop.
    let clocks = theirs("3.0", "Clocks");
    let record: Vec<String> = COUNTERS.iter().map(|v| format!("clocks.{v}")).collect();
    let record: Vec<&str> = record.iter().map(String::as_str).collect();
    let r = same_rows_isolated("the C Clocks", 10.0, 0.5, &record, |iso| {
        system_isolated(&[("clocks", &clocks)], &[], Vec::new(), iso)
    });
    assert_eq!(*r.column(5).last().unwrap(), 1000.0, "output3: {:?}", r.column(5));
    let (_, record) = sampled_loop(None);
    let r = same_rows_isolated("sampled loop in Scheduled Execution", 0.5, 1e-3, &record, |iso| {
        let (mut sim, _) = sampled_loop(iso);
        sim.use_scheduled_execution("controller")
            .unwrap_or_else(|e| panic!("{e}"));
        sim
    });
    assert!(r.column(4).iter().any(|x| x.abs() > 1e-3), "{:?}", r.column(4));
}

#[test]
fn a_scheduled_execution_component_whose_process_died_runs_again_in_scheduled_execution() {
    // The C Reference-FMUs' Clocks has only <ScheduledExecution>: instantiated again after its
    // process died (fmi2Fatal) as a co-simulation component (the bug this checks), no partition
    // is activated and every counter stays 0 (seen: "row 0: t = 0 [0, 0, 0, 0, 0, 0] against
    // t = 0 [1, 0, 0, 1, 0, 0]").
    let clocks = theirs("3.0", "Clocks");
    let record: Vec<String> = COUNTERS.iter().map(|v| format!("clocks.{v}")).collect();
    let record: Vec<&str> = record.iter().map(String::as_str).collect();
    let mut sim = system_isolated(&[("clocks", &clocks)], &[], Vec::new(), Some(isolation(None)));
    let mut opts = RunOptions::new(10.0, 0.5);
    opts.record = record.iter().map(|r| r.to_string()).collect();
    let whole = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    let mut sent = false;
    let failure = sim
        .run(&opts, &mut |k, _| {
            if k >= 4 && !sent {
                sent = true;
                // SAFETY: a signal to a process this test started (through the Simulation).
                assert_eq!(unsafe { libc::kill(child_of("clocks"), libc::SIGKILL) }, 0);
            }
        })
        .expect_err("the process of 'clocks' is gone");
    assert_eq!(failure.error.status.as_deref(), Some("Fatal"), "{}", failure.error);
    assert!(failure.error.message.contains("SIGKILL"), "{}", failure.error);
    // The next run starts it anew, in Scheduled Execution: the rows of the first run.
    let again = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    assert!(sim.is_scheduled("clocks"));
    assert_eq!(first_difference(&again, &whole), None);
    assert_eq!(
        *again.column(5).last().unwrap(),
        1000.0,
        "output3: {:?}",
        again.column(5)
    );
}
