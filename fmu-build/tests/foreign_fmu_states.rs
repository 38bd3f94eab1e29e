//! Two packaged FMUs loaded into one process, as a master loads them: an FMU state made by one
//! is refused by the other (fmi2Error with a message), and the refusing instance is unchanged
//! and still works. Needs `target/fmu/{Pendulum,Controller,DCMotor}.fmu`
//! (`cargo run --release -p fmu-build -- build --workspace`).

use rustfmu::__private::abi::*;
use std::ffi::{CStr, CString, c_char, c_void};
use std::io::Read;
use std::path::PathBuf;
use std::sync::Mutex;

type Instantiate = unsafe extern "C" fn(
    fmi2String,
    fmi2Type,
    fmi2String,
    fmi2String,
    *const fmi2CallbackFunctions,
    fmi2Boolean,
    fmi2Boolean,
) -> fmi2Component;
type Unary = unsafe extern "C" fn(fmi2Component) -> fmi2Status;
type Setup = unsafe extern "C" fn(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real) -> fmi2Status;
type DoStep = unsafe extern "C" fn(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean) -> fmi2Status;
type GetState = unsafe extern "C" fn(fmi2Component, *mut fmi2FMUstate) -> fmi2Status;
type SetState = unsafe extern "C" fn(fmi2Component, fmi2FMUstate) -> fmi2Status;
type StateSize = unsafe extern "C" fn(fmi2Component, fmi2FMUstate, *mut usize) -> fmi2Status;
type Serialize = unsafe extern "C" fn(fmi2Component, fmi2FMUstate, *mut fmi2Byte, usize) -> fmi2Status;

/// One FMU's binary, loaded, and the functions this test calls.
struct Fmu {
    name: &'static str,
    guid: CString,
    instantiate: Instantiate,
    free_instance: unsafe extern "C" fn(fmi2Component),
    setup: Setup,
    enter_init: Unary,
    exit_init: Unary,
    do_step: DoStep,
    get_state: GetState,
    set_state: SetState,
    free_state: GetState,
    state_size: StateSize,
    serialize: Serialize,
    _lib: libloading::Library,
}

fn fmu_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target"))
        .join("fmu")
}

impl Fmu {
    /// Unpacks `target/fmu/<name>.fmu`'s linux64 binary and loads it.
    fn load(name: &'static str) -> Fmu {
        let path = fmu_dir().join(format!("{name}.fmu"));
        let file = std::fs::File::open(&path).unwrap_or_else(|e| {
            panic!(
                "{}: {e}: run `cargo run --release -p fmu-build -- build --workspace` first",
                path.display()
            )
        });
        let mut zip = zip::ZipArchive::new(file).expect("an FMU is a zip archive");
        let mut read = |entry: &str| {
            let mut bytes = Vec::new();
            zip.by_name(entry)
                .unwrap_or_else(|e| panic!("{name}.fmu: {entry}: {e}"))
                .read_to_end(&mut bytes)
                .unwrap();
            bytes
        };
        let description = String::from_utf8(read("modelDescription.xml")).unwrap();
        let guid = description
            .split("guid=\"")
            .nth(1)
            .and_then(|rest| rest.split('"').next())
            .expect("modelDescription.xml has a guid");
        let so = std::env::temp_dir().join(format!("rustfmu-foreign-states-{}-{name}.so", std::process::id()));
        std::fs::write(&so, read(&format!("binaries/linux64/{name}.so"))).unwrap();
        // SAFETY: an FMU's binary; loading runs no initializers beyond Rust's own.
        let lib = unsafe { libloading::Library::new(&so) }.unwrap_or_else(|e| panic!("{name}: {e}"));
        let _ = std::fs::remove_file(&so);
        // SAFETY: the FMI 2.0 functions have these signatures (tests/abi_matches_fmi_sys.rs).
        unsafe {
            macro_rules! f {
                ($sym:literal) => {
                    *lib.get($sym).unwrap_or_else(|e| panic!("{name}: {e}"))
                };
            }
            Fmu {
                name,
                guid: CString::new(guid).unwrap(),
                instantiate: f!(b"fmi2Instantiate"),
                free_instance: f!(b"fmi2FreeInstance"),
                setup: f!(b"fmi2SetupExperiment"),
                enter_init: f!(b"fmi2EnterInitializationMode"),
                exit_init: f!(b"fmi2ExitInitializationMode"),
                do_step: f!(b"fmi2DoStep"),
                get_state: f!(b"fmi2GetFMUstate"),
                set_state: f!(b"fmi2SetFMUstate"),
                free_state: f!(b"fmi2FreeFMUstate"),
                state_size: f!(b"fmi2SerializedFMUstateSize"),
                serialize: f!(b"fmi2SerializeFMUstate"),
                _lib: lib,
            }
        }
    }
}

#[derive(Default)]
struct Log(Mutex<Vec<(fmi2Status, String)>>);

unsafe extern "C" fn collect(
    env: fmi2ComponentEnvironment,
    _name: fmi2String,
    status: fmi2Status,
    _category: fmi2String,
    _message: fmi2String,
    text: *const c_char,
) {
    // SAFETY: env is the leaked Log of the instance; the FMUs log "%s" with one argument.
    let (log, text) = unsafe { (&*(env as *const Log), CStr::from_ptr(text)) };
    log.0
        .lock()
        .unwrap()
        .push((status, text.to_string_lossy().into_owned()));
}

/// An initialized instance of `fmu` after 10 steps of 1 ms, and its log.
fn running(fmu: &Fmu) -> (fmi2Component, &'static Log) {
    let log: &'static Log = Box::leak(Box::default());
    let callbacks: &'static fmi2CallbackFunctions = Box::leak(Box::new(fmi2CallbackFunctions {
        // SAFETY: on this ABI a callee with the fixed arguments and one more reads "%s"'s argument.
        logger: Some(unsafe {
            std::mem::transmute::<
                unsafe extern "C" fn(
                    fmi2ComponentEnvironment,
                    fmi2String,
                    fmi2Status,
                    fmi2String,
                    fmi2String,
                    *const c_char,
                ),
                unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...),
            >(collect)
        }),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: log as *const Log as *mut c_void,
    }));
    // SAFETY: valid strings and callbacks that outlive the instance (leaked).
    unsafe {
        let c = (fmu.instantiate)(
            c"foreign".as_ptr(),
            fmi2CoSimulation,
            fmu.guid.as_ptr(),
            std::ptr::null(),
            callbacks,
            fmi2False,
            fmi2False,
        );
        assert!(
            !c.is_null(),
            "{}: fmi2Instantiate: {:?}",
            fmu.name,
            log.0.lock().unwrap()
        );
        assert_eq!((fmu.setup)(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
        assert_eq!((fmu.enter_init)(c), fmi2OK);
        assert_eq!((fmu.exit_init)(c), fmi2OK);
        for k in 0..10 {
            assert_eq!((fmu.do_step)(c, k as f64 * 1e-3, 1e-3, fmi2True), fmi2OK);
        }
        (c, log)
    }
}

/// The serialized form of c's current state.
fn serialized(fmu: &Fmu, c: fmi2Component) -> Vec<u8> {
    // SAFETY: c is a live instance of fmu; the buffers are as large as passed.
    unsafe {
        let mut s: fmi2FMUstate = std::ptr::null_mut();
        assert_eq!((fmu.get_state)(c, &mut s), fmi2OK);
        let mut n = 0;
        assert_eq!((fmu.state_size)(c, s, &mut n), fmi2OK);
        let mut bytes = vec![0u8; n];
        assert_eq!((fmu.serialize)(c, s, bytes.as_mut_ptr() as *mut fmi2Byte, n), fmi2OK);
        assert_eq!((fmu.free_state)(c, &mut s), fmi2OK);
        bytes
    }
}

/// `from`'s state handed to every state function of `to`: refused, logged, nothing changed.
fn refused_by_the_other(from: &Fmu, to: &Fmu) {
    let (a, _) = running(from);
    let (b, log) = running(to);
    let what = format!("{}'s state handed to {}", from.name, to.name);
    // SAFETY: a and b are live instances of their FMUs; the foreign state is passed only as an
    // importer would pass it, and `to` must not read through it.
    unsafe {
        let mut foreign: fmi2FMUstate = std::ptr::null_mut();
        assert_eq!((from.get_state)(a, &mut foreign), fmi2OK);
        let before = serialized(to, b);
        assert_eq!((to.set_state)(b, foreign), fmi2Error, "fmi2SetFMUstate: {what}");
        let mut n = 0;
        assert_eq!(
            (to.state_size)(b, foreign, &mut n),
            fmi2Error,
            "fmi2SerializedFMUstateSize: {what}"
        );
        let mut freed = foreign;
        assert_eq!((to.free_state)(b, &mut freed), fmi2Error, "fmi2FreeFMUstate: {what}");
        assert_eq!(
            freed, foreign,
            "{what}: the refused free changed the importer's pointer"
        );
        let mut into = foreign;
        assert_eq!((to.get_state)(b, &mut into), fmi2Error, "fmi2GetFMUstate into {what}");
        let log = std::mem::take(&mut *log.0.lock().unwrap());
        let refusals = log
            .iter()
            .filter(|(s, t)| *s == fmi2Error && t.contains("not a live state of this FMU"))
            .count();
        assert_eq!(refusals, 4, "{what}: every refusal says why: {log:?}");
        // Unchanged, and it still works.
        assert_eq!(serialized(to, b), before, "{what}: the refusing instance changed");
        for k in 10..20 {
            assert_eq!(
                (to.do_step)(b, k as f64 * 1e-3, 1e-3, fmi2True),
                fmi2OK,
                "{what}: step {k}"
            );
        }
        // The state is still its maker's, intact.
        assert_eq!((from.set_state)(a, foreign), fmi2OK);
        assert_eq!((from.free_state)(a, &mut foreign), fmi2OK);
        (from.free_instance)(a);
        (to.free_instance)(b);
    }
}

#[test]
fn a_state_of_another_fmu_in_the_same_process_is_refused() {
    let (pendulum, controller, motor) = (Fmu::load("Pendulum"), Fmu::load("Controller"), Fmu::load("DCMotor"));
    // The reproductions crashed 8 of 10 runs (Pendulum -> Controller) and 10 of 10
    // (DCMotor -> Pendulum): ten rounds of each, and the reverse directions.
    for _ in 0..10 {
        refused_by_the_other(&pendulum, &controller);
        refused_by_the_other(&motor, &pendulum);
        refused_by_the_other(&controller, &motor);
        refused_by_the_other(&controller, &pendulum);
    }
}
