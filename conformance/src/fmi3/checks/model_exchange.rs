//! FMI 3.0 model exchange: the continuous states and derivatives, and an explicit-Euler run.

use super::*;

// ---------------------------------------------------------------------------------------------
// Model exchange

/// fmi3GetNumberOfContinuousStates is the number of elements of the `<ContinuousStateDerivative>`s'
/// variables (an array counts each element, at the structural parameters' starts), and
/// fmi3GetNumberOfEventIndicators that of the `<EventIndicator>`s; over five Euler steps the
/// state and derivative vectors are the state and derivative variables' elements in that
/// order, the nominals are finite and positive, and the same states give the same derivatives.
pub fn fmi3_model_exchange_states_and_derivatives_are_consistent(fmu: &Fmu3) {
    me_only(fmu);
    let states = fmu.states().unwrap_or_else(|e| panic!("{}: {e}", fmu.id));
    let mut i = Inst::me(fmu);
    let api = &fmu.api;
    let n = i.n_states();
    let nx = fmu.n_states_declared();
    assert_eq!(
        n,
        nx,
        "{}: fmi3GetNumberOfContinuousStates says {n}, the {} <ContinuousStateDerivative> of <ModelStructure> have {nx} elements (with the structural parameters at their starts)",
        fmu.id,
        states.len()
    );
    let mut ne = usize::MAX;
    assert_eq!(
        // SAFETY: a live instance; each pointer is to a live local of the length passed, or is an
        // FMU state.
        i.call("fmi3GetNumberOfEventIndicators", |c| unsafe {
            crate::guard::fill_one(
                &mut ne,
                "fmi3GetNumberOfEventIndicators",
                "one size_t",
                crate::guard::COUNT_RULE3,
                |q| (api.get_number_of_event_indicators)(c, q),
            )
        }),
        fmi3OK
    );
    let nz = fmu.n_event_indicators_declared();
    assert_eq!(
        ne,
        nz,
        "{}: fmi3GetNumberOfEventIndicators says {ne}, the {} <EventIndicator> of <ModelStructure> have {nz} elements",
        fmu.id,
        fmu.md.event_indicators.len()
    );
    let state_vars: Vec<&Variable> = states.iter().map(|p| p.0).collect();
    let derivative_vars: Vec<&Variable> = states.iter().map(|p| p.1).collect();
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
        let (s, xs) = i.get_f64_of(&state_vars);
        assert_eq!(s, fmi3OK, "{}: fmi3GetFloat64 of the states: {}", fmu.id, i.log_text());
        let (s, ds) = i.get_f64_of(&derivative_vars);
        assert_eq!(
            s,
            fmi3OK,
            "{}: fmi3GetFloat64 of the derivatives: {}",
            fmu.id,
            i.log_text()
        );
        assert_eq!(
            crate::bits(&x),
            crate::bits(&xs),
            "{}: step {step}: fmi3GetContinuousStates {x:?} differs from fmi3GetFloat64 of the state variables' elements {xs:?}",
            fmu.id
        );
        assert_eq!(
            crate::bits(&dx),
            crate::bits(&ds),
            "{}: step {step}: fmi3GetContinuousStateDerivatives {dx:?} differs from fmi3GetFloat64 of the derivative variables' elements {ds:?}",
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
            i.args(vec![("values", crate::calllog::Val::F64s(x[..n].to_vec()))])
                // SAFETY: a live instance; `x` holds n values.
                .call("fmi3SetContinuousStates", |c| unsafe {
                    (api.set_continuous_states)(c, x.as_ptr(), n)
                }),
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
    // The Float64 values lead what `observe` records (their elements counted); the raw bytes of
    // the other types follow, which are no f64 to test for finiteness (an Int64 -5 is a NaN's
    // bits).
    let n_float64: usize = fmu
        .md
        .of_type(Type::Float64)
        .filter(|v| v.clocks.is_empty())
        .map(|v| fmu.element_count(v))
        .sum();
    let last: Vec<f64> = me
        .last()
        .unwrap()
        .iter()
        .take(n_float64)
        .map(|b| f64::from_bits(*b))
        .collect();
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
                // The importer sums the ME steps, the FMU its own: equal within a tolerance
                // relative to the step, not bit for bit (FMI 3.0.2 does not promise that).
                // The CS run's time away from the ME run's, which is where the importer set it
                // (steps * h): the co-simulation steps' defect, judged by
                // fmi3_do_step_advances_time_by_the_step.
                if !crate::outcome::same_time(last[k], cs_last[k], h)
                    && crate::outcome::same_time(last[k], steps as f64 * h, h)
                {
                    super::calls::time_judged_by_the_named_check(
                        &format!("the CS run's time after {steps} steps"),
                        cs_last[k],
                        last[k],
                    );
                    continue;
                }
                assert!(
                    crate::outcome::same_time(last[k], cs_last[k], h),
                    "{}: time after {steps} steps: ME {} CS {}",
                    fmu.id,
                    last[k],
                    cs_last[k]
                );
            }
        }
    }
}

/// The events of an importer's run through the FMI 3.0 calls (explicit Euler up to the default
/// experiment's stop time, at most [`crate::outcome::MAX_RUN_STEPS`] steps, from the start values
/// and, where no event happens there, again with the inputs moved off them; stepping onto every
/// time event and entering Event Mode
/// where an event indicator changes domain): every announced time event is reached and followed
/// by a later one (or none), the event iteration settles within 100 rounds, the indicators are a
/// function of time and states (the same states set again give them bit for bit), and
/// fmi3GetNumberOfEventIndicators agrees with the `<EventIndicator>`s.
pub fn fmi3_model_exchange_events_are_reached_settle_and_follow_the_states(fmu: &Fmu3) {
    me_only(fmu);
    let h = fmu.step_size().min(1e-3);
    let stop = crate::outcome::run_stop(fmu.md.default_experiment.stop_time(), h);
    let (run, how) = crate::outcome::event_run(
        !excitation(fmu).is_empty(),
        |r: &EventsRun| r.events,
        |excited| me_events_run(fmu, h, stop, excited),
    );
    let EventsRun {
        steps,
        events,
        time_events,
        indicators: nz,
        end,
    } = run;
    if events == 0 && nz == 0 {
        limitation(format!(
            "{}events: no event indicator, no time event in {stop} s",
            crate::outcome::NOT_DECLARED
        ));
    } else if events == 0 {
        limitation(format!(
            "{}events: none in {stop} s of explicit Euler from the start values, nor with the inputs moved off \
             them (the default experiment's stop time, at most {} steps): the {nz} event indicators never \
             changed domain",
            crate::outcome::NOT_EXERCISED,
            crate::outcome::MAX_RUN_STEPS
        ));
    }
    info(format!(
        "{steps} explicit-Euler steps up to t = {end} {how}: {events} events, {time_events} of them time events, \
         {nz} event indicators"
    ));
}

/// What one run of the events checks saw (`handed`: of co-simulation, the events handed to the
/// importer, in `events`).
struct EventsRun {
    steps: usize,
    events: usize,
    time_events: usize,
    indicators: usize,
    end: f64,
}

/// One run of [`fmi3_model_exchange_events_are_reached_settle_and_follow_the_states`] to
/// `stop`, its inputs at their start values or (`excited`) moved off them.
fn me_events_run(fmu: &Fmu3, h: f64, stop: f64, excited: bool) -> EventsRun {
    let id = &fmu.id;
    let mut i = Inst::me(fmu);
    if excited {
        excite(&i);
    }
    assert_eq!(i.enter_init(0.0), fmi3OK, "{id}: {}", i.log_text());
    assert_eq!(i.exit_init(), fmi3OK, "{id}: {}", i.log_text());
    let api = i.api();
    let (_, mut next) = i.event_iteration_timed();
    let enter_ct = |i: &Inst| {
        let s = i.unary("fmi3EnterContinuousTimeMode", api.enter_continuous_time_mode);
        assert_eq!(s, fmi3OK, "{id}: fmi3EnterContinuousTimeMode: {}", i.log_text());
    };
    enter_ct(&i);
    let nz = fmu.n_event_indicators_declared();
    let mut count = usize::MAX;
    // SAFETY: a live instance; each pointer is to a live local of the length passed, or is an FMU
    // state.
    let s = i.call("fmi3GetNumberOfEventIndicators", |c| unsafe {
        crate::guard::fill_one(
            &mut count,
            "fmi3GetNumberOfEventIndicators",
            "one size_t",
            crate::guard::COUNT_RULE3,
            |q| (api.get_number_of_event_indicators)(c, q),
        )
    });
    assert_eq!((s, count), (fmi3OK, nz), "{id}: fmi3GetNumberOfEventIndicators");
    let indicators = |i: &Inst| {
        let (s, z) = i.vector("fmi3GetEventIndicators", api.get_event_indicators, nz);
        assert_eq!(
            s,
            fmi3OK,
            "{id}: fmi3GetEventIndicators at t = {}: {}",
            i.time,
            i.log_text()
        );
        assert!(
            z.iter().all(|v| v.is_finite()),
            "{id}: indicators {z:?} at t = {}",
            i.time
        );
        z
    };
    let n = fmu.n_states_declared();
    let mut z = indicators(&i);
    let (mut events, mut time_events, mut steps) = (0usize, 0usize, 0usize);
    while i.time < stop - 0.5 * h {
        steps += 1;
        assert!(
            steps < 100 * ((stop / h) as usize + 1),
            "{id}: no end of the run at t = {}",
            i.time
        );
        let due = next.filter(|te| *te <= i.time + h);
        let t1 = due.map_or(i.time + h, |te| te.max(i.time));
        let (s, x) = i.vector("fmi3GetContinuousStates", api.get_continuous_states, n);
        let (s2, dx) = i.vector(
            "fmi3GetContinuousStateDerivatives",
            api.get_continuous_state_derivatives,
            n,
        );
        assert_eq!([s, s2], [fmi3OK; 2], "{id}: at t = {}: {}", i.time, i.log_text());
        let x1: Vec<f64> = x.iter().zip(&dx).map(|(x, d)| x + (t1 - i.time) * d).collect();
        if x1.iter().any(|v| !v.is_finite() || v.abs() > 1e150) {
            // The suite's explicit Euler diverged (a stiff model, such as the Reference Roberts,
            // at the default step): what the FMU says of non-finite states is not what is
            // checked here, so the run ends as a limitation, not a verdict.
            crate::outcome::limitation(format!(
                "the suite's explicit-Euler run diverged at t = {} (states {x1:?} from {x:?} with derivatives {dx:?}, \
                 step {}): a stiff model for this integrator; the events after it were not followed",
                i.time,
                t1 - i.time
            ));
            break;
        }
        i.args(vec![("time", crate::calllog::Val::F64(t1))]);
        // SAFETY: a live instance; each pointer is to a live local of the length passed, or is an
        // FMU state.
        let s = i.call("fmi3SetTime", |c| unsafe { (api.set_time)(c, t1) });
        i.args(vec![("values", crate::calllog::Val::F64s(x1[..n].to_vec()))]);
        // SAFETY: a live instance; each pointer is to a live local of the length passed, or is an
        // FMU state.
        let s2 = i.call("fmi3SetContinuousStates", |c| unsafe {
            (api.set_continuous_states)(c, x1.as_ptr(), n)
        });
        assert_eq!([s, s2], [fmi3OK; 2], "{id}: at t = {t1}: {}", i.log_text());
        i.time = t1;
        let (mut enter, mut term) = (7u8, 7u8);
        i.args(vec![]);
        // SAFETY: a live instance; each pointer is to a live local of the length passed, or is an
        // FMU state.
        let s = i.call("fmi3CompletedIntegratorStep", |c| unsafe {
            crate::guard::fill_integrator_step3(&mut enter, &mut term, |qa, qb| {
                (api.completed_integrator_step)(c, true, qa, qb)
            })
        });
        assert_eq!(
            (s, term),
            (fmi3OK, 0),
            "{id}: fmi3CompletedIntegratorStep at t = {t1}: {}",
            i.log_text()
        );
        let z1 = indicators(&i);
        let state_event = z1.iter().zip(&z).any(|(a, b)| (*a > 0.0) != (*b > 0.0));
        z = z1;
        if due.is_some() || state_event || enter == 1 {
            events += 1;
            time_events += usize::from(due.is_some());
            let s = i.unary("fmi3EnterEventMode", api.enter_event_mode);
            assert_eq!(s, fmi3OK, "{id}: fmi3EnterEventMode at t = {t1}: {}", i.log_text());
            let (flags, after) = i.event_iteration_timed();
            if flags[1] == 1 {
                info(format!("the model ended the simulation at t = {t1}"));
                break;
            }
            if let (Some(te), Some(later)) = (due, after) {
                assert!(
                    later > te,
                    "{id}: after the time event at {te} the next one is at {later}, not later"
                );
            }
            next = after;
            enter_ct(&i);
            z = indicators(&i);
        }
        if steps % 50 == 0 && nz > 0 {
            let (s, x) = i.vector("fmi3GetContinuousStates", api.get_continuous_states, n);
            i.args(vec![("values", crate::calllog::Val::F64s(x[..n].to_vec()))]);
            // SAFETY: a live instance; each pointer is to a live local of the length passed, or is
            // an FMU state.
            let s2 = i.call("fmi3SetContinuousStates", |c| unsafe {
                (api.set_continuous_states)(c, x.as_ptr(), n)
            });
            assert_eq!([s, s2], [fmi3OK; 2], "{id}: {}", i.log_text());
            assert_eq!(
                crate::bits(&indicators(&i)),
                crate::bits(&z),
                "{id}: indicators at t = {} after the same states",
                i.time
            );
        }
    }
    EventsRun {
        steps,
        events,
        time_events,
        indicators: nz,
        end: i.time,
    }
}

/// Co-simulation with event mode (`hasEventMode="true"`; instantiated with eventModeUsed and
/// earlyReturnAllowed), as an importer runs it up to the default experiment's stop time (at most
/// [`crate::outcome::MAX_RUN_STEPS`] steps; from the start values, and where no event happens
/// there, again with the inputs moved off them): after initialization the instance is in Event Mode (fmi3UpdateDiscreteStates settles,
/// fmi3EnterStepMode); every fmi3DoStep completes, or returns at an event with
/// eventHandlingNeeded, earlyReturn exactly when it stopped before the step's end, and
/// lastSuccessfulTime within the step; the event is then handled in Event Mode and stepping
/// resumes from there.
pub fn fmi3_co_simulation_event_mode_hands_the_events_to_the_importer(fmu: &Fmu3) {
    let Some(cs) = &fmu.md.cs else {
        skip_not_declared("<CoSimulation>");
    };
    if !cs.has_event_mode {
        skip_not_declared("hasEventMode");
    }
    let h = fmu.step_size();
    let stop = crate::outcome::run_stop(fmu.md.default_experiment.stop_time(), h);
    let (run, how) = crate::outcome::event_run(
        !excitation(fmu).is_empty(),
        |r: &EventsRun| r.events,
        |excited| cs_events_run(fmu, h, stop, excited),
    );
    let (handed, steps) = (run.events, run.steps);
    if handed == 0 && fmu.n_event_indicators_declared() == 0 {
        limitation(format!("{}events: none in {stop} s", crate::outcome::NOT_DECLARED));
    } else if handed == 0 {
        limitation(format!(
            "{}events: none in {stop} s from the start values, nor with the inputs moved off them (the default \
             experiment's stop time, at most {} steps): the {} event indicators never changed domain",
            crate::outcome::NOT_EXERCISED,
            crate::outcome::MAX_RUN_STEPS,
            fmu.n_event_indicators_declared()
        ));
    }
    info(format!(
        "{steps} steps of {h} s in event mode {how}: {handed} events handed to the importer"
    ));
}

/// One run of [`fmi3_co_simulation_event_mode_hands_the_events_to_the_importer`] to `stop`, its
/// inputs at their start values or (`excited`) moved off them.
fn cs_events_run(fmu: &Fmu3, h: f64, stop: f64, excited: bool) -> EventsRun {
    let id = &fmu.id;
    let mut i = Inst::cs_event_mode(fmu);
    if excited {
        excite(&i);
    }
    assert_eq!(i.enter_init(0.0), fmi3OK, "{id}: {}", i.log_text());
    assert_eq!(i.exit_init(), fmi3OK, "{id}: {}", i.log_text());
    let api = i.api();
    let step_mode = |i: &Inst| {
        let s = i.unary("fmi3EnterStepMode", api.enter_step_mode);
        assert_eq!(s, fmi3OK, "{id}: fmi3EnterStepMode at t = {}: {}", i.time, i.log_text());
    };
    i.event_iteration();
    step_mode(&i);
    let (mut handed, mut steps) = (0usize, 0usize);
    while i.time < stop - 0.5 * h {
        steps += 1;
        assert!(
            steps < 100 * ((stop / h) as usize + 1),
            "{id}: no end of the run at t = {}",
            i.time
        );
        let t = i.time;
        let step = h.min(stop - t);
        let (s, [event, terminate, early], last) = i.do_step(step);
        assert_eq!(s, fmi3OK, "{id}: fmi3DoStep({t}, {step}): {}", i.log_text());
        if event == 0 {
            assert!(
                early == 0,
                "{id}: a step from {t} without an event: earlyReturn {early}, lastSuccessfulTime {last} (FMI 3.0.2 §4.2.1: earlyReturn comes with an event here)"
            );
            if !crate::outcome::same_time(last, t + step, step) {
                super::calls::time_judged_by_the_named_check(
                    &format!("a step from {t} without an event: lastSuccessfulTime"),
                    last,
                    t + step,
                );
            }
        } else {
            // Within the step, its ends within a tolerance relative to the step (FMI 3.0.2
            // promises no bit identity of the FMU's time).
            let at_end = crate::outcome::same_time(last, t + step, step);
            assert!(
                (last >= t && last <= t + step) || at_end,
                "{id}: an event at lastSuccessfulTime {last}, outside the step from {t} by {step}"
            );
            assert!(
                early == 1 || at_end,
                "{id}: earlyReturn {early} with lastSuccessfulTime {last} before the end of the step {} (FMI 3.0.2 §4.2.1)",
                t + step
            );
            i.time = last;
            handed += 1;
            let s = i.unary("fmi3EnterEventMode", api.enter_event_mode);
            assert_eq!(s, fmi3OK, "{id}: fmi3EnterEventMode at t = {last}: {}", i.log_text());
            let (flags, _) = i.event_iteration_timed();
            if flags[1] == 1 {
                info(format!("the model ended the simulation at t = {last}"));
                break;
            }
            step_mode(&i);
        }
        if terminate == 1 {
            info(format!("the model ended the simulation at t = {}", i.time));
            break;
        }
    }
    // Every Float64 value (every element of the arrays) finite.
    let floats: Vec<&Variable> = fmu
        .md
        .variables
        .iter()
        .filter(|v| v.ty == Type::Float64 && v.clocks.is_empty())
        .collect();
    let (s, values) = i.get_f64_of(&floats);
    assert_eq!(s, fmi3OK, "{id}: {}", i.log_text());
    assert!(values.iter().all(|v| v.is_finite()), "{id}: {values:?}");
    EventsRun {
        steps,
        events: handed,
        time_events: 0,
        indicators: fmu.n_event_indicators_declared(),
        end: i.time,
    }
}
