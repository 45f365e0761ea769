//! Errors of the file readers, and the byte spans and lines that locate them.

use crate::error::ModelError;
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why a model or state file could not be read. The message always starts with the file's
/// path and, where known, `:LINE` (1-based).
#[derive(Debug, Error)]
pub enum FileError {
    /// The file could not be read.
    #[error("{}: cannot read the file: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
    /// The file is empty (or holds only white space).
    #[error("{}: the file is empty", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// A TOML or JSON syntax error.
    #[error("{}: syntax error: {message}", Loc(path, *line))]
    Syntax {
        /// The file.
        path: PathBuf,
        /// The line, when known.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// Well-formed, but not the contract's schema: a missing required key, an unknown key, a
    /// value of the wrong type, an unknown `base.kind`.
    #[error("{}: {message}", Loc(path, *line))]
    Schema {
        /// The file.
        path: PathBuf,
        /// The line, when known.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// The model is inconsistent ([`ModelError`]), at the line of the body, hinge or key
    /// concerned.
    #[error("{}: {source}", Loc(path, *line))]
    Model {
        /// The file.
        path: PathBuf,
        /// The line, when known.
        line: Option<usize>,
        /// The builder's error.
        source: ModelError,
    },
    /// A state that does not fit the model (wrong array length, non-unit attitude,
    /// non-finite number).
    #[error("{}: {field}: {message}", path.display())]
    State {
        /// The state file (or the file holding the state table).
        path: PathBuf,
        /// The field, such as `hinges.angle`.
        field: String,
        /// What is wrong.
        message: String,
    },
}

impl FileError {
    /// The file concerned.
    pub fn path(&self) -> &Path {
        match self {
            FileError::Read { path, .. }
            | FileError::Empty { path }
            | FileError::Syntax { path, .. }
            | FileError::Schema { path, .. }
            | FileError::Model { path, .. }
            | FileError::State { path, .. } => path,
        }
    }
    /// The line concerned (1-based), when known.
    pub fn line(&self) -> Option<usize> {
        match self {
            FileError::Syntax { line, .. }
            | FileError::Schema { line, .. }
            | FileError::Model { line, .. } => *line,
            _ => None,
        }
    }
}

/// `path` or `path:line`.
struct Loc<'a>(&'a Path, Option<usize>);

impl fmt::Display for Loc<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.1 {
            Some(line) => write!(f, "{}:{line}", self.0.display()),
            None => write!(f, "{}", self.0.display()),
        }
    }
}

/// The 1-based line of byte `offset` in `text`.
pub fn line_of(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// An error of [`ModelFile::build`](super::ModelFile::build), located by a byte span in the
/// TOML text the [`ModelFile`](super::ModelFile) was read from. [`SpannedError::in_file`]
/// turns it into a [`FileError`].
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SpannedError {
    /// A required key is missing (`inertia` of a body with mass).
    #[error("{message}")]
    Schema {
        /// Where.
        span: Option<Range<usize>>,
        /// What is wrong.
        message: String,
    },
    /// The builder rejected the model.
    #[error("{error}")]
    Model {
        /// Where.
        span: Option<Range<usize>>,
        /// The builder's error.
        error: ModelError,
    },
}

impl SpannedError {
    /// The byte span concerned, when known.
    pub fn span(&self) -> Option<Range<usize>> {
        match self {
            SpannedError::Schema { span, .. } | SpannedError::Model { span, .. } => span.clone(),
        }
    }
    /// Names the file `origin` and the line in `text` (the text the model was read from).
    pub fn in_file(self, text: &str, origin: &Path) -> FileError {
        let line = self.span().map(|s| line_of(text, s.start));
        let path = origin.to_path_buf();
        match self {
            SpannedError::Schema { message, .. } => FileError::Schema {
                path,
                line,
                message,
            },
            SpannedError::Model { error, .. } => FileError::Model {
                path,
                line,
                source: error,
            },
        }
    }
}
