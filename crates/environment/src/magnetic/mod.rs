//! The Earth's magnetic field: IGRF-14 (degree 13, with its secular variation) or the tilted
//! centred dipole of its degree-1 terms at the epoch.
//!
//! The coefficients are the official IGRF-14 table (IAGA Working Group V-MOD, released
//! December 2024; public), `data/igrf14coeffs.txt`, read at compile time and parsed once (at
//! the first [`GeoField::new`]). The file is the one the PyPI package `pyIGRF14` 1.0.4 ships
//! (`pyIGRF14/src/igrf14coeffs.txt`, md5 3606931c15c9234d9ba8e2e91b729cb0), byte for byte;
//! `fixtures/igrf_reference.py` checks it against `ppigrf`'s separate copy (IGRF14.shc).

mod dipole;
mod igrf;

use crate::earth::gcrf_to_itrf;
use crate::epoch::decimal_year;
use crate::{Epoch, Vec3};
use igrf::Table;

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

/// The geomagnetic field of a scene: a model and the epoch its time `t` counts from.
#[derive(Clone)]
pub struct GeoField {
    model: FieldModel,
    epoch: Epoch,
    table: &'static Table,
    /// The dipole's moment in Earth-fixed axes, (g11, h11, g10) at the epoch (nT).
    dipole: Vec3,
}

impl std::fmt::Debug for GeoField {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GeoField")
            .field("model", &self.model)
            .field("epoch", &self.epoch)
            .field("dipole_nT", &self.dipole)
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
        })
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
    /// `epoch + t`. Past 2030 IGRF-14 goes on with its 2025-2030 secular variation; the dipole
    /// keeps the epoch's terms. At the Earth's centre the field is not finite.
    pub fn field_itrf(&self, t: f64, r_itrf: &Vec3) -> Vec3 {
        let nanotesla = match self.model {
            FieldModel::Igrf14 => self.table.field(decimal_year(self.epoch, t), r_itrf),
            FieldModel::Dipole => dipole::field(&self.dipole, r_itrf),
        };
        nanotesla * 1e-9
    }
}
