//! The cost of isolation (issue 26): one run of `--seconds` (default 10) at `--step` (default
//! 1 ms) of an SSP system, its components in this process against each in a child process of
//! its own (`component`) and against the whole system in one child process (`system`;
//! `rustfmu_runner::isolate`), median of `--repeat` runs on the same System (fmi2Reset between
//! runs, as a study's pooled loops). Two recordings: every output at every point (the default
//! of `System.run`) and the two angles only. Also the cost of starting the system (the children
//! spawned, each FMU instantiated in its child). Prints one JSON line per system.
//!
//!     cargo run --release -p rustfmu-bench --bin isolation-cost -- [--system PendulumMotors] [--seconds 10] [--repeat 5]
//!
//! Needs target/fmu/<system>.ssp (the main job makes it) and target/release/rustfmu-runner (the
//! children's binary, found beside this one).

use clap::Parser;
use rustfmu_runner::isolate::{Isolation, SystemProcess, find_worker};
use rustfmu_runner::{RunOptions, Simulation};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Parser)]
struct Args {
    /// PendulumLQR, PendulumMotors (repeatable; default both).
    #[arg(long)]
    system: Vec<String>,
    #[command(flatten)]
    run: rustfmu_bench::RunArgs,
    #[arg(long, default_value = "target/fmu")]
    fmu_dir: PathBuf,
}

fn main() {
    rustfmu_bench::exit_on_error("isolation-cost", run());
}

fn per_run(sim: &mut Simulation, opts: &RunOptions, repeat: usize) -> Result<f64, String> {
    let mut times = Vec::new();
    for _ in 0..repeat.max(1) {
        let t0 = Instant::now();
        sim.run(opts, &mut |_, _| {}).map_err(|f| f.error.message)?;
        times.push(t0.elapsed().as_secs_f64());
    }
    Ok(rustfmu_bench::median(times))
}

fn run() -> Result<(), String> {
    let args = Args::parse();
    let systems = if args.system.is_empty() {
        vec!["PendulumLQR".to_owned(), "PendulumMotors".to_owned()]
    } else {
        args.system.clone()
    };
    let worker = find_worker(None, &[])?;
    for name in systems {
        let ssp = args.fmu_dir.join(format!("{name}.ssp"));
        let t0 = Instant::now();
        let mut here = Simulation::from_ssp(&ssp)?;
        let start_here = t0.elapsed().as_secs_f64();
        let iso = Isolation {
            worker: worker.clone(),
            timeout: None,
        };
        let t0 = Instant::now();
        let mut there = Simulation::from_ssp_isolated(&ssp, iso.clone())?;
        let start_there = t0.elapsed().as_secs_f64();
        let t0 = Instant::now();
        let mut whole = SystemProcess::spawn(iso, &ssp, false, &[])?;
        let start_whole = t0.elapsed().as_secs_f64();
        let mut all = RunOptions::new(args.run.seconds, args.run.step);
        all.record = here.outputs();
        let mut angles = RunOptions::new(args.run.seconds, args.run.step);
        angles.record = vec!["pendulum.alpha1".into(), "pendulum.alpha2".into()];
        let mut line = Vec::new();
        let steps = (args.run.seconds / args.run.step).round();
        for (what, opts) in [("all_outputs", &all), ("angles", &angles)] {
            // One run each first: the pages and caches of both.
            per_run(&mut here, opts, 1)?;
            per_run(&mut there, opts, 1)?;
            let a = per_run(&mut here, opts, args.run.repeat)?;
            let b = per_run(&mut there, opts, args.run.repeat)?;
            let mut times = Vec::new();
            for _ in 0..=args.run.repeat.max(1) {
                let t0 = Instant::now();
                whole.run(opts).map_err(|f| f.error.message)?;
                times.push(t0.elapsed().as_secs_f64());
            }
            times.remove(0);
            let c = rustfmu_bench::median(times);
            line.push(format!(
                "\"{what}\": {{\"in_process_ms\": {:.2}, \"component_ms\": {:.2}, \"component_ratio\": {:.1}, \"system_ms\": {:.2}, \"system_ratio\": {:.2}, \"in_process_us_per_step\": {:.3}, \"component_us_per_step\": {:.3}}}",
                a * 1e3,
                b * 1e3,
                b / a,
                c * 1e3,
                c / a,
                a / steps * 1e6,
                b / steps * 1e6
            ));
        }
        println!(
            "{{\"system\": \"{name}\", \"components\": {}, \"seconds\": {}, \"step\": {}, \"repeat\": {}, \"start_in_process_ms\": {:.1}, \"start_component_ms\": {:.1}, \"start_system_ms\": {:.1}, {}}}",
            here.components().len(),
            args.run.seconds,
            args.run.step,
            args.run.repeat,
            start_here * 1e3,
            start_there * 1e3,
            start_whole * 1e3,
            line.join(", ")
        );
    }
    Ok(())
}
