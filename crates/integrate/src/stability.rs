//! Linear stability of the explicit methods: one step of size `h` on `y' = λ y` multiplies
//! `y` by the method's stability polynomial `R(z)`, `z = λ h`. A motion of the linearised
//! system with eigenvalue `λ` stays bounded only while `|R(λ h)| <= 1`, whatever the
//! tolerance: that, not the accuracy, holds an explicit method's step on a stiff mode.
//!
//! The polynomials are made from the Butcher tableaux the steppers run (`Yᵢ = 1 + z Σⱼ aᵢⱼ Yⱼ`,
//! `R = 1 + z Σᵢ bᵢ Yᵢ`), so they are the propagated solutions' own: DP5(4)'s fifth-order
//! one (Hairer & Wanner, Solving ODEs I, II.4: `R(z) = Σ_{k<=5} zᵏ/k! + z⁶/600`) and DOP853's
//! eighth-order one (degree 12).

use std::sync::OnceLock;

use crate::{dop853, dp54, options::Method};

/// `p(z) · z`, coefficients in increasing powers.
fn times_z(p: &[f64]) -> Vec<f64> {
    std::iter::once(0.0).chain(p.iter().copied()).collect()
}

/// `Σ wᵢ pᵢ(z)`.
fn weighted_sum(w: &[f64], p: &[Vec<f64>]) -> Vec<f64> {
    let len = p.iter().map(Vec::len).max().unwrap_or(0);
    let mut s = vec![0.0; len];
    for (wi, pi) in w.iter().zip(p) {
        for (sk, pk) in s.iter_mut().zip(pi) {
            *sk += wi * pk;
        }
    }
    s
}

/// `R(z)` of the explicit Runge-Kutta method with strictly lower-triangular rows `a` and
/// weights `b` (over the first `b.len()` stages).
fn from_tableau(a: &[&[f64]], b: &[f64]) -> Vec<f64> {
    let mut y: Vec<Vec<f64>> = Vec::with_capacity(b.len());
    for row in &a[..b.len()] {
        let mut yi = times_z(&weighted_sum(row, &y));
        yi.resize(yi.len().max(1), 0.0);
        yi[0] += 1.0;
        y.push(yi);
    }
    let mut r = times_z(&weighted_sum(b, &y));
    r[0] += 1.0;
    r
}

/// The polynomials, made once each (a step limit's scan evaluates them thousands of times).
static RK4: [f64; 5] = [1.0, 1.0, 0.5, 1.0 / 6.0, 1.0 / 24.0];
static DP54: OnceLock<Vec<f64>> = OnceLock::new();
static DOP853: OnceLock<Vec<f64>> = OnceLock::new();

impl Method {
    /// Whether the method chooses its steps by an error estimate without solving for its
    /// stages (DP5(4), DOP853): explicit, so held by its stability region on a stiff motion.
    pub fn is_explicit_adaptive(self) -> bool {
        matches!(self, Method::Dp54 | Method::Dop853)
    }

    /// The coefficients of the method's stability polynomial `R(z)`, in increasing powers of
    /// `z = λ h`; `None` for the implicit Radau IIA, whose stability function is rational and
    /// bounded by 1 over the whole left half-plane (A- and L-stable: no step limit from a
    /// damped or undamped mode).
    ///
    /// ```
    /// use satsim_integrate::Method;
    /// let r = Method::Rk4.stability_polynomial().unwrap();
    /// assert_eq!(r, [1.0, 1.0, 0.5, 1.0 / 6.0, 1.0 / 24.0]);
    /// assert!(Method::Radau5.stability_polynomial().is_none());
    /// ```
    pub fn stability_polynomial(self) -> Option<&'static [f64]> {
        match self {
            Method::Rk4 => Some(&RK4),
            // Row 6 is the fifth-order weights (the FSAL stage's row).
            Method::Dp54 => Some(DP54.get_or_init(|| from_tableau(&dp54::A, dp54::A[6]))),
            Method::Dop853 => Some(DOP853.get_or_init(|| from_tableau(&dop853::A, &dop853::B))),
            Method::Radau5 => None,
        }
    }

    /// `|R(z)|` at `z = re + i im`, the factor by which one step multiplies a linear motion
    /// with `λ h = z`; `None` for the implicit Radau IIA (see
    /// [`Method::stability_polynomial`]).
    ///
    /// ```
    /// use satsim_integrate::Method;
    /// // RK4 keeps an undamped oscillation bounded up to ω h = 2√2.
    /// let edge = 2.0 * 2f64.sqrt();
    /// assert!(Method::Rk4.stability_gain(0.0, 0.99 * edge).unwrap() <= 1.0);
    /// assert!(Method::Rk4.stability_gain(0.0, 1.01 * edge).unwrap() > 1.0);
    /// ```
    pub fn stability_gain(self, re: f64, im: f64) -> Option<f64> {
        let r = self.stability_polynomial()?;
        // Horner in complex arithmetic.
        let (mut pr, mut pi) = (0.0, 0.0);
        for c in r.iter().rev() {
            (pr, pi) = (pr * re - pi * im + c, pr * im + pi * re);
        }
        Some(pr.hypot(pi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn factorial(k: usize) -> f64 {
        (1..=k).map(|i| i as f64).product()
    }

    /// A method of order `p` reproduces `e^z` to `z^p` and no further: the first `p + 1`
    /// coefficients are `1/k!`, the next is not (a wrong tableau row or weight breaks this).
    #[test]
    fn the_polynomials_match_the_exponential_to_the_methods_order_and_no_further() {
        for m in [Method::Dp54, Method::Dop853] {
            let r = m.stability_polynomial().unwrap();
            let p = m.order();
            for k in 0..=p {
                let want = 1.0 / factorial(k);
                assert!(
                    (r[k] - want).abs() <= 1e-12 * want,
                    "{m}: z^{k} coefficient {} against 1/{k}! = {want}",
                    r[k]
                );
            }
            let next = 1.0 / factorial(p + 1);
            assert!(
                (r[p + 1] - next).abs() > 1e-3 * next,
                "{m}: z^{} coefficient {} is 1/{}!",
                p + 1,
                r[p + 1],
                p + 1
            );
        }
    }

    /// DOPRI5's polynomial as Hairer, Nørsett & Wanner print it (Solving ODEs I, II.5): the
    /// exponential's terms to `z⁵`, then `z⁶/600`, nothing above (six stages propagate).
    /// DOP853's has degree 12 (twelve stages).
    #[test]
    fn the_degrees_and_dopri5s_last_coefficient_are_the_published_ones() {
        let r = Method::Dp54.stability_polynomial().unwrap();
        assert_eq!(r.len(), 7);
        assert!((r[6] - 1.0 / 600.0).abs() < 1e-15, "{}", r[6]);
        assert_eq!(Method::Dop853.stability_polynomial().unwrap().len(), 13);
    }

    /// Where a scan along the ray of `(re, im)` first leaves the region.
    fn edge(m: Method, re: f64, im: f64) -> f64 {
        let mut s = 0.0;
        while m.stability_gain(re * (s + 1e-4), im * (s + 1e-4)).unwrap() <= 1.0 + 1e-12 {
            s += 1e-4;
        }
        s
    }

    /// The regions' ends on the axes: RK4's `2√2` and 2.785; DOPRI5's 3.3066 on the negative
    /// real axis (Hairer, Nørsett & Wanner, Solving ODEs I, fig. II.4.x: "about 3.3"), and its
    /// region leaves the imaginary axis at 0.997 (`|R(iy)| - 1` is `-2.5e-5` at 0.9 and
    /// `+1.4e-6` at 1.0).
    #[test]
    fn the_regions_ends_on_the_axes() {
        let near = |got: f64, want: f64| assert!((got - want).abs() < 2e-4, "{got} against {want}");
        near(edge(Method::Rk4, 0.0, 1.0), 2.0 * 2f64.sqrt());
        near(edge(Method::Rk4, -1.0, 0.0), 2.7853);
        near(edge(Method::Dp54, -1.0, 0.0), 3.3066);
        near(edge(Method::Dp54, 0.0, 1.0), 0.9971);
        let g = |y: f64| Method::Dp54.stability_gain(0.0, y).unwrap() - 1.0;
        assert!((g(0.9) + 2.48e-5).abs() < 1e-7 && (g(1.0) - 1.39e-6).abs() < 1e-8);
    }

    /// The steppers themselves against their polynomials: a damped oscillator (ζ = 0.2) run
    /// with a tolerance too loose to hold anything, the step capped at `h_max`, dies out at
    /// 0.98 times the ray's end and grows at 1.02 times it (DP5(4) and DOP853).
    #[test]
    fn the_steppers_are_stable_up_to_the_rays_end_and_not_past_it() {
        use crate::{Options, Output, System, SystemError, integrate};
        use std::ops::ControlFlow;
        struct Damped(f64, f64);
        impl System for Damped {
            fn dim(&self) -> usize {
                2
            }
            fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SystemError> {
                let (w, z) = (self.0, self.1);
                dx[0] = x[1];
                dx[1] = -w * w * x[0] - 2.0 * z * w * x[1];
                Ok(())
            }
        }
        let (w, z): (f64, f64) = (1.0, 0.2);
        let (re, im) = (-z * w, w * (1.0 - z * z).sqrt());
        for m in [Method::Dp54, Method::Dop853] {
            let end = edge(m, re, im);
            let run = |factor: f64| {
                let h = factor * end;
                let opts = Options::new(m).with_tolerances(1e3, 1e3).with_h_max(h);
                let stats = integrate(
                    &mut Damped(w, z),
                    &opts,
                    0.0,
                    &[1.0, 0.0],
                    3000.0 * h,
                    &Output::Times(vec![]),
                    |_, _| ControlFlow::Continue(()),
                )
                .unwrap();
                stats.x_final[0].hypot(stats.x_final[1])
            };
            let (under, over) = (run(0.98), run(1.02));
            assert!(under < 1.0 && over > 1e3, "{m}: {under} under, {over} over");
        }
    }
}
