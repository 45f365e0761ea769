//! The limits a user hits (issue 28): outputs that do not fit, values that make no sense,
//! resumes that mix scenes, errors placed where the value is written, `--set` on every
//! command, Ctrl-C in a campaign's long runs, a trajectory cut by a kill.

use crate::common;

use common::root;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// A short scene of the preprint satellite (its model file beside it): 2 s of RK4 at 0.01 s,
/// rows every 0.5 s, springs on every hinge, the panels stowed.
const SHORT: &str = r#"model = "satellite.toml"
duration = 2.0

[initial]
hinges = { angle = [0.0, 0.0, 0.0, 3.0, -3.0], rate = [0.0, 0.0, 0.0, 0.0, 0.0] }

[integrator]
method = "rk4"
step = 0.01

[output]
every = 0.5
plots = false
view = false

[effects.hinge_springs]
stiffness = [50.0, 50.0, 50.0, 2.0, 2.0]
damping = [40.0, 40.0, 40.0, 4.0, 4.0]

[effects.hinge_stops]
[[effects.hinge_stops.stop]]
hinge = "h4"
lower = 0.0
"#;

/// The campaign table added to [`SHORT`] for the campaign tests.
const CAMPAIGN: &str = r#"
[campaign]
runs = 6
seed = 7

[[campaign.disperse]]
key = "effects.hinge_springs.stiffness"
index = 3
normal = { sigma = 1.0 }
"#;

fn temp_dir(test: &str) -> PathBuf {
    satsim_testkit::temp_dir_with(&format!("limits-{test}"), &["examples/satellite.toml"])
}

fn scene(dir: &Path, text: &str) -> PathBuf {
    let p = dir.join("short.toml");
    std::fs::write(&p, text).unwrap();
    p
}

fn satsim(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_satsim"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run satsim")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Exit status 2 (bad input): its standard error.
fn refused(o: &Output) -> String {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    err
}

fn ok(o: &Output) -> String {
    let err = stderr(o);
    assert!(o.status.success(), "{err}");
    err
}

fn rows(dir: &Path, out: &str) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(dir.join(out).join("trajectory.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(|f| f.parse().unwrap()).collect())
        .collect()
}

/// The line (1-based) of the first line of `text` that starts with `start` after `after`.
fn line_of(text: &str, after: &str, start: &str) -> usize {
    let from = text.find(after).expect("anchor");
    let before = text[..from].lines().count();
    before
        + text[from..]
            .lines()
            .position(|l| l.trim_start().starts_with(start))
            .expect("line")
        + 1
}

#[test]
fn a_run_whose_rows_exceed_the_limit_is_refused_before_it_starts() {
    let dir = temp_dir("rows");
    scene(&dir, SHORT);
    let started = Instant::now();
    let err = refused(&satsim(
        &dir,
        &[
            "run",
            "short.toml",
            "--out",
            "o",
            "--set",
            "output.every=1e-9",
        ],
    ));
    assert!(
        err.contains("`output.every` = 0.000000001 s over `duration` = 2 s makes 2000000001 rows, more than the limit of 1000000"),
        "{err}"
    );
    assert!(err.contains("--max-rows"), "{err}");
    assert!(
        !dir.join("o/trajectory.csv").exists(),
        "refused before writing"
    );
    // An absurd interval: the count in exponent form, not its 300 digits.
    let err = refused(&satsim(
        &dir,
        &[
            "run",
            "short.toml",
            "--out",
            "o",
            "--set",
            "output.every=1e-300",
        ],
    ));
    assert!(
        err.contains("`output.every` = 1e-300 s over `duration` = 2 s makes 2.000e300 rows"),
        "{err}"
    );
    // Refused at once, not after writing gigabytes.
    assert!(started.elapsed() < Duration::from_secs(30));
    // The limit is a flag: 2 s at 1e-3 s is 2001 rows.
    let err = refused(&satsim(
        &dir,
        &[
            "run",
            "short.toml",
            "--out",
            "o",
            "--set",
            "output.every=1e-3",
            "--max-rows",
            "2000",
        ],
    ));
    assert!(
        err.contains("makes 2001 rows, more than the limit of 2000"),
        "{err}"
    );
    ok(&satsim(
        &dir,
        &[
            "run",
            "short.toml",
            "--out",
            "o",
            "--set",
            "output.every=1e-3",
            "--max-rows",
            "2001",
        ],
    ));
    assert_eq!(rows(&dir, "o").len(), 2001);
    // A campaign too, before its first run.
    scene(&dir, &format!("{SHORT}{CAMPAIGN}"));
    let err = refused(&satsim(
        &dir,
        &[
            "campaign",
            "short.toml",
            "--out",
            "c",
            "--set",
            "output.every=1e-7",
        ],
    ));
    assert!(err.contains("makes 20000001 rows"), "{err}");
    assert!(!dir.join("c/runs.csv").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_output_interval_longer_than_the_run_still_writes_the_first_and_last_rows() {
    let dir = temp_dir("every");
    scene(&dir, SHORT);
    ok(&satsim(
        &dir,
        &[
            "run",
            "short.toml",
            "--out",
            "o",
            "--set",
            "output.every=1e16",
        ],
    ));
    let r = rows(&dir, "o");
    assert_eq!(r.len(), 2);
    assert_eq!((r[0][0], r[1][0]), (0.0, 2.0));
    // The start is the initial state (the panel stowed at 3 rad), the end is not.
    let h4 = 8 + 3;
    assert_eq!(r[0][h4], 3.0);
    assert_ne!(r[1][h4], 3.0);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn negative_spring_stiffness_and_damping_are_refused_at_their_line() {
    let dir = temp_dir("negative");
    for (key, bad) in [
        ("stiffness", "stiffness = [50.0, 50.0, 50.0, -2.0, 2.0]"),
        ("damping", "damping = [40.0, 40.0, -40.0, 4.0, 4.0]"),
    ] {
        let original = SHORT
            .lines()
            .find(|l| l.starts_with(key))
            .expect("the key's line");
        let text = SHORT.replace(original, bad);
        scene(&dir, &text);
        let err = refused(&satsim(&dir, &["run", "short.toml", "--out", "o"]));
        let line = line_of(&text, "[effects.hinge_springs]", key);
        assert!(
            err.contains(&format!("short.toml:{line}: `effects.hinge_springs.{key}`")),
            "{err}"
        );
        assert!(err.contains("must be >= 0"), "{err}");
    }
    // A campaign whose draws go negative: those runs are failed rows naming the key and value.
    scene(
        &dir,
        &format!("{SHORT}{CAMPAIGN}").replace("sigma = 1.0", "sigma = 4.0"),
    );
    ok(&satsim(
        &dir,
        &["campaign", "short.toml", "--out", "c", "--threads", "1"],
    ));
    let runs = std::fs::read_to_string(dir.join("c/runs.csv")).unwrap();
    let mut failed = 0;
    for line in runs.lines().skip(1) {
        let drawn: f64 = line.split(',').nth(1).unwrap().parse().unwrap();
        let status = line.split(',').nth(2).unwrap();
        assert_eq!(status == "failed", drawn < 0.0, "{line}");
        if drawn < 0.0 {
            failed += 1;
            assert!(
                line.contains(&format!(
                    "`effects.hinge_springs.stiffness`: entry 3 (hinge `h4`) is {drawn}: it must be >= 0"
                )),
                "{line}"
            );
        }
    }
    assert!(
        failed > 0,
        "the seed draws some negative stiffnesses:\n{runs}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn resume_and_merge_refuse_folders_without_a_scene_digest() {
    let dir = temp_dir("digest");
    scene(&dir, &format!("{SHORT}{CAMPAIGN}"));
    ok(&satsim(&dir, &["campaign", "short.toml", "--out", "a"]));
    ok(&satsim(&dir, &["campaign", "short.toml", "--out", "b"]));
    // No campaign.json: nothing says which scene the runs came from.
    std::fs::remove_file(dir.join("a/campaign.json")).unwrap();
    let err = refused(&satsim(
        &dir,
        &["campaign", "short.toml", "--out", "a", "--resume"],
    ));
    assert!(err.contains("no campaign.json beside it"), "{err}");
    // A campaign.json without the digest (an older satsim's), and another scene's runs.
    let json_path = dir.join("b/campaign.json");
    let json = std::fs::read_to_string(&json_path).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&json).unwrap();
    v.as_object_mut().unwrap().remove("scene_digest");
    std::fs::write(&json_path, v.to_string()).unwrap();
    let text = std::fs::read_to_string(dir.join("short.toml")).unwrap();
    std::fs::write(
        dir.join("short.toml"),
        text.replace("duration = 2.0", "duration = 1.0"),
    )
    .unwrap();
    let err = refused(&satsim(
        &dir,
        &["campaign", "short.toml", "--out", "b", "--resume"],
    ));
    assert!(err.contains("has no scene digest"), "{err}");
    ok(&satsim(&dir, &["campaign", "short.toml", "--out", "d"]));
    let o = satsim(&dir, &["campaign", "merge", "d", "b", "--out", "m"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("has no scene digest"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_error_after_set_names_the_line_where_the_value_is_written() {
    let dir = temp_dir("place");
    scene(&dir, SHORT);
    let model = std::fs::read_to_string(dir.join("satellite.toml")).unwrap();
    // Body 4 (panel2): its `mass` line in the model file.
    let mass_line = {
        let body4 = model.match_indices("[[body]]").nth(4).unwrap().0;
        line_of(&model[body4..], "[[body]]", "mass") + model[..body4].lines().count()
    };
    let err = refused(&satsim(
        &dir,
        &[
            "run",
            "short.toml",
            "--out",
            "o",
            "--set",
            "model.body.4.mass=-5",
        ],
    ));
    assert!(
        err.contains(&format!(
            "satellite.toml:{mass_line}: body `panel2`: mass -5 is negative"
        )),
        "{err}"
    );
    // A scene key: its line in the scene file, and the overrides listed.
    let err = refused(&satsim(
        &dir,
        &[
            "run",
            "short.toml",
            "--out",
            "o",
            "--set",
            "effects.hinge_springs.damping=[1.0]",
        ],
    ));
    let line = line_of(SHORT, "[effects.hinge_springs]", "damping");
    assert!(
        err.contains(&format!(
            "short.toml:{line}: `effects.hinge_springs.damping`: expected 5 entries"
        )),
        "{err}"
    );
    assert!(
        err.contains("(with --set effects.hinge_springs.damping=[1.0])"),
        "{err}"
    );
    // A campaign's failed row names the model file's line too.
    let campaign = format!(
        "{SHORT}\n[campaign]\nruns = 1\n[[campaign.disperse]]\nkey = \"model.body.4.mass\"\nuniform = {{ low = -30.0, high = -25.0 }}\n"
    );
    scene(&dir, &campaign);
    ok(&satsim(&dir, &["campaign", "short.toml", "--out", "c"]));
    let runs = std::fs::read_to_string(dir.join("c/runs.csv")).unwrap();
    assert!(
        runs.contains(&format!(
            "satellite.toml:{mass_line}: body `panel2`: mass -"
        )),
        "{runs}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_fixed_step_longer_than_the_run_or_the_output_interval_warns() {
    let dir = temp_dir("step");
    scene(&dir, SHORT);
    let line = line_of(SHORT, "[integrator]", "step");
    let err = ok(&satsim(
        &dir,
        &[
            "run",
            "short.toml",
            "--out",
            "o",
            "--set",
            "integrator.step=5.0",
        ],
    ));
    assert!(
        err.contains(&format!(
            "warning: short.toml:{line} (with --set): `integrator.step` (5 s) is longer than `duration` (2 s)"
        )),
        "{err}"
    );
    let err = ok(&satsim(
        &dir,
        &[
            "run",
            "short.toml",
            "--out",
            "o",
            "--set",
            "integrator.step=0.8",
        ],
    ));
    assert!(
        err.contains("`integrator.step` (0.8 s) is longer than `output.every` (0.5 s)"),
        "{err}"
    );
    let err = ok(&satsim(&dir, &["run", "short.toml", "--out", "o"]));
    assert!(!err.contains("warning"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn ctrl_c_stops_a_campaigns_running_runs_at_their_next_row() {
    let dir = temp_dir("sigint");
    // Two runs of 20000 s on one thread: minutes each. Ctrl-C stops the running one at its
    // next row instead of waiting for it to end.
    scene(
        &dir,
        &format!("{SHORT}{CAMPAIGN}")
            .replace("duration = 2.0", "duration = 20000.0")
            .replace("every = 0.5", "every = 1.0")
            .replace("runs = 6", "runs = 2"),
    );
    let child = Command::new(env!("CARGO_BIN_EXE_satsim"))
        .args(["campaign", "short.toml", "--out", "c", "--threads", "1"])
        .current_dir(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The campaign has started when its folder holds campaign.json.
    let start = Instant::now();
    while !dir.join("c/campaign.json").exists() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no campaign.json"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(300));
    let interrupted = Instant::now();
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    // Stopped promptly (a run would take minutes), with no run written.
    assert!(interrupted.elapsed() < Duration::from_secs(30));
    let runs = std::fs::read_to_string(dir.join("c/runs.csv")).unwrap();
    assert_eq!(runs.lines().count(), 1, "{runs}");
    assert!(err.contains("interrupted: 0 runs in"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn plot_reads_a_trajectory_cut_mid_row_up_to_its_last_whole_row() {
    let dir = temp_dir("cut");
    scene(&dir, SHORT);
    ok(&satsim(&dir, &["run", "short.toml", "--out", "o"]));
    let text = std::fs::read_to_string(dir.join("o/trajectory.csv")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 6);
    // Killed while writing the row of t = 1.5 s: half of it is there, without its line end.
    let cut = format!(
        "{}\n{}",
        lines[..4].join("\n"),
        &lines[4][..lines[4].len() / 2]
    );
    std::fs::write(dir.join("cut.csv"), cut).unwrap();
    let o = satsim(
        &dir,
        &["plot", "cut.csv", "--columns", "angle_h4", "-o", "cut.svg"],
    );
    let err = ok(&o);
    assert!(
        err.contains("cut.csv:5: the last line has no line end"),
        "{err}"
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("3 rows, t = 0 .. 1 s"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn set_adds_keys_the_schema_knows_on_every_command_that_reads_a_scene() {
    let dir = temp_dir("set");
    let no_step = SHORT.replace("method = \"rk4\"\nstep = 0.01\n", "method = \"dp54\"\n");
    scene(&dir, &no_step);
    // `integrator.step` is left at its default: added, it switches to its value.
    ok(&satsim(
        &dir,
        &[
            "run",
            "short.toml",
            "--out",
            "o",
            "--set",
            "integrator.method=rk4",
            "--set",
            "integrator.step=0.25",
        ],
    ));
    assert_eq!(rows(&dir, "o").len(), 5);
    // A table the scene does not have, and a key inside an array's table: both read.
    ok(&satsim(
        &dir,
        &[
            "run",
            "short.toml",
            "--out",
            "o",
            "--set",
            "orbit.altitude=500e3",
            "--set",
            "effects.hinge_stops.stop.0.action=rebound",
        ],
    ));
    let err = refused(&satsim(
        &dir,
        &[
            "run",
            "short.toml",
            "--out",
            "o",
            "--set",
            "orbit.altitude=50",
        ],
    ));
    assert!(
        err.contains("`orbit.altitude` is 50 m, below 100 km"),
        "{err}"
    );
    // A key the schema does not know is refused by the reader, naming it.
    let err = refused(&satsim(
        &dir,
        &[
            "run",
            "short.toml",
            "--out",
            "o",
            "--set",
            "integrator.stepp=0.25",
        ],
    ));
    assert!(err.contains("unknown key `stepp`"), "{err}");
    // modes, linearize and accuracy take --set too.
    let stiff = "effects.hinge_springs.stiffness=[5.0, 5.0, 5.0, 2.0, 2.0]";
    let a = satsim(&dir, &["modes", "short.toml"]);
    let b = satsim(&dir, &["modes", "short.toml", "--set", stiff]);
    ok(&a);
    ok(&b);
    assert_ne!(
        a.stdout, b.stdout,
        "the softer gimbal springs change the modes"
    );
    let a = satsim(&dir, &["linearize", "short.toml"]);
    let b = satsim(&dir, &["linearize", "short.toml", "--set", stiff]);
    ok(&a);
    ok(&b);
    assert_ne!(a.stdout, b.stdout);
    let err = refused(&satsim(
        &dir,
        &[
            "accuracy",
            "short.toml",
            "--quick",
            "--out",
            "acc",
            "--set",
            "duration=-1",
        ],
    ));
    assert!(
        err.contains("`duration` must be a finite number > 0, got -1"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn angles_beyond_a_turn_warn_as_degrees_written_for_radians() {
    let dir = temp_dir("angles");
    let text = SHORT.replace("lower = 0.0", "lower = -90.0");
    scene(&dir, &text);
    let err = ok(&satsim(&dir, &["run", "short.toml", "--out", "o"]));
    let line = line_of(
        &text,
        "[[effects.hinge_stops.stop]]",
        "[[effects.hinge_stops.stop]]",
    );
    assert!(
        err.contains(&format!(
            ":{line}: `effects.hinge_stops.stop.lower` is -90 rad, beyond ±2π"
        )),
        "{err}"
    );
    assert!(err.contains("write -1.570796"), "{err}");
    let text = SHORT.replace(
        "angle = [0.0, 0.0, 0.0, 3.0, -3.0]",
        "angle = [0.0, 0.0, 0.0, 180.0, -3.0]",
    );
    scene(&dir, &text);
    let o = satsim(&dir, &["run", "short.toml", "--out", "o"]);
    assert!(
        stderr(&o).contains("hinges.angle: entry 3 is 180 rad, beyond ±2π"),
        "{}",
        stderr(&o)
    );
    // Angles within a turn say nothing.
    scene(&dir, SHORT);
    let err = ok(&satsim(&dir, &["run", "short.toml", "--out", "o"]));
    assert!(!err.contains("warning"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `satellite_flexible.toml` beside the scene, its last panel's beam replaced by
/// `modes_file = <file>`; the scene [`SHORT`] reading it. The model's text and the line of
/// `modes_file`.
fn flexible_with_modes_file(dir: &Path, file: &str) -> (String, usize) {
    let model = std::fs::read_to_string(root().join("examples/satellite_flexible.toml")).unwrap();
    let panel3 = model.find("name = \"panel3\"").unwrap();
    let beam = model[panel3..].find("beam = {").unwrap() + panel3;
    let end = model[beam..].find("modes = 3 }\n").unwrap() + beam + "modes = 3 }\n".len();
    let text = format!("{}modes_file = {file:?}\n{}", &model[..beam], &model[end..]);
    std::fs::write(dir.join("flex.toml"), &text).unwrap();
    scene(dir, &SHORT.replace("satellite.toml", "flex.toml"));
    let line = line_of(&text, "name = \"panel3\"", "modes_file");
    (text, line)
}

#[test]
fn a_modes_file_that_cannot_be_read_is_an_error_at_its_line_in_the_model() {
    let dir = temp_dir("modes-file");
    for (file, why) in [
        (".", "cannot read it: "),
        ("missing.toml", "cannot read it: "),
        ("empty.toml", "the file is empty"),
    ] {
        std::fs::write(dir.join("empty.toml"), "  \n").unwrap();
        let (_, line) = flexible_with_modes_file(&dir, file);
        let err = refused(&satsim(&dir, &["run", "short.toml", "--out", "o"]));
        assert!(
            err.contains(&format!(
                "flex.toml:{line}: body `panel3`: `modes_file` = {file:?}"
            )),
            "{err}"
        );
        assert!(err.contains(why), "{err}");
    }
    // A file of 500 modes: refused at its `frequencies_hz` line (the cap is 100).
    let n = 500;
    let hz: Vec<String> = (1..=n).map(|k| format!("{k}.0")).collect();
    let rows = "  [0.0, 0.0, 0.0, 0.0, 0.0, 0.1],\n".repeat(n);
    let modes = format!(
        "mass = 10.0\ninertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\nfrequencies_hz = [{}]\nmomentum = [\n{rows}]\n",
        hz.join(", ")
    );
    std::fs::write(dir.join("many.toml"), modes).unwrap();
    flexible_with_modes_file(&dir, "many.toml");
    let err = refused(&satsim(&dir, &["run", "short.toml", "--out", "o"]));
    assert!(
        err.contains("many.toml:3: `frequencies_hz`: 500 modes, more than the 100 a body may have"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// [`SHORT`] with the date, orbit, magnetic torquer, B-dot, thruster and star tracker of the
/// bound checks, each at a sane value.
const EQUIPPED: &str = r#"
[orbit]
altitude = 500e3
inclination_deg = 51.6

[effects.magnetic]
field = "dipole"
residual_dipole = [0.1, 0.0, 0.0]
[[effects.magnetic.torquer]]
name = "mx"
axis = [1.0, 0.0, 0.0]
max_dipole = 100.0
dipole = 2.0

[effects.bdot]
gain = 1e5
field = "dipole"

[effects.thrusters]
period = 0.5
[[effects.thrusters.thruster]]
name = "t1"
at = [0.0, 0.0, 1.0]
direction = [1.0, 0.0, 0.0]
thrust = 1.0

[sensors]
[[sensors.star_tracker]]
name = "st"
body = "bus"
period = 0.5
noise_arcsec = [10.0, 10.0, 10.0]
"#;

#[test]
fn values_beyond_any_spacecraft_are_refused_at_their_line_naming_the_bound() {
    let dir = temp_dir("bounds");
    let text = format!("epoch = \"2026-03-20T12:00:00 UTC\"\n{SHORT}{EQUIPPED}");
    scene(&dir, &text);
    ok(&satsim(&dir, &["run", "short.toml", "--out", "o"]));
    for (from, to, anchor, expected) in [
        (
            "thrust = 1.0",
            "thrust = 1e20",
            "thrust",
            "`effects.thrusters.thruster.thrust` is 1e20 N, more than 1e8 N",
        ),
        (
            "max_dipole = 100.0",
            "max_dipole = 1e20",
            "max_dipole",
            "`effects.magnetic.torquer.max_dipole` is 1e20 A m², more than 1e6 A m²",
        ),
        (
            "dipole = 2.0",
            "dipole = -1e20",
            "dipole =",
            "`effects.magnetic.torquer.dipole` is -1e20 A m², below -1e6 A m²",
        ),
        (
            "residual_dipole = [0.1,",
            "residual_dipole = [1e7,",
            "residual_dipole",
            "`effects.magnetic.residual_dipole` is 10000000 A m², more than 1e6 A m²",
        ),
        (
            "gain = 1e5",
            "gain = 1e308",
            "gain",
            "`effects.bdot.gain` is 1e308 A m² s/T, more than 1e12 A m² s/T",
        ),
        (
            "noise_arcsec = [10.0,",
            "noise_arcsec = [1e12,",
            "noise_arcsec",
            "`sensors.star_tracker.noise_arcsec` must be finite numbers >= 0 (arc seconds), at most 648000 (half a turn), got [1e12, 10, 10]",
        ),
        (
            "inclination_deg = 51.6",
            "inclination_deg = 1e308",
            "[orbit]",
            "`orbit.inclination_deg` is 1e308 deg: an inclination lies in [0, 180] deg",
        ),
    ] {
        let bad = text.replace(from, to);
        assert_ne!(bad, text, "{from}");
        scene(&dir, &bad);
        let err = refused(&satsim(&dir, &["run", "short.toml", "--out", "o"]));
        let line = line_of(&bad, "[orbit]", anchor);
        assert!(
            err.contains(&format!("short.toml:{line}: {expected}")),
            "{err}"
        );
    }
    // In the model: a facet of 1e30 m², or 1e308 m from its body.
    let model = std::fs::read_to_string(dir.join("satellite.toml")).unwrap();
    let shape = model.find("facets_from_shape").unwrap();
    let after = model[shape..].find('\n').unwrap() + shape + 1;
    for (facet, expected) in [
        (
            "{ area = 1e30, normal = [0, 0, 1], at = [0, 0, 0] }",
            "body `bus`: facet 0: area 1e30 m² is more than 1e6 m²",
        ),
        (
            "{ area = 1.0, normal = [0, 0, 1], at = [1e308, 0, 0] }",
            "body `bus`: facet 0: its centroid `at` is 1e308 m from the body's origin, more than 1e4 m",
        ),
    ] {
        let bad = format!("{}facets = [{facet}]\n{}", &model[..after], &model[after..]);
        std::fs::write(dir.join("big.toml"), &bad).unwrap();
        scene(&dir, &SHORT.replace("satellite.toml", "big.toml"));
        let err = refused(&satsim(&dir, &["run", "short.toml", "--out", "o"]));
        let line = bad[..after].lines().count() + 1;
        assert!(
            err.contains(&format!("big.toml:{line}: {expected}")),
            "{err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_run_that_overflows_names_the_state_that_went_non_finite_first() {
    let dir = temp_dir("overflow");
    scene(&dir, SHORT);
    for method in ["rk4", "dp54"] {
        let o = satsim(
            &dir,
            &[
                "run",
                "short.toml",
                "--out",
                "o",
                "--set",
                "effects.hinge_springs.stiffness=[50.0, 50.0, 50.0, 1e300, 2.0]",
                "--set",
                &format!("integrator.method={method}"),
            ],
        );
        let err = stderr(&o);
        if method == "rk4" {
            // RK4's fixed step is checked against the spring when the scene is read.
            assert_eq!(o.status.code(), Some(2), "{err}");
            assert!(
                err.contains("too long for rk4 with the hinges' springs")
                    && err.contains("mostly hinge `h4`"),
                "{err}"
            );
            continue;
        }
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.contains("non-finite value at t = "), "{err}");
        // A column's name, not an index into the state.
        assert!(err.contains(": the rate of change of `"), "{err}");
        assert!(!err.contains("state entry"), "{err}");
        assert!(
            err.contains("is not finite (the forces or the motion overflowed"),
            "{err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_hinge_control_profile_beyond_a_turn_warns_as_degrees_written_for_radians() {
    let dir = temp_dir("control-angles");
    let text = format!(
        "{SHORT}\n[effects.hinge_control]\n[[effects.hinge_control.hinge]]\nname = \"h5\"\nstart = 180.0\nend = 0.0\nduration = 10.0\nkp = 1.0\n"
    );
    scene(&dir, &text);
    let err = ok(&satsim(&dir, &["run", "short.toml", "--out", "o"]));
    let line = line_of(
        &text,
        "[[effects.hinge_control.hinge]]",
        "[[effects.hinge_control.hinge]]",
    );
    assert!(
        err.contains(&format!(
            "short.toml:{line}: `effects.hinge_control.hinge.start` is 180 rad, beyond ±2π"
        )),
        "{err}"
    );
    assert!(err.contains("write 3.141593"), "{err}");
    assert!(!err.contains("hinge.end"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
