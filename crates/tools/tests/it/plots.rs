//! The run's plots in bounded memory: a plot of 10⁶ rows keeps each curve's extremes and
//! weighs under 1 MiB.

use satsim_tools::output::{PlotRecorder, write_plots};

fn columns() -> Vec<String> {
    ["t", "q_w", "q_x", "q_y", "q_z", "kinetic_energy", "h_x"]
        .iter()
        .map(|s| s.to_string())
        .collect()
}

/// Row `k` of 10⁶: smooth curves plus one narrow spike on `q_x` (a single row).
fn row(k: usize) -> Vec<f64> {
    let t = k as f64 * 1e-3;
    let spike = if k == 777_777 { 5.0 } else { 0.0 };
    vec![
        t,
        t.cos(),
        (3.0 * t).sin() + spike,
        -(t * 0.01).sin(),
        0.1,
        1.0 + 1e-6 * t,
        -2.0,
    ]
}

#[test]
fn a_plot_of_a_million_rows_is_small_and_keeps_the_extremes() {
    let dir = satsim_testkit::temp_dir("plots");
    let n = 1_000_000;
    let mut plots = PlotRecorder::new(&columns());
    for k in 0..n {
        plots.push(&row(k));
    }
    assert_eq!(plots.rows(), n);
    // At most 4 points per bin, at most 2 x 490 bins, 6 curves.
    assert!(
        plots.kept_points() <= 6 * 4 * 980,
        "{}",
        plots.kept_points()
    );
    let files = plots.write(&dir).unwrap();
    assert_eq!(files, ["attitude.svg", "energy.svg", "momentum.svg"]);
    for f in &files {
        let size = std::fs::metadata(dir.join(f)).unwrap().len();
        assert!(size < 1 << 20, "{f}: {size} bytes");
    }
    let svg = std::fs::read_to_string(dir.join("attitude.svg")).unwrap();
    // The spike (one row in a million) is drawn: q_x's polyline reaches above every other
    // point, i.e. its smallest y pixel is the plot's top margin region.
    let q_x = svg
        .lines()
        .filter(|l| l.starts_with("<polyline"))
        .nth(1)
        .unwrap();
    let ys: Vec<f64> = q_x
        .split("points=\"")
        .nth(1)
        .unwrap()
        .trim_end_matches("\"/>")
        .split(' ')
        .map(|p| p.split(',').nth(1).unwrap().parse().unwrap())
        .collect();
    let top = ys.iter().copied().fold(f64::INFINITY, f64::min);
    // y range [-1.3, 5.1] after padding onto 36..352 px: 5.0 maps to about 51 px.
    assert!(top < 60.0, "the spike is lost: highest point at {top} px");
    // The same through `write_plots` on the rows themselves.
    let data: Vec<Vec<f64>> = (0..200_000).map(row).collect();
    let files = write_plots(&dir, &columns(), &data).unwrap();
    for f in &files {
        let size = std::fs::metadata(dir.join(f)).unwrap().len();
        assert!(size < 1 << 20, "write_plots {f}: {size} bytes");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Decimation keeps each curve's exact minimum and maximum and its first and last points.
#[test]
fn the_decimation_keeps_first_last_min_and_max() {
    let cols: Vec<String> = ["t", "h_x"].iter().map(|s| s.to_string()).collect();
    let mut plots = PlotRecorder::new(&cols);
    let n = 123_457;
    let y = |k: usize| ((k * 7919) % 10007) as f64 - 5000.0;
    for k in 0..n {
        plots.push(&[k as f64 * 0.5, y(k)]);
    }
    let dir = satsim_testkit::temp_dir("plots-m4");
    plots.write(&dir).unwrap();
    let svg = std::fs::read_to_string(dir.join("momentum.svg")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let pts: Vec<(f64, f64)> = svg
        .lines()
        .find(|l| l.starts_with("<polyline"))
        .unwrap()
        .split("points=\"")
        .nth(1)
        .unwrap()
        .trim_end_matches("\"/>")
        .split(' ')
        .map(|p| {
            let (a, b) = p.split_once(',').unwrap();
            (a.parse().unwrap(), b.parse().unwrap())
        })
        .collect();
    assert!(pts.len() <= 4 * 980 && pts.len() > 980, "{}", pts.len());
    // First point at the left edge, last at the right, in time order.
    assert!((pts[0].0 - 80.0).abs() < 0.01 && (pts.last().unwrap().0 - 570.0).abs() < 0.01);
    assert!(pts.windows(2).all(|w| w[1].0 >= w[0].0));
    // Extremes -5000 and 5006 reach the padded range's ends: 5 % inside the frame.
    let (lo, hi) = pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.1), b.max(p.1))
        });
    let frame = 352.0 - 36.0;
    assert!((hi - (352.0 - frame / 1.1 * 0.05)).abs() < 0.02, "{hi}");
    assert!((lo - (36.0 + frame / 1.1 * 0.05)).abs() < 0.02, "{lo}");
}
