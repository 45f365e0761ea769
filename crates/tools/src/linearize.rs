//! Linearisation of a scene's equations of motion at its initial state: `ż = A z + B u`
//! (contract section 9, `satsim linearize`).
//!
//! # The linear state `z`
//!
//! In this order (names in [`Linearization::states`]):
//!
//! 1. free base only: the attitude error `att_x, att_y, att_z` (rad), a small rotation of the
//!    root **in root axes**: the attitude is `q = q_ref ⊗ exp(δθ)` (Hamilton `[w, x, y, z]`,
//!    `exp` of the rotation vector), so `A` has no quaternion redundancy;
//! 2. free base only: `omega_x, omega_y, omega_z` (root angular velocity, root axes, rad/s)
//!    and `vel_x, vel_y, vel_z` (velocity of the root frame's origin, root axes, m/s);
//! 3. `angle_<hinge>` for every hinge, file order (rad);
//! 4. `rate_<hinge>` for every hinge, file order (rad/s);
//! 5. with flexible bodies (contract section 14), `eta_<body>_<k>` for every elastic
//!    coordinate (the modal coordinate of mode `k` from 1, √kg m; bodies in the model's
//!    depth-first order), then `etadot_<body>_<k>` (√kg m/s);
//! 6. every state of an enabled effect, in the run's order, named by the effect
//!    (`orbit_r_x` … `orbit_v_z` in m and m/s, `wheel_<name>_speed` in rad/s).
//!
//! Every part but the attitude is the deviation of the run's state from the reference
//! trajectory through the initial state `x₀`. The sampled laws due at the start have
//! latched their outputs first, as a run latches them before its first step, and hold them
//! (a thruster's constant duty fires; a sampled controller's output has no derivative). The attitude error is measured from the
//! reference attitude as it moves: with `ω_ref` the reference's angular velocity, the
//! error obeys `δθ̇ = J_r⁻¹(δθ) (ω − exp(δθ)ᵀ ω_ref)`, which to first order is
//! `δθ̇ = δω − ω_ref × δθ`. At rest this is `δθ̇ = δω`; for a spinning or orbit-following
//! reference it keeps the transport term that the rigid-body and gravity-gradient
//! textbook linearisations have (and without which the roll-yaw frequencies of an
//! Earth-pointing satellite come out wrong).
//!
//! # The inputs `u`
//!
//! `torque_<hinge>` for every hinge (N m, added to the hinge torques, acting on the child and
//! reacting on the parent), then, when reaction wheels are enabled, `wheel_<name>` for every
//! wheel: a motor torque (N m) on the rotor about its axis, reacting on the bus, added after
//! the controller's command and the wheel's limits.
//!
//! # How the Jacobians are computed, and why
//!
//! By central differences of the simulation's own right-hand side (the exact code a run
//! integrates, every enabled effect included), with one step of Richardson extrapolation:
//! `D(h) = (f(z + h eⱼ) − f(z − h eⱼ)) / 2h` at `h` and `h/2`, combined as
//! `(4 D(h/2) − D(h)) / 3`, whose truncation error is `O(h⁴)`. The step is
//! `h = 10⁻³ · max(|x₀ⱼ|, s)` with `s` = 1 (rad, rad/s, m/s) for the tree's rigid states,
//! for a flexible body's modal coordinate and rate the coordinate that bends the body by its
//! size ([`satsim_tree::flexible::FlexModel::modal_scale`]: its tip by its length or its tip's
//! slope by a radian, per second for the rate; a light strip's or a high mode's is far below
//! 1 √kg m, where `η = 10⁻³` would bend it out of the linear range), and, for
//! an effect's states, the larger of 1 and 10⁻³ times the norm of that effect's state
//! (so an orbit radius of 7000 km is stepped by metres, not millimetres). The difference
//! `|(4 D(h/2) − D(h))/3 − D(h/2)|` bounds the error of the plain estimate and is reported
//! as [`Linearization::error_estimate`]; on the test scenes the extrapolated Jacobian
//! agrees with the analytic one to about 10⁻⁹ relative.
//!
//! A linearisation whose error estimate is more than [`ACCURACY`] (10⁻³) of its largest
//! entry is an error ([`LinearizeError::Inaccurate`]), and so is one with an entry beyond
//! [`LARGEST_ENTRY`] (`√(f64::MAX)`, [`LinearizeError::OutOfRange`]): neither describes
//! the dynamics, and printing it would pass for a result.
//!
//! The alternative, exact derivatives (the analytic derivatives of ABA of Carpentier and
//! Mansard 2018, or forward-mode dual numbers through the engine), would need every effect
//! (each behind the open [`satsim_spacecraft::effects::Effect`] trait, with its own code for wheels,
//! friction, controllers, orbits and gravity) to supply its own derivatives or to be generic
//! over the scalar type; a new effect would silently be linearised wrong if its author
//! forgot. Finite differences of the right-hand side linearise every effect, present and
//! future, with no extra code. The price is `4 (n + m)` right-hand-side evaluations for `n`
//! states and `m` inputs (about a hundred evaluations of a few microseconds for the
//! preprint's satellite with wheels and an orbit), paid once per configuration, not per
//! step. The tests check the result against analytic Jacobians (`−M⁻¹K` from the mass
//! matrix of CRBA, a second algorithm) and analytic frequencies.
//!
//! # Locks and friction
//!
//! A hinge that is locked at the initial state (latched on a stop) is rigid: the rows and
//! columns of its angle and rate in `A`, and its rows in `B`, are zero, and [`crate::modes`]
//! leaves it out. A reaction wheel held at rest by static friction is released instead
//! (listed in [`Linearization::released`]): strictly, a perturbation small enough for a
//! linear model would leave it stuck and the attitude controller without an actuator, which
//! is not the model a controller is designed with. Released, it slips; Coulomb friction is
//! then a constant of zero slope and the Stribeck term has zero slope at zero speed, so the
//! wheel's friction enters `A` through its viscous term only.
//!
//! # Limits
//!
//! Non-smooth effects (torque and
//! speed limits, the direction of wheel friction) are linearised on the side the initial
//! state is on: the finite-difference steps are small against any sensible limit, but a
//! state sitting exactly on a limit gets a one-sided slope averaged with the other.

use crate::scene::Scene;
use nalgebra::{DMatrix, Matrix3, Quaternion, UnitQuaternion};
use satsim_integrate::{System, stop_due};
use satsim_spacecraft::simulation::{SimError, Simulation};
use satsim_tree::spatial::Vec3;
use std::ops::Range;
use thiserror::Error;

/// Relative step of the finite differences (see the module documentation).
const STEP: f64 = 1e-3;

/// The largest [`Linearization::error_estimate`] accepted, as a fraction of the largest
/// entry of `A` and `B`. Smooth dynamics give far less: 6.2·10⁻¹⁰ of it on the rigid
/// deployment, 8.2·10⁻⁸ on `deployment_modes.toml`, 8.4·10⁻⁶ on the flexible deployment
/// stowed (its strips' modes beside its slow gimbal); an estimate of 10⁻³ of it or more means the central differences
/// straddle a kink or a jump of the right-hand side (a limit, a stop, a sign switch at the
/// initial state) or a sum that lost its digits, and the entries (and the frequencies
/// from them) have fewer than three correct digits.
pub const ACCURACY: f64 = 1e-3;

/// The largest entry of `A` and `B` accepted: `√(f64::MAX)` ≈ 1.3·10¹⁵⁴. The model is
/// used by multiplying its entries together (the eigenvalue decomposition of
/// [`crate::modes`], `A z`, `A²` of a discretisation), and a product of two larger entries
/// overflows: with a spring of 10³⁰⁸ the eigenvalues come out as 10²⁹⁸ where they are
/// 10¹⁵³, with negative damping ratios.
pub const LARGEST_ENTRY: f64 = 1.3407807929942596e154;

/// The largest rate of a group of states at the linearisation point (its
/// [`Linearization::residual`]'s norm) that still counts as an equilibrium, relative to the
/// larger of 1 and the largest entry of `A`: a state that stays put to round-off (10⁻¹⁶ of
/// its terms) passes, and a drift of 10⁻⁹ rad/s over a unit state is already far below what
/// a mode of the model would show.
pub const EQUILIBRIUM: f64 = 1e-9;

/// Why a scene could not be linearised.
#[derive(Debug, Error)]
pub enum LinearizeError {
    /// The scene could not be set up (an effect's needs, the initial state).
    #[error("{0}")]
    Setup(#[from] SimError),
    /// The right-hand side failed at or near the initial state.
    #[error("the dynamics failed near the initial state: {0}")]
    Dynamics(String),
    /// A Jacobian entry is not finite (a singular configuration).
    #[error("the linearisation is not finite: d({row})/d({col}) = {value}")]
    NonFinite {
        /// The state whose derivative it is.
        row: String,
        /// The state or input it is differentiated by.
        col: String,
        /// The value.
        value: f64,
    },
    /// An entry beyond [`LARGEST_ENTRY`].
    #[error(
        "the linearisation is out of range: d({row})/d({col}) = {value:e} is beyond {LARGEST_ENTRY:.1e} \
         (the square root of the largest f64), so products of its entries overflow and its \
         eigenvalues are meaningless; the scene's values (a stiffness, an inertia) are too extreme"
    )]
    OutOfRange {
        /// The state whose derivative it is.
        row: String,
        /// The state or input it is differentiated by.
        col: String,
        /// The value.
        value: f64,
    },
    /// The error estimate is not small against the entries ([`ACCURACY`]).
    #[error(
        "the linearisation is not accurate: its error estimate {estimate:e} is more than \
         {ACCURACY:e} of its largest entry, {largest:e} (the dynamics are not smooth at the \
         initial state, such as a state on a limit or a stop, or lose their digits)"
    )]
    Inaccurate {
        /// [`Linearization::error_estimate`].
        estimate: f64,
        /// The largest entry of `A` and `B` (modulus).
        largest: f64,
    },
}

/// The linear model `ż = A z + B u` at a scene's initial state (see the module
/// documentation for the meaning and order of `z` and `u`).
#[derive(Clone, Debug)]
pub struct Linearization {
    /// Names of the linear states, in order.
    pub states: Vec<String>,
    /// Names of the inputs, in order.
    pub inputs: Vec<String>,
    /// `A` (`states × states`).
    pub a: DMatrix<f64>,
    /// `B` (`states × inputs`).
    pub b: DMatrix<f64>,
    /// Which states are frozen (a locked hinge's angle and rate).
    pub frozen: Vec<bool>,
    /// Largest difference between the extrapolated and the plain central difference over
    /// the entries of `A` and `B`: an upper bound on their error.
    pub error_estimate: f64,
    /// Names of the hinges locked at the initial state (latched on a stop), left rigid.
    pub locked: Vec<String>,
    /// Wheels (`wheel_<name>`) stuck by static friction at the initial state, released for
    /// the linearisation (see the module documentation).
    pub released: Vec<String>,
    /// `ż` at the linearisation point (`z = 0`, `u = 0`), by state (0 for a frozen state):
    /// zero at an equilibrium. `A` and `B` leave it out (see
    /// [`Linearization::not_an_equilibrium`]).
    pub residual: Vec<f64>,
    /// The states in groups, each named with the unit of its rate: `attitude (rad/s)`,
    /// `angular velocity (rad/s²)`, `velocity (m/s²)`, `hinge angles (rad/s)`,
    /// `hinge rates (rad/s²)`, the elastic coordinates and rates, then each effect's states
    /// (by the effect's name, per second), with their ranges in [`Linearization::states`].
    pub groups: Vec<(String, Range<usize>)>,
}

impl Linearization {
    /// The index of state `name`.
    pub fn state(&self, name: &str) -> Option<usize> {
        self.states.iter().position(|s| s == name)
    }

    /// The norm of [`Linearization::residual`] over each group of
    /// [`Linearization::groups`], in their order.
    pub fn residuals(&self) -> Vec<(&str, f64)> {
        self.groups
            .iter()
            .map(|(g, r)| {
                let norm = self.residual[r.clone()].iter().map(|v| v * v).sum::<f64>();
                (g.as_str(), norm.sqrt())
            })
            .collect()
    }

    /// Why the linearisation point is not an equilibrium, when it is not: the groups whose
    /// rate [`Linearization::residual`] is more than [`EQUILIBRIUM`] times the larger of 1
    /// and the largest entry of `A` (the orbit's own states, which move on any orbit, left
    /// out), with what to set. `A` is then the Jacobian at one instant of a motion, and its
    /// eigenvalues describe the start of that motion frozen there, not vibrations about a
    /// pose.
    pub fn not_an_equilibrium(&self) -> Option<String> {
        let tolerance = EQUILIBRIUM * self.a.amax().max(1.0);
        let moving: Vec<String> = self
            .residuals()
            .into_iter()
            .filter(|(g, norm)| !g.starts_with("orbit") && (norm.is_nan() || *norm > tolerance))
            .map(|(g, norm)| format!("{g} {norm:.3e}"))
            .collect();
        if moving.is_empty() {
            return None;
        }
        Some(format!(
            "the initial state is not an equilibrium: its rate of change there, per group of \
             states, is {}; the linear model and its modes describe that motion frozen at \
             t = 0, not vibrations about a pose (frequencies, damping ratios and shapes can be \
             meaningless). For vibration modes start at rest where the loads balance: zero \
             rates (`[initial] base.angular_velocity`, `hinges.rate`; or a spin about a \
             principal axis), hinge angles at their springs' `reference`, or sweep with \
             `satsim modes --along`, which holds each configuration",
            moving.join(", ")
        ))
    }
}

/// Linearises `scene` at its initial state (t = 0): see the module documentation.
///
/// ```
/// use satsim_tools::{linearize::linearize, scene::Scene};
/// let scene = Scene::parse(r#"
/// duration = 1.0
/// [model]
/// base = { kind = "fixed" }
/// [[model.body]]
/// name = "base"
/// mass = 1.0
/// inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
/// [[model.body]]
/// name = "panel"
/// mass = 0.0
/// inertia = [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]]
/// [[model.hinge]]
/// name = "h"
/// parent = "base"
/// child = "panel"
/// axis = [0.0, 0.0, 1.0]
/// [effects.hinge_springs]
/// stiffness = [8.0]
/// "#, "panel.toml".as_ref())?;
/// let lin = linearize(&scene)?;
/// assert_eq!(lin.states, ["angle_h", "rate_h"]);
/// assert!((lin.a[(1, 0)] + 4.0).abs() < 1e-9); // −k / I
/// assert!((lin.b[(1, 0)] - 0.5).abs() < 1e-9); // 1 / I
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn linearize(scene: &Scene) -> Result<Linearization, LinearizeError> {
    let mut sim = scene.simulation()?;
    linearize_simulation(&mut sim)
}

/// Linearises a freshly built simulation at its initial state and time. Wheels stuck at the
/// start are released on `sim` (see the module documentation); the constant hinge torques
/// are left as they were.
pub fn linearize_simulation(sim: &mut Simulation) -> Result<Linearization, LinearizeError> {
    let layout = sim.layout().clone();
    let model = sim.model().clone();
    let mut x0 = sim.x0().to_vec();
    let t0 = sim.t0();
    // A run latches the sampled laws due at its start (a thruster's duty, a sampled
    // controller's output) before its first step: the linear model holds what they latch
    // there, as the run does until their next sample.
    if stop_due(t0, sim.next_stop()) {
        sim.on_stop(t0, &mut x0)
            .map_err(|e| LinearizeError::Dynamics(e.to_string()))?;
    }
    let n_user = layout.n_hinges;
    let n_rotors = model.n_hinges() - n_user;
    let mut released = Vec::new();
    for j in 0..n_rotors {
        if sim.locked()[n_user + j] {
            sim.release(n_user + j);
            released.push(model.hinge_names()[n_user + j].clone());
        }
    }
    let locked = sim.locked().to_vec();
    let hinge_names = &model.hinge_names();

    let LinearStates {
        names: states,
        x_index,
        scale,
        frozen,
        groups,
    } = linear_states(sim, &x0, &locked);
    let n = states.len();

    // The inputs: one torque per hinge, one motor torque per rotor.
    let mut inputs: Vec<String> = (0..n_user)
        .map(|k| format!("torque_{}", hinge_names[k]))
        .collect();
    inputs.extend((0..n_rotors).map(|j| hinge_names[n_user + j].clone()));
    let m = inputs.len();
    let tau0 = sim.constant_torques_mut().to_vec();

    let q_ref = if layout.free {
        let a = &x0[layout.attitude.clone()];
        UnitQuaternion::new_normalize(Quaternion::new(a[0], a[1], a[2], a[3]))
    } else {
        UnitQuaternion::identity()
    };
    let omega_ref = if layout.free {
        Vec3::from_column_slice(&x0[layout.omega.clone()])
    } else {
        Vec3::zeros()
    };

    let mut x = x0.clone();
    let mut dx = vec![0.0; x0.len()];
    // ż at the linear state z (a perturbation of x0) with the hinge torques `tau`.
    let mut zdot = |sim: &mut Simulation,
                    z: &[f64],
                    tau: &[f64],
                    out: &mut [f64]|
     -> Result<(), LinearizeError> {
        x.copy_from_slice(&x0);
        let mut phi = Vec3::zeros();
        for (j, xi) in x_index.iter().enumerate() {
            match xi {
                Some(i) => x[*i] += z[j],
                None => phi[j] = z[j],
            }
        }
        if layout.free {
            let q = q_ref * UnitQuaternion::from_scaled_axis(phi);
            let a = layout.attitude.start;
            x[a] = q.w;
            x[a + 1] = q.i;
            x[a + 2] = q.j;
            x[a + 3] = q.k;
        }
        sim.constant_torques_mut().copy_from_slice(tau);
        let r = sim.rhs(t0, &x, &mut dx);
        sim.constant_torques_mut().copy_from_slice(&tau0);
        r.map_err(|e| LinearizeError::Dynamics(e.to_string()))?;
        if layout.free {
            let omega = Vec3::from_column_slice(&x[layout.omega.clone()]);
            let e = UnitQuaternion::from_scaled_axis(phi);
            let rel = omega - e.inverse_transform_vector(&omega_ref);
            let phidot = right_jacobian_inv(&phi) * rel;
            out[..3].copy_from_slice(phidot.as_slice());
        }
        for (j, xi) in x_index.iter().enumerate() {
            if let Some(i) = xi {
                out[j] = dx[*i];
            }
        }
        Ok(())
    };

    // Central differences with one Richardson step, column by column.
    let mut a = DMatrix::zeros(n, n);
    let mut b = DMatrix::zeros(n, m);
    let mut error_estimate: f64 = 0.0;
    let mut z = vec![0.0; n];
    let mut fp = vec![0.0; n];
    let mut fm = vec![0.0; n];
    let mut d = [vec![0.0; n], vec![0.0; n]];
    for j in 0..n + m {
        let h0 = if j < n {
            let base = x_index[j].map_or(0.0, |i| x0[i].abs());
            STEP * base.max(scale[j])
        } else {
            STEP * tau0[j - n].abs().max(1.0)
        };
        if j < n && frozen[j] {
            continue;
        }
        for (level, h) in [h0, 0.5 * h0].into_iter().enumerate() {
            let mut tau = tau0.clone();
            if j < n {
                z[j] = h;
            } else {
                tau[j - n] = tau0[j - n] + h;
            }
            zdot(sim, &z, &tau, &mut fp)?;
            if j < n {
                z[j] = -h;
            } else {
                tau[j - n] = tau0[j - n] - h;
            }
            zdot(sim, &z, &tau, &mut fm)?;
            if j < n {
                z[j] = 0.0;
            }
            for r in 0..n {
                d[level][r] = (fp[r] - fm[r]) / (2.0 * h);
            }
        }
        for r in 0..n {
            let rich = (4.0 * d[1][r] - d[0][r]) / 3.0;
            let value = if frozen[r] { 0.0 } else { rich };
            let col = if j < n { &states[j] } else { &inputs[j - n] };
            if !value.is_finite() {
                return Err(LinearizeError::NonFinite {
                    row: states[r].clone(),
                    col: col.clone(),
                    value,
                });
            }
            if !frozen[r] {
                error_estimate = error_estimate.max((rich - d[1][r]).abs());
            }
            if j < n {
                a[(r, j)] = value;
            } else {
                b[(r, j - n)] = value;
            }
        }
    }
    // Where the linear model starts: zero at an equilibrium.
    let mut residual = vec![0.0; n];
    zdot(sim, &vec![0.0; n], &tau0, &mut residual)?;
    for (r, f) in residual.iter_mut().zip(&frozen) {
        if *f {
            *r = 0.0;
        }
    }
    check_range(&a, &b, &states, &inputs)?;
    let largest = a.amax().max(b.amax());
    if error_estimate > ACCURACY * largest {
        return Err(LinearizeError::Inaccurate {
            estimate: error_estimate,
            largest,
        });
    }
    let locked_names = (0..model.n_hinges())
        .filter(|&k| locked[k])
        .map(|k| hinge_names[k].clone())
        .collect();
    Ok(Linearization {
        states,
        inputs,
        a,
        b,
        frozen,
        error_estimate,
        locked: locked_names,
        released,
        residual,
        groups,
    })
}

/// The linear states, the rows and columns of `A`: attitude error, rates and velocity (free
/// base), hinge angles and rates, elastic coordinates and rates, then each effect's own.
struct LinearStates {
    names: Vec<String>,
    /// Where each lives in `x`; `None` for a component of the attitude error.
    x_index: Vec<Option<usize>>,
    /// The least step scale of each.
    scale: Vec<f64>,
    /// Held by a lock (its row and column of `A` stay zero).
    frozen: Vec<bool>,
    /// The states' groups, by which the not-an-equilibrium residual is reported.
    groups: Vec<(String, Range<usize>)>,
}

/// The linear states of `sim` at `x0` with the hinges `locked` (tree order).
fn linear_states(sim: &Simulation, x0: &[f64], locked: &[bool]) -> LinearStates {
    let layout = sim.layout();
    let n_user = layout.n_hinges;
    let hinge_names = sim.model().hinge_names();
    let mut states: Vec<String> = Vec::new();
    let mut x_index: Vec<Option<usize>> = Vec::new(); // None: attitude error component
    let mut scale: Vec<f64> = Vec::new();
    let mut frozen: Vec<bool> = Vec::new();
    let mut groups: Vec<(String, Range<usize>)> = Vec::new();
    let mut group = |name: &str, states: &[String]| {
        let start = groups
            .last()
            .map_or(0, |(_, r): &(String, Range<usize>)| r.end);
        if states.len() > start {
            groups.push((name.to_owned(), start..states.len()));
        }
    };
    if layout.free {
        for c in ["x", "y", "z"] {
            states.push(format!("att_{c}"));
            x_index.push(None);
            scale.push(1.0);
            frozen.push(false);
        }
        group("attitude (rad/s)", &states);
        for (prefix, range, g) in [
            ("omega", &layout.omega, "angular velocity (rad/s²)"),
            ("vel", &layout.velocity, "velocity (m/s²)"),
        ] {
            for (k, c) in ["x", "y", "z"].iter().enumerate() {
                states.push(format!("{prefix}_{c}"));
                x_index.push(Some(range.start + k));
                scale.push(1.0);
                frozen.push(false);
            }
            group(g, &states);
        }
    }
    for (prefix, range, g) in [
        ("angle", &layout.angles, "hinge angles (rad/s)"),
        ("rate", &layout.rates, "hinge rates (rad/s²)"),
    ] {
        for k in 0..n_user {
            states.push(format!("{prefix}_{}", hinge_names[k]));
            x_index.push(Some(range.start + k));
            scale.push(1.0);
            frozen.push(locked[k]);
        }
        group(g, &states);
    }
    // A flexible body's modal coordinates and rates (√kg m, √kg m/s), after the hinge rates.
    // Their steps are scaled by the coordinate that bends the body by its size (per second
    // for the rates): in `√kg m` a light strip is bent past its length by `η = 1e-3`.
    let elastic = sim.elastic_names();
    let modal_scale = |e: usize| {
        sim.flex_model()
            .and_then(|f| f.modal_scale(e))
            .unwrap_or(1.0)
    };
    for (prefix, range, g) in [
        ("eta", &layout.eta, "elastic coordinates (√kg m/s)"),
        ("etadot", &layout.etadot, "elastic rates (√kg m/s²)"),
    ] {
        for (e, (name, i)) in elastic.iter().zip(range.clone()).enumerate() {
            states.push(format!("{prefix}_{name}"));
            x_index.push(Some(i));
            scale.push(modal_scale(e));
            frozen.push(false);
        }
        group(g, &states);
    }
    for (name, range) in &layout.effects {
        if range.is_empty() {
            continue;
        }
        let names = sim
            .effect(name)
            .map(|e| e.state_names())
            .unwrap_or_default();
        let norm = x0[range.clone()].iter().map(|v| v * v).sum::<f64>().sqrt();
        let rotors = sim.effect(name).is_some_and(|e| !e.rotors().is_empty());
        for (k, i) in range.clone().enumerate() {
            states.push(
                names
                    .get(k)
                    .cloned()
                    .unwrap_or_else(|| format!("{name}_{k}")),
            );
            x_index.push(Some(i));
            scale.push(1.0f64.max(STEP * norm));
            frozen.push(rotors && locked.get(n_user + k).copied().unwrap_or(false));
        }
        group(&format!("{name} (per second)"), &states);
    }
    LinearStates {
        names: states,
        x_index,
        scale,
        frozen,
        groups,
    }
}

/// An error naming the first entry of `A` (then `B`) beyond [`LARGEST_ENTRY`].
fn check_range(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    states: &[String],
    inputs: &[String],
) -> Result<(), LinearizeError> {
    for (m, cols) in [(a, states), (b, inputs)] {
        for r in 0..m.nrows() {
            for c in 0..m.ncols() {
                let value = m[(r, c)];
                if value.abs() > LARGEST_ENTRY {
                    return Err(LinearizeError::OutOfRange {
                        row: states[r].clone(),
                        col: cols[c].clone(),
                        value,
                    });
                }
            }
        }
    }
    Ok(())
}

/// `J_r⁻¹(φ)`: the inverse of the right Jacobian of SO(3), mapping the body angular velocity
/// to the rate of the rotation vector of a right perturbation, `φ̇ = J_r⁻¹(φ) ω`.
fn right_jacobian_inv(phi: &Vec3) -> Matrix3<f64> {
    let t = phi.norm();
    let k = phi.cross_matrix();
    let c = if t < 1e-4 {
        1.0 / 12.0 + t * t / 720.0
    } else {
        1.0 / (t * t) - (1.0 + t.cos()) / (2.0 * t * t.sin())
    };
    Matrix3::identity() + 0.5 * k + c * k * k
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bus(initial: &str) -> Scene {
        let text = format!(
            r#"duration = 1.0
[model]
[[model.body]]
name = "bus"
mass = 100.0
inertia = [[10.0, 0.0, 0.0], [0.0, 20.0, 0.0], [0.0, 0.0, 30.0]]
{initial}"#
        );
        Scene::parse(&text, "bus.toml".as_ref()).unwrap()
    }

    #[test]
    fn a_tumbling_start_is_not_an_equilibrium_and_says_by_how_much() {
        // Euler's equations at ω = (0.1, 0.2, 0.3): I ω̇ = −ω × I ω = −(0.6, −0.6, 0.2).
        let lin = linearize(&bus(
            "[initial]\nbase = { angular_velocity = [0.1, 0.2, 0.3] }",
        ))
        .unwrap();
        let omega = lin.state("omega_x").unwrap();
        let expected = [-0.06, 0.03, -0.2 / 30.0];
        for (k, e) in expected.iter().enumerate() {
            assert!(
                (lin.residual[omega + k] - e).abs() < 1e-12,
                "{:?}",
                lin.residual
            );
        }
        let groups = lin.residuals();
        let (name, norm) = groups[1];
        assert_eq!(name, "angular velocity (rad/s²)");
        assert!((norm - 0.0674125).abs() < 1e-6, "{groups:?}");
        // The attitude error is measured from the reference as it moves: no drift there.
        assert_eq!(groups[0], ("attitude (rad/s)", 0.0));
        let w = lin.not_an_equilibrium().expect("a warning");
        assert!(
            w.starts_with("the initial state is not an equilibrium")
                && w.contains("angular velocity (rad/s²) 6.741e-2")
                && !w.contains("attitude (rad/s)")
                && w.contains("zero rates"),
            "{w}"
        );
    }

    #[test]
    fn a_bus_at_rest_or_spinning_about_a_principal_axis_is_an_equilibrium() {
        for initial in [
            "",
            "[initial]\nbase = { angular_velocity = [0.0, 0.0, 2.0] }",
        ] {
            let lin = linearize(&bus(initial)).unwrap();
            assert!(lin.residual.iter().all(|r| *r == 0.0), "{:?}", lin.residual);
            assert_eq!(lin.not_an_equilibrium(), None);
        }
    }

    #[test]
    fn right_jacobian_inverse_inverts_the_kinematics() {
        // Integrate q̇ = ½ q ⊗ ω for a short time and compare log(q) with φ̇ = J_r⁻¹ ω.
        let phi = Vec3::new(0.3, -0.2, 0.5);
        let w = Vec3::new(0.7, 0.1, -0.4);
        let dt = 1e-6;
        let q0 = UnitQuaternion::from_scaled_axis(phi);
        let q1 = q0 * UnitQuaternion::from_scaled_axis(w * dt);
        let q_1 = q0 * UnitQuaternion::from_scaled_axis(-w * dt);
        let rate = (q1.scaled_axis() - q_1.scaled_axis()) / (2.0 * dt);
        let predicted = right_jacobian_inv(&phi) * w;
        assert!((rate - predicted).norm() < 1e-8, "{rate} vs {predicted}");
        // The small-angle series joins the closed form.
        let small = Vec3::new(1e-4, 0.0, 0.0);
        let a = right_jacobian_inv(&small);
        let b = right_jacobian_inv(&(small * 1.0001));
        assert!((a - b).norm() < 1e-8);
    }
}
