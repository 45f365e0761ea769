//! The preprint's parameters as a typed struct, a realistic default, and the builder that
//! turns them into a [`satsim_tree::Model`].
//!
//! Notation (preprint §1, Fig. 2): body 1 is the satellite bus (SB) with centre of mass `O1`,
//! bodies 2, 3, 4 the three solar-array (SA) parts with centres of mass `O2, O3, O4`. Hinges
//! `P1, P2, P3` (axes `e1, e2, e3`) form the 3-DOF root hinge, joined by massless rods of zero
//! length (`P1 = P2 = P3`); `P4` (axis `e4`) joins parts 1 and 2 of the array, `P5` (axis `e5`)
//! parts 2 and 3. `a1 = O1P1, c2 = P3O2, a2 = O2P4, c3 = P4O3, a3 = O3P5, c4 = P5O4`.

use nalgebra::{Quaternion, UnitQuaternion};
use satsim_tree::spatial::{Mat3, Vec3};
use satsim_tree::{BaseKind, Body, Hinge, Model, ModelBuilder, ModelError};

/// Body names used by [`build_model`], in the model's body order: bus, the two gimbal links,
/// the three panels.
pub const BODY_NAMES: [&str; 6] = ["bus", "link1", "link2", "panel1", "panel2", "panel3"];
/// Hinge names used by [`build_model`]: the preprint's hinges `P1..P5`, in file order.
pub const HINGE_NAMES: [&str; 5] = ["h1", "h2", "h3", "h4", "h5"];

/// The preprint's parameters, each vector in the frame in which Table 1 of the preprint gives
/// it (that is, fixed in a body), SI units throughout.
///
/// Frames: `bus` is `O1x1y1z1`, `panel1..3` are `O2x2y2z2 .. O4x4y4z4`, all with origins at
/// the centres of mass; `link1`, `link2` are the hinge frames `P1ξ1η1ζ1`, `P2ξ2η2ζ2`.
#[derive(Clone, Debug, PartialEq)]
pub struct PreprintParams {
    /// `m1..m4`: masses of the bus and of panels 1 to 3 (kg), each `> 0`.
    pub mass: [f64; 4],
    /// `I1..I4`: inertia tensors about each body's own centre of mass, in its own axes
    /// (kg m²).
    pub inertia: [Mat3; 4],
    /// `a1 = O1P1`: from the bus centre of mass to the gimbal point, bus axes (m).
    pub a1: Vec3,
    /// `c2 = P3O2`: from the gimbal point to panel 1's centre of mass, panel-1 axes (m).
    pub c2: Vec3,
    /// `a2 = O2P4`: from panel 1's centre of mass to hinge 4, panel-1 axes (m).
    pub a2: Vec3,
    /// `c3 = P4O3`: from hinge 4 to panel 2's centre of mass, panel-2 axes (m).
    pub c3: Vec3,
    /// `a3 = O3P5`: from panel 2's centre of mass to hinge 5, panel-2 axes (m).
    pub a3: Vec3,
    /// `c4 = P5O4`: from hinge 5 to panel 3's centre of mass, panel-3 axes (m).
    pub c4: Vec3,
    /// `e1..e5`: unit hinge axes, each in its PARENT body's axes (bus, link 1, link 2,
    /// panel 1, panel 2), which is how the model file gives `axis` (dimensionless).
    pub e: [Vec3; 5],
    /// Fixed rotation of each hinge's child frame relative to its parent frame at zero angle
    /// (maps child coordinates to parent coordinates; the model file's `rotation`). These are
    /// the constant parts of the preprint's `B_i` and `D_i` (see [`crate::table2`](mod@crate::table2)).
    pub rotation: [UnitQuaternion<f64>; 5],
}

/// A uniform rectangular plate's inertia about its centre (kg m²): sides `x`, `y`, thickness
/// `z` (m).
pub fn plate_inertia(mass: f64, x: f64, y: f64, z: f64) -> Mat3 {
    Mat3::from_diagonal(&Vec3::new(
        mass * (y * y + z * z) / 12.0,
        mass * (x * x + z * z) / 12.0,
        mass * (x * x + y * y) / 12.0,
    ))
}

impl Default for PreprintParams {
    /// The realistic satellite of the project's example model
    /// (`shared/spec/examples/satellite.toml`, also `examples/` of the repository): an 800 kg
    /// bus with principal moments 900, 800, 600 kg m² (a uniform box of about
    /// 1.94 x 2.29 x 2.87 m), and three 20 kg panels, each a uniform 2.0 m (x) by 1.0 m (y)
    /// by 0.02 m (z) plate ([`plate_inertia`]), hinged edge to edge along y. The gimbal point
    /// is 1 m from the bus centre of mass along y; panel 1's centre of mass is 0.6 m beyond it;
    /// the panel hinges sit on the panels' edges (0.5 m from their centres). The gimbal axes
    /// are z (e1), x (e2), y (e3); the panel fold axes are x (e4, e5). These proportions (a bus
    /// of about a tonne, a 60 kg, 6 m² three-part array folding accordion-wise) are those of
    /// a small Earth-observation satellite; the preprint itself prints no numbers.
    fn default() -> Self {
        let panel = plate_inertia(20.0, 2.0, 1.0, 0.02);
        Self {
            mass: [800.0, 20.0, 20.0, 20.0],
            inertia: [
                Mat3::from_diagonal(&Vec3::new(900.0, 800.0, 600.0)),
                panel,
                panel,
                panel,
            ],
            a1: Vec3::new(0.0, 1.0, 0.0),
            c2: Vec3::new(0.0, 0.6, 0.0),
            a2: Vec3::new(0.0, 0.5, 0.0),
            c3: Vec3::new(0.0, 0.5, 0.0),
            a3: Vec3::new(0.0, 0.5, 0.0),
            c4: Vec3::new(0.0, 0.5, 0.0),
            e: [Vec3::z(), Vec3::x(), Vec3::y(), Vec3::x(), Vec3::x()],
            rotation: [UnitQuaternion::identity(); 5],
        }
    }
}

/// Named deployment states of the realistic satellite's array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Deployment {
    /// Panels folded accordion-wise on top of each other (`φ4 = π, φ5 = −π`).
    Stowed,
    /// Panels at right angles (`φ4 = π/2, φ5 = −π/2`).
    HalfDeployed,
    /// Panels in a straight line (all angles zero).
    Deployed,
}

impl Deployment {
    /// All three states.
    pub const ALL: [Deployment; 3] = [
        Deployment::Stowed,
        Deployment::HalfDeployed,
        Deployment::Deployed,
    ];
    /// Hinge angles `φ1..φ5` (rad) of this state for the default parameters.
    pub fn angles(self) -> [f64; 5] {
        use std::f64::consts::{FRAC_PI_2, PI};
        match self {
            Deployment::Stowed => [0.0, 0.0, 0.0, PI, -PI],
            Deployment::HalfDeployed => [0.0, 0.0, 0.0, FRAC_PI_2, -FRAC_PI_2],
            Deployment::Deployed => [0.0; 5],
        }
    }
}

/// Builds the preprint's layout on the tree engine: a free-floating `bus`, hinges `h1`
/// (bus to `link1`), `h2` (`link1` to `link2`), `h3` (`link2` to `panel1`), `h4` (`panel1`
/// to `panel2`), `h5` (`panel2` to `panel3`), in that file order. Every body frame sits at
/// its body's centre of mass; the links are massless, inertia-free and of zero length.
///
/// ```
/// use satsim_satellite::{build_model, PreprintParams};
/// let model = build_model(&PreprintParams::default())?;
/// assert_eq!((model.n_bodies(), model.nv()), (6, 11));
/// # Ok::<(), satsim_tree::ModelError>(())
/// ```
pub fn build_model(p: &PreprintParams) -> Result<Model, ModelError> {
    let q = |k: usize| -> Quaternion<f64> { *p.rotation[k].quaternion() };
    ModelBuilder::new(BaseKind::Free)
        .body(Body::new(BODY_NAMES[0], p.mass[0], p.inertia[0]))
        .body(Body::massless(BODY_NAMES[1]))
        .body(Body::massless(BODY_NAMES[2]))
        .body(Body::new(BODY_NAMES[3], p.mass[1], p.inertia[1]))
        .body(Body::new(BODY_NAMES[4], p.mass[2], p.inertia[2]))
        .body(Body::new(BODY_NAMES[5], p.mass[3], p.inertia[3]))
        .hinge(
            Hinge::revolute(HINGE_NAMES[0], BODY_NAMES[0], BODY_NAMES[1], p.e[0])
                .at(p.a1)
                .rotation(q(0)),
        )
        .hinge(Hinge::revolute(HINGE_NAMES[1], BODY_NAMES[1], BODY_NAMES[2], p.e[1]).rotation(q(1)))
        .hinge(
            Hinge::revolute(HINGE_NAMES[2], BODY_NAMES[2], BODY_NAMES[3], p.e[2])
                .child_at(-p.c2)
                .rotation(q(2)),
        )
        .hinge(
            Hinge::revolute(HINGE_NAMES[3], BODY_NAMES[3], BODY_NAMES[4], p.e[3])
                .at(p.a2)
                .child_at(-p.c3)
                .rotation(q(3)),
        )
        .hinge(
            Hinge::revolute(HINGE_NAMES[4], BODY_NAMES[4], BODY_NAMES[5], p.e[4])
                .at(p.a3)
                .child_at(-p.c4)
                .rotation(q(4)),
        )
        .build()
}
