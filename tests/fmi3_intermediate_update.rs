//! Issue 25: FMI 3.0 co-simulation's intermediate update (FMI 3.0, 4.2.2). The runtime's
//! integrator calls the importer's callback at the end of each accepted internal step (time
//! only: intermediateVariableSetRequested = intermediateVariableGetAllowed = false, and
//! intermediateStepFinished = true); with earlyReturnAllowed the importer may ask fmi3DoStep to
//! return early, at the time it names or at the step end it was told. A model exported here
//! with `export_fmi3!`: x' = -x, x(0) = 1, so x(t) = e^-t.

use rustfmu::__private::abi3::*;
use rustfmu::testing::{Log, fmi3};
use std::ffi::c_void;
use std::ptr::null_mut;
use std::sync::Mutex;

mod model {
    use rustfmu::prelude::*;

    /// A first-order decay.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    #[fmu(fmi3_only)]
    pub struct Decay {
        /// the state
        #[variable(vr = 1, output, continuous, start = 1.0, initial = exact, depends = [])]
        pub x: f64,
        /// its derivative
        #[variable(vr = 2, local, continuous, derivative_of = x, depends = [x])]
        pub der_x: f64,
    }

    impl Model for Decay {
        fn derivatives<D: Real>(&self, _t: D, v: &mut DecayContinuous<D>) {
            v.der_x = -v.x;
        }
    }

    impl CoSimulation for Decay {
        fn tolerances(&self, _ctx: &Context) -> rustfmu::solver::Tolerances {
            rustfmu::solver::Tolerances {
                rtol: 1e-10,
                atol: 1e-12,
            }
        }
    }

    rustfmu::export_fmi3!(Decay);
}
use model::__rustfmu_fmi3_exports::*;

/// One call of the callback: (intermediateUpdateTime, setRequested, getAllowed, stepFinished,
/// canReturnEarly).
type Call = (f64, bool, bool, bool, bool);

/// What the importer of these tests keeps: the messages, the callback's calls, and what it
/// answers.
#[derive(Default)]
struct Host {
    log: Log,
    calls: Mutex<Vec<Call>>,
    /// Ask for an early return at this time once the callback is called at or after `after`.
    request: Mutex<Option<(f64, f64)>>,
    /// The instance, to call into from the callback (refused: another call is running).
    instance: Mutex<Option<usize>>,
    /// The status of that call.
    nested: Mutex<Option<fmi3Status>>,
}

impl fmi3::Host for Host {
    fn log(&self) -> &Log {
        &self.log
    }
}

#[allow(clippy::too_many_arguments)]
unsafe extern "C" fn intermediate(
    env: *mut c_void,
    time: f64,
    set_requested: bool,
    get_allowed: bool,
    finished: bool,
    can_return_early: bool,
    early_return_requested: *mut bool,
    early_return_time: *mut f64,
) {
    // SAFETY: env is the leaked &Host given at instantiation (`instance`); the two outputs are
    // the runtime's locals.
    let host = unsafe { &*(env as *const Host) };
    host.calls
        .lock()
        .unwrap()
        .push((time, set_requested, get_allowed, finished, can_return_early));
    if let Some(c) = *host.instance.lock().unwrap() {
        let mut x = 0.0;
        // SAFETY: the live instance; one value. (Refused: fmi3DoStep is running.)
        let status = unsafe { fmi3GetFloat64(c as fmi3Instance, &1, 1, &mut x, 1) };
        *host.nested.lock().unwrap() = Some(status);
    }
    if let Some((after, at)) = *host.request.lock().unwrap()
        && time >= after
    {
        // SAFETY: the runtime's locals.
        unsafe {
            *early_return_requested = true;
            *early_return_time = at;
        }
    }
}

fn instance(host: &'static Host, early_return_allowed: bool, required: &[u32]) -> fmi3Instance {
    let how = fmi3::Instantiation {
        early_return_allowed,
        required_intermediate_variables: required,
        ..fmi3::Instantiation::new("decay")
    };
    how.co_simulation(fmi3InstantiateCoSimulation, TOKEN, host, Some(intermediate))
}

fn started(host: &'static Host, early_return_allowed: bool) -> fmi3Instance {
    let c = instance(host, early_return_allowed, &[]);
    assert!(!c.is_null(), "{:?}", host.log.messages());
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0), fmi3OK);
        assert_eq!(fmi3ExitInitializationMode(c), fmi3OK);
    }
    c
}

/// fmi3DoStep's status and (earlyReturn, lastSuccessfulTime).
fn step(c: fmi3Instance, t: f64, h: f64) -> (fmi3Status, bool, f64) {
    let (mut event, mut terminate, mut early, mut last) = (false, false, false, f64::NAN);
    // SAFETY: a live instance; four writable outputs.
    let status = unsafe { fmi3DoStep(c, t, h, false, &mut event, &mut terminate, &mut early, &mut last) };
    assert!(!event && !terminate);
    (status, early, last)
}

fn x(c: fmi3Instance) -> f64 {
    let mut x = f64::NAN;
    // SAFETY: a live instance; one value.
    assert_eq!(unsafe { fmi3GetFloat64(c, &1, 1, &mut x, 1) }, fmi3OK);
    x
}

fn leak() -> &'static Host {
    Box::leak(Box::default())
}

#[test]
fn the_callback_is_told_every_accepted_internal_step_and_the_result_is_unchanged() {
    let host = leak();
    let c = started(host, false);
    assert_eq!(step(c, 0.0, 1.0), (fmi3OK, false, 1.0));
    let calls = host.calls.lock().unwrap().clone();
    assert!(calls.len() > 3, "{calls:?}");
    assert!(calls.windows(2).all(|w| w[0].0 < w[1].0), "increasing times: {calls:?}");
    assert!(calls.iter().all(|c| c.0 > 0.0 && c.0 <= 1.0));
    assert_eq!(calls.last().unwrap().0, 1.0, "the last one at the step's end");
    // Time only, accepted steps, no early return without earlyReturnAllowed.
    assert!(
        calls
            .iter()
            .all(|c| (c.1, c.2, c.3, c.4) == (false, false, true, false))
    );
    assert!((x(c) - (-1.0f64).exp()).abs() < 1e-9);

    // The same step without a callback: the same number to the bit.
    let plain = leak();
    let d = fmi3::Instantiation::new("plain").co_simulation(fmi3InstantiateCoSimulation, TOKEN, plain, None);
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(fmi3EnterInitializationMode(d, false, 0.0, 0.0, false, 0.0), fmi3OK);
        assert_eq!(fmi3ExitInitializationMode(d), fmi3OK);
    }
    assert_eq!(step(d, 0.0, 1.0), (fmi3OK, false, 1.0));
    assert_eq!(x(c).to_bits(), x(d).to_bits());
    // SAFETY: live instances, freed once.
    unsafe {
        fmi3FreeInstance(c);
        fmi3FreeInstance(d);
    }
}

#[test]
fn an_early_return_ends_the_step_at_the_time_asked_for_with_the_state_there() {
    let host = leak();
    let c = started(host, true);
    // Once told a time past 0.1, ask for 0.37: the step goes on to 0.37 exactly and returns.
    *host.request.lock().unwrap() = Some((0.1, 0.37));
    let (status, early, last) = step(c, 0.0, 1.0);
    assert_eq!((status, early, last), (fmi3OK, true, 0.37));
    assert!(
        host.calls.lock().unwrap().iter().all(|c| c.4),
        "canReturnEarly with earlyReturnAllowed"
    );
    assert!((x(c) - (-0.37f64).exp()).abs() < 1e-9, "{}", x(c));
    assert!(host.log.messages().is_empty(), "{:?}", host.log.messages());

    // A time already passed: the step returns at the internal step's end it was told.
    host.calls.lock().unwrap().clear();
    *host.request.lock().unwrap() = Some((0.5, 0.0));
    let (status, early, last) = step(c, 0.37, 0.63);
    let told = host.calls.lock().unwrap().last().unwrap().0;
    assert!((0.5..1.0).contains(&told), "{told}");
    assert_eq!((status, early, last), (fmi3OK, true, told));
    assert!((x(c) - (-told).exp()).abs() < 1e-9);

    // The next step starts there; a request at or after the step's end is no early return.
    *host.request.lock().unwrap() = Some((0.0, 5.0));
    assert_eq!(step(c, told, 1.0 - told), (fmi3OK, false, 1.0));
    assert!((x(c) - (-1.0f64).exp()).abs() < 1e-9);
    // SAFETY: a live instance, freed once.
    unsafe { fmi3FreeInstance(c) };
}

#[test]
fn without_early_return_allowed_a_request_is_not_followed() {
    let host = leak();
    let c = started(host, false);
    *host.request.lock().unwrap() = Some((0.0, 0.2));
    assert_eq!(step(c, 0.0, 1.0), (fmi3OK, false, 1.0));
    // SAFETY: a live instance, freed once.
    unsafe { fmi3FreeInstance(c) };
}

#[test]
fn a_call_into_the_instance_from_the_callback_is_refused_and_the_step_goes_on() {
    let host = leak();
    let c = started(host, false);
    *host.instance.lock().unwrap() = Some(c as usize);
    assert_eq!(step(c, 0.0, 0.5), (fmi3OK, false, 0.5));
    assert_eq!(*host.nested.lock().unwrap(), Some(fmi3Error));
    assert!(
        host.log
            .messages()
            .iter()
            .any(|m| m.contains("fmi3GetFloat64: called while a call into this instance is still running")),
        "{:?}",
        host.log.messages()
    );
    *host.instance.lock().unwrap() = None;
    assert!((x(c) - (-0.5f64).exp()).abs() < 1e-9);
    // SAFETY: a live instance, freed once.
    unsafe { fmi3FreeInstance(c) };
}

#[test]
fn required_intermediate_variables_not_declared_are_named_in_a_warning_and_the_instance_is_made() {
    // FMI 3.0 (2.3.1) has the importer list only intermediateUpdate variables; fmusim's
    // --intermediate-update lists every output, and the Reference-FMUs accept that (issue 49).
    let host = leak();
    let c = instance(host, true, &[1, 77]);
    assert!(!c.is_null(), "{:?}", host.log.messages());
    {
        let log = host.log.messages();
        assert!(
            log.iter().any(|m| m.contains("2 requiredIntermediateVariables given")
                && m.contains("'x' (vr 1)")
                && m.contains("vr 77 (no such variable)")
                && m.contains("none of them is updated")),
            "{log:?}"
        );
    }
    // The instance works as one instantiated without the list.
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0), fmi3OK);
        assert_eq!(fmi3ExitInitializationMode(c), fmi3OK);
    }
    let (mut event, mut terminate, mut early, mut last) = (false, false, false, 0.0);
    // SAFETY: a live instance, four writable outputs.
    let status = unsafe { fmi3DoStep(c, 0.0, 0.5, false, &mut event, &mut terminate, &mut early, &mut last) };
    assert_eq!((status, early, last), (fmi3OK, false, 0.5));
    assert!((x(c) - (-0.5f64).exp()).abs() < 1e-9);
    // SAFETY: a live instance, freed once.
    unsafe { fmi3FreeInstance(c) };
    let _ = null_mut::<c_void>();
}
