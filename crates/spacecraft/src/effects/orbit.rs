//! The orbit of the system's centre of mass: Keplerian (preprint eq. 17), J2-perturbed
//! (eq. 18 with `F_per` the J2 zonal acceleration), or in the Earth's spherical-harmonic field
//! ([`Orbit::harmonics`]: EGM2008 to a chosen degree and order, evaluated in the Earth-fixed
//! frame at the epoch; a run reads all but its central term and J2 through an Earth-fixed
//! lattice of [`Orbit::lattice_deg`], [`HarmonicLattice`]), optionally with the Sun's and the Moon's point-mass perturbations
//! ([`Orbit::third_bodies`]). States: position `r` and velocity `v`, inertial (GCRF:
//! Earth-centred, Z along the Earth's pole), SI units.
//!
//! The gravity-gradient torque ([`super::gravity_gradient`]) keeps the point-mass field's
//! gradient (`μ/r³` with the orbit's `mu`) whatever the orbit's field: J2's and the
//! harmonics' gradients are about 1e-3 of it, the third bodies' 1e-7 (LEO) to 1e-5 (GEO).
//!
//! The attitude and hinge motion are integrated in the frame that translates with the centre
//! of mass (free-falling, not rotating); the orbit effect carries that frame's motion. To the
//! first order in size/r that the gravity-gradient models keep, the two motions decouple: the
//! tidal forces sum to zero, so the centre of mass follows eq. (17) or (18) exactly.
//!
//! Output: the orbit's radius, position and velocity, and the bus' `roll`, `pitch`, `yaw` (rad)
//! relative to the local orbital frame (LVLH, [`OrbitState::orbital_frame`]: z to nadir,
//! y along the negative orbit normal, x completing the triad, along-track on a circular
//! orbit), sequence z-y'-x'' (yaw, then pitch, then roll).

use super::{Context, Effect, Forces, OrbitState};
use nalgebra::UnitQuaternion;
use satsim_environment::Epoch;
use satsim_environment::gravity::{
    HarmonicField, HarmonicLattice, LATTICE_DEG, MU_MOON, MU_SUN, third_body_acceleration,
};
use satsim_environment::moon::MoonTrack;
use satsim_environment::sun::SunTrack;
use satsim_integrate::SystemError;
use satsim_tree::spatial::Vec3;
use std::sync::Arc;

/// Earth's gravitational parameter μ (m³/s², EGM96/WGS-84).
pub const MU_EARTH: f64 = 3.986004418e14;
/// Earth's equatorial radius R_E (m, WGS-84).
pub const R_EARTH: f64 = 6_378_137.0;
/// Earth's second zonal harmonic J2 (EGM2008, unnormalised).
pub const J2_EARTH: f64 = 1.08262668e-3;

/// Which equation moves the centre of mass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum OrbitModel {
    /// `r'' = −μ r / r³` (eq. 17).
    #[default]
    Kepler,
    /// Eq. (18) with the J2 zonal perturbation.
    J2,
}

/// Classical orbital elements (SI, angles in radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Elements {
    /// Semi-major axis a (m).
    pub a: f64,
    /// Eccentricity e, `0 <= e < 1`.
    pub e: f64,
    /// Inclination i (rad).
    pub i: f64,
    /// Right ascension of the ascending node Ω (rad).
    pub raan: f64,
    /// Argument of periapsis ω (rad).
    pub argp: f64,
    /// True anomaly ν (rad).
    pub nu: f64,
}

impl Elements {
    /// A circular orbit of radius `a`.
    pub fn circular(a: f64, i: f64) -> Self {
        Self {
            a,
            e: 0.0,
            i,
            raan: 0.0,
            argp: 0.0,
            nu: 0.0,
        }
    }
    /// Position and velocity (inertial) for gravitational parameter `mu`.
    ///
    /// ```
    /// use satsim_spacecraft::effects::orbit::{Elements, MU_EARTH};
    /// let (r, v) = Elements::circular(7.0e6, 0.0).to_cartesian(MU_EARTH);
    /// assert!((r.norm() - 7.0e6).abs() < 1e-6);
    /// assert!((v.norm() - (MU_EARTH / 7.0e6).sqrt()).abs() < 1e-9);
    /// ```
    pub fn to_cartesian(&self, mu: f64) -> (Vec3, Vec3) {
        let p = self.a * (1.0 - self.e * self.e);
        let (sn, cn) = self.nu.sin_cos();
        let rad = p / (1.0 + self.e * cn);
        let r_pf = Vec3::new(rad * cn, rad * sn, 0.0);
        let k = (mu / p).sqrt();
        let v_pf = Vec3::new(-k * sn, k * (self.e + cn), 0.0);
        let rot = nalgebra::Rotation3::from_axis_angle(&Vec3::z_axis(), self.raan)
            * nalgebra::Rotation3::from_axis_angle(&Vec3::x_axis(), self.i)
            * nalgebra::Rotation3::from_axis_angle(&Vec3::z_axis(), self.argp);
        (rot * r_pf, rot * v_pf)
    }
}

/// Which third bodies perturb the orbit (point masses, [`third_body_acceleration`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct ThirdBodies {
    /// The Sun ([`MU_SUN`], position from [`SunTrack`]).
    pub sun: bool,
    /// The Moon ([`MU_MOON`], position from [`MoonTrack`]).
    pub moon: bool,
}

impl ThirdBodies {
    /// Whether any is on.
    pub fn any(&self) -> bool {
        self.sun || self.moon
    }
}

/// The Sun's and the Moon's tracks and the harmonics' lattice (caches: knots that depend
/// only on `t` or on the lattice's indices, so two orbits with the same settings compare
/// equal whatever their caches hold).
#[derive(Clone, Debug, Default)]
struct Tracks {
    sun: Option<SunTrack>,
    moon: Option<MoonTrack>,
    /// The lattice and the spacing it was made for.
    harmonics: Option<(f64, HarmonicLattice)>,
}

impl PartialEq for Tracks {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// The orbit effect.
#[derive(Clone, Debug, PartialEq)]
pub struct Orbit {
    /// Kepler or J2 (the Earth's field when [`Orbit::harmonics`] is `None`).
    pub model: OrbitModel,
    /// The Earth's spherical-harmonic field (GM and radius its own), which replaces `model`'s
    /// when set; it needs [`Orbit::epoch`]. Give `mu` the field's GM too (the scene reader
    /// does): the elements' conversion and the gravity-gradient torque use `mu`.
    pub harmonics: Option<Arc<HarmonicField>>,
    /// The spacing (degrees) of the Earth-fixed lattice a run reads [`Orbit::harmonics`]
    /// through, less their central term and J2 ([`HarmonicLattice`]); 0: the series at every
    /// call. Default [`LATTICE_DEG`].
    pub lattice_deg: f64,
    /// The third bodies; any needs [`Orbit::epoch`].
    pub third_bodies: ThirdBodies,
    /// t = 0 of the run: the Earth's orientation and the third bodies' positions.
    pub epoch: Option<Epoch>,
    /// Gravitational parameter (m³/s²).
    pub mu: f64,
    /// Equatorial radius used by J2 (m).
    pub radius: f64,
    /// J2 coefficient.
    pub j2: f64,
    /// Initial position (m, inertial).
    pub r0: Vec3,
    /// Initial velocity (m/s, inertial).
    pub v0: Vec3,
    tracks: Tracks,
}

impl Orbit {
    /// An Earth orbit from an initial position and velocity.
    pub fn new(model: OrbitModel, r0: Vec3, v0: Vec3) -> Self {
        Self {
            model,
            mu: MU_EARTH,
            radius: R_EARTH,
            j2: J2_EARTH,
            r0,
            v0,
            harmonics: None,
            lattice_deg: LATTICE_DEG,
            third_bodies: ThirdBodies::default(),
            epoch: None,
            tracks: Tracks::default(),
        }
    }
    /// An Earth orbit from classical elements.
    pub fn from_elements(model: OrbitModel, el: &Elements) -> Self {
        let (r, v) = el.to_cartesian(MU_EARTH);
        Self::new(model, r, v)
    }
    /// The gravitational acceleration of `model` (Kepler or J2) at `r` (inertial).
    pub fn acceleration(&self, r: &Vec3) -> Vec3 {
        let r2 = r.norm_squared();
        let rn = r2.sqrt();
        let mut a = -self.mu / (r2 * rn) * r;
        if self.model == OrbitModel::J2 {
            let z2 = r.z * r.z / r2;
            let k = -1.5 * self.j2 * self.mu * self.radius * self.radius / (r2 * r2 * rn);
            a += k * Vec3::new(
                r.x * (1.0 - 5.0 * z2),
                r.y * (1.0 - 5.0 * z2),
                r.z * (3.0 - 5.0 * z2),
            );
        }
        a
    }
    /// The Earth's gravitational acceleration (m/s², GCRF) at `r` (GCRF) at time `t`: the
    /// harmonic field's, turned to and from the Earth-fixed frame at `epoch + t`, when
    /// [`Orbit::harmonics`] is set, otherwise [`Orbit::acceleration`]. The series itself,
    /// not its lattice: a run's acceleration ([`Orbit::gravity_on_lattice`]) differs from it
    /// by the lattice's interpolation error (`satsim_environment::gravity`'s page).
    pub fn gravity(&self, t: f64, r: &Vec3) -> Result<Vec3, SystemError> {
        match (&self.harmonics, self.epoch) {
            (None, _) => Ok(self.acceleration(r)),
            (Some(field), Some(epoch)) => Ok(field.acceleration_gcrf(epoch, t, r)),
            (Some(_), None) => Err(SystemError::new(
                "orbit: the harmonic gravity field needs an epoch (the Earth's orientation)",
            )),
        }
    }
    /// The Earth's gravitational acceleration (m/s², GCRF) at `r` (GCRF) at time `t` as a run
    /// sees it: [`Orbit::gravity`], with the harmonics beyond J2 read through the lattice
    /// when [`Orbit::lattice_deg`] is not 0. A function of `(t, r)` alone, whatever the
    /// calls before.
    pub fn gravity_on_lattice(&mut self, t: f64, r: &Vec3) -> Result<Vec3, SystemError> {
        let (Some(field), Some(epoch)) = (&self.harmonics, self.epoch) else {
            return self.gravity(t, r);
        };
        let deg = self.lattice_deg;
        let cache = &mut self.tracks.harmonics;
        // The settings are public: a changed field or spacing is a new lattice.
        if cache
            .as_ref()
            .is_none_or(|(d, l)| *d != deg || !Arc::ptr_eq(l.field(), field))
        {
            *cache = HarmonicLattice::new(field.clone(), deg).map(|l| (deg, l));
        }
        match cache {
            Some((_, l)) => Ok(l.acceleration_gcrf(epoch, t, r)),
            None => self.gravity(t, r),
        }
    }
    /// The third bodies' positions (m, GCRF, from the Earth's centre) at `t`: the Sun's and
    /// the Moon's, each when it is on (`None` when off, or without an epoch).
    pub fn third_body_positions(&mut self, t: f64) -> (Option<Vec3>, Option<Vec3>) {
        let Some(epoch) = self.epoch else {
            return (None, None);
        };
        let tracks = &mut self.tracks;
        let sun = self.third_bodies.sun.then(|| {
            tracks
                .sun
                .get_or_insert_with(|| SunTrack::new(epoch))
                .position(t)
        });
        let moon = self.third_bodies.moon.then(|| {
            tracks
                .moon
                .get_or_insert_with(|| MoonTrack::new(epoch))
                .position(t)
        });
        (sun, moon)
    }
    /// The third bodies' perturbing acceleration (m/s², GCRF) at `r` (GCRF) at `t`: the sum
    /// of [`third_body_acceleration`] over those on (zero when none is).
    pub fn third_body(&mut self, t: f64, r: &Vec3) -> Result<Vec3, SystemError> {
        if !self.third_bodies.any() {
            return Ok(Vec3::zeros());
        }
        if self.epoch.is_none() {
            return Err(SystemError::new(
                "orbit: the third bodies need an epoch (their positions)",
            ));
        }
        let (sun, moon) = self.third_body_positions(t);
        let mut a = Vec3::zeros();
        if let Some(s) = sun {
            a += third_body_acceleration(MU_SUN, &s, r);
        }
        if let Some(m) = moon {
            a += third_body_acceleration(MU_MOON, &m, r);
        }
        Ok(a)
    }
    /// Roll, pitch and yaw (rad) of `attitude` (bus to inertial) relative to the local
    /// orbital frame of the orbit state `own` (see [`Effect::output_columns`]).
    ///
    /// ```
    /// use nalgebra::UnitQuaternion;
    /// use satsim_spacecraft::effects::orbit::{Elements, Orbit, OrbitModel};
    /// let orbit = Orbit::from_elements(OrbitModel::Kepler, &Elements::circular(7.0e6, 0.3));
    /// let own = [orbit.r0.x, orbit.r0.y, orbit.r0.z, orbit.v0.x, orbit.v0.y, orbit.v0.z];
    /// let lvlh = orbit.state(&own).orbital_frame();
    /// let bus = lvlh * UnitQuaternion::from_euler_angles(0.1, -0.2, 0.3);
    /// let (roll, pitch, yaw) = orbit.attitude_in_orbit(bus, &own);
    /// assert!((roll - 0.1).abs() < 1e-12 && (pitch + 0.2).abs() < 1e-12 && (yaw - 0.3).abs() < 1e-12);
    /// ```
    pub fn attitude_in_orbit(&self, attitude: UnitQuaternion<f64>, own: &[f64]) -> (f64, f64, f64) {
        // nalgebra's Euler angles are those of Rz(yaw) Ry(pitch) Rx(roll): z-y'-x''.
        (self.state(own).orbital_frame().inverse() * attitude).euler_angles()
    }
    /// The state of the orbit held in `own` (`[r, v]`).
    pub fn state(&self, own: &[f64]) -> OrbitState {
        OrbitState {
            r: Vec3::new(own[0], own[1], own[2]),
            v: Vec3::new(own[3], own[4], own[5]),
            mu: self.mu,
        }
    }
}

impl Effect for Orbit {
    fn name(&self) -> &str {
        "orbit"
    }
    fn n_states(&self) -> usize {
        6
    }
    fn state_names(&self) -> Vec<String> {
        ["r_x", "r_y", "r_z", "v_x", "v_y", "v_z"]
            .iter()
            .map(|s| format!("orbit_{s}"))
            .collect()
    }
    fn orbit_state(&self, own: &[f64]) -> Option<OrbitState> {
        Some(self.state(own))
    }
    fn initial_state(&self, own: &mut [f64]) {
        own[..3].copy_from_slice(self.r0.as_slice());
        own[3..].copy_from_slice(self.v0.as_slice());
    }
    fn apply(
        &mut self,
        ctx: &Context,
        _forces: &mut Forces,
        own: &[f64],
        own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        let r = Vec3::new(own[0], own[1], own[2]);
        if r.norm().is_nan() || r.norm() == 0.0 {
            return Err(SystemError::new(
                "orbit: the centre of mass reached the Earth's centre",
            ));
        }
        let a = self.gravity_on_lattice(ctx.t, &r)? + self.third_body(ctx.t, &r)?;
        own_dot[..3].copy_from_slice(&own[3..6]);
        own_dot[3..].copy_from_slice(a.as_slice());
        Ok(())
    }
    /// The radius, the position and velocity (the orbit's whole state, so that a run can be
    /// restarted from a row), and the bus' roll, pitch and yaw (rad) relative to the
    /// local orbital frame ([`OrbitState::orbital_frame`]), sequence z-y'-x'': the bus is the
    /// orbital frame turned by yaw about its z, then pitch about the new y, then roll about
    /// the newest x.
    fn output_columns(&self) -> Vec<String> {
        [
            "orbit_radius",
            "orbit_r_x",
            "orbit_r_y",
            "orbit_r_z",
            "orbit_v_x",
            "orbit_v_y",
            "orbit_v_z",
            "roll",
            "pitch",
            "yaw",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect()
    }
    fn output(&self, ctx: &Context, own: &[f64], row: &mut Vec<f64>) {
        row.push(Vec3::new(own[0], own[1], own[2]).norm());
        row.extend_from_slice(&own[..6]);
        let (roll, pitch, yaw) = self.attitude_in_orbit(ctx.attitude, own);
        row.extend_from_slice(&[roll, pitch, yaw]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use satsim_environment::gravity::egm2008;
    use satsim_environment::parse_epoch;

    #[test]
    fn a_run_reads_the_harmonics_on_the_lattice_and_0_degrees_is_the_series() {
        let field = Arc::new(HarmonicField::new(egm2008().unwrap(), 20, 20).unwrap());
        let el = Elements::circular(6_878e3, 51.6f64.to_radians());
        let mut orbit = Orbit::from_elements(OrbitModel::Kepler, &el);
        orbit.harmonics = Some(field);
        orbit.epoch = Some(parse_epoch("2026-03-20T12:00:00 UTC").unwrap());
        let (t, r) = (123.4, orbit.r0);
        let exact = orbit.gravity(t, &r).unwrap();
        let on = orbit.gravity_on_lattice(t, &r).unwrap();
        // Within the lattice's documented 8e-7 m/s², and not the series' bits.
        assert!((on - exact).norm() < 1e-6 && on != exact, "{on} {exact}");
        // A copy with another history reads the same bits.
        let mut other = orbit.clone();
        other.gravity_on_lattice(0.0, &(r * 1.01)).unwrap();
        assert_eq!(other.gravity_on_lattice(t, &r).unwrap(), on);
        // A changed spacing is a new lattice; 0 is the series.
        orbit.lattice_deg = 3.0;
        let coarse = orbit.gravity_on_lattice(t, &r).unwrap();
        assert!(coarse != on && (coarse - exact).norm() < 1e-5);
        orbit.lattice_deg = 0.0;
        assert_eq!(orbit.gravity_on_lattice(t, &r).unwrap(), exact);
    }
}
