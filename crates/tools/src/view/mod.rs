//! The 3-D playback of a run (`cli-contract.md` section 11): `DIR/view.html`, one
//! self-contained page (WebGL written directly, no library, no network) that plays the run
//! back from the poses recorded at the output times.
//!
//! - [`PoseRecorder`] turns output rows ([`satsim_spacecraft::simulation::Simulation::columns`]) into
//!   body poses with the model's own forward kinematics, keeping at most a bounded number of
//!   frames (it halves its frames and doubles its stride when full, so memory and the page's
//!   size stay bounded for any run length; the last row is always kept).
//! - [`ViewData`] holds what the page shows: the scene ([`ViewScene`]: boxes, hinges,
//!   events) and the [`Frames`]. [`ViewData::write`] writes the kept poses
//!   (`DIR/poses.csv`), the scene (`DIR/view.json`) and the page (`DIR/view.html`);
//!   [`ViewData::read`] reads the first two back, so `satsim view DIR` re-creates the page.
//!
//! # Conventions
//!
//! Positions are in metres, in inertial axes, relative to the system's centre of mass for a
//! free base (the frame that falls with it when an orbit is on) and to the inertial origin for
//! a fixed base. Attitudes are Hamilton quaternions `[w, x, y, z]` mapping body coordinates to
//! inertial ones, sign-continuous from frame to frame. A body is drawn as a box: its model
//! `shape`, or else the box of uniform density with the body's mass and principal moments
//! (edges `a_k = sqrt(6 (tr I − 2 I_k) / m)` along the principal axes, each at least 2 % of
//! the longest, so that thin plates stay visible); a massless body without `shape` is not
//! drawn. A hinge is drawn on its axis through its point, both fixed in the child body
//! (`rotationᵀ · axis` and `child_at`). With an orbit the nadir is `−r / |r|` (inertial). The
//! page interpolates between frames: positions linearly, attitudes by slerp. A flexible
//! body's beam ([`ViewBeam`]) is drawn as a polyline along its axis bent by its modes and the
//! frame's modal coordinates, its deflection multiplied by the page's "bend ×" factor
//! (default 1; `#bend=20` in the address sets it).
//!
//! Numbers are kept to 1e-9 (metres, quaternion components, radians), far below what the
//! page can show and what the tests check (1e-6 m).

use nalgebra::{Rotation3, SymmetricEigen, UnitQuaternion};
use satsim_tree::flexible::{self, Beam, FlexData, FlexModel};
use satsim_tree::spatial::{Mat3, Vec3};
use satsim_tree::{BaseKind, Data, Model, center_of_mass, forward_poses};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The page's file name in a run's folder.
pub const VIEW_HTML: &str = "view.html";
/// The kept poses' file name in a run's folder.
pub const POSES_CSV: &str = "poses.csv";
/// The kept scene's file name in a run's folder.
pub const VIEW_JSON: &str = "view.json";
/// The version of `view.json` and `poses.csv` this code writes and reads.
pub const FORMAT: u32 = 1;

/// The page's HTML, CSS and JavaScript, with `/*SATSIM_VIEW_DATA*/null` where the data go.
const TEMPLATE: &str = include_str!("template.html");
const PLACEHOLDER: &str = "/*SATSIM_VIEW_DATA*/null";

/// The numbers kept in a frame, at most (the frame budget is this over the frame's width).
const NUMBER_BUDGET: usize = 120_000;

/// Why the view could not be written or read back.
#[derive(Debug, Error)]
pub enum ViewError {
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// A kept file is not what [`ViewData::write`] writes.
    #[error("{}{}: {message}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Kept {
        /// The file.
        path: PathBuf,
        /// The line (1-based), when known.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// The rows given to the recorder do not fit its model.
    #[error("view: {0}")]
    Record(String),
}

/// The box drawn for a body, in the body's frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DrawnBox {
    /// Edge lengths along the box's axes (m).
    pub size: [f64; 3],
    /// The box's centre in the body frame (m).
    pub centre: [f64; 3],
    /// The box's axes relative to the body's, `[w, x, y, z]` (box to body coordinates).
    pub rotation: [f64; 4],
    /// `"shape"` (the model's `shape` key) or `"inertia"` (the equivalent-inertia box).
    pub from: String,
}

/// A body of the view.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewBody {
    /// The model's name.
    pub name: String,
    /// Its box, or `None` for a massless body without `shape`.
    pub drawn: Option<DrawnBox>,
}

/// A hinge of the view, fixed in its child body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewHinge {
    /// The model's name.
    pub name: String,
    /// Index of the child body in [`ViewScene::bodies`].
    pub body: usize,
    /// Unit axis in the child frame (`rotationᵀ · axis`).
    pub axis: [f64; 3],
    /// The hinge point in the child frame (`child_at`, m).
    pub at: [f64; 3],
}

/// An event of the run (a latch, a stop, stick or slip), marked on the timeline.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewEvent {
    /// Time (s).
    pub t: f64,
    /// What happened.
    pub what: String,
}

/// A flexible body's beam (contract section 14), drawn as a polyline along its axis bent by
/// its modes: the point at `x` along the axis is
/// `root + x·axis + exaggeration · Σₖ ηₖ φₖ(x) · bend` in the body's frame, `ηₖ` the frame's
/// modal coordinates of the body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewBeam {
    /// The flexible body (index into [`ViewScene::bodies`]).
    pub body: usize,
    /// The clamped end, body frame (m).
    pub root: [f64; 3],
    /// Unit direction root to tip, body frame.
    pub axis: [f64; 3],
    /// Unit direction of the deflection, body frame.
    pub bend: [f64; 3],
    /// Distances along the axis of the polyline's points (m), from 0 to the length.
    pub points: Vec<f64>,
    /// Per mode (from 1), the mass-normalised shape `φₖ` at each point (m/√kg).
    pub shapes: Vec<Vec<f64>>,
}

/// Points of a beam's polyline ([`ViewBeam::points`]).
pub const BEAM_POINTS: usize = 25;

impl ViewBeam {
    /// The beam of body `body` with its cantilever modes sampled at [`BEAM_POINTS`] points.
    pub fn new(body: usize, beam: &Beam) -> Self {
        let points: Vec<f64> = (0..BEAM_POINTS)
            .map(|j| beam.length * j as f64 / (BEAM_POINTS - 1) as f64)
            .collect();
        let shapes = beam
            .cantilever_modes()
            .iter()
            .map(|m| points.iter().map(|&x| m.shape(x)[0]).collect())
            .collect();
        let v = |a: &Vec3| [a.x, a.y, a.z];
        Self {
            body,
            root: v(&beam.root),
            axis: v(&beam.axis),
            bend: v(&beam.bend),
            points,
            shapes,
        }
    }

    /// The polyline in the body's frame (m) for the modal coordinates `eta` (one per mode),
    /// deflections multiplied by `exaggeration` (what the page draws).
    pub fn polyline(&self, eta: &[f64], exaggeration: f64) -> Vec<[f64; 3]> {
        self.points
            .iter()
            .enumerate()
            .map(|(j, &x)| {
                let w: f64 = self.shapes.iter().zip(eta).map(|(s, e)| s[j] * e).sum();
                std::array::from_fn(|c| {
                    self.root[c] + x * self.axis[c] + exaggeration * w * self.bend[c]
                })
            })
            .collect()
    }
}

/// The scene shown: everything but the frames (`DIR/view.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ViewScene {
    /// [`FORMAT`].
    pub format: u32,
    /// A title (the scene file's name).
    pub title: String,
    /// `"centre of mass"` (free base) or `"inertial origin"` (fixed base): what positions
    /// are relative to.
    pub origin: String,
    /// Bodies in the model's order (the root first).
    pub bodies: Vec<ViewBody>,
    /// Every hinge of the model.
    pub hinges: Vec<ViewHinge>,
    /// How many of the last bodies (and hinges) are wheel rotors (hinged to the root): the
    /// header counts them apart, as a run's summary does (absent from the file when none).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub rotors: usize,
    /// The hinges whose angles are plotted (those with an `angle_<name>` column), in the
    /// columns' order.
    pub angles: Vec<String>,
    /// Whether the frames carry the nadir (an orbit is on).
    pub nadir: bool,
    /// The run's events.
    pub events: Vec<ViewEvent>,
    /// The flexible bodies' beams (absent from the file when there is none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub beams: Vec<ViewBeam>,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

impl ViewScene {
    /// Each beam's body name and number of modes, in the frames' order.
    fn beam_modes(&self) -> impl Iterator<Item = (&str, usize)> {
        self.beams
            .iter()
            .map(|b| (self.bodies[b.body].name.as_str(), b.shapes.len()))
    }
}

/// The recorded frames, one row of [`Frames::width`] numbers each: `t`, the plotted angles
/// (rad), for each body `x, y, z, q_w, q_x, q_y, q_z`, then (with an orbit) the nadir
/// `x, y, z` (see the module's conventions), then each beam's modal coordinates
/// `η₁ … ηₘ` (√kg m).
#[derive(Clone, Debug, PartialEq)]
pub struct Frames {
    /// Numbers per frame.
    pub width: usize,
    /// The frames, row after row.
    pub data: Vec<f64>,
}

impl Frames {
    /// Number of frames.
    pub fn len(&self) -> usize {
        self.data.len() / self.width.max(1)
    }
    /// Whether there is no frame.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }
    /// Frame `k`.
    pub fn frame(&self, k: usize) -> &[f64] {
        &self.data[k * self.width..(k + 1) * self.width]
    }
}

/// Everything the page shows.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewData {
    /// The scene.
    pub scene: ViewScene,
    /// The frames.
    pub frames: Frames,
}

/// Column names of `poses.csv` for a scene.
fn pose_columns(scene: &ViewScene) -> Vec<String> {
    let mut c = vec!["t".to_owned()];
    c.extend(scene.angles.iter().map(|a| format!("angle_{a}")));
    for b in &scene.bodies {
        for s in ["x", "y", "z", "q_w", "q_x", "q_y", "q_z"] {
            c.push(format!("{}.{s}", b.name));
        }
    }
    if scene.nadir {
        c.extend(["nadir_x", "nadir_y", "nadir_z"].map(str::to_owned));
    }
    for (body, m) in scene.beam_modes() {
        c.extend((1..=m).map(|k| format!("eta_{body}_{k}")));
    }
    c
}

/// Appends `x` rounded to 1e-9, without trailing zeros (`-0` written as `0`).
fn push_number(out: &mut String, x: f64) {
    crate::numbers::push_fixed_trimmed(out, x, 9);
}

impl ViewData {
    /// The page: the template with the scene and frames inlined as JSON.
    pub fn html(&self) -> String {
        self.html_of(&self.frame_rows())
    }

    /// The page, its frames' numbers taken from `rows` ([`Self::frame_rows`]): the numbers
    /// are formatted once for both files ([`Self::write`]).
    fn html_of(&self, rows: &str) -> String {
        let scene = serde_json::to_string(&self.scene).expect("the scene serialises");
        let mut json = String::with_capacity(rows.len() + scene.len() + 64);
        json.push_str("{\"scene\":");
        // Inside a <script> element, `</` could close it: JSON allows `<\/` for `</`. Only
        // the scene's strings can hold one; the frames are numbers.
        json.push_str(&scene.replace("</", "<\\/"));
        let _ = write!(json, ",\"width\":{},\"frames\":[", self.frames.width);
        // The rows' numbers in order, one list: each line's end a comma, the last none.
        json.push_str(&rows.strip_suffix('\n').unwrap_or(rows).replace('\n', ","));
        json.push_str("]}");
        TEMPLATE.replacen(PLACEHOLDER, &json, 1)
    }

    /// The frames as `poses.csv`'s rows (without its header): each frame a line, its numbers
    /// to 1e-9 separated by commas.
    fn frame_rows(&self) -> String {
        let mut s = String::with_capacity(self.frames.data.len() * 12);
        for k in 0..self.frames.len() {
            for (i, x) in self.frames.frame(k).iter().enumerate() {
                if i > 0 {
                    s.push(',');
                }
                push_number(&mut s, *x);
            }
            s.push('\n');
        }
        s
    }

    /// `poses.csv`'s text (numbers to 1e-9, as in the page).
    pub fn poses_csv(&self) -> String {
        self.poses_csv_of(&self.frame_rows())
    }

    fn poses_csv_of(&self, rows: &str) -> String {
        let mut s = pose_columns(&self.scene).join(",");
        s.push('\n');
        s.push_str(rows);
        s
    }

    /// Writes `dir/poses.csv`, `dir/view.json` and `dir/view.html`; returns the page's path.
    pub fn write(&self, dir: &Path) -> Result<PathBuf, ViewError> {
        let put = |name: &str, text: &str| {
            let path = dir.join(name);
            std::fs::write(&path, text).map_err(|source| ViewError::Io { path, source })
        };
        let rows = self.frame_rows();
        put(POSES_CSV, &self.poses_csv_of(&rows))?;
        let scene = serde_json::to_string_pretty(&self.scene).expect("the scene serialises");
        put(VIEW_JSON, &(scene + "\n"))?;
        put(VIEW_HTML, &self.html_of(&rows))?;
        Ok(dir.join(VIEW_HTML))
    }

    /// Writes the page alone to `path`.
    pub fn write_html(&self, path: &Path) -> Result<(), ViewError> {
        std::fs::write(path, self.html()).map_err(|source| ViewError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Reads back the kept scene and poses of a run's folder (`dir/view.json`,
    /// `dir/poses.csv`), as [`ViewData::write`] wrote them.
    pub fn read(dir: &Path) -> Result<Self, ViewError> {
        let read = |name: &str| {
            let path = dir.join(name);
            std::fs::read_to_string(&path)
                .map(|t| (t, path.clone()))
                .map_err(|source| ViewError::Io { path, source })
        };
        let (json, json_path) = read(VIEW_JSON)?;
        let scene: ViewScene = serde_json::from_str(&json).map_err(|e| ViewError::Kept {
            path: json_path.clone(),
            line: (e.line() > 0).then_some(e.line()),
            message: e.to_string(),
        })?;
        if scene.format != FORMAT {
            return Err(ViewError::Kept {
                path: json_path,
                line: None,
                message: format!(
                    "format {} (this satsim reads format {FORMAT})",
                    scene.format
                ),
            });
        }
        let (csv, csv_path) = read(POSES_CSV)?;
        let bad = |line: usize, message: String| ViewError::Kept {
            path: csv_path.clone(),
            line: Some(line),
            message,
        };
        let columns = pose_columns(&scene);
        let mut lines = csv.lines();
        let header = lines.next().unwrap_or_default();
        if header != columns.join(",") {
            return Err(bad(
                1,
                format!(
                    "the header does not match {VIEW_JSON}: expected `{}`",
                    columns.join(",")
                ),
            ));
        }
        let width = columns.len();
        let mut data = Vec::new();
        for (k, line) in lines.enumerate() {
            let before = data.len();
            for field in line.split(',') {
                match field.trim().parse::<f64>() {
                    Ok(x) if x.is_finite() => data.push(x),
                    _ => return Err(bad(k + 2, format!("`{field}` is not a finite number"))),
                }
            }
            if data.len() - before != width {
                return Err(bad(
                    k + 2,
                    format!("{} numbers, expected {width}", data.len() - before),
                ));
            }
        }
        Ok(Self {
            scene,
            frames: Frames { width, data },
        })
    }
}

/// The box with `mass` and principal moments of `inertia` (about the centre of mass), or
/// `None` for a massless body.
pub fn inertia_box(mass: f64, com: &Vec3, inertia: &Mat3) -> Option<DrawnBox> {
    if mass <= 0.0 {
        return None;
    }
    let eig = SymmetricEigen::new(*inertia);
    let trace: f64 = eig.eigenvalues.iter().sum();
    let mut size = [0.0; 3];
    for (k, s) in size.iter_mut().enumerate() {
        *s = (6.0 * (trace - 2.0 * eig.eigenvalues[k]) / mass)
            .max(0.0)
            .sqrt();
    }
    let longest = size.iter().copied().fold(0.0, f64::max);
    if longest <= 0.0 {
        return None;
    }
    for s in &mut size {
        *s = s.max(0.02 * longest);
    }
    let mut axes = eig.eigenvectors;
    if axes.determinant() < 0.0 {
        axes.set_column(2, &(-axes.column(2)));
    }
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(axes));
    Some(DrawnBox {
        size,
        centre: [com.x, com.y, com.z],
        rotation: [q.w, q.i, q.j, q.k],
        from: "inertia".into(),
    })
}

impl ViewScene {
    /// The scene of `model`, plotting the hinges that have an `angle_<name>` column among
    /// `columns`, with the nadir when `columns` has `orbit_r_x, orbit_r_y, orbit_r_z`.
    pub fn new(model: &Model, columns: &[String], title: impl Into<String>) -> Self {
        let bodies = model
            .bodies()
            .iter()
            .map(|b| ViewBody {
                name: b.name().to_owned(),
                drawn: match b.shape() {
                    Some(s) => {
                        let c = s.centre(b.com());
                        Some(DrawnBox {
                            size: [s.size.x, s.size.y, s.size.z],
                            centre: [c.x, c.y, c.z],
                            rotation: [1.0, 0.0, 0.0, 0.0],
                            from: "shape".into(),
                        })
                    }
                    None => inertia_box(b.mass(), b.com(), b.inertia_com()),
                },
            })
            .collect();
        let hinges = (1..model.n_bodies())
            .filter_map(|i| model.joint(i).map(|j| (i, j)))
            .map(|(i, j)| {
                let axis = j.rot0().tr_mul(j.axis());
                let at = j.child_at();
                ViewHinge {
                    name: model.hinge_names()[j.hinge()].clone(),
                    body: i,
                    axis: [axis.x, axis.y, axis.z],
                    at: [at.x, at.y, at.z],
                }
            })
            .collect();
        let angles = model
            .hinge_names()
            .iter()
            .filter(|h| columns.iter().any(|c| *c == format!("angle_{h}")))
            .cloned()
            .collect();
        let nadir = ["orbit_r_x", "orbit_r_y", "orbit_r_z"]
            .iter()
            .all(|n| columns.iter().any(|c| c == n));
        Self {
            format: FORMAT,
            title: title.into(),
            origin: match model.base() {
                BaseKind::Free => "centre of mass".into(),
                BaseKind::Fixed => "inertial origin".into(),
            },
            bodies,
            hinges,
            rotors: 0,
            angles,
            nadir,
            events: Vec::new(),
            beams: Vec::new(),
        }
    }
}

/// The flexible kinematics of [`PoseRecorder::with_flexible`]: the model, its workspace, the
/// `eta_<body>_<k>` column of every elastic coordinate, and `q`, `v` with them.
struct FlexPoses {
    model: FlexModel,
    data: FlexData,
    cols: Vec<usize>,
    q: Vec<f64>,
}

/// Records body poses from output rows (see the module's conventions), keeping at most
/// `NUMBER_BUDGET / width` frames (at least 64).
///
/// ```
/// use satsim_tools::view::PoseRecorder;
/// use satsim_tree::{BaseKind, samples::chain};
/// let model = chain(3, BaseKind::Free); // bodies b0, b1, b2; hinges h1, h2
/// let columns: Vec<String> = ["t", "q_w", "q_x", "q_y", "q_z", "angle_h1", "angle_h2"]
///     .map(String::from).to_vec();
/// let mut rec = PoseRecorder::new(&model, &columns, "chain")?;
/// rec.record(&[0.0, 1.0, 0.0, 0.0, 0.0, 0.1, 0.2])?;
/// rec.record(&[1.0, 1.0, 0.0, 0.0, 0.0, 0.2, 0.4])?;
/// let view = rec.finish(&[]);
/// assert_eq!(view.frames.len(), 2);
/// assert_eq!(view.frames.width, 1 + 2 + 7 * 3);
/// # Ok::<(), satsim_tools::view::ViewError>(())
/// ```
pub struct PoseRecorder {
    model: Model,
    data: Data,
    q: Vec<f64>,
    scene: ViewScene,
    attitude: Option<[usize; 4]>,
    /// For each model hinge, its `angle_<name>` column (a wheel rotor's has none: zero).
    angle_cols: Vec<Option<usize>>,
    /// The plotted angles' columns.
    plotted: Vec<usize>,
    orbit: Option<[usize; 3]>,
    /// Each beam's `eta_<body>_<k>` columns, in the frames' order.
    eta_cols: Vec<usize>,
    /// With flexible bodies, their kinematics (a hinge on a flexible parent rides on its
    /// deformation).
    flex: Option<FlexPoses>,
    width: usize,
    max_frames: usize,
    stride: usize,
    seen: usize,
    frames: Vec<f64>,
    /// The last row's frame, kept by `finish` when the stride did not keep it
    /// (`last_pending`).
    last: Vec<f64>,
    last_pending: bool,
    /// Each body's attitude in the previous row (for sign continuity).
    previous: Vec<[f64; 4]>,
    frame: Vec<f64>,
}

impl PoseRecorder {
    /// A recorder for rows with `columns` (they must include `t`, and `q_w, q_x, q_y, q_z`
    /// for a free base) of a run of `model`.
    pub fn new(model: &Model, columns: &[String], title: &str) -> Result<Self, ViewError> {
        let col = |name: &str| columns.iter().position(|c| c == name);
        let missing = |name: &str| ViewError::Record(format!("the rows have no `{name}` column"));
        if col("t") != Some(0) {
            return Err(missing("t"));
        }
        let attitude = match model.base() {
            BaseKind::Free => {
                let mut a = [0; 4];
                for (k, n) in ["q_w", "q_x", "q_y", "q_z"].iter().enumerate() {
                    a[k] = col(n).ok_or_else(|| missing(n))?;
                }
                Some(a)
            }
            BaseKind::Fixed => None,
        };
        let angle_cols: Vec<Option<usize>> = model
            .hinge_names()
            .iter()
            .map(|h| col(&format!("angle_{h}")))
            .collect();
        let scene = ViewScene::new(model, columns, title);
        let plotted = scene
            .angles
            .iter()
            .map(|h| col(&format!("angle_{h}")).expect("found by ViewScene::new"))
            .collect();
        let orbit = scene
            .nadir
            .then(|| ["orbit_r_x", "orbit_r_y", "orbit_r_z"].map(|n| col(n).expect("found above")));
        let width = 1 + scene.angles.len() + 7 * model.n_bodies() + if scene.nadir { 3 } else { 0 };
        Ok(Self {
            data: Data::new(model),
            q: model.neutral(),
            model: model.clone(),
            scene,
            attitude,
            angle_cols,
            plotted,
            orbit,
            eta_cols: Vec::new(),
            flex: None,
            width,
            max_frames: (NUMBER_BUDGET / width).max(64),
            stride: 1,
            seen: 0,
            frames: Vec::new(),
            last: Vec::with_capacity(width),
            last_pending: false,
            previous: Vec::with_capacity(model.n_bodies()),
            frame: Vec::with_capacity(width),
        })
    }

    /// Draws the beams of flexible bodies, `(body index, beam)`, bent by the rows'
    /// `eta_<body>_<k>` columns (`columns` as given to [`PoseRecorder::new`]), which must be
    /// there. Call before recording.
    pub fn with_beams(
        mut self,
        beams: &[(usize, Beam)],
        columns: &[String],
    ) -> Result<Self, ViewError> {
        for (body, beam) in beams {
            let b = ViewBeam::new(*body, beam);
            let name = &self.scene.bodies[*body].name;
            for k in 1..=b.shapes.len() {
                let c = format!("eta_{name}_{k}");
                let i = columns
                    .iter()
                    .position(|n| *n == c)
                    .ok_or_else(|| ViewError::Record(format!("the rows have no `{c}` column")))?;
                self.eta_cols.push(i);
            }
            self.scene.beams.push(b);
        }
        self.width = 1
            + self.scene.angles.len()
            + 7 * self.model.n_bodies()
            + if self.scene.nadir { 3 } else { 0 }
            + self.eta_cols.len();
        self.max_frames = (NUMBER_BUDGET / self.width).max(64);
        self.last = Vec::with_capacity(self.width);
        self.frame = Vec::with_capacity(self.width);
        Ok(self)
    }

    /// The poses of a tree with flexible bodies (`model`, whose rigid tree is the recorder's):
    /// each hinge on a flexible parent carried by the deformation at its point, and each
    /// beam drawn bent ([`PoseRecorder::with_beams`]). Every `eta_<body>_<k>` column must
    /// be among `columns`.
    pub fn with_flexible(self, model: &FlexModel, columns: &[String]) -> Result<Self, ViewError> {
        let rigid = model.rigid();
        if rigid.n_bodies() != self.model.n_bodies() {
            return Err(ViewError::Record(
                "the flexible model is not the recorder's tree".into(),
            ));
        }
        let beams: Vec<(usize, Beam)> = (0..rigid.n_bodies())
            .filter_map(|i| model.beam(i).map(|b| (i, b.clone())))
            .collect();
        let mut rec = self.with_beams(&beams, columns)?;
        let mut cols = Vec::with_capacity(model.n_elastic());
        for i in 0..rigid.n_bodies() {
            for k in 1..=model.modes(i) {
                let c = format!("eta_{}_{k}", rigid.bodies()[i].name());
                cols.push(
                    columns.iter().position(|n| *n == c).ok_or_else(|| {
                        ViewError::Record(format!("the rows have no `{c}` column"))
                    })?,
                );
            }
        }
        rec.flex = Some(FlexPoses {
            data: FlexData::new(model),
            q: model.neutral(),
            model: model.clone(),
            cols,
        });
        Ok(rec)
    }

    /// Marks the model's last `n` bodies, on its last `n` hinges, as wheel rotors (as
    /// [`satsim_spacecraft::simulation::Simulation`] appends them), so that the page's
    /// header counts them apart from the bodies and hinges.
    pub fn with_rotors(mut self, n: usize) -> Result<Self, ViewError> {
        if n >= self.scene.bodies.len() || n > self.scene.hinges.len() {
            return Err(ViewError::Record(format!(
                "{n} wheel rotors in a model of {} bodies and {} hinges",
                self.scene.bodies.len(),
                self.scene.hinges.len()
            )));
        }
        self.scene.rotors = n;
        Ok(self)
    }

    /// Sets the most frames kept (at least 2); the recorder halves its frames when full.
    pub fn with_max_frames(mut self, max_frames: usize) -> Self {
        self.max_frames = max_frames.max(2);
        self
    }

    /// The frame of one row, into `self.frame`.
    fn pose(&mut self, row: &[f64]) -> Result<(), ViewError> {
        let nq0 = self.model.base_nq();
        if let Some(a) = self.attitude {
            let norm = a.iter().map(|&k| row[k] * row[k]).sum::<f64>().sqrt();
            for (k, &c) in a.iter().enumerate() {
                self.q[k] = row[c] / norm;
            }
        }
        for (k, c) in self.angle_cols.iter().enumerate() {
            self.q[nq0 + k] = c.map_or(0.0, |c| row[c]);
        }
        match &mut self.flex {
            Some(fx) => {
                let nq = self.q.len();
                fx.q[..nq].copy_from_slice(&self.q);
                for (j, &c) in fx.cols.iter().enumerate() {
                    fx.q[nq + j] = row[c];
                }
                flexible::forward_poses(&fx.model, &mut fx.data, &mut self.data, &fx.q)
            }
            None => forward_poses(&self.model, &mut self.data, &self.q),
        }
        .map_err(|e| ViewError::Record(e.to_string()))?;
        let origin = match self.model.base() {
            BaseKind::Free => center_of_mass(&self.model, &self.data),
            BaseKind::Fixed => Vec3::zeros(),
        };
        let first = self.previous.is_empty();
        let f = &mut self.frame;
        f.clear();
        f.push(row[0]);
        f.extend(self.plotted.iter().map(|&c| row[c]));
        for i in 0..self.model.n_bodies() {
            let p = self.data.position[i] - origin;
            let r = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(
                self.data.rotation[i],
            ));
            let mut q = [r.w, r.i, r.j, r.k];
            // Sign-continuous attitudes, so that the page's slerp takes the short way.
            if first {
                self.previous.push(q);
            } else {
                let prev = self.previous[i];
                if (0..4).map(|k| prev[k] * q[k]).sum::<f64>() < 0.0 {
                    q = q.map(|x| -x);
                }
                self.previous[i] = q;
            }
            f.extend_from_slice(&[p.x, p.y, p.z]);
            f.extend_from_slice(&q);
        }
        if let Some(o) = self.orbit {
            let r = Vec3::new(row[o[0]], row[o[1]], row[o[2]]);
            let n = -r / r.norm();
            f.extend_from_slice(&[n.x, n.y, n.z]);
        }
        f.extend(self.eta_cols.iter().map(|&c| row[c]));
        Ok(())
    }

    /// Records one output row (at output times, in order). A row whose poses are not all
    /// finite is not kept (the run reports such a state itself); the view shows the rows
    /// before it.
    pub fn record(&mut self, row: &[f64]) -> Result<(), ViewError> {
        self.pose(row)?;
        if !self.frame.iter().all(|x| x.is_finite()) {
            return Ok(());
        }
        let w = self.width;
        if self.seen.is_multiple_of(self.stride) && self.frames.len() / w == self.max_frames {
            // Full: keep every other frame (in place), record every other row from now on.
            let n = self.frames.len() / w;
            for k in 1..n.div_ceil(2) {
                self.frames.copy_within(2 * k * w..(2 * k + 1) * w, k * w);
            }
            self.frames.truncate(n.div_ceil(2) * w);
            self.stride *= 2;
        }
        if self.seen.is_multiple_of(self.stride) {
            self.frames.extend_from_slice(&self.frame);
            self.last_pending = false;
        } else {
            self.last.clone_from(&self.frame);
            self.last_pending = true;
        }
        self.seen += 1;
        Ok(())
    }

    /// The recorded view, with the run's `events` (`(t, what)`, as
    /// [`satsim_spacecraft::simulation::Simulation::event_log`]).
    pub fn finish(mut self, events: &[(f64, String)]) -> ViewData {
        if self.last_pending {
            self.frames.extend_from_slice(&self.last);
        }
        self.scene.events = events
            .iter()
            .map(|(t, what)| ViewEvent {
                t: *t,
                what: what.clone(),
            })
            .collect();
        ViewData {
            scene: self.scene,
            frames: Frames {
                width: self.width,
                data: self.frames,
            },
        }
    }
}

#[cfg(test)]
mod tests;
