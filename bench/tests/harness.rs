//! The benchmark harness measures what it says: the direct and the C-API step compute the same
//! thing, the native master runs the real loops (they stand the pendulum up), and a wrong name or
//! type in a loop is reported. Needs the packaged FMUs (tests/run.sh builds them before the Rust
//! tests).

use rustfmu::Value;
use rustfmu_bench::master::{Master, Scheme};
use rustfmu_bench::single::{Direct, ViaFmi};
use rustfmu_bench::topology::{self, Slave, Topology};

const STATES: [&str; 4] = ["alpha1", "omega1", "alpha2", "omega2"];

/// The error of `Master::new` for `topo`, which must refuse it (`what`: the loop's fault).
fn refusal(topo: Topology, what: &str) -> String {
    Master::new(topo)
        .err()
        .unwrap_or_else(|| panic!("{what} must be refused"))
}

#[test]
fn direct_and_c_api_steps_compute_the_same_swing() {
    let mut direct = Direct::new();
    let mut fmi = ViaFmi::new("Pendulum", Some(&STATES)).unwrap_or_else(|e| panic!("{e}"));
    let h = 1e-3;
    let mut via_fmi = [0.0; 4];
    let mut via_rust = [0.0; 4];
    for k in 0..1000 {
        via_rust = direct.round_trip(k as f64 * h, h, [0.0, 0.0]);
        via_fmi.copy_from_slice(fmi.round_trip(k as f64 * h, h, &[0.0, 0.0]));
    }
    assert_eq!(via_rust, via_fmi, "after 1 s the direct step and fmi2DoStep disagree");
    assert!(
        via_rust[0].abs() > 0.5,
        "the pendulum should have fallen: alpha1 = {}",
        via_rust[0]
    );
}

/// The composed loop the benchmarks time is the real one: Controller, two DC motors and the
/// plant, with the parameters of `holonomic/systems.toml`, stand the pendulum up.
#[test]
fn full_loop_stands_the_pendulum_up_in_the_native_master() {
    let mut master = Master::new(topology::full()).unwrap_or_else(|e| panic!("{e}"));
    master.initialize(10.0).unwrap_or_else(|e| panic!("{e}"));
    master.run(10_000, 1e-3).unwrap_or_else(|e| panic!("{e}"));
    let x = master.plant_state().unwrap_or_else(|e| panic!("{e}"));
    assert!(
        x[0].abs() < 1e-3 && x[2].abs() < 1e-3,
        "from alpha1 = 0.1, alpha2 = -0.05 rad the motor loop should hold the pendulum within 1e-3 rad after \
         10 s, got (alpha1, omega1, alpha2, omega2) = {x:?}"
    );
}

#[test]
fn controller_plant_loop_brings_the_pendulum_upright_at_rest() {
    let mut master = Master::new(topology::controller_plant()).unwrap_or_else(|e| panic!("{e}"));
    master.initialize(10.0).unwrap_or_else(|e| panic!("{e}"));
    master.run(10_000, 1e-3).unwrap_or_else(|e| panic!("{e}"));
    let x = master.plant_state().unwrap_or_else(|e| panic!("{e}"));
    assert!(
        x.iter().all(|v| v.abs() < 1e-6),
        "from alpha1 = 0.1, alpha2 = -0.05 rad the Controller FMU's LQR should be upright at rest after 10 s, \
         got {x:?}"
    );
}

#[test]
fn the_full_loop_is_evaluated_plant_controller_motors() {
    let master = Master::new(topology::full()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        master.evaluation_order(),
        ["pendulum", "controller", "motor1", "motor2"],
        "the Controller feeds through from the plant's outputs, the motors from the Controller's"
    );
}

/// The plant's state after 2 s of the controller-plant loop at h = 2 ms.
fn lqr_state_after_2s(scheme: Scheme, sampled: bool) -> Vec<f64> {
    let mut topo = topology::controller_plant();
    topo.start_values
        .push((("controller", "sampled"), Value::Boolean(sampled)));
    let mut master = Master::new(topo).unwrap_or_else(|e| panic!("{e}"));
    master.scheme = scheme;
    master.initialize(2.0).unwrap_or_else(|e| panic!("{e}"));
    master.run(1000, 2e-3).unwrap_or_else(|e| panic!("{e}"));
    master.plant_state().unwrap_or_else(|e| panic!("{e}"))
}

/// Gauss-Seidel with a sampled controller is the old Jacobi loop with a feedthrough one, to the
/// bit: both give the controller the state of the previous communication point. Without
/// `sampled`, Gauss-Seidel removes that delay.
#[test]
fn gauss_seidel_with_a_sampled_controller_is_the_jacobi_loop() {
    let jacobi = lqr_state_after_2s(Scheme::Jacobi, false);
    let sampled = lqr_state_after_2s(Scheme::GaussSeidel, true);
    assert_eq!(
        sampled, jacobi,
        "Gauss-Seidel + sampled vs Jacobi + feedthrough after 2 s"
    );
    let feedthrough = lqr_state_after_2s(Scheme::GaussSeidel, false);
    assert_ne!(
        feedthrough, jacobi,
        "Gauss-Seidel + feedthrough should differ from the delayed loop"
    );
}

#[test]
fn every_parameter_of_the_system_reaches_the_loop() {
    let topo = topology::full();
    let system = topology::systems().unwrap().get(topo.system).unwrap();
    let n: usize = system.components.iter().map(|c| c.parameters.len()).sum();
    assert_eq!(
        topo.start_values.len(),
        n,
        "the loop must set every parameter of {}",
        system.name
    );
    for ((inst, var), value) in [
        (("controller", "mode"), Value::Integer(3)),
        (("controller", "drives_motors"), Value::Boolean(true)),
        (("motor2", "gear_ratio"), Value::Real(200.0)),
    ] {
        assert!(
            topo.start_values.contains(&((inst, var), value)),
            "expected {inst}.{var} = {value:?} in the full loop, it sets {:?}",
            topo.start_values
        );
    }
}

#[test]
fn a_wrong_variable_name_in_the_loop_is_reported_with_the_names_that_exist() {
    let mut topo = topology::controller_plant();
    topo.start_values.push((("pendulum", "torque"), Value::Real(1.0)));
    let err = refusal(topo, "a loop naming 'pendulum.torque'");
    assert!(
        err.contains("no variable 'torque'") && err.contains("M1") && err.contains("alpha1"),
        "the error should name the missing variable and list the existing ones: {err}"
    );
}

#[test]
fn a_start_value_of_the_wrong_type_is_reported() {
    let mut topo = topology::controller_plant();
    topo.start_values.push((("controller", "mode"), Value::Real(1.0)));
    let err = refusal(topo, "a Real value for the Enumeration 'mode'");
    assert!(
        // The runner names the declared type as modelDescription.xml has it (set through
        // fmi2SetInteger, as an Integer value).
        err.contains("'mode' is Enumeration") && err.contains("not Real"),
        "the error should say the declared and the given type: {err}"
    );
}

#[test]
fn a_missing_fmu_is_reported_with_the_command_that_builds_it() {
    let topo = Topology {
        name: "test",
        system: "none",
        description: "an FMU that is not packaged",
        slaves: vec![Slave {
            instance: "X",
            fmu: "NoSuchFmu",
        }],
        connections: vec![],
        start_values: vec![],
        plant: "X",
    };
    let err = refusal(topo, "a loop with an unpackaged FMU");
    assert!(
        err.contains("NoSuchFmu.fmu is missing") && err.contains("fmu-build"),
        "the error should name the file and how to build it: {err}"
    );
}

/// The benchmark's master (the systems table, the FMUs of target/fmu) and the runner on the SSP
/// file of the same system (its SSD, the FMUs inside the archive) compute the same loop, to the bit.
#[test]
fn the_master_on_the_systems_table_and_the_runner_on_the_ssp_file_agree() {
    for (name, system) in topology::TOPOLOGIES {
        let mut master = Master::new(topology::by_name(name).unwrap()).unwrap_or_else(|e| panic!("{e}"));
        master.initialize(2.0).unwrap_or_else(|e| panic!("{e}"));
        master.run(2000, 1e-3).unwrap_or_else(|e| panic!("{e}"));
        let x = master.plant_state().unwrap_or_else(|e| panic!("{e}"));
        let ssp = rustfmu_bench::fmu_dir().join(format!("{system}.ssp"));
        let mut sim = rustfmu_runner::Simulation::from_ssp(&ssp).unwrap_or_else(|e| panic!("{e}"));
        let mut opts = rustfmu_runner::RunOptions::new(2.0, 1e-3);
        opts.record = STATES.iter().map(|v| format!("pendulum.{v}")).collect();
        let r = sim.run(&opts, &mut |_, _| {}).unwrap_or_else(|f| panic!("{f}"));
        // The master's state after its 2000th step is the runner's last row (read after
        // propagating at t = 2 s, which changes no state).
        assert_eq!(
            r.values[2000 * 4..],
            x[..],
            "{system}: runner on the SSP file vs the bench master"
        );
    }
}
