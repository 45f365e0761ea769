//! The centred dipole in closed form: the degree-1 potential
//! `V = a (a/r)² (g10 cos θ + (g11 cos φ + h11 sin φ) sin θ) = a³ (m · r) / r³` with
//! `m = (g11, h11, g10)`, whose gradient is `B = −∇V = (a/r)³ (3 (m · r̂) r̂ − m)`.

use super::igrf::A_REF;
use crate::Vec3;

/// The dipole's field (nT, Earth-fixed axes) at the Earth-fixed position `r` (m), for the
/// moment `m = (g11, h11, g10)` (nT).
pub(super) fn field(m: &Vec3, r: &Vec3) -> Vec3 {
    let d = r.norm();
    let u = r / d;
    let scale = (A_REF / d).powi(3);
    (u * (3.0 * m.dot(&u)) - m) * scale
}
