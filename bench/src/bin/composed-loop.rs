//! Runs the composed loop once in the native master and prints wall time and real-time factor.
//!
//!     cargo run --release -p rustfmu-bench --bin composed-loop -- [--topology NAME] [--seconds 10] [--step 1e-3] [--repeat 5] [--jacobi]
//!     cargo run --release -p rustfmu-bench --bin composed-loop -- --topology-json
//!
//! Topologies (`bench/src/topology.rs`, from the systems of `holonomic/systems.toml`): `full` (the
//! default: Controller, two DC motors, Pendulum) and `controller-plant` (Controller, Pendulum).

use clap::Parser;
use rustfmu_bench::master::{Master, Scheme};
use rustfmu_bench::topology;
use std::time::Instant;

/// The composed loop in the native master: wall time and real-time factor, as one JSON line.
#[derive(Parser)]
struct Args {
    /// Loop to run: `full` or `controller-plant`.
    #[arg(long, default_value = topology::DEFAULT)]
    topology: String,
    /// Print the loop table as JSON (for bench/python/composed_loop.py) and exit.
    #[arg(long)]
    topology_json: bool,
    #[command(flatten)]
    run: rustfmu_bench::RunArgs,
    /// Evaluate each communication point in the Jacobi order (every output read, then every input
    /// set; what fmpy.ssp and libcosim do) instead of the dependency order.
    #[arg(long)]
    jacobi: bool,
}

fn main() {
    rustfmu_bench::exit_on_error("composed-loop", run());
}

fn run() -> Result<(), String> {
    let args = Args::parse();
    let topo = topology::by_name(&args.topology)?;
    if args.topology_json {
        println!("{}", topo.to_json());
        return Ok(());
    }
    let (seconds, h, repeat) = (args.run.seconds, args.run.step, args.run.repeat);
    let n = (seconds / h).round() as usize;
    let mut master = Master::new(topo)?;
    if args.jacobi {
        master.scheme = Scheme::Jacobi;
    }
    let mut walls = Vec::new();
    for _ in 0..repeat.max(1) {
        master.initialize(seconds)?;
        let start = Instant::now();
        master.run(n, h)?;
        walls.push(start.elapsed().as_secs_f64());
    }
    walls.sort_by(f64::total_cmp);
    let best = walls[0];
    let median = walls[walls.len() / 2];
    let x = master.plant_state()?;
    println!(
        "{{\"topology\": \"{}\", \"description\": \"{}\", \"seconds\": {seconds}, \"step\": {h}, \"steps\": {n}, \
         \"runs\": {}, \"wall_best_s\": {best:.6e}, \"wall_median_s\": {median:.6e}, \"real_time_factor\": {:.1}, \
         \"final_state\": [{}]}}",
        master.topology.name,
        master.topology.description,
        walls.len(),
        seconds / median,
        x.iter().map(|v| format!("{v:.17e}")).collect::<Vec<_>>().join(", ")
    );
    Ok(())
}
