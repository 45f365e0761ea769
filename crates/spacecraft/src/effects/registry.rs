//! The effect registry: which `[effects.<name>]` sections a scene may have, and how each is
//! read into an effect.
//!
//! An effect readable from a scene implements [`SceneEffect`]: its section's serde struct
//! (`deny_unknown_fields`, [`toml::Spanned`] where an error should name a value's line), and
//! its construction and validation from it. A [`Registry`] maps section names to such
//! effects. The built-in effects register through the same call a user's effect does:
//!
//! ```
//! use satsim_spacecraft::effects::{HingeSprings, Registry};
//! let mut registry = Registry::new();
//! registry.register::<HingeSprings>();
//! assert_eq!(registry.names(), vec!["hinge_springs"]);
//! assert!(Registry::with_builtins().names().contains(&"reaction_wheels"));
//! ```
//!
//! The scene reader (`satsim_tools::scene::Scene::read_with_registry`) reads a scene against a
//! registry (`Scene::read` uses [`Registry::with_builtins`]); a section no entry names is an
//! error naming the file, the line and the known sections. `examples/custom_effect.rs`
//! adds an effect outside this crate.

use super::Section;
use super::{
    AttitudeControl, Bdot, Drag, Effect, GravityGradient, HingeControl, HingeSprings, HingeStops,
    Magnetic, ReactionWheels, Rotor, SolarRadiation, Thrusters,
};

use satsim_tree::io::FileError;
use serde::de::DeserializeOwned;
use std::any::Any;
use std::fmt;

/// An effect a scene can enable with an `[effects.<SECTION>]` section.
pub trait SceneEffect: Effect + Clone + fmt::Debug + Sync + 'static {
    /// The section's name, `[effects.<SECTION>]`; also the effect's [`Effect::name`].
    const SECTION: &'static str;
    /// The section as written: a serde struct with `#[serde(deny_unknown_fields)]` (an
    /// unknown key is then an error naming the key and its line). Declare
    /// `enabled: Option<bool>` to let a scene switch the effect off without removing the
    /// section (the reader skips a section with `enabled = false`).
    type File: DeserializeOwned;
    /// The effect from its section, checked against the scene's model; errors name the
    /// scene file and line ([`SceneText::error`](super::SceneText::error), through the section).
    fn from_section(file: Self::File, section: &Section) -> Result<Self, FileError>;
    /// Checks the effect against the other enabled ones (the orbit included); `Err` is a
    /// message that the reader places at the section's line. The default checks
    /// [`Effect::needs`] and the declared dependencies ([`needs_met`]).
    fn check(&self, enabled: &EffectSet) -> Result<(), String> {
        needs_met(self, enabled)
    }
}

/// The default [`SceneEffect::check`]: an orbit, rotors to command and every declared
/// dependency ([`Effect::after`], [`Effect::before`]) are enabled when needed.
pub fn needs_met(e: &dyn Effect, enabled: &EffectSet) -> Result<(), String> {
    let needs = e.needs();
    let name = e.name();
    if needs.orbit && !enabled.contains("orbit") {
        return Err(format!(
            "effects.{name} needs an [orbit] table (e.g. `[orbit]` with `altitude = 500e3`)"
        ));
    }
    if needs.rotors && !enabled.iter().any(|o| !o.rotors().is_empty()) {
        return Err(format!(
            "effects.{name} needs rotors to command (e.g. [effects.reaction_wheels] with at least one [[effects.reaction_wheels.wheel]])"
        ));
    }
    for (word, deps) in [("after", e.after()), ("before", e.before())] {
        if let Some(d) = deps.iter().find(|d| !enabled.contains(d)) {
            return Err(format!(
                "effects.{name} runs {word} `{d}`, which is not enabled (add [effects.{d}])"
            ));
        }
    }
    Ok(())
}

/// A boxed effect that can be cloned, printed and looked up by type: what an [`EffectSet`]
/// holds. Implemented for every `Effect + Clone + Debug + Sync + 'static`.
pub trait AnyEffect: Effect + fmt::Debug + Sync {
    /// A boxed copy.
    fn clone_box(&self) -> Box<dyn AnyEffect>;
    /// For downcasting to the concrete type.
    fn as_any(&self) -> &dyn Any;
    /// For downcasting to the concrete type.
    fn as_any_mut(&mut self) -> &mut dyn Any;
    /// The effect, for [`crate::simulation::SimulationBuilder::boxed`].
    fn into_effect(self: Box<Self>) -> Box<dyn Effect>;
    /// The effect, as a trait object.
    fn as_effect(&self) -> &dyn Effect;
}

impl<T: Effect + Clone + fmt::Debug + Sync + 'static> AnyEffect for T {
    fn clone_box(&self) -> Box<dyn AnyEffect> {
        Box::new(self.clone())
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
    fn into_effect(self: Box<Self>) -> Box<dyn Effect> {
        self
    }
    fn as_effect(&self) -> &dyn Effect {
        self
    }
}

impl Clone for Box<dyn AnyEffect> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// The effects a scene enables (the orbit included), at most one of each name, in the order
/// they were added (the simulation then orders them by their dependencies).
///
/// ```
/// use satsim_spacecraft::effects::{EffectSet, HingeSprings};
/// let mut set = EffectSet::default();
/// set.insert(HingeSprings::new(vec![10.0]));
/// set.get_mut::<HingeSprings>().unwrap().stiffness[0] = 20.0;
/// assert_eq!(set.get::<HingeSprings>().unwrap().stiffness, vec![20.0]);
/// assert_eq!(set.names().collect::<Vec<_>>(), vec!["hinge_springs"]);
/// ```
#[derive(Clone, Debug, Default)]
pub struct EffectSet {
    effects: Vec<Box<dyn AnyEffect>>,
}

impl EffectSet {
    /// Adds `e`, replacing an effect of the same name (in place).
    pub fn insert(&mut self, e: impl AnyEffect + 'static) {
        self.insert_boxed(Box::new(e));
    }
    /// Adds a boxed effect, replacing an effect of the same name (in place).
    pub fn insert_boxed(&mut self, e: Box<dyn AnyEffect>) {
        match self.effects.iter().position(|o| o.name() == e.name()) {
            Some(i) => self.effects[i] = e,
            None => self.effects.push(e),
        }
    }
    /// Removes the effect called `name`; whether there was one.
    pub fn remove(&mut self, name: &str) -> bool {
        let n = self.effects.len();
        self.effects.retain(|e| e.name() != name);
        self.effects.len() != n
    }
    /// The enabled effect of type `E`.
    pub fn get<E: 'static>(&self) -> Option<&E> {
        self.effects.iter().find_map(|e| e.as_any().downcast_ref())
    }
    /// The enabled effect of type `E`, to change it before a simulation is built.
    pub fn get_mut<E: 'static>(&mut self) -> Option<&mut E> {
        self.effects
            .iter_mut()
            .find_map(|e| e.as_any_mut().downcast_mut())
    }
    /// Whether an effect called `name` is enabled.
    pub fn contains(&self, name: &str) -> bool {
        self.effects.iter().any(|e| e.name() == name)
    }
    /// The enabled effects' names, in order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.effects.iter().map(|e| e.name())
    }
    /// The rotors the enabled effects add, in order: those a simulation hinges on after the
    /// model's hinges (one effect may add them; a simulation refuses more).
    pub fn rotors(&self) -> Vec<Rotor> {
        self.iter().flat_map(|e| e.rotors()).collect()
    }
    /// The enabled effects, in order.
    pub fn iter(&self) -> impl Iterator<Item = &dyn Effect> {
        self.effects.iter().map(|e| e.as_effect())
    }
    /// Number of enabled effects.
    pub fn len(&self) -> usize {
        self.effects.len()
    }
    /// Whether no effect is enabled.
    pub fn is_empty(&self) -> bool {
        self.effects.is_empty()
    }
    /// The boxed effect called `name`.
    pub fn find(&self, name: &str) -> Option<&dyn AnyEffect> {
        self.effects
            .iter()
            .find(|e| e.name() == name)
            .map(|e| e.as_ref())
    }
    /// Fresh copies of the effects, for a simulation.
    pub fn to_boxed(&self) -> Vec<Box<dyn Effect>> {
        self.effects
            .iter()
            .map(|e| e.clone_box().into_effect())
            .collect()
    }
}

type Read = fn(&Section) -> Result<Option<Box<dyn AnyEffect>>, FileError>;
type Check = fn(&dyn AnyEffect, &EffectSet) -> Result<(), String>;

struct Entry {
    name: &'static str,
    read: Read,
    check: Check,
}

/// Section names mapped to the effects they enable (see the module documentation).
pub struct Registry {
    entries: Vec<Entry>,
}

impl Default for Registry {
    /// [`Registry::with_builtins`].
    fn default() -> Self {
        Self::with_builtins()
    }
}

impl fmt::Debug for Registry {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.names()).finish()
    }
}

impl Registry {
    /// A registry that knows no section.
    pub fn new() -> Self {
        Self {
            entries: Vec::new(),
        }
    }
    /// The built-in effects, registered in the order a scene lists them to the simulation
    /// (which then applies their declared dependencies).
    pub fn with_builtins() -> Self {
        let mut r = Self::new();
        r.register::<GravityGradient>()
            .register::<HingeSprings>()
            .register::<HingeControl>()
            .register::<HingeStops>()
            .register::<AttitudeControl>()
            .register::<ReactionWheels>()
            .register::<SolarRadiation>()
            .register::<Drag>()
            .register::<Bdot>()
            .register::<Magnetic>()
            .register::<Thrusters>();
        r
    }
    /// Registers `E` under [`SceneEffect::SECTION`], replacing an effect registered under
    /// the same name (a user's version of a built-in one).
    pub fn register<E: SceneEffect>(&mut self) -> &mut Self {
        let entry = Entry {
            name: E::SECTION,
            read: read::<E>,
            check: |e, set| {
                e.as_any()
                    .downcast_ref::<E>()
                    .map_or(Ok(()), |e| e.check(set))
            },
        };
        match self.entries.iter().position(|o| o.name == E::SECTION) {
            Some(i) => self.entries[i] = entry,
            None => self.entries.push(entry),
        }
        self
    }
    /// The known section names, in registration order.
    pub fn names(&self) -> Vec<&'static str> {
        self.entries.iter().map(|e| e.name).collect()
    }
    /// Whether a section called `name` is known.
    pub fn contains(&self, name: &str) -> bool {
        self.entries.iter().any(|e| e.name == name)
    }
    /// Reads the section called `section.name()`, `None` when it is switched off.
    pub fn read(&self, section: &Section) -> Result<Option<Box<dyn AnyEffect>>, FileError> {
        match self.entries.iter().find(|e| e.name == section.name()) {
            Some(e) => (e.read)(section),
            None => Ok(None),
        }
    }
    /// Checks an effect read by this registry against the other enabled effects.
    pub fn check(&self, e: &dyn AnyEffect, enabled: &EffectSet) -> Result<(), String> {
        match self.entries.iter().find(|x| x.name == e.name()) {
            Some(x) => (x.check)(e, enabled),
            None => needs_met(e.as_effect(), enabled),
        }
    }
}

fn read<E: SceneEffect>(section: &Section) -> Result<Option<Box<dyn AnyEffect>>, FileError> {
    // The whole section is checked against its schema even when switched off.
    let Some(file) = section.effect_section::<E::File>(section.name())? else {
        return Ok(None);
    };
    if !section.enabled() {
        return Ok(None);
    }
    let e = E::from_section(file.into_inner(), section)?;
    if e.name() != E::SECTION {
        return Err(section.error_here(format!(
            "the effect registered for [effects.{}] calls itself `{}`: `SceneEffect::SECTION` and `Effect::name` must agree",
            E::SECTION,
            e.name()
        )));
    }
    Ok(Some(Box::new(e)))
}
