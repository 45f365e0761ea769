//! In-memory entry points shared by the `satsim` command line and the Python module: the
//! dynamics of one state (`satsim dynamics`, contract section 3) and a scene's whole
//! trajectory (`satsim run`, contract section 7) as columns and rows instead of a CSV file.
//!
//! [`campaign_table`] is `satsim campaign`'s `runs.csv` (contract section 8) in memory. The
//! linear model and the modes (section 9) need nothing more than [`crate::linearize`] and
//! [`crate::modes`].
//!
//! A model with flexible bodies (contract section 14) is a [`DynamicsModel`] with its
//! [`FlexModel`]: [`flex_dynamics`] evaluates the flexible algorithms, with the elastic
//! coordinates after the hinge rates, and [`DynamicsModel::modes`] its coupled modes.
//!
//! These call exactly the code the command line calls ([`crba()`], [`bias()`], [`aba()`],
//! [`kinetic_energy()`]; [`Scene::simulation`], [`Simulation::run`], [`Simulation::columns`];
//! [`Campaign::run_one`]), so their numbers equal the command line's to the last bit.
//!
//! Conventions are the contract's: generalised velocities `[ω (3), v (3), hinge rates]` for a
//! free base (root-body axes, Featherstone's angular-then-linear order), `[hinge rates]` for
//! a fixed base; SI units; quaternions Hamilton `[w, x, y, z]`.
//!
//! [`Simulation::run`]: satsim_spacecraft::simulation::Simulation::run
//! [`Simulation::columns`]: satsim_spacecraft::simulation::Simulation::columns

use crate::campaign::{Campaign, CampaignError, RunRecord, Shard};
use crate::scene::Scene;
use crate::scene::flexible::{
    CoupledModes, Elastic, coupled_modes, elastic_state, json_line, parse_state_json,
};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use satsim_integrate::Output as Times;
use satsim_spacecraft::simulation::{RunError, SimError};
use satsim_tree::aba::aba;
use satsim_tree::flexible::{self, FlexData, FlexModel};
use satsim_tree::io::{self as tio, FileError};
use satsim_tree::{Data, DynamicsError, Model, State, bias, crba, kinetic_energy};
use std::fmt;
use std::path::Path;
use thiserror::Error;

/// The dynamics of one state (contract section 3): `mass_matrix * acceleration + bias = tau`.
#[derive(Clone, Debug, PartialEq)]
pub struct Dynamics {
    /// Degrees of freedom (`nv`; with flexible bodies, the rigid `nv` plus the modes).
    pub dof: usize,
    /// Joint-space mass matrix `M(q)` (CRBA), `dof x dof`, symmetric.
    pub mass_matrix: DMatrix<f64>,
    /// Velocity-product terms `C(q, v) v` (RNEA with zero acceleration; no gravity, no
    /// external forces); with flexible bodies also the modal stiffness and damping forces
    /// `ωₖ² ηₖ + 2 ζ ωₖ η̇ₖ` and a beam's geometric stiffening.
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

impl Dynamics {
    /// The result, or [`DynamicsFailure::NonFinite`] when a number is not finite.
    fn finite(
        dof: usize,
        mass_matrix: DMatrix<f64>,
        bias: DVector<f64>,
        acceleration: DVector<f64>,
        kinetic_energy: f64,
    ) -> Result<Self, DynamicsFailure> {
        let finite = mass_matrix
            .iter()
            .chain(bias.iter())
            .chain(acceleration.iter())
            .all(|x| x.is_finite())
            && kinetic_energy.is_finite();
        if !finite {
            return Err(DynamicsFailure::NonFinite);
        }
        Ok(Self {
            dof,
            mass_matrix,
            bias,
            acceleration,
            kinetic_energy,
        })
    }
}

/// The mass matrix, bias, forward-dynamics acceleration and kinetic energy of `state`.
/// Every number is finite, or the result is an error.
pub fn dynamics(model: &Model, state: &State) -> Result<Dynamics, DynamicsFailure> {
    let mut data = Data::new(model);
    let mass_matrix = crba(model, &mut data, &state.q)?.clone();
    let bias = bias(model, &mut data, &state.q, &state.v, None)?.clone();
    let acceleration = aba(model, &mut data, &state.q, &state.v, &state.tau, None)?.clone();
    let kinetic_energy = kinetic_energy(model, &mut data, &state.q, &state.v)?;
    Dynamics::finite(model.nv(), mass_matrix, bias, acceleration, kinetic_energy)
}

/// The dynamics of a state of a model with flexible bodies (contract sections 3 and 14): the
/// rigid `state` (its `q`, `v`, `tau` those of `model.rigid()`) extended by `elastic`, so that
/// `q = [rigid q…, η…]`, `v = [rigid v…, η̇…]` and `tau = [state.tau…, 0…]` (no modal
/// force). The mass matrix is the flexible CRBA's; the bias the flexible RNEA's at zero
/// acceleration: the velocity products, the modal stiffness `ωₖ² ηₖ` and damping
/// `2 ζ ωₖ η̇ₖ` forces on the elastic rows, and a beam's geometric stiffening; the
/// acceleration the flexible ABA's; the kinetic energy [`flexible::energy`]'s (the strain
/// energy left out). `dof` is the rigid `nv` plus the number of modes. Every number is
/// finite, or the result is an error.
pub fn flex_dynamics(
    model: &FlexModel,
    state: &State,
    elastic: &Elastic,
) -> Result<Dynamics, DynamicsFailure> {
    let q = [state.q.as_slice(), &elastic.eta].concat();
    let v = [state.v.as_slice(), &elastic.etadot].concat();
    let mut tau = state.tau.clone();
    tau.resize(tau.len() + elastic.eta.len(), 0.0);
    let mut data = FlexData::new(model);
    let mass_matrix = flexible::crba(model, &mut data, &q)?.clone();
    let bias = flexible::bias(model, &mut data, &q, &v, None)?.clone();
    let acceleration = flexible::aba(model, &mut data, &q, &v, &tau, None)?.clone();
    let (kinetic_energy, _strain) = flexible::energy(model, &mut data, &q, &v)?;
    Dynamics::finite(model.nv(), mass_matrix, bias, acceleration, kinetic_energy)
}

/// A model file read for `satsim dynamics` and `satsim.Model`: its rigid tree and, when a
/// body has `[body.flexible]`, its flexible model (whose rigid tree `rigid` is). A rigid
/// file is read exactly as [`satsim_tree::io::read_model`] reads it.
#[derive(Clone, Debug)]
pub struct DynamicsModel {
    /// The rigid tree (a beam's mass included in its body).
    pub rigid: Model,
    /// The flexible model, when a body is flexible.
    pub flex: Option<FlexModel>,
}

impl DynamicsModel {
    /// Reads the model file at `path`.
    pub fn read(path: &Path) -> Result<Self, FileError> {
        let text = std::fs::read_to_string(path).map_err(|source| FileError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Parses a model file's text; `origin` names it in errors (and a `modes_file` is read
    /// relative to its folder).
    pub fn parse(text: &str, origin: &Path) -> Result<Self, FileError> {
        let file = tio::parse_model_file(text, origin)?;
        if file.body.iter().all(|b| b.get_ref().flexible.is_none()) {
            let rigid = file.build().map_err(|e| e.in_file(text, origin))?;
            return Ok(Self { rigid, flex: None });
        }
        let flex = tio::flex_model_of(&file, text, origin)?;
        Ok(Self {
            rigid: flex.rigid().clone(),
            flex: Some(flex),
        })
    }

    /// Degrees of freedom: the rigid `nv` plus the number of modes.
    pub fn dof(&self) -> usize {
        self.flex.as_ref().map_or(self.rigid.nv(), FlexModel::nv)
    }

    /// The flexible bodies, in the model's order, with their numbers of modes.
    pub fn flexible_bodies(&self) -> Vec<(String, usize)> {
        let Some(flex) = &self.flex else {
            return Vec::new();
        };
        (0..self.rigid.n_bodies())
            .filter(|&i| flex.modes(i) > 0)
            .map(|i| (self.rigid.bodies()[i].name().to_owned(), flex.modes(i)))
            .collect()
    }

    /// The flexible bodies with their clamped modal frequencies `ωₖ / 2π` (Hz), mode 1
    /// first.
    pub fn modal_frequencies(&self) -> Vec<(String, Vec<f64>)> {
        let Some(flex) = &self.flex else {
            return Vec::new();
        };
        (0..self.rigid.n_bodies())
            .filter(|&i| flex.modes(i) > 0)
            .map(|i| {
                let o = flex.elastic_offset(i);
                let hz = flex.stiffness()[o..o + flex.modes(i)]
                    .iter()
                    .map(|w2| w2.sqrt() / (2.0 * std::f64::consts::PI))
                    .collect();
                (self.rigid.bodies()[i].name().to_owned(), hz)
            })
            .collect()
    }

    /// Parses a state file's JSON text (contract section 2; with flexible bodies, its
    /// optional `flexible` object of section 14); `origin` names it in errors. A rigid
    /// model's state is read as [`satsim_tree::io::parse_state`] reads it.
    pub fn parse_state(&self, text: &str, origin: &Path) -> Result<(State, Elastic), FileError> {
        let Some(flex) = &self.flex else {
            let state = tio::parse_state(text, origin, &self.rigid)?;
            return Ok((state, Elastic::default()));
        };
        let (sf, given) = parse_state_json(text, origin)?;
        let elastic = elastic_state(
            Some(flex),
            &self.rigid,
            given.iter().map(|(b, e)| (b.as_str(), e)),
        )
        .map_err(|(k, message)| FileError::Schema {
            path: origin.to_path_buf(),
            line: json_line(text, &given[k].0),
            message,
        })?;
        let state = sf.resolve(&self.rigid).map_err(|e| e.in_file(origin))?;
        Ok((state, elastic))
    }

    /// Reads the state file at `path` ([`DynamicsModel::parse_state`]).
    pub fn read_state(&self, path: &Path) -> Result<(State, Elastic), FileError> {
        if self.flex.is_none() {
            let state = tio::read_state(path, &self.rigid)?;
            return Ok((state, Elastic::default()));
        }
        let text = std::fs::read_to_string(path).map_err(|source| FileError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        self.parse_state(&text, path)
    }

    /// [`dynamics`] of a rigid model, [`flex_dynamics`] of a flexible one.
    pub fn dynamics(&self, state: &State, elastic: &Elastic) -> Result<Dynamics, DynamicsFailure> {
        match &self.flex {
            None => dynamics(&self.rigid, state),
            Some(flex) => flex_dynamics(flex, state, elastic),
        }
    }

    /// The coupled undamped modes at the configuration of `state` and `elastic`
    /// ([`coupled_modes`]; none for a rigid model). The error says why there are none (the
    /// mass matrix not positive definite there).
    pub fn modes(&self, state: &State, elastic: &Elastic) -> Result<CoupledModes, String> {
        let Some(flex) = &self.flex else {
            return Ok(CoupledModes {
                omega: Vec::new(),
                shapes: DMatrix::zeros(self.rigid.nv(), 0),
            });
        };
        let q = [state.q.as_slice(), &elastic.eta].concat();
        if q.len() != flex.nq() {
            return Err(format!(
                "the state has {} coordinates, the model {}",
                q.len(),
                flex.nq()
            ));
        }
        coupled_modes(flex, &q).ok_or_else(|| {
            "no modes: the mass matrix is not positive definite at this state".to_owned()
        })
    }
}

/// A trajectory held in memory: the header and rows `satsim run` writes to `trajectory.csv`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Trajectory {
    /// Column names ([`Simulation::columns`](satsim_spacecraft::simulation::Simulation::columns)).
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
pub fn run_scene(scene: &Scene, stop: impl FnMut() -> bool) -> Result<Trajectory, RunFailure> {
    run_scene_warned(scene, stop).map(|(t, _)| t)
}

/// What `satsim run` warns of after `sim`, built from `scene`, finished with `stats`: the
/// simulation's warnings ([`Simulation::run_warnings`](satsim_spacecraft::simulation::Simulation::run_warnings))
/// and an explicit method's steps held by a stiff motion
/// ([`held_steps_warning`](crate::scene::step_limit::held_steps_warning)).
pub fn after_run_warnings(
    scene: &Scene,
    sim: &satsim_spacecraft::simulation::Simulation,
    stats: &satsim_integrate::Stats,
) -> Vec<String> {
    let mut warnings = sim.run_warnings();
    warnings.extend(crate::scene::step_limit::held_steps_warning(
        scene,
        &satsim_integrate::Steps::of(stats, sim.t0()),
    ));
    warnings
}

/// [`run_scene`], with the warnings `satsim run` prints after a run that finished: the
/// scene reader's ([`Scene::warnings`]), then [`after_run_warnings`] (a flexible body bent
/// beyond what its modal model holds, an energy budget that did not close, an explicit
/// method's steps held by a stiff motion).
pub fn run_scene_warned(
    scene: &Scene,
    mut stop: impl FnMut() -> bool,
) -> Result<(Trajectory, Vec<String>), RunFailure> {
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
        Ok(stats) => {
            let mut warnings = scene.warnings.clone();
            warnings.extend(after_run_warnings(scene, &sim, &stats));
            Ok((out, warnings))
        }
        Err(RunError::Sink { .. }) => Err(RunFailure::Stopped { partial: out }),
        Err(RunError::Integrate(e)) => Err(RunFailure::Failed {
            why: e.to_string(),
            partial: out,
        }),
    }
}

/// `runs.csv` of a campaign (contract section 8) in memory: one row per run of the shard,
/// sorted by the run number `k`.
///
/// `columns` is `runs.csv`'s header ([`Campaign::header`]); every row of `values` holds the
/// same numbers as the line `satsim campaign` writes, bit for bit, except in the two text
/// columns: `status` holds 1 (`ok`) or 0 (`failed`) and `message` holds NaN (the texts are in
/// [`CampaignTable::status`] and [`CampaignTable::messages`]). A failed run's statistics are
/// NaN (empty in the CSV).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CampaignTable {
    /// `runs.csv`'s header.
    pub columns: Vec<String>,
    /// The rows, one after the other (row-major, `columns.len()` values per row).
    pub values: Vec<f64>,
    /// `ok` or `failed`, per row.
    pub status: Vec<String>,
    /// Why a run failed (empty for a run that finished), per row.
    pub messages: Vec<String>,
}

impl CampaignTable {
    /// Number of rows (runs).
    pub fn n_rows(&self) -> usize {
        self.status.len()
    }
}

/// Runs the shard `shard` of `campaign` on `threads` worker threads (`None`: every core) with
/// [`Campaign::run_one`], as `satsim campaign` does, and returns its `runs.csv` in memory
/// (nothing is written). The rows depend on `k` alone, not on the threads or the shard.
pub fn campaign_table(
    campaign: &Campaign,
    threads: Option<usize>,
    shard: Shard,
) -> Result<CampaignTable, CampaignError> {
    campaign_table_until(campaign, threads, shard, &|| false)
}

/// [`campaign_table`], checking `stop` before each run and at each output row: once it turns
/// true no run starts, the running ones stop, and the result is
/// [`CampaignError::Interrupted`] (the Python module's Ctrl-C).
pub fn campaign_table_until(
    campaign: &Campaign,
    threads: Option<usize>,
    shard: Shard,
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<CampaignTable, CampaignError> {
    let todo: Vec<u64> = (0..campaign.runs).filter(|k| shard.contains(*k)).collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| CampaignError::Other(format!("cannot start the thread pool: {e}")))?;
    // `collect` keeps the order of `todo`: sorted by k.
    let records: Vec<Option<RunRecord>> = pool.install(|| {
        todo.par_iter()
            .with_max_len(1)
            .map(|&k| match stop() {
                true => None,
                false => campaign.run_one_until(k, stop),
            })
            .collect()
    });
    let held = records.iter().flatten().count() as u64;
    if held < todo.len() as u64 {
        return Err(CampaignError::Other(format!(
            "interrupted: {held} of {} runs finished",
            todo.len()
        )));
    }
    let records: Vec<RunRecord> = records.into_iter().flatten().collect();
    let columns = campaign.header();
    // With the column `stability_held`.
    let n_stats = 3 * (campaign.columns.len() - 1) + campaign.peak_columns.len() + 1;
    let mut out = CampaignTable {
        values: Vec::with_capacity(records.len() * columns.len()),
        columns,
        ..CampaignTable::default()
    };
    for r in &records {
        out.values.push(r.k as f64);
        out.values.extend_from_slice(&r.values);
        match &r.outcome {
            Ok(st) => {
                out.values.extend_from_slice(&[1.0, f64::NAN]);
                for c in 0..st.last.len() {
                    out.values
                        .extend_from_slice(&[st.last[c], st.min[c], st.max[c]]);
                }
                out.values.extend_from_slice(&st.peaks);
                out.values.push(f64::from(u8::from(st.held)));
                out.status.push("ok".into());
                out.messages.push(String::new());
            }
            Err(m) => {
                out.values.extend_from_slice(&[0.0, f64::NAN]);
                out.values.extend(std::iter::repeat_n(f64::NAN, n_stats));
                out.status.push("failed".into());
                out.messages.push(m.clone());
            }
        }
    }
    debug_assert_eq!(out.values.len(), out.n_rows() * out.columns.len());
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use satsim_tree::io::parse_model;
    use std::path::{Path, PathBuf};

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

    fn flexible_satellite() -> (PathBuf, DynamicsModel) {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/satellite_flexible.toml");
        let model = DynamicsModel::read(&path).unwrap();
        (path, model)
    }

    /// A state of the flexible satellite: hinge angles, rates and torques, and every panel
    /// deformed and vibrating.
    const FLEX_STATE: &str = r#"{
  "base": {"attitude": [0.5, 0.5, -0.5, 0.5], "angular_velocity": [0.01, -0.02, 0.015],
           "velocity": [0.1, 0.0, -0.2]},
  "hinges": {"angle": [0.3, -0.2, 0.1, 1.2, -1.0], "rate": [0.1, 0.2, -0.1, 0.5, -0.4],
             "torque": [0.0, 0.0, 0.3, -0.5, 0.4]},
  "flexible": {
    "panel1": {"eta": [0.02, -0.004, 0.001], "etadot": [0.1, 0.02, -0.01]},
    "panel2": {"eta": [-0.01, 0.003, 0.0]},
    "panel3": {"etadot": [-0.05, 0.0, 0.03]}
  }
}"#;

    #[test]
    fn flexible_dynamics_are_the_flexible_algorithms_and_solve_their_own_equation() {
        let (_, model) = flexible_satellite();
        let flex = model.flex.as_ref().unwrap();
        let (state, elastic) = model.parse_state(FLEX_STATE, Path::new("s.json")).unwrap();
        assert_eq!((elastic.eta.len(), elastic.etadot.len()), (9, 9));
        assert_eq!(elastic.eta[..3], [0.02, -0.004, 0.001]);
        assert_eq!(elastic.etadot[6..], [-0.05, 0.0, 0.03]);
        let d = model.dynamics(&state, &elastic).unwrap();
        assert_eq!(d.dof, 11 + 9);
        assert_eq!(model.dof(), 20);
        let q = [state.q.as_slice(), &elastic.eta].concat();
        let v = [state.v.as_slice(), &elastic.etadot].concat();
        let mut data = FlexData::new(flex);
        assert_eq!(d.mass_matrix, *flexible::crba(flex, &mut data, &q).unwrap());
        assert_eq!(d.mass_matrix, d.mass_matrix.transpose());
        // M a + b = tau, tau zero on the base and the modes.
        let mut tau = DVector::zeros(20);
        tau.rows_mut(6, 5).copy_from_slice(&state.tau[6..]);
        let lhs = &d.mass_matrix * &d.acceleration + &d.bias;
        let scale = (&d.mass_matrix * &d.acceleration).amax().max(d.bias.amax());
        assert!((&lhs - &tau).amax() <= 1e-10 * scale, "{}", lhs - tau);
        // T = v' M v / 2.
        let vv = DVector::from_column_slice(&v);
        let t = 0.5 * vv.dot(&(&d.mass_matrix * &vv));
        assert!(
            (t - d.kinetic_energy).abs() <= 1e-12 * t,
            "{t} {}",
            d.kinetic_energy
        );
        // At rest the bias is the modal stiffness alone: omega_k^2 eta_k on the modes.
        let rest = State {
            v: vec![0.0; 11],
            ..state.clone()
        };
        let still = Elastic {
            etadot: vec![0.0; 9],
            ..elastic.clone()
        };
        let b = model.dynamics(&rest, &still).unwrap().bias;
        assert!(b.rows(0, 11).amax() < 1e-12, "{b}");
        for (e, w2) in flex.stiffness().iter().enumerate() {
            let want = w2 * elastic.eta[e];
            assert!(
                (b[11 + e] - want).abs() <= 1e-12 * want.abs().max(1.0),
                "{e}"
            );
        }
        // Damping adds 2 zeta omega_k etadot_k, the odd part of the bias in v (the velocity
        // products and the stiffening are quadratic in v).
        let back = State {
            v: state.v.iter().map(|x| -x).collect(),
            ..state.clone()
        };
        let reversed = Elastic {
            etadot: elastic.etadot.iter().map(|x| -x).collect(),
            ..elastic.clone()
        };
        let odd = (&d.bias - model.dynamics(&back, &reversed).unwrap().bias) * 0.5;
        assert!(odd.rows(0, 11).amax() < 1e-12 * d.bias.amax(), "{odd}");
        for (e, c) in flex.damping().iter().enumerate() {
            let want = c * elastic.etadot[e];
            assert!((odd[11 + e] - want).abs() <= 1e-12 * d.bias.amax(), "{e}");
        }
        assert!(flex.damping().iter().all(|c| *c > 0.0));
    }

    #[test]
    fn a_rigid_model_reads_and_computes_as_before() {
        let m = DynamicsModel::parse(MODEL, Path::new("m.toml")).unwrap();
        assert!(m.flex.is_none() && m.flexible_bodies().is_empty());
        assert_eq!(m.rigid, model());
        let text = r#"{"base": {"angular_velocity": [0.1, 0.0, -0.05]},
                       "hinges": {"angle": [0.4], "rate": [0.3], "torque": [2.0]}}"#;
        let (state, elastic) = m.parse_state(text, Path::new("s.json")).unwrap();
        assert_eq!(elastic, Elastic::default());
        assert_eq!(
            state,
            tio::parse_state(text, Path::new("s.json"), &model()).unwrap()
        );
        assert_eq!(
            m.dynamics(&state, &elastic).unwrap(),
            dynamics(&model(), &state).unwrap()
        );
        // A rigid model's state file takes no `flexible` (as before).
        let e = m
            .parse_state(
                r#"{"hinges": {"angle": [0.4], "rate": [0.3]}, "flexible": {}}"#,
                Path::new("s.json"),
            )
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("s.json") && e.contains("flexible"), "{e}");
        assert!(m.modes(&state, &elastic).unwrap().omega.is_empty());
    }

    #[test]
    fn a_bad_elastic_state_names_the_file_and_line() {
        let (_, model) = flexible_satellite();
        let text = "{\n  \"hinges\": {\"angle\": [0, 0, 0, 0, 0], \"rate\": [0, 0, 0, 0, 0]},\n  \"flexible\": {\n    \"panel2\": {\"eta\": [0.1, 0.2]}\n  }\n}\n";
        let dir = satsim_testkit::temp_dir("api-bad-eta");
        let file = dir.join("bad.json");
        std::fs::write(&file, text).unwrap();
        let e = model.read_state(&file).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{}:4:", file.display())), "{e}");
        assert!(e.contains("flexible.panel2.eta: expected 3 values"), "{e}");
        for (bad, needle) in [
            (r#"{"flexible": {"bus": {"eta": [1.0]}}}"#, "not flexible"),
            (r#"{"flexible": {"nobody": {}}}"#, "no body of that name"),
            (
                r#"{"flexible": {"panel1": {"eta": [1, 2, 3], "x": 1}}}"#,
                "unknown",
            ),
        ] {
            let e = model
                .parse_state(bad, Path::new("b.json"))
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("b.json") && e.contains(needle), "{e}");
        }
    }

    /// `(βₙL)²`, the roots of `cos x cosh x = −1` squared: a clamped-free beam's
    /// `ωₙ √(ρA L⁴ / EI)`.
    const CLAMPED: [f64; 3] = [3.516_015_268, 22.034_491_87, 61.697_214_35];

    #[test]
    fn a_cantilevers_coupled_modes_are_euler_bernoullis() {
        let text = r#"[base]
kind = "fixed"
[[body]]
name = "beam"
mass = 0.0
inertia = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]
[body.flexible]
beam = { root = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], bend = [0.0, 0.0, 1.0],
         length = 1.0, EI = 1.0, rho_A = 1.0, modes = 3 }
"#;
        let m = DynamicsModel::parse(text, Path::new("c.toml")).unwrap();
        assert_eq!(m.dof(), 3);
        assert_eq!(m.flexible_bodies(), [("beam".to_owned(), 3)]);
        let (state, elastic) = m.parse_state("{}", Path::new("s.json")).unwrap();
        let modes = m.modes(&state, &elastic).unwrap();
        for (w, want) in modes.omega.iter().zip(CLAMPED) {
            assert!((w / want - 1.0).abs() < 1e-4, "{w} {want}");
        }
        let hz = &m.modal_frequencies()[0].1;
        for (f, w) in hz.iter().zip(&modes.omega) {
            assert!((f * 2.0 * std::f64::consts::PI / w - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn coupled_modes_are_mass_normalised_and_include_the_highest() {
        let (_, model) = flexible_satellite();
        let flex = model.flex.as_ref().unwrap();
        let (state, elastic) = model.parse_state(FLEX_STATE, Path::new("s.json")).unwrap();
        let modes = model.modes(&state, &elastic).unwrap();
        assert_eq!(modes.omega.len(), 9);
        assert_eq!(modes.shapes.shape(), (20, 9));
        assert!(modes.omega.windows(2).all(|w| w[0] <= w[1]));
        let q = [state.q.as_slice(), &elastic.eta].concat();
        let d = model.dynamics(&state, &elastic).unwrap();
        let mut k = DMatrix::zeros(20, 20);
        for (e, w2) in flex.stiffness().iter().enumerate() {
            k[(11 + e, 11 + e)] = *w2;
        }
        for (c, w) in modes.omega.iter().enumerate() {
            let x = modes.shapes.column(c);
            let mx = &d.mass_matrix * x;
            assert!((x.dot(&mx) - 1.0).abs() < 1e-9);
            let r = &k * x - mx * (w * w);
            assert!(r.amax() < 1e-8 * w * w, "mode {c}: {r}");
        }
        let (top, _) = crate::scene::flexible::highest_frequency(flex, &q).unwrap();
        assert_eq!(top, *modes.omega.last().unwrap());
        // Between the strips' clamped frequencies and well above zero.
        let clamped = model.modal_frequencies();
        assert_eq!(clamped.len(), 3);
        assert!(modes.omega[0] > 0.5 * clamped[0].1[0] * 2.0 * std::f64::consts::PI);
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

    fn campaign() -> Campaign {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/scenes/deploy_campaign.toml");
        let text = std::fs::read_to_string(&path)
            .unwrap()
            .replace("duration = 60.0", "duration = 1.0")
            .replace("runs = 64", "runs = 5");
        Campaign::parse(&text, &path).unwrap()
    }

    #[test]
    fn campaign_table_holds_the_csv_rows_and_ignores_threads_and_shards() {
        let c = campaign();
        let all = campaign_table(&c, Some(2), Shard::ALL).unwrap();
        assert_eq!(all.columns, c.header());
        assert_eq!(all.n_rows(), 5);
        let w = all.columns.len();
        for (k, row) in all.values.chunks_exact(w).enumerate() {
            // The CSV line of the same run, field by field.
            let record = c.run_one(k as u64);
            let line = c.csv_row(&record);
            let fields: Vec<&str> = line.trim_end().split(',').collect();
            assert_eq!(fields.len(), w);
            for (j, (f, v)) in fields.iter().zip(row).enumerate() {
                match all.columns[j].as_str() {
                    "status" => assert_eq!(*v, if *f == "ok" { 1.0 } else { 0.0 }),
                    "message" => assert!(v.is_nan()),
                    _ if f.is_empty() => assert!(v.is_nan()),
                    _ => assert_eq!(f.parse::<f64>().unwrap().to_bits(), v.to_bits()),
                }
            }
            let status = all.columns.iter().position(|c| c == "status").unwrap();
            assert_eq!(all.status[k], fields[status]);
        }
        // Two shards on one thread each hold the same rows.
        let even = campaign_table(&c, Some(1), Shard::new(0, 2).unwrap()).unwrap();
        let odd = campaign_table(&c, Some(1), Shard::new(1, 2).unwrap()).unwrap();
        assert_eq!((even.n_rows(), odd.n_rows()), (3, 2));
        for (k, row) in all.values.chunks_exact(w).enumerate() {
            let shard = if k % 2 == 0 { &even } else { &odd };
            let got = &shard.values[(k / 2) * w..(k / 2 + 1) * w];
            let same = got.iter().zip(row).all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(same, "run {k}");
        }
    }
}
