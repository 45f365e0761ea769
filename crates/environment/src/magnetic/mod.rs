//! The Earth's magnetic field: IGRF-14 (degree 13, with its secular variation) or the tilted
//! centred dipole of its degree-1 terms at the epoch.
//!
//! The coefficients are the official IGRF-14 table (IAGA Working Group V-MOD, released
//! December 2024; public), `data/igrf14coeffs.txt`, read at compile time and parsed once (at
//! the first [`GeoField::new`]). The file is the one the PyPI package `pyIGRF14` 1.0.4 ships
//! (`pyIGRF14/src/igrf14coeffs.txt`, md5 3606931c15c9234d9ba8e2e91b729cb0), byte for byte;
//! `fixtures/igrf_reference.py` checks it against `ppigrf`'s separate copy (IGRF14.shc).
//!
//! # The lattice
//!
//! [`GeoField::with_lattice`] reads IGRF-14 through the Earth-fixed
//! [`Lattice`] the gravity harmonics use: each node holds the field
//! (Earth-fixed Cartesian components, nT) at the epoch of the 5-yearly model in force and its
//! rate (nT/year); the Gauss coefficients are linear in time over a model's five years, so the
//! field at a date is the first plus the years since times the second, with no error from the
//! time. The error is the place's: along one orbit at 500 km (inclined 51.6 degrees, and
//! polar; a call every 0.5 s), largest 10.7 nT (4.3e-4 of the field) at 1 degree, the default
//! [`LATTICE_DEG`]; 40.8 nT (1.7e-3) at 2, 90 nT (3.7e-3) at 3, 163 nT (6.5e-3) at 4 degrees
//! (IGRF's own error against the real field is of order 100 nT). The cost on a warm lattice,
//! its fills included: 220 ns a call with a call every 0.1 s, 600-700 ns every 0.5 s, against
//! 1.3-1.4 µs for the model (release build, a loaded 2-core machine). The numbers:
//! `cargo test -p satsim-environment --release --test it -- --ignored --nocapture lattice_`.

mod dipole;
mod igrf;

use crate::earth::gcrf_to_itrf;
use crate::epoch::decimal_year;
use crate::lattice::Lattice;
use crate::{Epoch, Vec3};
use igrf::Table;
use std::sync::Mutex;

/// The lattice spacing the magnetic effect reads IGRF-14 through by default (degrees): see
/// [`GeoField::with_lattice`].
pub const LATTICE_DEG: f64 = 1.0;

/// Which field model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldModel {
    /// IGRF-14 to degree 13, with its secular variation.
    Igrf14,
    /// The tilted centred dipole of IGRF-14's degree-1 terms at the epoch, in closed form.
    Dipole,
}

impl FieldModel {
    /// The model named `name` ("igrf14", "dipole"), or `None` for another name.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "igrf14" => Some(Self::Igrf14),
            "dipole" => Some(Self::Dipole),
            _ => None,
        }
    }

    /// The model's name, as [`FieldModel::from_name`] reads it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Igrf14 => "igrf14",
            Self::Dipole => "dipole",
        }
    }
}

/// The geomagnetic field of a scene: a model and the epoch its time `t` counts from, and
/// optionally the lattice IGRF-14 is read through ([`GeoField::with_lattice`]).
pub struct GeoField {
    model: FieldModel,
    epoch: Epoch,
    table: &'static Table,
    /// The dipole's moment in Earth-fixed axes, (g11, h11, g10) at the epoch (nT).
    dipole: Vec3,
    /// IGRF-14's field at its model's epoch and its rate (nT, nT/year, Earth-fixed axes) on
    /// a lattice keyed by the model; a lock, not a `&mut`, so that every reader of the field
    /// (the effect, a magnetometer, the environment report) sees the same values.
    lattice: Option<Box<Mutex<Lattice<6>>>>,
}

impl Clone for GeoField {
    /// A copy with its own copy of the lattice's cells (the values are the same).
    fn clone(&self) -> Self {
        Self {
            model: self.model,
            epoch: self.epoch,
            table: self.table,
            dipole: self.dipole,
            lattice: self.lattice.as_ref().map(|l| {
                let l = l.lock().unwrap_or_else(|e| e.into_inner());
                Box::new(Mutex::new(l.clone()))
            }),
        }
    }
}

impl std::fmt::Debug for GeoField {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GeoField")
            .field("model", &self.model)
            .field("epoch", &self.epoch)
            .field("dipole_nT", &self.dipole)
            .field("lattice_deg", &self.lattice_deg())
            .finish()
    }
}

impl GeoField {
    /// The field `model` with time counted from `epoch`, or a message when the epoch lies
    /// outside IGRF-14's span (1900.0 to 2030.0).
    ///
    /// ```
    /// use satsim_environment::{magnetic::{FieldModel, GeoField}, parse_epoch};
    /// let e = parse_epoch("2026-03-20T12:00:00 UTC").unwrap();
    /// assert!(GeoField::new(FieldModel::Igrf14, e).is_ok());
    /// let old = parse_epoch("1850-01-01T00:00:00 UTC").unwrap();
    /// assert!(GeoField::new(FieldModel::Dipole, old).unwrap_err().contains("1900"));
    /// ```
    pub fn new(model: FieldModel, epoch: Epoch) -> Result<GeoField, String> {
        let year = decimal_year(epoch, 0.0);
        if !(igrf::FIRST_YEAR..=igrf::LAST_YEAR).contains(&year) {
            return Err(format!(
                "the epoch {epoch} (year {year:.3}) is outside IGRF-14's span, {:.1} to {:.1}",
                igrf::FIRST_YEAR,
                igrf::LAST_YEAR
            ));
        }
        let table = igrf::table()?;
        let [g10, g11, h11] = table.degree_one(year);
        Ok(GeoField {
            model,
            epoch,
            table,
            dipole: Vec3::new(g11, h11, g10),
            lattice: None,
        })
    }

    /// The field read through an Earth-fixed lattice of spacing `cell_deg` degrees (rounded
    /// as [`Lattice::new`] says; 0 or a value outside (0, 90]: IGRF-14 at every call). Each
    /// node holds IGRF-14's field at the epoch of the 5-yearly model in force and its rate;
    /// the coefficients are linear in time within a model's five years, so the time costs no
    /// error, the place costs the interpolation's (the module's page). The dipole is in
    /// closed form and never on a lattice.
    pub fn with_lattice(mut self, cell_deg: f64) -> Self {
        self.lattice = Lattice::new(cell_deg).map(|l| Box::new(Mutex::new(l)));
        self
    }

    /// The lattice's spacing (degrees; 0 without one).
    pub fn lattice_deg(&self) -> f64 {
        self.lattice.as_ref().map_or(0.0, |l| {
            l.lock().unwrap_or_else(|e| e.into_inner()).cell_deg()
        })
    }

    /// The evaluations of IGRF-14 made at the lattice's nodes so far (0 without one).
    pub fn lattice_evaluations(&self) -> u64 {
        self.lattice.as_ref().map_or(0, |l| {
            l.lock().unwrap_or_else(|e| e.into_inner()).evaluations()
        })
    }

    /// The same field without its lattice: IGRF-14 at every call.
    pub fn exact(&self) -> GeoField {
        GeoField {
            lattice: None,
            ..*self
        }
    }

    /// The model.
    pub fn model(&self) -> FieldModel {
        self.model
    }

    /// The field (T) in GCRF axes at the GCRF position `r` (m) at `epoch + t`.
    pub fn field_gcrf(&self, t: f64, r: &Vec3) -> Vec3 {
        let to_itrf = gcrf_to_itrf(self.epoch, t);
        to_itrf.inverse() * self.field_itrf(t, &(to_itrf * r))
    }

    /// The field (T) in Earth-fixed (ITRF) axes at the Earth-fixed position `r_itrf` (m) at
    /// `epoch + t`, through the lattice when there is one. Past 2030 IGRF-14 goes on with its
    /// 2025-2030 secular variation; the dipole keeps the epoch's terms. At the Earth's centre
    /// the field is not finite.
    pub fn field_itrf(&self, t: f64, r_itrf: &Vec3) -> Vec3 {
        let year = decimal_year(self.epoch, t);
        let nanotesla = match (self.model, &self.lattice) {
            (FieldModel::Igrf14, None) => self.table.field(year, r_itrf),
            (FieldModel::Igrf14, Some(lattice)) => {
                let (k, dt) = Table::interval(year);
                let table = self.table;
                let mut lattice = lattice.lock().unwrap_or_else(|e| e.into_inner());
                let v = lattice.value(k as i64, r_itrf, |p| {
                    let [b, rate] = table.model_and_rate(k, p);
                    [b.x, b.y, b.z, rate.x, rate.y, rate.z]
                });
                Vec3::new(v[0], v[1], v[2]) + dt * Vec3::new(v[3], v[4], v[5])
            }
            (FieldModel::Dipole, _) => dipole::field(&self.dipole, r_itrf),
        };
        nanotesla * 1e-9
    }
}
