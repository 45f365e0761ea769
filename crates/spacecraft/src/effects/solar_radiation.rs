//! Solar radiation pressure on every facet of every body, with the Earth's shadow and, on
//! request, the spacecraft's own shadows (contract section 12).
//!
//! Per lit facet of area `A`, outward unit normal `n`, with `s` the unit vector from the
//! spacecraft to the Sun, `cos θ = n·s > 0`, the shadow fraction `ν` and the pressure
//! `P = P_1AU (1 AU / r_sun)²`:
//!
//! `F = −ν P A_lit cos θ [ (1 − specular) s + 2 (specular cos θ + diffuse / 3) n ]`
//!
//! at the facet's centroid, in its current attitude (the facet moves with its body, so a
//! panel turned on an offset hinge carries its centre of pressure with it: Basilisk's #1533).
//! `A_lit` is the facet's area, or with `self_shadowing` the part of it from which the Sun is
//! not hidden by another facet ([`Facets::shade`]: a grid of `resolution`² rays per facet).
//! The force acts on the body that carries the facet and reaches every hinge through the tree.
//! The Sun's direction is taken from the centre of mass for every facet (the parallax over
//! a spacecraft's size, 1e-11 rad, is far below the series' accuracy).
//!
//! Output: `shadow` (ν), and `srp_torque_x/y/z`, the moment of all the facets' forces about
//! the spacecraft's centre of mass, bus axes (N m).
//!
//! Energy: the pressure does work (actuator's, in the budget).

use super::facets::Facets;
use super::{Context, Effect, Forces, Needs, OrbitState, SceneEffect, Section};
use satsim_environment::shadow::{ShadowModel, shadow_fraction};
use satsim_environment::sun::SunTrack;
use satsim_environment::{AU, Epoch, SOLAR_PRESSURE_1AU};
use satsim_integrate::SystemError;
use satsim_tree::io::FileError;
use satsim_tree::spatial::{Force, Vec3};
use serde::Deserialize;
use toml::Spanned;

/// The default number of rays along each side of a facet for self-shadowing.
pub const DEFAULT_RESOLUTION: usize = 8;

/// The estimated time of one self-shadowing pass (s, per right-hand side) from which reading
/// the scene warns ([`Facets::shade_estimate`]): 10 ms, 40 ms per RK4 step, an hour's run at
/// one-second steps taking over two minutes in the shading alone.
pub const SHADE_WARNING: f64 = 0.01;

/// What one evaluation found: the Sun, the shadow and the loads' moment about the centre
/// of mass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sunlight {
    /// Unit vector from the spacecraft to the Sun, inertial.
    pub sun: Vec3,
    /// The spacecraft-Sun distance (m).
    pub distance: f64,
    /// The fraction of the Sun's disk visible, `ν` (1 in full sun).
    pub shadow: f64,
    /// The pressure on a surface facing the Sun, before the shadow (N/m²).
    pub pressure: f64,
}

/// The solar-radiation-pressure effect.
#[derive(Clone, Debug)]
pub struct SolarRadiation {
    sun: SunTrack,
    shadow: ShadowModel,
    self_shadowing: bool,
    resolution: usize,
    facets: Facets,
    last: Option<Sunlight>,
    /// The moment of the last evaluation's forces about the centre of mass, bus axes.
    torque: Vec3,
}

impl SolarRadiation {
    /// The effect on `facets` (every facet of the model, [`Facets::of_model`]) from `epoch`
    /// (t = 0), with the Earth's shadow `shadow`; `self_shadowing`: whether facets shade
    /// each other, sampled on `resolution`² rays per facet.
    pub fn new(
        epoch: Epoch,
        shadow: ShadowModel,
        self_shadowing: bool,
        resolution: usize,
        facets: Facets,
    ) -> Self {
        Self {
            sun: SunTrack::new(epoch),
            shadow,
            self_shadowing,
            resolution: resolution.max(1),
            facets,
            last: None,
            torque: Vec3::zeros(),
        }
    }
    /// The Sun, the shadow and the pressure at time `t` for the orbit `orbit`.
    pub fn sunlight(&mut self, t: f64, orbit: &OrbitState) -> Sunlight {
        let r_sun = self.sun.position(t);
        let to_sun = r_sun - orbit.r;
        let distance = to_sun.norm();
        Sunlight {
            sun: to_sun / distance,
            distance,
            shadow: shadow_fraction(self.shadow, &orbit.r, &r_sun),
            pressure: SOLAR_PRESSURE_1AU * (AU / distance).powi(2),
        }
    }
    /// The Earth's shadow model.
    pub fn shadow_model(&self) -> ShadowModel {
        self.shadow
    }
    /// What the last evaluation found (`None` before the first).
    pub fn last(&self) -> Option<&Sunlight> {
        self.last.as_ref()
    }
    /// The facets it loads.
    pub fn facets(&self) -> &Facets {
        &self.facets
    }
}

/// The force (N) of light from direction `s` (unit, towards the Sun) on a flat surface of
/// lit area `area`, outward unit normal `n` and optical fractions `specular`, `diffuse`,
/// under pressure `p` (N/m², the shadow included): zero when the surface faces away.
///
/// ```
/// use satsim_spacecraft::effects::solar_radiation::plate_force;
/// use satsim_tree::spatial::Vec3;
/// // A black plate facing the Sun is pushed away from it by P A.
/// let f = plate_force(&Vec3::z(), &Vec3::z(), 2.0, 0.0, 0.0, 4.56e-6);
/// assert!((f + Vec3::z() * 2.0 * 4.56e-6).norm() < 1e-20);
/// ```
pub fn plate_force(s: &Vec3, n: &Vec3, area: f64, specular: f64, diffuse: f64, p: f64) -> Vec3 {
    let c = n.dot(s);
    if c <= 0.0 || area <= 0.0 {
        return Vec3::zeros();
    }
    -p * area * c * ((1.0 - specular) * s + 2.0 * (specular * c + diffuse / 3.0) * n)
}

impl Effect for SolarRadiation {
    fn name(&self) -> &str {
        "solar_radiation"
    }
    fn needs(&self) -> Needs {
        Needs::SURFACE_LOADS
    }
    fn apply(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        _own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        let orbit = ctx.orbit_or_err("solar_radiation")?;
        let com = ctx.com_or_err("solar_radiation")?;
        let light = self.sunlight(ctx.t, &orbit);
        self.last = Some(light);
        self.torque = Vec3::zeros();
        if light.shadow <= 0.0 || self.facets.is_empty() {
            return Ok(());
        }
        self.facets.place(ctx.data);
        if self.self_shadowing {
            self.facets.shade(&light.sun, self.resolution);
        } else {
            self.facets.shade_none(&light.sun);
        }
        let p = light.shadow * light.pressure;
        let mut moment = Vec3::zeros();
        for k in 0..self.facets.len() {
            let lit = self.facets.lit(k);
            if lit <= 0.0 {
                continue;
            }
            let facet = self.facets.facet(k);
            let n = *self.facets.normal(k);
            let f = plate_force(
                &light.sun,
                &n,
                lit * facet.area,
                facet.specular,
                facet.diffuse,
                p,
            );
            let i = self.facets.body(k);
            let lin = ctx.data.rotation[i].tr_mul(&f);
            forces.add_wrench(i, Force::new(facet.at.cross(&lin), lin));
            moment += (self.facets.centroid(k) - com).cross(&f);
        }
        self.torque = ctx.attitude.inverse_transform_vector(&moment);
        Ok(())
    }
    fn output_columns(&self) -> Vec<String> {
        ["shadow", "srp_torque_x", "srp_torque_y", "srp_torque_z"]
            .map(String::from)
            .into()
    }
    fn output(&self, _ctx: &Context, _own: &[f64], row: &mut Vec<f64>) {
        row.push(self.last.map_or(f64::NAN, |l| l.shadow));
        row.extend_from_slice(self.torque.as_slice());
    }
}

/// `[effects.solar_radiation]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolarRadiationFile {
    /// The Earth's shadow: `"conical"` (default), `"cylindrical"` or `"none"`.
    #[serde(default)]
    pub shadow: Option<Spanned<String>>,
    /// Whether facets shade each other (default false).
    #[serde(default)]
    pub self_shadowing: Option<bool>,
    /// Rays along each side of a facet for self-shadowing (default 8).
    #[serde(default)]
    pub resolution: Option<Spanned<i64>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

impl SceneEffect for SolarRadiation {
    const SECTION: &'static str = "solar_radiation";
    type File = SolarRadiationFile;
    fn from_section(file: SolarRadiationFile, section: &Section) -> Result<Self, FileError> {
        let shadow = match &file.shadow {
            None => ShadowModel::default(),
            Some(s) => ShadowModel::from_name(s.get_ref()).ok_or_else(|| {
                section.error(
                    Some(s.span()),
                    format!(
                        "`effects.solar_radiation.shadow`: unknown value `{}`, expected \"conical\", \"cylindrical\" or \"none\"",
                        s.get_ref()
                    ),
                )
            })?,
        };
        let resolution = match &file.resolution {
            None => DEFAULT_RESOLUTION,
            Some(r) if (1..=256).contains(r.get_ref()) => *r.get_ref() as usize,
            Some(r) => {
                return Err(section.error(
                    Some(r.span()),
                    format!(
                        "`effects.solar_radiation.resolution` must be between 1 and 256 rays per side, got {}",
                        r.get_ref()
                    ),
                ));
            }
        };
        let facets = Facets::of_section(section)?;
        let self_shadowing = file.self_shadowing.unwrap_or(false);
        if self_shadowing
            && let Some(seconds) =
                Facets::shade_estimate(section.model(), resolution, SHADE_WARNING)
            && seconds >= SHADE_WARNING
        {
            section.warn(
                section.span(),
                format!(
                    "`effects.solar_radiation.self_shadowing` on {} facets at resolution {resolution} \
                     costs about {:.0} ms per right-hand side ({:.2} s per RK4 step; estimated at \
                     the model's neutral pose): lower `resolution`, give fewer, larger facets, or \
                     set `self_shadowing = false`",
                    facets.len(),
                    seconds * 1e3,
                    4.0 * seconds
                ),
            );
        }
        Ok(SolarRadiation::new(
            section.epoch()?,
            shadow,
            self_shadowing,
            resolution,
            facets,
        ))
    }
}
