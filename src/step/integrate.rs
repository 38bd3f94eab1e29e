//! [`Context::integrate`]: the co-simulation step with the runtime's integrator, what
//! [`CoSimulation::do_step`] does unless a model supplies its own step. A model with events or
//! an importer's intermediate update goes on to [`super::events::integrate_with_events`].

use crate::model::{CoSimulation, Context, StateVector, StepFailure, Variables};
use crate::value::Value;

/// The inputs of `c` with a derivative in `slopes` at `dt` after the step's start: u + du dt,
/// u the value the model holds (set by the importer at the step's start).
#[inline]
fn slope_inputs<M: Variables>(c: &mut M::Continuous<f64>, model: &M, slopes: &[(u32, f64)], dt: f64) {
    for &(vr, s) in slopes {
        if let (Some(Value::Real(u)), Some(slot)) = (model.get(vr), M::continuous_slot(c, vr)) {
            *slot = u + s * dt;
        }
    }
}

/// The derivatives at the step's end where the integrator's last stage does not hold them (a
/// failed step, inputs with slopes): out of line, since inlined here the compiler moved the
/// outputs' `sin` calls (sin α1, sin α2 of the Pendulum) into the other branch, where this
/// call had them already, and so kept them from pairing with their `cos` into one `sincos`
/// (bench/callgrind.sh, docs/performance.md).
#[cold]
#[inline(never)]
fn derivatives_at_end<M: CoSimulation>(model: &M, t: f64, c: &mut M::Continuous<f64>) {
    model.derivatives(t, c);
}

impl Context<'_> {
    /// Integrates the model's [`crate::Model::derivatives`] from `t` over `h` with the runtime's
    /// Dormand-Prince 5(4) integrator, at [`CoSimulation::tolerances`], the inputs held; then
    /// computes its outputs at the end. What [`CoSimulation::do_step`] does unless a model
    /// supplies its own step.
    ///
    /// A model with events ([`crate::Model::update`] with event indicators or time events) has them
    /// handled inside the step: the integrator stops at every sign change of an event indicator
    /// (located on its dense output to [`CoSimulation::event_tolerance`]) and at every time
    /// event, the model's [`crate::Model::update`] runs (event iteration included), and the
    /// integration restarts from the new state.
    pub fn integrate<M: CoSimulation>(&mut self, model: &mut M, t: f64, h: f64) -> Result<(), StepFailure> {
        if !M::INDICATORS.is_empty()
            || self.events.as_ref().is_some_and(|e| e.next_event_time.is_some())
            || self.intermediate.is_some()
        {
            return super::events::integrate_with_events(self, model, t, h);
        }
        let slopes = self.input_slopes;
        if !slopes.is_empty() && self.events.as_ref().is_some_and(|e| e.next_event_time.is_some()) {
            return Err(StepFailure {
                reached_time: t,
                message: "input derivatives over a step with a pending time event are not supported: the step that \
                          handles time events holds the inputs"
                    .into(),
            });
        }
        // A structural parameter may hide entries of the state vector (a sized array state):
        // they keep still, and the error norm is the visible entries' (core::structural). A
        // model without one takes the closure without the mask (its step cost 200 instructions
        // more with it: bench/callgrind.sh).
        let sized = const { M::DESCRIPTION.has_sized_arrays() };
        let mask = if sized {
            super::structural::active_mask(&*model)
        } else {
            None
        };
        let tol = if sized {
            super::structural::scaled_tolerances(model.tolerances(self), mask.as_ref())
        } else {
            model.tolerances(self)
        };
        let Some(solver) = self.solver.as_deref_mut() else {
            return Err(StepFailure {
                reached_time: t,
                message: "no integrator in this context (use Context::standalone_with_solver)".into(),
            });
        };
        let t0 = t;
        let mut c = model.continuous::<f64>();
        let mut x = M::states_of(&c);
        let result = if sized {
            <M::States as StateVector>::integrate(
                solver,
                |t, x| {
                    M::set_states_of(&mut c, x);
                    slope_inputs(&mut c, &*model, slopes, t - t0);
                    model.derivatives(t, &mut c);
                    let mut dx = M::derivatives_of(&c);
                    super::structural::hide(&mut dx, mask.as_ref());
                    dx
                },
                t,
                h,
                &mut x,
                tol,
            )
        } else {
            // Inlined into each of the integrator's stages (with `StateVector::integrate`'s own
            // closure): as a call of its own the right-hand side passed its state, derivatives and
            // the model's parameters through memory, 7 times a step (the Pendulum's fmi2DoStep
            // 4 674 -> 4 516 instructions with both inlined, 4 747 with only the outer one:
            // bash bench/callgrind.sh, docs/performance.md).
            <M::States as StateVector>::integrate(
                solver,
                #[inline(always)]
                |t, x| {
                    M::set_states_of(&mut c, x);
                    slope_inputs(&mut c, &*model, slopes, t - t0);
                    model.derivatives(t, &mut c);
                    M::derivatives_of(&c)
                },
                t,
                h,
                &mut x,
                tol,
            )
        };
        // The last right-hand side evaluated is, after a successful integration, the one at the
        // final state (Dormand-Prince's last stage): its derivatives are already in `c`.
        let fresh = M::states_of(&c)
            .as_slice()
            .iter()
            .zip(x.as_slice())
            .all(|(a, b)| a.to_bits() == b.to_bits());
        M::set_states_of(&mut c, &x);
        let reached = match &result {
            Ok(()) => t + h,
            Err(e) => e.time(),
        };
        if !slopes.is_empty() {
            // The inputs at the step's end: there they now have these values.
            slope_inputs(&mut c, &*model, slopes, reached - t0);
            for &(vr, s) in slopes {
                if let Some(Value::Real(u)) = model.get(vr) {
                    model.set(vr, Value::Real(u + s * (reached - t0)));
                }
            }
        }
        if !fresh || !slopes.is_empty() {
            derivatives_at_end(&*model, reached, &mut c);
        }
        model.outputs(reached, &mut c);
        model.store_continuous(&c);
        model.set_states(&x);
        // And what the model computes outside the equations, from the step's end (as
        // `evaluate` does; before, a step left those values where the last get had put them).
        model.calculate(reached);
        self.refreshed = true;
        result.map_err(|e| StepFailure {
            reached_time: e.time(),
            message: e.to_string(),
        })
    }
}
