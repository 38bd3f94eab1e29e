//! Directional derivatives in Initialization Mode: those of the InitialUnknowns with respect to
//! the knowns of that mode (FMI 2.0 section 2.1.9, FMI 3.0 section 2.2.11 "Getting Partial
//! Derivatives"). FMI 2.0 (2.1.9): `v_unknown` is, in Initialization Mode, the "unknowns listed
//! under `<ModelStructure><InitialUnknowns>` that have type Real", `v_known` the "Real input
//! variables of function h that changes its value in the actual Mode", and the function
//! computes Δv_unknown = (∂h/∂v_known) Δv_known. FMI 3.0: in Initialization Mode "the exposed
//! unknowns listed as elements `<InitialUnknown>` in `<ModelStructure>` that have a floating
//! point type", and `v_known` "the vector of arguments of function f that could appear in
//! `dependencies` ... in `<ModelStructure>` of the unknown variables": the inputs and the
//! variables with initial = exact (parameters, states' start values), as `initial_depends`
//! declares them.
//!
//! h here is the model's `initialize` followed by its equations. The equations run on dual
//! numbers, `initialize` and the parameters on `f64` (the model contract): a known that only the
//! equations read (an input or a state's start value that `initialize` leaves alone, found by
//! moving it and comparing what `initialize` makes of the model) gets its column exactly, by
//! dual numbers; any other (a parameter, a known `initialize` reads) by central differences of
//! the whole initialization extrapolated to step 0 (Ridders): a start value copied into a state
//! gets exactly 1, other relations their derivative to the rounding of the differences (about
//! 1e-11 relative where the unknown is large beside its change, 1e-14 otherwise: measured in
//! tests/initial_unknowns_derivatives.rs). Not exact in the dual numbers' sense: that needs
//! `initialize` and the parameters on dual numbers, which the model contract does not ask.

use super::instance::Instance;
use super::{OK, Status, Version};
use crate::description::{Causality, Initial, VarType, Variability, Variable};
use crate::model::{CoSimulation, Context};
use crate::step::{evaluate, non_finite};
use crate::value::Value;
use num_dual::Dual64;

/// One element of a variable: its value reference, declaration and storage index.
type Element = (u32, &'static Variable, usize);

impl<M: CoSimulation> Instance<M> {
    /// Whether `decl` is a known of Initialization Mode: a Float64 input, or a Float64 variable
    /// with initial = exact (a parameter, a state's or output's start value) that is not a
    /// constant; what `initial_depends` may name.
    pub(super) fn is_initial_known(decl: &Variable) -> bool {
        decl.var_type == VarType::Real
            && decl.variability != Variability::Constant
            && decl.causality != Causality::Independent
            && !decl.is_clocked()
            && (decl.causality == Causality::Input || decl.effective_initial() == Some(Initial::Exact))
    }

    /// FMI 2.0's element `vr` of an array (a calculated parameter `K[1,2]`: FMI 2.0 has no
    /// arrays), in Initialization Mode: the array's declaration and the element.
    fn fmi2_element(&self, vr: u32) -> Option<(&'static Variable, usize)> {
        if self.version != Version::Fmi2 || !const { M::DESCRIPTION.has_fmi2_arrays() } {
            return None;
        }
        let (i, k) = M::DESCRIPTION.fmi2_element(vr)?;
        Some((&M::DESCRIPTION.variables[i], k))
    }

    /// The Float64 variable `vr` names for a derivative and the number of values it has in the
    /// seed or sensitivity (an array's elements; in Initialization Mode of FMI 2.0 also an
    /// element of an array, one value).
    pub(super) fn derivative_declaration(&self, vr: u32, initialization: bool) -> Option<(&'static Variable, usize)> {
        if initialization && let Some((decl, _)) = self.fmi2_element(vr) {
            return (decl.var_type == VarType::Real).then_some((decl, 1));
        }
        let decl = M::declaration(vr, VarType::Real)?;
        Some((decl, crate::step::structural::element_count(&self.sim.model, decl)))
    }

    /// The elements (value reference, declaration, storage index) of `vrs`, in the order of the
    /// seed and sensitivity arrays.
    fn elements_of(&self, vrs: &[u32]) -> Vec<Element> {
        let model = &self.sim.model;
        let mut out = Vec::new();
        for vr in vrs {
            if let Some((decl, k)) = self.fmi2_element(*vr) {
                let k = crate::step::structural::storage_index(model, decl, k);
                out.push((decl.value_reference, decl, k));
            } else if let Some(decl) = M::declaration(*vr, VarType::Real) {
                for i in 0..crate::step::structural::element_count(model, decl) {
                    out.push((*vr, decl, crate::step::structural::storage_index(model, decl, i)));
                }
            }
        }
        out
    }

    /// dv_unknown = (d unknowns / d knowns) dv_known in Initialization Mode, after the caller
    /// checked the references and the seed and brought the initialization up to date. A known
    /// that is not one of Initialization Mode (a calculated state in model exchange) keeps the
    /// meaning it has elsewhere: the partial derivative of the equations at the current values.
    pub(super) fn initial_directional_derivative(
        &self,
        f: &str,
        unknowns: &[u32],
        knowns: &[u32],
        dv_known: &[f64],
        dv_unknown: &mut [f64],
    ) -> Status {
        let unknown_elements = self.elements_of(unknowns);
        let model = &self.sim.model;
        let mut total = vec![0.0; unknown_elements.len()];
        let mut dual = model.continuous::<Dual64>();
        let mut any_dual = false;
        for ((vr, decl, k), dv) in self.elements_of(knowns).into_iter().zip(dv_known) {
            if *dv == 0.0 {
                continue;
            }
            let exact = !Self::is_initial_known(decl) || self.initialize_ignores(vr, decl, k);
            if exact && let Some(slot) = M::continuous_element(&mut dual, vr, k) {
                slot.eps += *dv;
                any_dual = true;
                continue;
            }
            let column = match self.initial_column(vr, decl, k, &unknown_elements) {
                Ok(column) => column,
                Err(message) => {
                    return self.error(&format!(
                        "{f}: the derivative with respect to '{}' (vr {vr}) in Initialization Mode: {message}",
                        decl.name
                    ));
                }
            };
            for (sum, d) in total.iter_mut().zip(column) {
                *sum += dv * d;
            }
        }
        if any_dual {
            let t = Dual64::from(self.sim.start_time);
            model.derivatives(t, &mut dual);
            model.outputs(t, &mut dual);
            for (sum, (vr, _, k)) in total.iter_mut().zip(&unknown_elements) {
                *sum += M::continuous_element(&mut dual, *vr, *k).map_or(0.0, |d| d.eps);
            }
        }
        for ((vr, decl, _), d) in unknown_elements.iter().zip(&total) {
            if !d.is_finite() {
                return self.error(&format!(
                    "{f}: the derivative of '{}' (vr {vr}) in Initialization Mode is {d}",
                    decl.name
                ));
            }
        }
        for (slot, d) in dv_unknown.iter_mut().zip(total) {
            *slot = d;
        }
        OK
    }

    /// The context `initialize` runs in here: the instance's, without the logger (the
    /// initializations of the differences would repeat its messages).
    fn quiet_context(&self) -> Context<'_> {
        Context::outside_step(
            self.sim.start_time,
            self.sim.tolerance,
            None,
            self.resources.as_deref(),
            self.model_exchange,
        )
    }

    /// Whether the model's `initialize` leaves everything as it is when element `k` of the
    /// known `vr` moves (the equations read it directly, so dual numbers give its column): the
    /// model after `initialize` is compared byte for byte with the known moved and put back.
    fn initialize_ignores(&self, vr: u32, decl: &'static Variable, k: usize) -> bool {
        if !M::is_known(vr) {
            return false;
        }
        let ctx = self.quiet_context();
        let Ok(x) = read(&self.sim.model, vr, decl, k) else {
            return false;
        };
        let mut same = self.sim.model.clone();
        let mut moved = self.sim.model.clone();
        let initialized = same.initialize(&ctx).is_ok()
            && write(&mut moved, vr, decl, k, x + step(x, decl)).is_ok()
            && moved.initialize(&ctx).is_ok()
            && write(&mut moved, vr, decl, k, x).is_ok();
        match (initialized, postcard::to_allocvec(&same), postcard::to_allocvec(&moved)) {
            (true, Ok(a), Ok(b)) => a == b,
            _ => false,
        }
    }

    /// The unknowns' values after the initialization with element `k` of `vr` at `x`: the
    /// instance's model (already initialized: `initialize` derives the calculated values from
    /// the exact ones again, as fmi2ExitInitializationMode does) with the known moved, then
    /// `initialize` and the equations.
    fn initial_values(
        &self,
        vr: u32,
        decl: &'static Variable,
        k: usize,
        x: f64,
        unknowns: &[Element],
    ) -> Result<Vec<f64>, String> {
        let mut model = self.sim.model.clone();
        write(&mut model, vr, decl, k, x)?;
        model
            .initialize(&self.quiet_context())
            .map_err(|e| format!("with '{}' = {x} the initialization fails: {e}", decl.name))?;
        evaluate(&mut model, self.sim.start_time);
        if let Some(what) = non_finite(&model) {
            return Err(format!("with '{}' = {x}: {what}", decl.name));
        }
        unknowns.iter().map(|(u, d, i)| read(&model, *u, d, *i)).collect()
    }

    /// The column of element `k` of the known `vr`: d unknown / d known for every unknown
    /// element, by Ridders' extrapolation of central differences of the initialization. An
    /// unknown that `initial_depends` declares independent of the known gets an exact 0 (the
    /// declarations are checked when the FMU is built).
    fn initial_column(
        &self,
        vr: u32,
        decl: &'static Variable,
        k: usize,
        unknowns: &[Element],
    ) -> Result<Vec<f64>, String> {
        let x = read(&self.sim.model, vr, decl, k)?;
        let mut column: Option<(Vec<f64>, Vec<f64>)> = None;
        // A first step that crosses a kink (a limit the unknown reaches near x) leaves an
        // extrapolation whose error estimate is large: the components not yet within 1e-9 of
        // their size are taken again from steps 2^6 and 2^12 times smaller, keeping the
        // estimate with the smaller error.
        for shrink in [1.0, 2f64.powi(-6), 2f64.powi(-12)] {
            let (best, error) = self.differences(vr, decl, k, x, step(x, decl) * shrink, unknowns)?;
            let merged = column.get_or_insert_with(|| (best.clone(), error.clone()));
            for c in 0..best.len() {
                if error[c] < merged.1[c] {
                    (merged.0[c], merged.1[c]) = (best[c], error[c]);
                }
            }
            if merged.0.iter().zip(&merged.1).all(|(d, e)| *e <= 1e-9 * d.abs()) {
                break;
            }
        }
        let mut column = column.map(|(best, _)| best).unwrap_or_default();
        for (d, (u, udecl, _)) in column.iter_mut().zip(unknowns) {
            let declared = M::DESCRIPTION
                .is_initial_unknown(udecl)
                .then(|| M::DESCRIPTION.dependencies(*u, true, u32::MAX))
                .flatten();
            if declared.is_some_and(|deps| !deps.contains(&vr)) && *u != vr {
                *d = 0.0;
            }
        }
        Ok(column)
    }

    /// Ridders' extrapolation for element `k` of `vr` at `x` from the first step `h`: central
    /// differences where the declared bounds leave room on both sides, else one-sided ones; and
    /// one-sided ones too where the initialization refuses one side (a parameter at the edge of
    /// what the model's own check accepts). The estimates and their errors.
    fn differences(
        &self,
        vr: u32,
        decl: &'static Variable,
        k: usize,
        x: f64,
        h: f64,
        unknowns: &[Element],
    ) -> Result<(Vec<f64>, Vec<f64>), String> {
        let below = decl.min.is_none_or(|b| b.admits_above(x - h));
        let above = decl.max.is_none_or(|b| b.admits_below(x + h));
        let sides = match (below, above) {
            (true, true) => &[Side::Both, Side::Above, Side::Below][..],
            (false, true) => &[Side::Above],
            (true, false) => &[Side::Below],
            (false, false) => &[Side::Both],
        };
        let mut first_error = None;
        for side in sides {
            match ridders(|x| self.initial_values(vr, decl, k, x, unknowns), x, h, *side) {
                Ok(found) => return Ok(found),
                Err(e) => {
                    first_error.get_or_insert(e);
                }
            }
        }
        Err(first_error.unwrap_or_default())
    }
}

/// The first step of the differences for a known at `x`: 2^-5 of its size (of its nominal, or
/// 1, at 0), a power of two times it so that x ± h is as close to exact as it can be.
fn step(x: f64, decl: &Variable) -> f64 {
    let size = if x != 0.0 {
        x.abs()
    } else {
        decl.nominal.map_or(1.0, f64::abs)
    };
    size * 2f64.powi(-5)
}

/// Element `k` of `vr` in `model`, a Float64.
fn read<M: CoSimulation>(model: &M, vr: u32, decl: &Variable, k: usize) -> Result<f64, String> {
    let value = if decl.is_array() {
        model.get_element(vr, k)
    } else {
        model.get(vr)
    };
    match value {
        Some(Value::Real(x)) => Ok(x),
        _ => Err(format!("'{}' (vr {vr}) has no Float64 value at element {k}", decl.name)),
    }
}

/// Stores `x` as element `k` of `vr` in `model` (no check: a copy of the instance's model).
fn write<M: CoSimulation>(model: &mut M, vr: u32, decl: &Variable, k: usize, x: f64) -> Result<(), String> {
    let stored = if decl.is_array() {
        model.set_element(vr, k, Value::Real(x))
    } else {
        model.set(vr, Value::Real(x))
    };
    if stored {
        Ok(())
    } else {
        Err(format!("'{}' (vr {vr}) cannot be moved to {x}", decl.name))
    }
}

/// Which points the differences take: x ± h, or x and x + h, or x - h and x.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Side {
    Both,
    Above,
    Below,
}

/// d g / dx at `x` for each component of `g` (Ridders' method, Numerical Recipes' `dfridr`):
/// differences at steps h, h/1.4, h/1.4², ... extrapolated to step 0 in a Neville tableau (in
/// powers of h² for central differences, of h for one-sided ones), each component stopping
/// where its error estimate stops improving (estimates and their errors). Each difference
/// divides by the distance of its two points as they are in f64 ((x + h) - (x - h), exact), so
/// a copy of x gives exactly 1 and a relation linear in x its slope to rounding.
fn ridders<G>(mut g: G, x: f64, h: f64, side: Side) -> Result<(Vec<f64>, Vec<f64>), String>
where
    G: FnMut(f64) -> Result<Vec<f64>, String>,
{
    const SHRINK: f64 = 1.4;
    const LEVELS: usize = 10;
    const SAFE: f64 = 2.0;
    let ratio = if side == Side::Both { SHRINK * SHRINK } else { SHRINK };
    let at_x = if side == Side::Both { None } else { Some(g(x)?) };
    let mut table: Vec<[[f64; LEVELS]; LEVELS]> = Vec::new();
    let mut best: Vec<f64> = Vec::new();
    let mut error: Vec<f64> = Vec::new();
    let mut done: Vec<bool> = Vec::new();
    let mut hh = h;
    for i in 0..LEVELS {
        let (xp, xm) = match side {
            Side::Both => (x + hh, x - hh),
            Side::Above => (x + hh, x),
            Side::Below => (x, x - hh),
        };
        let fp = if xp == x { at_x.clone() } else { None }.map_or_else(|| g(xp), Ok)?;
        let fm = if xm == x { at_x.clone() } else { None }.map_or_else(|| g(xm), Ok)?;
        if i == 0 {
            table = vec![[[0.0; LEVELS]; LEVELS]; fp.len()];
            best = vec![0.0; fp.len()];
            error = vec![f64::INFINITY; fp.len()];
            done = vec![false; fp.len()];
        }
        for c in 0..fp.len() {
            if done[c] {
                continue;
            }
            let a = &mut table[c];
            a[0][i] = (fp[c] - fm[c]) / (xp - xm);
            if i == 0 {
                best[c] = a[0][0];
                continue;
            }
            let mut factor = ratio;
            for j in 1..=i {
                a[j][i] = (a[j - 1][i] * factor - a[j - 1][i - 1]) / (factor - 1.0);
                factor *= ratio;
                let e = (a[j][i] - a[j - 1][i]).abs().max((a[j][i] - a[j - 1][i - 1]).abs());
                if e <= error[c] {
                    error[c] = e;
                    best[c] = a[j][i];
                }
            }
            if (a[i][i] - a[i - 1][i - 1]).abs() >= SAFE * error[c] {
                done[c] = true;
            }
        }
        if done.iter().all(|d| *d) {
            break;
        }
        hh /= SHRINK;
    }
    Ok((best, error))
}

#[cfg(test)]
mod tests {
    use super::{Side, ridders};

    fn g(x: f64) -> Result<Vec<f64>, String> {
        Ok(vec![x, 3.0 * x - 1.0, x.exp(), (2.0 * x).sin()])
    }

    #[test]
    fn ridders_gives_a_copys_slope_exactly_and_smooth_ones_to_rounding() {
        for side in [Side::Both, Side::Above, Side::Below] {
            let (d, _) = ridders(g, 0.7, 0.7 / 128.0, side).unwrap();
            assert_eq!(d[0], 1.0, "{side:?}");
            assert!((d[1] - 3.0).abs() <= 3e-13, "{side:?}: {}", d[1]);
            let (exp, cos) = (0.7f64.exp(), 2.0 * 1.4f64.cos());
            assert!((d[2] - exp).abs() < 1e-11 * exp, "{side:?}: {} for {exp}", d[2]);
            assert!((d[3] - cos).abs() < 1e-11, "{side:?}: {} for {cos}", d[3]);
        }
    }
}
