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
//! # The table
//!
//! [`cap_moments`] sums rings over the cap where the plate's horizon cuts it, about 0.4 µs a
//! plate; [`CapTable`] gives the same moments in under a tenth of that, and [`cap_moments`]
//! stays the reference it is built from and tested against. With `t = h cos β` (`h = |r| /
//! R_EARTH`), the moments are closed forms for `t >= 1` (the whole cap above the horizon;
//! the cone's coefficients depend on `h` only) and 0 for `t <= −1`, and the table serves
//! the cut regime between:
//!
//! - **Entries.** `[irradiance, p, q]` with `flux = p n + q nadir` (`p = v_x / sin β`,
//!   `q = v_z − p cos β`), per `(R_EARTH / r)²`, less `(1 + t)/2` times the whole cap's
//!   closed forms continued into the cut regime, so that each entry is 0 at both kinks
//!   (`t = ±1`: nothing seen, the whole cap) and the table meets the closed forms there
//!   exactly. The normal moment is `n·flux = p + q cos β` (an identity of the sums,
//!   `cos θ = n·d`).
//! - **Nodes.** 193 uniform in `u = √(1 + t) − √(1 − t)` ∈ [−√2, √2] (the kinks at the end
//!   nodes; the moments' onsets there go as `(1 ± t)^{5/2}`, smooth in `u`), times 129
//!   uniform in the cap's half-angle `α = asin(1/h)` ∈ [0, π/2] (every altitude: the
//!   entries vanish as `α → 0`, a point-like Earth, their value at the first node). One
//!   static table (600 kB), built on first use from the exact sums (25 000 of them, 10 to
//!   20 ms), the same every time.
//! - **Interpolation.** Cubic Lagrange in `u` (4 nodes), quadratic in `α` (3 nodes),
//!   one-sided at the ends. [`CapTable::at_altitude`] does the altitude's part once
//!   ([`CapSlice`]: `α`, its weights, the cone's coefficients); [`CapSlice::moments`] the
//!   tilt's, per plate, with no allocation; a pure function of `(cos β, h)`.
//! - **Error.** Against [`cap_moments`] over tilts from facing the nadir to facing away
//!   (through both kinks) at 100 km to 384 000 km: within 3.4e-7 of `(R_EARTH / r)²` (the
//!   nadir-facing plate's moments) at 100–150 km, 1.1e-7 at 500 km, 9e-8 above; the tests
//!   hold it to 1e-6. On a 1 m² plate in low orbit that is below 1e-14 N, against the
//!   light's few 1e-9 N (and the model's own uniform Earth, a factor of two off locally).
//! - **Cost.** About 38 ns a plate against 470 ns for the exact sums (12 times less),
//!   over a box's six faces at 16 attitudes at 500 km (84 of the 96 cut by the horizon),
//!   one core of an AMD EPYC, release build (`cargo test -p satsim-environment --release
//!   -- --ignored --nocapture cost_per_plate`). Of the 38 ns: about 15 the interpolation
//!   (45 products), 6 the two square roots of `u`, 5 the call.
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
    let (mut v_z, mut v_x, mut w) = if cb * h >= 1.0 {
        let ((v_z, v_x), w) = cone(alpha);
        (v_z, v_x, w)
    } else {
        // The horizon cuts the cap from the ring at |90° − β| on (the cone inside it fully
        // lit when the plate faces the nadir, dark when it faces away).
        let kink = cb.asin().abs();
        let ((v_z, v_x), w) = if cb > 0.0 {
            cone(kink)
        } else {
            ((0.0, 0.0), 0.0)
        };
        add_rings((v_z, v_x, w), cb, sb, kink, alpha)
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

/// The rings of [`cap_moments`] where the horizon cuts them, from `kink` to `alpha` (rad,
/// from the nadir), added to the sums `(v_z, v_x, w)` (before the division by π); `cb`, `sb`
/// the cosine and sine of the tilt.
fn add_rings(
    (mut v_z, mut v_x, mut w): (f64, f64, f64),
    cb: f64,
    sb: f64,
    kink: f64,
    alpha: f64,
) -> (f64, f64, f64) {
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
    (v_z, v_x, w)
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

/// Nodes of [`CapTable`] in its tilt coordinate `u`, over [−√2, √2].
const TABLE_U: usize = 193;
/// Node spacings in `u` per unit of `u`.
const U_SCALE: f64 = (TABLE_U - 1) as f64 / (2.0 * std::f64::consts::SQRT_2);
/// Nodes of [`CapTable`] in the cap's half-angle `α`, over [0, π/2].
const TABLE_ALPHA: usize = 129;

/// The cone of half-angle `α` (rad) about the nadir, per `π sin² α`: the `(A, B)` of
/// `∫ d dᵀ dω = π sin² α (A (I − ẑẑᵀ) + B ẑẑᵀ)` (see [`cap_moments`]), free of the
/// cancellation in `1 − cos α` at small angles: `A = (1 − c)(2 + c) / (3 (1 + c))`,
/// `B = 2 (1 + c + c²) / (3 (1 + c))`, `c = cos α`.
fn cone_per_area(alpha: f64) -> (f64, f64) {
    let c = alpha.cos();
    let omc = 2.0 * (0.5 * alpha).sin().powi(2);
    let k = 1.0 / (3.0 * (1.0 + c));
    (omc * (2.0 + c) * k, 2.0 * (1.0 + c + c * c) * k)
}

/// The tilt `t = h cos β` at the table's coordinate `u` (the inverse of
/// `u = √(1 + t) − √(1 − t)`).
fn tilt_at(u: f64) -> f64 {
    u * (1.0 - 0.25 * u * u).max(0.0).sqrt()
}

/// The closed forms of the whole cap, extended into the cut regime, per `sin² α`:
/// `[irradiance, p, q]` with `flux = p n + q nadir` (see [`CapTable`]), at
/// `cb = cos β` for the cone `(A, B)`.
fn cone_extended(cb: f64, (a, b): (f64, f64)) -> [f64; 3] {
    [cb, a, (b - a) * cb]
}

/// 3-point Lagrange weights at `x` (in node spacings from the first node) on `n` uniform
/// nodes: the first node of the stencil (about the nearest node, one-sided at the ends) and
/// the weights. Total: a NaN gives a stencil and NaN weights, never an index out of range.
#[inline]
fn quadratic_stencil(x: f64, n: usize) -> (usize, [f64; 3]) {
    // The nearest node in the middle where it can be.
    let i = ((x + 0.5) as isize - 1).clamp(0, n as isize - 3) as usize;
    let p = x - i as f64;
    let (p1, p2) = (p - 1.0, p - 2.0);
    (i, [0.5 * p1 * p2, -p * p2, 0.5 * p * p1])
}

/// 4-point Lagrange weights at `x` (in node spacings from the first node) on `n` uniform
/// nodes: the first node of the stencil (centred where it can be, one-sided at the ends)
/// and the weights. Total, as [`quadratic_stencil`].
#[inline]
fn cubic_stencil(x: f64, n: usize) -> (usize, [f64; 4]) {
    // Saturating float-to-int casts: NaN gives 0; truncation is the floor where it
    // matters (x >= 1).
    let i = ((x as isize) - 1).clamp(0, n as isize - 4) as usize;
    let p = x - i as f64;
    let (p1, p2, p3) = (p - 1.0, p - 2.0, p - 3.0);
    let w = [
        -p1 * p2 * p3 * (1.0 / 6.0),
        p * p2 * p3 * 0.5,
        -p * p1 * p3 * 0.5,
        p * p1 * p2 * (1.0 / 6.0),
    ];
    (i, w)
}

/// A table of [`cap_moments`] for a fast evaluation: the sums over the visible cap as
/// functions of the tilt `cos β = n·nadir` and the altitude `h` (Earth radii), for every
/// `h >= 1`, built once ([`CapTable::shared`]) and deterministic. See the module's
/// documentation (*The table*) for its nodes, its interpolation and its error.
///
/// ```
/// use satsim_environment::earth_radiation::{CapTable, cap_moments};
/// use satsim_environment::Vec3;
/// let h = 1.0784; // 500 km
/// let slice = CapTable::shared().at_altitude(h);
/// let nadir = -Vec3::z();
/// let n = Vec3::new(0.8, 0.0, -0.6); // the horizon cuts the cap
/// let (fast, exact) = (slice.moments(&n, &nadir), cap_moments(&n, &nadir, h));
/// let scale = 1.0 / (h * h); // (R/r)²: the nadir-facing plate's
/// assert!((fast.flux - exact.flux).norm() < 1e-6 * scale);
/// assert!((fast.irradiance - exact.irradiance).abs() < 1e-6 * scale);
/// ```
#[derive(Debug)]
pub struct CapTable {
    /// `[irradiance, p, q]` per `sin² α`, less `(1 + t)/2` times the whole cap's closed
    /// forms ([`cone_extended`]), at node `(j, i)` (`α_j`, `u_i`): from index
    /// `3 (j TABLE_U + i)`.
    nodes: Vec<f64>,
}

impl CapTable {
    /// The table, built on first use (25 000 evaluations of the exact sums, 10 to 20 ms)
    /// and shared.
    pub fn shared() -> &'static CapTable {
        static TABLE: std::sync::OnceLock<CapTable> = std::sync::OnceLock::new();
        TABLE.get_or_init(CapTable::build)
    }

    /// The spacing of the nodes in `u` and in `α` (rad).
    fn spacing() -> (f64, f64) {
        (
            2.0 * std::f64::consts::SQRT_2 / (TABLE_U - 1) as f64,
            0.5 * PI / (TABLE_ALPHA - 1) as f64,
        )
    }

    /// Evaluates the exact sums at every node.
    fn build() -> CapTable {
        let (du, da) = Self::spacing();
        let mut nodes = vec![0.0; 3 * TABLE_U * TABLE_ALPHA];
        // α = 0 (a point-like Earth): every entry is 0, the limit (each is O(α)).
        for j in 1..TABLE_ALPHA {
            let alpha = da * j as f64;
            let sa = alpha.sin();
            let (s2, h) = (sa * sa, 1.0 / sa);
            let cone = cone_per_area(alpha);
            // The ends (t = ±1, the kinks) are 0 by construction: nothing, and the whole
            // cap, there.
            for i in 1..TABLE_U - 1 {
                let t = tilt_at(-std::f64::consts::SQRT_2 + du * i as f64);
                let cb = t * sa;
                let sb = (1.0 - cb * cb).sqrt();
                // The exact sums of `cap_moments` (per π), the inner cone free of
                // cancellation at small angles.
                let kink = cb.asin().abs();
                let inner = if cb > 0.0 {
                    let (a, b) = cone_per_area(kink);
                    let k = PI * kink.sin().powi(2);
                    (k * b * cb, k * a * sb, k * (a * sb * sb + b * cb * cb))
                } else {
                    (0.0, 0.0, 0.0)
                };
                // The normal moment is p + q cos β: not stored.
                let (v_z, v_x, _) = add_rings(inner, cb, sb, kink, alpha);
                let p = v_x / (PI * sb);
                let moments = [sphere_view_factor(cb, h), p, v_z / PI - cb * p];
                let ext = cone_extended(cb, cone);
                let blend = 0.5 * (1.0 + t);
                for k in 0..3 {
                    nodes[3 * (j * TABLE_U + i) + k] = moments[k] / s2 - blend * ext[k];
                }
            }
        }
        CapTable { nodes }
    }

    /// The part of the evaluation that depends on the altitude only, for the plates at
    /// `h` Earth radii from the centre (`h >= 1`; less, or NaN, is taken as 1).
    pub fn at_altitude(&self, h: f64) -> CapSlice<'_> {
        let h = h.max(1.0);
        let sa = 1.0 / h;
        let alpha = sa.asin();
        let (_, da) = Self::spacing();
        let (j, wa) = quadratic_stencil(alpha / da, TABLE_ALPHA);
        CapSlice {
            table: self,
            h,
            s2: sa * sa,
            cone: cone_per_area(alpha),
            j,
            wa,
        }
    }
}

/// [`CapTable`] at one altitude: what [`CapSlice::moments`] needs that depends on the
/// altitude only (the cap's half-angle, the interpolation's weights in it, the whole cap's
/// closed forms), computed once for all the plates there.
#[derive(Clone, Copy, Debug)]
pub struct CapSlice<'a> {
    table: &'a CapTable,
    /// Earth radii from the centre, >= 1.
    h: f64,
    /// `sin² α = 1/h²`.
    s2: f64,
    /// The whole cap's `(A, B)` ([`cone_per_area`]).
    cone: (f64, f64),
    /// The first node in `α` of the stencil, and its weights.
    j: usize,
    wa: [f64; 3],
}

impl CapSlice<'_> {
    /// The table's entries interpolated at the stencil from node `i` in `u` (weights
    /// `wu`) and the slice's in `α`. Sums in pairs: a shorter chain of additions.
    #[inline]
    fn interpolate(&self, i: usize, wu: &[f64; 4]) -> [f64; 3] {
        const ROW: usize = 3 * TABLE_U;
        let nodes = &self.table.nodes[(self.j * TABLE_U + i) * 3..];
        let row = |dj: usize| -> [f64; 3] {
            let r: &[f64; 12] = nodes[dj * ROW..][..12].try_into().unwrap_or(&[0.0; 12]);
            std::array::from_fn(|k| {
                (wu[0] * r[k] + wu[1] * r[3 + k]) + (wu[2] * r[6 + k] + wu[3] * r[9 + k])
            })
        };
        let (r0, r1, r2) = (row(0), row(1), row(2));
        let wa = &self.wa;
        std::array::from_fn(|k| (wa[0] * r0[k] + wa[1] * r1[k]) + wa[2] * r2[k])
    }

    /// [`cap_moments`] of a plate of outward unit normal `n`, `nadir` the unit direction to
    /// the Earth's centre (same frame), by the table: exact (closed forms) when the whole
    /// cap or none of it is above the plate's horizon, interpolated between.
    #[inline]
    pub fn moments(&self, n: &Vec3, nadir: &Vec3) -> CapMoments {
        let cb = n.dot(nadir).clamp(-1.0, 1.0);
        let t = cb * self.h;
        let m = if t >= 1.0 {
            cone_extended(cb, self.cone)
        } else if t > -1.0 {
            let u = (1.0 + t).sqrt() - (1.0 - t).sqrt();
            let (i, wu) = cubic_stencil((u + std::f64::consts::SQRT_2) * U_SCALE, TABLE_U);
            let g = self.interpolate(i, &wu);
            let blend = 0.5 * (1.0 + t);
            let ext = cone_extended(cb, self.cone);
            let mut m = [0.0; 3];
            for k in 0..3 {
                m[k] = g[k] + blend * ext[k];
            }
            m
        } else {
            return CapMoments::default();
        };
        let [irradiance, p, q] = m.map(|x| x * self.s2);
        // n·flux: the sums of cos θ d and of cos² θ are one (cos θ = n·d).
        let normal = p + cb * q;
        if irradiance <= 0.0 {
            return CapMoments::default();
        }
        CapMoments {
            irradiance,
            flux: n * p + nadir * q,
            normal,
        }
    }
}

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

    /// A unit normal at `cos β = cb` from `nadir`, turned by `phi` about it.
    fn tilted(nadir: &Vec3, cb: f64, phi: f64) -> Vec3 {
        let e1 = nadir.cross(&Vec3::new(0.3, 0.9, -0.2)).normalize();
        let e2 = nadir.cross(&e1);
        let sb = (1.0 - cb * cb).max(0.0).sqrt();
        nadir * cb + (e1 * phi.cos() + e2 * phi.sin()) * sb
    }

    /// The largest difference of the moments, per `(R/r)² = 1/h²`.
    fn moments_error(a: &CapMoments, b: &CapMoments, h: f64) -> f64 {
        ((a.irradiance - b.irradiance).abs())
            .max((a.flux - b.flux).norm())
            .max((a.normal - b.normal).abs())
            * h
            * h
    }

    /// The table's error: within this of the nadir-facing plate's moments, `(R/r)²`.
    const TABLE_TOLERANCE: f64 = 1e-6;

    #[test]
    fn the_table_matches_the_exact_sums_at_every_tilt_and_altitude() {
        let nadir = Vec3::new(0.3, -0.5, -0.81).normalize();
        let table = CapTable::shared();
        // 100 km to beyond the geostationary orbit, and the Moon's distance.
        for km in [100.0, 150.0, 500.0, 2000.0, 20_000.0, 36_000.0, 384_000.0] {
            let h = 1.0 + km * 1e3 / R_EARTH;
            let slice = table.at_altitude(h);
            let edge = 1.0 / h;
            let mut tilts: Vec<f64> = (0..=4000).map(|k| (PI * k as f64 / 4000.0).cos()).collect();
            // Dense through the cut regime, and at and about both kinks, edge-on, facing the
            // nadir and away.
            tilts.extend((0..=4000).map(|k| edge * (2.0 * k as f64 / 4000.0 - 1.0)));
            for d in [0.0, 1e-15, 1e-12, 1e-9, 1e-6, 1e-3] {
                tilts.extend([edge - d, edge + d, -edge - d, -edge + d, d, -d]);
            }
            tilts.extend([1.0, -1.0]);
            let mut worst = 0.0f64;
            for (k, &cb) in tilts.iter().enumerate() {
                let n = tilted(&nadir, cb.clamp(-1.0, 1.0), 0.37 * k as f64);
                let (fast, mut exact) = (slice.moments(&n, &nadir), cap_moments(&n, &nadir, h));
                // Near both kinks the reference's view factor (asin and acos of 1 − η) loses
                // half its digits (an error up to √ε (R/r)/h² = 1.5e-8 / h³ absolute): within
                // 1e-6 of them the cut part is below 1e-15 (it goes as (1 ∓ h cos β)^{5/2}),
                // so the closed forms there are the reference: the whole cap's, and none.
                let t = n.dot(&nadir) * h;
                if (1.0 - t).abs() < 1e-6 {
                    exact.irradiance = n.dot(&nadir) / (h * h);
                } else if (1.0 + t).abs() < 1e-6 {
                    exact.irradiance = 0.0;
                }
                let err = moments_error(&fast, &exact, h);
                assert!(
                    err <= TABLE_TOLERANCE,
                    "{km} km, cos β {cb}: {err:.2e}: {fast:?} against {exact:?}"
                );
                worst = worst.max(err);
            }
            println!("{km} km: worst {worst:.2e} of (R/r)²");
        }
    }

    #[test]
    fn the_table_is_continuous_through_the_kinks() {
        let nadir = -Vec3::z();
        for km in [150.0, 500.0, 2000.0, 20_000.0, 36_000.0] {
            let h = 1.0 + km * 1e3 / R_EARTH;
            let slice = CapTable::shared().at_altitude(h);
            let at = |cb: f64| slice.moments(&tilted(&nadir, cb, 0.0), &nadir);
            for edge in [1.0 / h, -1.0 / h] {
                for d in [1e-15, 1e-12, 1e-9] {
                    let (lo, hi) = (at(edge - d), at(edge + d));
                    let jump = moments_error(&lo, &hi, h);
                    assert!(
                        jump <= TABLE_TOLERANCE,
                        "{km} km, cos β {edge} ± {d}: {jump:.2e}"
                    );
                }
            }
            // The kinks themselves: nothing, and the whole cap in closed form.
            assert!(moments_error(&at(-1.0 / h), &CapMoments::default(), h) < 1e-14);
            let whole = cap_moments(&tilted(&nadir, 1.0 / h, 0.0), &nadir, h);
            assert!(moments_error(&at(1.0 / h), &whole, h) < 1e-14);
        }
    }

    #[test]
    fn the_table_is_built_the_same_every_time() {
        let (a, b) = (CapTable::build(), CapTable::shared());
        assert_eq!(a.nodes.len(), b.nodes.len());
        assert!(
            a.nodes
                .iter()
                .zip(&b.nodes)
                .all(|(x, y)| x.to_bits() == y.to_bits())
        );
        // Bad input: no panic; nothing from a NaN normal or from infinitely far; below the
        // surface taken as on it.
        let n = Vec3::new(0.6, 0.0, -0.8);
        let nan = Vec3::new(f64::NAN, 0.0, 0.0);
        assert_eq!(
            b.at_altitude(1.1).moments(&nan, &-Vec3::z()),
            CapMoments::default()
        );
        let far = b.at_altitude(f64::INFINITY).moments(&n, &-Vec3::z());
        assert_eq!(far, CapMoments::default());
        let (below, on) = (b.at_altitude(0.5), b.at_altitude(1.0));
        assert_eq!(below.moments(&n, &-Vec3::z()), on.moments(&n, &-Vec3::z()));
        assert_eq!(
            b.at_altitude(f64::NAN).moments(&n, &-Vec3::z()),
            on.moments(&n, &-Vec3::z())
        );
    }

    /// The cost of the exact sums and of the table per plate, over a box's six faces at
    /// several attitudes (all three regimes) at 500 km. Release:
    /// `cargo test -p satsim-environment --release -- --ignored --nocapture cost_per_plate`.
    #[test]
    #[ignore]
    fn cost_per_plate() {
        use std::hint::black_box;
        use std::time::Instant;
        let nadir = -Vec3::z();
        let mut normals = Vec::new();
        for k in 0..16 {
            let q = nalgebra::Rotation3::from_euler_angles(
                0.7 * k as f64,
                0.3 * k as f64,
                1.1 * k as f64,
            );
            for axis in [Vec3::x(), Vec3::y(), Vec3::z()] {
                normals.extend([q * axis, -(q * axis)]);
            }
        }
        let h = 1.0784;
        let cut = normals
            .iter()
            .filter(|n| n.dot(&nadir).abs() * h < 1.0)
            .count();
        let rounds = 20_000;
        let time = |f: &dyn Fn() -> f64| {
            f();
            let start = Instant::now();
            let mut x = 0.0;
            for _ in 0..rounds {
                x += f();
            }
            black_box(x);
            start.elapsed().as_secs_f64() * 1e9 / (rounds * normals.len()) as f64
        };
        let exact = time(&|| {
            normals
                .iter()
                .map(|n| cap_moments(black_box(n), &nadir, black_box(h)).flux.z)
                .sum()
        });
        let table = CapTable::shared();
        let fast = time(&|| {
            let slice = table.at_altitude(black_box(h));
            normals
                .iter()
                .map(|n| slice.moments(black_box(n), &nadir).flux.z)
                .sum()
        });
        let start = Instant::now();
        black_box(CapTable::build());
        let build = start.elapsed().as_secs_f64() * 1e3;
        println!(
            "{} plates ({cut} cut by the horizon): exact {exact:.1} ns, table {fast:.1} ns a \
             plate; the table built in {build:.1} ms",
            normals.len()
        );
    }
}
