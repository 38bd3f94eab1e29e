//! What the runtime refuses, through the C API of a model exported into this test binary: calls
//! and arguments no importer should make, and results no model should return. Each refusal is
//! an error status with a logged message, and the instance stays as it was.

use rustfmu::__private::abi::*;
use std::ffi::{CStr, CString, c_char};
use std::sync::Mutex;

mod probe {
    use rustfmu::prelude::*;

    /// Integrates its input.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    pub struct Probe {
        /// Input u
        #[variable(vr = 0, input, start = 0.0)]
        pub u: f64,
        /// y = gain atan(acc): finite whatever acc is
        #[variable(vr = 1, output, depends = [])]
        pub y: f64,
        /// u squared, computed at initialization and after every step: overflows for |u| > 1.3e154
        #[variable(vr = 2, output, depends = [])]
        pub power: f64,
        /// Gain
        #[variable(vr = 3, parameter, tunable, start = 1.0, min > 0.0, max = 10.0)]
        pub gain: f64,
        /// A count with bounds
        #[variable(vr = 4, parameter, fixed, start = 2, min = 1, max = 5)]
        pub count: i32,
        /// Internal state: the integral of u, not a variable
        pub acc: f64,
    }

    impl Probe {
        fn outputs(&mut self) {
            self.y = self.gain * self.acc.atan();
            self.power = self.u * self.u;
        }
    }

    impl Model for Probe {
        fn initialize(&mut self, _ctx: &Context) -> Result<(), String> {
            self.outputs();
            Ok(())
        }

        fn check_internal_state(&self) -> Result<(), String> {
            if self.acc.is_finite() {
                Ok(())
            } else {
                Err(format!("the integral acc = {} is not finite", self.acc))
            }
        }
    }

    impl CoSimulation for Probe {
        fn do_step(&mut self, _t: f64, h: f64, ctx: &mut Context) -> Result<(), StepFailure> {
            ctx.log("logEvents", "stepping");
            self.acc += self.u * h;
            self.outputs();
            Ok(())
        }
    }

    rustfmu::export_fmi2!(Probe);
}
use probe::*;

use rustfmu::testing::Log;

type Collector =
    unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, *const c_char);

/// Callbacks with a logger of this file's own (one that calls back into the FMU); the
/// recording ones are `rustfmu::testing::callbacks`.
fn callbacks(logger: Collector, env: *mut std::ffi::c_void) -> &'static fmi2CallbackFunctions {
    Box::leak(Box::new(fmi2CallbackFunctions {
        // SAFETY: on this ABI a callee with the fixed arguments and one more reads "%s"'s argument.
        logger: Some(unsafe {
            std::mem::transmute::<
                Collector,
                unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...),
            >(logger)
        }),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: env,
    }))
}

/// An instance named `name` and its log; NULL when refused.
fn instantiate(name: &CStr) -> (fmi2Component, &'static Log) {
    let log = Log::leak();
    let c = rustfmu::testing::fmi2::Instantiation::new(fmi2CoSimulation, name).call(
        fmi2Instantiate,
        probe::__rustfmu_fmi2_exports::GUID,
        log,
    );
    (c, log)
}

fn assert_logged(log: &Log, status: fmi2Status, words: &[&str]) {
    let entries = log.take_texts();
    assert!(
        entries
            .iter()
            .any(|(s, text)| *s == status && words.iter().all(|w| text.contains(w))),
        "expected a message with status {status} saying {words:?}, got {entries:?}"
    );
}

#[test]
fn an_instance_name_of_only_white_space_is_refused() {
    for name in [c"   ", c"\t", c" \n\r "] {
        let (c, log) = instantiate(name);
        assert!(c.is_null(), "instance name {name:?} was accepted");
        assert_logged(log, fmi2Error, &["fmi2Instantiate", "instanceName"]);
    }
    let (c, _) = instantiate(c" a ");
    assert!(!c.is_null(), "a name with one non-white-space character is legal");
    // SAFETY: c came from fmi2Instantiate and is freed once.
    unsafe { fmi2FreeInstance(c) };
}

/// An initialized Probe with the given input.
fn initialized(u: f64) -> (fmi2Component, &'static Log) {
    let (c, log) = instantiate(c"probe");
    assert!(!c.is_null());
    // SAFETY: c is a live instance; arrays of one.
    unsafe {
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(fmi2SetReal(c, &0, 1, &u), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK, "{:?}", log.take_texts());
    }
    (c, log)
}

fn get_reals(c: fmi2Component, vrs: &[u32]) -> (fmi2Status, Vec<f64>) {
    let mut out = vec![f64::NAN; vrs.len()];
    // SAFETY: as many references as slots.
    let s = unsafe { fmi2GetReal(c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) };
    (s, out)
}

fn last_successful_time(c: fmi2Component) -> f64 {
    let mut t = f64::NAN;
    // SAFETY: a live instance, one slot.
    assert_eq!(unsafe { fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &mut t) }, fmi2OK);
    t
}

#[test]
fn a_step_whose_output_is_not_finite_is_discarded_and_the_model_keeps_its_last_good_state() {
    let (c, log) = initialized(1.0);
    // SAFETY: c is a live instance; arrays of one.
    unsafe {
        assert_eq!(fmi2DoStep(c, 0.0, 0.5, fmi2True), fmi2OK);
        let good = get_reals(c, &[1, 2]).1;
        // Finite, and accepted: but u² overflows.
        assert_eq!(fmi2SetReal(c, &0, 1, &1e200), fmi2OK);
        let s = fmi2DoStep(c, 0.5, 0.5, fmi2True);
        assert_eq!(s, fmi2Discard, "a step to power = inf must not return {s}");
        assert_logged(log, fmi2Discard, &["fmi2DoStep", "'power' (vr 2) = inf"]);
        let (s, after) = get_reals(c, &[1, 2]);
        assert_eq!(s, fmi2OK);
        assert_eq!(after, good, "y and power must be as they were at t = 0.5");
        assert_eq!(last_successful_time(c), 0.5);
        fmi2FreeInstance(c);
    }
}

#[test]
fn a_step_whose_internal_state_is_not_finite_is_discarded() {
    let (c, log) = initialized(1e150);
    // SAFETY: c is a live instance.
    unsafe {
        // acc = u h overflows while every variable stays finite (y = gain atan(acc)): only the
        // model's own check of its internal state sees it.
        let s = fmi2DoStep(c, 0.0, 1e160, fmi2True);
        assert_eq!(s, fmi2Discard, "a step to acc = inf must not return {s}");
        assert_logged(log, fmi2Discard, &["internal state", "acc = inf"]);
        assert_eq!(last_successful_time(c), 0.0);
        assert_eq!(get_reals(c, &[1]).1, [0.0], "y is back at its value at t = 0");
        fmi2FreeInstance(c);
    }
}

#[test]
fn an_initialization_that_computes_a_non_finite_value_is_an_error_naming_it() {
    let (c, log) = instantiate(c"probe");
    // SAFETY: c is a live instance; arrays of one.
    unsafe {
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(fmi2SetReal(c, &0, 1, &1e200), fmi2OK);
        let (s, _) = get_reals(c, &[2]);
        assert_eq!(s, fmi2Error, "fmi2GetReal of power = inf in initialization mode");
        assert_logged(log, fmi2Error, &["'power' (vr 2) = inf"]);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2Error);
        assert_logged(log, fmi2Error, &["fmi2ExitInitializationMode", "'power' (vr 2) = inf"]);
        // Nothing changed: still in initialization mode, and a good input initializes it.
        assert_eq!(fmi2SetReal(c, &0, 1, &3.0), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK, "{:?}", log.take_texts());
        assert_eq!(get_reals(c, &[2]).1, [9.0]);
        fmi2FreeInstance(c);
    }
}

/// The serialized form of c's current state.
fn serialized(c: fmi2Component) -> Vec<u8> {
    // SAFETY: c is a live instance; the buffers are as large as passed.
    unsafe {
        let mut s: fmi2FMUstate = std::ptr::null_mut();
        assert_eq!(fmi2GetFMUstate(c, &mut s), fmi2OK);
        let mut n = 0;
        assert_eq!(fmi2SerializedFMUstateSize(c, s, &mut n), fmi2OK);
        let mut bytes = vec![0u8; n];
        assert_eq!(
            fmi2SerializeFMUstate(c, s, bytes.as_mut_ptr() as *mut fmi2Byte, n),
            fmi2OK
        );
        assert_eq!(fmi2FreeFMUstate(c, &mut s), fmi2OK);
        bytes
    }
}

/// `bytes` decoded, changed by `doctor`, and encoded again with a correct header and checksum.
fn doctored(bytes: &[u8], doctor: impl FnOnce(&mut rustfmu::core::instance::Sim<Probe>)) -> Vec<u8> {
    use rustfmu::core::state;
    let guid = probe::__rustfmu_fmi2_exports::GUID;
    let mut sim =
        state::deserialize::<Probe>(&rustfmu::fmi2::TERMS, guid, bytes).expect("the runtime reads its own state");
    doctor(&mut sim);
    state::serialize(guid, &sim).unwrap()
}

#[test]
fn a_deserialized_state_is_checked_like_values_set_through_the_api() {
    let (c, log) = initialized(1.0);
    let good = serialized(c);
    type Doctor = fn(&mut rustfmu::core::instance::Sim<Probe>);
    let cases: [(&str, Doctor, &[&str]); 7] = [
        (
            "a NaN input",
            |s| s.model.u = f64::NAN,
            &["NaN for 'u' (vr 0) is not a finite number"],
        ),
        (
            "an infinite output",
            |s| s.model.power = f64::INFINITY,
            &["inf for 'power'"],
        ),
        (
            "gain = -1",
            |s| s.model.gain = -1.0,
            &["-1 for 'gain' (vr 3) is outside (0, 10]"],
        ),
        (
            "count = 9",
            |s| s.model.count = 9,
            &["9 for 'count' (vr 4) is outside [1, 5]"],
        ),
        (
            "an infinite internal state",
            |s| s.model.acc = f64::INFINITY,
            &["internal state", "acc = inf"],
        ),
        ("a NaN time", |s| s.time = f64::NAN, &["time = NaN"]),
        ("tolerance = -1", |s| s.tolerance = Some(-1.0), &["tolerance = -1"]),
    ];
    for (what, doctor, words) in cases {
        let bytes = doctored(&good, doctor);
        let mut s: fmi2FMUstate = std::ptr::null_mut();
        // SAFETY: bytes.len() readable bytes; s is an FMUstate slot.
        let status = unsafe { fmi2DeSerializeFMUstate(c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), &mut s) };
        assert_eq!(status, fmi2Error, "a state with {what} (correct checksum) was accepted");
        assert!(s.is_null(), "{what}: a refused state was handed out");
        let mut words = words.to_vec();
        words.push("fmi2DeSerializeFMUstate");
        assert_logged(log, fmi2Error, &words);
    }
    // The undoctored state still restores.
    let mut s: fmi2FMUstate = std::ptr::null_mut();
    // SAFETY: as above.
    unsafe {
        assert_eq!(
            fmi2DeSerializeFMUstate(c, good.as_ptr() as *const fmi2Byte, good.len(), &mut s),
            fmi2OK
        );
        assert_eq!(fmi2SetFMUstate(c, s), fmi2OK);
        assert_eq!(fmi2FreeFMUstate(c, &mut s), fmi2OK);
        fmi2FreeInstance(c);
    }
}

/// A second model in this binary, not exported (its symbols would clash with the Probe's):
/// instantiated through the runtime's generic functions, with a GUID of its own.
mod other {
    use rustfmu::prelude::*;

    /// Something else entirely.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    pub struct Other {
        /// A name
        #[variable(vr = 0, parameter, fixed, start = "other")]
        pub label: String,
        /// A count
        #[variable(vr = 1, output, depends = [])]
        pub n: i32,
    }

    impl Model for Other {}
    impl CoSimulation for Other {
        fn do_step(&mut self, _t: f64, _h: f64, _ctx: &mut Context) -> Result<(), StepFailure> {
            self.n += 1;
            Ok(())
        }
    }

    pub const GUID: &str = "{00000000-0000-5000-8000-000000000000}";
}

/// A co-simulation instance of a model of this binary that is not exported, made through the
/// runtime's generic functions (what an export of it would call), with a GUID of its own.
fn generic_instance<M: rustfmu::CoSimulation>(guid: &'static str, name: &CStr) -> (fmi2Component, &'static Log) {
    use rustfmu::__private::api;
    let log = Log::leak();
    let cb = rustfmu::testing::callbacks(log);
    let guid_c = CString::new(guid).unwrap();
    // SAFETY: valid strings and callbacks that outlive the instance.
    let c = unsafe {
        api::instantiate::<M>(
            guid,
            &[],
            name.as_ptr(),
            fmi2CoSimulation,
            guid_c.as_ptr(),
            std::ptr::null(),
            cb,
            fmi2False,
            fmi2False,
        )
    };
    assert!(!c.is_null(), "{:?}", log.take_texts());
    (c, log)
}

/// An FMU state made by the Other model, and its instance.
fn state_of_another_model() -> (fmi2Component, fmi2FMUstate) {
    let (c, _) = generic_instance::<other::Other>(other::GUID, c"other");
    let mut s: fmi2FMUstate = std::ptr::null_mut();
    // SAFETY: a live instance and a valid out pointer.
    let status = unsafe {
        let other = rustfmu::core::guard::component(c);
        rustfmu::__private::shared::get_fmu_state::<other::Other>(&rustfmu::fmi2::TERMS, other, &mut s)
    };
    assert_eq!(status, fmi2OK);
    (c, s)
}

/// Every state function refuses `s` on `c` with a logged error and leaves c as it was.
fn assert_every_state_function_refuses(c: fmi2Component, log: &Log, s: fmi2FMUstate, what: &str) {
    let before = serialized(c);
    // SAFETY: c is a live instance; s is passed only as the importer would pass it, and the
    // runtime must not dereference it.
    unsafe {
        assert_eq!(fmi2SetFMUstate(c, s), fmi2Error, "fmi2SetFMUstate accepted {what}");
        assert_logged(log, fmi2Error, &["fmi2SetFMUstate", "not a live state of this FMU"]);
        let mut n = 0;
        assert_eq!(fmi2SerializedFMUstateSize(c, s, &mut n), fmi2Error, "size of {what}");
        assert_logged(log, fmi2Error, &["fmi2SerializedFMUstateSize"]);
        let mut buf = [0u8; 64];
        let status = fmi2SerializeFMUstate(c, s, buf.as_mut_ptr() as *mut fmi2Byte, buf.len());
        assert_eq!(status, fmi2Error, "fmi2SerializeFMUstate of {what}");
        assert_logged(log, fmi2Error, &["fmi2SerializeFMUstate"]);
        let mut into = s;
        assert_eq!(fmi2GetFMUstate(c, &mut into), fmi2Error, "fmi2GetFMUstate into {what}");
        assert_logged(log, fmi2Error, &["fmi2GetFMUstate"]);
        let good = serialized(c);
        let status = fmi2DeSerializeFMUstate(c, good.as_ptr() as *const fmi2Byte, good.len(), &mut into);
        assert_eq!(status, fmi2Error, "fmi2DeSerializeFMUstate into {what}");
        assert_logged(log, fmi2Error, &["fmi2DeSerializeFMUstate"]);
        let mut freed = s;
        assert_eq!(fmi2FreeFMUstate(c, &mut freed), fmi2Error, "fmi2FreeFMUstate of {what}");
        assert_logged(log, fmi2Error, &["fmi2FreeFMUstate", "not a live state of this FMU"]);
        assert_eq!(
            (into, freed),
            (s, s),
            "{what}: a refused call changed the importer's pointer"
        );
    }
    assert_eq!(serialized(c), before, "{what}: a refused call changed the instance");
    // And it still works.
    let mut t = f64::NAN;
    // SAFETY: c is a live instance; t is a local.
    unsafe {
        assert_eq!(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &mut t), fmi2OK);
        assert_eq!(
            fmi2DoStep(c, t, 0.1, fmi2True),
            fmi2OK,
            "{what}: {:?}",
            log.take_texts()
        );
    }
}

#[test]
fn a_state_of_another_model_is_refused_by_every_state_function() {
    let (c, log) = initialized(1.0);
    let (other, mut s) = state_of_another_model();
    assert_every_state_function_refuses(c, log, s, "a state of another model and GUID");
    // SAFETY: s is the Other instance's live state, freed once by it.
    unsafe {
        assert_eq!(
            rustfmu::__private::shared::free_fmu_state::<other::Other>(
                &rustfmu::fmi2::TERMS,
                rustfmu::core::guard::component(other),
                &mut s
            ),
            fmi2OK
        );
        rustfmu::__private::shared::free_instance::<other::Other>(&rustfmu::fmi2::TERMS, other);
        fmi2FreeInstance(c);
    }
}

#[test]
fn garbage_and_made_up_pointers_are_refused_without_being_dereferenced() {
    let (c, log) = initialized(1.0);
    let garbage: &'static mut [u64; 64] = Box::leak(Box::new([0xdead_beef_dead_beef; 64]));
    let copy = *garbage;
    assert_every_state_function_refuses(c, log, garbage.as_mut_ptr() as fmi2FMUstate, "a pointer to garbage");
    assert_eq!(*garbage, copy, "the runtime wrote to memory it does not own");
    for made_up in [1usize, 0x1000, usize::MAX - 7] {
        assert_every_state_function_refuses(c, log, made_up as fmi2FMUstate, &format!("pointer {made_up:#x}"));
    }
    // SAFETY: from fmi2Instantiate, freed once.
    unsafe { fmi2FreeInstance(c) };
}

#[test]
fn a_freed_state_is_refused_and_cannot_be_freed_twice() {
    let (c, log) = initialized(1.0);
    let mut s: fmi2FMUstate = std::ptr::null_mut();
    // SAFETY: c is a live instance.
    unsafe {
        assert_eq!(fmi2GetFMUstate(c, &mut s), fmi2OK);
        let freed = s;
        assert_eq!(fmi2FreeFMUstate(c, &mut s), fmi2OK);
        assert!(s.is_null(), "fmi2FreeFMUstate sets the pointer to NULL");
        assert_every_state_function_refuses(c, log, freed, "a freed state");
        fmi2FreeInstance(c);
    }
}

#[test]
fn a_state_of_another_instance_of_the_same_fmu_is_accepted() {
    let (a, _) = initialized(1.0);
    let (b, log_b) = initialized(2.0);
    // SAFETY: live instances; s is a's state, freed once.
    unsafe {
        assert_eq!(fmi2DoStep(a, 0.0, 0.5, fmi2True), fmi2OK);
        let mut s: fmi2FMUstate = std::ptr::null_mut();
        assert_eq!(fmi2GetFMUstate(a, &mut s), fmi2OK);
        assert_eq!(fmi2SetFMUstate(b, s), fmi2OK, "{:?}", log_b.take_texts());
        assert_eq!(serialized(b), serialized(a));
        assert_eq!(
            fmi2FreeFMUstate(b, &mut s),
            fmi2OK,
            "any instance of the FMU may free it"
        );
        fmi2FreeInstance(a);
        fmi2FreeInstance(b);
    }
}

/// A call an importer's callback makes on an instance.
type Nested = fn(fmi2Component) -> fmi2Status;

/// A logger that, when armed, calls back into the instance that is logging.
#[derive(Default)]
struct Reentrant {
    log: Log,
    component: std::sync::atomic::AtomicPtr<std::ffi::c_void>,
    /// The nested call to make on the next message, once.
    armed: Mutex<Option<Nested>>,
    nested: Mutex<Vec<fmi2Status>>,
}

unsafe extern "C" fn reenter(
    env: fmi2ComponentEnvironment,
    name: fmi2String,
    status: fmi2Status,
    category: fmi2String,
    message: fmi2String,
    text: *const c_char,
) {
    let _ = (name, category, message);
    // SAFETY: env is the leaked Reentrant of the instance; the runtime logs "%s" with one string.
    let (r, text) = unsafe { (&*(env as *const Reentrant), CStr::from_ptr(text)) };
    r.log.push(rustfmu::testing::LogEntry {
        status,
        category: String::new(),
        text: text.to_string_lossy().into_owned(),
    });
    let call = r.armed.lock().unwrap().take();
    if let Some(call) = call {
        let c = r.component.load(std::sync::atomic::Ordering::SeqCst);
        let s = call(c);
        r.nested.lock().unwrap().push(s);
    }
}

#[test]
fn a_call_into_an_instance_from_inside_a_call_into_it_is_refused() {
    let r: &'static Reentrant = Box::leak(Box::default());
    let cb = callbacks(reenter, r as *const Reentrant as *mut _);
    // fmi2 calls on the live instance from inside a call into it: the nested ones are the point.
    let nested_calls: [(&str, Nested); 6] = [
        // SAFETY: the live instance the logger reenters; arrays of one, locals.
        ("fmi2DoStep", |c| unsafe { fmi2DoStep(c, 0.0, 1e-3, fmi2True) }),
        // SAFETY: the live instance the logger reenters; arrays of one, locals.
        ("fmi2SetReal", |c| unsafe { fmi2SetReal(c, &0, 1, &5.0) }),
        ("fmi2GetReal", |c| {
            let mut y = 0.0;
            // SAFETY: the live instance the logger reenters; arrays of one, locals.
            unsafe { fmi2GetReal(c, &1, 1, &mut y) }
        }),
        ("fmi2GetFMUstate", |c| {
            let mut s: fmi2FMUstate = std::ptr::null_mut();
            // SAFETY: the live instance the logger reenters; arrays of one, locals.
            unsafe { fmi2GetFMUstate(c, &mut s) }
        }),
        // SAFETY: the live instance the logger reenters; arrays of one, locals.
        ("fmi2Reset", |c| unsafe { fmi2Reset(c) }),
        // No status: the steps after it show that the instance was not freed.
        ("fmi2FreeInstance", |c| {
            // SAFETY: the live instance the logger reenters; refused from inside a call, so it
            // stays alive (the steps after it show it).
            unsafe { fmi2FreeInstance(c) };
            fmi2Error
        }),
    ];
    let how = rustfmu::testing::fmi2::Instantiation {
        logging_on: true,
        ..rustfmu::testing::fmi2::Instantiation::new(fmi2CoSimulation, c"probe")
    };
    let c = how.call_with(fmi2Instantiate, probe::__rustfmu_fmi2_exports::GUID, cb);
    assert!(!c.is_null());
    r.component.store(c, std::sync::atomic::Ordering::SeqCst);
    // SAFETY: a live instance; arrays of one.
    unsafe {
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(fmi2SetReal(c, &0, 1, &1.0), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK);
        r.log.take_texts();
        let mut t = 0.0;
        for (name, call) in nested_calls {
            // The Probe logs "stepping" inside every fmi2DoStep: the logger then makes the call.
            *r.armed.lock().unwrap() = Some(call);
            assert_eq!(fmi2DoStep(c, t, 1e-3, fmi2True), fmi2OK, "the outer step itself");
            t += 1e-3;
            assert_eq!(
                r.nested.lock().unwrap().pop(),
                Some(fmi2Error),
                "{name} from the logger, inside fmi2DoStep on the same instance"
            );
            assert_logged(
                &r.log,
                fmi2Error,
                &[name, "while a call into this instance is still running"],
            );
            assert_eq!(last_successful_time(c), t, "after the step with a nested {name}");
        }
        // One step of 1 ms per outer call, with u = 1 throughout: acc = 6 ms, not more.
        let acc = (0..6).fold(0.0f64, |acc, _| acc + 1.0 * 1e-3);
        let (_, y) = get_reals(c, &[1]);
        assert_eq!(y, [acc.atan()], "the nested calls changed the instance");
        fmi2FreeInstance(c);
    }
}

/// A model of an input, a parameter and an output only: no continuous state, and the default
/// co-simulation step (`impl CoSimulation for Gain {}`). Not exported (the Probe's symbols are);
/// run through the runtime's generic functions, as an export of it would.
mod stateless {
    use rustfmu::prelude::*;

    /// A static gain: y = k u
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    pub struct Gain {
        /// Input u
        #[variable(vr = 0, input, continuous, start = 0.0)]
        pub u: f64,
        /// Gain k
        #[variable(vr = 1, parameter, fixed, start = 2.0)]
        pub k: f64,
        /// Output y = k u
        #[variable(vr = 2, output, continuous, depends = [u])]
        pub y: f64,
    }

    impl Model for Gain {
        fn outputs<D: Real>(&self, _t: D, v: &mut GainContinuous<D>) {
            v.y = v.u * self.k;
        }
    }

    impl CoSimulation for Gain {}

    pub const GUID: &str = "{00000000-0000-5000-8000-00000000000b}";
}

/// Issue 23: with no state, the default step's integrator divided 0 by 0 and every fmi2DoStep
/// was discarded at t = 0 ("the state became NaN or infinite").
#[test]
fn a_model_without_continuous_states_steps_with_the_default_co_simulation() {
    use rustfmu::__private::api;
    use stateless::Gain;
    let (c, log) = generic_instance::<Gain>(stateless::GUID, c"gain");
    use rustfmu::__private::shared::{Transition, transition};
    // SAFETY: a live instance, arrays of the lengths passed.
    unsafe {
        let g = rustfmu::core::guard::component::<Gain>(c);
        let terms = &rustfmu::fmi2::TERMS;
        assert_eq!(
            api::setup_experiment::<Gain>(g, fmi2False, 0.0, 0.0, fmi2False, 0.0),
            fmi2OK
        );
        assert_eq!(
            transition::<Gain>(terms, Transition::EnterInitializationMode, g),
            fmi2OK
        );
        assert_eq!(transition::<Gain>(terms, Transition::ExitInitializationMode, g), fmi2OK);
        let mut t = 0.0;
        for k in 0..100 {
            let u = [k as f64 * 0.5];
            assert_eq!(
                api::set::<Gain, f64>(g, "fmi2SetReal", [0u32].as_ptr(), 1, u.as_ptr()),
                fmi2OK
            );
            let s = api::do_step::<Gain>(g, t, 0.01, fmi2True);
            assert_eq!(s, fmi2OK, "fmi2DoStep at t = {t}: {:?}", log.take_texts());
            t += 0.01;
            let mut y = [f64::NAN];
            assert_eq!(
                api::get::<Gain, f64>(g, "fmi2GetReal", [2u32].as_ptr(), 1, y.as_mut_ptr()),
                fmi2OK
            );
            assert_eq!(y, [2.0 * u[0]], "y after the step at t = {t}");
        }
        rustfmu::__private::shared::free_instance::<Gain>(&rustfmu::fmi2::TERMS, c);
    }
}
