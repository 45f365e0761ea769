//! The longest fixed RK4 step a scene's linear stiffness and damping allow, at its initial
//! state: the flexible bodies' modes, the hinge springs and dampers
//! (`[effects.hinge_springs]`), the continuous hinge controllers' gains
//! (`[effects.hinge_control]` without a `period`), the reaction wheels' viscous friction and a
//! continuous attitude controller's gains (`[effects.attitude_control]` without a `period`,
//! acting through the wheels). Beyond it a motion grows without bound, so the scene reader
//! refuses such a step at its line and the accuracy sweep does not run it.
//!
//! The linearisation is `ẋ = [[0, I], [−M⁻¹K, −M⁻¹D]] x` over the generalised velocity's
//! coordinates of the tree the simulation integrates (the model's, then its wheels' rotors,
//! [`with_rotors`](satsim_spacecraft::simulation::with_rotors)), `M` the (flexible) tree's mass
//! matrix at the initial state. `K` and `D` are diagonal but for the attitude controller:
//! `ωₖ²` and `2ζₖωₖ` on each elastic coordinate, a hinge's spring stiffness plus its
//! controller's `kp` and its damping plus `kd` on its coordinate, a wheel's viscous friction
//! on its rotor's; the attitude controller's motor commands `τ = −A⁺ u` with
//! `u = −kp θ − kd ω` (its small-error law, `θ` the bus's rotation) put `−kp A⁺` and
//! `−kd A⁺` in the rotors' rows and the bus's rotation columns. A flexible body with
//! `stiffening` on a moving spacecraft adds its geometric stiffness at the initial
//! velocities to the elastic block of `K` ([`geometric_stiffness`]): a spinning beam is
//! stiffer, its modes faster, and the step shorter. Left out: the other velocity terms'
//! slopes (gyroscopic coupling, the rigid bodies' centrifugal stiffness), the effects' loads
//! (thrust, the gravity gradient), sampled controllers, stops, the wheels' torque limits (the
//! linear motion is the one inside them) and their Coulomb and Stribeck friction (not linear
//! at a slip).

use nalgebra::{Complex, DMatrix};
use satsim_integrate::{Method, Steps};
use satsim_spacecraft::effects::{
    AttitudeControl, EffectSet, HingeControl, HingeSprings, ReactionWheels,
};
use satsim_tree::Model;
use satsim_tree::flexible::{FlexError, FlexModel};

use super::flexible::{eigen_of, modal_stiffness, mode_of};

/// RK4's stability limit on the imaginary axis: an undamped oscillation of angular frequency
/// `ω` stays bounded for `ω h <= 2√2` (the largest `|λ h|` on the imaginary axis where
/// `|1 + z + z²/2 + z³/6 + z⁴/24| <= 1`).
pub const RK4_LIMIT: f64 = 2.0 * std::f64::consts::SQRT_2;

/// The largest step `h` for which RK4 keeps `ẋ = λ x` bounded (`|R(λ h')| <= 1` for every
/// `h' <= h`): `2√2 / |λ|` on the imaginary axis, `2.785 / |λ|` on the negative real axis,
/// infinite for `λ = 0`, zero for a growing mode (`Re λ > 0`) ([`step_limit`] for RK4).
pub fn rk4_step_limit(lambda: Complex<f64>) -> f64 {
    step_limit(Method::Rk4, lambda)
}

/// The largest step `h` for which the explicit `method` keeps `ẋ = λ x` bounded
/// (`|R(λ h')| <= 1` for every `h' <= h`, `R` its stability polynomial,
/// [`Method::stability_gain`]); infinite for `λ = 0` or the implicit Radau IIA (A-stable),
/// zero for a growing mode (`Re λ > 0`). Along the ray of `λ` from the origin the region is
/// an interval within `|z| < 8` (RK4's within 3, DP5(4)'s within 3.4, DOP853's within
/// 6.4): its end is found by a scan, then bisection to round-off.
///
/// DP5(4)'s region crosses the imaginary axis only to `0.997`, and beyond it an undamped
/// motion grows by parts per million a step; a damping ratio of 0.5 % moves the ray's end to
/// `1.70 / ω`, where the step-size controller of a scene's lightly damped mode settles.
pub fn step_limit(method: Method, lambda: Complex<f64>) -> f64 {
    let r = lambda.norm();
    if r == 0.0 || method.stability_polynomial().is_none() {
        return f64::INFINITY;
    }
    let u = lambda / r;
    // Round-off's allowance: on the imaginary axis `|R| = 1` at the origin (and at RK4's end).
    let stable = |s: f64| {
        method
            .stability_gain(u.re * s, u.im * s)
            .is_some_and(|g| g <= 1.0 + 1e-12)
    };
    last_stable(stable, 8.0, 800, 60) / r
}

/// The end of the interval `[0, s*]` on which `stable` holds, within `[0, end]`: a scan of
/// `scan` equal steps finds the first point where it fails (`end` where none does), then
/// `bisections` halvings close in on the boundary below it.
pub(super) fn last_stable(
    stable: impl Fn(f64) -> bool,
    end: f64,
    scan: usize,
    bisections: usize,
) -> f64 {
    let (mut lo, mut hi) = (0.0, end);
    for k in 1..=scan {
        let s = end * k as f64 / scan as f64;
        if !stable(s) {
            hi = s;
            break;
        }
        lo = s;
    }
    for _ in 0..bisections {
        let mid = 0.5 * (lo + hi);
        if stable(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The eigenvalue that limits `method`'s step most among `ev` and that step. The free motions'
/// zero eigenvalues come out of the Schur decomposition as round-off, `±1e-17` on the
/// deployment scene, some with a positive real part, where RK4's region has no room (a
/// spurious limit of `1e-12/|λ|`): eigenvalues below `1e-6` of the largest in size are taken
/// for zero. A real one that small would limit the step a million times less than the largest.
fn fastest(method: Method, ev: &[Complex<f64>]) -> Option<(Complex<f64>, f64)> {
    let largest = ev.iter().map(|l| l.norm()).fold(0.0, f64::max);
    ev.iter()
        .filter(|l| l.norm() > 1e-6 * largest)
        .map(|&l| (l, step_limit(method, l)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// The linear stiffness and damping a scene puts on its hinges, one entry per hinge of the
/// tree the simulation integrates (the model file's order, then the wheels' rotors): the
/// springs' and dampers' plus the continuous controllers' `kp` and `kd`, and each wheel's
/// viscous friction on its rotor; and a continuous attitude controller's gains, which act on
/// the bus's rotation through the rotors.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HingeGains {
    /// N m/rad.
    pub stiffness: Vec<f64>,
    /// N m s/rad.
    pub damping: Vec<f64>,
    /// The continuous attitude controller, where the scene has one.
    pub attitude: Option<AttitudeGains>,
    /// The model's own hinges, before the rotors'.
    model_hinges: usize,
}

/// A continuous attitude controller's linear law ([`AttitudeControl`]): the bus torque
/// `u = −kp θ − kd ω` for a small rotation `θ` of the bus from its target and its rate `ω`
/// (bus axes), commanded to the rotors as `τ = −A⁺ u`.
#[derive(Clone, Debug, PartialEq)]
pub struct AttitudeGains {
    /// N m/rad.
    pub kp: f64,
    /// N m s/rad.
    pub kd: f64,
    /// `A⁺`: a row per rotor, in the rotors' order ([`AttitudeControl::allocation_for`]).
    pub allocation: DMatrix<f64>,
}

impl AttitudeGains {
    /// The scene's attitude law on the rotors of its effects, and its `period` (`None`:
    /// continuous); `None` without a controller or rotors.
    pub fn in_scene(effects: &EffectSet) -> Option<(Self, Option<f64>)> {
        let control = effects.get::<AttitudeControl>()?;
        let law = Self {
            kp: control.kp,
            kd: control.kd,
            allocation: wheel_allocation(effects)?,
        };
        Some((law, control.period()))
    }

    /// The velocity coordinate of each rotor the law commands, in the allocation's order,
    /// on `flex`, whose last hinges they are after the model's `hinges.model_hinges`; `None`
    /// where the base is not free or the tree has not those rotors (the model alone).
    pub(super) fn rotor_dofs(&self, flex: &FlexModel, hinges: &HingeGains) -> Option<Vec<usize>> {
        rotor_dofs(flex, hinges, self.allocation.nrows())
    }
}

/// The attitude controllers' allocation over the effects' rotors, `A⁺` a row per rotor
/// ([`AttitudeControl::allocation_for`]: the root's wheels, as `[fsw.control]` allocates
/// too); `None` without rotors.
pub fn wheel_allocation(effects: &EffectSet) -> Option<DMatrix<f64>> {
    let rotors = effects.rotors();
    (!rotors.is_empty()).then(|| AttitudeControl::allocation_for(&rotors))
}

/// [`AttitudeGains::rotor_dofs`] for an allocation over `n` rotors.
pub(super) fn rotor_dofs(flex: &FlexModel, hinges: &HingeGains, n: usize) -> Option<Vec<usize>> {
    let rigid = flex.rigid();
    let first = hinges.model_hinges;
    if rigid.base_nv() != 6 || n == 0 || rigid.n_hinges() != first + n {
        return None;
    }
    let mut dofs = vec![0; n];
    for b in 0..rigid.n_bodies() {
        if let Some(j) = rigid.joint(b)
            && let Some(r) = j.hinge().checked_sub(first)
        {
            dofs[r] = j.dof();
        }
    }
    Some(dofs)
}

impl HingeGains {
    /// None on any of `n_hinges` hinges.
    pub fn none(n_hinges: usize) -> Self {
        Self {
            stiffness: vec![0.0; n_hinges],
            damping: vec![0.0; n_hinges],
            attitude: None,
            model_hinges: n_hinges,
        }
    }

    /// The gains `effects` put on the model's `n_hinges` hinges and on the rotors after them:
    /// `hinge_springs`, `hinge_control` where it is continuous (a sampled law's stability
    /// depends on its period, not on RK4), the wheels' viscous friction, and
    /// `attitude_control` where it is continuous. A tree without the rotors
    /// ([`with_rotors`](satsim_spacecraft::simulation::with_rotors)) reads only the first
    /// `n_hinges` entries and no attitude controller.
    pub fn of(effects: &EffectSet, n_hinges: usize) -> Self {
        let rotors = effects.rotors();
        let mut g = Self::none(n_hinges + rotors.len());
        g.model_hinges = n_hinges;
        if let Some(w) = effects.get::<ReactionWheels>()
            && w.wheels.len() == rotors.len()
        {
            for (j, wheel) in w.wheels.iter().enumerate() {
                g.damping[n_hinges + j] += wheel.viscous;
            }
        }
        g.attitude = AttitudeGains::in_scene(effects)
            .filter(|(_, period)| period.is_none())
            .map(|(law, _)| law);
        if let Some(s) = effects.get::<HingeSprings>() {
            for (i, (k, c)) in s
                .stiffness
                .iter()
                .zip(&s.damping)
                .enumerate()
                .take(n_hinges)
            {
                g.stiffness[i] += k;
                g.damping[i] += c;
            }
        }
        if let Some(c) = effects.get::<HingeControl>().filter(|c| c.period.is_none()) {
            for p in c.hinges.iter().filter(|p| p.hinge < n_hinges) {
                g.stiffness[p.hinge] += p.kp;
                g.damping[p.hinge] += p.kd;
            }
        }
        g
    }
}

/// What mostly moves in the motion that limits an explicit method's step ([`StepLimit`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limiting {
    /// An elastic coordinate (index among them): a flexible body's mode.
    Mode(usize),
    /// A hinge (model file order, then the wheels' rotors), on its spring, damper or
    /// controller, or a rotor on its viscous friction.
    Hinge(usize),
    /// The bus on the attitude controller: the step is shorter with it than without.
    Attitude,
}

/// What limits an explicit method's step ([`explicit_limit`], [`rk4_limit`]).
#[derive(Clone, Debug, PartialEq)]
pub struct StepLimit {
    /// The largest stable step (s).
    pub step: f64,
    /// The eigenvalue that sets it (1/s; its conjugate too where complex).
    pub lambda: Complex<f64>,
    /// The undamped coupled motion it belongs to (mostly): its angular frequency (rad/s; zero
    /// for a motion that only a damper holds) ...
    pub omega: f64,
    /// ... its damping ratio (its share of the damping, `xᵀ D x / 2ω`; infinite at `ω = 0`) ...
    pub zeta: f64,
    /// ... the coordinate whose stiffness and damping take the largest share of it ...
    pub by: Limiting,
    /// ... and the share of its stiffness (`xᵀ K x = ω²`) that the flexible bodies'
    /// geometric stiffness at the initial motion gives ([`geometric_stiffness`]): zero at
    /// rest or without `stiffening`, negative where the motion softens it.
    pub geometric: f64,
}

impl StepLimit {
    /// Whether what limits the step is a wheel's rotor (a hinge of the tree that a gyrostat
    /// turns on), on its viscous friction.
    pub fn on_rotor(&self, flex: &FlexModel) -> bool {
        let Limiting::Hinge(h) = self.by else {
            return false;
        };
        let rigid = flex.rigid();
        rigid
            .gyrostats()
            .iter()
            .any(|g| rigid.joint(g.body()).is_some_and(|j| j.hinge() == h))
    }

    /// What limits the step, in words: "body `hub`'s mode 3" or "hinge `h1`".
    pub fn what(&self, flex: &FlexModel) -> String {
        match self.by {
            Limiting::Mode(e) => {
                let (body, mode) = mode_of(flex, e);
                format!("body `{body}`'s mode {mode}")
            }
            Limiting::Hinge(h) => {
                let name = &flex.rigid().hinge_names()[h];
                if self.on_rotor(flex) {
                    format!("rotor `{name}` on its viscous friction")
                } else {
                    format!("hinge `{name}`")
                }
            }
            Limiting::Attitude => "the bus".to_owned(),
        }
    }
}

/// The diagonals of `K` and `D` over the generalised velocity's coordinates (rigid `v…`, then
/// `η̇…`), and each coordinate's hinge (`None` for the base's and the elastic ones).
fn diagonals(flex: &FlexModel, hinges: &HingeGains) -> (Vec<f64>, Vec<f64>, Vec<Option<usize>>) {
    let rigid = flex.rigid();
    let first = rigid.nv();
    let n = flex.nv();
    let mut k = modal_stiffness(flex);
    let mut d = vec![0.0; n];
    d[first..].copy_from_slice(flex.damping());
    let mut hinge_of = vec![None; n];
    for b in 0..rigid.n_bodies() {
        if let Some(j) = rigid.joint(b) {
            let (h, v) = (j.hinge(), j.dof());
            if let (Some(kh), Some(ch)) = (hinges.stiffness.get(h), hinges.damping.get(h)) {
                k[v] += kh;
                d[v] += ch;
            }
            hinge_of[v] = Some(h);
        }
    }
    (k, d, hinge_of)
}

/// [`diagonals`]' `K` and `D` as matrices.
fn diagonal_matrices(flex: &FlexModel, hinges: &HingeGains) -> (DMatrix<f64>, DMatrix<f64>) {
    let (k, d, _) = diagonals(flex, hinges);
    let diagonal = |v: Vec<f64>| DMatrix::from_diagonal(&nalgebra::DVector::from_vec(v));
    (diagonal(k), diagonal(d))
}

/// The relative step of [`geometric_stiffness`]'s central differences, of the coordinate
/// that bends a body by its size ([`FlexModel::modal_scale`]): the terms are linear in `η`
/// but for the deflection's rotation of what a body carries, whose error is this squared.
const GEOMETRIC_STEP: f64 = 1e-4;

/// The flexible bodies' geometric stiffness at the motion `v` (the tree's velocities, the
/// elastic rates included) and the positions `q`: `∂/∂η` of the modal rows of the velocity
/// products `b(q, v) − b(q, 0)` ([`bias`](satsim_tree::flexible::bias), the tree's inverse
/// dynamics at zero acceleration less the modes' own stiffness), an `n_e × n_e` matrix over
/// the elastic coordinates. With `stiffening` a beam on a spinning spacecraft is stiffened
/// by its sections' centrifugal pull and softened in the plane of the spin by the deflection's
/// own inertia, and what it carries pulls on it too; the dynamics give it as
/// `K_g(v) η − (ωᵀ A₂ ω) η` and the foreshortening of its loads' points (the theory page,
/// "Geometric stiffening"), and so does this, by central differences. `None` where nothing
/// moves, no body has `stiffening`, or the dynamics fail at `q`.
pub fn geometric_stiffness(flex: &FlexModel, q: &[f64], v: &[f64]) -> Option<DMatrix<f64>> {
    use satsim_tree::flexible::{FlexData, bias};
    let rigid = flex.rigid();
    let n = flex.n_elastic();
    let stiffened = (0..rigid.n_bodies()).any(|i| flex.stiffened(i));
    if n == 0 || !stiffened || v.iter().all(|x| *x == 0.0) {
        return None;
    }
    let (nq, nv) = (rigid.nq(), rigid.nv());
    let mut data = FlexData::new(flex);
    let still = vec![0.0; v.len()];
    // The modal rows of b(q, v) − b(q, 0): the velocity products alone (the modes' own
    // stiffness `ωₖ² ηₖ` cancels, so that its round-off does not swamp them).
    let mut moving = |x: &[f64]| -> Option<Vec<f64>> {
        let with = bias(flex, &mut data, x, v, None).ok()?.as_slice()[nv..].to_vec();
        let without = bias(flex, &mut data, x, &still, None).ok()?;
        Some(
            with.iter()
                .zip(&without.as_slice()[nv..])
                .map(|(a, b)| a - b)
                .collect(),
        )
    };
    let mut kg = DMatrix::zeros(n, n);
    let mut x = q.to_vec();
    for j in 0..n {
        let h = GEOMETRIC_STEP * flex.modal_scale(j).unwrap_or(1.0).max(q[nq + j].abs());
        x[nq + j] = q[nq + j] + h;
        let plus = moving(&x)?;
        x[nq + j] = q[nq + j] - h;
        let minus = moving(&x)?;
        x[nq + j] = q[nq + j];
        for i in 0..n {
            kg[(i, j)] = (plus[i] - minus[i]) / (2.0 * h);
        }
    }
    kg.iter().all(|k| k.is_finite()).then_some(kg)
}

/// `km` with the geometric stiffness `kg` added to its elastic block (the last rows and
/// columns, after the rigid tree's).
fn with_geometric(
    mut km: DMatrix<f64>,
    flex: &FlexModel,
    kg: Option<&DMatrix<f64>>,
) -> DMatrix<f64> {
    if let Some(kg) = kg {
        let first = flex.rigid().nv();
        let mut block = km.view_mut((first, first), (kg.nrows(), kg.ncols()));
        block += kg;
    }
    km
}

/// `K` and `D` as matrices, with a continuous attitude controller's gains from the bus's
/// rotation to the rotors (`hinges.attitude`, where the tree has the rotors it commands):
/// `Q_r = τ_r = −(A⁺ u)_r = (A⁺ (kp θ + kd ω))_r`, written `Q = −K x − D ẋ`.
pub(super) fn matrices(flex: &FlexModel, hinges: &HingeGains) -> (DMatrix<f64>, DMatrix<f64>) {
    let (mut km, mut dm) = diagonal_matrices(flex, hinges);
    if let Some(att) = &hinges.attitude
        && let Some(dofs) = att.rotor_dofs(flex, hinges)
    {
        for (r, &dof) in dofs.iter().enumerate() {
            for a in 0..3 {
                km[(dof, a)] -= att.kp * att.allocation[(r, a)];
                dm[(dof, a)] -= att.kd * att.allocation[(r, a)];
            }
        }
    }
    (km, dm)
}

/// The largest step RK4 is stable at on the scene's linear motions at `q` moving at `v` (the
/// flexible bodies' modes, stiffened by the motion where they have `stiffening`
/// ([`geometric_stiffness`]), and the `hinges`' gains, damping included): the eigenvalues `λ` of
/// `ẋ = [[0, I], [−M⁻¹K, −M⁻¹D]] x`, the smallest [`rk4_step_limit`]. Undamped it is `2√2 / ω`
/// of the highest mode; a heavily damped motion (`ζ > 1`) has a real eigenvalue up to `2ζω`
/// in size and limits the step below that (a damper alone, `−c` over the inertia it moves).
/// The motion named is the undamped coupled one whose own damped eigenvalue
/// (`λ² + 2ζωλ + ω² = 0` with its share of `D`) limits the step most, and in it the
/// coordinate with the largest share of `K + |λ| D`. `None` when nothing is stiff or damped,
/// or when `M` is not positive definite at `q`.
///
/// A rigid model is passed as a [`FlexModel`] without flexible bodies
/// (`FlexModel::attach(model, &[])`).
///
/// A continuous attitude controller (`hinges.attitude`, on a tree with the rotors it
/// commands) adds its gains from the bus's rotation to the rotors, which are not diagonal:
/// where the coupled system's eigenvalues with them limit the step more than those without,
/// the limit is theirs ([`Limiting::Attitude`], `ω = |λ|` and `ζ = −Re λ / |λ|` of the
/// limiting eigenvalue: a second-order motion's own for a complex pair, `ζ = 1` for a real
/// one).
pub fn rk4_limit(flex: &FlexModel, q: &[f64], v: &[f64], hinges: &HingeGains) -> Option<StepLimit> {
    explicit_limit(Method::Rk4, flex, q, v, hinges)
}

/// [`rk4_limit`] for any explicit `method`, on its own stability region ([`step_limit`]):
/// the step DP5(4) or DOP853 cannot exceed for long whatever its tolerance, its controller
/// settling there when the tolerance alone would take longer steps. `None` for the implicit
/// Radau IIA, which no linear motion of a stable system holds.
pub fn explicit_limit(
    method: Method,
    flex: &FlexModel,
    q: &[f64],
    v: &[f64],
    hinges: &HingeGains,
) -> Option<StepLimit> {
    method.stability_polynomial()?;
    let kg = geometric_stiffness(flex, q, v);
    let diagonal = diagonal_limit(method, flex, q, kg.as_ref(), hinges);
    let Some(att) = &hinges.attitude else {
        return diagonal;
    };
    // A tree without the rotors (the model alone) has no controller to check.
    if att.rotor_dofs(flex, hinges).is_none() {
        return diagonal;
    }
    let (km, dm) = matrices(flex, hinges);
    let km = with_geometric(km, flex, kg.as_ref());
    let (lambda, step) = coupled_limit(method, flex, q, &km, &dm)?;
    if diagonal
        .as_ref()
        .is_some_and(|l| l.step <= step * (1.0 + 1e-9))
        || lambda.norm() == 0.0
    {
        return diagonal;
    }
    // A controller that moves a fast motion's frequency by less than a tenth leaves it that
    // motion (a panel's mode coupled to the bus it rocks): named as without the controller.
    let (by, geometric) = match diagonal {
        Some(d) if (d.omega - lambda.norm()).abs() <= 0.1 * lambda.norm() => (d.by, d.geometric),
        _ => (Limiting::Attitude, 0.0),
    };
    Some(StepLimit {
        step,
        lambda: Complex::new(lambda.re, lambda.im.abs()),
        omega: lambda.norm(),
        zeta: -lambda.re / lambda.norm(),
        by,
        geometric,
    })
}

/// The limiting eigenvalue of `ẋ = [[0, I], [−M⁻¹K, −M⁻¹D]] x` at `q` and its step
/// ([`fastest`]); `None` when `M` is not positive definite or the Schur decomposition does
/// not converge.
fn coupled_limit(
    method: Method,
    flex: &FlexModel,
    q: &[f64],
    km: &DMatrix<f64>,
    dm: &DMatrix<f64>,
) -> Option<(Complex<f64>, f64)> {
    let (a, _) = plant(flex, q, km, dm)?;
    nalgebra::Schur::try_new(a, f64::EPSILON, 10_000)
        .and_then(|s| fastest(method, s.complex_eigenvalues().as_slice()))
}

/// `A = [[0, I], [−M⁻¹K, −M⁻¹D]]` at `q`, and `M⁻¹`; `None` where `M` is not positive
/// definite.
pub(super) fn plant(
    flex: &FlexModel,
    q: &[f64],
    km: &DMatrix<f64>,
    dm: &DMatrix<f64>,
) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
    use satsim_tree::flexible::{FlexData, crba};
    let n = flex.nv();
    let mut data = FlexData::new(flex);
    let m = crba(flex, &mut data, q).ok()?.clone();
    let m_inv = m.cholesky()?.inverse();
    let mut a = DMatrix::zeros(2 * n, 2 * n);
    a.view_mut((0, n), (n, n)).fill_with_identity();
    a.view_mut((n, 0), (n, n)).copy_from(&(-&m_inv * km));
    a.view_mut((n, n), (n, n)).copy_from(&(-&m_inv * dm));
    Some((a, m_inv))
}

/// [`rk4_limit`] on the diagonal `K` and `D` (everything but the attitude controller), with
/// the geometric stiffness `kg` on the elastic block of `K`.
fn diagonal_limit(
    method: Method,
    flex: &FlexModel,
    q: &[f64],
    kg: Option<&DMatrix<f64>>,
    hinges: &HingeGains,
) -> Option<StepLimit> {
    let (k, d, hinge_of) = diagonals(flex, hinges);
    let km = DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(&k));
    let km = with_geometric(km, flex, kg);
    if km.iter().chain(&d).all(|v| *v == 0.0) {
        return None;
    }
    let (w2, x) = eigen_of(flex, q, &km)?;
    let n = flex.nv();
    let dm = DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(&d));
    // Each undamped motion with its share of the damping: which one limits the step.
    let roots = |w2: f64, c: f64| {
        let disc = Complex::new(0.25 * c * c - w2, 0.0).sqrt();
        [-0.5 * c + disc, -0.5 * c - disc]
    };
    let (mode, lambda, step) = (0..w2.len())
        .map(|j| {
            let xj = x.column(j);
            let c = xj.dot(&(&dm * xj));
            roots(w2[j].max(0.0), c)
                .into_iter()
                .map(|l| (j, l, step_limit(method, l)))
                .min_by(|a, b| a.2.total_cmp(&b.2))
                .expect("two roots")
        })
        .min_by(|a, b| a.2.total_cmp(&b.2))?;
    // The step itself from the coupled system's eigenvalues (the damping need not be
    // proportional to the stiffness), where the Schur decomposition converges.
    let (lambda, step) = coupled_limit(method, flex, q, &km, &dm).unwrap_or((lambda, step));
    let omega = w2[mode].max(0.0).sqrt();
    let xm = x.column(mode);
    let kx = &km * xm;
    let share = |i: usize| xm[i] * kx[i] + lambda.norm() * d[i] * xm[i] * xm[i];
    let top = (0..n).max_by(|a, b| share(*a).total_cmp(&share(*b)))?;
    // The geometric stiffness's part of `xᵀ K x` (= ω², the shapes mass-normalised).
    let geometric = match kg {
        Some(kg) if omega > 0.0 => {
            let xe = xm.rows(flex.rigid().nv(), kg.nrows());
            xe.dot(&(kg * xe)) / (omega * omega)
        }
        _ => 0.0,
    };
    let first = flex.rigid().nv();
    let by = match hinge_of[top] {
        Some(h) => Limiting::Hinge(h),
        None if top >= first => Limiting::Mode(top - first),
        None => return None,
    };
    let zeta = xm.dot(&(&dm * xm)) / (2.0 * omega);
    (step.is_finite() && step > 0.0).then_some(StepLimit {
        step,
        lambda: Complex::new(lambda.re, lambda.im.abs()),
        omega,
        zeta,
        by,
        geometric,
    })
}

/// The tree a simulation of a scene integrates, as the step limit checks it: `model` with its
/// flexible bodies `flex` and the effects' rotors hinged on after its hinges
/// ([`with_rotors`](satsim_spacecraft::simulation::with_rotors)), and the number of rotors;
/// the model alone (no rotors) where they do not fit it (the simulation's set-up then says
/// why).
pub fn integrated_tree(
    model: &Model,
    flex: Option<&FlexModel>,
    effects: &EffectSet,
) -> Result<(FlexModel, usize), FlexError> {
    let rotors = effects.rotors();
    let with = (!rotors.is_empty())
        .then(|| satsim_spacecraft::simulation::with_rotors(model, &rotors).ok())
        .flatten();
    let rotor_tree = with.and_then(|m| match flex {
        Some(f) => f.with_rigid(m).ok(),
        None => FlexModel::attach(m, &[]).ok(),
    });
    Ok(match rotor_tree {
        Some(t) => (t, rotors.len()),
        None => match flex {
            Some(f) => (f.clone(), 0),
            None => (FlexModel::attach(model.clone(), &[])?, 0),
        },
    })
}

/// The positions of [`integrated_tree`]'s tree: the model's `q`, the rotors' angles (zero),
/// then the elastic coordinates `eta`.
pub fn integrated_q(q: &[f64], n_rotors: usize, eta: &[f64]) -> Vec<f64> {
    q.iter()
        .copied()
        .chain(std::iter::repeat_n(0.0, n_rotors))
        .chain(eta.iter().copied())
        .collect()
}

/// The velocities of [`integrated_tree`]'s tree: the model's `v`, the `n_rotors` rotors'
/// speeds (the reaction wheels' initial `speed`, where they are the rotors; else zero),
/// then the elastic rates `etadot`.
pub fn integrated_v(v: &[f64], effects: &EffectSet, n_rotors: usize, etadot: &[f64]) -> Vec<f64> {
    let speeds: Vec<f64> = match effects.get::<ReactionWheels>() {
        Some(w) if w.wheels.len() == n_rotors => w.wheels.iter().map(|w| w.speed).collect(),
        _ => vec![0.0; n_rotors],
    };
    v.iter().chain(&speeds).chain(etadot).copied().collect()
}

/// The largest step RK4 is stable at for `scene` ([`rk4_limit`] at its initial state and
/// motion, with its hinge gains), and what limits it in words ([`StepLimit::what`], with the frequency);
/// `None` where nothing limits it. What the scene reader checks a given `integrator.step`
/// against, for the callers that choose steps themselves (the accuracy sweep).
pub fn rk4_stable_step(scene: &super::Scene) -> Option<(f64, String)> {
    stable_step(scene, Method::Rk4)
}

/// [`rk4_stable_step`] for any explicit `method` ([`explicit_limit`]); `None` for Radau IIA.
pub fn stable_step(scene: &super::Scene, method: Method) -> Option<(f64, String)> {
    let (tree, n_rotors) =
        integrated_tree(&scene.model, scene.flexible.as_ref(), &scene.effects).ok()?;
    let flex = &tree;
    let q = integrated_q(&scene.initial.q, n_rotors, &scene.elastic.eta);
    let v = integrated_v(
        &scene.initial.v,
        &scene.effects,
        n_rotors,
        &scene.elastic.etadot,
    );
    let gains = HingeGains::of(&scene.effects, scene.model.n_hinges());
    let limit = explicit_limit(method, flex, &q, &v, &gains)?;
    let what = format!(
        "{} ({:.3} Hz)",
        limit.what(flex),
        limit.omega / std::f64::consts::TAU
    );
    Some((limit.step, what))
}

/// How far from an explicit method's stability limit the mean accepted step of its run may be
/// (a factor either way) for the stiff motion rather than the tolerance to have held the steps
/// ([`held_steps_warning`]). On the shipped scenes under DP5(4), the mean step over the limit
/// is 0.87 on the flexible deployment and 0.99 on the stiff hinge, where the motion holds the
/// steps (a fifth and a tenth of the attempts rejected; 0.89 and 0.93 under DOP853); 0.18 or
/// less where the tolerance does (`cmg.toml`, `deploy.toml`, `two_wings.toml`, and
/// `spinning_booms.toml` at `rtol 1e-9`, `atol 1e-12`), and 12 where the motion is never
/// excited (`deployment_modes.toml`). `spinning_booms.toml` as shipped, DOP853 at `rtol
/// 1e-8`, `atol 1e-9`: 0.54 (steps of 0.072 s against the 0.133 s of the booms' 7.96 Hz
/// mode, a quarter of the attempts rejected), the tolerance and the limit sharing the hold,
/// and no warning: Radau IIA would step over the mode but not keep the angular momentum.
pub const HELD: f64 = 1.5;

/// The fewest accepted steps of a run whose steps [`held_steps_warning`] weighs: below it the
/// cost is not worth a warning.
pub const HELD_MIN_STEPS: usize = 1000;

/// Whether a run of `method` that took `accepted` steps can have been held by a stability
/// limit worth a warning: an adaptive explicit method (DP5(4), DOP853) and at least
/// [`HELD_MIN_STEPS`] steps. Cheap: the limit ([`stable_step`]) is worked out only then.
pub fn may_be_held(method: Method, accepted: usize) -> bool {
    method.is_explicit_adaptive() && accepted >= HELD_MIN_STEPS
}

/// Whether the `steps` of an explicit run were held by the stability `limit`: the steps the
/// error control set (those cut to land on a time stop, the run's end or `h_max` left out,
/// [`Steps::mean_free`]) have a mean within a factor [`HELD`] of the limit either way, and the
/// time stops (a sampled law's period, a stepped simulation's pieces) come no more often than
/// [`HELD`] times the limit. Stops that come more often than that bound the steps about as
/// much as the limit does, and an implicit method would take about as many.
pub fn held(steps: &Steps, limit: f64) -> bool {
    steps.mean_capped_spacing() >= HELD * limit
        && steps
            .mean_free()
            .is_some_and(|mean| mean <= HELD * limit && mean >= limit / HELD)
}

/// A warning where the `steps` of an adaptive explicit run of `scene` (DP5(4), DOP853) were
/// held by its stability limit on the scene's fastest linear motion ([`stable_step`],
/// [`held`]): that motion, not the tolerance, held the steps, and the implicit Radau IIA
/// would step over it. `None` for other methods, runs of fewer than [`HELD_MIN_STEPS`] steps
/// (a cost not worth a warning) and runs whose steps the tolerance or the time stops held.
pub fn held_steps_warning(scene: &super::Scene, steps: &Steps) -> Option<String> {
    let method = scene.options.method;
    if !may_be_held(method, steps.accepted) {
        return None;
    }
    held_steps_message(scene, steps, &stable_step(scene, method)?)
}

/// [`held_steps_warning`] with the stability limit and what sets it (`stable_step`'s) worked
/// out already: for a caller that weighs its steps more than once (a stepped simulation).
pub fn held_steps_message(
    scene: &super::Scene,
    steps: &Steps,
    (limit, what): &(f64, String),
) -> Option<String> {
    let method = scene.options.method;
    if !may_be_held(method, steps.accepted) || !held(steps, *limit) {
        return None;
    }
    let (accepted, mean) = (steps.accepted - steps.capped, steps.mean_free()?);
    let modes = if scene.flexible.is_some() {
        " (with `elastic_error = false` where the modes' own ringing need not be resolved)"
    } else {
        ""
    };
    Some(format!(
        "{}: the {accepted} steps of {method} averaged {mean:.3e} s, within a factor {HELD} of its stability limit on {what}, {limit:.3e} s: that motion, not the tolerance, held the steps; `integrator.method = \"radau5\"` (implicit) steps over it{modes}",
        scene.path.display()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Round-off's eigenvalues of the free motions (as the deployment scene's Schur
    /// decomposition gives them, scaled up a million times) do not limit the step; the
    /// oscillator does.
    #[test]
    fn round_off_eigenvalues_of_free_motions_do_not_limit_the_step() {
        let oscillator = Complex::new(-8.3333, 128.8302);
        let spurious = [Complex::new(4.5e-11, 5.1e-11), Complex::new(-2.4e-11, 0.0)];
        // Alone, a round-off eigenvalue in the right half-plane limits the step to nothing.
        assert!(
            rk4_step_limit(spurious[0]) < 0.1,
            "{}",
            rk4_step_limit(spurious[0])
        );
        let ev = [
            spurious[0],
            spurious[1],
            oscillator,
            oscillator.conj(),
            Complex::new(0.0, 0.0),
        ];
        let (l, step) = fastest(Method::Rk4, &ev).unwrap();
        assert_eq!(l.norm(), oscillator.norm());
        assert_eq!(step, rk4_step_limit(oscillator));
    }
}
