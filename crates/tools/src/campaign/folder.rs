//! A campaign folder while its runs are made: [`Folder::open`] writes `campaign.json` and
//! opens `runs.csv` and `traces.csv` (fresh, or resumed: the runs they hold are skipped),
//! [`Folder::emit`] appends each run's record as it finishes, in any order and from any
//! process, and [`Folder::close`] finishes the folder ([`finish`]) once every run is in.
//!
//! [`run_campaign`](super::run_campaign) drives it with the built-in controllers on a
//! thread pool; `satsim.campaign(controller=...)` drives it from Python, the records made
//! by worker processes or any executor ([`super::stepped`]). Either way the folder is the
//! same: each row depends on its run alone, and [`finish`] sorts them.
//!
//! The user's metrics (`satsim.campaign(metrics=...)`) are columns after the statistics,
//! named by the keys of the first finished run's metrics (every run must give the same
//! keys; a run that gives others is failed). Rows of failed runs streamed before that get
//! those fields empty when the columns are added.

use super::files::{Appender, Streams, add_columns, open_append, open_streams};
use super::meta::Meta;
use super::{CAMPAIGN_JSON, Campaign, CampaignError, Finished, RUNS_CSV, RunRecord, Shard, finish};
use std::collections::HashSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A campaign folder being written: see the module documentation.
pub struct Folder {
    dir: PathBuf,
    meta: Meta,
    runs: Appender,
    traces: Appender,
    /// The user's metric columns, once a finished run named them.
    metrics: Vec<String>,
    /// Whether records may carry metrics (a campaign stepped by the user's controller).
    with_metrics: bool,
    todo: Vec<u64>,
    skipped: u64,
    ran: u64,
}

impl Folder {
    /// Opens `dir` for the shard `shard` of `campaign`: fresh, or with `resume` continuing
    /// the runs `runs.csv` holds (which must have been made with the same scene, draws,
    /// shard and `controller`). `controller` names the flight software that steps the runs
    /// (`None`: the built-in controllers); `with_metrics`: whether records carry the user's
    /// metrics.
    pub fn open(
        campaign: &Campaign,
        dir: &Path,
        shard: Shard,
        resume: bool,
        controller: Option<String>,
        with_metrics: bool,
    ) -> Result<Folder, CampaignError> {
        campaign.nominal.check_rows(campaign.max_rows())?;
        std::fs::create_dir_all(dir).map_err(|e| CampaignError::io(dir, e))?;
        let digest = campaign.scene_digest();
        let meta = Meta {
            scene: campaign.path.display().to_string(),
            runs: campaign.runs,
            seed: campaign.seed,
            shard,
            histograms: campaign.histograms.clone(),
            scene_digest: Some(digest.clone()),
            controller,
        };
        // A folder is resumed only with the scene its runs were made with: the drawn values
        // alone would not notice a changed model file or a different `--set`.
        let json = dir.join(CAMPAIGN_JSON);
        // Without a digest nothing says which scene the runs there were made with: refused.
        if resume && (json.exists() || dir.join(RUNS_CSV).exists()) {
            if !json.exists() {
                return Err(CampaignError::Other(format!(
                    "{}: no {CAMPAIGN_JSON} beside it, so nothing says which scene its runs were made with: --resume needs the folder a campaign wrote whole; use another --out",
                    dir.join(RUNS_CSV).display()
                )));
            }
            let before = Meta::read(dir)?;
            match &before.scene_digest {
                None => {
                    return Err(CampaignError::Other(format!(
                        "{}: has no scene digest (written by an older satsim), so nothing says which scene its runs were made with: use another --out",
                        json.display()
                    )));
                }
                Some(d) if *d != digest => {
                    return Err(CampaignError::Other(format!(
                        "{}: its runs were made with another scene (a changed scene, model file or --set value; scene digest {d} here, {digest} now): resume with the same scene and --set, or use another --out",
                        json.display(),
                    )));
                }
                Some(_) => {}
            }
            if before.controller != meta.controller {
                return Err(CampaignError::Other(format!(
                    "{}: its runs were made with another controller ({} there, {} now): resume with the same, or use another --out",
                    json.display(),
                    before.controller_name(),
                    meta.controller_name()
                )));
            }
        }
        meta.write(dir)?;
        let Streams {
            runs,
            traces,
            done,
            extra,
        } = open_streams(dir, &campaign.header(), resume, with_metrics)?;
        // Rows already there must be this campaign's (same draws), and this shard's.
        for (k, fields) in &done {
            if *k >= campaign.runs || !shard.contains(*k) {
                return Err(CampaignError::Other(format!(
                    "{}: holds run {k}, which is not in shard {shard} of a {}-run campaign: resume with the same --shard, or use another --out",
                    dir.join(RUNS_CSV).display(),
                    campaign.runs
                )));
            }
            let drawn: Vec<String> = campaign.draw(*k).iter().map(|v| v.to_string()).collect();
            if fields[1..=drawn.len()] != drawn[..] {
                return Err(CampaignError::Other(format!(
                    "{}: run {k} holds other drawn values than this campaign draws (was the seed or a dispersion changed?): use another --out",
                    dir.join(RUNS_CSV).display()
                )));
            }
        }
        let done: HashSet<u64> = done.into_iter().map(|(k, _)| k).collect();
        let todo: Vec<u64> = (0..campaign.runs)
            .filter(|k| shard.contains(*k) && !done.contains(k))
            .collect();
        Ok(Folder {
            dir: dir.to_path_buf(),
            meta,
            runs,
            traces,
            metrics: extra,
            with_metrics,
            todo,
            skipped: done.len() as u64,
            ran: 0,
        })
    }

    /// The runs to make, ascending.
    pub fn todo(&self) -> &[u64] {
        &self.todo
    }

    /// The runs `runs.csv` held already (resumed).
    pub fn skipped(&self) -> u64 {
        self.skipped
    }

    /// The runs emitted so far.
    pub fn ran(&self) -> u64 {
        self.ran
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The user's metric columns so far (empty until a finished run named them).
    pub fn metric_columns(&self) -> &[String] {
        &self.metrics
    }

    /// Appends run `r.k`'s record: its traces, then its row, each flushed (so a row in
    /// `runs.csv` always has its traces). A finished run whose metrics are named otherwise
    /// than the columns is written as failed, saying so. Returns whether the run counts
    /// as finished (`ok`).
    pub fn emit(&mut self, campaign: &Campaign, r: RunRecord) -> Result<bool, CampaignError> {
        let r = self.check_metrics(campaign, r)?;
        let mut row = campaign.csv_row(&r);
        if !self.metrics.is_empty() {
            row.pop(); // its line break
            if r.outcome.is_ok() {
                for (_, v) in &r.metrics {
                    let _ = write!(row, ",{v}");
                }
            } else {
                for _ in &self.metrics {
                    row.push(',');
                }
            }
            row.push('\n');
        }
        self.traces.append(&campaign.trace_lines(&r))?;
        self.runs.append(&row)?;
        self.ran += 1;
        Ok(r.outcome.is_ok())
    }

    /// `r`, or a failed record where its metrics do not fit the columns; names the columns
    /// at the first finished run that has metrics.
    fn check_metrics(
        &mut self,
        campaign: &Campaign,
        mut r: RunRecord,
    ) -> Result<RunRecord, CampaignError> {
        if r.outcome.is_err() {
            r.metrics.clear();
            return Ok(r);
        }
        if !self.with_metrics && !r.metrics.is_empty() {
            return Err(CampaignError::Other(
                "a run has metrics, but the folder was opened without them".into(),
            ));
        }
        if let Some((n, v)) = r.metrics.iter().find(|(_, v)| !v.is_finite()) {
            let why = format!(
                "run {} at its end: the metric `{n}` is {v}: a metric must be a finite number",
                r.k
            );
            return Ok(RunRecord::failed(r.k, r.values, why));
        }
        let names: Vec<&str> = r.metrics.iter().map(|(n, _)| n.as_str()).collect();
        if self.metrics.is_empty() && !names.is_empty() {
            if let Some(why) = metric_names_refused(campaign, &names) {
                let why = format!("run {} at its end: {why}", r.k);
                return Ok(RunRecord::failed(r.k, r.values, why));
            }
            // Named now: the header gets the columns, the rows before (all failed runs) the
            // fields empty.
            self.metrics = names.iter().map(|n| (*n).to_owned()).collect();
            let path = self.dir.join(RUNS_CSV);
            add_columns(&path, &self.metrics)?;
            self.runs = open_append(&path)?;
            return Ok(r);
        }
        if names != self.metrics.iter().map(String::as_str).collect::<Vec<_>>() {
            let why = format!(
                "run {} at its end: the metrics returned the keys [{}], the campaign's columns are [{}] (every run must return the same keys, in the same order)",
                r.k,
                names.join(", "),
                self.metrics.join(", ")
            );
            return Ok(RunRecord::failed(r.k, r.values, why));
        }
        Ok(r)
    }

    /// Finishes the folder ([`finish`]: sorted files, `summary.json`, the plots) once every
    /// run of [`Folder::todo`] was emitted; otherwise leaves `runs.csv` as streamed (every
    /// emitted run kept, for a resume) and returns [`CampaignError::Interrupted`].
    pub fn close(self) -> Result<Finished, CampaignError> {
        let Folder {
            dir,
            meta,
            runs,
            traces,
            todo,
            skipped,
            ran,
            ..
        } = self;
        drop((runs, traces));
        if ran < todo.len() as u64 {
            return Err(CampaignError::Interrupted {
                runs_csv: dir.join(RUNS_CSV),
                held: skipped + ran,
                left: todo.len() as u64 - ran,
            });
        }
        finish(&dir, &meta)
    }
}

/// Why the user's metric names cannot be columns of `runs.csv`, if they cannot.
fn metric_names_refused(campaign: &Campaign, names: &[&str]) -> Option<String> {
    let header = campaign.header();
    for (i, n) in names.iter().enumerate() {
        if let Err(e) = satsim_tree::io::column_name(n) {
            return Some(format!("the metric `{n}` cannot be a column: {e}"));
        }
        if header.iter().any(|h| h == n) || names[..i].contains(n) {
            return Some(format!(
                "the metric `{n}` is a column already: name it otherwise"
            ));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with(mut r: RunRecord, metrics: &[(&str, f64)]) -> RunRecord {
        r.metrics = metrics.iter().map(|(n, v)| ((*n).to_owned(), *v)).collect();
        r
    }

    /// The metric columns are named by the first finished run: failed rows streamed before
    /// get the fields empty; a run with other keys, or a non-finite value, is failed.
    #[test]
    fn metrics_become_columns_named_by_the_first_finished_run() {
        let c = super::super::tests::short_example(0.5, 4);
        let dir = std::env::temp_dir().join(format!("satsim-folder-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut f = Folder::open(
            &c,
            &dir,
            Shard::ALL,
            false,
            Some("m:f every 0.1 s".into()),
            true,
        )
        .unwrap();
        assert_eq!(f.todo(), [0, 1, 2, 3]);
        let failed = RunRecord::failed(3, c.draw(3), "boom".into());
        assert!(!f.emit(&c, failed).unwrap());
        assert!(
            f.emit(&c, with(c.run_one(1), &[("a", 1.5), ("b", 2.0)]))
                .unwrap()
        );
        assert_eq!(f.metric_columns(), ["a", "b"]);
        assert!(
            !f.emit(&c, with(c.run_one(0), &[("b", 1.0), ("a", 2.0)]))
                .unwrap()
        );
        assert!(
            !f.emit(&c, with(c.run_one(2), &[("a", f64::NAN), ("b", 2.0)]))
                .unwrap()
        );
        f.close().unwrap();
        let text = std::fs::read_to_string(dir.join(RUNS_CSV)).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines[0].ends_with(",a,b"), "{}", lines[0]);
        let width = lines[0].split(',').count();
        for l in &lines[1..] {
            assert_eq!(super::super::files::split(l).len(), width, "{l}");
        }
        assert!(
            lines[2].contains(",ok,") && lines[2].ends_with(",1.5,2"),
            "{}",
            lines[2]
        );
        assert!(lines[1].contains("the metrics returned the keys [b, a]"));
        assert!(
            lines[3].contains("run 2 at its end: the metric `a` is NaN"),
            "{}",
            lines[3]
        );
        assert!(lines[1].contains("run 0 at its end: "), "{}", lines[1]);
        assert!(lines[4].contains("boom") && lines[4].ends_with(",,"));
        // Resumed with another controller: refused.
        let e = Folder::open(&c, &dir, Shard::ALL, true, None, false)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("another controller"), "{e}");
        let again = Folder::open(
            &c,
            &dir,
            Shard::ALL,
            true,
            Some("m:f every 0.1 s".into()),
            true,
        )
        .unwrap();
        assert_eq!(
            (again.todo().len(), again.metric_columns()),
            (0, &["a".to_owned(), "b".to_owned()][..])
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
