//! The longest RK4 step a scene allows on its hinges' springs, dampers and controllers
//! (`scene/step_limit.rs`): the analytic oscillator's numbers, the limit sharp against runs,
//! and a longer step refused at its line.

use satsim_tools::scene::Scene;
use satsim_tools::scene::step_limit::{
    HingeGains, Limiting, rk4_limit, rk4_stable_step, rk4_step_limit,
};
use satsim_tree::flexible::FlexModel;
use std::path::Path;

/// An arm on a fixed hub, its centre of mass 0.5 m from the hinge: `I = 0.1 + 2 × 0.5² = 0.6`
/// kg m² about the hinge axis, on a spring `k` and a damper `c`.
fn arm(k: f64, c: f64, control: &str, step: f64) -> String {
    format!(
        "duration = 2.0
[model]
[model.base]
kind = \"fixed\"
[[model.body]]
name = \"hub\"
mass = 100.0
inertia = [[10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.0, 0.0, 10.0]]
[[model.body]]
name = \"arm\"
mass = 2.0
inertia = [[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]
[[model.hinge]]
name = \"h\"
parent = \"hub\"
child = \"arm\"
axis = [0.0, 0.0, 1.0]
child_at = [-0.5, 0.0, 0.0]
[initial]
hinges = {{ angle = [0.1], rate = [0.0] }}
[effects.hinge_springs]
stiffness = [{k}]
damping = [{c}]
reference = [0.0]
{control}
[integrator]
method = \"rk4\"
step = {step}
[output]
every = 2.0
plots = false
view = false
"
    )
}

const I: f64 = 0.6;

fn limit_of(s: &Scene) -> satsim_tools::scene::step_limit::Rk4Limit {
    let tree = FlexModel::attach(s.model.clone(), &[]).unwrap();
    let gains = HingeGains::of(&s.effects, 1);
    rk4_limit(&tree, &s.initial.q, &gains).unwrap()
}

/// The largest |angle| of a run of `scene` at step `h` (`None` when it failed); its rows are
/// at the start and the end, so that the fixed steps are `h` between them.
fn largest_angle(scene: &Scene, h: f64) -> Option<f64> {
    let mut s = scene.clone();
    s.options = s.options.clone().with_fixed_step(h);
    let t = satsim_tools::api::run_scene(&s, || false).ok()?;
    let c = t.columns.iter().position(|c| c == "angle_h").unwrap();
    Some(t.rows().map(|r| r[c].abs()).fold(0.0, f64::max)).filter(|m| m.is_finite())
}

#[test]
fn a_hinge_spring_and_damper_limit_rk4s_step_as_the_oscillator_does() {
    let (k, c) = (1e4, 10.0);
    let s = Scene::parse(&arm(k, c, "", 0.001), Path::new("arm.toml")).unwrap();
    let limit = limit_of(&s);
    // ω = √(k/I), ζ = c / (2 √(k I)), λ = −ζω ± iω√(1 − ζ²).
    let (w, z) = ((k / I).sqrt(), c / (2.0 * (k * I).sqrt()));
    assert!((limit.omega - w).abs() < 1e-9 * w, "{limit:?}");
    assert!((limit.zeta - z).abs() < 1e-9, "{limit:?}");
    let lambda = nalgebra::Complex::new(-z * w, w * (1.0 - z * z).sqrt());
    assert!((limit.lambda - lambda).norm() < 1e-9 * w, "{limit:?}");
    assert!(
        (limit.step - rk4_step_limit(lambda)).abs() < 1e-12,
        "{limit:?}"
    );
    assert_eq!(limit.by, Limiting::Hinge(0));
    // Sharp: bounded just under it (the damper takes the swing down), growing just over.
    let under = largest_angle(&s, 0.98 * limit.step).unwrap();
    assert!(under <= 0.1 + 1e-12, "{under}");
    let over = largest_angle(&s, 1.02 * limit.step);
    assert!(over.is_none_or(|m| m > 10.0), "{over:?}");
    // From the file, a longer step is an error at its line naming the hinge.
    let err = Scene::parse(&arm(k, c, "", 2.0 * limit.step), Path::new("arm.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("arm.toml:28")
            && err.contains("mostly hinge `h`")
            && err.contains("20.5468 Hz")
            && err.contains("use an adaptive method"),
        "{err}"
    );
    let (step, what) = rk4_stable_step(&s).unwrap();
    assert_eq!((step, what.as_str()), (limit.step, "hinge `h` (20.547 Hz)"));
}

/// A damper alone limits the step by its real eigenvalue `−c/I` (RK4's real-axis limit
/// 2.785), where the undamped check would see nothing to limit.
#[test]
fn a_damper_alone_limits_the_step_by_its_real_eigenvalue() {
    let c = 100.0;
    let s = Scene::parse(&arm(0.0, c, "", 0.001), Path::new("arm.toml")).unwrap();
    let limit = limit_of(&s);
    assert_eq!(limit.omega, 0.0);
    assert!((limit.lambda.re + c / I).abs() < 1e-9 * c / I && limit.lambda.im == 0.0);
    assert!((limit.step * c / I - 2.785).abs() < 1e-3, "{limit:?}");
    let err = Scene::parse(&arm(0.0, c, "", 0.05), Path::new("arm.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("arm.toml:28")
            && err.contains("has no stiffness, only damping, eigenvalue -166.6667 1/s"),
        "{err}"
    );
    // Without spring or damper nothing limits the step.
    let free = Scene::parse(&arm(0.0, 0.0, "", 0.5), Path::new("arm.toml")).unwrap();
    assert!(rk4_stable_step(&free).is_none());
}

/// A continuous hinge controller's gains add to the spring's and the damper's; a sampled
/// one's are left out (its stability is its period's, not RK4's).
#[test]
fn a_continuous_hinge_controllers_gains_count_and_a_sampled_ones_do_not() {
    let control = |period: &str| {
        format!(
            "[effects.hinge_control]\n{period}[[effects.hinge_control.hinge]]\nname = \"h\"\nstart = 0.1\nend = 0.0\nt_start = 0.0\nduration = 1.0\nkp = 3e4\nkd = 5.0\n"
        )
    };
    let s = Scene::parse(&arm(1e4, 10.0, &control(""), 0.001), Path::new("arm.toml")).unwrap();
    assert_eq!(
        HingeGains::of(&s.effects, 1),
        HingeGains {
            stiffness: vec![4e4],
            damping: vec![15.0]
        }
    );
    let limit = limit_of(&s);
    assert!(
        (limit.omega - (4e4 / I).sqrt()).abs() < 1e-9 * limit.omega,
        "{limit:?}"
    );
    let sampled = Scene::parse(
        &arm(1e4, 10.0, &control("period = 0.01\n"), 0.001),
        Path::new("arm.toml"),
    )
    .unwrap();
    assert_eq!(
        HingeGains::of(&sampled.effects, 1),
        HingeGains {
            stiffness: vec![1e4],
            damping: vec![10.0]
        }
    );
}

/// A step longer than the output interval is cut to it (the reader warns): the interval is
/// then the step taken, and what the check holds against the limit.
#[test]
fn a_step_cut_to_the_output_interval_is_checked_at_the_interval() {
    let (k, c) = (1e4, 10.0);
    // The limit is 0.0227 s: a 0.05 s step cut to 0.01 s outputs runs.
    let text = arm(k, c, "", 0.05).replace("every = 2.0", "every = 0.01");
    let s = Scene::parse(&text, Path::new("arm.toml")).unwrap();
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("longer than `output.every`"))
    );
    // Cut to 0.04 s outputs it is still too long, and the message says what cut it.
    let text = arm(k, c, "", 0.05).replace("every = 2.0", "every = 0.04");
    let err = Scene::parse(&text, Path::new("arm.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("`integrator.step` = 0.05 s (cut to `output.every` = 0.04 s) is too long")
            && err.contains("|λ| × step = 5.164"),
        "{err}"
    );
}
