//! Co-simulation's optional step features: the intermediate-update callback (and early return)
//! and output derivatives. (Registered with the calls, [`super::calls`] re-exports them.)

use super::*;

/// Intermediate update (FMI 3.0, 4.2.2; `providesIntermediateUpdate`): over ten steps, every
/// call of the importer's callback names a time inside the step in progress, never earlier than
/// one it named with intermediateStepFinished, with canReturnEarly only where earlyReturnAllowed;
/// the outputs equal a run without the callback. With `canReturnEarlyAfterIntermediateUpdate`
/// and earlyReturnAllowed, asking (from the first call past the step's middle that offers
/// canReturnEarly) to return at the step's three-quarter point ends the step there or at the time
/// the callback was told, with earlyReturn and that lastSuccessfulTime, and the run goes on from it
/// (five steps ten times as long, so that there are internal steps to return after). An FMU that
/// offers canReturnEarly at none of the calls is warned, not failed: the standard leaves the flag to
/// the FMU at each call (the Reference BouncingBall v0.0.41 declares the capability and never
/// offers it).
pub fn fmi3_intermediate_update_names_times_inside_the_step_and_returns_early_where_asked(fmu: &Fmu3) {
    let Some(cs) = &fmu.md.cs else {
        skip_not_declared("<CoSimulation>");
    };
    if !cs.provides_intermediate_update {
        skip_not_declared("providesIntermediateUpdate");
    }
    let id = &fmu.id;
    let h = fmu.step_size();
    // Every Float64 output, an array with all its elements.
    let outputs: Vec<&Variable> = fmu
        .md
        .variables
        .iter()
        .filter(|v| v.ty == Type::Float64 && v.clocks.is_empty() && v.causality == Causality::Output)
        .collect();
    let labels = element_labels(fmu, &outputs);
    let mut plain = Inst::cs(fmu);
    let mut told = Inst::cs_intermediate_update(fmu, false);
    for i in [&plain, &told] {
        excite(i);
    }
    plain.initialize();
    told.initialize();
    let mut finished_at = f64::NEG_INFINITY;
    let mut calls = 0;
    for n in 0..10 {
        let t = told.time;
        let (s, flags, last) = told.do_step(h);
        assert_eq!(
            s,
            fmi3OK,
            "{id}: fmi3DoStep({t}, {h}) with the callback: {}",
            told.log_text()
        );
        if flags[1] == 1 {
            info(format!("the model ended the simulation at t = {last}"));
            break;
        }
        // lastSuccessfulTime within a tolerance relative to the step (FMI 3.0.2 promises no
        // bit identity of the FMU's time).
        // eventHandlingNeeded only where the instance uses event mode (an FMU with clocks; the
        // suite handles the event at the step's end).
        let event = told.auto_events && flags[0] == 1;
        assert!(
            flags == [u8::from(event), 0, 0],
            "{id}: step {n} with the callback: flags {flags:?}, lastSuccessfulTime {last}: expected [{}, 0, 0] (FMI 3.0.2 §4.2.1)",
            u8::from(event)
        );
        let time_off = !crate::outcome::same_time(last, t + h, h);
        if time_off {
            super::calls::time_judged_by_the_named_check(
                &format!("step {n} with the callback: lastSuccessfulTime"),
                last,
                t + h,
            );
        }
        let (s, _, _) = plain.do_step(h);
        assert_eq!(s, fmi3OK, "{id}: fmi3DoStep({t}, {h}): {}", plain.log_text());
        for (time, [_, _, finished, can_return_early]) in told.sink.intermediate.lock().unwrap().drain(..) {
            calls += 1;
            // Inside the step, its ends within a tolerance relative to the step (the FMU's
            // time is its own sum).
            let inside = (time >= t || crate::outcome::same_time(time, t, h))
                && (time <= t + h || crate::outcome::same_time(time, t + h, h));
            if !inside && time_off {
                // The FMU's clock runs away from the steps (its lastSuccessfulTime is off too):
                // the same defect, judged by fmi3_do_step_advances_time_by_the_step.
                super::calls::time_judged_by_the_named_check(&format!("step {n}: intermediateUpdateTime"), time, t + h);
            } else {
                assert!(
                    inside,
                    "{id}: intermediateUpdateTime {time} outside the step from {t} by {h}"
                );
            }
            assert!(
                time >= finished_at,
                "{id}: intermediateUpdateTime {time} before {finished_at}, told earlier with intermediateStepFinished"
            );
            if finished {
                finished_at = time;
            }
            assert!(
                !can_return_early,
                "{id}: canReturnEarly at {time} without earlyReturnAllowed"
            );
        }
        let (a, b) = (plain.get_f64_of(&outputs), told.get_f64_of(&outputs));
        assert_eq!(a.0, fmi3OK, "{id}: {}", plain.log_text());
        assert_eq!(b.0, fmi3OK, "{id}: {}", told.log_text());
        for (k, (x, y)) in a.1.iter().zip(&b.1).enumerate() {
            assert!(
                (x - y).abs() <= 1e-12 * x.abs().max(1.0),
                "{id}: output {} at t = {}: {y} with the intermediate update, {x} without",
                labels[k],
                t + h
            );
        }
    }
    info(format!("{calls} intermediate updates in 10 steps of {h}"));
    if !cs.can_return_early {
        limitation("canReturnEarlyAfterIntermediateUpdate is not declared: the early return was not tried");
        return;
    }
    let mut early = Inst::cs_intermediate_update(fmu, true);
    excite(&early);
    early.initialize();
    // Longer steps, so that the integrator takes several internal steps in one.
    let h = 10.0 * h;
    let mut returned = 0;
    let (mut offered, mut offered_of) = (0, 0);
    for n in 0..5 {
        let t = early.time;
        *early.sink.early_request.lock().unwrap() = Some((t + 0.5 * h, t + 0.75 * h));
        let (s, flags, last) = early.do_step(h);
        assert_eq!(
            s,
            fmi3OK,
            "{id}: fmi3DoStep({t}, {h}) asked to return early: {}",
            early.log_text()
        );
        if flags[1] == 1 {
            info(format!("the model ended the simulation at t = {last}"));
            break;
        }
        let calls: Vec<(f64, [bool; 4])> = early.sink.intermediate.lock().unwrap().drain(..).collect();
        offered += calls.iter().filter(|c| c.1[3]).count();
        offered_of += calls.len();
        if early.auto_events && flags[0] == 1 {
            // An FMU with clocks is made with eventModeUsed, and with earlyReturnAllowed it may
            // end the step at an event of its own, lastSuccessfulTime the time it reached
            // (FMI 3.0.2 §4.2.1, fmi3DoStep; the FMI Guide's "Early Return": to signal an
            // internal event); the suite handled the event.
            assert!(
                last > t && (last <= t + h || crate::outcome::same_time(last, t + h, h)),
                "{id}: step {n}: an event at lastSuccessfulTime {last}, outside the step from {t} by {h}"
            );
            early.time = if flags[2] == 1 { last } else { t + h };
            *early.sink.early_request.lock().unwrap() = None;
            continue;
        }
        // The suite asks (LogSink's callback) only at a call that offers canReturnEarly.
        let asked = calls.iter().find(|c| c.0 >= t + 0.5 * h && c.1[3]).map(|c| c.0);
        match asked {
            Some(at) if at < t + h => {
                let expected = at.max(t + 0.75 * h);
                assert_eq!(flags[2], 1, "{id}: step {n}: no earlyReturn though asked at {at}");
                assert!(
                    (last - expected).abs() <= 1e-12 * expected.abs().max(1.0) || last == at,
                    "{id}: step {n}: returned at {last}, asked at {at} to return at {}",
                    t + 0.75 * h
                );
                early.time = last;
                returned += 1;
            }
            _ if flags[2] == 1 && cs.might_return_early => {
                // FMI 3.0.2 §4.2.1: with mightReturnEarlyFromDoStep and earlyReturnAllowed, the
                // FMU may return early of its own accord (at an event of its own).
                assert!(
                    last > t && (last < t + h || crate::outcome::same_time(last, t + h, h)),
                    "{id}: step {n}: an early return of its own at lastSuccessfulTime {last}, outside the step from {t} by {h}"
                );
                early.time = last;
            }
            _ => {
                assert_eq!(
                    flags[2], 0,
                    "{id}: step {n}: an early return nobody asked for (lastSuccessfulTime {last}), without \
                     mightReturnEarlyFromDoStep (FMI 3.0.2 §4.2.1)"
                );
                // Where the step ended: fmi3_do_step_advances_time_by_the_step's verdict.
                if !crate::outcome::same_time(last, t + h, h) {
                    super::calls::time_judged_by_the_named_check(
                        &format!("step {n} without an early-return request: lastSuccessfulTime"),
                        last,
                        t + h,
                    );
                }
            }
        }
        *early.sink.early_request.lock().unwrap() = None;
    }
    if offered == 0 && offered_of > 0 {
        // Warned, not failed: the callback's canReturnEarly is the FMU's to set at each call
        // (FMI 3.0.2 §4.2.2, fmi3IntermediateUpdateCallback: "When canReturnEarly == fmi3True the
        // FMU signals to the co-simulation algorithm its ability to return early from the current
        // fmi3DoStep"); no sentence obliges an FMU that declares
        // canReturnEarlyAfterIntermediateUpdate to offer it. But an importer then never can.
        crate::outcome::warn(format!(
            "{id}: declares canReturnEarlyAfterIntermediateUpdate, but none of {offered_of} intermediate updates \
             over 5 steps of {h} with earlyReturnAllowed offered canReturnEarly: an importer can never make it \
             return early (FMI 3.0.2 §4.2.2: it may ask only where canReturnEarly is true)"
        ));
    }
    info(format!(
        "{returned} of 5 steps of {h} returned early where asked; {offered} of {offered_of} intermediate updates offered canReturnEarly"
    ));
}

/// fmi3GetOutputDerivatives with `maxOutputDerivativeOrder` >= 1: as the FMI 2.0 check
/// (`output_derivatives_agree_with_finite_differences_of_the_outputs`): at three communication
/// points the first derivative of every continuous Float64 scalar output agrees with the
/// output's finite differences over two steps of a tenth of the step size; order 0 and orders
/// beyond `maxOutputDerivativeOrder` are refused. Array outputs are not compared (skipped when
/// every continuous output is an array, a limitation otherwise).
pub fn fmi3_output_derivatives_agree_with_finite_differences_of_the_outputs(fmu: &Fmu3) {
    let Some(cs) = &fmu.md.cs else {
        skip_not_declared("<CoSimulation>");
    };
    let order = cs.max_output_derivative_order;
    if order == 0 {
        skip_not_declared("maxOutputDerivativeOrder >= 1");
    }
    let continuous_output =
        |v: &&Variable| v.causality == Causality::Output && v.variability == Variability::Continuous;
    let outputs: Vec<u32> = fmu
        .md
        .of_type(Type::Float64)
        .filter(continuous_output)
        .map(|v| v.vr)
        .collect();
    let arrays: Vec<&str> = fmu
        .md
        .variables
        .iter()
        .filter(|v| v.ty == Type::Float64 && v.array && v.clocks.is_empty())
        .filter(continuous_output)
        .map(|v| v.name.as_str())
        .collect();
    if outputs.is_empty() {
        if arrays.is_empty() {
            skip_not_declared("a continuous Float64 output");
        }
        // fmi3GetOutputDerivatives of array outputs (nValues counting their elements) is not
        // compared here: only scalar outputs are.
        skip_not_declared(format!(
            "a continuous Float64 scalar output (the check compares the output derivatives of scalar outputs; the continuous outputs {} are arrays)",
            arrays.join(", ")
        ));
    }
    if !arrays.is_empty() {
        limitation(format!(
            "output derivatives of the array outputs {}: only the scalar outputs are compared",
            arrays.join(", ")
        ));
    }
    let mut i = Inst::cs(fmu);
    excite(&i);
    i.initialize();
    crate::checks::calls::compare_output_derivatives(&mut i, &fmu.id, &outputs, fmu.step_size(), order);
}

impl crate::checks::calls::OutputDerivatives for Inst<'_> {
    fn now(&self) -> f64 {
        self.time
    }
    fn step_ok(&mut self, h: f64) {
        let (s, flags, _) = self.do_step(h);
        assert_eq!((s, flags[1]), (fmi3OK, 0), "{}: {}", self.fmu.id, self.log_text());
    }
    fn outputs(&mut self, vrs: &[u32]) -> Vec<f64> {
        let (s, v) = self.get_f64(vrs);
        assert_eq!(s, fmi3OK, "{}: {}", self.fmu.id, self.log_text());
        v
    }
    fn output_derivatives(&mut self, vrs: &[u32], orders: &[i32]) -> Result<Vec<f64>, String> {
        let (s, out) = self.get_output_derivatives(vrs, orders);
        if s == fmi3OK { Ok(out) } else { Err(self.log_text()) }
    }
}
