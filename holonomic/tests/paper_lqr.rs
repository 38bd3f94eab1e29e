//! The paper's LQR design, equations (14) and (15), recomputed from the plant model code (the
//! linearization of `PendulumParams::rhs`, not typed-in matrices).

use holonomic::models::pendulum::PendulumParams;
use holonomic::numerics::lqr::lqr;
use holonomic::numerics::lti::{characteristic_polynomial, transfer_numerator};
use nalgebra::{DMatrix, Matrix2, Matrix4, SMatrix, Vector2, Vector4};

/// K and A − BK with the paper's weights Q = CᵀC, R = I.
fn paper_design() -> (SMatrix<f64, 2, 4>, Matrix4<f64>, SMatrix<f64, 4, 2>) {
    let (a, b) = PendulumParams::default().linearize(&Vector4::zeros(), &Vector2::zeros());
    let c = PendulumParams::output_matrix();
    let k = lqr(&a, &b, &(c.transpose() * c), &Matrix2::identity()).expect("the paper's LQR problem is solvable");
    (k, a - b * k, b)
}

#[test]
fn lqr_gain_matches_paper_eq14() {
    let (k, _, _) = paper_design();
    // Equation (14), printed to 4 decimals.
    let paper = [[14.0666, 2.8816, 1.1348, 1.0010], [-3.1814, 0.1161, 4.8456, 0.9957]];
    for (i, row) in paper.iter().enumerate() {
        for (j, printed) in row.iter().enumerate() {
            let rounded = (k[(i, j)] * 1e4).round() / 1e4;
            assert!(
                (rounded - printed).abs() < 1e-9,
                "K[{}{}]: paper prints {printed}, computed {} (rounds to {rounded})",
                i + 1,
                j + 1,
                k[(i, j)]
            );
        }
    }
}

#[test]
fn closed_loop_poles_match_paper() {
    let (_, acl, _) = paper_design();
    let mut poles: Vec<_> = acl.complex_eigenvalues().iter().map(|l| (l.re, l.im)).collect();
    poles.sort_by(|p, q| p.0.total_cmp(&q.0).then(p.1.total_cmp(&q.1)));
    let expected = [
        (-7.99871, -0.92943),
        (-7.99871, 0.92943),
        (-3.26937, -0.47891),
        (-3.26937, 0.47891),
    ];
    for (got, want) in poles.iter().zip(expected) {
        assert!(
            (got.0 - want.0).abs() < 5e-6 && (got.1 - want.1).abs() < 5e-6,
            "closed-loop poles: expected {expected:?}, got {poles:?}"
        );
    }
}

#[test]
fn closed_loop_polynomial_matches_paper_eq15() {
    let (_, acl, _) = paper_design();
    let p = characteristic_polynomial(&DMatrix::from_column_slice(4, 4, acl.as_slice()));
    // s⁴ + 22.536 s³ + 180.364 s² + 598.656 s + 707.968 (printed rounded as 22.54, 180.4, 598.7, 708).
    let expected = [1.0, 22.536, 180.364, 598.656, 707.968];
    for (got, want) in p.iter().zip(expected) {
        assert!(
            (got - want).abs() < 5e-4,
            "closed-loop polynomial: expected {expected:?}, got {p:?}"
        );
    }
}

#[test]
fn closed_loop_transfer_numerators_match_paper_eq15() {
    let (_, acl, b) = paper_design();
    let acl = DMatrix::from_column_slice(4, 4, acl.as_slice());
    let b = DMatrix::from_column_slice(4, 2, b.as_slice());
    let c = DMatrix::from_row_slice(2, 4, &[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    // (output, input, numerator as printed, highest power first; the paper drops one "s" in α1/M2).
    let cases = [
        ("alpha1/M1", 0, 0, [6.0, 35.85, 86.15]),
        ("alpha2/M1", 1, 0, [-6.0, -4.179, 114.5]),
        ("alpha1/M2", 0, 1, [-6.0, -36.04, -40.85]),
        ("alpha2/M2", 1, 1, [12.0, 103.7, 241.5]),
    ];
    for (name, out, inp, printed) in cases {
        let num = transfer_numerator(&acl, &b, &c, out, inp);
        assert!(num[0].abs() < 1e-9, "{name}: s³ coefficient should vanish, got {num:?}");
        for (got, want) in num[1..].iter().zip(printed) {
            // Four significant digits, as printed.
            assert!(
                (got - want).abs() <= 5e-4 * want.abs().max(1.0) + 1e-12,
                "{name}: paper prints {printed:?}, computed {:?}",
                &num[1..]
            );
        }
    }
}
