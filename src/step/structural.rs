//! What structural parameters mean for the arrays and the state vector (FMI 3.0, 2.4.7.6):
//! UInt64 parameters that set the lengths of arrays. A sized array is stored at its capacity (the Rust array's
//! lengths, the parameter's `max` at most); what the importer sees of it is the first
//! `n` (`n × m`) elements, row-major, and of an array state the first `n` entries. The
//! continuous state vector keeps its compile-time length (every capacity): the entries outside
//! the lengths are constant zero-derivative states the importer never sees, and the integrator's
//! error norm is taken over the visible ones ([`active_mask`], [`scaled_tolerances`]).

use crate::description::{NOT_SIZED, Variable};
use crate::model::{StateVector, Variables};
use crate::solver::Tolerances;
use crate::value::Value;

/// The length of one dimension now: the structural parameter's value (at most the capacity), or
/// the fixed length.
#[inline]
fn length<M: Variables>(model: &M, sized_by: u32, capacity: u32) -> usize {
    if sized_by == NOT_SIZED {
        return capacity as usize;
    }
    match model.get(sized_by) {
        Some(Value::UInt64(n)) => n.min(capacity as u64) as usize,
        _ => capacity as usize,
    }
}

/// How many values `decl` has now: 1 for a scalar, the product of its lengths for an array
/// (a sized array's from its structural parameters' values).
#[inline]
pub fn element_count<M: Variables>(model: &M, decl: &Variable) -> usize {
    if !decl.is_sized() {
        return decl.element_count();
    }
    decl.fmi3
        .sized_by
        .iter()
        .zip(decl.fmi3.dimensions)
        .map(|(s, c)| length(model, *s, *c))
        .product()
}

/// Where element `k` (row-major over the lengths now) of `decl` is stored (row-major over the
/// capacity): of a sized `[[T; C]; R]` with lengths (r, c), element (i, j) is `i C + j`.
#[inline]
pub fn storage_index<M: Variables>(model: &M, decl: &Variable, k: usize) -> usize {
    if !decl.is_sized() || decl.fmi3.dimensions.len() < 2 {
        return k;
    }
    let cols = length(model, decl.fmi3.sized_by[1], decl.fmi3.dimensions[1]).max(1);
    (k / cols) * decl.fmi3.dimensions[1] as usize + k % cols
}

/// The number of values of `vr` (1 for a scalar or an unknown reference).
#[inline]
pub fn count_of<M: Variables>(model: &M, vr: u32) -> usize {
    M::variable_index(vr).map_or(1, |i| element_count(model, &M::DESCRIPTION.variables[i]))
}

/// Whether entry `i` of the state vector is one the importer sees: a scalar state, or an
/// element of an array state within its length now.
#[inline]
fn state_active<M: Variables>(model: &M, i: usize) -> bool {
    let decl = M::variable_index(M::STATES[i]).map(|k| &M::DESCRIPTION.variables[k]);
    match decl {
        Some(d) if d.is_sized() => (M::STATE_ELEMENTS[i] as usize) < element_count(model, d),
        _ => true,
    }
}

/// The entries of the state vector the importer sees, in order (all of them unless a
/// structural parameter sizes an array state).
pub fn active_states<M: Variables>(model: &M) -> impl Iterator<Item = usize> + '_ {
    let sized = const { M::DESCRIPTION.has_sized_arrays() };
    (0..M::STATES.len()).filter(move |i| !sized || state_active(model, *i))
}

/// The number of continuous states now (numberOfContinuousStates of FMI 3.0's
/// fmi3GetNumberOfContinuousStates).
#[inline]
pub fn number_of_states<M: Variables>(model: &M) -> usize {
    if !const { M::DESCRIPTION.has_sized_arrays() } {
        return <M::States as StateVector>::LEN;
    }
    active_states(model).count()
}

/// 1 for the entries of the state vector the importer sees, 0 for the others; `None` when all
/// are seen.
pub fn active_mask<M: Variables>(model: &M) -> Option<M::States> {
    if !const { M::DESCRIPTION.has_sized_arrays() } {
        return None;
    }
    let mut mask = <M::States as StateVector>::zeros();
    for i in active_states(model) {
        mask.as_mut_slice()[i] = 1.0;
    }
    Some(mask)
}

/// Zeroes the derivatives of the entries the mask hides: they stay as they are.
#[inline]
pub fn hide<X: StateVector>(dx: &mut X, mask: Option<&X>) {
    if let Some(mask) = mask {
        for (d, m) in dx.as_mut_slice().iter_mut().zip(mask.as_slice()) {
            if *m == 0.0 {
                *d = 0.0;
            }
        }
    }
}

/// The integrator's error norm is the root mean square over the whole state vector; with `n`
/// of its `N` entries seen, tolerances scaled by sqrt(n / N) make it the root mean square over
/// those `n` (the hidden entries' errors are 0).
pub fn scaled_tolerances<X: StateVector>(tol: Tolerances, mask: Option<&X>) -> Tolerances {
    let Some(mask) = mask else { return tol };
    let seen = mask.as_slice().iter().filter(|m| **m != 0.0).count().max(1);
    let f = (seen as f64 / X::LEN.max(1) as f64).sqrt();
    Tolerances {
        rtol: tol.rtol * f,
        atol: tol.atol * f,
    }
}
