//! In-place Cholesky factorisation and solve of the small dense blocks of the flexible
//! algorithms (a body's `(1 + m)` hinge-and-modes pivot, the root's `6 + m` system), on
//! caller-owned row-major slices: no allocation.

/// Factors the symmetric `n x n` matrix in `a` (row-major, lower triangle read) into `L`
/// (lower triangle written, `A = L Lᵀ`). `false` unless positive definite.
pub(crate) fn cholesky(a: &mut [f64], n: usize) -> bool {
    if n == 1 {
        // A rigid hinge's pivot, most of a tree's: no loops.
        let d = a[0];
        a[0] = d.sqrt();
        return d > 0.0 && d.is_finite();
    }
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    true
}

/// `b ← L⁻¹ b` (forward substitution) with the factor of [`cholesky`].
pub(crate) fn forward(l: &[f64], n: usize, b: &mut [f64]) {
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i * n + k] * b[k];
        }
        b[i] = s / l[i * n + i];
    }
}

/// `b ← L⁻ᵀ b` (backward substitution) with the factor of [`cholesky`].
pub(crate) fn backward(l: &[f64], n: usize, b: &mut [f64]) {
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= l[k * n + i] * b[k];
        }
        b[i] = s / l[i * n + i];
    }
}

/// `b ← A⁻¹ b` with the factor of [`cholesky`].
pub(crate) fn solve(l: &[f64], n: usize, b: &mut [f64]) {
    if n == 1 {
        b[0] = b[0] / l[0] / l[0];
        return;
    }
    forward(l, n, b);
    backward(l, n, b);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_one_by_one_pivot_is_the_general_factor_and_solve() {
        // The shortcut for n = 1 against the loops it skips (forward, then backward).
        for (a, b) in [(2.5, 7.0), (1e-9, -3.0), (4.0, 1.0)] {
            let mut l = [a];
            assert!(cholesky(&mut l, 1));
            assert_eq!(l[0], a.sqrt());
            let mut x = [b];
            solve(&l, 1, &mut x);
            let mut y = [b];
            forward(&l, 1, &mut y);
            backward(&l, 1, &mut y);
            assert_eq!(x, y);
        }
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(!cholesky(&mut [bad], 1), "{bad}");
        }
    }

    #[test]
    fn the_factor_solves_a_small_system() {
        let a = [4.0, 2.0, 0.4, 2.0, 5.0, 1.0, 0.4, 1.0, 3.0];
        let mut l = a;
        assert!(cholesky(&mut l, 3));
        let mut x = [1.0, -2.0, 0.5];
        let b = x;
        solve(&l, 3, &mut x);
        for i in 0..3 {
            let r: f64 = (0..3).map(|j| a[i * 3 + j] * x[j]).sum();
            assert!((r - b[i]).abs() < 1e-14, "{r} {}", b[i]);
        }
        let mut indefinite = [1.0, 2.0, 2.0, 1.0];
        assert!(!cholesky(&mut indefinite, 2));
    }
}
