//! The scalar of the per-call algorithms that run in lanes: `f64`, or [`F64x`], `N` independent
//! `f64`s (one per run of a campaign) computed together.
//!
//! An algorithm written once over `T: Real` computes, in lane `k` of `F64x<N>`, exactly what
//! it computes for `f64` on lane `k`'s inputs: every operation of [`F64x`] is the same IEEE
//! operation on each lane (`+ − × ÷` and negation; no fused multiply-add, which Rust never
//! forms by itself), and the one transcendental function, [`Real::sin_cos`], is libm's
//! `sincos` on each lane. The results are bit for bit the scalar ones; only the branches
//! differ, and those that depend on data ([`Real::all`]) are taken by a batch only when all
//! its lanes take them, so a batch where the lanes disagree is reported to its caller
//! (see the unrolled kernel of `satsim-satellite`) instead of computed otherwise.
//!
//! ```
//! use satsim_tree::real::{F64x, Real};
//! let x = F64x([0.1, 0.2, 0.3, 0.4]);
//! let y = x * x + F64x::splat(1.0) / x;
//! for k in 0..4 {
//!     assert_eq!(y.lane(k), x.lane(k) * x.lane(k) + 1.0 / x.lane(k)); // bit for bit
//! }
//! let (s, c) = x.sin_cos();
//! assert_eq!((s.lane(2), c.lane(2)), Real::sin_cos(0.3));
//! assert!(x.all(|v| v > 0.0) && !x.all(|v| v > 0.15));
//! ```

use nalgebra::{ClosedAddAssign, ClosedDivAssign, ClosedMulAssign, ClosedSubAssign, Scalar};
use num_traits::{One, Zero};
use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// A scalar of the lane-generic algorithms: `f64` (one run) or [`F64x`] (`N` runs).
pub trait Real:
    Scalar
    + Copy
    + Default
    + Zero
    + One
    + ClosedAddAssign
    + ClosedSubAssign
    + ClosedMulAssign
    + ClosedDivAssign
    + Neg<Output = Self>
{
    /// How many independent values one holds.
    const LANES: usize;
    /// Whether the algorithms keep their larger pieces out of line (`f64`: inlined into the
    /// passes they multiplied the instruction-cache misses, see `axis.rs`) or inline them
    /// (lanes: so that a caller compiled for wider vectors, `#[target_feature]`, compiles
    /// the whole kernel for them; an out-of-line piece would keep the baseline target's).
    const OUT_OF_LINE: bool;
    /// Every lane `x`.
    fn splat(x: f64) -> Self;
    /// Lane `k` (`k < LANES`).
    fn lane(self, k: usize) -> f64;
    /// The value whose lane `k` is `f(k)`.
    fn from_fn(f: impl FnMut(usize) -> f64) -> Self;
    /// `(sin x, cos x)` on each lane, by libm's `sincos` (< 1 ulp, the same on every lane
    /// as for one `f64`).
    fn sin_cos(self) -> (Self, Self);
    /// Whether `test` holds on every lane: the form of every data-dependent branch.
    fn all(self, test: impl Fn(f64) -> bool) -> bool;
    /// Whether `test` holds on every lane of `self` and `other` together.
    fn all_with(self, other: Self, test: impl Fn(f64, f64) -> bool) -> bool;
}

impl Real for f64 {
    const LANES: usize = 1;
    const OUT_OF_LINE: bool = true;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn lane(self, _k: usize) -> f64 {
        self
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f64) -> Self {
        f(0)
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        // libm's (musl's) sincos: inlined, and it leaves the rounding mode alone (see `axis.rs`).
        libm::sincos(self)
    }
    #[inline(always)]
    fn all(self, test: impl Fn(f64) -> bool) -> bool {
        test(self)
    }
    #[inline(always)]
    fn all_with(self, other: Self, test: impl Fn(f64, f64) -> bool) -> bool {
        test(self, other)
    }
}

/// `N` independent `f64`s, one per lane, every operation lane by lane (structure of arrays
/// over runs). Written as plain loops over `[f64; N]`, which the compiler turns into the
/// widest vector instructions the function it is compiled in allows: two-wide SSE2 on the
/// baseline x86-64 target, four-wide AVX2 (or eight-wide AVX-512) inside a function compiled
/// for those features, NEON on aarch64.
#[derive(Clone, Copy, PartialEq, Debug)]
#[repr(transparent)]
pub struct F64x<const N: usize>(pub [f64; N]);

impl<const N: usize> Default for F64x<N> {
    #[inline(always)]
    fn default() -> Self {
        Self([0.0; N])
    }
}

macro_rules! lanewise {
    ($Op:ident, $op:ident, $OpAssign:ident, $op_assign:ident, $sym_assign:tt) => {
        impl<const N: usize> $Op for F64x<N> {
            type Output = Self;
            #[inline(always)]
            fn $op(mut self, o: Self) -> Self {
                for k in 0..N {
                    self.0[k] $sym_assign o.0[k];
                }
                self
            }
        }
        impl<const N: usize> $OpAssign for F64x<N> {
            #[inline(always)]
            fn $op_assign(&mut self, o: Self) {
                for k in 0..N {
                    self.0[k] $sym_assign o.0[k];
                }
            }
        }
    };
}
lanewise!(Add, add, AddAssign, add_assign, +=);
lanewise!(Sub, sub, SubAssign, sub_assign, -=);
lanewise!(Mul, mul, MulAssign, mul_assign, *=);
lanewise!(Div, div, DivAssign, div_assign, /=);

impl<const N: usize> Neg for F64x<N> {
    type Output = Self;
    #[inline(always)]
    fn neg(mut self) -> Self {
        for x in &mut self.0 {
            *x = -*x;
        }
        self
    }
}

impl<const N: usize> Zero for F64x<N> {
    #[inline(always)]
    fn zero() -> Self {
        Self([0.0; N])
    }
    fn is_zero(&self) -> bool {
        self.0.iter().all(|&x| x == 0.0)
    }
}

impl<const N: usize> One for F64x<N> {
    #[inline(always)]
    fn one() -> Self {
        Self([1.0; N])
    }
}

impl<const N: usize> Real for F64x<N> {
    const LANES: usize = N;
    const OUT_OF_LINE: bool = false;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        Self([x; N])
    }
    #[inline(always)]
    fn lane(self, k: usize) -> f64 {
        self.0[k]
    }
    #[inline(always)]
    fn from_fn(f: impl FnMut(usize) -> f64) -> Self {
        Self(std::array::from_fn(f))
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        let (mut s, mut c) = ([0.0; N], [0.0; N]);
        for k in 0..N {
            (s[k], c[k]) = libm::sincos(self.0[k]);
        }
        (Self(s), Self(c))
    }
    #[inline(always)]
    fn all(self, test: impl Fn(f64) -> bool) -> bool {
        // Not short-circuiting: one branch for the batch, not one per lane.
        self.0.iter().fold(true, |ok, &x| ok & test(x))
    }
    #[inline(always)]
    fn all_with(self, other: Self, test: impl Fn(f64, f64) -> bool) -> bool {
        (0..N).fold(true, |ok, k| ok & test(self.0[k], other.0[k]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Vector3};

    /// nalgebra's generic products over lanes equal the `f64` products lane by lane, bit
    /// for bit (the same order of operations).
    #[test]
    fn matrix_products_are_lanewise() {
        let m =
            |k: usize| Matrix3::from_fn(|r, c| ((r * 3 + c + 1) as f64).sqrt() * (k + 1) as f64);
        let v = |k: usize| Vector3::new(0.1 * k as f64 - 0.7, 1.3, -2.0 / (k + 1) as f64);
        let ml: Matrix3<F64x<4>> = Matrix3::from_fn(|r, c| F64x::from_fn(|k| m(k)[(r, c)]));
        let vl: Vector3<F64x<4>> = Vector3::from_fn(|r, _| F64x::from_fn(|k| v(k)[r]));
        let out = ml * vl + ml.tr_mul(&vl).cross(&vl) * ml.trace();
        for k in 0..4 {
            let want = m(k) * v(k) + m(k).tr_mul(&v(k)).cross(&v(k)) * m(k).trace();
            for r in 0..3 {
                assert_eq!(out[r].lane(k).to_bits(), want[r].to_bits());
            }
        }
    }

    #[test]
    fn all_is_every_lane() {
        let x = F64x([1.0, f64::NAN, 2.0]);
        assert!(!x.all(|v| v > 0.0));
        assert!(x.all(|v| v.is_nan() || v > 0.0));
        assert!(F64x([3.0; 2]).all(f64::is_finite));
    }
}
