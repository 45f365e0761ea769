//! The factorisations' tests: solutions to rounding, blocks, refusals, the AVX2 instances'
//! bits, and the plain LAPACK-order loops' bits.

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
fn block_lower_triangular_matrices_factor_block_by_block() {
    // Blocks 0..2, 2..3, 3..7, the first diagonal entry of the two larger ones zero so
    // that they pivot within the block; the entries above the blocks zero.
    let (n, bounds) = (7, [0, 2, 3, 7]);
    let block = |i: usize| bounds.iter().rposition(|&b| b <= i).expect("block");
    let mut next = entries(77);
    let a: Vec<f64> = (0..n * n)
        .map(|k| {
            let (r, c) = (k % n, k / n);
            let v = next();
            if block(c) > block(r) || (r == c && (r == 0 || r == 3)) {
                0.0
            } else {
                v
            }
        })
        .collect();
    let (xr, xi): (Vec<f64>, Vec<f64>) = (0..n).map(|_| (next(), next())).unzip();
    let mut real = RealLu::new(n);
    let mut complex = ComplexLu::new(n);
    real.start_blocks(&bounds);
    complex.start_blocks(&bounds);
    let (mut b, mut br, mut bi) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for c in 0..n {
        for r in 0..n {
            let v = a[c * n + r];
            real.set(r, c, v);
            // The complex matrix: a (1 + 0.5 i).
            complex.set(r, c, v, 0.5 * v);
            b[r] += v * xr[c];
            br[r] += v * xr[c] - 0.5 * v * xi[c];
            bi[r] += v * xi[c] + 0.5 * v * xr[c];
        }
    }
    assert!(real.factor() && complex.factor());
    real.solve(&mut b);
    complex.solve(&mut br, &mut bi);
    for i in 0..n {
        assert!(
            (b[i] - xr[i]).abs() < 1e-12,
            "real, {i}: {} against {}",
            b[i],
            xr[i]
        );
        assert!(
            (br[i] - xr[i]).abs() < 1e-12 && (bi[i] - xi[i]).abs() < 1e-12,
            "complex, {i}"
        );
    }
    // A block whose own part is singular is refused, though the whole matrix is not:
    // the blocks are factored alone.
    let mut real = RealLu::new(2);
    real.start_blocks(&[0, 1, 2]);
    real.set(0, 0, 0.0);
    real.set(1, 0, 1.0);
    real.set(1, 1, 1.0);
    assert!(!real.factor());
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

/// The plain factors: real and imaginary parts (column-major `n × n`, `U`'s diagonal as
/// reciprocals) and the pivots.
type Factors = (Vec<f64>, Vec<f64>, Vec<usize>);

/// The factorisation and solve with the rows swapped across the whole block (LAPACK's
/// order, as `getrf` and `getrs`), operation for operation otherwise: factors `(re, im)`
/// (column-major `n × n`; `im` `None` for a real matrix), solves `(br, bi)` in place and
/// returns the factors, `None` where a block is singular.
fn plain_solve(
    n: usize,
    bounds: &[usize],
    (mut re, mut im): (Vec<f64>, Option<Vec<f64>>),
    (br, bi): (&mut [f64], &mut [f64]),
) -> Option<Factors> {
    let cplx = im.is_some();
    let mut imv = im.take().unwrap_or_else(|| vec![0.0; n * n]);
    let mut piv = vec![0; n];
    for w in bounds.windows(2) {
        let (s, e) = (w[0], w[1]);
        for k in s..e {
            let mut p = k;
            let mut best = re[k * n + k].abs() + imv[k * n + k].abs();
            for i in k + 1..e {
                let m = re[k * n + i].abs() + imv[k * n + i].abs();
                if m > best {
                    (p, best) = (i, m);
                }
            }
            piv[k] = p;
            if best == 0.0 {
                return None;
            }
            for j in s..e {
                re.swap(j * n + k, j * n + p);
                imv.swap(j * n + k, j * n + p);
            }
            let (pr, pi) = (re[k * n + k], imv[k * n + k]);
            let (ir, ii) = if cplx {
                let d = pr * pr + pi * pi;
                (pr / d, -pi / d)
            } else {
                (1.0 / pr, 0.0)
            };
            (re[k * n + k], imv[k * n + k]) = (ir, ii);
            for i in k + 1..e {
                let (r, m) = (re[k * n + i], imv[k * n + i]);
                if cplx {
                    re[k * n + i] = r * ir - m * ii;
                    imv[k * n + i] = r * ii + m * ir;
                } else {
                    re[k * n + i] = r * ir;
                }
            }
            for j in k + 1..e {
                let (ar, ai) = (re[j * n + k], imv[j * n + k]);
                if ar != 0.0 || ai != 0.0 {
                    for i in k + 1..e {
                        let (lr, li) = (re[k * n + i], imv[k * n + i]);
                        if cplx {
                            re[j * n + i] -= lr * ar - li * ai;
                            imv[j * n + i] -= lr * ai + li * ar;
                        } else {
                            re[j * n + i] -= lr * ar;
                        }
                    }
                }
            }
        }
    }
    let sub = |br: &mut [f64], bi: &mut [f64], j: usize, i: usize, (xr, xi): (f64, f64)| {
        let (cr, ci) = (re[j * n + i], imv[j * n + i]);
        if cplx {
            br[i] -= cr * xr - ci * xi;
            bi[i] -= cr * xi + ci * xr;
        } else {
            br[i] -= cr * xr;
        }
    };
    for w in bounds.windows(2) {
        let (s, e) = (w[0], w[1]);
        for j in 0..s {
            let x = (br[j], bi[j]);
            if x != (0.0, 0.0) {
                (s..e).for_each(|i| sub(br, bi, j, i, x));
            }
        }
        for k in s..e {
            br.swap(k, piv[k]);
            bi.swap(k, piv[k]);
        }
        for k in s..e {
            let x = (br[k], bi[k]);
            if x != (0.0, 0.0) {
                (k + 1..e).for_each(|i| sub(br, bi, k, i, x));
            }
        }
        for k in (s..e).rev() {
            let (cr, ci) = (re[k * n + k], imv[k * n + k]);
            let (xr, xi) = (br[k], bi[k]);
            let y = if cplx {
                (xr * cr - xi * ci, xr * ci + xi * cr)
            } else {
                (xr * cr, 0.0)
            };
            (br[k], bi[k]) = y;
            (s..k).for_each(|i| sub(br, bi, k, i, y));
        }
    }
    Some((re, imv, piv))
}

/// Whether factors stored `ld` apart (LINPACK's row order for `L`) are the plain
/// factors `plain` (`n` apart, LAPACK's order) bit for bit: `U` and the blocks below as
/// they are, each column of `L` once the later steps' swaps are applied to it.
fn same_factors(ld: usize, ours: &[f64], plain: &[f64], piv: &[usize], bounds: &[usize]) {
    let n = piv.len();
    for w in bounds.windows(2) {
        let (s, e) = (w[0], w[1]);
        for c in s..e {
            let col = &ours[c * ld..][..n];
            let mut l = col[c + 1..e].to_vec();
            for t in c + 1..e {
                l.swap(t - c - 1, piv[t] - c - 1);
            }
            let lower: Vec<f64> = col[..=c]
                .iter()
                .chain(&l)
                .chain(&col[e..])
                .copied()
                .collect();
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&lower), bits(&plain[c * n..][..n]), "column {c}");
        }
    }
}

/// The factorisations and solves, in both instances, give the plain loops' bits: the
/// factors (`L`'s rows in LINPACK's order, the rest as they are) and the solutions, in
/// blocks, with zeros and negative zeros among the entries.
#[test]
fn the_solves_are_the_plain_loops_bit_for_bit() {
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let mut next = entries(4242);
    for (n, bounds) in [
        (1, vec![0, 1]),
        (4, vec![0, 4]),
        (5, vec![0, 2, 5]),
        (9, vec![0, 9]),
        (13, vec![0, 3, 13]),
        (27, vec![0, 3, 27]),
        (31, vec![0, 1, 6, 20, 31]),
    ] {
        let block = |i: usize| bounds.iter().rposition(|&b| b <= i).expect("block");
        let mut entry = |r: usize, c: usize| {
            let v = next();
            if block(c) > block(r) {
                0.0
            } else if v.abs() < 0.3 {
                if v < 0.0 { -0.0 } else { 0.0 }
            } else {
                v
            }
        };
        let (mut a, mut ai) = (vec![0.0; n * n], vec![0.0; n * n]);
        for c in 0..n {
            for r in 0..n {
                a[c * n + r] = entry(r, c);
                ai[c * n + r] = entry(r, c);
            }
            // A dominant entry off the diagonal, a cyclic shift within the block: every
            // block regular, and every step of the elimination pivots.
            let (bs, be) = (bounds[block(c)], bounds[block(c) + 1]);
            a[c * n + bs + (c - bs + 1) % (be - bs)] += 4.0;
        }
        let rhs: Vec<f64> = (0..2 * n)
            .map(|i| if i % 5 == 3 { -0.0 } else { next() })
            .collect();
        let (mut wr, mut wi) = (rhs[..n].to_vec(), vec![0.0; n]);
        let (real_lu, _, real_piv) =
            plain_solve(n, &bounds, (a.clone(), None), (&mut wr, &mut wi)).expect("regular");
        let (mut zr, mut zi) = (rhs[..n].to_vec(), rhs[n..].to_vec());
        let cplx = (a.clone(), Some(ai.clone()));
        let (lu_re, lu_im, complex_piv) =
            plain_solve(n, &bounds, cplx, (&mut zr, &mut zi)).expect("regular");
        for wide in [false, true] {
            let mut real = RealLu::new(n + 3);
            let mut complex = ComplexLu::new(n + 3);
            real.start_blocks(&bounds);
            complex.start_blocks(&bounds);
            for c in 0..n {
                for r in 0..n {
                    real.set(r, c, a[c * n + r]);
                    complex.set(r, c, a[c * n + r], ai[c * n + r]);
                }
            }
            assert!(real.factor_on(wide) && complex.factor_on(wide));
            assert_eq!(
                (&real.piv[..n], &complex.piv[..n]),
                (&real_piv[..], &complex_piv[..])
            );
            same_factors(n, &real.a, &real_lu, &real_piv, &bounds);
            same_factors(n, &complex.re, &lu_re, &complex_piv, &bounds);
            same_factors(n, &complex.im, &lu_im, &complex_piv, &bounds);
            let mut x = rhs[..n].to_vec();
            real.solve_on(wide, &mut x);
            assert_eq!(bits(&x), bits(&wr), "real, n = {n}, wide {wide}");
            let (mut yr, mut yi) = (rhs[..n].to_vec(), rhs[n..].to_vec());
            complex.solve_on(wide, &mut yr, &mut yi);
            assert_eq!(bits(&yr), bits(&zr), "complex re, n = {n}, wide {wide}");
            assert_eq!(bits(&yi), bits(&zi), "complex im, n = {n}, wide {wide}");
        }
    }
}

/// The instances compiled for AVX2 give the baseline's bits, in blocks too (where the
/// CPU has AVX2; elsewhere both calls are the baseline's).
#[test]
fn the_avx2_instances_give_the_baselines_bits() {
    let (n, bounds) = (31, [0, 3, 31]);
    let mut next = entries(2024);
    let mut real = [RealLu::new(n), RealLu::new(n)];
    let mut complex = [ComplexLu::new(n), ComplexLu::new(n)];
    for (lu, c) in real.iter_mut().zip(&mut complex) {
        lu.start_blocks(&bounds);
        c.start_blocks(&bounds);
    }
    for col in 0..n {
        for row in 0..n {
            // Zero above the diagonal blocks.
            let (a, b, c) = (next(), next(), next());
            let above = row < 3 && col >= 3;
            for k in 0..2 {
                real[k].set(row, col, if above { 0.0 } else { a });
                complex[k].set(
                    row,
                    col,
                    if above { 0.0 } else { b },
                    if above { 0.0 } else { c },
                );
            }
        }
    }
    let rhs: Vec<f64> = (0..3 * n).map(|_| next()).collect();
    let mut x = [rhs.clone(), rhs.clone()];
    for (k, wide) in [false, true].into_iter().enumerate() {
        assert!(real[k].factor_on(wide) && complex[k].factor_on(wide));
        real[k].solve_on(wide, &mut x[k][..n]);
        let (br, bi) = x[k][n..].split_at_mut(n);
        complex[k].solve_on(wide, br, bi);
    }
    assert_eq!(real[0].a, real[1].a);
    assert_eq!(
        (&complex[0].re, &complex[0].im),
        (&complex[1].re, &complex[1].im)
    );
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&x[0]), bits(&x[1]));
    assert_ne!(x[0], rhs, "the solves ran");
}
