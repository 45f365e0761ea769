//! The flexible-body engine (`satsim_tree::flexible`): beam modes against the closed forms,
//! RNEA, CRBA and ABA against each other, the rigid algorithms when no mode is kept, energy
//! conservation, an independent discretisation (rigid chains with hinge springs) and no
//! allocation per call.

use nalgebra::{DMatrix, DVector, Quaternion, SymmetricEigen};
use satsim_testkit::alloc::allocations;
use satsim_tree::flexible::beam::{
    BETA1_L, CantileverMode, PANELS, POINTS, beta_l, gauss_legendre, integrate,
};
use satsim_tree::flexible::{
    self, Beam, FlexData, FlexModel, Flexible, ModalData, Modes, NodeShape,
};
use satsim_tree::samples::{SplitMix, random_tree};
use satsim_tree::spatial::{Force, Mat3, Vec3};
use satsim_tree::{BaseKind, Body, Data, DynamicsError, Hinge, Model, ModelBuilder};

/// The contract's example beam along `axis`, bending along `bend`, rooted at the origin.
fn beam(axis: Vec3, bend: Vec3, modes: usize) -> Beam {
    Beam {
        root: Vec3::zeros(),
        axis,
        bend,
        length: 2.0,
        ei: 500.0,
        rho_a: 5.0,
        modes,
    }
}

/// The relative error `|a − b| / max(|a|, |b|)` (0 for two zeros).
fn rel(a: f64, b: f64) -> f64 {
    let s = a.abs().max(b.abs());
    if s == 0.0 { 0.0 } else { (a - b).abs() / s }
}

// 1. βL roots and the cantilever frequencies.
#[test]
fn beta_roots_and_frequencies() {
    // The roots of cos x cosh x = −1 to 16 digits (Blevins' table), then the asymptote.
    let table = [
        BETA1_L,
        4.694_091_132_974_175,
        7.854_757_438_237_613,
        10.995_540_734_875_47,
    ];
    for (k, &t) in table.iter().enumerate() {
        let b = beta_l(k + 1);
        assert!(rel(b, t) < 1e-14, "mode {}: {b} vs {t}", k + 1);
        assert!((b.cos() * b.cosh() + 1.0).abs() < 1e-10 * b.cosh());
    }
    for n in 5..=12 {
        let b = beta_l(n);
        // The root to the last bits: the residual is the function's slope (≈ 1) times an ulp.
        assert!(
            (b.cos() + 1.0 / b.cosh()).abs() < 4.0 * f64::EPSILON * b,
            "mode {n}"
        );
        assert!((b - (2 * n - 1) as f64 * std::f64::consts::FRAC_PI_2).abs() < 1e-5);
    }
    let bm = beam(Vec3::y(), Vec3::z(), 4);
    for (k, &t) in table.iter().enumerate() {
        let closed = t * t * (bm.ei / (bm.rho_a * bm.length.powi(4))).sqrt();
        assert!(rel(bm.omega(k + 1), closed) < 1e-10);
    }
    // The model's modal stiffness is ω².
    let model = FlexModel::build(
        ModelBuilder::new(BaseKind::Fixed).body(Body::new("beam", 0.0, Mat3::zeros())),
        &[Flexible {
            body: "beam".into(),
            modes: Modes::Beam(bm.clone()),
            damping: 0.0,
            stiffening: false,
        }],
    )
    .unwrap();
    for (k, t) in table.iter().enumerate() {
        let w = t * t * 2.5 / (2.0 * std::f64::consts::PI); // Hz
        let model_hz = model.stiffness()[k].sqrt() / (2.0 * std::f64::consts::PI);
        assert!(rel(model_hz, w) < 1e-10, "mode {}", k + 1);
    }
}

// 2. The modal integrals by quadrature.
#[test]
fn modes_are_mass_normalised_and_orthogonal() {
    let bm = Beam {
        modes: 12,
        ..beam(Vec3::y(), Vec3::z(), 12)
    };
    let modes = bm.cantilever_modes();
    let rule = gauss_legendre(POINTS);
    for panels in [PANELS, 2 * PANELS] {
        for i in 0..modes.len() {
            for j in 0..=i {
                let (a, b) = (&modes[i], &modes[j]);
                let mass = bm.rho_a
                    * integrate(bm.length, panels, &rule, |x| a.shape(x)[0] * b.shape(x)[0]);
                let stiff =
                    bm.ei * integrate(bm.length, panels, &rule, |x| a.shape(x)[2] * b.shape(x)[2]);
                let w2 = bm.omega(i + 1).powi(2);
                let (m_ref, k_ref) = if i == j { (1.0, w2) } else { (0.0, 0.0) };
                assert!((mass - m_ref).abs() < 1e-10, "{i} {j}: {mass}");
                assert!(
                    (stiff - k_ref).abs() < 1e-10 * w2,
                    "{i} {j}: {stiff} vs {k_ref}"
                );
            }
        }
    }
    // The clamped end and the free end's boundary conditions.
    for m in &modes {
        let [f0, d0, _] = m.shape(0.0);
        let [_, _, dd] = m.shape(bm.length);
        assert!(f0.abs() < 1e-12 && d0.abs() < 1e-12 && dd.abs() < 1e-9 * m.beta().powi(2));
    }
    // The momentum coefficients against a plain sum at twice the panels.
    let p = bm.momentum_coefficients();
    for (k, m) in modes.iter().enumerate() {
        let s1 = bm.rho_a * integrate(bm.length, 2 * PANELS, &rule, |x| m.shape(x)[0]);
        assert!((p[k].lin - Vec3::z() * s1).norm() < 1e-13);
    }
    let _ = CantileverMode::new(1, 1.0, 1.0);
}

/// The random flexible tree of the tests that sweep seeds: 3 to 10 bodies, a fixed base for
/// every third seed, else a free one (`random_flexible`'s `massless_links`).
pub(crate) fn seeded_flexible(seed: u64, massless_links: bool) -> FlexModel {
    random_flexible(
        3 + (seed % 8) as usize,
        seeded_base(seed),
        massless_links,
        seed,
    )
}

/// The seed sweeps' base: fixed for every third seed, else free.
fn seeded_base(seed: u64) -> BaseKind {
    if seed.is_multiple_of(3) {
        BaseKind::Fixed
    } else {
        BaseKind::Free
    }
}

/// How many bodies of `model` hang on a flexible parent (on a node of its deflection).
pub(crate) fn carried_bodies(model: &FlexModel) -> usize {
    (1..model.rigid().n_bodies())
        .filter(|&i| model.modes(model.rigid().parent()[i].unwrap()) > 0)
        .count()
}

/// A random flexible tree: `random_tree`'s bodies and hinges, some bodies (the root among
/// them for odd seeds) flexible: beams of random placement, or given modal data with
/// general node shapes (three rotation stages). With `massless_links`, some bodies are
/// massless links of 2- and 3-hinge chains (`random_tree`'s).
pub(crate) fn random_flexible(
    n: usize,
    base: BaseKind,
    massless_links: bool,
    seed: u64,
) -> FlexModel {
    with_random_modes(random_tree(n, base, massless_links, seed), seed)
}

/// `rigid` with random bodies made flexible, as [`random_flexible`] makes them (for odd
/// seeds the root among them; never a massless body).
pub(crate) fn with_random_modes(rigid: Model, seed: u64) -> FlexModel {
    with_random_modes_up_to(rigid, seed, 4)
}

/// [`with_random_modes`] with 1 to `most` modes a flexible body (4 there: the mode counts the
/// flexible algorithms have instances for).
pub(crate) fn with_random_modes_up_to(rigid: Model, seed: u64, most: usize) -> FlexModel {
    let mut rng = SplitMix(seed ^ 0xf1e8);
    let builder = rigid.to_builder();
    let mut flex = Vec::new();
    for (i, b) in rigid.bodies().iter().enumerate() {
        // Massless links stay rigid (the chains' links: `flexible_chains.rs`).
        if b.mass() == 0.0 && *b.inertia_com() == Mat3::zeros() {
            continue;
        }
        let pick = if i == 0 {
            seed % 2 == 1
        } else {
            rng.next_f64() < 0.5
        };
        if !pick {
            continue;
        }
        let m = 1 + (rng.next_f64() * most as f64) as usize;
        let damping = rng.range(0.0, 0.05);
        let modes = if rng.next_f64() < 0.5 {
            let axis = rng.unit();
            let bend = axis.cross(&rng.unit()).normalize();
            Modes::Beam(Beam {
                root: rng.vec3(0.3),
                axis,
                bend,
                length: rng.range(0.3, 2.0),
                ei: rng.range(10.0, 500.0),
                rho_a: rng.range(0.5, 3.0),
                modes: m,
            })
        } else {
            // Momentum small enough that [[I, P], [Pᵀ, 1]] stays positive definite.
            let s = 0.2 * (b.mass() * 0.02).sqrt();
            let data = ModalData {
                momentum: (0..m)
                    .map(|_| Force::new(rng.vec3(s), rng.vec3(s)))
                    .collect(),
                omega: (0..m).map(|_| rng.range(1.0, 30.0)).collect(),
            };
            let nodes = rigid
                .hinge_names()
                .iter()
                .enumerate()
                .filter(|(k, _)| rigid.parent()[rigid.hinge_body()[*k]] == Some(i))
                .map(|(_, h)| {
                    (
                        h.clone(),
                        NodeShape {
                            phi: (0..m).map(|_| rng.vec3(0.5)).collect(),
                            psi: (0..m).map(|_| rng.vec3(0.8)).collect(),
                            shortening: None,
                        },
                    )
                })
                .collect();
            Modes::Given {
                data,
                nodes,
                stiffening: None,
                watch: Vec::new(),
            }
        };
        flex.push(Flexible {
            body: b.name().to_string(),
            // Given modes stiffen only with their second-order inertia, which these lack.
            stiffening: !seed.is_multiple_of(4) && matches!(modes, Modes::Beam(_)),
            modes,
            damping,
        });
    }
    FlexModel::build(builder, &flex).expect("random flexible trees are valid")
}

/// A random state: attitude, hinge angles, deformations,
/// rates, accelerations, external forces.
#[allow(clippy::type_complexity)]
pub(crate) fn random_state(
    model: &FlexModel,
    rng: &mut SplitMix,
) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<Force>) {
    let mut q = model.neutral();
    let r = model.rigid();
    let nb = r.base_nq();
    if nb == 7 {
        let a = Quaternion::new(0.4, rng.range(-1.0, 1.0), -0.3, 0.2).normalize();
        q[..4].copy_from_slice(&[a.w, a.i, a.j, a.k]);
        for x in &mut q[4..7] {
            *x = rng.range(-1.0, 1.0);
        }
    }
    for x in &mut q[nb..r.nq()] {
        *x = rng.range(-3.0, 3.0);
    }
    // Small deformations (the model's premise; the foreshortening of stiffened beams keeps
    // their inertia, and with its momentum `−c (η̇ᵀ J₀ η)` their mass matrix, positive only
    // there: at ±0.02 a 0.32 kg beam of 0.43 m with 4 modes is bent to slopes of 2 rad and
    // its mass matrix is indefinite).
    for x in &mut q[r.nq()..] {
        *x = rng.range(-0.01, 0.01);
    }
    let v = (0..model.nv()).map(|_| rng.range(-2.0, 2.0)).collect();
    let a = (0..model.nv()).map(|_| rng.range(-2.0, 2.0)).collect();
    let f = (0..r.n_bodies())
        .map(|_| Force::new(rng.vec3(1.0), rng.vec3(1.0)))
        .collect();
    (q, v, a, f)
}

pub(crate) fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, y| m.max(y.abs()))
}

// 3. RNEA, CRBA and ABA agree.
#[test]
fn rnea_crba_aba_agree_on_random_flexible_trees() {
    let mut flexible_bodies = 0;
    let mut carried = 0;
    let mut worst: f64 = 0.0;
    for seed in 0..40u64 {
        let model = seeded_flexible(seed, false);
        let n = model.rigid().n_bodies();
        flexible_bodies += (0..n).filter(|&i| model.modes(i) > 0).count();
        carried += carried_bodies(&model);
        worst = worst.max(rnea_crba_aba_check(&model, seed));
    }
    println!("ABA vs solve: worst error / bound {worst:e}");
    assert!(
        flexible_bodies > 60 && carried > 40,
        "{flexible_bodies} {carried}"
    );
}

/// RNEA, CRBA and ABA on `model` at a random state from `seed`: `M` symmetric, `M a + b = τ`,
/// `½ vᵀ M v` the kinetic energy, ABA inverting RNEA within the solve's bound; returns the
/// ABA's error against the dense solve over that bound.
fn rnea_crba_aba_check(model: &FlexModel, seed: u64) -> f64 {
    let mut rng = SplitMix(seed ^ 0xabc);
    let (q, v, a, fext) = random_state(model, &mut rng);
    let mut data = FlexData::new(model);
    let tau = flexible::rnea(model, &mut data, &q, &v, &a, Some(&fext))
        .unwrap()
        .clone();
    let m = flexible::crba(model, &mut data, &q).unwrap().clone();
    let b = flexible::bias(model, &mut data, &q, &v, Some(&fext))
        .unwrap()
        .clone();
    assert!(
        (&m - m.transpose()).amax() == 0.0,
        "seed {seed}: M symmetric"
    );
    let av = DVector::from_column_slice(&a);
    let scale = max_abs(tau.as_slice()) + m.amax() * max_abs(&a) + max_abs(b.as_slice());
    let residual = (&m * &av + &b - &tau).amax();
    assert!(
        residual < 1e-12 * scale,
        "seed {seed}: M a + b − τ = {residual:e}"
    );
    // ½ vᵀ M v is the kinetic energy summed body by body.
    let vv = DVector::from_column_slice(&v);
    let (t, _) = flexible::energy(model, &mut data, &q, &v).unwrap();
    assert!(
        rel(0.5 * vv.dot(&(&m * &vv)), t) < 1e-12,
        "seed {seed}: energy"
    );
    // ABA inverts RNEA and equals the dense solve.
    let ddq = flexible::aba(model, &mut data, &q, &v, tau.as_slice(), Some(&fext))
        .unwrap()
        .clone();
    let residual = (&m * &ddq + &b - &tau).amax();
    assert!(
        residual < 1e-12 * scale,
        "seed {seed}: M ddq + b − τ = {residual:e}"
    );
    // The forward error of a solve whose right-hand side τ − b is known to round-off of
    // |τ| + |b|: (|τ| + |b|) ε / λ_min(M).
    let solve = m.clone().cholesky().unwrap().solve(&(&tau - &b));
    let lowest = SymmetricEigen::new(m.clone()).eigenvalues.min();
    let bound = 1e-15 * (tau.amax() + b.amax()) / lowest;
    let err = (&ddq - &solve).amax();
    assert!(
        err < bound,
        "seed {seed}: ABA vs solve {err:e} (bound {bound:e})"
    );
    assert!((&ddq - &av).amax() < bound, "seed {seed}");
    err / bound
}

/// The same beyond the mode counts the algorithms have instances for (1 to 4): bodies of up
/// to 7 modes take the general code of the ABA, the first pass and the node's state (against
/// the node's own `pose`).
#[test]
fn rnea_crba_aba_agree_beyond_the_instanced_mode_counts() {
    let (mut beyond, mut carried_beyond) = (0, 0);
    for seed in 0..24u64 {
        let rigid = random_tree(3 + (seed % 8) as usize, seeded_base(seed), false, seed);
        let model = with_random_modes_up_to(rigid, seed, 7);
        let r = model.rigid();
        beyond += (0..r.n_bodies()).filter(|&i| model.modes(i) > 4).count();
        carried_beyond += (1..r.n_bodies())
            .filter(|&i| model.modes(r.parent()[i].unwrap()) > 4)
            .count();
        rnea_crba_aba_check(&model, seed);
        poses_check(&model, seed);
    }
    assert!(
        beyond > 10 && carried_beyond > 5,
        "{beyond} {carried_beyond}"
    );
}

// Hybrid dynamics: locked hinges have zero acceleration, the rest is the CRBA's system with
// the locked rows and columns removed.
/// A state whose deformation makes the mass matrix indefinite (a large `η` through the
/// inertia's first-order terms) is refused by the ABA naming the pivot that failed, not a
/// positive one, and a coordinate of the system. The two trees and states are of the
/// random family above (its seeds 903 and 1261, drawn the same way) where `M` has a negative
/// eigenvalue.
#[test]
fn an_indefinite_state_is_refused_with_the_failing_pivot() {
    for seed in [903u64, 1261] {
        let model = seeded_flexible(seed, false);
        let mut rng = SplitMix(seed ^ 0xabc);
        let (q, v, a, _) = random_state(&model, &mut rng);
        let mut data = FlexData::new(&model);
        let m = flexible::crba(&model, &mut data, &q).unwrap().clone();
        assert!(
            SymmetricEigen::new(m).eigenvalues.min() < -0.1,
            "seed {seed}: M is indefinite here"
        );
        match flexible::aba(&model, &mut data, &q, &v, &a, None) {
            Err(DynamicsError::NotPositiveDefinite { index, pivot }) => {
                assert!(index < model.nv(), "seed {seed}: coordinate {index}");
                assert!(pivot <= 0.0 || pivot.is_nan(), "seed {seed}: pivot {pivot}");
            }
            other => panic!("seed {seed}: {other:?}"),
        }
    }
}

#[test]
fn hybrid_aba_equals_the_reduced_crba_solve() {
    let mut locked_total = 0;
    let mut worst: f64 = 0.0;
    for seed in 0..40u64 {
        let model = seeded_flexible(seed, false);
        let r = model.rigid();
        let mut rng = SplitMix(seed ^ 0x10c4);
        let locked: Vec<bool> = (0..r.n_hinges())
            .map(|_| rng.range(0.0, 1.0) < 0.4)
            .collect();
        locked_total += locked.iter().filter(|&&l| l).count();
        let (q, v, tau, fext) = random_state(&model, &mut rng);
        let mut data = FlexData::new(&model);
        let m = flexible::crba(&model, &mut data, &q).unwrap().clone();
        let b = flexible::bias(&model, &mut data, &q, &v, Some(&fext))
            .unwrap()
            .clone();
        let base_nv = r.nv() - r.n_hinges();
        let is_locked = |k: usize| k >= base_nv && k < r.nv() && locked[k - base_nv];
        let free: Vec<usize> = (0..model.nv()).filter(|&k| !is_locked(k)).collect();
        let nf = free.len();
        let mff = DMatrix::from_fn(nf, nf, |i, j| m[(free[i], free[j])]);
        let rhs = DVector::from_fn(nf, |i, _| tau[free[i]] - b[free[i]]);
        let solve = mff.clone().cholesky().unwrap().solve(&rhs);
        let ddq = flexible::aba_hybrid(&model, &mut data, &q, &v, &tau, Some(&fext), &locked)
            .unwrap()
            .clone();
        for k in (0..model.nv()).filter(|&k| is_locked(k)) {
            assert_eq!(ddq[k], 0.0, "seed {seed}: locked coordinate {k}");
        }
        // The reduced system's residual (backward error), at the unlocked test's 1e-12 of
        // the scale; the forward error against the dense solve is reported in units of the
        // unlocked test's bound (ABA's pivots condition it differently from the dense solve).
        let xf = DVector::from_fn(nf, |i, _| ddq[free[i]]);
        let scale = max_abs(&tau) + mff.amax() * xf.amax() + b.amax();
        let residual = (&mff * &xf - &rhs).amax();
        assert!(
            residual < 1e-12 * scale,
            "seed {seed}: reduced M ddq + b − τ = {residual:e} (scale {scale:e})"
        );
        let lowest = SymmetricEigen::new(mff).eigenvalues.min();
        let bound = 1e-15 * (max_abs(&tau) + b.amax()) / lowest;
        let err = (&xf - &solve).amax();
        worst = worst.max(err / bound);
        // Nothing locked: the plain ABA, bit for bit.
        let none = vec![false; r.n_hinges()];
        let hybrid = flexible::aba_hybrid(&model, &mut data, &q, &v, &tau, Some(&fext), &none)
            .unwrap()
            .clone();
        let plain = flexible::aba(&model, &mut data, &q, &v, &tau, Some(&fext)).unwrap();
        assert_eq!(&hybrid, plain, "seed {seed}");
    }
    println!(
        "hybrid ABA vs reduced solve: worst forward error / the unlocked bound {worst:e}, {locked_total} locked"
    );
    assert!(locked_total > 40, "{locked_total}");
}

// 4. Without modes, the rigid algorithms.
#[test]
fn without_modes_the_rigid_algorithms() {
    for seed in 0..30u64 {
        let rigid = random_tree(2 + (seed % 10) as usize, seeded_base(seed), false, seed);
        let model = FlexModel::attach(rigid.clone(), &[]).unwrap();
        let mut rng = SplitMix(seed);
        let (q, v, a, fext) = random_state(&model, &mut rng);
        let mut fd = FlexData::new(&model);
        let mut rd = Data::new(&rigid);
        let tau_f = flexible::rnea(&model, &mut fd, &q, &v, &a, Some(&fext))
            .unwrap()
            .clone();
        let tau_r = satsim_tree::rnea(&rigid, &mut rd, &q, &v, &a, Some(&fext))
            .unwrap()
            .clone();
        assert_eq!(tau_f, tau_r, "seed {seed}: RNEA bit for bit");
        let m_f = flexible::crba(&model, &mut fd, &q).unwrap().clone();
        let m_r = satsim_tree::crba(&rigid, &mut rd, &q).unwrap().clone();
        assert!(
            (&m_f - &m_r).amax() <= 1e-14 * m_r.amax(),
            "seed {seed}: CRBA"
        );
        let dd_f = flexible::aba(&model, &mut fd, &q, &v, &a, Some(&fext))
            .unwrap()
            .clone();
        let dd_r = satsim_tree::aba::aba(&rigid, &mut rd, &q, &v, &a, Some(&fext))
            .unwrap()
            .clone();
        assert!(
            (&dd_f - &dd_r).amax() <= 1e-14 * dd_r.amax(),
            "seed {seed}: ABA {:e}",
            (&dd_f - &dd_r).amax() / dd_r.amax()
        );
    }
}

/// A bus (20 kg) with two contract beams as panels on hinges at `(0, ±0.5, 0)` about x,
/// `m` modes each.
fn bus_with_two_beams(m: usize, damping: f64) -> FlexModel {
    let builder = ModelBuilder::new(BaseKind::Free)
        .body(Body::new(
            "bus",
            20.0,
            Mat3::from_diagonal(&Vec3::new(3.0, 2.0, 3.5)),
        ))
        .body(Body::new("panel1", 0.0, Mat3::zeros()))
        .body(Body::new("panel2", 0.0, Mat3::zeros()))
        .hinge(Hinge::revolute("h1", "bus", "panel1", Vec3::x()).at(Vec3::new(0.0, 0.5, 0.0)))
        .hinge(Hinge::revolute("h2", "bus", "panel2", Vec3::x()).at(Vec3::new(0.0, -0.5, 0.0)));
    let flex = [
        Flexible {
            body: "panel1".into(),
            modes: Modes::Beam(beam(Vec3::y(), Vec3::z(), m)),
            damping,
            stiffening: true,
        },
        Flexible {
            body: "panel2".into(),
            modes: Modes::Beam(beam(-Vec3::y(), Vec3::z(), m)),
            damping,
            stiffening: true,
        },
    ];
    FlexModel::build(builder, &flex).unwrap()
}

/// The state derivative `[q̇; v̇]` of a free-base flexible model (quaternion kinematics
/// `q̇ = ½ q ⊗ [0; ω]`, position `ṗ = R v`, hinge and modal coordinates `q̇ = v`).
fn derivative(model: &FlexModel, data: &mut FlexData, x: &[f64], dx: &mut [f64]) {
    let (nq, nv) = (model.nq(), model.nv());
    let (q, v) = x.split_at(nq);
    let att = Quaternion::new(q[0], q[1], q[2], q[3]);
    let w = Quaternion::new(0.0, v[0], v[1], v[2]);
    let qd = att * w * 0.5;
    dx[..4].copy_from_slice(&[qd.w, qd.i, qd.j, qd.k]);
    let r = nalgebra::UnitQuaternion::from_quaternion(att);
    let pd = r * Vec3::new(v[3], v[4], v[5]);
    dx[4..7].copy_from_slice(pd.as_slice());
    dx[7..nq].copy_from_slice(&v[6..]);
    let tau = vec![0.0; nv];
    let a = flexible::aba(model, data, q, v, &tau, None).unwrap();
    dx[nq..].copy_from_slice(a.as_slice());
}

/// One RK4 step of `x` by `h`.
fn rk4_step(model: &FlexModel, data: &mut FlexData, x: &mut [f64], h: f64, k: &mut [Vec<f64>; 5]) {
    let n = x.len();
    let [k1, k2, k3, k4, y] = k;
    derivative(model, data, x, k1);
    for i in 0..n {
        y[i] = x[i] + 0.5 * h * k1[i];
    }
    derivative(model, data, y, k2);
    for i in 0..n {
        y[i] = x[i] + 0.5 * h * k2[i];
    }
    derivative(model, data, y, k3);
    for i in 0..n {
        y[i] = x[i] + h * k3[i];
    }
    derivative(model, data, y, k4);
    for i in 0..n {
        x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
}

/// The kinetic and strain energies and the linear and angular momenta at `(q, v)` by
/// `energy` and `momentum`, asserted equal bit for bit to the output rows' one pass,
/// `energy_and_momentum` (after `forward_kinematics`).
pub(crate) fn energies_and_momenta(
    model: &FlexModel,
    data: &mut FlexData,
    rigid: &mut satsim_tree::Data,
    q: &[f64],
    v: &[f64],
) -> (f64, f64, Vec3, Vec3) {
    let (t, u) = flexible::energy(model, data, q, v).unwrap();
    flexible::forward_kinematics(model, data, rigid, q, v).unwrap();
    let (p, h) = flexible::momentum(model, rigid, q, v);
    let one_pass = flexible::energy_and_momentum(model, data, rigid, q, v);
    assert_eq!(one_pass, (t, u, p, h));
    (t, u, p, h)
}

/// Integrates `x` over `steps` steps of `h`; returns the largest relative change of the
/// total (kinetic plus strain) energy.
fn energy_drift(model: &FlexModel, x: &mut [f64], h: f64, steps: usize) -> f64 {
    let mut data = FlexData::new(model);
    let mut rigid = satsim_tree::Data::new(model.rigid());
    let nq = model.nq();
    let mut energy = |x: &[f64]| {
        let (q, v) = x.split_at(nq);
        let (t, u, _, _) = energies_and_momenta(model, &mut data, &mut rigid, q, v);
        t + u
    };
    let e0 = energy(x);
    let mut k: [Vec<f64>; 5] = std::array::from_fn(|_| vec![0.0; x.len()]);
    let mut data = FlexData::new(model);
    let mut worst: f64 = 0.0;
    for _ in 0..steps {
        rk4_step(model, &mut data, x, h, &mut k);
        worst = worst.max(rel(energy(x), e0));
    }
    worst
}

// 5. Energy conservation.
#[test]
fn energy_is_conserved_without_damping() {
    let model = bus_with_two_beams(3, 0.0);
    let (nq, nv) = (model.nq(), model.nv());
    let mut x = vec![0.0; nq + nv];
    x[..nq].copy_from_slice(&model.neutral());
    // Spin, drift, a hinge swing, both beams deflected and moving.
    let v0 = [
        0.3, -0.2, 0.5, 0.1, 0.0, -0.05, 0.4, -0.3, 0.02, -0.1, 0.3, -0.05, 0.1, 0.2,
    ];
    x[nq..].copy_from_slice(&v0[..nv]);
    x[7] = 0.2;
    x[9] = 0.01;
    x[10] = -0.003;
    x[12] = -0.008;
    let x0 = x.clone();
    let h = 1e-4;
    // 2 s: almost three periods of the first coupled mode.
    let worst = energy_drift(&model, &mut x, h, 20_000);
    println!("energy drift over 2 s at h = 1e-4: {worst:e}");
    assert!(worst < 1e-8, "relative energy drift {worst:e}");
    assert!(x[9] != x0[9] && x[nq + 9] != x0[nq + 9], "the beams moved");
    // Spun fast about the beams' bending direction: the stiffening (K_g = 9 J₁, 14 % of
    // ω₁²) and its foreshortening inertia are in play, and the energy still holds.
    let mut x = x0.clone();
    x[nq + 2] = 3.0;
    // Half the step: the stiffened modes are faster (the drift is RK4's: 1.4e-8 at 1e-4).
    let worst = energy_drift(&model, &mut x, 0.5 * h, 20_000);
    println!("energy drift over 1 s spun at 3 rad/s, h = 5e-5: {worst:e}");
    assert!(worst < 1e-8, "relative energy drift {worst:e}");
    // With damping the energy falls.
    let damped = bus_with_two_beams(3, 0.02);
    let mut dd = FlexData::new(&damped);
    let mut xd = x0.clone();
    let (t0, u0) = flexible::energy(&damped, &mut dd, &xd[..nq], &xd[nq..]).unwrap();
    let mut k: [Vec<f64>; 5] = std::array::from_fn(|_| vec![0.0; xd.len()]);
    for _ in 0..2000 {
        rk4_step(&damped, &mut dd, &mut xd, h, &mut k);
    }
    let (t1, u1) = flexible::energy(&damped, &mut dd, &xd[..nq], &xd[nq..]).unwrap();
    assert!(t1 + u1 < (t0 + u0) * (1.0 - 1e-6));
}

/// The eigenvalues of `K x = λ M x` (`M` positive definite, `K` symmetric), ascending.
fn generalized_eigenvalues(m: &DMatrix<f64>, k: &DMatrix<f64>) -> Vec<f64> {
    let l = m.clone().cholesky().expect("M positive definite").l();
    let n = m.nrows();
    let li = l.solve_lower_triangular(&DMatrix::identity(n, n)).unwrap();
    let a = &li * k * li.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let mut e: Vec<f64> = SymmetricEigen::new(a).eigenvalues.iter().copied().collect();
    e.sort_by(|x, y| x.partial_cmp(y).unwrap());
    e
}

/// Pushes a chain of `n` rigid segments discretising the contract beam from `at` on
/// `parent`, along `dir` (±y), bending about x; returns the hinge names.
fn push_chain(b: &mut ModelBuilder, parent: &str, at: Vec3, dir: f64, n: usize, tag: &str) {
    let (l, rho_a) = (2.0 / n as f64, 5.0);
    let m = rho_a * l;
    let j = m * l * l / 12.0;
    let mut prev = parent.to_string();
    for s in 0..n {
        let name = format!("{tag}{s}");
        b.push_body(
            Body::new(name.clone(), m, Mat3::from_diagonal(&Vec3::new(j, 0.0, j)))
                .with_com(Vec3::new(0.0, dir * 0.5 * l, 0.0)),
        );
        let hat = if s == 0 {
            at
        } else {
            Vec3::new(0.0, dir * l, 0.0)
        };
        b.push_hinge(
            Hinge::revolute(format!("h{name}"), prev.clone(), name.clone(), Vec3::x()).at(hat),
        );
        prev = name;
    }
}

/// The first two elastic frequencies (rad/s) of the rigid-chain discretisations with `n`
/// segments per beam: clamped (fixed base), and bus + two beams (free).
fn chain_frequencies(n: usize) -> ([f64; 2], [f64; 2]) {
    let k = 500.0 / (2.0 / n as f64); // EI / (L / N)
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    b.push_body(Body::new("ground", 0.0, Mat3::zeros()));
    push_chain(&mut b, "ground", Vec3::zeros(), 1.0, n, "s");
    let model = b.build().unwrap();
    let mut data = Data::new(&model);
    let m = satsim_tree::crba(&model, &mut data, &model.neutral())
        .unwrap()
        .clone();
    let kk = DMatrix::from_diagonal_element(n, n, k);
    let e = generalized_eigenvalues(&m, &kk);
    let clamped = [e[0].sqrt(), e[1].sqrt()];
    let mut b = ModelBuilder::new(BaseKind::Free);
    b.push_body(Body::new(
        "bus",
        20.0,
        Mat3::from_diagonal(&Vec3::new(3.0, 2.0, 3.5)),
    ));
    push_chain(&mut b, "bus", Vec3::new(0.0, 0.5, 0.0), 1.0, n, "p");
    push_chain(&mut b, "bus", Vec3::new(0.0, -0.5, 0.0), -1.0, n, "q");
    let model = b.build().unwrap();
    let mut data = Data::new(&model);
    let m = satsim_tree::crba(&model, &mut data, &model.neutral())
        .unwrap()
        .clone();
    let nv = model.nv();
    let mut kk = DMatrix::zeros(nv, nv);
    for i in 6..nv {
        kk[(i, i)] = k;
    }
    let e = generalized_eigenvalues(&m, &kk);
    (clamped, [e[6].sqrt(), e[7].sqrt()])
}

// 6. Against an independent discretisation.
#[test]
fn frequencies_match_rigid_chain_discretisations() {
    let (c40, f40) = chain_frequencies(40);
    let (c80, f80) = chain_frequencies(80);
    let (c160, f160) = chain_frequencies(160);
    println!("clamped {c40:?} {c80:?} {c160:?}");
    println!("free {f40:?} {f80:?} {f160:?}");
    // The flexible model: clamped, its modes; free-free, the hinges locked (their rows and
    // columns removed).
    let model = bus_with_two_beams(6, 0.0);
    let mut data = FlexData::new(&model);
    let m = flexible::crba(&model, &mut data, &model.neutral())
        .unwrap()
        .clone();
    let keep: Vec<usize> = (0..model.nv()).filter(|&i| i != 6 && i != 7).collect();
    let mr = DMatrix::from_fn(keep.len(), keep.len(), |r, c| m[(keep[r], keep[c])]);
    let mut kr = DMatrix::zeros(keep.len(), keep.len());
    for (e, w2) in model.stiffness().iter().enumerate() {
        kr[(6 + e, 6 + e)] = *w2;
    }
    let e = generalized_eigenvalues(&mr, &kr);
    assert!(
        e[..6].iter().all(|x| x.abs() < 1e-9 * e[6]),
        "six rigid modes"
    );
    let flex = [e[6].sqrt(), e[7].sqrt()];
    println!("flex {flex:?}");
    // The chains converge as 1/N (each halving of the segments halves the error, checked
    // here on 40, 80 and 160): Richardson's extrapolation of first order, 2 f₈₀ − f₄₀.
    let bm = beam(Vec3::y(), Vec3::z(), 2);
    for k in 0..2 {
        for (f40, f80, f160) in [(c40[k], c80[k], c160[k]), (f40[k], f80[k], f160[k])] {
            let ratio = (f80 - f40) / (f160 - f80);
            assert!(
                (ratio - 2.0).abs() < 0.1,
                "mode {}: order ratio {ratio}",
                k + 1
            );
        }
        let clamped = 2.0 * c80[k] - c40[k];
        let free = 2.0 * f80[k] - f40[k];
        println!(
            "mode {}: clamped chain {clamped:.5} vs analytic {:.5}; free-free chain {free:.5} vs flexible {:.5}",
            k + 1,
            bm.omega(k + 1),
            flex[k]
        );
        assert!(
            rel(clamped, bm.omega(k + 1)) < 0.01,
            "clamped mode {}",
            k + 1
        );
        assert!(rel(free, flex[k]) < 0.01, "free-free mode {}", k + 1);
    }
}

// 7. No allocation per call.
#[test]
fn per_call_algorithms_do_not_allocate() {
    for (model, seed) in [
        (bus_with_two_beams(4, 0.01), 1u64),
        (random_flexible(9, BaseKind::Free, false, 3), 3),
        (random_flexible(7, BaseKind::Fixed, false, 5), 5),
    ] {
        let mut rng = SplitMix(seed);
        let (q, v, a, fext) = random_state(&model, &mut rng);
        let mut data = FlexData::new(&model);
        let locked: Vec<bool> = (0..model.rigid().n_hinges()).map(|k| k % 2 == 0).collect();
        let before = allocations();
        for _ in 0..3 {
            flexible::aba_hybrid(&model, &mut data, &q, &v, &a, Some(&fext), &locked).unwrap();
            flexible::rnea(&model, &mut data, &q, &v, &a, Some(&fext)).unwrap();
            flexible::bias(&model, &mut data, &q, &v, None).unwrap();
            flexible::crba(&model, &mut data, &q).unwrap();
            flexible::aba(&model, &mut data, &q, &v, &a, Some(&fext)).unwrap();
            flexible::energy(&model, &mut data, &q, &v).unwrap();
        }
        assert_eq!(allocations(), before, "seed {seed}");
    }
}

// Modal damping: a clamped beam's free decay follows 2 ζ ω: η̈ + 2 ζ ω η̇ + ω² η = 0.
#[test]
fn modal_damping_and_tip_deflection() {
    let bm = beam(Vec3::y(), Vec3::z(), 3);
    let model = FlexModel::build(
        ModelBuilder::new(BaseKind::Fixed).body(Body::new("beam", 0.0, Mat3::zeros())),
        &[Flexible {
            body: "beam".into(),
            modes: Modes::Beam(bm.clone()),
            damping: 0.05,
            stiffening: true,
        }],
    )
    .unwrap();
    let mut data = FlexData::new(&model);
    let q = [0.01, -0.02, 0.003];
    let v = [0.5, 0.1, -0.2];
    let ddq = flexible::aba(&model, &mut data, &q, &v, &[0.0; 3], None).unwrap();
    for k in 0..3 {
        let w = bm.omega(k + 1);
        let expected = -2.0 * 0.05 * w * v[k] - w * w * q[k];
        assert!(rel(ddq[k], expected) < 1e-13, "mode {}", k + 1);
    }
    // The tip deflection: Σ φₖ(L) ηₖ, the unscaled tip shape being 2 (±) over √(ρA L).
    let tip = model.tip_deflection(0, &q).unwrap();
    let scale = 1.0 / (bm.rho_a * bm.length).sqrt();
    let expected = 2.0 * scale * (q[0] - q[1] + q[2]);
    assert!(rel(tip, expected) < 1e-12, "{tip} vs {expected}");
}

// The rigid reader (`read_model`, so `satsim run`) refuses `[body.flexible]` with a clear error
// naming the line; `read_flex_model` reads it (tests/it/flexible_io.rs).
#[cfg(feature = "files")]
#[test]
fn model_file_rejects_flexible_bodies_for_now() {
    let text = r#"
[[body]]
name = "bus"
mass = 100.0
inertia = [[10, 0, 0], [0, 10, 0], [0, 0, 10]]
[body.flexible]
beam = { root = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], bend = [0.0, 0.0, 1.0], length = 2.0, EI = 500.0, rho_A = 5.0, modes = 3 }
"#;
    let Err(err) = satsim_tree::parse_model(text, std::path::Path::new("flex.toml")) else {
        panic!("flexible bodies are not read yet");
    };
    let err = err.to_string();
    println!("{err}");
    assert!(
        err.contains("flexible") && err.contains("flex.toml"),
        "{err}"
    );
}

// Geometric stiffening: Southwell's coefficient of a uniform cantilever's first flapwise
// mode on a hub spinning about an axis through its root (one mode, the Rayleigh value):
// ω² = ω₀² + 1.193 Ω².
#[test]
fn centrifugal_stiffening_gives_southwell_coefficient() {
    let spin = 3.0; // rad/s
    let model = FlexModel::build(
        ModelBuilder::new(BaseKind::Fixed)
            .body(Body::new("ground", 0.0, Mat3::zeros()))
            .body(Body::new(
                "hub",
                1.0,
                Mat3::from_diagonal(&Vec3::new(5e5, 5e5, 1e6)),
            ))
            .hinge(Hinge::revolute("spin", "ground", "hub", Vec3::z())),
        &[Flexible {
            body: "hub".into(),
            modes: Modes::Beam(beam(Vec3::y(), Vec3::z(), 1)),
            damping: 0.0,
            stiffening: true,
        }],
    )
    .unwrap();
    let mut data = FlexData::new(&model);
    let v = [spin, 0.0];
    let d = 1e-6;
    let mut acc =
        |eta: f64| flexible::aba(&model, &mut data, &[0.3, eta], &v, &[0.0; 2], None).unwrap()[1];
    let k = -(acc(d) - acc(-d)) / (2.0 * d);
    let w0 = beam(Vec3::y(), Vec3::z(), 1).omega(1);
    let coefficient = (k - w0 * w0) / (spin * spin);
    println!("Southwell coefficient (one mode): {coefficient:.5}");
    assert!((coefficient - 1.193).abs() < 1e-3, "{coefficient}");
    // Spun about the beam's own axis, nothing stiffens it: it softens, ω² = ω₀² − Ω².
    let hinged = FlexModel::build(
        ModelBuilder::new(BaseKind::Fixed)
            .body(Body::new("ground", 0.0, Mat3::zeros()))
            .body(Body::new(
                "hub",
                1.0,
                Mat3::from_diagonal(&Vec3::new(5e5, 1e6, 5e5)),
            ))
            .hinge(Hinge::revolute("spin", "ground", "hub", Vec3::y())),
        &[Flexible {
            body: "hub".into(),
            modes: Modes::Beam(beam(Vec3::y(), Vec3::z(), 1)),
            damping: 0.0,
            stiffening: true,
        }],
    )
    .unwrap();
    let mut data = FlexData::new(&hinged);
    let a = flexible::aba(&hinged, &mut data, &[0.0, 0.01], &v, &[0.0; 2], None).unwrap()[1];
    // No axial load; the deflection, across the spin, carries its own centrifugal load.
    assert!(
        rel(-a / 0.01, w0 * w0 - spin * spin) < 1e-3,
        "{}",
        -a / 0.01
    );
}

// The first pass makes each body's inertia at the deformation once, for the algorithms
// and for the effects that read it after the kinematics (`FlexData::inertias`).
#[test]
fn the_first_pass_leaves_the_deformed_inertias() {
    for seed in 0..12u64 {
        let model = random_flexible(3 + (seed % 6) as usize, BaseKind::Free, false, seed);
        let mut rng = SplitMix(seed ^ 0x1e);
        let mut data = FlexData::new(&model);
        let mut poses = Data::new(model.rigid());
        let nq = model.rigid().nq();
        let same = |data: &FlexData, q: &[f64]| {
            (0..model.rigid().n_bodies())
                .all(|i| data.inertias()[i] == model.deformed_inertia(i, &q[nq..]))
        };
        let (q, v, a, _) = random_state(&model, &mut rng);
        flexible::forward_kinematics(&model, &mut data, &mut poses, &q, &v).unwrap();
        assert!(same(&data, &q), "seed {seed}: forward kinematics");
        // Each algorithm's own first pass, at another deformation.
        for pass in 0..3 {
            let (q, v, _, _) = random_state(&model, &mut rng);
            match pass {
                0 => drop(flexible::aba(&model, &mut data, &q, &v, &a, None).unwrap()),
                1 => drop(flexible::rnea(&model, &mut data, &q, &v, &a, None).unwrap()),
                _ => drop(flexible::crba(&model, &mut data, &q).unwrap()),
            }
            assert!(same(&data, &q), "seed {seed}: pass {pass}");
        }
    }
}

/// The beams deflected beyond a tenth of their length are named, the largest first, with
/// their tips and modes; a deflection within it is not.
#[test]
fn deflections_beyond_a_tenth_of_a_beams_length_are_large() {
    use satsim_tree::flexible::SMALL_DEFLECTION;
    let model = bus_with_two_beams(2, 0.01);
    let (b1, b2) = (1, 2);
    let at = |i: usize| model.rigid().nq() + 2 * (i - 1);
    let length = model.beam(b1).unwrap().length;
    // The tip per unit first-mode coordinate.
    let mut q = model.neutral();
    q[at(b1)] = 1.0;
    let unit = model.tip_deflection(b1, &q).unwrap();
    let set = |q: &mut Vec<f64>, i: usize, fraction: f64| q[at(i)] = fraction * length / unit;
    let mut q = model.neutral();
    set(&mut q, b1, 0.05);
    set(&mut q, b2, -0.3);
    let large = model.large_deflections(&q);
    assert_eq!(large.len(), 1, "{large:?}");
    let d = &large[0];
    assert_eq!((d.body, d.length), (b2, length));
    assert!((d.tip + 0.3 * length).abs() < 1e-12, "{d:?}");
    assert_eq!(d.eta, q[at(b2)..at(b2) + 2].to_vec());
    set(&mut q, b1, 0.5);
    let order: Vec<usize> = model.large_deflections(&q).iter().map(|d| d.body).collect();
    assert_eq!(order, [b1, b2]);
    set(&mut q, b1, 0.99 * SMALL_DEFLECTION);
    set(&mut q, b2, -0.99 * SMALL_DEFLECTION);
    assert!(model.large_deflections(&q).is_empty());
}

// The view's poses: the transforms alone give forward kinematics' poses bit for bit, on
// random trees with beams (stiffened: the foreshortening moves their nodes), given modes
// with general node shapes (three rotation stages) and bodies carried by flexible parents.
#[test]
fn poses_alone_are_forward_kinematics_poses_bit_for_bit() {
    let mut carried = 0;
    for seed in 0..40u64 {
        let model = seeded_flexible(seed, seed % 2 == 0);
        carried += carried_bodies(&model);
        poses_check(&model, seed);
    }
    assert!(carried > 20, "{carried} bodies carried by flexible parents");
    let model = random_flexible(4, BaseKind::Free, false, 1);
    let mut data = FlexData::new(&model);
    let mut rigid = satsim_tree::Data::new(model.rigid());
    let short = vec![0.0; model.nq() - 1];
    assert!(flexible::forward_poses(&model, &mut data, &mut rigid, &short).is_err());
}

/// [`flexible::forward_poses`] at a random state from `seed` gives
/// [`flexible::forward_kinematics`]'s poses and transforms bit for bit (the node's `pose`
/// against its `state`: their own loops).
fn poses_check(model: &FlexModel, seed: u64) {
    let mut rng = SplitMix(seed ^ 0x5e7);
    let (q, v, _, _) = random_state(model, &mut rng);
    let mut data = FlexData::new(model);
    let mut full = satsim_tree::Data::new(model.rigid());
    flexible::forward_kinematics(model, &mut data, &mut full, &q, &v).unwrap();
    let mut alone = satsim_tree::Data::new(model.rigid());
    let mut fresh = FlexData::new(model);
    flexible::forward_poses(model, &mut fresh, &mut alone, &q).unwrap();
    assert_eq!(alone.rotation, full.rotation, "seed {seed}: rotations");
    assert_eq!(alone.position, full.position, "seed {seed}: positions");
    assert_eq!(alone.xup, full.xup, "seed {seed}: transforms");
}
