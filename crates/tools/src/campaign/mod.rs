//! Monte Carlo campaigns (contract section 8): a scene run many times with dispersed inputs,
//! on every core ([rayon]) and across machines (shards merged afterwards).
//!
//! - [`Campaign::read`] reads a scene with a `[campaign]` table: the nominal scene (checked as
//!   `satsim run` checks it), the runs, the seed and the dispersed numbers ([`spec`] says how
//!   keys address the scene and how run `k` draws its values from `(seed, k)` alone).
//! - [`Campaign::run_one`] runs one `k`: the scene as written with the drawn values
//!   substituted is parsed by [`Scene::parse`] exactly as `satsim run` parses a file, built and
//!   integrated with the same output times, and reduced to the final, minimum and maximum of
//!   every trajectory column at the output times. A run that fails (a drawn value the scene
//!   rejects, an integrator failure, a non-finite value, even a panic) is a failed record with
//!   its message, never the end of the campaign.
//! - [`run_campaign`] runs a shard on a local thread pool and streams `runs.csv` (and the
//!   envelope samples `traces.csv`) as runs finish; [`finish`] then rewrites both sorted by
//!   `k` and writes `summary.json` and the plots. Output is therefore in completion order
//!   while a campaign runs (an interrupted campaign keeps every finished run, and `--resume`
//!   skips them) and in `k` order once it is done, byte for byte the same whatever the thread
//!   count or sharding: each row depends on its `k` alone, and the summary and plots are
//!   computed from the sorted files.
//! - [`merge`] combines shards' output folders into the folder one machine would have written.
//!
//! Per run, the scene is re-resolved from its substituted table (TOML text, parse, model and
//! effects built afresh: about 0.3 to 0.6 ms for `examples/scenes/deploy_campaign.toml`,
//! under 1 % of one of its runs; `cargo bench -p satsim-satellite --bench campaign` measures
//! it); the integration itself does not allocate in its inner loop.

pub mod files;
pub mod folder;
pub mod lanes;
pub mod meta;
pub mod plots;
pub mod shard;
pub mod spec;
pub mod stats;
pub mod stepped;
mod warnings;

pub use files::{Finished, finish, merge};
pub use folder::Folder;
pub use shard::{Shard, ShardChoice, choose_shard};
pub use spec::{Dispersed, Law, Segment, draw, run_rng};
pub use warnings::{HELD_COLUMN, beyond_warning, budget_drifted_row, budget_warning, held_warning};

use crate::scene::step_limit::{held, may_be_held, stable_step};
use crate::scene::{DEFAULT_MAX_ROWS, Scene};
use crate::scene_keys::{KeyError, Override, inline_sources};
use rayon::prelude::*;
use satsim_integrate::Output as Times;
use satsim_spacecraft::simulation::{RowSink, RunError, Simulation};
use satsim_tree::io::{FileError, line_of, with_key};
use serde::Deserialize;
use spec::CampaignFile;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicU64;
use std::sync::{Mutex, OnceLock};
use thiserror::Error;
use toml::{Spanned, Table};

/// Why a campaign could not run (bad input or unusable output folder; exit status 2). A run
/// that fails is not an error: it is a failed row.
#[derive(Debug, Error)]
pub enum CampaignError {
    /// The scene, its model or state, or its `[campaign]` table is bad input.
    #[error("{0}")]
    File(#[from] FileError),
    /// A file of the output folder could not be read or written.
    #[error("{}: {message}", path.display())]
    Output {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// Anything else (a thread pool that cannot start, shards that do not belong together…).
    #[error("{0}")]
    Other(String),
    /// Stopped on request ([`Progress::cancelled`]): `runs.csv` holds every finished run,
    /// in completion order, and `--resume` continues the campaign.
    #[error(
        "interrupted: {held} runs in {}, {left} not run; continue with --resume",
        runs_csv.display()
    )]
    Interrupted {
        /// The folder's `runs.csv`.
        runs_csv: PathBuf,
        /// Runs it holds.
        held: u64,
        /// Runs of the campaign (or shard) not run.
        left: u64,
    },
}

impl CampaignError {
    pub(crate) fn io(path: &Path, e: impl std::fmt::Display) -> Self {
        CampaignError::Output {
            path: path.to_path_buf(),
            message: e.to_string(),
        }
    }
}

/// A scene with a `[campaign]` table, read and checked.
#[derive(Clone, Debug)]
pub struct Campaign {
    /// The scene file.
    pub path: PathBuf,
    /// Number of runs.
    pub runs: u64,
    /// Master seed.
    pub seed: u64,
    /// The dispersed numbers, in draw order.
    pub dispersed: Vec<Dispersed>,
    /// The stat columns drawn as histograms.
    pub histograms: Vec<String>,
    /// The trajectory columns (contract section 7) of the nominal scene, `t` first.
    pub columns: Vec<String>,
    /// The columns after the statistics for the nominal scene's beams, in body order:
    /// `peak_deflection_<body>` ([`RunStats::peaks`]); empty without watched flexible
    /// bodies.
    pub peak_columns: Vec<String>,
    /// The nominal scene.
    pub nominal: Scene,
    /// The scene as written, `[campaign]` removed, `model` and `initial` read in as tables.
    base: Table,
    /// The scene file's text as written (before `--set`), to place a drawn scene's errors.
    source: String,
    /// Trajectory columns sampled for the envelope plots (`t` first).
    trace_columns: Vec<usize>,
    /// Every how many output rows a trace sample is kept.
    stride: usize,
    /// The most output rows one run may have.
    max_rows: u64,
    /// The nominal scene's stability limit on its fastest linear motion for its explicit
    /// adaptive method ([`stable_step`]), worked out the first time a run may have been held
    /// by it ([`Campaign::stability_held`]).
    stability_limit: OnceLock<Option<f64>>,
}

/// The largest number of samples of a run's trace for the envelope plots.
const TRACE_POINTS: usize = 200;

/// The most runs one campaign may have: a billion runs of the smallest scene are days of a
/// large cluster's time; a number beyond it is a slip, not a study.
pub const MAX_RUNS: i64 = 1_000_000_000;

/// Whether a dispersed number is the sensors' seed (`sensors.seed`), which each run sets.
fn is_sensor_seed(path: &[Segment]) -> bool {
    matches!(path, [Segment::Key(a), Segment::Key(b), ..] if a == "sensors" && b == "seed")
}

/// One run's statistics over its output rows (every trajectory column but `t`, in order).
#[derive(Clone, Debug, PartialEq)]
pub struct RunStats {
    /// The value at the last output time.
    pub last: Vec<f64>,
    /// The minimum over the output times.
    pub min: Vec<f64>,
    /// The maximum over the output times.
    pub max: Vec<f64>,
    /// Each beam's largest tip deflection over every accepted step of the run (not only
    /// the output times), as a fraction of its length, in body order
    /// ([`Simulation::deflection_peaks`]): past
    /// [`SMALL_DEFLECTION`](satsim_tree::flexible::SMALL_DEFLECTION) the run went beyond
    /// what its modal model holds. Empty without beams.
    pub peaks: Vec<f64>,
    /// Whether the run's steps were held by its explicit method's stability limit on the
    /// scene's fastest linear motion rather than by the tolerance, as `satsim run` warns of
    /// its one run ([`Campaign::stability_held`]): the column [`HELD_COLUMN`]. For a run
    /// stepped by flight software, over the steps the integrator set within the control
    /// periods ([`Stepping::steps`](satsim_spacecraft::simulation::Stepping::steps)): a
    /// period shorter than about the limit bounds the steps itself.
    pub held: bool,
}

/// The outcome of run `k`.
#[derive(Clone, Debug)]
pub struct RunRecord {
    /// The run.
    pub k: u64,
    /// The values it used, one per [`Campaign::dispersed`].
    pub values: Vec<f64>,
    /// Its statistics, or why it failed.
    pub outcome: Result<RunStats, String>,
    /// Samples of the trace columns (`t` first), every `stride` output rows.
    pub trace: Vec<Vec<f64>>,
    /// The user's metrics of the run (`name`, value), columns after the statistics
    /// ([`stepped`]); empty for a campaign of the built-in controllers.
    pub metrics: Vec<(String, f64)>,
}

#[derive(Deserialize)]
struct Top {
    #[serde(default)]
    campaign: Option<Spanned<CampaignFile>>,
}

fn reword(m: &str) -> String {
    let m = m.trim_end().replace("expected f64", "expected a number");
    if let Some(rest) = m.strip_prefix("unknown field ") {
        format!("unknown key {rest}")
    } else if let Some(rest) = m.strip_prefix("missing field ") {
        format!("missing required key {rest}")
    } else {
        m
    }
}

impl Campaign {
    /// A fingerprint of the scene every run starts from (the scene after `--set`, with its
    /// model file and initial state read in, `[campaign]` left out): 16 hex digits of the
    /// 64-bit FNV-1a hash of its TOML. Recorded in `campaign.json`, so that `--resume` and
    /// `merge` refuse runs made from another scene. FNV-1a rather than std's hasher, whose
    /// output may change between Rust releases.
    pub fn scene_digest(&self) -> String {
        let text = toml::to_string(&self.base).expect("a TOML table serialises");
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in text.bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        format!("{h:016x}")
    }

    /// Reads the scene file at `path` and its `[campaign]` table.
    pub fn read(path: impl AsRef<Path>) -> Result<Campaign, FileError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| FileError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Campaign::parse(&text, path)
    }

    /// Reads the scene file at `path` with `overrides` (`--set KEY=VALUE`, see
    /// [`crate::scene_keys`]; `campaign.runs` and the like included) applied in order.
    pub fn read_with(
        path: impl AsRef<Path>,
        overrides: &[Override],
    ) -> Result<Campaign, FileError> {
        let path = path.as_ref();
        if overrides.is_empty() {
            return Campaign::read(path);
        }
        let text = std::fs::read_to_string(path).map_err(|source| FileError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let rewritten = crate::scene_keys::overridden_text(&text, path, overrides)?;
        let mut c = Campaign::parse(&rewritten, path)
            .map_err(|e| crate::scene_keys::relocate(e, &text, path, &rewritten, overrides))?;
        c.source = text;
        Ok(c)
    }

    /// Parses a campaign scene's text; `path` names it in errors and anchors relative paths.
    pub fn parse(text: &str, path: &Path) -> Result<Campaign, FileError> {
        let nominal = Scene::parse(text, path)?;
        let schema = |span: Option<std::ops::Range<usize>>, message: String| FileError::Schema {
            path: path.to_path_buf(),
            line: span.map(|s| line_of(text, s.start)),
            message,
        };
        let top: Top = toml::from_str(text).map_err(|e| FileError::Schema {
            path: path.to_path_buf(),
            line: e.span().map(|s| line_of(text, s.start)),
            message: with_key(&e, reword(e.message())),
        })?;
        let Some(file) = top.campaign else {
            return Err(schema(
                None,
                "no [campaign] table: a campaign needs `[campaign]` with `runs` (see `satsim help campaign`)".into(),
            ));
        };
        let file = file.into_inner();
        let runs = *file.runs.get_ref();
        if !(1..=MAX_RUNS).contains(&runs) {
            return Err(schema(
                Some(file.runs.span()),
                format!(
                    "`campaign.runs` must be a whole number from 1 to {MAX_RUNS}, got {runs} (split a larger study into campaigns with their own seeds)"
                ),
            ));
        }
        let seed = match &file.seed {
            Some(s) if *s.get_ref() < 0 => {
                return Err(schema(
                    Some(s.span()),
                    format!(
                        "`campaign.seed` must be a whole number >= 0, got {}",
                        s.get_ref()
                    ),
                ));
            }
            Some(s) => *s.get_ref() as u64,
            None => 0,
        };

        let mut base: Table = text
            .parse()
            .map_err(|e: toml::de::Error| FileError::Syntax {
                path: path.to_path_buf(),
                line: e.span().map(|s| line_of(text, s.start)),
                message: e.message().trim_end().to_owned(),
            })?;
        base.remove("campaign");
        inline_sources(&mut base, text, path)?;

        let mut dispersed: Vec<Dispersed> = Vec::new();
        for (i, d) in file.disperse.iter().enumerate() {
            let span = Some(d.span());
            let d = d.get_ref();
            let key = d.key.get_ref();
            let named = |m: String| {
                schema(
                    span.clone(),
                    format!("`campaign.disperse[{i}]` (key `{key}`): {m}"),
                )
            };
            let law = spec::law_of(d).map_err(named)?;
            let index = d.index.as_ref().map(|x| *x.get_ref());
            let found = spec::resolve(&base, key, index, law).map_err(|KeyError(m)| named(m))?;
            if found.iter().any(|f| is_sensor_seed(&f.path)) {
                return Err(named(
                    "`sensors.seed` cannot be dispersed: each run writes its own (drawn from `campaign.seed` and the run's number), so a dispersed one would be ignored".into(),
                ));
            }
            spec::check_reach(&found, law).map_err(named)?;
            for f in &found {
                if dispersed.iter().any(|o| o.path == f.path) {
                    return Err(named(format!("`{}` is dispersed twice", f.column)));
                }
            }
            // A key the scene reads as a whole number (a count: `beam.modes`, `resolution`)
            // refuses the drawn values, which are real: found now, not as every run failing.
            let mut t = base.clone();
            for f in &found {
                spec::set(&mut t, &f.path, f.nominal);
            }
            let floated = toml::to_string(&t).expect("a TOML table serialises");
            if let Err(e) = Scene::parse(&floated, path) {
                let why = |e: FileError| match e {
                    FileError::Schema { message, .. } | FileError::Syntax { message, .. } => {
                        message
                    }
                    other => other.to_string(),
                };
                // Blamed on the key only where the scene as read in takes its nominal values.
                let nominal = toml::to_string(&base).expect("a TOML table serialises");
                if let Err(e) = Scene::parse(&nominal, path) {
                    return Err(schema(
                        None,
                        format!(
                            "the scene with its model and state files read in as tables (as each run is) fails: {}",
                            why(e)
                        ),
                    ));
                }
                return Err(named(format!(
                    "the scene takes only whole numbers there, and dispersed values are real numbers ({})",
                    why(e)
                )));
            }
            dispersed.extend(found);
        }

        let sim = nominal
            .simulation()
            .map_err(|e| schema(None, e.to_string()))?;
        let columns = sim.columns();
        let peak_columns = peak_columns(&sim);
        let mut stat_names: Vec<String> = stat_columns(&columns);
        stat_names.extend(peak_columns.iter().cloned());
        let histograms = match &file.histograms {
            Some(h) => {
                for c in h.get_ref() {
                    if !stat_names.contains(c) {
                        return Err(schema(
                            Some(h.span()),
                            format!(
                                "`campaign.histograms`: unknown column `{c}` (the columns are final_, min_ and max_ of: {}{})",
                                columns[1..].join(", "),
                                if peak_columns.is_empty() {
                                    String::new()
                                } else {
                                    format!("; and {}", peak_columns.join(", "))
                                }
                            ),
                        ));
                    }
                }
                h.get_ref().clone()
            }
            None => columns[1..]
                .iter()
                .filter(|c| c.starts_with("angle_") || c.starts_with("omega_"))
                .map(|c| format!("final_{c}"))
                .collect(),
        };
        let trace_columns: Vec<usize> = (0..columns.len())
            .filter(|&i| i == 0 || is_trace_column(&columns[i]))
            .collect();
        let rows = (nominal.duration / nominal.every).floor() as usize + 1;
        let stride = rows.div_ceil(TRACE_POINTS).max(1);
        Ok(Campaign {
            path: path.to_path_buf(),
            runs: runs as u64,
            seed,
            dispersed,
            histograms,
            columns,
            peak_columns,
            nominal,
            base,
            source: text.to_owned(),
            trace_columns,
            stride,
            max_rows: DEFAULT_MAX_ROWS,
            stability_limit: OnceLock::new(),
        })
    }

    /// The most output rows one run may have (default [`DEFAULT_MAX_ROWS`]): the nominal
    /// scene beyond it is refused when the campaign starts, a drawn one is a failed run.
    pub fn max_rows(&self) -> u64 {
        self.max_rows
    }

    /// Sets [`Campaign::max_rows`] (`satsim campaign --max-rows`).
    pub fn set_max_rows(&mut self, max_rows: u64) {
        self.max_rows = max_rows;
    }

    /// The `runs.csv` header.
    pub fn header(&self) -> Vec<String> {
        let mut h = vec!["run".to_owned()];
        h.extend(self.dispersed.iter().map(|d| d.column.clone()));
        h.push("status".into());
        h.push("message".into());
        h.extend(stat_columns(&self.columns));
        h.extend(self.peak_columns.iter().cloned());
        h.push(HELD_COLUMN.into());
        h
    }

    /// Whether a run of this campaign that took `steps` had them held by its explicit
    /// adaptive method's stability limit rather than by the tolerance: at least
    /// [`HELD_MIN_STEPS`](crate::scene::step_limit::HELD_MIN_STEPS) accepted steps, those the
    /// error control set within a factor [`HELD`](crate::scene::step_limit::HELD) of the
    /// nominal scene's limit ([`stable_step`]; a dispersed run's own moves with its values,
    /// and the factor covers that), the time stops no more often ([`held`]). The test
    /// `satsim run` applies to its one run
    /// ([`held_steps_warning`](crate::scene::step_limit::held_steps_warning)).
    pub fn stability_held(&self, steps: &satsim_integrate::Steps) -> bool {
        let method = self.nominal.options.method;
        if !may_be_held(method, steps.accepted) {
            return false;
        }
        let limit = self
            .stability_limit
            .get_or_init(|| stable_step(&self.nominal, method).map(|(limit, _)| limit));
        limit.is_some_and(|limit| held(steps, limit))
    }

    /// The values run `k` uses.
    pub fn draw(&self, k: u64) -> Vec<f64> {
        draw(&self.dispersed, self.seed, k)
    }

    /// The scene as written with `values` substituted for the dispersed numbers (external
    /// `model` and `initial` files inlined, no `[campaign]`), as TOML text.
    pub fn scene_text(&self, values: &[f64]) -> String {
        let mut t = self.base.clone();
        for (d, v) in self.dispersed.iter().zip(values) {
            spec::set(&mut t, &d.path, *v);
        }
        spec::normalise_quaternions(&mut t, &self.dispersed);
        toml::to_string(&t).expect("a TOML table serialises")
    }

    /// The sensors' noise seed of run `k` (its scene's `sensors.seed`): the next 63 bits of
    /// run `k`'s generator ([`run_rng`]) after its dispersed values, so that each run draws
    /// its own noise from `(seed, k)` alone (63 bits: a TOML integer is signed).
    pub fn sensor_seed(&self, k: u64) -> u64 {
        let mut rng = run_rng(self.seed, k);
        for d in &self.dispersed {
            d.law.draw(d.nominal, &mut rng);
        }
        rand_core::Rng::next_u64(&mut rng) >> 1
    }

    /// Run `k`'s scene: [`Campaign::scene_text`] of its drawn values, and, when the scene has
    /// `[sensors]`, its own `sensors.seed` ([`Campaign::sensor_seed`]). `satsim run` of this
    /// text gives run `k`'s row of `runs.csv`.
    pub fn run_text(&self, k: u64, values: &[f64]) -> String {
        let mut t = self.base.clone();
        for (d, v) in self.dispersed.iter().zip(values) {
            spec::set(&mut t, &d.path, *v);
        }
        spec::normalise_quaternions(&mut t, &self.dispersed);
        if let Some(toml::Value::Table(s)) = t.get_mut("sensors") {
            s.insert(
                "seed".into(),
                toml::Value::Integer(self.sensor_seed(k) as i64),
            );
        }
        toml::to_string(&t).expect("a TOML table serialises")
    }

    /// Runs `k`.
    pub fn run_one(&self, k: u64) -> RunRecord {
        self.run_one_until(k, &|| false)
            .expect("a run that is never stopped finishes")
    }

    /// Runs `k`, checking `stop` at every output row: `None` when it turned true before the
    /// run ended (the run is left out, to be run again by `--resume`, as `satsim run` stops
    /// at the next row on Ctrl-C).
    pub fn run_one_until(&self, k: u64, stop: &(dyn Fn() -> bool + Sync)) -> Option<RunRecord> {
        let values = self.draw(k);
        let mut collect = None;
        let outcome = catch_panic(|| {
            let (scene, sim) = self.prepare(k, &values)?;
            let c = collect.insert(Collect::new(self, k, stop));
            let mut sim = sim;
            let result = sim.run(
                &scene.options,
                sim.t0() + scene.duration,
                &Times::Interval(scene.every),
                |t, row| c.row(t, row),
            );
            c.take_peaks(&sim);
            Ok(result)
        });
        match (outcome, collect) {
            (Ok(result), Some(c)) => c.record(values, result),
            (Err(_), Some(c)) if c.stopped => None,
            (Err(why), _) => Some(RunRecord::failed(k, values, why)),
            (Ok(_), None) => unreachable!("a run collects its rows"),
        }
    }

    /// Run `k`'s scene with the drawn `values`, parsed, checked and built as `satsim run`
    /// builds it; the message of a failed run where it cannot be.
    fn prepare(&self, k: u64, values: &[f64]) -> Result<(Scene, Simulation), String> {
        let scene = self.drawn_scene(k, values)?;
        let sim = scene.simulation().map_err(|e| e.to_string())?;
        if sim.columns() != self.columns {
            return Err(
                "the drawn scene's trajectory columns differ from the nominal scene's".into(),
            );
        }
        Ok((scene, sim))
    }

    /// Run `k`'s scene with the drawn `values`, parsed and checked as `satsim run` checks
    /// it; the message of a failed run where it cannot be.
    pub(crate) fn drawn_scene(&self, k: u64, values: &[f64]) -> Result<Scene, String> {
        let text = self.run_text(k, values);
        // The drawn text is rewritten: its errors are placed where the value is written.
        let scene = Scene::parse_drawn(&text, &self.path).map_err(|e| {
            let e = crate::scene_keys::relocate(e, &self.source, &self.path, &text, &[]);
            format!("the drawn scene is invalid: {e}")
        })?;
        scene.check_rows(self.max_rows).map_err(|e| match e {
            FileError::Schema { message, .. } => format!("the drawn scene is refused: {message}"),
            other => other.to_string(),
        })?;
        Ok(scene)
    }

    /// The `runs.csv` row of a record (with its newline).
    pub fn csv_row(&self, r: &RunRecord) -> String {
        let mut s = String::new();
        let _ = write!(s, "{}", r.k);
        for v in &r.values {
            let _ = write!(s, ",{v}");
        }
        match &r.outcome {
            Ok(st) => {
                s.push_str(",ok,");
                for c in 0..st.last.len() {
                    let _ = write!(s, ",{},{},{}", st.last[c], st.min[c], st.max[c]);
                }
                for p in &st.peaks {
                    let _ = write!(s, ",{p}");
                }
                let _ = write!(s, ",{}", u8::from(st.held));
            }
            Err(m) => {
                s.push_str(",failed,");
                s.push_str(&crate::output::quote(m));
                for _ in 1..self.columns.len() {
                    s.push_str(",,,");
                }
                for _ in &self.peak_columns {
                    s.push(',');
                }
                s.push(',');
            }
        }
        s.push('\n');
        s
    }

    /// The `traces.csv` lines of a record: `k,column,values...` per trace column.
    pub fn trace_lines(&self, r: &RunRecord) -> String {
        let mut s = String::new();
        if r.outcome.is_err() {
            return s;
        }
        for (vals, &c) in r.trace.iter().zip(&self.trace_columns) {
            let _ = write!(s, "{},{}", r.k, self.columns[c]);
            for v in vals {
                let _ = write!(s, ",{v:.7e}");
            }
            s.push('\n');
        }
        s
    }
}

/// A run's rows reduced as they come: the final, minimum and maximum of every column, the
/// trace samples; and whether it was stopped.
pub(crate) struct Collect<'c> {
    campaign: &'c Campaign,
    k: u64,
    stats: RunStats,
    rows: usize,
    /// The time of the first row: the run's start.
    t0: f64,
    trace: Vec<Vec<f64>>,
    stop: &'c (dyn Fn() -> bool + Sync),
    stopped: bool,
}

impl<'c> Collect<'c> {
    pub(crate) fn new(campaign: &'c Campaign, k: u64, stop: &'c (dyn Fn() -> bool + Sync)) -> Self {
        let n = campaign.columns.len() - 1;
        // Sized for the nominal output times, so that rows do not reallocate as they come.
        let rows = (campaign.nominal.duration / campaign.nominal.every).floor() as usize + 1;
        let trace =
            vec![Vec::with_capacity(rows / campaign.stride + 1); campaign.trace_columns.len()];
        Self {
            campaign,
            k,
            stats: RunStats {
                last: vec![f64::NAN; n],
                min: vec![f64::INFINITY; n],
                max: vec![f64::NEG_INFINITY; n],
                peaks: Vec::new(),
                held: false,
            },
            rows: 0,
            t0: f64::NAN,
            trace,
            stop,
            stopped: false,
        }
    }

    /// The run's record from its outcome; `None` when it was stopped.
    pub(crate) fn record(
        self,
        values: Vec<f64>,
        result: Result<satsim_integrate::Stats, RunError<String>>,
    ) -> Option<RunRecord> {
        if self.stopped {
            return None;
        }
        Some(match result {
            Ok(stats) => {
                let mut c = self;
                // The run's own span: its first output row is at its start.
                let steps = satsim_integrate::Steps::of(&stats, c.t0);
                c.stats.held = c.campaign.stability_held(&steps);
                c.into_record(values)
            }
            Err(RunError::Integrate(e)) => RunRecord::failed(self.k, values, e.to_string()),
            Err(RunError::Sink { error, .. }) => {
                RunRecord::failed(self.k, values, format!("non-finite result: {error}"))
            }
        })
    }

    /// The beams' deflection peaks of the run `sim` made ([`RunStats::peaks`]).
    pub(crate) fn take_peaks(&mut self, sim: &Simulation) {
        self.stats.peaks = peaks(sim);
    }

    /// The record of a run that ended at its end time, from the rows collected.
    pub(crate) fn into_record(self, values: Vec<f64>) -> RunRecord {
        if self.rows == 0 {
            return RunRecord::failed(self.k, values, "the run wrote no output row".into());
        }
        RunRecord {
            k: self.k,
            values,
            outcome: Ok(self.stats),
            trace: self.trace,
            metrics: Vec::new(),
        }
    }
}

impl RowSink for Collect<'_> {
    type Error = String;
    fn row(&mut self, t: f64, row: &[f64]) -> Result<(), String> {
        if (self.stop)() {
            self.stopped = true;
            return Err("stopped".into());
        }
        // Finite: `Simulation::run` and the lanes refuse a row that is not before its sink
        // sees it (no second pass over every value here).
        debug_assert!(
            row.iter().all(|v| v.is_finite()),
            "a non-finite row at t = {t}"
        );
        let values = &row[1..];
        let s = &mut self.stats;
        s.last.copy_from_slice(values);
        for (m, &v) in s.min.iter_mut().zip(values) {
            *m = m.min(v);
        }
        for (m, &v) in s.max.iter_mut().zip(values) {
            *m = m.max(v);
        }
        if self.rows == 0 {
            self.t0 = t;
        }
        if self.rows.is_multiple_of(self.campaign.stride) {
            for (s, &c) in self.trace.iter_mut().zip(&self.campaign.trace_columns) {
                s.push(row[c]);
            }
        }
        self.rows += 1;
        Ok(())
    }
}

impl RunRecord {
    /// A failed run's record.
    pub fn failed(k: u64, values: Vec<f64>, why: String) -> Self {
        RunRecord {
            k,
            values,
            outcome: Err(why),
            trace: Vec::new(),
            metrics: Vec::new(),
        }
    }
}

/// `f()`, or the message of its panic as a failed run's (a bug, never the campaign's end).
pub(crate) fn catch_panic<T>(f: impl FnOnce() -> Result<T, String>) -> Result<T, String> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).unwrap_or_else(|p| {
        let what = p
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into());
        Err(format!("internal error (a bug in satsim): {what}"))
    })
}

/// The name of a watched flexible body's [`RunStats::peaks`] column, before the body's name.
pub const PEAK_PREFIX: &str = "peak_deflection_";

/// `peak_deflection_<body>` for each watched flexible body of `sim`'s model (a beam, or
/// given modes with a node off the body's frame), in body order: the columns of
/// [`RunStats::peaks`].
fn peak_columns(sim: &Simulation) -> Vec<String> {
    let bodies = sim.model().bodies();
    sim.deflection_peaks()
        .iter()
        .map(|p| format!("{PEAK_PREFIX}{}", bodies[p.body].name()))
        .collect()
}

/// [`RunStats::peaks`] of the runs `sim` made.
pub(crate) fn peaks(sim: &Simulation) -> Vec<f64> {
    sim.deflection_peaks()
        .iter()
        .map(|p| p.fraction())
        .collect()
}

/// `final_c, min_c, max_c` for every column but the first (`t`).
pub fn stat_columns(columns: &[String]) -> Vec<String> {
    columns[1..]
        .iter()
        .flat_map(|c| [format!("final_{c}"), format!("min_{c}"), format!("max_{c}")])
        .collect()
}

/// Whether a trajectory column gets an envelope plot: hinge angles and bus rates.
pub fn is_trace_column(c: &str) -> bool {
    c.starts_with("angle_") || c.starts_with("omega_")
}

/// How to run a campaign.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Worker threads (`None`: every core).
    pub threads: Option<usize>,
    /// Which runs.
    pub shard: Shard,
    /// Continue the campaign in the output folder, skipping the runs its `runs.csv` holds.
    pub resume: bool,
    /// Several runs per core in SIMD lanes where the scene allows it ([`lanes`]): the same
    /// records, sooner. `false`: one run at a time per thread.
    pub lanes: bool,
}

/// Told about a campaign's progress (the command line draws a progress bar).
pub trait Progress: Sync {
    /// `todo` runs are about to start; `skipped` were already in `runs.csv` (`--resume`).
    fn start(&self, _todo: u64, _skipped: u64) {}
    /// One run finished.
    fn finished(&self, _ok: bool) {}
    /// Whether to stop, asked before each run and at each run's output rows: once it turns
    /// true no run starts, those running stop at their next row and are left out (`--resume`
    /// runs them again), and the campaign ends with [`CampaignError::Interrupted`].
    fn cancelled(&self) -> bool {
        false
    }
}

/// No progress report.
pub struct Quiet;
impl Progress for Quiet {}

/// What a campaign did.
#[derive(Clone, Debug)]
pub struct Report {
    /// Runs executed now.
    pub ran: u64,
    /// Runs skipped because `runs.csv` already held them.
    pub skipped: u64,
    /// The finished folder.
    pub finished: Finished,
    /// How the runs used lanes ([`RunOptions::lanes`]), `None` where they ran one at a time.
    pub lanes: Option<LaneUse>,
}

/// How a campaign's runs used SIMD lanes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LaneUse {
    /// Runs per batch ([`Simulation::lane_width`]).
    pub width: usize,
    /// Right-hand sides of the runs made in batches.
    pub rhs: u64,
    /// Of those, the ones whose dynamics were solved in lanes (the others: a stage where the
    /// runs' lock masks differed, an event located by one run alone, a batch's tail).
    pub in_lanes: u64,
}

/// The files of a campaign folder.
pub const RUNS_CSV: &str = "runs.csv";
/// Envelope samples of the finished runs.
pub const TRACES_CSV: &str = "traces.csv";
/// The campaign's identity (scene, runs, seed, shard, histograms).
pub const CAMPAIGN_JSON: &str = "campaign.json";
/// The statistics.
pub const SUMMARY_JSON: &str = "summary.json";

/// Runs the shard `opts.shard` of `campaign` into `dir`: see the module documentation.
pub fn run_campaign(
    campaign: &Campaign,
    dir: &Path,
    opts: &RunOptions,
    progress: &dyn Progress,
) -> Result<Report, CampaignError> {
    let folder = Folder::open(campaign, dir, opts.shard, opts.resume, None, false)?;
    let todo = folder.todo().to_vec();
    let skipped = folder.skipped();
    progress.start(todo.len() as u64, skipped);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.threads.unwrap_or(0))
        .build()
        .map_err(|e| CampaignError::Other(format!("cannot start the thread pool: {e}")))?;
    let folder = Mutex::new(folder);
    let emit = |r: RunRecord| -> Result<(), CampaignError> {
        let ok = folder
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .emit(campaign, r)?;
        progress.finished(ok);
        Ok(())
    };
    let mut lane_use = None;
    if opts.lanes && lanes::applies(campaign) {
        // Each thread takes runs from the queue, several at a time in lanes.
        let next = std::sync::atomic::AtomicUsize::new(0);
        let failure = Mutex::new(None);
        let counts = [AtomicU64::new(0), AtomicU64::new(0)];
        let queue = lanes::Queue {
            todo: &todo,
            next: &next,
            counts: &counts,
        };
        pool.broadcast(|_| {
            lanes::work(
                campaign,
                &queue,
                &|| progress.cancelled(),
                &mut |r| match emit(r) {
                    Ok(()) => true,
                    Err(e) => {
                        failure
                            .lock()
                            .unwrap_or_else(|p| p.into_inner())
                            .get_or_insert(e);
                        false
                    }
                },
            )
        });
        if let Some(e) = failure.into_inner().unwrap_or_else(|p| p.into_inner()) {
            return Err(e);
        }
        let [rhs, in_lanes] = counts.map(AtomicU64::into_inner);
        lane_use = Some(LaneUse {
            width: Simulation::lane_width(),
            rhs,
            in_lanes,
        });
    } else {
        pool.install(|| {
            todo.par_iter()
                .with_max_len(1)
                .try_for_each(|&k| -> Result<(), CampaignError> {
                    if progress.cancelled() {
                        return Ok(());
                    }
                    match campaign.run_one_until(k, &|| progress.cancelled()) {
                        Some(r) => emit(r),
                        None => Ok(()),
                    }
                })
        })?;
    }
    let folder = folder.into_inner().unwrap_or_else(|p| p.into_inner());
    let ran = folder.ran();
    // Stopped part-way: runs.csv stays as streamed (complete rows, completion order), not
    // sorted or summarised, so that --resume takes it up (CampaignError::Interrupted).
    let finished = folder.close()?;
    Ok(Report {
        lanes: lane_use,
        ran,
        skipped,
        finished,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn example() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes/deploy_campaign.toml")
    }

    /// The example campaign shortened to `duration` seconds and `runs` runs (RK4, 0.01 s).
    pub(crate) fn short_example(duration: f64, runs: u64) -> Campaign {
        let text = std::fs::read_to_string(example())
            .unwrap()
            .replace("duration = 60.0", &format!("duration = {duration:?}"))
            .replace("runs = 64", &format!("runs = {runs}"));
        Campaign::parse(&text, &example()).unwrap()
    }

    #[test]
    fn the_scene_digest_follows_the_scene_not_the_campaign_table() {
        let text = std::fs::read_to_string(example()).unwrap();
        let digest = |t: &str| Campaign::parse(t, &example()).unwrap().scene_digest();
        let d = digest(&text);
        assert_eq!(d.len(), 16);
        assert_eq!(d, digest(&text), "deterministic");
        // More runs or another seed: the same scene (a campaign may be extended).
        assert_eq!(d, digest(&text.replace("runs = 64", "runs = 65")));
        assert_eq!(d, digest(&text.replace("seed = 2015", "seed = 7")));
        // Any change of what a run starts from: another digest.
        assert_ne!(d, digest(&text.replace("duration = ", "duration = 1")));
    }

    /// The sampled laws' loops are worked out for the nominal scene, whose warnings are
    /// printed, and not for each drawn run, whose are not.
    #[test]
    fn a_drawn_run_leaves_out_the_sampled_laws_warnings() {
        let sets = [
            "effects.attitude_control.period=5.0",
            "effects.attitude_control.kd=3000.0",
        ]
        .map(|s| Override::parse(s).unwrap());
        let c = Campaign::read_with(example(), &sets).unwrap_or_else(|e| panic!("{e}"));
        let unstable = |s: &Scene| {
            s.warnings
                .iter()
                .any(|w| w.contains("the sampled law is unstable"))
        };
        assert!(unstable(&c.nominal), "{:?}", c.nominal.warnings);
        let drawn = c.drawn_scene(0, &c.draw(0)).unwrap();
        assert!(!unstable(&drawn), "{:?}", drawn.warnings);
    }

    #[test]
    fn the_example_campaign_reads_and_every_draw_is_a_valid_scene() {
        let c = Campaign::read(example()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((c.runs, c.seed), (64, 2015));
        let columns: Vec<&str> = c.dispersed.iter().map(|d| d.column.as_str()).collect();
        assert_eq!(
            columns,
            [
                "effects.hinge_springs.stiffness[3]",
                "effects.hinge_springs.stiffness[4]",
                "effects.hinge_springs.damping[3]",
                "effects.hinge_springs.damping[4]",
                "initial.hinges.angle[3]",
                "initial.hinges.angle[4]",
                "model.body.4.mass",
                "model.body.5.mass",
                "effects.reaction_wheels.wheel.0.coulomb",
                "effects.reaction_wheels.wheel.1.coulomb",
                "effects.reaction_wheels.wheel.2.coulomb",
            ]
        );
        // The nominal values are those written in the scene and its model file (the stowed
        // fold angles are written as 3.14159, not pi).
        let folded: f64 = "3.14159".parse().unwrap();
        let nominal: Vec<f64> = c.dispersed.iter().map(|d| d.nominal).collect();
        assert_eq!(
            nominal,
            [
                2.0, 2.0, 4.0, 4.0, folded, -folded, 20.0, 20.0, 0.002, 0.002, 0.002
            ]
        );
        for k in 0..16 {
            let values = c.draw(k);
            let scene = Scene::parse(&c.scene_text(&values), &c.path).unwrap();
            // The substituted numbers arrive where the keys point.
            let springs = scene
                .effects
                .get::<satsim_spacecraft::effects::HingeSprings>()
                .unwrap();
            assert_eq!(springs.stiffness[3], values[0]);
            assert_eq!(springs.damping[4], values[3]);
            assert_eq!(scene.initial.q[7 + 3], values[4]);
            assert_eq!(scene.model.bodies()[4].mass(), values[6]);
            let wheels = scene
                .effects
                .get::<satsim_spacecraft::effects::ReactionWheels>()
                .unwrap();
            assert_eq!(wheels.wheels[2].coulomb, values[10]);
            // Untouched numbers stay as written.
            assert_eq!(springs.stiffness[0], 50.0);
            assert_eq!(scene.model.bodies()[3].mass(), 20.0);
        }
    }

    #[test]
    fn with_nothing_dispersed_a_run_is_the_nominal_scene() {
        let text = std::fs::read_to_string(example()).unwrap();
        let cut = text.find("[[campaign.disperse]]").unwrap();
        let text = text[..cut].replace("duration = 60.0", "duration = 2.0");
        let c = Campaign::parse(&text, &example()).unwrap();
        let r = c.run_one(3);
        let stats = r.outcome.unwrap();
        let mut sim = c.nominal.simulation().unwrap();
        let mut last = Vec::new();
        sim.run(
            &c.nominal.options,
            c.nominal.duration,
            &Times::Interval(c.nominal.every),
            |_, row| {
                last = row.to_vec();
                Ok::<(), ()>(())
            },
        )
        .unwrap();
        assert_eq!(stats.last, last[1..]);
    }
}
