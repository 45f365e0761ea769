//! How an effect reads its own `[effects.<name>]` section: [`SceneText`] (the scene's text and
//! path, with the checks every section uses, each error naming the file and line) and
//! [`Section`] (one section being read, and the model it applies to). The scene reader in
//! `satsim-tools` makes them and calls each registered effect's
//! [`SceneEffect::from_section`](super::SceneEffect::from_section); no effect imports the
//! scene reader.

use satsim_environment::Epoch;
use satsim_tree::Model;
use satsim_tree::error::Num;
use satsim_tree::io::{Document, FileError, line_of, with_key};
use serde::de::{self, DeserializeOwned, DeserializeSeed, IgnoredAny, MapAccess, Visitor};
use std::cell::RefCell;
use std::fmt;
use std::marker::PhantomData;
use std::ops::{Deref, Range};
use std::path::Path;
use toml::Spanned;

/// A scene file's text and path: what an error needs to name the file and line. The checks
/// here are the ones every section uses (numbers finite, positive, ...).
#[derive(Clone, Copy, Debug)]
pub struct SceneText<'a> {
    text: &'a str,
    path: &'a Path,
    /// The text parsed, where the reader parsed it once for every section
    /// ([`Self::parsed`]); without it each section parses the text.
    doc: Option<&'a Document<'a>>,
}

impl<'a> SceneText<'a> {
    /// The scene `text`, read from `path`.
    pub fn new(text: &'a str, path: &'a Path) -> Self {
        Self {
            text,
            path,
            doc: None,
        }
    }

    /// The scene already parsed into `doc`, read from `path`: each section is read from
    /// `doc`'s tree rather than by parsing the text again.
    pub fn parsed(doc: &'a Document<'a>, path: &'a Path) -> Self {
        Self {
            text: doc.text(),
            path,
            doc: Some(doc),
        }
    }

    /// The parsed scene, when it was given ([`Self::parsed`]).
    pub fn document(&self) -> Option<&'a Document<'a>> {
        self.doc
    }
    /// The scene's text.
    pub fn text(&self) -> &'a str {
        self.text
    }
    /// The scene file's path.
    pub fn path(&self) -> &'a Path {
        self.path
    }

    /// A schema error at the line of `span` (no line when `None`).
    pub fn error(&self, span: Option<Range<usize>>, message: impl Into<String>) -> FileError {
        FileError::Schema {
            path: self.path.to_path_buf(),
            line: span.map(|s| line_of(self.text, s.start)),
            message: message.into(),
        }
    }

    /// `x`, which must be a finite number > 0 (`what` names the key).
    pub fn positive(&self, x: &Spanned<f64>, what: &str) -> Result<f64, FileError> {
        let v = *x.get_ref();
        if !(v > 0.0 && v.is_finite()) {
            return Err(self.error(
                Some(x.span()),
                format!("`{what}` must be a finite number > 0, got {}", Num(v)),
            ));
        }
        Ok(v)
    }

    /// `x`, which must be a finite number > 0 within `bound` (`what` names the key).
    pub fn positive_within(
        &self,
        x: &Spanned<f64>,
        what: &str,
        bound: Bound,
    ) -> Result<f64, FileError> {
        let v = self.positive(x, what)?;
        bound
            .check(v, what)
            .map_err(|m| self.error(Some(x.span()), m))?;
        Ok(v)
    }

    /// `x`, which must be a finite number >= 0 (`what` names the key).
    pub fn non_negative(&self, x: &Spanned<f64>, what: &str) -> Result<f64, FileError> {
        let v = *x.get_ref();
        if !(v >= 0.0 && v.is_finite()) {
            return Err(self.error(
                Some(x.span()),
                format!("`{what}` must be a finite number >= 0, got {}", Num(v)),
            ));
        }
        Ok(v)
    }

    /// `name`, which becomes part of output column names: letters, digits and `_` only (see
    /// [`satsim_tree::io::column_name`]); `what` names the key, e.g. `effects.thrusters.thruster.name`.
    pub fn column_name<'n>(
        &self,
        name: &'n Spanned<String>,
        what: &str,
    ) -> Result<&'n String, FileError> {
        satsim_tree::io::column_name(name.get_ref())
            .map_err(|m| self.error(Some(name.span()), format!("`{what}` {m}")))?;
        Ok(name.get_ref())
    }

    /// Every given value is finite (TOML accepts `nan` and `inf`), and those marked
    /// non-negative are `>= 0`; the error names the key and the table's line.
    pub fn check_numbers(
        &self,
        span: Range<usize>,
        table: &str,
        values: &[(&str, Option<f64>, bool)],
    ) -> Result<(), FileError> {
        for &(key, v, non_negative) in values {
            let Some(v) = v else { continue };
            if !v.is_finite() || (non_negative && v < 0.0) {
                let what = if non_negative {
                    "a finite number >= 0"
                } else {
                    "a finite number"
                };
                return Err(self.error(
                    Some(span),
                    format!("`{table}{key}` must be {what}, got {}", Num(v)),
                ));
            }
        }
        Ok(())
    }

    /// The section `[effects.<name>]` as `T` (`None` when the scene has none), with the
    /// spans of its values in this text. A schema error names the key and its line.
    pub fn effect_section<T: DeserializeOwned>(
        &self,
        name: &str,
    ) -> Result<Option<Spanned<T>>, FileError> {
        let located = |e: &toml::de::Error| e.span().map(|s| line_of(self.text, s.start));
        let schema = |e: toml::de::Error| FileError::Schema {
            line: located(&e),
            message: with_key(&e, reword(e.message())),
            path: self.path.to_path_buf(),
        };
        let de = match self.doc {
            Some(doc) => doc.only(&["effects", name]),
            None => toml::Deserializer::parse(self.text).map_err(schema)?,
        };
        Pick::<T> {
            path: &["effects", name],
            t: PhantomData,
        }
        .deserialize(de)
        .map_err(schema)
    }
}

/// Deserializes only the value at `path` (table keys) from a document, as `Spanned<T>`.
/// The deserializer is the document's, so spans and the key path in errors are the file's.
struct Pick<'p, T> {
    path: &'p [&'p str],
    t: PhantomData<T>,
}

impl<'de, T: DeserializeOwned> DeserializeSeed<'de> for Pick<'_, T> {
    type Value = Option<Spanned<T>>;
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
        d.deserialize_map(self)
    }
}

impl<'de, T: DeserializeOwned> Visitor<'de> for Pick<'_, T> {
    type Value = Option<Spanned<T>>;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a table")
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
        let mut found = None;
        while let Some(key) = map.next_key::<String>()? {
            if key != self.path[0] {
                map.next_value::<IgnoredAny>()?;
            } else if self.path.len() == 1 {
                found = Some(map.next_value::<Spanned<T>>()?);
            } else {
                found = map.next_value_seed(Pick::<T> {
                    path: &self.path[1..],
                    t: PhantomData,
                })?;
            }
        }
        Ok(found)
    }
}

/// The largest magnitude a value may have: beyond any real spacecraft's (`why` says so), so
/// that a larger value is a slip (a unit, an exponent) refused at its line, not a run that
/// overflows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bound {
    /// The largest magnitude.
    pub max: f64,
    /// Its unit, for the message (`N`, `A m²`).
    pub unit: &'static str,
    /// Why no real value exceeds it, for the message.
    pub why: &'static str,
}

impl Bound {
    /// `v` within the bound; else the message, naming the key `what`.
    pub fn check(&self, v: f64, what: &str) -> Result<(), String> {
        if v.abs() <= self.max {
            return Ok(());
        }
        // The bound is a round power of ten: `1e8`, not `100000000`.
        let (unit, max) = (self.unit, format!("{:e}", self.max));
        let limit = if v < 0.0 {
            format!("below -{max} {unit}")
        } else {
            format!("more than {max} {unit}")
        };
        Err(format!(
            "`{what}` is {} {unit}, {limit}: {}",
            Num(v),
            self.why
        ))
    }
}

/// One `[effects.<name>]` section being read: where it is (for errors naming the scene file
/// and line) and the model it applies to. It dereferences to [`SceneText`], whose checks
/// (`positive`, `check_numbers`, ...) name the file and line.
pub struct Section<'a> {
    text: SceneText<'a>,
    name: &'a str,
    span: Range<usize>,
    model: &'a Model,
    enabled: bool,
    epoch: Option<Epoch>,
    warnings: RefCell<Vec<String>>,
}

impl<'a> Deref for Section<'a> {
    type Target = SceneText<'a>;
    fn deref(&self) -> &SceneText<'a> {
        &self.text
    }
}

impl<'a> Section<'a> {
    /// The section `[effects.<name>]` of `text` at `span`, for `model`; `enabled`: whether it
    /// is switched on. The scene reader makes one per section.
    pub fn new(
        text: SceneText<'a>,
        name: &'a str,
        span: Range<usize>,
        model: &'a Model,
        enabled: bool,
    ) -> Self {
        Self {
            text,
            name,
            span,
            model,
            enabled,
            epoch: None,
            warnings: RefCell::new(Vec::new()),
        }
    }
    /// The section of a scene whose `epoch` (t = 0 as a date) is `epoch`.
    pub fn with_epoch(mut self, epoch: Option<Epoch>) -> Self {
        self.epoch = epoch;
        self
    }
    /// The scene's epoch, for an effect that needs a date (the Sun, the Earth's rotation,
    /// the field's secular variation); without one, an error at the section's line saying
    /// what to add.
    pub fn epoch(&self) -> Result<Epoch, FileError> {
        self.epoch.ok_or_else(|| {
            self.error_here(format!(
                "[effects.{}] needs the scene's `epoch` (t = 0 as a date): add e.g. `epoch = \"2026-03-20T12:00:00 UTC\"` at the top of the scene",
                self.name
            ))
        })
    }
    /// Notes something the reader accepts but the user should hear about (an implausible
    /// value), at the line of `span`: `file:line: message`. The scene reader collects them
    /// into the scene's warnings, which the command line prints on standard error.
    pub fn warn(&self, span: Range<usize>, message: impl Into<String>) {
        let line = line_of(self.text.text, span.start);
        self.warnings.borrow_mut().push(format!(
            "{}:{line}: {}",
            self.text.path.display(),
            message.into()
        ));
    }
    /// Warns when the angle `value` (rad) of `what` lies beyond ±2π: most likely degrees
    /// written where radians are meant (90 for a right angle).
    pub fn check_angle(&self, span: Range<usize>, what: &str, value: f64) {
        if value.abs() > std::f64::consts::TAU {
            self.warn(
                span,
                format!(
                    "`{what}` is {} rad, beyond ±2π: angles are in radians (for {} degrees write {:.6})",
                    Num(value),
                    Num(value),
                    value.to_radians()
                ),
            );
        }
    }
    /// The warnings noted while reading the section, in order.
    pub fn take_warnings(&self) -> Vec<String> {
        std::mem::take(&mut *self.warnings.borrow_mut())
    }
    /// Whether the section is switched on (a section switched off is still checked against
    /// its schema, and makes no effect).
    pub fn enabled(&self) -> bool {
        self.enabled
    }
    /// The section's name (`hinge_springs` for `[effects.hinge_springs]`).
    pub fn name(&self) -> &str {
        self.name
    }
    /// The scene's model (the hinges the section may name).
    pub fn model(&self) -> &Model {
        self.model
    }
    /// The section's span in the scene text (an error there names its first line).
    pub fn span(&self) -> Range<usize> {
        self.span.clone()
    }
    /// An error at the section's line.
    pub fn error_here(&self, message: impl Into<String>) -> FileError {
        self.text.error(Some(self.span()), message)
    }
    /// The index (file order) of the hinge called `name`; else an error at its line listing
    /// the model's hinges.
    pub fn hinge_index(&self, name: &Spanned<String>) -> Result<usize, FileError> {
        self.model.hinge_index(name.get_ref()).ok_or_else(|| {
            self.text.error(
                Some(name.span()),
                format!(
                    "unknown hinge `{}` (the model's hinges: {})",
                    name.get_ref(),
                    self.model.hinge_names().join(", ")
                ),
            )
        })
    }
    /// A list with one finite number per hinge (file order); `what` names the key.
    pub fn per_hinge(&self, x: &Spanned<Vec<f64>>, what: &str) -> Result<Vec<f64>, FileError> {
        let n = self.model.n_hinges();
        if x.get_ref().len() != n {
            return Err(self.text.error(
                Some(x.span()),
                format!(
                    "`{what}`: expected {n} entries (one per hinge, file order), got {}",
                    x.get_ref().len()
                ),
            ));
        }
        if x.get_ref().iter().any(|v| !v.is_finite()) {
            return Err(self
                .text
                .error(Some(x.span()), format!("`{what}`: entries must be finite")));
        }
        Ok(x.get_ref().clone())
    }
    /// [`Section::per_hinge`] whose entries must also be `>= 0` (a stiffness, a damping):
    /// the error names the key, the hinge and the value.
    pub fn per_hinge_non_negative(
        &self,
        x: &Spanned<Vec<f64>>,
        what: &str,
    ) -> Result<Vec<f64>, FileError> {
        let v = self.per_hinge(x, what)?;
        if let Some((k, bad)) = v.iter().enumerate().find(|(_, v)| **v < 0.0) {
            return Err(self.text.error(
                Some(x.span()),
                format!(
                    "`{what}`: entry {k} (hinge `{}`) is {}: it must be >= 0",
                    self.model.hinge_names()[k],
                    Num(*bad)
                ),
            ));
        }
        Ok(v)
    }
}

/// Rewords serde's messages in the file's vocabulary.
pub fn reword(m: &str) -> String {
    let m = m.trim_end().replace("expected f64", "expected a number");
    if let Some(rest) = m.strip_prefix("unknown field ") {
        format!("unknown key {rest}")
    } else if let Some(rest) = m.strip_prefix("missing field ") {
        format!("missing required key {rest}")
    } else {
        m
    }
}
