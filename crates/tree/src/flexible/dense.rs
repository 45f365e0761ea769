//! In-place `L D Lᵀ` factorisation and solve of the small dense blocks of the flexible
//! algorithms (a body's `(1 + m)` hinge-and-modes pivot, the root's `6 + m` system), on
//! caller-owned row-major slices: no allocation.
//!
//! The factor keeps `L` (unit lower triangular) below the diagonal and `1 / dⱼ` on it: no
//! square roots, and the substitutions multiply where a Cholesky factor's divide. On these
//! short chains of dependent operations a square root or a division costs several
//! multiplications' latency: the flexible deployment's ABA took 11 % of the run's time in
//! the Cholesky factors and solves of its pivots (`perf`), for 2.5 % of its instructions.

/// Factors the symmetric `n x n` matrix in `a` (row-major, lower triangle read) into
/// `A = L D Lᵀ`: `L` (unit diagonal) below the diagonal, `1 / dⱼ` on it. Unless positive
/// definite (every `dⱼ > 0`, finite), the first pivot that is not: `Err((j, dⱼ))`.
///
/// The sizes of a body with up to five modes and of a free root without modes are
/// instances with `n` known (the loops unrolled, no index checks): the same operations in
/// the same order, so the same bits. Always inlined, as [`solve`]: the ABA's instances for a
/// mode count then pick their sizes with no call (0.3 % of the flexible deployment's
/// instructions, 0.7 % of its time).
#[inline(always)]
pub(crate) fn factor(a: &mut [f64], n: usize) -> Result<(), (usize, f64)> {
    match n {
        1 => {
            // A rigid hinge's pivot, most of a tree's: no loops.
            let d = a[0];
            a[0] = 1.0 / d;
            if d > 0.0 && d.is_finite() {
                Ok(())
            } else {
                Err((0, d))
            }
        }
        2 => factor_in(&mut a[..4], 2),
        3 => factor_in(&mut a[..9], 3),
        4 => factor_in(&mut a[..16], 4),
        5 => factor_in(&mut a[..25], 5),
        6 => factor_in(&mut a[..36], 6),
        _ => factor_in(a, n),
    }
}

/// Row by row: `tᵢⱼ = Lᵢⱼ dⱼ = aᵢⱼ − Σₖ₍ₖ<ⱼ₎ tᵢₖ Lⱼₖ` kept in row `i` until `dᵢ = aᵢᵢ −
/// Σₖ tᵢₖ Lᵢₖ` is known, each `Lᵢₖ = tᵢₖ / dₖ` taken on the way.
#[inline(always)]
fn factor_in(a: &mut [f64], n: usize) -> Result<(), (usize, f64)> {
    for i in 0..n {
        for j in 0..i {
            let mut t = a[i * n + j];
            for k in 0..j {
                t -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = t;
        }
        let mut d = a[i * n + i];
        for k in 0..i {
            let t = a[i * n + k];
            let l = t * a[k * n + k];
            d -= t * l;
            a[i * n + k] = l;
        }
        if !(d > 0.0 && d.is_finite()) {
            return Err((i, d));
        }
        a[i * n + i] = 1.0 / d;
    }
    Ok(())
}

/// `b ← L⁻¹ b` (forward substitution, `L` of unit diagonal) with the factor of [`factor`].
#[inline(always)]
pub(crate) fn forward(l: &[f64], n: usize, b: &mut [f64]) {
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i * n + k] * b[k];
        }
        b[i] = s;
    }
}

/// `b ← D⁻¹ b` with the factor of [`factor`].
#[inline(always)]
fn scale(l: &[f64], n: usize, b: &mut [f64]) {
    for i in 0..n {
        b[i] *= l[i * n + i];
    }
}

/// `b ← L⁻ᵀ b` (backward substitution, `L` of unit diagonal) with the factor of [`factor`].
#[inline(always)]
pub(crate) fn backward(l: &[f64], n: usize, b: &mut [f64]) {
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= l[k * n + i] * b[k];
        }
        b[i] = s;
    }
}

/// `b ← A⁻¹ b` with the factor of [`factor`] (the same sizes unrolled).
#[inline(always)]
pub(crate) fn solve(l: &[f64], n: usize, b: &mut [f64]) {
    match n {
        1 => b[0] *= l[0],
        2 => solve_in(&l[..4], 2, &mut b[..2]),
        3 => solve_in(&l[..9], 3, &mut b[..3]),
        4 => solve_in(&l[..16], 4, &mut b[..4]),
        5 => solve_in(&l[..25], 5, &mut b[..5]),
        6 => solve_in(&l[..36], 6, &mut b[..6]),
        _ => solve_in(l, n, b),
    }
}

#[inline(always)]
fn solve_in(l: &[f64], n: usize, b: &mut [f64]) {
    forward(l, n, b);
    scale(l, n, b);
    backward(l, n, b);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_one_by_one_pivot_is_the_general_factor_and_solve() {
        // The shortcut for n = 1 against the loops it skips.
        for (a, b) in [(2.5, 7.0), (1e-9, -3.0), (4.0, 1.0)] {
            let mut l = [a];
            assert!(factor(&mut l, 1).is_ok());
            let mut g = [a];
            assert!(factor_in(&mut g, std::hint::black_box(1)).is_ok());
            assert_eq!(l, g);
            let mut x = [b];
            solve(&l, 1, &mut x);
            let mut y = [b];
            solve_in(&g, std::hint::black_box(1), &mut y);
            assert_eq!(x, y);
            assert!((x[0] * a - b).abs() <= 1e-15 * b.abs());
        }
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = factor(&mut [bad], 1).unwrap_err();
            assert!(e.0 == 0 && e.1.total_cmp(&bad).is_eq(), "{bad}");
        }
    }

    #[test]
    fn the_factor_solves_a_small_system_and_is_l_d_lt() {
        let a = [4.0, 2.0, 0.4, 2.0, 5.0, 1.0, 0.4, 1.0, 3.0];
        let mut l = a;
        assert!(factor(&mut l, 3).is_ok());
        // L D Lᵀ from the factor: unit L below the diagonal, 1/d on it.
        let lij = |i: usize, j: usize| match i.cmp(&j) {
            std::cmp::Ordering::Greater => l[i * 3 + j],
            std::cmp::Ordering::Equal => 1.0,
            std::cmp::Ordering::Less => 0.0,
        };
        for i in 0..3 {
            for j in 0..3 {
                let r: f64 = (0..3).map(|k| lij(i, k) * lij(j, k) / l[k * 3 + k]).sum();
                assert!((r - a[i * 3 + j]).abs() < 1e-14, "({i}, {j}): {r}");
            }
        }
        let mut x = [1.0, -2.0, 0.5];
        let b = x;
        solve(&l, 3, &mut x);
        for i in 0..3 {
            let r: f64 = (0..3).map(|j| a[i * 3 + j] * x[j]).sum();
            assert!((r - b[i]).abs() < 1e-14, "{r} {}", b[i]);
        }
        // The first pivot that is not positive, and where: the second, 1 − 2²/1.
        let mut indefinite = [1.0, 2.0, 2.0, 1.0];
        assert_eq!(factor(&mut indefinite, 2), Err((1, -3.0)));
        let mut singular = [1.0, 1.0, 1.0, 1.0];
        assert_eq!(factor(&mut singular, 2), Err((1, 0.0)));
    }

    #[test]
    fn the_unrolled_sizes_are_the_loops_bit_for_bit() {
        // n from a black box: the general loops, against the instances with n known.
        for n in 2..=7usize {
            // A random-ish symmetric positive definite matrix: B Bᵀ + n I.
            let b: Vec<f64> = (0..n * n).map(|k| ((k * 7 + 3) as f64).sin()).collect();
            let mut a = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    a[i * n + j] = (0..n).map(|k| b[i * n + k] * b[j * n + k]).sum::<f64>()
                        + if i == j { n as f64 } else { 0.0 };
                }
            }
            let (mut fixed, mut general) = (a.clone(), a.clone());
            assert!(factor(&mut fixed, n).is_ok());
            assert!(factor_in(&mut general, std::hint::black_box(n)).is_ok());
            assert_eq!(fixed, general, "n = {n}");
            let rhs: Vec<f64> = (0..n).map(|k| (k as f64).cos()).collect();
            let (mut x, mut y) = (rhs.clone(), rhs.clone());
            solve(&fixed, n, &mut x);
            solve_in(&general, std::hint::black_box(n), &mut y);
            assert_eq!(x, y, "n = {n}");
            let r: f64 = (0..n)
                .map(|i| ((0..n).map(|j| a[i * n + j] * x[j]).sum::<f64>() - rhs[i]).abs())
                .fold(0.0, f64::max);
            assert!(r < 1e-12, "n = {n}: residual {r:e}");
        }
    }
}
