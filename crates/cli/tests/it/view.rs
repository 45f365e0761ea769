//! The 3-D playback `DIR/view.html` (contract section 11), `satsim view DIR`, and the page in
//! a real browser: headless Chromium (Debian's `chromium`) loads the page with no console
//! message, the body positions it computes match satsim's own (the contract's kinematics,
//! recomputed here from `trajectory.csv` and the model file) to 1e-6 m, and screenshots at
//! t = 0 and at the end differ where the panels moved.
//!
//! The browser tests need Chromium: they fail when it is missing and `CI=true`, and are
//! skipped with a note otherwise. `SATSIM_CHROMIUM` names the browser's binary if it is not
//! `chromium` (or `chromium-browser`, `google-chrome`) on the `PATH`.

use crate::common;
use common::{csv, root, satsim_in};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use satsim_tree::io::parse_model_file;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

type V3 = Vector3<f64>;

fn temp_dir(test: &str) -> PathBuf {
    satsim_testkit::temp_dir(&format!("view-{test}"))
}

/// A scene of the satellite (`examples/satellite.toml`, with `shape` keys) whose panels start
/// folded and open on their springs.
fn scene(duration: f64, every: f64, step: f64, view: Option<bool>) -> String {
    let view = view.map_or(String::new(), |v| format!("view = {v}\n"));
    format!(
        r#"model = "satellite.toml"
duration = {duration}
[initial]
base = {{ attitude = [0.9, 0.1, 0.3, 0.3], angular_velocity = [0.01, -0.02, 0.03] }}
hinges = {{ angle = [0.2, -0.1, 0.1, 2.6, -2.6], rate = [0.0, 0.0, 0.0, 0.0, 0.0] }}
[integrator]
method = "rk4"
step = {step}
[output]
every = {every}
{view}[effects.hinge_springs]
stiffness = [50.0, 50.0, 50.0, 8.0, 8.0]
damping = [40.0, 40.0, 40.0, 1.0, 1.0]
"#
    )
}

fn setup(test: &str, scene_text: &str) -> PathBuf {
    let dir = temp_dir(test);
    std::fs::copy(
        root().join("examples/satellite.toml"),
        dir.join("satellite.toml"),
    )
    .unwrap();
    std::fs::write(dir.join("deploy.toml"), scene_text).unwrap();
    let o = satsim_in(&dir, &["run", "deploy.toml", "--out", "out"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    dir
}

// ---------------------------------------------------------------------------------------------
// Without a browser

#[test]
fn run_writes_the_page_and_satsim_view_recreates_it() {
    let dir = setup("recreate", &scene(3.0, 0.5, 0.01, None));
    let out = dir.join("out");
    let page = std::fs::read_to_string(out.join("view.html")).unwrap();
    assert!(page.starts_with("<!DOCTYPE html>"));
    for f in ["poses.csv", "view.json"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let (_, rows) = csv(&out.join("poses.csv"));
    assert_eq!(rows.len(), 7);
    // Self-contained: nothing is loaded from anywhere.
    for needle in [
        "http://",
        "https://",
        "src=\"",
        "fetch(",
        "XMLHttpRequest",
        "@import",
    ] {
        assert!(!page.contains(needle), "{needle}");
    }
    std::fs::remove_file(out.join("view.html")).unwrap();
    let o = satsim_in(&dir, &["view", "out"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read_to_string(out.join("view.html")).unwrap(),
        page
    );
    let o = satsim_in(&dir, &["view", "out", "--out", "copy.html"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read_to_string(dir.join("copy.html")).unwrap(),
        page
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn view_false_writes_no_page_and_satsim_view_says_why() {
    let dir = setup("off", &scene(1.0, 0.5, 0.01, Some(false)));
    let out = dir.join("out");
    assert!(out.join("trajectory.csv").is_file());
    for f in ["view.html", "poses.csv", "view.json"] {
        assert!(!out.join(f).exists(), "{f}");
    }
    let o = satsim_in(&dir, &["view", "out"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.starts_with("error: out/view.json: "), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    let o = satsim_in(&dir, &["view"]);
    assert_eq!(o.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn pages_stay_small_however_long_the_run() {
    // 1000 rows of the satellite: every row kept, under 2 MiB.
    let dir = setup("size", &scene(99.9, 0.1, 0.01, None));
    let out = dir.join("out");
    let (_, rows) = csv(&out.join("trajectory.csv"));
    assert_eq!(rows.len(), 1000);
    let (_, poses) = csv(&out.join("poses.csv"));
    assert_eq!(poses.len(), 1000);
    let size = std::fs::metadata(out.join("view.html")).unwrap().len();
    assert!(size < 2 << 20, "{size} bytes");
    // 20 001 rows: decimated to a bounded number of frames, first and last kept.
    std::fs::write(dir.join("long.toml"), scene(200.0, 0.01, 0.01, None)).unwrap();
    let o = satsim_in(&dir, &["run", "long.toml", "--out", "long"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, poses) = csv(&dir.join("long/poses.csv"));
    assert!(poses.len() < 4000, "{} frames", poses.len());
    assert_eq!((poses[0][0], poses.last().unwrap()[0]), (0.0, 200.0));
    let size = std::fs::metadata(dir.join("long/view.html")).unwrap().len();
    assert!(size < 2 << 20, "{size} bytes");
    let _ = std::fs::remove_dir_all(&dir);
}

// ---------------------------------------------------------------------------------------------
// The contract's kinematics, written out here (not the library's): body positions relative to
// the system's centre of mass, inertial axes.

fn body_positions(model_text: &str, row: &[f64], header: &[String]) -> HashMap<String, V3> {
    let file = parse_model_file(model_text, Path::new("satellite.toml")).unwrap();
    let col = |n: &str| header.iter().position(|c| c == n).unwrap();
    let q0 = UnitQuaternion::from_quaternion(Quaternion::new(
        row[col("q_w")],
        row[col("q_x")],
        row[col("q_y")],
        row[col("q_z")],
    ));
    let v3 = |a: &[f64; 3]| V3::new(a[0], a[1], a[2]);
    let root = file.body[0].get_ref().name.get_ref().clone();
    let mut pose: HashMap<String, (UnitQuaternion<f64>, V3)> = HashMap::new();
    pose.insert(root, (q0, V3::zeros()));
    // Place children once their parent is placed (hinges in any order).
    while pose.len() < file.body.len() {
        for h in &file.hinge {
            let h = h.get_ref();
            let (parent, child) = (h.parent.get_ref(), h.child.get_ref());
            if pose.contains_key(child) {
                continue;
            }
            let Some(&(rp, pp)) = pose.get(parent) else {
                continue;
            };
            let phi = row[col(&format!("angle_{}", h.name.get_ref()))];
            let axis = nalgebra::Unit::new_normalize(v3(h.axis.get_ref()));
            let rot0 = h.rotation.as_ref().map_or(UnitQuaternion::identity(), |r| {
                let [w, x, y, z] = *r.get_ref();
                UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z))
            });
            let at = h.at.as_ref().map_or(V3::zeros(), |a| v3(a.get_ref()));
            let child_at = h.child_at.as_ref().map_or(V3::zeros(), |a| v3(a.get_ref()));
            // R_c = R_p Rot(axis, φ) rotation; h = r_p + R_p at; r_c = h − R_c child_at.
            let rc = rp * UnitQuaternion::from_axis_angle(&axis, phi) * rot0;
            let point = pp + rp * at;
            pose.insert(child.clone(), (rc, point - rc * child_at));
        }
    }
    let (mut m, mut mc) = (0.0, V3::zeros());
    for b in &file.body {
        let b = b.get_ref();
        let (r, p) = pose[b.name.get_ref()];
        let com = b.com.as_ref().map_or(V3::zeros(), |c| v3(c.get_ref()));
        m += b.mass.get_ref();
        mc += (p + r * com) * *b.mass.get_ref();
    }
    let c = mc / m;
    pose.into_iter().map(|(n, (_, p))| (n, p - c)).collect()
}

// ---------------------------------------------------------------------------------------------
// The browser

/// The Chromium binary, or `None` (after a note) where it is missing outside CI.
fn chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("SATSIM_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH").unwrap_or_default();
    for name in ["chromium", "chromium-browser", "google-chrome"] {
        for dir in std::env::split_paths(&path) {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!(
            "chromium is required in CI for the 3-D view's browser test (apt-get install chromium)"
        );
    }
    eprintln!("note: chromium not found: skipping the 3-D view's browser test");
    None
}

/// Runs headless Chromium on `url` with `extra` flags (at most 120 s); returns its stdout and
/// stderr.
fn browse(chromium: &Path, work: &Path, url: &str, extra: &[&str]) -> (String, String) {
    let profile = work.join(format!("profile-{}", extra.len() + url.len()));
    let _ = std::fs::remove_dir_all(&profile);
    std::fs::create_dir_all(&profile).unwrap();
    let (out_path, err_path) = (work.join("chromium.out"), work.join("chromium.err"));
    let mut child = Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
            "--force-device-scale-factor=1",
            "--window-size=1200,800",
            "--virtual-time-budget=4000",
            "--enable-logging=stderr",
            "--v=0",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(url)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out_path).unwrap())
        .stderr(std::fs::File::create(&err_path).unwrap())
        .spawn()
        .expect("start chromium");
    let started = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if started.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("chromium did not finish within 120 s on {url}");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = std::fs::remove_dir_all(&profile);
    (
        std::fs::read_to_string(out_path).unwrap(),
        std::fs::read_to_string(err_path).unwrap(),
    )
}

/// The page's layout in the browser tests (CSS pixels): fixed, so that the report of one
/// browser run describes the screenshot of another (headless Chromium lays a page out in a
/// smaller viewport for `--dump-dom` than for `--screenshot`).
const SIZE: &str = "1100x760";

/// The page's self-test report (`#selftest=…`), parsed.
fn selftest(chromium: &Path, work: &Path, page: &Path, fragment: &str) -> serde_json::Value {
    let url = format!("file://{}#size={SIZE}&{fragment}", page.display());
    let (dom, log) = browse(chromium, work, &url, &["--dump-dom"]);
    // The page logs nothing: any console line is an error or a warning. SwiftShader (the
    // software WebGL of a machine without a GPU) adds its own performance notices about the
    // compositor reading the canvas back ("GL Driver Message (OpenGL, Performance, …): GPU
    // stall due to ReadPixels"), whatever the page does: those alone are not the page's.
    let console: Vec<&str> = log
        .lines()
        .filter(|l| l.contains(":CONSOLE"))
        .filter(|l| {
            !(l.contains("GL Driver Message (OpenGL, Performance,") && l.contains("GPU stall"))
        })
        .collect();
    assert!(console.is_empty(), "console messages: {console:#?}");
    let start = dom
        .find("<pre id=\"satsim-selftest\">")
        .expect("the page's report element")
        + "<pre id=\"satsim-selftest\">".len();
    let end = start + dom[start..].find("</pre>").unwrap();
    let text = dom[start..end]
        .replace("&quot;", "\"")
        .replace("&amp;", "&");
    assert!(!text.is_empty(), "the page wrote no report: {log}");
    let report: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(report["webgl"], true, "{report}");
    assert_eq!(report["errors"], serde_json::json!([]), "{report}");
    assert_eq!(report["gl_error"], 0, "{report}");
    report
}

struct Image {
    width: usize,
    height: usize,
    rgb: Vec<[u8; 3]>,
}

fn screenshot(chromium: &Path, work: &Path, page: &Path, fragment: &str, name: &str) -> Image {
    let png_path = work.join(name);
    let url = format!("file://{}#size={SIZE}&{fragment}", page.display());
    let (_, log) = browse(
        chromium,
        work,
        &url,
        &[&format!("--screenshot={}", png_path.display())],
    );
    let decoder = png::Decoder::new(
        std::fs::File::open(&png_path)
            .unwrap_or_else(|e| panic!("no screenshot {}: {e}\n{log}", png_path.display())),
    );
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    let channels = match info.color_type {
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        other => panic!("unexpected PNG colour type {other:?}"),
    };
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let rgb = buf[..info.buffer_size()]
        .chunks(channels)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    Image {
        width: info.width as usize,
        height: info.height as usize,
        rgb,
    }
}

/// `[x0, y0, x1, y1]` in page pixels.
fn rect(v: &serde_json::Value) -> [f64; 4] {
    let a: Vec<f64> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    [a[0], a[1], a[2], a[3]]
}

fn inside(r: &[f64; 4], x: usize, y: usize, margin: f64) -> bool {
    let (x, y) = (x as f64 + 0.5, y as f64 + 0.5);
    x >= r[0] - margin && x <= r[2] + margin && y >= r[1] - margin && y <= r[3] + margin
}

#[test]
fn the_page_plays_the_run_in_a_real_browser() {
    let Some(chromium) = chromium() else {
        return;
    };
    let dir = setup("browser", &scene(6.0, 0.5, 0.01, None));
    let page = dir.join("out/view.html").canonicalize().unwrap();
    let work = dir.join("browser");
    std::fs::create_dir_all(&work).unwrap();

    // Positions at three output times against the contract's kinematics.
    let (header, rows) = csv(&dir.join("out/trajectory.csv"));
    let model_text = std::fs::read_to_string(dir.join("satellite.toml")).unwrap();
    let picks = [0, 5, rows.len() - 1];
    let mut times: Vec<String> = picks.iter().map(|&k| rows[k][0].to_string()).collect();
    // And half-way between rows 5 and 6: the page interpolates positions linearly.
    let mid = 0.5 * (rows[5][0] + rows[6][0]);
    times.push(mid.to_string());
    let report = selftest(
        &chromium,
        &work,
        &page,
        &format!("t=0&selftest={}", times.join(",")),
    );
    let names: Vec<String> = report["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap().to_owned())
        .collect();
    assert_eq!(names.len(), 6);
    let mut worst: f64 = 0.0;
    for (j, &k) in picks.iter().enumerate() {
        let expected = body_positions(&model_text, &rows[k], &header);
        for (i, name) in names.iter().enumerate() {
            let p = &report["positions"][j][i];
            let page_p = V3::new(
                p[0].as_f64().unwrap(),
                p[1].as_f64().unwrap(),
                p[2].as_f64().unwrap(),
            );
            let err = (page_p - expected[name]).norm();
            worst = worst.max(err);
            assert!(
                err < 1e-6,
                "{name} at t = {}: page {page_p:?}, satsim {:?}",
                rows[k][0],
                expected[name]
            );
        }
    }
    let (p5, p6) = (
        body_positions(&model_text, &rows[5], &header),
        body_positions(&model_text, &rows[6], &header),
    );
    for (i, name) in names.iter().enumerate() {
        let p = &report["positions"][3][i];
        let page_p = V3::new(
            p[0].as_f64().unwrap(),
            p[1].as_f64().unwrap(),
            p[2].as_f64().unwrap(),
        );
        let lerp = 0.5 * (p5[name] + p6[name]);
        assert!(
            (page_p - lerp).norm() < 1e-6,
            "{name} at t = {mid}: {page_p:?}, {lerp:?}"
        );
    }
    // The panels really moved (the comparison is not of frozen poses).
    let at = |j: usize, name: &str| {
        let i = names.iter().position(|n| n == name).unwrap();
        let p = &report["positions"][j][i];
        V3::new(
            p[0].as_f64().unwrap(),
            p[1].as_f64().unwrap(),
            p[2].as_f64().unwrap(),
        )
    };
    assert!((at(2, "panel3") - at(0, "panel3")).norm() > 0.5);
    eprintln!("largest position difference, page against satsim: {worst:e} m");

    // Screenshots at t = 0 and at the end: they differ where the panels moved and nowhere
    // far from the bodies.
    let end = selftest(&chromium, &work, &page, "t=end&selftest=");
    let first = screenshot(&chromium, &work, &page, "t=0", "t0.png");
    let last = screenshot(&chromium, &work, &page, "t=end", "end.png");
    assert_eq!((first.width, first.height), (last.width, last.height));
    let canvas = rect(&report["canvas"]);
    let canvas = [
        canvas[0],
        canvas[1],
        canvas[0] + canvas[2],
        canvas[1] + canvas[3],
    ];
    let boxes = |r: &serde_json::Value| -> Vec<[f64; 4]> {
        r["screen"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|b| !b.is_null())
            .map(rect)
            .collect()
    };
    let panel_box = |r: &serde_json::Value, name: &str| {
        rect(&r["screen"][names.iter().position(|n| n == name).unwrap()])
    };
    let all_boxes: Vec<[f64; 4]> = boxes(&report).into_iter().chain(boxes(&end)).collect();
    let changed = |x: usize, y: usize| {
        let (a, b) = (first.rgb[y * first.width + x], last.rgb[y * last.width + x]);
        (0..3).any(|c| a[c].abs_diff(b[c]) > 24)
    };
    let (mut in_panel3, mut n_panel3, mut far_changed, mut n_far) = (0, 0, 0, 0);
    let panel3_end = panel_box(&end, "panel3");
    let panel3_start = panel_box(&report, "panel3");
    for y in 0..first.height {
        for x in 0..first.width {
            if !inside(&canvas, x, y, -2.0) {
                continue;
            }
            // Where panel 3 is at the end and was not at the start.
            if inside(&panel3_end, x, y, -3.0) && !inside(&panel3_start, x, y, 3.0) {
                n_panel3 += 1;
                in_panel3 += changed(x, y) as usize;
            }
            // Far (40 px) from every body at both times: the background.
            if all_boxes.iter().all(|b| !inside(b, x, y, 40.0)) {
                n_far += 1;
                far_changed += changed(x, y) as usize;
            }
        }
    }
    eprintln!(
        "screenshots: {in_panel3} of {n_panel3} pixels changed where panel3 moved to, \
         {far_changed} of {n_far} far from the bodies"
    );
    assert!(
        n_panel3 > 200,
        "panel 3 barely moved on screen: {n_panel3} pixels"
    );
    // A tilted box fills about half its bounding box.
    assert!(
        in_panel3 as f64 > 0.25 * n_panel3 as f64,
        "{in_panel3} of {n_panel3} pixels changed where panel3 moved to"
    );
    // Panel 3 is drawn, in its own colour, at its centre on screen at each time, and the
    // other screenshot shows something else there.
    let i3 = names.iter().position(|n| n == "panel3").unwrap();
    let colour = report["colours"][i3].as_str().unwrap();
    let base: Vec<f64> = (0..3)
        .map(|k| u8::from_str_radix(&colour[1 + 2 * k..3 + 2 * k], 16).unwrap() as f64)
        .collect();
    for (r, here, other) in [(&report, &first, &last), (&end, &last, &first)] {
        let c = &r["centres"][i3];
        let (x, y) = (
            c[0].as_f64().unwrap() as usize,
            c[1].as_f64().unwrap() as usize,
        );
        let p = here.rgb[y * here.width + x].map(f64::from);
        // Lit: the base colour times one factor (0.32 to 1) for all three channels.
        let k = p[0] / base[0];
        assert!(
            (0.3..=1.02).contains(&k) && (0..3).all(|c| (p[c] - k * base[c]).abs() < 6.0),
            "panel3's centre ({x}, {y}) shows {p:?}, not {colour}"
        );
        let q = other.rgb[y * other.width + x].map(f64::from);
        assert!(
            (0..3).any(|c| (q[c] - k * base[c]).abs() > 24.0),
            "the other screenshot shows panel3 at ({x}, {y}) too: {q:?}"
        );
    }
    assert!(n_far > 10_000);
    // Axes' labels and the thin hinge lines may reach beyond the boxes: allow a few pixels.
    assert!(
        (far_changed as f64) < 0.002 * n_far as f64,
        "{far_changed} of {n_far} background pixels changed"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A cantilever on a fixed base (its root body's frame is the inertial one), along y, bending
/// along z, its first mode deflected at the start.
const CANTILEVER_SCENE: &str = r#"duration = 0.5
[model]
base = { kind = "fixed" }
[[model.body]]
name = "beam"
mass = 1.0
inertia = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]
[model.body.flexible]
beam = { root = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], bend = [0.0, 0.0, 1.0],
         length = 2.0, EI = 500.0, rho_A = 5.0, modes = 3 }
[initial]
flexible = { beam = { eta = [0.01, 0.0, 0.0], etadot = [0.0, 0.02, 0.0] } }
[output]
every = 0.05
plots = false
"#;

#[test]
fn the_page_draws_the_beam_bent_by_its_modes() {
    let Some(chromium) = chromium() else {
        return;
    };
    let dir = temp_dir("beam");
    std::fs::write(dir.join("beam.toml"), CANTILEVER_SCENE).unwrap();
    let o = satsim_in(&dir, &["run", "beam.toml", "--out", "out"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let page = dir.join("out/view.html").canonicalize().unwrap();
    let work = dir.join("browser");
    std::fs::create_dir_all(&work).unwrap();
    let (header, rows) = csv(&dir.join("out/trajectory.csv"));
    let tip = header.iter().position(|c| c == "tip_beam").unwrap();
    let picks = [0, 3, rows.len() - 1];
    let times: Vec<String> = picks.iter().map(|&k| rows[k][0].to_string()).collect();
    let report = selftest(
        &chromium,
        &work,
        &page,
        &format!("bend=10&selftest={}", times.join(",")),
    );
    assert_eq!(report["bend"], 10.0, "{report}");
    for (n, &k) in picks.iter().enumerate() {
        let line = report["beams"][n][0].as_array().unwrap();
        let at = |j: usize, c: usize| line[j][c].as_f64().unwrap();
        // The clamped root stays put; the tip is at the beam's length along y, deflected along
        // z by ten times the run's `tip_beam` (the poses keep 1e-9 of the modal coordinates).
        for c in 0..3 {
            assert!(at(0, c).abs() < 1e-12, "{line:?}");
        }
        let last = line.len() - 1;
        assert!(at(last, 0).abs() < 1e-12 && (at(last, 1) - 2.0).abs() < 1e-12);
        let expected = 10.0 * rows[k][tip];
        assert!(
            (at(last, 2) - expected).abs() < 1e-7,
            "t = {}: {} vs {expected}",
            rows[k][0],
            at(last, 2)
        );
    }
    // The tip moves: the drawing is not the straight beam.
    assert!(rows.iter().map(|r| r[tip].abs()).fold(0.0, f64::max) > 1e-3);
    let _ = std::fs::remove_dir_all(&dir);
}
