//! Loads on the modes of a flexible body: a force spread uniformly over a facet of the body
//! (a pressure: sunlight, the air) does the virtual work `Σₖ φ̄ₖ · F δηₖ` on its modes, with
//! `φ̄ₖ` the mean translation of mode `k` over the facet's rectangle (body axes), taken once,
//! by Gauss–Legendre quadrature over the rectangle, from the body's mode shapes
//! ([`FlexModel::point_shape`]). A rigid body's facets, and a modes file's (its shapes known
//! at its nodes only), load no modes.
//!
//! The facet rides the deflection: [`FacetModes::deflection`] gives its mean translation
//! `Σₖ φ̄ₖ ηₖ` and mean rotation `Σₖ ψ̄ₖ ηₖ` (the local slope, `ψ̄ₖ` each mode's rotation
//! averaged the same way), with which [`super::facets::Facets::place_deflected`] moves its
//! centroid and turns its normal and edges (to first order in the slope), so that the
//! pressure acts on the deflected plate, at its deflected place, and shading sees it there.
//! The projection on the modes keeps the undeformed `φ̄ₖ` (its change with the deflection
//! is second order).

use satsim_tree::facet::Facet;
use satsim_tree::flexible::FlexModel;
use satsim_tree::flexible::beam::gauss_legendre;
use satsim_tree::spatial::Vec3;
use std::ops::Range;

/// Quadrature points along each side of a facet: the mean of a beam's mode shapes (whose
/// highest mode has at most 12 half-waves) over a facet to well below 1e-9.
const POINTS: usize = 16;

/// Per facet (in its owner's order): where its body's modes lie among the elastic
/// coordinates and each mode's mean translation and rotation over it; `None` for a facet
/// that loads no modes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FacetModes(Vec<Option<FacetShape>>);

/// One facet's share of its body's modes.
#[derive(Clone, Debug, PartialEq)]
struct FacetShape {
    /// The body's modes among the elastic coordinates.
    range: Range<usize>,
    /// Per mode, the mean translation over the facet (body axes, per unit `ηₖ`).
    phi: Vec<Vec3>,
    /// Per mode, the mean rotation vector over the facet (body axes, per unit `ηₖ`).
    psi: Vec<Vec3>,
}

impl FacetModes {
    /// The facets `(body, facet)` of the tree whose flexible bodies are `flex`.
    pub fn new<'a>(
        flex: Option<&FlexModel>,
        facets: impl IntoIterator<Item = (usize, &'a Facet)>,
    ) -> Self {
        let Some(flex) = flex else {
            return Self::default();
        };
        let rule = gauss_legendre(POINTS);
        Self(
            facets
                .into_iter()
                .map(|(body, f)| {
                    let (range, _) = flex.point_shape(body, &f.at)?;
                    let mut phi = vec![Vec3::zeros(); range.len()];
                    let mut psi = phi.clone();
                    for &(u, wu) in &rule {
                        for &(v, wv) in &rule {
                            let p = f.at + f.edges[0] * (0.5 * u) + f.edges[1] * (0.5 * v);
                            let (_, shape) = flex.point_shape(body, &p)?;
                            let w = 0.25 * wu * wv;
                            for (m, s) in phi.iter_mut().zip(&shape.phi) {
                                *m += s * w;
                            }
                            for (m, s) in psi.iter_mut().zip(&shape.psi) {
                                *m += s * w;
                            }
                        }
                    }
                    Some(FacetShape { range, phi, psi })
                })
                .collect(),
        )
    }

    /// Whether no facet loads a mode.
    pub fn is_empty(&self) -> bool {
        self.0.iter().all(Option::is_none)
    }

    /// Adds facet `j`'s force `force` (N, body axes, spread over it) to the elastic
    /// coordinates' generalised forces `elastic`.
    #[inline]
    pub fn add(&self, j: usize, force: &Vec3, elastic: &mut [f64]) {
        if let Some(Some(f)) = self.0.get(j) {
            for (q, phi) in elastic[f.range.clone()].iter_mut().zip(&f.phi) {
                *q += phi.dot(force);
            }
        }
    }

    /// Facet `j`'s mean translation (m) and mean rotation vector (rad), body axes, at the
    /// elastic coordinates `eta` (all of them, the layout's order); given the rates `η̇`,
    /// their rates. `None` for a facet that loads no modes (or `eta` too short).
    #[inline]
    pub fn deflection(&self, j: usize, eta: &[f64]) -> Option<(Vec3, Vec3)> {
        let f = self.0.get(j)?.as_ref()?;
        let eta = eta.get(f.range.clone())?;
        let mut u = Vec3::zeros();
        let mut theta = Vec3::zeros();
        for ((e, phi), psi) in eta.iter().zip(&f.phi).zip(&f.psi) {
            u += phi * *e;
            theta += psi * *e;
        }
        Some((u, theta))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use satsim_tree::flexible::{Beam, Flexible, Modes};
    use satsim_tree::{BaseKind, Body, ModelBuilder, spatial::Mat3};

    /// A facet over a whole beam strip: each mode's mean translation is `b S₁ₖ / (ρA L)`,
    /// the integral of its shape over the length (the beam's own quadrature), over the
    /// length; over half the strip's width, the same (the shape does not vary across it).
    #[test]
    fn a_facet_over_the_whole_strip_averages_the_mode_shapes() {
        let beam = Beam {
            root: Vec3::new(0.0, 0.5, 0.0),
            axis: Vec3::y(),
            bend: Vec3::z(),
            length: 2.0,
            ei: 100.0,
            rho_a: 10.0,
            modes: 3,
        };
        let b = ModelBuilder::new(BaseKind::Fixed).body(Body::new("panel", 1.0, Mat3::identity()));
        let flex = FlexModel::build(
            b,
            &[Flexible {
                body: "panel".into(),
                modes: Modes::Beam(beam.clone()),
                damping: 0.0,
                stiffening: false,
            }],
        )
        .unwrap();
        let whole =
            Facet::new(2.0, Vec3::z(), Vec3::new(0.0, 1.5, 0.0)).with_size(1.0, 2.0, Vec3::x());
        let half =
            Facet::new(1.0, Vec3::z(), Vec3::new(0.25, 1.5, 0.0)).with_size(0.5, 2.0, Vec3::x());
        let fm = FacetModes::new(Some(&flex), [(0, &whole), (0, &half)]);
        let s1 = beam.stiffening_integrals().s1;
        for j in 0..2 {
            let mut q = vec![0.0; 3];
            fm.add(j, &Vec3::z(), &mut q);
            for k in 0..3 {
                let expected = s1[k] / (beam.rho_a * beam.length);
                assert!(
                    (q[k] - expected).abs() < 1e-10 * expected.abs(),
                    "{j} {k}: {} vs {expected}",
                    q[k]
                );
            }
        }
        // A force in the strip's plane does no work on its bending.
        let mut q = vec![0.0; 3];
        fm.add(0, &Vec3::x(), &mut q);
        assert!(q.iter().all(|x| x.abs() < 1e-15), "{q:?}");
        // A rigid tree: nothing.
        assert!(FacetModes::new(None, [(0, &whole)]).is_empty());
    }
}
