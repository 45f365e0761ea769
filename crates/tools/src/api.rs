//! In-memory entry points shared by the `satsim` command line and the Python module: the
//! dynamics of one state (`satsim dynamics`, contract section 3) and a scene's whole
//! trajectory (`satsim run`, contract section 7) as columns and rows instead of a CSV file.
//!
//! [`campaign_table`] is `satsim campaign`'s `runs.csv` (contract section 8) in memory. The
//! linear model and the modes (section 9) need nothing more than [`crate::linearize`] and
//! [`crate::modes`].
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
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use satsim_integrate::Output as Times;
use satsim_spacecraft::simulation::{RunError, SimError};
use satsim_tree::aba::aba;
use satsim_tree::{Data, DynamicsError, Model, State, bias, crba, kinetic_energy};
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
    let n_stats = 3 * (campaign.columns.len() - 1);
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
            assert_eq!(all.status[k], fields[w - 3 * (c.columns.len() - 1) - 2]);
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
