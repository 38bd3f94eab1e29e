//! Events as the runtime runs them: one round of the event iteration as both interfaces run it
//! ([`update_round`]), the whole iteration ([`iterate`]), and the co-simulation step that finds
//! and handles state and time events inside a communication step ([`integrate_with_events`]).
//! What a model's [`crate::Model::update`] is told is [`crate::Event`], in the model's room.

use crate::model::{
    CoSimulation, Context, Event, EventClock, Model, ReturnAtEvents, StateVector, StepFailure, StepView,
};

/// What one round of the event iteration answered.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Round {
    /// The model asked for another round.
    pub again: bool,
    /// The model asked to end the simulation, with this reason.
    pub terminate: Option<String>,
    /// The continuous states changed (bit for bit).
    pub states_changed: bool,
}

/// One round of the event iteration at `time`: the equations evaluated at the values before
/// the event, [`Model::update`], the pending time event kept in `clock`, the equations evaluated
/// again. `Err` when the model refused the event, scheduled a time event that is not after
/// `time` or left a value that is not finite; the caller puts the model back.
pub fn update_round<M: CoSimulation>(
    model: &mut M,
    ctx: &Context,
    time: f64,
    clock: &mut EventClock,
) -> Result<Round, String> {
    super::evaluate(model, time);
    let states = model.states();
    let pending = clock.next_event_time;
    // Due: reached up to round-off, or marked due by the step that ended within round-off
    // before it (EventClock::time_event_due).
    let time_event = pending.is_some_and(|te| clock.time_event_due || due(te, time));
    // A due time event happens at the time it was scheduled for: the importer's time may differ
    // from it in the last bits (communication points summed up), the model's sample times must not.
    let time = match pending {
        Some(te) if time_event => te,
        _ => time,
    };
    let mut event = Event {
        time,
        initial: clock.initial,
        time_event,
        next_event_time: pending,
        scheduled: false,
        again: false,
        terminate: None,
        ctx,
    };
    model.update(&mut event)?;
    let Event {
        next_event_time,
        scheduled,
        again,
        terminate,
        ..
    } = event;
    clock.next_event_time = match next_event_time {
        Some(te) if !te.is_finite() => {
            return Err(format!("the next time event it scheduled, {te}, is not a finite time"));
        }
        Some(te) if due(te, time) && scheduled => {
            return Err(format!(
                "it scheduled the next time event at t = {te}, which is not after the event's time {time}"
            ));
        }
        // A due time event the model did not reschedule is over.
        Some(te) if due(te, time) => None,
        other => other,
    };
    // The time event marked due is handled (rescheduled or over).
    clock.time_event_due = false;
    clock.count += 1;
    super::evaluate(model, time);
    if let Some(what) = super::non_finite(model) {
        return Err(format!("after the update, {what}"));
    }
    let states_changed = model
        .states()
        .as_slice()
        .iter()
        .zip(states.as_slice())
        .any(|(a, b)| a.to_bits() != b.to_bits());
    Ok(Round {
        again,
        terminate,
        states_changed,
    })
}

/// Whether a time event at `te` is due at `time`: reached, up to the round-off of the times an
/// importer computes (start + n h, or sums of steps).
pub fn due(te: f64, time: f64) -> bool {
    time >= te - 4.0 * f64::EPSILON * te.abs().max(time.abs())
}

/// The most rounds of one event iteration before the runtime gives up on it.
pub const MAX_ROUNDS: usize = 100;

/// The most events inside one communication step before the step is refused (chattering).
pub const MAX_EVENTS_PER_STEP: usize = 100_000;

/// The event iteration at `time` until the model asks for no more rounds (at most
/// [`MAX_ROUNDS`]): all of it or nothing (on `Err` the model is as before). Answers whether the
/// continuous states changed and the termination request.
pub fn iterate<M: CoSimulation>(
    model: &mut M,
    ctx: &Context,
    time: f64,
    clock: &mut EventClock,
) -> Result<(bool, Option<String>), String> {
    let (before, clock_before) = (model.clone(), *clock);
    let mut changed = false;
    for _ in 0..MAX_ROUNDS {
        match update_round(model, ctx, time, clock) {
            Ok(round) => {
                changed |= round.states_changed;
                if round.terminate.is_some() || !round.again {
                    return Ok((changed, round.terminate));
                }
            }
            Err(why) => {
                *model = before;
                *clock = clock_before;
                return Err(why);
            }
        }
    }
    *model = before;
    *clock = clock_before;
    Err(format!(
        "the event iteration at t = {time} did not settle after {MAX_ROUNDS} rounds (update keeps asking for another)"
    ))
}

/// The event indicators of `model` at state `x` and time `t` (the equations run on a copy of
/// its continuous variables).
fn indicators<M: Model>(model: &M, t: f64, x: &M::States, z: &mut [f64]) {
    let mut c = model.continuous::<f64>();
    M::set_states_of(&mut c, x);
    model.derivatives(t, &mut c);
    model.outputs(t, &mut c);
    M::indicators_of(&c, z);
}

/// The FMI domain of an indicator: z > 0 or z <= 0; an event is a change of domain.
fn side(z: f64) -> bool {
    z > 0.0
}

/// Where indicator `i` changes its domain within an accepted step of the integrator, `z` its
/// values at the step's start and end: the Illinois method on the step's continuous extension,
/// over [a, b] with the indicator on its old side at a and on its new side at b, until b - a is
/// within `event_tol`. Answers b, the local time where the indicator is on its new side.
fn locate<M: Model>(
    model: &M,
    step: &StepView<'_, M::States>,
    i: usize,
    z: (f64, f64),
    event_tol: f64,
    z_probe: &mut [f64],
) -> f64 {
    let old = side(z.0);
    let (mut a, mut b) = (step.s0, step.s0 + step.h);
    let (mut za, mut zb) = z;
    let mut last_kept = 0i8;
    let tol_s = event_tol.max(4.0 * f64::EPSILON * (step.t0 + b).abs());
    while b - a > tol_s {
        let mut s = if zb != za {
            b - zb * (b - a) / (zb - za)
        } else {
            0.5 * (a + b)
        };
        if !(s > a && s < b) {
            s = 0.5 * (a + b);
        }
        let xs = step.at(s);
        indicators(model, step.t0 + s, &xs, z_probe);
        let zs = z_probe[i];
        if side(zs) == old {
            a = s;
            za = zs;
            if last_kept == -1 {
                zb *= 0.5;
            }
            last_kept = -1;
        } else {
            b = s;
            zb = zs;
            if last_kept == 1 {
                za *= 0.5;
            }
            last_kept = 1;
        }
    }
    b
}

/// Where a step refused at one of its bounds (MAX_EVENTS_PER_STEP, the integrator's budget)
/// ends: right after the last event it handled (`last`), a consistent state the model's own
/// `update` left (inside an event storm the state at the bound is mid-storm), else at `now`
/// with the model's states `x` (an accepted state of the integrator). Answers that time.
fn back_to_last_event<M: CoSimulation>(
    model: &mut M,
    clock: &mut EventClock,
    last: Option<(M, EventClock, f64)>,
    now: f64,
    x: &M::States,
) -> f64 {
    let at = match last {
        Some((m, c, at)) => {
            (*model, *clock) = (m, c);
            at
        }
        None => {
            model.set_states(x);
            now
        }
    };
    super::evaluate(model, at);
    at
}

/// Why a step that reached its integrator budget ends where it ends.
fn over_budget(steps: u64, at: f64, ends: f64) -> String {
    let ends = if ends < at {
        format!("; the step ends after the last event handled, at t = {ends}")
    } else {
        String::new()
    };
    format!("gave up after {steps} internal steps of the integrator in one communication step, at t = {at}{ends}")
}

/// [`Context::integrate`] for a model with events: integrates from `t` over `h`, stopping at
/// every state event (a change of domain of an event indicator, located on the integrator's
/// continuous extension by the Illinois method to [`CoSimulation::event_tolerance`]; the state
/// is taken where the indicator is already on its new side) and at every time event, where
/// the event iteration runs and the integrator restarts.
///
/// One function of ~230 lines on purpose: one loop over the stretches between events, whose
/// every exit (an event for the importer, an early return, a refusal at a bound, the end) must
/// leave the model, its event clock and the integrator's budget consistent together; the pieces
/// without that state are apart ([`locate`], [`indicators`], [`back_to_last_event`]).
pub(crate) fn integrate_with_events<M: CoSimulation>(
    ctx: &mut Context,
    model: &mut M,
    t: f64,
    h: f64,
) -> Result<(), StepFailure> {
    // Entries of the state vector a structural parameter hides keep still (core::structural).
    let mask = super::structural::active_mask(&*model);
    let tol = super::structural::scaled_tolerances(model.tolerances(ctx), mask.as_ref());
    let end = t + h;
    let n = M::INDICATORS.len();
    let mut now = t;
    let mut events = 0usize;
    let mut clock = ctx.events.as_deref().copied().unwrap_or_default();
    let fail = |ctx: &mut Context, clock: EventClock, reached: f64, message: String| {
        if let Some(c) = ctx.events.as_deref_mut() {
            *c = clock;
        }
        Err(StepFailure {
            reached_time: reached,
            message,
        })
    };
    let mut z_now = vec![0.0; n];
    let mut z_end = vec![0.0; n];
    let mut z_probe = vec![0.0; n];
    // A time the importer asked to return early at, in the intermediate update (FMI 3.0
    // co-simulation), not reached yet.
    let mut early_return: Option<f64> = None;
    // The integrator's `max_steps` bounds the whole communication step, every stretch between
    // its events together, not each stretch: with at most MAX_EVENTS_PER_STEP events too, one
    // call's work has a bound whatever the parameters (docs/performance.md, "Bounded steps").
    let (budget, steps_at_start) = ctx.solver.as_deref().map_or((0, 0), |s| {
        (s.max_steps, s.stats.accepted_steps + s.stats.rejected_steps)
    });
    // The model, its clock and the time right after the last event handled in this step: where
    // a step refused for chattering leaves the instance (a consistent state, not one inside the
    // storm).
    let mut after_event: Option<(M, EventClock, f64)> = None;
    loop {
        // The time event inside this step, if any; one within round-off of the step's end
        // happens at its end.
        let time_event = clock
            .next_event_time
            .filter(|te| *te <= end || due(*te, end) || (*te - end) <= 1e-9 * h);
        // One marked due and left unhandled (an importer that did not enter the Event Mode it was
        // asked for) happens now: no stretch of a few ulps to integrate first.
        let mut target = time_event.map_or(end, |te| if clock.time_event_due { now } else { te.clamp(now, end) });
        // Event mode without early return: a time event a few ulps before the step's end (an
        // importer's t += h passing 0.01 as 0.010000000000000002) is the communication point's,
        // at the end, for the importer's Event Mode. Handled inside the step instead, a triggered
        // output clock it ticks would be over before the importer could ask fmi3GetClock. So is
        // every time event inside the step of a model with output clocks: its tick is signalled
        // at the step's end (FMI-LS-BUS 1.0.0, Triggered Tx Clocks: "Pending Tx data shall be
        // signaled by returning from fmi3DoStep with the eventHandlingNeeded arguments set to
        // fmi3True"), where an importer that moved its grid (a step shortened to another FMU's
        // countdown tick) can ask fmi3GetClock.
        if ctx.return_at_events == ReturnAtEvents::AtStepEnd
            && !clock.time_event_due
            && time_event.is_some_and(|te| te < end && (due(end, te) || M::DESCRIPTION.has_output_clocks()))
        {
            target = end;
        }
        if let Some(tr) = early_return {
            target = target.min(tr);
        }
        // Set when the step callback stops the integration for an early return (not an event).
        let mut stopped_early: Option<f64> = None;
        let intermediate = &mut ctx.intermediate;
        let mut x = model.states();
        indicators(model, now, &x, &mut z_now);
        let mut c = model.continuous::<f64>();
        let solver = ctx.solver.as_deref_mut().expect("checked by the caller");
        let used = solver.stats.accepted_steps + solver.stats.rejected_steps - steps_at_start;
        if target > now && used >= budget {
            let (at, x) = (now, model.states());
            now = back_to_last_event(model, &mut clock, after_event.take(), now, &x);
            return fail(ctx, clock, now, over_budget(used, at, now));
        }
        solver.max_steps = budget - used;
        let model_ref = &*model;
        let event_tol = model.event_tolerance(now);
        let outcome = if target > now {
            <M::States as StateVector>::integrate_until(
                solver,
                |t, x| {
                    M::set_states_of(&mut c, x);
                    model_ref.derivatives(t, &mut c);
                    let mut dx = M::derivatives_of(&c);
                    super::structural::hide(&mut dx, mask.as_ref());
                    dx
                },
                |step| {
                    let t_end = step.t0 + step.s0 + step.h;
                    indicators(model_ref, t_end, &step.end, &mut z_end);
                    let crossed = (0..n).filter(|&i| side(z_now[i]) != side(z_end[i]));
                    let mut first: Option<f64> = None;
                    for i in crossed {
                        let b = locate(model_ref, step, i, (z_now[i], z_end[i]), event_tol, &mut z_probe);
                        first = Some(first.map_or(b, |f| f.min(b)));
                    }
                    match first {
                        Some(s) => Some((s, step.at(s))),
                        None => {
                            z_now.copy_from_slice(&z_end);
                            // An accepted step without an event: the intermediate update. An
                            // early return the importer asks for ends the integration here
                            // (at or before this time) or at its time later in the step.
                            let s_end = step.s0 + step.h;
                            match intermediate.as_deref_mut().and_then(|f| f(t_end)) {
                                Some(tr) if tr < end && s_end < target - now => {
                                    stopped_early = Some(tr);
                                    Some((s_end, step.end))
                                }
                                Some(tr) if tr < end => {
                                    stopped_early = Some(tr);
                                    None
                                }
                                _ => None,
                            }
                        }
                    }
                },
                now,
                target - now,
                &mut x,
                tol,
            )
        } else {
            Ok(None)
        };
        if let Some(s) = ctx.solver.as_deref_mut() {
            s.max_steps = budget;
        }
        let (reached, state_event) = match outcome {
            Ok(Some(at)) => (now + at, stopped_early.is_none()),
            Ok(None) => (target, false),
            Err(crate::solver::OdeError::TooManySteps { t: at, .. }) => {
                // Its count is what was left of the step's budget: say the budget.
                now = back_to_last_event(model, &mut clock, after_event.take(), at, &x);
                return fail(ctx, clock, now, over_budget(budget, at, now));
            }
            Err(e) => {
                let reached = e.time();
                model.set_states(&x);
                super::evaluate(model, reached);
                return fail(ctx, clock, reached, e.to_string());
            }
        };
        model.set_states(&x);
        now = reached;
        if let Some(tr) = stopped_early {
            early_return = Some(tr.max(now));
        }
        let time_event_now = time_event.is_some_and(|te| clock.time_event_due || reached >= te.min(end));
        // A time event reached only up to round-off (the step's end a few ulps before it): due
        // all the same, at its scheduled time (update_round).
        if time_event_now {
            clock.time_event_due = true;
        }
        if !state_event && !time_event_now && early_return.is_some_and(|tr| now >= tr) && now < end {
            // The early return the importer asked for in the intermediate update: the step ends
            // here, at an accepted state (FMI 3.0, 4.2.2).
            super::evaluate(model, now);
            clock.returned_early_at = Some(now);
            if let Some(c) = ctx.events.as_deref_mut() {
                *c = clock;
            }
            ctx.refreshed = true;
            return Ok(());
        }
        let to_importer = match ctx.return_at_events {
            ReturnAtEvents::Never => false,
            ReturnAtEvents::AtStepEnd => now >= end,
            ReturnAtEvents::Each => true,
        };
        if (state_event || time_event_now) && to_importer {
            // FMI 3.0 event mode: stop here, the event unhandled; the importer enters Event Mode
            // (a time event within round-off of the step's end is at the end, and marked due).
            super::evaluate(model, now);
            clock.stopped_at = Some(now);
            if let Some(c) = ctx.events.as_deref_mut() {
                *c = clock;
            }
            ctx.refreshed = true;
            return Ok(());
        }
        if state_event || time_event_now {
            events += 1;
            if events > MAX_EVENTS_PER_STEP {
                // The state here lies past an indicator's zero, the event unhandled.
                let (chattering_at, x) = (now, model.states());
                now = back_to_last_event(model, &mut clock, after_event.take(), now, &x);
                return fail(
                    ctx,
                    clock,
                    now,
                    format!(
                        "more than {MAX_EVENTS_PER_STEP} events in one step (chattering at t = {chattering_at}); \
                         the step ends after the last event handled, at t = {now}"
                    ),
                );
            }
            let solver_ctx = Context::outside_step(ctx.start_time, ctx.tolerance, ctx.logger, ctx.resources, false);
            match iterate(model, &solver_ctx, now, &mut clock) {
                Ok((_, None)) => {}
                Ok((_, Some(reason))) => {
                    clock.terminated = true;
                    return fail(
                        ctx,
                        clock,
                        now,
                        format!("the model ended the simulation at t = {now}: {reason}"),
                    );
                }
                Err(why) => {
                    super::evaluate(model, now);
                    return fail(ctx, clock, now, format!("the event at t = {now} failed: {why}"));
                }
            }
            if let Some(solver) = ctx.solver.as_deref_mut() {
                solver.restart();
            }
            match &mut after_event {
                Some((m, c, at)) => {
                    m.clone_from(model);
                    (*c, *at) = (clock, now);
                }
                None => after_event = Some((model.clone(), clock, now)),
            }
        }
        if now >= end {
            break;
        }
    }
    super::evaluate(model, end);
    if events > 0 && ctx.return_at_events == ReturnAtEvents::AtStepEnd {
        // Event mode without early return: the events inside the step were handled there (the
        // FMI guide's "mitigative internal event handling": the step cannot end before its end,
        // and a bounce put off to it would let the ball through the floor); the importer is
        // told at the step's end all the same (eventHandlingNeeded), so that its Event Mode
        // sees the discrete changes at the communication point (issue 49).
        clock.stopped_at = Some(end);
    }
    if let Some(c) = ctx.events.as_deref_mut() {
        *c = clock;
    }
    ctx.refreshed = true;
    Ok(())
}
