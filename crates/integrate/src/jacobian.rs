//! The Jacobian `∂f/∂x` the implicit methods linearise with: the system's own where it gives
//! one ([`System::jacobian`]), otherwise forward differences, one right-hand side a column.

use crate::{
    common::{Ctx, all_finite},
    error::IntegrateError,
    system::System,
};

/// `∂f/∂x` at the last point evaluated, row-major.
#[derive(Clone, Debug)]
pub(crate) struct Jacobian {
    n: usize,
    j: Vec<f64>,
    tmp: Vec<f64>,
}

impl Jacobian {
    pub fn new(n: usize) -> Self {
        Self {
            n,
            j: vec![0.0; n * n],
            tmp: vec![0.0; n],
        }
    }

    /// Entry `(r, c)`, `∂f_r/∂x_c`.
    #[inline]
    pub fn get(&self, r: usize, c: usize) -> f64 {
        self.j[r * self.n + c]
    }

    /// Evaluates `J` at `(t, x)`, `f0 = f(t, x)`; true when the system gave it. `x` is
    /// perturbed one entry at a time for the differences and left as it was.
    pub fn evaluate<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        ctx: &mut Ctx,
        t: f64,
        x: &mut [f64],
        f0: &[f64],
    ) -> Result<bool, IntegrateError> {
        let n = self.n;
        ctx.jacobian_evals += 1;
        let analytic = sys
            .jacobian(t, x, &mut self.j)
            .map_err(|source| IntegrateError::System { t, source })?;
        if analytic {
            if !all_finite(&self.j) {
                return Err(IntegrateError::NonFinite {
                    t,
                    entry: None,
                    what: ": in the system's Jacobian".into(),
                });
            }
            return Ok(true);
        }
        // Forward differences with RADAU5's increment sqrt(eps * max(1e-5, |x_j|)).
        for c in 0..n {
            let xc = x[c];
            let delta = (f64::EPSILON * xc.abs().max(1e-5)).sqrt();
            x[c] = xc + delta;
            let r = ctx.eval(sys, t, x, &mut self.tmp);
            x[c] = xc;
            r?;
            for (r, (fr, f0r)) in self.tmp.iter().zip(f0).enumerate() {
                self.j[r * n + c] = (fr - f0r) / delta;
            }
        }
        Ok(false)
    }
}
