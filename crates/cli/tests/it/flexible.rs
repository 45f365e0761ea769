//! Flexible bodies in scenes (contract section 14): `satsim modes` of a cantilever on a fixed
//! base against the analytic frequencies, of a free bus with a beam between the clamped and
//! the free-free beam's, `[initial] flexible` and a state file's `flexible` (the run starts
//! there and vibrates at the analytic frequency), bad elastic states exit 2 naming file and
//! line, `dynamics` of a flexible model, and a campaign dispersing `EI` and `damping`.

use crate::common;
use common::{json, numbers, satsim_in};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Output;

/// `βₙL`, the roots of `cos x cosh x = −1` (Blevins, *Formulas for natural frequency and mode
/// shape*, table 8-1), and of `cos x cosh x = 1` (the free-free beam).
const BETA_L_CLAMPED: [f64; 3] = [
    1.875_104_068_711_961,
    4.694_091_132_974_175,
    7.854_757_438_237_613,
];
const BETA_L_FREE: [f64; 2] = [4.730_040_744_862_704, 7.853_204_624_095_838];

const L: f64 = 2.0;
const EI: f64 = 500.0;
const RHO_A: f64 = 5.0;

/// `(βₙL)² √(EI / (ρA L⁴)) / 2π` (Hz).
fn beam_hz(beta_l: f64, ei: f64) -> f64 {
    beta_l * beta_l * (ei / (RHO_A * L.powi(4))).sqrt() / (2.0 * std::f64::consts::PI)
}

/// A cantilever on a fixed base: the base body is the beam's clamp.
const CANTILEVER: &str = r#"[base]
kind = "fixed"

[[body]]
name = "beam"
mass = 1.0
inertia = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]
[body.flexible]
beam = { root = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], bend = [0.0, 0.0, 1.0],
         length = 2.0, EI = 500.0, rho_A = 5.0, modes = 3 }
damping = 0.0
"#;

/// A free bus carrying the same beam.
const BUS: &str = r#"[[body]]
name = "bus"
mass = 100.0
inertia = [[10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.0, 0.0, 10.0]]
[body.flexible]
beam = { root = [0.0, 0.5, 0.0], axis = [0.0, 1.0, 0.0], bend = [0.0, 0.0, 1.0],
         length = 2.0, EI = 500.0, rho_A = 5.0, modes = 2 }
"#;

fn setup(test: &str) -> PathBuf {
    let dir = satsim_testkit::temp_dir(&format!("flex-{test}"));
    std::fs::write(dir.join("cantilever.toml"), CANTILEVER).unwrap();
    std::fs::write(dir.join("bus.toml"), BUS).unwrap();
    dir
}

fn scene(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join(name), text).unwrap();
}

fn fails(o: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in: {err}");
    }
}

fn names(v: &Value) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_owned())
        .collect()
}

#[test]
fn a_cantilever_on_a_fixed_base_has_the_analytic_frequencies() {
    let dir = setup("cantilever");
    scene(
        &dir,
        "c.toml",
        "model = \"cantilever.toml\"\nduration = 1.0\n",
    );
    let lin = json(&satsim_in(&dir, &["linearize", "c.toml"]));
    let states = names(&lin["states"]);
    assert_eq!(
        states,
        [
            "eta_beam_1",
            "eta_beam_2",
            "eta_beam_3",
            "etadot_beam_1",
            "etadot_beam_2",
            "etadot_beam_3"
        ]
    );
    let v = json(&satsim_in(&dir, &["modes", "c.toml"]));
    let f = numbers(&v["frequencies_hz"]);
    assert_eq!(f.len(), 3, "{v}");
    for (k, bl) in BETA_L_CLAMPED.iter().enumerate() {
        let exact = beam_hz(*bl, EI);
        assert!(
            (f[k] - exact).abs() < 1e-6 * exact,
            "mode {}: {} vs {exact}",
            k + 1,
            f[k]
        );
        // Mode k moves its own modal coordinate only: the shape is that coordinate.
        let shape = &v["modes"][k]["shape"];
        for j in 1..=3 {
            let s = shape[format!("eta_beam_{j}")].as_f64().unwrap();
            let expected = if j == k + 1 { 1.0 } else { 0.0 };
            assert!(
                (s - expected).abs() < 1e-9,
                "mode {} eta_beam_{j} = {s}",
                k + 1
            );
        }
    }
    assert_eq!(v["rigid_modes"], 0);
}

/// `satsim modes` and `satsim linearize` integrate nothing: a fixed RK4 step too long for
/// the modes refuses the run, not the list of the modes that says which step would do.
#[test]
fn modes_and_linearize_take_a_scene_whose_rk4_step_is_too_long_for_its_modes() {
    let dir = setup("rk4-modes");
    let text = "model = \"cantilever.toml\"\nduration = 1.0\n[integrator]\nmethod = \"rk4\"\nstep = 0.03\n[output]\nevery = 0.1\n";
    scene(&dir, "c.toml", text);
    // The third mode, 2π × 24.5 Hz, takes rk4 only up to 2√2/ω = 18.3 ms.
    fails(
        &satsim_in(&dir, &["run", "c.toml", "--out", "o"]),
        &["too long for rk4", "body `beam`'s mode 3"],
    );
    let v = json(&satsim_in(&dir, &["modes", "c.toml"]));
    let f = numbers(&v["frequencies_hz"]);
    let third = beam_hz(BETA_L_CLAMPED[2], EI);
    assert!((f[2] - third).abs() < 1e-6 * third, "{f:?}");
    assert!(2.0 * std::f64::consts::PI * f[2] * 0.03 > 2.0 * std::f64::consts::SQRT_2);
    let lin = json(&satsim_in(&dir, &["linearize", "c.toml"]));
    assert_eq!(names(&lin["states"]).len(), 6, "{lin}");
}

#[test]
fn a_free_bus_with_a_beam_vibrates_above_the_clamped_beam() {
    let dir = setup("bus");
    scene(&dir, "b.toml", "model = \"bus.toml\"\nduration = 1.0\n");
    let v = json(&satsim_in(&dir, &["modes", "b.toml"]));
    let f = numbers(&v["frequencies_hz"]);
    // Attitude and angular velocity: three double zeros; velocity: three simple ones; two
    // elastic modes.
    assert_eq!(v["rigid_modes"], 9, "{v}");
    assert_eq!(f.len(), 2, "{v}");
    // Between the beam clamped to an infinite mass and the free-free beam (a massless bus).
    for k in 0..2 {
        let (lo, hi) = (beam_hz(BETA_L_CLAMPED[k], EI), beam_hz(BETA_L_FREE[k], EI));
        assert!(
            f[k] > lo * (1.0 + 1e-3) && f[k] < hi,
            "mode {}: {} not in ({lo}, {hi})",
            k + 1,
            f[k]
        );
    }
    let shape = &v["modes"][0]["shape"];
    assert!(shape.get("eta_bus_1").is_some() && shape.get("etadot_bus_2").is_some());
}

/// The trajectory's header and rows.
fn trajectory(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

#[test]
fn the_initial_elastic_state_starts_the_run_and_the_mode_vibrates_at_its_frequency() {
    let dir = setup("initial");
    let body = "model = \"cantilever.toml\"\nduration = 2.0\n[integrator]\nrtol = 1e-11\natol = 1e-14\n[output]\nevery = 0.05\nplots = false\n";
    scene(
        &dir,
        "toml.toml",
        &format!("{body}[initial]\nflexible = {{ beam = {{ eta = [0.01, 0.0, 0.0] }} }}\n"),
    );
    std::fs::write(
        dir.join("state.json"),
        r#"{"flexible": {"beam": {"eta": [0.01, 0.0, 0.0], "etadot": [0.0, 0.0, 0.0]}}}"#,
    )
    .unwrap();
    scene(
        &dir,
        "json.toml",
        &format!("initial = \"state.json\"\n{body}"),
    );
    let w1 = 2.0 * std::f64::consts::PI * beam_hz(BETA_L_CLAMPED[0], EI);
    let mut finals = Vec::new();
    for s in ["toml", "json"] {
        let o = satsim_in(&dir, &["run", &format!("{s}.toml"), "--out", s]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let (h, rows) = trajectory(&dir.join(s).join("trajectory.csv"));
        let col = |n: &str| {
            h.iter()
                .position(|c| c == n)
                .unwrap_or_else(|| panic!("{n} in {h:?}"))
        };
        let (e1, e2, tip) = (col("eta_beam_1"), col("eta_beam_2"), col("tip_beam"));
        col("etadot_beam_3");
        for r in &rows {
            // Fixed base, at rest: the modes are uncoupled, η₁ = 0.01 cos ω₁t.
            let exact = 0.01 * (w1 * r[0]).cos();
            assert!(
                (r[e1] - exact).abs() < 1e-7,
                "t = {}: {} vs {exact}",
                r[0],
                r[e1]
            );
            assert!(r[e2].abs() < 1e-9);
            // φ₁(L) = 2 / √(ρA L) for a mass-normalised uniform cantilever.
            let tip_exact = 2.0 / (RHO_A * L).sqrt() * r[e1];
            assert!(
                (r[tip] - tip_exact).abs() < 1e-9,
                "{} vs {tip_exact}",
                r[tip]
            );
        }
        finals.push(rows.last().unwrap().clone());
        // The view draws the beam, with its modal coordinates in the kept poses.
        let view: Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join(s).join("view.json")).unwrap())
                .unwrap();
        assert_eq!(view["beams"][0]["shapes"].as_array().unwrap().len(), 3);
        let poses = std::fs::read_to_string(dir.join(s).join("poses.csv")).unwrap();
        assert!(
            poses
                .lines()
                .next()
                .unwrap()
                .ends_with(",eta_beam_1,eta_beam_2,eta_beam_3")
        );
    }
    assert_eq!(finals[0], finals[1]);
}

#[test]
fn bad_elastic_states_exit_2_naming_file_and_line() {
    let dir = setup("bad");
    for (initial, needles) in [
        (
            "flexible = { panel = { eta = [0.0] } }",
            vec!["bad.toml:4", "panel", "no body"],
        ),
        (
            "flexible = { beam = { eta = [0.0, 1.0] } }",
            vec![
                "bad.toml:4",
                "initial.flexible.beam.eta: expected 3 values, one per mode of body `beam`, got 2 (mode 3 has none)",
            ],
        ),
        (
            "flexible = { beam = { etadot = [0.0, nan, 0.0] } }",
            vec![
                "bad.toml:4",
                "initial.flexible.beam.etadot: body `beam`'s mode 2 is NaN: values must be finite",
            ],
        ),
        (
            "flexible = { beam = { eta = [0.0, 0.0, 0.0], speed = 1 } }",
            vec!["bad.toml:4", "speed"],
        ),
    ] {
        scene(
            &dir,
            "bad.toml",
            &format!("model = \"cantilever.toml\"\nduration = 1.0\n[initial]\n{initial}\n"),
        );
        fails(&satsim_in(&dir, &["run", "bad.toml"]), &needles);
        fails(&satsim_in(&dir, &["modes", "bad.toml"]), &needles);
    }
    // A body that is not flexible.
    scene(
        &dir,
        "rigid.toml",
        "duration = 1.0\n[model]\n[[model.body]]\nname = \"bus\"\nmass = 1.0\ninertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]\n[initial]\n\nflexible = { bus = { eta = [0.0] } }\n",
    );
    fails(
        &satsim_in(&dir, &["run", "rigid.toml"]),
        &["rigid.toml:9", "flexible.bus", "not flexible"],
    );
    // In a JSON state file, at the body's line of the file.
    std::fs::write(
        dir.join("s.json"),
        "{\n  \"flexible\": {\n    \"beam\": {\"eta\": [1.0]}\n  }\n}\n",
    )
    .unwrap();
    scene(
        &dir,
        "j.toml",
        "model = \"cantilever.toml\"\ninitial = \"s.json\"\nduration = 1.0\n",
    );
    fails(
        &satsim_in(&dir, &["run", "j.toml"]),
        &["s.json:3", "expected 3 values"],
    );
    // `dynamics` takes the same state file: the elastic coordinates after the hinge rates.
    std::fs::write(
        dir.join("bent.json"),
        "{\"flexible\": {\"beam\": {\"eta\": [0.01, -0.002, 0.0005], \"etadot\": [0.1, 0.0, 0.0]}}}",
    )
    .unwrap();
    let o = satsim_in(
        &dir,
        &[
            "dynamics",
            "--model",
            "cantilever.toml",
            "--state",
            "bent.json",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let d = json(&o);
    assert_eq!(d["dof"], 3);
    // A cantilever's mass matrix is the identity (mass-normalised modes); at eta its bias
    // holds omega_k^2 eta_k and the damping (none here), so a = -omega^2 eta.
    let m = d["mass_matrix"].as_array().unwrap();
    for (i, row) in m.iter().enumerate() {
        for (j, x) in numbers(row).iter().enumerate() {
            assert!(
                (x - f64::from(u8::from(i == j))).abs() < 1e-12,
                "{i} {j}: {x}"
            );
        }
    }
    let eta = [0.01, -0.002, 0.0005];
    for (k, (a, b)) in numbers(&d["acceleration"])
        .iter()
        .zip(numbers(&d["bias"]))
        .enumerate()
    {
        let w = 2.0 * std::f64::consts::PI * beam_hz(BETA_L_CLAMPED[k], EI);
        assert!((b / (w * w * eta[k]) - 1.0).abs() < 1e-6, "mode {k}: {b}");
        assert!((a + b).abs() < 1e-9 * b.abs(), "mode {k}: {a} {b}");
    }
    let t = d["kinetic_energy"].as_f64().unwrap();
    assert!((t - 0.5 * 0.1 * 0.1).abs() < 1e-15, "{t}");
    // A wrong number of values is an error at the file's line.
    fails(
        &satsim_in(
            &dir,
            &[
                "dynamics",
                "--model",
                "cantilever.toml",
                "--state",
                "s.json",
            ],
        ),
        &["s.json:3", "flexible.beam.eta: expected 3 values"],
    );
    // `preprint` and `bench` evaluate the rigid algorithms: they refuse it, at its line.
    fails(
        &satsim_in(&dir, &["bench", "--model", "cantilever.toml"]),
        &[
            "cantilever.toml:8",
            "flexible",
            "satsim bench",
            "rigid models only",
        ],
    );
}

/// Final, minimum and maximum of every column but `t` of a trajectory CSV.
fn trajectory_stats(path: &Path) -> (Vec<String>, Vec<[f64; 3]>) {
    let (header, rows) = trajectory(path);
    let mut stats = vec![[f64::NAN, f64::INFINITY, f64::NEG_INFINITY]; header.len() - 1];
    for r in rows {
        for (c, v) in r.iter().skip(1).enumerate() {
            stats[c] = [*v, stats[c][1].min(*v), stats[c][2].max(*v)];
        }
    }
    (header[1..].to_vec(), stats)
}

#[test]
fn a_campaign_disperses_ei_and_damping_and_each_row_is_satsim_run_of_its_scene() {
    let dir = setup("campaign");
    let base = "duration = 1.0\n[initial]\nflexible = { beam = { eta = [0.01, 0.0, 0.0] } }\n[integrator]\nmethod = \"rk4\"\nstep = 0.002\n[output]\nevery = 0.1\nplots = false\n";
    let campaign = "[campaign]\nruns = 4\nseed = 7\n[[campaign.disperse]]\nkey = \"model.body.0.flexible.beam.EI\"\nscale = { sigma = 0.2 }\n[[campaign.disperse]]\nkey = \"model.body.0.flexible.damping\"\nuniform = { low = 0.0, high = 0.05 }\n";
    // `satsim campaign NAME.toml --out NAME` of the cantilever with `start` (the scene's
    // settings and initial state) and the campaign above.
    let run_campaign = |name: &str, start: &str| {
        scene(
            &dir,
            &format!("{name}.toml"),
            &format!("model = \"cantilever.toml\"\n{start}{campaign}"),
        );
        let file = format!("{name}.toml");
        satsim_in(&dir, &["campaign", &file, "--out", name, "--threads", "2"])
    };
    let o = run_campaign("c", base);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(dir.join("c/runs.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let mut frequencies = Vec::new();
    for line in text.lines().skip(1) {
        let r: Vec<&str> = line.split(',').collect();
        let (k, ei, zeta) = (r[0], r[1], r[2]);
        // The scene with this run's values written in by hand.
        let model = CANTILEVER
            .replace("EI = 500.0", &format!("EI = {ei}"))
            .replace("damping = 0.0", &format!("damping = {zeta}"));
        assert_ne!(model, CANTILEVER);
        std::fs::write(dir.join(format!("model{k}.toml")), model).unwrap();
        scene(
            &dir,
            &format!("run{k}.toml"),
            &format!("model = \"model{k}.toml\"\n{base}"),
        );
        let out = format!("run{k}");
        let o = satsim_in(&dir, &["run", &format!("run{k}.toml"), "--out", &out]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let (cols, stats) = trajectory_stats(&dir.join(&out).join("trajectory.csv"));
        assert!(cols.iter().any(|c| c == "eta_beam_1"));
        for (c, name) in cols.iter().enumerate() {
            for (s, prefix) in ["final_", "min_", "max_"].iter().enumerate() {
                let h = format!("{prefix}{name}");
                let i = header.iter().position(|x| *x == h).unwrap();
                let campaign: f64 = r[i].parse().unwrap();
                assert_eq!(campaign.to_bits(), stats[c][s].to_bits(), "run {k} {h}");
            }
        }
        // The drawn EI and damping are the run's: its modes say so.
        let v = json(&satsim_in(&dir, &["modes", &format!("run{k}.toml")]));
        let (ei, zeta): (f64, f64) = (ei.parse().unwrap(), zeta.parse().unwrap());
        // The undamped frequency |λ| / 2π (`frequencies_hz` is the damped one, Im λ / 2π).
        let lambda = &v["modes"][0]["eigenvalue"];
        let f1 = lambda[0]
            .as_f64()
            .unwrap()
            .hypot(lambda[1].as_f64().unwrap())
            / (2.0 * std::f64::consts::PI);
        let exact = beam_hz(BETA_L_CLAMPED[0], ei);
        assert!(
            (f1 - exact).abs() < 1e-6 * exact,
            "run {k}: {f1} vs {exact}"
        );
        let z1 = v["damping_ratios"][0].as_f64().unwrap();
        assert!((z1 - zeta).abs() < 1e-6, "run {k}: {z1} vs {zeta}");
        frequencies.push(f1);
    }
    assert_eq!(frequencies.len(), 4);
    for (a, b) in frequencies.iter().zip(&frequencies[1..]) {
        assert!((a - b).abs() > 1e-3 * a, "{frequencies:?}");
    }
    // The column before the last (`stability_held`): each run's largest tip over every step
    // as a fraction of the 2 m, about the 6.3 mm it starts at (0.3 %); no warning.
    let p = header.len() - 2;
    assert_eq!(header[p], "peak_deflection_beam");
    assert_eq!(header[p + 1], "stability_held");
    for line in text.lines().skip(1) {
        let peak: f64 = line.split(',').nth(p).unwrap().parse().unwrap();
        assert!(peak > 0.002 && peak < 0.005, "{peak}");
    }
    assert!(!String::from_utf8_lossy(&o.stderr).contains("warning"));
    // Started bent by 0.25 m (12.6 % of the length), every run is past a tenth, and the
    // campaign says so after it.
    let bent = base.replace("eta = [0.01, 0.0, 0.0]", "eta = [0.4, 0.0, 0.0]");
    assert_ne!(bent, base);
    let o = run_campaign("b", &bent);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("warning: 4 of the 4 finished runs bent a flexible body past a tenth of its length at some step (a beam's tip, or a modes file's node for its distance from the body's frame): beyond what its modal model holds"),
        "{err}"
    );
}

/// A model file in a folder of its own finds its `modes_file` beside it (relative to the
/// model file's folder) in a plain run, under `--set` and in a campaign, which read the
/// model in as an inline table of the scene: the same trajectory each way.
#[test]
fn a_modes_file_beside_its_model_is_found_under_set_and_in_a_campaign() {
    let dir = setup("modes-file-folder");
    std::fs::create_dir_all(dir.join("models")).unwrap();
    std::fs::copy(
        common::root().join("examples/modes/panel_beam_modes.toml"),
        dir.join("models/panel.toml"),
    )
    .unwrap();
    let model = "[base]\nkind = \"fixed\"\n[[body]]\nname = \"panel\"\nmass = 1.0\ninertia = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]\n[body.flexible]\nmodes_file = \"panel.toml\"\ndamping = 0.01\n";
    std::fs::write(dir.join("models/panel_model.toml"), model).unwrap();
    let base = "model = \"models/panel_model.toml\"\nduration = 0.5\n[initial]\nflexible = { panel = { eta = [0.01, 0.0, 0.0] } }\n[output]\nevery = 0.1\nplots = false\nview = false\n";
    scene(&dir, "s.toml", base);
    let plain = satsim_in(&dir, &["run", "s.toml", "--out", "plain"]);
    assert!(
        plain.status.success(),
        "{}",
        String::from_utf8_lossy(&plain.stderr)
    );
    let set = satsim_in(
        &dir,
        &[
            "run",
            "s.toml",
            "--out",
            "set",
            "--set",
            "model.body.0.mass=1.0",
        ],
    );
    assert!(
        set.status.success(),
        "{}",
        String::from_utf8_lossy(&set.stderr)
    );
    let read = |d: &str| std::fs::read_to_string(dir.join(d).join("trajectory.csv")).unwrap();
    assert_eq!(read("plain"), read("set"));
    scene(
        &dir,
        "c.toml",
        &format!(
            "{base}[campaign]\nruns = 2\nseed = 1\n[[campaign.disperse]]\nkey = \"model.body.0.flexible.damping\"\nuniform = {{ low = 0.0, high = 0.02 }}\n"
        ),
    );
    let c = satsim_in(&dir, &["campaign", "c.toml", "--out", "c"]);
    assert!(c.status.success(), "{}", String::from_utf8_lossy(&c.stderr));
    let runs = std::fs::read_to_string(dir.join("c/runs.csv")).unwrap();
    let header: Vec<&str> = runs.lines().next().unwrap().split(',').collect();
    let status = header.iter().position(|h| *h == "status").unwrap();
    assert_eq!(runs.lines().count(), 3, "{runs}");
    for l in runs.lines().skip(1) {
        assert_eq!(l.split(',').nth(status), Some("ok"), "{runs}");
    }
}
