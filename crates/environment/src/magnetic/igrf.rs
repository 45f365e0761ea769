//! IGRF-14: the geocentric spherical-harmonic synthesis of the main field to degree 13
//! (Schmidt semi-normalised associated Legendre functions, reference radius 6371.2 km), its
//! Gauss coefficients linear in time between the 5-yearly models and, after 2025, along the
//! 2025-2030 secular variation (Alken et al. 2021, "International Geomagnetic Reference
//! Field: the thirteenth generation", section 2; IGRF-14 has the same form).
//!
//! The Legendre functions come from the standard recursions in degree; for the east
//! component, which divides `P_n^m` by sin θ, the same recursions run on `P_n^m / sin θ`
//! seeded with `sin^(m−1) θ`, and the θ derivatives come from the recursions differentiated:
//! no division by sin θ anywhere, so the poles are ordinary points.

use crate::Vec3;
use std::sync::OnceLock;

/// The reference radius a (m).
pub(super) const A_REF: f64 = 6_371_200.0;
/// The highest degree.
const N_MAX: usize = 13;
/// The models' epochs: 1900.0, 1905.0, …, 2025.0.
const MODELS: usize = 26;
/// The first model's year.
pub(super) const FIRST_YEAR: f64 = 1900.0;
/// The end of IGRF-14's span.
pub(super) const LAST_YEAR: f64 = 2030.0;
/// The official coefficient table (IAGA V-MOD), nT and nT/year.
const COEFFS: &str = include_str!("../../data/igrf14coeffs.txt");

/// Coefficients by `[n][m]`.
type Coeffs = [[f64; N_MAX + 1]; N_MAX + 1];

/// The parsed table: each model's g and h, and their rate of change (nT/year) over the five
/// years that follow it (the secular variation for the last).
pub(super) struct Table {
    g: [Coeffs; MODELS],
    h: [Coeffs; MODELS],
    g_rate: [Coeffs; MODELS],
    h_rate: [Coeffs; MODELS],
    /// The recursion's factors (see [`Table::field`]): `k1[n][m] = (2n−1)/sqrt(n²−m²)`,
    /// `k2[n][m] = sqrt(((n−1)²−m²)/(n²−m²))`, `k1[m][m] = sqrt((2m−1)/2m)` (sectoral).
    k1: Coeffs,
    k2: Coeffs,
}

/// The table, parsed at the first call.
pub(super) fn table() -> Result<&'static Table, String> {
    static TABLE: OnceLock<Result<Box<Table>, String>> = OnceLock::new();
    TABLE
        .get_or_init(|| parse(COEFFS))
        .as_ref()
        .map(|t| &**t)
        .map_err(|e| format!("data/igrf14coeffs.txt: {e}"))
}

/// Reads the table's `g`/`h` rows: `g n m`, then 26 models (1900.0 to 2025.0), then the
/// secular variation.
fn parse(text: &str) -> Result<Box<Table>, String> {
    let zero = [[0.0; N_MAX + 1]; N_MAX + 1];
    let mut t = Box::new(Table {
        g: [zero; MODELS],
        h: [zero; MODELS],
        g_rate: [zero; MODELS],
        h_rate: [zero; MODELS],
        k1: zero,
        k2: zero,
    });
    for m in 0..=N_MAX {
        t.k1[m][m] = ((2 * m) as f64 - 1.0).max(0.0).sqrt() / ((2 * m) as f64).max(1.0).sqrt();
        for n in (m + 1)..=N_MAX {
            let nm = (n * n - m * m) as f64;
            t.k1[n][m] = (2 * n - 1) as f64 / nm.sqrt();
            t.k2[n][m] = (((n - 1) * (n - 1) - m * m) as f64 / nm).sqrt();
        }
    }
    let (mut sv_g, mut sv_h) = (zero, zero);
    let mut rows = 0;
    let mut header = false;
    for (i, line) in text.lines().enumerate() {
        let mut fields = line.split_whitespace();
        let kind = fields.next();
        if kind == Some("g/h") {
            // `g/h n m 1900.0 1905.0 … 2025.0 2025-30`: the columns this parser assumes.
            let years: Vec<&str> = fields.skip(2).collect();
            let expected: Vec<String> = (0..MODELS)
                .map(|k| format!("{:.1}", FIRST_YEAR + 5.0 * k as f64))
                .collect();
            if years.len() != MODELS + 1 || years[..MODELS] != expected[..] {
                return Err(format!(
                    "line {}: models {years:?}, expected {expected:?} then the SV",
                    i + 1
                ));
            }
            header = true;
            continue;
        }
        let is_g = match kind {
            Some("g") => true,
            Some("h") => false,
            _ => continue,
        };
        let bad = |what: &str| format!("line {}: {what}: `{line}`", i + 1);
        let mut int = || -> Result<usize, String> {
            fields
                .next()
                .and_then(|x| x.parse().ok())
                .ok_or_else(|| bad("no degree/order"))
        };
        let (n, m) = (int()?, int()?);
        if n == 0 || n > N_MAX || m > n || (!is_g && m == 0) {
            return Err(bad("degree/order out of range"));
        }
        let values = fields
            .map(|x| x.parse::<f64>().map_err(|_| bad("not a number")))
            .collect::<Result<Vec<f64>, String>>()?;
        if values.len() != MODELS + 1 {
            return Err(bad("expected 26 models and the SV"));
        }
        let (models, sv) = if is_g {
            (&mut t.g, &mut sv_g)
        } else {
            (&mut t.h, &mut sv_h)
        };
        for (k, v) in values[..MODELS].iter().enumerate() {
            models[k][n][m] = *v;
        }
        sv[n][m] = values[MODELS];
        rows += 1;
    }
    // Every (n, m) of g (n = 1..13, m = 0..n: 104) and of h (m >= 1: 91).
    if !header || rows != 195 {
        return Err(format!(
            "{rows} coefficient rows (header found: {header}), expected 195"
        ));
    }
    for k in 0..MODELS {
        for n in 1..=N_MAX {
            for m in 0..=n {
                (t.g_rate[k][n][m], t.h_rate[k][n][m]) = if k + 1 < MODELS {
                    (
                        (t.g[k + 1][n][m] - t.g[k][n][m]) / 5.0,
                        (t.h[k + 1][n][m] - t.h[k][n][m]) / 5.0,
                    )
                } else {
                    (sv_g[n][m], sv_h[n][m])
                };
            }
        }
    }
    Ok(t)
}

impl Table {
    /// The model before `year` and the years since it (before 1900: 1900's model).
    pub(super) fn interval(year: f64) -> (usize, f64) {
        let k = ((year - FIRST_YEAR) / 5.0)
            .floor()
            .clamp(0.0, (MODELS - 1) as f64) as usize;
        let since = (year - (FIRST_YEAR + 5.0 * k as f64)).max(0.0);
        (k, since)
    }

    /// (g10, g11, h11) at `year` (nT).
    pub(super) fn degree_one(&self, year: f64) -> [f64; 3] {
        let (k, dt) = Self::interval(year);
        let g = |m: usize| self.g[k][1][m] + self.g_rate[k][1][m] * dt;
        let h11 = self.h[k][1][1] + self.h_rate[k][1][1] * dt;
        [g(0), g(1), h11]
    }

    /// The field (nT, Earth-fixed Cartesian axes) at the Earth-fixed position `r` (m) at the
    /// decimal year `year`.
    pub(super) fn field(&self, year: f64, r: &Vec3) -> Vec3 {
        let (k, dt) = Self::interval(year);
        let (g, h, gr, hr) = (&self.g[k], &self.h[k], &self.g_rate[k], &self.h_rate[k]);
        let basis = self.basis(r);
        basis.sum(|n, m| (g[n][m] + gr[n][m] * dt, h[n][m] + hr[n][m] * dt))
    }

    /// The model `k` (of [`Table::interval`]) at the Earth-fixed `r` (m): its field (nT) at
    /// its epoch and its rate (nT/year), Earth-fixed Cartesian axes; the field at `dt` years
    /// after the epoch is the first plus `dt` times the second.
    pub(super) fn model_and_rate(&self, k: usize, r: &Vec3) -> [Vec3; 2] {
        let (g, h, gr, hr) = (&self.g[k], &self.h[k], &self.g_rate[k], &self.h_rate[k]);
        let basis = self.basis(r);
        [
            basis.sum(|n, m| (g[n][m], h[n][m])),
            basis.sum(|n, m| (gr[n][m], hr[n][m])),
        ]
    }

    /// The Legendre functions and the angles at `r`.
    fn basis(&self, r: &Vec3) -> Basis {
        let rho = r.x.hypot(r.y);
        let d = rho.hypot(r.z);
        // Colatitude θ and longitude φ; on the axis φ = 0 (any φ would do: the components
        // are taken back to Cartesian axes with the same φ).
        let (st, ct) = (rho / d, r.z / d);
        let (sp, cp) = if rho > 0.0 {
            (r.y / rho, r.x / rho)
        } else {
            (0.0, 1.0)
        };

        // p[n][m] = P_n^m(cos θ), q[n][m] = P_n^m / sin θ (m >= 1), dp[n][m] = dP_n^m/dθ.
        let mut p = [[0.0; N_MAX + 1]; N_MAX + 1];
        let mut q = [[0.0; N_MAX + 1]; N_MAX + 1];
        let mut dp = [[0.0; N_MAX + 1]; N_MAX + 1];
        p[0][0] = 1.0;
        for m in 0..=N_MAX {
            if m >= 1 {
                // Sectoral: P_1^1 = sin θ, P_m^m = sqrt((2m−1)/2m) sin θ P_{m−1}^{m−1}.
                q[m][m] = if m == 1 {
                    1.0
                } else {
                    self.k1[m][m] * st * q[m - 1][m - 1]
                };
                p[m][m] = st * q[m][m];
                dp[m][m] = m as f64 * ct * q[m][m];
            }
            // P_n^m = ((2n−1) cos θ P_{n−1}^m − sqrt((n−1)²−m²) P_{n−2}^m) / sqrt(n²−m²).
            for n in (m + 1)..=N_MAX {
                let (k1, k2) = (self.k1[n][m], self.k2[n][m]);
                let (p2, q2, d2) = if n >= m + 2 {
                    (p[n - 2][m], q[n - 2][m], dp[n - 2][m])
                } else {
                    (0.0, 0.0, 0.0)
                };
                p[n][m] = k1 * ct * p[n - 1][m] - k2 * p2;
                q[n][m] = k1 * ct * q[n - 1][m] - k2 * q2;
                dp[n][m] = k1 * (ct * dp[n - 1][m] - st * p[n - 1][m]) - k2 * d2;
            }
        }
        Basis {
            p,
            q,
            dp,
            d,
            st,
            ct,
            sp,
            cp,
        }
    }
}

/// The Legendre functions at a position (see [`Table::basis`]), its distance and the sines
/// and cosines of its colatitude and longitude.
struct Basis {
    p: Coeffs,
    q: Coeffs,
    dp: Coeffs,
    d: f64,
    st: f64,
    ct: f64,
    sp: f64,
    cp: f64,
}

impl Basis {
    /// The field (nT, Earth-fixed Cartesian axes) of the Gauss coefficients `gh(n, m)`.
    fn sum(&self, gh: impl Fn(usize, usize) -> (f64, f64)) -> Vec3 {
        let (p, q, dp) = (&self.p, &self.q, &self.dp);
        let (st, ct, sp, cp) = (self.st, self.ct, self.sp, self.cp);
        // B = −∇V, V = a Σ (a/r)^(n+1) Σ (g cos mφ + h sin mφ) P_n^m.
        let (mut b_r, mut b_t, mut b_p) = (0.0, 0.0, 0.0);
        let ratio = A_REF / self.d;
        let mut rn = ratio * ratio; // (a/r)^(n+2), from n = 0
        for n in 1..=N_MAX {
            rn *= ratio;
            let (mut cm, mut sm) = (1.0, 0.0); // cos mφ, sin mφ
            let (mut sum_r, mut sum_t, mut sum_p) = (0.0, 0.0, 0.0);
            for m in 0..=n {
                let (gnm, hnm) = gh(n, m);
                let c = gnm * cm + hnm * sm;
                sum_r += c * p[n][m];
                sum_t += c * dp[n][m];
                sum_p += m as f64 * (gnm * sm - hnm * cm) * q[n][m];
                (cm, sm) = (cm * cp - sm * sp, sm * cp + cm * sp);
            }
            b_r += (n + 1) as f64 * rn * sum_r;
            b_t -= rn * sum_t;
            b_p += rn * sum_p;
        }
        // B_r r̂ + B_θ θ̂ + B_φ φ̂.
        let r_hat = Vec3::new(st * cp, st * sp, ct);
        let t_hat = Vec3::new(ct * cp, ct * sp, -st);
        let p_hat = Vec3::new(-sp, cp, 0.0);
        r_hat * b_r + t_hat * b_t + p_hat * b_p
    }
}
