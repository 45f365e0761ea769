//! A state file's `base.attitude`, in any of its three forms: a quaternion, Euler angles in a
//! stated sequence, or an axis and an angle.
//!
//! See [`Attitude`].

use crate::spatial::Vec3;
use nalgebra::{Unit, UnitQuaternion};
use serde::Deserialize;
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use std::fmt;

/// `base.attitude` as written, in one of three forms.
///
/// All three give the root body frame relative to the inertial frame: the rotation that maps
/// root-body coordinates to inertial ones (the quaternion `q` of the state, Hamilton
/// `[w, x, y, z]`, `v_inertial = q v_body q*`).
///
/// - `[w, x, y, z]`: the quaternion itself (the contract's form).
/// - `{"euler_deg": [a1, a2, a3], "sequence": "zyx"}`: intrinsic rotations, in degrees, about
///   the axes named by `sequence` in that order, each about the axis as already turned by the
///   rotations before it: `q = Q(e1, a1) ⊗ Q(e2, a2) ⊗ Q(e3, a3)`. The angles come in the
///   order of the sequence (as `scipy`'s `from_euler("ZYX", …)` and MATLAB's
///   `eul2quat(…, "ZYX")` take them): for `"zyx"`, `[yaw, pitch, roll]` (z-y′-x″, the
///   aerospace 3-2-1 sequence), which is nalgebra's
///   `UnitQuaternion::from_euler_angles(roll, pitch, yaw)`. Any of the 12 sequences of three
///   axes with no axis twice in a row: the six Tait–Bryan ones (`xyz`, `xzy`, `yxz`, `yzx`,
///   `zxy`, `zyx`) and the six proper Euler ones (`xyx`, `xzx`, `yxy`, `yzy`, `zxz`, `zyz`).
/// - `{"axis": [x, y, z], "angle_deg": θ}`: a right-handed rotation by `θ` degrees about
///   `axis` (the same components in both frames; any non-zero length, normalised):
///   `q = [cos(θ/2), sin(θ/2) â]`.
///
/// The angle forms are checked as they are read (so that a JSON or TOML error names the line);
/// the quaternion's length and norm are checked against the model by
/// [`StateFile::resolve`](super::StateFile::resolve).
///
/// ```
/// use satsim_tree::io::{Attitude, StateFile};
/// let f: StateFile = serde_json::from_str(
///     r#"{"base": {"attitude": {"euler_deg": [90, 0, 0], "sequence": "zyx"}}}"#,
/// )?;
/// let Some(Attitude::Euler { angles_deg, sequence }) = f.base.unwrap().attitude else {
///     panic!()
/// };
/// assert_eq!((angles_deg, sequence.as_str()), ([90.0, 0.0, 0.0], "zyx"));
/// # Ok::<(), serde_json::Error>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub enum Attitude {
    /// `[w, x, y, z]`, as written (its length and norm are checked by
    /// [`StateFile::resolve`](super::StateFile::resolve)).
    Quaternion(Vec<f64>),
    /// `{"euler_deg": [a1, a2, a3], "sequence": "zyx"}`: intrinsic rotations (degrees) in the
    /// order of the sequence.
    Euler {
        /// The three angles (degrees), in the order of `sequence`.
        angles_deg: [f64; 3],
        /// The axes, in order.
        sequence: EulerSequence,
    },
    /// `{"axis": [x, y, z], "angle_deg": θ}`: a rotation by `θ` degrees about `axis`.
    AxisAngle {
        /// Unit axis (the same components in root-body and inertial coordinates).
        axis: Unit<Vec3>,
        /// Angle (degrees), right-handed about `axis`.
        angle_deg: f64,
    },
}

/// The axes of an Euler-angle sequence, e.g. `zyx` (intrinsic: each rotation about the axis
/// as turned by the rotations before it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EulerSequence([u8; 3]);

/// The accepted sequences, as written.
pub const EULER_SEQUENCES: [&str; 12] = [
    "xyz", "xzy", "yxz", "yzx", "zxy", "zyx", "xyx", "xzx", "yxy", "yzy", "zxz", "zyz",
];

impl EulerSequence {
    /// Parses a sequence such as `"zyx"`: three of `x`, `y`, `z` (lower case), no axis twice
    /// in a row.
    pub fn parse(s: &str) -> Option<Self> {
        EULER_SEQUENCES.contains(&s).then(|| {
            let b = s.as_bytes();
            Self([b[0], b[1], b[2]])
        })
    }
    /// The sequence as written, e.g. `"zyx"`.
    pub fn as_str(&self) -> &str {
        std::str::from_utf8(&self.0).expect("ascii")
    }
    /// `Q(e1, a1) ⊗ Q(e2, a2) ⊗ Q(e3, a3)` for angles in radians.
    pub fn quaternion(&self, angles: [f64; 3]) -> UnitQuaternion<f64> {
        self.0
            .iter()
            .zip(angles)
            .fold(UnitQuaternion::identity(), |q, (&axis, angle)| {
                let e = match axis {
                    b'x' => Vec3::x_axis(),
                    b'y' => Vec3::y_axis(),
                    _ => Vec3::z_axis(),
                };
                q * UnitQuaternion::from_axis_angle(&e, angle)
            })
    }
}

impl Attitude {
    /// The rotation (root body to inertial) for the angle forms; `None` for the quaternion
    /// form, which [`StateFile::resolve`](super::StateFile::resolve) checks against its
    /// tolerance.
    pub fn rotation(&self) -> Option<UnitQuaternion<f64>> {
        match self {
            Attitude::Quaternion(_) => None,
            Attitude::Euler {
                angles_deg,
                sequence,
            } => Some(sequence.quaternion(angles_deg.map(f64::to_radians))),
            Attitude::AxisAngle { axis, angle_deg } => Some(UnitQuaternion::from_axis_angle(
                axis,
                angle_deg.to_radians(),
            )),
        }
    }
}

/// The table forms, as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AttitudeTable {
    #[serde(default)]
    euler_deg: Option<Vec<f64>>,
    #[serde(default)]
    sequence: Option<String>,
    #[serde(default)]
    axis: Option<Vec<f64>>,
    #[serde(default)]
    angle_deg: Option<f64>,
}

fn three(key: &str, x: &[f64], what: &str) -> Result<[f64; 3], String> {
    let [a, b, c] = x else {
        return Err(format!(
            "`{key}`: expected 3 numbers ({what}), got {}",
            x.len()
        ));
    };
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(format!("`{key}`: entry {i} is not a finite number"));
    }
    Ok([*a, *b, *c])
}

impl AttitudeTable {
    fn check(self) -> Result<Attitude, String> {
        const FORMS: &str = "give either `euler_deg` and `sequence`, or `axis` and `angle_deg`";
        match self {
            AttitudeTable {
                euler_deg: Some(angles),
                sequence,
                axis: None,
                angle_deg: None,
            } => {
                let Some(sequence) = sequence else {
                    return Err(
                        "`euler_deg` needs `sequence` (e.g. \"zyx\": the angles are yaw, pitch, roll)"
                            .to_owned(),
                    );
                };
                let angles_deg =
                    three("euler_deg", &angles, "degrees, in the order of `sequence`")?;
                let sequence = EulerSequence::parse(&sequence).ok_or_else(|| {
                    format!(
                        "`sequence`: unknown Euler sequence \"{sequence}\" (expected one of {}; intrinsic, lower case)",
                        EULER_SEQUENCES.join(", ")
                    )
                })?;
                Ok(Attitude::Euler {
                    angles_deg,
                    sequence,
                })
            }
            AttitudeTable {
                euler_deg: None,
                sequence: None,
                axis: Some(axis),
                angle_deg,
            } => {
                let Some(angle_deg) = angle_deg else {
                    return Err("`axis` needs `angle_deg` (degrees)".to_owned());
                };
                if !angle_deg.is_finite() {
                    return Err("`angle_deg` is not a finite number".to_owned());
                }
                let [x, y, z] = three("axis", &axis, "a direction")?;
                let axis = Unit::try_new(Vec3::new(x, y, z), 0.0)
                    .ok_or_else(|| "`axis` is zero: it has no direction".to_owned())?;
                Ok(Attitude::AxisAngle { axis, angle_deg })
            }
            AttitudeTable {
                euler_deg: None,
                sequence: Some(_),
                axis: None,
                ..
            } => Err("`sequence` needs `euler_deg` (three angles in degrees)".to_owned()),
            AttitudeTable {
                euler_deg: None,
                axis: None,
                angle_deg: Some(_),
                ..
            } => Err("`angle_deg` needs `axis`".to_owned()),
            _ => Err(format!("an attitude table: {FORMS}")),
        }
    }
}

struct AttitudeVisitor;

impl<'de> Visitor<'de> for AttitudeVisitor {
    type Value = Attitude;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(
            "a quaternion [w, x, y, z], {euler_deg = [..], sequence = \"..\"} or {axis = [..], angle_deg = ..}",
        )
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Attitude, A::Error> {
        let mut q = Vec::with_capacity(4);
        while let Some(x) = seq.next_element::<f64>()? {
            q.push(x);
        }
        Ok(Attitude::Quaternion(q))
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Attitude, A::Error> {
        AttitudeTable::deserialize(de::value::MapAccessDeserializer::new(map))?
            .check()
            .map_err(de::Error::custom)
    }
}

impl<'de> Deserialize<'de> for Attitude {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(AttitudeVisitor)
    }
}
