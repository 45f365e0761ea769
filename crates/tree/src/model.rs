//! The immutable [`Model`]: topology and parameters of a tree of rigid bodies joined by
//! revolute hinges, built and validated by [`ModelBuilder`].
//!
//! Frames and kinematics (the model file's contract): with `R_p`, `r_p` the parent frame's
//! attitude and origin, a hinge at angle `φ` places its child at
//! `R_c = R_p · Rot(axis, φ) · rotation`, hinge point `h = r_p + R_p · at`,
//! child origin `r_c = h − R_c · child_at`. The axis is given in the parent's frame.
//!
//! Coordinates: `q = [attitude w x y z, position x y z, hinge angles…]` for a free base
//! (`nq = 7 + n`), `q = [hinge angles…]` for a fixed one; `v = [ω (3), v (3), hinge rates…]`
//! (root-body axes, root frame origin) or `[hinge rates…]`. Hinges follow the order in
//! which they were added (the model file's order), whatever the tree's shape.

use crate::axis::CoordAxis;
use crate::error::ModelError;
use crate::facet::Facet;
pub use crate::shape::BoxShape;
pub use crate::spatial::UNIT_NORM_TOLERANCE;
use crate::spatial::{
    ArticulatedInertia, Mat3, Motion, RigidInertia, Transform, Vec3, rotation_about,
};
use nalgebra::{Quaternion, SymmetricEigen, UnitQuaternion};
use std::collections::HashMap;

/// How the root body is attached to the inertial frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BaseKind {
    /// A 6-DOF floating root (a spacecraft).
    #[default]
    Free,
    /// The root is fixed in the inertial frame (a robot arm on a table).
    Fixed,
}

/// A rigid body as given to the builder.
///
/// ```
/// use satsim_tree::{Body, spatial::{Mat3, Vec3}};
/// let bus = Body::new("bus", 500.0, Mat3::from_diagonal(&Vec3::new(40.0, 40.0, 30.0)))
///     .with_com(Vec3::new(0.0, 0.0, 0.1));
/// assert_eq!(bus.name, "bus");
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    /// Unique name.
    pub name: String,
    /// Mass (kg), `>= 0`.
    pub mass: f64,
    /// Centre of mass in the body frame (m).
    pub com: Vec3,
    /// Inertia tensor about the centre of mass, body axes (kg m²).
    pub inertia: Mat3,
    /// How to draw the body (the model file's optional `shape`); no algorithm reads it.
    pub shape: Option<BoxShape>,
    /// The body's surface facets (body frame), for the surface-force models (solar
    /// radiation pressure, drag); default none. No algorithm of the tree reads them.
    pub facets: Vec<Facet>,
}

impl Body {
    /// A body with its centre of mass at the frame origin.
    pub fn new(name: impl Into<String>, mass: f64, inertia: Mat3) -> Self {
        Self {
            name: name.into(),
            mass,
            com: Vec3::zeros(),
            inertia,
            shape: None,
            facets: Vec::new(),
        }
    }
    /// A massless, inertia-free link (to build multi-axis hinges from 1-DOF hinges).
    pub fn massless(name: impl Into<String>) -> Self {
        Self::new(name, 0.0, Mat3::zeros())
    }
    /// Sets the centre of mass (body frame, m).
    pub fn with_com(mut self, com: Vec3) -> Self {
        self.com = com;
        self
    }
    /// Sets the box drawn for the body (drawing only).
    pub fn with_shape(mut self, shape: BoxShape) -> Self {
        self.shape = Some(shape);
        self
    }
    /// Sets the body's surface facets (body frame), replacing any given before.
    pub fn with_facets(mut self, facets: impl IntoIterator<Item = Facet>) -> Self {
        self.facets = facets.into_iter().collect();
        self
    }
}

/// A revolute hinge as given to the builder.
///
/// ```
/// use satsim_tree::{Hinge, spatial::Vec3};
/// let h = Hinge::revolute("yaw", "bus", "panel", Vec3::z()).at(Vec3::new(0.75, 0.0, 0.0));
/// assert_eq!(h.parent, "bus");
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Hinge {
    /// Unique name.
    pub name: String,
    /// Parent body's name.
    pub parent: String,
    /// Child body's name.
    pub child: String,
    /// Rotation axis in the parent frame (normalised by the builder if within 1e-6 of unit).
    pub axis: Vec3,
    /// Hinge point in the parent frame (m).
    pub at: Vec3,
    /// Hinge point in the child frame (m).
    pub child_at: Vec3,
    /// Child frame relative to the parent frame at zero angle (maps child to parent
    /// coordinates); a Hamilton quaternion, normalised by the builder if within 1e-6 of unit.
    pub rotation: Quaternion<f64>,
    /// Armature (kg m²): a rotor inertia about the hinge axis, added to the mass matrix's
    /// diagonal (as a motor's reflected inertia is). Zero by default; a small value is the
    /// documented regularisation of a gimbal lock of massless links.
    pub armature: f64,
}

impl Hinge {
    /// A revolute hinge with coincident frames at zero angle.
    pub fn revolute(
        name: impl Into<String>,
        parent: impl Into<String>,
        child: impl Into<String>,
        axis: Vec3,
    ) -> Self {
        Self {
            name: name.into(),
            parent: parent.into(),
            child: child.into(),
            axis,
            at: Vec3::zeros(),
            child_at: Vec3::zeros(),
            rotation: Quaternion::identity(),
            armature: 0.0,
        }
    }
    /// Sets the hinge point in the parent frame.
    pub fn at(mut self, at: Vec3) -> Self {
        self.at = at;
        self
    }
    /// Sets the hinge point in the child frame.
    pub fn child_at(mut self, child_at: Vec3) -> Self {
        self.child_at = child_at;
        self
    }
    /// Sets the fixed rotation (child to parent at zero angle).
    pub fn rotation(mut self, rotation: Quaternion<f64>) -> Self {
        self.rotation = rotation;
        self
    }
    /// Sets the armature (kg m², `>= 0`).
    pub fn armature(mut self, armature: f64) -> Self {
        self.armature = armature;
        self
    }
}

/// Collects bodies and hinges, then validates them into a [`Model`].
///
/// ```
/// use satsim_tree::{BaseKind, Body, Hinge, ModelBuilder, spatial::{Mat3, Vec3}};
/// let model = ModelBuilder::new(BaseKind::Free)
///     .body(Body::new("bus", 500.0, Mat3::identity() * 40.0))
///     .body(Body::new("panel", 20.0, Mat3::identity() * 2.0))
///     .hinge(Hinge::revolute("h", "bus", "panel", Vec3::z()).at(Vec3::x()))
///     .build()?;
/// assert_eq!((model.nq(), model.nv()), (8, 7));
/// # Ok::<(), satsim_tree::ModelError>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct ModelBuilder {
    base: BaseKind,
    pub(crate) bodies: Vec<Body>,
    hinges: Vec<Hinge>,
}

impl ModelBuilder {
    /// An empty builder with the given base.
    pub fn new(base: BaseKind) -> Self {
        Self {
            base,
            ..Self::default()
        }
    }
    /// Adds a body; the first body added is the root.
    pub fn body(mut self, body: Body) -> Self {
        self.bodies.push(body);
        self
    }
    /// Adds a hinge; hinges' coordinates follow the order in which they are added.
    pub fn hinge(mut self, hinge: Hinge) -> Self {
        self.hinges.push(hinge);
        self
    }
    /// Adds a body in place.
    pub fn push_body(&mut self, body: Body) -> &mut Self {
        self.bodies.push(body);
        self
    }
    /// Adds a hinge in place.
    pub fn push_hinge(&mut self, hinge: Hinge) -> &mut Self {
        self.hinges.push(hinge);
        self
    }
    /// The hinges added so far, in order of addition, to adjust before [`ModelBuilder::build`]
    /// (e.g. a scene's `armature`).
    pub fn hinges_mut(&mut self) -> &mut [Hinge] {
        &mut self.hinges
    }
    /// The bodies added so far (the first is the root), to adjust before
    /// [`ModelBuilder::build`].
    pub fn bodies_mut(&mut self) -> &mut [Body] {
        &mut self.bodies
    }

    /// Validates and builds the model.
    pub fn build(&self) -> Result<Model, ModelError> {
        if self.bodies.is_empty() {
            return Err(ModelError::NoBodies);
        }
        let mut index: HashMap<&str, usize> = HashMap::new();
        for (i, b) in self.bodies.iter().enumerate() {
            if index.insert(b.name.as_str(), i).is_some() {
                return Err(ModelError::DuplicateBody(b.name.clone()));
            }
            check_body(b)?;
        }
        // Facets with unit normals, per body in the order given.
        let facets = self
            .bodies
            .iter()
            .map(|b| {
                b.facets
                    .iter()
                    .enumerate()
                    .map(|(k, f)| f.checked(&b.name, k))
                    .collect::<Result<Vec<Facet>, ModelError>>()
            })
            .collect::<Result<Vec<_>, ModelError>>()?;
        let mut hinge_names: HashMap<&str, ()> = HashMap::new();
        // parent_hinge[b] = index of the hinge whose child is body b (file order)
        let mut parent_hinge: Vec<Option<usize>> = vec![None; self.bodies.len()];
        let mut units = Vec::with_capacity(self.hinges.len());
        for (k, h) in self.hinges.iter().enumerate() {
            if hinge_names.insert(h.name.as_str(), ()).is_some() {
                return Err(ModelError::DuplicateHinge(h.name.clone()));
            }
            let p = *index
                .get(h.parent.as_str())
                .ok_or_else(|| ModelError::UnknownBody {
                    hinge: h.name.clone(),
                    role: "parent",
                    body: h.parent.clone(),
                })?;
            let c = *index
                .get(h.child.as_str())
                .ok_or_else(|| ModelError::UnknownBody {
                    hinge: h.name.clone(),
                    role: "child",
                    body: h.child.clone(),
                })?;
            if p == c {
                return Err(ModelError::SelfLoop(h.name.clone()));
            }
            if c == 0 {
                return Err(ModelError::RootIsChild {
                    hinge: h.name.clone(),
                    body: h.child.clone(),
                });
            }
            if let Some(first) = parent_hinge[c] {
                return Err(ModelError::TwoParents {
                    body: h.child.clone(),
                    first: self.hinges[first].name.clone(),
                    second: h.name.clone(),
                });
            }
            parent_hinge[c] = Some(k);
            units.push(check_hinge(h)?);
        }
        for (b, ph) in parent_hinge.iter().enumerate().skip(1) {
            if ph.is_none() {
                return Err(ModelError::NoParent(self.bodies[b].name.clone()));
            }
        }
        // Every non-root body has exactly one parent; a body unreachable from the root lies
        // on a cycle. Order bodies depth-first from the root so that λ(i) < i.
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); self.bodies.len()];
        for (k, h) in self.hinges.iter().enumerate() {
            let _ = k;
            children[index[h.parent.as_str()]].push(index[h.child.as_str()]);
        }
        let mut order = Vec::with_capacity(self.bodies.len());
        let mut stack = vec![0usize];
        while let Some(b) = stack.pop() {
            order.push(b);
            for &c in children[b].iter().rev() {
                stack.push(c);
            }
        }
        if order.len() < self.bodies.len() {
            let mut seen = vec![false; self.bodies.len()];
            for &b in &order {
                seen[b] = true;
            }
            let cycle = (0..self.bodies.len())
                .filter(|&b| !seen[b])
                .map(|b| self.bodies[b].name.clone())
                .collect();
            return Err(ModelError::Cycle(cycle));
        }
        for (b, kids) in children.iter().enumerate() {
            let body = &self.bodies[b];
            // Entry by entry: the norm of a tiny inertia (1e-200 on the diagonal) underflows.
            if kids.is_empty()
                && body.mass == 0.0
                && body.inertia.iter().all(|x| *x == 0.0)
                && b != 0
            {
                return Err(ModelError::MasslessLeaf(body.name.clone()));
            }
        }
        let mut position = vec![0usize; self.bodies.len()];
        for (i, &b) in order.iter().enumerate() {
            position[b] = i;
        }
        let base_nv = match self.base {
            BaseKind::Free => 6,
            BaseKind::Fixed => 0,
        };
        let bodies: Vec<BodyInfo> = order
            .iter()
            .map(|&b| {
                let body = &self.bodies[b];
                BodyInfo {
                    name: body.name.clone(),
                    mass: body.mass,
                    com: body.com,
                    inertia_com: body.inertia,
                    inertia: RigidInertia::from_com(body.mass, body.com, body.inertia),
                    shape: body.shape,
                    facets: facets[b].clone(),
                }
            })
            .collect();
        let mut parent = vec![None; bodies.len()];
        let mut joints = vec![None; bodies.len()];
        let mut hinge_body = vec![0usize; self.hinges.len()];
        for (i, &b) in order.iter().enumerate().skip(1) {
            let k = parent_hinge[b].expect("checked above");
            let h = &self.hinges[k];
            let (axis, rot0) = units[k];
            parent[i] = Some(position[index[h.parent.as_str()]]);
            hinge_body[k] = i;
            // Motion subspace in child coordinates: the axis is invariant under its own
            // rotation, so S = [rot0ᵀ axis; child_at × rot0ᵀ axis] is constant.
            let s = rot0.tr_mul(&axis);
            joints[i] = Some(Joint {
                hinge: k,
                dof: base_nv + k,
                axis,
                at: h.at,
                child_at: h.child_at,
                rot0,
                rotation: h.rotation,
                s: Motion::new(s, h.child_at.cross(&s)),
                armature: h.armature,
            });
        }
        let mut model = Model {
            base: self.base,
            bodies,
            parent,
            joints,
            hinge_names: self.hinges.iter().map(|h| h.name.clone()).collect(),
            hinge_body,
            base_nv,
            gyrostats: Vec::new(),
            is_gyrostat: Vec::new(),
            carrier_inertia: Vec::new(),
            carrier_ia: Vec::new(),
            rigid_ia: Vec::new(),
            coord_axis: Vec::new(),
            chains: Vec::new(),
            chain_part: Vec::new(),
        };
        model.coord_axis = model
            .joints
            .iter()
            .map(|j| j.as_ref().and_then(|j| CoordAxis::of(&j.axis, &j.rot0)))
            .collect();
        model.rigid_ia = model.bodies.iter().map(|b| b.inertia.into()).collect();
        model.find_gyrostats();
        model.find_chains();
        Ok(model)
    }
}

/// Relative tolerance of the tests that make a leaf body a [`Gyrostat`]: its inertia must be
/// axisymmetric about the hinge axis and its centre of mass on that axis to within this
/// fraction of the body's scale (i.e. to round-off).
pub const GYROSTAT_TOLERANCE: f64 = 1e-14;

/// A balanced axisymmetric rotor: a leaf body on a hinge without armature whose centre of
/// mass lies on the hinge axis and whose inertia about it is `J a aᵀ + Iₜ (1 − a aᵀ)`.
///
/// Its inertia seen from the parent does not depend on the rotor angle, so the
/// articulated-body algorithm ([`crate::aba::aba`]) folds it into its parent as a gyrostat: the
/// rotor, locked, is part of the parent's rigid inertia, and its spin adds the momentum
/// `J Ω a` and the axial coupling. Exact for such rotors (same result as the rotor as a tree
/// body, to round-off); the other algorithms keep the rotor as a body.
#[derive(Clone, Debug, PartialEq)]
pub struct Gyrostat {
    /// The rotor body.
    pub(crate) body: usize,
    /// Its parent (the carrier).
    pub(crate) parent: usize,
    /// Unit spin axis, parent coordinates.
    pub(crate) axis: Vec3,
    /// Moment of inertia about the spin axis, `J` (kg m², > 0).
    pub(crate) axial: f64,
}

impl Gyrostat {
    /// The rotor body.
    pub fn body(&self) -> usize {
        self.body
    }
    /// Its parent (the carrier).
    pub fn parent(&self) -> usize {
        self.parent
    }
    /// Unit spin axis, parent coordinates.
    pub fn axis(&self) -> &Vec3 {
        &self.axis
    }
    /// Moment of inertia about the spin axis, `J` (kg m², > 0).
    pub fn axial(&self) -> f64 {
        self.axial
    }
}

/// A chain of `k = 2` or `3` hinges through massless, inertia-less links of zero length (each
/// link's two hinge points coincide, so every axis passes through one point), ending at a body
/// with mass or inertia, the *tip* (e.g. the preprint's 3-DOF gimbal: hinges `h1`, `h2`, `h3`
/// through `link1`, `link2` to `panel1`). Each link has exactly one child (rotors count);
/// links carry no rotors and the tip is no gyrostat rotor.
///
/// [`crate::aba::aba`] processes such a chain as one multi-axis joint at its tip (a `6 x k`
/// motion subspace and a `k x k` pivot block), not as `k` bodies: same accelerations to
/// round-off, and the same singular-hinge errors. The other algorithms keep the links as
/// bodies; [`Model::without_chains`] gives the plain form.
///
/// ```
/// use satsim_tree::{BaseKind, Body, Hinge, ModelBuilder, spatial::{Mat3, Vec3}};
/// let model = ModelBuilder::new(BaseKind::Free)
///     .body(Body::new("bus", 500.0, Mat3::identity() * 40.0))
///     .body(Body::massless("link"))
///     .body(Body::new("panel", 20.0, Mat3::identity() * 2.0))
///     .hinge(Hinge::revolute("h1", "bus", "link", Vec3::z()).at(Vec3::y()))
///     .hinge(Hinge::revolute("h2", "link", "panel", Vec3::x()).child_at(-Vec3::y()))
///     .build()?;
/// let chain = &model.chains()[0];
/// assert_eq!((chain.tip(), chain.links(), chain.hinges()), (2, &[1][..], 2));
/// # Ok::<(), satsim_tree::ModelError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Chain {
    /// The bodies in ABA's elimination order: the tip, its link, ..., the outermost link
    /// last (the first `k` entries count).
    pub(crate) order: [usize; 3],
    /// Number of hinges `k` (2 or 3).
    pub(crate) k: usize,
    /// The outermost link's parent.
    pub(crate) parent: usize,
    /// `k = 3` without armature: a spherical joint, which passes on only a linear inertia.
    pub(crate) spherical: bool,
    /// Whether some link's origin lies off the hinge point (its singular-pivot scale then
    /// needs the off-point terms).
    pub(crate) offset_links: bool,
    /// Per hinge (elimination order): its unit axis in its child's coordinates (`s.ang`).
    pub(crate) axis: [Vec3; 3],
    /// Per hinge: its armature.
    pub(crate) armature: [f64; 3],
    /// Per hinge: its coordinate's index in `v`.
    pub(crate) dof: [usize; 3],
    /// Per link (entry 0 unused): the hinge point in the link's frame (its `child_at`).
    pub(crate) link_at: [Vec3; 3],
    /// The hinge point in the tip's frame (its `child_at`).
    pub(crate) tip_at: Vec3,
    /// The hinge point in the parent's frame (the outermost link's `at`).
    pub(crate) point: Vec3,
}

impl Chain {
    /// The tip body (with mass or inertia).
    pub fn tip(&self) -> usize {
        self.order[0]
    }
    /// Number of hinges (2 or 3).
    pub fn hinges(&self) -> usize {
        self.k
    }
    /// The links, innermost (the tip's parent) first.
    pub fn links(&self) -> &[usize] {
        &self.order[1..self.k]
    }
    /// The outermost link's parent.
    pub fn parent(&self) -> usize {
        self.parent
    }
    /// The bodies in ABA's elimination order: the tip, its link, ..., the outermost link.
    pub fn order(&self) -> &[usize] {
        &self.order[..self.k]
    }
    /// Each hinge's coordinate index in `v`, in [`Chain::order`] (each body's own hinge).
    pub fn dofs(&self) -> &[usize] {
        &self.dof[..self.k]
    }
    /// Whether the chain is a spherical joint: three hinges, no armature (ABA passes on only
    /// a linear inertia through it).
    pub fn is_spherical(&self) -> bool {
        self.spherical
    }
    /// Whether some link's origin lies off the common hinge point.
    pub fn has_offset_links(&self) -> bool {
        self.offset_links
    }
    /// The common hinge point in the tip's frame (the tip's `child_at`).
    pub fn tip_at(&self) -> &Vec3 {
        &self.tip_at
    }
    /// The common hinge point in the parent's frame (the outermost link's `at`).
    pub fn point(&self) -> &Vec3 {
        &self.point
    }
}

/// A body's part in a [`Chain`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChainPart {
    /// Not in a chain (or the chain's parent).
    None,
    /// A massless link: ABA processes it at its chain's tip.
    Link,
    /// The tip of chain `Model::chains[_]`.
    Tip(usize),
}

fn finite3(v: &Vec3, what: impl FnOnce() -> String) -> Result<(), ModelError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(ModelError::NonFinite(what()))
    }
}

pub(crate) fn check_body(b: &Body) -> Result<(), ModelError> {
    if !b.mass.is_finite() {
        return Err(ModelError::NonFinite(format!("body `{}`: mass", b.name)));
    }
    if b.mass < 0.0 {
        return Err(ModelError::NegativeMass {
            body: b.name.clone(),
            mass: b.mass,
        });
    }
    finite3(&b.com, || format!("body `{}`: com", b.name))?;
    if !b.inertia.iter().all(|x| x.is_finite()) {
        return Err(ModelError::NonFinite(format!("body `{}`: inertia", b.name)));
    }
    if let Some(shape) = &b.shape {
        finite3(&shape.size, || format!("body `{}`: shape.box", b.name))?;
        if let Some(at) = &shape.at {
            finite3(at, || format!("body `{}`: shape.at", b.name))?;
        }
        if shape.size.iter().any(|&x| x <= 0.0) {
            return Err(ModelError::ShapeSize {
                body: b.name.clone(),
                size: [shape.size.x, shape.size.y, shape.size.z],
            });
        }
    }
    let i = &b.inertia;
    let scale = i.abs().max().max(f64::MIN_POSITIVE);
    if (i - i.transpose()).abs().max() > 1e-9 * scale {
        return Err(ModelError::InertiaNotSymmetric(b.name.clone()));
    }
    let mut p: Vec<f64> = SymmetricEigen::new(*i)
        .eigenvalues
        .iter()
        .copied()
        .collect();
    p.sort_by(f64::total_cmp);
    let tol = 1e-9 * scale;
    if p[0] < -tol {
        return Err(ModelError::InertiaNotPositive {
            body: b.name.clone(),
            moment: p[0],
        });
    }
    if p[2] > p[0] + p[1] + tol {
        return Err(ModelError::InertiaTriangle {
            body: b.name.clone(),
            moments: [p[0], p[1], p[2]],
        });
    }
    Ok(())
}

fn check_hinge(h: &Hinge) -> Result<(Vec3, Mat3), ModelError> {
    finite3(&h.axis, || format!("hinge `{}`: axis", h.name))?;
    finite3(&h.at, || format!("hinge `{}`: at", h.name))?;
    finite3(&h.child_at, || format!("hinge `{}`: child_at", h.name))?;
    if !h.armature.is_finite() {
        return Err(ModelError::NonFinite(format!(
            "hinge `{}`: armature",
            h.name
        )));
    }
    if h.armature < 0.0 {
        return Err(ModelError::NegativeArmature {
            hinge: h.name.clone(),
            armature: h.armature,
        });
    }
    if !h.rotation.coords.iter().all(|x| x.is_finite()) {
        return Err(ModelError::NonFinite(format!(
            "hinge `{}`: rotation",
            h.name
        )));
    }
    let norm = h.axis.norm();
    if (norm - 1.0).abs() > UNIT_NORM_TOLERANCE {
        return Err(ModelError::AxisNorm {
            hinge: h.name.clone(),
            norm,
        });
    }
    let qn = h.rotation.norm();
    if (qn - 1.0).abs() > UNIT_NORM_TOLERANCE {
        return Err(ModelError::RotationNorm {
            hinge: h.name.clone(),
            norm: qn,
        });
    }
    let rot0 = UnitQuaternion::from_quaternion(h.rotation)
        .to_rotation_matrix()
        .into_inner();
    Ok((h.axis / norm, rot0))
}

/// A body of a built model, with its inertia about its frame origin.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyInfo {
    /// Name.
    pub(crate) name: String,
    /// Mass (kg).
    pub(crate) mass: f64,
    /// Centre of mass, body frame (m).
    pub(crate) com: Vec3,
    /// Inertia about the centre of mass, body axes (kg m²).
    pub(crate) inertia_com: Mat3,
    /// Spatial inertia about the body frame's origin.
    pub(crate) inertia: RigidInertia,
    /// The box drawn for the body, if the model gave one (drawing only).
    pub(crate) shape: Option<BoxShape>,
    /// The body's surface facets (body frame, unit normals).
    pub(crate) facets: Vec<Facet>,
}

impl BodyInfo {
    /// Name.
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Mass (kg).
    pub fn mass(&self) -> f64 {
        self.mass
    }
    /// Centre of mass, body frame (m).
    pub fn com(&self) -> &Vec3 {
        &self.com
    }
    /// Inertia about the centre of mass, body axes (kg m²).
    pub fn inertia_com(&self) -> &Mat3 {
        &self.inertia_com
    }
    /// Spatial inertia about the body frame's origin.
    pub fn inertia(&self) -> &RigidInertia {
        &self.inertia
    }
    /// The box drawn for the body, if the model gave one (drawing only).
    pub fn shape(&self) -> Option<&BoxShape> {
        self.shape.as_ref()
    }
    /// The body's surface facets (body frame, unit normals), in the order given; no
    /// algorithm of the tree reads them.
    pub fn facets(&self) -> &[Facet] {
        &self.facets
    }
}

/// The revolute hinge that joins body `i` to its parent `λ(i)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// Index of the hinge in the order of addition (the model file's order).
    pub(crate) hinge: usize,
    /// Index of its coordinate in `v` (and of its angle in the hinge part of `q`).
    pub(crate) dof: usize,
    /// Unit axis, parent frame.
    pub(crate) axis: Vec3,
    /// Hinge point, parent frame.
    pub(crate) at: Vec3,
    /// Hinge point, child frame.
    pub(crate) child_at: Vec3,
    /// Child to parent rotation at zero angle.
    pub(crate) rot0: Mat3,
    /// The hinge's fixed rotation as the builder got it (kept so that
    /// [`Model::to_builder`] gives back exactly the same model).
    pub(crate) rotation: Quaternion<f64>,
    /// Motion subspace `S` (constant, child coordinates).
    pub(crate) s: Motion,
    /// Armature (kg m²) added to the hinge's diagonal entry of `M`.
    pub(crate) armature: f64,
}

impl Joint {
    /// Index of the hinge in the order of addition (the model file's order).
    pub fn hinge(&self) -> usize {
        self.hinge
    }
    /// Index of its coordinate in `v` (and of its angle in the hinge part of `q`).
    pub fn dof(&self) -> usize {
        self.dof
    }
    /// Unit axis, parent frame.
    pub fn axis(&self) -> &Vec3 {
        &self.axis
    }
    /// Hinge point, parent frame (m).
    pub fn at(&self) -> &Vec3 {
        &self.at
    }
    /// Hinge point, child frame (m).
    pub fn child_at(&self) -> &Vec3 {
        &self.child_at
    }
    /// Child to parent rotation at zero angle.
    pub fn rot0(&self) -> &Mat3 {
        &self.rot0
    }
    /// The hinge's fixed rotation, child to parent at zero angle, Hamilton `[w, x, y, z]`,
    /// exactly as given to the builder (`rot0` is its matrix).
    pub fn rotation(&self) -> &Quaternion<f64> {
        &self.rotation
    }
    /// Motion subspace `S` (constant, child coordinates).
    #[inline]
    pub fn s(&self) -> &Motion {
        &self.s
    }
    /// Armature (kg m²) added to the hinge's diagonal entry of `M`.
    pub fn armature(&self) -> f64 {
        self.armature
    }
    /// [`Joint::transform`] through `axis`, the hinge's coordinate-axis form where it has one
    /// (the same transform, with its zeros folded).
    #[inline]
    pub(crate) fn transform_with(&self, axis: Option<&CoordAxis>, phi: f64) -> Transform {
        match axis {
            Some(a) => a.transform(phi, &self.at, &self.child_at),
            None => self.transform(phi),
        }
    }

    /// `Xup`: the transform from the parent's coordinates to the child's at angle `phi`.
    #[inline]
    pub fn transform(&self, phi: f64) -> Transform {
        // Eᵀ = Rot(axis, φ) · rot0 maps child to parent coordinates. Most hinges have no
        // fixed rotation: then the product is skipped.
        let rot = rotation_about(&self.axis, phi);
        let et = if self.rot0 == Mat3::identity() {
            rot
        } else {
            rot * self.rot0
        };
        Transform::new(et.transpose(), self.at - et * self.child_at)
    }
}

/// The immutable model: bodies in depth-first order (`λ(i) < i`, body 0 the root), the
/// parent array `λ` and one revolute [`Joint`] per non-root body.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// Free or fixed root.
    pub(crate) base: BaseKind,
    /// Bodies, depth-first from the root.
    pub(crate) bodies: Vec<BodyInfo>,
    /// `λ(i)`: the parent of body `i` (`None` for the root).
    pub(crate) parent: Vec<Option<usize>>,
    /// The hinge joining body `i` to `λ(i)` (`None` for the root).
    pub(crate) joints: Vec<Option<Joint>>,
    /// Hinge names in the order of addition.
    pub(crate) hinge_names: Vec<String>,
    /// For hinge `k` (order of addition), the body it moves.
    pub(crate) hinge_body: Vec<usize>,
    base_nv: usize,
    /// Rotors that ABA treats as gyrostats of their parents (see [`Gyrostat`]).
    pub(crate) gyrostats: Vec<Gyrostat>,
    /// Per body: whether it is a [`Gyrostat`] rotor.
    pub(crate) is_gyrostat: Vec<bool>,
    /// Per body: its rigid inertia with its gyrostat rotors locked on (ABA's gyrostat form).
    pub(crate) carrier_inertia: Vec<RigidInertia>,
    /// Per body: the articulated inertia ABA starts from in the gyrostat form, the carrier
    /// inertia less `J a aᵀ` (angular block) for each rotor.
    pub(crate) carrier_ia: Vec<ArticulatedInertia>,
    /// Per body: its own rigid inertia as an articulated inertia, where ABA's plain form
    /// starts (the gyrostat form starts from `carrier_ia`).
    pub(crate) rigid_ia: Vec<ArticulatedInertia>,
    /// Per body: its hinge's coordinate axis where the hinge turns about one (the fast path
    /// of `axis.rs`), `None` for the root and for general hinges.
    pub(crate) coord_axis: Vec<Option<CoordAxis>>,
    /// Chains of hinges through massless zero-length links that ABA processes as one
    /// multi-axis joint (see [`Chain`]).
    pub(crate) chains: Vec<Chain>,
    /// Per body: its part in a [`Chain`], if any.
    pub(crate) chain_part: Vec<ChainPart>,
}

impl Model {
    /// Free or fixed root.
    pub fn base(&self) -> BaseKind {
        self.base
    }
    /// Bodies, depth-first from the root (`λ(i) < i`, body 0 the root).
    pub fn bodies(&self) -> &[BodyInfo] {
        &self.bodies
    }
    /// `λ`: the parent of each body (`None` for the root).
    pub fn parent(&self) -> &[Option<usize>] {
        &self.parent
    }
    /// The hinge joining body `body` to its parent (`None` for the root).
    pub fn joint(&self, body: usize) -> Option<&Joint> {
        self.joints.get(body).and_then(Option::as_ref)
    }
    /// Hinge names in the order of addition.
    pub fn hinge_names(&self) -> &[String] {
        &self.hinge_names
    }
    /// For hinge `k` (order of addition), the body it moves.
    pub fn hinge_body(&self) -> &[usize] {
        &self.hinge_body
    }
    /// Rotors that ABA treats as gyrostats of their parents (see [`Gyrostat`]).
    pub fn gyrostats(&self) -> &[Gyrostat] {
        &self.gyrostats
    }
    /// Number of bodies.
    pub fn n_bodies(&self) -> usize {
        self.bodies.len()
    }
    /// Number of hinges.
    pub fn n_hinges(&self) -> usize {
        self.hinge_names.len()
    }
    /// Number of velocity coordinates (degrees of freedom).
    pub fn nv(&self) -> usize {
        self.base_nv + self.n_hinges()
    }
    /// Velocity coordinate `index` of `v` in words, for messages: `the base's angular
    /// velocity x` (a free base's 0 to 2, root axes), `the base's velocity x` (3 to 5), or
    /// ``hinge `h1` ``.
    ///
    /// ```
    /// use satsim_tree::{samples::chain, BaseKind};
    /// let model = chain(2, BaseKind::Free);
    /// assert_eq!(model.coordinate(1), "the base's angular velocity y");
    /// assert_eq!(model.coordinate(6), format!("hinge `{}`", model.hinge_names()[0]));
    /// ```
    pub fn coordinate(&self, index: usize) -> String {
        const AXES: [&str; 3] = ["x", "y", "z"];
        match (self.base, index) {
            (BaseKind::Free, 0..3) => format!("the base's angular velocity {}", AXES[index]),
            (BaseKind::Free, 3..6) => format!("the base's velocity {}", AXES[index - 3]),
            _ => index
                .checked_sub(self.base_nv)
                .and_then(|k| self.hinge_names.get(k))
                .map_or_else(|| format!("coordinate {index}"), |h| format!("hinge `{h}`")),
        }
    }
    /// Number of position coordinates.
    pub fn nq(&self) -> usize {
        self.base_nq() + self.n_hinges()
    }
    /// Degrees of freedom of the base (6 or 0).
    pub fn base_nv(&self) -> usize {
        self.base_nv
    }
    /// Position coordinates of the base (7 or 0).
    pub fn base_nq(&self) -> usize {
        if self.base_nv == 6 { 7 } else { 0 }
    }
    /// Index of the body called `name`.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }
    /// Index (order of addition) of the hinge called `name`.
    pub fn hinge_index(&self, name: &str) -> Option<usize> {
        self.hinge_names.iter().position(|h| h == name)
    }
    /// Total mass (kg).
    pub fn total_mass(&self) -> f64 {
        self.bodies.iter().map(|b| b.mass).sum()
    }
    /// Children of body `i`.
    pub fn children(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        (i + 1..self.n_bodies()).filter(move |&j| self.parent[j] == Some(i))
    }
    /// A builder that rebuilds this model: a built model never changes, so a variant (another
    /// armature, a heavier body) is built anew. Bodies come in the model's depth-first order
    /// and hinges in their order of addition, so the rebuilt model numbers bodies, hinges and
    /// coordinates as this one does. A hinge's fixed `rotation` comes back exactly as it was
    /// given and its axis normalised, so an unchanged rebuild has the same joint frames.
    ///
    /// ```
    /// use satsim_tree::{BaseKind, Body, Hinge, ModelBuilder, spatial::{Mat3, Vec3}};
    /// let model = ModelBuilder::new(BaseKind::Free)
    ///     .body(Body::new("bus", 500.0, Mat3::identity() * 40.0))
    ///     .body(Body::new("panel", 20.0, Mat3::identity() * 2.0))
    ///     .hinge(Hinge::revolute("h", "bus", "panel", Vec3::z()).at(Vec3::x()))
    ///     .build()?;
    /// let mut builder = model.to_builder();
    /// builder.hinges_mut()[0].armature = 0.1;
    /// let stiffer = builder.build()?;
    /// assert_eq!(stiffer.joint(1).unwrap().armature(), 0.1);
    /// assert_eq!(model.joint(1).unwrap().armature(), 0.0);
    /// # Ok::<(), satsim_tree::ModelError>(())
    /// ```
    pub fn to_builder(&self) -> ModelBuilder {
        let mut builder = ModelBuilder::new(self.base);
        for b in &self.bodies {
            let mut body = Body::new(b.name.clone(), b.mass, b.inertia_com).with_com(b.com);
            body.shape = b.shape;
            body.facets = b.facets.clone();
            builder.push_body(body);
        }
        for (k, name) in self.hinge_names.iter().enumerate() {
            let i = self.hinge_body[k];
            let j = self.joints[i].as_ref().expect("non-root body has a joint");
            let p = self.parent[i].expect("non-root body has a parent");
            let rotation = j.rotation;
            builder.push_hinge(
                Hinge::revolute(
                    name.clone(),
                    self.bodies[p].name.clone(),
                    self.bodies[i].name.clone(),
                    j.axis,
                )
                .at(j.at)
                .child_at(j.child_at)
                .rotation(rotation)
                .armature(j.armature),
            );
        }
        builder
    }
    /// The neutral configuration: identity attitude, origin, zero angles.
    pub fn neutral(&self) -> Vec<f64> {
        let mut q = vec![0.0; self.nq()];
        if self.base_nv == 6 {
            q[0] = 1.0;
        }
        q
    }
    /// The same model with every rotor kept as a plain tree body in ABA (no gyrostat terms):
    /// the reference form against which the gyrostat form is checked.
    pub fn without_gyrostats(&self) -> Model {
        let mut m = self.clone();
        m.gyrostats.clear();
        m.is_gyrostat = vec![false; m.n_bodies()];
        m.carrier_inertia = m.bodies.iter().map(|b| b.inertia).collect();
        m.carrier_ia = m.carrier_inertia.iter().map(|&i| i.into()).collect();
        m
    }

    /// Chains of hinges through massless zero-length links that ABA processes as one
    /// multi-axis joint (see [`Chain`]).
    pub fn chains(&self) -> &[Chain] {
        &self.chains
    }

    /// The same model with every massless link of a [`Chain`] kept as a plain tree body in
    /// ABA: the reference form against which the multi-axis form is checked.
    pub fn without_chains(&self) -> Model {
        let mut m = self.clone();
        m.chains.clear();
        m.chain_part = vec![ChainPart::None; m.n_bodies()];
        m
    }

    /// Recognises the chains of hinges through massless zero-length links (see [`Chain`]);
    /// after [`Model::find_gyrostats`] (a gyrostat rotor is no chain's tip).
    fn find_chains(&mut self) {
        let n = self.n_bodies();
        self.chains.clear();
        self.chain_part = vec![ChainPart::None; n];
        let mut children = vec![0usize; n];
        for p in self.parent.iter().flatten() {
            children[*p] += 1;
        }
        let massless = |b: &BodyInfo| b.mass == 0.0 && b.inertia_com == Mat3::zeros();
        for tip in 1..n {
            if massless(&self.bodies[tip]) || self.is_gyrostat[tip] {
                continue;
            }
            // Walk up through massless one-child links whose two hinge points coincide.
            let mut inward = Vec::new(); // the tip's link first
            let mut child = tip;
            while let Some(l) = self.parent[child] {
                let (Some(lj), Some(cj)) = (&self.joints[l], &self.joints[child]) else {
                    break; // the root is no link
                };
                if !massless(&self.bodies[l]) || children[l] != 1 || cj.at != lj.child_at {
                    break;
                }
                inward.push(l);
                child = l;
            }
            // k = 2 or 3 hinges; more through one point are always singular: plain bodies.
            if inward.is_empty() || inward.len() > 2 {
                continue;
            }
            let k = inward.len() + 1;
            let mut order = [tip; 3];
            order[1..k].copy_from_slice(&inward);
            let outermost = inward[inward.len() - 1];
            let armature = order[..k]
                .iter()
                .any(|&b| self.joints[b].as_ref().expect("joint").armature != 0.0);
            let offset_links = inward
                .iter()
                .any(|&b| self.joints[b].as_ref().expect("joint").child_at != Vec3::zeros());
            for &l in &inward {
                self.chain_part[l] = ChainPart::Link;
            }
            self.chain_part[tip] = ChainPart::Tip(self.chains.len());
            let joint = |t: usize| self.joints[order[t]].as_ref().expect("joint");
            let mut chain = Chain {
                order,
                k,
                parent: self.parent[outermost].expect("a link has a parent"),
                spherical: k == 3 && !armature,
                offset_links,
                axis: [Vec3::zeros(); 3],
                armature: [0.0; 3],
                dof: [0; 3],
                link_at: [Vec3::zeros(); 3],
                tip_at: joint(0).child_at,
                point: joint(k - 1).at,
            };
            for t in 0..k {
                let j = joint(t);
                chain.axis[t] = j.s.ang;
                chain.armature[t] = j.armature;
                chain.dof[t] = j.dof;
                if t > 0 {
                    chain.link_at[t] = j.child_at;
                }
            }
            self.chains.push(chain);
        }
    }

    /// Recognises the balanced axisymmetric leaf rotors (see [`Gyrostat`]).
    fn find_gyrostats(&mut self) {
        let n = self.n_bodies();
        self.gyrostats.clear();
        self.is_gyrostat = vec![false; n];
        self.carrier_inertia = self.bodies.iter().map(|b| b.inertia).collect();
        let mut has_child = vec![false; n];
        for p in self.parent.iter().flatten() {
            has_child[*p] = true;
        }
        for (i, &parent_of_others) in has_child.iter().enumerate().skip(1) {
            let joint = self.joints[i].as_ref().expect("non-root body has a joint");
            if parent_of_others || joint.armature != 0.0 {
                continue;
            }
            let body = &self.bodies[i];
            let a = joint.s.ang; // unit axis, child coordinates
            let ic = &body.inertia_com;
            let j = a.dot(&(ic * a));
            let scale = ic.abs().max();
            if !(j > 0.0 && j.is_finite()) {
                continue;
            }
            let it = 0.5 * (ic.trace() - j);
            let aat = a * a.transpose();
            let sym = aat * j + (Mat3::identity() - aat) * it;
            if (ic - sym).abs().max() > GYROSTAT_TOLERANCE * scale {
                continue;
            }
            // The centre of mass on the axis through the hinge point.
            let off = (body.com - joint.child_at).cross(&a);
            let len = body.com.norm() + joint.child_at.norm();
            if off.norm() > GYROSTAT_TOLERANCE * len.max(f64::MIN_POSITIVE) {
                continue;
            }
            let p = self.parent[i].expect("parent");
            let locked = body.inertia.inv_transform(&joint.transform(0.0));
            self.carrier_inertia[p] += locked;
            self.is_gyrostat[i] = true;
            self.gyrostats.push(Gyrostat {
                body: i,
                parent: p,
                axis: joint.axis,
                axial: j,
            });
        }
        self.carrier_ia = self.carrier_inertia.iter().map(|&i| i.into()).collect();
        for g in &self.gyrostats {
            self.carrier_ia[g.parent].a -= g.axis * g.axis.transpose() * g.axial;
        }
    }

    /// `Xup[i]` for a non-root body `i` at the angles in `q` (the coordinate-axis fast path
    /// where it applies).
    #[inline]
    pub(crate) fn xup(&self, i: usize, q: &[f64]) -> Transform {
        let joint = self.joints[i].as_ref().expect("non-root body has a joint");
        joint.transform_with(self.coord_axis[i].as_ref(), self.angle(q, joint))
    }

    /// The hinge angle of body `i`'s joint in `q`.
    #[inline]
    pub(crate) fn angle(&self, q: &[f64], joint: &Joint) -> f64 {
        q[self.base_nq() + joint.hinge]
    }
}
