//! A campaign's plots: percentile envelopes over time of the hinge angles and bus rates
//! (`envelope_<column>.svg`: the p1–p99 and p5–p95 bands and the median over the finished
//! runs at each sampled output time) and histograms of chosen statistics
//! (`histogram_<column>.svg`, the failed runs counted in the note).

use super::meta::Meta;
use super::stats::percentile;
use crate::output::{Band, band_plot, histogram_plot};
use std::collections::BTreeMap;
use std::io;
use std::path::Path;

fn file_safe(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The envelope of `series` (runs, each a time series; shorter runs drop out where they
/// end): p1, p5, p50, p95, p99 at each index.
pub fn envelope(series: &[&[f64]]) -> [Vec<f64>; 5] {
    let len = series.iter().map(|s| s.len()).max().unwrap_or(0);
    let mut out: [Vec<f64>; 5] = Default::default();
    let mut at = Vec::with_capacity(series.len());
    for i in 0..len {
        at.clear();
        at.extend(series.iter().filter_map(|s| s.get(i).copied()));
        at.sort_by(f64::total_cmp);
        for (o, p) in out.iter_mut().zip([1.0, 5.0, 50.0, 95.0, 99.0]) {
            o.push(percentile(&at, p));
        }
    }
    out
}

/// Writes every plot; returns the file names.
pub(crate) fn write_all(
    dir: &Path,
    stat_names: &[String],
    ok_rows: &[(u64, Vec<f64>)],
    failed: u64,
    traces: &BTreeMap<u64, Vec<(String, Vec<f64>)>>,
    meta: &Meta,
) -> io::Result<Vec<String>> {
    let mut written = Vec::new();
    let note = format!("{failed} failed (not shown)");
    // Envelopes.
    let columns: Vec<&str> = traces
        .values()
        .next()
        .map(|cols| cols.iter().map(|(c, _)| c.as_str()).collect())
        .unwrap_or_default();
    let series_of = |col: &str| -> Vec<&[f64]> {
        traces
            .values()
            .filter_map(|cols| cols.iter().find(|(c, _)| c == col))
            .map(|(_, v)| v.as_slice())
            .collect()
    };
    let t: Vec<f64> = series_of("t")
        .into_iter()
        .max_by_key(|s| s.len())
        .map(<[f64]>::to_vec)
        .unwrap_or_default();
    for col in columns.iter().filter(|c| **c != "t") {
        let series = series_of(col);
        let [p1, p5, p50, p95, p99] = envelope(&series);
        let unit = if col.starts_with("angle_") {
            "rad"
        } else {
            "rad/s"
        };
        let title = format!(
            "{col} ({unit}): {} runs, {failed} failed (not shown)",
            series.len()
        );
        let svg = band_plot(
            &title,
            "t (s)",
            &t[..t.len().min(p50.len())],
            &[
                Band {
                    label: "p1-p99",
                    lower: &p1,
                    upper: &p99,
                },
                Band {
                    label: "p5-p95",
                    lower: &p5,
                    upper: &p95,
                },
            ],
            ("median", &p50),
        );
        let name = format!("envelope_{}.svg", file_safe(col));
        std::fs::write(dir.join(&name), svg)?;
        written.push(name);
    }
    // Histograms.
    for h in &meta.histograms {
        let Some(c) = stat_names.iter().position(|s| s == h) else {
            continue;
        };
        let values: Vec<f64> = ok_rows.iter().map(|r| r.1[c]).collect();
        let bins = ((values.len() as f64).sqrt().ceil() as usize).clamp(5, 50);
        let svg = histogram_plot(
            &format!("{h} over the finished runs"),
            h,
            &values,
            bins,
            &note,
        );
        let name = format!("histogram_{}.svg", file_safe(h));
        std::fs::write(dir.join(&name), svg)?;
        written.push(name);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn envelopes_are_ordered_and_follow_the_runs() {
        let runs: Vec<Vec<f64>> = (0..101).map(|k| vec![k as f64, 2.0 * k as f64]).collect();
        let refs: Vec<&[f64]> = runs.iter().map(|r| r.as_slice()).collect();
        let [p1, p5, p50, p95, p99] = envelope(&refs);
        assert_eq!(p50, [50.0, 100.0]);
        assert_eq!(p1, [1.0, 2.0]);
        assert_eq!(p99, [99.0, 198.0]);
        for i in 0..2 {
            assert!(p1[i] <= p5[i] && p5[i] <= p50[i] && p50[i] <= p95[i] && p95[i] <= p99[i]);
        }
    }
}
