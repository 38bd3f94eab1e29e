//! The step-cost tables of docs/performance.md: the plant's step called directly against the
//! same step through the packaged `.so`, alone and with the master's fmi2SetReal/fmi2GetReal,
//! and the composed loop. The variants are timed in interleaved rounds (each round runs every
//! variant for one simulated second of the swing), so a busy machine slows all of them alike;
//! the table gives the fastest round (least disturbed) and the median round.
//!
//!     cargo run --release -p rustfmu-bench --bin perf-report -- [--rounds 31]
//!
//! For a profile (instruction counts do not depend on the machine's load):
//!
//!     valgrind --tool=callgrind target/release/perf-report --only fmi-1ms --steps 2000

use clap::Parser;
use rustfmu_bench::master::Master;
use rustfmu_bench::single::{Direct, ViaFmi};
use rustfmu_bench::topology;
use std::hint::black_box;
use std::time::Instant;

const STATES: [&str; 4] = ["alpha1", "omega1", "alpha2", "omega2"];

struct Subjects {
    direct: Direct,
    fmi: ViaFmi,
    me: fmi::fmi2::instance::InstanceME,
}

/// Runs `steps` steps of `variant` from the start of the swing; returns seconds per step.
fn run(s: &mut Subjects, variant: &str, steps: usize) -> Result<f64, String> {
    let h = if variant.ends_with("10ms") { 1e-2 } else { 1e-3 };
    s.direct.restart();
    s.fmi.restart()?;
    let states = rustfmu_bench::swing_states();
    let p = holonomic::models::pendulum::PendulumParams::default();
    let start = Instant::now();
    match variant {
        // One evaluation of the right-hand side at a new state: in Rust, and as a model-exchange
        // importer's integrator makes it through the C API.
        "direct-rhs" => {
            for k in 0..steps {
                black_box(p.rhs(black_box(states[k & 1023]), black_box([0.0, 0.0])));
            }
        }
        "fmi-derivatives" => {
            use fmi::fmi2::instance::ModelExchange;
            let mut dx = [0.0; 4];
            for k in 0..steps {
                s.me.set_continuous_states(black_box(&states[k & 1023]))
                    .map_err(|e| format!("fmi2SetContinuousStates: {e:?}"))?;
                s.me.get_derivatives(&mut dx)
                    .map_err(|e| format!("fmi2GetDerivatives: {e:?}"))?;
                black_box(dx);
            }
        }
        "direct-1ms" | "direct-10ms" => {
            for k in 0..steps {
                s.direct.step(k as f64 * h, h);
            }
        }
        "fmi-1ms" | "fmi-10ms" => {
            for k in 0..steps {
                s.fmi.step(k as f64 * h, h);
            }
        }
        "direct-round-trip-1ms" => {
            for k in 0..steps {
                black_box(s.direct.round_trip(k as f64 * h, h, black_box([0.0, 0.0])));
            }
        }
        "fmi-round-trip-1ms" => {
            for k in 0..steps {
                black_box(s.fmi.round_trip(k as f64 * h, h, black_box(&[0.0, 0.0])));
            }
        }
        other => return Err(format!("unknown variant '{other}'")),
    }
    Ok(start.elapsed().as_secs_f64() / steps as f64)
}

const VARIANTS: [&str; 6] = [
    "direct-1ms",
    "fmi-1ms",
    "direct-10ms",
    "fmi-10ms",
    "direct-round-trip-1ms",
    "fmi-round-trip-1ms",
];

fn main() {
    rustfmu_bench::exit_on_error("perf-report", report());
}

fn stats(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[0], v[v.len() / 2])
}

/// Step cost of the Pendulum, direct and through the C API, and the composed loops.
#[derive(clap::Parser)]
struct Args {
    /// Interleaved rounds of every variant.
    #[arg(long, default_value_t = 31)]
    rounds: usize,
    /// Run only this variant (e.g. `fmi-1ms`), for profiling under callgrind.
    #[arg(long)]
    only: Option<String>,
    /// Steps of the `--only` variant.
    #[arg(long, default_value_t = 1000)]
    steps: usize,
}

fn report() -> Result<(), String> {
    let args = Args::parse();
    let fmu = rustfmu_bench::Fmu::load("Pendulum")?;
    let mut me = fmu
        .import
        .instantiate_me("perf-report-me", false, false)
        .map_err(|e| format!("fmi2Instantiate(ModelExchange): {e}"))?;
    {
        use fmi::fmi2::instance::{Common, ModelExchange};
        let e = |what: &'static str| move |err| format!("{what}: {err:?}");
        me.setup_experiment(None, 0.0, None).map_err(e("fmi2SetupExperiment"))?;
        me.enter_initialization_mode()
            .map_err(e("fmi2EnterInitializationMode"))?;
        me.exit_initialization_mode().map_err(e("fmi2ExitInitializationMode"))?;
        me.enter_continuous_time_mode()
            .map_err(e("fmi2EnterContinuousTimeMode"))?;
    }
    let mut s = Subjects {
        direct: Direct::new(),
        fmi: ViaFmi::new("Pendulum", Some(&STATES))?,
        me,
    };
    if let Some(variant) = args.only {
        let steps = args.steps;
        let t = run(&mut s, &variant, steps)?;
        println!("{variant}: {steps} steps, {:.1} ns per step", t * 1e9);
        return Ok(());
    }
    let rounds = args.rounds;
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); VARIANTS.len()];
    for _ in 0..rounds {
        for (i, v) in VARIANTS.iter().enumerate() {
            // One simulated second per round: 1000 steps at 1 ms, 100 at 10 ms.
            let steps = if v.ends_with("10ms") { 100 } else { 1000 };
            times[i].push(run(&mut s, v, steps)?);
        }
    }
    let st: Vec<(f64, f64)> = times.into_iter().map(stats).collect();
    println!("Pendulum, swing from alpha1 = 0.1 rad, alpha2 = 0.15 rad, default tolerances; {rounds} rounds\n");
    println!("| step | direct Rust call | through the C API (.so) | overhead (fastest / median round) |");
    println!("|---|---|---|---|");
    for (label, d, f) in [
        ("do_step vs fmi2DoStep, h = 1 ms", 0, 1),
        ("do_step vs fmi2DoStep, h = 10 ms", 2, 3),
        ("set M1 M2, step, get 4 states, h = 1 ms", 4, 5),
    ] {
        let (dmin, dmed) = st[d];
        let (fmin, fmed) = st[f];
        println!(
            "| {label} | {:.0} ns / {:.0} ns | {:.0} ns / {:.0} ns | {:+.1} % / {:+.1} % |",
            dmin * 1e9,
            dmed * 1e9,
            fmin * 1e9,
            fmed * 1e9,
            (fmin / dmin - 1.0) * 100.0,
            (fmed / dmed - 1.0) * 100.0
        );
    }

    for (name, _) in topology::TOPOLOGIES {
        let mut master = Master::new(topology::by_name(name)?)?;
        let mut walls = Vec::new();
        for _ in 0..rounds.clamp(3, 11) {
            master.initialize(10.0)?;
            let start = Instant::now();
            master.run(10_000, 1e-3)?;
            walls.push(start.elapsed().as_secs_f64());
        }
        let (wmin, wmed) = stats(walls);
        println!(
            "\ncomposed loop '{}' ({}), 10 s at 1 ms, native master: fastest {:.2} ms, median {:.2} ms, \
             real-time factor {:.0} (median)",
            master.topology.name,
            master.topology.description,
            wmin * 1e3,
            wmed * 1e3,
            10.0 / wmed
        );
    }
    Ok(())
}
