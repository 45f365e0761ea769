//! `satsim plot CSV --columns a,b,... [--from T] [--to T] [-o OUT.svg]`: re-plots columns of a
//! run's CSV (such as `out/deploy/trajectory.csv`) against its time column `t`, without
//! running again. The file is streamed and each curve decimated as `satsim run`'s own plots
//! are ([`satsim_tools::output::Decimation`]), so the plot stays small whatever the
//! number of rows.
//!
//! Bad input (exit status 2): an unreadable or empty file, a file without a `t` column, a
//! column that is not in the file (the message lists those that are), a range with
//! `--from` >= `--to` or holding no row, and a row that is not numbers (file and line named).
//! A last line without its line end (a run killed while writing it) is left out with a
//! warning: the plot holds every whole row.

use super::{CliError, Output, usage};
use satsim_tools::output::{Decimation, column_matches, plot_curves};
use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};

/// The flags of `satsim plot`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A CSV file with a header row and a time column `t` (as `satsim run` writes)
    #[arg(value_name = "CSV")]
    pub csv: PathBuf,
    /// The columns to plot, comma-separated; `*` matches any text (`angle_*`)
    #[arg(long, value_name = "A,B,...", value_delimiter = ',', required = true)]
    pub columns: Vec<String>,
    /// Plot only the rows with t >= FROM (s) [default: the first row]
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub from: Option<f64>,
    /// Plot only the rows with t <= TO (s) [default: the last row]
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub to: Option<f64>,
    /// The SVG to write [default: beside the CSV, <CSV stem>-plot.svg]
    #[arg(short, long, value_name = "OUT.svg")]
    pub out: Option<PathBuf>,
}

/// Runs the command.
pub fn run(args: &Args) -> Result<Output, CliError> {
    let (from, to) = (
        args.from.unwrap_or(f64::NEG_INFINITY),
        args.to.unwrap_or(f64::INFINITY),
    );
    for (flag, v) in [("--from", args.from), ("--to", args.to)] {
        if v.is_some_and(|v| !v.is_finite()) {
            return Err(usage(
                &["plot"],
                format!("`{flag}` must be a finite time (s)"),
            ));
        }
    }
    if from >= to {
        return Err(usage(
            &["plot"],
            format!("bad range: `--from {from}` is not before `--to {to}`"),
        ));
    }
    let path = &args.csv;
    let name = path.display();
    let file = File::open(path).map_err(|e| CliError::Other(format!("{name}: {e}")))?;
    let mut lines = WholeLines {
        reader: BufReader::new(file),
        read: 0,
        cut: None,
    };
    let header = match lines.next() {
        Some(Ok(h)) if !h.trim().is_empty() => h,
        Some(Err(e)) => return Err(CliError::Other(format!("{name}: {e}"))),
        _ => return Err(CliError::Other(format!("{name}: the file is empty"))),
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let t_col = names.iter().position(|c| *c == "t").ok_or_else(|| {
        CliError::Other(format!(
            "{name}:1: no time column `t` (the columns are: {})",
            names.join(", ")
        ))
    })?;
    // The plotted columns, in the order asked (a pattern adds its matches in file order).
    let mut plotted: Vec<usize> = Vec::new();
    for want in &args.columns {
        let found: Vec<usize> = (0..names.len())
            .filter(|&c| c != t_col && column_matches(want, names[c]))
            .collect();
        if found.is_empty() {
            return Err(CliError::Other(format!(
                "{name}:1: no column `{want}`; the columns are: {}",
                names.join(", ")
            )));
        }
        for c in found {
            if !plotted.contains(&c) {
                plotted.push(c);
            }
        }
    }

    let mut curves: Vec<Decimation> = plotted.iter().map(|_| Decimation::new()).collect();
    let (mut rows, mut first_t, mut last_t) = (0usize, f64::NAN, f64::NAN);
    // The file's own time span, for the message when the range holds none of its rows.
    let (mut file_first, mut file_last) = (f64::NAN, f64::NAN);
    for (k, line) in lines.by_ref().enumerate() {
        let line_no = k + 2;
        let line = line.map_err(|e| CliError::Other(format!("{name}:{line_no}: {e}")))?;
        if line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').collect();
        if fields.len() != names.len() {
            return Err(CliError::Other(format!(
                "{name}:{line_no}: {} fields, the header has {}",
                fields.len(),
                names.len()
            )));
        }
        let number = |c: usize| -> Result<f64, CliError> {
            fields[c].trim().parse::<f64>().map_err(|_| {
                CliError::Other(format!(
                    "{name}:{line_no}: `{}` in column `{}` is not a number",
                    fields[c], names[c]
                ))
            })
        };
        let t = number(t_col)?;
        if file_first.is_nan() {
            file_first = t;
        }
        file_last = t;
        if t < from || t > to {
            continue;
        }
        for (curve, &c) in curves.iter_mut().zip(&plotted) {
            curve.push(t, number(c)?);
        }
        if rows == 0 {
            first_t = t;
        }
        last_t = t;
        rows += 1;
    }
    if let Some(n) = lines.cut {
        super::print_warnings(&[format!(
            "{name}:{n}: the last line has no line end (the run was stopped while writing it?): left out; plotted the rows before it"
        )]);
    }
    if rows == 0 {
        let range = match (args.from, args.to) {
            (None, None) => String::new(),
            (Some(f), None) => format!(" with t >= {f} s"),
            (None, Some(t)) => format!(" with t <= {t} s"),
            (Some(f), Some(t)) => format!(" with {f} <= t <= {t} s"),
        };
        let span = if file_first.is_nan() {
            String::new()
        } else {
            format!("; its rows span t = {file_first} .. {file_last} s")
        };
        return Err(CliError::Other(format!("{name}: no rows{range}{span}")));
    }

    let labels: Vec<&str> = plotted.iter().map(|&c| names[c]).collect();
    let title = format!(
        "{}: {}",
        path.file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_default(),
        labels.join(", ")
    );
    let points: Vec<(&str, Vec<(f64, f64)>)> = labels
        .iter()
        .zip(&curves)
        .map(|(l, d)| (*l, d.points()))
        .collect();
    let svg = plot_curves(&title, "t (s)", &points);
    let out = args.out.clone().unwrap_or_else(|| default_out(path));
    std::fs::write(&out, svg)
        .map_err(|e| CliError::Other(format!("cannot write {}: {e}", out.display())))?;
    Ok(format!(
        "wrote      {} ({} of {}; {rows} rows, t = {first_t} .. {last_t} s)\n",
        out.display(),
        labels.join(", "),
        name
    ))
}

/// The lines of a file that end with a line end; a last line without one (cut off) is
/// not given, and `cut` holds its line number.
struct WholeLines<R> {
    reader: R,
    read: usize,
    cut: Option<usize>,
}

impl<R: BufRead> Iterator for WholeLines<R> {
    type Item = std::io::Result<String>;
    fn next(&mut self) -> Option<Self::Item> {
        let mut line = String::new();
        self.read += 1;
        match self.reader.read_line(&mut line) {
            Ok(0) => None,
            Ok(_) if line.ends_with('\n') => {
                line.pop();
                if line.ends_with('\r') {
                    line.pop();
                }
                Some(Ok(line))
            }
            Ok(_) => {
                self.cut = Some(self.read);
                None
            }
            Err(e) => Some(Err(e)),
        }
    }
}

/// `<CSV stem>-plot.svg` in the CSV's folder.
fn default_out(csv: &Path) -> PathBuf {
    let stem = csv
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "plot".into());
    csv.with_file_name(format!("{stem}-plot.svg"))
}
