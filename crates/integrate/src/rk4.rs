//! Classic fourth-order Runge-Kutta at a fixed step, with a cubic Hermite
//! interpolant (from the endpoint derivatives) as dense output.
//!
//! Four right-hand sides per step: the slope at the end of a step is evaluated once, at the
//! start of the next step (after any projection of the state), or earlier by
//! [`Stepper::prepare_dense`] when an output time or an event falls inside the step.

use crate::{
    common::{Ctx, Stepper, all_finite, clamp_to_limit},
    error::IntegrateError,
    system::System,
};

/// RK4 stepper. `f` holds `f(t, x)` when `f_valid`: both the next step's first stage and
/// the Hermite slope at the right end of the last step.
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
    /// The step under way: its size, whether it lands on `limit`.
    h: f64,
    land: bool,
    limit: f64,
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
            h: 0.0,
            land: false,
            limit: 0.0,
        }
    }
}

/// A step in pieces, so that a batch of runs (`lanes.rs`) evaluates each stage of all its
/// runs together: [`Rk4::begin_step`], then the right-hand side of each [`Rk4::stage`], then
/// [`Rk4::end_step`]. [`Stepper::step`] is exactly that sequence.
impl Rk4 {
    /// The step toward `limit` (landing on it when within reach).
    #[inline]
    pub(crate) fn begin_step(&mut self, ctx: &Ctx, limit: f64) -> Result<(), IntegrateError> {
        ctx.check_budget(self.t)?;
        let h_fixed = ctx.fixed.expect("validated: rk4 has a fixed step");
        (self.h, self.land) = clamp_to_limit(self.t, h_fixed, limit);
        self.limit = limit;
        Ok(())
    }

    /// Stage `s` (0 to 3): where the slope is wanted, `(t, x)`, and where it goes; `None`
    /// for the first stage when the slope at the step's start is known already.
    #[inline]
    pub(crate) fn stage(&mut self, s: usize) -> Option<(f64, &[f64], &mut [f64])> {
        let (t, h) = (self.t, self.h);
        match s {
            0 => (!self.f_valid).then_some((t, &self.x[..], &mut self.f[..])),
            1 => {
                axpy(&mut self.tmp, &self.x, 0.5 * h, &self.f);
                Some((t + 0.5 * h, &self.tmp, &mut self.k2))
            }
            2 => {
                axpy(&mut self.tmp, &self.x, 0.5 * h, &self.k2);
                Some((t + 0.5 * h, &self.tmp, &mut self.k3))
            }
            _ => {
                axpy(&mut self.tmp, &self.x, h, &self.k3);
                Some((t + h, &self.tmp, &mut self.k4))
            }
        }
    }

    /// The step's end from its four slopes.
    #[inline]
    pub(crate) fn end_step(&mut self, ctx: &mut Ctx) -> Result<(), IntegrateError> {
        let (t, h) = (self.t, self.h);
        std::mem::swap(&mut self.x, &mut self.x_old);
        std::mem::swap(&mut self.f, &mut self.f_old);
        let slopes = self.f_old.iter().zip(&self.k2).zip(&self.k3).zip(&self.k4);
        for ((x, x_old), (((f, k2), k3), k4)) in self.x.iter_mut().zip(&self.x_old).zip(slopes) {
            *x = x_old + h / 6.0 * (f + 2.0 * (k2 + k3) + k4);
        }
        if !all_finite(&self.x) {
            return Err(IntegrateError::non_finite_state(t + h, &self.x));
        }
        self.t_old = t;
        self.t = if self.land { self.limit } else { t + h };
        ctx.steps_accepted += 1;
        // The end slope is evaluated lazily: by the next step (at the projected state) or by
        // `prepare_dense`, never twice.
        self.f_valid = false;
        Ok(())
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
        self.begin_step(ctx, limit)?;
        for stage in 0..4 {
            if let Some((t, x, dx)) = self.stage(stage) {
                ctx.eval(sys, t, x, dx)?;
            }
        }
        self.end_step(ctx)
    }

    fn prepare_dense<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        ctx: &mut Ctx,
    ) -> Result<(), IntegrateError> {
        if !self.f_valid {
            // The slope at the (possibly projected) end point: the Hermite interpolant's right
            // slope, and the next step's first stage.
            ctx.eval(sys, self.t, &self.x, &mut self.f)?;
            self.f_valid = true;
        }
        Ok(())
    }

    fn dense(&self, t: f64, out: &mut [f64]) {
        debug_assert!(self.f_valid, "prepare_dense must run first");
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
        // The end slope (if already evaluated) described the unprojected end point.
        self.f_valid = false;
    }
}

/// Cubic Hermite interpolation between `(t0, x0, f0)` and `(t1, x1, f1)`.
/// `out = x + a k` (zipped: no bounds checks, so that the loop vectorises).
#[inline]
fn axpy(out: &mut [f64], x: &[f64], a: f64, k: &[f64]) {
    for ((o, x), k) in out.iter_mut().zip(x).zip(k) {
        *o = x + a * k;
    }
}

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
    let h10 = s3 - 2.0 * s2 + s;
    let h01 = -2.0 * s3 + 3.0 * s2;
    let h11 = s3 - s2;
    // x0 + h01 (x1 − x0) rather than h00 x0 + h01 x1 (h00 = 1 − h01): a component that
    // does not move during the step (a latched hinge: x1 = x0, zero slopes) comes out as
    // x0 exactly, where the blend rounded it by an ulp depending on where t falls.
    for i in 0..out.len() {
        out[i] = x0[i] + h01 * (x1[i] - x0[i]) + h * (h10 * f0[i] + h11 * f1[i]);
    }
}

#[cfg(test)]
mod tests {
    use super::hermite;
    use crate::{Method, Options, Output, System, SystemError, integrate};
    use std::ops::ControlFlow;

    /// A rotating unit vector (a "quaternion" kept on the sphere by projection), counting
    /// its right-hand sides.
    struct Spin {
        evals: usize,
    }
    impl System for Spin {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
            self.evals += 1;
            dx[0] = -x[1];
            dx[1] = x[0];
            Ok(())
        }
        fn project(&mut self, x: &mut [f64]) {
            let n = x[0].hypot(x[1]);
            x[0] /= n;
            x[1] /= n;
        }
    }

    fn run(output: &Output) -> (crate::Stats, Vec<(f64, f64)>, usize) {
        let mut sys = Spin { evals: 0 };
        let opts = Options::new(Method::Rk4).with_fixed_step(0.1);
        let mut rows = Vec::new();
        let st = integrate(&mut sys, &opts, 0.0, &[1.0, 0.0], 10.0, output, |t, x| {
            rows.push((t, x[0]));
            ControlFlow::Continue(())
        })
        .unwrap();
        (st, rows, sys.evals)
    }

    #[test]
    fn four_evaluations_per_step_even_with_projection() {
        // No output inside the steps: exactly four slopes per step (the end slope of a step
        // is the next step's first stage, evaluated once after the projection).
        let (st, _, evals) = run(&Output::Times(vec![]));
        assert_eq!(st.steps_accepted, 100);
        assert_eq!(evals, st.rhs_evals);
        assert_eq!(st.rhs_evals, 4 * 100);
        // Fixed steps land on output times, so an output grid costs nothing extra either;
        // the final state agrees with the run without outputs (to the rounding of the step
        // times), and with the exact solution to RK4's error.
        let (st2, rows, _) = run(&Output::Interval(1.0));
        assert_eq!(st2.rhs_evals, 400);
        assert!((st2.x_final[0] - st.x_final[0]).abs() < 1e-13);
        assert_eq!(rows.len(), 11);
        // Phase error of RK4 on a rotation: 100 h⁵/120 ≈ 8e-6 rad.
        assert!((st.x_final[0] - 10f64.cos()).abs() < 1e-5);
    }

    #[test]
    fn hermite_keeps_a_component_that_does_not_move_exactly() {
        // A latched hinge's angle: equal ends, zero slopes, at any point of the step.
        let x = [-1.3876441445556664e-11, 0.3, 1.0 / 3.0, -7.1e5];
        let zero = [0.0; 4];
        let mut out = [0.0; 4];
        for k in 0..=1000 {
            let t = 116.53228313873322 + 0.01 * k as f64 / 1000.0;
            hermite(
                116.53228313873322,
                &x,
                &zero,
                116.54228313873322,
                &x,
                &zero,
                t,
                &mut out,
            );
            assert_eq!(out, x, "at t = {t}");
        }
    }

    #[test]
    fn dense_output_evaluates_the_end_slope_once() {
        // With a fixed step the driver lands on output times, so exercise the interpolant
        // directly through the stepper: prepare_dense evaluates the end slope only once, and
        // the next step reuses it.
        use crate::common::{Ctx, Stepper};
        let mut sys = Spin { evals: 0 };
        let opts = Options::new(Method::Rk4).with_fixed_step(0.1);
        let mut ctx = Ctx::new(&sys, &opts, f64::INFINITY).unwrap();
        let mut st = super::Rk4::new(2);
        st.restart(&mut sys, &mut ctx, 0.0, &[1.0, 0.0]).unwrap();
        st.step(&mut sys, &mut ctx, 1.0).unwrap();
        assert_eq!(sys.evals, 4);
        st.prepare_dense(&mut sys, &mut ctx).unwrap();
        st.prepare_dense(&mut sys, &mut ctx).unwrap();
        assert_eq!(sys.evals, 5);
        let mut mid = [0.0; 2];
        st.dense(0.05, &mut mid);
        // Cubic Hermite error h⁴/384 max|x⁗| ≈ 2.6e-7.
        assert!((mid[0] - 0.05f64.cos()).abs() < 1e-6 && (mid[1] - 0.05f64.sin()).abs() < 1e-6);
        st.step(&mut sys, &mut ctx, 1.0).unwrap();
        assert_eq!(sys.evals, 8);
        assert_eq!(ctx.rhs_evals, 8);
    }
}
