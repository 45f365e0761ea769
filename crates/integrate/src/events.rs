//! Root location of event functions on the dense output (Illinois method).

use crate::system::EventDirection;

/// Locates the crossing of `g` in `[ta, tb]` given `g(ta) = ga`, `g(tb) = gb`
/// with `dir.crosses(ga, gb)`. Returns the right end of a final bracket no
/// wider than `tol`, i.e. a time at which `g` has already crossed (so the
/// event does not fire again when integration resumes from there).
///
/// Illinois (modified regula falsi): superlinear on smooth `g`, with a
/// bisection fallback that guarantees the bracket shrinks. An error from `g`
/// (the system could not evaluate its event functions) is passed on.
///
/// A secant point at or beyond an end's margin (a quarter of `tol` inside it) is moved to
/// the margin, as SUNDIALS' root finding moves it, rather than replaced by the midpoint:
/// once the secant has converged onto the crossing, it falls on the end it last moved, and
/// the point just past the crossing closes the bracket at once, where bisecting from the
/// far end took `log₂(width / tol)` more evaluations (about 25 for a step of 0.05 s and
/// `tol` 1e-10; each an evaluation of the event functions, a right-hand side where they
/// read hold torques). A moved point that leaves the bracket wide (the crossing not within
/// the margin after all) makes the next point the midpoint.
pub(crate) fn locate<E>(
    dir: EventDirection,
    mut ta: f64,
    mut ga: f64,
    mut tb: f64,
    mut gb: f64,
    tol: f64,
    mut g: impl FnMut(f64) -> Result<f64, E>,
) -> Result<f64, E> {
    // Which end was kept last time (-1 left, +1 right), for the Illinois halving.
    let mut kept = 0i8;
    let mut iter = 0;
    // Whether the last point was moved to a margin.
    let mut moved = false;
    while tb - ta > tol {
        iter += 1;
        let width = tb - ta;
        let tm_secant = if ga != gb {
            ta + width * ga / (ga - gb)
        } else {
            f64::NAN
        };
        // Stay strictly inside, a margin away from the ends; bisect when the secant is
        // unusable, stalls (many iterations), or was moved to a margin last time and would be
        // again.
        let margin = 0.25 * tol.min(width);
        let (lo, hi) = (ta + margin, tb - margin);
        let inside = tm_secant > lo && tm_secant < hi;
        let tm = if inside && iter <= 60 {
            moved = false;
            tm_secant
        } else if tm_secant.is_nan() || iter > 60 || moved || lo >= hi {
            moved = false;
            0.5 * (ta + tb)
        } else {
            moved = true;
            if tm_secant <= lo { lo } else { hi }
        };
        let gm = g(tm)?;
        if dir.crosses(ga, gm) {
            tb = tm;
            gb = gm;
            if kept == -1 {
                ga *= 0.5;
            }
            kept = -1;
        } else {
            ta = tm;
            ga = gm;
            if kept == 1 {
                gb *= 0.5;
            }
            kept = 1;
        }
        if iter > 200 {
            break;
        }
    }
    Ok(tb)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    /// The crossing of `g` in `[0, 0.05]` with `tol` 1e-10, and how many evaluations it took.
    fn locate_counting(dir: EventDirection, g: impl Fn(f64) -> f64) -> (f64, usize) {
        let calls = Cell::new(0);
        let counted = |t: f64| {
            calls.set(calls.get() + 1);
            Ok::<f64, ()>(g(t))
        };
        let (ta, tb) = (0.0, 0.05);
        let t = locate(dir, ta, g(ta), tb, g(tb), 1e-10, counted).unwrap();
        (t, calls.get())
    }

    /// A name, the exact crossing, the function and the most evaluations allowed.
    type Case = (&'static str, f64, Box<dyn Fn(f64) -> f64>, usize);

    #[test]
    fn smooth_crossings_close_their_bracket_in_a_few_evaluations() {
        let root = (1.04f64).ln() / 3.0;
        let cases: [Case; 4] = [
            ("linear", 0.0123, Box::new(|t| t - 0.0123), 3),
            ("exponential", root, Box::new(|t| (3.0 * t).exp() - 1.04), 8),
            (
                "sine, falling",
                (0.3f64).asin() / 20.0,
                Box::new(|t| 0.3 - (20.0 * t).sin()),
                8,
            ),
            (
                "quadratic",
                0.02,
                Box::new(|t| (t + 0.01) * (t + 0.01) - 0.0009),
                10,
            ),
        ];
        for (name, exact, g, most) in cases {
            let (t, n) = locate_counting(EventDirection::Both, g);
            // The right end of the final bracket: at or just past the crossing.
            assert!(
                t >= exact - 1e-15 && t - exact <= 1e-10,
                "{name}: {t} against {exact}"
            );
            // Bisecting the last bracket from its far end took 20 to 28.
            assert!(n <= most, "{name}: {n} evaluations");
        }
    }

    #[test]
    fn kinks_and_jumps_are_still_bracketed() {
        let kink = |t: f64| {
            if t < 0.02 {
                t - 0.02
            } else {
                10.0 * (t - 0.02)
            }
        };
        let jump = |t: f64| if t < 0.0171 { -1.0 } else { 1.0 };
        for (name, exact, g) in [
            ("kink", 0.02, &kink as &dyn Fn(f64) -> f64),
            ("jump", 0.0171, &jump),
        ] {
            let (t, n) = locate_counting(EventDirection::Rising, g);
            assert!(t >= exact && t - exact <= 1e-10, "{name}: {t}");
            assert!(n <= 60, "{name}: {n} evaluations");
        }
    }
}
