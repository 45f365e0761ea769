//! The gyrostat form of ABA (balanced axisymmetric rotors folded into their carriers, see
//! `satsim_tree::Gyrostat`) against the plain tree form, CRBA + Cholesky and RNEA, on random
//! trees with massless link chains, rotors with and without mass, external forces on every
//! body (rotors included), free and fixed roots.

use nalgebra::DVector;
use satsim_tree::aba::{aba, aba_hybrid};
use satsim_tree::cholesky::crba_cholesky;
use satsim_tree::samples::{SplitMix, random_q, random_tree_with_rotors};
use satsim_tree::spatial::{Force, Mat3, Vec3};
use satsim_tree::*;

fn state(model: &Model, rng: &mut SplitMix) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<Force>) {
    let q = random_q(model, rng, 5.0);
    // Rotor rates up to 100 rad/s: the gyroscopic terms dominate.
    let v = (0..model.nv())
        .map(|k| {
            let fast = k >= model.nv() - model.gyrostats().len();
            rng.range(-1.0, 1.0) * if fast { 100.0 } else { 1.0 }
        })
        .collect();
    let tau = (0..model.nv()).map(|_| rng.range(-2.0, 2.0)).collect();
    let fext = (0..model.n_bodies())
        .map(|_| Force::new(rng.vec3(1.0), rng.vec3(1.0)))
        .collect();
    (q, v, tau, fext)
}

fn rel(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax() / a.amax().max(b.amax()).max(1.0)
}

#[test]
fn gyrostat_form_equals_the_tree_form() {
    let (mut worst, mut worst_abs): (f64, f64) = (0.0, 0.0);
    for seed in 0..300u64 {
        let mut rng = SplitMix(seed ^ 0x9e37);
        let n = 2 + (seed % 25) as usize;
        let base = if seed % 3 == 0 {
            BaseKind::Fixed
        } else {
            BaseKind::Free
        };
        let rotors = 1 + (seed % 4) as usize;
        let model = random_tree_with_rotors(n, base, seed % 2 == 0, rotors, seed);
        assert_eq!(model.gyrostats().len(), rotors, "seed {seed}");
        let tree = model.without_gyrostats();
        assert!(tree.gyrostats().is_empty());
        let (q, v, tau, fext) = state(&model, &mut rng);
        let mut d = Data::new(&model);
        for f in [None, Some(fext.as_slice())] {
            let gyro = aba(&model, &mut d, &q, &v, &tau, f).unwrap().clone();
            let plain = aba(&tree, &mut d, &q, &v, &tau, f).unwrap().clone();
            let chol = crba_cholesky(&tree, &mut d, &q, &v, &tau, f)
                .unwrap()
                .clone();
            let m = crba(&tree, &mut d, &q).unwrap().clone();
            let cond = {
                let e = m.clone().symmetric_eigenvalues();
                e.max() / e.min()
            };
            // The two forms agree to 1e-12 (measured: 4e-14 at worst); against CRBA +
            // Cholesky, two backward-stable solutions agree to about κ(M) ε (properties.rs).
            let tol = (cond * f64::EPSILON).max(1e-12);
            let e = rel(&gyro, &plain);
            worst = worst.max(e / tol);
            worst_abs = worst_abs.max(e);
            assert!(
                e < 1e-12,
                "seed {seed}: gyrostat vs tree {e:e} (κ {cond:e})"
            );
            assert!(
                rel(&gyro, &chol) < tol,
                "seed {seed}: gyrostat vs crba {:e}",
                rel(&gyro, &chol)
            );
            // Backward error in RNEA (which keeps the rotors as bodies): no κ.
            let back = rnea(&tree, &mut d, &q, &v, gyro.as_slice(), f)
                .unwrap()
                .clone();
            let b = bias(&tree, &mut d, &q, &v, f).unwrap().clone();
            let scale = (m.abs() * gyro.abs()).amax()
                + b.amax()
                + tau.iter().fold(0.0f64, |a, t| a.max(t.abs()));
            let res = (&back - DVector::from_column_slice(&tau)).amax() / scale;
            assert!(res < 1e-13, "seed {seed}: rnea(aba) residual {res:e}");
        }
    }
    eprintln!("gyrostat vs tree: worst relative difference {worst_abs:e}");
    assert!(worst < 1.0);
}

#[test]
fn only_balanced_axisymmetric_rotors_without_armature_are_gyrostats() {
    let rotor = |com: Vec3, inertia: Mat3, armature: f64| {
        ModelBuilder::new(BaseKind::Free)
            .body(Body::new("bus", 10.0, Mat3::identity()))
            .body(Body::new("wheel", 1.0, inertia).with_com(com))
            .hinge(
                Hinge::revolute("w", "bus", "wheel", Vec3::z())
                    .at(Vec3::new(0.3, 0.0, 0.0))
                    .armature(armature),
            )
            .build()
            .unwrap()
    };
    let sym = Mat3::from_diagonal(&Vec3::new(0.05, 0.05, 0.1));
    let m = rotor(Vec3::new(0.0, 0.0, 0.2), sym, 0.0);
    assert_eq!(m.gyrostats().len(), 1);
    assert_eq!(m.gyrostats()[0].axial(), 0.1);
    // Centre of mass off the axis, unequal transverse moments, armature: plain bodies.
    assert!(
        rotor(Vec3::new(0.01, 0.0, 0.0), sym, 0.0)
            .gyrostats()
            .is_empty()
    );
    let asym = Mat3::from_diagonal(&Vec3::new(0.05, 0.06, 0.1));
    assert!(rotor(Vec3::zeros(), asym, 0.0).gyrostats().is_empty());
    assert!(rotor(Vec3::zeros(), sym, 0.01).gyrostats().is_empty());
    // A rotor with children is not a leaf (the tip, unbalanced, is no rotor either).
    let m = ModelBuilder::new(BaseKind::Free)
        .body(Body::new("bus", 10.0, Mat3::identity()))
        .body(Body::new("wheel", 1.0, sym))
        .body(Body::new("tip", 1.0, asym).with_com(Vec3::y()))
        .hinge(Hinge::revolute("w", "bus", "wheel", Vec3::z()))
        .hinge(Hinge::revolute("t", "wheel", "tip", Vec3::x()))
        .build()
        .unwrap();
    assert!(m.gyrostats().is_empty());
}

#[test]
fn hybrid_dynamics_with_a_locked_rotor_keeps_the_rotor_a_body() {
    let model = random_tree_with_rotors(6, BaseKind::Free, true, 2, 11);
    let mut rng = SplitMix(5);
    let (q, v, tau, _) = state(&model, &mut rng);
    let mut locked = vec![false; model.n_hinges()];
    let nh = model.n_hinges();
    locked[nh - 1] = true;
    let mut d = Data::new(&model);
    let a = aba_hybrid(&model, &mut d, &q, &v, &tau, None, &locked)
        .unwrap()
        .clone();
    let b = aba_hybrid(
        &model.without_gyrostats(),
        &mut d,
        &q,
        &v,
        &tau,
        None,
        &locked,
    )
    .unwrap()
    .clone();
    assert_eq!(a, b);
    assert_eq!(a[model.nv() - 1], 0.0);
}
