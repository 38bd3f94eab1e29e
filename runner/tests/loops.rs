//! Algebraic loops solved by the runner (runner/src/sim/loops.rs), on a system of existing FMUs
//! whose direct feedthrough closes a cycle, written as an SSP file here, against the same
//! equations solved here, independently.
//!
//! The system: two of the project's DC motors (`DCMotor.fmu`, `coupled = true`: joint speed
//! `omega` in, torque `tau = n (km i - B n omega)` out, direct feedthrough), each driving a
//! massless viscous load of 1 N·m·s/rad (a `Feedthrough` FMU: speed = torque / 1) whose speed is the
//! other motor's joint speed. At every communication point the loop is
//!
//! ```text
//! w_a = km_b i_b - B_b w_b,    w_b = km_a i_a - B_a w_a      (n = 1)
//! ```
//!
//! and with B_a B_b = 3 > 1 it is no contraction: Gauss-Seidel sweeps would diverge, Newton's
//! method solves it. Over a step each motor's current follows its armature circuit with its
//! joint speed held, `L di/dt = U - R i - kb w`: i(t + h) = i e^(-Rh/L) + (U - kb w)(1 - e^(-Rh/L))/R.
//!
//! Needs target/fmu (`cargo run --release -p fmu-build`) and, for the foreign Feedthrough, the C
//! Reference-FMUs of ../shared/independent.

// rustfmu_runner::Error is large (it carries the details of a failure), on the cold path only.
#![allow(clippy::result_large_err)]

mod support;

use rustfmu_runner::{ErrorKind, RunOptions, RunResult, Simulation};
use std::io::Write;
use std::path::{Path, PathBuf};
use support::{ours, theirs};

/// One motor's parameters (gear ratio 1, coupled) and its voltage and initial current.
#[derive(Clone, Copy)]
struct Motor {
    l: f64,
    r: f64,
    km: f64,
    kb: f64,
    b: f64,
    u: f64,
    i0: f64,
    /// Supply limit: U_applied = U limited to +-u_max.
    u_max: f64,
}

const A: Motor = Motor {
    l: 0.1,
    r: 1.0,
    km: 0.5,
    kb: 0.5,
    b: 2.0,
    u: 1.0,
    i0: 0.2,
    u_max: 6.0,
};
const B: Motor = Motor {
    l: 0.2,
    r: 2.0,
    km: 0.4,
    kb: 0.3,
    b: 1.5,
    u: -0.5,
    i0: 0.0,
    u_max: 6.0,
};

fn motor_xml(name: &str, m: Motor) -> String {
    let real = |n: &str, v: f64| format!(r#"<ssv:Parameter name="{n}"><ssv:Real value="{v:?}"/></ssv:Parameter>"#);
    format!(
        r#"<ssd:Component name="{name}" source="resources/DCMotor.fmu"><ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues><ssv:ParameterSet version="1.0" name="p"><ssv:Parameters>{}{}{}{}{}{}{}{}{}<ssv:Parameter name="coupled"><ssv:Boolean value="true"/></ssv:Parameter></ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings></ssd:Component>"#,
        real("L", m.l),
        real("R", m.r),
        real("km", m.km),
        real("kb", m.kb),
        real("B", m.b),
        real("gear_ratio", 1.0),
        real("U", m.u),
        real("i", m.i0),
        real("U_max", m.u_max),
    )
}

/// A folder of this test process, removed when dropped.
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        std::fs::remove_dir_all(&self.0).ok();
    }
}

/// The SSP file of the two motors and their loads (`load` the Feedthrough FMU's file) in a
/// folder `dir` of this process (the file, and the folder to drop when done): each motor's torque
/// drives its load, whose speed is the other motor's.
fn system(dir: &str, a: Motor, b: Motor, load: &Path) -> (PathBuf, Scratch) {
    let speeds = [
        ("motor_a", "tau", "load_a", "Float64_continuous_input"),
        ("load_a", "Float64_continuous_output", "motor_b", "omega"),
        ("motor_b", "tau", "load_b", "Float64_continuous_input"),
        ("load_b", "Float64_continuous_output", "motor_a", "omega"),
    ];
    system_with(dir, a, b, load, &speeds)
}

/// [`system`] with other `connections` (start element, connector, end element, connector).
fn system_with(
    dir: &str,
    a: Motor,
    b: Motor,
    load: &Path,
    connections: &[(&str, &str, &str, &str)],
) -> (PathBuf, Scratch) {
    let conn: String = connections
        .iter()
        .map(|(a, x, b, y)| {
            format!(r#"<ssd:Connection startElement="{a}" startConnector="{x}" endElement="{b}" endConnector="{y}"/>"#)
        })
        .collect();
    let ssd = format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
  xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
  xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" version="1.0" name="TwoMotors">
<ssd:System name="TwoMotors"><ssd:Elements>{}{}
<ssd:Component name="load_a" source="resources/Feedthrough.fmu"/>
<ssd:Component name="load_b" source="resources/Feedthrough.fmu"/>
</ssd:Elements><ssd:Connections>{}</ssd:Connections></ssd:System>
<ssd:DefaultExperiment startTime="0" stopTime="1"/></ssd:SystemStructureDescription>"#,
        motor_xml("motor_a", a),
        motor_xml("motor_b", b),
        conn,
    );
    let d = std::env::temp_dir().join(format!("rustfmu-runner-loops-{dir}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let path = d.join("TwoMotors.ssp");
    let mut z = zip::ZipWriter::new(std::fs::File::create(&path).unwrap());
    let opts = zip::write::SimpleFileOptions::default();
    z.start_file("SystemStructure.ssd", opts).unwrap();
    z.write_all(ssd.as_bytes()).unwrap();
    for (name, file) in [("DCMotor", ours("DCMotor", false)), ("Feedthrough", load.to_path_buf())] {
        z.start_file(format!("resources/{name}.fmu"), opts).unwrap();
        z.write_all(&std::fs::read(file).unwrap()).unwrap();
    }
    z.finish().unwrap();
    (path, Scratch(d))
}

const RECORD: [&str; 4] = ["motor_a.i", "motor_b.i", "motor_a.tau", "motor_b.tau"];

/// The loop's solution and the motors' steps, here: rows [i_a, i_b, tau_a, tau_b] at t = k h.
fn independent(a: Motor, b: Motor, stop: f64, h: f64) -> Vec<[f64; 4]> {
    let n = (stop / h).round() as usize;
    let (mut ia, mut ib) = (a.i0, b.i0);
    let mut rows = Vec::with_capacity(n + 1);
    let step = |m: Motor, i: f64, w: f64| {
        let e = (-m.r * h / m.l).exp();
        i * e + (m.u - m.kb * w) * (1.0 - e) / m.r
    };
    for _ in 0..=n {
        // w_a + B_b w_b = km_b i_b, B_a w_a + w_b = km_a i_a (Cramer).
        let det = 1.0 - a.b * b.b;
        let wa = (b.km * ib - b.b * a.km * ia) / det;
        let wb = (a.km * ia - a.b * b.km * ib) / det;
        // tau_a is load_a's speed, motor_b's: w_b; tau_b is w_a.
        rows.push([ia, ib, wb, wa]);
        (ia, ib) = (step(a, ia, wa), step(b, ib, wb));
    }
    rows
}

fn run(ssp: &Path, stop: f64, h: f64, finite_differences: bool) -> RunResult {
    let mut sim = Simulation::from_ssp(ssp).unwrap_or_else(|e| panic!("{e}"));
    let mut opts = RunOptions::new(stop, h);
    opts.record = RECORD.iter().map(|s| s.to_string()).collect();
    opts.loops.finite_differences = finite_differences;
    sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"))
}

/// A run of 10 s at 1 ms made twice on one simulation (the second timed): its result and the
/// wall time of one communication step (every component stepped, the loop solved), µs.
fn timed(ssp: &Path, finite_differences: bool) -> (RunResult, f64) {
    let mut sim = Simulation::from_ssp(ssp).unwrap_or_else(|e| panic!("{e}"));
    let mut opts = RunOptions::new(10.0, 1e-3);
    opts.record = RECORD.iter().map(|s| s.to_string()).collect();
    opts.loops.finite_differences = finite_differences;
    sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    let started = std::time::Instant::now();
    let r = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    let per_step = started.elapsed().as_secs_f64() * 1e6 / r.time.len() as f64;
    (r, per_step)
}

/// The largest |runner - independent| over every recorded value and point.
fn largest_error(r: &RunResult, rows: &[[f64; 4]]) -> f64 {
    assert_eq!(r.time.len(), rows.len());
    let mut worst = 0.0f64;
    for (k, row) in rows.iter().enumerate() {
        for (j, x) in row.iter().enumerate() {
            worst = worst.max((r.values[k * 4 + j] - x).abs());
        }
    }
    worst
}

#[test]
fn a_loop_of_feedthrough_is_ordered_as_one_block_and_named() {
    let (ssp, _dir) = system("order", A, B, &ours("Feedthrough", false));
    let sim = Simulation::from_ssp(&ssp).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(sim.evaluation_order(), ["motor_a", "motor_b", "load_a", "load_b"]);
    let loops = sim.algebraic_loops();
    assert_eq!(loops.len(), 1);
    assert_eq!(loops[0].0, ["motor_a", "motor_b", "load_a", "load_b"]);
    // Every connection feeds an input with feedthrough: four unknowns, grouped by component.
    assert_eq!(
        loops[0].1,
        [
            "motor_a.omega",
            "motor_b.omega",
            "load_a.Float64_continuous_input",
            "load_b.Float64_continuous_input"
        ]
    );
}

#[test]
fn the_loop_solved_by_newton_with_exact_jacobians_is_the_independent_solution() {
    let (stop, h) = (1.0, 1e-2);
    let (ssp, _dir) = system("exact", A, B, &ours("Feedthrough", false));
    let r = run(&ssp, stop, h, false);
    let error = largest_error(&r, &independent(A, B, stop, h));
    let report = &r.loops[0];
    println!("{report}; largest |runner - independent| = {error:.3e}");
    assert!(
        report.exact_jacobian,
        "every component gives directional derivatives: {report}"
    );
    assert!(
        error < 1e-10,
        "the runner's trajectory differs from the loop solved here by {error}"
    );
    // A linear loop: one Newton iteration a solve, from the first guess (the unknowns' start
    // values at t = 0, then the previous point's solution); 0 where that guess already solves it.
    assert_eq!(report.most_iterations, 1, "{report}");
    assert!(
        report.solves > 101,
        "every propagation solves it (initialization too): {report}"
    );
    // i(0) = 0.2 A: t = 0 needs the loop solved in Initialization Mode too.
    assert!(
        (r.values[2] - 0.5 * 0.2 / (1.0 - 3.0)).abs() < 1e-12,
        "tau_a(0) = {}",
        r.values[2]
    );
}

#[test]
fn finite_differences_and_directional_derivatives_give_the_same_solution() {
    let (stop, h) = (1.0, 1e-2);
    let (ssp, _dir) = system("fd", A, B, &ours("Feedthrough", false));
    let exact = run(&ssp, stop, h, false);
    let fd = run(&ssp, stop, h, true);
    assert!(exact.loops[0].exact_jacobian && !fd.loops[0].exact_jacobian);
    let worst = exact
        .values
        .iter()
        .zip(&fd.values)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    println!(
        "exact: {}\nfinite differences: {}\nlargest difference {worst:.3e}",
        exact.loops[0], fd.loops[0]
    );
    assert!(worst < 1e-10, "the two Jacobians lead to solutions {worst} apart");
    assert!(largest_error(&fd, &independent(A, B, stop, h)) < 1e-10);
    assert!(fd.loops[0].most_iterations <= 2, "{}", fd.loops[0]);
    // What each costs (printed, not asserted: a machine's load decides it).
    for finite_differences in [false, true] {
        let (r, us) = timed(&ssp, finite_differences);
        let error = largest_error(&r, &independent(A, B, 10.0, 1e-3));
        println!(
            "10 s at 1 ms: {}; {us:.2} µs a communication step; largest |runner - independent| = {error:.3e}",
            r.loops[0]
        );
        // A point whose first guess (the point before's solution) already meets the tolerance
        // (|u - g(u)| <= 1e-10 + 1e-10 |u|) takes it: the error is the tolerance's order.
        assert!(error < 1e-8, "{error}");
    }
}

#[test]
fn a_foreign_component_without_directional_derivatives_gets_finite_differences() {
    let (stop, h) = (1.0, 1e-2);
    let (ssp, _dir) = system("theirs", A, B, &theirs("2.0", "Feedthrough"));
    let r = run(&ssp, stop, h, false);
    let error = largest_error(&r, &independent(A, B, stop, h));
    println!("{}; largest |runner - independent| = {error:.3e}", r.loops[0]);
    assert!(
        !r.loops[0].exact_jacobian,
        "the Reference-FMUs' Feedthrough gives no directional derivatives"
    );
    assert!(error < 1e-10, "{error}");
}

#[test]
fn a_singular_loop_fails_the_run_naming_loop_unknowns_residual_and_time() {
    // B_a B_b = 1: w_a + w_b = km_b i_b and w_a + w_b = km_a i_a, no unique solution (none
    // unless km_a i_a = km_b i_b); found in Initialization Mode, where the loop is first solved.
    let a = Motor { b: 1.0, ..A };
    let b = Motor { b: 1.0, ..B };
    let (ssp, _dir) = system("singular", a, b, &ours("Feedthrough", false));
    let mut sim = Simulation::from_ssp(&ssp).unwrap_or_else(|e| panic!("{e}"));
    let mut opts = RunOptions::new(1.0, 1e-2);
    opts.record = vec!["motor_a.i".into()];
    let f = sim
        .run(&opts, &mut |_, _| {})
        .expect_err("a singular loop must fail the run");
    let m = &f.error.message;
    println!("{m}");
    assert_eq!(f.error.kind, ErrorKind::Loop);
    assert_eq!(f.error.time, Some(0.0), "{m}");
    for part in [
        "algebraic loop among components motor_a, motor_b, load_a, load_b",
        "unknowns motor_a.omega, motor_b.omega",
        "at t = 0 s",
        "singular",
        "residual max |u - g(u)| = ",
        "exact Jacobian",
    ] {
        assert!(m.contains(part), "'{part}' missing from: {m}");
    }
    assert!(f.partial.time.is_empty(), "nothing recorded before initialization");
}

#[test]
fn a_loop_not_converged_in_the_iterations_allowed_fails_naming_them() {
    let (ssp, _dir) = system("limit", A, B, &ours("Feedthrough", false));
    let mut sim = Simulation::from_ssp(&ssp).unwrap_or_else(|e| panic!("{e}"));
    let mut opts = RunOptions::new(1.0, 1e-2);
    opts.loops.max_iterations = 0;
    let f = sim
        .run(&opts, &mut |_, _| {})
        .expect_err("no iteration allowed: i(0) = 0.2 A must fail");
    let m = &f.error.message;
    assert_eq!(f.error.time, Some(0.0), "{m}");
    assert!(
        m.contains("did not converge in 0 iterations") && m.contains("at t = 0 s") && m.contains("residual"),
        "{m}"
    );
    opts.loops.rtol = -1.0;
    let e = sim
        .run(&opts, &mut |_, _| {})
        .expect_err("a negative tolerance is refused")
        .error;
    assert!(e.message.contains("rtol = -1"), "{e}");
}

#[test]
fn the_same_loop_with_a_step_of_delay_diverges() {
    // The Jacobi order (every output read, then every input set) solves nothing: each point
    // takes the loop's values of the point before, w <- km i - B w, whose gain B_a B_b = 3 per
    // round trip makes it grow without bound; Newton's solution stays below 1 N·m.
    let (ssp, _dir) = system("jacobi", A, B, &ours("Feedthrough", false));
    let mut sim = Simulation::from_ssp(&ssp).unwrap_or_else(|e| panic!("{e}"));
    sim.scheme = rustfmu_runner::Scheme::Jacobi;
    let mut opts = RunOptions::new(0.5, 1e-2);
    opts.record = vec!["motor_a.tau".into()];
    let r = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
    assert!(r.loops.is_empty(), "the Jacobi order solves no loop");
    let delayed = r.column(0).iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let solved = independent(A, B, 0.5, 1e-2)
        .iter()
        .fold(0.0f64, |m, row| m.max(row[2].abs()));
    println!("largest |motor_a.tau| over 0.5 s: {delayed:.3e} with a step of delay, {solved:.3e} solved");
    assert!(solved < 1.0 && delayed > 1e3, "{delayed} vs {solved}");
}

#[test]
fn a_loop_through_a_supply_limit_takes_newton_across_the_limit() {
    // Nonlinear, not smooth: motor_a's voltage is motor_b's torque (through load_b), motor_b's
    // speed motor_a's applied voltage (through load_a), U_applied = U limited to +-0.5 V:
    //   U = km_b i_b - B_b clamp(U, -0.5, 0.5).
    // As i_b rises past 3 A the solution leaves the linear piece (slope 1 + B_b = 3) for the
    // limited one (slope 1): Newton from the point before's solution needs more than one
    // iteration there, the Jacobian through the limit exact (its derivative 0 beyond it, from the
    // FMU) or by differences.
    let a = Motor {
        u_max: 0.5,
        i0: 0.0,
        ..A
    };
    let b = Motor {
        l: 0.2,
        r: 1.0,
        km: 0.5,
        kb: 0.3,
        b: 2.0,
        u: 5.0,
        i0: 0.0,
        u_max: 6.0,
    };
    let limited = [
        ("motor_a", "U_applied", "load_a", "Float64_continuous_input"),
        ("load_a", "Float64_continuous_output", "motor_b", "omega"),
        ("motor_b", "tau", "load_b", "Float64_continuous_input"),
        ("load_b", "Float64_continuous_output", "motor_a", "U"),
    ];
    let (ssp, _dir) = system_with("limit-loop", a, b, &ours("Feedthrough", false), &limited);
    let (stop, h): (f64, f64) = (1.0, 1e-2);
    // Here: the loop by its two pieces, the currents stepped exactly (motor_a's joint speed is
    // not connected: 0).
    let mut expected = Vec::new();
    let (mut ia, mut ib) = (a.i0, b.i0);
    for _ in 0..=(stop / h).round() as usize {
        let x = b.km * ib;
        let u = if (x / (1.0 + b.b)).abs() <= a.u_max {
            x / (1.0 + b.b)
        } else {
            x - b.b * a.u_max * x.signum()
        };
        let applied = u.clamp(-a.u_max, a.u_max);
        expected.push([ia, ib, applied, u]);
        let step = |m: Motor, i: f64, drive: f64| {
            let e = (-m.r * h / m.l).exp();
            i * e + drive * (1.0 - e) / m.r
        };
        (ia, ib) = (step(a, ia, applied), step(b, ib, b.u - b.kb * applied));
    }
    assert!(
        expected.iter().any(|r| r[3].abs() < a.u_max) && expected.iter().any(|r| r[3].abs() > a.u_max),
        "the run crosses the limit"
    );
    for finite_differences in [false, true] {
        let mut sim = Simulation::from_ssp(&ssp).unwrap_or_else(|e| panic!("{e}"));
        let mut opts = RunOptions::new(stop, h);
        opts.record = ["motor_a.i", "motor_b.i", "motor_a.U_applied", "motor_b.tau"]
            .map(String::from)
            .to_vec();
        opts.loops.finite_differences = finite_differences;
        let r = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
        let error = largest_error(&r, &expected);
        println!("{}; largest |runner - independent| = {error:.3e}", r.loops[0]);
        assert!(error < 1e-9, "{error}");
        // One iteration on a piece; across the limit more (the first step, on the linear
        // piece's slope, lands beyond the limit; a step that does not lower the residual is
        // halved), and a few.
        let most = r.loops[0].most_iterations;
        assert!((2..=4).contains(&most), "across the limit: {}", r.loops[0]);
    }
}

#[test]
fn a_first_order_hold_through_a_loop_is_refused_saying_so() {
    let (ssp, _dir) = system("hold", A, B, &ours("Feedthrough", false));
    let mut sim = Simulation::from_ssp(&ssp).unwrap_or_else(|e| panic!("{e}"));
    let mut opts = RunOptions::new(0.1, 1e-2);
    opts.input_derivatives = true;
    let e = sim.run(&opts, &mut |_, _| {}).expect_err("refused").error;
    assert_eq!(e.kind, ErrorKind::Usage);
    assert!(
        e.message.contains("through an algebraic loop are not computed")
            && e.message.contains("[motor_a, motor_b, load_a, load_b]"),
        "{e}"
    );
}
