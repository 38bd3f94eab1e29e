//! The plant model against the paper's linearization (12) and the numbers derived from it.
//! A and B come from the model's own right-hand side (exact dual-number Jacobian), not typed in.

use holonomic::models::pendulum::PendulumParams;
use nalgebra::{Matrix4, SMatrix, Vector2, Vector4};

fn paper_a_b() -> (Matrix4<f64>, SMatrix<f64, 4, 2>) {
    PendulumParams::default().linearize(&Vector4::zeros(), &Vector2::zeros())
}

#[test]
fn jacobian_at_upright_reproduces_eq12_a_and_b() {
    let (a, b) = paper_a_b();
    #[rustfmt::skip]
    let a_paper = Matrix4::new(
        0.0, 1.0, 0.0, 0.0,
        44.145, 0.0, -14.715, 0.0,
        0.0, 0.0, 0.0, 1.0,
        -44.145, 0.0, 29.43, 0.0,
    );
    #[rustfmt::skip]
    let b_paper = SMatrix::<f64, 4, 2>::new(
        0.0, 0.0,
        6.0, -6.0,
        0.0, 0.0,
        -6.0, 12.0,
    );
    assert!((a - a_paper).abs().max() < 1e-12, "A = {a}, paper (12): {a_paper}");
    assert!((b - b_paper).abs().max() < 1e-12, "B = {b}, paper (12): {b_paper}");
}

#[test]
fn open_loop_poles_match_paper() {
    let (a, _) = paper_a_b();
    let mut poles: Vec<f64> = a
        .complex_eigenvalues()
        .iter()
        .map(|p| {
            assert!(p.im.abs() < 1e-9, "pole {p} should be real");
            p.re
        })
        .collect();
    poles.sort_by(f64::total_cmp);
    let paper = [-7.9571, -3.2031, 3.2031, 7.9571];
    for (p, q) in poles.iter().zip(paper) {
        assert!((p - q).abs() < 5e-5, "poles {poles:?}, paper: {paper:?}");
    }
    // Two poles in the right half-plane: the upright pendulum is unstable.
    assert_eq!(poles.iter().filter(|p| **p > 0.0).count(), 2);
}

#[test]
fn open_loop_characteristic_polynomial_matches_eq13() {
    // det(sI - A) = s^4 - 73.575 s^2 + 649.594 (the paper prints -73.57 and 649.6).
    let (a, _) = paper_a_b();
    let c2 = -(a[(1, 0)] + a[(3, 2)]);
    let c0 = a[(1, 0)] * a[(3, 2)] - a[(1, 2)] * a[(3, 0)];
    assert!((c2 + 73.575).abs() < 1e-9, "s^2 coefficient {c2}");
    assert!((c0 - 649.594).abs() < 1e-3, "s^0 coefficient {c0}");
}

#[test]
fn controllability_rank_is_four() {
    let (a, b) = paper_a_b();
    let mut co = SMatrix::<f64, 4, 8>::zeros();
    let mut akb = b;
    for k in 0..4 {
        co.fixed_view_mut::<4, 2>(0, 2 * k).copy_from(&akb);
        akb = a * akb;
    }
    let sv = co.svd(false, false).singular_values;
    let rank = sv.iter().filter(|s| **s > 1e-9 * sv.max()).count();
    assert_eq!(rank, 4, "singular values of [B AB A²B A³B]: {sv}");
}

#[test]
fn mass_matrix_at_rest_inverts_to_b() {
    // B's lower rows are M(0)^-1: [6 -6; -6 12].
    let m_inv = PendulumParams::default().mass_matrix_upright().try_inverse().unwrap();
    let want = nalgebra::Matrix2::new(6.0, -6.0, -6.0, 12.0);
    assert!((m_inv - want).abs().max() < 1e-12, "M(0)^-1 = {m_inv}");
}
