//! The plant's integrator across tolerances: error at t_end against a reference state, right-hand
//! side evaluations, and time per simulated second; and a fixed-step RK4 with the same number of
//! evaluations. One JSON object per line; `bench/python/work_precision.py` gives the reference
//! and sets scipy's integrators beside these rows.
//!
//!     cargo run --release -p rustfmu-bench --bin work-precision -- \
//!         --x0 0.5,0,-0.3,0 --t-end 1 --reference A1,W1,A2,W2 --tols 1e-3,1e-6,1e-9

use clap::Parser;
use holonomic::models::pendulum::PendulumParams;
use nalgebra::{Vector2, Vector4};
use pendulum_fmu::Pendulum;
use rustfmu::solver::{Dopri5, Stats, Tolerances};
use rustfmu::{Standalone, Variables};
use rustfmu_bench::rk4;
use std::hint::black_box;
use std::time::Instant;

fn main() {
    rustfmu_bench::exit_on_error("work-precision", run());
}

/// Median wall time of `f` over enough repetitions to last about 50 ms (at least 3).
fn median_seconds(mut f: impl FnMut()) -> f64 {
    let start = Instant::now();
    f();
    let once = start.elapsed().as_secs_f64().max(1e-9);
    let reps = ((0.05 / once) as usize).clamp(3, 10_000);
    let mut times: Vec<f64> = (0..reps)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[reps / 2]
}

/// One row: the method, its tolerance, its error at t_end, its counts and its time per simulated
/// second, as one JSON object.
fn print_row(method: &str, tol: f64, error: f64, counts: Stats, seconds_per_simulated_second: f64) {
    println!(
        "{{\"method\": \"{method}\", \"tol\": {tol:e}, \"error\": {error:e}, \"rhs\": {}, \"accepted\": {}, \
         \"rejected\": {}, \"seconds_per_simulated_second\": {seconds_per_simulated_second:e}}}",
        counts.rhs_evaluations, counts.accepted_steps, counts.rejected_steps
    );
}

fn max_abs_error(x: &Vector4<f64>, reference: &[f64]) -> f64 {
    x.iter().zip(reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
}

/// Work-precision rows of the plant's integrator, one JSON object per line.
#[derive(clap::Parser)]
struct Args {
    /// Initial state alpha1,omega1,alpha2,omega2 [rad, rad/s].
    #[arg(long, value_delimiter = ',', required = true, allow_hyphen_values = true)]
    x0: Vec<f64>,
    /// Reference state at t_end, same order.
    #[arg(long, value_delimiter = ',', required = true, allow_hyphen_values = true)]
    reference: Vec<f64>,
    /// End time [s].
    #[arg(long)]
    t_end: f64,
    /// Tolerances (rtol = atol) to run.
    #[arg(long, value_delimiter = ',', required = true, allow_hyphen_values = true)]
    tols: Vec<f64>,
}

fn run() -> Result<(), String> {
    let args = Args::parse();
    let (x0, reference, t_end, tols) = (args.x0, args.reference, args.t_end, args.tols);
    if x0.len() != 4 || reference.len() != 4 {
        return Err("--x0 and --reference take 4 numbers: alpha1, omega1, alpha2, omega2".into());
    }
    let x0 = Vector4::new(x0[0], x0[1], x0[2], x0[3]);
    let p = PendulumParams::default();
    let u = Vector2::zeros();
    let f = |x: &Vector4<f64>| p.derivative(x, &u);

    for tol in tols {
        let tol_pair = Tolerances { rtol: tol, atol: tol };
        // A method's row at this tolerance: its state at t_end, its counts, its time for the run.
        let row = |method: &str, x: &Vector4<f64>, counts: Stats, seconds: f64| {
            print_row(method, tol, max_abs_error(x, &reference), counts, seconds / t_end);
        };
        // Dopri5 over [0, t_end] in one call: the integrator alone.
        let one_call = || {
            let mut ode = Dopri5::default();
            let mut x = x0;
            ode.integrate(|_, x: &Vector4<f64>| f(x), 0.0, t_end, &mut x, tol_pair)
                .map(|()| (x, ode.stats))
        };
        let (x, stats) = one_call().map_err(|e| format!("Dopri5 at tol {tol:e}: {e}"))?;
        let seconds = median_seconds(|| {
            black_box(one_call().ok());
        });
        row("rustfmu Dopri5, one call", &x, stats, seconds);
        // The FMU's model stepped at h = 1 ms: what the FMU does for an importer.
        let h = 1e-3;
        let n = (t_end / h).round() as usize;
        let fmu_run = || {
            let mut m = Pendulum::start();
            (m.alpha1_0, m.omega1_0, m.alpha2_0, m.omega2_0) = (x0[0], x0[1], x0[2], x0[3]);
            (m.rtol, m.atol) = (tol, tol);
            let mut sim = Standalone::new(m, 0.0, None);
            sim.initialize()?;
            for _ in 0..n {
                sim.do_step(h).map_err(|e| e.message)?;
            }
            Ok::<_, String>((sim.model.state(), sim.solver.stats))
        };
        let (x, stats) = fmu_run().map_err(|e| format!("Pendulum model at tol {tol:e}: {e}"))?;
        let seconds = median_seconds(|| {
            black_box(fmu_run().ok());
        });
        row("rustfmu Pendulum do_step, h = 1 ms", &x, stats, seconds);
        // RK4 with as many evaluations as the one-call Dopri5.
        let one_call_rhs = one_call().map_err(|e| e.to_string())?.1.rhs_evaluations;
        let steps = (one_call_rhs / 4).max(1) as usize;
        let rk4_run = || {
            let mut x = x0;
            let rhs = rk4::integrate(f, &mut x, t_end / steps as f64, steps);
            (x, rhs)
        };
        let (x, rhs) = rk4_run();
        let seconds = median_seconds(|| {
            black_box(rk4_run());
        });
        let counts = Stats {
            rhs_evaluations: rhs,
            accepted_steps: steps as u64,
            rejected_steps: 0,
        };
        row("RK4 fixed step, equal cost", &x, counts, seconds);
    }
    Ok(())
}
