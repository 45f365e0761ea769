//! Structural modes: the eigenvalues and eigenvectors of the linearised scene (contract
//! section 9, `satsim modes`), and their sweep over a deployment (`satsim modes --along`).
//!
//! From `A` of [`crate::linearize`] (the frozen states of locked hinges left out), the
//! eigenvalues `λ` of the remaining matrix are sorted into
//!
//! - **rigid**: `|λ| ≤ √(ε · max |Aᵢⱼ|)` with `ε` = [`RIGID_TOLERANCE`] = 10⁻¹⁴ (all of
//!   them when `A` is zero). A free body has three double zeros (attitude and angular
//!   velocity) and three simple ones (velocity); a hinge with neither spring nor controller
//!   adds a double zero. Why this scale: the decomposition returns the eigenvalues of `A`
//!   perturbed by about `n · 2⁻⁵² · max |Aᵢⱼ|` (its backward error, `ε` above for the
//!   tens of states of a spacecraft), and a double zero (a free coordinate and its rate,
//!   `q̇ = v`, `v̇ = 0`) perturbed by `δ` splits into `±√δ`: that is how far from zero a
//!   rigid mode can land. A tolerance relative to the largest eigenvalue instead grows
//!   with the stiffest spring: a gimbal spring of 10¹² N m/rad (eigenvalues of 10⁵ 1/s)
//!   made it 0.1 1/s and hid the panels' 0.03 Hz mode, which this one (0.04 1/s there,
//!   3·10⁻⁷ 1/s for the example scenes) keeps;
//! - **oscillatory**: a pair `λ, λ̄` with non-zero imaginary part, one [`Mode`] per pair
//!   with frequency `f = |Im λ| / 2π` (Hz) and damping ratio `ζ = −Re λ / |λ|`
//!   (negative: the mode grows);
//! - **real**: the rest (overdamped or divergent motions), listed in
//!   [`Modes::real_eigenvalues`].
//!
//! A mode's shape is the eigenvector of `λ` (the member of the pair with `Im λ > 0`),
//! divided by its hinge-angle entry of largest modulus, so that this entry is exactly
//! `1 + 0i`; when the mode moves no hinge (all hinge-angle entries below 10⁻⁹ of its
//! largest entry, or a model without hinges) by its modal-coordinate (`eta_`, flexible
//! bodies) entry of largest modulus, and when it moves neither, by its largest entry. [`Mode::shape`]
//! holds the real parts, [`Mode::shape_imag`] the imaginary parts (zero for undamped or
//! proportionally damped structures), both by state name.
//!
//! Locked hinges are left out of the decomposition and stuck wheels released, as
//! [`crate::linearize`] says; the zero rows of a locked hinge's angle and rate are two
//! eigenvalues of `A` at zero, counted in [`Modes::rigid_modes`].
//!
//! Eigenvalues come from faer's real Schur decomposition (`Mat::eigen`).

use crate::linearize::{Linearization, LinearizeError, linearize};
use crate::output::{Series, line_plot};
use crate::scene::Scene;
use thiserror::Error;

/// The eigenvalues' relative backward error `ε`: an eigenvalue with
/// `|λ| ≤ √(ε · max |Aᵢⱼ|)` counts as zero (rigid; see the module documentation).
pub const RIGID_TOLERANCE: f64 = 1e-14;

/// Why modes could not be computed.
#[derive(Debug, Error)]
pub enum ModesError {
    /// The linearisation failed.
    #[error("{0}")]
    Linearize(#[from] LinearizeError),
    /// The eigenvalue decomposition did not converge.
    #[error("the eigenvalue decomposition of A did not converge")]
    Eigen,
    /// A bad `--along` sweep (unknown hinge, no steps…).
    #[error("{0}")]
    Sweep(String),
}

/// One oscillatory mode (a pair of complex-conjugate eigenvalues).
#[derive(Clone, Debug, PartialEq)]
pub struct Mode {
    /// `|Im λ| / 2π` (Hz).
    pub frequency_hz: f64,
    /// `−Re λ / |λ|`.
    pub damping_ratio: f64,
    /// `λ` with `Im λ > 0`: `(Re, Im)` (1/s).
    pub eigenvalue: (f64, f64),
    /// Real part of the normalised eigenvector, `(state name, value)` in state order.
    pub shape: Vec<(String, f64)>,
    /// Imaginary part of the normalised eigenvector, same order.
    pub shape_imag: Vec<(String, f64)>,
}

/// The modes of a linearised scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Modes {
    /// Frequencies of the oscillatory modes (Hz), ascending.
    pub frequencies_hz: Vec<f64>,
    /// Their damping ratios, same order.
    pub damping_ratios: Vec<f64>,
    /// Number of eigenvalues of `A` at zero (a locked hinge's angle and rate count two).
    pub rigid_modes: usize,
    /// The oscillatory modes, same order.
    pub modes: Vec<Mode>,
    /// The non-zero real eigenvalues (1/s), ascending.
    pub real_eigenvalues: Vec<f64>,
    /// Hinges locked at the initial state, left out of the analysis.
    pub locked: Vec<String>,
    /// Wheels stuck at the initial state, released for the analysis.
    pub released: Vec<String>,
    /// Why the initial state is not an equilibrium, when it is not
    /// ([`Linearization::not_an_equilibrium`]): the modes then describe a motion frozen at
    /// one instant, not vibrations.
    pub not_equilibrium: Option<String>,
}

/// Linearises `scene` at its initial state and returns its modes.
pub fn modes(scene: &Scene) -> Result<Modes, ModesError> {
    let lin = linearize(scene)?;
    modes_of(&lin)
}

/// The modes of a linearisation.
pub fn modes_of(lin: &Linearization) -> Result<Modes, ModesError> {
    let active: Vec<usize> = (0..lin.states.len()).filter(|&i| !lin.frozen[i]).collect();
    let n = active.len();
    let a = faer::Mat::<f64>::from_fn(n, n, |r, c| lin.a[(active[r], active[c])]);
    let (values, vectors) = if n == 0 {
        (Vec::new(), faer::Mat::<faer::c64>::zeros(0, 0))
    } else {
        let evd = a.eigen().map_err(|_| ModesError::Eigen)?;
        let s = evd.S().column_vector();
        let values: Vec<(f64, f64)> = (0..n).map(|i| (s[i].re, s[i].im)).collect();
        (values, evd.U().to_owned())
    };
    if values
        .iter()
        .any(|(re, im)| !re.is_finite() || !im.is_finite())
    {
        return Err(ModesError::Eigen);
    }
    let largest = active
        .iter()
        .flat_map(|&r| active.iter().map(move |&c| lin.a[(r, c)].abs()))
        .fold(0.0f64, f64::max);
    let zero = (RIGID_TOLERANCE * largest).sqrt();
    // The frozen states' rows of `A` are zero: each is an eigenvalue at zero of the printed
    // `A`, counted as such.
    let mut rigid = lin.states.len() - n;
    let mut real = Vec::new();
    let mut modes = Vec::new();
    let angle_rows: Vec<usize> = (0..n)
        .filter(|&r| lin.states[active[r]].starts_with("angle_"))
        .collect();
    let eta_rows: Vec<usize> = (0..n)
        .filter(|&r| lin.states[active[r]].starts_with("eta_"))
        .collect();
    for (i, &(re, im)) in values.iter().enumerate() {
        let modulus = re.hypot(im);
        if modulus <= zero {
            rigid += 1;
        } else if im == 0.0 {
            real.push(re);
        } else if im > 0.0 {
            let col = vectors.col(i);
            let magnitude = |r: usize| col[r].re.hypot(col[r].im);
            let overall = (0..n).map(magnitude).fold(0.0f64, f64::max);
            let best_angle = angle_rows
                .iter()
                .copied()
                .max_by(|&p, &q| magnitude(p).total_cmp(&magnitude(q)));
            let best_eta = eta_rows
                .iter()
                .copied()
                .max_by(|&p, &q| magnitude(p).total_cmp(&magnitude(q)));
            let pivot = match (best_angle, best_eta) {
                (Some(p), _) if magnitude(p) > 1e-9 * overall => p,
                (_, Some(p)) if magnitude(p) > 1e-9 * overall => p,
                _ => (0..n)
                    .max_by(|&p, &q| magnitude(p).total_cmp(&magnitude(q)))
                    .unwrap_or(0),
            };
            let p = col[pivot];
            let den = p.re * p.re + p.im * p.im;
            let mut shape: Vec<(String, f64)> =
                lin.states.iter().map(|s| (s.clone(), 0.0)).collect();
            let mut shape_imag = shape.clone();
            for r in 0..n {
                let v = col[r];
                // v / p
                let (sr, si) = if r == pivot {
                    (1.0, 0.0)
                } else {
                    (
                        (v.re * p.re + v.im * p.im) / den,
                        (v.im * p.re - v.re * p.im) / den,
                    )
                };
                shape[active[r]].1 = sr;
                shape_imag[active[r]].1 = si;
            }
            modes.push(Mode {
                frequency_hz: im / (2.0 * std::f64::consts::PI),
                // `+ 0.0` turns the −0 of an undamped mode into 0.
                damping_ratio: -re / modulus + 0.0,
                eigenvalue: (re, im),
                shape,
                shape_imag,
            });
        }
    }
    modes.sort_by(|a, b| {
        a.frequency_hz
            .total_cmp(&b.frequency_hz)
            .then(a.damping_ratio.total_cmp(&b.damping_ratio))
    });
    real.sort_by(f64::total_cmp);
    Ok(Modes {
        frequencies_hz: modes.iter().map(|m| m.frequency_hz).collect(),
        damping_ratios: modes.iter().map(|m| m.damping_ratio).collect(),
        rigid_modes: rigid,
        modes,
        real_eigenvalues: real,
        locked: lin.locked.clone(),
        released: lin.released.clone(),
        not_equilibrium: lin.not_an_equilibrium(),
    })
}

/// One hinge swept by [`sweep`]: from `from` to `to` (rad).
#[derive(Clone, Debug, PartialEq)]
pub struct Along {
    /// The hinge's name.
    pub hinge: String,
    /// First angle (rad).
    pub from: f64,
    /// Last angle (rad).
    pub to: f64,
}

impl Along {
    /// Parses `HINGE=FROM:TO` (angles in rad).
    pub fn parse(text: &str) -> Result<Self, String> {
        let (hinge, range) = text
            .split_once('=')
            .ok_or_else(|| format!("`{text}`: expected HINGE=FROM:TO"))?;
        let (from, to) = range
            .split_once(':')
            .ok_or_else(|| format!("`{text}`: expected HINGE=FROM:TO"))?;
        let num = |s: &str| {
            s.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("`{text}`: `{s}` is not a finite number of radians"))
        };
        Ok(Self {
            hinge: hinge.trim().to_owned(),
            from: num(from)?,
            to: num(to)?,
        })
    }
}

/// One configuration of a sweep: the swept hinges' angles (rad, in the order given) and the
/// modes there.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepPoint {
    /// The swept hinges' angles (rad).
    pub angles: Vec<f64>,
    /// The modes at that configuration.
    pub modes: Modes,
}

/// The modes of `scene` with the hinges of `along` moved together, in `steps` equal steps
/// (`steps >= 2` configurations, ends included), every other part of the initial state as
/// in the scene. Each configuration is held: the swept hinges' spring references
/// (`[effects.hinge_springs] reference`) move with them, so that a configuration at rest is
/// an equilibrium, as a deployment that paused there would be (linearised about a
/// configuration its springs are pulling out of, the model would describe the start of
/// that motion, not vibrations about it). A configuration the scene rejects (a hinge
/// beyond its stop) is an error.
pub fn sweep(scene: &Scene, along: &[Along], steps: usize) -> Result<Vec<SweepPoint>, ModesError> {
    if along.is_empty() {
        return Err(ModesError::Sweep("no hinge to sweep".into()));
    }
    if steps < 2 {
        return Err(ModesError::Sweep(format!(
            "a sweep needs at least 2 configurations, got {steps}"
        )));
    }
    let model = &scene.model;
    let mut index = Vec::with_capacity(along.len());
    for a in along {
        let k = model.hinge_names()[..model.n_hinges()]
            .iter()
            .position(|n| *n == a.hinge)
            .ok_or_else(|| {
                ModesError::Sweep(format!(
                    "unknown hinge `{}` (the model's hinges: {})",
                    a.hinge,
                    model.hinge_names().join(", ")
                ))
            })?;
        if index.contains(&k) {
            return Err(ModesError::Sweep(format!(
                "hinge `{}` swept twice",
                a.hinge
            )));
        }
        index.push(k);
    }
    let nq0 = model.base_nq();
    let mut points = Vec::with_capacity(steps);
    for s in 0..steps {
        let f = s as f64 / (steps - 1) as f64;
        let mut sc = scene.clone();
        let angles: Vec<f64> = along.iter().map(|a| a.from + f * (a.to - a.from)).collect();
        for (&k, &angle) in index.iter().zip(&angles) {
            sc.initial.q[nq0 + k] = angle;
            if let Some(springs) = sc
                .effects
                .get_mut::<satsim_spacecraft::effects::HingeSprings>()
            {
                springs.reference[k] = angle;
            }
        }
        let m = modes(&sc).map_err(|e| {
            let at: Vec<String> = along
                .iter()
                .zip(&angles)
                .map(|(a, v)| format!("{} = {v}", a.hinge))
                .collect();
            ModesError::Sweep(format!("at {}: {e}", at.join(", ")))
        })?;
        points.push(SweepPoint { angles, modes: m });
    }
    Ok(points)
}

/// An SVG plot of a sweep: each frequency (by rank: the lowest, the second lowest, …)
/// against the first swept hinge's angle in degrees. A rank a configuration lacks (a mode
/// that became overdamped or locked) leaves a gap.
pub fn sweep_plot(points: &[SweepPoint], along: &[Along], title: &str) -> String {
    let x: Vec<f64> = points
        .iter()
        .map(|p| p.angles.first().copied().unwrap_or(0.0).to_degrees())
        .collect();
    let ranks = points
        .iter()
        .map(|p| p.modes.frequencies_hz.len())
        .max()
        .unwrap_or(0);
    let ys: Vec<Vec<f64>> = (0..ranks)
        .map(|r| {
            points
                .iter()
                .map(|p| p.modes.frequencies_hz.get(r).copied().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    let labels: Vec<String> = (1..=ranks).map(|r| format!("mode {r} (Hz)")).collect();
    let series: Vec<Series> = labels
        .iter()
        .zip(&ys)
        .map(|(label, y)| Series { label, y })
        .collect();
    let xlabel = match along.first() {
        Some(a) if along.len() == 1 => format!("angle of {} (deg)", a.hinge),
        Some(a) => format!(
            "angle of {} (deg; {} swept with it)",
            a.hinge,
            along[1..]
                .iter()
                .map(|a| a.hinge.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ),
        None => "angle (deg)".into(),
    };
    line_plot(title, &xlabel, &x, &series)
}
