//! The Euler-Bernoulli cantilever of the model file's `beam` shorthand: its clamped-free mode
//! shapes, natural frequencies and the modal integrals a [`super::ModalData`] needs.
//!
//! Mode `n` of a uniform cantilever of length `L`, bending stiffness `EI` (N m²) and mass per
//! length `ρA` (kg/m): `βₙL` the `n`-th root of `cos x cosh x = −1`,
//! `ωₙ = (βₙL)² √(EI / (ρA L⁴))` (rad/s), shape
//! `φₙ(x) = cosh βx − cos βx − σ (sinh βx − sin βx)`, `σ = (cosh βL + cos βL) / (sinh βL + sin βL)`,
//! scaled so that `∫₀ᴸ ρA φₙ² dx = 1` (mass-normalised). The hyperbolic terms are evaluated
//! as `e^{βx} (1 − σ) / 2 + e^{−βx} (1 + σ) / 2` with `1 − σ` formed without cancellation,
//! so high modes keep full precision along the whole beam.

use crate::spatial::{Force, Vec3};

/// The first root of `cos x cosh x = −1` (`β₁L`), to double precision.
pub const BETA1_L: f64 = 1.875_104_068_711_961;

/// An Euler-Bernoulli cantilever in a body's frame: clamped at `root`, along `axis`, bending
/// along `bend` (unit, perpendicular).
#[derive(Clone, Debug, PartialEq)]
pub struct Beam {
    /// The clamped end, body frame (m).
    pub root: Vec3,
    /// Unit direction from the root to the tip, body frame.
    pub axis: Vec3,
    /// Unit direction of the deflection, perpendicular to `axis`, body frame.
    pub bend: Vec3,
    /// Length `L` (m), positive.
    pub length: f64,
    /// Bending stiffness `EI` (N m²), positive.
    pub ei: f64,
    /// Mass per length `ρA` (kg/m), positive.
    pub rho_a: f64,
    /// Number of cantilever modes kept, at least 1.
    pub modes: usize,
}

/// The `n`-th root (`n` from 1) of `cos x cosh x = −1`, `βₙL`: bisection of
/// `cos x + 1 / cosh x` (the same roots, bounded) on `(2n − 1) π / 2 ± 0.5` to the last bit.
pub fn beta_l(n: usize) -> f64 {
    assert!(n >= 1, "modes count from 1");
    let f = |x: f64| x.cos() + 1.0 / x.cosh();
    let c = (2 * n - 1) as f64 * std::f64::consts::FRAC_PI_2;
    let (mut lo, mut hi) = if n == 1 {
        (1.0, 2.07)
    } else {
        (c - 0.5, c + 0.5)
    };
    let flo = f(lo);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if (f(mid) > 0.0) == (flo > 0.0) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// One cantilever mode: `β` (1/m), `σ`, `1 − σ` and the mass-normalising factor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CantileverMode {
    beta: f64,
    sigma: f64,
    one_minus_sigma: f64,
    scale: f64,
    length: f64,
}

impl CantileverMode {
    /// Mode `n` (from 1) of a cantilever of length `length` and mass per length `rho_a`.
    pub fn new(n: usize, length: f64, rho_a: f64) -> Self {
        let bl = beta_l(n);
        let (sh, ch, s, c) = (bl.sinh(), bl.cosh(), bl.sin(), bl.cos());
        let den = sh + s;
        let sigma = (ch + c) / den;
        // 1 − σ = (sinh − cosh + sin − cos) / den with sinh − cosh = −e^{−βL}.
        let one_minus_sigma = (-(-bl).exp() + s - c) / den;
        // The unscaled shape has ∫₀ᴸ φ² dx = L (a property of the clamped-free modes).
        Self {
            beta: bl / length,
            sigma,
            one_minus_sigma,
            scale: 1.0 / (rho_a * length).sqrt(),
            length,
        }
    }
    /// `β` (1/m).
    pub fn beta(&self) -> f64 {
        self.beta
    }
    /// `[φ(x), φ'(x), φ''(x)]`, mass-normalised (units 1/√kg, per m, per m²).
    pub fn shape(&self, x: f64) -> [f64; 3] {
        let y = self.beta * x;
        // e^{y} (1 − σ) / 2 stays bounded: (1 − σ) ~ e^{−βL} and y ≤ βL.
        let (ep, em) = (
            0.5 * y.exp() * self.one_minus_sigma,
            0.5 * (-y).exp() * (1.0 + self.sigma),
        );
        let (s, c) = y.sin_cos();
        let b = self.beta;
        [
            self.scale * (ep + em - c + self.sigma * s),
            self.scale * b * (ep - em + s + self.sigma * c),
            self.scale * b * b * (ep + em + c - self.sigma * s),
        ]
    }
    /// The beam's length (m).
    pub fn length(&self) -> f64 {
        self.length
    }
}

/// Gauss-Legendre nodes and weights on `[−1, 1]`, `n` points (Newton on `Pₙ`, to round-off).
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    out
}

/// Panels and points per panel of the beam integrals: 16 panels of 20 Gauss points. The
/// integrands are smooth of wavelength `2π / β`; with `βL ≤ 40` (12 modes) a panel holds
/// at most half a wavelength and 20 points integrate it to round-off (tested: the
/// orthogonality integrals to 1e-12, unchanged at double the panels).
pub const PANELS: usize = 16;
/// Gauss points per panel (see [`PANELS`]).
pub const POINTS: usize = 20;

/// `∫₀ᴸ g(x) dx` by composite Gauss-Legendre quadrature on `panels` panels of the rule `rule`.
pub fn integrate(
    length: f64,
    panels: usize,
    rule: &[(f64, f64)],
    mut g: impl FnMut(f64) -> f64,
) -> f64 {
    let mut sum = 0.0;
    for (x, factor) in nodes(length, panels, rule) {
        sum += factor * g(x);
    }
    sum
}

/// The nodes of [`integrate`], in its order: each `(x, w h / 2)`, `integrate` adding
/// `w h / 2 · g(x)` (`h` the panel's length).
fn nodes(length: f64, panels: usize, rule: &[(f64, f64)]) -> impl Iterator<Item = (f64, f64)> + '_ {
    let h = length / panels as f64;
    (0..panels).flat_map(move |p| {
        let mid = (p as f64 + 0.5) * h;
        rule.iter()
            .map(move |&(x, w)| (mid + 0.5 * h * x, w * 0.5 * h))
    })
}

/// The modes' shapes at the nodes of [`integrate`] over `[0, length]`, each computed once
/// for every integral over them (`[φ, φ', φ'']` of each mode: an exponential pair and a
/// `sincos`). A beam's second-order inertia takes `m (m + 1) + 2m` integrals of products of
/// shapes: with the shapes sampled once, the flexible deployment's scene is read in 15.7 M
/// instructions where it took 24.8 M (callgrind, 2026-12-07), which every run of a campaign
/// pays. The sums are [`integrate`]'s, term for term: the same bits.
struct Sampled {
    /// `(x, w h / 2)` per node.
    nodes: Vec<(f64, f64)>,
    /// Per node, each mode's shape.
    shapes: Vec<[f64; 3]>,
    modes: usize,
}

impl Sampled {
    fn new(modes: &[CantileverMode], length: f64, rule: &[(f64, f64)]) -> Self {
        let nodes: Vec<_> = nodes(length, PANELS, rule).collect();
        let shapes = nodes
            .iter()
            .flat_map(|&(x, _)| modes.iter().map(move |md| md.shape(x)))
            .collect();
        Self {
            nodes,
            shapes,
            modes: modes.len(),
        }
    }

    /// `∫ g(x, shapes(x)) dx`, as [`integrate`] sums it.
    fn integrate(&self, mut g: impl FnMut(f64, &[[f64; 3]]) -> f64) -> f64 {
        let mut sum = 0.0;
        for (&(x, factor), shapes) in self.nodes.iter().zip(self.shapes.chunks(self.modes)) {
            sum += factor * g(x, shapes);
        }
        sum
    }
}

impl Beam {
    /// The beam's modes, `1..=modes`.
    pub fn cantilever_modes(&self) -> Vec<CantileverMode> {
        (1..=self.modes)
            .map(|n| CantileverMode::new(n, self.length, self.rho_a))
            .collect()
    }
    /// The natural frequency of mode `n` (from 1), `(βₙL)² √(EI / (ρA L⁴))` (rad/s).
    pub fn omega(&self, n: usize) -> f64 {
        let bl = beta_l(n);
        bl * bl * (self.ei / (self.rho_a * self.length.powi(4))).sqrt()
    }
    /// The beam's mass `ρA L` (kg).
    pub fn mass(&self) -> f64 {
        self.rho_a * self.length
    }
    /// The axis of the sections' rotation, `axis × bend` (unit): a positive rotation about it
    /// turns `axis` towards `bend`.
    pub fn rotation_axis(&self) -> Vec3 {
        self.axis.cross(&self.bend)
    }
    /// The modal momentum coefficients: per mode `k`, the spatial momentum (body frame, about
    /// its origin) that `η̇ₖ = 1` gives the beam, `[∫ρA r × bend φₖ; bend ∫ρA φₖ]`.
    pub fn momentum_coefficients(&self) -> Vec<Force> {
        let rule = gauss_legendre(POINTS);
        self.cantilever_modes()
            .iter()
            .map(|m| {
                let s1 = self.rho_a * integrate(self.length, PANELS, &rule, |x| m.shape(x)[0]);
                let s2 = self.rho_a * integrate(self.length, PANELS, &rule, |x| x * m.shape(x)[0]);
                Force::new(
                    self.root.cross(&self.bend) * s1 + self.rotation_axis() * s2,
                    self.bend * s1,
                )
            })
            .collect()
    }
    /// The node shapes at a point `p` of the body (body frame, m): the point is carried by
    /// the section at `x = (p − root) · axis` clamped to `[0, L]`; per mode, its translation
    /// `bend φ(x) + (axis × bend) φ'(x) × d` (`d` the point's offset from the section's centre)
    /// and the section's rotation `(axis × bend) φ'(x)`.
    pub fn node(&self, p: &Vec3) -> super::NodeShape {
        let x = (p - self.root).dot(&self.axis).clamp(0.0, self.length);
        let d = p - (self.root + self.axis * x);
        let n = self.rotation_axis();
        let (mut phi, mut psi) = (Vec::new(), Vec::new());
        for m in self.cantilever_modes() {
            let [f, df, _] = m.shape(x);
            phi.push(self.bend * f + (n * df).cross(&d));
            psi.push(n * df);
        }
        super::NodeShape {
            phi,
            psi,
            shortening: None,
        }
    }
}

/// The second-order (in `η`) inertia of a beam on a body spinning at `ω` (body axes), both
/// parts or neither (`stiffening`): with the first alone, bending in the plane of the spin
/// stiffens as `ω₀² + 1.193 Ω²` instead of `ω₀² + 0.193 Ω²`; with the second alone it softens
/// as `ω₀² − Ω²` and diverges once `Ω > ω₀`.
///
/// - The centrifugal stiffening: the axial force `N(x) = ρA ∫ₓᴸ ωᵀ A(ξ) ω dξ` of the
///   centrifugal field `−ω × (ω × r)` along the beam (`A(ξ) = A₀ + ξ A₁`,
///   `A₀ = (r₀·a) 1 − sym(r₀ aᵀ)`, `A₁ = 1 − a aᵀ`) gives the geometric stiffness
///   `K_g(ω) = ∫ N φᵢ' φⱼ' dx = (ωᵀ A₀ ω) J₀ + (ωᵀ A₁ ω) J₁`, with
///   `J₀ = ρA ∫ (L − x) φᵢ' φⱼ' dx` and `J₁ = ρA ∫ (L² − x²)/2 φᵢ' φⱼ' dx` (row-major `m x m`).
/// - The deflection's own rotational inertia `∫ ρA (|u|² 1 − u uᵀ) = A₂ ηᵀη`,
///   `A₂ = 1 − b bᵀ` (mass-orthonormal modes along one `bend` `b`): the deflected sections'
///   centrifugal load, `−(ωᵀ A₂ ω) η` on the modes (the softening of in-plane bending).
/// - The foreshortening's translation: the first moment less `½ (ηᵀ J₀ η) a` and the modal
///   momentum `Pₖ − (J₀ η)ₖ c`, `c = [r₀ × a; a]`. With them the axial load is that of the
///   frame's whole acceleration: `K_g(v)` adds `((ω × a) · v_O) J₀` (the frame origin's
///   centripetal acceleration: a hub's radius for a beam on a hinge off the spin axis), and
///   `P(η)ᵀ a` the frame's linear and angular acceleration along the beam (thrust, spin-up).
#[derive(Clone, Debug, PartialEq)]
pub struct Stiffening {
    /// `A₀` (m), body axes.
    pub a0: crate::spatial::Mat3,
    /// `A₁`, body axes.
    pub a1: crate::spatial::Mat3,
    /// `J₀` (1/m), row-major.
    pub j0: Vec<f64>,
    /// `J₁` (dimensionless), row-major.
    pub j1: Vec<f64>,
    /// `A₂ = 1 − b bᵀ`, body axes.
    pub a2: crate::spatial::Mat3,
    /// The beam's axis `a` (unit), body axes: the foreshortening moves the first moment of
    /// mass by `−½ (ηᵀ J₀ η) a`.
    pub axis: Vec3,
    /// `c = [r₀ × a; a]`: the spatial momentum (about the frame origin) of a uniform axial
    /// velocity of the whole beam per kg; the foreshortening's rate `u̇ₐ` gives the beam the
    /// momentum `−c (η̇ᵀ J₀ η)`, so the modal momentum columns are `Pₖ − (J₀ η)ₖ c`.
    pub shortening: Force,
    /// Per mode `k`, the first-order change of the body's inertia per unit `ηₖ` (mass 0):
    /// first moment `b S₁ₖ`, rotational inertia about the origin
    /// `2 (r₀·b) S₁ₖ 1 − (r₀ S₁ₖ + a S₂ₖ) bᵀ − b (r₀ S₁ₖ + a S₂ₖ)ᵀ` (`S₁ₖ = ∫ ρA φₖ`,
    /// `S₂ₖ = ∫ ρA x φₖ`): the deflected mass, a dynamic imbalance under spin.
    pub first: Vec<crate::spatial::RigidInertia>,
}

/// The integrals over a beam-like structure's length from which its [`Stiffening`] follows
/// (mass-normalised modes `φₖ(x)` along the axis, `x` from the root): what a modes file's
/// `[stiffening]` block gives for modes not computed here.
#[derive(Clone, Debug, PartialEq)]
pub struct StiffeningIntegrals {
    /// `J₀ = ρA ∫ (L − x) φᵢ' φⱼ' dx` (1/m), row-major `m x m`.
    pub j0: Vec<f64>,
    /// `J₁ = ρA ∫ (L² − x²)/2 φᵢ' φⱼ' dx` (dimensionless), row-major `m x m`.
    pub j1: Vec<f64>,
    /// `S₁ₖ = ∫ ρA φₖ dx` (√kg), per mode.
    pub s1: Vec<f64>,
    /// `S₂ₖ = ∫ ρA x φₖ dx` (√kg m), per mode.
    pub s2: Vec<f64>,
}

impl Beam {
    /// The integrals of the beam's second-order inertia (Gauss–Legendre over the length).
    pub fn stiffening_integrals(&self) -> StiffeningIntegrals {
        let rule = gauss_legendre(POINTS);
        let modes = self.cantilever_modes();
        let m = modes.len();
        let (mut j0, mut j1) = (vec![0.0; m * m], vec![0.0; m * m]);
        let l = self.length;
        let at = Sampled::new(&modes, l, &rule);
        for i in 0..m {
            for j in 0..=i {
                let d = |s: &[[f64; 3]]| s[i][1] * s[j][1];
                let x0 = self.rho_a * at.integrate(|x, s| (l - x) * d(s));
                let x1 = self.rho_a * at.integrate(|x, s| 0.5 * (l * l - x * x) * d(s));
                for (k, v) in [(i * m + j, x0), (j * m + i, x0)] {
                    j0[k] = v;
                }
                for (k, v) in [(i * m + j, x1), (j * m + i, x1)] {
                    j1[k] = v;
                }
            }
        }
        let s1 = (0..m)
            .map(|k| self.rho_a * at.integrate(|_, s| s[k][0]))
            .collect();
        let s2 = (0..m)
            .map(|k| self.rho_a * at.integrate(|x, s| x * s[k][0]))
            .collect();
        StiffeningIntegrals { j0, j1, s1, s2 }
    }

    /// The foreshortening at the section of a point `p` (body frame):
    /// `C(ξ) = ∫₀^ξ φ'φ'ᵀ` (`m × m`, row-major; 1/kg), `ξ = (p − root) · axis` clamped to
    /// `[0, L]`. Bent by `η`, the section is drawn towards the root by `½ ηᵀ C(ξ) η` along
    /// `axis`, so a load carried there along the axis (a body hung on it, pulled outwards
    /// by its centrifugal force) does work through the bending: its geometric stiffness.
    pub fn foreshortening(&self, p: &Vec3) -> Vec<f64> {
        let rule = gauss_legendre(POINTS);
        let modes = self.cantilever_modes();
        let m = modes.len();
        let xi = (p - self.root).dot(&self.axis).clamp(0.0, self.length);
        let at = Sampled::new(&modes, xi, &rule);
        let mut c = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..=i {
                let v = at.integrate(|_, s| s[i][1] * s[j][1]);
                c[i * m + j] = v;
                c[j * m + i] = v;
            }
        }
        c
    }

    /// The beam's second-order inertia: the centrifugal-stiffening integrals and the
    /// deflection's own inertia.
    pub fn stiffening(&self) -> Stiffening {
        Stiffening::along(self.root, self.axis, self.bend, self.stiffening_integrals())
    }
}

impl Stiffening {
    /// The second-order inertia of a structure along the unit `axis` from `root` (body
    /// frame), bending along the unit `bend` (normal to `axis`), with the integrals `s`.
    pub fn along(root: Vec3, axis: Vec3, bend: Vec3, s: StiffeningIntegrals) -> Self {
        let a = axis;
        let ra = root * a.transpose();
        let id = crate::spatial::Mat3::identity();
        let (b, r0) = (bend, root);
        let first =
            s.s1.iter()
                .zip(&s.s2)
                .map(|(&s1, &s2)| {
                    let d = r0 * s1 + a * s2;
                    let db = d * b.transpose();
                    crate::spatial::RigidInertia {
                        mass: 0.0,
                        h: b * s1,
                        inertia: id * (2.0 * r0.dot(&b) * s1) - db - db.transpose(),
                    }
                })
                .collect();
        Stiffening {
            a0: id * root.dot(&a) - (ra + ra.transpose()) * 0.5,
            a1: id - a * a.transpose(),
            j0: s.j0,
            j1: s.j1,
            a2: id - bend * bend.transpose(),
            axis: a,
            shortening: Force::new(root.cross(&a), a),
            first,
        }
    }
}

// Row-major m x m matrices against m-vectors: index loops read best. Always inlined: the
// flexible algorithms' instances for a body's mode count unroll them (the same sums).
#[allow(clippy::needless_range_loop)]
impl Stiffening {
    /// `[ηᵀ J₀ η, ηᵀ J₁ η, ηᵀ η]` and their rates `[2 η̇ᵀ J₀ η, 2 η̇ᵀ J₁ η, 2 η̇ᵀ η]`.
    #[inline(always)]
    pub(crate) fn forms(&self, eta: &[f64], etad: &[f64]) -> ([f64; 3], [f64; 3]) {
        let m = eta.len();
        // Sliced to `m × m` first: with `m` known where this is inlined, the loops index
        // without bounds checks (as `j0_row`, `j1_row` and `add_force` below).
        let (j0, j1, etad) = (&self.j0[..m * m], &self.j1[..m * m], &etad[..m]);
        let (mut out, mut rate) = ([0.0; 3], [0.0; 3]);
        for k in 0..m {
            let (mut a, mut b) = (0.0, 0.0);
            for l in 0..m {
                a += j0[k * m + l] * eta[l];
                b += j1[k * m + l] * eta[l];
            }
            out[0] += eta[k] * a;
            out[1] += eta[k] * b;
            out[2] += eta[k] * eta[k];
            rate[0] += 2.0 * etad[k] * a;
            rate[1] += 2.0 * etad[k] * b;
            rate[2] += 2.0 * etad[k] * eta[k];
        }
        (out, rate)
    }
    /// `G = A₀ s₀ + A₁ s₁ − A₂ s₂` (`s` from `forms`): the body's inertia is
    /// `I − G`, the foreshortening taking `½ ωᵀ (A₀ s₀ + A₁ s₁) ω` of kinetic energy and the
    /// deflection adding `½ ωᵀ A₂ ω s₂`.
    #[inline(always)]
    pub(crate) fn g(&self, s: &[f64; 3]) -> crate::spatial::Mat3 {
        self.a0 * s[0] + self.a1 * s[1] - self.a2 * s[2]
    }
    /// `(J₀ x)ₖ`.
    #[inline(always)]
    pub(crate) fn j0_row(&self, k: usize, x: &[f64]) -> f64 {
        let m = x.len();
        let row = &self.j0[k * m..][..m];
        let mut s = 0.0;
        for l in 0..m {
            s += row[l] * x[l];
        }
        s
    }
    /// `(J₁ x)ₖ`.
    #[inline(always)]
    pub(crate) fn j1_row(&self, k: usize, x: &[f64]) -> f64 {
        let m = x.len();
        let row = &self.j1[k * m..][..m];
        let mut s = 0.0;
        for l in 0..m {
            s += row[l] * x[l];
        }
        s
    }
    /// `xᵀ J₀ y`.
    #[inline(always)]
    pub(crate) fn j0_form(&self, x: &[f64], y: &[f64]) -> f64 {
        (0..x.len()).map(|k| x[k] * self.j0_row(k, y)).sum()
    }
    /// `out[k] += (K_g(v) η − (ωᵀ A₂ ω) η)ₖ` (`−∂T/∂η` of the second-order inertia) for the
    /// frame moving at `v = [ω; v_O]`: `K_g(v) = (ωᵀ A₀ ω + (ω × a) · v_O) J₀ + (ωᵀ A₁ ω) J₁`,
    /// the axial load of the centripetal acceleration of the sections (about the frame
    /// origin, `A₀` and `A₁`) and of the frame origin's own velocity product `ω × v_O`.
    #[inline(always)]
    pub(crate) fn add_force(&self, v: &crate::spatial::Motion, eta: &[f64], out: &mut [f64]) {
        let m = eta.len();
        let omega = &v.ang;
        let w0 = omega.dot(&(self.a0 * omega)) + omega.cross(&self.axis).dot(&v.lin);
        let w1 = omega.dot(&(self.a1 * omega));
        let w2 = omega.dot(&(self.a2 * omega));
        let (j0, j1, out) = (&self.j0[..m * m], &self.j1[..m * m], &mut out[..m]);
        for k in 0..m {
            let mut s = -w2 * eta[k];
            for l in 0..m {
                s += (w0 * j0[k * m + l] + w1 * j1[k * m + l]) * eta[l];
            }
            out[k] += s;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sampled shapes give [`integrate`]'s sums bit for bit: each integral as the
    /// shapes' product written out and integrated alone.
    #[test]
    fn sampled_integrals_are_integrates_to_the_bit() {
        let beam = Beam {
            root: Vec3::new(0.1, 0.0, 0.0),
            axis: Vec3::x(),
            bend: Vec3::z(),
            length: 1.7,
            ei: 30.0,
            rho_a: 0.8,
            modes: 4,
        };
        let (rule, modes, l) = (gauss_legendre(POINTS), beam.cantilever_modes(), beam.length);
        let s = beam.stiffening_integrals();
        let m = modes.len();
        for i in 0..m {
            for j in 0..=i {
                let d = |x: f64| modes[i].shape(x)[1] * modes[j].shape(x)[1];
                let x0 = beam.rho_a * integrate(l, PANELS, &rule, |x| (l - x) * d(x));
                let x1 = beam.rho_a * integrate(l, PANELS, &rule, |x| 0.5 * (l * l - x * x) * d(x));
                for k in [i * m + j, j * m + i] {
                    assert_eq!(
                        (s.j0[k].to_bits(), s.j1[k].to_bits()),
                        (x0.to_bits(), x1.to_bits())
                    );
                }
            }
            let s1 = beam.rho_a * integrate(l, PANELS, &rule, |x| modes[i].shape(x)[0]);
            let s2 = beam.rho_a * integrate(l, PANELS, &rule, |x| x * modes[i].shape(x)[0]);
            assert_eq!(
                (s.s1[i].to_bits(), s.s2[i].to_bits()),
                (s1.to_bits(), s2.to_bits())
            );
        }
        for p in [0.9, 5.0] {
            let c = beam.foreshortening(&Vec3::new(p, 0.2, 0.0));
            let xi = (p - 0.1f64).clamp(0.0, l);
            for i in 0..m {
                for j in 0..=i {
                    let v = integrate(xi, PANELS, &rule, |x| {
                        modes[i].shape(x)[1] * modes[j].shape(x)[1]
                    });
                    assert_eq!(c[i * m + j].to_bits(), v.to_bits());
                    assert_eq!(c[j * m + i].to_bits(), v.to_bits());
                }
            }
        }
    }
}
