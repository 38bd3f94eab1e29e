//! The benchmark harness measures what it says: the direct and the C-API step compute the same
//! thing, the native master closes the loop, and a wrong name in the loop table is reported.
//! Needs the packaged Pendulum FMU (tests/run.sh builds it before the Rust tests).

use rustfmu_bench::master::Master;
use rustfmu_bench::single::{Direct, ViaFmi};
use rustfmu_bench::topology::{self, Slave, Topology};

const STATES: [&str; 4] = ["alpha1", "omega1", "alpha2", "omega2"];

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

#[test]
fn stand_in_feedback_brings_the_pendulum_back_upright() {
    let mut master = Master::new(topology::stand_in()).unwrap_or_else(|e| panic!("{e}"));
    master.initialize(10.0).unwrap_or_else(|e| panic!("{e}"));
    master.run(10_000, 1e-3).unwrap_or_else(|e| panic!("{e}"));
    let vrs: Vec<u32> = STATES.iter().map(|s| master.vr("Pendulum", s).unwrap()).collect();
    let x = master.get("Pendulum", &vrs).unwrap();
    assert!(
        x.iter().all(|v| v.abs() < 1e-6),
        "from alpha1 = 0.1, alpha2 = -0.05 the LQR of eq. (14) should be upright at rest after 10 s, got {x:?}"
    );
}

#[test]
fn a_wrong_variable_name_in_the_loop_is_reported_with_the_names_that_exist() {
    let mut topo = topology::stand_in();
    topo.start_values.push((("Pendulum", "torque"), 1.0));
    let err = Master::new(topo)
        .err()
        .expect("a loop naming 'Pendulum.torque' must be refused");
    assert!(
        err.contains("no Real variable 'torque'") && err.contains("M1") && err.contains("alpha1"),
        "the error should name the missing variable and list the existing ones: {err}"
    );
}

#[test]
fn a_missing_fmu_is_reported_with_the_command_that_builds_it() {
    let topo = Topology {
        name: "test",
        description: "an FMU that is not packaged",
        slaves: vec![Slave {
            instance: "X",
            fmu: "NoSuchFmu",
        }],
        connections: vec![],
        start_values: vec![],
        feedback: None,
    };
    let err = Master::new(topo)
        .err()
        .expect("a loop with an unpackaged FMU must be refused");
    assert!(
        err.contains("NoSuchFmu.fmu is missing") && err.contains("fmu-build"),
        "the error should name the file and how to build it: {err}"
    );
}
