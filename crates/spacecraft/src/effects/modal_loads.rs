//! Loads on the modes of a flexible body: a force spread uniformly over a facet of the body
//! (a pressure: sunlight, the air) does the virtual work `Σₖ φ̄ₖ · F δηₖ` on its modes, with
//! `φ̄ₖ` the mean translation of mode `k` over the facet's rectangle (body axes), taken once,
//! by Gauss–Legendre quadrature over the rectangle, from the body's mode shapes
//! ([`FlexModel::point_shape`]). A rigid body's facets, and a modes file's (its shapes known
//! at its nodes only), load no modes.
//!
//! The facet is the undeformed one: its centroid and normal do not follow the deflection
//! (the load's change with the deflection is second order in it).

use satsim_tree::facet::Facet;
use satsim_tree::flexible::FlexModel;
use satsim_tree::flexible::beam::gauss_legendre;
use satsim_tree::spatial::Vec3;
use std::ops::Range;

/// Quadrature points along each side of a facet: the mean of a beam's mode shapes (whose
/// highest mode has at most 12 half-waves) over a facet to well below 1e-9.
const POINTS: usize = 16;

/// Per facet (in its owner's order): where its body's modes lie among the elastic
/// coordinates and each mode's mean translation over it; `None` for a facet that loads no
/// modes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FacetModes(Vec<Option<(Range<usize>, Vec<Vec3>)>>);

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
                    let mut mean = vec![Vec3::zeros(); range.len()];
                    for &(u, wu) in &rule {
                        for &(v, wv) in &rule {
                            let p = f.at + f.edges[0] * (0.5 * u) + f.edges[1] * (0.5 * v);
                            let (_, shape) = flex.point_shape(body, &p)?;
                            for (m, phi) in mean.iter_mut().zip(&shape.phi) {
                                *m += phi * (0.25 * wu * wv);
                            }
                        }
                    }
                    Some((range, mean))
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
        if let Some(Some((range, mean))) = self.0.get(j) {
            for (q, phi) in elastic[range.clone()].iter_mut().zip(mean) {
                *q += phi.dot(force);
            }
        }
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
