//! Model exchange (FMI 2.0 chapter 3), where the FMU declares `<ModelExchange>`: every function
//! in every state of the model-exchange state machine (section 3.2.3), the co-simulation
//! functions refused by a model-exchange instance and the model-exchange functions by a
//! co-simulation instance, bad arguments, the continuous states and derivatives, the event
//! iteration, an explicit-Euler run, and FMU states taken in EventMode and ContinuousTimeMode.
//!
//! On an FMU without `<ModelExchange>` these checks are skipped as not declared, except the
//! state-machine check, which then checks that fmi2Instantiate refuses fmi2ModelExchange.
//!
//! The state machine is observed through this exporter's serialized FMU state (the numbers of
//! the model-exchange states are learned from the FMU, [`crate::me::StateCodes`]), and Error
//! and Fatal are entered by restoring a forged one. On another exporter's FMU the functions are
//! called in the states an importer reaches by calls, and the state after a call is not
//! observed.

#![allow(non_upper_case_globals)] // fmi2OK etc. are the standard's names, matched on

use crate::fmi2::*;
use crate::instance::{Args, Instance, excitation, status_name};
use crate::me::{self, Euler, ME_REACHABLE, ME_STATES, MeState, MeState::*, Rng, needs_me};
use crate::outcome::{NOT_DECLARED, convention, info, limitation, skip_not_declared};
use crate::standard::REACHABLE;
use crate::state::{STATES, State};
use crate::{Fmu, LogEntry, Type, bits};
use fmi_description::Causality;
use std::ptr;

/// FMU states of a donor model-exchange instance, one per model-exchange state, for the
/// functions that take an FMUstate. Of another exporter's FMU: taken in the reachable states
/// (NULL for the others, which are not tried), when the FMU can get and serialize its state.
struct Donor<'a> {
    inst: Instance<'a>,
    states: Vec<fmi2FMUstate>,
    bytes: Vec<Vec<u8>>,
}

impl<'a> Donor<'a> {
    fn new(fmu: &'a Fmu) -> Donor<'a> {
        let mut inst = Instance::new_me(fmu);
        let mut states = vec![ptr::null_mut(); ME_STATES.len()];
        let mut bytes = vec![vec![]; ME_STATES.len()];
        if let Ok(codes) = fmu.me_state_codes() {
            inst.me_initialize();
            let snap = inst.snapshot();
            for s in ME_STATES {
                let Some(b) = codes.byte(s) else { continue };
                let forged = crate::state::forge_byte(&snap, b);
                let (st, p) = inst.deserialize(&forged);
                assert_eq!(st, fmi2OK, "{}", inst.log_text());
                states[s as usize] = p;
                bytes[s as usize] = forged;
            }
        } else if me::can_snapshot_me(fmu) {
            let mut take = |inst: &mut Instance, s: MeState| {
                let (st, p) = inst.get_state();
                assert_eq!(st, fmi2OK, "{}: fmi2GetFMUstate in {s:?}: {}", fmu.id, inst.log_text());
                bytes[s as usize] = inst
                    .serialize(p)
                    .unwrap_or_else(|st| panic!("{}: serializing in {s:?}: {st}: {}", fmu.id, inst.log_text()));
                states[s as usize] = p;
            };
            take(&mut inst, Instantiated);
            assert_eq!(
                [inst.setup(0.0, None), inst.enter_init()],
                [fmi2OK; 2],
                "{}",
                inst.log_text()
            );
            take(&mut inst, InitializationMode);
            assert_eq!(inst.exit_init(), fmi2OK, "{}", inst.log_text());
            take(&mut inst, EventMode);
            inst.event_iteration();
            assert_eq!(inst.enter_continuous_time_mode(), fmi2OK, "{}", inst.log_text());
            take(&mut inst, ContinuousTimeMode);
            assert_eq!(inst.terminate(), fmi2OK, "{}", inst.log_text());
            take(&mut inst, Terminated);
        }
        Donor { inst, states, bytes }
    }
}

impl Drop for Donor<'_> {
    fn drop(&mut self) {
        for p in self.states.iter_mut().filter(|p| !p.is_null()) {
            assert_eq!(self.inst.free_state(p), fmi2OK);
        }
    }
}

type CallFn = fn(&mut Instance, &mut Donor, MeState) -> fmi2Status;

struct Case {
    function: &'static str,
    /// What a valid call answers in an allowed state.
    answers: &'static [fmi2Status],
    /// The state after an allowed call, from the state before.
    next: fn(MeState) -> MeState,
    call: CallFn,
}

fn same(s: MeState) -> MeState {
    s
}

/// Variables of a type to set in a state: those the standard lets an importer set there (for a
/// state where no set is allowed: those settable in EventMode, so that the call is a real
/// attempt).
fn settable<'a>(inst: &Instance<'a>, ty: Type, s: MeState) -> Vec<&'a crate::Variable> {
    let at = if me::allowed_states(set_function(ty)).contains(&s) {
        s
    } else {
        EventMode
    };
    inst.fmu
        .md
        .of_type(ty)
        .filter(|v| crate::standard::settable_in_me(v, &format!("{at:?}")))
        .collect()
}

fn set_function(ty: Type) -> &'static str {
    match ty {
        Type::Real => "fmi2SetReal",
        Type::Integer | Type::Enumeration => "fmi2SetInteger",
        Type::Boolean => "fmi2SetBoolean",
        Type::String => "fmi2SetString",
    }
}

/// Start values of the continuous states (0 where there is none).
fn start_states(fmu: &Fmu) -> Vec<f64> {
    match fmu.md.continuous_states() {
        Ok(states) => states.iter().map(|(x, _)| x.start_real().unwrap_or(0.0)).collect(),
        Err(_) => vec![0.0; fmu.md.number_of_continuous_states()],
    }
}

/// A directional-derivative call with valid arguments for this FMU (see
/// [`super::directional_derivatives::valid_call`]).
fn directional_derivative(i: &mut Instance, s: MeState) -> fmi2Status {
    let (unknowns, knowns) = if s == InitializationMode {
        // What may be asked in initialization mode is InitialUnknowns: nothing is asked.
        (vec![], vec![])
    } else {
        super::directional_derivatives::valid_pair(i.fmu, true)
    };
    super::directional_derivatives::call(i, &unknowns, &knowns).0
}

fn cases() -> Vec<Case> {
    vec![
        Case {
            function: "fmi2SetDebugLogging",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, _| i.set_debug_logging(true, &[]),
        },
        Case {
            function: "fmi2SetupExperiment",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, _| i.setup(0.0, None),
        },
        Case {
            function: "fmi2EnterInitializationMode",
            answers: &[fmi2OK],
            next: |_| InitializationMode,
            call: |i, _, _| i.enter_init(),
        },
        Case {
            function: "fmi2ExitInitializationMode",
            answers: &[fmi2OK],
            next: |_| EventMode,
            call: |i, _, _| i.exit_init(),
        },
        Case {
            function: "fmi2Terminate",
            answers: &[fmi2OK],
            next: |_| Terminated,
            call: |i, _, _| i.terminate(),
        },
        Case {
            function: "fmi2Reset",
            answers: &[fmi2OK],
            next: |_| Instantiated,
            call: |i, _, _| i.reset(),
        },
        Case {
            function: "fmi2GetReal",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, _| i.get_real(&i.fmu.md.vrs_of_type(Type::Real)).0,
        },
        Case {
            function: "fmi2GetInteger",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, _| {
                let mut vrs = i.fmu.md.vrs_of_type(Type::Integer);
                vrs.extend(i.fmu.md.vrs_of_type(Type::Enumeration));
                i.get_integer(&vrs).0
            },
        },
        Case {
            function: "fmi2GetBoolean",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, _| i.get_boolean(&i.fmu.md.vrs_of_type(Type::Boolean)).0,
        },
        Case {
            function: "fmi2GetString",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, _| {
                let vrs = i.fmu.md.vrs_of_type(Type::String);
                let mut v: Vec<fmi2String> = vec![ptr::null(); vrs.len()];
                // SAFETY: arrays of nvr elements.
                unsafe { (i.fmu.api.get_string)(i.c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr()) }
            },
        },
        Case {
            function: "fmi2SetReal",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, s| {
                let vars = settable(i, Type::Real, s);
                let vrs: Vec<u32> = vars.iter().map(|v| v.vr).collect();
                let values: Vec<f64> = vars.iter().map(|v| v.start_real().unwrap_or(0.0)).collect();
                i.set_real(&vrs, &values)
            },
        },
        Case {
            function: "fmi2SetInteger",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, s| {
                let mut vars = settable(i, Type::Integer, s);
                vars.extend(settable(i, Type::Enumeration, s));
                let vrs: Vec<u32> = vars.iter().map(|v| v.vr).collect();
                let values: Vec<i32> = vars.iter().map(|v| v.start_integer().unwrap_or(0)).collect();
                i.set_integer(&vrs, &values)
            },
        },
        Case {
            function: "fmi2SetBoolean",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, s| {
                let vars = settable(i, Type::Boolean, s);
                let vrs: Vec<u32> = vars.iter().map(|v| v.vr).collect();
                let values: Vec<bool> = vars.iter().map(|v| v.start_boolean().unwrap_or(false)).collect();
                i.set_boolean(&vrs, &values)
            },
        },
        Case {
            function: "fmi2SetString",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, s| {
                let vars = settable(i, Type::String, s);
                let vrs: Vec<u32> = vars.iter().map(|v| v.vr).collect();
                // Each to its start value (a model may refuse an empty file name, say).
                let starts: Vec<std::ffi::CString> = vars
                    .iter()
                    .map(|v| std::ffi::CString::new(v.start.clone().unwrap_or_default()).unwrap_or_default())
                    .collect();
                let v: Vec<fmi2String> = starts.iter().map(|c| c.as_ptr()).collect();
                // SAFETY: arrays of nvr elements; the strings outlive the call.
                unsafe { (i.fmu.api.set_string)(i.c, vrs.as_ptr(), vrs.len(), v.as_ptr()) }
            },
        },
        Case {
            function: "fmi2GetFMUstate",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, _| {
                let (st, mut p) = i.get_state();
                if st == fmi2OK {
                    assert!(!p.is_null(), "fmi2GetFMUstate answered fmi2OK with a NULL state");
                    assert_eq!(i.free_state(&mut p), fmi2OK);
                } else {
                    assert!(p.is_null(), "a refused fmi2GetFMUstate wrote a state");
                }
                st
            },
        },
        Case {
            function: "fmi2SetFMUstate",
            answers: &[fmi2OK],
            // The donor's state for state s is in state s: restoring it keeps the state.
            next: same,
            call: |i, d, s| i.set_state(d.states[s as usize]),
        },
        Case {
            function: "fmi2FreeFMUstate",
            answers: &[fmi2OK],
            next: same,
            call: |i, d, s| {
                let (st, mut p) = d.inst.deserialize(&d.bytes[s as usize].clone());
                assert_eq!(st, fmi2OK);
                let status = i.free_state(&mut p);
                if status == fmi2OK {
                    assert!(p.is_null(), "fmi2FreeFMUstate must set *FMUstate = NULL");
                } else {
                    assert!(!p.is_null(), "a refused fmi2FreeFMUstate cleared the pointer");
                    assert_eq!(d.inst.free_state(&mut p), fmi2OK);
                }
                status
            },
        },
        Case {
            function: "fmi2SerializedFMUstateSize",
            answers: &[fmi2OK],
            next: same,
            call: |i, d, s| {
                let mut size = 0usize;
                // SAFETY: a state of this FMU, a valid out pointer.
                let st = unsafe { (i.fmu.api.serialized_fmu_state_size)(i.c, d.states[s as usize], &mut size) };
                if st == fmi2OK {
                    assert_eq!(size, d.bytes[s as usize].len(), "fmi2SerializedFMUstateSize");
                }
                st
            },
        },
        Case {
            function: "fmi2SerializeFMUstate",
            answers: &[fmi2OK],
            next: same,
            call: |i, d, s| {
                let want = &d.bytes[s as usize];
                let mut buf = vec![0u8; want.len()];
                // SAFETY: a state of this FMU, a buffer of the size it needs.
                let st = unsafe {
                    (i.fmu.api.serialize_fmu_state)(
                        i.c,
                        d.states[s as usize],
                        buf.as_mut_ptr() as *mut fmi2Byte,
                        buf.len(),
                    )
                };
                if st == fmi2OK {
                    assert_eq!(&buf, want, "serializing a deserialized state must give the same bytes");
                }
                st
            },
        },
        Case {
            function: "fmi2DeSerializeFMUstate",
            answers: &[fmi2OK],
            next: same,
            call: |i, d, s| {
                let (st, mut p) = i.deserialize(&d.bytes[s as usize].clone());
                if st == fmi2OK {
                    assert_eq!(i.free_state(&mut p), fmi2OK);
                } else {
                    assert!(p.is_null(), "a refused fmi2DeSerializeFMUstate wrote a state");
                }
                st
            },
        },
        Case {
            function: "fmi2GetDirectionalDerivative",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, s| directional_derivative(i, s),
        },
        // ---- model exchange only
        Case {
            function: "fmi2EnterEventMode",
            answers: &[fmi2OK],
            next: |_| EventMode,
            call: |i, _, _| i.enter_event_mode(),
        },
        Case {
            function: "fmi2NewDiscreteStates",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, _| i.new_discrete_states().0,
        },
        Case {
            function: "fmi2EnterContinuousTimeMode",
            answers: &[fmi2OK],
            next: |_| ContinuousTimeMode,
            call: |i, _, _| i.enter_continuous_time_mode(),
        },
        Case {
            function: "fmi2CompletedIntegratorStep",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, _| i.completed_integrator_step().status,
        },
        Case {
            function: "fmi2SetTime",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, _| {
                let t = i.time;
                i.set_time(t)
            },
        },
        Case {
            function: "fmi2SetContinuousStates",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, _| {
                let x = start_states(i.fmu);
                i.set_continuous_states(&x)
            },
        },
        Case {
            function: "fmi2GetDerivatives",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, _| i.get_derivatives().0,
        },
        Case {
            function: "fmi2GetEventIndicators",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, _| i.get_event_indicators().0,
        },
        Case {
            function: "fmi2GetContinuousStates",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, _| i.get_continuous_states().0,
        },
        Case {
            function: "fmi2GetNominalsOfContinuousStates",
            answers: &[fmi2OK],
            next: same,
            call: |i, _, _| i.get_nominals().0,
        },
        // ---- co-simulation only: refused everywhere
        Case {
            function: "fmi2SetRealInputDerivatives",
            answers: &[],
            next: same,
            call: |i, _, _| {
                let inputs: Vec<u32> = i
                    .fmu
                    .md
                    .of_type(Type::Real)
                    .filter(|v| v.causality == Causality::Input)
                    .map(|v| v.vr)
                    .take(1)
                    .collect();
                let (order, der) = (vec![1; inputs.len()], vec![0.0; inputs.len()]);
                // SAFETY: arrays of nvr elements.
                unsafe {
                    (i.fmu.api.set_real_input_derivatives)(
                        i.c,
                        inputs.as_ptr(),
                        inputs.len(),
                        order.as_ptr(),
                        der.as_ptr(),
                    )
                }
            },
        },
        Case {
            function: "fmi2GetRealOutputDerivatives",
            answers: &[],
            next: same,
            call: |i, _, _| {
                let outputs: Vec<u32> = i
                    .fmu
                    .md
                    .of_type(Type::Real)
                    .filter(|v| v.causality == Causality::Output)
                    .map(|v| v.vr)
                    .take(1)
                    .collect();
                let (order, mut der) = (vec![1; outputs.len()], vec![0.0; outputs.len()]);
                // SAFETY: arrays of nvr elements.
                unsafe {
                    (i.fmu.api.get_real_output_derivatives)(
                        i.c,
                        outputs.as_ptr(),
                        outputs.len(),
                        order.as_ptr(),
                        der.as_mut_ptr(),
                    )
                }
            },
        },
        Case {
            function: "fmi2DoStep",
            answers: &[],
            next: same,
            call: |i, _, _| {
                let h = crate::instance::step_size(i.fmu);
                i.do_step(i.time, h)
            },
        },
        Case {
            function: "fmi2CancelStep",
            answers: &[],
            next: same,
            // SAFETY: a live instance.
            call: |i, _, _| unsafe { (i.fmu.api.cancel_step)(i.c) },
        },
        Case {
            function: "fmi2GetStatus",
            answers: &[],
            next: same,
            call: |i, _, _| {
                let mut v = 99;
                // SAFETY: a valid out pointer.
                unsafe { (i.fmu.api.get_status)(i.c, fmi2DoStepStatus, &mut v) }
            },
        },
        Case {
            function: "fmi2GetRealStatus",
            answers: &[],
            next: same,
            call: |i, _, _| i.last_successful_time().0,
        },
        Case {
            function: "fmi2GetIntegerStatus",
            answers: &[],
            next: same,
            call: |i, _, _| {
                let mut v = 0;
                // SAFETY: a valid out pointer.
                unsafe { (i.fmu.api.get_integer_status)(i.c, fmi2PendingStatus, &mut v) }
            },
        },
        Case {
            function: "fmi2GetBooleanStatus",
            answers: &[],
            next: same,
            call: |i, _, _| i.terminated().0,
        },
        Case {
            function: "fmi2GetStringStatus",
            answers: &[],
            next: same,
            call: |i, _, _| {
                let mut v: fmi2String = ptr::null();
                // SAFETY: a valid out pointer.
                unsafe { (i.fmu.api.get_string_status)(i.c, fmi2PendingStatus, &mut v) }
            },
        },
    ]
}

/// Why a case does not apply to this FMU, if it does not.
fn not_applicable(fmu: &Fmu, function: &str) -> Option<&'static str> {
    let me = fmu.md.me.as_ref()?;
    match function {
        "fmi2GetFMUstate" | "fmi2SetFMUstate" if !me.can_get_and_set_fmu_state => {
            Some("<ModelExchange> does not declare canGetAndSetFMUstate")
        }
        "fmi2FreeFMUstate" | "fmi2SerializedFMUstateSize" | "fmi2SerializeFMUstate" | "fmi2DeSerializeFMUstate"
            if !me::can_snapshot_me(fmu) =>
        {
            Some("<ModelExchange> does not declare canGetAndSetFMUstate and canSerializeFMUstate")
        }
        "fmi2GetDirectionalDerivative" if !me.provides_directional_derivative => Some(
            "<ModelExchange> does not declare providesDirectionalDerivative (checked by directional_derivative_flag_is_either_value_and_false_means_refused)",
        ),
        _ => None,
    }
}

/// Whether the log holds the refusal of `function` as this exporter words it (under
/// logStatusError, naming the function), or, of another exporter's FMU, any fmi2Error message.
fn refusal_logged(inst: &Instance, log: &[LogEntry], function: &str) -> bool {
    if inst.fmu.own_state_format() {
        log.iter()
            .any(|e| e.status == fmi2Error && e.category == "logStatusError" && e.text.contains(function))
    } else {
        convention(inst.fmu, "refusals under category logStatusError, naming the function");
        log.iter().any(|e| e.status == fmi2Error)
    }
}

pub fn model_exchange_every_function_in_every_state_answers_as_the_standard_says(fmu: &Fmu) {
    if fmu.md.me.is_none() {
        // What applies to an FMU without <ModelExchange>: fmi2ModelExchange is refused.
        let args = Args {
            fmu_type: fmi2ModelExchange,
            ..Args::valid(fmu)
        };
        let log = Instance::with(fmu, &args).err().unwrap_or_else(|| {
            panic!(
                "{}: no <ModelExchange>, but fmi2Instantiate(fmi2ModelExchange) gave an instance",
                fmu.id
            )
        });
        assert!(
            log.iter().any(|e| e.status == fmi2Error),
            "{}: fmi2Instantiate(fmi2ModelExchange) refused without a message: {log:?}",
            fmu.id
        );
        info(
            "the FMU declares no <ModelExchange>: checked only that fmi2Instantiate refuses fmi2ModelExchange with a message",
        );
        return;
    }
    needs_me(fmu);
    let mut failures = vec![];
    let codes = fmu.me_state_codes().clone();
    let observed = codes.is_ok();
    let forged = codes.as_ref().is_ok_and(|c| c.knows_error_and_fatal());
    if let Err(why) = &codes {
        limitation(format!(
            "functions are called only in the states an importer reaches, and the state after each call is not observed ({why})"
        ));
    } else if !forged {
        limitation("Error and Fatal are not entered: their state bytes in a model-exchange instance are not known");
    }
    if let Ok(c) = &codes {
        info(format!(
            "model-exchange states in the serialized FMU state (learned): {:?}",
            ME_STATES.map(|s| (s, c.byte(s)))
        ));
    }
    let states: Vec<MeState> = ME_STATES
        .into_iter()
        .filter(|s| ME_REACHABLE.contains(s) || forged)
        .collect();
    let mut donor = Donor::new(fmu);
    for case in cases() {
        if let Some(why) = not_applicable(fmu, case.function) {
            limitation(format!("{} not tried: {why}", case.function));
            continue;
        }
        for &s in &states {
            if donor.bytes[s as usize].is_empty() && case.function.contains("FMUstate") {
                limitation(format!(
                    "{} in {s:?}: no FMU state of that state to pass",
                    case.function
                ));
                continue;
            }
            let mut inst = me::instance_in(fmu, s);
            let status = (case.call)(&mut inst, &mut donor, s);
            let log = inst.log();
            let allowed = me::allowed_states(case.function).contains(&s);
            let mut fail = |what: String| failures.push((case.function, what, s, format!("{log:?}")));
            if allowed {
                if !case.answers.contains(&status) {
                    fail(format!(
                        "allowed, expected {:?}, got {}",
                        case.answers,
                        status_name(status)
                    ));
                }
            } else {
                if status != fmi2Error {
                    fail(format!("not allowed, expected fmi2Error, got {}", status_name(status)));
                }
                if !refusal_logged(&inst, &log, case.function) {
                    fail("not allowed: no fmi2Error message naming the function (under logStatusError)".into());
                }
            }
            if s == Fatal || !observed {
                continue;
            }
            let after = inst.me_state();
            let expected = if allowed && status != fmi2Error {
                (case.next)(s)
            } else {
                s
            };
            if after != expected {
                fail(format!("state after the call: {after:?}, expected {expected:?}"));
            }
        }
    }
    let grouped = super::one_line_per_cause(&fmu.id, "model-exchange ", failures);
    assert!(
        grouped.is_empty(),
        "{} failures:\n{}",
        grouped.len(),
        grouped.join("\n")
    );
}

/// The model-exchange functions, for [`one_me_call`].
const ME_CALLS: usize = 10;

pub fn a_co_simulation_instance_refuses_every_model_exchange_function(fmu: &Fmu) {
    if fmu.api.me.is_err() {
        if fmu.md.me.is_some() {
            needs_me(fmu);
        }
        skip_not_declared("<ModelExchange>, and the binary does not export the model-exchange functions");
    }
    let own = fmu.own_state_format();
    if !own {
        limitation(
            "called only in Instantiated, InitializationMode, StepComplete and Terminated; the state after each call is not observed",
        );
    }
    let mut failures = vec![];
    for s in STATES.into_iter().filter(|s| own || REACHABLE.contains(s)) {
        for k in 0..ME_CALLS {
            // One call per fresh instance: an FMU that wrongly accepts one must not spoil the
            // next.
            let mut inst = super::state_machine::instance_in(fmu, s);
            let before = if s != State::Fatal { inst.fingerprint() } else { None };
            let (function, status) = one_me_call(&mut inst, k);
            let log = inst.log();
            let at = format!("{}: {function} in co-simulation state {s:?}", fmu.id);
            if status != fmi2Error {
                failures.push(format!(
                    "{at}: expected fmi2Error, got {}; log {log:?}",
                    status_name(status)
                ));
            } else if !refusal_logged(&inst, &log, function) {
                failures.push(format!(
                    "{at}: refused without an fmi2Error message naming the function: {log:?}"
                ));
            }
            if s != State::Fatal && status == fmi2Error {
                if before.is_some() && inst.fingerprint() != before {
                    failures.push(format!("{at}: refused, but the FMU state changed"));
                }
                if own && inst.machine_state() != s {
                    failures.push(format!("{at}: refused, but the state machine left {s:?}"));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// The k-th model-exchange function with valid arguments: (name, status).
fn one_me_call(inst: &mut Instance, k: usize) -> (&'static str, fmi2Status) {
    let x = start_states(inst.fmu);
    let t = inst.time;
    match k {
        0 => ("fmi2EnterEventMode", inst.enter_event_mode()),
        1 => ("fmi2NewDiscreteStates", inst.new_discrete_states().0),
        2 => ("fmi2EnterContinuousTimeMode", inst.enter_continuous_time_mode()),
        3 => ("fmi2CompletedIntegratorStep", inst.completed_integrator_step().status),
        4 => ("fmi2SetTime", inst.set_time(t)),
        5 => ("fmi2SetContinuousStates", inst.set_continuous_states(&x)),
        6 => ("fmi2GetDerivatives", inst.get_derivatives().0),
        7 => ("fmi2GetEventIndicators", inst.get_event_indicators().0),
        8 => ("fmi2GetContinuousStates", inst.get_continuous_states().0),
        _ => ("fmi2GetNominalsOfContinuousStates", inst.get_nominals().0),
    }
}

/// Fails unless the last call was refused with fmi2Error and a logged message (naming the
/// function, on this exporter's FMUs).
fn refused(inst: &Instance, function: &str, what: &str, status: fmi2Status) {
    let log = inst.log();
    assert_eq!(
        status,
        fmi2Error,
        "{}: {function} with {what}: expected fmi2Error, got {}; log {log:?}",
        inst.fmu.id,
        status_name(status)
    );
    assert!(
        refusal_logged(inst, &log, function),
        "{}: {function} with {what}: refused without an fmi2Error message naming the function: {log:?}",
        inst.fmu.id
    );
}

/// What a model-exchange instance shows of itself: states, derivatives, event indicators and
/// every variable, as bit patterns.
fn me_observe(inst: &Instance) -> Vec<u64> {
    let (s1, x) = inst.get_continuous_states();
    let (s2, dx) = inst.get_derivatives();
    let (s3, z) = inst.get_event_indicators();
    assert_eq!([s1, s2, s3], [fmi2OK; 3], "{}: {}", inst.fmu.id, inst.log_text());
    let mut out = bits(&x);
    out.extend(bits(&dx));
    out.extend(bits(&z));
    out.extend(inst.observe());
    out
}

/// A model-exchange instance in ContinuousTimeMode after `steps` explicit-Euler steps of 1e-4 s.
fn advanced(fmu: &Fmu, steps: usize) -> (Instance<'_>, Euler) {
    let mut inst = Instance::new_me(fmu);
    let info = inst.me_initialize();
    let mut euler = Euler::new(&inst, 1e-4, &info);
    for _ in 0..steps {
        euler.step(&mut inst);
    }
    inst.log();
    (inst, euler)
}

pub fn model_exchange_bad_arguments_are_refused_with_a_message_and_change_nothing(fmu: &Fmu) {
    let me = needs_me(fmu);
    let (mut inst, _) = advanced(fmu, 10);
    let (nx, ni) = (inst.nx(), inst.ni());
    let c = inst.c;
    type Vector = unsafe extern "C" fn(fmi2Component, *mut fmi2Real, usize) -> fmi2Status;
    let getters: [(&str, Vector, usize); 4] = [
        ("fmi2GetContinuousStates", me.get_continuous_states, nx),
        ("fmi2GetDerivatives", me.get_derivatives, nx),
        (
            "fmi2GetNominalsOfContinuousStates",
            me.get_nominals_of_continuous_states,
            nx,
        ),
        ("fmi2GetEventIndicators", me.get_event_indicators, ni),
    ];
    let reference = me_observe(&inst);
    let check_unchanged = |inst: &mut Instance, what: &str, before: &Option<Vec<u8>>| {
        assert_eq!(
            &inst.fingerprint(),
            before,
            "{}: {what}: refused, but the FMU state changed",
            fmu.id
        );
        assert_eq!(
            me_observe(inst),
            reference,
            "{}: after the refused {what}, the instance shows other values",
            fmu.id
        );
    };
    let mut sizes: Vec<usize> = vec![];
    for (function, f, n) in getters {
        // Wrong lengths, with a buffer of that length; NULL with the right length.
        sizes.clear();
        sizes.extend([n + 1, n + 7]);
        if n > 0 {
            sizes.push(n - 1);
        }
        for m in sizes.iter().copied() {
            let before = inst.fingerprint();
            let mut buf = vec![0.0; m];
            // SAFETY: a buffer of m elements.
            let s = unsafe { f(c, buf.as_mut_ptr(), m) };
            let what = format!("n = {m} (the FMU has {n})");
            refused(&inst, function, &what, s);
            check_unchanged(&mut inst, &format!("{function}({what})"), &before);
        }
        let before = inst.fingerprint();
        let m = n.max(1);
        // SAFETY: NULL with n > 0, which the FMU must refuse.
        let s = unsafe { f(c, ptr::null_mut(), m) };
        refused(&inst, function, &format!("NULL and n = {m}"), s);
        check_unchanged(&mut inst, &format!("{function}(NULL, {m})"), &before);
    }
    // fmi2SetContinuousStates: lengths, NULL, non-finite values (each position).
    let (_, x) = inst.get_continuous_states();
    let mut bad_states: Vec<(String, Vec<f64>, bool)> = vec![
        (
            format!("n = {} (the FMU has {nx})", nx + 1),
            [&x[..], &[0.0]].concat(),
            false,
        ),
        (format!("NULL and n = {}", nx.max(1)), vec![], true),
    ];
    if nx > 0 {
        bad_states.push((
            format!("n = {} (the FMU has {nx})", nx - 1),
            x[..nx - 1].to_vec(),
            false,
        ));
    }
    for j in 0..nx {
        for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut y = x.clone();
            y[j] = v;
            bad_states.push((format!("x[{j}] = {v}"), y, false));
        }
    }
    for (what, y, null) in bad_states {
        let before = inst.fingerprint();
        let (p, n) = if null {
            (ptr::null(), nx.max(1))
        } else {
            (y.as_ptr(), y.len())
        };
        // SAFETY: an array of n elements, or NULL on purpose.
        let s = unsafe { (me.set_continuous_states)(c, p, n) };
        refused(&inst, "fmi2SetContinuousStates", &what, s);
        check_unchanged(&mut inst, &format!("fmi2SetContinuousStates({what})"), &before);
    }
    // fmi2SetTime: not finite.
    let t = inst.time;
    for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let before = inst.fingerprint();
        let s = inst.set_time(v);
        refused(&inst, "fmi2SetTime", &format!("time = {v}"), s);
        check_unchanged(&mut inst, &format!("fmi2SetTime({v})"), &before);
    }
    inst.time = t;
    // fmi2CompletedIntegratorStep: NULL out pointers.
    let (mut a, mut b) = (0, 0);
    for (what, pa, pb) in [
        ("enterEventMode NULL", ptr::null_mut(), &mut b as *mut fmi2Boolean),
        ("terminateSimulation NULL", &mut a as *mut fmi2Boolean, ptr::null_mut()),
    ] {
        let before = inst.fingerprint();
        // SAFETY: NULL on purpose, a valid pointer otherwise.
        let s = unsafe { (me.completed_integrator_step)(c, fmi2False, pa, pb) };
        refused(&inst, "fmi2CompletedIntegratorStep", what, s);
        check_unchanged(&mut inst, &format!("fmi2CompletedIntegratorStep({what})"), &before);
    }
    // fmi2NewDiscreteStates(NULL), in EventMode.
    assert_eq!(inst.enter_event_mode(), fmi2OK, "{}", inst.log_text());
    inst.log();
    let before = inst.fingerprint();
    // What the valid call answers without the refused one before it: on a twin instance.
    let (mut twin, _) = advanced(fmu, 10);
    assert_eq!(twin.enter_event_mode(), fmi2OK, "{}", twin.log_text());
    let (s_ref, info_ref) = twin.new_discrete_states();
    // SAFETY: NULL on purpose.
    let s = unsafe { (me.new_discrete_states)(c, ptr::null_mut()) };
    refused(&inst, "fmi2NewDiscreteStates", "eventInfo NULL", s);
    assert_eq!(
        inst.fingerprint(),
        before,
        "{}: fmi2NewDiscreteStates(NULL) changed the FMU state",
        fmu.id
    );
    let (s, info) = inst.new_discrete_states();
    assert_eq!(
        (s, info),
        (s_ref, info_ref),
        "{}: fmi2NewDiscreteStates after the refused one answers otherwise",
        fmu.id
    );
    if before.is_none() {
        limitation(
            "<ModelExchange> does not declare canGetAndSetFMUstate and canSerializeFMUstate: the FMU state is not compared",
        );
    }
}

pub fn model_exchange_each_variable_can_be_set_exactly_where_the_standard_allows_it(fmu: &Fmu) {
    needs_me(fmu);
    let mut failures = vec![];
    for state in [Instantiated, InitializationMode, EventMode, ContinuousTimeMode] {
        for v in fmu
            .md
            .variables
            .iter()
            // An alias is checked through the first variable of its set.
            .filter(|v| v.ty != Type::String && !crate::standard::aliases_an_earlier(&fmu.md.variables, v))
        {
            let mut inst = me::instance_in(fmu, state);
            let before = inst.fingerprint();
            let s = match v.ty {
                Type::Real => inst.set_real(&[v.vr], &[v.start_real().unwrap_or(0.0)]),
                Type::Integer | Type::Enumeration => inst.set_integer(&[v.vr], &[v.start_integer().unwrap_or(0)]),
                Type::Boolean => inst.set_boolean(&[v.vr], &[v.start_boolean().unwrap_or(false)]),
                Type::String => unreachable!(),
            };
            let log = inst.log();
            let want = crate::standard::settable_in_me(v, &format!("{state:?}"));
            let at = format!(
                "{}: set '{}' ({:?} {} {}, initial {:?}) in model-exchange state {state:?}",
                fmu.id,
                v.name,
                v.ty,
                v.causality,
                v.variability,
                crate::standard::initial(v.causality, v.variability, v.declared_initial)
            );
            if want && s != fmi2OK {
                failures.push(format!(
                    "{at}: allowed by the standard, got {}: {log:?}",
                    status_name(s)
                ));
            }
            if !want {
                let function_allowed = me::allowed_states(set_function(v.ty)).contains(&state);
                if s != fmi2Error {
                    failures.push(format!("{at}: not allowed, got {}", status_name(s)));
                } else if function_allowed && !inst.says(&log, fmi2Error, &[&format!("'{}'", v.name)]) {
                    failures.push(format!("{at}: the refusal does not name the variable: {log:?}"));
                } else if !log.iter().any(|e| e.status == fmi2Error) {
                    failures.push(format!("{at}: refused without a message"));
                }
                if inst.fingerprint() != before {
                    failures.push(format!("{at}: refused, but the FMU state changed"));
                }
            }
            // A settable Real refuses NaN and infinities.
            if want && v.ty == Type::Real {
                for bad in [f64::NAN, f64::INFINITY] {
                    let before = inst.fingerprint();
                    let s = inst.set_real(&[v.vr], &[bad]);
                    let log = inst.log();
                    if s != fmi2Error || !log.iter().any(|e| e.status == fmi2Error) {
                        failures.push(format!(
                            "{at}: = {bad}: expected fmi2Error with a message, got {}",
                            status_name(s)
                        ));
                    }
                    if inst.fingerprint() != before {
                        failures.push(format!("{at}: = {bad} refused, but the FMU state changed"));
                    }
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

pub fn model_exchange_states_and_derivatives_are_declared_consistent_and_deterministic(fmu: &Fmu) {
    needs_me(fmu);
    let md = &fmu.md;
    let states = md
        .continuous_states()
        .unwrap_or_else(|e| panic!("{}: <ModelStructure><Derivatives>: {e}", fmu.id));
    let nx = states.len();
    for (i, (x, _)) in states.iter().enumerate() {
        assert!(
            !states[..i].iter().any(|(y, _)| y.vr == x.vr),
            "{}: '{}' is the state of two derivatives",
            fmu.id,
            x.name
        );
    }
    for u in md.model_structure.outputs.iter() {
        let v = md
            .by_index(u.index)
            .unwrap_or_else(|| panic!("{}: <Outputs> lists index {}, which is no variable", fmu.id, u.index));
        assert_eq!(
            v.causality,
            Causality::Output,
            "{}: <Outputs> lists '{}', no output",
            fmu.id,
            v.name
        );
    }
    let state_vrs: Vec<u32> = states.iter().map(|(x, _)| x.vr).collect();
    let der_vrs: Vec<u32> = states.iter().map(|(_, d)| d.vr).collect();
    // Nominals are there before initialization too.
    let fresh = Instance::new_me(fmu);
    let (s, nominals) = fresh.get_nominals();
    assert_eq!(
        s,
        fmi2OK,
        "{}: fmi2GetNominalsOfContinuousStates in Instantiated: {}",
        fmu.id,
        fresh.log_text()
    );
    drop(fresh);
    let (mut inst, mut euler) = advanced(fmu, 0);
    let (s, nominals_ct) = inst.get_nominals();
    assert_eq!(s, fmi2OK, "{}: {}", fmu.id, inst.log_text());
    for (j, n) in nominals.iter().chain(&nominals_ct).enumerate() {
        assert!(
            n.is_finite() && *n > 0.0,
            "{}: the nominal of state '{}' is {n} (not finite and > 0)",
            fmu.id,
            states[j % nx.max(1)].0.name
        );
    }
    let mut rng = Rng::new(0x57a7e5);
    for round in 0..20 {
        // The state vector is the declared variables, in <Derivatives> order; so are the
        // derivatives.
        let (s1, x) = inst.get_continuous_states();
        let (s2, dx) = inst.get_derivatives();
        assert_eq!([s1, s2], [fmi2OK; 2], "{}: {}", fmu.id, inst.log_text());
        let at = format!("{}: round {round}, t = {}", fmu.id, inst.time);
        assert_eq!(x.len(), nx);
        assert_eq!(
            bits(&x),
            bits(&inst.get_real(&state_vrs).1),
            "{at}: fmi2GetContinuousStates differs from fmi2GetReal of the state variables {state_vrs:?}"
        );
        assert_eq!(
            bits(&dx),
            bits(&inst.get_real(&der_vrs).1),
            "{at}: fmi2GetDerivatives differs from fmi2GetReal of the derivative variables {der_vrs:?}"
        );
        assert!(dx.iter().all(|d| d.is_finite()), "{at}: derivatives not finite: {dx:?}");
        assert_eq!(
            bits(&inst.get_derivatives().1),
            bits(&dx),
            "{at}: fmi2GetDerivatives twice differs"
        );
        // Random states: set, read back bit-identically, derivatives finite and a function of
        // the states alone (the same after going elsewhere and back).
        let y: Vec<f64> = states
            .iter()
            .map(|(v, _)| {
                let r = rng.uniform(-0.5, 0.5);
                let r = v.max.map_or(r, |m| r.min(m));
                v.min.map_or(r, |m| r.max(m))
            })
            .collect();
        assert_eq!(inst.set_continuous_states(&y), fmi2OK, "{at}: {}", inst.log_text());
        let (s, back) = inst.get_continuous_states();
        assert_eq!(s, fmi2OK);
        assert_eq!(
            bits(&back),
            bits(&y),
            "{at}: fmi2GetContinuousStates after fmi2SetContinuousStates({y:?})"
        );
        assert_eq!(
            bits(&inst.get_real(&state_vrs).1),
            bits(&y),
            "{at}: fmi2GetReal of the states after fmi2SetContinuousStates"
        );
        let (s, dy) = inst.get_derivatives();
        assert_eq!(s, fmi2OK);
        assert!(
            dy.iter().all(|d| d.is_finite()),
            "{at}: derivatives at {y:?} not finite: {dy:?}"
        );
        let elsewhere: Vec<f64> = y.iter().map(|v| v * 0.5 + 0.125).collect();
        assert_eq!(inst.set_continuous_states(&elsewhere), fmi2OK);
        inst.get_derivatives();
        assert_eq!(inst.set_continuous_states(&y), fmi2OK);
        assert_eq!(
            bits(&inst.get_derivatives().1),
            bits(&dy),
            "{at}: the derivatives at {y:?} differ after the states went elsewhere and back"
        );
        // Back where the integration was, one step on.
        assert_eq!(inst.set_continuous_states(&x), fmi2OK);
        euler.step(&mut inst);
    }
    info(format!(
        "{nx} continuous states, {} event indicators",
        fmu.md.number_of_event_indicators
    ));
}

pub fn model_exchange_new_discrete_states_fills_the_event_info_sensibly(fmu: &Fmu) {
    needs_me(fmu);
    let mut inst = Instance::new_me(fmu);
    let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(fmu).into_iter().unzip();
    assert_eq!(inst.set_real(&vrs, &vals), fmi2OK, "{}", inst.log_text());
    inst.me_to_event_mode();
    let mut first = true;
    let mut events = 0;
    // At the initial event and at the next three events (time events where the FMU defines
    // them, else an event the importer asks for 10 ms later).
    while events < 4 {
        let now = inst.time;
        let (_, x_before) = inst.get_continuous_states();
        let mut calls = 0;
        let info = loop {
            let (s, info) = inst.new_discrete_states();
            assert_eq!(
                s,
                fmi2OK,
                "{}: fmi2NewDiscreteStates at t = {now}: {}",
                fmu.id,
                inst.log_text()
            );
            me::check_event_info(fmu, &info, now);
            calls += 1;
            if info.newDiscreteStatesNeeded == fmi2False || calls == 100 {
                break info;
            }
        };
        assert_eq!(
            info.newDiscreteStatesNeeded, fmi2False,
            "{}: still newDiscreteStatesNeeded after 100 calls at t = {now}",
            fmu.id
        );
        if calls > 1 && convention(fmu, "one fmi2NewDiscreteStates call settles the discrete states") {
            panic!(
                "{}: at t = {now}, {calls} fmi2NewDiscreteStates calls were needed",
                fmu.id
            );
        }
        let (_, x_after) = inst.get_continuous_states();
        if info.valuesOfContinuousStatesChanged == fmi2False {
            assert_eq!(
                bits(&x_after),
                bits(&x_before),
                "{}: at t = {now}: valuesOfContinuousStatesChanged = false, but the continuous states changed",
                fmu.id
            );
        }
        // Once settled, another call changes nothing and says the same.
        let (s, again) = inst.new_discrete_states();
        assert_eq!(s, fmi2OK, "{}", inst.log_text());
        assert_eq!(
            (
                again.newDiscreteStatesNeeded,
                again.nextEventTimeDefined,
                again.terminateSimulation
            ),
            (fmi2False, info.nextEventTimeDefined, fmi2False),
            "{}: at t = {now}: a second fmi2NewDiscreteStates once settled answers {again:?} after {info:?}",
            fmu.id
        );
        if info.nextEventTimeDefined == fmi2True {
            assert_eq!(
                again.nextEventTime.to_bits(),
                info.nextEventTime.to_bits(),
                "{}: at t = {now}: the next event time moved from {} to {} without time passing",
                fmu.id,
                info.nextEventTime,
                again.nextEventTime
            );
        }
        if first {
            crate::outcome::info(format!("the initial event info: {info:?}"));
            first = false;
        }
        events += 1;
        assert_eq!(inst.enter_continuous_time_mode(), fmi2OK, "{}", inst.log_text());
        let target = if info.nextEventTimeDefined == fmi2True {
            info.nextEventTime
        } else {
            now + 0.01
        };
        // Integrate up to the event (no state events expected before: checked by Euler), at
        // 1e-4 s or the default experiment's step where that is finer (a stiff model).
        let h = crate::instance::step_size(fmu).min(1e-4);
        let mut euler = Euler::new(&inst, h, &info);
        euler.next_event = None;
        while inst.time + h < target {
            euler.step(&mut inst);
            assert_eq!(euler.events, 0, "{}: an event before t = {target}", fmu.id);
        }
        assert_eq!(inst.set_time(target), fmi2OK, "{}: {}", fmu.id, inst.log_text());
        assert_eq!(inst.enter_event_mode(), fmi2OK, "{}: {}", fmu.id, inst.log_text());
    }
}

pub fn model_exchange_an_explicit_euler_run_gives_finite_outputs(fmu: &Fmu) {
    needs_me(fmu);
    // 1 s at 1e-4 s (or at the default experiment's step, where that is finer: a stiff model).
    let h = crate::instance::step_size(fmu).min(1e-4);
    let steps = (1.0 / h).round() as usize;
    let (mut inst, mut euler) = {
        let mut inst = Instance::new_me(fmu);
        let info = inst.me_initialize();
        let euler = Euler::new(&inst, h, &info);
        (inst, euler)
    };
    let reals = fmu.md.vrs_of_type(Type::Real);
    // A step that reaches a time event ends there, so a model with time events takes more
    // steps than 1 / h to reach 1 s (and ends within one step after it).
    let mut n = 0;
    while inst.time < 1.0 - 0.5 * h {
        assert!(
            n < 10 * steps,
            "{}: more than {} steps to reach 1 s (t = {})",
            fmu.id,
            10 * steps,
            inst.time
        );
        euler.step(&mut inst);
        if n % 100 == 99 || inst.time >= 1.0 - 0.5 * h {
            let (s, y) = inst.get_real(&reals);
            assert_eq!(s, fmi2OK, "{}: {}", fmu.id, inst.log_text());
            if let Some(i) = y.iter().position(|v| !v.is_finite()) {
                panic!(
                    "{}: at t = {}: '{}' = {}",
                    fmu.id,
                    inst.time,
                    fmu.md.of_type(Type::Real).nth(i).unwrap().name,
                    y[i]
                );
            }
        }
        n += 1;
    }
    assert!(inst.time < 1.0 + h, "{}: the run ended at t = {}", fmu.id, inst.time);
    assert_eq!(inst.enter_event_mode(), fmi2OK, "{}", inst.log_text());
    assert_eq!(inst.terminate(), fmi2OK, "{}", inst.log_text());
    info(format!(
        "{n} steps of {h} s (or up to a time event), {} events",
        euler.events
    ));
}

/// The events of a run, as an importer handles them (the explicit-Euler run of
/// [`Euler`], up to the default experiment's stop time, at most [`crate::outcome::MAX_RUN_STEPS`]
/// steps): every time event the FMU
/// announces is reached exactly and is followed by a later one (or none); the event iteration
/// settles within 100 rounds ([`Instance::event_iteration`]); the event indicators are a
/// function of time and states (the same states set again give the same indicators, bit for
/// bit, and fmi2NewDiscreteStates leaves them finite); the count of indicators is the
/// description's.
pub fn model_exchange_events_are_reached_settle_and_follow_the_states(fmu: &Fmu) {
    needs_me(fmu);
    let h = crate::instance::step_size(fmu).min(1e-3);
    let stop = fmu
        .md
        .default_experiment
        .stop_time()
        .unwrap_or(1.0)
        .clamp(h, crate::outcome::MAX_RUN_STEPS * h);
    // The default experiment from the start values first (what the FMU's user runs); where no
    // event happens there and the FMU has inputs, again with the inputs moved off their start
    // values (a model whose events depend on an input).
    let mut run = events_run(fmu, h, stop, false);
    let mut how = "from the start values";
    if run.events == 0 && !crate::instance::excitation(fmu).is_empty() {
        run = events_run(fmu, h, stop, true);
        how = "with the inputs moved off their start values (none happened from the start values)";
    }
    let EventsRun {
        steps,
        events,
        time_events,
        indicators,
    } = run;
    if events == 0 && indicators == 0 {
        limitation(format!(
            "{NOT_DECLARED}events: no event indicator, no time event in {stop} s"
        ));
    } else if events == 0 {
        limitation(format!(
            "{}events: none in {stop} s of explicit Euler from the start values, nor with the inputs moved off \
             them (the default experiment's stop time, at most {} steps): the {indicators} event indicators never \
             changed domain",
            crate::outcome::NOT_EXERCISED,
            crate::outcome::MAX_RUN_STEPS,
        ));
    }
    info(format!(
        "{steps} explicit-Euler steps to t = {stop} {how}: {events} events, {time_events} of them time events, \
         {indicators} event indicators"
    ));
}

/// What one run of [`model_exchange_events_are_reached_settle_and_follow_the_states`] saw.
struct EventsRun {
    steps: usize,
    events: usize,
    time_events: usize,
    indicators: usize,
}

/// One run of [`model_exchange_events_are_reached_settle_and_follow_the_states`] to `stop`, its
/// inputs at their start values or (`excited`) moved off them.
fn events_run(fmu: &Fmu, h: f64, stop: f64, excited: bool) -> EventsRun {
    let mut inst = Instance::new_me(fmu);
    let info0 = if excited {
        inst.me_initialize()
    } else {
        inst.me_initialize_at_start()
    };
    let mut euler = Euler::new(&inst, h, &info0);
    let (s, z) = inst.get_event_indicators();
    assert_eq!(s, fmi2OK, "{}: {}", fmu.id, inst.log_text());
    assert_eq!(
        z.len(),
        fmu.md.number_of_event_indicators,
        "{}: fmi2GetEventIndicators with numberOfEventIndicators values",
        fmu.id
    );
    let (mut time_events, mut n) = (0usize, 0usize);
    while inst.time < stop - 0.5 * h && !euler.terminated {
        assert!(
            n < 100 * ((stop / h) as usize + 1),
            "{}: no end of the run at t = {}",
            fmu.id,
            inst.time
        );
        n += 1;
        let due = euler.next_event.filter(|te| *te <= inst.time + h);
        let before = euler.events;
        euler.step(&mut inst);
        if let Some(te) = due {
            time_events += 1;
            assert_eq!(
                inst.time.to_bits(),
                te.max(inst.time - h).to_bits(),
                "{}: the step to the time event at {te} ended at {}",
                fmu.id,
                inst.time
            );
            assert_eq!(euler.events, before + 1, "{}: no event at the time event {te}", fmu.id);
            if let Some(next) = euler.next_event {
                assert!(
                    next > te,
                    "{}: after the time event at {te} the next one is at {next}, not later",
                    fmu.id
                );
            }
        }
        if n % 50 == 0 && !z.is_empty() {
            // The indicators follow the states: the same states set again give the same values.
            let (s1, z1) = inst.get_event_indicators();
            let (s2, x) = inst.get_continuous_states();
            let s3 = inst.set_continuous_states(&x);
            let (s4, z2) = inst.get_event_indicators();
            assert_eq!([s1, s2, s3, s4], [fmi2OK; 4], "{}: {}", fmu.id, inst.log_text());
            assert_eq!(
                bits(&z1),
                bits(&z2),
                "{}: indicators at t = {} after the same states",
                fmu.id,
                inst.time
            );
            assert!(
                z1.iter().all(|v| v.is_finite()),
                "{}: indicators {z1:?} at t = {}",
                fmu.id,
                inst.time
            );
        }
    }
    if euler.terminated {
        info(format!("the model ended the simulation at t = {}", inst.time));
    } else {
        assert_eq!(inst.enter_event_mode(), fmi2OK, "{}", inst.log_text());
    }
    assert_eq!(inst.terminate(), fmi2OK, "{}", inst.log_text());
    EventsRun {
        steps: n,
        events: euler.events,
        time_events,
        indicators: z.len(),
    }
}

/// The calls that continue a run from a saved state: in EventMode the event iteration first.
fn continue_from(inst: &mut Instance, euler: &Euler, event_mode: bool, steps: usize) -> Vec<Vec<u64>> {
    let mut euler = euler.clone();
    let mut out = vec![];
    if event_mode {
        let info = inst.event_iteration();
        assert_eq!(inst.enter_continuous_time_mode(), fmi2OK, "{}", inst.log_text());
        euler.next_event = (info.nextEventTimeDefined == fmi2True).then_some(info.nextEventTime);
        out.push(me_observe(inst));
    }
    for _ in 0..steps {
        euler.step(inst);
        out.push(me_observe(inst));
    }
    out
}

pub fn model_exchange_fmu_states_in_event_and_continuous_time_mode_continue_bit_identically(fmu: &Fmu) {
    needs_me(fmu);
    if !me::can_snapshot_me(fmu) {
        skip_not_declared("canGetAndSetFMUstate and canSerializeFMUstate in <ModelExchange>");
    }
    let observed = fmu.me_state_codes().is_ok();
    if !observed {
        limitation("the state machine's state after restoring is not observed");
    }
    for mode in [ContinuousTimeMode, EventMode] {
        let (mut inst, euler) = advanced(fmu, 20);
        if mode == EventMode {
            assert_eq!(inst.enter_event_mode(), fmi2OK, "{}", inst.log_text());
        }
        let t = inst.time;
        let (st, mut saved) = inst.get_state();
        assert_eq!(
            st,
            fmi2OK,
            "{}: fmi2GetFMUstate in {mode:?}: {}",
            fmu.id,
            inst.log_text()
        );
        let bytes = inst
            .serialize(saved)
            .unwrap_or_else(|s| panic!("{}: serializing in {mode:?}: {s}: {}", fmu.id, inst.log_text()));
        let first = continue_from(&mut inst, &euler, mode == EventMode, 30);
        // Back twice (the state is not consumed), once from Terminated.
        for round in 0..3 {
            if round == 2 {
                assert_eq!(inst.enter_event_mode(), fmi2OK);
                assert_eq!(inst.terminate(), fmi2OK, "{}", inst.log_text());
            }
            assert_eq!(
                inst.set_state(saved),
                fmi2OK,
                "{}: fmi2SetFMUstate: {}",
                fmu.id,
                inst.log_text()
            );
            inst.time = t;
            if observed {
                assert_eq!(
                    inst.me_state(),
                    mode,
                    "{}: the state after restoring a state of {mode:?}",
                    fmu.id
                );
            }
            let now = inst.snapshot();
            if now != bytes {
                let at = now.iter().zip(&bytes).position(|(a, b)| a != b);
                panic!(
                    "{}: restored a state of {mode:?} (round {round}): serialized again it differs (lengths {} and {}, first difference at byte {at:?})",
                    fmu.id,
                    now.len(),
                    bytes.len()
                );
            }
            let again = continue_from(&mut inst, &euler, mode == EventMode, 30);
            assert!(
                again == first,
                "{}: after fmi2SetFMUstate (round {round}) of a state taken in {mode:?}, the run differs at call {:?}",
                fmu.id,
                again.iter().zip(&first).position(|(a, b)| a != b)
            );
        }
        assert_eq!(inst.free_state(&mut saved), fmi2OK);
        // Deserialized, in another instance.
        let mut other = Instance::new_me(fmu);
        other.restore(&bytes);
        other.time = t;
        let now = other.snapshot();
        assert!(
            now == bytes,
            "{}: a state of {mode:?} deserialized into another instance: serialized again it differs (first difference at byte {:?})",
            fmu.id,
            now.iter().zip(&bytes).position(|(a, b)| a != b)
        );
        // And into this one, after going on from it.
        continue_from(&mut inst, &euler, false, 3);
        inst.restore(&bytes);
        let now = inst.snapshot();
        assert!(
            now == bytes,
            "{}: a state of {mode:?} deserialized into the instance that made it, after going on: serialized again it differs (first difference at byte {:?})",
            fmu.id,
            now.iter().zip(&bytes).position(|(a, b)| a != b)
        );
        if observed {
            assert_eq!(other.me_state(), mode, "{}: a deserialized state of {mode:?}", fmu.id);
        }
        let again = continue_from(&mut other, &euler, mode == EventMode, 30);
        assert!(
            again == first,
            "{}: a state of {mode:?} serialized, deserialized in another instance: the run differs at call {:?}",
            fmu.id,
            again.iter().zip(&first).position(|(a, b)| a != b)
        );
    }
}

pub fn model_exchange_functions_refuse_a_null_component(fmu: &Fmu) {
    let Ok(me) = &fmu.api.me else {
        if fmu.md.me.is_some() {
            needs_me(fmu);
        }
        skip_not_declared("<ModelExchange>, and the binary does not export the model-exchange functions")
    };
    let c: fmi2Component = ptr::null_mut();
    let mut v = [0.0; 4];
    let mut info = fmi2EventInfo {
        newDiscreteStatesNeeded: 0,
        terminateSimulation: 0,
        nominalsOfContinuousStatesChanged: 0,
        valuesOfContinuousStatesChanged: 0,
        nextEventTimeDefined: 0,
        nextEventTime: 0.0,
    };
    let (mut a, mut b) = (0, 0);
    let n = fmu.md.number_of_continuous_states().min(4);
    let ni = fmu.md.number_of_event_indicators.min(4);
    crate::outcome::breadcrumb("model-exchange functions with a NULL component");
    // SAFETY: every function must check the component before touching anything.
    let answers = unsafe {
        [
            ("fmi2EnterEventMode", (me.enter_event_mode)(c)),
            ("fmi2NewDiscreteStates", (me.new_discrete_states)(c, &mut info)),
            ("fmi2EnterContinuousTimeMode", (me.enter_continuous_time_mode)(c)),
            (
                "fmi2CompletedIntegratorStep",
                (me.completed_integrator_step)(c, 0, &mut a, &mut b),
            ),
            ("fmi2SetTime", (me.set_time)(c, 0.0)),
            ("fmi2SetContinuousStates", (me.set_continuous_states)(c, v.as_ptr(), n)),
            ("fmi2GetDerivatives", (me.get_derivatives)(c, v.as_mut_ptr(), n)),
            (
                "fmi2GetEventIndicators",
                (me.get_event_indicators)(c, v.as_mut_ptr(), ni),
            ),
            (
                "fmi2GetContinuousStates",
                (me.get_continuous_states)(c, v.as_mut_ptr(), n),
            ),
            (
                "fmi2GetNominalsOfContinuousStates",
                (me.get_nominals_of_continuous_states)(c, v.as_mut_ptr(), n),
            ),
        ]
    };
    for (f, s) in answers {
        assert_eq!(s, fmi2Error, "{}: {f}(NULL, ...) answered {}", fmu.id, status_name(s));
    }
}
