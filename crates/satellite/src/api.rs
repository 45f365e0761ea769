//! In-memory entry points shared by the `satsim` command line and the Python module: the
//! dynamics of one state (`satsim dynamics`, contract section 3) and a scene's whole
//! trajectory (`satsim run`, contract section 7) as columns and rows instead of a CSV file.
//!
//! Both call exactly the code the command line calls ([`crba`], [`bias`], [`aba`],
//! [`kinetic_energy`]; [`Scene::simulation`], [`Simulation::run`], [`Simulation::columns`]),
//! so their numbers equal the command line's to the last bit.
//!
//! Conventions are the contract's: generalised velocities `[ω (3), v (3), hinge rates]` for a
//! free base (root-body axes, Featherstone's angular-then-linear order), `[hinge rates]` for
//! a fixed base; SI units; quaternions Hamilton `[w, x, y, z]`.
//!
//! [`Simulation::columns`]: crate::simulation::Simulation::columns

use crate::scene::Scene;
use crate::simulation::{RunError, SimError};
use nalgebra::{DMatrix, DVector};
use satsim_integrate::Output as Times;
use satsim_tree::{Data, DynamicsError, Model, State, aba, bias, crba, kinetic_energy};
use std::fmt;
use thiserror::Error;

/// The dynamics of one state (contract section 3): `mass_matrix * acceleration + bias = tau`.
#[derive(Clone, Debug, PartialEq)]
pub struct Dynamics {
    /// Degrees of freedom (`nv`).
    pub dof: usize,
    /// Joint-space mass matrix `M(q)` (CRBA), `dof x dof`, symmetric.
    pub mass_matrix: DMatrix<f64>,
    /// Velocity-product terms `C(q, v) v` (RNEA with zero acceleration; no gravity, no
    /// external forces).
    pub bias: DVector<f64>,
    /// Forward dynamics (ABA): the solution of `M a + b = tau`; the base part is the
    /// body-frame derivative of `[ω, v]`.
    pub acceleration: DVector<f64>,
    /// Kinetic energy (J).
    pub kinetic_energy: f64,
}

/// Why [`dynamics`] produced no result.
#[derive(Debug, Error)]
pub enum DynamicsFailure {
    /// The engine failed (a singular configuration).
    #[error("{0}")]
    Engine(#[from] DynamicsError),
    /// A result overflowed to a non-finite number.
    #[error("the dynamics of this state overflow (a non-finite result)")]
    NonFinite,
}

/// The mass matrix, bias, forward-dynamics acceleration and kinetic energy of `state`.
/// Every number is finite, or the result is an error.
pub fn dynamics(model: &Model, state: &State) -> Result<Dynamics, DynamicsFailure> {
    let mut data = Data::new(model);
    let mass_matrix = crba(model, &mut data, &state.q)?.clone();
    let bias = bias(model, &mut data, &state.q, &state.v, None)?.clone();
    let acceleration = aba(model, &mut data, &state.q, &state.v, &state.tau, None)?.clone();
    let kinetic_energy = kinetic_energy(model, &mut data, &state.q, &state.v)?;
    let finite = mass_matrix
        .iter()
        .chain(bias.iter())
        .chain(acceleration.iter())
        .all(|x| x.is_finite())
        && kinetic_energy.is_finite();
    if !finite {
        return Err(DynamicsFailure::NonFinite);
    }
    Ok(Dynamics {
        dof: model.nv(),
        mass_matrix,
        bias,
        acceleration,
        kinetic_energy,
    })
}

/// A trajectory held in memory: the header and rows `satsim run` writes to `trajectory.csv`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trajectory {
    /// Column names ([`Simulation::columns`](crate::simulation::Simulation::columns)).
    pub columns: Vec<String>,
    /// The rows, one after the other (row-major, `columns.len()` values per row).
    pub values: Vec<f64>,
}

impl Trajectory {
    /// Number of rows.
    pub fn n_rows(&self) -> usize {
        self.values
            .len()
            .checked_div(self.columns.len())
            .unwrap_or(0)
    }

    /// The rows.
    pub fn rows(&self) -> impl Iterator<Item = &[f64]> {
        self.values.chunks_exact(self.columns.len().max(1))
    }

    /// The time of the last row.
    pub fn last_t(&self) -> Option<f64> {
        self.rows().last().map(|r| r[0])
    }
}

/// Why [`run_scene`] did not run to the end.
#[derive(Debug)]
pub enum RunFailure {
    /// The scene could not be set up (bad input: an effect's needs not met, a singular initial
    /// state…). `satsim run` exits with status 2.
    Setup(SimError),
    /// The run failed part-way; `partial` holds every row up to the failure. `satsim run`
    /// exits with status 1.
    Failed {
        /// Why (the integrator's or the dynamics' message).
        why: String,
        /// The rows written before the failure.
        partial: Trajectory,
    },
    /// The caller's `stop` asked to stop after the last row of `partial`.
    Stopped {
        /// The rows up to the stop.
        partial: Trajectory,
    },
}

impl fmt::Display for RunFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunFailure::Setup(e) => write!(f, "{e}"),
            RunFailure::Failed { why, .. } => write!(f, "the run failed: {why}"),
            RunFailure::Stopped { partial } => match partial.last_t() {
                Some(t) => write!(f, "stopped at t = {t} s"),
                None => f.write_str("stopped before the first row"),
            },
        }
    }
}

impl std::error::Error for RunFailure {}

/// Marker for a stop requested by the caller.
#[derive(Debug)]
struct StopRequested;

impl fmt::Display for StopRequested {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("stopped")
    }
}

/// Runs `scene` from its initial state to `t0 + duration` exactly as `satsim run` does (the
/// same [`Scene::simulation`], integrator options and output times) and keeps the rows in
/// memory. `stop` is called after every row; returning `true` ends the run there
/// ([`RunFailure::Stopped`]).
pub fn run_scene(scene: &Scene, mut stop: impl FnMut() -> bool) -> Result<Trajectory, RunFailure> {
    let mut sim = scene.simulation().map_err(RunFailure::Setup)?;
    let mut out = Trajectory {
        columns: sim.columns(),
        values: Vec::new(),
    };
    let t_end = sim.t0() + scene.duration;
    let result = sim.run(
        &scene.options,
        t_end,
        &Times::Interval(scene.every),
        |_, row| -> Result<(), StopRequested> {
            out.values.extend_from_slice(row);
            if stop() { Err(StopRequested) } else { Ok(()) }
        },
    );
    match result {
        Ok(_) => Ok(out),
        Err(RunError::Sink { .. }) => Err(RunFailure::Stopped { partial: out }),
        Err(RunError::Integrate(e)) => Err(RunFailure::Failed {
            why: e.to_string(),
            partial: out,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use satsim_tree::io::parse_model;
    use std::path::Path;

    const MODEL: &str = r#"
[[body]]
name = "bus"
mass = 100.0
inertia = [[10.0, 0.0, 0.0], [0.0, 12.0, 0.0], [0.0, 0.0, 14.0]]

[[body]]
name = "panel"
mass = 5.0
com = [0.5, 0.0, 0.0]
inertia = [[0.2, 0.0, 0.0], [0.0, 0.4, 0.0], [0.0, 0.0, 0.5]]

[[hinge]]
name = "h"
parent = "bus"
child = "panel"
axis = [0.0, 0.0, 1.0]
at = [0.6, 0.0, 0.0]
"#;

    fn model() -> Model {
        parse_model(MODEL, Path::new("m.toml")).unwrap().0
    }

    #[test]
    fn dynamics_solves_its_own_equation() {
        let m = model();
        let mut s = State::rest(&m);
        s.v[0] = 0.1;
        s.v[2] = -0.05;
        s.v[6] = 0.3;
        s.q[7] = 0.4;
        s.tau[6] = 2.0;
        let d = dynamics(&m, &s).unwrap();
        assert_eq!(d.dof, 7);
        let residual =
            &d.mass_matrix * &d.acceleration + &d.bias - DVector::from_column_slice(&s.tau);
        assert!(residual.amax() < 1e-12, "{residual}");
        // T = v' M v / 2.
        let v = DVector::from_column_slice(&s.v);
        let t = 0.5 * v.dot(&(&d.mass_matrix * &v));
        assert!((t - d.kinetic_energy).abs() < 1e-14 * t.max(1.0));
    }

    fn scene(extra: &str) -> Scene {
        let text = format!(
            "duration = 2.0\n{extra}\n[integrator]\nmethod = \"rk4\"\nstep = 0.01\n[output]\nevery = 0.5\nplots = false\n[model]\n{}",
            MODEL
                .replace("[[body]]", "[[model.body]]")
                .replace("[[hinge]]", "[[model.hinge]]")
        );
        Scene::parse(&text, Path::new("s.toml")).unwrap()
    }

    #[test]
    fn run_scene_keeps_every_output_row() {
        let s = scene("initial = { hinges = { angle = [0.2], rate = [0.0] } }");
        let tr = run_scene(&s, || false).unwrap();
        assert_eq!(tr.n_rows(), 5);
        let t: Vec<f64> = tr.rows().map(|r| r[0]).collect();
        assert_eq!(t, [0.0, 0.5, 1.0, 1.5, 2.0]);
        assert_eq!(tr.columns[0], "t");
        assert!(tr.columns.iter().any(|c| c == "angle_h"));
        // The rows are the ones `Simulation::run` hands to its sink.
        let mut sim = s.simulation().unwrap();
        let mut direct = Vec::new();
        sim.run(
            &s.options,
            s.duration,
            &Times::Interval(s.every),
            |_, row| -> Result<(), StopRequested> {
                direct.extend_from_slice(row);
                Ok(())
            },
        )
        .unwrap();
        assert_eq!(tr.values, direct);
    }

    #[test]
    fn stop_ends_the_run_after_the_row() {
        let s = scene("");
        let mut calls = 0;
        let err = run_scene(&s, || {
            calls += 1;
            calls == 2
        })
        .unwrap_err();
        match err {
            RunFailure::Stopped { partial } => {
                assert_eq!(partial.n_rows(), 2);
                assert_eq!(partial.last_t(), Some(0.5));
            }
            other => panic!("{other}"),
        }
    }
}
