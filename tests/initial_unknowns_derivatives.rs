//! Issue 52, item 7: in Initialization Mode the directional derivatives are those of the
//! InitialUnknowns with respect to the knowns of that mode (FMI 2.0 section 2.1.9: "Initialization
//! Mode: unknowns listed under `<ModelStructure><InitialUnknowns>` that have type Real"; FMI 3.0
//! section 2.2.11: "the exposed unknowns listed as elements `<InitialUnknown>` in
//! `<ModelStructure>` that have a floating point type", the knowns "the vector of arguments ... that
//! could appear in `dependencies`"). The built Pendulum, DCMotor and Controller libraries are loaded
//! as an importer loads them; in Initialization Mode every Real InitialUnknown is asked for its
//! derivative with respect to every Real known its `initial_depends` declares, through
//! fmi2GetDirectionalDerivative and fmi3GetDirectionalDerivative (and fmi3GetAdjointDerivative),
//! and compared with central differences of the value read after setting the known, still in
//! Initialization Mode (forward ones at a declared minimum); a few against their analytic values.
//!
//! Needs the libraries of the same profile:
//! `cargo build --release -p pendulum-fmu -p dc-motor-fmu -p controller-fmu` (or `cargo fmu
//! build`); `RUSTFMU_FMU_LIBS` names another folder.

use rustfmu::__private::abi::*;
use rustfmu::__private::abi3 as v3;
use rustfmu::description::{FmiVersion, ModelDescription, VarType, Variable, decode, find_encoded_for, guid_string};
use std::path::PathBuf;

use rustfmu::testing::fmi2;
use rustfmu::testing::fmi3;

/// A built FMU library and its FMI 2.0 and 3.0 descriptions.
struct Library {
    name: &'static str,
    lib: libloading::Library,
    /// The FMI 2.0 description (an array is its elements there) and the FMI 3.0 one.
    md2: ModelDescription,
    md3: ModelDescription,
    guid: String,
    token: String,
}

fn library_dir() -> PathBuf {
    match std::env::var_os("RUSTFMU_FMU_LIBS") {
        Some(dir) => PathBuf::from(dir),
        // target/<profile>/deps/<this test> -> target/<profile>
        None => std::env::current_exe()
            .unwrap()
            .parent()
            .unwrap()
            .parent()
            .unwrap()
            .to_path_buf(),
    }
}

impl Library {
    fn load(name: &'static str, crate_name: &str) -> Library {
        let path = library_dir().join(format!(
            "{}{crate_name}{}",
            std::env::consts::DLL_PREFIX,
            std::env::consts::DLL_SUFFIX
        ));
        let binary = std::fs::read(&path).unwrap_or_else(|e| {
            panic!(
                "{}: {e}: build it first: cargo build --release -p pendulum-fmu -p dc-motor-fmu -p controller-fmu",
                path.display()
            )
        });
        let encoded2 = find_encoded_for(&binary, FmiVersion::V2).unwrap();
        let encoded3 = find_encoded_for(&binary, FmiVersion::V3).unwrap();
        let (md2, _) = decode(encoded2).unwrap();
        let (md3, _) = decode(encoded3).unwrap();
        // SAFETY: an FMU's binary; loading it runs no initializer beyond Rust's own.
        let lib = unsafe { libloading::Library::new(&path) }.unwrap_or_else(|e| panic!("{name}: {e}"));
        Library {
            name,
            lib,
            md2,
            md3,
            guid: guid_string(encoded2),
            token: guid_string(encoded3),
        }
    }

    /// The C function `symbol` as a `T`.
    ///
    /// # Safety
    /// `T` is the function's signature (fmi2Functions.h / fmi3Functions.h).
    unsafe fn get<T: Copy>(&self, symbol: &str) -> T {
        // SAFETY: the caller's.
        unsafe {
            *self
                .lib
                .get::<T>(symbol.as_bytes())
                .unwrap_or_else(|e| panic!("{}: {e}", self.name))
        }
    }

    fn vr(&self, name: &str) -> u32 {
        self.md3
            .by_name(name)
            .unwrap_or_else(|| panic!("{}: no '{name}'", self.name))
            .value_reference
    }

    /// Every (InitialUnknown, known) pair of Real variables its `initial_depends` declares in
    /// the description `md`.
    fn declared_pairs(md: &ModelDescription) -> Vec<(&'static Variable, &'static Variable)> {
        let mut pairs = vec![];
        for u in md
            .variables
            .iter()
            .filter(|v| v.var_type == VarType::Real && md.is_initial_unknown(v))
        {
            for d in md.dependencies(u.value_reference, true, u32::MAX).unwrap() {
                if let Some(k) = md
                    .variables
                    .iter()
                    .find(|v| v.value_reference == d && v.var_type == VarType::Real)
                {
                    pairs.push((u, k));
                }
            }
        }
        pairs
    }
}

/// What the comparison needs of an instance in Initialization Mode, in either version.
trait Host {
    fn set(&self, vr: u32, x: f64);
    /// The `n` values of `vr` (an FMI 3.0 array's elements).
    fn values(&self, vr: u32, n: usize) -> Vec<f64>;
    fn set_integer(&self, vr: u32, n: i32);
    fn set_boolean(&self, vr: u32, b: bool);
    /// d unknown / d known for each of the unknown's `n` values, or the status and the last
    /// message.
    fn derivatives(&self, unknown: u32, n: usize, known: u32) -> Result<Vec<f64>, String>;

    fn get(&self, vr: u32) -> f64 {
        self.values(vr, 1)[0]
    }
    fn derivative(&self, unknown: u32, known: u32) -> Result<f64, String> {
        self.derivatives(unknown, 1, known).map(|d| d[0])
    }
}

type Unary2 = unsafe extern "C" fn(fmi2Component) -> fmi2Status;
type Setup2 = unsafe extern "C" fn(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real) -> fmi2Status;
type Reals2 = unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *const fmi2Real) -> fmi2Status;
type GetReals2 = unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *mut fmi2Real) -> fmi2Status;
type Integers2 =
    unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *const fmi2Integer) -> fmi2Status;
type Directional2 = unsafe extern "C" fn(
    fmi2Component,
    *const fmi2ValueReference,
    usize,
    *const fmi2ValueReference,
    usize,
    *const fmi2Real,
    *mut fmi2Real,
) -> fmi2Status;

/// An FMI 2.0 co-simulation instance in Initialization Mode.
struct Fmi2<'a> {
    c: fmi2Component,
    log: &'static rustfmu::testing::Log,
    set: Reals2,
    get: GetReals2,
    set_integer: Integers2,
    set_boolean: Integers2,
    directional: Directional2,
    _lib: &'a Library,
}

impl<'a> Fmi2<'a> {
    fn initialization_mode(lib: &'a Library) -> Fmi2<'a> {
        let log = rustfmu::testing::Log::leak();
        // SAFETY: the functions of fmi2Functions.h with their signatures; a live instance.
        unsafe {
            let c = fmi2::cs_instance(lib.get("fmi2Instantiate"), &lib.guid, c"initial", log);
            assert_eq!(
                lib.get::<Setup2>("fmi2SetupExperiment")(c, fmi2False, 0.0, 0.0, fmi2False, 0.0),
                fmi2OK
            );
            assert_eq!(lib.get::<Unary2>("fmi2EnterInitializationMode")(c), fmi2OK);
            Fmi2 {
                c,
                log,
                set: lib.get("fmi2SetReal"),
                get: lib.get("fmi2GetReal"),
                set_integer: lib.get("fmi2SetInteger"),
                set_boolean: lib.get("fmi2SetBoolean"),
                directional: lib.get("fmi2GetDirectionalDerivative"),
                _lib: lib,
            }
        }
    }

    fn last(&self) -> String {
        self.log.entries().last().map(|e| e.text.clone()).unwrap_or_default()
    }
}

impl Host for Fmi2<'_> {
    fn set(&self, vr: u32, x: f64) {
        // SAFETY: a live instance; arrays of one element.
        let s = unsafe { (self.set)(self.c, &vr, 1, &x) };
        assert_eq!(s, fmi2OK, "fmi2SetReal(vr {vr}, {x}): {}", self.last());
    }
    fn values(&self, vr: u32, n: usize) -> Vec<f64> {
        assert_eq!(n, 1, "FMI 2.0 has no arrays");
        let mut x = f64::NAN;
        // SAFETY: as above.
        let s = unsafe { (self.get)(self.c, &vr, 1, &mut x) };
        assert_eq!(s, fmi2OK, "fmi2GetReal(vr {vr}): {}", self.last());
        vec![x]
    }
    fn set_integer(&self, vr: u32, n: i32) {
        // SAFETY: as above.
        let status = unsafe { (self.set_integer)(self.c, &vr, 1, &n) };
        assert_eq!(status, fmi2OK, "{}", self.last());
    }
    fn set_boolean(&self, vr: u32, b: bool) {
        let b = b as fmi2Boolean;
        // SAFETY: as above.
        let status = unsafe { (self.set_boolean)(self.c, &vr, 1, &b) };
        assert_eq!(status, fmi2OK, "{}", self.last());
    }
    fn derivatives(&self, unknown: u32, n: usize, known: u32) -> Result<Vec<f64>, String> {
        assert_eq!(n, 1, "FMI 2.0 has no arrays");
        let (seed, mut out) = (1.0, f64::NAN);
        // SAFETY: as above.
        let s = unsafe { (self.directional)(self.c, &unknown, 1, &known, 1, &seed, &mut out) };
        if s == fmi2OK {
            Ok(vec![out])
        } else {
            Err(format!("status {s}: {}", self.last()))
        }
    }
}

type Enter3 = unsafe extern "C" fn(v3::fmi3Instance, bool, f64, f64, bool, f64) -> v3::fmi3Status;
type Floats3 = unsafe extern "C" fn(v3::fmi3Instance, *const u32, usize, *const f64, usize) -> v3::fmi3Status;
type GetFloats3 = unsafe extern "C" fn(v3::fmi3Instance, *const u32, usize, *mut f64, usize) -> v3::fmi3Status;
type Int64s3 = unsafe extern "C" fn(v3::fmi3Instance, *const u32, usize, *const i64, usize) -> v3::fmi3Status;
type Booleans3 = unsafe extern "C" fn(v3::fmi3Instance, *const u32, usize, *const bool, usize) -> v3::fmi3Status;
type Derivative3 = unsafe extern "C" fn(
    v3::fmi3Instance,
    *const u32,
    usize,
    *const u32,
    usize,
    *const f64,
    usize,
    *mut f64,
    usize,
) -> v3::fmi3Status;

/// An FMI 3.0 co-simulation instance in Initialization Mode.
struct Fmi3<'a> {
    c: v3::fmi3Instance,
    log: &'static rustfmu::testing::Log,
    set: Floats3,
    get: GetFloats3,
    set_int64: Int64s3,
    set_boolean: Booleans3,
    directional: Derivative3,
    adjoint: Derivative3,
    _lib: &'a Library,
}

impl<'a> Fmi3<'a> {
    fn initialization_mode(lib: &'a Library) -> Fmi3<'a> {
        // SAFETY: the functions of fmi3Functions.h with their signatures; a live instance.
        unsafe {
            let (c, log) = fmi3::instance(lib.get("fmi3InstantiateCoSimulation"), &lib.token, "initial");
            assert_eq!(
                lib.get::<Enter3>("fmi3EnterInitializationMode")(c, false, 0.0, 0.0, false, 0.0),
                v3::fmi3OK,
                "{}",
                log.last()
            );
            Fmi3 {
                c,
                log,
                set: lib.get("fmi3SetFloat64"),
                get: lib.get("fmi3GetFloat64"),
                set_int64: lib.get("fmi3SetInt64"),
                set_boolean: lib.get("fmi3SetBoolean"),
                directional: lib.get("fmi3GetDirectionalDerivative"),
                adjoint: lib.get("fmi3GetAdjointDerivative"),
                _lib: lib,
            }
        }
    }
}

impl Host for Fmi3<'_> {
    fn set(&self, vr: u32, x: f64) {
        // SAFETY: a live instance; arrays of one element.
        let s = unsafe { (self.set)(self.c, &vr, 1, &x, 1) };
        assert_eq!(s, v3::fmi3OK, "fmi3SetFloat64(vr {vr}, {x}): {}", self.log.last());
    }
    fn values(&self, vr: u32, n: usize) -> Vec<f64> {
        let mut x = vec![f64::NAN; n];
        // SAFETY: as above; `x` holds the `n` values.
        let s = unsafe { (self.get)(self.c, &vr, 1, x.as_mut_ptr(), n) };
        assert_eq!(s, v3::fmi3OK, "fmi3GetFloat64(vr {vr}): {}", self.log.last());
        x
    }
    fn set_integer(&self, vr: u32, n: i32) {
        let n = n as i64;
        // SAFETY: as above.
        let status = unsafe { (self.set_int64)(self.c, &vr, 1, &n, 1) };
        assert_eq!(status, v3::fmi3OK, "{}", self.log.last());
    }
    fn set_boolean(&self, vr: u32, b: bool) {
        // SAFETY: as above.
        let status = unsafe { (self.set_boolean)(self.c, &vr, 1, &b, 1) };
        assert_eq!(status, v3::fmi3OK, "{}", self.log.last());
    }
    /// The directional derivative (an n x 1 Jacobian), whose every element the adjoint one
    /// must repeat bit for bit (its seed a unit vector over the unknown's elements).
    fn derivatives(&self, unknown: u32, n: usize, known: u32) -> Result<Vec<f64>, String> {
        let (seed, mut directional) = (1.0, vec![f64::NAN; n]);
        // SAFETY: as above; the sensitivity holds the unknown's `n` values.
        let s = unsafe { (self.directional)(self.c, &unknown, 1, &known, 1, &seed, 1, directional.as_mut_ptr(), n) };
        if s != v3::fmi3OK {
            return Err(format!("status {s}: {}", self.log.last()));
        }
        for (j, d) in directional.iter().enumerate() {
            let mut unit = vec![0.0; n];
            unit[j] = 1.0;
            let mut adjoint = f64::NAN;
            // SAFETY: as above; the seed holds the unknown's `n` values.
            let s = unsafe { (self.adjoint)(self.c, &unknown, 1, &known, 1, unit.as_ptr(), n, &mut adjoint, 1) };
            if s != v3::fmi3OK {
                return Err(format!("fmi3GetAdjointDerivative: status {s}: {}", self.log.last()));
            }
            assert_eq!(
                d.to_bits(),
                adjoint.to_bits(),
                "vr {unknown}[{j}] / vr {known}: directional {d}, adjoint {adjoint}"
            );
        }
        Ok(directional)
    }
}

/// The operating point: Real values (by name) and Integer ones, set in Initialization Mode
/// before anything is asked.
struct Point {
    reals: &'static [(&'static str, f64)],
    integers: &'static [(&'static str, i32)],
    booleans: &'static [(&'static str, bool)],
}

/// Every declared pair's derivative against finite differences (step 1e-6 of the known's
/// size): within 1e-6 relative, plus the differences' own rounding. Returns the number of pairs
/// and the largest relative difference.
fn compare_with_differences(lib: &Library, host: &dyn Host, point: &Point, version: &str) -> (usize, f64) {
    for (name, x) in point.reals {
        host.set(lib.vr(name), *x);
    }
    for (name, n) in point.integers {
        host.set_integer(lib.vr(name), *n);
    }
    for (name, b) in point.booleans {
        host.set_boolean(lib.vr(name), *b);
    }
    let pairs = Library::declared_pairs(if version == "FMI 2.0" { &lib.md2 } else { &lib.md3 });
    let mut worst: f64 = 0.0;
    let mut failures = vec![];
    for (u, k) in &pairs {
        let (uvr, kvr, n) = (u.value_reference, k.value_reference, u.element_count());
        let got = match host.derivatives(uvr, n, kvr) {
            Ok(d) => d,
            Err(e) => {
                failures.push(format!("d {}/d {}: refused ({e})", u.name, k.name));
                continue;
            }
        };
        let x = host.get(kvr);
        let y = host.values(uvr, n);
        let h = if x != 0.0 { 1e-6 * x.abs() } else { 1e-6 };
        let at = |x: f64| {
            host.set(kvr, x);
            host.values(uvr, n)
        };
        // Central differences, or second-order forward ones at a declared minimum (J2 = 0).
        let differences: Vec<f64> = if k.min.is_some_and(|b| !b.admits_above(x - h)) {
            let (a, b) = (at(x + h), at(x + 2.0 * h));
            (0..n).map(|e| (-3.0 * y[e] + 4.0 * a[e] - b[e]) / (2.0 * h)).collect()
        } else {
            let (xp, xm) = (x + h, x - h);
            let (a, b) = (at(xp), at(xm));
            (0..n).map(|e| (a[e] - b[e]) / (xp - xm)).collect()
        };
        host.set(kvr, x);
        for e in 0..n {
            let (got, difference) = (got[e], differences[e]);
            let error = (got - difference).abs();
            let noise = 1e-13 * (1.0 + y[e].abs()) / h;
            let allowed = 1e-6 * got.abs().max(difference.abs()) + noise;
            // The relative difference where the derivative stands above the differences' rounding.
            let scale = got.abs().max(difference.abs());
            if scale > noise {
                worst = worst.max(error / scale);
            }
            if error.is_nan() || error > allowed {
                let element = if n > 1 { format!("[{e}]") } else { String::new() };
                failures.push(format!(
                    "d {}{element}/d {} at {} = {x}: {got}, finite differences {difference} (allowed {allowed:e})",
                    u.name, k.name, k.name
                ));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} ({version}): {} of {} declared pairs wrong:\n{}",
        lib.name,
        failures.len(),
        pairs.len(),
        failures.join("\n")
    );
    (pairs.len(), worst)
}

const PENDULUM: Point = Point {
    reals: &[
        ("alpha1_0", 0.3),
        ("omega1_0", -0.4),
        ("alpha2_0", 0.2),
        ("omega2_0", 0.5),
        ("M1", 0.7),
        ("M2", -0.3),
        ("J1", 0.01),
    ],
    integers: &[],
    booleans: &[],
};
/// Coupled: the torque on the joint follows the current.
const DC_MOTOR: Point = Point {
    reals: &[
        ("U", 2.0),
        ("omega", 1.3),
        ("i", 0.7),
        ("omega_r", 5.0),
        ("gear_ratio", 3.0),
    ],
    integers: &[],
    booleans: &[("coupled", true)],
};
/// LQR + PID, inside the limits.
const CONTROLLER: Point = Point {
    reals: &[
        ("alpha1", 0.02),
        ("omega1", -0.05),
        ("alpha2", 0.01),
        ("omega2", 0.03),
        ("alpha1_ref", 0.005),
        ("integral1", 0.01),
        ("integral2", -0.02),
    ],
    integers: &[("mode", 3)],
    booleans: &[],
};

fn check(lib: &Library, point: &Point, analytic: impl Fn(&dyn Host)) {
    for version in ["FMI 2.0", "FMI 3.0"] {
        let host: Box<dyn Host + '_> = if version == "FMI 2.0" {
            Box::new(Fmi2::initialization_mode(lib))
        } else {
            Box::new(Fmi3::initialization_mode(lib))
        };
        let (pairs, worst) = compare_with_differences(lib, host.as_ref(), point, version);
        assert!(pairs > 0, "{}: no declared pair", lib.name);
        eprintln!(
            "{} ({version}): {pairs} declared (InitialUnknown, known) pairs agree with finite differences; largest relative difference {worst:.1e}",
            lib.name
        );
        analytic(host.as_ref());
    }
}

/// A derivative (its name, its value) is the formula's value (its name, the value) to the
/// relative `tolerance`; the error it has is printed (in `fmu`'s name) either way.
fn assert_relatively_close(
    fmu: &str,
    (derivative, got): (&str, f64),
    (formula, expected): (&str, f64),
    tolerance: f64,
) {
    let error = (got - expected).abs() / expected.abs();
    eprintln!("{fmu}: {derivative} = {got}, {formula} = {expected}: relative error {error:.1e}");
    assert!(error <= tolerance, "{derivative} = {got}, {formula} = {expected}");
}

#[test]
fn the_pendulums_initial_unknowns_have_the_derivatives_of_their_initialization() {
    let lib = Library::load("Pendulum", "pendulum_fmu");
    let (alpha1, alpha1_0, m1) = (lib.vr("alpha1"), lib.vr("alpha1_0"), lib.vr("m1"));
    let (x1, l1) = (lib.vr("x1"), lib.vr("l1"));
    check(&lib, &PENDULUM, |host| {
        // The initial state is its parameter: d alpha1 / d alpha1_0 = 1.
        assert_eq!(host.derivative(alpha1, alpha1_0), Ok(1.0));
        // A known of Initialization Mode that alpha1 does not depend on (initial_depends says so).
        assert_eq!(host.derivative(alpha1, m1), Ok(0.0));
        // x1 = l1 sin(alpha1): d x1 / d alpha1_0 = l1 cos(alpha1_0).
        let expected = host.get(l1) * host.get(alpha1_0).cos();
        let got = host.derivative(x1, alpha1_0).unwrap();
        assert_relatively_close(
            "Pendulum",
            ("d x1/d alpha1_0", got),
            ("l1 cos(alpha1_0)", expected),
            1e-12,
        );
    });
}

#[test]
fn the_dc_motors_initial_unknowns_have_the_derivatives_of_their_initialization() {
    let lib = Library::load("DCMotor", "dc_motor_fmu");
    let (tau, i, km, n) = (lib.vr("tau"), lib.vr("i"), lib.vr("km"), lib.vr("gear_ratio"));
    check(&lib, &DC_MOTOR, |host| {
        // tau = n (km i - B omega_m): d tau / d i = n km, exactly (the equations on dual numbers).
        assert_eq!(host.derivative(tau, i), Ok(host.get(n) * host.get(km)));
        // ... and d tau / d km = n i (a parameter: differences of the initialization).
        let (got, expected) = (host.derivative(tau, km).unwrap(), host.get(n) * host.get(i));
        // tau (-106 N.m here) is large beside its change: the differences lose digits to it.
        assert_relatively_close("DCMotor", ("d tau/d km", got), ("n i", expected), 1e-9);
    });
}

#[test]
fn the_controllers_initial_unknowns_have_the_derivatives_of_their_initialization() {
    let lib = Library::load("Controller", "controller_fmu");
    check(&lib, &CONTROLLER, |_| {});
}

#[test]
fn a_known_outside_initialization_modes_knowns_is_refused_with_a_message() {
    let lib = Library::load("Pendulum", "pendulum_fmu");
    let (alpha1, energy) = (lib.vr("alpha1"), lib.vr("energy"));
    let host = Fmi2::initialization_mode(&lib);
    let refused = host.derivative(alpha1, energy).unwrap_err();
    assert!(
        refused.contains("'energy'") && refused.contains("is not a known"),
        "the refusal says which known and why: {refused}"
    );
    let host = Fmi3::initialization_mode(&lib);
    let refused = host.derivative(alpha1, energy).unwrap_err();
    assert!(
        refused.contains("'energy'") && refused.contains("is not a known"),
        "{refused}"
    );
}

type GetState2 = unsafe extern "C" fn(fmi2Component, *mut fmi2FMUstate) -> fmi2Status;
type StateSize2 = unsafe extern "C" fn(fmi2Component, fmi2FMUstate, *mut usize) -> fmi2Status;
type Serialize2 = unsafe extern "C" fn(fmi2Component, fmi2FMUstate, *mut fmi2Byte, usize) -> fmi2Status;

/// The instance's FMU state, serialized (fmi2GetFMUstate, fmi2SerializeFMUstate, fmi2FreeFMUstate).
fn serialized(lib: &Library, host: &Fmi2) -> Vec<u8> {
    let mut state: fmi2FMUstate = std::ptr::null_mut();
    let mut size = 0usize;
    // SAFETY: the functions of fmi2Functions.h with their signatures; a live instance, a state it
    // made, a buffer of the size it announced.
    unsafe {
        assert_eq!(lib.get::<GetState2>("fmi2GetFMUstate")(host.c, &mut state), fmi2OK);
        assert_eq!(
            lib.get::<StateSize2>("fmi2SerializedFMUstateSize")(host.c, state, &mut size),
            fmi2OK
        );
        let mut bytes = vec![0u8; size];
        assert_eq!(
            lib.get::<Serialize2>("fmi2SerializeFMUstate")(host.c, state, bytes.as_mut_ptr().cast(), size),
            fmi2OK
        );
        assert_eq!(lib.get::<GetState2>("fmi2FreeFMUstate")(host.c, &mut state), fmi2OK);
        bytes
    }
}

#[test]
fn a_derivative_refused_in_initialization_mode_leaves_the_fmu_state_as_it_was() {
    // The conformance suite's random model-exchange sequence of seed 6646168119972039503: the
    // inductance L set to a subnormal, then fmi2GetDirectionalDerivative in Initialization Mode:
    // d der(i) / dU = 1 / L overflows, refused with fmi2Error. The initialization the call
    // brought up to date for it must be taken back with the refusal (FMI 2.0.5 2.1.3: fmi2Error,
    // nothing changed), which it was not.
    let lib = Library::load("DCMotor", "dc_motor_fmu");
    let host = Fmi2::initialization_mode(&lib);
    host.set(lib.vr("L"), 6.73587195522396e-310);
    let before = serialized(&lib, &host);
    let refused = host.derivative(lib.vr("der(i)"), lib.vr("U")).unwrap_err();
    assert!(refused.contains("in Initialization Mode is inf"), "{refused}");
    assert!(serialized(&lib, &host) == before, "fmi2Error changed the FMU state");
    // With a finite L the same call answers, and the initialization stays brought up to date.
    host.set(lib.vr("L"), 1e-3);
    let d = host.derivative(lib.vr("der(i)"), lib.vr("U")).unwrap();
    assert!((d - 1e3).abs() < 1e-6, "d der(i)/dU = 1/L: {d}");
}
