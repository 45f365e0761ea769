//! [`Guidance`]: the reference attitude, rate and angular acceleration the control points the
//! body at (`[fsw.guidance]`, contract section 16).
//!
//! # Conventions
//!
//! - **Frames.** Inertial is the GCRF of [`satsim_environment`] (Earth-centred; positions in
//!   m, velocities in m/s). The Earth-fixed frame of a target is the ITRF of
//!   [`satsim_environment::earth`].
//! - **Attitude.** A [`Reference`]'s `attitude` is the quaternion body to inertial (it turns a
//!   body-axes vector into inertial axes), of the body as the reference asks it to be: "the
//!   reference's axes" are the body axes the reference asks for.
//! - **Rate and acceleration.** `rate` is the reference frame's angular velocity relative to
//!   inertial, in the reference's axes (rad/s); `acceleration` is the time derivative of those
//!   components (rad/s²). For a frame's own angular velocity that derivative is the same
//!   whether taken in inertial or in the frame's axes, so `acceleration` is also the inertial
//!   `dω/dt` expressed in the reference's axes.
//! - **Time.** `t` (s) counts from the law's `epoch` (the scene's `epoch`): the Sun and the
//!   Earth's rotation are evaluated at `epoch + t`.
//!
//! # The laws
//!
//! - [`Guidance::Inertial`]: a fixed attitude `q_ref` (body to inertial), `ω_ref = 0`,
//!   `ω̇_ref = 0`.
//! - [`Guidance::Nadir`]: the local orbital frame (LVLH) of [`OrbitState::orbital_frame`] — z
//!   towards the Earth's centre, y along the negative orbit normal `−r × v`, x = y × z (along
//!   the velocity on a circular orbit) — times a fixed offset, turning at
//!   [`OrbitState::orbital_rate`] `ω = r × v / r²`: the same frame as
//!   `[effects.attitude_control] target = "orbital"` and the state file's `frame = "orbital"`.
//!   Its acceleration is `dω/dt = −2 ω (r·v)/r²`, exact for two-body motion (`h = r × v` is
//!   then constant); for nadir on a circular orbit `ω_ref = (0, −n, 0)`, `ω̇_ref = 0`.
//! - [`Guidance::Sun`]: body `axis` on the direction from the spacecraft to the Sun,
//!   `s = (S(t) − r)/|S(t) − r|` ([`sun_position`], the geocentric Sun), turned about it so that
//!   body `secondary` lies nearest the orbit normal `n = r × v/|r × v|`.
//! - [`Guidance::Target`]: body `axis` on the direction from the spacecraft to a point fixed
//!   on the rotating Earth (geodetic WGS-84 latitude, longitude and height, [`geodetic_to_itrf`],
//!   taken to GCRF by [`gcrf_to_itrf`]), `secondary` nearest the orbit normal as for the Sun.
//!
//! # The two-vector frame (Sun and target)
//!
//! With the body unit vectors `a = axis` and `b = secondary` and the inertial unit vectors
//! `p` (the primary direction: to the Sun, to the target) and `n` (the orbit normal):
//!
//! ```text
//! body triad      B = [a, b⊥, a × b⊥],  b⊥ = (b − (b·a) a)/|…|
//! inertial triad  E = [p, n⊥, p × n⊥],  n⊥ = (n − (n·p) p)/|…|
//! attitude        R = E Bᵀ   (body to inertial)
//! ```
//!
//! so `R a = p` exactly and `R b = (b·a) p + |b − (b·a) a| n⊥`: `b` lies in the plane of `p`
//! and `n`, on the normal's side, the nearest it can be to `n` with `a` on `p`.
//!
//! Degenerate geometry (no NaN ever):
//!
//! - `secondary` parallel to `axis` (the sine of their angle under [`MIN_SINE`]) is refused
//!   by the constructors [`Guidance::sun`] and [`Guidance::target`] (and by
//!   [`Guidance::reference_at`] for a law built by hand), as are zero or non-finite vectors.
//! - When the primary direction is within `asin(MIN_SINE)` (1e-6 rad) of ±`n` (the Sun along
//!   the orbit normal), or the orbit normal is undefined (`r × v = 0`), the secondary direction
//!   falls back to the spacecraft's velocity (its part perpendicular to `p`: `v ⊥ n`, so it is
//!   well defined exactly when `p` is along `n`), then to the GCRF z axis, then the GCRF x
//!   axis, the first whose part perpendicular to `p` has a norm of at least [`MIN_SINE`]. The
//!   two-vector frame turns fast near that geometry (the secondary direction turns about `p`
//!   at the rate the primary crosses the normal, divided by their angle), and the fall-back is
//!   a jump about `p`: the reference stays finite, and a [`super::slew::Slew`] keeps the
//!   commanded motion within its limits.
//! - A spacecraft at the target (or at the Sun) has no direction to point: an error.
//!
//! # Rates and accelerations of the Sun and target references
//!
//! They are the derivatives of the very attitude the law computes, by finite differences in
//! time. The orbit is carried from `t` to `t + τ` by its two-body Taylor series through the
//! jerk, `r(τ) = r + v τ + a τ²/2 + j τ³/6` (`a = −μ r/|r|³`, `j = da/dt`), the Sun by the
//! quadratic through [`sun_position`] at `t` and `t ± 600 s` (its error in the Sun's velocity
//! is 2e-9 of it), the target by the Earth's spin about the pole of date at the rate of the
//! sidereal time ([`earth_rotation_gcrf`]'s axis, 360.985 647 366 29° per UT1 day: the
//! change of the precession over a second, 1e-12 rad, left out). With
//! `φ(τ) = log(q(0)* ⊗ q(τ))` (the rotation vector from the attitude at `t`, reference axes),
//! `φ̇(0) = ω` and `φ̈(0) = ω̇` exactly (the kinematics `φ̇ = ω + φ × ω/2 + O(φ²)`), and the
//! five-point stencils at `τ = 0, ±h, ±2h`, `h =` [`DIFFERENCE_STEP`] (0.25 s), give
//!
//! ```text
//! ω  ≈ (φ(−2h) − 8 φ(−h) + 8 φ(h) − φ(2h)) / (12 h)        error h⁴ |φ⁽⁵⁾| / 30
//! ω̇  ≈ (−φ(−2h) + 16 φ(−h) + 16 φ(h) − φ(2h)) / (12 h²)    error h⁴ |φ⁽⁶⁾| / 90
//! ```
//!
//! The Taylor series' error (order `τ⁴`) cancels in both stencils to the same order. For a
//! geometry turning at `ν` (rad/s: the orbital rate for the Sun, `v/d` for a target at
//! distance `d` seen at speed `v`) the derivatives scale as `φ⁽ᵏ⁾ ~ k! ν^k`, so the relative
//! error is of order `(h ν)⁴`: 1e-13 at the orbital rate, 1e-7 for a target passing
//! straight overhead 200 km below (ν = 0.04 rad/s). Rounding adds about 1e-15 rad/s to the rate
//! and 1e-14 rad/s² to the acceleration (attitudes good to a few 1e-16 rad over `h`, target
//! positions to 1e-9 m at 500 km).
//!
//! Guidance reads the orbit (position and velocity of the centre of mass): the orbit is not a
//! sensor, so the references are those a flight computer with a perfect on-board orbit would
//! compute.

use super::mekf::log_rotation;
use crate::effects::OrbitState;
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use satsim_environment::earth::{earth_rotation_gcrf, gcrf_to_itrf};
use satsim_environment::sun::sun_position;
use satsim_environment::{Epoch, R_EARTH};

/// The WGS-84 flattening of the Earth's ellipsoid (equatorial radius
/// [`satsim_environment::R_EARTH`]).
pub const WGS84_FLATTENING: f64 = 1.0 / 298.257_223_563;

/// The smallest sine of the angle between two directions that a two-vector frame uses: the
/// body `axis` and `secondary` must be at least this far from parallel, and an inertial
/// secondary direction nearer the primary than this falls back (see the module page).
pub const MIN_SINE: f64 = 1e-6;

/// The time step `h` (s) of the finite differences that give the Sun and target references'
/// rates and accelerations (see the module page).
pub const DIFFERENCE_STEP: f64 = 0.25;

/// Half the span (s) of the three Sun positions the Sun's motion over the differences is
/// fitted to.
const SUN_SPAN: f64 = 600.0;

/// The Earth's rotation rate (rad/s) of the sidereal time of [`satsim_environment::earth`]:
/// 360.985 647 366 29° per day of UT1 (IAU-82; its `T²` term changes this by 2e-11 of it).
fn sidereal_rate() -> f64 {
    360.985_647_366_29_f64.to_radians() / 86_400.0
}

/// A guidance law (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Guidance {
    /// A fixed inertial attitude (body to inertial).
    Inertial(UnitQuaternion<f64>),
    /// The local orbital frame times this offset (body to orbital).
    Nadir(UnitQuaternion<f64>),
    /// Body `axis` on the Sun, `secondary` nearest the orbit normal (built by
    /// [`Guidance::sun`]).
    Sun {
        /// Unit body axis pointed at the Sun.
        axis: Vector3<f64>,
        /// Unit body axis kept nearest the orbit normal (not parallel to `axis`).
        secondary: Vector3<f64>,
        /// The instant `t = 0`.
        epoch: Epoch,
    },
    /// Body `axis` on a point fixed on the rotating Earth, `secondary` nearest the orbit
    /// normal (built by [`Guidance::target`]).
    Target {
        /// The point, Earth-fixed (ITRF) position (m).
        position: Vector3<f64>,
        /// Unit body axis pointed at the point.
        axis: Vector3<f64>,
        /// Unit body axis kept nearest the orbit normal (not parallel to `axis`).
        secondary: Vector3<f64>,
        /// The instant `t = 0`.
        epoch: Epoch,
    },
}

/// A reference: the attitude (body to inertial), the rate (rad/s, in the reference's axes)
/// and the angular acceleration (rad/s², the time derivative of `rate`'s components).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reference {
    /// Attitude, body to inertial.
    pub attitude: UnitQuaternion<f64>,
    /// Angular velocity, the reference's axes (rad/s).
    pub rate: Vector3<f64>,
    /// Angular acceleration, the reference's axes (rad/s²): the time derivative of `rate`.
    pub acceleration: Vector3<f64>,
}

/// The Earth-fixed (ITRF) position (m) of the point at geodetic WGS-84 latitude and longitude
/// (degrees) and height above the ellipsoid (m):
/// `((N + h) cos φ cos λ, (N + h) cos φ sin λ, (N (1 − e²) + h) sin φ)`,
/// `N = a/√(1 − e² sin² φ)`, `e² = f (2 − f)`.
pub fn geodetic_to_itrf(latitude_deg: f64, longitude_deg: f64, altitude_m: f64) -> Vector3<f64> {
    let e2 = WGS84_FLATTENING * (2.0 - WGS84_FLATTENING);
    let (sp, cp) = latitude_deg.to_radians().sin_cos();
    let (sl, cl) = longitude_deg.to_radians().sin_cos();
    let n = R_EARTH / (1.0 - e2 * sp * sp).sqrt();
    Vector3::new(
        (n + altitude_m) * cp * cl,
        (n + altitude_m) * cp * sl,
        (n * (1.0 - e2) + altitude_m) * sp,
    )
}

/// `v` normalised when finite and non-zero.
fn unit(v: &Vector3<f64>) -> Option<Vector3<f64>> {
    let n = v.norm();
    (n.is_finite() && n > 0.0).then(|| v / n)
}

/// The triad `[p, s, p × s]` with `s` the part of the first of `candidates` perpendicular to
/// the unit `p` whose norm (as a unit vector) is at least [`MIN_SINE`].
fn triad(p: &Vector3<f64>, candidates: &[Vector3<f64>]) -> Option<Matrix3<f64>> {
    candidates.iter().find_map(|c| {
        let u = unit(c)?;
        let perp = u - p * p.dot(&u);
        let m = perp.norm();
        (m >= MIN_SINE).then(|| {
            // Twice: the first pass leaves `s · p` of order 1e-16/m.
            let s = perp / m;
            let s = (s - p * p.dot(&s)).normalize();
            Matrix3::from_columns(&[*p, s, p.cross(&s)])
        })
    })
}

/// The body triad `[a, b⊥, a × b⊥]` of a two-vector law, or why there is none.
fn body_triad(axis: &Vector3<f64>, secondary: &Vector3<f64>) -> Result<Matrix3<f64>, String> {
    let a = unit(axis).ok_or("fsw.guidance: `axis` must be a finite, non-zero vector")?;
    unit(secondary).ok_or("fsw.guidance: `secondary` must be a finite, non-zero vector")?;
    triad(&a, &[*secondary]).ok_or_else(|| {
        "fsw.guidance: `secondary` must not be parallel to `axis` (the turn about the axis would be undefined)"
            .to_string()
    })
}

/// The orbit carried `tau` seconds by its two-body Taylor series through the jerk.
fn taylor(o: &OrbitState, tau: f64) -> (Vector3<f64>, Vector3<f64>) {
    if tau == 0.0 {
        return (o.r, o.v);
    }
    let r2 = o.r.norm_squared();
    let r3 = r2 * r2.sqrt();
    let a = -o.mu / r3 * o.r;
    let j = -o.mu / r3 * (o.v - 3.0 * o.r.dot(&o.v) / r2 * o.r);
    (
        o.r + tau * (o.v + tau / 2.0 * (a + tau / 3.0 * j)),
        o.v + tau * (a + tau / 2.0 * j),
    )
}

/// The attitude (body to inertial) of the two-vector frame with the body triad `body`, the
/// primary direction `primary` (inertial, any length) and the orbit `r`, `v`.
fn two_vector(
    body: &Matrix3<f64>,
    primary: &Vector3<f64>,
    r: &Vector3<f64>,
    v: &Vector3<f64>,
    what: &str,
) -> Result<UnitQuaternion<f64>, String> {
    let p = unit(primary).ok_or_else(|| format!("fsw.guidance: no direction to {what}"))?;
    let e = triad(&p, &[r.cross(v), *v, Vector3::z(), Vector3::x()])
        .ok_or_else(|| format!("fsw.guidance: no direction to {what}"))?;
    Ok(UnitQuaternion::from_rotation_matrix(
        &Rotation3::from_matrix_unchecked(e * body.transpose()),
    ))
}

/// The reference whose attitude at `t + τ` is `attitude(τ)`: its rate and acceleration by the
/// five-point differences of the module page.
fn differentiate(
    attitude: impl Fn(f64) -> Result<UnitQuaternion<f64>, String>,
) -> Result<Reference, String> {
    let q0 = attitude(0.0)?;
    let phi = |tau: f64| -> Result<Vector3<f64>, String> {
        Ok(log_rotation(&(q0.inverse() * attitude(tau)?)))
    };
    let h = DIFFERENCE_STEP;
    let (m2, m1, p1, p2) = (phi(-2.0 * h)?, phi(-h)?, phi(h)?, phi(2.0 * h)?);
    let rate = (m2 - p2 + 8.0 * (p1 - m1)) / (12.0 * h);
    let acceleration = (16.0 * (p1 + m1) - (p2 + m2)) / (12.0 * h * h);
    if !(rate.iter().all(|x| x.is_finite()) && acceleration.iter().all(|x| x.is_finite())) {
        return Err("fsw.guidance: the reference's rate is not finite".into());
    }
    Ok(Reference {
        attitude: q0,
        rate,
        acceleration,
    })
}

/// The orbit, checked finite with `r ≠ 0`, or an error naming the mode.
fn orbit_for<'a>(orbit: Option<&'a OrbitState>, mode: &str) -> Result<&'a OrbitState, String> {
    let o = orbit.ok_or_else(|| format!("fsw.guidance mode = \"{mode}\" needs an orbit"))?;
    let finite = o.r.iter().chain(o.v.iter()).all(|x| x.is_finite()) && o.mu.is_finite();
    if !finite || o.r.norm_squared() == 0.0 || !(o.r.norm_squared() * o.r.norm()).is_normal() {
        return Err(format!(
            "fsw.guidance mode = \"{mode}\": the orbit is not finite or is at the Earth's centre"
        ));
    }
    Ok(o)
}

impl Guidance {
    /// The Sun-pointing law: body `axis` on the Sun, body `secondary` nearest the orbit
    /// normal, the Sun at `epoch + t`. Both are normalised; an error when either is zero or
    /// not finite, or when they are parallel (the sine of their angle under [`MIN_SINE`]).
    ///
    /// ```
    /// use nalgebra::Vector3;
    /// use satsim_environment::{parse_epoch, sun::sun_position};
    /// use satsim_spacecraft::effects::OrbitState;
    /// use satsim_spacecraft::fsw::Guidance;
    /// let epoch = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
    /// // Solar panels' normal (body +x) on the Sun, body +z nearest the orbit normal.
    /// let law = Guidance::sun(Vector3::x(), Vector3::z(), epoch).unwrap();
    /// let o = OrbitState { r: Vector3::new(7e6, 0.0, 0.0), v: Vector3::new(0.0, 7.5e3, 0.0), mu: 3.986e14 };
    /// let t = 60.0;
    /// let r = law.reference_at(t, Some(&o)).unwrap();
    /// let s = (sun_position(epoch, t) - o.r).normalize();
    /// assert!((r.attitude * Vector3::x() - s).norm() < 1e-12);
    /// assert!(r.rate.norm() < 1e-6); // the Sun and the orbit normal hardly turn
    /// assert!(Guidance::sun(Vector3::x(), -Vector3::x(), epoch).is_err());
    /// ```
    pub fn sun(axis: Vector3<f64>, secondary: Vector3<f64>, epoch: Epoch) -> Result<Self, String> {
        body_triad(&axis, &secondary)?;
        Ok(Guidance::Sun {
            axis: axis.normalize(),
            secondary: secondary.normalize(),
            epoch,
        })
    }

    /// The target-pointing law: body `axis` on the point at geodetic WGS-84 `latitude_deg`,
    /// `longitude_deg` (degrees) and `altitude_m` (m above the ellipsoid), fixed on the rotating
    /// Earth; body `secondary` nearest the orbit normal; the Earth's rotation at `epoch + t`.
    /// An error for a latitude outside [−90, 90], a longitude or altitude not finite, or
    /// `axis`, `secondary` as for [`Guidance::sun`].
    pub fn target(
        latitude_deg: f64,
        longitude_deg: f64,
        altitude_m: f64,
        axis: Vector3<f64>,
        secondary: Vector3<f64>,
        epoch: Epoch,
    ) -> Result<Self, String> {
        if !(-90.0..=90.0).contains(&latitude_deg) {
            return Err(format!(
                "fsw.guidance: latitude_deg = {latitude_deg} is outside [-90, 90]"
            ));
        }
        if !longitude_deg.is_finite() || !altitude_m.is_finite() {
            return Err("fsw.guidance: longitude_deg and altitude must be finite".into());
        }
        body_triad(&axis, &secondary)?;
        Ok(Guidance::Target {
            position: geodetic_to_itrf(latitude_deg, longitude_deg, altitude_m),
            axis: axis.normalize(),
            secondary: secondary.normalize(),
            epoch,
        })
    }

    /// Whether the law reads the orbit.
    pub fn needs_orbit(&self) -> bool {
        !matches!(self, Guidance::Inertial(_))
    }

    /// The reference where the orbit is `orbit`, for the laws that do not depend on the time
    /// (inertial and nadir: the same as [`Guidance::reference_at`] at any `t`). An error when
    /// the law needs an orbit and there is none, and for the Sun and target laws, which need
    /// the time: use [`Guidance::reference_at`].
    ///
    /// ```
    /// use nalgebra::{UnitQuaternion, Vector3};
    /// use satsim_spacecraft::effects::OrbitState;
    /// use satsim_spacecraft::fsw::Guidance;
    /// let o = OrbitState { r: Vector3::new(7e6, 0.0, 0.0), v: Vector3::new(0.0, 7.5e3, 0.0), mu: 3.986e14 };
    /// let r = Guidance::Nadir(UnitQuaternion::identity()).reference(Some(&o)).unwrap();
    /// assert_eq!(r.attitude, o.orbital_frame());
    /// assert!((r.rate - Vector3::new(0.0, -7.5e3 / 7e6, 0.0)).norm() < 1e-18);
    /// ```
    pub fn reference(&self, orbit: Option<&OrbitState>) -> Result<Reference, String> {
        match self {
            Guidance::Sun { .. } | Guidance::Target { .. } => Err(
                "fsw.guidance: the sun and target laws need the time (Guidance::reference_at)"
                    .into(),
            ),
            _ => self.reference_at(0.0, orbit),
        }
    }

    /// The reference at `t` seconds from the law's epoch, where the orbit is `orbit` (GCRF,
    /// SI): attitude (body to inertial), rate and acceleration in the reference's axes (see
    /// the module page). An error when the law needs an orbit and there is none (or it is not
    /// finite), when a two-vector law's axes are unusable, or when the spacecraft is at the
    /// point it should look at; never a NaN.
    ///
    /// ```
    /// use nalgebra::{UnitQuaternion, Vector3};
    /// use satsim_environment::parse_epoch;
    /// use satsim_spacecraft::effects::OrbitState;
    /// use satsim_spacecraft::fsw::Guidance;
    /// let o = OrbitState { r: Vector3::new(7e6, 0.0, 0.0), v: Vector3::new(0.0, 7.5e3, 1e3), mu: 3.986e14 };
    /// let nadir = Guidance::Nadir(UnitQuaternion::identity()).reference_at(0.0, Some(&o)).unwrap();
    /// // Moving away from the Earth (r·v = 0 here): the frame does not speed up or slow down.
    /// assert_eq!(nadir.acceleration, Vector3::zeros());
    /// let epoch = parse_epoch("2026-06-01T00:00:00 UTC").unwrap();
    /// // Body +z at the point below the equator at 0° longitude, body +x nearest the normal.
    /// let law = Guidance::target(0.0, 0.0, 0.0, Vector3::z(), Vector3::x(), epoch).unwrap();
    /// let r = law.reference_at(120.0, Some(&o)).unwrap();
    /// assert!(r.rate.norm() < 0.1);
    /// ```
    pub fn reference_at(&self, t: f64, orbit: Option<&OrbitState>) -> Result<Reference, String> {
        match self {
            Guidance::Inertial(q) => Ok(Reference {
                attitude: *q,
                rate: Vector3::zeros(),
                acceleration: Vector3::zeros(),
            }),
            Guidance::Nadir(offset) => {
                let o = orbit.ok_or("fsw.guidance mode = \"nadir\" needs an orbit")?;
                let lvlh = o.orbital_frame();
                let attitude = if *offset == UnitQuaternion::identity() {
                    lvlh
                } else {
                    lvlh * offset
                };
                let omega = o.orbital_rate();
                let omega_dot = -2.0 * o.r.dot(&o.v) / o.r.norm_squared() * omega;
                Ok(Reference {
                    attitude,
                    rate: attitude.inverse_transform_vector(&omega),
                    acceleration: attitude.inverse_transform_vector(&omega_dot),
                })
            }
            Guidance::Sun {
                axis,
                secondary,
                epoch,
            } => {
                let o = orbit_for(orbit, "sun")?;
                let body = body_triad(axis, secondary)?;
                let s0 = sun_position(*epoch, t);
                let (sm, sp) = (
                    sun_position(*epoch, t - SUN_SPAN),
                    sun_position(*epoch, t + SUN_SPAN),
                );
                let s1 = (sp - sm) / (2.0 * SUN_SPAN);
                let s2 = (sp - 2.0 * s0 + sm) / (SUN_SPAN * SUN_SPAN);
                differentiate(|tau| {
                    let (r, v) = taylor(o, tau);
                    let sun = if tau == 0.0 {
                        s0
                    } else {
                        s0 + tau * (s1 + tau / 2.0 * s2)
                    };
                    two_vector(&body, &(sun - r), &r, &v, "the Sun")
                })
            }
            Guidance::Target {
                position,
                axis,
                secondary,
                epoch,
            } => {
                let o = orbit_for(orbit, "target")?;
                let body = body_triad(axis, secondary)?;
                if !position.iter().all(|x| x.is_finite()) {
                    return Err("fsw.guidance: the target's position is not finite".into());
                }
                let p0 = gcrf_to_itrf(*epoch, t).inverse() * position;
                let spin = earth_rotation_gcrf(*epoch, t).normalize() * sidereal_rate();
                differentiate(|tau| {
                    let (r, v) = taylor(o, tau);
                    let p = if tau == 0.0 {
                        p0
                    } else {
                        Rotation3::from_scaled_axis(spin * tau) * p0
                    };
                    two_vector(&body, &(p - r), &r, &v, "the target")
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use satsim_environment::{MU_EARTH, parse_epoch};

    fn epoch() -> Epoch {
        parse_epoch("2026-05-17T06:30:00 UTC").unwrap()
    }

    /// Angle (rad) between two attitudes.
    fn angle(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>) -> f64 {
        log_rotation(&(a.inverse() * b)).norm()
    }

    /// An inclined eccentric orbit at its state `t` seconds after perigee-ish start.
    fn eccentric() -> OrbitState {
        // Perigee 6878 km, apogee ~ 9000 km, inclined 51.6°, not at an apsis.
        let rp = 6.878e6;
        let e = 0.13;
        let a = rp / (1.0 - e);
        let nu: f64 = 0.7; // true anomaly (rad)
        let p = a * (1.0 - e * e);
        let rn = p / (1.0 + e * nu.cos());
        let (s, c) = nu.sin_cos();
        let r_pf = Vector3::new(rn * c, rn * s, 0.0);
        let k = (MU_EARTH / p).sqrt();
        let v_pf = Vector3::new(-k * s, k * (e + c), 0.0);
        let rot = Rotation3::from_axis_angle(&Vector3::z_axis(), 0.4)
            * Rotation3::from_axis_angle(&Vector3::x_axis(), 51.6f64.to_radians())
            * Rotation3::from_axis_angle(&Vector3::z_axis(), 1.1);
        OrbitState {
            r: rot * r_pf,
            v: rot * v_pf,
            mu: MU_EARTH,
        }
    }

    /// Two-body motion carried `t` seconds by RK4 at 1/64 s steps (error far under 1e-12 of it).
    fn propagate(o: &OrbitState, t: f64) -> OrbitState {
        let f = |r: &Vector3<f64>| -o.mu * r / r.norm().powi(3);
        let n = (t.abs() * 64.0).ceil().max(1.0) as usize;
        let h = t / n as f64;
        let (mut r, mut v) = (o.r, o.v);
        for _ in 0..n {
            let (k1r, k1v) = (v, f(&r));
            let (k2r, k2v) = (v + h / 2.0 * k1v, f(&(r + h / 2.0 * k1r)));
            let (k3r, k3v) = (v + h / 2.0 * k2v, f(&(r + h / 2.0 * k2r)));
            let (k4r, k4v) = (v + h * k3v, f(&(r + h * k3r)));
            r += h / 6.0 * (k1r + 2.0 * k2r + 2.0 * k3r + k4r);
            v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        }
        OrbitState { r, v, mu: o.mu }
    }

    /// The rate and acceleration of `law` by central differences of its attitude at `t ± d`,
    /// `t ± 2d` along the propagated orbit (independent of the law's own differences).
    fn numeric(law: &Guidance, o: &OrbitState, t: f64, d: f64) -> (Vector3<f64>, Vector3<f64>) {
        let q0 = law.reference_at(t, Some(o)).unwrap().attitude;
        let phi = |k: f64| {
            let q = law
                .reference_at(t + k * d, Some(&propagate(o, k * d)))
                .unwrap()
                .attitude;
            log_rotation(&(q0.inverse() * q))
        };
        let (m2, m1, p1, p2) = (phi(-2.0), phi(-1.0), phi(1.0), phi(2.0));
        (
            (m2 - p2 + 8.0 * (p1 - m1)) / (12.0 * d),
            (16.0 * (p1 + m1) - (p2 + m2)) / (12.0 * d * d),
        )
    }

    #[test]
    fn nadir_is_the_orbital_frame_and_its_acceleration_the_rates_derivative() {
        let o = eccentric();
        let law = Guidance::Nadir(UnitQuaternion::identity());
        let r = law.reference_at(123.0, Some(&o)).unwrap();
        assert!(angle(&r.attitude, &o.orbital_frame()) < 1e-12);
        // The rate: the frame's angular velocity in its own axes.
        let w = r.attitude.inverse_transform_vector(&o.orbital_rate());
        assert!((r.rate - w).norm() < 1e-18);
        assert_eq!(r, law.reference(Some(&o)).unwrap());
        // The acceleration: the derivative of the rate's components along the orbit.
        let d = 2.0;
        let rate_at = |t: f64| law.reference_at(0.0, Some(&propagate(&o, t))).unwrap().rate;
        let fd =
            (rate_at(-2.0 * d) - rate_at(2.0 * d) + 8.0 * (rate_at(d) - rate_at(-d))) / (12.0 * d);
        assert!(
            r.acceleration.norm() > 1e-8,
            "eccentric: {}",
            r.acceleration
        );
        assert!(
            (fd - r.acceleration).norm() < 1e-8 * r.acceleration.norm(),
            "{fd} vs {}",
            r.acceleration
        );
        // With an offset, the same angular velocity in the offset axes.
        let offset = UnitQuaternion::from_euler_angles(0.3, -0.2, 1.0);
        let ro = Guidance::Nadir(offset).reference_at(5.0, Some(&o)).unwrap();
        assert!(angle(&ro.attitude, &(o.orbital_frame() * offset)) < 1e-12);
        assert!((ro.rate - offset.inverse_transform_vector(&r.rate)).norm() < 1e-18);
        assert!(
            (ro.acceleration - offset.inverse_transform_vector(&r.acceleration)).norm() < 1e-20
        );
        // Inertial: still, and needs no orbit.
        let q = UnitQuaternion::from_euler_angles(0.1, 0.2, 0.3);
        let ri = Guidance::Inertial(q).reference_at(7.0, None).unwrap();
        assert_eq!(
            (ri.attitude, ri.rate, ri.acceleration),
            (q, Vector3::zeros(), Vector3::zeros())
        );
        assert!(law.reference_at(0.0, None).is_err());
    }

    #[test]
    fn sun_reference_points_the_axis_and_keeps_the_secondary_by_the_normal() {
        let o = eccentric();
        let (axis, secondary) = (Vector3::new(1.0, 1.0, 0.0), Vector3::new(0.2, -0.1, 1.0));
        let law = Guidance::sun(axis * 3.0, secondary, epoch()).unwrap();
        let t = 4000.0;
        let r = law.reference_at(t, Some(&o)).unwrap();
        let s = (sun_position(epoch(), t) - o.r).normalize();
        assert!((r.attitude * axis.normalize() - s).norm() < 1e-12);
        let n = o.r.cross(&o.v).normalize();
        let b = r.attitude * secondary.normalize();
        // In the plane of the Sun and the normal, on the normal's side of the Sun's line.
        assert!(b.dot(&s.cross(&n).normalize()).abs() < 1e-12);
        let n_perp = (n - s * s.dot(&n)).normalize();
        assert!(b.dot(&n_perp) > 0.1);
        // Nearest: turning about the Sun line by ±1e-3 rad moves b away from n.
        for d in [-1e-3, 1e-3] {
            let turned = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(s), d) * b;
            assert!(turned.dot(&n) < b.dot(&n));
        }
        // Rate and acceleration: the derivatives of the attitude along the orbit.
        let (w, wd) = numeric(&law, &o, t, 20.0);
        assert!(r.rate.norm() > 1e-8 && r.acceleration.norm() > 1e-12);
        assert!(
            (w - r.rate).norm() < 1e-7 * r.rate.norm(),
            "{w} vs {}",
            r.rate
        );
        assert!(
            (wd - r.acceleration).norm() < 5e-4 * r.acceleration.norm(),
            "{wd} vs {}",
            r.acceleration
        );
        // The constructors refuse unusable axes.
        for (a, b) in [
            (Vector3::x(), Vector3::x() * -2.0),
            (Vector3::zeros(), Vector3::y()),
            (Vector3::x(), Vector3::new(f64::NAN, 0.0, 1.0)),
            (Vector3::x(), Vector3::new(1.0, 1e-8, 0.0)),
        ] {
            assert!(Guidance::sun(a, b, epoch()).is_err());
            assert!(Guidance::target(0.0, 0.0, 0.0, a, b, epoch()).is_err());
        }
        assert!(Guidance::target(91.0, 0.0, 0.0, Vector3::x(), Vector3::y(), epoch()).is_err());
        assert!(law.reference_at(t, None).is_err());
        assert!(law.reference(Some(&o)).is_err());
    }

    /// Geodetic latitude, longitude (degrees) and height (m) of an ITRF position, by the
    /// fixed-point iteration on the latitude (converged to machine precision).
    fn itrf_to_geodetic(p: &Vector3<f64>) -> (f64, f64, f64) {
        let f = WGS84_FLATTENING;
        let e2 = f * (2.0 - f);
        let rho = p.x.hypot(p.y);
        let mut lat = p.z.atan2(rho * (1.0 - e2));
        let mut h = 0.0;
        for _ in 0..50 {
            let n = R_EARTH / (1.0 - e2 * lat.sin().powi(2)).sqrt();
            h = rho / lat.cos() - n;
            lat = p.z.atan2(rho * (1.0 - e2 * n / (n + h)));
        }
        (lat.to_degrees(), p.y.atan2(p.x).to_degrees(), h)
    }

    #[test]
    fn target_reference_points_the_axis_at_the_point() {
        let o = eccentric();
        let (lat, lon, alt) = (48.85, 2.35, 35.0);
        let (axis, secondary) = (Vector3::z(), Vector3::x());
        let law = Guidance::target(lat, lon, alt, axis, secondary, epoch()).unwrap();
        for t in [0.0, 1234.5, 86_400.0 * 3.3] {
            let r = law.reference_at(t, Some(&o)).unwrap();
            // The point, independently: on the ellipsoid's normal at (lat, lon), `alt` above.
            let (b, e2) = (
                R_EARTH * (1.0 - WGS84_FLATTENING),
                WGS84_FLATTENING * (2.0 - WGS84_FLATTENING),
            );
            let (phi, lam) = (lat.to_radians(), lon.to_radians());
            let up = Vector3::new(phi.cos() * lam.cos(), phi.cos() * lam.sin(), phi.sin());
            // The surface point where the normal is `up`: (a² up_xy, b² up_z)/√(a² up_xy² + b² up_z²).
            let a2 = R_EARTH * R_EARTH;
            let k = (a2 * (up.x * up.x + up.y * up.y) + b * b * up.z * up.z).sqrt();
            let surface = Vector3::new(a2 * up.x / k, a2 * up.y / k, b * b * up.z / k);
            let itrf = surface + alt * up;
            assert!(
                (itrf - geodetic_to_itrf(lat, lon, alt)).norm() < 1e-6,
                "{e2}"
            );
            let gcrf = gcrf_to_itrf(epoch(), t).transpose() * itrf;
            let d = (gcrf - o.r).normalize();
            let pointed = r.attitude * axis;
            assert!(pointed.cross(&d).norm() < 1e-9 && pointed.dot(&d) > 0.0);
        }
        // Rate and acceleration: the derivatives of the attitude (Earth's rotation by the
        // rotation matrices at each instant, orbit propagated) agree.
        let t = 1234.5;
        let r = law.reference_at(t, Some(&o)).unwrap();
        let (w, wd) = numeric(&law, &o, t, 10.0);
        assert!(
            (w - r.rate).norm() < 1e-7 * r.rate.norm(),
            "{w} vs {}",
            r.rate
        );
        assert!(
            (wd - r.acceleration).norm() < 2e-6 * r.acceleration.norm(),
            "{wd} vs {}",
            r.acceleration
        );
    }

    #[test]
    fn target_below_gives_nadir_pointing() {
        let o = eccentric();
        let t = 777.0;
        let to_itrf = gcrf_to_itrf(epoch(), t);
        let r_itrf = to_itrf * o.r;
        // The point where the radius meets the ellipsoid: straight below, geocentrically.
        let b = R_EARTH * (1.0 - WGS84_FLATTENING);
        let u = r_itrf.normalize();
        let lambda =
            1.0 / ((u.x * u.x + u.y * u.y) / (R_EARTH * R_EARTH) + u.z * u.z / (b * b)).sqrt();
        let (lat, lon, h) = itrf_to_geodetic(&(u * lambda));
        assert!(h.abs() < 1e-6);
        // Body +z at it, body −y nearest the orbit normal: the LVLH frame itself.
        let law = Guidance::target(lat, lon, h, Vector3::z(), -Vector3::y(), epoch()).unwrap();
        let r = law.reference_at(t, Some(&o)).unwrap();
        assert!(angle(&r.attitude, &o.orbital_frame()) < 1e-9);
        assert!(
            r.rate
                .iter()
                .chain(r.acceleration.iter())
                .all(|x| x.is_finite())
        );
        // The geodetic sub-satellite point: along the ellipsoid's normal, within 0.2° of nadir.
        let (lat, lon, _) = itrf_to_geodetic(&r_itrf);
        let law = Guidance::target(lat, lon, 0.0, Vector3::z(), -Vector3::y(), epoch()).unwrap();
        let r = law.reference_at(t, Some(&o)).unwrap();
        let normal_down = -(to_itrf.transpose()
            * Vector3::new(
                lat.to_radians().cos() * lon.to_radians().cos(),
                lat.to_radians().cos() * lon.to_radians().sin(),
                lat.to_radians().sin(),
            ));
        assert!((r.attitude * Vector3::z() - normal_down).norm() < 1e-9);
        assert!(angle(&r.attitude, &o.orbital_frame()) < 0.2f64.to_radians());
        // A spacecraft at the target: an error, not a NaN.
        let at = OrbitState {
            r: to_itrf.transpose() * geodetic_to_itrf(lat, lon, 0.0),
            ..o
        };
        assert!(law.reference_at(t, Some(&at)).is_err());
    }

    #[test]
    fn degenerate_geometry_gives_no_nan() {
        let t = 100.0;
        let sun = sun_position(epoch(), t);
        // An orbit whose normal is exactly along ±(the direction to the Sun): r · (S − r) = 0.
        let s_hat = sun.normalize();
        let e1 = s_hat.cross(&Vector3::z()).normalize();
        let rn = 7e6;
        let r =
            e1 * (rn * (1.0 - (rn / sun.norm()).powi(2)).sqrt()) + s_hat * (rn * rn / sun.norm());
        assert!(r.dot(&(sun - r)).abs() < 1e-3 * rn);
        let law = Guidance::sun(Vector3::x(), Vector3::y(), epoch()).unwrap();
        for sign in [1.0, -1.0] {
            for tilt in [0.0, 1e-8, 1e-5] {
                let v_dir = r.cross(&(sun - r)).normalize() * sign;
                let v = (v_dir + tilt * s_hat).normalize() * 7.5e3;
                let o = OrbitState { r, v, mu: MU_EARTH };
                let rf = law.reference_at(t, Some(&o)).unwrap();
                let all = rf
                    .attitude
                    .coords
                    .iter()
                    .chain(rf.rate.iter())
                    .chain(rf.acceleration.iter());
                assert!(all.clone().all(|x| x.is_finite()), "{rf:?}");
                let s = (sun - r).normalize();
                let miss = (rf.attitude * Vector3::x() - s).norm();
                assert!(miss < 1e-12, "{sign} {tilt}: {miss}");
                // The secondary stays perpendicular to the Sun line (the fall-back or the
                // normal's part), on the side of what it follows.
                assert!((rf.attitude * Vector3::y()).dot(&s).abs() < 1e-12);
            }
        }
        // At exact degeneracy the secondary follows the velocity.
        let o = OrbitState {
            r,
            v: r.cross(&(sun - r)).normalize() * 7.5e3,
            mu: MU_EARTH,
        };
        let rf = law.reference_at(t, Some(&o)).unwrap();
        assert!((rf.attitude * Vector3::y() - o.v.normalize()).norm() < 1e-9);
        // A radial trajectory (no orbit normal) and a still one.
        for v in [o.r * 1e-3, Vector3::zeros()] {
            let o = OrbitState { r, v, mu: MU_EARTH };
            let rf = law.reference_at(t, Some(&o)).unwrap();
            assert!(rf.rate.iter().all(|x| x.is_finite()));
        }
        // A target straight below and a target along the orbit normal (high above the ground).
        let o = eccentric();
        let itrf = gcrf_to_itrf(epoch(), t) * o.r;
        let (lat, lon, h) = itrf_to_geodetic(&itrf);
        for alt in [0.0, h * 0.5] {
            let law = Guidance::target(lat, lon, alt, Vector3::z(), Vector3::x(), epoch()).unwrap();
            let rf = law.reference_at(t, Some(&o)).unwrap();
            assert!(
                rf.rate
                    .iter()
                    .chain(rf.acceleration.iter())
                    .all(|x| x.is_finite())
            );
        }
        let n = o.r.cross(&o.v).normalize();
        let above = gcrf_to_itrf(epoch(), t) * (o.r + n * 1e5);
        let (lat, lon, h) = itrf_to_geodetic(&above);
        let law = Guidance::target(lat, lon, h, Vector3::z(), Vector3::x(), epoch()).unwrap();
        let rf = law.reference_at(t, Some(&o)).unwrap();
        assert!(
            rf.rate
                .iter()
                .chain(rf.acceleration.iter())
                .all(|x| x.is_finite())
        );
        assert!((rf.attitude * Vector3::z() - n).norm() < 1e-6);
        // An orbit that is not finite: an error.
        let bad = OrbitState {
            r: Vector3::new(f64::NAN, 0.0, 0.0),
            ..o
        };
        assert!(law.reference_at(t, Some(&bad)).is_err());
        let bad = OrbitState {
            r: Vector3::zeros(),
            ..o
        };
        assert!(law.reference_at(t, Some(&bad)).is_err());
    }
}
