//! Shared helpers of the preprint tests: a tiny deterministic generator (driven by proptest's
//! seeds) and random models with the preprint's layout but arbitrary frames.
#![allow(dead_code)]

use nalgebra::{Quaternion, UnitQuaternion};
use satsim_satellite::{Deployment, PreprintParams, build_model};
use satsim_tree::spatial::{Force, Mat3, Vec3};
use satsim_tree::{BaseKind, Body, Hinge, Model, ModelBuilder};

/// SplitMix64.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn vec3(&mut self, r: f64) -> Vec3 {
        Vec3::new(
            self.uniform(-r, r),
            self.uniform(-r, r),
            self.uniform(-r, r),
        )
    }
    pub fn unit(&mut self) -> Vec3 {
        loop {
            let v = self.vec3(1.0);
            if v.norm() > 0.2 && v.norm() < 1.0 {
                return v.normalize();
            }
        }
    }
    pub fn rotation(&mut self) -> UnitQuaternion<f64> {
        UnitQuaternion::from_quaternion(Quaternion::new(
            self.uniform(-1.0, 1.0),
            self.uniform(-1.0, 1.0),
            self.uniform(-1.0, 1.0),
            self.uniform(-1.0, 1.0),
        ))
    }
    /// A random rigid-body inertia about the centre of mass (from random point-mass second
    /// moments, so the triangle inequality holds), in random axes.
    pub fn inertia(&mut self, mass: f64, size: f64) -> Mat3 {
        let p = Mat3::from_diagonal(&Vec3::new(
            self.uniform(0.02, 1.0),
            self.uniform(0.02, 1.0),
            self.uniform(0.02, 1.0),
        )) * (mass * size * size);
        let i = Mat3::identity() * p.trace() - p;
        let r = self.rotation().to_rotation_matrix().into_inner();
        let i = r * i * r.transpose();
        (i + i.transpose()) * 0.5
    }
}

/// A random model with the preprint's layout: random masses, inertias, centres of mass away
/// from the body frames, hinge points, axes and fixed rotations (link frames included).
pub fn random_model(rng: &mut Rng) -> Model {
    let m_bus = rng.uniform(10.0, 1000.0);
    let m_p = [
        rng.uniform(0.5, 50.0),
        rng.uniform(0.5, 50.0),
        rng.uniform(0.5, 50.0),
    ];
    let bus = Body::new("bus", m_bus, rng.inertia(m_bus, 1.0)).with_com(rng.vec3(0.5));
    let panels: Vec<Body> = (0..3)
        .map(|k| {
            Body::new(format!("panel{}", k + 1), m_p[k], rng.inertia(m_p[k], 0.6))
                .with_com(rng.vec3(0.5))
        })
        .collect();
    let p1_link1 = rng.vec3(0.5);
    let p2_link2 = rng.vec3(0.5);
    let q = |rng: &mut Rng| *rng.rotation().quaternion();
    let h1 = Hinge::revolute("h1", "bus", "link1", rng.unit())
        .at(rng.vec3(2.0))
        .child_at(p1_link1)
        .rotation(q(rng));
    let h2 = Hinge::revolute("h2", "link1", "link2", rng.unit())
        .at(p1_link1)
        .child_at(p2_link2)
        .rotation(q(rng));
    let h3 = Hinge::revolute("h3", "link2", "panel1", rng.unit())
        .at(p2_link2)
        .child_at(rng.vec3(1.5))
        .rotation(q(rng));
    let h4 = Hinge::revolute("h4", "panel1", "panel2", rng.unit())
        .at(rng.vec3(1.5))
        .child_at(rng.vec3(1.5))
        .rotation(q(rng));
    let h5 = Hinge::revolute("h5", "panel2", "panel3", rng.unit())
        .at(rng.vec3(1.5))
        .child_at(rng.vec3(1.5))
        .rotation(q(rng));
    ModelBuilder::new(BaseKind::Free)
        .body(bus)
        .body(Body::massless("link1"))
        .body(Body::massless("link2"))
        .body(panels[0].clone())
        .body(panels[1].clone())
        .body(panels[2].clone())
        .hinge(h1)
        .hinge(h2)
        .hinge(h3)
        .hinge(h4)
        .hinge(h5)
        .build()
        .expect("a valid random model")
}

/// A random engine state `(q, v, tau)` for an 11-DOF free model.
pub fn random_state(rng: &mut Rng, rate: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let att = rng.rotation();
    let mut q = vec![att.w, att.i, att.j, att.k];
    q.extend(rng.vec3(10.0).iter());
    q.extend((0..5).map(|_| rng.uniform(-3.2, 3.2)));
    let v: Vec<f64> = (0..11).map(|_| rng.uniform(-rate, rate)).collect();
    let mut tau = vec![0.0; 11];
    for t in tau.iter_mut().skip(6) {
        *t = rng.uniform(-2.0, 2.0);
    }
    (q, v, tau)
}

/// The realistic satellite at a deployment state, with the example state's rates and torques
/// (`shared/spec/examples/state.json`) scaled by `rate_scale`.
pub fn realistic(d: Deployment, rate_scale: f64) -> (Model, Vec<f64>, Vec<f64>, Vec<f64>) {
    let model = build_model(&PreprintParams::default()).unwrap();
    let mut q = model.neutral();
    q[7..12].copy_from_slice(&d.angles());
    let mut v = vec![
        0.001, -0.002, 0.0015, 0.0, 0.0, 0.0, 0.01, 0.02, -0.01, 0.05, -0.04,
    ];
    for x in v.iter_mut() {
        *x *= rate_scale;
    }
    let tau = vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -0.5, 0.4];
    (model, q, v, tau)
}

/// External couples `M1..M4` (each in its body's own axes) as engine forces.
pub fn couples(model: &Model, layout_bodies: [usize; 4], m: &[Vec3; 4]) -> Vec<Force> {
    let mut f = vec![Force::zero(); model.n_bodies()];
    for (k, &b) in layout_bodies.iter().enumerate() {
        f[b] = Force::new(m[k], Vec3::zeros());
    }
    f
}
