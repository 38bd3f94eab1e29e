//! Random call sequences with random arguments through the C API of every packaged FMU
//! (proptest). A shadow model of the FMI 2.0 state machine predicts, for each call, whether it
//! is allowed and which state follows; the FMU must agree, and:
//! - never answer fmi2Fatal (a caught panic) or anything but OK/Warning/Discard/Error;
//! - refuse every call the state does not allow with fmi2Error and a message;
//! - change nothing when it answers fmi2Error (serialized FMU state compared byte for byte);
//! - refuse non-finite or non-positive step sizes, mismatched communication points, NULL
//!   FMU states and damaged serialized states;
//! - finish every call within 10 s (no hang);
//! - log only under declared categories, with "%s", to the right componentEnvironment.
//!
//! Cases: [`crate::random_sequences`] per FMU (`PROPTEST_CASES`, default 2000 sequences of up
//! to 99 calls: seconds per FMU), generated from the seed [`crate::seed`] (`$RUSTFMU_SEED`, else
//! drawn): each check records it in its report and in its failure message ([`crate::seed_note`]),
//! so that a failure in CI is repeated with `RUSTFMU_SEED=<seed>` and the same number of
//! sequences. A failing sequence is shrunk, printed, and then belongs in
//! `regressions_found_by_random_sequences` below.
//!
//! On another exporter's FMU the state machine is not read from the FMU (only this exporter's
//! serialized state shows it), serialized states are damaged only by truncation (bit flips may
//! be accepted by a format without checksum, and would then put the FMU in a state the shadow
//! cannot know), fmi2SetDebugLogging may answer anything for categories of this exporter, the
//! wording of refusals is not required, and calls of FMU-state functions the FMU does not
//! declare are left out.

#![allow(non_upper_case_globals)] // fmi2OK etc. are the standard's names, matched on

use crate::fmi2::*;
use crate::instance::{Args, Instance, status_name};
use crate::me::{MeState, needs_me};
use crate::outcome::{breadcrumb, info, limitation};
use crate::standard::allowed_states;
use crate::state::State;
use crate::{Fmu, Type, state};
use fmi_description::Causality;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestCaseError, TestRunner};
use std::ptr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

const SLOTS: usize = 3;

/// Coverage counters: calls made in each state, and calls answered fmi2OK in each state.
static CALLS: [AtomicUsize; 8] = [const { AtomicUsize::new(0) }; 8];
static OK_CALLS: [AtomicUsize; 8] = [const { AtomicUsize::new(0) }; 8];
static OK_STEPS: AtomicUsize = AtomicUsize::new(0);

/// A value reference: one of the FMU's variables (by index, modulo their number) or any number.
#[derive(Debug, Clone, Copy)]
enum Vr {
    Known(usize),
    Raw(u32),
}

/// When the communication point of a step is.
#[derive(Debug, Clone, Copy)]
enum When {
    /// The FMU's time, as the importer tracks it.
    Now,
    /// Off by round-off.
    NowTimes(f64),
    At(f64),
}

#[derive(Debug, Clone)]
enum Op {
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

fn vr() -> impl Strategy<Value = Vr> {
    prop_oneof![
        8 => (0..64usize).prop_map(Vr::Known),
        1 => any::<u32>().prop_map(Vr::Raw),
    ]
}

fn real() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -2.0..2.0f64,
        1 => Just(0.0),
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => any::<f64>(),
        1 => -1e-14..1e-14f64,
    ]
}

fn step_size() -> impl Strategy<Value = f64> {
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

fn op() -> impl Strategy<Value = Op> {
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
struct Shadow {
    state: State,
    time: f64,
    stop: Option<f64>,
    slots: [Option<(fmi2FMUstate, Snap)>; SLOTS],
    bytes: Option<(Vec<u8>, Snap)>,
}

/// What an FMU state holds that the shadow tracks.
#[derive(Debug, Clone, Copy)]
struct Snap {
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

const CATEGORIES: [&std::ffi::CStr; 9] = [
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

fn resolve(fmu: &Fmu, v: Vr) -> u32 {
    match v {
        Vr::Known(i) => fmu.md.variables[i % fmu.md.variables.len()].vr,
        Vr::Raw(r) => r,
    }
}

fn function_of(op: &Op) -> &'static str {
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

/// What the shadow knows about the answer of an allowed call, beyond the state machine.
enum Expect {
    Anything,
    /// The arguments are invalid whatever the FMU: it must refuse.
    Refused,
    /// A valid call that must succeed (fmi2OK; for a step also fmi2Discard).
    Succeeds,
}

/// Runs one call; returns its status, what the shadow expects of it, and the state that
/// follows if it succeeds.
fn call(inst: &mut Instance, sh: &mut Shadow, op: &Op) -> (fmi2Status, Expect, Option<State>) {
    let fmu = inst.fmu;
    let api = &fmu.api;
    let c = inst.c;
    let vrs_of = |v: &[Vr]| -> Vec<u32> { v.iter().map(|x| resolve(fmu, *x)).collect() };
    // SAFETY (for every call below): arrays have the lengths passed (or are NULL on purpose,
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
                let mut out = vec![0.0; v.len()];
                let p = if *null { ptr::null_mut() } else { out.as_mut_ptr() };
                let s = (api.get_real)(c, v.as_ptr(), v.len(), p);
                let bad = *null && !v.is_empty();
                (s, if bad { Expect::Refused } else { Expect::Anything }, None)
            }
            Op::GetInteger { vrs } => {
                let v = vrs_of(vrs);
                let mut out = vec![0; v.len()];
                (
                    (api.get_integer)(c, v.as_ptr(), v.len(), out.as_mut_ptr()),
                    Expect::Anything,
                    None,
                )
            }
            Op::GetBoolean { vrs } => {
                let v = vrs_of(vrs);
                let mut out = vec![0; v.len()];
                (
                    (api.get_boolean)(c, v.as_ptr(), v.len(), out.as_mut_ptr()),
                    Expect::Anything,
                    None,
                )
            }
            Op::GetString { vrs } => {
                let v = vrs_of(vrs);
                let mut out: Vec<fmi2String> = vec![ptr::null(); v.len()];
                (
                    (api.get_string)(c, v.as_ptr(), v.len(), out.as_mut_ptr()),
                    Expect::Anything,
                    None,
                )
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
                let s = (api.get_fmu_state)(c, &mut p);
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
                let s = (api.free_fmu_state)(c, &mut p);
                if s == fmi2OK {
                    assert!(p.is_null(), "fmi2FreeFMUstate left the pointer set");
                    sh.slots[*slot] = None;
                }
                (s, Expect::Succeeds, None)
            }
            Op::Serialize { slot } => match sh.slots[*slot] {
                Some((p, snap)) => {
                    let mut size = 0usize;
                    let s1 = (api.serialized_fmu_state_size)(c, p, &mut size);
                    if s1 != fmi2OK {
                        return (s1, Expect::Succeeds, None);
                    }
                    let mut buf = vec![0u8; size];
                    let s = (api.serialize_fmu_state)(c, p, buf.as_mut_ptr() as *mut fmi2Byte, size);
                    if s == fmi2OK {
                        sh.bytes = Some((buf, snap));
                    }
                    (s, Expect::Succeeds, None)
                }
                None => {
                    let mut size = 0usize;
                    (
                        (api.serialized_fmu_state_size)(c, ptr::null_mut(), &mut size),
                        Expect::Refused,
                        None,
                    )
                }
            },
            Op::Deserialize { to, damage, truncate } => {
                let damage = if fmu.own_state_format() { damage } else { &None };
                let Some((mut bytes, snap)) = sh.bytes.clone() else {
                    let mut p = ptr::null_mut();
                    let s = (api.deserialize_fmu_state)(c, ptr::null(), 8, &mut p);
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
                let s = (api.deserialize_fmu_state)(c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), &mut p);
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
                        let _ = (api.get_real_status)(c, fmi2LastSuccessfulTime, &mut lst);
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
                    0 => (api.get_status)(c, *kind, &mut 0),
                    1 => (api.get_real_status)(c, *kind, &mut 0.0),
                    2 => (api.get_integer_status)(c, *kind, &mut 0),
                    3 => (api.get_boolean_status)(c, *kind, &mut 0),
                    _ => (api.get_string_status)(c, *kind, &mut ptr::null()),
                };
                (s, Expect::Anything, None)
            }
            Op::DirectionalDerivative { n } => {
                let reals = fmu.md.vrs_of_type(Type::Real);
                let v = &reals[..(*n).min(reals.len())];
                let (dk, mut du) = (vec![1.0; v.len()], vec![0.0; v.len()]);
                let s = (api.get_directional_derivative)(
                    c,
                    v.as_ptr(),
                    v.len(),
                    v.as_ptr(),
                    v.len(),
                    dk.as_ptr(),
                    du.as_mut_ptr(),
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
                    (api.get_real_output_derivatives)(c, v.as_ptr(), *n, o.as_ptr(), x.as_mut_ptr()),
                    Expect::Anything,
                    None,
                )
            }
        }
    }
}

fn execute(fmu: &Fmu, logging_on: bool, ops: &[Op]) -> Result<(), TestCaseError> {
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
    let result = run_ops(&mut inst, &mut sh, ops);
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
fn declared(fmu: &Fmu, op: &Op) -> bool {
    match op {
        Op::GetState { .. } | Op::SetState { .. } | Op::FreeState { .. } => fmu.cs().can_get_and_set_fmu_state,
        Op::Serialize { .. } | Op::Deserialize { .. } => fmu.can_snapshot(),
        _ => true,
    }
}

fn run_ops(inst: &mut Instance, sh: &mut Shadow, ops: &[Op]) -> Result<(), TestCaseError> {
    let own = inst.fmu.own_state_format();
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
        breadcrumb(&format!(
            "random call {i} of a sequence: {op:?} in state {:?}",
            sh.state
        ));
        let clock = Instant::now();
        let (status, expect, next) = call(inst, sh, op);
        let took = clock.elapsed();
        let log = inst.log();
        CALLS[sh.state as usize].fetch_add(1, Ordering::Relaxed);
        if status == fmi2OK {
            OK_CALLS[sh.state as usize].fetch_add(1, Ordering::Relaxed);
            if function == "fmi2DoStep" {
                OK_STEPS.fetch_add(1, Ordering::Relaxed);
            }
        }
        let at = format!("op {i} {op:?} in {:?}", sh.state);
        prop_assert!(took < Duration::from_secs(10), "{}: took {:?}", at, took);
        prop_assert!(
            matches!(status, fmi2OK | fmi2Warning | fmi2Discard | fmi2Error),
            "{}: answered {} ({}); log {:?}",
            at,
            status_name(status),
            status,
            log
        );
        if status != fmi2OK {
            prop_assert!(
                log.iter().any(|e| e.status == status),
                "{}: {} without a message; log {:?}",
                at,
                status_name(status),
                log
            );
        }
        if !allowed {
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
        } else {
            match expect {
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
            if snapshots {
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
fn note_limitations(fmu: &Fmu) {
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

/// The runner's configuration: [`crate::random_sequences`] cases, the RNG seeded from
/// [`crate::seed`] (`$RUSTFMU_SEED`, else drawn once per process and printed).
fn config() -> Config {
    let cases = crate::random_sequences();
    crate::seeded(Config {
        cases,
        max_shrink_iters: 4096,
        failure_persistence: None,
        ..Config::default()
    })
}

/// The time the random sequences may take: an FMU whose long steps are slow (a container FMU
/// steps its components at its internal step: a random step of 60 s is 60,000 of them) runs the
/// sequences that fit, and the pass is partial.
const SEQUENCE_BUDGET_S: f64 = 20.0;

pub fn random_call_sequences_keep_every_fmu_conformant(fmu: &Fmu) {
    // First, so that the report shows the seed whatever happens next.
    info(crate::seed_note());
    note_limitations(fmu);
    let clock = Instant::now();
    let mut runner = TestRunner::new(config());
    let strategy = (any::<bool>(), prop::collection::vec(op(), 1..100));
    let ran = AtomicUsize::new(0);
    let result = runner.run(&strategy, |(logging_on, ops)| {
        if clock.elapsed().as_secs_f64() > SEQUENCE_BUDGET_S {
            return Ok(());
        }
        ran.fetch_add(1, Ordering::Relaxed);
        execute(fmu, logging_on, &ops)
    });
    if let Err(e) = result {
        panic!("{}: {e}\n{}", fmu.id, crate::seed_note());
    }
    let ran = ran.into_inner();
    if ran < config().cases as usize {
        limitation(format!(
            "{ran} of {} random sequences ran in the {SEQUENCE_BUDGET_S} s budget (the FMU's long steps are slow)",
            config().cases
        ));
    }
    let counts = |c: &[AtomicUsize; 8]| -> Vec<usize> { c.iter().map(|x| x.swap(0, Ordering::Relaxed)).collect() };
    let (calls, ok) = (counts(&CALLS), counts(&OK_CALLS));
    info(format!(
        "{} random sequences in {:.1} s; calls per state {:?}: {:?}, of which fmi2OK {:?}; {} steps done",
        config().cases,
        clock.elapsed().as_secs_f64(),
        state::STATES,
        calls,
        ok,
        OK_STEPS.swap(0, Ordering::Relaxed)
    ));
    // The sequences must reach the states where the interesting calls are allowed.
    for s in [
        State::Instantiated,
        State::InitializationMode,
        State::StepComplete,
        State::Terminated,
    ] {
        assert!(
            calls[s as usize] > 0,
            "{}: no random call was made in {s:?}\n{}",
            fmu.id,
            crate::seed_note()
        );
    }
}

/// Sequences that failed once (found by the random run above, shrunk by proptest), kept as
/// tests of their own for every FMU.
pub fn regressions_found_by_random_sequences(fmu: &Fmu) {
    note_limitations(fmu);
    let init = [
        Op::Setup {
            tolerance: None,
            start: 0.0,
            stop: None,
        },
        Op::EnterInit,
    ];
    let mut cases: Vec<(&str, Vec<Op>)> = vec![
        (
            // fmi2GetReal of an unknown reference in initialization mode answered fmi2Error
            // after it had already run the model's initialization (the FMU state changed).
            "unknown reference read in initialization mode",
            [
                &init[..],
                &[Op::GetReal {
                    vrs: vec![Vr::Raw(u32::MAX)],
                    null: false,
                }],
            ]
            .concat(),
        ),
        (
            // At t = 0 a step of 1e9 s accepted a communication point 5 s off: the tolerance
            // scaled with the step size.
            "a huge step from a wrong communication point",
            [
                &init[..],
                &[
                    Op::ExitInit,
                    Op::DoStep {
                        when: When::At(5.0),
                        h: 1e9,
                    },
                ],
            ]
            .concat(),
        ),
    ];
    let vars = &fmu.md.variables;
    if let (Some(b), Some(r)) = (
        vars.iter().position(|v| v.ty == Type::Boolean),
        vars.iter().position(|v| v.ty == Type::Real),
    ) {
        // fmi2GetBoolean of a Boolean then a Real in initialization mode: one reference at
        // a time, the first one initialized the model before the second was refused.
        cases.push((
            "a Boolean and a Real read as Booleans in initialization mode",
            [
                &init[..],
                &[Op::GetBoolean {
                    vrs: vec![Vr::Known(b), Vr::Known(r)],
                }],
            ]
            .concat(),
        ));
    }
    for (what, ops) in &cases {
        for logging_on in [false, true] {
            if let Err(e) = execute(fmu, logging_on, ops) {
                panic!("{}: {what}: {e}", fmu.id);
            }
        }
    }
    // Issue 49: on BouncingBall, g = -2.249e194 (a Real parameter without bounds, as in the
    // Reference FMUs) and one fmi2DoStep(0, 0.0044) took 14-32 s, answered fmi2Discard ("more
    // than 100000 events in one step") and left h = -3.8e168 and v = -5.8e181 behind. Not of any
    // FMU (what a huge value of some parameter means is the model's business): of each one with a
    // Real parameter named g. It asserts behaviour, not time.
    if let Some(g) = fmu
        .md
        .variables
        .iter()
        .find(|v| v.name == "g" && v.ty == Type::Real && v.causality == Causality::Parameter)
    {
        for logging_on in [false, true] {
            if let Err(e) = huge_g_then_a_step(fmu, g, logging_on) {
                panic!(
                    "{}: g = {HUGE_G:e}, then fmi2DoStep(0, {HUGE_G_STEP}) (logging {}): {e}",
                    fmu.id,
                    if logging_on { "on" } else { "off" }
                );
            }
        }
    }
}

/// The value of g and the step of [`huge_g_then_a_step`] (issue 49).
const HUGE_G: f64 = -2.249e194;
const HUGE_G_STEP: f64 = 0.0044;

/// A co-simulation instance, `g` set to [`HUGE_G`] in Instantiated (where the standard lets a
/// parameter be set), initialized, then `fmi2DoStep(0, HUGE_G_STEP)`. The FMU may refuse the
/// value where a declared bound excludes it (at the setter), or refuse it at
/// fmi2ExitInitializationMode with fmi2Error and a message (the model's initialization finds it
/// meaningless); either is a pass. Otherwise the step must return fmi2OK or fmi2Discard, every
/// Real must be finite afterwards, and after fmi2Discard `fmi2LastSuccessfulTime` is a time t in
/// [0, HUGE_G_STEP] and the variables are those of t: the same bits as before the step for t =
/// 0, the independent variable t, and close (a relative 1e-3: integrators differ) to those of
/// a fresh instance stepped from 0 to t where that step answers fmi2OK.
fn huge_g_then_a_step(fmu: &Fmu, g: &crate::Variable, logging_on: bool) -> Result<(), String> {
    let args = Args {
        logging_on,
        ..Args::valid(fmu)
    };
    let initialized = |set_g: bool| -> Result<Option<Instance>, String> {
        let mut inst = Instance::with(fmu, &args).map_err(|log| format!("fmi2Instantiate refused: {log:?}"))?;
        if set_g {
            let s = inst.set_real(&[g.vr], &[HUGE_G]);
            let log = inst.log_text();
            let outside = g.min.is_some_and(|lo| HUGE_G < lo) || g.max.is_some_and(|hi| HUGE_G > hi);
            match s {
                fmi2OK | fmi2Warning => {}
                fmi2Error if outside => return Ok(None),
                _ => {
                    return Err(format!(
                        "fmi2SetReal in Instantiated answered {} although g declares no bound that excludes it; log: {log}",
                        status_name(s)
                    ));
                }
            }
        }
        let s = [inst.setup(0.0, None), inst.enter_init()];
        if s != [fmi2OK; 2] {
            return Err(format!(
                "fmi2SetupExperiment, fmi2EnterInitializationMode answered {:?}; log: {}",
                s.map(status_name),
                inst.log_text()
            ));
        }
        let s = inst.exit_init();
        let log = inst.log();
        match s {
            fmi2OK | fmi2Warning => Ok(Some(inst)),
            fmi2Error if set_g && log.iter().any(|e| e.status == fmi2Error) => Ok(None),
            _ => Err(format!(
                "fmi2ExitInitializationMode answered {}; log: {log:?}",
                status_name(s)
            )),
        }
    };
    let Some(mut inst) = initialized(true)? else {
        return Ok(());
    };
    let reals = fmu.md.vrs_of_type(Type::Real);
    let (s, before) = inst.get_real(&reals);
    if s != fmi2OK {
        return Err(format!(
            "fmi2GetReal of every Real after initialization answered {}; log: {}",
            status_name(s),
            inst.log_text()
        ));
    }
    let step = inst.do_step(0.0, HUGE_G_STEP);
    // (Its end: a step that handles events one by one may log each of them.)
    let log = inst.log_text();
    let log = match log.char_indices().rev().nth(2000) {
        Some((i, _)) => format!("...{}", &log[i..]),
        None => log,
    };
    if !matches!(step, fmi2OK | fmi2Discard) {
        return Err(format!(
            "the step answered {}, not fmi2OK or fmi2Discard; log: {log}",
            status_name(step)
        ));
    }
    let (s, after) = inst.get_real(&reals);
    if s != fmi2OK {
        return Err(format!(
            "after the step answered {}, fmi2GetReal of every Real answered {}; log: {}",
            status_name(step),
            status_name(s),
            inst.log_text()
        ));
    }
    let name = |vr: u32| {
        fmu.md
            .variables
            .iter()
            .find(|v| v.ty == Type::Real && v.vr == vr)
            .map_or("?", |v| v.name.as_str())
    };
    let not_finite: Vec<String> = reals
        .iter()
        .zip(&after)
        .filter(|(_, x)| !x.is_finite())
        .map(|(vr, x)| format!("{} = {x}", name(*vr)))
        .collect();
    if !not_finite.is_empty() {
        return Err(format!(
            "after the step answered {}, not finite: {}; step's log: {log}",
            status_name(step),
            not_finite.join(", ")
        ));
    }
    if step == fmi2OK {
        return Ok(());
    }
    let (s, t) = inst.last_successful_time();
    if s != fmi2OK || !(0.0..=HUGE_G_STEP).contains(&t) {
        return Err(format!(
            "after fmi2Discard, fmi2GetRealStatus(fmi2LastSuccessfulTime) answered {} and {t}, not a time in [0, {HUGE_G_STEP}]; step's log: {log}",
            status_name(s)
        ));
    }
    let independent = fmu
        .md
        .variables
        .iter()
        .find(|v| v.ty == Type::Real && v.causality == Causality::Independent);
    // The variables of time t: at t = 0 those before the step, bit for bit; later ones compared
    // with a fresh instance stepped from 0 to t.
    let expected = if t == 0.0 {
        Some((before, true))
    } else {
        let mut fresh = initialized(true)?.ok_or("a fresh instance refused what the first accepted")?;
        match (fresh.do_step(0.0, t), fresh.get_real(&reals)) {
            (fmi2OK, (fmi2OK, x)) => Some((x, false)),
            _ => None,
        }
    };
    let wrong: Vec<String> = reals
        .iter()
        .enumerate()
        .filter_map(|(i, vr)| {
            let x = after[i];
            let want = match (&expected, independent) {
                (_, Some(v)) if v.vr == *vr => t,
                (Some((e, _)), _) => e[i],
                (None, _) => return None,
            };
            let exact = expected.as_ref().is_some_and(|e| e.1) || independent.is_some_and(|v| v.vr == *vr);
            let close = if exact {
                x.to_bits() == want.to_bits()
            } else {
                (x - want).abs() <= 1e-3 * x.abs().max(want.abs()) + 1e-9
            };
            (!close).then(|| format!("{} = {x:e}, at t = {t:e} {want:e}", name(*vr)))
        })
        .collect();
    if !wrong.is_empty() {
        return Err(format!(
            "after fmi2Discard (fmi2LastSuccessfulTime {t:e}) the variables are not those of that time: {}; step's log: {log}",
            wrong.join(", ")
        ));
    }
    Ok(())
}

// ---- model exchange ------------------------------------------------------------------------

/// A call of a model-exchange instance (the common functions and the model-exchange ones, and
/// a co-simulation one, which must always be refused).
#[derive(Debug, Clone)]
enum MeOp {
    SetDebugLogging {
        on: bool,
    },
    Setup {
        start: f64,
    },
    EnterInit,
    ExitInit,
    Terminate,
    Reset,
    GetReal {
        vrs: Vec<Vr>,
        null: bool,
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
    GetState {
        slot: usize,
    },
    SetState {
        slot: usize,
    },
    FreeState {
        slot: usize,
    },
    /// Serializes the state in the slot and deserializes it (truncated: must be refused).
    Reserialize {
        slot: usize,
        truncate: Option<usize>,
    },
    EnterEventMode,
    NewDiscreteStates {
        null: bool,
    },
    EnterContinuousTimeMode,
    CompletedIntegratorStep {
        null: bool,
    },
    /// fmi2SetTime(time + dt).
    SetTime {
        dt: f64,
    },
    /// fmi2SetContinuousStates of the current states moved by `dx`, with nx + `dn` values.
    SetContinuousStates {
        dx: f64,
        dn: i8,
        null: bool,
    },
    /// 0 states, 1 derivatives, 2 event indicators, 3 nominals; n + `dn` values.
    GetVector {
        which: u8,
        dn: i8,
        null: bool,
    },
    DoStep,
    DirectionalDerivative,
}

fn me_op() -> impl Strategy<Value = MeOp> {
    let slot = 0..SLOTS;
    let dn = prop_oneof![8 => Just(0i8), 1 => Just(1i8), 1 => Just(-1i8)];
    prop_oneof![
        1 => any::<bool>().prop_map(|on| MeOp::SetDebugLogging { on }),
        2 => prop_oneof![4 => Just(0.0), 1 => real()].prop_map(|start| MeOp::Setup { start }),
        3 => Just(MeOp::EnterInit),
        3 => Just(MeOp::ExitInit),
        1 => Just(MeOp::Terminate),
        1 => Just(MeOp::Reset),
        2 => (prop::collection::vec(vr(), 0..4), prop::bool::weighted(0.05)).prop_map(|(vrs, null)| MeOp::GetReal { vrs, null }),
        3 => (prop::collection::vec((vr(), real()), 0..3), prop::bool::weighted(0.05)).prop_map(|(values, null)| MeOp::SetReal { values, null }),
        1 => prop::collection::vec((vr(), any::<i32>()), 0..2).prop_map(|values| MeOp::SetInteger { values }),
        1 => prop::collection::vec((vr(), 0..2i32), 0..2).prop_map(|values| MeOp::SetBoolean { values }),
        2 => slot.clone().prop_map(|slot| MeOp::GetState { slot }),
        2 => slot.clone().prop_map(|slot| MeOp::SetState { slot }),
        1 => slot.clone().prop_map(|slot| MeOp::FreeState { slot }),
        1 => (slot, prop::option::of(any::<usize>())).prop_map(|(slot, truncate)| MeOp::Reserialize { slot, truncate }),
        3 => Just(MeOp::EnterEventMode),
        3 => prop::bool::weighted(0.1).prop_map(|null| MeOp::NewDiscreteStates { null }),
        4 => Just(MeOp::EnterContinuousTimeMode),
        4 => prop::bool::weighted(0.1).prop_map(|null| MeOp::CompletedIntegratorStep { null }),
        4 => prop_oneof![8 => 0.0..0.01f64, 1 => real()].prop_map(|dt| MeOp::SetTime { dt }),
        5 => (prop_oneof![6 => -0.1..0.1f64, 1 => real()], dn.clone(), prop::bool::weighted(0.05))
            .prop_map(|(dx, dn, null)| MeOp::SetContinuousStates { dx, dn, null }),
        5 => (0..4u8, dn, prop::bool::weighted(0.05)).prop_map(|(which, dn, null)| MeOp::GetVector { which, dn, null }),
        1 => Just(MeOp::DoStep),
        1 => Just(MeOp::DirectionalDerivative),
    ]
}

fn me_function_of(op: &MeOp) -> &'static str {
    match op {
        MeOp::SetDebugLogging { .. } => "fmi2SetDebugLogging",
        MeOp::Setup { .. } => "fmi2SetupExperiment",
        MeOp::EnterInit => "fmi2EnterInitializationMode",
        MeOp::ExitInit => "fmi2ExitInitializationMode",
        MeOp::Terminate => "fmi2Terminate",
        MeOp::Reset => "fmi2Reset",
        MeOp::GetReal { .. } => "fmi2GetReal",
        MeOp::SetReal { .. } => "fmi2SetReal",
        MeOp::SetInteger { .. } => "fmi2SetInteger",
        MeOp::SetBoolean { .. } => "fmi2SetBoolean",
        MeOp::GetState { .. } => "fmi2GetFMUstate",
        MeOp::SetState { .. } => "fmi2SetFMUstate",
        MeOp::FreeState { .. } => "fmi2FreeFMUstate",
        MeOp::Reserialize { .. } => "fmi2SerializeFMUstate",
        MeOp::EnterEventMode => "fmi2EnterEventMode",
        MeOp::NewDiscreteStates { .. } => "fmi2NewDiscreteStates",
        MeOp::EnterContinuousTimeMode => "fmi2EnterContinuousTimeMode",
        MeOp::CompletedIntegratorStep { .. } => "fmi2CompletedIntegratorStep",
        MeOp::SetTime { .. } => "fmi2SetTime",
        MeOp::SetContinuousStates { .. } => "fmi2SetContinuousStates",
        MeOp::GetVector { which, .. } => [
            "fmi2GetContinuousStates",
            "fmi2GetDerivatives",
            "fmi2GetEventIndicators",
            "fmi2GetNominalsOfContinuousStates",
        ][*which as usize],
        MeOp::DoStep => "fmi2DoStep",
        MeOp::DirectionalDerivative => "fmi2GetDirectionalDerivative",
    }
}

/// The shadow of a model-exchange instance: its state, its time (as the importer set it), and
/// the FMU states the importer holds, with the state and time each was taken in.
struct MeShadow {
    state: MeState,
    time: f64,
    slots: [Option<(fmi2FMUstate, MeState, f64)>; SLOTS],
}

/// Runs one model-exchange call: its status, what the shadow expects, the state after success.
fn me_call(inst: &mut Instance, sh: &mut MeShadow, op: &MeOp) -> (fmi2Status, Expect, Option<MeState>) {
    let fmu = inst.fmu;
    let api = &fmu.api;
    let me = fmu.api.me.as_ref().expect("model-exchange functions");
    let c = inst.c;
    let nx = fmu.md.number_of_continuous_states();
    let ni = fmu.md.number_of_event_indicators;
    let resize = |n: usize, dn: i8| (n as isize + dn as isize).max(0) as usize;
    // SAFETY (for every call below): arrays have the lengths passed (or are NULL on purpose,
    // which the FMU must refuse), FMU states are ones this FMU handed out and not yet freed.
    unsafe {
        match op {
            MeOp::SetDebugLogging { on } => (
                (api.set_debug_logging)(c, *on as i32, 0, ptr::null()),
                Expect::Succeeds,
                None,
            ),
            MeOp::Setup { start } => {
                let s = (api.setup_experiment)(c, 0, 0.0, *start, 0, 0.0);
                if s == fmi2OK {
                    sh.time = *start;
                }
                (
                    s,
                    if start.is_finite() {
                        Expect::Succeeds
                    } else {
                        Expect::Refused
                    },
                    None,
                )
            }
            MeOp::EnterInit => (
                (api.enter_initialization_mode)(c),
                Expect::Succeeds,
                Some(MeState::InitializationMode),
            ),
            MeOp::ExitInit => (
                (api.exit_initialization_mode)(c),
                Expect::Anything,
                Some(MeState::EventMode),
            ),
            MeOp::Terminate => ((api.terminate)(c), Expect::Succeeds, Some(MeState::Terminated)),
            MeOp::Reset => {
                let s = (api.reset)(c);
                if s == fmi2OK {
                    sh.time = 0.0;
                }
                (s, Expect::Succeeds, Some(MeState::Instantiated))
            }
            MeOp::GetReal { vrs, null } => {
                let v: Vec<u32> = vrs.iter().map(|x| resolve(fmu, *x)).collect();
                let mut out = vec![0.0; v.len()];
                let p = if *null { ptr::null_mut() } else { out.as_mut_ptr() };
                let s = (api.get_real)(c, v.as_ptr(), v.len(), p);
                (
                    s,
                    if *null && !v.is_empty() {
                        Expect::Refused
                    } else {
                        Expect::Anything
                    },
                    None,
                )
            }
            MeOp::SetReal { values, null } => {
                let v: Vec<u32> = values.iter().map(|(x, _)| resolve(fmu, *x)).collect();
                let x: Vec<f64> = values.iter().map(|(_, x)| *x).collect();
                let p = if *null { ptr::null() } else { x.as_ptr() };
                let s = (api.set_real)(c, v.as_ptr(), v.len(), p);
                let bad = (*null && !v.is_empty()) || x.iter().any(|x| !x.is_finite());
                (s, if bad { Expect::Refused } else { Expect::Anything }, None)
            }
            MeOp::SetInteger { values } => {
                let v: Vec<u32> = values.iter().map(|(x, _)| resolve(fmu, *x)).collect();
                let x: Vec<i32> = values.iter().map(|(_, x)| *x).collect();
                (
                    (api.set_integer)(c, v.as_ptr(), v.len(), x.as_ptr()),
                    Expect::Anything,
                    None,
                )
            }
            MeOp::SetBoolean { values } => {
                let v: Vec<u32> = values.iter().map(|(x, _)| resolve(fmu, *x)).collect();
                let x: Vec<i32> = values.iter().map(|(_, x)| *x).collect();
                (
                    (api.set_boolean)(c, v.as_ptr(), v.len(), x.as_ptr()),
                    Expect::Anything,
                    None,
                )
            }
            MeOp::GetState { slot } => {
                let mut p = sh.slots[*slot].map_or(ptr::null_mut(), |s| s.0);
                let s = (api.get_fmu_state)(c, &mut p);
                if s == fmi2OK {
                    sh.slots[*slot] = Some((p, sh.state, sh.time));
                }
                (s, Expect::Succeeds, None)
            }
            MeOp::SetState { slot } => match sh.slots[*slot] {
                Some((p, state, time)) => {
                    let s = (api.set_fmu_state)(c, p);
                    if s == fmi2OK {
                        sh.time = time;
                    }
                    (s, Expect::Succeeds, Some(state))
                }
                None => ((api.set_fmu_state)(c, ptr::null_mut()), Expect::Refused, None),
            },
            MeOp::FreeState { slot } => {
                let mut p = sh.slots[*slot].map_or(ptr::null_mut(), |s| s.0);
                let s = (api.free_fmu_state)(c, &mut p);
                if s == fmi2OK {
                    assert!(p.is_null(), "fmi2FreeFMUstate left the pointer set");
                    sh.slots[*slot] = None;
                }
                (s, Expect::Succeeds, None)
            }
            MeOp::Reserialize { slot, truncate } => {
                let Some((p, _, _)) = sh.slots[*slot] else {
                    let mut size = 0usize;
                    return (
                        (api.serialized_fmu_state_size)(c, ptr::null_mut(), &mut size),
                        Expect::Refused,
                        None,
                    );
                };
                let mut size = 0usize;
                let s = (api.serialized_fmu_state_size)(c, p, &mut size);
                if s != fmi2OK {
                    return (s, Expect::Succeeds, None);
                }
                let mut buf = vec![0u8; size];
                let s = (api.serialize_fmu_state)(c, p, buf.as_mut_ptr() as *mut fmi2Byte, size);
                if s != fmi2OK {
                    return (s, Expect::Succeeds, None);
                }
                let cut = truncate.map(|n| n % (size + 1)).filter(|n| *n < size);
                if let Some(n) = cut {
                    buf.truncate(n);
                }
                let mut q = ptr::null_mut();
                let s = (api.deserialize_fmu_state)(c, buf.as_ptr() as *const fmi2Byte, buf.len(), &mut q);
                if s == fmi2OK {
                    let _ = (api.free_fmu_state)(c, &mut q);
                }
                (
                    s,
                    if cut.is_some() {
                        Expect::Refused
                    } else {
                        Expect::Succeeds
                    },
                    None,
                )
            }
            MeOp::EnterEventMode => ((me.enter_event_mode)(c), Expect::Succeeds, Some(MeState::EventMode)),
            MeOp::NewDiscreteStates { null } => {
                let mut info = fmi2EventInfo {
                    newDiscreteStatesNeeded: 0,
                    terminateSimulation: 0,
                    nominalsOfContinuousStatesChanged: 0,
                    valuesOfContinuousStatesChanged: 0,
                    nextEventTimeDefined: 0,
                    nextEventTime: 0.0,
                };
                let p = if *null {
                    ptr::null_mut()
                } else {
                    &mut info as *mut fmi2EventInfo
                };
                let s = (me.new_discrete_states)(c, p);
                // Valid: the model may still fail (random parameters).
                (s, if *null { Expect::Refused } else { Expect::Anything }, None)
            }
            MeOp::EnterContinuousTimeMode => (
                (me.enter_continuous_time_mode)(c),
                Expect::Succeeds,
                Some(MeState::ContinuousTimeMode),
            ),
            MeOp::CompletedIntegratorStep { null } => {
                let (mut a, mut b) = (0, 0);
                let p = if *null {
                    ptr::null_mut()
                } else {
                    &mut a as *mut fmi2Boolean
                };
                let s = (me.completed_integrator_step)(c, fmi2False, p, &mut b);
                (s, if *null { Expect::Refused } else { Expect::Anything }, None)
            }
            MeOp::SetTime { dt } => {
                let t = sh.time + dt;
                let s = (me.set_time)(c, t);
                if s == fmi2OK {
                    sh.time = t;
                }
                // Going back in time: the standard does not say, the FMU may refuse.
                let expect = if !t.is_finite() {
                    Expect::Refused
                } else if *dt >= 0.0 {
                    Expect::Succeeds
                } else {
                    Expect::Anything
                };
                (s, expect, None)
            }
            MeOp::SetContinuousStates { dx, dn, null } => {
                // The start values of the states, moved by dx (not the states read from the
                // FMU: a read in InitializationMode may compute, and change the FMU state).
                let x: Vec<f64> = match fmu.md.continuous_states() {
                    Ok(states) => states.iter().map(|(v, _)| v.start_real().unwrap_or(0.0)).collect(),
                    Err(_) => vec![0.0; nx],
                };
                let n = resize(nx, *dn);
                let y: Vec<f64> = (0..n).map(|i| x.get(i).copied().unwrap_or(0.0) + dx).collect();
                let p = if *null { ptr::null() } else { y.as_ptr() };
                let s = (me.set_continuous_states)(c, p, n);
                let bad = n != nx || (*null && n > 0) || (n > 0 && !dx.is_finite());
                (s, if bad { Expect::Refused } else { Expect::Anything }, None)
            }
            MeOp::GetVector { which, dn, null } => {
                let (f, n) = match which {
                    0 => (me.get_continuous_states, nx),
                    1 => (me.get_derivatives, nx),
                    2 => (me.get_event_indicators, ni),
                    _ => (me.get_nominals_of_continuous_states, nx),
                };
                let m = resize(n, *dn);
                let mut v = vec![0.0; m];
                let p = if *null { ptr::null_mut() } else { v.as_mut_ptr() };
                let s = f(c, p, m);
                let bad = m != n || (*null && m > 0);
                // Valid: the model may still fail to compute (random parameters).
                (s, if bad { Expect::Refused } else { Expect::Anything }, None)
            }
            MeOp::DoStep => ((api.do_step)(c, sh.time, 1e-3, fmi2False), Expect::Refused, None),
            MeOp::DirectionalDerivative => {
                let (unknowns, knowns) = super::directional_derivatives::valid_pair(fmu, true);
                let (s, _) = super::directional_derivatives::call(inst, &unknowns, &knowns);
                (s, Expect::Anything, None)
            }
        }
    }
}

fn me_declared(fmu: &Fmu, op: &MeOp) -> bool {
    let md = fmu.md.me.as_ref();
    match op {
        MeOp::GetState { .. } | MeOp::SetState { .. } | MeOp::FreeState { .. } => {
            md.is_some_and(|m| m.can_get_and_set_fmu_state)
        }
        MeOp::Reserialize { .. } => crate::me::can_snapshot_me(fmu),
        _ => true,
    }
}

static ME_CALLS: [AtomicUsize; 7] = [const { AtomicUsize::new(0) }; 7];

fn me_execute(fmu: &Fmu, ops: &[MeOp]) -> Result<(), TestCaseError> {
    let args = Args {
        fmu_type: fmi2ModelExchange,
        ..Args::valid(fmu)
    };
    let mut inst = Instance::with(fmu, &args).map_err(|log| TestCaseError::fail(format!("instantiate: {log:?}")))?;
    let mut sh = MeShadow {
        state: MeState::Instantiated,
        time: 0.0,
        slots: [None; SLOTS],
    };
    let result = me_run_ops(&mut inst, &mut sh, ops);
    for slot in sh.slots.iter_mut() {
        if let Some((mut p, _, _)) = slot.take() {
            let _ = inst.free_state(&mut p);
        }
    }
    inst.log();
    result
}

fn me_run_ops(inst: &mut Instance, sh: &mut MeShadow, ops: &[MeOp]) -> Result<(), TestCaseError> {
    let observed = inst.fmu.me_state_codes().is_ok();
    let snapshots = crate::me::can_snapshot_me(inst.fmu);
    let own = inst.fmu.own_state_format();
    for (i, op) in ops.iter().enumerate() {
        if !me_declared(inst.fmu, op) {
            continue;
        }
        let function = me_function_of(op);
        let allowed = crate::me::allowed_states(function).contains(&sh.state);
        let before = if snapshots { inst.snapshot() } else { vec![] };
        breadcrumb(&format!("random model-exchange call {i}: {op:?} in {:?}", sh.state));
        let clock = Instant::now();
        let (status, expect, next) = me_call(inst, sh, op);
        let took = clock.elapsed();
        let log = inst.log();
        ME_CALLS[sh.state as usize].fetch_add(1, Ordering::Relaxed);
        let at = format!("op {i} {op:?} in {:?}", sh.state);
        prop_assert!(took < Duration::from_secs(10), "{}: took {:?}", at, took);
        prop_assert!(
            matches!(status, fmi2OK | fmi2Warning | fmi2Discard | fmi2Error),
            "{}: answered {} ({}); log {:?}",
            at,
            status_name(status),
            status,
            log
        );
        if status != fmi2OK {
            prop_assert!(
                log.iter().any(|e| e.status == status),
                "{}: {} without a message; log {:?}",
                at,
                status_name(status),
                log
            );
        }
        if !allowed {
            prop_assert_eq!(
                status,
                fmi2Error,
                "{}: not allowed but answered {}; log {:?}",
                at,
                status_name(status),
                log
            );
            prop_assert!(
                !own || log.iter().any(|e| e.status == fmi2Error && e.text.contains(function)),
                "{}: refused without naming the function: {:?}",
                at,
                log
            );
        } else {
            match expect {
                Expect::Refused => {
                    prop_assert_eq!(status, fmi2Error, "{}: invalid arguments accepted; log {:?}", at, log)
                }
                Expect::Succeeds => prop_assert!(
                    status == fmi2OK,
                    "{}: a valid call answered {}: {:?}",
                    at,
                    status_name(status),
                    log
                ),
                Expect::Anything => {}
            }
        }
        if status == fmi2Error {
            if snapshots {
                prop_assert!(
                    inst.snapshot() == before,
                    "{}: answered fmi2Error but changed the FMU state",
                    at
                );
            }
        } else if allowed && let Some(next) = next {
            sh.state = next;
        }
        if observed {
            let now = inst.me_state();
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

pub fn random_model_exchange_call_sequences_keep_every_fmu_conformant(fmu: &Fmu) {
    needs_me(fmu);
    if fmu.me_state_codes().is_err() {
        limitation(
            "the state machine is not read from the FMU after each call (only this exporter's serialized state shows it)",
        );
    }
    if !crate::me::can_snapshot_me(fmu) {
        limitation(
            "<ModelExchange> does not declare canGetAndSetFMUstate and canSerializeFMUstate: that a refused call changes nothing is not checked",
        );
    }
    info(crate::seed_note());
    let clock = Instant::now();
    let mut runner = TestRunner::new(config());
    let strategy = prop::collection::vec(me_op(), 1..100);
    if let Err(e) = runner.run(&strategy, |ops| me_execute(fmu, &ops)) {
        panic!("{}: {e}\n{}", fmu.id, crate::seed_note());
    }
    let calls: Vec<usize> = ME_CALLS.iter().map(|x| x.swap(0, Ordering::Relaxed)).collect();
    info(format!(
        "{} random model-exchange sequences in {:.1} s; calls per state {:?}: {:?}",
        config().cases,
        clock.elapsed().as_secs_f64(),
        crate::me::ME_STATES,
        calls
    ));
    for s in crate::me::ME_REACHABLE {
        assert!(
            calls[s as usize] > 0,
            "{}: no random call was made in {s:?}\n{}",
            fmu.id,
            crate::seed_note()
        );
    }
}
