//! The Earth's own radiation: the sunlight it reflects (albedo) and the heat it emits
//! (infrared), as they reach a small flat plate near it.
//!
//! # Model
//!
//! - The Earth is a sphere of radius [`R_EARTH`].
//! - **Reflected light.** A Lambertian reflector of uniform albedo `a` ([`ALBEDO`], 0.3,
//!   unless given) whose radiance everywhere is that of the sub-spacecraft point under the
//!   Sun: `L_a = a S max(0, ŝ·r̂) / π`, with `ŝ` the Sun's direction from the Earth's centre,
//!   `r̂` the spacecraft's and `S` the solar flux at the Earth's distance from the Sun,
//!   `S = S_1AU (1 AU / |r_sun|)²` ([`solar_flux`]), `S_1AU` = [`SOLAR_PRESSURE_1AU`] × c
//!   (1367 W/m², the flux behind the solar pressure the spacecraft already feels). Zero over
//!   the night side (`ŝ·r̂ <= 0`): the terminator's twilight and the cap's lit part seen from
//!   a spacecraft over the night side are neglected.
//! - **Emitted heat.** A uniform emitter of `M_ir` ([`EARTH_IR`], 237 W/m², the global mean
//!   outgoing long-wave flux, unless given), radiance `M_ir / π`, day and night alike.
//! - **On a plate.** A uniform Lambertian sphere of radiance `L` gives a small plate with
//!   unit normal `n` the irradiance `E = π L F`, `F` the view factor from the tilted plate to
//!   the sphere ([`sphere_view_factor`], exact for a uniform sphere, including the part of
//!   it cut by the plate's horizon). The plate facing the nadir receives
//!   `E = π L (R_EARTH / |r|)²`.
//! - **Its momentum.** The light arrives from every direction in which the plate sees the
//!   Earth (the cap of half-angle `asin(R_EARTH / |r|)` about the nadir, 68° at 500 km,
//!   above the plate's horizon); [`cap_moments`] gives the sums over those directions that
//!   a flat plate's force law takes (the sunlight's law, summed).
//!
//! What this leaves out: the albedo's variation over the visible cap (each element's own
//! solar zenith angle and view angle) and over the globe (clouds, ice, oceans, from 0.1 to
//! 0.8), and the infrared's with latitude. Knocke's model (Knocke, Ries & Tapley, "Earth
//! radiation pressure effects on satellites", AIAA 88-4292, 1988), used by orbit
//! determination, sums zonal albedo and emissivity over rings of the visible cap; Basilisk's
//! albedo module integrates per element over the cap from a map. Over an orbit these
//! average closer to this model than at any one place; at one place the difference can
//! reach a factor of two.
//!
//! Frames: positions and the normal in the GCRF (any common frame will do: only their
//! relative directions enter). Units: SI (m, W/m²).

use crate::{AU, R_EARTH, SOLAR_PRESSURE_1AU, Vec3};
use std::f64::consts::PI;

/// The Earth's uniform albedo (the Bond albedo, 0.3).
pub const ALBEDO: f64 = 0.3;

/// The Earth's emitted long-wave flux (W/m², the global mean outgoing infrared).
pub const EARTH_IR: f64 = 237.0;

/// The speed of light in vacuum (m/s, exact).
pub const SPEED_OF_LIGHT: f64 = 299_792_458.0;

/// The solar flux at 1 AU (W/m²) behind [`SOLAR_PRESSURE_1AU`]: that pressure times c,
/// 1367.05 W/m².
pub const SOLAR_FLUX_1AU: f64 = SOLAR_PRESSURE_1AU * SPEED_OF_LIGHT;

/// The solar flux (W/m²) at `distance` (m) from the Sun: `S_1AU (1 AU / distance)²`.
pub fn solar_flux(distance: f64) -> f64 {
    SOLAR_FLUX_1AU * (AU / distance).powi(2)
}

/// A flux of the Earth's radiation (W/m²): what it reflects and what it emits.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EarthFlux {
    /// Reflected sunlight (W/m²).
    pub reflected: f64,
    /// Emitted infrared (W/m²).
    pub emitted: f64,
}

impl EarthFlux {
    /// Reflected plus emitted (W/m²).
    pub fn total(&self) -> f64 {
        self.reflected + self.emitted
    }
    /// Both scaled by `k`.
    pub fn scaled(&self, k: f64) -> Self {
        Self {
            reflected: self.reflected * k,
            emitted: self.emitted * k,
        }
    }
}

/// The model's parameters: the Earth's albedo and its emitted flux (see the module's
/// documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EarthRadiation {
    /// The uniform albedo, in [0, 1] ([`ALBEDO`] by default).
    pub albedo: f64,
    /// The emitted long-wave flux at the surface (W/m², [`EARTH_IR`] by default).
    pub infrared: f64,
}

impl Default for EarthRadiation {
    /// Albedo [`ALBEDO`], infrared [`EARTH_IR`].
    fn default() -> Self {
        Self {
            albedo: ALBEDO,
            infrared: EARTH_IR,
        }
    }
}

impl EarthRadiation {
    /// The Earth's radiant exitance `π L` (W/m²) seen from the spacecraft at `r` (m, GCRF,
    /// from the Earth's centre, not zero) with the Sun at `r_sun` (m, GCRF): reflected
    /// `a S max(0, ŝ·r̂)`, emitted `M_ir`. A plate facing the whole Earth at `r` receives
    /// this times its [`sphere_view_factor`].
    ///
    /// ```
    /// use satsim_environment::earth_radiation::{EarthRadiation, solar_flux};
    /// use satsim_environment::Vec3;
    /// let sun = Vec3::new(1.496e11, 0.0, 0.0);
    /// let m = EarthRadiation::default();
    /// // Under the Sun, and over the night side.
    /// let day = m.exitance(&Vec3::new(7e6, 0.0, 0.0), &sun);
    /// assert!((day.reflected - 0.3 * solar_flux(1.496e11)).abs() < 1e-12);
    /// let night = m.exitance(&Vec3::new(-7e6, 0.0, 0.0), &sun);
    /// assert_eq!((night.reflected, night.emitted), (0.0, 237.0));
    /// ```
    pub fn exitance(&self, r: &Vec3, r_sun: &Vec3) -> EarthFlux {
        let d = r_sun.norm();
        let day = (r_sun / d).dot(&(r / r.norm())).max(0.0);
        EarthFlux {
            reflected: self.albedo * solar_flux(d) * day,
            emitted: self.infrared,
        }
    }

    /// The Earth's radiation arriving on a small plate of outward unit normal `n` at `r`
    /// with the Sun at `r_sun` (all GCRF, m): [`EarthRadiation::exitance`] times the view
    /// factor from the plate to the Earth, W/m² of the plate's area.
    ///
    /// ```
    /// use satsim_environment::earth_radiation::EarthRadiation;
    /// use satsim_environment::{R_EARTH, Vec3};
    /// let r = Vec3::new(0.0, 0.0, 2.0 * R_EARTH);
    /// let sun = Vec3::new(1.496e11, 0.0, 0.0); // over the terminator: no albedo
    /// let e = EarthRadiation::default().irradiance(&-Vec3::z(), &r, &sun);
    /// assert_eq!((e.reflected, e.emitted), (0.0, 237.0 / 4.0));
    /// ```
    pub fn irradiance(&self, n: &Vec3, r: &Vec3, r_sun: &Vec3) -> EarthFlux {
        let rn = r.norm();
        let f = sphere_view_factor(-n.dot(r) / rn, rn / R_EARTH);
        self.exitance(r, r_sun).scaled(f)
    }
}

/// The view factor from a small plate to a sphere: the plate at `h` radii from the
/// sphere's centre (`h >= 1`; less is taken as 1), its normal at `β` from the direction to
/// the centre (`cos_beta = cos β`). The closed form (Howell's catalogue of configuration
/// factors, "differential planar element to sphere"): `cos β / h²` while the whole sphere
/// is above the plate's horizon (`cos β >= 1/h`); 0 when none of it is (`cos β <= −1/h`);
/// between,
///
/// `1/2 − asin(x / (h sin β)) / π + (cos β acos(−x cot β) − x √(1 − h² cos² β)) / (π h²)`,
/// `x = √(h² − 1)`.
///
/// ```
/// use satsim_environment::earth_radiation::sphere_view_factor;
/// assert_eq!(sphere_view_factor(1.0, 2.0), 0.25); // facing the centre: (R / r)²
/// assert_eq!(sphere_view_factor(-0.6, 2.0), 0.0);  // facing away
/// ```
pub fn sphere_view_factor(cos_beta: f64, h: f64) -> f64 {
    let h = h.max(1.0);
    let cos_beta = cos_beta.clamp(-1.0, 1.0);
    let h2 = h * h;
    if cos_beta * h >= 1.0 {
        return cos_beta / h2;
    }
    if cos_beta * h <= -1.0 {
        return 0.0;
    }
    let sin_beta = (1.0 - cos_beta * cos_beta).sqrt();
    let x = (h2 - 1.0).sqrt();
    let a = (x / (h * sin_beta)).min(1.0).asin();
    let b = (-x * cos_beta / sin_beta).clamp(-1.0, 1.0).acos();
    let c = (1.0 - h2 * cos_beta * cos_beta).max(0.0).sqrt();
    (0.5 - a / PI + (cos_beta * b - x * c) / (PI * h2)).max(0.0)
}

/// The Earth's light on a small plate, integrated over the directions `d` (unit, from the
/// plate towards the Earth) in which the plate sees the Earth (the visible cap, above the
/// plate's horizon: `n·d > 0`), per unit exitance of a uniform Earth (radiance `1/π`):
/// what the force of the light on the plate takes. Multiplied by the exitance `M` (W/m²),
/// each is a flux (W/m²).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CapMoments {
    /// `(1/π) ∫ cos θ dω`: the view factor `F` ([`sphere_view_factor`]), `cos θ = n·d`.
    pub irradiance: f64,
    /// `(1/π) ∫ cos θ d dω`: the light's momentum direction, weighted (same frame as `n`
    /// and the nadir). A plate absorbing all of it is pushed by `−(M/c) A` times this.
    pub flux: Vec3,
    /// `(1/π) ∫ cos² θ dω`: the normal momentum a mirror returns (twice this).
    pub normal: f64,
}

/// [`CapMoments`] of a plate of outward unit normal `n` at `h` Earth radii from the
/// centre (`h >= 1`; less is taken as 1), `nadir` the unit direction to the centre.
///
/// With `β` the angle between `n` and the nadir and `α = asin(1/h)` the cap's half-angle
/// seen from the plate: while the whole cap is above the plate's horizon (`β + α <= 90°`)
/// the moments are those of a cone, in closed form: with `Ω = 2π (1 − cos α)`,
/// `b = 2π (1 − cos³ α)/3`, `a = (Ω − b)/2` (`∫ d dᵀ dω = a (I − ẑẑᵀ) + b ẑẑᵀ`),
/// `flux = (a n + (b − a) cos β ẑ)/π`, `normal = (a sin² β + b cos² β)/π`. When the
/// horizon cuts the cap, in rings about the nadir (as Knocke's model sums its rings): in
/// each ring, at angle `γ` from the nadir, `n·d = A + B cos φ` (`A = cos β cos γ`,
/// `B = sin β sin γ`) is positive on an arc `|φ| < φ₀`, `cos φ₀ = −A/B`, over which the
/// azimuthal integrals are closed forms; the rings are summed by Gauss–Legendre in `γ`
/// (8 nodes, in `u²` from the ring where the horizon starts to cut, which smooths the
/// arc's square-root onset), with the fully lit cone inside it in closed form. Continuous
/// through the horizon, and 0 beyond `β = 90° + α`. `irradiance` is the closed-form view
/// factor throughout.
///
/// ```
/// use satsim_environment::earth_radiation::cap_moments;
/// use satsim_environment::Vec3;
/// // Far away the cap is a point: the moments of a beam from the nadir, (R/r)² each.
/// let c = cap_moments(&-Vec3::z(), &-Vec3::z(), 1000.0);
/// assert!((c.flux.z / -1e-6 - 1.0).abs() < 1e-6 && (c.normal / 1e-6 - 1.0).abs() < 1e-6);
/// ```
pub fn cap_moments(n: &Vec3, nadir: &Vec3, h: f64) -> CapMoments {
    let h = h.max(1.0);
    let cb = n.dot(nadir).clamp(-1.0, 1.0);
    let irradiance = sphere_view_factor(cb, h);
    if irradiance <= 0.0 {
        return CapMoments::default();
    }
    let sa = 1.0 / h;
    let alpha = sa.asin();
    let sb = (1.0 - cb * cb).sqrt();
    // The unit vector across the nadir towards n (any when n is along it: then unused).
    let across = if sb > 1e-12 {
        (n - nadir * cb) / sb
    } else {
        Vec3::zeros()
    };
    // The cone of half-angle `g` about the nadir, all of it lit: ∫ cos θ d dω and
    // ∫ cos² θ dω, as components (along the nadir, across).
    let cone = |g: f64| {
        let c = g.cos();
        let omega = 2.0 * PI * (1.0 - c);
        let b = 2.0 * PI * (1.0 - c * c * c) / 3.0;
        let a = 0.5 * (omega - b);
        ((b * cb, a * sb), a * sb * sb + b * cb * cb)
    };
    let ((mut v_z, mut v_x), mut w) = if cb * h >= 1.0 {
        cone(alpha)
    } else {
        // The horizon cuts the cap from the ring at |90° − β| on (the cone inside it fully
        // lit when the plate faces the nadir, dark when it faces away).
        let kink = cb.asin().abs();
        let ((mut v_z, mut v_x), mut w) = if cb > 0.0 {
            cone(kink)
        } else {
            ((0.0, 0.0), 0.0)
        };
        let span = alpha - kink;
        for (x, wt) in GL8 {
            let u = 0.5 * (1.0 + x);
            let g = kink + span * u * u;
            let jac = 0.5 * wt * span * 2.0 * u;
            let (sg, cg) = g.sin_cos();
            let (a, b) = (cb * cg, sb * sg);
            let c0 = (-a / b).clamp(-1.0, 1.0);
            let phi0 = c0.acos();
            let s0 = (1.0 - c0 * c0).sqrt();
            let i0 = 2.0 * (a * phi0 + b * s0);
            let ic = 2.0 * a * s0 + b * (phi0 + s0 * c0);
            let i2 = 2.0 * a * a * phi0 + 4.0 * a * b * s0 + b * b * (phi0 + s0 * c0);
            let k = jac * sg;
            v_z += k * i0 * cg;
            v_x += k * ic * sg;
            w += k * i2;
        }
        ((v_z, v_x), w)
    };
    v_z /= PI;
    v_x /= PI;
    w /= PI;
    CapMoments {
        irradiance,
        flux: nadir * v_z + across * v_x,
        normal: w,
    }
}

/// 8-point Gauss–Legendre nodes and weights on [−1, 1].
const GL8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_2, 0.101_228_536_290_376_3),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_2, 0.101_228_536_290_376_3),
];

#[cfg(test)]
mod tests {
    use super::*;

    /// The view factor by quadrature over the directions from the plate: `F = (1/π) ∫
    /// max(0, n·d) dω` over the cone of directions `d` that meet the sphere (half-angle
    /// `asin(1/h)` about the nadir). Polar angle γ from the nadir in composite
    /// Gauss–Legendre panels, graded towards the kinks where the cone's edge crosses the
    /// plate's horizon; azimuth over the lit arc only (where `n·d > 0`), also Gauss–Legendre.
    /// Independent of Howell's closed form.
    fn view_factor_quadrature(beta: f64, h: f64) -> f64 {
        // 8-point Gauss–Legendre on [-1, 1].
        const X: [f64; 4] = [
            0.183_434_642_495_649_8,
            0.525_532_409_916_329,
            0.796_666_477_413_626_7,
            0.960_289_856_497_536_2,
        ];
        const W: [f64; 4] = [
            0.362_683_783_378_362,
            0.313_706_645_877_887_3,
            0.222_381_034_453_374_5,
            0.101_228_536_290_376_3,
        ];
        let gl = |a: f64, b: f64, f: &dyn Fn(f64) -> f64| {
            let (m, r) = (0.5 * (a + b), 0.5 * (b - a));
            (0..4)
                .map(|i| W[i] * (f(m - r * X[i]) + f(m + r * X[i])))
                .sum::<f64>()
                * r
        };
        let (sb, cb) = beta.sin_cos();
        let inner = |g: f64| {
            // n·d = cos β cos γ + sin β sin γ cos φ = A + B cos φ; lit for |φ| < φ0.
            let (sg, cg) = g.sin_cos();
            let (a, b) = (cb * cg, sb * sg);
            let phi0 = if a >= b.abs() {
                PI
            } else if a <= -b.abs() {
                return 0.0;
            } else {
                (-a / b).acos()
            };
            let panels = 16;
            let mut s = 0.0;
            for k in 0..panels {
                let (lo, hi) = (
                    phi0 * k as f64 / panels as f64,
                    phi0 * (k + 1) as f64 / panels as f64,
                );
                s += gl(lo, hi, &|p: f64| a + b * p.cos());
            }
            2.0 * s * sg
        };
        let cap = (1.0 / h).asin();
        // Kinks of the inner integral: γ = |π/2 − β| (where A = ±B).
        let mut cuts = vec![0.0, cap];
        let k = (PI / 2.0 - beta).abs();
        if k > 0.0 && k < cap {
            cuts.insert(1, k);
        }
        let mut total = 0.0;
        for w in cuts.windows(2) {
            // Panels graded as t² towards both ends of each piece.
            let n = 400;
            let (lo, hi) = (w[0], w[1]);
            let mid = 0.5 * (lo + hi);
            for side in [-1.0, 1.0] {
                let end = if side < 0.0 { lo } else { hi };
                for j in 0..n {
                    let t0 = (j as f64 / n as f64).powi(2);
                    let t1 = ((j + 1) as f64 / n as f64).powi(2);
                    let (g0, g1) = (end + (mid - end) * t1, end + (mid - end) * t0);
                    total += gl(g0.min(g1), g0.max(g1), &inner);
                }
            }
        }
        total / PI
    }

    #[test]
    fn the_view_factor_matches_a_quadrature_over_the_visible_cap() {
        // Low orbit (500 km), 2000 km, geostationary-like, and a close one; tilts across the
        // three regimes: the whole Earth visible, cut by the horizon, none.
        let mut worst = 0.0f64;
        for h in [1.0784f64, 1.3136, 6.61, 1.01] {
            let horizon = (1.0 / h).acos(); // β beyond which the horizon cuts the Earth
            for beta in [
                0.0,
                0.5 * horizon,
                horizon,
                0.5 * (horizon + PI / 2.0),
                PI / 2.0 - 0.01,
                PI / 2.0,
                PI / 2.0 + 0.3 * (PI / 2.0 - horizon),
                PI - horizon - 1e-3,
            ] {
                let f = sphere_view_factor(beta.cos(), h);
                let q = view_factor_quadrature(beta, h);
                assert!(
                    (f - q).abs() <= 1e-6 * q.max(1e-3),
                    "h {h}, β {beta}: closed form {f}, quadrature {q}"
                );
                worst = worst.max((f - q).abs() / q.max(1e-3));
            }
        }
        println!("view factor against the quadrature: worst {worst:.1e} relative");
    }

    /// The three moments by brute force: a midpoint rule over the directions from the plate
    /// (γ from the nadir, φ about it), `max(0, n·d)` taken sample by sample.
    fn moments_brute(beta: f64, h: f64) -> (f64, Vec3, f64) {
        let cap = (1.0 / h).asin();
        let n = Vec3::new(beta.sin(), 0.0, beta.cos());
        let (ng, nphi) = (1200, 1200);
        let (dg, dphi) = (cap / ng as f64, 2.0 * PI / nphi as f64);
        let (mut e, mut v, mut w) = (0.0, Vec3::zeros(), 0.0);
        for i in 0..ng {
            let g = (i as f64 + 0.5) * dg;
            let (sg, cg) = g.sin_cos();
            for j in 0..nphi {
                let (sp, cp) = ((j as f64 + 0.5) * dphi).sin_cos();
                let d = Vec3::new(sg * cp, sg * sp, cg);
                let c = n.dot(&d);
                if c > 0.0 {
                    let k = sg * dg * dphi / PI;
                    e += c * k;
                    v += d * (c * k);
                    w += c * c * k;
                }
            }
        }
        (e, v, w)
    }

    #[test]
    fn the_cap_moments_match_a_brute_force_sum_over_the_visible_cap() {
        let mut worst = 0.0f64;
        for h in [1.0784f64, 1.3136, 6.61] {
            let horizon = (1.0 / h).acos();
            let alpha = (1.0 / h).asin();
            for beta in [
                0.0,
                0.5 * horizon,
                horizon + 0.05,
                1.2,
                PI / 2.0,
                PI / 2.0 + 0.5 * alpha,
                PI / 2.0 + alpha - 0.05,
            ] {
                let n = Vec3::new(beta.sin(), 0.0, beta.cos());
                let c = cap_moments(&n, &Vec3::z(), h);
                let (e, v, w) = moments_brute(beta, h);
                // The midpoint rule, with a kink in each ring the horizon cuts: 3e-7 of the
                // full cap's at worst.
                let scale = 1.0 / (h * h);
                let err = ((c.irradiance - e).abs())
                    .max((c.flux - v).norm())
                    .max((c.normal - w).abs())
                    / scale;
                worst = worst.max(err);
                assert!(err < 2e-6, "h {h}, β {beta}: {c:?} against {e}, {v}, {w}");
            }
        }
        println!("cap moments against the brute-force sum: worst {worst:.1e} of (R/r)²");
    }

    #[test]
    fn the_cap_moments_are_closed_forms_facing_the_nadir_and_continuous_at_the_horizon() {
        // Facing the nadir: flux and normal moment (2/3)(1 − cos³ α) (the cone's b/π).
        for h in [1.0784f64, 2.0, 10.0] {
            let ca = (1.0 - 1.0 / (h * h)).sqrt();
            let m = 2.0 / 3.0 * (1.0 - ca * ca * ca);
            let c = cap_moments(&Vec3::z(), &Vec3::z(), h);
            assert!((c.flux - Vec3::z() * m).norm() < 1e-15 && (c.normal - m).abs() < 1e-15);
            assert_eq!(c.irradiance, 1.0 / (h * h));
            // Through the tilt where the horizon starts to cut (closed form one side,
            // rings the other) and through 90°: continuous.
            let horizon = (1.0 / h).acos();
            for edge in [horizon, PI / 2.0] {
                let tilt = |b: f64| cap_moments(&Vec3::new(b.sin(), 0.0, b.cos()), &Vec3::z(), h);
                let (lo, hi) = (tilt(edge - 1e-9), tilt(edge + 1e-9));
                assert!((lo.flux - hi.flux).norm() < 1e-7, "h {h}: {lo:?} {hi:?}");
                assert!((lo.normal - hi.normal).abs() < 1e-7);
            }
            // Beyond 90° + α: nothing.
            let away = PI / 2.0 + (1.0 / h).asin() + 1e-6;
            let n = Vec3::new(away.sin(), 0.0, away.cos());
            assert_eq!(cap_moments(&n, &Vec3::z(), h), CapMoments::default());
        }
    }

    #[test]
    fn the_flux_under_the_sun_at_normal_incidence_is_the_closed_form() {
        let m = EarthRadiation {
            albedo: 0.35,
            infrared: 240.0,
        };
        let r_sun = Vec3::new(0.6, -0.8, 0.0) * 1.52e11;
        let r = r_sun.normalize() * (R_EARTH + 500e3);
        let e = m.irradiance(&-r.normalize(), &r, &r_sun);
        let f = (R_EARTH / r.norm()).powi(2);
        let s = SOLAR_PRESSURE_1AU * SPEED_OF_LIGHT * (AU / 1.52e11).powi(2);
        assert!((e.reflected / (0.35 * s * f) - 1.0).abs() < 1e-14);
        assert!((e.emitted / (240.0 * f) - 1.0).abs() < 1e-14);
        // 1367 W/m² at 1 AU.
        assert!((SOLAR_FLUX_1AU - 1367.05).abs() < 0.01);
        // Sun at 60° from the zenith: half the reflected light; over the night side none;
        // the emitted light unchanged.
        let q = nalgebra::Rotation3::from_axis_angle(&Vec3::z_axis(), PI / 3.0);
        let tilted = m.irradiance(&-(q * r).normalize(), &(q * r), &r_sun);
        assert!((tilted.reflected / e.reflected - 0.5).abs() < 1e-14);
        let night = m.irradiance(&r.normalize(), &-r, &r_sun);
        assert_eq!(night.reflected, 0.0);
        assert!((night.emitted / e.emitted - 1.0).abs() < 1e-15);
        // A plate facing away from the Earth, beyond the horizon: nothing.
        let away = m.irradiance(&r.normalize(), &r, &r_sun);
        assert_eq!(away, EarthFlux::default());
    }
}
