//! Issue 11's last lever, measured: is a hand-vectorised kernel the way to Basilisk / satsim
//! ≥ 30? One serial body's inward step of the unrolled kernel (pass 2: the projection
//! `IA − U Uᵀ / D`, `IAᵃ c`, the similarity `Xᵀ IAᵃ X` and the parent's start added), the
//! largest block of the kernel (14 % of the orbit's instructions), two ways:
//! - `scalar`: as the kernel does it today (nalgebra, scalar and two-wide SSE2): a copy of
//!   `crates/tree/src/axis.rs`'s `project_at_point::<0, 1, 2>` with `spatial.rs`'s
//!   `add_translated` (copied, not called: both are private to the crate);
//! - `avx2`: hand-written AVX2 + FMA, each 3x3 block as three columns of four lanes, `B` kept
//!   in both orientations so that nothing is ever transposed.
//!
//! Hinge about x, `E = [[1,0,0],[0,c,s],[0,−s,c]]`, a panel's inertia. `check` runs a chain
//! of 8 bodies both ways and asserts that every block and `IAᵃ c` agree to 1e-13 relative.
//! The timings: `scalar` / `avx2` chain the steps as the kernel does (each body's inertia
//! is its parent's input, written into two buffers in turn); `scalar-free` / `avx2-free`
//! repeat independent steps (the throughput, which the kernel never sees). Not part of the
//! workspace or of CI; x86-64 with AVX2 and FMA only.
//!
//!     cd benches/simd-probe && cargo run --release -- check
//!     for m in scalar avx2 scalar-free avx2-free; do target/release/simd-probe $m 20000000; done
//!     objdump -d --no-show-raw-insn target/release/simd-probe | less   # the instructions
//!
//! Measured (AMD EPYC, Zen 4; medians of 15 alternating runs of 40 M steps; the performance
//! page has the table): the AVX2 step executes 195 instructions against 489, but takes
//! 27.6 ns against 35.6 ns chained (1.29×) and 21.8 ns against 30.9 ns independent (1.42×):
//! the step is a chain of dependent operations (the pivot's division, the projection, the
//! rotation, the translation, the stores the next body reads), and fewer instructions
//! shorten it little.
//!
//! Without fused multiply-adds (`--features no-fma`: each `a * b + c` a multiply and an
//! add, as the kernel must compute it to give the same bits on every instruction set):
//! 29.25 ns against 35.29 ns chained (1.17×, per-round median of 9 alternating runs of 20 M
//! steps, with FMA 1.30× in the same runs; 1.21× and 1.29× in 5 more; AMD EPYC Zen 4 with
//! AVX-512, 2026-11-29).
//!
//!     cargo build --release --features no-fma --target-dir target/no-fma
//!     target/no-fma/release/simd-probe avx2 20000000

use nalgebra::{Matrix3, Vector3};
use std::arch::x86_64::*;

// `a * b + c`, `a * b - c` and `c - a * b`: fused by default, a separate multiply and add
// (or subtract) with `--features no-fma`.
#[cfg(not(feature = "no-fma"))]
macro_rules! fmadd {
    ($a:expr, $b:expr, $c:expr $(,)?) => {
        _mm256_fmadd_pd($a, $b, $c)
    };
}
#[cfg(not(feature = "no-fma"))]
macro_rules! fmsub {
    ($a:expr, $b:expr, $c:expr $(,)?) => {
        _mm256_fmsub_pd($a, $b, $c)
    };
}
#[cfg(not(feature = "no-fma"))]
macro_rules! fnmadd {
    ($a:expr, $b:expr, $c:expr $(,)?) => {
        _mm256_fnmadd_pd($a, $b, $c)
    };
}
#[cfg(feature = "no-fma")]
macro_rules! fmadd {
    ($a:expr, $b:expr, $c:expr $(,)?) => {
        _mm256_add_pd(_mm256_mul_pd($a, $b), $c)
    };
}
#[cfg(feature = "no-fma")]
macro_rules! fmsub {
    ($a:expr, $b:expr, $c:expr $(,)?) => {
        _mm256_sub_pd(_mm256_mul_pd($a, $b), $c)
    };
}
#[cfg(feature = "no-fma")]
macro_rules! fnmadd {
    ($a:expr, $b:expr, $c:expr $(,)?) => {
        _mm256_sub_pd($c, _mm256_mul_pd($a, $b))
    };
}
use std::hint::black_box;
use std::time::Instant;

type Mat3 = Matrix3<f64>;
type Vec3 = Vector3<f64>;

#[derive(Clone, Copy, Debug, Default)]
struct Ia {
    a: Mat3,
    b: Mat3,
    c: Mat3,
}

// ---------------------------------------------------------------- scalar (today's kernel)

fn cross_columns(a: &Vec3, m: &Mat3) -> Mat3 {
    Mat3::from_columns(&[
        a.cross(&m.column(0)),
        a.cross(&m.column(1)),
        a.cross(&m.column(2)),
    ])
}

#[inline(never)]
fn scalar_step(
    ia: &Ia,
    cang: &Vec3,
    clin: &Vec3,
    e: &Mat3,
    r_at: &Vec3,
    start: &Ia,
    out: &mut Ia,
) -> (Vec3, Vec3) {
    const K: usize = 0;
    const I: usize = 1;
    const J: usize = 2;
    let d = ia.a[(K, K)];
    let r = 1.0 / d;
    let (a, b) = (&ia.a, &ia.b);
    let (ai, aj) = (a[(K, I)], a[(K, J)]);
    let bk = b.row(K).transpose();
    let (ri, rj) = (ai * r, aj * r);
    let (aii, aij, ajj) = (
        a[(I, I)] - ai * ri,
        a[(I, J)] - ai * rj,
        a[(J, J)] - aj * rj,
    );
    let bi = b.row(I).transpose() - bk * ri;
    let bj = b.row(J).transpose() - bk * rj;
    let cp = ia.c - (bk * r) * bk.transpose();
    let (ci, cj) = (cang[I], cang[J]);
    let mut f_ang = Vec3::zeros();
    f_ang[I] = aii * ci + aij * cj + bi.dot(clin);
    f_ang[J] = aij * ci + ajj * cj + bj.dot(clin);
    let f_lin = bi * ci + bj * cj + cp * clin;
    let (eii, eij, eji, ejj) = (e[(I, I)], e[(I, J)], e[(J, I)], e[(J, J)]);
    let (nii, nij) = (aii * eii + aij * eji, aii * eij + aij * ejj);
    let (nji, njj) = (aij * eii + ajj * eji, aij * eij + ajj * ejj);
    let mut an = Mat3::zeros();
    an[(I, I)] = eii * nii + eji * nji;
    an[(I, J)] = eii * nij + eji * njj;
    an[(J, I)] = an[(I, J)];
    an[(J, J)] = eij * nij + ejj * njj;
    let col = |row: &Vec3| {
        let mut o = *row;
        o[I] = row[I] * eii + row[J] * eji;
        o[J] = row[I] * eij + row[J] * ejj;
        o
    };
    let (bi, bj) = (col(&bi), col(&bj));
    let mut bn = Mat3::zeros();
    bn.set_row(I, &(bi * eii + bj * eji).transpose());
    bn.set_row(J, &(bi * eij + bj * ejj).transpose());
    let cn = {
        let m = &cp;
        let mut n = *m;
        for row in 0..3 {
            let (mi, mj) = (m[(row, I)], m[(row, J)]);
            n[(row, I)] = mi * eii + mj * eji;
            n[(row, J)] = mi * eij + mj * ejj;
        }
        let mut o = n;
        for c in 0..3 {
            let (ni, nj) = (n[(I, c)], n[(J, c)]);
            o[(I, c)] = eii * ni + eji * nj;
            o[(J, c)] = eij * ni + ejj * nj;
        }
        o
    };
    let nb = bn + cross_columns(r_at, &cn);
    let na = an
        + cross_columns(r_at, &bn.transpose())
        + cross_columns(r_at, &nb.transpose()).transpose();
    out.a = start.a + na;
    out.b = start.b + nb;
    out.c = start.c + cn;
    (f_ang, f_lin)
}

// ---------------------------------------------------------------- AVX2 + FMA

/// The blocks as columns in four lanes (the fourth zero): `A`, `B`, `Bᵀ`, `C`.
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct Ia4 {
    a: [__m256d; 3],
    b: [__m256d; 3],
    bt: [__m256d; 3],
    c: [__m256d; 3],
}

/// A body's constants: its hinge point in the parent, `r`, and its permutations.
#[derive(Clone, Copy)]
struct At4 {
    r_yzx: __m256d,
    r_zxy: __m256d,
    r: [__m256d; 3], // broadcasts of r0, r1, r2
}

unsafe fn v4(v: &Vec3) -> __m256d {
    unsafe { _mm256_setr_pd(v[0], v[1], v[2], 0.0) }
}

unsafe fn to4(ia: &Ia) -> Ia4 {
    unsafe {
        let cols = |m: &Mat3| {
            [
                v4(&m.column(0).into()),
                v4(&m.column(1).into()),
                v4(&m.column(2).into()),
            ]
        };
        Ia4 {
            a: cols(&ia.a),
            b: cols(&ia.b),
            bt: cols(&ia.b.transpose()),
            c: cols(&ia.c),
        }
    }
}

unsafe fn from4(x: &Ia4) -> (Ia, Mat3) {
    let get = |v: __m256d| {
        let mut o = [0.0; 4];
        unsafe { _mm256_storeu_pd(o.as_mut_ptr(), v) };
        Vec3::new(o[0], o[1], o[2])
    };
    let m = |c: &[__m256d; 3]| Mat3::from_columns(&[get(c[0]), get(c[1]), get(c[2])]);
    (
        Ia {
            a: m(&x.a),
            b: m(&x.b),
            c: m(&x.c),
        },
        m(&x.bt),
    )
}

unsafe fn at4(r: &Vec3) -> At4 {
    unsafe {
        At4 {
            r_yzx: _mm256_setr_pd(r[1], r[2], r[0], 0.0),
            r_zxy: _mm256_setr_pd(r[2], r[0], r[1], 0.0),
            r: [
                _mm256_set1_pd(r[0]),
                _mm256_set1_pd(r[1]),
                _mm256_set1_pd(r[2]),
            ],
        }
    }
}

#[inline]
#[target_feature(enable = "avx2,fma")]
fn bcast<const L: i32>(v: __m256d) -> __m256d {
    // vpermpd with all four selectors = L
    match L {
        0 => _mm256_permute4x64_pd::<0b00_00_00_00>(v),
        1 => _mm256_permute4x64_pd::<0b01_01_01_01>(v),
        _ => _mm256_permute4x64_pd::<0b10_10_10_10>(v),
    }
}

/// `r × v` (lane 3 stays zero).
#[inline]
#[target_feature(enable = "avx2,fma")]
fn cross(at: &At4, v: __m256d) -> __m256d {
    let v_zxy = _mm256_permute4x64_pd::<0b11_01_00_10>(v); // (v2, v0, v1, v3)
    let v_yzx = _mm256_permute4x64_pd::<0b11_00_10_01>(v); // (v1, v2, v0, v3)
    fmsub!(at.r_yzx, v_zxy, _mm256_mul_pd(at.r_zxy, v_yzx))
}

#[inline(never)]
#[target_feature(enable = "avx2,fma")]
fn avx2_step(
    ia: &Ia4,
    cang: &[f64; 4],
    clin: &[f64; 4],
    sc: (f64, f64),
    at: &At4,
    start: &Ia4,
    out: &mut Ia4,
) -> (__m256d, __m256d) {
    let (s, c) = sc;
    // The projection: U = [a; bk], a = A e₀, bk = Bᵀ e₀; D = a₀.
    let a = ia.a[0];
    let bk = ia.bt[0];
    let d = _mm256_cvtsd_f64(a);
    let r = _mm256_set1_pd(1.0 / d);
    let (ar, bkr) = (_mm256_mul_pd(a, r), _mm256_mul_pd(bk, r));
    let (a0, a1, a2) = (bcast::<0>(a), bcast::<1>(a), bcast::<2>(a));
    let (k0, k1, k2) = (bcast::<0>(bk), bcast::<1>(bk), bcast::<2>(bk));
    let pa = [
        fnmadd!(ar, a0, ia.a[0]),
        fnmadd!(ar, a1, ia.a[1]),
        fnmadd!(ar, a2, ia.a[2]),
    ];
    let pb = [
        fnmadd!(ar, k0, ia.b[0]),
        fnmadd!(ar, k1, ia.b[1]),
        fnmadd!(ar, k2, ia.b[2]),
    ];
    let pbt = [
        fnmadd!(bkr, a0, ia.bt[0]),
        fnmadd!(bkr, a1, ia.bt[1]),
        fnmadd!(bkr, a2, ia.bt[2]),
    ];
    let pc = [
        fnmadd!(bkr, k0, ia.c[0]),
        fnmadd!(bkr, k1, ia.c[1]),
        fnmadd!(bkr, k2, ia.c[2]),
    ];
    // IAᵃ c.
    let (ca0, ca1, ca2) = (
        _mm256_set1_pd(cang[0]),
        _mm256_set1_pd(cang[1]),
        _mm256_set1_pd(cang[2]),
    );
    let (cl0, cl1, cl2) = (
        _mm256_set1_pd(clin[0]),
        _mm256_set1_pd(clin[1]),
        _mm256_set1_pd(clin[2]),
    );
    let f_ang = fmadd!(
        pa[0],
        ca0,
        fmadd!(
            pa[1],
            ca1,
            fmadd!(
                pa[2],
                ca2,
                fmadd!(pb[0], cl0, fmadd!(pb[1], cl1, _mm256_mul_pd(pb[2], cl2)),),
            ),
        ),
    );
    let f_lin = fmadd!(
        pbt[0],
        ca0,
        fmadd!(
            pbt[1],
            ca1,
            fmadd!(
                pbt[2],
                ca2,
                fmadd!(pc[0], cl0, fmadd!(pc[1], cl1, _mm256_mul_pd(pc[2], cl2)),),
            ),
        ),
    );
    // Eᵀ M E: columns mix (M E), then rows (lanes 1, 2).
    let (vc, vs) = (_mm256_set1_pd(c), _mm256_set1_pd(s));
    let k_1 = _mm256_setr_pd(1.0, c, c, 0.0);
    let k_2 = _mm256_setr_pd(0.0, -s, s, 0.0);
    let rot = |m: &[__m256d; 3]| {
        let c1 = fnmadd!(vs, m[2], _mm256_mul_pd(vc, m[1]));
        let c2 = fmadd!(vs, m[1], _mm256_mul_pd(vc, m[2]));
        let lanes = |v: __m256d| {
            fmadd!(
                _mm256_permute4x64_pd::<0b11_01_10_00>(v),
                k_2,
                _mm256_mul_pd(v, k_1),
            )
        };
        [lanes(m[0]), lanes(c1), lanes(c2)]
    };
    let (an, bn, bnt, cn) = (rot(&pa), rot(&pb), rot(&pbt), rot(&pc));
    // The translation by r: nb = B + [r]× C, nbᵀ = Bᵀ − C [r]×,
    // na = A + [r]× Bᵀ − nb [r]× (column j of M [r]× is M (r × e_j)).
    let [r0, r1, r2] = at.r;
    let nb = [
        _mm256_add_pd(bn[0], cross(at, cn[0])),
        _mm256_add_pd(bn[1], cross(at, cn[1])),
        _mm256_add_pd(bn[2], cross(at, cn[2])),
    ];
    let nbt = [
        _mm256_sub_pd(bnt[0], fmsub!(r2, cn[1], _mm256_mul_pd(r1, cn[2]))),
        _mm256_sub_pd(bnt[1], fmsub!(r0, cn[2], _mm256_mul_pd(r2, cn[0]))),
        _mm256_sub_pd(bnt[2], fmsub!(r1, cn[0], _mm256_mul_pd(r0, cn[1]))),
    ];
    let na = [
        _mm256_sub_pd(
            _mm256_add_pd(an[0], cross(at, bnt[0])),
            fmsub!(r2, nb[1], _mm256_mul_pd(r1, nb[2])),
        ),
        _mm256_sub_pd(
            _mm256_add_pd(an[1], cross(at, bnt[1])),
            fmsub!(r0, nb[2], _mm256_mul_pd(r2, nb[0])),
        ),
        _mm256_sub_pd(
            _mm256_add_pd(an[2], cross(at, bnt[2])),
            fmsub!(r1, nb[0], _mm256_mul_pd(r0, nb[1])),
        ),
    ];
    for j in 0..3 {
        out.a[j] = _mm256_add_pd(start.a[j], na[j]);
        out.b[j] = _mm256_add_pd(start.b[j], nb[j]);
        out.bt[j] = _mm256_add_pd(start.bt[j], nbt[j]);
        out.c[j] = _mm256_add_pd(start.c[j], cn[j]);
    }
    (f_ang, f_lin)
}

// ---------------------------------------------------------------- set-up, check, timing

fn rigid(m: f64, com: Vec3, ic: Mat3) -> Ia {
    // About a point at −com from the centre of mass: [Ic + m [c]×[c]×ᵀ, m [c]×; m [c]×ᵀ, m 1].
    let cx = com.cross_matrix();
    Ia {
        a: ic + m * cx * cx.transpose(),
        b: m * cx,
        c: m * Mat3::identity(),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mode = args.get(1).map(String::as_str).unwrap_or("check");
    let steps: usize = args
        .get(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000_000);
    // A panel (20 kg, 2 m x 1 m) about its hinge point, its centre 1 m out along y.
    let start = rigid(
        20.0,
        Vec3::new(0.02, 1.0, -0.03),
        Mat3::from_diagonal(&Vec3::new(6.7, 1.7, 8.3)),
    );
    let r_at = Vec3::new(0.01, 2.0, 0.02); // the child's hinge point in the parent
    let phi: f64 = 0.7;
    let (s, c) = phi.sin_cos();
    let mut e = Mat3::identity();
    e[(1, 1)] = c;
    e[(2, 2)] = c;
    e[(1, 2)] = s;
    e[(2, 1)] = -s;
    let cang = Vec3::new(0.01, -0.02, 0.03);
    let clin = Vec3::new(-0.1, 0.05, 0.02);
    // The first child: the panel plus another projected and moved in (a plausible IA).
    let mut ia0 = Ia::default();
    scalar_step(&start, &cang, &clin, &e, &r_at, &start, &mut ia0);
    assert!(is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"));
    unsafe {
        let (ia4, start4, at) = (to4(&ia0), to4(&start), at4(&r_at));
        let (ca, cl) = (
            [cang[0], cang[1], cang[2], 0.0],
            [clin[0], clin[1], clin[2], 0.0],
        );
        match mode {
            "check" => {
                // A chain of 8 bodies both ways: every block and IAᵃ c to round-off.
                let (mut x, mut y) = (ia0, ia4);
                for k in 0..8 {
                    let mut xo = Ia::default();
                    let (fa, fl) = scalar_step(&x, &cang, &clin, &e, &r_at, &start, &mut xo);
                    let mut yo = y;
                    let (ga, gl) = avx2_step(&y, &ca, &cl, (s, c), &at, &start4, &mut yo);
                    let (yi, ybt) = from4(&yo);
                    let scale = xo.a.amax().max(xo.b.amax()).max(xo.c.amax());
                    let err = [
                        (xo.a - yi.a).amax(),
                        (xo.b - yi.b).amax(),
                        (xo.b.transpose() - ybt).amax(),
                        (xo.c - yi.c).amax(),
                    ];
                    let g = |v: __m256d| {
                        let mut o = [0.0; 4];
                        _mm256_storeu_pd(o.as_mut_ptr(), v);
                        Vec3::new(o[0], o[1], o[2])
                    };
                    let ferr =
                        (fa - g(ga)).amax().max((fl - g(gl)).amax()) / fa.amax().max(fl.amax());
                    println!(
                        "body {k}: |IA| {scale:.3e}, max rel. difference A {:.1e} B {:.1e} Bt {:.1e} C {:.1e}, IAa c {ferr:.1e}",
                        err[0] / scale,
                        err[1] / scale,
                        err[2] / scale,
                        err[3] / scale
                    );
                    assert!(err.iter().all(|e| *e <= 1e-13 * scale) && ferr < 1e-13);
                    (x, y) = (xo, yo);
                }
                println!("agree to round-off");
            }
            "scalar" => {
                let mut acc = 0.0;
                let t0 = Instant::now();
                for _ in 0..steps / 16 {
                    let mut bufs = [black_box(ia0), ia0];
                    for _ in 0..8 {
                        let [x, xo] = &mut bufs;
                        let (fa, _) = scalar_step(
                            x,
                            black_box(&cang),
                            &clin,
                            black_box(&e),
                            &r_at,
                            &start,
                            xo,
                        );
                        acc += fa[1];
                        let (fa, _) = scalar_step(
                            xo,
                            black_box(&cang),
                            &clin,
                            black_box(&e),
                            &r_at,
                            &start,
                            x,
                        );
                        acc += fa[1];
                    }
                    acc += bufs[0].c[(2, 2)];
                }
                let dt = t0.elapsed().as_secs_f64();
                println!(
                    "scalar: {:.2} ns per step ({acc:e})",
                    dt / (steps / 16 * 16) as f64 * 1e9
                );
            }
            "avx2" => time_avx2(true, steps, ia4, ca, cl, (s, c), at, start4),
            "scalar-free" => {
                let mut acc = 0.0;
                let t0 = Instant::now();
                let x = ia0;
                for _ in 0..steps {
                    let mut xo = Ia::default();
                    let (fa, _) = scalar_step(
                        black_box(&x),
                        black_box(&cang),
                        &clin,
                        black_box(&e),
                        &r_at,
                        &start,
                        &mut xo,
                    );
                    acc += fa[1] + xo.c[(2, 2)];
                }
                let dt = t0.elapsed().as_secs_f64();
                println!(
                    "scalar, independent steps: {:.2} ns per step ({acc:e})",
                    dt / steps as f64 * 1e9
                );
            }
            "avx2-free" => time_avx2(false, steps, ia4, ca, cl, (s, c), at, start4),
            _ => eprintln!("mode: check | scalar | avx2"),
        }
    }
}

/// The AVX2 step timed `chained` (each output the next input, two buffers in turn) or on
/// independent inputs.
#[target_feature(enable = "avx2,fma")]
fn time_avx2(
    chained: bool,
    steps: usize,
    ia4: Ia4,
    ca: [f64; 4],
    cl: [f64; 4],
    sc: (f64, f64),
    at: At4,
    start4: Ia4,
) {
    let mut acc = _mm256_setzero_pd();
    let t0 = Instant::now();
    if chained {
        for _ in 0..steps / 16 {
            let mut bufs = [black_box(ia4), ia4];
            for _ in 0..8 {
                let [y, yo] = &mut bufs;
                let (fa, _) = avx2_step(y, black_box(&ca), &cl, black_box(sc), &at, &start4, yo);
                acc = _mm256_add_pd(acc, fa);
                let (fa, _) = avx2_step(yo, black_box(&ca), &cl, black_box(sc), &at, &start4, y);
                acc = _mm256_add_pd(acc, fa);
            }
            acc = _mm256_add_pd(acc, bufs[0].c[2]);
        }
    } else {
        for _ in 0..steps / 16 * 16 {
            let mut yo = ia4;
            let (fa, _) = avx2_step(
                black_box(&ia4),
                black_box(&ca),
                &cl,
                black_box(sc),
                &at,
                &start4,
                &mut yo,
            );
            acc = _mm256_add_pd(acc, _mm256_add_pd(fa, yo.c[1]));
        }
    }
    let dt = t0.elapsed().as_secs_f64();
    let what = if chained {
        "avx2"
    } else {
        "avx2, independent steps"
    };
    println!(
        "{what}: {:.2} ns per step ({:e})",
        dt / (steps / 16 * 16) as f64 * 1e9,
        _mm256_cvtsd_f64(acc)
    );
}
