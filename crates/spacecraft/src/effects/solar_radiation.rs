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
//! # The Earth's light (`albedo = true`)
//!
//! The Earth's reflected sunlight and emitted infrared
//! ([`satsim_environment::earth_radiation`]: a Lambertian sphere of uniform albedo
//! `albedo_coefficient`, 0.3, lit as the sub-spacecraft point is, and a uniform emitter of
//! `earth_ir`, 237 W/m²) push every facet that sees the Earth. With `M` the Earth's exitance
//! (reflected `a S max(0, ŝ·r̂)`, on the day side only; emitted `M_ir`, in eclipse too), the
//! sunlight's law summed over the directions `d` from which the facet sees the Earth (the
//! visible cap above its horizon,
//! [`cap_moments`](satsim_environment::earth_radiation::cap_moments), evaluated by its table
//! [`CapTable`]:
//! `F_v`, the view factor, `V = (1/π) ∫ cos θ d dω`, `W = (1/π) ∫ cos² θ dω`):
//!
//! `F = −(M/c) A_lit [ (1 − specular) V + 2 (specular W + diffuse F_v / 3) n ]`
//!
//! at the facet's centroid ([`earth_plate_force`]). A facet facing the nadir at `r` receives
//! the irradiance `M (R_EARTH / r)²`, and its force is
//! `(M/c) A [ (1 + specular) (2/3)(1 − cos³ α) + (2/3) diffuse (R_EARTH / r)² ]` away from
//! the Earth, `sin α = R_EARTH / r`: its absorbed and mirrored parts at 500 km 0.73 of what a
//! beam of the same irradiance from the nadir would give (the light comes from a cap reaching
//! 68° from the nadir, and its sideways push cancels). A facet edge-on to the nadir, or tilted past it, still sees the
//! cap's edge and is pushed (up to `90° + α`), continuously in its tilt. With
//! `self_shadowing` a facet facing the nadir is shaded by the others as from a light at the
//! nadir (a second shading pass); a facet facing away from the nadir, lit by the cap's edge
//! only, is not shaded.
//!
//! Output: `shadow` (ν), and `srp_torque_x/y/z`, the moment of the Sun's forces on all the
//! facets about the spacecraft's centre of mass, bus axes (N m); with `albedo = true`, also
//! `earth_radiation_torque_x/y/z`, the same of the Earth's light.
//!
//! Energy: the pressure does work (actuator's, in the budget).

use super::facets::Facets;
use super::modal_loads::FacetModes;
use super::{Context, Effect, Forces, Links, Needs, OrbitState, SceneEffect, Section};
use satsim_environment::earth_radiation::{
    ALBEDO, CapMoments, CapTable, EARTH_IR, EarthRadiation, SPEED_OF_LIGHT,
};
use satsim_environment::shadow::{ShadowModel, shadow_fraction};
use satsim_environment::sun::SunTrack;
use satsim_environment::{AU, Epoch, R_EARTH, SOLAR_PRESSURE_1AU};
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

/// Which light the effect applies: all of it in a run; one source at a time where its
/// loads are reported apart (`satsim environment`'s `solar_radiation` and
/// `earth_radiation`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSources {
    /// The Sun's, and the Earth's when it is on.
    #[default]
    All,
    /// The Sun's only.
    Sun,
    /// The Earth's only (none when it is off).
    Earth,
}

/// The solar-radiation-pressure effect.
#[derive(Clone, Debug)]
pub struct SolarRadiation {
    sun: SunTrack,
    shadow: ShadowModel,
    self_shadowing: bool,
    resolution: usize,
    facets: Facets,
    /// The Earth's reflected and emitted light, when on.
    earth: Option<EarthRadiation>,
    sources: LightSources,
    last: Option<Sunlight>,
    /// The moment of the last evaluation's Sun forces about the centre of mass, bus axes.
    torque: Vec3,
    /// The same of the Earth's light.
    earth_torque: Vec3,
    /// Each facet's mean mode shapes, on a flexible body (set by `connect`).
    modes: FacetModes,
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
            earth: None,
            sources: LightSources::All,
            last: None,
            torque: Vec3::zeros(),
            earth_torque: Vec3::zeros(),
            modes: FacetModes::default(),
        }
    }
    /// With the Earth's reflected and emitted light (`Some`), or without.
    pub fn with_earth_radiation(mut self, earth: Option<EarthRadiation>) -> Self {
        self.earth = earth;
        self
    }
    /// The Earth's light model, when on.
    pub fn earth_radiation(&self) -> Option<&EarthRadiation> {
        self.earth.as_ref()
    }
    /// Applies only the light of `sources` from now on ([`LightSources::All`] in a run).
    pub fn set_sources(&mut self, sources: LightSources) {
        self.sources = sources;
    }
    /// The Sun, the shadow and the pressure at time `t` for the orbit `orbit`.
    pub fn sunlight(&mut self, t: f64, orbit: &OrbitState) -> Sunlight {
        let r_sun = self.sun.position(t);
        Self::sunlight_from(&r_sun, self.shadow, orbit)
    }
    /// [`SolarRadiation::sunlight`] with the Sun at `r_sun` (m, GCRF).
    fn sunlight_from(r_sun: &Vec3, shadow: ShadowModel, orbit: &OrbitState) -> Sunlight {
        let to_sun = r_sun - orbit.r;
        let distance = to_sun.norm();
        Sunlight {
            sun: to_sun / distance,
            distance,
            shadow: shadow_fraction(shadow, &orbit.r, r_sun),
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

/// The force (N) of the Earth's light on a flat surface of area `area`, outward unit normal
/// `n` and optical fractions `specular`, `diffuse`, its [`CapMoments`] `cap` (same frame as
/// `n`), under the Earth's exitance over c `m` (N/m²):
/// `−m A [ (1 − specular) V + 2 (specular W + diffuse F_v / 3) n ]`: the sunlight's law of
/// [`plate_force`] summed over the directions from which the surface sees the Earth.
///
/// ```
/// use satsim_environment::earth_radiation::cap_moments;
/// use satsim_spacecraft::effects::solar_radiation::earth_plate_force;
/// use satsim_tree::spatial::Vec3;
/// // Far from the Earth, facing it: a beam, m A (1 + specular) (R/r)² away from it.
/// let cap = cap_moments(&-Vec3::z(), &-Vec3::z(), 1000.0);
/// let f = earth_plate_force(&cap, &-Vec3::z(), 2.0, 0.5, 0.0, 1.0);
/// assert!((f.z / 3e-6 - 1.0).abs() < 1e-6);
/// ```
pub fn earth_plate_force(
    cap: &CapMoments,
    n: &Vec3,
    area: f64,
    specular: f64,
    diffuse: f64,
    m: f64,
) -> Vec3 {
    if cap.irradiance <= 0.0 || area <= 0.0 {
        return Vec3::zeros();
    }
    -m * area
        * ((1.0 - specular) * cap.flux
            + 2.0 * (specular * cap.normal + diffuse * cap.irradiance / 3.0) * n)
}

impl Effect for SolarRadiation {
    fn connect(&mut self, links: &Links) {
        self.modes = FacetModes::new(
            links.flex,
            (0..self.facets.len()).map(|k| (self.facets.body(k), self.facets.facet(k))),
        );
    }
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
        let r_sun = self.sun.position(ctx.t);
        let light = Self::sunlight_from(&r_sun, self.shadow, &orbit);
        self.last = Some(light);
        self.torque = Vec3::zeros();
        self.earth_torque = Vec3::zeros();
        let sun_on = light.shadow > 0.0 && self.sources != LightSources::Earth;
        let earth = self.earth.filter(|_| self.sources != LightSources::Sun);
        if !(sun_on || earth.is_some()) || self.facets.is_empty() {
            return Ok(());
        }
        let modes = &self.modes;
        self.facets
            .place_deflected(ctx.data, |k| modes.deflection(k, ctx.eta));
        if sun_on {
            self.torque = self.sun_loads(ctx, forces, &light, &com);
        }
        if let Some(earth) = earth {
            self.earth_torque = self.earth_loads(ctx, forces, &earth, &orbit, &r_sun, &com);
        }
        Ok(())
    }
    fn output_columns(&self) -> Vec<String> {
        let mut columns: Vec<String> = ["shadow", "srp_torque_x", "srp_torque_y", "srp_torque_z"]
            .map(String::from)
            .into();
        if self.earth.is_some() {
            columns.extend(["x", "y", "z"].map(|a| format!("earth_radiation_torque_{a}")));
        }
        columns
    }
    fn output(&self, _ctx: &Context, _own: &[f64], row: &mut Vec<f64>) {
        row.push(self.last.map_or(f64::NAN, |l| l.shadow));
        row.extend_from_slice(self.torque.as_slice());
        if self.earth.is_some() {
            row.extend_from_slice(self.earth_torque.as_slice());
        }
    }
}

impl SolarRadiation {
    /// The Sun's forces on the placed facets, added to `forces`; their moment about `com`,
    /// bus axes.
    fn sun_loads(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        light: &Sunlight,
        com: &Vec3,
    ) -> Vec3 {
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
            forces.add_wrench(i, Force::new(self.facets.at(k).cross(&lin), lin));
            self.modes.add(k, &lin, &mut forces.elastic);
            moment += (self.facets.centroid(k) - com).cross(&f);
        }
        ctx.attitude.inverse_transform_vector(&moment)
    }

    /// The Earth's light on the placed facets (see the module's documentation), added to
    /// `forces`; its moment about `com`, bus axes. `r_sun`: the Sun from the Earth's centre
    /// (m, GCRF).
    fn earth_loads(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        earth: &EarthRadiation,
        orbit: &OrbitState,
        r_sun: &Vec3,
        com: &Vec3,
    ) -> Vec3 {
        let exitance = earth.exitance(&orbit.r, r_sun).total();
        let r = orbit.r.norm();
        if exitance <= 0.0 || r <= 0.0 || r.is_nan() {
            return Vec3::zeros();
        }
        let nadir = -orbit.r / r;
        if self.self_shadowing {
            self.facets.shade(&nadir, self.resolution);
        } else {
            self.facets.shade_none(&nadir);
        }
        // The cap's moments by their table (within 1e-6 (R/r)² of the exact sums): the
        // altitude's part once, each facet's tilt in the loop.
        let cap_at = CapTable::shared().at_altitude(r / R_EARTH);
        let m = exitance / SPEED_OF_LIGHT;
        let mut moment = Vec3::zeros();
        for k in 0..self.facets.len() {
            let n = *self.facets.normal(k);
            let cap = cap_at.moments(&n, &nadir);
            if cap.irradiance <= 0.0 {
                continue;
            }
            // Shaded as from the nadir when facing it; lit by the cap's edge only, unshaded.
            let lit = if n.dot(&nadir) > 0.0 {
                self.facets.lit(k)
            } else {
                1.0
            };
            if lit <= 0.0 {
                continue;
            }
            let facet = self.facets.facet(k);
            let f = earth_plate_force(&cap, &n, lit * facet.area, facet.specular, facet.diffuse, m);
            let i = self.facets.body(k);
            let lin = ctx.data.rotation[i].tr_mul(&f);
            forces.add_wrench(i, Force::new(self.facets.at(k).cross(&lin), lin));
            self.modes.add(k, &lin, &mut forces.elastic);
            moment += (self.facets.centroid(k) - com).cross(&f);
        }
        ctx.attitude.inverse_transform_vector(&moment)
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
    /// Whether the Earth's reflected and emitted light pushes the facets too (default
    /// false).
    #[serde(default)]
    pub albedo: Option<bool>,
    /// The Earth's uniform albedo, in [0, 1] (default 0.3; with `albedo = true` only).
    #[serde(default)]
    pub albedo_coefficient: Option<Spanned<f64>>,
    /// The Earth's emitted infrared flux (W/m², from 0 to 1000; default 237; with
    /// `albedo = true` only).
    #[serde(default)]
    pub earth_ir: Option<Spanned<f64>>,
}

impl SolarRadiationFile {
    /// The Earth's light model the keys ask for: `None` without `albedo = true`; an error at
    /// a key's place for a value out of its range, or for `albedo_coefficient` or `earth_ir`
    /// without `albedo = true`.
    fn earth_radiation(&self, section: &Section) -> Result<Option<EarthRadiation>, FileError> {
        let on = self.albedo.unwrap_or(false);
        let read = |key: &str, value: &Option<Spanned<f64>>, default: f64, max: f64, unit: &str| {
            let Some(v) = value else {
                return Ok(default);
            };
            if !on {
                return Err(section.error(
                    Some(v.span()),
                    format!(
                        "`effects.solar_radiation.{key}` applies only with `albedo = true` (the Earth's light is off)"
                    ),
                ));
            }
            let x = *v.get_ref();
            if !(0.0..=max).contains(&x) {
                return Err(section.error(
                    Some(v.span()),
                    format!(
                        "`effects.solar_radiation.{key}` must be between 0 and {max}{unit}, got {x}"
                    ),
                ));
            }
            Ok(x)
        };
        let albedo = read(
            "albedo_coefficient",
            &self.albedo_coefficient,
            ALBEDO,
            1.0,
            "",
        )?;
        let infrared = read("earth_ir", &self.earth_ir, EARTH_IR, 1000.0, " W/m²")?;
        Ok(on.then_some(EarthRadiation { albedo, infrared }))
    }
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
        let earth = file.earth_radiation(section)?;
        let facets = Facets::of_section(section)?;
        let self_shadowing = file.self_shadowing.unwrap_or(false);
        // With the Earth's light, two shading passes per right-hand side (the Sun's, the
        // nadir's).
        let passes = if earth.is_some() { 2.0 } else { 1.0 };
        if self_shadowing
            && let Some(pass) =
                Facets::shade_estimate(section.model(), resolution, SHADE_WARNING / passes)
            && pass * passes >= SHADE_WARNING
        {
            let seconds = pass * passes;
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
        Ok(
            SolarRadiation::new(section.epoch()?, shadow, self_shadowing, resolution, facets)
                .with_earth_radiation(earth),
        )
    }
}
