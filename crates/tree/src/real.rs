//! The scalar of the per-call algorithms that run in lanes: `f64`, or [`F64x`], `N` independent
//! `f64`s (one per run of a campaign) computed together.
//!
//! An algorithm written once over `T: Real` computes, in lane `k` of `F64x<N>`, exactly what
//! it computes for `f64` on lane `k`'s inputs: every operation of [`F64x`] is the same IEEE
//! operation on each lane (`+ − × ÷` and negation; no fused multiply-add, which Rust never
//! forms by itself), and the one transcendental function, [`Real::sin_cos`], gives libm's
//! `sincos` on each lane: where every lane is within `|x| ≲ π/4` it evaluates libm's own
//! polynomials (`k_sin`, `k_cos`) lane by lane, the same operations in the same order, which
//! the compiler vectorises; otherwise it calls `sincos` on each lane. The results are bit
//! for bit the scalar ones; only the branches
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
    /// Every lane `x`.
    fn splat(x: f64) -> Self;
    /// Lane `k` (`k < LANES`).
    fn lane(self, k: usize) -> f64;
    /// The value whose lane `k` is `f(k)`.
    fn from_fn(f: impl FnMut(usize) -> f64) -> Self;
    /// `(sin x, cos x)` on each lane, libm's `sincos` (< 1 ulp) bit for bit, the same on every
    /// lane as for one `f64`. `f64` calls it; [`F64x`], where every lane is within
    /// `|x| ≲ π/4` (libm reduces no argument there), evaluates libm's polynomials for that
    /// range (`k_sin(x, 0, 0)`, `k_cos(x, 0)`, and `(x, 1)` below `2⁻²⁷ √2`) lane by lane
    /// with the same constants and the same operations in the same order, which the compiler
    /// vectorises (four lanes in one AVX2 instruction) where one call per lane would keep it
    /// scalar; any other batch (an argument to reduce, or not finite) calls `sincos` on each
    /// lane.
    fn sin_cos(self) -> (Self, Self);
    /// Whether `test` holds on every lane: the form of every data-dependent branch.
    fn all(self, test: impl Fn(f64) -> bool) -> bool;
    /// Whether `test` holds on every lane of `self` and `other` together.
    fn all_with(self, other: Self, test: impl Fn(f64, f64) -> bool) -> bool;
}

impl Real for f64 {
    const LANES: usize = 1;
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
        // Every lane within π/4, on the bits and without branches per lane: `PIO4_BITS −
        // abs_bits(x)` is negative on the others (both are below 2⁶³), one lane-wise
        // subtraction, or-ed together.
        let outside = self.0.iter().fold(0, |acc, &x| {
            acc | (PIO4_BITS as i64).wrapping_sub(abs_bits(x) as i64)
        });
        if outside >= 0 {
            return self.sin_cos_pio4();
        }
        // Some lane needs its argument reduced (or is not finite): libm on each lane.
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

/// The bits of `|x|`.
#[inline(always)]
fn abs_bits(x: f64) -> u64 {
    x.to_bits() & !(1 << 63)
}

/// The largest `abs_bits` that libm's `sincos` computes without reducing its argument: a high
/// word `<= 0x3fe921fb` (`|x| ≲ π/4`).
const PIO4_BITS: u64 = 0x3fe9_21fb_ffff_ffff;
/// `abs_bits` below which libm's `sincos` returns `(x, 1)`: a high word `< 0x3e46a09e`
/// (`|x| < 2⁻²⁷ √2`).
const TINY_BITS: u64 = 0x3e46_a09e_0000_0000;

/// libm's polynomial coefficients, its literals digit for digit (more digits than an `f64`
/// holds: the bits are in the comments, checked by the tests).
#[allow(clippy::excessive_precision)]
mod coefficients {
    // libm's `k_sin` (FreeBSD's `__kernel_sin`): sin x ≈ x + S1 x³ + … + S6 x¹³ on [-π/4, π/4].
    pub const S1: f64 = -1.66666666666666324348e-01; // 0xBFC55555_55555549
    pub const S2: f64 = 8.33333333332248946124e-03; // 0x3F811111_1110F8A6
    pub const S3: f64 = -1.98412698298579493134e-04; // 0xBF2A01A0_19C161D5
    pub const S4: f64 = 2.75573137070700676789e-06; // 0x3EC71DE3_57B1FE7D
    pub const S5: f64 = -2.50507602534068634195e-08; // 0xBE5AE5E6_8A2B9CEB
    pub const S6: f64 = 1.58969099521155010221e-10; // 0x3DE5D93A_5ACFD57C
    // libm's `k_cos` (FreeBSD's `__kernel_cos`): cos x ≈ 1 − x²/2 + C1 x⁴ + … + C6 x¹⁴.
    pub const C1: f64 = 4.16666666666666019037e-02; // 0x3FA55555_5555554C
    pub const C2: f64 = -1.38888888888741095749e-03; // 0xBF56C16C_16C15177
    pub const C3: f64 = 2.48015872894767294178e-05; // 0x3EFA01A0_19CB1590
    pub const C4: f64 = -2.75573143513906633035e-07; // 0xBE927E4F_809C52AD
    pub const C5: f64 = 2.08757232129817482790e-09; // 0x3E21EE9E_BDB4B1C4
    pub const C6: f64 = -1.13596475577881948265e-11; // 0xBDA8FAE9_BE8838D4
}
use coefficients::*;

impl<const N: usize> F64x<N> {
    /// libm's `sincos` where every lane is within `|x| ≲ π/4` (`abs_bits(x) <= PIO4_BITS`),
    /// lane-wise and without branches: `k_sin(x, 0.0, 0)` and `k_cos(x, 0.0)`, the same
    /// operations in the same order, and `(x, 1.0)` selected on the lanes below `TINY_BITS`
    /// as libm returns them. The same bits as libm's on every lane.
    #[inline(always)]
    fn sin_cos_pio4(self) -> (Self, Self) {
        let k = Self::splat;
        let x = self;
        // k_sin(x, 0.0, 0).
        let z = x * x;
        let w = z * z;
        let r = k(S2) + z * (k(S3) + z * k(S4)) + z * w * (k(S5) + z * k(S6));
        let v = z * x;
        let mut s = x + v * (k(S1) + z * r);
        // k_cos(x, y) with y = 0.0, literally (`x * y` is ±0, and `z * r − (±0)` is `z * r`).
        let y = k(0.0);
        let z = x * x;
        let w = z * z;
        let r = z * (k(C1) + z * (k(C2) + z * k(C3))) + w * w * (k(C4) + z * (k(C5) + z * k(C6)));
        let hz = k(0.5) * z;
        let w = k(1.0) - hz;
        let mut c = w + (((k(1.0) - w) - hz) + (z * r - x * y));
        // |x| < 2⁻²⁷ √2: libm's (x, 1.0) (the polynomial would turn −0 into +0), selected on
        // the bits with a mask (all ones on those lanes), without branches.
        for i in 0..N {
            let tiny = ((abs_bits(x.0[i]) as i64).wrapping_sub(TINY_BITS as i64) >> 63) as u64;
            let select = |a: f64, b: f64| f64::from_bits(a.to_bits() & tiny | b.to_bits() & !tiny);
            s.0[i] = select(x.0[i], s.0[i]);
            c.0[i] = select(1.0, c.0[i]);
        }
        (s, c)
    }
}

/// nalgebra's 3×3 products, the same arithmetic in the same order, always inlined.
/// nalgebra's generic products are ordinary functions that the optimiser may keep out of
/// line; out of line, a kernel compiled for wider vectors (`#[target_feature]`) calls them as
/// the baseline target compiled them, with its operands through memory, and which calls it
/// keeps moves from one build to the next. Bit for bit the same: tested below.
pub mod mat3 {
    use super::Real;
    use nalgebra::{Matrix3, Vector3};

    /// `m v`. nalgebra's `gemv`, column by column: `((m₀ x₀ + m₁ x₁) + m₂ x₂)` per row (its
    /// factors `1` are exact).
    #[inline(always)]
    pub fn mul<T: Real>(m: &Matrix3<T>, v: &Vector3<T>) -> Vector3<T> {
        Vector3::new(
            m[(0, 0)] * v[0] + m[(0, 1)] * v[1] + m[(0, 2)] * v[2],
            m[(1, 0)] * v[0] + m[(1, 1)] * v[1] + m[(1, 2)] * v[2],
            m[(2, 0)] * v[0] + m[(2, 1)] * v[1] + m[(2, 2)] * v[2],
        )
    }

    /// `mᵀ v`. nalgebra's `tr_mul`: a dot product per column, `(a₀ b₀ + a₁ b₁) + a₂ b₂`.
    #[inline(always)]
    pub fn tr_mul<T: Real>(m: &Matrix3<T>, v: &Vector3<T>) -> Vector3<T> {
        Vector3::new(
            m[(0, 0)] * v[0] + m[(1, 0)] * v[1] + m[(2, 0)] * v[2],
            m[(0, 1)] * v[0] + m[(1, 1)] * v[1] + m[(2, 1)] * v[2],
            m[(0, 2)] * v[0] + m[(1, 2)] * v[1] + m[(2, 2)] * v[2],
        )
    }

    /// `a b`: nalgebra's `gemm`, [`mul`] column by column.
    #[inline(always)]
    pub fn mul_mat<T: Real>(a: &Matrix3<T>, b: &Matrix3<T>) -> Matrix3<T> {
        Matrix3::from_columns(&[
            mul(a, &Vector3::new(b[(0, 0)], b[(1, 0)], b[(2, 0)])),
            mul(a, &Vector3::new(b[(0, 1)], b[(1, 1)], b[(2, 1)])),
            mul(a, &Vector3::new(b[(0, 2)], b[(1, 2)], b[(2, 2)])),
        ])
    }

    /// `aᵀ b`: nalgebra's `tr_mul`, [`tr_mul`] column by column.
    #[inline(always)]
    pub fn tr_mul_mat<T: Real>(a: &Matrix3<T>, b: &Matrix3<T>) -> Matrix3<T> {
        Matrix3::from_columns(&[
            tr_mul(a, &Vector3::new(b[(0, 0)], b[(1, 0)], b[(2, 0)])),
            tr_mul(a, &Vector3::new(b[(0, 1)], b[(1, 1)], b[(2, 1)])),
            tr_mul(a, &Vector3::new(b[(0, 2)], b[(1, 2)], b[(2, 2)])),
        ])
    }

    /// `a × b`, as nalgebra's `cross`.
    #[inline(always)]
    pub fn cross<T: Real>(a: &Vector3<T>, b: &Vector3<T>) -> Vector3<T> {
        Vector3::new(
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        )
    }

    /// `u vᵀ`. nalgebra's `gemm` of a column by a row: `uᵢ vⱼ`.
    #[inline(always)]
    pub fn outer<T: Real>(u: &Vector3<T>, v: &Vector3<T>) -> Matrix3<T> {
        Matrix3::from_fn(|i, j| u[i] * v[j])
    }
}

#[cfg(test)]
mod tests {
    /// `mat3`'s inlined products are nalgebra's bit for bit, on lanes of random values.
    #[test]
    fn mat3_products_are_nalgebras() {
        use super::mat3;
        use nalgebra::{Matrix3, Vector3};
        let mut rng = crate::samples::SplitMix(7);
        let mut r = || {
            let x = rng.range(-2.0, 2.0);
            x * 10f64.powi((x * 40.0) as i32)
        };
        let bits3 = |v: &Vector3<F64x<4>>, w: &[Vector3<f64>; 4]| {
            (0..4).all(|k| (0..3).all(|i| v[i].0[k].to_bits() == w[k][i].to_bits()))
        };
        for _ in 0..2000 {
            let m: [Matrix3<f64>; 4] = std::array::from_fn(|_| Matrix3::from_fn(|_, _| r()));
            let a: [Vector3<f64>; 4] = std::array::from_fn(|_| Vector3::from_fn(|_, _| r()));
            let b: [Vector3<f64>; 4] = std::array::from_fn(|_| Vector3::from_fn(|_, _| r()));
            let ml = Matrix3::from_fn(|i, j| F64x(std::array::from_fn(|k| m[k][(i, j)])));
            let al = Vector3::from_fn(|i, _| F64x(std::array::from_fn(|k| a[k][i])));
            let bl = Vector3::from_fn(|i, _| F64x(std::array::from_fn(|k| b[k][i])));
            assert!(bits3(
                &mat3::mul(&ml, &al),
                &std::array::from_fn(|k| m[k] * a[k])
            ));
            assert!(bits3(
                &mat3::tr_mul(&ml, &al),
                &std::array::from_fn(|k| m[k].tr_mul(&a[k]))
            ));
            assert!(bits3(
                &mat3::cross(&al, &bl),
                &std::array::from_fn(|k| a[k].cross(&b[k]))
            ));
            let m2: [Matrix3<f64>; 4] = std::array::from_fn(|_| Matrix3::from_fn(|_, _| r()));
            let ml2 = Matrix3::from_fn(|i, j| F64x(std::array::from_fn(|k| m2[k][(i, j)])));
            let (p, tp) = (mat3::mul_mat(&ml, &ml2), mat3::tr_mul_mat(&ml, &ml2));
            for k in 0..4 {
                let (want, want_t) = (m[k] * m2[k], m[k].tr_mul(&m2[k]));
                assert!((0..9).all(|e| p[e].0[k].to_bits() == want[e].to_bits()));
                assert!((0..9).all(|e| tp[e].0[k].to_bits() == want_t[e].to_bits()));
            }
            let o = mat3::outer(&al, &bl);
            for k in 0..4 {
                let want = a[k] * b[k].transpose();
                assert!((0..9).all(|e| o[e].0[k].to_bits() == want[e].to_bits()));
            }
        }
    }
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

    /// A deterministic xorshift64* generator for the `sin_cos` tests.
    struct XorShift(u64);

    impl XorShift {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
        }
        /// Uniform in `[0, n)` (`n` small).
        fn below(&mut self, n: u64) -> u64 {
            self.next() % n
        }
        /// Uniform in `[-a, a)`.
        fn symmetric(&mut self, a: f64) -> f64 {
            a * ((self.next() >> 11) as f64 / (1u64 << 52) as f64 - 1.0)
        }
        /// `x` or `-x`, at random.
        fn signed(&mut self, x: f64) -> f64 {
            if self.next() >> 63 == 1 { -x } else { x }
        }
    }

    /// The edges of libm's branches: `|x| ≲ π/4` (the high word `0x3fe921fb`, and π/4 itself),
    /// `|x| < 2⁻²⁷ √2` (the high word `0x3e46a09e`), zero, subnormals, the least normal, and
    /// what is not finite; each with its neighbours (`from_bits ± 1, 2`).
    fn edges() -> Vec<f64> {
        let pio4 = std::f64::consts::FRAC_PI_4.to_bits();
        let mut centres = vec![
            pio4,
            PIO4_BITS,
            PIO4_BITS + 1,
            0x3fe9_21fb_0000_0000,
            TINY_BITS,
            0x3e46_a09d_ffff_ffff,
            0x3e40_0000_0000_0000, // 2⁻²⁷
            0x0010_0000_0000_0000, // the least normal
            0x000f_ffff_ffff_ffff, // the largest subnormal
            2,
            0x3ff0_0000_0000_0000,
            std::f64::consts::FRAC_PI_2.to_bits(),
        ];
        centres.extend([0.75f64, 0.78, 0.785, 0.79, 0.5, 1e-300, 1e300].map(f64::to_bits));
        let mut xs: Vec<f64> = centres
            .iter()
            .flat_map(|&b| (b.saturating_sub(2)..=b + 2).map(f64::from_bits))
            .collect();
        xs.extend([0.0, f64::INFINITY, f64::NAN, f64::MAX, f64::MIN_POSITIVE]);
        let negated: Vec<f64> = xs.iter().map(|x| -x).collect();
        xs.extend(negated);
        xs
    }

    /// One random argument: in `|x| ≲ π/4` when `inside`, else anywhere, edges often.
    fn argument(rng: &mut XorShift, edges: &[f64], inside: bool) -> f64 {
        let x = match rng.below(if inside { 4 } else { 7 }) {
            0 => edges[rng.below(edges.len() as u64) as usize],
            // Every magnitude from the subnormals to about 1: random exponent and mantissa.
            // (Half of them from 2⁻³¹ up, the polynomials' range.)
            1 => {
                let e = if rng.below(2) == 0 {
                    0x3e0 + rng.below(0x1f)
                } else {
                    rng.below(0x3ff)
                };
                f64::from_bits((e << 52) | (rng.next() >> 12))
            }
            2 => rng.symmetric(std::f64::consts::FRAC_PI_4),
            3 => rng.symmetric(0.7),
            4 => rng.symmetric(0.8),
            5 => rng.symmetric(10.0),
            _ => f64::from_bits(rng.next()),
        };
        let x = rng.signed(x);
        if inside && abs_bits(x) > PIO4_BITS {
            rng.symmetric(std::f64::consts::FRAC_PI_4)
        } else {
            x
        }
    }

    /// `F64x::<N>::sin_cos` equals libm's `sincos` on each lane, bit for bit, over `batches`
    /// random batches (half with every lane within π/4, the rest mixed). (With AVX2: the
    /// unrolled kernel's tests in `satsim-satellite`.)
    fn sin_cos_is_libm<const N: usize>(batches: usize) {
        let edges = edges();
        let mut rng = XorShift(0x9e37_79b9_7f4a_7c15 ^ N as u64);
        let (mut inside, mut tiny) = (0, 0);
        for b in 0..batches {
            let x = F64x::<N>::from_fn(|_| argument(&mut rng, &edges, b % 2 == 0));
            let (s, c) = x.sin_cos();
            for k in 0..N {
                let (ws, wc) = libm::sincos(x.0[k]);
                assert_eq!(
                    (s.0[k].to_bits(), c.0[k].to_bits()),
                    (ws.to_bits(), wc.to_bits()),
                    "lane {k} of {x:?}"
                );
            }
            if x.all(|v| abs_bits(v) <= PIO4_BITS) {
                inside += 1;
                tiny += usize::from(!x.all(|v| abs_bits(v) >= TINY_BITS));
            }
        }
        // The lane-wise path taken by at least the batches drawn within π/4, with tiny lanes.
        assert!(
            inside >= batches / 2 && tiny > batches / 20,
            "{inside} {tiny}"
        );
    }

    #[test]
    fn sin_cos_is_libm_on_4_lanes() {
        sin_cos_is_libm::<4>(200_000);
    }

    #[test]
    fn sin_cos_is_libm_on_2_and_8_lanes() {
        sin_cos_is_libm::<2>(200_000);
        sin_cos_is_libm::<8>(100_000);
    }

    /// The polynomials' coefficients are libm's (the bits in `k_sin.rs` and `k_cos.rs`).
    #[test]
    fn coefficients_are_libm() {
        let bits = [S1, S2, S3, S4, S5, S6, C1, C2, C3, C4, C5, C6].map(f64::to_bits);
        assert_eq!(
            bits,
            [
                0xbfc5_5555_5555_5549,
                0x3f81_1111_1110_f8a6,
                0xbf2a_01a0_19c1_61d5,
                0x3ec7_1de3_57b1_fe7d,
                0xbe5a_e5e6_8a2b_9ceb,
                0x3de5_d93a_5acf_d57c,
                0x3fa5_5555_5555_554c,
                0xbf56_c16c_16c1_5177,
                0x3efa_01a0_19cb_1590,
                0xbe92_7e4f_809c_52ad,
                0x3e21_ee9e_bdb4_b1c4,
                0xbda8_fae9_be88_38d4,
            ]
        );
    }

    #[test]
    fn all_is_every_lane() {
        let x = F64x([1.0, f64::NAN, 2.0]);
        assert!(!x.all(|v| v > 0.0));
        assert!(x.all(|v| v.is_nan() || v > 0.0));
        assert!(F64x([3.0; 2]).all(f64::is_finite));
    }
}
