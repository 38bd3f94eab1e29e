//! FMI 3.0 directional and adjoint derivatives against finite differences.

use super::*;

// ---------------------------------------------------------------------------------------------
// Directional and adjoint derivatives

/// The unknowns of the derivatives: the derivatives of the continuous states (ME), then the
/// Float64 outputs (not clocked), arrays included (each element a row of the Jacobian).
pub(super) fn unknowns(fmu: &Fmu3, me: bool) -> Vec<&Variable> {
    let mut list = vec![];
    if me {
        list.extend(fmu.md.derivatives.iter().filter_map(|u| fmu.md.by_vr(u.vr)));
    }
    list.extend(
        fmu.md
            .outputs
            .iter()
            .filter_map(|u| fmu.md.by_vr(u.vr))
            // (Clocked outputs are read at their ticks only, not where derivatives are taken.)
            .filter(|v| v.ty == Type::Float64 && v.clocks.is_empty()),
    );
    list
}

/// The knowns: the continuous states (ME), then the continuous Float64 inputs, arrays included
/// (each element a column of the Jacobian).
pub(super) fn knowns(fmu: &Fmu3, me: bool) -> Vec<&Variable> {
    let mut list = vec![];
    if me {
        list.extend(fmu.states().unwrap_or_default().iter().map(|p| p.0));
    }
    list.extend(float_inputs(fmu));
    list
}

fn dependencies(fmu: &Fmu3, me: bool, unknown: u32) -> Option<Vec<u32>> {
    let list = if me {
        fmu.md.derivatives.iter().chain(&fmu.md.outputs).collect::<Vec<_>>()
    } else {
        fmu.md.outputs.iter().collect()
    };
    list.iter()
        .find(|u| u.vr == unknown)
        .and_then(|u| u.dependencies.clone())
}

/// Each value of the variables, one after the other (an array's elements row-major, at the
/// structural parameters' starts): (the variable's index, the element's index in it).
fn elements(fmu: &Fmu3, vars: &[&Variable]) -> Vec<(usize, usize)> {
    vars.iter()
        .enumerate()
        .flat_map(|(k, v)| (0..fmu.element_count(v)).map(move |e| (k, e)))
        .collect()
}

// Over ~150 lines: the comparisons of one initialized instance, in sequence, sharing its knowns,
// unknowns and seeds.
fn derivatives_check(fmu: &Fmu3, me: bool) {
    let i = if me { fmu.md.me.as_ref() } else { fmu.md.cs.as_ref() };
    let Some(i) = i else {
        skip_not_declared(if me { "<ModelExchange>" } else { "<CoSimulation>" })
    };
    if !i.provides_directional_derivatives {
        skip_not_declared("providesDirectionalDerivatives");
    }
    let (u_vars, k_vars) = (unknowns(fmu, me), knowns(fmu, me));
    // nSeed and nSensitivity count every element of the knowns and unknowns (FMI 3.0, 2.3.11).
    let (ue, ke) = (elements(fmu, &u_vars), elements(fmu, &k_vars));
    if ue.is_empty() || ke.is_empty() {
        // A co-simulation FMU without continuous Real inputs has no knowns (BouncingBall).
        let elements = if (ue.len(), ke.len()) == (u_vars.len(), k_vars.len()) {
            String::new()
        } else {
            format!("; their elements {} and {}", ue.len(), ke.len())
        };
        skip_not_declared(format!(
            "a Real unknown and known to differentiate (unknowns {}, knowns {}{elements})",
            u_vars.len(),
            k_vars.len()
        ));
    }
    let u: Vec<u32> = u_vars.iter().map(|v| v.vr).collect();
    let k: Vec<u32> = k_vars.iter().map(|v| v.vr).collect();
    let (u_names, k_names) = (element_labels(fmu, &u_vars), element_labels(fmu, &k_vars));
    // The state vector: where each state's elements are in it (ME).
    let slots = if me {
        fmu.state_slots().unwrap_or_else(|e| panic!("{}: {e}", fmu.id))
    } else {
        vec![]
    };
    let nx = fmu.n_states_declared();
    let mut inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
    excite(&inst);
    inst.initialize();
    for _ in 0..20 {
        inst.step(fmu.step_size());
    }
    let api = &fmu.api;
    let (nu, nk) = (ue.len(), ke.len());
    // J by columns (directional) and by rows (adjoint), over the elements.
    let mut jd = vec![vec![0.0; nk]; nu];
    for j in 0..nk {
        let mut seed = vec![0.0; nk];
        seed[j] = 1.0;
        let mut sens = vec![f64::NAN; nu];
        let s = inst.derivative(false, &u, &k, &seed, &mut sens);
        assert_eq!(
            s,
            fmi3OK,
            "{}: fmi3GetDirectionalDerivative by {} (nUnknowns = {}, nKnowns = {}, nSeed = {nk}, nSensitivity = {nu}): {}",
            fmu.id,
            k_names[j],
            u.len(),
            k.len(),
            inst.log_text()
        );
        for r in 0..nu {
            jd[r][j] = sens[r];
        }
    }
    let mut ja = vec![vec![0.0; nk]; nu];
    if i.provides_adjoint_derivatives {
        for r in 0..nu {
            let mut seed = vec![0.0; nu];
            seed[r] = 1.0;
            let mut sens = vec![f64::NAN; nk];
            let s = inst.derivative(true, &u, &k, &seed, &mut sens);
            assert_eq!(
                s,
                fmi3OK,
                "{}: fmi3GetAdjointDerivative of {} (nUnknowns = {}, nKnowns = {}, nSeed = {nu}, nSensitivity = {nk}): {}",
                fmu.id,
                u_names[r],
                u.len(),
                k.len(),
                inst.log_text()
            );
            ja[r] = sens;
        }
        for r in 0..nu {
            for j in 0..nk {
                let (a, b) = (jd[r][j], ja[r][j]);
                assert!(
                    (a - b).abs() <= 1e-12 * (1.0 + a.abs()),
                    "{}: d{}/d{}: directional {a}, adjoint {b}: the adjoint must be the transpose",
                    fmu.id,
                    u_names[r],
                    k_names[j]
                );
            }
        }
    } else {
        info("providesAdjointDerivatives is false: the adjoint is not compared");
    }
    // Finite differences: perturb each element of each known, read every element of the
    // unknowns. The derivatives through fmi3GetContinuousStateDerivatives (ME), the rest
    // through fmi3GetFloat64.
    let read = |inst: &Inst| -> Vec<f64> {
        let (s, mut all) = inst.get_f64_n(&u, nu);
        assert_eq!(s, fmi3OK, "{}: reading the unknowns: {}", fmu.id, inst.log_text());
        if me {
            let dx = inst.derivatives_ok(nx);
            for (r, (var, e)) in ue.iter().enumerate() {
                if let Some(slot) = slots.iter().find(|p| p.1.vr == u[*var]) {
                    all[r] = dx[slot.2 + e];
                }
            }
        }
        all
    };
    let (_, base_x) = if me {
        inst.vector("fmi3GetContinuousStates", api.get_continuous_states, nx)
    } else {
        (fmi3OK, vec![])
    };
    let (s, base_k) = inst.get_f64_n(&k, nk);
    assert_eq!(s, fmi3OK, "{}: reading the knowns: {}", fmu.id, inst.log_text());
    // Where each known's elements start in `base_k`.
    let k_start: Vec<usize> = (0..k.len())
        .map(|var| ke.iter().position(|p| p.0 == var).unwrap_or(0))
        .collect();
    let set = |inst: &Inst, j: usize, value: f64| {
        let (var, e) = ke[j];
        let vr = k[var];
        if let Some(slot) = slots.iter().find(|p| p.0.vr == vr) {
            let mut x = base_x.clone();
            x[slot.2 + e] = value;
            inst.args(vec![("values", crate::calllog::Val::F64s(x.clone()))]);
            assert_eq!(
                // SAFETY: a live instance; each pointer is to a live local of the length passed, or
                // is an FMU state.
                inst.call("fmi3SetContinuousStates", |c| unsafe {
                    (api.set_continuous_states)(c, x.as_ptr(), x.len())
                }),
                fmi3OK,
                "{}: setting state {} = {value}: {}",
                fmu.id,
                k_names[j],
                inst.log_text()
            );
        } else {
            // The known's every element, the one perturbed among them.
            let n = fmu.element_count(k_vars[var]);
            let mut x = base_k[k_start[var]..k_start[var] + n].to_vec();
            x[e] = value;
            assert_eq!(
                inst.set_f64(&[vr], &x),
                fmi3OK,
                "{}: setting known {} = {value}: {}",
                fmu.id,
                k_names[j],
                inst.log_text()
            );
        }
    };
    let mut compared = 0;
    let mut kinks = 0;
    for j in 0..nk {
        let x0 = base_k[j];
        let fd = |eps: f64| -> Vec<f64> {
            set(&inst, j, x0 + eps);
            let p = read(&inst);
            set(&inst, j, x0 - eps);
            let m = read(&inst);
            set(&inst, j, x0);
            p.iter().zip(&m).map(|(p, m)| (p - m) / (2.0 * eps)).collect()
        };
        let e = 1e-6 * x0.abs().max(1.0);
        let (d1, d2) = (fd(e), fd(e / 10.0));
        for r in 0..nu {
            let a = jd[r][j];
            let (uv, kv) = (u[ue[r].0], k[ke[j].0]);
            if let Some(deps) = dependencies(fmu, me, uv)
                && !deps.contains(&kv)
            {
                assert_eq!(
                    a, 0.0,
                    "{}: d{}/d{} = {a}, but <ModelStructure> declares no dependency of vr {uv} on vr {kv}",
                    fmu.id, u_names[r], k_names[j]
                );
            }
            let tol = |x: f64| 1e-4 * (1.0 + x.abs());
            if (d1[r] - d2[r]).abs() > tol(d1[r]) {
                kinks += 1;
                continue;
            }
            assert!(
                (a - d1[r]).abs() <= tol(d1[r]),
                "{}: d{}/d{}: fmi3GetDirectionalDerivative {a}, central finite difference {} ({})",
                fmu.id,
                u_names[r],
                k_names[j],
                d1[r],
                if me { "ME" } else { "CS" }
            );
            compared += 1;
        }
    }
    let arrays = u_vars.iter().chain(&k_vars).filter(|v| v.array).count();
    info(format!(
        "{compared} of {} partial derivatives compared with finite differences ({kinks} left out where two step sizes disagree){}",
        nu * nk,
        if arrays > 0 {
            format!(
                "; {} unknown(s) and {} known(s) with {nu} and {nk} elements ({arrays} arrays)",
                u.len(),
                k.len()
            )
        } else {
            String::new()
        }
    ));
    // Bad arguments: nSeed != the knowns' elements, nSensitivity != the unknowns', an unknown
    // vr, a NULL seed.
    let (nuv, nkv) = (u.len(), k.len());
    let seed = vec![1.0; nk + 1];
    // Each through the call log (Inst::derivative_probe): the reproducer's line makes it again.
    refused_by(
        &inst,
        "fmi3GetDirectionalDerivative(nSeed = the knowns' elements + 1)",
        || inst.derivative_probe(false, &u, &k, Some(&seed), nk + 1, nu),
    );
    refused_by(
        &inst,
        "fmi3GetDirectionalDerivative(nSensitivity = the unknowns' elements + 1)",
        || inst.derivative_probe(false, &u, &k, Some(&seed), nk, nu + 1),
    );
    if nu != nuv || nk != nkv {
        // nSeed and nSensitivity counting variables, not elements (an importer's mistake with
        // arrays): refused.
        refused_by(
            &inst,
            &format!(
                "fmi3GetDirectionalDerivative(nSeed = nKnowns = {nkv}, nSensitivity = nUnknowns = {nuv}: the arrays' elements are {nk} and {nu})"
            ),
            || inst.derivative_probe(false, &u, &k, Some(&seed), nkv, nuv),
        );
    }
    let bad = [fmu.md.unknown_vr()];
    refused_by(&inst, "fmi3GetDirectionalDerivative(unknown vr as unknown)", || {
        inst.derivative_probe(false, &bad, &k, Some(&seed), nk, 1)
    });
    refused_by(&inst, "fmi3GetDirectionalDerivative(seed = NULL)", || {
        inst.derivative_probe(false, &u, &k, None, nk, nu)
    });
    if i.provides_adjoint_derivatives {
        let (n_seed, m) = if nk == nu { (nu + 1, nk) } else { (nk, nu) };
        refused_by(
            &inst,
            "fmi3GetAdjointDerivative(nSeed = the knowns' elements: the adjoint's seed has the unknowns')",
            || inst.derivative_probe(true, &u, &k, Some(&seed), n_seed, m),
        );
    }
}

pub fn fmi3_co_simulation_directional_derivatives_match_finite_differences_and_the_adjoint_is_the_transpose(
    fmu: &Fmu3,
) {
    derivatives_check(fmu, false);
}

pub fn fmi3_model_exchange_directional_derivatives_match_finite_differences_and_the_adjoint_is_the_transpose(
    fmu: &Fmu3,
) {
    derivatives_check(fmu, true);
}
