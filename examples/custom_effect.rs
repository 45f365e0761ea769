//! Adding an effect from outside satsim: a magnetic torquer, a coil of fixed dipole moment
//! `m` (bus axes) in the Earth's magnetic field, which turns the bus with the torque
//! `τ = m × B`.
//!
//! Everything the effect needs lives in this one file: the physics ([`Effect`]), its scene
//! section `[effects.magnetic_torquer]` (a serde struct) and its construction from it
//! ([`SceneEffect`]). It is registered next to the built-in effects, exactly as they are
//! registered, and `examples/scenes/magnetic_torquer.toml` uses it.
//!
//! `cargo run --release --example custom_effect` runs that scene; `cargo test --release
//! --example custom_effect` checks the turn against the analytic one.
//!
//! Field model: a centred dipole aligned with the Earth's axis (inertial z, the Earth's
//! rotation ignored), `B(r) = μ0/(4π r³) (3 (m_E·r̂) r̂ − m_E)` with `m_E = −M_E ẑ`
//! (the field points north at the equator). SI units; the torque acts on the root body.

use satsim::integrate::{Output, SystemError};
use satsim::spacecraft::effects::{Context, Effect, Forces, Needs, Registry, SceneEffect, Section};
use satsim::tools::scene::Scene;
use satsim::tree::io::FileError;
use satsim::tree::spatial::{Force, Vec3};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// μ0/4π (T m/A).
const MU0_4PI: f64 = 1e-7;
/// The Earth's dipole moment (A m²).
const EARTH_DIPOLE: f64 = 7.94e22;

/// The Earth's dipole field at `r` (m, inertial), inertial axes (T).
fn earth_field(r: Vec3) -> Vec3 {
    let d = r.norm();
    let u = r / d;
    let m_e = Vec3::new(0.0, 0.0, -EARTH_DIPOLE);
    MU0_4PI / (d * d * d) * (3.0 * m_e.dot(&u) * u - m_e)
}

/// A magnetic torquer of fixed dipole moment.
#[derive(Clone, Debug)]
pub struct MagneticTorquer {
    /// Dipole moment, bus axes (A m²).
    pub dipole: Vec3,
}

impl MagneticTorquer {
    /// The torque on the bus (bus axes, N m) in this context.
    fn torque(&self, ctx: &Context) -> Result<Vec3, SystemError> {
        let orbit = ctx.orbit_or_err("magnetic_torquer")?;
        let b_bus = ctx.attitude.inverse_transform_vector(&earth_field(orbit.r));
        Ok(self.dipole.cross(&b_bus))
    }
}

impl Effect for MagneticTorquer {
    fn name(&self) -> &str {
        "magnetic_torquer"
    }
    fn needs(&self) -> Needs {
        Needs {
            orbit: true,
            free_base: true,
            ..Needs::default()
        }
    }
    fn apply(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        _own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        let tau = self.torque(ctx)?;
        // A pure couple on the root body (body 0), about its origin.
        forces.add_wrench(0, Force::new(tau, Vec3::zeros()));
        Ok(())
    }
    fn output_columns(&self) -> Vec<String> {
        ["x", "y", "z"].map(|a| format!("mtq_torque_{a}")).into()
    }
    fn output(&self, ctx: &Context, _own: &[f64], row: &mut Vec<f64>) {
        let tau = self.torque(ctx).unwrap_or(Vec3::repeat(f64::NAN));
        row.extend_from_slice(tau.as_slice());
    }
}

/// `[effects.magnetic_torquer]` as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MagneticTorquerFile {
    /// Dipole moment, bus axes (A m²).
    dipole: Spanned<[f64; 3]>,
    /// Off without removing the section (default true).
    #[serde(default)]
    #[allow(dead_code)] // read by the scene reader from the raw section
    enabled: Option<bool>,
}

impl SceneEffect for MagneticTorquer {
    const SECTION: &'static str = "magnetic_torquer";
    type File = MagneticTorquerFile;
    fn from_section(file: MagneticTorquerFile, section: &Section) -> Result<Self, FileError> {
        let dipole = Vec3::from(*file.dipole.get_ref());
        if !dipole.iter().all(|x| x.is_finite()) {
            return Err(section.error(
                Some(file.dipole.span()),
                "`effects.magnetic_torquer.dipole` must be finite (A m²)",
            ));
        }
        Ok(MagneticTorquer { dipole })
    }
}

/// The built-in effects and the magnetic torquer.
fn registry() -> Registry {
    let mut registry = Registry::with_builtins();
    registry.register::<MagneticTorquer>();
    registry
}

fn scene_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/magnetic_torquer.toml")
}

/// Output columns and the rows at the output times.
type Table = (Vec<String>, Vec<Vec<f64>>);

/// Runs `scene`.
fn run(scene: &Scene) -> Result<Table, Box<dyn std::error::Error>> {
    let mut sim = scene.simulation()?;
    let columns = sim.columns();
    let mut rows = Vec::new();
    sim.run(
        &scene.options,
        scene.duration,
        &Output::Interval(scene.every),
        |_, row| {
            rows.push(row.to_vec());
            Ok::<(), std::convert::Infallible>(())
        },
    )?;
    Ok((columns, rows))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scene = Scene::read_with_registry(scene_path(), &registry())?;
    let (columns, rows) = run(&scene)?;
    let col = |name: &str| columns.iter().position(|c| c == name).unwrap();
    println!(
        "effects: {}",
        scene.effects.names().collect::<Vec<_>>().join(", ")
    );
    println!("{:>6} {:>12} {:>14}", "t (s)", "omega_y", "torque_y (N m)");
    for row in &rows {
        println!(
            "{:6.1} {:12.4e} {:14.6e}",
            row[col("t")],
            row[col("omega_y")],
            row[col("mtq_torque_y")]
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On the equator the field is `B = μ0 M_E/(4π r³) ẑ` all along the orbit; the dipole
    /// `m x̂` then turns the bus about `y` like a pendulum from rest,
    /// `θ̈ = −(m B / I) cos θ` (θ the turn about y, from 0). For a small turn
    /// `ω_y(t) = −(m B/I) t` and `θ(t) = −½ (m B/I) t²`, up to a relative `θ²/2 ≈ 1e-4`.
    #[test]
    fn the_torquer_turns_the_bus_by_the_analytic_amount() {
        let scene = Scene::read_with_registry(scene_path(), &registry()).unwrap();
        let (columns, rows) = run(&scene).unwrap();
        let col = |name: &str| columns.iter().position(|c| c == name).unwrap();
        let last = rows.last().unwrap();
        let t = last[col("t")];
        let r = 6_378_137.0 + 500e3;
        let alpha = 100.0 * MU0_4PI * EARTH_DIPOLE / (r * r * r) / 10.0;
        let omega_y = last[col("omega_y")];
        assert!(
            (omega_y + alpha * t).abs() < 1e-3 * alpha * t,
            "ω_y = {omega_y}, analytic {}",
            -alpha * t
        );
        // The turn: q = (cos θ/2, 0, sin θ/2, 0).
        let theta = 2.0 * last[col("q_y")].atan2(last[col("q_w")]);
        let expected = -0.5 * alpha * t * t;
        assert!(
            (theta - expected).abs() < 1e-3 * expected.abs(),
            "θ = {theta}, analytic {expected}"
        );
        // Nothing else turns the bus.
        assert!(last[col("omega_x")].abs() < 1e-12 && last[col("omega_z")].abs() < 1e-12);
    }

    #[test]
    fn without_the_torquer_the_bus_stays_put_and_unknown_sections_are_refused() {
        let text = std::fs::read_to_string(scene_path()).unwrap();
        let off = text.replace(
            "\n[effects.magnetic_torquer]\n",
            "\n[effects.magnetic_torquer]\nenabled = false\n",
        );
        assert_ne!(off, text);
        let scene = Scene::parse_with_registry(&off, &scene_path(), &registry()).unwrap();
        let (columns, rows) = run(&scene).unwrap();
        let w = columns.iter().position(|c| c == "omega_y").unwrap();
        assert_eq!(rows.last().unwrap()[w], 0.0);
        // The built-in registry does not know the section: an error naming file and line.
        let e = Scene::parse(&text, &scene_path()).unwrap_err().to_string();
        assert!(
            e.contains("magnetic_torquer.toml:25")
                && e.contains("unknown key `magnetic_torquer` in [effects]")
                && e.contains("hinge_springs"),
            "{e}"
        );
    }
}
