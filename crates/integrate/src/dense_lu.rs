//! LU factorisation with partial pivoting of small dense matrices: the stage system's
//! matrices once the states a Jacobian row ties to a single other state are eliminated
//! (`stage_matrices.rs`), `γ/h - J' - K'/(γ/h)` real and its complex counterpart, which are
//! not shifts of one matrix and so have no Hessenberg shortcut. The complex one keeps its
//! real and imaginary parts apart so that the column updates vectorise.
//!
//! A matrix that is block lower triangular (the stage system's states ordered so that each
//! group reads only itself and the groups before it: an orbit that no attitude moves, ahead
//! of the attitude its gravity gradient turns) is factored block by block: each diagonal
//! block alone, the blocks below it kept as they are for the solve's block forward
//! substitution. One block (the default) is the plain factorisation, operation for operation.
//!
//! Written here rather than taken from faer, whose blocked, recursive factorisation is built
//! for large matrices: on the 49 states of the flexible deployment these plain loops executed
//! about as many instructions as faer 0.24 for the pair (417 k against about 420 k,
//! callgrind; faer's are AVX2, these the baseline's) and took the whole Radau IIA run from
//! 0.080 s to 0.071 s: less dispatch and recursion around small blocks.

use crate::common::all_finite;

/// A factorisation's `factor` (the instance the process runs on), `factor_on` (the one
/// asked for) and its AVX2 instance, around the type's `factor_in`: the same operations, so
/// the same bits (`crate::wide`).
macro_rules! factor_instances {
    () => {
        /// Factors the matrix set; false when a pivot is zero or anything is not finite.
        pub fn factor(&mut self) -> bool {
            self.factor_on(crate::wide::avx2())
        }

        /// [`Self::factor`] on the instance compiled for AVX2 where `wide` and the CPU has
        /// it, else on the baseline's.
        #[allow(unsafe_code)]
        pub fn factor_on(&mut self, wide: bool) -> bool {
            #[cfg(target_arch = "x86_64")]
            if wide && crate::wide::cpu_avx2() {
                // SAFETY: `factor_avx2` requires only a CPU with AVX2, which `cpu_avx2` found.
                return unsafe { self.factor_avx2() };
            }
            self.factor_in()
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        fn factor_avx2(&mut self) -> bool {
            self.factor_in()
        }
    };
}

/// `A = P L U` of a real `n × n` matrix, column-major, in place; `piv[k]` is the row swapped
/// with row `k` at step `k`, and `L`'s multipliers keep the rows of their own step
/// (LINPACK's `dgefa`, where LAPACK's `getrf` swaps them too). `U`'s diagonal is kept as its
/// reciprocals, so that the back substitution multiplies: a division's latency is several
/// multiplications' on its chain of dependent steps.
#[derive(Clone, Debug)]
pub(crate) struct RealLu {
    n: usize,
    a: Vec<f64>,
    piv: Vec<usize>,
    /// The diagonal blocks' bounds, `[0, …, n]`.
    bounds: Vec<usize>,
}

impl RealLu {
    /// Storage for matrices up to `cap × cap`; the first is `cap × cap`, one block.
    pub fn new(cap: usize) -> Self {
        Self {
            n: cap,
            a: vec![0.0; cap * cap],
            piv: vec![0; cap],
            bounds: vec![0, cap],
        }
    }

    /// The next matrix is block lower triangular with the diagonal blocks `bounds[b] ..
    /// bounds[b + 1]` (`bounds` from 0 to its size, at most the capacity): zero above them.
    pub fn start_blocks(&mut self, bounds: &[usize]) {
        let n = *bounds.last().expect("bounds");
        assert!(n <= self.piv.len(), "dimension {n} over the capacity");
        assert!(bounds[0] == 0 && bounds.windows(2).all(|w| w[0] < w[1] || n == 0));
        self.n = n;
        self.bounds.clear();
        self.bounds.extend_from_slice(bounds);
    }

    /// Entry `(r, c)` of the matrix to factor.
    #[cfg(test)]
    pub fn set(&mut self, r: usize, c: usize, v: f64) {
        self.a[c * self.n + r] = v;
    }

    /// The matrix to factor, column-major (`n × n`).
    pub fn matrix_mut(&mut self) -> &mut [f64] {
        &mut self.a[..self.n * self.n]
    }

    factor_instances!();

    #[inline(always)]
    fn factor_in(&mut self) -> bool {
        let n = self.n;
        if !all_finite(&self.a[..n * n]) {
            return false;
        }
        for b in 0..self.bounds.len() - 1 {
            let (s, e) = (self.bounds[b], self.bounds[b + 1]);
            for k in s..e {
                let col = &self.a[k * n..(k + 1) * n];
                let mut p = k;
                for i in k + 1..e {
                    if col[i].abs() > col[p].abs() {
                        p = i;
                    }
                }
                self.piv[k] = p;
                if col[p] == 0.0 {
                    return false;
                }
                // The rows swap in the columns from `k` on only (LINPACK's `dgefa`): the
                // multipliers of the earlier steps keep their rows, and the solve swaps the
                // right side just before each step's elimination (`dgesl`), which gives
                // every entry the operations and the bits of swapping whole rows first
                // (tested). The blocks to the left keep their order too: the solve applies
                // them before the block's pivots.
                if p != k {
                    for j in k..e {
                        self.a.swap(j * n + k, j * n + p);
                    }
                }
                let (head, tail) = self.a[..e * n].split_at_mut((k + 1) * n);
                let colk = &mut head[k * n..k * n + e];
                let inv = 1.0 / colk[k];
                colk[k] = inv;
                for v in &mut colk[k + 1..] {
                    *v *= inv;
                }
                for colj in tail.chunks_exact_mut(n) {
                    let akj = colj[k];
                    if akj != 0.0 {
                        for (aij, lik) in colj[k + 1..e].iter_mut().zip(&colk[k + 1..]) {
                            *aij -= lik * akj;
                        }
                    }
                }
            }
        }
        true
    }

    /// Overwrites `b` with `A⁻¹ b`.
    pub fn solve(&self, b: &mut [f64]) {
        self.solve_on(crate::wide::avx2(), b);
    }

    /// [`Self::solve`] on the instance compiled for AVX2 where `wide` and the CPU has it: the
    /// same bits.
    #[allow(unsafe_code)]
    pub fn solve_on(&self, wide: bool, b: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if wide && crate::wide::cpu_avx2() {
            // SAFETY: `solve_avx2` requires only a CPU with AVX2, which `cpu_avx2` found.
            unsafe { self.solve_avx2(b) };
            return;
        }
        self.solve_in(b);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn solve_avx2(&self, b: &mut [f64]) {
        self.solve_in(b);
    }

    #[inline(always)]
    fn solve_in(&self, b: &mut [f64]) {
        let n = self.n;
        for w in self.bounds.windows(2) {
            let (s, e) = (w[0], w[1]);
            // The blocks to the left, solved: `b_B − A[B, ..s] x[..s]`.
            let (x, bb) = b[..e].split_at_mut(s);
            for (j, &xj) in x.iter().enumerate() {
                if xj != 0.0 {
                    let col = &self.a[j * n + s..j * n + e];
                    for (bi, aij) in bb.iter_mut().zip(col) {
                        *bi -= aij * xj;
                    }
                }
            }
            for k in s..e {
                b.swap(k, self.piv[k]);
                let bk = b[k];
                if bk != 0.0 {
                    let col = &self.a[k * n..k * n + e];
                    for (bi, lik) in b[k + 1..e].iter_mut().zip(&col[k + 1..]) {
                        *bi -= lik * bk;
                    }
                }
            }
            for k in (s..e).rev() {
                let col = &self.a[k * n..(k + 1) * n];
                b[k] *= col[k];
                let bk = b[k];
                for (bi, uik) in b[s..k].iter_mut().zip(&col[s..k]) {
                    *bi -= uik * bk;
                }
            }
        }
    }
}

/// The same for a complex matrix, its real and imaginary parts apart (`U`'s diagonal as its
/// reciprocals too). The pivot is the entry of largest `|re| + |im|` (LINPACK's `cabs1`).
#[derive(Clone, Debug)]
pub(crate) struct ComplexLu {
    n: usize,
    re: Vec<f64>,
    im: Vec<f64>,
    piv: Vec<usize>,
    /// The diagonal blocks' bounds, `[0, …, n]`.
    bounds: Vec<usize>,
}

impl ComplexLu {
    /// Storage for matrices up to `cap × cap`; the first is `cap × cap`, one block.
    pub fn new(cap: usize) -> Self {
        Self {
            n: cap,
            re: vec![0.0; cap * cap],
            im: vec![0.0; cap * cap],
            piv: vec![0; cap],
            bounds: vec![0, cap],
        }
    }

    /// The next matrix is block lower triangular with the diagonal blocks `bounds[b] ..
    /// bounds[b + 1]` (`bounds` from 0 to its size, at most the capacity): zero above them.
    pub fn start_blocks(&mut self, bounds: &[usize]) {
        let n = *bounds.last().expect("bounds");
        assert!(n <= self.piv.len(), "dimension {n} over the capacity");
        assert!(bounds[0] == 0 && bounds.windows(2).all(|w| w[0] < w[1] || n == 0));
        self.n = n;
        self.bounds.clear();
        self.bounds.extend_from_slice(bounds);
    }

    /// Entry `(r, c)` of the matrix to factor, `re + i im`.
    #[cfg(test)]
    pub fn set(&mut self, r: usize, c: usize, re: f64, im: f64) {
        self.re[c * self.n + r] = re;
        self.im[c * self.n + r] = im;
    }

    /// The matrix to factor, real and imaginary parts, column-major (`n × n`).
    pub fn matrix_mut(&mut self) -> (&mut [f64], &mut [f64]) {
        let nn = self.n * self.n;
        (&mut self.re[..nn], &mut self.im[..nn])
    }

    factor_instances!();

    #[inline(always)]
    fn factor_in(&mut self) -> bool {
        let n = self.n;
        if !(all_finite(&self.re[..n * n]) && all_finite(&self.im[..n * n])) {
            return false;
        }
        for b in 0..self.bounds.len() - 1 {
            let (s, e) = (self.bounds[b], self.bounds[b + 1]);
            for k in s..e {
                let (cr, ci) = (&self.re[k * n..(k + 1) * n], &self.im[k * n..(k + 1) * n]);
                let mut p = k;
                let mut best = cr[k].abs() + ci[k].abs();
                for i in k + 1..e {
                    let m = cr[i].abs() + ci[i].abs();
                    if m > best {
                        (p, best) = (i, m);
                    }
                }
                self.piv[k] = p;
                if best == 0.0 {
                    return false;
                }
                // The rows swap in the columns from `k` on, as the real one's.
                if p != k {
                    for j in k..e {
                        self.re.swap(j * n + k, j * n + p);
                        self.im.swap(j * n + k, j * n + p);
                    }
                }
                let (hr, tr) = self.re[..e * n].split_at_mut((k + 1) * n);
                let (hi, ti) = self.im[..e * n].split_at_mut((k + 1) * n);
                let (lr, li) = (&mut hr[k * n..k * n + e], &mut hi[k * n..k * n + e]);
                // 1 / pivot
                let d = lr[k] * lr[k] + li[k] * li[k];
                let (ir, ii) = (lr[k] / d, -li[k] / d);
                (lr[k], li[k]) = (ir, ii);
                for (vr, vi) in lr[k + 1..].iter_mut().zip(&mut li[k + 1..]) {
                    let (r, i) = (*vr, *vi);
                    *vr = r * ir - i * ii;
                    *vi = r * ii + i * ir;
                }
                for (cjr, cji) in tr.chunks_exact_mut(n).zip(ti.chunks_exact_mut(n)) {
                    let (ar, ai) = (cjr[k], cji[k]);
                    if ar != 0.0 || ai != 0.0 {
                        let it = cjr[k + 1..e]
                            .iter_mut()
                            .zip(&mut cji[k + 1..e])
                            .zip(lr[k + 1..].iter().zip(&li[k + 1..]));
                        for ((xr, xi), (l_r, l_i)) in it {
                            *xr -= l_r * ar - l_i * ai;
                            *xi -= l_r * ai + l_i * ar;
                        }
                    }
                }
            }
        }
        true
    }

    /// Overwrites `(br, bi)` with `A⁻¹ (br + i bi)`.
    pub fn solve(&self, br: &mut [f64], bi: &mut [f64]) {
        self.solve_on(crate::wide::avx2(), br, bi);
    }

    /// [`Self::solve`] on the instance compiled for AVX2 where `wide` and the CPU has it: the
    /// same bits.
    #[allow(unsafe_code)]
    pub fn solve_on(&self, wide: bool, br: &mut [f64], bi: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if wide && crate::wide::cpu_avx2() {
            // SAFETY: `solve_avx2` requires only a CPU with AVX2, which `cpu_avx2` found.
            unsafe { self.solve_avx2(br, bi) };
            return;
        }
        self.solve_in(br, bi);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn solve_avx2(&self, br: &mut [f64], bi: &mut [f64]) {
        self.solve_in(br, bi);
    }

    #[inline(always)]
    fn solve_in(&self, br: &mut [f64], bi: &mut [f64]) {
        let n = self.n;
        // `b -= x · column` over `rows`, the slices zipped so that the loop has no index
        // checks (the same operations as indexed, so the same bits).
        let sub = |br: &mut [f64],
                   bi: &mut [f64],
                   j: usize,
                   rows: std::ops::Range<usize>,
                   (xr, xi): (f64, f64)| {
            let col = self.re[j * n..(j + 1) * n][rows.clone()]
                .iter()
                .zip(&self.im[j * n..(j + 1) * n][rows.clone()]);
            for ((vr, vi), (cr, ci)) in br[rows.clone()].iter_mut().zip(&mut bi[rows]).zip(col) {
                *vr -= cr * xr - ci * xi;
                *vi -= cr * xi + ci * xr;
            }
        };
        for w in self.bounds.windows(2) {
            let (s, e) = (w[0], w[1]);
            // The blocks to the left, solved: `b_B − A[B, ..s] x[..s]`.
            for j in 0..s {
                let x = (br[j], bi[j]);
                if x != (0.0, 0.0) {
                    sub(br, bi, j, s..e, x);
                }
            }
            for k in s..e {
                br.swap(k, self.piv[k]);
                bi.swap(k, self.piv[k]);
                let x = (br[k], bi[k]);
                if x != (0.0, 0.0) {
                    sub(br, bi, k, k + 1..e, x);
                }
            }
            for k in (s..e).rev() {
                let (cr, ci) = (self.re[k * n + k], self.im[k * n + k]);
                let (xr, xi) = (br[k], bi[k]);
                let y = (xr * cr - xi * ci, xr * ci + xi * cr);
                (br[k], bi[k]) = y;
                sub(br, bi, k, s..k, y);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hessenberg::tests::entries;

    #[test]
    fn real_lu_solves_to_rounding_and_pivots() {
        for n in [1, 2, 7, 49] {
            let mut next = entries(n as u64);
            let a: Vec<f64> = (0..n * n).map(|_| next()).collect();
            let x: Vec<f64> = (0..n).map(|_| next()).collect();
            let mut lu = RealLu::new(n);
            for c in 0..n {
                for r in 0..n {
                    lu.set(r, c, a[c * n + r]);
                }
            }
            // Zero the (0, 0) entry: the first step must pivot.
            lu.set(0, 0, 0.0);
            let mut b: Vec<f64> = (0..n)
                .map(|r| {
                    (0..n)
                        .map(|c| if r + c == 0 { 0.0 } else { a[c * n + r] * x[c] })
                        .sum()
                })
                .collect();
            if n == 1 {
                lu.set(0, 0, 2.0);
                b[0] = 2.0 * x[0];
            }
            assert!(lu.factor());
            lu.solve(&mut b);
            let err = b
                .iter()
                .zip(&x)
                .map(|(u, v)| (u - v).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-11, "n = {n}: {err:e}");
        }
    }

    #[test]
    fn complex_lu_solves_to_rounding() {
        for n in [1, 3, 49] {
            let mut next = entries(100 + n as u64);
            let (ar, ai): (Vec<f64>, Vec<f64>) = (0..n * n).map(|_| (next(), next())).unzip();
            let (xr, xi): (Vec<f64>, Vec<f64>) = (0..n).map(|_| (next(), next())).unzip();
            let mut lu = ComplexLu::new(n);
            let (mut br, mut bi) = (vec![0.0; n], vec![0.0; n]);
            for c in 0..n {
                for r in 0..n {
                    let (p, q) = (ar[c * n + r], ai[c * n + r]);
                    lu.set(r, c, p, q);
                    br[r] += p * xr[c] - q * xi[c];
                    bi[r] += p * xi[c] + q * xr[c];
                }
            }
            assert!(lu.factor());
            lu.solve(&mut br, &mut bi);
            let err = (0..n)
                .map(|i| (br[i] - xr[i]).abs().max((bi[i] - xi[i]).abs()))
                .fold(0.0, f64::max);
            assert!(err < 1e-11, "n = {n}: {err:e}");
        }
    }

    #[test]
    fn block_lower_triangular_matrices_factor_block_by_block() {
        // Blocks 0..2, 2..3, 3..7, the first diagonal entry of the two larger ones zero so
        // that they pivot within the block; the entries above the blocks zero.
        let (n, bounds) = (7, [0, 2, 3, 7]);
        let block = |i: usize| bounds.iter().rposition(|&b| b <= i).expect("block");
        let mut next = entries(77);
        let a: Vec<f64> = (0..n * n)
            .map(|k| {
                let (r, c) = (k % n, k / n);
                let v = next();
                if block(c) > block(r) || (r == c && (r == 0 || r == 3)) {
                    0.0
                } else {
                    v
                }
            })
            .collect();
        let (xr, xi): (Vec<f64>, Vec<f64>) = (0..n).map(|_| (next(), next())).unzip();
        let mut real = RealLu::new(n);
        let mut complex = ComplexLu::new(n);
        real.start_blocks(&bounds);
        complex.start_blocks(&bounds);
        let (mut b, mut br, mut bi) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for c in 0..n {
            for r in 0..n {
                let v = a[c * n + r];
                real.set(r, c, v);
                // The complex matrix: a (1 + 0.5 i).
                complex.set(r, c, v, 0.5 * v);
                b[r] += v * xr[c];
                br[r] += v * xr[c] - 0.5 * v * xi[c];
                bi[r] += v * xi[c] + 0.5 * v * xr[c];
            }
        }
        assert!(real.factor() && complex.factor());
        real.solve(&mut b);
        complex.solve(&mut br, &mut bi);
        for i in 0..n {
            assert!(
                (b[i] - xr[i]).abs() < 1e-12,
                "real, {i}: {} against {}",
                b[i],
                xr[i]
            );
            assert!(
                (br[i] - xr[i]).abs() < 1e-12 && (bi[i] - xi[i]).abs() < 1e-12,
                "complex, {i}"
            );
        }
        // A block whose own part is singular is refused, though the whole matrix is not:
        // the blocks are factored alone.
        let mut real = RealLu::new(2);
        real.start_blocks(&[0, 1, 2]);
        real.set(0, 0, 0.0);
        real.set(1, 0, 1.0);
        real.set(1, 1, 1.0);
        assert!(!real.factor());
    }

    #[test]
    fn singular_or_non_finite_matrices_are_refused() {
        let mut lu = RealLu::new(2);
        lu.set(0, 0, 1.0);
        lu.set(0, 1, 2.0);
        lu.set(1, 0, 2.0);
        lu.set(1, 1, 4.0);
        assert!(!lu.factor());
        let mut lu = RealLu::new(2);
        lu.set(0, 0, f64::NAN);
        lu.set(1, 1, 1.0);
        assert!(!lu.factor());
        let mut lu = ComplexLu::new(2);
        lu.set(0, 0, 1.0, 1.0);
        lu.set(0, 1, 2.0, 2.0);
        lu.set(1, 0, 1.0, 0.0);
        lu.set(1, 1, 2.0, 0.0);
        assert!(!lu.factor());
    }

    /// The factorisation and solve with the rows swapped across the whole block (LAPACK's
    /// order, as `getrf` and `getrs`), operation for operation otherwise.
    /// `(re, im)` column-major `n × n`; `im` `None` for a real matrix.
    /// Returns the factors (`U`'s diagonal as reciprocals) and the pivots, `None` where
    /// singular, after solving `(br, bi)` with them.
    #[allow(clippy::type_complexity)]
    fn plain_solve(
        n: usize,
        bounds: &[usize],
        (mut re, mut im): (Vec<f64>, Option<Vec<f64>>),
        (br, bi): (&mut [f64], &mut [f64]),
    ) -> Option<(Vec<f64>, Vec<f64>, Vec<usize>)> {
        let cplx = im.is_some();
        let mut imv = im.take().unwrap_or_else(|| vec![0.0; n * n]);
        let mut piv = vec![0; n];
        for w in bounds.windows(2) {
            let (s, e) = (w[0], w[1]);
            for k in s..e {
                let mut p = k;
                let mut best = re[k * n + k].abs() + imv[k * n + k].abs();
                for i in k + 1..e {
                    let m = re[k * n + i].abs() + imv[k * n + i].abs();
                    if m > best {
                        (p, best) = (i, m);
                    }
                }
                piv[k] = p;
                if best == 0.0 {
                    return None;
                }
                for j in s..e {
                    re.swap(j * n + k, j * n + p);
                    imv.swap(j * n + k, j * n + p);
                }
                let (pr, pi) = (re[k * n + k], imv[k * n + k]);
                let (ir, ii) = if cplx {
                    let d = pr * pr + pi * pi;
                    (pr / d, -pi / d)
                } else {
                    (1.0 / pr, 0.0)
                };
                (re[k * n + k], imv[k * n + k]) = (ir, ii);
                for i in k + 1..e {
                    let (r, m) = (re[k * n + i], imv[k * n + i]);
                    if cplx {
                        re[k * n + i] = r * ir - m * ii;
                        imv[k * n + i] = r * ii + m * ir;
                    } else {
                        re[k * n + i] = r * ir;
                    }
                }
                for j in k + 1..e {
                    let (ar, ai) = (re[j * n + k], imv[j * n + k]);
                    if ar != 0.0 || ai != 0.0 {
                        for i in k + 1..e {
                            let (lr, li) = (re[k * n + i], imv[k * n + i]);
                            if cplx {
                                re[j * n + i] -= lr * ar - li * ai;
                                imv[j * n + i] -= lr * ai + li * ar;
                            } else {
                                re[j * n + i] -= lr * ar;
                            }
                        }
                    }
                }
            }
        }
        let sub = |br: &mut [f64], bi: &mut [f64], j: usize, i: usize, (xr, xi): (f64, f64)| {
            let (cr, ci) = (re[j * n + i], imv[j * n + i]);
            if cplx {
                br[i] -= cr * xr - ci * xi;
                bi[i] -= cr * xi + ci * xr;
            } else {
                br[i] -= cr * xr;
            }
        };
        for w in bounds.windows(2) {
            let (s, e) = (w[0], w[1]);
            for j in 0..s {
                let x = (br[j], bi[j]);
                if x != (0.0, 0.0) {
                    (s..e).for_each(|i| sub(br, bi, j, i, x));
                }
            }
            for k in s..e {
                br.swap(k, piv[k]);
                bi.swap(k, piv[k]);
            }
            for k in s..e {
                let x = (br[k], bi[k]);
                if x != (0.0, 0.0) {
                    (k + 1..e).for_each(|i| sub(br, bi, k, i, x));
                }
            }
            for k in (s..e).rev() {
                let (cr, ci) = (re[k * n + k], imv[k * n + k]);
                let (xr, xi) = (br[k], bi[k]);
                let y = if cplx {
                    (xr * cr - xi * ci, xr * ci + xi * cr)
                } else {
                    (xr * cr, 0.0)
                };
                (br[k], bi[k]) = y;
                (s..k).for_each(|i| sub(br, bi, k, i, y));
            }
        }
        Some((re, imv, piv))
    }

    /// Whether factors stored `ld` apart (LINPACK's row order for `L`) are the plain
    /// factors `plain` (`n` apart, LAPACK's order) bit for bit: `U` and the blocks below as
    /// they are, each column of `L` once the later steps' swaps are applied to it.
    fn same_factors(ld: usize, ours: &[f64], plain: &[f64], piv: &[usize], bounds: &[usize]) {
        let n = piv.len();
        for w in bounds.windows(2) {
            let (s, e) = (w[0], w[1]);
            for c in s..e {
                let col = &ours[c * ld..][..n];
                let mut l = col[c + 1..e].to_vec();
                for t in c + 1..e {
                    l.swap(t - c - 1, piv[t] - c - 1);
                }
                let lower: Vec<f64> = col[..=c]
                    .iter()
                    .chain(&l)
                    .chain(&col[e..])
                    .copied()
                    .collect();
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&lower), bits(&plain[c * n..][..n]), "column {c}");
            }
        }
    }

    /// The factorisations and solves, in both instances, give the plain loops' bits: the
    /// factors (`L`'s rows in LINPACK's order, the rest as they are) and the solutions, in
    /// blocks, with zeros and negative zeros among the entries.
    #[test]
    fn the_solves_are_the_plain_loops_bit_for_bit() {
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut next = entries(4242);
        for (n, bounds) in [
            (1, vec![0, 1]),
            (4, vec![0, 4]),
            (5, vec![0, 2, 5]),
            (9, vec![0, 9]),
            (13, vec![0, 3, 13]),
            (27, vec![0, 3, 27]),
            (31, vec![0, 1, 6, 20, 31]),
        ] {
            let block = |i: usize| bounds.iter().rposition(|&b| b <= i).expect("block");
            let mut entry = |r: usize, c: usize| {
                let v = next();
                if block(c) > block(r) {
                    0.0
                } else if v.abs() < 0.3 {
                    if v < 0.0 { -0.0 } else { 0.0 }
                } else {
                    v
                }
            };
            let (mut a, mut ai) = (vec![0.0; n * n], vec![0.0; n * n]);
            for c in 0..n {
                for r in 0..n {
                    a[c * n + r] = entry(r, c);
                    ai[c * n + r] = entry(r, c);
                }
                // A dominant entry off the diagonal, a cyclic shift within the block: every
                // block regular, and every step of the elimination pivots.
                let (bs, be) = (bounds[block(c)], bounds[block(c) + 1]);
                a[c * n + bs + (c - bs + 1) % (be - bs)] += 4.0;
            }
            let rhs: Vec<f64> = (0..2 * n)
                .map(|i| if i % 5 == 3 { -0.0 } else { next() })
                .collect();
            let (mut wr, mut wi) = (rhs[..n].to_vec(), vec![0.0; n]);
            let (real_lu, _, real_piv) =
                plain_solve(n, &bounds, (a.clone(), None), (&mut wr, &mut wi)).expect("regular");
            let (mut zr, mut zi) = (rhs[..n].to_vec(), rhs[n..].to_vec());
            let cplx = (a.clone(), Some(ai.clone()));
            let (lu_re, lu_im, complex_piv) =
                plain_solve(n, &bounds, cplx, (&mut zr, &mut zi)).expect("regular");
            for wide in [false, true] {
                let mut real = RealLu::new(n + 3);
                let mut complex = ComplexLu::new(n + 3);
                real.start_blocks(&bounds);
                complex.start_blocks(&bounds);
                for c in 0..n {
                    for r in 0..n {
                        real.set(r, c, a[c * n + r]);
                        complex.set(r, c, a[c * n + r], ai[c * n + r]);
                    }
                }
                assert!(real.factor_on(wide) && complex.factor_on(wide));
                assert_eq!(
                    (&real.piv[..n], &complex.piv[..n]),
                    (&real_piv[..], &complex_piv[..])
                );
                same_factors(n, &real.a, &real_lu, &real_piv, &bounds);
                same_factors(n, &complex.re, &lu_re, &complex_piv, &bounds);
                same_factors(n, &complex.im, &lu_im, &complex_piv, &bounds);
                let mut x = rhs[..n].to_vec();
                real.solve_on(wide, &mut x);
                assert_eq!(bits(&x), bits(&wr), "real, n = {n}, wide {wide}");
                let (mut yr, mut yi) = (rhs[..n].to_vec(), rhs[n..].to_vec());
                complex.solve_on(wide, &mut yr, &mut yi);
                assert_eq!(bits(&yr), bits(&zr), "complex re, n = {n}, wide {wide}");
                assert_eq!(bits(&yi), bits(&zi), "complex im, n = {n}, wide {wide}");
            }
        }
    }

    /// The instances compiled for AVX2 give the baseline's bits, in blocks too (where the
    /// CPU has AVX2; elsewhere both calls are the baseline's).
    #[test]
    fn the_avx2_instances_give_the_baselines_bits() {
        let (n, bounds) = (31, [0, 3, 31]);
        let mut next = entries(2024);
        let mut real = [RealLu::new(n), RealLu::new(n)];
        let mut complex = [ComplexLu::new(n), ComplexLu::new(n)];
        for (lu, c) in real.iter_mut().zip(&mut complex) {
            lu.start_blocks(&bounds);
            c.start_blocks(&bounds);
        }
        for col in 0..n {
            for row in 0..n {
                // Zero above the diagonal blocks.
                let (a, b, c) = (next(), next(), next());
                let above = row < 3 && col >= 3;
                for k in 0..2 {
                    real[k].set(row, col, if above { 0.0 } else { a });
                    complex[k].set(
                        row,
                        col,
                        if above { 0.0 } else { b },
                        if above { 0.0 } else { c },
                    );
                }
            }
        }
        let rhs: Vec<f64> = (0..3 * n).map(|_| next()).collect();
        let mut x = [rhs.clone(), rhs.clone()];
        for (k, wide) in [false, true].into_iter().enumerate() {
            assert!(real[k].factor_on(wide) && complex[k].factor_on(wide));
            real[k].solve_on(wide, &mut x[k][..n]);
            let (br, bi) = x[k][n..].split_at_mut(n);
            complex[k].solve_on(wide, br, bi);
        }
        assert_eq!(real[0].a, real[1].a);
        assert_eq!(
            (&complex[0].re, &complex[0].im),
            (&complex[1].re, &complex[1].im)
        );
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&x[0]), bits(&x[1]));
        assert_ne!(x[0], rhs, "the solves ran");
    }
}
