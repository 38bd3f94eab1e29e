//! The FMI 3.0 calls one by one: version, instantiation, bad arguments, setting each variable
//! where the standard allows it, start values, the time variable, fmi3DoStep's output
//! arguments, fmi3SetDebugLogging.

pub use super::co_simulation::{
    fmi3_intermediate_update_names_times_inside_the_step_and_returns_early_where_asked,
    fmi3_output_derivatives_agree_with_finite_differences_of_the_outputs,
};
use super::*;
use crate::calllog::Val;
use crate::guard::{GETTER_RULE3 as RULE, fill, fill_one};

// ---------------------------------------------------------------------------------------------
// Calls

pub fn fmi3_get_version_is_3_0(fmu: &Fmu3) {
    // SAFETY: no arguments; returns a static string.
    let v = unsafe { (fmu.api.get_version)() };
    assert!(!v.is_null(), "{}: fmi3GetVersion returned NULL", fmu.id);
    // SAFETY: not NULL (asserted), and fmi3GetVersion returns a NUL-terminated static string.
    let v = unsafe { std::ffi::CStr::from_ptr(v) }.to_string_lossy().into_owned();
    assert!(
        v.starts_with("3."),
        "{}: fmi3GetVersion returned \"{v}\", not a 3.x version (fmi3Version is \"3.0\")",
        fmu.id
    );
    assert!(
        crate::Version::of(&fmu.md.fmi_version) == Some(crate::Version::Fmi3),
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

/// Each instantiation function the FMU declares, given a wrong or a NULL instantiationToken, a
/// NULL instanceName, or (co-simulation without hasEventMode) eventModeUsed = true, should return
/// NULL; with valid arguments, also without a logMessage callback, an instance.
///
/// Verdict on the name: an instance for a NULL instanceName is warned, not failed: FMI 3.0.2
/// §2.3.1: "The argument instanceName must be a non empty string (in other words, must have at
/// least one character that is not a white space)" binds the importer, as the token's "must"s do.
///
/// Verdict on the token: an instance for a wrong or a NULL instantiationToken is warned, not
/// failed. FMI 3.0.2 §2.3.1 (fmi3Instantiate...): "instantiationToken can be used by the FMU to
/// check that the modelDescription.xml file [...] is compatible with the
/// implementation of the FMU. [...] It must be passed unchanged to the FMU. This argument must not
/// be a null pointer." The check is the FMU's option ("can be used"); the "must"s bind the
/// importer. An FMU that does not check leaves an importer's mistake (a description of another
/// build) undetected: a warning. Refusing eventModeUsed without hasEventMode stays a failure
/// (ibid.: "The flag may only be fmi3True, if hasEventMode == true, otherwise the FMU must raise
/// an error").
// Over ~150 lines: raw instantiations of each interface, each beside the free of what it returned.
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
            // SAFETY: the strings are live CStrings or NULL (the cases the FMU must refuse), the NULL
            // required-intermediate-variables array comes with a count of 0, `env` outlives the instance.
            Box::new(move |n, t, event_mode, log, env| unsafe {
                (api.instantiate_co_simulation)(n, t, res, false, false, event_mode, false, null(), 0, env, log, None)
            }),
        ));
    }
    if fmu.md.me.is_some() {
        let res = res.as_ptr();
        interfaces.push((
            "fmi3InstantiateModelExchange",
            // SAFETY: the strings are live CStrings or NULL (the cases the FMU must refuse); `env` outlives the
            // instance.
            Box::new(move |n, t, _, log, env| unsafe {
                (api.instantiate_model_exchange)(n, t, res, false, false, env, log)
            }),
        ));
    }
    for (what, inst) in &interfaces {
        let sink = crate::fmi3::LogSink::default();
        let log = Some(crate::fmi3::log_message as unsafe extern "C" fn(_, _, _, _));
        for (case, n, t) in [
            ("a wrong instantiationToken", name.as_ptr(), wrong.as_ptr()),
            ("a NULL instantiationToken", name.as_ptr(), null()),
            ("a NULL instanceName", null(), token.as_ptr()),
        ] {
            crate::outcome::breadcrumb(&format!("{what} with {case}"));
            let c = inst(n, t, false, log, sink.env());
            if !c.is_null() {
                // SAFETY: `c` is the non-NULL instance just returned, freed once and not used again.
                unsafe { (api.free_instance)(c) };
                if t == token.as_ptr() {
                    crate::outcome::warn(format!(
                        "{}: {what} with {case} returned an instance: the importer's mistake is not detected \
                         (FMI 3.0.2 §2.3.1: \"The argument instanceName must be a non empty string\" binds the \
                         importer; no sentence requires a refusal)",
                        fmu.id
                    ));
                    continue;
                }
                crate::outcome::warn(format!(
                    "{}: {what} with {case} returned an instance: the FMU does not check that its modelDescription.xml \
                     is the one of its implementation (FMI 3.0.2 §2.3.1: the token \"can be used by the FMU\" to check \
                     that; no sentence requires a refusal)",
                    fmu.id
                ));
            }
        }
        // The right token: an instance, also without a logger, and with a NULL resourcePath.
        crate::outcome::breadcrumb(&format!("{what} without a logMessage callback"));
        // (An FMU with clocks requires eventModeUsed: FMI 3.0, 4.2.1.)
        let c = inst(name.as_ptr(), token.as_ptr(), fmu.has_clocks(), None, null_mut());
        assert!(
            !c.is_null(),
            "{}: {what} without a logMessage callback returned NULL (it may be NULL: FMI 3.0 section 2.3.1)",
            fmu.id
        );
        // SAFETY: `c` is the non-NULL instance just returned, freed once and not used again.
        unsafe { (api.free_instance)(c) };
        let c = inst(name.as_ptr(), token.as_ptr(), fmu.has_clocks(), log, sink.env());
        assert!(
            !c.is_null(),
            "{}: {what}: NULL with valid arguments: {:?}",
            fmu.id,
            sink.take()
        );
        // SAFETY: `c` is the non-NULL instance just returned, freed once and not used again.
        unsafe { (api.free_instance)(c) };
    }
    if let Some(cs) = &fmu.md.cs {
        if !cs.has_event_mode {
            let sink = crate::fmi3::LogSink::default();
            // SAFETY: live CStrings, the NULL array with a count of 0, and a sink that outlives the instance
            // (freed below).
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
                    Some(crate::fmi3::log_message),
                    None,
                )
            };
            if !c.is_null() {
                // SAFETY: `c` is the non-NULL instance just returned, freed once and not used again.
                unsafe { (api.free_instance)(c) };
                panic!(
                    "{}: fmi3InstantiateCoSimulation with eventModeUsed = true returned an instance, but <CoSimulation> has no hasEventMode=\"true\": expected NULL",
                    fmu.id
                );
            }
        }
        let sink = crate::fmi3::LogSink::default();
        // SAFETY: resourcePath NULL on purpose (the FMU may refuse it); the other strings are live CStrings,
        // the NULL array comes with a count of 0, and the sink outlives the instance.
        let c = unsafe {
            (api.instantiate_co_simulation)(
                c"nores".as_ptr(),
                token.as_ptr(),
                null(),
                false,
                false,
                fmu.has_clocks(),
                false,
                null(),
                0,
                sink.env(),
                Some(crate::fmi3::log_message),
                None,
            )
        };
        if c.is_null() {
            // An FMU that reads its resources when it is instantiated (a container FMU, whose
            // system is there) cannot be made without them: NULL with an fmi3Error message
            // naming what is missing is its answer (as the FMI 2.0 check accepts).
            let log = sink.take();
            assert!(
                log.iter().any(|e| e.status == fmi3Error),
                "{}: fmi3InstantiateCoSimulation with resourcePath = NULL returned NULL without an fmi3Error message",
                fmu.id
            );
            info("instantiation needs the FMU's resources: resourcePath = NULL refused with a message".to_string());
        } else {
            // SAFETY: `c` is the non-NULL instance just returned, freed once and not used again.
            unsafe { (api.free_instance)(c) };
        }
    }
    if !fmu.md.se {
        // SAFETY: live CStrings and NULL callbacks (allowed: the FMU must refuse the call anyway, having no
        // <ScheduledExecution>); the environment NULL is never dereferenced by us.
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
            // SAFETY: `c` is the non-NULL instance just returned, freed once and not used again.
            unsafe { (api.free_instance)(c) };
            panic!(
                "{}: fmi3InstantiateScheduledExecution returned an instance, but there is no <ScheduledExecution>",
                fmu.id
            );
        }
    }
}

pub fn fmi3_bad_arguments_are_refused_with_a_message_and_change_nothing(fmu: &Fmu3) {
    for me in [false, true] {
        if (me && fmu.md.me.is_some()) || (!me && fmu.md.cs.is_some()) {
            bad_arguments(fmu, me);
        }
    }
}

// Over ~150 lines: a list of bad calls of a few lines each, on one instance whose state each
// refusal must leave as it was.
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
    let out = [0.0f64; 4];
    // NULL arrays with n > 0, and nValues other than the variables' elements (every variable is
    // a scalar), through the call log (Inst::float64_probe: a failure leaves a reproducer that
    // makes them again).
    let z = [0.0];
    refused_by(&inst, "fmi3GetFloat64(vrs = NULL, n = 1)", || {
        inst.float64_probe(false, None, 1, Some(&z[..]), 1)
    });
    refused_by(&inst, "fmi3GetFloat64(values = NULL, n = 1)", || {
        inst.float64_probe(false, Some(&[f][..]), 1, None, 1)
    });
    refused_by(&inst, "fmi3SetFloat64(vrs = NULL, n = 1)", || {
        inst.float64_probe(true, None, 1, Some(&z[..]), 1)
    });
    refused_by(&inst, "fmi3SetFloat64(values = NULL, n = 1)", || {
        inst.float64_probe(true, Some(&[f][..]), 1, None, 1)
    });
    refused_by(&inst, "fmi3GetFloat64(n = 1, nValues = 2)", || {
        inst.float64_probe(false, Some(&[f][..]), 1, Some(&[0.0; 2][..]), 2)
    });
    refused_by(&inst, "fmi3GetFloat64(n = 1, nValues = 0)", || {
        inst.float64_probe(false, Some(&[f][..]), 1, Some(&[][..]), 0)
    });
    // Unknown value references, and a known one with an unknown one (all-or-nothing).
    // SAFETY: bad on purpose, for the FMU to refuse; pointers NULL or to live locals of the lengths
    // passed.
    refused_by(&inst, &format!("fmi3GetFloat64([{unknown}])"), || {
        inst.float64_probe(false, Some(&[unknown][..]), 1, Some(&out[..1]), 1)
    });
    let inputs = float_inputs(fmu);
    if let Some(u) = inputs.first() {
        // An array input takes every element (the bad value in its last one, the others good).
        let n = fmu.element_count(u);
        let with_last = |bad: f64| {
            let mut x = vec![0.25; n];
            x[n - 1] = bad;
            x
        };
        let vrs = [u.vr, unknown];
        let good = vec![0.5; n + 1];
        // SAFETY: bad on purpose, for the FMU to refuse; pointers NULL or to live locals of the
        // lengths passed.
        refused_by(&inst, "fmi3SetFloat64([an input, an unknown vr])", || {
            inst.float64_probe(true, Some(&vrs[..]), 2, Some(&good[..]), n + 1)
        });
        if n > 0 {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                let x = with_last(bad);
                // SAFETY: bad on purpose, for the FMU to refuse; pointers NULL or to live locals of
                // the lengths passed.
                refused_by(&inst, &format!("fmi3SetFloat64({} = {x:?})", u.name), || {
                    inst.float64_probe(true, Some(std::slice::from_ref(&u.vr)), 1, Some(&x[..]), n)
                });
            }
            if let Some(hi) = u.max {
                let x = with_last(hi + 1.0 + hi.abs());
                refused_by(&inst, &format!("fmi3SetFloat64({} = {x:?} > max {hi})", u.name), || {
                    inst.float64_probe(true, Some(std::slice::from_ref(&u.vr)), 1, Some(&x[..]), n)
                });
            }
            if let Some(lo) = u.min {
                let x = with_last(lo - 1.0 - lo.abs());
                refused_by(&inst, &format!("fmi3SetFloat64({} = {x:?} < min {lo})", u.name), || {
                    inst.float64_probe(true, Some(std::slice::from_ref(&u.vr)), 1, Some(&x[..]), n)
                });
            }
            if u.array {
                // nValues one short of (and one past) the array's elements.
                let x = vec![0.25; n + 1];
                for m in [n - 1, n + 1] {
                    refused_by(
                        &inst,
                        &format!(
                            "fmi3SetFloat64 of the array '{}' ({n} elements) with nValues = {m}",
                            u.name
                        ),
                        || inst.float64_probe(true, Some(std::slice::from_ref(&u.vr)), 1, Some(&x[..]), m),
                    );
                }
            }
        }
        // all-or-nothing: good values with a NaN (the last element of the second input).
        if inputs.len() > 1 {
            let m = fmu.element_count(inputs[1]);
            if m > 0 {
                let vrs = [inputs[0].vr, inputs[1].vr];
                let mut x = vec![0.25; n + m];
                x[n + m - 1] = f64::NAN;
                // SAFETY: bad on purpose, for the FMU to refuse; pointers NULL or to live locals of
                // the lengths passed.
                refused_by(&inst, "fmi3SetFloat64([input = 0.25, input = NaN])", || {
                    inst.float64_probe(true, Some(&vrs[..]), 2, Some(&x[..]), n + m)
                });
            }
        } else if n > 1 {
            // The same within one array: its good elements are not set either.
            let mut x = vec![0.25; n];
            x[0] = f64::NAN;
            refused_by(
                &inst,
                &format!("fmi3SetFloat64({} = {x:?}: NaN in the first element)", u.name),
                || inst.float64_probe(true, Some(std::slice::from_ref(&u.vr)), 1, Some(&x[..]), n),
            );
        }
    } else {
        info("no continuous Float64 input: NaN/inf/min/max and all-or-nothing of setters not exercised");
    }
    // Wrong types: a Float64 vr through every other getter, into one value of the getter's own
    // type (a guard after it: an FMU that writes its 8-byte Float64 there overruns it).
    // (every type with a getter of numbers or Booleans but Float64; Enumeration's is Int64's)
    let others = Type::ALL.into_iter().filter(|t| {
        !matches!(
            t,
            Type::Float64 | Type::Enumeration | Type::String | Type::Binary | Type::Clock
        )
    });
    for ty in others {
        // Through the call log (Inst::get_as): the reproducer's line makes the call again.
        refused_by(&inst, &format!("fmi3Get{} of a Float64 (vr {f})", ty.name()), || {
            inst.get_as(ty, f, 1).0
        });
    }
    let mut s: fmi3String = null();
    refused_by(&inst, "fmi3GetString of a Float64", || {
        inst.args(vec![("vr", Val::U32s(vec![f])), ("nValues", Val::U64(1))])
            // SAFETY: bad on purpose, for the FMU to refuse; one value reference and one string
            // with a guard after it.
            .call("fmi3GetString", |c| unsafe {
                fill_one(&mut s, "fmi3GetString", "nValues", RULE, |p| {
                    (api.get_string)(c, &f, 1, p, 1)
                })
            })
    });
    refused_by(&inst, "fmi3GetBinary of a Float64", || inst.get_binary(&[f], 1).0);
    if let Some(i32v) = md.of_type(Type::Int32).next() {
        refused_by(&inst, &format!("fmi3GetFloat64 of the Int32 '{}'", i32v.name), || {
            inst.get_as(Type::Float64, i32v.vr, 1).0
        });
    }
    if let Some(b) = md.of_type(Type::Boolean).next() {
        refused_by(&inst, &format!("fmi3GetInt32 of the Boolean '{}'", b.name), || {
            inst.get_as(Type::Int32, b.vr, 1).0
        });
    }
    if let Some(e) = md.of_type(Type::Enumeration).next() {
        refused_by(
            &inst,
            &format!(
                "fmi3GetInt32 of the Enumeration '{}' (FMI 3.0: Enumerations are Int64)",
                e.name
            ),
            || inst.get_as(Type::Int32, e.vr, 1).0,
        );
        let s = inst.get_as(Type::Int64, e.vr, 1).0;
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
        refused_by(
            &inst,
            &format!(
                "fmi3SetFloat64 of '{}' ({}, {}) in {state:?}",
                v.name, v.causality, v.variability
            ),
            || {
                inst.float64_probe(
                    true,
                    Some(std::slice::from_ref(&v.vr)),
                    1,
                    Some(std::slice::from_ref(&0.125)),
                    1,
                )
            },
        );
    }
    // Zero values with NULL arrays are fine (the reproducer's line expects fmi3OK).
    let s = inst.float64_probe(false, None, 0, None, 0);
    crate::calllog::standard_requires(crate::replay::Expected::OK);
    assert_eq!(
        s,
        fmi3OK,
        "{}: fmi3GetFloat64 of no variables with NULL arrays: expected fmi3OK, got {}",
        fmu.id,
        status_name(s)
    );
    // ME vector functions with a wrong size.
    if me {
        let n = fmu.n_states_declared();
        let v = vec![0.0; n + 2];
        refused_by(&inst, "fmi3GetContinuousStates(nContinuousStates + 1)", || {
            inst.vector("fmi3GetContinuousStates", api.get_continuous_states, n + 1)
                .0
        });
        // Recorded with its values: a failure after it leaves a reproducer that makes it again.
        refused_by(&inst, "fmi3SetContinuousStates(nContinuousStates + 1)", || {
            inst.args(vec![("values", Val::F64s(v[..n + 1].to_vec()))])
                // SAFETY: bad on purpose, for the FMU to refuse; `v` holds n + 2 values.
                .call("fmi3SetContinuousStates", |c| unsafe {
                    (api.set_continuous_states)(c, v.as_ptr(), n + 1)
                })
        });
        if n > 0 {
            refused_by(&inst, "fmi3GetContinuousStateDerivatives(NULL)", || {
                inst.vector_null(
                    "fmi3GetContinuousStateDerivatives",
                    api.get_continuous_state_derivatives,
                    n,
                )
            });
            let nan = vec![f64::NAN; n];
            refused_by(&inst, "fmi3SetContinuousStates(NaN...)", || {
                inst.args(vec![("values", Val::F64s(nan.clone()))])
                    // SAFETY: bad on purpose, for the FMU to refuse; `nan` holds n values.
                    .call("fmi3SetContinuousStates", |c| unsafe {
                        (api.set_continuous_states)(c, nan.as_ptr(), n)
                    })
            });
        }
        refused_by(&inst, "fmi3SetTime(NaN)", || {
            inst.args(vec![("time", Val::F64(f64::NAN))])
                // SAFETY: a live instance; NaN on purpose, for the FMU to refuse.
                .call("fmi3SetTime", |c| unsafe { (api.set_time)(c, f64::NAN) })
        });
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
            // (Clocked variables: where they may be set is the clock check's. Arrays: Float64
            // ones, every element set.)
            for v in fmu.md.variables.iter().filter(|v| {
                v.clocks.is_empty()
                    && (if v.array {
                        v.ty == Type::Float64
                    } else {
                        matches!(v.ty, Type::Float64 | Type::Int32 | Type::Boolean | Type::Enumeration)
                    })
            }) {
                let inst = in_state(fmu, me, state);
                let s = match v.ty {
                    Type::Float64 if v.array => {
                        // the values it has (where readable), else its start, else zeros
                        let n = fmu.element_count(v);
                        let got = if state == State::Instantiated {
                            None
                        } else {
                            let (s, x) = inst.get_f64_of(&[v]);
                            (s == fmi3OK).then_some(x)
                        };
                        let x = got.unwrap_or_else(|| {
                            let start: Vec<f64> = v
                                .start
                                .as_deref()
                                .unwrap_or_default()
                                .split_whitespace()
                                .filter_map(|x| x.parse().ok())
                                .collect();
                            if start.len() == n { start } else { vec![0.0; n] }
                        });
                        inst.set_f64(&[v.vr], &x)
                    }
                    Type::Float64 => {
                        // the value it has (where readable), else its start, else 0
                        let got = (state != State::Instantiated)
                            .then(|| inst.get_f64(&[v.vr]))
                            .filter(|(s, _)| *s == fmi3OK)
                            .map(|(_, x)| x[0]);
                        let x = got.unwrap_or_else(|| v.start.as_deref().and_then(|s| s.parse().ok()).unwrap_or(0.0));
                        inst.set_f64(&[v.vr], &[x])
                    }
                    Type::Int32 => {
                        let x: i32 = v.start.as_deref().and_then(|s| s.parse().ok()).unwrap_or(0);
                        inst.set_raw(v, &x.to_ne_bytes())
                    }
                    Type::Enumeration => {
                        let x: i64 = v.start.as_deref().and_then(|s| s.parse().ok()).unwrap_or(1);
                        inst.set_raw(v, &x.to_ne_bytes())
                    }
                    _ => inst.set_raw(v, &[u8::from(v.start.as_deref() == Some("true"))]),
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
                } else if s != fmi3Error {
                    // The importer's mistake: FMI 3.0.2 §2.2.4 requires fmi3Error "when
                    // detecting" it, not the detection; undetected, a warning.
                    crate::outcome::warn(format!(
                        "{}: setting '{}' ({}, {}, initial {:?}) in {state:?} ({}) answered {}: the standard does not allow it (an importer's mistake not detected)",
                        fmu.id,
                        v.name,
                        v.causality,
                        v.variability,
                        crate::standard::initial(v.causality, v.variability, v.declared_initial),
                        if me { "ME" } else { "CS" },
                        status_name(s)
                    ));
                }
            }
        }
    }
    info(format!("{cases} (variable, state) cases"));
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
                    inst.args(vec![
                        ("vr", crate::calllog::Val::U32s(vec![v.vr])),
                        ("nValues", crate::calllog::Val::U64(1)),
                    ]);
                    // SAFETY: the standard's function from the library the FMU keeps loaded, on
                    // this instance's live handle; each pointer we pass is to a live local of at
                    // least the length passed (or is an FMU state, the FMU's own handle).
                    let s = inst.call($name, |c| unsafe {
                        fill(&mut got, $name, "nValues", RULE, |p| {
                            (api.$get)(c, &v.vr, 1, p, 1)
                        })
                    });
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
            inst.args(vec![
                ("vr", crate::calllog::Val::U32s(vec![v.vr])),
                ("nValues", crate::calllog::Val::U64(1)),
            ]);
            // SAFETY: a live instance; each pointer is to a live local of the length passed, or is
            // an FMU state.
            let s = inst.call("fmi3GetBoolean", |c| unsafe {
                fill(&mut got, "fmi3GetBoolean", "nValues", RULE, |p| {
                    (api.get_boolean)(c, &v.vr, 1, p, 1)
                })
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
            inst.args(vec![
                ("vr", crate::calllog::Val::U32s(vec![v.vr])),
                ("nValues", crate::calllog::Val::U64(1)),
            ]);
            // SAFETY: a live instance; each pointer is to a live local of the length passed, or is
            // an FMU state.
            let s = inst.call("fmi3GetString", |c| unsafe {
                fill(&mut got, "fmi3GetString", "nValues", RULE, |p| {
                    (api.get_string)(c, &v.vr, 1, p, 1)
                })
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
        refused_by(
            &other,
            &format!("fmi3SetFloat64 of the independent variable '{}'", t.name),
            || {
                other.float64_probe(
                    true,
                    Some(std::slice::from_ref(&t.vr)),
                    1,
                    Some(std::slice::from_ref(&1.0)),
                    1,
                )
            },
        );
        assert_eq!(i.exit_init(), fmi3OK);
        if me {
            i.event_iteration();
            assert_eq!(
                i.unary("fmi3EnterContinuousTimeMode", api.enter_continuous_time_mode),
                fmi3OK
            );
        }
        let h = fmu.step_size();
        for _ in 0..3 {
            i.step(h);
        }
        let (s, v) = i.get_f64(&[t.vr]);
        assert_eq!(s, fmi3OK);
        // Within a tolerance relative to the step: FMI 3.0.2 does not promise that the FMU sums
        // the steps as the importer does (its time is its own: fmi3DoStep's lastSuccessfulTime).
        // Co-simulation: after fmi3OK steps the FMU's time is what fmi3OK means, the verdict of
        // fmi3_do_step_advances_time_by_the_step; model exchange: the time the importer set.
        if !me && !crate::outcome::same_time(v[0], i.time, h) {
            time_judged_by_the_named_check(&format!("{} after 3 steps of {h} from 0.25 (CS)", t.name), v[0], i.time);
        } else {
            assert!(
                crate::outcome::same_time(v[0], i.time, h),
                "{}: {} after 3 steps of {h} from 0.25 ({}): {}, expected {} within a tolerance relative to the step (FMI 3.0.2 §2.4.7.4: the independent variable is the time)",
                fmu.id,
                t.name,
                if me { "ME" } else { "CS" },
                v[0],
                i.time
            );
        }
    }
}

/// Verdict: lastSuccessfulTime is compared with t + h within a tolerance relative to the step
/// (FMI 3.0.2 promises no bit identity of the FMU's time); a step that answers fmi3OK without
/// early return and ends elsewhere fails. Refusing a bad step size, a wrong
/// currentCommunicationPoint or NULL output pointers is detecting the importer's mistakes: a
/// warning when not done (FMI 3.0.2 §2.2.4 requires fmi3Error only "when detecting" them).
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
        // eventHandlingNeeded only where the instance uses event mode: an FMU with clocks is made
        // with eventModeUsed (the standard requires it), and there an event at the step's end
        // (a time event at t + h) is the importer's to handle: eventHandlingNeeded asks for Event
        // Mode (FMI 3.0.2 §4.2.1, fmi3DoStep); the suite handles it.
        let expected = [u8::from(i.auto_events && flags[0] == 1), 0, 0];
        assert_eq!(
            flags,
            expected,
            "{}: step {n}: eventHandlingNeeded, terminateSimulation, earlyReturn = {flags:?}: expected {expected:?} ({}no early return)",
            fmu.id,
            if i.auto_events { "" } else { "no event mode, " }
        );
        // FMI 3.0.2 §4.2.1 (fmi3DoStep): lastSuccessfulTime is the FMU's own time; without an
        // early return it ends the step, up to rounding: compared within a tolerance relative
        // to the step, never bit for bit.
        if !crate::outcome::same_time(last, t + h, h) {
            time_judged_by_the_named_check(&format!("step {n}: lastSuccessfulTime"), last, t + h);
        }
    }
    // Refused steps: the instance stays where it was.
    let api = &fmu.api;
    let t = i.time;
    for bad in [0.0, -h, f64::NAN, f64::INFINITY] {
        let (mut flags, mut last) = ([0u8; 3], 0.0);
        let s = i
            .args(vec![
                ("currentCommunicationPoint", Val::F64(t)),
                ("communicationStepSize", Val::F64(bad)),
            ])
            // SAFETY: a live instance; each pointer is to a live local of the length passed, or
            // is an FMU state.
            .call("fmi3DoStep", |c| unsafe {
                crate::guard::fill_outputs("fmi3DoStep", &mut flags, &mut last, |[a, b, c2], l| {
                    (api.do_step)(c, t, bad, true, a, b, c2, l)
                })
            });
        if s != fmi3Error {
            crate::calllog::warning_requires(crate::replay::Expected::ERROR);
        }
        crate::outcome::warn_unless(s == fmi3Error, || {
            format!(
                "{}: fmi3DoStep(t = {t}, h = {bad}): expected fmi3Error, got {} (an importer's mistake not detected)",
                fmu.id,
                status_name(s)
            )
        });
    }
    // After refused steps the instance may be in an error state (FMI 3.0: after fmi3Error only
    // some calls are allowed); a fresh instance continues.
    let mut j = Inst::cs(fmu);
    excite(&j);
    j.initialize();
    let (mut flags, mut last) = ([0u8; 3], 0.0);
    let s = j
        .args(vec![
            ("currentCommunicationPoint", Val::F64(1.0 + 10.0 * h)),
            ("communicationStepSize", Val::F64(h)),
        ])
        // SAFETY: a live instance; each pointer is to a live local of the length passed, or is an
        // FMU state.
        .call("fmi3DoStep", |c| unsafe {
            crate::guard::fill_outputs("fmi3DoStep", &mut flags, &mut last, |[a, b, c2], l| {
                (api.do_step)(c, 1.0 + 10.0 * h, h, true, a, b, c2, l)
            })
        });
    // FMI 3.0.2 asks no check of currentCommunicationPoint against the FMU's time (the
    // Reference-FMUs' maintainers: "there is no requirement"): a warning.
    if s == fmi3OK {
        crate::calllog::warning_requires(crate::replay::Expected(!1 & 0b1111));
    }
    crate::outcome::warn_unless(s != fmi3OK, || {
        format!(
            "{}: fmi3DoStep at currentCommunicationPoint 1 + 10 h while the FMU is at 0 answered fmi3OK (an importer's mistake not detected)",
            fmu.id
        )
    });
    // null output pointers with valid step
    let mut k = Inst::cs(fmu);
    k.initialize();
    let s = crate::outcome::on_purpose(|| k.do_step_null_outputs(0.0, h));
    if s != fmi3OK && s != fmi3Error {
        crate::calllog::warning_requires(crate::replay::Expected(1 | 1 << 3));
    }
    crate::outcome::warn_unless(s == fmi3OK || s == fmi3Error, || {
        format!(
            "{}: fmi3DoStep with NULL output pointers (an importer's mistake): {} (expected fmi3OK or fmi3Error)",
            fmu.id,
            status_name(s)
        )
    });
    let _ = k.time;
    // A huge step: completed (lastSuccessfulTime = t + h) or discarded (fmi3Discard with a
    // message, t <= lastSuccessfulTime < t + h); then the outputs are readable and the
    // instance can be terminated (FMI 3.0 fmi3DoStep, "fmi3Discard").
    let mut big = Inst::cs(fmu);
    excite(&big);
    big.initialize();
    let huge = 1e3 * fmu.md.default_experiment.stop_time().unwrap_or(1.0).max(1.0);
    let (s, flags, last) = big.do_step(huge);
    if s == fmi3OK && flags[1] == 1 {
        // The model ended the simulation inside the step (terminateSimulation): the step ends there.
        assert!(
            (0.0..=huge).contains(&last),
            "{}: a step of {huge} that ended the simulation: lastSuccessfulTime {last}",
            fmu.id
        );
        info(format!("a step of {huge} s: the model ended the simulation at {last}"));
    } else if s == fmi3OK {
        crate::outcome::warn_unless(crate::outcome::same_time(last, huge, huge), || {
            format!(
                "{}: a completed step of {huge} (absurd input): lastSuccessfulTime {last}, not t + h within a tolerance relative to the step",
                fmu.id
            )
        });
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
    // eventHandlingNeeded only where the instance uses event mode (an FMU with clocks, made with
    // eventModeUsed: an event in the huge step is the importer's to handle).
    assert!(
        flags[1] <= 1 && (flags[0] == 0 || big.auto_events && flags[0] == 1) && flags[2] == 0,
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
    let t = big.unary("fmi3Terminate", api.terminate);
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
    // Through the call log (Inst::set_debug_logging): a failure leaves a reproducer that makes
    // these calls again.
    let cats = &fmu.md.log_categories;
    let s = i.set_debug_logging(true, cats.len(), Some(cats.as_slice()));
    crate::calllog::standard_requires(crate::replay::Expected::OK);
    assert_eq!(
        s,
        fmi3OK,
        "{}: fmi3SetDebugLogging with the declared categories {:?}: {}",
        fmu.id,
        fmu.md.log_categories,
        i.log_text()
    );
    // A NULL category array with a count of 0, which the standard allows.
    let s = i.set_debug_logging(true, 0, None);
    crate::calllog::standard_requires(crate::replay::Expected::OK);
    assert_eq!(
        s,
        fmi3OK,
        "{}: fmi3SetDebugLogging(true, 0, NULL): {}",
        fmu.id,
        i.log_text()
    );
    let s = i.set_debug_logging(true, 1, Some(&["noSuchCategory".to_string()][..]));
    crate::calllog::standard_requires(crate::replay::Expected::ERROR);
    assert_eq!(
        s,
        fmi3Error,
        "{}: fmi3SetDebugLogging with an undeclared category: {}",
        fmu.id,
        status_name(s)
    );
    // NULL categories with a count of 1 on purpose: the FMU must refuse without reading them.
    let s = i.set_debug_logging(true, 1, None);
    crate::calllog::standard_requires(crate::replay::Expected::ERROR);
    assert_eq!(
        s,
        fmi3Error,
        "{}: fmi3SetDebugLogging(nCategories = 1, categories = NULL): {}",
        fmu.id,
        status_name(s)
    );
    let s = i.set_debug_logging(false, 0, None);
    crate::calllog::standard_requires(crate::replay::Expected::OK);
    assert_eq!(s, fmi3OK);
}

/// Every getter, with every (non-clocked) variable through its own type's getter
/// ([`Inst::observe`]: every element of the arrays, each Binary), all Float64 at once, each
/// String, and in Model Exchange fmi3GetNumberOfContinuousStates and the state vectors, after
/// initialization and after a step, in each declared interface: each writes no byte past the
/// array it is given (the guard after every buffer, `src/guard.rs`).
///
/// Verdict: a byte written past the array is a failure: FMI 3.0.2, Getting and Setting Variable
/// Values (`nValues` is the size of the `values` array the importer provides), and the
/// model-exchange functions' `size_t` and vectors of nContinuousStates elements. What the
/// values are is other checks' business.
pub fn fmi3_getters_write_no_value_past_the_array_they_are_given(fmu: &Fmu3) {
    for me in [false, true] {
        if (me && fmu.md.me.is_none()) || (!me && fmu.md.cs.is_none()) {
            continue;
        }
        let mut inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
        excite(&inst);
        inst.initialize();
        for round in 0..2 {
            if round == 1 {
                inst.step(fmu.step_size());
            }
            let _ = inst.observe();
            let floats: Vec<&Variable> = fmu.md.of_type(Type::Float64).filter(|v| v.clocks.is_empty()).collect();
            let _ = inst.get_f64_of(&floats);
            for v in fmu.md.of_type(Type::String).filter(|v| !v.array && v.clocks.is_empty()) {
                let mut out = [null::<std::ffi::c_char>()];
                inst.args(vec![
                    ("vr", crate::calllog::Val::U32s(vec![v.vr])),
                    ("nValues", crate::calllog::Val::U64(1)),
                ]);
                // SAFETY: a live instance; one value reference, one value (and the guard after it).
                inst.call("fmi3GetString", |c| unsafe {
                    fill(&mut out, "fmi3GetString", "nValues", RULE, |p| {
                        (fmu.api.get_string)(c, &v.vr, 1, p, 1)
                    })
                });
            }
            if me {
                let n = inst.n_states();
                if n != usize::MAX {
                    let _ = inst.vector("fmi3GetContinuousStates", fmu.api.get_continuous_states, n);
                    let _ = inst.vector(
                        "fmi3GetContinuousStateDerivatives",
                        fmu.api.get_continuous_state_derivatives,
                        n,
                    );
                }
            }
        }
    }
}

/// fmi3DoStep answered fmi3OK (without early return) three times from the start time: the FMU is
/// at t0 + 3 h, as its time variable (the `independent` Float64) and the `lastSuccessfulTime` of
/// each step say (within a millionth of the step: `outcome::same_time`); with the default
/// experiment's step and with the step of the native C host (at most 1 ms), which may be shorter
/// than a fixed step the FMU computes with inside.
///
/// Verdict: a failure where either says another time after fmi3OK without early return: FMI
/// 3.0.2 §4.2.1 (fmi3DoStep computes the communication step from currentCommunicationPoint to
/// currentCommunicationPoint + communicationStepSize; with fmi3OK and earlyReturn = false the
/// step was computed to its end, and lastSuccessfulTime is that end; a step the FMU cannot
/// complete is answered fmi3Discard or returns early). This check carries that verdict alone: the
/// other checks that meet the same time (the time variable's, the output arguments', the
/// intermediate update's, event mode's, the ME/CS comparison and the C host) note it and point
/// here, so that one defect is one failure. Skipped without `<CoSimulation>`.
pub fn fmi3_do_step_advances_time_by_the_step(fmu: &Fmu3) {
    if fmu.md.cs.is_none() {
        skip_not_declared("<CoSimulation>");
    }
    let Some(time) = fmu.md.independent().filter(|v| v.ty == Type::Float64) else {
        panic!(
            "{}: no Float64 variable with causality=\"independent\" (FMI 3.0.2 §2.4.7.4: exactly one is required)",
            fmu.id
        )
    };
    let default = fmu.step_size();
    let short = default.min(1e-3);
    let sizes: &[f64] = if short < default { &[default, short] } else { &[default] };
    for &h in sizes {
        let mut inst = Inst::cs(fmu);
        excite(&inst);
        inst.initialize();
        let t0 = inst.time;
        for n in 1..=3 {
            let (s, flags, last) = inst.do_step(h);
            assert_eq!(s, fmi3OK, "{}: fmi3DoStep {n} of h = {h}: {}", fmu.id, inst.log_text());
            if flags[2] == 1 {
                skip("fmi3DoStep returned early (earlyReturn), so the step's end is not where it stopped");
            }
            crate::calllog::expect_values(&[inst.time], crate::outcome::time_tolerance(inst.time, h));
            assert!(
                crate::outcome::same_time(last, inst.time, h),
                "{}: after {n} fmi3DoStep of h = {h} from t = {t0} answered fmi3OK without earlyReturn, lastSuccessfulTime \
                 is {last}, expected {} (FMI 3.0.2 §4.2.1, fmi3DoStep: fmi3OK without earlyReturn means the step was \
                 computed to currentCommunicationPoint + communicationStepSize, and lastSuccessfulTime is its end)",
                fmu.id,
                inst.time
            );
            let (s, v) = inst.get_f64(&[time.vr]);
            crate::calllog::expect_values(&[inst.time], crate::outcome::time_tolerance(inst.time, h));
            assert!(
                s == fmi3OK && crate::outcome::same_time(v[0], inst.time, h),
                "{}: after {n} fmi3DoStep of h = {h} from t = {t0} answered fmi3OK, the time variable '{}' reads {} ({}), \
                 expected {} (FMI 3.0.2 §4.2.1, fmi3DoStep: fmi3OK without earlyReturn means the step was computed to \
                 currentCommunicationPoint + communicationStepSize)",
                fmu.id,
                time.name,
                v[0],
                status_name(s),
                inst.time
            );
        }
    }
}

/// Notes (as information, not a failure) that a step answered fmi3OK without early return ended
/// at `reached`, not at `end`: [`fmi3_do_step_advances_time_by_the_step`] carries that verdict.
pub(super) fn time_judged_by_the_named_check(what: &str, reached: f64, end: f64) {
    info(format!(
        "{what}: {reached} where the step ended at {end}; judged by fmi3_do_step_advances_time_by_the_step (one defect, one failure)"
    ));
}

/// The interface a check of any declared interface drives: co-simulation where declared, else
/// model exchange; skipped (naming the declarations) on an FMU of Scheduled Execution only.
fn cs_or_me(fmu: &Fmu3) -> bool {
    match (fmu.md.cs.is_some(), fmu.md.me.is_some()) {
        (true, _) => false,
        (false, true) => true,
        (false, false) => skip_not_declared("<CoSimulation> or <ModelExchange> (this check drives one of them)"),
    }
}

/// fmi3FreeInstance of an instance in each state an importer frees one in: Instantiated,
/// Initialization Mode, after a step (Step Mode; model exchange: Continuous-Time Mode),
/// Terminated. Each call must return; a crash or a hang in it fails this check with the call it
/// died in (the worker's report).
///
/// Verdict: a crash in fmi3FreeInstance is a failure: FMI 3.0.2 §2.3.1 (fmi3FreeInstance
/// disposes of the instance and frees all the memory and other resources its functions
/// allocated; a call allowed in every state of the super state FMU State Setable), with the
/// instance the instantiation function returned; the importer's process dies with it.
pub fn fmi3_free_instance_frees_an_instance_in_every_state_without_crashing(fmu: &Fmu3) {
    let me = cs_or_me(fmu);
    let new = || if me { Inst::me(fmu) } else { Inst::cs(fmu) };
    let h = fmu.step_size();
    // Instantiated.
    drop(new());
    // Initialization Mode.
    let mut inst = new();
    assert_eq!(
        inst.enter_init(0.0),
        fmi3OK,
        "{}: fmi3EnterInitializationMode: {}",
        fmu.id,
        inst.log_text()
    );
    drop(inst);
    // After a step.
    let mut inst = new();
    inst.initialize();
    inst.step(h);
    drop(inst);
    // Terminated.
    let mut inst = new();
    inst.initialize();
    inst.step(h);
    let s = inst.unary("fmi3Terminate", fmu.api.terminate);
    assert_eq!(s, fmi3OK, "{}: fmi3Terminate: {}", fmu.id, inst.log_text());
    drop(inst);
}

/// After initialization and after a step, every variable the model description declares (but
/// Clocks and clocked variables, which are read only at their clocks' ticks) is read alone
/// through its type's getter (every element of an array), by the value reference the
/// description gives it: the binary must know it.
///
/// Verdict: a declared variable refused (any status but fmi3OK/fmi3Warning) is a failure: the
/// description and the binary disagree. FMI 3.0.2 §2.4.7 (`valueReference` identifies the
/// variable in the C API) and §4.2.1 (Step Mode: fmi3Get{VariableType} on the variables);
/// fmi3Error is for "illegal arguments" (§2.2.4), which a declared value reference is not.
pub fn fmi3_the_binary_knows_every_variable_its_description_declares(fmu: &Fmu3) {
    let me = cs_or_me(fmu);
    let mut inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
    excite(&inst);
    inst.initialize();
    for round in 0..2 {
        if round == 1 {
            inst.step(fmu.step_size());
        }
        let when = if round == 0 {
            "after initialization"
        } else {
            "after a step"
        };
        for v in fmu
            .md
            .variables
            .iter()
            .filter(|v| v.ty != Type::Clock && v.clocks.is_empty())
        {
            let (function, s) = if v.ty == Type::String {
                let n = fmu.element_count(v);
                let mut out = vec![null::<std::ffi::c_char>(); n];
                inst.args(vec![
                    ("vr", crate::calllog::Val::U32s(vec![v.vr])),
                    ("nValues", crate::calllog::Val::U64(n as u64)),
                ]);
                // SAFETY: a live instance; one value reference, n values (and the guard after them).
                let s = inst.call("fmi3GetString", |c| unsafe {
                    fill(&mut out, "fmi3GetString", "nValues", RULE, |p| {
                        (fmu.api.get_string)(c, &v.vr, 1, p, n)
                    })
                });
                ("fmi3GetString".to_string(), s)
            } else {
                (format!("fmi3Get{}", crate::fmi3::accessor(v.ty)), inst.get_raw(v).0)
            };
            assert!(
                s == fmi3OK || s == fmi3Warning,
                "{}: {function} of the declared variable '{}' (value reference {}) answered {} {when}: the binary \
                 does not know a variable its description declares (FMI 3.0.2 §2.4.7: the valueReference \
                 identifies the variable in the C API). Log: {}",
                fmu.id,
                v.name,
                v.vr,
                status_name(s),
                inst.log_text()
            );
        }
    }
}
