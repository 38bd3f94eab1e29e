//! The rules every value passes before it is stored, whether set through the API or restored
//! from a serialized FMU state ([`check_restored`]).

use super::sim::Sim;
use crate::description::Variable;
use crate::model::CoSimulation;
use crate::step::non_finite;
use crate::value::Value;

/// Why a value may not be stored, as a message: `<value> for '<name>' (vr <n>) <reason>`.
pub(super) enum Refusal {
    /// A rule of the runtime: finite, within the declared bounds, an item of the enumeration.
    Rule(String),
    /// The model's own check refused it.
    Model(String),
}

/// The rules every value passes before it is stored, whether set through the API or restored
/// from a serialized state: a finite number, within the declared bounds, an item of its
/// enumeration, accepted by the model's own check (with the other values of `model`).
pub(super) fn refusal<M: CoSimulation>(model: &M, decl: &Variable, value: Value) -> Option<Refusal> {
    refusal_as(model, decl, value, decl.name, decl.value_reference)
}

/// [`refusal`], the messages naming the variable `name` (vr `vr`): FMI 2.0's element of an array.
pub(super) fn refusal_as<M: CoSimulation>(
    model: &M,
    decl: &Variable,
    value: Value,
    name: &str,
    vr: u32,
) -> Option<Refusal> {
    if !value.is_finite() {
        return Some(Refusal::Rule(format!(
            "{} for '{name}' (vr {vr}) is not a finite number",
            value.as_f64().unwrap_or(f64::NAN)
        )));
    }
    if !value.within(decl.min, decl.max) {
        let x = match value.as_i128() {
            Some(n) => n.to_string(),
            None => value.as_f64().map(|x| x.to_string()).unwrap_or_default(),
        };
        return Some(Refusal::Rule(format!(
            "{x} for '{name}' (vr {vr}) is outside {}",
            range_text(decl)
        )));
    }
    if let (Some(e), Value::Integer(code)) = (decl.enumeration, value)
        && e.item(code).is_none()
    {
        let items: Vec<String> = e.items.iter().map(|i| format!("{} = {}", i.name, i.value)).collect();
        return Some(Refusal::Rule(format!(
            "{code} for '{name}' (vr {vr}) is no item of the enumeration {} ({})",
            e.name,
            items.join(", ")
        )));
    }
    if let Err(why) = model.check(decl, value) {
        return Some(Refusal::Model(format!(
            "{value:?} for '{name}' (vr {vr}) refused: {why}"
        )));
    }
    None
}

/// What a deserialized state must be before it is accepted: every value as a setter would
/// accept it, the model's internal state usable, and the runtime's own bookkeeping sound.
/// (The serialized form's magic, GUID, length and checksum only say who wrote it and that it
/// is intact, not that its content is one this FMU can run from.)
pub fn check_restored<M: CoSimulation>(sim: &Sim<M>) -> Result<(), String> {
    for decl in M::DESCRIPTION.variables {
        if let Some(value) = sim.model.get(decl.value_reference)
            && let Some(Refusal::Rule(why) | Refusal::Model(why)) = refusal(&sim.model, decl, value)
        {
            return Err(format!("the state's {why}"));
        }
        if let (Some(max), Some(bytes)) = (decl.fmi3.max_size, sim.model.get_binary(decl.value_reference))
            && bytes.len() > max as usize
        {
            return Err(format!(
                "the state's '{}' has {} bytes, more than its maxSize = {max}",
                decl.name,
                bytes.len()
            ));
        }
        if decl.is_array() {
            for i in 0..decl.element_count() {
                if let Some(value) = sim.model.get_element(decl.value_reference, i)
                    && let Some(Refusal::Rule(why) | Refusal::Model(why)) = refusal(&sim.model, decl, value)
                {
                    return Err(format!("the state's element {i}: {why}"));
                }
            }
        }
    }
    if let Some(what) = non_finite(&sim.model) {
        return Err(format!("in the state, {what}"));
    }
    sim.solver.validate().map_err(|e| format!("in the state, {e}"))?;
    if let Some(te) = sim.events.next_event_time
        && !te.is_finite()
    {
        return Err(format!("the state's next time event {te} is not finite"));
    }
    let times = [
        ("startTime", sim.start_time),
        ("time", sim.time),
        ("last successful time", sim.last_successful_time),
    ];
    for (what, t) in times {
        if !t.is_finite() {
            return Err(format!("the state's {what} = {t} is not finite"));
        }
    }
    if let Some(tol) = sim.tolerance
        && !(tol.is_finite() && tol > 0.0)
    {
        return Err(format!("the state's tolerance = {tol} must be finite and > 0"));
    }
    if let Some(stop) = sim.stop_time
        && !(stop.is_finite() && stop >= sim.start_time)
    {
        return Err(format!(
            "the state's stopTime = {stop} must be finite and not before its startTime = {}",
            sim.start_time
        ));
    }
    Ok(())
}

/// `[min, max]` with exclusive ends as `(`/`)`, for messages; an undeclared end of an integer
/// type is the type's own (`[0, 200]` for a UInt8 with max = 200, not `(-inf, 200]`).
pub(super) fn range_text(v: &Variable) -> String {
    let own = v.var_type.integer_range();
    let lo = match (v.min, own) {
        (Some(b), _) => format!("{}{}", if b.exclusive { "(" } else { "[" }, b.value),
        (None, Some((lo, _))) => format!("[{lo}"),
        (None, None) => "(-inf".into(),
    };
    let hi = match (v.max, own) {
        (Some(b), _) => format!("{}{}", b.value, if b.exclusive { ")" } else { "]" }),
        (None, Some((_, hi))) => format!("{hi}]"),
        (None, None) => "inf)".into(),
    };
    format!("{lo}, {hi}")
}
