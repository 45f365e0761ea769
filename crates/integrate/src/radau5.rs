//! Implicit Radau IIA of order 5 (three stages), after Hairer & Wanner's
//! RADAU5: simplified Newton iterations with a finite-difference (or
//! user-supplied) Jacobian, LU factors reused while convergence is good and
//! the step size is unchanged, the embedded error estimate filtered by
//! `(I - h γ₀ J)⁻¹`, Gustafsson's predictive step-size controller and the
//! collocation polynomial as dense output.
//!
//! As in RADAU5 the stage system `(I - h A⊗J) ΔZ = -Z + h (A⊗I) F(Z)` is solved
//! in the eigenbasis of `A⁻¹` (`W = (T⁻¹⊗I) Z`, `T⁻¹A⁻¹T = diag(γ, [[α, -β], [β, α]])`):
//! one real `n × n` system `(γ/h - J)` and one complex `((α + iβ)/h - J)` instead
//! of one real `3n × 3n`. On the 49 states of a flexible deployment that is 5
//! times fewer flops a factorisation (which the step-size changes make often),
//! and the real factor is the error estimate's filter as it stands. Both are factored
//! through the Jacobian's Hessenberg form, made once per Jacobian (`hessenberg.rs`), so
//! that a new step size costs `O(n²)`.

use crate::{
    common::{Ctx, STAGE_RETRY_FACTOR, Stepper, all_finite, clamp_to_limit, largest_error},
    error::IntegrateError,
    jacobian::Jacobian,
    stage_matrices::StageMatrices,
    system::System,
};

const SQ6: f64 = 2.449_489_742_783_178;
/// Nodes of Radau IIA (order 5).
pub(crate) const C: [f64; 3] = [(4.0 - SQ6) / 10.0, (4.0 + SQ6) / 10.0, 1.0];
/// Butcher matrix of Radau IIA (order 5); the steps use it through [`T`], [`TI`] and the
/// eigenvalues of its inverse.
#[cfg(test)]
pub(crate) const A: [[f64; 3]; 3] = [
    [
        (88.0 - 7.0 * SQ6) / 360.0,
        (296.0 - 169.0 * SQ6) / 1800.0,
        (-2.0 + 3.0 * SQ6) / 225.0,
    ],
    [
        (296.0 + 169.0 * SQ6) / 1800.0,
        (88.0 + 7.0 * SQ6) / 360.0,
        (-2.0 - 3.0 * SQ6) / 225.0,
    ],
    [(16.0 - SQ6) / 36.0, (16.0 + SQ6) / 36.0, 1.0 / 9.0],
];
/// Error-estimate weights on the stage increments (Hairer's DD1..DD3).
pub(crate) const DD: [f64; 3] = [
    -(13.0 + 7.0 * SQ6) / 3.0,
    (-13.0 + 7.0 * SQ6) / 3.0,
    -1.0 / 3.0,
];

/// The real eigenvalue of `A⁻¹` (Hairer's U1 after inversion): `1/γ₀`.
pub(crate) fn u1() -> f64 {
    let (c81, c9) = (81f64.cbrt(), 9f64.cbrt());
    30.0 / (6.0 + c81 - c9)
}

/// The complex pair of eigenvalues of `A⁻¹`, `α ± iβ` (Hairer's ALPH, BETA after inversion).
pub(crate) fn alpha_beta() -> (f64, f64) {
    let (c81, c9) = (81f64.cbrt(), 9f64.cbrt());
    let alph = (12.0 - c81 + c9) / 60.0;
    let beta = (c81 + c9) * 3f64.sqrt() / 60.0;
    let cno = alph * alph + beta * beta;
    (alph / cno, beta / cno)
}

/// `T`, whose columns are (real and imaginary parts of) eigenvectors of `A⁻¹`, and `T⁻¹`
/// (RADAU5's T11..T31, TI11..TI33).
pub(crate) const T: [[f64; 3]; 3] = [
    [
        9.123_239_487_089_294e-2,
        -0.141_255_295_020_954_2,
        -3.002_919_410_514_742_4e-2,
    ],
    [
        0.241_717_932_707_107,
        0.204_129_352_293_799_93,
        0.382_942_112_757_261_9,
    ],
    [0.966_048_182_615_093, 1.0, 0.0],
];
pub(crate) const TI: [[f64; 3]; 3] = [
    [
        4.325_579_890_063_155,
        0.339_199_251_815_809_87,
        0.541_770_539_935_874_9,
    ],
    [
        -4.178_718_591_551_905,
        -0.327_682_820_761_062_4,
        0.476_623_554_500_550_45,
    ],
    [
        -0.502_872_634_945_786_9,
        2.571_926_949_855_605,
        -0.596_039_204_828_224_9,
    ],
];

/// Maximum Newton iterations per step.
const NIT: usize = 7;
const SAFE: f64 = 0.9;
/// The Jacobian is kept when the Newton contraction rate stays below this: RADAU5's default
/// 0.001 for a Jacobian given by the system, and the 0.1 Hairer & Wanner advise for a costly
/// one for ours by finite differences (`n` right-hand sides; on the flexible deployment it
/// halves the right-hand sides at the same error).
const THET: f64 = 0.001;
const THET_DIFFERENCES: f64 = 0.1;

/// Updates of a Jacobian ([`System::update_jacobian`]) between two evaluated ones. On the
/// flexible deployment, over 24 tolerances from `1e-5` to `1.5e-5`: 4 548 right-hand sides on
/// average without updates, 4 118 with at most two, 4 098 with three and more; the hinge
/// angles' largest error at most 9.3e-5, 9.9e-5 and 1.2e-4 rad.
const MAX_UPDATES: usize = 2;
/// Bounds of `h / h_new`.
const FACL: f64 = 5.0;
const FACR: f64 = 1.0 / 8.0;
/// Keep `h` (and the LU) when `h_new / h` falls in `[QUOT1, QUOT2]`.
const QUOT1: f64 = 1.0;
const QUOT2: f64 = 1.2;

/// Radau IIA stepper.
pub(crate) struct Radau5 {
    n: usize,
    t: f64,
    t_old: f64,
    /// Proposed next step.
    h: f64,
    /// Last accepted step (for dense output and extrapolation).
    h_old: f64,
    x: Vec<f64>,
    /// `f(t, x)` at the step start (made by every restart). After an accepted step it is
    /// the collocation polynomial's slope there (see [`Self::accept`]), exact (evaluated)
    /// when `f0_exact`: the error estimate takes either, a Jacobian's differences only the
    /// exact one.
    f0: Vec<f64>,
    f0_exact: bool,
    /// Stage increments `z_i = Y_i - x`, stacked (3n), their derivatives, the increments in
    /// `A⁻¹`'s eigenbasis (`w = (T⁻¹⊗I) z`) and the Newton update of `w`.
    z: Vec<f64>,
    fz: Vec<f64>,
    w: Vec<f64>,
    dz: Vec<f64>,
    /// The complex pair's right-hand side, imaginary part (the real part in `dz[n..2n]`).
    dc: Vec<f64>,
    tmp: Vec<f64>,
    err: Vec<f64>,
    scal: Vec<f64>,
    /// Collocation polynomial of the last step: `x + s (c0 + (s - c2 + 1)(c1 + (s - c1 + 1) c2))`.
    cont: [Vec<f64>; 3],
    jac: Jacobian,
    /// `γ/h - J` (the real block, also the error estimate's filter) and `(α + iβ)/h - J`:
    /// the Jacobian reduced once (`stage_matrices.rs`), factored at each new step size.
    e: StageMatrices,
    /// Tolerances transformed as in RADAU5 (the method's error estimate is
    /// of lower order than the solution).
    rtol: f64,
    atol: f64,
    fnewt: f64,
    first: bool,
    /// The next restart may continue the last step's collocation polynomial (set by
    /// [`Radau5::resume`]).
    resumable: bool,
    reject: bool,
    /// The Jacobian was evaluated (or updated) at the current step start.
    jac_current: bool,
    /// The Jacobian is an evaluated one, not one the system updated
    /// ([`System::update_jacobian`]).
    jac_exact: bool,
    /// Where the Jacobian stands: the state it was evaluated or last updated at.
    t_jac: f64,
    x_jac: Vec<f64>,
    /// Updates since the last evaluated Jacobian, and whether the next must be evaluated
    /// (an updated one failed Newton).
    updates: usize,
    evaluate_next: bool,
    /// A Jacobian has been evaluated in this integration (a restart may keep it: see
    /// [`System::jacobian_survives_restart`]).
    has_jacobian: bool,
    need_jac: bool,
    /// Step size the current LU factors were built for (NaN: invalid).
    h_lu: f64,
    theta: f64,
    /// [`THET`] or [`THET_DIFFERENCES`], once the Jacobian's kind is known.
    thet: f64,
    /// The eigenvalues of `A⁻¹`: `γ` ([`u1`]) and `α ± iβ` ([`alpha_beta`]), made once.
    gamma: f64,
    alpha: f64,
    beta: f64,
    faccon: f64,
    hacc: f64,
    erracc: f64,
    n_accepted: usize,
}

/// The three stages' parts of a `3n` vector, each of length `n`.
fn stages(v: &[f64], n: usize) -> (&[f64], &[f64], &[f64]) {
    let (a, rest) = v[..3 * n].split_at(n);
    let (b, c) = rest.split_at(n);
    (a, b, c)
}

/// [`stages`], mutable.
fn stages_mut(v: &mut [f64], n: usize) -> (&mut [f64], &mut [f64], &mut [f64]) {
    let (a, rest) = v[..3 * n].split_at_mut(n);
    let (b, c) = rest.split_at_mut(n);
    (a, b, c)
}

impl Radau5 {
    /// Lets the next restart continue this workspace's last step, where it starts at that
    /// step's end with its state ([`crate::integrate_on`]).
    pub(crate) fn resume(&mut self) {
        self.resumable = true;
    }

    pub fn new(n: usize, rtol: f64, atol: f64) -> Self {
        let z = || vec![0.0; n];
        let rt = 0.1 * rtol.powf(2.0 / 3.0);
        let at = if rtol > 0.0 { rt * (atol / rtol) } else { atol };
        let rt_newton = rt.max(1e-12);
        let fnewt = (10.0 * f64::EPSILON / rt_newton).max(0.03f64.min(rt_newton.sqrt()));
        Self {
            n,
            t: 0.0,
            t_old: 0.0,
            h: 0.0,
            h_old: 0.0,
            x: z(),
            f0: z(),
            f0_exact: false,
            z: vec![0.0; 3 * n],
            fz: vec![0.0; 3 * n],
            w: vec![0.0; 3 * n],
            dz: vec![0.0; 3 * n],
            dc: vec![0.0; n],
            tmp: z(),
            err: z(),
            scal: z(),
            cont: [z(), z(), z()],
            jac: Jacobian::new(n),
            e: StageMatrices::new(n),
            rtol: rt,
            atol: at,
            fnewt,
            first: true,
            resumable: false,
            reject: false,
            jac_current: false,
            jac_exact: false,
            t_jac: 0.0,
            x_jac: z(),
            updates: 0,
            evaluate_next: false,
            has_jacobian: false,
            need_jac: true,
            h_lu: f64::NAN,
            theta: THET,
            thet: THET,
            gamma: u1(),
            alpha: alpha_beta().0,
            beta: alpha_beta().1,
            faccon: 1.0,
            hacc: 0.0,
            erracc: 0.0,
            n_accepted: 0,
        }
    }

    fn compute_jacobian<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        ctx: &mut Ctx,
    ) -> Result<(), IntegrateError> {
        // The system may bring the last Jacobian here for much less than the differences'
        // right-hand side a column; an updated one that failed Newton, or the last of
        // `MAX_UPDATES`, gives way to an evaluated one.
        if self.has_jacobian && !self.evaluate_next && self.updates < MAX_UPDATES {
            let from = (self.t_jac, &self.x_jac[..]);
            if self.jac.update(sys, from, self.t, &self.x)? {
                ctx.jacobian_updates += 1;
                self.updates += 1;
                let jac = &self.jac;
                self.e.reduce(|r, c| jac.get(r, c));
                self.jac_current = true;
                self.jac_exact = false;
                self.t_jac = self.t;
                self.x_jac.copy_from_slice(&self.x);
                self.h_lu = f64::NAN;
                return Ok(());
            }
        }
        if !self.f0_exact {
            ctx.eval(sys, self.t, &self.x, &mut self.f0)?;
            self.f0_exact = true;
        }
        let analytic = self.jac.evaluate(sys, ctx, self.t, &mut self.x, &self.f0)?;
        self.updates = 0;
        self.evaluate_next = false;
        self.jac_exact = true;
        self.t_jac = self.t;
        self.x_jac.copy_from_slice(&self.x);
        self.has_jacobian = true;
        self.thet = if analytic { THET } else { THET_DIFFERENCES };
        let jac = &self.jac;
        self.e.reduce(|r, c| jac.get(r, c));
        self.jac_current = true;
        self.h_lu = f64::NAN;
        Ok(())
    }

    /// Factors `γ/h - J` and `(α + iβ)/h - J` through the Jacobian's Hessenberg form
    /// (`O(n²)` each). False if singular.
    fn factor(&mut self, ctx: &mut Ctx, h: f64) -> bool {
        let fac1 = self.gamma / h;
        let (alphn, betan) = (self.alpha / h, self.beta / h);
        ctx.lu_decompositions += 1;
        if !self.e.factor(fac1, (alphn, betan)) {
            return false;
        }
        self.h_lu = h;
        true
    }

    /// Weighted RMS of `e / scal`, floored at 1e-10 as in RADAU5.
    fn err_norm(&self, ctx: &Ctx, e: &[f64]) -> f64 {
        if ctx.wsum == 0.0 {
            return 1e-10;
        }
        let mut s = 0.0;
        for i in 0..self.n {
            let w = ctx.weights[i];
            if w != 0.0 {
                let r = e[i] / self.scal[i];
                s += w * r * r;
            }
        }
        // A NaN (a non-finite error or scale) is a rejection, not the floor's acceptance.
        let e = (s / ctx.wsum).sqrt();
        if e.is_finite() {
            e.max(1e-10)
        } else {
            f64::INFINITY
        }
    }

    /// Simplified Newton iteration for the stage increments at step `h`.
    /// `Ok(Ok(iterations))` on convergence, `Ok(Err(factor))` when the step
    /// must be retried with `h * factor`.
    /// A Newton iteration that did not contract: records the entry whose last increment
    /// (over the three stages, against its scale, the quadrature states left out as the
    /// iteration's test leaves them) was the largest, as a shortened step's
    /// ([`Ctx::shortened`]), and returns `fac`, the factor the step is cut by.
    fn newton_failed(&self, ctx: &mut Ctx, fac: f64) -> f64 {
        let n = self.n;
        let (quadrature, scal) = (&ctx.quadrature[..n], &self.scal[..n]);
        let size = |i: usize| {
            let s = self
                .dz
                .chunks_exact(n)
                .map(|dz| (dz[i] / scal[i]).abs())
                .fold(0.0, f64::max);
            if s.is_nan() { f64::INFINITY } else { s }
        };
        ctx.rejected_by = (0..n)
            .filter(|&i| !quadrature[i])
            .max_by(|&a, &b| size(a).total_cmp(&size(b)));
        fac
    }

    fn newton<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        ctx: &mut Ctx,
        h: f64,
    ) -> Result<Result<usize, f64>, IntegrateError> {
        let (n, t) = (self.n, self.t);
        // Starting values: zero, or the previous collocation polynomial extrapolated.
        if self.first {
            self.z.fill(0.0);
        } else {
            let c3q = h / self.h_old;
            let (c1m1, c2m1) = (C[0] - 1.0, C[1] - 1.0);
            let (k0, k1, k2) = (&self.cont[0][..n], &self.cont[1][..n], &self.cont[2][..n]);
            for (zs, ci) in self.z.chunks_exact_mut(n).zip(&C) {
                let q = ci * c3q;
                for i in 0..n {
                    zs[i] = q * (k0[i] + (q - c2m1) * (k1[i] + (q - c1m1) * k2[i]));
                }
            }
        }
        // The same increments in the eigenbasis: w = (T⁻¹⊗I) z. (Here and below the stages
        // are taken as slices of length `n` before the loops, which then index them without
        // bounds checks: indexed across `3n`, those were a third of the iteration's own
        // instructions.)
        {
            let (z1, z2, z3) = stages(&self.z, n);
            let (w1, w2, w3) = stages_mut(&mut self.w, n);
            for i in 0..n {
                let (a, b, c) = (z1[i], z2[i], z3[i]);
                w1[i] = TI[0][0] * a + TI[0][1] * b + TI[0][2] * c;
                w2[i] = TI[1][0] * a + TI[1][1] * b + TI[1][2] * c;
                w3[i] = TI[2][0] * a + TI[2][1] * b + TI[2][2] * c;
            }
        }
        let fac1 = self.gamma / h;
        let (alphn, betan) = (self.alpha / h, self.beta / h);
        self.faccon = self.faccon.max(f64::EPSILON).powf(0.8);
        self.theta = THET;
        let mut dyno_old = 0.0;
        let mut thq_old = 0.0;
        let mut newt = 0;
        loop {
            if newt >= NIT {
                return Ok(Err(self.newton_failed(ctx, 0.5)));
            }
            for s in 0..3 {
                let (tmp, x, z) = (&mut self.tmp[..n], &self.x[..n], &self.z[s * n..][..n]);
                for i in 0..n {
                    tmp[i] = x[i] + z[i];
                }
                // A stage the system refuses: the step is retried shorter.
                if let Err(e) = ctx.eval(
                    sys,
                    t + C[s] * h,
                    &self.tmp,
                    &mut self.fz[s * n..(s + 1) * n],
                ) {
                    ctx.stage_refused(e)?;
                    return Ok(Err(STAGE_RETRY_FACTOR));
                }
            }
            // The residual (T⁻¹⊗I) F(Z) - (Λ/h ⊗ I) W, then ΔW from the two factored blocks
            // (RADAU5's SLVRAD).
            {
                let (f1, f2, f3) = stages(&self.fz, n);
                let (w1, w2, w3) = stages(&self.w, n);
                let (d1, d2, _) = stages_mut(&mut self.dz, n);
                let d3 = &mut self.dc[..n];
                for i in 0..n {
                    let (f1, f2, f3) = (f1[i], f2[i], f3[i]);
                    let (w1, w2, w3) = (w1[i], w2[i], w3[i]);
                    let g = |s: usize| TI[s][0] * f1 + TI[s][1] * f2 + TI[s][2] * f3;
                    d1[i] = g(0) - fac1 * w1;
                    d2[i] = g(1) - alphn * w2 + betan * w3;
                    d3[i] = g(2) - alphn * w3 - betan * w2;
                }
            }
            let (d1, rest) = self.dz.split_at_mut(n);
            self.e.solve_stages(d1, &mut rest[..n], &mut self.dc);
            self.dz[2 * n..].copy_from_slice(&self.dc);
            newt += 1;
            // The quadrature states stay out of the test: no stage reads them, and their
            // increments follow the others' (System::quadratures).
            let mut sum = 0.0;
            let (quadrature, scal) = (&ctx.quadrature[..n], &self.scal[..n]);
            for dz in self.dz.chunks_exact(n) {
                for i in 0..n {
                    if !quadrature[i] {
                        let r = dz[i] / scal[i];
                        sum += r * r;
                    }
                }
            }
            let counted = 3 * (n - ctx.n_quadrature);
            let dyno = if counted > 0 {
                (sum / counted as f64).sqrt()
            } else {
                0.0
            };
            if !dyno.is_finite() {
                return Ok(Err(self.newton_failed(ctx, 0.5)));
            }
            if newt > 1 && newt < NIT {
                let thq = dyno / dyno_old;
                self.theta = if newt == 2 {
                    thq
                } else {
                    (thq * thq_old).sqrt()
                };
                thq_old = thq;
                if self.theta < 0.99 {
                    self.faccon = self.theta / (1.0 - self.theta);
                    // Predicted error after the remaining iterations too large: shrink h now.
                    let dyth =
                        self.faccon * dyno * self.theta.powi((NIT - 1 - newt) as i32) / self.fnewt;
                    if dyth >= 1.0 {
                        let qnewt = dyth.clamp(1e-4, 20.0);
                        let fac = 0.8 * qnewt.powf(-1.0 / (4.0 + (NIT - 1 - newt) as f64));
                        return Ok(Err(self.newton_failed(ctx, fac)));
                    }
                } else {
                    return Ok(Err(self.newton_failed(ctx, 0.5)));
                }
            }
            dyno_old = dyno.max(f64::EPSILON);
            // W += ΔW; Z = (T⊗I) W.
            {
                let (w1, w2, w3) = stages_mut(&mut self.w, n);
                let (d1, d2, d3) = stages(&self.dz, n);
                let (z1, z2, z3) = stages_mut(&mut self.z, n);
                for i in 0..n {
                    w1[i] += d1[i];
                    w2[i] += d2[i];
                    w3[i] += d3[i];
                    let (a, b, c) = (w1[i], w2[i], w3[i]);
                    z1[i] = T[0][0] * a + T[0][1] * b + T[0][2] * c;
                    z2[i] = T[1][0] * a + T[1][1] * b + T[1][2] * c;
                    z3[i] = T[2][0] * a + T[2][1] * b + T[2][2] * c;
                }
            }
            if self.faccon * dyno <= self.fnewt {
                return Ok(Ok(newt));
            }
        }
    }

    /// The filtered error estimate of RADAU5 (ESTRAD).
    fn error_estimate<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        ctx: &mut Ctx,
        h: f64,
    ) -> Result<f64, IntegrateError> {
        let n = self.n;
        // tmp = Σ (dd_i / h) z_i; err = (u1/h I - J)⁻¹ (f0 + tmp).
        for i in 0..n {
            self.tmp[i] =
                (DD[0] * self.z[i] + DD[1] * self.z[n + i] + DD[2] * self.z[2 * n + i]) / h;
            self.err[i] = self.tmp[i] + self.f0[i];
        }
        self.e.solve_real(&mut self.err);
        let mut err = self.err_norm(ctx, &self.err);
        if err >= 1.0 && (self.first || self.reject) {
            // One more filtering pass through f, which tames the estimate for
            // very stiff components (Hairer & Wanner IV.8).
            for i in 0..n {
                self.err[i] += self.x[i];
            }
            // `dz` (3n) is free here; use its head as scratch for f.
            let (fe, _) = self.dz.split_at_mut(n);
            ctx.eval(sys, self.t, &self.err, fe)?;
            for i in 0..n {
                self.err[i] = fe[i] + self.tmp[i];
            }
            self.e.solve_real(&mut self.err);
            err = self.err_norm(ctx, &self.err);
        }
        Ok(err)
    }

    fn accept(&mut self, h: f64, t_new: f64) {
        let n = self.n;
        let (c1, c2) = (C[0], C[1]);
        let (c1m1, c2m1, c1mc2) = (c1 - 1.0, c2 - 1.0, c1 - c2);
        for i in 0..n {
            let (z1, z2, z3) = (self.z[i], self.z[n + i], self.z[2 * n + i]);
            self.x[i] += z3;
            self.cont[0][i] = (z2 - z3) / c2m1;
            let ak = (z1 - z2) / c1mc2;
            let acont3 = (ak - z1 / c1) / c2;
            self.cont[1][i] = (ak - self.cont[0][i]) / c1m1;
            self.cont[2][i] = self.cont[1][i] - acont3;
        }
        self.t_old = self.t;
        self.t = t_new;
        self.h_old = h;
        self.first = false;
        self.jac_current = false;
        // The slope at the new step start, for the next error estimate: the collocation
        // polynomial's at its end, `((hA)⁻¹ Z)₃ = (T (Λ/h) W)₃`, which the last Newton
        // iteration made `f(x + z₃)` to first order (`F(Z) + J ΔZ`), the error of that
        // being the iteration's own. Evaluating `f` there instead, as RADAU5 does, was 6 to
        // 14 % of the right-hand sides on the stiff-hinge scene, for the same steps and
        // errors. A Jacobian still differences from `f` itself ([`Self::compute_jacobian`]),
        // and a slope the system holds is taken (`step`).
        {
            let (w1, w2, w3) = stages(&self.w, n);
            let (g, a, b) = (self.gamma / h, self.alpha / h, self.beta / h);
            let (t0, t1) = (T[2][0] * g, T[2][1]);
            debug_assert_eq!(T[2][2], 0.0);
            for i in 0..n {
                self.f0[i] = t0 * w1[i] + t1 * (a * w2[i] - b * w3[i]);
            }
        }
        self.f0_exact = false;
    }
}

impl Stepper for Radau5 {
    fn restart<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        ctx: &mut Ctx,
        t: f64,
        x: &[f64],
    ) -> Result<(), IntegrateError> {
        // A run continued from where the last one ended, its state untouched, starts
        // Newton from the last step's collocation polynomial, as a step within a run does.
        let continues = std::mem::take(&mut self.resumable)
            && self.h_old > 0.0
            && t == self.t
            && x == &self.x[..];
        self.t = t;
        self.t_old = t;
        self.x.copy_from_slice(x);
        self.first = !continues;
        self.reject = false;
        // Asked at every restart, so that each answer covers the handling since the last.
        let survives = sys.jacobian_survives_restart();
        self.need_jac = !(self.has_jacobian && survives);
        self.jac_current = false;
        // The factors stay valid with the Jacobian they were made from (a new one clears
        // them, `compute_jacobian`): a run continued at the step size it ended with
        // (`integrate_on`) keeps them too.
        self.theta = THET;
        self.faccon = 1.0;
        self.n_accepted = 0;
        ctx.eval(sys, t, x, &mut self.f0)?;
        self.f0_exact = true;
        self.h = match ctx.fixed {
            Some(h) => h,
            None => {
                let (a, b) = self.dz.split_at_mut(self.n);
                ctx.initial_step(sys, 5, t, x, &self.f0, a, &mut b[..self.n])?
            }
        };
        Ok(())
    }

    fn step<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        ctx: &mut Ctx,
        limit: f64,
    ) -> Result<(), IntegrateError> {
        let t = self.t;
        // The exact slope where the system holds it already (`System::holds_rhs`).
        if !self.f0_exact && sys.holds_rhs(t, &self.x) {
            ctx.eval(sys, t, &self.x, &mut self.f0)?;
            self.f0_exact = true;
        }
        for i in 0..self.n {
            self.scal[i] = self.atol + self.rtol * self.x[i].abs();
        }
        let fixed = ctx.fixed.is_some();
        // Fixed steps have no error control to catch a stale Jacobian.
        if fixed {
            self.need_jac = !self.jac_current;
        }
        let mut n_singular = 0;
        loop {
            ctx.check_budget(t)?;
            let (h, land) = clamp_to_limit(t, self.h.min(ctx.h_max), limit);
            let capped = land || h < self.h;
            if !fixed {
                ctx.check_step_size(t, h)?;
            }
            if self.need_jac {
                self.compute_jacobian(sys, ctx)?;
                self.need_jac = false;
            }
            if h != self.h_lu && !self.factor(ctx, h) {
                n_singular += 1;
                if n_singular >= 5 || fixed {
                    return Err(IntegrateError::ConvergenceFailure { t, h });
                }
                self.h = 0.5 * h;
                self.reject = true;
                ctx.rejected_by = None;
                ctx.steps_rejected += 1;
                continue;
            }
            let newt = match self.newton(sys, ctx, h)? {
                Ok(it) => it,
                Err(fac) => {
                    // An updated Jacobian that fails Newton gives way to an evaluated one.
                    self.evaluate_next |= !self.jac_exact;
                    if fixed {
                        if self.jac_current && self.jac_exact {
                            return Err(IntegrateError::ConvergenceFailure { t, h });
                        }
                        self.need_jac = true;
                        continue;
                    }
                    self.h = h * fac;
                    self.reject = true;
                    self.need_jac = !self.jac_current || !self.jac_exact;
                    ctx.steps_rejected += 1;
                    continue;
                }
            };
            let t_new = if land { limit } else { t + h };
            if fixed {
                self.accept(h, t_new);
                if !all_finite(&self.x) {
                    return Err(IntegrateError::non_finite_state(t_new, &self.x));
                }
                ctx.steps_accepted += 1;
                ctx.passed(t_new);
                return Ok(());
            }
            let err = self.error_estimate(sys, ctx, h)?;
            // Step-size proposal, damped when Newton needed many iterations.
            let cfac = SAFE * (1 + 2 * NIT) as f64;
            let fac = SAFE.min(cfac / (newt + 2 * NIT) as f64);
            let mut quot = (err.powf(0.25) / fac).clamp(FACR, FACL);
            let mut h_new = h / quot;
            if err < 1.0 {
                self.n_accepted += 1;
                if self.n_accepted > 1 {
                    // Gustafsson's predictive controller.
                    let facgus = ((self.hacc / h) * (err * err / self.erracc).powf(0.25) / SAFE)
                        .clamp(FACR, FACL);
                    quot = quot.max(facgus);
                    h_new = h / quot;
                }
                self.hacc = h;
                self.erracc = err.max(1e-2);
                self.accept(h, t_new);
                ctx.steps_accepted += 1;
                ctx.count_capped(capped, h);
                ctx.passed(t_new);
                h_new = h_new.min(ctx.h_max);
                if self.reject {
                    h_new = h_new.min(h);
                }
                self.reject = false;
                let qt = h_new / h;
                if self.theta <= self.thet && (QUOT1..=QUOT2).contains(&qt) {
                    // Keep h and the LU factors.
                    self.h = h;
                } else {
                    self.h = h_new;
                    self.need_jac = self.theta > self.thet;
                }
                if self.h < h {
                    ctx.rejected_by = largest_error(&ctx.weights, &self.err, |i| self.scal[i]);
                }
                return Ok(());
            }
            self.reject = true;
            ctx.steps_rejected += 1;
            ctx.rejected_by = largest_error(&ctx.weights, &self.err, |i| self.scal[i]);
            self.h = if self.first { 0.1 * h } else { h_new };
            // Unlike RADAU5, a Jacobian under which Newton contracted well is kept: the step
            // was too long for the error, not for the iteration. On the flexible deployment
            // this takes the Jacobians from 83 to 31 and the right-hand sides by a quarter,
            // the errors unchanged.
            self.need_jac = !self.jac_current && self.theta > self.thet;
        }
    }

    fn dense(&self, t: f64, out: &mut [f64]) {
        let s = if self.h_old > 0.0 {
            (t - self.t) / self.h_old
        } else {
            0.0
        };
        let (c1m1, c2m1) = (C[0] - 1.0, C[1] - 1.0);
        let c = &self.cont;
        for i in 0..out.len() {
            out[i] = self.x[i] + s * (c[0][i] + (s - c2m1) * (c[1][i] + (s - c1m1) * c[2][i]));
        }
    }

    fn proposed_step(&self) -> f64 {
        self.h
    }
    fn t(&self) -> f64 {
        self.t
    }
    fn t_old(&self) -> f64 {
        self.t_old
    }
    fn x(&self) -> &[f64] {
        &self.x
    }
    fn x_mut(&mut self) -> &mut [f64] {
        &mut self.x
    }
    /// The projection moves the state by about the local error ([`System::project`]): the
    /// collocation slope stays the error estimate's, and a Jacobian evaluates `f` anew.
    fn state_modified(&mut self) {
        self.f0_exact = false;
    }

    /// The collocation polynomial's slope at the step's end ([`Self::accept`]), where `f`
    /// was not evaluated there.
    fn end_slope(&self) -> Option<&[f64]> {
        (!self.f0_exact).then_some(self.f0.as_slice())
    }
}

#[cfg(test)]
mod tests {
    use crate::common::{Ctx, Stepper};
    use crate::{Method, Options, System, SystemError};

    /// A stiff damped oscillator (`ω` from 200 to 100) and a slow nonlinear state; counts the
    /// evaluations at a watched point.
    struct Stiff {
        watch: (f64, [f64; 3]),
        hits: usize,
    }
    impl System for Stiff {
        fn dim(&self) -> usize {
            3
        }
        fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
            if (t, x) == (self.watch.0, &self.watch.1[..]) {
                self.hits += 1;
            }
            dx[0] = x[1];
            dx[1] = -1e4 * (1.0 + 3.0 * x[2] * x[2]) * x[0] - 2.0 * x[1] + 10.0 * x[2];
            dx[2] = -5.0 * x[2] * x[2].abs() + 0.1 * x[0];
            Ok(())
        }
    }

    /// The slope the next error estimate takes is the collocation polynomial's at the step's
    /// end: `f` there to the Newton iteration's accuracy (on the scale of the step's error
    /// control), with no right-hand side spent on it except where a Jacobian is made there.
    #[test]
    fn the_step_end_slope_is_the_collocation_polynomials() {
        let mut sys = Stiff {
            watch: (f64::NAN, [0.0; 3]),
            hits: 0,
        };
        let opts = Options::new(Method::Radau5).with_tolerances(1e-6, 1e-6);
        let mut ctx = Ctx::new(&sys, &opts, f64::INFINITY).unwrap();
        let mut st = super::Radau5::new(3, 1e-6, 1e-6);
        st.restart(&mut sys, &mut ctx, 0.0, &[1e-3, 0.0, 1.0])
            .unwrap();
        let mut f = [0.0; 3];
        let mut worst: f64 = 0.0;
        for k in 0..40 {
            let jacobians = ctx.jacobian_evals;
            st.step(&mut sys, &mut ctx, 1.0).unwrap();
            // Each step's start point (after the restart's) was evaluated for its Jacobian
            // only.
            if k > 0 {
                assert_eq!(sys.hits, ctx.jacobian_evals - jacobians, "step {k}");
            }
            let (t, x) = (st.t, [st.x[0], st.x[1], st.x[2]]);
            sys.rhs(t, &x, &mut f).unwrap();
            (sys.watch, sys.hits) = ((t, x), 0);
            assert!(!st.f0_exact);
            // `f`'s difference from the slope, as the error estimate sees it: filtered by
            // `(γ/h - J)⁻¹` and weighed by `scal`, where a step is accepted below 1. (What
            // is left is `(J(x) - J) ΔZ`, the kept Jacobian's error on Newton's last
            // correction.)
            let mut d: Vec<f64> = (0..3).map(|i| f[i] - st.f0[i]).collect();
            st.e.solve_real(&mut d);
            for i in 0..3 {
                let scal = st.atol + st.rtol * x[i].abs();
                worst = worst.max((d[i] / scal).abs());
            }
        }
        assert!(ctx.jacobian_evals > 1, "{} Jacobians", ctx.jacobian_evals);
        // 0.044 measured: the error estimate moves by under a tenth of its threshold.
        assert!(worst < 0.1, "slope off by {worst} of the error scale");
        assert!(worst > 0.0, "the slope is the evaluated f");
    }

    /// [`Stiff`] with a Jacobian the system brings to each new state: the exact one there,
    /// or a wrong one (every entry zero).
    struct Updating {
        stiff: Stiff,
        exact: bool,
    }
    impl System for Updating {
        fn dim(&self) -> usize {
            3
        }
        fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
            self.stiff.rhs(t, x, dx)
        }
        fn update_jacobian(
            &mut self,
            _t0: f64,
            _x0: &[f64],
            _t: f64,
            x: &[f64],
            jac: &mut [f64],
        ) -> Result<bool, SystemError> {
            jac.fill(0.0);
            if self.exact {
                jac[1] = 1.0;
                jac[3] = -1e4 * (1.0 + 3.0 * x[2] * x[2]);
                jac[4] = -2.0;
                jac[5] = -6e4 * x[2] * x[0] + 10.0;
                jac[6] = 0.1;
                jac[8] = -10.0 * x[2].abs();
            }
            Ok(true)
        }
    }

    fn run(sys: &mut dyn System) -> crate::Stats {
        let opts = Options::new(Method::Radau5).with_tolerances(1e-6, 1e-6);
        let out = crate::Output::Interval(1.0);
        crate::integrate(sys, &opts, 0.0, &[1e-3, 0.0, 1.0], 4.0, &out, |_, _| {
            std::ops::ControlFlow::Continue(())
        })
        .unwrap()
    }

    /// Updated Jacobians stand in for evaluated ones, at most [`super::MAX_UPDATES`] in a
    /// row; a wrong one costs Newton's failure and an evaluated one, never the solution.
    #[test]
    fn updated_jacobians_stand_in_for_evaluated_ones_and_a_wrong_one_gives_way() {
        let stiff = || Stiff {
            watch: (f64::NAN, [0.0; 3]),
            hits: 0,
        };
        let plain = run(&mut stiff());
        assert_eq!(plain.jacobian_updates, 0);
        assert!(plain.jacobian_evals > 3, "{plain:?}");
        let close = |s: &crate::Stats| {
            let d = (0..3).map(|i| {
                (s.x_final[i] - plain.x_final[i]).abs() / (1e-6 + 1e-6 * plain.x_final[i].abs())
            });
            d.fold(0.0, f64::max)
        };
        let exact = run(&mut Updating {
            stiff: stiff(),
            exact: true,
        });
        assert!(exact.jacobian_updates > 0, "{exact:?}");
        assert!(exact.jacobian_updates <= super::MAX_UPDATES * exact.jacobian_evals);
        assert!(exact.jacobian_evals < plain.jacobian_evals, "{exact:?}");
        assert!(close(&exact) < 100.0, "{} tolerances off", close(&exact));
        let wrong = run(&mut Updating {
            stiff: stiff(),
            exact: false,
        });
        assert!(wrong.jacobian_updates > 0, "{wrong:?}");
        assert!(wrong.jacobian_evals >= wrong.jacobian_updates, "{wrong:?}");
        assert!(close(&wrong) < 100.0, "{} tolerances off", close(&wrong));
    }
}
