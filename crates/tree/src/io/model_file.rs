//! The model file (contract section 1): its TOML schema ([`ModelFile`]) and its reading into
//! a validated [`Model`].

use super::error::{FileError, SpannedError, line_of};
use super::exact::exact;
use super::read_text;
use crate::error::ModelError;
use crate::facet::{DEFAULT_DRAG, Facet, facets_of_box};
use crate::model::{BaseKind, Body, BoxShape, Hinge, Model, ModelBuilder, UNIT_NORM_TOLERANCE};
use crate::spatial::{Mat3, Vec3};
use nalgebra::Quaternion;
use serde::Deserialize;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;

/// The model file (contract section 1), as written. Deserialise it from TOML text (directly or
/// as a field of a larger document, e.g. a scene's inline `[model]` table) with
/// `toml::from_str`: the [`Spanned`] fields record byte offsets into that text. (Going through
/// an intermediate `toml::Value` loses the spans and fails.)
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// `[base]` (default: a free base).
    #[serde(default)]
    pub base: Option<Spanned<BaseFile>>,
    /// `[[body]]` entries, in file order; the first is the root.
    #[serde(default)]
    pub body: Vec<Spanned<BodyFile>>,
    /// `[[hinge]]` entries, in file order (the order of the hinge coordinates).
    #[serde(default)]
    pub hinge: Vec<Spanned<HingeFile>>,
}

/// `[base]`.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BaseFile {
    /// `kind = "free"` (default) or `"fixed"`.
    #[serde(default)]
    pub kind: BaseKindFile,
}

/// The values of `base.kind`.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum BaseKindFile {
    /// `"free"`: a 6-DOF floating root.
    #[default]
    Free,
    /// `"fixed"`: the root is fixed in the inertial frame.
    Fixed,
}

impl From<BaseKindFile> for BaseKind {
    fn from(k: BaseKindFile) -> Self {
        match k {
            BaseKindFile::Free => BaseKind::Free,
            BaseKindFile::Fixed => BaseKind::Fixed,
        }
    }
}

/// A `[[body]]` entry.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BodyFile {
    /// Unique name.
    pub name: Spanned<String>,
    /// Mass (kg).
    pub mass: Spanned<f64>,
    /// Centre of mass in the body frame (m), default zero.
    #[serde(default, deserialize_with = "exact")]
    pub com: Option<Spanned<[f64; 3]>>,
    /// Inertia about the centre of mass, body axes (kg m²), rows; required unless the mass
    /// is 0 (then zero by default).
    #[serde(default, deserialize_with = "exact")]
    pub inertia: Option<Spanned<[[f64; 3]; 3]>>,
    /// `shape = { box = [lx, ly, lz], at = [x, y, z] }`: how to draw the body (optional;
    /// no algorithm reads it).
    #[serde(default)]
    pub shape: Option<Spanned<ShapeFile>>,
    /// `facets = [{ area, normal, at, specular, diffuse, drag, size, edge }, …]`: the body's
    /// surface facets, body frame (optional).
    #[serde(default)]
    pub facets: Vec<Spanned<FacetFile>>,
    /// `facets_from_shape = { specular, diffuse, drag }`: the six faces of `shape`'s box as
    /// facets with these coefficients, after the listed `facets` (requires `shape`).
    #[serde(default)]
    pub facets_from_shape: Option<Spanned<CoefficientsFile>>,
    /// `[body.flexible]` (contract section 14): the body's elastic coordinates. Read by
    /// [`super::read_flex_model`] only; [`ModelFile::build`] refuses it.
    #[serde(default)]
    pub flexible: Option<Spanned<FlexibleFile>>,
}

/// One of a body's `facets`: a flat one-sided rectangle, body frame. Written with `area`,
/// `normal` and `at` alone it is a square (see [`Facet::new`]); `size = [a, b]` makes it an
/// `a × b` rectangle (then `area`, if given, must be `a · b` within 1e-9 relative) and
/// `edge` turns its side `a` along `edge` projected onto the facet's plane.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FacetFile {
    /// Area (m²), required unless `size` is given.
    #[serde(default)]
    pub area: Option<Spanned<f64>>,
    /// Outward unit normal (normalised if within 1e-6 of unit).
    #[serde(deserialize_with = "exact")]
    pub normal: Spanned<[f64; 3]>,
    /// Centroid (m).
    #[serde(deserialize_with = "exact")]
    pub at: Spanned<[f64; 3]>,
    /// Fraction of the light reflected specularly, default 0.
    #[serde(default)]
    pub specular: Option<Spanned<f64>>,
    /// Fraction of the light reflected diffusely, default 0.
    #[serde(default)]
    pub diffuse: Option<Spanned<f64>>,
    /// Drag coefficient, default [`DEFAULT_DRAG`].
    #[serde(default)]
    pub drag: Option<Spanned<f64>>,
    /// `[a, b]` (m): the rectangle's sides (an extension of the contract).
    #[serde(default, deserialize_with = "exact")]
    pub size: Option<Spanned<[f64; 2]>>,
    /// The direction of side `a` (an extension of the contract).
    #[serde(default, deserialize_with = "exact")]
    pub edge: Option<Spanned<[f64; 3]>>,
}

/// `facets_from_shape`: the coefficients of the six faces of a body's `shape` box.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CoefficientsFile {
    /// Fraction of the light reflected specularly, default 0.
    #[serde(default)]
    pub specular: Option<Spanned<f64>>,
    /// Fraction of the light reflected diffusely, default 0.
    #[serde(default)]
    pub diffuse: Option<Spanned<f64>>,
    /// Drag coefficient, default [`DEFAULT_DRAG`].
    #[serde(default)]
    pub drag: Option<Spanned<f64>>,
}

/// A body's `shape`: a box of edge lengths `box` (m, body axes, each positive) centred at
/// `at` (m, body frame; default the body's `com`). For drawing only.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShapeFile {
    /// Edge lengths along the body's x, y, z axes (m).
    #[serde(rename = "box", deserialize_with = "exact")]
    pub size: Spanned<[f64; 3]>,
    /// The box's centre in the body frame (m), default the centre of mass.
    #[serde(default, deserialize_with = "exact")]
    pub at: Option<Spanned<[f64; 3]>>,
}

/// `[body.flexible]`: `beam` or `modes_file` (exactly one), `damping`, `stiffening`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FlexibleFile {
    /// An Euler-Bernoulli cantilever.
    #[serde(default)]
    pub beam: Option<Spanned<BeamFile>>,
    /// A modes file, relative to the model file's folder.
    #[serde(default)]
    pub modes_file: Option<Spanned<String>>,
    /// Modal damping ratio of every mode, `>= 0` (default 0, or the modes file's).
    #[serde(default)]
    pub damping: Option<Spanned<f64>>,
    /// The consistent terms (default true for a beam; for a modes file, whether it has a
    /// `[stiffening]` block, and `true` refused without one).
    #[serde(default)]
    pub stiffening: Option<Spanned<bool>>,
}

impl FlexibleFile {
    /// The span of `beam` or `modes_file`, whichever is given first.
    pub(crate) fn key_span(&self) -> Option<Range<usize>> {
        self.beam
            .as_ref()
            .map(Spanned::span)
            .or_else(|| self.modes_file.as_ref().map(Spanned::span))
    }
}

/// `beam = { root, axis, bend, length, EI, rho_A, modes }` (see
/// [`Beam`](crate::flexible::Beam)).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BeamFile {
    /// The clamped end, body frame (m).
    #[serde(deserialize_with = "exact")]
    pub root: Spanned<[f64; 3]>,
    /// Unit direction root to tip (normalised if within 1e-6 of unit).
    #[serde(deserialize_with = "exact")]
    pub axis: Spanned<[f64; 3]>,
    /// Unit direction of the deflection, perpendicular to `axis` within 1e-6.
    #[serde(deserialize_with = "exact")]
    pub bend: Spanned<[f64; 3]>,
    /// Length (m), positive.
    pub length: Spanned<f64>,
    /// Bending stiffness (N m²), positive.
    #[serde(rename = "EI")]
    pub ei: Spanned<f64>,
    /// Mass per length (kg/m), positive.
    #[serde(rename = "rho_A")]
    pub rho_a: Spanned<f64>,
    /// Number of cantilever modes, 1 to
    /// [`MAX_BEAM_MODES`](crate::flexible::model::MAX_BEAM_MODES).
    pub modes: Spanned<i64>,
}

/// A `[[hinge]]` entry.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HingeFile {
    /// Unique name.
    pub name: Spanned<String>,
    /// Parent body.
    pub parent: Spanned<String>,
    /// Child body.
    pub child: Spanned<String>,
    /// Axis in the parent frame.
    #[serde(deserialize_with = "exact")]
    pub axis: Spanned<[f64; 3]>,
    /// Hinge point in the parent frame (m), default zero.
    #[serde(default, deserialize_with = "exact")]
    pub at: Option<Spanned<[f64; 3]>>,
    /// Hinge point in the child frame (m), default zero.
    #[serde(default, deserialize_with = "exact")]
    pub child_at: Option<Spanned<[f64; 3]>>,
    /// Child frame relative to the parent at zero angle, `[w, x, y, z]`, default identity.
    #[serde(default, deserialize_with = "exact")]
    pub rotation: Option<Spanned<[f64; 4]>>,
    /// Armature (kg m²), default zero: rotor inertia about the axis (an extension of the
    /// contract, used to regularise a gimbal lock).
    #[serde(default)]
    pub armature: Option<Spanned<f64>>,
}

/// Relative tolerance between a facet's `area` and the product of its `size`.
const AREA_TOLERANCE: f64 = 1e-9;

/// A coefficient (`specular`, `diffuse`, `drag`) given or its default, checked finite.
fn coefficient(
    x: &Option<Spanned<f64>>,
    default: f64,
    nonfinite: impl Fn(Option<Range<usize>>) -> SpannedError,
) -> Result<f64, SpannedError> {
    match x {
        Some(v) if !v.get_ref().is_finite() => Err(nonfinite(span_of(v))),
        Some(v) => Ok(*v.get_ref()),
        None => Ok(default),
    }
}

/// The facets of `body` (the file entry `b`, the body read so far `entry`): the listed
/// `facets`, then the faces of `facets_from_shape`. Non-finite numbers, `size` and `edge`
/// are checked here with their spans; the builder checks the rest (its errors are located
/// by [`ModelFile::locate`]).
fn facets_of(b: &Spanned<BodyFile>, entry: &Body) -> Result<Vec<Facet>, SpannedError> {
    let body = b.get_ref();
    let name = &entry.name;
    let mut facets = Vec::with_capacity(body.facets.len() + 6);
    for (k, f) in body.facets.iter().enumerate() {
        let spec = f.get_ref();
        let nonfinite = |field: &str| {
            let what = format!("body `{name}`: facet {k}: {field}");
            move |span| SpannedError::Model {
                span,
                error: ModelError::NonFinite(what.clone()),
            }
        };
        let schema = |span: Range<usize>, message: String| SpannedError::Schema {
            span: Some(span),
            message: format!("body `{name}`: facet {k}: {message}"),
        };
        let vec = |field: &str, x: &Spanned<[f64; 3]>| {
            if x.get_ref().iter().all(|x| x.is_finite()) {
                Ok(v3(x.get_ref()))
            } else {
                Err(nonfinite(field)(span_of(x)))
            }
        };
        let normal = vec("normal", &spec.normal)?;
        let at = vec("at", &spec.at)?;
        let edge = match &spec.edge {
            Some(e) => {
                let dir = vec("edge", e)?;
                // An edge along the normal has no direction in the plane (with a normal
                // that is not unit, the builder reports the normal instead).
                let unit = (normal.norm() - 1.0).abs() <= UNIT_NORM_TOLERANCE;
                let n = normal / normal.norm();
                if unit && (dir - n * n.dot(&dir)).norm() <= 1e-9 * dir.norm() {
                    return Err(schema(
                        e.span(),
                        format!(
                            "edge {:?} has no direction in the facet's plane",
                            e.get_ref()
                        ),
                    ));
                }
                Some(dir)
            }
            None => None,
        };
        let given = match &spec.area {
            Some(a) => Some((coefficient(&spec.area, 0.0, nonfinite("area"))?, a)),
            None => None,
        };
        let size = match &spec.size {
            Some(size) => {
                let [a, b] = *size.get_ref();
                if !(a.is_finite() && b.is_finite()) {
                    return Err(nonfinite("size")(span_of(size)));
                }
                if a <= 0.0 || b <= 0.0 {
                    return Err(schema(
                        size.span(),
                        format!("size [{a}, {b}] must be positive"),
                    ));
                }
                if let Some((area, key)) = given
                    && (area - a * b).abs() > AREA_TOLERANCE * (a * b)
                {
                    return Err(schema(
                        key.span(),
                        format!(
                            "area {area} is not size[0] · size[1] = {} (within 1e-9 relative)",
                            a * b
                        ),
                    ));
                }
                Some((a, b))
            }
            None => None,
        };
        let area = match (given, size) {
            (Some((area, _)), _) => area,
            (None, Some((a, b))) => a * b,
            (None, None) => {
                return Err(SpannedError::Schema {
                    span: span_of(f),
                    message: format!(
                        "body `{name}`: facet {k}: missing key `area` (required unless `size` is given)"
                    ),
                });
            }
        };
        let mut facet = Facet::new(area, normal, at)
            .with_specular(coefficient(&spec.specular, 0.0, nonfinite("specular"))?)
            .with_diffuse(coefficient(&spec.diffuse, 0.0, nonfinite("diffuse"))?)
            .with_drag(coefficient(&spec.drag, DEFAULT_DRAG, nonfinite("drag"))?);
        match (size, edge) {
            (Some((a, b)), dir) => facet = facet.with_size(a, b, dir.unwrap_or(facet.edges[0])),
            (None, Some(dir)) => {
                // A square turned to `edge`; its area stays exactly as written.
                let side = area.sqrt();
                facet = facet.with_size(side, side, dir);
                facet.area = area;
            }
            (None, None) => {}
        }
        facets.push(facet);
    }
    if let Some(c) = &body.facets_from_shape {
        let Some(shape) = &entry.shape else {
            return Err(SpannedError::Schema {
                span: span_of(c),
                message: format!("body `{name}`: `facets_from_shape` requires a `shape`"),
            });
        };
        let spec = c.get_ref();
        let nonfinite = |field: &str| {
            let what = format!("body `{name}`: facets_from_shape.{field}");
            move |span| SpannedError::Model {
                span,
                error: ModelError::NonFinite(what.clone()),
            }
        };
        let specular = coefficient(&spec.specular, 0.0, nonfinite("specular"))?;
        let diffuse = coefficient(&spec.diffuse, 0.0, nonfinite("diffuse"))?;
        let drag = coefficient(&spec.drag, DEFAULT_DRAG, nonfinite("drag"))?;
        facets.extend(facets_of_box(shape, &entry.com).map(|f| {
            f.with_specular(specular)
                .with_diffuse(diffuse)
                .with_drag(drag)
        }));
    }
    Ok(facets)
}

fn v3(a: &[f64; 3]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

fn span_of<T>(s: &Spanned<T>) -> Option<Range<usize>> {
    Some(s.span())
}

impl ModelFile {
    /// The base kind (free unless `[base] kind = "fixed"`).
    pub fn base_kind(&self) -> BaseKind {
        self.base
            .as_ref()
            .map(|b| b.get_ref().kind.into())
            .unwrap_or_default()
    }

    /// Validates and builds the model. Errors carry the span of the body, hinge or key
    /// concerned; [`SpannedError::in_file`] names the file and line. A file with flexible
    /// bodies is refused (the rigid [`Model`] has no elastic coordinates): it is
    /// [`super::read_flex_model`]'s.
    pub fn build(&self) -> Result<Model, SpannedError> {
        if let Some((name, f)) = self.body.iter().find_map(|b| {
            let b = b.get_ref();
            b.flexible.as_ref().map(|f| (b.name.get_ref(), f))
        }) {
            return Err(SpannedError::Schema {
                span: Some(f.get_ref().key_span().unwrap_or_else(|| f.span())),
                message: format!(
                    "body `{name}`: flexible bodies are read only by the flexible reader \
                     (`read_flex_model`); the rigid algorithms (`Model`) do not take them: run \
                     the model in a scene or with `satsim dynamics`"
                ),
            });
        }
        let builder = self.builder()?;
        builder.build().map_err(|error| SpannedError::Model {
            span: self.locate(&error),
            error,
        })
    }

    /// The validated entries as a [`ModelBuilder`] (not yet built; `[body.flexible]` not read).
    pub(crate) fn builder(&self) -> Result<ModelBuilder, SpannedError> {
        let mut builder = ModelBuilder::new(self.base_kind());
        for b in &self.body {
            let body = b.get_ref();
            let name = body.name.get_ref();
            super::column_name(name).map_err(|m| SpannedError::Schema {
                span: span_of(&body.name),
                message: format!("`body.name` {m}"),
            })?;
            let mass = *body.mass.get_ref();
            let nonfinite = |field: &str, span: Option<Range<usize>>| SpannedError::Model {
                span,
                error: ModelError::NonFinite(format!("body `{name}`: {field}")),
            };
            if !mass.is_finite() {
                return Err(nonfinite("mass", span_of(&body.mass)));
            }
            let inertia = match &body.inertia {
                Some(i) => {
                    if !i.get_ref().iter().flatten().all(|x| x.is_finite()) {
                        return Err(nonfinite("inertia", span_of(i)));
                    }
                    let r = i.get_ref();
                    Mat3::new(
                        r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1],
                        r[2][2],
                    )
                }
                None if mass == 0.0 => Mat3::zeros(),
                None => {
                    return Err(SpannedError::Schema {
                        span: span_of(b),
                        message: format!(
                            "body `{name}`: missing key `inertia` (required unless mass is 0)"
                        ),
                    });
                }
            };
            let com = match &body.com {
                Some(c) => {
                    if !c.get_ref().iter().all(|x| x.is_finite()) {
                        return Err(nonfinite("com", span_of(c)));
                    }
                    v3(c.get_ref())
                }
                None => Vec3::zeros(),
            };
            let mut entry = Body::new(name.clone(), mass, inertia).with_com(com);
            if let Some(shape) = &body.shape {
                let shape = shape.get_ref();
                if !shape.size.get_ref().iter().all(|x| x.is_finite()) {
                    return Err(nonfinite("shape.box", span_of(&shape.size)));
                }
                let mut drawn = BoxShape::new(v3(shape.size.get_ref()));
                if let Some(at) = &shape.at {
                    if !at.get_ref().iter().all(|x| x.is_finite()) {
                        return Err(nonfinite("shape.at", span_of(at)));
                    }
                    drawn = drawn.at(v3(at.get_ref()));
                }
                entry = entry.with_shape(drawn);
            }
            entry.facets = facets_of(b, &entry)?;
            builder.push_body(entry);
        }
        for h in &self.hinge {
            let hinge = h.get_ref();
            let name = hinge.name.get_ref();
            super::column_name(name).map_err(|m| SpannedError::Schema {
                span: span_of(&hinge.name),
                message: format!("`hinge.name` {m}"),
            })?;
            let nonfinite = |field: &str, span: Option<Range<usize>>| SpannedError::Model {
                span,
                error: ModelError::NonFinite(format!("hinge `{name}`: {field}")),
            };
            let vec = |field: &str, x: &Option<Spanned<[f64; 3]>>| match x {
                Some(s) if !s.get_ref().iter().all(|x| x.is_finite()) => {
                    Err(nonfinite(field, span_of(s)))
                }
                Some(s) => Ok(v3(s.get_ref())),
                None => Ok(Vec3::zeros()),
            };
            let axis = vec("axis", &Some(hinge.axis.clone()))?;
            let at = vec("at", &hinge.at)?;
            let child_at = vec("child_at", &hinge.child_at)?;
            let rotation = match &hinge.rotation {
                Some(r) if !r.get_ref().iter().all(|x| x.is_finite()) => {
                    return Err(nonfinite("rotation", span_of(r)));
                }
                Some(r) => {
                    let [w, x, y, z] = *r.get_ref();
                    Quaternion::new(w, x, y, z)
                }
                None => Quaternion::identity(),
            };
            builder.push_hinge(
                Hinge::revolute(
                    name.clone(),
                    hinge.parent.get_ref().clone(),
                    hinge.child.get_ref().clone(),
                    axis,
                )
                .at(at)
                .child_at(child_at)
                .rotation(rotation)
                .armature(hinge.armature.as_ref().map_or(0.0, |a| *a.get_ref())),
            );
        }
        Ok(builder)
    }

    fn body_named(&self, name: &str, occurrence: usize) -> Option<&BodyFile> {
        self.body
            .iter()
            .map(|b| b.get_ref())
            .filter(|b| b.name.get_ref() == name)
            .nth(occurrence)
    }

    fn hinge_named(&self, name: &str, occurrence: usize) -> Option<&HingeFile> {
        self.hinge
            .iter()
            .map(|h| h.get_ref())
            .filter(|h| h.name.get_ref() == name)
            .nth(occurrence)
    }

    fn body_span(&self, name: &str) -> Option<Range<usize>> {
        self.body_named(name, 0).map(|b| b.name.span())
    }

    fn hinge_span(&self, name: &str) -> Option<Range<usize>> {
        self.hinge_named(name, 0).map(|h| h.name.span())
    }

    /// The span of `body`'s facet `index`: the key `key` picks where given, else the facet's
    /// entry; an index past the listed facets is one of `facets_from_shape`'s faces.
    fn facet_span(
        &self,
        body: &str,
        index: usize,
        key: impl Fn(&FacetFile) -> Option<Range<usize>>,
    ) -> Option<Range<usize>> {
        let b = self.body_named(body, 0)?;
        match b.facets.get(index) {
            Some(f) => key(f.get_ref()).or_else(|| Some(f.span())),
            None => b
                .facets_from_shape
                .as_ref()
                .map(Spanned::span)
                .or_else(|| Some(b.name.span())),
        }
    }

    /// The span of the body, hinge or key a [`ModelError`] is about. The builder checks the
    /// entries in file order, so the first entry of a name is the one concerned (the second
    /// for duplicates).
    pub(crate) fn locate(&self, error: &ModelError) -> Option<Range<usize>> {
        match error {
            ModelError::NoBodies => None,
            ModelError::DuplicateBody(n) => self.body_named(n, 1).map(|b| b.name.span()),
            ModelError::DuplicateHinge(n) => self.hinge_named(n, 1).map(|h| h.name.span()),
            ModelError::UnknownBody { hinge, role, .. } => {
                self.hinge_named(hinge, 0).map(|h| match *role {
                    "parent" => h.parent.span(),
                    _ => h.child.span(),
                })
            }
            ModelError::SelfLoop(hinge) | ModelError::RootIsChild { hinge, .. } => {
                self.hinge_named(hinge, 0).map(|h| h.child.span())
            }
            ModelError::TwoParents { second, .. } => {
                self.hinge_named(second, 0).map(|h| h.child.span())
            }
            ModelError::NoParent(b) | ModelError::MasslessLeaf(b) => self.body_span(b),
            ModelError::Cycle(bodies) => bodies.first().and_then(|b| self.body_span(b)),
            ModelError::NonFinite(what) => {
                let name = |prefix: &str| {
                    what.strip_prefix(prefix)
                        .and_then(|r| r.split('`').next())
                        .map(str::to_owned)
                };
                if let Some(b) = name("body `") {
                    self.body_span(&b)
                } else if let Some(h) = name("hinge `") {
                    self.hinge_span(&h)
                } else {
                    None
                }
            }
            ModelError::NegativeMass { body, .. } => {
                self.body_named(body, 0).map(|b| b.mass.span())
            }
            ModelError::InertiaNotSymmetric(body)
            | ModelError::InertiaNotPositive { body, .. }
            | ModelError::InertiaTriangle { body, .. } => self.body_named(body, 0).map(|b| {
                b.inertia
                    .as_ref()
                    .map(|i| i.span())
                    .unwrap_or_else(|| b.name.span())
            }),
            ModelError::ShapeSize { body, .. } => self.body_named(body, 0).map(|b| {
                b.shape
                    .as_ref()
                    .map(|s| s.get_ref().size.span())
                    .unwrap_or_else(|| b.name.span())
            }),
            ModelError::FacetArea { body, index, .. }
            | ModelError::FacetTooLarge { body, index, .. } => {
                self.facet_span(body, *index, |f| f.area.as_ref().map(Spanned::span))
            }
            ModelError::FacetNormal { body, index, .. } => {
                self.facet_span(body, *index, |f| Some(f.normal.span()))
            }
            ModelError::FacetTooFar { body, index, .. } => {
                self.facet_span(body, *index, |f| Some(f.at.span()))
            }
            ModelError::FacetOptical { body, index, .. } => self.facet_span(body, *index, |f| {
                f.specular
                    .as_ref()
                    .or(f.diffuse.as_ref())
                    .map(Spanned::span)
            }),
            ModelError::FacetDrag { body, index, .. } => {
                self.facet_span(body, *index, |f| f.drag.as_ref().map(Spanned::span))
            }
            ModelError::FacetEdges { body, index } => {
                self.facet_span(body, *index, |f| f.edge.as_ref().map(Spanned::span))
            }
            ModelError::NegativeArmature { hinge, .. } => self.hinge_named(hinge, 0).map(|h| {
                h.armature
                    .as_ref()
                    .map(|a| a.span())
                    .unwrap_or_else(|| h.name.span())
            }),
            ModelError::AxisNorm { hinge, .. } => self.hinge_named(hinge, 0).map(|h| h.axis.span()),
            ModelError::RotationNorm { hinge, .. } => self.hinge_named(hinge, 0).map(|h| {
                h.rotation
                    .as_ref()
                    .map(|r| r.span())
                    .unwrap_or_else(|| h.name.span())
            }),
        }
    }
}

/// Deserialises a model file's text into a [`ModelFile`] without building it. `origin` names
/// the file in errors.
pub fn parse_model_file(text: &str, origin: &Path) -> Result<ModelFile, FileError> {
    let path = origin.to_path_buf();
    if text.trim().is_empty() {
        return Err(FileError::Empty { path });
    }
    let located = |e: &toml::de::Error| e.span().map(|s| line_of(text, s.start));
    // Parsed first, to tell syntax errors from schema errors.
    let doc = super::Document::parse(text).map_err(|e| FileError::Syntax {
        line: located(&e),
        message: e.message().trim_end().to_owned(),
        path: path.clone(),
    })?;
    ModelFile::deserialize(doc.deserializer()).map_err(|e| FileError::Schema {
        line: located(&e),
        message: with_key(&e, schema_message(e.message())),
        path,
    })
}

/// Prefixes a toml error's message with the dotted key it concerns, when toml knows it.
pub fn with_key(e: &toml::de::Error, message: String) -> String {
    let mut bare = e.clone();
    bare.set_input(None);
    let shown = bare.to_string();
    let key = shown
        .lines()
        .find_map(|l| l.strip_prefix("in `").and_then(|r| r.strip_suffix('`')));
    match key {
        Some(k) if !k.is_empty() => format!("`{k}`: {message}"),
        _ => message,
    }
}

/// Rewords serde's messages in the file's vocabulary (keys, not fields).
pub(crate) fn schema_message(m: &str) -> String {
    let owned = m.trim_end().replace("expected f64", "expected a number");
    let m = owned.as_str();
    if let Some(rest) = m.strip_prefix("unknown field ") {
        format!("unknown key {rest}")
    } else if let Some(rest) = m.strip_prefix("missing field ") {
        format!("missing required key {rest}")
    } else if let Some(rest) = m.strip_prefix("unknown variant ") {
        format!("unknown value {rest}")
    } else {
        m.to_owned()
    }
}

/// Parses and builds a model file's text. `origin` names the file in errors.
pub fn parse_model(text: &str, origin: &Path) -> Result<(Model, ModelFile), FileError> {
    let file = parse_model_file(text, origin)?;
    let model = file.build().map_err(|e| e.in_file(text, origin))?;
    Ok((model, file))
}

/// Reads and builds the model file at `path`.
pub fn read_model(path: impl AsRef<Path>) -> Result<Model, FileError> {
    let path = path.as_ref();
    let text = read_text(path)?;
    parse_model(&text, path).map(|(m, _)| m)
}
