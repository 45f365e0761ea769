//! The preprint satellite's own forward-dynamics kernel: ABA unrolled for its layout
//! (Featherstone §7.3, the chain form of `satsim-tree`'s `aba.rs`), straight-line code with
//! everything constant folded in once. It implements the engine's [`Kernel`]: attached to a
//! [`satsim_tree::ForwardDynamics`] (`.with_kernel(Box::new(kernel))`), it takes every call
//! whose lock mask it accepts, the generic ABA the others. It lives here, not in the generic
//! engine, because it knows one spacecraft's layout; it is built from the engine's
//! [`satsim_tree::kernel_parts`].
//!
//! The layout ([`UnrolledAba::new`] recognises it): a free base; balanced rotors
//! ([`satsim_tree::Gyrostat`]) on the base only; one spherical [`satsim_tree::Chain`] (three
//! hinges, no armature, link origins on the hinge point) from the base to a tip body; then a
//! serial chain of up to [`MAX_SERIAL`] bodies, each the only child of the one before (the
//! tip's child first); every hinge of the chain and of the serial bodies about a coordinate
//! axis without fixed rotation or armature; no other bodies. This is the preprint satellite (bus,
//! three reaction wheels, the 3-DOF gimbal to panel 1, panels 2 and 3).
//!
//! What is folded, and why it is the same algorithm as [`satsim_tree::aba::aba`]:
//! - Every body below the base is processed in a frame with its own axes and its origin at
//!   its hinge point (the tip: the gimbal's common point). A constant change of origin: the
//!   rigid inertias and the children's hinge points are moved once, here. Then each motion
//!   subspace is `S = [σ e_k; 0]`, each hinge transform has a constant translation, and
//!   `U = IA S` and `D = Sᵀ U` are a signed column of `IA` and one entry.
//! - The gimbal's links are massless: they get no inertia, no bias; only the chain's
//!   rotation, its velocity-product term `c` and the tip's velocity (all axes through one
//!   point, so `c = Σ vₜ × Sₜ q̇ₜ` in closed form). The spherical joint passes on only
//!   `C − Bᵀ A⁻¹ B` (as `aba.rs`'s `chain_inward`), factored `L Δ Lᵀ` in the same order with
//!   the same pivots, so a gimbal lock fails as there, with the same
//!   [`DynamicsError::SingularHinge`].
//! - Rotors add `ω × Σ J Ω a + Σ τ a` to the base's bias and `Ω̇ = τ / J − a · ω̇` at the end.
//! - External forces (`fext`, body coordinates, about each body's origin) are moved once to
//!   the frame a body is processed in: about its hinge point, `n' = n + o × f` with `o` its
//!   origin from the point. A rotor's axial moment `Sᵀ f` adds to its `τ`, the whole wrench
//!   reaches the base through the bearing (`aba.rs`'s gyrostat form). The massless links'
//!   wrenches (their origins are the gimbal's point: a rotation only) load the hinges
//!   between them and the base and reach the base rigidly (`aba.rs`'s `links_bias`). A
//!   const parameter keeps the force-free instance free of all this.
//! - Locked hinges ([`Locks`], hybrid dynamics as [`satsim_tree::aba::aba_hybrid`]): a locked
//!   serial body passes its inertia and bias to its parent unprojected; a locked rotor's axial
//!   inertia is the base's again and its axial torque leaves the base's bias. A locked
//!   gimbal hinge is not taken ([`UnrolledAba::locks`] says so).
//! - The serial chain's length is a const parameter for the preprint's length
//!   ([`PREPRINT_SERIAL`]): its loops unroll over arrays of known size (no per-body
//!   dispatch, no `Option`s, no index checks). Other lengths share one instance whose loops
//!   run to the model's length over arrays of [`MAX_SERIAL`].
//!
//! Equal to [`satsim_tree::aba::aba`] to round-off (tested on the preprint satellite and on
//! random models of the layout, in `kernel/tests.rs`; through
//! [`satsim_tree::ForwardDynamics`], bit for bit the kernel's own result, in
//! `tests/it/kernel.rs`).
//!
//! **Lanes of runs.** The kernel is written once over its scalar ([`Real`]): `UnrolledAba`
//! is `UnrolledAba<f64>`, one run; [`UnrolledAba::gather`] makes `UnrolledAba<F64x<N>>`, `N`
//! runs of one layout (a campaign's runs, their masses, inertias and hinge points dispersed)
//! solved together, lane `k` of every argument being run `k`'s, and each lane's result bit
//! for bit what that run's own kernel gives (tested in `kernel/tests.rs`, on every instance
//! the CPU runs).
//! One run and lanes run an instance compiled for the widest instructions the CPU has
//! ([`Instructions`]: AVX-512, AVX2 or the baseline's; `SATSIM_INSTRUCTIONS` caps it),
//! chosen at run time, the same bits on each (lanes have the instances of their own
//! register size only: [`UnrolledAba::instance`]); a pivot test
//! that not all lanes pass returns [`DynamicsError::LanesPart`] and the caller solves those
//! runs one by one. Four lanes on AVX2 solve four runs in about a third of the time of four
//! calls, eight lanes on AVX-512 eight runs in about a quarter (`benches/lanes.rs`; the
//! performance page has the figures).

pub use crate::instructions::Instructions;
use nalgebra::{DVector, Matrix3, Vector3};
use satsim_tree::kernel_parts::{
    self, ChainPart, CoordAxis, SINGULAR_PIVOT_RELATIVE, add_linear_inv_transform, check_len,
    massless_hinges_below, offset_scale,
};
use satsim_tree::real::F64x;
use satsim_tree::real::{Real, mat3};
use satsim_tree::spatial::{
    ArticulatedInertia, Force, Mat3, Motion, RigidInertia, Transform, Vec3, rotation_about,
};
use satsim_tree::{BaseKind, Data, DynamicsError, Input, Kernel, Model};

/// The longest serial chain below the gimbal's tip that [`UnrolledAba`] takes.
pub const MAX_SERIAL: usize = 6;

/// The preprint satellite's serial chain: panels 2 and 3 below the gimbal's tip (panel 1).
/// The kernel has an instance unrolled at this length; others share one that loops.
pub const PREPRINT_SERIAL: usize = 2;

/// An instance of [`UnrolledAba::run_in`] (the same body, so the same operations) under
/// its own attributes: the baseline's out of line, and one per instruction set.
macro_rules! run_instance {
    ($(#[$attr:meta])* $name:ident) => {
        $(#[$attr])*
        fn $name<const N: usize, const EXACT: bool, const LOADED: bool>(
            &self,
            ddq: &mut [T],
            q: &[T],
            v: &[T],
            tau: &[T],
            fext: &[Force<T>],
            locks: Locks,
        ) -> Result<(), DynamicsError> {
            self.run_in::<N, EXACT, LOADED>(ddq, q, v, tau, fext, locks)
        }
    };
}

/// Which of the kernel's hinges are locked (hybrid dynamics, as
/// [`satsim_tree::aba::aba_hybrid`]): the rotors' and the serial bodies', one bit each (rotor `k` of the model's gyrostats, serial
/// body `j` from the tip). Made by [`UnrolledAba::locks`] from a lock mask.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Locks {
    rotors: u64,
    serial: u8,
}

impl Locks {
    /// Nothing locked.
    pub const NONE: Locks = Locks {
        rotors: 0,
        serial: 0,
    };

    /// Whether nothing is locked.
    pub fn is_none(&self) -> bool {
        *self == Self::NONE
    }

    #[inline(always)]
    fn rotor(&self, k: usize) -> bool {
        k < 64 && self.rotors >> k & 1 == 1
    }

    #[inline(always)]
    fn serial(&self, j: usize) -> bool {
        self.serial >> j & 1 == 1
    }
}

/// A balanced rotor on the base (a [`satsim_tree::Gyrostat`]).
#[derive(Clone, Debug)]
struct Rotor<T: Real> {
    /// Unit spin axis, base coordinates.
    axis: Vector3<T>,
    /// `J a`: the axis times the axial moment of inertia (kg m²).
    j_axis: Vector3<T>,
    /// `1 / J`.
    inv_j: T,
    /// Its coordinate in `v`.
    dof: usize,
    /// Its body (the index of its wrench in `fext`), its hinge (axis, fixed rotation where
    /// not the identity, hinge point, child's origin), the hinge's coordinate axis and its
    /// angle's index in `q`: only a wrench on the rotor needs its transform.
    body: usize,
    hinge_axis: Vector3<T>,
    rot0: Option<Matrix3<T>>,
    at: Vector3<T>,
    child_at: Vector3<T>,
    /// The hinge's motion subspace `S` (its axial moment of a wrench is `Sᵀ f`).
    s: Motion<T>,
    coord: Option<CoordAxis>,
    angle: usize,
}

impl<T: Real> Rotor<T> {
    /// `Xup` of the rotor's hinge at `q`: `Joint::transform` (through its coordinate-axis
    /// form where it has one, as `Model::xup`), the same arithmetic.
    #[inline]
    fn xup(&self, q: &[T]) -> Transform<T> {
        let phi = q[self.angle];
        match &self.coord {
            Some(a) => a.transform(phi, &self.at, &self.child_at),
            None => {
                let rot = rotation_about(&self.hinge_axis, phi);
                let et = match &self.rot0 {
                    None => rot,
                    Some(r0) => rot * r0,
                };
                Transform::new(et.transpose(), self.at - et * self.child_at)
            }
        }
    }
}

/// A body of the serial chain, in the frame at its hinge point (its own axes).
#[derive(Clone, Debug)]
struct Serial<T: Real> {
    axis: CoordAxis,
    /// The hinge point in the parent's frame (that frame's origin is the parent's hinge point).
    at: Vector3<T>,
    /// Rigid inertia about the hinge point.
    inertia: RigidInertia<T>,
    /// The same as an articulated inertia (where pass 2 starts).
    start: ArticulatedInertia<T>,
    /// The body's origin from its hinge point (`−child_at`), for the pivot scale of
    /// `aba.rs`, which is taken about the body's origin.
    origin: Vector3<T>,
    /// Its coordinate in `q` and in `v`.
    angle: usize,
    dof: usize,
    /// Its index in `model.bodies` (its wrench in `fext`).
    body: usize,
}

/// [`satsim_tree::aba::aba`] unrolled for one layout (see the module documentation), with external
/// forces ([`UnrolledAba::aba_with_forces`]) or without ([`UnrolledAba::aba`]), and with
/// locked hinges ([`UnrolledAba::aba_hybrid_with_forces`]): the
/// preprint satellite's right-hand side at a fraction of the generic
/// algorithm's instructions, with the same result to round-off and the same errors.
/// Its place is behind the engine's entry, as a [`Kernel`] (see the impl below).
///
/// ```
/// use satsim_satellite::kernel::UnrolledAba;
/// use satsim_tree::{BaseKind, Body, Data, Hinge, ModelBuilder, aba::aba};
/// use satsim_tree::spatial::{Mat3, Vec3};
/// // A bus, a 3-DOF gimbal through two massless links to a panel, a second panel below it.
/// let model = ModelBuilder::new(BaseKind::Free)
///     .body(Body::new("bus", 800.0, Mat3::from_diagonal(&Vec3::new(900.0, 800.0, 600.0))))
///     .body(Body::massless("link1"))
///     .body(Body::massless("link2"))
///     .body(Body::new("panel1", 20.0, Mat3::from_diagonal(&Vec3::new(1.7, 6.7, 8.3))))
///     .body(Body::new("panel2", 20.0, Mat3::from_diagonal(&Vec3::new(1.7, 6.7, 8.3))))
///     .hinge(Hinge::revolute("h1", "bus", "link1", Vec3::z()).at(Vec3::y()))
///     .hinge(Hinge::revolute("h2", "link1", "link2", Vec3::x()))
///     .hinge(Hinge::revolute("h3", "link2", "panel1", Vec3::y()).child_at(-0.6 * Vec3::y()))
///     .hinge(
///         Hinge::revolute("h4", "panel1", "panel2", Vec3::x())
///             .at(0.5 * Vec3::y())
///             .child_at(-0.5 * Vec3::y()),
///     )
///     .build()?;
/// let kernel = UnrolledAba::new(&model).expect("the preprint's layout");
/// let mut data = Data::new(&model);
/// let mut q = model.neutral();
/// q[7..].copy_from_slice(&[0.1, 0.2, 0.3, 1.2]);
/// let (v, tau) = (vec![0.01; model.nv()], vec![0.5; model.nv()]);
/// let fast = kernel.aba(&mut data, &q, &v, &tau)?.clone();
/// let generic = aba(&model, &mut data, &q, &v, &tau, None)?;
/// assert!((&fast - generic).amax() < 1e-12 * generic.amax());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct UnrolledAba<T: Real = f64> {
    nq: usize,
    nv: usize,
    /// The base with its rotors locked on (bias), and less `J a aᵀ` per rotor (pass 2 start).
    base_inertia: RigidInertia<T>,
    base_start: ArticulatedInertia<T>,
    rotors: Vec<Rotor<T>>,
    /// The gimbal's hinges in elimination order: the tip's, its link's, the outermost.
    gimbal: [CoordAxis; 3],
    gimbal_angle: [usize; 3],
    gimbal_dof: [usize; 3],
    /// The gimbal's point in the base's frame.
    point: Vector3<T>,
    /// The tip's rigid inertia about the gimbal's point.
    tip_inertia: RigidInertia<T>,
    tip_start: ArticulatedInertia<T>,
    /// The tip's origin from the gimbal's point (`−child_at`), for the pivot scale.
    tip_origin: Vector3<T>,
    serial: Vec<Serial<T>>,
    /// Bodies (indices in `model.bodies`, as in `fext`): the tip, its link, the outermost link.
    chain_bodies: [usize; 3],
    n_bodies: usize,
    /// Hinge indices (as in a lock mask): the gimbal's, the rotors', the serial bodies'.
    gimbal_hinges: [usize; 3],
    rotor_hinges: Vec<usize>,
    serial_hinges: Vec<usize>,
    n_hinges: usize,
    /// The widest instructions this kernel may run on ([`UnrolledAba::instructions`]).
    at_most: Instructions,
    /// Per pivot (the gimbal's three in elimination order, then the serial bodies): the
    /// hinge named by a singular-hinge error and the hinges through massless links below it.
    names: Vec<(String, Vec<String>)>,
}

impl UnrolledAba {
    /// The kernel for `model` if it has the layout (see the module documentation), `None`
    /// otherwise (the caller keeps [`satsim_tree::aba::aba`]).
    pub fn new(model: &Model) -> Option<Self> {
        if model.base() != BaseKind::Free || model.chains().len() != 1 {
            return None;
        }
        let chain = &model.chains()[0];
        if chain.hinges() != 3
            || !chain.is_spherical()
            || chain.has_offset_links()
            || chain.parent() != 0
        {
            return None;
        }
        if model.gyrostats().iter().any(|g| g.parent() != 0) {
            return None;
        }
        let order: [usize; 3] = chain.order().try_into().expect("three hinges");
        let dofs: [usize; 3] = chain.dofs().try_into().expect("three hinges");
        let joint = |i: usize| model.joint(i).expect("non-root body has a joint");
        let mut gimbal = [None; 3];
        for (t, g) in gimbal.iter_mut().enumerate() {
            *g = kernel_parts::coord_axis(model, order[t]);
        }
        let [Some(g0), Some(g1), Some(g2)] = gimbal else {
            return None;
        };
        // The serial chain: the tip's only child, its only child, ...
        let tip = chain.tip();
        let mut body = tip;
        let mut serial_bodies = Vec::new();
        loop {
            let mut children = model.children(body);
            let Some(child) = children.next() else { break };
            if children.next().is_some()
                || kernel_parts::is_gyrostat(model, child)
                || kernel_parts::chain_part(model, child) != ChainPart::None
                || kernel_parts::coord_axis(model, child).is_none()
                || joint(child).armature() != 0.0
                || serial_bodies.len() == MAX_SERIAL
            {
                return None;
            }
            serial_bodies.push(child);
            body = child;
        }
        // No other bodies: the base, its rotors, the two links, the tip and the serial chain.
        if model.n_bodies() != 1 + model.gyrostats().len() + 3 + serial_bodies.len() {
            return None;
        }
        let base_nq = model.base_nq();
        let r = *chain.tip_at();
        let tip_body = &model.bodies()[tip];
        let tip_inertia =
            RigidInertia::from_com(tip_body.mass(), tip_body.com() - r, *tip_body.inertia_com());
        let mut serial = Vec::new();
        let mut parent_origin = r; // the parent's hinge point in its own body frame
        for &i in &serial_bodies {
            let j = joint(i);
            let b = &model.bodies()[i];
            let inertia =
                RigidInertia::from_com(b.mass(), b.com() - j.child_at(), *b.inertia_com());
            serial.push(Serial {
                axis: kernel_parts::coord_axis(model, i).expect("checked above"),
                at: j.at() - parent_origin,
                inertia,
                start: inertia.into(),
                origin: -j.child_at(),
                angle: base_nq + j.hinge(),
                dof: model.base_nv() + j.hinge(),
                body: i,
            });
            parent_origin = *j.child_at();
        }
        let name = |i: usize| {
            (
                model.hinge_names()[joint(i).hinge()].clone(),
                massless_hinges_below(model, i),
            )
        };
        let names = order
            .iter()
            .chain(&serial_bodies)
            .map(|&i| name(i))
            .collect();
        let rotors = model
            .gyrostats()
            .iter()
            .map(|g| Rotor {
                axis: *g.axis(),
                j_axis: g.axis() * g.axial(),
                inv_j: 1.0 / g.axial(),
                dof: joint(g.body()).dof(),
                body: g.body(),
                hinge_axis: *joint(g.body()).axis(),
                rot0: Some(*joint(g.body()).rot0()).filter(|r| *r != Mat3::identity()),
                at: *joint(g.body()).at(),
                child_at: *joint(g.body()).child_at(),
                s: *joint(g.body()).s(),
                coord: kernel_parts::coord_axis(model, g.body()),
                angle: base_nq + joint(g.body()).hinge(),
            })
            .collect();
        Some(Self {
            nq: model.nq(),
            nv: model.nv(),
            base_inertia: *kernel_parts::carrier_inertia(model, 0),
            base_start: *kernel_parts::carrier_start(model, 0),
            rotors,
            gimbal: [g0, g1, g2],
            gimbal_angle: order.map(|i| base_nq + joint(i).hinge()),
            gimbal_dof: dofs,
            point: *chain.point(),
            tip_inertia,
            tip_start: tip_inertia.into(),
            tip_origin: -r,
            serial,
            chain_bodies: order,
            n_bodies: model.n_bodies(),
            gimbal_hinges: order.map(|i| joint(i).hinge()),
            rotor_hinges: model
                .gyrostats()
                .iter()
                .map(|g| joint(g.body()).hinge())
                .collect(),
            serial_hinges: serial_bodies.iter().map(|&i| joint(i).hinge()).collect(),
            n_hinges: model.n_hinges(),
            at_most: Instructions::Avx512,
            names,
        })
    }

    /// Forward dynamics without external forces, as [`satsim_tree::aba::aba`] with `fext = None`:
    /// the accelerations `q̈` into `data.ddq` (same layout: the base's `[ω̇; v̇]` in its own
    /// axes, then the hinges in their order of addition, rotors included). `data` must be
    /// this model's; only `data.ddq` is written (the other buffers of `aba` are not, nor
    /// read: the kernel computes its own transforms, so a caller's forward kinematics in
    /// `data` stays as it was). Fails as [`satsim_tree::aba::aba`] does:
    /// [`DynamicsError::SingularHinge`] at a gimbal lock (same hinge, same pivot),
    /// [`DynamicsError::SingularBase`], or a dimension error.
    pub fn aba<'d>(
        &self,
        data: &'d mut Data,
        q: &[f64],
        v: &[f64],
        tau: &[f64],
    ) -> Result<&'d DVector<f64>, DynamicsError> {
        self.aba_with_forces(data, q, v, tau, None)
    }

    /// As [`UnrolledAba::aba`], with external body forces `fext` in [`satsim_tree::aba::aba`]'s
    /// convention (one wrench `[n; f]` per body in `model.bodies` order, body coordinates,
    /// moment about the body's origin; see [`satsim_tree::rnea()`]), on any body: the base, its
    /// rotors (the axial moment drives the spin, the rest acts on the base through the
    /// bearing), the gimbal's massless links, the tip and the serial bodies. `None` is the
    /// force-free instance, as cheap as [`UnrolledAba::aba`]. A `fext` of another length
    /// than the model's bodies is a dimension error.
    ///
    /// ```
    /// use satsim_tree::spatial::{Force, Mat3, Vec3};
    /// use satsim_satellite::kernel::UnrolledAba;
    /// use satsim_tree::{BaseKind, Body, Data, Hinge, ModelBuilder, aba::aba, samples};
    /// // A bus with three wheels, a 3-DOF gimbal through two massless links to a panel.
    /// let mut builder = ModelBuilder::new(BaseKind::Free)
    ///     .body(Body::new("bus", 800.0, Mat3::from_diagonal(&Vec3::new(900.0, 800.0, 600.0))))
    ///     .body(Body::massless("link1"))
    ///     .body(Body::massless("link2"))
    ///     .body(Body::new("panel", 20.0, Mat3::from_diagonal(&Vec3::new(1.7, 6.7, 8.3))))
    ///     .hinge(Hinge::revolute("h1", "bus", "link1", Vec3::z()).at(Vec3::y()))
    ///     .hinge(Hinge::revolute("h2", "link1", "link2", Vec3::x()))
    ///     .hinge(Hinge::revolute("h3", "link2", "panel", Vec3::y()).child_at(-0.6 * Vec3::y()));
    /// samples::push_wheels(&mut builder, "bus");
    /// let model = builder.build()?;
    /// let kernel = UnrolledAba::new(&model).expect("the preprint's layout");
    /// let mut data = Data::new(&model);
    /// let mut q = model.neutral();
    /// q[7..10].copy_from_slice(&[0.1, 0.2, 0.3]);
    /// let (v, tau) = (vec![0.01; model.nv()], vec![0.5; model.nv()]);
    /// // A wrench on every body, the massless links included.
    /// let fext: Vec<Force> = (0..model.n_bodies())
    ///     .map(|i| Force::new(Vec3::new(0.1, -0.2, 0.3) * i as f64, Vec3::new(1.0, 0.5, -0.4)))
    ///     .collect();
    /// let fast = kernel.aba_with_forces(&mut data, &q, &v, &tau, Some(&fext))?.clone();
    /// let generic = aba(&model, &mut data, &q, &v, &tau, Some(&fext))?;
    /// assert!((&fast - generic).amax() < 1e-12 * generic.amax());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn aba_with_forces<'d>(
        &self,
        data: &'d mut Data,
        q: &[f64],
        v: &[f64],
        tau: &[f64],
        fext: Option<&[Force]>,
    ) -> Result<&'d DVector<f64>, DynamicsError> {
        self.aba_hybrid_with_forces(data, q, v, tau, fext, Locks::NONE)
    }

    /// Hybrid dynamics (Featherstone §9.2), as [`satsim_tree::aba::aba_hybrid`]: as
    /// [`UnrolledAba::aba_with_forces`], except that the hinges locked in `locks` (rotors,
    /// serial bodies; see [`UnrolledAba::locks`]) have zero acceleration, their `τ` ignored,
    /// and pass their child's inertia rigidly to the parent. A locked rotor rides on the
    /// base: its axial inertia is the base's again, its axial torque and the axial moment of
    /// its wrench go through the lock, its spin's gyroscopic couple stays.
    ///
    /// ```
    /// use satsim_tree::spatial::{Mat3, Vec3};
    /// use satsim_satellite::kernel::UnrolledAba;
    /// use satsim_tree::{BaseKind, Body, Data, Hinge, ModelBuilder, aba::aba_hybrid};
    /// let mut builder = ModelBuilder::new(BaseKind::Free)
    ///     .body(Body::new("bus", 800.0, Mat3::from_diagonal(&Vec3::new(900.0, 800.0, 600.0))))
    ///     .body(Body::massless("link1"))
    ///     .body(Body::massless("link2"))
    ///     .body(Body::new("panel", 20.0, Mat3::from_diagonal(&Vec3::new(1.7, 6.7, 8.3))))
    ///     .hinge(Hinge::revolute("h1", "bus", "link1", Vec3::z()).at(Vec3::y()))
    ///     .hinge(Hinge::revolute("h2", "link1", "link2", Vec3::x()))
    ///     .hinge(Hinge::revolute("h3", "link2", "panel", Vec3::y()).child_at(-0.6 * Vec3::y()));
    /// satsim_tree::samples::push_wheels(&mut builder, "bus");
    /// let model = builder.build()?;
    /// let kernel = UnrolledAba::new(&model).expect("the preprint's layout");
    /// // Wheel `x` (hinge 3) held; a gimbal hinge locked is not the kernel's.
    /// let mut locked = vec![false, false, false, true, false, false];
    /// let locks = kernel.locks(&locked).expect("no gimbal hinge locked");
    /// let mut data = Data::new(&model);
    /// let mut q = model.neutral();
    /// q[7..10].copy_from_slice(&[0.1, 0.2, 0.3]);
    /// let (v, tau) = (vec![0.01; model.nv()], vec![0.5; model.nv()]);
    /// let fast = kernel.aba_hybrid_with_forces(&mut data, &q, &v, &tau, None, locks)?.clone();
    /// let generic = aba_hybrid(&model, &mut data, &q, &v, &tau, None, &locked)?;
    /// assert!((&fast - generic).amax() < 1e-12 * generic.amax());
    /// assert_eq!(fast[6 + 3], 0.0);
    /// locked[1] = true;
    /// assert!(kernel.locks(&locked).is_none());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn aba_hybrid_with_forces<'d>(
        &self,
        data: &'d mut Data,
        q: &[f64],
        v: &[f64],
        tau: &[f64],
        fext: Option<&[Force]>,
        locks: Locks,
    ) -> Result<&'d DVector<f64>, DynamicsError> {
        self.aba_hybrid_with_forces_into(q, v, tau, fext, locks, data.ddq.as_mut_slice())?;
        Ok(&data.ddq)
    }
}

impl<T: Real> UnrolledAba<T> {
    /// The same kernel on the baseline target's instructions only (two-wide SSE2 on
    /// x86-64): `self.instructions(Instructions::Baseline)`.
    pub fn portable(self) -> Self {
        self.instructions(Instructions::Baseline)
    }

    /// The same kernel on instructions no wider than `at_most`, where the CPU has wider
    /// ones (by default a kernel runs on the widest it has): to measure what the wider
    /// instructions give, and to test that every instance gives the same bits.
    pub fn instructions(mut self, at_most: Instructions) -> Self {
        self.at_most = at_most;
        self
    }

    /// Number of serial bodies below the gimbal's tip.
    pub fn serial_bodies(&self) -> usize {
        self.serial.len()
    }

    /// The kernel's form of a lock mask `locked` (one entry per hinge in the order of
    /// addition, rotors included, as [`satsim_tree::aba::aba_hybrid`] takes it), or `None`
    /// where the kernel does not take it: a gimbal hinge locked (the caller keeps
    /// [`satsim_tree::aba::aba_hybrid`]), a mask of another length, or a locked rotor past
    /// the 64th.
    pub fn locks(&self, locked: &[bool]) -> Option<Locks> {
        if locked.len() != self.n_hinges || self.gimbal_hinges.iter().any(|&h| locked[h]) {
            return None;
        }
        let mut locks = Locks::NONE;
        for (k, &h) in self.rotor_hinges.iter().enumerate() {
            if locked[h] {
                if k >= 64 {
                    return None;
                }
                locks.rotors |= 1 << k;
            }
        }
        for (j, &h) in self.serial_hinges.iter().enumerate() {
            if locked[h] {
                locks.serial |= 1 << j;
            }
        }
        Some(locks)
    }

    /// As [`UnrolledAba::aba_hybrid_with_forces`], with `q̈` written into `ddq` (length
    /// `nv`) instead of `data.ddq`: the kernel needs no [`Data`], and a caller whose state
    /// holds the velocities in `v`'s order gets `q̈` straight into its derivative, with no
    /// copy (a copy right after the writes costs more than its instructions: its wide loads
    /// wait for the narrower stores to retire).
    ///
    /// Over lanes (`T` = [`satsim_tree::real::F64x`], a kernel made by
    /// [`UnrolledAba::gather`]): `N` runs at once, lane `k` of every argument and of `ddq`
    /// being run `k`'s, each lane's result bit for bit what the `f64` kernel of that run
    /// gives. Where the lanes part ways at a pivot test (near a singular configuration on
    /// some lane), it returns [`DynamicsError::LanesPart`] with `ddq` unspecified: solve each
    /// run with its own `f64` kernel then.
    pub fn aba_hybrid_with_forces_into(
        &self,
        q: &[T],
        v: &[T],
        tau: &[T],
        fext: Option<&[Force<T>]>,
        locks: Locks,
        ddq: &mut [T],
    ) -> Result<(), DynamicsError> {
        check_len("q", q.len(), self.nq)?;
        check_len("v", v.len(), self.nv)?;
        check_len("tau", tau.len(), self.nv)?;
        check_len("ddq", ddq.len(), self.nv)?;
        match fext {
            None => self.serial_len::<false>(ddq, q, v, tau, &[], locks),
            Some(f) => {
                check_len("fext", f.len(), self.n_bodies)?;
                self.serial_len::<true>(ddq, q, v, tau, f, locks)
            }
        }
    }

    /// [`UnrolledAba::run`]'s instance for this model's serial chain: the preprint's
    /// length ([`PREPRINT_SERIAL`]) has its own, unrolled at that length; every other length
    /// (0 to [`MAX_SERIAL`]) shares one that loops to the model's length. Both execute the
    /// same operations in the same order, so the same bits. An instance for each of the
    /// seven lengths made three times the machine code (each is the whole kernel inlined,
    /// per scalar, instruction set and `LOADED`) to save about 2 % on the other lengths.
    #[inline(always)]
    fn serial_len<const LOADED: bool>(
        &self,
        ddq: &mut [T],
        q: &[T],
        v: &[T],
        tau: &[T],
        fext: &[Force<T>],
        locks: Locks,
    ) -> Result<(), DynamicsError> {
        if self.serial.len() == PREPRINT_SERIAL {
            self.run::<PREPRINT_SERIAL, true, LOADED>(ddq, q, v, tau, fext, locks)
        } else {
            self.run::<MAX_SERIAL, false, LOADED>(ddq, q, v, tau, fext, locks)
        }
    }

    /// [`UnrolledAba::run_in`], compiled for the widest vectors this CPU has (at most
    /// [`UnrolledAba::instructions`]) on x86-64: the instance compiled for AVX-512 (32
    /// vector registers, eight `f64` per instruction), else for AVX2 (four `f64` per
    /// instruction, 16 registers; the baseline target has two), else the baseline's. One run
    /// (`f64`) takes them too: its operations are not lane-wise, but the 3-vectors and 3×3
    /// blocks fill wider registers, and VEX/EVEX's three-operand forms and AVX-512's extra
    /// registers save moves and spills (one orbit of the peer scene: 0.83 of the baseline
    /// instance's time on AVX2 or AVX-512).
    #[inline(always)]
    #[allow(unsafe_code)]
    fn run<const N: usize, const EXACT: bool, const LOADED: bool>(
        &self,
        ddq: &mut [T],
        q: &[T],
        v: &[T],
        tau: &[T],
        fext: &[Force<T>],
        locks: Locks,
    ) -> Result<(), DynamicsError> {
        #[cfg(target_arch = "x86_64")]
        {
            // `instance` says which instance runs; the guards repeat what it already
            // ensures, as constants of `T`, so the compiler does not even instantiate the
            // instances a `T` has not.
            match self.instance() {
                // SAFETY: `run_avx512`'s only requirement is a CPU with AVX-512 F and VL
                // (and AVX2): `instance` gives `Avx512` only where `Instructions::detected`
                // found them.
                Instructions::Avx512 if const { Self::HAS_AVX512 } => {
                    return unsafe {
                        self.run_avx512::<N, EXACT, LOADED>(ddq, q, v, tau, fext, locks)
                    };
                }
                // SAFETY: `run_avx2`'s only requirement is a CPU with AVX2: `instance` gives
                // `Avx2` only where `Instructions::detected` found it.
                Instructions::Avx2 if const { Self::HAS_AVX2 } => {
                    return unsafe {
                        self.run_avx2::<N, EXACT, LOADED>(ddq, q, v, tau, fext, locks)
                    };
                }
                _ => {}
            }
        }
        self.run_out::<N, EXACT, LOADED>(ddq, q, v, tau, fext, locks)
    }

    /// Whether `T` has an AVX2 instance: one run, and four lanes (one 256-bit register per
    /// value).
    const HAS_AVX2: bool = T::LANES == 1 || T::LANES == 4;
    /// Whether `T` has an AVX-512 instance: one run, and eight lanes (one 512-bit register
    /// per value).
    const HAS_AVX512: bool = T::LANES == 1 || T::LANES == 8;

    /// The instance this kernel runs on this CPU: the widest instruction set, no wider than
    /// [`UnrolledAba::instructions`] and the CPU's, that `T` has an instance for.
    ///
    /// One run (`f64`) has all three. Lanes have the baseline's and the one whose registers
    /// hold one value of theirs: four lanes AVX2's, eight lanes AVX-512's, two lanes only the
    /// baseline's (SSE2's 128-bit registers). These are the widths
    /// [`Instructions::lanes`] gives each CPU; another width on a CPU runs on the baseline's
    /// instance (four lanes on AVX-512: AVX2's). Each instance is the whole kernel inlined,
    /// for the preprint's serial length and for any other, with and without loads, and the
    /// wider lanes' are the largest:
    /// the instances that no CPU's own width takes were a third of the kernel's machine code.
    pub fn instance(&self) -> Instructions {
        match self.at_most.min(Instructions::detected()) {
            Instructions::Avx512 if Self::HAS_AVX512 => Instructions::Avx512,
            Instructions::Avx2 | Instructions::Avx512 if Self::HAS_AVX2 => Instructions::Avx2,
            _ => Instructions::Baseline,
        }
    }

    run_instance! {
        /// [`UnrolledAba::run_in`] out of line, for the baseline target.
        #[inline(never)]
        run_out
    }

    run_instance! {
        /// [`UnrolledAba::run_in`] compiled for AVX2: every piece of the kernel is inlined
        /// into it, so all of it uses four-wide registers. The
        /// same operations as the baseline's, lane by lane (no fused multiply-add: Rust does
        /// not contract `a * b + c`), so the same bits.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        run_avx2
    }

    run_instance! {
        /// [`UnrolledAba::run_in`] compiled for AVX-512 (F and VL): the same operations again,
        /// so the same bits, in 32 vector registers where AVX2 has 16. Eight lanes fill one
        /// 512-bit register per value; four lanes in 256-bit registers spill less.
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2,avx512f,avx512vl")]
        run_avx512
    }

    /// The three passes for the serial bodies (`q`, `v`, `tau`, `ddq` of checked lengths):
    /// exactly `N` of them when `EXACT` (the loops unroll), else the model's, at most `N`;
    /// `LOADED`: with the external forces `fext` (one per body, checked), else `fext` is
    /// not read; `locks`: the locked hinges (hybrid dynamics).
    #[inline(always)]
    fn run_in<const N: usize, const EXACT: bool, const LOADED: bool>(
        &self,
        ddq: &mut [T],
        q: &[T],
        v: &[T],
        tau: &[T],
        fext: &[Force<T>],
        locks: Locks,
    ) -> Result<(), DynamicsError> {
        // A constant length where `EXACT`; else the model's, which `min` tells the compiler
        // is within the arrays below (no index checks).
        let serial: &[Serial<T>] = if EXACT {
            <&[Serial<T>; N]>::try_from(self.serial.as_slice()).expect("N bodies")
        } else {
            &self.serial[..self.serial.len().min(N)]
        };
        let len = serial.len();
        // Pass 1, outward. The base, with its rotors' gyroscopic couple and axial reactions.
        let v0 = Motion::from_slice(&v[..6]);
        let mut pa0 = v0.cross_force(&self.base_inertia.mul_motion(&v0));
        if LOADED {
            pa0 -= fext[0];
        }
        let mut spin = Vector3::zeros();
        for (k, r) in self.rotors.iter().enumerate() {
            spin += r.j_axis * v[r.dof];
            if !locks.rotor(k) {
                // (Locked, the axial torque goes through the lock: the hold torque.)
                pa0.ang += r.axis * self.rotor_torque::<LOADED>(r, tau, fext);
            }
            if LOADED && !is_zero(&fext[r.body]) {
                // The rest of the rotor's wrench acts on the base through the bearing. None
                // where no effect loads the rotor (the gravity gradient loads the wheels
                // through the bus): then its transform, a `sin_cos` per lane, is not needed.
                pa0 -= r.xup(q).inv_apply_force(&fext[r.body]);
            }
        }
        pa0.ang += mat3::cross(&v0.ang, &spin);
        // The gimbal: its rotation (base axes to the tip's), the axes in the tip's axes.
        let [g0, g1, g2] = &self.gimbal;
        let [i0, i1, i2] = self.gimbal_angle;
        let o = Vector3::zeros();
        let e0m = g0.transform(q[i0], &o, &o).rot;
        let e1m = g1.transform(q[i1], &o, &o).rot;
        let e2m = g2.transform(q[i2], &o, &o).rot;
        let e0 = g0.scaled_axis(T::one());
        let e1 = g1.times_axis(&e0m);
        let r01 = g1.post_rotate(&e0m, &e1m);
        let e2 = g2.times_axis(&r01);
        let x = Transform::new(g2.post_rotate(&r01, &e2m), self.point);
        let [d0, d1, d2] = self.gimbal_dof;
        let (w0, w1, w2) = (e0 * v[d0], e1 * v[d1], e2 * v[d2]);
        let w_rel = w0 + w1 + w2;
        // The base's velocity at the point, tip axes; all axes pass through the point, so
        // the chain's velocity-product term is Σ vₜ × Sₜ q̇ₜ with vₜ the links' velocities.
        let vp = x.apply_motion(&v0);
        let c_tip = Motion::new(
            mat3::cross(&vp.ang, &w_rel) + mat3::cross(&w2, &w1) + mat3::cross(&(w2 + w1), &w0),
            mat3::cross(&vp.lin, &w_rel),
        );
        let v_tip = Motion::new(vp.ang + w_rel, vp.lin);
        let mut pa_tip = v_tip.cross_force(&self.tip_inertia.mul_motion(&v_tip));
        let [tip, link_in, link_out] = self.chain_bodies;
        // The links' wrenches at the point, tip axes: g₁ the tip's link's, g₂ both links'
        // (each link's origin is the point: a rotation only).
        let (mut g1, mut g2) = (Force::zero(), Force::zero());
        if LOADED {
            pa_tip -= at_hinge(&fext[tip], &self.tip_origin);
            let rotate = |m: &Matrix3<T>, f: &Force<T>| {
                Force::new(mat3::mul(m, &f.ang), mat3::mul(m, &f.lin))
            };
            g1 = rotate(&e0m, &fext[link_in]);
            g2 = g1 + rotate(&r01, &fext[link_out]);
        }
        // The serial bodies.
        let mut xs = [Transform::identity(); N];
        let mut cs = [Motion::zero(); N];
        let mut pas = [Force::zero(); N];
        let mut vp = v_tip;
        for (j, s) in serial.iter().enumerate() {
            xs[j] = s.axis.transform(q[s.angle], &s.at, &o);
            let vx = s.axis.apply_motion(&xs[j], &vp);
            let sq = s.axis.scaled_axis(v[s.dof]);
            cs[j] = Motion::new(mat3::cross(&vx.ang, &sq), mat3::cross(&vx.lin, &sq));
            let vj = Motion::new(vx.ang + sq, vx.lin);
            pas[j] = vj.cross_force(&s.inertia.mul_motion(&vj));
            if LOADED {
                pas[j] -= at_hinge(&fext[s.body], &s.origin);
            }
            vp = vj;
        }
        // Pass 2, inward: the serial bodies, last first, each projected into its parent.
        let mut us = [Force::zero(); N];
        let mut uu = [T::zero(); N];
        let mut inv_ds = [T::zero(); N];
        // Each parent's inertia is written into one of two buffers, in turn, and read from
        // there (no 216-byte copies of whole inertias).
        let mut buffers = [ArticulatedInertia::default(); 2];
        let [b0, b1] = &mut buffers;
        let (mut parent, mut written) = (b0, b1);
        let mut ia: &ArticulatedInertia<T> = if len > 0 {
            &serial[len - 1].start
        } else {
            &self.tip_start
        };
        let mut pa = if len > 0 { pas[len - 1] } else { pa_tip };
        for j in (0..len).rev() {
            let s = &serial[j];
            let a = &s.axis;
            let (parent_start, parent_bias) = if j > 0 {
                (&serial[j - 1].start, pas[j - 1])
            } else {
                (&self.tip_start, pa_tip)
            };
            if locks.serial(j) {
                // Known (zero) acceleration: the body rides rigidly on its parent.
                a.add_inv_transform(ia, &xs[j], parent, Some(parent_start));
                let pa_j = pa + ia.mul_motion(&cs[j]);
                pa = parent_bias + a.inv_apply_force(&xs[j], &pa_j);
            } else {
                let u_col = Force::new(a.times_axis(&ia.a), a.tr_times_axis(&ia.b));
                let d = a.dot_axis(&u_col.ang);
                self.check(d, ia, &s.origin, 3 + j)?;
                let inv_d = T::one() / d;
                let u = tau[s.dof] - a.dot_axis(&pa.ang);
                // The parent's inertia: its start plus Xᵀ (IA − U Uᵀ / D) X.
                let iac = a.project_at_point(ia, inv_d, &cs[j], &xs[j], parent, parent_start);
                let pa_j = pa + iac + u_col * (u * inv_d);
                pa = parent_bias + a.inv_apply_force(&xs[j], &pa_j);
                (us[j], uu[j], inv_ds[j]) = (u_col, u, inv_d);
            }
            std::mem::swap(&mut parent, &mut written);
            ia = written;
        }
        // The gimbal at its point: D = L Δ Lᵀ over the axes e₀ (the tip's), e₁, e₂, as
        // `chain_inward` (the tip's hinge first), with the same pivot scales.
        let (ah, bh) = (&ia.a, &ia.b);
        let w0 = Force::new(g0.times_axis(ah), g0.tr_times_axis(bh));
        let u0 = tau[d0] - g0.dot_axis(&pa.ang);
        let p0 = g0.dot_axis(&w0.ang);
        self.check(p0, ia, &self.tip_origin, 0)?;
        let inv0 = T::one() / p0;
        let tr_a = ah.trace() - w0.ang.dot(&w0.ang) * inv0;
        let l10 = e1.dot(&w0.ang) * inv0;
        let w1 = Force::new(mat3::mul(ah, &e1), mat3::tr_mul(bh, &e1)) - w0 * l10;
        // The links' wrenches load the hinges between them and the base (`links_bias` of
        // `aba.rs`): the tip's link's on e₁, both on e₂.
        let (t1, t2) = if LOADED {
            (tau[d1] + e1.dot(&g1.ang), tau[d2] + e2.dot(&g2.ang))
        } else {
            (tau[d1], tau[d2]) // (no `+ 0`: it cannot be folded away)
        };
        let u1 = t1 - e1.dot(&pa.ang) - l10 * u0;
        let p1 = e1.dot(&w1.ang);
        self.check_plain(p1, tr_a, 1)?;
        let inv1 = T::one() / p1;
        let tr_a = tr_a - w1.ang.dot(&w1.ang) * inv1;
        let l20 = e2.dot(&w0.ang) * inv0;
        let l21 = e2.dot(&w1.ang) * inv1;
        let w2 = Force::new(mat3::mul(ah, &e2), mat3::tr_mul(bh, &e2)) - w0 * l20 - w1 * l21;
        let u2 = t2 - e2.dot(&pa.ang) - l20 * u0 - l21 * u1;
        let p2 = e2.dot(&w2.ang);
        self.check_plain(p2, tr_a, 2)?;
        let inv2 = T::one() / p2;
        // What the spherical joint passes on: [0 0; 0 C − Bᵀ A⁻¹ B], and the bias.
        let cc: Matrix3<T> = ia.c
            - mat3::outer(&(w0.lin * inv0), &w0.lin)
            - mat3::outer(&(w1.lin * inv1), &w1.lin)
            - mat3::outer(&(w2.lin * inv2), &w2.lin);
        let mut pa_h = pa + w0 * (u0 * inv0) + w1 * (u1 * inv1) + w2 * (u2 * inv2);
        pa_h.lin += mat3::mul(&cc, &c_tip.lin);
        if LOADED {
            pa_h -= g2; // and reach the base rigidly
        }
        // Locked rotors' axial inertia is the base's again.
        let with_locked;
        let base_start = if locks.rotors == 0 {
            &self.base_start
        } else {
            let mut start = self.base_start;
            for (k, r) in self.rotors.iter().enumerate() {
                if locks.rotor(k) {
                    start.a += mat3::outer(&r.j_axis, &r.axis);
                }
            }
            with_locked = start;
            &with_locked
        };
        let mut ia0 = ArticulatedInertia::default();
        add_linear_inv_transform(&cc, &x, &mut ia0, Some(base_start));
        let pa0 = pa0 + x.inv_apply_force(&pa_h);
        // Pass 3, outward: a₀ = IA₀⁻¹ (τ₀ − pA₀), the rotors, the gimbal, the serial bodies.
        let a0 = ia0
            .solve(&(Force::from_slice(&tau[..6]) - pa0))
            .ok_or(if T::LANES == 1 {
                DynamicsError::SingularBase
            } else {
                DynamicsError::LanesPart
            })?;
        ddq[..6].copy_from_slice(&a0.to_array());
        for (k, r) in self.rotors.iter().enumerate() {
            ddq[r.dof] = if locks.rotor(k) {
                T::zero()
            } else {
                self.rotor_torque::<LOADED>(r, tau, fext) * r.inv_j - r.axis.dot(&a0.ang)
            };
        }
        let a = x.apply_motion(&a0) + c_tip;
        let qdd2 = (u2 - a.dot(&w2)) * inv2;
        let qdd1 = (u1 - a.dot(&w1)) * inv1 - l21 * qdd2;
        let qdd0 = (u0 - a.dot(&w0)) * inv0 - l20 * qdd2 - l10 * qdd1;
        ddq[d0] = qdd0;
        ddq[d1] = qdd1;
        ddq[d2] = qdd2;
        let mut ap = Motion::new(a.ang + e0 * qdd0 + e1 * qdd1 + e2 * qdd2, a.lin);
        for (j, s) in serial.iter().enumerate() {
            let aj = s.axis.apply_motion(&xs[j], &ap) + cs[j];
            let qdd = if locks.serial(j) {
                T::zero()
            } else {
                (uu[j] - aj.dot(&us[j])) * inv_ds[j]
            };
            ddq[s.dof] = qdd;
            ap = Motion::new(aj.ang + s.axis.scaled_axis(qdd), aj.lin);
        }
        Ok(())
    }

    /// Rotor `r`'s axial torque: its `τ`, plus the axial moment `Sᵀ f` of its external
    /// wrench when `LOADED` (not `+ 0` otherwise: that cannot be folded away).
    #[inline(always)]
    fn rotor_torque<const LOADED: bool>(&self, r: &Rotor<T>, tau: &[T], fext: &[Force<T>]) -> T {
        if LOADED {
            tau[r.dof] + r.s.dot(&fext[r.body])
        } else {
            tau[r.dof]
        }
    }

    /// `aba.rs`'s pivot test for a body whose articulated inertia `ia` is given about its
    /// hinge point while `aba.rs` takes the scale about the body's origin, at `origin` from
    /// the point: `tr A_o + |o|² tr C`. Cheap first: for a positive semidefinite `ia`,
    /// `tr A_o ≤ 2 tr A + 2 |o|² tr C` (`(x + y)ᵀ M (x + y) ≤ 2 xᵀ M x + 2 yᵀ M y`), so a
    /// pivot above that bound's threshold is regular; the exact scale only below it (one
    /// run; a batch of lanes where any lane is below it parts: [`DynamicsError::LanesPart`]).
    #[inline]
    fn check(
        &self,
        d: T,
        ia: &ArticulatedInertia<T>,
        origin: &Vector3<T>,
        pivot: usize,
    ) -> Result<(), DynamicsError> {
        let (tr_a, tr_c) = (ia.a.trace(), ia.c.trace());
        let o2 = origin.dot(origin);
        let bound = T::splat(2.0) * tr_a + T::splat(3.0) * o2 * tr_c;
        if d.all_with(bound, |d, bound| {
            d > SINGULAR_PIVOT_RELATIVE * bound && d < f64::INFINITY
        }) {
            return Ok(());
        }
        if T::LANES > 1 {
            return Err(DynamicsError::LanesPart);
        }
        let lane = |m: &Matrix3<T>| m.map(|x| x.lane(0));
        let (origin, tr_a, tr_c) = (origin.map(|x| x.lane(0)), tr_a.lane(0), tr_c.lane(0));
        let scale = offset_scale(&origin, &lane(&ia.b), &lane(&ia.c), &[], &[], tr_a, tr_c);
        self.check_plain(d, T::splat(scale), pivot)
    }

    /// `aba.rs`'s pivot test against `scale`; the error names pivot `pivot`'s hinge.
    #[inline]
    fn check_plain(&self, d: T, scale: T, pivot: usize) -> Result<(), DynamicsError> {
        // Written so that a NaN pivot counts as singular too.
        if d.all_with(scale, |d, scale| {
            d.is_finite() && d > SINGULAR_PIVOT_RELATIVE * scale
        }) {
            Ok(())
        } else if T::LANES > 1 {
            Err(DynamicsError::LanesPart)
        } else {
            Err(self.singular(d.lane(0), scale.lane(0), pivot))
        }
    }

    #[cold]
    #[inline(never)]
    fn singular(&self, d: f64, scale: f64, pivot: usize) -> DynamicsError {
        let (hinge, through) = self.names[pivot].clone();
        DynamicsError::SingularHinge {
            hinge,
            through,
            pivot: d,
            relative: if scale > 0.0 { d / scale } else { 0.0 },
        }
    }
}

impl<const N: usize> UnrolledAba<F64x<N>> {
    /// The kernel of `N` runs in lanes (lane `k`: `runs[k]`'s constants), or `None` where
    /// they differ in anything the kernel branches on: the layout (coordinates, bodies,
    /// hinge axes and their signs, which rotors have a fixed rotation or a coordinate axis)
    /// and which serial hinge points coincide with the parent's (the pure-rotation case of
    /// the inertia transform). Masses, inertias and hinge points may differ: the runs of a
    /// campaign that disperses them share one kernel.
    ///
    /// ```
    /// use satsim_satellite::kernel::{Locks, UnrolledAba};
    /// use satsim_tree::real::{F64x, Real};
    /// use satsim_tree::read_model;
    /// let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/satellite.toml");
    /// let heavy = {
    ///     let mut b = read_model(&path)?.to_builder();
    ///     b.bodies_mut()[4].mass *= 1.5; // panel 2
    ///     b.build()?
    /// };
    /// let (nominal, heavy) = (read_model(&path)?, heavy);
    /// let (k0, k1) = (UnrolledAba::new(&nominal).unwrap(), UnrolledAba::new(&heavy).unwrap());
    /// let lanes = UnrolledAba::<F64x<2>>::gather([&k0, &k1]).expect("one layout");
    /// // Run k's state in lane k.
    /// let mut q0 = nominal.neutral();
    /// q0[7..12].copy_from_slice(&[0.1, 0.2, 0.3, 1.2, -1.0]);
    /// let mut q1 = q0.clone();
    /// q1[10] = 0.9;
    /// let (v, tau) = (vec![0.01; nominal.nv()], vec![0.5; nominal.nv()]);
    /// let pack = |a: &[f64], b: &[f64]| -> Vec<F64x<2>> {
    ///     a.iter().zip(b).map(|(&x, &y)| F64x([x, y])).collect()
    /// };
    /// let mut ddq = vec![F64x::splat(0.0); nominal.nv()];
    /// let (q, v2, tau2) = (pack(&q0, &q1), pack(&v, &v), pack(&tau, &tau));
    /// lanes.aba_hybrid_with_forces_into(&q, &v2, &tau2, None, Locks::NONE, &mut ddq)?;
    /// let mut one = vec![0.0; nominal.nv()];
    /// k1.aba_hybrid_with_forces_into(&q1, &v, &tau, None, Locks::NONE, &mut one)?;
    /// assert!(ddq.iter().zip(&one).all(|(l, x)| l.lane(1).to_bits() == x.to_bits()));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn gather(runs: [&UnrolledAba; N]) -> Option<Self> {
        let first = runs.first()?;
        let same_shape = runs.iter().all(|r| {
            r.nq == first.nq
                && r.nv == first.nv
                && r.gimbal == first.gimbal
                && r.gimbal_angle == first.gimbal_angle
                && r.gimbal_dof == first.gimbal_dof
                && r.chain_bodies == first.chain_bodies
                && r.n_bodies == first.n_bodies
                && r.gimbal_hinges == first.gimbal_hinges
                && r.rotor_hinges == first.rotor_hinges
                && r.serial_hinges == first.serial_hinges
                && r.n_hinges == first.n_hinges
                && r.rotors.len() == first.rotors.len()
                && r.rotors.iter().zip(&first.rotors).all(|(a, b)| {
                    (a.dof, a.body, a.coord, a.angle, a.rot0.is_some())
                        == (b.dof, b.body, b.coord, b.angle, b.rot0.is_some())
                })
                && r.serial.len() == first.serial.len()
                && r.serial.iter().zip(&first.serial).all(|(a, b)| {
                    (a.axis, a.angle, a.dof, a.body, a.at == Vec3::zeros())
                        == (b.axis, b.angle, b.dof, b.body, b.at == Vec3::zeros())
                })
        });
        if !same_shape {
            return None;
        }
        let scalar = |f: &dyn Fn(&UnrolledAba) -> f64| F64x(std::array::from_fn(|k| f(runs[k])));
        let vector = |f: &dyn Fn(&UnrolledAba) -> &Vec3| {
            Vector3::from_fn(|i, _| F64x(std::array::from_fn(|k| f(runs[k])[i])))
        };
        let matrix = |f: &dyn Fn(&UnrolledAba) -> &Mat3| {
            Matrix3::from_fn(|i, j| F64x(std::array::from_fn(|k| f(runs[k])[(i, j)])))
        };
        let rigid = |f: &dyn Fn(&UnrolledAba) -> &RigidInertia| RigidInertia {
            mass: scalar(&|r| f(r).mass),
            h: vector(&|r| &f(r).h),
            inertia: matrix(&|r| &f(r).inertia),
        };
        let articulated = |f: &dyn Fn(&UnrolledAba) -> &ArticulatedInertia| ArticulatedInertia {
            a: matrix(&|r| &f(r).a),
            b: matrix(&|r| &f(r).b),
            c: matrix(&|r| &f(r).c),
        };
        let rotors = (0..first.rotors.len())
            .map(|i| {
                let r0 = &first.rotors[i];
                Rotor {
                    axis: vector(&|r| &r.rotors[i].axis),
                    j_axis: vector(&|r| &r.rotors[i].j_axis),
                    inv_j: scalar(&|r| r.rotors[i].inv_j),
                    dof: r0.dof,
                    body: r0.body,
                    hinge_axis: vector(&|r| &r.rotors[i].hinge_axis),
                    rot0: r0
                        .rot0
                        .map(|_| matrix(&|r| r.rotors[i].rot0.as_ref().expect("same shape"))),
                    at: vector(&|r| &r.rotors[i].at),
                    child_at: vector(&|r| &r.rotors[i].child_at),
                    s: Motion::new(
                        vector(&|r| &r.rotors[i].s.ang),
                        vector(&|r| &r.rotors[i].s.lin),
                    ),
                    coord: r0.coord,
                    angle: r0.angle,
                }
            })
            .collect();
        let serial = (0..first.serial.len())
            .map(|j| {
                let s0 = &first.serial[j];
                Serial {
                    axis: s0.axis,
                    at: vector(&|r| &r.serial[j].at),
                    inertia: rigid(&|r| &r.serial[j].inertia),
                    start: articulated(&|r| &r.serial[j].start),
                    origin: vector(&|r| &r.serial[j].origin),
                    angle: s0.angle,
                    dof: s0.dof,
                    body: s0.body,
                }
            })
            .collect();
        Some(Self {
            nq: first.nq,
            nv: first.nv,
            base_inertia: rigid(&|r| &r.base_inertia),
            base_start: articulated(&|r| &r.base_start),
            rotors,
            gimbal: first.gimbal,
            gimbal_angle: first.gimbal_angle,
            gimbal_dof: first.gimbal_dof,
            point: vector(&|r| &r.point),
            tip_inertia: rigid(&|r| &r.tip_inertia),
            tip_start: articulated(&|r| &r.tip_start),
            tip_origin: vector(&|r| &r.tip_origin),
            serial,
            chain_bodies: first.chain_bodies,
            n_bodies: first.n_bodies,
            gimbal_hinges: first.gimbal_hinges,
            rotor_hinges: first.rotor_hinges.clone(),
            serial_hinges: first.serial_hinges.clone(),
            n_hinges: first.n_hinges,
            at_most: Instructions::Avx512,
            names: first.names.clone(),
        })
    }
}

/// The engine's interface: a [`satsim_tree::ForwardDynamics`] with this kernel attached
/// gives it every call whose lock mask [`UnrolledAba::locks`] takes (nothing locked, locked
/// rotors and serial hinges; not a locked gimbal hinge), and solves it exactly as
/// [`UnrolledAba::aba_hybrid_with_forces_into`] does: the same numbers, bit for bit.
///
/// ```
/// use satsim_satellite::kernel::UnrolledAba;
/// use satsim_tree::{Data, ForwardDynamics, Input, read_model, samples::push_wheels};
/// let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
/// let path = dir.join("../../examples/satellite.toml");
/// let mut builder = read_model(&path)?.to_builder();
/// push_wheels(&mut builder, "bus");
/// let model = builder.build()?;
/// let kernel = UnrolledAba::new(&model).expect("the preprint's layout");
/// let fd = ForwardDynamics::new(&model).with_kernel(Box::new(kernel));
/// let mut data = Data::new(&model);
/// let mut q = model.neutral();
/// q[7..12].copy_from_slice(&[0.1, 0.2, 0.3, 1.2, -1.0]);
/// let (v, tau) = (vec![0.01; model.nv()], vec![0.5; model.nv()]);
/// let mut ddq = vec![0.0; model.nv()];
/// // A wheel held: the kernel; a gimbal hinge held: the generic hybrid ABA.
/// let mut locked = vec![false; model.n_hinges()];
/// locked[5] = true;
/// assert!(fd.uses_kernel(Some(&locked)));
/// fd.solve(&model, &mut data, Input::new(&q, &v, &tau).locked(Some(&locked)), &mut ddq)?;
/// assert_eq!(ddq[6 + 5], 0.0);
/// locked[0] = true;
/// assert!(!fd.uses_kernel(Some(&locked)));
/// fd.solve(&model, &mut data, Input::new(&q, &v, &tau).locked(Some(&locked)), &mut ddq)?;
/// assert_eq!((ddq[6], ddq[6 + 5]), (0.0, 0.0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
impl Kernel for UnrolledAba {
    fn accepts(&self, locked: Option<&[bool]>) -> bool {
        locked.is_none_or(|mask| self.locks(mask).is_some())
    }

    fn try_solve(&self, input: &Input<'_>, ddq: &mut [f64]) -> Option<Result<(), DynamicsError>> {
        let locks = match input.locked {
            None => Locks::NONE,
            Some(mask) => self.locks(mask)?,
        };
        let Input {
            q, v, tau, fext, ..
        } = *input;
        Some(self.aba_hybrid_with_forces_into(q, v, tau, fext, locks, ddq))
    }

    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

/// Whether every component of `f` is zero in every lane (±0). Subtracting a zero wrench
/// moved to another frame (±0 in each component) changes no bit of a nonzero sum, and at
/// most the sign of a zero one (`−0 − −0 = +0`).
#[inline]
fn is_zero<T: Real>(f: &Force<T>) -> bool {
    f.ang
        .iter()
        .chain(f.lin.iter())
        .all(|x| x.all(|x| x == 0.0))
}

/// A wrench `f` about a body's origin moved to its hinge point, the origin lying at `o` from
/// the point (same axes): `[n + o × f; f]`.
#[inline(always)]
fn at_hinge<T: Real>(f: &Force<T>, o: &Vector3<T>) -> Force<T> {
    Force::new(f.ang + mat3::cross(o, &f.lin), f.lin)
}

#[cfg(test)]
mod tests;
