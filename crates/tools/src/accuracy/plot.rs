//! The log-log SVG line plot of the work-precision diagrams.

/// A log-log SVG line plot (the shared [`crate::output::Figure`] writer): decade grid and
/// labels, one polyline with markers per series, an optional dashed horizontal line labelled
/// "reference floor".
pub fn loglog_plot(
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[(String, Vec<(f64, f64)>)],
    floor: Option<f64>,
) -> String {
    use crate::output::{Axis, Figure};
    let xs = series.iter().flat_map(|s| s.1.iter().map(|p| p.0));
    let ys = series.iter().flat_map(|s| s.1.iter().map(|p| p.1));
    let mut f = Figure::new(
        title,
        Axis::log10(xlabel, xs),
        Axis::log10(ylabel, ys.chain(floor)),
    );
    if let Some(floor) = floor {
        f.reference(floor, "reference floor");
    }
    for (k, (label, points)) in series.iter().enumerate() {
        f.curve(label, points.iter().copied(), k);
        f.markers(points.iter().copied(), k);
    }
    f.finish()
}
