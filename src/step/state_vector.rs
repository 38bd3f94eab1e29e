//! The state vector `[f64; N]` on the runtime's integrator: [`StateVector::integrate`] and
//! [`StateVector::integrate_until`] hand the model's right-hand side to [`Dopri5`] as nalgebra
//! vectors and show each accepted step as a [`StepView`].

use crate::model::{StateVector, StepView};
use crate::solver::{Dopri5, Tolerances};

impl<const N: usize> StateVector for [f64; N] {
    const LEN: usize = N;
    #[inline]
    fn as_slice(&self) -> &[f64] {
        self
    }
    #[inline]
    fn as_mut_slice(&mut self) -> &mut [f64] {
        self
    }
    #[inline]
    fn zeros() -> Self {
        [0.0; N]
    }
    #[inline]
    fn integrate<F: FnMut(f64, &Self) -> Self>(
        solver: &mut Dopri5,
        mut f: F,
        t0: f64,
        span: f64,
        x: &mut Self,
        tol: Tolerances,
    ) -> Result<(), crate::solver::OdeError> {
        let mut v = nalgebra::SVector::<f64, N>::from(*x);
        let result = solver.integrate(
            // Inlined into each stage of the integrator, as `f` is where `Context::integrate`
            // passes it (src/step/integrate.rs says what the call cost).
            #[inline(always)]
            |t, v: &nalgebra::SVector<f64, N>| nalgebra::SVector::from(f(t, &(*v).into())),
            t0,
            span,
            &mut v,
            tol,
        );
        *x = v.into();
        result
    }
    #[inline]
    fn integrate_until<F: FnMut(f64, &Self) -> Self, S: FnMut(&StepView<'_, Self>) -> Option<(f64, Self)>>(
        solver: &mut Dopri5,
        mut f: F,
        mut stop: S,
        t0: f64,
        span: f64,
        x: &mut Self,
        tol: Tolerances,
    ) -> Result<Option<f64>, crate::solver::OdeError> {
        let mut v = nalgebra::SVector::<f64, N>::from(*x);
        let result = solver.integrate_until(
            |t, v: &nalgebra::SVector<f64, N>| nalgebra::SVector::from(f(t, &(*v).into())),
            t0,
            span,
            &mut v,
            tol,
            |step: &crate::solver::DenseStep<'_, N>| {
                let dense = |s: f64| -> [f64; N] { step.at(s).into() };
                stop(&StepView {
                    t0: step.t0,
                    s0: step.s0,
                    h: step.h,
                    end: (*step.end()).into(),
                    dense: &dense,
                })
                .map(|(s, x)| (s, nalgebra::SVector::from(x)))
            },
        );
        *x = v.into();
        result
    }
}
