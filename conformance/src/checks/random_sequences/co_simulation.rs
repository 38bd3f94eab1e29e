//! Random co-simulation call sequences: the calls ([`Op`]) and their strategies, the shadow of
//! the FMI 2.0 state machine, one call with what the shadow expects of it (the check that runs them: [`super::checks`]).

use super::{Expect, SLOTS, Vr, real, resolve, vr};
use crate::fmi2::*;
use crate::guard::{GETTER_RULE2, Guarded, STATE_RULE2};
use crate::instance::{Args, Instance, status_name};
use crate::outcome::{breadcrumb, limitation};
use crate::replay::Expected;
use crate::standard::allowed_states;
use crate::state::State;
use crate::{Fmu, Type, state};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;
use std::ptr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Coverage counters: calls made in each state, and calls answered fmi2OK in each state.
pub(super) static CALLS: [AtomicUsize; 8] = [const { AtomicUsize::new(0) }; 8];
pub(super) static OK_CALLS: [AtomicUsize; 8] = [const { AtomicUsize::new(0) }; 8];
pub(super) static OK_STEPS: AtomicUsize = AtomicUsize::new(0);

/// When the communication point of a step is.
#[derive(Debug, Clone, Copy)]
pub(super) enum When {
    /// The FMU's time, as the importer tracks it.
    Now,
    /// Off by round-off.
    NowTimes(f64),
    At(f64),
}

#[derive(Debug, Clone)]
pub(super) enum Op {
    SetDebugLogging {
        on: bool,
        categories: Vec<usize>,
        null: bool,
    },
    Setup {
        tolerance: Option<f64>,
        start: f64,
        stop: Option<f64>,
    },
    EnterInit,
    ExitInit,
    Terminate,
    Reset,
    GetReal {
        vrs: Vec<Vr>,
        null: bool,
    },
    GetInteger {
        vrs: Vec<Vr>,
    },
    GetBoolean {
        vrs: Vec<Vr>,
    },
    GetString {
        vrs: Vec<Vr>,
    },
    SetReal {
        values: Vec<(Vr, f64)>,
        null: bool,
    },
    SetInteger {
        values: Vec<(Vr, i32)>,
    },
    SetBoolean {
        values: Vec<(Vr, i32)>,
    },
    SetString {
        vrs: Vec<Vr>,
    },
    GetState {
        slot: usize,
    },
    SetState {
        slot: usize,
    },
    FreeState {
        slot: usize,
    },
    Serialize {
        slot: usize,
    },
    Deserialize {
        to: usize,
        damage: Option<(usize, u8)>,
        truncate: Option<usize>,
    },
    DoStep {
        when: When,
        h: f64,
    },
    CancelStep,
    Status {
        which: u8,
        kind: u32,
    },
    DirectionalDerivative {
        n: usize,
    },
    InputDerivatives {
        n: usize,
    },
    OutputDerivatives {
        n: usize,
    },
}

pub(super) fn step_size() -> impl Strategy<Value = f64> {
    prop_oneof![
        12 => 1e-4..0.05f64,
        1 => Just(0.0),
        1 => -1.0..0.0f64,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::MIN_POSITIVE),
        1 => 1.0..100.0f64,
    ]
}

pub(super) fn op() -> impl Strategy<Value = Op> {
    let slot = 0..SLOTS;
    prop_oneof![
        1 => (any::<bool>(), prop::collection::vec(0..9usize, 0..3), prop::bool::weighted(0.1))
            .prop_map(|(on, categories, null)| Op::SetDebugLogging { on, categories, null }),
        2 => (prop::option::of(prop_oneof![1e-12..1e-2f64, real()]), prop_oneof![4 => Just(0.0), 1 => real()], prop::option::of(prop_oneof![0.0..10.0f64, real()]))
            .prop_map(|(tolerance, start, stop)| Op::Setup { tolerance, start, stop }),
        4 => Just(Op::EnterInit),
        4 => Just(Op::ExitInit),
        1 => Just(Op::Terminate),
        1 => Just(Op::Reset),
        3 => (prop::collection::vec(vr(), 0..5), prop::bool::weighted(0.05)).prop_map(|(vrs, null)| Op::GetReal { vrs, null }),
        1 => prop::collection::vec(vr(), 0..3).prop_map(|vrs| Op::GetInteger { vrs }),
        1 => prop::collection::vec(vr(), 0..3).prop_map(|vrs| Op::GetBoolean { vrs }),
        1 => prop::collection::vec(vr(), 0..2).prop_map(|vrs| Op::GetString { vrs }),
        5 => (prop::collection::vec((vr(), real()), 0..4), prop::bool::weighted(0.05)).prop_map(|(values, null)| Op::SetReal { values, null }),
        1 => prop::collection::vec((vr(), any::<i32>()), 0..3).prop_map(|values| Op::SetInteger { values }),
        1 => prop::collection::vec((vr(), any::<i32>()), 0..3).prop_map(|values| Op::SetBoolean { values }),
        1 => prop::collection::vec(vr(), 0..2).prop_map(|vrs| Op::SetString { vrs }),
        2 => slot.clone().prop_map(|slot| Op::GetState { slot }),
        2 => slot.clone().prop_map(|slot| Op::SetState { slot }),
        1 => slot.clone().prop_map(|slot| Op::FreeState { slot }),
        1 => slot.clone().prop_map(|slot| Op::Serialize { slot }),
        1 => (slot, prop::option::of((any::<usize>(), 1..=255u8)), prop::option::of(any::<usize>()))
            .prop_map(|(to, damage, truncate)| Op::Deserialize { to, damage, truncate }),
        10 => (prop_oneof![8 => Just(When::Now), 1 => (-1e-13..1e-13f64).prop_map(|e| When::NowTimes(1.0 + e)), 1 => real().prop_map(When::At)], step_size())
            .prop_map(|(when, h)| Op::DoStep { when, h }),
        1 => Just(Op::CancelStep),
        2 => (0..5u8, 0..6u32).prop_map(|(which, kind)| Op::Status { which, kind }),
        1 => (0..3usize).prop_map(|n| Op::DirectionalDerivative { n }),
        1 => (0..3usize).prop_map(|n| Op::InputDerivatives { n }),
        1 => (0..3usize).prop_map(|n| Op::OutputDerivatives { n }),
    ]
}

/// The shadow model: the state machine as the standard describes it, the FMU's time, and
/// what the importer holds (FMU states and serialized bytes) with the state each was taken in.
pub(super) struct Shadow {
    state: State,
    time: f64,
    stop: Option<f64>,
    slots: [Option<(fmi2FMUstate, Snap)>; SLOTS],
    bytes: Option<(Vec<u8>, Snap)>,
}

/// What an FMU state holds that the shadow tracks.
#[derive(Debug, Clone, Copy)]
pub(super) struct Snap {
    state: State,
    time: f64,
    stop: Option<f64>,
}

impl Shadow {
    fn snap(&self) -> Snap {
        Snap {
            state: self.state,
            time: self.time,
            stop: self.stop,
        }
    }
}

pub(super) const CATEGORIES: [&std::ffi::CStr; 9] = [
    c"logEvents",
    c"logStatusWarning",
    c"logStatusDiscard",
    c"logStatusError",
    c"logStatusFatal",
    c"logCalls",
    c"logAll",
    c"logNoSuchCategory",
    c"log%s%n",
];

pub(super) fn function_of(op: &Op) -> &'static str {
    match op {
        Op::SetDebugLogging { .. } => "fmi2SetDebugLogging",
        Op::Setup { .. } => "fmi2SetupExperiment",
        Op::EnterInit => "fmi2EnterInitializationMode",
        Op::ExitInit => "fmi2ExitInitializationMode",
        Op::Terminate => "fmi2Terminate",
        Op::Reset => "fmi2Reset",
        Op::GetReal { .. } => "fmi2GetReal",
        Op::GetInteger { .. } => "fmi2GetInteger",
        Op::GetBoolean { .. } => "fmi2GetBoolean",
        Op::GetString { .. } => "fmi2GetString",
        Op::SetReal { .. } => "fmi2SetReal",
        Op::SetInteger { .. } => "fmi2SetInteger",
        Op::SetBoolean { .. } => "fmi2SetBoolean",
        Op::SetString { .. } => "fmi2SetString",
        Op::GetState { .. } => "fmi2GetFMUstate",
        Op::SetState { .. } => "fmi2SetFMUstate",
        Op::FreeState { .. } => "fmi2FreeFMUstate",
        Op::Serialize { .. } => "fmi2SerializeFMUstate",
        Op::Deserialize { .. } => "fmi2DeSerializeFMUstate",
        Op::DoStep { .. } => "fmi2DoStep",
        Op::CancelStep => "fmi2CancelStep",
        Op::Status { which, .. } => [
            "fmi2GetStatus",
            "fmi2GetRealStatus",
            "fmi2GetIntegerStatus",
            "fmi2GetBooleanStatus",
            "fmi2GetStringStatus",
        ][*which as usize],
        Op::DirectionalDerivative { .. } => "fmi2GetDirectionalDerivative",
        Op::InputDerivatives { .. } => "fmi2SetRealInputDerivatives",
        Op::OutputDerivatives { .. } => "fmi2GetRealOutputDerivatives",
    }
}

/// Runs one call; returns its status, what the shadow expects of it, and the state that
/// follows if it succeeds.
// One arm per kind of call: kept whole, over ~150 lines, so that what the shadow expects of each
// call sits beside the call itself.
pub(super) fn call(inst: &mut Instance, sh: &mut Shadow, op: &Op) -> (fmi2Status, Expect, Option<State>) {
    let fmu = inst.fmu;
    let api = &fmu.api;
    let c = inst.c;
    let vrs_of = |v: &[Vr]| -> Vec<u32> { v.iter().map(|x| resolve(fmu, *x)).collect() };
    // SAFETY: for every call below, arrays have the lengths passed (or are NULL on purpose,
    // which the FMU must refuse), FMU states are ones this FMU handed out and not yet freed.
    unsafe {
        match op {
            Op::SetDebugLogging { on, categories, null } => {
                let cats: Vec<fmi2String> = categories.iter().map(|i| CATEGORIES[*i].as_ptr()).collect();
                let p = if *null && !cats.is_empty() {
                    ptr::null()
                } else {
                    cats.as_ptr()
                };
                let s = (api.set_debug_logging)(c, *on as i32, cats.len(), p);
                let bad = (*null && !cats.is_empty()) || categories.iter().any(|i| *i >= 7);
                let expect = if *null && !cats.is_empty() {
                    Expect::Refused
                } else if !fmu.own_state_format() {
                    // Which categories another exporter's FMU knows is its own business.
                    Expect::Anything
                } else if bad {
                    Expect::Refused
                } else {
                    Expect::Succeeds
                };
                (s, expect, None)
            }
            Op::Setup { tolerance, start, stop } => {
                let s = (api.setup_experiment)(
                    c,
                    tolerance.is_some() as i32,
                    tolerance.unwrap_or(0.0),
                    *start,
                    stop.is_some() as i32,
                    stop.unwrap_or(0.0),
                );
                if s == fmi2OK {
                    (sh.time, sh.stop) = (*start, *stop);
                }
                let bad = !start.is_finite()
                    || tolerance.is_some_and(|t| !(t.is_finite() && t > 0.0))
                    || stop.is_some_and(|e| !(e.is_finite() && e >= *start));
                (s, if bad { Expect::Refused } else { Expect::Succeeds }, None)
            }
            Op::EnterInit => (
                (api.enter_initialization_mode)(c),
                Expect::Succeeds,
                Some(State::InitializationMode),
            ),
            Op::ExitInit => (
                (api.exit_initialization_mode)(c),
                Expect::Anything,
                Some(State::StepComplete),
            ),
            Op::Terminate => ((api.terminate)(c), Expect::Succeeds, Some(State::Terminated)),
            Op::Reset => {
                let s = (api.reset)(c);
                if s == fmi2OK {
                    (sh.time, sh.stop) = (0.0, None);
                }
                (s, Expect::Succeeds, Some(State::Instantiated))
            }
            Op::GetReal { vrs, null } => {
                let v = vrs_of(vrs);
                let mut out = Guarded::new(v.len(), 0.0);
                let p = if *null { ptr::null_mut() } else { out.as_mut_ptr() };
                let s = (api.get_real)(c, v.as_ptr(), v.len(), p);
                out.into_values(|| format!("fmi2GetReal with nvr = {}", v.len()), GETTER_RULE2);
                let bad = *null && !v.is_empty();
                (s, if bad { Expect::Refused } else { Expect::Anything }, None)
            }
            Op::GetInteger { vrs } => {
                let v = vrs_of(vrs);
                let mut out = Guarded::new(v.len(), 0);
                let s = (api.get_integer)(c, v.as_ptr(), v.len(), out.as_mut_ptr());
                out.into_values(|| format!("fmi2GetInteger with nvr = {}", v.len()), GETTER_RULE2);
                (s, Expect::Anything, None)
            }
            Op::GetBoolean { vrs } => {
                let v = vrs_of(vrs);
                let mut out = Guarded::new(v.len(), 0);
                let s = (api.get_boolean)(c, v.as_ptr(), v.len(), out.as_mut_ptr());
                out.into_values(|| format!("fmi2GetBoolean with nvr = {}", v.len()), GETTER_RULE2);
                (s, Expect::Anything, None)
            }
            Op::GetString { vrs } => {
                let v = vrs_of(vrs);
                let mut out: Guarded<fmi2String> = Guarded::new(v.len(), ptr::null());
                let s = (api.get_string)(c, v.as_ptr(), v.len(), out.as_mut_ptr());
                out.into_values(|| format!("fmi2GetString with nvr = {}", v.len()), GETTER_RULE2);
                (s, Expect::Anything, None)
            }
            Op::SetReal { values, null } => {
                let v: Vec<u32> = values.iter().map(|(x, _)| resolve(fmu, *x)).collect();
                let x: Vec<f64> = values.iter().map(|(_, x)| *x).collect();
                let p = if *null { ptr::null() } else { x.as_ptr() };
                let s = (api.set_real)(c, v.as_ptr(), v.len(), p);
                let bad = (*null && !v.is_empty()) || x.iter().any(|x| !x.is_finite());
                (s, if bad { Expect::Refused } else { Expect::Anything }, None)
            }
            Op::SetInteger { values } => {
                let v: Vec<u32> = values.iter().map(|(x, _)| resolve(fmu, *x)).collect();
                let x: Vec<i32> = values.iter().map(|(_, x)| *x).collect();
                (
                    (api.set_integer)(c, v.as_ptr(), v.len(), x.as_ptr()),
                    Expect::Anything,
                    None,
                )
            }
            Op::SetBoolean { values } => {
                let v: Vec<u32> = values.iter().map(|(x, _)| resolve(fmu, *x)).collect();
                let x: Vec<i32> = values.iter().map(|(_, x)| *x).collect();
                (
                    (api.set_boolean)(c, v.as_ptr(), v.len(), x.as_ptr()),
                    Expect::Anything,
                    None,
                )
            }
            Op::SetString { vrs } => {
                let v = vrs_of(vrs);
                let x: Vec<fmi2String> = vec![c"text %s".as_ptr(); v.len()];
                (
                    (api.set_string)(c, v.as_ptr(), v.len(), x.as_ptr()),
                    Expect::Anything,
                    None,
                )
            }
            Op::GetState { slot } => {
                let mut p = sh.slots[*slot].map_or(ptr::null_mut(), |s| s.0);
                let s = crate::guard::fill_state2(&mut p, "fmi2GetFMUstate", |q| (api.get_fmu_state)(c, q));
                if s == fmi2OK {
                    sh.slots[*slot] = Some((p, sh.snap()));
                }
                (s, Expect::Succeeds, None)
            }
            Op::SetState { slot } => match sh.slots[*slot] {
                Some((p, snap)) => {
                    let s = (api.set_fmu_state)(c, p);
                    if s == fmi2OK {
                        (sh.time, sh.stop) = (snap.time, snap.stop);
                    }
                    (s, Expect::Succeeds, Some(snap.state))
                }
                None => ((api.set_fmu_state)(c, ptr::null_mut()), Expect::Refused, None),
            },
            Op::FreeState { slot } => {
                let mut p = sh.slots[*slot].map_or(ptr::null_mut(), |s| s.0);
                let s = crate::guard::fill_state2(&mut p, "fmi2FreeFMUstate", |q| (api.free_fmu_state)(c, q));
                if s == fmi2OK {
                    assert!(p.is_null(), "fmi2FreeFMUstate left the pointer set");
                    sh.slots[*slot] = None;
                }
                (s, Expect::Succeeds, None)
            }
            Op::Serialize { slot } => match sh.slots[*slot] {
                Some((p, snap)) => {
                    let mut size = 0usize;
                    let s1 = crate::guard::fill_state_size2(&mut size, "fmi2SerializedFMUstateSize", |q| {
                        (api.serialized_fmu_state_size)(c, p, q)
                    });
                    if s1 != fmi2OK {
                        return (s1, Expect::Succeeds, None);
                    }
                    let mut guarded = Guarded::new(size, 0u8);
                    let s = (api.serialize_fmu_state)(c, p, guarded.as_mut_ptr() as *mut fmi2Byte, size);
                    let buf = guarded.into_values(|| format!("fmi2SerializeFMUstate with size = {size}"), STATE_RULE2);
                    if s == fmi2OK {
                        sh.bytes = Some((buf, snap));
                    }
                    (s, Expect::Succeeds, None)
                }
                None => {
                    let mut size = 0usize;
                    (
                        crate::guard::fill_state_size2(&mut size, "fmi2SerializedFMUstateSize", |p| {
                            (api.serialized_fmu_state_size)(c, ptr::null_mut(), p)
                        }),
                        Expect::Refused,
                        None,
                    )
                }
            },
            Op::Deserialize { to, damage, truncate } => {
                let damage = if fmu.own_state_format() { damage } else { &None };
                let Some((mut bytes, snap)) = sh.bytes.clone() else {
                    let mut p = ptr::null_mut();
                    let s = crate::guard::fill_state2(&mut p, "fmi2DeSerializeFMUstate", |q| {
                        (api.deserialize_fmu_state)(c, ptr::null(), 8, q)
                    });
                    return (s, Expect::Refused, None);
                };
                let damaged = damage.is_some() || truncate.is_some_and(|n| n % (bytes.len() + 1) < bytes.len());
                if let Some((at, x)) = damage {
                    let n = bytes.len();
                    bytes[at % n] ^= x;
                }
                if let Some(n) = truncate {
                    bytes.truncate(n % (bytes.len() + 1));
                }
                let mut p = sh.slots[*to].map_or(ptr::null_mut(), |s| s.0);
                let before = p;
                let s = crate::guard::fill_state2(&mut p, "fmi2DeSerializeFMUstate", |q| {
                    (api.deserialize_fmu_state)(c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), q)
                });
                if s == fmi2OK {
                    sh.slots[*to] = Some((p, snap));
                } else {
                    assert_eq!(p, before, "a refused fmi2DeSerializeFMUstate changed *FMUstate");
                }
                (s, if damaged { Expect::Refused } else { Expect::Succeeds }, None)
            }
            Op::DoStep { when, h } => {
                let now = sh.time;
                let t = match when {
                    When::Now => sh.time,
                    When::NowTimes(f) => sh.time * f,
                    When::At(t) => *t,
                };
                let s = (api.do_step)(c, t, *h, fmi2False);
                let next = match s {
                    fmi2OK => {
                        sh.time = t + h;
                        Some(State::StepComplete)
                    }
                    fmi2Discard => {
                        let mut lst = f64::NAN;
                        let _ = crate::guard::fill_status2(&mut lst, "fmi2GetRealStatus", |p| {
                            (api.get_real_status)(c, fmi2LastSuccessfulTime, p)
                        });
                        sh.time = lst;
                        Some(State::StepFailed)
                    }
                    _ => None,
                };
                let bad_h = !(h.is_finite() && *h > 0.0) || t + h <= t;
                let off = (t - now).abs() > 1e-6 * (1.0 + now.abs());
                let past_stop = sh.stop.is_some_and(|e| t + h > e + 1e-6 * (1.0 + e.abs()));
                let good =
                    matches!(when, When::Now | When::NowTimes(_)) && (1e-4..0.05).contains(h) && sh.stop.is_none();
                let expect = if bad_h || off || past_stop {
                    Expect::Refused
                } else if good {
                    Expect::Succeeds
                } else {
                    Expect::Anything
                };
                (s, expect, next)
            }
            Op::CancelStep => ((api.cancel_step)(c), Expect::Anything, None),
            Op::Status { which, kind } => {
                let s = match which {
                    0 => crate::guard::fill_status2(&mut 0, "fmi2GetStatus", |p| (api.get_status)(c, *kind, p)),
                    1 => crate::guard::fill_status2(&mut 0.0, "fmi2GetRealStatus", |p| {
                        (api.get_real_status)(c, *kind, p)
                    }),
                    2 => crate::guard::fill_status2(&mut 0, "fmi2GetIntegerStatus", |p| {
                        (api.get_integer_status)(c, *kind, p)
                    }),
                    3 => crate::guard::fill_status2(&mut 0, "fmi2GetBooleanStatus", |p| {
                        (api.get_boolean_status)(c, *kind, p)
                    }),
                    _ => crate::guard::fill_status2(&mut ptr::null(), "fmi2GetStringStatus", |p| {
                        (api.get_string_status)(c, *kind, p)
                    }),
                };
                (s, Expect::Anything, None)
            }
            Op::DirectionalDerivative { n } => {
                let reals = fmu.md.vrs_of_type(Type::Real);
                let v = &reals[..(*n).min(reals.len())];
                let (dk, mut du) = (vec![1.0; v.len()], vec![0.0; v.len()]);
                let s = crate::guard::fill(
                    &mut du,
                    "fmi2GetDirectionalDerivative",
                    "nUnknown",
                    crate::guard::GETTER_RULE2,
                    |p| (api.get_directional_derivative)(c, v.as_ptr(), v.len(), v.as_ptr(), v.len(), dk.as_ptr(), p),
                );
                (s, Expect::Anything, None)
            }
            Op::InputDerivatives { n } => {
                let v = vec![0u32; *n];
                let (o, x) = (vec![1; *n], vec![0.0; *n]);
                (
                    (api.set_real_input_derivatives)(c, v.as_ptr(), *n, o.as_ptr(), x.as_ptr()),
                    Expect::Anything,
                    None,
                )
            }
            Op::OutputDerivatives { n } => {
                let v = vec![0u32; *n];
                let (o, mut x) = (vec![1; *n], vec![0.0; *n]);
                (
                    crate::guard::fill(
                        &mut x,
                        "fmi2GetRealOutputDerivatives",
                        "nvr",
                        crate::guard::GETTER_RULE2,
                        |p| (api.get_real_output_derivatives)(c, v.as_ptr(), *n, o.as_ptr(), p),
                    ),
                    Expect::Anything,
                    None,
                )
            }
        }
    }
}

/// What every call of a random sequence answers, of either interface: within 10 s, one of the
/// four statuses, and (where mistakes are judged) a message with any status but fmi2OK.
/// `Ok(false)`: the sequence ends here.
pub(super) fn answered(
    at: &str,
    took: Duration,
    status: fmi2Status,
    log: &[crate::LogEntry],
    judge_mistakes: bool,
) -> Result<bool, TestCaseError> {
    prop_assert!(took < Duration::from_secs(10), "{}: took {:?}", at, took);
    prop_assert!(
        matches!(status, fmi2OK | fmi2Warning | fmi2Discard | fmi2Error),
        "{}: answered {} ({}); log {:?}",
        at,
        status_name(status),
        status,
        log
    );
    // After fmi2Error FMI 2.0.5 (§2.1.3) leaves the instance undefined but for fmi2Reset,
    // fmi2SetFMUstate and fmi2FreeInstance, and requires no message with it: on another
    // exporter's FMU the sequence ends there.
    if status == fmi2Error && !judge_mistakes {
        return Ok(false);
    }
    // FMI 2.0.5 asks no message with a status: judged where mistakes are.
    if status != fmi2OK && judge_mistakes {
        prop_assert!(
            log.iter().any(|e| e.status == status),
            "{}: {} without a message; log {:?}",
            at,
            status_name(status),
            log
        );
    }
    Ok(true)
}

pub(super) fn execute(fmu: &Fmu, logging_on: bool, ops: &[Op]) -> Result<(), TestCaseError> {
    execute_with(fmu, logging_on, ops, &mut |_, _, _, _, _| Ok(()))
}

/// What [`run_ops`] tells about each call it made, before it checks the answer: the call's index
/// in the sequence, the call, the status, what the standard requires there, the log it wrote.
pub(in crate::checks) type Hook<'h, O> =
    &'h mut dyn FnMut(usize, &O, fmi2Status, Expected, &[crate::LogEntry]) -> Result<(), TestCaseError>;

/// The statuses the standard allows a call: fmi2Error where the state does not allow it or the
/// arguments are invalid, fmi2OK (a step also fmi2Discard) where it must succeed, else any.
pub(super) fn expected_of(allowed: bool, expect: &Expect, function: &str) -> Expected {
    match (allowed, expect) {
        (false, _) | (true, Expect::Refused) => Expected::ERROR,
        (true, Expect::Succeeds) if function == "fmi2DoStep" => Expected::OK_OR_DISCARD,
        (true, Expect::Succeeds) => Expected::OK,
        (true, Expect::Anything) => Expected::ANY,
    }
}

/// [`execute`], telling `hook` about each call.
pub(super) fn execute_with(fmu: &Fmu, logging_on: bool, ops: &[Op], hook: Hook<Op>) -> Result<(), TestCaseError> {
    let args = Args {
        logging_on,
        ..Args::valid(fmu)
    };
    let mut inst = Instance::with(fmu, &args).map_err(|log| TestCaseError::fail(format!("instantiate: {log:?}")))?;
    let mut sh = Shadow {
        state: State::Instantiated,
        time: 0.0,
        stop: None,
        slots: [None; SLOTS],
        bytes: None,
    };
    let result = run_ops(&mut inst, &mut sh, ops, hook);
    // Whatever happened, free the FMU states the importer still holds (allowed in every state
    // the shadow can be in; Fatal would already have failed the case).
    for slot in sh.slots.iter_mut() {
        if let Some((mut p, _)) = slot.take() {
            let _ = inst.free_state(&mut p);
        }
    }
    inst.log();
    result
}

/// Whether the FMU declares what the call needs (an importer calls nothing else).
pub(super) fn declared(fmu: &Fmu, op: &Op) -> bool {
    match op {
        Op::GetState { .. } | Op::SetState { .. } | Op::FreeState { .. } => fmu.cs().can_get_and_set_fmu_state,
        Op::Serialize { .. } | Op::Deserialize { .. } => fmu.can_snapshot(),
        _ => true,
    }
}

pub(super) fn run_ops(inst: &mut Instance, sh: &mut Shadow, ops: &[Op], hook: Hook<Op>) -> Result<(), TestCaseError> {
    let own = inst.fmu.own_state_format();
    // The importer's mistakes (a call the state machine does not allow, invalid arguments) and
    // the FMU state after a refusal are judged on this exporter's FMUs and under --strict; FMI
    // 2.0.5 asks no detection of them (the calls checks warn about them on any FMU).
    let judge_mistakes = own || crate::outcome::strict();
    let snapshots = inst.fmu.can_snapshot();
    for (i, op) in ops.iter().enumerate() {
        if !declared(inst.fmu, op) {
            continue;
        }
        let function = function_of(op);
        let allowed = allowed_states(function).contains(&sh.state);
        let before = if snapshots { inst.snapshot() } else { vec![] };
        if own {
            prop_assert_eq!(
                state::machine_state(&before).unwrap(),
                sh.state,
                "op {}: shadow and FMU disagree before {:?}",
                i,
                op
            );
        }
        // A NULL array passed with values on purpose (`null: true`, no empty list) and a step
        // size that is not finite and positive are importer's mistakes: a crash or hang in them
        // is a warning (outcome::IMPORTERS_MISTAKE), as in the calls checks.
        let text = format!("random call {i} of a sequence: {op:?} in state {:?}", sh.state);
        let bad_step = matches!(op, Op::DoStep { h, .. } if !(h.is_finite() && *h > 0.0));
        if (text.contains("null: true") && !text.contains("[]")) || bad_step {
            breadcrumb(&format!("{}{text}", crate::outcome::IMPORTERS_MISTAKE));
        } else {
            breadcrumb(&text);
        }
        let clock = Instant::now();
        let (status, expect, next) = call(inst, sh, op);
        let took = clock.elapsed();
        let log = inst.log();
        hook(i, op, status, expected_of(allowed, &expect, function), &log)?;
        CALLS[sh.state as usize].fetch_add(1, Ordering::Relaxed);
        if status == fmi2OK {
            OK_CALLS[sh.state as usize].fetch_add(1, Ordering::Relaxed);
            if function == "fmi2DoStep" {
                OK_STEPS.fetch_add(1, Ordering::Relaxed);
            }
        }
        let at = format!("op {i} {op:?} in {:?}", sh.state);
        if !answered(&at, took, status, &log, judge_mistakes)? {
            return Ok(());
        }
        if !allowed && judge_mistakes {
            prop_assert_eq!(
                status,
                fmi2Error,
                "{}: not allowed but answered {}",
                at,
                status_name(status)
            );
            let state = format!("state {:?}", sh.state);
            let named = if own {
                log.iter().any(|e| e.text.contains(function) && e.text.contains(&state))
            } else {
                inst.says(&log, fmi2Error, &[function, &state])
            };
            prop_assert!(named, "{}: refused without naming function and state: {:?}", at, log);
        } else if allowed {
            match expect {
                Expect::Refused if !judge_mistakes => {}
                Expect::Refused => prop_assert_eq!(status, fmi2Error, "{}: invalid arguments accepted", at),
                Expect::Succeeds => prop_assert!(
                    status == fmi2OK || (function == "fmi2DoStep" && status == fmi2Discard),
                    "{}: a valid call answered {}: {:?}",
                    at,
                    status_name(status),
                    log
                ),
                Expect::Anything => {}
            }
        }
        if status == fmi2Error {
            if snapshots && judge_mistakes {
                let after = inst.snapshot();
                prop_assert!(after == before, "{}: answered fmi2Error but changed the FMU state", at);
            }
        } else if allowed && let Some(next) = next {
            sh.state = next;
        }
        if own {
            let now = state::machine_state(&inst.snapshot()).unwrap();
            prop_assert_eq!(
                now,
                sh.state,
                "{}: the FMU is in {:?}, the standard says {:?}",
                at,
                now,
                sh.state
            );
        }
    }
    Ok(())
}

/// Records what the random sequences cannot do on this FMU.
pub(super) fn note_limitations(fmu: &Fmu) {
    if !fmu.own_state_format() {
        limitation(
            "the state machine is not read from the FMU after each call (only this exporter's serialized state shows it)",
        );
        limitation("serialized states are damaged only by truncation, not by bit flips");
        limitation("fmi2SetDebugLogging may accept or refuse category names (not this exporter's categories)");
    }
    if !fmu.can_snapshot() {
        limitation(
            "the FMU cannot serialize its state: that a refused call changes nothing is not checked, and its FMU-state functions are not called",
        );
    }
}

/// The time the random sequences may take: an FMU whose long steps are slow (a container FMU
/// steps its components at its internal step: a random step of 60 s is 60,000 of them) runs the
/// sequences that fit, and the pass is partial.
pub(super) const SEQUENCE_BUDGET_S: f64 = 20.0;
