//! `satsim campaign SCENE.toml [--out DIR] [--threads T] [--shard I/N] [--shards N]
//! [--resume]` and `satsim campaign merge DIR... --out DIR` (contract section 8): a thin
//! wrapper over [`satsim_satellite::campaign`].
//!
//! Without `--shard`, the shard comes from the scheduler's environment when present (Slurm
//! job array, Kubernetes indexed Job with `--shards N`, AWS Batch array job); standard error
//! says which was used. A progress bar (runs, runs per second, time left, failures) is drawn
//! on standard error when it is a terminal. Exit status 0 when the campaign could run, even
//! with failed runs; 2 for bad input.

use super::{CliError, Options, Output, usage_line};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use satsim_satellite::campaign::{
    self, Campaign, CampaignError, Finished, Progress, RunOptions, Shard, choose_shard,
};
use std::ffi::OsString;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

const NAME: &str = "campaign";

fn usage(message: impl Into<String>) -> CliError {
    CliError::Usage {
        command: Some(NAME),
        message: message.into(),
    }
}

fn from(e: CampaignError) -> CliError {
    match e {
        CampaignError::File(f) => CliError::File(f),
        other => CliError::Other(other.to_string()),
    }
}

/// Runs `satsim campaign ARGS`.
pub fn run(args: &[OsString]) -> Result<Output, CliError> {
    if args.first().is_some_and(|a| a == "merge") {
        return merge(&args[1..]);
    }
    let resume = args.iter().any(|a| a == "--resume");
    let rest: Vec<OsString> = args.iter().filter(|a| *a != "--resume").cloned().collect();
    let opts = Options::parse(
        NAME,
        &rest,
        &["out", "threads", "shard", "shards", "set"],
        1,
    )?;
    if opts.help {
        return Ok(format!("usage: {}\n", usage_line(Some(NAME))));
    }
    let scene_path = opts
        .positional
        .first()
        .map(PathBuf::from)
        .ok_or_else(|| usage("missing the scene file"))?;
    let number = |name: &str| -> Result<Option<u64>, CliError> {
        opts.get(name)
            .map(|v| {
                v.to_string_lossy()
                    .parse::<u64>()
                    .ok()
                    .filter(|n| *n >= 1)
                    .ok_or_else(|| {
                        usage(format!(
                            "`--{name}` must be a whole number >= 1, got `{}`",
                            v.to_string_lossy()
                        ))
                    })
            })
            .transpose()
    };
    let threads = number("threads")?.map(|t| t as usize);
    let shards = number("shards")?;
    let flag = opts
        .get("shard")
        .map(|s| {
            s.to_string_lossy()
                .parse::<Shard>()
                .map_err(|e| usage(format!("`--shard`: {e}")))
        })
        .transpose()?;
    let choice = choose_shard(flag, shards, |n| std::env::var(n).ok()).map_err(usage)?;

    let c = Campaign::read_with(&scene_path, &opts.overrides(NAME)?)?;
    let stem = scene_path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let dir = opts
        .path("out")
        .unwrap_or_else(|| Path::new("out").join(format!("{stem}-campaign")));
    eprintln!(
        "satsim campaign: shard {} ({})",
        choice.shard, choice.source
    );
    let threads_used = threads.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    });
    let bar = Bar::new();
    let started = Instant::now();
    let report = campaign::run_campaign(
        &c,
        &dir,
        &RunOptions {
            threads,
            shard: choice.shard,
            resume,
        },
        &bar,
    )
    .map_err(from)?;
    bar.bar.finish_and_clear();
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
    summary_lines(&mut s, &dir, &report.finished);
    Ok(s)
}

fn summary_lines(s: &mut String, dir: &Path, f: &Finished) {
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

fn merge(args: &[OsString]) -> Result<Output, CliError> {
    let opts = Options::parse(NAME, args, &["out"], usize::MAX)?;
    if opts.help {
        return Ok(format!("usage: {}\n", usage_line(Some(NAME))));
    }
    let out = opts.required_path(NAME, "out")?;
    if opts.positional.is_empty() {
        return Err(usage("`merge` needs the campaign folders to merge"));
    }
    let dirs: Vec<PathBuf> = opts.positional.iter().map(PathBuf::from).collect();
    let f = campaign::merge(&dirs, &out).map_err(from)?;
    let mut s = String::new();
    let _ = writeln!(s, "merged     {} folders", dirs.len());
    summary_lines(&mut s, &out, &f);
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
}
