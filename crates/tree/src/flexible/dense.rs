//! In-place Cholesky factorisation and solve of the small dense blocks of the flexible
//! algorithms (a body's `(1 + m)` hinge-and-modes pivot, the root's `6 + m` system), on
//! caller-owned row-major slices: no allocation.

/// Factors the symmetric `n x n` matrix in `a` (row-major, lower triangle read) into `L`
/// (lower triangle written, `A = L Lᵀ`). `false` unless positive definite.
pub(crate) fn cholesky(a: &mut [f64], n: usize) -> bool {
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
    forward(l, n, b);
    backward(l, n, b);
}
