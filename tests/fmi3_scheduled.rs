//! FMI 3.0 Scheduled Execution (FMI 3.0, chapter 5) through the C API: a model declared
//! `#[fmu(fmi3_only, scheduled_execution)]` whose input clocks' partitions the importer activates
//! with fmi3ActivateModelPartition in Clock Activation Mode; the clockUpdate callback (called
//! after the activation left the instance, so the importer calls back into it: fmi3GetClock,
//! fmi3GetIntervalDecimal, the getters), the state machine, the refusals, FMU states, and calls
//! from two threads (serialized, not refused).

use rustfmu::__private::abi3::*;
use rustfmu::core::machine::State;
use rustfmu::testing::{Log, fmi3};
use std::ffi::c_void;
use std::ptr::null_mut;
use std::sync::Mutex;
use std::sync::atomic::{AtomicPtr, Ordering};

mod model {
    use rustfmu::prelude::*;

    /// Three input clocks, each a model partition, and an output clock.
    #[derive(Model, Debug, Clone, serde::Serialize, serde::Deserialize)]
    #[fmu(fmi3_only, scheduled_execution)]
    pub struct Scheduled {
        /// Every second
        #[variable(vr = 1, input, clock(constant, interval = 1.0, priority = 0))]
        pub fast: Clock,
        /// When the importer says
        #[variable(vr = 2, input, clock(triggered, priority = 1))]
        pub trig: Clock,
        /// 0.5 s after the second tick of `fast`
        #[variable(vr = 3, input, clock(countdown, priority = 2))]
        pub later: Clock,
        /// Ticks at every third activation
        #[variable(vr = 4, output, clock(triggered, priority = 2))]
        pub out: Clock,
        /// Ticks of `fast`
        #[variable(vr = 10, output, discrete, clocks = [fast])]
        pub fast_ticks: i32,
        /// Added at each tick of `trig`
        #[variable(vr = 11, input, discrete, clocks = [trig], start = 0)]
        pub u: i32,
        /// The sum of `u` over the ticks of `trig`
        #[variable(vr = 12, output, discrete, clocks = [trig])]
        pub sum: i32,
        /// Ticks of `later`
        #[variable(vr = 13, output, discrete, clocks = [later])]
        pub later_ticks: i32,
        /// Activations so far
        #[variable(vr = 14, output, discrete, clocks = [out])]
        pub total: i32,
    }

    impl Model for Scheduled {
        fn update(&mut self, _event: &mut Event) -> Result<(), String> {
            if self.fast.is_active() {
                self.fast_ticks += 1;
                if self.fast_ticks == 2 {
                    self.later.set_interval(0.5);
                }
            }
            if self.trig.is_active() {
                self.sum += self.u;
            }
            if self.later.is_active() {
                self.later_ticks += 1;
            }
            self.total += 1;
            if self.total % 3 == 0 {
                self.out.tick();
            }
            Ok(())
        }
    }

    impl CoSimulation for Scheduled {}

    rustfmu::export_fmi3!(Scheduled);
}
use model::__rustfmu_fmi3_exports::*;

/// What one clockUpdate call read from inside: (state, out ticks, total, status of total's
/// get, later's interval and qualifier).
type Update = (Option<State>, bool, i32, fmi3Status, (f64, u32));

/// What the callbacks see: the messages, and what the clockUpdate callback read from inside it.
#[derive(Default)]
struct Probe {
    log: Log,
    instance: AtomicPtr<c_void>,
    /// Per clockUpdate call.
    updates: Mutex<Vec<Update>>,
}

impl fmi3::Host for Probe {
    fn log(&self) -> &Log {
        &self.log
    }
}

unsafe extern "C" fn clock_update(env: *mut c_void) {
    // SAFETY: env is the leaked &Probe given at instantiation.
    let p = unsafe { &*(env as *const Probe) };
    let c = p.instance.load(Ordering::Acquire);
    // SAFETY: no call is inside the instance while its clockUpdate callback runs.
    let state = unsafe { rustfmu::core::guard::state_of::<model::Scheduled>(c) };
    let out = get_clock(c, 4).1;
    let (status, total) = get_i32(c, 14);
    let (_, h, q) = interval(c, 3);
    p.updates.lock().unwrap().push((state, out, total, status, (h, q)));
}

fn last(p: &Probe) -> String {
    p.log.last()
}

fn scheduled_with(callback: fmi3ClockUpdateCallback) -> (fmi3Instance, &'static Probe) {
    let p: &'static Probe = Box::leak(Box::default());
    let how = fmi3::Instantiation {
        logging_on: true,
        ..fmi3::Instantiation::new("scheduled")
    };
    let c = how.scheduled_execution(fmi3InstantiateScheduledExecution, TOKEN, p, callback);
    assert!(!c.is_null(), "{}", last(p));
    p.instance.store(c, Ordering::Release);
    (c, p)
}

/// An instance for scheduled execution with a clockUpdate callback, in Clock Activation Mode at t = 0.
fn scheduled() -> (fmi3Instance, &'static Probe) {
    let (c, p) = scheduled_with(Some(clock_update));
    init(c);
    (c, p)
}

fn init(c: fmi3Instance) {
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(fmi3EnterInitializationMode(c, false, 0.0, 0.0, false, 0.0), fmi3OK);
        assert_eq!(fmi3ExitInitializationMode(c), fmi3OK);
    }
    assert_eq!(state(c), Some(State::ClockActivationMode));
}

fn state(c: fmi3Instance) -> Option<State> {
    // SAFETY: a live instance, no call inside it.
    unsafe { rustfmu::core::guard::state_of::<model::Scheduled>(c) }
}

fn activate(c: fmi3Instance, vr: u32, t: f64) -> fmi3Status {
    // SAFETY: a live instance.
    unsafe { fmi3ActivateModelPartition(c, vr, t) }
}

fn get_i32(c: fmi3Instance, vr: u32) -> (fmi3Status, i32) {
    let mut x = 0;
    // SAFETY: a live instance; locals.
    (unsafe { fmi3GetInt32(c, &vr, 1, &mut x, 1) }, x)
}

fn set_i32(c: fmi3Instance, vr: u32, x: i32) -> fmi3Status {
    // SAFETY: a live instance; locals.
    unsafe { fmi3SetInt32(c, &vr, 1, &x, 1) }
}

fn get_clock(c: fmi3Instance, vr: u32) -> (fmi3Status, bool) {
    let mut x = false;
    // SAFETY: a live instance; locals.
    (unsafe { fmi3GetClock(c, &vr, 1, &mut x) }, x)
}

fn interval(c: fmi3Instance, vr: u32) -> (fmi3Status, f64, u32) {
    let (mut h, mut q) = (0.0, 99);
    // SAFETY: a live instance; locals.
    (unsafe { fmi3GetIntervalDecimal(c, &vr, 1, &mut h, &mut q) }, h, q)
}

fn free(c: fmi3Instance) {
    // SAFETY: a live instance, freed once.
    unsafe { fmi3FreeInstance(c) };
}

const NOT_YET_KNOWN: u32 = 0;
const UNCHANGED: u32 = 1;
const CHANGED: u32 = 2;

/// A refusal on a fresh instance (in Clock Activation Mode unless `fresh`): fmi3Error, the message says `why`.
fn refused(fresh: bool, why: &str, call: impl FnOnce(fmi3Instance) -> fmi3Status) {
    let (c, p) = scheduled_with(Some(clock_update));
    if !fresh {
        init(c);
    }
    assert_eq!(call(c), fmi3Error, "expected a refusal saying '{why}'");
    assert!(last(p).contains(why), "'{}' does not say '{why}'", last(p));
    free(c);
}

#[test]
fn partitions_run_when_activated_and_the_clock_update_callback_reads_from_inside() {
    let (c, p) = scheduled();
    assert_eq!(interval(c, 1), (fmi3OK, 1.0, UNCHANGED));
    assert_eq!(interval(c, 3), (fmi3OK, 0.0, NOT_YET_KNOWN));
    // t = 0: fast, then trig with u = 5 set before its activation.
    assert_eq!(activate(c, 1, 0.0), fmi3OK);
    assert_eq!(get_i32(c, 10), (fmi3OK, 1));
    assert_eq!(set_i32(c, 11, 5), fmi3OK);
    assert_eq!(activate(c, 2, 0.0), fmi3OK);
    assert_eq!(get_i32(c, 12), (fmi3OK, 5));
    assert!(p.updates.lock().unwrap().is_empty());
    // t = 1: fast's second tick: the third activation (out ticks) gives `later` its interval.
    assert_eq!(activate(c, 1, 1.0), fmi3OK);
    {
        let updates = p.updates.lock().unwrap();
        assert_eq!(
            updates.as_slice(),
            &[(Some(State::ClockUpdateMode), true, 3, fmi3OK, (0.5, CHANGED))]
        );
    }
    // After the callback: back in Clock Activation Mode, the output clock inactive, the
    // interval reported.
    assert_eq!(state(c), Some(State::ClockActivationMode));
    assert_eq!(get_clock(c, 4), (fmi3OK, false));
    assert_eq!(interval(c, 3), (fmi3OK, 0.5, UNCHANGED));
    // The countdown partition at 1.5; the clocked variables are read after it.
    assert_eq!(activate(c, 3, 1.5), fmi3OK);
    assert_eq!(get_i32(c, 13), (fmi3OK, 1));
    assert_eq!(get_i32(c, 14), (fmi3OK, 4));
    // Two more: the sixth activation ticks `out` again (no new interval this time).
    assert_eq!(activate(c, 1, 2.0), fmi3OK);
    assert_eq!(activate(c, 2, 2.0), fmi3OK);
    assert_eq!(p.updates.lock().unwrap().len(), 2);
    assert!(p.updates.lock().unwrap()[1].1);
    assert_eq!(p.updates.lock().unwrap()[1].2, 6);
    assert_eq!(p.updates.lock().unwrap()[1].4.1, UNCHANGED);
    // SAFETY: a live instance.
    unsafe {
        assert_eq!(fmi3Terminate(c), fmi3OK);
        assert_eq!(state(c), Some(State::Terminated));
        assert_eq!(fmi3Reset(c), fmi3OK);
    }
    assert_eq!(state(c), Some(State::Instantiated));
    init(c);
    assert_eq!(get_i32(c, 14), (fmi3OK, 0), "{}", last(p));
    free(c);
}

#[test]
fn without_a_callback_the_output_clock_is_read_after_the_activation() {
    let (c, p) = scheduled_with(None);
    init(c);
    for t in [0.0, 1.0] {
        assert_eq!(activate(c, 1, t), fmi3OK);
        assert_eq!(get_clock(c, 4), (fmi3OK, false));
    }
    assert_eq!(activate(c, 2, 1.0), fmi3OK);
    assert_eq!(get_clock(c, 4), (fmi3OK, true));
    assert_eq!(interval(c, 3), (fmi3OK, 0.5, CHANGED));
    // The next activation ends the tick.
    assert_eq!(activate(c, 2, 1.0), fmi3OK);
    assert_eq!(get_clock(c, 4), (fmi3OK, false));
    assert!(p.updates.lock().unwrap().is_empty());
    free(c);
}

#[test]
fn the_state_machine_and_the_refusals() {
    // Each closure: SAFETY: a live instance; locals.
    refused(true, "not allowed in state Instantiated", |c| activate(c, 1, 0.0));
    refused(false, "'out') is an output Clock", |c| activate(c, 4, 0.0));
    refused(false, "'fast_ticks') is a Int32 variable, not a Clock", |c| {
        activate(c, 10, 0.0)
    });
    refused(false, "no variable of this FMU", |c| activate(c, 99, 0.0));
    refused(false, "a finite time not before", |c| activate(c, 1, f64::NAN));
    refused(false, "a finite time not before", |c| {
        assert_eq!(activate(c, 1, 1.0), fmi3OK);
        activate(c, 1, 0.5)
    });
    // The model-exchange and co-simulation functions.
    refused(
        false,
        "is a co-simulation function; this instance was instantiated for scheduled execution",
        // SAFETY: the fresh live instance `refused` passes; the outputs are locals.
        |c| unsafe {
            let (mut a, mut b, mut d, mut t) = (false, false, false, 0.0);
            fmi3DoStep(c, 0.0, 1.0, false, &mut a, &mut b, &mut d, &mut t)
        },
    );
    // SAFETY: the fresh live instance `refused` passes; the outputs are locals.
    refused(false, "is a model-exchange function", |c| unsafe {
        fmi3EnterEventMode(c)
    });
    // SAFETY: the fresh live instance `refused` passes; the outputs are locals.
    refused(false, "is a model-exchange function", |c| unsafe {
        let (mut a, mut b, mut d, mut e, mut f, mut g) = (false, false, false, false, false, 0.0);
        fmi3UpdateDiscreteStates(c, &mut a, &mut b, &mut d, &mut e, &mut f, &mut g)
    });
    // SAFETY: the fresh live instance `refused` passes; the outputs are locals.
    refused(false, "fmi3ActivateModelPartition", |c| unsafe {
        fmi3SetClock(c, &1, 1, &true)
    });
    // SAFETY: the fresh live instance `refused` passes; the outputs are locals.
    refused(false, "only fixed and tunable clocks", |c| unsafe {
        fmi3SetIntervalDecimal(c, &1, 1, &0.5)
    });
    // A clocked input is set before its partition runs; an output is not set.
    refused(false, "cannot be set", |c| set_i32(c, 12, 1));
    // A call into the instance from its clockUpdate callback is fine, except what is not allowed
    // in Clock Update Mode: an FMU state, another activation.
    for (what, why) in [
        ("state", "not allowed in state ClockUpdateMode"),
        ("activate", "not allowed in state ClockUpdateMode"),
    ] {
        let (c, p) = scheduled_with(Some(if what == "state" {
            nested_state
        } else {
            nested_activation
        }));
        init(c);
        for t in [0.0, 0.0, 0.0] {
            assert_eq!(activate(c, 2, t), fmi3OK);
        }
        assert!(
            p.log.messages().iter().any(|m| m.contains(why)),
            "{:?}",
            p.log.messages()
        );
        // The refusal inside ended the run (FMI 3.0: fmi3Error leads to Terminated).
        assert_eq!(state(c), Some(State::Terminated));
        free(c);
    } // fmi3FreeInstance from the callback would pull the instance from under the activation that
    // called it: refused, and the instance goes on.
    let (c, p) = scheduled_with(Some(nested_free));
    init(c);
    for t in [0.0, 0.0, 0.0] {
        assert_eq!(activate(c, 2, t), fmi3OK);
    }
    assert!(last(p).contains("called from the clockUpdate callback"), "{}", last(p));
    assert_eq!(state(c), Some(State::ClockActivationMode));
    assert_eq!(activate(c, 2, 1.0), fmi3OK);
    free(c);
}

unsafe extern "C" fn nested_state(env: *mut c_void) {
    // SAFETY: env is the leaked &Probe given at instantiation.
    let p = unsafe { &*(env as *const Probe) };
    let mut s: fmi3FMUState = null_mut();
    // SAFETY: the live instance; a local.
    let status = unsafe { fmi3GetFMUState(p.instance.load(Ordering::Acquire), &mut s) };
    assert_eq!(status, fmi3Error);
}

unsafe extern "C" fn nested_free(env: *mut c_void) {
    // SAFETY: env is the leaked &Probe given at instantiation.
    let p = unsafe { &*(env as *const Probe) };
    // SAFETY: the live instance (the runtime refuses to free it from here).
    unsafe { fmi3FreeInstance(p.instance.load(Ordering::Acquire)) };
}

unsafe extern "C" fn nested_activation(env: *mut c_void) {
    // SAFETY: env is the leaked &Probe given at instantiation.
    let p = unsafe { &*(env as *const Probe) };
    assert_eq!(activate(p.instance.load(Ordering::Acquire), 1, 0.0), fmi3Error);
}

#[test]
fn model_exchange_and_co_simulation_instances_refuse_the_activation() {
    let p: &'static Probe = Box::leak(Box::default());
    let how = fmi3::Instantiation {
        logging_on: true,
        ..fmi3::Instantiation::new("me")
    };
    let me = how.model_exchange(fmi3InstantiateModelExchange, TOKEN, p);
    assert!(!me.is_null());
    // SAFETY: a live instance, freed once.
    unsafe {
        assert_eq!(fmi3EnterInitializationMode(me, false, 0.0, 0.0, false, 0.0), fmi3OK);
        assert_eq!(fmi3ExitInitializationMode(me), fmi3OK);
        assert_eq!(activate(me, 1, 0.0), fmi3Error);
        assert!(
            last(p).contains("is a scheduled-execution function; this instance was instantiated for model exchange")
        );
        fmi3FreeInstance(me);
    }
    let how = fmi3::Instantiation {
        logging_on: true,
        event_mode_used: true,
        ..fmi3::Instantiation::new("cs")
    };
    let cs = how.co_simulation(fmi3InstantiateCoSimulation, TOKEN, p, None);
    assert!(!cs.is_null());
    // SAFETY: a live instance, freed once.
    unsafe {
        assert_eq!(fmi3EnterInitializationMode(cs, false, 0.0, 0.0, false, 0.0), fmi3OK);
        assert_eq!(fmi3ExitInitializationMode(cs), fmi3OK);
        assert_eq!(activate(cs, 1, 0.0), fmi3Error);
        assert!(last(p).contains("instantiated for co-simulation"));
        fmi3FreeInstance(cs);
    }
    // The token is checked as for the other interfaces.
    let how = fmi3::Instantiation {
        logging_on: true,
        ..fmi3::Instantiation::new("x")
    };
    let c = how.scheduled_execution(fmi3InstantiateScheduledExecution, "{wrong}", p, None);
    assert!(c.is_null());
    assert!(last(p).contains("does not match"));
}

#[test]
fn fmu_states_are_taken_and_restored_in_clock_activation_mode() {
    let (c, _) = scheduled();
    assert_eq!(activate(c, 1, 0.0), fmi3OK);
    let mut s: fmi3FMUState = null_mut();
    // SAFETY: a live instance; locals; the state is freed below.
    unsafe {
        assert_eq!(fmi3GetFMUState(c, &mut s), fmi3OK);
    }
    let run = |c| {
        assert_eq!(activate(c, 1, 1.0), fmi3OK);
        assert_eq!(set_i32(c, 11, 3), fmi3OK);
        assert_eq!(activate(c, 2, 1.0), fmi3OK);
        assert_eq!(activate(c, 3, 1.5), fmi3OK);
        [10, 12, 13, 14].map(|vr| get_i32(c, vr).1)
    };
    let first = run(c);
    assert_eq!(first, [2, 3, 1, 4]);
    // SAFETY: a live instance and its state; locals.
    unsafe {
        assert_eq!(fmi3SetFMUState(c, s), fmi3OK);
        assert_eq!(state(c), Some(State::ClockActivationMode));
        assert_eq!(get_i32(c, 14), (fmi3OK, 1));
        assert_eq!(run(c), first);
        // Serialized and restored into another instance for scheduled execution.
        let mut size = 0;
        assert_eq!(fmi3SerializedFMUStateSize(c, s, &mut size), fmi3OK);
        let mut bytes = vec![0u8; size];
        assert_eq!(fmi3SerializeFMUState(c, s, bytes.as_mut_ptr(), size), fmi3OK);
        let (d, _) = scheduled();
        let mut t: fmi3FMUState = null_mut();
        assert_eq!(fmi3DeserializeFMUState(d, bytes.as_ptr(), size, &mut t), fmi3OK);
        assert_eq!(fmi3SetFMUState(d, t), fmi3OK);
        assert_eq!(run(d), first);
        assert_eq!(fmi3FreeFMUState(d, &mut t), fmi3OK);
        free(d);
        assert_eq!(fmi3FreeFMUState(c, &mut s), fmi3OK);
    }
    free(c);
}

#[test]
fn activations_from_two_threads_wait_for_each_other() {
    let (c, p) = scheduled();
    let handle = c as usize;
    let threads: Vec<_> = (0..2)
        .map(|k| {
            std::thread::spawn(move || {
                let c = handle as fmi3Instance;
                for _ in 0..300 {
                    assert_eq!(activate(c, 2 + k, 0.0), fmi3OK);
                }
            })
        })
        .collect();
    for t in threads {
        t.join().unwrap();
    }
    assert_eq!(get_i32(c, 14), (fmi3OK, 600));
    // Every third activation called back, each time from inside a serialized call.
    let updates = p.updates.lock().unwrap();
    assert_eq!(updates.len(), 200);
    assert!(
        updates
            .iter()
            .all(|u| u.0 == Some(State::ClockUpdateMode) && u.1 && u.2 % 3 == 0 && u.3 == fmi3OK)
    );
    drop(updates);
    free(c);
}
