//! Errors of model construction and of the per-call algorithms, and [`Num`], the form every
//! message prints a number in.

use std::fmt;
use thiserror::Error;

/// A number as a message or an output prints it: as `{}` does (`0.5`, `-3`, `2000`), but in
/// exponent form (`1e300`, `2.5e-12`) from 1e9 up or below 1e-9 in magnitude, where `{}`
/// writes a run of zeros (301 digits for 1e300). Both forms read back to the same `f64`.
///
/// ```
/// use satsim_tree::error::Num;
/// assert_eq!(Num(1e300).to_string(), "1e300");
/// assert_eq!(Num(1e8).to_string(), "100000000");
/// assert_eq!(Num(-2.5e9).to_string(), "-2.5e9");
/// assert_eq!(Num(-2.5e-12).to_string(), "-2.5e-12");
/// assert_eq!(Num(123456.5).to_string(), "123456.5");
/// assert_eq!(Num(1e-9).to_string(), "0.000000001");
/// assert_eq!((Num(0.0).to_string(), Num(f64::INFINITY).to_string()), ("0".into(), "inf".into()));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Num(pub f64);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0.abs();
        if a.is_finite() && a != 0.0 && !(1e-9..1e9).contains(&a) {
            write!(f, "{:e}", self.0)
        } else {
            write!(f, "{}", self.0)
        }
    }
}

/// A count (rows, samples, steps) as a message writes it: whole below 1e15, three
/// significant digits in exponent form above (not the 300 digits of `1e300`).
///
/// ```
/// use satsim_tree::error::Count;
/// assert_eq!(Count(2000000001.0).to_string(), "2000000001");
/// assert_eq!(Count(3e302).to_string(), "3.000e302");
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Count(pub f64);

impl fmt::Display for Count {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0 < 1e15 {
            write!(f, "{:.0}", self.0)
        } else {
            write!(f, "{:.3e}", self.0)
        }
    }
}

/// Why a model could not be built. Each variant names the body or hinge concerned.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ModelError {
    /// The model has no body.
    #[error("the model has no body (the first body listed is the root)")]
    NoBodies,
    /// Two bodies share a name.
    #[error("duplicate body name `{0}`")]
    DuplicateBody(String),
    /// Two hinges share a name.
    #[error("duplicate hinge name `{0}`")]
    DuplicateHinge(String),
    /// A hinge names a body that does not exist.
    #[error("hinge `{hinge}`: unknown {role} body `{body}`")]
    UnknownBody {
        /// The hinge.
        hinge: String,
        /// `parent` or `child`.
        role: &'static str,
        /// The unknown name.
        body: String,
    },
    /// A hinge joins a body to itself.
    #[error("hinge `{0}` joins a body to itself")]
    SelfLoop(String),
    /// The root (first body) is the child of a hinge.
    #[error(
        "hinge `{hinge}` makes the root body `{body}` a child (the first body listed is the root)"
    )]
    RootIsChild {
        /// The hinge.
        hinge: String,
        /// The root body.
        body: String,
    },
    /// A body is the child of two hinges.
    #[error("body `{body}` has two parents (hinges `{first}` and `{second}`)")]
    TwoParents {
        /// The body.
        body: String,
        /// The first hinge naming it as child.
        first: String,
        /// The second hinge naming it as child.
        second: String,
    },
    /// A body other than the root is the child of no hinge (a second root).
    #[error(
        "body `{0}` is the child of no hinge (a second root); only the first body may be the root"
    )]
    NoParent(String),
    /// The hinges form a cycle not connected to the root.
    #[error("the hinges form a cycle through bodies {0:?}")]
    Cycle(Vec<String>),
    /// A number is NaN or infinite.
    #[error("{0}: value is not finite")]
    NonFinite(String),
    /// A negative mass.
    #[error("body `{body}`: mass {} is negative", Num(*mass))]
    NegativeMass {
        /// The body.
        body: String,
        /// The mass given.
        mass: f64,
    },
    /// An inertia tensor that is not symmetric.
    #[error("body `{0}`: inertia is not symmetric")]
    InertiaNotSymmetric(String),
    /// An inertia tensor with a negative principal moment.
    #[error("body `{body}`: inertia is not positive semi-definite (principal moment {moment})")]
    InertiaNotPositive {
        /// The body.
        body: String,
        /// The smallest principal moment.
        moment: f64,
    },
    /// Principal moments that break the triangle inequality (no mass distribution has them).
    #[error("body `{body}`: principal moments {moments:?} break the triangle inequality")]
    InertiaTriangle {
        /// The body.
        body: String,
        /// The principal moments.
        moments: [f64; 3],
    },
    /// A hinge axis whose norm is not 1 (within 1e-6).
    #[error("hinge `{hinge}`: axis norm {norm} is not 1 (within 1e-6)")]
    AxisNorm {
        /// The hinge.
        hinge: String,
        /// The norm given.
        norm: f64,
    },
    /// A hinge rotation quaternion whose norm is not 1 (within 1e-6).
    #[error("hinge `{hinge}`: rotation quaternion norm {norm} is not 1 (within 1e-6)")]
    RotationNorm {
        /// The hinge.
        hinge: String,
        /// The norm given.
        norm: f64,
    },
    /// A negative hinge armature.
    #[error("hinge `{hinge}`: armature {} is negative", Num(*armature))]
    NegativeArmature {
        /// The hinge.
        hinge: String,
        /// The armature given.
        armature: f64,
    },
    /// A body's `shape` box with an edge length that is not positive.
    #[error("body `{body}`: shape box sizes {size:?} must all be positive")]
    ShapeSize {
        /// The body.
        body: String,
        /// The sizes given.
        size: [f64; 3],
    },
    /// A facet whose area is not positive.
    #[error("body `{body}`: facet {index}: area {} must be positive", Num(*area))]
    FacetArea {
        /// The body.
        body: String,
        /// The facet's index in the body's facets.
        index: usize,
        /// The area given.
        area: f64,
    },
    /// A facet whose area is larger than [`MAX_FACET_AREA`](crate::facet::MAX_FACET_AREA).
    #[error(
        "body `{body}`: facet {index}: area {} m² is more than {max:e} m² (a square kilometre): no spacecraft's surface is that large",
        Num(*area)
    )]
    FacetTooLarge {
        /// The body.
        body: String,
        /// The facet's index in the body's facets.
        index: usize,
        /// The area given.
        area: f64,
        /// The largest area (m²): carried, not imported, so that the errors need no facet.
        max: f64,
    },
    /// A facet whose centroid lies farther than
    /// [`MAX_FACET_DISTANCE`](crate::facet::MAX_FACET_DISTANCE) from its body's origin.
    #[error(
        "body `{body}`: facet {index}: its centroid `at` is {} m from the body's origin, more than {max:e} m: no spacecraft is that large (lengths are in metres)",
        Num(*distance)
    )]
    FacetTooFar {
        /// The body.
        body: String,
        /// The facet's index in the body's facets.
        index: usize,
        /// The centroid's distance from the body's origin (m).
        distance: f64,
        /// The farthest distance (m).
        max: f64,
    },
    /// A facet normal whose norm is not 1 (within 1e-6).
    #[error("body `{body}`: facet {index}: normal norm {norm} is not 1 (within 1e-6)")]
    FacetNormal {
        /// The body.
        body: String,
        /// The facet's index in the body's facets.
        index: usize,
        /// The norm given.
        norm: f64,
    },
    /// A facet's reflection fractions outside `[0, 1]` or summing to more than 1.
    #[error(
        "body `{body}`: facet {index}: specular {specular} and diffuse {diffuse} must each lie in [0, 1] and sum to at most 1"
    )]
    FacetOptical {
        /// The body.
        body: String,
        /// The facet's index in the body's facets.
        index: usize,
        /// The specular fraction given.
        specular: f64,
        /// The diffuse fraction given.
        diffuse: f64,
    },
    /// A negative drag coefficient.
    #[error("body `{body}`: facet {index}: drag coefficient {} is negative", Num(*drag))]
    FacetDrag {
        /// The body.
        body: String,
        /// The facet's index in the body's facets.
        index: usize,
        /// The drag coefficient given.
        drag: f64,
    },
    /// Facet edges that are not finite, leave the facet's plane or do not span its area.
    #[error(
        "body `{body}`: facet {index}: edges must lie in the facet's plane with edges[0] × edges[1] = area · normal (an edge direction along the normal has no direction in the plane)"
    )]
    FacetEdges {
        /// The body.
        body: String,
        /// The facet's index in the body's facets.
        index: usize,
    },
    /// A leaf body with zero mass and zero inertia: its hinge acceleration is undetermined.
    #[error(
        "body `{0}` is a leaf with zero mass and zero inertia: its hinge acceleration would be undetermined"
    )]
    MasslessLeaf(String),
}

/// Why a per-call algorithm could not produce a result.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum DynamicsError {
    /// A slice had the wrong length.
    #[error("{what}: expected {expected} entries, got {got}")]
    Dimension {
        /// What the slice is (`q`, `v`, `tau`, `fext`).
        what: &'static str,
        /// The length the model needs.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// The articulated inertia about a hinge axis vanished: the configuration is singular
    /// (for example the gimbal lock of a 3-DOF hinge made of massless links).
    #[error(
        "singular configuration at hinge `{hinge}`{}: articulated inertia about its axis is {pivot:e} (relative {relative:e}); a small hinge armature regularises it",
        gimbal_note(.through)
    )]
    SingularHinge {
        /// The hinge.
        hinge: String,
        /// The hinges below it reached through massless links (a multi-axis hinge in
        /// gimbal lock), empty otherwise.
        through: Vec<String>,
        /// The pivot `D = Sᵀ IA S`.
        pivot: f64,
        /// The pivot relative to the system's inertia scale.
        relative: f64,
    },
    /// The floating base's articulated inertia is not positive definite.
    #[error("singular floating base: its articulated inertia is not positive definite")]
    SingularBase,
    /// The mass matrix is not positive definite (Cholesky failed at a generalised coordinate).
    #[error("mass matrix is not positive definite at coordinate {index} (pivot {pivot:e})")]
    NotPositiveDefinite {
        /// The coordinate.
        index: usize,
        /// The failing pivot.
        pivot: f64,
    },
    /// A non-finite number in the input.
    #[error("{0} contains a non-finite number")]
    NonFinite(&'static str),
    /// A batch of runs in lanes ([`crate::real::F64x`]) reached a data-dependent branch that
    /// not all its lanes take (a pivot test near a singular configuration, a singular base
    /// on some lane): nothing was computed for the batch; solve each lane on its own, which
    /// gives each its own result or error.
    #[error("the lanes of a batch part ways at a pivot test: solve each lane on its own")]
    LanesPart,
}

fn gimbal_note(through: &[String]) -> String {
    if through.is_empty() {
        String::new()
    } else {
        let names: Vec<String> = through.iter().map(|h| format!("`{h}`")).collect();
        format!(
            " (gimbal lock with {} through massless links)",
            names.join(", ")
        )
    }
}
