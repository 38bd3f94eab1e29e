//! The FMI 3.0 functions of a model exported into this test binary with `export_fmi3!`: both
//! interfaces, every type the declarations have (Float64, Int32, Boolean, String, Int64 for
//! enumerations), the added `time` variable, fmi3DoStep's output arguments, the state table,
//! directional and adjoint derivatives, FMU state, and the 3.0 logger's messages.

use rustfmu::__private::abi3::*;
use rustfmu::testing::{Log, fmi3};
use std::ffi::{CStr, CString, c_char};
use std::ptr::{null, null_mut};

#[macro_use]
mod common;

#[allow(non_snake_case)] // T, the time constant's symbol
mod model {
    use rustfmu::prelude::*;

    /// How the lag reacts.
    #[derive(FmuEnum, Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
    pub enum Mode {
        /// follow u
        Follow = 1,
        /// follow 2 u
        Double = 2,
    }

    /// A first-order lag with a quadratic output: T dx/dt = k u - x, y = x^2 + u.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    pub struct Lag3 {
        /// Input u
        #[variable(vr = 0, input, continuous, start = 0.0)]
        pub u: f64,
        /// The state x
        #[variable(vr = 1, output, continuous, initial = exact, start = 0.5, depends = [x])]
        pub x: f64,
        /// d(x)/dt
        #[variable(vr = 2, name = "der(x)", local, continuous, derivative_of = x, depends = [u, x])]
        pub der_x: f64,
        /// y = x^2 + u
        #[variable(vr = 3, output, continuous, depends = [u, x])]
        pub y: f64,
        /// Time constant T
        #[variable(vr = 4, parameter, fixed, start = 0.5, unit = "s", min > 0.0)]
        pub T: f64,
        /// Mode: the gain k
        #[variable(vr = 5, parameter, fixed, start = Mode::Follow)]
        pub mode: Mode,
        /// A count
        #[variable(vr = 6, parameter, fixed, start = 3, min = 1, max = 9)]
        pub count: i32,
        /// A switch
        #[variable(vr = 7, parameter, fixed, start = false)]
        pub switch: bool,
        /// A label
        #[variable(vr = 8, parameter, fixed, start = "lag")]
        pub label: String,
    }

    impl Model for Lag3 {
        fn derivatives<D: Real>(&self, _t: D, v: &mut Lag3Continuous<D>) {
            let k = match self.mode {
                Mode::Follow => 1.0,
                Mode::Double => 2.0,
            };
            v.der_x = (v.u * k - v.x) / self.T;
        }
        fn outputs<D: Real>(&self, _t: D, v: &mut Lag3Continuous<D>) {
            v.y = v.x * v.x + v.u;
        }
    }

    impl CoSimulation for Lag3 {}

    rustfmu::export_fmi3!(Lag3);
}
use model::__rustfmu_fmi3_exports::*;

const TIME_VR: u32 = 9;

/// A refused call: what it is, the call, words its message must contain.
type Refusal<'a> = (&'a str, &'a dyn Fn() -> fmi3Status, &'a [&'a str]);

/// The messages so far as (status, category, message), taken from the log; every one in FMI
/// 3.0's words (the core words its messages in the calling layer's terms, nothing is rewritten
/// after the fact).
fn taken(log: &Log) -> Vec<(fmi3Status, String, String)> {
    let entries: Vec<_> = log.take().into_iter().map(|e| (e.status, e.category, e.text)).collect();
    for (_, _, message) in &entries {
        for word in ["fmi2", "GUID", "StepComplete", "StepFailed", "FMUstate"] {
            assert!(!message.contains(word), "an FMI 3.0 message says {word:?}: {message}");
        }
    }
    entries
}

fn token() -> CString {
    CString::new(TOKEN).unwrap()
}

fmi3_instances!("cs", "me");

fn get(c: fmi3Instance, vrs: &[u32]) -> (fmi3Status, Vec<f64>) {
    let mut v = vec![f64::NAN; vrs.len()];
    // SAFETY: arrays of the given lengths.
    let s = unsafe { fmi3GetFloat64(c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr(), v.len()) };
    (s, v)
}

struct Step {
    status: fmi3Status,
    event: bool,
    terminate: bool,
    early: bool,
    last: f64,
}

fn step(c: fmi3Instance, t: f64, h: f64) -> Step {
    let (mut event, mut terminate, mut early, mut last) = (true, true, true, f64::NAN);
    // SAFETY: valid output pointers.
    let status = unsafe { fmi3DoStep(c, t, h, false, &mut event, &mut terminate, &mut early, &mut last) };
    Step {
        status,
        event,
        terminate,
        early,
        last,
    }
}

fn logged(log: &Log, status: fmi3Status, words: &[&str]) {
    let entries = taken(log);
    assert!(
        entries
            .iter()
            .any(|(s, _, m)| *s == status && words.iter().all(|w| m.contains(w))),
        "no message with status {status} containing {words:?} in {entries:?}"
    );
}

#[test]
fn co_simulation_steps_report_their_outputs_truthfully_and_time_is_a_variable() {
    let (c, _log) = cs();
    init(c);
    let mut x = 0.5;
    for k in 0..10 {
        let t = k as f64 * 0.01;
        let s = step(c, t, 0.01);
        assert_eq!(s.status, fmi3OK);
        assert!(!s.event && !s.terminate && !s.early);
        assert!((s.last - (t + 0.01)).abs() < 1e-15);
        x *= (-0.01f64 / 0.5).exp(); // u = 0: x decays exactly
    }
    let (s, v) = get(c, &[1, TIME_VR, 3]);
    assert_eq!(s, fmi3OK);
    assert!((v[0] - x).abs() < 1e-9, "{} vs {x}", v[0]);
    assert!((v[1] - 0.1).abs() < 1e-12, "time {}", v[1]);
    assert!((v[2] - x * x).abs() < 1e-9);
    // SAFETY: a live instance, freed once.
    unsafe { fmi3FreeInstance(c) };
}

#[test]
fn time_cannot_be_set_and_a_wrong_n_values_is_refused_with_nothing_changed() {
    let (c, log) = initialized();
    let vr = [TIME_VR];
    // SAFETY: arrays of the given lengths.
    unsafe {
        assert_eq!(fmi3SetFloat64(c, vr.as_ptr(), 1, [3.0].as_ptr(), 1), fmi3Error);
        logged(log, fmi3Error, &["fmi3SetFloat64", "'time'", "independent"]);
        assert_eq!(fmi3Reset(c), fmi3OK);
        init(c);
        let vrs = [0u32];
        assert_eq!(fmi3SetFloat64(c, vrs.as_ptr(), 1, [1.0, 2.0].as_ptr(), 2), fmi3Error);
        logged(log, fmi3Error, &["nValues = 2", "nValueReferences = 1"]);
        assert_eq!(get(c, &[0]).1, vec![0.0]);
        fmi3FreeInstance(c);
    }
}

#[test]
fn every_type_has_its_own_accessor_and_enumerations_are_int64() {
    let (c, log) = cs();
    // SAFETY: arrays of the given lengths, in Instantiated (parameters settable).
    unsafe {
        let mode = [5u32];
        let count = [6u32];
        // Each refusal is an fmi3Error, after which the FMU is Terminated until fmi3Reset.
        let refusals: [Refusal; 5] = [
            (
                "item",
                &|| fmi3SetInt64(c, mode.as_ptr(), 1, [7i64].as_ptr(), 1),
                &["no item of the enumeration"],
            ),
            (
                "range",
                &|| fmi3SetInt64(c, mode.as_ptr(), 1, [1i64 << 40].as_ptr(), 1),
                &["no item of its enumeration"],
            ),
            (
                "Int32 of an enumeration",
                &|| fmi3SetInt32(c, mode.as_ptr(), 1, [1].as_ptr(), 1),
                &["'mode'", "Enumeration", "fmi3GetInt64/fmi3SetInt64"],
            ),
            (
                "Int64 of an Int32",
                &|| fmi3SetInt64(c, count.as_ptr(), 1, [4].as_ptr(), 1),
                &["'count'", "Int32"],
            ),
            (
                "Float32",
                &|| fmi3SetFloat32(c, count.as_ptr(), 1, [1.0f32].as_ptr(), 1),
                &["fmi3SetFloat32", "('count') is an Int32 variable, not a Float32"],
            ),
        ];
        for (what, call, words) in refusals {
            assert_eq!(call(), fmi3Error, "{what}");
            logged(log, fmi3Error, words);
            assert_eq!(fmi3Reset(c), fmi3OK);
        }
        assert_eq!(fmi3SetInt64(c, mode.as_ptr(), 1, [2i64].as_ptr(), 1), fmi3OK);
        assert_eq!(fmi3SetInt32(c, count.as_ptr(), 1, [4].as_ptr(), 1), fmi3OK);
        let switch = [7u32];
        assert_eq!(fmi3SetBoolean(c, switch.as_ptr(), 1, [true].as_ptr(), 1), fmi3OK);
        let label = [8u32];
        assert_eq!(
            fmi3SetString(c, label.as_ptr(), 1, [c"fast".as_ptr()].as_ptr(), 1),
            fmi3OK
        );
        assert_eq!(fmi3SetUInt8(c, null(), 0, null(), 0), fmi3OK);

        init(c);
        let mut e = [0i64];
        assert_eq!(fmi3GetInt64(c, mode.as_ptr(), 1, e.as_mut_ptr(), 1), fmi3OK);
        assert_eq!(e, [2]);
        let mut n = [0i32];
        assert_eq!(fmi3GetInt32(c, count.as_ptr(), 1, n.as_mut_ptr(), 1), fmi3OK);
        assert_eq!(n, [4]);
        let mut b = [false];
        assert_eq!(fmi3GetBoolean(c, switch.as_ptr(), 1, b.as_mut_ptr(), 1), fmi3OK);
        assert_eq!(b, [true]);
        let mut s = [null::<c_char>()];
        assert_eq!(fmi3GetString(c, label.as_ptr(), 1, s.as_mut_ptr(), 1), fmi3OK);
        assert_eq!(CStr::from_ptr(s[0]).to_str().unwrap(), "fast");
        // Mode::Double: x follows 2u.
        assert_eq!(fmi3SetFloat64(c, [0u32].as_ptr(), 1, [1.0].as_ptr(), 1), fmi3OK);
        let mut t = 0.0;
        for _ in 0..2000 {
            assert_eq!(step(c, t, 0.005).status, fmi3OK);
            t += 0.005;
        }
        assert!((get(c, &[1]).1[0] - 2.0).abs() < 1e-6);
        fmi3FreeInstance(c);
    }
}

/// FMI 3.0.2 lets an importer read start values in Instantiated (fmi-standard #2174): every
/// variable with a start value answers it (or the value set since), in both interfaces and after
/// fmi3Reset; a calculated one and `time` have none yet and are refused, naming the variable.
#[test]
fn start_values_are_readable_in_instantiated_and_calculated_values_are_not() {
    for (c, log) in [cs(), me()] {
        // SAFETY: arrays of the given lengths on a live instance.
        unsafe {
            // u (input, start 0), x (output, initial exact, start 0.5), T (parameter, start 0.5).
            assert_eq!(get(c, &[0, 1, 4]), (fmi3OK, vec![0.0, 0.5, 0.5]));
            let mut e = [0i64];
            assert_eq!(fmi3GetInt64(c, [5u32].as_ptr(), 1, e.as_mut_ptr(), 1), fmi3OK);
            assert_eq!(e, [1]);
            let mut n = [0i32];
            assert_eq!(fmi3GetInt32(c, [6u32].as_ptr(), 1, n.as_mut_ptr(), 1), fmi3OK);
            assert_eq!(n, [3]);
            let mut b = [true];
            assert_eq!(fmi3GetBoolean(c, [7u32].as_ptr(), 1, b.as_mut_ptr(), 1), fmi3OK);
            assert_eq!(b, [false]);
            let mut text = [null::<c_char>()];
            assert_eq!(fmi3GetString(c, [8u32].as_ptr(), 1, text.as_mut_ptr(), 1), fmi3OK);
            assert_eq!(CStr::from_ptr(text[0]).to_str().unwrap(), "lag");
            // A value set in Instantiated is what a get answers there.
            assert_eq!(fmi3SetFloat64(c, [4u32].as_ptr(), 1, [0.25].as_ptr(), 1), fmi3OK);
            assert_eq!(get(c, &[4]), (fmi3OK, vec![0.25]));
            assert!(taken(log).iter().all(|(s, _, _)| *s == fmi3OK));

            // y is calculated: no value before initialization. Refused whole (nothing written).
            let (s, v) = get(c, &[0, 3]);
            assert_eq!(s, fmi3Error);
            assert!(v.iter().all(|x| x.is_nan()), "a refused get wrote {v:?}");
            logged(
                log,
                fmi3Error,
                &["fmi3GetFloat64", "'y'", "no value before initialization"],
            );
            assert_eq!(fmi3Reset(c), fmi3OK);
            assert_eq!(get(c, &[TIME_VR]).0, fmi3Error);
            logged(log, fmi3Error, &["'time'", "no start value"]);
            // After fmi3Reset: the start values again, not the value set before.
            assert_eq!(fmi3Reset(c), fmi3OK);
            assert_eq!(get(c, &[4]), (fmi3OK, vec![0.5]));
            // Once initialized, every variable reads.
            assert_eq!(fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0), fmi3OK);
            assert_eq!(get(c, &[3, TIME_VR]), (fmi3OK, vec![0.25, 0.0]));
            fmi3FreeInstance(c);
        }
    }
}

#[test]
fn the_state_table_is_fmi_3() {
    let (c, log) = cs();
    // SAFETY: a live instance; every refused call leaves it unchanged.
    unsafe {
        assert_eq!(fmi3ExitInitializationMode(c), fmi3Error);
        logged(
            log,
            fmi3Error,
            &["fmi3ExitInitializationMode", "not allowed in state Instantiated"],
        );
        // FMI 3.0, 2.3.1: after fmi3Error the FMU is Terminated until fmi3Reset.
        assert_eq!(fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0), fmi3Error);
        logged(log, fmi3Error, &["not allowed in state Terminated"]);
        assert_eq!(fmi3Reset(c), fmi3OK);
        assert_eq!(fmi3EnterConfigurationMode(c), fmi3Error);
        logged(log, fmi3Error, &["no structural parameters"]);
        assert_eq!(fmi3Reset(c), fmi3OK);
        init(c);
        assert_eq!(fmi3EnterEventMode(c), fmi3Error);
        logged(
            log,
            fmi3Error,
            &[
                "fmi3EnterEventMode",
                "co-simulation with event mode",
                "eventModeUsed = false",
            ],
        );
        assert_eq!(fmi3Reset(c), fmi3OK);
        init(c);
        assert_eq!(fmi3EnterStepMode(c), fmi3Error);
        assert_eq!(fmi3Reset(c), fmi3OK);
        init(c);
        let mut dx = [0.0];
        assert_eq!(fmi3GetContinuousStateDerivatives(c, dx.as_mut_ptr(), 1), fmi3Error);
        logged(log, fmi3Error, &["fmi3GetContinuousStateDerivatives"]);
        assert_eq!(fmi3Reset(c), fmi3OK);
        init(c);
        assert_eq!(fmi3Terminate(c), fmi3OK);
        assert_eq!(step(c, 0.0, 0.1).status, fmi3Error);
        logged(
            log,
            fmi3Error,
            &["fmi3DoStep", "not allowed in state Terminated", "StepMode"],
        );
        assert_eq!(fmi3Reset(c), fmi3OK);
        init(c);
        assert_eq!(step(c, 0.0, 0.1).status, fmi3OK);
        fmi3FreeInstance(c);
    }
}

#[test]
fn instantiation_refuses_a_wrong_token_a_missing_name_and_event_mode() {
    let log = Log::leak();
    let how = fmi3::Instantiation::new("x");
    let c = how.model_exchange(fmi3InstantiateModelExchange, "{nope}", log);
    assert!(c.is_null());
    logged(log, fmi3Error, &["instantiationToken '{nope}'"]);
    // Event mode is offered (hasEventMode="true"): the instance is made.
    let c = fmi3::Instantiation {
        event_mode_used: true,
        ..how
    }
    .co_simulation(fmi3InstantiateCoSimulation, TOKEN, log, None);
    assert!(!c.is_null());
    // SAFETY: a live instance, freed once.
    unsafe { fmi3FreeInstance(c) };
    let c = how.scheduled_execution(fmi3InstantiateScheduledExecution, TOKEN, log, None);
    assert!(c.is_null());
    // SAFETY: NULL for the name; valid strings otherwise.
    unsafe {
        let c = fmi3InstantiateModelExchange(
            null(),
            token().as_ptr(),
            null(),
            false,
            false,
            fmi3::environment(log),
            Some(fmi3::logger::<Log>),
        );
        assert!(c.is_null());
        // No logger at all: allowed in FMI 3.0, and the instance works.
        let c = fmi3InstantiateModelExchange(
            c"quiet".as_ptr(),
            token().as_ptr(),
            null(),
            false,
            true,
            null_mut(),
            None,
        );
        assert!(!c.is_null());
        assert_eq!(fmi3ExitInitializationMode(c), fmi3Error);
        fmi3FreeInstance(c);
    }
}

#[test]
fn model_exchange_integrates_and_adjoint_is_the_transpose_of_directional() {
    let (c, _log) = me();
    // SAFETY: a live instance and arrays of the given lengths.
    unsafe {
        let mut n = 0usize;
        assert_eq!(fmi3GetNumberOfContinuousStates(c, &mut n), fmi3OK);
        assert_eq!(n, 1);
        assert_eq!(fmi3GetNumberOfEventIndicators(c, &mut n), fmi3OK);
        assert_eq!(n, 0);
        assert_eq!(fmi3EnterInitializationMode(c, true, 1e-6, 0.0, true, 10.0), fmi3OK);
        let mut dx = [0.0];
        // 3.0 allows the derivatives in initialization mode.
        assert_eq!(fmi3GetContinuousStateDerivatives(c, dx.as_mut_ptr(), 1), fmi3OK);
        assert_eq!(dx, [-1.0]);
        assert_eq!(fmi3ExitInitializationMode(c), fmi3OK);
        let (mut a, mut b, mut d, mut e, mut f, mut g) = (true, true, true, true, true, 1.0);
        assert_eq!(
            fmi3UpdateDiscreteStates(c, &mut a, &mut b, &mut d, &mut e, &mut f, &mut g),
            fmi3OK
        );
        assert!(!a && !b && !d && !e && !f);
        assert_eq!(fmi3EnterContinuousTimeMode(c), fmi3OK);
        assert_eq!(fmi3SetFloat64(c, [0u32].as_ptr(), 1, [0.3].as_ptr(), 1), fmi3OK);
        // knowns u (vr 0), x (vr 1); unknowns der(x) (vr 2), y (vr 3).
        let knowns = [0u32, 1];
        let unknowns = [2u32, 3];
        let mut jac = [[0.0; 2]; 2];
        for (j, seed) in [[1.0, 0.0], [0.0, 1.0]].iter().enumerate() {
            let mut col = [0.0; 2];
            assert_eq!(
                fmi3GetDirectionalDerivative(
                    c,
                    unknowns.as_ptr(),
                    2,
                    knowns.as_ptr(),
                    2,
                    seed.as_ptr(),
                    2,
                    col.as_mut_ptr(),
                    2
                ),
                fmi3OK
            );
            jac[0][j] = col[0];
            jac[1][j] = col[1];
        }
        // d der(x)/du = 1/T = 2, d der(x)/dx = -2, dy/du = 1, dy/dx = 2x = 1.
        assert_eq!(jac, [[2.0, -2.0], [1.0, 1.0]]);
        let w = [0.7, -1.3];
        let mut adj = [0.0; 2];
        // The adjoint of the unknowns der(x), y with the seeds w, for the first n_knowns knowns.
        let adjoint = |n_knowns: usize, adj: &mut [f64; 2]| {
            fmi3GetAdjointDerivative(
                c,
                unknowns.as_ptr(),
                2,
                knowns.as_ptr(),
                n_knowns,
                w.as_ptr(),
                2,
                adj.as_mut_ptr(),
                2,
            )
        };
        assert_eq!(adjoint(2, &mut adj), fmi3OK);
        for j in 0..2 {
            let expected = jac[0][j] * w[0] + jac[1][j] * w[1];
            assert!((adj[j] - expected).abs() < 1e-15, "{adj:?}");
        }
        // Explicit Euler: x' = (u - x)/T.
        let (mut x, h) = (0.5, 1e-3);
        let mut t = 0.0;
        for _ in 0..1000 {
            assert_eq!(fmi3GetContinuousStateDerivatives(c, dx.as_mut_ptr(), 1), fmi3OK);
            x += h * dx[0];
            t += h;
            assert_eq!(fmi3SetTime(c, t), fmi3OK);
            assert_eq!(fmi3SetContinuousStates(c, [x].as_ptr(), 1), fmi3OK);
            let (mut ev, mut term) = (true, true);
            assert_eq!(fmi3CompletedIntegratorStep(c, true, &mut ev, &mut term), fmi3OK);
            assert!(!ev && !term);
        }
        let exact = 0.3 + 0.2 * (-2.0f64).exp();
        assert!((x - exact).abs() < 1e-3, "{x} vs {exact}");
        assert!((get(c, &[TIME_VR]).1[0] - 1.0).abs() < 1e-12);
        assert_eq!(fmi3EnterEventMode(c), fmi3OK);
        // Wrong sizes are refused (nSeed = nUnknowns for the adjoint).
        assert_eq!(adjoint(1, &mut adj), fmi3Error);
        // ... and the FMU is Terminated (FMI 3.0, 2.3.1).
        assert_eq!(fmi3Terminate(c), fmi3Error);
        fmi3FreeInstance(c);
    }
}

#[test]
fn an_fmu_state_round_trips_through_serialization() {
    let (c, _log) = cs();
    init(c);
    // SAFETY: a live instance; the states are this FMU's.
    unsafe {
        assert_eq!(fmi3SetFloat64(c, [0u32].as_ptr(), 1, [1.0].as_ptr(), 1), fmi3OK);
        assert_eq!(step(c, 0.0, 0.1).status, fmi3OK);
        let mut s: fmi3FMUState = null_mut();
        assert_eq!(fmi3GetFMUState(c, &mut s), fmi3OK);
        let mut size = 0usize;
        assert_eq!(fmi3SerializedFMUStateSize(c, s, &mut size), fmi3OK);
        let mut bytes = vec![0u8; size];
        assert_eq!(fmi3SerializeFMUState(c, s, bytes.as_mut_ptr(), size), fmi3OK);
        let at = get(c, &[1, TIME_VR]).1;
        assert_eq!(step(c, 0.1, 0.1).status, fmi3OK);
        let mut r: fmi3FMUState = null_mut();
        assert_eq!(fmi3DeserializeFMUState(c, bytes.as_ptr(), size, &mut r), fmi3OK);
        assert_eq!(fmi3SetFMUState(c, r), fmi3OK);
        assert_eq!(get(c, &[1, TIME_VR]).1, at);
        bytes[size / 2] ^= 0xff;
        let mut bad: fmi3FMUState = null_mut();
        assert_eq!(fmi3DeserializeFMUState(c, bytes.as_ptr(), size, &mut bad), fmi3Error);
        assert_eq!(fmi3FreeFMUState(c, &mut s), fmi3OK);
        assert_eq!(fmi3FreeFMUState(c, &mut r), fmi3OK);
        fmi3FreeInstance(c);
    }
}

#[test]
fn messages_speak_fmi_3() {
    let (c, log) = me();
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(
            fmi3SetDebugLogging(c, true, 1, [c"logNoSuchThing".as_ptr()].as_ptr()),
            fmi3Error
        );
        logged(log, fmi3Error, &["fmi3SetDebugLogging", "unknown log category"]);
        assert_eq!(fmi3Reset(c), fmi3OK);
        assert_eq!(
            fmi3EnterInitializationMode(c, false, 0.0, f64::NAN, false, 0.0),
            fmi3Error
        );
        logged(log, fmi3Error, &["fmi3EnterInitializationMode", "startTime = NaN"]);
        assert_eq!(fmi3Reset(c), fmi3OK);
        assert_eq!(fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0), fmi3OK);
        assert_eq!(fmi3ExitInitializationMode(c), fmi3OK);
        assert_eq!(fmi3EnterContinuousTimeMode(c), fmi3OK);
        let mut dx = [0.0; 3];
        assert_eq!(fmi3GetContinuousStateDerivatives(c, dx.as_mut_ptr(), 3), fmi3Error);
        let entries = taken(log);
        assert!(
            entries.iter().any(|(s, cat, m)| *s == fmi3Error
                && cat == "logStatusError"
                && m.contains("fmi3GetContinuousStateDerivatives: nx = 3")),
            "{entries:?}"
        );
        assert!(entries.iter().all(|(_, _, m)| !m.contains("fmi2")), "{entries:?}");
        fmi3FreeInstance(c);
    }
}
