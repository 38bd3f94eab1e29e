//! Prints the paper's numbers as this project computes them, next to the values the paper
//! prints: `cargo run --release --example paper_numbers`.
//!
//! Everything is derived from the model code the FMUs run: A and B are the exact Jacobians of
//! equations (6)–(7), K solves the Riccati equation, the polynomials come from A − BK.

use holonomic::models::controller::lqr_gain;
use holonomic::models::dc_motor::DcMotorParams;
use holonomic::models::pendulum::PendulumParams;
use holonomic::numerics::lti::{characteristic_polynomial, controllability_matrix, rank, transfer_numerator};
use nalgebra::{DMatrix, Matrix2, Vector2, Vector4};

fn dyn_matrix<const R: usize, const C: usize>(m: &nalgebra::SMatrix<f64, R, C>) -> DMatrix<f64> {
    DMatrix::from_column_slice(R, C, m.as_slice())
}

fn row(v: &[f64], digits: usize) -> String {
    v.iter()
        .map(|x| format!("{x:>10.digits$}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn poles(m: &DMatrix<f64>) -> String {
    let mut p: Vec<_> = m.clone().complex_eigenvalues().iter().map(|l| (l.re, l.im)).collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    p.iter()
        .map(|(re, im)| format!("{re:.5}{im:+.5}i"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn main() {
    let plant = PendulumParams::default();
    let (a, b) = plant.linearize(&Vector4::zeros(), &Vector2::zeros());
    let c = PendulumParams::output_matrix();
    let (ad, bd, cd) = (dyn_matrix(&a), dyn_matrix(&b), dyn_matrix(&c));

    println!("The control of holonomic system (Liptak et al.): computed | printed in the paper\n");
    println!(
        "Plant m1 = m2 = {} kg, l1 = l2 = {} m, g = {} m/s^2",
        plant.m1, plant.l1, plant.g
    );
    println!("\nA, eq. (12):");
    let paper_a = [
        [0.0, 1.0, 0.0, 0.0],
        [44.145, 0.0, -14.715, 0.0],
        [0.0, 0.0, 0.0, 1.0],
        [-44.145, 0.0, 29.43, 0.0],
    ];
    for (i, pa) in paper_a.iter().enumerate() {
        let r: Vec<f64> = (0..4).map(|j| a[(i, j)]).collect();
        println!("  {} | {}", row(&r, 4), row(pa, 4));
    }
    println!("B, eq. (12):");
    let paper_b = [[0.0, 0.0], [6.0, -6.0], [0.0, 0.0], [-6.0, 12.0]];
    for (i, pb) in paper_b.iter().enumerate() {
        println!("  {} | {}", row(&[b[(i, 0)], b[(i, 1)]], 4), row(pb, 4));
    }
    println!("Open-loop poles: {} | +-7.9571, +-3.2031", poles(&ad));
    let ol = characteristic_polynomial(&ad);
    println!("Open-loop polynomial (13): {} | 1 0 -73.57 0 649.6", row(&ol, 3));
    let co = controllability_matrix(&ad, &bd);
    println!("Controllability matrix rank: {} | 4", rank(&co));

    let k = lqr_gain(&plant, &(c.transpose() * c), &Matrix2::identity()).expect("LQR");
    println!("\nK = lqr(A, B, C'C, I), eq. (14):");
    let paper_k = [[14.0666, 2.8816, 1.1348, 1.0010], [-3.1814, 0.1161, 4.8456, 0.9957]];
    for (i, pk) in paper_k.iter().enumerate() {
        let r: Vec<f64> = (0..4).map(|j| k[(i, j)]).collect();
        println!("  {} | {}", row(&r, 4), row(pk, 4));
    }
    let acl = dyn_matrix(&(a - b * k));
    println!("Closed-loop poles: {}", poles(&acl));
    let cl = characteristic_polynomial(&acl);
    println!("Closed-loop polynomial (15): {} | 1 22.54 180.4 598.7 708", row(&cl, 3));
    println!("Closed-loop numerators (15):");
    let printed = ["6 35.85 86.15", "-6 -4.179 114.5", "-6 -36.04 -40.85", "12 103.7 241.5"];
    let mut n = 0;
    for input in 0..2 {
        for output in 0..2 {
            let num = transfer_numerator(&acl, &bd, &cd, output, input);
            println!(
                "  alpha{}/M{}: {} | {}",
                output + 1,
                input + 1,
                row(&num[1..], 3),
                printed[n]
            );
            n += 1;
        }
    }

    let motor = DcMotorParams::default();
    let den = motor.speed_transfer_denominator();
    println!("\nDC motor, eq. (17): km / (J L s^2 + (J R + B L) s + (B R + km kb))");
    println!("  numerator km = {} | 0.00449", motor.km);
    println!(
        "  denominator: {:.4e} {:.9} {:.5} | 2.637e-9 0.001148843 27.19 (B R + km kb is 20.19: misprint)",
        den[0], den[1], den[2]
    );
    println!(
        "  stall torque at {} V: {:.4} N.m; gravity torque on link 1 at 0.1 rad: {:.3} N.m",
        motor.u_max,
        motor.stall_torque(),
        (plant.m1 * plant.g * plant.l1 / 2.0 + plant.m2 * plant.g * plant.l1) * 0.1f64.sin()
    );
}
