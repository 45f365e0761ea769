//! The rotation chain of the preprint's Table 2: matrices that take coordinates in a hinge
//! or body frame to the bus frame `O1x1y1z1`.
//!
//! The preprint defines `(ξ1,η1,ζ1)ᵀ = B1 (x1,y1,z1)ᵀ`, `(ξi,ηi,ζi)ᵀ = Bi (ξ(i−1),…)ᵀ` for
//! `i = 2, 3`, `(ξi,ηi,ζi)ᵀ = Bi (x(i−2),…)ᵀ` for `i = 4, 5`, and
//! `(xi,yi,zi)ᵀ = Di (ξ(i+1),…)ᵀ` for `i = 2, 3, 4`, but never says how the hinge angles
//! enter `Bi`, `Di`. On the model file's kinematics (child-to-parent rotation
//! `Rot(e_k, φ_k) · rotation_k` for hinge `k`) we take:
//!
//! | preprint frame | model frame | matrix |
//! |---|---|---|
//! | `P1ξ1η1ζ1` | `link1` | `B1ᵀ = Rot(e1, φ1) · rotation1` |
//! | `P2ξ2η2ζ2` | `link2` | `B2ᵀ = Rot(e2, φ2) · rotation2` |
//! | `P3ξ3η3ζ3` | `link2` turned by `φ3` about `e3` | `B3ᵀ = Rot(e3, φ3)`, `D2ᵀ = rotation3` |
//! | `P4ξ4η4ζ4` | `panel1` turned by `φ4` about `e4` | `B4ᵀ = Rot(e4, φ4)`, `D3ᵀ = rotation4` |
//! | `P5ξ5η5ζ5` | `panel2` turned by `φ5` about `e5` | `B5ᵀ = Rot(e5, φ5)`, `D4ᵀ = rotation5` |
//!
//! so that `B_iᵀ` holds the hinge motion and `D_iᵀ` the fixed mounting rotation, and the
//! axis `e_k` has the same coordinates in `P_k` as in the parent body (for `k = 3, 4, 5`),
//! or `rotation_kᵀ e_k` (for `k = 1, 2`, where `P_k` is the link itself).
#![allow(non_snake_case)]

use super::params::PreprintParams;
use super::variant::Variant;
use nalgebra::{Rotation3, Unit};
use satsim_tree::spatial::{Mat3, Vec3};

/// `Rot(axis, angle)`: the rotation by `angle` about the unit `axis` (Rodrigues, computed by
/// nalgebra, independently of the engine).
pub fn rot(axis: &Vec3, angle: f64) -> Mat3 {
    Rotation3::from_axis_angle(&Unit::new_normalize(*axis), angle).into_inner()
}

fn fixed(p: &PreprintParams, k: usize) -> Mat3 {
    p.rotation[k].to_rotation_matrix().into_inner()
}

/// `B1`: bus coordinates to `P1ξ1η1ζ1` (link 1) coordinates.
pub fn B_1(p: &PreprintParams, phi: &[f64; 5]) -> Mat3 {
    (rot(&p.e[0], phi[0]) * fixed(p, 0)).transpose()
}
/// `B2`: `P1` to `P2` (link 2) coordinates.
pub fn B_2(p: &PreprintParams, phi: &[f64; 5]) -> Mat3 {
    (rot(&p.e[1], phi[1]) * fixed(p, 1)).transpose()
}
/// `B3`: `P2` to `P3` coordinates (hinge 3's motion).
pub fn B_3(p: &PreprintParams, phi: &[f64; 5]) -> Mat3 {
    rot(&p.e[2], phi[2]).transpose()
}
/// `B4`: panel-1 (`O2x2y2z2`) to `P4` coordinates (hinge 4's motion).
pub fn B_4(p: &PreprintParams, phi: &[f64; 5]) -> Mat3 {
    rot(&p.e[3], phi[3]).transpose()
}
/// `B5`: panel-2 (`O3x3y3z3`) to `P5` coordinates (hinge 5's motion).
pub fn B_5(p: &PreprintParams, phi: &[f64; 5]) -> Mat3 {
    rot(&p.e[4], phi[4]).transpose()
}
/// `D2`: `P3` to panel-1 (`O2x2y2z2`) coordinates (hinge 3's fixed mounting).
pub fn D_2(p: &PreprintParams) -> Mat3 {
    fixed(p, 2).transpose()
}
/// `D3`: `P4` to panel-2 coordinates.
pub fn D_3(p: &PreprintParams) -> Mat3 {
    fixed(p, 3).transpose()
}
/// `D4`: `P5` to panel-3 coordinates.
pub fn D_4(p: &PreprintParams) -> Mat3 {
    fixed(p, 4).transpose()
}

/// The rows of Table 2: each matrix takes coordinates in the named frame to `O1x1y1z1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Table2 {
    /// `P1ξ1η1ζ1 ⇒ O1`: `B1ᵀ`.
    pub p1: Mat3,
    /// `P2ξ2η2ζ2 ⇒ O1`: `B1ᵀB2ᵀ`.
    pub p2: Mat3,
    /// `P3ξ3η3ζ3 ⇒ O1`: `B1ᵀB2ᵀB3ᵀ`.
    pub p3: Mat3,
    /// `O2x2y2z2 ⇒ O1`: `B1ᵀB2ᵀB3ᵀD2ᵀ`.
    pub o2: Mat3,
    /// `P4ξ4η4ζ4 ⇒ O1`: `B1ᵀB2ᵀB3ᵀD2ᵀB4ᵀ`.
    pub p4: Mat3,
    /// `O3x3y3z3 ⇒ O1`: printed `…B4ᵀB3ᵀ`, corrected `…B4ᵀD3ᵀ` (erratum E4).
    pub o3: Mat3,
    /// `P5ξ5η5ζ5 ⇒ O1`: `…B4ᵀD3ᵀB5ᵀ`.
    pub p5: Mat3,
    /// `O4x4y4z4 ⇒ O1`: `…B4ᵀD3ᵀB5ᵀD4ᵀ`.
    pub o4: Mat3,
}

/// Table 2 at hinge angles `phi`, as printed or corrected. Only the `O3` row differs: the
/// printed `B3ᵀ` in last place should be `D3ᵀ` (the `P5` and `O4` rows already have `D3ᵀ`).
pub fn table2(p: &PreprintParams, phi: &[f64; 5], variant: Variant) -> Table2 {
    let p1 = B_1(p, phi).transpose();
    let p2 = p1 * B_2(p, phi).transpose();
    let p3 = p2 * B_3(p, phi).transpose();
    let o2 = p3 * D_2(p).transpose();
    let p4 = o2 * B_4(p, phi).transpose();
    let o3 = match variant {
        Variant::Printed => p4 * B_3(p, phi).transpose(),
        Variant::Corrected => p4 * D_3(p).transpose(),
    };
    let o3_correct = p4 * D_3(p).transpose();
    let p5 = o3_correct * B_5(p, phi).transpose();
    let o4 = p5 * D_4(p).transpose();
    Table2 {
        p1,
        p2,
        p3,
        o2,
        p4,
        o3,
        p5,
        o4,
    }
}
