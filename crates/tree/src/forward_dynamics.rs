//! [`ForwardDynamics`]: the engine's one forward-dynamics entry (Pinocchio's
//! `forwardDynamics`), made once per model, solving each call by the algorithm that fits it.
//!
//! The accelerations `q̈` produced by generalised forces `τ` and external body forces, with
//! some hinges possibly locked (hybrid dynamics), are computed by one of several algorithms:
//! the articulated-body algorithm ([`crate::aba`], O(n), the default) in its plain, hybrid
//! and after-kinematics forms; the mass-matrix path ([`crate::cholesky`], CRBA + RNEA +
//! Cholesky); or a [`Kernel`], ABA specialised for one layout outside this crate. A caller
//! makes one [`ForwardDynamics`] for its model, choosing the method and attaching a kernel
//! once, then describes each call by an [`Input`]; [`ForwardDynamics::solve`] picks the form:
//!
//! | the call | `Method::Aba` runs | bit for bit |
//! |---|---|---|
//! | a kernel is attached and [`Kernel::accepts`] the lock mask | the kernel | the kernel's own result |
//! | nothing locked, transforms not current | [`crate::aba::aba`] | yes |
//! | nothing locked, `data.xup` current | [`crate::aba::aba_with_kinematics`] | yes |
//! | hinges locked, transforms not current | [`crate::aba::aba_hybrid`] | yes |
//! | hinges locked, `data.xup` current | [`crate::aba::aba_hybrid_with_kinematics`] | yes |
//!
//! With [`Method::CrbaCholesky`] the generic forms are [`crate::cholesky::crba_cholesky`]
//! (nothing locked) and its hybrid form (locked hinges: the principal block of the free
//! coordinates); it computes its own transforms (a current `data.xup` changes nothing).
//!
//! Each generic form runs the code of the function in the table with the same arguments
//! (ABA's instance for the model's gyrostats and chains, which [`crate::aba::aba`] picks
//! per call, is picked here once, from the same model), so the accelerations are bit for
//! bit those that function returns (tested below on random trees with gyrostats, chains,
//! external forces and locks, and at a gimbal lock: the same errors); they are then copied
//! into the caller's `ddq` (as a caller of those functions copied them out of `data.ddq`). A kernel
//! writes straight into `ddq`: a caller whose state holds the velocities as one run gets `q̈`
//! into its derivative with no copy. Its accelerations equal ABA's to round-off (a kernel's
//! contract, tested by the kernel), not bit for bit: a kernel orders the same arithmetic
//! differently.
//!
//! The per-call path allocates nothing (`tests/it/no_alloc.rs`).
//!
//! ```
//! use satsim_tree::{BaseKind, Data, ForwardDynamics, Input, samples::chain};
//! use satsim_tree::aba::{aba, aba_hybrid};
//! let model = chain(4, BaseKind::Free);
//! let fd = ForwardDynamics::new(&model);
//! let mut data = Data::new(&model);
//! let (q, v, tau) = (model.neutral(), vec![0.1; model.nv()], vec![0.2; model.nv()]);
//! let mut ddq = vec![0.0; model.nv()];
//! fd.solve(&model, &mut data, Input::new(&q, &v, &tau), &mut ddq)?;
//! assert_eq!(ddq.as_slice(), aba(&model, &mut data, &q, &v, &tau, None)?.as_slice());
//! // The first hinge locked: hybrid dynamics.
//! let locked = [true, false, false];
//! fd.solve(&model, &mut data, Input::new(&q, &v, &tau).locked(Some(&locked)), &mut ddq)?;
//! assert_eq!(ddq[6], 0.0);
//! let old = aba_hybrid(&model, &mut data, &q, &v, &tau, None, &locked)?;
//! assert_eq!(ddq.as_slice(), old.as_slice());
//! # Ok::<(), satsim_tree::DynamicsError>(())
//! ```

use crate::aba::{self, Instance};
use crate::cholesky;
use crate::data::Data;
use crate::error::DynamicsError;
use crate::kernel_parts::check_len;
use crate::model::Model;
use crate::spatial::Force;
use std::fmt;

/// The generic algorithm behind a [`ForwardDynamics`] (where no kernel takes the call).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// The articulated-body algorithm ([`crate::aba`]): O(n), the default; its gyrostat and
    /// chain forms, hybrid dynamics for locked hinges, the reuse of current transforms.
    #[default]
    Aba,
    /// Through the mass matrix ([`crate::cholesky`]): `M q̈ = τ − C` with `M` from CRBA, `C`
    /// from RNEA, a Cholesky solve (O(n³)); the second, independent path beside ABA.
    CrbaCholesky,
}

/// One forward-dynamics call: the state, the forces, the locks, and whether `data.xup`
/// already holds this state's hinge transforms. Build it by [`Input::new`] and the
/// chained setters, or as a struct.
///
/// Conventions ([`crate::model`], [`crate::rnea()`]): `q` (length `nq`), `v` and `tau`
/// (length `nv`), `fext` one wrench per body in body coordinates about the body's origin,
/// `locked` one entry per hinge in the order of addition.
#[derive(Clone, Copy, Debug)]
pub struct Input<'a> {
    /// Positions, `nq`.
    pub q: &'a [f64],
    /// Velocities, `nv`.
    pub v: &'a [f64],
    /// Generalised forces, `nv` (a locked hinge's is ignored).
    pub tau: &'a [f64],
    /// External body forces (`None`: none).
    pub fext: Option<&'a [Force]>,
    /// Locked hinges, hybrid dynamics (`None`: nothing locked; `Some` runs the hybrid form
    /// even where no entry is `true`, as calling [`crate::aba::aba_hybrid`] did).
    pub locked: Option<&'a [bool]>,
    /// Whether `data.xup` holds the hinge transforms of this `q` (forward kinematics, or an
    /// earlier solve, ran on it): ABA then reuses them, with bit for bit the same result.
    /// Stale transforms give wrong accelerations silently: leave it `false` when unsure.
    pub xup_current: bool,
}

impl<'a> Input<'a> {
    /// A call at `q`, `v` with generalised forces `tau`: no external forces, nothing
    /// locked, transforms not current.
    pub fn new(q: &'a [f64], v: &'a [f64], tau: &'a [f64]) -> Self {
        Self {
            q,
            v,
            tau,
            fext: None,
            locked: None,
            xup_current: false,
        }
    }

    /// With external body forces `fext` (`None`: none).
    pub fn fext(mut self, fext: Option<&'a [Force]>) -> Self {
        self.fext = fext;
        self
    }

    /// With the hinges of `locked` locked (`None`: nothing locked).
    pub fn locked(mut self, locked: Option<&'a [bool]>) -> Self {
        self.locked = locked;
        self
    }

    /// Whether `data.xup` holds this `q`'s transforms (see [`Input::xup_current`]).
    pub fn xup_current(mut self, current: bool) -> Self {
        self.xup_current = current;
        self
    }
}

/// A specialised forward-dynamics kernel: ABA written out for one model's layout, its
/// constants folded in when it is made (e.g. `satsim-satellite`'s unrolled ABA for the
/// preprint satellite). Attached by [`ForwardDynamics::with_kernel`], it takes every call
/// whose lock mask it [`accepts`](Kernel::accepts); the generic algorithm takes the others.
///
/// A kernel is made for one model and must give that model's accelerations: [`crate::aba::aba`]'s
/// to round-off, with its errors (the same [`DynamicsError::SingularHinge`] at the same
/// hinge, dimension errors for wrong lengths, `ddq` included). It holds its own constants
/// and works on the stack: it reads no [`Data`] and writes only `ddq`, so a caller's
/// kinematics in `data` stays as it was. [`crate::kernel_parts`] holds the engine's pieces a
/// kernel needs to be the same algorithm.
pub trait Kernel: fmt::Debug + Send + Sync {
    /// Whether the kernel takes calls with these locked hinges (`None`: nothing locked);
    /// [`Kernel::try_solve`] declines exactly the masks this refuses.
    fn accepts(&self, locked: Option<&[bool]>) -> bool;

    /// `q̈` for `input` into `ddq` (length `nv`), or `None` where the kernel does not take
    /// `input.locked` (then `ddq` is untouched and the generic algorithm runs).
    /// `input.xup_current` may be ignored (a kernel computes its transforms).
    fn try_solve(&self, input: &Input<'_>, ddq: &mut [f64]) -> Option<Result<(), DynamicsError>>;

    /// The kernel as its own type, for a caller that knows more of it than this trait says
    /// (several runs' kernels gathered into SIMD lanes, in `satsim-spacecraft`); `None` by
    /// default.
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        None
    }
}

/// The forward dynamics of one model: the generic algorithm ([`Method`]), its instance for
/// the model's forms (gyrostats, chains: chosen here, once) and an optional [`Kernel`],
/// behind one [`ForwardDynamics::solve`]. See the module documentation for which form a
/// call takes and why the results are bit for bit those of the algorithm it calls.
///
/// ```
/// use satsim_tree::{BaseKind, Data, ForwardDynamics, Input, Method, samples::random_tree};
/// let model = random_tree(6, BaseKind::Free, false, 3);
/// let mut data = Data::new(&model);
/// let (q, v, tau) = (model.neutral(), vec![0.1; model.nv()], vec![0.2; model.nv()]);
/// let (mut by_aba, mut by_crba) = (vec![0.0; model.nv()], vec![0.0; model.nv()]);
/// let input = Input::new(&q, &v, &tau);
/// ForwardDynamics::new(&model).solve(&model, &mut data, input, &mut by_aba)?;
/// ForwardDynamics::new(&model)
///     .with_method(Method::CrbaCholesky)
///     .solve(&model, &mut data, input, &mut by_crba)?;
/// for (a, b) in by_aba.iter().zip(&by_crba) {
///     assert!((a - b).abs() < 1e-10 * a.abs().max(1.0));
/// }
/// # Ok::<(), satsim_tree::DynamicsError>(())
/// ```
#[derive(Debug)]
pub struct ForwardDynamics {
    method: Method,
    /// ABA's instance for the model's gyrostats and chains.
    instance: Instance,
    kernel: Option<Box<dyn Kernel>>,
}

impl ForwardDynamics {
    /// Forward dynamics for `model` by ABA, with no kernel.
    pub fn new(model: &Model) -> Self {
        Self {
            method: Method::Aba,
            instance: Instance::of(model),
            kernel: None,
        }
    }

    /// The generic algorithm `method` (ABA by default).
    pub fn with_method(mut self, method: Method) -> Self {
        self.method = method;
        self
    }

    /// With `kernel` (made for this model) taking the calls it accepts, whatever the method.
    pub fn with_kernel(mut self, kernel: Box<dyn Kernel>) -> Self {
        self.kernel = Some(kernel);
        self
    }

    /// With `kernel` where there is one (`None`: the generic algorithm only); e.g.
    /// `.with_optional_kernel(MyKernel::new(&model).map(|k| Box::new(k) as _))`.
    pub fn with_optional_kernel(mut self, kernel: Option<Box<dyn Kernel>>) -> Self {
        self.kernel = kernel;
        self
    }

    /// The generic algorithm.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The attached kernel, if any.
    pub fn kernel(&self) -> Option<&dyn Kernel> {
        self.kernel.as_deref()
    }

    /// Whether a call with these locked hinges goes to the kernel.
    pub fn uses_kernel(&self, locked: Option<&[bool]>) -> bool {
        self.kernel.as_ref().is_some_and(|k| k.accepts(locked))
    }

    /// The accelerations `q̈` for `input` into `ddq` (length `nv`; for a free base its first
    /// six entries are the body-frame derivatives of `[ω; v]`, then the hinges in their order
    /// of addition). `model` and `data` are the model this was made for and its workspace;
    /// the generic algorithms use `data` as [`crate::aba::aba`] does (and leave the same
    /// accelerations in `data.ddq`), a kernel does not touch it. Fails as the algorithm
    /// called fails: a dimension error, [`DynamicsError::SingularHinge`],
    /// [`DynamicsError::SingularBase`], or (by the mass matrix)
    /// [`DynamicsError::NotPositiveDefinite`].
    pub fn solve(
        &self,
        model: &Model,
        data: &mut Data,
        input: Input<'_>,
        ddq: &mut [f64],
    ) -> Result<(), DynamicsError> {
        if let Some(solved) = self.kernel.as_ref().and_then(|k| k.try_solve(&input, ddq)) {
            return solved;
        }
        check_len("ddq", ddq.len(), model.nv())?;
        let Input {
            q,
            v,
            tau,
            fext,
            locked,
            xup_current,
        } = input;
        let out = match (self.method, locked) {
            (Method::Aba, None) => {
                aba::plain_or_chains(self.instance, model, data, q, v, tau, fext, xup_current)?
            }
            (Method::Aba, Some(l)) => aba::hybrid(model, data, q, v, tau, fext, l, xup_current)?,
            (Method::CrbaCholesky, l) => cholesky::solve(model, data, q, v, tau, fext, l)?,
        };
        ddq.copy_from_slice(out.as_slice());
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::aba::{aba, aba_hybrid, aba_hybrid_with_kinematics, aba_with_kinematics};
    use crate::cholesky::crba_cholesky;
    use crate::kinematics::forward_kinematics;
    use crate::model::BaseKind;
    use crate::samples::{SplitMix, random_q, random_tree_with_rotors};

    /// `q`, `v`, `tau`, `fext`, `locked`.
    type RandomInput = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<Force>, Vec<bool>);

    /// A random state of `model`: positions, rates, torques, a wrench on every body, a lock
    /// mask (about a third locked).
    fn random_input(model: &Model, rng: &mut SplitMix) -> RandomInput {
        let q = random_q(model, rng, 3.0);
        let v = (0..model.nv()).map(|_| rng.range(-2.0, 2.0)).collect();
        let tau = (0..model.nv()).map(|_| rng.range(-2.0, 2.0)).collect();
        let fext = (0..model.n_bodies())
            .map(|_| Force::new(rng.vec3(1.0), rng.vec3(1.0)))
            .collect();
        let locked = (0..model.n_hinges())
            .map(|_| rng.next_f64() < 0.3)
            .collect();
        (q, v, tau, fext, locked)
    }

    /// Bit for bit: the same accelerations, or the same error.
    fn same(
        got: Result<Vec<f64>, DynamicsError>,
        old: Result<Vec<f64>, DynamicsError>,
        what: &str,
    ) {
        match (got, old) {
            (Ok(a), Ok(b)) => {
                let (a, b): (Vec<u64>, Vec<u64>) = (
                    a.iter().map(|x| x.to_bits()).collect(),
                    b.iter().map(|x| x.to_bits()).collect(),
                );
                assert_eq!(a, b, "{what}");
            }
            (Err(x), Err(y)) => assert_eq!(x, y, "{what}"),
            (a, b) => panic!("{what}: ForwardDynamics {a:?}, the old path {b:?}"),
        }
    }

    /// `ForwardDynamics::solve` gives bit for bit the accelerations (or the error) of each
    /// function it stands for: plain, after kinematics, hybrid, hybrid after kinematics, and
    /// by the mass matrix, with and without external forces, on random trees with massless
    /// links (chains), gyrostat rotors, free and fixed roots; `data.ddq` is left as the old
    /// function left it.
    #[test]
    fn solve_is_bit_for_bit_each_old_path() {
        let (mut solved, mut refused) = (0, 0);
        for seed in 0..300u64 {
            let base = if seed % 3 == 0 {
                BaseKind::Fixed
            } else {
                BaseKind::Free
            };
            let n = 2 + (seed % 16) as usize;
            let model = random_tree_with_rotors(n, base, seed % 2 == 0, (seed % 4) as usize, seed);
            let mut rng = SplitMix(seed ^ 0xfd);
            let (q, v, tau, fext, locked) = random_input(&model, &mut rng);
            let aba_fd = ForwardDynamics::new(&model);
            let crba_fd = ForwardDynamics::new(&model).with_method(Method::CrbaCholesky);
            let (mut data, mut old) = (Data::new(&model), Data::new(&model));
            let mut ddq = vec![f64::NAN; model.nv()];
            for f in [None, Some(fext.as_slice())] {
                for (l, xup) in [
                    (None, false),
                    (None, true),
                    (Some(&locked), false),
                    (Some(&locked), true),
                ] {
                    if xup {
                        forward_kinematics(&model, &mut data, &q, &v).unwrap();
                        forward_kinematics(&model, &mut old, &q, &v).unwrap();
                    }
                    let input = Input::new(&q, &v, &tau)
                        .fext(f)
                        .locked(l.map(Vec::as_slice))
                        .xup_current(xup);
                    let got = aba_fd
                        .solve(&model, &mut data, input, &mut ddq)
                        .map(|()| ddq.clone());
                    let was = match (l, xup) {
                        (None, false) => aba(&model, &mut old, &q, &v, &tau, f),
                        (None, true) => aba_with_kinematics(&model, &mut old, &q, &v, &tau, f),
                        (Some(l), false) => aba_hybrid(&model, &mut old, &q, &v, &tau, f, l),
                        (Some(l), true) => {
                            aba_hybrid_with_kinematics(&model, &mut old, &q, &v, &tau, f, l)
                        }
                    }
                    .map(|a| a.as_slice().to_vec());
                    let what = format!("seed {seed}: locked {}, xup {xup}", l.is_some());
                    match &got {
                        Ok(_) => solved += 1,
                        Err(_) => refused += 1,
                    }
                    if got.is_ok() {
                        assert_eq!(data.ddq, old.ddq, "{what}: data.ddq");
                    }
                    same(got, was, &what);
                }
                // By the mass matrix (no hybrid function before: only the unlocked call).
                let got = crba_fd
                    .solve(
                        &model,
                        &mut data,
                        Input::new(&q, &v, &tau).fext(f),
                        &mut ddq,
                    )
                    .map(|()| ddq.clone());
                let was =
                    crba_cholesky(&model, &mut old, &q, &v, &tau, f).map(|a| a.as_slice().to_vec());
                same(got, was, &format!("seed {seed}: crba_cholesky"));
            }
        }
        assert!(solved > 1500, "{solved} solved, {refused} refused");
    }

    /// At a gimbal lock (three hinges through massless links, the middle one at 90°: the
    /// outer axes parallel) the entry fails as each old path fails, with the same error.
    #[test]
    fn a_gimbal_lock_fails_as_the_old_paths() {
        use crate::model::{Body, Hinge, ModelBuilder};
        use crate::spatial::{Mat3, Vec3};
        let model = ModelBuilder::new(BaseKind::Free)
            .body(Body::new("bus", 500.0, Mat3::identity() * 40.0))
            .body(Body::massless("l1"))
            .body(Body::massless("l2"))
            .body(Body::new("panel", 20.0, Mat3::identity() * 2.0))
            .hinge(Hinge::revolute("h1", "bus", "l1", Vec3::z()).at(Vec3::y()))
            .hinge(Hinge::revolute("h2", "l1", "l2", Vec3::x()))
            .hinge(Hinge::revolute("h3", "l2", "panel", Vec3::y()).child_at(-Vec3::y()))
            .build()
            .unwrap();
        let mut q = model.neutral();
        q[8] = std::f64::consts::FRAC_PI_2;
        let (v, tau) = (vec![0.1; model.nv()], vec![0.2; model.nv()]);
        let (mut data, mut old) = (Data::new(&model), Data::new(&model));
        let mut ddq = vec![0.0; model.nv()];
        let fd = ForwardDynamics::new(&model);
        let got = fd.solve(&model, &mut data, Input::new(&q, &v, &tau), &mut ddq);
        let was = aba(&model, &mut old, &q, &v, &tau, None).map(|_| ());
        assert!(
            matches!(&got, Err(DynamicsError::SingularHinge { .. })),
            "{got:?}"
        );
        assert_eq!(got, was);
        // Hybrid, h1 locked: h2 and h3 still meet at the lock.
        let locked = [true, false, false];
        let input = Input::new(&q, &v, &tau).locked(Some(&locked));
        let got = fd.solve(&model, &mut data, input, &mut ddq);
        let was = aba_hybrid(&model, &mut old, &q, &v, &tau, None, &locked).map(|_| ());
        assert_eq!(got, was);
        // By the mass matrix: not positive definite, as `crba_cholesky`.
        let crba_fd = ForwardDynamics::new(&model).with_method(Method::CrbaCholesky);
        let got = crba_fd.solve(&model, &mut data, Input::new(&q, &v, &tau), &mut ddq);
        let was = crba_cholesky(&model, &mut old, &q, &v, &tau, None).map(|_| ());
        assert!(got.is_err());
        assert_eq!(got, was);
    }

    /// Hybrid dynamics by the mass matrix equals hybrid ABA to round-off (κ(M) ε): the
    /// locked hinges do not move, the free ones solve the principal block.
    #[test]
    fn crba_cholesky_hybrid_equals_aba_hybrid() {
        let mut compared = 0;
        for seed in 0..200u64 {
            let base = if seed % 3 == 0 {
                BaseKind::Fixed
            } else {
                BaseKind::Free
            };
            // Past FAER_MIN_DOF sometimes: faer's path too.
            let n = if seed % 10 == 0 {
                50
            } else {
                2 + (seed % 14) as usize
            };
            let model = random_tree_with_rotors(n, base, false, (seed % 3) as usize, seed);
            let mut rng = SplitMix(seed ^ 0x4b);
            let (q, v, tau, fext, locked) = random_input(&model, &mut rng);
            let mut data = Data::new(&model);
            let crba_fd = ForwardDynamics::new(&model).with_method(Method::CrbaCholesky);
            let mut a = vec![0.0; model.nv()];
            let input = Input::new(&q, &v, &tau)
                .fext(Some(&fext))
                .locked(Some(&locked));
            let Ok(b) = aba_hybrid(&model, &mut data, &q, &v, &tau, Some(&fext), &locked).cloned()
            else {
                continue;
            };
            crba_fd.solve(&model, &mut data, input, &mut a).unwrap();
            let m = crate::crba(&model, &mut data, &q).unwrap();
            let eig = m.clone().symmetric_eigenvalues();
            let kappa_eps = eig.max() / eig.min() * f64::EPSILON;
            let scale = b.amax().max(1.0);
            for (k, (x, y)) in a.iter().zip(b.iter()).enumerate() {
                assert!(
                    (x - y).abs() <= 1e-12_f64.max(100.0 * kappa_eps) * scale,
                    "seed {seed} coordinate {k}: {x:e} vs {y:e}"
                );
            }
            for (h, &l) in locked.iter().enumerate() {
                if l {
                    assert_eq!(a[model.base_nv() + h], 0.0);
                }
            }
            compared += 1;
        }
        assert!(compared > 150, "only {compared}");
    }

    /// A kernel that takes only unlocked calls and writes a marker: the dispatch goes to it
    /// exactly where it accepts, to the generic algorithm elsewhere.
    #[derive(Debug)]
    struct Marker;

    impl Kernel for Marker {
        fn accepts(&self, locked: Option<&[bool]>) -> bool {
            locked.is_none()
        }
        fn try_solve(
            &self,
            input: &Input<'_>,
            ddq: &mut [f64],
        ) -> Option<Result<(), DynamicsError>> {
            if !self.accepts(input.locked) {
                return None;
            }
            ddq.fill(42.0);
            Some(Ok(()))
        }
    }

    #[test]
    fn a_kernel_takes_the_calls_it_accepts() {
        let model = random_tree_with_rotors(5, BaseKind::Free, false, 1, 7);
        let fd = ForwardDynamics::new(&model).with_kernel(Box::new(Marker));
        assert!(fd.kernel().is_some() && fd.method() == Method::Aba);
        let mut data = Data::new(&model);
        let (q, v, tau) = (
            model.neutral(),
            vec![0.1; model.nv()],
            vec![0.2; model.nv()],
        );
        let locked = vec![false; model.n_hinges()];
        let mut ddq = vec![0.0; model.nv()];
        assert!(fd.uses_kernel(None) && !fd.uses_kernel(Some(&locked)));
        fd.solve(&model, &mut data, Input::new(&q, &v, &tau), &mut ddq)
            .unwrap();
        assert!(ddq.iter().all(|&x| x == 42.0));
        let input = Input::new(&q, &v, &tau).locked(Some(&locked));
        fd.solve(&model, &mut data, input, &mut ddq).unwrap();
        let hybrid = aba_hybrid(&model, &mut data, &q, &v, &tau, None, &locked).unwrap();
        assert_eq!(ddq.as_slice(), hybrid.as_slice());
        let generic = ForwardDynamics::new(&model).with_optional_kernel(None);
        assert!(generic.kernel().is_none() && !generic.uses_kernel(None));
    }

    #[test]
    fn wrong_lengths_are_refused() {
        let model = random_tree_with_rotors(4, BaseKind::Free, false, 0, 2);
        let fd = ForwardDynamics::new(&model);
        let mut data = Data::new(&model);
        let (q, v) = (model.neutral(), vec![0.0; model.nv()]);
        let mut ddq = vec![0.0; model.nv()];
        let e = fd
            .solve(&model, &mut data, Input::new(&q, &v, &v), &mut ddq[1..])
            .unwrap_err();
        assert!(
            matches!(e, DynamicsError::Dimension { what: "ddq", .. }),
            "{e}"
        );
        let short = vec![false; model.n_hinges() - 1];
        for method in [Method::Aba, Method::CrbaCholesky] {
            let input = Input::new(&q, &v, &v).locked(Some(&short));
            let e = ForwardDynamics::new(&model)
                .with_method(method)
                .solve(&model, &mut data, input, &mut ddq)
                .unwrap_err();
            assert!(
                matches!(e, DynamicsError::Dimension { what: "locked", .. }),
                "{e}"
            );
        }
        let e = fd
            .solve(&model, &mut data, Input::new(&q, &v, &v[1..]), &mut ddq)
            .unwrap_err();
        assert!(
            matches!(e, DynamicsError::Dimension { what: "tau", .. }),
            "{e}"
        );
    }
}
