//! Ready-made trees for benchmarks, tests and examples: chains and binary trees of identical
//! links, and a deterministic pseudo-random tree.

use crate::model::{BaseKind, Body, Hinge, Model, ModelBuilder};
use crate::spatial::{Mat3, Vec3};
use nalgebra::Quaternion;

fn link(i: usize) -> Body {
    Body::new(
        format!("b{i}"),
        1.0,
        Mat3::from_diagonal(&Vec3::new(0.02, 0.08, 0.09)),
    )
    .with_com(Vec3::new(0.25, 0.0, 0.0))
}

fn hinge(i: usize, parent: usize) -> Hinge {
    // Alternate axes so that no two consecutive hinges are parallel.
    let axis = match i % 3 {
        0 => Vec3::z(),
        1 => Vec3::y(),
        _ => Vec3::x(),
    };
    Hinge::revolute(format!("h{i}"), format!("b{parent}"), format!("b{i}"), axis)
        .at(Vec3::new(0.5, 0.0, 0.0))
}

/// A chain of `n` bodies: body 0 the root, body `i` hinged to body `i − 1`.
///
/// ```
/// let m = satsim_tree::samples::chain(10, satsim_tree::BaseKind::Free);
/// assert_eq!(m.nv(), 6 + 9);
/// ```
pub fn chain(n: usize, base: BaseKind) -> Model {
    let mut b = ModelBuilder::new(base);
    for i in 0..n {
        b.push_body(link(i));
        if i > 0 {
            b.push_hinge(hinge(i, i - 1));
        }
    }
    b.build().expect("a chain of identical links is valid")
}

/// A balanced binary tree of `n` bodies: body `i` hinged to body `(i − 1) / 2`.
///
/// ```
/// let m = satsim_tree::samples::binary_tree(15, satsim_tree::BaseKind::Fixed);
/// assert_eq!(m.nv(), 14);
/// ```
pub fn binary_tree(n: usize, base: BaseKind) -> Model {
    let mut b = ModelBuilder::new(base);
    for i in 0..n {
        b.push_body(link(i));
        if i > 0 {
            b.push_hinge(hinge(i, (i - 1) / 2));
        }
    }
    b.build()
        .expect("a binary tree of identical links is valid")
}

/// A small deterministic generator (SplitMix64), so samples need no dependency.
#[derive(Clone, Debug)]
pub struct SplitMix(pub u64);

impl SplitMix {
    /// The next number, uniform in `[0, 1)`.
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }
    /// A vector with entries uniform in `[-s, s)`.
    pub fn vec3(&mut self, s: f64) -> Vec3 {
        Vec3::new(self.range(-s, s), self.range(-s, s), self.range(-s, s))
    }
    /// A random unit vector.
    pub fn unit(&mut self) -> Vec3 {
        loop {
            let v = self.vec3(1.0);
            let n = v.norm();
            if n > 0.1 && n < 1.0 {
                return v / n;
            }
        }
    }
}

/// Adds three balanced reaction wheels to `parent` (2 kg, 0.1 kg m² about their axes `x`,
/// `y`, `z`, 0.05 transverse, 0.3 m out along their axes; bodies and hinges named `x`, `y`,
/// `z`): the peer orbit's wheels (`benches/peers/orbit.toml`), as `satsim-satellite` adds
/// them, for the benchmarks and tests of the gyrostat and unrolled paths.
pub fn push_wheels(b: &mut ModelBuilder, parent: &str) {
    for (k, name) in ["x", "y", "z"].into_iter().enumerate() {
        let axis = Vec3::ith(k, 1.0);
        let aat = axis * axis.transpose();
        let inertia = aat * 0.1 + (Mat3::identity() - aat) * 0.05;
        b.push_body(Body::new(name, 2.0, inertia));
        b.push_hinge(Hinge::revolute(name, parent, name, axis).at(axis * 0.3));
    }
}

/// A random configuration `q` of `model`: a random unit attitude `[w, x, y, z]` and a
/// position with entries in `[-position, position)` for a free base, hinge angles in
/// `[-3, 3)` rad.
pub fn random_q(model: &Model, rng: &mut SplitMix, position: f64) -> Vec<f64> {
    let mut q = model.neutral();
    if model.base() == BaseKind::Free {
        let a = Quaternion::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        )
        .normalize();
        q[..4].copy_from_slice(&[a.w, a.i, a.j, a.k]);
        for x in &mut q[4..7] {
            *x = rng.range(-position, position);
        }
    }
    let nb = model.base_nq();
    for x in &mut q[nb..] {
        *x = rng.range(-3.0, 3.0);
    }
    q
}

/// A random physical inertia about the centre of mass: `R diag(p) Rᵀ` with principal moments
/// obeying the triangle inequality.
pub fn random_inertia(rng: &mut SplitMix, scale: f64) -> Mat3 {
    let (a, b) = (rng.range(0.2, 1.0), rng.range(0.2, 1.0));
    let c = rng.range((a - b).abs() + 0.01, a + b);
    let r = nalgebra::Rotation3::from_axis_angle(
        &nalgebra::Unit::new_normalize(rng.unit()),
        rng.range(0.0, 3.0),
    );
    let m = r.matrix() * Mat3::from_diagonal(&Vec3::new(a, b, c)) * r.matrix().transpose() * scale;
    (m + m.transpose()) * 0.5
}

/// A random tree of `n` bodies: random parents (so random branching), axes, hinge points,
/// fixed rotations, masses, centres of mass and inertias; when `massless_links`, some
/// non-leaf bodies are massless zero-length gimbal links. Hinges are listed in a shuffled
/// order to exercise the file-order coordinates.
///
/// ```
/// let m = satsim_tree::samples::random_tree(20, satsim_tree::BaseKind::Free, true, 7);
/// assert_eq!(m.n_bodies(), 20);
/// ```
pub fn random_tree(n: usize, base: BaseKind, massless_links: bool, seed: u64) -> Model {
    random_builder(n, base, massless_links, seed)
        .0
        .build()
        .expect("random trees are built valid")
}

/// [`random_tree`] plus `rotors` balanced axisymmetric rotors on random bodies (random spin
/// axis, hinge point, mass (zero for every other rotor), axial and transverse inertia, centre
/// of mass on the axis): the leaves that ABA treats as gyrostats ([`crate::Gyrostat`]).
///
/// ```
/// let m = satsim_tree::samples::random_tree_with_rotors(8, satsim_tree::BaseKind::Free, true, 3, 7);
/// assert_eq!(m.gyrostats().len(), 3);
/// ```
pub fn random_tree_with_rotors(
    n: usize,
    base: BaseKind,
    massless_links: bool,
    rotors: usize,
    seed: u64,
) -> Model {
    let (mut b, mut rng) = random_builder(n, base, massless_links, seed);
    for k in 0..rotors {
        // Carriers: any body with mass (a rotor on a massless link would be a massless leaf
        // chain's end, which is fine too, but keep the carriers ordinary).
        let p = loop {
            let p = (rng.next_f64() * n as f64) as usize;
            if b.bodies[p].mass > 0.0 {
                break p;
            }
        };
        let axis = rng.unit();
        let j = rng.range(0.01, 0.2);
        let it = rng.range(0.55 * j, 2.0 * j); // J ≤ 2 Iₜ: a physical rotor
        let aat = axis * axis.transpose();
        let inertia = aat * j + (Mat3::identity() - aat) * it;
        let mass = if k % 2 == 0 { rng.range(0.1, 3.0) } else { 0.0 };
        // The centre of mass on the axis, away from the body origin; the hinge point on the
        // axis too.
        let com = rng.vec3(0.3);
        let child_at = com + axis * rng.range(-0.2, 0.2);
        let name = format!("rotor{k}");
        b.push_body(Body::new(name.clone(), mass, inertia).with_com(com));
        b.push_hinge(
            Hinge::revolute(name.clone(), b.bodies[p].name.clone(), name, axis)
                .at(rng.vec3(0.5))
                .child_at(child_at),
        );
    }
    b.build().expect("random trees with rotors are built valid")
}

fn random_builder(
    n: usize,
    base: BaseKind,
    massless_links: bool,
    seed: u64,
) -> (ModelBuilder, SplitMix) {
    let mut rng = SplitMix(seed);
    let parents: Vec<usize> = (0..n)
        .map(|i| {
            if i == 0 {
                0
            } else {
                (rng.next_f64() * i as f64) as usize
            }
        })
        .collect();
    let has_child: Vec<bool> = (0..n)
        .map(|i| parents.iter().skip(1).any(|&p| p == i))
        .collect();
    let mut b = ModelBuilder::new(base);
    let mut massless = vec![false; n];
    for i in 0..n {
        // At most two massless links in a row: with three, four hinges would meet at one
        // point and the tree would be singular.
        let p = parents[i];
        let two_above = i > 0 && massless[p] && massless[parents[p]];
        massless[i] = massless_links && i > 0 && has_child[i] && !two_above && rng.next_f64() < 0.3;
        let body = if massless[i] {
            Body::massless(format!("b{i}"))
        } else {
            let m = rng.range(0.5, 5.0);
            Body::new(format!("b{i}"), m, random_inertia(&mut rng, m * 0.1)).with_com(rng.vec3(0.3))
        };
        b.push_body(body);
    }
    let mut hinges: Vec<Hinge> = (1..n)
        .map(|i| {
            let p = parents[i];
            let q = Quaternion::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            // Massless links are zero-length: the hinge point is the link's origin.
            let child_at = if massless[i] {
                Vec3::zeros()
            } else {
                rng.vec3(0.5)
            };
            let at = if massless[p] {
                Vec3::zeros()
            } else {
                rng.vec3(0.5)
            };
            Hinge::revolute(
                format!("h{i}"),
                format!("b{p}"),
                format!("b{i}"),
                rng.unit(),
            )
            .at(at)
            .child_at(child_at)
            .rotation(q.normalize())
        })
        .collect();
    for k in (1..hinges.len()).rev() {
        let j = (rng.next_f64() * (k + 1) as f64) as usize;
        hinges.swap(k, j);
    }
    for h in hinges {
        b.push_hinge(h);
    }
    (b, rng)
}
