//! Every function of the co-simulation interface in every state of the FMI 2.0 state machine
//! (section 4.2.4), for every packaged FMU: allowed → it works and moves to the state the
//! standard says; not allowed → fmi2Error, a logged message naming the function and the state,
//! and the state machine where it was. The table of allowed states is written from the standard
//! ([`crate::standard`]), not taken from the runtime's own table.
//!
//! The state machine is observed through this exporter's serialized FMU state, and the states
//! an FMU cannot reach by itself are entered by restoring a forged one ([`crate::state`]). On
//! another exporter's FMU the functions are called in the states an importer reaches by calls
//! ([`REACHABLE`]), and the state after each call is not observed.

use crate::fmi2::*;
use crate::instance::{Instance, status_name};
use crate::outcome::{convention, limitation};
use crate::standard::{REACHABLE, SETTERS, allowed_states};
use crate::state::State::*;
use crate::state::{STATES, State, forge, name};
use crate::{Fmu, Type};
use std::ptr;

/// FMU states owned by a donor instance, one per state-machine state, to pass to the
/// functions that take an FMUstate. Of another exporter's FMU: taken in the reachable states
/// (NULL for the others, which are not tried), when the FMU can get and serialize its state.
struct Donor<'a> {
    inst: Instance<'a>,
    states: Vec<fmi2FMUstate>,
    bytes: Vec<Vec<u8>>,
}

impl<'a> Donor<'a> {
    fn new(fmu: &'a Fmu) -> Donor<'a> {
        let mut inst = Instance::new(fmu);
        let mut states = vec![ptr::null_mut(); STATES.len()];
        let mut bytes = vec![vec![]; STATES.len()];
        if fmu.own_state_format() {
            inst.initialize();
            let snap = inst.snapshot();
            for s in STATES {
                let b = forge(&snap, s);
                let (st, p) = inst.deserialize(&b);
                assert_eq!(st, fmi2OK, "{}", inst.log_text());
                states[s as usize] = p;
                bytes[s as usize] = b;
            }
        } else if fmu.can_snapshot() {
            let mut take = |inst: &mut Instance, s: State| {
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
            take(&mut inst, StepComplete);
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

type CallFn = fn(&mut Instance, &mut Donor, State) -> fmi2Status;

struct Case {
    function: &'static str,
    /// What a valid call answers in an allowed state.
    answers: &'static [fmi2Status],
    /// For an allowed call: a text its message must contain (for a function this FMU does not
    /// provide, which answers fmi2Error with the reason).
    says: Option<&'static str>,
    /// The state after an allowed call, from the state before.
    next: fn(State) -> State,
    call: CallFn,
}

fn same(s: State) -> State {
    s
}

/// Variables of a type to set in a state: those the standard lets an importer set there (for a
/// state where no set is allowed: those settable in StepComplete, so the call is a real attempt).
fn settable<'a>(inst: &Instance<'a>, ty: Type, s: State) -> (Vec<u32>, Vec<&'a crate::Variable>) {
    let at = if SETTERS.contains(&s) { s } else { StepComplete };
    let vars: Vec<_> = inst
        .fmu
        .md
        .of_type(ty)
        .filter(|v| crate::standard::settable_in(v, &name(at)))
        .collect();
    (vars.iter().map(|v| v.vr).collect(), vars)
}

// One row per function (a table, as the standard's): kept in one function, over ~150 lines, so that
// each function's answers, next state and call read in one place.
fn cases() -> Vec<Case> {
    vec![
        Case {
            function: "fmi2SetDebugLogging",
            answers: &[fmi2OK],
            says: None,
            next: same,
            call: |i, _, _| i.set_debug_logging(true, &[]),
        },
        Case {
            function: "fmi2SetupExperiment",
            answers: &[fmi2OK],
            says: None,
            next: same,
            call: |i, _, _| i.setup(0.0, None),
        },
        Case {
            function: "fmi2EnterInitializationMode",
            answers: &[fmi2OK],
            says: None,
            next: |_| InitializationMode,
            call: |i, _, _| i.enter_init(),
        },
        Case {
            function: "fmi2ExitInitializationMode",
            answers: &[fmi2OK],
            says: None,
            next: |_| StepComplete,
            call: |i, _, _| i.exit_init(),
        },
        Case {
            function: "fmi2Terminate",
            answers: &[fmi2OK],
            says: None,
            next: |_| Terminated,
            call: |i, _, _| i.terminate(),
        },
        Case {
            function: "fmi2Reset",
            answers: &[fmi2OK],
            says: None,
            next: |_| Instantiated,
            call: |i, _, _| i.reset(),
        },
        Case {
            function: "fmi2GetReal",
            answers: &[fmi2OK],
            says: None,
            next: same,
            call: |i, _, _| i.get_real(&i.fmu.md.vrs_of_type(Type::Real)).0,
        },
        Case {
            function: "fmi2GetInteger",
            answers: &[fmi2OK],
            says: None,
            next: same,
            call: |i, _, _| i.get_integer(&i.fmu.md.vrs_of_type(Type::Integer)).0,
        },
        Case {
            function: "fmi2GetBoolean",
            answers: &[fmi2OK],
            says: None,
            next: same,
            call: |i, _, _| i.get_boolean(&i.fmu.md.vrs_of_type(Type::Boolean)).0,
        },
        Case {
            function: "fmi2GetString",
            answers: &[fmi2OK],
            says: None,
            next: same,
            call: |i, _, _| i.get_string(&i.fmu.md.vrs_of_type(Type::String)).0,
        },
        Case {
            function: "fmi2SetReal",
            answers: &[fmi2OK],
            says: None,
            next: same,
            call: |i, _, s| {
                let (vrs, vars) = settable(i, Type::Real, s);
                let values: Vec<f64> = vars.iter().map(|v| v.start_real().unwrap_or(0.0)).collect();
                i.set_real(&vrs, &values)
            },
        },
        Case {
            function: "fmi2SetInteger",
            answers: &[fmi2OK],
            says: None,
            next: same,
            call: |i, _, s| {
                let (vrs, vars) = settable(i, Type::Integer, s);
                let values: Vec<i32> = vars.iter().map(|v| v.start_integer().unwrap_or(0)).collect();
                i.set_integer(&vrs, &values)
            },
        },
        Case {
            function: "fmi2SetBoolean",
            answers: &[fmi2OK],
            says: None,
            next: same,
            call: |i, _, s| {
                let (vrs, vars) = settable(i, Type::Boolean, s);
                let values: Vec<bool> = vars.iter().map(|v| v.start_boolean().unwrap_or(false)).collect();
                i.set_boolean(&vrs, &values)
            },
        },
        Case {
            function: "fmi2SetString",
            answers: &[fmi2OK],
            says: None,
            next: same,
            // Only the Strings the standard lets an importer set in this state (a fixed String
            // parameter is not settable after initialization), each to its start value.
            // Only the Strings the standard lets an importer set in this state (a fixed String
            // parameter is not settable after initialization), each to its start value.
            call: |i, _, s| {
                let (vrs, vars) = settable(i, Type::String, s);
                let starts: Vec<String> = vars.iter().map(|v| v.start.clone().unwrap_or_default()).collect();
                i.set_string(&vrs, &starts)
            },
        },
        Case {
            function: "fmi2GetFMUstate",
            answers: &[fmi2OK],
            says: None,
            next: same,
            call: |i, _, _| {
                let (st, mut p) = i.get_state();
                if st == fmi2OK {
                    assert!(!p.is_null(), "fmi2GetFMUstate answered fmi2OK with a NULL state");
                    // Freed by the instance that made it (allowed wherever Get was).
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
            says: None,
            // The donor's state for state s is in state s: restoring it keeps the state.
            next: same,
            call: |i, d, s| i.set_state(d.states[s as usize]),
        },
        Case {
            function: "fmi2FreeFMUstate",
            answers: &[fmi2OK],
            says: None,
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
            says: None,
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
            says: None,
            next: same,
            call: |i, d, s| {
                let want = &d.bytes[s as usize];
                let (st, buf) = i.serialize_into(d.states[s as usize], want.len());
                if st == fmi2OK {
                    assert_eq!(&buf, want, "serializing a deserialized state must give the same bytes");
                } else {
                    assert!(
                        buf.iter().all(|b| *b == 0),
                        "a refused fmi2SerializeFMUstate wrote bytes"
                    );
                }
                st
            },
        },
        Case {
            function: "fmi2DeSerializeFMUstate",
            answers: &[fmi2OK],
            says: None,
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
            // Of an FMU that does not provide them (providesDirectionalDerivative="false",
            // checked in `directional_derivative_flag...`); one that does must answer fmi2OK
            // (see `answers_of`).
            answers: &[fmi2Error],
            says: Some("providesDirectionalDerivative"),
            next: same,
            call: |i, _, s| {
                let (unknowns, knowns) = if !i.fmu.cs().provides_directional_derivative {
                    let reals = i.fmu.md.vrs_of_type(Type::Real);
                    (reals[reals.len() - 1..].to_vec(), reals[..1].to_vec())
                } else if s == InitializationMode {
                    // What may be asked there is InitialUnknowns: nothing is asked.
                    (vec![], vec![])
                } else {
                    super::directional_derivatives::valid_pair(i.fmu, false)
                };
                super::directional_derivatives::call(i, &unknowns, &knowns).0
            },
        },
        Case {
            function: "fmi2SetRealInputDerivatives",
            answers: &[fmi2OK],
            says: None,
            next: same,
            // nvr = 0: nothing to interpolate, valid whatever canInterpolateInputs says.
            // nvr = 0: nothing to interpolate, valid whatever canInterpolateInputs says.
            call: |i, _, _| i.set_real_input_derivatives(&[], &[], &[]),
        },
        Case {
            function: "fmi2GetRealOutputDerivatives",
            answers: &[fmi2OK],
            says: None,
            next: same,
            call: |i, _, _| i.get_real_output_derivatives(&[], &[]).0,
        },
        Case {
            function: "fmi2DoStep",
            answers: &[fmi2OK],
            says: None,
            next: same,
            call: |i, _, _| {
                let h = crate::instance::step_size(i.fmu);
                i.step(h)
            },
        },
        Case {
            function: "fmi2CancelStep",
            answers: &[],
            says: None,
            next: same,
            call: |i, _, _| i.cancel_step(),
        },
        Case {
            function: "fmi2GetStatus",
            // No asynchronous step: the answer for fmi2DoStepStatus is fmi2Discard.
            answers: &[fmi2Discard],
            says: None,
            next: same,
            call: |i, _, _| i.get_status(fmi2DoStepStatus).0,
        },
        Case {
            function: "fmi2GetRealStatus",
            answers: &[fmi2OK],
            says: None,
            next: same,
            call: |i, _, _| i.last_successful_time().0,
        },
        Case {
            function: "fmi2GetIntegerStatus",
            answers: &[fmi2Discard],
            says: None,
            next: same,
            call: |i, _, _| i.get_integer_status(fmi2PendingStatus).0,
        },
        Case {
            function: "fmi2GetBooleanStatus",
            answers: &[fmi2OK],
            says: None,
            next: same,
            call: |i, _, _| i.terminated().0,
        },
        Case {
            function: "fmi2GetStringStatus",
            answers: &[fmi2Discard],
            says: None,
            next: same,
            call: |i, _, _| i.get_string_status(fmi2PendingStatus).0,
        },
    ]
}

/// An instance of `fmu` in state `s`: reached by the standard's calls where the model can get
/// there, and by restoring a forged FMU state otherwise.
pub(crate) fn instance_in(fmu: &Fmu, s: State) -> Instance<'_> {
    let mut i = Instance::new(fmu);
    let h = crate::instance::step_size(fmu);
    match s {
        Instantiated => {}
        InitializationMode => {
            assert_eq!([i.setup(0.0, None), i.enter_init()], [fmi2OK; 2]);
        }
        _ => {
            i.initialize();
            assert_eq!(i.step(h), fmi2OK, "{}", i.log_text());
            match s {
                StepComplete => {}
                Terminated => assert_eq!(i.terminate(), fmi2OK),
                _ => i.force_state(s),
            }
        }
    }
    if s != Fatal && fmu.own_state_format() {
        assert_eq!(i.machine_state(), s, "{}: could not put an instance in {s:?}", fmu.id);
    }
    i.log();
    i
}

/// What a valid call of the case answers in an allowed state, and what its message must say:
/// fmi2GetDirectionalDerivative of an FMU that provides them answers fmi2OK.
fn answers_of(fmu: &Fmu, case: &Case) -> (&'static [fmi2Status], Option<&'static str>) {
    if case.function == "fmi2GetDirectionalDerivative" && fmu.cs().provides_directional_derivative {
        (&[fmi2OK], None)
    } else {
        (case.answers, case.says)
    }
}

/// Whether the FMU declares no support for the function (a capability flag of
/// `<CoSimulation>` is false): it may then answer fmi2Error with a logged reason.
fn unsupported(fmu: &Fmu, function: &str) -> bool {
    let cs = fmu.cs();
    match function {
        "fmi2SetRealInputDerivatives" => !cs.can_interpolate_inputs,
        "fmi2GetRealOutputDerivatives" => cs.max_output_derivative_order == 0,
        "fmi2GetStatus" | "fmi2GetIntegerStatus" | "fmi2GetStringStatus" => !cs.can_run_asynchronuously,
        _ => false,
    }
}

/// Why a case does not apply to this FMU, if it does not.
fn not_applicable(fmu: &Fmu, function: &str) -> Option<&'static str> {
    let cs = fmu.cs();
    match function {
        "fmi2GetFMUstate" | "fmi2SetFMUstate" if !cs.can_get_and_set_fmu_state => {
            Some("the FMU does not declare canGetAndSetFMUstate")
        }
        "fmi2FreeFMUstate" | "fmi2SerializedFMUstateSize" | "fmi2SerializeFMUstate" | "fmi2DeSerializeFMUstate"
            if !fmu.can_snapshot() =>
        {
            Some("the FMU does not declare canGetAndSetFMUstate and canSerializeFMUstate")
        }
        _ => None,
    }
}

pub fn every_function_in_every_state_answers_as_the_standard_says(fmu: &Fmu) {
    let mut failures = vec![];
    let mut mistakes = vec![];
    let own = fmu.own_state_format();
    if !own {
        limitation(
            "functions are called only in Instantiated, InitializationMode, StepComplete and Terminated (the other states need a forged FMU state)",
        );
        limitation("the state after each call is not observed (only this exporter's serialized state shows it)");
    }
    let mut donor = Donor::new(fmu);
    for case in cases() {
        if let Some(why) = not_applicable(fmu, case.function) {
            limitation(format!("{} not tried: {why}", case.function));
            continue;
        }
        let (answers, says) = answers_of(fmu, &case);
        for s in STATES.into_iter().filter(|s| own || REACHABLE.contains(s)) {
            let mut inst = instance_in(fmu, s);
            let status = (case.call)(&mut inst, &mut donor, s);
            let log = inst.log();
            let allowed = allowed_states(case.function).contains(&s);
            let mut fail = |what: String| failures.push((case.function, what, s, format!("{log:?}")));
            // A call the state machine does not allow is the importer's mistake: FMI 2.0.5 asks
            // the FMU to answer what is allowed, not to detect what is not; undetected, a warning.
            let mut mistake = |what: String| mistakes.push((case.function, what, s, format!("{log:?}")));
            let refusal = log.iter().find(|e| e.text.contains("not allowed in state"));
            // This exporter answers such a call as if supported (nothing to do); another
            // exporter's FMU may refuse it with a reason, as the checklist asks.
            let declined = allowed
                && !own
                && status == fmi2Error
                && unsupported(fmu, case.function)
                && log.iter().any(|e| e.status == fmi2Error);
            if declined {
                limitation(format!(
                    "{} answered fmi2Error with a reason (the FMU declares no support for it): accepted",
                    case.function
                ));
            }
            if allowed {
                if !answers.contains(&status) && !declined {
                    fail(format!("allowed, expected {:?}, got {}", answers, status_name(status)));
                }
                if let Some(e) = refusal {
                    fail(format!("allowed, but refused: {}", e.text));
                }
                if let Some(text) = says
                    && !log
                        .iter()
                        .any(|e| e.text.contains(case.function) && e.text.contains(text))
                    && !(status != fmi2OK && inst.says(&log, status, &[case.function, text]))
                {
                    fail(format!("expected a message with '{text}'"));
                }
            } else {
                if status != fmi2Error {
                    mistake(format!("not allowed, expected fmi2Error, got {}", status_name(status)));
                }
                let state = format!("state {}", name(s));
                let named = if own {
                    log.iter().any(|e| {
                        e.status == fmi2Error
                            && e.category == "logStatusError"
                            && e.text.contains(case.function)
                            && e.text.contains(&state)
                    })
                } else {
                    convention(fmu, "refusals under category logStatusError");
                    inst.says(&log, fmi2Error, &[case.function, &state])
                };
                if !named {
                    mistake("not allowed: no logStatusError message naming the function and the state".into());
                }
            }
            if s == Fatal || !own {
                continue;
            }
            let after = inst.machine_state();
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
    let grouped = super::one_line_per_cause(&fmu.id, "", failures);
    for line in crate::checks::one_line_per_cause(&fmu.id, "", mistakes) {
        crate::outcome::warn(line);
    }
    assert!(
        grouped.is_empty(),
        "{} failures:\n{}",
        grouped.len(),
        grouped.join("\n")
    );
}

pub fn a_null_component_is_refused_by_every_function(fmu: &Fmu) {
    // The calls go through the call log of a live instance (made first, in Instantiated, and
    // given to no call), so that a failure leaves a reproducer with them: `fmi2DoStep
    // component=NULL -> Error`, which `cargo fmu replay` makes again.
    let args = crate::instance::Args {
        fmu_type: if fmu.md.cs.is_none() {
            fmi2ModelExchange
        } else {
            fmi2CoSimulation
        },
        ..crate::instance::Args::valid(fmu)
    };
    let inst = Instance::with(fmu, &args).unwrap_or_else(|log| panic!("{}: fmi2Instantiate refused: {log:?}", fmu.id));
    let answers = crate::instance_calls::NULL_COMPONENT_PROBES.map(|f| {
        let s = inst.null_component(f);
        crate::calllog::standard_requires(crate::replay::Expected::ERROR);
        (f, s)
    });
    for (f, s) in answers {
        assert_eq!(s, fmi2Error, "{}: {f}(NULL, ...) answered {}", fmu.id, status_name(s));
    }
    // Through the call log: `fmi2FreeInstance component=NULL` (a crash in it is the report's,
    // with the call's breadcrumb).
    inst.free_instance_null();
}

pub fn version_and_platform_are_the_standards(fmu: &Fmu) {
    // SAFETY: static NUL-terminated strings.
    let (v, p) = unsafe {
        (
            std::ffi::CStr::from_ptr((fmu.api.get_version)()),
            std::ffi::CStr::from_ptr((fmu.api.get_types_platform)()),
        )
    };
    assert_eq!(v, c"2.0", "{}: fmi2GetVersion", fmu.id);
    assert_eq!(p, c"default", "{}: fmi2GetTypesPlatform", fmu.id);
    assert_eq!(fmu.md.fmi_version, "2.0", "{}: fmiVersion", fmu.id);
}

pub fn terminate_twice_is_refused_with_a_message(fmu: &Fmu) {
    let mut i = Instance::new(fmu);
    i.initialize();
    assert_eq!(i.terminate(), fmi2OK);
    i.log();
    let second = i.terminate();
    crate::calllog::standard_requires(crate::replay::Expected::ERROR);
    assert_eq!(second, fmi2Error, "{}: the second fmi2Terminate", fmu.id);
    let log = i.log();
    assert!(
        i.says(&log, fmi2Error, &["fmi2Terminate is not allowed in state Terminated"]),
        "{}: {log:?}",
        fmu.id
    );
    let own = fmu.own_state_format();
    if own {
        assert_eq!(i.machine_state(), Terminated);
    }
    // Still usable as the standard says: get, reset.
    assert_eq!(i.get_real(&fmu.md.vrs_of_type(Type::Real)).0, fmi2OK);
    assert_eq!(i.reset(), fmi2OK);
    if own {
        assert_eq!(i.machine_state(), Instantiated);
    }
}
