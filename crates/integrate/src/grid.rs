//! Evenly spaced instants `origin + k · step` as the decimals they were written as: the
//! output interval's rows, the fixed-step grid, a sampled law's or sensor's clock.
//!
//! `3.0 * 0.1` is `0.30000000000000004`, one unit in the last place above the double nearest
//! to 0.3 (`0.1` is a little above a tenth, and the product rounds up), and so is every
//! third row time of an output interval of `0.1` computed that way. `30.0 * 0.01` rounds to
//! `0.3` itself. The two clocks then meet at different doubles: a fixed-step run with rows
//! every `0.1 s` on a `0.01 s` step, or with a law sampled at 10 Hz, took a sliver step of
//! `5.6e-17 s` to land on each such row or sample, 482 extra steps over 300 s (4 right-hand
//! sides each for RK4), and its rows read `0.30000000000000004`. Here the `k`-th instant is
//! the double nearest to the exact decimal `origin + k · step` when `origin` and `step` are
//! short decimals (at most 15 significant digits, as written in a scene): `0.3`, the same
//! double from either clock. Otherwise, or where the decimal's digits pass `2^53`, it is
//! the product, as before.

/// The instants `origin + k · step`, `k = 0, 1, …`, each the double nearest to the exact
/// decimal where `origin` and `step` have short decimal forms.
///
/// ```
/// use satsim_integrate::DecimalGrid;
/// let rows = DecimalGrid::new(0.0, 0.1);
/// assert_eq!(rows.point(3.0), 0.3); // not 3.0 * 0.1 = 0.30000000000000004
/// assert_eq!(rows.point(3.0), DecimalGrid::new(0.0, 0.01).point(30.0));
/// assert_eq!(DecimalGrid::new(0.0, 1.0 / 3.0).point(3.0), 3.0 * (1.0 / 3.0));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DecimalGrid {
    origin: f64,
    step: f64,
    /// `origin = o / 10^d` and `step = p / 10^d` exactly as decimals, `o` and `p` integers
    /// below `2^53` (`None`: not short decimals, the product is used).
    decimal: Option<Decimal>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Decimal {
    o: f64,
    p: f64,
    /// `10^d`, exact (`d <= 22`).
    scale: f64,
}

/// Integers below this are exact doubles, and so are their sums of smaller ones.
const EXACT: f64 = 9_007_199_254_740_992.0; // 2^53

impl DecimalGrid {
    /// The grid from `origin` with spacing `step` (both finite).
    pub fn new(origin: f64, step: f64) -> Self {
        let decimal = match (short_decimal(origin), short_decimal(step)) {
            (Some((o, eo)), Some((p, ep))) => {
                // Both over the finer power of ten.
                let d = eo.max(ep);
                let widen = |n: u64, e: i32| n.checked_mul(10u64.checked_pow((d - e) as u32)?);
                match (widen(o, eo), widen(p, ep)) {
                    (Some(o_n), Some(p_n)) if (o_n as f64) < EXACT && (p_n as f64) < EXACT => {
                        Some(Decimal {
                            o: (o_n as f64).copysign(origin),
                            p: (p_n as f64).copysign(step),
                            scale: 10f64.powi(d),
                        })
                    }
                    _ => None,
                }
            }
            _ => None,
        };
        Self {
            origin,
            step,
            decimal,
        }
    }

    /// The origin.
    pub fn origin(&self) -> f64 {
        self.origin
    }

    /// The spacing.
    pub fn step(&self) -> f64 {
        self.step
    }

    /// The first instant after `t`, one within `slack` steps past `t` skipped (so that a
    /// time met within round-off moves on), computed from its index, never accumulated.
    pub fn next_after(&self, t: f64, slack: f64) -> f64 {
        self.point(((t - self.origin) / self.step + slack).floor() + 1.0)
    }

    /// The `k`-th instant (`k` a whole number): the double nearest to `origin + k · step`
    /// as decimals, else `origin + k · step` in doubles.
    pub fn point(&self, k: f64) -> f64 {
        if let Some(Decimal { o, p, scale }) = self.decimal {
            // `k p` and `o + k p` are exact while below 2^53, and one correctly rounded
            // division by the exact `10^d` gives the nearest double.
            let n = o + k * p;
            if n.abs() < EXACT && (k * p).abs() < EXACT {
                return n / scale;
            }
        }
        self.origin + k * self.step
    }
}

/// `x = n / 10^d` as decimals, `n` an integer of at most 15 digits and `d <= 22` (so that
/// `10^d` is an exact double), the least such `d`; `None` for anything else (a step of
/// `1/3` or `π`, or one too fine or too large to be exact). `n / 10^d`, one correctly rounded
/// division of exact doubles, is the double nearest to the decimal: where it is `x`, that
/// decimal reads back to `x`. Arithmetic only (no formatting): the stepping API makes a grid
/// where it reads a row's time.
fn short_decimal(x: f64) -> Option<(u64, i32)> {
    if !x.is_finite() {
        return None;
    }
    let a = x.abs();
    for d in 0..=22 {
        // Exact: every power up to 10^22 is a double, and so is each product on the way.
        let scale = 10f64.powi(d);
        let n = (a * scale).round();
        if n >= 1e15 {
            return None;
        }
        if n / scale == a {
            return Some((n as u64, d));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact decimal `k·p / 10^d` rounded to the nearest double, independently: the
    /// shortest form of the nearest double to a decimal written out is the decimal itself.
    fn nearest(text: &str) -> f64 {
        text.parse().expect("a decimal")
    }

    #[test]
    fn each_point_is_the_double_nearest_to_its_decimal() {
        let g = DecimalGrid::new(0.0, 0.1);
        for k in 0..3000u32 {
            let text = format!("{}.{}", k / 10, k % 10);
            assert_eq!(g.point(f64::from(k)), nearest(&text), "k = {k}");
        }
        // Where the product is off: k = 3 (0.30000000000000004), 1013 of these 3000.
        let off = (0..3000u32)
            .filter(|&k| f64::from(k) * 0.1 != g.point(f64::from(k)))
            .count();
        assert_eq!(off, 1013);
        let g = DecimalGrid::new(2.5, 0.01);
        for k in 0..30_000u32 {
            let hundredths = 250 + k;
            let text = format!("{}.{:02}", hundredths / 100, hundredths % 100);
            assert_eq!(g.point(f64::from(k)), nearest(&text), "k = {k}");
        }
    }

    #[test]
    fn two_clocks_meet_where_their_decimals_do() {
        let (rows, steps) = (DecimalGrid::new(0.0, 0.1), DecimalGrid::new(0.0, 0.01));
        for k in 0..3000 {
            assert_eq!(
                rows.point(k as f64),
                steps.point(10.0 * k as f64),
                "k = {k}"
            );
        }
        // The products: 482 of them differ, each a sliver step for a fixed-step run.
        let apart = (0..3000)
            .filter(|&k| k as f64 * 0.1 != (10 * k) as f64 * 0.01)
            .count();
        assert_eq!(apart, 482);
    }

    #[test]
    fn other_numbers_keep_the_product() {
        for (origin, step) in [
            (0.0, 1.0 / 3.0),
            (0.1 + 0.2, 0.1),
            (0.0, std::f64::consts::PI),
            (0.0, 1e-30),
            (1e300, 1.0),
        ] {
            let g = DecimalGrid::new(origin, step);
            assert_eq!(g.decimal, None, "{origin} {step}");
            for k in [0.0, 1.0, 7.0, 1e6] {
                assert_eq!(g.point(k), origin + k * step);
            }
        }
        // Past 2^53 in the decimal's digits: the product again.
        let g = DecimalGrid::new(0.0, 0.123456789012345);
        assert!(g.decimal.is_some());
        assert_eq!(g.point(1e6), 1e6 * 0.123456789012345);
    }

    #[test]
    fn the_next_instant_skips_one_within_the_slack() {
        let g = DecimalGrid::new(0.0, 0.01);
        assert_eq!(g.next_after(0.3, 1e-9), 0.31);
        assert_eq!(g.next_after(0.29, 1e-9), 0.3);
        // 0.3 − 1e-13 is within 1e-9 steps of 0.3: the point after it is 0.31.
        assert_eq!(g.next_after(0.3 - 1e-13, 1e-9), 0.31);
        assert_eq!(g.next_after(0.3 - 1e-6, 1e-9), 0.3);
        // The grid goes on below its origin.
        assert_eq!(g.next_after(-1.0, 1e-9), -0.99);
    }

    #[test]
    fn signs_large_steps_and_whole_numbers() {
        let g = DecimalGrid::new(-1.5, 0.25);
        assert_eq!(g.point(0.0), -1.5);
        assert_eq!(g.point(6.0), 0.0);
        assert_eq!(g.point(7.0), 0.25);
        let g = DecimalGrid::new(0.0, 2.5e3);
        assert_eq!(g.point(3.0), 7500.0);
        let g = DecimalGrid::new(10.0, -0.1);
        assert_eq!(g.point(3.0), 9.7);
        assert_eq!(short_decimal(0.1), Some((1, 1)));
        assert_eq!(short_decimal(120.0), Some((120, 0)));
        assert_eq!(short_decimal(1.0 / 3.0), None);
        assert_eq!(short_decimal(0.0), Some((0, 0)));
        assert_eq!(short_decimal(0.30000000000000004), None);
        assert_eq!(short_decimal(1e-22), Some((1, 22)));
        assert_eq!(short_decimal(1e-23), None);
        assert_eq!(short_decimal(123456789012345.0), Some((123456789012345, 0)));
        assert_eq!(short_decimal(1e15), None);
        // The least `d` is the shortest form's: as `{:e}` writes the digits.
        for x in [
            0.1,
            0.25,
            2.5e3,
            0.001,
            12.75,
            0.123456789012345,
            7e-9,
            86400.0,
        ] {
            let (n, d) = short_decimal(x).unwrap();
            let text = format!("{:e}", x);
            let (mantissa, exponent) = text.split_once('e').unwrap();
            let digits = mantissa.replace('.', "");
            let shift = exponent.parse::<i32>().unwrap() - (digits.len() as i32 - 1);
            let (want_n, want_d) = if shift >= 0 {
                (digits.parse::<u64>().unwrap() * 10u64.pow(shift as u32), 0)
            } else {
                (digits.parse::<u64>().unwrap(), -shift)
            };
            assert_eq!((n, d), (want_n, want_d), "{x}");
        }
    }
}
