//! What to measure: [`Sweep`] (methods, tolerances, steps, references) and its points'
//! [`Setting`]s.

use crate::scene::Scene;
use satsim_integrate::{Method, Options};

/// One setting of one method: a tolerance (adaptive methods) or a step (RK4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Setting {
    /// `rtol = tol`, `atol = tol * atol_scale`.
    Tolerance(f64),
    /// Fixed step (s).
    Step(f64),
}

impl Setting {
    /// `tol=1e-6` or `h=0.01`.
    pub fn label(&self) -> String {
        match self {
            Setting::Tolerance(t) => format!("tol={t:e}"),
            Setting::Step(h) => format!("h={h}"),
        }
    }
}

/// What to run.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    /// Methods, in the order they are reported.
    pub methods: Vec<Method>,
    /// Tolerances of the adaptive methods (`rtol`; `atol = rtol * atol_scale`).
    pub tolerances: Vec<f64>,
    /// Steps of the fixed-step RK4 (s).
    pub rk4_steps: Vec<f64>,
    /// `atol / rtol`.
    pub atol_scale: f64,
    /// Timed runs per point; the minimum wall time is reported.
    pub repeats: usize,
    /// The reference for every method but itself: `(method, tolerance)`.
    pub reference: (Method, f64),
    /// The reference for [`Sweep::reference`]'s own method.
    pub cross_reference: (Method, f64),
}

impl Sweep {
    /// The full sweep: tolerances `1e-3 … 1e-12` (one per decade), RK4 steps
    /// `every · 2^-k` for `k = 3 … 11` (steps that divide the output interval, so no step is
    /// shortened), 3 repeats, references at `1e-13`.
    pub fn full(scene: &Scene) -> Self {
        Self {
            methods: Method::ALL.to_vec(),
            tolerances: (3..=12).map(|k| 10f64.powi(-k)).collect(),
            rk4_steps: (3..=11).map(|k| scene.every * 0.5f64.powi(k)).collect(),
            atol_scale: 1.0,
            repeats: 3,
            reference: (Method::Dop853, 1e-13),
            cross_reference: (Method::Dp54, 1e-13),
        }
    }

    /// A small sweep for tests and smoke runs: two tolerances, two RK4 steps, one repeat,
    /// references at `1e-12`.
    pub fn quick(scene: &Scene) -> Self {
        Self {
            tolerances: vec![1e-4, 1e-7],
            rk4_steps: vec![scene.every / 8.0, scene.every / 32.0],
            repeats: 1,
            reference: (Method::Dop853, 1e-12),
            cross_reference: (Method::Dp54, 1e-12),
            ..Self::full(scene)
        }
    }

    /// Every `(method, setting)` of the sweep, in report order.
    pub fn settings(&self) -> Vec<(Method, Setting)> {
        let mut out = Vec::new();
        for &m in &self.methods {
            if m == Method::Rk4 {
                out.extend(self.rk4_steps.iter().map(|&h| (m, Setting::Step(h))));
            } else {
                out.extend(self.tolerances.iter().map(|&t| (m, Setting::Tolerance(t))));
            }
        }
        out
    }

    /// The integrator options of one setting, from the scene's (its step limits and
    /// `max_steps` are kept; its first step is not).
    pub fn options(&self, scene: &Scene, method: Method, setting: Setting) -> Options {
        let mut o = scene.options.clone();
        o.method = method;
        o.h0 = None;
        o.fixed_step = None;
        match setting {
            Setting::Tolerance(t) => o.with_tolerances(t, t * self.atol_scale),
            Setting::Step(h) => o.with_fixed_step(h),
        }
    }
}
