//! `[integrator]`: the method, its step and tolerances.

use super::file::IntegratorFile;
use super::parse::Parser;
use satsim_integrate::{Method, Options};
use satsim_tree::io::FileError;
use toml::Spanned;

/// The options when the scene has no `[integrator]`: DP54 at rtol 1e-9, atol 1e-12.
pub fn default_options() -> Options {
    Options::new(Method::Dp54)
        .with_tolerances(1e-9, 1e-12)
        .with_max_steps(10_000_000)
}

impl Parser<'_> {
    pub(super) fn integrator(
        &self,
        f: Option<&Spanned<IntegratorFile>>,
    ) -> Result<Options, FileError> {
        let Some(f) = f else {
            return Ok(Options::new(Method::Dp54)
                .with_tolerances(1e-9, 1e-12)
                .with_max_steps(10_000_000));
        };
        let i = f.get_ref();
        let method = match &i.method {
            None => Method::Dp54,
            Some(m) => m
                .get_ref()
                .parse::<Method>()
                .map_err(|e| self.error(Some(m.span()), format!("`integrator.method`: {e}")))?,
        };
        let mut o = Options::new(method).with_max_steps(10_000_000);
        let rtol = match &i.rtol {
            Some(r) => {
                let rtol = self.non_negative(r, "integrator.rtol")?;
                // RADAU5's tolerance transform (`satsim_integrate::Options`).
                if method == Method::Radau5 && rtol > 0.0 && rtol < 10.0 * f64::EPSILON {
                    return Err(self.error(
                        Some(r.span()),
                        format!(
                            "`integrator.rtol` = {rtol:e} is below ten rounding units ({:e}) for \
                             radau5, whose error estimate scales `atol` by rtol^(-1/3): set it to \
                             0 (atol alone) or at least that",
                            10.0 * f64::EPSILON
                        ),
                    ));
                }
                rtol
            }
            None => 1e-9,
        };
        let atol = match &i.atol {
            Some(a) => {
                let atol = self.non_negative(a, "integrator.atol")?;
                if atol == 0.0 {
                    return Err(self.error(
                        Some(a.span()),
                        "`integrator.atol` must be > 0: with a relative tolerance alone a state \
                         that is or passes through zero (a rate at rest, a quaternion component) \
                         has no error scale and no step passes the error test; set `atol` to the \
                         absolute error acceptable in the smallest states (the default is 1e-12)",
                    ));
                }
                atol
            }
            None => 1e-12,
        };
        o = o.with_tolerances(rtol, atol);
        match (&i.step, method) {
            (Some(s), Method::Rk4) => o = o.with_fixed_step(self.positive(s, "integrator.step")?),
            (Some(s), _) => o = o.with_h0(self.positive(s, "integrator.step")?),
            (None, Method::Rk4) => {
                return Err(self.error(
                    Some(f.span()),
                    "`integrator.step` is required by the fixed-step method rk4",
                ));
            }
            (None, _) => {}
        }
        if let Some(h) = &i.max_step {
            o = o.with_h_max(self.positive(h, "integrator.max_step")?);
        }
        if let Some(n) = &i.max_steps {
            if *n.get_ref() <= 0 {
                return Err(self.error(Some(n.span()), "`integrator.max_steps` must be > 0"));
            }
            o = o.with_max_steps(*n.get_ref() as usize);
        }
        Ok(o)
    }
}
