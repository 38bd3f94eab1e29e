//! Accuracy per cost of the runner's error-controlled communication steps (step doubling with
//! rollback, `RunOptions::adaptive`) against fixed steps, on an SSP file: for each fixed step and
//! each tolerance, the largest deviation of the recorded angles from a reference, the fmi2DoStep
//! calls (each one per component) and the run's time (median of `--repeat`).
//!
//!     cargo run --release -p rustfmu-bench --bin adaptive-steps -- [--system PendulumLQR] [--seconds 2] [--repeat 5]
//!
//! The reference: fixed steps of 100 µs and 50 µs extrapolated to h = 0 (Richardson, first order:
//! the coupling error of a held input is O(h) over a run), on the 100 µs run's points; the others
//! are compared at their own points, the reference linearly interpolated (its points are 100 µs
//! apart, the interpolation error ~1e-9 rad here). Needs target/fmu/<system>.ssp (the main job
//! makes it). Prints a Markdown table and one JSON line per run.

use clap::Parser;
use rustfmu_runner::{Adaptive, RunOptions, RunResult, Simulation};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Parser)]
struct Args {
    #[arg(long, default_value = "PendulumLQR")]
    system: String,
    #[arg(long, default_value_t = 2.0)]
    seconds: f64,
    #[arg(long, default_value_t = 5)]
    repeat: usize,
    #[arg(long, default_value = "target/fmu")]
    fmu_dir: PathBuf,
}

const RECORD: [&str; 2] = ["pendulum.alpha1", "pendulum.alpha2"];

fn main() {
    rustfmu_bench::exit_on_error("adaptive-steps", run());
}

fn options(seconds: f64, h: f64, tolerance: Option<f64>, on_angles: bool) -> RunOptions {
    let mut o = RunOptions::new(seconds, h);
    o.record = RECORD.iter().map(|s| s.to_string()).collect();
    o.adaptive = tolerance.map(|tolerance| Adaptive {
        tolerance,
        min_step: None,
        max_step: None,
        error_on: if on_angles { o.record.clone() } else { Vec::new() },
    });
    o
}

/// The reference's value of column `c` at `t` (linear between its points).
fn at(reference: &(Vec<f64>, Vec<Vec<f64>>), c: usize, t: f64) -> f64 {
    let (time, cols) = reference;
    let k = time.partition_point(|&x| x <= t).clamp(1, time.len() - 1);
    let (t0, t1) = (time[k - 1], time[k]);
    let w = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
    cols[c][k - 1] + w * (cols[c][k] - cols[c][k - 1])
}

fn run() -> Result<(), String> {
    let args = Args::parse();
    let ssp = args.fmu_dir.join(format!("{}.ssp", args.system));
    let mut sim = Simulation::from_ssp(&ssp).map_err(|e| e.message)?;
    let mut once =
        |o: &RunOptions| -> Result<RunResult, String> { sim.run(o, &mut |_, _| {}).map_err(|f| f.to_string()) };
    let coarse = once(&options(args.seconds, 1e-4, None, false))?;
    let fine = once(&options(args.seconds, 5e-5, None, false))?;
    let m = RECORD.len();
    let reference = (
        coarse.time.clone(),
        (0..m)
            .map(|c| {
                coarse
                    .time
                    .iter()
                    .enumerate()
                    .map(|(k, _)| 2.0 * fine.values[2 * k * m + c] - coarse.values[k * m + c])
                    .collect()
            })
            .collect::<Vec<Vec<f64>>>(),
    );
    let mut rows = Vec::new();
    let cases: Vec<(String, RunOptions)> = [8e-3, 4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4]
        .iter()
        .map(|&h| {
            (
                format!("fixed h = {} ms", h * 1e3),
                options(args.seconds, h, None, false),
            )
        })
        .chain([1e-3, 1e-4, 1e-5, 1e-6].iter().map(|&tol| {
            (
                format!("tolerance {tol:e}"),
                options(args.seconds, 1e-3, Some(tol), false),
            )
        }))
        .chain([1e-4, 1e-5, 1e-6].iter().map(|&tol| {
            (
                format!("tolerance {tol:e} on the angles"),
                options(args.seconds, 1e-3, Some(tol), true),
            )
        }))
        .collect();
    for (label, o) in &cases {
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..args.repeat.max(1) {
            let started = Instant::now();
            let r = once(o)?;
            times.push(started.elapsed().as_secs_f64());
            last = Some(r);
        }
        let r = last.expect("one run");
        let err = r
            .time
            .iter()
            .enumerate()
            .flat_map(|(k, &t)| (0..m).map(move |c| (k, c, t)))
            .map(|(k, c, t)| (r.values[k * m + c] - at(&reference, c, t)).abs())
            .fold(0.0f64, f64::max);
        let ms = rustfmu_bench::median(times) * 1e3;
        println!(
            "{{\"system\": \"{}\", \"case\": \"{label}\", \"error_rad\": {err:.3e}, \"fmu_steps\": {}, \"rejected\": {}, \"points\": {}, \"ms\": {ms:.2}}}",
            args.system,
            r.fmu_steps,
            r.rejected,
            r.time.len()
        );
        rows.push((
            label.clone(),
            err,
            r.fmu_steps,
            r.rejected,
            r.time.len(),
            ms,
            r.note.clone(),
        ));
    }
    println!();
    println!(
        "{} over {} s, largest |angle - reference| (rad), fmi2DoStep calls per component, run time (median of {}):",
        args.system, args.seconds, args.repeat
    );
    println!();
    println!("| run | error (rad) | fmi2DoStep calls | rejected | points | ms |");
    println!("|---|---|---|---|---|---|");
    for (label, err, steps, rejected, points, ms, note) in rows {
        println!(
            "| {label}{} | {err:.2e} | {steps} | {rejected} | {points} | {ms:.1} |",
            note.map(|n| format!(" ({n})")).unwrap_or_default()
        );
    }
    Ok(())
}
