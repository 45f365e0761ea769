//! Unit tests of the method coefficients.

use crate::{dop853, dp54, radau5};

fn assert_close(a: f64, b: f64, tol: f64, what: &str) {
    assert!((a - b).abs() <= tol, "{what}: {a} vs {b}");
}

#[test]
fn dp54_rows_sum_to_nodes() {
    for (i, row) in dp54::A.iter().enumerate() {
        assert_close(row.iter().sum(), dp54::C[i], 1e-15, &format!("row {i}"));
    }
    assert_close(dp54::E.iter().sum(), 0.0, 1e-16, "error weights");
    // The dense output must reproduce the step end: Σ d_j = 0 keeps r4 from moving it.
    assert_close(dp54::D.iter().sum(), 0.0, 1e-12, "dense weights");
}

#[test]
fn dop853_rows_sum_to_nodes() {
    for (i, row) in dop853::A.iter().enumerate() {
        assert_close(row.iter().sum(), dop853::C[i], 1e-14, &format!("row {i}"));
    }
    assert_close(dop853::B.iter().sum(), 1.0, 1e-14, "b");
    assert_close(dop853::BHH.iter().sum(), 1.0, 1e-14, "bhh");
    assert_close(dop853::ER.iter().sum(), 0.0, 1e-14, "er");
    // Order-8 quadrature condition Σ b_j c_j^7 = 1/8 (only a correct b passes).
    let q: f64 = dop853::B
        .iter()
        .zip(&dop853::C)
        .map(|(b, c)| b * c.powi(7))
        .sum();
    assert_close(q, 1.0 / 8.0, 1e-13, "Σ b c^7");
}

#[test]
fn radau5_coefficients() {
    for i in 0..3 {
        assert_close(
            radau5::A[i].iter().sum(),
            radau5::C[i],
            1e-15,
            &format!("row {i}"),
        );
    }
    // Stiffly accurate: the last row is b, whose quadrature is exact to degree 4.
    for p in 0..5 {
        let q: f64 = (0..3).map(|j| radau5::A[2][j] * radau5::C[j].powi(p)).sum();
        assert_close(q, 1.0 / (p as f64 + 1.0), 1e-14, &format!("Σ b c^{p}"));
    }
    // u1 is the real eigenvalue of A⁻¹: det(A - I/u1) = 0.
    let g = 1.0 / radau5::u1();
    let a = radau5::A;
    let m = |i: usize, j: usize| a[i][j] - if i == j { g } else { 0.0 };
    let det = m(0, 0) * (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1))
        - m(0, 1) * (m(1, 0) * m(2, 2) - m(1, 2) * m(2, 0))
        + m(0, 2) * (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0));
    assert_close(det, 0.0, 1e-14, "det(A - γ0 I)");
}

#[test]
fn radau5_eigenbasis_diagonalises_the_inverse_butcher_matrix() {
    let (t, ti, a) = (radau5::T, radau5::TI, radau5::A);
    // T T⁻¹ = I.
    for i in 0..3 {
        for j in 0..3 {
            let p: f64 = (0..3).map(|k| t[i][k] * ti[k][j]).sum();
            let id = if i == j { 1.0 } else { 0.0 };
            assert_close(p, id, 1e-14, &format!("(T T⁻¹)[{i}][{j}]"));
        }
    }
    // A⁻¹ T = T Λ, i.e. A T Λ = T, with Λ = [[γ, 0, 0], [0, α, -β], [0, β, α]].
    let (al, be) = radau5::alpha_beta();
    let lam = [[radau5::u1(), 0.0, 0.0], [0.0, al, -be], [0.0, be, al]];
    for i in 0..3 {
        for j in 0..3 {
            let atl: f64 = (0..3)
                .flat_map(|k| (0..3).map(move |l| (k, l)))
                .map(|(k, l)| a[i][k] * t[k][l] * lam[l][j])
                .sum();
            assert_close(atl, t[i][j], 1e-14, &format!("(A T Λ)[{i}][{j}]"));
        }
    }
}
