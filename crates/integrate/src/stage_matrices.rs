//! The two matrices of Radau IIA's stage system, `γ/h - J` and `(α + iβ)/h - J`, factored
//! through the Jacobian's Hessenberg form (`hessenberg.rs`), or, where rows of `J` tie a
//! state to a single other one (a position to its velocity), densely after eliminating those
//! states (`dense_lu.rs`) and grouping the rest block lower triangular; the states `J`
//! leaves uncoupled solved apart.

use crate::dense_lu;
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
///
/// A state `p` whose row has a single entry `a` in another state `t`'s column (`ẋ_p = a x_t`:
/// a hinge angle and its rate, an elastic coordinate and its rate) is eliminated as well,
/// `x_p = (b_p + a x_t) / c`, when `t`'s own row is coupled. What is left to factor is
/// `c - J' - K/c`, `J'` the coupled block and `K` the eliminated states' columns moved onto
/// their targets' (`K[r, t] = Σ J[r, p] a`). That is not a shift of one matrix, so it is
/// factored densely at each step size, `O(m³)`, but on `m` coupled states instead of `m + e`,
/// and its solves need no orthogonal transforms. On the flexible deployment (then 14 of its
/// 49 states eliminated, 32 left) the linear algebra took 174 M of the run's 562 M
/// instructions through the Hessenberg form and 112 M of 492 M this way. Where few states
/// are tied among many, the Hessenberg form stays cheaper and is kept (the rule in
/// [`Self::reduce`]).
///
/// The coupled states are then ordered by groups that read only themselves and the groups
/// before them ([`Self::group`]), so that both matrices are block lower triangular and are
/// factored block by block. On the flexible deployment today 17 states are eliminated (the
/// hinge angles, the elastic coordinates, the orbit's position) and 27 are coupled: the
/// orbit's 3 velocities, which read only the orbit, and the 24 others, which read it through
/// the gravity gradient. A factorisation of the pair takes 96 k instructions where the one
/// `27 × 27` block took 119 k.
#[derive(Clone, Debug)]
pub(crate) struct StageMatrices {
    n: usize,
    /// The coupled states (the reduced `J`'s rows and columns, in order), those with a zero
    /// row, and those with a zero column (and a row that is not zero).
    active: Vec<usize>,
    inert: Vec<usize>,
    last: Vec<usize>,
    /// Whether states are eliminated and the rest factored densely.
    dense: bool,
    /// With eliminated states: the bounds of `active`'s groups, each reading only itself
    /// and the groups before it (the strongly connected components of `J'` and `K`), so
    /// that the dense matrices are block lower triangular and factor block by block.
    bounds: Vec<usize>,
    /// Scratch of the grouping: which coupled state reads which, and Tarjan's marks.
    reads: Vec<bool>,
    tarjan: Tarjan,
    /// The eliminated states `p`, their targets' places in `active`, and `a = J[p, t]`.
    elim: Vec<usize>,
    target: Vec<usize>,
    elim_a: Vec<f64>,
    /// `J[active, inert]`, row-major, and `J[last, :]`, row-major.
    j_ai: Vec<f64>,
    j_last: Vec<f64>,
    /// With eliminated states: `J[active, elim]`, row-major; `J[active, active]` and `K`,
    /// column-major as the factorisations take them.
    j_ae: Vec<f64>,
    j_aa: Vec<f64>,
    k: Vec<f64>,
    hess: Hessenberg,
    real: RealLu,
    complex: ComplexLu,
    dense_real: dense_lu::RealLu,
    dense_complex: dense_lu::ComplexLu,
    /// Whether the entries kept apart from the factored block are all finite (checked once
    /// per Jacobian).
    finite: bool,
    /// The shifts factored: `γ/h` and `(α + iβ)/h`.
    c1: f64,
    c2: (f64, f64),
    /// Scratch for the coupled states (real; complex re and im), and for the eliminated
    /// states' `b / c` (real; complex re and im).
    s: [Vec<f64>; 3],
    y: [Vec<f64>; 3],
    /// Scratch of the sorting: each state's place in `active`, its row's single entry.
    place: Vec<usize>,
    tie: Vec<Option<usize>>,
    /// Scratch of the sorting: each row's entries (0, 1, 2 for more) and single column,
    /// each column's emptiness.
    row: Vec<(usize, usize)>,
    zero_column: Vec<bool>,
}

impl StageMatrices {
    pub fn new(n: usize) -> Self {
        Self {
            n,
            active: Vec::with_capacity(n),
            inert: Vec::with_capacity(n),
            last: Vec::with_capacity(n),
            dense: false,
            bounds: Vec::with_capacity(n + 1),
            reads: Vec::with_capacity(n * n),
            tarjan: Tarjan::new(n),
            elim: Vec::with_capacity(n),
            target: Vec::with_capacity(n),
            elim_a: Vec::with_capacity(n),
            j_ai: Vec::with_capacity(n * n),
            j_last: Vec::with_capacity(n * n),
            j_ae: Vec::with_capacity(n * n),
            j_aa: Vec::with_capacity(n * n),
            k: Vec::with_capacity(n * n),
            hess: Hessenberg::new(n),
            real: RealLu::new(n),
            complex: ComplexLu::new(n),
            dense_real: dense_lu::RealLu::new(n),
            dense_complex: dense_lu::ComplexLu::new(n),
            finite: true,
            c1: f64::NAN,
            c2: (f64::NAN, f64::NAN),
            s: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            y: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            place: vec![usize::MAX; n],
            tie: vec![None; n],
            row: vec![(0, 0); n],
            zero_column: vec![false; n],
        }
    }

    /// Sorts the states by `J`'s zero rows and columns and its rows with a single entry, and
    /// reduces the coupled block (or keeps it for the dense factorisations).
    pub fn reduce(&mut self, j: impl Fn(usize, usize) -> f64) {
        let n = self.n;
        self.active.clear();
        self.inert.clear();
        self.last.clear();
        self.elim.clear();
        self.target.clear();
        self.elim_a.clear();
        // Each row's number of entries (0, 1 or 2 for more) with its column where it has
        // one, and each column's emptiness: made once, read by both passes below.
        for r in 0..n {
            let mut row = (0, 0);
            for c in 0..n {
                if j(r, c) != 0.0 {
                    row = if row.0 == 0 { (1, c) } else { (2, 0) };
                    if row.0 == 2 {
                        break;
                    }
                }
            }
            self.row[r] = row;
            self.zero_column[r] = (0..n).all(|q| j(q, r) == 0.0);
        }
        let (row, zero_column) = (&self.row, &self.zero_column);
        // The candidates: a single entry in another state's column whose row is coupled.
        let tie = &mut self.tie;
        let mut coupled = 0;
        for r in 0..n {
            let (count, c) = row[r];
            tie[r] = (count == 1 && c != r && row[c].0 == 2).then_some(c);
            if count > 0 && tie[r].is_none() && !zero_column[r] {
                coupled += 1;
            }
        }
        let e = tie.iter().flatten().count();
        // Dense on the `m` coupled states or Hessenberg on `m + e`: the costs measured a
        // factorisation and its three stage solves on the flexible deployment, about
        // `3.7 m³ + 90 m²` against `164 (m + e)²` instructions.
        let (md, ma) = (coupled as f64, (coupled + e) as f64);
        self.dense = e > 0 && md * md * (3.7 * md + 90.0) < 164.0 * ma * ma;
        for r in 0..n {
            if !self.dense {
                tie[r] = None;
            }
            if tie[r].is_some() {
                continue;
            }
            if row[r].0 == 0 {
                self.inert.push(r);
            } else if zero_column[r] {
                self.last.push(r);
            } else {
                self.place[r] = self.active.len();
                self.active.push(r);
            }
        }
        if self.dense {
            self.group(&j);
        }
        let tie = &self.tie;
        for (p, t) in tie.iter().enumerate() {
            if let Some(t) = *t {
                self.elim.push(p);
                self.target.push(self.place[t]);
                self.elim_a.push(j(p, t));
            }
        }
        let gather = |into: &mut Vec<f64>, rows: &[usize], cols: &[usize]| {
            into.clear();
            for &r in rows {
                into.extend(cols.iter().map(|&c| j(r, c)));
            }
        };
        gather(&mut self.j_ai, &self.active, &self.inert);
        self.j_last.clear();
        for &f in &self.last {
            self.j_last.extend((0..n).map(|c| j(f, c)));
        }
        let kept = [&self.j_ai, &self.j_last];
        self.finite = kept.iter().all(|v| v.iter().all(|x| x.is_finite()));
        let active = &self.active;
        if !self.dense {
            self.hess
                .reduce(active.len(), |r, c| j(active[r], active[c]));
            return;
        }
        gather(&mut self.j_ae, active, &self.elim);
        // Column-major: the rows of the transpose.
        gather(&mut self.j_aa, active, active);
        let m = active.len();
        for r in 0..m {
            for c in r + 1..m {
                self.j_aa.swap(r * m + c, c * m + r);
            }
        }
        let e = self.elim.len();
        self.k.clear();
        self.k.resize(m * m, 0.0);
        for r in 0..m {
            for q in 0..e {
                self.k[self.target[q] * m + r] += self.j_ae[r * e + q] * self.elim_a[q];
            }
        }
        self.finite &= self.j_ae.iter().chain(&self.elim_a).all(|x| x.is_finite());
    }

    /// Orders the coupled states by groups that read only themselves and the groups before
    /// them (Tarjan's strongly connected components of "row reads column" in `J'` and, through
    /// the eliminated states, `K`), each group in the states' order, and sets the bounds.
    /// An orbit under Kepler's or a field's gravity reads only itself while the attitude
    /// reads it (the gravity gradient): on the flexible deployment the orbit's 3 velocities
    /// come out ahead of the other 24 coupled states, and the factorisations are of `24 × 24`
    /// and `3 × 3` where they were of `27 × 27`.
    fn group(&mut self, j: &impl Fn(usize, usize) -> f64) {
        let m = self.active.len();
        self.reads.clear();
        self.reads.resize(m * m, false);
        for (r, &a) in self.active.iter().enumerate() {
            for (c, &b) in self.active.iter().enumerate() {
                self.reads[r * m + c] = j(a, b) != 0.0;
            }
            for (p, t) in self.tie.iter().enumerate() {
                if let Some(t) = *t
                    && j(a, p) != 0.0
                {
                    self.reads[r * m + self.place[t]] = true;
                }
            }
        }
        self.tarjan.run(m, &self.reads, &mut self.bounds);
        let order = &mut self.tarjan.order;
        for (k, o) in order.iter_mut().enumerate() {
            *o = self.active[*o];
            self.place[*o] = k;
        }
        self.active.copy_from_slice(order);
    }

    /// Factors both matrices at step `h`'s shifts `c1 = γ/h`, `c2 = (α + iβ)/h`; false when
    /// either is singular or not finite.
    pub fn factor(&mut self, c1: f64, c2: (f64, f64)) -> bool {
        (self.c1, self.c2) = (c1, c2);
        if !(c1 != 0.0 && c2 != (0.0, 0.0) && self.finite) {
            return false;
        }
        if !self.dense {
            return self.real.factor(c1, &self.hess) && self.complex.factor(c2.0, c2.1, &self.hess);
        }
        // c - J' - K / c, the complex one with 1/c = (cr - i ci) / |c|².
        let m = self.active.len();
        let (cr, ci) = c2;
        let d = cr * cr + ci * ci;
        let (kr, ki, k1) = (cr / d, -ci / d, 1.0 / c1);
        self.dense_real.start_blocks(&self.bounds);
        self.dense_complex.start_blocks(&self.bounds);
        let a = self.dense_real.matrix_mut();
        for ((a, j), k) in a.iter_mut().zip(&self.j_aa).zip(&self.k) {
            *a = -j - k * k1;
        }
        let (are, aim) = self.dense_complex.matrix_mut();
        let it = are.iter_mut().zip(aim.iter_mut());
        for ((ar, ai), (j, k)) in it.zip(self.j_aa.iter().zip(&self.k)) {
            *ar = -j - k * kr;
            *ai = -k * ki;
        }
        for i in 0..m {
            a[i * m + i] += c1;
            are[i * m + i] += cr;
            aim[i * m + i] += ci;
        }
        self.dense_real.factor() && self.dense_complex.factor()
    }

    /// `b ← (γ/h - J)⁻¹ b`.
    pub fn solve_real(&mut self, b: &mut [f64]) {
        self.gather(0, b, None);
        let (m, ne) = (self.active.len(), self.elim.len());
        let (a, z) = (&self.active, &self.inert);
        let y = &self.y[0][..ne];
        coupled_right_side(&mut self.s[0][..m], b, a, z, &self.j_ai, &self.j_ae, y);
        let s = &mut self.s[0][..m];
        if !self.dense {
            self.hess.apply_qt([&mut *s]);
            self.real.solve_h(s);
            self.hess.apply_q([s]);
        } else {
            self.dense_real.solve(s);
        }
        self.scatter(0, b, None);
    }

    /// `d1 ← (γ/h - J)⁻¹ d1` and `d2 + i d3 ← ((α + iβ)/h - J)⁻¹ (d2 + i d3)`, the three
    /// through `Qᵀ` and `Q` together.
    pub fn solve_stages(&mut self, d1: &mut [f64], d2: &mut [f64], d3: &mut [f64]) {
        self.gather(0, d1, None);
        self.gather(1, d2, Some(&mut *d3));
        let (m, ne) = (self.active.len(), self.elim.len());
        let [s1, s2, s3] = &mut self.s;
        let (s1, s2, s3) = (&mut s1[..m], &mut s2[..m], &mut s3[..m]);
        let [y1, y2, y3] = &self.y;
        coupled_right_sides(
            [&mut *s1, &mut *s2, &mut *s3],
            [d1, d2, d3],
            [&y1[..ne], &y2[..ne], &y3[..ne]],
            (&self.active, &self.inert),
            (&self.j_ai, &self.j_ae),
        );
        if !self.dense {
            self.hess.apply_qt([&mut *s1, &mut *s2, &mut *s3]);
            self.real.solve_h(s1);
            self.complex.solve_h(s2, s3);
            self.hess.apply_q([s1, s2, s3]);
        } else {
            self.dense_real.solve(s1);
            self.dense_complex.solve(s2, s3);
        }
        self.scatter(0, d1, None);
        self.scatter(1, d2, Some(d3));
    }

    /// The states with a zero row solved (`b / c`, in place), and the eliminated states'
    /// `b / c` into scratch `y[k]` (and `y[k + 1]`, the imaginary part, for the complex
    /// shift: `im` given), for the coupled states' right side.
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
        // The eliminated states' b / c (their rows are left for the scatter).
        let (yr, rest) = self.y[k..].split_first_mut().expect("scratch");
        for (q, &p) in self.elim.iter().enumerate() {
            let (xr, xi) = (re[p], im.as_ref().map_or(0.0, |i| i[p]));
            yr[q] = (xr * cr + xi * ci) / d;
            if im.is_some() {
                rest[0][q] = (xi * cr - xr * ci) / d;
            }
        }
    }

    /// The coupled states back from scratch `k` (`k + 1`), the eliminated ones,
    /// `x = (b + a x_t) / c`, then the states with a zero column, `x = (b + J[last, :] x) / c`.
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
        for (q, &p) in self.elim.iter().enumerate() {
            let (a, t) = (self.elim_a[q], self.active[self.target[q]]);
            let xr = re[p] + a * re[t];
            let xi = im.as_ref().map_or(0.0, |i| i[p] + a * i[t]);
            re[p] = (xr * cr + xi * ci) / d;
            if let Some(i) = im.as_mut() {
                i[p] = (xi * cr - xr * ci) / d;
            }
        }
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

/// Tarjan's strongly connected components, with their storage kept from one Jacobian to
/// the next.
#[derive(Clone, Debug)]
struct Tarjan {
    /// The nodes by component, each component's nodes ascending, each component after
    /// those it reads.
    order: Vec<usize>,
    index: Vec<usize>,
    low: Vec<usize>,
    on_stack: Vec<bool>,
    stack: Vec<usize>,
    next: usize,
}

impl Tarjan {
    fn new(n: usize) -> Self {
        Self {
            order: Vec::with_capacity(n),
            index: Vec::with_capacity(n),
            low: Vec::with_capacity(n),
            on_stack: Vec::with_capacity(n),
            stack: Vec::with_capacity(n),
            next: 0,
        }
    }

    /// The components of the graph on `m` nodes where `reads[r * m + c]` is an edge from
    /// `r` to `c`, into `order`, and their bounds (from 0 to `m`) into `bounds`. Tarjan's
    /// algorithm closes a component only after every component reachable from it, so the
    /// components come out each after those it reads.
    fn run(&mut self, m: usize, reads: &[bool], bounds: &mut Vec<usize>) {
        self.order.clear();
        self.stack.clear();
        self.index.clear();
        self.index.resize(m, usize::MAX);
        self.low.clear();
        self.low.resize(m, 0);
        self.on_stack.clear();
        self.on_stack.resize(m, false);
        self.next = 0;
        bounds.clear();
        bounds.push(0);
        for v in 0..m {
            if self.index[v] == usize::MAX {
                self.visit(v, m, reads, bounds);
            }
        }
    }

    /// Depth-first from `v`; the recursion is at most as deep as the coupled states are many,
    /// which the dense route's cost rule keeps to a few hundred.
    fn visit(&mut self, v: usize, m: usize, reads: &[bool], bounds: &mut Vec<usize>) {
        self.index[v] = self.next;
        self.low[v] = self.next;
        self.next += 1;
        self.stack.push(v);
        self.on_stack[v] = true;
        for w in 0..m {
            if !reads[v * m + w] {
                continue;
            }
            if self.index[w] == usize::MAX {
                self.visit(w, m, reads, bounds);
                self.low[v] = self.low[v].min(self.low[w]);
            } else if self.on_stack[w] {
                self.low[v] = self.low[v].min(self.index[w]);
            }
        }
        if self.low[v] == self.index[v] {
            let start = self.order.len();
            loop {
                let w = self.stack.pop().expect("on the stack");
                self.on_stack[w] = false;
                self.order.push(w);
                if w == v {
                    break;
                }
            }
            self.order[start..].sort_unstable();
            bounds.push(self.order.len());
        }
    }
}

/// [`coupled_right_side`] for the three stage vectors at once: each row of `J[active, :]`
/// read once for the three (a third of the loads, and three chains of additions side by
/// side).
fn coupled_right_sides(
    out: [&mut [f64]; 3],
    b: [&[f64]; 3],
    y: [&[f64]; 3],
    (active, inert): (&[usize], &[usize]),
    (j_ai, j_ae): (&[f64], &[f64]),
) {
    let (nz, ne) = (inert.len(), y[0].len());
    let [o1, o2, o3] = out;
    let [y1, y2, y3] = y;
    for (r, &a) in active.iter().enumerate() {
        let mut s = [b[0][a], b[1][a], b[2][a]];
        for (jz, &z) in j_ai[r * nz..(r + 1) * nz].iter().zip(inert) {
            s[0] += jz * b[0][z];
            s[1] += jz * b[1][z];
            s[2] += jz * b[2][z];
        }
        let it = y1.iter().zip(y2).zip(y3);
        for (je, ((p, q), t)) in j_ae[r * ne..(r + 1) * ne].iter().zip(it) {
            s[0] += je * p;
            s[1] += je * q;
            s[2] += je * t;
        }
        (o1[r], o2[r], o3[r]) = (s[0], s[1], s[2]);
    }
}

/// `out[r] = b[active[r]] + J[active[r], inert] b[inert] + J[active[r], elim] y`, the
/// coupled states' right side (`b[inert]` already solved, `y` the eliminated states' `b / c`).
fn coupled_right_side(
    out: &mut [f64],
    b: &[f64],
    active: &[usize],
    inert: &[usize],
    j_ai: &[f64],
    j_ae: &[f64],
    y: &[f64],
) {
    let (nz, ne) = (inert.len(), y.len());
    for (r, (o, &a)) in out.iter_mut().zip(active).enumerate() {
        let mut s = b[a];
        if nz > 0 {
            for (jz, &z) in j_ai[r * nz..(r + 1) * nz].iter().zip(inert) {
                s += jz * b[z];
            }
        }
        if ne > 0 {
            s += dot(&j_ae[r * ne..(r + 1) * ne], y);
        }
        *o = s;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hessenberg::tests::{entries, matrix};

    /// Solves with `γ/h - J` and `(α + iβ)/h - J` through `st` (reduced and factored here)
    /// and checks them against `x` with `b = (c - J) x` formed directly; `zero` is a state
    /// whose solution must come out exactly zero.
    fn check_solves(st: &mut StageMatrices, j: &[f64], n: usize, zero: Option<usize>) {
        st.reduce(|r, c| j[r * n + c]);
        let (c1, c2) = (0.4, (0.3, 0.8));
        assert!(st.factor(c1, c2));
        let mut next = entries(3);
        let x: Vec<[f64; 3]> = (0..n).map(|_| [next(), next(), next()]).collect();
        let xs = |s: usize, i: usize| if Some(i) == zero { 0.0 } else { x[i][s] };
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
        if let Some(z) = zero {
            assert!([b0[z], b1[z], b2[z], b3[z]].iter().all(|v| *v == 0.0));
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
        check_solves(&mut st, &j, n, Some(5));
        assert_eq!(
            (st.inert.as_slice(), st.last.as_slice()),
            (&[2, 5][..], &[7][..])
        );
        assert!(!st.dense);
    }

    #[test]
    fn positions_tied_to_their_rates_are_eliminated_and_the_solves_stay_exact() {
        // States 0..4 positions whose rows read only their rates 4..8 (scaled as a
        // quaternion's would be), 8 and 9 coupled, 10 a zero row (a locked rate), 11 a zero
        // column, 12 a position of the locked rate (its target's row is zero: not
        // eliminated), 13 a row with a single entry on its own diagonal (kept).
        let n = 14;
        let mut j = matrix(n, 11);
        for p in [0, 1, 2, 3, 10, 12, 13] {
            j[p * n..(p + 1) * n].fill(0.0);
        }
        for p in 0..4 {
            j[p * n + 4 + p] = [1.0, 0.5, -2.0, 1.0][p];
        }
        j[12 * n + 10] = 1.0;
        j[13 * n + 13] = -3.0;
        for r in 0..n {
            j[r * n + 11] = 0.0;
        }
        let mut st = StageMatrices::new(n);
        check_solves(&mut st, &j, n, Some(10));
        assert!(st.dense);
        assert_eq!(st.elim, [0, 1, 2, 3]);
        assert_eq!(
            (st.inert.as_slice(), st.last.as_slice()),
            (&[10][..], &[11][..])
        );
        // 12 reads only the locked rate and 13 only itself: groups of their own, ahead of the
        // rates 4..8 and 8, 9 that read them.
        assert_eq!(st.active, [12, 13, 4, 5, 6, 7, 8, 9]);
        assert_eq!(st.bounds, [0, 1, 2, 8]);
        // The same matrix refactored at other shifts keeps solving it.
        assert!(st.factor(2.5, (1.5, -0.7)));
    }

    #[test]
    fn a_group_that_reads_only_itself_is_solved_ahead_of_the_states_that_read_it() {
        // An orbit: positions 0..3 read only their velocities 3..6, which read only the
        // positions; states 6..12 (an attitude and its rates) read everything, the orbit
        // too. The orbit's velocities are a group of their own ahead of the rest, and the
        // block-triangular solves stay exact.
        let n = 12;
        let mut j = matrix(n, 23);
        for r in 0..6 {
            j[r * n..(r + 1) * n].fill(0.0);
        }
        for p in 0..3 {
            j[p * n + 3 + p] = 1.0;
            for q in 0..3 {
                j[(3 + p) * n + q] = [[-2.0, 0.5, 0.1], [0.5, -1.0, 0.2], [0.1, 0.2, -3.0]][p][q];
            }
        }
        let mut st = StageMatrices::new(n);
        check_solves(&mut st, &j, n, None);
        assert!(st.dense);
        assert_eq!(st.elim, [0, 1, 2]);
        assert_eq!(st.active, [3, 4, 5, 6, 7, 8, 9, 10, 11]);
        assert_eq!(st.bounds, [0, 3, 9]);
        // Let the orbit read the attitude as well: one group, in the states' order.
        j[3 * n + 7] = 0.3;
        check_solves(&mut st, &j, n, None);
        assert_eq!(st.bounds, [0, 9]);
        assert_eq!(st.active, [3, 4, 5, 6, 7, 8, 9, 10, 11]);
    }

    #[test]
    fn a_few_ties_among_many_coupled_states_keep_the_hessenberg_form() {
        // One tie among 40 states: dense factorisations of 39 would cost more than the
        // Hessenberg route's solves save.
        let n = 40;
        let mut j = matrix(n, 5);
        j[..n].fill(0.0);
        j[1] = 1.0;
        let mut st = StageMatrices::new(n);
        check_solves(&mut st, &j, n, None);
        assert!(!st.dense && st.elim.is_empty());
        assert_eq!(st.active.len(), n);
    }
}
