//! The flexible ABA's spherical chains (`flexible/chain.rs`): a 3-DOF gimbal of massless
//! links eliminated at its tip as one joint, with the tip's modes, against the tree form
//! (every link a body, [`FlexModel::without_chains`]) and the dense solve of CRBA's system:
//! random flexible trees with chains, free and hybrid, with and without external wrenches.

use crate::flexible::{max_abs, random_flexible, random_state, with_random_modes};
use nalgebra::{DMatrix, DVector, Quaternion};
use satsim_testkit::alloc::allocations;
use satsim_tree::flexible::{self, FlexData, FlexModel};
use satsim_tree::samples::{SplitMix, push_wheels, random_inertia};
use satsim_tree::spatial::Vec3;
use satsim_tree::{BaseKind, Body, Hinge, Model, ModelBuilder};

/// A random gimbaled tree: a bus (with three wheels for some seeds), a 3-DOF gimbal of two
/// massless zero-length links of random axes and rotations to a tip, then up to three bodies
/// on the tip, each other or the bus.
fn gimbal_tree(base: BaseKind, seed: u64) -> Model {
    let mut rng = SplitMix(seed ^ 0x9b1);
    let mut b = ModelBuilder::new(base);
    let body = |b: &mut ModelBuilder, name: &str, rng: &mut SplitMix| {
        let m = rng.range(0.5, 5.0);
        b.push_body(Body::new(name, m, random_inertia(rng, m * 0.1)).with_com(rng.vec3(0.3)));
    };
    body(&mut b, "bus", &mut rng);
    b.push_body(Body::massless("link1"));
    b.push_body(Body::massless("link2"));
    body(&mut b, "tip", &mut rng);
    let rotation = |rng: &mut SplitMix| {
        let r = |rng: &mut SplitMix| rng.range(-1.0, 1.0);
        Quaternion::new(r(rng), r(rng), r(rng), r(rng)).normalize()
    };
    let gimbal = [("bus", "link1"), ("link1", "link2"), ("link2", "tip")];
    for (k, (p, c)) in gimbal.into_iter().enumerate() {
        let at = if k == 0 { rng.vec3(0.5) } else { Vec3::zeros() };
        let child_at = if k == 2 { rng.vec3(0.5) } else { Vec3::zeros() };
        b.push_hinge(
            Hinge::revolute(format!("g{k}"), p, c, rng.unit())
                .at(at)
                .child_at(child_at)
                .rotation(rotation(&mut rng)),
        );
    }
    let mut names = vec!["bus".to_string(), "tip".to_string()];
    for k in 0..(seed % 4) as usize {
        let name = format!("b{k}");
        body(&mut b, &name, &mut rng);
        let parent = names[(rng.next_f64() * names.len() as f64) as usize].clone();
        b.push_hinge(
            Hinge::revolute(format!("h{k}"), parent, name.clone(), rng.unit())
                .at(rng.vec3(0.5))
                .child_at(rng.vec3(0.5))
                .rotation(rotation(&mut rng)),
        );
        names.push(name);
    }
    if seed % 3 == 1 {
        push_wheels(&mut b, "bus");
    }
    b.build().expect("gimbaled trees are valid")
}

/// `M ddq + b − τ` over its scale, and the largest difference from the tree form's
/// accelerations over their size, for one call (hybrid where `locked` is given).
fn check(model: &FlexModel, seed: u64, locked: Option<&[bool]>, wrenches: bool) -> (f64, f64) {
    let mut rng = SplitMix(seed ^ 0x5ca1);
    let (q, v, tau, fext) = random_state(model, &mut rng);
    let fext = wrenches.then_some(&fext[..]);
    let tree = model.without_chains();
    let (mut data, mut data_tree) = (FlexData::new(model), FlexData::new(&tree));
    let (ddq, ddq_tree) = match locked {
        Some(l) => (
            flexible::aba_hybrid(model, &mut data, &q, &v, &tau, fext, l),
            flexible::aba_hybrid(&tree, &mut data_tree, &q, &v, &tau, fext, l),
        ),
        None => (
            flexible::aba(model, &mut data, &q, &v, &tau, fext),
            flexible::aba(&tree, &mut data_tree, &q, &v, &tau, fext),
        ),
    };
    let (ddq, ddq_tree) = (ddq.unwrap().clone(), ddq_tree.unwrap().clone());
    let m = flexible::crba(model, &mut data, &q).unwrap().clone();
    let b = flexible::bias(model, &mut data, &q, &v, fext)
        .unwrap()
        .clone();
    // The locked hinges' rows and columns out (none locked: the whole system).
    let r = model.rigid();
    let base_nv = r.nv() - r.n_hinges();
    let is_locked = |k: usize| k >= base_nv && k < r.nv() && locked.is_some_and(|l| l[k - base_nv]);
    let free: Vec<usize> = (0..model.nv()).filter(|&k| !is_locked(k)).collect();
    let nf = free.len();
    let mff = DMatrix::from_fn(nf, nf, |i, j| m[(free[i], free[j])]);
    let rhs = DVector::from_fn(nf, |i, _| tau[free[i]] - b[free[i]]);
    let xf = DVector::from_fn(nf, |i, _| ddq[free[i]]);
    for k in (0..model.nv()).filter(|&k| is_locked(k)) {
        assert_eq!(ddq[k], 0.0, "seed {seed}: locked coordinate {k}");
    }
    let scale = max_abs(&tau) + mff.amax() * xf.amax() + b.amax();
    let residual = (&mff * &xf - &rhs).amax() / scale;
    // Over the accelerations' size (zero where every hinge is locked and nothing else moves).
    let apart = (&ddq - &ddq_tree).amax() / ddq_tree.amax().max(f64::MIN_POSITIVE);
    (residual, apart)
}

#[test]
fn folded_chains_solve_crbas_system_as_the_tree_form_does() {
    let (mut folded, mut flexible_tips) = (0, 0);
    let (mut worst_residual, mut worst_apart): (f64, f64) = (0.0, 0.0);
    for seed in 0..80u64 {
        let base = if seed % 4 == 0 {
            BaseKind::Fixed
        } else {
            BaseKind::Free
        };
        let model = if seed % 2 == 0 {
            with_random_modes(gimbal_tree(base, seed), seed)
        } else {
            random_flexible(5 + (seed % 9) as usize, base, true, seed)
        };
        let chains: Vec<_> = model.folded_chains().collect();
        if chains.is_empty() {
            continue;
        }
        folded += chains.len();
        flexible_tips += chains.iter().filter(|c| model.modes(c.tip()) > 0).count();
        let r = model.rigid();
        let mut rng = SplitMix(seed ^ 0x10c);
        // Locks here and there: a chain with a locked hinge is eliminated as the tree form.
        let locked: Vec<bool> = (0..r.n_hinges()).map(|_| rng.next_f64() < 0.3).collect();
        for (locks, wrenches) in [(None, false), (None, true), (Some(&locked[..]), true)] {
            let (residual, apart) = check(&model, seed, locks, wrenches);
            assert!(
                residual < 1e-12,
                "seed {seed}: M ddq + b − τ = {residual:e}"
            );
            assert!(apart < 1e-9, "seed {seed}: {apart:e} from the tree form");
            worst_residual = worst_residual.max(residual);
            worst_apart = worst_apart.max(apart);
        }
    }
    println!(
        "{folded} folded chains ({flexible_tips} flexible tips): residual {worst_residual:e}, \
         {worst_apart:e} from the tree form"
    );
    assert!(
        folded >= 10 && flexible_tips >= 4,
        "{folded} {flexible_tips}"
    );
}

#[test]
fn a_folded_chain_does_not_allocate() {
    // The first gimbaled tree whose folded chain has a flexible tip.
    let model = (0..40u64)
        .step_by(2)
        .map(|seed| with_random_modes(gimbal_tree(BaseKind::Free, seed), seed))
        .find(|m| m.folded_chains().any(|c| m.modes(c.tip()) > 0))
        .expect("a gimbaled tree with a flexible tip");
    let mut rng = SplitMix(11);
    let (q, v, tau, fext) = random_state(&model, &mut rng);
    let mut data = FlexData::new(&model);
    let before = allocations();
    for _ in 0..3 {
        flexible::aba(&model, &mut data, &q, &v, &tau, Some(&fext)).unwrap();
        flexible::aba(&model, &mut data, &q, &v, &tau, None).unwrap();
    }
    assert_eq!(allocations(), before);
}
