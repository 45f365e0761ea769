//! LU factorisation with partial pivoting of small dense matrices: the stage system's
//! matrices once the states a Jacobian row ties to a single other state are eliminated
//! (`stage_matrices.rs`), `γ/h - J' - K'/(γ/h)` real and its complex counterpart, which are
//! not shifts of one matrix and so have no Hessenberg shortcut. The complex one keeps its
//! real and imaginary parts apart so that the column updates vectorise.
//!
//! Written here rather than taken from faer, whose blocked, recursive factorisation is built
//! for large matrices: on the 49 states of the flexible deployment these plain loops executed
//! about as many instructions as faer 0.24 for the pair (417 k against about 420 k,
//! callgrind; faer's are AVX2, these the baseline's) and took the whole Radau IIA run from
//! 0.080 s to 0.071 s: less dispatch and recursion around small blocks.

/// `A = P L U` of a real `n × n` matrix, column-major, in place; `piv[k]` is the row swapped
/// with row `k` at step `k` (LAPACK's `getrf` convention). `U`'s diagonal is kept as its
/// reciprocals, so that the back substitution multiplies: a division's latency is several
/// multiplications' on its chain of dependent steps.
#[derive(Clone, Debug)]
pub(crate) struct RealLu {
    n: usize,
    a: Vec<f64>,
    piv: Vec<usize>,
}

impl RealLu {
    /// Storage for matrices up to `cap × cap`.
    pub fn new(cap: usize) -> Self {
        Self {
            n: cap,
            a: vec![0.0; cap * cap],
            piv: vec![0; cap],
        }
    }

    /// The next matrix is `n × n` (at most the capacity), written through `matrix_mut`.
    pub fn start(&mut self, n: usize) {
        assert!(n <= self.piv.len(), "dimension {n} over the capacity");
        self.n = n;
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

    /// Factors the matrix set; false when a pivot is zero or anything is not finite.
    pub fn factor(&mut self) -> bool {
        let n = self.n;
        if !self.a[..n * n].iter().all(|v| v.is_finite()) {
            return false;
        }
        for k in 0..n {
            let col = &self.a[k * n..(k + 1) * n];
            let mut p = k;
            for i in k + 1..n {
                if col[i].abs() > col[p].abs() {
                    p = i;
                }
            }
            self.piv[k] = p;
            if col[p] == 0.0 {
                return false;
            }
            if p != k {
                for j in 0..n {
                    self.a.swap(j * n + k, j * n + p);
                }
            }
            let (head, tail) = self.a[..n * n].split_at_mut((k + 1) * n);
            let colk = &mut head[k * n..];
            let inv = 1.0 / colk[k];
            colk[k] = inv;
            for v in &mut colk[k + 1..] {
                *v *= inv;
            }
            for colj in tail.chunks_exact_mut(n) {
                let akj = colj[k];
                if akj != 0.0 {
                    for (aij, lik) in colj[k + 1..].iter_mut().zip(&colk[k + 1..]) {
                        *aij -= lik * akj;
                    }
                }
            }
        }
        true
    }

    /// Overwrites `b` with `A⁻¹ b`.
    pub fn solve(&self, b: &mut [f64]) {
        let n = self.n;
        for k in 0..n {
            b.swap(k, self.piv[k]);
        }
        for k in 0..n {
            let bk = b[k];
            if bk != 0.0 {
                let col = &self.a[k * n..(k + 1) * n];
                for (bi, lik) in b[k + 1..].iter_mut().zip(&col[k + 1..]) {
                    *bi -= lik * bk;
                }
            }
        }
        for k in (0..n).rev() {
            let col = &self.a[k * n..(k + 1) * n];
            b[k] *= col[k];
            let bk = b[k];
            for (bi, uik) in b[..k].iter_mut().zip(&col[..k]) {
                *bi -= uik * bk;
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
}

impl ComplexLu {
    /// Storage for matrices up to `cap × cap`.
    pub fn new(cap: usize) -> Self {
        Self {
            n: cap,
            re: vec![0.0; cap * cap],
            im: vec![0.0; cap * cap],
            piv: vec![0; cap],
        }
    }

    /// The next matrix is `n × n` (at most the capacity), written through `matrix_mut`.
    pub fn start(&mut self, n: usize) {
        assert!(n <= self.piv.len(), "dimension {n} over the capacity");
        self.n = n;
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

    /// Factors the matrix set; false when a pivot is zero or anything is not finite.
    pub fn factor(&mut self) -> bool {
        let n = self.n;
        if !self.re[..n * n]
            .iter()
            .chain(&self.im[..n * n])
            .all(|v| v.is_finite())
        {
            return false;
        }
        for k in 0..n {
            let (cr, ci) = (&self.re[k * n..(k + 1) * n], &self.im[k * n..(k + 1) * n]);
            let mut p = k;
            let mut best = cr[k].abs() + ci[k].abs();
            for i in k + 1..n {
                let m = cr[i].abs() + ci[i].abs();
                if m > best {
                    (p, best) = (i, m);
                }
            }
            self.piv[k] = p;
            if best == 0.0 {
                return false;
            }
            if p != k {
                for j in 0..n {
                    self.re.swap(j * n + k, j * n + p);
                    self.im.swap(j * n + k, j * n + p);
                }
            }
            let (hr, tr) = self.re[..n * n].split_at_mut((k + 1) * n);
            let (hi, ti) = self.im[..n * n].split_at_mut((k + 1) * n);
            let (lr, li) = (&mut hr[k * n..], &mut hi[k * n..]);
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
                    let it = cjr[k + 1..]
                        .iter_mut()
                        .zip(&mut cji[k + 1..])
                        .zip(lr[k + 1..].iter().zip(&li[k + 1..]));
                    for ((xr, xi), (l_r, l_i)) in it {
                        *xr -= l_r * ar - l_i * ai;
                        *xi -= l_r * ai + l_i * ar;
                    }
                }
            }
        }
        true
    }

    /// Overwrites `(br, bi)` with `A⁻¹ (br + i bi)`.
    pub fn solve(&self, br: &mut [f64], bi: &mut [f64]) {
        let n = self.n;
        for k in 0..n {
            br.swap(k, self.piv[k]);
            bi.swap(k, self.piv[k]);
        }
        for k in 0..n {
            let (xr, xi) = (br[k], bi[k]);
            if xr != 0.0 || xi != 0.0 {
                let (cr, ci) = (&self.re[k * n..(k + 1) * n], &self.im[k * n..(k + 1) * n]);
                for i in k + 1..n {
                    br[i] -= cr[i] * xr - ci[i] * xi;
                    bi[i] -= cr[i] * xi + ci[i] * xr;
                }
            }
        }
        for k in (0..n).rev() {
            let (cr, ci) = (&self.re[k * n..(k + 1) * n], &self.im[k * n..(k + 1) * n]);
            let (xr, xi) = (br[k], bi[k]);
            let (yr, yi) = (xr * cr[k] - xi * ci[k], xr * ci[k] + xi * cr[k]);
            br[k] = yr;
            bi[k] = yi;
            for i in 0..k {
                br[i] -= cr[i] * yr - ci[i] * yi;
                bi[i] -= cr[i] * yi + ci[i] * yr;
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
}
