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
//! kept out of line: inlined into ABA's three passes (three axes each) they multiplied its
//! instruction-cache misses and made it slower in wall time despite fewer instructions.

use crate::spatial::{
    ArticulatedInertia, Force, Mat3, Motion, RigidInertia, Transform, Vec3, add_translated,
};

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

    /// `Xup` at hinge angle `phi`: `E = Rot(sign e_k, φ)ᵀ`, `r = at − Eᵀ child_at`.
    #[inline]
    pub fn transform(&self, phi: f64, at: &Vec3, child_at: &Vec3) -> Transform {
        // libm's (musl's) sincos, < 1 ulp: inlined, about 90 instructions against 130 for
        // the C library's through `f64::sin_cos` (callgrind), which also saves and restores
        // the rounding mode on every call. Five per right-hand side on the satellite.
        let sc = libm::sincos(self.sign * phi);
        // The axes as constants: no index checks, straight-line code.
        match self.k {
            0 => transform::<0, 1, 2>(sc, at, child_at),
            1 => transform::<1, 2, 0>(sc, at, child_at),
            _ => transform::<2, 0, 1>(sc, at, child_at),
        }
    }

    /// `E v` (parent to child coordinates).
    #[inline]
    fn rotate(&self, e: &Mat3, v: &Vec3) -> Vec3 {
        match self.k {
            0 => rotate::<1, 2, false>(e, v),
            1 => rotate::<2, 0, false>(e, v),
            _ => rotate::<0, 1, false>(e, v),
        }
    }

    /// `Eᵀ v` (child to parent coordinates).
    #[inline]
    fn rotate_back(&self, e: &Mat3, v: &Vec3) -> Vec3 {
        match self.k {
            0 => rotate::<1, 2, true>(e, v),
            1 => rotate::<2, 0, true>(e, v),
            _ => rotate::<0, 1, true>(e, v),
        }
    }

    /// `Eᵀ M E` for `M = A, B, C` of `ia`: rows then columns `i`, `j` mixed by the 2x2 block
    /// of `E`, with the axes as constants (no index checks, straight-line code).
    #[inline]
    fn similarities(&self, e: &Mat3, ia: &ArticulatedInertia) -> ArticulatedInertia {
        match self.k {
            0 => similarities::<1, 2>(e, ia),
            1 => similarities::<2, 0>(e, ia),
            _ => similarities::<0, 1>(e, ia),
        }
    }

    /// `X m` for this hinge's `Xup` (as [`Transform::apply_motion`]).
    #[inline(never)]
    pub fn apply_motion(&self, x: &Transform, m: &Motion) -> Motion {
        Motion {
            ang: self.rotate(&x.rot, &m.ang),
            lin: self.rotate(&x.rot, &(m.lin - x.trans.cross(&m.ang))),
        }
    }

    /// `Xᵀ f` for this hinge's `Xup` (as [`Transform::inv_apply_force`]).
    #[inline(never)]
    pub fn inv_apply_force(&self, x: &Transform, f: &Force) -> Force {
        self.inv_apply_force_inline(x, f)
    }

    /// [`CoordAxis::inv_apply_force`] inlined: for a chain of them (CRBA's columns), where
    /// a call's result returned through memory would make the next call wait for it.
    #[inline(always)]
    pub(crate) fn inv_apply_force_inline(&self, x: &Transform, f: &Force) -> Force {
        let lin = self.rotate_back(&x.rot, &f.lin);
        Force {
            ang: self.rotate_back(&x.rot, &f.ang) + x.trans.cross(&lin),
            lin,
        }
    }

    /// `Xᵀ I X` for this hinge's `Xup` and a rigid inertia `I` (as
    /// [`RigidInertia::inv_transform`]: CRBA's composite inertias): one planar similarity
    /// for the rotational inertia, `Eᵀ h` two entries mixed. Always inlined, as
    /// [`RigidInertia::inv_transform`] is (out of line, its result returns through memory).
    #[inline(always)]
    pub(crate) fn rigid_inv_transform(&self, ic: &RigidInertia, x: &Transform) -> RigidInertia {
        let rotated = RigidInertia {
            mass: ic.mass,
            h: self.rotate_back(&x.rot, &ic.h),
            inertia: match self.k {
                0 => similarity::<1, 2>(&x.rot, &ic.inertia),
                1 => similarity::<2, 0>(&x.rot, &ic.inertia),
                _ => similarity::<0, 1>(&x.rot, &ic.inertia),
            },
        };
        rotated.translated(&x.trans)
    }

    /// `out += Xᵀ IA X` (or `out = start + Xᵀ IA X`) for this hinge's `Xup` (as
    /// [`ArticulatedInertia::inv_transform`], accumulated in place into the parent's inertia).
    #[inline(never)]
    pub fn add_inv_transform(
        &self,
        ia: &ArticulatedInertia,
        x: &Transform,
        out: &mut ArticulatedInertia,
        start: Option<&ArticulatedInertia>,
    ) {
        let s = self.similarities(&x.rot, ia);
        add_translated(&s.a, &s.b, &s.c, &x.trans, out, start);
    }

    /// For a hinge through its child's origin (`S = [sign e_k; 0]`, `U = sign [A e_k; Bᵀ e_k]`,
    /// `D = A_kk`, `inv_d = 1 / D`): `out = start + Xᵀ IAᵃ X` with the projection
    /// `IAᵃ = IA − U Uᵀ / D`, and returns `IAᵃ c`. `IAᵃ` has row and column `k` of `A` and
    /// row `k` of `B` zero exactly (`IAᵃ S = 0`), and the rotation about `e_k` keeps them
    /// zero: they are neither formed nor rotated (the unrolled ABA's serial bodies).
    #[inline(never)]
    pub fn project_at_point(
        &self,
        ia: &ArticulatedInertia,
        inv_d: f64,
        c: &Motion,
        x: &Transform,
        out: &mut ArticulatedInertia,
        start: &ArticulatedInertia,
    ) -> Force {
        match self.k {
            0 => project_at_point::<0, 1, 2>(ia, inv_d, c, x, out, start),
            1 => project_at_point::<1, 2, 0>(ia, inv_d, c, x, out, start),
            _ => project_at_point::<2, 0, 1>(ia, inv_d, c, x, out, start),
        }
    }

    /// `U = IA S` for `S = [sign e_k; l]`, `l = child_at × sign e_k` (the joint's `s.lin`).
    #[inline(never)]
    pub fn mul_subspace(&self, ia: &ArticulatedInertia, l: &Vec3) -> Force {
        let k = self.k;
        // The lever term unconditionally: a branch costs more than its 30 flops.
        Force {
            ang: ia.a.column(k) * self.sign + ia.b * l,
            lin: ia.b.row(k).transpose() * self.sign + ia.c * l,
        }
    }

    /// `M E` for this hinge's `E` (`x.rot`): only columns `i` and `j` of `M` mix (a
    /// composite rotation through a chain of massless links, see `aba.rs`).
    #[inline]
    pub fn post_rotate(&self, m: &Mat3, e: &Mat3) -> Mat3 {
        let (i, j) = (self.i, self.j);
        let (eii, eij, eji, ejj) = (e[(i, i)], e[(i, j)], e[(j, i)], e[(j, j)]);
        let (mi, mj) = (m.column(i).into_owned(), m.column(j).into_owned());
        let mut out = *m;
        out.set_column(i, &(mi * eii + mj * eji));
        out.set_column(j, &(mi * eij + mj * ejj));
        out
    }

    /// `M a` for this hinge's axis `a = sign e_k`: a signed column of `M`.
    #[inline]
    pub fn times_axis(&self, m: &Mat3) -> Vec3 {
        m.column(self.k) * self.sign
    }

    /// `Mᵀ a` for this hinge's axis `a = sign e_k`: a signed row of `M`.
    #[inline]
    pub fn tr_times_axis(&self, m: &Mat3) -> Vec3 {
        m.row(self.k).transpose() * self.sign
    }

    /// `a · v` for this hinge's axis `a = sign e_k`: a signed entry of `v`.
    #[inline]
    pub fn dot_axis(&self, v: &Vec3) -> f64 {
        self.sign * v[self.k]
    }

    /// The axis `sign e_k` times `x`.
    #[inline]
    pub fn scaled_axis(&self, x: f64) -> Vec3 {
        Vec3::ith(self.k, self.sign * x)
    }

    /// `Sᵀ f` for `S = [sign e_k; l]`.
    #[inline]
    pub fn dot_subspace(&self, l: &Vec3, f: &Force) -> f64 {
        self.sign * f.ang[self.k] + l.dot(&f.lin)
    }
}

/// [`CoordAxis::transform`] about axis `K` (`I`, `J` the others in cyclic order), from
/// `(s, c) = sin_cos(sign φ)`.
#[inline(always)]
fn transform<const K: usize, const I: usize, const J: usize>(
    (s, c): (f64, f64),
    at: &Vec3,
    child_at: &Vec3,
) -> Transform {
    // Rot(e_k, φ) maps e_i to c e_i + s e_j; E is its transpose.
    let mut e = Mat3::zeros();
    e[(K, K)] = 1.0;
    e[(I, I)] = c;
    e[(J, J)] = c;
    e[(I, J)] = s;
    e[(J, I)] = -s;
    let mut rc = Vec3::zeros();
    rc[K] = child_at[K];
    rc[I] = c * child_at[I] - s * child_at[J];
    rc[J] = s * child_at[I] + c * child_at[J];
    Transform::new(e, at - rc)
}

/// `Eᵀ M E` for the three blocks, `E` a rotation about the third axis `k` (`i`, `j` the
/// others): only rows and columns `I` and `J` change.
#[inline(always)]
fn similarities<const I: usize, const J: usize>(
    e: &Mat3,
    ia: &ArticulatedInertia,
) -> ArticulatedInertia {
    ArticulatedInertia {
        a: similarity::<I, J>(e, &ia.a),
        b: similarity::<I, J>(e, &ia.b),
        c: similarity::<I, J>(e, &ia.c),
    }
}

/// [`CoordAxis::project_at_point`] about axis `K` (`I`, `J` the others in cyclic order).
#[inline(always)]
fn project_at_point<const K: usize, const I: usize, const J: usize>(
    ia: &ArticulatedInertia,
    r: f64,
    c: &Motion,
    x: &Transform,
    out: &mut ArticulatedInertia,
    start: &ArticulatedInertia,
) -> Force {
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
    let cp = ia.c - (bk * r) * bk.transpose();
    // IAᵃ c.
    let (ci, cj) = (c.ang[I], c.ang[J]);
    let mut f_ang = Vec3::zeros();
    f_ang[I] = aii * ci + aij * cj + bi.dot(&c.lin);
    f_ang[J] = aij * ci + ajj * cj + bj.dot(&c.lin);
    let f = Force::new(f_ang, bi * ci + bj * cj + cp * c.lin);
    // Eᵀ M E: the I-J block of A, rows I and J of B (then its columns), all of C.
    let e = &x.rot;
    let (eii, eij, eji, ejj) = (e[(I, I)], e[(I, J)], e[(J, I)], e[(J, J)]);
    let (nii, nij) = (aii * eii + aij * eji, aii * eij + aij * ejj);
    let (nji, njj) = (aij * eii + ajj * eji, aij * eij + ajj * ejj);
    let mut an = Mat3::zeros();
    an[(I, I)] = eii * nii + eji * nji;
    an[(I, J)] = eii * nij + eji * njj;
    an[(J, I)] = an[(I, J)];
    an[(J, J)] = eij * nij + ejj * njj;
    let col = |row: &Vec3| {
        let mut o = *row;
        o[I] = row[I] * eii + row[J] * eji;
        o[J] = row[I] * eij + row[J] * ejj;
        o
    };
    let (bi, bj) = (col(&bi), col(&bj));
    let mut bn = Mat3::zeros();
    bn.set_row(I, &(bi * eii + bj * eji).transpose());
    bn.set_row(J, &(bi * eij + bj * ejj).transpose());
    let cn = similarity::<I, J>(e, &cp);
    add_translated(&an, &bn, &cn, &x.trans, out, Some(start));
    f
}

/// `Eᵀ M E`, `E` a rotation about the third axis (`I`, `J` the others).
#[inline(always)]
fn similarity<const I: usize, const J: usize>(e: &Mat3, m: &Mat3) -> Mat3 {
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
fn rotate<const I: usize, const J: usize, const BACK: bool>(e: &Mat3, v: &Vec3) -> Vec3 {
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
