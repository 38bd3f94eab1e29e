//! Every model-exchange function in every state of the model-exchange state machine (FMI 2.0
//! section 3.2.3): one [`Case`] per function, called with valid arguments in each state.

#![allow(non_upper_case_globals)] // fmi2OK etc. are the standard's names, matched on

use super::{directional_derivative, refusal_logged, same, settable, start_states};
use crate::fmi2::*;
use crate::instance::{Args, Instance, status_name};
use crate::me::{self, ME_REACHABLE, ME_STATES, MeState, MeState::*, needs_me};
use crate::outcome::{info, limitation};
use crate::{Fmu, Type};
use md_reader::Causality;
use std::ptr;

/// FMU states of a donor model-exchange instance, one per model-exchange state, for the
/// functions that take an FMUstate. Of another exporter's FMU: taken in the reachable states
/// (NULL for the others, which are not tried), when the FMU can get and serialize its state.
pub(super) struct Donor<'a> {
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

pub(super) type CallFn = fn(&mut Instance, &mut Donor, MeState) -> fmi2Status;

pub(super) struct Case {
    function: &'static str,
    /// What a valid call answers in an allowed state.
    answers: &'static [fmi2Status],
    /// The state after an allowed call, from the state before.
    next: fn(MeState) -> MeState,
    call: CallFn,
}

// One row per model-exchange function (a table, as the standard's): kept in one function, over ~150
// lines, so that each function's answers, next state and call read in one place.
pub(super) fn cases() -> Vec<Case> {
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
            call: |i, _, _| i.get_string(&i.fmu.md.vrs_of_type(Type::String)).0,
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
                let starts: Vec<String> = vars.iter().map(|v| v.start.clone().unwrap_or_default()).collect();
                i.set_string(&vrs, &starts)
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
                let (st, size) = i.serialized_size(d.states[s as usize]);
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
                let (st, buf) = i.serialize_into(d.states[s as usize], want.len());
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
                i.set_real_input_derivatives(&inputs, &order, &der)
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
                i.get_real_output_derivatives(&outputs, &vec![1; outputs.len()]).0
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
            call: |i, _, _| i.cancel_step(),
        },
        Case {
            function: "fmi2GetStatus",
            answers: &[],
            next: same,
            call: |i, _, _| i.get_status(fmi2DoStepStatus).0,
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
            call: |i, _, _| i.get_integer_status(fmi2PendingStatus).0,
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
            call: |i, _, _| i.get_string_status(fmi2PendingStatus).0,
        },
    ]
}

/// Why a case does not apply to this FMU, if it does not.
pub(super) fn not_applicable(fmu: &Fmu, function: &str) -> Option<&'static str> {
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

pub fn model_exchange_every_function_in_every_state_answers_as_the_standard_says(fmu: &Fmu) {
    if fmu.md.me.is_none() {
        // What applies to an FMU without <ModelExchange>: fmi2ModelExchange is refused.
        let args = Args {
            fmu_type: fmi2ModelExchange,
            ..Args::valid(fmu)
        };
        // Instantiating an interface the FMU does not declare is the importer's mistake, which
        // FMI 2.0.5 leaves undefined: a warning, as in instantiate_refuses_model_exchange_and_unknown_types.
        let log = Instance::with(fmu, &args).err().unwrap_or_else(|| {
            crate::outcome::warned(format!(
                "{}: no <ModelExchange>, but fmi2Instantiate(fmi2ModelExchange) gave an instance: an importer's mistake not detected",
                fmu.id
            ))
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
    let mut mistakes = vec![];
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
            // A call the state machine does not allow is the importer's mistake: FMI 2.0.5 asks
            // the FMU to answer what is allowed, not to detect what is not; undetected, a warning.
            let mut mistake = |what: String| mistakes.push((case.function, what, s, format!("{log:?}")));
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
                    mistake(format!("not allowed, expected fmi2Error, got {}", status_name(status)));
                }
                if !refusal_logged(&inst, &log, case.function) {
                    mistake("not allowed: no fmi2Error message naming the function (under logStatusError)".into());
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
    let grouped = crate::checks::one_line_per_cause(&fmu.id, "model-exchange ", failures);
    for line in crate::checks::one_line_per_cause(&fmu.id, "model-exchange ", mistakes) {
        crate::outcome::warn(line);
    }
    assert!(
        grouped.is_empty(),
        "{} failures:\n{}",
        grouped.len(),
        grouped.join("\n")
    );
}
