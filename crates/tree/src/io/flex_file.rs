//! The model file's `[body.flexible]` (contract section 14) read into a [`FlexModel`], and
//! the modes file a body may name instead of a `beam`. The `[body.flexible]` table's own
//! types ([`FlexibleFile`](super::FlexibleFile), [`BeamFile`]) are the model file's, in
//! `model_file.rs` with the rest of its schema: this reader imports that file, not the
//! reverse.
//!
//! The modes file (TOML, body frame of the body that names it, SI units):
//! `frequencies_hz` (natural frequencies with the body frame held, Hz, one per mode),
//! optional `damping` (modal damping ratio per mode), `mass`, `com`, `inertia` (the mass, centre
//! of mass and inertia about it of the structure the modes describe, added to the body's own
//! as a beam's are), `momentum` (per mode, the column of `P`: the spatial momentum
//! `[n; p]` = `[angular; linear]` about the body origin that a unit modal rate gives, modes
//! mass-normalised), and `[[node]]` entries (`name`, `at`, per mode the `translation` and
//! `rotation` of the structure at `at`). A hinge whose parent is the body is carried by the
//! node whose `at` equals its own `at` within [`MODES_FILE_NODE_TOLERANCE`]. An optional
//! `[stiffening]` block ([`StiffeningFile`]) gives the modes' second-order inertia as a
//! structure along one axis has it (a beam's, written by [`write_modes_file`]): with it the
//! body stiffens under spin and acceleration as a `beam` does, and `stiffening` defaults to
//! on; without it `stiffening = true` is refused (nothing would compute the terms).

use super::error::{FileError, SpannedError, line_of};
use super::exact::exact;
use super::model_file::{BeamFile, ModelFile, parse_model_file, schema_message, with_key};
use super::read_text;
use crate::error::Num;
use crate::flexible::model::MAX_BEAM_MODES;
use crate::flexible::{
    Beam, FlexError, FlexModel, Flexible, ModalData, Modes, NodeShape, Stiffening,
    StiffeningIntegrals, WatchPoint,
};
use crate::model::{Body, UNIT_NORM_TOLERANCE};
use crate::spatial::{Force, Mat3, RigidInertia, Vec3, skew};
use serde::Deserialize;
use std::fmt::Write;
use std::ops::Range;
use std::path::Path;
use toml::Spanned;

pub use crate::flexible::MODES_FILE_NODE_TOLERANCE;

/// Most modes a modes file may give a body. A model reduced for dynamics keeps the modes up
/// to a few times the bandwidth of interest: tens, not hundreds. Each right-hand side
/// factorises the body's dense block of its modes (cost growing as their cube), and the
/// highest mode sets the step an explicit method can take.
pub const MAX_FILE_MODES: usize = 100;

/// A modes file (see the module documentation), as written.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModesFile {
    /// Natural frequencies with the body frame held (Hz), positive, one per mode.
    pub frequencies_hz: Spanned<Vec<f64>>,
    /// Modal damping ratio per mode, `>= 0` (optional).
    #[serde(default)]
    pub damping: Option<Spanned<Vec<f64>>>,
    /// Mass of the structure (kg), positive.
    pub mass: Spanned<f64>,
    /// Its centre of mass, body frame (m), default zero.
    #[serde(default, deserialize_with = "exact")]
    pub com: Option<Spanned<[f64; 3]>>,
    /// Its inertia about its centre of mass, body axes (kg m²), rows.
    #[serde(deserialize_with = "exact")]
    pub inertia: Spanned<[[f64; 3]; 3]>,
    /// Per mode, `[n_x, n_y, n_z, p_x, p_y, p_z]`: the column of `P` (kg^½ m, kg^½).
    #[serde(deserialize_with = "exact")]
    pub momentum: Spanned<Vec<[f64; 6]>>,
    /// The nodes where hinges may sit.
    #[serde(default)]
    pub node: Vec<Spanned<NodeFile>>,
    /// The second-order inertia of a beam-like structure (optional; needed for
    /// `stiffening`).
    #[serde(default)]
    pub stiffening: Option<Spanned<StiffeningFile>>,
}

/// A modes file's `[stiffening]`: the modes' second-order inertia, for a structure along one
/// axis bending along one direction (a beam, a boom, a long panel), as
/// [`Stiffening::along`] takes it.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StiffeningFile {
    /// The root of the structure's axis, body frame (m).
    #[serde(deserialize_with = "exact")]
    pub root: Spanned<[f64; 3]>,
    /// The axis (unit), body axes.
    #[serde(deserialize_with = "exact")]
    pub axis: Spanned<[f64; 3]>,
    /// The bending direction (unit, normal to `axis`), body axes.
    #[serde(deserialize_with = "exact")]
    pub bend: Spanned<[f64; 3]>,
    /// `J₀ = ρA ∫ (L − x) φᵢ' φⱼ' dx` (1/m), `m` rows of `m`, symmetric.
    pub j0: Spanned<Vec<Vec<f64>>>,
    /// `J₁ = ρA ∫ (L² − x²)/2 φᵢ' φⱼ' dx`, `m` rows of `m`, symmetric.
    pub j1: Spanned<Vec<Vec<f64>>>,
    /// `S₁ₖ = ∫ ρA φₖ dx` (√kg), per mode.
    pub s1: Spanned<Vec<f64>>,
    /// `S₂ₖ = ∫ ρA x φₖ dx` (√kg m), per mode.
    pub s2: Spanned<Vec<f64>>,
}

/// A modes file's `[[node]]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct NodeFile {
    /// Unique name.
    pub name: Spanned<String>,
    /// The point, body frame (m).
    #[serde(deserialize_with = "exact")]
    pub at: Spanned<[f64; 3]>,
    /// Per mode, the point's translation (m/√kg).
    #[serde(deserialize_with = "exact")]
    pub translation: Spanned<Vec<[f64; 3]>>,
    /// Per mode, the small rotation of the structure there (rad/√kg).
    #[serde(deserialize_with = "exact")]
    pub rotation: Spanned<Vec<[f64; 3]>>,
    /// The foreshortening `C` there (`m` rows of `m`, 1/kg; used with `[stiffening]`, whose
    /// `axis` it is along): the node drawn in along the axis by `½ ηᵀ C η`, so that what it
    /// carries along the axis stiffens the bending.
    #[serde(default)]
    pub shortening: Option<Spanned<Vec<Vec<f64>>>>,
}

fn v3(a: &[f64; 3]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

impl ModesFile {
    /// Number of modes.
    pub fn modes(&self) -> usize {
        self.frequencies_hz.get_ref().len()
    }
    /// The modal data (`ω = 2π f`).
    pub fn modal_data(&self) -> ModalData {
        ModalData {
            momentum: self
                .momentum
                .get_ref()
                .iter()
                .map(|c| Force::from_slice(c))
                .collect(),
            omega: self
                .frequencies_hz
                .get_ref()
                .iter()
                .map(|f| 2.0 * std::f64::consts::PI * f)
                .collect(),
        }
    }
    /// The shapes at node `k`.
    pub fn node_shape(&self, k: usize) -> NodeShape {
        let n = self.node[k].get_ref();
        NodeShape {
            phi: n.translation.get_ref().iter().map(v3).collect(),
            psi: n.rotation.get_ref().iter().map(v3).collect(),
            shortening: n.shortening.as_ref().map(|c| c.get_ref().concat()),
        }
    }
    /// Every node as a point whose deflection a run watches, and where a load reaches the
    /// modes ([`WatchPoint`]).
    pub fn watch_points(&self) -> Vec<WatchPoint> {
        self.node
            .iter()
            .map(|n| {
                let n = n.get_ref();
                WatchPoint {
                    name: n.name.get_ref().clone(),
                    at: v3(n.at.get_ref()),
                    translation: n.translation.get_ref().iter().map(v3).collect(),
                    rotation: n.rotation.get_ref().iter().map(v3).collect(),
                    shortening: n.shortening.as_ref().map(|c| c.get_ref().concat()),
                }
            })
            .collect()
    }
    /// The structure's inertia about the body origin.
    pub fn inertia(&self) -> RigidInertia {
        let r = self.inertia.get_ref();
        RigidInertia::from_com(
            *self.mass.get_ref(),
            self.com.as_ref().map_or(Vec3::zeros(), |c| v3(c.get_ref())),
            Mat3::new(
                r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
            ),
        )
    }

    /// The `[stiffening]` block as the engine takes it (axis and bend normalised).
    pub fn stiffening(&self) -> Option<Box<Stiffening>> {
        let s = self.stiffening.as_ref()?.get_ref();
        let flat = |rows: &[Vec<f64>]| rows.concat();
        Some(Box::new(Stiffening::along(
            v3(s.root.get_ref()),
            v3(s.axis.get_ref()).normalize(),
            v3(s.bend.get_ref()).normalize(),
            StiffeningIntegrals {
                j0: flat(s.j0.get_ref()),
                j1: flat(s.j1.get_ref()),
                s1: s.s1.get_ref().clone(),
                s2: s.s2.get_ref().clone(),
            },
        )))
    }

    /// Checks the `[stiffening]` block of a file of `m` modes.
    fn validate_stiffening(&self, m: usize) -> Result<(), (Range<usize>, String)> {
        let Some(block) = &self.stiffening else {
            return Ok(());
        };
        let s = block.get_ref();
        for (key, v) in [("root", &s.root), ("axis", &s.axis), ("bend", &s.bend)] {
            if !v.get_ref().iter().all(|x| x.is_finite()) {
                return Err((v.span(), format!("`stiffening.{key}` is not finite")));
            }
        }
        let (a, b) = (v3(s.axis.get_ref()), v3(s.bend.get_ref()));
        for (key, v, span) in [("axis", a, s.axis.span()), ("bend", b, s.bend.span())] {
            if (v.norm() - 1.0).abs() > UNIT_NORM_TOLERANCE {
                return Err((
                    span,
                    format!(
                        "`stiffening.{key}` must be a unit vector, its norm is {}",
                        Num(v.norm())
                    ),
                ));
            }
        }
        if a.dot(&b).abs() > UNIT_NORM_TOLERANCE {
            return Err((
                s.bend.span(),
                format!(
                    "`stiffening.bend` must be normal to `axis` (their dot product is {})",
                    Num(a.dot(&b))
                ),
            ));
        }
        for (key, rows) in [("j0", &s.j0), ("j1", &s.j1)] {
            let r = rows.get_ref();
            if r.len() != m || r.iter().any(|row| row.len() != m) {
                return Err((
                    rows.span(),
                    format!("`stiffening.{key}`: {m} rows of {m} expected (one per mode)"),
                ));
            }
            if !r.iter().flatten().all(|x| x.is_finite()) {
                return Err((rows.span(), format!("`stiffening.{key}` is not finite")));
            }
            let scale = r.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
            for (i, row) in r.iter().enumerate() {
                if let Some(j) = (0..i).find(|&j| (row[j] - r[j][i]).abs() > 1e-9 * scale) {
                    return Err((
                        rows.span(),
                        format!("`stiffening.{key}` must be symmetric: rows {i} and {j} differ"),
                    ));
                }
            }
            // Products of the modes' slopes under a weight that is not negative: a Gram
            // matrix. An indefinite one would soften the structure under the load that
            // stiffens it, and fail only when the run starts.
            let lowest =
                nalgebra::SymmetricEigen::new(nalgebra::DMatrix::from_fn(m, m, |i, j| r[i][j]))
                    .eigenvalues
                    .min();
            if lowest < -1e-9 * scale {
                return Err((
                    rows.span(),
                    format!(
                        "`stiffening.{key}` must be positive semi-definite (the weighted products of the modes' slopes): its lowest eigenvalue is {}",
                        Num(lowest)
                    ),
                ));
            }
        }
        for (key, v) in [("s1", &s.s1), ("s2", &s.s2)] {
            if v.get_ref().len() != m {
                return Err((
                    v.span(),
                    format!("`stiffening.{key}`: {m} entries expected (one per mode)"),
                ));
            }
            if !v.get_ref().iter().all(|x| x.is_finite()) {
                return Err((v.span(), format!("`stiffening.{key}` is not finite")));
            }
        }
        Ok(())
    }

    /// Checks counts, signs and finiteness; the span and message of the first fault.
    fn validate(&self) -> Result<(), (Range<usize>, String)> {
        let m = self.modes();
        let finite = |x: &[f64]| x.iter().all(|x| x.is_finite());
        let f = &self.frequencies_hz;
        if m == 0 {
            return Err((f.span(), "`frequencies_hz`: at least one mode".into()));
        }
        if m > MAX_FILE_MODES {
            return Err((
                f.span(),
                format!(
                    "`frequencies_hz`: {m} modes, more than the {MAX_FILE_MODES} a body may have"
                ),
            ));
        }
        if !f.get_ref().iter().all(|x| x.is_finite() && *x > 0.0) {
            return Err((f.span(), "`frequencies_hz`: each must be positive".into()));
        }
        if let Some(d) = &self.damping {
            if d.get_ref().len() != m {
                return Err((d.span(), format!("`damping`: {m} entries expected")));
            }
            if !d.get_ref().iter().all(|x| x.is_finite() && *x >= 0.0) {
                return Err((d.span(), "`damping`: each must be finite and >= 0".into()));
            }
        }
        let mass = *self.mass.get_ref();
        if !(mass.is_finite() && mass > 0.0) {
            return Err((self.mass.span(), "`mass` must be positive".into()));
        }
        if let Some(c) = &self.com
            && !finite(c.get_ref())
        {
            return Err((c.span(), "`com` is not finite".into()));
        }
        if !finite(self.inertia.get_ref().as_flattened()) {
            return Err((self.inertia.span(), "`inertia` is not finite".into()));
        }
        // The structure's inertia must be a mass distribution's, as a body's must (symmetric,
        // semi-definite, its principal moments a triangle's): checked here, at the file's own
        // line, rather than in the sum with the body's rigid part.
        let r = self.inertia.get_ref();
        let structure = Body::new(
            "the modes file's structure",
            mass,
            Mat3::from_fn(|i, j| r[i][j]),
        );
        if let Err(e) = crate::model::check_body(&structure) {
            let why = e.to_string();
            let why = why
                .strip_prefix("body `the modes file's structure`: ")
                .unwrap_or(&why);
            let message = match why.strip_prefix("inertia ") {
                Some(rest) => format!("`inertia` {rest}"),
                None => format!("`inertia`: {why}"),
            };
            return Err((self.inertia.span(), message));
        }
        let p = &self.momentum;
        if p.get_ref().len() != m {
            return Err((
                p.span(),
                format!("`momentum`: {m} rows (one per mode) expected"),
            ));
        }
        if !finite(p.get_ref().as_flattened()) {
            return Err((p.span(), "`momentum` is not finite".into()));
        }
        for (k, n) in self.node.iter().enumerate() {
            let node = n.get_ref();
            let name = node.name.get_ref();
            if self.node[..k]
                .iter()
                .any(|o| o.get_ref().name.get_ref() == name)
            {
                return Err((node.name.span(), format!("node `{name}` is given twice")));
            }
            if !finite(node.at.get_ref()) {
                return Err((node.at.span(), format!("node `{name}`: `at` is not finite")));
            }
            for (key, rows) in [
                ("translation", &node.translation),
                ("rotation", &node.rotation),
            ] {
                if rows.get_ref().len() != m {
                    return Err((
                        rows.span(),
                        format!("node `{name}`: `{key}`: {m} rows (one per mode) expected"),
                    ));
                }
                if !finite(rows.get_ref().as_flattened()) {
                    return Err((rows.span(), format!("node `{name}`: `{key}` is not finite")));
                }
            }
            if let Some(c) = &node.shortening {
                let rows = c.get_ref();
                let at = |m: String| Err((c.span(), format!("node `{name}`: `shortening`: {m}")));
                if rows.len() != m || rows.iter().any(|r| r.len() != m) {
                    return at(format!("{m} rows of {m} (a matrix per mode pair) expected"));
                }
                if !finite(&rows.concat()) {
                    return at("not finite".into());
                }
                let largest = rows.concat().iter().fold(0.0f64, |a, x| a.max(x.abs()));
                let asymmetric = (0..m)
                    .flat_map(|i| (0..i).map(move |j| (i, j)))
                    .find(|&(i, j)| (rows[i][j] - rows[j][i]).abs() > 1e-12 * largest);
                if let Some((i, j)) = asymmetric {
                    return at(format!("not symmetric (row {}, column {})", i + 1, j + 1));
                }
            }
        }
        self.validate_stiffening(m)
    }
}

/// Parses and validates a modes file's text; `origin` names the file in errors.
pub fn parse_modes_file(text: &str, origin: &Path) -> Result<ModesFile, FileError> {
    let path = origin.to_path_buf();
    if text.trim().is_empty() {
        return Err(FileError::Empty { path });
    }
    let located = |e: &toml::de::Error| e.span().map(|s| line_of(text, s.start));
    if let Err(e) = text.parse::<toml::Table>() {
        return Err(FileError::Syntax {
            line: located(&e),
            message: e.message().trim_end().to_owned(),
            path,
        });
    }
    let file = toml::from_str::<ModesFile>(text).map_err(|e| FileError::Schema {
        line: located(&e),
        message: with_key(&e, schema_message(e.message())),
        path: path.clone(),
    })?;
    file.validate()
        .map_err(|(span, message)| FileError::Schema {
            line: Some(line_of(text, span.start)),
            message,
            path,
        })?;
    Ok(file)
}

/// A modes file describing `beam`'s modes (its rod mass, `P`, and the shapes at `nodes`, by
/// name and point), as the reader takes it back: numbers in shortest round-trip form.
pub fn write_modes_file(beam: &Beam, damping: Option<f64>, nodes: &[(&str, Vec3)]) -> String {
    let list = |x: &[f64]| {
        let items: Vec<String> = x.iter().map(|x| format!("{x:?}")).collect();
        format!("[{}]", items.join(", "))
    };
    let m = beam.modes;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Modes of an Euler-Bernoulli cantilever (satsim modes file, body frame, SI units):\n\
         # root {:?}, axis {:?}, bend {:?}, L = {:?} m, EI = {:?} N m^2, rho_A = {:?} kg/m.\n\
         # Written by satsim_tree::io::write_modes_file.",
        beam.root.as_slice(),
        beam.axis.as_slice(),
        beam.bend.as_slice(),
        beam.length,
        beam.ei,
        beam.rho_a
    );
    let hz: Vec<f64> = (1..=m)
        .map(|k| beam.omega(k) / (2.0 * std::f64::consts::PI))
        .collect();
    let _ = writeln!(s, "frequencies_hz = {}", list(&hz));
    if let Some(z) = damping {
        let _ = writeln!(s, "damping = {}", list(&vec![z; m]));
    }
    let mass = beam.mass();
    let com = beam.root + beam.axis * (0.5 * beam.length);
    let ic = (Mat3::identity() - beam.axis * beam.axis.transpose())
        * (mass * beam.length * beam.length / 12.0);
    let _ = writeln!(s, "mass = {mass:?}");
    let _ = writeln!(s, "com = {}", list(com.as_slice()));
    let rows: Vec<String> = (0..3)
        .map(|r| list(&[ic[(r, 0)], ic[(r, 1)], ic[(r, 2)]]))
        .collect();
    let _ = writeln!(s, "inertia = [{}]", rows.join(", "));
    let _ = writeln!(s, "# per mode: [n_x, n_y, n_z, p_x, p_y, p_z]");
    let p: Vec<String> = beam
        .momentum_coefficients()
        .iter()
        .map(|c| format!("  {},", list(&c.to_array())))
        .collect();
    let _ = writeln!(s, "momentum = [\n{}\n]", p.join("\n"));
    let si = beam.stiffening_integrals();
    let square = |x: &[f64]| {
        let rows: Vec<String> = x.chunks(m).map(list).collect();
        format!("[\n  {},\n]", rows.join(",\n  "))
    };
    let _ = writeln!(
        s,
        "\n# The second-order inertia (stiffening), per the model file reference.\n[stiffening]\nroot = {}\naxis = {}\nbend = {}\nj0 = {}\nj1 = {}\ns1 = {}\ns2 = {}",
        list(beam.root.as_slice()),
        list(beam.axis.as_slice()),
        list(beam.bend.as_slice()),
        square(&si.j0),
        square(&si.j1),
        list(&si.s1),
        list(&si.s2)
    );
    for (name, at) in nodes {
        let shape = beam.node(at);
        let rows = |x: &[Vec3]| {
            let r: Vec<String> = x.iter().map(|v| list(v.as_slice())).collect();
            format!("[{}]", r.join(", "))
        };
        let _ = writeln!(
            s,
            "\n[[node]]\nname = {name:?}\nat = {}\ntranslation = {}\nrotation = {}\nshortening = {}",
            list(at.as_slice()),
            rows(&shape.phi),
            rows(&shape.psi),
            square(&beam.foreshortening(at))
        );
    }
    s
}

/// The beam of `b`, each value checked at its key; `axis` and `bend` normalised when within
/// [`UNIT_NORM_TOLERANCE`] of unit.
fn beam_of(
    b: &BeamFile,
    schema: &dyn Fn(Range<usize>, String) -> FileError,
) -> Result<Beam, FileError> {
    let vec = |key: &str, x: &Spanned<[f64; 3]>| {
        if x.get_ref().iter().all(|x| x.is_finite()) {
            Ok(v3(x.get_ref()))
        } else {
            Err(schema(x.span(), format!("beam.{key} is not finite")))
        }
    };
    let unit = |key: &str, x: &Spanned<[f64; 3]>| {
        let v = vec(key, x)?;
        let n = v.norm();
        if (n - 1.0).abs() > UNIT_NORM_TOLERANCE {
            return Err(schema(
                x.span(),
                format!(
                    "beam.{key} {:?} must be a unit vector (norm {n}; within {UNIT_NORM_TOLERANCE} of 1 it is normalised)",
                    x.get_ref()
                ),
            ));
        }
        Ok(v / n)
    };
    let root = vec("root", &b.root)?;
    let axis = unit("axis", &b.axis)?;
    let bend = unit("bend", &b.bend)?;
    let dot = axis.dot(&bend);
    if dot.abs() > UNIT_NORM_TOLERANCE {
        return Err(schema(
            b.bend.span(),
            format!(
                "beam.bend must be perpendicular to beam.axis (axis · bend = {dot}, tolerance {UNIT_NORM_TOLERANCE})"
            ),
        ));
    }
    let positive = |key: &str, x: &Spanned<f64>| {
        let v = *x.get_ref();
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(schema(
                x.span(),
                format!("beam.{key} = {} must be positive", Num(v)),
            ))
        }
    };
    let length = positive("length", &b.length)?;
    let ei = positive("EI", &b.ei)?;
    let rho_a = positive("rho_A", &b.rho_a)?;
    let modes = *b.modes.get_ref();
    if !(1..=MAX_BEAM_MODES as i64).contains(&modes) {
        return Err(schema(
            b.modes.span(),
            format!("beam.modes = {modes}: 1 to {MAX_BEAM_MODES} modes are supported"),
        ));
    }
    Ok(Beam {
        root,
        axis,
        bend,
        length,
        ei,
        rho_a,
        modes: modes as usize,
    })
}

/// Adds a structure's inertia `add` (body frame) to `body`'s.
fn add_inertia(body: &mut Body, add: RigidInertia) {
    let sum = RigidInertia::from_com(body.mass, body.com, body.inertia) + add;
    let com = sum.h / sum.mass;
    let cx = skew(&com);
    body.mass = sum.mass;
    body.com = com;
    let ic = sum.inertia + cx * cx * sum.mass;
    body.inertia = (ic + ic.transpose()) * 0.5;
}

/// The body a [`FlexError`] is about.
fn body_of(e: &FlexError) -> Option<&str> {
    match e {
        FlexError::Model(_) | FlexError::Grown => None,
        FlexError::UnknownBody(b) | FlexError::Duplicate(b) | FlexError::NotPositiveDefinite(b) => {
            Some(b)
        }
        FlexError::Invalid { body, .. }
        | FlexError::MissingNode { body, .. }
        | FlexError::Unresolved { body, .. }
        | FlexError::Magnified { body, .. } => Some(body),
    }
}

/// Parses a model file's text whose bodies may carry `[body.flexible]` into a [`FlexModel`].
/// `origin` names the file in errors; a `modes_file` is read relative to its folder.
pub fn parse_flex_model(text: &str, origin: &Path) -> Result<FlexModel, FileError> {
    let file = parse_model_file(text, origin)?;
    flex_model_of(&file, text, origin)
}

/// The [`FlexModel`] of a model file already deserialised from `text` (the model file's, or
/// a scene's whose inline `[model]` table it is: its spans are offsets into `text`).
/// `origin` names the file in errors; a `modes_file` is read relative to its folder.
pub fn flex_model_of(file: &ModelFile, text: &str, origin: &Path) -> Result<FlexModel, FileError> {
    let mut builder = file.builder().map_err(|e| e.in_file(text, origin))?;
    let mut flex = Vec::new();
    let mut per_mode_damping: Vec<(String, Vec<f64>)> = Vec::new();
    for b in &file.body {
        let body = b.get_ref();
        let Some(f) = &body.flexible else { continue };
        let name = body.name.get_ref();
        let spec = f.get_ref();
        let schema = |span: Range<usize>, message: String| {
            SpannedError::Schema {
                span: Some(span),
                message: format!("body `{name}`: {message}"),
            }
            .in_file(text, origin)
        };
        let damping = match &spec.damping {
            Some(d) => {
                let z = *d.get_ref();
                if !(z.is_finite() && z >= 0.0) {
                    return Err(schema(
                        d.span(),
                        format!("damping = {} must be >= 0", Num(z)),
                    ));
                }
                Some(z)
            }
            None => None,
        };
        // A beam's default is on; given modes' is whether the file gives the terms.
        let mut stiffen = spec.stiffening.as_ref().is_none_or(|s| *s.get_ref());
        let modes = match (&spec.beam, &spec.modes_file) {
            (Some(_), Some(m)) => {
                return Err(schema(
                    m.span(),
                    "give `beam` or `modes_file`, not both".into(),
                ));
            }
            (None, None) => {
                return Err(schema(
                    f.span(),
                    "[body.flexible] needs `beam` or `modes_file`".into(),
                ));
            }
            (Some(beam), None) => Modes::Beam(beam_of(beam.get_ref(), &schema)?),
            (None, Some(m)) => {
                let path = origin.parent().unwrap_or(Path::new("")).join(m.get_ref());
                // A file that cannot be read is the model's fault, at its `modes_file` line;
                // a fault inside the file is placed in the file.
                let modes_text = read_text(&path).map_err(|e| {
                    let why = match &e {
                        FileError::Read { source, .. } => format!("cannot read it: {source}"),
                        _ => "the file is empty".to_string(),
                    };
                    // The path it resolved to, where the model's folder adds to it.
                    let resolved = if path == Path::new(m.get_ref()) {
                        String::new()
                    } else {
                        format!(" ({})", path.display())
                    };
                    schema(
                        m.span(),
                        format!("`modes_file` = {:?}{resolved}: {why}", m.get_ref()),
                    )
                })?;
                let modes = parse_modes_file(&modes_text, &path)?;
                if let (Some(_), Some(d)) = (&modes.damping, &spec.damping) {
                    return Err(schema(
                        d.span(),
                        "damping is given both here and per mode in the modes file".into(),
                    ));
                }
                if let Some(zeta) = &modes.damping {
                    per_mode_damping.push((name.clone(), zeta.get_ref().clone()));
                }
                let entry = builder
                    .bodies_mut()
                    .iter_mut()
                    .find(|e| &e.name == name)
                    .expect("the reader pushed every body");
                // The rigid part as written, before the modes' mass hides a negative mass or
                // inertia in the sum.
                crate::model::check_body(entry).map_err(|error| {
                    SpannedError::Model {
                        span: file.locate(&error),
                        error,
                    }
                    .in_file(text, origin)
                })?;
                add_inertia(entry, modes.inertia());
                let mut nodes = Vec::new();
                for h in file.hinge.iter().map(|h| h.get_ref()) {
                    if h.parent.get_ref() != name {
                        continue;
                    }
                    let at = h.at.as_ref().map_or(Vec3::zeros(), |a| v3(a.get_ref()));
                    let Some(k) = modes.node.iter().position(|n| {
                        (v3(n.get_ref().at.get_ref()) - at).norm() <= MODES_FILE_NODE_TOLERANCE
                    }) else {
                        let names: Vec<String> = modes
                            .node
                            .iter()
                            .map(|n| {
                                let n = n.get_ref();
                                format!("`{}` at {:?}", n.name.get_ref(), n.at.get_ref())
                            })
                            .collect();
                        return Err(SpannedError::Schema {
                            span: Some(h.at.as_ref().map_or(h.name.span(), Spanned::span)),
                            message: format!(
                                "hinge `{}`: its point {:?} on the flexible body `{name}` is none of the nodes of {} (within {MODES_FILE_NODE_TOLERANCE} m): {}",
                                h.name.get_ref(),
                                at.as_slice(),
                                path.display(),
                                if names.is_empty() { "none".to_string() } else { names.join(", ") }
                            ),
                        }
                        .in_file(text, origin));
                    };
                    nodes.push((h.name.get_ref().clone(), modes.node_shape(k)));
                }
                if let Some(on) = &spec.stiffening
                    && *on.get_ref()
                    && modes.stiffening.is_none()
                {
                    return Err(schema(
                        on.span(),
                        format!(
                            "`stiffening = true`: the modes file {} has no [stiffening] block (the modes' second-order inertia, see the model file reference); give one, or leave `stiffening` out",
                            path.display()
                        ),
                    ));
                }
                stiffen = modes.stiffening.is_some()
                    && spec.stiffening.as_ref().is_none_or(|s| *s.get_ref());
                Modes::Given {
                    data: modes.modal_data(),
                    nodes,
                    stiffening: modes.stiffening(),
                    watch: modes.watch_points(),
                }
            }
        };
        flex.push(Flexible {
            body: name.clone(),
            modes,
            damping: damping.unwrap_or(0.0),
            stiffening: stiffen,
        });
    }
    let mut model = FlexModel::build(builder, &flex).map_err(|e| {
        match e {
            FlexError::Model(error) => SpannedError::Model {
                span: file.locate(&error),
                error,
            },
            other => {
                let span = body_of(&other).and_then(|name| {
                    file.body
                        .iter()
                        .map(|b| b.get_ref())
                        .find(|b| b.name.get_ref() == name)
                        .map(|b| {
                            b.flexible
                                .as_ref()
                                .and_then(|f| f.get_ref().key_span())
                                .unwrap_or_else(|| b.name.span())
                        })
                });
                SpannedError::Schema {
                    span,
                    message: other.to_string(),
                }
            }
        }
        .in_file(text, origin)
    })?;
    for (name, zeta) in per_mode_damping {
        let i = model.rigid.body_index(&name).expect("a flexible body");
        let o = model.offset[i];
        for (k, z) in zeta.iter().enumerate() {
            model.damping[o + k] = 2.0 * z * model.stiffness[o + k].sqrt();
        }
    }
    Ok(model)
}

/// Reads the model file at `path`, flexible bodies included.
pub fn read_flex_model(path: impl AsRef<Path>) -> Result<FlexModel, FileError> {
    let path = path.as_ref();
    let text = read_text(path)?;
    parse_flex_model(&text, path)
}
