//! Bad and edge-case arguments of every kind an importer can pass, for every packaged FMU:
//! fmi2Instantiate, get/set, fmi2DoStep, fmi2Reset and logging. Each refusal must come with
//! fmi2Error, a logged reason, and the FMU state exactly as it was (compared byte for byte
//! through the serialized FMU state).
//!
//! On another exporter's FMU, the wording of the messages and this exporter's log categories
//! are not required, and fmi2Reset is tried from the states an importer can reach.

#![allow(non_upper_case_globals)] // fmi2OK etc. are the standard's names, matched on

use crate::fmi2::*;
use crate::instance::{Args, Instance, excitation, excite, run, run_on, status_name, step_size};
use crate::outcome::{convention, info, limitation, skip_not_declared};
use crate::standard::REACHABLE;
use crate::state::{STATES, State, name};
use crate::{Fmu, Type};
use fmi_description::{Causality, Initial, Variability};
use std::ptr;

/// `(name, status)` of a raw call of the C API, with a breadcrumb naming it first (so that a
/// crash in it is reported with the call).
macro_rules! raw {
    ($name:literal, $call:expr) => {{
        crate::outcome::breadcrumb(concat!($name, ": ", stringify!($call)));
        ($name, $call)
    }};
}

fn refused(inst: &Instance, what: &str, status: fmi2Status, must_say: &[&str]) {
    let log = inst.log();
    assert_eq!(
        status,
        fmi2Error,
        "{}: {what}: expected fmi2Error, got {}",
        inst.fmu.id,
        status_name(status)
    );
    assert!(
        inst.says(&log, fmi2Error, must_say),
        "{}: {what}: expected an error message containing {must_say:?}; log: {log:#?}",
        inst.fmu.id
    );
}

// ---- fmi2Instantiate -----------------------------------------------------------------------

pub fn instantiate_refuses_a_wrong_null_or_empty_guid_with_a_message(fmu: &Fmu) {
    for guid in [Some("{00000000-0000-0000-0000-000000000000}"), Some(""), None] {
        let args = Args {
            guid: guid.map(String::from),
            ..Args::valid(fmu)
        };
        let log = Instance::with(fmu, &args)
            .err()
            .unwrap_or_else(|| panic!("{}: GUID {guid:?} accepted", fmu.id));
        assert!(
            says(fmu, &log, fmi2Error, &["GUID"]),
            "{}: GUID {guid:?}: no message about the GUID: {log:?}",
            fmu.id
        );
    }
}

pub fn instantiate_refuses_a_null_or_empty_instance_name_with_a_message(fmu: &Fmu) {
    for name in [Some(""), None] {
        let args = Args {
            name: name.map(String::from),
            ..Args::valid(fmu)
        };
        let log = Instance::with(fmu, &args)
            .err()
            .unwrap_or_else(|| panic!("{}: name {name:?} accepted", fmu.id));
        assert!(
            says(fmu, &log, fmi2Error, &["instanceName"]),
            "{}: name {name:?}: {log:?}",
            fmu.id
        );
    }
}

/// fmi2ModelExchange is refused unless the FMU declares `<ModelExchange>` (then it is
/// accepted); an unknown fmuType always.
pub fn instantiate_refuses_model_exchange_and_unknown_types_with_a_message(fmu: &Fmu) {
    for (ty, word) in [(fmi2ModelExchange, "fmi2ModelExchange"), (7, "fmuType")] {
        if ty == fmi2ModelExchange && fmu.md.me.is_some() {
            // Declared: fmi2ModelExchange must be accepted (the model-exchange checks go on).
            let args = Args {
                fmu_type: ty,
                ..Args::valid(fmu)
            };
            if let Err(log) = Instance::with(fmu, &args) {
                panic!(
                    "{}: the FMU declares <ModelExchange>, but fmi2Instantiate(fmi2ModelExchange) refused: {log:?}",
                    fmu.id
                );
            }
            continue;
        }
        let args = Args {
            fmu_type: ty,
            ..Args::valid(fmu)
        };
        let log = Instance::with(fmu, &args)
            .err()
            .unwrap_or_else(|| panic!("{}: fmuType {ty} accepted", fmu.id));
        assert!(
            log.iter().any(|e| e.text.contains(word)) || says(fmu, &log, fmi2Error, &[word]),
            "{}: fmuType {ty}: {log:?}",
            fmu.id
        );
    }
}

pub fn instantiate_without_callbacks_or_logger_returns_null_without_crashing(fmu: &Fmu) {
    let guid = std::ffi::CString::new(fmu.md.guid.as_str()).unwrap();
    let no_logger = fmi2CallbackFunctions {
        logger: None,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: ptr::null_mut(),
    };
    for callbacks in [ptr::null(), &no_logger as *const _] {
        // SAFETY: valid strings; the callbacks are NULL or have a NULL logger.
        let c = unsafe {
            (fmu.api.instantiate)(
                c"x".as_ptr(),
                fmi2CoSimulation,
                guid.as_ptr(),
                ptr::null(),
                callbacks,
                fmi2False,
                fmi2True,
            )
        };
        assert!(c.is_null(), "{}: instantiated without a logger", fmu.id);
    }
}

pub fn instantiate_accepts_every_resource_location_form_and_a_missing_folder(fmu: &Fmu) {
    // The FMU's own unpacked resources/, and a copy of it under a name that needs encoding.
    let abs = fmu.dir.join("resources");
    let dir = fmu.dir.join("resources with space%");
    copy_tree(&abs, &dir).unwrap_or_else(|e| panic!("{}: copying resources/: {e}", fmu.id));
    let encoded = format!(
        "file://{}",
        dir.display().to_string().replace('%', "%25").replace(' ', "%20")
    );
    assert!(encoded.ends_with("resources%20with%20space%25"));
    // (location, whether it holds the FMU's resources)
    let locations = [
        (Some(format!("file://{}", abs.display())), true),
        (Some(format!("file:{}", abs.display())), true),
        (Some(format!("file://localhost{}", abs.display())), true),
        (Some(encoded), true),
        (Some(format!("file://{}/no/such/folder", fmu.dir.display())), false),
        (Some("http://example.org/resources".into()), false),
        (Some(String::new()), false),
        (None, false),
    ];
    let mut needs_them = vec![];
    for (loc, has_files) in locations {
        let args = Args {
            resources: loc.clone(),
            ..Args::valid(fmu)
        };
        let mut inst = match Instance::with(fmu, &args) {
            Ok(inst) => inst,
            // An FMU that reads its resources when it is instantiated (a container FMU, whose
            // system is there) cannot be made without them: NULL with an fmi2Error message
            // naming what is missing is its answer. With its files, refusing is a failure.
            Err(log) if !has_files && log.iter().any(|e| e.status == fmi2Error) => {
                needs_them.push(format!("{loc:?} (at fmi2Instantiate)"));
                continue;
            }
            Err(log) => panic!("{}: resourceLocation {loc:?} refused: {log:?}", fmu.id),
        };
        if has_files {
            inst.initialize();
            assert_eq!(
                inst.step(step_size(fmu)),
                fmi2OK,
                "{}: after resourceLocation {loc:?}",
                fmu.id
            );
            continue;
        }
        // Without its files a model that reads them cannot initialize: an fmi2Error with a
        // message is its right answer (the standard only says a missing folder is no reason
        // to refuse the instance); anything else must run as usual.
        let s = [inst.setup(0.0, None), inst.enter_init(), inst.exit_init()];
        if s.iter().all(|s| *s == fmi2OK) {
            assert_eq!(
                inst.step(step_size(fmu)),
                fmi2OK,
                "{}: after resourceLocation {loc:?}",
                fmu.id
            );
        } else {
            let log = inst.log();
            assert!(
                s.iter().all(|s| *s == fmi2OK || *s == fmi2Error) && log.iter().any(|e| e.status == fmi2Error),
                "{}: initialization with resourceLocation {loc:?} answered {s:?} with no fmi2Error message: {log:?}",
                fmu.id
            );
            needs_them.push(format!("{loc:?}"));
        }
    }
    if !needs_them.is_empty() {
        info(format!(
            "initialization needs the FMU's resources: refused with a message for {}",
            needs_them.join(", ")
        ));
    }
}

/// Copies the folder `from` (files and sub-folders) to `to`.
fn copy_tree(from: &std::path::Path, to: &std::path::Path) -> std::io::Result<()> {
    std::fs::create_dir_all(to)?;
    for e in std::fs::read_dir(from)? {
        let e = e?;
        let target = to.join(e.file_name());
        if e.file_type()?.is_dir() {
            copy_tree(&e.path(), &target)?;
        } else {
            std::fs::copy(e.path(), target)?;
        }
    }
    Ok(())
}

// ---- get and set ---------------------------------------------------------------------------

/// [`Instance::says`] for a log taken without an instance (a refused fmi2Instantiate).
fn says(fmu: &Fmu, log: &[crate::LogEntry], status: fmi2Status, words: &[&str]) -> bool {
    log.iter()
        .any(|e| e.status == status && words.iter().all(|w| e.text.contains(w)))
        || (!convention(fmu, "the wording of messages (which words name what is wrong)")
            && log.iter().any(|e| e.status == status))
}

fn initialized(fmu: &Fmu) -> Instance<'_> {
    let mut inst = Instance::new(fmu);
    inst.initialize();
    inst
}

pub fn unknown_value_references_are_refused_with_a_message_naming_them(fmu: &Fmu) {
    let mut inst = initialized(fmu);
    for vr in [fmu.md.unknown_vr(), u32::MAX] {
        let before = inst.fingerprint();
        let n = vr.to_string();
        let s = inst.get_real(&[vr]).0;
        refused(&inst, "fmi2GetReal(unknown vr)", s, &["fmi2GetReal", &n]);
        let s = inst.get_integer(&[vr]).0;
        refused(&inst, "fmi2GetInteger(unknown vr)", s, &["fmi2GetInteger", &n]);
        let s = inst.get_boolean(&[vr]).0;
        refused(&inst, "fmi2GetBoolean(unknown vr)", s, &["fmi2GetBoolean", &n]);
        let s = inst.set_real(&[vr], &[1.0]);
        refused(&inst, "fmi2SetReal(unknown vr)", s, &["fmi2SetReal", &n]);
        let s = inst.set_integer(&[vr], &[1]);
        refused(&inst, "fmi2SetInteger(unknown vr)", s, &["fmi2SetInteger", &n]);
        let s = inst.set_boolean(&[vr], &[true]);
        refused(&inst, "fmi2SetBoolean(unknown vr)", s, &["fmi2SetBoolean", &n]);
        let mut out: [fmi2String; 1] = [ptr::null()];
        // SAFETY: arrays of one element.
        let s = unsafe { (fmu.api.get_string)(inst.c, &vr, 1, out.as_mut_ptr()) };
        refused(&inst, "fmi2GetString(unknown vr)", s, &["fmi2GetString", &n]);
        let v = [c"x".as_ptr()];
        // SAFETY: arrays of one element.
        let s = unsafe { (fmu.api.set_string)(inst.c, &vr, 1, v.as_ptr()) };
        refused(&inst, "fmi2SetString(unknown vr)", s, &["fmi2SetString", &n]);
        assert_eq!(
            inst.fingerprint(),
            before,
            "{}: refused calls changed the FMU state",
            fmu.id
        );
    }
    // A known vr of another type.
    let real = fmu.md.vrs_of_type(Type::Real)[0];
    if !fmu.md.vrs_of_type(Type::Integer).contains(&real) {
        let s = inst.get_integer(&[real]).0;
        refused(
            &inst,
            "fmi2GetInteger(a Real vr)",
            s,
            &["fmi2GetInteger", &real.to_string()],
        );
    }
}

pub fn zero_values_with_null_arrays_are_fine_and_null_arrays_with_values_are_refused(fmu: &Fmu) {
    let mut inst = initialized(fmu);
    let api = &fmu.api;
    let c = inst.c;
    let vr = [fmu.md.vrs_of_type(Type::Real)[0]];
    let mut r = [0.0];
    let mut i = [0];
    let mut st: [fmi2String; 1] = [ptr::null()];
    // SAFETY: nvr = 0 with NULL arrays is valid; with nvr = 1 the FMU must check for NULL.
    unsafe {
        let empty = [
            raw!(
                "nvr = 0, NULL arrays",
                (api.get_real)(c, ptr::null(), 0, ptr::null_mut())
            ),
            raw!(
                "nvr = 0, NULL arrays",
                (api.get_integer)(c, ptr::null(), 0, ptr::null_mut())
            ),
            raw!(
                "nvr = 0, NULL arrays",
                (api.get_boolean)(c, ptr::null(), 0, ptr::null_mut())
            ),
            raw!(
                "nvr = 0, NULL arrays",
                (api.get_string)(c, ptr::null(), 0, ptr::null_mut())
            ),
            raw!("nvr = 0, NULL arrays", (api.set_real)(c, ptr::null(), 0, ptr::null())),
            raw!(
                "nvr = 0, NULL arrays",
                (api.set_integer)(c, ptr::null(), 0, ptr::null())
            ),
            raw!(
                "nvr = 0, NULL arrays",
                (api.set_boolean)(c, ptr::null(), 0, ptr::null())
            ),
            raw!("nvr = 0, NULL arrays", (api.set_string)(c, ptr::null(), 0, ptr::null())),
        ];
        assert_eq!(
            empty.map(|(_, s)| s),
            [fmi2OK; 8],
            "{}: nvr = 0 with NULL arrays",
            fmu.id
        );
        let null_cases = [
            raw!("fmi2GetReal", (api.get_real)(c, ptr::null(), 1, r.as_mut_ptr())),
            raw!("fmi2GetReal", (api.get_real)(c, vr.as_ptr(), 1, ptr::null_mut())),
            raw!("fmi2GetInteger", (api.get_integer)(c, ptr::null(), 1, i.as_mut_ptr())),
            raw!("fmi2GetInteger", (api.get_integer)(c, vr.as_ptr(), 1, ptr::null_mut())),
            raw!("fmi2GetBoolean", (api.get_boolean)(c, ptr::null(), 1, i.as_mut_ptr())),
            raw!("fmi2GetBoolean", (api.get_boolean)(c, vr.as_ptr(), 1, ptr::null_mut())),
            raw!("fmi2GetString", (api.get_string)(c, ptr::null(), 1, st.as_mut_ptr())),
            raw!("fmi2GetString", (api.get_string)(c, vr.as_ptr(), 1, ptr::null_mut())),
            raw!("fmi2SetReal", (api.set_real)(c, ptr::null(), 1, r.as_ptr())),
            raw!("fmi2SetReal", (api.set_real)(c, vr.as_ptr(), 1, ptr::null())),
            raw!("fmi2SetInteger", (api.set_integer)(c, ptr::null(), 1, i.as_ptr())),
            raw!("fmi2SetInteger", (api.set_integer)(c, vr.as_ptr(), 1, ptr::null())),
            raw!("fmi2SetBoolean", (api.set_boolean)(c, ptr::null(), 1, i.as_ptr())),
            raw!("fmi2SetBoolean", (api.set_boolean)(c, vr.as_ptr(), 1, ptr::null())),
            raw!("fmi2SetString", (api.set_string)(c, ptr::null(), 1, st.as_ptr())),
            raw!("fmi2SetString", (api.set_string)(c, vr.as_ptr(), 1, ptr::null())),
        ];
        let log = inst.log();
        for (f, s) in null_cases {
            assert_eq!(s, fmi2Error, "{}: {f} with a NULL array and nvr = 1", fmu.id);
            let messages = log
                .iter()
                .filter(|e| e.text.contains(f) && e.text.contains("NULL"))
                .count();
            assert_eq!(
                messages, 2,
                "{}: {f}: one message per refused call expected: {log:?}",
                fmu.id
            );
        }
    }
    inst.time = 0.0;
    assert_eq!(
        inst.step(step_size(fmu)),
        fmi2OK,
        "{}: usable after the refusals",
        fmu.id
    );
}

/// For every variable, in each state where fmi2SetXXX is allowed, the FMU accepts exactly the
/// variables the standard lets an importer set there; a refusal names the variable and leaves
/// the FMU state as it was. Covers outputs, calculated parameters, fixed parameters after
/// initialization, and tunable parameters between steps.
pub fn each_variable_can_be_set_exactly_where_the_standard_allows_it(fmu: &Fmu) {
    let mut failures = vec![];
    for state in [State::Instantiated, State::InitializationMode, State::StepComplete] {
        for v in fmu
            .md
            .variables
            .iter()
            // An alias is checked through the first variable of its set.
            .filter(|v| v.ty != Type::String && !crate::standard::aliases_an_earlier(&fmu.md.variables, v))
        {
            let mut inst = Instance::new(fmu);
            match state {
                State::Instantiated => {}
                State::InitializationMode => assert_eq!([inst.setup(0.0, None), inst.enter_init()], [fmi2OK; 2]),
                _ => inst.initialize(),
            }
            let before = inst.fingerprint();
            let s = match v.ty {
                Type::Real => inst.set_real(&[v.vr], &[v.start_real().unwrap_or(0.0)]),
                Type::Integer | Type::Enumeration => inst.set_integer(&[v.vr], &[v.start_integer().unwrap_or(0)]),
                Type::Boolean => inst.set_boolean(&[v.vr], &[v.start_boolean().unwrap_or(false)]),
                Type::String => unreachable!(),
            };
            let log = inst.log();
            let want = crate::standard::settable_in(v, &name(state));
            let at = format!(
                "{}: set '{}' ({} {}, initial {:?}) in {state:?}",
                fmu.id,
                v.name,
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
                if s != fmi2Error {
                    failures.push(format!("{at}: not allowed, got {}", status_name(s)));
                } else if !inst.says(&log, fmi2Error, &[&format!("'{}'", v.name)]) {
                    failures.push(format!("{at}: the refusal does not name the variable: {log:?}"));
                }
                if inst.fingerprint() != before {
                    failures.push(format!("{at}: refused, but the FMU state changed"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

pub fn nan_and_infinite_values_are_refused_with_a_message_and_change_nothing(fmu: &Fmu) {
    for state in [State::Instantiated, State::InitializationMode, State::StepComplete] {
        let mut inst = Instance::new(fmu);
        match state {
            State::Instantiated => {}
            State::InitializationMode => assert_eq!([inst.setup(0.0, None), inst.enter_init()], [fmi2OK; 2]),
            _ => inst.initialize(),
        }
        let settable: Vec<_> = fmu
            .md
            .of_type(Type::Real)
            .filter(|v| crate::standard::settable_in(v, &name(state)))
            .collect();
        for v in &settable {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                let before = inst.fingerprint();
                let s = inst.set_real(&[v.vr], &[bad]);
                refused(
                    &inst,
                    &format!("set '{}' = {bad} in {state:?}", v.name),
                    s,
                    &[&format!("'{}'", v.name)],
                );
                assert_eq!(
                    inst.fingerprint(),
                    before,
                    "{}: '{}' = {bad} changed the FMU state",
                    fmu.id,
                    v.name
                );
            }
        }
        // All or nothing: a good value next to a bad one is not stored either.
        if let Some(first) = settable.first() {
            let before = inst.fingerprint();
            let s = inst.set_real(&[first.vr, first.vr], &[excite(first), f64::NAN]);
            refused(&inst, "a batch with one NaN", s, &["NaN"]);
            assert_eq!(inst.fingerprint(), before, "{}: a refused batch stored a value", fmu.id);
        }
    }
}

/// Values to retune a Real parameter to, best first: other values than its start value, inside
/// [min, max] and where a parameter can matter, halfway from the start value towards a declared
/// bound, else twice and half the start value (1 and -1 for a start value of 0). Never a bound
/// itself: a bound is a legal value, not a meaningful one (min = 5e-324, "positive", makes a
/// time constant's derivative infinite), and a model is right to answer it with an error.
fn retune_values(v: &crate::Variable) -> Vec<f64> {
    let start = v.start_real().unwrap_or(0.0);
    let (lo, hi) = (v.min.unwrap_or(f64::NEG_INFINITY), v.max.unwrap_or(f64::INFINITY));
    let mut candidates = vec![];
    if hi.is_finite() && hi > start {
        candidates.push(start + (hi - start) / 2.0);
    }
    if lo.is_finite() && lo < start {
        candidates.push(start - (start - lo) / 2.0);
    }
    if start != 0.0 {
        // start / 100 last: a limit (a torque bound, a saturation) that the excited run stays
        // far from acts only once it is small (a composed system's, whose excitation cannot
        // reach the limit through its inner connections).
        candidates.extend([start * 2.0, start / 2.0, -start, start / 100.0]);
    } else {
        candidates.extend([1.0, -1.0, 0.5, -0.5]);
    }
    let mut values: Vec<f64> = vec![];
    for x in candidates {
        // Inside the bounds, not on them, not a denormal-sized value next to one.
        let inside = x > lo && x < hi && x.is_finite() && x != start;
        let meaningful = x == 0.0 || x.abs() > 1e-300;
        if inside && meaningful && !values.contains(&x) {
            values.push(x);
        }
    }
    values
}

/// Another value for an input than the one [`excitation`] gives it, within [min, max]: the
/// input steps there between two steps.
fn stepped(v: &crate::Variable) -> f64 {
    let x = excite(v);
    let clamp = |y: f64| {
        let y = v.max.map_or(y, |m| y.min(m));
        v.min.map_or(y, |m| y.max(m))
    };
    [x * 2.0, x + 1.0, x - 1.0, v.start_real().unwrap_or(0.0)]
        .into_iter()
        .map(clamp)
        .find(|y| *y != x)
        .unwrap_or(x)
}

/// The values a tunable parameter is retuned to, one per attempt: Reals from
/// [`retune_values`], Integers one above and one below the start value (an integer mode has a
/// few legal values), a Boolean its negation.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Retune {
    Real(f64),
    Integer(i32),
    Boolean(bool),
}

fn retunes(p: &crate::Variable) -> Vec<Retune> {
    match p.ty {
        Type::Real => retune_values(p).into_iter().map(Retune::Real).collect(),
        Type::Integer => {
            let start = p.start_integer().unwrap_or(0);
            [start.checked_add(1), start.checked_sub(1)]
                .into_iter()
                .flatten()
                .filter(|x| p.min.is_none_or(|m| f64::from(*x) >= m) && p.max.is_none_or(|m| f64::from(*x) <= m))
                .map(Retune::Integer)
                .collect()
        }
        Type::Boolean => vec![Retune::Boolean(!p.start_boolean().unwrap_or(false))],
        _ => vec![],
    }
}

/// Sets a tunable parameter to `value`: whether the model accepted it (a refusal is an
/// fmi2Error; anything else but fmi2OK fails the check).
fn retune(inst: &mut Instance, p: &crate::Variable, value: Retune) -> bool {
    let s = match value {
        Retune::Real(x) => inst.set_real(&[p.vr], &[x]),
        Retune::Integer(x) => inst.set_integer(&[p.vr], &[x]),
        Retune::Boolean(x) => inst.set_boolean(&[p.vr], &[x]),
    };
    inst.log();
    if s != fmi2OK {
        assert_eq!(s, fmi2Error, "{}: setting '{}' to {value:?}", inst.fmu.id, p.name);
    }
    s == fmi2OK
}

/// A tunable parameter set between steps changes the trajectory from the next step on, and
/// not before. "Changes" is tried first from the excited run as it goes on; a parameter that
/// cannot matter there (a time constant of a lag at its steady state: the excitation sets the
/// input and the initial state alike) is tried again with the inputs stepped to other values
/// at the same step, compared with a run whose inputs step there too and whose parameter
/// stays. At least one tunable parameter must change something.
pub fn a_tunable_parameter_set_between_steps_takes_effect_at_the_next_step(fmu: &Fmu) {
    let tunables: Vec<_> = fmu
        .md
        .variables
        .iter()
        .filter(|v| v.causality == Causality::Parameter && v.variability == Variability::Tunable)
        .filter(|v| matches!(v.ty, Type::Real | Type::Integer | Type::Boolean))
        .collect();
    // The order of Instance::observe: Reals, then Integers, then Booleans.
    let observed: Vec<u32> = [Type::Real, Type::Integer, Type::Boolean]
        .iter()
        .flat_map(|t| fmu.md.vrs_of_type(*t))
        .collect();
    let inputs: Vec<(u32, f64)> = fmu
        .md
        .of_type(Type::Real)
        .filter(|v| v.causality == Causality::Input && v.variability != Variability::Constant)
        .map(|v| (v.vr, stepped(v)))
        .collect();
    // Steps long enough for a solver tolerance to matter (within 1 ms it rarely does).
    let h = 0.1;
    let (k, n) = (5, 10);
    // An excited run of n steps; before step k, the inputs step (`step_inputs`) and the
    // parameter is set (`p`, to a value). The observations if the model took the value: it may
    // refuse it when it is set (fmi2Error), or by failing a step after it (a value that makes the
    // model's derivative non-finite is the model's to refuse; `None` either way).
    let trajectory = |p: Option<(&crate::Variable, Retune)>, step_inputs: bool| -> Option<Vec<Vec<u64>>> {
        let mut inst = Instance::new(fmu);
        let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(fmu).into_iter().unzip();
        assert_eq!(inst.set_real(&vrs, &vals), fmi2OK);
        inst.initialize();
        let mut out = vec![inst.observe()];
        for step in 0..n {
            if step == k {
                if step_inputs {
                    let (vrs, vals): (Vec<u32>, Vec<f64>) = inputs.iter().copied().unzip();
                    assert_eq!(
                        inst.set_real(&vrs, &vals),
                        fmi2OK,
                        "{}: stepping the inputs: {}",
                        fmu.id,
                        inst.log_text()
                    );
                }
                if let Some((p, value)) = p
                    && !retune(&mut inst, p, value)
                {
                    return None;
                }
            }
            let s = inst.step(h);
            if s != fmi2OK
                && step >= k
                && let Some((p, value)) = p
            {
                info(format!(
                    "'{}' = {value:?} set at t = {:.1} s: the model answered the next steps with {} ({}); \
                     taken as its refusal of that value",
                    p.name,
                    k as f64 * h,
                    status_name(s),
                    inst.log_text()
                ));
                return None;
            }
            assert_eq!(s, fmi2OK, "{}: {}", fmu.id, inst.log_text());
            out.push(inst.observe());
        }
        Some(out)
    };
    let reference = run(fmu, n, h);
    let stepped_reference = (!inputs.is_empty()).then(|| trajectory(None, true).expect("no parameter set"));
    let mut effective = vec![];
    for p in &tunables {
        // Identical up to the change (only the parameter's own value differs), different after.
        let pi = observed.iter().position(|vr| *vr == p.vr).unwrap();
        let strip = |o: &Vec<u64>| {
            let mut o = o.clone();
            o.remove(pi);
            o
        };
        let differs = |out: &[Vec<u64>], reference: &[Vec<u64>]| {
            for step in 0..=k {
                assert_eq!(
                    strip(&out[step]),
                    strip(&reference[step]),
                    "{}: '{}' acted before it was set",
                    fmu.id,
                    p.name
                );
            }
            (k + 1..=n).any(|s| strip(&out[s]) != strip(&reference[s]))
        };
        // A value the model takes acts in the excited run, or else with the inputs stepped at
        // the same step; the values are tried in turn until one acts.
        for value in retunes(p) {
            let Some(out) = trajectory(Some((p, value)), false) else {
                continue;
            };
            let acts = differs(&out, &reference)
                || stepped_reference.as_ref().is_some_and(|stepped_reference| {
                    trajectory(Some((p, value)), true).is_some_and(|out| differs(&out, stepped_reference))
                });
            if acts {
                effective.push(p.name.clone());
                break;
            }
        }
    }
    // A parameter the FMU declares to change nothing: every <InitialUnknowns> element lists its
    // dependencies and none lists the parameter (the Reference-FMUs' Feedthrough stores its
    // tunable parameter and uses it nowhere). Such parameters need not act; they were checked
    // not to act before they were set like the others.
    let ms = &fmu.md.model_structure;
    let declared_inert = |p: &crate::Variable| {
        let index = fmu
            .md
            .variables
            .iter()
            .position(|v| v.vr == p.vr && v.name == p.name)
            .map(|i| i + 1);
        ms.initial_unknowns.iter().all(|u| {
            u.dependencies
                .as_ref()
                .is_some_and(|d| index.is_none_or(|i| !d.contains(&i)))
        })
    };
    let must_act: Vec<_> = tunables.iter().filter(|p| !declared_inert(p)).collect();
    if must_act.is_empty() && !tunables.is_empty() {
        info(format!(
            "tunable parameters {:?}: no <InitialUnknowns> element depends on them, so nothing was required to change",
            tunables.iter().map(|p| &p.name).collect::<Vec<_>>()
        ));
    }
    assert!(
        must_act.is_empty() || !effective.is_empty(),
        "{}: none of the tunable parameters {:?} changed anything after it was set between steps \
         (neither in the excited run nor with the inputs {:?} stepped at the same step)",
        fmu.id,
        must_act.iter().map(|p| &p.name).collect::<Vec<_>>(),
        inputs
    );
}

// ---- fmi2DoStep ----------------------------------------------------------------------------

pub fn do_step_refuses_a_step_size_that_is_not_finite_and_positive(fmu: &Fmu) {
    let h = step_size(fmu);
    let reference = run(fmu, 2, h);
    let mut inst = Instance::new(fmu);
    let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(fmu).into_iter().unzip();
    assert_eq!(inst.set_real(&vrs, &vals), fmi2OK);
    inst.initialize();
    assert_eq!(inst.step(h), fmi2OK);
    for bad in [
        0.0,
        -0.0,
        -h,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::MIN_POSITIVE / 4.0,
    ] {
        let before = inst.fingerprint();
        let s = inst.do_step(inst.time, bad);
        refused(&inst, &format!("fmi2DoStep(h = {bad:e})"), s, &["fmi2DoStep"]);
        assert_eq!(
            inst.fingerprint(),
            before,
            "{}: a refused step (h = {bad}) changed the FMU state",
            fmu.id
        );
        assert_eq!(inst.last_successful_time(), (fmi2OK, inst.time));
    }
    assert_eq!(
        inst.step(h),
        fmi2OK,
        "{}: a good step after the refusals: {}",
        fmu.id,
        inst.log_text()
    );
    assert_eq!(
        inst.observe(),
        reference[2],
        "{}: the refusals changed the trajectory",
        fmu.id
    );
}

pub fn do_step_compares_the_communication_point_with_a_relative_tolerance(fmu: &Fmu) {
    let h = 0.1;
    let mut inst = initialized(fmu);
    // An importer summing h: t = 0.1 + 0.1 + ... is not exactly n·h.
    let mut summed = 0.0;
    for n in 0..10 {
        let t = n as f64 * h;
        let s = inst.do_step(t, h);
        assert_eq!(
            s,
            fmi2OK,
            "{}: step {n} at t = {t:?} (summed {summed:?}): {}",
            fmu.id,
            inst.log_text()
        );
        summed += h;
    }
    inst.time = 10.0 * h;
    assert_ne!(summed, inst.time, "the round-off case this test is about");
    let s = inst.do_step(summed, h);
    assert_eq!(
        s,
        fmi2OK,
        "{}: t = {summed:?} where the FMU is at {:?}: {}",
        fmu.id,
        inst.time,
        inst.log_text()
    );
    inst.time = summed + h;
    // A real mismatch is refused, whatever the step size.
    for (dt, h) in [(1e-3, 0.1), (-1e-3, 0.1), (5.0, 1e9), (-0.5, 1e9)] {
        let before = inst.fingerprint();
        let s = inst.do_step(inst.time + dt, h);
        refused(
            &inst,
            &format!("fmi2DoStep off by {dt} with h = {h}"),
            s,
            &["currentCommunicationPoint"],
        );
        assert_eq!(
            inst.fingerprint(),
            before,
            "{}: a refused step changed the FMU state",
            fmu.id
        );
    }
}

pub fn do_step_beyond_the_stop_time_is_refused(fmu: &Fmu) {
    let mut inst = Instance::new(fmu);
    assert_eq!(
        [inst.setup(0.0, Some(0.05)), inst.enter_init(), inst.exit_init()],
        [fmi2OK; 3]
    );
    let s = inst.do_step(0.0, 0.1);
    refused(&inst, "a step past stopTime", s, &["stopTime"]);
    assert_eq!(
        inst.do_step(0.0, 0.05),
        fmi2OK,
        "{}: a step to stopTime: {}",
        fmu.id,
        inst.log_text()
    );
}

/// A huge step must end within bounded time with fmi2OK or fmi2Discard; after a discard the
/// status functions answer truthfully, another step is refused, and restoring an earlier FMU
/// state makes the instance usable again.
pub fn a_huge_step_completes_or_is_discarded_and_the_status_functions_tell_the_truth(fmu: &Fmu) {
    for huge in [1e6, 1e300, f64::MAX] {
        let mut inst = Instance::new(fmu);
        let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(fmu).into_iter().unzip();
        assert_eq!(inst.set_real(&vrs, &vals), fmi2OK);
        inst.initialize();
        let h = step_size(fmu);
        assert_eq!(inst.step(h), fmi2OK);
        let saved = fmu.can_snapshot().then(|| inst.snapshot());
        let t0 = inst.time;
        let clock = std::time::Instant::now();
        let s = inst.do_step(t0, huge);
        let took = clock.elapsed();
        assert!(took.as_secs() < 20, "{}: a step of {huge:e} s took {took:?}", fmu.id);
        let log = inst.log();
        match s {
            fmi2OK => {
                assert_eq!(inst.last_successful_time(), (fmi2OK, t0 + huge));
                if fmu.own_state_format() {
                    assert_eq!(inst.machine_state(), State::StepComplete);
                }
            }
            fmi2Discard => {
                let category = |e: &crate::LogEntry| {
                    e.category == "logStatusDiscard"
                        || !convention(fmu, "a discarded step's message under category logStatusDiscard")
                };
                assert!(
                    log.iter().any(|e| e.status == fmi2Discard && category(e)),
                    "{}: fmi2Discard without a message: {log:?}",
                    fmu.id
                );
                if fmu.own_state_format() {
                    assert_eq!(inst.machine_state(), State::StepFailed);
                }
                let (st, reached) = inst.last_successful_time();
                assert_eq!(st, fmi2OK);
                assert!(
                    reached >= t0 && reached < t0 + huge,
                    "{}: fmi2LastSuccessfulTime = {reached} after a discarded step from {t0} by {huge:e}",
                    fmu.id
                );
                // fmi2Terminated: true only where the model ended the simulation in the step.
                let (st, terminated) = inst.terminated();
                assert_eq!(st, fmi2OK, "{}: fmi2GetBooleanStatus(fmi2Terminated)", fmu.id);
                if terminated == fmi2True {
                    assert!(
                        log.iter()
                            .any(|e| e.status == fmi2Discard && e.text.contains("ended the simulation")),
                        "{}: fmi2Terminated after a discarded step, but no message says the model ended the simulation: {log:?}",
                        fmu.id
                    );
                }
                let values = inst.get_real(&fmu.md.vrs_of_type(Type::Real));
                assert_eq!(values.0, fmi2OK);
                assert!(
                    values.1.iter().all(|v| v.is_finite()),
                    "{}: values at the last successful time are not finite: {:?}",
                    fmu.id,
                    values.1
                );
                // No step after a discarded one until the state is restored.
                let s = inst.do_step(reached, h);
                refused(&inst, "a step after a discarded one", s, &["fmi2DoStep", "StepFailed"]);
                let Some(saved) = &saved else {
                    limitation(
                        "the FMU cannot serialize its state: restoring the state before a discarded step is not tried",
                    );
                    continue;
                };
                inst.restore(saved);
                inst.time = t0;
                assert_eq!(
                    inst.step(h),
                    fmi2OK,
                    "{}: a step after restoring: {}",
                    fmu.id,
                    inst.log_text()
                );
                assert_eq!(inst.terminate(), fmi2OK);
            }
            other => panic!(
                "{}: a step of {huge:e} answered {}: {log:?}",
                fmu.id,
                status_name(other)
            ),
        }
    }
}

pub fn status_functions_report_the_last_successful_time_and_no_termination_request(fmu: &Fmu) {
    let mut inst = initialized(fmu);
    let h = step_size(fmu);
    for _ in 0..3 {
        assert_eq!(inst.step(h), fmi2OK);
        assert_eq!(inst.last_successful_time(), (fmi2OK, inst.time));
        assert_eq!(inst.terminated(), (fmi2OK, fmi2False));
    }
    // Kinds that belong to another getter: fmi2Discard with a message, value untouched.
    let mut r = -1.0;
    // SAFETY: a valid out pointer.
    let s = unsafe { (fmu.api.get_real_status)(inst.c, fmi2Terminated, &mut r) };
    assert_eq!(
        (s, r),
        (fmi2Discard, -1.0),
        "{}: fmi2GetRealStatus(fmi2Terminated)",
        fmu.id
    );
    let mut b = -1;
    // SAFETY: a valid out pointer.
    let s = unsafe { (fmu.api.get_boolean_status)(inst.c, 99, &mut b) };
    assert_eq!((s, b), (fmi2Discard, -1), "{}: fmi2GetBooleanStatus(99)", fmu.id);
    // SAFETY: NULL out pointer: refused.
    let s = unsafe { (fmu.api.get_real_status)(inst.c, fmi2LastSuccessfulTime, ptr::null_mut()) };
    refused(&inst, "fmi2GetRealStatus(NULL)", s, &["NULL"]);
    assert_eq!(inst.terminate(), fmi2OK);
    assert_eq!(
        inst.last_successful_time(),
        (fmi2OK, inst.time),
        "{}: after fmi2Terminate",
        fmu.id
    );
}

// ---- fmi2Reset -----------------------------------------------------------------------------

/// From every state but Fatal; on another exporter's FMU from the states an importer reaches
/// by calls (the others need a forged FMU state).
pub fn reset_from_every_state_then_a_rerun_is_bit_identical(fmu: &Fmu) {
    let h = step_size(fmu);
    let reference = run(fmu, 20, h);
    let own = fmu.own_state_format();
    if !own {
        limitation(
            "fmi2Reset from StepFailed, StepCanceled and Error is not tried: only this exporter's FMUs can be put there",
        );
    }
    for s in STATES
        .into_iter()
        .filter(|s| *s != State::Fatal && (own || REACHABLE.contains(s)))
    {
        let mut inst = Instance::new(fmu);
        let first = run_on(&mut inst, 20, h);
        assert_eq!(first, reference, "{}: two fresh runs differ", fmu.id);
        if own && s != State::StepComplete {
            inst.force_state(s);
        } else {
            let calls = match s {
                State::Instantiated => vec![inst.reset()],
                State::InitializationMode => vec![inst.reset(), inst.setup(0.0, None), inst.enter_init()],
                State::Terminated => vec![inst.terminate()],
                _ => vec![],
            };
            assert!(
                calls.iter().all(|c| *c == fmi2OK),
                "{}: reaching {s:?} by calls: {calls:?}: {}",
                fmu.id,
                inst.log_text()
            );
        }
        assert_eq!(
            inst.reset(),
            fmi2OK,
            "{}: fmi2Reset from {s:?}: {}",
            fmu.id,
            inst.log_text()
        );
        if own {
            assert_eq!(inst.machine_state(), State::Instantiated);
        }
        // Every variable with a start value is back at it.
        assert_eq!([inst.setup(0.0, None), inst.enter_init()], [fmi2OK; 2]);
        for v in fmu.md.of_type(Type::Real).filter(|v| {
            v.causality != Causality::Output
                || crate::standard::initial(v.causality, v.variability, v.declared_initial) == Some(Initial::Exact)
        }) {
            if let Some(start) = v.start_real() {
                let (st, got) = inst.get_real(&[v.vr]);
                assert_eq!(
                    (st, got[0].to_bits()),
                    (fmi2OK, start.to_bits()),
                    "{}: '{}' after reset from {s:?}",
                    fmu.id,
                    v.name
                );
            }
        }
        assert_eq!(inst.reset(), fmi2OK);
        let again = run_on(&mut inst, 20, h);
        assert_eq!(
            again, reference,
            "{}: the run after fmi2Reset from {s:?} differs",
            fmu.id
        );
    }
}

// ---- logging -------------------------------------------------------------------------------

pub fn the_log_categories_importers_look_for_are_declared(fmu: &Fmu) {
    for c in [
        "logStatusError",
        "logStatusWarning",
        "logStatusDiscard",
        "logStatusFatal",
        "logAll",
        "logEvents",
    ] {
        if !fmu.md.log_categories.iter().any(|d| d == c)
            && convention(
                fmu,
                "the log categories this exporter declares (logStatus*, logAll, logEvents)",
            )
        {
            panic!("{}: <LogCategories> lacks {c}", fmu.id);
        }
    }
}

fn logged_run(fmu: &Fmu, logging_on: bool, debug: Option<(bool, &[&str])>) -> Vec<String> {
    let args = Args {
        logging_on,
        ..Args::valid(fmu)
    };
    let mut inst = Instance::with(fmu, &args).unwrap();
    if let Some((on, cats)) = debug {
        assert_eq!(inst.set_debug_logging(on, cats), fmi2OK, "{}", inst.log_text());
    }
    // What is logged from here on.
    inst.log();
    inst.initialize();
    assert_eq!(inst.step(step_size(fmu)), fmi2OK);
    inst.log().into_iter().map(|e| e.category).collect()
}

pub fn debug_logging_follows_logging_on_and_set_debug_logging(fmu: &Fmu) {
    assert_eq!(
        logged_run(fmu, false, None),
        Vec::<String>::new(),
        "{}: loggingOn = false",
        fmu.id
    );
    if !convention(
        fmu,
        "debug messages of a step under logEvents, and fmi2SetDebugLogging by this exporter's categories",
    ) {
        return;
    }
    let all_on = logged_run(fmu, true, None);
    assert!(
        all_on.iter().any(|c| c == "logEvents"),
        "{}: loggingOn = true: {all_on:?}",
        fmu.id
    );
    // nCategories = 0 means every category.
    let zero = logged_run(fmu, false, Some((true, &[])));
    assert_eq!(zero, all_on, "{}: fmi2SetDebugLogging(on, 0 categories)", fmu.id);
    let all = logged_run(fmu, false, Some((true, &["logAll"])));
    assert_eq!(all, all_on, "{}: fmi2SetDebugLogging(on, logAll)", fmu.id);
    let errors_only = logged_run(fmu, true, Some((true, &["logStatusError"])));
    assert_eq!(
        errors_only,
        Vec::<String>::new(),
        "{}: only logStatusError enabled",
        fmu.id
    );
    let events_only = logged_run(fmu, false, Some((true, &["logEvents"])));
    assert!(
        !events_only.is_empty() && events_only.iter().all(|c| c == "logEvents"),
        "{}: only logEvents enabled: {events_only:?}",
        fmu.id
    );
    let off = logged_run(fmu, true, Some((false, &[])));
    assert_eq!(off, Vec::<String>::new(), "{}: fmi2SetDebugLogging(off)", fmu.id);
}

pub fn set_debug_logging_refuses_unknown_categories_and_null_arrays(fmu: &Fmu) {
    let mut inst = Instance::new(fmu);
    let s = inst.set_debug_logging(true, &["logNoSuchThing"]);
    refused(&inst, "an unknown category", s, &["logNoSuchThing"]);
    // SAFETY: categories NULL with nCategories = 2: the FMU must check.
    let s = unsafe { (fmu.api.set_debug_logging)(inst.c, fmi2True, 2, ptr::null()) };
    refused(&inst, "NULL categories", s, &["NULL"]);
    let cats = [c"logEvents".as_ptr(), ptr::null()];
    // SAFETY: two entries, one NULL: the FMU must check each.
    let s = unsafe { (fmu.api.set_debug_logging)(inst.c, fmi2True, 2, cats.as_ptr()) };
    refused(&inst, "a NULL category", s, &["NULL"]);
}

pub fn a_percent_sign_in_a_message_reaches_the_logger_verbatim(fmu: &Fmu) {
    let args = Args {
        name: Some("inst %s %n %d %%".into()),
        ..Args::valid(fmu)
    };
    let mut inst = Instance::with(fmu, &args).unwrap();
    let s = inst.set_debug_logging(true, &["log%s%n%x%%"]);
    // Instance::log checks that the format is "%s" and the instance name came back intact.
    refused(&inst, "a category with '%'", s, &["'log%s%n%x%%'"]);
}

pub fn each_instance_logs_to_its_own_component_environment(fmu: &Fmu) {
    let mut a = Instance::new(fmu);
    let mut b = Instance::with(
        fmu,
        &Args {
            name: Some("second".into()),
            ..Args::valid(fmu)
        },
    )
    .unwrap();
    a.initialize();
    b.initialize();
    let (sa, sb) = (a.do_step(1.0, 0.1), b.do_step(2.0, 0.1));
    assert_eq!((sa, sb), (fmi2Error, fmi2Error));
    // Instance::log checks environment and name of every entry.
    let (la, lb) = (a.log(), b.log());
    assert!(a.says(&la, fmi2Error, &["= 1"]), "{}: {la:?}", fmu.id);
    assert!(b.says(&lb, fmi2Error, &["= 2"]), "{}: {lb:?}", fmu.id);
}

/// How far a declared output derivative may be from the finite differences of the output: the
/// second-order one-sided difference (4 y(t+d) - y(t+2d) - 3 y(t)) / 2d, whose error is of order
/// d^2, against the derivative, relative to their size; where the first-order differences over d
/// and 2d disagree by more than a tenth (an event, a kink) the point says nothing and is skipped.
/// `None`: agrees or skipped (the bool says skipped); `Some(message)`: disagrees.
pub(crate) fn output_derivative_disagrees(y: [f64; 3], d: f64, dy: f64) -> (bool, Option<String>) {
    let (fd1, fd2) = ((y[1] - y[0]) / d, (y[2] - y[0]) / (2.0 * d));
    if (fd1 - fd2).abs() > 0.1 * fd1.abs().max(fd2.abs()) + 1e-9 {
        return (true, None);
    }
    let estimate = (4.0 * y[1] - y[2] - 3.0 * y[0]) / (2.0 * d);
    // Relative 1e-3, and what an integrator's round-off of 1e-8 in the output makes of a
    // difference over d.
    let tolerance = 1e-3 * dy.abs().max(estimate.abs()) + 1e-8 * y[0].abs().max(1.0) / d;
    if (estimate - dy).abs() <= tolerance {
        (false, None)
    } else {
        (
            false,
            Some(format!(
                "derivative {dy}, finite differences {estimate} (first order {fd1}, {fd2})"
            )),
        )
    }
}

/// fmi2GetRealOutputDerivatives with `maxOutputDerivativeOrder` >= 1: at three communication
/// points the first derivative of every continuous Real output agrees with the output's finite
/// differences over the next two steps of d = a tenth of the step size (inputs held, as the FMU
/// holds them);
/// order 0 and orders beyond `maxOutputDerivativeOrder` are refused.
pub fn output_derivatives_agree_with_finite_differences_of_the_outputs(fmu: &Fmu) {
    let order = fmu.md.cs.as_ref().map_or(0, |cs| cs.max_output_derivative_order);
    if order == 0 {
        skip_not_declared("maxOutputDerivativeOrder >= 1");
    }
    let outputs: Vec<u32> = fmu
        .md
        .of_type(Type::Real)
        .filter(|v| v.causality == Causality::Output && v.variability == Variability::Continuous)
        .map(|v| v.vr)
        .collect();
    if outputs.is_empty() {
        skip_not_declared("a continuous Real output");
    }
    let mut inst = Instance::new(fmu);
    let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(fmu).into_iter().unzip();
    assert_eq!(inst.set_real(&vrs, &vals), fmi2OK);
    inst.initialize();
    compare_output_derivatives(&mut inst, &fmu.id, &outputs, step_size(fmu), order);
}

/// An instance whose output derivatives [`compare_output_derivatives`] checks (FMI 2.0 and
/// 3.0 alike).
pub(crate) trait OutputDerivatives {
    fn now(&self) -> f64;
    /// A step of `h` that must succeed (the message says where it did not).
    fn step_ok(&mut self, h: f64);
    fn outputs(&mut self, vrs: &[u32]) -> Vec<f64>;
    /// The output derivatives of `orders`; `Err(message)` where the FMU refused.
    fn output_derivatives(&mut self, vrs: &[u32], orders: &[i32]) -> Result<Vec<f64>, String>;
}

impl OutputDerivatives for Instance<'_> {
    fn now(&self) -> f64 {
        self.time
    }
    fn step_ok(&mut self, h: f64) {
        assert_eq!(self.step(h), fmi2OK, "{}: {}", self.fmu.id, self.log_text());
    }
    fn outputs(&mut self, vrs: &[u32]) -> Vec<f64> {
        let (s, v) = self.get_real(vrs);
        assert_eq!(s, fmi2OK, "{}: {}", self.fmu.id, self.log_text());
        v
    }
    fn output_derivatives(&mut self, vrs: &[u32], orders: &[i32]) -> Result<Vec<f64>, String> {
        let mut out = vec![f64::NAN; vrs.len()];
        // SAFETY: a live instance; arrays of vrs.len() elements.
        let s = unsafe {
            (self.fmu.api.get_real_output_derivatives)(
                self.c,
                vrs.as_ptr(),
                vrs.len(),
                orders.as_ptr(),
                out.as_mut_ptr(),
            )
        };
        if s == fmi2OK { Ok(out) } else { Err(self.log_text()) }
    }
}

/// What both versions' output-derivative checks do: at three communication points `h` apart
/// (plus the differences' own steps), the first derivative of each of `outputs` agrees with its
/// finite differences over two steps of `h / 10` ([`output_derivative_disagrees`]); order 0 and
/// orders beyond `order` are refused.
pub(crate) fn compare_output_derivatives(
    inst: &mut impl OutputDerivatives,
    id: &str,
    outputs: &[u32],
    h: f64,
    order: u32,
) {
    // The differences over a tenth of the step (their error falls with its square).
    let d = h / 10.0;
    let (mut compared, mut skipped) = (0, 0);
    for point in 0..3 {
        for _ in 0..point * 2 {
            inst.step_ok(h);
        }
        let t = inst.now();
        let dy = inst
            .output_derivatives(outputs, &vec![1; outputs.len()])
            .unwrap_or_else(|log| panic!("{id}: the output derivatives at t = {t} were refused: {log}"));
        let mut samples: Vec<Vec<f64>> = Vec::with_capacity(3);
        for k in 0..3 {
            if k > 0 {
                inst.step_ok(d);
            }
            samples.push(inst.outputs(outputs));
        }
        for (j, vr) in outputs.iter().enumerate() {
            match output_derivative_disagrees([samples[0][j], samples[1][j], samples[2][j]], d, dy[j]) {
                (true, _) => skipped += 1,
                (false, None) => compared += 1,
                (false, Some(why)) => panic!("{id}: output vr {vr} at t = {t}: {why}"),
            }
        }
    }
    for bad in [0, order as i32 + 1] {
        assert!(
            inst.output_derivatives(outputs, &vec![bad; outputs.len()]).is_err(),
            "{id}: output derivatives of order {bad} were answered"
        );
    }
    info(format!(
        "{compared} output derivatives agree with finite differences (step {d}); {skipped} points skipped (not smooth there)"
    ));
}
