//! The campaign folder: `runs.csv` (streamed, then sorted by `k`), `traces.csv` (envelope
//! samples), `campaign.json`, `summary.json` and the plots; resuming and merging.
//!
//! `runs.csv` is plain CSV (RFC 4180): fields are separated by commas, and a field holding a
//! comma, a quote or a line break is quoted with its quotes doubled (messages have their line
//! breaks replaced by spaces, so a row is one line). Numbers are written in Rust's shortest
//! round-trip form, so reading them back gives the same `f64` to the last bit.

pub use super::meta::Meta;
use super::stats::{ColumnStats, column_stats};
use super::{
    CAMPAIGN_JSON, CampaignError, HELD_COLUMN, PEAK_PREFIX, RUNS_CSV, SUMMARY_JSON, Shard,
    TRACES_CSV,
};
use crate::output::quote;
use satsim_tree::flexible::SMALL_DEFLECTION;
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The fields of one CSV line (without its line break).
pub fn split(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            (true, '"') => quoted = false,
            (false, '"') if field.is_empty() => quoted = true,
            (false, ',') => out.push(std::mem::take(&mut field)),
            (_, c) => field.push(c),
        }
    }
    out.push(field);
    out
}

/// A file appended to line by line, flushed after each append.
pub(crate) struct Appender {
    path: PathBuf,
    out: BufWriter<File>,
}

impl Appender {
    pub(crate) fn append(&mut self, text: &str) -> Result<(), CampaignError> {
        if text.is_empty() {
            return Ok(());
        }
        self.out
            .write_all(text.as_bytes())
            .and_then(|_| self.out.flush())
            .map_err(|e| CampaignError::io(&self.path, e))
    }
}

/// Complete lines of `text` (those ending in a line break) and the byte length they span.
fn complete_lines(text: &str) -> (Vec<&str>, usize) {
    let end = text.rfind('\n').map_or(0, |i| i + 1);
    (text[..end].lines().collect(), end)
}

/// Where a `runs.csv` header `found` departs from the `expected` one, in words: the first
/// column that differs, or the columns one lacks. Columns after `expected` are the user's
/// metrics where `extra` allows them. A folder written by an earlier satsim lacks the columns
/// added since (`stability_held`, after the statistics and the beams' peaks), so its rows
/// cannot be completed: the message says so rather than only that the headers differ.
fn columns_differ(found: &[String], expected: &[String], extra: bool) -> String {
    let lacks: Vec<&str> = expected
        .iter()
        .filter(|e| !found.contains(e))
        .map(String::as_str)
        .collect();
    // The columns satsim appended after the first campaigns: a folder without them, its
    // other columns in order, is an earlier version's.
    let added = |c: &str| c == HELD_COLUMN || c.starts_with(PEAK_PREFIX);
    let kept: Vec<&String> = expected.iter().filter(|e| found.contains(e)).collect();
    let earlier = !lacks.is_empty()
        && lacks.iter().all(|c| added(c))
        && found.len() >= kept.len()
        && found.iter().zip(&kept).all(|(f, k)| f == *k)
        && (found.len() == kept.len() || extra);
    if earlier {
        return format!(
            "it lacks `{}`, which this satsim writes: a folder from an earlier version",
            lacks.join("`, `")
        );
    }
    let common = found.len().min(expected.len());
    match (0..common).find(|&c| found[c] != expected[c]) {
        Some(c) => format!(
            "column {} is `{}` where this campaign writes `{}`: other dispersions or another scene",
            c + 1,
            found[c],
            expected[c]
        ),
        None if found.len() < expected.len() => format!(
            "it ends before `{}`: other dispersions or another scene",
            expected[common]
        ),
        None => format!(
            "`{}` after this campaign's {common} columns: other dispersions or another scene",
            found[common]
        ),
    }
}

/// `runs.csv` and `traces.csv` opened for streaming ([`open_streams`]).
pub(crate) struct Streams {
    pub(crate) runs: Appender,
    pub(crate) traces: Appender,
    /// The rows a resumed `runs.csv` holds, as `(k, fields)`.
    pub(crate) done: Vec<(u64, Vec<String>)>,
    /// The columns a resumed `runs.csv` has after `header` (the user's metrics).
    pub(crate) extra: Vec<String>,
}

/// Opens `runs.csv` and `traces.csv` for streaming. Fresh (header written) unless `resume`
/// and `runs.csv` exists; then its header must be `header` (followed by more columns, the
/// user's metrics, where `extra` allows), a cut-off last line (a campaign killed mid-write)
/// is removed, and the rows it holds are returned.
pub(crate) fn open_streams(
    dir: &Path,
    header: &[String],
    resume: bool,
    extra: bool,
) -> Result<Streams, CampaignError> {
    let runs_path = dir.join(RUNS_CSV);
    let traces_path = dir.join(TRACES_CSV);
    let head = header
        .iter()
        .map(|h| quote(h))
        .collect::<Vec<_>>()
        .join(",");
    let mut done = Vec::new();
    let mut more = Vec::new();
    let resuming = resume && runs_path.exists();
    if resuming {
        let text =
            std::fs::read_to_string(&runs_path).map_err(|e| CampaignError::io(&runs_path, e))?;
        let (lines, end) = complete_lines(&text);
        let first = lines.first().copied().unwrap_or_default();
        match first.strip_prefix(head.as_str()) {
            Some("") => {}
            Some(rest) if extra && rest.starts_with(',') => more = split(&rest[1..]),
            _ => {
                return Err(CampaignError::Other(format!(
                    "{}: its header is not this campaign's ({}); use another --out, or run without --resume to start again",
                    runs_path.display(),
                    columns_differ(&split(first), header, extra)
                )));
            }
        }
        let width = header.len() + more.len();
        for (n, line) in lines.iter().enumerate().skip(1) {
            let fields = split(line);
            let k = fields[0].parse::<u64>().map_err(|_| {
                CampaignError::io(&runs_path, format!("line {}: bad run number", n + 1))
            })?;
            if fields.len() != width {
                return Err(CampaignError::io(
                    &runs_path,
                    format!("line {}: {} fields, expected {width}", n + 1, fields.len()),
                ));
            }
            done.push((k, fields));
        }
        truncate(&runs_path, end)?;
        if traces_path.exists() {
            let t = std::fs::read_to_string(&traces_path)
                .map_err(|e| CampaignError::io(&traces_path, e))?;
            let (_, end) = complete_lines(&t);
            truncate(&traces_path, end)?;
        }
    } else {
        std::fs::write(&runs_path, format!("{head}\n"))
            .map_err(|e| CampaignError::io(&runs_path, e))?;
        std::fs::write(&traces_path, "").map_err(|e| CampaignError::io(&traces_path, e))?;
    }
    let open = open_append;
    Ok(Streams {
        runs: open(&runs_path)?,
        traces: open(&traces_path)?,
        done,
        extra: more,
    })
}

/// Opens `path` for appending.
pub(crate) fn open_append(path: &Path) -> Result<Appender, CampaignError> {
    let f = OpenOptions::new()
        .append(true)
        .create(true)
        .open(path)
        .map_err(|e| CampaignError::io(path, e))?;
    Ok(Appender {
        path: path.to_path_buf(),
        out: BufWriter::new(f),
    })
}

/// Gives `runs.csv` (whose rows are all failed runs) the columns `more` after its own, the
/// failed rows' fields for them empty: the user's metrics, named by the first run that
/// finished. Rewritten whole through a temporary file.
pub(crate) fn add_columns(path: &Path, more: &[String]) -> Result<(), CampaignError> {
    let text = std::fs::read_to_string(path).map_err(|e| CampaignError::io(path, e))?;
    let (lines, _) = complete_lines(&text);
    let mut out = String::with_capacity(text.len() + lines.len() * (more.len() + 1));
    for (n, line) in lines.iter().enumerate() {
        out.push_str(line);
        for m in more {
            out.push(',');
            if n == 0 {
                out.push_str(&quote(m));
            }
        }
        out.push('\n');
    }
    replace(path, &out)
}

fn truncate(path: &Path, len: usize) -> Result<(), CampaignError> {
    let f = OpenOptions::new()
        .write(true)
        .open(path)
        .map_err(|e| CampaignError::io(path, e))?;
    f.set_len(len as u64)
        .map_err(|e| CampaignError::io(path, e))
}

/// Writes `text` to `path` through a temporary file and a rename, so that a reader (or a
/// crash) never sees half a file.
fn replace(path: &Path, text: &str) -> Result<(), CampaignError> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, text).map_err(|e| CampaignError::io(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| CampaignError::io(path, e))
}

/// What [`finish`] found and wrote.
#[derive(Clone, Debug)]
pub struct Finished {
    /// Rows in `runs.csv`.
    pub runs: u64,
    /// Rows with status `ok`.
    pub ok: u64,
    /// Rows with status `failed`.
    pub failed: u64,
    /// Runs of the campaign (or shard) that `runs.csv` does not hold.
    pub missing: u64,
    /// Finished runs that bent a flexible body beyond what its modal model holds: a
    /// `peak_deflection_<body>` past
    /// [`SMALL_DEFLECTION`] (the run `ok`, its
    /// results from then on not the structure's).
    pub beyond: u64,
    /// Finished runs whose energy budget moved by more than
    /// [`BUDGET_DRIFT`](satsim_spacecraft::simulation::BUDGET_DRIFT) of its largest term
    /// ([`budget_drifted_row`](super::budget_drifted_row)): the integration's error.
    pub drifted: u64,
    /// Finished runs whose steps their explicit method's stability limit held rather than
    /// the tolerance: a 1 in [`HELD_COLUMN`] ([`RunStats::held`](super::RunStats::held)).
    pub held: u64,
    /// The files written (names in the folder).
    pub files: Vec<String>,
}

/// The rows of a `runs.csv`: header and `(k, line)` of each complete row.
struct RunsFile {
    header: String,
    rows: Vec<(u64, String)>,
}

fn read_runs(path: &Path) -> Result<RunsFile, CampaignError> {
    let text = std::fs::read_to_string(path).map_err(|e| CampaignError::io(path, e))?;
    let (lines, _) = complete_lines(&text);
    let Some((head, rest)) = lines.split_first() else {
        return Err(CampaignError::io(path, "no header"));
    };
    let mut rows = Vec::with_capacity(rest.len());
    for (n, line) in rest.iter().enumerate() {
        let k = line
            .split(',')
            .next()
            .and_then(|f| f.parse::<u64>().ok())
            .ok_or_else(|| CampaignError::io(path, format!("line {}: bad run number", n + 2)))?;
        rows.push((k, (*line).to_owned()));
    }
    Ok(RunsFile {
        header: (*head).to_owned(),
        rows,
    })
}

/// Sorts by `k` and drops exact duplicates; two different rows for one run are an error.
fn sort_rows(rows: &mut Vec<(u64, String)>, what: &Path) -> Result<(), CampaignError> {
    rows.sort();
    rows.dedup();
    if let Some(w) = rows.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(CampaignError::Other(format!(
            "{}: run {} appears twice with different results (folders of different campaigns?)",
            what.display(),
            w[0].0
        )));
    }
    Ok(())
}

/// Finishes a campaign folder: rewrites `runs.csv` and `traces.csv` sorted by `k` (the
/// traces of runs not in `runs.csv` dropped), then writes `summary.json` and the plots, all
/// computed from the sorted files.
pub fn finish(dir: &Path, meta: &Meta) -> Result<Finished, CampaignError> {
    let runs_path = dir.join(RUNS_CSV);
    let mut runs = read_runs(&runs_path)?;
    sort_rows(&mut runs.rows, &runs_path)?;
    let mut text = String::with_capacity(runs.rows.iter().map(|r| r.1.len() + 1).sum());
    text.push_str(&runs.header);
    text.push('\n');
    for (_, line) in &runs.rows {
        text.push_str(line);
        text.push('\n');
    }
    replace(&runs_path, &text)?;

    let header = split(&runs.header);
    let status = header
        .iter()
        .position(|h| h == "status")
        .ok_or_else(|| CampaignError::io(&runs_path, "no `status` column"))?;
    let first_stat = status + 2;
    let stat_names = &header[first_stat..];
    let mut ok_rows: Vec<(u64, Vec<f64>)> = Vec::new();
    let mut failed = 0u64;
    for (k, line) in &runs.rows {
        let f = split(line);
        if f.len() != header.len() {
            return Err(CampaignError::io(
                &runs_path,
                format!("run {k}: {} fields, expected {}", f.len(), header.len()),
            ));
        }
        if f[status] == "ok" {
            let vals = f[first_stat..]
                .iter()
                .map(|x| x.parse::<f64>())
                .collect::<Result<Vec<f64>, _>>()
                .map_err(|_| CampaignError::io(&runs_path, format!("run {k}: bad number")))?;
            ok_rows.push((*k, vals));
        } else {
            failed += 1;
        }
    }

    // Traces: keep the finished ok runs', sorted by k then column. A line whose every value
    // parses is copied as written: a value written as `{:.7e}` reads back as the nearest
    // double, which `{:.7e}` writes as the same text, so formatting it again (most of this
    // pass's time) would change nothing.
    let traces_path = dir.join(TRACES_CSV);
    let mut traces: BTreeMap<u64, Vec<(String, Vec<f64>)>> = BTreeMap::new();
    let mut written: BTreeMap<u64, Vec<Option<&str>>> = BTreeMap::new();
    let text = if traces_path.exists() {
        std::fs::read_to_string(&traces_path).map_err(|e| CampaignError::io(&traces_path, e))?
    } else {
        String::new()
    };
    let (lines, _) = complete_lines(&text);
    let ok: HashMap<u64, ()> = ok_rows.iter().map(|(k, _)| (*k, ())).collect();
    for line in lines {
        let mut it = line.split(',');
        let (Some(k_text), Some(col)) = (it.next(), it.next()) else {
            continue;
        };
        let Ok(k) = k_text.parse::<u64>() else {
            continue;
        };
        if !ok.contains_key(&k) {
            continue;
        }
        // The values as written, from the comma after the column.
        let values_text = &line[(k_text.len() + 1 + col.len()).min(line.len())..];
        let mut fields = 0;
        let vals: Vec<f64> = it
            .inspect(|_| fields += 1)
            .filter_map(|v| v.parse().ok())
            .collect();
        let as_written = (vals.len() == fields).then_some(values_text);
        let entry = traces.entry(k).or_default();
        let texts = written.entry(k).or_default();
        match entry.iter().position(|(c, _)| c == col) {
            Some(i) => {
                entry[i].1 = vals;
                texts[i] = as_written;
            }
            None => {
                entry.push((col.to_owned(), vals));
                texts.push(as_written);
            }
        }
    }
    let mut t = String::new();
    for ((k, cols), texts) in traces.iter().zip(written.values()) {
        for ((c, vals), as_written) in cols.iter().zip(texts) {
            let _ = write!(t, "{k},{c}");
            match as_written {
                Some(values) => t.push_str(values),
                None => {
                    for v in vals {
                        let _ = write!(t, ",{v:.7e}");
                    }
                }
            }
            t.push('\n');
        }
    }
    replace(&traces_path, &t)?;

    // Summary.
    let n_ok = ok_rows.len() as u64;
    let peaks: Vec<usize> = (0..stat_names.len())
        .filter(|&c| stat_names[c].starts_with(PEAK_PREFIX))
        .collect();
    let beyond = ok_rows
        .iter()
        .filter(|(_, v)| peaks.iter().any(|&c| v[c] > SMALL_DEFLECTION))
        .count() as u64;
    let drifted = ok_rows
        .iter()
        .filter(|(_, v)| super::budget_drifted_row(stat_names, v))
        .count() as u64;
    // A folder written before the column was: none counted.
    let held = stat_names
        .iter()
        .position(|c| c == HELD_COLUMN)
        .map_or(0, |c| ok_rows.iter().filter(|(_, v)| v[c] == 1.0).count()) as u64;
    let n_runs = runs.rows.len() as u64;
    let missing = meta.expected().saturating_sub(n_runs);
    let mut all_stats: Vec<Option<ColumnStats>> = Vec::with_capacity(stat_names.len());
    let mut column = Vec::with_capacity(ok_rows.len());
    for c in 0..stat_names.len() {
        column.clear();
        column.extend(ok_rows.iter().map(|r| r.1[c]));
        all_stats.push(column_stats(&column));
    }
    let summary = Summary {
        counts: [
            ("runs", n_runs),
            ("ok", n_ok),
            ("failed", failed),
            ("missing", missing),
            ("campaign_runs", meta.runs),
            ("seed", meta.seed),
        ],
        shard: meta.shard.to_string(),
        names: stat_names,
        stats: &all_stats,
    };
    let mut s = serde_json::to_string_pretty(&summary)
        .map_err(|e| CampaignError::io(&dir.join(SUMMARY_JSON), e))?;
    s.push('\n');
    std::fs::write(dir.join(SUMMARY_JSON), &s)
        .map_err(|e| CampaignError::io(&dir.join(SUMMARY_JSON), e))?;

    let mut files = vec![
        RUNS_CSV.to_owned(),
        TRACES_CSV.to_owned(),
        SUMMARY_JSON.to_owned(),
    ];
    let plots = super::plots::write_all(dir, stat_names, &ok_rows, failed, &traces, meta)
        .map_err(|e| CampaignError::io(dir, format!("cannot write the plots: {e}")))?;
    files.extend(plots);
    Ok(Finished {
        runs: n_runs,
        ok: n_ok,
        failed,
        missing,
        beyond,
        drifted,
        held,
        files,
    })
}

/// `summary.json`: the counts, the shard, then every statistics column's percentiles, mean
/// and standard deviation in column order (`null` where no run finished or a value is not
/// finite).
struct Summary<'a> {
    counts: [(&'static str, u64); 6],
    shard: String,
    names: &'a [String],
    stats: &'a [Option<ColumnStats>],
}

impl serde::Serialize for Summary<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let finite = |x: f64| x.is_finite().then_some(x);
        let mut map = s.serialize_map(Some(self.counts.len() + 1 + self.names.len()))?;
        for (key, n) in &self.counts {
            map.serialize_entry(key, n)?;
        }
        map.serialize_entry("shard", &self.shard)?;
        for (name, st) in self.names.iter().zip(self.stats) {
            let values: [Option<f64>; 7] = match st {
                Some(st) => {
                    let p = st.percentiles;
                    [p[0], p[1], p[2], p[3], p[4], st.mean, st.std].map(finite)
                }
                None => [None; 7],
            };
            let keys = ["p1", "p5", "p50", "p95", "p99", "mean", "std"];
            let entry: Vec<(&str, Option<f64>)> = keys.into_iter().zip(values).collect();
            map.serialize_entry(name, &Ordered(&entry))?;
        }
        map.end()
    }
}

/// A JSON object with its keys in the given order.
struct Ordered<'a>(&'a [(&'a str, Option<f64>)]);

impl serde::Serialize for Ordered<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in self.0 {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

/// Merges the campaign folders `dirs` (shards of one campaign) into `out`: their rows
/// together, sorted by `k`, as one machine would have written them; then [`finish`]. The
/// folders must be of one campaign (same header, runs, seed); a run held twice must hold the
/// same row. Cut-off last lines (a shard killed mid-write) are left out.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<Finished, CampaignError> {
    if dirs.is_empty() {
        return Err(CampaignError::Other(
            "merge needs at least one folder".into(),
        ));
    }
    let mut header: Option<(String, PathBuf)> = None;
    let mut meta: Option<Meta> = None;
    let mut rows = Vec::new();
    let mut traces = String::new();
    // A folder given twice, or two folders of one shard, would count its traces twice.
    let mut seen: Vec<(PathBuf, Shard, &PathBuf)> = Vec::new();
    for d in dirs {
        let m = Meta::read(d)?;
        let same = std::fs::canonicalize(d).unwrap_or_else(|_| d.clone());
        for (other, shard, given) in &seen {
            if *other == same {
                return Err(CampaignError::Other(format!(
                    "{} is given twice (as {} and {}): name each shard's folder once",
                    same.display(),
                    given.display(),
                    d.display()
                )));
            }
            if shard.count > 1 && *shard == m.shard {
                return Err(CampaignError::Other(format!(
                    "{} and {} both hold shard {}: name each shard's folder once",
                    given.display(),
                    d.display(),
                    m.shard
                )));
            }
        }
        seen.push((same, m.shard, d));
        // Shards are merged only when their digests say they ran the same scene.
        if m.scene_digest.is_none() {
            return Err(CampaignError::Other(format!(
                "{}: has no scene digest (written by an older satsim), so nothing says which scene its runs were made with: rerun that shard",
                d.join(CAMPAIGN_JSON).display()
            )));
        }
        match &meta {
            None => meta = Some(m),
            Some(first) if first.scene_digest != m.scene_digest => {
                return Err(CampaignError::Other(format!(
                    "{} was run with another scene than {} (scene digests {} and {}: a changed scene, model file or --set value)",
                    d.display(),
                    dirs[0].display(),
                    m.scene_digest.as_deref().unwrap_or_default(),
                    first.scene_digest.as_deref().unwrap_or_default()
                )));
            }
            Some(first) if first.controller != m.controller => {
                return Err(CampaignError::Other(format!(
                    "{} was run with another controller ({}) than {} ({})",
                    d.display(),
                    m.controller_name(),
                    dirs[0].display(),
                    first.controller_name()
                )));
            }
            Some(first) if first.runs != m.runs || first.seed != m.seed => {
                return Err(CampaignError::Other(format!(
                    "{} is another campaign ({} runs, seed {}) than {} ({} runs, seed {})",
                    d.display(),
                    m.runs,
                    m.seed,
                    dirs[0].display(),
                    first.runs,
                    first.seed
                )));
            }
            Some(_) => {}
        }
        let path = d.join(RUNS_CSV);
        let r = read_runs(&path)?;
        match &header {
            None => header = Some((r.header.clone(), path.clone())),
            Some((h, first)) if *h != r.header => {
                return Err(CampaignError::Other(format!(
                    "{}: its columns differ from {}'s (another campaign?): {}",
                    path.display(),
                    first.display(),
                    columns_differ(&split(&r.header), &split(h), false)
                )));
            }
            Some(_) => {}
        }
        rows.extend(r.rows);
        let tp = d.join(TRACES_CSV);
        if tp.exists() {
            let t = std::fs::read_to_string(&tp).map_err(|e| CampaignError::io(&tp, e))?;
            let (_, end) = complete_lines(&t);
            traces.push_str(&t[..end]);
        }
    }
    let (header, _) = header.expect("at least one folder");
    let mut meta = meta.expect("at least one folder");
    meta.shard = Shard::ALL;
    sort_rows(&mut rows, out)?;
    std::fs::create_dir_all(out).map_err(|e| CampaignError::io(out, e))?;
    let mut text = header;
    text.push('\n');
    for (_, line) in &rows {
        text.push_str(line);
        text.push('\n');
    }
    replace(&out.join(RUNS_CSV), &text)?;
    replace(&out.join(TRACES_CSV), &traces)?;
    meta.write(out)?;
    finish(out, &meta)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoting_round_trips() {
        for f in ["plain", "a, b", "say \"no\"", "", "x\ny"] {
            let line = format!("1,{},2", quote(f));
            let back = split(&line);
            assert_eq!(back.len(), 3, "{line}");
            assert_eq!(back[1], f.replace('\n', " "));
        }
        assert_eq!(quote("a,b"), "\"a,b\"");
        assert_eq!(quote("q\""), "\"q\"\"\"");
    }

    /// A header without the columns added since an earlier version is named as such; one
    /// of other dispersions names its first differing column.
    #[test]
    fn a_header_that_differs_is_described() {
        let cols = |s: &str| s.split(',').map(String::from).collect::<Vec<_>>();
        let now = cols("run,status,mass_bus,final_a,peak_deflection_p1,stability_held");
        let older = cols("run,status,mass_bus,final_a,peak_deflection_p1");
        assert_eq!(
            columns_differ(&older, &now, false),
            "it lacks `stability_held`, which this satsim writes: a folder from an earlier version"
        );
        // With the user's metrics after it, where they are allowed.
        let mut metrics = older.clone();
        metrics.push("settle_time".into());
        assert!(columns_differ(&metrics, &now, true).contains("earlier version"));
        assert!(!columns_differ(&metrics, &now, false).contains("earlier version"));
        // Older still: without the beams' peaks either.
        let oldest = cols("run,status,mass_bus,final_a");
        assert!(
            columns_differ(&oldest, &now, false)
                .starts_with("it lacks `peak_deflection_p1`, `stability_held`")
        );
        let other = cols("run,status,inertia_bus,final_a,peak_deflection_p1,stability_held");
        assert_eq!(
            columns_differ(&other, &now, false),
            "column 3 is `inertia_bus` where this campaign writes `mass_bus`: other dispersions or another scene"
        );
        let more = cols("run,status,mass_bus,final_a,peak_deflection_p1,stability_held,x");
        assert!(columns_differ(&more, &now, false).starts_with("`x` after this campaign's 6"));
    }

    /// `finish` rewrites `traces.csv` sorted by run, for the runs that finished, the last
    /// line of a run and column winning: a line whose values all parse is copied as
    /// written, one with a value that does not is written again without it, as `{:.7e}`.
    #[test]
    fn finish_sorts_the_traces_and_keeps_their_text() {
        let dir = std::env::temp_dir().join(format!("satsim-finish-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join(RUNS_CSV),
            "run,status,message,final_a\n1,ok,,2.0\n0,ok,,1.0\n2,failed,boom,\n",
        )
        .unwrap();
        std::fs::write(
            dir.join(TRACES_CSV),
            "1,t,0.0000000e0,1.0000000e-1\n\
             0,a,1.2345679e0,NaN\n\
             0,t,0.0000000e0,1.0000000e-1\n\
             2,t,0.0000000e0\n\
             1,a,5.0000000e-1,x,2.5000000e0\n\
             0,a,9.8765432e-3,1.0000000e300\n\
             1,t,0.0000000e0,1.0000000e-1,2.0",
        )
        .unwrap();
        let meta = Meta {
            scene: "scene.toml".into(),
            runs: 3,
            seed: 1,
            shard: Shard::new(0, 1).unwrap(),
            histograms: Vec::new(),
            scene_digest: None,
            controller: None,
        };
        let done = finish(&dir, &meta).unwrap();
        assert_eq!((done.ok, done.failed), (2, 1));
        let traces = std::fs::read_to_string(dir.join(TRACES_CSV)).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(
            traces,
            "0,a,9.8765432e-3,1.0000000e300\n\
             0,t,0.0000000e0,1.0000000e-1\n\
             1,t,0.0000000e0,1.0000000e-1\n\
             1,a,5.0000000e-1,2.5000000e0\n"
        );
    }
}
