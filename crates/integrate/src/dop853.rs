//! Hairer's DOP853: explicit Runge-Kutta of order 8 (Dormand-Prince 8(5,3))
//! with the combined 5th/3rd-order error estimator and the 7th-order
//! continuous extension (three extra stages, evaluated only when needed).
//!
//! Stage `i` here is Hairer's stage `i + 1`. Stages 0..=11 advance the
//! solution, stage 12 is the FSAL derivative `f(t + h, x_new)` and stages
//! 13..=15 feed the dense output.

// Coefficients keep the digits as published by Hairer.
#![allow(clippy::excessive_precision)]

use crate::{
    common::{Ctx, PiController, STAGE_RETRY_FACTOR, Stepper, all_finite, clamp_to_limit, combine},
    error::IntegrateError,
    system::System,
};

/// Nodes `c_i` of all 16 stages.
pub(crate) const C: [f64; 16] = [
    0.0,
    0.526001519587677318785587544488e-01,
    0.789002279381515978178381316732e-01,
    0.118350341907227396726757197510e+00,
    0.281649658092772603273242802490e+00,
    0.333333333333333333333333333333e+00,
    0.25e+00,
    0.307692307692307692307692307692e+00,
    0.651282051282051282051282051282e+00,
    0.6e+00,
    0.857142857142857142857142857142e+00,
    1.0,
    1.0,
    0.1e+00,
    0.2e+00,
    0.777777777777777777777777777778e+00,
];

/// Rows of the Butcher matrix; row 12 is the order-8 weights `b`.
#[rustfmt::skip]
pub(crate) const A: [&[f64]; 16] = [
    &[],
    &[5.26001519587677318785587544488e-2],
    &[1.97250569845378994544595329183e-2, 5.91751709536136983633785987549e-2],
    &[2.95875854768068491816892993775e-2, 0.0, 8.87627564304205475450678981324e-2],
    &[2.41365134159266685502369798665e-1, 0.0, -8.84549479328286085344864962717e-1,
      9.24834003261792003115737966543e-1],
    &[3.7037037037037037037037037037e-2, 0.0, 0.0, 1.70828608729473871279604482173e-1,
      1.25467687566822425016691814123e-1],
    &[3.7109375e-2, 0.0, 0.0, 1.70252211019544039314978060272e-1,
      6.02165389804559606850219397283e-2, -1.7578125e-2],
    &[3.70920001185047927108779319836e-2, 0.0, 0.0, 1.70383925712239993810214054705e-1,
      1.07262030446373284651809199168e-1, -1.53194377486244017527936158236e-2,
      8.27378916381402288758473766002e-3],
    &[6.24110958716075717114429577812e-1, 0.0, 0.0, -3.36089262944694129406857109825e0,
      -8.68219346841726006818189891453e-1, 2.75920996994467083049415600797e1,
      2.01540675504778934086186788979e1, -4.34898841810699588477366255144e1],
    &[4.77662536438264365890433908527e-1, 0.0, 0.0, -2.48811461997166764192642586468e0,
      -5.90290826836842996371446475743e-1, 2.12300514481811942347288949897e1,
      1.52792336328824235832596922938e1, -3.32882109689848629194453265587e1,
      -2.03312017085086261358222928593e-2],
    &[-9.3714243008598732571704021658e-1, 0.0, 0.0, 5.18637242884406370830023853209e0,
      1.09143734899672957818500254654e0, -8.14978701074692612513997267357e0,
      -1.85200656599969598641566180701e1, 2.27394870993505042818970056734e1,
      2.49360555267965238987089396762e0, -3.0467644718982195003823669022e0],
    &[2.27331014751653820792359768449e0, 0.0, 0.0, -1.05344954667372501984066689879e1,
      -2.00087205822486249909675718444e0, -1.79589318631187989172765950534e1,
      2.79488845294199600508499808837e1, -2.85899827713502369474065508674e0,
      -8.87285693353062954433549289258e0, 1.23605671757943030647266201528e1,
      6.43392746015763530355970484046e-1],
    &B,
    &[5.61675022830479523392909219681e-2, 0.0, 0.0, 0.0, 0.0, 0.0,
      2.53500210216624811088794765333e-1, -2.46239037470802489917441475441e-1,
      -1.24191423263816360469010140626e-1, 1.5329179827876569731206322685e-1,
      8.20105229563468988491666602057e-3, 7.56789766054569976138603589584e-3,
      -8.298e-3],
    &[3.18346481635021405060768473261e-2, 0.0, 0.0, 0.0, 0.0,
      2.83009096723667755288322961402e-2, 5.35419883074385676223797384372e-2,
      -5.49237485713909884646569340306e-2, 0.0, 0.0,
      -1.08347328697249322858509316994e-4, 3.82571090835658412954920192323e-4,
      -3.40465008687404560802977114492e-4, 1.41312443674632500278074618366e-1],
    &[-4.28896301583791923408573538692e-1, 0.0, 0.0, 0.0, 0.0,
      -4.69762141536116384314449447206e0, 7.68342119606259904184240953878e0,
      4.06898981839711007970213554331e0, 3.56727187455281109270669543021e-1,
      0.0, 0.0, 0.0, -1.39902416515901462129418009734e-3,
      2.9475147891527723389556272149e0, -9.15095847217987001081870187138e0],
];

/// Order-8 weights.
#[rustfmt::skip]
pub(crate) const B: [f64; 12] = [
    5.42937341165687622380535766363e-2, 0.0, 0.0, 0.0, 0.0,
    4.45031289275240888144113950566e0, 1.89151789931450038304281599044e0,
    -5.8012039600105847814672114227e0, 3.1116436695781989440891606237e-1,
    -1.52160949662516078556178806805e-1, 2.01365400804030348374776537501e-1,
    4.47106157277725905176885569043e-2,
];

/// Weights of the 3rd-order embedded formula on stages 0, 8, 11.
pub(crate) const BHH: [f64; 3] = [
    0.244094488188976377952755905512e+00,
    0.733846688281611857341361741547e+00,
    0.220588235294117647058823529412e-01,
];

/// `b - b̂₅`: the 5th-order error estimate.
#[rustfmt::skip]
pub(crate) const ER: [f64; 12] = [
    0.1312004499419488073250102996e-01, 0.0, 0.0, 0.0, 0.0,
    -0.1225156446376204440720569753e+01, -0.4957589496572501915214079952e+00,
    0.1664377182454986536961530415e+01, -0.3503288487499736816886487290e+00,
    0.3341791187130174790297318841e+00, 0.8192320648511571246570742613e-01,
    -0.2235530786388629525884427845e-01,
];

/// Dense-output coefficients `d_{4..7, j}` over the 16 stages.
#[rustfmt::skip]
pub(crate) const DENSE: [[f64; 16]; 4] = [
    [-0.84289382761090128651353491142e+01, 0.0, 0.0, 0.0, 0.0,
     0.56671495351937776962531783590e+00, -0.30689499459498916912797304727e+01,
     0.23846676565120698287728149680e+01, 0.21170345824450282767155149946e+01,
     -0.87139158377797299206789907490e+00, 0.22404374302607882758541771650e+01,
     0.63157877876946881815570249290e+00, -0.88990336451333310820698117400e-01,
     0.18148505520854727256656404962e+02, -0.91946323924783554000451984436e+01,
     -0.44360363875948939664310572000e+01],
    [0.10427508642579134603413151009e+02, 0.0, 0.0, 0.0, 0.0,
     0.24228349177525818288430175319e+03, 0.16520045171727028198505394887e+03,
     -0.37454675472269020279518312152e+03, -0.22113666853125306036270938578e+02,
     0.77334326684722638389603898808e+01, -0.30674084731089398182061213626e+02,
     -0.93321305264302278729567221706e+01, 0.15697238121770843886131091075e+02,
     -0.31139403219565177677282850411e+02, -0.93529243588444783865713862664e+01,
     0.35816841486394083752465898540e+02],
    [0.19985053242002433820987653617e+02, 0.0, 0.0, 0.0, 0.0,
     -0.38703730874935176555105901742e+03, -0.18917813819516756882830838328e+03,
     0.52780815920542364900561016686e+03, -0.11573902539959630126141871134e+02,
     0.68812326946963000169666922661e+01, -0.10006050966910838403183860980e+01,
     0.77771377980534432092869265740e+00, -0.27782057523535084065932004339e+01,
     -0.60196695231264120758267380846e+02, 0.84320405506677161018159903784e+02,
     0.11992291136182789328035130030e+02],
    [-0.25693933462703749003312586129e+02, 0.0, 0.0, 0.0, 0.0,
     -0.15418974869023643374053993627e+03, -0.23152937917604549567536039109e+03,
     0.35763911791061412378285349910e+03, 0.93405324183624310003907691704e+02,
     -0.37458323136451633156875139351e+02, 0.10409964950896230045147246184e+03,
     0.29840293426660503123344363579e+02, -0.43533456590011143754432175058e+02,
     0.96324553959188282948394950600e+02, -0.39177261675615439165231486172e+02,
     -0.14972683625798562581422125276e+03],
];

/// DOP853 stepper.
#[derive(Debug)]
pub(crate) struct Dop853 {
    t: f64,
    t_old: f64,
    /// Step size proposed for the next attempt.
    h: f64,
    /// Size of the last accepted step.
    h_done: f64,
    x: Vec<f64>,
    x_old: Vec<f64>,
    k: Vec<Vec<f64>>,
    /// `k[0] = f(t, x)` is valid.
    f_valid: bool,
    /// The FSAL derivative of the last step still sits in `k[12]`.
    fsal_pending: bool,
    dense_ready: bool,
    tmp: Vec<f64>,
    err3: Vec<f64>,
    /// Dense output `r[0..8]` (Hairer's CONT).
    r: Vec<Vec<f64>>,
    ctrl: PiController,
}

impl Dop853 {
    pub fn new(n: usize) -> Self {
        let z = || vec![0.0; n];
        Self {
            t: 0.0,
            t_old: 0.0,
            h: 0.0,
            h_done: 0.0,
            x: z(),
            x_old: z(),
            k: (0..16).map(|_| z()).collect(),
            f_valid: false,
            fsal_pending: false,
            dense_ready: false,
            tmp: z(),
            err3: z(),
            r: (0..8).map(|_| z()).collect(),
            // Hairer's defaults: beta 0, 1/3 <= h_new/h <= 6.
            ctrl: PiController::new(8.0, 0.0, 0.333, 6.0),
        }
    }
}

/// Hairer's combined estimate `|h| ‖e5‖² / sqrt(‖e5‖² + 0.01 ‖e3‖²)`: of
/// 8th order like the method yet robust (the 3rd-order part guards against
/// an accidentally small 5th-order estimate).
fn error(ctx: &Ctx, h: f64, x0: &[f64], x1: &[f64], e5v: &[f64], e3v: &[f64]) -> f64 {
    if ctx.wsum == 0.0 {
        return 0.0;
    }
    let (mut e5, mut e3) = (0.0, 0.0);
    for i in 0..x1.len() {
        let w = ctx.weights[i];
        if w != 0.0 {
            let sk = ctx.atol + ctx.rtol * x0[i].abs().max(x1[i].abs());
            let a = e5v[i] / sk;
            let b = e3v[i] / sk;
            e5 += w * a * a;
            e3 += w * b * b;
        }
    }
    let mut deno = e5 + 0.01 * e3;
    if deno <= 0.0 {
        deno = 1.0;
    }
    let err = h.abs() * e5 * (1.0 / (ctx.wsum * deno)).sqrt();
    if err.is_finite() { err } else { f64::INFINITY }
}

impl Stepper for Dop853 {
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
        self.x_old.copy_from_slice(x);
        self.ctrl.reset();
        self.fsal_pending = false;
        self.dense_ready = false;
        self.h = ctx.start_explicit(sys, 8, t, x, &mut self.k)?;
        self.f_valid = true;
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
        if self.fsal_pending {
            self.k.swap(0, 12);
            self.fsal_pending = false;
        }
        if !self.f_valid {
            ctx.eval(sys, t, &self.x, &mut self.k[0])?;
            self.f_valid = true;
        }
        self.x_old.copy_from_slice(&self.x);
        'step: loop {
            ctx.check_budget(t)?;
            let (h, land) = clamp_to_limit(t, self.h.min(ctx.h_max), limit);
            let capped = land || h < self.h;
            if ctx.fixed.is_none() {
                ctx.check_step_size(t, h)?;
            }
            for s in 1..12 {
                combine(&mut self.tmp, &self.x_old, h, A[s], &self.k[..s]);
                if let Err(e) = ctx.eval(sys, t + C[s] * h, &self.tmp, &mut self.k[s]) {
                    ctx.stage_refused(e)?;
                    ctx.steps_rejected += 1;
                    self.h = h * STAGE_RETRY_FACTOR;
                    continue 'step;
                }
            }
            // x_new = x + h Σ b_j k_j; `x` holds it from here on (x_old is kept).
            combine(&mut self.x, &self.x_old, h, &B, &self.k[..12]);
            let (k_lo, k_hi) = self.k.split_at_mut(12);
            if let Err(e) = ctx.eval(sys, t + h, &self.x, &mut k_hi[0]) {
                ctx.stage_refused(e)?;
                ctx.steps_rejected += 1;
                self.h = h * STAGE_RETRY_FACTOR;
                self.x.copy_from_slice(&self.x_old);
                continue 'step;
            }
            let accepted = if ctx.fixed.is_some() {
                if !all_finite(&self.x) {
                    return Err(IntegrateError::non_finite_state(t + h, &self.x));
                }
                true
            } else {
                for i in 0..n {
                    let mut e5 = 0.0;
                    let mut bsum = 0.0;
                    for j in 0..12 {
                        e5 += ER[j] * k_lo[j][i];
                        bsum += B[j] * k_lo[j][i];
                    }
                    self.tmp[i] = e5;
                    self.err3[i] =
                        bsum - BHH[0] * k_lo[0][i] - BHH[1] * k_lo[8][i] - BHH[2] * k_lo[11][i];
                }
                let err = error(ctx, h, &self.x_old, &self.x, &self.tmp, &self.err3);
                let (ok, h_new) = self.ctrl.control(err, h);
                self.h = h_new;
                if h_new < h {
                    ctx.shortened(&self.tmp, &self.x_old, &self.x);
                }
                ok
            };
            if !accepted {
                ctx.steps_rejected += 1;
                self.x.copy_from_slice(&self.x_old);
                continue;
            }
            self.h_done = h;
            self.t_old = t;
            self.t = if land { limit } else { t + h };
            self.fsal_pending = true;
            self.dense_ready = false;
            ctx.steps_accepted += 1;
            ctx.count_capped(capped, h);
            ctx.passed(self.t);
            return Ok(());
        }
    }

    fn prepare_dense<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        ctx: &mut Ctx,
    ) -> Result<(), IntegrateError> {
        if self.dense_ready || !self.fsal_pending {
            // Nothing stepped since the last (re)start, or already done.
            return Ok(());
        }
        let (h, t) = (self.h_done, self.t_old);
        for s in 13..16 {
            combine(&mut self.tmp, &self.x_old, h, A[s], &self.k[..s]);
            ctx.eval(sys, t + C[s] * h, &self.tmp, &mut self.k[s])?;
        }
        let n = self.x.len();
        for i in 0..n {
            let ydiff = self.x[i] - self.x_old[i];
            let bspl = h * self.k[0][i] - ydiff;
            self.r[0][i] = self.x_old[i];
            self.r[1][i] = ydiff;
            self.r[2][i] = bspl;
            self.r[3][i] = ydiff - h * self.k[12][i] - bspl;
            for (row, d) in DENSE.iter().enumerate() {
                let mut acc = 0.0;
                for (dj, kj) in d.iter().zip(&self.k) {
                    acc += dj * kj[i];
                }
                self.r[4 + row][i] = h * acc;
            }
        }
        self.dense_ready = true;
        Ok(())
    }

    fn dense(&self, t: f64, out: &mut [f64]) {
        debug_assert!(self.dense_ready, "prepare_dense must run first");
        let h = self.t - self.t_old;
        let s = if h > 0.0 { (t - self.t_old) / h } else { 1.0 };
        let s1 = 1.0 - s;
        let r = &self.r;
        for i in 0..out.len() {
            out[i] = r[0][i]
                + s * (r[1][i]
                    + s1 * (r[2][i]
                        + s * (r[3][i]
                            + s1 * (r[4][i] + s * (r[5][i] + s1 * (r[6][i] + s * r[7][i]))))));
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
        self.f_valid = false;
    }
}
