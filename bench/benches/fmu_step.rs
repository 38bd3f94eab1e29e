//! `cargo bench -p rustfmu-bench` (quick check that every benchmark runs: `-- --test`).
//!
//! - pendulum_step/{direct,fmi2DoStep}/h=1ms|10ms: the plant's step called in Rust against the
//!   same step through the packaged `.so`'s C API (default tolerances rtol = atol = 1e-10);
//! - pendulum_round_trip/{direct,fmi}: the same with the fmi2SetReal (M1, M2) and fmi2GetReal
//!   (alpha1, omega1, alpha2, omega2) a master makes around each step;
//! - fmi2DoStep/<id>/h=1ms: every other packaged FMU (Controller, DCMotor, ...) with its
//!   parameters of the `full` loop, inputs set and outputs read as a master does;
//! - composed_loop/10s_at_1ms/{controller-plant,full}: the whole loop in the native master;
//! - pendulum_derivatives/{direct_rhs,fmi2SetContinuousStates+fmi2GetDerivatives}: one
//!   evaluation of the plant's right-hand side at a new state, called in Rust against the same
//!   through the packaged `.so`'s model-exchange C API (what an importer's integrator does per
//!   stage).

use criterion::{Criterion, criterion_group, criterion_main};
use rustfmu::Value;
use rustfmu_bench::master::Master;
use rustfmu_bench::single::{Direct, ViaFmi, time_steps};
use rustfmu_bench::{packaged_fmus, topology};
use std::hint::black_box;
use std::time::{Duration, Instant};

const STATES: [&str; 4] = ["alpha1", "omega1", "alpha2", "omega2"];

fn pendulum_step(c: &mut Criterion) {
    let mut g = c.benchmark_group("pendulum_step");
    let mut direct = Direct::new();
    let mut fmi = ViaFmi::new("Pendulum", Some(&STATES)).unwrap_or_else(|e| panic!("{e}"));
    for (label, h) in [("h=1ms", 1e-3), ("h=10ms", 1e-2)] {
        g.bench_function(format!("direct/{label}"), |b| {
            b.iter_custom(|iters| time_steps(&mut direct, iters, h, Direct::restart, |d, t, h| d.step(t, h)))
        });
        g.bench_function(format!("fmi2DoStep/{label}"), |b| {
            b.iter_custom(|iters| time_steps(&mut fmi, iters, h, |f| f.restart().unwrap(), |f, t, h| f.step(t, h)))
        });
    }
    g.finish();

    let mut g = c.benchmark_group("pendulum_round_trip");
    let h = 1e-3;
    g.bench_function("direct/h=1ms", |b| {
        b.iter_custom(|iters| {
            time_steps(&mut direct, iters, h, Direct::restart, |d, t, h| {
                black_box(d.round_trip(t, h, black_box([0.0, 0.0])));
            })
        })
    });
    g.bench_function("fmi/h=1ms", |b| {
        b.iter_custom(|iters| {
            time_steps(
                &mut fmi,
                iters,
                h,
                |f| f.restart().unwrap(),
                |f, t, h| {
                    black_box(f.round_trip(t, h, black_box(&[0.0, 0.0])));
                },
            )
        })
    });
    g.finish();
}

fn other_fmus(c: &mut Criterion) {
    let mut g = c.benchmark_group("fmi2DoStep");
    // Each with the parameter values it has in the full loop (Controller in LQR + PID mode
    // computing voltages, DCMotor with the 200:1 gear), inputs held at 0.
    let full = topology::full();
    for id in packaged_fmus().into_iter().filter(|id| id != "Pendulum") {
        let instance = full.slaves.iter().find(|s| s.fmu == id).map(|s| s.instance);
        let starts: Vec<(&str, Value)> = full
            .start_values
            .iter()
            .filter(|((inst, _), _)| Some(*inst) == instance)
            .map(|((_, var), v)| (*var, *v))
            .collect();
        let mut fmu = ViaFmi::with_starts(&id, None, &starts).unwrap_or_else(|e| panic!("{e}"));
        let u = vec![0.0; fmu.in_vrs.len()];
        g.bench_function(format!("{id}/h=1ms"), |b| {
            b.iter_custom(|iters| {
                time_steps(
                    &mut fmu,
                    iters,
                    1e-3,
                    |f| f.restart().unwrap(),
                    |f, t, h| {
                        black_box(f.round_trip(t, h, &u));
                    },
                )
            })
        });
    }
    g.finish();
}

fn composed_loop(c: &mut Criterion) {
    let mut g = c.benchmark_group("composed_loop");
    g.sample_size(10);
    for (name, _) in topology::TOPOLOGIES {
        let mut master =
            Master::new(topology::by_name(name).unwrap_or_else(|e| panic!("{e}"))).unwrap_or_else(|e| panic!("{e}"));
        g.bench_function(format!("10s_at_1ms/{name}"), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    master.initialize(10.0).unwrap_or_else(|e| panic!("{e}"));
                    let start = Instant::now();
                    master.run(10_000, 1e-3).unwrap_or_else(|e| panic!("{e}"));
                    total += start.elapsed();
                }
                total
            })
        });
    }
    g.finish();
}

fn pendulum_derivatives(c: &mut Criterion) {
    use fmi::fmi2::instance::{Common, ModelExchange};
    use holonomic::models::pendulum::PendulumParams;
    let mut g = c.benchmark_group("pendulum_derivatives");
    let states = rustfmu_bench::swing_states();
    let p = PendulumParams::default();
    g.bench_function("direct_rhs", |b| {
        let mut k = 0;
        b.iter(|| {
            k = (k + 1) & 1023;
            black_box(p.rhs(black_box(states[k]), black_box([0.0, 0.0])))
        })
    });
    let fmu = rustfmu_bench::Fmu::load("Pendulum").unwrap_or_else(|e| panic!("{e}"));
    let mut me = fmu
        .import
        .instantiate_me("bench-me", false, false)
        .unwrap_or_else(|e| panic!("fmi2Instantiate(ModelExchange): {e}"));
    me.setup_experiment(None, 0.0, None).expect("fmi2SetupExperiment");
    me.enter_initialization_mode().expect("fmi2EnterInitializationMode");
    me.exit_initialization_mode().expect("fmi2ExitInitializationMode");
    me.enter_continuous_time_mode().expect("fmi2EnterContinuousTimeMode");
    let mut dx = [0.0; 4];
    g.bench_function("fmi2SetContinuousStates+fmi2GetDerivatives", |b| {
        let mut k = 0;
        b.iter(|| {
            k = (k + 1) & 1023;
            me.set_continuous_states(black_box(&states[k]))
                .expect("fmi2SetContinuousStates");
            me.get_derivatives(&mut dx).expect("fmi2GetDerivatives");
            black_box(dx)
        })
    });
    g.finish();
}

criterion_group!(benches, pendulum_step, other_fmus, composed_loop, pendulum_derivatives);
criterion_main!(benches);
