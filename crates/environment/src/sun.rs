//! The Sun's position from the Earth's centre, from the truncated VSOP87 series of the Earth
//! (VSOP87D: heliocentric ecliptic longitude, latitude and radius referred to the mean
//! ecliptic and equinox of date), as Meeus prints it (Astronomical Algorithms, 2nd ed.,
//! chapter 32 and Appendix III; the phases 3.142 and 3.14 are his rounded π's, kept as
//! printed). Against ERFA's epv00 ephemeris over 1900-2100 (tests/it/sun.rs) the truncation is
//! good to 0.5 arcsecond and 2e-6 in distance. The date's mean equator follows from the
//! IAU-1976 obliquity, then the IAU-1976 precession (the same as [`crate::earth`]'s) takes it
//! back to the J2000 mean equator and equinox, the GCRF's axes to 0.02 arcsecond (the frame
//! bias).
//!
//! The position is geometric (where the Sun is at `t`), not apparent: light time (8.3 min)
//! would move it by 20.5 arcseconds along the ecliptic. The FK5 correction (0.09 arcsecond)
//! is left out.

use crate::earth::precession;
use crate::epoch::centuries_tt;
use crate::{AU, Epoch, Vec3};

/// A series term `A cos(B + C τ)`: A in 1e-8 (rad or AU), B rad, C rad per Julian millennium.
type Term = (f64, f64, f64);

/// Longitude (rad ×1e-8), the τ⁰ series; L1…L5 multiply τ…τ⁵.
const L0: [Term; 64] = [
    (175347046.0, 0.0, 0.0),
    (3341656.0, 4.6692568, 6283.07585),
    (34894.0, 4.6261, 12566.1517),
    (3497.0, 2.7441, 5753.3849),
    (3418.0, 2.8289, 3.5231),
    (3136.0, 3.6277, 77713.7715),
    (2676.0, 4.4181, 7860.4194),
    (2343.0, 6.1352, 3930.2097),
    (1324.0, 0.7425, 11506.7698),
    (1273.0, 2.0371, 529.691),
    (1199.0, 1.1096, 1577.3435),
    (990.0, 5.233, 5884.927),
    (902.0, 2.045, 26.298),
    (857.0, 3.508, 398.149),
    (780.0, 1.179, 5223.694),
    (753.0, 2.533, 5507.553),
    (505.0, 4.583, 18849.228),
    (492.0, 4.205, 775.523),
    (357.0, 2.92, 0.067),
    (317.0, 5.849, 11790.629),
    (284.0, 1.899, 796.298),
    (271.0, 0.315, 10977.079),
    (243.0, 0.345, 5486.778),
    (206.0, 4.806, 2544.314),
    (205.0, 1.869, 5573.143),
    (202.0, 2.458, 6069.777),
    (156.0, 0.833, 213.299),
    (132.0, 3.411, 2942.463),
    (126.0, 1.083, 20.775),
    (115.0, 0.645, 0.98),
    (103.0, 0.636, 4694.003),
    (102.0, 0.976, 15720.839),
    (102.0, 4.267, 7.114),
    (99.0, 6.21, 2146.17),
    (98.0, 0.68, 155.42),
    (86.0, 5.98, 161000.69),
    (85.0, 1.3, 6275.96),
    (85.0, 3.67, 71430.7),
    (80.0, 1.81, 17260.15),
    (79.0, 3.04, 12036.46),
    (75.0, 1.76, 5088.63),
    (74.0, 3.5, 3154.69),
    (74.0, 4.68, 801.82),
    (70.0, 0.83, 9437.76),
    (62.0, 3.98, 8827.39),
    (61.0, 1.82, 7084.9),
    (57.0, 2.78, 6286.6),
    (56.0, 4.39, 14143.5),
    (56.0, 3.47, 6279.55),
    (52.0, 0.19, 12139.55),
    (52.0, 1.33, 1748.02),
    (51.0, 0.28, 5856.48),
    (49.0, 0.49, 1194.45),
    (41.0, 5.37, 8429.24),
    (41.0, 2.4, 19651.05),
    (39.0, 6.17, 10447.39),
    (37.0, 6.04, 10213.29),
    (37.0, 2.57, 1059.38),
    (36.0, 1.71, 2352.87),
    (36.0, 1.78, 6812.77),
    (33.0, 0.59, 17789.85),
    (30.0, 0.44, 83996.85),
    (30.0, 2.74, 1349.87),
    (25.0, 3.16, 4690.48),
];
const L1: [Term; 34] = [
    (628331966747.0, 0.0, 0.0),
    (206059.0, 2.678235, 6283.07585),
    (4303.0, 2.6351, 12566.1517),
    (425.0, 1.59, 3.523),
    (119.0, 5.796, 26.298),
    (109.0, 2.966, 1577.344),
    (93.0, 2.59, 18849.23),
    (72.0, 1.14, 529.69),
    (68.0, 1.87, 398.15),
    (67.0, 4.41, 5507.55),
    (59.0, 2.89, 5223.69),
    (56.0, 2.17, 155.42),
    (45.0, 0.4, 796.3),
    (36.0, 0.47, 775.52),
    (29.0, 2.65, 7.11),
    (21.0, 5.34, 0.98),
    (19.0, 1.85, 5486.78),
    (19.0, 4.97, 213.3),
    (17.0, 2.99, 6275.96),
    (16.0, 0.03, 2544.31),
    (16.0, 1.43, 2146.17),
    (15.0, 1.21, 10977.08),
    (12.0, 2.83, 1748.02),
    (12.0, 3.26, 5088.63),
    (12.0, 5.27, 1194.45),
    (12.0, 2.08, 4694.0),
    (11.0, 0.77, 553.57),
    (10.0, 1.3, 6286.6),
    (10.0, 4.24, 1349.87),
    (9.0, 2.7, 242.73),
    (9.0, 5.64, 951.72),
    (8.0, 5.3, 2352.87),
    (6.0, 2.65, 9437.76),
    (6.0, 4.67, 4690.48),
];
const L2: [Term; 20] = [
    (52919.0, 0.0, 0.0),
    (8720.0, 1.0721, 6283.0758),
    (309.0, 0.867, 12566.152),
    (27.0, 0.05, 3.52),
    (16.0, 5.19, 26.3),
    (16.0, 3.68, 155.42),
    (10.0, 0.76, 18849.23),
    (9.0, 2.06, 77713.77),
    (7.0, 0.83, 775.52),
    (5.0, 4.66, 1577.34),
    (4.0, 1.03, 7.11),
    (4.0, 3.44, 5573.14),
    (3.0, 5.14, 796.3),
    (3.0, 6.05, 5507.55),
    (3.0, 1.19, 242.73),
    (3.0, 6.12, 529.69),
    (3.0, 0.31, 398.15),
    (3.0, 2.28, 553.57),
    (2.0, 4.38, 5223.69),
    (2.0, 3.75, 0.98),
];
const L3: [Term; 7] = [
    (289.0, 5.844, 6283.076),
    (35.0, 0.0, 0.0),
    (17.0, 5.49, 12566.15),
    (3.0, 5.2, 155.42),
    (1.0, 4.72, 3.52),
    (1.0, 5.3, 18849.23),
    (1.0, 5.97, 242.73),
];
#[allow(clippy::approx_constant)]
const L4: [Term; 3] = [
    (114.0, 3.142, 0.0),
    (8.0, 4.13, 6283.08),
    (1.0, 3.84, 12566.15),
];
#[allow(clippy::approx_constant)]
const L5: [Term; 1] = [(1.0, 3.14, 0.0)];
/// Latitude (rad ×1e-8), τ⁰ and τ¹.
const B0: [Term; 5] = [
    (280.0, 3.199, 84334.662),
    (102.0, 5.422, 5507.553),
    (80.0, 3.88, 5223.69),
    (44.0, 3.7, 2352.87),
    (32.0, 4.0, 1577.34),
];
const B1: [Term; 2] = [(9.0, 3.9, 5507.55), (6.0, 1.73, 5223.69)];
/// Radius (AU ×1e-8), τ⁰ to τ⁴.
const R0: [Term; 40] = [
    (100013989.0, 0.0, 0.0),
    (1670700.0, 3.0984635, 6283.07585),
    (13956.0, 3.05525, 12566.1517),
    (3084.0, 5.1985, 77713.7715),
    (1628.0, 1.1739, 5753.3849),
    (1576.0, 2.8469, 7860.4194),
    (925.0, 5.453, 11506.77),
    (542.0, 4.564, 3930.21),
    (472.0, 3.661, 5884.927),
    (346.0, 0.964, 5507.553),
    (329.0, 5.9, 5223.694),
    (307.0, 0.299, 5573.143),
    (243.0, 4.273, 11790.629),
    (212.0, 5.847, 1577.344),
    (186.0, 5.022, 10977.079),
    (175.0, 3.012, 18849.228),
    (110.0, 5.055, 5486.778),
    (98.0, 0.89, 6069.78),
    (86.0, 5.69, 15720.84),
    (86.0, 1.27, 161000.69),
    (65.0, 0.27, 17260.15),
    (63.0, 0.92, 529.69),
    (57.0, 2.01, 83996.85),
    (56.0, 5.24, 71430.7),
    (49.0, 3.25, 2544.31),
    (47.0, 2.58, 775.52),
    (45.0, 5.54, 9437.76),
    (43.0, 6.01, 6275.96),
    (39.0, 5.36, 4694.0),
    (38.0, 2.39, 8827.39),
    (37.0, 0.83, 19651.05),
    (37.0, 4.9, 12139.55),
    (36.0, 1.67, 12036.46),
    (35.0, 1.84, 2942.46),
    (33.0, 0.24, 7084.9),
    (32.0, 0.18, 5088.63),
    (32.0, 1.78, 398.15),
    (28.0, 1.21, 6286.6),
    (28.0, 1.9, 6279.55),
    (26.0, 4.59, 10447.39),
];
#[allow(clippy::approx_constant)]
const R1: [Term; 10] = [
    (103019.0, 1.10749, 6283.07585),
    (1721.0, 1.0644, 12566.1517),
    (702.0, 3.142, 0.0),
    (32.0, 1.02, 18849.23),
    (31.0, 2.84, 5507.55),
    (25.0, 1.32, 5223.69),
    (18.0, 1.42, 1577.34),
    (10.0, 5.91, 10977.08),
    (9.0, 1.42, 6275.96),
    (9.0, 0.27, 5486.78),
];
#[allow(clippy::approx_constant)]
const R2: [Term; 6] = [
    (4359.0, 5.7846, 6283.0758),
    (124.0, 5.579, 12566.152),
    (12.0, 3.14, 0.0),
    (9.0, 3.63, 77713.77),
    (6.0, 1.87, 5573.14),
    (3.0, 5.47, 18849.23),
];
const R3: [Term; 2] = [(145.0, 4.273, 6283.076), (7.0, 3.92, 12566.15)];
const R4: [Term; 1] = [(4.0, 2.56, 6283.08)];

/// `Σ A cos(B + C τ)` over a series' terms.
fn sum(terms: &[Term], tau: f64) -> f64 {
    terms.iter().map(|(a, b, c)| a * (b + c * tau).cos()).sum()
}

/// `(S0 + S1 τ + S2 τ² + …) × 1e-8`: a VSOP87 variable from its series in powers of τ.
fn vsop(series: &[&[Term]], tau: f64) -> f64 {
    series
        .iter()
        .rev()
        .fold(0.0, |acc, s| acc * tau + sum(s, tau))
        * 1e-8
}

/// The IAU-1976 mean obliquity of the ecliptic (rad) at `t` Julian centuries of TT from J2000
/// (Lieske et al. 1977).
pub(crate) fn mean_obliquity(t: f64) -> f64 {
    let arcsec = 84_381.448 + t * (-46.815 + t * (-0.00059 + t * 0.001813));
    (arcsec / 3600.0).to_radians()
}

/// The Sun's position from the Earth's centre (m), GCRF (J2000 mean equator and equinox), at
/// `epoch + t` seconds.
///
/// ```
/// use satsim_environment::{AU, parse_epoch, sun::sun_position};
/// let r = sun_position(parse_epoch("2026-01-03T12:00:00 UTC").unwrap(), 0.0);
/// // Early January: near perihelion, 0.983 AU.
/// assert!((r.norm() / AU - 0.9833).abs() < 1e-3);
/// ```
pub fn sun_position(epoch: Epoch, t: f64) -> Vec3 {
    // TT stands for TDB (they differ by 1.7 ms at most).
    let t_c = centuries_tt(epoch, t);
    let tau = t_c / 10.0;
    let l = vsop(&[&L0, &L1, &L2, &L3, &L4, &L5], tau);
    let b = vsop(&[&B0, &B1], tau);
    let r = vsop(&[&R0, &R1, &R2, &R3, &R4], tau) * AU;
    // The Sun seen from the Earth: opposite the Earth seen from the Sun.
    let (lon, lat) = (l + std::f64::consts::PI, -b);
    let ecl = Vec3::new(lat.cos() * lon.cos(), lat.cos() * lon.sin(), lat.sin()) * r;
    // Ecliptic of date to equator of date: about x by the obliquity.
    let (se, ce) = mean_obliquity(t_c).sin_cos();
    let eq = Vec3::new(ecl.x, ce * ecl.y - se * ecl.z, se * ecl.y + ce * ecl.z);
    // Mean of date back to J2000.
    precession(t_c).inverse() * eq
}

/// The Sun's position along a run: [`sun_position`] at the knots `k · STEP` (s after the
/// epoch) and linear between them. The series costs about 3 µs, and a right-hand side asks
/// for the Sun several times per step; the Sun's geocentric direction turns by 2e-7 rad/s with
/// an acceleration of 4e-14 rad/s², so the chord between knots 600 s apart is off by at most
/// `STEP²/8 · 4e-14 ≈ 2e-9` of the distance (4e-4″), a thousandth of the series' own
/// accuracy. The knots depend only on `t`, so the result does not depend on the order of the
/// calls (a campaign's runs, a restarted step, the environment report all see the same Sun).
///
/// ```
/// use satsim_environment::{parse_epoch, sun::{SunTrack, sun_position}};
/// let epoch = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
/// let mut track = SunTrack::new(epoch);
/// let (a, b) = (track.position(1234.5), sun_position(epoch, 1234.5));
/// assert!((a - b).norm() < 1e-8 * b.norm());
/// ```
#[derive(Clone, Debug)]
pub struct SunTrack(crate::track::Track);

impl SunTrack {
    /// Seconds between knots.
    pub const STEP: f64 = 600.0;

    /// Along a run that starts at `epoch`.
    pub fn new(epoch: Epoch) -> Self {
        Self(crate::track::Track::new(epoch, Self::STEP, sun_position))
    }

    /// The position (m, GCRF, from the Earth's centre) at `epoch + t`.
    pub fn position(&mut self, t: f64) -> Vec3 {
        self.0.position(t)
    }
}

#[cfg(test)]
mod track_tests {
    use super::*;
    use crate::parse_epoch;

    #[test]
    fn the_track_follows_the_series_within_its_bound_in_any_call_order() {
        let epoch = parse_epoch("2026-07-04T00:00:00 UTC").unwrap();
        let mut track = SunTrack::new(epoch);
        let mut worst: f64 = 0.0;
        for k in 0..2000 {
            let t = -3600.0 + 97.3 * k as f64;
            let exact = sun_position(epoch, t);
            worst = worst.max((track.position(t) - exact).norm() / exact.norm());
        }
        assert!(worst < 5e-9, "worst {worst:e}");
        // Backwards and from a fresh track: the same bits.
        let mut fresh = SunTrack::new(epoch);
        for t in [5000.0, 123.0, 599.999, 600.0, -1.0] {
            assert_eq!(fresh.position(t), track.position(t));
        }
    }
}
