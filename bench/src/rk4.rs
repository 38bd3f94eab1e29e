//! The classical fixed-step explicit Runge–Kutta scheme of order 4: the baseline of the
//! work-precision table, run with as many right-hand-side evaluations as the adaptive
//! integrator used, so the table shows what error control buys at equal cost.

use nalgebra::SVector;

/// Integrates `x' = f(x)` from t0 over `steps` equal steps of size `h`, in place; returns the
/// number of right-hand-side evaluations (4 per step).
pub fn integrate<const N: usize>(
    f: impl Fn(&SVector<f64, N>) -> SVector<f64, N>,
    x: &mut SVector<f64, N>,
    h: f64,
    steps: usize,
) -> u64 {
    for _ in 0..steps {
        let k1 = f(x);
        let k2 = f(&(*x + k1 * (h / 2.0)));
        let k3 = f(&(*x + k2 * (h / 2.0)));
        let k4 = f(&(*x + k3 * h));
        *x += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0);
    }
    4 * steps as u64
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector2;

    #[test]
    fn error_of_rk4_falls_sixteenfold_when_the_step_halves() {
        // x'' = -x from (1, 0): exact (cos t, -sin t) at t = 1.
        let f = |x: &Vector2<f64>| Vector2::new(x[1], -x[0]);
        let err = |steps: usize| {
            let mut x = Vector2::new(1.0, 0.0);
            super::integrate(f, &mut x, 1.0 / steps as f64, steps);
            (x - Vector2::new(1f64.cos(), -1f64.sin())).norm()
        };
        let ratio = err(20) / err(40);
        assert!(
            (14.0..18.0).contains(&ratio),
            "error ratio {ratio}, expected about 16 for order 4"
        );
    }
}
