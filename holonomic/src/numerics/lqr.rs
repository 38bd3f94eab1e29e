//! Linear-quadratic regulator: the continuous algebraic Riccati equation (CARE)
//!
//! ```text
//! Aᵀ X + X A − X B R⁻¹ Bᵀ X + Q = 0,        K = R⁻¹ Bᵀ X,
//! ```
//!
//! whose stabilizing solution X gives the gain of MATLAB's `K = lqr(A, B, Q, R)` (the paper's
//! equation (14)); u = −K x minimizes ∫ xᵀQx + uᵀRu dt.
//!
//! Method: the matrix sign function of the Hamiltonian H = [A, −B R⁻¹ Bᵀ; −Q, −Aᵀ] (Roberts
//! 1971; Byers 1987, with determinant scaling), then Newton–Kleinman refinement.
//! Why this and not the others:
//! - The Schur method needs an *ordered* real Schur form (stable eigenvalues first); nalgebra
//!   has a Schur decomposition but no reordering, and writing one is more code than this.
//! - Newton–Kleinman alone needs a stabilizing gain to start from, and the pendulum is open-loop
//!   unstable, so some other method must supply it anyway.
//! - The sign iteration needs only matrix inverses (nalgebra LU) and converges quadratically; it
//!   fails cleanly (no convergence, singular iterate) exactly when H has eigenvalues on the
//!   imaginary axis, i.e. when no stabilizing solution exists. Two Newton–Kleinman steps from
//!   its result bring the Riccati residual to round-off (~1e-14 here); each solves one Lyapunov
//!   equation by its Kronecker form, which is a 16×16 system for n = 4.
//!
//! Runs once, at FMU initialization, so it uses dynamic matrices and may allocate.

use nalgebra::{DMatrix, SMatrix};

/// Why no LQR gain could be computed; the message names the offending matrix.
#[derive(Debug, Clone, PartialEq)]
pub struct LqrError(pub String);

impl std::fmt::Display for LqrError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for LqrError {}

fn err<T>(msg: impl Into<String>) -> Result<T, LqrError> {
    Err(LqrError(msg.into()))
}

/// K = lqr(A, B, Q, R) for fixed sizes: n states, m inputs. See the module documentation.
pub fn lqr<const N: usize, const M: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, M>,
    q: &SMatrix<f64, N, N>,
    r: &SMatrix<f64, M, M>,
) -> Result<SMatrix<f64, M, N>, LqrError> {
    let to_d = |m: &[f64], rows, cols| DMatrix::from_column_slice(rows, cols, m);
    let (a, b, q, r) = (
        to_d(a.as_slice(), N, N),
        to_d(b.as_slice(), N, M),
        to_d(q.as_slice(), N, N),
        to_d(r.as_slice(), M, M),
    );
    let x = care(&a, &b, &q, &r)?;
    let k = gain(&b, &r, &x)?;
    Ok(SMatrix::<f64, M, N>::from_column_slice(k.as_slice()))
}

/// K = R⁻¹ Bᵀ X.
fn gain(b: &DMatrix<f64>, r: &DMatrix<f64>, x: &DMatrix<f64>) -> Result<DMatrix<f64>, LqrError> {
    let Some(chol) = r.clone().cholesky() else {
        return err("R must be symmetric positive definite");
    };
    Ok(chol.solve(&(b.transpose() * x)))
}

/// Most iterations of an eigenvalue or SVD decomposition (a few dozen suffice for the
/// converging ones here).
const MAX_ITERATIONS: usize = 10_000;

/// The stabilizing solution X = Xᵀ ≥ 0 of the CARE, or why there is none.
pub fn care(a: &DMatrix<f64>, b: &DMatrix<f64>, q: &DMatrix<f64>, r: &DMatrix<f64>) -> Result<DMatrix<f64>, LqrError> {
    let n = a.nrows();
    if a.ncols() != n || b.nrows() != n || q.shape() != (n, n) || r.shape() != (b.ncols(), b.ncols()) {
        return err(format!(
            "inconsistent sizes: A {:?}, B {:?}, Q {:?}, R {:?}",
            a.shape(),
            b.shape(),
            q.shape(),
            r.shape()
        ));
    }
    let finite = |m: &DMatrix<f64>| m.iter().all(|v| v.is_finite());
    if !(finite(a) && finite(b) && finite(q) && finite(r)) {
        return err("A, B, Q and R must be finite");
    }
    let symmetric = |m: &DMatrix<f64>| (m - m.transpose()).amax() <= 1e-12 * (1.0 + m.amax());
    if !symmetric(q) {
        return err("Q must be symmetric");
    }
    // nalgebra's eigenvalue and SVD iterations run without a limit by default: with
    // intermediates that overflow they may never stop, so every one here has one.
    let Some(q_eigen) = q.clone().try_symmetric_eigen(f64::EPSILON, MAX_ITERATIONS) else {
        return err("Q: the eigenvalue iteration did not converge (values out of range?)");
    };
    if q_eigen.eigenvalues.min() < -1e-12 * (1.0 + q.amax()) {
        return err("Q must be positive semidefinite");
    }
    let Some(r_chol) = r.clone().cholesky() else {
        return err("R must be symmetric positive definite");
    };
    let g = b * r_chol.solve(&b.transpose());

    // Hamiltonian H = [A, −G; −Q, −Aᵀ].
    let mut h = DMatrix::<f64>::zeros(2 * n, 2 * n);
    h.view_mut((0, 0), (n, n)).copy_from(a);
    h.view_mut((0, n), (n, n)).copy_from(&(-&g));
    h.view_mut((n, 0), (n, n)).copy_from(&(-q));
    h.view_mut((n, n), (n, n)).copy_from(&(-a.transpose()));

    let w = matrix_sign(h)?;
    // The stable invariant subspace of H is spanned by [I; X], and sign(H) = −1 on it:
    // (W + I)[I; X] = 0, i.e. [W12; W22 + I] X = −[W11 + I; W21] (least squares, 2n × n).
    let identity = DMatrix::<f64>::identity(n, n);
    let mut lhs = DMatrix::<f64>::zeros(2 * n, n);
    lhs.view_mut((0, 0), (n, n)).copy_from(&w.view((0, n), (n, n)));
    lhs.view_mut((n, 0), (n, n))
        .copy_from(&(w.view((n, n), (n, n)) + &identity));
    let mut rhs = DMatrix::<f64>::zeros(2 * n, n);
    rhs.view_mut((0, 0), (n, n))
        .copy_from(&(-(w.view((0, 0), (n, n)) + &identity)));
    rhs.view_mut((n, 0), (n, n)).copy_from(&(-w.view((n, 0), (n, n))));
    let Some(svd) = lhs.try_svd(true, true, f64::EPSILON, MAX_ITERATIONS) else {
        return err("CARE: the SVD did not converge (values out of range?)");
    };
    let x = svd.solve(&rhs, 1e-14).map_err(|e| LqrError(format!("CARE: {e}")))?;
    let mut x = (&x + x.transpose()) * 0.5;

    // Newton–Kleinman: X ← solution of (A − G X)ᵀ X' + X' (A − G X) = −(Q + X G X).
    let mut residual = care_residual(a, &g, q, &x);
    for _ in 0..3 {
        let acl = a - &g * &x;
        let rhs = -(q + &x * &g * &x);
        let next = lyapunov(&acl, &rhs)?;
        let next_residual = care_residual(a, &g, q, &next);
        if next_residual >= residual {
            break;
        }
        (x, residual) = (next, next_residual);
    }
    let scale = 1.0 + q.amax() + (&x * &g * &x).amax();
    if residual > 1e-8 * scale {
        return err(format!(
            "CARE: the solution's residual {residual:e} is too large (ill-conditioned problem)"
        ));
    }
    let closed_loop = a - &g * &x;
    let Some(schur) = closed_loop.try_schur(f64::EPSILON, MAX_ITERATIONS) else {
        return err("CARE: the closed loop's eigenvalue iteration did not converge (values out of range?)");
    };
    let worst = schur
        .complex_eigenvalues()
        .iter()
        .map(|l| l.re)
        .fold(f64::NEG_INFINITY, f64::max);
    if worst >= 0.0 {
        return err(format!(
            "CARE: no stabilizing solution (closed-loop eigenvalue with real part {worst}); is (A, B) stabilizable and (A, Q) detectable?"
        ));
    }
    Ok(x)
}

/// max |Aᵀ X + X A − X G X + Q|.
fn care_residual(a: &DMatrix<f64>, g: &DMatrix<f64>, q: &DMatrix<f64>, x: &DMatrix<f64>) -> f64 {
    (a.transpose() * x + x * a - x * g * x + q).amax()
}

/// sign(H) by the scaled Newton iteration Z ← (c Z + (c Z)⁻¹)/2, c = |det Z|^(−1/N).
fn matrix_sign(mut z: DMatrix<f64>) -> Result<DMatrix<f64>, LqrError> {
    let size = z.nrows() as f64;
    for _ in 0..100 {
        let det = z.determinant();
        let Some(inv) = z.clone().try_inverse().filter(|_| det != 0.0 && det.is_finite()) else {
            return err("CARE: the Hamiltonian has eigenvalues on the imaginary axis (no stabilizing solution)");
        };
        // libm's pow: the same gains on every platform and thread (msvcrt's pow under wine
        // depends on the calling thread's x87 precision control).
        let c = libm::pow(det.abs(), -1.0 / size);
        let next = (&z * c + inv / c) * 0.5;
        let change = (&next - &z).norm() / next.norm();
        z = next;
        if !z.iter().all(|v| v.is_finite()) {
            return err("CARE: the sign iteration diverged");
        }
        if change < 1e-13 {
            return Ok(z);
        }
    }
    err("CARE: the sign iteration did not converge in 100 steps (eigenvalues near the imaginary axis)")
}

/// Solves Aᵀ X + X A = C by the Kronecker form (I ⊗ Aᵀ + Aᵀ ⊗ I) vec X = vec C.
fn lyapunov(a: &DMatrix<f64>, c: &DMatrix<f64>) -> Result<DMatrix<f64>, LqrError> {
    let n = a.nrows();
    let identity = DMatrix::<f64>::identity(n, n);
    let at = a.transpose();
    let big = identity.kronecker(&at) + at.kronecker(&identity);
    let vec_c = DMatrix::from_column_slice(n * n, 1, c.as_slice());
    let Some(vec_x) = big.lu().solve(&vec_c) else {
        return err(
            "CARE: no stabilizing solution: a Newton step's Lyapunov equation is singular (is (A, B) stabilizable?)",
        );
    };
    let x = DMatrix::from_column_slice(n, n, vec_x.as_slice());
    Ok((&x + x.transpose()) * 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix1, Matrix2, Vector2};

    #[test]
    fn scalar_lqr_matches_closed_form() {
        // ẋ = a x + b u: X = (a + sqrt(a² + b² q / r)) r / b², K = b X / r.
        let (a, b, q, r) = (3.0, 2.0, 5.0, 0.5);
        let k = lqr(&Matrix1::new(a), &Matrix1::new(b), &Matrix1::new(q), &Matrix1::new(r)).unwrap()[0];
        let x = (a + (a * a + b * b * q / r).sqrt()) * r / (b * b);
        assert!((k - b * x / r).abs() < 1e-12, "expected K = {}, got {k}", b * x / r);
    }

    #[test]
    fn double_integrator_lqr_matches_closed_form() {
        // ẍ = u, Q = I, R = 1: K = [1, √3].
        let a = Matrix2::new(0.0, 1.0, 0.0, 0.0);
        let b = Vector2::new(0.0, 1.0);
        let k = lqr(&a, &b, &Matrix2::identity(), &Matrix1::new(1.0)).unwrap();
        assert!(
            (k[0] - 1.0).abs() < 1e-12 && (k[1] - 3f64.sqrt()).abs() < 1e-12,
            "expected [1, 1.7320508], got {k}"
        );
    }

    #[test]
    fn uncontrollable_unstable_mode_is_an_error() {
        // ẋ1 = x1 (unstable, not reachable), ẋ2 = u.
        let a = Matrix2::new(1.0, 0.0, 0.0, 0.0);
        let b = Vector2::new(0.0, 1.0);
        let e = lqr(&a, &b, &Matrix2::identity(), &Matrix1::new(1.0)).unwrap_err();
        assert!(e.0.contains("CARE"), "expected a CARE error, got {e}");
    }

    #[test]
    fn indefinite_r_is_an_error_naming_r() {
        let a = Matrix2::new(0.0, 1.0, 0.0, 0.0);
        let b = Vector2::new(0.0, 1.0);
        let e = lqr(&a, &b, &Matrix2::identity(), &Matrix1::new(-1.0)).unwrap_err();
        assert!(e.0.contains("R must be"), "expected an error about R, got {e}");
    }
}
