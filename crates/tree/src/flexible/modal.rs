//! A flexible body's modal data (floating frame of reference, small deformation, constant
//! modal integrals evaluated undeformed) and the shapes of its modes at a point.

use crate::spatial::{Force, Vec3};

/// The modal integrals of one flexible body, `m` mass-normalised modes, about its frame
/// (body axes, frame origin). With `v` the frame's spatial velocity and `η̇` the modal rates,
/// the body's kinetic energy is `½ vᵀ I v + vᵀ P η̇ + ½ η̇ᵀ η̇` (`I` the rigid [`crate::Body`]
/// inertia of the whole body, deformable part included; `M_ee = 1`), its strain energy
/// `½ Σ ωₖ² ηₖ²`, its modal damping force `2 ζ ωₖ η̇ₖ`.
#[derive(Clone, Debug, PartialEq)]
pub struct ModalData {
    /// `P`, per mode: the spatial momentum `[n; p]` (body frame, about its origin) that
    /// `η̇ₖ = 1` gives the body (kg^½ m, kg^½).
    pub momentum: Vec<Force>,
    /// Natural frequencies `ωₖ` of the modes with the frame held (rad/s), positive.
    pub omega: Vec<f64>,
}

impl ModalData {
    /// Number of modes `m`.
    pub fn modes(&self) -> usize {
        self.omega.len()
    }
}

/// The mode shapes at a point of a flexible body (a child hinge's `at`), per mode `k`: the
/// point's translation `Φₖ` (m/√kg) and the material's small rotation there `Ψₖ` (rad/√kg),
/// body axes. A hinge at that point is carried by them: `η` moves its joint frame by `Φ η`
/// and turns it by `Ψ η`.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct NodeShape {
    /// Translation per mode, body axes.
    pub phi: Vec<Vec3>,
    /// Rotation (a rotation vector per unit `ηₖ`) per mode, body axes.
    pub psi: Vec<Vec3>,
    /// The foreshortening `C` at the point (`m × m`, row-major, 1/kg), where known: a
    /// stiffened structure draws the point in along its axis by `½ ηᵀ C η`, so a load it
    /// carries there along the axis stiffens its bending (a modes file's node `shortening`;
    /// a beam's is [`super::Beam::foreshortening`]).
    pub shortening: Option<Vec<f64>>,
}
