//! The magnetic blocks of `[fsw]` (contract section 16): B-dot detumbling on the
//! magnetometer's readings (`[fsw.bdot]`) and wheel momentum dumping (`[fsw.momentum]`),
//! both commanding the scene's magnetic torquers.
//!
//! At each of its samples `t_k` (every `n`-th sample of its magnetometer, `Δt = n` times the
//! magnetometer's period), with `B_k` the magnetometer's reading taken there (body axes, T,
//! noise included):
//!
//! ```text
//! B-dot:     m_k = −k (B_k − B_{k−1}) / Δt          k in A m² s/T; no command at the first
//!                                                   sample (no difference yet)
//! momentum:  m_k = k (h_k × B_k) / |B_k|²           k in 1/s; h_k = Σ_j I_j Ω_j a_j
//! ```
//!
//! `m` is the dipole wanted (body axes, A m²). For momentum dumping `h` is the wheels' spin
//! momentum relative to the bus (N m s, body axes): `I_j` the wheel's axial inertia, `a_j`
//! its axis and `Ω_j` its speed relative to the bus as its tachometer reads it, taken
//! without noise. The couple `m × B = −k h_⊥` (with `h_⊥` the part of `h` across the field)
//! takes momentum out of the spacecraft across the field; a control on the wheels that holds
//! the attitude then absorbs that torque, and the wheels' momentum falls at the rate `k`.
//!
//! The dipole goes to the torquers as the truth-based [`crate::effects::Bdot`] sends it:
//! torquer `j` (on the root body, unit axis `a_j`) is commanded `a_j · m` through
//! [`crate::effects::Forces::dipole_command`], held until the next sample (zero-order hold);
//! the magnetic effect clamps each to its `max_dipole`. Torquers on other bodies get none.

use crate::effects::{Forces, Links};
use crate::sensors::Sensor;
use nalgebra::Vector3;

/// Which law a [`DipoleSpec`] runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DipoleLaw {
    /// B-dot on the finite difference of the readings, gain in A m² s/T.
    Bdot {
        /// The gain `k` (A m² s/T).
        gain: f64,
    },
    /// Wheel momentum dumping, gain in 1/s.
    Momentum {
        /// The gain `k` (1/s).
        gain: f64,
    },
}

/// A magnetic block's wiring: its law, the magnetometer it reads and its clock.
#[derive(Clone, Debug, PartialEq)]
pub struct DipoleSpec {
    /// The law.
    pub law: DipoleLaw,
    /// The magnetometer (index in the [`Sensors`](crate::sensors::Sensors) set), on the root
    /// body.
    pub magnetometer: usize,
    /// The block's period (s): `every` times the magnetometer's.
    pub period: f64,
    /// It runs at every `every`-th magnetometer sample (the first included); >= 1.
    pub every: u64,
    /// The wheels whose momentum it dumps: rotor names (`wheel_<name>`); empty for B-dot.
    pub wheels: Vec<String>,
}

/// `−k (b − b_prev) / dt`: the B-dot dipole (A m²) from two readings `dt` apart.
pub fn bdot_dipole(gain: f64, b_prev: &Vector3<f64>, b: &Vector3<f64>, dt: f64) -> Vector3<f64> {
    -gain * (b - b_prev) / dt
}

/// `k (h × b) / |b|²`: the momentum-dumping dipole (A m²); zero where `b` is zero.
pub fn momentum_dipole(gain: f64, h: &Vector3<f64>, b: &Vector3<f64>) -> Vector3<f64> {
    let b2 = b.norm_squared();
    if b2 > 0.0 {
        gain * h.cross(b) / b2
    } else {
        Vector3::zeros()
    }
}

/// A magnetic block running: see the module documentation.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct DipoleBlock {
    spec: DipoleSpec,
    /// Each torquer's axis (root axes), zero for a torquer on another body (from `connect`).
    axes: Vec<Vector3<f64>>,
    /// The wheels' rotor indices, axes and axial inertias (from `connect`).
    rotors: Vec<(usize, Vector3<f64>, f64)>,
    /// The reading of the block's last sample (B-dot).
    last_b: Option<Vector3<f64>>,
    /// Magnetometer samples seen.
    seen: u64,
    /// The dipole held (body axes, A m²).
    dipole: Vector3<f64>,
    /// Each torquer's held command (A m²).
    held: Vec<f64>,
}

impl DipoleBlock {
    pub(crate) fn new(spec: DipoleSpec) -> Self {
        Self {
            spec,
            axes: Vec::new(),
            rotors: Vec::new(),
            last_b: None,
            seen: 0,
            dipole: Vector3::zeros(),
            held: Vec::new(),
        }
    }

    pub(crate) fn connect(&mut self, links: &Links) {
        self.axes = links
            .torquers
            .iter()
            .map(|t| {
                if t.body == 0 {
                    t.axis
                } else {
                    Vector3::zeros()
                }
            })
            .collect();
        self.held = vec![0.0; self.axes.len()];
        self.rotors = self
            .spec
            .wheels
            .iter()
            .filter_map(|name| {
                let j = links.rotors.iter().position(|r| &r.name == name)?;
                let r = &links.rotors[j];
                Some((j, r.nominal, r.axial))
            })
            .collect();
    }

    /// The wheels' momentum relative to the bus (N m s, body axes) at these rotor speeds.
    fn wheel_momentum(&self, rotor_rates: &[f64]) -> Vector3<f64> {
        self.rotors
            .iter()
            .map(|(j, a, i)| a * (i * rotor_rates[*j]))
            .sum()
    }

    /// The dipole of a sample on reading `b`, with the previous sample's reading
    /// `last_b` (B-dot), and the wheels' speeds (momentum dumping).
    fn law(
        &self,
        b: &Vector3<f64>,
        last_b: Option<&Vector3<f64>>,
        rotor_rates: &[f64],
    ) -> Vector3<f64> {
        match self.spec.law {
            DipoleLaw::Bdot { gain } => match last_b {
                Some(prev) => bdot_dipole(gain, prev, b, self.spec.period),
                None => Vector3::zeros(),
            },
            DipoleLaw::Momentum { gain } => {
                momentum_dipole(gain, &self.wheel_momentum(rotor_rates), b)
            }
        }
    }

    /// Whether magnetometer sample number `k` (from 0) is one of the block's.
    fn runs_at(&self, k: u64) -> bool {
        k.is_multiple_of(self.spec.every)
    }

    /// Runs after the sensors sampled at this instant: a new magnetometer sample that is one
    /// of the block's sets the dipole held.
    pub(crate) fn sample(&mut self, sensors: &[Sensor], rotor_rates: &[f64]) {
        let mag = &sensors[self.spec.magnetometer];
        let taken = mag.samples_taken();
        if taken <= self.seen {
            return;
        }
        self.seen = taken;
        if !self.runs_at(taken - 1) {
            return;
        }
        let b = vector(mag.last_reading());
        self.dipole = self.law(&b, self.last_b.as_ref(), rotor_rates);
        for (c, a) in self.held.iter_mut().zip(&self.axes) {
            *c = a.dot(&self.dipole);
        }
        self.last_b = Some(b);
    }

    /// Starts afresh from the magnetometer's samples so far: no previous reading, no
    /// dipole held.
    pub(crate) fn reset(&mut self, sensors: &[Sensor]) {
        self.seen = sensors[self.spec.magnetometer].samples_taken();
        self.last_b = None;
        self.dipole = Vector3::zeros();
        self.held.fill(0.0);
    }

    /// The dipole held (body axes, A m²).
    pub(crate) fn dipole(&self) -> Vector3<f64> {
        self.dipole
    }

    /// Adds the held commands to the torquers'.
    pub(crate) fn apply(&self, forces: &mut Forces) {
        for (c, h) in forces.dipole_command.iter_mut().zip(&self.held) {
            *c += h;
        }
    }
}

fn vector(r: &[f64]) -> Vector3<f64> {
    Vector3::new(r[0], r[1], r[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bdot_opposes_the_change_of_the_field() {
        let m = bdot_dipole(
            1e5,
            &Vector3::new(1e-5, 0.0, 0.0),
            &Vector3::new(1.2e-5, -1e-6, 0.0),
            0.5,
        );
        assert!((m - Vector3::new(-0.4, 0.2, 0.0)).norm() < 1e-12, "{m}");
    }

    #[test]
    fn momentum_dumping_torques_against_the_momentum_across_the_field() {
        let b = Vector3::new(2e-5, 0.0, 1e-5);
        let h = Vector3::new(0.3, -0.2, 0.5);
        let k = 1e-3;
        let m = momentum_dipole(k, &h, &b);
        // The couple m × B = −k h_⊥.
        let tau = m.cross(&b);
        let h_perp = h - b * (h.dot(&b) / b.norm_squared());
        assert!((tau + k * h_perp).norm() < 1e-15, "{tau} {h_perp}");
        assert_eq!(momentum_dipole(k, &h, &Vector3::zeros()), Vector3::zeros());
    }
}
