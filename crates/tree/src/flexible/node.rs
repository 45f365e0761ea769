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
use crate::axis::CoordAxis;
use crate::spatial::{Mat3, Motion, Transform, Vec3, rotation_about};

/// One rotation stage: about the unit `axis` by `Σₖ coef[k] ηₖ`.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RotationStage {
    pub(crate) axis: Vec3,
    pub(crate) coef: Vec<f64>,
}

impl RotationStage {
    /// The stage's angle `Σₖ coef[k] ηₖ` ([`Self::turn`]'s, the same sum).
    #[inline(always)]
    fn angle(&self, eta: &[f64]) -> f64 {
        let mut angle = 0.0;
        for (k, &s) in self.coef.iter().enumerate() {
            angle += s * eta[k];
        }
        angle
    }

    /// The stage's angle `Σₖ coef[k] ηₖ` and its rate `Σₖ coef[k] η̇ₖ`.
    #[inline(always)]
    fn turn(&self, eta: &[f64], etad: &[f64]) -> (f64, f64) {
        let m = eta.len();
        let (coef, etad) = (&self.coef[..m], &etad[..m]);
        let (mut angle, mut speed) = (0.0, 0.0);
        for k in 0..m {
            angle += coef[k] * eta[k];
            speed += coef[k] * etad[k];
        }
        (angle, speed)
    }
}

/// The foreshortening of a stiffened beam at a node: the node is drawn towards the root by
/// `½ ηᵀ C η` along the beam's `axis` ([`super::Beam::foreshortening`]).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Shortening {
    pub(crate) axis: Vec3,
    /// `C`, `m × m`, row-major.
    pub(crate) c: Vec<f64>,
}

/// A child hinge's node on its flexible parent (parent body frame).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Node {
    /// The hinge point `at` (m).
    pub(crate) at: Vec3,
    /// `Φₖ` per parent mode.
    pub(crate) phi: Vec<Vec3>,
    /// On a stiffened beam, the foreshortening that moves the node along the beam's axis
    /// (second order in `η`): the translation stage then has the subspace
    /// `[0; Φₖ − a (C η)ₖ]` and the velocity product `[0; −a η̇ᵀ C η̇]`. Through it the loads
    /// the node carries along the beam stiffen (or soften) its bending.
    pub(crate) shortening: Option<Shortening>,
    /// The rotation stages (none when `Ψ = 0`).
    pub(crate) rotations: Vec<RotationStage>,
    /// The coordinate axis of a single rotation stage about `±x`, `±y` or `±z` (a beam
    /// bending about a body axis): its rotation then made and applied by the fast path of
    /// [`CoordAxis`], row and column `k` exactly `e_k`.
    pub(crate) coord: Option<CoordAxis>,
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
        let coord = match rotations.as_slice() {
            [r] => CoordAxis::of(&r.axis, &Mat3::identity()),
            _ => None,
        };
        Self {
            at,
            phi: shape.phi.clone(),
            shortening: None,
            rotations,
            coord,
        }
    }

    /// The node frame at `eta` alone: [`Node::state`]'s `x`, the same sums, for a caller
    /// that reads no motion (a view's poses).
    pub(crate) fn pose(&self, eta: &[f64]) -> Transform {
        let mut disp = self.at;
        for (k, p) in self.phi.iter().enumerate() {
            disp += p * eta[k];
        }
        if let Some(s) = &self.shortening {
            let m = self.phi.len();
            let mut along = 0.0;
            for (k, row) in s.c.chunks_exact(m).enumerate() {
                let mut ce = 0.0;
                for l in 0..m {
                    ce += row[l] * eta[l];
                }
                along += eta[k] * ce;
            }
            disp -= s.axis * (0.5 * along);
        }
        if let (Some(ca), [r]) = (&self.coord, self.rotations.as_slice()) {
            let zero = Vec3::zeros();
            let xr = ca.transform(r.angle(eta), &zero, &zero);
            return Transform::new(xr.rot, disp);
        }
        let mut x = Transform::new(Mat3::identity(), disp);
        for r in &self.rotations {
            let xr = Transform::new(
                rotation_about(&r.axis, r.angle(eta)).transpose(),
                Vec3::zeros(),
            );
            x = xr.compose(&x);
        }
        x
    }

    /// The node frame at `eta`, `etad` with the parent moving at `vp` (parent coordinates);
    /// writes the node's motion subspace `G` (node coordinates, one column per mode) into
    /// `g`.
    ///
    /// Always inlined: the first pass calls it in instances for the common mode counts
    /// (`m = eta.len()` known there), so that its loops unroll (the same sums).
    #[inline(always)]
    pub(crate) fn state(
        &self,
        eta: &[f64],
        etad: &[f64],
        vp: &Motion,
        g: &mut [Motion],
    ) -> NodeState {
        let m = eta.len();
        let (phi, etad, g) = (&self.phi[..m], &etad[..m], &mut g[..m]);
        let mut disp = self.at;
        let mut rate = Vec3::zeros();
        for k in 0..m {
            let p = &phi[k];
            disp += p * eta[k];
            rate += p * etad[k];
            // Written field by field: a `Motion` built on the stack and copied was read
            // back across its stores' halves (a stalled store forwarding, `perf`).
            g[k].ang = Vec3::new(0.0, 0.0, 0.0);
            g[k].lin = *p;
        }
        // The foreshortening `−½ a ηᵀCη`: its rate `−a ηᵀCη̇`, its subspace columns
        // `−a (Cη)ₖ`, and `Ṡ η̇ = −a η̇ᵀCη̇` (C symmetric).
        let mut shortened = Vec3::zeros();
        if let Some(s) = &self.shortening {
            let c = &s.c[..m * m];
            let (mut along, mut along_rate, mut product) = (0.0, 0.0, 0.0);
            for k in 0..m {
                let row = &c[k * m..][..m];
                let (mut ce, mut ced) = (0.0, 0.0);
                for l in 0..m {
                    ce += row[l] * eta[l];
                    ced += row[l] * etad[l];
                }
                along += eta[k] * ce;
                along_rate += eta[k] * ced;
                product += etad[k] * ced;
                g[k].lin -= s.axis * ce;
            }
            disp -= s.axis * (0.5 * along);
            rate -= s.axis * along_rate;
            shortened = -s.axis * product;
        }
        let mut x = Transform::new(Mat3::identity(), disp);
        let vj = Motion::new(Vec3::zeros(), rate);
        let mut w = x.apply_motion(vp) + vj;
        let mut c = w.cross_motion(&vj);
        c.lin += shortened;
        if let (Some(ca), [r]) = (&self.coord, self.rotations.as_slice()) {
            // One rotation about a coordinate axis: the rigid hinges' fast path, and the
            // node frame `(E, disp)` made at once (the translation stage has `E = 1`).
            let (angle, speed) = r.turn(eta, etad);
            let zero = Vec3::zeros();
            let xr = ca.transform(angle, &zero, &zero);
            let vj = Motion::new(r.axis * speed, zero);
            w = ca.apply_motion(&xr, &w) + vj;
            c = ca.apply_motion(&xr, &c) + w.cross_motion(&vj);
            for (k, gk) in g.iter_mut().enumerate() {
                *gk = ca.apply_motion(&xr, gk) + Motion::new(r.axis * r.coef[k], zero);
            }
            return NodeState {
                x: Transform::new(xr.rot, disp),
                w,
                c,
            };
        }
        for r in &self.rotations {
            let (angle, speed) = r.turn(eta, etad);
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

#[cfg(test)]
mod tests {
    //! A node turning about a coordinate axis takes the hinges' fast path: its rotation in
    //! [`Node::state`], and, where the child's hinge turns about the same axis, the child's
    //! `Xup` in the first pass and the ABA. Both against the general path (the same model
    //! with the fast paths taken away), to round-off.
    use super::super::{Beam, FlexData, FlexModel, Flexible, Modes, aba, crba, rnea};
    use crate::samples::SplitMix;
    use crate::spatial::{Force, Mat3, Vec3};
    use crate::{BaseKind, Body, Hinge, ModelBuilder};

    /// A bus with a panel on a hinge about x whose beam (along y, bending along z) turns its
    /// tip about x; at the tip a second panel on a hinge about x (both fast paths) and a third
    /// on a hinge about z (the node's only), with the signs of the axes flipped by `sign`.
    fn model(sign: f64) -> FlexModel {
        let builder = ModelBuilder::new(BaseKind::Free)
            .body(Body::new(
                "bus",
                20.0,
                Mat3::from_diagonal(&Vec3::new(3.0, 2.0, 3.5)),
            ))
            .body(Body::new(
                "panel1",
                1.0,
                Mat3::from_diagonal(&Vec3::new(0.3, 0.02, 0.31)),
            ))
            .body(Body::new(
                "panel2",
                2.0,
                Mat3::from_diagonal(&Vec3::new(0.6, 0.05, 0.62)),
            ))
            .body(Body::new(
                "panel3",
                1.5,
                Mat3::from_diagonal(&Vec3::new(0.4, 0.13, 0.5)),
            ))
            .hinge(
                Hinge::revolute("h1", "bus", "panel1", Vec3::x() * sign)
                    .at(Vec3::new(0.0, 0.5, 0.0)),
            )
            .hinge(
                Hinge::revolute("h2", "panel1", "panel2", Vec3::x() * sign)
                    .at(Vec3::new(0.0, 2.0, 0.0))
                    .child_at(Vec3::new(0.0, -0.5, 0.1)),
            )
            .hinge(
                Hinge::revolute("h3", "panel1", "panel3", Vec3::z())
                    .at(Vec3::new(0.0, 2.0, 0.0))
                    .child_at(Vec3::new(0.2, -0.4, 0.0)),
            );
        let beam = Beam {
            root: Vec3::zeros(),
            axis: Vec3::y(),
            bend: Vec3::z() * sign,
            length: 2.0,
            ei: 500.0,
            rho_a: 5.0,
            modes: 3,
        };
        let flex = [Flexible {
            body: "panel1".into(),
            modes: Modes::Beam(beam),
            damping: 0.01,
            stiffening: true,
        }];
        FlexModel::build(builder, &flex).unwrap()
    }

    fn close_to(a: &[f64], b: &[f64], tol: f64, what: &str) {
        let scale = b.iter().fold(1.0_f64, |m, x| m.max(x.abs()));
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() <= tol * scale, "{what}: {a:?} vs {b:?}");
        }
    }

    fn close(a: &[f64], b: &[f64], what: &str) {
        close_to(a, b, 1e-13, what);
    }

    #[test]
    fn coordinate_axis_nodes_are_the_general_path() {
        for sign in [1.0, -1.0] {
            let fast = model(sign);
            assert!(
                fast.nodes[2].as_ref().unwrap().coord.is_some(),
                "node fast path"
            );
            assert!(
                fast.node_axis[2].is_some(),
                "the x hinge on the node: fast path"
            );
            assert!(
                fast.node_axis[3].is_none(),
                "the z hinge on the node: general"
            );
            let mut general = fast.clone();
            general.node_axis.iter_mut().for_each(|a| *a = None);
            for node in general.nodes.iter_mut().flatten() {
                node.coord = None;
            }
            let mut rng = SplitMix(7);
            let (mut df, mut dg) = (FlexData::new(&fast), FlexData::new(&general));
            for _ in 0..10 {
                let mut q = fast.neutral();
                let nq = fast.rigid().nq();
                for x in &mut q[7..nq] {
                    *x = rng.range(-3.0, 3.0);
                }
                for x in &mut q[nq..] {
                    *x = rng.range(-0.05, 0.05);
                }
                let v: Vec<f64> = (0..fast.nv()).map(|_| rng.range(-2.0, 2.0)).collect();
                let a: Vec<f64> = (0..fast.nv()).map(|_| rng.range(-2.0, 2.0)).collect();
                let f: Vec<Force> = (0..4)
                    .map(|_| Force::new(rng.vec3(1.0), rng.vec3(1.0)))
                    .collect();
                let tf = rnea(&fast, &mut df, &q, &v, &a, Some(&f)).unwrap().clone();
                let tg = rnea(&general, &mut dg, &q, &v, &a, Some(&f))
                    .unwrap()
                    .clone();
                close(tf.as_slice(), tg.as_slice(), "rnea");
                for i in 1..4 {
                    let (xf, xg) = (df.xup[i], dg.xup[i]);
                    close(xf.rot.as_slice(), xg.rot.as_slice(), "Xup rotation");
                    close(xf.trans.as_slice(), xg.trans.as_slice(), "Xup translation");
                    close(&df.v[i].to_array(), &dg.v[i].to_array(), "velocity");
                    close(
                        &df.c[i].to_array(),
                        &dg.c[i].to_array(),
                        "bias acceleration",
                    );
                }
                close(
                    df.g[..3]
                        .iter()
                        .flat_map(|g| g.to_array())
                        .collect::<Vec<_>>()
                        .as_slice(),
                    dg.g[..3]
                        .iter()
                        .flat_map(|g| g.to_array())
                        .collect::<Vec<_>>()
                        .as_slice(),
                    "G",
                );
                let mf = crba(&fast, &mut df, &q).unwrap().clone();
                let mg = crba(&general, &mut dg, &q).unwrap().clone();
                close(mf.as_slice(), mg.as_slice(), "crba");
                let af = aba(&fast, &mut df, &q, &v, tf.as_slice(), Some(&f))
                    .unwrap()
                    .clone();
                let ag = aba(&general, &mut dg, &q, &v, tf.as_slice(), Some(&f))
                    .unwrap()
                    .clone();
                close(af.as_slice(), ag.as_slice(), "aba");
                // The solve's forward error: round-off times the mass matrix's condition.
                close_to(af.as_slice(), &a, 1e-11, "aba inverts rnea");
            }
        }
    }
}
