//! Output sinks of a run: a streamed CSV trajectory and small SVG line plots (written here,
//! no plotting crate).

use std::fmt::Write as _;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// A CSV file written row by row and flushed after each row, so that a run that fails
/// leaves a valid file up to its last row.
pub struct CsvWriter {
    out: BufWriter<File>,
    line: String,
}

impl CsvWriter {
    /// Creates `path` and writes the header.
    pub fn create(path: &Path, columns: &[String]) -> io::Result<Self> {
        let mut out = BufWriter::new(File::create(path)?);
        writeln!(out, "{}", columns.join(","))?;
        out.flush()?;
        Ok(Self {
            out,
            line: String::new(),
        })
    }
    /// Appends one row (shortest round-trip formatting) and flushes it.
    pub fn row(&mut self, values: &[f64]) -> io::Result<()> {
        self.line.clear();
        for (i, v) in values.iter().enumerate() {
            if i > 0 {
                self.line.push(',');
            }
            let _ = write!(self.line, "{v}");
        }
        self.line.push('\n');
        self.out.write_all(self.line.as_bytes())?;
        self.out.flush()
    }
}

/// One curve of a plot.
pub struct Series<'a> {
    /// Legend label.
    pub label: &'a str,
    /// The y values (one per x).
    pub y: &'a [f64],
}

const COLOURS: [&str; 8] = [
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
];

fn nice_ticks(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let span = (hi - lo).max(f64::MIN_POSITIVE);
    let raw = span / n as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let mut t = (lo / step).ceil() * step;
    let mut out = Vec::new();
    while t <= hi + 1e-9 * step {
        out.push(if t.abs() < 1e-12 * step { 0.0 } else { t });
        t += step;
    }
    out
}

fn fmt_tick(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v.abs() >= 1e4 || v.abs() < 1e-3 {
        format!("{v:.2e}")
    } else {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// An SVG line plot of `series` against `x`, with axes, ticks, a title and a legend.
/// Non-finite values are skipped.
///
/// ```
/// use satsim_satellite::output::{Series, line_plot};
/// let x = [0.0, 1.0, 2.0];
/// let svg = line_plot("demo", "t (s)", &x, &[Series { label: "y", y: &[0.0, 1.0, 4.0] }]);
/// assert!(svg.starts_with("<svg") && svg.contains("polyline"));
/// ```
pub fn line_plot(title: &str, xlabel: &str, x: &[f64], series: &[Series]) -> String {
    let (w, h) = (720.0, 400.0);
    let (ml, mr, mt, mb) = (80.0, 150.0, 36.0, 48.0);
    let (pw, ph) = (w - ml - mr, h - mt - mb);
    let finite = |v: &&f64| v.is_finite();
    let (mut x0, mut x1) = x
        .iter()
        .filter(finite)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let (mut y0, mut y1) = series
        .iter()
        .flat_map(|s| s.y.iter())
        .filter(finite)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if !x0.is_finite() {
        (x0, x1) = (0.0, 1.0);
    }
    if !y0.is_finite() {
        (y0, y1) = (-1.0, 1.0);
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    if y1 - y0 <= 1e-12 * y0.abs().max(y1.abs()).max(1e-300) {
        let pad = if y0 == 0.0 { 1.0 } else { 0.1 * y0.abs() };
        y0 -= pad;
        y1 += pad;
    } else {
        let pad = 0.05 * (y1 - y0);
        y0 -= pad;
        y1 += pad;
    }
    let sx = |v: f64| ml + (v - x0) / (x1 - x0) * pw;
    let sy = |v: f64| mt + ph - (v - y0) / (y1 - y0) * ph;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="22" text-anchor="middle" font-size="15">{}</text>"#,
        ml + pw / 2.0,
        esc(title)
    );
    for t in nice_ticks(x0, x1, 8) {
        let px = sx(t);
        let _ = writeln!(
            s,
            r##"<line x1="{px:.1}" y1="{mt}" x2="{px:.1}" y2="{:.1}" stroke="#e5e5e5"/><text x="{px:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
            mt + ph,
            mt + ph + 16.0,
            fmt_tick(t)
        );
    }
    for t in nice_ticks(y0, y1, 6) {
        let py = sy(t);
        let _ = writeln!(
            s,
            r##"<line x1="{ml}" y1="{py:.1}" x2="{:.1}" y2="{py:.1}" stroke="#e5e5e5"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
            ml + pw,
            ml - 6.0,
            py + 4.0,
            fmt_tick(t)
        );
    }
    let _ = writeln!(
        s,
        r#"<rect x="{ml}" y="{mt}" width="{pw}" height="{ph}" fill="none" stroke="black"/>"#
    );
    let _ = writeln!(
        s,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
        ml + pw / 2.0,
        h - 10.0,
        esc(xlabel)
    );
    for (k, ser) in series.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        let mut pts = String::new();
        for (xv, yv) in x.iter().zip(ser.y) {
            if xv.is_finite() && yv.is_finite() {
                let _ = write!(pts, "{:.2},{:.2} ", sx(*xv), sy(*yv));
            }
        }
        let _ = writeln!(
            s,
            r#"<polyline fill="none" stroke="{colour}" stroke-width="1.5" points="{}"/>"#,
            pts.trim_end()
        );
        let ly = mt + 10.0 + 18.0 * k as f64;
        let _ = writeln!(
            s,
            r#"<line x1="{:.1}" y1="{ly:.1}" x2="{:.1}" y2="{ly:.1}" stroke="{colour}" stroke-width="2"/><text x="{:.1}" y="{:.1}">{}</text>"#,
            ml + pw + 10.0,
            ml + pw + 30.0,
            ml + pw + 36.0,
            ly + 4.0,
            esc(ser.label)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// The plots `satsim run` draws from a finished trajectory: `(file name, title, columns)`.
/// Groups whose columns are absent are skipped.
pub const PLOT_GROUPS: [(&str, &str, &[&str]); 6] = [
    (
        "attitude.svg",
        "Attitude quaternion",
        &["q_w", "q_x", "q_y", "q_z"],
    ),
    (
        "rates.svg",
        "Bus angular velocity (rad/s)",
        &["omega_x", "omega_y", "omega_z"],
    ),
    ("hinge_angles.svg", "Hinge angles (rad)", &["angle_*"]),
    (
        "wheel_speeds.svg",
        "Wheel speeds (rad/s)",
        &["wheel_*_speed"],
    ),
    (
        "energy.svg",
        "Energy (J)",
        &["kinetic_energy", "potential_energy", "total_energy"],
    ),
    (
        "momentum.svg",
        "Angular momentum about the centre of mass (N m s)",
        &["h_x", "h_y", "h_z"],
    ),
];

fn matches(pattern: &str, name: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == name,
        Some((a, b)) => name.len() >= a.len() + b.len() && name.starts_with(a) && name.ends_with(b),
    }
}

/// Writes the [`PLOT_GROUPS`] plots of a trajectory (`columns`, rows `data`, first column
/// the time) into `dir`; returns the files written.
pub fn write_plots(dir: &Path, columns: &[String], data: &[Vec<f64>]) -> io::Result<Vec<String>> {
    let t: Vec<f64> = data.iter().map(|r| r[0]).collect();
    let mut written = Vec::new();
    for (file, title, patterns) in PLOT_GROUPS {
        let idx: Vec<usize> = (0..columns.len())
            .filter(|&c| patterns.iter().any(|p| matches(p, &columns[c])))
            .collect();
        if idx.is_empty() {
            continue;
        }
        let ys: Vec<Vec<f64>> = idx
            .iter()
            .map(|&c| data.iter().map(|r| r[c]).collect())
            .collect();
        let series: Vec<Series> = idx
            .iter()
            .zip(&ys)
            .map(|(&c, y)| Series {
                label: &columns[c],
                y,
            })
            .collect();
        std::fs::write(dir.join(file), line_plot(title, "t (s)", &t, &series))?;
        written.push(file.to_owned());
    }
    Ok(written)
}
