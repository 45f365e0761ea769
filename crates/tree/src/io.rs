//! Readers for the model TOML and state JSON files of the command-line contract
//! (`cli-contract.md` sections 1 and 2).
//!
//! - [`read_model`] / [`parse_model`]: a model file into a validated [`Model`]. The file is
//!   first deserialised into a [`ModelFile`] (strict: unknown keys are errors), which keeps the
//!   byte span of every body, hinge and key, so that every error names the line concerned.
//! - [`read_state`] / [`parse_state`]: a state file into a [`State`] in the engine's layout.
//!
//! Every [`FileError`] displays as `PATH:LINE: message` (or `PATH: field: message` where
//! only the field is known, as for JSON arrays of the wrong length).
//!
//! ```
//! use satsim_tree::io::{parse_model, parse_state};
//! use std::path::Path;
//! let text = r#"
//! [[body]]
//! name = "bus"
//! mass = 500
//! inertia = [[40, 0, 0], [0, 40, 0], [0, 0, 30]]
//!
//! [[body]]
//! name = "panel"
//! mass = 20.0
//! inertia = [[1.7, 0, 0], [0, 6.7, 0], [0, 0, 8.3]]
//!
//! [[hinge]]
//! name = "h"
//! parent = "bus"
//! child = "panel"
//! axis = [1, 0, 0]
//! at = [0, 1, 0]
//! "#;
//! let (model, _file) = parse_model(text, Path::new("sat.toml"))?;
//! assert_eq!(model.nv(), 7);
//! let state = parse_state(r#"{"hinges": {"angle": [0.1], "rate": [0.0]}}"#, Path::new("s.json"), &model)?;
//! assert_eq!(state.q, [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1]);
//!
//! let bad = text.replace("parent = \"bus\"", "parent = \"bsu\"");
//! let err = parse_model(&bad, Path::new("bad.toml")).unwrap_err();
//! assert_eq!(err.to_string(), "bad.toml:14: hinge `h`: unknown parent body `bsu`");
//! # Ok::<(), satsim_tree::io::FileError>(())
//! ```

use crate::error::ModelError;
use crate::model::{BaseKind, Body, BoxShape, Hinge, Model, ModelBuilder, UNIT_NORM_TOLERANCE};
use crate::spatial::{Mat3, Vec3};
use nalgebra::Quaternion;
use serde::Deserialize;
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};
use thiserror::Error;
use toml::Spanned;

// ---------------------------------------------------------------------------------------------
// Errors

/// Why a model or state file could not be read. The message always starts with the file's
/// path and, where known, `:LINE` (1-based).
#[derive(Debug, Error)]
pub enum FileError {
    /// The file could not be read.
    #[error("{}: cannot read the file: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// The file is empty (or holds only white space).
    #[error("{}: the file is empty", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// A TOML or JSON syntax error.
    #[error("{}: syntax error: {message}", Loc(path, *line))]
    Syntax {
        /// The file.
        path: PathBuf,
        /// The line, when known.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// Well-formed, but not the contract's schema: a missing required key, an unknown key, a
    /// value of the wrong type, an unknown `base.kind`.
    #[error("{}: {message}", Loc(path, *line))]
    Schema {
        /// The file.
        path: PathBuf,
        /// The line, when known.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// The model is inconsistent ([`ModelError`]), at the line of the body, hinge or key
    /// concerned.
    #[error("{}: {source}", Loc(path, *line))]
    Model {
        /// The file.
        path: PathBuf,
        /// The line, when known.
        line: Option<usize>,
        /// The builder's error.
        source: ModelError,
    },
    /// A state that does not fit the model (wrong array length, non-unit attitude,
    /// non-finite number).
    #[error("{}: {field}: {message}", path.display())]
    State {
        /// The state file (or the file holding the state table).
        path: PathBuf,
        /// The field, such as `hinges.angle`.
        field: String,
        /// What is wrong.
        message: String,
    },
}

impl FileError {
    /// The file concerned.
    pub fn path(&self) -> &Path {
        match self {
            FileError::Read { path, .. }
            | FileError::Empty { path }
            | FileError::Syntax { path, .. }
            | FileError::Schema { path, .. }
            | FileError::Model { path, .. }
            | FileError::State { path, .. } => path,
        }
    }
    /// The line concerned (1-based), when known.
    pub fn line(&self) -> Option<usize> {
        match self {
            FileError::Syntax { line, .. }
            | FileError::Schema { line, .. }
            | FileError::Model { line, .. } => *line,
            _ => None,
        }
    }
}

/// `path` or `path:line`.
struct Loc<'a>(&'a Path, Option<usize>);

impl fmt::Display for Loc<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.1 {
            Some(line) => write!(f, "{}:{line}", self.0.display()),
            None => write!(f, "{}", self.0.display()),
        }
    }
}

/// The 1-based line of byte `offset` in `text`.
pub fn line_of(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// An error of [`ModelFile::build`], located by a byte span in the TOML text the
/// [`ModelFile`] was read from. [`SpannedError::in_file`] turns it into a [`FileError`].
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SpannedError {
    /// A required key is missing (`inertia` of a body with mass).
    #[error("{message}")]
    Schema {
        /// Where.
        span: Option<Range<usize>>,
        /// What is wrong.
        message: String,
    },
    /// The builder rejected the model.
    #[error("{error}")]
    Model {
        /// Where.
        span: Option<Range<usize>>,
        /// The builder's error.
        error: ModelError,
    },
}

impl SpannedError {
    /// The byte span concerned, when known.
    pub fn span(&self) -> Option<Range<usize>> {
        match self {
            SpannedError::Schema { span, .. } | SpannedError::Model { span, .. } => span.clone(),
        }
    }
    /// Names the file `origin` and the line in `text` (the text the model was read from).
    pub fn in_file(self, text: &str, origin: &Path) -> FileError {
        let line = self.span().map(|s| line_of(text, s.start));
        let path = origin.to_path_buf();
        match self {
            SpannedError::Schema { message, .. } => FileError::Schema {
                path,
                line,
                message,
            },
            SpannedError::Model { error, .. } => FileError::Model {
                path,
                line,
                source: error,
            },
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Model file

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
    #[serde(default)]
    pub com: Option<Spanned<[f64; 3]>>,
    /// Inertia about the centre of mass, body axes (kg m²), rows; required unless the mass
    /// is 0 (then zero by default).
    #[serde(default)]
    pub inertia: Option<Spanned<[[f64; 3]; 3]>>,
    /// `shape = { box = [lx, ly, lz], at = [x, y, z] }`: how to draw the body (optional;
    /// no algorithm reads it).
    #[serde(default)]
    pub shape: Option<Spanned<ShapeFile>>,
}

/// A body's `shape`: a box of edge lengths `box` (m, body axes, each positive) centred at
/// `at` (m, body frame; default the body's `com`). For drawing only.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShapeFile {
    /// Edge lengths along the body's x, y, z axes (m).
    #[serde(rename = "box")]
    pub size: Spanned<[f64; 3]>,
    /// The box's centre in the body frame (m), default the centre of mass.
    #[serde(default)]
    pub at: Option<Spanned<[f64; 3]>>,
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
    pub axis: Spanned<[f64; 3]>,
    /// Hinge point in the parent frame (m), default zero.
    #[serde(default)]
    pub at: Option<Spanned<[f64; 3]>>,
    /// Hinge point in the child frame (m), default zero.
    #[serde(default)]
    pub child_at: Option<Spanned<[f64; 3]>>,
    /// Child frame relative to the parent at zero angle, `[w, x, y, z]`, default identity.
    #[serde(default)]
    pub rotation: Option<Spanned<[f64; 4]>>,
    /// Armature (kg m²), default zero: rotor inertia about the axis (an extension of the
    /// contract, used to regularise a gimbal lock).
    #[serde(default)]
    pub armature: Option<Spanned<f64>>,
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
    /// concerned; [`SpannedError::in_file`] names the file and line.
    pub fn build(&self) -> Result<Model, SpannedError> {
        let mut builder = ModelBuilder::new(self.base_kind());
        for b in &self.body {
            let body = b.get_ref();
            let name = body.name.get_ref();
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
            builder.push_body(entry);
        }
        for h in &self.hinge {
            let hinge = h.get_ref();
            let name = hinge.name.get_ref();
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
        builder.build().map_err(|error| SpannedError::Model {
            span: self.locate(&error),
            error,
        })
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

    /// The span of the body, hinge or key a [`ModelError`] is about. The builder checks the
    /// entries in file order, so the first entry of a name is the one concerned (the second
    /// for duplicates).
    fn locate(&self, error: &ModelError) -> Option<Range<usize>> {
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

fn read_text(path: &Path) -> Result<String, FileError> {
    let text = std::fs::read_to_string(path).map_err(|source| FileError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    if text.trim().is_empty() {
        return Err(FileError::Empty {
            path: path.to_path_buf(),
        });
    }
    Ok(text)
}

/// Deserialises a model file's text into a [`ModelFile`] without building it. `origin` names
/// the file in errors.
pub fn parse_model_file(text: &str, origin: &Path) -> Result<ModelFile, FileError> {
    let path = origin.to_path_buf();
    if text.trim().is_empty() {
        return Err(FileError::Empty { path });
    }
    let located = |e: &toml::de::Error| e.span().map(|s| line_of(text, s.start));
    // A plain parse first, to tell syntax errors from schema errors.
    if let Err(e) = text.parse::<toml::Table>() {
        return Err(FileError::Syntax {
            line: located(&e),
            message: e.message().trim_end().to_owned(),
            path,
        });
    }
    toml::from_str::<ModelFile>(text).map_err(|e| FileError::Schema {
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
fn schema_message(m: &str) -> String {
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

// ---------------------------------------------------------------------------------------------
// State file

/// A state in the engine's layout (see [`crate::model`]): `q` (`nq`), `v` (`nv`) and the
/// generalised forces `tau` (`nv`, zero on the base coordinates, hinge torques after).
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    /// Positions: `[attitude w x y z, position (zero), angles…]` or `[angles…]`.
    pub q: Vec<f64>,
    /// Velocities: `[ω, v, rates…]` or `[rates…]`.
    pub v: Vec<f64>,
    /// Generalised forces: zeros on the base, then the hinge torques.
    pub tau: Vec<f64>,
}

impl State {
    /// The state at rest in the neutral configuration, no torque.
    pub fn rest(model: &Model) -> Self {
        Self {
            q: model.neutral(),
            v: vec![0.0; model.nv()],
            tau: vec![0.0; model.nv()],
        }
    }
}

/// The state file (contract section 2), as written. Also deserialisable from TOML (a scene's
/// inline `[initial]` table).
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StateFile {
    /// The root's state (free base; ignored for a fixed base).
    #[serde(default)]
    pub base: Option<BaseStateFile>,
    /// The hinges' state, in the model file's hinge order (may be omitted only for a model
    /// without hinges).
    #[serde(default)]
    pub hinges: Option<HingesStateFile>,
}

/// `base` of a state file.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BaseStateFile {
    /// Root body frame relative to inertial, `[w, x, y, z]` (default identity).
    #[serde(default)]
    pub attitude: Option<Vec<f64>>,
    /// Root angular velocity in root axes (rad/s), default zero.
    #[serde(default)]
    pub angular_velocity: Option<Vec<f64>>,
    /// Velocity of the root frame's origin in root axes (m/s), default zero.
    #[serde(default)]
    pub velocity: Option<Vec<f64>>,
}

/// `hinges` of a state file.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HingesStateFile {
    /// Angles (rad), one per hinge.
    pub angle: Vec<f64>,
    /// Rates (rad/s), one per hinge.
    pub rate: Vec<f64>,
    /// Torques (N m), one per hinge, default zeros.
    #[serde(default)]
    pub torque: Option<Vec<f64>>,
}

/// A state that does not fit its model: the field (such as `hinges.angle`) and the reason.
#[derive(Clone, Debug, PartialEq, Eq, Error)]
#[error("{field}: {message}")]
pub struct FieldError {
    /// The field, such as `hinges.angle`.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

impl FieldError {
    fn new(field: &str, message: impl Into<String>) -> Self {
        Self {
            field: field.to_owned(),
            message: message.into(),
        }
    }
    /// Names the file holding the state.
    pub fn in_file(self, origin: &Path) -> FileError {
        FileError::State {
            path: origin.to_path_buf(),
            field: self.field,
            message: self.message,
        }
    }
}

fn check_array(field: &str, x: &[f64], n: usize, what: &str) -> Result<(), FieldError> {
    if x.len() != n {
        return Err(FieldError::new(
            field,
            format!("expected {n} entries ({what}), got {}", x.len()),
        ));
    }
    if let Some(i) = x.iter().position(|x| !x.is_finite()) {
        return Err(FieldError::new(
            field,
            format!("entry {i} is not a finite number"),
        ));
    }
    Ok(())
}

/// How far from unit norm a state's attitude quaternion may be: it is normalised, silently
/// within [`UNIT_NORM_TOLERANCE`] (rounding), with a warning ([`StateFile::warnings`]) up to
/// this (a quaternion typed with a few digits), and refused beyond.
pub const STATE_ATTITUDE_TOLERANCE: f64 = 1e-3;

impl StateFile {
    /// What [`StateFile::resolve`] accepts but a user should hear about: an attitude
    /// quaternion normalised from a norm more than [`UNIT_NORM_TOLERANCE`] away from 1.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        if let Some(a) = self.base.as_ref().and_then(|b| b.attitude.as_ref()) {
            let norm = a.iter().map(|x| x * x).sum::<f64>().sqrt();
            if (norm - 1.0).abs() > UNIT_NORM_TOLERANCE
                && (norm - 1.0).abs() <= STATE_ATTITUDE_TOLERANCE
            {
                out.push(format!(
                    "base.attitude: quaternion norm {norm} is not 1; normalised"
                ));
            }
        }
        out
    }

    /// Checks the state against `model` and lays it out as the engine's `q`, `v`, `tau`.
    pub fn resolve(&self, model: &Model) -> Result<State, FieldError> {
        let mut state = State::rest(model);
        let nh = model.n_hinges();
        let (nq0, nv0) = (model.base_nq(), model.base_nv());
        // A fixed base ignores the `base` object.
        if let (BaseKind::Free, Some(base)) = (model.base, &self.base) {
            if let Some(a) = &base.attitude {
                check_array("base.attitude", a, 4, "a quaternion [w, x, y, z]")?;
                let norm = a.iter().map(|x| x * x).sum::<f64>().sqrt();
                if (norm - 1.0).abs() > STATE_ATTITUDE_TOLERANCE {
                    return Err(FieldError::new(
                        "base.attitude",
                        format!("quaternion norm {norm} is not 1 (within 1e-3)"),
                    ));
                }
                for (k, x) in a.iter().enumerate() {
                    state.q[k] = x / norm;
                }
            }
            if let Some(w) = &base.angular_velocity {
                check_array("base.angular_velocity", w, 3, "a vector")?;
                state.v[..3].copy_from_slice(w);
            }
            if let Some(u) = &base.velocity {
                check_array("base.velocity", u, 3, "a vector")?;
                state.v[3..6].copy_from_slice(u);
            }
        }
        match &self.hinges {
            Some(h) => {
                check_array("hinges.angle", &h.angle, nh, "one per hinge")?;
                check_array("hinges.rate", &h.rate, nh, "one per hinge")?;
                state.q[nq0..].copy_from_slice(&h.angle);
                state.v[nv0..].copy_from_slice(&h.rate);
                if let Some(t) = &h.torque {
                    check_array("hinges.torque", t, nh, "one per hinge")?;
                    state.tau[nv0..].copy_from_slice(t);
                }
            }
            None if nh == 0 => {}
            None => {
                return Err(FieldError::new(
                    "hinges",
                    format!(
                        "missing (the model has {nh} hinges: `hinges.angle` and `hinges.rate` are required)"
                    ),
                ));
            }
        }
        Ok(state)
    }
}

/// Parses a state file's JSON text for `model`. `origin` names the file in errors.
pub fn parse_state(text: &str, origin: &Path, model: &Model) -> Result<State, FileError> {
    parse_state_file(text, origin)?
        .resolve(model)
        .map_err(|e| e.in_file(origin))
}

/// Deserialises a state file's JSON text without checking it against a model.
pub fn parse_state_file(text: &str, origin: &Path) -> Result<StateFile, FileError> {
    let path = origin.to_path_buf();
    if text.trim().is_empty() {
        return Err(FileError::Empty { path });
    }
    serde_json::from_str::<StateFile>(text).map_err(|e| {
        let line = (e.line() > 0).then_some(e.line());
        // serde_json appends " at line L column C" to its messages: the line is ours.
        let full = e.to_string();
        let message = match full.rfind(" at line ") {
            Some(k) if line.is_some() => full[..k].to_owned(),
            _ => full,
        };
        match e.classify() {
            serde_json::error::Category::Data => FileError::Schema {
                path,
                line,
                message: schema_message(&message),
            },
            _ => FileError::Syntax {
                path,
                line,
                message,
            },
        }
    })
}

/// Reads the state file at `path` for `model`.
pub fn read_state(path: impl AsRef<Path>, model: &Model) -> Result<State, FileError> {
    let path = path.as_ref();
    let text = read_text(path)?;
    parse_state(&text, path, model)
}

#[cfg(test)]
mod tests;
