//! fmi2GetDirectionalDerivative (FMI 2.0 section 2.1.9), for both interfaces: where the FMU
//! declares providesDirectionalDerivative="true", the derivatives of the unknowns of
//! `<ModelStructure>` with respect to the knowns agree with central finite differences computed
//! through the black-box API, at random points; an unknown declared not to depend on a known
//! has derivative 0; bad arguments are refused. Where it declares "false", the function must
//! answer fmi2Error.
//!
//! Knowns and unknowns: in model exchange, the continuous states and the continuous Real inputs,
//! and the derivatives (`<Derivatives>`) and Real outputs (`<Outputs>`); in co-simulation, the
//! continuous Real inputs and the Real outputs (the states cannot be set there). Finite differences: in
//! model exchange fmi2SetContinuousStates / fmi2SetReal of an input, then fmi2GetReal of the
//! unknowns; in co-simulation fmi2SetReal of an input, then fmi2GetReal of the outputs.

use crate::fmi2::*;
use crate::instance::{Instance, excitation, status_name, step_size};
use crate::instance_calls::Derivative;
use crate::me::{Euler, Rng, needs_me};
use crate::outcome::{NOT_DECLARED, info, limitation, skip_not_declared};
use crate::{Fmu, Type, Variable, bits};
use md_reader::{Causality, Initial, Variability};

/// Relative (and, below 1, absolute) tolerance of the comparison with finite differences.
const TOLERANCE: f64 = 1e-5;
/// Random points tried per FMU and interface; more are tried (up to twice as many) for pairs
/// that every point so far left out (finite differences in two step sizes disagreed: a kink).
const POINTS: usize = 4;

/// An unknown: the variable and the dependencies `<ModelStructure>` declares (`None`: any).
type UnknownVar<'a> = (&'a Variable, Option<&'a Vec<usize>>);

/// The unknowns of an interface (see the module documentation), Real only.
pub fn unknowns(fmu: &Fmu, me: bool) -> Vec<UnknownVar<'_>> {
    let md = &fmu.md;
    let ms = &md.model_structure;
    let mut list: Vec<&md_reader::fmi2::Unknown> = vec![];
    if me {
        list.extend(&ms.derivatives);
    }
    list.extend(&ms.outputs);
    let mut out: Vec<UnknownVar> = vec![];
    for u in list {
        if let Some(v) = md.by_index(u.index).filter(|v| v.ty == Type::Real)
            && !out.iter().any(|(w, _)| w.vr == v.vr)
        {
            out.push((v, u.dependencies.as_ref()));
        }
    }
    out
}

/// A known: a continuous state (its position in the state vector) or a Real input.
#[derive(Debug, Clone, Copy)]
pub enum Known<'a> {
    State(usize, &'a Variable),
    Input(&'a Variable),
}

impl<'a> Known<'a> {
    fn var(&self) -> &'a Variable {
        match self {
            Known::State(_, v) | Known::Input(v) => v,
        }
    }
}

/// The knowns of an interface (see the module documentation).
pub fn knowns(fmu: &Fmu, me: bool) -> Vec<Known<'_>> {
    let md = &fmu.md;
    let mut out = vec![];
    if me {
        if let Ok(states) = md.continuous_states() {
            out.extend(states.into_iter().enumerate().map(|(j, (x, _))| Known::State(j, x)));
        }
        out.extend(
            md.of_type(Type::Real)
                .filter(|v| v.causality == Causality::Input && v.variability == Variability::Continuous)
                .map(Known::Input),
        );
    } else {
        // As in model exchange: the continuous inputs. A discrete input changes only at
        // communication points and events; the partial derivatives the standard defines are
        // those of the continuous-time equations (FMI 2.0, 2.1.9), which a discrete input is
        // not a variable of.
        out.extend(
            md.of_type(Type::Real)
                .filter(|v| v.causality == Causality::Input && v.variability == Variability::Continuous)
                .map(Known::Input),
        );
    }
    out
}

/// One unknown and one known of the interface, for a call with valid arguments (empty when
/// the FMU has none).
pub fn valid_pair(fmu: &Fmu, me: bool) -> (Vec<u32>, Vec<u32>) {
    match (unknowns(fmu, me).first(), knowns(fmu, me).first()) {
        (Some((u, _)), Some(k)) => (vec![u.vr], vec![k.var().vr]),
        _ => (vec![], vec![]),
    }
}

/// fmi2GetDirectionalDerivative(unknowns, knowns, seed 1 for every known): the sum of the
/// columns of the knowns.
pub fn call(inst: &Instance, unknowns: &[u32], knowns: &[u32]) -> (fmi2Status, Vec<f64>) {
    let seed = vec![1.0; knowns.len()];
    inst.directional_derivative(Derivative::of(unknowns, knowns, &seed))
}

fn provides(fmu: &Fmu, me: bool) -> bool {
    if me {
        fmu.md.me.as_ref().is_some_and(|m| m.provides_directional_derivative)
    } else {
        fmu.cs().provides_directional_derivative
    }
}

/// An instance where directional derivatives are asked: co-simulation after a step, model
/// exchange in ContinuousTimeMode.
fn ready(fmu: &Fmu, me: bool) -> Instance<'_> {
    if me {
        let mut inst = Instance::new_me(fmu);
        inst.me_initialize();
        inst
    } else {
        let mut inst = Instance::new(fmu);
        let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(fmu).into_iter().unzip();
        assert_eq!(inst.set_real(&vrs, &vals), fmi2OK, "{}", inst.log_text());
        inst.initialize();
        assert_eq!(inst.step(step_size(fmu)), fmi2OK, "{}", inst.log_text());
        inst
    }
}

fn interface(me: bool) -> &'static str {
    if me { "model exchange" } else { "co-simulation" }
}

pub fn directional_derivative_flag_is_either_value_and_false_means_refused(fmu: &Fmu) {
    let mut interfaces = vec![false];
    if fmu.md.me.is_some() {
        needs_me(fmu);
        interfaces.push(true);
    }
    for me in interfaces {
        let flag = provides(fmu, me);
        info(format!("{}: providesDirectionalDerivative=\"{flag}\"", interface(me)));
        let inst = ready(fmu, me);
        let (mut unknowns, mut knowns) = valid_pair(fmu, me);
        if !flag && unknowns.is_empty() {
            // Something to ask for, so that the refusal is not an answer to an empty call.
            let real = fmu.md.vrs_of_type(Type::Real);
            (unknowns, knowns) = (real[..1].to_vec(), real[..1].to_vec());
        }
        let (s, values) = call(&inst, &unknowns, &knowns);
        let log = inst.log();
        let at = format!("{}: {}: fmi2GetDirectionalDerivative", fmu.id, interface(me));
        if flag {
            assert_eq!(s, fmi2OK, "{at} (providesDirectionalDerivative=\"true\"): {log:?}");
            assert!(values.iter().all(|v| v.is_finite()), "{at}: not finite: {values:?}");
            if unknowns.is_empty() {
                limitation(format!(
                    "{NOT_DECLARED}{}: a Real unknown and known to ask for (no continuous Real input{})",
                    interface(me),
                    if me { " or state" } else { "" }
                ));
            }
        } else {
            assert_eq!(
                s,
                fmi2Error,
                "{at}: providesDirectionalDerivative=\"false\", expected fmi2Error, got {}; log {log:?}",
                status_name(s)
            );
            assert!(
                inst.says(&log, fmi2Error, &["fmi2GetDirectionalDerivative"]),
                "{at}: refused without a message: {log:?}"
            );
        }
    }
}

/// What the comparisons found, for the report.
#[derive(Default)]
struct Stats {
    compared: usize,
    kinks: usize,
    max_error: f64,
    zeros: usize,
}

/// Sets a known to a value (a state through fmi2SetContinuousStates, from the base vector).
fn set_known(inst: &mut Instance, k: &Known, x_base: &[f64], value: f64) {
    let s = match k {
        Known::State(j, _) => {
            let mut x = x_base.to_vec();
            x[*j] = value;
            inst.set_continuous_states(&x)
        }
        Known::Input(v) => inst.set_real(&[v.vr], &[value]),
    };
    assert_eq!(
        s,
        fmi2OK,
        "{}: setting '{}' = {value}: {}",
        inst.fmu.id,
        k.var().name,
        inst.log_text()
    );
}

fn read(inst: &Instance, vrs: &[u32]) -> Vec<f64> {
    let (s, y) = inst.get_real(vrs);
    assert_eq!(s, fmi2OK, "{}: fmi2GetReal: {}", inst.fmu.id, inst.log_text());
    y
}

/// The 1-based `<ModelVariables>` index of a variable.
fn index_of(fmu: &Fmu, v: &Variable) -> usize {
    fmu.md
        .variables
        .iter()
        .position(|w| std::ptr::eq(w, v))
        .expect("a variable of the FMU")
        + 1
}

/// Compares every column at the instance's current point; `done[u][k]` records the pairs
/// compared (not left out for a kink).
fn compare_here(
    inst: &mut Instance,
    me: bool,
    point: usize,
    done: &mut [Vec<bool>],
    stats: &mut Stats,
    failures: &mut Vec<String>,
) {
    let fmu = inst.fmu;
    let unknowns = unknowns(fmu, me);
    let knowns = knowns(fmu, me);
    let vrs: Vec<u32> = unknowns.iter().map(|(v, _)| v.vr).collect();
    let x_base = if me {
        let (s, x) = inst.get_continuous_states();
        assert_eq!(s, fmi2OK, "{}", inst.log_text());
        x
    } else {
        vec![]
    };
    let y0 = read(inst, &vrs);
    for (kj, k) in knowns.iter().enumerate() {
        let at = |u: &Variable| {
            format!(
                "{}: {}: point {point}: d '{}' / d '{}'",
                fmu.id,
                interface(me),
                u.name,
                k.var().name
            )
        };
        let (s, dd) = call(inst, &vrs, &[k.var().vr]);
        let dd_call = crate::calllog::last_call();
        if s != fmi2OK {
            failures.push(format!(
                "{}: {}: fmi2GetDirectionalDerivative(unknowns, ['{}']) answered {}: {}",
                fmu.id,
                interface(me),
                k.var().name,
                status_name(s),
                inst.log_text()
            ));
            continue;
        }
        let v0 = match k {
            Known::State(j, _) => x_base[*j],
            Known::Input(v) => read(inst, &[v.vr])[0],
        };
        let mut fd = |h: f64| -> Vec<f64> {
            let (a, b) = (v0 + h, v0 - h);
            set_known(inst, k, &x_base, a);
            let ya = read(inst, &vrs);
            set_known(inst, k, &x_base, b);
            let yb = read(inst, &vrs);
            set_known(inst, k, &x_base, v0);
            ya.iter().zip(&yb).map(|(p, q)| (p - q) / (a - b)).collect()
        };
        let h = 1e-6 * v0.abs().max(1.0);
        let (fd1, fd2) = (fd(h), fd(10.0 * h));
        assert_eq!(
            bits(&read(inst, &vrs)),
            bits(&y0),
            "{}: {}: the unknowns differ after '{}' was set back to {v0}",
            fmu.id,
            interface(me),
            k.var().name
        );
        let k_index = index_of(fmu, k.var());
        for (ui, (u, deps)) in unknowns.iter().enumerate() {
            if !dd[ui].is_finite() {
                failures.push(format!("{}: the directional derivative is {}", at(u), dd[ui]));
                continue;
            }
            if let Some(deps) = deps
                && !deps.contains(&k_index)
            {
                stats.zeros += 1;
                if dd[ui] != 0.0 {
                    let mut expected = dd.clone();
                    expected[ui] = 0.0;
                    crate::calllog::fails_at(dd_call, &expected, 0.0);
                    failures.push(format!(
                        "{}: <ModelStructure> declares no dependency, but the directional derivative is {:e}",
                        at(u),
                        dd[ui]
                    ));
                }
            }
            let scale = fd1[ui].abs().max(1.0);
            if (fd1[ui] - fd2[ui]).abs() > TOLERANCE * scale {
                stats.kinks += 1;
                continue;
            }
            done[ui][kj] = true;
            stats.compared += 1;
            let error = (dd[ui] - fd1[ui]).abs() / scale;
            stats.max_error = stats.max_error.max(error);
            if error > TOLERANCE {
                // The reproducer ends with this call, expecting the finite difference here
                // (and the other unknowns as they came): its replay differs where this did.
                let mut expected = dd.clone();
                expected[ui] = fd1[ui];
                crate::calllog::fails_at(dd_call, &expected, TOLERANCE * scale);
                failures.push(format!(
                    "{}: fmi2GetDirectionalDerivative gives {:e}, central finite differences {:e} (step {h:e}; {:e} with 10 times the step)",
                    at(u),
                    dd[ui],
                    fd1[ui],
                    fd2[ui]
                ));
            }
        }
    }
}

/// A value of moderate size for a variable: uniform in [-0.5, 0.5], within its min and max.
fn moderate(rng: &mut Rng, v: &Variable) -> f64 {
    let x = rng.uniform(-0.5, 0.5);
    let x = v.max.map_or(x, |m| x.min(m));
    v.min.map_or(x, |m| x.max(m))
}

/// An instance at random point number `point`.
fn at_random_point<'f>(fmu: &'f Fmu, me: bool, rng: &mut Rng) -> Instance<'f> {
    let knowns = knowns(fmu, me);
    let inputs: Vec<&Variable> = knowns
        .iter()
        .filter_map(|k| match k {
            Known::Input(v) => Some(*v),
            Known::State(..) => None,
        })
        .collect();
    if me {
        let mut inst = Instance::new_me(fmu);
        let info = inst.me_initialize();
        let mut euler = Euler::new(&inst, 1e-4, &info);
        for _ in 0..5 {
            euler.step(&mut inst);
        }
        let states: Vec<f64> = knowns
            .iter()
            .filter_map(|k| match k {
                Known::State(_, v) => Some(moderate(rng, v)),
                Known::Input(_) => None,
            })
            .collect();
        if !states.is_empty() {
            assert_eq!(inst.set_continuous_states(&states), fmi2OK, "{}", inst.log_text());
        }
        for v in &inputs {
            let u = moderate(rng, v);
            assert_eq!(inst.set_real(&[v.vr], &[u]), fmi2OK, "{}", inst.log_text());
        }
        inst
    } else {
        // The initial states (non-parameter Reals with initial="exact") and the inputs.
        let mut inst = Instance::new(fmu);
        for v in fmu.md.of_type(Type::Real).filter(|v| {
            v.variability != Variability::Constant
                && (v.causality == Causality::Input
                    || (v.causality != Causality::Parameter
                        && crate::standard::initial(v.causality, v.variability, v.declared_initial)
                            == Some(Initial::Exact)))
        }) {
            let x = moderate(rng, v);
            assert_eq!(inst.set_real(&[v.vr], &[x]), fmi2OK, "{}", inst.log_text());
        }
        inst.initialize();
        for _ in 0..5 {
            assert_eq!(inst.step(step_size(fmu)), fmi2OK, "{}", inst.log_text());
        }
        for v in &inputs {
            let u = moderate(rng, v);
            assert_eq!(inst.set_real(&[v.vr], &[u]), fmi2OK, "{}", inst.log_text());
        }
        inst
    }
}

fn match_finite_differences(fmu: &Fmu, me: bool) {
    if !provides(fmu, me) {
        skip_not_declared(format!(
            "providesDirectionalDerivative=\"true\" in <{}>",
            if me { "ModelExchange" } else { "CoSimulation" }
        ));
    }
    let unknowns = unknowns(fmu, me);
    let knowns = knowns(fmu, me);
    if unknowns.is_empty() || knowns.is_empty() {
        info(format!(
            "{}: {} Real unknowns, {} knowns: nothing to differentiate",
            interface(me),
            unknowns.len(),
            knowns.len()
        ));
        return;
    }
    let mut rng = Rng::new(0x5eed_d1ff ^ me as u64);
    let mut done = vec![vec![false; knowns.len()]; unknowns.len()];
    let mut stats = Stats::default();
    let mut failures = vec![];
    let mut points = 0;
    while points < POINTS || (points < 2 * POINTS && done.iter().flatten().any(|d| !d)) {
        let mut inst = at_random_point(fmu, me, &mut rng);
        compare_here(&mut inst, me, points, &mut done, &mut stats, &mut failures);
        points += 1;
    }
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
    for (ui, (u, _)) in unknowns.iter().enumerate() {
        for (kj, k) in knowns.iter().enumerate() {
            if !done[ui][kj] {
                limitation(format!(
                    "d '{}' / d '{}' not compared: finite differences in two step sizes disagreed at every one of {points} points (a kink?)",
                    u.name,
                    k.var().name
                ));
            }
        }
    }
    info(format!(
        "{}: {} unknowns x {} knowns at {points} random points: {} comparisons (largest relative difference {:.1e}), {} left out for a kink, {} declared independent and 0",
        interface(me),
        unknowns.len(),
        knowns.len(),
        stats.compared,
        stats.max_error,
        stats.kinks,
        stats.zeros
    ));
}

pub fn co_simulation_directional_derivatives_match_finite_differences(fmu: &Fmu) {
    match_finite_differences(fmu, false);
}

pub fn model_exchange_directional_derivatives_match_finite_differences(fmu: &Fmu) {
    needs_me(fmu);
    match_finite_differences(fmu, true);
}

/// fmi2GetDirectionalDerivative with an unknown value reference among the unknowns and among the
/// knowns, and with each array NULL: refused with fmi2Error and a message, and the same valid
/// call afterwards gives the same result.
///
/// Verdict: warned, not failed, where a mistaken call is not refused (or crashes): these are the
/// importer's mistakes, which FMI 2.0.5 leaves undefined (§2.1.3: fmi2Error is the answer to what
/// the FMU detects; detecting is good practice, not a requirement). Failed: the valid call after
/// them answering other than fmi2OK or giving another result (the instance must still serve).
pub fn directional_derivatives_refuse_unknown_references_and_null_arrays(fmu: &Fmu) {
    let mut interfaces = vec![];
    if provides(fmu, false) {
        interfaces.push(false);
    }
    if fmu.md.me.is_some() && provides(fmu, true) {
        needs_me(fmu);
        interfaces.push(true);
    }
    if interfaces.is_empty() {
        skip_not_declared("providesDirectionalDerivative=\"true\"");
    }
    for me in interfaces {
        let inst = ready(fmu, me);
        let (unknowns, knowns) = valid_pair(fmu, me);
        if unknowns.is_empty() {
            limitation(format!(
                "{NOT_DECLARED}{}: a Real unknown and known (bad arguments not tried)",
                interface(me)
            ));
            continue;
        }
        let (s, good) = call(&inst, &unknowns, &knowns);
        assert_eq!(s, fmi2OK, "{}: {}", fmu.id, inst.log_text());
        inst.log();
        let bad_vr = [fmu.md.unknown_vr()];
        let seed = [1.0];
        let valid = Derivative::of(&unknowns, &knowns, &seed);
        // (what, the call): each an importer's mistake.
        let cases: [(&str, Derivative); 6] = [
            (
                "an unknown value reference among the unknowns",
                Derivative {
                    unknowns: Some(&bad_vr),
                    ..valid
                },
            ),
            (
                "an unknown value reference among the knowns",
                Derivative {
                    knowns: Some(&bad_vr),
                    ..valid
                },
            ),
            (
                "vUnknown_ref NULL with nUnknown = 1",
                Derivative {
                    unknowns: None,
                    ..valid
                },
            ),
            ("vKnown_ref NULL with nKnown = 1", Derivative { knowns: None, ..valid }),
            ("dvKnown NULL", Derivative { seed: None, ..valid }),
            ("dvUnknown NULL", Derivative { output: false, ..valid }),
        ];
        let mut refused = 0;
        for (what, d) in cases {
            // Each call alone is the importer's mistake (outcome::on_purpose): a crash in it is
            // a warning naming it, the calls before and after it are the check's own.
            let s = crate::outcome::on_purpose(|| inst.directional_derivative(d).0);
            refused += usize::from(s == fmi2Error);
            crate::outcome::warn_unless(s == fmi2Error, || {
                format!(
                    "{}: {}: fmi2GetDirectionalDerivative with {what}: expected fmi2Error, got {} (an importer's \
                     mistake not detected)",
                    fmu.id,
                    interface(me),
                    status_name(s)
                )
            });
        }
        let log = inst.log();
        let messages = log.iter().filter(|e| e.status == fmi2Error).count();
        crate::outcome::warn_unless(messages >= refused, || {
            format!(
                "{}: {}: {refused} refused calls, {messages} fmi2Error messages: {log:?}",
                fmu.id,
                interface(me)
            )
        });
        let (s, again) = call(&inst, &unknowns, &knowns);
        assert_eq!(s, fmi2OK, "{}: usable after the refusals: {}", fmu.id, inst.log_text());
        assert_eq!(
            bits(&again),
            bits(&good),
            "{}: {}: the same call after the refusals gives another result",
            fmu.id,
            interface(me)
        );
    }
}
