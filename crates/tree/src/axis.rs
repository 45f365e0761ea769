//! Hinges about a coordinate axis: the fast path of the per-call algorithms.
//!
//! A hinge whose axis is `±x`, `±y` or `±z` and that has no fixed rotation (`rot0 = 1`, the
//! common case: every hinge of the preprint satellite) turns its child about one coordinate
//! axis `k`. Then `E = Rot(±e_k, φ)ᵀ` has row and column `k` equal to `e_k` and a 2x2 rotation
//! block on the two other axes, and the motion subspace is `S = [±e_k; child_at × ±e_k]`.
//! Every product with `E` or `S` then touches two of three rows (or one entry): `Xᵀ IA X`
//! costs three planar similarities instead of three 3x3 similarities, `U = IA S` is a column
//! of `IA` (plus a lever term when the hinge point is off the child's origin), `D` an entry.
//! The results equal the general path's to round-off (tested in `aba.rs`). The kernels are
//! inlined where they are called: the unrolled kernel's instances compiled for wider
//! vectors (`#[target_feature]`) compile them for those vectors too, where an out-of-line
//! piece keeps the baseline target's code (kept out of line until 2026-11-28, for the
//! instruction cache; inlined, one orbit of the peer scene takes 0.83 of the time and
//! `satsim bench`'s generic ABA 0.89: `docs/src/engineering/kernel.md`).
//!
//! Every kernel is generic over its scalar ([`Real`]): the same code for one run (`f64`) and
//! for lanes of runs; the axis and its sign are the batch's, common to its lanes.

use crate::real::{Real, mat3};
use crate::spatial::{
    ArticulatedInertia, Force, Mat3, Motion, RigidInertia, Transform, Vec3, add_translated,
};
use nalgebra::{Matrix3, Vector3};

/// A hinge about the coordinate axis `k` of its parent (and child) frame, with sign `sign`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoordAxis {
    /// The axis: 0, 1, 2 for x, y, z.
    k: usize,
    /// The two other axes in cyclic order: `(k + 1) % 3`, `(k + 2) % 3`.
    i: usize,
    j: usize,
    /// `+1` or `−1`: the hinge axis is `sign · e_k`.
    sign: f64,
}

impl CoordAxis {
    /// The coordinate axis of a hinge about `axis` (unit, parent frame) with fixed rotation
    /// `rot0`, if the axis is exactly `±e_k` and `rot0` exactly the identity.
    pub fn of(axis: &Vec3, rot0: &Mat3) -> Option<Self> {
        if *rot0 != Mat3::identity() {
            return None;
        }
        let k = (0..3).find(|&k| axis[k].abs() == 1.0)?;
        if (0..3).any(|m| m != k && axis[m] != 0.0) {
            return None;
        }
        Some(Self {
            k,
            i: (k + 1) % 3,
            j: (k + 2) % 3,
            sign: axis[k],
        })
    }

    /// The axis's index: 0, 1, 2 for x, y, z.
    pub(crate) fn index(&self) -> usize {
        self.k
    }

    /// `a ∘ b` (first `b`, then `a`, as [`Transform::compose`]) for two transforms whose
    /// rotations are both about this axis (row and column `k` exactly `e_k`): the product
    /// of their 2x2 blocks, the same sums as the general product's.
    #[inline(always)]
    pub(crate) fn compose<T: Real>(&self, a: &Transform<T>, b: &Transform<T>) -> Transform<T> {
        let (i, j) = (self.i, self.j);
        let (ea, eb) = (&a.rot, &b.rot);
        let mut rot = Matrix3::zeros();
        rot[(self.k, self.k)] = T::one();
        rot[(i, i)] = ea[(i, i)] * eb[(i, i)] + ea[(i, j)] * eb[(j, i)];
        rot[(i, j)] = ea[(i, i)] * eb[(i, j)] + ea[(i, j)] * eb[(j, j)];
        rot[(j, i)] = ea[(j, i)] * eb[(i, i)] + ea[(j, j)] * eb[(j, i)];
        rot[(j, j)] = ea[(j, i)] * eb[(i, j)] + ea[(j, j)] * eb[(j, j)];
        Transform::new(rot, b.trans + self.rotate_back(eb, &a.trans))
    }

    /// `Xup` at hinge angle `phi`: `E = Rot(sign e_k, φ)ᵀ`, `r = at − Eᵀ child_at`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn transform<T: Real>(
        &self,
        phi: T,
        at: &Vector3<T>,
        child_at: &Vector3<T>,
    ) -> Transform<T> {
        // libm's (musl's) sincos, < 1 ulp: inlined, about 90 instructions against 130 for
        // the C library's through `f64::sin_cos` (callgrind), which also saves and restores
        // the rounding mode on every call. Five per right-hand side on the satellite.
        let sc = (T::splat(self.sign) * phi).sin_cos();
        // The axes as constants: no index checks, straight-line code.
        match self.k {
            0 => transform::<_, 0, 1, 2>(sc, at, child_at),
            1 => transform::<_, 1, 2, 0>(sc, at, child_at),
            _ => transform::<_, 2, 0, 1>(sc, at, child_at),
        }
    }

    /// `E v` (parent to child coordinates).
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    fn rotate<T: Real>(&self, e: &Matrix3<T>, v: &Vector3<T>) -> Vector3<T> {
        match self.k {
            0 => rotate::<_, 1, 2, false>(e, v),
            1 => rotate::<_, 2, 0, false>(e, v),
            _ => rotate::<_, 0, 1, false>(e, v),
        }
    }

    /// `Eᵀ v` (child to parent coordinates).
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    fn rotate_back<T: Real>(&self, e: &Matrix3<T>, v: &Vector3<T>) -> Vector3<T> {
        match self.k {
            0 => rotate::<_, 1, 2, true>(e, v),
            1 => rotate::<_, 2, 0, true>(e, v),
            _ => rotate::<_, 0, 1, true>(e, v),
        }
    }

    /// `Eᵀ M E` for `M = A, B, C` of `ia`: rows then columns `i`, `j` mixed by the 2x2 block
    /// of `E`, with the axes as constants (no index checks, straight-line code).
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    fn similarities<T: Real>(
        &self,
        e: &Matrix3<T>,
        ia: &ArticulatedInertia<T>,
    ) -> ArticulatedInertia<T> {
        match self.k {
            0 => similarities::<_, 1, 2>(e, ia),
            1 => similarities::<_, 2, 0>(e, ia),
            _ => similarities::<_, 0, 1>(e, ia),
        }
    }

    /// `X m` for this hinge's `Xup` (as [`Transform::apply_motion`]).
    #[inline(always)]
    pub fn apply_motion<T: Real>(&self, x: &Transform<T>, m: &Motion<T>) -> Motion<T> {
        Motion {
            ang: self.rotate(&x.rot, &m.ang),
            lin: self.rotate(&x.rot, &(m.lin - mat3::cross(&x.trans, &m.ang))),
        }
    }

    /// `Xᵀ f` for this hinge's `Xup` (as [`Transform::inv_apply_force`]). Always inlined:
    /// CRBA's columns chain them on the walk to the root, and a result returned through
    /// memory would make the next call wait for its stores.
    #[inline(always)]
    pub fn inv_apply_force<T: Real>(&self, x: &Transform<T>, f: &Force<T>) -> Force<T> {
        let lin = self.rotate_back(&x.rot, &f.lin);
        Force {
            ang: self.rotate_back(&x.rot, &f.ang) + mat3::cross(&x.trans, &lin),
            lin,
        }
    }

    /// `Xᵀ I X` for this hinge's `Xup` and a rigid inertia `I` (as
    /// [`RigidInertia::inv_transform`]: CRBA's composite inertias): one planar similarity
    /// for the rotational inertia, `Eᵀ h` two entries mixed. Always inlined, as
    /// [`RigidInertia::inv_transform`] is (out of line, its result returns through memory).
    #[inline(always)]
    pub(crate) fn rigid_inv_transform<T: Real>(
        &self,
        ic: &RigidInertia<T>,
        x: &Transform<T>,
    ) -> RigidInertia<T> {
        let rotated = RigidInertia {
            mass: ic.mass,
            h: self.rotate_back(&x.rot, &ic.h),
            inertia: match self.k {
                0 => similarity::<_, 1, 2>(&x.rot, &ic.inertia),
                1 => similarity::<_, 2, 0>(&x.rot, &ic.inertia),
                _ => similarity::<_, 0, 1>(&x.rot, &ic.inertia),
            },
        };
        rotated.translated(&x.trans)
    }

    /// `out += Xᵀ IA X` (or `out = start + Xᵀ IA X`) for this hinge's `Xup` (as
    /// [`ArticulatedInertia::inv_transform`], accumulated in place into the parent's inertia).
    #[inline(always)]
    pub fn add_inv_transform<T: Real>(
        &self,
        ia: &ArticulatedInertia<T>,
        x: &Transform<T>,
        out: &mut ArticulatedInertia<T>,
        start: Option<&ArticulatedInertia<T>>,
    ) {
        let s = self.similarities(&x.rot, ia);
        add_translated(&s.a, &s.b, &s.c, &x.trans, out, start);
    }

    /// For a hinge through its child's origin (`S = [sign e_k; 0]`, `U = sign [A e_k; Bᵀ e_k]`,
    /// `D = A_kk`, `inv_d = 1 / D`): `out = start + Xᵀ IAᵃ X` with the projection
    /// `IAᵃ = IA − U Uᵀ / D`, and returns `IAᵃ c`. `IAᵃ` has row and column `k` of `A` and
    /// row `k` of `B` zero exactly (`IAᵃ S = 0`), and the rotation about `e_k` keeps them
    /// zero: they are neither formed nor rotated (the unrolled ABA's serial bodies).
    #[inline(always)]
    pub fn project_at_point<T: Real>(
        &self,
        ia: &ArticulatedInertia<T>,
        inv_d: T,
        c: &Motion<T>,
        x: &Transform<T>,
        out: &mut ArticulatedInertia<T>,
        start: &ArticulatedInertia<T>,
    ) -> Force<T> {
        match self.k {
            0 => project_at_point::<_, 0, 1, 2>(ia, inv_d, c, x, out, start),
            1 => project_at_point::<_, 1, 2, 0>(ia, inv_d, c, x, out, start),
            _ => project_at_point::<_, 2, 0, 1>(ia, inv_d, c, x, out, start),
        }
    }

    /// `U = IA S` for `S = [sign e_k; l]`, `l = child_at × sign e_k` (the joint's `s.lin`).
    #[inline(never)]
    pub fn mul_subspace<T: Real>(&self, ia: &ArticulatedInertia<T>, l: &Vector3<T>) -> Force<T> {
        let (k, sign) = (self.k, T::splat(self.sign));
        // The lever term unconditionally: a branch costs more than its 30 flops.
        Force {
            ang: ia.a.column(k) * sign + ia.b * l,
            lin: ia.b.row(k).transpose() * sign + ia.c * l,
        }
    }

    /// `M E` for this hinge's `E` (`x.rot`): only columns `i` and `j` of `M` mix (a
    /// composite rotation through a chain of massless links, see `aba.rs`).
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn post_rotate<T: Real>(&self, m: &Matrix3<T>, e: &Matrix3<T>) -> Matrix3<T> {
        let (i, j) = (self.i, self.j);
        let (eii, eij, eji, ejj) = (e[(i, i)], e[(i, j)], e[(j, i)], e[(j, j)]);
        let (mi, mj) = (m.column(i).into_owned(), m.column(j).into_owned());
        let mut out = *m;
        out.set_column(i, &(mi * eii + mj * eji));
        out.set_column(j, &(mi * eij + mj * ejj));
        out
    }

    /// `M a` for this hinge's axis `a = sign e_k`: a signed column of `M`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn times_axis<T: Real>(&self, m: &Matrix3<T>) -> Vector3<T> {
        m.column(self.k) * T::splat(self.sign)
    }

    /// `Mᵀ a` for this hinge's axis `a = sign e_k`: a signed row of `M`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn tr_times_axis<T: Real>(&self, m: &Matrix3<T>) -> Vector3<T> {
        m.row(self.k).transpose() * T::splat(self.sign)
    }

    /// `a · v` for this hinge's axis `a = sign e_k`: a signed entry of `v`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn dot_axis<T: Real>(&self, v: &Vector3<T>) -> T {
        T::splat(self.sign) * v[self.k]
    }

    /// The axis `sign e_k` times `x`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn scaled_axis<T: Real>(&self, x: T) -> Vector3<T> {
        Vector3::ith(self.k, T::splat(self.sign) * x)
    }

    /// `Sᵀ f` for `S = [sign e_k; l]`.
    #[cfg_attr(not(debug_assertions), inline(always))]
    #[cfg_attr(debug_assertions, inline)]
    pub fn dot_subspace<T: Real>(&self, l: &Vector3<T>, f: &Force<T>) -> T {
        T::splat(self.sign) * f.ang[self.k] + l.dot(&f.lin)
    }
}

/// [`CoordAxis::transform`] about axis `K` (`I`, `J` the others in cyclic order), from
/// `(s, c) = sin_cos(sign φ)`.
#[inline(always)]
fn transform<T: Real, const K: usize, const I: usize, const J: usize>(
    (s, c): (T, T),
    at: &Vector3<T>,
    child_at: &Vector3<T>,
) -> Transform<T> {
    // Rot(e_k, φ) maps e_i to c e_i + s e_j; E is its transpose.
    let mut e = Matrix3::zeros();
    e[(K, K)] = T::one();
    e[(I, I)] = c;
    e[(J, J)] = c;
    e[(I, J)] = s;
    e[(J, I)] = -s;
    let mut rc = Vector3::zeros();
    rc[K] = child_at[K];
    rc[I] = c * child_at[I] - s * child_at[J];
    rc[J] = s * child_at[I] + c * child_at[J];
    Transform::new(e, at - rc)
}

/// `Eᵀ M E` for the three blocks, `E` a rotation about the third axis `k` (`i`, `j` the
/// others): only rows and columns `I` and `J` change.
#[inline(always)]
fn similarities<T: Real, const I: usize, const J: usize>(
    e: &Matrix3<T>,
    ia: &ArticulatedInertia<T>,
) -> ArticulatedInertia<T> {
    ArticulatedInertia {
        a: similarity::<_, I, J>(e, &ia.a),
        b: similarity::<_, I, J>(e, &ia.b),
        c: similarity::<_, I, J>(e, &ia.c),
    }
}

/// [`CoordAxis::project_at_point`] about axis `K` (`I`, `J` the others in cyclic order).
#[inline(always)]
fn project_at_point<T: Real, const K: usize, const I: usize, const J: usize>(
    ia: &ArticulatedInertia<T>,
    r: T,
    c: &Motion<T>,
    x: &Transform<T>,
    out: &mut ArticulatedInertia<T>,
    start: &ArticulatedInertia<T>,
) -> Force<T> {
    let (a, b) = (&ia.a, &ia.b);
    // U = ±[a; bk]: column K of A, row K of B. The projected blocks: A's I-J block, B's
    // rows I and J, all of C.
    let (ai, aj) = (a[(K, I)], a[(K, J)]);
    let bk = b.row(K).transpose();
    let (ri, rj) = (ai * r, aj * r);
    let (aii, aij, ajj) = (
        a[(I, I)] - ai * ri,
        a[(I, J)] - ai * rj,
        a[(J, J)] - aj * rj,
    );
    let bi = b.row(I).transpose() - bk * ri;
    let bj = b.row(J).transpose() - bk * rj;
    let cp = ia.c - mat3::outer(&(bk * r), &bk);
    // IAᵃ c.
    let (ci, cj) = (c.ang[I], c.ang[J]);
    let mut f_ang = Vector3::zeros();
    f_ang[I] = aii * ci + aij * cj + bi.dot(&c.lin);
    f_ang[J] = aij * ci + ajj * cj + bj.dot(&c.lin);
    let f = Force::new(f_ang, bi * ci + bj * cj + mat3::mul(&cp, &c.lin));
    // Eᵀ M E: the I-J block of A, rows I and J of B (then its columns), all of C.
    let e = &x.rot;
    let (eii, eij, eji, ejj) = (e[(I, I)], e[(I, J)], e[(J, I)], e[(J, J)]);
    let (nii, nij) = (aii * eii + aij * eji, aii * eij + aij * ejj);
    let (nji, njj) = (aij * eii + ajj * eji, aij * eij + ajj * ejj);
    let mut an = Matrix3::zeros();
    an[(I, I)] = eii * nii + eji * nji;
    an[(I, J)] = eii * nij + eji * njj;
    an[(J, I)] = an[(I, J)];
    an[(J, J)] = eij * nij + ejj * njj;
    let col = |row: &Vector3<T>| {
        let mut o = *row;
        o[I] = row[I] * eii + row[J] * eji;
        o[J] = row[I] * eij + row[J] * ejj;
        o
    };
    let (bi, bj) = (col(&bi), col(&bj));
    let mut bn = Matrix3::zeros();
    bn.set_row(I, &(bi * eii + bj * eji).transpose());
    bn.set_row(J, &(bi * eij + bj * ejj).transpose());
    let cn = similarity::<_, I, J>(e, &cp);
    add_translated(&an, &bn, &cn, &x.trans, out, Some(start));
    f
}

/// `Eᵀ M E`, `E` a rotation about the third axis (`I`, `J` the others).
#[inline(always)]
fn similarity<T: Real, const I: usize, const J: usize>(
    e: &Matrix3<T>,
    m: &Matrix3<T>,
) -> Matrix3<T> {
    let (eii, eij, eji, ejj) = (e[(I, I)], e[(I, J)], e[(J, I)], e[(J, J)]);
    let mut n = *m;
    for r in 0..3 {
        let (mi, mj) = (m[(r, I)], m[(r, J)]);
        n[(r, I)] = mi * eii + mj * eji;
        n[(r, J)] = mi * eij + mj * ejj;
    }
    let mut out = n;
    for col in 0..3 {
        let (ni, nj) = (n[(I, col)], n[(J, col)]);
        out[(I, col)] = eii * ni + eji * nj;
        out[(J, col)] = eij * ni + ejj * nj;
    }
    out
}

/// `E v` (or `Eᵀ v` when `BACK`), `E` a rotation about the third axis (`I`, `J` the others).
#[inline(always)]
fn rotate<T: Real, const I: usize, const J: usize, const BACK: bool>(
    e: &Matrix3<T>,
    v: &Vector3<T>,
) -> Vector3<T> {
    let (eij, eji) = if BACK {
        (e[(J, I)], e[(I, J)])
    } else {
        (e[(I, J)], e[(J, I)])
    };
    let mut out = *v;
    out[I] = e[(I, I)] * v[I] + eij * v[J];
    out[J] = eji * v[I] + e[(J, J)] * v[J];
    out
}

#[cfg(test)]
mod tests {
    //! Each coordinate-axis kernel against the general 3x3 form it replaces, on every signed
    //! axis, and over lanes against `f64` lane by lane (the same bits).
    use super::*;
    use crate::real::F64x;
    use crate::samples::{SplitMix, random_inertia};
    use crate::spatial::rotation_about;

    fn close(a: &[f64], b: &[f64], what: &str) {
        let scale = b.iter().fold(1.0_f64, |m, x| m.max(x.abs()));
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() <= 1e-14 * scale, "{what}: {a:?} vs {b:?}");
        }
    }

    fn blocks(ia: &ArticulatedInertia) -> Vec<f64> {
        ia.a.iter()
            .chain(ia.b.iter())
            .chain(ia.c.iter())
            .copied()
            .collect()
    }

    /// A general articulated inertia (its `B` not a cross-product matrix): two rigid bodies,
    /// one moved by a random transform, less a random rank-one projection.
    fn inertia(rng: &mut SplitMix) -> ArticulatedInertia {
        let rigid = |rng: &mut SplitMix| {
            let m = rng.range(0.5, 20.0);
            RigidInertia::from_com(m, rng.vec3(1.0), random_inertia(rng, m))
        };
        let x = Transform::new(
            rotation_about(&rng.unit(), rng.range(-3.0, 3.0)),
            rng.vec3(1.0),
        );
        let mut ia = ArticulatedInertia::from(rigid(rng));
        ia += ArticulatedInertia::from(rigid(rng)).inv_transform(&x);
        let u = ia.mul_motion(&Motion::new(rng.unit(), rng.vec3(1.0)));
        let d = 4.0 * u.ang.norm_squared().max(u.lin.norm_squared()) + 1.0;
        ia.sub_outer(&u, 1.0 / d);
        ia
    }

    fn axes() -> Vec<(CoordAxis, Vec3)> {
        (0..3)
            .flat_map(|k| {
                [1.0, -1.0].map(|s| {
                    let a = Vec3::ith(k, s);
                    (
                        CoordAxis::of(&a, &Mat3::identity()).expect("a coordinate axis"),
                        a,
                    )
                })
            })
            .collect()
    }

    #[test]
    fn coordinate_axis_kernels_equal_the_general_forms() {
        let mut rng = SplitMix(29);
        for (ax, axis) in axes() {
            for _ in 0..20 {
                let phi = rng.range(-4.0, 4.0);
                let (at, child_at) = (rng.vec3(1.0), rng.vec3(1.0));
                // The general transform (`Joint::transform`): E = Rot(a, φ)ᵀ, r = at − Eᵀ child_at.
                let et = rotation_about(&axis, phi);
                let general = Transform::new(et.transpose(), at - et * child_at);
                let x = ax.transform(phi, &at, &child_at);
                close(x.rot.as_slice(), general.rot.as_slice(), "E");
                close(x.trans.as_slice(), general.trans.as_slice(), "r");
                let m = Motion::new(rng.vec3(2.0), rng.vec3(2.0));
                let f = Force::new(rng.vec3(2.0), rng.vec3(2.0));
                close(
                    &ax.apply_motion(&x, &m).to_array(),
                    &x.apply_motion(&m).to_array(),
                    "X m",
                );
                close(
                    &ax.inv_apply_force(&x, &f).to_array(),
                    &x.inv_apply_force(&f).to_array(),
                    "Xᵀ f",
                );
                let ia = inertia(&mut rng);
                let start = inertia(&mut rng);
                let mut out = start;
                ax.add_inv_transform(&ia, &x, &mut out, None);
                let mut want = start;
                want += ia.inv_transform(&x);
                close(&blocks(&out), &blocks(&want), "Xᵀ IA X");
                let mut out = ArticulatedInertia::default();
                ax.add_inv_transform(&ia, &x, &mut out, Some(&start));
                close(&blocks(&out), &blocks(&want), "start + Xᵀ IA X");
                let rigid =
                    RigidInertia::from_com(3.0, rng.vec3(1.0), random_inertia(&mut rng, 3.0));
                let (r1, r2) = (ax.rigid_inv_transform(&rigid, &x), rigid.inv_transform(&x));
                close(&[r1.mass], &[r2.mass], "m");
                close(r1.h.as_slice(), r2.h.as_slice(), "h");
                close(r1.inertia.as_slice(), r2.inertia.as_slice(), "I");
                // S = [a; l], l = child_at × a.
                let l = child_at.cross(&axis);
                let s = Motion::new(axis, l);
                close(
                    &ax.mul_subspace(&ia, &l).to_array(),
                    &ia.mul_motion(&s).to_array(),
                    "IA S",
                );
                close(&[ax.dot_subspace(&l, &f)], &[s.dot(&f)], "Sᵀ f");
                let m3 = Mat3::from_fn(|_, _| rng.range(-1.0, 1.0));
                close(
                    ax.post_rotate(&m3, &x.rot).as_slice(),
                    (m3 * x.rot).as_slice(),
                    "M E",
                );
                close(ax.times_axis(&m3).as_slice(), (m3 * axis).as_slice(), "M a");
                close(
                    ax.tr_times_axis(&m3).as_slice(),
                    m3.tr_mul(&axis).as_slice(),
                    "Mᵀ a",
                );
                close(&[ax.dot_axis(&m.ang)], &[axis.dot(&m.ang)], "a · v");
                close(
                    ax.scaled_axis(1.7).as_slice(),
                    (axis * 1.7).as_slice(),
                    "a x",
                );
                // The projection at a hinge through the child's origin (S = [a; 0]).
                let x0 = ax.transform(phi, &at, &Vec3::zeros());
                let u = ia.mul_motion(&Motion::new(axis, Vec3::zeros()));
                let d = axis.dot(&u.ang);
                let c = Motion::new(rng.vec3(1.0), rng.vec3(1.0));
                let mut out = ArticulatedInertia::default();
                let iac = ax.project_at_point(&ia, 1.0 / d, &c, &x0, &mut out, &start);
                let mut projected = ia;
                projected.sub_outer(&u, 1.0 / d);
                let mut want = start;
                want += projected.inv_transform(&x0);
                close(&blocks(&out), &blocks(&want), "start + Xᵀ IAᵃ X");
                close(
                    &iac.to_array(),
                    &projected.mul_motion(&c).to_array(),
                    "IAᵃ c",
                );
            }
        }
    }

    /// Over four lanes, each kernel gives on each lane the bits it gives for that lane's
    /// `f64` inputs.
    #[test]
    fn lanes_are_the_f64_kernels_bit_for_bit() {
        let mut rng = SplitMix(31);
        let v = |xs: &[Vec3; 4]| Vector3::from_fn(|i, _| F64x(std::array::from_fn(|k| xs[k][i])));
        let mt =
            |xs: &[Mat3; 4]| Matrix3::from_fn(|i, j| F64x(std::array::from_fn(|k| xs[k][(i, j)])));
        let ial = |xs: &[ArticulatedInertia; 4]| ArticulatedInertia {
            a: mt(&xs.map(|x| x.a)),
            b: mt(&xs.map(|x| x.b)),
            c: mt(&xs.map(|x| x.c)),
        };
        let same = |lanes: &[F64x<4>], k: usize, one: &[f64], what: &str| {
            let got: Vec<u64> = lanes.iter().map(|x| x.0[k].to_bits()).collect();
            let want: Vec<u64> = one.iter().map(|x| x.to_bits()).collect();
            assert_eq!(got, want, "{what}, lane {k}");
        };
        for (ax, _) in axes() {
            let phi: [f64; 4] = std::array::from_fn(|_| rng.range(-4.0, 4.0));
            let at: [Vec3; 4] = std::array::from_fn(|_| rng.vec3(1.0));
            let ia: [ArticulatedInertia; 4] = std::array::from_fn(|_| inertia(&mut rng));
            let start: [ArticulatedInertia; 4] = std::array::from_fn(|_| inertia(&mut rng));
            let c: [Motion; 4] = std::array::from_fn(|_| Motion::new(rng.vec3(1.0), rng.vec3(1.0)));
            let o = Vector3::zeros();
            let xl = ax.transform(F64x(phi), &v(&at), &o);
            let cl = Motion::new(v(&c.map(|m| m.ang)), v(&c.map(|m| m.lin)));
            let ual = ax.times_axis(&ial(&ia).a);
            let dl = ax.dot_axis(&ual);
            let mut out = ArticulatedInertia::default();
            let fl = ax.project_at_point(
                &ial(&ia),
                F64x::splat(1.0) / dl,
                &cl,
                &xl,
                &mut out,
                &ial(&start),
            );
            let ml = ax.apply_motion(&xl, &cl);
            for k in 0..4 {
                let x = ax.transform(phi[k], &at[k], &Vec3::zeros());
                same(xl.rot.as_slice(), k, x.rot.as_slice(), "E");
                same(xl.trans.as_slice(), k, x.trans.as_slice(), "r");
                let d = ax.dot_axis(&ax.times_axis(&ia[k].a));
                let mut o1 = ArticulatedInertia::default();
                let f = ax.project_at_point(&ia[k], 1.0 / d, &c[k], &x, &mut o1, &start[k]);
                same(&fl.to_array(), k, &f.to_array(), "IAᵃ c");
                for (l, one) in [(&out.a, &o1.a), (&out.b, &o1.b), (&out.c, &o1.c)] {
                    same(l.as_slice(), k, one.as_slice(), "start + Xᵀ IAᵃ X");
                }
                same(
                    &ml.to_array(),
                    k,
                    &ax.apply_motion(&x, &c[k]).to_array(),
                    "X m",
                );
            }
        }
    }
}
