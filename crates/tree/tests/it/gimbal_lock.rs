//! Hard case: gimbal lock of the preprint's 3-DOF hinge (three hinges through two massless,
//! zero-length links). When the middle hinge turns 90°, e1 and e3 are parallel: the three
//! axes span only a plane, the mass matrix is singular and the hinge accelerations are
//! undetermined. The engine must refuse, name the hinges, still solve close to the lock, and
//! solve at the lock once a (documented) armature regularises it.

use crate::common;
use nalgebra::DVector;

use common::satellite;
use satsim_tree::aba::aba;
use satsim_tree::cholesky::crba_cholesky;
use satsim_tree::*;
use std::f64::consts::FRAC_PI_2;

fn state(model: &Model, middle: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut q = model.neutral();
    q[7..].copy_from_slice(&[0.3, middle, 0.1, 1.2, -1.0]);
    let v = vec![
        0.001, -0.002, 0.0015, 0.0, 0.0, 0.0, 0.01, 0.02, -0.01, 0.05, -0.04,
    ];
    let mut tau = vec![0.0; model.nv()];
    tau[10] = 0.4;
    tau[9] = -0.5;
    (q, v, tau)
}

#[test]
fn lock_is_refused_naming_the_three_hinges() {
    let model = satellite(0.0);
    let mut data = Data::new(&model);
    let (q, v, tau) = state(&model, FRAC_PI_2);
    let err = aba(&model, &mut data, &q, &v, &tau, None).unwrap_err();
    match &err {
        DynamicsError::SingularHinge { hinge, through, .. } => {
            assert_eq!(hinge, "h1");
            assert_eq!(through, &["h2".to_string(), "h3".to_string()]);
        }
        other => panic!("expected a singular hinge, got {other:?}"),
    }
    let message = err.to_string();
    assert!(
        message.contains("gimbal lock") && message.contains("`h2`") && message.contains("armature"),
        "{message}"
    );
    // The second path refuses too: M is not positive definite at the lock.
    assert!(crba_cholesky(&model, &mut data, &q, &v, &tau, None).is_err());
}

#[test]
fn near_lock_both_paths_solve_and_agree_within_the_conditioning() {
    let model = satellite(0.0);
    let mut data = Data::new(&model);
    for delta in [1e-3, 1e-4, 1e-5] {
        let (q, v, tau) = state(&model, FRAC_PI_2 - delta);
        let by_aba = aba(&model, &mut data, &q, &v, &tau, None).unwrap().clone();
        let by_crba = crba_cholesky(&model, &mut data, &q, &v, &tau, None)
            .unwrap()
            .clone();
        let m = crba(&model, &mut data, &q).unwrap().clone();
        let eig = m.symmetric_eigenvalues();
        let cond = eig.max() / eig.min();
        let rel = (&by_aba - &by_crba).amax() / by_aba.amax();
        println!(
            "δ = {delta:e}: κ(M) = {cond:.3e}, relative difference {rel:.3e}, κε = {:.3e}",
            cond * f64::EPSILON
        );
        // κ grows like 1/δ²; the two solutions agree to the textbook forward-error bound κ ε.
        assert!(cond > 0.1 / (delta * delta), "κ should grow like δ⁻²");
        assert!(
            rel < cond * f64::EPSILON,
            "δ = {delta:e}: {rel:e} > κε = {:e}",
            cond * f64::EPSILON
        );
        // And the solution is a solution: RNEA reproduces τ (a backward error, no κ).
        let back = rnea(&model, &mut data, &q, &v, by_aba.as_slice(), None)
            .unwrap()
            .clone();
        let scale = (m.abs() * by_aba.abs()).amax();
        assert!((&back - DVector::from_column_slice(&tau)).amax() < 1e-12 * scale.max(1.0));
    }
}

#[test]
fn armature_regularises_the_lock() {
    let model = satellite(1e-3);
    let mut data = Data::new(&model);
    let (q, v, tau) = state(&model, FRAC_PI_2);
    let by_aba = aba(&model, &mut data, &q, &v, &tau, None).unwrap().clone();
    let by_crba = crba_cholesky(&model, &mut data, &q, &v, &tau, None)
        .unwrap()
        .clone();
    let m = crba(&model, &mut data, &q).unwrap().clone();
    let eig = m.symmetric_eigenvalues();
    let cond = eig.max() / eig.min();
    assert!((&by_aba - &by_crba).amax() <= cond * f64::EPSILON * by_aba.amax());
    assert!(by_aba.iter().all(|x| x.is_finite()));
}
