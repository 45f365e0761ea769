//! [`FlexModel`]: a rigid [`Model`] whose bodies may carry elastic coordinates.
//!
//! Coordinates: `q = [the rigid model's q…, η…]`, `v = [the rigid model's v…, η̇…]`, the
//! elastic coordinates of each flexible body together, bodies in the model's (depth-first)
//! order, modes from 1 within a body.

use super::beam::{Beam, Stiffening};
use super::modal::{ModalData, NodeShape};
use super::node::Node;
use crate::error::{ModelError, Num};
use crate::model::{Model, ModelBuilder, UNIT_NORM_TOLERANCE};
use crate::spatial::{Force, Mat3, Motion, RigidInertia, Vec3};
use thiserror::Error;

pub use super::deflection::{Deflection, LargeDeflection, SMALL_DEFLECTION};

/// Why the dynamics cannot resolve a mode whose articulated pivot comes out not positive
/// ([`FlexError::Unresolved`], and the scene reader's check at the initial state).
pub const UNRESOLVED: &str = "each mode has unit modal mass, so the shapes of a body far \
     lighter than the bodies it carries move them by huge amounts per unit coordinate, and \
     their inertia drowns its own in round-off; give the body its real mass, or model it as a \
     hinge spring";

/// The largest entry of the mass matrix's diagonal at an elastic coordinate, in units of the
/// mode's own modal mass (1), that the dynamics resolve: the inertia a mode carries, magnified
/// by its unit-modal-mass shapes, enters its articulated pivot with round-off of about
/// `1e-16` of itself, which at this ratio is `1e-6` of the mode's own mass. The flexible
/// deployment's strips carry up to 220 times theirs; a strip 1e13 times lighter (`rho_A =
/// 1e-12`) passes the pivot's sign at rest and fails at its first steps.
pub const MAGNIFICATION_LIMIT: f64 = 1e10;

/// Largest distance (m) between a child hinge's `at` and the modes-file node that carries it,
/// and between a thruster's point and the node whose shapes it takes.
pub const MODES_FILE_NODE_TOLERANCE: f64 = 1e-6;

/// Largest number of beam modes (the beam integrals' quadrature is sized for it).
pub const MAX_BEAM_MODES: usize = 12;

/// Where a flexible body's modes come from.
#[derive(Clone, Debug, PartialEq)]
pub enum Modes {
    /// An Euler-Bernoulli cantilever; its mass `ρA L` (a uniform thin rod) adds to the body's.
    Beam(Beam),
    /// Given modal data (the body's inertia already includes the deformable part) and the
    /// mode shapes at each child hinge's point, by hinge name.
    Given {
        /// The modal integrals.
        data: ModalData,
        /// Per child hinge (its name): the shapes at its `at`.
        nodes: Vec<(String, NodeShape)>,
        /// The second-order inertia of a beam-like structure along one axis (a modes file's
        /// `[stiffening]`), or none: the stiffening of given modes is what this says.
        stiffening: Option<Box<Stiffening>>,
        /// Points whose deflection tells how far the body is bent (a modes file's nodes):
        /// [`FlexModel::deflection_of`] watches those off the body frame's origin.
        watch: Vec<WatchPoint>,
    },
}

/// A point of a body with given modes where their shapes are known (a modes file's node):
/// watched for a deflection beyond what the modal model holds
/// ([`FlexModel::deflection_of`]), and where a load reaches the modes
/// ([`FlexModel::point_shape`]).
#[derive(Clone, Debug, PartialEq)]
pub struct WatchPoint {
    /// Its name (for messages).
    pub name: String,
    /// Where it is undeformed, body frame (m).
    pub at: Vec3,
    /// Each mode's translation there, body axes (m per unit `ηₖ`).
    pub translation: Vec<Vec3>,
    /// Each mode's small rotation there, body axes (rad per unit `ηₖ`).
    pub rotation: Vec<Vec3>,
    /// The foreshortening there, where the file gives it ([`NodeShape::shortening`]).
    pub shortening: Option<Vec<f64>>,
}

/// A flexible body as given to [`FlexModel::build`].
#[derive(Clone, Debug, PartialEq)]
pub struct Flexible {
    /// The body's name.
    pub body: String,
    /// Its modes.
    pub modes: Modes,
    /// Modal damping ratio `ζ` of every mode, `>= 0`.
    pub damping: f64,
    /// The consistent terms of a beam, or of given modes with their `stiffening` (for given
    /// modes without it, `true` is refused: [`FlexError::Invalid`]): the deflection's
    /// first-order inertia (its first moment and products of inertia) and, for the
    /// geometric stiffening, its second-order inertia: the axial load of the frame's whole
    /// acceleration (centrifugal about the frame's origin, the origin's own centripetal and
    /// linear acceleration, the angular acceleration) through the foreshortening, and the
    /// deflection's own centrifugal load (the softening of bending across the spin).
    pub stiffening: bool,
}

/// Why a flexible model could not be built.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum FlexError {
    /// The rigid model is invalid.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A flexible body names no body of the model.
    #[error("flexible body `{0}`: no body of that name")]
    UnknownBody(String),
    /// Two flexible entries name one body.
    #[error("body `{0}` is given flexible twice")]
    Duplicate(String),
    /// A parameter is out of range.
    #[error("flexible body `{body}`: {what}")]
    Invalid {
        /// The body.
        body: String,
        /// What is wrong.
        what: String,
    },
    /// Given modes lack the shapes at a child hinge's point.
    #[error("flexible body `{body}`: no mode shapes at the point of its child hinge `{hinge}`")]
    MissingNode {
        /// The body.
        body: String,
        /// The hinge.
        hinge: String,
    },
    /// [`FlexModel::with_rigid`] was given a tree that does not start with the model's bodies.
    #[error("a grown tree must keep the flexible model's bodies first, unchanged")]
    Grown,
    /// `[[I, P], [Pᵀ, 1]]` is not positive semidefinite.
    #[error("flexible body `{0}`: its mass matrix [[I, P], [Pᵀ, 1]] is not positive semidefinite")]
    NotPositiveDefinite(String),
    /// At rest, the dynamics' pivot of a mode is not positive: round-off, where a body's modes
    /// (each of unit modal mass) carry bodies far heavier than itself.
    #[error(
        "flexible body `{body}`: at rest the dynamics cannot resolve its mode {mode} (its \
         articulated pivot is {pivot}, where the mass matrix makes it positive): {}",
        UNRESOLVED
    )]
    Unresolved {
        /// The body.
        body: String,
        /// Its mode (from 1).
        mode: usize,
        /// The pivot the articulated-body algorithm found.
        pivot: Num,
    },
    /// At rest, a mode carries more than [`MAGNIFICATION_LIMIT`] times its own modal mass:
    /// its pivot is round-off, whatever its sign.
    #[error(
        "flexible body `{body}`: at rest the dynamics cannot resolve its mode {mode} (it \
         carries {ratio:.3e} times its own modal mass, past the {} at which round-off of that \
         inertia reaches a millionth of the mode's own): {}",
        Num(MAGNIFICATION_LIMIT),
        UNRESOLVED
    )]
    Magnified {
        /// The body.
        body: String,
        /// Its mode (from 1).
        mode: usize,
        /// The mass matrix's diagonal entry at the mode (its own modal mass is 1).
        ratio: f64,
    },
}

/// A rigid [`Model`] plus, per body, optional modal data, and per hinge whose parent is
/// flexible, the node (its virtual joints, `node.rs`) that carries it. Immutable;
/// [`super::FlexData`] is its workspace.
#[derive(Clone, Debug, PartialEq)]
pub struct FlexModel {
    pub(crate) rigid: Model,
    /// Per body: number of modes `mᵢ` (0 for a rigid body).
    pub(crate) modes: Vec<usize>,
    /// Per body: the index of its first mode among all elastic coordinates.
    pub(crate) offset: Vec<usize>,
    /// Total number of elastic coordinates.
    pub(crate) n_elastic: usize,
    /// `P` columns, all bodies (at `offset`).
    pub(crate) momentum: Vec<Force>,
    /// `ωₖ²` (1/s²), all modes.
    pub(crate) stiffness: Vec<f64>,
    /// `2 ζ ωₖ` (1/s), all modes.
    pub(crate) damping: Vec<f64>,
    /// Per body: the node carrying its hinge when its parent is flexible.
    pub(crate) nodes: Vec<Option<Node>>,
    /// Per body on a node: the hinge's coordinate axis where the node turns only about that
    /// axis too (a beam bending about the hinge's axis), so that `Xup` is a rotation about
    /// it and takes the hinges' fast path ([`FlexModel::frame_axis`]).
    pub(crate) node_axis: Vec<Option<crate::axis::CoordAxis>>,
    /// Per body: its beam, if its modes are a beam's (for the tip deflection).
    pub(crate) beams: Vec<Option<Beam>>,
    /// Per beam body: its modes' deflection at the tip, `φₖ(L)` (an output's column, so made
    /// once: each mode's shape is a root of the frequency equation).
    pub(crate) tips: Vec<Vec<f64>>,
    /// Per body: its children.
    pub(crate) children: Vec<Vec<usize>>,
    /// Per body: its beam's second-order inertia (centrifugal stiffening), when on.
    pub(crate) stiffening: Vec<Option<Stiffening>>,
    /// Per stiffened body: its stiffening's weights in the field's generalised forces
    /// (`field.rs`).
    pub(crate) field_weights: Vec<Option<super::field::FieldWeights>>,
    /// Per body with given modes: the points [`FlexModel::deflection_of`] watches (those of
    /// [`Modes::Given`]'s `watch` off the frame's origin).
    pub(crate) watch: Vec<Vec<WatchPoint>>,
    /// The flexible bodies as given (to attach them again to a grown tree).
    pub(crate) spec: Vec<Flexible>,
    /// Every balanced rotor of the rigid model ([`crate::Gyrostat`]) rides on a rigid
    /// carrier: the flexible ABA folds them into their carriers as the rigid ABA does.
    pub(crate) fold_rotors: bool,
    /// Per chain of the rigid model ([`crate::Chain`]): whether the flexible ABA eliminates
    /// it at its tip as one spherical joint (`flexible/chain.rs`): three hinges without
    /// armature, rigid links and a rigid parent (the tip may be flexible).
    pub(crate) fold_chain: Vec<bool>,
    /// Per body: the chain it is the tip or a link of, where that chain folds.
    pub(crate) chain_of: Vec<Option<usize>>,
}

fn invalid(body: &str, what: impl Into<String>) -> FlexError {
    FlexError::Invalid {
        body: body.to_string(),
        what: what.into(),
    }
}

fn check_beam(body: &str, b: &Beam) -> Result<(), FlexError> {
    let finite = [b.length, b.ei, b.rho_a]
        .iter()
        .chain(b.root.iter())
        .chain(b.axis.iter())
        .chain(b.bend.iter())
        .all(|x| x.is_finite());
    if !finite {
        return Err(invalid(body, "beam: a value is not finite"));
    }
    if !(b.length > 0.0 && b.ei > 0.0 && b.rho_a > 0.0) {
        return Err(invalid(body, "beam: length, EI and rho_A must be positive"));
    }
    if (b.axis.norm() - 1.0).abs() > UNIT_NORM_TOLERANCE
        || (b.bend.norm() - 1.0).abs() > UNIT_NORM_TOLERANCE
    {
        return Err(invalid(body, "beam: axis and bend must be unit vectors"));
    }
    if b.axis.dot(&b.bend).abs() > UNIT_NORM_TOLERANCE {
        return Err(invalid(body, "beam: axis and bend must be perpendicular"));
    }
    if b.modes == 0 || b.modes > MAX_BEAM_MODES {
        return Err(invalid(
            body,
            format!("beam: modes must be 1 to {MAX_BEAM_MODES}, got {}", b.modes),
        ));
    }
    // Each value in range, together they can still take the beam's mass, its inertia or its
    // modes' stiffness out of f64 (a length of 1e-300 m: frequencies of 1e600 rad/s), which
    // the dynamics would meet as a NaN pivot at their first step.
    let (m, w1, wn) = (b.mass(), b.omega(1), b.omega(b.modes));
    let moment = m * b.length * b.length / 12.0;
    if !(m.is_normal() && moment.is_finite() && w1 > 0.0 && (wn * wn).is_finite()) {
        return Err(invalid(
            body,
            format!(
                "beam: length {}, EI {} and rho_A {} make a mass of {} kg, a moment of inertia of {} kg m² and modes from {} to {} rad/s: out of the range the dynamics computes in (f64)",
                Num(b.length),
                Num(b.ei),
                Num(b.rho_a),
                Num(m),
                Num(moment),
                Num(w1),
                Num(wn)
            ),
        ));
    }
    Ok(())
}

impl FlexModel {
    /// Builds the rigid model from `builder` (a beam's mass added to its body first) and
    /// attaches the flexible bodies' modes.
    pub fn build(builder: ModelBuilder, flexible: &[Flexible]) -> Result<FlexModel, FlexError> {
        let mut builder = builder;
        let mut beams_by_name: Vec<(String, Beam)> = Vec::new();
        for f in flexible {
            if flexible.iter().filter(|g| g.body == f.body).count() > 1 {
                return Err(FlexError::Duplicate(f.body.clone()));
            }
            if !(f.damping >= 0.0 && f.damping.is_finite()) {
                return Err(invalid(&f.body, "damping must be finite and >= 0"));
            }
            let body = builder
                .bodies_mut()
                .iter_mut()
                .find(|b| b.name == f.body)
                .ok_or_else(|| FlexError::UnknownBody(f.body.clone()))?;
            // The rigid part as written, before the beam's mass hides a negative mass or
            // inertia in the sum.
            crate::model::check_body(body)?;
            if let Modes::Beam(beam) = &f.modes {
                check_beam(&f.body, beam)?;
                // A uniform thin rod of the beam's mass along its axis.
                let bm = beam.mass();
                let rod = RigidInertia::from_com(
                    bm,
                    beam.root + beam.axis * (0.5 * beam.length),
                    (Mat3::identity() - beam.axis * beam.axis.transpose())
                        * (bm * beam.length * beam.length / 12.0),
                );
                let own = RigidInertia::from_com(body.mass, body.com, body.inertia);
                let sum = own + rod;
                let com = sum.h / sum.mass;
                let cx = crate::spatial::skew(&com);
                body.mass = sum.mass;
                body.com = com;
                let ic = sum.inertia + cx * cx * sum.mass;
                body.inertia = (ic + ic.transpose()) * 0.5;
                beams_by_name.push((f.body.clone(), beam.clone()));
            }
        }
        let rigid = builder.build()?;
        FlexModel::attach(rigid, flexible)
    }

    /// Attaches flexible bodies to a built rigid model whose inertias already include them
    /// (as [`FlexModel::build`] makes it). With no flexible body, the rigid model itself.
    pub fn attach(rigid: Model, flexible: &[Flexible]) -> Result<FlexModel, FlexError> {
        Self::attach_reusing(rigid, flexible, None)
    }

    /// [`FlexModel::attach`], taking a beam's integrals (its momentum coefficients and
    /// second-order inertia: Gauss-Legendre over its length, most of a flexible model's
    /// making) from `known` where it has the same beam on the same body.
    fn attach_reusing(
        rigid: Model,
        flexible: &[Flexible],
        known: Option<&FlexModel>,
    ) -> Result<FlexModel, FlexError> {
        let n = rigid.n_bodies();
        let mut data: Vec<Option<(ModalData, f64)>> = vec![None; n];
        let mut beams: Vec<Option<Beam>> = vec![None; n];
        let mut stiffening: Vec<Option<Stiffening>> = vec![None; n];
        let mut watch: Vec<Vec<WatchPoint>> = vec![Vec::new(); n];
        for f in flexible {
            let b = rigid
                .body_index(&f.body)
                .ok_or_else(|| FlexError::UnknownBody(f.body.clone()))?;
            if data[b].is_some() {
                return Err(FlexError::Duplicate(f.body.clone()));
            }
            let md = match &f.modes {
                Modes::Beam(beam) => {
                    check_beam(&f.body, beam)?;
                    beams[b] = Some(beam.clone());
                    let same =
                        known.filter(|k| k.beams.get(b).and_then(Option::as_ref) == Some(beam));
                    if f.stiffening {
                        stiffening[b] = Some(
                            same.and_then(|k| k.stiffening[b].clone())
                                .unwrap_or_else(|| beam.stiffening()),
                        );
                    }
                    ModalData {
                        momentum: same.map_or_else(
                            || beam.momentum_coefficients(),
                            |k| k.momentum[k.offset[b]..][..k.modes[b]].to_vec(),
                        ),
                        omega: (1..=beam.modes).map(|k| beam.omega(k)).collect(),
                    }
                }
                Modes::Given {
                    data,
                    stiffening: given,
                    watch: points,
                    ..
                } => {
                    if data.momentum.len() != data.omega.len() {
                        return Err(invalid(&f.body, "momentum and omega lengths differ"));
                    }
                    for p in points {
                        if p.translation.len() != data.omega.len() {
                            return Err(invalid(
                                &f.body,
                                format!(
                                    "watched point `{}`: {} translations for {} modes",
                                    p.name,
                                    p.translation.len(),
                                    data.omega.len()
                                ),
                            ));
                        }
                        let finite = p.at.iter().chain(p.translation.iter().flatten());
                        if !finite.into_iter().all(|x| x.is_finite()) {
                            return Err(invalid(
                                &f.body,
                                format!("watched point `{}`: a value is not finite", p.name),
                            ));
                        }
                    }
                    // A point at the frame's origin has no distance to measure its
                    // deflection against.
                    watch[b] = points
                        .iter()
                        .filter(|p| p.at.norm() > 0.0)
                        .cloned()
                        .collect();
                    if f.stiffening {
                        let m = data.omega.len();
                        match given {
                            None => {
                                return Err(invalid(
                                    &f.body,
                                    "stiffening needs the modes' second-order inertia (a modes file's [stiffening] block)",
                                ));
                            }
                            Some(s)
                                if s.j0.len() != m * m
                                    || s.j1.len() != m * m
                                    || s.first.len() != m =>
                            {
                                return Err(invalid(
                                    &f.body,
                                    "the stiffening's integrals do not match the number of modes",
                                ));
                            }
                            Some(s) => stiffening[b] = Some(s.as_ref().clone()),
                        }
                    }
                    if !data.omega.iter().all(|w| *w > 0.0 && w.is_finite()) {
                        return Err(invalid(&f.body, "frequencies must be positive and finite"));
                    }
                    data.clone()
                }
            };
            // [[I, P], [Pᵀ, 1]] ≥ 0 ⟺ I − P Pᵀ ≥ 0 (semidefinite: a bare beam has no
            // inertia about its own axis), to round-off of the body's inertia scale.
            let inertia = rigid.bodies()[b].inertia.to_matrix();
            let mut schur = inertia;
            for p in &md.momentum {
                let c = p.to_vector();
                schur -= c * c.transpose();
            }
            let lowest = schur.symmetric_eigenvalues().min();
            if lowest.is_nan() || lowest < -1e-12 * inertia.amax() {
                return Err(FlexError::NotPositiveDefinite(f.body.clone()));
            }
            data[b] = Some((md, f.damping));
        }
        let modes: Vec<usize> = data
            .iter()
            .map(|d| d.as_ref().map_or(0, |(m, _)| m.modes()))
            .collect();
        let mut offset = vec![0; n];
        let mut total = 0;
        for i in 0..n {
            offset[i] = total;
            total += modes[i];
        }
        let mut momentum = Vec::with_capacity(total);
        let mut stiffness = Vec::with_capacity(total);
        let mut damping = Vec::with_capacity(total);
        for (md, zeta) in data.iter().flatten() {
            momentum.extend_from_slice(&md.momentum);
            stiffness.extend(md.omega.iter().map(|w| w * w));
            damping.extend(md.omega.iter().map(|w| 2.0 * zeta * w));
        }
        let mut nodes = vec![None; n];
        let mut children = vec![Vec::new(); n];
        for i in 1..n {
            let p = rigid.parent()[i].expect("non-root body has a parent");
            children[p].push(i);
            if modes[p] == 0 {
                continue;
            }
            let joint = rigid.joint(i).expect("joint");
            let hinge = &rigid.hinge_names()[joint.hinge()];
            let pname = &rigid.bodies()[p].name;
            let shape = if let Some(beam) = &beams[p] {
                beam.node(joint.at())
            } else {
                let f = flexible
                    .iter()
                    .find(|f| &f.body == pname)
                    .expect("flexible");
                let Modes::Given { nodes, .. } = &f.modes else {
                    unreachable!("a body without a beam has given modes")
                };
                nodes
                    .iter()
                    .find(|(h, _)| h == hinge)
                    .map(|(_, s)| s.clone())
                    .ok_or_else(|| FlexError::MissingNode {
                        body: pname.clone(),
                        hinge: hinge.clone(),
                    })?
            };
            if shape.phi.len() != modes[p] || shape.psi.len() != modes[p] {
                return Err(invalid(
                    pname,
                    format!("hinge `{hinge}`: one shape per mode"),
                ));
            }
            let mut node = Node::new(*joint.at(), &shape);
            if let Some(s) = &stiffening[p] {
                let c = match &beams[p] {
                    Some(beam) => Some(beam.foreshortening(joint.at())),
                    None => shape.shortening.clone(),
                };
                node.shortening = c.map(|c| super::node::Shortening { axis: s.axis, c });
            }
            nodes[i] = Some(node);
        }
        let node_axis = (0..n)
            .map(|i| {
                let (node, axis) = (nodes[i].as_ref()?, rigid.coord_axis[i]?);
                let turns_about = |c: &crate::axis::CoordAxis| c.index() == axis.index();
                (node.rotations.is_empty() || node.coord.as_ref().is_some_and(turns_about))
                    .then_some(axis)
            })
            .collect();
        let tips = beams
            .iter()
            .map(|b| {
                b.as_ref().map_or_else(Vec::new, |beam| {
                    beam.cantilever_modes()
                        .iter()
                        .map(|m| m.shape(beam.length)[0])
                        .collect()
                })
            })
            .collect();
        // A rotor on a flexible carrier stays a body (its carrier's inertia is the deformed
        // one, which the folded form does not carry), and then every rotor does.
        let fold_rotors = rigid
            .gyrostats
            .iter()
            .all(|g| modes[g.parent] == 0 && modes[g.body] == 0 && nodes[g.body].is_none());
        let fold_chain = rigid
            .chains
            .iter()
            .map(|c| {
                let rigid_links = c.order[1..c.k].iter().all(|&l| modes[l] == 0);
                c.spherical && rigid_links && modes[c.parent] == 0
            })
            .collect::<Vec<_>>();
        let mut chain_of = vec![None; n];
        for (k, c) in rigid.chains.iter().enumerate() {
            if fold_chain[k] {
                for &b in &c.order[..c.k] {
                    chain_of[b] = Some(k);
                }
            }
        }
        let model = FlexModel {
            fold_rotors,
            fold_chain,
            chain_of,
            rigid,
            modes,
            tips,
            offset,
            n_elastic: total,
            momentum,
            stiffness,
            damping,
            nodes,
            node_axis,
            beams,
            children,
            field_weights: stiffening
                .iter()
                .map(|s| s.as_ref().map(super::field::FieldWeights::of))
                .collect(),
            stiffening,
            watch,
            spec: flexible.to_vec(),
        };
        model.check_resolved()?;
        Ok(model)
    }

    /// The dynamics at rest (the neutral configuration, no motion) must resolve every mode.
    /// Each body passes its own test above, but a flexible body far lighter than what it
    /// carries (`rho_A = 1e-30` on the flexible deployment's first strip) has unit-modal-mass
    /// shapes of `1/√m` and sees its children's inertia magnified by `1/m`: the articulated
    /// pivot of its modes is then round-off of that (`-4.5e15` at that strip's mode 3), and
    /// every run would end at its first step in "mass matrix is not positive definite". A
    /// hinge's pivot failing is left to the run: it is the rigid tree's to report.
    fn check_resolved(&self) -> Result<(), FlexError> {
        if self.n_elastic == 0 {
            return Ok(());
        }
        let rest = self.neutral();
        let name = |i: usize| self.rigid.bodies()[i].name.clone();
        if let Some((i, mode, pivot)) = self.unresolved_mode(&rest) {
            return Err(FlexError::Unresolved {
                body: name(i),
                mode,
                pivot: Num(pivot),
            });
        }
        match self.magnified_mode(&rest) {
            Some((i, mode, ratio)) => Err(FlexError::Magnified {
                body: name(i),
                mode,
                ratio,
            }),
            None => Ok(()),
        }
    }

    /// The mode that carries the most inertia at positions `q`, if more than
    /// [`MAGNIFICATION_LIMIT`] times its own modal mass: its body, the mode (from 1) and the
    /// mass matrix's diagonal entry there (the mode's own modal mass is 1). A mode past it
    /// has a pivot of round-off, which can keep its sign at rest and lose it at the first
    /// steps.
    pub fn magnified_mode(&self, q: &[f64]) -> Option<(usize, usize, f64)> {
        let mut data = super::FlexData::new(self);
        let m = super::crba(self, &mut data, q).ok()?;
        let nv = self.rigid.nv();
        let (e, ratio) = (0..self.n_elastic)
            .map(|e| (e, m[(nv + e, nv + e)]))
            .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
        if ratio > MAGNIFICATION_LIMIT {
            let (i, mode) = self.mode_of(e)?;
            Some((i, mode, ratio))
        } else {
            None
        }
    }

    /// The mode whose articulated pivot the dynamics at positions `q` (at rest, no force)
    /// find not positive, if any: its body, the mode (from 1) and the pivot. A hinge's pivot
    /// failing, or any other error, is not a mode's and gives `None`.
    pub fn unresolved_mode(&self, q: &[f64]) -> Option<(usize, usize, f64)> {
        let zero = vec![0.0; self.nv()];
        let mut data = super::FlexData::new(self);
        match super::aba(self, &mut data, q, &zero, &zero, None) {
            Err(crate::DynamicsError::NotPositiveDefinite { index, pivot }) => {
                let (i, mode) = self.mode_of(index.checked_sub(self.rigid.nv())?)?;
                Some((i, mode, pivot))
            }
            _ => None,
        }
    }

    /// The same flexible bodies attached to `rigid`, a tree grown from this one by bodies
    /// appended after its own (a simulation's reaction-wheel rotors): the first bodies must
    /// be this model's, in order, with the same names and inertias. The modal damping
    /// (per mode, as a modes file may give it) is kept. A body added on a flexible parent
    /// rides on the deformation at its hinge point like any other.
    pub fn with_rigid(&self, rigid: Model) -> Result<FlexModel, FlexError> {
        let n = self.rigid.n_bodies();
        let same = rigid.n_bodies() >= n
            && self
                .rigid
                .bodies()
                .iter()
                .zip(rigid.bodies())
                .all(|(a, b)| a.name == b.name && a.inertia == b.inertia);
        if !same {
            return Err(FlexError::Grown);
        }
        // The beams are this model's: their integrals are taken, not made again.
        let mut grown = FlexModel::attach_reusing(rigid, &self.spec, Some(self))?;
        grown.damping.copy_from_slice(&self.damping);
        Ok(grown)
    }

    /// Velocity coordinate `index` of `v` in words, for messages: the rigid model's
    /// ([`Model::coordinate`]), or ``body `panel`'s mode 2`` (modes from 1).
    pub fn coordinate(&self, index: usize) -> String {
        let nv = self.rigid.nv();
        match index.checked_sub(nv).and_then(|e| self.mode_of(e)) {
            Some((i, k)) => format!("body `{}`'s mode {k}", self.rigid.bodies()[i].name),
            None if index < nv => self.rigid.coordinate(index),
            None => format!("coordinate {index}"),
        }
    }

    /// The body and its mode (from 1) of elastic coordinate `e` (from 0, all the elastic
    /// coordinates in order).
    pub fn mode_of(&self, e: usize) -> Option<(usize, usize)> {
        (0..self.rigid.n_bodies())
            .find(|&i| e >= self.offset[i] && e < self.offset[i] + self.modes[i])
            .map(|i| (i, e - self.offset[i] + 1))
    }

    /// The rigid model (the flexible bodies' undeformed inertias).
    pub fn rigid(&self) -> &Model {
        &self.rigid
    }
    /// The flexible bodies as given to [`FlexModel::build`] or [`FlexModel::attach`].
    pub fn flexible(&self) -> &[Flexible] {
        &self.spec
    }
    /// Whether body `i` has `stiffening`: its inertia then depends on its deformation
    /// ([`FlexModel::deformed_inertia`]).
    pub fn stiffened(&self, i: usize) -> bool {
        self.stiffening.get(i).is_some_and(Option::is_some)
    }
    /// Body `i`'s beam, when its modes are a beam's.
    pub fn beam(&self, i: usize) -> Option<&Beam> {
        self.beams[i].as_ref()
    }
    /// Number of position coordinates: the rigid model's plus the elastic ones.
    pub fn nq(&self) -> usize {
        self.rigid.nq() + self.n_elastic
    }
    /// Number of velocity coordinates: the rigid model's plus the elastic ones.
    pub fn nv(&self) -> usize {
        self.rigid.nv() + self.n_elastic
    }
    /// Number of elastic coordinates.
    pub fn n_elastic(&self) -> usize {
        self.n_elastic
    }
    /// Modes of body `i` (0 when rigid).
    pub fn modes(&self, i: usize) -> usize {
        self.modes[i]
    }
    /// Index of body `i`'s first mode among the elastic coordinates (add `rigid().nq()` for
    /// `q`, `rigid().nv()` for `v`).
    pub fn elastic_offset(&self, i: usize) -> usize {
        self.offset[i]
    }
    /// `ωₖ²` of all modes, in coordinate order (1/s²).
    pub fn stiffness(&self) -> &[f64] {
        &self.stiffness
    }
    /// `2 ζ ωₖ` of all modes (1/s).
    pub fn damping(&self) -> &[f64] {
        &self.damping
    }
    /// The neutral configuration: the rigid model's, zero deformation.
    pub fn neutral(&self) -> Vec<f64> {
        let mut q = self.rigid.neutral();
        q.resize(self.nq(), 0.0);
        q
    }
    /// The mode shapes of body `i` at its point `p` (body frame, m), with where its modes lie
    /// among the elastic coordinates: a load `(n, f)` (couple, force; body axes) at `p`
    /// does the work `Σₖ (ψₖ·n + φₖ·f) δηₖ`, its generalised forces on them. `None` for a
    /// rigid body, and for given modes at a point that is none of their nodes (a modes
    /// file's shapes are known at its nodes only; [`MODES_FILE_NODE_TOLERANCE`]).
    pub fn point_shape(
        &self,
        i: usize,
        p: &crate::spatial::Vec3,
    ) -> Option<(std::ops::Range<usize>, NodeShape)> {
        let at = self.offset[i];
        let range = at..at + self.modes[i];
        if let Some(beam) = self.beams.get(i)?.as_ref() {
            return Some((range, beam.node(p)));
        }
        let node = self.node_at(i, p)?;
        Some((
            range,
            NodeShape {
                phi: node.translation.clone(),
                psi: node.rotation.clone(),
                shortening: node.shortening.clone(),
            },
        ))
    }
    /// For a stiffened beam, its axis and the foreshortening at its point `p`
    /// ([`Beam::foreshortening`]), and for stiffened given modes at a node whose
    /// `shortening` the file gives: a force `f` there does the work `−(a · f) (C η)ₖ` on mode
    /// `k` besides `φₖ · f`, the geometric stiffness of a load carried along the beam (as a
    /// body hung on a node has through the node's kinematics). `None` otherwise.
    pub fn point_shortening(&self, i: usize, p: &Vec3) -> Option<(Vec3, Vec<f64>)> {
        let axis = self.stiffening.get(i)?.as_ref()?.axis;
        match self.beams[i].as_ref() {
            Some(beam) => Some((axis, beam.foreshortening(p))),
            None => Some((axis, self.node_at(i, p)?.shortening.clone()?)),
        }
    }
    /// The node of body `i`'s given modes at `p` (within [`MODES_FILE_NODE_TOLERANCE`]), if any.
    pub fn node_at(&self, i: usize, p: &crate::spatial::Vec3) -> Option<&WatchPoint> {
        self.watch
            .get(i)?
            .iter()
            .find(|n| (n.at - p).norm() <= MODES_FILE_NODE_TOLERANCE)
    }
    /// The coordinate axis of body `i`'s hinge where its `Xup` is the rigid hinge's (the body
    /// on its parent's frame, not on a node) and the hinge has one: the fast path of the
    /// transforms ([`crate::axis::CoordAxis`]), as the rigid algorithms take it.
    #[inline(always)]
    pub(crate) fn frame_axis(&self, i: usize) -> &Option<crate::axis::CoordAxis> {
        match self.nodes[i] {
            None => &self.rigid.coord_axis[i],
            Some(_) => &self.node_axis[i],
        }
    }
    /// Body `i`'s rigid inertia at the deformation in `q`: with stiffening, plus the
    /// deflection's first-order inertia `Σ ηₖ Iₖ`, the angular block less `G(η)` (the
    /// foreshortening's kinetic energy `−½ ωᵀ (A₀ s₀ + A₁ s₁) ω` and the deflection's own
    /// `½ ωᵀ A₂ ω ηᵀη`) and the first moment less `½ s₀ a` (the foreshortening's shift of
    /// the beam's mass towards its root); else the rigid model's.
    /// Always inlined, as [`Self::add_stiffening`]: returned through the stack, its result
    /// was read back across its stores' halves (a stalled store forwarding, `perf`).
    #[inline(always)]
    pub(crate) fn inertia_at(&self, i: usize, q: &[f64]) -> RigidInertia {
        self.deformed(i, &q[self.rigid.nq()..])
    }
    /// Body `i`'s inertia (mass, first moment and rotational inertia about its frame's
    /// origin, body axes) at the elastic coordinates `eta` (all of them, coordinate order):
    /// the rigid model's, and with `stiffening` the deflection's first- and second-order
    /// terms (see [`Stiffening`]). What the dynamics uses, and so what the centre of mass and
    /// a field acting on the mass distribution ([`FlexModel::linear_field`]) must use.
    #[inline]
    pub fn deformed_inertia(&self, i: usize, eta: &[f64]) -> RigidInertia {
        self.deformed(i, eta)
    }
    #[inline(always)]
    fn deformed(&self, i: usize, eta: &[f64]) -> RigidInertia {
        self.deformed_of(i, &eta[self.offset[i]..][..self.modes[i]])
    }
    /// [`Self::deformed_inertia`] from body `i`'s own elastic coordinates `eta` (its `mᵢ`):
    /// inlined where the caller knows `mᵢ`, its loops unrolled (the same sums).
    #[inline(always)]
    pub(crate) fn deformed_of(&self, i: usize, eta: &[f64]) -> RigidInertia {
        let mut inertia = self.rigid.bodies[i].inertia;
        if let Some(s) = &self.stiffening[i] {
            let (f, _) = s.forms(eta, eta);
            inertia.inertia -= s.g(&f);
            inertia.h -= s.axis * (0.5 * f[0]);
            for (ik, e) in s.first[..eta.len()].iter().zip(eta) {
                inertia.h += ik.h * *e;
                inertia.inertia += ik.inertia * *e;
            }
        }
        inertia
    }
    /// Body `i`'s modal momentum column `k` at the deformation in `q`: with stiffening,
    /// `Pₖ − (J₀ η)ₖ [r₀ × a; a]` (the foreshortening's rate moves the beam along its axis);
    /// else `Pₖ`. Always inlined: returned through the stack, its result was read back
    /// across its stores' halves (a stalled store forwarding per mode, `perf`).
    #[inline(always)]
    pub(crate) fn momentum_at(&self, i: usize, q: &[f64], k: usize) -> Force {
        let eta = &q[self.rigid.nq() + self.offset[i]..][..self.modes[i]];
        self.momentum_of(i, eta, k)
    }
    /// [`Self::momentum_at`] from body `i`'s own elastic coordinates `eta` (its `mᵢ`, as
    /// [`Self::deformed_of`]).
    #[inline(always)]
    pub(crate) fn momentum_of(&self, i: usize, eta: &[f64], k: usize) -> Force {
        let pk = self.momentum[self.offset[i] + k];
        match &self.stiffening[i] {
            Some(s) => pk - s.shortening * s.j0_row(k, eta),
            None => pk,
        }
    }
    /// With stiffening, the deformation-dependent inertia's terms in body `i`'s equations
    /// (`vi` the frame's velocity): the frame force `İ(η) v + Ṗ(η) η̇` (`İ` of mass 0: first
    /// moment `Σ η̇ₖ b S₁ₖ − (η̇ᵀ J₀ η) a`, rotational `Σ η̇ₖ Dₖ − Ġ`;
    /// `Ṗ η̇ = −c (η̇ᵀ J₀ η̇)`) and the modal forces `−∂T/∂η`: `−½ vᵀ Iₖ v` (the centrifugal
    /// load of the first-order inertia) and `K_g(v) η − (ωᵀ A₂ ω) η` (the `η`-derivative of
    /// `vᵀ P(η) η̇` cancels against `Ṗᵀ v`), added to `frame` and `modal`. Always inlined:
    /// out of line, the frame force it added to was read back across its stores' halves (a
    /// stalled store forwarding, `perf`).
    #[inline(always)]
    pub(crate) fn add_stiffening(
        &self,
        i: usize,
        q: &[f64],
        v: &[f64],
        vi: &Motion,
        frame: &mut Force,
        modal: &mut [f64],
    ) {
        let (o, m) = (self.offset[i], self.modes[i]);
        let eta = &q[self.rigid.nq() + o..][..m];
        let etad = &v[self.rigid.nv() + o..][..m];
        self.add_stiffening_of(i, eta, etad, vi, frame, modal);
    }
    /// [`Self::add_stiffening`] from body `i`'s own elastic coordinates and rates (its `mᵢ`,
    /// as [`Self::deformed_of`]).
    #[inline(always)]
    pub(crate) fn add_stiffening_of(
        &self,
        i: usize,
        eta: &[f64],
        etad: &[f64],
        vi: &Motion,
        frame: &mut Force,
        modal: &mut [f64],
    ) {
        if let Some(s) = &self.stiffening[i] {
            let (_, rate) = s.forms(eta, etad);
            let mut idot = RigidInertia {
                mass: 0.0,
                h: -s.axis * (0.5 * rate[0]),
                inertia: -s.g(&rate),
            };
            // Sliced to `m`: known in the ABA's instances, so the loop unrolls.
            let (first, etad) = (&s.first[..eta.len()], &etad[..eta.len()]);
            for (k, ik) in first.iter().enumerate() {
                idot.h += ik.h * etad[k];
                idot.inertia += ik.inertia * etad[k];
                // −∂T/∂ηₖ of the first-order inertia: −½ vᵀ Iₖ v.
                modal[k] -= 0.5 * vi.dot(&ik.mul_motion(vi));
            }
            *frame += idot.mul_motion(vi);
            *frame -= s.shortening * s.j0_form(etad, etad);
            s.add_force(vi, eta, modal);
        }
    }
    /// The rigid model's [`crate::Chain`]s that the flexible ABA eliminates at their tips as
    /// one spherical joint with the tip's modes: three hinges without armature, links
    /// without modes and a parent without modes. The others' links are bodies there.
    pub fn folded_chains(&self) -> impl Iterator<Item = &crate::Chain> {
        self.rigid
            .chains
            .iter()
            .zip(&self.fold_chain)
            .filter_map(|(c, &f)| f.then_some(c))
    }
    /// The same model with every [`crate::Chain`]'s links kept as plain bodies in the
    /// flexible ABA: the reference form against which the folded chains are checked (as
    /// [`Model::without_chains`] for the rigid ABA).
    pub fn without_chains(&self) -> FlexModel {
        let mut m = self.clone();
        m.fold_chain.fill(false);
        m.chain_of.fill(None);
        m
    }
    /// Largest number of modes of one body.
    pub(crate) fn max_modes(&self) -> usize {
        self.modes.iter().copied().max().unwrap_or(0)
    }
}
