//! A scene with a flexible body (contract section 14) through the tools: the inline model and
//! `[initial] flexible` read into the scene (modal coordinates in the model's order), the
//! linear states' order, `armature` kept with the modes, and stepping (what Python's
//! `satsim.Simulation` drives) reproducing the run bit for bit with the elastic columns.

use satsim_tools::api::run_scene;
use satsim_tools::linearize::linearize;
use satsim_tools::scene::Scene;
use satsim_tools::stepping::SceneStepper;
use std::path::Path;

/// A hub with a hinged panel whose beam has two modes, then a second flexible body (the
/// hub's own antenna, three modes, its highest at 276 rad/s: within RK4's reach at 5 ms) to
/// check the order of the elastic coordinates.
fn scene(extra: &str) -> Scene {
    Scene::parse(&scene_text(extra), Path::new("flex.toml")).expect("a valid scene")
}

/// [`scene`]'s text.
fn scene_text(extra: &str) -> String {
    format!(
        r#"duration = 2.0
{extra}
[model]
[[model.body]]
name = "hub"
mass = 50.0
inertia = [[5.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 5.0]]
[model.body.flexible]
beam = {{ root = [0.0, 0.0, 0.5], axis = [0.0, 0.0, 1.0], bend = [1.0, 0.0, 0.0],
         length = 1.0, EI = 20.0, rho_A = 1.0, modes = 3 }}
[[model.body]]
name = "panel"
mass = 2.0
inertia = [[0.2, 0.0, 0.0], [0.0, 0.2, 0.0], [0.0, 0.0, 0.2]]
[model.body.flexible]
beam = {{ root = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], bend = [0.0, 0.0, 1.0],
         length = 2.0, EI = 500.0, rho_A = 2.0, modes = 2 }}
damping = 0.01
[[model.hinge]]
name = "h"
parent = "hub"
child = "panel"
axis = [1.0, 0.0, 0.0]
at = [0.0, 0.6, 0.0]
[initial]
base = {{ angular_velocity = [0.01, 0.02, 0.0] }}
hinges = {{ angle = [0.1], rate = [0.0] }}
flexible = {{ panel = {{ eta = [0.02, -0.01] }}, hub = {{ etadot = [0.0, 0.1, 0.0] }} }}
[integrator]
method = "rk4"
step = 0.005
[output]
every = 0.1
plots = false
view = false
[effects.hinge_springs]
stiffness = [10.0]
"#
    )
}

#[test]
fn the_initial_elastic_state_is_in_the_models_order() {
    let s = scene("");
    let f = s.flexible.as_ref().expect("flexible bodies");
    assert_eq!(f.n_elastic(), 5);
    // Bodies in depth-first order (hub, panel), modes from 1.
    assert_eq!(s.elastic.eta, [0.0, 0.0, 0.0, 0.02, -0.01]);
    assert_eq!(s.elastic.etadot, [0.0, 0.1, 0.0, 0.0, 0.0]);
    let lin = linearize(&s).unwrap();
    let names: Vec<&str> = lin.states.iter().map(String::as_str).collect();
    let at = names.iter().position(|n| *n == "rate_h").unwrap();
    assert_eq!(
        &names[at + 1..at + 11],
        [
            "eta_hub_1",
            "eta_hub_2",
            "eta_hub_3",
            "eta_panel_1",
            "eta_panel_2",
            "etadot_hub_1",
            "etadot_hub_2",
            "etadot_hub_3",
            "etadot_panel_1",
            "etadot_panel_2"
        ]
    );
    // d(η̈)/dη of the panel's first mode is −ω₁² (its own stiffness) to the linearisation's
    // accuracy: the row of etadot_panel_1, the column of eta_panel_1.
    let w2 = f.stiffness()[3];
    let (r, c) = (
        names.iter().position(|n| *n == "etadot_panel_1").unwrap(),
        at + 4,
    );
    assert!(lin.a[(r, c)] < -0.5 * w2, "{} vs -{w2}", lin.a[(r, c)]);
    // The armature keeps the modes (and their damping).
    let a = scene("armature = 0.01");
    let fa = a.flexible.as_ref().unwrap();
    assert_eq!(fa.stiffness(), f.stiffness());
    assert_eq!(fa.damping(), f.damping());
}

#[test]
fn stepping_a_flexible_scene_reproduces_the_run_with_its_elastic_columns() {
    let s = scene("");
    let run = run_scene(&s, || false).unwrap();
    let mut st = SceneStepper::new(&s, None, "flex").unwrap();
    assert_eq!(st.columns(), run.columns.as_slice());
    for c in ["eta_panel_2", "etadot_hub_3", "tip_panel", "tip_hub"] {
        assert!(
            run.columns.iter().any(|n| n == c),
            "{c} in {:?}",
            run.columns
        );
    }
    // The inputs are the hinges' torques: the elastic coordinates are states, not inputs.
    assert_eq!(st.inputs(), ["torque_h"]);
    let row = st.row().unwrap();
    let col = |n: &str| run.columns.iter().position(|c| c == n).unwrap();
    assert_eq!(row[col("eta_panel_1")], 0.02);
    assert_eq!(row[col("etadot_hub_2")], 0.1);
    for dt in [0.3, 0.005, 0.695, 1.0] {
        st.advance(dt).unwrap();
    }
    assert_eq!(st.trajectory(), &run);
}

/// The largest |η| of a run's rows (`None` when the run failed).
fn largest_eta(scene: &Scene) -> Option<f64> {
    let t = run_scene(scene, || false).ok()?;
    let cols: Vec<usize> = (0..t.columns.len())
        .filter(|&c| t.columns[c].starts_with("eta_"))
        .collect();
    Some(
        t.rows()
            .flat_map(|r| cols.iter().map(move |&c| r[c].abs()))
            .fold(0.0, f64::max),
    )
    .filter(|m: &f64| m.is_finite())
}

#[test]
fn an_rk4_step_beyond_the_highest_modes_stability_limit_is_refused_and_the_limit_is_sharp() {
    use satsim_tools::scene::flexible::{highest_frequency, mode_of};
    use satsim_tools::scene::step_limit::RK4_LIMIT;
    let s = scene("");
    let flex = s.flexible.as_ref().unwrap();
    let q = s.initial_q();
    let (w, e) = highest_frequency(flex, &q).unwrap();
    // The hub's antenna (EI 20, ρA 1, 1 m): its third clamped mode is 61.70 rad/s × 4.47 =
    // 275.9 rad/s; on the free hub its coupled frequency is a little higher.
    assert_eq!(mode_of(flex, e), ("hub".to_string(), 3));
    assert!(w > 275.0 && w < 300.0, "{w}");
    let limit = RK4_LIMIT / w;
    // Just under the limit the modes stay bounded (RK4 damps them a little); just over it
    // they grow by about 15 % per step: the limit the check uses is the dynamics' own.
    let with_step = |h: f64| {
        let mut s = scene("");
        s.options = s.options.clone().with_fixed_step(h);
        s.duration = 2.0;
        // The highest mode deflected at the start.
        let third = s.flexible.as_ref().unwrap().elastic_offset(0) + 2;
        s.elastic.eta[third] = 0.01;
        s
    };
    let at_rest = largest_eta(&with_step(0.005)).unwrap();
    let under = largest_eta(&with_step(0.98 * limit)).unwrap();
    assert!(under < 2.0 * at_rest, "{under} against {at_rest}");
    let over = largest_eta(&with_step(1.02 * limit));
    assert!(over.is_none_or(|m| m > 1e3 * at_rest), "{over:?}");
    // Read from the file, a step over the limit is an error at its line naming the mode.
    let text = |h: f64| {
        format!(
            "duration = 1.0\n[model]\n[[model.body]]\nname = \"hub\"\nmass = 50.0\ninertia = [[5.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 5.0]]\n[model.body.flexible]\nbeam = {{ root = [0.0, 0.0, 0.5], axis = [0.0, 0.0, 1.0], bend = [1.0, 0.0, 0.0], length = 1.0, EI = 20.0, rho_A = 1.0, modes = 3 }}\n[integrator]\nmethod = \"rk4\"\nstep = {h}\n[output]\nevery = 0.5\n"
        )
    };
    let Err(err) = Scene::parse(&text(0.02), Path::new("flex.toml")) else {
        panic!("a step beyond the limit was accepted")
    };
    let err = err.to_string();
    assert!(
        err.contains("flex.toml:11")
            && err.contains("body `hub`'s mode 3")
            && err.contains("use an adaptive method"),
        "{err}"
    );
    Scene::parse(&text(0.005), Path::new("flex.toml")).expect("a stable step");
}

/// With heavy damping the mode that limits RK4 is overdamped: its fast eigenvalue is real,
/// about `2ζω` in size, and the step limit falls far below the undamped `2√2/ω`. The check
/// takes the damping in, and its limit is as sharp as the undamped one.
#[test]
fn an_rk4_step_limit_takes_the_modes_damping_in() {
    use satsim_tools::scene::flexible::highest_frequency;
    use satsim_tools::scene::step_limit::{HingeGains, RK4_LIMIT, rk4_limit};
    // The hub's antenna (its highest mode about 280 rad/s) with damping ratio 5.
    let damped = |step: f64| {
        scene_text("")
            .replace(
                "length = 1.0, EI = 20.0, rho_A = 1.0, modes = 3 }",
                "length = 1.0, EI = 20.0, rho_A = 1.0, modes = 3 }\ndamping = 5.0",
            )
            .replace("step = 0.005", &format!("step = {step}"))
    };
    let s = Scene::parse(&damped(0.0002), Path::new("flex.toml")).expect("a stable step");
    let flex = s.flexible.as_ref().unwrap();
    let q = s.initial_q();
    let (w, _) = highest_frequency(flex, &q).unwrap();
    let gains = HingeGains::of(&s.effects, flex.rigid().n_hinges());
    let limit = rk4_limit(flex, &q, &s.initial_v(), &gains).unwrap();
    assert!(limit.lambda.im == 0.0 && limit.zeta > 4.5, "{limit:?}");
    // The real eigenvalue ω (ζ + √(ζ² − 1)) of the highest mode: RK4's real-axis limit 2.785.
    assert!(
        limit.step < 0.15 * RK4_LIMIT / w,
        "{} against {}",
        limit.step,
        RK4_LIMIT / w
    );
    let with_step = |h: f64| {
        let mut s = s.clone();
        s.options = s.options.clone().with_fixed_step(h);
        s.duration = 0.5;
        let third = s.flexible.as_ref().unwrap().elastic_offset(0) + 2;
        s.elastic.eta[third] = 0.01;
        s
    };
    let at_rest = largest_eta(&with_step(0.0002)).unwrap();
    let under = largest_eta(&with_step(0.98 * limit.step)).unwrap();
    assert!(under < 2.0 * at_rest, "{under} against {at_rest}");
    let over = largest_eta(&with_step(1.02 * limit.step));
    assert!(over.is_none_or(|m| m > 1e3 * at_rest), "{over:?}");
    // Read from the file, a step within the undamped limit but over the damped one is an
    // error at its line, naming the mode and its damping.
    let Err(err) = Scene::parse(&damped(2.0 * limit.step), Path::new("flex.toml")) else {
        panic!("a step beyond the damped limit was accepted")
    };
    let err = err.to_string();
    assert!(
        err.contains("flex.toml:")
            && err.contains("body `hub`'s mode 3")
            && err.contains("damping ratio"),
        "{err}"
    );
}

/// The hinge angles, the attitude quaternion and the step count of a run of `scene` with
/// `options`, at its output times.
fn rigid_rows(scene: &Scene, options: &satsim_integrate::Options) -> (Vec<Vec<f64>>, usize) {
    let mut sim = scene.simulation().expect("the scene builds");
    let cols = sim.columns();
    let keep: Vec<usize> = (0..cols.len())
        .filter(|&c| cols[c].starts_with("angle_") || cols[c].starts_with("q_"))
        .collect();
    assert_eq!(keep.len(), 5, "{cols:?}");
    let mut rows = Vec::new();
    let t_end = sim.t0() + scene.duration;
    let stats = sim
        .run(
            options,
            t_end,
            &satsim_integrate::Output::Interval(scene.every),
            |_, row| -> Result<(), ()> {
                rows.push(keep.iter().map(|&c| row[c]).collect());
                Ok(())
            },
        )
        .expect("the run");
    (rows, stats.steps_accepted)
}

#[test]
fn the_elastic_coordinates_left_out_of_the_error_take_fewer_steps_for_the_same_rigid_motion() {
    use satsim_integrate::{Method, Options};
    // The hub's antenna rings at 276 rad/s, undamped, from a deflected start.
    let mut s = scene("");
    let third = s.flexible.as_ref().unwrap().elastic_offset(0) + 2;
    s.elastic.eta[third] = 0.01;
    let (reference, _) = rigid_rows(
        &s,
        &Options::new(Method::Dop853).with_tolerances(1e-12, 1e-12),
    );
    let radau = Options::new(Method::Radau5).with_tolerances(1e-6, 1e-6);
    let (all, steps_all) = rigid_rows(&s, &radau);
    s.elastic_error = false;
    // An explicit method is refused with the modes out of its error, by a run and by the
    // stepping API alike (the scene reader refuses it at its line).
    let dp54 = Options::new(Method::Dp54).with_tolerances(1e-6, 1e-6);
    let refusal = satsim_spacecraft::simulation::elastic_error_refusal(Method::Dp54);
    let mut sim = s.simulation().unwrap();
    let err = sim
        .run(
            &dp54,
            0.1,
            &satsim_integrate::Output::Interval(0.05),
            |_, _| Ok::<(), String>(()),
        )
        .unwrap_err()
        .to_string();
    assert!(err.contains(&refusal), "{err}");
    let grid = satsim_spacecraft::simulation::OutputGrid {
        t0: 0.0,
        every: 0.05,
        t_end: 0.1,
    };
    let mut st = satsim_spacecraft::simulation::Stepping::new(s.simulation().unwrap(), grid);
    let err = st
        .advance(&dp54, 0.1, |_, _| Ok::<(), String>(()))
        .unwrap_err()
        .to_string();
    assert_eq!(err, refusal);
    assert!(st.advance(&radau, 0.1, |_, _| Ok::<(), String>(())).is_ok());
    let (rigid, steps_rigid) = rigid_rows(&s, &radau);
    let largest = |rows: &[Vec<f64>]| {
        rows.iter()
            .zip(&reference)
            .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
            .fold(0.0, f64::max)
    };
    assert_eq!(rigid.len(), reference.len());
    // Both within a few tolerances of the reference in the hinge angle and the quaternion,
    // the rigid-only error control in about two thirds of the steps (1 324 against 2 013).
    // With every state in the error the result rides on where the steps fall around the
    // ringing: tolerances 0.9e-6 to 1.1e-6 give 2.2e-7 to 3.4e-6 (measured; the rigid-only
    // control 1.8e-7 at 1e-6).
    assert!(largest(&all) < 4e-6, "{:e}", largest(&all));
    assert!(largest(&rigid) < 1e-6, "{:e}", largest(&rigid));
    assert!(
        (steps_rigid as f64) < 0.8 * steps_all as f64,
        "{steps_rigid} against {steps_all}"
    );
}

#[test]
fn elastic_error_is_refused_on_a_rigid_model_and_with_an_explicit_method_and_must_be_a_bool() {
    let rigid = "duration = 1.0\n[model]\n[[model.body]]\nname = \"hub\"\nmass = 50.0\ninertia = [[5.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 5.0]]\n[integrator]\nmethod = \"radau5\"\nelastic_error = false\n";
    let err = Scene::parse(rigid, Path::new("r.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("r.toml:9") && err.contains("no flexible bodies"),
        "{err}"
    );
    let flexible = rigid.replace(
        "[integrator]",
        "[model.body.flexible]\nbeam = { root = [0.0, 0.0, 0.5], axis = [0.0, 0.0, 1.0], bend = [1.0, 0.0, 0.0], length = 1.0, EI = 20.0, rho_A = 1.0, modes = 3 }\n[integrator]",
    );
    let s = Scene::parse(&flexible, Path::new("f.toml")).expect("a flexible model takes it");
    assert!(!s.elastic_error);
    // Only Radau IIA is stable on the modes its steps go past; an explicit method is refused
    // at the key's line, saying what to do.
    for method in ["dp54", "dop853"] {
        let text = flexible.replace("\"radau5\"", &format!("\"{method}\""));
        let err = Scene::parse(&text, Path::new("f.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("f.toml:11")
                && err.contains(&format!("with `{method}`"))
                && err.contains("radau5")
                && err.contains("elastic_error = true"),
            "{err}"
        );
        assert!(Scene::parse(&text.replace("false", "true"), Path::new("f.toml")).is_ok());
    }
    let err = Scene::parse(
        &flexible.replace("elastic_error = false", "elastic_error = 0"),
        Path::new("f.toml"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("f.toml:11") && err.contains("boolean"),
        "{err}"
    );
}

/// An initial deformation large enough to make the mass matrix indefinite (the deformed
/// inertia no body's) is refused when the scene is read, at the body's entry, naming the key,
/// the mode whose pivot failed and how far the body is bent: the run would fail at its first
/// step.
#[test]
fn an_initial_deformation_that_makes_the_mass_matrix_indefinite_is_refused() {
    let with_eta = |eta: f64| {
        let text = scene_text("").replace("eta = [0.02, -0.01]", &format!("eta = [{eta}, 0.0]"));
        Scene::parse(&text, Path::new("flex.toml"))
    };
    with_eta(1.0).expect("a deformation the panel can take");
    let Err(err) = with_eta(3.0) else {
        panic!("an indefinite initial mass matrix was accepted")
    };
    let err = err.to_string();
    assert!(
        err.starts_with("flex.toml:28: initial.flexible.panel.eta: the initial deformation makes the mass matrix not positive definite at body `panel`'s mode 1 (eta = 3, pivot -")
            && err.contains("): the deformation moves its tip 3.0000 m off its axis, 150 % of its 2 m length, where a modal model holds a few per cent;")
            && err.contains("start closer to rest"),
        "{err}"
    );
}

/// The flexible deployment with its first strip made far lighter than the panels it carries
/// (`rho_A` 1e-12 and 1e-15 where it is 10): its modes carry 1e13 and more times their own
/// modal mass, and their pivots are round-off. At 1e-15 the pivot at the stowed start was
/// negative; at 1e-12 it kept its sign there and the run failed at 2e-4 s ("mass matrix is
/// not positive definite"). Both are refused where the model is read, naming the body and
/// the mode; as shipped the strips carry far less than the limit.
#[test]
fn a_strip_too_light_for_the_panels_it_carries_is_refused_where_it_is_read() {
    use satsim_tree::flexible::{FlexData, MAGNIFICATION_LIMIT, UNRESOLVED, crba};
    let dir = satsim_testkit::temp_dir_with(
        "light-strip",
        &[
            "examples/flexible_array.toml",
            "examples/satellite_flexible.toml",
        ],
    );
    let shipped = Scene::read(dir.join("flexible_array.toml")).expect("the scene as shipped");
    let flex = shipped.flexible.as_ref().expect("flexible");
    let q: Vec<f64> = shipped
        .initial
        .q
        .iter()
        .copied()
        .chain(std::iter::repeat_n(0.0, flex.n_elastic()))
        .collect();
    let m = crba(flex, &mut FlexData::new(flex), &q).expect("M").clone();
    let nv = flex.rigid().nv();
    let carried: Vec<f64> = (0..flex.n_elastic()).map(|e| m[(nv + e, nv + e)]).collect();
    println!("shipped: each mode's diagonal entry {carried:.3?}");
    assert!(
        carried
            .iter()
            .all(|r| *r >= 1.0 && *r < 1e-6 * MAGNIFICATION_LIMIT)
    );
    assert!(flex.magnified_mode(&q).is_none());
    let model = std::fs::read_to_string(dir.join("satellite_flexible.toml")).unwrap();
    for rho in ["1e-12", "1e-15"] {
        let light = model.replacen("rho_A = 10.0", &format!("rho_A = {rho}"), 1);
        assert_ne!(light, model);
        std::fs::write(dir.join("light.toml"), &light).unwrap();
        let err = satsim_tree::io::parse_flex_model(&light, &dir.join("light.toml"))
            .expect_err("refused")
            .to_string();
        println!("{rho}: {err}");
        assert!(
            err.contains("light.toml:")
                && err.contains(
                    "flexible body `panel1`: at rest the dynamics cannot resolve its mode "
                )
                && err.contains(" times its own modal mass, past the 1e10 at which")
                && err.contains(UNRESOLVED),
            "{err}"
        );
        let scene = std::fs::read_to_string(dir.join("flexible_array.toml"))
            .unwrap()
            .replace("\"satellite_flexible.toml\"", "\"light.toml\"");
        std::fs::write(dir.join("scene.toml"), scene).unwrap();
        let err = Scene::read(dir.join("scene.toml")).unwrap_err().to_string();
        assert!(
            err.contains("light.toml:") && err.contains("`panel1`") && err.contains(UNRESOLVED),
            "{err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A pivot that fails during a run (here a state deformed past what the panel's inertia
/// takes, which the reader refuses at the initial state) is named by its coordinate in words,
/// not by its index alone, and by the deflection that made it fail.
#[test]
fn a_pivot_that_fails_in_a_run_names_its_coordinate() {
    use satsim_integrate::System;
    let mut sim = scene("").simulation().expect("a simulation");
    let mut x = sim.x0().to_vec();
    // The hub's three modes, then the panel's two.
    x[sim.layout().eta.start + 3] = 3.0;
    let mut dx = vec![0.0; x.len()];
    let err = sim.rhs(0.0, &x, &mut dx).unwrap_err().to_string();
    let index = sim.model().nv() + 3;
    assert!(
        err.starts_with(&format!(
            "mass matrix is not positive definite at coordinate {index} (pivot -"
        )) && err.contains(&format!("; coordinate {index} is body `panel`'s mode 1: the flexible bodies are deflected beyond what their modal model holds: body `panel`'s tip is 3.0100 m off its axis, 150 % of its 2 m length (modal coordinates [3.0000, -0.0100])")),
        "{err}"
    );
}

/// The flexible deployment run to `duration` with its panels' hinge springs at `k` (N m/rad;
/// 2 as shipped): the simulation after the run and the run's outcome.
fn deployment(
    dir: &Path,
    k: f64,
    duration: f64,
) -> (
    satsim_spacecraft::simulation::Simulation,
    Result<(), String>,
) {
    let shipped = std::fs::read_to_string(dir.join("flexible_array.toml")).unwrap();
    let text = shipped.replace(
        "stiffness = [50.0, 50.0, 50.0, 2.0, 2.0]",
        &format!("stiffness = [50.0, 50.0, 50.0, {k:?}, {k:?}]"),
    );
    assert!(k == 2.0 || text != shipped);
    std::fs::write(dir.join("stiffer.toml"), text).unwrap();
    let scene = Scene::read(dir.join("stiffer.toml")).expect("a valid scene");
    let mut sim = scene.simulation().expect("a simulation");
    let outcome = sim
        .run(
            &scene.options,
            duration,
            &satsim_integrate::Output::Interval(1.0),
            |_, _| Ok::<(), std::convert::Infallible>(()),
        )
        .map(|_| ())
        .map_err(|e| e.to_string());
    (sim, outcome)
}

/// Each beam's tip is watched at every accepted step. The deployment as shipped (springs of
/// 2 N m/rad on the panels' hinges) keeps every tip within 4.2 cm of its 1 m strip's axis
/// (the largest at the second latch's ringing, 10.39 s). At 80 N m/rad the panels slam open
/// and bend their strips by more than half their length within a second: the run goes on, and
/// warns of each strip from the step its tip passed a tenth of its length. At 200 N m/rad the
/// steps cannot get past 0.55 s: the run's error names the state the steps were last
/// shortened for and says the deflection went beyond the modal model, naming the strip bent
/// most, where the integrator's own words were only "step size underflow".
#[test]
fn a_deflection_beyond_the_modal_model_is_a_warning_or_in_the_error() {
    let dir = satsim_testkit::temp_dir_with(
        "stiff-deployment",
        &[
            "examples/flexible_array.toml",
            "examples/satellite_flexible.toml",
        ],
    );
    let (sim, outcome) = deployment(&dir, 2.0, 20.0);
    outcome.expect("the shipped deployment runs");
    let peaks = sim.deflection_peaks();
    assert_eq!(peaks.len(), 3);
    let largest = peaks.iter().map(|p| p.tip.abs()).fold(0.0, f64::max);
    // 0.0416 m measured (a tenth of the length is 0.1 m).
    assert!(largest > 0.03 && largest < 0.05, "{peaks:?}");
    assert!(sim.deflection_warnings().is_empty());
    let (sim, outcome) = deployment(&dir, 80.0, 2.0);
    outcome.expect("it runs on");
    let warnings = sim.deflection_warnings();
    assert_eq!(warnings.len(), 3, "{warnings:?}");
    for (w, p) in warnings.iter().zip(sim.deflection_peaks()) {
        let passed = p.passed.unwrap();
        // 0.58 m measured: the panels each strip carries, flung outwards, stretch and stiffen
        // it (without their pull it bends by 0.8 m).
        assert!(passed < p.t && p.tip.abs() > 0.5, "{p:?}");
        assert!(
            w.contains("'s tip passed a tenth of its 1 m length at t = ")
                && w.contains("beyond what its modal model holds")
                && w.contains(&format!("results from t = {passed:.4} s on")),
            "{w}"
        );
    }
    let (_, outcome) = deployment(&dir, 200.0, 2.0);
    let err = outcome.unwrap_err();
    assert!(
        err.contains("step size underflow at t = ")
            && err.contains(": the steps were last shortened for `")
            && err.contains(
                ", after the flexible bodies were deflected beyond what their modal model holds: body `panel"
            )
            && err.contains("'s tip passed a tenth of its 1 m length at t = ")
            && err.contains("stiffen the body, or soften what drives it"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A campaign's runs that bend a beam beyond its modal model still finish `ok`, but
/// `runs.csv` says so: each run's `peak_deflection_<body>` is the largest tip deflection
/// over every accepted step as a fraction of the length (its own simulation's
/// `deflection_peaks`, bit for bit), where the output times alone miss most of it, and the
/// folder's summary counts the runs past a tenth. Springs of 80 N m/rad on the panels bend
/// every strip past it within 2 s (the test above); the shipped 2 N m/rad never does.
#[test]
fn a_campaign_counts_the_runs_beyond_the_modal_model() {
    use satsim_tools::campaign::{Campaign, Quiet, RunOptions, Shard, run_campaign};
    let dir = satsim_testkit::temp_dir_with(
        "deflection-campaign",
        &[
            "examples/flexible_array.toml",
            "examples/satellite_flexible.toml",
        ],
    );
    let shipped = std::fs::read_to_string(dir.join("flexible_array.toml")).unwrap();
    let campaign_table = "duration = 2.0\n\n[campaign]\nruns = 3\nseed = 5\nhistograms = [\"peak_deflection_panel1\"]\n[[campaign.disperse]]\nkey = \"model.body.0.mass\"\nnormal = { sigma = 0.5 }\n";
    for (k, beyond) in [(2.0, false), (80.0, true)] {
        let text = shipped
            .replace(
                "stiffness = [50.0, 50.0, 50.0, 2.0, 2.0]",
                &format!("stiffness = [50.0, 50.0, 50.0, {k:?}, {k:?}]"),
            )
            .replace("duration = 300.0\n", campaign_table);
        let path = dir.join(format!("campaign_{k}.toml"));
        std::fs::write(&path, text).unwrap();
        let campaign = Campaign::read(&path).expect("a valid campaign");
        assert_eq!(
            campaign.peak_columns,
            [
                "peak_deflection_panel1",
                "peak_deflection_panel2",
                "peak_deflection_panel3"
            ]
        );
        let mut last = campaign.peak_columns.clone();
        last.push("stability_held".into());
        assert!(campaign.header().ends_with(&last));
        let out = dir.join(format!("out_{k}"));
        let opts = RunOptions {
            threads: Some(1),
            shard: Shard::ALL,
            resume: false,
            lanes: true,
        };
        let report = run_campaign(&campaign, &out, &opts, &Quiet).expect("the campaign runs");
        assert_eq!(report.finished.ok, 3);
        assert_eq!(report.finished.beyond, if beyond { 3 } else { 0 });
        // A peak can be drawn as a histogram.
        assert!(out.join("histogram_peak_deflection_panel1.svg").is_file());
        let runs = std::fs::read_to_string(out.join("runs.csv")).unwrap();
        let header: Vec<&str> = runs.lines().next().unwrap().split(',').collect();
        for (k, line) in runs.lines().skip(1).enumerate() {
            let row: Vec<&str> = line.split(',').collect();
            let value = |name: &str| -> f64 {
                row[header.iter().position(|h| *h == name).unwrap()]
                    .parse()
                    .unwrap()
            };
            // The run alone: its own peaks.
            let scene = Scene::parse(
                &campaign.run_text(k as u64, &campaign.draw(k as u64)),
                &path,
            )
            .unwrap();
            let mut sim = scene.simulation().unwrap();
            sim.run(
                &scene.options,
                scene.duration,
                &satsim_integrate::Output::Interval(scene.every),
                |_, _| Ok::<(), std::convert::Infallible>(()),
            )
            .unwrap();
            for (p, body) in sim
                .deflection_peaks()
                .iter()
                .zip(["panel1", "panel2", "panel3"])
            {
                let peak = value(&format!("peak_deflection_{body}"));
                assert_eq!(
                    peak.to_bits(),
                    (p.tip.abs() / p.length).to_bits(),
                    "run {k}, {body}"
                );
                assert_eq!(peak > 0.1, beyond, "run {k}, {body}: {peak}");
                let sampled = value(&format!("max_tip_{body}"))
                    .abs()
                    .max(value(&format!("min_tip_{body}")).abs());
                if beyond {
                    // The output times (every second) see a fraction of it (0.44 of 0.58 m).
                    assert!(peak > 1.2 * sampled, "run {k}, {body}: {peak} {sampled}");
                }
            }
        }
    }
    // A histogram of a column there is not is refused, naming the peaks among the columns.
    let path = dir.join("campaign_2.toml");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("peak_deflection_panel1\"]", "peak_deflection_bus\"]");
    std::fs::write(&path, text).unwrap();
    let err = Campaign::read(&path).unwrap_err().to_string();
    assert!(
        err.contains("`campaign.histograms`: unknown column `peak_deflection_bus`")
            && err.ends_with(
                "; and peak_deflection_panel1, peak_deflection_panel2, peak_deflection_panel3)"
            ),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A body whose modes come from a modes file is watched at the file's nodes: a run that
/// bends it past a tenth of a node's distance from its frame warns, naming the node, and a
/// campaign of it has the body's `peak_deflection_<body>` column. The contract beam's modes
/// file (nodes at 0, 1 and 2 m along the panel; the linear model, without its
/// `[stiffening]`, whose deformed inertia a start this bent would take out of a body's) on
/// a free hub, started with its first mode at 15 % of the tip's 2 m and at 2 %.
#[test]
fn a_modes_file_body_bent_beyond_its_modal_model_is_a_warning() {
    use satsim_tools::campaign::Campaign;
    let dir = satsim_testkit::temp_dir_with(
        "modes-file-deflection",
        &["examples/modes/panel_beam_modes.toml"],
    );
    let text = |fraction: f64| modes_file_scene(fraction * 2.0 / TIP_PER_UNIT_MODE_1);
    let run = |fraction: f64| {
        run_for_a_second(&dir.join(format!("bent_{fraction}.toml")), &text(fraction))
    };
    let small = run(0.02);
    let peaks = small.deflection_peaks();
    assert_eq!(peaks.len(), 1, "{peaks:?}");
    // The panel rings about its start: never past it (the free hub takes part of the
    // motion), and not far below.
    assert!(
        peaks[0].fraction() > 0.01 && peaks[0].fraction() <= 0.02,
        "{peaks:?}"
    );
    assert!(small.deflection_warnings().is_empty());
    let bent = run(0.15);
    let p = &bent.deflection_peaks()[0];
    assert_eq!((p.body, p.point, p.length), (1, Some(1), 2.0), "{p:?}");
    assert!(
        p.fraction() > 0.1 && p.fraction() <= 0.15 && p.passed.is_some(),
        "{p:?}"
    );
    let warnings = bent.deflection_warnings();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].starts_with("body `panel` passed a tenth of its size at t = ")
            && warnings[0].contains(": its node `tip` moved ")
            && warnings[0]
                .contains("of its 2 m from the body's frame, beyond what its modal model holds"),
        "{}",
        warnings[0]
    );
    let path = dir.join("campaign.toml");
    let campaign_table = "\n[campaign]\nruns = 2\n[[campaign.disperse]]\nkey = \"model.body.0.mass\"\nnormal = { sigma = 0.5 }\n";
    std::fs::write(&path, text(0.15) + campaign_table).unwrap();
    let campaign = Campaign::read(&path).expect("a valid campaign");
    assert_eq!(campaign.peak_columns, ["peak_deflection_panel"]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The scene `text`, written at `path`, run for its first second (rows every 0.1 s).
fn run_for_a_second(path: &Path, text: &str) -> satsim_spacecraft::simulation::Simulation {
    std::fs::write(path, text).unwrap();
    let scene = Scene::read(path).expect("a valid scene");
    let mut sim = scene.simulation().expect("a simulation");
    sim.run(
        &scene.options,
        1.0,
        &satsim_integrate::Output::Interval(0.1),
        |_, _| Ok::<(), std::convert::Infallible>(()),
    )
    .expect("it runs");
    sim
}

/// The contract beam's modes file's tip translation per unit first-mode coordinate (its
/// `tip` node, 2 m from the frame).
const TIP_PER_UNIT_MODE_1: f64 = 0.63246;

/// A free hub (50 kg) with a panel on a hinge spring whose modes come from the contract
/// beam's modes file (in the scene's folder; the linear model, without its `[stiffening]`),
/// the panel's first mode started at `eta1`, RK4 at 5 ms for 1 s.
fn modes_file_scene(eta1: f64) -> String {
    format!(
        r#"duration = 1.0
[model]
[[model.body]]
name = "hub"
mass = 50.0
inertia = [[5.0, 0.0, 0.0], [0.0, 5.0, 0.0], [0.0, 0.0, 5.0]]
[[model.body]]
name = "panel"
mass = 0.0
[model.body.flexible]
modes_file = "panel_beam_modes.toml"
stiffening = false
[[model.hinge]]
name = "h"
parent = "hub"
child = "panel"
axis = [1.0, 0.0, 0.0]
at = [0.0, 0.5, 0.0]
[initial]
hinges = {{ angle = [0.0], rate = [0.0] }}
flexible = {{ panel = {{ eta = [{eta1:?}, 0.0, 0.0] }} }}
[integrator]
method = "rk4"
step = 0.005
[output]
every = 0.1
plots = false
view = false
[effects.hinge_springs]
stiffness = [10.0]
"#
    )
}

/// An energy budget that does not close is a warning after the run. The modes-file panel
/// above (its first mode started at 2 % of the tip's distance) rings its free-free modes,
/// the highest at 65.8 Hz (`satsim modes`): RK4 at 5 ms is inside that mode's stability
/// limit (6.85 ms; the scene reader's check passes) but shrinks it by 30 % a step, and a
/// third of the energy is gone within the second, with no dissipation in the scene. DP5(4)
/// at `1e-8` closes the budget to 4e-6 of it.
#[test]
fn an_energy_budget_that_does_not_close_is_a_warning() {
    let dir =
        satsim_testkit::temp_dir_with("budget-warning", &["examples/modes/panel_beam_modes.toml"]);
    let eta1 = 0.02 * 2.0 / TIP_PER_UNIT_MODE_1;
    let run = |integrator: &str| {
        let text = modes_file_scene(eta1)
            .replace("[integrator]\nmethod = \"rk4\"\nstep = 0.005\n", integrator);
        run_for_a_second(&dir.join("budget.toml"), &text)
    };
    let rk4 = run("[integrator]\nmethod = \"rk4\"\nstep = 0.005\n");
    let warning = rk4.budget_warning().expect("a warning");
    assert!(
        warning.starts_with("the energy budget moved by 5.0")
            && warning.contains("this is the integration's error, not the structure's behaviour"),
        "{warning}"
    );
    assert!(!warning.contains("elastic_error"), "{warning}");
    assert_eq!(rk4.run_warnings(), [warning]);
    let dp54 = run("[integrator]\nmethod = \"dp54\"\nrtol = 1e-8\natol = 1e-8\n");
    assert_eq!(dp54.budget_warning(), None);
    // Radau IIA with the modes out of its error steps over the ringing and damps it: the
    // warning names that first. With them in its error, at the same tolerance, it closes.
    let radau = |elastic: &str| {
        run(&format!(
            "[integrator]\nmethod = \"radau5\"\nrtol = 1e-3\natol = 1e-3\nelastic_error = {elastic}\n"
        ))
    };
    assert_eq!(radau("true").budget_warning(), None);
    let warning = radau("false").budget_warning().expect("a warning");
    assert!(
        warning.contains("not the structure's behaviour: with `integrator.elastic_error = false` the implicit method damps"),
        "{warning}"
    );
    // A campaign counts such runs from their rows' budget and energies, as the run does.
    use satsim_tools::campaign::{Campaign, Quiet, RunOptions, Shard, run_campaign};
    for (integrator, drifted) in [
        ("[integrator]\nmethod = \"rk4\"\nstep = 0.005\n", 2),
        (
            "[integrator]\nmethod = \"dp54\"\nrtol = 1e-8\natol = 1e-8\n",
            0,
        ),
    ] {
        let text = modes_file_scene(eta1)
            .replace("[integrator]\nmethod = \"rk4\"\nstep = 0.005\n", integrator)
            + "\n[campaign]\nruns = 2\n[[campaign.disperse]]\nkey = \"model.body.0.mass\"\nnormal = { sigma = 0.5 }\n";
        let path = dir.join("budget_campaign.toml");
        std::fs::write(&path, text).unwrap();
        let campaign = Campaign::read(&path).expect("a valid campaign");
        let opts = RunOptions {
            threads: Some(1),
            shard: Shard::ALL,
            resume: false,
            lanes: true,
        };
        let out = dir.join(format!("out_{drifted}"));
        let report = run_campaign(&campaign, &out, &opts, &Quiet).expect("the campaign runs");
        assert_eq!(report.finished.ok, 2);
        assert_eq!(report.finished.drifted, drifted, "{integrator}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A thruster at a node of a modes file loads the modes through the node's shapes: the
/// contract beam's modes file (its `tip` node at 2 m) under a 1 N thruster at the tip, on a
/// fixed base, moves as the beam it was written from does under the same thruster (the
/// file's shapes are the beam's to its printed digits). Off the nodes, and for the pressure
/// on a modes-file body's facets, the scene warns that the load does not reach the modes.
#[test]
fn a_thruster_at_a_modes_file_node_bends_the_body_as_on_the_beam() {
    let dir = satsim_testkit::temp_dir_with(
        "modes-file-thruster",
        &["examples/modes/panel_beam_modes.toml"],
    );
    let scene_of = |flexible: &str, at: f64| {
        format!(
            r#"duration = 2.0
[integrator]
method = "dp54"
rtol = 1e-10
atol = 1e-12
[output]
every = 0.1
[model]
[model.base]
kind = "fixed"
[[model.body]]
name = "panel"
mass = 0.0
[model.body.flexible]
{flexible}
damping = 0.05
[effects.thrusters]
period = 1.0
[[effects.thrusters.thruster]]
name = "t"
body = "panel"
at = [0.0, {at}, 0.0]
direction = [0.0, 0.0, 1.0]
thrust = 1.0
duty = 1.0
"#
        )
    };
    let beam = "beam = { root = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], bend = [0.0, 0.0, 1.0], length = 2.0, EI = 500.0, rho_A = 5.0, modes = 3 }\nstiffening = false";
    let file = "modes_file = \"panel_beam_modes.toml\"\nstiffening = false";
    let tip = |text: &str, name: &str| {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let scene = Scene::read(&path).unwrap_or_else(|e| panic!("{e}"));
        let mut sim = scene.simulation().unwrap();
        let columns = sim.columns();
        let at: Vec<usize> = (1..=3)
            .map(|k| {
                columns
                    .iter()
                    .position(|c| *c == format!("eta_panel_{k}"))
                    .unwrap()
            })
            .collect();
        let mut eta = Vec::new();
        sim.run(
            &scene.options,
            2.0,
            &satsim_integrate::Output::Interval(0.1),
            |_, row| {
                eta.push(at.iter().map(|&i| row[i]).collect::<Vec<f64>>());
                Ok::<(), std::convert::Infallible>(())
            },
        )
        .unwrap();
        (scene.warnings, eta)
    };
    // A beam's mass is its own; the file's body carries the same 10 kg in its inertia.
    let (w_beam, beam_eta) = tip(&scene_of(beam, 2.0), "beam.toml");
    let (w_file, file_eta) = tip(&scene_of(file, 2.0), "file.toml");
    assert!(
        w_beam.is_empty() && w_file.is_empty(),
        "{w_beam:?} {w_file:?}"
    );
    let largest = beam_eta
        .iter()
        .flatten()
        .fold(0.0f64, |m, e| m.max(e.abs()));
    assert!(largest > 1e-3, "the thruster bends the beam: {largest}");
    for (b, f) in beam_eta.iter().zip(&file_eta) {
        for (b, f) in b.iter().zip(f) {
            assert!((b - f).abs() < 1e-9 * largest, "{b} vs {f}");
        }
    }
    // Off the nodes: a warning naming the thruster and the nodes; the modes stay at rest.
    let (w_off, off_eta) = tip(&scene_of(file, 1.5), "off.toml");
    let off = off_eta.iter().flatten().fold(0.0f64, |m, e| m.max(e.abs()));
    assert!(off < 1e-12 * largest, "{off} against {largest}");
    assert_eq!(w_off.len(), 1, "{w_off:?}");
    assert!(
        w_off[0].starts_with("thruster `t` on body `panel` is at none of its modes file's nodes")
            && w_off[0].contains("`tip` at [0, 2, 0]"),
        "{}",
        w_off[0]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A thruster's force along a stiffened beam loads its bending through the foreshortening
/// of its point: at the tip of the contract cantilever (fixed base, 3 modes), 150 N towards
/// the root (half Euler's `π² EI / 4L² = 308 N`) softens it and 150 N outwards stiffens it,
/// `K = diag(ωₖ²) ∓ P C(L)`, `C(L) = ∫₀ᴸ φ'φ'ᵀ` (the Galerkin of the axially loaded beam on
/// the same cantilever modes). Without `stiffening` the load leaves them at the unloaded
/// beam's.
#[test]
fn a_thrust_along_a_beam_compresses_or_stretches_it() {
    use nalgebra::{DMatrix, SymmetricEigen};
    use satsim_tree::flexible::beam::{PANELS, POINTS, gauss_legendre, integrate};
    let scene_of = |direction: f64, stiffening: bool| {
        format!(
            r#"duration = 1.0
[model]
[model.base]
kind = "fixed"
[[model.body]]
name = "beam"
mass = 0.0
[model.body.flexible]
beam = {{ root = [0.0, 0.0, 0.0], axis = [0.0, 1.0, 0.0], bend = [0.0, 0.0, 1.0], length = 2.0, EI = 500.0, rho_A = 5.0, modes = 3 }}
stiffening = {stiffening}
[effects.thrusters]
period = 1.0
[[effects.thrusters.thruster]]
name = "t"
body = "beam"
at = [0.0, 2.0, 0.0]
direction = [0.0, {direction:?}, 0.0]
thrust = 150.0
duty = 1.0
"#
        )
    };
    // The linear model with the thruster firing, as it does from the start: its samples at
    // `t = 0` taken (a linearisation alone takes none), then `K = −∂η̈/∂η` (unit modal mass
    // on the fixed base; states `η`, `η̇`).
    let frequencies = |text: &str| {
        let scene = Scene::parse(text, Path::new("thrust.toml")).unwrap_or_else(|e| panic!("{e}"));
        let mut sim = scene.simulation().unwrap();
        sim.state_at(&scene.options, 0.0).unwrap();
        let lin = satsim_tools::linearize::linearize_simulation(&mut sim).unwrap();
        assert_eq!(lin.states[3], "etadot_beam_1");
        let k = -lin.a.view((3, 0), (3, 3)).clone_owned();
        let k = (&k + k.transpose()) * 0.5;
        let mut f: Vec<f64> = SymmetricEigen::new(k)
            .eigenvalues
            .iter()
            .map(|l| l.sqrt() / std::f64::consts::TAU)
            .collect();
        f.sort_by(|a, b| a.partial_cmp(b).unwrap());
        f
    };
    let beam = satsim_tree::flexible::Beam {
        root: satsim_tree::spatial::Vec3::zeros(),
        axis: satsim_tree::spatial::Vec3::y(),
        bend: satsim_tree::spatial::Vec3::z(),
        length: 2.0,
        ei: 500.0,
        rho_a: 5.0,
        modes: 3,
    };
    let modes = beam.cantilever_modes();
    let rule = gauss_legendre(POINTS);
    let galerkin = |pull: f64| {
        let k = DMatrix::from_fn(3, 3, |i, j| {
            let c = integrate(2.0, 2 * PANELS, &rule, |x| {
                modes[i].shape(x)[1] * modes[j].shape(x)[1]
            });
            let own = if i == j {
                beam.omega(i + 1).powi(2)
            } else {
                0.0
            };
            own + pull * c
        });
        let mut f: Vec<f64> = SymmetricEigen::new(k)
            .eigenvalues
            .iter()
            .map(|l| l.sqrt() / std::f64::consts::TAU)
            .collect();
        f.sort_by(|a, b| a.partial_cmp(b).unwrap());
        f
    };
    for (direction, pull) in [(-1.0, -150.0), (1.0, 150.0)] {
        let got = frequencies(&scene_of(direction, true));
        let expected = galerkin(pull);
        for (g, e) in got.iter().zip(&expected) {
            assert!(
                (g - e).abs() < 1e-6 * e,
                "pull {pull}: {got:?} vs {expected:?}"
            );
        }
    }
    // Compressed to half the buckling load, the first mode is a third lower.
    let unloaded = galerkin(0.0);
    assert!(galerkin(-150.0)[0] < 0.8 * unloaded[0]);
    let linear = frequencies(&scene_of(-1.0, false));
    assert!(
        (linear[0] - unloaded[0]).abs() < 1e-6 * unloaded[0],
        "{linear:?}"
    );
}

/// The unit beam (L = EI = ρA = 1, two modes, `stiffening` on by default) on a hinge of a hub
/// fixed to the inertial frame, with `initial` (the hinge's state first).
fn hinged_beam(initial: &str) -> String {
    format!(
        r#"duration = 1.0
[model]
[model.base]
kind = "fixed"
[[model.body]]
name = "hub"
mass = 10.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[model.body]]
name = "boom"
mass = 0.0
[model.body.flexible]
beam = {{ root = [0.0, 0.0, 0.0], axis = [1.0, 0.0, 0.0], bend = [0.0, 0.0, 1.0],
         length = 1.0, EI = 1.0, rho_A = 1.0, modes = 2 }}
[[model.hinge]]
name = "spin"
parent = "hub"
child = "boom"
axis = [0.0, 0.0, 1.0]
{initial}
[output]
every = 0.1
plots = false
view = false
"#
    )
}

/// Every error about a flexible body's initial elastic state names the key, the body and
/// the mode, at the line of the body's entry, in the scene or in its JSON state file: a value
/// missing or one too many, a value that is not finite, and a deformation that makes the
/// mass matrix indefinite where the dynamics' pivot fails at the hinge, not at a mode (the
/// mode to blame is the one that bends the body most: here the second, its tip 10 m off).
#[test]
fn initial_deformation_errors_name_the_key_the_body_and_the_mode() {
    let inline = |entry: &str| {
        let text = hinged_beam(&format!(
            "[initial]\nhinges = {{ angle = [0.0], rate = [0.0] }}\nflexible = {{ boom = {{ {entry} }} }}"
        ));
        Scene::parse(&text, Path::new("beam.toml"))
            .map(|_| ())
            .unwrap_err()
            .to_string()
    };
    for (entry, expected) in [
        (
            "eta = [0.0]",
            "beam.toml:22: initial.flexible.boom.eta: expected 2 values, one per mode of body `boom`, got 1 (mode 2 has none)",
        ),
        (
            "etadot = [0.0, 0.0, 1.0]",
            "beam.toml:22: initial.flexible.boom.etadot: expected 2 values, one per mode of body `boom`, got 3 (value 3 is no mode's)",
        ),
        (
            "etadot = [0.0, inf]",
            "beam.toml:22: initial.flexible.boom.etadot: body `boom`'s mode 2 is inf: values must be finite",
        ),
    ] {
        assert_eq!(inline(entry), expected);
    }
    let indefinite = "initial.flexible.boom.eta: the initial deformation makes the mass matrix not positive definite at body `boom`'s mode 2 (eta = 5): the deformation moves its tip 10.0000 m off its axis, 1000 % of its 1 m length, where a modal model holds a few per cent; with `stiffening`";
    let err = inline("eta = [0.0, 5.0]");
    assert!(
        err.starts_with(&format!("beam.toml:22: {indefinite}"))
            && err.ends_with("start closer to rest"),
        "{err}"
    );
    // From a state file, at the body's line there.
    let dir = satsim_testkit::temp_dir("initial-deformation-errors");
    std::fs::write(
        dir.join("s.json"),
        "{\n  \"hinges\": {\"angle\": [0.0], \"rate\": [0.0]},\n  \"flexible\": {\n    \"boom\": {\"eta\": [0.0, 5.0]}\n  }\n}\n",
    )
    .unwrap();
    let text = format!("initial = \"s.json\"\n{}", hinged_beam(""));
    let err = Scene::parse(&text, &dir.join("beam.toml"))
        .map(|_| ())
        .unwrap_err()
        .to_string();
    let in_file = format!("{}:4: {}", dir.join("s.json").display(), &indefinite[8..]);
    assert!(err.starts_with(&in_file), "{err}\nnot\n{in_file}");
    let _ = std::fs::remove_dir_all(&dir);
}
