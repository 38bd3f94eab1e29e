//! The variable dependencies at run time, and the directional and adjoint derivatives
//! (exact: dual numbers through the model's equations).
//!
//! # Safety
//! As for [`super`]: every `unsafe fn` has the contract of the `fmi3*` function it implements.

use super::values::{added_time_vr, value_count};
use super::*;

/// The dependencies of `dependent` in the instance's state, from the declarations (the same
/// ones `<ModelStructure>` lists), or the logged refusal.
fn dependencies_of<M: CoSimulation>(
    inst: &Instance<M>,
    function: &str,
    dependent: u32,
) -> Result<Vec<u32>, fmi3Status> {
    let initialization = matches!(inst.state(), State::Instantiated | State::InitializationMode);
    let time_vr = M::DESCRIPTION.time_value_reference();
    M::DESCRIPTION
        .dependencies(dependent, initialization, time_vr)
        .ok_or_else(|| {
            let what = match M::variable_index(dependent) {
                Some(i) => format!("'{}'", M::DESCRIPTION.variables[i].name),
                None if added_time_vr::<M>() == Some(dependent) => "'time'".to_string(),
                None => {
                    return inst.error(&format!(
                        "{function}: value reference {dependent} is no variable of {}",
                        M::DESCRIPTION.model_identifier
                    ));
                }
            };
            inst.error(&format!(
                "{function}: {what} (vr {dependent}) is no unknown {}: it has no dependencies to report",
                if initialization {
                    "of Initialization Mode (<InitialUnknown>)"
                } else {
                    "of <ModelStructure> (an output, a state derivative or an event indicator)"
                }
            ))
        })
}

pub unsafe fn get_number_of_variable_dependencies<M: CoSimulation>(
    c: Option<&Component<M>>,
    dependent: fmi3ValueReference,
    n: *mut usize,
) -> fmi3Status {
    const F: &str = "fmi3GetNumberOfVariableDependencies";
    with_instance(c, Call::SetDebugLogging, F, |inst| {
        if n.is_null() {
            return inst.error(&format!("{F}: nDependencies is NULL"));
        }
        match dependencies_of(inst, F, dependent) {
            Ok(deps) => {
                // SAFETY: not NULL; the contract makes it point to one size_t.
                unsafe { *n = deps.len() };
                fmi3OK
            }
            Err(status) => status,
        }
    })
}

pub unsafe fn get_variable_dependencies<M: CoSimulation>(
    c: Option<&Component<M>>,
    dependent: fmi3ValueReference,
    element_indices_of_dependent: *mut usize,
    independents: *mut fmi3ValueReference,
    element_indices_of_independents: *mut usize,
    kinds: *mut fmi3DependencyKind,
    n: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetVariableDependencies";
    with_instance(c, Call::SetDebugLogging, F, |inst| {
        let deps = match dependencies_of(inst, F, dependent) {
            Ok(deps) => deps,
            Err(status) => return status,
        };
        if n != deps.len() {
            return inst.error(&format!(
                "{F}: nDependencies = {n}, but '{dependent}' has {} (fmi3GetNumberOfVariableDependencies)",
                deps.len()
            ));
        }
        // SAFETY: `slice_mut` checks NULL; the contract makes each array hold `n` elements.
        let arrays = unsafe {
            (
                slice_mut(element_indices_of_dependent, n),
                slice_mut(independents, n),
                slice_mut(element_indices_of_independents, n),
                slice_mut(kinds, n),
            )
        };
        let (Some(e_dep), Some(ind), Some(e_ind), Some(k)) = arrays else {
            return inst.error(&format!("{F}: an output array is NULL with nDependencies = {n}"));
        };
        for (i, vr) in deps.into_iter().enumerate() {
            // Every variable is a scalar: element index 0 (the whole variable); the kind is not
            // analysed further than "depends".
            e_dep[i] = 0;
            ind[i] = vr;
            e_ind[i] = 0;
            k[i] = fmi3Dependent;
        }
        fmi3OK
    })
}

/// fmi3GetDirectionalDerivative (`adjoint` false) and fmi3GetAdjointDerivative (true): the
/// instance and the state check, the array lengths (`seed` has one element per known and
/// `sensitivity` one per unknown for the directional derivative, the other way round for the
/// adjoint), the four arrays' NULL checks; then `directional` or `adjoint`. Inlined into
/// each exported function, so that `adjoint` is a constant there.
///
/// # Safety
/// The contract of fmi3GetDirectionalDerivative / fmi3GetAdjointDerivative: `c` NULL or a live
/// instance of this library for `M`; each array NULL or as long as the count beside it,
/// `sensitivity` writable.
#[inline(always)]
pub unsafe fn get_derivative<M: CoSimulation>(
    adjoint: bool,
    c: Option<&Component<M>>,
    unknowns: *const fmi3ValueReference,
    n_unknowns: usize,
    knowns: *const fmi3ValueReference,
    n_knowns: usize,
    seed: *const fmi3Float64,
    n_seed: usize,
    sensitivity: *mut fmi3Float64,
    n_sensitivity: usize,
) -> fmi3Status {
    let function = if adjoint {
        "fmi3GetAdjointDerivative"
    } else {
        "fmi3GetDirectionalDerivative"
    };
    with_instance(c, Call::GetDirectionalDerivative, function, |inst| {
        // An array counts each of its elements (FMI 3.0, 2.2.11: nSeed and nSensitivity are
        // the numbers of elements of the knowns and unknowns).
        let (n_unknown_values, n_known_values) = if const { M::DESCRIPTION.has_arrays() } {
            // SAFETY: as below.
            let count = |vrs: *const fmi3ValueReference, n: usize| match unsafe { slice(vrs, n) } {
                Some(vrs) => value_count::<M>(&inst.sim.model, vrs),
                None => n,
            };
            (count(unknowns, n_unknowns), count(knowns, n_knowns))
        } else {
            (n_unknowns, n_knowns)
        };
        let ((seed_of, n_seed_of), (sensitivity_of, n_sensitivity_of)) = if adjoint {
            (
                ("the unknowns' values", n_unknown_values),
                ("the knowns' values", n_known_values),
            )
        } else {
            (
                ("the knowns' values", n_known_values),
                ("the unknowns' values", n_unknown_values),
            )
        };
        if n_seed != n_seed_of || n_sensitivity != n_sensitivity_of {
            return inst.error(&format!(
                "{function}: nSeed = {n_seed} must equal the number of {seed_of} = {n_seed_of} and nSensitivity = \
                 {n_sensitivity} that of {sensitivity_of} = {n_sensitivity_of} (nUnknowns = {n_unknowns}, nKnowns = \
                 {n_knowns}; an array counts each element)"
            ));
        }
        // SAFETY: `slice` and `slice_mut` check NULL; the contract makes each array as long as
        // the count beside it.
        let arrays = unsafe {
            (
                slice(unknowns, n_unknowns),
                slice(knowns, n_knowns),
                slice(seed, n_seed),
                slice_mut(sensitivity, n_sensitivity),
            )
        };
        match arrays {
            (Some(unknowns), Some(knowns), Some(seed), Some(out)) if adjoint => {
                adjoint_of(inst, unknowns, knowns, seed, out)
            }
            // fmi3GetDirectionalDerivative: sensitivity = J seed, exact (dual numbers); in
            // Initialization Mode the InitialUnknowns' over the knowns of that mode
            // (`core::initial_derivatives`).
            (Some(unknowns), Some(knowns), Some(seed), Some(out)) => {
                let mut got = vec![0.0; out.len()];
                let status = inst.directional_derivative(unknowns, knowns, seed, &mut got);
                if status == fmi3OK {
                    out.copy_from_slice(&got);
                }
                status
            }
            _ => inst.error(&format!(
                "{function}: unknowns, knowns, seed or sensitivity is NULL (nUnknowns = {n_unknowns}, nKnowns = {n_knowns})"
            )),
        }
    })
}

/// fmi3GetAdjointDerivative: sensitivity = Jᵀ seed, J = d unknowns / d knowns, exact: each
/// column of J from one run of the equations on dual numbers (one per known); in
/// Initialization Mode each column as fmi3GetDirectionalDerivative gives it there.
fn adjoint_of<M: CoSimulation>(
    inst: &mut Instance<M>,
    unknowns: &[u32],
    knowns: &[u32],
    seed: &[f64],
    out: &mut [f64],
) -> fmi3Status {
    const F: &str = "fmi3GetAdjointDerivative";
    if let Some((i, s)) = seed.iter().enumerate().find(|(_, s)| !s.is_finite()) {
        return inst.error(&format!("{F}: seed[{i}] = {s} is not finite"));
    }
    // Element counts (an array counts each element): `get_derivative` checked them.
    let mut result = vec![0.0; out.len()];
    let mut unit = vec![0.0; out.len()];
    let mut column = vec![0.0; seed.len()];
    // Checks the references even when there is no known (no column is computed then).
    if knowns.is_empty() {
        let status = inst.directional_derivative(unknowns, knowns, &[], &mut column);
        if status != fmi3OK {
            return status;
        }
    }
    for j in 0..unit.len() {
        unit.fill(0.0);
        unit[j] = 1.0;
        let status = inst.directional_derivative(unknowns, knowns, &unit, &mut column);
        if status != fmi3OK {
            return status;
        }
        result[j] = column.iter().zip(seed).map(|(d, s)| d * s).sum();
    }
    out.copy_from_slice(&result);
    fmi3OK
}
