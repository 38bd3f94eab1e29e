//! Facts about linear time-invariant systems ẋ = A x + B u, y = C x: characteristic
//! polynomials, single-input single-output transfer-function numerators, controllability.
//! Used to reproduce the paper's equations (13)–(15); sizes are small (n = 4), so plain dynamic
//! matrices and textbook algorithms are exact enough and fast enough.

use nalgebra::DMatrix;

/// Coefficients of det(sI − A), highest power first: `[1, c1, …, cn]`, by the Faddeev–LeVerrier
/// recursion M_k = A M_{k−1} + c_{k−1} I, c_k = −tr(A M_k)/k (exact in exact arithmetic; for
/// the 4×4 matrices here the round-off is ~1e-13 relative).
pub fn characteristic_polynomial(a: &DMatrix<f64>) -> Vec<f64> {
    let n = a.nrows();
    assert_eq!(n, a.ncols(), "characteristic_polynomial needs a square matrix");
    let mut coefficients = vec![1.0];
    let mut m = DMatrix::<f64>::zeros(n, n);
    let identity = DMatrix::<f64>::identity(n, n);
    for k in 1..=n {
        m = a * &m + &identity * coefficients[k - 1];
        let am = a * &m;
        coefficients.push(-am.trace() / k as f64);
    }
    coefficients
}

/// Numerator of the transfer function y_i/u_j = c_i (sI − A)⁻¹ b_j, highest power first, with
/// the denominator det(sI − A). Uses the rank-one identity
/// c (sI − A)⁻¹ b = [det(sI − A + b c) − det(sI − A)] / det(sI − A),
/// so the numerator is the difference of two characteristic polynomials (leading term dropped,
/// it cancels): degree n − 1 coefficients.
pub fn transfer_numerator(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
    output: usize,
    input: usize,
) -> Vec<f64> {
    let bc = b.column(input) * c.row(output);
    let with = characteristic_polynomial(&(a - bc));
    let without = characteristic_polynomial(a);
    with.iter().zip(&without).skip(1).map(|(p, q)| p - q).collect()
}

/// The controllability matrix [B, AB, A²B, …, Aⁿ⁻¹B].
pub fn controllability_matrix(a: &DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    let n = a.nrows();
    let m = b.ncols();
    let mut co = DMatrix::<f64>::zeros(n, n * m);
    let mut block = b.clone();
    for k in 0..n {
        co.view_mut((0, k * m), (n, m)).copy_from(&block);
        block = a * block;
    }
    co
}

/// Numerical rank: singular values above max(size) · ε · σ_max (MATLAB's `rank` rule).
pub fn rank(m: &DMatrix<f64>) -> usize {
    let sv = m.singular_values();
    let largest = sv.max();
    let tol = m.nrows().max(m.ncols()) as f64 * f64::EPSILON * largest;
    sv.iter().filter(|&&s| s > tol).count()
}

/// Evaluates a polynomial given highest power first (Horner), for real s.
pub fn polyval(p: &[f64], s: f64) -> f64 {
    p.iter().fold(0.0, |acc, c| acc * s + c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn characteristic_polynomial_of_companion_matrix_is_its_polynomial() {
        // Companion matrix of s³ + 2s² − 5s + 7.
        let a = DMatrix::from_row_slice(3, 3, &[0.0, 1.0, 0.0, 0.0, 0.0, 1.0, -7.0, 5.0, -2.0]);
        let p = characteristic_polynomial(&a);
        let expected = [1.0, 2.0, -5.0, 7.0];
        for (got, want) in p.iter().zip(expected) {
            assert!((got - want).abs() < 1e-12, "expected {expected:?}, got {p:?}");
        }
    }

    #[test]
    fn transfer_numerator_of_double_integrator_is_one() {
        // ẍ = u, y = x: 1/s².
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
        let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
        let c = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
        let num = transfer_numerator(&a, &b, &c, 0, 0);
        assert_eq!(num, vec![0.0, 1.0], "numerator of 1/s² expected [0, 1], got {num:?}");
    }

    #[test]
    fn rank_sees_dependent_columns() {
        let m = DMatrix::from_row_slice(2, 3, &[1.0, 2.0, 3.0, 2.0, 4.0, 6.0]);
        assert_eq!(rank(&m), 1);
    }
}
