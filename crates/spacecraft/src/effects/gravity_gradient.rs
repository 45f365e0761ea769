//! Gravity gradient: the Earth's point-mass gravity on a spacecraft whose size is small
//! against its orbit radius, in the frame falling with the centre of mass `O`.
//!
//! In that frame every body `i` (mass `m_i`, inertia `I_i` about its centre of mass,
//! centre of mass `ρ_i` from `O`) feels its gravity minus the frame's acceleration
//! `−μ r_O / r_O³`. Expanding `−μ m (r_O + ρ) / |r_O + ρ|³` in `ρ / r_O` and summing over the
//! body's mass points gives, to first order in size/r (`E = r_O / r_O` the local vertical,
//! `k = μ / r_O³`):
//!
//! - the couple about the body's centre of mass `M_iG = 3 k E × I_i E` (E in body axes);
//! - the tidal force at its centre of mass `F_i = k m_i (3 (E·ρ_i) E − ρ_i)`.
//!
//! Two models:
//!
//! - [`GravityModel::Preprint`]: the preprint's section 2, per-body couples only, with the
//!   sign corrected: the preprint prints `M_iG = −3 μ/r³ E × I_i E`, but the couple of a
//!   brute-force sum of point masses is `+3 μ/r³ E × I_i E` (test `gravity_gradient_sign`
//!   in `tests/it/physics.rs`); the printed sign would make the long-axis-vertical attitude
//!   unstable. Its forces are the preprint's `F_i ≈ −μ m_i r_O / r_O³`, which cancel exactly
//!   against the frame's acceleration.
//! - [`GravityModel::Full`]: the couples plus the tidal forces `F_i`, applied at each body's
//!   centre of mass. The preprint's approximation of `F_i` drops them, yet they are of the
//!   same order as the couples it keeps: for a panel at distance `d` from `O`, `F_i` has a
//!   moment about `O` of order `k m_i d²`, while the panel's own couple is of order
//!   `k m_i l²` with `l` its size. For an array whose panels sit metres from the bus, the
//!   dropped moment is the larger one. The tidal forces sum to zero (Σ m_i ρ_i = 0), so the
//!   orbit is unaffected.
//!
//! A flexible body with `stiffening` (its mass distribution following its deformation to
//! the order the dynamics keeps) feels `full`'s field over its deformed mass rather than at
//! its undeformed centre of mass: [`FlexModel::linear_field`] gives the wrench on its frame
//! and the loads on its modes (the lateral load over a beam's length, the deflected mass's
//! own, and the geometric stiffness of the field's axial load: a boom along the local
//! vertical is in tension), all gradients of the same potential, so the energy budget
//! closes; the system's centre of mass takes the deformed first moments. A body without
//! `stiffening` keeps its undeformed inertia in the dynamics, and so here (its modes feel
//! no field); so does a flexible body carrying rotors, and every body under `preprint`.
//!
//! The potential energy counted in the total energy is the same expansion:
//! `V = Σ k/2 (3 E·I_i E − tr I_i)` (plus `−Σ k m_i/2 (3 (E·ρ_i)² − ρ_i²)` for `full`). In a
//! rotating orbit it is not conserved on its own: the field turns with the local vertical
//! `E` and its strength `k` changes along an eccentric orbit, so the forces also do the work
//! `∫ ∂V/∂t dt` (`V`'s rate of change at fixed attitude and shape, with `Ė = (v − (E·v) E)/r`,
//! `k̇ = −3 k (E·v)/r`), which the energy budget counts as actuator work (see
//! [`Effect::power`]).

use super::{Context, Effect, Forces, Links, Needs, OrbitState, Power, SceneEffect, Section};
use satsim_integrate::SystemError;
use satsim_tree::flexible::FlexModel;
use satsim_tree::flexible::field::{field_wrench, potential};
use satsim_tree::io::FileError;
use satsim_tree::kernel_parts;
use satsim_tree::spatial::{Force, Mat3, RigidInertia, Vec3, skew};
use satsim_tree::{Model, center_of_mass};
use serde::Deserialize;
use toml::Spanned;

/// Which gravity-gradient model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum GravityModel {
    /// Per-body couples only (the preprint, sign corrected).
    #[default]
    Preprint,
    /// Couples plus each body's tidal force at its own centre of mass.
    Full,
}

/// The gravity-gradient effect.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct GravityGradient {
    /// The model.
    pub model: GravityModel,
    /// `∂V/∂t` at the last `apply` (W), computed there from the same per-body terms when the
    /// simulation asks for it ([`Context::power`]); NaN after an `apply` that did not.
    field_power: f64,
    /// The bodies the field loads, in body order (from [`Effect::connect`]): a body with
    /// neither mass nor inertia (a gimbal link) feels nothing and is left out, and a gyrostat
    /// rotor is loaded through its carrier ([`Loaded`]).
    loaded: Vec<Loaded>,
    /// The number of bodies of the tree `loaded` was made for.
    n_bodies: usize,
    /// For `full`, each loaded body's centre of mass in inertial axes from the system's
    /// origin, by `apply` (room made once, by `connect`).
    at: Vec<Vec3>,
    /// For `full`, each deformable loaded body's inertia at the deformation
    /// ([`FlexModel::deformed_inertia`]), by `apply`: its centre of mass for `at`, then its
    /// load (one evaluation a body where there were two). Unused for a rigid body.
    deformed: Vec<RigidInertia>,
    /// For `full` on a tree with a stiffened flexible body: the flexible model, whose
    /// [`FlexModel::linear_field`] spreads the tidal field over such a body's deformed mass
    /// and onto its modes (see the module's documentation).
    flex: Option<Box<FlexModel>>,
    /// Per body of the tree, whether it is loaded as deformable (by `connect`): what the
    /// rows' passes over every body ask of each.
    deforms: Vec<bool>,
}

/// A body the field loads: its per-body constants, worked out once.
///
/// A balanced rotor that the tree folds into its carrier as a gyrostat
/// ([`satsim_tree::Gyrostat`], e.g. a reaction wheel) is loaded as part of its carrier: its
/// inertia does not change as it spins, and the field's couple and tidal force are linear in
/// the mass distribution (second moments), so the carrier with its rotors locked on
/// ([`kernel_parts::carrier_inertia`]) feels the sum of what each would feel alone. Their
/// share about the spin axis is zero (`a · (E × J a (a·E)) = 0`), so the rotors' spin is
/// untouched; the carrier takes the rest, as the tree would pass it on. One body's terms
/// instead of one per wheel (the same to round-off; test
/// `rotors_load_through_their_carrier`). The preprint's model keeps only each body's couple
/// about its own centre of mass, which is not linear in that way for a rotor with mass off
/// the carrier's centre (the offset's share is the tidal term it drops): there a carrier
/// takes its rotors only when none of them has mass.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Loaded {
    /// Its index in the tree's bodies.
    body: usize,
    /// Its mass with its rotors (kg).
    mass: f64,
    /// Its centre of mass with its rotors, body axes (m).
    com: Vec3,
    /// Its inertia with its rotors about that centre of mass, body axes (kg m²).
    inertia: Mat3,
    /// The trace of `inertia` (for `∂V/∂t`).
    trace: f64,
    /// Whether it is a gyrostat rotor, loaded alone.
    rotor: bool,
    /// Whether it is a stiffened flexible body (with no rotors): its mass distribution
    /// follows its deformation, and the field reaches its modes.
    deformable: bool,
}

/// Whether body `carrier` takes its gyrostat rotors under `gm` ([`Loaded`]).
fn takes_rotors(model: &Model, gm: GravityModel, carrier: usize) -> bool {
    let mut rotors = model.gyrostats().iter().filter(|g| g.parent() == carrier);
    match gm {
        GravityModel::Full => true,
        GravityModel::Preprint => rotors.all(|g| model.bodies()[g.body()].mass() == 0.0),
    }
}

impl Loaded {
    /// Body `i` with the rotors the tree folds into it, where it takes them; `None` for a
    /// rotor its carrier takes and for a body with neither mass nor inertia (a gimbal link).
    fn of(model: &Model, gm: GravityModel, i: usize) -> Option<Self> {
        let taken = |g: &satsim_tree::Gyrostat| takes_rotors(model, gm, g.parent());
        if model.gyrostats().iter().any(|g| g.body() == i && taken(g)) {
            return None;
        }
        let body = &model.bodies()[i];
        let carries = model.gyrostats().iter().any(|g| g.parent() == i);
        let (mass, com, inertia) = if carries && takes_rotors(model, gm, i) {
            // The locked-on inertia about the body origin, back to its centre of mass:
            // `I_O = I_c − m [c]×[c]×` (`RigidInertia::from_com`).
            let ri = kernel_parts::carrier_inertia(model, i);
            let com = if ri.mass > 0.0 {
                ri.h / ri.mass
            } else {
                *body.com()
            };
            let cx = skew(&com);
            (ri.mass, com, ri.inertia + cx * cx * ri.mass)
        } else {
            (body.mass(), *body.com(), *body.inertia_com())
        };
        (mass != 0.0 || inertia.norm() != 0.0).then(|| Loaded {
            body: i,
            mass,
            com,
            inertia,
            trace: inertia.trace(),
            rotor: model.gyrostats().iter().any(|g| g.body() == i),
            deformable: false,
        })
    }
}

/// Body `i`'s inertia at its deformation: the kinematics' own where it is current.
fn deformed_inertia(ctx: &Context, flex: &FlexModel, i: usize) -> RigidInertia {
    ctx.deformed
        .map_or_else(|| flex.deformed_inertia(i, ctx.eta), |d| d[i])
}

/// The couple `3 k E × I E` on a body of inertia `inertia` (about its centre of mass) with
/// the local vertical `eb`, both in its axes.
fn couple(k: f64, eb: &Vec3, inertia: &Mat3) -> Vec3 {
    3.0 * k * eb.cross(&(inertia * eb))
}

/// The tidal force `k m (3 (E·ρ) E − ρ)` on a body of mass `m` whose centre of mass is at
/// `rho` from the system's, inertial axes.
fn tidal(k: f64, e: &Vec3, m: f64, rho: &Vec3) -> Vec3 {
    k * m * (3.0 * e.dot(rho) * e - rho)
}

/// The tidal field's tensor `k (3 E Eᵀ − 1)` (1/s²) for the local vertical `eb`, and with
/// `RATE` its rate `k̇ (3 E Eᵀ − 1) + 3k (Ė Eᵀ + E Ėᵀ)` for `eb_dot`, in the same axes
/// (else zero: the right-hand side does not read it).
#[inline(always)]
fn field<const RATE: bool>(k: f64, eb: &Vec3, k_dot: f64, eb_dot: &Vec3) -> (Mat3, Mat3) {
    let shape = eb * eb.transpose() * 3.0 - Mat3::identity();
    if !RATE {
        return (shape * k, Mat3::zeros());
    }
    let turn = (eb_dot * eb.transpose() + eb * eb_dot.transpose()) * (3.0 * k);
    (shape * k, shape * k_dot + turn)
}

impl GravityGradient {
    /// Each loaded body's centre of mass (`at`, inertial axes) from the poses; for `full`.
    fn place(&mut self, ctx: &Context) {
        for ((p, l), d) in self.at.iter_mut().zip(&self.loaded).zip(&mut self.deformed) {
            let i = l.body;
            let com = match &self.flex {
                Some(flex) if l.deformable => {
                    // The dynamics' own, made once by the kinematics, where it is current.
                    let deformed = deformed_inertia(ctx, flex, i);
                    *d = deformed;
                    deformed.h / l.mass
                }
                _ => l.com,
            };
            *p = ctx.data.position[i] + ctx.data.rotation[i] * com;
        }
    }

    /// The system's centre of mass from `at`: the loaded bodies hold all the mass (a rotor's
    /// in its carrier's, a body left out has none), so this is
    /// [`satsim_tree::center_of_mass`] to round-off, without a second pass over the bodies.
    fn com(&self) -> Vec3 {
        let mut m = 0.0;
        let mut mc = Vec3::zeros();
        for (p, l) in self.at.iter().zip(&self.loaded) {
            if l.mass > 0.0 {
                m += l.mass;
                mc += p * l.mass;
            }
        }
        if m > 0.0 { mc / m } else { Vec3::zeros() }
    }

    /// The flexible model, when body `i` is loaded as deformable.
    fn deformable(&self, i: usize) -> Option<&FlexModel> {
        self.flex.as_deref().filter(|_| self.deforms[i])
    }

    /// The system's centre of mass (inertial axes, from the tree's reference point), the
    /// deformable bodies' first moments at their deformation.
    fn system_com(&self, ctx: &Context) -> Vec3 {
        let Some(flex) = &self.flex else {
            return center_of_mass(ctx.model, ctx.data);
        };
        let (mut m, mut first) = (0.0, Vec3::zeros());
        for (i, body) in ctx.model.bodies().iter().enumerate() {
            let h = if self.deformable(i).is_some() {
                deformed_inertia(ctx, flex, i).h
            } else {
                body.com() * body.mass()
            };
            m += body.mass();
            first += ctx.data.position[i] * body.mass() + ctx.data.rotation[i] * h;
        }
        if m > 0.0 { first / m } else { Vec3::zeros() }
    }

    /// The effect with the given model.
    pub fn new(model: GravityModel) -> Self {
        Self {
            model,
            field_power: 0.0,
            loaded: Vec::new(),
            n_bodies: 0,
            at: Vec::new(),
            deformed: Vec::new(),
            flex: None,
            deforms: Vec::new(),
        }
    }

    /// [`Self::load`] for deformable body `n` of `loaded`: the field over its deformed mass
    /// (its inertia from `place`: `full` only has deformable bodies), its origin at `ρ` from
    /// the centre of mass; returns `∂V/∂t` with `POWER`. Out of line, so that the rigid
    /// bodies' loop keeps its code: inlined, the rigid deployment's gravity gradient took
    /// 1.2 % more instructions (callgrind), the flexible one's no fewer.
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn load_deformable<const POWER: bool>(
        &self,
        ctx: &Context,
        forces: &mut Forces,
        flex: &FlexModel,
        n: usize,
        rho: &Vec3,
        t: &Mat3,
        t_dot: &Mat3,
    ) -> f64 {
        let i = self.loaded[n].body;
        let inertia = &self.deformed[n];
        let load = flex.linear_field_on(i, inertia, ctx.eta, t, rho, &mut forces.elastic);
        forces.add_wrench(i, load.wrench);
        if POWER {
            potential(inertia, t_dot, rho)
        } else {
            0.0
        }
    }

    /// Adds every loaded body's couple (and, for `full`, tidal force) to `forces`; with
    /// `POWER`, returns `∂V/∂t` from the same terms (else 0: nothing reads it this pass, and
    /// its terms cost about as much as the couples). `k = μ/r³`, `e` the local vertical.
    fn load<const POWER: bool>(
        &self,
        ctx: &Context,
        forces: &mut Forces,
        orbit: &OrbitState,
        r: f64,
        k: f64,
        e: Vec3,
    ) -> f64 {
        // For the energy budget, ∂V/∂t (see `power`): Ė = (v − (E·v) E)/r, k̇ = −3 k (E·v)/r.
        let (e_dot, k_dot) = if POWER {
            let ev = e.dot(&orbit.v);
            ((orbit.v - ev * e) / r, -3.0 * k * ev / r)
        } else {
            (Vec3::zeros(), 0.0)
        };
        let full = self.model == GravityModel::Full;
        let com = if full { self.com() } else { Vec3::zeros() };
        let mut field_power = 0.0;
        for (n, l) in self.loaded.iter().enumerate() {
            let i = l.body;
            let rot = &ctx.data.rotation[i];
            let eb = rot.tr_mul(&e);
            if let Some(flex) = self.flex.as_ref().filter(|_| l.deformable) {
                let rho = rot.tr_mul(&(ctx.data.position[i] - com));
                let (t, t_dot) = if POWER {
                    field::<true>(k, &eb, k_dot, &rot.tr_mul(&e_dot))
                } else {
                    field::<false>(k, &eb, k_dot, &e_dot)
                };
                field_power +=
                    self.load_deformable::<POWER>(ctx, forces, flex, n, &rho, &t, &t_dot);
                continue;
            }
            let ie = l.inertia * eb;
            let mut ang = couple(k, &eb, &l.inertia);
            if POWER {
                field_power += 0.5 * k_dot * (3.0 * eb.dot(&ie) - l.trace)
                    + 3.0 * k * rot.tr_mul(&e_dot).dot(&ie);
            }
            let mut lin = Vec3::zeros();
            if full && l.mass > 0.0 {
                let rho = self.at[n] - com;
                let f = tidal(k, &e, l.mass, &rho);
                lin = rot.tr_mul(&f);
                ang += l.com.cross(&lin);
                if POWER {
                    let er = e.dot(&rho);
                    field_power -= 0.5
                        * l.mass
                        * (k_dot * (3.0 * er * er - rho.norm_squared())
                            + 6.0 * k * er * e_dot.dot(&rho));
                }
            }
            forces.add_wrench(i, Force::new(ang, lin));
        }
        field_power
    }
}

impl Effect for GravityGradient {
    fn name(&self) -> &str {
        "gravity_gradient"
    }
    fn needs(&self) -> Needs {
        Needs {
            orbit: true,
            free_base: true,
            poses: true,
            ..Needs::default()
        }
    }
    /// The per-body constants of the tree, once: the loaded bodies, each with the gyrostat
    /// rotors the tree folds into it.
    fn connect(&mut self, links: &Links) {
        let model = links.model;
        self.loaded = (0..model.n_bodies())
            .filter_map(|i| Loaded::of(model, self.model, i))
            .collect();
        self.n_bodies = model.n_bodies();
        self.at = vec![Vec3::zeros(); self.loaded.len()];
        self.deformed = self
            .loaded
            .iter()
            .map(|l| *model.bodies()[l.body].inertia())
            .collect();
        self.flex = None;
        if let Some(flex) = links.flex.filter(|_| self.model == GravityModel::Full) {
            for l in &mut self.loaded {
                l.deformable = flex.stiffened(l.body)
                    && !model.gyrostats().iter().any(|g| g.parent() == l.body);
            }
            if self.loaded.iter().any(|l| l.deformable) {
                self.flex = Some(Box::new(flex.clone()));
            }
        }
        self.deforms = vec![false; model.n_bodies()];
        for l in self.loaded.iter().filter(|l| l.deformable) {
            self.deforms[l.body] = true;
        }
    }
    fn apply(
        &mut self,
        ctx: &Context,
        forces: &mut Forces,
        _own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        let orbit = ctx.orbit_or_err("gravity_gradient")?;
        if self.n_bodies != ctx.model.bodies().len() {
            return Err(SystemError::new(
                "gravity_gradient: not connected to this tree (`Effect::connect`)",
            ));
        }
        let r = orbit.r.norm();
        let k = orbit.mu / (r * r * r);
        let e = orbit.r / r;
        if self.model == GravityModel::Full {
            self.place(ctx);
        }
        self.field_power = if ctx.power {
            self.load::<true>(ctx, forces, &orbit, r, k, e)
        } else {
            self.load::<false>(ctx, forces, &orbit, r, k, e);
            f64::NAN
        };
        Ok(())
    }
    /// `∂V/∂t`: the work rate of the field turning with the orbit (the rest of the forces'
    /// power is `−dV/dt` at fixed time, counted in the potential), computed by `apply` (the
    /// simulation asks for it only after an `apply` with [`Context::power`]).
    fn power(&self, _ctx: &Context, _own: &[f64], _applied: f64) -> Power {
        Power::actuator(self.field_power)
    }
    /// Its power is `∂V/∂t`, from its own terms.
    fn power_reads_applied(&self) -> bool {
        false
    }
    /// Only where it loads a rotor alone (the preprint's model, a rotor with mass): a rotor
    /// its carrier takes is no loaded body. `output` and `potential_energy` read every body,
    /// but their passes compute every pose.
    fn reads_rotor_poses(&self) -> bool {
        self.loaded.iter().any(|l| l.rotor)
    }
    /// `gg_torque_x/y/z`: the moment of the couples and tidal forces about the centre of
    /// mass, bus axes (N m), beside the other disturbances' columns.
    fn output_columns(&self) -> Vec<String> {
        ["gg_torque_x", "gg_torque_y", "gg_torque_z"]
            .map(String::from)
            .into()
    }
    /// Computed here rather than in `apply`, so that the right-hand side does not pay for
    /// a column: the couples, plus for `full` the tidal forces' moments `ρ_i × F_i`.
    fn output(&self, ctx: &Context, _own: &[f64], row: &mut Vec<f64>) {
        let Some(orbit) = ctx.orbit else {
            row.extend_from_slice(&[f64::NAN; 3]);
            return;
        };
        let com = self.system_com(ctx);
        let r = orbit.r.norm();
        let (k, e) = (orbit.mu / (r * r * r), orbit.r / r);
        let mut moment = Vec3::zeros();
        for (i, body) in ctx.model.bodies().iter().enumerate() {
            let rot = &ctx.data.rotation[i];
            if let Some(flex) = self.deformable(i) {
                let rho = rot.tr_mul(&(ctx.data.position[i] - com));
                let (t, _) = field::<false>(k, &rot.tr_mul(&e), 0.0, &Vec3::zeros());
                let w = field_wrench(&deformed_inertia(ctx, flex, i), &t, &rho);
                moment += rot * w.ang + (ctx.data.position[i] - com).cross(&(rot * w.lin));
                continue;
            }
            moment += rot * couple(k, &rot.tr_mul(&e), body.inertia_com());
            if self.model == GravityModel::Full && body.mass() > 0.0 {
                let rho = ctx.data.position[i] + rot * body.com() - com;
                moment += rho.cross(&tidal(k, &e, body.mass(), &rho));
            }
        }
        row.extend_from_slice(ctx.attitude.inverse_transform_vector(&moment).as_slice());
    }
    fn potential_energy(&self, ctx: &Context, _own: &[f64]) -> f64 {
        let Some(orbit) = ctx.orbit else { return 0.0 };
        let r = orbit.r.norm();
        let k = orbit.mu / (r * r * r);
        let e = orbit.r / r;
        let com = self.system_com(ctx);
        let mut v = 0.0;
        for (i, body) in ctx.model.bodies().iter().enumerate() {
            let rot = &ctx.data.rotation[i];
            let eb = rot.tr_mul(&e);
            if let Some(flex) = self.deformable(i) {
                let rho = rot.tr_mul(&(ctx.data.position[i] - com));
                let (t, _) = field::<false>(k, &eb, 0.0, &Vec3::zeros());
                v += potential(&deformed_inertia(ctx, flex, i), &t, &rho);
                continue;
            }
            v += 0.5 * k * (3.0 * eb.dot(&(body.inertia_com() * eb)) - body.inertia_com().trace());
            if self.model == GravityModel::Full {
                let rho = ctx.data.position[i] + rot * body.com() - com;
                let er = e.dot(&rho);
                v -= 0.5 * k * body.mass() * (3.0 * er * er - rho.norm_squared());
            }
        }
        v
    }
}

/// `[effects.gravity_gradient]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GravityFile {
    /// `"preprint"` (default) or `"full"`.
    #[serde(default)]
    pub model: Option<Spanned<String>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

impl SceneEffect for GravityGradient {
    const SECTION: &'static str = "gravity_gradient";
    type File = GravityFile;
    fn from_section(file: GravityFile, section: &Section) -> Result<Self, FileError> {
        let model = match file
            .model
            .as_ref()
            .map(|m| (m.get_ref().as_str(), m.span()))
        {
            None | Some(("preprint", _)) => GravityModel::Preprint,
            Some(("full", _)) => GravityModel::Full,
            Some((other, s)) => {
                return Err(section.error(Some(s), format!("`effects.gravity_gradient.model`: unknown value `{other}`, expected \"preprint\" or \"full\"")));
            }
        };
        Ok(GravityGradient::new(model))
    }
}
