//! Output sinks of a run: a streamed CSV trajectory, its events, and SVG plots (the one
//! in-house writer [`Figure`], used by every plot of satsim), in bounded memory whatever the
//! number of rows.

use std::fmt::Write as _;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::time::{Duration, Instant};

/// Size of the CSV writer's block (bytes).
const CSV_BLOCK: usize = 64 * 1024;
/// The CSV is also flushed when this long has passed since the last flush, so that a file
/// being watched grows while a slow run goes on.
const CSV_FLUSH_EVERY: Duration = Duration::from_millis(500);

/// A CSV file written row by row in blocks of 64 KiB (and at least every 0.5 s). A block
/// holds whole rows only, so the file always ends with a complete row; call
/// [`CsvWriter::flush`] when the run ends, fails or is interrupted (dropping the writer
/// flushes too, ignoring errors).
pub struct CsvWriter {
    out: BufWriter<File>,
    line: String,
    flushed: Instant,
}

impl CsvWriter {
    /// Creates `path` and writes the header.
    pub fn create(path: &Path, columns: &[String]) -> io::Result<Self> {
        let mut out = BufWriter::with_capacity(CSV_BLOCK, File::create(path)?);
        writeln!(out, "{}", columns.join(","))?;
        out.flush()?;
        Ok(Self {
            out,
            line: String::new(),
            flushed: Instant::now(),
        })
    }
    /// Appends one row (shortest round-trip formatting, in exponent form past 1e9 or below
    /// 1e-9 in magnitude: [`satsim_tree::error::Num`]). It reaches the file when its block
    /// is full, 0.5 s after the last flush, or at [`CsvWriter::flush`].
    pub fn row(&mut self, values: &[f64]) -> io::Result<()> {
        self.line.clear();
        for (i, v) in values.iter().enumerate() {
            if i > 0 {
                self.line.push(',');
            }
            crate::numbers::push_shortest(&mut self.line, *v);
        }
        self.line.push('\n');
        // `BufWriter` writes its buffer out before a line that does not fit: blocks end on
        // row boundaries.
        self.out.write_all(self.line.as_bytes())?;
        if self.flushed.elapsed() >= CSV_FLUSH_EVERY {
            self.flush()?;
        }
        Ok(())
    }
    /// Writes every buffered row to the file.
    pub fn flush(&mut self) -> io::Result<()> {
        self.flushed = Instant::now();
        self.out.flush()
    }
}

/// The events file of a run: the header `t,effect,event`, then one line per event in the
/// order they happened (`t` in seconds, shortest round-trip form; the effect's scene name;
/// what happened, CSV-quoted when it holds a comma or a quote). `satsim run` writes it as
/// `DIR/events.csv`.
pub fn write_events<'a>(
    path: &Path,
    events: impl IntoIterator<Item = (f64, &'a str, &'a str)>,
) -> io::Result<usize> {
    let mut out = BufWriter::new(File::create(path)?);
    writeln!(out, "t,effect,event")?;
    let mut n = 0;
    for (t, effect, what) in events {
        writeln!(out, "{t},{},{}", quote(effect), quote(what))?;
        n += 1;
    }
    out.flush()?;
    Ok(n)
}

// Plots. Every plot of satsim (a run's, `satsim plot`'s, a campaign's envelopes and
// histograms, the accuracy sweep's log-log diagram, the modes sweep) is drawn by the one
// in-house SVG writer [`Figure`]. Measured against `plotters` (SVG backend) on the five plots
// of a 10⁶-row, 15-column run, both drawing the same decimated points: plotters writes them in
// 16 ms and 426 kB, this writer in 20 ms and 564 kB, while the decimation itself takes 470 ms;
// plotters rounds every point to a whole pixel (so the decimation's exact extremes, which the
// tests locate to 0.02 px, move by up to half a pixel) and adds three crates (plotters,
// plotters-backend, plotters-svg). Either is fine for a user; the in-house writer is kept for
// exact coordinates, no dependency, and one look for log axes, bands and histograms too.

/// One curve of a plot.
pub struct Series<'a> {
    /// Legend label.
    pub label: &'a str,
    /// The y values (one per x).
    pub y: &'a [f64],
}

/// The colours of successive curves.
pub const COLOURS: [&str; 8] = [
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

/// Width of a plot's drawing area in pixels.
pub const PLOT_WIDTH_PX: usize = 490;

/// A plot's size (px) and margins: left, right (the legend), top, bottom.
const SIZE: (f64, f64) = (720.0, 400.0);
const MARGINS: (f64, f64, f64, f64) = (80.0, 150.0, 36.0, 48.0);

/// How an axis maps data to pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// Linear, ticks at 1, 2, 5 times a power of ten.
    Linear,
    /// Base-10 logarithmic, ticks at decades (values <= 0 are not drawn).
    Log10,
}

/// One axis of a [`Figure`]: its range in data units, scale and label.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// The data value at the low end.
    pub lo: f64,
    /// The data value at the high end.
    pub hi: f64,
    /// The scale.
    pub scale: Scale,
    /// The label ("" for none).
    pub label: String,
}

impl Axis {
    /// A linear axis over the finite `values`: their exact range when `pad` is false, widened
    /// by 5 % each side when it is true; a flat or empty set gets a range around it.
    pub fn linear<'a>(label: &str, values: impl IntoIterator<Item = &'a f64>, pad: bool) -> Self {
        let (mut lo, mut hi) = values
            .into_iter()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        if !lo.is_finite() {
            (lo, hi) = if pad { (-1.0, 1.0) } else { (0.0, 1.0) };
        }
        if hi - lo <= 1e-12 * lo.abs().max(hi.abs()).max(1e-300) {
            let half = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
            (lo, hi) = if pad {
                (lo - half, hi + half)
            } else {
                (lo, lo + 2.0 * half)
            };
        } else if pad {
            let p = 0.05 * (hi - lo);
            (lo, hi) = (lo - p, hi + p);
        }
        Self {
            lo,
            hi,
            scale: Scale::Linear,
            label: label.to_owned(),
        }
    }

    /// A logarithmic axis over the positive finite `values`, widened to whole decades.
    pub fn log10(label: &str, values: impl IntoIterator<Item = f64>) -> Self {
        let (lo, hi) = values
            .into_iter()
            .filter(|v| *v > 0.0 && v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        let (a, b) = if lo.is_finite() {
            (lo.log10().floor(), hi.log10().ceil())
        } else {
            (0.0, 1.0)
        };
        Self {
            lo: 10f64.powf(a),
            hi: 10f64.powf(if b > a { b } else { a + 1.0 }),
            scale: Scale::Log10,
            label: label.to_owned(),
        }
    }

    /// Where `v` falls between the ends, 0 at `lo` and 1 at `hi` (`None` for a value the
    /// scale cannot draw).
    fn fraction(&self, v: f64) -> Option<f64> {
        match self.scale {
            Scale::Linear => v.is_finite().then(|| (v - self.lo) / (self.hi - self.lo)),
            Scale::Log10 => (v > 0.0 && v.is_finite())
                .then(|| (v.log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10())),
        }
    }

    /// The ticks and their labels.
    fn ticks(&self, n: usize) -> Vec<(f64, String)> {
        match self.scale {
            Scale::Linear => nice_ticks(self.lo, self.hi, n)
                .into_iter()
                .map(|t| (t, fmt_tick(t)))
                .collect(),
            Scale::Log10 => {
                let (a, b) = (self.lo.log10().round(), self.hi.log10().round());
                let step = ((b - a) / n as f64).ceil().max(1.0);
                let mut out = Vec::new();
                let mut d = a;
                while d <= b + 1e-9 {
                    out.push((10f64.powf(d), format!("1e{}", d as i32)));
                    d += step;
                }
                out
            }
        }
    }
}

/// An SVG plot being drawn: the frame (title, grid, ticks, axis labels) is written by
/// [`Figure::new`], then curves, bands, bars and legend entries, then [`Figure::finish`].
/// Every element is one line of the file; a curve is one `<polyline>` per unbroken run of
/// drawable points, coordinates to 0.01 px.
///
/// ```
/// use satsim_tools::output::{Axis, Figure};
/// let x = [0.0, 1.0, 2.0];
/// let y = [0.0, 1.0, 4.0];
/// let mut f = Figure::new("demo", Axis::linear("t (s)", &x, false), Axis::linear("", &y, true));
/// f.curve("y", x.iter().copied().zip(y), 0);
/// let svg = f.finish();
/// assert!(svg.starts_with("<svg") && svg.contains("<polyline"));
/// ```
pub struct Figure {
    svg: String,
    x: Axis,
    y: Axis,
    legend: usize,
}

impl Figure {
    /// A plot titled `title` over the axes `x` and `y`.
    pub fn new(title: &str, x: Axis, y: Axis) -> Self {
        let (w, h) = SIZE;
        let (ml, mr, mt, mb) = MARGINS;
        let (pw, ph) = (w - ml - mr, h - mt - mb);
        let mut f = Self {
            svg: String::new(),
            x,
            y,
            legend: 0,
        };
        let s = &mut f.svg;
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
        for (t, label) in f.x.ticks(8) {
            let Some(px) = f.px(t) else { continue };
            let _ = writeln!(
                f.svg,
                r##"<line x1="{px:.1}" y1="{mt}" x2="{px:.1}" y2="{:.1}" stroke="#e5e5e5"/><text x="{px:.1}" y="{:.1}" text-anchor="middle">{label}</text>"##,
                mt + ph,
                mt + ph + 16.0,
            );
        }
        for (t, label) in f.y.ticks(6) {
            let Some(py) = f.py(t) else { continue };
            let _ = writeln!(
                f.svg,
                r##"<line x1="{ml}" y1="{py:.1}" x2="{:.1}" y2="{py:.1}" stroke="#e5e5e5"/><text x="{:.1}" y="{:.1}" text-anchor="end">{label}</text>"##,
                ml + pw,
                ml - 6.0,
                py + 4.0,
            );
        }
        let s = &mut f.svg;
        let _ = writeln!(
            s,
            r#"<rect x="{ml}" y="{mt}" width="{pw}" height="{ph}" fill="none" stroke="black"/>"#
        );
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            ml + pw / 2.0,
            h - 10.0,
            esc(&f.x.label)
        );
        if !f.y.label.is_empty() {
            let _ = writeln!(
                s,
                r#"<text transform="translate(16,{:.1}) rotate(-90)" text-anchor="middle">{}</text>"#,
                mt + ph / 2.0,
                esc(&f.y.label)
            );
        }
        f
    }

    /// The pixel column of `x` (`None` where the scale cannot draw it).
    pub fn px(&self, x: f64) -> Option<f64> {
        let (w, _) = SIZE;
        let (ml, mr, _, _) = MARGINS;
        Some(ml + self.x.fraction(x)? * (w - ml - mr))
    }

    /// The pixel row of `y` (`None` where the scale cannot draw it).
    pub fn py(&self, y: f64) -> Option<f64> {
        let (_, h) = SIZE;
        let (_, _, mt, mb) = MARGINS;
        let ph = h - mt - mb;
        Some(mt + ph - self.y.fraction(y)? * ph)
    }

    fn pixel(&self, (x, y): (f64, f64)) -> Option<(f64, f64)> {
        Some((self.px(x)?, self.py(y)?))
    }

    /// A curve through `points` in colour `k` with a legend entry: one polyline per run of
    /// drawable points, so a missing value leaves a gap.
    pub fn curve(&mut self, label: &str, points: impl IntoIterator<Item = (f64, f64)>, k: usize) {
        let colour = COLOURS[k % COLOURS.len()];
        let mut run = String::new();
        for p in points {
            match self.pixel(p) {
                Some((x, y)) => push_pixel(&mut run, x, y),
                None => self.polyline(colour, &mut run),
            }
        }
        self.polyline(colour, &mut run);
        self.legend_line(label, colour, "");
    }

    fn polyline(&mut self, colour: &str, run: &mut String) {
        if !run.is_empty() {
            let _ = writeln!(
                self.svg,
                r#"<polyline fill="none" stroke="{colour}" stroke-width="1.5" points="{}"/>"#,
                run.trim_end()
            );
            run.clear();
        }
    }

    /// A dot of colour `k` at each drawable point.
    pub fn markers(&mut self, points: impl IntoIterator<Item = (f64, f64)>, k: usize) {
        let colour = COLOURS[k % COLOURS.len()];
        for p in points {
            if let Some((x, y)) = self.pixel(p) {
                let _ = writeln!(
                    self.svg,
                    r#"<circle cx="{x:.2}" cy="{y:.2}" r="3" fill="{colour}"/>"#
                );
            }
        }
    }

    /// A shaded band between `lower` and `upper` (points `(x, y)`), with a legend swatch.
    pub fn band(&mut self, label: &str, lower: &[(f64, f64)], upper: &[(f64, f64)], opacity: f64) {
        let mut pts = String::new();
        for p in upper.iter().chain(lower.iter().rev()) {
            if let Some((x, y)) = self.pixel(*p) {
                push_pixel(&mut pts, x, y);
            }
        }
        let _ = writeln!(
            self.svg,
            r##"<polygon fill="{}" fill-opacity="{opacity:.2}" stroke="none" points="{}"/>"##,
            COLOURS[0],
            pts.trim_end()
        );
        let (lx, ly) = self.legend_at();
        let _ = writeln!(
            self.svg,
            r##"<rect x="{lx:.1}" y="{:.1}" width="20" height="10" fill="{}" fill-opacity="{opacity:.2}"/><text x="{:.1}" y="{:.1}">{}</text>"##,
            ly - 5.0,
            COLOURS[0],
            lx + 26.0,
            ly + 4.0,
            esc(label)
        );
    }

    /// A histogram bar from `x0` to `x1`, `height` high (`class="bin"`).
    pub fn bar(&mut self, x0: f64, x1: f64, height: f64) {
        let (Some((xa, ya)), Some((xb, yb))) = (self.pixel((x0, height)), self.pixel((x1, 0.0)))
        else {
            return;
        };
        let _ = writeln!(
            self.svg,
            r##"<rect class="bin" x="{xa:.2}" y="{ya:.2}" width="{:.2}" height="{:.2}" fill="{}" stroke="white"/>"##,
            (xb - xa).max(0.0),
            (yb - ya).max(0.0),
            COLOURS[0]
        );
    }

    /// A dashed horizontal line across the plot at `y`, labelled in the margin.
    pub fn reference(&mut self, y: f64, label: &str) {
        let Some(py) = self.py(y) else { return };
        let (w, _) = SIZE;
        let (ml, mr, _, _) = MARGINS;
        let _ = writeln!(
            self.svg,
            r##"<line x1="{ml}" y1="{py:.1}" x2="{:.1}" y2="{py:.1}" stroke="#777" stroke-dasharray="6,4"/><text x="{:.1}" y="{:.1}" fill="#555">{}</text>"##,
            w - mr,
            w - mr + 8.0,
            py + 4.0,
            esc(label)
        );
    }

    /// A legend entry: a line of `colour` (dashed by `dash`, an SVG dash array, when not
    /// empty) and its label.
    pub fn legend_line(&mut self, label: &str, colour: &str, dash: &str) {
        let (lx, ly) = self.legend_at();
        let dash = if dash.is_empty() {
            String::new()
        } else {
            format!(r#" stroke-dasharray="{dash}""#)
        };
        let _ = writeln!(
            self.svg,
            r#"<line x1="{lx:.1}" y1="{ly:.1}" x2="{:.1}" y2="{ly:.1}" stroke="{colour}" stroke-width="2"{dash}/><text x="{:.1}" y="{:.1}">{}</text>"#,
            lx + 20.0,
            lx + 26.0,
            ly + 4.0,
            esc(label)
        );
    }

    /// A line of text in the legend.
    pub fn legend_text(&mut self, text: &str) {
        let (lx, ly) = self.legend_at();
        let _ = writeln!(
            self.svg,
            r#"<text x="{lx:.1}" y="{:.1}">{}</text>"#,
            ly + 4.0,
            esc(text)
        );
    }

    /// The next legend row's anchor.
    fn legend_at(&mut self) -> (f64, f64) {
        let (w, _) = SIZE;
        let (_, mr, mt, _) = MARGINS;
        let at = (w - mr + 10.0, mt + 10.0 + 18.0 * self.legend as f64);
        self.legend += 1;
        at
    }

    /// The SVG text.
    pub fn finish(mut self) -> String {
        self.svg.push_str("</svg>\n");
        self.svg
    }
}

/// An SVG line plot of `series` against `x`, with axes, ticks, a title and a legend.
/// Non-finite values leave gaps. Every point is drawn: decimate long series first (see
/// [`Decimation`]).
///
/// ```
/// use satsim_tools::output::{Series, line_plot};
/// let x = [0.0, 1.0, 2.0];
/// let svg = line_plot("demo", "t (s)", &x, &[Series { label: "y", y: &[0.0, 1.0, 4.0] }]);
/// assert!(svg.starts_with("<svg") && svg.contains("polyline"));
/// ```
pub fn line_plot(title: &str, xlabel: &str, x: &[f64], series: &[Series]) -> String {
    let curves: Vec<(&str, Vec<(f64, f64)>)> = series
        .iter()
        .map(|s| {
            (
                s.label,
                x.iter().copied().zip(s.y.iter().copied()).collect(),
            )
        })
        .collect();
    plot_curves(title, xlabel, &curves)
}

/// As [`line_plot`], each curve with its own points `(x, y)`: the x axis spans the points
/// exactly, the y axis with 5 % to spare.
pub fn plot_curves(title: &str, xlabel: &str, curves: &[(&str, Vec<(f64, f64)>)]) -> String {
    let xs: Vec<f64> = curves
        .iter()
        .flat_map(|c| c.1.iter().map(|p| p.0))
        .collect();
    let ys: Vec<f64> = curves
        .iter()
        .flat_map(|c| c.1.iter().map(|p| p.1))
        .collect();
    let mut f = Figure::new(
        title,
        Axis::linear(xlabel, &xs, false),
        Axis::linear("", &ys, true),
    );
    for (k, (label, points)) in curves.iter().enumerate() {
        f.curve(label, points.iter().copied(), k);
    }
    f.finish()
}

/// The plots `satsim run` draws from a finished trajectory: `(file name, title, columns)`.
/// Groups whose columns are absent are skipped.
pub const PLOT_GROUPS: [(&str, &str, &[&str]); 12] = [
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
        "Energy (J): the budget T + V − W + D stays flat",
        &[
            "kinetic_energy",
            "potential_energy",
            "work_actuators",
            "energy_dissipated",
            "energy_budget",
        ],
    ),
    (
        "momentum.svg",
        "Angular momentum about the centre of mass (N m s)",
        &["h_x", "h_y", "h_z"],
    ),
    (
        "disturbances.svg",
        "Disturbance torques about the centre of mass, bus axes (N m)",
        &[
            "gg_torque_*",
            "srp_torque_*",
            "earth_radiation_torque_*",
            "drag_torque_*",
            "magnetic_torque_*",
        ],
    ),
    (
        "environment.svg",
        "Sunlight (fraction of the Sun's disk visible)",
        &["shadow"],
    ),
    (
        "magnetic_field.svg",
        "Geomagnetic field, bus axes (T)",
        &["magnetic_field_*"],
    ),
    (
        "fsw_pointing.svg",
        "Flight software: pointing and estimation errors (rad)",
        &["pointing_error", "est_error"],
    ),
    ("fsw_mode.svg", "Flight software mode", &["fsw_mode"]),
    (
        "fsw_dipole.svg",
        "Flight software: dipole commanded, bus axes (A m²)",
        &["fsw_dipole_*"],
    ),
];

/// Whether the column `name` matches `pattern`, where one `*` stands for any text
/// (`angle_*` matches `angle_h1`).
pub fn column_matches(pattern: &str, name: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == name,
        Some((a, b)) => name.len() >= a.len() + b.len() && name.starts_with(a) && name.ends_with(b),
    }
}

/// One curve's bounded decimation: the time axis is cut into at most [`Decimation::BINS`]
/// bins of equal width starting at the first row's time, and each bin keeps its first, last,
/// smallest and largest point (M4 decimation). Drawn as a polyline, these points cover the
/// same pixels as the full data as long as a bin is no wider than a pixel column. When a row
/// falls beyond the last bin, neighbouring bins merge pairwise (the width doubles), so at
/// least `BINS / 2` bins are always in use.
///
/// ```
/// use satsim_tools::output::Decimation;
/// let mut d = Decimation::new();
/// for k in 0..1_000_000 {
///     let t = k as f64 * 1e-3;
///     d.push(t, if k == 123_456 { 9.0 } else { t.sin() });
/// }
/// let points = d.points();
/// assert!(points.len() <= 4 * Decimation::BINS);
/// assert!(points.contains(&(123.456, 9.0)));
/// ```
#[derive(Clone, Debug)]
pub struct Decimation {
    t0: f64,
    width: f64,
    /// Per bin: first, last, min, max points `(t, y)`; `None` where no row fell.
    bins: Vec<Option<[(f64, f64); 4]>>,
}

impl Default for Decimation {
    fn default() -> Self {
        Self::new()
    }
}

impl Decimation {
    /// Bins kept: twice the plot's pixel width, so that every pixel column has a bin.
    pub const BINS: usize = 2 * PLOT_WIDTH_PX;

    /// An empty decimation.
    pub fn new() -> Self {
        Self {
            t0: f64::NAN,
            width: 0.0,
            bins: Vec::new(),
        }
    }

    fn merge(a: [(f64, f64); 4], b: [(f64, f64); 4]) -> [(f64, f64); 4] {
        let min = if b[2].1 < a[2].1 { b[2] } else { a[2] };
        let max = if b[3].1 > a[3].1 { b[3] } else { a[3] };
        [a[0], b[1], min, max]
    }

    /// Adds the point `(t, y)`; `t` must not decrease from one call to the next. Non-finite
    /// points are skipped.
    pub fn push(&mut self, t: f64, y: f64) {
        if !(t.is_finite() && y.is_finite()) {
            return;
        }
        if self.bins.is_empty() {
            self.t0 = t;
            self.width = 0.0;
            // The bins never outgrow this: no reallocation as they fill.
            self.bins.reserve_exact(Self::BINS);
            self.bins.push(Some([(t, y); 4]));
            return;
        }
        if self.width == 0.0 {
            // Second distinct time: the first width spreads the run so far over the bins.
            if t <= self.t0 {
                let b = self.bins[0].get_or_insert([(t, y); 4]);
                *b = Self::merge(*b, [(t, y); 4]);
                return;
            }
            self.width = (t - self.t0) / 4.0;
        }
        let mut k = ((t - self.t0) / self.width).floor().max(0.0) as usize;
        while k >= Self::BINS {
            // Merge pairs: bin j of the new width is bins 2j and 2j + 1 of the old, in
            // place (bin j is written after bins 2j and 2j + 1 are read).
            let n = self.bins.len();
            for j in 0..n.div_ceil(2) {
                let a = self.bins[2 * j];
                let b = self.bins.get(2 * j + 1).copied().flatten();
                self.bins[j] = match (a, b) {
                    (Some(a), Some(b)) => Some(Self::merge(a, b)),
                    (a, b) => a.or(b),
                };
            }
            self.bins.truncate(n.div_ceil(2));
            self.width *= 2.0;
            k = ((t - self.t0) / self.width).floor().max(0.0) as usize;
        }
        if self.bins.len() <= k {
            self.bins.resize(k + 1, None);
        }
        let p = [(t, y); 4];
        self.bins[k] = Some(match self.bins[k] {
            Some(b) => Self::merge(b, p),
            None => p,
        });
    }

    /// The kept points in time order (duplicates removed).
    pub fn points(&self) -> Vec<(f64, f64)> {
        let mut out: Vec<(f64, f64)> = Vec::with_capacity(4 * self.bins.len());
        for b in self.bins.iter().flatten() {
            let mut four = *b;
            four.sort_by(|p, q| p.0.total_cmp(&q.0));
            for p in four {
                if out.last() != Some(&p) {
                    out.push(p);
                }
            }
        }
        out
    }
}

/// The [`PLOT_GROUPS`] plots of a run, built while it runs in bounded memory: each plotted
/// column keeps a min/max-per-bin decimation (at least one bin per pixel column, see
/// [`PLOT_WIDTH_PX`]) instead of its rows, so a plot of 10⁶ rows looks like the full data and
/// weighs a few tens of kilobytes per curve.
///
/// ```
/// use satsim_tools::output::PlotRecorder;
/// let columns: Vec<String> = ["t", "q_w"].iter().map(|s| s.to_string()).collect();
/// let mut plots = PlotRecorder::new(&columns);
/// for k in 0..100_000 {
///     let t = k as f64 * 1e-3;
///     plots.push(&[t, t.sin()]);
/// }
/// assert_eq!(plots.rows(), 100_000);
/// assert!(plots.kept_points() <= 4 * 980);
/// ```
#[derive(Clone, Debug)]
pub struct PlotRecorder {
    columns: Vec<String>,
    /// `(file, title, column indices)` of the groups present.
    groups: Vec<(&'static str, &'static str, Vec<usize>)>,
    /// One decimation per column (empty for columns no plot uses).
    curves: Vec<Option<Decimation>>,
    rows: usize,
}

impl PlotRecorder {
    /// A recorder for rows with these `columns` (the first is the time).
    pub fn new(columns: &[String]) -> Self {
        let mut curves = vec![None; columns.len()];
        let mut groups = Vec::new();
        for (file, title, patterns) in PLOT_GROUPS {
            let idx: Vec<usize> = (0..columns.len())
                .filter(|&c| patterns.iter().any(|p| column_matches(p, &columns[c])))
                .collect();
            if idx.is_empty() {
                continue;
            }
            for &c in &idx {
                curves[c] = Some(Decimation::new());
            }
            groups.push((file, title, idx));
        }
        Self {
            columns: columns.to_vec(),
            groups,
            curves,
            rows: 0,
        }
    }
    /// Records one row (`row[0]` the time). Rows must come in increasing time.
    pub fn push(&mut self, row: &[f64]) {
        let Some(&t) = row.first() else {
            return;
        };
        self.rows += 1;
        for (c, curve) in self.curves.iter_mut().enumerate() {
            if let (Some(d), Some(&y)) = (curve, row.get(c)) {
                d.push(t, y);
            }
        }
    }
    /// Rows recorded.
    pub fn rows(&self) -> usize {
        self.rows
    }
    /// Points kept over all curves (bounded whatever the number of rows).
    pub fn kept_points(&self) -> usize {
        self.curves.iter().flatten().map(|d| d.points().len()).sum()
    }
    /// Writes the plots into `dir`; returns the files written (none without rows).
    pub fn write(&self, dir: &Path) -> io::Result<Vec<String>> {
        let mut written = Vec::new();
        if self.rows == 0 {
            return Ok(written);
        }
        for (file, title, idx) in &self.groups {
            let curves: Vec<(&str, Vec<(f64, f64)>)> = idx
                .iter()
                .filter_map(|&c| {
                    let d = self.curves[c].as_ref()?;
                    Some((self.columns[c].as_str(), d.points()))
                })
                .collect();
            std::fs::write(dir.join(file), plot_curves(title, "t (s)", &curves))?;
            written.push((*file).to_owned());
        }
        Ok(written)
    }
}

/// Writes the [`PLOT_GROUPS`] plots of a trajectory (`columns`, rows `data`, first column
/// the time) into `dir`; returns the files written. The same as feeding the rows to a
/// [`PlotRecorder`].
pub fn write_plots(dir: &Path, columns: &[String], data: &[Vec<f64>]) -> io::Result<Vec<String>> {
    let mut plots = PlotRecorder::new(columns);
    for row in data {
        plots.push(row);
    }
    plots.write(dir)
}

/// One shaded band of a [`band_plot`]: `lower` to `upper` at each x.
pub struct Band<'a> {
    /// Legend label.
    pub label: &'a str,
    /// Lower edge (one per x).
    pub lower: &'a [f64],
    /// Upper edge (one per x).
    pub upper: &'a [f64],
}

/// An SVG plot of nested shaded bands (drawn widest first, each darker than the last) and a
/// centre line, against `x`: a percentile envelope. Non-finite points are skipped.
///
/// ```
/// use satsim_tools::output::{Band, band_plot};
/// let x = [0.0, 1.0];
/// let svg = band_plot("env", "t (s)", &x, &[Band { label: "p5-p95", lower: &[0.0, 1.0], upper: &[1.0, 2.0] }], ("p50", &[0.5, 1.5]));
/// assert!(svg.contains("<polygon") && svg.contains("polyline"));
/// ```
pub fn band_plot(
    title: &str,
    xlabel: &str,
    x: &[f64],
    bands: &[Band],
    (centre_label, centre): (&str, &[f64]),
) -> String {
    let ys = bands
        .iter()
        .flat_map(|b| b.lower.iter().chain(b.upper))
        .chain(centre);
    let mut f = Figure::new(
        title,
        Axis::linear(xlabel, x, false),
        Axis::linear("", ys, true),
    );
    let n = bands.len().max(1) as f64;
    let points = |y: &[f64]| -> Vec<(f64, f64)> {
        x.iter()
            .zip(y)
            .map(|(a, b)| (*a, *b))
            .filter(|(a, b)| a.is_finite() && b.is_finite())
            .collect()
    };
    for (k, b) in bands.iter().enumerate() {
        let opacity = 0.2 + 0.3 * k as f64 / n;
        f.band(b.label, &points(b.lower), &points(b.upper), opacity);
    }
    f.curve(centre_label, points(centre), 1);
    f.finish()
}

/// An SVG histogram of the finite `values` in `bins` equal bins, with a note under the
/// legend (such as how many runs failed and are not shown).
///
/// ```
/// use satsim_tools::output::histogram_plot;
/// let svg = histogram_plot("h", "x", &[1.0, 2.0, 2.5, 3.0], 3, "0 failed");
/// assert_eq!(svg.matches("<rect class=\"bin\"").count(), 3);
/// ```
pub fn histogram_plot(
    title: &str,
    xlabel: &str,
    values: &[f64],
    bins: usize,
    note: &str,
) -> String {
    let bins = bins.max(1);
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    let (mut lo, mut hi) = finite
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        (lo, hi) = (0.0, 1.0);
    }
    if hi - lo <= 1e-12 * lo.abs().max(hi.abs()).max(1e-300) {
        let pad = if lo == 0.0 { 0.5 } else { 0.05 * lo.abs() };
        (lo, hi) = (lo - pad, hi + pad);
    }
    let width = (hi - lo) / bins as f64;
    let mut counts = vec![0usize; bins];
    for v in &finite {
        let b = (((v - lo) / width).floor() as usize).min(bins - 1);
        counts[b] += 1;
    }
    let top = counts.iter().copied().max().unwrap_or(0).max(1) as f64 * 1.05;
    let mut f = Figure::new(
        title,
        Axis::linear(xlabel, &[lo, hi], false),
        Axis::linear("runs", &[0.0, top], false),
    );
    for (b, &c) in counts.iter().enumerate() {
        f.bar(lo + b as f64 * width, lo + (b + 1) as f64 * width, c as f64);
    }
    f.legend_text(&format!("{} runs", finite.len()));
    f.legend_text(note);
    f.finish()
}

/// A CSV field, quoted when it must be (line breaks become spaces).
pub fn quote(field: &str) -> String {
    let one_line: String = field
        .chars()
        .map(|c| if c == '\n' || c == '\r' { ' ' } else { c })
        .collect();
    if one_line.contains([',', '"']) {
        format!("\"{}\"", one_line.replace('"', "\"\""))
    } else {
        one_line
    }
}

/// Appends the point `x,y ` of a polyline, as `format!("{x:.2},{y:.2} ")` writes it.
fn push_pixel(out: &mut String, x: f64, y: f64) {
    crate::numbers::push_fixed(out, x, 2);
    out.push(',');
    crate::numbers::push_fixed(out, y, 2);
    out.push(' ');
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bins merged in place are the bins merged into a new vector, as the decimation
    /// first did: the same bins through ten merges (300 000 points).
    #[test]
    fn decimation_merged_in_place_is_the_copying_merge() {
        fn copied(bins: &[Option<[(f64, f64); 4]>]) -> Vec<Option<[(f64, f64); 4]>> {
            bins.chunks(2)
                .map(|pair| match (pair[0], pair.get(1).copied().flatten()) {
                    (Some(a), Some(b)) => Some(Decimation::merge(a, b)),
                    (a, b) => a.or(b),
                })
                .collect()
        }
        let mut d = Decimation::new();
        let mut seen = 0;
        for k in 0..300_000u64 {
            let t = k as f64 * 0.25 + if k % 3 == 0 { 0.0 } else { 0.1 };
            let y = ((k * 7919) % 10007) as f64;
            let before = d.bins.clone();
            d.push(t, y);
            if d.bins.len() < before.len() {
                // A merge (or several): redo them by copying, then add the point.
                let mut want = before;
                while want.len() > d.bins.len() || want.len() >= Decimation::BINS {
                    want = copied(&want);
                }
                let last = d.bins.len() - 1;
                assert_eq!(
                    &want[..last.min(want.len())],
                    &d.bins[..last.min(want.len())]
                );
                seen += 1;
            }
        }
        assert!(seen >= 8, "{seen} merges");
    }

    #[test]
    fn events_file_has_one_quoted_line_per_event() {
        let dir = std::env::temp_dir().join(format!("satsim-events-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("events.csv");
        let n = write_events(
            &path,
            [
                (0.5, "hinge_stops", "hinge a latched"),
                (1.25, "reaction_wheels", "wheel 1, saturated \"hard\""),
            ],
        )
        .unwrap();
        assert_eq!(n, 2);
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            text,
            "t,effect,event\n0.5,hinge_stops,hinge a latched\n1.25,reaction_wheels,\"wheel 1, saturated \"\"hard\"\"\"\n"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn huge_and_tiny_numbers_are_written_in_exponent_form_and_read_back_exactly() {
        let dir = std::env::temp_dir().join(format!("satsim-csv-num-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.csv");
        let mut w = CsvWriter::create(&path, &["a".into(), "b".into(), "c".into()]).unwrap();
        let row = [1e300, -2.5e-300, 0.125, 123456.75, 1e9, f64::MAX, 5e-324];
        w.row(&row).unwrap();
        w.flush().unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let line = text.lines().nth(1).unwrap();
        assert_eq!(
            line,
            "1e300,-2.5e-300,0.125,123456.75,1e9,1.7976931348623157e308,5e-324"
        );
        let back: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
        assert_eq!(back, row);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
