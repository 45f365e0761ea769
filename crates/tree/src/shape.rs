//! [`BoxShape`], the box a body is drawn as: the 3-D view draws it, and the model file's
//! `facets_from_shape` makes its six faces into facets ([`crate::facet::facets_of_box`]).
//! Its own file, below both the model and the facets, so that neither imports the other.

use crate::spatial::Vec3;

/// A box drawn for a body (the model file's `shape = { box = [lx, ly, lz], at = [x, y, z] }`).
/// For drawing only: no algorithm reads it.
///
/// ```
/// use satsim_tree::{Body, BoxShape, spatial::{Mat3, Vec3}};
/// let panel = Body::new("panel", 20.0, Mat3::identity())
///     .with_com(Vec3::new(0.0, 1.0, 0.0))
///     .with_shape(BoxShape::new(Vec3::new(0.02, 2.0, 1.0)));
/// assert_eq!(panel.shape.unwrap().centre(&panel.com), Vec3::new(0.0, 1.0, 0.0));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxShape {
    /// Edge lengths along the body's x, y, z axes (m), each positive and finite.
    pub size: Vec3,
    /// The box's centre in the body frame (m); `None` puts it at the body's centre of mass.
    pub at: Option<Vec3>,
}

impl BoxShape {
    /// A box of edge lengths `size` (body axes, m) centred on the body's centre of mass.
    pub fn new(size: Vec3) -> Self {
        Self { size, at: None }
    }
    /// Places the box's centre at `at` (body frame, m).
    pub fn at(mut self, at: Vec3) -> Self {
        self.at = Some(at);
        self
    }
    /// The box's centre in the body frame: `at`, or the centre of mass `com` by default.
    pub fn centre(&self, com: &Vec3) -> Vec3 {
        self.at.unwrap_or(*com)
    }
}
