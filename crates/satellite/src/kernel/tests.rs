//! Tests of [`super::UnrolledAba`]: against the generic ABA, lanes against runs, bit for bit.

use super::*;
use nalgebra::Quaternion;
use satsim_tree::aba::aba;
use satsim_tree::samples::{SplitMix, random_inertia, random_q};
use satsim_tree::{Body, Hinge, ModelBuilder};

/// A signed coordinate axis other than `not` (so that two consecutive gimbal axes are
/// never parallel).
fn coordinate_axis(rng: &mut SplitMix, not: Option<usize>) -> (usize, Vec3) {
    loop {
        let k = (rng.next_f64() * 3.0) as usize;
        if Some(k) != not {
            let sign = if rng.next_f64() < 0.5 { -1.0 } else { 1.0 };
            return (k, Vec3::ith(k, sign));
        }
    }
}

fn body(rng: &mut SplitMix, name: &str, mass: (f64, f64)) -> Body {
    let m = rng.range(mass.0, mass.1);
    Body::new(name, m, random_inertia(rng, m * 0.3)).with_com(rng.vec3(0.5))
}

/// A random model of the layout: a bus, `rotors` balanced rotors on it about random
/// axes, a 3-DOF gimbal about signed coordinate axes (random point, tip hinge point) to
/// a tip, and `serial` bodies in a row below the tip (random masses, inertias, hinge
/// points, signed coordinate axes); bodies and hinges listed in a random order.
fn random_layout(serial: usize, rotors: usize, seed: u64) -> Model {
    let mut rng = SplitMix(seed);
    let mut bodies = vec![
        body(&mut rng, "bus", (100.0, 1000.0)),
        Body::massless("l1"),
        Body::massless("l2"),
        body(&mut rng, "tip", (1.0, 50.0)),
    ];
    let (k1, a1) = coordinate_axis(&mut rng, None);
    let (k2, a2) = coordinate_axis(&mut rng, Some(k1));
    let (_, a3) = coordinate_axis(&mut rng, Some(k2));
    let mut hinges = vec![
        Hinge::revolute("g1", "bus", "l1", a1).at(rng.vec3(1.0)),
        Hinge::revolute("g2", "l1", "l2", a2),
        Hinge::revolute("g3", "l2", "tip", a3).child_at(rng.vec3(0.8)),
    ];
    let mut parent = "tip".to_string();
    for j in 0..serial {
        let name = format!("s{j}");
        bodies.push(body(&mut rng, &name, (0.5, 30.0)));
        let (_, a) = coordinate_axis(&mut rng, None);
        hinges.push(
            Hinge::revolute(format!("h{j}"), parent.clone(), name.clone(), a)
                .at(rng.vec3(0.6))
                .child_at(rng.vec3(0.6)),
        );
        parent = name;
    }
    for r in 0..rotors {
        let axis = rng.unit();
        let j = rng.range(0.01, 0.2);
        let it = rng.range(0.55 * j, 2.0 * j);
        let aat = axis * axis.transpose();
        let inertia = aat * j + (Mat3::identity() - aat) * it;
        let mass = if r % 2 == 0 { rng.range(0.1, 3.0) } else { 0.0 };
        let com = rng.vec3(0.3);
        let name = format!("rotor{r}");
        bodies.push(Body::new(name.clone(), mass, inertia).with_com(com));
        hinges.push(
            Hinge::revolute(name.clone(), "bus", name, axis)
                .at(rng.vec3(0.5))
                .child_at(com + axis * rng.range(-0.2, 0.2)),
        );
    }
    // Rotors first or last among the bodies; hinges (so coordinates) in a random order.
    if seed.is_multiple_of(2) {
        bodies[4..].rotate_right(rotors);
    }
    for k in (1..hinges.len()).rev() {
        let j = (rng.next_f64() * (k + 1) as f64) as usize;
        hinges.swap(k, j);
    }
    let mut b = ModelBuilder::new(BaseKind::Free);
    for x in bodies {
        b.push_body(x);
    }
    for h in hinges {
        b.push_hinge(h);
    }
    b.build().expect("a valid layout")
}

/// The preprint satellite (`examples/satellite.toml`) plus the peer orbit's three
/// reaction wheels on the bus, as `satsim-satellite` adds them.
fn satellite_with_wheels() -> (Model, Model) {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/satellite.toml");
    let plain = satsim_tree::read_model(&path).unwrap();
    let mut b = plain.to_builder();
    satsim_tree::samples::push_wheels(&mut b, "bus");
    (plain, b.build().unwrap())
}

fn random_state(model: &Model, rng: &mut SplitMix) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let q = random_q(model, rng, 3.0);
    let v = (0..model.nv()).map(|_| rng.range(-2.0, 2.0)).collect();
    let tau = (0..model.nv()).map(|_| rng.range(-5.0, 5.0)).collect();
    (q, v, tau)
}

/// A random wrench on every body (base, rotors, links, tip, serial bodies).
fn random_wrenches(model: &Model, rng: &mut SplitMix) -> Vec<Force> {
    (0..model.n_bodies())
        .map(|_| Force::new(rng.vec3(5.0), rng.vec3(5.0)))
        .collect()
}

/// The kernel against the generic ABA on one state, with external forces `fext` or
/// without: the same accelerations to 1e-12 of the largest, or the same refusal.
/// Returns whether both solved.
fn agrees(
    model: &Model,
    kernel: &UnrolledAba,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    fext: Option<&[Force]>,
) -> bool {
    let (mut dk, mut dg) = (Data::new(model), Data::new(model));
    let fast = if fext.is_some() {
        kernel.aba_with_forces(&mut dk, q, v, tau, fext).cloned()
    } else {
        kernel.aba(&mut dk, q, v, tau).cloned()
    };
    let generic = aba(model, &mut dg, q, v, tau, fext).cloned();
    match (fast, generic) {
        (Ok(a), Ok(b)) => {
            // Forward: 1e-12 of the largest acceleration, or the textbook bound κ(M) ε
            // where the mass matrix is ill-conditioned (close to a gimbal lock, where
            // any two orders of the same arithmetic differ by that much; `aba`'s chain
            // and tree forms too).
            let m = satsim_tree::crba(model, &mut dg, q).unwrap().clone();
            let eig = m.symmetric_eigenvalues();
            let kappa_eps = eig.max() / eig.min() * f64::EPSILON;
            let e = (&a - &b).amax() / b.amax();
            assert!(
                e < 1e-12_f64.max(kappa_eps),
                "relative difference {e:e}, κε {kappa_eps:e}\n{a}\n{b}"
            );
            // Backward (no κ): inverse dynamics of the kernel's result gives back τ.
            let back = satsim_tree::rnea(model, &mut dg, q, v, a.as_slice(), fext).unwrap();
            let scale = (m.abs() * a.abs()).amax().max(1.0);
            let r = (back - DVector::from_column_slice(tau)).amax();
            assert!(r < 1e-12 * scale, "residual {r:e} of {scale:e}");
            true
        }
        (Err(x), Err(y)) => {
            same_refusal(&x, &y);
            false
        }
        (a, b) => panic!("kernel {a:?}, generic {b:?}"),
    }
}

fn same_refusal(x: &DynamicsError, y: &DynamicsError) {
    match (x, y) {
        (
            DynamicsError::SingularHinge {
                hinge: h1,
                through: t1,
                pivot: p1,
                ..
            },
            DynamicsError::SingularHinge {
                hinge: h2,
                through: t2,
                pivot: p2,
                ..
            },
        ) => {
            assert_eq!((h1, t1), (h2, t2));
            assert!((p1 - p2).abs() <= 1e-9 * p1.abs().max(p2.abs()).max(1e-3));
        }
        (DynamicsError::SingularBase, DynamicsError::SingularBase) => {}
        (x, y) => panic!("kernel {x:?}, generic {y:?}"),
    }
}

/// `model` with its masses and inertias scaled by `mass` and every nonzero hinge point
/// by `reach`: the same layout, other constants (a campaign's dispersed run).
fn dispersed(model: &Model, mass: f64, reach: f64) -> Model {
    let mut b = model.to_builder();
    for body in b.bodies_mut() {
        body.mass *= mass;
        body.inertia *= mass;
        body.com *= reach;
    }
    for h in b.hinges_mut() {
        h.at *= reach;
        h.child_at *= reach;
    }
    b.build().expect("a valid model")
}

/// Lane `k` of `xs`.
fn lane<const N: usize>(xs: &[F64x<N>], k: usize) -> Vec<f64> {
    xs.iter().map(|x| x.0[k]).collect()
}

/// `N` runs' vectors as one of lanes: lane `k` is `xs[k]`.
fn pack<const N: usize>(xs: [&[f64]; N]) -> Vec<F64x<N>> {
    (0..xs[0].len())
        .map(|i| F64x(std::array::from_fn(|k| xs[k][i])))
        .collect()
}

/// `N` runs' wrenches as wrenches of lanes: lane `k` is `fs[k]`.
fn pack_wrenches<const N: usize>(fs: [&[Force]; N]) -> Vec<Force<F64x<N>>> {
    (0..fs[0].len())
        .map(|b| {
            let f = |k: usize| fs[k][b].to_array();
            let part = |i: usize| F64x(std::array::from_fn(|k| f(k)[i]));
            Force::new(
                Vector3::new(part(0), part(1), part(2)),
                Vector3::new(part(3), part(4), part(5)),
            )
        })
        .collect()
}

/// `N` runs in lanes (each its own model of the layout, its own state with hinge angles
/// in `±3 · scale` rad, its own wrenches and the same locks) against each run's own `f64`
/// kernel: the same bits, or the batch parts (then a lane's own kernel refuses its state).
/// Every instance of the kernel this CPU runs (baseline, AVX2, AVX-512) gives the same.
fn lanes_agree<const N: usize>(
    models: &[Model; N],
    rng: &mut SplitMix,
    loaded: bool,
    locked: &[bool],
    scale: f64,
) -> bool {
    let kernels: Vec<UnrolledAba> = models
        .iter()
        .map(|m| UnrolledAba::new(m).unwrap())
        .collect();
    let lanes =
        UnrolledAba::<F64x<N>>::gather(std::array::from_fn(|k| &kernels[k])).expect("one layout");
    let locks = kernels[0].locks(locked).expect("the kernel's locks");
    let runs: Vec<_> = models
        .iter()
        .map(|m| {
            let (mut q, v, tau) = random_state(m, rng);
            for x in &mut q[m.base_nq()..] {
                *x *= scale;
            }
            (q, v, tau, random_wrenches(m, rng))
        })
        .collect();
    let q = pack(std::array::from_fn(|k| runs[k].0.as_slice()));
    let v = pack(std::array::from_fn(|k| runs[k].1.as_slice()));
    let tau = pack(std::array::from_fn(|k| runs[k].2.as_slice()));
    let fext = pack_wrenches(std::array::from_fn(|k| runs[k].3.as_slice()));
    let nv = models[0].nv();
    let mut ddq = vec![F64x::splat(f64::NAN); nv];
    let got = lanes.aba_hybrid_with_forces_into(
        &q,
        &v,
        &tau,
        loaded.then_some(fext.as_slice()),
        locks,
        &mut ddq,
    );
    // The narrower instructions this CPU has: the same outcome, the same bits.
    let widest = Instructions::detected();
    for narrower in [Instructions::Baseline, Instructions::Avx2].map(|i| i.min(widest)) {
        let mut ddq_narrow = vec![F64x::splat(f64::NAN); nv];
        let got_narrow = lanes
            .clone()
            .instructions(narrower)
            .aba_hybrid_with_forces_into(
                &q,
                &v,
                &tau,
                loaded.then_some(fext.as_slice()),
                locks,
                &mut ddq_narrow,
            );
        assert_eq!(got.is_ok(), got_narrow.is_ok(), "{narrower:?}");
        if got.is_ok() {
            let bits = |x: &[F64x<N>]| {
                x.iter()
                    .flat_map(|x| x.0.map(f64::to_bits))
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&ddq), bits(&ddq_narrow), "{narrower:?}");
        }
    }
    let mut alone = vec![0.0; nv];
    let each: Vec<_> = (0..N)
        .map(|k| {
            let (q, v, tau, f) = &runs[k];
            let solve = |kernel: &UnrolledAba, ddq: &mut Vec<f64>| {
                kernel
                    .aba_hybrid_with_forces_into(
                        q,
                        v,
                        tau,
                        loaded.then_some(f.as_slice()),
                        locks,
                        ddq,
                    )
                    .map(|()| ddq.clone())
            };
            let one = solve(&kernels[k], &mut alone);
            // One run on the narrower instructions too: the same outcome, the same bits.
            for narrower in [Instructions::Baseline, Instructions::Avx2].map(|i| i.min(widest)) {
                let mut ddq_narrow = vec![f64::NAN; nv];
                let narrow = solve(&kernels[k].clone().instructions(narrower), &mut ddq_narrow);
                let bits = |x: &Result<Vec<f64>, _>| {
                    x.as_ref()
                        .ok()
                        .map(|x| x.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
                };
                assert_eq!(bits(&one), bits(&narrow), "run {k}, {narrower:?}");
            }
            one
        })
        .collect();
    match got {
        Ok(()) => {
            for (k, one) in each.iter().enumerate() {
                let one = one.as_ref().expect("a lane solved, so its run solves");
                let bits = |x: &[f64]| x.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&lane(&ddq, k)), bits(one), "lane {k}");
            }
            true
        }
        // Some lane fell below the cheap pivot bound (near a singular configuration).
        Err(DynamicsError::LanesPart) => false,
        Err(e) => panic!("a batch fails only by parting: {e}"),
    }
}

#[test]
fn lanes_equal_runs_bit_for_bit() {
    let (mut batches, mut batches8) = (0, 0);
    for seed in 0..60u64 {
        let (serial, rotors) = ((seed % 5) as usize, ((seed / 5) % 4) as usize);
        let base = random_layout(serial, rotors, seed);
        let models = [
            base.clone(),
            dispersed(&base, 1.3, 1.0),
            dispersed(&base, 0.6, 1.2),
            dispersed(&base, 2.0, 0.8),
        ];
        // Eight lanes (one AVX-512 register per value): four more runs.
        let eight: [Model; 8] = std::array::from_fn(|k| match k {
            0..4 => models[k].clone(),
            _ => dispersed(
                &base,
                0.5 + 0.4 * k as f64 / 7.0,
                1.3 - 0.1 * k as f64 / 7.0,
            ),
        });
        let mut rng = SplitMix(seed ^ 0x1a4e);
        let n = base.n_hinges();
        // Nothing locked; every rotor and serial hinge the kernel takes locked in turn.
        let mut masks = vec![vec![false; n]];
        let kernel = UnrolledAba::new(&base).unwrap();
        masks.extend((0..n).filter_map(|h| {
            let mut m = vec![false; n];
            m[h] = true;
            kernel.locks(&m).map(|_| m)
        }));
        // Hinge angles anywhere, and all within π/4 (±0.75 rad: `sin_cos` lane-wise).
        let small = seed % 2 == 0;
        for mask in &masks {
            for (loaded, small) in [(false, small), (true, !small)] {
                let scale = if small { 0.25 } else { 1.0 };
                batches += usize::from(lanes_agree(&models, &mut rng, loaded, mask, scale));
                batches8 += usize::from(lanes_agree(&eight, &mut rng, loaded, mask, scale));
            }
        }
    }
    assert!(batches > 400, "only {batches} batches of four solved");
    assert!(batches8 > 400, "only {batches8} batches of eight solved");
}

/// Each width runs on the instance of its own register size, else the baseline's; one
/// run on each instruction set (`run` dispatches on `instance`).
#[test]
fn each_width_takes_its_own_instances() {
    use Instructions::{Avx2, Avx512, Baseline};
    let (_, model) = satellite_with_wheels();
    let one = UnrolledAba::new(&model).unwrap();
    let two = UnrolledAba::<F64x<2>>::gather([&one, &one]).unwrap();
    let four = UnrolledAba::<F64x<4>>::gather([&one; 4]).unwrap();
    let eight = UnrolledAba::<F64x<8>>::gather([&one; 8]).unwrap();
    for cap in [Baseline, Avx2, Avx512] {
        let level = cap.min(Instructions::detected());
        assert_eq!(one.clone().instructions(cap).instance(), level);
        assert_eq!(two.clone().instructions(cap).instance(), Baseline);
        assert_eq!(four.clone().instructions(cap).instance(), level.min(Avx2));
        let wide = if level == Avx512 { Avx512 } else { Baseline };
        assert_eq!(eight.clone().instructions(cap).instance(), wide);
    }
}

/// A gimbal lock on one lane parts the batch; the other lanes then solve on their own.
#[test]
fn a_singular_lane_parts_the_batch() {
    let (_, model) = satellite_with_wheels();
    let kernel = UnrolledAba::new(&model).unwrap();
    let lanes = UnrolledAba::<F64x<2>>::gather([&kernel, &kernel]).unwrap();
    let mut q = model.neutral();
    q[7..12].copy_from_slice(&[0.1, 0.2, 0.3, 1.2, -1.0]);
    let mut locked = q.clone();
    // the middle hinge at a right angle locks the outer two
    let middle = kernel.gimbal_angle[1];
    locked[middle] = std::f64::consts::FRAC_PI_2;
    let (v, tau) = (vec![0.01; model.nv()], vec![0.5; model.nv()]);
    let mut one = vec![0.0; model.nv()];
    let alone = kernel.aba_hybrid_with_forces_into(&locked, &v, &tau, None, Locks::NONE, &mut one);
    assert!(
        matches!(alone, Err(DynamicsError::SingularHinge { .. })),
        "{alone:?}"
    );
    let pack = |a: &[f64], b: &[f64]| -> Vec<F64x<2>> {
        a.iter().zip(b).map(|(&x, &y)| F64x([x, y])).collect()
    };
    let mut ddq = vec![F64x::splat(0.0); model.nv()];
    let got = lanes.aba_hybrid_with_forces_into(
        &pack(&q, &locked),
        &pack(&v, &v),
        &pack(&tau, &tau),
        None,
        Locks::NONE,
        &mut ddq,
    );
    assert!(matches!(got, Err(DynamicsError::LanesPart)), "{got:?}");
    kernel
        .aba_hybrid_with_forces_into(&q, &v, &tau, None, Locks::NONE, &mut one)
        .expect("the regular lane solves on its own");
}

/// Runs that differ in the layout, or in which serial hinge points coincide with the
/// parent's, are not gathered.
#[test]
fn other_shapes_are_not_gathered() {
    let base = random_layout(2, 2, 7);
    let k0 = UnrolledAba::new(&base).unwrap();
    let k1 = UnrolledAba::new(&dispersed(&base, 1.5, 1.1)).unwrap();
    assert!(UnrolledAba::<F64x<2>>::gather([&k0, &k1]).is_some());
    let other = UnrolledAba::new(&random_layout(2, 2, 8)).unwrap();
    assert!(UnrolledAba::<F64x<2>>::gather([&k0, &other]).is_none());
    let mut b = base.to_builder();
    // Body s1's hinge point on s0's: s1's frame then has its origin on its parent's.
    let find = |b: &mut ModelBuilder, name: &str| {
        b.hinges_mut().iter().position(|h| h.name == name).unwrap()
    };
    let (h0, h1) = (find(&mut b, "h0"), find(&mut b, "h1"));
    b.hinges_mut()[h1].at = b.hinges_mut()[h0].child_at;
    let k2 = UnrolledAba::new(&b.build().unwrap()).unwrap();
    assert!(UnrolledAba::<F64x<2>>::gather([&k0, &k2]).is_none());
    assert!(UnrolledAba::<F64x<2>>::gather([&k2, &k2]).is_some());
}

#[test]
fn preprint_satellite_equals_generic_aba() {
    let (plain, wheels) = satellite_with_wheels();
    for (model, rotors) in [(plain, 0), (wheels, 3)] {
        let kernel = UnrolledAba::new(&model).expect("the preprint's layout");
        assert_eq!((kernel.serial_bodies(), kernel.rotors.len()), (2, rotors));
        let mut rng = SplitMix(11);
        let solved = (0..300)
            .filter(|_| {
                let (q, v, tau) = random_state(&model, &mut rng);
                let fext = random_wrenches(&model, &mut rng);
                let free = agrees(&model, &kernel, &q, &v, &tau, None);
                let loaded = agrees(&model, &kernel, &q, &v, &tau, Some(&fext));
                assert_eq!(free, loaded, "a force changes no pivot");
                free
            })
            .count();
        assert!(solved > 290, "{solved}");
    }
}

/// The preprint's length has its own unrolled instance; the instance that every other
/// length shares, run on the preprint's layout, gives the same bits: one run on every
/// instruction set this CPU has, and four lanes; with and without wrenches; free, a
/// panel's hinge locked, a wheel locked.
#[test]
fn the_instance_of_any_length_gives_the_unrolled_ones_bits() {
    /// `q`, `v`, `tau` and the wrenches, if any.
    type Args<'a, T> = (&'a [T], &'a [T], &'a [T], Option<&'a [Force<T>]>);
    fn both<T: Real>(
        kernel: &UnrolledAba<T>,
        (q, v, tau, fext): Args<'_, T>,
        locks: Locks,
    ) -> Option<(Vec<T>, Vec<T>)> {
        let (mut exact, mut any) = (vec![T::zero(); v.len()], vec![T::zero(); v.len()]);
        let unrolled = kernel.aba_hybrid_with_forces_into(q, v, tau, fext, locks, &mut exact);
        let shared = match fext {
            None => kernel.run::<MAX_SERIAL, false, false>(&mut any, q, v, tau, &[], locks),
            Some(f) => kernel.run::<MAX_SERIAL, false, true>(&mut any, q, v, tau, f, locks),
        };
        assert_eq!(unrolled.is_ok(), shared.is_ok());
        unrolled.ok().map(|()| (exact, any))
    }
    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    let (_, model) = satellite_with_wheels();
    let one = UnrolledAba::new(&model).unwrap();
    assert_eq!(one.serial_bodies(), PREPRINT_SERIAL);
    let mut masks = vec![vec![false; one.n_hinges]; 3];
    masks[1][one.serial_hinges[1]] = true;
    masks[2][one.rotor_hinges[0]] = true;
    let lanes = UnrolledAba::<F64x<4>>::gather([&one; 4]).unwrap();
    let mut rng = SplitMix(29);
    let mut solved = 0;
    for case in 0..240 {
        let locks = one.locks(&masks[case % 3]).unwrap();
        let loaded = case % 2 == 1;
        let runs: [_; 4] = std::array::from_fn(|_| {
            let (q, v, tau) = random_state(&model, &mut rng);
            (q, v, tau, random_wrenches(&model, &mut rng))
        });
        let (q, v, tau, f) = &runs[0];
        for cap in [
            Instructions::Baseline,
            Instructions::Avx2,
            Instructions::Avx512,
        ] {
            let kernel = one.clone().instructions(cap);
            let fext = loaded.then_some(f.as_slice());
            if let Some((exact, any)) = both(&kernel, (q, v, tau, fext), locks) {
                assert_eq!(bits(&exact), bits(&any), "case {case}, {cap:?}");
                solved += 1;
            }
        }
        let (q4, v4, tau4) = (
            pack(std::array::from_fn(|k| runs[k].0.as_slice())),
            pack(std::array::from_fn(|k| runs[k].1.as_slice())),
            pack(std::array::from_fn(|k| runs[k].2.as_slice())),
        );
        let f4 = pack_wrenches(std::array::from_fn(|k| runs[k].3.as_slice()));
        let fext = loaded.then_some(f4.as_slice());
        if let Some((exact, any)) = both(&lanes, (&q4, &v4, &tau4, fext), locks) {
            for k in 0..4 {
                assert_eq!(bits(&lane(&exact, k)), bits(&lane(&any, k)), "case {case}");
            }
            solved += 1;
        }
    }
    assert!(solved > 800, "{solved}");
}

#[test]
fn random_layouts_equal_generic_aba() {
    let mut solved = 0;
    let mut seen = [[0usize; 4]; 5]; // serial bodies x rotors
    for seed in 0..400u64 {
        let (serial, rotors) = ((seed % 5) as usize, ((seed / 5) % 4) as usize);
        let model = random_layout(serial, rotors, seed);
        let kernel = UnrolledAba::new(&model).expect("the layout");
        assert_eq!(kernel.serial_bodies(), serial);
        assert_eq!(kernel.rotors.len(), rotors);
        let mut rng = SplitMix(seed ^ 0xab1e);
        for _ in 0..3 {
            let (q, v, tau) = random_state(&model, &mut rng);
            let fext = random_wrenches(&model, &mut rng);
            let free = agrees(&model, &kernel, &q, &v, &tau, None);
            let loaded = agrees(&model, &kernel, &q, &v, &tau, Some(&fext));
            assert_eq!(free, loaded, "a force changes no pivot");
            if free {
                solved += 1;
                seen[serial][rotors] += 1;
            }
        }
    }
    assert!(solved > 1100, "only {solved} regular cases");
    assert!(seen.iter().flatten().all(|&s| s > 30), "{seen:?}");
}

/// Layouts that differ from the kernel's in one way each are not taken.
#[test]
fn other_layouts_are_refused() {
    let base = random_layout(2, 2, 7);
    assert!(UnrolledAba::new(&base).is_some());
    let hinge_of = |b: &mut ModelBuilder, name: &str| {
        b.hinges_mut().iter().position(|h| h.name == name).unwrap()
    };
    let variant = |f: &dyn Fn(&mut ModelBuilder)| {
        let mut b = base.to_builder();
        f(&mut b);
        UnrolledAba::new(&b.build().unwrap())
    };
    // A fixed base.
    let mut b = ModelBuilder::new(BaseKind::Fixed);
    for x in base.to_builder().bodies_mut() {
        b.push_body(x.clone());
    }
    for h in base.to_builder().hinges_mut() {
        b.push_hinge(h.clone());
    }
    assert!(
        UnrolledAba::new(&b.build().unwrap()).is_none(),
        "fixed base"
    );
    // Armature on a serial hinge, on a gimbal hinge.
    for name in ["h1", "g2"] {
        let r = variant(&|b| {
            let k = hinge_of(b, name);
            b.hinges_mut()[k].armature = 0.1;
        });
        assert!(r.is_none(), "armature on {name}");
    }
    // A general axis, a fixed rotation, on a serial hinge and on a gimbal hinge.
    for name in ["h0", "g3"] {
        let r = variant(&|b| {
            let k = hinge_of(b, name);
            b.hinges_mut()[k].axis = Vec3::new(1.0, 1.0, 0.0).normalize();
        });
        assert!(r.is_none(), "general axis on {name}");
        let r = variant(&|b| {
            let k = hinge_of(b, name);
            b.hinges_mut()[k].rotation = Quaternion::new(0.9, 0.1, 0.0, 0.0).normalize();
        });
        assert!(r.is_none(), "fixed rotation on {name}");
    }
    // A branch below the tip, a second (non-rotor) body on the bus, a rotor off the base.
    for parent in ["tip", "s0", "bus"] {
        let r = variant(&|b| {
            b.push_body(Body::new("extra", 1.0, Mat3::identity()).with_com(Vec3::x()));
            b.push_hinge(Hinge::revolute("extra", parent, "extra", Vec3::z()));
        });
        assert!(r.is_none(), "an extra body on {parent}");
    }
    let r = variant(&|b| {
        b.push_body(Body::new("wheel", 1.0, Mat3::identity()));
        b.push_hinge(Hinge::revolute("wheel", "s1", "wheel", Vec3::z()));
    });
    assert!(r.is_none(), "a rotor off the base");
    // Offset links: link 2's origin off the gimbal's point (zero length kept).
    let r = variant(&|b| {
        for h in b.hinges_mut() {
            if h.child == "l2" {
                h.child_at = Vec3::new(0.1, 0.2, 0.0);
            }
            if h.parent == "l2" {
                h.at = Vec3::new(0.1, 0.2, 0.0);
            }
        }
    });
    assert!(r.is_none(), "offset links");
    // A link with mass: no chain.
    let r = variant(&|b| {
        let k = b.bodies_mut().iter().position(|x| x.name == "l1").unwrap();
        b.bodies_mut()[k] = Body::new("l1", 1.0, Mat3::identity());
    });
    assert!(r.is_none(), "no chain");
    // A 2-DOF gimbal: link 2 welded away (tip hinged on link 1).
    let mut b = ModelBuilder::new(BaseKind::Free);
    for x in base
        .to_builder()
        .bodies_mut()
        .iter()
        .filter(|x| x.name != "l2")
    {
        b.push_body(x.clone());
    }
    for h in base.to_builder().hinges_mut() {
        if h.name == "g2" {
            continue;
        }
        if h.parent == "l2" {
            h.parent = "l1".into();
        }
        b.push_hinge(h.clone());
    }
    assert!(UnrolledAba::new(&b.build().unwrap()).is_none(), "k = 2");
    // Too long a serial chain.
    let long = random_layout(MAX_SERIAL, 0, 3);
    assert!(UnrolledAba::new(&long).is_some());
    let mut b = long.to_builder();
    b.push_body(Body::new("last", 1.0, Mat3::identity()).with_com(Vec3::x()));
    let tail = format!("s{}", MAX_SERIAL - 1);
    b.push_hinge(Hinge::revolute("last", tail, "last", Vec3::z()));
    assert!(UnrolledAba::new(&b.build().unwrap()).is_none(), "too long");
}

/// A gimbal lock (the middle hinge at 90°) fails as in the generic ABA: the same hinge,
/// the same hinges named through the links, the same pivot.
#[test]
fn gimbal_lock_fails_as_generic_aba() {
    let (_, model) = satellite_with_wheels();
    let kernel = UnrolledAba::new(&model).unwrap();
    let mut q = model.neutral();
    q[7..12].copy_from_slice(&[0.3, std::f64::consts::FRAC_PI_2, 0.1, 1.2, -1.0]);
    let v: Vec<f64> = (0..model.nv()).map(|k| 0.01 * k as f64).collect();
    let tau = vec![0.3; model.nv()];
    let (mut dk, mut dg) = (Data::new(&model), Data::new(&model));
    let x = kernel.aba(&mut dk, &q, &v, &tau).unwrap_err();
    let y = aba(&model, &mut dg, &q, &v, &tau, None).unwrap_err();
    same_refusal(&x, &y);
    assert!(matches!(&x, DynamicsError::SingularHinge { hinge, .. } if hinge == "h1"));
    // Close to the lock both solve, and agree.
    q[8] = std::f64::consts::FRAC_PI_2 - 1e-3;
    let fast = kernel.aba(&mut dk, &q, &v, &tau).unwrap().clone();
    let generic = aba(&model, &mut dg, &q, &v, &tau, None).unwrap();
    assert!((&fast - generic).amax() < 1e-9 * generic.amax());
}

/// A wrench on one body at a time (each kind: base, rotor, link, tip, serial body) moves
/// the accelerations, and as in the generic ABA.
#[test]
fn each_bodys_wrench_acts_as_in_generic_aba() {
    for seed in 0..20u64 {
        let model = random_layout(2, 2, seed);
        let kernel = UnrolledAba::new(&model).unwrap();
        let mut rng = SplitMix(seed ^ 0xf0ce);
        let (q, v, tau) = random_state(&model, &mut rng);
        let mut data = Data::new(&model);
        let Ok(free) = kernel.aba(&mut data, &q, &v, &tau).cloned() else {
            continue;
        };
        for i in 0..model.n_bodies() {
            let mut fext = vec![Force::zero(); model.n_bodies()];
            fext[i] = Force::new(rng.vec3(5.0), rng.vec3(5.0));
            assert!(agrees(&model, &kernel, &q, &v, &tau, Some(&fext)));
            let loaded = kernel
                .aba_with_forces(&mut data, &q, &v, &tau, Some(&fext))
                .unwrap();
            let moved = (loaded - &free).amax();
            assert!(moved > 1e-6 * free.amax(), "body {i}: moved {moved:e}");
        }
    }
}

/// Hybrid dynamics: random locks on the rotors and the serial bodies, with and without
/// wrenches, against the generic `aba_hybrid` (the plain tree form: rotors and links as
/// bodies), forward to the same tolerance as above (a locked system's mass matrix is a
/// principal block of `M`: its κ is no larger) and backward (RNEA of the result gives
/// back `τ` on the free hinges; the locked ones do not move).
#[test]
fn hybrid_equals_generic_aba_hybrid() {
    let (mut solved, mut locked_rotors, mut locked_serial) = (0, 0, 0);
    for seed in 0..300u64 {
        let (serial, rotors) = ((seed % 5) as usize, ((seed / 5) % 4) as usize);
        let model = random_layout(serial, rotors, seed);
        let kernel = UnrolledAba::new(&model).unwrap();
        let mut rng = SplitMix(seed ^ 0x10c4);
        let (q, v, tau) = random_state(&model, &mut rng);
        let fext = random_wrenches(&model, &mut rng);
        let gimbal: Vec<usize> = kernel.gimbal_hinges.to_vec();
        let locked: Vec<bool> = (0..model.n_hinges())
            .map(|h| !gimbal.contains(&h) && rng.next_f64() < 0.5)
            .collect();
        let locks = kernel.locks(&locked).expect("no gimbal hinge locked");
        locked_rotors += locks.rotors.count_ones();
        locked_serial += locks.serial.count_ones();
        for f in [None, Some(fext.as_slice())] {
            let (mut dk, mut dg) = (Data::new(&model), Data::new(&model));
            let fast = kernel
                .aba_hybrid_with_forces(&mut dk, &q, &v, &tau, f, locks)
                .cloned();
            let generic =
                satsim_tree::aba::aba_hybrid(&model, &mut dg, &q, &v, &tau, f, &locked).cloned();
            let (a, b) = match (fast, generic) {
                (Ok(a), Ok(b)) => (a, b),
                (Err(x), Err(y)) => {
                    same_refusal(&x, &y);
                    continue;
                }
                (a, b) => panic!("seed {seed}: kernel {a:?}, generic {b:?}"),
            };
            solved += 1;
            let m = satsim_tree::crba(&model, &mut dg, &q).unwrap().clone();
            let eig = m.symmetric_eigenvalues();
            let kappa_eps = eig.max() / eig.min() * f64::EPSILON;
            let e = (&a - &b).amax() / b.amax();
            assert!(e < 1e-12_f64.max(kappa_eps), "seed {seed}: {e:e}\n{a}\n{b}");
            let back = satsim_tree::rnea(&model, &mut dg, &q, &v, a.as_slice(), f).unwrap();
            let scale = (m.abs() * a.abs()).amax().max(1.0);
            for (h, &l) in locked.iter().enumerate() {
                let dof = model.base_nv() + h;
                if l {
                    assert_eq!(a[dof], 0.0, "seed {seed}: locked hinge {h} moves");
                } else {
                    let r = (back[dof] - tau[dof]).abs();
                    assert!(r < 1e-12 * scale, "seed {seed}: hinge {h} residual {r:e}");
                }
            }
        }
    }
    assert!(solved > 550, "only {solved} regular cases");
    assert!(locked_rotors > 100 && locked_serial > 100);
}

/// A lock mask with a gimbal hinge locked, or of another length, is not the kernel's.
#[test]
fn gimbal_locks_are_not_taken() {
    let model = random_layout(2, 2, 9);
    let kernel = UnrolledAba::new(&model).unwrap();
    let mut locked = vec![false; model.n_hinges()];
    assert_eq!(kernel.locks(&locked), Some(Locks::NONE));
    for &h in &kernel.gimbal_hinges {
        locked[h] = true;
        assert_eq!(kernel.locks(&locked), None);
        locked[h] = false;
    }
    assert_eq!(kernel.locks(&locked[1..]), None);
    for (h, l) in locked.iter_mut().enumerate() {
        *l = !kernel.gimbal_hinges.contains(&h);
    }
    let locks = kernel.locks(&locked).unwrap();
    assert_eq!((locks.rotors, locks.serial), (0b11, 0b11));
}

#[test]
fn wrong_lengths_are_refused() {
    let model = random_layout(1, 1, 5);
    let kernel = UnrolledAba::new(&model).unwrap();
    let mut data = Data::new(&model);
    let (q, v) = (model.neutral(), vec![0.0; model.nv()]);
    assert!(kernel.aba(&mut data, &q[1..], &v, &v).is_err());
    assert!(kernel.aba(&mut data, &q, &v[1..], &v).is_err());
    assert!(kernel.aba(&mut data, &q, &v, &v[1..]).is_err());
    let other = random_layout(2, 1, 5);
    assert!(kernel.aba(&mut Data::new(&other), &q, &v, &v).is_err());
    let fext = vec![Force::zero(); model.n_bodies()];
    // (At the neutral angles this gimbal's first and last axes may be parallel: locked.)
    let (q, v, tau) = random_state(&model, &mut SplitMix(1));
    assert!(
        kernel
            .aba_with_forces(&mut data, &q, &v, &tau, Some(&fext))
            .is_ok()
    );
    let e = kernel
        .aba_with_forces(&mut data, &q, &v, &tau, Some(&fext[1..]))
        .unwrap_err();
    assert!(e.to_string().contains("fext"), "{e}");
    // The `_into` form: the same numbers, bit for bit, into the caller's slice, whose
    // length is checked too.
    let mut ddq = vec![0.0; model.nv()];
    kernel
        .aba_hybrid_with_forces_into(&q, &v, &tau, Some(&fext), Locks::NONE, &mut ddq)
        .unwrap();
    let into_data = kernel.aba_with_forces(&mut data, &q, &v, &tau, Some(&fext));
    assert_eq!(ddq.as_slice(), into_data.unwrap().as_slice());
    let e = kernel
        .aba_hybrid_with_forces_into(&q, &v, &tau, None, Locks::NONE, &mut ddq[1..])
        .unwrap_err();
    assert!(e.to_string().contains("ddq"), "{e}");
}
