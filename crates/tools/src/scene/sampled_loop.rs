//! Whether a sampled law is stable at its period: the zero-order-hold loop over one period,
//! on the scene's linear motions at its initial state (the linearisation of
//! [`super::step_limit`]). Three laws are checked: an attitude law (`[effects.attitude_control]`
//! with a `period`), a hinge law (`[effects.hinge_control]` with a `period`) and the flight
//! software's PID on the wheels (`[fsw.control]`, each mode's), each with the others left
//! out where several are sampled. An unstable one is the design's, not the
//! integrator's, so the scene reader warns of it and runs it.

use nalgebra::{Complex, DMatrix, Schur};
use satsim_spacecraft::effects::{EffectSet, HingeControl, SceneText};
use satsim_tree::Model;
use satsim_tree::error::Num;
use satsim_tree::flexible::FlexModel;
use satsim_tree::io::line_of;

use super::file::SceneFile;
use super::fsw::WheelLaw;
use super::step_limit::{
    AttitudeGains, HingeGains, last_stable, matrices, plant, rotor_dofs, wheel_allocation,
};

/// A scene's sampled laws, as the reader checks them: the attitude law with its period, the
/// hinge law, and the flight software's controls on the wheels with the wheels' allocation.
#[derive(Debug, Default)]
pub(super) struct SampledLaws {
    attitude: Option<(AttitudeGains, f64)>,
    hinges: Option<HingeLaw>,
    wheels: Vec<WheelLaw>,
    allocation: Option<DMatrix<f64>>,
}

impl SampledLaws {
    /// The sampled laws of `effects` and the flight software's `wheels` controls.
    pub(super) fn in_scene(effects: &EffectSet, wheels: Vec<WheelLaw>) -> Self {
        Self {
            attitude: AttitudeGains::in_scene(effects)
                .and_then(|(law, period)| period.map(|p| (law, p))),
            hinges: HingeLaw::in_scene(effects),
            allocation: (!wheels.is_empty())
                .then(|| wheel_allocation(effects))
                .flatten(),
            wheels,
        }
    }

    /// Whether there is none to check.
    pub(super) fn is_empty(&self) -> bool {
        self.attitude.is_none() && self.hinges.is_none() && self.wheels.is_empty()
    }

    /// A warning for each law unstable at its period, at its table's line in `src`, on
    /// `tree` (the tree the simulation integrates) at `q` with the continuous `gains`.
    pub(super) fn warnings(
        &self,
        src: &SceneText,
        file: &SceneFile,
        model: &Model,
        tree: &FlexModel,
        q: &[f64],
        gains: &HingeGains,
    ) -> Vec<String> {
        let section = |name: &str| {
            let line = file
                .effects
                .as_ref()
                .and_then(|e| e.get_ref().get(name))
                .map(|v| format!(":{}", line_of(src.text(), v.span().start)))
                .unwrap_or_default();
            format!("{}{line}: [effects.{name}]", src.path().display())
        };
        let mut out = Vec::new();
        if let Some((law, period)) = &self.attitude
            && let Some(l) = sampled_attitude(tree, q, gains, law, *period)
        {
            let g = format!(
                "kp = {} N m/rad, kd = {} N m s/rad",
                Num(law.kp),
                Num(law.kd)
            );
            out.extend(l.warning(&section("attitude_control"), *period, &g, Shows::Attitude));
        }
        if let Some(law) = &self.hinges
            && let Some(l) = sampled_hinges(tree, q, gains, law)
        {
            let g: Vec<String> = law
                .hinges
                .iter()
                .map(|&(h, kp, kd)| {
                    let name = &model.hinge_names()[h];
                    format!(
                        "`{name}` kp = {} N m/rad, kd = {} N m s/rad",
                        Num(kp),
                        Num(kd)
                    )
                })
                .collect();
            let at = section("hinge_control");
            out.extend(l.warning(&at, law.period, &g.join("; "), Shows::Hinges));
        }
        let allocation = self.allocation.as_ref();
        for wl in &self.wheels {
            let Some(l) = allocation.and_then(|a| sampled_pid(tree, q, gains, a, &wl.law)) else {
                continue;
            };
            let three = |v: &[f64; 3]| format!("[{}, {}, {}]", Num(v[0]), Num(v[1]), Num(v[2]));
            let law = &wl.law;
            let g = format!(
                "with a perfect estimate: kp = {} N m/rad, ki = {} N m/(rad s), kd = {} N m s/rad",
                three(&law.kp),
                three(&law.ki),
                three(&law.kd)
            );
            let at = format!("{}:{}: {}", src.path().display(), wl.line, wl.title);
            out.extend(l.warning(&at, law.period, &g, Shows::FlightSoftware));
        }
        out
    }
}

/// What a run of an unstable sampled law shows, for its warning.
#[derive(Clone, Copy)]
enum Shows {
    Attitude,
    Hinges,
    FlightSoftware,
}

/// How a sampled law fares at its period ([`sampled_attitude`], [`sampled_hinges`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SampledLoop {
    /// The largest `|z|` of the closed loop's eigenvalues over one period: above 1 a motion
    /// grows by that factor a sample.
    pub growth: f64,
    /// Where the loop is unstable at its period: the longest period below it at which it is
    /// stable (the stable periods found from zero up, to round-off), `None` where it is
    /// stable at its own.
    pub stable_below: Option<f64>,
}

impl SampledLoop {
    /// The warning for a law at `at` (`file:line: [table]`) with its `gains` in words, where
    /// it is unstable at its `period`: the design's instability, not the integrator's, so the
    /// run goes ahead. `None` where it is stable.
    fn warning(&self, at: &str, period: f64, gains: &str, shows: Shows) -> Option<String> {
        let below = self.stable_below?;
        let (motion, run) = match shows {
            Shows::Attitude => (
                "the bus's",
                "the attitude diverge, or chatter within the wheels' torque limits (a flight software at this rate would do the same)",
            ),
            Shows::Hinges => (
                "the hinges'",
                "the hinges diverge, or chatter within their torque limits (a real controller at this rate would do the same)",
            ),
            Shows::FlightSoftware => (
                "the bus's",
                "the attitude diverge, or chatter within the wheels' torque limits (the flight software at this rate would do the same)",
            ),
        };
        Some(format!(
            "{at}: the sampled law is unstable at `period` = {} s: on {motion} linear motion at the initial state ({gains}; the torques held between samples) a motion grows by a factor {:.4} a sample; it is stable at periods up to {below:.4e} s. A run shows {run}",
            Num(period),
            self.growth,
        ))
    }
}

/// `|z|` above `1 + this` is growth: the free motions' eigenvalues `z = 1` (a free base's
/// translation, a wheel, a hinge without a spring: Jordan blocks, which round-off splits by
/// about `√ε`; 1.3e-7 on the test's bus) and the undamped modes' `|z| = 1` are not. A loop
/// growing by less than this a sample takes over 70 000 samples to double.
const GROWTH_TOLERANCE: f64 = 1e-5;

/// A sampled attitude law (`[effects.attitude_control]` with a `period`) on the scene's linear
/// motions at the initial state (as [`rk4_limit`](super::step_limit::rk4_limit)'s: `M` of the
/// tree with the rotors, `K` and `D` of `hinges`' continuous gains, friction and modes, the
/// modes' geometric stiffness at the initial motion left out): the
/// bus torque `u = −kp θ − kd ω` taken at each sample and held to the next (zero-order hold),
/// through the rotors' commands `τ = −A⁺ u`: over one period `x⁺ = Φ x + Γ u`
/// (`[[Φ, Γ], [0, 1]] = exp([[A, B], [0, 0]] T)`), so the loop is `x⁺ = (Φ − Γ G) x` with
/// `u = −G x`, stable where every eigenvalue has `|z| <= 1`. A property of the design (the
/// flight software would do the same), not of the integrator. `None` where `M` is not
/// positive definite, the base is not free or the tree has not the law's rotors.
pub fn sampled_attitude(
    flex: &FlexModel,
    q: &[f64],
    hinges: &HingeGains,
    law: &AttitudeGains,
    period: f64,
) -> Option<SampledLoop> {
    let dofs = law.rotor_dofs(flex, hinges)?;
    let n = flex.nv();
    // The rotors' generalised forces −A⁺ u.
    let mut qu = DMatrix::zeros(n, 3);
    for (r, &dof) in dofs.iter().enumerate() {
        for c in 0..3 {
            qu[(dof, c)] = -law.allocation[(r, c)];
        }
    }
    let mut g = DMatrix::zeros(3, 2 * n);
    for c in 0..3 {
        g[(c, c)] = law.kp;
        g[(c, n + c)] = law.kd;
    }
    zoh_loop(flex, q, hinges, &qu, &g, None, period)
}

/// A sampled hinge law (`[effects.hinge_control]` with a `period`): its gains on each
/// controlled hinge, in the section's order.
#[derive(Clone, Debug, PartialEq)]
pub struct HingeLaw {
    /// The hinge (model file order), `kp` (N m/rad) and `kd` (N m s/rad).
    pub hinges: Vec<(usize, f64, f64)>,
    /// The sample period (s).
    pub period: f64,
}

impl HingeLaw {
    /// The scene's hinge law where it is sampled; `None` for a continuous one (the RK4
    /// check's) or none.
    pub fn in_scene(effects: &EffectSet) -> Option<Self> {
        let c = effects.get::<HingeControl>()?;
        let period = c.period.as_ref()?.period();
        Some(Self {
            hinges: c.hinges.iter().map(|p| (p.hinge, p.kp, p.kd)).collect(),
            period,
        })
    }
}

/// A sampled hinge law on the scene's linear motions at the initial state (as
/// [`sampled_attitude`]'s): each controlled hinge's torque `u = −kp θ − kd θ̇` (about the
/// reference, which moves the operating point, not the loop) taken at each sample and held
/// to the next (the loop of [`sampled_attitude`]). The torque limits are left out: the linear motion is the one
/// inside them. `None` where `M` is not positive definite or a hinge is not in the tree.
pub fn sampled_hinges(
    flex: &FlexModel,
    q: &[f64],
    hinges: &HingeGains,
    law: &HingeLaw,
) -> Option<SampledLoop> {
    let rigid = flex.rigid();
    let n = flex.nv();
    let k = law.hinges.len();
    let mut qu = DMatrix::zeros(n, k);
    let mut g = DMatrix::zeros(k, 2 * n);
    for (c, &(h, kp, kd)) in law.hinges.iter().enumerate() {
        let dof = (0..rigid.n_bodies())
            .filter_map(|b| rigid.joint(b))
            .find(|j| j.hinge() == h)?
            .dof();
        qu[(dof, c)] = 1.0;
        g[(c, dof)] = kp;
        g[(c, n + dof)] = kd;
    }
    zoh_loop(flex, q, hinges, &qu, &g, None, law.period)
}

/// A sampled PID attitude law on the wheels (`[fsw.control]` with actuator `"wheels"`, its
/// default): per-axis gains (body axes) and its period.
#[derive(Clone, Debug, PartialEq)]
pub struct PidLaw {
    /// N m/rad.
    pub kp: [f64; 3],
    /// N m/(rad s).
    pub ki: [f64; 3],
    /// N m s/rad.
    pub kd: [f64; 3],
    /// The control period (s).
    pub period: f64,
}

/// A sampled PID law (`[fsw.control]` on the wheels) on the scene's linear motions at the
/// initial state (as [`sampled_attitude`]'s), with a perfect estimate: at each sample the
/// integral steps `I ← I + T θ`, then the bus torque `u = −kp∘θ − ki∘I − kd∘ω` is held to
/// the next, through the rotors' commands `τ = −A⁺ u` (`allocation`,
/// [`wheel_allocation`]). The feed-forward `ω × J ω` is
/// second order, the integral's clamp and the torque limits are outside the linear motion.
/// An observer's estimate keeps the loop's eigenvalues and adds its own (the separation
/// principle, for the linear motion), so a loop unstable here stays unstable with the
/// estimator; one stable here may still not be (the estimate's age at a sample is left out). `None` where `M` is not
/// positive definite, the base is not free or the tree has not the rotors.
pub fn sampled_pid(
    flex: &FlexModel,
    q: &[f64],
    hinges: &HingeGains,
    allocation: &DMatrix<f64>,
    law: &PidLaw,
) -> Option<SampledLoop> {
    let dofs = rotor_dofs(flex, hinges, allocation.nrows())?;
    let n = flex.nv();
    let mut qu = DMatrix::zeros(n, 3);
    for (r, &dof) in dofs.iter().enumerate() {
        for c in 0..3 {
            qu[(dof, c)] = -allocation[(r, c)];
        }
    }
    let mut g = DMatrix::zeros(3, 2 * n);
    let mut ki = DMatrix::zeros(3, 3);
    let mut theta = DMatrix::zeros(3, 2 * n);
    for c in 0..3 {
        g[(c, c)] = law.kp[c];
        g[(c, n + c)] = law.kd[c];
        ki[(c, c)] = law.ki[c];
        theta[(c, c)] = 1.0;
    }
    let integral = law
        .ki
        .iter()
        .any(|k| *k != 0.0)
        .then_some(Integral { ki, theta });
    zoh_loop(flex, q, hinges, &qu, &g, integral.as_ref(), law.period)
}

/// A sampled law's integral `I` of `θ = C x`, stepped `I ← I + T θ` at each sample before
/// the output `u = −G x − Ki I`.
struct Integral {
    /// `Ki` (inputs × integrals).
    ki: DMatrix<f64>,
    /// `C` (integrals × states).
    theta: DMatrix<f64>,
}

/// The zero-order-hold loop of the inputs `u = −G x` (`k` of them, each a generalised force
/// `Q_u`'s column), held over `period` on `ẋ = A x + B u`, `A` the linearisation of
/// [`rk4_limit`](super::step_limit::rk4_limit) (a continuous attitude controller's gains
/// included) and `B = [0; M⁻¹ Q_u]`: over one period `x⁺ = Φ x + Γ u`
/// (`[[Φ, Γ], [0, 1]] = exp([[A, B], [0, 0]] T)`), so the loop is `x⁺ = (Φ − Γ G) x`, stable
/// where every eigenvalue has `|z| <= 1`. With an `integral`, `u = −G x − Ki I⁺` and
/// `I⁺ = I + T C x`: the loop on `[x; I]` is `[[Φ − Γ (G + T Ki C), −Γ Ki], [T C, 1]]`.
fn zoh_loop(
    flex: &FlexModel,
    q: &[f64],
    hinges: &HingeGains,
    qu: &DMatrix<f64>,
    g: &DMatrix<f64>,
    integral: Option<&Integral>,
    period: f64,
) -> Option<SampledLoop> {
    let n = flex.nv();
    let k = qu.ncols();
    let r = integral.map_or(0, |i| i.theta.nrows());
    let (km, dm) = matrices(flex, hinges);
    let (a, m_inv) = plant(flex, q, &km, &dm)?;
    let mut bm = DMatrix::zeros(2 * n, k);
    bm.view_mut((n, 0), (n, k)).copy_from(&(&m_inv * qu));
    let growth = |t: f64| -> Option<f64> {
        let mut aug = DMatrix::zeros(2 * n + k, 2 * n + k);
        aug.view_mut((0, 0), (2 * n, 2 * n)).copy_from(&(&a * t));
        aug.view_mut((0, 2 * n), (2 * n, k)).copy_from(&(&bm * t));
        let e = aug.exp();
        let phi = e.view((0, 0), (2 * n, 2 * n)).into_owned();
        let gamma = e.view((0, 2 * n), (2 * n, k)).into_owned();
        // z = 1 + t μ, μ the eigenvalues of (loop − 1)/t: a short period puts every z near
        // 1, where the Schur iteration on the loop itself does not converge, while
        // (loop − 1)/t tends to the continuous loop's matrix.
        let mut closed = DMatrix::zeros(2 * n + r, 2 * n + r);
        let mut gain = g.clone();
        if let Some(i) = integral {
            gain += &i.ki * &i.theta * t;
            closed
                .view_mut((0, 2 * n), (2 * n, r))
                .copy_from(&(-(&gamma * &i.ki) / t));
            closed.view_mut((2 * n, 0), (r, 2 * n)).copy_from(&i.theta);
        }
        let mut x = phi - gamma * gain;
        for i in 0..2 * n {
            x[(i, i)] -= 1.0;
        }
        closed.view_mut((0, 0), (2 * n, 2 * n)).copy_from(&(x / t));
        let mu = Schur::try_new(closed, f64::EPSILON, 10_000)?.complex_eigenvalues();
        let one = Complex::new(1.0, 0.0);
        let largest = mu.iter().map(|m| (one + m * t).norm()).fold(0.0, f64::max);
        largest.is_finite().then_some(largest)
    };
    let at = growth(period)?;
    // A period whose loop the decomposition cannot resolve is taken for stable: the warning
    // names only the growth it measured.
    let stable = |t: f64| growth(t).is_none_or(|z| z <= 1.0 + GROWTH_TOLERANCE);
    // The first unstable period of a scan from zero, then bisection below it.
    let stable_below = (at > 1.0 + GROWTH_TOLERANCE).then(|| last_stable(stable, period, 40, 40));
    Some(SampledLoop {
        growth: at,
        stable_below,
    })
}
