//! The log-log SVG line plot of the work-precision diagrams.

use std::fmt::Write as _;

const COLOURS: [&str; 6] = [
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b",
];

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// A log-log SVG line plot: decade grid and labels, one polyline with markers per series,
/// an optional dashed horizontal line labelled "reference floor".
pub fn loglog_plot(
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[(String, Vec<(f64, f64)>)],
    floor: Option<f64>,
) -> String {
    let (w, h) = (760.0, 480.0);
    let (ml, mr, mt, mb) = (80.0, 170.0, 40.0, 52.0);
    let (pw, ph) = (w - ml - mr, h - mt - mb);
    let pos = |v: f64| v > 0.0 && v.is_finite();
    let xs = series
        .iter()
        .flat_map(|s| s.1.iter().map(|p| p.0))
        .filter(|v| pos(*v));
    let ys = series
        .iter()
        .flat_map(|s| s.1.iter().map(|p| p.1))
        .chain(floor)
        .filter(|v| pos(*v));
    let range = |it: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = it.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
        if lo.is_finite() {
            let (a, b) = (lo.log10().floor(), hi.log10().ceil());
            (a, if b > a { b } else { a + 1.0 })
        } else {
            (0.0, 1.0)
        }
    };
    let (x0, x1) = range(&mut xs.into_iter());
    let (y0, y1) = range(&mut ys.into_iter());
    let sx = |v: f64| ml + (v.log10() - x0) / (x1 - x0) * pw;
    let sy = |v: f64| mt + ph - (v.log10() - y0) / (y1 - y0) * ph;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="24" text-anchor="middle" font-size="15">{}</text>"#,
        ml + pw / 2.0,
        esc(title)
    );
    let decade_label = |d: f64| format!("1e{}", d as i32);
    let xstep = ((x1 - x0) / 10.0).ceil().max(1.0);
    let mut d = x0;
    while d <= x1 + 1e-9 {
        let px = ml + (d - x0) / (x1 - x0) * pw;
        let _ = writeln!(
            s,
            r##"<line x1="{px:.1}" y1="{mt}" x2="{px:.1}" y2="{:.1}" stroke="#e0e0e0"/><text x="{px:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
            mt + ph,
            mt + ph + 16.0,
            decade_label(d)
        );
        d += xstep;
    }
    let ystep = ((y1 - y0) / 12.0).ceil().max(1.0);
    let mut d = y0;
    while d <= y1 + 1e-9 {
        let py = mt + ph - (d - y0) / (y1 - y0) * ph;
        let _ = writeln!(
            s,
            r##"<line x1="{ml}" y1="{py:.1}" x2="{:.1}" y2="{py:.1}" stroke="#e0e0e0"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
            ml + pw,
            ml - 6.0,
            py + 4.0,
            decade_label(d)
        );
        d += ystep;
    }
    let _ = writeln!(
        s,
        r#"<rect x="{ml}" y="{mt}" width="{pw}" height="{ph}" fill="none" stroke="black"/>"#
    );
    let _ = writeln!(
        s,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
        ml + pw / 2.0,
        h - 12.0,
        esc(xlabel)
    );
    let _ = writeln!(
        s,
        r#"<text transform="translate(18,{:.1}) rotate(-90)" text-anchor="middle">{}</text>"#,
        mt + ph / 2.0,
        esc(ylabel)
    );
    if let Some(f) = floor.filter(|f| pos(*f)) {
        let py = sy(f);
        let _ = writeln!(
            s,
            r##"<line x1="{ml}" y1="{py:.1}" x2="{:.1}" y2="{py:.1}" stroke="#777" stroke-dasharray="6,4"/><text x="{:.1}" y="{:.1}" fill="#555">reference floor</text>"##,
            ml + pw,
            ml + pw + 8.0,
            py + 4.0
        );
    }
    for (k, (label, pts)) in series.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        let pts: Vec<(f64, f64)> = pts
            .iter()
            .copied()
            .filter(|p| pos(p.0) && pos(p.1))
            .collect();
        let line: Vec<String> = pts
            .iter()
            .map(|p| format!("{:.1},{:.1}", sx(p.0), sy(p.1)))
            .collect();
        let _ = writeln!(
            s,
            r#"<polyline fill="none" stroke="{colour}" stroke-width="1.8" points="{}"/>"#,
            line.join(" ")
        );
        for p in &pts {
            let _ = writeln!(
                s,
                r#"<circle cx="{:.1}" cy="{:.1}" r="3" fill="{colour}"/>"#,
                sx(p.0),
                sy(p.1)
            );
        }
        let ly = mt + 12.0 + 20.0 * k as f64;
        let _ = writeln!(
            s,
            r#"<line x1="{:.1}" y1="{ly:.1}" x2="{:.1}" y2="{ly:.1}" stroke="{colour}" stroke-width="2"/><text x="{:.1}" y="{:.1}">{}</text>"#,
            ml + pw + 36.0,
            ml + pw + 56.0,
            ml + pw + 62.0,
            ly + 4.0,
            esc(label)
        );
    }
    s.push_str("</svg>\n");
    s
}
