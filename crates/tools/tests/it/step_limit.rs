//! The longest RK4 step a scene allows on its hinges' springs, dampers and controllers
//! (`scene/step_limit.rs`): the analytic oscillator's numbers, the limit sharp against runs,
//! and a longer step refused at its line.

use satsim_tools::scene::Scene;
use satsim_tools::scene::step_limit::{
    HingeGains, Limiting, integrated_q, integrated_tree, integrated_v, rk4_limit, rk4_stable_step,
    rk4_step_limit,
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

fn limit_of(s: &Scene) -> satsim_tools::scene::step_limit::StepLimit {
    let tree = FlexModel::attach(s.model.clone(), &[]).unwrap();
    let gains = HingeGains::of(&s.effects, 1);
    rk4_limit(&tree, &s.initial.q, &s.initial.v, &gains).unwrap()
}

/// The largest |value| of `column` over a run of `scene` at step `h`, the reader's check
/// bypassed (`None` when it failed); its rows are at the start and the end, so that the fixed
/// steps are `h` between them.
fn largest(scene: &Scene, h: f64, column: &str) -> Option<f64> {
    let mut s = scene.clone();
    s.options = s.options.clone().with_fixed_step(h);
    let t = satsim_tools::api::run_scene(&s, || false).ok()?;
    let c = t.columns.iter().position(|c| c == column).unwrap();
    Some(t.rows().map(|r| r[c].abs()).fold(0.0, f64::max)).filter(|m| m.is_finite())
}

/// The largest |angle| of the arm's hinge over a run at step `h`.
fn largest_angle(scene: &Scene, h: f64) -> Option<f64> {
    largest(scene, h, "angle_h")
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
    let g = HingeGains::of(&s.effects, 1);
    assert_eq!((g.stiffness, g.damping), (vec![4e4], vec![15.0]));
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
    let g = HingeGains::of(&sampled.effects, 1);
    assert_eq!((g.stiffness, g.damping), (vec![1e4], vec![10.0]));
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

/// A free bus (principal moments 10, 20, 30 kg m²) with three wheels of 0.1 kg m² on its
/// axes (transverse 0.05), `viscous` friction on wheel x, and a continuous attitude
/// controller with `kp`, `kd` (`period` line optional), rotated 0.04 rad about x.
fn wheeled_bus(viscous: f64, kp: f64, kd: f64, period: &str, step: f64) -> String {
    let wheel = |name: &str, axis: &str, c: f64| {
        format!(
            "[[effects.reaction_wheels.wheel]]\nname = \"{name}\"\naxis = {axis}\ninertia = 0.1\nviscous = {c}\n"
        )
    };
    format!(
        "duration = 200.0
[model]
[model.base]
kind = \"free\"
[[model.body]]
name = \"bus\"
mass = 100.0
inertia = [[10.0, 0.0, 0.0], [0.0, 20.0, 0.0], [0.0, 0.0, 30.0]]
[initial]
base = {{ attitude = [0.9998, 0.02, 0.0, 0.0], angular_velocity = [0.0, 0.0, 0.0] }}
[effects.reaction_wheels]
{}{}{}[effects.attitude_control]
target = \"inertial\"
attitude = [1.0, 0.0, 0.0, 0.0]
kp = {kp}
kd = {kd}
{period}
[integrator]
method = \"rk4\"
step = {step}
[output]
every = 200.0
plots = false
view = false
",
        wheel("x", "[1.0, 0.0, 0.0]", viscous),
        wheel("y", "[0.0, 1.0, 0.0]", 0.0),
        wheel("z", "[0.0, 0.0, 1.0]", 0.0),
    )
}

/// The limit of a scene on the tree it integrates (the wheels' rotors included).
fn tree_limit_of(s: &Scene) -> Option<satsim_tools::scene::step_limit::StepLimit> {
    let (tree, n) = integrated_tree(&s.model, s.flexible.as_ref(), &s.effects).unwrap();
    let q = integrated_q(&s.initial.q, n, &s.elastic.eta);
    let v = integrated_v(&s.initial.v, &s.effects, n, &s.elastic.etadot);
    rk4_limit(
        &tree,
        &q,
        &v,
        &HingeGains::of(&s.effects, s.model.n_hinges()),
    )
}

/// The largest |ω_x| of the bus over a run at step `h`.
fn largest_rate(scene: &Scene, h: f64) -> Option<f64> {
    largest(scene, h, "omega_x")
}

/// A continuous attitude controller through the wheels: about x the bus, its wheel x free
/// to spin, is an oscillator of inertia `10 + 0.05 + 0.05` (the bus and the other wheels'
/// transverse moments) on `kp` and `kd`. The check's frequency, damping ratio and limit are
/// that oscillator's; runs are bounded just inside the limit and grow just outside; the
/// step line is refused naming the controller; a sampled controller is left out.
#[test]
fn a_continuous_attitude_controller_limits_the_step_as_the_bus_on_its_gains() {
    let (kp, kd) = (1e4, 1.0);
    let text = wheeled_bus(0.0, kp, kd, "", 0.01);
    let s = Scene::parse(&text, Path::new("bus.toml")).unwrap();
    let limit = tree_limit_of(&s).unwrap();
    let i = 10.1;
    let (w, z) = ((kp / i).sqrt(), kd / (2.0 * (kp * i).sqrt()));
    assert_eq!(limit.by, Limiting::Attitude);
    assert!((limit.omega - w).abs() < 1e-9 * w, "{limit:?}");
    assert!((limit.zeta - z).abs() < 1e-9, "{limit:?}");
    let lambda = nalgebra::Complex::new(-z * w, w * (1.0 - z * z).sqrt());
    let analytic = rk4_step_limit(lambda);
    assert!((limit.step - analytic).abs() < 1e-9 * analytic, "{limit:?}");
    // The reader's own check and the accuracy sweep's agree.
    assert_eq!(rk4_stable_step(&s).unwrap().0, limit.step);
    // The model alone (no rotors) has nothing to check.
    let alone = FlexModel::attach(s.model.clone(), &[]).unwrap();
    assert!(
        rk4_limit(
            &alone,
            &s.initial.q,
            &s.initial.v,
            &HingeGains::of(&s.effects, 0)
        )
        .is_none()
    );
    // Sharp against runs: bounded at 0.98 of the limit, growing at 1.02.
    let start = largest_rate(&s, 0.001).unwrap();
    let inside = largest_rate(&s, 0.98 * limit.step).unwrap();
    assert!(inside < 2.0 * start, "{inside} against {start}");
    let outside = largest_rate(&s, 1.02 * limit.step);
    assert!(
        outside.is_none_or(|m| m > 10.0 * start),
        "{outside:?} against {start}"
    );
    let err = Scene::parse(&wheeled_bus(0.0, kp, kd, "", 0.1), Path::new("bus.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("bus.toml:35")
            && err.contains("too long for rk4 with the attitude controller's gains")
            && err.contains("(mostly the bus) is an oscillation on the controller's gains (kp = 10000 N m/rad, kd = 1 N m s/rad) at 5.0079 Hz"),
        "{err}"
    );
    // Sampled, its stability is its period's: nothing limits the step.
    let sampled = Scene::parse(
        &wheeled_bus(0.0, kp, kd, "period = 0.5", 0.1),
        Path::new("bus.toml"),
    )
    .unwrap();
    assert!(tree_limit_of(&sampled).is_none());
}

/// A wheel's viscous friction `c` relaxes its speed at `c / J_eff`, `J_eff = J (1 − J / I)`
/// the wheel's inertia less what the bus takes back (`I = 10.2` about x with every rotor's
/// share): a damper on the rotor's coordinate, named as the wheel's. A wheel far lighter
/// than any real one (1e-20 kg m², 1e-5 N m s/rad: 1e15 /s) is refused at the step's line.
#[test]
fn a_wheels_viscous_friction_limits_the_step_by_its_rotors_decay() {
    let c = 50.0;
    let s = Scene::parse(&wheeled_bus(c, 0.0, 0.0, "", 0.001), Path::new("bus.toml")).unwrap();
    let limit = tree_limit_of(&s).unwrap();
    let j_eff = 0.1 * (1.0 - 0.1 / 10.2);
    assert!(
        (limit.lambda.re + c / j_eff).abs() < 1e-9 * c / j_eff && limit.lambda.im == 0.0,
        "{limit:?}"
    );
    let (tree, _) = integrated_tree(&s.model, None, &s.effects).unwrap();
    assert_eq!(limit.what(&tree), "rotor `wheel_x` on its viscous friction");
    let light =
        wheeled_bus(1e-5, 0.0, 0.0, "", 0.01).replacen("inertia = 0.1", "inertia = 1e-20", 1);
    let err = Scene::parse(&light, Path::new("bus.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("bus.toml:35")
            && err.contains("too long for rk4 with the wheels' viscous friction")
            && err.contains("(mostly rotor `wheel_x` on its viscous friction) has no stiffness, only damping, eigenvalue -1.0000e15 1/s"),
        "{err}"
    );
}

/// The ZOH PD loop of a double integrator of inertia `i` over a period `t`:
/// `θ⁺ = θ + t ω + t²/(2i) u`, `ω⁺ = ω + t/i u`, `u = −kp θ − kd ω`; its largest `|z|`.
fn zoh_growth(i: f64, kp: f64, kd: f64, t: f64) -> f64 {
    let m = nalgebra::Matrix2::new(
        1.0 - kp * t * t / (2.0 * i),
        t - kd * t * t / (2.0 * i),
        -kp * t / i,
        1.0 - kd * t / i,
    );
    m.complex_eigenvalues()
        .iter()
        .map(|z| z.norm())
        .fold(0.0, f64::max)
}

/// The longest stable period of a closed form's growth a sample, by bisection between 0.01 s
/// (stable) and 1 s (not): the loops here are stable from zero up.
fn longest_stable(growth: impl Fn(f64) -> f64) -> f64 {
    let (mut lo, mut hi) = (0.01, 1.0);
    assert!(growth(lo) <= 1.0 && growth(hi) > 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if growth(mid) <= 1.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    lo
}

/// A sampled loop's check against its closed form: the growth a sample (to 1e-9, or within
/// `√ε` of the free motions' 1 where stable), and where unstable the longest stable period
/// (`lo`, to 1e-4) and the scene's warning, starting `at` and holding each of `holds`; where
/// stable, none.
fn check_loop(
    l: &satsim_tools::scene::sampled_loop::SampledLoop,
    expected: f64,
    lo: f64,
    s: &Scene,
    at: &str,
    holds: &[&str],
) {
    let unstable = expected > 1.0;
    let tolerance = if unstable { 1e-9 * expected } else { 1e-6 };
    assert!(
        (l.growth - expected).abs() < tolerance,
        "{l:?} against {expected}"
    );
    let warned = s
        .warnings
        .iter()
        .find(|w| w.contains("the sampled law is unstable"));
    if unstable {
        let below = l.stable_below.unwrap();
        assert!((below - lo).abs() < 1e-4 * lo, "{below} against {lo}");
        let w = warned.expect("a warning");
        let growth = format!("grows by a factor {expected:.4} a sample");
        assert!(
            w.starts_with(at) && w.contains(&growth) && holds.iter().all(|h| w.contains(h)),
            "{w}"
        );
    } else {
        assert_eq!(l.stable_below, None);
        assert!(warned.is_none(), "{warned:?}");
    }
}

/// A sampled attitude law on the bus with its wheels: each axis is a double integrator of
/// inertia 10.1, 20.1 or 30.1 kg m² (its wheel free) under a zero-order-hold PD, whose loop
/// is known in closed form. The check's growth a sample and its longest stable period agree
/// with it; stable, the scene reads without a warning, unstable with one at the section's
/// line; the RK4 check leaves the sampled law out.
#[test]
fn a_sampled_attitude_law_unstable_at_its_period_is_a_warning_with_the_stable_period() {
    use satsim_tools::scene::sampled_loop::sampled_attitude;
    use satsim_tools::scene::step_limit::AttitudeGains;
    let (kp, kd) = (100.0, 50.0);
    let axes = [10.1, 20.1, 30.1];
    let closed_form = |t: f64| {
        axes.iter()
            .map(|&i| zoh_growth(i, kp, kd, t))
            .fold(1.0, f64::max)
    };
    let lo = longest_stable(closed_form);
    for (period, unstable) in [(0.2, false), (0.6, true)] {
        let text = wheeled_bus(0.0, kp, kd, &format!("period = {period}"), 0.01);
        let s = Scene::parse(&text, Path::new("bus.toml")).unwrap();
        let (tree, n) = integrated_tree(&s.model, None, &s.effects).unwrap();
        let q = integrated_q(&s.initial.q, n, &[]);
        let gains = HingeGains::of(&s.effects, 0);
        assert!(gains.attitude.is_none(), "a sampled law is not RK4's");
        let (law, sampled) = AttitudeGains::in_scene(&s.effects).unwrap();
        assert_eq!(sampled, Some(period));
        let l = sampled_attitude(&tree, &q, &gains, &law, period).unwrap();
        // Stable, the largest |z| is the free motions' 1 (Jordan blocks: within √ε).
        let expected = closed_form(period);
        assert_eq!(expected > 1.0, unstable);
        check_loop(
            &l,
            expected,
            lo,
            &s,
            "bus.toml:27: [effects.attitude_control]",
            &[],
        );
    }
}

/// A sampled hinge law on the arm (a double integrator of inertia 0.6 kg m², no spring):
/// its zero-order-hold loop is [`zoh_growth`]'s. The check's growth a sample and its longest
/// stable period agree with the closed form; stable, the scene reads without a warning,
/// unstable with one at the section's line naming the hinge and its gains.
#[test]
fn a_sampled_hinge_law_unstable_at_its_period_is_a_warning_with_the_stable_period() {
    use satsim_tools::scene::sampled_loop::{HingeLaw, sampled_hinges};
    let (kp, kd) = (10.0, 2.0);
    let lo = longest_stable(|t| zoh_growth(I, kp, kd, t));
    let mut swings = Vec::new();
    for (period, unstable) in [(0.2, false), (0.6, true)] {
        let control = format!(
            "[effects.hinge_control]\nperiod = {period}\n[[effects.hinge_control.hinge]]\nname = \"h\"\nstart = 0.1\nend = 0.0\nt_start = 0.0\nduration = 1.0\nkp = {kp}\nkd = {kd}\n"
        );
        let s = Scene::parse(&arm(0.0, 0.0, &control, 0.01), Path::new("arm.toml")).unwrap();
        let law = HingeLaw::in_scene(&s.effects).unwrap();
        assert_eq!(
            law,
            HingeLaw {
                hinges: vec![(0, kp, kd)],
                period
            }
        );
        let tree = FlexModel::attach(s.model.clone(), &[]).unwrap();
        let gains = HingeGains::of(&s.effects, 1);
        let l = sampled_hinges(&tree, &s.initial.q, &gains, &law).unwrap();
        let expected = zoh_growth(I, kp, kd, period);
        assert_eq!(expected > 1.0, unstable);
        let gains = "`h` kp = 10 N m/rad, kd = 2 N m s/rad";
        check_loop(
            &l,
            expected,
            lo,
            &s,
            "arm.toml:25: [effects.hinge_control]",
            &[gains],
        );
        swings.push(largest_angle(&s, 0.01).unwrap());
    }
    // The runs agree: the stable loop keeps the arm within its start, the unstable one
    // throws it (the loop doubles a motion each 0.6 s sample).
    assert!(swings[0] <= 0.1 + 1e-12 && swings[1] > 0.4, "{swings:?}");
    // A continuous law is RK4's, not this check's.
    let continuous = "[effects.hinge_control]\n[[effects.hinge_control.hinge]]\nname = \"h\"\nstart = 0.1\nend = 0.0\nduration = 1.0\nkp = 10.0\n";
    let s = Scene::parse(&arm(0.0, 0.0, continuous, 0.01), Path::new("arm.toml")).unwrap();
    assert_eq!(HingeLaw::in_scene(&s.effects), None);
}

/// `|z|` of a zero-order-hold PID on a double integrator of inertia `i`, its integral stepped
/// `I ← I + T θ` before the output `u = −kp θ − ki I − kd ω`: the loop on `[θ, ω, I]`.
fn zoh_pid_growth(i: f64, (kp, ki, kd): (f64, f64, f64), t: f64) -> f64 {
    let (b, c, k) = (t * t / (2.0 * i), t / i, kp + t * ki);
    let m = nalgebra::Matrix3::new(
        1.0 - b * k,
        t - b * kd,
        -b * ki,
        -c * k,
        1.0 - c * kd,
        -c * ki,
        t,
        0.0,
        1.0,
    );
    m.complex_eigenvalues()
        .iter()
        .map(|z| z.norm())
        .fold(0.0, f64::max)
}

/// The flight software's PID on the wheels (`[fsw.control]`), on the wheeled bus: each axis a
/// double integrator under a zero-order-hold PID, whose loop is known in closed form. The
/// check's growth a sample and its longest stable period agree with it, per-axis gains and
/// the integral included; without `ki` it is the attitude law's loop.
#[test]
fn a_sampled_pid_on_the_wheels_is_checked_against_its_closed_form_loop() {
    use satsim_tools::scene::sampled_loop::{PidLaw, sampled_attitude, sampled_pid};
    use satsim_tools::scene::step_limit::{AttitudeGains, wheel_allocation};
    // The attitude law sampled, so that the tree's K and D hold no controller.
    let text = wheeled_bus(0.0, 1.0, 1.0, "period = 1.0", 0.01);
    let s = Scene::parse(&text, Path::new("bus.toml")).unwrap();
    let (tree, n) = integrated_tree(&s.model, None, &s.effects).unwrap();
    let q = integrated_q(&s.initial.q, n, &[]);
    let gains = HingeGains::of(&s.effects, 0);
    let allocation = wheel_allocation(&s.effects).unwrap();
    let axes = [10.1, 20.1, 30.1];
    let law = |period: f64| PidLaw {
        kp: [100.0, 150.0, 120.0],
        ki: [20.0, 5.0, 30.0],
        kd: [50.0, 80.0, 90.0],
        period,
    };
    let closed_form = |l: &PidLaw, t: f64| {
        (0..3)
            .map(|a| zoh_pid_growth(axes[a], (l.kp[a], l.ki[a], l.kd[a]), t))
            .fold(1.0, f64::max)
    };
    let l0 = law(1.0);
    let lo = longest_stable(|t| closed_form(&l0, t));
    for (period, unstable) in [(0.1, false), (0.6, true), (1.0, true)] {
        let l = sampled_pid(&tree, &q, &gains, &allocation, &law(period)).unwrap();
        let expected = closed_form(&law(period), period);
        let tolerance = if unstable { 1e-9 * expected } else { 1e-6 };
        assert!(
            (l.growth - expected).abs() < tolerance,
            "{period}: {l:?} against {expected}"
        );
        if unstable {
            let below = l.stable_below.unwrap();
            assert!((below - lo).abs() < 1e-4 * lo, "{below} against {lo}");
        } else {
            assert_eq!(l.stable_below, None);
        }
    }
    // Without `ki`, equal gains on the axes: the attitude law's loop.
    let pd = PidLaw {
        kp: [100.0; 3],
        ki: [0.0; 3],
        kd: [50.0; 3],
        period: 0.6,
    };
    let attitude = AttitudeGains {
        kp: 100.0,
        kd: 50.0,
        allocation: allocation.clone(),
    };
    let a = sampled_attitude(&tree, &q, &gains, &attitude, 0.6).unwrap();
    let p = sampled_pid(&tree, &q, &gains, &allocation, &pd).unwrap();
    assert!(
        (a.growth - p.growth).abs() < 1e-12 * a.growth,
        "{a:?} {p:?}"
    );
}

/// The unit beam (L = EI = ρA = 1 kg/m, one mode, `stiffening` on by default) along x on a
/// hub fixed to the inertial frame, swinging about z on hinge `spin` at `rate`, bending along
/// the spin axis, undeformed: the spin stiffens it (`ω² = ω₀² + Ω² J₁`, Southwell's
/// 1.193 Ω²) and leaves its bending out of the hinge's motion, so that its mode alone limits
/// the step.
fn spinning_beam(rate: f64, step: f64) -> String {
    format!(
        "duration = 20.0
[model]
[model.base]
kind = \"fixed\"
[[model.body]]
name = \"hub\"
mass = 10.0
inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
[[model.body]]
name = \"boom\"
mass = 0.0
[model.body.flexible]
beam = {{ root = [0.0, 0.0, 0.0], axis = [1.0, 0.0, 0.0], bend = [0.0, 0.0, 1.0],
         length = 1.0, EI = 1.0, rho_A = 1.0, modes = 1 }}
[[model.hinge]]
name = \"spin\"
parent = \"hub\"
child = \"boom\"
axis = [0.0, 0.0, 1.0]
[initial]
hinges = {{ angle = [0.0], rate = [{rate}] }}
[integrator]
method = \"rk4\"
step = {step}
[output]
every = 20.0
plots = false
view = false
"
    )
}

/// A beam with `stiffening` on a spinning spacecraft is stiffer than at rest, and RK4's limit
/// is the stiffened mode's: spun at 5 rad/s the unit beam's mode goes from 0.5596 Hz to
/// 1.0338 Hz, its limit from 0.804 s to 0.435 s. A step of 0.6 s between them, which a check
/// of the modes at rest passes, grows without bound; the reader refuses it, naming the
/// stiffened frequency, and the limit's frequency is `satsim modes`' (the linearised dynamics
/// at the initial state, every velocity term included) and the closed form's. (Deformed at
/// the start, the beam's foreshortening changes its inertia about the spin axis, which
/// couples its bending with the free hinge's rate: `satsim modes` has that gyroscopic
/// coupling and the check does not, a difference of second order in the deformation.)
#[test]
fn a_spinning_stiffened_beams_step_limit_is_its_stiffened_modes() {
    use satsim_tools::scene::flexible::highest_frequency;
    use satsim_tools::scene::step_limit::RK4_LIMIT;
    let spin = 5.0;
    let s = Scene::parse(&spinning_beam(spin, 0.01), Path::new("spin.toml")).unwrap();
    let flex = s.flexible.as_ref().unwrap();
    let gains = HingeGains::of(&s.effects, 1);
    let limit = rk4_limit(flex, &s.initial_q(), &s.initial_v(), &gains).unwrap();
    assert_eq!(limit.by, Limiting::Mode(0));
    // The closed form: ω² = ω₀² + Ω² J₁, J₁ = ρA ∫ (L² − x²)/2 φ'² dx (1.193 for mode 1).
    let (w0, _) = highest_frequency(flex, &s.initial_q()).unwrap();
    let j1 = flex.beam(1).unwrap().stiffening_integrals().j1[0];
    assert!((j1 - 1.193).abs() < 1e-3, "{j1}");
    let w = (w0 * w0 + spin * spin * j1).sqrt();
    assert!(
        (limit.omega - w).abs() < 1e-6 * w,
        "{} against {w}",
        limit.omega
    );
    assert!(
        (limit.step - RK4_LIMIT / w).abs() < 1e-6 * limit.step,
        "{limit:?}"
    );
    assert!(
        (limit.geometric - spin * spin * j1 / (w * w)).abs() < 1e-6,
        "{limit:?}"
    );
    // `satsim modes`' highest frequency is the limit's, to the linearisation's accuracy.
    let modes = satsim_tools::modes::modes(&s).unwrap();
    let highest = modes.frequencies_hz.last().copied().unwrap();
    let hz = limit.omega / std::f64::consts::TAU;
    assert!(
        (highest - hz).abs() < 1e-6 * hz,
        "{highest} Hz against {hz} Hz"
    );
    // At rest the check is the unstiffened mode's.
    let still = Scene::parse(&spinning_beam(0.0, 0.01), Path::new("spin.toml")).unwrap();
    let rest = rk4_limit(flex, &still.initial_q(), &still.initial_v(), &gains).unwrap();
    assert!((rest.omega - w0).abs() < 1e-12 * w0 && rest.geometric == 0.0);
    // 0.6 s: within the unstiffened limit (0.804 s), beyond the stiffened one (0.435 s).
    let between = 0.6;
    assert!(RK4_LIMIT / w0 > between && limit.step < between);
    // The mode deflected at the start, tip 2 cm off the axis.
    let mut deflected = s.clone();
    deflected.elastic.eta[0] = 0.01;
    let eta = |h: f64| largest(&deflected, h, "eta_boom_1");
    let under = eta(0.98 * limit.step).unwrap();
    assert!(under <= 0.01 + 1e-9, "{under}");
    let over = eta(between);
    assert!(over.is_none_or(|m| m > 1e3), "{over:?}");
    // Read from the file, the step is refused at its line with the stiffened frequency.
    let err = Scene::parse(&spinning_beam(spin, between), Path::new("spin.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("spin.toml:24")
            && err.contains("mostly body `boom`'s mode 1, stiffened by the initial motion, whose geometric stiffness is 70.7 % of the mode's")
            && err.contains(&format!("is at {hz:.4} Hz"))
            && err.contains("1.0338 Hz")
            && err.contains("stable on it only for steps up to 4.3542e-1 s"),
        "{err}"
    );
    Scene::parse(&spinning_beam(spin, 0.4), Path::new("spin.toml")).expect("a stable step");
    let (step, what) = rk4_stable_step(&s).unwrap();
    assert_eq!(
        (step, what.as_str()),
        (limit.step, "body `boom`'s mode 1 (1.034 Hz)")
    );
}

/// The arm on a stiff spring (ω = 129 rad/s, damper `c`) for 60 s under `method`: at ζ = 0.2 its swing
/// dies in a tenth of a second, and then only the stability of that motion holds an explicit
/// method's steps for the rest of the run.
fn damped_arm(method: &str, rtol: f64, c: f64) -> Scene {
    let text = arm(1e4, c, "", 0.001).replace(
        "method = \"rk4\"\nstep = 0.001",
        &format!("method = \"{method}\"\nrtol = {rtol}\natol = {rtol}"),
    );
    let text = text.replace("duration = 2.0", "duration = 60.0");
    Scene::parse(&text, Path::new("arm.toml")).unwrap()
}

/// DP5(4)'s and DOP853's regions (`step_limit`) hold their runs' steps where nothing else does:
/// on the arm's damped spring their mean steps come within a factor 1.5 of the limits, and the
/// run says so, naming the hinge and Radau IIA; with the swing kept up (ζ = 0.0006) and a tight
/// tolerance, the tolerance holds the steps far below the limit and nothing is said.
#[test]
fn an_explicit_methods_steps_held_by_a_stiff_motion_are_a_warning_after_the_run() {
    use satsim_integrate::Method;
    use satsim_tools::scene::step_limit::{HELD, step_limit};
    let c = 0.2 * 2.0 * (1e4 * I).sqrt();
    for (method, name) in [(Method::Dp54, "dp54"), (Method::Dop853, "dop853")] {
        let s = damped_arm(name, 1e-6, c);
        let (w, z) = ((1e4 / I).sqrt(), 0.2);
        let lambda = nalgebra::Complex::new(-z * w, w * (1.0 - z * z).sqrt());
        let (limit, what) = satsim_tools::scene::step_limit::stable_step(&s, method).unwrap();
        assert!(
            (limit - step_limit(method, lambda)).abs() < 1e-12 * limit,
            "{limit}"
        );
        assert_eq!(what, "hinge `h` (20.547 Hz)");
        let (_, warnings) = satsim_tools::api::run_scene_warned(&s, || false).unwrap();
        let held = warnings
            .iter()
            .find(|w| w.contains("held the steps"))
            .unwrap_or_else(|| panic!("{name}: {warnings:?}"));
        assert!(
            held.contains(&format!("steps of {name} averaged"))
                && held.contains("its stability limit on hinge `h` (20.547 Hz)")
                && held.contains("`integrator.method = \"radau5\"`")
                && !held.contains("elastic_error"),
            "{held}"
        );
        // The mean step it quotes is within the factor of the limit.
        let mean: f64 = held
            .split("averaged ")
            .nth(1)
            .and_then(|r| r.split(' ').next())
            .unwrap()
            .parse()
            .unwrap();
        assert!(
            mean <= HELD * limit && mean >= limit / HELD,
            "{mean} {limit}"
        );
        // Radau IIA steps over it: far fewer steps, nothing said.
        let radau = damped_arm("radau5", 1e-6, c);
        let (_, warnings) = satsim_tools::api::run_scene_warned(&radau, || false).unwrap();
        assert!(
            warnings.iter().all(|w| !w.contains("held the steps")),
            "{warnings:?}"
        );
        // Kept swinging and held to 1e-10, the steps are the tolerance's.
        let tight = damped_arm(name, 1e-10, 0.1);
        let (_, warnings) = satsim_tools::api::run_scene_warned(&tight, || false).unwrap();
        assert!(
            warnings.iter().all(|w| !w.contains("held the steps")),
            "{name}: {warnings:?}"
        );
    }
}

/// A sampled law's instants bound an explicit run's steps as its stability limit would: on
/// the damped arm under DP5(4), a hinge law sampled at 1/1.2 of the limit lands almost every
/// step on an instant, their mean within the factor of the limit, and nothing is said (an
/// implicit method would take as many steps). Sampled at ten times the limit, the steps between the
/// instants are the limit's, and the run says so.
#[test]
fn steps_held_by_a_sampled_laws_instants_are_not_a_warning() {
    use satsim_integrate::Method;
    let c = 0.2 * 2.0 * (1e4 * I).sqrt();
    let (limit, _) =
        satsim_tools::scene::step_limit::stable_step(&damped_arm("dp54", 1e-6, c), Method::Dp54)
            .unwrap();
    let sampled = |period: f64| {
        let law = format!(
            "[effects.hinge_control]\nperiod = {period}\n[[effects.hinge_control.hinge]]\nname = \"h\"\nstart = 0.0\nend = 0.0\nduration = 1.0\nkp = 1.0\n"
        );
        let text = arm(1e4, c, &law, 0.001)
            .replace(
                "method = \"rk4\"\nstep = 0.001",
                "method = \"dp54\"\nrtol = 1e-6\natol = 1e-6",
            )
            .replace("duration = 2.0", "duration = 60.0");
        let s = Scene::parse(&text, Path::new("arm.toml")).unwrap();
        let mut sim = s.simulation().unwrap();
        let every = satsim_integrate::Output::Interval(s.every);
        let run: Result<_, satsim_spacecraft::simulation::RunError<()>> =
            sim.run(&s.options, s.duration, &every, |_, _| Ok(()));
        let stats = run.unwrap();
        let warnings = satsim_tools::api::after_run_warnings(&s, &sim, &stats);
        let held = warnings.iter().any(|w| w.contains("held the steps"));
        (satsim_integrate::Steps::of(&stats, 0.0), held)
    };
    let (steps, held) = sampled(limit / 1.2);
    let mean = steps.span / steps.accepted as f64;
    assert!(
        !held && steps.accepted > 1000 && mean > limit / 1.5 && mean < 1.5 * limit,
        "{steps:?} {limit}"
    );
    // About a step a period: each instant goes on with the step the error control proposed
    // (3 247 steps for 3 098 instants, where a first step estimated at each took 18 342).
    assert!(steps.accepted < 2 * steps.capped, "{steps:?}");
    let (steps, held) = sampled(10.0 * limit);
    assert!(
        held && steps.capped < steps.accepted / 2,
        "{steps:?} {limit}"
    );
}
