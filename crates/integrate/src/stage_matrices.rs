//! The two matrices of Radau IIA's stage system, `γ/h - J` and `(α + iβ)/h - J`, factored
//! through the Jacobian's Hessenberg form (`hessenberg.rs`), with the states `J` leaves
//! uncoupled solved apart.

use crate::hessenberg::{ComplexLu, Hessenberg, RealLu, dot};

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
    /// Whether the coupling entries kept apart are all finite (checked once per Jacobian).
    finite: bool,
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
            finite: true,
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
            && self.finite
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
    use crate::hessenberg::tests::{entries, matrix};

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
}
