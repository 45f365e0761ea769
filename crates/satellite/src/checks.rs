//! Independent checks of the other formulas the project takes from the preprint: the
//! centre of mass (13), the gravity-gradient torque `M_iG`, the quaternion equation (20) and
//! its `Ω` matrix, and the gravity force approximation `F_i ≈ −μ m_i r_O / r_O³`.
//!
//! Each formula is implemented here as printed (and corrected where wrong); the tests in
//! `tests/it/preprint_formulas.rs` compare them with a brute-force computation.

use super::closed_form::{Symbols, Variant};
use nalgebra::{Matrix4, SymmetricEigen, UnitQuaternion, Vector4};
use satsim_tree::spatial::{Mat3, Vec3, skew};

/// The Earth's gravitational parameter `μ = fM` (m³/s², EGM96/WGS 84).
pub const MU_EARTH: f64 = 3.986_004_418e14;

/// Equation (13): `r_O1 − r_O = −(m2+m3+m4)/m (a1+c2) − (m3+m4)/m (a2+c3) − m4/m (a3+c4)`,
/// the bus centre of mass relative to the system centre of mass, in the frame of the
/// symbols (bus axes).
pub fn bus_offset_eq13(s: &Symbols) -> Vec3 {
    let [_, m2, m3, m4] = s.m;
    let m = s.m_total();
    -(m2 + m3 + m4) / m * (s.a1 + s.c2) - (m3 + m4) / m * (s.a2 + s.c3) - m4 / m * (s.a3 + s.c4)
}

/// The preprint's gravity-gradient torque on a body of inertia `inertia` (about its centre of
/// mass), `M_iG = k (μ / r_O³) E × I_i E` with `E` the unit local vertical (either sense: the
/// expression is even in `E`), all in one frame. Printed: `k = −3`; corrected: `k = +3`
/// (erratum E5), the classical result `3 μ/r³ R̂ × I R̂` (Hughes, *Spacecraft Attitude
/// Dynamics*, §8.2).
pub fn gravity_gradient_torque(
    variant: Variant,
    mu: f64,
    r_o: f64,
    vertical: &Vec3,
    inertia: &Mat3,
) -> Vec3 {
    let k = match variant {
        Variant::Printed => -3.0,
        Variant::Corrected => 3.0,
    };
    let e = vertical.normalize();
    k * mu / r_o.powi(3) * e.cross(&(inertia * e))
}

/// Six point masses with the given total mass, centre of mass at the origin and inertia
/// tensor `inertia` about it (pairs of `m/6` on the principal axes). Needs `mass > 0` and an
/// inertia satisfying the triangle inequality (true of every rigid body).
pub fn point_masses(mass: f64, inertia: &Mat3) -> Vec<(f64, Vec3)> {
    // Second moment P = Σ m ρρᵀ = ½ tr(I) 1 − I.
    let p = Mat3::identity() * (0.5 * inertia.trace()) - inertia;
    let eig = SymmetricEigen::new(p);
    let mut out = Vec::with_capacity(6);
    for k in 0..3 {
        let s = (3.0 * eig.eigenvalues[k].max(0.0) / mass).sqrt();
        let u: Vec3 = eig.eigenvectors.column(k).into_owned();
        out.push((mass / 6.0, u * s));
        out.push((mass / 6.0, -u * s));
    }
    out
}

/// The exact (inverse-square) gravity torque about `centre` (the reference point's position
/// relative to the Earth's centre) of point masses `(m, ρ)` at positions `ρ` RELATIVE to
/// `centre`. Working with `ρ` rather than absolute positions keeps the moment arms exact:
/// adding metre-sized offsets to a 7000 km radius loses nine digits, as much as the
/// gravity-gradient signal itself.
pub fn point_mass_torque(mu: f64, centre: &Vec3, points: &[(f64, Vec3)]) -> Vec3 {
    points
        .iter()
        .map(|(m, rho)| {
            let r = centre + rho;
            // ρ × (−μ m r/|r|³) with ρ × ρ = 0.
            -mu * m / r.norm().powi(3) * rho.cross(centre)
        })
        .sum()
}

/// The gravity torque about the system centre of mass split three ways (inertial axes, N m).
#[derive(Clone, Debug, PartialEq)]
pub struct GravityBudget {
    /// What the preprint keeps: `Σ M_iG = Σ 3μ/r³ E × I_i E` (corrected sign), each body's
    /// own gravity gradient about its own centre of mass.
    pub kept: Vec3,
    /// What `F_i ≈ −μ m_i r_O / r_O³` drops: the moment about the system centre of mass of the
    /// first-order part of the force on each body's centre of mass,
    /// `Σ ρ_i × (−μ m_i/r³)(ρ_i − 3 (E·ρ_i) E) = Σ 3μ m_i/r³ (E·ρ_i) ρ_i × E`, with
    /// `ρ_i = r_Oi − r_O`. It has the same order, `μ/r³ × (kg m²)`, as what is kept.
    pub dropped: Vec3,
    /// Brute force: every body replaced by [`point_masses`], exact inverse-square gravity.
    pub exact: Vec3,
}

/// The [`GravityBudget`] of bodies with masses `m_i`, inertias `inertia_i` (inertial axes,
/// about their centres of mass) and centres of mass `rho_i` relative to the system centre of
/// mass (inertial), at `r_o` (system centre of mass relative to the Earth's centre).
pub fn gravity_budget(mu: f64, r_o: &Vec3, bodies: &[(f64, Mat3, Vec3)]) -> GravityBudget {
    let r = r_o.norm();
    let e = r_o / r;
    let k = 3.0 * mu / r.powi(3);
    let mut kept = Vec3::zeros();
    let mut dropped = Vec3::zeros();
    let mut points = Vec::new();
    for (m, i, rho) in bodies {
        kept += gravity_gradient_torque(Variant::Corrected, mu, r, &e, i);
        dropped += k * m * e.dot(rho) * rho.cross(&e);
        for (mp, p) in point_masses(*m, i) {
            points.push((mp, rho + p));
        }
    }
    GravityBudget {
        kept,
        dropped,
        exact: point_mass_torque(mu, r_o, &points),
    }
}

/// The preprint's `Ω(ω)` of equation (20), `q̇ = ½ Ω q`, as printed:
/// `[[0, ω3, −ω2, ω1], [−ω3, 0, ω1, ω2], [ω2, −ω1, 0, ω3], [−ω1, −ω2, −ω3, 0]]`.
///
/// It is `[[−[ω×], ω], [−ωᵀ, 0]]`: the quaternion is SCALAR-LAST, `q = (q1, q2, q3, q4)` with
/// `q4` the scalar, and (20) is `q̇ = ½ q ⊗ (ω, 0)` in Hamilton's product with `ω` in bus axes.
/// Hence `q` is the Hamilton quaternion of the bus-to-inertial rotation, which is the JPL
/// (Shuster) quaternion of the attitude matrix `A` (inertial to bus coordinates) that the
/// text calls the "rotation from CXYZ to O1x1y1z1". See [`paper_quaternion`].
pub fn omega_matrix(w: &Vec3) -> Matrix4<f64> {
    let (w1, w2, w3) = (w.x, w.y, w.z);
    Matrix4::new(
        0.0, w3, -w2, w1, //
        -w3, 0.0, w1, w2, //
        w2, -w1, 0.0, w3, //
        -w1, -w2, -w3, 0.0,
    )
}

/// The preprint's quaternion `(q1, q2, q3, q4)` of a bus attitude given as nalgebra's
/// `UnitQuaternion` of the bus-to-inertial rotation (the state file's `attitude`
/// `[w, x, y, z]`): it is exactly nalgebra's storage order `coords = [i, j, k, w]`.
pub fn paper_quaternion(attitude: &UnitQuaternion<f64>) -> Vector4<f64> {
    attitude.coords
}

/// The attitude matrix of a scalar-last (JPL, Shuster) quaternion,
/// `A(q) = (q4² − |q_v|²) 1 + 2 q_v q_vᵀ − 2 q4 [q_v×]`: inertial to bus coordinates.
pub fn attitude_matrix(q: &Vector4<f64>) -> Mat3 {
    let v = Vec3::new(q[0], q[1], q[2]);
    let s = q[3];
    Mat3::identity() * (s * s - v.dot(&v)) + 2.0 * v * v.transpose() - 2.0 * s * skew(&v)
}
