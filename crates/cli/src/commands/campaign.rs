//! `satsim campaign SCENE.toml [--out DIR] [--threads T] [--shard I/N] [--shards N]
//! [--resume] [--no-lanes]` and `satsim campaign merge DIR... --out DIR` (contract section 8): a thin
//! wrapper over [`satsim_tools::campaign`].
//!
//! Without `--shard`, the shard comes from the scheduler's environment when present (Slurm
//! job array, Kubernetes indexed Job with `--shards N`, AWS Batch array job); standard error
//! says which was used. A progress bar (runs, runs per second, time left, failures) is drawn
//! on standard error when it is a terminal. Exit status 0 when the campaign could run, even
//! with failed runs; 2 for bad input; 130 when stopped by Ctrl-C (`runs.csv` keeps every
//! finished run, `--resume` continues).

use super::{CliError, Output, at_least_one, stem, usage};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use satsim_tools::campaign::{
    self, Campaign, CampaignError, Finished, Progress, RunOptions, Shard, choose_shard,
};
use satsim_tools::scene_keys::Override;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// The flags of `satsim campaign`.
#[derive(Debug, clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct Args {
    /// `satsim campaign merge`
    #[command(subcommand)]
    pub merge: Option<Merge>,
    /// The scene file with a [campaign] table (TOML, cli-contract sections 7 and 8)
    #[arg(value_name = "SCENE.toml", required = true)]
    pub scene: Option<PathBuf>,
    /// Output folder [default: out/<scene stem>-campaign]
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Worker threads [default: all cores]
    #[arg(long, value_name = "T", value_parser = at_least_one)]
    pub threads: Option<usize>,
    /// Run only the runs k with k % N == I (0 <= I < N) [default: from the scheduler's
    /// environment (Slurm, Kubernetes indexed Job, AWS Batch), else 0/1]
    #[arg(long, value_name = "I/N", value_parser = parse_shard)]
    pub shard: Option<Shard>,
    /// The shard count of a Kubernetes indexed Job (its index comes from
    /// JOB_COMPLETION_INDEX)
    #[arg(long, value_name = "N", value_parser = at_least_one)]
    pub shards: Option<usize>,
    /// Keep the runs already in DIR/runs.csv and run only the missing ones
    #[arg(long)]
    pub resume: bool,
    /// One run at a time per thread: no SIMD lanes of runs (fixed-step RK4 scenes of the
    /// preprint's layout otherwise run 8 per core with AVX-512, 4 with AVX2, 2 without; the
    /// results are the same, byte for byte)
    #[arg(long)]
    pub no_lanes: bool,
    /// Override a scene value by its dotted path before the runs are drawn, e.g.
    /// `--set campaign.runs=20` (repeatable)
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = super::run::parse_override)]
    pub set: Vec<Override>,
    /// Refuse a campaign whose runs would each write more rows than this
    /// (`duration / output.every`); a drawn scene beyond it is a failed run
    #[arg(long, value_name = "N", default_value_t = satsim_tools::scene::DEFAULT_MAX_ROWS)]
    pub max_rows: u64,
}

/// The subcommand of `satsim campaign`.
#[derive(Debug, clap::Subcommand)]
pub enum Merge {
    /// Merge the shards' output folders into the one a single machine would have written
    /// (byte-identical runs.csv)
    Merge(MergeArgs),
}

/// The flags of `satsim campaign merge`.
#[derive(Debug, clap::Args)]
pub struct MergeArgs {
    /// The shards' output folders (each written by `satsim campaign ... --shard I/N`)
    #[arg(value_name = "SHARD_DIR", required = true)]
    pub dirs: Vec<PathBuf>,
    /// The merged folder
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

fn parse_shard(s: &str) -> Result<Shard, String> {
    s.parse::<Shard>().map_err(|e| e.to_string())
}

fn from(e: CampaignError) -> CliError {
    match e {
        CampaignError::File(f) => CliError::File(f),
        e @ CampaignError::Interrupted { .. } => CliError::Interrupted(e.to_string()),
        other => CliError::Other(other.to_string()),
    }
}

/// Runs `satsim campaign`.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let scene_path = match (&args.merge, &args.scene) {
        (Some(Merge::Merge(m)), _) => return merge(m),
        (None, Some(scene)) => scene,
        // clap requires one or the other.
        (None, None) => return Err(usage(&["campaign"], "missing the scene file")),
    };
    let choice = choose_shard(args.shard, args.shards.map(|n| n as u64), |n| {
        std::env::var(n).ok()
    })
    .map_err(|e| usage(&["campaign"], e))?;
    let mut c = Campaign::read_with(scene_path, &args.set)?;
    c.set_max_rows(args.max_rows);
    super::print_warnings(&c.nominal.warnings);
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(format!("{}-campaign", stem(scene_path))));
    // A split campaign names its shard before it runs, for a scheduler's log of a job that
    // never finishes; the whole campaign's shard is only in the summary.
    if choice.shard != Shard::ALL {
        eprintln!(
            "satsim campaign: shard {} ({})",
            choice.shard, choice.source
        );
    }
    let threads_used = args.threads.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    });
    let bar = Bar::new();
    let started = Instant::now();
    // Ctrl-C: no new run starts, the running ones stop at their next row and are left out
    // (`--resume` runs them again), exit 130 (a
    // second Ctrl-C within 2 s is ignored, a later one ends the process at once).
    super::run::interrupt::install();
    let report = campaign::run_campaign(
        &c,
        &dir,
        &RunOptions {
            threads: args.threads,
            shard: choice.shard,
            resume: args.resume,
            lanes: !args.no_lanes,
        },
        &bar,
    );
    bar.bar.finish_and_clear();
    let report = report.map_err(from)?;
    let secs = started.elapsed().as_secs_f64();

    let mut s = String::new();
    let _ = writeln!(
        s,
        "campaign   {} ({} runs, seed {}, {} dispersed values)",
        scene_path.display(),
        c.runs,
        c.seed,
        c.dispersed.len()
    );
    let _ = writeln!(s, "shard      {} ({})", choice.shard, choice.source);
    let _ = writeln!(
        s,
        "ran        {} runs in {secs:.2} s ({:.2} runs/s) on {threads_used} thread{}{}",
        report.ran,
        report.ran as f64 / secs.max(1e-9),
        if threads_used == 1 { "" } else { "s" },
        if report.skipped > 0 {
            format!("; {} already in runs.csv (--resume)", report.skipped)
        } else {
            String::new()
        }
    );
    if let Some(l) = report.lanes {
        let _ = writeln!(
            s,
            "lanes      {} runs per core in SIMD lanes; {:.1} % of their right-hand sides solved in lanes (--no-lanes: one at a time, the same results)",
            l.width,
            100.0 * l.in_lanes as f64 / (l.rhs.max(1) as f64)
        );
    }
    summary_lines(&mut s, &dir, &report.finished);
    Ok(s)
}

/// The summary's lines; a warning on standard error where finished runs bent a body
/// beyond its modal model, moved their energy budget, or had their steps held by a stability
/// limit (as `satsim run` warns of its one run).
fn summary_lines(s: &mut String, dir: &Path, f: &Finished) {
    if f.beyond > 0 {
        super::print_warnings(&[campaign::beyond_warning(f.beyond, f.ok)]);
    }
    if f.drifted > 0 {
        super::print_warnings(&[campaign::budget_warning(f.drifted, f.ok)]);
    }
    if f.held > 0 {
        super::print_warnings(&[campaign::held_warning(f.held, f.ok)]);
    }
    let _ = writeln!(
        s,
        "runs       {} in runs.csv: {} ok, {} failed{}",
        f.runs,
        f.ok,
        f.failed,
        if f.missing > 0 {
            format!(", {} missing", f.missing)
        } else {
            String::new()
        }
    );
    let plots = f.files.iter().filter(|n| n.ends_with(".svg")).count();
    let data: Vec<&str> = f
        .files
        .iter()
        .filter(|n| !n.ends_with(".svg"))
        .map(String::as_str)
        .collect();
    let _ = writeln!(
        s,
        "wrote      {}: {} and {plots} plots",
        dir.display(),
        data.join(", ")
    );
}

fn merge(args: &MergeArgs) -> Result<Output, CliError> {
    let (dirs, out) = (&args.dirs, &args.out);
    let f = campaign::merge(dirs, out).map_err(from)?;
    let mut s = String::new();
    let _ = writeln!(s, "merged     {} folders", dirs.len());
    summary_lines(&mut s, out, &f);
    Ok(s)
}

/// The progress bar: runs done, runs per second, time left, failures so far. Hidden when
/// standard error is not a terminal.
struct Bar {
    bar: ProgressBar,
    failed: AtomicU64,
}

impl Bar {
    fn new() -> Self {
        let bar = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr());
        bar.set_style(
            ProgressStyle::with_template(
                "[{bar:30}] {pos}/{len} runs  {per_sec}  {eta} left  {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("#> "),
        );
        Self {
            bar,
            failed: AtomicU64::new(0),
        }
    }
}

impl Progress for Bar {
    fn start(&self, todo: u64, _skipped: u64) {
        self.bar.set_length(todo);
        self.bar.reset_eta();
    }
    fn finished(&self, ok: bool) {
        if !ok {
            let n = self.failed.fetch_add(1, Ordering::Relaxed) + 1;
            self.bar.set_message(format!("{n} failed"));
        }
        self.bar.inc(1);
    }
    fn cancelled(&self) -> bool {
        super::run::interrupt::requested()
    }
}
