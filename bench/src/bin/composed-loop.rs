//! Runs the composed loop once in the native master and prints wall time and real-time factor.
//!
//!     cargo run --release -p rustfmu-bench --bin composed-loop -- [--topology NAME] [--seconds 10] [--step 1e-3] [--repeat 5]
//!     cargo run --release -p rustfmu-bench --bin composed-loop -- --topology-json
//!
//! Topologies (`bench/src/topology.rs`, from the systems of `rustfmu::systems`): `full` (the
//! default: Controller, two DC motors, Pendulum) and `controller-plant` (Controller, Pendulum).

use rustfmu_bench::master::Master;
use rustfmu_bench::topology;
use std::time::Instant;

fn main() {
    if let Err(e) = run() {
        eprintln!("composed-loop: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let number = |flag: &str, default: f64| -> Result<f64, String> {
        value(flag).map_or(Ok(default), |v| {
            v.parse().map_err(|_| format!("{flag} {v}: not a number"))
        })
    };
    let topo = topology::by_name(&value("--topology").unwrap_or_else(|| topology::DEFAULT.to_owned()))?;
    if args.iter().any(|a| a == "--topology-json") {
        println!("{}", topo.to_json());
        return Ok(());
    }
    let seconds = number("--seconds", 10.0)?;
    let h = number("--step", 1e-3)?;
    let repeat = number("--repeat", 5.0)? as usize;
    let n = (seconds / h).round() as usize;
    let mut master = Master::new(topo)?;
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
