//! The Earth's orientation: GCRF to the Earth-fixed frame (ITRF) by the IAU-1976 precession
//! (Lieske et al. 1977: the angles ζ, z, θ) then the Greenwich mean sidereal time (IAU-82,
//! Aoki et al. 1982), with UT1 = UTC.
//!
//! Left out, with their size: nutation (the true pole is within 9.2 arcseconds in obliquity
//! and 17.2 × sin ε ≈ 6.8 arcseconds in longitude of the mean pole: at most about 12
//! arcseconds altogether; its equation of the equinoxes would turn GMST by up to 1.1 s of
//! time, but it turns the equator of date back by the same angle, so the two cancel along the
//! pole); polar motion (about 0.3 arcsecond, 10 m on the ground); UT1 − UTC (under 0.9 s:
//! 13.5 arcseconds of longitude); the frame bias (0.02 arcsecond).

use crate::epoch::{centuries_tt, days_ut1};
use crate::{Epoch, OMEGA_EARTH, Vec3};
use nalgebra::Rotation3;

/// The IAU-1976 precession angles `(ζ, z, θ)` (rad) at `t` Julian centuries of TT from
/// J2000 (Lieske et al. 1977; Vallado eq. 3-88).
fn precession_angles(t: f64) -> (f64, f64, f64) {
    let arcsec = |x: f64| (x / 3600.0).to_radians();
    let zeta = arcsec(t * (2306.2181 + t * (0.30188 + t * 0.017998)));
    let z = arcsec(t * (2306.2181 + t * (1.09468 + t * 0.018203)));
    let theta = arcsec(t * (2004.3109 + t * (-0.42665 - t * 0.041833)));
    (zeta, z, theta)
}

/// `R_z(a) R_y(b) R_z(c)` (active rotations), written out: three `sin_cos` and no
/// quaternion or matrix products (this runs at every right-hand side of a run with the
/// harmonic gravity, the geomagnetic field or a co-rotating atmosphere).
fn zyz(a: f64, b: f64, c: f64) -> Rotation3<f64> {
    let ((sa, ca), (sb, cb), (sc, cc)) = (a.sin_cos(), b.sin_cos(), c.sin_cos());
    Rotation3::from_matrix_unchecked(nalgebra::Matrix3::new(
        ca * cb * cc - sa * sc,
        -ca * cb * sc - sa * cc,
        ca * sb,
        sa * cb * cc + ca * sc,
        -sa * cb * sc + ca * cc,
        sa * sb,
        -sb * cc,
        sb * sc,
        cb,
    ))
}

/// The IAU-1976 precession at `t` Julian centuries of TT from J2000.0: the rotation taking
/// J2000 mean equatorial coordinates to those of the mean equator and equinox of date,
/// `R3(−z) R2(θ) R3(−ζ)` (Lieske et al. 1977; Vallado eq. 3-88) written as active rotations.
pub(crate) fn precession(t: f64) -> Rotation3<f64> {
    let (zeta, z, theta) = precession_angles(t);
    zyz(z, -theta, zeta)
}

/// The Greenwich mean sidereal time (rad, in [0, 2π)) at `d` days of UT1 from J2000, IAU-82
/// in the form Meeus gives (Astronomical Algorithms, eq. 12.4).
pub fn gmst(d: f64) -> f64 {
    let t = d / 36_525.0;
    let deg = 280.460_618_37 + 360.985_647_366_29 * d + t * t * (0.000_387_933 - t / 38_710_000.0);
    deg.rem_euclid(360.0).to_radians()
}

/// The rotation taking GCRF coordinates to Earth-fixed (ITRF) ones at `epoch + t` seconds:
/// `R3(GMST) P` (precession, then the sidereal turn; nutation and polar motion left out: see
/// the module's page).
///
/// ```
/// use satsim_environment::{Vec3, earth::gcrf_to_itrf, parse_epoch};
/// let r = gcrf_to_itrf(parse_epoch("2026-03-20T12:00:00 UTC").unwrap(), 0.0);
/// // The pole stays (nearly) the pole: precession moves it by 0.14 degrees since J2000.
/// assert!((r * Vec3::z()).z > (0.2f64).to_radians().cos());
/// ```
pub fn gcrf_to_itrf(epoch: Epoch, t: f64) -> Rotation3<f64> {
    // R3(GMST) P = R_z(z − GMST) R_y(−θ) R_z(ζ): the sidereal turn folded into the
    // precession's last one.
    let (zeta, z, theta) = precession_angles(centuries_tt(epoch, t));
    zyz(z - gmst(days_ut1(epoch, t)), -theta, zeta)
}

/// The Earth's angular velocity (rad/s) in GCRF axes at `epoch + t`: [`OMEGA_EARTH`] along
/// the (mean) pole of date, `Pᵀ ẑ`.
pub fn earth_rotation_gcrf(epoch: Epoch, t: f64) -> Vec3 {
    let (zeta, _, theta) = precession_angles(centuries_tt(epoch, t));
    let ((st, ct), (sz, cz)) = (theta.sin_cos(), zeta.sin_cos());
    Vec3::new(st * cz, -st * sz, ct) * OMEGA_EARTH
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse_epoch;

    fn about(axis: nalgebra::Unit<Vec3>, angle: f64) -> Rotation3<f64> {
        Rotation3::from_axis_angle(&axis, angle)
    }

    /// The written-out rotations are the products of nalgebra's axis-angle ones: the
    /// precession `R_z(z) R_y(−θ) R_z(ζ)`, the Earth-fixed frame `R_z(−GMST) P` and the pole
    /// of date `Pᵀ ẑ`, over two centuries.
    #[test]
    fn the_written_out_rotations_are_the_axis_angle_products() {
        let epoch = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
        for t in [-3.1e9, -1e8, 0.0, 12_345.6, 4e7, 3.1e9] {
            let c = centuries_tt(epoch, t);
            let (zeta, z, theta) = precession_angles(c);
            let p = about(Vec3::z_axis(), z)
                * about(Vec3::y_axis(), -theta)
                * about(Vec3::z_axis(), zeta);
            assert!((precession(c).matrix() - p.matrix()).amax() < 1e-15, "{t}");
            let r = about(Vec3::z_axis(), -gmst(days_ut1(epoch, t))) * p;
            assert!(
                (gcrf_to_itrf(epoch, t).matrix() - r.matrix()).amax() < 1e-14,
                "{t}"
            );
            let pole = p.inverse() * Vec3::z() * OMEGA_EARTH;
            assert!((earth_rotation_gcrf(epoch, t) - pole).amax() < 1e-20, "{t}");
        }
    }
}
