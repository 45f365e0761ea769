//! The command-line contract (`cli-contract.md` sections 3, 5 and 6), driven through the
//! built `satsim` binary.

use crate::common;
use common::{numbers, root};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn satsim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_satsim"))
        .args(args)
        .output()
        .expect("run satsim")
}

fn fixtures() -> PathBuf {
    root().join("tests/fixtures/pinocchio")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A fresh directory under the system's temporary directory.
fn temp_dir(test: &str) -> PathBuf {
    satsim_testkit::temp_dir(&format!("contract-{test}"))
}

fn matrix(v: &Value) -> Vec<Vec<f64>> {
    v.as_array().expect("array").iter().map(numbers).collect()
}

/// `|got - exp| <= 1e-10 * max(1, max |exp|)` entry by entry.
fn close(what: &str, got: &[f64], exp: &[f64]) {
    assert_eq!(got.len(), exp.len(), "{what}: length");
    let scale = exp.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for (i, (g, e)) in got.iter().zip(exp).enumerate() {
        assert!(
            (g - e).abs() <= 1e-10 * scale,
            "{what}[{i}]: {g:e} vs {e:e}"
        );
    }
}

/// Runs `dynamics` and parses its output, which must be one JSON object and nothing else.
fn dynamics(model: &Path, state: &Path) -> Value {
    let o = satsim(&[
        "dynamics",
        "--model",
        model.to_str().unwrap(),
        "--state",
        state.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "dynamics failed: {}", stderr(&o));
    assert!(stderr(&o).is_empty(), "stderr: {}", stderr(&o));
    serde_json::from_slice(&o.stdout).expect("one JSON object")
}

/// Compares a `dynamics` output with an expected file of the same schema.
fn compare(case: &str, got: &Value, exp: &Value) {
    assert_eq!(got["dof"], exp["dof"], "{case}: dof");
    let keys: Vec<&String> = got.as_object().unwrap().keys().collect();
    for k in [
        "dof",
        "mass_matrix",
        "bias",
        "acceleration",
        "kinetic_energy",
    ] {
        assert!(got.get(k).is_some(), "{case}: key {k} missing ({keys:?})");
    }
    let flat = |v: &Value| matrix(v).concat();
    close(
        &format!("{case}: mass_matrix"),
        &flat(&got["mass_matrix"]),
        &flat(&exp["mass_matrix"]),
    );
    close(
        &format!("{case}: bias"),
        &numbers(&got["bias"]),
        &numbers(&exp["bias"]),
    );
    close(
        &format!("{case}: acceleration"),
        &numbers(&got["acceleration"]),
        &numbers(&exp["acceleration"]),
    );
    close(
        &format!("{case}: kinetic_energy"),
        &[got["kinetic_energy"].as_f64().unwrap()],
        &[exp["kinetic_energy"].as_f64().unwrap()],
    );
}

/// `M * acceleration + bias = tau` (zero on the base, hinge torques after).
fn equation_holds(case: &str, out: &Value, state: &Path) {
    let m = matrix(&out["mass_matrix"]);
    let b = numbers(&out["bias"]);
    let a = numbers(&out["acceleration"]);
    let n = out["dof"].as_u64().unwrap() as usize;
    let s: Value = serde_json::from_str(&std::fs::read_to_string(state).unwrap()).unwrap();
    let torque = s["hinges"]
        .get("torque")
        .map(numbers)
        .unwrap_or_else(|| vec![0.0; n]);
    let mut tau = vec![0.0; n - torque.len()];
    tau.extend(torque);
    let scale = m
        .iter()
        .flatten()
        .chain(&b)
        .fold(1.0f64, |s, x| s.max(x.abs()));
    for i in 0..n {
        let lhs: f64 = (0..n).map(|j| m[i][j] * a[j]).sum::<f64>() + b[i];
        assert!(
            (lhs - tau[i]).abs() <= 1e-9 * scale,
            "{case}: row {i}: M a + b = {lhs:e}, tau = {:e}",
            tau[i]
        );
    }
}

fn expected(case: &str) -> Value {
    let text = std::fs::read_to_string(fixtures().join(format!("{case}.expected.json"))).unwrap();
    serde_json::from_str(&text).unwrap()
}

#[test]
fn dynamics_on_the_examples() {
    let model = root().join("examples/satellite.toml");
    let state = root().join("examples/state.json");
    let out = dynamics(&model, &state);
    compare("examples", &out, &expected("satellite"));
    equation_holds("examples", &out, &state);
    assert_eq!(out["dof"], 11);
}

#[test]
fn dynamics_on_every_fixture_case() {
    let mut cases: Vec<String> = std::fs::read_dir(fixtures())
        .unwrap()
        .filter_map(|e| {
            let n = e.ok()?.file_name().into_string().ok()?;
            n.strip_suffix(".expected.json").map(str::to_owned)
        })
        .collect();
    cases.sort();
    assert!(cases.len() >= 7, "{cases:?}");
    for case in cases {
        let state = fixtures().join(format!("{case}.state.json"));
        let out = dynamics(&fixtures().join(format!("{case}.model.toml")), &state);
        compare(&case, &out, &expected(&case));
        equation_holds(&case, &out, &state);
    }
}

#[test]
fn bench_prints_the_four_figures() {
    let model = root().join("examples/satellite.toml");
    let state = root().join("examples/state.json");
    for extra in [&[][..], &["--state", state.to_str().unwrap()][..]] {
        let mut args = vec!["bench", "--model", model.to_str().unwrap(), "--calls", "50"];
        args.extend_from_slice(extra);
        let o = satsim(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
        assert_eq!(v["dof"], 11);
        assert_eq!(v["calls"], 50);
        // The satellite has the unrolled kernel's layout: its figure is there too.
        for k in ["crba", "rnea", "aba", "crba_cholesky", "aba_unrolled"] {
            let x = v["ns_per_call"][k].as_f64().unwrap_or(-1.0);
            assert!(x > 0.0 && x.is_finite(), "{k}: {x}");
        }
    }
    // A model without that layout has no `aba_unrolled` key.
    let wings = root().join("examples/two_wings.toml");
    let o = satsim(&["bench", "--model", wings.to_str().unwrap(), "--calls", "50"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    assert!(v["ns_per_call"]["aba"].as_f64().is_some());
    assert!(v["ns_per_call"].get("aba_unrolled").is_none());
    let o = satsim(&["bench", "--model", model.to_str().unwrap(), "--calls", "0"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(o.stdout.is_empty());
}

#[test]
fn help_and_version() {
    for args in [&["--help"][..], &["help"][..]] {
        let o = satsim(args);
        assert!(o.status.success());
        let out = stdout(&o);
        for c in ["dynamics", "bench", "preprint", "run"] {
            assert!(out.contains(c), "{out}");
        }
    }
    let o = satsim(&["--version"]);
    assert!(o.status.success());
    assert!(stdout(&o).starts_with("satsim "));
}

/// Exit status 2, stdout empty, one message on stderr containing every `needles`.
fn fails(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    assert!(o.stdout.is_empty(), "stdout: {}", stdout(o));
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "stderr `{err}` lacks `{n}`");
    }
}

#[test]
fn usage_errors() {
    // `satsim` alone runs the default scene (tests/it/run.rs). The messages are clap's: the
    // problem naming the flag or command, then the command's usage.
    fails(
        &satsim(&["dynamics", "--state", "state.json"]),
        &[
            "required arguments were not provided",
            "--model <MODEL.toml>",
            "Usage: satsim dynamics",
        ],
    );
    fails(
        &satsim(&["dynamics", "--model"]),
        &["a value is required for '--model <MODEL.toml>'"],
    );
    fails(
        &satsim(&["dynamics", "--modle", "x"]),
        &["unexpected argument '--modle'", "'--model'"],
    );
    fails(
        &satsim(&["frobnicate"]),
        &["unrecognized subcommand 'frobnicate'"],
    );
    fails(&satsim(&["bench"]), &["--model <MODEL.toml>"]);
    fails(
        &satsim(&["bench", "--model", "m.toml", "--calls", "0"]),
        &["'--calls <N>'", "must be a whole number >= 1"],
    );
    fails(
        &satsim(&["preprint"]),
        &["--model <MODEL.toml>", "Usage: satsim preprint"],
    );
    fails(
        &satsim(&["accuracy"]),
        &["<SCENE.toml>", "Usage: satsim accuracy"],
    );
    fails(
        &satsim(&["run", "a.toml", "--out", "x", "--out", "y"]),
        &["'--out <DIR>' cannot be used multiple times"],
    );
}

/// `tests/fixtures/two_body.toml` (shared with the model reader's unit tests).
/// Line numbers: 4 bus, 9 panel, 14 hinge (name 15, parent 16, child 17, axis 18, at 19).
const MODEL: &str = include_str!("../../../../tests/fixtures/two_body.toml");

const STATE: &str = r#"{
  "base": {"attitude": [1, 0, 0, 0], "angular_velocity": [0.1, 0, 0], "velocity": [0, 0, 0]},
  "hinges": {"angle": [0.2], "rate": [0.3], "torque": [1.0]}
}
"#;

const EXTRA_BODY: &str =
    "\n[[body]]\nname = \"extra\"\nmass = 1.0\ninertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n";

fn extra_hinge(parent: &str, child: &str) -> String {
    format!(
        "\n[[hinge]]\nname = \"h2\"\nparent = \"{parent}\"\nchild = \"{child}\"\naxis = [0, 0, 1]\n"
    )
}

/// Runs `dynamics` on a model text and a state text written into `dir`.
fn dynamics_on(dir: &Path, name: &str, model: &str, state: &str) -> (Output, String, String) {
    let m = dir.join(format!("{name}.toml"));
    let s = dir.join(format!("{name}.json"));
    std::fs::write(&m, model).unwrap();
    std::fs::write(&s, state).unwrap();
    let (m, s) = (m.display().to_string(), s.display().to_string());
    (satsim(&["dynamics", "--model", &m, "--state", &s]), m, s)
}

#[test]
fn the_test_model_is_good() {
    let dir = temp_dir("good");
    let (o, _, _) = dynamics_on(&dir, "good", MODEL, STATE);
    assert!(o.status.success(), "{}", stderr(&o));
    // A fixed base ignores the state's `base` object.
    let fixed = MODEL.replace("\"free\"", "\"fixed\"");
    let (o, _, _) = dynamics_on(&dir, "fixed", &fixed, STATE);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["dof"], 1);
    // A massless leaf with inertia (a wheel rotor) is fine.
    let rotor = MODEL.replace("mass = 20.0", "mass = 0");
    let (o, _, _) = dynamics_on(&dir, "rotor", &rotor, STATE);
    assert!(o.status.success(), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn model_file_errors() {
    let dir = temp_dir("model");
    // (file name, model text, line, substring)
    let cases: Vec<(&str, String, Option<usize>, &str)> = vec![
        ("empty", String::new(), None, "empty"),
        (
            "syntax",
            MODEL.replace("mass = 20.0", "mass = = 20.0"),
            Some(11),
            "syntax error",
        ),
        (
            "missing_mass",
            MODEL.replace("mass = 20.0\n", ""),
            Some(9),
            "missing required key `mass`",
        ),
        (
            "missing_axis",
            MODEL.replace("axis = [1, 0, 0]\n", ""),
            Some(14),
            "missing required key `axis`",
        ),
        (
            "missing_inertia",
            MODEL.replace("inertia = [[1.7, 0, 0], [0, 6.7, 0], [0, 0, 8.3]]\n", ""),
            Some(9),
            "missing key `inertia`",
        ),
        (
            "intertia",
            MODEL.replace("inertia = [[1.7", "intertia = [[1.7"),
            Some(12),
            "unknown key `intertia`",
        ),
        (
            "wrong_type",
            MODEL.replace("mass = 20.0", "mass = \"heavy\""),
            Some(11),
            "invalid type",
        ),
        (
            "base_kind",
            MODEL.replace("\"free\"", "\"floating\""),
            Some(2),
            "unknown value `floating`",
        ),
        (
            "dup_body",
            MODEL.replace("name = \"panel\"", "name = \"bus\""),
            Some(10),
            "duplicate body name `bus`",
        ),
        (
            "dup_hinge",
            format!(
                "{MODEL}{EXTRA_BODY}{}",
                extra_hinge("bus", "extra").replace("\"h2\"", "\"h\"")
            ),
            Some(27),
            "duplicate hinge name `h`",
        ),
        (
            "unknown_parent",
            MODEL.replace("parent = \"bus\"", "parent = \"bsu\""),
            Some(16),
            "unknown parent body `bsu`",
        ),
        (
            "unknown_child",
            MODEL.replace("child = \"panel\"", "child = \"pannel\""),
            Some(17),
            "unknown child body `pannel`",
        ),
        (
            "cycle",
            format!(
                "{}{EXTRA_BODY}{}",
                MODEL.replace("parent = \"bus\"", "parent = \"extra\""),
                extra_hinge("panel", "extra")
            ),
            Some(10),
            "cycle",
        ),
        (
            "second_root",
            format!("{MODEL}{EXTRA_BODY}"),
            Some(22),
            "child of no hinge",
        ),
        (
            "two_parents",
            format!("{MODEL}{}", extra_hinge("bus", "panel")),
            Some(24),
            "two parents",
        ),
        (
            "negative_mass",
            MODEL.replace("mass = 20.0", "mass = -20.0"),
            Some(11),
            "negative",
        ),
        (
            "nan_mass",
            MODEL.replace("mass = 20.0", "mass = nan"),
            Some(11),
            "not finite",
        ),
        (
            "inf_vector",
            MODEL.replace("at = [0, 1, 0]", "at = [0, inf, 0]"),
            Some(19),
            "hinge `h`: at: value is not finite",
        ),
        (
            "asymmetric",
            MODEL.replace("[[1.7, 0, 0], [0, 6.7", "[[1.7, 0.5, 0], [0, 6.7"),
            Some(12),
            "not symmetric",
        ),
        (
            "not_psd",
            MODEL.replace("[0, 0, 8.3]]", "[0, 0, -8.3]]"),
            Some(12),
            "positive semi-definite",
        ),
        (
            "triangle",
            MODEL.replace("[0, 0, 8.3]]", "[0, 0, 9.3]]"),
            Some(12),
            "triangle inequality",
        ),
        (
            "axis_norm",
            MODEL.replace("axis = [1, 0, 0]", "axis = [2, 0, 0]"),
            Some(18),
            "axis norm 2",
        ),
        (
            "rotation_norm",
            MODEL.replace("at = [0, 1, 0]", "rotation = [0.5, 0, 0, 0]"),
            Some(19),
            "rotation quaternion norm",
        ),
        (
            "massless_leaf",
            MODEL
                .replace("mass = 20.0", "mass = 0")
                .replace("inertia = [[1.7, 0, 0], [0, 6.7, 0], [0, 0, 8.3]]\n", ""),
            Some(10),
            "zero mass and zero inertia",
        ),
    ];
    for (name, text, line, needle) in cases {
        let (o, m, _) = dynamics_on(&dir, name, &text, STATE);
        let at = match line {
            Some(l) => format!("{m}:{l}: "),
            None => format!("{m}: "),
        };
        fails(&o, &[&at, needle]);
        assert_eq!(
            stderr(&o).trim_end().lines().count(),
            1,
            "{name}: one line: {}",
            stderr(&o)
        );
    }
    // Unreadable: no such file.
    let missing = dir.join("missing.toml").display().to_string();
    let s = dir.join("missing.json");
    std::fs::write(&s, STATE).unwrap();
    let o = satsim(&[
        "dynamics",
        "--model",
        &missing,
        "--state",
        s.to_str().unwrap(),
    ]);
    fails(&o, &[&format!("{missing}: cannot read")]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn state_file_errors() {
    let dir = temp_dir("state");
    let cases: Vec<(&str, String, &str)> = vec![
        ("empty", "  \n".into(), ": the file is empty"),
        (
            "syntax",
            STATE.replace("\"rate\": [0.3],", "\"rate\": [0.3],,"),
            ":3: syntax error",
        ),
        (
            "unknown_key",
            STATE.replace("\"torque\"", "\"torques\""),
            ":3: unknown key `torques`",
        ),
        (
            "wrong_type",
            STATE.replace("[0.3]", "[\"fast\"]"),
            ":3: invalid type",
        ),
        (
            "missing_rate",
            STATE.replace("\"rate\": [0.3], ", ""),
            ":3: missing required key `rate`",
        ),
        (
            "angle_length",
            STATE.replace("[0.2]", "[0.2, 0.1]"),
            ": hinges.angle: expected 1 entries (one per hinge), got 2",
        ),
        (
            "rate_length",
            STATE.replace("[0.3]", "[]"),
            ": hinges.rate: expected 1 entries",
        ),
        (
            "torque_length",
            STATE.replace("[1.0]", "[1.0, 2.0, 3.0]"),
            ": hinges.torque: expected 1 entries",
        ),
        (
            "attitude_length",
            STATE.replace("[1, 0, 0, 0]", "[1, 0, 0]"),
            ": base.attitude: expected 4 entries",
        ),
        (
            "attitude_norm",
            STATE.replace("[1, 0, 0, 0]", "[1, 0.1, 0, 0]"),
            ": base.attitude: quaternion norm",
        ),
        (
            "velocity_length",
            STATE.replace("[0.1, 0, 0]", "[0.1, 0]"),
            ": base.angular_velocity: expected 3 entries",
        ),
    ];
    for (name, text, needle) in cases {
        let (o, _, s) = dynamics_on(&dir, name, MODEL, &text);
        fails(&o, &[&format!("{s}{needle}")]);
    }
    // The satellite's state given to a model with another number of hinges: names the state.
    let s = root().join("examples/state.json").display().to_string();
    let m = dir.join("one_hinge.toml");
    std::fs::write(&m, MODEL).unwrap();
    let o = satsim(&["dynamics", "--model", m.to_str().unwrap(), "--state", &s]);
    fails(
        &o,
        &[&format!(
            "{s}: hinges.angle: expected 1 entries (one per hinge), got 5"
        )],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `satsim preprint` (contract section 4): the five keys, 8 x 8 and 8 entries, closed form and
/// engine agreeing; and a clear refusal for a model without the preprint's layout.
#[test]
fn preprint_on_the_examples_and_a_refusal() {
    for (model, state) in [
        (
            root().join("examples/satellite.toml"),
            root().join("examples/state.json"),
        ),
        (
            fixtures().join("satellite_rotated.model.toml"),
            fixtures().join("satellite_rotated.state.json"),
        ),
    ] {
        let o = satsim(&[
            "preprint",
            "--model",
            model.to_str().unwrap(),
            "--state",
            state.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let v: Value = serde_json::from_str(&stdout(&o)).unwrap();
        let keys: Vec<&str> = v.as_object().unwrap().keys().map(|k| k.as_str()).collect();
        for k in [
            "S_closed_form",
            "N_closed_form",
            "S_tree",
            "N_tree",
            "max_abs_difference",
        ] {
            assert!(keys.contains(&k), "missing {k}");
        }
        let s_cf = matrix(&v["S_closed_form"]);
        let s_tree = matrix(&v["S_tree"]);
        assert_eq!(
            (s_cf.len(), s_cf[0].len(), numbers(&v["N_tree"]).len()),
            (8, 8, 8)
        );
        let mut worst = 0.0f64;
        for (a, b) in s_cf.iter().flatten().zip(s_tree.iter().flatten()) {
            worst = worst.max((a - b).abs());
        }
        for (a, b) in numbers(&v["N_closed_form"])
            .iter()
            .zip(numbers(&v["N_tree"]))
        {
            worst = worst.max((a - b).abs());
        }
        let reported = v["max_abs_difference"].as_f64().unwrap();
        assert_eq!(worst, reported);
        // Entries reach ~1.3e3 kg m²: 1e-9 absolute is 1e-12 relative.
        assert!(reported < 1e-9, "{reported}");
    }
    let o = satsim(&[
        "preprint",
        "--model",
        fixtures().join("tree_free.model.toml").to_str().unwrap(),
        "--state",
        fixtures().join("tree_free.state.json").to_str().unwrap(),
    ]);
    fails(&o, &["tree_free.model.toml", "preprint's layout"]);
}
