//! Dotted keys into a scene (contract section 8) and `--set KEY=VALUE` overrides.
//!
//! A key is a dotted path into the scene's TOML tree after an external `model` file (TOML)
//! or `initial` file (JSON) has been read in as if it were an inline table. A segment names a
//! table key, or, in an array (of tables or of numbers), a 0-based position:
//! `model.body.2.mass`, `effects.hinge_springs.stiffness`, `initial.hinges.angle`,
//! `orbit.altitude`, a flexible body's `model.body.1.flexible.beam.EI`,
//! `model.body.1.flexible.damping` and `initial.flexible.panel1.eta`. `satsim campaign` disperses the numbers such keys address; `satsim run
//! --set` and `satsim campaign --set` replace any value by one written as a TOML value.
//!
//! An override replaces a value that the scene (or its model or state file) already gives by
//! one of the same kind: a number by a number (an integer by an integer), a string by a
//! string, a boolean by a boolean, an array by an array, a table by an inline table; where
//! the scene accepts either of two forms (`initial.base.attitude`, `armature`,
//! `fsw.estimator.star_tracker`), by either. A value
//! that is not valid TOML replaces a string as that string (so `--set
//! integrator.method=rk4` needs no quotes). A key the file leaves out (at its default) is
//! added, with the tables on its way (`--set integrator.step=0.01`, `--set
//! effects.gravity_gradient.model=full`): the scene reader then checks it against the schema
//! like any written key, so a misspelt one is refused as an unknown key.
//!
//! An error the scene reader finds after the overrides names the file and line where the
//! value is written (the model file's line for a `model.` key read from a model file), found
//! with [`relocate`], and lists the overrides.

use satsim_tree::io::{FileError, line_of};
use serde::Deserialize;
use std::fmt;
use std::path::{Path, PathBuf};
use toml::de::{DeTable, DeValue};
use toml::{Spanned, Table, Value};

/// One step of a path into the scene's tree.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Segment {
    /// A table key.
    Key(String),
    /// A position in an array.
    Index(usize),
}

/// Why a key does not address a value (or a value cannot go there).
#[derive(Debug, Clone, PartialEq)]
pub struct KeyError(pub String);

impl fmt::Display for KeyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for KeyError {}

/// The kind of a TOML value, for messages ("a number", "a table"…).
pub fn kind(v: &Value) -> &'static str {
    match v {
        Value::String(_) => "a string",
        Value::Integer(_) => "an integer",
        Value::Float(_) => "a number",
        Value::Boolean(_) => "a boolean",
        Value::Datetime(_) => "a date",
        Value::Array(_) => "an array",
        Value::Table(_) => "a table",
    }
}

/// Walks the dotted `key` in `root`: the path to the value and the value.
pub fn walk<'a>(root: &'a Table, key: &str) -> Result<(Vec<Segment>, &'a Value), KeyError> {
    if key.is_empty() {
        return Err(KeyError("the key is empty".into()));
    }
    let mut path = Vec::new();
    let mut here: Option<&Value> = None;
    let mut walked = String::new();
    for seg in key.split('.') {
        if seg.is_empty() {
            return Err(KeyError(format!("`{key}` has an empty segment")));
        }
        let next = match here {
            None => {
                path.push(Segment::Key(seg.to_owned()));
                root.get(seg)
                    .ok_or_else(|| KeyError(format!("the scene has no `{seg}`")))?
            }
            Some(Value::Table(t)) => {
                path.push(Segment::Key(seg.to_owned()));
                t.get(seg)
                    .ok_or_else(|| KeyError(format!("`{walked}` has no key `{seg}`")))?
            }
            Some(Value::Array(a)) => {
                let i: usize = seg.parse().map_err(|_| {
                    KeyError(format!(
                        "`{walked}` is an array: expected a position (0-based), got `{seg}`"
                    ))
                })?;
                path.push(Segment::Index(i));
                a.get(i).ok_or_else(|| {
                    KeyError(format!(
                        "position {i} is out of range: `{walked}` has {} entries",
                        a.len()
                    ))
                })?
            }
            Some(other) => {
                return Err(KeyError(format!(
                    "`{walked}` is {}, not a table or an array",
                    kind(other)
                )));
            }
        };
        if !walked.is_empty() {
            walked.push('.');
        }
        walked.push_str(seg);
        here = Some(next);
    }
    Ok((path, here.expect("a non-empty key has a value")))
}

/// Replaces the value at `path` in `root` (which [`walk`] found there) by `value`.
pub fn set(root: &mut Table, path: &[Segment], value: Value) {
    let (first, rest) = path.split_first().expect("a resolved path is not empty");
    let Segment::Key(k) = first else {
        unreachable!("a path starts with a key")
    };
    let mut here = root.get_mut(k).expect("resolved path");
    for seg in rest {
        here = match (here, seg) {
            (Value::Table(t), Segment::Key(k)) => t.get_mut(k).expect("resolved path"),
            (Value::Array(a), Segment::Index(i)) => a.get_mut(*i).expect("resolved path"),
            _ => unreachable!("the tree changed under a resolved path"),
        };
    }
    *here = value;
}

/// One `--set KEY=VALUE`.
#[derive(Clone, Debug, PartialEq)]
pub struct Override {
    /// The dotted key.
    pub key: String,
    /// The value as written after `=`.
    pub text: String,
}

impl Override {
    /// Splits `KEY=VALUE` at its first `=`.
    pub fn parse(s: &str) -> Result<Override, KeyError> {
        let (key, text) = s.split_once('=').ok_or_else(|| {
            KeyError(format!(
                "`{s}`: expected KEY=VALUE (a dotted key, e.g. `model.body.2.mass=3.5`)"
            ))
        })?;
        let key = key.trim();
        if key.is_empty() {
            return Err(KeyError(format!("`{s}`: the key is empty")));
        }
        Ok(Override {
            key: key.to_owned(),
            text: text.trim().to_owned(),
        })
    }

    /// The value, parsed as a TOML value; a string target takes text that is not TOML as is.
    fn value_for(&self, target: &Value) -> Result<Value, KeyError> {
        let parsed = format!("v = {}", self.text)
            .parse::<Table>()
            .ok()
            .and_then(|mut t| t.remove("v"));
        match (parsed, target) {
            (Some(v), _) => Ok(v),
            (None, Value::String(_)) if !self.text.is_empty() => {
                Ok(Value::String(self.text.clone()))
            }
            (None, _) => Err(KeyError(format!(
                "`{}`: `{}` is not a TOML value (a number, \"string\", true/false, [array] or {{ table }})",
                self.key, self.text
            ))),
        }
    }

    /// Replaces the addressed value of `root` by this override's value, of the same kind; a
    /// key that is not there is added (with the tables on its way), for the scene reader to
    /// check against its schema.
    pub fn apply(&self, root: &mut Table) -> Result<(), KeyError> {
        self.clear_other_forms(root);
        if walk(root, &self.key).is_err() {
            return self.add(root);
        }
        let (path, target) = walk(root, &self.key)
            .map_err(|KeyError(m)| KeyError(format!("`--set {}`: unknown key: {m}", self.key)))?;
        let value = self.value_for(target)?;
        let value = match (target, value) {
            (Value::Float(_), Value::Integer(i)) => Value::Float(i as f64),
            (Value::Float(_), v @ Value::Float(_))
            | (Value::Integer(_), v @ Value::Integer(_))
            | (Value::String(_), v @ Value::String(_))
            | (Value::Boolean(_), v @ Value::Boolean(_))
            | (Value::Array(_), v @ Value::Array(_))
            | (Value::Table(_), v @ Value::Table(_))
            | (Value::Datetime(_), v @ Value::Datetime(_)) => v,
            // A value the scene may write in either form replaces the form written.
            (_, Value::Integer(i)) if other_form(&self.key, &Value::Float(0.0)) => {
                Value::Float(i as f64)
            }
            (_, v) if other_form(&self.key, &v) => v,
            (t, v) => {
                return Err(KeyError(format!(
                    "`--set {}`: wrong type: the scene has {} there, got {}",
                    self.key,
                    kind(t),
                    kind(&v)
                )));
            }
        };
        set(root, &path, value);
        Ok(())
    }

    /// A key of one of `initial.base.attitude`'s table forms (`euler_deg` and `sequence`, or
    /// `axis` and `angle_deg`) replaces the attitude written in another form: the quaternion
    /// array, or the other table form's keys.
    fn clear_other_forms(&self, root: &mut Table) {
        let Some(rest) = self.key.strip_prefix("initial.base.attitude.") else {
            return;
        };
        let form: &[&str] = match rest {
            "euler_deg" | "sequence" => &["euler_deg", "sequence"],
            "axis" | "angle_deg" => &["axis", "angle_deg"],
            _ => return,
        };
        let Some(Value::Table(base)) = root.get_mut("initial").and_then(|i| i.get_mut("base"))
        else {
            return;
        };
        match base.get_mut("attitude") {
            Some(Value::Table(t)) => t.retain(|k, _| form.contains(&k)),
            Some(a) => *a = Value::Table(Table::new()),
            None => {}
        }
    }

    /// Adds the key that [`walk`] did not find: every missing segment is a table key (an
    /// array position cannot be added), the last one takes the value as written.
    fn add(&self, root: &mut Table) -> Result<(), KeyError> {
        let unknown = |m: String| KeyError(format!("`--set {}`: unknown key: {m}", self.key));
        let segments: Vec<&str> = self.key.split('.').collect();
        if segments.iter().any(|s| s.is_empty()) {
            return Err(unknown(format!("`{}` has an empty segment", self.key)));
        }
        let (last, parents) = segments.split_last().expect("split gives one segment");
        // The value first: a refused override changes nothing.
        let value = self.value_for(&Value::String(String::new()))?;
        let mut here = root;
        let mut walked = String::new();
        for seg in parents {
            let next = match here.entry(seg.to_string()) {
                toml::map::Entry::Vacant(v) => v.insert(Value::Table(Table::new())),
                toml::map::Entry::Occupied(o) => o.into_mut(),
            };
            if !walked.is_empty() {
                walked.push('.');
            }
            walked.push_str(seg);
            here = match next {
                Value::Table(t) => t,
                Value::Array(a) => {
                    // The rest of the key goes on inside an existing array element.
                    let rest = &self.key[walked.len() + 1..];
                    let (i, tail) = rest.split_once('.').unwrap_or((rest, ""));
                    let i: usize = i.parse().map_err(|_| {
                        unknown(format!(
                            "`{walked}` is an array: expected a position (0-based), got `{i}`"
                        ))
                    })?;
                    let n = a.len();
                    let element = a.get_mut(i).ok_or_else(|| {
                        unknown(format!(
                            "position {i} is out of range: `{walked}` has {n} entries"
                        ))
                    })?;
                    let Value::Table(t) = element else {
                        return Err(unknown(format!(
                            "`{walked}.{i}` is {}, not a table",
                            kind(element)
                        )));
                    };
                    if tail.is_empty() {
                        return Err(unknown(format!("`{walked}.{i}` is already there")));
                    }
                    let inner = Override {
                        key: tail.to_owned(),
                        text: self.text.clone(),
                    };
                    return inner.apply(t).map_err(|KeyError(m)| {
                        KeyError(
                            m.replace(&format!("`--set {tail}`"), &format!("`--set {}`", self.key)),
                        )
                    });
                }
                other => {
                    return Err(unknown(format!(
                        "`{walked}` is {}, not a table",
                        kind(other)
                    )));
                }
            };
        }
        here.insert(last.to_string(), value);
        Ok(())
    }
}

/// Whether the scene accepts `value` at `key` in place of a value of another kind: the keys
/// a scene may write in either of two forms, `initial.base.attitude` (a quaternion array or
/// an Euler or axis-angle table), `armature` (one number or one per hinge) and
/// `fsw.estimator.star_tracker` (a sensor's name or a list of them).
fn other_form(key: &str, value: &Value) -> bool {
    match key {
        "initial.base.attitude" => matches!(value, Value::Array(_) | Value::Table(_)),
        "armature" => matches!(value, Value::Array(_) | Value::Float(_)),
        "fsw.estimator.star_tracker" => matches!(value, Value::Array(_) | Value::String(_)),
        _ => false,
    }
}

#[derive(Deserialize)]
struct Sources {
    #[serde(default)]
    model: Option<Spanned<Value>>,
    #[serde(default)]
    initial: Option<Spanned<Value>>,
}

/// Replaces `model = "file"` and `initial = "file"` of the scene `base` (whose text is
/// `text`, at `path`) by the files' contents, as tables (the JSON state's numbers as floats,
/// as the state reader reads them). A file that does not exist is reported at the scene's
/// line.
pub fn inline_sources(base: &mut Table, text: &str, path: &Path) -> Result<(), FileError> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let spans: Option<Sources> = toml::from_str(text).ok();
    let line_of_key = |key: &str| {
        spans.as_ref().and_then(|s| {
            let v = if key == "model" {
                s.model.as_ref()
            } else {
                s.initial.as_ref()
            };
            v.map(|v| line_of(text, v.span().start))
        })
    };
    for key in ["model", "initial"] {
        let Some(Value::String(p)) = base.get(key) else {
            continue;
        };
        let file = dir.join(p);
        if !file.is_file() {
            return Err(missing_source(path, line_of_key(key), key, p, &file));
        }
        let source = std::fs::read_to_string(&file).map_err(|source| FileError::Read {
            path: file.clone(),
            source,
        })?;
        let v = if key == "model" {
            let t: Table = source
                .parse()
                .map_err(|e: toml::de::Error| FileError::Syntax {
                    line: e.span().map(|s| line_of(&source, s.start)),
                    message: e.message().trim_end().to_owned(),
                    path: file.clone(),
                })?;
            let mut t = t;
            rebase_modes_files(&mut t, Path::new(p).parent().unwrap_or(Path::new("")));
            Value::Table(t)
        } else {
            let json: serde_json::Value =
                serde_json::from_str(&source).map_err(|e| FileError::Syntax {
                    path: file.clone(),
                    line: Some(e.line()),
                    message: e.to_string(),
                })?;
            json_to_toml(&json).map_err(|m| FileError::Schema {
                path: file.clone(),
                line: None,
                message: m,
            })?
        };
        base.insert(key.into(), v);
    }
    Ok(())
}

/// A model file's bodies' `flexible.modes_file` paths, which are relative to the model
/// file's folder, made relative to the scene's (the model file's folder being `model_dir`
/// from the scene's), so that the model read in as an inline table still finds them. An
/// absolute path stays as it is.
fn rebase_modes_files(model: &mut Table, model_dir: &Path) {
    let Some(Value::Array(bodies)) = model.get_mut("body") else {
        return;
    };
    for body in bodies {
        if let Some(Value::String(file)) = body
            .get_mut("flexible")
            .and_then(|f| f.get_mut("modes_file"))
        {
            let rebased = model_dir.join(file.as_str());
            *file = rebased.to_string_lossy().into_owned();
        }
    }
}

/// The error for a `model` or `initial` file that does not exist, at the scene's line.
pub fn missing_source(
    scene: &Path,
    line: Option<usize>,
    key: &str,
    written: &str,
    resolved: &Path,
) -> FileError {
    FileError::Schema {
        path: scene.to_path_buf(),
        line,
        message: format!(
            "`{key}`: the file \"{written}\" does not exist (looked for {}; a relative path is relative to the scene file's folder)",
            resolved.display()
        ),
    }
}

/// A JSON value as TOML (numbers as floats, as the state reader reads them).
pub fn json_to_toml(v: &serde_json::Value) -> Result<Value, String> {
    use serde_json::Value as J;
    Ok(match v {
        J::Null => return Err("`null` has no TOML form".into()),
        J::Bool(b) => Value::Boolean(*b),
        J::Number(n) => Value::Float(n.as_f64().ok_or("a number out of range")?),
        J::String(s) => Value::String(s.clone()),
        J::Array(a) => Value::Array(a.iter().map(json_to_toml).collect::<Result<_, _>>()?),
        J::Object(o) => Value::Table(
            o.iter()
                .map(|(k, v)| Ok((k.clone(), json_to_toml(v)?)))
                .collect::<Result<Table, String>>()?,
        ),
    })
}

/// The scene text at `path` with `overrides` applied: its `model` and `initial` files read
/// in as tables, each override applied in order, written back as TOML. An override that
/// does not apply is a [`FileError::Schema`] of the scene file naming the key.
pub fn overridden_text(
    text: &str,
    path: &Path,
    overrides: &[Override],
) -> Result<String, FileError> {
    let mut base: Table = text
        .parse()
        .map_err(|e: toml::de::Error| FileError::Syntax {
            path: path.to_path_buf(),
            line: e.span().map(|s| line_of(text, s.start)),
            message: e.message().trim_end().to_owned(),
        })?;
    inline_sources(&mut base, text, path)?;
    for o in overrides {
        o.apply(&mut base)
            .map_err(|KeyError(m)| FileError::Schema {
                path: path.to_path_buf(),
                line: None,
                message: m,
            })?;
    }
    Ok(toml::to_string(&base).expect("a TOML table serialises"))
}

/// A value's dotted key and its first and last line in a text.
type KeyLines = (String, usize, usize);

/// The dotted key, first line and last line of every value of a TOML `text` (each key from
/// its name to the end of its value; arrays' elements by position), outermost first. Empty
/// for a text that is not TOML.
fn value_lines(text: &str) -> Vec<KeyLines> {
    /// The offsets where lines start: a line number is a binary search, not a scan.
    struct Lines(Vec<usize>);
    impl Lines {
        fn of(&self, offset: usize) -> usize {
            self.0.partition_point(|&start| start <= offset)
        }
    }
    fn table(t: &DeTable, prefix: &str, text: &Lines, out: &mut Vec<KeyLines>) {
        for (k, v) in t.iter() {
            let key = if prefix.is_empty() {
                k.get_ref().to_string()
            } else {
                format!("{prefix}.{}", k.get_ref())
            };
            value(v, key, k.span().start.min(v.span().start), text, out);
        }
    }
    fn value(
        v: &Spanned<DeValue>,
        key: String,
        start: usize,
        text: &Lines,
        out: &mut Vec<KeyLines>,
    ) {
        let end = v.span().end.saturating_sub(1).max(start);
        out.push((key.clone(), text.of(start), text.of(end)));
        match v.get_ref() {
            DeValue::Table(t) => table(t, &key, text, out),
            DeValue::Array(a) => {
                for (i, e) in a.iter().enumerate() {
                    value(e, format!("{key}.{i}"), e.span().start, text, out);
                }
            }
            _ => {}
        }
    }
    let mut out = Vec::new();
    if let Ok(doc) = DeTable::parse(text) {
        let starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        table(doc.get_ref(), "", &Lines(starts), &mut out);
    }
    out
}

/// The line of `key` in `lines` (from [`value_lines`]), else of its nearest ancestor there.
fn line_of_key(lines: &[KeyLines], key: &str) -> Option<usize> {
    let mut k = key;
    loop {
        if let Some((_, first, _)) = lines.iter().find(|(name, ..)| name == k) {
            return Some(*first);
        }
        k = &k[..k.rfind('.')?];
    }
}

/// Maps a line of the rewritten scene text ([`overridden_text`]) back to where the user
/// wrote that value: a line of the scene file, a line of its model file for a `model.` key,
/// the state file (no line: JSON spans are not kept) for an `initial.` key.
pub struct Origins {
    scene: PathBuf,
    scene_lines: Vec<KeyLines>,
    model: Option<(PathBuf, Vec<KeyLines>)>,
    initial: Option<PathBuf>,
    rewritten_lines: Vec<KeyLines>,
}

impl Origins {
    /// The origins of the rewritten text `rewritten` of the scene `text` at `path`.
    pub fn new(text: &str, path: &Path, rewritten: &str) -> Self {
        let dir = path.parent().unwrap_or(Path::new(""));
        let written: Option<Table> = text.parse().ok();
        let source = |key: &str| match written.as_ref().and_then(|t| t.get(key)) {
            Some(Value::String(p)) => Some(dir.join(p)),
            _ => None,
        };
        let model = source("model").map(|file| {
            let lines = std::fs::read_to_string(&file)
                .map(|t| value_lines(&t))
                .unwrap_or_default();
            (file, lines)
        });
        Origins {
            scene: path.to_path_buf(),
            scene_lines: value_lines(text),
            model,
            initial: source("initial"),
            rewritten_lines: value_lines(rewritten),
        }
    }

    /// The dotted key whose value holds `line` of the rewritten text (the innermost one).
    pub fn key_at(&self, line: usize) -> Option<&str> {
        self.rewritten_lines
            .iter()
            .filter(|(_, first, last)| *first <= line && line <= *last)
            .min_by_key(|(key, first, last)| (last - first, usize::MAX - key.len()))
            .map(|(key, ..)| key.as_str())
    }

    /// Where the value at `line` of the rewritten text was written: the file and its line.
    pub fn place(&self, line: usize) -> (PathBuf, Option<usize>) {
        let Some(key) = self.key_at(line) else {
            return (self.scene.clone(), None);
        };
        if let (Some(rest), Some((file, lines))) = (key.strip_prefix("model."), &self.model) {
            return (file.clone(), line_of_key(lines, rest));
        }
        if let (Some(_), Some(file)) = (key.strip_prefix("initial."), &self.initial) {
            return (file.clone(), None);
        }
        (self.scene.clone(), line_of_key(&self.scene_lines, key))
    }

    /// A warning `scene:line: message` of the rewritten text, placed where the value was
    /// written and marked as read with `--set`.
    pub fn warning(&self, w: &str) -> String {
        let prefix = format!("{}:", self.scene.display());
        if let Some(rest) = w.strip_prefix(&prefix)
            && let Some((line, msg)) = rest.split_once(':')
            && let Ok(line) = line.parse::<usize>()
        {
            let (file, line) = self.place(line);
            return match line {
                Some(l) => format!("{}:{l} (with --set):{msg}", file.display()),
                None => format!("{} (with --set):{msg}", file.display()),
            };
        }
        w.to_owned()
    }
}

/// An error that the scene reader found in the rewritten text `rewritten` of the scene
/// `text` at `path`: placed where the value was written (see [`Origins`]), and the message
/// lists the overrides.
pub fn relocate(
    e: FileError,
    text: &str,
    path: &Path,
    rewritten: &str,
    overrides: &[Override],
) -> FileError {
    let line = match &e {
        FileError::Schema { path: p, line, .. }
        | FileError::Syntax { path: p, line, .. }
        | FileError::Model { path: p, line, .. }
            if p == path =>
        {
            *line
        }
        _ => return e,
    };
    let Some(line) = line else {
        return after_overrides(e, path, overrides);
    };
    let (file, at) = Origins::new(text, path, rewritten).place(line);
    match after_overrides(e, path, overrides) {
        FileError::Schema { message, .. } => FileError::Schema {
            path: file,
            line: at,
            message,
        },
        FileError::Syntax { message, .. } => FileError::Syntax {
            path: file,
            line: at,
            message,
        },
        FileError::Model { source, .. } => FileError::Model {
            path: file,
            line: at,
            source,
        },
        other => other,
    }
}

/// An error found in the overridden text of the scene at `path`, without its line (one of
/// the rewritten text); the message says the overrides were applied. [`relocate`] also
/// finds the line where the value was written.
pub fn after_overrides(e: FileError, path: &Path, overrides: &[Override]) -> FileError {
    let note = |m: String| {
        if overrides.is_empty() {
            return m;
        }
        let list: Vec<String> = overrides
            .iter()
            .map(|o| format!("{}={}", o.key, o.text))
            .collect();
        format!("{m} (with --set {})", list.join(", --set "))
    };
    match e {
        FileError::Schema {
            path: p, message, ..
        } if p == path => FileError::Schema {
            path: p,
            line: None,
            message: note(message),
        },
        FileError::Syntax {
            path: p, message, ..
        } if p == path => FileError::Syntax {
            path: p,
            line: None,
            message: note(message),
        },
        // The builder's typed error keeps its type (and so no note); the line goes.
        FileError::Model {
            path: p, source, ..
        } if p == path => FileError::Model {
            path: p,
            line: None,
            source,
        },
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn root() -> Table {
        toml::from_str(
            "[model]\n[[model.body]]\nmass = 1.0\n[[model.body]]\nmass = 2.5\n[x]\nname = \"a\"\nn = 3\nv = [1.0, 2.0]\non = true\n",
        )
        .unwrap()
    }

    fn set_one(r: &mut Table, s: &str) -> Result<(), KeyError> {
        Override::parse(s)?.apply(r)
    }

    #[test]
    fn overrides_replace_values_of_the_same_kind() {
        let mut r = root();
        set_one(&mut r, "model.body.1.mass=4").unwrap();
        assert_eq!(r["model"]["body"][1]["mass"].as_float(), Some(4.0));
        set_one(&mut r, "x.v.0 = -0.5").unwrap();
        assert_eq!(r["x"]["v"][0].as_float(), Some(-0.5));
        set_one(&mut r, "x.v=[3.0, 4.0, 5.0]").unwrap();
        assert_eq!(r["x"]["v"].as_array().unwrap().len(), 3);
        set_one(&mut r, "x.name=\"b c\"").unwrap();
        assert_eq!(r["x"]["name"].as_str(), Some("b c"));
        set_one(&mut r, "x.name=rk4").unwrap();
        assert_eq!(r["x"]["name"].as_str(), Some("rk4"));
        set_one(&mut r, "x.on=false").unwrap();
        assert_eq!(r["x"]["on"].as_bool(), Some(false));
        set_one(&mut r, "x.n=7").unwrap();
        assert_eq!(r["x"]["n"].as_integer(), Some(7));
        // An `=` in the value stays in the value.
        set_one(&mut r, "x.name=a=b").unwrap();
        assert_eq!(r["x"]["name"].as_str(), Some("a=b"));
    }

    #[test]
    fn keys_the_scene_leaves_out_are_added() {
        let mut r = root();
        set_one(&mut r, "x.w=1").unwrap();
        assert_eq!(r["x"]["w"].as_integer(), Some(1));
        // With the tables on the way, and a bare word as a string.
        set_one(&mut r, "integrator.method=rk4").unwrap();
        assert_eq!(r["integrator"]["method"].as_str(), Some("rk4"));
        set_one(&mut r, "a.b.c=[1.0, 2.0]").unwrap();
        assert_eq!(r["a"]["b"]["c"].as_array().unwrap().len(), 2);
        // Inside an existing element of an array of tables.
        set_one(&mut r, "model.body.1.name=\"panel\"").unwrap();
        assert_eq!(r["model"]["body"][1]["name"].as_str(), Some("panel"));
        assert_eq!(r["model"]["body"][1]["mass"].as_float(), Some(2.5));
    }

    #[test]
    fn either_form_replaces_the_other() {
        let mut r: Table = toml::from_str(
            "armature = 0.001\n[initial.base]\nattitude = { euler_deg = [90.0, 0.0, 0.0], sequence = \"zyx\" }\n",
        )
        .unwrap();
        let attitude = |r: &Table| r["initial"]["base"]["attitude"].clone();
        set_one(&mut r, "initial.base.attitude=[1, 0, 0, 0]").unwrap();
        assert_eq!(attitude(&r).as_array().map(Vec::len), Some(4));
        // A table form's key replaces the quaternion, then the other table form's keys.
        set_one(&mut r, "initial.base.attitude.euler_deg=[0.0, 0.0, 10.0]").unwrap();
        set_one(&mut r, "initial.base.attitude.sequence=zyx").unwrap();
        let t = attitude(&r);
        let keys = |t: &Value| {
            let mut k: Vec<String> = t.as_table().unwrap().keys().cloned().collect();
            k.sort();
            k
        };
        assert_eq!(keys(&t), ["euler_deg", "sequence"]);
        set_one(&mut r, "initial.base.attitude.axis=[0.0, 0.0, 1.0]").unwrap();
        set_one(&mut r, "initial.base.attitude.angle_deg=30").unwrap();
        let t = attitude(&r);
        assert_eq!(keys(&t), ["angle_deg", "axis"]);
        set_one(
            &mut r,
            "initial.base.attitude={ euler_deg = [1.0, 2.0, 3.0], sequence = \"xyz\" }",
        )
        .unwrap();
        assert_eq!(attitude(&r)["sequence"].as_str(), Some("xyz"));
        // `armature`: one number or one per hinge.
        set_one(&mut r, "armature=[0.0, 1e-3]").unwrap();
        assert_eq!(r["armature"].as_array().map(Vec::len), Some(2));
        set_one(&mut r, "armature=0").unwrap();
        assert_eq!(r["armature"].as_float(), Some(0.0));
        // The estimator's star trackers: one name or a list of them.
        let mut f: Table = toml::from_str("[fsw.estimator]\nstar_tracker = \"st\"\n").unwrap();
        let trackers = |f: &Table| f["fsw"]["estimator"]["star_tracker"].clone();
        set_one(&mut f, "fsw.estimator.star_tracker=[\"st\", \"st2\"]").unwrap();
        assert_eq!(trackers(&f).as_array().map(Vec::len), Some(2));
        set_one(&mut f, "fsw.estimator.star_tracker=\"st2\"").unwrap();
        assert_eq!(trackers(&f).as_str(), Some("st2"));
        // Elsewhere the kinds still must match.
        let e = set_one(&mut r, "initial.base.attitude=\"identity\"").unwrap_err();
        assert!(e.0.contains("wrong type"), "{e}");
    }

    #[test]
    fn bad_overrides_name_the_key() {
        let mut r = root();
        for (s, why) in [
            ("model.body.2.mass=1", "out of range"),
            ("model.body.2.extra=1", "out of range"),
            ("model.body.x=1", "expected a position"),
            ("x.name.z=1", "`x.name` is a string, not a table"),
            (
                "x.v=1.0",
                "wrong type: the scene has an array there, got a number",
            ),
            (
                "x.n=1.5",
                "wrong type: the scene has an integer there, got a number",
            ),
            ("x.on=yes", "not a TOML value"),
            ("model.body.0.mass=\"heavy\"", "wrong type"),
            ("x.v", "expected KEY=VALUE"),
            ("new.table=", "is not a TOML value"),
            ("=3", "the key is empty"),
        ] {
            let e = set_one(&mut r, s).unwrap_err().0;
            assert!(e.contains(why), "{s}: {e}");
            if let Some((key, _)) = s.split_once('=')
                && !key.is_empty()
            {
                assert!(e.contains(key.trim()), "{s}: {e} does not name the key");
            }
        }
        // Nothing was changed by the refused overrides.
        assert_eq!(r, root());
    }
}
