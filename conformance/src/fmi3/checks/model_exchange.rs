//! FMI 3.0 model exchange: the continuous states and derivatives, and an explicit-Euler run.

use super::*;

// ---------------------------------------------------------------------------------------------
// Model exchange

pub fn fmi3_model_exchange_states_and_derivatives_are_consistent(fmu: &Fmu3) {
    me_only(fmu);
    let states = fmu.md.continuous_states().unwrap_or_else(|e| panic!("{}: {e}", fmu.id));
    let mut i = Inst::me(fmu);
    let api = &fmu.api;
    let n = i.n_states();
    assert_eq!(
        n,
        states.len(),
        "{}: fmi3GetNumberOfContinuousStates says {n}, <ModelStructure> lists {} <ContinuousStateDerivative>",
        fmu.id,
        states.len()
    );
    let mut ne = usize::MAX;
    assert_eq!(
        i.call("n", |c| unsafe { (api.get_number_of_event_indicators)(c, &mut ne) }),
        fmi3OK
    );
    assert_eq!(
        ne,
        fmu.md.event_indicators.len(),
        "{}: fmi3GetNumberOfEventIndicators says {ne}, <ModelStructure> lists {} <EventIndicator>",
        fmu.id,
        fmu.md.event_indicators.len()
    );
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
        let (_, xs) = i.get_f64(&states.iter().map(|p| p.0).collect::<Vec<_>>());
        let (_, ds) = i.get_f64(&states.iter().map(|p| p.1).collect::<Vec<_>>());
        assert_eq!(
            crate::bits(&x),
            crate::bits(&xs),
            "{}: step {step}: fmi3GetContinuousStates differs from fmi3GetFloat64 of the state variables",
            fmu.id
        );
        assert_eq!(
            crate::bits(&dx),
            crate::bits(&ds),
            "{}: step {step}: fmi3GetContinuousStateDerivatives differs from fmi3GetFloat64 of the derivative variables",
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
            i.call("sx", |c| unsafe { (api.set_continuous_states)(c, x.as_ptr(), n) }),
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
    let last: Vec<f64> = me.last().unwrap().iter().map(|b| f64::from_bits(*b)).collect();
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
                assert_eq!(
                    last[k], cs_last[k],
                    "{}: time after {steps} steps: ME {} CS {}",
                    fmu.id, last[k], cs_last[k]
                );
            }
        }
    }
}
