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
    /// Whether the quadrature states' columns have been checked to be zero (once, at the
    /// first finite-difference Jacobian; skipped after it).
    quadratures_checked: bool,
}

impl Jacobian {
    pub fn new(n: usize) -> Self {
        Self {
            n,
            j: vec![0.0; n * n],
            tmp: vec![0.0; n],
            quadratures_checked: false,
        }
    }

    /// Entry `(r, c)`, `∂f_r/∂x_c`.
    #[inline]
    pub fn get(&self, r: usize, c: usize) -> f64 {
        self.j[r * self.n + c]
    }

    /// Has the system bring `J`, evaluated at `(t0, x0)`, to `(t, x)`
    /// ([`System::update_jacobian`]); true when it did.
    pub fn update<S: System + ?Sized>(
        &mut self,
        sys: &mut S,
        (t0, x0): (f64, &[f64]),
        t: f64,
        x: &[f64],
    ) -> Result<bool, IntegrateError> {
        let updated = sys
            .update_jacobian(t0, x0, t, x, &mut self.j)
            .map_err(|source| IntegrateError::System { t, source })?;
        if updated && !all_finite(&self.j) {
            return Err(IntegrateError::NonFinite {
                t,
                entry: None,
                what: ": in the system's updated Jacobian".into(),
            });
        }
        Ok(updated)
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
        // Forward differences with RADAU5's increment sqrt(eps * max(1e-5, |x_j|)). A
        // quadrature state's column is zero: differenced once, to check that it is.
        let skip = self.quadratures_checked;
        self.quadratures_checked = true;
        for c in 0..n {
            if skip && ctx.quadrature[c] {
                for r in 0..n {
                    self.j[r * n + c] = 0.0;
                }
                continue;
            }
            let xc = x[c];
            let delta = (f64::EPSILON * xc.abs().max(1e-5)).sqrt();
            x[c] = xc + delta;
            let r = ctx.eval(sys, t, x, &mut self.tmp);
            x[c] = xc;
            r?;
            for (r, (fr, f0r)) in self.tmp.iter().zip(f0).enumerate() {
                self.j[r * n + c] = (fr - f0r) / delta;
            }
            let read_by = ctx.quadrature[c]
                .then(|| (0..n).find(|r| self.j[r * n + c] != 0.0))
                .flatten();
            if let Some(r) = read_by {
                return Err(IntegrateError::InvalidOptions(format!(
                    "state {c} is declared a quadrature (System::quadratures), but the \
                     derivative of state {r} depends on it"
                )));
            }
        }
        Ok(false)
    }
}
