//! NRLMSISE-00 (Picone, Hedin, Drob and Aikin 2002, J. Geophys. Res. 107(A12), 1468): the
//! air's total mass density including anomalous oxygen, the model's `gtd7d` (its `d[5]`,
//! "the effective total mass density for drag"), at a place and a time.
//!
//! The model is the `nrlmsise00` crate's, whose `f64` results are bit for bit those of the
//! reference C translation (its own fixtures); here it is checked against pymsis's build of
//! NRL's Fortran (`tests/it/msis.rs`, `fixtures/msis_reference.py`). Its inputs:
//!
//! - the geodetic latitude, longitude and altitude (WGS-84) of the position turned into the
//!   Earth-fixed frame by [`gcrf_to_itrf`] ([`geodetic`]);
//! - the day of the year and the seconds of the day, UTC (= UT1, as [`crate::earth`] takes
//!   it), at `epoch + t`;
//! - the local solar time `seconds/3600 + longitude/15` h, as the model's notes recommend
//!   and pymsis computes it (the mean solar time: the equation of time, up to 16 minutes, is
//!   left out, as in both);
//! - the previous day's F10.7, its 81-day centred mean and Ap: constants ([`Drivers`]'s
//!   `Constant`, the model's daily-Ap mode, switch 9 = 1) or a space-weather file's days
//!   ([`SpaceWeather`], the storm-time mode with the 7-element Ap history, switch 9 = −1).
//!
//! One evaluation costs about a microsecond or two, as much as the rest of a right-hand side
//! of a small spacecraft, so a run reads it through [`MsisTrack`]: the logarithm of the
//! density at the nodes of a lattice in time and geodetic place, interpolated.

use super::space_weather::{SpaceWeather, day_and_seconds};
use crate::earth::{gcrf_to_itrf, gmst, precession};
use crate::epoch::{centuries_tt, days_ut1};
use crate::{Epoch, Vec3};
use nalgebra::Rotation3;
use nrlmsise00::{Input, MagneticActivity, Model};
use std::sync::Arc;

/// WGS-84 semi-major axis (m).
const WGS84_A: f64 = 6_378_137.0;
/// WGS-84 flattening.
const WGS84_F: f64 = 1.0 / 298.257_223_563;

/// The geodetic latitude (rad), longitude (rad, east, in (−π, π]) and height (m) on the
/// WGS-84 ellipsoid of the Earth-fixed position `r` (m): Bowring's closed form (1976), one
/// step from the parametric latitude (within 1e-9 rad, 6 mm, in latitude and 1 mm in height
/// from the ground to 1000 km, the test's round trip; 5e-9 rad at the geostationary
/// radius): ample for a density. At the pole the longitude is 0.
///
/// ```
/// use satsim_environment::{Vec3, atmosphere::nrlmsise::geodetic};
/// let (lat, lon, h) = geodetic(&Vec3::new(0.0, 7.0e6, 0.0));
/// assert_eq!((lat, lon), (0.0, std::f64::consts::FRAC_PI_2));
/// assert!((h - (7.0e6 - 6_378_137.0)).abs() < 1e-6);
/// ```
pub fn geodetic(r: &Vec3) -> (f64, f64, f64) {
    let e2 = WGS84_F * (2.0 - WGS84_F);
    let b = WGS84_A * (1.0 - WGS84_F);
    let p = r.x.hypot(r.y);
    let lon = r.y.atan2(r.x);
    let (st, ct) = (r.z * WGS84_A).atan2(p * b).sin_cos();
    let lat = (r.z + e2 / (1.0 - e2) * b * st * st * st).atan2(p - e2 * WGS84_A * ct * ct * ct);
    let (s, c) = lat.sin_cos();
    // Valid at the poles too (no division by cos(lat)).
    let h = p * c + r.z * s - WGS84_A * (1.0 - e2 * s * s).sqrt();
    (lat, lon, h)
}

/// The Earth-fixed position (m) of geodetic latitude, longitude (rad) and height (m) on the
/// WGS-84 ellipsoid: the inverse of [`geodetic`].
pub fn from_geodetic(lat: f64, lon: f64, h: f64) -> Vec3 {
    let e2 = WGS84_F * (2.0 - WGS84_F);
    let (s, c) = lat.sin_cos();
    let n = WGS84_A / (1.0 - e2 * s * s).sqrt();
    Vec3::new(
        (n + h) * c * lon.cos(),
        (n + h) * c * lon.sin(),
        (n * (1.0 - e2) + h) * s,
    )
}

/// The year and day of the year (1 to 366) of day number `n` from 1900-01-01.
fn year_and_day(n: i64) -> i32 {
    let (y, _, _) = super::space_weather::date_of(n);
    (n - super::space_weather::day_number(y, 1, 1) + 1) as i32
}

/// The solar flux and geomagnetic activity the model reads.
#[derive(Clone, Debug)]
pub enum Drivers {
    /// The same at every time: the previous day's F10.7 and its 81-day mean (sfu), and the
    /// daily Ap (the model's daily-Ap mode).
    Constant {
        /// The previous day's F10.7 (sfu).
        f107: f64,
        /// The 81-day centred mean of F10.7 (sfu).
        f107a: f64,
        /// The daily Ap.
        ap: f64,
    },
    /// The same at every time, with the 7-element Ap history of the storm-time mode (the
    /// order [`super::space_weather`]'s page gives).
    History {
        /// The previous day's F10.7 (sfu).
        f107: f64,
        /// The 81-day centred mean of F10.7 (sfu).
        f107a: f64,
        /// Daily Ap, the 3-hour ap now, 3, 6 and 9 hours before, the means of 8 from 12 to
        /// 33 and from 36 to 57 hours before.
        ap: [f64; 7],
    },
    /// A space-weather file's days, looked up at each time (the storm-time mode).
    Table(Arc<SpaceWeather>),
}

impl Default for Drivers {
    /// F10.7 = 150, its mean 150 and Ap = 4: the model's own moderate activity.
    fn default() -> Self {
        Drivers::Constant {
            f107: 150.0,
            f107a: 150.0,
            ap: 4.0,
        }
    }
}

/// NRLMSISE-00 at the scene's dates.
#[derive(Clone, Debug)]
pub struct Msis {
    model: Model,
    epoch: Epoch,
    drivers: Drivers,
}

impl Msis {
    /// The model along a run starting at `epoch`, with `drivers`.
    pub fn new(epoch: Epoch, drivers: Drivers) -> Self {
        Self {
            model: Model::new(),
            epoch,
            drivers,
        }
    }

    /// The drivers.
    pub fn drivers(&self) -> &Drivers {
        &self.drivers
    }

    /// The epoch (t = 0).
    pub fn epoch(&self) -> Epoch {
        self.epoch
    }

    /// The density (kg/m³) at `epoch + t` (s) at geodetic latitude `lat` and longitude `lon`
    /// (degrees) and height `h_km` (km); the error says which date the space-weather file
    /// lacks, or that the result is not a positive finite number.
    pub fn density_geodetic(&self, t: f64, lat: f64, lon: f64, h_km: f64) -> Result<f64, String> {
        let s = self.epoch.to_utc_seconds() + t;
        let (day, seconds) = day_and_seconds(s);
        let (f107, f107a, magnetic) = match &self.drivers {
            Drivers::Constant { f107, f107a, ap } => {
                (*f107, *f107a, MagneticActivity::Daily { ap: *ap })
            }
            Drivers::History { f107, f107a, ap } => {
                (*f107, *f107a, MagneticActivity::History { ap: *ap })
            }
            Drivers::Table(table) => {
                let d = table.drivers(s)?;
                (d.f107, d.f107a, MagneticActivity::History { ap: d.ap })
            }
        };
        let out = self.model.gtd7d(&Input::consistent(
            year_and_day(day),
            seconds,
            h_km,
            lat,
            lon,
            f107a,
            f107,
            magnetic,
        ));
        let rho = out.total_mass;
        if !(rho.is_finite() && rho > 0.0) {
            return Err(format!(
                "NRLMSISE-00 gives the density {rho} kg/m³ at latitude {lat}°, longitude {lon}°, height {h_km} km"
            ));
        }
        Ok(rho)
    }

    /// The density (kg/m³) at `epoch + t` at `r` (m, GCRF, from the Earth's centre),
    /// evaluated there.
    pub fn density(&self, t: f64, r: &Vec3) -> Result<f64, String> {
        let (lat, lon, h) = geodetic(&(gcrf_to_itrf(self.epoch, t) * r));
        self.density_geodetic(t, lat.to_degrees(), lon.to_degrees(), h / 1000.0)
    }
}

/// The lattice's spacing in latitude and longitude (degrees).
pub const LATTICE_DEG: f64 = 2.0;
/// The lattice's spacing in height (km).
pub const LATTICE_KM: f64 = 1.0;
/// The cells [`MsisTrack`] keeps (an integrator's stages within a step meet a few).
const CELLS: usize = 4;

/// One cell of the lattice: its lowest node's indices (time, latitude, longitude, height)
/// and the logarithm of the density at its 16 nodes (bit 0 of the index: the next time,
/// bit 1: the next latitude, bit 2: the next longitude, bit 3: the next height).
#[derive(Clone, Copy, Debug)]
struct Cell {
    key: [i64; 4],
    ln_rho: [f64; 16],
}

/// NRLMSISE-00 along a run: the logarithm of the density at the nodes of a lattice, `step`
/// seconds apart in time, [`LATTICE_DEG`] in geodetic latitude and longitude and
/// [`LATTICE_KM`] in height, interpolated multilinearly in between.
///
/// The density moves with the place as well as with the time, and where the spacecraft
/// will be at a later knot is not known at a call, so the knots span the place too. Each
/// node's value depends only on its indices, so the result is a function of `(t, r)` alone:
/// the order of the calls (an integrator's stages, a step redone, a run redone, the
/// environment report) does not change a bit of it. A few cells are kept; a spacecraft in
/// low orbit crosses into a new one every few seconds and then evaluates the model at the
/// nodes the cells it holds do not share (8 when it crosses one face). `step = 0` evaluates
/// the model at every call instead.
#[derive(Clone, Debug)]
pub struct MsisTrack {
    msis: Msis,
    step: f64,
    cells: [Option<Cell>; CELLS],
    /// The cell replaced next.
    next: usize,
    /// Evaluations of the model made (for the cost's measurement).
    evaluations: u64,
    /// The time knot and the precession at it (it turns the pole by 1e-10 rad a minute).
    precession: (i64, Rotation3<f64>),
    /// Days of UT1 from J2000 at t = 0 (the epoch converted once).
    days0: f64,
}

impl MsisTrack {
    /// `msis` on a lattice `step` (s, >= 0) apart in time; 0: evaluated at every call.
    pub fn new(msis: Msis, step: f64) -> Self {
        Self {
            days0: days_ut1(msis.epoch, 0.0),
            msis,
            step,
            cells: [None; CELLS],
            next: 0,
            evaluations: 0,
            precession: (i64::MIN, Rotation3::identity()),
        }
    }

    /// The model.
    pub fn msis(&self) -> &Msis {
        &self.msis
    }

    /// The lattice's spacing in time (s; 0: none).
    pub fn step(&self) -> f64 {
        self.step
    }

    /// The evaluations of the model made so far.
    pub fn evaluations(&self) -> u64 {
        self.evaluations
    }

    /// The density (kg/m³) at `epoch + t` (s) at `r` (m, GCRF); the error says what the
    /// model lacks (a date in the space-weather file, a finite result).
    pub fn density(&mut self, t: f64, r: &Vec3) -> Result<f64, String> {
        if self.step == 0.0 {
            self.evaluations += 1;
            return self.msis.density(t, r);
        }
        // GCRF to ITRF as `gcrf_to_itrf`, with the precession of the time knot: a function
        // of t alone still, and one sidereal turn a call.
        let knot = (t / self.step).floor();
        if !knot.is_finite() {
            return Err(format!("NRLMSISE-00: no density at t = {t} s"));
        }
        if self.precession.0 != knot as i64 {
            let p = precession(centuries_tt(self.msis.epoch, knot * self.step));
            self.precession = (knot as i64, p);
        }
        let spin = Rotation3::from_axis_angle(&Vec3::z_axis(), -gmst(self.days0 + t / 86_400.0));
        let (lat, lon, h) = geodetic(&(spin * (self.precession.1 * r)));
        let u = [
            t / self.step,
            lat.to_degrees() / LATTICE_DEG,
            lon.to_degrees() / LATTICE_DEG,
            h / 1000.0 / LATTICE_KM,
        ];
        if u.iter().any(|x| !(x.is_finite() && x.abs() < 1e15)) {
            return Err(format!(
                "NRLMSISE-00: no density at t = {t} s, latitude {}°, longitude {}°, height {} km",
                lat.to_degrees(),
                lon.to_degrees(),
                h / 1000.0
            ));
        }
        let low = u.map(f64::floor);
        // The pole's latitude is the top of the last cell, not the bottom of one past it.
        let key = [
            low[0] as i64,
            (low[1] as i64).min((90.0 / LATTICE_DEG) as i64 - 1),
            low[2] as i64,
            low[3] as i64,
        ];
        let cell = self.cell(key)?;
        let w = [
            u[0] - key[0] as f64,
            u[1] - key[1] as f64,
            u[2] - key[2] as f64,
            u[3] - key[3] as f64,
        ];
        // Multilinear: fold one dimension at a time, the highest bit first.
        let mut v = cell.ln_rho;
        let mut n = 16;
        for d in (0..4).rev() {
            n /= 2;
            for k in 0..n {
                v[k] += w[d] * (v[k + n] - v[k]);
            }
        }
        Ok(v[0].exp())
    }

    /// The cell whose lowest node is `key`: kept, or made (its nodes taken from the cells
    /// kept where they share them, the model evaluated at the others).
    fn cell(&mut self, key: [i64; 4]) -> Result<Cell, String> {
        if let Some(c) = self.cells.iter().flatten().find(|c| c.key == key) {
            return Ok(*c);
        }
        let mut ln_rho = [0.0; 16];
        for (b, slot) in ln_rho.iter_mut().enumerate() {
            let node = [0, 1, 2, 3].map(|d| key[d] + ((b >> d) & 1) as i64);
            let kept = self.cells.iter().flatten().find_map(|c| {
                let off = [0, 1, 2, 3].map(|d| node[d] - c.key[d]);
                off.iter()
                    .all(|o| (0..=1).contains(o))
                    .then(|| c.ln_rho[(0..4).map(|d| (off[d] as usize) << d).sum::<usize>()])
            });
            *slot = match kept {
                Some(v) => v,
                None => {
                    self.evaluations += 1;
                    self.msis
                        .density_geodetic(
                            node[0] as f64 * self.step,
                            node[1] as f64 * LATTICE_DEG,
                            node[2] as f64 * LATTICE_DEG,
                            node[3] as f64 * LATTICE_KM,
                        )?
                        .ln()
                }
            };
        }
        let cell = Cell { key, ln_rho };
        self.cells[self.next] = Some(cell);
        self.next = (self.next + 1) % CELLS;
        Ok(cell)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geodetic_coordinates_round_trip_from_the_ground_to_beyond_geostationary() {
        let (mut worst_lat, mut worst_h) = (0.0f64, 0.0f64);
        for &(lat, lon, h) in &[
            (0.0, 0.0, 0.0),
            (45.0, 10.0, 400e3),
            (-89.9, -170.0, 800e3),
            (90.0, 0.0, 500e3),
            (33.3, 123.0, 1000e3),
            (-12.0, 179.9, -1000.0),
            (60.0, -45.0, 150e3),
        ] {
            let r = from_geodetic(f64::to_radians(lat), f64::to_radians(lon), h);
            let (la, lo, hh) = geodetic(&r);
            worst_lat = worst_lat.max((la - lat.to_radians()).abs());
            worst_h = worst_h.max((hh - h).abs());
            if lat.abs() < 90.0 {
                assert!((lo.to_degrees() - lon).abs() < 1e-11, "{lat} {lon} {h}");
            }
        }
        assert!(
            worst_lat < 1e-9 && worst_h < 1e-3,
            "{worst_lat} rad, {worst_h} m"
        );
        // Geostationary: 5e-9 rad (0.2 m along the ground).
        let r = from_geodetic(0.6, 1.0, 35_786e3);
        let (la, _, hh) = geodetic(&r);
        assert!(
            (la - 0.6).abs() < 1e-8 && (hh - 35_786e3).abs() < 1e-2,
            "{la} {hh}"
        );
        // The ellipsoid: the pole is 21.4 km nearer the centre than the equator.
        let (_, _, h) = geodetic(&Vec3::new(0.0, 0.0, 6_356_752.314_245));
        assert!(h.abs() < 1e-6, "{h}");
    }

    #[test]
    fn day_of_year_counts_from_the_first_of_january() {
        use super::super::space_weather::day_number;
        assert_eq!(year_and_day(day_number(2026, 1, 1)), 1);
        assert_eq!(year_and_day(day_number(2024, 12, 31)), 366);
        assert_eq!(year_and_day(day_number(2026, 3, 20)), 79);
    }
}
