//! The scene's `[[faults]]` (contract section 17): each fault handed to the effect that owns
//! its target ([`satsim_spacecraft::effects::faults`]): a wheel's to the reaction wheels, a
//! thruster's to the thrusters, a sensor's to the sensors. Every error names the scene file
//! and the line of the key at fault.

use satsim_spacecraft::effects::faults::{FaultKind, show};
use satsim_spacecraft::effects::{EffectSet, ReactionWheels, SceneText, Thrusters};
use satsim_spacecraft::sensors::Sensors;
use satsim_tree::io::FileError;
use serde::Deserialize;
use toml::Spanned;

/// One `[[faults]]` entry.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaultFile {
    /// When it happens (s, finite, >= 0).
    pub at: Spanned<f64>,
    /// What fails: `wheel_stuck`, `wheel_off`, `thruster_stuck_on`, `thruster_off`,
    /// `sensor_stuck` or `sensor_bias`.
    pub kind: Spanned<String>,
    /// The name of the wheel, thruster or sensor that fails.
    pub target: Spanned<String>,
    /// `sensor_bias`'s bias: a number for a one-value sensor, else an array with one number
    /// per component of its reading (its units). No other kind takes one.
    #[serde(default)]
    pub value: Option<Spanned<toml::Value>>,
}

/// Hands each fault of `faults` to the enabled effect that owns its target.
pub(crate) fn read(
    text: &SceneText,
    faults: &[Spanned<FaultFile>],
    effects: &mut EffectSet,
) -> Result<(), FileError> {
    for f in faults {
        let f = f.get_ref();
        let at = *f.at.get_ref();
        if !(at.is_finite() && at >= 0.0) {
            return Err(text.error(
                Some(f.at.span()),
                format!("`faults.at` must be a finite time >= 0 (s), got {at}"),
            ));
        }
        let name = f.kind.get_ref().as_str();
        let target = f.target.get_ref();
        let kind = match name {
            "wheel_stuck" => FaultKind::WheelStuck,
            "wheel_off" => FaultKind::WheelOff,
            "thruster_stuck_on" => FaultKind::ThrusterStuckOn,
            "thruster_off" => FaultKind::ThrusterOff,
            "sensor_stuck" => FaultKind::SensorStuck,
            "sensor_bias" => FaultKind::SensorBias(bias(text, f)?),
            other => {
                return Err(text.error(
                    Some(f.kind.span()),
                    format!(
                        "`faults.kind`: unknown kind `{other}` (known: {})",
                        FaultKind::NAMES.join(", ")
                    ),
                ));
            }
        };
        if !matches!(kind, FaultKind::SensorBias(_))
            && let Some(v) = &f.value
        {
            return Err(text.error(
                Some(v.span()),
                format!("`faults.value`: a `{name}` fault takes no value"),
            ));
        }
        let unknown = |what: &str, section: &str, names: Vec<&str>| {
            let message = if names.is_empty() {
                format!(
                    "`faults.target`: a `{name}` fault needs {what}s, and the scene has none ({section})"
                )
            } else {
                format!(
                    "`faults.target`: no {what} `{target}` in the scene (its {what}s: {})",
                    names.join(", ")
                )
            };
            text.error(Some(f.target.span()), message)
        };
        let added = match kind {
            FaultKind::WheelStuck | FaultKind::WheelOff => {
                let wheels = effects.get_mut::<ReactionWheels>();
                let names = wheels.as_ref().map_or(Vec::new(), |w| {
                    w.wheels.iter().map(|w| w.name.as_str()).collect()
                });
                let Some(j) = names.iter().position(|n| n == target) else {
                    return Err(unknown("wheel", "[effects.reaction_wheels]", names));
                };
                wheels.expect("a wheel").add_fault(at, j, kind)
            }
            FaultKind::ThrusterStuckOn | FaultKind::ThrusterOff => {
                let thrusters = effects.get_mut::<Thrusters>();
                let names = thrusters.as_ref().map_or(Vec::new(), |t| {
                    t.list().iter().map(|t| t.name.as_str()).collect()
                });
                let Some(j) = names.iter().position(|n| n == target) else {
                    return Err(unknown("thruster", "[effects.thrusters]", names));
                };
                thrusters.expect("a thruster").add_fault(at, j, kind)
            }
            FaultKind::SensorStuck | FaultKind::SensorBias(_) => {
                let sensors = effects.get_mut::<Sensors>();
                let names = sensors.as_ref().map_or(Vec::new(), |s| {
                    s.sensors().iter().map(|s| s.name()).collect()
                });
                let Some(j) = names.iter().position(|n| n == target) else {
                    return Err(unknown("sensor", "[sensors]", names));
                };
                sensors.expect("a sensor").add_fault(at, j, kind)
            }
        };
        // A bias of the wrong length is the value's fault; any other, the kind's.
        let span = f.value.as_ref().map_or(f.kind.span(), |v| v.span());
        added.map_err(|m| text.error(Some(span), format!("`faults`: {m}")))?;
    }
    Ok(())
}

/// `sensor_bias`'s `value`: a number, or an array of numbers.
fn bias(text: &SceneText, f: &FaultFile) -> Result<Vec<f64>, FileError> {
    let Some(v) = &f.value else {
        return Err(text.error(
            Some(f.kind.span()),
            format!(
                "`faults.value`: a `sensor_bias` fault on `{}` needs the bias: a number for a one-value sensor, else an array with one number per component of its reading (its units)",
                f.target.get_ref()
            ),
        ));
    };
    let number = |x: &toml::Value| match x {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    };
    let values = match v.get_ref() {
        toml::Value::Array(a) => a.iter().map(number).collect::<Option<Vec<f64>>>(),
        x => number(x).map(|x| vec![x]),
    };
    match values {
        Some(b) if b.iter().all(|x| x.is_finite()) => Ok(b),
        _ => Err(text.error(
            Some(v.span()),
            format!(
                "`faults.value` must be a finite number or an array of finite numbers (the bias, the sensor's units), got {}",
                match values {
                    Some(b) => show(&b),
                    None => v.get_ref().to_string(),
                }
            ),
        )),
    }
}
