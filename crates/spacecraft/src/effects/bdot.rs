//! B-dot detumbling: the magnetic torquers' classic controller.
//!
//! The commanded dipole opposes the rate of change of the field seen in the bus' axes,
//! `m = −k Ḃ_b`. With the field's own change along the orbit left out (slower than a
//! tumble by the ratio of the orbital rate to the body rate), `Ḃ_b = −ω × B_b`, so
//! `m = k ω × B_b` and the couple `m × B_b = −k [B² ω − (B·ω) B]` removes the rate across
//! the field: it only ever takes energy out. Each torquer `j` of the bus is commanded
//! `a_j · m` through [`Forces::dipole_command`] (the magnetic effect clamps it to its
//! `max_dipole`).
//!
//! Its field is its own copy of the magnetic effect's model (`field`, default IGRF-14):
//! a flight computer would read a magnetometer; the sensors come with the flight-software
//! issue.

use super::magnetic::field_model;
use super::{
    Bound, Context, Effect, EffectSet, Forces, Links, Needs, SceneEffect, Section, needs_met,
};
use satsim_environment::magnetic::GeoField;
use satsim_integrate::SystemError;
use satsim_tree::io::FileError;
use satsim_tree::spatial::Vec3;
use serde::Deserialize;
use toml::Spanned;

/// The largest B-dot `gain`: at it a rate of 10⁻⁵ rad/s in a 20 µT field already asks for
/// 200 A m², more than most torquers give; a larger gain changes nothing but the rates at
/// which the command saturates.
pub const MAX_GAIN: Bound = Bound {
    max: 1e12,
    unit: "A m² s/T",
    why: "at that gain any rate above 10⁻⁵ rad/s already saturates the torquers",
};

/// The B-dot controller.
#[derive(Clone, Debug)]
pub struct Bdot {
    gain: f64,
    field: GeoField,
    /// Each torquer's axis in bus axes, or zero for a torquer on another body.
    axes: Vec<Vec3>,
}

impl Bdot {
    /// The law `m = k ω × B_b` with gain `gain` (A m² s / T) in the field `field`.
    pub fn new(gain: f64, field: GeoField) -> Self {
        Self {
            gain,
            field,
            axes: Vec::new(),
        }
    }
    /// The dipole it asks for (bus axes, A m²) at rate `omega` (bus axes) in the field
    /// `b_bus` (bus axes).
    pub fn dipole(&self, omega: &Vec3, b_bus: &Vec3) -> Vec3 {
        self.gain * omega.cross(b_bus)
    }
}

impl Effect for Bdot {
    fn name(&self) -> &str {
        "bdot"
    }
    fn needs(&self) -> Needs {
        Needs {
            orbit: true,
            free_base: true,
            ..Needs::default()
        }
    }
    fn commands_dipoles(&self) -> bool {
        true
    }
    fn before(&self) -> &[&str] {
        &["magnetic"]
    }
    fn connect(&mut self, links: &Links) {
        self.axes = links
            .torquers
            .iter()
            .map(|t| if t.body == 0 { t.axis } else { Vec3::zeros() })
            .collect();
    }
    fn apply(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        _own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        let orbit = ctx.orbit_or_err("bdot")?;
        let b = ctx
            .attitude
            .inverse_transform_vector(&self.field.field_gcrf(ctx.t, &orbit.r));
        let m = self.dipole(&ctx.omega, &b);
        for (c, a) in forces.dipole_command.iter_mut().zip(&self.axes) {
            *c += a.dot(&m);
        }
        Ok(())
    }
}

/// `[effects.bdot]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BdotFile {
    /// The gain k (A m² s / T, > 0).
    pub gain: Spanned<f64>,
    /// The field the controller assumes: `"igrf14"` (default) or `"dipole"`.
    #[serde(default)]
    pub field: Option<Spanned<String>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

impl SceneEffect for Bdot {
    const SECTION: &'static str = "bdot";
    type File = BdotFile;
    fn from_section(file: BdotFile, section: &Section) -> Result<Self, FileError> {
        let gain = section.positive_within(&file.gain, "effects.bdot.gain", MAX_GAIN)?;
        let model = field_model(file.field.as_ref(), "effects.bdot.field", section)?;
        let field = GeoField::new(model, section.epoch()?)
            .map_err(|e| section.error_here(format!("`epoch`: {e}")))?;
        Ok(Bdot::new(gain, field))
    }
    fn check(&self, enabled: &EffectSet) -> Result<(), String> {
        needs_met(self, enabled)?;
        if enabled
            .iter()
            .all(|e| e.torquers().iter().all(|t| t.body != 0))
        {
            return Err("effects.bdot commands magnetic torquers on the bus: add at least one [[effects.magnetic.torquer]] (on the root body)".into());
        }
        Ok(())
    }
}
