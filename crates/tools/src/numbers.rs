//! Numbers written into the output files, byte for byte as `std`'s formatting writes them,
//! in a fraction of its time.
//!
//! - [`push_shortest`]: [`Num`]'s form (the shortest digits that read back to the same
//!   `f64`; exponent form past 1e9 or below 1e-9 in magnitude), the trajectory's CSV. The
//!   digits are `zmij`'s (Schubfach: the shortest, and of those the closest, as `std`'s
//!   Grisu with its Dragon fallback); only their layout is written here.
//! - [`push_fixed`]: `format!("{x:.p}")` for `p <= 9`, the plots' pixels and the 3-D view's
//!   poses. The exact binary value is scaled by `10^p` in 128-bit integers and rounded half
//!   to even, as `std` rounds, where `std` runs its exact digit generation.
//!
//! Measured (callgrind on `satsim run`, the rigid deployment at DP5(4)): the trajectory's CSV
//! rows 15.5 M → 6.6 M instructions, the plots 16.8 M → 7.1 M, the view's files 43.2 M →
//! 15.0 M, every output file the same bytes (`docs/src/engineering/reading-and-writing.md`).

use satsim_tree::error::Num;
use std::fmt::Write;

/// Appends `x` as `Num(x)` displays it.
pub(crate) fn push_shortest(out: &mut String, x: f64) {
    if !x.is_finite() {
        let _ = write!(out, "{}", Num(x));
        return;
    }
    if x == 0.0 {
        out.push_str(if x.is_sign_negative() { "-0" } else { "0" });
        return;
    }
    if may_tie(x) {
        let _ = write!(out, "{}", Num(x));
        return;
    }
    let mut buffer = zmij::Buffer::new();
    let text = buffer.format_finite(x);
    // `zmij` writes the plain form from 1e-5 to 1e16 (`.0` on a whole number), `d.ddde-n`
    // below (`{:e}`'s form) and `d.ddde+n` above. Where that is `Num`'s form it goes out as
    // it is; the exponents -6 to -9 are laid out plain from their digits; the rest (from
    // `1e9`, rare in a run's columns) goes through the digits' layout.
    let a = x.abs();
    if (1e-5..1e9).contains(&a) {
        out.push_str(text.strip_suffix(".0").unwrap_or(text));
        return;
    }
    if a < 1e-9 {
        out.push_str(text);
        return;
    }
    if a < 1e-5 && push_small(out, text) {
        return;
    }
    let d = Decimal::of(text);
    let (digits, point) = (d.digits(), d.point);
    if x < 0.0 {
        out.push('-');
    }
    if !(1e-9..1e9).contains(&x.abs()) {
        // `{:e}`: d.ddd, `e`, the exponent.
        out.push_str(&digits[..1]);
        if digits.len() > 1 {
            out.push('.');
            out.push_str(&digits[1..]);
        }
        out.push('e');
        out.push_str(itoa::Buffer::new().format(point));
    } else if point < 0 {
        // `{}` below 1: 0.000ddd.
        out.push_str("0.");
        for _ in 0..(-point - 1) {
            out.push('0');
        }
        out.push_str(digits);
    } else {
        // `{}` from 1: the whole part (zeros past the digits), then the fraction if any.
        let whole = point as usize + 1;
        if digits.len() <= whole {
            out.push_str(digits);
            for _ in digits.len()..whole {
                out.push('0');
            }
        } else {
            out.push_str(&digits[..whole]);
            out.push('.');
            out.push_str(&digits[whole..]);
        }
    }
}

/// Appends `zmij`'s `d.ddde-n`, `n` from 6 to 9, as `{}` writes it: `0.` and `n - 1` zeros
/// before the digits. Writes nothing and returns `false` for any other form.
fn push_small(out: &mut String, text: &str) -> bool {
    let (negative, t) = match text.strip_prefix('-') {
        Some(t) => (true, t),
        None => (false, text),
    };
    let b = t.as_bytes();
    let Some(&[e, minus, n]) = b.last_chunk::<3>() else {
        return false;
    };
    if e != b'e' || minus != b'-' || !(b'6'..=b'9').contains(&n) {
        return false;
    }
    let mantissa = &t[..t.len() - 3];
    if negative {
        out.push('-');
    }
    out.push_str("0.");
    out.push_str(&"00000000"[..usize::from(n - b'1')]);
    out.push_str(&mantissa[..1]);
    out.push_str(mantissa.get(2..).unwrap_or(""));
    true
}

/// `|x| = m 2^e` exactly, `m < 2^53` (finite `x`).
fn binary(x: f64) -> (u64, i32) {
    let bits = x.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let fraction = bits & ((1u64 << 52) - 1);
    if biased == 0 {
        (fraction, -1074)
    } else {
        (fraction | (1u64 << 52), biased - 1075)
    }
}

/// Whether two shortest digit strings may be equally close to `x`, where `zmij` (to even)
/// and `std` may choose differently (`-1.7631798335403773e15`: `std` the upper): only where `x`'s exact decimal value has 17 or 18
/// significant digits, the last a 5, halfway between two of 16 or 17 (fewer digits are
/// too far apart for both to read back to `x`). Those few go through `std`; so does any
/// `x` of 2^64 or more, which no output column reaches.
fn may_tie(x: f64) -> bool {
    let (m, e) = binary(x);
    // The exact value's significant digits as an integer `n` (no trailing zeros).
    let n: u128 = if e >= 0 {
        if e > 11 {
            return true;
        }
        let mut n = m << e;
        while n.is_multiple_of(10) {
            n /= 10;
        }
        n as u128
    } else {
        // m 2^-k = (m / 2^t) 5^(k - t) / 10^(k - t), t the trailing zero bits of m: the
        // digits of an odd number times 5^j, which is odd and so ends in no zero.
        let t = m.trailing_zeros() as i32;
        let j = -e - t;
        if j <= 0 {
            // An integer below 2^53: 16 digits at most.
            return false;
        }
        if j > 27 {
            // 5^28 > 10^19: 20 digits at least.
            return false;
        }
        (m >> t) as u128 * 5u128.pow(j as u32)
    };
    (10u128.pow(16)..10u128.pow(18)).contains(&n)
}

/// The significant digits of a finite non-zero number as `zmij` writes it (`-1.25e-7`,
/// `0.001`, `123.5`, `1e300`, `100.0`): the digits without leading or trailing zeros, and
/// the power of ten of the first (the number is `d.ddd × 10^point`).
struct Decimal {
    buf: [u8; 32],
    len: usize,
    point: i32,
}

impl Decimal {
    fn of(s: &str) -> Self {
        let b = s.as_bytes();
        let b = b.strip_prefix(b"-").unwrap_or(b);
        let (mantissa, exponent) = match b.iter().position(|&c| c == b'e') {
            Some(i) => (&b[..i], exponent_of(&b[i + 1..])),
            None => (b, 0),
        };
        let mut d = Decimal {
            buf: [0; 32],
            len: 0,
            point: exponent - 1,
        };
        let mut before_point = true;
        for &c in mantissa {
            if c == b'.' {
                before_point = false;
            } else if c == b'0' && d.len == 0 {
                // A leading zero: the first significant digit is one place further down.
                d.point -= i32::from(!before_point);
            } else {
                d.buf[d.len] = c;
                d.len += 1;
                d.point += i32::from(before_point);
            }
        }
        // Zeros of the whole part after its first digit count in `point` too (`100.0`).
        while d.len > 0 && d.buf[d.len - 1] == b'0' {
            d.len -= 1;
        }
        d
    }

    fn digits(&self) -> &str {
        std::str::from_utf8(&self.buf[..self.len]).expect("ASCII digits")
    }
}

/// The exponent `zmij` writes after its `e`: an optional sign and decimal digits.
fn exponent_of(b: &[u8]) -> i32 {
    let (negative, digits) = match b.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, b),
    };
    let v = digits
        .iter()
        .fold(0i32, |v, &c| v * 10 + i32::from(c - b'0'));
    if negative { -v } else { v }
}

/// Appends `format!("{x:.p}")`, `p <= 9`.
pub(crate) fn push_fixed(out: &mut String, x: f64, p: usize) {
    assert!(p <= 9, "push_fixed takes at most 9 decimals");
    match rounded(x, p) {
        Some((negative, whole, fraction)) => {
            if negative {
                out.push('-');
            }
            push_integer(out, whole);
            if p > 0 {
                out.push('.');
                push_padded(out, fraction, p);
            }
        }
        None => {
            let _ = write!(out, "{x:.p$}");
        }
    }
}

/// Appends `x` rounded to `p <= 9` decimals, without trailing zeros and with `-0` as `0`:
/// what `format!("{x:.p}")` trimmed of its zeros (and its point) gives.
pub(crate) fn push_fixed_trimmed(out: &mut String, x: f64, p: usize) {
    assert!(p <= 9, "push_fixed_trimmed takes at most 9 decimals");
    let Some((negative, whole, mut fraction)) = rounded(x, p) else {
        let start = out.len();
        let _ = write!(out, "{x:.p$}");
        if out[start..].contains('.') {
            let kept = out[start..]
                .trim_end_matches('0')
                .trim_end_matches('.')
                .len();
            out.truncate(start + kept);
        }
        if &out[start..] == "-0" {
            out.truncate(start);
            out.push('0');
        }
        return;
    };
    if negative && (whole != 0 || fraction != 0) {
        out.push('-');
    }
    push_integer(out, whole);
    if fraction != 0 {
        let mut places = p;
        while fraction.is_multiple_of(10) {
            fraction /= 10;
            places -= 1;
        }
        out.push('.');
        push_padded(out, fraction, places);
    }
}

/// `f` in `places` digits (at least), zeros in front.
fn push_padded(out: &mut String, f: u64, places: usize) {
    let mut buffer = itoa::Buffer::new();
    let digits = buffer.format(f);
    for _ in digits.len()..places {
        out.push('0');
    }
    out.push_str(digits);
}

fn push_integer(out: &mut String, v: u128) {
    match u64::try_from(v) {
        Ok(w) => out.push_str(itoa::Buffer::new().format(w)),
        Err(_) => out.push_str(itoa::Buffer::new().format(v)),
    }
}

const POW10: [u64; 10] = [
    1,
    10,
    100,
    1_000,
    10_000,
    100_000,
    1_000_000,
    10_000_000,
    100_000_000,
    1_000_000_000,
];

/// `x` rounded to `p` decimals as `std` rounds it (the exact binary value, half to even):
/// its sign, whole part and the `p` decimals as an integer. `None` where the value scaled by
/// `10^p` does not fit 128 bits, or `x` is not finite.
fn rounded(x: f64, p: usize) -> Option<(bool, u128, u64)> {
    if !x.is_finite() {
        return None;
    }
    let negative = x.is_sign_negative();
    let (m, e) = binary(x);
    let scale = POW10[p];
    if e >= 0 {
        // An integer: no decimals.
        if e > 128 - 53 {
            return None;
        }
        return Some((negative, (m as u128) << e, 0));
    }
    let k = (-e) as u32;
    let scaled = m as u128 * scale as u128; // < 2^83
    // n = round(m 2^-k 10^p), half to even.
    let n = if k >= 84 {
        // Below 2^-1: rounds to zero (2^83 / 2^84 = 1/2 is never reached).
        0
    } else {
        let q = scaled >> k;
        let r = scaled & ((1u128 << k) - 1);
        let half = 1u128 << (k - 1);
        if r > half || (r == half && q & 1 == 1) {
            q + 1
        } else {
            q
        }
    };
    // n < 2^83: its whole part and decimals.
    let (whole, decimals) = match u64::try_from(n) {
        Ok(n) => ((n / scale) as u128, n % scale),
        Err(_) => (n / scale as u128, (n % scale as u128) as u64),
    };
    Some((negative, whole, decimals))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic stream of 64-bit numbers (splitmix64).
    fn stream(mut seed: u64) -> impl FnMut() -> u64 {
        move || {
            seed = seed.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = seed;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }
    }

    /// Every kind of number the files see and the edges of the formats: any bit pattern,
    /// numbers of every magnitude from a few digits, dyadic fractions (the ties of
    /// rounding), the thresholds of the exponent form, and halfway points nudged by an ulp.
    fn samples() -> Vec<f64> {
        let mut next = stream(7);
        let mut v = vec![
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            1.5,
            2.5,
            0.125,
            0.375,
            -0.125,
            0.0009765625,
            1e-9,
            -1e-9,
            1e9,
            -1e9,
            999_999_999.999_999_9,
            1e-10,
            0.999_999_999_5,
            9.999_999_995,
            f64::MIN_POSITIVE,
            5e-324,
            f64::MAX,
            -f64::MAX,
            f64::EPSILON,
            1e300,
            1e-300,
            123456.5,
            1e8,
            -2.5e9,
            -2.5e-12,
            4503599627370496.5,
            9007199254740993.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        for _ in 0..100_000 {
            v.push(f64::from_bits(next()));
        }
        for _ in 0..100_000 {
            // A few significant digits at a power of ten from 1e-14 to 1e14.
            let digits = (next() % 100_000) as f64;
            let p = (next() % 29) as i32 - 14;
            let x = digits * 10f64.powi(p);
            v.push(if next().is_multiple_of(2) { x } else { -x });
        }
        for _ in 0..100_000 {
            // k / 2^n: exact ties at some number of decimals.
            let k = (next() % 1_000_000) as f64;
            let n = (next() % 40) as i32;
            v.push(k * 2f64.powi(-n) * if next().is_multiple_of(2) { 1.0 } else { -1.0 });
        }
        for _ in 0..200_000 {
            // Full-precision numbers of every magnitude from 1e-12 to 1e18, as a run's
            // states are, and the edges of `zmij`'s and `Num`'s forms and their neighbours.
            let p = (next() % 31) as i32 - 12;
            let x = (1.0 + (next() >> 11) as f64 / (1u64 << 53) as f64 * 9.0) * 10f64.powi(p);
            v.push(if next().is_multiple_of(2) { x } else { -x });
        }
        for edge in [1e-9f64, 1e-5, 1e9, 1e16] {
            let mut x = edge;
            for _ in 0..4 {
                x = x.next_down();
            }
            for _ in 0..9 {
                v.extend([x, -x]);
                x = x.next_up();
            }
        }
        for _ in 0..50_000 {
            // Halfway points of 2 and 9 decimals, and their neighbours.
            let p = if next().is_multiple_of(2) { 2 } else { 9 };
            let n = (next() % 10_000_000_000) as f64;
            let x = (n + 0.5) / 10f64.powi(p);
            v.extend([x, x.next_up(), x.next_down()]);
        }
        v
    }

    #[test]
    fn shortest_is_nums_display() {
        let mut out = String::new();
        for x in samples() {
            out.clear();
            push_shortest(&mut out, x);
            assert_eq!(out, Num(x).to_string(), "{x:e} ({:#x})", x.to_bits());
        }
    }

    #[test]
    fn numbers_from_1e_9_to_1e_5_take_the_short_layout() {
        let mut out = String::new();
        let small = samples()
            .into_iter()
            .filter(|x| (1e-9..1e-5).contains(&x.abs()));
        let mut n = 0;
        for x in small {
            out.clear();
            let mut buffer = zmij::Buffer::new();
            assert!(push_small(&mut out, buffer.format_finite(x)), "{x:e}");
            n += 1;
        }
        assert!(n > 10_000, "{n} samples");
    }

    #[test]
    fn fixed_is_stds_to_the_byte() {
        let mut out = String::new();
        for x in samples() {
            for p in [0, 1, 2, 4, 6, 9] {
                out.clear();
                push_fixed(&mut out, x, p);
                assert_eq!(out, format!("{x:.p$}"), "{x:e} ({:#x}) to {p}", x.to_bits());
            }
        }
    }

    #[test]
    fn fixed_trimmed_drops_the_zeros_and_the_sign_of_zero() {
        let mut out = String::new();
        for x in samples() {
            for p in [2, 9] {
                let std = format!("{x:.p$}");
                let std = if std.contains('.') {
                    std.trim_end_matches('0').trim_end_matches('.')
                } else {
                    &std
                };
                let std = if std == "-0" { "0" } else { std };
                out.clear();
                push_fixed_trimmed(&mut out, x, p);
                assert_eq!(out, std, "{x:e} ({:#x}) to {p}", x.to_bits());
            }
        }
        for (x, text) in [
            (1.0, "1"),
            (-0.0000000001, "0"),
            (0.1, "0.1"),
            (-2.5, "-2.5"),
            (1e20, "100000000000000000000"),
            (0.0009765625, "0.000976562"),
        ] {
            out.clear();
            push_fixed_trimmed(&mut out, x, 9);
            assert_eq!(out, text);
        }
    }
}
