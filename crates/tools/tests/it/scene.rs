//! Scene files: state layout derived from the enabled effects, effects visited only when
//! enabled, strict parsing with lines, needs.

use satsim_integrate::{Output, System};
use satsim_spacecraft::simulation::attitude_norm_error;
use satsim_tools::scene::Scene;
use std::path::{Path, PathBuf};

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

/// A scene next to the examples' model files (so `model = "../satellite.toml"` resolves).
fn parse(text: &str) -> Result<Scene, String> {
    Scene::parse(text, &examples().join("scenes/test.toml")).map_err(|e| e.to_string())
}

const BASE: &str = r#"model = "../satellite.toml"
duration = 2.0
[initial]
hinges = { angle = [0.0, 0.1, 0.0, 1.0, -1.0], rate = [0.0, 0.0, 0.0, 0.1, 0.0] }
[integrator]
method = "rk4"
step = 0.01
"#;

const ORBIT: &str = "[orbit]\naltitude = 500e3\ninclination_deg = 51.6\n";
const SPRINGS: &str = "[effects.hinge_springs]\nstiffness = [50.0, 50.0, 50.0, 2.0, 2.0]\ndamping = [1.0, 1.0, 1.0, 1.0, 1.0]\n";
const GG: &str = "[effects.gravity_gradient]\nmodel = \"full\"\n";
const WHEELS: &str = r#"[effects.reaction_wheels]
[[effects.reaction_wheels.wheel]]
name = "x"
axis = [1.0, 0.0, 0.0]
inertia = 0.05
[[effects.reaction_wheels.wheel]]
name = "y"
axis = [0.0, 1.0, 0.0]
inertia = 0.05
[[effects.reaction_wheels.wheel]]
name = "z"
axis = [0.0, 0.0, 1.0]
inertia = 0.05
"#;
const CONTROL: &str = "[effects.attitude_control]\nkp = 5.0\nkd = 50.0\n";

fn scene(parts: &[&str]) -> Scene {
    let text: String = std::iter::once(BASE).chain(parts.iter().copied()).collect();
    parse(&text).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

#[test]
fn the_state_holds_only_the_enabled_effects_states() {
    // [attitude 4, angles 5, ω 3, velocity 3, rates 5] = 20, then the effects' states
    let cases: [(&[&str], usize, &[&str]); 6] = [
        (&[], 20, &[]),
        (&[SPRINGS], 20, &["hinge_springs"]),
        (&[ORBIT], 26, &["orbit"]),
        (
            &[ORBIT, GG, SPRINGS],
            26,
            &["orbit", "gravity_gradient", "hinge_springs"],
        ),
        (&[WHEELS], 23, &["reaction_wheels"]),
        (
            &[ORBIT, GG, SPRINGS, WHEELS, CONTROL],
            29,
            &[
                "orbit",
                "gravity_gradient",
                "hinge_springs",
                "attitude_control",
                "reaction_wheels",
            ],
        ),
    ];
    for (parts, len, names) in cases {
        // Plus the energy budget's two work states, whatever the effects.
        let len = len + 2;
        let sim = scene(parts).simulation().unwrap();
        assert_eq!(sim.layout().len, len, "{names:?}");
        assert_eq!(sim.x0().len(), len);
        assert_eq!(sim.effect_names(), names);
    }
}

#[test]
fn a_disabled_effect_adds_no_state_and_is_never_visited() {
    let off = "[effects.gravity_gradient]\nenabled = false\n[effects.hinge_springs]\nstiffness = [1.0, 1.0, 1.0, 1.0, 1.0]\nenabled = false\n";
    let s = scene(&[ORBIT, off]);
    assert!(!s.effects.contains("gravity_gradient") && !s.effects.contains("hinge_springs"));
    let mut sim = s.simulation().unwrap();
    assert_eq!(sim.effect_names(), ["orbit"]);
    assert_eq!(sim.layout().len, 26 + 2); // + the energy budget's work states
    let stats = sim
        .run(&s.options, s.duration, &Output::Interval(1.0), |_, _| {
            Ok::<(), ()>(())
        })
        .unwrap();
    // Every rhs evaluation visited the one enabled effect, and nothing else exists to visit.
    assert_eq!(sim.effect_calls(), [stats.rhs_evals as u64]);
    assert_eq!(sim.rhs_evals(), stats.rhs_evals as u64);
}

#[test]
fn every_enabled_effect_is_visited_at_every_evaluation() {
    let s = scene(&[ORBIT, GG, SPRINGS, WHEELS, CONTROL]);
    let mut sim = s.simulation().unwrap();
    let stats = sim
        .run(&s.options, s.duration, &Output::Interval(1.0), |_, _| {
            Ok::<(), ()>(())
        })
        .unwrap();
    assert_eq!(sim.effect_calls(), vec![stats.rhs_evals as u64; 5]);
}

#[test]
fn the_quaternion_stays_normalised() {
    let s = scene(&[SPRINGS]);
    let mut sim = s.simulation().unwrap();
    let mut opts = s.options.clone();
    opts.fixed_step = Some(0.05);
    let x0 = sim.x0().to_vec();
    let mut worst: f64 = 0.0;
    let layout = sim.layout().clone();
    satsim_integrate::integrate(&mut sim, &opts, 0.0, &x0, 20.0, &Output::Steps, |_, x| {
        worst = worst.max(attitude_norm_error(&layout, x));
        std::ops::ControlFlow::Continue(())
    })
    .unwrap();
    assert!(worst < 1e-12, "{worst}");
}

#[test]
fn output_columns_follow_the_contract() {
    let sim = scene(&[ORBIT, GG, WHEELS, CONTROL]).simulation().unwrap();
    let cols = sim.columns();
    for c in [
        "t",
        "q_w",
        "q_x",
        "q_y",
        "q_z",
        "omega_x",
        "omega_y",
        "omega_z",
        "angle_h1",
        "angle_h5",
        "rate_h1",
        "rate_h5",
        "kinetic_energy",
        "total_energy",
        "h_x",
        "h_y",
        "h_z",
        "orbit_radius",
        "wheel_x_speed",
        "wheel_z_torque",
    ] {
        assert!(cols.iter().any(|x| x == c), "{c} missing from {cols:?}");
    }
    let mut sim = sim;
    let mut row = Vec::new();
    let x0 = sim.x0().to_vec();
    sim.row(0.0, &x0, &mut row).unwrap();
    assert_eq!(row.len(), cols.len());
}

#[test]
fn rhs_rejects_nothing_on_a_valid_state() {
    let mut sim = scene(&[ORBIT, GG, SPRINGS, WHEELS, CONTROL])
        .simulation()
        .unwrap();
    let x0 = sim.x0().to_vec();
    let mut dx = vec![0.0; x0.len()];
    sim.rhs(0.0, &x0, &mut dx).unwrap();
    assert!(dx.iter().all(|v| v.is_finite()));
}

fn error(text: &str) -> String {
    parse(text)
        .err()
        .unwrap_or_else(|| panic!("accepted:\n{text}"))
}

#[test]
fn scene_errors_name_the_file_and_line() {
    let e = error(&format!(
        "{BASE}[effects.hinge_springs]\nstifness = [1.0]\n"
    ));
    assert!(
        e.contains("test.toml:9") && e.contains("unknown key `stifness`"),
        "{e}"
    );
    let e = error(&format!("{BASE}durration = 3.0\n"));
    assert!(
        e.contains("test.toml:8") && e.contains("unknown key `durration`"),
        "{e}"
    );
    let e = error(&BASE.replace("duration = 2.0\n", ""));
    assert!(e.contains("missing required key `duration`"), "{e}");
    let e = error(&BASE.replace("duration = 2.0", "duration = -2.0"));
    assert!(
        e.contains("test.toml:2") && e.contains("`duration` must be"),
        "{e}"
    );
    let e = error(&BASE.replace("step = 0.01", "step = -0.01"));
    assert!(
        e.contains("test.toml:7") && e.contains("`integrator.step`"),
        "{e}"
    );
    let e = error(&BASE.replace("\"rk4\"", "\"euler\""));
    assert!(
        e.contains("test.toml:6") && e.contains("unknown integration method"),
        "{e}"
    );
    let e = error(&format!("{BASE}[integrator2]\n"));
    assert!(e.contains("unknown key"), "{e}");
    let e = error(&format!(
        "{BASE}[effects.hinge_springs]\nstiffness = [1.0, 2.0]\n"
    ));
    assert!(
        e.contains("test.toml:9") && e.contains("expected 5 entries"),
        "{e}"
    );
    let e = error(&format!(
        "{BASE}[effects.hinge_stops]\n[[effects.hinge_stops.stop]]\nhinge = \"h9\"\nlower = 0.0\n"
    ));
    assert!(
        e.contains("test.toml:10") && e.contains("unknown hinge `h9`"),
        "{e}"
    );
    let e = error(&format!("{BASE}[output]\nevery = 0.0\n"));
    assert!(
        e.contains("test.toml:9") && e.contains("`output.every`"),
        "{e}"
    );
    let e = error(&format!(
        "{BASE}[orbit]\naltitude = 500e3\nposition = [7e6, 0, 0]\n"
    ));
    assert!(e.contains("test.toml:8") && e.contains("[orbit]"), "{e}");
    let e = error("duration = 1.0\n");
    assert!(e.contains("missing required key `model`"), "{e}");
    let e = error(&format!("{BASE}[initial2]\n"));
    assert!(e.contains("unknown key"), "{e}");
    let e = error(
        "model = \"../satellite.toml\"\nduration = 1\ninitial = { hinges = { angle = [0.0], rate = [0.0] } }\n",
    );
    assert!(
        e.contains("initial.hinges.angle") && e.contains("expected 5"),
        "{e}"
    );
    let e = error("model = \"nope.toml\"\nduration = 1\n");
    assert!(
        e.contains("test.toml:1:") && e.contains("nope.toml") && e.contains("does not exist"),
        "{e}"
    );
}

/// A fixed-length array with too many entries is refused at its line, as one with too few,
/// wherever the scene holds it: an effect's table, `[orbit]`, an inline model.
#[test]
fn scene_arrays_with_too_many_entries_are_refused_at_their_line() {
    let four = "invalid length 4, expected an array of length 3";
    let wheels = WHEELS.replacen("[1.0, 0.0, 0.0]", "[1.0, 0.0, 0.0, \"junk\"]", 1);
    let orbit = "[orbit]\nposition = [7e6, 0, 0, 1]\nvelocity = [0, 7.5e3, 0]\n";
    let inline = "duration = 1.0\n[[model.body]]\nname = \"bus\"\nmass = 1.0\n\
                  inertia = [[1.0, 0.0, 0.0, 99.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]\n";
    for (text, line) in [
        (format!("{BASE}{wheels}"), 11),
        (format!("{BASE}{orbit}"), 9),
        (inline.to_owned(), 5),
    ] {
        let e = error(&text);
        assert!(
            e.contains(&format!("test.toml:{line}: ")) && e.contains(four),
            "{e}"
        );
    }
    let e = error(&format!("{BASE}{}", orbit.replace("0, 0, 1]", "0]")));
    assert!(
        e.contains("test.toml:9: ") && e.contains("invalid length 2, expected an array"),
        "{e}"
    );
}

#[test]
fn unmet_needs_say_what_to_add() {
    let e = error(&format!("{BASE}{GG}"));
    assert!(
        e.contains("test.toml:8") && e.contains("effects.gravity_gradient needs an [orbit] table"),
        "{e}"
    );
    let e = error(&format!("{BASE}{CONTROL}"));
    assert!(
        e.contains("effects.attitude_control needs [effects.reaction_wheels]"),
        "{e}"
    );
    let e = error(&format!(
        "{BASE}{WHEELS}[effects.attitude_control]\ntarget = \"orbital\"\nkp = 1.0\nkd = 1.0\n"
    ));
    assert!(e.contains("needs an [orbit] table"), "{e}");
    let fixed = "duration = 1.0\n[model]\nbase = { kind = \"fixed\" }\n[[model.body]]\nname = \"b\"\nmass = 1.0\ninertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n[orbit]\naltitude = 5e5\n[effects.gravity_gradient]\n";
    let e = error(fixed);
    assert!(e.contains("free-floating root"), "{e}");
}

#[test]
fn an_inline_model_reports_lines_in_the_scene() {
    let text = "duration = 1.0\n[model]\n[[model.body]]\nname = \"bus\"\nmass = 10.0\ninertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n[[model.body]]\nname = \"p\"\nmass = 1.0\ninertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n[[model.hinge]]\nname = \"h\"\nparent = \"bsu\"\nchild = \"p\"\naxis = [0, 0, 1]\n";
    let e = error(text);
    assert!(
        e.contains("test.toml:1") && e.contains("unknown parent body `bsu`"),
        "{e}"
    );
    let ok = text.replace("bsu", "bus");
    let s = parse(&ok).unwrap();
    assert_eq!(s.model.nv(), 7);
    assert_eq!(s.simulation().unwrap().layout().len, 4 + 1 + 6 + 1 + 2);
}

#[test]
fn an_unknown_effect_section_names_its_line_the_known_ones_and_how_to_register_one() {
    // BASE has 7 lines; the section header is line 8.
    let e = error(&format!("{BASE}[effects.magnetorquer]\ndipole = 1.0\n"));
    assert!(
        e.contains("test.toml:8")
            && e.contains("unknown key `magnetorquer` in [effects]")
            && e.contains("gravity_gradient, hinge_springs, hinge_control, hinge_stops, attitude_control, reaction_wheels")
            && e.contains("`Registry::register`")
            && e.contains("cargo run --example custom_effect"),
        "{e}"
    );
}

/// The scene is parsed once (`satsim_tree::io::Document`): a syntax error is still TOML's at
/// its line, and an integer too large for any key, which the parse accepts, is an error at
/// its key and line where a section or the scene's own keys read it.
#[test]
fn a_scene_parsed_once_names_syntax_and_value_errors_at_their_lines() {
    let e = error(&format!("{BASE}[orbit\n"));
    assert!(e.contains("test.toml:8"), "{e}");
    let e = error(&BASE.replace("duration = 2.0", "duration = 99999999999999999999"));
    assert!(e.contains("test.toml:2") && e.contains("`duration`"), "{e}");
    let e = error(&format!(
        "{BASE}[effects.hinge_springs]\nstiffness = [1, 1, 1, 1, 99999999999999999999]\n"
    ));
    assert!(e.contains("test.toml:9") && e.contains("stiffness"), "{e}");
}

#[test]
fn the_file_order_of_sections_does_not_change_the_run_order() {
    // Written wheels-last and wheels-first: the controller runs before the wheels either way.
    for text in [
        format!("{BASE}{WHEELS}{CONTROL}"),
        format!("{BASE}{CONTROL}{WHEELS}"),
    ] {
        let sim = parse(&text).unwrap().simulation().unwrap();
        assert_eq!(sim.effect_names(), ["attitude_control", "reaction_wheels"]);
    }
}
