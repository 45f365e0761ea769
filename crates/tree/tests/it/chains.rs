//! The multi-axis form of ABA for chains of hinges through massless zero-length links
//! (`satsim_tree::Chain`) on the preprint satellite: its 3-DOF gimbal is one spherical chain,
//! and the chain form agrees with the tree form (every link a body) away from, near and at
//! the gimbal lock (the same refusal, naming the same hinges).

use crate::common;
use nalgebra::DVector;
use satsim_tree::spatial::{Force, Vec3};

use common::satellite;
use satsim_tree::aba::aba;
use satsim_tree::*;
use std::f64::consts::FRAC_PI_2;

fn state(model: &Model, middle: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<Force>) {
    let mut q = model.neutral();
    q[..4].copy_from_slice(&[0.9, 0.1, -0.3, 0.2]);
    let n = q[..4].iter().map(|x| x * x).sum::<f64>().sqrt();
    q[..4].iter_mut().for_each(|x| *x /= n);
    q[7..].copy_from_slice(&[0.3, middle, 0.1, 1.2, -1.0]);
    let v = vec![
        0.01, -0.02, 0.015, 0.1, 0.2, -0.1, 0.3, 0.2, -0.1, 0.5, -0.4,
    ];
    let tau = vec![0.1, -0.2, 0.3, 1.0, -2.0, 0.5, 0.2, -0.3, 0.1, 0.4, -0.5];
    let fext = (0..model.n_bodies())
        .map(|i| {
            let s = i as f64;
            Force::new(Vec3::new(0.1 * s, -0.2, 0.3), Vec3::new(1.0, s, -0.5))
        })
        .collect();
    (q, v, tau, fext)
}

fn rel(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax() / a.amax().max(b.amax())
}

#[test]
fn the_satellite_gimbal_is_one_spherical_chain() {
    let model = satellite(0.0);
    let chains = model.chains();
    assert_eq!(chains.len(), 1);
    let c = &chains[0];
    let name = |i: usize| model.bodies()[i].name();
    assert_eq!(c.hinges(), 3);
    assert_eq!(name(c.tip()), "panel1");
    assert_eq!(name(c.parent()), "bus");
    let links: Vec<&str> = c.links().iter().map(|&i| name(i)).collect();
    assert_eq!(links, ["link2", "link1"]);
    assert!(model.without_chains().chains().is_empty());
}

#[test]
fn chain_form_equals_tree_form_on_the_satellite() {
    for armature in [0.0, 1e-3, 0.2] {
        let model = satellite(armature);
        let tree = model.without_chains();
        let mut d = Data::new(&model);
        let mut dt = Data::new(&tree);
        for middle in [0.0, -0.7, 1.3] {
            let (q, v, tau, fext) = state(&model, middle);
            for f in [None, Some(fext.as_slice())] {
                let a = aba(&model, &mut d, &q, &v, &tau, f).unwrap().clone();
                let b = aba(&tree, &mut dt, &q, &v, &tau, f).unwrap().clone();
                let e = rel(&a, &b);
                assert!(e < 1e-12, "armature {armature}, middle {middle}: {e:e}");
                for i in 0..model.n_bodies() {
                    let diff = (d.a[i].to_vector() - dt.a[i].to_vector()).amax();
                    assert!(diff < 1e-12 * b.amax(), "body {i}: {diff:e}");
                }
            }
        }
    }
}

#[test]
fn at_the_lock_both_forms_refuse_naming_the_same_hinges_and_agree_near_it() {
    let model = satellite(0.0);
    let tree = model.without_chains();
    let (mut d, mut dt) = (Data::new(&model), Data::new(&tree));
    let names = |e: DynamicsError| match e {
        DynamicsError::SingularHinge { hinge, through, .. } => (hinge, through),
        other => panic!("{other}"),
    };
    for lock in [FRAC_PI_2, -FRAC_PI_2] {
        let (q, v, tau, _) = state(&model, lock);
        let a = aba(&model, &mut d, &q, &v, &tau, None).unwrap_err();
        let b = aba(&tree, &mut dt, &q, &v, &tau, None).unwrap_err();
        let (a, b) = (names(a), names(b));
        assert_eq!(a, b);
        assert_eq!(a.0, "h1");
    }
    // Closer than about 3e-7 rad the relative pivot falls under 1e-13: both refuse alike.
    let (q, v, tau, _) = state(&model, FRAC_PI_2 - 1e-7);
    let a = aba(&model, &mut d, &q, &v, &tau, None).unwrap_err();
    let b = aba(&tree, &mut dt, &q, &v, &tau, None).unwrap_err();
    assert_eq!(names(a), names(b));
    for delta in [1e-3, 1e-4, 1e-5, 1e-6] {
        let (q, v, tau, fext) = state(&model, FRAC_PI_2 - delta);
        let a = aba(&model, &mut d, &q, &v, &tau, Some(&fext))
            .unwrap()
            .clone();
        let b = aba(&tree, &mut dt, &q, &v, &tau, Some(&fext))
            .unwrap()
            .clone();
        let m = crba(&tree, &mut dt, &q).unwrap().clone();
        let eig = m.symmetric_eigenvalues();
        let cond = eig.max() / eig.min();
        let e = rel(&a, &b);
        println!("δ = {delta:e}: κ = {cond:.2e}, chain vs tree {e:.2e}");
        assert!(e < (cond * f64::EPSILON).max(1e-12), "δ = {delta:e}: {e:e}");
        // And the chain form's solution is a solution: RNEA reproduces τ (no κ).
        let back = rnea(&tree, &mut dt, &q, &v, a.as_slice(), Some(&fext))
            .unwrap()
            .clone();
        let scale = (m.abs() * a.abs()).amax() + 10.0;
        let res = (&back - DVector::from_column_slice(&tau)).amax() / scale;
        println!("  rnea residual {res:.2e}");
        assert!(res < 1e-13, "δ = {delta:e}: residual {res:e}");
    }
}
