//! [`Facet`]: a flat, one-sided rectangle on a body's surface, with the optical and drag
//! coefficients of the surface-force models (solar radiation pressure, aerodynamic drag).
//!
//! Facets are data: no algorithm of the tree reads them. They are given in the body's frame
//! (the model file's `facets` and `facets_from_shape` keys) and carried into the built
//! [`Model`](crate::Model), where [`BodyInfo::facets`](crate::BodyInfo::facets) returns them
//! with unit normals.
//!
//! A facet is the rectangle of corners `at ± edges[0]/2 ± edges[1]/2`, with
//! `edges[0] × edges[1] = area · normal`: its edges matter only where a facet shades another
//! (self-shadowing). A facet given by its area, normal and centroid alone
//! ([`Facet::new`]) is a **square** of side `√area`; [`Facet::with_size`] makes it an `a × b`
//! rectangle along a chosen direction.

use crate::error::ModelError;
use crate::shape::BoxShape;
use crate::spatial::{UNIT_NORM_TOLERANCE, Vec3};

/// The default drag coefficient `C_D` of a facet (2.2, the usual value for a flat plate in
/// free-molecular flow).
pub const DEFAULT_DRAG: f64 = 2.2;

/// The largest facet area (m²): a square kilometre, a hundred times the largest solar sail
/// flown or planned. A larger area is a unit slip (mm² for m²) or a typo.
pub const MAX_FACET_AREA: f64 = 1e6;

/// The farthest a facet's centroid may lie from its body's origin (m): 10 km, beyond any
/// structure a body's surface could describe.
pub const MAX_FACET_DISTANCE: f64 = 1e4;

/// A flat, one-sided rectangle of a body's surface, in the body's frame: lit, and met by
/// the flow, only on its normal's side.
///
/// ```
/// use satsim_tree::facet::Facet;
/// use satsim_tree::spatial::Vec3;
/// let f = Facet::new(4.0, Vec3::z(), Vec3::new(0.0, 0.8, 0.0)).with_specular(0.3).with_diffuse(0.1);
/// assert_eq!(f.edges[0].cross(&f.edges[1]), 4.0 * Vec3::z()); // a 2 m square
/// assert_eq!((f.specular, f.diffuse, f.drag), (0.3, 0.1, 2.2));
/// let r = f.with_size(4.0, 0.5, Vec3::y()); // 4 m along y, 0.5 m across
/// assert_eq!(r.area, 2.0);
/// assert_eq!(r.edges, [Vec3::new(0.0, 4.0, 0.0), Vec3::new(-0.5, 0.0, 0.0)]);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Facet {
    /// Area (m²), positive.
    pub area: f64,
    /// Outward unit normal, body frame (normalised by the builder if within 1e-6 of unit).
    pub normal: Vec3,
    /// Centroid, body frame (m).
    pub at: Vec3,
    /// Fraction of the incident light reflected specularly, in `[0, 1]`.
    pub specular: f64,
    /// Fraction of the incident light reflected diffusely, in `[0, 1]`; `specular + diffuse
    /// <= 1`, the rest is absorbed.
    pub diffuse: f64,
    /// Drag coefficient `C_D`, `>= 0`.
    pub drag: f64,
    /// The two sides of the rectangle (m, body frame): corners `at ± edges[0]/2 ±
    /// edges[1]/2`, `edges[0] × edges[1] = area · normal`.
    pub edges: [Vec3; 2],
}

/// The unit vector along the component of `dir` in the plane normal to the unit `n`.
fn in_plane(dir: &Vec3, n: &Vec3) -> Vec3 {
    let u = dir - n * n.dot(dir);
    u / u.norm()
}

impl Facet {
    /// A square facet of area `area` (m²), outward normal `normal` and centroid `at` (body
    /// frame), with no reflection (`specular = diffuse = 0`) and `drag =` [`DEFAULT_DRAG`].
    ///
    /// The square's first side lies along the body axis least aligned with the normal (the
    /// first such axis on a tie), projected onto the facet's plane; the second is
    /// `normal × first`. (The sides matter only for self-shadowing: a facet written with an
    /// area, a normal and a centroid alone is a square there.)
    pub fn new(area: f64, normal: Vec3, at: Vec3) -> Self {
        let n = normal / normal.norm();
        let axis = (0..3)
            .min_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
            .expect("three axes");
        let side = area.sqrt();
        let u = in_plane(&Vec3::ith(axis, 1.0), &n);
        Self {
            area,
            normal,
            at,
            specular: 0.0,
            diffuse: 0.0,
            drag: DEFAULT_DRAG,
            edges: [u * side, n.cross(&u) * side],
        }
    }
    /// Sets the fraction of the incident light reflected specularly.
    pub fn with_specular(mut self, specular: f64) -> Self {
        self.specular = specular;
        self
    }
    /// Sets the fraction of the incident light reflected diffusely.
    pub fn with_diffuse(mut self, diffuse: f64) -> Self {
        self.diffuse = diffuse;
        self
    }
    /// Sets the drag coefficient `C_D`.
    pub fn with_drag(mut self, drag: f64) -> Self {
        self.drag = drag;
        self
    }
    /// Makes the facet an `a × b` rectangle (m) whose side `a` lies along `edge_dir`
    /// projected onto the facet's plane (and `b` along `normal × edge_dir`); the area becomes
    /// `a · b`. An `edge_dir` along the normal leaves no direction in the plane: the edges
    /// are then not finite, which the model builder rejects.
    pub fn with_size(mut self, a: f64, b: f64, edge_dir: Vec3) -> Self {
        let n = self.normal / self.normal.norm();
        let u = in_plane(&edge_dir, &n);
        self.area = a * b;
        self.edges = [u * a, n.cross(&u) * b];
        self
    }
    /// The four corners (body frame, m), counter-clockwise about the normal:
    /// `at − e₀/2 − e₁/2`, `at + e₀/2 − e₁/2`, `at + e₀/2 + e₁/2`, `at − e₀/2 + e₁/2`.
    pub fn corners(&self) -> [Vec3; 4] {
        let [h0, h1] = [self.edges[0] * 0.5, self.edges[1] * 0.5];
        [
            self.at - h0 - h1,
            self.at + h0 - h1,
            self.at + h0 + h1,
            self.at - h0 + h1,
        ]
    }

    /// Validates the facet (`body`'s facet `index`) and returns it with a unit normal.
    pub(crate) fn checked(&self, body: &str, index: usize) -> Result<Facet, ModelError> {
        let nonfinite =
            |field: &str| ModelError::NonFinite(format!("body `{body}`: facet {index}: {field}"));
        let finite3 = |v: &Vec3| v.iter().all(|x| x.is_finite());
        if !self.area.is_finite() {
            return Err(nonfinite("area"));
        }
        if !finite3(&self.normal) {
            return Err(nonfinite("normal"));
        }
        if !finite3(&self.at) {
            return Err(nonfinite("at"));
        }
        for (field, x) in [
            ("specular", self.specular),
            ("diffuse", self.diffuse),
            ("drag", self.drag),
        ] {
            if !x.is_finite() {
                return Err(nonfinite(field));
            }
        }
        if self.area <= 0.0 {
            return Err(ModelError::FacetArea {
                body: body.to_owned(),
                index,
                area: self.area,
            });
        }
        if self.area > MAX_FACET_AREA {
            return Err(ModelError::FacetTooLarge {
                body: body.to_owned(),
                index,
                area: self.area,
                max: MAX_FACET_AREA,
            });
        }
        // Scaled, so that a centroid at 1e308 m is said to be there, not at infinity.
        let scale = self.at.amax();
        let distance = if scale > 0.0 {
            scale * (self.at / scale).norm()
        } else {
            0.0
        };
        if distance > MAX_FACET_DISTANCE {
            return Err(ModelError::FacetTooFar {
                body: body.to_owned(),
                index,
                distance,
                max: MAX_FACET_DISTANCE,
            });
        }
        let norm = self.normal.norm();
        if (norm - 1.0).abs() > UNIT_NORM_TOLERANCE {
            return Err(ModelError::FacetNormal {
                body: body.to_owned(),
                index,
                norm,
            });
        }
        let unit = |x: f64| (0.0..=1.0).contains(&x);
        if !unit(self.specular) || !unit(self.diffuse) || self.specular + self.diffuse > 1.0 {
            return Err(ModelError::FacetOptical {
                body: body.to_owned(),
                index,
                specular: self.specular,
                diffuse: self.diffuse,
            });
        }
        if self.drag < 0.0 {
            return Err(ModelError::FacetDrag {
                body: body.to_owned(),
                index,
                drag: self.drag,
            });
        }
        let n = self.normal / norm;
        let [e0, e1] = self.edges;
        // The edges must lie in the plane and span `area · n`, to the tolerance of a unit
        // normal (a normal normalised from within 1e-6 of unit keeps its edges).
        let tol = UNIT_NORM_TOLERANCE;
        let consistent = finite3(&e0)
            && finite3(&e1)
            && e0.dot(&n).abs() <= tol * e0.norm()
            && e1.dot(&n).abs() <= tol * e1.norm()
            && (e0.cross(&e1) - n * self.area).norm() <= tol * self.area;
        if !consistent {
            return Err(ModelError::FacetEdges {
                body: body.to_owned(),
                index,
            });
        }
        Ok(Facet { normal: n, ..*self })
    }
}

/// The six outward faces of the box `shape` of a body whose centre of mass is `com` (the
/// box's centre is [`BoxShape::centre`]), in the order +x, −x, +y, −y, +z, −z, with no
/// reflection and `drag =` [`DEFAULT_DRAG`]. Each face is the exact rectangle of the box's
/// side: the +x face has edges `[ly ŷ, lz ẑ]`, the +y face `[lz ẑ, lx x̂]`, the +z face
/// `[lx x̂, ly ŷ]`, and the −x, −y, −z faces the same two edges swapped.
///
/// ```
/// use satsim_tree::{BoxShape, facet::facets_of_box, spatial::Vec3};
/// let faces = facets_of_box(&BoxShape::new(Vec3::new(1.0, 2.0, 3.0)), &Vec3::zeros());
/// assert_eq!(faces[2].area, 3.0); // +y: 1 m × 3 m
/// assert_eq!(faces[2].at, Vec3::new(0.0, 1.0, 0.0));
/// assert_eq!(faces[5].normal, -Vec3::z());
/// ```
pub fn facets_of_box(shape: &BoxShape, com: &Vec3) -> [Facet; 6] {
    let c = shape.centre(com);
    let s = shape.size;
    let axis = |k: usize| Vec3::ith(k, s[k]);
    let face = |k: usize, sign: f64| {
        // Sides along the next two axes in cyclic order: (k+1) × (k+2) = +k.
        let (a, b) = (axis((k + 1) % 3), axis((k + 2) % 3));
        let edges = if sign > 0.0 { [a, b] } else { [b, a] };
        Facet {
            area: s[(k + 1) % 3] * s[(k + 2) % 3],
            normal: Vec3::ith(k, sign),
            at: c + Vec3::ith(k, sign * 0.5 * s[k]),
            specular: 0.0,
            diffuse: 0.0,
            drag: DEFAULT_DRAG,
            edges,
        }
    };
    [
        face(0, 1.0),
        face(0, -1.0),
        face(1, 1.0),
        face(1, -1.0),
        face(2, 1.0),
        face(2, -1.0),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cross_ok(f: &Facet) {
        let c = f.edges[0].cross(&f.edges[1]);
        assert!((c - f.normal * f.area).norm() <= 1e-14 * f.area, "{f:?}");
        assert!(f.edges[0].dot(&f.normal).abs() < 1e-15);
        assert!(f.edges[1].dot(&f.normal).abs() < 1e-15);
    }

    #[test]
    fn facets_beyond_any_spacecraft_are_refused_naming_the_value() {
        let too_large = Facet::new(1e30, Vec3::z(), Vec3::zeros()).checked("bus", 2);
        assert_eq!(
            too_large,
            Err(ModelError::FacetTooLarge {
                body: "bus".into(),
                index: 2,
                area: 1e30,
                max: MAX_FACET_AREA
            })
        );
        assert!(
            too_large
                .unwrap_err()
                .to_string()
                .contains("facet 2: area 1e30 m² is more than 1e6 m²")
        );
        // 1e308 m away: said as such, not as an infinite distance.
        let far = Facet::new(1.0, Vec3::z(), Vec3::new(1e308, 1e308, 0.0)).checked("bus", 0);
        let Err(ModelError::FacetTooFar { distance, .. }) = &far else {
            panic!("{far:?}")
        };
        assert!((distance / 1e308 - 2f64.sqrt()).abs() < 1e-15, "{distance}");
        let message = far.unwrap_err().to_string();
        assert!(
            message.contains("its centroid `at` is 1.41421356"),
            "{message}"
        );
        assert!(
            message.contains("e308 m from the body's origin, more than 1e4 m"),
            "{message}"
        );
        // At the bounds: accepted.
        let edge = Facet::new(
            MAX_FACET_AREA,
            Vec3::z(),
            Vec3::new(0.0, MAX_FACET_DISTANCE, 0.0),
        );
        assert!(edge.checked("bus", 0).is_ok());
    }

    #[test]
    fn squares_take_the_least_aligned_axis() {
        // Normal z: x and y tie at 0, x (the first) wins.
        let f = Facet::new(2.25, Vec3::z(), Vec3::zeros());
        assert_eq!(
            f.edges,
            [Vec3::new(1.5, 0.0, 0.0), Vec3::new(0.0, 1.5, 0.0)]
        );
        // Normal mostly along x with some z: y is the least aligned axis.
        let n = Vec3::new(0.8, 0.0, 0.6);
        let f = Facet::new(1.0, n, Vec3::zeros());
        assert_eq!(f.edges[0], Vec3::y());
        cross_ok(&f);
        // A general normal: the first edge is the projected z axis (|n_z| least).
        let n = Vec3::new(0.6, -0.7, 0.1).normalize();
        let f = Facet::new(3.0, n, Vec3::zeros());
        let u = (Vec3::z() - n * n.z).normalize();
        assert!((f.edges[0] - u * 3f64.sqrt()).norm() < 1e-15);
        assert!((f.edges[0].norm() - f.edges[1].norm()).abs() < 1e-15);
        cross_ok(&f);
    }

    #[test]
    fn rectangles_and_corners() {
        let f = Facet::new(1.0, -Vec3::x(), Vec3::new(1.0, 2.0, 3.0)).with_size(
            2.0,
            0.5,
            Vec3::new(0.3, 0.0, 1.0), // projects onto z
        );
        assert_eq!(f.area, 1.0);
        assert_eq!(
            f.edges,
            [Vec3::new(0.0, 0.0, 2.0), Vec3::new(0.0, 0.5, 0.0)]
        );
        cross_ok(&f);
        let c = f.corners();
        assert_eq!(c[0], Vec3::new(1.0, 1.75, 2.0));
        assert_eq!(c[2], Vec3::new(1.0, 2.25, 4.0));
        // Counter-clockwise about the normal: consecutive sides cross along it.
        for k in 0..4 {
            let a = c[(k + 1) % 4] - c[k];
            let b = c[(k + 2) % 4] - c[(k + 1) % 4];
            assert!((a.cross(&b) - f.normal * f.area).norm() < 1e-12);
        }
        let centroid = c.iter().sum::<Vec3>() / 4.0;
        assert!((centroid - f.at).norm() < 1e-15);
    }

    #[test]
    fn box_faces_are_outward_and_exact() {
        let shape = BoxShape::new(Vec3::new(1.0, 2.0, 4.0)).at(Vec3::new(0.0, 0.0, 1.0));
        let faces = facets_of_box(&shape, &Vec3::new(9.0, 9.0, 9.0));
        let areas = [8.0, 8.0, 4.0, 4.0, 2.0, 2.0];
        for (k, f) in faces.iter().enumerate() {
            assert_eq!(f.area, areas[k]);
            cross_ok(f);
            // Outward: the centroid lies on the normal's side of the centre.
            let off = f.at - Vec3::new(0.0, 0.0, 1.0);
            assert_eq!(off.dot(&f.normal), 0.5 * shape.size[k / 2]);
            assert_eq!((f.specular, f.diffuse, f.drag), (0.0, 0.0, DEFAULT_DRAG));
            // Every corner lies on the box's surface.
            for c in f.corners() {
                let r = c - Vec3::new(0.0, 0.0, 1.0);
                for a in 0..3 {
                    assert!(r[a].abs() <= 0.5 * shape.size[a] + 1e-15);
                }
            }
        }
        // Without `at`, the box is centred on the centre of mass.
        let faces = facets_of_box(&BoxShape::new(Vec3::repeat(2.0)), &Vec3::x());
        assert_eq!(faces[0].at, Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(faces[1].at, Vec3::zeros());
    }

    #[test]
    fn checks_name_the_body_and_facet() {
        let good = Facet::new(1.0, Vec3::new(0.0, 0.0, 1.0 + 5e-7), Vec3::zeros());
        let ok = good.checked("p", 0).unwrap();
        assert_eq!(ok.normal, Vec3::z());
        let err = |f: Facet| f.checked("p", 3).unwrap_err().to_string();
        assert_eq!(
            err(Facet { area: 0.0, ..good }),
            "body `p`: facet 3: area 0 must be positive"
        );
        assert_eq!(
            err(Facet {
                area: f64::NAN,
                ..good
            }),
            "body `p`: facet 3: area: value is not finite"
        );
        assert!(err(Facet::new(1.0, Vec3::new(0.0, 0.0, 1.1), Vec3::zeros())).contains("normal"));
        assert!(err(good.with_specular(0.7).with_diffuse(0.4)).contains("specular 0.7"));
        assert!(err(good.with_diffuse(-0.1)).contains("diffuse -0.1"));
        assert!(err(good.with_specular(1.5)).contains("specular 1.5"));
        assert_eq!(
            err(good.with_drag(-1.0)),
            "body `p`: facet 3: drag coefficient -1 is negative"
        );
        assert!(err(good.with_drag(f64::INFINITY)).contains("drag: value is not finite"));
        // Edges along the normal, or that do not span the area.
        assert!(err(good.with_size(1.0, 1.0, Vec3::z())).contains("edges"));
        let mut skew = good;
        skew.area = 2.0;
        assert!(err(skew).contains("edges"));
        // Boundary values are accepted.
        assert!(
            good.with_specular(0.25)
                .with_diffuse(0.75)
                .checked("p", 0)
                .is_ok()
        );
        assert!(good.with_drag(0.0).checked("p", 0).is_ok());
    }
}
