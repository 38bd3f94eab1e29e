//! Derivatives the importer asks for: of outputs with respect to time (FMI 2.0's
//! fmi2GetRealOutputDerivatives) and directional derivatives, exact from the same equations
//! run on dual numbers.

use super::Instance;
use crate::core::machine::State;
use crate::core::{Function, OK, Status};
use crate::description::{Causality, VarType, Variability};
use crate::model::{CoSimulation, StateVector};

impl<M: CoSimulation> Instance<M> {
    /// The first time derivatives of Real outputs at the instance's time
    /// (fmi2GetRealOutputDerivatives, fmi3GetOutputDerivatives; maxOutputDerivativeOrder = 1):
    /// exact, from the model's equations in dual numbers, with time moving at rate 1, each
    /// continuous state at its derivative, and the inputs held (canInterpolateInputs = false:
    /// they are constant over a step). A discrete output's derivative is 0 (it changes at
    /// events only). All references are checked before anything is computed.
    pub fn output_derivatives(&mut self, function: &str, vrs: &[u32], orders: &[i32], out: &mut [f64]) -> Status {
        use num_dual::Dual64;
        let mut probe = self.sim.model.continuous::<f64>();
        for (vr, order) in vrs.iter().zip(orders) {
            let decl = match self.lookup(function, *vr, VarType::Real) {
                Ok(d) => d,
                Err(status) => return status,
            };
            if decl.causality != Causality::Output {
                return self.error(&format!(
                    "{function}: '{}' (vr {vr}) is a {:?}, not an output: output derivatives are those of outputs",
                    decl.name, decl.causality
                ));
            }
            if *order != 1 {
                return self.error(&format!(
                    "{function}: order {order} for '{}' (vr {vr}): this FMU gives first derivatives only (maxOutputDerivativeOrder = 1)",
                    decl.name
                ));
            }
            let held = decl.variability == Variability::Discrete;
            if !held && M::continuous_slot(&mut probe, *vr).is_none() {
                return self.error(&format!(
                    "{function}: '{}' (vr {vr}) is computed outside the equations (Model::calculate): it has no derivative",
                    decl.name
                ));
            }
        }
        if let Err(status) = self.up_to_date(function) {
            return status;
        }
        let t = self.sim.time;
        let mut c = self.sim.model.continuous::<f64>();
        self.sim.model.derivatives(t, &mut c);
        let x_dot = M::derivatives_of(&c);
        let mut d = self.sim.model.continuous::<Dual64>();
        for ((vr, k), rate) in M::STATES.iter().zip(M::STATE_ELEMENTS).zip(x_dot.as_slice()) {
            if let Some(slot) = M::continuous_element(&mut d, *vr, *k as usize) {
                slot.eps = *rate;
            }
        }
        let t = Dual64::new(t, 1.0);
        self.sim.model.derivatives(t, &mut d);
        self.sim.model.outputs(t, &mut d);
        for (vr, slot) in vrs.iter().zip(out.iter_mut()) {
            let rate = M::continuous_slot(&mut d, *vr).map_or(0.0, |x| x.eps);
            if !rate.is_finite() {
                let name = M::declaration(*vr, VarType::Real).map_or("?", |v| v.name);
                return self.not_finite(
                    function,
                    &format!("the time derivative of '{name}' (vr {vr}) is {rate}"),
                );
            }
            *slot = rate;
        }
        OK
    }

    /// fmi2GetDirectionalDerivative: dv_unknown = (d unknowns / d knowns) dv_known, exact, by
    /// running the equations once on dual numbers seeded with dv_known. Knowns: the
    /// continuous states (model exchange) and the Real inputs; unknowns: what the equations
    /// compute (derivatives, outputs, locals), or a known itself. In Initialization Mode also
    /// the InitialUnknowns with respect to the knowns of that mode (inputs, parameters and
    /// start values with initial = exact: `super::initial_derivatives`). An array (FMI 3.0)
    /// counts each of its elements: `dv_known` holds one value per element of the knowns,
    /// row-major, `dv_unknown` one per element of the unknowns (the counting of FMI 3.0's nSeed
    /// and nSensitivity; a sized array's elements within its lengths now).
    pub fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        dv_known: &[f64],
        dv_unknown: &mut [f64],
    ) -> Status {
        let f = self.terms.name(Function::GetDirectionalDerivative);
        use num_dual::Dual64;
        let mut probe = self.sim.model.continuous::<f64>();
        let initialization = self.sim.state == State::InitializationMode;
        let mut at = 0;
        for vr in knowns {
            let Some((decl, n)) = self.derivative_declaration(*vr, initialization) else {
                return self.error(&format!(
                    "{f}: known value reference {vr} is not a Real variable of {}",
                    M::DESCRIPTION.model_identifier
                ));
            };
            let is_state = M::STATES.contains(vr);
            let allowed = decl.causality == Causality::Input && decl.variability == Variability::Continuous
                || (is_state && self.model_exchange);
            let allowed = allowed && M::continuous_element(&mut probe, *vr, 0).is_some()
                || initialization && Self::is_initial_known(decl);
            if !allowed {
                return self.error(&format!(
                    "{f}: '{}' (vr {vr}) is not a known of the equations in {}: the knowns are the continuous Real inputs{}{}",
                    decl.name,
                    if self.model_exchange { "model exchange" } else { "co-simulation" },
                    if self.model_exchange { " and the continuous states" } else { "" },
                    if initialization {
                        ", and in Initialization Mode the Real inputs and the Real variables with initial = exact \
                         (parameters, start values) the InitialUnknowns depend on"
                    } else {
                        ""
                    }
                ));
            }
            for (i, dv) in dv_known.iter().skip(at).take(n).enumerate() {
                if !dv.is_finite() {
                    let what = if decl.is_array() {
                        format!(" element {i}")
                    } else {
                        String::new()
                    };
                    return self.error(&format!(
                        "{f}: dvKnown for '{}'{what} (vr {vr}) = {dv} is not finite",
                        decl.name
                    ));
                }
            }
            at += n;
        }
        for vr in unknowns {
            let Some((decl, _)) = self.derivative_declaration(*vr, initialization) else {
                return self.error(&format!(
                    "{f}: unknown value reference {vr} is not a Real variable of {}",
                    M::DESCRIPTION.model_identifier
                ));
            };
            // A discrete output is held between events: its derivative with respect to the
            // continuous knowns is 0 (answered below: it has no slot in the equations).
            let held = decl.causality == Causality::Output && decl.variability == Variability::Discrete;
            let initial_unknown = initialization && M::DESCRIPTION.is_initial_unknown(decl);
            if !held && !initial_unknown && M::continuous_element(&mut probe, *vr, 0).is_none() {
                return self.error(&format!(
                    "{f}: '{}' (vr {vr}) is not computed by the equations (a parameter, or not continuous){}: no derivative",
                    decl.name,
                    if initialization { " nor an InitialUnknown" } else { "" }
                ));
            }
        }
        if initialization {
            // The initialization brought up to date for the derivatives is taken back with a
            // refusal: an fmi2Error leaves the FMU state as it was (a getter would bring it up
            // to date again). Found by the conformance suite's random model-exchange sequences
            // (seed 6646168119972039503: L = 6.7e-310, then d der(i) = -inf refused, and the
            // serialized state had changed).
            let before = self.sim.init_dirty.then(|| {
                (
                    self.sim.model.clone(),
                    self.sim.stale_derivatives,
                    self.sim.stale_outputs,
                )
            });
            if let Err(status) = self.initialize_model(f, false) {
                return status;
            }
            let status = self.initial_directional_derivative(f, unknowns, knowns, dv_known, dv_unknown);
            if status != OK
                && let Some((model, stale_derivatives, stale_outputs)) = before
            {
                self.sim.model = model;
                self.sim.init_dirty = true;
                self.sim.stale_derivatives = stale_derivatives;
                self.sim.stale_outputs = stale_outputs;
            }
            return status;
        }
        let model = &self.sim.model;
        let elements = |vr: u32| {
            let decl = M::variable_index(vr).map(|i| &M::DESCRIPTION.variables[i]);
            let n = decl.map_or(1, |d| crate::step::structural::element_count(model, d));
            (0..n).map(move |i| decl.map_or(i, |d| crate::step::structural::storage_index(model, d, i)))
        };
        let mut c = model.continuous::<Dual64>();
        let mut seed = dv_known.iter();
        for vr in knowns {
            for k in elements(*vr) {
                let dv = seed.next().copied().unwrap_or(0.0);
                if let Some(slot) = M::continuous_element(&mut c, *vr, k) {
                    slot.eps += dv;
                }
            }
        }
        let t = Dual64::from(self.sim.time);
        model.derivatives(t, &mut c);
        model.outputs(t, &mut c);
        let mut out = dv_unknown.iter_mut();
        for vr in unknowns {
            for k in elements(*vr) {
                let d = M::continuous_element(&mut c, *vr, k).map_or(0.0, |d| d.eps);
                if !d.is_finite() {
                    let name = M::declaration(*vr, VarType::Real).map_or("?", |v| v.name);
                    return self.not_finite(f, &format!("the derivative of '{name}' (vr {vr}) is {d}"));
                }
                if let Some(slot) = out.next() {
                    *slot = d;
                }
            }
        }
        OK
    }
}
