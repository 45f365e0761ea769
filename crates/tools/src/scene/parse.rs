//! The scene reader: the top level, the model and initial state, `armature`, the
//! `[effects.<name>]` sections through the registry, and `[sensors]` ([`super::sensors`]).
//! [`SceneText`] carries the scene's text and path so that every check names the file and
//! line.

use super::file::{ArmatureFile, ModelSource, SceneFile, StateSource};
use super::flexible::{Elastic, elastic_state, json_line, parse_state_json};
use super::{Clock, Scene};
use crate::scene_keys;
use satsim_integrate::Options;
use satsim_spacecraft::effects::section::reword;
use satsim_spacecraft::effects::{EffectSet, Registry, SceneText, Section};
use satsim_spacecraft::simulation::elastic_error_refusal;
use satsim_tree::error::Num;
use satsim_tree::flexible::FlexModel;
use satsim_tree::io::{
    Document, FileError, FrameMotion, ModelFile, flex_model_of, line_of, with_key,
};
use satsim_tree::{Model, State};

use serde::Deserialize;
use std::collections::BTreeMap;
use std::ops::{Deref, Range};
use std::path::{Path, PathBuf};
use toml::Spanned;

/// Where a flexible body's initial elastic state is written, for the errors about it: its
/// entry in the scene's `[initial] flexible` (the entry's span), or in a JSON state file
/// (the file and the entry's line).
enum ElasticAt {
    Scene(Range<usize>),
    File(PathBuf, Option<usize>),
}

/// The built-in effects whose `period` is a sample period: a clock each ([`Clock`]).
const SAMPLED: [&str; 3] = ["attitude_control", "hinge_control", "thrusters"];

/// Reads a scene's text into a [`Scene`].
pub(crate) struct Parser<'a> {
    src: SceneText<'a>,
    registry: &'a Registry,
    /// Whether to work out the warnings that cost time (the sampled laws' loops).
    advise: bool,
    /// Whether the scene is read to be integrated: a fixed step's checks (its stability on
    /// the scene's linear motions, its count against `max_steps`) are about the run, and a
    /// linearisation (`satsim modes`, `satsim linearize`) integrates nothing.
    integrates: bool,
}

impl<'a> Deref for Parser<'a> {
    type Target = SceneText<'a>;
    fn deref(&self) -> &SceneText<'a> {
        &self.src
    }
}

impl<'a> Parser<'a> {
    pub(crate) fn new(src: SceneText<'a>, registry: &'a Registry) -> Self {
        Self {
            src,
            registry,
            advise: true,
            integrates: true,
        }
    }

    /// Reads the scene to linearise it, not to integrate it: without the fixed step's checks.
    pub(crate) fn for_linearisation(mut self) -> Self {
        self.integrates = false;
        self
    }

    /// Leaves out the warnings that cost time to work out (whether each sampled law is
    /// stable at its period, `sampled_loop.rs`: a matrix exponential and a Schur
    /// decomposition, 8 M instructions on `fsw_mekf_pointing.toml`, 40 % of its read).
    pub(crate) fn without_advice(mut self) -> Self {
        self.advise = false;
        self
    }

    pub(super) fn scene(&self) -> Result<Scene, FileError> {
        let path = self.path().to_path_buf();
        if self.text().trim().is_empty() {
            return Err(FileError::Empty { path });
        }
        let located = |e: &toml::de::Error| e.span().map(|s| line_of(self.text(), s.start));
        // The text is parsed once, and the scene's keys and every effect's section read
        // from that tree (`Document`).
        let Some(doc) = self.document() else {
            let doc = Document::parse(self.text()).map_err(|e| FileError::Syntax {
                line: located(&e),
                message: e.message().trim_end().to_owned(),
                path,
            })?;
            return Parser {
                src: SceneText::parsed(&doc, self.path()),
                registry: self.registry,
                advise: self.advise,
                integrates: self.integrates,
            }
            .scene();
        };
        let file = SceneFile::deserialize(doc.deserializer()).map_err(|e| FileError::Schema {
            line: located(&e),
            message: with_key(&e, reword(e.message())),
            path: path.clone(),
        })?;
        let dir = self.path().parent().unwrap_or(Path::new("")).to_path_buf();

        // Model and initial state.
        let (model, flex) = match file.model.get_ref() {
            ModelSource::Path(p) => {
                let model_path = existing(self, &dir, p, file.model.span(), "model")?;
                let text =
                    std::fs::read_to_string(&model_path).map_err(|source| FileError::Read {
                        path: model_path.clone(),
                        source,
                    })?;
                let mf = satsim_tree::io::parse_model_file(&text, &model_path)?;
                built(&mf, &text, &model_path)?
            }
            ModelSource::Inline(m) => built(m, self.text(), self.path())?,
        };
        let (model, flex) = match &file.armature {
            Some(a) => self.armature(model, flex, a)?,
            None => (model, flex),
        };
        // The orbit first: a state relative to the orbital frame needs its frame at t = 0.
        let orbit = match &file.orbit {
            Some(o) => Some(self.orbit(o)?),
            None => None,
        };
        let orbital = orbit.as_ref().map(|o| {
            let at_start = o.state(&[o.r0.x, o.r0.y, o.r0.z, o.v0.x, o.v0.y, o.v0.z]);
            FrameMotion {
                attitude: at_start.orbital_frame(),
                angular_velocity: at_start.orbital_rate(),
            }
        });
        let mut warnings = Vec::new();
        let mut elastic = Elastic::rest(flex.as_ref());
        let mut elastic_at: Vec<(String, ElasticAt)> = Vec::new();
        let initial = match file.initial.as_ref().map(|s| (s.get_ref(), s.span())) {
            None => State::rest(&model),
            Some((StateSource::Path(p), span)) => {
                let state_path = existing(self, &dir, p, span, "initial")?;
                let text =
                    std::fs::read_to_string(&state_path).map_err(|source| FileError::Read {
                        path: state_path.clone(),
                        source,
                    })?;
                let (sf, given) = parse_state_json(&text, &state_path)?;
                elastic = elastic_state(
                    flex.as_ref(),
                    &model,
                    given.iter().map(|(b, e)| (b.as_str(), e)),
                )
                .map_err(|(k, message)| FileError::Schema {
                    path: state_path.clone(),
                    line: json_line(&text, &given[k].0),
                    message,
                })?;
                elastic_at = given
                    .iter()
                    .map(|(b, _)| {
                        let line = json_line(&text, b);
                        (b.clone(), ElasticAt::File(state_path.clone(), line))
                    })
                    .collect();
                warnings.extend(
                    sf.warnings()
                        .into_iter()
                        .map(|w| format!("{}: {w}", state_path.display())),
                );
                sf.resolve_in_frame(&model, orbital.as_ref())
                    .map_err(|e| e.in_file(&state_path))?
            }
            Some((StateSource::Inline(s, given), span)) => {
                elastic = elastic_state(
                    flex.as_ref(),
                    &model,
                    given.iter().map(|(b, e)| (b.as_str(), e.get_ref())),
                )
                .map_err(|(k, m)| self.error(Some(given[k].1.span()), format!("initial.{m}")))?;
                elastic_at = given
                    .iter()
                    .map(|(b, e)| (b.clone(), ElasticAt::Scene(e.span())))
                    .collect();
                warnings.extend(s.warnings().into_iter().map(|w| {
                    format!(
                        "{}:{}: initial.{w}",
                        self.path().display(),
                        line_of(self.text(), span.start)
                    )
                }));
                s.resolve_in_frame(&model, orbital.as_ref()).map_err(|e| {
                    self.error(Some(span), format!("initial.{}: {}", e.field, e.message))
                })?
            }
        };

        let duration = self.positive(&file.duration, "duration")?;
        let epoch = match &file.epoch {
            Some(e) => {
                let at_line = |m: String| self.error(Some(e.span()), format!("`epoch`: {m}"));
                let epoch = satsim_environment::parse_epoch(e.get_ref()).map_err(at_line)?;
                satsim_environment::epoch::check_span(epoch, duration).map_err(at_line)?;
                Some(epoch)
            }
            None => None,
        };
        let options = self.integrator(file.integrator.as_ref())?;
        if self.integrates {
            self.check_step_count(&file, &options, duration)?;
        }
        let elastic_error = match file
            .integrator
            .as_ref()
            .and_then(|i| i.get_ref().elastic_error.as_ref())
        {
            Some(e) if flex.is_none() => {
                return Err(self.error(
                    Some(e.span()),
                    "`integrator.elastic_error`: the model has no flexible bodies",
                ));
            }
            // Refused where it is written, as a run would refuse it.
            Some(e) if !*e.get_ref() && options.method.is_explicit_adaptive() => {
                return Err(self.error(Some(e.span()), elastic_error_refusal(options.method)));
            }
            Some(e) => *e.get_ref(),
            None => true,
        };
        if let Some(f) = flex.as_ref() {
            self.check_initial_modes(&file, f, &initial, &elastic, &elastic_at)?;
        }
        let (every, plots, view, energy_budget) = match &file.output {
            None => (duration / 100.0, true, true, true),
            Some(o) => {
                let o = o.get_ref();
                let every = match &o.every {
                    Some(e) => self.positive(e, "output.every")?,
                    None => duration / 100.0,
                };
                (
                    every,
                    o.plots.unwrap_or(true),
                    o.view.unwrap_or(true),
                    o.energy_budget.unwrap_or(true),
                )
            }
        };
        if let Some(w) = self
            .step_warning(&file, &options, duration, every)
            .filter(|_| self.integrates)
        {
            warnings.push(w);
        }
        let mut effects = EffectSet::default();
        if let (Some(mut o), Some(f)) = (orbit, &file.orbit) {
            self.orbit_epoch(f, &mut o, epoch)?;
            effects.insert(o);
        }
        let mut clocks = Vec::new();
        if let Some(e) = &file.effects {
            self.effects(e, &model, epoch, &mut effects, &mut warnings)?;
            clocks = self.clocks(&effects)?;
        }
        if let Some(s) = &file.sensors
            && let Some(set) = super::sensors::read(self, s, &model, epoch, &effects)?
        {
            effects.insert(set);
            clocks.extend(super::sensors::clocks(self, s));
        }
        let mut wheel_laws = Vec::new();
        if let Some(f) = &file.fsw {
            wheel_laws = super::fsw::read(
                self,
                f,
                &model,
                epoch,
                &mut effects,
                &mut clocks,
                &mut warnings,
            )?;
        }
        super::faults::read(self, &file.faults, &mut effects)?;
        if let Some(f) = flex.as_ref() {
            warnings.extend(super::flexible::unloaded_modes(f, &effects));
        }
        let sampled = if self.advise {
            super::sampled_loop::SampledLaws::in_scene(&effects, wheel_laws)
        } else {
            super::sampled_loop::SampledLaws::default()
        };
        // The tree for the checks of the linear motions. Where it cannot be made, a fixed
        // step's check is an error, as before; the sampled laws' warnings are left out, and
        // the simulation's set-up says what is wrong.
        let fixed_step = options.fixed_step.filter(|_| self.integrates);
        let tree = (fixed_step.is_some() || !sampled.is_empty())
            .then(|| super::step_limit::integrated_tree(&model, flex.as_ref(), &effects))
            .transpose()
            .or_else(|e| match fixed_step {
                Some(_) => Err(self.error(None, e.to_string())),
                None => Ok(None),
            })?;
        if let Some((tree, n_rotors)) = tree {
            let q = super::step_limit::integrated_q(&initial.q, n_rotors, &elastic.eta);
            let gains = super::step_limit::HingeGains::of(&effects, model.n_hinges());
            warnings.extend(sampled.warnings(self, &file, &model, &tree, &q, &gains));
            if let Some(h) = fixed_step {
                let v = super::step_limit::integrated_v(
                    &initial.v,
                    &effects,
                    n_rotors,
                    &elastic.etadot,
                );
                self.fixed_step_checked(&file, &tree, (&q, &v), &gains, h, duration, every)?;
            }
        }
        let scene = Scene {
            path,
            model,
            flexible: flex,
            initial,
            elastic,
            duration,
            epoch,
            options,
            elastic_error,
            every,
            plots,
            view,
            energy_budget,
            effects,
            clocks,
            warnings,
        };
        // Build once to surface any remaining setup error with the scene's name.
        let sim = scene
            .simulation()
            .map_err(|e| self.error(None, e.to_string()))?;
        if let Some(s) = &file.sensors {
            super::sensors::check_columns(self, s, &sim.columns())?;
        }
        Ok(scene)
    }

    /// The dynamics must resolve every mode at the initial state. Undeformed, a flexible
    /// body far lighter than the bodies it carries fails there (the model's own check is at
    /// its neutral configuration, and round-off's sign depends on the configuration): an
    /// error at the scene's `model` line, naming the mode. Deformed, the deformed inertia
    /// depends on `η` (to first and second order), and an `eta` large enough makes it no
    /// body's: an error at the body's entry (`elastic_at`: in the scene, or in its state
    /// file) naming the key, the body and the mode to blame
    /// ([`super::flexible::blamed_mode`]) and how far the deformation bends the body. Either
    /// way the run would end at its first step in "mass matrix is not positive definite".
    fn check_initial_modes(
        &self,
        file: &SceneFile,
        flex: &FlexModel,
        initial: &State,
        elastic: &Elastic,
        elastic_at: &[(String, ElasticAt)],
    ) -> Result<(), FileError> {
        use super::flexible::{blamed_mode, mass_positive};
        use satsim_tree::flexible::UNRESOLVED;
        let name = |i: usize| flex.rigid().bodies()[i].name().to_owned();
        let rest: Vec<f64> = initial
            .q
            .iter()
            .copied()
            .chain(elastic.eta.iter().map(|_| 0.0))
            .collect();
        if let Some((i, mode, pivot)) = flex.unresolved_mode(&rest) {
            return Err(self.error(
                Some(file.model.span()),
                format!(
                    "`model`: at the initial state the dynamics cannot resolve body `{}`'s \
                     mode {mode} (its articulated pivot is {}, where the mass matrix makes it \
                     positive): {UNRESOLVED}",
                    name(i),
                    Num(pivot)
                ),
            ));
        }
        if let Some((i, mode, ratio)) = flex.magnified_mode(&rest) {
            return Err(self.error(
                Some(file.model.span()),
                format!(
                    "`model`: at the initial state the dynamics cannot resolve body `{}`'s \
                     mode {mode} (it carries {:.3e} times its own modal mass, past the {} at \
                     which round-off of that inertia reaches a millionth of the mode's own): \
                     {UNRESOLVED}",
                    name(i),
                    ratio,
                    Num(satsim_tree::flexible::MAGNIFICATION_LIMIT)
                ),
            ));
        }
        if elastic.eta.iter().all(|e| *e == 0.0) {
            return Ok(());
        }
        let q: Vec<f64> = initial.q.iter().chain(&elastic.eta).copied().collect();
        // Other failures (a non-finite value) are the run's to report.
        if mass_positive(flex, &q) != Some(false) {
            return Ok(());
        }
        let (i, mode, pivot) = blamed_mode(flex, &initial.q, &elastic.eta);
        let body = name(i);
        let value = elastic.eta[flex.elastic_offset(i) + mode - 1];
        let pivot = pivot
            .map(|p| format!(", pivot {}", Num(p)))
            .unwrap_or_default();
        let bent = flex
            .deflection_of(i, &elastic.eta)
            .map(|d| {
                let (offset, length, pct) = (d.offset.abs(), Num(d.length), 100.0 * d.fraction());
                let moved = match d.point {
                    None => format!(
                        "its tip {offset:.4} m off its axis, {pct:.0} % of its {length} m length"
                    ),
                    Some(k) => format!(
                        "its node `{}` {offset:.4} m, {pct:.0} % of its {length} m from the body's frame",
                        flex.watch_points(i)[k].name
                    ),
                };
                format!(": the deformation moves {moved}, where a modal model holds a few per cent")
            })
            .unwrap_or_default();
        let message = format!(
            "the initial deformation makes the mass matrix not positive definite at body \
             `{body}`'s mode {mode} (eta = {}{pivot}){bent}; with `stiffening` the deformed \
             inertia depends on `eta`, and one this large takes it out of any body's: start \
             closer to rest",
            Num(value)
        );
        Err(match elastic_at.iter().find(|(b, _)| *b == body) {
            Some((_, ElasticAt::Scene(span))) => self.error(
                Some(span.clone()),
                format!("initial.flexible.{body}.eta: {message}"),
            ),
            Some((_, ElasticAt::File(path, line))) => FileError::Schema {
                path: path.clone(),
                line: *line,
                message: format!("flexible.{body}.eta: {message}"),
            },
            // Only a body given a deformation can be blamed for it.
            None => self.error(
                file.initial.as_ref().map(|s| s.span()),
                format!("initial.flexible.{body}.eta: {message}"),
            ),
        })
    }

    /// [`Self::check_rk4_step`] for a fixed step `h`, cut to the output interval and the
    /// duration as the run cuts it (`step_warning`): the longest step taken is what must be
    /// stable.
    #[allow(clippy::too_many_arguments)]
    fn fixed_step_checked(
        &self,
        file: &SceneFile,
        tree: &FlexModel,
        state: (&[f64], &[f64]),
        gains: &super::step_limit::HingeGains,
        h: f64,
        duration: f64,
        every: f64,
    ) -> Result<(), FileError> {
        let cut = if h > duration.min(every) {
            Some(if every <= duration {
                ("output.every", every)
            } else {
                ("duration", duration)
            })
        } else {
            None
        };
        self.check_rk4_step(file, tree, state, gains, h, cut)
    }

    /// A fixed RK4 step must keep the scene's linear motions at the initial state `(q, v)`
    /// (the flexible bodies' modes, stiffened by the initial motion where they have
    /// `stiffening`, the hinges on their springs, dampers and continuous controllers) within
    /// RK4's stability region, damping included ([`super::step_limit::rk4_limit`]): beyond it
    /// they grow without bound, so it is an error at `integrator.step` naming what limits the
    /// step, its frequency and damping, and the largest stable step. `cut` is what the steps
    /// are cut to, where they are (the output interval or the duration, and its value): the
    /// longest step taken is what must be stable.
    fn check_rk4_step(
        &self,
        file: &SceneFile,
        flex: &FlexModel,
        (q, v): (&[f64], &[f64]),
        gains: &super::step_limit::HingeGains,
        h: f64,
        cut: Option<(&str, f64)>,
    ) -> Result<(), FileError> {
        use super::step_limit::{Limiting, rk4_limit};
        let Some(limit) = rk4_limit(flex, q, v, gains) else {
            return Ok(());
        };
        let taken = cut.map_or(h, |(_, to)| to);
        if taken <= limit.step {
            return Ok(());
        }
        let cut = cut
            .map(|(by, to)| format!(" (cut to `{by}` = {} s)", Num(to)))
            .unwrap_or_default();
        let span = file
            .integrator
            .as_ref()
            .and_then(|i| i.get_ref().step.as_ref())
            .map(|s| s.span());
        let (w, l) = (limit.omega, limit.lambda);
        // A step to suggest: nine tenths of the limit, two significant digits, rounded down.
        let digits = 10f64.powf((0.9 * limit.step).log10().floor() - 1.0);
        let suggested = (0.9 * limit.step / digits).floor() * digits;
        // Fixed-point below a million, in exponent form above (a rate of 1e15 /s is not
        // written with sixteen digits).
        let fixed = |x: f64, digits: usize| {
            if x.abs() < 1e6 {
                format!("{x:.digits$}")
            } else {
                format!("{x:.digits$e}")
            }
        };
        let eigenvalue = if l.im > 0.0 {
            format!("{} ± {}i 1/s", fixed(l.re, 4), fixed(l.im, 4))
        } else {
            format!("{} 1/s", fixed(l.re, 4))
        };
        let mut what = limit.what(flex);
        // The initial motion's part in the stiffness, where it shows in the frequency.
        let g = limit.geometric;
        if matches!(limit.by, Limiting::Mode(_)) && g.abs() >= 1e-3 {
            let how = if g > 0.0 { "stiffened" } else { "softened" };
            what += &format!(
                ", {how} by the initial motion, whose geometric stiffness is {:.1} % of the mode's",
                100.0 * g
            );
        }
        let (with, motion) = match limit.by {
            Limiting::Mode(_) => ("the flexible modes", "mode"),
            Limiting::Hinge(_) if limit.on_rotor(flex) => {
                ("the wheels' viscous friction", "motion")
            }
            Limiting::Hinge(_) => ("the hinges' springs, dampers and controllers", "motion"),
            Limiting::Attitude => ("the attitude controller's gains", "motion"),
        };
        let character = if limit.by == Limiting::Attitude {
            let g = gains.attitude.as_ref().map_or_else(String::new, |a| {
                format!(
                    " (kp = {} N m/rad, kd = {} N m s/rad)",
                    Num(a.kp),
                    Num(a.kd)
                )
            });
            if l.im > 0.0 {
                format!(
                    "is an oscillation on the controller's gains{g} at {:.4} Hz (ω = {w:.4} rad/s) with damping ratio {:.3}",
                    w / std::f64::consts::TAU,
                    limit.zeta
                )
            } else {
                format!("is a decay on the controller's gains{g}, overdamped")
            }
        } else if w > 0.0 {
            format!(
                "is at {:.4} Hz (ω = {w:.4} rad/s) with damping ratio {:.3}",
                w / std::f64::consts::TAU,
                limit.zeta
            )
        } else {
            "has no stiffness, only damping".to_owned()
        };
        Err(self.error(
            span,
            format!(
                "`integrator.step` = {} s{cut} is too long for rk4 with {with}: the {motion} that limits it (mostly {what}) {character}, eigenvalue {eigenvalue}, and rk4 is stable on it only for steps up to {:.4e} s (|λ| × step within rk4's stability region: <= 2√2 = 2.83 undamped, <= 2.785 for a real λ; here |λ| × step = {}): set `step` at most {suggested:.1e} s, or use an adaptive method (`method = \"radau5\"`, implicit, steps over the {motion})",
                Num(h),
                limit.step,
                fixed(l.norm() * taken, 3),
            ),
        ))
    }

    /// A fixed step that takes more than `integrator.max_steps` steps over the duration fails
    /// for certain: an error at `integrator.step` naming both numbers and the shortest step
    /// that fits, before the run rather than after `max_steps` steps.
    fn check_step_count(
        &self,
        file: &SceneFile,
        options: &Options,
        duration: f64,
    ) -> Result<(), FileError> {
        let Some(h) = options.fixed_step else {
            return Ok(());
        };
        let steps = duration / h;
        let max = options.max_steps;
        // The slack: the step suggested below, `duration / max`, may round to a hair more.
        if steps <= max as f64 * (1.0 + 1e-9) {
            return Ok(());
        }
        let span = file
            .integrator
            .as_ref()
            .and_then(|i| i.get_ref().step.as_ref())
            .map(|s| s.span());
        Err(self.error(
            span,
            format!(
                "`integrator.step` = {} s over `duration` = {} s makes {} steps, more than `integrator.max_steps` = {max}: set `step` at least {} s, or raise `max_steps`",
                Num(h),
                Num(duration),
                if steps < 1e15 {
                    format!("{}", steps.ceil())
                } else {
                    format!("{steps:.3e}")
                },
                Num(duration / max as f64)
            ),
        ))
    }

    /// A fixed step longer than the duration or the output interval is silently cut to it
    /// (steps land on output times), so the run is not at the step the user chose: say so,
    /// naming the keys, at `integrator.step`'s line.
    fn step_warning(
        &self,
        file: &SceneFile,
        options: &Options,
        duration: f64,
        every: f64,
    ) -> Option<String> {
        let h = options.fixed_step?;
        let (other, limit) = if h > duration {
            ("duration", duration)
        } else if h > every {
            ("output.every", every)
        } else {
            return None;
        };
        let line = file
            .integrator
            .as_ref()
            .and_then(|i| i.get_ref().step.as_ref())
            .map(|s| format!(":{}", line_of(self.text(), s.span().start)))
            .unwrap_or_default();
        Some(format!(
            "{}{line}: `integrator.step` ({h} s) is longer than `{other}` ({limit} s): every step is cut to {limit} s, so the accuracy is that of a {limit} s step; set `integrator.step` at most {limit}",
            self.path().display()
        ))
    }

    /// Reads every `[effects.<name>]` section with the registry's effect of that name, in
    /// the registry's order, then checks each against the others (at its section's line).
    fn effects(
        &self,
        sections: &Spanned<BTreeMap<String, Spanned<toml::Value>>>,
        model: &Model,
        epoch: Option<satsim_environment::Epoch>,
        out: &mut EffectSet,
        warnings: &mut Vec<String>,
    ) -> Result<(), FileError> {
        // Unknown sections first, in file order.
        let mut written: Vec<(&String, &Spanned<toml::Value>)> =
            sections.get_ref().iter().collect();
        written.sort_by_key(|(_, v)| v.span().start);
        if let Some((name, v)) = written.iter().find(|(n, _)| !self.registry.contains(n)) {
            return Err(self.error(
                Some(v.span()),
                format!(
                    "unknown key `{name}` in [effects]: no effect of that name is registered (known: {}; \
                     an effect of your own is registered by the program that reads the scene, \
                     `Registry::register`, as `cargo run --example custom_effect` does)",
                    self.registry.names().join(", ")
                ),
            ));
        }
        let mut spans = Vec::new();
        for name in self.registry.names() {
            let Some(raw) = sections.get_ref().get(name) else {
                continue;
            };
            let enabled = raw.get_ref().get("enabled").and_then(|v| v.as_bool()) != Some(false);
            let section =
                Section::new(self.src, name, raw.span(), model, enabled).with_epoch(epoch);
            let read = self.registry.read(&section)?;
            warnings.extend(section.take_warnings());
            if let Some(e) = read {
                spans.push((name, raw.span()));
                out.insert_boxed(e);
            }
        }
        for (name, span) in spans {
            let e = out.find(name).expect("an effect read above");
            self.registry
                .check(e, out)
                .map_err(|m| self.error(Some(span), m))?;
        }
        Ok(())
    }

    /// The clocks of the enabled effects that sample with a `period` (their sections'
    /// `period` key, in this order).
    fn clocks(&self, effects: &EffectSet) -> Result<Vec<Clock>, FileError> {
        /// A section's `period`, its other keys left to the effect.
        #[derive(Deserialize)]
        struct Period {
            #[serde(default)]
            period: Option<Spanned<f64>>,
        }
        let mut out = Vec::new();
        for name in SAMPLED {
            if !effects.contains(name) {
                continue;
            }
            if let Some(p) = self
                .effect_section::<Period>(name)?
                .and_then(|s| s.into_inner().period)
            {
                out.push(Clock {
                    what: format!("`effects.{name}`"),
                    line: Some(line_of(self.text(), p.span().start)),
                    period: *p.get_ref(),
                });
            }
        }
        Ok(out)
    }

    /// The model (and its flexible bodies) with the scene's `armature` on its hinges.
    fn armature(
        &self,
        model: Model,
        flex: Option<FlexModel>,
        a: &Spanned<ArmatureFile>,
    ) -> Result<(Model, Option<FlexModel>), FileError> {
        let n = model.n_hinges();
        let values = match a.get_ref() {
            ArmatureFile::All(v) => vec![*v; n],
            ArmatureFile::PerHinge(v) if v.len() == n => v.clone(),
            ArmatureFile::PerHinge(v) => {
                return Err(self.error(
                    Some(a.span()),
                    format!(
                        "`armature`: expected {n} entries (one per hinge, file order), got {}",
                        v.len()
                    ),
                ));
            }
        };
        if let Some(v) = values.iter().find(|v| !(**v >= 0.0 && v.is_finite())) {
            return Err(self.error(
                Some(a.span()),
                format!("`armature` must be finite numbers >= 0 (kg m²), got {v}"),
            ));
        }
        // A built model never changes: the armature goes through the builder (which also
        // stops treating a rotor with armature as a gyrostat).
        let mut builder = model.to_builder();
        for (hinge, v) in builder.hinges_mut().iter_mut().zip(values) {
            hinge.armature = v;
        }
        let model = builder
            .build()
            .map_err(|e| self.error(Some(a.span()), format!("`armature`: {e}")))?;
        let flex = match flex {
            // The same modes (and per-mode damping) on the tree with the armature.
            Some(f) => Some(
                f.with_rigid(model.clone())
                    .map_err(|e| self.error(Some(a.span()), format!("`armature`: {e}")))?,
            ),
            None => None,
        };
        Ok((model, flex))
    }
}

/// The rigid model of a model file (deserialised from `text`, at `origin`) and, when a body
/// has `[body.flexible]`, its flexible model (whose rigid tree the model is). A rigid file is
/// built as `read_model` builds it.
fn built(
    file: &ModelFile,
    text: &str,
    origin: &Path,
) -> Result<(Model, Option<FlexModel>), FileError> {
    if file.body.iter().all(|b| b.get_ref().flexible.is_none()) {
        let model = file.build().map_err(|e| e.in_file(text, origin))?;
        return Ok((model, None));
    }
    let flex = flex_model_of(file, text, origin)?;
    Ok((flex.rigid().clone(), Some(flex)))
}

/// `dir/written`, which must exist: else an error at the scene's line of `key`.
fn existing(
    text: &SceneText,
    dir: &Path,
    written: &str,
    span: Range<usize>,
    key: &str,
) -> Result<PathBuf, FileError> {
    let file = dir.join(written);
    if file.is_file() {
        Ok(file)
    } else {
        Err(scene_keys::missing_source(
            text.path(),
            Some(line_of(text.text(), span.start)),
            key,
            written,
            &file,
        ))
    }
}
