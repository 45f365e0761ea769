//! Command-line conveniences of issue 12 item 4: `--set KEY=VALUE` on `run` and `campaign`,
//! `DIR/events.csv`, a missing `model` file reported at the scene's line.

use crate::common;
use common::{root, satsim_in};
use std::path::{Path, PathBuf};
use std::process::Output;

fn setup(test: &str) -> PathBuf {
    let dir = satsim_testkit::temp_dir_with(
        &format!("cliux-{test}"),
        &["examples/satellite.toml", "examples/state.json"],
    );
    std::fs::write(dir.join("scene.toml"), SCENE).unwrap();
    dir
}

const SCENE: &str = r#"model = "satellite.toml"
initial = "state.json"
duration = 4.0
[integrator]
method = "rk4"
step = 0.01
[output]
every = 1.0
plots = false
[effects.hinge_springs]
stiffness = [50.0, 50.0, 50.0, 2.0, 2.0]
damping = [1.0, 1.0, 1.0, 0.5, 0.5]
"#;

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn last_row(path: &Path) -> (Vec<String>, Vec<f64>) {
    let text = std::fs::read_to_string(path).unwrap();
    let header = text.lines().next().unwrap().split(',').map(String::from);
    let last = text.lines().last().unwrap();
    (
        header.collect(),
        last.split(',').map(|v| v.parse().unwrap()).collect(),
    )
}

#[test]
fn set_overrides_scene_model_and_state_values() {
    let dir = setup("set");
    let base = satsim_in(&dir, &["run", "scene.toml", "--out", "base"]);
    assert!(base.status.success(), "{}", stderr(&base));
    let (header, b) = last_row(&dir.join("base/trajectory.csv"));
    assert_eq!(b[0], 4.0);
    let o = satsim_in(
        &dir,
        &[
            "run",
            "scene.toml",
            "--out",
            "set",
            "--set",
            "duration=2",
            "--set=effects.hinge_springs.stiffness.0=500.0",
            "--set",
            "model.body.1.mass=40.0",
            "--set",
            "integrator.method=dp54",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, s) = last_row(&dir.join("set/trajectory.csv"));
    // `duration` (an integer given for a number) took effect.
    assert_eq!(s[0], 2.0);
    // The same scene run to 2 s without the spring, mass and method overrides differs.
    let plain = satsim_in(
        &dir,
        &[
            "run",
            "scene.toml",
            "--out",
            "plain",
            "--set",
            "duration=2.0",
        ],
    );
    assert!(plain.status.success(), "{}", stderr(&plain));
    let (_, p) = last_row(&dir.join("plain/trajectory.csv"));
    let a1 = header.iter().position(|c| c == "angle_1").unwrap_or(1);
    assert!(
        (s[a1] - p[a1]).abs() > 1e-6,
        "overrides changed nothing: {} vs {}",
        s[a1],
        p[a1]
    );
}

#[test]
fn bad_set_exits_2_naming_the_key() {
    let dir = setup("badset");
    for (arg, why) in [
        (
            "effects.hinge_springs.stifness=3.0",
            "unknown key `stifness`",
        ),
        ("model.body.99.mass=1.0", "out of range"),
        ("duration=\"long\"", "wrong type"),
        ("effects.hinge_springs.stiffness=5.0", "wrong type"),
        ("integrator.step=fast", "not a TOML value"),
    ] {
        let o = satsim_in(&dir, &["run", "scene.toml", "--set", arg]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{arg}: {err}");
        assert!(err.contains(why), "{arg}: {err}");
        let key = arg.split_once('=').unwrap().0;
        assert!(err.contains(key), "{arg}: {err} does not name the key");
        assert!(err.contains("scene.toml"), "{arg}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    }
    // Not KEY=VALUE.
    let o = satsim_in(&dir, &["run", "scene.toml", "--set", "duration"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("KEY=VALUE"), "{}", stderr(&o));
    // A value the scene reader refuses names the scene file and the override.
    let o = satsim_in(&dir, &["run", "scene.toml", "--set", "duration=-1.0"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("duration") && err.contains("--set duration=-1.0"),
        "{err}"
    );
}

#[test]
fn campaign_takes_set_too() {
    let dir = setup("campaign");
    let scene = format!(
        "{SCENE}[campaign]\nruns = 5\nseed = 3\n[[campaign.disperse]]\nkey = \"model.body.1.mass\"\nscale = {{ sigma = 0.05 }}\n"
    );
    std::fs::write(dir.join("c.toml"), scene).unwrap();
    let o = satsim_in(
        &dir,
        &[
            "campaign",
            "c.toml",
            "--out",
            "camp",
            "--threads",
            "1",
            "--set",
            "campaign.runs=2",
            "--set",
            "duration=1.0",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let runs = std::fs::read_to_string(dir.join("camp/runs.csv")).unwrap();
    assert_eq!(runs.lines().count(), 3, "{runs}");
    let o = satsim_in(&dir, &["campaign", "c.toml", "--set", "campaign.run=2"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("campaign.run"), "{}", stderr(&o));
}

#[test]
fn every_event_goes_to_events_csv() {
    // two_wings.toml with a livelier elbow stop has more events than the ten the summary
    // prints (19: two latches, then rebounds until the elbow comes to rest).
    let dir = setup("events");
    let scene = root().join("examples/scenes/two_wings.toml");
    let o = satsim_in(
        &dir,
        &[
            "run",
            scene.to_str().unwrap(),
            "--out",
            "ev",
            "--set",
            "effects.hinge_stops.stop.2.restitution=0.7",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let shown = out.lines().filter(|l| l.starts_with("  event ")).count();
    let more: usize = out
        .lines()
        .find_map(|l| {
            l.trim()
                .strip_prefix("...")?
                .trim()
                .strip_suffix(" more events")
        })
        .map_or(0, |n| n.parse().unwrap());
    assert_eq!(shown, 10, "{out}");
    assert!(more > 0, "{out}");
    let text = std::fs::read_to_string(dir.join("ev/events.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,effect,event"));
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), shown + more, "{text}");
    let mut last_t = f64::NEG_INFINITY;
    for r in &rows {
        let (t, rest) = r.split_once(',').unwrap();
        let t: f64 = t.parse().unwrap();
        assert!(t >= last_t, "events out of order: {text}");
        last_t = t;
        let effect = rest.split_once(',').unwrap().0;
        assert!(
            ["hinge_stops", "reaction_wheels"].contains(&effect),
            "{effect} in {text}"
        );
    }
    // The first ten match the summary.
    for (line, row) in out.lines().filter(|l| l.starts_with("  event ")).zip(&rows) {
        let what = line.split_once(" s: ").unwrap().1;
        assert!(row.contains(what.trim_matches('"')), "{line} vs {row}");
    }
}

#[test]
fn a_missing_model_file_is_reported_at_the_scene_line() {
    let dir = setup("missing");
    std::fs::write(
        dir.join("bad.toml"),
        SCENE.replace("model = \"satellite.toml\"", "model = \"satelite.toml\""),
    )
    .unwrap();
    let o = satsim_in(&dir, &["run", "bad.toml"]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("bad.toml:1:"), "{err}");
    assert!(
        err.contains("satelite.toml") && err.contains("does not exist"),
        "{err}"
    );
    std::fs::write(
        dir.join("bad2.toml"),
        SCENE.replace("initial = \"state.json\"", "initial = \"nostate.json\""),
    )
    .unwrap();
    let o = satsim_in(&dir, &["run", "bad2.toml", "--set", "duration=1.0"]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(
        err.contains("nostate.json") && err.contains("does not exist"),
        "{err}"
    );
    assert!(err.contains("bad2.toml:2:"), "{err}");
}

#[test]
fn an_orbit_below_100_km_is_refused_with_a_units_hint() {
    let dir = setup("altitude");
    let orbit = |o: &str| format!("{SCENE}[orbit]\n{o}\n");
    // Line 13 is the first line of [orbit]; line 14 its first key.
    for (name, o, at, hint) in [
        (
            "km.toml",
            "altitude = 500",
            "km.toml:14:",
            "altitude = 500e3",
        ),
        (
            "low.toml",
            "altitude = 99e3",
            "low.toml:14:",
            "below 100 km",
        ),
        (
            "sma.toml",
            "semi_major_axis = 6400e3",
            "sma.toml:13:",
            "in metres",
        ),
        (
            "pos.toml",
            "position = [6400e3, 0, 0]\nvelocity = [0, 7.8e3, 0]",
            "pos.toml:13:",
            "in metres",
        ),
    ] {
        std::fs::write(dir.join(name), orbit(o)).unwrap();
        let out = satsim_in(&dir, &["run", name]);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(at) && err.contains(hint), "{name}: {err}");
        assert!(err.contains("100 km"), "{name}: {err}");
    }
    // 100 km itself and the usual 500 km are fine.
    std::fs::write(
        dir.join("ok.toml"),
        orbit("altitude = 100e3").replace("duration = 4.0", "duration = 1.0"),
    )
    .unwrap();
    let out = satsim_in(&dir, &["run", "ok.toml"]);
    assert!(out.status.success(), "{}", stderr(&out));
}

#[test]
fn a_nearly_unit_attitude_is_normalised_with_a_warning() {
    let dir = setup("quat");
    let state = |q: &str| {
        format!(
            "{{\"base\": {{\"attitude\": {q}}}, \"hinges\": {{\"angle\": [0, 0, 0, 0, 0], \"rate\": [0, 0, 0, 0, 0]}}}}"
        )
    };
    std::fs::write(dir.join("state.json"), state("[1.0005, 0, 0, 0]")).unwrap();
    let o = satsim_in(&dir, &["run", "scene.toml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("warning:") && err.contains("state.json") && err.contains("normalised"),
        "{err}"
    );
    // With --set the state is read into the scene: the warning names the state file, no line.
    let o = satsim_in(
        &dir,
        &["run", "scene.toml", "--set", "duration=1.0", "--out", "s"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("warning: state.json (with --set): initial.base.attitude"),
        "{err}"
    );
    let (header, row) = last_row(&dir.join("out/scene/trajectory.csv"));
    let q: Vec<f64> = ["q_w", "q_x", "q_y", "q_z"]
        .iter()
        .map(|c| row[header.iter().position(|h| h == c).unwrap()])
        .collect();
    let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!((norm - 1.0).abs() < 1e-9, "{norm}");
    // Every command that reads a scene says so, not only `run`.
    for command in ["linearize", "modes"] {
        let o = satsim_in(&dir, &[command, "scene.toml"]);
        assert!(o.status.success(), "{command}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(
            err.contains("warning:") && err.contains("normalised"),
            "{command}: {err}"
        );
    }
    std::fs::write(dir.join("state.json"), state("[1.01, 0, 0, 0]")).unwrap();
    let o = satsim_in(&dir, &["run", "scene.toml"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("within 1e-3"), "{}", stderr(&o));
}

/// `--help` for every command lists each of its flags (with a value name and, where there is
/// one, the default); `satsim help COMMAND` says the same; `--version` the version.
#[test]
fn every_command_has_a_complete_help() {
    let dir = setup("help");
    for (command, needles) in [
        (
            "dynamics",
            &["--model <MODEL.toml>", "--state <STATE.json>"][..],
        ),
        (
            "bench",
            &[
                "--model <MODEL.toml>",
                "--state <STATE.json>",
                "--calls <N>",
                "about 1.5 s",
            ][..],
        ),
        (
            "preprint",
            &["--model <MODEL.toml>", "--state <STATE.json>"][..],
        ),
        (
            "run",
            &[
                "<SCENE.toml>",
                "--out <DIR>",
                "[default: out/<scene stem>]",
                "--set <KEY=VALUE>",
            ][..],
        ),
        (
            "accuracy",
            &[
                "<SCENE.toml>",
                "--out <DIR>",
                "--repeats <N>",
                "--methods <LIST>",
                "--quick",
            ][..],
        ),
        (
            "campaign",
            &[
                "<SCENE.toml>",
                "--threads <T>",
                "[default: all cores]",
                "--shard <I/N>",
                "--shards <N>",
                "--resume",
                "--set <KEY=VALUE>",
                "merge",
            ][..],
        ),
        ("linearize", &["<SCENE.toml>"][..]),
        (
            "modes",
            &[
                "<SCENE.toml>",
                "--along <HINGE=FROM:TO[:N][,...]>",
                "--plot <FILE.svg>",
            ][..],
        ),
        (
            "view",
            &["<DIR>", "--out <FILE>", "[default: DIR/view.html]"][..],
        ),
        (
            "plot",
            &[
                "<CSV>",
                "--columns <A,B,...>",
                "--from <T>",
                "--to <T>",
                "-o, --out <OUT.svg>",
            ][..],
        ),
        ("completions", &["<SHELL>", "bash", "zsh", "fish"][..]),
    ] {
        let o = satsim_in(&dir, &[command, "--help"]);
        assert!(o.status.success(), "{command}: {}", stderr(&o));
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(out.contains(&format!("Usage: satsim {command}")), "{out}");
        for n in needles {
            assert!(
                out.contains(n),
                "`satsim {command} --help` lacks `{n}`:\n{out}"
            );
        }
        let o = satsim_in(&dir, &["help", command]);
        assert!(o.status.success());
        assert_eq!(String::from_utf8_lossy(&o.stdout), out, "{command}");
    }
    let o = satsim_in(&dir, &["campaign", "merge", "--help"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("Usage: satsim campaign merge") && out.contains("--out <DIR>"),
        "{out}"
    );
    let o = satsim_in(&dir, &["--help"]);
    let out = String::from_utf8_lossy(&o.stdout);
    for c in [
        "plot",
        "completions",
        "campaign",
        "modes",
        "view",
        "accuracy",
    ] {
        assert!(out.contains(c), "{out}");
    }
    let o = satsim_in(&dir, &["--version"]);
    assert_eq!(
        String::from_utf8_lossy(&o.stdout),
        format!("satsim {}\n", env!("CARGO_PKG_VERSION"))
    );
}

#[test]
fn completions_cover_every_command() {
    let dir = setup("completions");
    for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
        let o = satsim_in(&dir, &["completions", shell]);
        assert!(o.status.success(), "{shell}: {}", stderr(&o));
        let script = String::from_utf8_lossy(&o.stdout);
        for c in [
            "dynamics", "campaign", "merge", "plot",
            // Flags by name: fish writes `-l columns`, the others `--columns`.
            "columns", "set", "along",
        ] {
            assert!(script.contains(c), "{shell} completions lack `{c}`");
        }
    }
    let o = satsim_in(&dir, &["completions", "tcsh"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("invalid value 'tcsh'"),
        "{}",
        stderr(&o)
    );
}

/// The polylines of an SVG written by satsim: each a list of pixel points.
fn polylines(svg: &str) -> Vec<Vec<(f64, f64)>> {
    svg.lines()
        .filter(|l| l.starts_with("<polyline"))
        .map(|l| {
            l.split("points=\"")
                .nth(1)
                .unwrap()
                .trim_end_matches("\"/>")
                .split(' ')
                .map(|p| {
                    let (a, b) = p.split_once(',').unwrap();
                    (a.parse().unwrap(), b.parse().unwrap())
                })
                .collect()
        })
        .collect()
}

#[test]
fn plot_redraws_chosen_columns_of_a_run() {
    let dir = setup("plot");
    let o = satsim_in(&dir, &["run", "scene.toml", "--set", "duration=20.0"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = "out/scene/trajectory.csv";
    let o = satsim_in(&dir, &["plot", csv, "--columns", "angle_*,kinetic_energy"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("out/scene/trajectory-plot.svg") && out.contains("21 rows"),
        "{out}"
    );
    let svg = std::fs::read_to_string(dir.join("out/scene/trajectory-plot.svg")).unwrap();
    let header = std::fs::read_to_string(dir.join(csv)).unwrap();
    let angles = header
        .lines()
        .next()
        .unwrap()
        .split(',')
        .filter(|c| c.starts_with("angle_"))
        .count();
    assert_eq!(angles, 5);
    // One curve per angle plus the energy, each through every one of the 21 rows, spanning
    // the plot from its left edge (80 px) to its right (570 px).
    let lines = polylines(&svg);
    assert_eq!(lines.len(), angles + 1, "{svg}");
    for l in &lines {
        assert_eq!(l.len(), 21);
        assert!(
            (l[0].0 - 80.0).abs() < 0.01 && (l[20].0 - 570.0).abs() < 0.01,
            "{l:?}"
        );
    }
    assert!(svg.contains(">kinetic_energy</text>"), "{svg}");

    // A window: 5 s to 10 s holds rows 5..=10.
    let o = satsim_in(
        &dir,
        &[
            "plot",
            csv,
            "--columns",
            "h_x",
            "--from",
            "5",
            "--to",
            "10",
            "-o",
            "h.svg",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("6 rows, t = 5 .. 10 s"));
    let lines = polylines(&std::fs::read_to_string(dir.join("h.svg")).unwrap());
    assert_eq!(lines.len(), 1);
    assert_eq!(lines[0].len(), 6);
}

#[test]
fn plot_refuses_bad_input_naming_it() {
    let dir = setup("plotbad");
    std::fs::write(dir.join("a.csv"), "t,x,y\n0,1,2\n1,2,3\n2,3,oops\n").unwrap();
    std::fs::write(dir.join("empty.csv"), "").unwrap();
    std::fs::write(dir.join("no_t.csv"), "time,x\n0,1\n").unwrap();
    let fails = |args: &[&str], needles: &[&str]| {
        let o = satsim_in(&dir, args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(o.stdout.is_empty());
        for n in needles {
            assert!(err.contains(n), "{args:?}: `{err}` lacks `{n}`");
        }
    };
    // A missing column lists the available ones.
    fails(
        &["plot", "a.csv", "--columns", "x,z"],
        &["a.csv:1", "no column `z`", "the columns are: t, x, y"],
    );
    fails(
        &[
            "plot",
            "a.csv",
            "--columns",
            "x",
            "--from",
            "2",
            "--to",
            "1",
        ],
        &["--from 2", "--to 1"],
    );
    fails(
        &["plot", "a.csv", "--columns", "x", "--from", "5"],
        &["a.csv", "no rows with t >= 5 s; its rows span t = 0 .. 2 s"],
    );
    fails(
        &["plot", "a.csv", "--columns", "x", "--to", "abc"],
        &["'--to <T>'"],
    );
    fails(
        &["plot", "a.csv", "--columns", "y"],
        &["a.csv:4", "`oops`", "column `y`"],
    );
    fails(&["plot", "missing.csv", "--columns", "x"], &["missing.csv"]);
    fails(
        &["plot", "empty.csv", "--columns", "x"],
        &["empty.csv", "empty"],
    );
    fails(
        &["plot", "no_t.csv", "--columns", "x"],
        &["no_t.csv:1", "no time column `t`"],
    );
    fails(&["plot", "a.csv"], &["--columns <A,B,...>"]);
    // Negative times are times, not flags.
    let o = satsim_in(
        &dir,
        &[
            "plot",
            "a.csv",
            "--columns",
            "x",
            "--from",
            "-1",
            "--to",
            "1.5",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("2 rows"));
}

#[test]
fn environment_at_0_shows_a_thruster_firing_from_the_start() {
    // Duty 1 from t = 0: the thruster is on over the first period; `--at 0` used to report
    // the state before the start's sample, with no thrust at all.
    let dir = setup("env-thrust0");
    std::fs::write(
        dir.join("thrust.toml"),
        r#"duration = 1.0
[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.0, 0.0, 10.0]]
[effects.thrusters]
period = 0.1
[[effects.thrusters.thruster]]
name = "roll"
at = [0.0, 1.0, 0.0]
direction = [0.0, 0.0, 1.0]
thrust = 2.0
duty = 1.0
"#,
    )
    .unwrap();
    for at in ["0", "0.05"] {
        let o = satsim_in(&dir, &["environment", "thrust.toml", "--at", at]);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let bus = &v["effects"]["thrusters"]["bodies"]["bus"];
        assert_eq!(
            bus["force"],
            serde_json::json!([0.0, 0.0, 2.0]),
            "--at {at}: {v}"
        );
        assert_eq!(
            bus["torque"],
            serde_json::json!([2.0, 0.0, 0.0]),
            "--at {at}: {v}"
        );
    }
}

#[test]
fn the_views_header_counts_wheel_rotors_apart() {
    // A bus, one panel on one hinge and three wheels: the tree has 5 bodies and 4 hinges,
    // the view's header must say "2 bodies, 1 hinges, 3 wheel rotors" as the summary does.
    let dir = setup("view-rotors");
    std::fs::write(
        dir.join("wheels.toml"),
        r#"duration = 0.5
[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.0, 0.0, 10.0]]
[[model.body]]
name = "panel"
mass = 5.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
com = [0.0, 1.0, 0.0]
[[model.hinge]]
name = "root"
parent = "bus"
child = "panel"
axis = [1.0, 0.0, 0.0]
at = [0.0, 0.5, 0.0]
[integrator]
method = "rk4"
step = 0.1
[output]
every = 0.1
plots = false
[effects.reaction_wheels]
[[effects.reaction_wheels.wheel]]
name = "x"
axis = [1.0, 0.0, 0.0]
inertia = 0.01
[[effects.reaction_wheels.wheel]]
name = "y"
axis = [0.0, 1.0, 0.0]
inertia = 0.01
[[effects.reaction_wheels.wheel]]
name = "z"
axis = [0.0, 0.0, 1.0]
inertia = 0.01
speed = 10.0
"#,
    )
    .unwrap();
    let o = satsim_in(&dir, &["run", "wheels.toml", "--out", "w"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("model      2 bodies, 1 hinges, 3 wheel rotors"),
        "{out}"
    );
    let scene: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("w/view.json")).unwrap()).unwrap();
    // Every body is drawn (the rotors too); the header subtracts the rotors.
    assert_eq!(scene["bodies"].as_array().unwrap().len(), 5, "{scene}");
    assert_eq!(scene["hinges"].as_array().unwrap().len(), 4, "{scene}");
    assert_eq!(scene["rotors"], 3, "{scene}");
    let page = std::fs::read_to_string(dir.join("w/view.html")).unwrap();
    assert!(
        page.contains("${NB - NR} bodies, ${SCENE.hinges.length - NR} hinges"),
        "the page's header does not subtract the rotors"
    );
    // `satsim view` re-creates the page from view.json, rotors included.
    let o = satsim_in(&dir, &["view", "w", "--out", "again.html"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let again = std::fs::read_to_string(dir.join("again.html")).unwrap();
    assert!(
        again.contains("\"rotors\":3"),
        "rotors lost on the way back"
    );
}

#[test]
fn modes_at_a_state_that_is_no_equilibrium_warn_with_the_residual() {
    // tumbling.toml spins about the intermediate axis, slightly off it: Euler's equations
    // give |ω̇| = 9.49e-5 rad/s² at t = 0, and its "modes" describe that motion.
    let dir = setup("modes-drift");
    let tumbling = root().join("examples/scenes/tumbling.toml");
    let o = satsim_in(&dir, &["modes", tumbling.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("warning: the initial state is not an equilibrium")
            && err.contains("angular velocity (rad/s²) 9.49")
            && err.contains("zero rates"),
        "{err}"
    );
    let o = satsim_in(&dir, &["linearize", tumbling.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("not an equilibrium"), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let states = v["states"].as_array().unwrap();
    let residual = v["residual"].as_array().unwrap();
    assert_eq!(residual.len(), states.len());
    let at = |name: &str| {
        let k = states.iter().position(|s| s == name).unwrap();
        residual[k].as_f64().unwrap()
    };
    // ω̇_x = −(ω_y I_z ω_z − ω_z I_y ω_y) / I_x = 0.08 / 900.
    assert!((at("omega_x") - 0.08 / 900.0).abs() < 1e-12, "{v}");
    // At rest, at its springs' references: an equilibrium, no warning.
    let rest = root().join("examples/scenes/deployment_modes.toml");
    for command in ["modes", "linearize"] {
        let o = satsim_in(&dir, &[command, rest.to_str().unwrap()]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(!stderr(&o).contains("equilibrium"), "{}", stderr(&o));
    }
}

#[test]
fn self_shadowing_many_facets_warns_with_its_cost() {
    // 2000 facets scattered in a 4 m cube, each shading many others: self-shadowing costs
    // tens of milliseconds per right-hand side, which reading the scene says.
    let dir = setup("shade-cost");
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut uniform = move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    };
    let facets = |n: usize, uniform: &mut dyn FnMut() -> f64| {
        (0..n)
            .map(|_| {
                let at = [4.0 * uniform(), 4.0 * uniform(), 4.0 * uniform()];
                let n = [uniform() - 0.5, uniform() - 0.5, uniform() + 0.1];
                let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                let normal = n.map(|c| c / norm);
                format!(
                    "  {{ area = {}, normal = {normal:?}, at = {at:?} }},\n",
                    0.05 + 0.4 * uniform()
                )
            })
            .collect::<String>()
    };
    let scene = |facets: &str, shadowing: bool| {
        format!(
            r#"epoch = "2026-03-20T12:00:00 UTC"
duration = 1.0
[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.0, 0.0, 10.0]]
facets = [
{facets}]
[orbit]
altitude = 500e3
[effects.solar_radiation]
self_shadowing = {shadowing}
"#
        )
    };
    let many = facets(2000, &mut uniform);
    std::fs::write(dir.join("many.toml"), scene(&many, true)).unwrap();
    std::fs::write(dir.join("off.toml"), scene(&many, false)).unwrap();
    std::fs::write(dir.join("few.toml"), scene(&facets(30, &mut uniform), true)).unwrap();
    let o = satsim_in(&dir, &["environment", "many.toml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    let line = 2012; // the [effects.solar_radiation] line: 9 + 2000 facets + 3
    assert!(
        err.contains(&format!(
            "warning: many.toml:{line}: `effects.solar_radiation.self_shadowing` on 2000 facets \
             at resolution 8 costs about"
        )) && err.contains("ms per right-hand side")
            && err.contains("set `self_shadowing = false`"),
        "{err}"
    );
    for quiet in ["off.toml", "few.toml"] {
        let o = satsim_in(&dir, &["environment", quiet]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            !stderr(&o).contains("self_shadowing"),
            "{quiet}: {}",
            stderr(&o)
        );
    }
}
