//! A linear force field over a flexible body's deformed mass: the gravity gradient's tidal
//! field `f(x) = T x` per unit mass (`T = μ/r³ (3 E Eᵀ − 1)`, `x` from the system's centre
//! of mass), distributed over the body rather than lumped at its frame.
//!
//! With `x = ρ + p` for a point `p` of body `i` (its frame's origin at `ρ` from the field's
//! centre, both in body axes), the field's potential over the body is
//!
//! `V = −½ m ρᵀTρ − ρᵀT h − ½ tr(T J)`, `J = ∫ p pᵀ dm = ½ tr(I) 1 − I`,
//!
//! with `m`, `h` (first moment) and `I` (rotational inertia about the origin) the body's
//! inertia at its deformation, [`FlexModel::deformed_inertia`]: what the dynamics uses. Its
//! wrench on the frame (about the origin, body axes) is `F = T (m ρ + h)`,
//! `N = h × Tρ − vec(I T)` (`vec(M) = [M₂₃ − M₃₂, M₃₁ − M₁₃, M₁₂ − M₂₁]`; `3k E × I E` for
//! the tidal `T`), and its generalised force on mode `k` is `Qₖ = −∂V/∂ηₖ`: with a beam's
//! `stiffening` (`h(η) = h₀ + Σ b S₁ₖ ηₖ − ½ (ηᵀJ₀η) a`, `I(η) = I₀ + Σ Iₖ ηₖ − G(η)`,
//! [`super::Stiffening`]),
//!
//! `Qₖ = ρᵀT (b S₁ₖ − (J₀η)ₖ a) + c(Iₖ) − 2 (J₀η)ₖ c(A₀) − 2 (J₁η)ₖ c(A₁) + 2 ηₖ c(A₂)`,
//! `c(A) = ¼ tr T tr A − ½ tr(T A)`,
//!
//! which for the tidal field is `Qₖ = bᵀT (ρ + r₀) S₁ₖ + bᵀT a S₂ₖ + (bᵀT b) ηₖ
//! − [(aᵀT (ρ + r₀)) J₀ + (aᵀT a) J₁] η`: the lateral load over the length, the deflected
//! mass's own, and the geometric stiffness of the field's axial load (a beam hanging along
//! the local vertical is in tension, `N(x) = 2k ρA ∫ₓᴸ (r₀ + ξ) dξ` from a root at `r₀`).
//! Without `stiffening` the model keeps the undeformed inertia, so `V` does not depend on
//! `η` and the modes feel no field (the lumped load only), consistently.

use super::FlexModel;
use crate::spatial::{Force, Mat3, RigidInertia, Vec3};

/// What a linear field does to one body ([`FlexModel::linear_field`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldLoad {
    /// The field's wrench on the body's frame (about its origin, body axes; N m, N).
    pub wrench: Force,
    /// The field's potential over the body (J).
    pub potential: f64,
}

/// `vec(I T) = [(IT)₂₃ − (IT)₃₂, (IT)₃₁ − (IT)₁₃, (IT)₁₂ − (IT)₂₁]` (`∫ p × T p dm` is
/// `vec(J T)`, and `vec(J T) = −vec(I T)` for the symmetric `T`): the six off-diagonal
/// entries of the product alone, 18 products where the whole product takes 27.
#[inline(always)]
fn vec_of_product(i: &Mat3, t: &Mat3) -> Vec3 {
    let e =
        |a: usize, b: usize| i[(a, 0)] * t[(0, b)] + i[(a, 1)] * t[(1, b)] + i[(a, 2)] * t[(2, b)];
    Vec3::new(e(1, 2) - e(2, 1), e(2, 0) - e(0, 2), e(0, 1) - e(1, 0))
}

/// The weights `w` of `c(A) = ¼ tr T tr A − ½ tr(T A)` as a dot product with the symmetric
/// `T`'s six entries `[T₁₁, T₂₂, T₃₃, T₁₂, T₁₃, T₂₃]` ([`packed`]): `c(A)` is linear in `T`,
/// and only `A`'s symmetric part meets a symmetric `T`. Made once a model
/// ([`FieldWeights`]), so that the field's generalised forces take six products a term
/// where `tr A` and `T ∘ A` took twelve.
pub(crate) fn weights(a: &Mat3) -> [f64; 6] {
    let q = 0.25 * a.trace();
    [
        q - 0.5 * a[(0, 0)],
        q - 0.5 * a[(1, 1)],
        q - 0.5 * a[(2, 2)],
        -0.5 * (a[(0, 1)] + a[(1, 0)]),
        -0.5 * (a[(0, 2)] + a[(2, 0)]),
        -0.5 * (a[(1, 2)] + a[(2, 1)]),
    ]
}

/// The symmetric `t`'s six entries, in the order of [`weights`].
#[inline(always)]
fn packed(t: &Mat3) -> [f64; 6] {
    [
        t[(0, 0)],
        t[(1, 1)],
        t[(2, 2)],
        t[(0, 1)],
        t[(0, 2)],
        t[(1, 2)],
    ]
}

#[inline(always)]
fn dot6(a: &[f64; 6], b: &[f64; 6]) -> f64 {
    (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) + (a[3] * b[3] + a[4] * b[4] + a[5] * b[5])
}

/// A stiffened body's [`weights`] of `A₀`, `A₁`, `A₂` and of each mode's first-order
/// inertia change `Iₖ`: what the field's generalised forces read of its
/// [`super::Stiffening`], made with the model.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct FieldWeights {
    a: [[f64; 6]; 3],
    first: Vec<[f64; 6]>,
}

impl FieldWeights {
    pub(crate) fn of(s: &super::Stiffening) -> Self {
        Self {
            a: [weights(&s.a0), weights(&s.a1), weights(&s.a2)],
            first: s.first.iter().map(|f| weights(&f.inertia)).collect(),
        }
    }
}

/// The potential `V = −½ m ρᵀTρ − ρᵀT h − ½ tr(T J)` (`tr(T J) = ½ tr T tr I − tr(T I)`) of
/// the linear field `f(x) = T x` over a body of inertia `inertia` (about its frame's origin,
/// body axes), that origin at `rho` from the field's centre: [`FlexModel::field_potential`]
/// for a caller that has the body's [`FlexModel::deformed_inertia`] already. Always inlined:
/// out of line, the one [`FlexModel::linear_field_on`] makes was computed even where its
/// caller reads only the wrench (the gravity gradient, twice a flexible body a right-hand side).
#[inline(always)]
pub fn potential(inertia: &RigidInertia, t: &Mat3, rho: &Vec3) -> f64 {
    let tj = 0.5 * t.trace() * inertia.inertia.trace() - t.component_mul(&inertia.inertia).sum();
    -0.5 * inertia.mass * rho.dot(&(t * rho)) - rho.dot(&(t * inertia.h)) - 0.5 * tj
}

/// The wrench of the linear field `f(x) = T x` on a body of inertia `inertia` (about its
/// frame's origin, body axes), that origin at `rho` from the field's centre, on its frame:
/// [`FlexModel::linear_field_on`]'s, for a caller that reads only the wrench (an output
/// column).
#[inline(always)]
pub fn field_wrench(inertia: &RigidInertia, t: &Mat3, rho: &Vec3) -> Force {
    wrench_of(inertia, t, rho, &(t * rho))
}

#[inline(always)]
fn wrench_of(inertia: &RigidInertia, t: &Mat3, rho: &Vec3, t_rho: &Vec3) -> Force {
    Force::new(
        inertia.h.cross(t_rho) - vec_of_product(&inertia.inertia, t),
        t * (rho * inertia.mass + inertia.h),
    )
}

impl FlexModel {
    /// The potential `V` of the linear field `f(x) = T x` (per unit mass, `t` symmetric,
    /// body axes, 1/s²) over body `i` at the elastic coordinates `eta` (all of them), its
    /// frame's origin at `rho` (m, body axes) from the field's centre (see the module's
    /// documentation). Linear in `t`: with `Ṫ` it is the field's `∂V/∂t`.
    pub fn field_potential(&self, i: usize, eta: &[f64], t: &Mat3, rho: &Vec3) -> f64 {
        potential(&self.deformed_inertia(i, eta), t, rho)
    }

    /// The linear field `f(x) = T x` (per unit mass, `t` symmetric, body axes, 1/s²) over
    /// body `i`'s deformed mass at the elastic coordinates `eta` (all of them), its frame's
    /// origin at `rho` (m, body axes) from the field's centre: its wrench on the frame and
    /// its potential, and its generalised forces `−∂V/∂ηₖ` added to `elastic` (all the
    /// elastic coordinates; only a beam with `stiffening` has any). See the module's page.
    pub fn linear_field(
        &self,
        i: usize,
        eta: &[f64],
        t: &Mat3,
        rho: &Vec3,
        elastic: &mut [f64],
    ) -> FieldLoad {
        self.linear_field_on(i, &self.deformed_inertia(i, eta), eta, t, rho, elastic)
    }

    /// [`FlexModel::linear_field`] with body `i`'s inertia at `eta` given: what
    /// [`FlexModel::deformed_inertia`] returns, for a caller that has it already (the
    /// gravity gradient, which needs it first for the system's centre of mass). Inlined:
    /// its wrench, returned through the stack, was read back across its stores' halves (a
    /// stalled store forwarding, `perf`).
    #[inline(always)]
    pub fn linear_field_on(
        &self,
        i: usize,
        inertia: &RigidInertia,
        eta: &[f64],
        t: &Mat3,
        rho: &Vec3,
        elastic: &mut [f64],
    ) -> FieldLoad {
        let t_rho = t * rho;
        let wrench = wrench_of(inertia, t, rho, &t_rho);
        let potential = potential(inertia, t, rho);
        if let (Some(s), Some(w)) = (&self.stiffening[i], &self.field_weights[i]) {
            let (at, eta) = (self.offset[i], &eta[self.offset[i]..]);
            let elastic = &mut elastic[at..];
            // An instance for the common mode counts, the loops unrolled (the same sums):
            // with the count a variable, the loops' own bookkeeping took as many
            // instructions as their arithmetic.
            match self.modes[i] {
                1 => modal_forces(s, w, 1, t, &t_rho, eta, elastic),
                2 => modal_forces(s, w, 2, t, &t_rho, eta, elastic),
                3 => modal_forces(s, w, 3, t, &t_rho, eta, elastic),
                4 => modal_forces(s, w, 4, t, &t_rho, eta, elastic),
                m => modal_forces(s, w, m, t, &t_rho, eta, elastic),
            }
        }
        FieldLoad { wrench, potential }
    }
}

/// The field's generalised forces `Qₖ` on a stiffened body's `m` modes (the module's page),
/// added to `elastic`; `eta` and `elastic` start at the body's first coordinate. Inlined with
/// `m` known where [`FlexModel::linear_field_on`] dispatches on it.
#[inline(always)]
fn modal_forces(
    s: &super::Stiffening,
    w: &FieldWeights,
    m: usize,
    t: &Mat3,
    t_rho: &Vec3,
    eta: &[f64],
    elastic: &mut [f64],
) {
    // `c(a) = ½ tr(T ∂J)` for an inertia change `a` (`∂J = ½ tr(a) 1 − a`), from the
    // weights made with the model.
    let tp = packed(t);
    let (c0, c1, c2) = (dot6(&tp, &w.a[0]), dot6(&tp, &w.a[1]), dot6(&tp, &w.a[2]));
    let rta = t_rho.dot(&s.axis);
    let (eta, elastic) = (&eta[..m], &mut elastic[..m]);
    let (first, weights) = (&s.first[..m], &w.first[..m]);
    for k in 0..m {
        let j0 = s.j0_row(k, eta);
        let j1 = s.j1_row(k, eta);
        elastic[k] += t_rho.dot(&first[k].h) - j0 * rta + dot6(&tp, &weights[k])
            - 2.0 * (j0 * c0 + j1 * c1)
            + 2.0 * eta[k] * c2;
    }
}
