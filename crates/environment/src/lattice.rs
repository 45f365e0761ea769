//! A lattice in the Earth-fixed frame for smooth fields (the gravity harmonics, the
//! geomagnetic field): values at nodes in geocentric latitude, longitude and radius,
//! interpolated trilinearly in between.
//!
//! Nodes lie at latitude `i·h`, longitude `j·h` and radius `k·h·a/4` (`h` the spacing in
//! radians, `a` = [`crate::R_EARTH`]). A term of degree `n` varies as `cos nλ` in angle and as
//! `r^−(n+2)` in radius: the linear interpolation's error, `(n h)²/8` of it across a cell in
//! angle, is `(n+2)(n+3) (Δr/r)²/8` in radius, which for the dipole (`n = 1`) would be 12
//! times the angular one with cubic cells; a quarter of the angular step in radius brings them
//! level. A near-circular orbit rarely crosses a radial face, so the finer radial step costs
//! almost no fills. A value is a fixed-size array (`N` numbers: Cartesian Earth-fixed
//! components of vectors, never angles), so it has no singularity anywhere: at a pole all
//! the nodes of a longitude row are the same point with the same value, the cell narrows to
//! a wedge, and the interpolant stays continuous and bounded.
//!
//! Each node's value is a function of its indices alone (the position computed from them, and
//! a caller's `generation`, e.g. which coefficient set), so the result is a function of
//! `(generation, r)`: the order of the calls (an integrator's stages, a step redone, a run
//! redone) does not change a bit of it. A few cells are kept, as in
//! [`crate::atmosphere::nrlmsise::MsisTrack`]; a new cell takes the nodes it shares with the
//! kept ones from them and evaluates the others (4 when a low orbit crosses one face). No
//! allocation after construction.
//!
//! Where a position gives no finite coordinates (the Earth's centre, a non-finite input) the
//! function is evaluated there instead.

use crate::{R_EARTH, Vec3};
use std::f64::consts::PI;

/// The cells kept (an integrator's stages within a step meet one or two).
const CELLS: usize = 4;
/// Indices beyond this are not taken (a radius of 1e12 cells is far beyond any orbit).
const MAX_INDEX: f64 = 1e12;

/// One cell: its lowest node's key (generation, latitude, longitude, radius indices) and the
/// values at its 8 nodes (bit 0 of the index: the next latitude, bit 1: the next longitude,
/// bit 2: the next radius).
#[derive(Clone, Copy, Debug)]
struct Cell<const N: usize> {
    key: [i64; 4],
    values: [[f64; N]; 8],
}

/// A field of `N` numbers on the Earth-fixed lattice of the module's page.
#[derive(Clone, Debug)]
pub struct Lattice<const N: usize> {
    /// Cells in 180 degrees (latitude from pole to pole, half a turn in longitude).
    half_turn: i64,
    /// The spacing (rad).
    step: f64,
    /// The radial spacing (m).
    radial: f64,
    cells: [Option<Cell<N>>; CELLS],
    /// The cell replaced next.
    next: usize,
    /// Node evaluations made (for the cost's measurement).
    evaluations: u64,
}

impl<const N: usize> Lattice<N> {
    /// A lattice of spacing `cell_deg` degrees, rounded to divide 90 degrees (`90/cell_deg`
    /// rounded to the nearest whole number of cells, at least 1: the poles are nodes, and at
    /// most `1e12`, beyond which every position's indices are out of range and the field is
    /// evaluated where asked); `None` when `cell_deg` is not a finite number in (0, 90].
    pub fn new(cell_deg: f64) -> Option<Self> {
        if !(cell_deg > 0.0 && cell_deg <= 90.0) {
            return None;
        }
        // Bounded before the integer conversion: 90 / 1e-300 would saturate and overflow.
        let half_turn = 2 * (90.0 / cell_deg).round().clamp(1.0, MAX_INDEX) as i64;
        let step = PI / half_turn as f64;
        Some(Self {
            half_turn,
            step,
            radial: step * R_EARTH / 4.0,
            cells: [None; CELLS],
            next: 0,
            evaluations: 0,
        })
    }

    /// The spacing in latitude and longitude (degrees, after rounding).
    pub fn cell_deg(&self) -> f64 {
        180.0 / self.half_turn as f64
    }

    /// The radial spacing (m).
    pub fn radial_step(&self) -> f64 {
        self.radial
    }

    /// The node evaluations made so far.
    pub fn evaluations(&self) -> u64 {
        self.evaluations
    }

    /// The Earth-fixed position (m) of the node at latitude, longitude and radius indices.
    fn node(&self, i: i64, j: i64, k: i64) -> Vec3 {
        let (sl, cl) = (i as f64 * self.step).sin_cos();
        // The same longitude index modulo a turn is the same node, bit for bit.
        let (so, co) = (j.rem_euclid(2 * self.half_turn) as f64 * self.step).sin_cos();
        let d = k as f64 * self.radial;
        Vec3::new(d * cl * co, d * cl * so, d * sl)
    }

    /// The field at the Earth-fixed position `r` (m): `f`, the field at a node's position,
    /// interpolated. `f` must be a function of `generation` and its argument alone (the
    /// lattice keeps its values under that key).
    pub fn value(
        &mut self,
        generation: i64,
        r: &Vec3,
        mut f: impl FnMut(&Vec3) -> [f64; N],
    ) -> [f64; N] {
        let rho = r.x.hypot(r.y);
        let d = rho.hypot(r.z);
        let u = [
            r.z.atan2(rho) / self.step,
            r.y.atan2(r.x) / self.step,
            d / self.radial,
        ];
        if d == 0.0 || !u.iter().all(|x| x.is_finite() && x.abs() < MAX_INDEX) {
            self.evaluations += 1;
            return f(r);
        }
        // The pole's latitude is the top of the last cell, not the bottom of one past it.
        let top = self.half_turn / 2;
        let key = [
            generation,
            (u[0].floor() as i64).clamp(-top, top - 1),
            u[1].floor() as i64,
            u[2].floor() as i64,
        ];
        let values = self.cell(key, &mut f);
        let w = [
            u[0] - key[1] as f64,
            u[1] - key[2] as f64,
            u[2] - key[3] as f64,
        ];
        // Trilinear: fold one dimension at a time, the highest bit first.
        let mut v = values;
        let mut n = 8;
        for d in (0..3).rev() {
            n /= 2;
            for k in 0..n {
                let far = v[k + n];
                for (x, y) in v[k].iter_mut().zip(far) {
                    *x += w[d] * (y - *x);
                }
            }
        }
        v[0]
    }

    /// The values at the nodes of the cell `key`: kept, or made (the nodes it shares with the
    /// cells kept taken from them, `f` evaluated at the others).
    fn cell(&mut self, key: [i64; 4], f: &mut impl FnMut(&Vec3) -> [f64; N]) -> [[f64; N]; 8] {
        if let Some(c) = self.cells.iter().flatten().find(|c| c.key == key) {
            return c.values;
        }
        let mut values = [[0.0; N]; 8];
        for (b, slot) in values.iter_mut().enumerate() {
            let node = [
                key[1] + (b & 1) as i64,
                key[2] + ((b >> 1) & 1) as i64,
                key[3] + ((b >> 2) & 1) as i64,
            ];
            let kept = self.cells.iter().flatten().find_map(|c| {
                let off = [node[0] - c.key[1], node[1] - c.key[2], node[2] - c.key[3]];
                (c.key[0] == key[0] && off.iter().all(|o| (0..=1).contains(o)))
                    .then(|| c.values[(off[0] | off[1] << 1 | off[2] << 2) as usize])
            });
            *slot = match kept {
                Some(v) => v,
                None => {
                    self.evaluations += 1;
                    f(&self.node(node[0], node[1], node[2]))
                }
            };
        }
        self.cells[self.next] = Some(Cell { key, values });
        self.next = (self.next + 1) % CELLS;
        values
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth field with a known form: the position's components and a product.
    fn f(r: &Vec3) -> [f64; 2] {
        [r.x + 2.0 * r.y - r.z, 1e-7 * r.x * r.z]
    }

    #[test]
    fn linear_fields_are_reproduced_and_the_poles_are_finite() {
        let mut l = Lattice::<2>::new(2.0).unwrap();
        assert_eq!(l.cell_deg(), 2.0);
        // A field linear in the latitude, longitude and radius indices would be exact; the
        // Cartesian components are not, but stay within the chord's error (h²/8 of r).
        let h = 2f64.to_radians();
        for r in [
            Vec3::new(6.9e6, 1.0e5, -2.0e5),
            Vec3::new(0.0, 0.0, 7.0e6),
            Vec3::new(0.0, 0.0, -7.0e6),
            Vec3::new(1.0, -1.0, 7.0e6),
            Vec3::new(-7.0e6, -1e-9, 3.0e5),
            Vec3::new(-7.0e6, 0.0, 3.0e5),
        ] {
            let v = l.value(0, &r, f);
            let e = f(&r);
            assert!(v.iter().all(|x| x.is_finite()), "{r:?}");
            assert!((v[0] - e[0]).abs() < h * h * 7.0e6, "{r:?}: {v:?} {e:?}");
        }
        // About a pole every longitude's cell gives the pole's value (within the step to it).
        let pole = f(&Vec3::new(0.0, 0.0, 7.0e6));
        for lon in [0.3f64, 2.0, -2.5, PI] {
            let r = Vec3::new(1e-3 * lon.cos(), 1e-3 * lon.sin(), 7.0e6);
            let v = l.value(0, &r, f);
            assert!((v[0] - pole[0]).abs() < 0.01, "{lon}: {v:?} {pole:?}");
        }
    }

    #[test]
    fn the_centre_and_non_finite_positions_fall_back_to_the_function() {
        let mut l = Lattice::<2>::new(1.0).unwrap();
        assert_eq!(l.value(0, &Vec3::zeros(), f), f(&Vec3::zeros()));
        let v = l.value(0, &Vec3::new(f64::NAN, 0.0, 1.0), f);
        assert!(v[0].is_nan());
        assert!(Lattice::<2>::new(0.0).is_none() && Lattice::<2>::new(f64::NAN).is_none());
        assert_eq!(Lattice::<1>::new(0.7).unwrap().cell_deg(), 90.0 / 129.0);
        // A vanishing spacing is a lattice too fine to index: the function where asked.
        let mut fine = Lattice::<2>::new(1e-300).unwrap();
        let r = Vec3::new(6.9e6, 1.0e5, -2.0e5);
        assert_eq!(fine.value(0, &r, f), f(&r));
    }

    #[test]
    fn the_value_does_not_depend_on_the_order_of_the_calls() {
        let points: Vec<Vec3> = (0..400)
            .map(|k| {
                let a = k as f64 * 0.01;
                Vec3::new(
                    6.9e6 * a.cos(),
                    6.9e6 * a.sin() * 0.6,
                    6.9e6 * a.sin() * 0.8,
                )
            })
            .collect();
        let mut forward = Lattice::<2>::new(1.0).unwrap();
        let ahead: Vec<[f64; 2]> = points.iter().map(|r| forward.value(3, r, f)).collect();
        let mut backward = Lattice::<2>::new(1.0).unwrap();
        for (r, v) in points.iter().zip(&ahead).rev() {
            assert_eq!(backward.value(3, r, f), *v);
        }
        // Another generation is another key: its values are its own.
        let mut l = forward.clone();
        let other = l.value(4, &points[0], |r| f(r).map(|x| 2.0 * x));
        assert_eq!(other, ahead[0].map(|x| 2.0 * x));
    }
}
