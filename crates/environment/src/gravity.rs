//! The Earth's gravity as a spherical-harmonic series (EGM2008, shipped to degree and order
//! 70), and the point-mass perturbations of third bodies (the Sun, the Moon).
//!
//! # The harmonic field
//!
//! The potential, in the Earth-fixed frame (ITRF), with fully normalised coefficients
//! `C̄nm`, `S̄nm` and associated Legendre functions `P̄nm` (geodesy's normalisation,
//! `∫ P̄nm² cos²(mλ) dσ = 4π`, no Condon-Shortley phase):
//!
//! `U = GM/r Σn Σm (a/r)^n P̄nm(sin φ) (C̄nm cos mλ + S̄nm sin mλ)`.
//!
//! The acceleration is evaluated without angles or divisions by cos φ, by Cunningham's
//! recursion (Montenbruck & Gill, Satellite Orbits, section 3.2.4, eqs. 3.29-3.33) for the
//! solid harmonics `V̄nm + i W̄nm = N_nm (a/r)^(n+1) P_nm(sin φ) e^(imλ)`, each scaled by its
//! normalisation `N_nm = sqrt((2 − δ_m0)(2n + 1)(n − m)!/(n + m)!)`: the sectoral terms from
//! `V̄mm = f_m (x₀ V̄(m−1)(m−1) − y₀ W̄(m−1)(m−1))` (`f_1 = √3`, `f_m = sqrt((2m + 1)/2m)`), the
//! columns from the standard normalised recursion `V̄nm = α_nm z₀ V̄(n−1)m − β_nm ρ V̄(n−2)m`
//! with `α_nm = sqrt((2n + 1)(2n − 1)/((n − m)(n + m)))` and
//! `β_nm = sqrt((2n + 1)(n + m − 1)(n − m − 1)/((2n − 3)(n + m)(n − m)))` (`x₀ = a x/r²`,
//! `ρ = a²/r²`). Normalised, the terms stay of order one to any degree (the unnormalised
//! ones reach 10^±119 at degree 70), and the recursions are the stable forward ones. The
//! acceleration is Montenbruck & Gill's eq. 3.33 with each `C_nm V_(n+1)k` written
//! `C̄nm V̄(n+1)k · N_nm / N_(n+1)k`; those ratios and the recursion's factors are computed
//! once per field. Degree 0 is `−GM r/r³` (C̄00 = 1); degree 1 is zero (the frame's origin is
//! the centre of mass).
//!
//! # The coefficients
//!
//! `data/egm2008_70.gfc`: EGM2008 (Pavlis et al. 2012; NGA, public domain), tide-free, fully
//! normalised, GM = 3.986004415e14 m³/s², a = 6 378 136.3 m, truncated to degree and order 70
//! from the degree-120 file that the `brahe` package (1.8.0, MIT) ships; `data/README.md`
//! tells how it was made.
//!
//! # The lattice a run reads
//!
//! A series to degree 20 costs a few microseconds a call, the most of a right-hand side, so a
//! run reads it through [`HarmonicLattice`]: the central term and J2 (`C̄20`) in closed form at
//! every call, the rest (the non-zonal degree-2 terms and degrees 3 up) on the Earth-fixed
//! [`Lattice`] of [`LATTICE_DEG`] (1 degree; radial step a quarter of it at the ground,
//! 27.8 km), interpolated trilinearly in its Cartesian components. Along one orbit at 500 km
//! (inclined 51.6 degrees, and polar; a call every 0.5 s), EGM2008 20x20 (the rest up to
//! 3.1e-4 m/s²):
//!
//! | spacing | largest error | RMS error |
//! |---|---|---|
//! | 0.5 deg | 2.0e-7 m/s² | 5.8e-8 m/s² |
//! | 1 deg (default) | 8.0e-7 m/s² | 2.4e-7 m/s² |
//! | 2 deg | 3.2e-6 m/s² | 9.1e-7 m/s² |
//! | 3 deg | 6.6e-6 m/s² | 2.1e-6 m/s² |
//!
//! against the terms of degrees 21 to 30 that a 20x20 field leaves out: up to 4.9e-5 m/s²,
//! RMS 1.3e-5 m/s² on the same orbits. At 1 degree the lattice's error is 1.6 % of the
//! truncation's at worst. The cost on a warm lattice, its fills (4 nodes at a face, 2180 an
//! orbit at 1 degree) included: 207 ns a call with a call every 0.1 s, 566 ns every 0.5 s,
//! against 2.7-3.2 µs for the series (release build, a loaded 2-core machine; the rotation
//! [`gcrf_to_itrf`] adds 0.7-0.8 µs to either). Each node's value depends only on its indices,
//! so a run's results do not depend on the order of the calls. The numbers:
//! `cargo test -p satsim-environment --release --test it -- --ignored --nocapture lattice_`;
//! `tests/it/lattice.rs` asserts the bound. [`HarmonicField`] itself stays the exact series.
//!
//! # Third bodies
//!
//! A body of gravitational parameter `μ_b` at `r_b` from the Earth's centre pulls the
//! spacecraft (at `r`) and the Earth differently; in the Earth-centred frame the difference
//! is `μ_b [(r_b − r)/|r_b − r|³ − r_b/|r_b|³]` ([`third_body_acceleration`], evaluated in
//! Battin's form, which keeps its digits where `|r| ≪ |r_b|`).

use crate::earth::gcrf_to_itrf;
use crate::lattice::Lattice;
use crate::{Epoch, Vec3};
use std::sync::{Arc, OnceLock};

/// The Sun's gravitational parameter (m³/s², IAU 2015 nominal GM☉ in TDB units, the DE430
/// value 1.32712440041e20 to 1e-11).
pub const MU_SUN: f64 = 1.327_124_4e20;
/// The Moon's gravitational parameter (m³/s², DE430: 4902.800066 km³/s²).
pub const MU_MOON: f64 = 4.902_800_066e12;
/// The highest degree shipped (and the highest a field accepts).
pub const MAX_DEGREE: usize = 70;

/// The EGM2008 coefficient file, truncated to degree and order [`MAX_DEGREE`].
const EGM2008: &str = include_str!("../data/egm2008_70.gfc");

/// A spherical-harmonic model's coefficients: its GM, reference radius and fully normalised
/// `C̄nm`, `S̄nm` to its highest degree.
#[derive(Clone, Debug, PartialEq)]
pub struct Coefficients {
    /// The model's name.
    pub name: String,
    /// GM (m³/s²).
    pub gm: f64,
    /// The reference radius a (m).
    pub radius: f64,
    /// The highest degree held.
    pub max_degree: usize,
    /// `C̄nm` at `n (n + 1)/2 + m`.
    c: Vec<f64>,
    /// `S̄nm` at `n (n + 1)/2 + m`.
    s: Vec<f64>,
}

/// The index of `(n, m)` in a triangular table.
fn tri(n: usize, m: usize) -> usize {
    n * (n + 1) / 2 + m
}

impl Coefficients {
    /// Coefficients from a function `(n, m) -> (C̄nm, S̄nm)` for `0 <= m <= n <= max_degree`
    /// (fully normalised; degree 0 and 1 are taken as `C̄00 = 1` and zero whatever it says).
    pub fn from_fn(
        name: &str,
        gm: f64,
        radius: f64,
        max_degree: usize,
        f: impl Fn(usize, usize) -> (f64, f64),
    ) -> Self {
        let len = tri(max_degree + 1, 0);
        let (mut c, mut s) = (vec![0.0; len], vec![0.0; len]);
        for n in 2..=max_degree {
            for m in 0..=n {
                (c[tri(n, m)], s[tri(n, m)]) = f(n, m);
            }
        }
        c[0] = 1.0;
        Self {
            name: name.to_owned(),
            gm,
            radius,
            max_degree,
            c,
            s,
        }
    }

    /// `(C̄nm, S̄nm)`, zero beyond the highest degree.
    pub fn get(&self, n: usize, m: usize) -> (f64, f64) {
        if m > n || n > self.max_degree {
            return (0.0, 0.0);
        }
        (self.c[tri(n, m)], self.s[tri(n, m)])
    }

    /// Reads an ICGEM `.gfc` file (fully normalised; `gfc n m C S [σC σS]` rows after
    /// `end_of_head`; Fortran `d` exponents allowed), to `max_degree`.
    pub fn parse_gfc(text: &str, max_degree: usize) -> Result<Self, String> {
        let (mut name, mut gm, mut radius) = (String::new(), None, None);
        let mut lines = text.lines().enumerate();
        let number = |s: &str| s.replace(['d', 'D'], "e").parse::<f64>();
        for (_, line) in lines.by_ref() {
            let mut f = line.split_whitespace();
            match (f.next(), f.next()) {
                (Some("modelname"), Some(v)) => name = v.to_owned(),
                (Some("earth_gravity_constant"), Some(v)) => gm = number(v).ok(),
                (Some("radius"), Some(v)) => radius = number(v).ok(),
                (Some("norm"), Some(v)) if v != "fully_normalized" => {
                    return Err(format!("`norm {v}`: only fully normalised files are read"));
                }
                (Some("end_of_head"), _) => break,
                _ => {}
            }
        }
        let (Some(gm), Some(radius)) = (gm, radius) else {
            return Err("the header gives no `earth_gravity_constant` or `radius`".into());
        };
        let len = tri(max_degree + 1, 0);
        let (mut c, mut s) = (vec![0.0; len], vec![0.0; len]);
        let mut seen = vec![false; len];
        for (i, line) in lines {
            let f: Vec<&str> = line.split_whitespace().collect();
            if f.is_empty() {
                continue;
            }
            let bad = || format!("line {}: expected `gfc n m C S ...`", i + 1);
            if f[0] != "gfc" || f.len() < 5 {
                return Err(bad());
            }
            let (n, m) = match (f[1].parse::<usize>(), f[2].parse::<usize>()) {
                (Ok(n), Ok(m)) if m <= n => (n, m),
                _ => return Err(bad()),
            };
            if n > max_degree {
                continue;
            }
            let (Ok(cv), Ok(sv)) = (number(f[3]), number(f[4])) else {
                return Err(bad());
            };
            (c[tri(n, m)], s[tri(n, m)], seen[tri(n, m)]) = (cv, sv, true);
        }
        // Every term from degree 2 up must be there (degree 1 is zero by the origin).
        for n in 2..=max_degree {
            for m in 0..=n {
                if !seen[tri(n, m)] {
                    return Err(format!("no coefficients for degree {n}, order {m}"));
                }
            }
        }
        if c[0] != 1.0 || c[1..3].iter().chain(&s[..3]).any(|v| *v != 0.0) {
            return Err("degree 0 must be C00 = 1 and degree 1 zero".into());
        }
        Ok(Self {
            name,
            gm,
            radius,
            max_degree,
            c,
            s,
        })
    }
}

/// EGM2008 to degree and order [`MAX_DEGREE`], parsed at the first call.
pub fn egm2008() -> Result<&'static Coefficients, String> {
    static TABLE: OnceLock<Result<Coefficients, String>> = OnceLock::new();
    TABLE
        .get_or_init(|| Coefficients::parse_gfc(EGM2008, MAX_DEGREE))
        .as_ref()
        .map_err(|e| format!("data/egm2008_70.gfc: {e}"))
}

/// A spherical-harmonic field truncated to a degree and order, with the recursion's factors:
/// see the module's page.
#[derive(Clone, Debug, PartialEq)]
pub struct HarmonicField {
    /// GM (m³/s²).
    pub gm: f64,
    /// The reference radius a (m).
    pub radius: f64,
    /// The highest degree summed.
    pub degree: usize,
    /// The highest order summed.
    pub order: usize,
    /// `C̄nm`, `S̄nm` (`tri` index), to `degree`, zero beyond `order`.
    c: Vec<f64>,
    s: Vec<f64>,
    /// The column recursion's `α_nm`, `β_nm` (`tri` index) to degree `degree + 1`.
    alpha: Vec<f64>,
    beta: Vec<f64>,
    /// The sectoral factor `f_m` to order `order + 1`.
    sectoral: Vec<f64>,
    /// The acceleration's factors for `(n, m)` (`tri` index): on `V̄(n+1)(m+1)`, on
    /// `V̄(n+1)(m−1)` and on `V̄(n+1)m`, the normalisation ratios included.
    p_up: Vec<f64>,
    p_down: Vec<f64>,
    p_same: Vec<f64>,
}

impl HarmonicField {
    /// The field of `coefficients` to `degree` and `order` (`order <= degree <=` the
    /// coefficients' highest degree and [`MAX_DEGREE`]).
    pub fn new(coefficients: &Coefficients, degree: usize, order: usize) -> Result<Self, String> {
        let top = coefficients.max_degree.min(MAX_DEGREE);
        if degree > top {
            return Err(format!(
                "degree {degree} is beyond the {} coefficients shipped (degree {top} at most)",
                coefficients.name
            ));
        }
        if order > degree {
            return Err(format!(
                "order {order} is beyond degree {degree} (order <= degree)"
            ));
        }
        let len = tri(degree + 2, 0);
        let mut f = Self {
            gm: coefficients.gm,
            radius: coefficients.radius,
            degree,
            order,
            c: vec![0.0; len],
            s: vec![0.0; len],
            alpha: vec![0.0; len],
            beta: vec![0.0; len],
            sectoral: vec![0.0; order + 2],
            p_up: vec![0.0; len],
            p_down: vec![0.0; len],
            p_same: vec![0.0; len],
        };
        for n in 2..=degree {
            for m in 0..=n.min(order) {
                (f.c[tri(n, m)], f.s[tri(n, m)]) = coefficients.get(n, m);
            }
        }
        for m in 1..=order + 1 {
            let m = m as f64;
            f.sectoral[m as usize] = if m == 1.0 {
                3f64.sqrt()
            } else {
                ((2.0 * m + 1.0) / (2.0 * m)).sqrt()
            };
        }
        for n in 1..=degree + 1 {
            for m in 0..n.min(order + 2) {
                let (nf, mf) = (n as f64, m as f64);
                f.alpha[tri(n, m)] =
                    ((2.0 * nf + 1.0) * (2.0 * nf - 1.0) / ((nf - mf) * (nf + mf))).sqrt();
                if n >= m + 2 {
                    f.beta[tri(n, m)] = ((2.0 * nf + 1.0) * (nf + mf - 1.0) * (nf - mf - 1.0)
                        / ((2.0 * nf - 3.0) * (nf + mf) * (nf - mf)))
                        .sqrt();
                }
            }
        }
        for n in 0..=degree {
            for m in 0..=n.min(order) {
                let (nf, mf) = (n as f64, m as f64);
                let k = (2.0 * nf + 1.0) / (2.0 * nf + 3.0);
                // N_nm / N_(n+1)(m+1), N_nm / N_(n+1)m, N_nm / N_(n+1)(m−1).
                let d0 = if m == 0 { 0.5 } else { 1.0 };
                let up = (d0 * k * (nf + mf + 1.0) * (nf + mf + 2.0)).sqrt();
                let same = (k * (nf + mf + 1.0) / (nf - mf + 1.0)).sqrt();
                f.p_same[tri(n, m)] = (nf - mf + 1.0) * same;
                if m == 0 {
                    f.p_up[tri(n, m)] = up;
                } else {
                    let d1 = if m == 1 { 2.0 } else { 1.0 };
                    let down = (d1 * k / ((nf - mf + 1.0) * (nf - mf + 2.0))).sqrt();
                    f.p_up[tri(n, m)] = 0.5 * up;
                    f.p_down[tri(n, m)] = 0.5 * (nf - mf + 1.0) * (nf - mf + 2.0) * down;
                }
            }
        }
        Ok(f)
    }

    /// The acceleration (m/s²) at `r` (m), both in the model's frame (Earth-fixed for the
    /// Earth's models): the central term `−GM r/r³` plus the harmonics from degree 2.
    pub fn acceleration(&self, r: &Vec3) -> Vec3 {
        self.central(r) + self.harmonics(r)
    }

    /// The central term `−GM r/r³`.
    pub fn central(&self, r: &Vec3) -> Vec3 {
        let r2 = r.norm_squared();
        -self.gm / (r2 * r2.sqrt()) * r
    }

    /// The acceleration of the harmonics from degree 2 (m/s²) at `r`: the series of the
    /// module's page, without its central term.
    pub fn harmonics(&self, r: &Vec3) -> Vec3 {
        const ROWS: usize = MAX_DEGREE + 2;
        let (nmax, mmax) = (self.degree, self.order);
        if nmax < 2 {
            return Vec3::zeros();
        }
        let r2 = r.norm_squared();
        let a = self.radius;
        let rho = a * a / r2;
        let (x0, y0, z0) = (a * r.x / r2, a * r.y / r2, a * r.z / r2);
        // Three columns (orders m − 1, m, m + 1) of V̄ and W̄, rows n = 0 ..= nmax + 1,
        // at slots (order mod 3).
        let mut v = [[0.0f64; ROWS]; 3];
        let mut w = [[0.0f64; ROWS]; 3];
        let fill = |v: &mut [f64; ROWS], w: &mut [f64; ROWS], m: usize, vd: f64, wd: f64| {
            v[m] = vd;
            w[m] = wd;
            for n in m + 1..=nmax + 1 {
                let (al, be) = (self.alpha[tri(n, m)], self.beta[tri(n, m)]);
                let (v2, w2) = if n >= m + 2 {
                    (v[n - 2], w[n - 2])
                } else {
                    (0.0, 0.0)
                };
                v[n] = al * z0 * v[n - 1] - be * rho * v2;
                w[n] = al * z0 * w[n - 1] - be * rho * w2;
            }
        };
        let sectoral = |m: usize, vp: f64, wp: f64| {
            let f = self.sectoral[m];
            (f * (x0 * vp - y0 * wp), f * (x0 * wp + y0 * vp))
        };
        // Orders 0 and 1.
        let v00 = rho.sqrt();
        {
            let (v0, w0) = (&mut v[0], &mut w[0]);
            fill(v0, w0, 0, v00, 0.0);
        }
        let (mut vd, mut wd) = sectoral(1, v00, 0.0);
        {
            let (v1, w1) = (&mut v[1], &mut w[1]);
            fill(v1, w1, 1, vd, wd);
        }
        let (mut ax, mut ay, mut az) = (0.0, 0.0, 0.0);
        for m in 0..=mmax {
            let (cur, up) = (m % 3, (m + 1) % 3);
            let down = (m + 2) % 3; // (m − 1) mod 3
            for n in m.max(2)..=nmax {
                let k = tri(n, m);
                let (c, s) = (self.c[k], self.s[k]);
                let (vu, wu) = (v[up][n + 1], w[up][n + 1]);
                let (vs, ws) = (v[cur][n + 1], w[cur][n + 1]);
                let (pu, ps) = (self.p_up[k], self.p_same[k]);
                az += ps * (-c * vs - s * ws);
                if m == 0 {
                    ax -= pu * c * vu;
                    ay -= pu * c * wu;
                } else {
                    let (vl, wl) = (v[down][n + 1], w[down][n + 1]);
                    let pd = self.p_down[k];
                    ax += pu * (-c * vu - s * wu) + pd * (c * vl + s * wl);
                    ay += pu * (-c * wu + s * vu) + pd * (-c * wl + s * vl);
                }
            }
            // The next column, order m + 2 (needed while m + 2 <= mmax + 1).
            if m + 2 <= mmax + 1 {
                (vd, wd) = sectoral(m + 2, vd, wd);
                let slot = (m + 2) % 3;
                let (vs, ws) = (&mut v[slot], &mut w[slot]);
                vs.fill(0.0);
                ws.fill(0.0);
                fill(vs, ws, m + 2, vd, wd);
            }
        }
        Vec3::new(ax, ay, az) * (self.gm / (a * a))
    }

    /// The acceleration (m/s², GCRF) at `r` (m, GCRF) at `epoch + t`: `r` turned to the
    /// Earth-fixed frame by [`gcrf_to_itrf`], the field evaluated there, the acceleration
    /// turned back.
    pub fn acceleration_gcrf(&self, epoch: Epoch, t: f64, r: &Vec3) -> Vec3 {
        let to_itrf = gcrf_to_itrf(epoch, t);
        self.central(r) + to_itrf.inverse() * self.harmonics(&(to_itrf * r))
    }
}

/// The lattice spacing a run reads the harmonics through by default (degrees): see
/// [`HarmonicLattice`].
pub const LATTICE_DEG: f64 = 1.0;

/// A [`HarmonicField`] read through an Earth-fixed [`Lattice`]: the central term and J2
/// (`C̄20`) evaluated at every call, the rest of the harmonics (the non-zonal degree 2 and
/// everything from degree 3) interpolated from the lattice's nodes. J2 is a thousand times
/// the rest and would dominate the interpolation's error; what is left is smooth and small.
/// See the module's page for the error and the cost.
#[derive(Clone, Debug)]
pub struct HarmonicLattice {
    /// The field as given (the exact evaluation, and the key a cache is checked against).
    field: Arc<HarmonicField>,
    /// The field less its central term and `C̄20`.
    rest: HarmonicField,
    /// `GM a² J2` (m⁵/s²), `J2 = −√5 C̄20`.
    gm_a2_j2: f64,
    lattice: Lattice<3>,
}

impl HarmonicLattice {
    /// `field` on a lattice of spacing `cell_deg` degrees (rounded as [`Lattice::new`] says);
    /// `None` when `cell_deg` is not in (0, 90].
    pub fn new(field: Arc<HarmonicField>, cell_deg: f64) -> Option<Self> {
        let lattice = Lattice::new(cell_deg)?;
        let mut rest = (*field).clone();
        let c20 = if field.degree >= 2 {
            std::mem::take(&mut rest.c[tri(2, 0)])
        } else {
            0.0
        };
        Some(Self {
            gm_a2_j2: field.gm * field.radius * field.radius * (-(5f64.sqrt()) * c20),
            field,
            rest,
            lattice,
        })
    }

    /// The field as given.
    pub fn field(&self) -> &Arc<HarmonicField> {
        &self.field
    }

    /// The lattice (its spacing, its evaluations).
    pub fn lattice(&self) -> &Lattice<3> {
        &self.lattice
    }

    /// The acceleration of the harmonics from degree 2 (m/s²) at the Earth-fixed `r` (m):
    /// J2's in closed form plus the rest's, interpolated.
    pub fn harmonics(&mut self, r: &Vec3) -> Vec3 {
        let rest = &self.rest;
        let v = self.lattice.value(0, r, |p| rest.harmonics(p).into());
        self.j2(r) + Vec3::from(v)
    }

    /// J2's acceleration (m/s²) at the Earth-fixed `r` (m), about the Earth-fixed z axis.
    fn j2(&self, r: &Vec3) -> Vec3 {
        let r2 = r.norm_squared();
        let z2 = r.z * r.z / r2;
        let k = -1.5 * self.gm_a2_j2 / (r2 * r2 * r2.sqrt());
        k * Vec3::new(
            r.x * (1.0 - 5.0 * z2),
            r.y * (1.0 - 5.0 * z2),
            r.z * (3.0 - 5.0 * z2),
        )
    }

    /// The acceleration (m/s², GCRF) at `r` (m, GCRF) at `epoch + t`, as
    /// [`HarmonicField::acceleration_gcrf`] with the harmonics of [`HarmonicLattice::harmonics`].
    pub fn acceleration_gcrf(&mut self, epoch: Epoch, t: f64, r: &Vec3) -> Vec3 {
        let to_itrf = gcrf_to_itrf(epoch, t);
        self.field.central(r) + to_itrf.inverse() * self.harmonics(&(to_itrf * r))
    }
}

/// The perturbing acceleration (m/s²) of a point mass `mu` (m³/s²) at `r_body` on a
/// spacecraft at `r`, both from the Earth's centre: the pull on the spacecraft less the pull
/// on the Earth, `μ_b [(r_b − r)/|r_b − r|³ − r_b/|r_b|³]`.
///
/// Written as Battin's `−μ_b/|r_b − r|³ (r + F(q) r_b)` with `q = r·(r − 2 r_b)/r_b²` and
/// `F(q) = q (3 + 3q + q²)/(1 + (1 + q)^(3/2))`, equal to the difference without its
/// cancellation (the two terms agree to 1e-5 for a low orbit and the Moon).
///
/// ```
/// use satsim_environment::{Vec3, gravity::{MU_SUN, third_body_acceleration}};
/// let (r, sun) = (Vec3::new(42_164e3, 0.0, 0.0), Vec3::new(1.496e11, 0.0, 0.0));
/// let direct = MU_SUN * ((sun - r) / (sun - r).norm().powi(3) - sun / sun.norm().powi(3));
/// let battin = third_body_acceleration(MU_SUN, &sun, &r);
/// assert!((battin - direct).norm() < 1e-9 * direct.norm());
/// // The tide along the line: 2 μ r / d³, 3.3e-6 m/s² at geostationary altitude.
/// assert!((battin.x - 2.0 * MU_SUN * r.x / sun.norm().powi(3)).abs() < 1e-3 * battin.x);
/// ```
pub fn third_body_acceleration(mu: f64, r_body: &Vec3, r: &Vec3) -> Vec3 {
    let d = r_body - r;
    let q = r.dot(&(r - 2.0 * r_body)) / r_body.norm_squared();
    let f = q * (3.0 + 3.0 * q + q * q) / (1.0 + (1.0 + q).powf(1.5));
    let d3 = d.norm_squared() * d.norm();
    -mu / d3 * (r + f * r_body)
}
