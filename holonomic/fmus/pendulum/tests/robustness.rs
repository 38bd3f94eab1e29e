//! The Pendulum FMU through its C API (linked into this test binary) where the issue "nothing
//! wrong ever leaves an FMU with fmi2OK" found it wanting: absolute start times, tolerances at
//! the ends of their ranges, non-finite results of finite inputs, doctored serialized states.

use pendulum_fmu::Pendulum;
use pendulum_fmu::*;
use rustfmu::__private::abi::*;
use rustfmu::Variables;
use rustfmu::testing::Log;

fn vr(name: &str) -> u32 {
    Pendulum::DESCRIPTION
        .by_name(name)
        .unwrap_or_else(|| panic!("the Pendulum has no variable '{name}'"))
        .value_reference
}

struct Fmu {
    c: fmi2Component,
    log: &'static Log,
    time: f64,
}

impl Fmu {
    /// Instantiated, fmi2SetupExperiment(startTime = t0), in initialization mode.
    fn new(t0: f64) -> Fmu {
        let log = Log::leak();
        let c = rustfmu::testing::fmi2::cs_instance(
            fmi2Instantiate,
            pendulum_fmu::__rustfmu_fmi2_exports::GUID,
            c"robustness",
            log,
        );
        // SAFETY: a live instance.
        unsafe {
            assert_eq!(fmi2SetupExperiment(c, fmi2False, 0.0, t0, fmi2False, 0.0), fmi2OK);
            assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        }
        Fmu { c, log, time: t0 }
    }

    fn set(&self, values: &[(&str, f64)]) -> fmi2Status {
        let (vrs, xs): (Vec<u32>, Vec<f64>) = values.iter().map(|(n, x)| (vr(n), *x)).unzip();
        // SAFETY: as many references as values.
        unsafe { fmi2SetReal(self.c, vrs.as_ptr(), vrs.len(), xs.as_ptr()) }
    }

    fn get(&self, names: &[&str]) -> Vec<f64> {
        let vrs: Vec<u32> = names.iter().map(|n| vr(n)).collect();
        let mut out = vec![0.0; vrs.len()];
        // SAFETY: as many references as slots.
        let s = unsafe { fmi2GetReal(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) };
        assert_eq!(s, fmi2OK, "fmi2GetReal: {:?}", self.messages());
        out
    }

    fn exit_init(&self) -> fmi2Status {
        // SAFETY: a live instance.
        unsafe { fmi2ExitInitializationMode(self.c) }
    }

    fn step(&mut self, h: f64) -> fmi2Status {
        // SAFETY: a live instance.
        let s = unsafe { fmi2DoStep(self.c, self.time, h, fmi2True) };
        if s == fmi2OK {
            self.time += h;
        }
        s
    }

    fn messages(&self) -> Vec<(fmi2Status, String)> {
        self.log.take_texts()
    }

    fn assert_logged(&self, status: fmi2Status, words: &[&str]) {
        let entries = self.messages();
        assert!(
            entries
                .iter()
                .any(|(s, text)| *s == status && words.iter().all(|w| text.contains(w))),
            "expected a message with status {status} saying {words:?}, got {entries:?}"
        );
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        // SAFETY: from fmi2Instantiate, freed once.
        unsafe { fmi2FreeInstance(self.c) };
    }
}

const STATE: [&str; 4] = ["alpha1", "omega1", "alpha2", "omega2"];

#[test]
fn a_unix_time_stamp_as_start_time_does_not_discard_the_first_step_from_rest() {
    let mut p = Fmu::new(1.7e9);
    assert_eq!(p.exit_init(), fmi2OK);
    let s = p.step(1e-3);
    assert_eq!(s, fmi2OK, "first 1 ms step from rest at t0 = 1.7e9: {:?}", p.messages());
}

#[test]
fn the_trajectory_does_not_depend_on_the_start_time() {
    let run = |t0: f64| {
        let mut p = Fmu::new(t0);
        assert_eq!(
            p.set(&[("alpha1_0", 2.5), ("alpha2_0", -1.0), ("rtol", 1e-10), ("atol", 1e-10)]),
            fmi2OK
        );
        assert_eq!(p.exit_init(), fmi2OK);
        let h = 1e-3;
        for k in 0..2000 {
            // The importer's time stamps: t0 + k h, as fmpy computes them.
            p.time = t0 + k as f64 * h;
            assert_eq!(p.step(h), fmi2OK, "t0 = {t0}, step {k}: {:?}", p.messages());
        }
        p.get(&STATE)
    };
    let (from_zero, from_1e6) = (run(0.0), run(1e6));
    assert_eq!(
        from_zero, from_1e6,
        "2 s from t0 = 0 and from t0 = 1e6 (the same steps of 1 ms) must give the same state"
    );
}

#[test]
fn an_initialization_to_a_non_finite_energy_is_an_error_naming_it() {
    for start in [&[("omega1_0", 1e200)][..], &[("l1", 1e300), ("omega1_0", 1.0)]] {
        let p = Fmu::new(0.0);
        assert_eq!(p.set(start), fmi2OK, "{start:?} are finite and legal");
        let s = p.exit_init();
        assert_eq!(
            s, fmi2Error,
            "{start:?}: fmi2ExitInitializationMode must not return {s}"
        );
        p.assert_logged(
            fmi2Error,
            &["fmi2ExitInitializationMode", "'energy' (vr 6)", "not a finite number"],
        );
    }
}

#[test]
fn the_absolute_tolerance_is_declared_positive_and_any_positive_value_works() {
    // atol = 0 would make the error norm 0/0 at rest (every state component is exactly 0 at the
    // default start): it is outside the declared domain and refused, naming it.
    let p = Fmu::new(0.0);
    assert_eq!(p.set(&[("atol", 0.0)]), fmi2Error, "atol = 0 must be refused");
    p.assert_logged(fmi2Error, &["'atol'", "outside (0, 1]"]);
    // The smallest positive ones give pure relative error control wherever the state is not 0.
    for atol in [5e-324, 1e-300, 1e-20] {
        for start in [&[("M1", 1.0)][..], &[], &[("alpha1_0", 2.5), ("alpha2_0", -1.0)]] {
            let mut p = Fmu::new(0.0);
            assert_eq!(p.set(&[("atol", atol), ("rtol", 1e-8)]), fmi2OK);
            assert_eq!(p.set(start), fmi2OK);
            assert_eq!(p.exit_init(), fmi2OK);
            for k in 0..100 {
                let s = p.step(1e-3);
                assert_eq!(s, fmi2OK, "atol = {atol:e}, {start:?}, step {k}: {:?}", p.messages());
            }
        }
    }
}

#[test]
fn masses_and_lengths_outside_their_declared_domain_are_refused_naming_them() {
    for var in ["m1", "m2", "l1", "l2"] {
        for bad in [0.0, -1.0, -5e-324] {
            let p = Fmu::new(0.0);
            assert_eq!(p.set(&[(var, bad)]), fmi2Error, "{var} = {bad} must be refused");
            p.assert_logged(fmi2Error, &[&format!("for '{var}'"), "outside (0, inf)"]);
            assert_eq!(p.exit_init(), fmi2OK, "the refusal changed nothing");
        }
    }
}

#[test]
fn a_deserialized_state_with_a_correct_checksum_but_illegal_content_is_refused() {
    use rustfmu::core::instance::Sim;
    use rustfmu::core::state;
    let guid = pendulum_fmu::__rustfmu_fmi2_exports::GUID;
    let mut p = Fmu::new(0.0);
    assert_eq!(p.set(&[("alpha1_0", 0.3)]), fmi2OK);
    assert_eq!(p.exit_init(), fmi2OK);
    assert_eq!(p.step(1e-3), fmi2OK);
    // SAFETY: p.c is a live instance; the buffers are as large as passed.
    let good = unsafe {
        let mut s: fmi2FMUstate = std::ptr::null_mut();
        assert_eq!(fmi2GetFMUstate(p.c, &mut s), fmi2OK);
        let mut n = 0;
        assert_eq!(fmi2SerializedFMUstateSize(p.c, s, &mut n), fmi2OK);
        let mut bytes = vec![0u8; n];
        assert_eq!(
            fmi2SerializeFMUstate(p.c, s, bytes.as_mut_ptr() as *mut fmi2Byte, n),
            fmi2OK
        );
        assert_eq!(fmi2FreeFMUstate(p.c, &mut s), fmi2OK);
        bytes
    };
    type Doctor = fn(&mut Sim<Pendulum>);
    let cases: [(&str, Doctor, &str); 4] = [
        ("alpha1 = NaN", |s| s.model.alpha1 = f64::NAN, "NaN for 'alpha1'"),
        (
            "m1 = -1",
            |s| s.model.m1 = -1.0,
            "-1 for 'm1' (vr 20) is outside (0, inf)",
        ),
        (
            "rtol = -1",
            |s| s.model.rtol = -1.0,
            "-1 for 'rtol' (vr 30) is outside [0.00000000000001, 0.1]",
        ),
        ("h_next = NaN", |s| s.solver.h_next = f64::NAN, "h_next = NaN"),
    ];
    for (what, doctor, says) in cases {
        let mut sim = state::deserialize::<Pendulum>(&rustfmu::fmi2::TERMS, guid, &good).unwrap();
        doctor(&mut sim);
        let bytes = state::serialize(guid, &sim).unwrap();
        let mut s: fmi2FMUstate = std::ptr::null_mut();
        // SAFETY: bytes.len() readable bytes; s is an FMUstate slot.
        let status = unsafe { fmi2DeSerializeFMUstate(p.c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), &mut s) };
        assert_eq!(
            status, fmi2Error,
            "a state with {what} and a correct checksum was accepted"
        );
        assert!(s.is_null());
        p.assert_logged(fmi2Error, &["fmi2DeSerializeFMUstate", says]);
    }
}

/// The initial state is the parameters alpha1_0..omega2_0 (what SSP importers apply); the states
/// are calculated from them, so setting a state itself is refused, naming it.
#[test]
fn the_initial_state_is_the_parameters_and_a_state_takes_no_value() {
    let p = Fmu::new(0.0);
    assert_eq!(
        p.set(&[("alpha1", 0.3)]),
        fmi2Error,
        "alpha1 is calculated: it takes no value"
    );
    p.assert_logged(fmi2Error, &["'alpha1'"]);
    let start = [0.3, -0.2, 0.1, 0.4];
    let names = ["alpha1_0", "omega1_0", "alpha2_0", "omega2_0"];
    let values: Vec<(&str, f64)> = names.iter().copied().zip(start).collect();
    assert_eq!(p.set(&values), fmi2OK);
    assert_eq!(
        p.get(&STATE),
        start,
        "in initialization mode the states already follow the parameters"
    );
    assert_eq!(p.exit_init(), fmi2OK);
    assert_eq!(p.get(&STATE), start, "the states start at alpha1_0..omega2_0");
}
