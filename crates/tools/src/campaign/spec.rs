//! The `[campaign]` table: runs, seed, the dispersions and their laws, and the values they
//! address in the scene as written (contract section 8).
//!
//! # Addressing
//!
//! A `key` is a dotted path into the scene's TOML tree ([`crate::scene_keys`], shared with
//! `--set`): `model.body.2.mass`, `effects.hinge_springs.stiffness`, `initial.hinges.angle`,
//! a flexible body's `model.body.1.flexible.beam.EI` (`rho_A`) and `.flexible.damping`.
//! The value at the end must be a number or an array of numbers; `index` picks one element
//! of an array.
//!
//! # Draws
//!
//! Run `k` draws from a ChaCha12 generator whose 256-bit key is the master seed as 8
//! little-endian bytes followed by 24 zero bytes, and whose 64-bit stream (nonce) is `k`,
//! starting at word 0. ChaCha is a pseudo-random function of (key, stream, position), so the
//! draws of run `k` depend on `(seed, k)` alone, never on which thread or shard runs it. Each
//! dispersed value takes exactly one variate, in file order (`[[campaign.disperse]]` entries
//! in order, the elements of an array without `index` in order):
//!
//! - `normal = { sigma }`: `nominal + sigma * z`, `z` standard normal (ziggurat, `rand_distr`);
//! - `uniform = { low, high }`: `nominal + low + (high - low) * u`, `u` uniform in `[0, 1)`;
//! - `scale = { sigma }`: `nominal * (1 + sigma * z)`.

use crate::scene_keys::{self, kind, walk};
pub use crate::scene_keys::{KeyError, Segment};
use chacha20::ChaCha12Rng;
use rand_core::SeedableRng;
use rand_distr::{Distribution, StandardNormal, StandardUniform};
use serde::Deserialize;
use toml::{Spanned, Table, Value};

/// `[campaign]` as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct CampaignFile {
    pub runs: Spanned<i64>,
    #[serde(default)]
    pub seed: Option<Spanned<i64>>,
    #[serde(default)]
    pub disperse: Vec<Spanned<DisperseFile>>,
    /// Stat columns to draw histograms of (default: the final hinge angles and bus rates).
    #[serde(default)]
    pub histograms: Option<Spanned<Vec<String>>>,
}

/// One `[[campaign.disperse]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct DisperseFile {
    pub key: Spanned<String>,
    #[serde(default)]
    pub index: Option<Spanned<i64>>,
    #[serde(default)]
    pub normal: Option<SigmaFile>,
    #[serde(default)]
    pub uniform: Option<UniformFile>,
    #[serde(default)]
    pub scale: Option<SigmaFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SigmaFile {
    pub sigma: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct UniformFile {
    pub low: f64,
    pub high: f64,
}

/// A dispersion law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Law {
    /// `nominal + sigma * z`, `z ~ N(0, 1)`.
    Normal {
        /// Standard deviation (same unit as the value), >= 0.
        sigma: f64,
    },
    /// `nominal + low + (high - low) * u`, `u ~ U[0, 1)`.
    Uniform {
        /// Lower bound of the offset.
        low: f64,
        /// Upper bound of the offset (>= `low`).
        high: f64,
    },
    /// `nominal * (1 + sigma * z)`, `z ~ N(0, 1)`.
    Scale {
        /// Relative standard deviation, >= 0.
        sigma: f64,
    },
}

impl Law {
    /// The value drawn from `nominal` with the next variate(s) of `rng` (exactly one).
    pub fn draw(&self, nominal: f64, rng: &mut ChaCha12Rng) -> f64 {
        match *self {
            Law::Normal { sigma } => {
                let z: f64 = StandardNormal.sample(rng);
                nominal + sigma * z
            }
            Law::Uniform { low, high } => {
                let u: f64 = StandardUniform.sample(rng);
                nominal + low + (high - low) * u
            }
            Law::Scale { sigma } => {
                let z: f64 = StandardNormal.sample(rng);
                nominal * (1.0 + sigma * z)
            }
        }
    }
}

/// One dispersed number of the scene.
#[derive(Clone, Debug)]
pub struct Dispersed {
    /// The `runs.csv` column: `key[index]`, or `key` for a scalar.
    pub column: String,
    /// The path to the number (the array element included).
    pub path: Vec<Segment>,
    /// The value as written in the scene.
    pub nominal: f64,
    /// Its law.
    pub law: Law,
}

/// The generator of run `k` (see the module documentation).
pub fn run_rng(seed: u64, k: u64) -> ChaCha12Rng {
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    let mut rng = ChaCha12Rng::from_seed(key);
    rng.set_stream(k);
    rng
}

/// The values run `k` uses, one per dispersed number, in order.
pub fn draw(dispersed: &[Dispersed], seed: u64, k: u64) -> Vec<f64> {
    let mut rng = run_rng(seed, k);
    dispersed
        .iter()
        .map(|d| d.law.draw(d.nominal, &mut rng))
        .collect()
}

fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Integer(i) => Some(*i as f64),
        Value::Float(x) => Some(*x),
        _ => None,
    }
}

/// Resolves `key` (with an optional `index`) in `root` into the dispersed numbers it
/// addresses (one, or one per element of an array without `index`).
pub(crate) fn resolve(
    root: &Table,
    key: &str,
    index: Option<i64>,
    law: Law,
) -> Result<Vec<Dispersed>, KeyError> {
    let (path, target) = walk(root, key)?;
    let element = |i: usize, v: &Value| -> Result<Dispersed, KeyError> {
        let nominal = number(v)
            .ok_or_else(|| KeyError(format!("`{key}[{i}]` is {}, not a number", kind(v))))?;
        let mut p = path.clone();
        p.push(Segment::Index(i));
        Ok(Dispersed {
            column: format!("{key}[{i}]"),
            path: p,
            nominal,
            law,
        })
    };
    match (target, index) {
        (Value::Array(a), Some(i)) => {
            if i < 0 || i as usize >= a.len() {
                return Err(KeyError(format!(
                    "index {i} is out of range: `{key}` has {} entries",
                    a.len()
                )));
            }
            Ok(vec![element(i as usize, &a[i as usize])?])
        }
        (Value::Array(a), None) => {
            if a.is_empty() {
                return Err(KeyError(format!("`{key}` is an empty array")));
            }
            a.iter().enumerate().map(|(i, v)| element(i, v)).collect()
        }
        (v, None) => match number(v) {
            Some(nominal) => Ok(vec![Dispersed {
                column: key.to_owned(),
                path,
                nominal,
                law,
            }]),
            None => Err(KeyError(format!(
                "`{key}` is {}, not a number or an array of numbers",
                kind(v)
            ))),
        },
        (v, Some(_)) => Err(KeyError(format!(
            "`index` is given but `{key}` is {}, not an array",
            kind(v)
        ))),
    }
}

/// Sets the number at `path` in `root` (which [`resolve`] found there).
pub(crate) fn set(root: &mut Table, path: &[Segment], value: f64) {
    scene_keys::set(root, path, Value::Float(value));
}

/// The keys whose value, when it is an array of four numbers, is a quaternion `[w, x, y, z]`:
/// `initial.base.attitude`, `fsw.guidance.attitude`, `effects.attitude_control.attitude`, a
/// hinge's `rotation`.
const QUATERNION_KEYS: [&str; 2] = ["attitude", "rotation"];

/// Normalises each quaternion of `root` one of whose components `dispersed` draws: a drawn
/// component moves the norm off 1 by more than a scene accepts (`sigma = 0.05` on one
/// component moves it by 1.3e-3), and the run takes the attitude the drawn quaternion points
/// at. `runs.csv` keeps the component as drawn. A quaternion drawn zero or not finite is left
/// as drawn, for the run's scene to refuse.
pub(crate) fn normalise_quaternions(root: &mut Table, dispersed: &[Dispersed]) {
    for d in dispersed {
        let Some((Segment::Index(_), parent)) = d.path.split_last() else {
            continue;
        };
        let Some(Segment::Key(key)) = parent.last() else {
            continue;
        };
        if !QUATERNION_KEYS.contains(&key.as_str()) {
            continue;
        }
        let Some(Value::Array(a)) = value_mut(root, parent) else {
            continue;
        };
        let q: Vec<f64> = a
            .iter()
            .filter_map(|v| match v {
                Value::Float(x) => Some(*x),
                Value::Integer(i) => Some(*i as f64),
                _ => None,
            })
            .collect();
        let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        if q.len() == 4 && a.len() == 4 && norm.is_finite() && norm > 0.0 {
            for (v, x) in a.iter_mut().zip(q) {
                *v = Value::Float(x / norm);
            }
        }
    }
}

/// The value at `path` in `root`, if there is one.
fn value_mut<'a>(root: &'a mut Table, path: &[Segment]) -> Option<&'a mut Value> {
    let (Segment::Key(first), rest) = path.split_first()? else {
        return None;
    };
    let mut here = root.get_mut(first)?;
    for seg in rest {
        here = match (here, seg) {
            (Value::Table(t), Segment::Key(k)) => t.get_mut(k)?,
            (Value::Array(a), Segment::Index(i)) => a.get_mut(*i)?,
            _ => return None,
        };
    }
    Some(here)
}

/// The largest |z| a standard normal variate is taken to reach when checking that draws stay
/// finite: beyond 40 the normal's probability is below 1e-300.
const Z_REACH: f64 = 40.0;

/// Checks that `law` keeps every draw from the numbers `found` finite (a `sigma` of 1e308
/// would draw infinities and record them as values).
pub(crate) fn check_reach(found: &[Dispersed], law: Law) -> Result<(), String> {
    for f in found {
        let x = f.nominal.abs();
        let (reach, what) = match law {
            Law::Normal { sigma } => (x + Z_REACH * sigma, "normal.sigma"),
            Law::Scale { sigma } => (x * (1.0 + Z_REACH * sigma), "scale.sigma"),
            Law::Uniform { low, high } => (
                (x + low.abs().max(high.abs())) + (high - low),
                "uniform.low` and `uniform.high",
            ),
        };
        if !reach.is_finite() {
            return Err(format!(
                "`{what}` is too large for `{}` = {}: its draws would overflow to infinity",
                f.column, f.nominal
            ));
        }
    }
    Ok(())
}

/// The law of a `[[campaign.disperse]]` entry, checked.
pub(crate) fn law_of(d: &DisperseFile) -> Result<Law, String> {
    let given = [d.normal.is_some(), d.uniform.is_some(), d.scale.is_some()]
        .iter()
        .filter(|g| **g)
        .count();
    if given != 1 {
        return Err(format!(
            "give exactly one law (`normal`, `uniform` or `scale`), got {given}"
        ));
    }
    let sigma_ok = |what: &str, s: f64| {
        if s.is_finite() && s >= 0.0 {
            Ok(s)
        } else {
            Err(format!(
                "`{what}.sigma` must be a finite number >= 0, got {s}"
            ))
        }
    };
    if let Some(n) = &d.normal {
        return Ok(Law::Normal {
            sigma: sigma_ok("normal", n.sigma)?,
        });
    }
    if let Some(s) = &d.scale {
        return Ok(Law::Scale {
            sigma: sigma_ok("scale", s.sigma)?,
        });
    }
    let u = d.uniform.as_ref().expect("one law is given");
    if !(u.low.is_finite() && u.high.is_finite()) {
        return Err(format!(
            "`uniform.low` and `uniform.high` must be finite, got {} and {}",
            u.low, u.high
        ));
    }
    if u.low > u.high {
        return Err(format!(
            "`uniform.low` ({}) is above `uniform.high` ({})",
            u.low, u.high
        ));
    }
    Ok(Law::Uniform {
        low: u.low,
        high: u.high,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn moments(xs: &[f64]) -> (f64, f64) {
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, var.sqrt())
    }

    fn draws(law: Law, nominal: f64, n: u64) -> Vec<f64> {
        let d = [Dispersed {
            column: "x".into(),
            path: vec![Segment::Key("x".into())],
            nominal,
            law,
        }];
        (0..n).map(|k| draw(&d, 7, k)[0]).collect()
    }

    // With n draws the sample mean's standard error is sd / sqrt(n) and the sample standard
    // deviation's is about sd / sqrt(2 n): the bounds below are 5 standard errors.
    const N: u64 = 20_000;

    #[test]
    fn normal_draws_have_the_nominal_mean_and_sigma() {
        let xs = draws(Law::Normal { sigma: 0.3 }, 2.0, N);
        let (m, s) = moments(&xs);
        let n = N as f64;
        assert!((m - 2.0).abs() < 5.0 * 0.3 / n.sqrt(), "mean {m}");
        assert!((s - 0.3).abs() < 5.0 * 0.3 / (2.0 * n).sqrt(), "sd {s}");
    }

    #[test]
    fn uniform_draws_cover_the_interval_with_the_right_moments() {
        let (low, high) = (-0.5, 1.5);
        let xs = draws(Law::Uniform { low, high }, 10.0, N);
        assert!(xs.iter().all(|x| (10.0 + low..10.0 + high).contains(x)));
        let (m, s) = moments(&xs);
        let sd = (high - low) / 12f64.sqrt();
        let n = N as f64;
        assert!((m - 10.5).abs() < 5.0 * sd / n.sqrt(), "mean {m}");
        // The uniform's kurtosis is lower than the normal's: the bound is conservative.
        assert!((s - sd).abs() < 5.0 * sd / (2.0 * n).sqrt(), "sd {s}");
    }

    #[test]
    fn scale_draws_are_relative() {
        let xs = draws(Law::Scale { sigma: 0.05 }, 40.0, N);
        let (m, s) = moments(&xs);
        let sd = 40.0 * 0.05;
        let n = N as f64;
        assert!((m - 40.0).abs() < 5.0 * sd / n.sqrt(), "mean {m}");
        assert!((s - sd).abs() < 5.0 * sd / (2.0 * n).sqrt(), "sd {s}");
        // Zero stays zero under a relative law.
        assert!(
            draws(Law::Scale { sigma: 0.5 }, 0.0, 10)
                .iter()
                .all(|x| *x == 0.0)
        );
    }

    #[test]
    fn zero_spread_returns_the_nominal_value() {
        assert!(
            draws(Law::Normal { sigma: 0.0 }, 1.25, 50)
                .iter()
                .all(|x| *x == 1.25)
        );
        assert!(
            draws(
                Law::Uniform {
                    low: 0.0,
                    high: 0.0
                },
                1.25,
                50
            )
            .iter()
            .all(|x| *x == 1.25)
        );
    }

    #[test]
    fn a_run_depends_on_seed_and_k_alone() {
        let d: Vec<Dispersed> = (0..3)
            .map(|i| Dispersed {
                column: format!("x[{i}]"),
                path: vec![],
                nominal: 0.0,
                law: Law::Normal { sigma: 1.0 },
            })
            .collect();
        assert_eq!(draw(&d, 7, 5), draw(&d, 7, 5));
        assert_ne!(draw(&d, 7, 5), draw(&d, 7, 6));
        assert_ne!(draw(&d, 7, 5), draw(&d, 8, 5));
        // Elements of one run are different variates.
        let v = draw(&d, 7, 5);
        assert!(v[0] != v[1] && v[1] != v[2]);
    }

    #[test]
    fn keys_walk_tables_and_arrays() {
        let root: Table = toml::from_str(
            "[model]\n[[model.body]]\nmass = 1\n[[model.body]]\nmass = 2.5\ninertia = [[1.0, 0.0], [0.0, 2.0]]\n[x]\nname = \"a\"\nv = [1.0, 2.0, 3.0]\n",
        )
        .unwrap();
        let law = Law::Normal { sigma: 1.0 };
        let d = resolve(&root, "model.body.1.mass", None, law).unwrap();
        assert_eq!(d.len(), 1);
        assert_eq!(
            (d[0].column.as_str(), d[0].nominal),
            ("model.body.1.mass", 2.5)
        );
        let d = resolve(&root, "model.body.0.mass", None, law).unwrap();
        assert_eq!(d[0].nominal, 1.0);
        let d = resolve(&root, "x.v", None, law).unwrap();
        assert_eq!(
            d.iter().map(|d| d.column.as_str()).collect::<Vec<_>>(),
            ["x.v[0]", "x.v[1]", "x.v[2]"]
        );
        let d = resolve(&root, "x.v", Some(2), law).unwrap();
        assert_eq!((d[0].column.as_str(), d[0].nominal), ("x.v[2]", 3.0));
        let d = resolve(&root, "model.body.1.inertia.1", Some(1), law).unwrap();
        assert_eq!(d[0].nominal, 2.0);
        for (key, index, why) in [
            ("model.body.2.mass", None, "out of range"),
            ("model.body.one.mass", None, "expected a position"),
            ("x.w", None, "has no key `w`"),
            ("y", None, "no `y`"),
            ("x.name", None, "not a number"),
            ("x.v", Some(3), "index 3 is out of range"),
            ("x.v", Some(-1), "out of range"),
            ("model.body.1.mass", Some(0), "not an array"),
            ("model.body.1.inertia", None, "not a number"),
            ("x..v", None, "empty segment"),
        ] {
            let e = resolve(&root, key, index, law).unwrap_err().0;
            assert!(e.contains(why), "{key}: {e}");
        }
    }

    #[test]
    fn set_writes_the_addressed_number() {
        let mut root: Table =
            toml::from_str("[[b]]\nm = 1\n[[b]]\nm = 2\nv = [1.0, 2.0]\n").unwrap();
        let d = resolve(&root, "b.1.v", Some(1), Law::Normal { sigma: 1.0 }).unwrap();
        set(&mut root, &d[0].path, 9.5);
        let d = resolve(&root, "b.1.m", None, Law::Normal { sigma: 1.0 }).unwrap();
        set(&mut root, &d[0].path, 0.25);
        assert_eq!(root["b"][1]["v"][1].as_float(), Some(9.5));
        assert_eq!(root["b"][1]["m"].as_float(), Some(0.25));
        assert_eq!(root["b"][0]["m"].as_integer(), Some(1));
    }
}
