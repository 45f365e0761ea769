//! The Moon's position from the Earth's centre, from the truncated ELP-2000/82 series as
//! Meeus prints it (Astronomical Algorithms, 2nd ed., chapter 47: the mean arguments of
//! Chapront-Touzé & Chapront with Simon et al.'s (1994) mean longitude, tables 47.A and 47.B,
//! the additive terms of Venus, Jupiter and the flattening, and the factor E of the Sun's
//! eccentricity). The tables are transcribed from ERFA's `moon98.c` (BSD-3, the same series),
//! whose comparison with ELP/MPP02 over 1950-2100 gives 2.9 arcseconds rms and 18.3 at worst
//! in direction, 6.1 km rms in distance. The series gives the geocentric longitude and
//! latitude on the mean ecliptic and equinox of date; as for the Sun ([`crate::sun`]), the
//! IAU-1976 obliquity takes them to the mean equator of date and the IAU-1976 precession back
//! to the J2000 mean equator and equinox (the GCRF's axes to 0.02 arcsecond).
//!
//! The position is geometric (where the Moon is at `t`; light time, 1.3 s, would move it by
//! 1.3 arcseconds). Against astropy's built-in Moon (ERFA's `moon98`, the same series with the
//! IAU 2006 precession; tests/it/moon.rs) it agrees within 0.29 arcsecond at 24 dates over
//! 1950-2100 (the target is 0.01 degree).

use crate::earth::precession;
use crate::epoch::centuries_tt;
use crate::sun::mean_obliquity;
use crate::{Epoch, Vec3};

/// Meeus table 47.A: multiples of D, M, M', F; Σl coefficient (1e-6 degree), Σr coefficient (m).
const LR: [([i8; 4], f64, f64); 60] = [
    ([0, 0, 1, 0], 6288774.0, -20905355.0),
    ([2, 0, -1, 0], 1274027.0, -3699111.0),
    ([2, 0, 0, 0], 658314.0, -2955968.0),
    ([0, 0, 2, 0], 213618.0, -569925.0),
    ([0, 1, 0, 0], -185116.0, 48888.0),
    ([0, 0, 0, 2], -114332.0, -3149.0),
    ([2, 0, -2, 0], 58793.0, 246158.0),
    ([2, -1, -1, 0], 57066.0, -152138.0),
    ([2, 0, 1, 0], 53322.0, -170733.0),
    ([2, -1, 0, 0], 45758.0, -204586.0),
    ([0, 1, -1, 0], -40923.0, -129620.0),
    ([1, 0, 0, 0], -34720.0, 108743.0),
    ([0, 1, 1, 0], -30383.0, 104755.0),
    ([2, 0, 0, -2], 15327.0, 10321.0),
    ([0, 0, 1, 2], -12528.0, 0.0),
    ([0, 0, 1, -2], 10980.0, 79661.0),
    ([4, 0, -1, 0], 10675.0, -34782.0),
    ([0, 0, 3, 0], 10034.0, -23210.0),
    ([4, 0, -2, 0], 8548.0, -21636.0),
    ([2, 1, -1, 0], -7888.0, 24208.0),
    ([2, 1, 0, 0], -6766.0, 30824.0),
    ([1, 0, -1, 0], -5163.0, -8379.0),
    ([1, 1, 0, 0], 4987.0, -16675.0),
    ([2, -1, 1, 0], 4036.0, -12831.0),
    ([2, 0, 2, 0], 3994.0, -10445.0),
    ([4, 0, 0, 0], 3861.0, -11650.0),
    ([2, 0, -3, 0], 3665.0, 14403.0),
    ([0, 1, -2, 0], -2689.0, -7003.0),
    ([2, 0, -1, 2], -2602.0, 0.0),
    ([2, -1, -2, 0], 2390.0, 10056.0),
    ([1, 0, 1, 0], -2348.0, 6322.0),
    ([2, -2, 0, 0], 2236.0, -9884.0),
    ([0, 1, 2, 0], -2120.0, 5751.0),
    ([0, 2, 0, 0], -2069.0, 0.0),
    ([2, -2, -1, 0], 2048.0, -4950.0),
    ([2, 0, 1, -2], -1773.0, 4130.0),
    ([2, 0, 0, 2], -1595.0, 0.0),
    ([4, -1, -1, 0], 1215.0, -3958.0),
    ([0, 0, 2, 2], -1110.0, 0.0),
    ([3, 0, -1, 0], -892.0, 3258.0),
    ([2, 1, 1, 0], -810.0, 2616.0),
    ([4, -1, -2, 0], 759.0, -1897.0),
    ([0, 2, -1, 0], -713.0, -2117.0),
    ([2, 2, -1, 0], -700.0, 2354.0),
    ([2, 1, -2, 0], 691.0, 0.0),
    ([2, -1, 0, -2], 596.0, 0.0),
    ([4, 0, 1, 0], 549.0, -1423.0),
    ([0, 0, 4, 0], 537.0, -1117.0),
    ([4, -1, 0, 0], 520.0, -1571.0),
    ([1, 0, -2, 0], -487.0, -1739.0),
    ([2, 1, 0, -2], -399.0, 0.0),
    ([0, 0, 2, -2], -381.0, -4421.0),
    ([1, 1, 1, 0], 351.0, 0.0),
    ([3, 0, -2, 0], -340.0, 0.0),
    ([4, 0, -3, 0], 330.0, 0.0),
    ([2, -1, 2, 0], 327.0, 0.0),
    ([0, 2, 1, 0], -323.0, 1165.0),
    ([1, 1, -1, 0], 299.0, 0.0),
    ([2, 0, 3, 0], 294.0, 0.0),
    ([2, 0, -1, -2], 0.0, 8752.0),
];
/// Meeus table 47.B: multiples of D, M, M', F; Σb coefficient (1e-6 degree).
const B: [([i8; 4], f64); 60] = [
    ([0, 0, 0, 1], 5128122.0),
    ([0, 0, 1, 1], 280602.0),
    ([0, 0, 1, -1], 277693.0),
    ([2, 0, 0, -1], 173237.0),
    ([2, 0, -1, 1], 55413.0),
    ([2, 0, -1, -1], 46271.0),
    ([2, 0, 0, 1], 32573.0),
    ([0, 0, 2, 1], 17198.0),
    ([2, 0, 1, -1], 9266.0),
    ([0, 0, 2, -1], 8822.0),
    ([2, -1, 0, -1], 8216.0),
    ([2, 0, -2, -1], 4324.0),
    ([2, 0, 1, 1], 4200.0),
    ([2, 1, 0, -1], -3359.0),
    ([2, -1, -1, 1], 2463.0),
    ([2, -1, 0, 1], 2211.0),
    ([2, -1, -1, -1], 2065.0),
    ([0, 1, -1, -1], -1870.0),
    ([4, 0, -1, -1], 1828.0),
    ([0, 1, 0, 1], -1794.0),
    ([0, 0, 0, 3], -1749.0),
    ([0, 1, -1, 1], -1565.0),
    ([1, 0, 0, 1], -1491.0),
    ([0, 1, 1, 1], -1475.0),
    ([0, 1, 1, -1], -1410.0),
    ([0, 1, 0, -1], -1344.0),
    ([1, 0, 0, -1], -1335.0),
    ([0, 0, 3, 1], 1107.0),
    ([4, 0, 0, -1], 1021.0),
    ([4, 0, -1, 1], 833.0),
    ([0, 0, 1, -3], 777.0),
    ([4, 0, -2, 1], 671.0),
    ([2, 0, 0, -3], 607.0),
    ([2, 0, 2, -1], 596.0),
    ([2, -1, 1, -1], 491.0),
    ([2, 0, -2, 1], -451.0),
    ([0, 0, 3, -1], 439.0),
    ([2, 0, 2, 1], 422.0),
    ([2, 0, -3, -1], 421.0),
    ([2, 1, -1, 1], -366.0),
    ([2, 1, 0, 1], -351.0),
    ([4, 0, 0, 1], 331.0),
    ([2, -1, 1, 1], 315.0),
    ([2, -2, 0, -1], 302.0),
    ([0, 0, 1, 3], -283.0),
    ([2, 1, 1, -1], -229.0),
    ([1, 1, 0, -1], 223.0),
    ([1, 1, 0, 1], 223.0),
    ([0, 1, -2, -1], -220.0),
    ([2, 1, -1, -1], -220.0),
    ([1, 0, 1, 1], -185.0),
    ([2, -1, -2, -1], 181.0),
    ([0, 1, 2, 1], -177.0),
    ([4, 0, -2, -1], 176.0),
    ([4, -1, -1, -1], 166.0),
    ([1, 0, 1, -1], -164.0),
    ([4, 0, 1, -1], 132.0),
    ([1, 0, -1, -1], -119.0),
    ([4, -1, 0, -1], 115.0),
    ([2, -2, 0, 1], 107.0),
];

/// A polynomial in `t` (degrees), coefficients from the constant up.
fn poly(c: &[f64], t: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, k| acc * t + k)
}

/// The Moon's geocentric ecliptic longitude λ and latitude β (rad, mean ecliptic and equinox
/// of date) and its distance Δ (m), at `t` Julian centuries of TT (for TDB) from J2000.0:
/// Meeus' equations 47.1-47.7 and the sums of tables 47.A and 47.B.
///
/// ```
/// // Meeus' example 47.a: 1992 April 12, 0h TD.
/// use satsim_environment::moon::ecliptic_of_date;
/// let t = (2_448_724.5 - 2_451_545.0) / 36_525.0;
/// let (lon, lat, dist) = ecliptic_of_date(t);
/// // Meeus' mean longitude L' (218.3164477° at J2000) includes the light time; this one (Simon
/// // et al.'s 218.31665436°, as ERFA) is geometric: 0.000207° (0.74 arcsecond) ahead.
/// assert!((lon.to_degrees() - 133.162_655 - 0.000_207).abs() < 2e-6);
/// assert!((lat.to_degrees() + 3.229_126).abs() < 2e-6);
/// assert!((dist - 368_409.7e3).abs() < 100.0);
/// ```
pub fn ecliptic_of_date(t: f64) -> (f64, f64, f64) {
    let rad = |deg: f64| deg.rem_euclid(360.0).to_radians();
    // Mean longitude L', elongation D, the Sun's and the Moon's mean anomalies M and M', and
    // the argument of latitude F (eqs. 47.1-47.5, Simon et al. 1994 for L').
    let lp = rad(poly(
        &[
            218.316_654_36,
            481_267.881_234_21,
            -0.001_578_6,
            1.0 / 538_841.0,
            -1.0 / 65_194_000.0,
        ],
        t,
    ));
    let d = rad(poly(
        &[
            297.850_192_1,
            445_267.111_403_4,
            -0.001_881_9,
            1.0 / 545_868.0,
            -1.0 / 113_065_000.0,
        ],
        t,
    ));
    let m = rad(poly(
        &[
            357.529_109_2,
            35_999.050_290_9,
            -0.000_153_6,
            1.0 / 24_490_000.0,
        ],
        t,
    ));
    let mp = rad(poly(
        &[
            134.963_396_4,
            477_198.867_505_5,
            0.008_741_4,
            1.0 / 69_699.0,
            -1.0 / 14_712_000.0,
        ],
        t,
    ));
    let f = rad(poly(
        &[
            93.272_095_0,
            483_202.017_523_3,
            -0.003_653_9,
            -1.0 / 3_526_000.0,
            1.0 / 863_310_000.0,
        ],
        t,
    ));
    let a1 = rad(119.75 + 131.849 * t);
    let a2 = rad(53.09 + 479_264.290 * t);
    let a3 = rad(313.45 + 481_266.484 * t);
    // The decreasing eccentricity of the Earth's orbit (eq. 47.6): terms in M carry E, in 2M E².
    let e = 1.0 + t * (-0.002_516 - 0.000_007_4 * t);
    let e_factor = |k: i8| match k.abs() {
        1 => e,
        2 => e * e,
        _ => 1.0,
    };
    let arg = |k: &[i8; 4]| {
        f64::from(k[0]) * d + f64::from(k[1]) * m + f64::from(k[2]) * mp + f64::from(k[3]) * f
    };
    let (mut sl, mut sr, mut sb) = (0.0, 0.0, 0.0);
    // Smallest terms first.
    for (k, cl, cr) in LR.iter().rev() {
        let (s, c) = arg(k).sin_cos();
        let ef = e_factor(k[1]);
        sl += cl * ef * s;
        sr += cr * ef * c;
    }
    for (k, cb) in B.iter().rev() {
        sb += cb * e_factor(k[1]) * arg(k).sin();
    }
    // The additive terms (Venus: A1, Jupiter: A2, the Earth's flattening: L' − F).
    sl += 3958.0 * a1.sin() + 1962.0 * (lp - f).sin() + 318.0 * a2.sin();
    sb += -2235.0 * lp.sin()
        + 382.0 * a3.sin()
        + 175.0 * (a1 - f).sin()
        + 175.0 * (a1 + f).sin()
        + 127.0 * (lp - mp).sin()
        - 115.0 * (lp + mp).sin();
    (
        lp + (sl * 1e-6).to_radians(),
        (sb * 1e-6).to_radians(),
        385_000_560.0 + sr,
    )
}

/// The Moon's position from the Earth's centre (m), GCRF (J2000 mean equator and equinox),
/// at `epoch + t` seconds.
///
/// ```
/// use satsim_environment::{moon::moon_position, parse_epoch};
/// let r = moon_position(parse_epoch("2026-03-20T12:00:00 UTC").unwrap(), 0.0);
/// // Between perigee and apogee.
/// assert!(r.norm() > 356e6 && r.norm() < 407e6);
/// ```
pub fn moon_position(epoch: Epoch, t: f64) -> Vec3 {
    // TT stands for TDB (they differ by 1.7 ms at most: 1.7 ms of the Moon's motion).
    let t_c = centuries_tt(epoch, t);
    let (lon, lat, dist) = ecliptic_of_date(t_c);
    let ecl = Vec3::new(lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin()) * dist;
    let (se, ce) = mean_obliquity(t_c).sin_cos();
    let eq = Vec3::new(ecl.x, ce * ecl.y - se * ecl.z, se * ecl.y + ce * ecl.z);
    precession(t_c).inverse() * eq
}

/// The Moon's position along a run: [`moon_position`] at the knots `k · STEP` (s after the
/// epoch) and linear between them, as [`crate::sun::SunTrack`] does for the Sun. The series
/// costs a few microseconds; the Moon's geocentric acceleration is at most
/// `μ⊕ / (356 000 km)² ≈ 3.2e-3 m/s²`, so the chord between knots 600 s apart is off by at most
/// `STEP²/8 · 3.2e-3 ≈ 140 m` (0.08 arcsecond at the Moon's distance), far below the series'
/// own accuracy. The knots depend only on `t`: the result does not depend on the order of
/// the calls.
///
/// ```
/// use satsim_environment::{parse_epoch, moon::{MoonTrack, moon_position}};
/// let epoch = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
/// let mut track = MoonTrack::new(epoch);
/// let (a, b) = (track.position(1234.5), moon_position(epoch, 1234.5));
/// assert!((a - b).norm() < 200.0);
/// ```
#[derive(Clone, Debug)]
pub struct MoonTrack(crate::track::Track);

impl MoonTrack {
    /// Seconds between knots.
    pub const STEP: f64 = 600.0;

    /// Along a run that starts at `epoch`.
    pub fn new(epoch: Epoch) -> Self {
        Self(crate::track::Track::new(epoch, Self::STEP, moon_position))
    }

    /// The position (m, GCRF, from the Earth's centre) at `epoch + t`.
    pub fn position(&mut self, t: f64) -> Vec3 {
        self.0.position(t)
    }
}
