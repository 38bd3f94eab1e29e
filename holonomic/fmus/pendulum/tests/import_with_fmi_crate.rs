//! The packaged Pendulum.fmu, loaded and simulated by another Rust importer (the `fmi` crate),
//! agrees with the model stepped in-process: the archive, the binary and the ABI all work.
//! Needs `target/fmu/Pendulum.fmu` (`cargo run --release -p fmu-build`).

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common};
use pendulum_fmu::Pendulum;
use rustfmu::{Standalone, Variables};

fn vr(name: &str) -> u32 {
    Pendulum::DESCRIPTION.by_name(name).unwrap().value_reference
}

fn fmu_path() -> std::path::PathBuf {
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../target"));
    let p = target.join("fmu").join("Pendulum.fmu");
    assert!(
        p.exists(),
        "{} is missing: run `cargo run --release -p fmu-build` first",
        p.display()
    );
    p
}

#[test]
fn fmi_crate_simulates_the_packaged_fmu_like_the_model_in_process() {
    let import: Fmi2Import = fmi::import::from_path(fmu_path()).expect("fmi crate reads Pendulum.fmu");
    let mut inst = import
        .instantiate_cs("pendulum-via-fmi-crate", false, true)
        .expect("instantiate");
    inst.setup_experiment(None, 0.0, Some(1.0)).unwrap();
    inst.set_real(&[vr("alpha1_0"), vr("alpha2_0")], &[0.1, -0.05]).unwrap();
    inst.enter_initialization_mode().unwrap();
    inst.set_real(&[vr("M1")], &[0.2]).unwrap();
    inst.exit_initialization_mode().unwrap();

    let mut start = Pendulum::start();
    (start.alpha1_0, start.alpha2_0, start.M1) = (0.1, -0.05, 0.2);
    let mut sim = Standalone::new(start, 0.0, None);
    sim.initialize().unwrap();

    let outputs = [vr("alpha1"), vr("omega1"), vr("alpha2"), vr("omega2"), vr("energy")];
    let h = 1e-3;
    for n in 0..1000 {
        let t = n as f64 * h;
        inst.do_step(t, h, true).expect("fmi2DoStep");
        sim.do_step(h).unwrap();
    }
    let model = &sim.model;
    let mut got = [0.0; 5];
    inst.get_real(&outputs, &mut got).unwrap();
    let want = [model.alpha1, model.omega1, model.alpha2, model.omega2, model.energy];
    assert_eq!(got, want, "through the fmi crate vs in-process after 1 s");
    assert!(
        got[0].abs() > 0.1,
        "the pendulum should have fallen away from upright: alpha1 = {}",
        got[0]
    );
    inst.terminate().unwrap();
}
