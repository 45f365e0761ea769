//! Recognising the preprint's layout in any [`Model`] (cli-contract section 4).
//!
//! The layout: a free-floating root (the bus, body 1); hinges 1, 2, 3 (file order) through two
//! massless, inertia-free links of zero length (`P1 = P2 = P3`) to panel 1 (body 2); hinge 4
//! to panel 2 (body 3); hinge 5 to panel 3 (body 4). Body frames need not sit at the centres
//! of mass (the preprint's `a_i`, `c_i` are measured from them), and fixed hinge-frame
//! rotations are allowed.

use super::params::PreprintParams;
use nalgebra::{Rotation3, UnitQuaternion};
use satsim_tree::{BaseKind, Model};
use thiserror::Error;

/// Why a model does not have the preprint's layout.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum LayoutError {
    /// The root is fixed; the preprint's bus floats freely.
    #[error("the root body `{0}` is fixed; the preprint's bus needs `kind = \"free\"`")]
    FixedBase(String),
    /// Not five hinges.
    #[error("the preprint's layout has 5 hinges (3 gimbal hinges, 2 panel hinges), found {0}")]
    HingeCount(usize),
    /// Not six bodies.
    #[error("the preprint's layout has 6 bodies (bus, 2 massless links, 3 panels), found {0}")]
    BodyCount(usize),
    /// A hinge is attached to the wrong body.
    #[error(
        "hinge {number} (`{hinge}`, the {role}) must hang from {expected}, but its parent is `{found}`"
    )]
    WrongParent {
        /// 1-based number of the hinge in file order.
        number: usize,
        /// Its name.
        hinge: String,
        /// What the hinge is in the preprint.
        role: &'static str,
        /// Which body it must hang from.
        expected: String,
        /// Its actual parent.
        found: String,
    },
    /// A gimbal link has mass or inertia.
    #[error(
        "body `{body}` (gimbal link {number}, between hinges {number} and {next}) must be massless and inertia-free, found mass {mass} kg and inertia norm {inertia} kg m^2"
    )]
    LinkHasMass {
        /// 1 or 2.
        number: usize,
        /// The next hinge's number.
        next: usize,
        /// The link's name.
        body: String,
        /// Its mass.
        mass: f64,
        /// Frobenius norm of its inertia.
        inertia: f64,
    },
    /// A gimbal link has non-zero length.
    #[error(
        "body `{body}` (gimbal link {number}) must have zero length: hinge `{outgoing}` leaves it {distance} m from where hinge `{incoming}` enters it (its `at` must equal `{incoming}`'s `child_at`)"
    )]
    LinkLength {
        /// 1 or 2.
        number: usize,
        /// The link's name.
        body: String,
        /// The hinge entering the link.
        incoming: String,
        /// The hinge leaving the link.
        outgoing: String,
        /// The distance between the two hinge points (m).
        distance: f64,
    },
    /// The bus or a panel has no mass.
    #[error(
        "body `{body}` (the preprint's body {number}, {role}) must have a positive mass, found {mass} kg"
    )]
    NoMass {
        /// 1..4.
        number: usize,
        /// Bus or panel.
        role: &'static str,
        /// Its name.
        body: String,
        /// Its mass.
        mass: f64,
    },
}

/// Where the preprint's bodies sit in a model, and its parameters read from the model.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// Model body indices of bus, link 1, link 2, panel 1, panel 2, panel 3.
    pub bodies: [usize; 6],
    /// The preprint's parameters, read from the model (`a_i`, `c_i` from the centres of mass).
    pub params: PreprintParams,
}

impl Layout {
    /// Model body index of the preprint's body `i` (1 = bus, 2..4 = panels 1..3); `None` for
    /// any other `i` (the preprint has bodies 1 to 4).
    pub fn body(&self, i: usize) -> Option<usize> {
        match i {
            1 => Some(self.bodies[0]),
            2..=4 => Some(self.bodies[i + 1]),
            _ => None,
        }
    }
}

/// Relative tolerance on the zero length of the gimbal links.
pub const ZERO_LENGTH_TOLERANCE: f64 = 1e-9;

/// Recognises the preprint's layout in `model`, or says precisely what differs.
///
/// ```
/// use satsim_satellite::{build_model, recognise, PreprintParams};
/// let p = PreprintParams::default();
/// let layout = recognise(&build_model(&p)?)?;
/// assert_eq!(layout.params, p);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn recognise(model: &Model) -> Result<Layout, LayoutError> {
    let name = |i: usize| model.bodies()[i].name().to_owned();
    if model.base() != BaseKind::Free {
        return Err(LayoutError::FixedBase(name(0)));
    }
    if model.n_hinges() != 5 {
        return Err(LayoutError::HingeCount(model.n_hinges()));
    }
    if model.n_bodies() != 6 {
        return Err(LayoutError::BodyCount(model.n_bodies()));
    }
    const ROLES: [&str; 5] = [
        "gimbal hinge P1",
        "gimbal hinge P2",
        "gimbal hinge P3",
        "panel hinge P4",
        "panel hinge P5",
    ];
    const PARENTS: [&str; 5] = [
        "the root body",
        "the child of hinge 1 (gimbal link 1)",
        "the child of hinge 2 (gimbal link 2)",
        "the child of hinge 3 (panel 1)",
        "the child of hinge 4 (panel 2)",
    ];
    let mut chain = [0usize; 6];
    for k in 0..5 {
        let child = model.hinge_body()[k];
        let parent = model.parent()[child].expect("a hinge's child has a parent");
        if parent != chain[k] {
            let expected = format!("{} `{}`", PARENTS[k], name(chain[k]));
            return Err(LayoutError::WrongParent {
                number: k + 1,
                hinge: model.hinge_names()[k].clone(),
                role: ROLES[k],
                expected,
                found: name(parent),
            });
        }
        chain[k + 1] = child;
    }
    let joint = |k: usize| model.joint(chain[k + 1]).expect("joint");
    for (number, link) in [(1usize, chain[1]), (2, chain[2])] {
        let b = &model.bodies()[link];
        if b.mass() != 0.0 || b.inertia_com().norm() != 0.0 {
            return Err(LayoutError::LinkHasMass {
                number,
                next: number + 1,
                body: b.name().to_owned(),
                mass: b.mass(),
                inertia: b.inertia_com().norm(),
            });
        }
        let (incoming, outgoing) = (joint(number - 1), joint(number));
        let scale = 1.0 + incoming.child_at().norm() + outgoing.at().norm();
        if (incoming.child_at() - outgoing.at()).norm() > ZERO_LENGTH_TOLERANCE * scale {
            return Err(LayoutError::LinkLength {
                number,
                body: b.name().to_owned(),
                incoming: model.hinge_names()[number - 1].clone(),
                outgoing: model.hinge_names()[number].clone(),
                distance: (incoming.child_at() - outgoing.at()).norm(),
            });
        }
    }
    const MASSIVE: [(usize, &str); 4] = [
        (0, "the bus"),
        (3, "panel 1"),
        (4, "panel 2"),
        (5, "panel 3"),
    ];
    for (number, (slot, role)) in MASSIVE.into_iter().enumerate() {
        let b = &model.bodies()[chain[slot]];
        if b.mass() <= 0.0 || b.mass().is_nan() {
            return Err(LayoutError::NoMass {
                number: number + 1,
                role,
                body: b.name().to_owned(),
                mass: b.mass(),
            });
        }
    }
    let com = |slot: usize| *model.bodies()[chain[slot]].com();
    let inertia = |slot: usize| *model.bodies()[chain[slot]].inertia_com();
    let params = PreprintParams {
        mass: MASSIVE.map(|(slot, _)| model.bodies()[chain[slot]].mass()),
        inertia: [inertia(0), inertia(3), inertia(4), inertia(5)],
        a1: joint(0).at() - com(0),
        c2: com(3) - joint(2).child_at(),
        a2: joint(3).at() - com(3),
        c3: com(4) - joint(3).child_at(),
        a3: joint(4).at() - com(4),
        c4: com(5) - joint(4).child_at(),
        e: [0, 1, 2, 3, 4].map(|k| *joint(k).axis()),
        rotation: [0, 1, 2, 3, 4].map(|k| {
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(
                *joint(k).rot0(),
            ))
        }),
    };
    Ok(Layout {
        bodies: chain,
        params,
    })
}
