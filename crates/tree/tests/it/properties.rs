//! Properties that a wrong engine would break, on random trees (branching, up to 50 bodies,
//! massless links, free and fixed roots, random axes, offsets and rotations):
//! ABA, CRBA + Cholesky and RNEA agree; M is symmetric positive definite; T = ½ vᵀ M v;
//! M is the Hessian of T in v (finite differences of kinematics alone); dT/dt = τ · q̇.

use nalgebra::{DMatrix, DVector, Quaternion, UnitQuaternion};
use proptest::prelude::*;
use satsim_tree::aba::{aba, aba_hybrid};
use satsim_tree::cholesky::crba_cholesky;
use satsim_tree::samples::{SplitMix, random_tree};
use satsim_tree::*;

struct Case {
    model: Model,
    q: Vec<f64>,
    v: Vec<f64>,
    tau: Vec<f64>,
}

fn case(n: usize, free: bool, massless: bool, seed: u64) -> Case {
    let base = if free {
        BaseKind::Free
    } else {
        BaseKind::Fixed
    };
    let model = random_tree(n, base, massless, seed);
    let mut rng = SplitMix(seed ^ 0x5eed);
    let mut q = model.neutral();
    if free {
        let att = Quaternion::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        )
        .normalize();
        q[..4].copy_from_slice(
            att.coords
                .as_slice()
                .iter()
                .cycle()
                .skip(3)
                .take(4)
                .copied()
                .collect::<Vec<_>>()
                .as_slice(),
        );
        for x in &mut q[4..7] {
            *x = rng.range(-10.0, 10.0);
        }
    }
    let nb = model.base_nq();
    for x in &mut q[nb..] {
        *x = rng.range(-3.0, 3.0);
    }
    let v = (0..model.nv()).map(|_| rng.range(-1.0, 1.0)).collect();
    let mut tau: Vec<f64> = (0..model.nv()).map(|_| rng.range(-2.0, 2.0)).collect();
    for t in &mut tau[..model.base_nv()] {
        *t *= 0.5;
    }
    Case { model, q, v, tau }
}

fn rel(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax() / a.amax().max(b.amax()).max(1.0)
}

fn strategy() -> impl Strategy<Value = (usize, bool, bool, u64)> {
    (2usize..=50, any::<bool>(), any::<bool>(), any::<u64>())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn aba_crba_cholesky_and_rnea_agree((n, free, massless, seed) in strategy()) {
        let c = case(n, free, massless, seed);
        let mut d = Data::new(&c.model);
        let by_aba = aba(&c.model, &mut d, &c.q, &c.v, &c.tau, None).unwrap().clone();
        let by_crba = crba_cholesky(&c.model, &mut d, &c.q, &c.v, &c.tau, None).unwrap().clone();
        // Two backward-stable solvers agree to a forward error bounded by about κ(M) ε: the
        // bound is 1e-12 relative while κ ≤ 4500, κ ε beyond (random trees reach κ ~ 1e6;
        // the measured errors sit near 0.1 κ ε).
        let m = crba(&c.model, &mut d, &c.q).unwrap().clone();
        let cond = { let e = m.clone().symmetric_eigenvalues(); e.max() / e.min() };
        let tol = (cond * f64::EPSILON).max(1e-12);
        prop_assert!(rel(&by_aba, &by_crba) < tol, "aba vs crba: {:e} (cond {cond:e})", rel(&by_aba, &by_crba));
        let b = bias(&c.model, &mut d, &c.q, &c.v, None).unwrap().clone();
        let tau = rnea(&c.model, &mut d, &c.q, &c.v, by_aba.as_slice(), None).unwrap().clone();
        // The residual of ABA's answer in the inverse dynamics is a backward error: measured
        // against the size of the terms that cancel, |M||q̈| + |C| + |τ|, with no κ.
        let scale = (m.abs() * by_aba.abs()).amax() + b.amax() + c.tau.iter().fold(0.0f64, |a, t| a.max(t.abs()));
        let residual = (&tau - DVector::from_column_slice(&c.tau)).amax() / scale;
        prop_assert!(residual < 1e-13, "rnea(aba) residual {residual:e}");
    }

    #[test]
    fn rnea_is_mass_matrix_times_a_plus_bias((n, free, massless, seed) in strategy()) {
        let c = case(n, free, massless, seed);
        let mut d = Data::new(&c.model);
        let a = DVector::from_iterator(c.model.nv(), c.tau.iter().map(|t| t * 1.7 - 0.3));
        let m = crba(&c.model, &mut d, &c.q).unwrap().clone();
        let b = bias(&c.model, &mut d, &c.q, &c.v, None).unwrap().clone();
        let tau = rnea(&c.model, &mut d, &c.q, &c.v, a.as_slice(), None).unwrap().clone();
        prop_assert!(rel(&tau, &(&m * &a + &b)) < 1e-12);
    }

    #[test]
    fn mass_matrix_is_spd_and_gives_kinetic_energy((n, free, massless, seed) in strategy()) {
        let c = case(n, free, massless, seed);
        let mut d = Data::new(&c.model);
        let m = crba(&c.model, &mut d, &c.q).unwrap().clone();
        prop_assert_eq!(&m, &m.transpose());
        prop_assert!(m.clone().cholesky().is_some());
        prop_assert!(m.clone().symmetric_eigenvalues().min() > 0.0);
        let v = DVector::from_column_slice(&c.v);
        let t = kinetic_energy(&c.model, &mut d, &c.q, &c.v).unwrap();
        let quad = 0.5 * v.dot(&(&m * &v));
        prop_assert!((t - quad).abs() <= 1e-12 * t.abs().max(1e-3), "T {t} vs ½vᵀMv {quad}");
    }
}

/// The Hessian of T(v) by central differences uses only forward kinematics and the bodies'
/// inertias, not CRBA. T is quadratic in v, so the differences are exact up to rounding.
#[test]
fn mass_matrix_is_the_hessian_of_kinetic_energy() {
    for (seed, n, free) in [
        (1u64, 8usize, true),
        (2, 12, false),
        (3, 20, true),
        (4, 5, false),
    ] {
        let c = case(n, free, true, seed);
        let mut d = Data::new(&c.model);
        let m = crba(&c.model, &mut d, &c.q).unwrap().clone();
        let nv = c.model.nv();
        let h = 1e-2;
        let mut hess = DMatrix::zeros(nv, nv);
        let mut t_at = |di: f64, i: usize, dj: f64, j: usize| {
            let mut v = c.v.clone();
            v[i] += di;
            v[j] += dj;
            kinetic_energy(&c.model, &mut d, &c.q, &v).unwrap()
        };
        for i in 0..nv {
            for j in 0..nv {
                hess[(i, j)] = (t_at(h, i, h, j) - t_at(h, i, -h, j) - t_at(-h, i, h, j)
                    + t_at(-h, i, -h, j))
                    / (4.0 * h * h);
            }
        }
        let err = (&hess - &m).amax() / m.amax();
        assert!(
            err < 1e-9,
            "seed {seed}: Hessian of T differs from M by {err:e}"
        );
    }
}

/// Power balance: along the motion produced by ABA, dT/dt = τ · v (no external forces).
/// dT/dt is taken by central differences of T along (q̇, v̇), which uses kinematics only.
#[test]
fn aba_obeys_the_power_balance() {
    for (seed, n, free) in [
        (11u64, 6usize, true),
        (12, 15, false),
        (13, 30, true),
        (14, 3, true),
    ] {
        let c = case(n, free, true, seed);
        let mut d = Data::new(&c.model);
        let vdot = aba(&c.model, &mut d, &c.q, &c.v, &c.tau, None)
            .unwrap()
            .clone();
        let nqb = c.model.base_nq();
        let nvb = c.model.base_nv();
        let step = |s: f64| -> (Vec<f64>, Vec<f64>) {
            let mut q = c.q.clone();
            if nvb == 6 {
                // q̇ of the attitude is ½ q ⊗ (0, ω); the origin moves with R v.
                let att = UnitQuaternion::from_quaternion(Quaternion::new(
                    c.q[0], c.q[1], c.q[2], c.q[3],
                ));
                let w = nalgebra::Vector3::new(c.v[0], c.v[1], c.v[2]);
                let lin = nalgebra::Vector3::new(c.v[3], c.v[4], c.v[5]);
                let turned = att * UnitQuaternion::from_scaled_axis(w * s);
                let r = att * lin * s;
                q[..4].copy_from_slice(&[turned.w, turned.i, turned.j, turned.k]);
                for k in 0..3 {
                    q[4 + k] += r[k];
                }
            }
            for k in 0..c.model.n_hinges() {
                q[nqb + k] += c.v[nvb + k] * s;
            }
            let v: Vec<f64> =
                c.v.iter()
                    .zip(vdot.iter())
                    .map(|(v, a)| v + a * s)
                    .collect();
            (q, v)
        };
        let h = 1e-5;
        let (qp, vp) = step(h);
        let (qm, vm) = step(-h);
        let tp = kinetic_energy(&c.model, &mut d, &qp, &vp).unwrap();
        let tm = kinetic_energy(&c.model, &mut d, &qm, &vm).unwrap();
        let dtdt = (tp - tm) / (2.0 * h);
        let power: f64 = c.tau.iter().zip(&c.v).map(|(t, v)| t * v).sum();
        assert!(
            (dtdt - power).abs() < 1e-6 * power.abs().max(1.0),
            "seed {seed}: dT/dt {dtdt} vs τ·v {power}"
        );
    }
}

/// Hybrid dynamics with locked hinges equals ABA on the same tree where each locked hinge's
/// acceleration is forced to zero: checked against the mass-matrix equations restricted to
/// the free coordinates, `M_ff q̈_f = τ_f − C_f`.
#[test]
fn hybrid_dynamics_matches_the_reduced_mass_matrix_equations() {
    for (seed, n, free) in [(21u64, 8usize, true), (22, 14, false), (23, 25, true)] {
        let c = case(n, free, true, seed);
        let mut d = Data::new(&c.model);
        let mut rng = SplitMix(seed);
        let locked: Vec<bool> = (0..c.model.n_hinges())
            .map(|_| rng.next_f64() < 0.4)
            .collect();
        let ddq = aba_hybrid(&c.model, &mut d, &c.q, &c.v, &c.tau, None, &locked)
            .unwrap()
            .clone();
        let m = crba(&c.model, &mut d, &c.q).unwrap().clone();
        let b = bias(&c.model, &mut d, &c.q, &c.v, None).unwrap().clone();
        let nb = c.model.base_nv();
        let free_idx: Vec<usize> = (0..c.model.nv())
            .filter(|&i| i < nb || !locked[i - nb])
            .collect();
        let mff = DMatrix::from_fn(free_idx.len(), free_idx.len(), |r, s| {
            m[(free_idx[r], free_idx[s])]
        });
        let rhs = DVector::from_fn(free_idx.len(), |r, _| c.tau[free_idx[r]] - b[free_idx[r]]);
        let expected = mff.cholesky().unwrap().solve(&rhs);
        for (r, &i) in free_idx.iter().enumerate() {
            assert!(
                (ddq[i] - expected[r]).abs() < 1e-9 * expected.amax().max(1.0),
                "seed {seed}: coordinate {i}"
            );
        }
        for (k, &l) in locked.iter().enumerate() {
            if l {
                assert_eq!(ddq[nb + k], 0.0);
            }
        }
    }
}

/// A hinge impulse conserves the system's momentum (it acts between two bodies of the tree)
/// and changes the hinge rate by (M⁻¹)_kk per unit impulse.
#[test]
fn hinge_impulse_conserves_momentum() {
    let c = case(12, true, true, 31);
    let mut d = Data::new(&c.model);
    for k in 0..c.model.n_hinges() {
        let dv = impulse::hinge_impulse(&c.model, &mut d, &c.q, k)
            .unwrap()
            .clone();
        let m = crba(&c.model, &mut d, &c.q).unwrap().clone();
        // M Δv = e_k: zero generalised impulse on the base, i.e. no net external impulse.
        let mdv = &m * &dv;
        for r in 0..c.model.nv() {
            let expected = if r == 6 + k { 1.0 } else { 0.0 };
            assert!(
                (mdv[r] - expected).abs() < 1e-10,
                "hinge {k} row {r}: {}",
                mdv[r]
            );
        }
        let v0: Vec<f64> = c.v.clone();
        let v1: Vec<f64> =
            c.v.iter()
                .zip(dv.iter())
                .map(|(a, b)| a + 0.3 * b)
                .collect();
        forward_kinematics(&c.model, &mut d, &c.q, &v0).unwrap();
        let (p0, h0) = momentum(&c.model, &d);
        forward_kinematics(&c.model, &mut d, &c.q, &v1).unwrap();
        let (p1, h1) = momentum(&c.model, &d);
        assert!(
            (p1 - p0).norm() < 1e-10 && (h1 - h0).norm() < 1e-10,
            "hinge {k}"
        );
    }
}
