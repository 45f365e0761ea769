//! Aerodynamic drag on every facet of every body (contract section 12).
//!
//! Per facet of area `A`, outward unit normal `n` and drag coefficient `C_D`, with `v` the
//! velocity of the facet's centroid relative to the atmosphere, `v̂ = v/|v|` and
//! `cos α = n·v̂ > 0` (the facet meets the flow on its normal's side):
//!
//! `F = −½ ρ |v|² C_D A cos α v̂`
//!
//! at the centroid. `v` is the orbit's velocity plus the centroid's own velocity in the
//! frame falling with the centre of mass (the bus turning, a panel deploying), minus, when
//! the atmosphere turns with the Earth (`co_rotating`, the default), `ω_E × r` at the
//! centroid's position `r`. The density is the atmosphere's at the centre of mass (over a
//! spacecraft's size it changes by 1e-4 of itself per 10 m at 500 km): the exponential
//! atmosphere (Vallado's Table 8-4, [`satsim_environment::atmosphere::exponential`], the
//! default), or NRLMSISE-00 (`atmosphere = "nrlmsise00"`,
//! [`satsim_environment::atmosphere::nrlmsise`]) with the solar flux and Ap given as
//! constants (`f107`, `f107a`, `ap`: 150, 150, 4 unless given; the model's daily-Ap mode) or
//! read from a space-weather file (`space_weather`, CelesTrak's CSV, a path from the scene
//! file's folder; the 7-element Ap history), through its lattice of `density_step` seconds
//! (300 unless given; 0: the model at every call). Facets do not shield each other from the
//! flow.
//!
//! Output: `density` (kg/m³) and `drag_torque_x/y/z`, the moment of all the facets' forces
//! about the spacecraft's centre of mass, bus axes (N m).
//!
//! Energy: the power of the drag forces on the motion in the falling frame (the bodies'
//! own velocities `u` at the centroids) is split in two. The steady flow (the orbit's
//! velocity and the Earth's rotation alone, `V`) does the work `Σ F(V)·u`, booked as an
//! actuator's: the wind that turns a panel. The rest, `Σ (F(V + u) − F(V))·u`, the damping
//! by the bodies' own motion through the air, is booked as dissipation.

use super::facets::Facets;
use super::modal_loads::FacetModes;
use super::{Context, Effect, Forces, Links, Needs, Power, SceneEffect, Section};
use satsim_environment::Epoch;
use satsim_environment::atmosphere::density;
use satsim_environment::atmosphere::nrlmsise::{Drivers, Msis, MsisTrack};
use satsim_environment::atmosphere::space_weather::{SpaceWeather, date_text, day_and_seconds};
use satsim_environment::earth::earth_rotation_gcrf;
use satsim_integrate::SystemError;
use satsim_tree::io::FileError;
use satsim_tree::spatial::{Force, Vec3};
use serde::Deserialize;
use std::sync::Arc;
use toml::Spanned;

/// Which atmosphere.
#[derive(Clone, Debug, Default)]
pub enum Atmosphere {
    /// The exponential atmosphere of Vallado's Table 8-4.
    #[default]
    Exponential,
    /// NRLMSISE-00 on its lattice along the run.
    Nrlmsise00(Box<MsisTrack>),
}

/// The lattice's spacing in time (s) unless `density_step` is given.
pub const DENSITY_STEP: f64 = 300.0;

/// The drag effect.
#[derive(Clone, Debug)]
pub struct Drag {
    atmosphere: Atmosphere,
    /// `Some(epoch)`: the atmosphere turns with the Earth (the pole's direction of date from
    /// the epoch); `None`: it is at rest in the inertial frame.
    co_rotating: Option<Epoch>,
    facets: Facets,
    density: f64,
    torque: Vec3,
    /// `Σ F(V)·u` at the last `apply` (W): the steady flow's work rate (see the module docs).
    flow_power: f64,
    /// Each facet's mean mode shapes, on a flexible body (set by `connect`).
    modes: FacetModes,
}

/// The drag force (N) on a flat surface of area `area`, outward unit normal `n` and drag
/// coefficient `cd`, moving at `v` (m/s) through air of density `rho` (kg/m³): zero when
/// the surface faces away from the flow it meets.
///
/// ```
/// use satsim_spacecraft::effects::drag::plate_force;
/// use satsim_tree::spatial::Vec3;
/// // A plate moving along its normal at 7.6 km/s.
/// let f = plate_force(&Vec3::new(7600.0, 0.0, 0.0), &Vec3::x(), 1.0, 2.2, 1e-12);
/// assert!((f.x + 0.5 * 1e-12 * 7600.0f64.powi(2) * 2.2).abs() < 1e-18);
/// ```
pub fn plate_force(v: &Vec3, n: &Vec3, area: f64, cd: f64, rho: f64) -> Vec3 {
    #[cfg(test)]
    tests::PLATES.with(|k| k.set(k.get() + 1));
    let speed = v.norm();
    if speed == 0.0 {
        return Vec3::zeros();
    }
    let vh = v / speed;
    let c = n.dot(&vh);
    if c <= 0.0 {
        return Vec3::zeros();
    }
    -0.5 * rho * speed * speed * cd * area * c * vh
}

impl Drag {
    /// Drag on `facets` in `atmosphere`; `co_rotating`: the epoch, when the atmosphere
    /// turns with the Earth.
    pub fn new(atmosphere: Atmosphere, co_rotating: Option<Epoch>, facets: Facets) -> Self {
        Self {
            atmosphere,
            co_rotating,
            facets,
            density: 0.0,
            torque: Vec3::zeros(),
            flow_power: 0.0,
            modes: FacetModes::default(),
        }
    }
    /// The density (kg/m³) at time `t` (s) at `r` (m, GCRF, from the Earth's centre): the
    /// value a run's `density` column holds there, bit for bit (NRLMSISE-00's lattice is a
    /// function of `(t, r)` alone); the error says what the model lacks.
    pub fn density(&self, t: f64, r: &Vec3) -> Result<f64, SystemError> {
        match &self.atmosphere {
            Atmosphere::Exponential => Ok(density(r.norm())),
            Atmosphere::Nrlmsise00(track) => track
                .as_ref()
                .clone()
                .density(t, r)
                .map_err(|m| SystemError::new(format!("drag: {m}"))),
        }
    }
    /// The density at the last evaluation (kg/m³).
    pub fn last_density(&self) -> f64 {
        self.density
    }
}

impl Effect for Drag {
    fn connect(&mut self, links: &Links) {
        self.modes = FacetModes::new(
            links.flex,
            (0..self.facets.len()).map(|k| (self.facets.body(k), self.facets.facet(k))),
        );
    }
    fn name(&self) -> &str {
        "drag"
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
        let orbit = ctx.orbit_or_err("drag")?;
        let com = ctx.com_or_err("drag")?;
        self.density = match &mut self.atmosphere {
            Atmosphere::Exponential => density(orbit.r.norm()),
            Atmosphere::Nrlmsise00(track) => track
                .density(ctx.t, &orbit.r)
                .map_err(|m| SystemError::new(format!("drag: {m}")))?,
        };
        let earth = match self.co_rotating {
            Some(epoch) => earth_rotation_gcrf(epoch, ctx.t),
            None => Vec3::zeros(),
        };
        let modes = &self.modes;
        self.facets
            .place_deflected(ctx.data, |k| modes.deflection(k, ctx.eta));
        let mut moment = Vec3::zeros();
        let mut flow_power = 0.0;
        for k in 0..self.facets.len() {
            let facet = self.facets.facet(k);
            let (i, at) = (self.facets.body(k), *self.facets.at(k));
            let rot = &ctx.data.rotation[i];
            // The centroid's velocity in the falling frame (body axes, then inertial), its
            // deflection's rate included.
            let vb = &ctx.data.v[i];
            let bending = self
                .modes
                .deflection(k, ctx.etadot)
                .map_or(Vec3::zeros(), |(u, _)| u);
            let own = rot * (vb.lin + vb.ang.cross(&at) + bending);
            let c = self.facets.centroid(k) - com;
            let flow = orbit.v - earth.cross(&(orbit.r + c));
            let (n, area, cd) = (self.facets.normal(k), facet.area, facet.drag);
            let f = plate_force(&(flow + own), n, area, cd, self.density);
            // The steady flow's force only for the energy budget: nothing else reads it.
            if ctx.power {
                flow_power += plate_force(&flow, n, area, cd, self.density).dot(&own);
            }
            if f == Vec3::zeros() {
                continue;
            }
            let lin = rot.tr_mul(&f);
            forces.add_wrench(i, Force::new(at.cross(&lin), lin));
            self.modes.add(k, &lin, &mut forces.elastic);
            moment += c.cross(&f);
        }
        self.torque = ctx.attitude.inverse_transform_vector(&moment);
        self.flow_power = flow_power;
        Ok(())
    }
    /// The steady flow's work is an actuator's, the rest dissipation (see the module docs).
    fn power(&self, _ctx: &Context, _own: &[f64], applied: f64) -> Power {
        Power {
            actuator: self.flow_power,
            dissipated: self.flow_power - applied,
        }
    }
    fn output_columns(&self) -> Vec<String> {
        ["density", "drag_torque_x", "drag_torque_y", "drag_torque_z"]
            .map(String::from)
            .into()
    }
    fn output(&self, _ctx: &Context, _own: &[f64], row: &mut Vec<f64>) {
        row.push(self.density);
        row.extend_from_slice(self.torque.as_slice());
    }
}

/// `[effects.drag]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DragFile {
    /// `"exponential"` (default) or `"nrlmsise00"`.
    #[serde(default)]
    pub atmosphere: Option<Spanned<String>>,
    /// NRLMSISE-00: the previous day's F10.7 (sfu, default 150).
    #[serde(default)]
    pub f107: Option<Spanned<f64>>,
    /// NRLMSISE-00: the 81-day centred mean of F10.7 (sfu, default 150).
    #[serde(default)]
    pub f107a: Option<Spanned<f64>>,
    /// NRLMSISE-00: the daily Ap (default 4).
    #[serde(default)]
    pub ap: Option<Spanned<f64>>,
    /// NRLMSISE-00: a CelesTrak space-weather CSV (from the scene file's folder), in place
    /// of `f107`, `f107a` and `ap`.
    #[serde(default)]
    pub space_weather: Option<Spanned<String>>,
    /// NRLMSISE-00: the lattice's spacing in time (s, default 300; 0: the model at every
    /// call).
    #[serde(default)]
    pub density_step: Option<Spanned<f64>>,
    /// Whether the atmosphere turns with the Earth (default true; needs the scene's epoch).
    #[serde(default)]
    pub co_rotating: Option<bool>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

impl SceneEffect for Drag {
    const SECTION: &'static str = "drag";
    type File = DragFile;
    fn from_section(file: DragFile, section: &Section) -> Result<Self, FileError> {
        let atmosphere = match &file.atmosphere {
            None => Atmosphere::Exponential,
            Some(a) if a.get_ref() == "exponential" => Atmosphere::Exponential,
            Some(a) if a.get_ref() == "nrlmsise00" => {
                Atmosphere::Nrlmsise00(Box::new(msis_of_section(&file, section)?))
            }
            Some(a) => {
                return Err(section.error(
                    Some(a.span()),
                    format!(
                        "`effects.drag.atmosphere`: unknown value `{}`, expected \"exponential\" or \"nrlmsise00\"",
                        a.get_ref()
                    ),
                ));
            }
        };
        if !matches!(atmosphere, Atmosphere::Nrlmsise00(_)) {
            let keys = [
                ("f107", file.f107.as_ref().map(Spanned::span)),
                ("f107a", file.f107a.as_ref().map(Spanned::span)),
                ("ap", file.ap.as_ref().map(Spanned::span)),
                (
                    "space_weather",
                    file.space_weather.as_ref().map(Spanned::span),
                ),
                (
                    "density_step",
                    file.density_step.as_ref().map(Spanned::span),
                ),
            ];
            if let Some((key, span)) = keys.into_iter().find(|k| k.1.is_some()) {
                return Err(section.error(
                    span,
                    format!(
                        "`effects.drag.{key}` is NRLMSISE-00's: it needs `atmosphere = \"nrlmsise00\"`"
                    ),
                ));
            }
        }
        let facets = Facets::of_section(section)?;
        let co_rotating = match file.co_rotating.unwrap_or(true) {
            true => Some(section.epoch()?),
            false => None,
        };
        Ok(Drag::new(atmosphere, co_rotating, facets))
    }
}

/// NRLMSISE-00 as `[effects.drag]` sets it up: the drivers (constants, or the space-weather
/// file, every day the run reads checked now) and the lattice's step.
fn msis_of_section(file: &DragFile, section: &Section) -> Result<MsisTrack, FileError> {
    let epoch = section.epoch()?;
    let at = |x: &Spanned<f64>, m: String| section.error(Some(x.span()), m);
    let step = match &file.density_step {
        None => DENSITY_STEP,
        Some(x) => section.non_negative(x, "effects.drag.density_step")?,
    };
    let drivers = match &file.space_weather {
        Some(path) => {
            if let Some((key, x)) = [
                ("f107", &file.f107),
                ("f107a", &file.f107a),
                ("ap", &file.ap),
            ]
            .into_iter()
            .find_map(|(k, x)| x.as_ref().map(|x| (k, x)))
            {
                return Err(at(
                    x,
                    format!(
                        "`effects.drag.{key}`: give either `space_weather` or `f107`, `f107a` and `ap`, not both"
                    ),
                ));
            }
            let here = |m: String| {
                section.error(
                    Some(path.span()),
                    format!("`effects.drag.space_weather`: {m}"),
                )
            };
            let full = section
                .path()
                .parent()
                .unwrap_or(std::path::Path::new(""))
                .join(path.get_ref());
            let table = SpaceWeather::read(&full).map_err(here)?;
            // The days the run reads: to its end and the lattice's next knot past it.
            let duration = match section.document() {
                Some(doc) => Duration::deserialize(doc.only(&["duration"])).ok(),
                None => toml::from_str::<Duration>(section.text()).ok(),
            }
            .and_then(|d| d.duration)
            .filter(|d| d.is_finite() && *d >= 0.0)
            .unwrap_or(0.0);
            let start = epoch.to_utc_seconds();
            let (first, _) = day_and_seconds(start);
            let (last, _) = day_and_seconds(start + duration + step);
            table.check_days(first, last).map_err(|m| {
                here(format!(
                    "{m} (a run from {} to {} reads the days from {} on)",
                    date_text(first),
                    date_text(last),
                    date_text(first - 3)
                ))
            })?;
            Drivers::Table(Arc::new(table))
        }
        None => {
            let value = |x: &Option<Spanned<f64>>, key: &str, default: f64, max: f64| {
                let Some(x) = x else { return Ok(default) };
                // F10.7 is above 0 (its "> 0" refuses 0 and the negatives alike), Ap from 0.
                let v = if key == "ap" {
                    section.non_negative(x, &format!("effects.drag.{key}"))?
                } else {
                    section.positive(x, &format!("effects.drag.{key}"))?
                };
                if v > max {
                    return Err(at(
                        x,
                        format!(
                            "`effects.drag.{key}` is {v}: NRLMSISE-00 takes {} up to {max}",
                            if key == "ap" { "from 0" } else { "above 0" }
                        ),
                    ));
                }
                Ok(v)
            };
            Drivers::Constant {
                f107: value(&file.f107, "f107", 150.0, 1000.0)?,
                f107a: value(&file.f107a, "f107a", 150.0, 1000.0)?,
                ap: value(&file.ap, "ap", 4.0, 400.0)?,
            }
        }
    };
    Ok(MsisTrack::new(Msis::new(epoch, drivers), step))
}

/// The scene's `duration`, which says which days a space-weather file must hold.
#[derive(Deserialize)]
struct Duration {
    duration: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::orbit::{Elements, Orbit, OrbitModel};
    use crate::simulation::Simulation;
    use satsim_integrate::System;
    use satsim_tree::spatial::Mat3;
    use satsim_tree::{BaseKind, Body, BoxShape, ModelBuilder, facets_of_box};
    use std::cell::Cell;

    thread_local! {
        /// Calls of [`plate_force`] on this thread.
        pub(super) static PLATES: Cell<usize> = const { Cell::new(0) };
    }

    #[test]
    fn each_facet_is_evaluated_once_per_rhs_unless_the_energy_budget_asks_for_the_flows() {
        let shape = BoxShape::new(Vec3::new(1.0, 2.0, 3.0));
        let model = ModelBuilder::new(BaseKind::Free)
            .body(
                Body::new("bus", 100.0, 10.0 * Mat3::identity())
                    .with_facets(facets_of_box(&shape, &Vec3::zeros())),
            )
            .build()
            .unwrap();
        let rhs = |budget: bool| {
            let mut sim = Simulation::builder(model.clone())
                .effect(Orbit::from_elements(
                    OrbitModel::Kepler,
                    &Elements::circular(6.778e6, 0.9),
                ))
                .effect(Drag::new(
                    Atmosphere::Exponential,
                    None,
                    Facets::of_model(&model),
                ))
                .energy_budget(budget)
                .build()
                .unwrap();
            let mut x = sim.x0().to_vec();
            // The bus turning: its facets' own velocities add to the flow's.
            x[sim.layout().omega.clone()].copy_from_slice(&[0.01, -0.02, 0.03]);
            let mut dx = vec![0.0; x.len()];
            PLATES.with(|k| k.set(0));
            sim.rhs(0.0, &x, &mut dx).unwrap();
            (PLATES.with(Cell::get), sim.layout().clone(), dx)
        };
        let (plain, layout, dx) = rhs(false);
        let (budget, with_layout, dx_budget) = rhs(true);
        assert_eq!(plain, 6, "one plate per facet");
        assert_eq!(budget, 12, "and the steady flow's for the budget");
        // The same motion, bit for bit (the budget's states come after it).
        assert_eq!(dx[..layout.len], dx_budget[..layout.len]);
        assert!(with_layout.len >= layout.len);
    }

    /// `[effects.drag]` of `text` (a scene at `path`, epoch `epoch`) on a 1 m x 2 m x 3 m box,
    /// read from the text and from the text parsed once as the scene reader parses it: the
    /// same outcome both ways.
    fn read(text: &str, path: &std::path::Path, epoch: Option<Epoch>) -> Result<Drag, FileError> {
        use super::super::section::SceneText;
        let model = boxed_model();
        let doc = satsim_tree::io::Document::parse(text);
        let scenes = [
            Some(SceneText::new(text, path)),
            doc.as_ref().ok().map(|d| SceneText::parsed(d, path)),
        ];
        let mut read = scenes.into_iter().flatten().map(|scene| {
            let section =
                Section::new(scene, "drag", 0..text.len(), &model, true).with_epoch(epoch);
            let file = scene
                .effect_section::<DragFile>("drag")?
                .unwrap()
                .into_inner();
            Drag::from_section(file, &section)
        });
        let first = read.next().unwrap();
        for other in read {
            assert_eq!(format!("{other:?}"), format!("{first:?}"));
        }
        first
    }

    fn boxed_model() -> satsim_tree::Model {
        let shape = BoxShape::new(Vec3::new(1.0, 2.0, 3.0));
        ModelBuilder::new(BaseKind::Free)
            .body(
                Body::new("bus", 100.0, 10.0 * Mat3::identity())
                    .with_facets(facets_of_box(&shape, &Vec3::zeros())),
            )
            .build()
            .unwrap()
    }

    /// The folder of the environment's fixtures, where the space-weather fixture lies.
    fn fixtures() -> std::path::PathBuf {
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../environment/fixtures")
    }

    #[test]
    fn nrlmsise00_runs_and_its_density_column_is_the_models_at_each_row() {
        let epoch = satsim_environment::parse_epoch("2024-05-11T03:00:00 UTC").unwrap();
        let path = fixtures().join("scene.toml");
        let constant = "duration = 600.0\n[effects.drag]\natmosphere = \"nrlmsise00\"\nf107 = 180.0\nap = 15.0\n";
        let table = "duration = 600.0\n[effects.drag]\natmosphere = \"nrlmsise00\"\nspace_weather = \"msis_space_weather.csv\"\ndensity_step = 30.0\n";
        let mut seen = Vec::new();
        for text in [constant, table] {
            let drag = read(text, &path, Some(epoch)).unwrap();
            let Atmosphere::Nrlmsise00(track) = &drag.atmosphere else {
                panic!("not NRLMSISE-00")
            };
            let msis = track.msis().clone();
            let model = boxed_model();
            let mut sim = Simulation::builder(model.clone())
                .effect(Orbit::from_elements(
                    OrbitModel::Kepler,
                    &Elements::circular(6.778e6, 0.9),
                ))
                .effect(drag.clone())
                .build()
                .unwrap();
            let columns = sim.columns();
            let at = |name: &str| columns.iter().position(|c| c == name).unwrap();
            let (rho, rx) = (at("density"), at("orbit_r_x"));
            let mut rows = Vec::new();
            sim.run(
                &satsim_integrate::Options::default(),
                600.0,
                &satsim_integrate::Output::Interval(60.0),
                |t, row| {
                    rows.push((t, row[rho], Vec3::new(row[rx], row[rx + 1], row[rx + 2])));
                    Ok::<(), ()>(())
                },
            )
            .unwrap();
            assert_eq!(rows.len(), 11);
            for (t, column, r) in rows {
                // What `satsim environment` reports there: the same bits.
                assert_eq!(drag.density(t, &r).unwrap(), column, "t = {t}");
                // The model itself, off the lattice by its interpolation only.
                let direct = msis.density(t, &r).unwrap();
                assert!(
                    (column / direct - 1.0).abs() < 5e-4,
                    "t = {t}: {column} vs {direct}"
                );
            }
            seen.push(drag.density(0.0, &Vec3::new(6.778e6, 0.0, 0.0)).unwrap());
        }
        // The storm the file holds (Ap 207 in the hour) raises the density over Ap 15's.
        assert!(seen[1] > 1.2 * seen[0], "{seen:?}");
    }

    #[test]
    fn nrlmsise00_refuses_what_it_cannot_use_naming_the_file_and_line() {
        let epoch = satsim_environment::parse_epoch("2024-05-11T03:00:00 UTC").ok();
        let path = fixtures().join("scene.toml");
        let err = |text: &str, epoch: Option<Epoch>| {
            let head = "duration = 600.0\n[effects.drag]\natmosphere = \"nrlmsise00\"\n";
            read(&format!("{head}{text}"), &path, epoch)
                .unwrap_err()
                .to_string()
        };
        let m = err("", None);
        assert!(m.contains("epoch"), "{m}");
        let m = err("space_weather = \"nowhere.csv\"\n", epoch);
        assert!(
            m.contains("scene.toml:4") && m.contains("nowhere.csv") && m.contains("cannot be read"),
            "{m}"
        );
        // A day the run reads that the file lacks: the date named.
        let late = satsim_environment::parse_epoch("2024-05-12T23:59:00 UTC").ok();
        let m = err("space_weather = \"msis_space_weather.csv\"\n", late);
        assert!(
            m.contains("msis_space_weather.csv:7:") && m.contains("`AP_AVG`"),
            "{m}"
        );
        // The days to the run's end: 2024-05-13 lacks its `AP_AVG` too.
        let m = read(
            "duration = 172800.0\n[effects.drag]\natmosphere = \"nrlmsise00\"\nspace_weather = \"msis_space_weather.csv\"\n",
            &path,
            epoch,
        )
        .unwrap_err()
        .to_string();
        assert!(
            m.contains("msis_space_weather.csv:7:") && m.contains("reads the days"),
            "{m}"
        );
        let early = satsim_environment::parse_epoch("2024-05-10T00:00:00 UTC").ok();
        let m = err("space_weather = \"msis_space_weather.csv\"\n", early);
        assert!(m.contains("no row for 2024-05-07"), "{m}");
        let m = err(
            "space_weather = \"msis_space_weather.csv\"\nap = 4.0\n",
            epoch,
        );
        assert!(m.contains("scene.toml:5") && m.contains("not both"), "{m}");
        let m = err("ap = 500.0\n", epoch);
        assert!(m.contains("scene.toml:4") && m.contains("up to 400"), "{m}");
        // Zero and the negatives alike: "> 0", as the reference says.
        for f in ["f107 = 0.0\n", "f107 = -1.0\n", "f107a = 0.0\n"] {
            let m = err(f, epoch);
            assert!(m.contains("`effects.drag.f107") && m.contains("> 0"), "{m}");
        }
        let m = err("ap = -1.0\n", epoch);
        assert!(m.contains("`effects.drag.ap`") && m.contains(">= 0"), "{m}");
        let m = err("density_step = -1.0\n", epoch);
        assert!(m.contains("density_step"), "{m}");
        let m = read("[effects.drag]\nf107 = 100.0\n", &path, epoch)
            .unwrap_err()
            .to_string();
        assert!(
            m.contains("scene.toml:2") && m.contains("needs `atmosphere = \"nrlmsise00\"`"),
            "{m}"
        );
        let m = read("[effects.drag]\natmosphere = \"msis\"\n", &path, epoch)
            .unwrap_err()
            .to_string();
        assert!(m.contains("\"nrlmsise00\""), "{m}");
    }

    /// The cost of NRLMSISE-00 in a run: one orbit of the box at 400 km under RK4 at 0.1 s
    /// and at 1 s, with the exponential atmosphere, NRLMSISE-00 on its lattice and NRLMSISE-00
    /// at every call: `cargo test -p satsim-spacecraft --release --lib -- drag::tests::msis_run_cost --ignored --nocapture`.
    #[test]
    #[ignore = "a timing, not a check"]
    fn msis_run_cost() {
        use std::time::Instant;
        let epoch = satsim_environment::parse_epoch("2026-03-20T06:00:00 UTC").ok();
        let path = fixtures().join("scene.toml");
        let head = "[effects.drag]\n";
        for dt in [0.1, 1.0] {
            let mut times = Vec::new();
            for extra in [
                "",
                "atmosphere = \"nrlmsise00\"\n",
                "atmosphere = \"nrlmsise00\"\ndensity_step = 0.0\n",
            ] {
                let drag = read(&format!("{head}{extra}"), &path, epoch).unwrap();
                let model = boxed_model();
                let mut sim = Simulation::builder(model)
                    .effect(Orbit::from_elements(
                        OrbitModel::Kepler,
                        &Elements::circular(6.778e6, 0.9),
                    ))
                    .effect(drag)
                    .build()
                    .unwrap();
                let options = satsim_integrate::Options {
                    method: satsim_integrate::Method::Rk4,
                    fixed_step: Some(dt),
                    ..Default::default()
                };
                let start = Instant::now();
                let stats = sim
                    .run(
                        &options,
                        5560.0,
                        &satsim_integrate::Output::Interval(60.0),
                        |_, _| Ok::<(), ()>(()),
                    )
                    .unwrap();
                let per = start.elapsed().as_secs_f64() / stats.rhs_evals as f64;
                times.push(per);
                println!(
                    "dt {dt} s, drag {extra:?}: {:.3} us a right-hand side ({} of them)",
                    per * 1e6,
                    stats.rhs_evals
                );
            }
            println!(
                "dt {dt} s: NRLMSISE-00's share of a right-hand side {:.0} % on its lattice, {:.0} % at every call",
                100.0 * (times[1] - times[0]) / times[1],
                100.0 * (times[2] - times[0]) / times[2]
            );
        }
    }
}
