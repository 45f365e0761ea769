//! A scene's flexible bodies (contract section 14): the model's `[body.flexible]` tables read
//! into a [`FlexModel`] (through [`satsim_tree::io::flex_model_of`], so that a model file or
//! an inline `[model]` table is read alike), and the initial elastic state
//!
//! ```toml
//! [initial]
//! flexible = { panel1 = { eta = [0.01, 0.0, 0.0], etadot = [0.0, 0.0, 0.0] } }
//! ```
//!
//! of `[initial]` or of a JSON state file (`"flexible": {"panel1": {"eta": […]}}`): per
//! flexible body, `eta` (the modal coordinates, √kg m) and `etadot` (their rates, √kg m/s),
//! one value per mode, each default zeros. The result is in [`FlexModel`]'s coordinate order:
//! bodies in the model's depth-first order, modes from 1.

use nalgebra::{DMatrix, DVector};
use satsim_spacecraft::effects::section::reword;
use satsim_tree::Model;
use satsim_tree::flexible::FlexModel;
use satsim_tree::io::{FileError, StateFile, line_of};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

/// One body's initial elastic state as written.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ElasticFile {
    /// Modal coordinates, one per mode (√kg m), default zeros.
    #[serde(default)]
    pub eta: Option<Vec<f64>>,
    /// Their rates (√kg m/s), default zeros.
    #[serde(default)]
    pub etadot: Option<Vec<f64>>,
}

/// The initial elastic state in [`FlexModel`]'s coordinate order (empty without flexible
/// bodies).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Elastic {
    /// `η` (√kg m).
    pub eta: Vec<f64>,
    /// `η̇` (√kg m/s).
    pub etadot: Vec<f64>,
}

impl Elastic {
    /// The elastic state at rest of `flex` (zeros; empty without flexible bodies).
    pub fn rest(flex: Option<&FlexModel>) -> Self {
        let n = flex.map_or(0, FlexModel::n_elastic);
        Self {
            eta: vec![0.0; n],
            etadot: vec![0.0; n],
        }
    }
}

/// The elastic state of `flex` (whose rigid tree is `rigid`) from the written entries
/// `(body, entry)`: zeros where not given. The error names the key (`flexible.<body>.eta`),
/// the body and what is wrong (an unknown body, a body that is not flexible, a wrong length
/// and the mode without a value, a value that is not finite and its mode), with the index of
/// its entry.
pub fn elastic_state<'a>(
    flex: Option<&FlexModel>,
    rigid: &Model,
    given: impl IntoIterator<Item = (&'a str, &'a ElasticFile)>,
) -> Result<Elastic, (usize, String)> {
    let mut out = Elastic::rest(flex);
    for (k, (body, e)) in given.into_iter().enumerate() {
        let flexible: Vec<&str> = flex
            .map(|f| {
                (0..rigid.n_bodies())
                    .filter(|&i| f.modes(i) > 0)
                    .map(|i| rigid.bodies()[i].name())
                    .collect()
            })
            .unwrap_or_default();
        let list = if flexible.is_empty() {
            "the model has none".to_string()
        } else {
            format!("flexible bodies: {}", flexible.join(", "))
        };
        let Some(i) = rigid.body_index(body) else {
            return Err((k, format!("flexible.{body}: no body of that name ({list})")));
        };
        let (Some(f), true) = (flex, flexible.contains(&body)) else {
            return Err((
                k,
                format!("flexible.{body}: the body is not flexible ({list})"),
            ));
        };
        let (o, m) = (f.elastic_offset(i), f.modes(i));
        for (key, values, target) in [
            ("eta", &e.eta, &mut out.eta),
            ("etadot", &e.etadot, &mut out.etadot),
        ] {
            let Some(v) = values else { continue };
            if v.len() != m {
                // Which mode lacks its value, or which value has no mode.
                let which = if v.len() < m {
                    format!("mode {} has none", v.len() + 1)
                } else {
                    format!("value {} is no mode's", m + 1)
                };
                return Err((
                    k,
                    format!(
                        "flexible.{body}.{key}: expected {m} values, one per mode of body `{body}`, got {} ({which})",
                        v.len()
                    ),
                ));
            }
            if let Some((j, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
                return Err((
                    k,
                    format!(
                        "flexible.{body}.{key}: body `{body}`'s mode {} is {x}: values must be finite",
                        j + 1
                    ),
                ));
            }
            target[o..o + m].copy_from_slice(v);
        }
    }
    Ok(out)
}

/// A JSON state file with the optional `flexible` object.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonState {
    #[serde(default)]
    base: Option<satsim_tree::io::BaseStateFile>,
    #[serde(default)]
    hinges: Option<satsim_tree::io::HingesStateFile>,
    #[serde(default)]
    flexible: Option<BTreeMap<String, ElasticFile>>,
}

/// A JSON state file's text read as the tree's [`StateFile`] and its `flexible` entries (in
/// the order of their bodies' names). A file without `flexible` is read by
/// [`satsim_tree::io::parse_state_file`] itself.
pub fn parse_state_json(
    text: &str,
    path: &Path,
) -> Result<(StateFile, Vec<(String, ElasticFile)>), FileError> {
    let has_flexible = serde_json::from_str::<serde_json::Value>(text)
        .ok()
        .is_some_and(|v| v.get("flexible").is_some());
    if !has_flexible {
        return Ok((satsim_tree::io::parse_state_file(text, path)?, Vec::new()));
    }
    let s: JsonState = serde_json::from_str(text).map_err(|e| {
        let full = e.to_string();
        let message = match full.rfind(" at line ") {
            Some(k) => full[..k].to_owned(),
            None => full,
        };
        FileError::Schema {
            path: path.to_path_buf(),
            line: (e.line() > 0).then_some(e.line()),
            message: reword(&message),
        }
    })?;
    Ok((
        StateFile {
            base: s.base,
            hinges: s.hinges,
        },
        s.flexible.unwrap_or_default().into_iter().collect(),
    ))
}

/// The line of a JSON state file where the `flexible` entry of `body` is written (its key
/// after `"flexible"`), for messages.
pub fn json_line(text: &str, body: &str) -> Option<usize> {
    let start = text.find("\"flexible\"")?;
    let at = text[start..].find(&format!("\"{body}\""))? + start;
    Some(line_of(text, at))
}

/// The coupled undamped modes of the structure at `q`: `K x = ω² M(q) x`, `M` the flexible
/// tree's mass matrix and `K` the modes' stiffness (`ωₖ²` on each elastic coordinate, zero on
/// the rigid ones: hinge springs, geometric stiffening and the control left out).
#[derive(Clone, Debug, PartialEq)]
pub struct CoupledModes {
    /// The angular frequencies `ω` (rad/s), ascending, one per elastic coordinate (the rigid
    /// coordinates' zero frequencies left out).
    pub omega: Vec<f64>,
    /// The shapes, one column per frequency, in the generalised velocity's coordinates (rigid
    /// `v…`, then `η̇…`): mass-normalised (`xᵀ M x = 1`), signed so that the elastic entry of
    /// largest modulus is positive.
    pub shapes: DMatrix<f64>,
}

/// The modes' stiffness as the diagonal of `K` over the generalised velocity's coordinates:
/// `ωₖ²` on each elastic coordinate, zero on the rigid ones.
pub(super) fn modal_stiffness(flex: &FlexModel) -> Vec<f64> {
    let first = flex.rigid().nv();
    let mut k = vec![0.0; flex.nv()];
    k[first..].copy_from_slice(flex.stiffness());
    k
}

/// The eigenvalues `ω²` of `M⁻¹ K` at `q` (unsorted), `K` the diagonal `k` over the
/// generalised velocity's coordinates, and the matrix whose columns are their shapes
/// (`xᵀ M x = 1`). `None` when `M` is not positive definite at `q`.
pub(super) fn eigen(
    flex: &FlexModel,
    q: &[f64],
    k: &[f64],
) -> Option<(DVector<f64>, DMatrix<f64>)> {
    eigen_of(
        flex,
        q,
        &DMatrix::from_diagonal(&DVector::from_column_slice(k)),
    )
}

/// [`eigen`] of a full stiffness matrix `k` (its symmetric part: a motion's skew part does
/// no work and leaves out of the undamped frequencies).
pub(super) fn eigen_of(
    flex: &FlexModel,
    q: &[f64],
    k: &DMatrix<f64>,
) -> Option<(DVector<f64>, DMatrix<f64>)> {
    use nalgebra::SymmetricEigen;
    use satsim_tree::flexible::{FlexData, crba};
    let mut data = FlexData::new(flex);
    let m = crba(flex, &mut data, q).ok()?.clone();
    let l = m.cholesky()?.l();
    let l_inv = l.clone().try_inverse()?;
    // L⁻¹ K L⁻ᵀ: symmetric for a symmetric K, with the eigenvalues of M⁻¹ K.
    let a = &l_inv * k * l_inv.transpose();
    let eig = SymmetricEigen::new((&a + a.transpose()) * 0.5);
    // The mode shapes in the coordinates: x = L⁻ᵀ y.
    let shapes = l_inv.transpose() * eig.eigenvectors;
    Some((eig.eigenvalues, shapes))
}

/// The coupled undamped modes of `flex` at `q` ([`CoupledModes`]): empty without elastic
/// coordinates; `None` when `M` is not positive definite at `q` or a result is not finite.
pub fn coupled_modes(flex: &FlexModel, q: &[f64]) -> Option<CoupledModes> {
    let n_elastic = flex.n_elastic();
    if n_elastic == 0 {
        return Some(CoupledModes {
            omega: Vec::new(),
            shapes: DMatrix::zeros(flex.nv(), 0),
        });
    }
    let (w2, x) = eigen(flex, q, &modal_stiffness(flex))?;
    let mut order: Vec<usize> = (0..w2.len()).collect();
    order.sort_by(|a, b| w2[*a].total_cmp(&w2[*b]));
    // `K` has rank n_elastic at most: the rigid coordinates' eigenvalues are the lowest.
    let kept = &order[order.len() - n_elastic..];
    let first = flex.rigid().nv();
    let mut shapes = DMatrix::zeros(flex.nv(), n_elastic);
    let mut omega = Vec::with_capacity(n_elastic);
    for (c, &j) in kept.iter().enumerate() {
        omega.push(w2[j].max(0.0).sqrt());
        let col = x.column(j);
        let largest = (first..flex.nv())
            .max_by(|a, b| col[*a].abs().total_cmp(&col[*b].abs()))
            .expect("an elastic coordinate");
        let sign = if col[largest] < 0.0 { -1.0 } else { 1.0 };
        shapes.set_column(c, &(col * sign));
    }
    let finite = omega.iter().chain(shapes.iter()).all(|v| v.is_finite());
    finite.then_some(CoupledModes { omega, shapes })
}

/// The highest angular frequency (rad/s) of the structure at `q` (the highest of
/// [`coupled_modes`]) and the elastic coordinate (index among them) that moves most in it.
/// `None` without elastic coordinates or when `M` is not positive definite at `q`.
pub fn highest_frequency(flex: &FlexModel, q: &[f64]) -> Option<(f64, usize)> {
    if flex.n_elastic() == 0 {
        return None;
    }
    let (w2, x) = eigen(flex, q, &modal_stiffness(flex))?;
    let (top, &w2) = w2.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
    let first = flex.rigid().nv();
    let (e, _) = (0..flex.n_elastic())
        .map(|e| (e, x[(first + e, top)].abs()))
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    (w2 > 0.0 && w2.is_finite()).then(|| (w2.sqrt(), e))
}

/// Whether the mass matrix of `flex` at `q` is positive definite; `None` where it cannot be
/// formed (a value that is not finite).
pub(super) fn mass_positive(flex: &FlexModel, q: &[f64]) -> Option<bool> {
    use satsim_tree::flexible::{FlexData, crba};
    let mut data = FlexData::new(flex);
    let m = crba(flex, &mut data, q).ok()?.clone();
    Some(m.cholesky().is_some())
}

/// The body and mode (from 1) an initial deformation `eta` (at the rigid positions
/// `rigid_q`) that leaves the mass matrix not positive definite is to blame on, with the
/// pivot where the flexible ABA's fails at a mode: that mode. Else the first body whose
/// deformation alone does it (where none does alone, the one bent most for its size), and
/// in it the mode that bends it most (`|ηₖ|` over the coordinate that bends the body by its
/// size, [`FlexModel::modal_scale`]).
pub(super) fn blamed_mode(
    flex: &FlexModel,
    rigid_q: &[f64],
    eta: &[f64],
) -> (usize, usize, Option<f64>) {
    let q_of = |eta: &[f64]| -> Vec<f64> { rigid_q.iter().chain(eta).copied().collect() };
    if let Some((i, mode, pivot)) = flex.unresolved_mode(&q_of(eta)) {
        return (i, mode, Some(pivot));
    }
    let n = flex.rigid().n_bodies();
    let deformed: Vec<usize> = (0..n)
        .filter(|&i| {
            let o = flex.elastic_offset(i);
            eta[o..o + flex.modes(i)].iter().any(|e| *e != 0.0)
        })
        .collect();
    let alone = |i: usize| {
        let o = flex.elastic_offset(i);
        let mut only = vec![0.0; eta.len()];
        only[o..o + flex.modes(i)].copy_from_slice(&eta[o..o + flex.modes(i)]);
        mass_positive(flex, &q_of(&only)) == Some(false)
    };
    let bent = |i: usize| flex.deflection_of(i, eta).map_or(0.0, |d| d.fraction());
    let i = deformed
        .iter()
        .copied()
        .find(|&i| alone(i))
        .or_else(|| {
            deformed
                .iter()
                .copied()
                .max_by(|a, b| bent(*a).total_cmp(&bent(*b)))
        })
        .unwrap_or(0);
    let o = flex.elastic_offset(i);
    let bends = |k: usize| eta[o + k].abs() / flex.modal_scale(o + k).unwrap_or(1.0);
    let k = (0..flex.modes(i))
        .max_by(|a, b| bends(*a).total_cmp(&bends(*b)))
        .unwrap_or(0);
    (i, k + 1, None)
}

/// The body (name) and mode number (from 1) of elastic coordinate `e`.
pub fn mode_of(flex: &FlexModel, e: usize) -> (String, usize) {
    flex.mode_of(e)
        .map(|(i, k)| (flex.rigid().bodies()[i].name().to_owned(), k))
        .unwrap_or_default()
}

/// What reaches a body whose modes come from a file but not its modes, as warnings: the
/// file's shapes are known at its nodes only, so a thruster off its nodes and the pressure
/// on its facets (sunlight and the Earth's light, `solar_radiation`; the air, `drag`) act
/// on the body's frame alone. A thruster at a node loads the modes through the node's
/// shapes; a `beam` takes them over its facets.
pub(super) fn unloaded_modes(
    flex: &FlexModel,
    effects: &satsim_spacecraft::effects::EffectSet,
) -> Vec<String> {
    use satsim_spacecraft::effects::{Drag, SolarRadiation, Thrusters};
    let bodies = flex.rigid().bodies();
    let given = |i: usize| flex.modes(i) > 0 && flex.beam(i).is_none();
    let nodes = |i: usize| {
        flex.watch_points(i)
            .iter()
            .map(|n| format!("`{}` at [{}, {}, {}]", n.name, n.at.x, n.at.y, n.at.z))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut out = Vec::new();
    if let Some(t) = effects.get::<Thrusters>() {
        for th in t.list() {
            if given(th.body) && flex.node_at(th.body, &th.at).is_none() {
                out.push(format!(
                    "thruster `{}` on body `{}` is at none of its modes file's nodes: its force moves the body but does not bend it (a modes file's shapes are known at its nodes only; place it at one for its load to reach the modes: {})",
                    th.name,
                    bodies[th.body].name(),
                    nodes(th.body)
                ));
            }
        }
    }
    let pressing: Vec<&str> = [
        effects.get::<SolarRadiation>().map(|_| "`solar_radiation`"),
        effects.get::<Drag>().map(|_| "`drag`"),
    ]
    .into_iter()
    .flatten()
    .collect();
    if !pressing.is_empty() {
        for (i, b) in bodies.iter().enumerate() {
            if given(i) && !b.facets().is_empty() {
                out.push(format!(
                    "body `{}`'s facets take {} on the body but not on its modes: its modes come from a file, whose shapes are known at its nodes only (a `beam` body's facets load its modes and ride its deflection)",
                    b.name(),
                    pressing.join(" and ")
                ));
            }
        }
    }
    out
}
