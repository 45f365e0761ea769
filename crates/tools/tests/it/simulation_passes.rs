//! The simulation's passes, white-box: the lean event pass against the full one, the centre
//! of mass only on request, the unrolled kernel against the generic ABA in the right-hand
//! side and the hold torques.

use satsim_integrate::{System, SystemError};
use satsim_spacecraft::effects::{Context, Effect, EventReads, Forces, Needs};
use satsim_spacecraft::simulation::Simulation;
use satsim_tools::scene::Scene;
use satsim_tree::samples::SplitMix;
use satsim_tree::spatial::Vec3;
use satsim_tree::{BaseKind, State, samples::chain};
use std::path::{Path, PathBuf};

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

/// Scenes whose built-in effects have events, in every mode: hinges latched at the start
/// (locked), free stops, rebounding stops, wheels stuck at the start (locked, reading hold
/// torques and the controller's commands) and wheels slipping.
fn scenes() -> Vec<(String, Simulation)> {
    let deploy = examples().join("scenes/deploy.toml");
    let text = std::fs::read_to_string(&deploy).unwrap();
    // h4 starts on its latching stop; wheel y spins (slips), x and z start at rest (stuck).
    let modes = text
        .replace(
            "angle = [0.0, 0.0, 0.0, 3.14159, -3.14159]",
            "angle = [0.0, 0.0, 0.0, 0.0, -0.5]",
        )
        .replace("name = \"y\"", "name = \"y\"\nspeed = 5.0");
    assert_ne!(modes, text);
    let mut out = Vec::new();
    for (name, text, path) in [
        ("deploy", text.clone(), deploy.clone()),
        ("deploy, latched and stuck", modes, deploy),
    ] {
        let scene = Scene::parse(&text, &path).unwrap();
        out.push((name.to_owned(), scene.simulation().unwrap()));
    }
    for f in ["scenes/two_wings.toml", "scenes/spin_down.toml"] {
        let scene = Scene::read(examples().join(f)).unwrap();
        out.push((f.to_owned(), scene.simulation().unwrap()));
    }
    out
}

/// `x0` with every state but the orbit moved at random (attitude renormalised).
/// `a` equals `b` to round-off: every entry within `1e-12` of `b`'s largest.
fn assert_round_off(a: &[f64], b: &[f64], what: &str) {
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(diff <= 1e-12 * scale, "{what}: {diff:e} of {scale:e}");
}

fn random_state(sim: &Simulation, rng: &mut SplitMix) -> Vec<f64> {
    let l = sim.layout().clone();
    let mut x = sim.x0().to_vec();
    let orbit = l
        .effects
        .iter()
        .find(|(n, _)| n == "orbit")
        .map(|(_, r)| r.clone());
    for (k, v) in x.iter_mut().enumerate() {
        if orbit.as_ref().is_some_and(|r| r.contains(&k)) {
            continue;
        }
        *v += rng.range(-0.5, 0.5);
    }
    if l.free {
        let a = l.attitude.clone();
        let n = x[a.clone()].iter().map(|v| v * v).sum::<f64>().sqrt();
        x[a].iter_mut().for_each(|v| *v /= n);
    }
    x
}

/// Every built-in effect's event functions give, bit for bit, the same `g` in the lean pass
/// (only what `event_reads` declares is computed; the rest is left from an evaluation at
/// another state) as in the full pass, at random states in every mode.
#[test]
fn lean_event_pass_equals_the_full_pass() {
    let mut rng = SplitMix(0xe7e);
    let (mut stuck_wheels, mut locked_hinges, mut lean_passes) = (0, 0, 0);
    for (name, mut sim) in scenes() {
        let n_user = sim.layout().angles.len();
        let locked = sim.locked().to_vec();
        locked_hinges += locked[..n_user].iter().filter(|&&l| l).count();
        stuck_wheels += locked[n_user..].iter().filter(|&&l| l).count();
        let n = sim.n_events();
        assert!(n > 0, "{name}");
        let mut dx = vec![0.0; sim.dim()];
        let (mut lean, mut full) = (vec![0.0; n], vec![0.0; n]);
        for trial in 0..50 {
            // Stale buffers: forces, kinematics and hold torques of another state.
            let other = random_state(&sim, &mut rng);
            sim.reference_events(rng.range(0.0, 100.0), &other, &mut full)
                .unwrap();
            sim.rhs(rng.range(0.0, 100.0), &other, &mut dx).unwrap();
            let stale = sim.data().forces().hinge_torque.clone();
            let t = rng.range(0.0, 100.0);
            let x = random_state(&sim, &mut rng);
            sim.events(t, &x, &mut lean).unwrap();
            let reads = sim
                .effects()
                .filter(|e| e.n_events() > 0)
                .fold(EventReads::STATE, |r, e| r.union(e.event_reads()));
            if !reads.forces {
                // Lean indeed: no effect was applied.
                assert_eq!(sim.data().forces().hinge_torque, stale, "{name}");
                lean_passes += 1;
            }
            sim.reference_events(t, &x, &mut full).unwrap();
            for k in 0..n {
                assert_eq!(
                    lean[k].to_bits(),
                    full[k].to_bits(),
                    "{name}, trial {trial}, event {k}: lean {} full {}",
                    lean[k],
                    full[k]
                );
            }
        }
    }
    // The modes above were really exercised.
    assert!(
        locked_hinges >= 1 && stuck_wheels >= 2,
        "{locked_hinges} {stuck_wheels}"
    );
    assert!(lean_passes >= 100, "{lean_passes} passes without `apply`");
}

/// An effect that reads the centre of mass, declaring it or not.
#[derive(Clone)]
struct ReadsCom(bool);

impl Effect for ReadsCom {
    fn name(&self) -> &str {
        "reads_com"
    }
    fn needs(&self) -> Needs {
        Needs {
            kinematics: true,
            com: self.0,
            ..Needs::default()
        }
    }
    fn apply(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        _own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        forces.hinge_torque[0] += ctx.com_or_err("reads_com")?.x;
        Ok(())
    }
}

/// The centre of mass is there for an effect that declares it, and an error naming the
/// effect and the declaration otherwise (never a silent zero).
#[test]
fn centre_of_mass_only_when_declared() {
    let model = chain(3, BaseKind::Free);
    let mut state = State::rest(&model);
    state.q[7] = 0.4;
    for declared in [true, false] {
        let sim = Simulation::builder(model.clone())
            .initial(state.clone())
            .effect(ReadsCom(declared))
            .build();
        match (declared, sim) {
            (true, Ok(mut sim)) => {
                let x = sim.x0().to_vec();
                let mut dx = vec![0.0; x.len()];
                sim.rhs(0.0, &x, &mut dx).unwrap();
            }
            (false, Err(e)) => {
                let e = e.to_string();
                assert!(e.contains("reads_com") && e.contains("Needs::com"), "{e}");
            }
            (d, r) => panic!("declared {d}: {:?}", r.err()),
        }
    }
}

/// The default scene (examples/scenes/deploy.toml: the gravity gradient asks for
/// kinematics and writes a wrench on every body; wheels, springs, stops) takes the unrolled
/// ABA with its forces, and its right-hand side equals the generic ABA's to round-off at
/// random states; the forward kinematics the effects read is left as it was. In three
/// modes: as written (the wheels start at rest, held by static friction: locked rotors,
/// hybrid dynamics), with h4 latched from the start as well (a locked serial hinge), and
/// with the wheels spinning (nothing locked).
#[test]
fn unrolled_aba_with_forces_and_kinematics_in_the_right_hand_side() {
    let deploy = examples().join("scenes/deploy.toml");
    let text = std::fs::read_to_string(&deploy).unwrap();
    let latched = text.replace(
        "angle = [0.0, 0.0, 0.0, 3.14159, -3.14159]",
        "angle = [0.0, 0.0, 0.0, 0.0, -0.5]",
    );
    let spinning = ["x", "y", "z"].iter().fold(text.clone(), |t, w| {
        t.replace(
            &format!("name = \"{w}\""),
            &format!("name = \"{w}\"\nspeed = 5.0"),
        )
    });
    assert!(latched != text && spinning != text);
    for (text, n_locked) in [(text, 3), (latched, 4), (spinning, 0)] {
        let scene = Scene::parse(&text, &deploy).unwrap();
        let mut fast = scene.simulation().unwrap();
        assert_eq!(fast.locked().iter().filter(|&&l| l).count(), n_locked);
        let fd = fast.sim_model().dynamics();
        assert!(fd.kernel().is_some(), "the kernel's layout");
        assert!(
            fd.uses_kernel(Some(fast.locked())),
            "no gimbal hinge locked"
        );
        let mut generic = scene.simulation().unwrap();
        generic.use_generic_dynamics();
        let mut rng = SplitMix(8);
        let n = fast.dim();
        for _ in 0..50 {
            let x = random_state(&fast, &mut rng);
            let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
            fast.rhs(0.0, &x, &mut a).unwrap();
            // The kernel's arm with kinematics and wrenches.
            assert!(fast.runs_kinematics() && fast.data().forces().has_wrench);
            let bodies = fast.model().bodies();
            for (body, f) in bodies.iter().zip(&fast.data().forces().body_wrench) {
                if body.mass() > 0.0 {
                    assert!(
                        f.ang != Vec3::zeros() && f.lin != Vec3::zeros(),
                        "{}",
                        body.name()
                    );
                }
            }
            generic.rhs(0.0, &x, &mut b).unwrap();
            assert_round_off(&a, &b, &format!("{n_locked} locked"));
            // The poses of the forward kinematics are those of this state in both.
            for (p, q) in fast
                .data()
                .tree()
                .position
                .iter()
                .zip(&generic.data().tree().position)
            {
                assert_eq!(p, q);
            }
        }
    }
}

/// The hold torques of the default scene's stuck wheels and latched panel (one hybrid solve
/// for the locked hinges, and one per unlocked hinge: a gimbal hinge's goes to the generic
/// code) equal the generic hybrid ABA's to round-off at random states.
#[test]
fn unrolled_aba_in_the_hold_torques() {
    let deploy = examples().join("scenes/deploy.toml");
    let text = std::fs::read_to_string(&deploy).unwrap();
    let latched = text.replace(
        "angle = [0.0, 0.0, 0.0, 3.14159, -3.14159]",
        "angle = [0.0, 0.0, 0.0, 0.0, -0.5]",
    );
    for (text, n_locked) in [(text.clone(), 3), (latched, 4)] {
        let scene = Scene::parse(&text, &deploy).unwrap();
        let mut fast = scene.simulation().unwrap();
        assert!(fast.needs_hold_torques() && fast.sim_model().dynamics().kernel().is_some());
        assert_eq!(fast.locked().iter().filter(|&&l| l).count(), n_locked);
        let mut generic = scene.simulation().unwrap();
        generic.use_generic_dynamics();
        let mut rng = SplitMix(9);
        for _ in 0..30 {
            let x = random_state(&fast, &mut rng);
            for all in [false, true] {
                let a = fast.hold_torques(0.0, &x, all).unwrap().to_vec();
                let b = generic.hold_torques(0.0, &x, all).unwrap();
                let scale = b.iter().fold(0.0f64, |m, h| m.max(h.abs()));
                assert!(scale > 0.0);
                for (k, (a, b)) in a.iter().zip(b).enumerate() {
                    assert_eq!(a.is_nan(), b.is_nan(), "hinge {k}");
                    if !b.is_nan() {
                        assert!((a - b).abs() <= 1e-12 * scale, "hinge {k}: {a:e} {b:e}");
                    }
                }
            }
        }
    }
}

/// The peer orbit's scene (benches/peers/orbit.toml: the preprint satellite with three
/// wheels) takes the unrolled ABA, and its right-hand side equals the generic ABA's to
/// round-off at random states.
#[test]
fn unrolled_aba_in_the_right_hand_side() {
    let scene = Scene::read(examples().join("../benches/peers/orbit.toml")).unwrap();
    let mut fast = scene.simulation().unwrap();
    assert!(fast.sim_model().dynamics().kernel().is_some());
    // The velocities are one run of the state: the kernel writes `q̈` straight into `dx`.
    assert!(fast.velocity_is_one_run());
    let mut generic = scene.simulation().unwrap();
    generic.use_generic_dynamics();
    let mut rng = SplitMix(5);
    let n = fast.dim();
    for _ in 0..50 {
        let x = random_state(&fast, &mut rng);
        let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
        fast.rhs(0.0, &x, &mut a).unwrap();
        generic.rhs(0.0, &x, &mut b).unwrap();
        assert_round_off(&a, &b, "orbit");
    }
}

/// An effect that reads the reaction wheels' poses with the poses alone ([`Needs::poses`]
/// and the default `reads_rotor_poses`) and adds nothing: each `apply` checks that the
/// first wheel (a rotor hinged to the bus about a coordinate axis, its angle 0) is turned
/// exactly as its carrier, an error otherwise.
#[derive(Clone)]
struct ReadsRotorPoses;

impl Effect for ReadsRotorPoses {
    fn name(&self) -> &str {
        "reads_rotor_poses"
    }
    fn needs(&self) -> Needs {
        Needs {
            poses: true,
            ..Needs::default()
        }
    }
    fn apply(
        &mut self,
        ctx: &Context,
        _forces: &mut Forces,
        _own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        let g = &ctx.model.gyrostats()[0];
        let (rotor, carrier) = (ctx.data.rotation[g.body()], ctx.data.rotation[g.parent()]);
        if (rotor - carrier).norm() > 1e-15 {
            return Err(SystemError::new("reads_rotor_poses: a stale rotor pose"));
        }
        Ok(())
    }
}

/// The deployment scene (the gravity gradient reads the poses only and loads the wheels
/// through the bus, so the right-hand side leaves the wheels' poses out), with the extra
/// effect or without.
fn deploy_with(reads_rotors: bool) -> Simulation {
    let scene = Scene::read(examples().join("scenes/deploy.toml")).unwrap();
    let mut b = Simulation::builder(scene.model.clone())
        .initial(scene.initial.clone())
        .energy_budget(scene.energy_budget);
    for e in scene.effects.to_boxed() {
        b = b.boxed(e);
    }
    if reads_rotors {
        b = b.effect(ReadsRotorPoses);
    }
    b.build().unwrap()
}

/// An effect that reads a rotor's pose with the poses alone gets it current at every
/// right-hand side (the bus turned at random states); and leaving the rotors' poses out, as
/// the right-hand side does without such an effect, changes no bit of its result, with the
/// unrolled kernel and with the generic ABA (which reads the rotors' transforms, kept from
/// the start).
#[test]
fn rotor_poses_are_skipped_only_where_no_effect_reads_them() {
    for generic in [false, true] {
        let mut rng = SplitMix(47);
        let (mut skip, mut read) = (deploy_with(false), deploy_with(true));
        if generic {
            skip.use_generic_dynamics();
            read.use_generic_dynamics();
        }
        assert!(skip.x0().len() == read.x0().len());
        for trial in 0..40 {
            let x = random_state(&skip, &mut rng);
            let (mut a, mut b) = (vec![0.0; x.len()], vec![0.0; x.len()]);
            skip.rhs(0.0, &x, &mut a).unwrap();
            read.rhs(0.0, &x, &mut b)
                .unwrap_or_else(|e| panic!("generic {generic}, trial {trial}: {e}"));
            let bits = |v: &[f64]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&a), bits(&b), "generic {generic}, trial {trial}");
        }
    }
}
