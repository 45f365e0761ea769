//! The Jacobian in upper Hessenberg form, `J = Q H Qᵀ`, and the LU factors of the shifted
//! matrices `c - J` that Radau IIA solves with (`c = γ/h` real, `c = (α + iβ)/h` complex).
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
//! factorisations they replace.

/// `Σ aᵢ bᵢ` over the shorter of the two, in four interleaved partial sums.
#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
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
    (s[0] + s[1]) + (s[2] + s[3]) + tail
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
        if !self.h[..n * n].iter().all(|x| x.is_finite()) {
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
            for (x, a) in b.iter_mut().zip(v) {
                *x -= s * a;
            }
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
        for (a, h) in self.a.iter_mut().zip(&hess.h[..n * n]) {
            *a = -h;
        }
        for k in 0..n {
            self.a[k * n + k] += c;
        }
        if !self.a[..n * n].iter().all(|x| x.is_finite()) {
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
        for (a, h) in self.re.iter_mut().zip(&hess.h[..n * n]) {
            *a = -h;
        }
        self.im[..n * n].fill(0.0);
        for k in 0..n {
            self.re[k * n + k] += cr;
            self.im[k * n + k] = ci;
        }
        if !self.re[..n * n].iter().all(|x| x.is_finite()) {
            return false;
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

/// The two matrices of Radau IIA's stage system, `γ/h - J` and `(α + iβ)/h - J`, with the
/// states that `J` leaves uncoupled taken out before the Hessenberg reduction:
///
/// - a state whose row of `J` is zero (a locked hinge's rate: its derivative does not depend
///   on the state) solves alone, `x = b / c`, and enters the others through its column;
/// - a state whose column of `J` is zero (the energy budget's work: nothing depends on it)
///   is solved last from the others, `x = (b + J_row x) / c`.
///
/// This is exact, and it keeps a zero a zero: the orthogonal transforms would otherwise
/// spread rounding (1e-19) into a locked hinge's rate, which must stay exactly zero to be
/// seen as not turning.
#[derive(Clone, Debug)]
pub(crate) struct StageMatrices {
    n: usize,
    /// The coupled states (the reduced `J`'s rows and columns, in order), those with a zero
    /// row, and those with a zero column (and a row that is not zero).
    active: Vec<usize>,
    inert: Vec<usize>,
    last: Vec<usize>,
    /// `J[active, inert]`, row-major, and `J[last, :]`, row-major.
    j_ai: Vec<f64>,
    j_last: Vec<f64>,
    hess: Hessenberg,
    real: RealLu,
    complex: ComplexLu,
    /// The shifts factored: `γ/h` and `(α + iβ)/h`.
    c1: f64,
    c2: (f64, f64),
    /// Scratch for the coupled states (real; complex re and im).
    s: [Vec<f64>; 3],
}

impl StageMatrices {
    pub fn new(n: usize) -> Self {
        Self {
            n,
            active: Vec::with_capacity(n),
            inert: Vec::with_capacity(n),
            last: Vec::with_capacity(n),
            j_ai: Vec::with_capacity(n * n),
            j_last: Vec::with_capacity(n * n),
            hess: Hessenberg::new(n),
            real: RealLu::new(n),
            complex: ComplexLu::new(n),
            c1: f64::NAN,
            c2: (f64::NAN, f64::NAN),
            s: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
        }
    }

    /// Sorts the states by `J`'s zero rows and columns and reduces the coupled block.
    pub fn reduce(&mut self, j: impl Fn(usize, usize) -> f64) {
        let n = self.n;
        self.active.clear();
        self.inert.clear();
        self.last.clear();
        for r in 0..n {
            if (0..n).all(|c| j(r, c) == 0.0) {
                self.inert.push(r);
            } else if (0..n).all(|q| j(q, r) == 0.0) {
                self.last.push(r);
            } else {
                self.active.push(r);
            }
        }
        self.j_ai.clear();
        for &a in &self.active {
            self.j_ai.extend(self.inert.iter().map(|&z| j(a, z)));
        }
        self.j_last.clear();
        for &f in &self.last {
            self.j_last.extend((0..n).map(|c| j(f, c)));
        }
        let active = &self.active;
        self.hess
            .reduce(active.len(), |r, c| j(active[r], active[c]));
    }

    /// Factors both matrices at step `h`'s shifts `c1 = γ/h`, `c2 = (α + iβ)/h`; false when
    /// either is singular or not finite.
    pub fn factor(&mut self, c1: f64, c2: (f64, f64)) -> bool {
        let ok = c1 != 0.0
            && c2 != (0.0, 0.0)
            && self.j_ai.iter().chain(&self.j_last).all(|x| x.is_finite())
            && self.real.factor(c1, &self.hess)
            && self.complex.factor(c2.0, c2.1, &self.hess);
        (self.c1, self.c2) = (c1, c2);
        ok
    }

    /// `b ← (γ/h - J)⁻¹ b`.
    pub fn solve_real(&mut self, b: &mut [f64]) {
        self.gather(0, b, None);
        let m = self.active.len();
        let s = &mut self.s[0][..m];
        self.hess.apply_qt([&mut *s]);
        self.real.solve_h(s);
        self.hess.apply_q([s]);
        self.scatter(0, b, None);
    }

    /// `d1 ← (γ/h - J)⁻¹ d1` and `d2 + i d3 ← ((α + iβ)/h - J)⁻¹ (d2 + i d3)`, the three
    /// through `Qᵀ` and `Q` together.
    pub fn solve_stages(&mut self, d1: &mut [f64], d2: &mut [f64], d3: &mut [f64]) {
        self.gather(0, d1, None);
        self.gather(1, d2, Some(d3));
        let m = self.active.len();
        let [s1, s2, s3] = &mut self.s;
        let (s1, s2, s3) = (&mut s1[..m], &mut s2[..m], &mut s3[..m]);
        self.hess.apply_qt([&mut *s1, &mut *s2, &mut *s3]);
        self.real.solve_h(s1);
        self.complex.solve_h(s2, s3);
        self.hess.apply_q([s1, s2, s3]);
        self.scatter(0, d1, None);
        self.scatter(1, d2, Some(d3));
    }

    /// The states with a zero row solved (`b / c`, in place), and the coupled states' right
    /// side `b + J[active, inert] x_inert` into scratch `k` (and `k + 1`, the imaginary
    /// part, for the complex shift: `im` given).
    fn gather(&mut self, k: usize, re: &mut [f64], mut im: Option<&mut [f64]>) {
        let (cr, ci) = if im.is_some() {
            self.c2
        } else {
            (self.c1, 0.0)
        };
        let d = cr * cr + ci * ci;
        for &z in &self.inert {
            let (xr, xi) = (re[z], im.as_ref().map_or(0.0, |i| i[z]));
            re[z] = (xr * cr + xi * ci) / d;
            if let Some(i) = im.as_mut() {
                i[z] = (xi * cr - xr * ci) / d;
            }
        }
        let nz = self.inert.len();
        for (r, &a) in self.active.iter().enumerate() {
            let row = &self.j_ai[r * nz..(r + 1) * nz];
            let mut sr = re[a];
            for (jz, &z) in row.iter().zip(&self.inert) {
                sr += jz * re[z];
            }
            self.s[k][r] = sr;
            if let Some(i) = im.as_ref() {
                let mut si = i[a];
                for (jz, &z) in row.iter().zip(&self.inert) {
                    si += jz * i[z];
                }
                self.s[k + 1][r] = si;
            }
        }
    }

    /// The coupled states back from scratch `k` (`k + 1`), then the states with a zero
    /// column, `x = (b + J[last, :] x) / c`.
    fn scatter(&self, k: usize, re: &mut [f64], mut im: Option<&mut [f64]>) {
        for (r, &a) in self.active.iter().enumerate() {
            re[a] = self.s[k][r];
            if let Some(i) = im.as_mut() {
                i[a] = self.s[k + 1][r];
            }
        }
        let (cr, ci) = if im.is_some() {
            self.c2
        } else {
            (self.c1, 0.0)
        };
        let d = cr * cr + ci * ci;
        let n = self.n;
        // J[last, last] = 0: the unsolved entries in the sums are multiplied by zero.
        for (r, &f) in self.last.iter().enumerate() {
            let row = &self.j_last[r * n..(r + 1) * n];
            let xr = re[f] + dot(row, re);
            let xi = im.as_ref().map_or(0.0, |i| i[f] + dot(row, i));
            re[f] = (xr * cr + xi * ci) / d;
            if let Some(i) = im.as_mut() {
                i[f] = (xi * cr - xr * ci) / d;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic, well-scattered sequence in (-1, 1).
    fn entries(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    fn matrix(n: usize, seed: u64) -> Vec<f64> {
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

    #[test]
    fn uncoupled_states_are_solved_apart_and_a_zero_stays_zero() {
        let n = 9;
        let mut j = matrix(n, 7);
        // States 2 and 5: zero rows (their derivative depends on nothing); state 7: a zero
        // column (nothing depends on it).
        for c in 0..n {
            j[2 * n + c] = 0.0;
            j[5 * n + c] = 0.0;
        }
        for r in 0..n {
            j[r * n + 7] = 0.0;
        }
        let mut st = StageMatrices::new(n);
        st.reduce(|r, c| j[r * n + c]);
        assert_eq!(
            (st.inert.as_slice(), st.last.as_slice()),
            (&[2, 5][..], &[7][..])
        );
        let (c1, c2) = (0.4, (0.3, 0.8));
        assert!(st.factor(c1, c2));
        let mut next = entries(3);
        let x: Vec<[f64; 3]> = (0..n).map(|_| [next(), next(), next()]).collect();
        // b1 = (c1 - J) x1, b2 + i b3 = (c2 - J)(x2 + i x3); state 5's solution is zero.
        let xs = |s: usize, i: usize| if i == 5 { 0.0 } else { x[i][s] };
        let jx = |s: usize, r: usize| (0..n).map(|c| j[r * n + c] * xs(s, c)).sum::<f64>();
        let mut b1: Vec<f64> = (0..n).map(|r| c1 * xs(0, r) - jx(0, r)).collect();
        let mut b2: Vec<f64> = (0..n)
            .map(|r| c2.0 * xs(1, r) - c2.1 * xs(2, r) - jx(1, r))
            .collect();
        let mut b3: Vec<f64> = (0..n)
            .map(|r| c2.0 * xs(2, r) + c2.1 * xs(1, r) - jx(2, r))
            .collect();
        let mut b0 = b1.clone();
        st.solve_real(&mut b0);
        st.solve_stages(&mut b1, &mut b2, &mut b3);
        for i in 0..n {
            for (s, got) in [b0[i], b1[i], b2[i], b3[i]].into_iter().enumerate() {
                let want = xs(s.saturating_sub(1), i);
                assert!(
                    (got - want).abs() < 1e-12,
                    "state {i}, solve {s}: {got} against {want}"
                );
            }
        }
        assert!([b0[5], b1[5], b2[5], b3[5]].iter().all(|v| *v == 0.0));
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
