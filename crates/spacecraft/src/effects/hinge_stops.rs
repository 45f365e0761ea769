//! Hinge stops: a hinge reaching a stop angle either latches (a plastic impact, then the
//! hinge is locked for the rest of the run) or rebounds with a coefficient of restitution.
//!
//! The impact instant is located by the integrator's event handling (zero crossing of
//! `φ − lower` or `upper − φ`, falling). At the impact the simulation applies the impulse
//! `λ` between the hinge's two bodies that gives the hinge the wanted rate: `Δv = M⁻¹ e_k λ`
//! over the unlocked degrees of freedom, which conserves the system's linear and angular
//! momentum (the impulse is internal). Latch: wanted rate 0, then the hinge is locked (the
//! hybrid articulated-body algorithm makes it transmit rigidly). Rebound: wanted rate
//! `−e φ̇`; a rebound slower than `min_rebound_rate` latches instead, so that a hinge pressed
//! against its stop comes to rest rather than bouncing forever (Zeno).

use super::{
    Context, EVENT_TEXT, Effect, EventReads, Forces, Request, SceneEffect, Section, set_text,
};
use satsim_integrate::{EventAction, EventDirection, SystemError};
use satsim_tree::io::FileError;
use serde::Deserialize;
use toml::Spanned;

/// What a stop does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StopAction {
    /// Plastic impact, then locked.
    Latch,
    /// Rebound with restitution `e` in `[0, 1]`.
    Rebound {
        /// Coefficient of restitution.
        restitution: f64,
    },
}

/// The stops of one hinge.
#[derive(Clone, Debug, PartialEq)]
pub struct HingeStop {
    /// The hinge (model file order).
    pub hinge: usize,
    /// Lower stop angle (rad), if any.
    pub lower: Option<f64>,
    /// Upper stop angle (rad), if any.
    pub upper: Option<f64>,
    /// What happens at the stop.
    pub action: StopAction,
    /// A rebound slower than this latches (rad/s).
    pub min_rebound_rate: f64,
}

/// The hinge-stops effect.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct HingeStops {
    /// The stops.
    pub stops: Vec<HingeStop>,
    latched: Vec<bool>,
    last: String,
    /// Number of impacts so far.
    pub impacts: usize,
}

impl HingeStops {
    /// The effect for these stops.
    pub fn new(stops: Vec<HingeStop>) -> Self {
        let n = stops.len();
        Self {
            stops,
            latched: vec![false; n],
            last: String::with_capacity(EVENT_TEXT),
            impacts: 0,
        }
    }
    /// Whether stop `s` has latched.
    pub fn is_latched(&self, s: usize) -> bool {
        self.latched[s]
    }
}

impl Effect for HingeStops {
    fn name(&self) -> &str {
        "hinge_stops"
    }
    fn apply(
        &mut self,
        _ctx: &Context,
        _forces: &mut Forces,
        _own: &[f64],
        _own_dot: &mut [f64],
    ) -> Result<(), SystemError> {
        Ok(())
    }
    fn start(
        &mut self,
        ctx: &Context,
        _forces: &Forces,
        _own: &[f64],
        requests: &mut Vec<Request>,
    ) -> Result<(), SystemError> {
        // Room for the events' descriptions (a clone keeps none): no allocation at an event.
        self.last.reserve(EVENT_TEXT);
        for (s, stop) in self.stops.iter().enumerate() {
            let phi = ctx.angles[stop.hinge];
            let name = &ctx.model.hinge_names()[stop.hinge];
            let below = stop.lower.is_some_and(|l| phi < l);
            let above = stop.upper.is_some_and(|u| phi > u);
            if below || above {
                return Err(SystemError::new(format!(
                    "hinge_stops: hinge `{name}` starts at {phi} rad, beyond its stop"
                )));
            }
            let on = stop.lower == Some(phi) || stop.upper == Some(phi);
            if on && stop.action == StopAction::Latch {
                self.latched[s] = true;
                requests.push(Request::Lock(stop.hinge));
            }
        }
        Ok(())
    }
    fn n_events(&self) -> usize {
        2 * self.stops.len()
    }
    fn events(&self, ctx: &Context, _forces: &Forces, _own: &[f64], g: &mut [f64]) {
        for (s, stop) in self.stops.iter().enumerate() {
            let phi = ctx.angles[stop.hinge];
            let free = !self.latched[s] && !ctx.locked[stop.hinge];
            g[2 * s] = match stop.lower {
                Some(l) if free => phi - l,
                _ => 1.0,
            };
            g[2 * s + 1] = match stop.upper {
                Some(u) if free => u - phi,
                _ => 1.0,
            };
        }
    }
    /// The angles, the locked flags and the latches: nothing beyond the state.
    fn event_reads(&self) -> EventReads {
        EventReads::STATE
    }
    fn event_direction(&self, _k: usize) -> EventDirection {
        EventDirection::Falling
    }
    fn on_event(
        &mut self,
        k: usize,
        ctx: &Context,
        _forces: &Forces,
        _own: &mut [f64],
        requests: &mut Vec<Request>,
    ) -> EventAction {
        let s = k / 2;
        let stop = &self.stops[s];
        let h = stop.hinge;
        let rate = ctx.rates[h];
        let approaching = if k.is_multiple_of(2) {
            rate < 0.0
        } else {
            rate > 0.0
        };
        if !approaching {
            return EventAction::Continue;
        }
        self.impacts += 1;
        let name = &ctx.model.hinge_names()[h];
        let side = if k.is_multiple_of(2) {
            "lower"
        } else {
            "upper"
        };
        match stop.action {
            StopAction::Latch => {
                self.latched[s] = true;
                requests.push(Request::Lock(h));
                set_text(
                    &mut self.last,
                    format_args!("hinge `{name}` latched at its {side} stop ({rate:.4} rad/s)"),
                );
            }
            StopAction::Rebound { restitution } => {
                let after = -restitution * rate;
                if after.abs() < stop.min_rebound_rate {
                    self.latched[s] = true;
                    requests.push(Request::Lock(h));
                    set_text(
                        &mut self.last,
                        format_args!("hinge `{name}` came to rest at its {side} stop"),
                    );
                } else {
                    requests.push(Request::SetRate {
                        hinge: h,
                        rate: after,
                    });
                    set_text(
                        &mut self.last,
                        format_args!(
                            "hinge `{name}` rebounded at its {side} stop ({rate:.4} -> {after:.4} rad/s)"
                        ),
                    );
                }
            }
        }
        EventAction::Reset
    }
    fn describe_event(&self, _k: usize) -> String {
        self.last.clone()
    }
    fn describe_event_into(&self, _k: usize, out: &mut String) {
        out.push_str(&self.last);
    }
}

/// `[effects.hinge_stops]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HingeStopsFile {
    /// `[[effects.hinge_stops.stop]]`.
    #[serde(default)]
    pub stop: Vec<Spanned<StopFile>>,
    /// Off without removing the table (default true).
    #[serde(default)]
    pub enabled: Option<bool>,
}

/// One `[[effects.hinge_stops.stop]]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StopFile {
    /// The hinge's name.
    pub hinge: Spanned<String>,
    /// Lower stop (rad).
    #[serde(default)]
    pub lower: Option<f64>,
    /// Upper stop (rad).
    #[serde(default)]
    pub upper: Option<f64>,
    /// `"latch"` (default) or `"rebound"`.
    #[serde(default)]
    pub action: Option<Spanned<String>>,
    /// Coefficient of restitution of a rebound, in [0, 1] (default 0.5).
    #[serde(default)]
    pub restitution: Option<Spanned<f64>>,
    /// A rebound slower than this latches (rad/s, default 1e-3).
    #[serde(default)]
    pub min_rebound_rate: Option<f64>,
}

impl SceneEffect for HingeStops {
    const SECTION: &'static str = "hinge_stops";
    type File = HingeStopsFile;
    fn from_section(s: HingeStopsFile, section: &Section) -> Result<Self, FileError> {
        let mut stops = Vec::new();
        for st in &s.stop {
            let sf = st.get_ref();
            let hinge = section.hinge_index(&sf.hinge)?;
            section.check_numbers(
                st.span(),
                "effects.hinge_stops.stop.",
                &[
                    ("lower", sf.lower, false),
                    ("upper", sf.upper, false),
                    ("min_rebound_rate", sf.min_rebound_rate, true),
                ],
            )?;
            for (key, v) in [("lower", sf.lower), ("upper", sf.upper)] {
                if let Some(v) = v {
                    section.check_angle(st.span(), &format!("effects.hinge_stops.stop.{key}"), v);
                }
            }
            if sf.lower.is_none() && sf.upper.is_none() {
                return Err(section.error(Some(st.span()), "a stop needs `lower`, `upper` or both"));
            }
            if let (Some(l), Some(u)) = (sf.lower, sf.upper)
                && l >= u
            {
                return Err(section.error(Some(st.span()), "`lower` must be below `upper`"));
            }
            let action = match sf.action.as_ref().map(|a| (a.get_ref().as_str(), a.span())) {
                None | Some(("latch", _)) => StopAction::Latch,
                Some(("rebound", _)) => {
                    let e = match &sf.restitution {
                        Some(e) => {
                            let v = section.non_negative(e, "restitution")?;
                            if v > 1.0 {
                                return Err(section
                                    .error(Some(e.span()), "`restitution` must be in [0, 1]"));
                            }
                            v
                        }
                        None => 0.5,
                    };
                    StopAction::Rebound { restitution: e }
                }
                Some((other, sp)) => {
                    return Err(section.error(
                        Some(sp),
                        format!(
                            "`action`: unknown value `{other}`, expected \"latch\" or \"rebound\""
                        ),
                    ));
                }
            };
            stops.push(HingeStop {
                hinge,
                lower: sf.lower,
                upper: sf.upper,
                action,
                min_rebound_rate: sf.min_rebound_rate.unwrap_or(1e-3),
            });
        }
        Ok(HingeStops::new(stops))
    }
}
