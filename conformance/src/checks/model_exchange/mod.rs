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
use crate::instance::Instance;
use crate::me::{self, Euler, MeState, MeState::*};
use crate::outcome::convention;
use crate::{Fmu, LogEntry, Type, bits};

mod arguments;
mod runs;
mod state_table;
pub use arguments::*;
pub use runs::*;
pub use state_table::*;

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
