//! The kinematics of a hinge carried by a flexible parent: the joint frame displaced by
//! `Φ η` and turned by `Ψ η`, as a sequence of virtual joints whose motion subspaces are
//! constant in their own frames (so that the model is exactly Lagrangian and the three
//! algorithms use one set of exact formulas).
//!
//! Stage 0 translates the frame to `at + Φ η` (axes unchanged: subspace `[0; Φ]`). Then one
//! rotation stage per rotation axis: when every `Ψₖ` is parallel to one unit vector `e` (a
//! beam bending in a plane), a single rotation about `e` by `(ψ · η)` (subspace `[e ψᵀ; 0]`,
//! `e` invariant); otherwise three, about the body's x, y and z axes in turn. To first order
//! in `η` the node frame is displaced by `Φ η` and turned by `Ψ η`.

use super::modal::NodeShape;
use crate::spatial::{Mat3, Motion, Transform, Vec3, rotation_about};

/// One rotation stage: about the unit `axis` by `Σₖ coef[k] ηₖ`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RotationStage {
    pub(crate) axis: Vec3,
    pub(crate) coef: Vec<f64>,
}

/// A child hinge's node on its flexible parent (parent body frame).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Node {
    /// The hinge point `at` (m).
    pub(crate) at: Vec3,
    /// `Φₖ` per parent mode.
    pub(crate) phi: Vec<Vec3>,
    /// The rotation stages (none when `Ψ = 0`).
    pub(crate) rotations: Vec<RotationStage>,
}

/// The node frame from the parent's coordinates, its velocity and velocity-product
/// acceleration, for the parent's current `η`, `η̇` and velocity.
#[derive(Clone, Copy, Debug)]
pub(crate) struct NodeState {
    /// From the parent's coordinates to the node frame.
    pub(crate) x: Transform,
    /// The node frame's spatial velocity (node coordinates).
    pub(crate) w: Motion,
    /// Its acceleration not proportional to `a_parent` or `η̈`: Σ over stages of
    /// `wₛ ×m (Sₛ η̇)`, carried to the node frame.
    pub(crate) c: Motion,
}

impl Node {
    /// The node of a hinge at `at` with the parent's mode shapes there.
    pub(crate) fn new(at: Vec3, shape: &NodeShape) -> Self {
        let m = shape.phi.len();
        let mut rotations = Vec::new();
        let largest = shape.psi.iter().map(|p| p.norm()).fold(0.0, f64::max);
        if largest > 0.0 {
            let k = shape
                .psi
                .iter()
                .position(|p| p.norm() == largest)
                .expect("a largest column");
            let e = shape.psi[k] / largest;
            let parallel = shape
                .psi
                .iter()
                .all(|p| (p - e * p.dot(&e)).norm() <= 1e-14 * largest);
            if parallel {
                rotations.push(RotationStage {
                    axis: e,
                    coef: shape.psi.iter().map(|p| p.dot(&e)).collect(),
                });
            } else {
                for axis in [Vec3::x(), Vec3::y(), Vec3::z()] {
                    rotations.push(RotationStage {
                        axis,
                        coef: shape.psi.iter().map(|p| p.dot(&axis)).collect(),
                    });
                }
            }
        }
        debug_assert!(rotations.iter().all(|r| r.coef.len() == m));
        Self {
            at,
            phi: shape.phi.clone(),
            rotations,
        }
    }

    /// The node frame at `eta`, `etad` with the parent moving at `vp` (parent coordinates);
    /// writes the node's motion subspace `G` (node coordinates, one column per mode) into
    /// `g`.
    pub(crate) fn state(
        &self,
        eta: &[f64],
        etad: &[f64],
        vp: &Motion,
        g: &mut [Motion],
    ) -> NodeState {
        let mut disp = self.at;
        let mut rate = Vec3::zeros();
        for (k, p) in self.phi.iter().enumerate() {
            disp += p * eta[k];
            rate += p * etad[k];
            // Written field by field: a `Motion` built on the stack and copied was read
            // back across its stores' halves (a stalled store forwarding, `perf`).
            g[k].ang = Vec3::new(0.0, 0.0, 0.0);
            g[k].lin = *p;
        }
        let mut x = Transform::new(Mat3::identity(), disp);
        let vj = Motion::new(Vec3::zeros(), rate);
        let mut w = x.apply_motion(vp) + vj;
        let mut c = w.cross_motion(&vj);
        for r in &self.rotations {
            let (mut angle, mut speed) = (0.0, 0.0);
            for (k, &s) in r.coef.iter().enumerate() {
                angle += s * eta[k];
                speed += s * etad[k];
            }
            let xr = Transform::new(rotation_about(&r.axis, angle).transpose(), Vec3::zeros());
            let vj = Motion::new(r.axis * speed, Vec3::zeros());
            w = xr.apply_motion(&w) + vj;
            c = xr.apply_motion(&c) + w.cross_motion(&vj);
            for (k, gk) in g.iter_mut().enumerate() {
                *gk = xr.apply_motion(gk) + Motion::new(r.axis * r.coef[k], Vec3::zeros());
            }
            x = xr.compose(&x);
        }
        NodeState { x, w, c }
    }
}
