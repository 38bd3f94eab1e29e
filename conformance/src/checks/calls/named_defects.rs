//! Checks named by the defect they catch: a getter that writes past the values it is given, a
//! `fmi2DoStep` that answers fmi2OK without advancing time. (Other checks meet these defects on
//! their way too; these say what is wrong in their names.)

use super::initialized;
use crate::fmi2::*;
use crate::instance::step_size;
use crate::{Fmu, Type};
use md_reader::Causality;

/// Every getter and status function, with every variable of its type at once and each alone,
/// after initialization and after a step: each writes no byte past the array it is given (the
/// guard after every buffer, `src/guard.rs`).
///
/// Verdict: a byte written past the array is a failure: FMI 2.0.5 §2.1.7 ("`value[]` ... a vector
/// of nvr values" the importer provides), §4.2.3 (fmi2Get*Status return one value through
/// `value`). What the values are is other checks' business.
pub fn getters_write_no_value_past_the_array_they_are_given(fmu: &Fmu) {
    let mut inst = initialized(fmu);
    let h = step_size(fmu);
    for round in 0..2 {
        if round == 1 {
            // The values after a step (whatever its status: the getters are what is checked).
            let _ = inst.step(h);
        }
        for ty in [
            Type::Real,
            Type::Integer,
            Type::Enumeration,
            Type::Boolean,
            Type::String,
        ] {
            let vrs = fmu.md.vrs_of_type(ty);
            for chunk in std::iter::once(&vrs[..]).chain(vrs.chunks(1)) {
                match ty {
                    Type::Real => drop(inst.get_real(chunk)),
                    Type::Integer | Type::Enumeration => drop(inst.get_integer(chunk)),
                    Type::Boolean => drop(inst.get_boolean(chunk)),
                    Type::String => drop(inst.get_string(chunk)),
                }
            }
        }
        if round == 1 {
            let _ = inst.last_successful_time();
            let _ = inst.terminated();
        }
    }
}

/// fmi2DoStep answered fmi2OK three times from the start time: the FMU is at t0 + 3 h, as its
/// time variable (the `independent` Real, where declared) and fmi2LastSuccessfulTime say
/// (within a millionth of the step: `outcome::same_time`).
///
/// Verdict: a failure where either reads another time after fmi2OK: FMI 2.0.5 §4.2.2
/// (fmi2DoStep computes the communication step from currentCommunicationPoint to
/// currentCommunicationPoint + communicationStepSize; fmi2OK: the step was computed to its end),
/// §2.2.7 (causality "independent": its value is "after initialization set ... by arguments
/// currentCommunicationPoint and communicationStepSize of fmi2DoStep for CoSimulation"; "[The
/// actual value can be inquired with fmi2GetReal.]") and §4.2.3 (fmi2LastSuccessfulTime: "the
/// end time of the last successfully completed communication step"). The Reference Feedthrough
/// and Resource v0.0.41 (no continuous states) keep their time variable at the start time. Skipped where the FMU declares no independent variable and does not
/// answer fmi2LastSuccessfulTime (it then shows its time nowhere).
pub fn do_step_advances_time_by_the_step(fmu: &Fmu) {
    let time = fmu
        .md
        .variables
        .iter()
        .find(|v| v.ty == Type::Real && v.causality == Causality::Independent)
        .map(|v| (v.vr, v.name.clone()));
    let mut inst = initialized(fmu);
    let h = step_size(fmu);
    let t0 = inst.time;
    let mut shown = time.is_some();
    for n in 1..=3 {
        let s = inst.step(h);
        assert_eq!(s, fmi2OK, "{}: fmi2DoStep {n} of h = {h}: {}", fmu.id, inst.log_text());
        if let Some((vr, name)) = &time {
            let (s, v) = inst.get_real(&[*vr]);
            crate::calllog::expect_values(&[inst.time], crate::outcome::time_tolerance(inst.time, h));
            assert!(
                s == fmi2OK && crate::outcome::same_time(v[0], inst.time, h),
                "{}: after {n} fmi2DoStep of h = {h} from t = {t0} answered fmi2OK, the time variable '{name}' reads \
                 {} ({}), expected {} (FMI 2.0.5 §4.2.2: fmi2OK means the step was computed to \
                 currentCommunicationPoint + communicationStepSize; §2.2.7: the independent variable's value is set by \
                 the arguments of fmi2DoStep)",
                fmu.id,
                v[0],
                crate::instance::status_name(s),
                inst.time
            );
        }
        let (s, last) = inst.last_successful_time();
        if s == fmi2OK {
            shown = true;
            crate::calllog::expect_values(&[inst.time], crate::outcome::time_tolerance(inst.time, h));
            assert!(
                crate::outcome::same_time(last, inst.time, h),
                "{}: after {n} fmi2DoStep of h = {h} from t = {t0} answered fmi2OK, fmi2LastSuccessfulTime is {last}, \
                 expected {} (FMI 2.0.5 §4.2.2, §4.2.3: the end time of the last successfully completed communication step)",
                fmu.id,
                inst.time
            );
        }
    }
    if !shown {
        crate::outcome::skip_not_declared(
            "an independent (time) variable, and fmi2GetRealStatus(fmi2LastSuccessfulTime) is not answered",
        );
    }
}

/// fmi2FreeInstance of an instance in each state an importer frees one in: Instantiated,
/// Initialization Mode, Step Mode after a step, Terminated. Each call must return; a crash or a
/// hang in it fails this check with the call it died in (the worker's report).
///
/// Verdict: a crash in fmi2FreeInstance is a failure: FMI 2.0.5 §2.1.5 (fmi2FreeInstance
/// "Disposes the given instance, unloads the loaded model, and frees all the allocated memory
/// and other resources"), a call the state machine allows in every state (§4.2.4) with the
/// instance fmi2Instantiate returned; the importer's process dies with it.
pub fn free_instance_frees_an_instance_in_every_state_without_crashing(fmu: &Fmu) {
    let h = step_size(fmu);
    // Instantiated.
    drop(crate::instance::Instance::new(fmu));
    // Initialization Mode.
    let mut inst = crate::instance::Instance::new(fmu);
    assert_eq!(
        inst.setup(0.0, None),
        fmi2OK,
        "{}: fmi2SetupExperiment: {}",
        fmu.id,
        inst.log_text()
    );
    assert_eq!(
        inst.enter_init(),
        fmi2OK,
        "{}: fmi2EnterInitializationMode: {}",
        fmu.id,
        inst.log_text()
    );
    drop(inst);
    // Step Mode, after a step (whatever the step answered: the free is what is checked).
    let mut inst = initialized(fmu);
    let _ = inst.step(h);
    drop(inst);
    // Terminated.
    let mut inst = initialized(fmu);
    let _ = inst.step(h);
    assert_eq!(
        inst.terminate(),
        fmi2OK,
        "{}: fmi2Terminate: {}",
        fmu.id,
        inst.log_text()
    );
    drop(inst);
}

/// After initialization and after a step, every variable the model description declares is read
/// alone through its type's getter (Real, Integer and Enumeration, Boolean, String), by the value
/// reference the description gives it: the binary must know it.
///
/// Verdict: a declared variable refused (any status but fmi2OK/fmi2Warning) is a failure: the
/// description and the binary disagree. FMI 2.0.5 §2.2.7 (`valueReference`: "A handle of the
/// variable to efficiently identify the variable value in the model interface") and §4.2.4 (the
/// co-simulation state machine allows fmi2GetXXX on every variable after initialization);
/// fmi2Error is for "illegal arguments" (§2.1.3), which a declared value reference is not.
pub fn the_binary_knows_every_variable_its_description_declares(fmu: &Fmu) {
    let mut inst = initialized(fmu);
    let h = step_size(fmu);
    for round in 0..2 {
        if round == 1 {
            let s = inst.step(h);
            assert!(
                s == fmi2OK || s == fmi2Warning,
                "{}: fmi2DoStep(h = {h}) after initialization: {}: {}",
                fmu.id,
                crate::instance::status_name(s),
                inst.log_text()
            );
        }
        let when = if round == 0 {
            "after initialization"
        } else {
            "after a step"
        };
        for v in &fmu.md.variables {
            let vr = [v.vr];
            let (function, s) = match v.ty {
                Type::Real => ("fmi2GetReal", inst.get_real(&vr).0),
                Type::Integer | Type::Enumeration => ("fmi2GetInteger", inst.get_integer(&vr).0),
                Type::Boolean => ("fmi2GetBoolean", inst.get_boolean(&vr).0),
                Type::String => ("fmi2GetString", inst.get_string(&vr).0),
            };
            assert!(
                s == fmi2OK || s == fmi2Warning,
                "{}: {function} of the declared variable '{}' (value reference {}) answered {} {when}: the binary \
                 does not know a variable its description declares (FMI 2.0.5 §2.2.7: the valueReference \
                 identifies the variable in the model interface; §4.2.4: fmi2GetXXX is allowed on every \
                 variable after initialization). Log: {}",
                fmu.id,
                v.name,
                v.vr,
                crate::instance::status_name(s),
                inst.log_text()
            );
        }
    }
}
