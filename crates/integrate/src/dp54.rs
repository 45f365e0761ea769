//! Dormand-Prince 5(4) (Hairer's DOPRI5): FSAL, PI step-size control and
//! Shampine's fourth-order continuous extension.

use crate::{
    common::{
        Ctx, PiController, STAGE_RETRY_FACTOR, Stepper, all_finite, clamp_to_limit, combine,
        lincomb,
    },
    error::IntegrateError,
    system::System,
};

/// Nodes `c_i`.
pub(crate) const C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];

/// Rows of the Butcher matrix (row `i` holds `a_ij`, `j < i`). Row 6 is the
/// fifth-order weights `b`, which makes stage 7 the FSAL derivative.
pub(crate) const A: [&[f64]; 7] = [
    &[],
    &[1.0 / 5.0],
    &[3.0 / 40.0, 9.0 / 40.0],
    &[44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0],
    &[
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
    ],
    &[
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
    ],
    &[
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];

/// `b - b̂`: difference of the 5th- and 4th-order weights (error estimate).
pub(crate) const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

/// Shampine's dense-output coefficients (Hairer's D1..D7).
pub(crate) const D: [f64; 7] = [
    -12715105075.0 / 11282082432.0,
    0.0,
    87487479700.0 / 32700410799.0,
    -10690763975.0 / 1880347072.0,
    701980252875.0 / 199316789632.0,
    -1453857185.0 / 822651844.0,
    69997945.0 / 29380423.0,
];

/// DOPRI5 stepper.
#[derive(Debug)]
pub(crate) struct Dp54 {
    t: f64,
    t_old: f64,
    h: f64,
    x: Vec<f64>,
    /// Stages; `k[0] = f(t, x)` (valid when `fsal_valid`).
    k: Vec<Vec<f64>>,
    fsal_valid: bool,
    x_new: Vec<f64>,
    tmp: Vec<f64>,
    /// Dense output: `x_old + s (r1 + (1-s) (r2 + s (r3 + (1-s) r4)))`.
    r: [Vec<f64>; 5],
    ctrl: PiController,
}

impl Dp54 {
    pub fn new(n: usize) -> Self {
        let z = || vec![0.0; n];
        Self {
            t: 0.0,
            t_old: 0.0,
            h: 0.0,
            x: z(),
            k: (0..7).map(|_| z()).collect(),
            fsal_valid: false,
            x_new: z(),
            tmp: z(),
            r: [z(), z(), z(), z(), z()],
            // Hairer's defaults: beta 0.04, 0.2 <= h_new/h <= 10.
            ctrl: PiController::new(5.0, 0.04, 0.2, 10.0),
        }
    }
}

impl Stepper for Dp54 {
    fn restart<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        ctx: &mut Ctx,
        t: f64,
        x: &[f64],
    ) -> Result<(), IntegrateError> {
        self.t = t;
        self.t_old = t;
        self.x.copy_from_slice(x);
        self.ctrl.reset();
        self.h = ctx.start_explicit(sys, 5, t, x, &mut self.k)?;
        self.fsal_valid = true;
        Ok(())
    }

    fn step<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        ctx: &mut Ctx,
        limit: f64,
    ) -> Result<(), IntegrateError> {
        let n = self.x.len();
        let t = self.t;
        if !self.fsal_valid {
            ctx.eval(sys, t, &self.x, &mut self.k[0])?;
            self.fsal_valid = true;
        }
        'step: loop {
            ctx.check_budget(t)?;
            let (h, land) = clamp_to_limit(t, self.h.min(ctx.h_max), limit);
            let capped = land || h < self.h;
            if ctx.fixed.is_none() {
                ctx.check_step_size(t, h)?;
            }
            for s in 1..7 {
                combine(&mut self.tmp, &self.x, h, A[s], &self.k[..s]);
                if let Err(e) = ctx.eval(sys, t + C[s] * h, &self.tmp, &mut self.k[s]) {
                    ctx.stage_refused(e)?;
                    ctx.steps_rejected += 1;
                    self.h = h * STAGE_RETRY_FACTOR;
                    continue 'step;
                }
                if s == 6 {
                    self.x_new.copy_from_slice(&self.tmp);
                }
            }
            let accepted = if ctx.fixed.is_some() {
                if !all_finite(&self.x_new) {
                    return Err(IntegrateError::non_finite_state(t + h, &self.x_new));
                }
                true
            } else {
                lincomb(&mut self.tmp, h, &E, &self.k);
                let err = ctx.norm(&self.tmp, &self.x, &self.x_new);
                let (ok, h_new) = self.ctrl.control(err, h);
                self.h = h_new;
                if h_new < h {
                    ctx.shortened(&self.tmp, &self.x, &self.x_new);
                }
                ok
            };
            if !accepted {
                ctx.steps_rejected += 1;
                continue;
            }
            // Dense output coefficients (Hairer's RCONT), built from the stages
            // before they are overwritten.
            for i in 0..n {
                let ydiff = self.x_new[i] - self.x[i];
                let bspl = h * self.k[0][i] - ydiff;
                self.r[0][i] = self.x[i];
                self.r[1][i] = ydiff;
                self.r[2][i] = bspl;
                self.r[3][i] = ydiff - h * self.k[6][i] - bspl;
                let mut d = 0.0;
                for (dj, kj) in D.iter().zip(&self.k) {
                    d += dj * kj[i];
                }
                self.r[4][i] = h * d;
            }
            self.x.copy_from_slice(&self.x_new);
            self.k.swap(0, 6);
            self.t_old = t;
            self.t = if land { limit } else { t + h };
            ctx.steps_accepted += 1;
            ctx.count_capped(capped, h);
            ctx.passed(self.t);
            return Ok(());
        }
    }

    fn dense(&self, t: f64, out: &mut [f64]) {
        let h = self.t - self.t_old;
        let s = if h > 0.0 { (t - self.t_old) / h } else { 1.0 };
        let s1 = 1.0 - s;
        let r = &self.r;
        for i in 0..out.len() {
            out[i] = r[0][i] + s * (r[1][i] + s1 * (r[2][i] + s * (r[3][i] + s1 * r[4][i])));
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
    fn state_modified(&mut self) {
        self.fsal_valid = false;
    }
}
