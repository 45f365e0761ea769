//! The spacecraft's surface facets in the world frame, and which part of each is lit
//! (self-shadowing): the geometry that the surface-force models (solar radiation pressure,
//! drag) share.
//!
//! [`Facets::of_model`] gathers every body's [`Facet`]s once (body order, then each body's
//! order); [`Facets::place`] carries them into the world frame from the body poses of the
//! tree's forward kinematics; [`Facets::shade`] then computes, for a direction `s` towards the
//! light (or against the flow), the lit fraction of each facet.
//!
//! # Self-shadowing by ray sampling
//!
//! A facet is one-sided: it is dark when it faces away from `s` (`n·s <= 0`). Otherwise its
//! lit fraction is the fraction of its area from which the ray `p + t s`, `t > 0`, meets no
//! other facet. Every facet occludes, whatever its orientation: facets are the surfaces of
//! solids, and a ray that meets the back of a solid's face has met the solid.
//!
//! The fraction is estimated on a `resolution × resolution` midpoint grid over the facet's
//! rectangle, one ray per sample, each ray intersected with the facet's candidate occluders
//! (ray–rectangle: the ray's parameter `t` at the occluder's plane, then the hit's
//! coordinates along the occluder's edges). Candidates are culled cheaply first: an
//! occluder entirely behind the facet along `s` (its largest depth `s·x` no more than the
//! facet's smallest) cannot be met; nor can one whose bounding circle, projected on the
//! plane normal to `s`, misses the facet's; nor one met, over the whole facet, only behind
//! the ray's start or outside its rectangle. The ray parameter and the hit's coordinates are
//! affine in the sample's grid coordinates `(α, β)`, which makes that last cull exact and the
//! rays cheap: along a grid row each occluder blocks the samples of one interval of `β`,
//! found from the three affine tests, so a row's rays are decided together (a bit per
//! sample) with the same answer as one at a time.
//!
//! Occluders met closer than `1e-9` of the two facets' size along the ray are ignored:
//! coincident surfaces, such as the two sides of a thin panel given as facets with opposite
//! normals at the same place, do not shade each other; nor do rays that graze an occluder's
//! plane (`|n·s| < 1e-12`, a set of zero area).
//!
//! Error: each sample stands for a cell of `1/resolution²` of the facet and only cells cut by
//! a shadow's boundary can be misclassified, so the area error is `O(1/resolution)` of the
//! facet per shadow edge crossing it (at most half a cell per grid row or column that a
//! straight edge crosses, `A/(2 resolution)` for an edge along a side); a facet in full
//! light or full shadow is exact.
//!
//! Cost: the culling tests of every pair of `n` facets, `O(n²)`, and, for each lit facet
//! with `m` candidate occluders, `resolution · m` row intervals. From 48 facets on, the
//! facets are first binned by their centroids projected across the light in a grid of
//! cells about a facet's size, and a facet tests only the facets of the cells within its
//! reach (its radius plus the largest): the same candidates as every pair, so the same
//! bits (test `the_grid_finds_the_same_shade_as_every_pair_to_the_bit`), at `O(n)` tests
//! for facets spread over a surface (3000 tiles of an array: 20 ms every pair, 1.9 ms with
//! the grid, test `shade_cost_of_many_facets`; facets heaped in a volume keep many
//! candidates). [`Facets::shade_estimate`] counts the work without sampling, for the scene
//! reader's warning of a costly self-shadowing. Measured (test `shade_cost`, release build, on
//! a 2-core machine shared with other builds) for 26 facets (a bus and three folded panels as
//! boxes, and two more facets), averaged over 64 light directions: 4.5 µs at resolution 1,
//! 10.4 µs at 8, 16.4 µs at 16; [`Facets::place`] 0.46 µs, [`Facets::shade_none`] 0.02 µs.
//! No call allocates (but for the row mask's growth the first time a resolution above 64 is
//! used).

use satsim_tree::spatial::Vec3;
use satsim_tree::{Data, Facet, Model};

/// Rays closer to parallel with an occluder's plane than this (`|n·s|`) cannot meet it on a
/// set of positive area.
const GRAZING: f64 = 1e-12;

/// Occluders met closer than this fraction of the two facets' size along the ray are the
/// facet's own surface (coincident facets), not occluders.
const COINCIDENT: f64 = 1e-9;

/// A candidate occluder of one facet: the ray parameter `t` and the occluder's rectangle
/// coordinates `u`, `v` of the hit, each `[constant, ∂/∂α, ∂/∂β]` in the lit facet's grid
/// coordinates `α`, `β` (the sample `p = c + α e₀ + β e₁`). The ray meets the occluder when
/// `t > 0` (the coincidence margin taken off) and `|u|, |v| <= 1/2`.
#[derive(Clone, Copy, Debug, Default)]
struct Occluder {
    t: [f64; 3],
    u: [f64; 3],
    v: [f64; 3],
    /// `1 / ∂/∂β` of `t`, `u`, `v` (infinite where it is 0).
    inv: [f64; 3],
}

impl Occluder {
    /// Whether the ray from sample `(α, β)` meets the occluder: the one-ray test that
    /// [`Occluder::row`] solves for a whole row at once (the reference of the tests).
    #[cfg(test)]
    fn blocks(&self, alpha: f64, beta: f64) -> bool {
        let at = |c: &[f64; 3]| c[0] + alpha * c[1] + beta * c[2];
        at(&self.t) > 0.0 && at(&self.u).abs() <= 0.5 && at(&self.v).abs() <= 0.5
    }

    /// The interval of `β` where the ray from `(α, β)` meets the occluder (empty when the
    /// lower bound exceeds the upper): along a row the three tests are affine in `β`.
    #[inline]
    fn row(&self, alpha: f64) -> (f64, f64) {
        let mut range = (f64::NEG_INFINITY, f64::INFINITY);
        let (t, u, v, inv) = (&self.t, &self.u, &self.v, &self.inv);
        clip(
            t[0] + alpha * t[1],
            t[2],
            inv[0],
            0.0,
            f64::INFINITY,
            &mut range,
        );
        clip(u[0] + alpha * u[1], u[2], inv[1], -0.5, 0.5, &mut range);
        clip(v[0] + alpha * v[1], v[2], inv[2], -0.5, 0.5, &mut range);
        range
    }
}

/// Narrows `range` to the `β` where `c + β d` lies in `[lo, hi]` (`inv = 1/d`).
#[inline]
fn clip(c: f64, d: f64, inv: f64, lo: f64, hi: f64, range: &mut (f64, f64)) {
    if d > 0.0 {
        range.0 = range.0.max((lo - c) * inv);
        range.1 = range.1.min((hi - c) * inv);
    } else if d < 0.0 {
        range.0 = range.0.max((hi - c) * inv);
        range.1 = range.1.min((lo - c) * inv);
    } else if c < lo || c > hi {
        *range = (f64::INFINITY, f64::NEG_INFINITY);
    }
}

/// Sets bits `first..=last` of the mask `row` (64 bits a word).
fn mark(row: &mut [u64], first: usize, last: usize) {
    for (w, word) in row
        .iter_mut()
        .enumerate()
        .take(last / 64 + 1)
        .skip(first / 64)
    {
        let lo = first.saturating_sub(64 * w);
        let hi = (last - 64 * w).min(63);
        // Bits lo..=hi of this word.
        *word |= (u64::MAX >> (63 - hi)) & (u64::MAX << lo);
    }
}

/// Below this many facets [`Facets::shade`] tests every pair; from it on, it bins the
/// facets in a [`Grid`] first (same occluders, fewer tests).
const GRID_MIN: usize = 48;

/// The facets' centroids projected on the plane normal to the light, binned in square
/// cells: the candidate occluders of a facet are then read from the cells within its reach
/// (its radius plus the largest) instead of from every facet. Storage is reserved when the
/// facets are gathered; building and reading it allocate nothing.
#[derive(Clone, Debug, Default)]
struct Grid {
    /// Per facet: its projected centroid's coordinates along two axes of the plane.
    at: Vec<[f64; 2]>,
    /// Per facet: its cell.
    cell: Vec<usize>,
    /// Per cell: where its facets start in `items` (one entry more than cells).
    start: Vec<usize>,
    /// The facets, cell by cell.
    items: Vec<usize>,
    /// The lower corner of the cells (m).
    origin: [f64; 2],
    /// A cell's side (m).
    side: f64,
    /// Cells along each axis.
    cells: [usize; 2],
    /// The largest facet radius (m).
    r_max: f64,
}

impl Grid {
    /// Storage for `n` facets: at most `(⌈2√n⌉ + 1)²` cells.
    fn new(n: usize) -> Self {
        let per_side = Self::per_side(n) + 1;
        Self {
            at: vec![[0.0; 2]; n],
            cell: vec![0; n],
            start: Vec::with_capacity(per_side * per_side + 1),
            items: vec![0; n],
            ..Self::default()
        }
    }

    fn per_side(n: usize) -> usize {
        ((4 * n) as f64).sqrt().ceil().max(1.0) as usize
    }

    /// Bins the facets (`across`: centroids projected on the plane normal to the unit `s`,
    /// `radius`: their circumscribed radii); `false`, binning nothing, when a coordinate is
    /// not finite.
    fn build(&mut self, s: &Vec3, across: &[Vec3], radius: &[f64]) -> bool {
        let n = across.len();
        let e = if s.x.abs() < 0.9 {
            Vec3::x()
        } else {
            Vec3::y()
        };
        let a = (e - s * s.dot(&e)).normalize();
        let b = s.cross(&a);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let (mut r_max, mut r_sum) = (0.0f64, 0.0);
        for (k, c) in across.iter().enumerate() {
            let p = [c.dot(&a), c.dot(&b)];
            for d in 0..2 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
            r_max = r_max.max(radius[k]);
            r_sum += radius[k];
            self.at[k] = p;
        }
        if !(lo.iter().chain(&hi).all(|v| v.is_finite()) && r_sum.is_finite()) {
            return false;
        }
        // Cells about a facet's diameter, no more than about 4n of them.
        let per_side = Self::per_side(n) as f64;
        let side = (2.0 * r_sum / n as f64)
            .max((hi[0] - lo[0]) / per_side)
            .max((hi[1] - lo[1]) / per_side);
        self.side = if side > 0.0 { side } else { 1.0 };
        self.origin = lo;
        self.r_max = r_max;
        for d in 0..2 {
            self.cells[d] = ((hi[d] - lo[d]) / self.side) as usize + 1;
        }
        let count = self.cells[0] * self.cells[1];
        self.start.clear();
        self.start.resize(count + 1, 0);
        for k in 0..n {
            let c = self.cell_of(self.at[k]);
            self.cell[k] = c;
            self.start[c + 1] += 1;
        }
        for c in 0..count {
            self.start[c + 1] += self.start[c];
        }
        // Counting sort: `start[c]` runs ahead as cell c fills, then is set back.
        for k in 0..n {
            let c = self.cell[k];
            self.items[self.start[c]] = k;
            self.start[c] += 1;
        }
        for c in (0..count).rev() {
            self.start[c + 1] = self.start[c];
        }
        self.start[0] = 0;
        true
    }

    /// The cell index along axis `d` of coordinate `x` (clamped to the grid).
    fn index(&self, d: usize, x: f64) -> usize {
        (((x - self.origin[d]) / self.side).max(0.0) as usize).min(self.cells[d] - 1)
    }

    fn cell_of(&self, p: [f64; 2]) -> usize {
        self.index(1, p[1]) * self.cells[0] + self.index(0, p[0])
    }

    /// The cells `(x range, y range)` holding every facet whose projected centroid lies
    /// within `reach` of facet `k`'s, with a margin for the round-off of the projection.
    fn around(&self, k: usize, reach: f64) -> ([usize; 2], [usize; 2]) {
        let p = self.at[k];
        let r = reach * (1.0 + 1e-9) + 1e-9 * (p[0].abs() + p[1].abs() + self.side);
        (
            [self.index(0, p[0] - r), self.index(0, p[0] + r)],
            [self.index(1, p[1] - r), self.index(1, p[1] + r)],
        )
    }
}

/// Half the range of the affine form `c[0] + α c[1] + β c[2]` over `|α|, |β| <= 1/2`.
fn half_range(c: &[f64; 3]) -> f64 {
    0.5 * (c[1].abs() + c[2].abs())
}

/// Every facet of a model, with its world-frame geometry and lit fraction. Built once per
/// model; [`Facets::place`] and [`Facets::shade`] write into preallocated storage.
#[derive(Clone, Debug)]
pub struct Facets {
    /// Per facet: the body carrying it.
    body: Vec<usize>,
    /// Per facet: as given (body frame, unit normal).
    facet: Vec<Facet>,
    /// Body-frame centroid (m) as placed: the given one, plus the deflection of a flexible
    /// body's facet ([`Facets::place_deflected`]).
    at: Vec<Vec3>,
    /// World centroid (m), relative to the tree's reference point.
    centroid: Vec<Vec3>,
    /// World unit normal.
    normal: Vec<Vec3>,
    /// World edges (m).
    edges: Vec<[Vec3; 2]>,
    /// The reciprocal basis of the edges in the facet's plane, `g₀ = e₁ × n / A`,
    /// `g₁ = n × e₀ / A`: `(x − c)·gᵢ` are a point's coordinates along the edges.
    dual: Vec<[Vec3; 2]>,
    /// Radius of the facet's circumscribed circle (m).
    radius: Vec<f64>,
    /// Lit fraction, `[0, 1]`, from the last [`Facets::shade`] or [`Facets::shade_none`].
    lit: Vec<f64>,
    /// Scratch of [`Facets::shade`], per facet: its depth range `[lo, hi]` along `s`.
    depth: Vec<[f64; 2]>,
    /// Scratch of [`Facets::shade`], per facet: its centroid projected on the plane normal
    /// to `s`.
    across: Vec<Vec3>,
    /// Scratch: the candidate occluders of the facet being shaded (capacity `len`).
    occluders: Vec<Occluder>,
    /// Scratch: the blocked samples of one grid row, a bit each (grown with the largest
    /// resolution used).
    row: Vec<u64>,
    /// Scratch of [`Facets::shade`]: the facets binned across the light (from
    /// [`GRID_MIN`] facets on).
    grid: Grid,
}

impl Facets {
    /// The facets of the model an `[effects.<name>]` section applies to; none is an error at
    /// the section's line saying how to give some.
    pub fn of_section(section: &super::Section) -> Result<Self, satsim_tree::io::FileError> {
        let facets = Self::of_model(section.model());
        if facets.is_empty() {
            return Err(section.error_here(format!(
                "[effects.{}] needs facets: give a body `facets = [...]` or `facets_from_shape = {{ ... }}` in the model file",
                section.name()
            )));
        }
        Ok(facets)
    }
    /// Every body's facets, in body order (the model's depth-first order, each body's facets
    /// in the order given), with the index of the body carrying each. Their world geometry
    /// is unset until [`Facets::place`]; every facet is lit until [`Facets::shade`].
    pub fn of_model(model: &Model) -> Self {
        let mut body = Vec::new();
        let mut facet = Vec::new();
        for (i, b) in model.bodies().iter().enumerate() {
            for f in b.facets() {
                body.push(i);
                facet.push(*f);
            }
        }
        let n = facet.len();
        Self {
            body,
            at: facet.iter().map(|f| f.at).collect(),
            centroid: facet.iter().map(|f| f.at).collect(),
            normal: facet.iter().map(|f| f.normal).collect(),
            edges: facet.iter().map(|f| f.edges).collect(),
            dual: vec![[Vec3::zeros(); 2]; n],
            radius: vec![0.0; n],
            lit: vec![1.0; n],
            depth: vec![[0.0; 2]; n],
            across: vec![Vec3::zeros(); n],
            occluders: Vec::with_capacity(n),
            row: vec![0; 1],
            grid: if n >= GRID_MIN {
                Grid::new(n)
            } else {
                Grid::default()
            },
            facet,
        }
    }
    /// Number of facets.
    pub fn len(&self) -> usize {
        self.facet.len()
    }
    /// Whether the model has no facet.
    pub fn is_empty(&self) -> bool {
        self.facet.is_empty()
    }
    /// The body carrying facet `k` (an index into [`Model::bodies`]).
    pub fn body(&self, k: usize) -> usize {
        self.body[k]
    }
    /// Facet `k` as given (body frame, unit normal).
    pub fn facet(&self, k: usize) -> &Facet {
        &self.facet[k]
    }
    /// Facet `k`'s centroid in its body's frame (m) as of the last [`Facets::place`] (the
    /// given one) or [`Facets::place_deflected`] (moved by the deflection): where its loads
    /// act on the body.
    pub fn at(&self, k: usize) -> &Vec3 {
        &self.at[k]
    }
    /// Facet `k`'s centroid in the world frame (m), relative to the tree's reference point,
    /// as of the last [`Facets::place`].
    pub fn centroid(&self, k: usize) -> &Vec3 {
        &self.centroid[k]
    }
    /// Facet `k`'s unit outward normal in the world frame, as of the last [`Facets::place`].
    pub fn normal(&self, k: usize) -> &Vec3 {
        &self.normal[k]
    }
    /// Facet `k`'s edges in the world frame (m), as of the last [`Facets::place`].
    pub fn edges(&self, k: usize) -> &[Vec3; 2] {
        &self.edges[k]
    }
    /// Facet `k`'s lit fraction in `[0, 1]`, as of the last [`Facets::shade`] or
    /// [`Facets::shade_none`].
    pub fn lit(&self, k: usize) -> f64 {
        self.lit[k]
    }
    /// Every facet's lit fraction, in facet order.
    pub fn lit_fractions(&self) -> &[f64] {
        &self.lit
    }

    /// Places the facets in the world frame from the body poses in `data` (after the tree's
    /// forward kinematics: `data.rotation`, `data.position`): centroid
    /// `position[i] + rotation[i] · at`, normal `rotation[i] · n`, edges `rotation[i] · e`.
    pub fn place(&mut self, data: &Data) {
        self.place_deflected(data, |_| None);
    }

    /// [`Facets::place`] with facet `k` moved by `deflection(k) = Some((u, θ))` (body axes):
    /// its centroid by `u`, its normal and edges turned by the small rotation `θ`
    /// (`v + θ × v`, the normal renormalised): a flexible body's facet riding its deflected
    /// shape ([`super::modal_loads::FacetModes::deflection`]). `None` leaves it as given.
    pub fn place_deflected(
        &mut self,
        data: &Data,
        deflection: impl Fn(usize) -> Option<(Vec3, Vec3)>,
    ) {
        for (k, f) in self.facet.iter().enumerate() {
            let i = self.body[k];
            let r = &data.rotation[i];
            let (at, n, e) = match deflection(k) {
                Some((u, theta)) => (
                    f.at + u,
                    (f.normal + theta.cross(&f.normal)).normalize(),
                    f.edges.map(|e| e + theta.cross(&e)),
                ),
                None => (f.at, f.normal, f.edges),
            };
            let n = r * n;
            let [e0, e1] = [r * e[0], r * e[1]];
            self.at[k] = at;
            self.centroid[k] = data.position[i] + r * at;
            self.normal[k] = n;
            self.edges[k] = [e0, e1];
            self.dual[k] = [e1.cross(&n) / f.area, n.cross(&e0) / f.area];
            // The corners are c ± e₀/2 ± e₁/2.
            self.radius[k] = 0.5 * (e0 + e1).norm().max((e0 - e1).norm());
        }
    }

    /// The lit fractions without occlusion: `lit(k) = 1` if `n·s > 0`, else 0 (`s` towards
    /// the light, world frame), for use without self-shadowing.
    pub fn shade_none(&mut self, s: &Vec3) {
        for (lit, n) in self.lit.iter_mut().zip(&self.normal) {
            *lit = if n.dot(s) > 0.0 { 1.0 } else { 0.0 };
        }
    }

    /// The lit fractions with self-shadowing for the unit direction `s` towards the light
    /// (world frame), each facet sampled on a `resolution × resolution` midpoint grid (see
    /// the module's documentation for the method, its error and its cost). `resolution` 0
    /// is taken as 1. Call after [`Facets::place`]. No allocation, except that the row mask
    /// (a bit per sample of a grid row, 64 to start with) grows the first time a larger
    /// resolution is used.
    pub fn shade(&mut self, s: &Vec3, resolution: usize) {
        self.shade_by(s, resolution, self.len() >= GRID_MIN);
    }

    /// [`Facets::shade`], the candidate occluders read from a [`Grid`] (`grid`) or from
    /// every pair: the same candidates either way, so the same bits.
    fn shade_by(&mut self, s: &Vec3, resolution: usize, grid: bool) {
        let r = resolution.max(1);
        let cells = (r * r) as f64;
        let words = r.div_ceil(64);
        if self.row.len() < words {
            self.row.resize(words, 0);
        }
        for k in 0..self.len() {
            let c = self.centroid[k];
            let [e0, e1] = self.edges[k];
            let (mid, half) = (c.dot(s), 0.5 * (e0.dot(s).abs() + e1.dot(s).abs()));
            self.depth[k] = [mid - half, mid + half];
            self.across[k] = c - s * mid;
        }
        let grid = grid && self.grid.build(s, &self.across, &self.radius);
        for k in 0..self.len() {
            let nk = self.normal[k];
            if nk.dot(s) <= 0.0 {
                self.lit[k] = 0.0;
                continue;
            }
            self.gather_occluders(k, s, grid);
            if self.occluders.is_empty() {
                self.lit[k] = 1.0;
                continue;
            }
            let free = self.free_samples(r);
            self.lit[k] = free as f64 / cells;
        }
    }

    /// The work of [`Facets::shade`] for `s` at `resolution`, at the facets' last places:
    /// `(pairs, intervals)`, the facet pairs put to the culling tests and the occluder row
    /// intervals the sampling then solves (`resolution` per candidate occluder of each facet
    /// facing `s`). Its time is about `pairs · 25 ns + intervals · 35 ns` (see
    /// [`Facets::shade_seconds`]).
    pub fn shade_work(&mut self, s: &Vec3, resolution: usize) -> (usize, usize) {
        let r = resolution.max(1);
        for k in 0..self.len() {
            let c = self.centroid[k];
            let [e0, e1] = self.edges[k];
            let (mid, half) = (c.dot(s), 0.5 * (e0.dot(s).abs() + e1.dot(s).abs()));
            self.depth[k] = [mid - half, mid + half];
            self.across[k] = c - s * mid;
        }
        let grid = self.len() >= GRID_MIN && self.grid.build(s, &self.across, &self.radius);
        let (mut pairs, mut intervals) = (0, 0);
        for k in 0..self.len() {
            if self.normal[k].dot(s) <= 0.0 {
                continue;
            }
            pairs += if grid {
                let ([x0, x1], [y0, y1]) = self.grid.around(k, self.radius[k] + self.grid.r_max);
                (y0..=y1)
                    .map(|y| {
                        let row = y * self.grid.cells[0];
                        self.grid.start[row + x1 + 1] - self.grid.start[row + x0]
                    })
                    .sum()
            } else {
                self.len()
            };
            self.gather_occluders(k, s, grid);
            intervals += r * self.occluders.len();
        }
        (pairs, intervals)
    }

    /// The estimated time (s) of one [`Facets::shade`] from its [`Facets::shade_work`]:
    /// 25 ns a pair and 35 ns an interval, as test `shade_cost_of_many_facets` measured
    /// them on 3000 facets (a shared two-core machine, the tests' optimisation; a release
    /// build is faster, so this errs high).
    pub fn shade_seconds(work: (usize, usize)) -> f64 {
        work.0 as f64 * 25e-9 + work.1 as f64 * 35e-9
    }

    /// The estimated time (s) of one [`Facets::shade`] of `model`'s facets at its neutral
    /// pose: the largest over three light directions of [`Facets::shade_seconds`]. `None`
    /// when even every pair occluding every other (`n²` pairs, `resolution · n²` intervals)
    /// would take less than `below` (the facets are then not placed at all).
    pub fn shade_estimate(model: &Model, resolution: usize, below: f64) -> Option<f64> {
        let n = model
            .bodies()
            .iter()
            .map(|b| b.facets().len())
            .sum::<usize>();
        if Self::shade_seconds((n * n, resolution.max(1) * n * n)) < below {
            return None;
        }
        let mut f = Self::of_model(model);
        let mut data = Data::new(model);
        satsim_tree::forward_kinematics(model, &mut data, &model.neutral(), &vec![0.0; model.nv()])
            .ok()?;
        f.place(&data);
        let worst = [
            Vec3::new(0.3, -0.4, 0.8),
            Vec3::new(-0.7, 0.5, 0.3),
            Vec3::new(0.5, 0.6, -0.6),
        ]
        .iter()
        .map(|s| Self::shade_seconds(f.shade_work(&s.normalize(), resolution)))
        .fold(0.0, f64::max);
        Some(worst)
    }

    /// The number of samples of an `r × r` grid whose rays meet none of `self.occluders`.
    /// Row by row: each occluder blocks an interval of the row's samples, marked in a bit
    /// mask.
    fn free_samples(&mut self, r: usize) -> usize {
        let step = 1.0 / r as f64;
        let words = r.div_ceil(64);
        let mut free = 0;
        for a in 0..r {
            let alpha = (a as f64 + 0.5) * step - 0.5;
            let row = &mut self.row[..words];
            row.fill(0);
            for o in &self.occluders {
                let (lo, hi) = o.row(alpha);
                // Samples b with (b + 1/2) step − 1/2 in [lo, hi].
                let first = ((lo + 0.5) * r as f64 - 0.5).ceil().max(0.0);
                let last = ((hi + 0.5) * r as f64 - 0.5).floor().min((r - 1) as f64);
                if first > last {
                    continue;
                }
                mark(row, first as usize, last as usize);
            }
            let blocked: u32 = row.iter().map(|w| w.count_ones()).sum();
            free += r - blocked as usize;
        }
        free
    }

    /// Facet `j` as an occluder of the rays from facet `k` along `s` (`None` when the rays
    /// graze its plane).
    fn occluder(&self, k: usize, j: usize, s: &Vec3) -> Option<Occluder> {
        let (ck, cj) = (self.centroid[k], self.centroid[j]);
        let [e0, e1] = self.edges[k];
        let nj = self.normal[j];
        let d = nj.dot(s);
        if d.abs() < GRAZING {
            return None;
        }
        // t(p) = nⱼ·(cⱼ − p) / (nⱼ·s), with p = cₖ + α e₀ + β e₁.
        let inv_d = 1.0 / d;
        let t = [
            nj.dot(&(cj - ck)) * inv_d,
            -nj.dot(&e0) * inv_d,
            -nj.dot(&e1) * inv_d,
        ];
        // The hit's coordinates (p + t s − cⱼ)·g along the occluder's edges.
        let w = ck - cj;
        let coords = |g: &Vec3| {
            let gs = g.dot(s);
            [
                w.dot(g) + t[0] * gs,
                e0.dot(g) + t[1] * gs,
                e1.dot(g) + t[2] * gs,
            ]
        };
        let [g0, g1] = &self.dual[j];
        // Hits closer than the margin are on the facet's own surface.
        let margin = COINCIDENT * (self.radius[j] + self.radius[k]);
        let (u, v) = (coords(g0), coords(g1));
        Some(Occluder {
            t: [t[0] - margin, t[1], t[2]],
            u,
            v,
            inv: [1.0 / t[2], 1.0 / u[2], 1.0 / v[2]],
        })
    }

    /// Fills `self.occluders` with the facets that may meet a ray from facet `k` along `s`
    /// (with `self.depth` and `self.across` already computed for `s`, and `self.grid` built
    /// for it when `grid`): every facet tested, or only those in the cells within reach.
    fn gather_occluders(&mut self, k: usize, s: &Vec3, grid: bool) {
        self.occluders.clear();
        if !grid {
            for j in 0..self.len() {
                if let Some(o) = self.candidate(k, j, s) {
                    self.occluders.push(o);
                }
            }
            return;
        }
        let ([x0, x1], [y0, y1]) = self.grid.around(k, self.radius[k] + self.grid.r_max);
        for y in y0..=y1 {
            let row = y * self.grid.cells[0];
            for i in self.grid.start[row + x0]..self.grid.start[row + x1 + 1] {
                if let Some(o) = self.candidate(k, self.grid.items[i], s) {
                    self.occluders.push(o);
                }
            }
        }
    }

    /// Facet `j` as an occluder of facet `k` along `s`, unless the cheap tests show that no
    /// ray from `k` can meet it.
    #[inline]
    fn candidate(&self, k: usize, j: usize, s: &Vec3) -> Option<Occluder> {
        // Entirely behind the facet along s: no point of a ray (t > 0) is that deep.
        if j == k || self.depth[j][1] <= self.depth[k][0] {
            return None;
        }
        // Bounding circles, projected on the plane normal to s, apart.
        let reach = self.radius[j] + self.radius[k];
        if (self.across[j] - self.across[k]).norm_squared() > reach * reach {
            return None;
        }
        let o = self.occluder(k, j, s)?;
        // Over the whole facet the hit is behind the ray's start or off the rectangle.
        if o.t[0] + half_range(&o.t) <= 0.0
            || o.u[0].abs() - half_range(&o.u) > 0.5
            || o.v[0].abs() - half_range(&o.v) > 0.5
        {
            return None;
        }
        Some(o)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;
    use satsim_tree::spatial::Mat3;
    use satsim_tree::{BaseKind, Body, BoxShape, Hinge, ModelBuilder, facets_of_box};
    use satsim_tree::{forward_kinematics, io::parse_model};
    use std::path::Path;

    /// One free body carrying `facets`, placed at the neutral pose.
    fn placed(facets: Vec<Facet>) -> Facets {
        let model = ModelBuilder::new(BaseKind::Free)
            .body(Body::new("b", 1.0, Mat3::identity()).with_facets(facets))
            .build()
            .unwrap();
        let mut data = Data::new(&model);
        forward_kinematics(&model, &mut data, &model.neutral(), &[0.0; 6]).unwrap();
        let mut f = Facets::of_model(&model);
        f.place(&data);
        f
    }

    /// A unit square facing +z at `at` (edges along x and y).
    fn square(at: Vec3, normal: Vec3) -> Facet {
        Facet::new(1.0, normal, at)
    }

    /// Two unit squares, the upper one 1 m above: light from `s ∝ (ox, oy, 1)` moves the
    /// upper square's shadow by `(ox, oy)`, so `(1 − |ox|)(1 − |oy|)` of the lower is shaded.
    fn shaded_lower(ox: f64, oy: f64, resolution: usize) -> (f64, f64) {
        let mut f = placed(vec![
            square(Vec3::zeros(), Vec3::z()),
            square(Vec3::z(), Vec3::z()),
        ]);
        f.shade(&Vec3::new(ox, oy, 1.0).normalize(), resolution);
        // Nothing above the upper square.
        assert_eq!(f.lit(1), 1.0);
        (1.0 - f.lit(0), (1.0 - ox.abs()) * (1.0 - oy.abs()))
    }

    #[test]
    fn parallel_squares_shade_the_exact_fraction() {
        // Shadow edges on grid lines: the midpoint rule is exact.
        for r in [8, 16, 32] {
            assert_eq!(shaded_lower(0.5, 0.5, r), (0.25, 0.25));
            assert_eq!(shaded_lower(0.25, -0.5, r), (0.375, 0.375));
        }
        // Edges off the grid: the error is at most half a cell per grid row crossed by each
        // of the two shadow edges, and its worst case over the offsets halves with the
        // resolution.
        let offsets: Vec<(f64, f64)> = (1..20)
            .map(|i| (0.0493 * i as f64, 0.61 - 0.0377 * i as f64))
            .collect();
        let mut worst = Vec::new();
        for r in [8, 16, 32] {
            let mut w: f64 = 0.0;
            for &(ox, oy) in &offsets {
                let (shaded, exact) = shaded_lower(ox, oy, r);
                let err = (shaded - exact).abs();
                // The shadow is a rectangle of sides lx, ly (fractions of the square's): each
                // side's sample count is off by at most half a cell.
                let (lx, ly, h) = (1.0 - ox.abs(), 1.0 - oy.abs(), 0.5 / r as f64);
                let bound = (lx + ly) * h + h * h;
                assert!(err <= bound, "r = {r}, ({ox}, {oy}): {err} > {bound}");
                w = w.max(err);
            }
            worst.push(w);
        }
        assert!(
            worst[1] <= 0.6 * worst[0] && worst[2] <= 0.6 * worst[1],
            "{worst:?}"
        );
        assert!(worst[0] > 0.0, "the sweep must leave edges off the grid");
    }

    /// The row-by-row count is the count of one ray per sample against every other facet,
    /// unculled: random facets (crossing one another or not) and directions.
    #[test]
    fn rows_count_the_samples_one_ray_each() {
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut rand = move || {
            // xorshift64
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut partial = 0;
        for _ in 0..30 {
            let mut unit = || Vec3::new(rand() - 0.5, rand() - 0.5, rand() - 0.5).normalize();
            let facets: Vec<Facet> = (0..8)
                .map(|_| {
                    let (n, dir) = (unit(), unit());
                    let at = unit() * 1.2;
                    Facet::new(1.0, n, at).with_size(0.5 + 0.5 * at.x.abs(), 0.8, dir)
                })
                .collect();
            let mut f = placed(facets);
            let s = unit();
            for r in [1, 3, 8, 16, 70, 130] {
                f.shade(&s, r);
                for k in 0..f.len() {
                    if f.normal(k).dot(&s) <= 0.0 {
                        assert_eq!(f.lit(k), 0.0);
                        continue;
                    }
                    let all: Vec<Occluder> = (0..f.len())
                        .filter(|&j| j != k)
                        .filter_map(|j| f.occluder(k, j, &s))
                        .collect();
                    let step = 1.0 / r as f64;
                    let mut free = 0;
                    for a in 0..r {
                        for b in 0..r {
                            let (alpha, beta) =
                                ((a as f64 + 0.5) * step - 0.5, (b as f64 + 0.5) * step - 0.5);
                            if !all.iter().any(|o| o.blocks(alpha, beta)) {
                                free += 1;
                            }
                        }
                    }
                    assert_eq!(f.lit(k), free as f64 / (r * r) as f64, "facet {k}, r = {r}");
                    if free > 0 && free < r * r {
                        partial += 1;
                    }
                }
            }
        }
        // Enough partly shaded facets for the comparison to mean something.
        assert!(partial > 100, "{partial}");
    }

    #[test]
    fn light_from_behind_and_occluders_behind() {
        let mut f = placed(vec![
            square(Vec3::zeros(), Vec3::z()),
            square(-Vec3::z(), Vec3::z()),
        ]);
        // The square below does not shade the upper one (it is behind along s), whatever
        // the resolution, and is itself shaded fully.
        for r in [1, 8, 16] {
            f.shade(&Vec3::z(), r);
            assert_eq!(f.lit_fractions(), &[1.0, 0.0]);
        }
        // Light from behind: both dark.
        f.shade(&-Vec3::z(), 8);
        assert_eq!(f.lit_fractions(), &[0.0, 0.0]);
        // Grazing light: dark (one-sided, n·s <= 0).
        f.shade(&Vec3::x(), 8);
        assert_eq!(f.lit_fractions(), &[0.0, 0.0]);
        // Without self-shadowing both squares facing the light are lit.
        f.shade_none(&Vec3::new(0.1, 0.0, 1.0).normalize());
        assert_eq!(f.lit_fractions(), &[1.0, 1.0]);
        f.shade_none(&-Vec3::z());
        assert_eq!(f.lit_fractions(), &[0.0, 0.0]);
    }

    #[test]
    fn a_facet_never_shades_itself_nor_its_solid_from_outside() {
        // One facet alone, lit at a slant: fully lit.
        let mut f = placed(vec![square(Vec3::zeros(), Vec3::new(0.6, 0.0, 0.8))]);
        f.shade(&Vec3::new(0.0, 0.6, 0.8), 16);
        assert_eq!(f.lit(0), 1.0);
        // A box alone: its faces towards the light are fully lit, the others dark (its
        // adjacent faces, sharing edges, do not shade one another).
        let faces = facets_of_box(&BoxShape::new(Vec3::new(1.0, 2.0, 3.0)), &Vec3::zeros());
        let mut f = placed(faces.to_vec());
        let s = Vec3::new(0.3, -0.5, 0.8).normalize();
        f.shade(&s, 16);
        for k in 0..6 {
            let towards = f.normal(k).dot(&s) > 0.0;
            assert_eq!(f.lit(k), if towards { 1.0 } else { 0.0 }, "face {k}");
        }
        // A thin panel written as two coincident facets back to back: the lit side is not
        // shaded by its own back.
        let mut f = placed(vec![
            square(Vec3::zeros(), Vec3::z()),
            square(Vec3::zeros(), -Vec3::z()),
        ]);
        f.shade(&Vec3::new(0.2, 0.1, 1.0).normalize(), 16);
        assert_eq!(f.lit_fractions(), &[1.0, 0.0]);
    }

    #[test]
    fn an_occluder_of_any_orientation_shades() {
        // The upper square turned to face down (its back to the lower one) shades the same.
        let mut f = placed(vec![
            square(Vec3::zeros(), Vec3::z()),
            square(Vec3::z(), -Vec3::z()),
        ]);
        f.shade(&Vec3::new(0.5, 0.5, 1.0).normalize(), 16);
        assert_eq!(f.lit_fractions(), &[0.75, 0.0]);
        // A wall (normal +x, y ∈ [−0.5, 0.5], z ∈ [0, 1]) standing on the line x = −0.25 of the
        // lower square: light from s ∝ (−1, 0, 1) carries the ray from (x, y, 0) to the wall
        // at height x + 0.25 <= 0.75, so every point with x >= −0.25 is shaded, though the
        // wall faces away from the light.
        let wall = Facet::new(1.0, Vec3::x(), Vec3::new(-0.25, 0.0, 0.5));
        let mut f = placed(vec![square(Vec3::zeros(), Vec3::z()), wall]);
        f.shade(&Vec3::new(-1.0, 0.0, 1.0).normalize(), 16);
        assert_eq!(f.lit(0), 0.25);
        // The wall faces away from that light.
        assert_eq!(f.lit(1), 0.0);
    }

    /// A bus (a 2 m cube from `facets_from_shape`) and a panel folded flat over its +z face,
    /// 0.5 m above it, hinged about y: the panel is the 1 m square x ∈ [0, 1],
    /// y ∈ [−0.8, 0.2] at z = 1.5, with a facet on each side.
    const FOLDED: &str = r#"
[[body]]
name = "bus"
mass = 500
inertia = [[40, 0, 0], [0, 40, 0], [0, 0, 40]]
shape = { box = [2, 2, 2] }
facets_from_shape = { specular = 0.1, diffuse = 0.2 }

[[body]]
name = "panel"
mass = 10
inertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
facets = [
  { area = 1, normal = [0, 0, 1], at = [0.5, -0.3, 0] },
  { area = 1, normal = [0, 0, -1], at = [0.5, -0.3, 0] },
]

[[hinge]]
name = "fold"
parent = "bus"
child = "panel"
axis = [0, 1, 0]
at = [0, 0, 1.5]
"#;

    #[test]
    fn a_folded_panel_shades_the_bus_face_below_it() {
        let (model, _) = parse_model(FOLDED, Path::new("folded.toml")).unwrap();
        let mut data = Data::new(&model);
        let mut f = Facets::of_model(&model);
        assert_eq!(f.len(), 8);
        assert_eq!((f.body(0), f.body(6), f.body(7)), (0, 1, 1));
        assert_eq!(f.facet(4).specular, 0.1);
        // Light from s ∝ (−0.8, 0.6, 1): a ray from the bus's +z face (z = 1) rises 0.5 m
        // to the panel while moving (−0.4, +0.3): it meets the panel when x − 0.4 ∈ [0, 1]
        // and y + 0.3 ∈ [−0.8, 0.2], i.e. x ∈ [0.4, 1] (the face ends at 1) and
        // y ∈ [−1, −0.1] (the face starts at −1): 0.6 × 0.9 = 0.54 of the face's 4 m².
        let s_body = Vec3::new(-0.8, 0.6, 1.0).normalize();
        let exact = 1.0 - 0.54 / 4.0;
        // The same in any attitude of the spacecraft, the light turning with it.
        let attitude = UnitQuaternion::from_euler_angles(0.3, -1.1, 2.0);
        let mut q = model.neutral();
        q[..4].copy_from_slice(&[attitude.w, attitude.i, attitude.j, attitude.k]);
        q[4..7].copy_from_slice(&[7.0, -3.0, 2.0]);
        for (q, s) in [(model.neutral(), s_body), (q, attitude * s_body)] {
            forward_kinematics(&model, &mut data, &q, &vec![0.0; model.nv()]).unwrap();
            f.place(&data);
            let panel_centre = data.position[1] + data.rotation[1] * Vec3::new(0.5, -0.3, 0.0);
            assert!((f.centroid(6) - panel_centre).norm() < 1e-12);
            for r in [8, 16, 32] {
                f.shade(&s, r);
                let err = (f.lit(4) - exact).abs();
                // Two shadow edges cross the face, each at most half a cell per row
                // (of the face's 4 m²: shaded area 0.54 = 13.5% of it).
                assert!(err <= 1.0 / r as f64, "r = {r}: {} vs {exact}", f.lit(4));
                // −x faces the light and nothing is in its way; +x, ±y and −z face away
                // (the ±y faces: s·(±y) = ±0.6/‖s‖, so +y is lit: nothing shades it).
                assert_eq!(f.lit(1), 1.0);
                assert_eq!(f.lit(2), 1.0);
                for k in [0, 3, 5] {
                    assert_eq!(f.lit(k), 0.0, "face {k}");
                }
                // The panel's top is in full light, its back dark.
                assert_eq!((f.lit(6), f.lit(7)), (1.0, 0.0));
            }
        }
        // Turned 180° about the hinge (y), the panel covers x ∈ [−1, 0] upside down: the
        // ray meets it when x − 0.4 ∈ [−1, 0], i.e. x ∈ [−0.6, 0.4], so 1.0 × 0.9 of the face
        // is shaded.
        let mut q = model.neutral();
        q[7] = std::f64::consts::PI;
        forward_kinematics(&model, &mut data, &q, &vec![0.0; model.nv()]).unwrap();
        f.place(&data);
        assert!((f.normal(6) + Vec3::z()).norm() < 1e-15);
        f.shade(&s_body, 16);
        assert!((f.lit(4) - (1.0 - 0.9 / 4.0)).abs() <= 1.0 / 16.0);
        // The panel's faces swapped: the former back (now up) is lit.
        assert_eq!((f.lit(6), f.lit(7)), (0.0, 1.0));
    }

    /// A bus, three panels as thin boxes in a row beyond its +y face, and two more facets:
    /// 26 facets.
    fn spacecraft() -> (Model, Data) {
        let i = Mat3::identity();
        let panel_box = BoxShape::new(Vec3::new(1.0, 2.0, 0.02));
        let mut b = ModelBuilder::new(BaseKind::Free).body(
            Body::new("bus", 500.0, i * 40.0).with_facets(
                facets_of_box(&BoxShape::new(Vec3::new(1.5, 1.5, 1.5)), &Vec3::zeros())
                    .into_iter()
                    .chain([
                        Facet::new(0.5, Vec3::z(), Vec3::new(0.0, 0.0, 1.0)),
                        Facet::new(0.3, -Vec3::x(), Vec3::new(-1.0, 0.0, 0.3)),
                    ]),
            ),
        );
        for (k, parent) in ["bus", "p1", "p2"].iter().enumerate() {
            let name = format!("p{}", k + 1);
            b = b
                .body(
                    Body::new(&name, 10.0, i)
                        .with_facets(facets_of_box(&panel_box, &Vec3::zeros())),
                )
                .hinge(
                    Hinge::revolute(format!("h{}", k + 1), *parent, &name, Vec3::x())
                        .at(Vec3::new(0.0, if k == 0 { 0.75 } else { 1.0 }, 0.0))
                        .child_at(Vec3::new(0.0, -1.0, 0.0)),
                );
        }
        let model = b.build().unwrap();
        let data = Data::new(&model);
        (model, data)
    }

    /// `n` facets scattered in a 4 m cube: random sizes (0.01 to 0.5 m²), normals and
    /// in-plane turns, on one body at the neutral pose.
    fn scattered(n: usize, seed: u64) -> Facets {
        let mut state = seed;
        let mut uniform = move || {
            // xorshift64*: enough for a test's scatter.
            state ^= state >> 12;
            state ^= state << 25;
            state ^= state >> 27;
            (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
        };
        let facets: Vec<Facet> = (0..n)
            .map(|_| {
                let at = Vec3::new(uniform(), uniform(), uniform()) * 4.0;
                let normal = Vec3::new(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5);
                let area = 0.01 + 0.49 * uniform();
                let mut f = Facet::new(area, normal.normalize(), at);
                // Turned in its plane, and stretched into a rectangle.
                let turn = UnitQuaternion::from_axis_angle(
                    &nalgebra::Unit::new_normalize(normal),
                    6.0 * uniform(),
                );
                let stretch = 0.3 + 2.0 * uniform();
                f.edges = [turn * f.edges[0] * stretch, turn * f.edges[1] / stretch];
                f
            })
            .collect();
        placed(facets)
    }

    #[test]
    fn the_grid_finds_the_same_shade_as_every_pair_to_the_bit() {
        for (n, seed) in [(GRID_MIN, 7), (300, 11), (1000, 13)] {
            let mut f = scattered(n, seed);
            let mut partly = 0;
            for k in 0..24 {
                let a = k as f64 * 0.9;
                let s = Vec3::new(a.cos(), (1.7 * a).sin(), a.sin() - 0.2).normalize();
                for r in [1, 8] {
                    f.shade_by(&s, r, false);
                    let every: Vec<u64> = f.lit.iter().map(|l| l.to_bits()).collect();
                    f.shade_by(&s, r, true);
                    let grid: Vec<u64> = f.lit.iter().map(|l| l.to_bits()).collect();
                    assert_eq!(every, grid, "{n} facets, s = {s:?}, resolution {r}");
                    partly += f.lit.iter().filter(|l| **l > 0.0 && **l < 1.0).count();
                }
            }
            // The scatter shades: the comparison is not of facets all lit or all dark.
            assert!(partly > n, "{n} facets: {partly} partly lit");
            // `shade` takes the grid from GRID_MIN facets on.
            f.shade(&Vec3::z(), 8);
            let shaded = f.lit.clone();
            f.shade_by(&Vec3::z(), 8, false);
            assert_eq!(shaded, f.lit);
        }
    }

    /// What the grid buys (run with `--release -- --ignored --nocapture`): `shade` on 3000
    /// scattered facets and on an array of 3000 tiles, every pair against the grid.
    #[test]
    #[ignore = "timing: run in release"]
    fn shade_cost_of_many_facets() {
        // 3000 tiles of 0.1 m on a 5 m × 6 m array (both sides), tilted to the light.
        let tiles: Vec<Facet> = (0..1500)
            .flat_map(|k| {
                let at = Vec3::new((k % 50) as f64 * 0.1, (k / 50) as f64 * 0.2, 0.0);
                [
                    Facet::new(0.01, Vec3::z(), at),
                    Facet::new(0.01, -Vec3::z(), at),
                ]
            })
            .collect();
        for (what, mut f) in [
            ("3000 scattered facets", scattered(3000, 5)),
            ("3000 tiles", placed(tiles)),
        ] {
            let s = Vec3::new(0.3, -0.4, 0.8).normalize();
            for grid in [false, true] {
                let start = std::time::Instant::now();
                for _ in 0..5 {
                    f.shade_by(&s, 8, grid);
                }
                println!(
                    "{what}, resolution 8, {}: {:.2} ms per call",
                    if grid { "grid" } else { "every pair" },
                    start.elapsed().as_secs_f64() / 5.0 * 1e3
                );
            }
            for r in [1, 8, 32] {
                let work = f.shade_work(&s, r);
                let start = std::time::Instant::now();
                for _ in 0..5 {
                    f.shade(&s, r);
                }
                println!(
                    "{what}, resolution {r}: {work:?} (pairs, intervals), {:.2} ms per call, \
                     estimated {:.2} ms",
                    start.elapsed().as_secs_f64() / 5.0 * 1e3,
                    Facets::shade_seconds(work) * 1e3
                );
            }
        }
    }

    /// The cost of `shade` for 26 facets (run with `--release -- --ignored --nocapture`).
    #[test]
    #[ignore = "timing: run in release"]
    fn shade_cost() {
        let (model, mut data) = spacecraft();
        let mut f = Facets::of_model(&model);
        assert_eq!(f.len(), 26);
        let mut q = model.neutral();
        // The array folded in a zig-zag, so that the panels shade one another and the bus.
        q[7..10].copy_from_slice(&[0.4, -0.8, 0.8]);
        forward_kinematics(&model, &mut data, &q, &vec![0.0; model.nv()]).unwrap();
        f.place(&data);
        let directions: Vec<Vec3> = (0..64)
            .map(|k| {
                let a = k as f64 * 0.7;
                Vec3::new(a.cos(), 0.5 * (1.3 * a).sin(), a.sin() + 0.3).normalize()
            })
            .collect();
        // The fastest of 40 batches over the 64 directions: the least disturbed by other
        // work on the machine.
        let batch = |f: &mut Facets, shade: &dyn Fn(&mut Facets, &Vec3)| {
            (0..40)
                .map(|_| {
                    let start = std::time::Instant::now();
                    for s in &directions {
                        shade(f, s);
                    }
                    start.elapsed().as_secs_f64() / directions.len() as f64
                })
                .fold(f64::INFINITY, f64::min)
        };
        for r in [1, 8, 16] {
            let per = batch(&mut f, &|f, s| f.shade(s, r));
            let mut lit = 0.0;
            let mut shaded = 0.0;
            for s in &directions {
                f.shade(s, r);
                lit += f.lit_fractions().iter().sum::<f64>();
                f.shade_none(s);
                shaded += f.lit_fractions().iter().sum::<f64>();
            }
            println!(
                "shade, 26 facets, resolution {r}: {:.2} µs per call (lit area fraction summed over facets: {:.2} of {:.2} facing the light, mean)",
                per * 1e6,
                lit / directions.len() as f64,
                shaded / directions.len() as f64,
            );
        }
        let per = batch(&mut f, &|f, s| f.shade_none(s));
        println!("shade_none, 26 facets: {:.3} µs per call", per * 1e6);
        let start = std::time::Instant::now();
        for _ in 0..1000 {
            f.place(&data);
        }
        println!(
            "place, 26 facets: {:.3} µs per call",
            start.elapsed().as_secs_f64() / 1000.0 * 1e6
        );
    }
}
