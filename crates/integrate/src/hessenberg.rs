//! The Jacobian in upper Hessenberg form, `J = Q H Qᵀ`, and the LU factors of the shifted
//! matrices `c - J` that Radau IIA solves with (`c = γ/h` real, `c = (α + iβ)/h` complex;
//! `stage_matrices.rs` assembles them for the stage system).
//!
//! Radau IIA refactors at nearly every change of the step size while the Jacobian stays the
//! same for many steps. With `H` made once per Jacobian (Householder, `10/3 n³` flops), each
//! factorisation of `c - H` is `O(n²)` (partial pivoting on a Hessenberg matrix only ever
//! swaps neighbouring rows); a solve pays for it with `Qᵀ` and `Q` around the two triangular
//! sweeps. This is RADAU5's `IWORK(1)` option (its ELMHES, DECH and DECHC), here with
//! Householder rather than elimination transforms.
//!
//! Storage is row-major: the triangular sweeps are dot products along rows. The dot products
//! keep four partial sums ([`dot`]): with one, each addition waits for the last, and on the
//! flexible deployment's 49 states the reflections alone took longer than the dense LU
//! factorisations they replace. The sums are added even with even and odd with odd, so that
//! they stay two pairs of neighbours in two vector registers: added `(0 + 1) + (2 + 3)`, the
//! compiler interleaves them with a shuffle on every load (a third more instructions).

use crate::common::all_finite;

/// `Σ aᵢ bᵢ` over the shorter of the two, in four interleaved partial sums.
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let (ac, bc) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = ac
        .remainder()
        .iter()
        .zip(bc.remainder())
        .map(|(x, y)| x * y)
        .sum();
    let mut s = [0.0; 4];
    for (x, y) in ac.zip(bc) {
        for l in 0..4 {
            s[l] += x[l] * y[l];
        }
    }
    (s[0] + s[2]) + (s[1] + s[3]) + tail
}

/// `y += a x` over the shorter of the two, four entries at a time: the reflectors are
/// mostly shorter than the length from which the compiler vectorises a plain loop.
#[inline]
fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    let n = x.len().min(y.len());
    let (x, y) = (&x[..n], &mut y[..n]);
    let mut yc = y.chunks_exact_mut(4);
    let mut xc = x.chunks_exact(4);
    for (yy, xx) in (&mut yc).zip(&mut xc) {
        for l in 0..4 {
            yy[l] += a * xx[l];
        }
    }
    for (yy, xx) in yc.into_remainder().iter_mut().zip(xc.remainder()) {
        *yy += a * xx;
    }
}

/// `J = Q H Qᵀ`: `H` upper Hessenberg, `Q = P₀ P₁ … P_{n-3}` with the Householder reflectors
/// `P_k = I - β_k v_k v_kᵀ` acting on entries `k+1..n`.
#[derive(Clone, Debug)]
pub(crate) struct Hessenberg {
    n: usize,
    /// `H`, row-major (zero below the subdiagonal).
    h: Vec<f64>,
    /// Reflector `k` in `v[k * n + k + 1..(k + 1) * n]`.
    v: Vec<f64>,
    beta: Vec<f64>,
    /// Scratch row of the reduction.
    u: Vec<f64>,
}

impl Hessenberg {
    pub fn new(n: usize) -> Self {
        Self {
            n,
            h: vec![0.0; n * n],
            v: vec![0.0; n * n],
            beta: vec![0.0; n],
            u: vec![0.0; n],
        }
    }

    /// Reduces the `m × m` matrix `J` (entry `(r, c)` from `j`; `m` at most the `n` this was
    /// made for) to Hessenberg form. A `J` with an entry that is not finite is kept as it is,
    /// and the factorisations refuse it.
    pub fn reduce(&mut self, m: usize, j: impl Fn(usize, usize) -> f64) {
        assert!(m * m <= self.h.len(), "dimension {m} over the capacity");
        self.n = m;
        let n = m;
        for r in 0..n {
            for c in 0..n {
                self.h[r * n + c] = j(r, c);
            }
        }
        if !all_finite(&self.h[..n * n]) {
            return;
        }
        for k in 0..n.saturating_sub(2) {
            let v = &mut self.v[k * n..(k + 1) * n];
            let mut norm2 = 0.0;
            for i in k + 1..n {
                v[i] = self.h[i * n + k];
                norm2 += v[i] * v[i];
            }
            let tail2 = norm2 - v[k + 1] * v[k + 1];
            if tail2 == 0.0 {
                // Already zero below the subdiagonal: no reflection.
                self.beta[k] = 0.0;
                continue;
            }
            let norm = norm2.sqrt();
            let alpha = if v[k + 1] > 0.0 { -norm } else { norm };
            v[k + 1] -= alpha;
            let vv = tail2 + v[k + 1] * v[k + 1];
            let beta = 2.0 / vv;
            self.beta[k] = beta;
            // H ← P H (rows k+1..n; columns before k are already zero there).
            // (as the rank-one update `H -= v (β vᵀ H)`, row by row).
            let u = &mut self.u;
            u[k..].fill(0.0);
            for i in k + 1..n {
                let vi = beta * v[i];
                for (uc, h) in u[k..].iter_mut().zip(&self.h[i * n + k..(i + 1) * n]) {
                    *uc += vi * h;
                }
            }
            for i in k + 1..n {
                let vi = v[i];
                for (h, uc) in self.h[i * n + k..(i + 1) * n].iter_mut().zip(&u[k..]) {
                    *h -= vi * uc;
                }
            }
            // H ← H P (columns k+1..n).
            for r in 0..n {
                let row = &mut self.h[r * n..(r + 1) * n];
                let s = beta * dot(&row[k + 1..], &v[k + 1..]);
                for i in k + 1..n {
                    row[i] -= s * v[i];
                }
            }
            self.h[(k + 1) * n + k] = alpha;
            for i in k + 2..n {
                self.h[i * n + k] = 0.0;
            }
        }
    }

    /// `b ← P_k b` for each `b` (together: the reflector is read once, and the dot
    /// products run side by side).
    fn reflect<const K: usize>(&self, k: usize, bs: &mut [&mut [f64]; K]) {
        let (n, beta) = (self.n, self.beta[k]);
        if beta == 0.0 {
            return;
        }
        let v = &self.v[k * n + k + 1..(k + 1) * n];
        for b in bs.iter_mut() {
            let b = &mut b[k + 1..];
            let s = beta * dot(v, b);
            axpy(-s, v, b);
        }
    }

    /// `b ← Qᵀ b` for each `b`.
    pub fn apply_qt<const K: usize>(&self, mut bs: [&mut [f64]; K]) {
        for k in 0..self.n.saturating_sub(2) {
            self.reflect(k, &mut bs);
        }
    }

    /// `b ← Q b` for each `b`.
    pub fn apply_q<const K: usize>(&self, mut bs: [&mut [f64]; K]) {
        for k in (0..self.n.saturating_sub(2)).rev() {
            self.reflect(k, &mut bs);
        }
    }
}

/// `c - J = Q (c - H) Qᵀ` for a real `c`, `c - H` as `P L U` (`L` unit lower bidiagonal).
#[derive(Clone, Debug)]
pub(crate) struct RealLu {
    n: usize,
    /// `U` on and above the diagonal, `L`'s multipliers on the subdiagonal; row-major.
    a: Vec<f64>,
    /// Whether rows `k` and `k + 1` were swapped at step `k`.
    swap: Vec<bool>,
}

/// Row `r`'s entries that a Hessenberg elimination reads: from the subdiagonal rightwards
/// (about half the matrix; the rest is neither written nor read).
fn band(n: usize, r: usize) -> std::ops::Range<usize> {
    r * n + r.saturating_sub(1)..(r + 1) * n
}

/// `a = c - H` on the band; false when an entry is not finite.
fn shifted_band(a: &mut [f64], c: f64, hess: &Hessenberg) -> bool {
    let n = hess.n;
    for r in 0..n {
        let band = band(n, r);
        for (a, h) in a[band.clone()].iter_mut().zip(&hess.h[band.clone()]) {
            *a = -h;
        }
        a[r * n + r] += c;
        if !all_finite(&a[band]) {
            return false;
        }
    }
    true
}

impl RealLu {
    pub fn new(n: usize) -> Self {
        Self {
            n,
            a: vec![0.0; n * n],
            swap: vec![false; n],
        }
    }

    /// Factors `c - H`; false when a pivot is zero or anything is not finite.
    pub fn factor(&mut self, c: f64, hess: &Hessenberg) -> bool {
        let n = hess.n;
        self.n = n;
        if n == 0 {
            return c.is_finite();
        }
        if !shifted_band(&mut self.a, c, hess) {
            return false;
        }
        for k in 0..n {
            if k + 1 == n {
                self.swap[k] = false;
                break;
            }
            let (top, bottom) = self.a.split_at_mut((k + 1) * n);
            let (rk, rk1) = (&mut top[k * n..], &mut bottom[..n]);
            let swap = rk1[k].abs() > rk[k].abs();
            if swap {
                rk[k..].swap_with_slice(&mut rk1[k..]);
            }
            self.swap[k] = swap;
            if rk[k] == 0.0 {
                return false;
            }
            let l = rk1[k] / rk[k];
            rk1[k] = l;
            for (x, u) in rk1[k + 1..].iter_mut().zip(&rk[k + 1..]) {
                *x -= l * u;
            }
        }
        self.a[n * n - 1] != 0.0
    }

    /// Overwrites `b` with `(c - J)⁻¹ b`.
    #[cfg(test)]
    pub fn solve(&self, hess: &Hessenberg, b: &mut [f64]) {
        hess.apply_qt([&mut *b]);
        self.solve_h(b);
        hess.apply_q([b]);
    }

    /// Overwrites `b` with `(c - H)⁻¹ b` (`b` in the Hessenberg basis).
    pub fn solve_h(&self, b: &mut [f64]) {
        let n = self.n;
        for k in 0..n.saturating_sub(1) {
            if self.swap[k] {
                b.swap(k, k + 1);
            }
            b[k + 1] -= self.a[(k + 1) * n + k] * b[k];
        }
        for k in (0..n).rev() {
            let row = &self.a[k * n..(k + 1) * n];
            let s = dot(&row[k + 1..], &b[k + 1..]);
            b[k] = (b[k] - s) / row[k];
        }
    }
}

/// The same for a complex `c`, real and imaginary parts apart. The pivot is the entry of
/// larger `|re| + |im|` (LINPACK's `cabs1`).
#[derive(Clone, Debug)]
pub(crate) struct ComplexLu {
    n: usize,
    re: Vec<f64>,
    im: Vec<f64>,
    swap: Vec<bool>,
}

impl ComplexLu {
    pub fn new(n: usize) -> Self {
        Self {
            n,
            re: vec![0.0; n * n],
            im: vec![0.0; n * n],
            swap: vec![false; n],
        }
    }

    /// Factors `(cr + i ci) - H`; false when a pivot is zero or anything is not finite.
    pub fn factor(&mut self, cr: f64, ci: f64, hess: &Hessenberg) -> bool {
        let n = hess.n;
        self.n = n;
        if !(cr.is_finite() && ci.is_finite()) {
            return false;
        }
        if n == 0 {
            return true;
        }
        if !shifted_band(&mut self.re, cr, hess) {
            return false;
        }
        for r in 0..n {
            self.im[band(n, r)].fill(0.0);
            self.im[r * n + r] = ci;
        }
        for k in 0..n {
            if k + 1 == n {
                self.swap[k] = false;
                break;
            }
            let (tr, br) = self.re.split_at_mut((k + 1) * n);
            let (ti, bi) = self.im.split_at_mut((k + 1) * n);
            let (rk, rk1) = (&mut tr[k * n..], &mut br[..n]);
            let (ik, ik1) = (&mut ti[k * n..], &mut bi[..n]);
            let swap = rk1[k].abs() + ik1[k].abs() > rk[k].abs() + ik[k].abs();
            if swap {
                rk[k..].swap_with_slice(&mut rk1[k..]);
                ik[k..].swap_with_slice(&mut ik1[k..]);
            }
            self.swap[k] = swap;
            let d = rk[k] * rk[k] + ik[k] * ik[k];
            if d == 0.0 {
                return false;
            }
            // l = a[k+1][k] / a[k][k]
            let (pr, pi) = (rk[k] / d, -ik[k] / d);
            let (lr, li) = (rk1[k] * pr - ik1[k] * pi, rk1[k] * pi + ik1[k] * pr);
            rk1[k] = lr;
            ik1[k] = li;
            let it = rk1[k + 1..]
                .iter_mut()
                .zip(&mut ik1[k + 1..])
                .zip(rk[k + 1..].iter().zip(&ik[k + 1..]));
            for ((xr, xi), (ur, ui)) in it {
                *xr -= lr * ur - li * ui;
                *xi -= lr * ui + li * ur;
            }
        }
        let last = n * n - 1;
        self.re[last] != 0.0 || self.im[last] != 0.0
    }

    /// Overwrites `(br, bi)` with `((cr + i ci) - J)⁻¹ (br + i bi)`.
    #[cfg(test)]
    pub fn solve(&self, hess: &Hessenberg, br: &mut [f64], bi: &mut [f64]) {
        hess.apply_qt([&mut *br, &mut *bi]);
        self.solve_h(br, bi);
        hess.apply_q([br, bi]);
    }

    /// Overwrites `(br, bi)` with `((cr + i ci) - H)⁻¹ (br + i bi)` (in the Hessenberg
    /// basis).
    pub fn solve_h(&self, br: &mut [f64], bi: &mut [f64]) {
        let n = self.n;
        for k in 0..n.saturating_sub(1) {
            if self.swap[k] {
                br.swap(k, k + 1);
                bi.swap(k, k + 1);
            }
            let (lr, li) = (self.re[(k + 1) * n + k], self.im[(k + 1) * n + k]);
            let (xr, xi) = (br[k], bi[k]);
            br[k + 1] -= lr * xr - li * xi;
            bi[k + 1] -= lr * xi + li * xr;
        }
        for k in (0..n).rev() {
            let (rr, ri) = (&self.re[k * n..(k + 1) * n], &self.im[k * n..(k + 1) * n]);
            let (ur, ui, xr, xi) = (&rr[k + 1..], &ri[k + 1..], &br[k + 1..], &bi[k + 1..]);
            let sr = br[k] - (dot(ur, xr) - dot(ui, xi));
            let si = bi[k] - (dot(ur, xi) + dot(ui, xr));
            let d = rr[k] * rr[k] + ri[k] * ri[k];
            br[k] = (sr * rr[k] + si * ri[k]) / d;
            bi[k] = (si * rr[k] - sr * ri[k]) / d;
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A deterministic, well-scattered sequence in (-1, 1).
    pub(crate) fn entries(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    pub(crate) fn matrix(n: usize, seed: u64) -> Vec<f64> {
        let mut next = entries(seed);
        (0..n * n).map(|_| next()).collect()
    }

    #[test]
    fn the_reduction_is_hessenberg_and_similar_to_the_matrix() {
        for n in [1, 2, 3, 8, 49] {
            let j = matrix(n, n as u64);
            let mut hs = Hessenberg::new(n);
            hs.reduce(n, |r, c| j[r * n + c]);
            for r in 0..n {
                for c in 0..r.saturating_sub(1) {
                    assert_eq!(hs.h[r * n + c], 0.0, "n = {n}: H[{r}][{c}]");
                }
            }
            // Q H Qᵀ e_c, column by column, against J e_c.
            let mut worst: f64 = 0.0;
            for c in 0..n {
                let mut e = vec![0.0; n];
                e[c] = 1.0;
                hs.apply_qt([&mut e]);
                let mut he: Vec<f64> = (0..n)
                    .map(|r| (0..n).map(|k| hs.h[r * n + k] * e[k]).sum())
                    .collect();
                hs.apply_q([&mut he]);
                for r in 0..n {
                    worst = worst.max((he[r] - j[r * n + c]).abs());
                }
            }
            assert!(worst < 1e-13, "n = {n}: {worst:e}");
        }
    }

    #[test]
    fn shifted_real_and_complex_solves_agree_with_the_matrix_to_rounding() {
        for n in [1, 2, 7, 49] {
            let j = matrix(n, 10 + n as u64);
            let mut next = entries(99 + n as u64);
            let (xr, xi): (Vec<f64>, Vec<f64>) = (0..n).map(|_| (next(), next())).unzip();
            let mut hs = Hessenberg::new(n);
            hs.reduce(n, |r, c| j[r * n + c]);
            // A shift small against |J| so that the pivoting is exercised.
            let (cr, ci) = (0.3, 0.7);
            let mut real = RealLu::new(n);
            assert!(real.factor(cr, &hs));
            let mut b: Vec<f64> = (0..n)
                .map(|r| cr * xr[r] - (0..n).map(|c| j[r * n + c] * xr[c]).sum::<f64>())
                .collect();
            real.solve(&hs, &mut b);
            let err = b
                .iter()
                .zip(&xr)
                .map(|(u, v)| (u - v).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-11, "real, n = {n}: {err:e}");
            let mut complex = ComplexLu::new(n);
            assert!(complex.factor(cr, ci, &hs));
            // b = (c - J) x, c = cr + i ci.
            let (mut br, mut bi): (Vec<f64>, Vec<f64>) = (0..n)
                .map(|r| {
                    let jr: f64 = (0..n).map(|c| j[r * n + c] * xr[c]).sum();
                    let ji: f64 = (0..n).map(|c| j[r * n + c] * xi[c]).sum();
                    (cr * xr[r] - ci * xi[r] - jr, cr * xi[r] + ci * xr[r] - ji)
                })
                .unzip();
            complex.solve(&hs, &mut br, &mut bi);
            let err = (0..n)
                .map(|i| (br[i] - xr[i]).abs().max((bi[i] - xi[i]).abs()))
                .fold(0.0, f64::max);
            assert!(err < 1e-11, "complex, n = {n}: {err:e}");
        }
    }

    /// The factorisations write and read only the band from the subdiagonal right: storage
    /// left from anything (here NaN) changes no bit of a solve.
    #[test]
    fn the_factors_read_nothing_below_the_subdiagonal() {
        let n = 49;
        let j = matrix(n, 5);
        let mut hs = Hessenberg::new(n);
        hs.reduce(n, |r, c| j[r * n + c]);
        let (cr, ci) = (0.3, 0.7);
        let b0: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let solve_real = |real: &mut RealLu| {
            assert!(real.factor(cr, &hs));
            let mut b = b0.clone();
            real.solve(&hs, &mut b);
            b.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        };
        let solve_complex = |complex: &mut ComplexLu| {
            assert!(complex.factor(cr, ci, &hs));
            let (mut br, mut bi) = (b0.clone(), b0.iter().map(|v| -v).collect::<Vec<_>>());
            complex.solve(&hs, &mut br, &mut bi);
            (br.iter().chain(&bi).map(|v| v.to_bits())).collect::<Vec<_>>()
        };
        let (mut real, mut complex) = (RealLu::new(n), ComplexLu::new(n));
        let (want_real, want_complex) = (solve_real(&mut real), solve_complex(&mut complex));
        real.a.fill(f64::NAN);
        complex.re.fill(f64::NAN);
        complex.im.fill(f64::NAN);
        assert_eq!(solve_real(&mut real), want_real);
        assert_eq!(solve_complex(&mut complex), want_complex);
    }

    #[test]
    fn singular_or_non_finite_matrices_are_refused() {
        // J = [[1, 2], [2, 4]] shifted by 0 is singular; by 5 it is not (eigenvalues 0, 5).
        let j = [1.0, 2.0, 2.0, 4.0];
        let mut hs = Hessenberg::new(2);
        hs.reduce(2, |r, c| j[r * 2 + c]);
        let mut real = RealLu::new(2);
        assert!(!real.factor(0.0, &hs));
        assert!(!real.factor(5.0, &hs));
        assert!(real.factor(1.0, &hs));
        let mut complex = ComplexLu::new(2);
        assert!(!complex.factor(5.0, 0.0, &hs));
        assert!(complex.factor(5.0, 1e-3, &hs));
        assert!(!real.factor(f64::NAN, &hs));
        assert!(!complex.factor(1.0, f64::INFINITY, &hs));
        hs.reduce(2, |r, c| if r == c { f64::NAN } else { 0.0 });
        assert!(!real.factor(1.0, &hs) && !complex.factor(1.0, 1.0, &hs));
    }
}
