//! The FMI 3.0 checks. Each is a `fn(&Fmu3)` that returns when the FMU passed and panics with
//! what was expected and what came instead when it did not (skips and limitations as in
//! [`crate::outcome`]). Written from the FMI 3.0 standard: the state machine of section 4.2.x /
//! 3.2.x (Co-Simulation, Model Exchange), the function descriptions of section 2.3, the model
//! description of section 2.4; nothing here knows rustfmu or a particular model.

use super::Type;
use super::api::Api;
use super::standard::{State, settable_in};
use super::types::*;
use super::{Fmu3, Inst, euler_step};
use crate::checks::Group;
use crate::outcome::{info, limitation, skip, skip_not_declared};
use fmi_description::{Causality, Initial, Variability};
use std::ffi::CString;
use std::ptr::{null, null_mut};

/// A named FMI 3.0 check.
#[derive(Clone, Copy)]
pub struct Check3 {
    pub name: &'static str,
    pub group: Group,
    pub run: fn(&Fmu3),
}

impl Check3 {
    pub fn run_on(&self, fmu: &Fmu3) -> (crate::outcome::Outcome, crate::outcome::Findings) {
        crate::outcome::capture(|| (self.run)(fmu))
    }
    pub fn matches(&self, filter: &str) -> bool {
        self.name.contains(filter) || self.group.name().contains(filter)
    }
}

macro_rules! registry {
    ($($group:ident: {$($name:ident),* $(,)?};)*) => {
        /// Every FMI 3.0 check, in report order.
        pub fn all_checks() -> &'static [Check3] {
            &[$($(Check3 { name: stringify!($name), group: Group::$group, run: $name },)*)*]
        }
    };
}

registry! {
    Native: {
        fmi3_the_binary_exports_every_fmi3_function_and_no_others,
    };
    Calls: {
        fmi3_get_version_is_3_0,
        fmi3_instantiate_refuses_a_wrong_or_null_token_or_name_and_event_mode_with_null,
        fmi3_bad_arguments_are_refused_with_a_message_and_change_nothing,
        fmi3_each_variable_can_be_set_exactly_where_the_standard_allows_it,
        fmi3_start_values_are_readable_in_instantiated,
        fmi3_the_time_variable_reads_the_current_time_and_cannot_be_set,
        fmi3_do_step_output_arguments_are_truthful,
        fmi3_set_debug_logging_refuses_unknown_categories,
    };
    StateMachine: {
        fmi3_co_simulation_every_function_in_every_state_answers_as_the_standard_says,
        fmi3_model_exchange_every_function_in_every_state_answers_as_the_standard_says,
        fmi3_reset_from_every_state_then_a_rerun_is_bit_identical,
        fmi3_after_fmi3_error_the_instance_is_terminated_until_reset_or_set_fmu_state,
        fmi3_a_null_instance_is_refused_by_every_function,
    };
    ModelExchange: {
        fmi3_model_exchange_states_and_derivatives_are_consistent,
        fmi3_model_exchange_an_explicit_euler_run_follows_the_co_simulation_run,
    };
    DirectionalDerivatives: {
        fmi3_co_simulation_directional_derivatives_match_finite_differences_and_the_adjoint_is_the_transpose,
        fmi3_model_exchange_directional_derivatives_match_finite_differences_and_the_adjoint_is_the_transpose,
    };
    FmuState: {
        fmi3_fmu_state_get_set_and_serialize_round_trips_continue_bit_identically,
        fmi3_damaged_serialized_states_and_states_of_other_fmus_are_refused,
        fmi3_a_state_serialized_here_restores_in_another_process_and_continues_identically,
    };
    Instances: {
        fmi3_interleaved_instances_and_instances_on_threads_match_a_single_run,
    };
    Memory: {
        fmi3_ten_thousand_instantiate_free_cycles_leave_memory_flat,
    };
    RandomSequences: {
        fmi3_random_call_sequences_never_crash_and_keep_status_consistent,
    };
    Native: {
        fmi3_a_c_host_runs_co_simulation_and_model_exchange_clean_under_valgrind,
    };
}

pub fn find(name: &str) -> Option<&'static Check3> {
    all_checks().iter().find(|c| c.name == name)
}

/// Runs the check of that name on every packaged FMI 3.0 FMU ([`super::all3`]), strictly (a
/// skip other than "not declared" and a partial pass fail), for the workspace's `#[test]`s.
pub fn on_every_fmu3(name: &str) {
    use crate::outcome::Outcome;
    let check = find(name).unwrap_or_else(|| panic!("no FMI 3.0 check named {name}"));
    let mut failures = vec![];
    for fmu in super::all3() {
        let (outcome, findings) = check.run_on(fmu);
        for line in &findings.info {
            println!("{}: {line}", fmu.id);
        }
        match outcome {
            Outcome::Pass if findings.limitations.is_empty() => {}
            Outcome::Pass => failures.push(format!(
                "{}: {name} tested only partly: {}",
                fmu.id,
                findings.limitations.join("; ")
            )),
            Outcome::Skip(why) if why.starts_with(crate::outcome::NOT_DECLARED) => {
                println!("{}: {name} skipped: {why}", fmu.id)
            }
            Outcome::Skip(why) => failures.push(format!("{}: {name} skipped: {why}", fmu.id)),
            Outcome::Fail(m) => failures.push(m),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

// ---------------------------------------------------------------------------------------------
// Helpers

fn cs_only(fmu: &Fmu3) {
    if fmu.md.cs.is_none() {
        skip_not_declared("<CoSimulation>");
    }
}
fn me_only(fmu: &Fmu3) {
    if fmu.md.me.is_none() {
        skip_not_declared("<ModelExchange>");
    }
}

/// An instance of the interface brought into `state`.
fn in_state(fmu: &Fmu3, me: bool, state: State) -> Inst<'_> {
    let mut i = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
    let id = &fmu.id;
    let api = &fmu.api;
    if state == State::Instantiated {
        return i;
    }
    assert_eq!(
        i.enter_init(0.0),
        fmi3OK,
        "{id}: fmi3EnterInitializationMode: {}",
        i.log_text()
    );
    if state == State::InitializationMode {
        return i;
    }
    assert_eq!(
        i.exit_init(),
        fmi3OK,
        "{id}: fmi3ExitInitializationMode: {}",
        i.log_text()
    );
    if me {
        i.event_iteration();
        if state == State::ContinuousTimeMode {
            assert_eq!(
                i.call("fmi3EnterContinuousTimeMode", |c| unsafe {
                    (api.enter_continuous_time_mode)(c)
                }),
                fmi3OK
            );
        }
    }
    if state == State::Terminated {
        assert_eq!(
            i.call("fmi3Terminate", |c| unsafe { (api.terminate)(c) }),
            fmi3OK,
            "{id}: fmi3Terminate: {}",
            i.log_text()
        );
    }
    i
}

fn float_inputs(fmu: &Fmu3) -> Vec<&super::Variable> {
    fmu.md
        .of_type(Type::Float64)
        .filter(|v| v.causality == Causality::Input && v.variability == Variability::Continuous)
        .collect()
}

/// A moderate excitation of every continuous Float64 input (inside min/max).
fn excitation(fmu: &Fmu3) -> Vec<(u32, f64)> {
    float_inputs(fmu)
        .iter()
        .enumerate()
        .map(|(k, v)| {
            let mut x = 0.1 * (k as f64 + 1.0);
            if let Some(lo) = v.min {
                x = x.max(lo);
            }
            if let Some(hi) = v.max {
                x = x.min(hi);
            }
            (v.vr, x)
        })
        .collect()
}

fn excite(inst: &Inst) {
    let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(inst.fmu).into_iter().unzip();
    assert_eq!(
        inst.set_f64(&vrs, &vals),
        fmi3OK,
        "{}: setting the inputs: {}",
        inst.fmu.id,
        inst.log_text()
    );
}

/// A run: excitation, initialization, `steps` steps of `h`; every Float64 after each step.
fn run(fmu: &Fmu3, me: bool, steps: usize, h: f64) -> Vec<Vec<u64>> {
    let mut i = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
    excite(&i);
    i.initialize();
    (0..steps)
        .map(|_| {
            i.step(h);
            i.observe()
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Native: symbols

pub fn fmi3_the_binary_exports_every_fmi3_function_and_no_others(fmu: &Fmu3) {
    let so = fmu.so.to_str().unwrap();
    let out = match std::process::Command::new("nm")
        .args(["-D", "--defined-only", so])
        .output()
    {
        Ok(o) => o,
        Err(_) => skip("nm is not installed (tests/setup-env.sh installs it)"),
    };
    assert!(
        out.status.success(),
        "nm -D {so}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let names: Vec<&str> = text.lines().filter_map(|l| l.split_whitespace().nth(2)).collect();
    let linker = ["_init", "_fini", "_edata", "_end", "__bss_start"];
    let foreign: Vec<&&str> = names
        .iter()
        .filter(|n| !n.starts_with("fmi3") && !n.starts_with("fmi2") && !linker.contains(n))
        .collect();
    assert!(
        foreign.is_empty(),
        "{}: exports symbols that are not FMI functions: {foreign:?}",
        fmu.id
    );
    // A binary may implement FMI 2.0 too (rustfmu's `export_fmu!` binaries serve both
    // versions): then its co-simulation functions (34), with model exchange 44.
    let fmi2 = names.iter().filter(|n| n.starts_with("fmi2")).count();
    assert!(
        [0, 34, 44].contains(&fmi2),
        "{}: exports {fmi2} fmi2 names: FMI 2.0 whole (34 functions of co-simulation, 44 with model \
         exchange) or none",
        fmu.id
    );
    let missing: Vec<&&str> = super::api::FUNCTIONS.iter().filter(|f| !names.contains(f)).collect();
    assert!(
        missing.is_empty(),
        "{}: does not export {missing:?} (FMI 3.0 section 2.3: every function of fmi3Functions.h)",
        fmu.id
    );
    let extra: Vec<&&str> = names
        .iter()
        .filter(|n| n.starts_with("fmi3") && !super::api::FUNCTIONS.contains(n))
        .collect();
    assert!(
        extra.is_empty(),
        "{}: exports fmi3 symbols the standard does not define: {extra:?}",
        fmu.id
    );
    info(format!(
        "{} fmi3 functions{}, nothing else",
        super::api::FUNCTIONS.len(),
        if fmi2 > 0 {
            format!(" and FMI 2.0's {fmi2}")
        } else {
            String::new()
        }
    ));
}

// ---------------------------------------------------------------------------------------------
// Calls

pub fn fmi3_get_version_is_3_0(fmu: &Fmu3) {
    // SAFETY: no arguments; returns a static string.
    let v = unsafe { (fmu.api.get_version)() };
    assert!(!v.is_null(), "{}: fmi3GetVersion returned NULL", fmu.id);
    let v = unsafe { std::ffi::CStr::from_ptr(v) }.to_string_lossy().into_owned();
    assert!(
        v.starts_with("3."),
        "{}: fmi3GetVersion returned \"{v}\", not a 3.x version (fmi3Version is \"3.0\")",
        fmu.id
    );
    assert!(
        super::is_fmi3(&fmu.md.fmi_version),
        "{}: fmiVersion \"{}\"",
        fmu.id,
        fmu.md.fmi_version
    );
}

type Instantiate<'a> = dyn Fn(
        *const std::os::raw::c_char,
        *const std::os::raw::c_char,
        bool,
        fmi3LogMessageCallback,
        fmi3InstanceEnvironment,
    ) -> fmi3Instance
    + 'a;

pub fn fmi3_instantiate_refuses_a_wrong_or_null_token_or_name_and_event_mode_with_null(fmu: &Fmu3) {
    let api = &fmu.api;
    let res = CString::new(fmu.resource_path()).unwrap();
    let token = CString::new(fmu.md.token.as_str()).unwrap();
    let wrong = CString::new(format!("{}-wrong", fmu.md.token)).unwrap();
    let name = c"conformance";
    let mut interfaces: Vec<(&str, Box<Instantiate<'_>>)> = vec![];
    if fmu.md.cs.is_some() {
        let res = res.as_ptr();
        interfaces.push((
            "fmi3InstantiateCoSimulation",
            Box::new(move |n, t, event_mode, log, env| unsafe {
                (api.instantiate_co_simulation)(n, t, res, false, false, event_mode, false, null(), 0, env, log, None)
            }),
        ));
    }
    if fmu.md.me.is_some() {
        let res = res.as_ptr();
        interfaces.push((
            "fmi3InstantiateModelExchange",
            Box::new(move |n, t, _, log, env| unsafe {
                (api.instantiate_model_exchange)(n, t, res, false, false, env, log)
            }),
        ));
    }
    for (what, inst) in &interfaces {
        let sink = super::LogSink::default();
        let log = Some(super::log_message as unsafe extern "C" fn(_, _, _, _));
        for (case, n, t) in [
            ("a wrong instantiationToken", name.as_ptr(), wrong.as_ptr()),
            ("a NULL instantiationToken", name.as_ptr(), null()),
            ("a NULL instanceName", null(), token.as_ptr()),
        ] {
            crate::outcome::breadcrumb(&format!("{what} with {case}"));
            let c = inst(n, t, false, log, sink.env());
            if !c.is_null() {
                unsafe { (api.free_instance)(c) };
                panic!("{}: {what} with {case} returned an instance; expected NULL", fmu.id);
            }
        }
        // The right token: an instance, also without a logger, and with a NULL resourcePath.
        crate::outcome::breadcrumb(&format!("{what} without a logMessage callback"));
        let c = inst(name.as_ptr(), token.as_ptr(), false, None, null_mut());
        assert!(
            !c.is_null(),
            "{}: {what} without a logMessage callback returned NULL (it may be NULL: FMI 3.0 section 2.3.1)",
            fmu.id
        );
        unsafe { (api.free_instance)(c) };
        let c = inst(name.as_ptr(), token.as_ptr(), false, log, sink.env());
        assert!(
            !c.is_null(),
            "{}: {what}: NULL with valid arguments: {:?}",
            fmu.id,
            sink.take()
        );
        unsafe { (api.free_instance)(c) };
    }
    if let Some(cs) = &fmu.md.cs {
        if !cs.has_event_mode {
            let sink = super::LogSink::default();
            let c = unsafe {
                (api.instantiate_co_simulation)(
                    name.as_ptr(),
                    token.as_ptr(),
                    res.as_ptr(),
                    false,
                    false,
                    true,
                    false,
                    null(),
                    0,
                    sink.env(),
                    Some(super::log_message),
                    None,
                )
            };
            if !c.is_null() {
                unsafe { (api.free_instance)(c) };
                panic!(
                    "{}: fmi3InstantiateCoSimulation with eventModeUsed = true returned an instance, but <CoSimulation> has no hasEventMode=\"true\": expected NULL",
                    fmu.id
                );
            }
        }
        let c = unsafe {
            (api.instantiate_co_simulation)(
                c"nores".as_ptr(),
                token.as_ptr(),
                null(),
                false,
                false,
                false,
                false,
                null(),
                0,
                null_mut(),
                None,
                None,
            )
        };
        assert!(
            !c.is_null(),
            "{}: fmi3InstantiateCoSimulation with resourcePath = NULL returned NULL",
            fmu.id
        );
        unsafe { (api.free_instance)(c) };
    }
    if !fmu.md.se {
        let c = unsafe {
            (api.instantiate_scheduled_execution)(
                name.as_ptr(),
                token.as_ptr(),
                res.as_ptr(),
                false,
                false,
                null_mut(),
                None,
                None,
                None,
                None,
            )
        };
        if !c.is_null() {
            unsafe { (api.free_instance)(c) };
            panic!(
                "{}: fmi3InstantiateScheduledExecution returned an instance, but there is no <ScheduledExecution>",
                fmu.id
            );
        }
    }
}

/// Runs `f`, which must be refused with fmi3Error, with a message; then the Float64 values
/// must be what they were (`what` says what was passed).
fn refused(inst: &Inst, what: &str, f: impl FnOnce(fmi3Instance) -> fmi3Status) {
    let before = inst.observe();
    let s = inst.call(what, f);
    assert_eq!(
        s,
        fmi3Error,
        "{}: {what}: expected fmi3Error, got {}",
        inst.fmu.id,
        status_name(s)
    );
    assert_eq!(
        inst.observe(),
        before,
        "{}: {what} was refused but changed values",
        inst.fmu.id
    );
}

pub fn fmi3_bad_arguments_are_refused_with_a_message_and_change_nothing(fmu: &Fmu3) {
    for me in [false, true] {
        if (me && fmu.md.me.is_some()) || (!me && fmu.md.cs.is_some()) {
            bad_arguments(fmu, me);
        }
    }
}

fn bad_arguments(fmu: &Fmu3, me: bool) {
    let mut inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
    excite(&inst);
    inst.initialize();
    inst.step(fmu.step_size());
    let api = &fmu.api;
    let md = &fmu.md;
    let unknown = md.unknown_vr();
    let floats = md.vrs_of_type(Type::Float64);
    let f = floats[0];
    let mut out = vec![0.0f64; 4];
    // NULL arrays with n > 0.
    refused(&inst, "fmi3GetFloat64(vrs = NULL, n = 1)", |c| unsafe {
        (api.get_float64)(c, null(), 1, out.as_mut_ptr(), 1)
    });
    refused(&inst, "fmi3GetFloat64(values = NULL, n = 1)", |c| unsafe {
        (api.get_float64)(c, &f, 1, null_mut(), 1)
    });
    refused(&inst, "fmi3SetFloat64(vrs = NULL, n = 1)", |c| unsafe {
        (api.set_float64)(c, null(), 1, [0.0].as_ptr(), 1)
    });
    refused(&inst, "fmi3SetFloat64(values = NULL, n = 1)", |c| unsafe {
        (api.set_float64)(c, &f, 1, null(), 1)
    });
    // nValues != nValueReferences (every variable is a scalar).
    refused(&inst, "fmi3GetFloat64(n = 1, nValues = 2)", |c| unsafe {
        (api.get_float64)(c, &f, 1, out.as_mut_ptr(), 2)
    });
    refused(&inst, "fmi3GetFloat64(n = 1, nValues = 0)", |c| unsafe {
        (api.get_float64)(c, &f, 1, out.as_mut_ptr(), 0)
    });
    // Unknown value references, and a known one with an unknown one (all-or-nothing).
    refused(&inst, &format!("fmi3GetFloat64([{unknown}])"), |c| unsafe {
        (api.get_float64)(c, &unknown, 1, out.as_mut_ptr(), 1)
    });
    let inputs = float_inputs(fmu);
    if let Some(u) = inputs.first() {
        let vrs = [u.vr, unknown];
        refused(&inst, "fmi3SetFloat64([an input, an unknown vr])", |c| unsafe {
            (api.set_float64)(c, vrs.as_ptr(), 2, [0.5, 0.5].as_ptr(), 2)
        });
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            refused(&inst, &format!("fmi3SetFloat64({} = {bad})", u.name), |c| unsafe {
                (api.set_float64)(c, &u.vr, 1, &bad, 1)
            });
        }
        if let Some(hi) = u.max {
            let v = hi + 1.0 + hi.abs();
            refused(
                &inst,
                &format!("fmi3SetFloat64({} = {v} > max {hi})", u.name),
                |c| unsafe { (api.set_float64)(c, &u.vr, 1, &v, 1) },
            );
        }
        if let Some(lo) = u.min {
            let v = lo - 1.0 - lo.abs();
            refused(
                &inst,
                &format!("fmi3SetFloat64({} = {v} < min {lo})", u.name),
                |c| unsafe { (api.set_float64)(c, &u.vr, 1, &v, 1) },
            );
        }
        // all-or-nothing: a good value with a NaN.
        if inputs.len() > 1 {
            let vrs = [inputs[0].vr, inputs[1].vr];
            refused(&inst, "fmi3SetFloat64([input = 0.25, input = NaN])", |c| unsafe {
                (api.set_float64)(c, vrs.as_ptr(), 2, [0.25, f64::NAN].as_ptr(), 2)
            });
        }
    } else {
        info("no continuous Float64 input: NaN/inf/min/max and all-or-nothing of setters not exercised");
    }
    // Wrong types: a Float64 vr through every other getter.
    let mut buf = [0u64; 4];
    let p = buf.as_mut_ptr() as *mut std::ffi::c_void;
    for (name, g) in [
        ("fmi3GetFloat32", api.get_float32),
        ("fmi3GetInt8", api.get_int8),
        ("fmi3GetUInt8", api.get_uint8),
        ("fmi3GetInt16", api.get_int16),
        ("fmi3GetUInt16", api.get_uint16),
        ("fmi3GetUInt32", api.get_uint32),
        ("fmi3GetUInt64", api.get_uint64),
    ] {
        refused(&inst, &format!("{name} of a Float64 (vr {f})"), |c| unsafe {
            g(c, &f, 1, p, 1)
        });
    }
    refused(&inst, "fmi3GetInt32 of a Float64", |c| unsafe {
        (api.get_int32)(c, &f, 1, buf.as_mut_ptr() as *mut i32, 1)
    });
    refused(&inst, "fmi3GetInt64 of a Float64", |c| unsafe {
        (api.get_int64)(c, &f, 1, buf.as_mut_ptr() as *mut i64, 1)
    });
    refused(&inst, "fmi3GetBoolean of a Float64", |c| unsafe {
        (api.get_boolean)(c, &f, 1, buf.as_mut_ptr() as *mut u8, 1)
    });
    let mut s: fmi3String = null();
    refused(&inst, "fmi3GetString of a Float64", |c| unsafe {
        (api.get_string)(c, &f, 1, &mut s, 1)
    });
    let (mut size, mut bin) = (0usize, null::<u8>());
    refused(&inst, "fmi3GetBinary of a Float64", |c| unsafe {
        (api.get_binary)(c, &f, 1, &mut size, &mut bin, 1)
    });
    if let Some(i32v) = md.of_type(Type::Int32).next() {
        let mut x = 0.0;
        refused(
            &inst,
            &format!("fmi3GetFloat64 of the Int32 '{}'", i32v.name),
            |c| unsafe { (api.get_float64)(c, &i32v.vr, 1, &mut x, 1) },
        );
    }
    if let Some(b) = md.of_type(Type::Boolean).next() {
        let mut x = 0i32;
        refused(
            &inst,
            &format!("fmi3GetInt32 of the Boolean '{}'", b.name),
            |c| unsafe { (api.get_int32)(c, &b.vr, 1, &mut x, 1) },
        );
    }
    if let Some(e) = md.of_type(Type::Enumeration).next() {
        let mut x = 0i32;
        refused(
            &inst,
            &format!(
                "fmi3GetInt32 of the Enumeration '{}' (FMI 3.0: Enumerations are Int64)",
                e.name
            ),
            |c| unsafe { (api.get_int32)(c, &e.vr, 1, &mut x, 1) },
        );
        let mut y = 0i64;
        let s = inst.call("fmi3GetInt64 of an Enumeration", |c| unsafe {
            (api.get_int64)(c, &e.vr, 1, &mut y, 1)
        });
        assert_eq!(
            s,
            fmi3OK,
            "{}: fmi3GetInt64 of the Enumeration '{}': {}",
            fmu.id,
            e.name,
            inst.log_text()
        );
    }
    // Setting what may not be set here: outputs, the independent variable, constants.
    let state = if me { State::ContinuousTimeMode } else { State::StepMode };
    for v in md
        .variables
        .iter()
        .filter(|v| v.ty == Type::Float64 && !v.array && !settable_in(v, state))
        .take(8)
    {
        refused(
            &inst,
            &format!(
                "fmi3SetFloat64 of '{}' ({}, {}) in {state:?}",
                v.name, v.causality, v.variability
            ),
            |c| unsafe { (api.set_float64)(c, &v.vr, 1, &0.125, 1) },
        );
    }
    // Zero values with NULL arrays are fine.
    let s = inst.call("fmi3GetFloat64(NULL, 0, NULL, 0)", |c| unsafe {
        (api.get_float64)(c, null(), 0, null_mut(), 0)
    });
    assert_eq!(
        s,
        fmi3OK,
        "{}: fmi3GetFloat64 of no variables with NULL arrays: expected fmi3OK, got {}",
        fmu.id,
        status_name(s)
    );
    // ME vector functions with a wrong size.
    if me {
        let n = md.derivatives.len();
        let mut v = vec![0.0; n + 2];
        refused(&inst, "fmi3GetContinuousStates(nContinuousStates + 1)", |c| unsafe {
            (api.get_continuous_states)(c, v.as_mut_ptr(), n + 1)
        });
        refused(&inst, "fmi3SetContinuousStates(nContinuousStates + 1)", |c| unsafe {
            (api.set_continuous_states)(c, v.as_ptr(), n + 1)
        });
        if n > 0 {
            refused(&inst, "fmi3GetContinuousStateDerivatives(NULL)", |c| unsafe {
                (api.get_continuous_state_derivatives)(c, null_mut(), n)
            });
            let nan = vec![f64::NAN; n];
            refused(&inst, "fmi3SetContinuousStates(NaN...)", |c| unsafe {
                (api.set_continuous_states)(c, nan.as_ptr(), n)
            });
        }
        refused(&inst, "fmi3SetTime(NaN)", |c| unsafe { (api.set_time)(c, f64::NAN) });
    }
}

pub fn fmi3_each_variable_can_be_set_exactly_where_the_standard_allows_it(fmu: &Fmu3) {
    let mut cases = 0;
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) {
            continue;
        }
        let states: &[State] = if me { &State::ME } else { &State::CS };
        for &state in states.iter().filter(|s| **s != State::Terminated) {
            for v in
                fmu.md.variables.iter().filter(|v| {
                    !v.array && matches!(v.ty, Type::Float64 | Type::Int32 | Type::Boolean | Type::Enumeration)
                })
            {
                let inst = in_state(fmu, me, state);
                let api = &fmu.api;
                let s = match v.ty {
                    Type::Float64 => {
                        let mut x = 0.0;
                        // the value it has (where readable), else its start, else 0
                        let got = state != State::Instantiated
                            && inst.call("get", |c| unsafe { (api.get_float64)(c, &v.vr, 1, &mut x, 1) }) == fmi3OK;
                        if !got {
                            x = v.start.as_deref().and_then(|s| s.parse().ok()).unwrap_or(0.0);
                        }
                        inst.call("fmi3SetFloat64", |c| unsafe { (api.set_float64)(c, &v.vr, 1, &x, 1) })
                    }
                    Type::Int32 => {
                        let x: i32 = v.start.as_deref().and_then(|s| s.parse().ok()).unwrap_or(0);
                        inst.call("fmi3SetInt32", |c| unsafe { (api.set_int32)(c, &v.vr, 1, &x, 1) })
                    }
                    Type::Enumeration => {
                        let x: i64 = v.start.as_deref().and_then(|s| s.parse().ok()).unwrap_or(1);
                        inst.call("fmi3SetInt64", |c| unsafe { (api.set_int64)(c, &v.vr, 1, &x, 1) })
                    }
                    _ => {
                        let x = v.start.as_deref() == Some("true");
                        inst.call("fmi3SetBoolean", |c| unsafe { (api.set_boolean)(c, &v.vr, 1, &x, 1) })
                    }
                };
                let want = settable_in(v, state);
                cases += 1;
                if want {
                    assert_eq!(
                        s,
                        fmi3OK,
                        "{}: setting '{}' ({}, {}, initial {:?}) in {state:?} ({}) answered {}: the standard allows it: {}",
                        fmu.id,
                        v.name,
                        v.causality,
                        v.variability,
                        crate::standard::initial(v.causality, v.variability, v.declared_initial),
                        if me { "ME" } else { "CS" },
                        status_name(s),
                        inst.log_text()
                    );
                } else {
                    assert_eq!(
                        s,
                        fmi3Error,
                        "{}: setting '{}' ({}, {}, initial {:?}) in {state:?} ({}) answered {}: the standard does not allow it",
                        fmu.id,
                        v.name,
                        v.causality,
                        v.variability,
                        crate::standard::initial(v.causality, v.variability, v.declared_initial),
                        if me { "ME" } else { "CS" },
                        status_name(s)
                    );
                }
            }
        }
    }
    info(format!("{cases} (variable, state) cases"));
}

/// The scalar variables of element `ty` that have a start value in the description (FMI 3.0,
/// 2.4.7.4: inputs, and initial exact or approx; never the independent variable).
fn with_start(fmu: &Fmu3, ty: Type) -> impl Iterator<Item = &super::Variable> {
    fmu.md.of_type(ty).filter(|v| {
        !v.array
            && v.causality != Causality::Independent
            && v.start.is_some()
            && (v.causality == Causality::Input
                || matches!(
                    crate::standard::initial(v.causality, v.variability, v.declared_initial),
                    Some(Initial::Exact | Initial::Approx)
                ))
    })
}

fn start_vrs(fmu: &Fmu3, ty: Type) -> Vec<u32> {
    with_start(fmu, ty).map(|v| v.vr).collect()
}

/// FMI 3.0.2's state table allows fmi3Get{VariableType} in Instantiated "to get variable start
/// values" (fmi-standard #2174): right after instantiation, every variable with a start value
/// answers it, in its own type's getter, and a value set there is what a get answers next. A
/// variable without a start value (initial calculated) is not what the table speaks of: an FMU
/// may refuse it or answer, but must not crash, and what it answers must be finite.
pub fn fmi3_start_values_are_readable_in_instantiated(fmu: &Fmu3) {
    let mut n = 0;
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) {
            continue;
        }
        let inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        let api = &fmu.api;
        let id = &fmu.id;
        for v in with_start(fmu, Type::Float64) {
            let want: f64 = v
                .start
                .as_deref()
                .unwrap()
                .parse()
                .unwrap_or_else(|e| panic!("{id}: start of {}: {e}", v.name));
            let (s, got) = inst.get_f64(&[v.vr]);
            assert_eq!(
                s,
                fmi3OK,
                "{id}: fmi3GetFloat64 of '{}' in Instantiated: {}: {}",
                v.name,
                status_name(s),
                inst.log_text()
            );
            assert_eq!(
                got[0].to_bits(),
                want.to_bits(),
                "{id}: '{}' in Instantiated: {} (start {want})",
                v.name,
                got[0]
            );
            n += 1;
        }
        // Int32 and Enumeration (read as Int64): the start attribute is the integer.
        macro_rules! integers {
            ($ty:expr, $get:ident, $t:ty, $name:literal) => {
                for v in with_start(fmu, $ty) {
                    let start = v.start.as_deref().unwrap_or_default();
                    let want: $t = start
                        .parse()
                        .unwrap_or_else(|e| panic!("{id}: start '{start}' of {}: {e}", v.name));
                    let mut got: [$t; 1] = [0];
                    let s = inst.call($name, |c| unsafe { (api.$get)(c, &v.vr, 1, got.as_mut_ptr(), 1) });
                    assert_eq!(
                        (s, got[0]),
                        (fmi3OK, want),
                        "{id}: {} of '{}' in Instantiated: {}",
                        $name,
                        v.name,
                        inst.log_text()
                    );
                    n += 1;
                }
            };
        }
        integers!(Type::Int32, get_int32, i32, "fmi3GetInt32");
        integers!(Type::Enumeration, get_int64, i64, "fmi3GetInt64");
        for v in with_start(fmu, Type::Boolean) {
            let want = matches!(v.start.as_deref(), Some("true" | "1"));
            let mut got = [2u8];
            let s = inst.call("fmi3GetBoolean", |c| unsafe {
                (api.get_boolean)(c, &v.vr, 1, got.as_mut_ptr(), 1)
            });
            assert_eq!(
                (s, got[0] != 0),
                (fmi3OK, want),
                "{id}: fmi3GetBoolean of '{}' in Instantiated: {}",
                v.name,
                inst.log_text()
            );
            n += 1;
        }
        for v in with_start(fmu, Type::String) {
            let mut got = [null::<std::ffi::c_char>()];
            let s = inst.call("fmi3GetString", |c| unsafe {
                (api.get_string)(c, &v.vr, 1, got.as_mut_ptr(), 1)
            });
            assert_eq!(
                s,
                fmi3OK,
                "{id}: fmi3GetString of '{}' in Instantiated: {}",
                v.name,
                inst.log_text()
            );
            assert!(!got[0].is_null(), "{id}: fmi3GetString of '{}' gave NULL", v.name);
            // SAFETY: a string the FMU returned, valid until the next call on this instance.
            let text = unsafe { std::ffi::CStr::from_ptr(got[0]) }
                .to_string_lossy()
                .into_owned();
            assert_eq!(
                Some(text.as_str()),
                v.start.as_deref(),
                "{id}: '{}' in Instantiated",
                v.name
            );
            n += 1;
        }
        // A value set in Instantiated is read back there (a settable Float64 one, inside its bounds).
        if let Some((v, x)) = with_start(fmu, Type::Float64)
            .filter(|v| settable_in(v, State::Instantiated))
            .find_map(|v| {
                let start: f64 = v.start.as_deref()?.parse().ok()?;
                let inside = |x: f64| v.min.is_none_or(|m| x >= m) && v.max.is_none_or(|m| x <= m);
                [start * 0.5 + 0.25, start + 1.0, start - 1.0]
                    .into_iter()
                    .find(|x| *x != start && inside(*x))
                    .map(|x| (v, x))
            })
        {
            assert_eq!(
                inst.set_f64(&[v.vr], &[x]),
                fmi3OK,
                "{id}: setting '{}' = {x} in Instantiated: {}",
                v.name,
                inst.log_text()
            );
            let (s, got) = inst.get_f64(&[v.vr]);
            assert_eq!(
                (s, got[0].to_bits()),
                (fmi3OK, x.to_bits()),
                "{id}: '{}' set to {x} in Instantiated reads {}",
                v.name,
                got[0]
            );
        }
        drop(inst);
        // The calculated ones: refused or answered finitely, never a crash.
        for v in fmu.md.of_type(Type::Float64).filter(|v| {
            !v.array
                && crate::standard::initial(v.causality, v.variability, v.declared_initial) == Some(Initial::Calculated)
        }) {
            let inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
            let (s, got) = inst.get_f64(&[v.vr]);
            assert!(
                s == fmi3Error || (s == fmi3OK && got[0].is_finite()),
                "{id}: fmi3GetFloat64 of the calculated '{}' in Instantiated: {} {}",
                v.name,
                status_name(s),
                got[0]
            );
        }
    }
    info(format!("{n} start values read in Instantiated"));
}

pub fn fmi3_the_time_variable_reads_the_current_time_and_cannot_be_set(fmu: &Fmu3) {
    let t = fmu.md.independent().unwrap_or_else(|| {
        panic!(
            "{}: no variable with causality=\"independent\" (FMI 3.0 section 2.4.7.4: exactly one is required)",
            fmu.id
        )
    });
    assert_eq!(
        t.ty,
        Type::Float64,
        "{}: the independent variable '{}' is a {}, not a Float64",
        fmu.id,
        t.name,
        t.ty
    );
    assert!(
        t.start.is_none(),
        "{}: the independent variable has a start value",
        fmu.id
    );
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) {
            continue;
        }
        let mut i = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        let api = &fmu.api;
        assert_eq!(
            i.enter_init(0.25),
            fmi3OK,
            "{}: fmi3EnterInitializationMode(startTime = 0.25): {}",
            fmu.id,
            i.log_text()
        );
        let (s, v) = i.get_f64(&[t.vr]);
        assert_eq!(
            (s, v[0]),
            (fmi3OK, 0.25),
            "{}: {} in initialization mode with startTime 0.25",
            fmu.id,
            t.name
        );
        // On an instance of its own: after fmi3Error the FMU is Terminated.
        let mut other = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        assert_eq!(other.enter_init(0.25), fmi3OK);
        refused(
            &other,
            &format!("fmi3SetFloat64 of the independent variable '{}'", t.name),
            |c| unsafe { (api.set_float64)(c, &t.vr, 1, &1.0, 1) },
        );
        assert_eq!(i.exit_init(), fmi3OK);
        if me {
            i.event_iteration();
            assert_eq!(
                i.call("ctm", |c| unsafe { (api.enter_continuous_time_mode)(c) }),
                fmi3OK
            );
        }
        let h = fmu.step_size();
        for _ in 0..3 {
            i.step(h);
        }
        let (s, v) = i.get_f64(&[t.vr]);
        assert_eq!(s, fmi3OK);
        assert_eq!(
            v[0],
            i.time,
            "{}: {} after 3 steps of {h} from 0.25 ({})",
            fmu.id,
            t.name,
            if me { "ME" } else { "CS" }
        );
    }
}

pub fn fmi3_do_step_output_arguments_are_truthful(fmu: &Fmu3) {
    cs_only(fmu);
    let mut i = Inst::cs(fmu);
    excite(&i);
    i.initialize();
    let h = fmu.step_size();
    for n in 0..10 {
        let t = i.time;
        let (s, flags, last) = i.do_step(h);
        assert_eq!(s, fmi3OK, "{}: fmi3DoStep({t}, {h}): {}", fmu.id, i.log_text());
        assert_eq!(
            flags,
            [0, 0, 0],
            "{}: step {n}: eventHandlingNeeded, terminateSimulation, earlyReturn = {flags:?}: expected all false (no event mode, no early return)",
            fmu.id
        );
        assert_eq!(
            last,
            t + h,
            "{}: step {n}: lastSuccessfulTime {last}, expected t + h = {}",
            fmu.id,
            t + h
        );
    }
    // Refused steps: the instance stays where it was.
    let api = &fmu.api;
    let t = i.time;
    for bad in [0.0, -h, f64::NAN, f64::INFINITY] {
        let (mut a, mut b, mut c2, mut last) = (0u8, 0u8, 0u8, 0.0);
        let s = i.call("fmi3DoStep(bad h)", |c| unsafe {
            (api.do_step)(c, t, bad, true, &mut a, &mut b, &mut c2, &mut last)
        });
        assert_eq!(
            s,
            fmi3Error,
            "{}: fmi3DoStep(t = {t}, h = {bad}): expected fmi3Error, got {}",
            fmu.id,
            status_name(s)
        );
    }
    // After refused steps the instance may be in an error state (FMI 3.0: after fmi3Error only
    // some calls are allowed); a fresh instance continues.
    let mut j = Inst::cs(fmu);
    excite(&j);
    j.initialize();
    let (mut a, mut b, mut c2, mut last) = (0u8, 0u8, 0u8, 0.0);
    let s = j.call("fmi3DoStep(wrong currentCommunicationPoint)", |c| unsafe {
        (api.do_step)(c, 1.0 + 10.0 * h, h, true, &mut a, &mut b, &mut c2, &mut last)
    });
    assert_ne!(
        s, fmi3OK,
        "{}: fmi3DoStep at currentCommunicationPoint 1 + 10 h while the FMU is at 0 answered fmi3OK",
        fmu.id
    );
    // null output pointers with valid step
    let mut k = Inst::cs(fmu);
    k.initialize();
    let s = k.call("fmi3DoStep(NULL outputs)", |c| unsafe {
        (api.do_step)(c, 0.0, h, true, null_mut(), null_mut(), null_mut(), null_mut())
    });
    assert!(
        s == fmi3OK || s == fmi3Error,
        "{}: fmi3DoStep with NULL output pointers: {} (expected fmi3OK or fmi3Error, no crash)",
        fmu.id,
        status_name(s)
    );
    let _ = k.time;
    // A huge step: completed (lastSuccessfulTime = t + h) or discarded (fmi3Discard with a
    // message, t <= lastSuccessfulTime < t + h); then the outputs are readable and the
    // instance can be terminated (FMI 3.0 fmi3DoStep, "fmi3Discard").
    let mut big = Inst::cs(fmu);
    excite(&big);
    big.initialize();
    let huge = 1e3 * fmu.md.default_experiment.stop_time().unwrap_or(1.0).max(1.0);
    let (s, flags, last) = big.do_step(huge);
    if s == fmi3OK {
        assert_eq!(
            last, huge,
            "{}: a completed step of {huge}: lastSuccessfulTime {last}",
            fmu.id
        );
    } else if s == fmi3Discard {
        assert!(
            (0.0..huge).contains(&last),
            "{}: a discarded step of {huge} from 0: lastSuccessfulTime {last}",
            fmu.id
        );
        info(format!("a step of {huge} s: fmi3Discard at lastSuccessfulTime {last}"));
    } else {
        panic!(
            "{}: a step of {huge} s answered {}: expected fmi3OK or fmi3Discard",
            fmu.id,
            status_name(s)
        );
    }
    assert!(
        flags[1] <= 1 && flags[0] == 0 && flags[2] == 0,
        "{}: flags {flags:?} after a huge step",
        fmu.id
    );
    let (g, _) = big.get_f64(&fmu.md.vrs_of_type(Type::Float64));
    assert_eq!(
        g,
        fmi3OK,
        "{}: fmi3GetFloat64 after the huge step: {}",
        fmu.id,
        big.log_text()
    );
    let t = big.call("fmi3Terminate", |c| unsafe { (api.terminate)(c) });
    assert_eq!(
        t,
        fmi3OK,
        "{}: fmi3Terminate after the huge step ({}): {}",
        fmu.id,
        status_name(s),
        big.log_text()
    );
}

pub fn fmi3_set_debug_logging_refuses_unknown_categories(fmu: &Fmu3) {
    let i = if fmu.md.cs.is_some() {
        Inst::cs(fmu)
    } else {
        Inst::me(fmu)
    };
    let api = &fmu.api;
    let cats: Vec<CString> = fmu
        .md
        .log_categories
        .iter()
        .map(|c| CString::new(c.as_str()).unwrap())
        .collect();
    let ptrs: Vec<fmi3String> = cats.iter().map(|c| c.as_ptr()).collect();
    let s = i.call("fmi3SetDebugLogging(true, declared categories)", |c| unsafe {
        (api.set_debug_logging)(c, true, ptrs.len(), ptrs.as_ptr())
    });
    assert_eq!(
        s,
        fmi3OK,
        "{}: fmi3SetDebugLogging with the declared categories {:?}: {}",
        fmu.id,
        fmu.md.log_categories,
        i.log_text()
    );
    let s = i.call("fmi3SetDebugLogging(true, none)", |c| unsafe {
        (api.set_debug_logging)(c, true, 0, null())
    });
    assert_eq!(
        s,
        fmi3OK,
        "{}: fmi3SetDebugLogging(true, 0, NULL): {}",
        fmu.id,
        i.log_text()
    );
    let bad = [c"noSuchCategory".as_ptr()];
    let s = i.call("fmi3SetDebugLogging(unknown)", |c| unsafe {
        (api.set_debug_logging)(c, true, 1, bad.as_ptr())
    });
    assert_eq!(
        s,
        fmi3Error,
        "{}: fmi3SetDebugLogging with an undeclared category: {}",
        fmu.id,
        status_name(s)
    );
    let s = i.call("fmi3SetDebugLogging(NULL, 1)", |c| unsafe {
        (api.set_debug_logging)(c, true, 1, null())
    });
    assert_eq!(
        s,
        fmi3Error,
        "{}: fmi3SetDebugLogging(nCategories = 1, categories = NULL): {}",
        fmu.id,
        status_name(s)
    );
    let s = i.call("fmi3SetDebugLogging(false)", |c| unsafe {
        (api.set_debug_logging)(c, false, 0, null())
    });
    assert_eq!(s, fmi3OK);
}

// ---------------------------------------------------------------------------------------------
// State machine

/// What the standard says of a call in a state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Expect {
    /// Allowed: fmi3OK (or fmi3Warning).
    Ok,
    /// Not allowed: fmi3Error.
    Error,
    /// Allowed by the state machine but refusable because the FMU lacks the capability (no
    /// clocks, no structural parameters, no output derivatives, no dependencies API), or a
    /// cell the standard leaves open: anything but fmi3Fatal and a crash.
    Either,
}

type Call = fn(&Inst) -> fmi3Status;

struct Row {
    name: &'static str,
    call: Call,
    /// (state, me) -> expectation
    rule: fn(State, bool) -> Expect,
}

use State::*;

fn ok_in(states: &[State], s: State) -> Expect {
    if states.contains(&s) { Expect::Ok } else { Expect::Error }
}
fn either_in(states: &[State], s: State) -> Expect {
    if states.contains(&s) {
        Expect::Either
    } else {
        Expect::Error
    }
}

fn me_vec(s: State, me: bool) -> Expect {
    if me {
        ok_in(&[InitializationMode, EventMode, ContinuousTimeMode, Terminated], s)
    } else {
        Expect::Error
    }
}

/// fmi3GetNumberOf* (Model Exchange only): the allowed calls of Instantiated and Event Mode
/// list them; those of Initialization Mode and Terminated do not, but the Reference FMUs allow
/// them in every state: open there, as in Continuous-Time Mode.
fn number_of(s: State, me: bool) -> Expect {
    match (me, s) {
        (false, _) => Expect::Error,
        (true, Instantiated | EventMode) => Expect::Ok,
        (true, _) => Expect::Either,
    }
}

fn first_of(fmu: &Fmu3, ty: Type) -> Option<u32> {
    fmu.md
        .of_type(ty)
        .find(|v| v.causality == Causality::Output)
        .or_else(|| fmu.md.of_type(ty).next())
        .map(|v| v.vr)
}

fn vr_list(fmu: &Fmu3, ty: Type) -> Vec<u32> {
    first_of(fmu, ty).into_iter().collect()
}

/// The Derivative call with valid arguments: one unknown (an output, else a derivative), one
/// known (a continuous input, else a state in ME), or none.
fn derivative_call(i: &Inst, adjoint: bool) -> fmi3Status {
    let (u, k) = derivative_pair(i.fmu, i.me);
    let (nu, nk) = (u.len(), k.len());
    let seed = vec![1.0; if adjoint { nu } else { nk }];
    let mut sens = vec![0.0; if adjoint { nk } else { nu }];
    let f = if adjoint {
        i.api().get_adjoint_derivative
    } else {
        i.api().get_directional_derivative
    };
    i.call("fmi3Get*Derivative", |c| unsafe {
        f(
            c,
            u.as_ptr(),
            nu,
            k.as_ptr(),
            nk,
            seed.as_ptr(),
            seed.len(),
            sens.as_mut_ptr(),
            sens.len(),
        )
    })
}

fn derivative_pair(fmu: &Fmu3, me: bool) -> (Vec<u32>, Vec<u32>) {
    let (u, k) = (unknowns(fmu, me), knowns(fmu, me));
    if u.is_empty() || k.is_empty() {
        return (vec![], vec![]);
    }
    (vec![u[0]], vec![k[0]])
}

/// What the getters' rows read: one variable with a start value (readable in every state the
/// getters are allowed in, Instantiated included), or none.
fn readable(fmu: &Fmu3, ty: Type) -> Vec<u32> {
    with_start(fmu, ty).map(|v| v.vr).take(1).collect()
}

fn rows() -> Vec<Row> {
    macro_rules! get {
        ($f:ident, $ty:expr, $t:ty) => {
            |i: &Inst| {
                let v = readable(i.fmu, $ty);
                let mut out: Vec<$t> = vec![Default::default(); v.len()];
                i.call(stringify!($f), |c| unsafe {
                    (i.api().$f)(c, v.as_ptr(), v.len(), out.as_mut_ptr(), out.len())
                })
            }
        };
    }
    macro_rules! none {
        ($f:ident) => {
            |i: &Inst| {
                i.call(stringify!($f), |c| unsafe {
                    (i.api().$f)(c, null(), 0, null_mut(), 0)
                })
            }
        };
    }
    macro_rules! none_set {
        ($f:ident) => {
            |i: &Inst| {
                i.call(stringify!($f), |c| unsafe {
                    (i.api().$f)(c, null(), 0, null(), 0)
                })
            }
        };
    }
    macro_rules! unary {
        ($f:ident) => {
            |i: &Inst| i.call(stringify!($f), |c| unsafe { (i.api().$f)(c) })
        };
    }
    // Instantiated: FMI 3.0.2's table allows fmi3Get{VariableType} there ("get variable start
    // values", fmi-standard #2174); which variables: fmi3_start_values_are_readable_in_instantiated_....
    let getters = |s: State, _me: bool| {
        ok_in(
            &[
                Instantiated,
                InitializationMode,
                EventMode,
                ContinuousTimeMode,
                StepMode,
                Terminated,
            ],
            s,
        )
    };
    let setters_f64 = |s: State, _me: bool| {
        ok_in(
            &[
                Instantiated,
                InitializationMode,
                EventMode,
                ContinuousTimeMode,
                StepMode,
            ],
            s,
        )
    };
    // The other setters: the standard's table lets ContinuousTimeMode set continuous-time
    // inputs only, which are Float: with no variable the call is open.
    let setters = |s: State, _me: bool| match s {
        ContinuousTimeMode => Expect::Either,
        _ => ok_in(&[Instantiated, InitializationMode, EventMode, StepMode], s),
    };
    vec![
        Row {
            name: "fmi3SetDebugLogging",
            call: |i| {
                i.call("fmi3SetDebugLogging", |c| unsafe {
                    (i.api().set_debug_logging)(c, false, 0, null())
                })
            },
            rule: |_, _| Expect::Ok,
        },
        Row {
            name: "fmi3EnterInitializationMode",
            call: |i| {
                i.call("eim", |c| unsafe {
                    (i.api().enter_initialization_mode)(c, false, 0.0, 0.0, false, 0.0)
                })
            },
            rule: |s, _| ok_in(&[Instantiated], s),
        },
        Row {
            name: "fmi3ExitInitializationMode",
            call: unary!(exit_initialization_mode),
            rule: |s, _| ok_in(&[InitializationMode], s),
        },
        // CS without event mode: never; ME: from continuous-time mode.
        Row {
            name: "fmi3EnterEventMode",
            call: unary!(enter_event_mode),
            rule: |s, me| {
                if me {
                    ok_in(&[ContinuousTimeMode], s)
                } else {
                    Expect::Error
                }
            },
        },
        Row {
            name: "fmi3Terminate",
            call: unary!(terminate),
            rule: |s, _| ok_in(&[EventMode, ContinuousTimeMode, StepMode], s),
        },
        Row {
            name: "fmi3Reset",
            call: unary!(reset),
            rule: |_, _| Expect::Ok,
        },
        Row {
            name: "fmi3GetFloat64",
            call: get!(get_float64, Type::Float64, f64),
            rule: getters,
        },
        Row {
            name: "fmi3GetInt32",
            call: get!(get_int32, Type::Int32, i32),
            rule: getters,
        },
        Row {
            name: "fmi3GetInt64",
            call: get!(get_int64, Type::Enumeration, i64),
            rule: getters,
        },
        Row {
            name: "fmi3GetBoolean",
            call: get!(get_boolean, Type::Boolean, u8),
            rule: getters,
        },
        Row {
            name: "fmi3GetString",
            call: |i| {
                let v = readable(i.fmu, Type::String);
                let mut out = vec![null(); v.len()];
                i.call("fmi3GetString", |c| unsafe {
                    (i.api().get_string)(c, v.as_ptr(), v.len(), out.as_mut_ptr(), out.len())
                })
            },
            rule: getters,
        },
        Row {
            name: "fmi3GetFloat32",
            call: none!(get_float32),
            rule: getters,
        },
        Row {
            name: "fmi3GetInt8",
            call: none!(get_int8),
            rule: getters,
        },
        Row {
            name: "fmi3GetUInt8",
            call: none!(get_uint8),
            rule: getters,
        },
        Row {
            name: "fmi3GetInt16",
            call: none!(get_int16),
            rule: getters,
        },
        Row {
            name: "fmi3GetUInt16",
            call: none!(get_uint16),
            rule: getters,
        },
        Row {
            name: "fmi3GetUInt32",
            call: none!(get_uint32),
            rule: getters,
        },
        Row {
            name: "fmi3GetUInt64",
            call: none!(get_uint64),
            rule: getters,
        },
        Row {
            name: "fmi3GetBinary",
            call: |i| {
                i.call("fmi3GetBinary", |c| unsafe {
                    (i.api().get_binary)(c, null(), 0, null_mut(), null_mut(), 0)
                })
            },
            rule: getters,
        },
        Row {
            name: "fmi3SetFloat64",
            call: none_set!(set_float64),
            rule: setters_f64,
        },
        Row {
            name: "fmi3SetInt32",
            call: none_set!(set_int32),
            rule: setters,
        },
        Row {
            name: "fmi3SetInt64",
            call: none_set!(set_int64),
            rule: setters,
        },
        Row {
            name: "fmi3SetBoolean",
            call: none_set!(set_boolean),
            rule: setters,
        },
        Row {
            name: "fmi3SetString",
            call: none_set!(set_string),
            rule: setters,
        },
        Row {
            name: "fmi3SetFloat32",
            call: none_set!(set_float32),
            rule: setters,
        },
        Row {
            name: "fmi3SetInt8",
            call: none_set!(set_int8),
            rule: setters,
        },
        Row {
            name: "fmi3SetUInt8",
            call: none_set!(set_uint8),
            rule: setters,
        },
        Row {
            name: "fmi3SetInt16",
            call: none_set!(set_int16),
            rule: setters,
        },
        Row {
            name: "fmi3SetUInt16",
            call: none_set!(set_uint16),
            rule: setters,
        },
        Row {
            name: "fmi3SetUInt32",
            call: none_set!(set_uint32),
            rule: setters,
        },
        Row {
            name: "fmi3SetUInt64",
            call: none_set!(set_uint64),
            rule: setters,
        },
        Row {
            name: "fmi3SetBinary",
            call: |i| {
                i.call("fmi3SetBinary", |c| unsafe {
                    (i.api().set_binary)(c, null(), 0, null(), null(), 0)
                })
            },
            rule: setters,
        },
        Row {
            name: "fmi3GetClock",
            call: |i| {
                i.call("fmi3GetClock", |c| unsafe {
                    (i.api().get_clock)(c, null(), 0, null_mut())
                })
            },
            rule: |_, _| Expect::Either,
        },
        Row {
            name: "fmi3SetClock",
            call: |i| i.call("fmi3SetClock", |c| unsafe { (i.api().set_clock)(c, null(), 0, null()) }),
            rule: |_, _| Expect::Either,
        },
        Row {
            name: "fmi3GetNumberOfVariableDependencies",
            call: |i| {
                let vr = first_of(i.fmu, Type::Float64).unwrap_or(0);
                let mut n = 0;
                i.call("fmi3GetNumberOfVariableDependencies", |c| unsafe {
                    (i.api().get_number_of_variable_dependencies)(c, vr, &mut n)
                })
            },
            rule: |_, _| Expect::Either,
        },
        Row {
            name: "fmi3GetVariableDependencies",
            call: |i| {
                let vr = first_of(i.fmu, Type::Float64).unwrap_or(0);
                i.call("fmi3GetVariableDependencies", |c| unsafe {
                    (i.api().get_variable_dependencies)(c, vr, null_mut(), null_mut(), null_mut(), null_mut(), 0)
                })
            },
            rule: |_, _| Expect::Either,
        },
        Row {
            name: "fmi3GetFMUState+FreeFMUState",
            call: |i| {
                let mut st: fmi3FMUState = null_mut();
                let s = i.call("fmi3GetFMUState", |c| unsafe { (i.api().get_fmu_state)(c, &mut st) });
                if s == fmi3OK {
                    let f = i.call("fmi3FreeFMUState", |c| unsafe { (i.api().free_fmu_state)(c, &mut st) });
                    assert_eq!(f, fmi3OK, "{}: fmi3FreeFMUState of a state just taken", i.fmu.id);
                }
                s
            },
            rule: |_, _| Expect::Ok,
        },
        Row {
            name: "fmi3FreeFMUState(NULL state)",
            call: |i| {
                let mut st: fmi3FMUState = null_mut();
                i.call("fmi3FreeFMUState", |c| unsafe { (i.api().free_fmu_state)(c, &mut st) })
            },
            rule: |_, _| Expect::Ok,
        },
        Row {
            name: "fmi3GetDirectionalDerivative",
            call: |i| derivative_call(i, false),
            rule: |s, _| {
                ok_in(
                    &[InitializationMode, EventMode, ContinuousTimeMode, StepMode, Terminated],
                    s,
                )
            },
        },
        Row {
            name: "fmi3GetAdjointDerivative",
            call: |i| derivative_call(i, true),
            rule: |s, _| {
                ok_in(
                    &[InitializationMode, EventMode, ContinuousTimeMode, StepMode, Terminated],
                    s,
                )
            },
        },
        // Allowed by the state machine in Instantiated, EventMode and StepMode, but only for
        // an FMU with structural parameters.
        Row {
            name: "fmi3EnterConfigurationMode",
            call: unary!(enter_configuration_mode),
            rule: |s, _| either_in(&[Instantiated, EventMode, StepMode], s),
        },
        Row {
            name: "fmi3ExitConfigurationMode",
            call: unary!(exit_configuration_mode),
            rule: |_, _| Expect::Error,
        },
        Row {
            name: "fmi3GetIntervalDecimal",
            call: |i| {
                i.call("fmi3GetIntervalDecimal", |c| unsafe {
                    (i.api().get_interval_decimal)(c, null(), 0, null_mut(), null_mut())
                })
            },
            rule: |_, _| Expect::Either,
        },
        Row {
            name: "fmi3GetIntervalFraction",
            call: |i| {
                i.call("fmi3GetIntervalFraction", |c| unsafe {
                    (i.api().get_interval_fraction)(c, null(), 0, null_mut(), null_mut(), null_mut())
                })
            },
            rule: |_, _| Expect::Either,
        },
        Row {
            name: "fmi3GetShiftDecimal",
            call: |i| {
                i.call("fmi3GetShiftDecimal", |c| unsafe {
                    (i.api().get_shift_decimal)(c, null(), 0, null_mut())
                })
            },
            rule: |_, _| Expect::Either,
        },
        Row {
            name: "fmi3GetShiftFraction",
            call: |i| {
                i.call("fmi3GetShiftFraction", |c| unsafe {
                    (i.api().get_shift_fraction)(c, null(), 0, null_mut(), null_mut())
                })
            },
            rule: |_, _| Expect::Either,
        },
        Row {
            name: "fmi3SetIntervalDecimal",
            call: |i| {
                i.call("fmi3SetIntervalDecimal", |c| unsafe {
                    (i.api().set_interval_decimal)(c, null(), 0, null())
                })
            },
            rule: |_, _| Expect::Either,
        },
        Row {
            name: "fmi3SetIntervalFraction",
            call: |i| {
                i.call("fmi3SetIntervalFraction", |c| unsafe {
                    (i.api().set_interval_fraction)(c, null(), 0, null(), null())
                })
            },
            rule: |_, _| Expect::Either,
        },
        Row {
            name: "fmi3SetShiftDecimal",
            call: |i| {
                i.call("fmi3SetShiftDecimal", |c| unsafe {
                    (i.api().set_shift_decimal)(c, null(), 0, null())
                })
            },
            rule: |_, _| Expect::Either,
        },
        Row {
            name: "fmi3SetShiftFraction",
            call: |i| {
                i.call("fmi3SetShiftFraction", |c| unsafe {
                    (i.api().set_shift_fraction)(c, null(), 0, null(), null())
                })
            },
            rule: |_, _| Expect::Either,
        },
        // EventMode (ME); in CS it belongs to Step Mode without event mode: left open.
        Row {
            name: "fmi3EvaluateDiscreteStates",
            call: unary!(evaluate_discrete_states),
            rule: |s, me| {
                if me {
                    ok_in(&[EventMode], s)
                } else {
                    either_in(&[StepMode], s)
                }
            },
        },
        Row {
            name: "fmi3UpdateDiscreteStates",
            call: |i| {
                let mut f = [0u8; 5];
                let mut t = 0.0;
                i.call("fmi3UpdateDiscreteStates", |c| unsafe {
                    let [a, b, cc, d, e] = &mut f;
                    (i.api().update_discrete_states)(c, a, b, cc, d, e, &mut t)
                })
            },
            rule: |s, me| if me { ok_in(&[EventMode], s) } else { Expect::Error },
        },
        Row {
            name: "fmi3EnterContinuousTimeMode",
            call: unary!(enter_continuous_time_mode),
            rule: |s, me| if me { ok_in(&[EventMode], s) } else { Expect::Error },
        },
        Row {
            name: "fmi3CompletedIntegratorStep",
            call: |i| {
                let (mut a, mut b) = (0u8, 0u8);
                i.call("fmi3CompletedIntegratorStep", |c| unsafe {
                    (i.api().completed_integrator_step)(c, true, &mut a, &mut b)
                })
            },
            rule: |s, me| {
                if me {
                    ok_in(&[ContinuousTimeMode], s)
                } else {
                    Expect::Error
                }
            },
        },
        Row {
            name: "fmi3SetTime",
            call: |i| i.call("fmi3SetTime", |c| unsafe { (i.api().set_time)(c, 0.0) }),
            // Continuous-Time Mode; Event Mode's list of allowed calls has no fmi3SetTime, but
            // the Reference FMUs allow it there: open.
            rule: |s, me| {
                if me && s == EventMode {
                    Expect::Either
                } else if me {
                    ok_in(&[ContinuousTimeMode], s)
                } else {
                    Expect::Error
                }
            },
        },
        // Event Mode: not in the 3.0 list of allowed calls, but the 3.0.2 maintenance release
        // allows setting continuous states in more states: open.
        Row {
            name: "fmi3SetContinuousStates",
            call: |i| {
                let n = i.fmu.md.derivatives.len();
                let x = vec![0.0; n];
                i.call("fmi3SetContinuousStates", |c| unsafe {
                    (i.api().set_continuous_states)(c, x.as_ptr(), n)
                })
            },
            rule: |s, me| {
                if !me {
                    Expect::Error
                } else if s == EventMode {
                    Expect::Either
                } else {
                    ok_in(&[ContinuousTimeMode], s)
                }
            },
        },
        Row {
            name: "fmi3GetContinuousStateDerivatives",
            call: |i| {
                i.vector(
                    "d",
                    i.api().get_continuous_state_derivatives,
                    i.fmu.md.derivatives.len(),
                )
                .0
            },
            rule: me_vec,
        },
        Row {
            name: "fmi3GetEventIndicators",
            call: |i| {
                i.vector("e", i.api().get_event_indicators, i.fmu.md.event_indicators.len())
                    .0
            },
            rule: me_vec,
        },
        Row {
            name: "fmi3GetContinuousStates",
            call: |i| {
                i.vector("x", i.api().get_continuous_states, i.fmu.md.derivatives.len())
                    .0
            },
            rule: me_vec,
        },
        Row {
            name: "fmi3GetNominalsOfContinuousStates",
            call: |i| {
                i.vector(
                    "n",
                    i.api().get_nominals_of_continuous_states,
                    i.fmu.md.derivatives.len(),
                )
                .0
            },
            rule: me_vec,
        },
        Row {
            name: "fmi3GetNumberOfEventIndicators",
            call: |i| {
                let mut n = 0;
                i.call("n", |c| unsafe { (i.api().get_number_of_event_indicators)(c, &mut n) })
            },
            rule: number_of,
        },
        Row {
            name: "fmi3GetNumberOfContinuousStates",
            call: |i| {
                let mut n = 0;
                i.call("n", |c| unsafe { (i.api().get_number_of_continuous_states)(c, &mut n) })
            },
            rule: number_of,
        },
        // Only from EventMode of a CS instance with event mode: never here.
        Row {
            name: "fmi3EnterStepMode",
            call: unary!(enter_step_mode),
            rule: |_, _| Expect::Error,
        },
        Row {
            name: "fmi3GetOutputDerivatives",
            call: |i| {
                let v = vr_list(i.fmu, Type::Float64);
                let orders = vec![1i32; v.len()];
                let mut out = vec![0.0; v.len()];
                i.call("fmi3GetOutputDerivatives", |c| unsafe {
                    (i.api().get_output_derivatives)(
                        c,
                        v.as_ptr(),
                        v.len(),
                        orders.as_ptr(),
                        out.as_mut_ptr(),
                        out.len(),
                    )
                })
            },
            rule: |s, me| {
                if me {
                    Expect::Error
                } else {
                    either_in(&[StepMode, Terminated], s)
                }
            },
        },
        Row {
            name: "fmi3DoStep",
            call: |i| {
                let (mut a, mut b, mut d, mut t) = (0u8, 0u8, 0u8, 0.0);
                let h = i.fmu.step_size();
                i.call("fmi3DoStep", |c| unsafe {
                    (i.api().do_step)(c, 0.0, h, true, &mut a, &mut b, &mut d, &mut t)
                })
            },
            rule: |s, me| if me { Expect::Error } else { ok_in(&[StepMode], s) },
        },
        Row {
            name: "fmi3ActivateModelPartition",
            call: |i| {
                i.call("fmi3ActivateModelPartition", |c| unsafe {
                    (i.api().activate_model_partition)(c, 0, 0.0)
                })
            },
            rule: |_, _| Expect::Error,
        },
    ]
}

fn state_table(fmu: &Fmu3, me: bool) {
    let states: &[State] = if me { &State::ME } else { &State::CS };
    let mut failures = vec![];
    let mut open = vec![];
    let mut n = 0;
    for row in rows() {
        for &state in states {
            let inst = in_state(fmu, me, state);
            crate::outcome::breadcrumb(&format!("{} in {state:?}", row.name));
            let s = (row.call)(&inst);
            n += 1;
            let want = (row.rule)(state, me);
            let good = match want {
                Expect::Ok => s == fmi3OK || s == fmi3Warning,
                Expect::Error => s == fmi3Error,
                Expect::Either => s == fmi3OK || s == fmi3Warning || s == fmi3Error || s == fmi3Discard,
            };
            if !good {
                failures.push(format!(
                    "{} in {state:?}: {}, expected {:?} ({})",
                    row.name,
                    status_name(s),
                    want,
                    inst.log_text()
                ));
            } else if want == Expect::Either {
                open.push(format!("{} in {state:?}: {}", row.name, status_name(s)));
            }
            drop(inst);
        }
    }
    // The C API also says fmi3GetVersion works without an instance and FreeInstance(NULL) is a no-op.
    unsafe { (fmu.api.free_instance)(null_mut()) };
    assert!(
        failures.is_empty(),
        "{}: {} of {n} calls answered against the FMI 3.0 state machine ({}):\n{}",
        fmu.id,
        failures.len(),
        if me { "Model Exchange" } else { "Co-Simulation" },
        failures.join("\n")
    );
    info(format!("{n} (function, state) calls as the standard says"));
    info(format!(
        "cells the standard leaves to the FMU's capabilities, as answered: {}",
        open.join("; ")
    ));
    // StepDiscarded and the error states cannot be reached by an importer with valid calls on
    // an FMU that never discards: they are not in the table (see the README).
    info(
        "states not in the table: StepDiscarded, the error states (an importer cannot bring a conformant FMU there on purpose)",
    );
}

pub fn fmi3_co_simulation_every_function_in_every_state_answers_as_the_standard_says(fmu: &Fmu3) {
    cs_only(fmu);
    state_table(fmu, false);
}

pub fn fmi3_model_exchange_every_function_in_every_state_answers_as_the_standard_says(fmu: &Fmu3) {
    me_only(fmu);
    state_table(fmu, true);
}

/// Every function that takes an instance answers fmi3Error to a NULL one, without a crash
/// (there is no instance, so no logger either); fmi3FreeInstance(NULL) is a no-op (FMI 3.0,
/// 2.3.1). The calls are the state table's, plus the serialization functions.
pub fn fmi3_a_null_instance_is_refused_by_every_function(fmu: &Fmu3) {
    let inst = Inst::null(fmu, fmu.md.cs.is_none());
    let api = &fmu.api;
    let mut answers: Vec<(&str, fmi3Status)> = rows().iter().map(|row| (row.name, (row.call)(&inst))).collect();
    let mut size = 0usize;
    let mut st: fmi3FMUState = null_mut();
    let mut buf = [0u8; 64];
    // SAFETY: valid pointers; the FMU must check the instance before touching anything.
    unsafe {
        answers.push((
            "fmi3SerializedFMUStateSize",
            (api.serialized_fmu_state_size)(null_mut(), null_mut(), &mut size),
        ));
        answers.push((
            "fmi3SerializeFMUState",
            (api.serialize_fmu_state)(null_mut(), null_mut(), buf.as_mut_ptr(), buf.len()),
        ));
        answers.push((
            "fmi3DeserializeFMUState",
            (api.deserialize_fmu_state)(null_mut(), buf.as_ptr(), buf.len(), &mut st),
        ));
        (api.free_instance)(null_mut());
    }
    let wrong: Vec<String> = answers
        .iter()
        .filter(|(_, s)| *s != fmi3Error)
        .map(|(f, s)| format!("{f}(NULL, ...): {}", status_name(*s)))
        .collect();
    assert!(
        st.is_null(),
        "{}: fmi3DeserializeFMUState(NULL, ...) wrote a state",
        fmu.id
    );
    assert!(
        wrong.is_empty(),
        "{}: expected fmi3Error for a NULL instance:\n{}",
        fmu.id,
        wrong.join("\n")
    );
    info(format!("{} functions refuse a NULL instance", answers.len()));
}

pub fn fmi3_reset_from_every_state_then_a_rerun_is_bit_identical(fmu: &Fmu3) {
    let h = fmu.step_size();
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) {
            continue;
        }
        let reference = run(fmu, me, 20, h);
        let states: &[State] = if me { &State::ME } else { &State::CS };
        for &state in states {
            let mut i = in_state(fmu, me, state);
            if matches!(state, StepMode | ContinuousTimeMode) {
                excite(&i);
                i.step(h);
            }
            let s = i.call("fmi3Reset", |c| unsafe { (fmu.api.reset)(c) });
            assert_eq!(s, fmi3OK, "{}: fmi3Reset in {state:?}: {}", fmu.id, i.log_text());
            i.time = 0.0;
            excite(&i);
            i.initialize();
            let again: Vec<Vec<u64>> = (0..20)
                .map(|_| {
                    i.step(h);
                    i.observe()
                })
                .collect();
            assert!(
                again == reference,
                "{}: after fmi3Reset in {state:?} ({}), a rerun differs from a run of a new instance",
                fmu.id,
                if me { "ME" } else { "CS" }
            );
        }
    }
}

/// FMI 3.0 section 2.3.1 (super state FMU State Setable): "If any function called in super
/// state FMU State Setable returns fmi3Error, the FMU enters state Terminated." So after a
/// refused call, only what Terminated allows is allowed (getters; fmi3Reset, FMU state
/// functions, fmi3FreeInstance); fmi3DoStep / fmi3EnterEventMode / fmi3Terminate are not.
/// fmi3Reset and fmi3SetFMUState bring the instance back.
pub fn fmi3_after_fmi3_error_the_instance_is_terminated_until_reset_or_set_fmu_state(fmu: &Fmu3) {
    let h = fmu.step_size();
    let api = &fmu.api;
    let mut failures = vec![];
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) {
            continue;
        }
        let what = if me { "ME" } else { "CS" };
        let running = if me { ContinuousTimeMode } else { StepMode };
        // A refused call: an unknown value reference.
        let mut i = in_state(fmu, me, running);
        let saved = fmu.can_snapshot(me).then(|| i.snapshot());
        let bad = fmu.md.unknown_vr();
        assert_eq!(
            i.set_f64(&[bad], &[1.0]),
            fmi3Error,
            "{}: setting an unknown vr",
            fmu.id
        );
        let (s, _) = i.get_f64(&fmu.md.vrs_of_type(Type::Float64));
        if s != fmi3OK {
            failures.push(format!(
                "{what}: fmi3GetFloat64 after an fmi3Error (Terminated allows getters): {}",
                status_name(s)
            ));
        }
        let s = if me {
            i.call("fmi3EnterEventMode", |c| unsafe { (api.enter_event_mode)(c) })
        } else {
            i.do_step(h).0
        };
        if s != fmi3Error {
            failures.push(format!(
                "{what}: {} after an fmi3Error in {running:?} answered {}: the FMU is Terminated then and must refuse it",
                if me { "fmi3EnterEventMode" } else { "fmi3DoStep" },
                status_name(s)
            ));
        }
        let s = i.call("fmi3Terminate", |c| unsafe { (api.terminate)(c) });
        if s != fmi3Error {
            failures.push(format!(
                "{what}: fmi3Terminate after an fmi3Error answered {}: the FMU is Terminated then",
                status_name(s)
            ));
        }
        // Back: fmi3SetFMUState of a state taken before, then steps.
        if let Some(bytes) = saved {
            let mut j = in_state(fmu, me, running);
            let _ = j.set_f64(&[bad], &[1.0]);
            let s = j.restore(&bytes);
            assert_eq!(
                s,
                fmi3OK,
                "{}: {what}: restoring a state after an fmi3Error: {}",
                fmu.id,
                j.log_text()
            );
            j.step(h);
        }
        // Back: fmi3Reset, then a whole run.
        let s = i.call("fmi3Reset", |c| unsafe { (api.reset)(c) });
        assert_eq!(
            s,
            fmi3OK,
            "{}: {what}: fmi3Reset after an fmi3Error: {}",
            fmu.id,
            i.log_text()
        );
        i.time = 0.0;
        i.initialize();
        i.step(h);
    }
    assert!(
        failures.is_empty(),
        "{}: after fmi3Error:\n{}",
        fmu.id,
        failures.join("\n")
    );
}

// ---------------------------------------------------------------------------------------------
// Model exchange

pub fn fmi3_model_exchange_states_and_derivatives_are_consistent(fmu: &Fmu3) {
    me_only(fmu);
    let states = fmu.md.continuous_states().unwrap_or_else(|e| panic!("{}: {e}", fmu.id));
    let mut i = Inst::me(fmu);
    let api = &fmu.api;
    let n = i.n_states();
    assert_eq!(
        n,
        states.len(),
        "{}: fmi3GetNumberOfContinuousStates says {n}, <ModelStructure> lists {} <ContinuousStateDerivative>",
        fmu.id,
        states.len()
    );
    let mut ne = usize::MAX;
    assert_eq!(
        i.call("n", |c| unsafe { (api.get_number_of_event_indicators)(c, &mut ne) }),
        fmi3OK
    );
    assert_eq!(
        ne,
        fmu.md.event_indicators.len(),
        "{}: fmi3GetNumberOfEventIndicators says {ne}, <ModelStructure> lists {} <EventIndicator>",
        fmu.id,
        fmu.md.event_indicators.len()
    );
    excite(&i);
    i.initialize();
    for step in 0..5 {
        let (s, x) = i.vector("fmi3GetContinuousStates", api.get_continuous_states, n);
        assert_eq!(s, fmi3OK);
        let (s, dx) = i.vector(
            "fmi3GetContinuousStateDerivatives",
            api.get_continuous_state_derivatives,
            n,
        );
        assert_eq!(s, fmi3OK);
        let (_, xs) = i.get_f64(&states.iter().map(|p| p.0).collect::<Vec<_>>());
        let (_, ds) = i.get_f64(&states.iter().map(|p| p.1).collect::<Vec<_>>());
        assert_eq!(
            crate::bits(&x),
            crate::bits(&xs),
            "{}: step {step}: fmi3GetContinuousStates differs from fmi3GetFloat64 of the state variables",
            fmu.id
        );
        assert_eq!(
            crate::bits(&dx),
            crate::bits(&ds),
            "{}: step {step}: fmi3GetContinuousStateDerivatives differs from fmi3GetFloat64 of the derivative variables",
            fmu.id
        );
        let (s, nom) = i.vector(
            "fmi3GetNominalsOfContinuousStates",
            api.get_nominals_of_continuous_states,
            n,
        );
        assert_eq!(s, fmi3OK);
        assert!(
            nom.iter().all(|v| v.is_finite() && *v > 0.0),
            "{}: nominals {nom:?} (finite and > 0)",
            fmu.id
        );
        // deterministic: the same states give the same derivatives
        assert_eq!(
            i.call("sx", |c| unsafe { (api.set_continuous_states)(c, x.as_ptr(), n) }),
            fmi3OK
        );
        let (_, dx2) = i.vector(
            "fmi3GetContinuousStateDerivatives",
            api.get_continuous_state_derivatives,
            n,
        );
        assert_eq!(
            crate::bits(&dx),
            crate::bits(&dx2),
            "{}: the same states gave other derivatives",
            fmu.id
        );
        euler_step(&mut i, fmu.step_size());
    }
    // SetTime backwards is refused in continuous-time mode? The standard only requires
    // time to be non-decreasing within an integrator step; not checked.
}

pub fn fmi3_model_exchange_an_explicit_euler_run_follows_the_co_simulation_run(fmu: &Fmu3) {
    me_only(fmu);
    let h = fmu.step_size().min(1e-3);
    let steps = 200;
    let me = run(fmu, true, steps, h);
    let last: Vec<f64> = me.last().unwrap().iter().map(|b| f64::from_bits(*b)).collect();
    assert!(
        last.iter().all(|v| v.is_finite()),
        "{}: non-finite values after {steps} Euler steps of {h}: {last:?}",
        fmu.id
    );
    info(format!(
        "{steps} explicit-Euler steps of {h} s through fmi3 ME calls: finite"
    ));
    if fmu.md.cs.is_some() {
        // Both reach t = steps * h; the co-simulation solver differs, so the agreement is loose.
        let cs = run(fmu, false, steps, h);
        let cs_last: Vec<f64> = cs.last().unwrap().iter().map(|b| f64::from_bits(*b)).collect();
        let vrs = fmu.md.vrs_of_type(Type::Float64);
        let t_vr = fmu.md.independent().map(|v| v.vr);
        for (k, vr) in vrs.iter().enumerate() {
            if Some(*vr) == t_vr {
                assert_eq!(
                    last[k], cs_last[k],
                    "{}: time after {steps} steps: ME {} CS {}",
                    fmu.id, last[k], cs_last[k]
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Directional and adjoint derivatives

fn unknowns(fmu: &Fmu3, me: bool) -> Vec<u32> {
    let mut list = vec![];
    if me {
        list.extend(fmu.md.derivatives.iter().map(|u| u.vr));
    }
    list.extend(
        fmu.md
            .outputs
            .iter()
            .map(|u| u.vr)
            .filter(|vr| fmu.md.by_vr(*vr).is_some_and(|v| v.ty == Type::Float64)),
    );
    list
}

fn knowns(fmu: &Fmu3, me: bool) -> Vec<u32> {
    let mut list = vec![];
    if me {
        list.extend(fmu.md.continuous_states().unwrap_or_default().iter().map(|p| p.0));
    }
    list.extend(float_inputs(fmu).iter().map(|v| v.vr));
    list
}

fn dependencies(fmu: &Fmu3, me: bool, unknown: u32) -> Option<Vec<u32>> {
    let list = if me {
        fmu.md.derivatives.iter().chain(&fmu.md.outputs).collect::<Vec<_>>()
    } else {
        fmu.md.outputs.iter().collect()
    };
    list.iter()
        .find(|u| u.vr == unknown)
        .and_then(|u| u.dependencies.clone())
}

fn derivatives_check(fmu: &Fmu3, me: bool) {
    let i = if me { fmu.md.me.as_ref() } else { fmu.md.cs.as_ref() };
    let Some(i) = i else {
        skip_not_declared(if me { "<ModelExchange>" } else { "<CoSimulation>" })
    };
    if !i.provides_directional_derivatives {
        skip_not_declared("providesDirectionalDerivatives");
    }
    let (u, k) = (unknowns(fmu, me), knowns(fmu, me));
    if u.is_empty() || k.is_empty() {
        skip(format!("no unknowns ({}) or knowns ({})", u.len(), k.len()));
    }
    let states = fmu.md.continuous_states().unwrap_or_default();
    let mut inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
    excite(&inst);
    inst.initialize();
    for _ in 0..20 {
        inst.step(fmu.step_size());
    }
    let api = &fmu.api;
    let (nu, nk) = (u.len(), k.len());
    // J by columns (directional) and by rows (adjoint).
    let mut jd = vec![vec![0.0; nk]; nu];
    for (j, _) in k.iter().enumerate() {
        let mut seed = vec![0.0; nk];
        seed[j] = 1.0;
        let mut sens = vec![f64::NAN; nu];
        let s = inst.call("fmi3GetDirectionalDerivative", |c| unsafe {
            (api.get_directional_derivative)(
                c,
                u.as_ptr(),
                nu,
                k.as_ptr(),
                nk,
                seed.as_ptr(),
                nk,
                sens.as_mut_ptr(),
                nu,
            )
        });
        assert_eq!(
            s,
            fmi3OK,
            "{}: fmi3GetDirectionalDerivative: {}",
            fmu.id,
            inst.log_text()
        );
        for r in 0..nu {
            jd[r][j] = sens[r];
        }
    }
    let mut ja = vec![vec![0.0; nk]; nu];
    if i.provides_adjoint_derivatives {
        for r in 0..nu {
            let mut seed = vec![0.0; nu];
            seed[r] = 1.0;
            let mut sens = vec![f64::NAN; nk];
            let s = inst.call("fmi3GetAdjointDerivative", |c| unsafe {
                (api.get_adjoint_derivative)(
                    c,
                    u.as_ptr(),
                    nu,
                    k.as_ptr(),
                    nk,
                    seed.as_ptr(),
                    nu,
                    sens.as_mut_ptr(),
                    nk,
                )
            });
            assert_eq!(s, fmi3OK, "{}: fmi3GetAdjointDerivative: {}", fmu.id, inst.log_text());
            ja[r] = sens;
        }
        for r in 0..nu {
            for j in 0..nk {
                let (a, b) = (jd[r][j], ja[r][j]);
                assert!(
                    (a - b).abs() <= 1e-12 * (1.0 + a.abs()),
                    "{}: d{}/d{}: directional {a}, adjoint {b}: the adjoint must be the transpose",
                    fmu.id,
                    u[r],
                    k[j]
                );
            }
        }
    } else {
        info("providesAdjointDerivatives is false: the adjoint is not compared");
    }
    // Finite differences: perturb each known, read the unknowns.
    // The unknowns: derivatives through fmi3GetContinuousStateDerivatives (ME), the rest
    // through fmi3GetFloat64.
    let read = |inst: &Inst| -> Vec<f64> {
        let (s, mut all) = inst.get_f64(&u);
        assert_eq!(s, fmi3OK, "{}: reading the unknowns: {}", fmu.id, inst.log_text());
        if me {
            let (s, dx) = inst.vector(
                "fmi3GetContinuousStateDerivatives",
                api.get_continuous_state_derivatives,
                states.len(),
            );
            assert_eq!(s, fmi3OK);
            for (r, vr) in u.iter().enumerate() {
                if let Some(si) = states.iter().position(|p| p.1 == *vr) {
                    all[r] = dx[si];
                }
            }
        }
        all
    };
    let (_, base_x) = if me {
        inst.vector("x", api.get_continuous_states, states.len())
    } else {
        (fmi3OK, vec![])
    };
    let (_, base_k) = inst.get_f64(&k);
    let set = |inst: &Inst, j: usize, value: f64| {
        let vr = k[j];
        if let Some(si) = states.iter().position(|p| p.0 == vr).filter(|_| me) {
            let mut x = base_x.clone();
            x[si] = value;
            assert_eq!(
                inst.call("sx", |c| unsafe { (api.set_continuous_states)(c, x.as_ptr(), x.len()) }),
                fmi3OK
            );
        } else {
            assert_eq!(
                inst.set_f64(&[vr], &[value]),
                fmi3OK,
                "{}: setting known {vr} = {value}: {}",
                fmu.id,
                inst.log_text()
            );
        }
    };
    let mut compared = 0;
    let mut kinks = 0;
    for j in 0..nk {
        let x0 = base_k[j];
        let fd = |eps: f64| -> Vec<f64> {
            set(&inst, j, x0 + eps);
            let p = read(&inst);
            set(&inst, j, x0 - eps);
            let m = read(&inst);
            set(&inst, j, x0);
            p.iter().zip(&m).map(|(p, m)| (p - m) / (2.0 * eps)).collect()
        };
        let e = 1e-6 * x0.abs().max(1.0);
        let (d1, d2) = (fd(e), fd(e / 10.0));
        for r in 0..nu {
            let a = jd[r][j];
            if let Some(deps) = dependencies(fmu, me, u[r])
                && !deps.contains(&k[j])
            {
                assert_eq!(
                    a, 0.0,
                    "{}: d{}/d{} = {a}, but <ModelStructure> declares no dependency",
                    fmu.id, u[r], k[j]
                );
            }
            let tol = |x: f64| 1e-4 * (1.0 + x.abs());
            if (d1[r] - d2[r]).abs() > tol(d1[r]) {
                kinks += 1;
                continue;
            }
            assert!(
                (a - d1[r]).abs() <= tol(d1[r]),
                "{}: d{}/d{}: fmi3GetDirectionalDerivative {a}, central finite difference {} ({})",
                fmu.id,
                u[r],
                k[j],
                d1[r],
                if me { "ME" } else { "CS" }
            );
            compared += 1;
        }
    }
    info(format!(
        "{compared} of {} partial derivatives compared with finite differences ({kinks} left out where two step sizes disagree)",
        nu * nk
    ));
    // Bad arguments: nSeed != nKnowns, unknown vr, NULL seed.
    let seed = vec![1.0; nk + 1];
    let mut sens = vec![0.0; nu + 1];
    refused(&inst, "fmi3GetDirectionalDerivative(nSeed = nKnowns + 1)", |c| unsafe {
        (api.get_directional_derivative)(
            c,
            u.as_ptr(),
            nu,
            k.as_ptr(),
            nk,
            seed.as_ptr(),
            nk + 1,
            sens.as_mut_ptr(),
            nu,
        )
    });
    refused(
        &inst,
        "fmi3GetDirectionalDerivative(nSensitivity = nUnknowns + 1)",
        |c| unsafe {
            (api.get_directional_derivative)(
                c,
                u.as_ptr(),
                nu,
                k.as_ptr(),
                nk,
                seed.as_ptr(),
                nk,
                sens.as_mut_ptr(),
                nu + 1,
            )
        },
    );
    let bad = [fmu.md.unknown_vr()];
    refused(
        &inst,
        "fmi3GetDirectionalDerivative(unknown vr as unknown)",
        |c| unsafe {
            (api.get_directional_derivative)(
                c,
                bad.as_ptr(),
                1,
                k.as_ptr(),
                nk,
                seed.as_ptr(),
                nk,
                sens.as_mut_ptr(),
                1,
            )
        },
    );
    refused(&inst, "fmi3GetDirectionalDerivative(seed = NULL)", |c| unsafe {
        (api.get_directional_derivative)(c, u.as_ptr(), nu, k.as_ptr(), nk, null(), nk, sens.as_mut_ptr(), nu)
    });
    if i.provides_adjoint_derivatives {
        refused(
            &inst,
            "fmi3GetAdjointDerivative(nSeed = nKnowns: the adjoint's seed has nUnknowns)",
            |c| unsafe {
                (api.get_adjoint_derivative)(
                    c,
                    u.as_ptr(),
                    nu,
                    k.as_ptr(),
                    nk,
                    seed.as_ptr(),
                    if nk == nu { nu + 1 } else { nk },
                    sens.as_mut_ptr(),
                    if nk == nu { nk } else { nu },
                )
            },
        );
    }
}

pub fn fmi3_co_simulation_directional_derivatives_match_finite_differences_and_the_adjoint_is_the_transpose(
    fmu: &Fmu3,
) {
    derivatives_check(fmu, false);
}

pub fn fmi3_model_exchange_directional_derivatives_match_finite_differences_and_the_adjoint_is_the_transpose(
    fmu: &Fmu3,
) {
    derivatives_check(fmu, true);
}

// ---------------------------------------------------------------------------------------------
// FMU state

fn snapshot_only(fmu: &Fmu3, me: bool) -> bool {
    if !fmu.can_snapshot(me) {
        info(format!(
            "{}: canGetAndSetFMUState/canSerializeFMUState not both declared",
            if me { "ME" } else { "CS" }
        ));
        return false;
    }
    true
}

pub fn fmi3_fmu_state_get_set_and_serialize_round_trips_continue_bit_identically(fmu: &Fmu3) {
    let h = fmu.step_size();
    let mut tested = 0;
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) || !snapshot_only(fmu, me) {
            continue;
        }
        tested += 1;
        let api = &fmu.api;
        let mut a = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        excite(&a);
        a.initialize();
        for _ in 0..10 {
            a.step(h);
        }
        let t_saved = a.time;
        // get/set through a pointer
        let mut st: fmi3FMUState = null_mut();
        assert_eq!(
            a.call("fmi3GetFMUState", |c| unsafe { (api.get_fmu_state)(c, &mut st) }),
            fmi3OK
        );
        let bytes = a.snapshot();
        let reference: Vec<Vec<u64>> = (0..10)
            .map(|_| {
                a.step(h);
                a.observe()
            })
            .collect();
        assert_eq!(
            a.call("fmi3SetFMUState", |c| unsafe { (api.set_fmu_state)(c, st) }),
            fmi3OK,
            "{}: fmi3SetFMUState: {}",
            fmu.id,
            a.log_text()
        );
        a.time = t_saved;
        let again: Vec<Vec<u64>> = (0..10)
            .map(|_| {
                a.step(h);
                a.observe()
            })
            .collect();
        assert!(
            again == reference,
            "{}: after fmi3SetFMUState the run differs ({})",
            fmu.id,
            if me { "ME" } else { "CS" }
        );
        // Another instance of the same FMU continues from that state like the first (as FMI 2.0
        // importers use it: a state is a copy of the FMU's state, not of one instance).
        let mut other = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        assert_eq!(
            other.call("fmi3SetFMUState (of another instance)", |c| unsafe {
                (api.set_fmu_state)(c, st)
            }),
            fmi3OK,
            "{}: fmi3SetFMUState with a state of another instance of the same FMU: {}",
            fmu.id,
            other.log_text()
        );
        other.time = t_saved;
        let from_other: Vec<Vec<u64>> = (0..10)
            .map(|_| {
                other.step(h);
                other.observe()
            })
            .collect();
        assert!(
            from_other == reference,
            "{}: another instance set to the state continues differently",
            fmu.id
        );
        drop(other);
        // Overwriting a state with fmi3GetFMUState on the same pointer.
        assert_eq!(
            a.call("fmi3GetFMUState (update)", |c| unsafe {
                (api.get_fmu_state)(c, &mut st)
            }),
            fmi3OK
        );
        assert_eq!(
            a.call("fmi3FreeFMUState", |c| unsafe { (api.free_fmu_state)(c, &mut st) }),
            fmi3OK
        );
        assert!(st.is_null(), "{}: fmi3FreeFMUState left the pointer non-NULL", fmu.id);
        // serialize / deserialize into a new instance
        let mut b = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        assert_eq!(
            b.restore(&bytes),
            fmi3OK,
            "{}: restoring a serialized state in a new instance: {}",
            fmu.id,
            b.log_text()
        );
        b.time = t_saved;
        assert_eq!(
            b.snapshot(),
            bytes,
            "{}: the state serialized after restoring differs from the one restored",
            fmu.id
        );
        let other: Vec<Vec<u64>> = (0..10)
            .map(|_| {
                b.step(h);
                b.observe()
            })
            .collect();
        assert!(
            other == reference,
            "{}: a new instance with the deserialized state continues differently ({})",
            fmu.id,
            if me { "ME" } else { "CS" }
        );
        // size and serialize with a too small buffer
        let mut st: fmi3FMUState = null_mut();
        assert_eq!(a.call("get", |c| unsafe { (api.get_fmu_state)(c, &mut st) }), fmi3OK);
        let mut small = vec![0u8; bytes.len().saturating_sub(1)];
        let s = a.call("fmi3SerializeFMUState(size - 1)", |c| unsafe {
            (api.serialize_fmu_state)(c, st, small.as_mut_ptr(), small.len())
        });
        assert_eq!(
            s,
            fmi3Error,
            "{}: fmi3SerializeFMUState into a buffer one byte too small: {}",
            fmu.id,
            status_name(s)
        );
        assert_eq!(a.call("free", |c| unsafe { (api.free_fmu_state)(c, &mut st) }), fmi3OK);
    }
    if tested == 0 {
        skip_not_declared("canGetAndSetFMUState and canSerializeFMUState");
    }
}

pub fn fmi3_damaged_serialized_states_and_states_of_other_fmus_are_refused(fmu: &Fmu3) {
    let me = fmu.md.cs.is_none();
    if !fmu.can_snapshot(me) {
        skip_not_declared("canGetAndSetFMUState and canSerializeFMUState");
    }
    let mut a = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
    excite(&a);
    a.initialize();
    a.step(fmu.step_size());
    let bytes = a.snapshot();
    let api = &fmu.api;
    let before = a.observe();
    // Damage of the length is refused whatever the format; damage only a checksum (or the
    // token in the state) can find is required to be refused of this exporter's format, and of
    // another exporter's only not to crash nor change the instance (its format may have none).
    let own = fmu.own_state_format();
    if !own {
        limitation(
            "bit flips, zeros of the right length and states of other FMUs may be accepted (another exporter's state may carry no checksum or token): they must not crash",
        );
    }
    let attempt = |what: &str, b: &[u8], strict: bool| {
        let mut st: fmi3FMUState = null_mut();
        let s = a.call(what, |c| unsafe {
            (api.deserialize_fmu_state)(c, b.as_ptr(), b.len(), &mut st)
        });
        if s == fmi3OK {
            let _ = a.call("free", |c| unsafe { (api.free_fmu_state)(c, &mut st) });
        }
        assert!(
            s == fmi3Error || (!strict && s == fmi3OK),
            "{}: fmi3DeserializeFMUState of {what}: expected fmi3Error{}, got {}",
            fmu.id,
            if strict { "" } else { " (or fmi3OK)" },
            status_name(s)
        );
    };
    let try_bytes = |what: &str, b: &[u8]| attempt(what, b, true);
    let try_checksum = |what: &str, b: &[u8]| attempt(what, b, own);
    try_bytes("an empty buffer", &[]);
    try_bytes("the state without its last byte", &bytes[..bytes.len() - 1]);
    try_bytes("the state without its first half", &bytes[bytes.len() / 2..]);
    let mut longer = bytes.clone();
    longer.push(0);
    try_bytes("the state with a byte appended", &longer);
    try_checksum("zeros of the state's size", &vec![0u8; bytes.len()]);
    for at in [0, bytes.len() / 3, bytes.len() / 2, bytes.len() - 1] {
        let mut b = bytes.clone();
        b[at] ^= 0x5a;
        try_checksum(&format!("the state with byte {at} of {} changed", bytes.len()), &b);
    }
    // NULL buffer with a size
    let mut st: fmi3FMUState = null_mut();
    let s = a.call("fmi3DeserializeFMUState(NULL, n)", |c| unsafe {
        (api.deserialize_fmu_state)(c, null(), bytes.len(), &mut st)
    });
    assert_eq!(
        s,
        fmi3Error,
        "{}: fmi3DeserializeFMUState(NULL, {}): {}",
        fmu.id,
        bytes.len(),
        status_name(s)
    );
    assert_eq!(a.observe(), before, "{}: refused states changed the instance", fmu.id);
    // States of the other packaged FMUs (3.0 files next to this one, and the 2.0 file of the
    // same model one folder up, as `cargo fmu build` places them).
    let mut others = 0;
    let dir = fmu.archive.parent().map(|p| p.to_path_buf()).unwrap_or_default();
    let mut candidates: Vec<std::path::PathBuf> = std::fs::read_dir(&dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "fmu") && *p != fmu.archive)
        .collect();
    candidates.sort();
    let root = crate::unpack_root().unwrap_or_else(|e| panic!("{e}"));
    for other in candidates.iter().take(3) {
        let Ok(o) = super::Fmu3::load(other, &root) else {
            continue;
        };
        let ome = o.md.cs.is_none();
        if !o.can_snapshot(ome) {
            continue;
        }
        let mut oi = if ome { Inst::me(&o) } else { Inst::cs(&o) };
        oi.initialize();
        let ob = oi.snapshot();
        try_checksum(&format!("a state of the FMU {}", o.id), &ob);
        others += 1;
    }
    if let Some(parent) = dir.parent() {
        let two = parent.join(format!("{}.fmu", fmu.id));
        if two.exists()
            && let Ok(f2) = crate::Fmu::load(&two, &root)
            && f2.can_snapshot()
        {
            let mut i2 = crate::Instance::new(&f2);
            let b2 = i2.snapshot();
            drop(i2);
            try_checksum("the state of the FMI 2.0 binary of the same model", &b2);
            others += 1;
        }
    }
    info(format!("states of {others} other FMUs refused"));
}

/// The other process is a worker ([`crate::worker`], mode `state-child`): it unpacks and loads
/// the FMU afresh, instantiates the same interface, restores the state, re-serializes it, and
/// continues; its bytes and every observation after each step must be those of this process.
pub fn fmi3_a_state_serialized_here_restores_in_another_process_and_continues_identically(fmu: &Fmu3) {
    let worker = crate::worker().unwrap_or_else(|| {
        panic!("no worker executable set (fmi_conformance::set_worker): the other process cannot be started")
    });
    let mut checked = 0;
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) || !fmu.can_snapshot(me) {
            continue;
        }
        let h = fmu.step_size();
        let mut inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        excite(&inst);
        inst.initialize();
        for _ in 0..10 {
            inst.step(h);
        }
        let bytes = inst.snapshot();
        let t = inst.time;
        let expected: Vec<Vec<u64>> = (0..20)
            .map(|_| {
                inst.step(h);
                inst.observe()
            })
            .collect();
        let file = fmu.scratch.join(format!("state-{}.bin", if me { "me" } else { "cs" }));
        std::fs::write(&file, &bytes).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let out = std::process::Command::new(&worker.exe)
            .args(&worker.args_prefix)
            .arg("state-child")
            .arg(&fmu.archive)
            .arg(&file)
            .args([
                "20".to_string(),
                h.to_string(),
                (if me { "me" } else { "cs" }).to_string(),
                t.to_string(),
            ])
            .stdin(std::process::Stdio::null())
            .output()
            .unwrap_or_else(|e| panic!("cannot run the worker {}: {e}", worker.exe.display()));
        let _ = std::fs::remove_file(&file);
        let what = if me { "Model Exchange" } else { "Co-Simulation" };
        assert!(
            out.status.success(),
            "{}: {what}: the other process failed ({}): {}",
            fmu.id,
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        let parse_hex = |l: &str| -> Vec<u64> {
            l.split_whitespace()
                .map(|x| u64::from_str_radix(x, 16).unwrap_or(u64::MAX))
                .collect()
        };
        let mut lines = stdout.lines();
        let reserialized: Vec<u8> = parse_hex(lines.next().unwrap_or(""))
            .into_iter()
            .map(|b| b as u8)
            .collect();
        assert_eq!(
            reserialized, bytes,
            "{}: {what}: the other process re-serializes the state differently",
            fmu.id
        );
        let got: Vec<Vec<u64>> = lines.map(parse_hex).collect();
        assert_eq!(
            got.len(),
            expected.len(),
            "{}: {what}: steps reported by the other process",
            fmu.id
        );
        assert_eq!(
            got, expected,
            "{}: {what}: the other process continues differently",
            fmu.id
        );
        checked += 1;
    }
    if checked == 0 {
        skip_not_declared("canGetAndSetFMUState and canSerializeFMUState");
    }
}

/// One cycle of what an importer does with an instance of each interface: instantiate and free;
/// in full, also set the inputs, initialize, step, take, serialize and restore a state, and make
/// a refused call (its message allocates).
fn cycle(fmu: &Fmu3, full: bool) {
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) {
            continue;
        }
        let mut inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        if full {
            excite(&inst);
            inst.initialize();
            inst.step(fmu.step_size());
            if fmu.can_snapshot(me) {
                let bytes = inst.snapshot();
                assert_eq!(
                    inst.restore(&bytes),
                    fmi3OK,
                    "{}: restoring a state: {}",
                    fmu.id,
                    inst.log_text()
                );
            }
            let s = inst.set_f64(&[fmu.md.unknown_vr()], &[0.0]);
            assert_eq!(
                s,
                fmi3Error,
                "{}: fmi3SetFloat64 of an unknown value reference: {}",
                fmu.id,
                status_name(s)
            );
            inst.sink.take();
        }
    }
}

/// 10,000 cycles of each kind leave the resident set flat (alone in its process: a worker of
/// its own under the runner, a test binary of its own in the workspace); the measuring loop is
/// the FMI 2.0 check's.
pub fn fmi3_ten_thousand_instantiate_free_cycles_leave_memory_flat(fmu: &Fmu3) {
    if !fmu.can_snapshot(fmu.md.cs.is_none()) {
        limitation("the FMU cannot serialize its state: the cycles take and restore no FMU state");
    }
    crate::checks::memory::cycles_leave_memory_flat(&fmu.id, |full| cycle(fmu, full));
}

// ---------------------------------------------------------------------------------------------
// Instances and threads

pub fn fmi3_interleaved_instances_and_instances_on_threads_match_a_single_run(fmu: &Fmu3) {
    let h = fmu.step_size();
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) {
            continue;
        }
        let steps = 50;
        let reference = run(fmu, me, steps, h);
        // interleaved: three instances, one with other inputs
        let mut a = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        let mut b = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        let mut c = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        excite(&a);
        excite(&c);
        for (vr, v) in excitation(fmu) {
            assert_eq!(b.set_f64(&[vr], &[-v]), fmi3OK);
        }
        a.initialize();
        b.initialize();
        c.initialize();
        for (n, expected) in reference.iter().enumerate() {
            a.step(h);
            b.step(h);
            c.step(h);
            assert_eq!(
                a.observe(),
                *expected,
                "{}: interleaved instance a differs from a single run at step {n}",
                fmu.id
            );
            assert_eq!(
                c.observe(),
                *expected,
                "{}: interleaved instance c differs at step {n}",
                fmu.id
            );
        }
        drop((a, b, c));
        // threads
        let results: Vec<Vec<Vec<u64>>> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..4).map(|_| s.spawn(|| run(fmu, me, steps, h))).collect();
            handles
                .into_iter()
                .map(|h| h.join().unwrap_or_else(|_| panic!("a thread's run panicked")))
                .collect()
        });
        for (k, r) in results.iter().enumerate() {
            assert!(
                *r == reference,
                "{}: the run on thread {k} differs from the sequential run ({})",
                fmu.id,
                if me { "ME" } else { "CS" }
            );
        }
    }
    info("3 interleaved instances and 4 threads, per interface, bit-identical");
}

// Inst holds raw pointers; the runs on threads each make their own instance.
unsafe impl Sync for Fmu3 {}

// ---------------------------------------------------------------------------------------------
// Random call sequences

#[derive(Debug, Clone, Copy)]
enum Op {
    EnterInit,
    ExitInit,
    Step,
    EnterEventMode,
    UpdateDiscrete,
    EnterCtm,
    SetInput(u8),
    GetAll,
    Terminate,
    Reset,
    SaveState,
    RestoreState,
    BadSet,
}

/// The state the standard puts the instance in after `op` returned fmi3OK (None: refused).
fn model(state: State, me: bool, op: Op) -> Option<State> {
    use State::*;
    match (op, state) {
        (Op::EnterInit, Instantiated) => Some(InitializationMode),
        (Op::ExitInit, InitializationMode) => Some(if me { EventMode } else { StepMode }),
        (Op::Step, StepMode) if !me => Some(StepMode),
        (Op::Step, ContinuousTimeMode) if me => Some(ContinuousTimeMode),
        (Op::EnterEventMode, ContinuousTimeMode) if me => Some(EventMode),
        (Op::UpdateDiscrete, EventMode) if me => Some(EventMode),
        (Op::EnterCtm, EventMode) if me => Some(ContinuousTimeMode),
        (Op::SetInput(_), Instantiated | InitializationMode | EventMode | ContinuousTimeMode | StepMode) => Some(state),
        (Op::GetAll, InitializationMode | EventMode | ContinuousTimeMode | StepMode | Terminated) => Some(state),
        (Op::Terminate, EventMode | ContinuousTimeMode | StepMode) => Some(Terminated),
        (Op::Reset, _) => Some(Instantiated),
        (Op::SaveState, _) => Some(state),
        (Op::RestoreState, _) => None, // depends on the saved state: handled in the loop
        (Op::BadSet, _) => None,
        _ => None,
    }
}

pub fn fmi3_random_call_sequences_never_crash_and_keep_status_consistent(fmu: &Fmu3) {
    use proptest::prelude::*;
    use proptest::test_runner::{Config, TestRunner};
    let cases = crate::random_sequences().clamp(1, 2000) / 4 + 1;
    let op = prop_oneof![
        Just(Op::EnterInit),
        Just(Op::ExitInit),
        Just(Op::Step),
        Just(Op::Step),
        Just(Op::EnterEventMode),
        Just(Op::UpdateDiscrete),
        Just(Op::EnterCtm),
        any::<u8>().prop_map(Op::SetInput),
        Just(Op::GetAll),
        Just(Op::Terminate),
        Just(Op::Reset),
        Just(Op::SaveState),
        Just(Op::RestoreState),
        Just(Op::BadSet),
    ];
    let strategy = (any::<bool>(), proptest::collection::vec(op, 1..40));
    let mut runner = TestRunner::new(Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    });
    let result = runner.run(&strategy, |(me_pick, ops)| {
        let me = match (fmu.md.cs.is_some(), fmu.md.me.is_some()) {
            (true, true) => me_pick,
            (false, true) => true,
            _ => false,
        };
        let snap = fmu.can_snapshot(me);
        let mut inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        let api = &fmu.api;
        let mut state = State::Instantiated;
        let mut saved: Option<(Vec<u8>, State, f64)> = None;
        let inputs = float_inputs(fmu);
        let h = fmu.step_size();
        // After an fmi3Error the standard puts the FMU in Terminated (checked on its own by
        // fmi3_after_fmi3_error_the_instance_is_terminated_until_reset_or_set_fmu_state):
        // until fmi3Reset or fmi3SetFMUState, calls are only required not to crash nor answer
        // fmi3Fatal.
        let mut errored = false;
        for (k, op) in ops.iter().enumerate() {
            if errored && !matches!(op, Op::Reset | Op::RestoreState) {
                let s = match op {
                    Op::GetAll => inst.get_f64(&fmu.md.vrs_of_type(Type::Float64)).0,
                    Op::EnterInit => inst.enter_init(0.0),
                    Op::ExitInit => inst.exit_init(),
                    Op::Step if me => inst.call("fmi3CompletedIntegratorStep", |c| unsafe {
                        (api.completed_integrator_step)(c, true, &mut 0, &mut 0)
                    }),
                    Op::Step => inst.do_step(h).0,
                    Op::EnterEventMode => inst.call("fmi3EnterEventMode", |c| unsafe { (api.enter_event_mode)(c) }),
                    Op::EnterCtm => inst.call("fmi3EnterContinuousTimeMode", |c| unsafe {
                        (api.enter_continuous_time_mode)(c)
                    }),
                    Op::Terminate => inst.call("fmi3Terminate", |c| unsafe { (api.terminate)(c) }),
                    _ => fmi3Error,
                };
                prop_assert!(
                    s != fmi3Fatal,
                    "{}: ops {:?}: fmi3Fatal after an fmi3Error: {}",
                    fmu.id,
                    &ops[..=k],
                    inst.log_text()
                );
                continue;
            }
            if matches!(op, Op::GetAll) && state == State::Instantiated {
                // Only start values can be read before initialization (FMI 3.0.2).
                let s = inst.get_f64(&start_vrs(fmu, Type::Float64)).0;
                prop_assert!(
                    s == fmi3OK,
                    "{}: ops {:?}: fmi3GetFloat64 of the Float64 variables with a start value in Instantiated: {}: {}",
                    fmu.id,
                    &ops[..=k],
                    status_name(s),
                    inst.log_text()
                );
                continue;
            }
            let expected = model(state, me, *op);
            let s = match op {
                Op::EnterInit => inst.enter_init(0.0),
                Op::ExitInit => inst.exit_init(),
                Op::Step if me => {
                    if state == State::ContinuousTimeMode {
                        euler_step(&mut inst, h);
                        fmi3OK
                    } else {
                        inst.call("fmi3CompletedIntegratorStep", |c| unsafe {
                            (api.completed_integrator_step)(c, true, &mut 0, &mut 0)
                        })
                    }
                }
                Op::Step => inst.do_step(h).0,
                Op::EnterEventMode => inst.call("fmi3EnterEventMode", |c| unsafe { (api.enter_event_mode)(c) }),
                Op::UpdateDiscrete => {
                    let mut f = [0u8; 5];
                    let mut t = 0.0;
                    inst.call("fmi3UpdateDiscreteStates", |c| unsafe {
                        let [a, b, cc, d, e] = &mut f;
                        (api.update_discrete_states)(c, a, b, cc, d, e, &mut t)
                    })
                }
                Op::EnterCtm => inst.call("fmi3EnterContinuousTimeMode", |c| unsafe {
                    (api.enter_continuous_time_mode)(c)
                }),
                Op::SetInput(x) => match inputs.get(*x as usize % inputs.len().max(1)) {
                    Some(v) => inst.set_f64(&[v.vr], &[(*x as f64 - 128.0) / 256.0]),
                    None => inst.set_f64(&[], &[]),
                },
                Op::GetAll => inst.get_f64(&fmu.md.vrs_of_type(Type::Float64)).0,
                Op::Terminate => inst.call("fmi3Terminate", |c| unsafe { (api.terminate)(c) }),
                Op::Reset => {
                    inst.time = 0.0;
                    inst.call("fmi3Reset", |c| unsafe { (api.reset)(c) })
                }
                Op::SaveState => {
                    if snap {
                        saved = Some((inst.snapshot(), state, inst.time));
                    }
                    fmi3OK
                }
                Op::RestoreState => match &saved {
                    Some((b, st, t)) => {
                        let s = inst.restore(b);
                        prop_assert_eq!(
                            s,
                            fmi3OK,
                            "{}: restoring a saved state (op {}): {}",
                            fmu.id,
                            k,
                            inst.log_text()
                        );
                        state = *st;
                        inst.time = *t;
                        errored = false;
                        continue;
                    }
                    None => continue,
                },
                Op::BadSet => {
                    let vr = fmu.md.unknown_vr();
                    let s = inst.set_f64(&[vr], &[1.0]);
                    prop_assert_eq!(
                        s,
                        fmi3Error,
                        "{}: op {}: setting an unknown vr in {:?}",
                        fmu.id,
                        k,
                        state
                    );
                    errored = true;
                    continue;
                }
            };
            prop_assert!(
                s != fmi3Fatal,
                "{}: op {} {:?} in {:?}: fmi3Fatal: {}",
                fmu.id,
                k,
                op,
                state,
                inst.log_text()
            );
            match expected {
                Some(next) => {
                    prop_assert!(
                        s == fmi3OK || s == fmi3Warning,
                        "{}: ops {:?}: op {} {:?} in {:?} answered {}, the standard allows it: {}",
                        fmu.id,
                        &ops[..=k],
                        k,
                        op,
                        state,
                        status_name(s),
                        inst.log_text()
                    );
                    state = next;
                    if matches!(op, Op::Reset) {
                        errored = false;
                    }
                }
                None => {
                    errored = true;
                    prop_assert_eq!(
                        s,
                        fmi3Error,
                        "{}: ops {:?}: op {} {:?} in {:?} answered {}, the standard does not allow it",
                        fmu.id,
                        &ops[..=k],
                        k,
                        op,
                        state,
                        status_name(s)
                    );
                }
            }
        }
        Ok(())
    });
    if let Err(e) = result {
        panic!("{}: random call sequence: {e}", fmu.id);
    }
    info(format!("{cases} random call sequences"));
}

// ---------------------------------------------------------------------------------------------
// The C host

pub fn fmi3_a_c_host_runs_co_simulation_and_model_exchange_clean_under_valgrind(fmu: &Fmu3) {
    cs_only(fmu);
    let src = fmu.scratch.join("host3.c");
    std::fs::write(&src, include_str!("../../c/host3.c")).unwrap();
    std::fs::write(fmu.scratch.join("dl.h"), include_str!("../../c/dl.h")).unwrap();
    let exe = fmu.scratch.join("c-host3");
    let cc = std::process::Command::new("cc")
        .args(["-std=gnu11", "-O1", "-g", "-Wall", "-Wextra", "-Werror", "-o"])
        .arg(&exe)
        .arg(&src)
        .arg("-ldl")
        .output();
    let cc = match cc {
        Ok(o) => o,
        Err(_) => skip("cc is not installed (tests/setup-env.sh installs it)"),
    };
    assert!(
        cc.status.success(),
        "compiling c/host3.c: {}",
        String::from_utf8_lossy(&cc.stderr)
    );
    let n_states = if fmu.md.me.is_some() {
        fmu.md.derivatives.len().to_string()
    } else {
        "-1".into()
    };
    let vrs: Vec<String> = fmu.md.vrs_of_type(Type::Float64).iter().map(u32::to_string).collect();
    let mut args = vec![
        fmu.so.to_string_lossy().into_owned(),
        fmu.md.token.clone(),
        fmu.resource_path(),
        "1000".into(),
        format!("{:?}", fmu.step_size().min(1e-3)),
        n_states,
        vrs.join(","),
    ];
    args.extend(excitation(fmu).iter().map(|(vr, v)| format!("{vr}={v:?}")));
    let plain = std::process::Command::new(&exe).args(&args).output().unwrap();
    let stdout = String::from_utf8_lossy(&plain.stdout).into_owned();
    assert!(
        plain.status.success(),
        "{}: the C host failed: {}{stdout}",
        fmu.id,
        String::from_utf8_lossy(&plain.stderr)
    );
    // The same numbers as this importer.
    let final_line = stdout
        .lines()
        .find(|l| l.starts_with("final "))
        .unwrap_or_else(|| panic!("no final line: {stdout}"));
    let got: Vec<u64> = final_line
        .split_whitespace()
        .skip(1)
        .map(|x| u64::from_str_radix(x, 16).unwrap())
        .collect();
    let want = run(fmu, false, 1000, fmu.step_size().min(1e-3)).pop().unwrap();
    assert_eq!(
        got, want,
        "{}: the C host's co-simulation run differs from this importer's",
        fmu.id
    );
    if fmu.md.me.is_some() {
        let line = stdout
            .lines()
            .find(|l| l.starts_with("me-final "))
            .unwrap_or_else(|| panic!("no me-final line: {stdout}"));
        let got: Vec<u64> = line
            .split_whitespace()
            .skip(1)
            .map(|x| u64::from_str_radix(x, 16).unwrap())
            .collect();
        let want = run(fmu, true, 1000, fmu.step_size().min(1e-3)).pop().unwrap();
        assert_eq!(
            got, want,
            "{}: the C host's explicit-Euler ME run differs from this importer's",
            fmu.id
        );
    }
    if std::process::Command::new("valgrind")
        .arg("--version")
        .output()
        .is_err()
    {
        skip("valgrind is not installed (tests/setup-env.sh installs it)");
    }
    let out = std::process::Command::new("valgrind")
        .args([
            "--error-exitcode=1",
            "--leak-check=full",
            "--show-leak-kinds=definite,indirect,possible",
            "--errors-for-leak-kinds=definite,indirect,possible",
            "--quiet",
        ])
        .arg(&exe)
        .args(&args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}: valgrind memcheck: {}{}",
        fmu.id,
        String::from_utf8_lossy(&out.stderr),
        String::from_utf8_lossy(&out.stdout)
    );
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        stdout,
        "{}: results under valgrind differ",
        fmu.id
    );
    info("C host: 1000 co-simulation steps and an explicit-Euler ME run, memcheck clean");
}

#[allow(dead_code)]
fn unused(_: &Api) {}
