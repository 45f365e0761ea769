//! Energy, centre of mass and momentum of the whole tree.

use crate::data::Data;
use crate::error::DynamicsError;
use crate::kinematics::forward_kinematics;
use crate::model::Model;
use crate::spatial::{RigidInertia, Vec3};

/// Kinetic energy `½ Σ vᵢᵀ Iᵢ vᵢ + ½ Σₖ aₖ q̇ₖ²` (J), running [`forward_kinematics`] first:
/// the bodies' energy plus that of the hinges' armatures `aₖ`, so that it is `½ vᵀ M v`
/// with the mass matrix of [`crate::crba()`] (and is conserved with an armature).
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, ModelBuilder, kinetic_energy, spatial::Mat3};
/// let model = ModelBuilder::new(BaseKind::Free).body(Body::new("b", 2.0, Mat3::identity())).build()?;
/// let mut data = Data::new(&model);
/// let t = kinetic_energy(&model, &mut data, &model.neutral(), &[0.0, 0.0, 2.0, 3.0, 0.0, 0.0])?;
/// assert!((t - (0.5 * 4.0 + 0.5 * 2.0 * 9.0)).abs() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn kinetic_energy(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
) -> Result<f64, DynamicsError> {
    forward_kinematics(model, data, q, v)?;
    Ok(kinetic_energy_after_kinematics(model, data, v))
}

/// As [`kinetic_energy`], from the body velocities of the caller's last
/// [`forward_kinematics`] (which must have run with this `v`): for a caller that has just
/// run kinematics, so that they do not run twice. `v` gives the armatures' rates.
///
/// ```
/// use satsim_tree::{forward_kinematics, kinetic_energy, kinetic_energy_after_kinematics};
/// use satsim_tree::{samples::chain, BaseKind, Data};
/// let model = chain(3, BaseKind::Free);
/// let mut data = Data::new(&model);
/// let (q, v) = (model.neutral(), vec![0.3; model.nv()]);
/// let t = kinetic_energy(&model, &mut data, &q, &v)?;
/// forward_kinematics(&model, &mut data, &q, &v)?;
/// assert_eq!(kinetic_energy_after_kinematics(&model, &data, &v), t);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn kinetic_energy_after_kinematics(model: &Model, data: &Data, v: &[f64]) -> f64 {
    let bodies: f64 = (0..model.n_bodies())
        .map(|i| 0.5 * data.v[i].dot(&model.bodies[i].inertia.mul_motion(&data.v[i])))
        .sum();
    bodies + armature_energy(model, v)
}

/// `½ Σₖ aₖ q̇ₖ²`, the hinges' armatures.
fn armature_energy(model: &Model, v: &[f64]) -> f64 {
    model
        .joints
        .iter()
        .flatten()
        .map(|j| 0.5 * j.armature * v[j.dof] * v[j.dof])
        .sum()
}

/// [`kinetic_energy_after_kinematics`] and [`momentum`] in one pass over the bodies, for an
/// output row that wants both: each body's momentum `Iᵢ vᵢ` and rotation are read once, and
/// every sum takes the same terms in the same order as in those functions (a float `sum`
/// starts from −0), so the results are theirs bit for bit. Returns `(kinetic, p, h)`.
///
/// ```
/// use satsim_tree::{energy_and_momentum, forward_kinematics, kinetic_energy_after_kinematics, momentum};
/// use satsim_tree::{samples::chain, BaseKind, Data};
/// let model = chain(3, BaseKind::Free);
/// let mut data = Data::new(&model);
/// let (q, v) = (model.neutral(), vec![0.3; model.nv()]);
/// forward_kinematics(&model, &mut data, &q, &v)?;
/// let (t, p, h) = energy_and_momentum(&model, &data, &v);
/// assert_eq!(t, kinetic_energy_after_kinematics(&model, &data, &v));
/// assert_eq!((p, h), momentum(&model, &data));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn energy_and_momentum(model: &Model, data: &Data, v: &[f64]) -> (f64, Vec3, Vec3) {
    let mut bodies: f64 = -0.0;
    let (mut p, mut h_origin) = (Vec3::zeros(), Vec3::zeros());
    let (mut m, mut mc) = (0.0, Vec3::zeros());
    for (i, b) in model.bodies.iter().enumerate() {
        // A body with neither mass nor inertia (a gimbal's link) adds ±0 to every sum (for
        // finite velocities and poses). The vector sums and the mass start at +0 and so are
        // never −0, and ±0 changes no bit of them; the energy starts at −0 (as `sum` does),
        // which a +0 would change. So such a body is left out once the energy is not −0: a
        // third of the pass for the preprint's layout, whose rows ask for it at every step.
        if b.mass == 0.0 && is_inert(&b.inertia) && bodies.to_bits() != NEG_ZERO {
            continue;
        }
        let f = b.inertia.mul_motion(&data.v[i]);
        bodies += 0.5 * data.v[i].dot(&f);
        let r = &data.rotation[i];
        let lin = r * f.lin;
        p += lin;
        h_origin += r * f.ang + data.position[i].cross(&lin);
        m += b.mass;
        mc += (data.position[i] + r * b.com) * b.mass;
    }
    let c = if m > 0.0 { mc / m } else { data.position[0] };
    (
        bodies + armature_energy(model, v),
        p,
        h_origin - c.cross(&p),
    )
}

/// The bits of −0.0.
const NEG_ZERO: u64 = 0x8000_0000_0000_0000;

/// Whether a spatial inertia is zero in every entry (either sign).
fn is_inert(i: &RigidInertia) -> bool {
    i.mass == 0.0 && i.h.iter().all(|&x| x == 0.0) && i.inertia.iter().all(|&x| x == 0.0)
}

/// The system's centre of mass in inertial coordinates (m), from the poses of the last
/// [`forward_kinematics`]. For a massless model, the root's origin.
pub fn center_of_mass(model: &Model, data: &Data) -> Vec3 {
    let mut m = 0.0;
    let mut mc = Vec3::zeros();
    for (i, b) in model.bodies.iter().enumerate() {
        // A massless body (a gimbal link, a wheel whose mass is the bus's) adds ±0 to sums
        // that start at +0 and so can never be −0: skipping it changes no bit (for finite
        // poses), and spares most of the loop where such bodies are common.
        if b.mass == 0.0 {
            continue;
        }
        m += b.mass;
        mc += (data.position[i] + data.rotation[i] * b.com) * b.mass;
    }
    if m > 0.0 { mc / m } else { data.position[0] }
}

/// Total linear momentum (N s) and angular momentum about the system centre of mass (N m s),
/// both in inertial coordinates, from the last [`forward_kinematics`].
///
/// ```
/// use satsim_tree::{BaseKind, Body, Data, ModelBuilder, forward_kinematics, momentum, spatial::{Mat3, Vec3}};
/// let model = ModelBuilder::new(BaseKind::Free).body(Body::new("b", 2.0, Mat3::identity() * 3.0)).build()?;
/// let mut data = Data::new(&model);
/// forward_kinematics(&model, &mut data, &model.neutral(), &[0.0, 0.0, 2.0, 1.0, 0.0, 0.0])?;
/// let (p, h) = momentum(&model, &data);
/// assert!((p - Vec3::new(2.0, 0.0, 0.0)).norm() < 1e-12 && (h - Vec3::new(0.0, 0.0, 6.0)).norm() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn momentum(model: &Model, data: &Data) -> (Vec3, Vec3) {
    let mut p = Vec3::zeros();
    let mut h_origin = Vec3::zeros();
    for (i, b) in model.bodies.iter().enumerate() {
        let f = b.inertia.mul_motion(&data.v[i]);
        let r = &data.rotation[i];
        let lin = r * f.lin;
        p += lin;
        h_origin += r * f.ang + data.position[i].cross(&lin);
    }
    let c = center_of_mass(model, data);
    (p, h_origin - c.cross(&p))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::BaseKind;
    use crate::samples::{SplitMix, random_tree_with_rotors};
    use crate::spatial::Mat3;

    /// `energy_and_momentum` equals the separate functions bit for bit (and
    /// `center_of_mass`, which skips the bodies without mass or inertia, the sums that do
    /// not): random trees with massless links and rotors, at random states, at rest (every
    /// term ±0) and with only some rates zero or −0.
    #[test]
    fn one_pass_equals_the_separate_functions() {
        let bits = |x: &[f64]| x.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut massless = 0;
        for seed in 0..60u64 {
            let mut rng = SplitMix(seed ^ 0xe4e7);
            let base = if seed % 3 == 0 {
                BaseKind::Fixed
            } else {
                BaseKind::Free
            };
            let model = random_tree_with_rotors(2 + (seed % 9) as usize, base, true, 2, seed);
            massless += model
                .bodies
                .iter()
                .filter(|b| b.mass == 0.0 && b.inertia_com == Mat3::zeros())
                .count();
            let mut data = Data::new(&model);
            let mut q = model.neutral();
            for x in &mut q[model.base_nq()..] {
                *x = rng.range(-3.0, 3.0);
            }
            for case in 0..4 {
                let v: Vec<f64> = (0..model.nv())
                    .map(|k| match case {
                        0 => 0.0,
                        1 => -0.0,
                        2 if k % 2 == 0 => -0.0,
                        _ => rng.range(-2.0, 2.0),
                    })
                    .collect();
                forward_kinematics(&model, &mut data, &q, &v).unwrap();
                let (t, p, h) = energy_and_momentum(&model, &data, &v);
                let (p1, h1) = momentum(&model, &data);
                let t1 = kinetic_energy_after_kinematics(&model, &data, &v);
                let what = format!("seed {seed} case {case}");
                assert_eq!(t.to_bits(), t1.to_bits(), "{what}: {t} {t1}");
                assert_eq!(bits(p.as_slice()), bits(p1.as_slice()), "{what}");
                assert_eq!(bits(h.as_slice()), bits(h1.as_slice()), "{what}");
            }
        }
        assert!(massless > 30, "{massless} massless bodies");
    }

    /// Bodies without mass or inertia, with every rate +0 or −0 in all patterns: a link
    /// after the root, and a lone massless body (no hinge, so no armature term turns a zero
    /// energy to +0). The energy is still −0 when the lone body comes, and
    /// `energy_and_momentum` must take its +0 term as the separate function does (leaving
    /// it out there gives −0: this test fails without that guard).
    #[test]
    fn massless_bodies_keep_the_sign_of_a_zero_energy() {
        use crate::model::{Body, Hinge, ModelBuilder};
        let linked = ModelBuilder::new(BaseKind::Free)
            .body(Body::new("bus", 10.0, Mat3::identity() * 2.0))
            .body(Body::new("link", 0.0, Mat3::zeros()))
            .body(Body::new("panel", 3.0, Mat3::identity()).with_com(Vec3::new(0.0, 1.0, 0.0)))
            .hinge(Hinge::revolute("h1", "bus", "link", Vec3::y()).at(Vec3::new(0.5, 0.0, 0.0)))
            .hinge(Hinge::revolute("h2", "link", "panel", Vec3::x()))
            .build()
            .unwrap();
        let lone = ModelBuilder::new(BaseKind::Free)
            .body(Body::new("point", 0.0, Mat3::zeros()))
            .build()
            .unwrap();
        let bits = |x: &[f64]| x.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for model in [linked, lone] {
            let mut data = Data::new(&model);
            let mut q = model.neutral();
            for (k, x) in q[model.base_nq()..].iter_mut().enumerate() {
                *x = 0.3 - 1.4 * k as f64;
            }
            for pattern in 0..1u32 << model.nv() {
                let v: Vec<f64> = (0..model.nv())
                    .map(|k| if pattern >> k & 1 == 1 { -0.0 } else { 0.0 })
                    .collect();
                forward_kinematics(&model, &mut data, &q, &v).unwrap();
                let (t, p, h) = energy_and_momentum(&model, &data, &v);
                let t1 = kinetic_energy_after_kinematics(&model, &data, &v);
                let (p1, h1) = momentum(&model, &data);
                assert_eq!(t.to_bits(), t1.to_bits(), "rates {v:?}: {t} {t1}");
                assert_eq!(bits(p.as_slice()), bits(p1.as_slice()), "rates {v:?}");
                assert_eq!(bits(h.as_slice()), bits(h1.as_slice()), "rates {v:?}");
            }
        }
    }
}
