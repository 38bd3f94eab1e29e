//! FMI 3.0 directional and adjoint derivatives against finite differences.

use super::*;

// ---------------------------------------------------------------------------------------------
// Directional and adjoint derivatives

pub(super) fn unknowns(fmu: &Fmu3, me: bool) -> Vec<u32> {
    let mut list = vec![];
    if me {
        list.extend(fmu.md.derivatives.iter().map(|u| u.vr));
    }
    list.extend(
        fmu.md
            .outputs
            .iter()
            .map(|u| u.vr)
            // (Clocked outputs are read at their ticks only, not where derivatives are taken.)
            .filter(|vr| {
                fmu.md
                    .by_vr(*vr)
                    .is_some_and(|v| v.ty == Type::Float64 && v.clocks.is_empty())
            }),
    );
    list
}

pub(super) fn knowns(fmu: &Fmu3, me: bool) -> Vec<u32> {
    let mut list = vec![];
    if me {
        list.extend(fmu.md.continuous_states().unwrap_or_default().iter().map(|p| p.0));
    }
    list.extend(float_inputs(fmu).iter().map(|v| v.vr));
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

fn derivatives_check(fmu: &Fmu3, me: bool) {
    let i = if me { fmu.md.me.as_ref() } else { fmu.md.cs.as_ref() };
    let Some(i) = i else {
        skip_not_declared(if me { "<ModelExchange>" } else { "<CoSimulation>" })
    };
    if !i.provides_directional_derivatives {
        skip_not_declared("providesDirectionalDerivatives");
    }
    let (u, k) = (unknowns(fmu, me), knowns(fmu, me));
    if u.is_empty() || k.is_empty() {
        // A co-simulation FMU without continuous Real inputs has no knowns (BouncingBall).
        skip_not_declared(format!(
            "a Real unknown and known to differentiate (unknowns {}, knowns {})",
            u.len(),
            k.len()
        ));
    }
    let states = fmu.md.continuous_states().unwrap_or_default();
    let mut inst = if me { Inst::me(fmu) } else { Inst::cs(fmu) };
    excite(&inst);
    inst.initialize();
    for _ in 0..20 {
        inst.step(fmu.step_size());
    }
    let api = &fmu.api;
    let (nu, nk) = (u.len(), k.len());
    // J by columns (directional) and by rows (adjoint).
    let mut jd = vec![vec![0.0; nk]; nu];
    for (j, _) in k.iter().enumerate() {
        let mut seed = vec![0.0; nk];
        seed[j] = 1.0;
        let mut sens = vec![f64::NAN; nu];
        let s = inst.call("fmi3GetDirectionalDerivative", |c| unsafe {
            (api.get_directional_derivative)(
                c,
                u.as_ptr(),
                nu,
                k.as_ptr(),
                nk,
                seed.as_ptr(),
                nk,
                sens.as_mut_ptr(),
                nu,
            )
        });
        assert_eq!(
            s,
            fmi3OK,
            "{}: fmi3GetDirectionalDerivative: {}",
            fmu.id,
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
            let s = inst.call("fmi3GetAdjointDerivative", |c| unsafe {
                (api.get_adjoint_derivative)(
                    c,
                    u.as_ptr(),
                    nu,
                    k.as_ptr(),
                    nk,
                    seed.as_ptr(),
                    nu,
                    sens.as_mut_ptr(),
                    nk,
                )
            });
            assert_eq!(s, fmi3OK, "{}: fmi3GetAdjointDerivative: {}", fmu.id, inst.log_text());
            ja[r] = sens;
        }
        for r in 0..nu {
            for j in 0..nk {
                let (a, b) = (jd[r][j], ja[r][j]);
                assert!(
                    (a - b).abs() <= 1e-12 * (1.0 + a.abs()),
                    "{}: d{}/d{}: directional {a}, adjoint {b}: the adjoint must be the transpose",
                    fmu.id,
                    u[r],
                    k[j]
                );
            }
        }
    } else {
        info("providesAdjointDerivatives is false: the adjoint is not compared");
    }
    // Finite differences: perturb each known, read the unknowns.
    // The unknowns: derivatives through fmi3GetContinuousStateDerivatives (ME), the rest
    // through fmi3GetFloat64.
    let read = |inst: &Inst| -> Vec<f64> {
        let (s, mut all) = inst.get_f64(&u);
        assert_eq!(s, fmi3OK, "{}: reading the unknowns: {}", fmu.id, inst.log_text());
        if me {
            let (s, dx) = inst.vector(
                "fmi3GetContinuousStateDerivatives",
                api.get_continuous_state_derivatives,
                states.len(),
            );
            assert_eq!(s, fmi3OK);
            for (r, vr) in u.iter().enumerate() {
                if let Some(si) = states.iter().position(|p| p.1 == *vr) {
                    all[r] = dx[si];
                }
            }
        }
        all
    };
    let (_, base_x) = if me {
        inst.vector("x", api.get_continuous_states, states.len())
    } else {
        (fmi3OK, vec![])
    };
    let (_, base_k) = inst.get_f64(&k);
    let set = |inst: &Inst, j: usize, value: f64| {
        let vr = k[j];
        if let Some(si) = states.iter().position(|p| p.0 == vr).filter(|_| me) {
            let mut x = base_x.clone();
            x[si] = value;
            assert_eq!(
                inst.call("sx", |c| unsafe { (api.set_continuous_states)(c, x.as_ptr(), x.len()) }),
                fmi3OK
            );
        } else {
            assert_eq!(
                inst.set_f64(&[vr], &[value]),
                fmi3OK,
                "{}: setting known {vr} = {value}: {}",
                fmu.id,
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
            if let Some(deps) = dependencies(fmu, me, u[r])
                && !deps.contains(&k[j])
            {
                assert_eq!(
                    a, 0.0,
                    "{}: d{}/d{} = {a}, but <ModelStructure> declares no dependency",
                    fmu.id, u[r], k[j]
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
                u[r],
                k[j],
                d1[r],
                if me { "ME" } else { "CS" }
            );
            compared += 1;
        }
    }
    info(format!(
        "{compared} of {} partial derivatives compared with finite differences ({kinks} left out where two step sizes disagree)",
        nu * nk
    ));
    // Bad arguments: nSeed != nKnowns, unknown vr, NULL seed.
    let seed = vec![1.0; nk + 1];
    let mut sens = vec![0.0; nu + 1];
    refused(&inst, "fmi3GetDirectionalDerivative(nSeed = nKnowns + 1)", |c| unsafe {
        (api.get_directional_derivative)(
            c,
            u.as_ptr(),
            nu,
            k.as_ptr(),
            nk,
            seed.as_ptr(),
            nk + 1,
            sens.as_mut_ptr(),
            nu,
        )
    });
    refused(
        &inst,
        "fmi3GetDirectionalDerivative(nSensitivity = nUnknowns + 1)",
        |c| unsafe {
            (api.get_directional_derivative)(
                c,
                u.as_ptr(),
                nu,
                k.as_ptr(),
                nk,
                seed.as_ptr(),
                nk,
                sens.as_mut_ptr(),
                nu + 1,
            )
        },
    );
    let bad = [fmu.md.unknown_vr()];
    refused(
        &inst,
        "fmi3GetDirectionalDerivative(unknown vr as unknown)",
        |c| unsafe {
            (api.get_directional_derivative)(
                c,
                bad.as_ptr(),
                1,
                k.as_ptr(),
                nk,
                seed.as_ptr(),
                nk,
                sens.as_mut_ptr(),
                1,
            )
        },
    );
    refused(&inst, "fmi3GetDirectionalDerivative(seed = NULL)", |c| unsafe {
        (api.get_directional_derivative)(c, u.as_ptr(), nu, k.as_ptr(), nk, null(), nk, sens.as_mut_ptr(), nu)
    });
    if i.provides_adjoint_derivatives {
        refused(
            &inst,
            "fmi3GetAdjointDerivative(nSeed = nKnowns: the adjoint's seed has nUnknowns)",
            |c| unsafe {
                (api.get_adjoint_derivative)(
                    c,
                    u.as_ptr(),
                    nu,
                    k.as_ptr(),
                    nk,
                    seed.as_ptr(),
                    if nk == nu { nu + 1 } else { nk },
                    sens.as_mut_ptr(),
                    if nk == nu { nk } else { nu },
                )
            },
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
