//! Classic fourth-order Runge-Kutta at a fixed step, with a cubic Hermite
//! interpolant (from the endpoint derivatives) as dense output.

use crate::{
    common::{Ctx, Stepper, all_finite, clamp_to_limit},
    error::IntegrateError,
    system::System,
};

/// RK4 stepper. `f` holds `f(t, x)`, which is both the next step's first
/// stage and the Hermite slope at the right end of the last step.
#[derive(Debug)]
pub(crate) struct Rk4 {
    t: f64,
    t_old: f64,
    x: Vec<f64>,
    x_old: Vec<f64>,
    f: Vec<f64>,
    f_old: Vec<f64>,
    f_valid: bool,
    k2: Vec<f64>,
    k3: Vec<f64>,
    k4: Vec<f64>,
    tmp: Vec<f64>,
}

impl Rk4 {
    pub fn new(n: usize) -> Self {
        let z = || vec![0.0; n];
        Self {
            t: 0.0,
            t_old: 0.0,
            x: z(),
            x_old: z(),
            f: z(),
            f_old: z(),
            f_valid: false,
            k2: z(),
            k3: z(),
            k4: z(),
            tmp: z(),
        }
    }
}

impl Stepper for Rk4 {
    fn restart<S: System + ?Sized>(
        &mut self,
        _sys: &mut S,
        _ctx: &mut Ctx,
        t: f64,
        x: &[f64],
    ) -> Result<(), IntegrateError> {
        self.t = t;
        self.t_old = t;
        self.x.copy_from_slice(x);
        self.x_old.copy_from_slice(x);
        self.f_valid = false;
        Ok(())
    }

    fn step<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        ctx: &mut Ctx,
        limit: f64,
    ) -> Result<(), IntegrateError> {
        ctx.check_budget(self.t)?;
        let h_fixed = ctx.fixed.expect("validated: rk4 has a fixed step");
        let (h, land) = clamp_to_limit(self.t, h_fixed, limit);
        let (t, n) = (self.t, self.x.len());
        if !self.f_valid {
            ctx.eval(sys, t, &self.x, &mut self.f)?;
        }
        let x = &self.x;
        for i in 0..n {
            self.tmp[i] = x[i] + 0.5 * h * self.f[i];
        }
        ctx.eval(sys, t + 0.5 * h, &self.tmp, &mut self.k2)?;
        for i in 0..n {
            self.tmp[i] = x[i] + 0.5 * h * self.k2[i];
        }
        ctx.eval(sys, t + 0.5 * h, &self.tmp, &mut self.k3)?;
        for i in 0..n {
            self.tmp[i] = x[i] + h * self.k3[i];
        }
        ctx.eval(sys, t + h, &self.tmp, &mut self.k4)?;

        std::mem::swap(&mut self.x, &mut self.x_old);
        std::mem::swap(&mut self.f, &mut self.f_old);
        for i in 0..n {
            self.x[i] = self.x_old[i]
                + h / 6.0 * (self.f_old[i] + 2.0 * (self.k2[i] + self.k3[i]) + self.k4[i]);
        }
        if !all_finite(&self.x) {
            return Err(IntegrateError::NonFinite { t: t + h });
        }
        self.t_old = t;
        self.t = if land { limit } else { t + h };
        ctx.steps_accepted += 1;
        // The end slope feeds both the Hermite interpolant and the next step.
        ctx.eval(sys, self.t, &self.x, &mut self.f)?;
        self.f_valid = true;
        Ok(())
    }

    fn dense(&self, t: f64, out: &mut [f64]) {
        hermite(
            self.t_old,
            &self.x_old,
            &self.f_old,
            self.t,
            &self.x,
            &self.f,
            t,
            out,
        );
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
        // `f` still describes the unprojected endpoint for interpolation over
        // the last step; the next step must start from the projected state.
        self.f_valid = false;
    }
}

/// Cubic Hermite interpolation between `(t0, x0, f0)` and `(t1, x1, f1)`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn hermite(
    t0: f64,
    x0: &[f64],
    f0: &[f64],
    t1: f64,
    x1: &[f64],
    f1: &[f64],
    t: f64,
    out: &mut [f64],
) {
    let h = t1 - t0;
    let s = if h > 0.0 { (t - t0) / h } else { 1.0 };
    let s2 = s * s;
    let s3 = s2 * s;
    let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
    let h10 = s3 - 2.0 * s2 + s;
    let h01 = -2.0 * s3 + 3.0 * s2;
    let h11 = s3 - s2;
    for i in 0..out.len() {
        out[i] = h00 * x0[i] + h * h10 * f0[i] + h01 * x1[i] + h * h11 * f1[i];
    }
}
