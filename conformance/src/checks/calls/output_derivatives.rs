//! Output derivatives against finite differences of the outputs, for both FMI versions
//! ([`compare_output_derivatives`]).

#![allow(non_upper_case_globals)] // fmi2OK etc. are the standard's names, matched on

use crate::fmi2::*;
use crate::instance::{Instance, excitation, step_size};
use crate::outcome::{info, skip_not_declared};
use crate::{Fmu, Type};
use md_reader::{Causality, Variability};

/// How far a declared output derivative may be from the finite differences of the output: the
/// second-order one-sided difference (4 y(t+d) - y(t+2d) - 3 y(t)) / 2d, whose error is of order
/// d^2, against the derivative, relative to their size; where the first-order differences over d
/// and 2d disagree by more than a tenth (an event, a kink) the point says nothing and is skipped.
/// `None`: agrees or skipped (the bool says skipped); `Some(message)`: disagrees.
pub(crate) fn output_derivative_disagrees(y: [f64; 3], d: f64, dy: f64) -> (bool, Option<String>) {
    let (fd1, fd2) = ((y[1] - y[0]) / d, (y[2] - y[0]) / (2.0 * d));
    if (fd1 - fd2).abs() > 0.1 * fd1.abs().max(fd2.abs()) + 1e-9 {
        return (true, None);
    }
    let estimate = (4.0 * y[1] - y[2] - 3.0 * y[0]) / (2.0 * d);
    // Relative 1e-3, and what an integrator's round-off of 1e-8 in the output makes of a
    // difference over d.
    let tolerance = 1e-3 * dy.abs().max(estimate.abs()) + 1e-8 * y[0].abs().max(1.0) / d;
    if (estimate - dy).abs() <= tolerance {
        (false, None)
    } else {
        (
            false,
            Some(format!(
                "derivative {dy}, finite differences {estimate} (first order {fd1}, {fd2})"
            )),
        )
    }
}

/// fmi2GetRealOutputDerivatives with `maxOutputDerivativeOrder` >= 1: at three communication
/// points the first derivative of every continuous Real output agrees with the output's finite
/// differences over the next two steps of d = a tenth of the step size (inputs held, as the FMU
/// holds them);
/// order 0 and orders beyond `maxOutputDerivativeOrder` are refused.
pub fn output_derivatives_agree_with_finite_differences_of_the_outputs(fmu: &Fmu) {
    let order = fmu.md.cs.as_ref().map_or(0, |cs| cs.max_output_derivative_order);
    if order == 0 {
        skip_not_declared("maxOutputDerivativeOrder >= 1");
    }
    let outputs: Vec<u32> = fmu
        .md
        .of_type(Type::Real)
        .filter(|v| v.causality == Causality::Output && v.variability == Variability::Continuous)
        .map(|v| v.vr)
        .collect();
    if outputs.is_empty() {
        skip_not_declared("a continuous Real output");
    }
    let mut inst = Instance::new(fmu);
    let (vrs, vals): (Vec<u32>, Vec<f64>) = excitation(fmu).into_iter().unzip();
    assert_eq!(inst.set_real(&vrs, &vals), fmi2OK);
    inst.initialize();
    compare_output_derivatives(&mut inst, &fmu.id, &outputs, step_size(fmu), order);
}

/// An instance whose output derivatives [`compare_output_derivatives`] checks (FMI 2.0 and
/// 3.0 alike).
pub(crate) trait OutputDerivatives {
    fn now(&self) -> f64;
    /// A step of `h` that must succeed (the message says where it did not).
    fn step_ok(&mut self, h: f64);
    fn outputs(&mut self, vrs: &[u32]) -> Vec<f64>;
    /// The output derivatives of `orders`; `Err(message)` where the FMU refused.
    fn output_derivatives(&mut self, vrs: &[u32], orders: &[i32]) -> Result<Vec<f64>, String>;
}

impl OutputDerivatives for Instance<'_> {
    fn now(&self) -> f64 {
        self.time
    }
    fn step_ok(&mut self, h: f64) {
        assert_eq!(self.step(h), fmi2OK, "{}: {}", self.fmu.id, self.log_text());
    }
    fn outputs(&mut self, vrs: &[u32]) -> Vec<f64> {
        let (s, v) = self.get_real(vrs);
        assert_eq!(s, fmi2OK, "{}: {}", self.fmu.id, self.log_text());
        v
    }
    fn output_derivatives(&mut self, vrs: &[u32], orders: &[i32]) -> Result<Vec<f64>, String> {
        // Through the call log (Instance::get_real_output_derivatives): a failure leaves a
        // reproducer with the call, which `cargo fmu replay` makes again.
        let (s, out) = self.get_real_output_derivatives(vrs, orders);
        if s == fmi2OK { Ok(out) } else { Err(self.log_text()) }
    }
}

/// What both versions' output-derivative checks do: at three communication points `h` apart
/// (plus the differences' own steps), the first derivative of each of `outputs` agrees with its
/// finite differences over two steps of `h / 10` ([`output_derivative_disagrees`]); order 0 and
/// orders beyond `order` are refused.
pub(crate) fn compare_output_derivatives(
    inst: &mut impl OutputDerivatives,
    id: &str,
    outputs: &[u32],
    h: f64,
    order: u32,
) {
    // The differences over a tenth of the step (their error falls with its square).
    let d = h / 10.0;
    let (mut compared, mut skipped) = (0, 0);
    for point in 0..3 {
        for _ in 0..point * 2 {
            inst.step_ok(h);
        }
        let t = inst.now();
        let dy = inst
            .output_derivatives(outputs, &vec![1; outputs.len()])
            .unwrap_or_else(|log| panic!("{id}: the output derivatives at t = {t} were refused: {log}"));
        let mut samples: Vec<Vec<f64>> = Vec::with_capacity(3);
        for k in 0..3 {
            if k > 0 {
                inst.step_ok(d);
            }
            samples.push(inst.outputs(outputs));
        }
        for (j, vr) in outputs.iter().enumerate() {
            match output_derivative_disagrees([samples[0][j], samples[1][j], samples[2][j]], d, dy[j]) {
                (true, _) => skipped += 1,
                (false, None) => compared += 1,
                (false, Some(why)) => panic!("{id}: output vr {vr} at t = {t}: {why}"),
            }
        }
    }
    for bad in [0, order as i32 + 1] {
        let answered = inst.output_derivatives(outputs, &vec![bad; outputs.len()]);
        // The reproducer's line expects a refusal (any status but OK).
        crate::calllog::standard_requires(crate::replay::Expected(0b11110));
        assert!(
            answered.is_err(),
            "{id}: output derivatives of order {bad} were answered"
        );
    }
    info(format!(
        "{compared} output derivatives agree with finite differences (step {d}); {skipped} points skipped (not smooth there)"
    ));
}
