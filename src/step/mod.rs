//! The runtime's own step, below the C layers and the instance: what runs a model's code and
//! checks what it computed. A model implements [`crate::model`]; everything here is the
//! runtime's, and nothing here knows FMI's states, functions or pointers:
//!
//! - [`evaluate`]: the equations at one time (derivatives, outputs, what `calculate` computes);
//!   [`non_finite`] and [`oversized_binary`], the checks every computed value passes;
//! - [`integrate`]: [`crate::Context::integrate`], the co-simulation step with the runtime's
//!   integrator (the inputs held or sloped, the structural mask);
//! - [`events`]: one round of the event iteration, the whole iteration, and the step that
//!   locates and handles state and time events inside a communication step;
//! - [`structural`]: the lengths structural parameters give, and the integrator's mask of the
//!   state entries they hide;
//! - `state_vector`: the state vector `[f64; N]` on the integrator ([`crate::StateVector`]);
//! - [`standalone`]: a model run the way the runtime runs it, without an FMU (tests, benchmarks).
//!
//! Arrows point down only: [`crate::core`] and the C layers use this room; this room uses
//! [`crate::model`], [`crate::solver`] and [`crate::description`].

pub mod events;
mod integrate;
pub mod standalone;
mod state_vector;
pub mod structural;

use crate::model::CoSimulation;

/// Runs the model's equations on `f64` at time `t`: derivatives, then outputs, and stores what
/// they computed. The caller checks the result ([`non_finite`]).
#[inline]
pub fn evaluate<M: CoSimulation>(model: &mut M, t: f64) {
    let mut c = model.continuous::<f64>();
    model.derivatives(t, &mut c);
    model.outputs(t, &mut c);
    model.store_continuous(&c);
    model.calculate(t);
}

/// The first Real variable the model computes (output, local, calculated parameter), or the
/// first part of its internal state, that is not finite, described for a message. The one
/// check every value computed by a model passes before it may leave under OK: after
/// initialization, after every step and parameter change, and on every deserialized state
/// (inputs and parameters pass the setters' checks when they are set).
#[inline]
pub fn non_finite<M: CoSimulation>(model: &M) -> Option<String> {
    match (model.non_finite_computed(), model.check_internal_state()) {
        (None, Ok(())) => None,
        (index, internal) => Some(describe_non_finite(model, index, internal)),
    }
}

#[cold]
fn describe_non_finite<M: CoSimulation>(model: &M, index: Option<usize>, internal: Result<(), String>) -> String {
    if let Some(i) = index {
        let v = &M::DESCRIPTION.variables[i];
        let x = model
            .get(v.value_reference)
            .and_then(|x| x.as_f64())
            .unwrap_or(f64::NAN);
        return format!("'{}' (vr {}) = {x} is not a finite number", v.name, v.value_reference);
    }
    format!(
        "the model's internal state is unusable: {}",
        internal.err().unwrap_or_default()
    )
}

/// The first Binary variable into which the model wrote more bytes than its `maxSize`,
/// described for a message. Checked wherever the model's code ran (initialization, the
/// equations, a step, an event's update, a parameter change): the call that ran it fails with
/// fmi3Error and the model keeps the values it had before, so no Binary longer than its
/// `maxSize` leaves the FMU, in `fmi3GetBinary` or in an FMU state (the setter refuses one
/// from the importer).
#[inline]
pub fn oversized_binary<M: CoSimulation>(model: &M) -> Option<String> {
    if !const { M::DESCRIPTION.has_max_sizes() } {
        return None;
    }
    M::DESCRIPTION.variables.iter().find_map(|v| {
        let max = v.fmi3.max_size?;
        let n = model.get_binary(v.value_reference)?.len();
        (n > max as usize).then(|| {
            format!(
                "'{}' (vr {}) holds {n} bytes, more than its maxSize = {max}",
                v.name, v.value_reference
            )
        })
    })
}
