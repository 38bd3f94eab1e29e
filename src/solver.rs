//! The integrator of the co-simulation interface: adaptive explicit Runge–Kutta,
//! Dormand–Prince 5(4) with PI step-size control (Hairer, Nørsett & Wanner, "Solving ODEs I",
//! II.4 and II.5; the DOPRI5 code). [`crate::Context::integrate`] runs a model's
//! [`crate::Model::derivatives`] with it; its memory ([`Dopri5`]) is part of the FMU state.
//!
//! Written here rather than taken from a crate because an FMU step has needs the ODE crates on
//! crates.io (ode_solvers, diffsol) do not meet together: integrate over one communication step
//! without allocating (ode_solvers pushes every step into Vecs), keep the step-size controller's
//! memory across calls so the next communication step starts with a good step, and be a plain
//! `Clone + Serialize` value so it is part of the FMU state.
//!
//! The step-size control's powers are `libm::pow`, not `f64::powf`: the C library's pow differs
//! between glibc and msvcrt, and under wine between threads (x87 precision control), and a
//! different last bit there is a different step sequence.

use nalgebra::SVector;
use serde::{Deserialize, Serialize};
use std::sync::OnceLock;

/// Relative and absolute error tolerances of the integrator, per component: each step keeps
/// err_i / (atol + rtol·|x_i|) ≤ 1 for every state x_i. A model chooses them with
/// [`crate::CoSimulation::tolerances`] (by default rtol from the importer, else 1e-6, and
/// atol = 1e-3 rtol); its documentation has an example.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Tolerances {
    /// Relative tolerance (per unit of the state's size).
    pub rtol: f64,
    /// Absolute tolerance (in the state's unit), what counts near 0.
    pub atol: f64,
}

/// Work counters, cumulative since the integrator was created or reset.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    pub rhs_evaluations: u64,
    pub accepted_steps: u64,
    pub rejected_steps: u64,
}

#[derive(Debug, Clone, PartialEq)]
pub enum OdeError {
    /// The step size fell below what time resolution allows, at time `t`.
    StepSizeTooSmall { t: f64, h: f64 },
    /// The right-hand side returned NaN or infinity at time `t`.
    NonFinite { t: f64 },
    /// More than the allowed number of steps for one call, having reached `t`.
    TooManySteps { t: f64, steps: u64 },
}

impl OdeError {
    /// The time up to which the integration succeeded.
    pub fn time(&self) -> f64 {
        match *self {
            OdeError::StepSizeTooSmall { t, .. } | OdeError::NonFinite { t } | OdeError::TooManySteps { t, .. } => t,
        }
    }
}

impl std::fmt::Display for OdeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OdeError::StepSizeTooSmall { t, h } => write!(f, "step size {h:e} s too small at t = {t} s"),
            OdeError::NonFinite { t } => write!(f, "the state became NaN or infinite at t = {t} s"),
            OdeError::TooManySteps { t, steps } => {
                write!(
                    f,
                    "gave up after {steps} internal steps at t = {t} s (communication step too long?)"
                )
            }
        }
    }
}

// Dormand–Prince 5(4) tableau.
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
// Error coefficients: 5th-order weights minus 4th-order weights.
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;

// Step-size controller (DOPRI5 defaults): safety factor, bounds of the change, PI exponents.
const SAFETY: f64 = 0.9;
const FAC_MIN: f64 = 0.2;
const FAC_MAX: f64 = 10.0;
const BETA: f64 = 0.04;
const ALPHA: f64 = 0.2 - BETA * 0.75;

/// The integrator's memory between calls: the proposed next step and the controller's error.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Dopri5 {
    /// Step size to try next; 0 until the first call chooses one.
    pub h_next: f64,
    err_old: f64,
    /// Upper bound of the step size (0: none).
    pub h_max: f64,
    /// Most internal steps allowed in one call of [`Dopri5::integrate`].
    pub max_steps: u64,
    pub stats: Stats,
}

impl Default for Dopri5 {
    fn default() -> Self {
        Dopri5 {
            h_next: 0.0,
            err_old: 1e-4,
            h_max: 0.0,
            max_steps: 100_000,
            stats: Stats::default(),
        }
    }
}

fn error_norm<const N: usize>(
    err: &SVector<f64, N>,
    x0: &SVector<f64, N>,
    x1: &SVector<f64, N>,
    tol: Tolerances,
) -> f64 {
    let mut sum = 0.0;
    for i in 0..N {
        let sc = tol.atol + tol.rtol * x0[i].abs().max(x1[i].abs());
        let r = err[i] / sc;
        sum += r * r;
    }
    (sum / N as f64).sqrt()
}

impl Dopri5 {
    /// Refuses a memory the integrator cannot run on (one restored from outside, say), naming
    /// the field.
    #[inline]
    pub fn validate(&self) -> Result<(), String> {
        // The runtime asks after every step: the common answer first, without the loops.
        let usable = |v: f64| v.is_finite() && v >= 0.0;
        if usable(self.h_next)
            && usable(self.h_max)
            && self.err_old.is_finite()
            && self.err_old > 0.0
            && self.max_steps > 0
        {
            return Ok(());
        }
        self.unusable()
    }

    #[cold]
    fn unusable(&self) -> Result<(), String> {
        for (name, v) in [("h_next", self.h_next), ("h_max", self.h_max)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("the integrator's {name} = {v} must be finite and >= 0"));
            }
        }
        if !(self.err_old.is_finite() && self.err_old > 0.0) {
            return Err(format!(
                "the integrator's error history {} must be finite and > 0",
                self.err_old
            ));
        }
        if self.max_steps == 0 {
            return Err("the integrator's max_steps must be at least 1".into());
        }
        Ok(())
    }

    /// Forgets the step-size history (after a discontinuous change of the state or of a
    /// parameter).
    pub fn restart(&mut self) {
        self.h_next = 0.0;
        self.err_old = 1e-4;
    }

    /// Hairer's starting step: from the sizes of x, f(x) and a trial Euler step.
    fn initial_step<const N: usize, F>(
        &mut self,
        f: &mut F,
        t: f64,
        x: &SVector<f64, N>,
        k1: &SVector<f64, N>,
        tol: Tolerances,
        span: f64,
    ) -> f64
    where
        F: FnMut(f64, &SVector<f64, N>) -> SVector<f64, N>,
    {
        // Scaled norms, capped at f64::MAX: with atol = 5e-324 and x = 0 they overflow, and
        // an infinite one would make the starting step 0 instead of merely tiny.
        let sc = x.map(|xi| tol.atol + tol.rtol * xi.abs());
        let scaled = |v: SVector<f64, N>| (v.component_div(&sc).norm_squared() / N as f64).sqrt().min(f64::MAX);
        let d0 = scaled(*x);
        let d1 = scaled(*k1);
        let h0 = if d0 < 1e-5 || d1 < 1e-5 { 1e-6 } else { 0.01 * d0 / d1 }.min(span);
        let x1 = x + k1 * h0;
        let k2 = f(t + h0, &x1);
        self.stats.rhs_evaluations += 1;
        let d2 = (scaled(k2 - k1) / h0).min(f64::MAX);
        let h1 = if d1.max(d2) <= 1e-15 {
            (h0 * 1e-3).max(1e-6)
        } else {
            libm::pow(0.01 / d1.max(d2), 0.2)
        };
        (100.0 * h0).min(h1).min(span)
    }

    /// Integrates `x' = f(t, x)` over `span` from `t0` in place. On error, `x` holds the state
    /// at the time the error names, which the integrator reached with full accuracy.
    ///
    /// The integrator runs on the time `s` since `t0` (from 0 to `span`); `f` is called with
    /// `t0 + s`. So the steps it takes, and the result, do not depend on where time starts: at
    /// `t0` = 1.7e9 s (a Unix time stamp) a step of 1e-6 s is as fine as at 0, and a master's
    /// rounded communication points (`t0 + n h`) do not leak into the state through `t_end - t0`.
    #[inline]
    pub fn integrate<const N: usize, F>(
        &mut self,
        f: F,
        t0: f64,
        span: f64,
        x: &mut SVector<f64, N>,
        tol: Tolerances,
    ) -> Result<(), OdeError>
    where
        F: FnMut(f64, &SVector<f64, N>) -> SVector<f64, N>,
    {
        self.integrate_until(f, t0, span, x, tol, |_: &DenseStep<'_, N>| None)
            .map(|_| ())
    }

    /// [`integrate`](Self::integrate), shown every accepted step with its continuous extension
    /// ([`DenseStep`]): when `stop` answers `Some((s, x_s))` (a local time `s` within the step,
    /// the state there), the integration ends at `s` with `x = x_s` and answers `Ok(Some(s))`;
    /// `Ok(None)` when it reached `span`. This is how the co-simulation step finds state events
    /// (`stop` looks for a sign change of the event indicators on the step and locates it).
    pub fn integrate_until<const N: usize, F, S>(
        &mut self,
        mut f: F,
        t0: f64,
        span: f64,
        x: &mut SVector<f64, N>,
        tol: Tolerances,
        mut stop: S,
    ) -> Result<Option<f64>, OdeError>
    where
        F: FnMut(f64, &SVector<f64, N>) -> SVector<f64, N>,
        S: FnMut(&DenseStep<'_, N>) -> Option<(f64, SVector<f64, N>)>,
    {
        // No state (a model of outputs and parameters only, a sampled controller): nothing to
        // integrate. Without this the error norm is 0/0 = NaN and every step was rejected as
        // "the state became NaN or infinite" (issue 23).
        if N == 0 {
            return Ok(None);
        }
        let mut s = 0.0;
        let mut k1 = f(t0, x);
        self.stats.rhs_evaluations += 1;
        if !k1.iter().all(|v| v.is_finite()) {
            return Err(OdeError::NonFinite { t: t0 });
        }
        if self.h_next <= 0.0 {
            self.h_next = self.initial_step(&mut f, t0, x, &k1, tol, span);
        }
        let mut steps = 0u64;
        let mut reject = false;
        while s < span {
            if steps >= self.max_steps {
                return Err(OdeError::TooManySteps { t: t0 + s, steps });
            }
            steps += 1;
            let mut h_proposed = self.h_next;
            if self.h_max > 0.0 {
                h_proposed = h_proposed.min(self.h_max);
            }
            // Land exactly on span; a step that would end within a hair of it is stretched.
            let remaining = span - s;
            let last = h_proposed >= remaining * (1.0 - 1e-12);
            let h = if last { remaining } else { h_proposed };
            if too_small(h, s) {
                return Err(OdeError::StepSizeTooSmall { t: t0 + s, h });
            }
            let t = t0 + s;

            let x2 = *x + h * (A21 * k1);
            let k2 = f(t + C2 * h, &x2);
            let x3 = *x + h * (A31 * k1 + A32 * k2);
            let k3 = f(t + C3 * h, &x3);
            let x4 = *x + h * (A41 * k1 + A42 * k2 + A43 * k3);
            let k4 = f(t + C4 * h, &x4);
            let x5 = *x + h * (A51 * k1 + A52 * k2 + A53 * k3 + A54 * k4);
            let k5 = f(t + C5 * h, &x5);
            let x6 = *x + h * (A61 * k1 + A62 * k2 + A63 * k3 + A64 * k4 + A65 * k5);
            let k6 = f(t + h, &x6);
            let x_new = *x + h * (A71 * k1 + A73 * k3 + A74 * k4 + A75 * k5 + A76 * k6);
            let k7 = f(t + h, &x_new);
            self.stats.rhs_evaluations += 6;
            let err_vec = h * (E1 * k1 + E3 * k3 + E4 * k4 + E5 * k5 + E6 * k6 + E7 * k7);
            let err = error_norm(&err_vec, x, &x_new, tol);

            // An infinite error of a finite step (a tiny atol) is an ordinary rejection below.
            if err.is_nan() || !x_new.iter().all(|v| v.is_finite()) {
                // Shrink hard and retry: a finite error may come with a smaller step.
                self.stats.rejected_steps += 1;
                self.h_next = h * FAC_MIN;
                reject = true;
                if too_small(self.h_next, s) {
                    return Err(OdeError::NonFinite { t });
                }
                continue;
            }

            if err <= 1.0 {
                // A last step keeps the larger proposal (below). When a lower bound of the
                // controller's factor already shows that its growth cannot reach the proposal,
                // its two powers cannot change the outcome and are not computed (they were a
                // tenth of the Pendulum's time per step).
                let keeps_proposal = last && keeps(h, h_proposed, err, self.err_old);
                let h_new = if keeps_proposal {
                    h_proposed
                } else {
                    // PI controller on accepted steps.
                    let fac = (libm::pow(err.max(1e-10), ALPHA) / libm::pow(self.err_old, BETA)) / SAFETY;
                    let fac = fac.clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN);
                    // From the step just taken: a last step cut short to land on span supports
                    // only its own size times the factor (scaling the longer proposal instead
                    // grew it tenfold on every communication step, to infinity).
                    let h_new = h / fac;
                    if reject { h_new.min(h_proposed) } else { h_new }
                };
                self.err_old = err.max(1e-4);
                self.stats.accepted_steps += 1;
                let dense = DenseStep {
                    t0,
                    s0: s,
                    h,
                    x0: x,
                    x1: &x_new,
                    k: [&k1, &k3, &k4, &k5, &k6, &k7],
                };
                if let Some((s_stop, x_stop)) = stop(&dense) {
                    *x = x_stop;
                    self.h_next = h_new;
                    return Ok(Some(s_stop));
                }
                s = if last { span } else { s + h };
                *x = x_new;
                k1 = k7;
                // A step cut short to land on span says nothing about the next step size:
                // keep the larger proposal.
                self.h_next = if last { h_new.max(h_proposed) } else { h_new };
                reject = false;
            } else {
                let fac = (libm::pow(err, ALPHA) / SAFETY).min(1.0 / FAC_MIN);
                self.h_next = h / fac;
                self.stats.rejected_steps += 1;
                reject = true;
            }
        }
        Ok(None)
    }
}

// Dense output of DOPRI5 (Hairer, Nørsett & Wanner, II.6; the DOPRI5 code's CONTD5): a
// continuous extension of order 4 from the stages of the step.
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// One accepted step of [`Dopri5::integrate_until`], from local time `s0` to `s0 + h` (time
/// `t0 + s0` to `t0 + s0 + h`), with its continuous extension.
pub struct DenseStep<'a, const N: usize> {
    /// The time the integration's local times count from.
    pub t0: f64,
    /// The step's start, as a local time.
    pub s0: f64,
    /// Its length.
    pub h: f64,
    x0: &'a SVector<f64, N>,
    x1: &'a SVector<f64, N>,
    /// k1, k3, k4, k5, k6, k7 (k2 has no weight in the extension).
    k: [&'a SVector<f64, N>; 6],
}

impl<const N: usize> DenseStep<'_, N> {
    /// The state at the step's start.
    pub fn start(&self) -> &SVector<f64, N> {
        self.x0
    }
    /// The state at its end.
    pub fn end(&self) -> &SVector<f64, N> {
        self.x1
    }
    /// The state at local time `s` within the step (4th-order accurate; exactly the ends at the
    /// ends).
    pub fn at(&self, s: f64) -> SVector<f64, N> {
        let theta = ((s - self.s0) / self.h).clamp(0.0, 1.0);
        if theta == 1.0 {
            return *self.x1;
        }
        let theta1 = 1.0 - theta;
        let [k1, k3, k4, k5, k6, k7] = self.k;
        let h = self.h;
        let ydiff = self.x1 - self.x0;
        let bspl = k1 * h - ydiff;
        let r4 = ydiff - k7 * h - bspl;
        let r5 = (k1 * D1 + k3 * D3 + k4 * D4 + k5 * D5 + k6 * D6 + k7 * D7) * h;
        self.x0 + (ydiff + (bspl + (r4 + r5 * theta1) * theta) * theta1) * theta
    }
}

/// Whether the PI controller's proposal after a last step of `h` with error `err` (previous
/// `err_old`) is sure to be below `h_proposed`, so that the step keeps `h_proposed`, decided
/// without the controller's `pow` calls.
///
/// The controller computes fac = clamp((max(err, 1e-10)^α / err_old^β) / SAFETY, 1/FAC_MAX,
/// 1/FAC_MIN) and proposes h / fac. With 2^n ≤ max(err, 1e-10) and err_old ≤ 2^m, powers being
/// increasing, fac before the clamp is at least lo = (2^n)^α / (2^m)^β / SAFETY (tabulated),
/// less a margin of 1e-9 that covers the rounding of pow (< 1 ulp) and of the quotients many
/// times over; so fac ≥ clamp(lo) and, division rounding monotonically, h / fac ≤ h / clamp(lo).
/// `tests::keeps_agrees_with_the_controller` checks it against the computed proposal.
fn keeps(h: f64, h_proposed: f64, err: f64, err_old: f64) -> bool {
    /// (2^-i)^α and (2^(1-i))^β.
    struct Powers {
        alpha: [f64; 35],
        beta: [f64; 50],
    }
    static POWERS: OnceLock<Powers> = OnceLock::new();
    let exponent = |x: f64| ((x.to_bits() >> 52) & 0x7ff) as i64 - 1023;
    let e = err.max(1e-10);
    if !(e <= 1.0 && err_old.is_normal() && err_old > 0.0 && err_old <= 1.0) {
        return false;
    }
    let (n, m) = (exponent(e), exponent(err_old) + 1);
    if !(-34..=0).contains(&n) || !(-48..=1).contains(&m) {
        return false;
    }
    let p = POWERS.get_or_init(|| Powers {
        alpha: std::array::from_fn(|i| libm::pow(libm::scalbn(1.0, -(i as i32)), ALPHA)),
        beta: std::array::from_fn(|i| libm::pow(libm::scalbn(1.0, 1 - i as i32), BETA)),
    });
    let lo = p.alpha[(-n) as usize] / p.beta[(1 - m) as usize] / SAFETY * (1.0 - 1e-9);
    h_proposed >= h / lo.clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN)
}

/// A step `h` at time `s` (since the start of the span) that time resolution cannot resolve:
/// relative to the local time, never to the absolute one: |h| <= 16 eps max(|s|, 1e-300).
/// Both sides are scaled by 2^64 (exactly), because near s = 0 the bound itself is subnormal
/// (3.6e-315), and a subnormal product costs a microcode assist of some hundred cycles, at the
/// start of every span.
fn too_small(h: f64, s: f64) -> bool {
    const TWO_POW_64: f64 = 18_446_744_073_709_551_616.0;
    h.abs() * TWO_POW_64 <= (16.0 * f64::EPSILON * TWO_POW_64) * s.abs().max(1e-300)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    #[test]
    fn a_system_without_states_integrates_to_nothing_without_error() {
        let mut ode = Dopri5::default();
        let mut x = nalgebra::SVector::<f64, 0>::zeros();
        let tol = Tolerances { rtol: 1e-6, atol: 1e-9 };
        for k in 0..3 {
            let t = k as f64 * 0.01;
            assert_eq!(
                ode.integrate(|_, x: &nalgebra::SVector<f64, 0>| *x, t, 0.01, &mut x, tol),
                Ok(())
            );
        }
        assert_eq!(ode.validate(), Ok(()));
    }

    #[test]
    fn harmonic_oscillator_matches_the_exact_solution_to_tolerance() {
        let mut ode = Dopri5::default();
        let tol = Tolerances {
            rtol: 1e-10,
            atol: 1e-10,
        };
        let mut x = Vector2::new(1.0, 0.0);
        let mut t = 0.0;
        for _ in 0..1000 {
            ode.integrate(|_, x: &Vector2<f64>| Vector2::new(x[1], -x[0]), t, 0.01, &mut x, tol)
                .unwrap();
            t += 0.01;
        }
        let exact = Vector2::new(t.cos(), -t.sin());
        assert!((x - exact).norm() < 1e-8, "error {} after 10 s", (x - exact).norm());
    }

    /// The continuous extension is of order 4: halving the step divides its error in the
    /// middle of the step by about 2^5 (local error O(h^5)); it is exact at both ends.
    #[test]
    fn the_dense_output_is_fourth_order_within_the_step() {
        let tol = Tolerances { rtol: 1.0, atol: 1.0 };
        let error_at_middle = |h: f64| {
            let mut ode = Dopri5 {
                h_next: h,
                ..Dopri5::default()
            };
            let mut x = Vector2::new(1.0, 0.0);
            let mut seen = None;
            let stopped = ode
                .integrate_until(
                    |_, x: &Vector2<f64>| Vector2::new(x[1], -x[0]),
                    0.0,
                    h,
                    &mut x,
                    tol,
                    |step: &DenseStep<'_, 2>| {
                        assert_eq!(step.at(step.s0 + step.h), *step.end());
                        assert_eq!(step.at(step.s0), *step.start());
                        seen = Some(step.at(step.s0 + step.h / 2.0));
                        None
                    },
                )
                .unwrap();
            assert_eq!(stopped, None);
            let m = seen.expect("one step");
            let exact = Vector2::new((h / 2.0).cos(), -(h / 2.0).sin());
            (m - exact).norm()
        };
        let (e1, e2) = (error_at_middle(0.2), error_at_middle(0.1));
        let order = (e1 / e2).log2();
        assert!(order > 4.5 && order < 6.5, "errors {e1:e}, {e2:e}: local order {order}");
    }

    #[test]
    fn integrate_until_stops_where_stop_says() {
        let mut ode = Dopri5::default();
        let tol = Tolerances {
            rtol: 1e-10,
            atol: 1e-10,
        };
        // x' = -1 from 1: reaches 0 at t = 1; stop at the step that crosses 0.
        let mut x = nalgebra::Vector1::new(1.0);
        let stopped = ode
            .integrate_until(
                |_, _: &nalgebra::Vector1<f64>| nalgebra::Vector1::new(-1.0),
                0.0,
                3.0,
                &mut x,
                tol,
                |step: &DenseStep<'_, 1>| {
                    (step.end()[0] <= 0.0).then(|| {
                        let s = step.s0 + step.start()[0];
                        (s, step.at(s))
                    })
                },
            )
            .unwrap();
        assert_eq!(stopped, Some(1.0));
        assert!(x[0].abs() < 1e-14, "{x}");
    }

    #[test]
    fn the_steps_do_not_depend_on_the_absolute_start_time() {
        let tol = Tolerances {
            rtol: 1e-10,
            atol: 1e-10,
        };
        let run = |t0: f64| {
            let mut ode = Dopri5::default();
            let mut x = Vector2::new(0.0, 0.0);
            // From rest with a constant push: Hairer's starting step is 1e-6, finer than the
            // time stamps' resolution at t0 = 1.7e9 s.
            ode.integrate(|_, x: &Vector2<f64>| Vector2::new(x[1], 1.0), t0, 1e-3, &mut x, tol)
                .map(|()| (x, ode.stats))
        };
        let at_zero = run(0.0).unwrap();
        let at_unix_time = run(1.7e9).unwrap_or_else(|e| panic!("t0 = 1.7e9: {e}"));
        assert_eq!(at_zero, at_unix_time, "the same 1 ms from t0 = 0 and from t0 = 1.7e9");
    }

    #[test]
    fn the_proposed_step_stays_bounded_over_many_short_spans() {
        // Every span is one step cut short to land on its end: the proposal must grow from
        // what those steps support, not tenfold per span (it reached infinity after ~300).
        let mut ode = Dopri5::default();
        let tol = Tolerances { rtol: 1e-6, atol: 1e-6 };
        let mut x = Vector2::new(1.0, 0.0);
        for k in 0..1000 {
            let f = |_, x: &Vector2<f64>| Vector2::new(x[1], -x[0]);
            ode.integrate(f, k as f64 * 1e-3, 1e-3, &mut x, tol).unwrap();
            assert!(
                ode.h_next.is_finite() && ode.h_next <= 1.0,
                "after span {k}: proposed step {} s for spans of 1 ms",
                ode.h_next
            );
        }
    }

    #[test]
    fn the_smallest_absolute_tolerance_starts_from_zero() {
        // atol = 5e-324 at x = 0 with x' != 0: the scaled norms overflow; the start must still
        // be a (tiny) step, and the error control relative from there on.
        let tol = Tolerances {
            rtol: 1e-8,
            atol: 5e-324,
        };
        let mut ode = Dopri5::default();
        let mut x = Vector2::new(0.0, 0.0);
        let r = ode.integrate(|_, x: &Vector2<f64>| Vector2::new(x[1], 1.0), 0.0, 1e-3, &mut x, tol);
        assert_eq!(r, Ok(()), "after {:?}", ode.stats);
        assert!((x[0] - 0.5e-6).abs() < 1e-14 && (x[1] - 1e-3).abs() < 1e-14, "x = {x}");
    }

    #[test]
    fn keeps_agrees_with_the_controller() {
        // Whenever `keeps` skips the controller, the controller's own proposal after a last
        // step, max(h / fac, h_proposed) (min with h_proposed first after a rejection), is
        // h_proposed to the bit. Random errors over their whole range, and proposals around
        // the boundary.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut kept, mut cases) = (0, 0);
        for _ in 0..200_000 {
            let err = 10f64.powf(-12.0 * uniform());
            let err_old = 10f64.powf(-5.0 * uniform()).max(1e-4);
            let h = 10f64.powf(-6.0 * uniform());
            let fac = (libm::pow(err.max(1e-10), ALPHA) / libm::pow(err_old, BETA)) / SAFETY;
            let fac = fac.clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN);
            let h_new = h / fac;
            for scale in [0.999, 1.0, 1.0 + 1e-15, 1.001, 1.1, 2.0] {
                let h_proposed = h_new * scale;
                cases += 1;
                if keeps(h, h_proposed, err, err_old) {
                    kept += 1;
                    for reject in [false, true] {
                        let h_new = if reject { h_new.min(h_proposed) } else { h_new };
                        assert_eq!(
                            h_new.max(h_proposed).to_bits(),
                            h_proposed.to_bits(),
                            "err {err:e}, err_old {err_old:e}, h {h:e}: kept {h_proposed:e}, the controller gives {h_new:e}"
                        );
                    }
                }
            }
        }
        assert!(kept > cases / 3, "the shortcut should apply often: {kept} of {cases}");
    }

    #[test]
    fn too_many_steps_is_an_error_not_a_hang() {
        let mut ode = Dopri5 {
            max_steps: 10,
            ..Default::default()
        };
        let tol = Tolerances {
            rtol: 1e-12,
            atol: 1e-12,
        };
        let mut x = Vector2::new(1.0, 0.0);
        let e = ode.integrate(|_, x: &Vector2<f64>| Vector2::new(x[1], -x[0]), 0.0, 1e6, &mut x, tol);
        assert!(matches!(e, Err(OdeError::TooManySteps { .. })), "{e:?}");
    }

    #[test]
    fn blow_up_is_reported_as_non_finite() {
        let mut ode = Dopri5::default();
        let tol = Tolerances { rtol: 1e-8, atol: 1e-8 };
        let mut x = SVector::<f64, 1>::new(1.0);
        // x' = x², x(0) = 1 blows up at t = 1.
        let e = ode.integrate(|_, x: &SVector<f64, 1>| x.map(|v| v * v), 0.0, 2.0, &mut x, tol);
        assert!(e.is_err(), "integrated through a singularity: {x:?}");
    }
}
