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
    while tb - ta > tol {
        iter += 1;
        let width = tb - ta;
        let mut tm = if ga != gb {
            ta + width * ga / (ga - gb)
        } else {
            f64::NAN
        };
        // Stay strictly inside, away from the ends, and bisect when the secant
        // stalls (many iterations) or is unusable.
        let margin = 0.25 * tol.min(width);
        if !(tm > ta + margin && tm < tb - margin) || iter > 60 {
            tm = 0.5 * (ta + tb);
        }
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
