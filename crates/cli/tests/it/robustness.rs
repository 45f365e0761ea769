//! `satsim run` on bad input and hard cases (docs/src/results/hard-cases.md): every bad
//! scene exits 2 with one message naming the file and the line or field, prints nothing on
//! standard output and never panics; a scene driven into gimbal lock exits 1 naming the
//! hinges and the time and keeps its CSV; Ctrl-C stops a run cleanly with exit status 130.

use crate::common;
use common::{csv, root, satsim_in};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn setup(test: &str) -> PathBuf {
    satsim_testkit::temp_dir_with(
        &format!("robust-{test}"),
        &["examples/satellite.toml", "examples/state.json"],
    )
}

/// A valid scene: lines are numbered in the comments the cases below rely on.
const SCENE: &str = r#"model = "satellite.toml"
initial = "state.json"
duration = 2.0
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

const WHEEL: &str = "[effects.reaction_wheels]\n[[effects.reaction_wheels.wheel]]\nname = \"x\"\naxis = [1.0, 0.0, 0.0]\ninertia = 0.1\n";

/// A thruster section, its one thruster's `name` left to add (at line 19 of a scene that
/// appends this to [`SCENE`]).
const THRUSTER: &str = "[effects.thrusters]\nperiod = 0.1\n[[effects.thrusters.thruster]]\nat = [0.0, 0.0, 0.0]\ndirection = [1.0, 0.0, 0.0]\nthrust = 1.0\n";

/// `(case, scene text, extra files, what the message must contain)`.
type Case = (
    &'static str,
    String,
    Vec<(&'static str, String)>,
    Vec<&'static str>,
);

fn cases() -> Vec<Case> {
    let s = |from: &str, to: &str| {
        assert!(SCENE.contains(from), "{from}");
        SCENE.replace(from, to)
    };
    let add = |extra: &str| format!("{SCENE}{extra}");
    let model = std::fs::read_to_string(root().join("examples/satellite.toml")).unwrap();
    let no_file = Vec::new;
    vec![
        // Syntax.
        (
            "syntax",
            s("duration = 2.0", "duration = = 2.0"),
            no_file(),
            vec!["bad.toml:3"],
        ),
        ("empty", String::new(), no_file(), vec!["bad.toml", "empty"]),
        (
            "wrong type",
            s("duration = 2.0", "duration = \"two\""),
            no_file(),
            vec!["bad.toml:3", "duration"],
        ),
        (
            "missing key",
            s("duration = 2.0\n", ""),
            no_file(),
            vec!["bad.toml", "missing required key `duration`"],
        ),
        // Unknown keys at every level.
        (
            "unknown top key",
            format!("colour = 1\n{SCENE}"),
            no_file(),
            vec!["bad.toml:1", "unknown key `colour`"],
        ),
        (
            "unknown integrator key",
            s("step = 0.01", "stpe = 0.01"),
            no_file(),
            vec!["bad.toml:6", "unknown key `stpe`"],
        ),
        (
            "unknown output key",
            s("every = 1.0", "evry = 1.0"),
            no_file(),
            vec!["bad.toml:8", "unknown key `evry`"],
        ),
        (
            "unknown effect",
            add("[effects.magnets]\n"),
            no_file(),
            vec!["bad.toml:13", "unknown key `magnets`"],
        ),
        (
            "unknown springs key",
            s("damping =", "dampin ="),
            no_file(),
            vec!["bad.toml:12", "unknown key `dampin`"],
        ),
        (
            "unknown orbit key",
            add("[orbit]\naltitude = 5e5\nheight = 1\n"),
            no_file(),
            vec!["bad.toml:15", "unknown key `height`"],
        ),
        (
            "unknown stop key",
            add(
                "[effects.hinge_stops]\n[[effects.hinge_stops.stop]]\nhinge = \"h4\"\nlower = 0.0\nlatch = true\n",
            ),
            no_file(),
            vec!["bad.toml:17", "unknown key `latch`"],
        ),
        (
            "unknown wheel key",
            add(&format!("{WHEEL}spin = 3.0\n")),
            no_file(),
            vec!["bad.toml:18", "unknown key `spin`"],
        ),
        (
            "unknown control key",
            add(
                "[effects.hinge_control]\n[[effects.hinge_control.hinge]]\nname = \"h4\"\nstart = 0.0\nend = 1.0\nduration = 1.0\nkp = 1.0\nki = 2.0\n",
            ),
            no_file(),
            vec!["bad.toml:20", "unknown key `ki`"],
        ),
        (
            "unknown attitude key",
            add(&format!(
                "{WHEEL}[effects.attitude_control]\nkp = 1.0\nkd = 1.0\nki = 1.0\n"
            )),
            no_file(),
            vec!["bad.toml:21", "unknown key `ki`"],
        ),
        (
            "unknown gravity key",
            add("[orbit]\naltitude = 5e5\n[effects.gravity_gradient]\norder = 2\n"),
            no_file(),
            vec!["bad.toml:16", "unknown key `order`"],
        ),
        (
            "unknown initial key",
            s("initial = \"state.json\"", "initial = { spin = 1.0 }"),
            no_file(),
            vec!["bad.toml:2", "unknown key `spin`"],
        ),
        (
            "unknown inline model key",
            "duration = 1.0\n[model]\n[[model.body]]\nname = \"b\"\nmass = 1.0\ninertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\ncolour = \"red\"\n"
                .to_string(),
            no_file(),
            vec!["bad.toml:7", "unknown key `colour`"],
        ),
        // Unknown names.
        (
            "unknown hinge in stops",
            add(
                "[effects.hinge_stops]\n[[effects.hinge_stops.stop]]\nhinge = \"h9\"\nlower = 0.0\n",
            ),
            no_file(),
            vec!["bad.toml:15", "unknown hinge `h9`"],
        ),
        (
            "unknown hinge in control",
            add(
                "[effects.hinge_control]\n[[effects.hinge_control.hinge]]\nname = \"wing\"\nstart = 0.0\nend = 1.0\nduration = 1.0\nkp = 1.0\n",
            ),
            no_file(),
            vec!["bad.toml:15", "unknown hinge `wing`"],
        ),
        (
            "bad integrator",
            s("\"rk4\"", "\"euler\""),
            no_file(),
            vec!["bad.toml:5", "unknown integration method `euler`"],
        ),
        (
            "bad orbit model",
            add("[orbit]\nmodel = \"newton\"\naltitude = 5e5\n"),
            no_file(),
            vec!["bad.toml:14", "orbit.model"],
        ),
        (
            "bad stop action",
            add(
                "[effects.hinge_stops]\n[[effects.hinge_stops.stop]]\nhinge = \"h4\"\nlower = 0.0\naction = \"stick\"\n",
            ),
            no_file(),
            vec!["bad.toml:17", "`action`"],
        ),
        // Wrong lengths.
        (
            "stiffness length",
            s(
                "stiffness = [50.0, 50.0, 50.0, 2.0, 2.0]",
                "stiffness = [50.0]",
            ),
            no_file(),
            vec!["bad.toml:11", "expected 5 entries"],
        ),
        (
            "damping length",
            s(
                "damping = [1.0, 1.0, 1.0, 0.5, 0.5]",
                "damping = [1.0, 1.0]",
            ),
            no_file(),
            vec!["bad.toml:12", "expected 5 entries"],
        ),
        (
            "reference length",
            add("reference = [0.0]\n"),
            no_file(),
            vec![
                "bad.toml:13",
                "effects.hinge_springs.reference",
                "expected 5",
            ],
        ),
        (
            "armature length",
            s("duration = 2.0", "duration = 2.0\narmature = [1e-3, 1e-3]"),
            no_file(),
            vec!["bad.toml:4", "`armature`: expected 5 entries"],
        ),
        (
            "initial angles length",
            s(
                "initial = \"state.json\"",
                "initial = { hinges = { angle = [0.0], rate = [0.0] } }",
            ),
            no_file(),
            vec!["bad.toml:2", "initial.hinges.angle", "expected 5"],
        ),
        (
            "wheel axis length",
            add(
                "[effects.reaction_wheels]\n[[effects.reaction_wheels.wheel]]\nname = \"x\"\naxis = [1.0, 0.0]\ninertia = 0.1\n",
            ),
            no_file(),
            vec!["bad.toml:16", "axis"],
        ),
        // Negative or zero durations, steps, tolerances, intervals.
        (
            "negative duration",
            s("duration = 2.0", "duration = -2.0"),
            no_file(),
            vec!["bad.toml:3", "`duration` must be"],
        ),
        (
            "zero duration",
            s("duration = 2.0", "duration = 0.0"),
            no_file(),
            vec!["bad.toml:3", "`duration` must be"],
        ),
        (
            "negative step",
            s("step = 0.01", "step = -0.01"),
            no_file(),
            vec!["bad.toml:6", "`integrator.step`"],
        ),
        (
            "zero step",
            s("step = 0.01", "step = 0.0"),
            no_file(),
            vec!["bad.toml:6", "`integrator.step`"],
        ),
        (
            "rk4 step too short for max_steps",
            s("step = 0.01", "step = 1e-300"),
            no_file(),
            vec![
                "bad.toml:6",
                "`integrator.step` = 1e-300 s over `duration` = 2 s makes 2.000e300 steps",
                "`integrator.max_steps` = 10000000",
                "at least 0.0000002 s",
            ],
        ),
        (
            "negative rtol",
            s("step = 0.01", "step = 0.01\nrtol = -1e-9"),
            no_file(),
            vec!["bad.toml:7", "`integrator.rtol`"],
        ),
        (
            "negative atol",
            s("step = 0.01", "step = 0.01\natol = -1e-9"),
            no_file(),
            vec!["bad.toml:7", "`integrator.atol`"],
        ),
        (
            "zero tolerances",
            s("step = 0.01", "step = 0.01\nrtol = 0.0\natol = 0.0"),
            no_file(),
            vec!["bad.toml:8", "`integrator.atol` must be > 0"],
        ),
        (
            "zero atol",
            s("step = 0.01", "step = 0.01\nrtol = 1e-9\natol = 0.0"),
            no_file(),
            vec!["bad.toml:8", "`integrator.atol` must be > 0", "passes through zero"],
        ),
        (
            "nan rtol",
            s("step = 0.01", "step = 0.01\nrtol = nan"),
            no_file(),
            vec!["bad.toml:7", "`integrator.rtol`", "finite"],
        ),
        (
            "radau5 rtol below ten rounding units",
            s(
                "method = \"rk4\"\nstep = 0.01",
                "method = \"radau5\"\nrtol = 1e-300",
            ),
            no_file(),
            vec!["bad.toml:6", "`integrator.rtol` = 1e-300", "radau5"],
        ),
        (
            "negative max_step",
            s("step = 0.01", "step = 0.01\nmax_step = -1.0"),
            no_file(),
            vec!["bad.toml:7", "`integrator.max_step`"],
        ),
        (
            "zero max_steps",
            s("step = 0.01", "step = 0.01\nmax_steps = 0"),
            no_file(),
            vec!["bad.toml:7", "`integrator.max_steps`"],
        ),
        (
            "rk4 without step",
            s("step = 0.01\n", ""),
            no_file(),
            vec!["bad.toml:4", "`integrator.step` is required"],
        ),
        (
            "negative output interval",
            s("every = 1.0", "every = -1.0"),
            no_file(),
            vec!["bad.toml:8", "`output.every`"],
        ),
        // Non-finite numbers (TOML has nan and inf).
        (
            "nan duration",
            s("duration = 2.0", "duration = nan"),
            no_file(),
            vec!["bad.toml:3", "`duration`"],
        ),
        (
            "inf step",
            s("step = 0.01", "step = inf"),
            no_file(),
            vec!["bad.toml:6", "`integrator.step`"],
        ),
        (
            "inf stiffness",
            s(
                "stiffness = [50.0, 50.0, 50.0, 2.0, 2.0]",
                "stiffness = [50.0, 50.0, inf, 2.0, 2.0]",
            ),
            no_file(),
            vec!["bad.toml:11", "finite"],
        ),
        (
            "nan armature",
            s("duration = 2.0", "duration = 2.0\narmature = nan"),
            no_file(),
            vec!["bad.toml:4", "`armature`"],
        ),
        (
            "negative armature",
            s("duration = 2.0", "duration = 2.0\narmature = -1e-3"),
            no_file(),
            vec!["bad.toml:4", "`armature`"],
        ),
        (
            "nan control gain",
            add(
                "[effects.hinge_control]\n[[effects.hinge_control.hinge]]\nname = \"h4\"\nstart = 0.0\nend = 1.0\nduration = 1.0\nkp = nan\n",
            ),
            no_file(),
            vec!["bad.toml:14", "kp"],
        ),
        (
            "inf stop",
            add(
                "[effects.hinge_stops]\n[[effects.hinge_stops.stop]]\nhinge = \"h4\"\nlower = -inf\n",
            ),
            no_file(),
            vec!["bad.toml:14", "lower"],
        ),
        (
            "inf wheel speed",
            add(&format!("{WHEEL}speed = inf\n")),
            no_file(),
            vec!["bad.toml:14", "speed"],
        ),
        (
            "nan wheel friction",
            add(&format!("{WHEEL}coulomb = nan\n")),
            no_file(),
            vec!["bad.toml:14", "coulomb"],
        ),
        (
            "nan orbit angle",
            add("[orbit]\naltitude = 5e5\ninclination_deg = nan\n"),
            no_file(),
            vec!["bad.toml:13", "inclination_deg"],
        ),
        (
            "nan attitude",
            add(&format!(
                "{WHEEL}[effects.attitude_control]\nkp = 1.0\nkd = 1.0\nattitude = [nan, 0.0, 0.0, 0.0]\n"
            )),
            no_file(),
            vec!["bad.toml:21", "attitude"],
        ),
        (
            "nan attitude gain",
            add(&format!(
                "{WHEEL}[effects.attitude_control]\nkp = 1.0\nkd = nan\n"
            )),
            no_file(),
            vec!["bad.toml:18", "kd"],
        ),
        (
            "nan initial rate",
            s(
                "initial = \"state.json\"",
                "initial = { base = { angular_velocity = [nan, 0.0, 0.0] } }",
            ),
            no_file(),
            vec!["bad.toml:2", "initial.base.angular_velocity"],
        ),
        // Non-physical values.
        (
            "restitution above 1",
            add(
                "[effects.hinge_stops]\n[[effects.hinge_stops.stop]]\nhinge = \"h4\"\nlower = 0.0\naction = \"rebound\"\nrestitution = 2.0\n",
            ),
            no_file(),
            vec!["bad.toml:18", "restitution"],
        ),
        (
            "stops crossed",
            add(
                "[effects.hinge_stops]\n[[effects.hinge_stops.stop]]\nhinge = \"h4\"\nlower = 1.0\nupper = 0.0\n",
            ),
            no_file(),
            vec!["bad.toml:14", "`lower` must be below `upper`"],
        ),
        (
            "zero wheel inertia",
            add(
                "[effects.reaction_wheels]\n[[effects.reaction_wheels.wheel]]\nname = \"x\"\naxis = [1.0, 0.0, 0.0]\ninertia = 0.0\n",
            ),
            no_file(),
            vec!["bad.toml:17", "inertia"],
        ),
        (
            "duplicate wheel",
            add(&format!(
                "{WHEEL}[[effects.reaction_wheels.wheel]]\nname = \"x\"\naxis = [0.0, 1.0, 0.0]\ninertia = 0.1\n"
            )),
            no_file(),
            vec!["bad.toml:19", "duplicate wheel name `x`"],
        ),
        (
            "orbit inside the Earth",
            add("[orbit]\naltitude = 5e5\neccentricity = 0.9\n"),
            no_file(),
            vec!["bad.toml:13", "inside the Earth"],
        ),
        // Unmet needs.
        (
            "gravity without orbit",
            add("[effects.gravity_gradient]\n"),
            no_file(),
            vec!["bad.toml:13", "needs an [orbit] table"],
        ),
        (
            "control without wheels",
            add("[effects.attitude_control]\nkp = 1.0\nkd = 1.0\n"),
            no_file(),
            vec!["bad.toml:13", "needs [effects.reaction_wheels]"],
        ),
        (
            "orbital target without orbit",
            add(&format!(
                "{WHEEL}[effects.attitude_control]\ntarget = \"orbital\"\nkp = 1.0\nkd = 1.0\n"
            )),
            no_file(),
            vec!["bad.toml:18", "needs an [orbit] table"],
        ),
        (
            "wheels without a wheel",
            add("[effects.reaction_wheels]\n"),
            no_file(),
            vec!["bad.toml:13", "needs at least one"],
        ),
        // The model and state files a scene names: their own file and line.
        (
            "missing model",
            s("model = \"satellite.toml\"", "model = \"nope.toml\""),
            no_file(),
            vec!["bad.toml:1", "nope.toml", "does not exist"],
        ),
        (
            "model cycle",
            String::from(SCENE),
            vec![(
                "satellite.toml",
                model.replace(
                    "parent = \"bus\"\nchild = \"link1\"",
                    "parent = \"panel1\"\nchild = \"link1\"",
                ),
            )],
            vec!["satellite.toml", "cycle"],
        ),
        (
            "negative mass",
            String::from(SCENE),
            vec![(
                "satellite.toml",
                model.replace("mass = 800.0", "mass = -800.0"),
            )],
            vec!["satellite.toml:9", "negative"],
        ),
        (
            "non-finite inertia",
            String::from(SCENE),
            vec![("satellite.toml", model.replace("[[900.0,", "[[nan,"))],
            vec!["satellite.toml:10", "not finite"],
        ),
        (
            "state length",
            String::from(SCENE),
            vec![(
                "state.json",
                "{\"hinges\": {\"angle\": [0.0], \"rate\": [0.0]}}".into(),
            )],
            vec!["state.json", "hinges.angle", "expected 5"],
        ),
        (
            "state syntax",
            String::from(SCENE),
            vec![("state.json", "{\"hinges\": ".into())],
            vec!["state.json:1"],
        ),
        // Names that become columns: letters, digits and `_` (a comma or a newline would
        // break the CSV), in the model file and the scene alike.
        (
            "hinge name with a comma",
            String::from(SCENE),
            vec![(
                "satellite.toml",
                model.replace("name = \"h1\"", "name = \"h,1\""),
            )],
            vec![
                "satellite.toml:48",
                "`hinge.name` must be letters, digits and `_`",
                "\"h,1\"",
            ],
        ),
        (
            "body name with a space",
            String::from(SCENE),
            vec![(
                "satellite.toml",
                model.replace("name = \"panel3\"", "name = \"panel 3\""),
            )],
            vec!["satellite.toml:41", "`body.name`", "\"panel 3\""],
        ),
        (
            "thruster name with a comma",
            add(&format!("{THRUSTER}name = \"a,b\"\n")),
            no_file(),
            vec![
                "bad.toml:19",
                "`effects.thrusters.thruster.name` must be letters, digits and `_`",
                "\"a,b\"",
            ],
        ),
        (
            "wheel name with a newline",
            add(&WHEEL.replace("name = \"x\"", "name = \"x\\ny\"")),
            no_file(),
            vec![
                "bad.toml:15",
                "`effects.reaction_wheels.wheel.name`",
                "\"x\\ny\"",
            ],
        ),
        (
            "torquer name with a space",
            format!(
                "epoch = \"2026-03-20T12:00:00 UTC\"\n{SCENE}[orbit]\naltitude = 5e5\n[effects.magnetic]\n[[effects.magnetic.torquer]]\nname = \"m x\"\naxis = [1.0, 0.0, 0.0]\nmax_dipole = 10.0\n"
            ),
            no_file(),
            vec!["bad.toml:18", "`effects.magnetic.torquer.name`", "\"m x\""],
        ),
        // A position and velocity without angular momentum have no orbital plane.
        (
            "radial orbit",
            add("[orbit]\nposition = [7e6, 0.0, 0.0]\nvelocity = [7000.0, 0.0, 0.0]\n"),
            no_file(),
            vec![
                "bad.toml:13",
                "the orbit is degenerate",
                "parallel to `orbit.position`",
                "r × v is zero",
            ],
        ),
        (
            "orbit at rest",
            add("[orbit]\nposition = [7e6, 0.0, 0.0]\nvelocity = [0.0, 0.0, 0.0]\n"),
            no_file(),
            vec!["bad.toml:13", "the orbit is degenerate", "`orbit.velocity` is zero"],
        ),
        // Epochs outside the span the Sun's series is checked over.
        (
            "epoch year 100000",
            format!("epoch = \"100000-01-01T00:00:00 UTC\"\n{SCENE}"),
            no_file(),
            vec!["bad.toml:1", "`epoch`", "outside 1900 to 2100"],
        ),
        (
            "epoch year 1",
            format!("epoch = \"0001-01-01T00:00:00 UTC\"\n{SCENE}"),
            no_file(),
            vec!["bad.toml:1", "`epoch`", "outside 1900 to 2100"],
        ),
        (
            "epoch year 9999",
            format!("epoch = \"9999-06-01T00:00:00 UTC\"\n{SCENE}"),
            no_file(),
            vec!["bad.toml:1", "`epoch`", "outside 1900 to 2100"],
        ),
        (
            "run past 2100",
            format!("epoch = \"2099-12-31T23:59:59 UTC\"\n{SCENE}"),
            no_file(),
            vec!["bad.toml:1", "`epoch`", "ends in year 2100"],
        ),
        // A sampled law whose period makes more samples than `--max-rows` (each a stop of
        // the integrator): refused before the run, which would take minutes.
        (
            "sensor period too short",
            add("[sensors]\n[[sensors.gyro]]\nname = \"g\"\nbody = \"bus\"\nperiod = 1e-6\n"),
            no_file(),
            vec![
                "bad.toml:17",
                "sensor `g`: `period` = 0.000001 s over `duration` = 2 s makes ",
                "samples, more than the limit of 1000000",
                "--max-rows",
            ],
        ),
        (
            "thruster period too short",
            add(&format!("{}name = \"t\"\n", THRUSTER.replace("period = 0.1", "period = 1e-6"))),
            no_file(),
            vec![
                "bad.toml:14",
                "`effects.thrusters`: `period` = 0.000001 s",
                "samples, more than the limit of 1000000",
            ],
        ),
    ]
}

/// Every bad scene: exit status 2, one message on standard error naming the file and the
/// line or the field, nothing on standard output, no panic.
#[test]
fn every_bad_scene_exits_2_with_the_file_and_line_or_field() {
    let dir = setup("bad");
    let mut failures = Vec::new();
    let cases = cases();
    for (case, text, files, needles) in &cases {
        for f in ["satellite.toml", "state.json"] {
            std::fs::copy(root().join("examples").join(f), dir.join(f)).unwrap();
        }
        for (name, content) in files {
            std::fs::write(dir.join(name), content).unwrap();
        }
        std::fs::write(dir.join("bad.toml"), text).unwrap();
        let o = satsim_in(&dir, &["run", "bad.toml"]);
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        println!("{case}: {}", err.trim_end());
        let mut why = Vec::new();
        if o.status.code() != Some(2) {
            why.push(format!("exit status {:?}", o.status.code()));
        }
        if !o.stdout.is_empty() {
            why.push("standard output is not empty".into());
        }
        if err.contains("internal error") || err.contains("panicked") {
            why.push("panic".into());
        }
        if err.trim_end().lines().count() != 1 {
            why.push("not one line".into());
        }
        for n in needles {
            if !err.contains(n) {
                why.push(format!("no `{n}`"));
            }
        }
        if !why.is_empty() {
            failures.push(format!(
                "{case}: {}\n    {}",
                why.join(", "),
                err.trim_end()
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

/// The preprint satellite's middle gimbal hinge latching at 90°: gimbal lock.
const LOCK: &str = r#"model = "satellite.toml"
duration = 4.0
[initial]
hinges = { angle = [0.0, 0.0, 0.0, 0.0, 0.0], rate = [0.0, 1.0, 0.0, 0.0, 0.0] }
[integrator]
method = "dp54"
[output]
every = 0.1
plots = false
[effects.hinge_stops]
[[effects.hinge_stops.stop]]
hinge = "h2"
upper = 1.5707963267948966
"#;

/// A scene driven into gimbal lock fails (exit 1) with the hinges and the time and keeps its
/// rows; the same scene with the scene key `armature` (one number for every hinge) runs
/// through (exit 0).
#[test]
fn gimbal_lock_is_refused_with_hinges_and_time_and_armature_runs_through() {
    let dir = setup("lock");
    std::fs::write(dir.join("lock.toml"), LOCK).unwrap();
    let o = satsim_in(&dir, &["run", "lock.toml"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(o.stdout.is_empty());
    assert!(
        err.contains("lock.toml: the run failed: system error at t = 1.65")
            && err.contains("singular configuration at hinge `h1` (gimbal lock with `h2`, `h3`")
            && err.contains("holds the rows up to t = 1.6 s")
            && !err.contains("masses span"),
        "{err}"
    );
    let (_, rows) = csv(&dir.join("out/lock/trajectory.csv"));
    assert_eq!(rows.len(), 17);

    let fixed = LOCK.replace("duration = 4.0", "duration = 4.0\narmature = 1e-3");
    std::fs::write(dir.join("lock.toml"), fixed).unwrap();
    let o = satsim_in(&dir, &["run", "lock.toml"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, rows) = csv(&dir.join("out/lock/trajectory.csv"));
    assert_eq!(rows.len(), 41);
}

/// A panel of 1e20 kg (a slip of units) on the 800 kg bus: the dynamics are singular at the
/// first step, and the message says why, naming the heaviest and the lightest body; the
/// same under a flexible panel whose beam's `rho_A` is 1e20 kg/m.
#[test]
fn a_singular_solve_of_masses_beyond_round_off_says_so() {
    let dir = setup("mass-span");
    std::fs::write(dir.join("scene.toml"), SCENE).unwrap();
    // The scene's run on `example` with `from` made `to`: its exit status and message.
    let run = |example: &str, from: &str, to: &str| {
        let model = std::fs::read_to_string(root().join(example)).unwrap();
        let changed = model.replacen(from, to, 1);
        assert_ne!(changed, model, "{from}");
        std::fs::write(dir.join("satellite.toml"), changed).unwrap();
        let o = satsim_in(&dir, &["run", "scene.toml"]);
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    // The run fails at its first step (exit 1), keeping the message of the solve.
    let (code, err) = run("examples/satellite.toml", "mass = 20.0", "mass = 1e20");
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("the run failed: system error at t = 0: singular configuration at hinge")
            && err.contains("the bodies' masses span 5.0e18: body `panel1` has 1e20 kg")
            && err.contains("body `panel2` 20 kg")
            && err.contains("check the units"),
        "{err}"
    );
    let (code, err) = run(
        "examples/satellite_flexible.toml",
        "rho_A = 10.0",
        "rho_A = 1e20",
    );
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("body `panel1` has 1e20 kg (with any beam's rho_A x length)")
            && err.contains("check the units (kg; kg/m for a beam's rho_A)"),
        "{err}"
    );
}

/// Ctrl-C: `satsim run` on a long scene, SIGINT after a second: exit status 130, the message
/// says where it stopped and how many rows it wrote, and the CSV holds exactly those rows,
/// each complete.
#[cfg(unix)]
#[test]
fn ctrl_c_stops_cleanly_and_keeps_the_csv() {
    let dir = setup("sigint");
    std::fs::write(
        dir.join("long.toml"),
        SCENE
            .replace("duration = 2.0", "duration = 1e7")
            // 10⁹ steps: a budget that holds them, or the run is refused before it starts.
            .replace("step = 0.01", "step = 0.01\nmax_steps = 2000000000")
            .replace("every = 1.0", "every = 0.05"),
    )
    .unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_satsim"))
        // 2·10⁸ rows: beyond the default row limit, which this endless run lifts.
        .args(["run", "long.toml", "--max-rows", "1000000000"])
        .current_dir(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until rows are being written, then interrupt.
    let csv_path = dir.join("out/long/trajectory.csv");
    let start = Instant::now();
    while std::fs::read_to_string(&csv_path).map_or(0, |t| t.lines().count()) < 5 {
        assert!(start.elapsed() < Duration::from_secs(60), "no rows written");
        std::thread::sleep(Duration::from_millis(20));
    }
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(o.stdout.is_empty());
    let (_, rows) = csv(&csv_path);
    let last = rows.last().unwrap()[0];
    let expected = format!(
        "interrupted at t = {last} s; {} rows written to out/long/trajectory.csv",
        rows.len()
    );
    assert_eq!(err.trim_end(), expected);
    // Every row up to the last is there, in order.
    for (k, r) in rows.iter().enumerate() {
        assert!(
            (r[0] - 0.05 * k as f64).abs() < 1e-9,
            "row {k}: t = {}",
            r[0]
        );
    }
}

/// Two SIGINTs in a row (as `timeout -s INT` or a double key press sends): the first starts
/// the clean stop, the second (within the grace period) must not kill the process before the
/// message and the complete CSV are out.
#[cfg(unix)]
#[test]
fn two_ctrl_c_in_a_row_still_stop_cleanly() {
    let dir = setup("sigint2");
    std::fs::write(
        dir.join("long.toml"),
        SCENE
            .replace("duration = 2.0", "duration = 1e7")
            // 10⁹ steps: a budget that holds them, or the run is refused before it starts.
            .replace("step = 0.01", "step = 0.01\nmax_steps = 2000000000")
            .replace("every = 1.0", "every = 500.0"),
    )
    .unwrap();
    let child = Command::new(env!("CARGO_BIN_EXE_satsim"))
        .args(["run", "long.toml"])
        .current_dir(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let csv_path = dir.join("out/long/trajectory.csv");
    let start = Instant::now();
    // Rows far apart (about 0.25 s of work each), so that the second signal arrives while the
    // first is still waiting for its row.
    while std::fs::read_to_string(&csv_path).map_or(0, |t| t.lines().count()) < 3 {
        assert!(start.elapsed() < Duration::from_secs(60), "no rows written");
        std::thread::sleep(Duration::from_millis(20));
    }
    // Two signals 30 ms apart (back to back they could merge into one pending signal).
    let pid = child.id().to_string();
    let status = Command::new("sh")
        .args([
            "-c",
            &format!("kill -INT {pid}; sleep 0.03; kill -INT {pid}"),
        ])
        .status()
        .unwrap();
    assert!(status.success());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err} ({:?})", o.status);
    let (_, rows) = csv(&csv_path);
    let last = rows.last().unwrap()[0];
    assert_eq!(
        err.trim_end(),
        format!(
            "interrupted at t = {last} s; {} rows written to out/long/trajectory.csv",
            rows.len()
        )
    );
}

/// Initial rates beyond 2 rad/s (degrees per second written as radians?) run, with a warning
/// at the `[initial]` table's line naming the entry and the value in radians, as hinge angles
/// beyond ±2π are warned.
#[test]
fn rates_beyond_2_rad_per_s_warn_as_degrees_would() {
    let dir = setup("rates");
    let text = SCENE.replace("initial = \"state.json\"\n", "").replace(
        "[integrator]",
        "[initial]\nbase = { angular_velocity = [5.0, 5.0, 5.0] }\nhinges = { angle = [0.0, 0.0, 0.0, 0.0, 0.0], rate = [0.0, 0.0, 0.0, -3.0, 0.0] }\n[integrator]",
    );
    std::fs::write(dir.join("rates.toml"), text).unwrap();
    let o = satsim_in(&dir, &["run", "rates.toml"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("rates.toml:3: initial.base.angular_velocity: entry 0 is 5 rad/s, beyond ±2 rad/s: rates are in rad/s (for 5 deg/s write 0.087266)"),
        "{err}"
    );
    assert!(
        err.contains("rates.toml:3: initial.hinges.rate: entry 3 is -3 rad/s"),
        "{err}"
    );
    // Rates within the bound: no warning.
    std::fs::write(dir.join("calm.toml"), SCENE).unwrap();
    let o = satsim_in(&dir, &["run", "calm.toml"]);
    assert!(o.status.success());
    assert!(
        o.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// `--set initial.base.attitude` takes either form whatever the scene writes: a quaternion
/// over Euler angles, and the keys of one table form over a quaternion or the other form.
#[test]
fn set_takes_either_attitude_form() {
    let dir = setup("attitude_forms");
    let euler = SCENE.replace("initial = \"state.json\"\n", "").replace(
        "[integrator]",
        "[initial]\nbase = { attitude = { euler_deg = [90.0, 0.0, 0.0], sequence = \"zyx\" } }\nhinges = { angle = [0.0, 0.0, 0.0, 0.0, 0.0], rate = [0.0, 0.0, 0.0, 0.0, 0.0] }\n[integrator]",
    );
    std::fs::write(dir.join("euler.toml"), euler).unwrap();
    std::fs::write(dir.join("quaternion.toml"), SCENE).unwrap();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    for (scene, sets, q) in [
        (
            "euler.toml",
            vec!["initial.base.attitude=[1, 0, 0, 0]"],
            [1.0, 0.0, 0.0, 0.0],
        ),
        (
            "quaternion.toml",
            vec![
                "initial.base.attitude.euler_deg=[90.0, 0.0, 0.0]",
                "initial.base.attitude.sequence=zyx",
            ],
            [h, 0.0, 0.0, h],
        ),
        (
            "euler.toml",
            vec![
                "initial.base.attitude.axis=[1.0, 0.0, 0.0]",
                "initial.base.attitude.angle_deg=90",
            ],
            [h, h, 0.0, 0.0],
        ),
        (
            "quaternion.toml",
            vec!["initial.base.attitude={ axis = [0.0, 1.0, 0.0], angle_deg = 90.0 }"],
            [h, 0.0, h, 0.0],
        ),
    ] {
        let mut args = vec!["run", scene, "--out", "out"];
        for s in &sets {
            args.extend(["--set", s]);
        }
        let o = satsim_in(&dir, &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{scene} {sets:?}: {err}");
        let (header, rows) = csv(&dir.join("out/trajectory.csv"));
        let col = |name: &str| header.iter().position(|c| c == name).unwrap();
        let got = ["q_w", "q_x", "q_y", "q_z"].map(|c| rows[0][col(c)]);
        for (g, w) in got.iter().zip(q) {
            assert!(
                (g - w).abs() < 1e-8,
                "{scene} {sets:?}: q = {got:?}, expected {q:?}"
            );
        }
    }
}

/// A bus on an orbit whose velocity is all but radial (1 mm/s across 10 km/s inwards): its
/// periapsis is a fraction of a micrometre from the Earth's centre, where the gravity's
/// singularity shortens the steps until they no longer move the time on.
const FALL: &str = r#"duration = 2000.0
[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.0, 0.0, 10.0]]
[orbit]
position = [7.0e6, 0.0, 0.0]
velocity = [-1.0e4, 1.0e-3, 0.0]
[integrator]
method = "dp54"
[output]
every = 10.0
plots = false
view = false
"#;

/// A step size underflow says when, which state the steps were last shortened for (named
/// as its column), why, and what to try: an implicit method after an explicit one, looser
/// tolerances (with their values), the initial state; under `radau5` it does not offer
/// `radau5` again. The run exits 1 and keeps its rows.
#[test]
fn a_step_size_underflow_names_the_state_and_what_to_try() {
    let dir = setup("underflow");
    std::fs::write(dir.join("fall.toml"), FALL).unwrap();
    let o = satsim_in(&dir, &["run", "fall.toml"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("fall.toml: the run failed: step size underflow at t = 454.42")
            && err.contains(": the steps were last shortened for `orbit_v_y`;")
            && err.contains("or it runs into a singularity or a jump in the forces")
            && err.contains("The method `dp54` is explicit and must follow every motion: try `integrator.method = \"radau5\"`")
            && err.contains("looser tolerances (`integrator.rtol` = 1e-9 and `atol` = 1e-12 now)")
            && err.contains("check the initial state for a value far too large")
            && err.contains("holds the rows up to t = 450 s"),
        "{err}"
    );
    let implicit = FALL.replace("\"dp54\"", "\"radau5\"\nrtol = 1e-8\natol = 1e-10");
    std::fs::write(dir.join("fall.toml"), implicit).unwrap();
    let o = satsim_in(&dir, &["run", "fall.toml"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("step size underflow at t = 454.42")
            && err.contains(": the steps were last shortened for `orbit_")
            && err.contains(
                "Try looser tolerances (`integrator.rtol` = 1e-8 and `atol` = 1e-10 now)"
            )
            && !err.contains("explicit")
            && !err.contains("\"radau5\""),
        "{err}"
    );
}
