//! The geomagnetic field on magnetic dipoles: a residual dipole of the spacecraft and
//! magnetic torquers (contract section 12).
//!
//! The field `B` (tesla) at the centre of mass is IGRF-14 (degree 13 with its secular
//! variation) or its tilted dipole, through the Earth's rotation from the scene's epoch
//! ([`satsim_environment::magnetic`]), read through an Earth-fixed lattice of `lattice_deg`
//! degrees (default [`LATTICE_DEG`]; 0: IGRF-14 at every call; a magnetometer on the effect's
//! field reads the same values). A dipole `m` (A m²) on body `i` feels the couple
//! `τ = m × B` (both in the body's axes), a pure torque on that body; the field's gradient
//! force (of order `3 m B / r`, 1e-10 N for 10 A m²) is left out.
//!
//! - `residual_dipole`: fixed, root-body axes.
//! - Torquers (`[[effects.magnetic.torquer]]`): a dipole along `axis` of `body`, of strength
//!   the command clamped to `±max_dipole`. The command is `dipole` (a constant, default 0)
//!   plus what a controller writes into [`Forces::dipole_command`] (the channel the wheels'
//!   commands use: e.g. [`super::Bdot`]) plus the stepping API's held `dipole_<name>` input
//!   ([`Forces::dipole_input`]).
//!
//! Output: `magnetic_field_x/y/z` (bus axes, T), `magnetic_torque_x/y/z` (the sum of the
//! couples, bus axes, N m) and each torquer's dipole `dipole_<name>` (A m², clamped).
//!
//! Energy: the couples do work (an actuator's, in the budget: the field turns with the
//! Earth and the torquers are driven).

use super::{Bound, Context, Effect, Forces, Links, Needs, SceneEffect, Section, Torquer};
use satsim_environment::Epoch;
use satsim_environment::magnetic::{FieldModel, GeoField, LATTICE_DEG};
use satsim_integrate::SystemError;
use satsim_tree::io::{FileError, exact};
use satsim_tree::spatial::{Force, Vec3};
use serde::Deserialize;
use toml::Spanned;

/// The largest dipole a scene gives a torquer or the residual (per axis): a thousand times
/// the strongest torquer flown (a few hundred A m²).
pub const MAX_DIPOLE: Bound = Bound {
    max: 1e6,
    unit: "A m²",
    why: "a thousand times the strongest magnetic torquer flown",
};

/// The largest lattice spacing a scene gives the field (degrees): beyond it the
/// interpolation's error passes 0.1 % of the field.
pub const MAX_LATTICE_DEG: f64 = 10.0;

/// The magnetic effect.
#[derive(Clone, Debug)]
pub struct Magnetic {
    field: GeoField,
    residual: Vec3,
    torquers: Vec<Torquer>,
    /// Each torquer's constant command (A m²), before the controller's.
    command: Vec<f64>,
    commanded: bool,
    /// The last evaluation: the field (bus axes), the torquers' dipoles, the total couple.
    b_bus: Vec3,
    dipoles: Vec<f64>,
    torque: Vec3,
}

impl Magnetic {
    /// The field `model` from `epoch` (on the lattice of [`LATTICE_DEG`]), a residual dipole
    /// (root axes, A m²) and `torquers`.
    pub fn new(
        model: FieldModel,
        epoch: Epoch,
        residual: Vec3,
        torquers: Vec<Torquer>,
    ) -> Result<Self, String> {
        let n = torquers.len();
        Ok(Self {
            field: GeoField::new(model, epoch)?.with_lattice(LATTICE_DEG),
            residual,
            command: vec![0.0; n],
            torquers,
            commanded: false,
            b_bus: Vec3::zeros(),
            dipoles: vec![0.0; n],
            torque: Vec3::zeros(),
        })
    }
    /// The same with the field on a lattice of `cell_deg` degrees (0: IGRF-14 at every call;
    /// [`GeoField::with_lattice`]).
    pub fn with_lattice(mut self, cell_deg: f64) -> Self {
        self.field = self.field.exact().with_lattice(cell_deg);
        self
    }
    /// The field model.
    pub fn field(&self) -> &GeoField {
        &self.field
    }
    /// The torquers' constant commands (A m², in [`Effect::torquers`] order), to change
    /// between runs or steps.
    pub fn command_mut(&mut self) -> &mut [f64] {
        &mut self.command
    }
}

impl Effect for Magnetic {
    fn name(&self) -> &str {
        "magnetic"
    }
    fn needs(&self) -> Needs {
        Needs {
            orbit: true,
            free_base: true,
            kinematics: !self.torquers.iter().all(|t| t.body == 0),
            ..Needs::default()
        }
    }
    fn torquers(&self) -> Vec<Torquer> {
        self.torquers.clone()
    }
    fn connect(&mut self, links: &Links) {
        self.commanded = links.dipoles_commanded;
    }
    fn apply(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        _own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        let orbit = ctx.orbit_or_err("magnetic")?;
        let b = self.field.field_gcrf(ctx.t, &orbit.r);
        self.b_bus = ctx.attitude.inverse_transform_vector(&b);
        let mut total = Vec3::zeros();
        if self.residual != Vec3::zeros() {
            let tau = self.residual.cross(&self.b_bus);
            forces.add_wrench(0, Force::new(tau, Vec3::zeros()));
            total += tau;
        }
        for (j, t) in self.torquers.iter().enumerate() {
            let wanted = self.command[j]
                + forces.dipole_input.get(j).copied().unwrap_or(0.0)
                + if self.commanded {
                    forces.dipole_command[j]
                } else {
                    0.0
                };
            let m = wanted.clamp(-t.max_dipole, t.max_dipole);
            self.dipoles[j] = m;
            if m == 0.0 {
                continue;
            }
            let (b_body, to_bus) = if t.body == 0 {
                (self.b_bus, None)
            } else {
                let rot = &ctx.data.rotation[t.body];
                (rot.tr_mul(&b), Some(rot))
            };
            let tau = (m * t.axis).cross(&b_body);
            forces.add_wrench(t.body, Force::new(tau, Vec3::zeros()));
            total += match to_bus {
                None => tau,
                Some(rot) => ctx.attitude.inverse_transform_vector(&(rot * tau)),
            };
        }
        self.torque = total;
        Ok(())
    }
    fn output_columns(&self) -> Vec<String> {
        let mut c: Vec<String> = [
            "magnetic_field_x",
            "magnetic_field_y",
            "magnetic_field_z",
            "magnetic_torque_x",
            "magnetic_torque_y",
            "magnetic_torque_z",
        ]
        .map(String::from)
        .into();
        c.extend(self.torquers.iter().map(|t| format!("dipole_{}", t.name)));
        c
    }
    fn output(&self, _ctx: &Context, _own: &[f64], row: &mut Vec<f64>) {
        row.extend_from_slice(self.b_bus.as_slice());
        row.extend_from_slice(self.torque.as_slice());
        row.extend_from_slice(&self.dipoles);
    }
}

/// `[[effects.magnetic.torquer]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TorquerFile {
    /// Unique name.
    pub name: Spanned<String>,
    /// The body that carries it (default the root).
    #[serde(default)]
    pub body: Option<Spanned<String>>,
    /// Its axis, the body's axes (normalised).
    #[serde(deserialize_with = "exact")]
    pub axis: Spanned<[f64; 3]>,
    /// The largest dipole (A m², > 0); commands beyond it are clamped.
    pub max_dipole: Spanned<f64>,
    /// A constant command (A m², default 0), added to a controller's.
    #[serde(default)]
    pub dipole: Option<Spanned<f64>>,
}

/// `[effects.magnetic]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MagneticFile {
    /// `"igrf14"` (default) or `"dipole"`.
    #[serde(default)]
    pub field: Option<Spanned<String>>,
    /// The spacecraft's residual dipole, root axes (A m², default 0).
    #[serde(default, deserialize_with = "exact")]
    pub residual_dipole: Option<Spanned<[f64; 3]>>,
    /// The spacing (degrees) of the Earth-fixed lattice IGRF-14 is read through (default
    /// [`LATTICE_DEG`]; 0: the model at every call; at most [`MAX_LATTICE_DEG`]).
    #[serde(default)]
    pub lattice_deg: Option<Spanned<f64>>,
    /// Magnetic torquers.
    #[serde(default)]
    pub torquer: Vec<TorquerFile>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

/// `field = "..."` of a section, default IGRF-14; an unknown name is an error at its line.
pub(super) fn field_model(
    field: Option<&Spanned<String>>,
    key: &str,
    section: &Section,
) -> Result<FieldModel, FileError> {
    match field {
        None => Ok(FieldModel::Igrf14),
        Some(f) => FieldModel::from_name(f.get_ref()).ok_or_else(|| {
            section.error(
                Some(f.span()),
                format!(
                    "`{key}`: unknown value `{}`, expected \"igrf14\" or \"dipole\"",
                    f.get_ref()
                ),
            )
        }),
    }
}

impl SceneEffect for Magnetic {
    const SECTION: &'static str = "magnetic";
    type File = MagneticFile;
    fn from_section(file: MagneticFile, section: &Section) -> Result<Self, FileError> {
        let model = field_model(file.field.as_ref(), "effects.magnetic.field", section)?;
        let residual = match &file.residual_dipole {
            None => Vec3::zeros(),
            Some(r) => {
                let v = Vec3::from(*r.get_ref());
                if !v.iter().all(|x| x.is_finite()) {
                    return Err(section.error(
                        Some(r.span()),
                        "`effects.magnetic.residual_dipole` must be finite (A m²)",
                    ));
                }
                for x in &v {
                    MAX_DIPOLE
                        .check(*x, "effects.magnetic.residual_dipole")
                        .map_err(|m| section.error(Some(r.span()), m))?;
                }
                v
            }
        };
        let mut torquers: Vec<Torquer> = Vec::new();
        let mut command = Vec::new();
        for t in &file.torquer {
            let name = section.column_name(&t.name, "effects.magnetic.torquer.name")?;
            if torquers.iter().any(|o| &o.name == name) {
                return Err(section.error(
                    Some(t.name.span()),
                    format!("torquer `{name}` is listed twice"),
                ));
            }
            let body = match &t.body {
                None => 0,
                Some(b) => section.model().body_index(b.get_ref()).ok_or_else(|| {
                    section.error(
                        Some(b.span()),
                        format!(
                            "torquer `{name}`: unknown body `{}` (the model's bodies: {})",
                            b.get_ref(),
                            section
                                .model()
                                .bodies()
                                .iter()
                                .map(|b| b.name())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    )
                })?,
            };
            let axis = Vec3::from(*t.axis.get_ref());
            let norm = axis.norm();
            if !norm.is_finite() || (norm - 1.0).abs() > 1e-6 {
                return Err(section.error(
                    Some(t.axis.span()),
                    format!("torquer `{name}`: `axis` must be a unit vector, its norm is {norm}"),
                ));
            }
            let max_dipole = section.positive_within(
                &t.max_dipole,
                "effects.magnetic.torquer.max_dipole",
                MAX_DIPOLE,
            )?;
            let c = match &t.dipole {
                None => 0.0,
                Some(d) if d.get_ref().is_finite() => {
                    MAX_DIPOLE
                        .check(*d.get_ref(), "effects.magnetic.torquer.dipole")
                        .map_err(|m| section.error(Some(d.span()), m))?;
                    *d.get_ref()
                }
                Some(d) => {
                    return Err(section.error(
                        Some(d.span()),
                        format!("torquer `{name}`: `dipole` must be finite"),
                    ));
                }
            };
            torquers.push(Torquer {
                name: name.clone(),
                body,
                axis: axis / norm,
                max_dipole,
            });
            command.push(c);
        }
        let lattice = match &file.lattice_deg {
            None => LATTICE_DEG,
            Some(d) => {
                let v = section.non_negative(d, "effects.magnetic.lattice_deg")?;
                if v > MAX_LATTICE_DEG {
                    return Err(section.error(
                        Some(d.span()),
                        format!(
                            "`effects.magnetic.lattice_deg` is {v}: the lattice's spacing lies from 0 (IGRF-14 at every call) to {MAX_LATTICE_DEG} degrees"
                        ),
                    ));
                }
                v
            }
        };
        let epoch = section.epoch()?;
        let mut m = Magnetic::new(model, epoch, residual, torquers).map_err(|e| {
            section.error(
                file.field
                    .as_ref()
                    .map(|f| f.span())
                    .or(Some(section.span())),
                format!("`epoch`: {e}"),
            )
        })?;
        m.command = command;
        Ok(m.with_lattice(lattice))
    }
}
