//! [`ThrustAllocation`]: a wanted body torque allocated over thrusters, which only push
//! (`[fsw.control] actuator = "thrusters"`, contract section 16).
//!
//! Thruster `j` pushes with `f_j ≥ 0` (N) along its unit direction `d_j` at the point `r_j`
//! (root body axes and frame, m). About the system's centre of mass `c` (root frame) it
//! makes the torque `f_j a_j`, `a_j = (r_j − c) × d_j` (its arm). With `F_j` its `thrust`
//! and `δ_j = f_j / F_j` its duty, the wanted torque `u` (N m, root axes) is allocated as
//! the non-negative least-squares duties
//!
//! ```text
//! δ = argmin_{δ ≥ 0} |B δ − u|² + λ² |δ|²,   B = [F_1 a_1 … F_k a_k]  (3 × k),
//! λ = 1e-6 max_ij |B_ij|
//! ```
//!
//! solved as the non-negative least squares of the stacked system `[B; λ I] δ = [u; 0]` by
//! the active-set algorithm of Lawson and Hanson ([`nnls`]; C. L. Lawson, R. J. Hanson,
//! *Solving Least Squares Problems*, Prentice-Hall 1974, chapter 23, algorithm NNLS): `B δ
//! = u` to a relative 1e-12 when `u` lies in the cone of the arms, else the torque of that
//! cone nearest to `u`. The small `λ` picks, among the duties that make it, the smallest
//! (least squares): thrusters of the same arm share the torque evenly (both of a couple
//! fire together, rather than one of them alone), and the busiest thruster is as idle as
//! the least squares allow. Then the whole vector is scaled down by `s = min(1, 1 / max_j
//! δ_j)` when one would exceed 1, keeping the torque's direction. The net force `Σ f_j d_j`
//! is not controlled (attitude only): thrusters in couples make none, others push the
//! orbit as well.

use nalgebra::{DMatrix, DVector, Vector3};

/// The non-negative least-squares solution `x ≥ 0` of `min |A x − b|²` (`A` of `m` rows,
/// `n = x.len()` columns), by Lawson and Hanson's active-set algorithm NNLS (1974, chapter
/// 23): start from `x = 0` with every variable held at zero; move in the one whose gradient
/// `w = Aᵀ(b − A x)` is the largest positive, solve the unconstrained least squares over the
/// free set, and step back to the boundary (freeing none, holding those that reach zero)
/// while that solution has an entry `≤ 0`; stop when no held variable has `w_j > tol`. It
/// ends in finitely many steps (at most `3 n` outer iterations here, a safeguard against
/// round-off cycling). `tol` scales with `|A|` and `|b|`.
pub fn nnls(a: &DMatrix<f64>, b: &DVector<f64>, x: &mut [f64]) {
    let n = a.ncols();
    assert_eq!(x.len(), n, "one unknown per column");
    x.fill(0.0);
    let bn = b.norm();
    if n == 0 || bn == 0.0 {
        return;
    }
    let amax = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let tol = 10.0 * f64::EPSILON * (a.nrows().max(n) as f64) * amax * bn;
    let mut free = vec![false; n];
    let gradient = |x: &[f64]| -> DVector<f64> {
        let r = b - a * DVector::from_column_slice(x);
        a.transpose() * r
    };
    // The unconstrained least squares over the free columns (zero elsewhere).
    let solve = |free: &[bool]| -> Vec<f64> {
        let cols: Vec<usize> = (0..n).filter(|&j| free[j]).collect();
        let sub = DMatrix::from_fn(a.nrows(), cols.len(), |r, c| a[(r, cols[c])]);
        let s = least_squares(sub, b, 1e-12 * amax);
        let mut z = vec![0.0; n];
        for (k, &j) in cols.iter().enumerate() {
            z[j] = s[k];
        }
        z
    };
    for _ in 0..3 * n {
        let w = gradient(x);
        let Some(j) = (0..n)
            .filter(|&j| !free[j] && w[j] > tol)
            .max_by(|&i, &j| w[i].total_cmp(&w[j]))
        else {
            return;
        };
        free[j] = true;
        loop {
            let z = solve(&free);
            if (0..n).all(|i| !free[i] || z[i] > 0.0) {
                x.copy_from_slice(&z);
                break;
            }
            // Step from x towards z up to the first free variable that reaches zero, and
            // hold it (and any other at zero) there.
            let (mut alpha, mut hit) = (1.0f64, None);
            for i in (0..n).filter(|&i| free[i] && z[i] <= 0.0) {
                let r = x[i] / (x[i] - z[i]);
                if r < alpha || hit.is_none() {
                    alpha = alpha.min(r);
                    hit = Some(i);
                }
            }
            for i in 0..n {
                x[i] += alpha * (z[i] - x[i]);
                if free[i] && (Some(i) == hit || x[i] <= 0.0) {
                    free[i] = false;
                    x[i] = 0.0;
                }
            }
            if !free.iter().any(|&f| f) {
                break;
            }
        }
    }
}

/// The least-squares solution of `m x = b`: by Householder QR where `m` has full column
/// rank (`|R_ii| > tol`, the accurate way for a stacked, regularised system), else the
/// minimum-norm solution by SVD (singular values below `tol` dropped).
fn least_squares(m: DMatrix<f64>, b: &DVector<f64>, tol: f64) -> DVector<f64> {
    let k = m.ncols();
    if k <= m.nrows() {
        let qr = m.clone().qr();
        let r = qr.r();
        if (0..k).all(|i| r[(i, i)].abs() > tol) {
            let qtb = qr.q().transpose() * b;
            if let Some(x) = r.solve_upper_triangular(&qtb) {
                return x;
            }
        }
    }
    m.svd(true, true)
        .solve(b, tol)
        .unwrap_or_else(|_| DVector::zeros(k))
}

/// Thrusters on the root body, and the duties that make a wanted torque: see the module
/// documentation.
#[derive(Clone, Debug, PartialEq)]
pub struct ThrustAllocation {
    /// Each thruster's point (m, root frame).
    at: Vec<Vector3<f64>>,
    /// Each thruster's unit direction (root axes).
    direction: Vec<Vector3<f64>>,
    /// Each thruster's force while on (N, > 0).
    thrust: Vec<f64>,
}

impl ThrustAllocation {
    /// Thrusters at `at` (m, root frame) pushing along the unit `direction`s (root axes)
    /// with `thrust` (N, > 0) each.
    pub fn new(at: &[Vector3<f64>], direction: &[Vector3<f64>], thrust: &[f64]) -> Self {
        assert!(at.len() == direction.len() && at.len() == thrust.len());
        Self {
            at: at.to_vec(),
            direction: direction.to_vec(),
            thrust: thrust.to_vec(),
        }
    }
    /// Number of thrusters.
    pub fn len(&self) -> usize {
        self.at.len()
    }
    /// Whether it has none.
    pub fn is_empty(&self) -> bool {
        self.at.is_empty()
    }
    /// The arms `a_j = (r_j − c) × d_j` about the centre of mass `c` (root frame), as the
    /// columns of a 3 × k matrix (N m per N).
    pub fn arms(&self, com: &Vector3<f64>) -> DMatrix<f64> {
        DMatrix::from_fn(3, self.len(), |r, j| {
            (self.at[j] - com).cross(&self.direction[j])[r]
        })
    }
    /// The duties' least squares: `[B; λ I]` (B the torque per unit duty, see the module
    /// documentation), `3 + k` rows.
    fn stacked(&self, com: &Vector3<f64>) -> DMatrix<f64> {
        let k = self.len();
        let mut m = DMatrix::zeros(3 + k, k);
        for j in 0..k {
            let a = (self.at[j] - com).cross(&self.direction[j]) * self.thrust[j];
            m.view_mut((0, j), (3, 1)).copy_from(&a);
        }
        let lambda = 1e-6 * m.iter().fold(0.0f64, |x, v| x.max(v.abs()));
        for j in 0..k {
            m[(3 + j, j)] = lambda;
        }
        m
    }
    /// The unscaled duties of `u` on the stacked system `m` into `out`.
    fn unscaled(&self, m: &DMatrix<f64>, u: &Vector3<f64>, out: &mut [f64]) {
        let mut b = DVector::zeros(m.nrows());
        b.rows_mut(0, 3).copy_from(u);
        nnls(m, &b, out);
    }
    /// The duties (each in [0, 1], into `out`, one per thruster) that make the torque `u`
    /// (N m, root axes) about the centre of mass `com` (root frame), or the nearest the
    /// thrusters make, scaled down as a whole when one would exceed 1.
    pub fn duties(&self, com: &Vector3<f64>, u: &Vector3<f64>, out: &mut [f64]) {
        self.unscaled(&self.stacked(com), u, out);
        let top = out.iter().fold(1.0f64, |m, &d| m.max(d));
        if top > 1.0 {
            out.iter_mut().for_each(|d| *d /= top);
        }
    }
    /// The torque (N m, root axes, about `com`) of the thrusters at these duties, each on
    /// for that fraction of the time.
    pub fn torque(&self, com: &Vector3<f64>, duties: &[f64]) -> Vector3<f64> {
        (0..self.len())
            .map(|j| (self.at[j] - com).cross(&self.direction[j]) * self.thrust[j] * duties[j])
            .sum()
    }
    /// The largest torque the allocation makes about each root axis, both ways (the smaller
    /// of the two; N m): the integral's clamp of [`super::Pid`]. Zero about an axis it cannot
    /// torque exactly both ways.
    pub fn capability(&self, com: &Vector3<f64>) -> [f64; 3] {
        let mut cap = [0.0; 3];
        let mut d = vec![0.0; self.len()];
        let m = self.stacked(com);
        for (i, c) in cap.iter_mut().enumerate() {
            let mut both = f64::INFINITY;
            for sign in [1.0, -1.0] {
                let e = Vector3::ith(i, sign);
                // The unit torque's duties, unscaled: the largest multiple fits in 1.
                self.unscaled(&m, &e, &mut d);
                let top = d.iter().fold(0.0f64, |m, &x| m.max(x));
                let made = self.torque(com, &d);
                both = if top > 0.0 && (made - e).norm() < 1e-9 {
                    both.min(1.0 / top)
                } else {
                    0.0
                };
            }
            *c = both;
        }
        cap
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Twelve thrusters in couples: two pairs about each axis, both ways, on a 1 m cube.
    fn couples() -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
        let mut at = Vec::new();
        let mut dir = Vec::new();
        for i in 0..3 {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            for s in [1.0, -1.0] {
                // +s torque about axis i: at +e_j push along +s e_k, at −e_j along −s e_k.
                at.push(Vector3::ith(j, 0.5));
                dir.push(Vector3::ith(k, s));
                at.push(Vector3::ith(j, -0.5));
                dir.push(Vector3::ith(k, -s));
            }
        }
        (at, dir)
    }

    /// A small deterministic generator (no dependency): uniform in [-1, 1).
    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    /// The least residual over every subset of columns whose unconstrained least squares is
    /// non-negative: the NNLS optimum (its solution is such a subset's).
    fn brute_force(a: &DMatrix<f64>, b: &DVector<f64>) -> f64 {
        let n = a.ncols();
        let mut best = b.norm();
        for mask in 1u32..(1 << n) {
            let cols: Vec<usize> = (0..n).filter(|j| mask & (1 << j) != 0).collect();
            if cols.len() > a.nrows() {
                continue;
            }
            let sub = DMatrix::from_fn(a.nrows(), cols.len(), |r, c| a[(r, cols[c])]);
            let Ok(s) = sub.clone().svd(true, true).solve(b, 1e-12) else {
                continue;
            };
            if s.iter().all(|v| *v >= -1e-12) {
                best = best.min((&sub * s - b).norm());
            }
        }
        best
    }

    #[test]
    fn nnls_is_exact_inside_the_cone_and_non_negative() {
        let (at, dir) = couples();
        let alloc = ThrustAllocation::new(&at, &dir, &[1.0; 12]);
        let a = alloc.arms(&Vector3::zeros());
        let mut x = vec![0.0; 12];
        for u in [
            Vector3::new(0.3, -0.2, 0.1),
            Vector3::new(-1.0, 0.0, 0.0),
            Vector3::new(0.0, 0.0, 2.5),
        ] {
            nnls(&a, &DVector::from_column_slice(u.as_slice()), &mut x);
            assert!(x.iter().all(|&f| f >= 0.0), "{x:?}");
            let made = &a * DVector::from_column_slice(&x);
            assert!((made - DVector::from_column_slice(u.as_slice())).norm() < 1e-12);
        }
        // A push that none of the columns leans towards: nothing fires.
        let one = DMatrix::from_column_slice(3, 2, &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        let mut y = vec![1.0; 2];
        nnls(
            &one,
            &DVector::from_column_slice(&[-1.0, -2.0, 3.0]),
            &mut y,
        );
        assert_eq!(y, [0.0, 0.0]);
        // Only the part it can make: the projection on the cone.
        nnls(&one, &DVector::from_column_slice(&[-1.0, 2.0, 3.0]), &mut y);
        assert_eq!(y, [0.0, 2.0]);
    }

    #[test]
    fn nnls_reaches_the_brute_force_optimum_over_active_sets() {
        let mut seed = 7u64;
        for trial in 0..300 {
            let n = 2 + trial % 7;
            let a = DMatrix::from_fn(3, n, |_, _| lcg(&mut seed));
            let b = DVector::from_fn(3, |_, _| lcg(&mut seed));
            let mut x = vec![0.0; n];
            nnls(&a, &b, &mut x);
            assert!(x.iter().all(|&v| v >= 0.0), "{x:?}");
            let r = (&a * DVector::from_column_slice(&x) - &b).norm();
            let best = brute_force(&a, &b);
            assert!(r <= best + 1e-10, "trial {trial}: {r} > {best}");
            // Optimality (KKT): no held variable's gradient points inwards.
            let w = a.transpose() * (&b - &a * DVector::from_column_slice(&x));
            for j in 0..n {
                assert!(w[j] <= 1e-10, "trial {trial}: w[{j}] = {}", w[j]);
                if x[j] > 0.0 {
                    assert!(w[j].abs() <= 1e-10, "trial {trial}: w[{j}] = {}", w[j]);
                }
            }
        }
    }

    #[test]
    fn duties_scale_down_as_a_whole_keeping_the_direction_about_the_centre_of_mass() {
        let (at, dir) = couples();
        let thrust = [2.0; 12];
        let alloc = ThrustAllocation::new(&at, &dir, &thrust);
        // The centre of mass off the geometric centre: the arms follow it.
        let com = Vector3::new(0.1, -0.05, 0.02);
        let mut d = vec![0.0; 12];
        let u = Vector3::new(0.4, -0.3, 0.2);
        alloc.duties(&com, &u, &mut d);
        assert!(d.iter().all(|&x| (0.0..=1.0).contains(&x)), "{d:?}");
        assert!((alloc.torque(&com, &d) - u).norm() < 1e-12 * u.norm());
        // About the centre: both thrusters of a couple share its torque, no net force.
        alloc.duties(&Vector3::zeros(), &u, &mut d);
        for pair in d.chunks(2) {
            assert!((pair[0] - pair[1]).abs() < 1e-9, "{d:?}");
        }
        let force: Vector3<f64> = (0..12).map(|j| dir[j] * thrust[j] * d[j]).sum();
        assert!(force.norm() < 1e-9, "{force}");
        // Ten times more than they make: scaled so the busiest is on all the time.
        let big = u * 10.0;
        alloc.duties(&com, &big, &mut d);
        let top = d.iter().fold(0.0f64, |m, &x| m.max(x));
        assert!((top - 1.0).abs() < 1e-12, "{d:?}");
        let made = alloc.torque(&com, &d);
        assert!(made.cross(&big).norm() < 1e-9 * big.norm() * made.norm());
        assert!(made.dot(&big) > 0.0 && made.norm() < big.norm());
        // One couple about each axis each way: 2 × 2 N × 0.5 m.
        let cap = alloc.capability(&Vector3::zeros());
        for c in cap {
            assert!((c - 2.0).abs() < 1e-9, "{cap:?}");
        }
        // Thrusters that cannot torque about z both ways: no capability there.
        let half = ThrustAllocation::new(&at[..10], &dir[..10], &thrust[..10]);
        assert_eq!(half.capability(&Vector3::zeros())[2], 0.0);
    }
}
