//! Random model-exchange call sequences: the calls ([`MeOp`]), the shadow of the
//! model-exchange state machine (the check that runs them: [`super::checks`]).

use super::co_simulation::{Hook, answered, expected_of};
use super::{Expect, SLOTS, Vr, real, resolve, vr};
use crate::Fmu;
use crate::fmi2::*;
use crate::guard::{GETTER_RULE2, Guarded, STATE_RULE2};
use crate::instance::{Args, Instance, status_name};
use crate::me::MeState;
use crate::outcome::breadcrumb;
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;
use std::ptr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// A call of a model-exchange instance (the common functions and the model-exchange ones, and
/// a co-simulation one, which must always be refused).
#[derive(Debug, Clone)]
pub(super) enum MeOp {
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

pub(super) fn me_op() -> impl Strategy<Value = MeOp> {
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

pub(super) fn me_function_of(op: &MeOp) -> &'static str {
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
pub(super) struct MeShadow {
    state: MeState,
    time: f64,
    slots: [Option<(fmi2FMUstate, MeState, f64)>; SLOTS],
}

/// Runs one model-exchange call: its status, what the shadow expects, the state after success.
// One arm per kind of call: kept whole, over ~150 lines, so that what the shadow expects of each
// call sits beside the call itself.
pub(super) fn me_call(inst: &mut Instance, sh: &mut MeShadow, op: &MeOp) -> (fmi2Status, Expect, Option<MeState>) {
    let fmu = inst.fmu;
    let api = &fmu.api;
    let me = fmu.api.me.as_ref().expect("model-exchange functions");
    let c = inst.c;
    let nx = fmu.md.number_of_continuous_states();
    let ni = fmu.md.number_of_event_indicators;
    let resize = |n: usize, dn: i8| (n as isize + dn as isize).max(0) as usize;
    // SAFETY: for every call below, arrays have the lengths passed (or are NULL on purpose,
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
                let mut out = Guarded::new(v.len(), 0.0);
                let p = if *null { ptr::null_mut() } else { out.as_mut_ptr() };
                let s = (api.get_real)(c, v.as_ptr(), v.len(), p);
                out.into_values(|| format!("fmi2GetReal with nvr = {}", v.len()), GETTER_RULE2);
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
            // fmi2Integer and fmi2Boolean are both C ints: one arm, the op's setter.
            MeOp::SetInteger { values } | MeOp::SetBoolean { values } => {
                let set = match op {
                    MeOp::SetInteger { .. } => api.set_integer,
                    _ => api.set_boolean,
                };
                let v: Vec<u32> = values.iter().map(|(x, _)| resolve(fmu, *x)).collect();
                let x: Vec<i32> = values.iter().map(|(_, x)| *x).collect();
                (set(c, v.as_ptr(), v.len(), x.as_ptr()), Expect::Anything, None)
            }
            MeOp::GetState { slot } => {
                let mut p = sh.slots[*slot].map_or(ptr::null_mut(), |s| s.0);
                let s = crate::guard::fill_state2(&mut p, "fmi2GetFMUstate", |q| (api.get_fmu_state)(c, q));
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
                let s = crate::guard::fill_state2(&mut p, "fmi2FreeFMUstate", |q| (api.free_fmu_state)(c, q));
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
                        crate::guard::fill_state_size2(&mut size, "fmi2SerializedFMUstateSize", |p| {
                            (api.serialized_fmu_state_size)(c, ptr::null_mut(), p)
                        }),
                        Expect::Refused,
                        None,
                    );
                };
                let mut size = 0usize;
                let s = crate::guard::fill_state_size2(&mut size, "fmi2SerializedFMUstateSize", |q| {
                    (api.serialized_fmu_state_size)(c, p, q)
                });
                if s != fmi2OK {
                    return (s, Expect::Succeeds, None);
                }
                let mut guarded = Guarded::new(size, 0u8);
                let s = (api.serialize_fmu_state)(c, p, guarded.as_mut_ptr() as *mut fmi2Byte, size);
                let mut buf = guarded.into_values(|| format!("fmi2SerializeFMUstate with size = {size}"), STATE_RULE2);
                if s != fmi2OK {
                    return (s, Expect::Succeeds, None);
                }
                let cut = truncate.map(|n| n % (size + 1)).filter(|n| *n < size);
                if let Some(n) = cut {
                    buf.truncate(n);
                }
                let mut q = ptr::null_mut();
                let s = crate::guard::fill_state2(&mut q, "fmi2DeSerializeFMUstate", |q| {
                    (api.deserialize_fmu_state)(c, buf.as_ptr() as *const fmi2Byte, buf.len(), q)
                });
                if s == fmi2OK {
                    let _ = crate::guard::fill_state2(&mut q, "fmi2FreeFMUstate", |q| (api.free_fmu_state)(c, q));
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
                let mut info = fmi2EventInfo::default();
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
                let (unknowns, knowns) = crate::checks::directional_derivatives::valid_pair(fmu, true);
                let (s, _) = crate::checks::directional_derivatives::call(inst, &unknowns, &knowns);
                (s, Expect::Anything, None)
            }
        }
    }
}

pub(super) fn me_declared(fmu: &Fmu, op: &MeOp) -> bool {
    let md = fmu.md.me.as_ref();
    match op {
        MeOp::GetState { .. } | MeOp::SetState { .. } | MeOp::FreeState { .. } => {
            md.is_some_and(|m| m.can_get_and_set_fmu_state)
        }
        MeOp::Reserialize { .. } => crate::me::can_snapshot_me(fmu),
        _ => true,
    }
}

pub(super) static ME_CALLS: [AtomicUsize; 7] = [const { AtomicUsize::new(0) }; 7];

pub(super) fn me_execute(fmu: &Fmu, ops: &[MeOp]) -> Result<(), TestCaseError> {
    me_execute_with(fmu, ops, &mut |_, _, _, _, _| Ok(()))
}

/// [`me_execute`], telling `hook` about each call.
pub(super) fn me_execute_with(fmu: &Fmu, ops: &[MeOp], hook: Hook<MeOp>) -> Result<(), TestCaseError> {
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
    let result = me_run_ops(&mut inst, &mut sh, ops, hook);
    for slot in sh.slots.iter_mut() {
        if let Some((mut p, _, _)) = slot.take() {
            let _ = inst.free_state(&mut p);
        }
    }
    inst.log();
    result
}

pub(super) fn me_run_ops(
    inst: &mut Instance,
    sh: &mut MeShadow,
    ops: &[MeOp],
    hook: Hook<MeOp>,
) -> Result<(), TestCaseError> {
    let observed = inst.fmu.me_state_codes().is_ok();
    let snapshots = crate::me::can_snapshot_me(inst.fmu);
    let own = inst.fmu.own_state_format();
    // The importer's mistakes (a call the state machine does not allow, invalid arguments) and
    // the FMU state after a refusal are judged on this exporter's FMUs and under --strict; FMI
    // 2.0.5 asks no detection of them (the calls checks warn about them on any FMU).
    let judge_mistakes = own || crate::outcome::strict();
    for (i, op) in ops.iter().enumerate() {
        if !me_declared(inst.fmu, op) {
            continue;
        }
        let function = me_function_of(op);
        let allowed = crate::me::allowed_states(function).contains(&sh.state);
        let before = if snapshots { inst.snapshot() } else { vec![] };
        // A NULL array passed with values on purpose (`null: true`, no empty list) is an importer's mistake: a
        // crash in it is a warning (outcome::IMPORTERS_MISTAKE), as in the calls checks.
        let text = format!("random model-exchange call {i}: {op:?} in {:?}", sh.state);
        if text.contains("null: true") && !text.contains("[]") {
            breadcrumb(&format!("{}{text}", crate::outcome::IMPORTERS_MISTAKE));
        } else {
            breadcrumb(&text);
        }
        let clock = Instant::now();
        let (status, expect, next) = me_call(inst, sh, op);
        let took = clock.elapsed();
        let log = inst.log();
        hook(i, op, status, expected_of(allowed, &expect, function), &log)?;
        ME_CALLS[sh.state as usize].fetch_add(1, Ordering::Relaxed);
        let at = format!("op {i} {op:?} in {:?}", sh.state);
        if !answered(&at, took, status, &log, judge_mistakes)? {
            return Ok(());
        }
        if !allowed && judge_mistakes {
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
        } else if allowed {
            match expect {
                Expect::Refused if !judge_mistakes => {}
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
            if snapshots && judge_mistakes {
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
