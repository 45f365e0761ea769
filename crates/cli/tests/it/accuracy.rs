//! `satsim accuracy`: the work-precision sweep writes its CSV, SVG diagrams and markdown
//! table; bad input exits with status 2.

use crate::common;
use common::satsim_in;
use std::path::PathBuf;
use std::process::Output;

fn temp_dir(test: &str) -> PathBuf {
    satsim_testkit::temp_dir_with(&format!("accuracy-{test}"), &["examples/satellite.toml"])
}

/// A short scene: the preprint satellite swinging on its hinge springs, one panel hitting a
/// latching stop (an event) part-way.
const SCENE: &str = r#"model = "satellite.toml"
duration = 2.0
[initial]
base = { angular_velocity = [0.01, -0.02, 0.005] }
hinges = { angle = [0.05, 0.0, 0.0, 0.3, -0.2], rate = [0.0, 0.0, 0.0, -0.4, 0.1] }
[integrator]
method = "dp54"
[output]
every = 0.25
[effects.hinge_springs]
stiffness = [50.0, 50.0, 50.0, 2.0, 2.0]
damping = [1.0, 1.0, 1.0, 0.5, 0.5]
[effects.hinge_stops]
[[effects.hinge_stops.stop]]
hinge = "h4"
lower = 0.0
action = "latch"
"#;

#[test]
fn quick_sweep_writes_csv_svg_and_markdown() {
    let dir = temp_dir("ok");
    std::fs::write(dir.join("short.toml"), SCENE).unwrap();
    let o = satsim_in(&dir, &["accuracy", "short.toml", "--quick"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let out = dir.join("out/short-accuracy");
    let csv = std::fs::read_to_string(out.join("accuracy.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    // 2 RK4 steps + 3 adaptive methods x 2 tolerances.
    assert_eq!(rows.len(), 8, "{csv}");
    let mut methods = Vec::new();
    for r in &rows {
        assert_eq!(r.len(), header.len(), "{r:?}");
        assert_eq!(r[col("status")], "ok", "{r:?}");
        let err: f64 = r[col("err_final")].parse().unwrap();
        let rms: f64 = r[col("err_rms")].parse().unwrap();
        let secs: f64 = r[col("seconds")].parse().unwrap();
        let rhs: usize = r[col("rhs_evals")].parse().unwrap();
        assert!(err.is_finite() && err >= 0.0 && rms.is_finite() && secs > 0.0 && rhs > 0);
        // The quick sweep's tolerances (1e-4, 1e-7) and steps give errors well below 1e-2.
        assert!(err < 1e-2, "{r:?}");
        methods.push(r[col("method")]);
    }
    for m in ["rk4", "dp54", "dop853", "radau5"] {
        assert!(methods.contains(&m), "{methods:?}");
    }
    // Tighter tolerance, smaller error (DP5(4): 1e-4 then 1e-7).
    let dp: Vec<f64> = rows
        .iter()
        .filter(|r| r[col("method")] == "dp54")
        .map(|r| r[col("err_final")].parse().unwrap())
        .collect();
    assert!(dp[1] < dp[0], "{dp:?}");
    for svg in ["accuracy.svg", "accuracy_rhs.svg"] {
        let text = std::fs::read_to_string(out.join(svg)).unwrap();
        assert!(text.starts_with("<svg") && text.trim_end().ends_with("</svg>"));
        assert!(text.matches("<polyline").count() >= 4, "{svg}");
        assert!(text.contains("error at the final time"));
    }
    let md = std::fs::read_to_string(out.join("accuracy.md")).unwrap();
    assert!(md.contains("| DOP853 |") && md.contains("Floor"), "{md}");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("accuracy.csv"), "{stdout}");

    // --methods and --out.
    let o = satsim_in(
        &dir,
        &[
            "accuracy",
            "short.toml",
            "--quick",
            "--methods",
            "dp54",
            "--out",
            "only",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(dir.join("only/accuracy.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3, "{csv}");

    // --tolerances in place of the sweep's: those runs, at those tolerances.
    let o = satsim_in(
        &dir,
        &[
            "accuracy",
            "short.toml",
            "--quick",
            "--methods",
            "dp54,radau5",
            "--tolerances",
            "1e-5,1.5e-5,2e-6",
            "--out",
            "chosen",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(dir.join("chosen/accuracy.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let runs: Vec<(String, f64)> = lines
        .map(|l| {
            let r: Vec<&str> = l.split(',').collect();
            (
                r[col("method")].to_string(),
                r[col("tolerance")].parse().unwrap(),
            )
        })
        .collect();
    let mut expected = Vec::new();
    for m in ["dp54", "radau5"] {
        for t in [1e-5, 1.5e-5, 2e-6] {
            expected.push((m.to_string(), t));
        }
    }
    assert_eq!(runs, expected, "{csv}");
}

/// Exit status 2, nothing on stdout, the needles on stderr.
fn fails(o: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    assert!(o.stdout.is_empty());
    for n in needles {
        assert!(err.contains(n), "stderr `{err}` lacks `{n}`");
    }
}

#[test]
fn bad_input_exits_with_status_2() {
    let dir = temp_dir("bad");
    fails(
        &satsim_in(&dir, &["accuracy", "missing.toml", "--quick"]),
        &["missing.toml"],
    );
    std::fs::write(dir.join("broken.toml"), "duration = \n").unwrap();
    fails(
        &satsim_in(&dir, &["accuracy", "broken.toml", "--quick"]),
        &["broken.toml"],
    );
    std::fs::write(dir.join("short.toml"), SCENE).unwrap();
    fails(
        &satsim_in(&dir, &["accuracy", "short.toml", "--repeats", "0"]),
        &["--repeats"],
    );
    fails(
        &satsim_in(&dir, &["accuracy", "short.toml", "--methods", "euler"]),
        &["unknown integration method `euler`"],
    );
    for bad in ["0", "-1e-5", "1e-5,abc", "inf"] {
        let flag = format!("--tolerances={bad}");
        fails(
            &satsim_in(&dir, &["accuracy", "short.toml", &flag]),
            &["--tolerances"],
        );
    }
    fails(
        &satsim_in(&dir, &["accuracy"]),
        &["required arguments were not provided", "<SCENE.toml>"],
    );
    assert!(!dir.join("out").exists(), "nothing written on bad input");
}
