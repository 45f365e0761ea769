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
mod tests;
