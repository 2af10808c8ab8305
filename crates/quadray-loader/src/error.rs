//! The loader's error: which file, where in it, and what is wrong.

use std::fmt;
use std::path::{Path, PathBuf};

/// A line and column in a text file, both 1-based.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Location {
    /// Line number, from 1.
    pub line: usize,
    /// Column number (in characters), from 1.
    pub column: usize,
}

impl Location {
    /// The location of byte `offset` in `text`.
    pub fn from_offset(text: &str, offset: usize) -> Location {
        let offset = offset.min(text.len());
        let before = &text[..text.floor_char_boundary(offset)];
        let line = before.matches('\n').count() + 1;
        let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        Location { line, column }
    }
}

/// What went wrong while loading.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LoadErrorKind {
    /// The file could not be read.
    #[error("cannot read the file: {0}")]
    Io(#[source] std::io::Error),
    /// The file is not well-formed (TOML syntax, wrong type, unknown key).
    #[error("{0}")]
    Syntax(String),
    /// A value is well-formed but not acceptable.
    #[error("`{key}`: {message}")]
    Invalid {
        /// The key (dotted path) holding the bad value.
        key: String,
        /// What is wrong with it.
        message: String,
    },
    /// A feature of the file format that quadray does not support.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// A file this one refers to (a glTF buffer, a mesh file) could not be read.
    #[error("cannot read {what} `{}`: {source}", path.display())]
    Referenced {
        /// What the file is for ("buffer 0", "mesh file").
        what: String,
        /// The resolved path that was tried.
        path: PathBuf,
        /// Why it could not be read.
        #[source]
        source: std::io::Error,
    },
    /// A command-line override (`--set KEY=VALUE`) names no place the file has: a usage error of
    /// the command line rather than of the file.
    #[error("{set}: {message}")]
    Override {
        /// The override as given (`--set sphere[9].radius=2`).
        set: String,
        /// Why it cannot be applied.
        message: String,
    },
    /// A file included by a scene failed to load; `source` names that file and its problem.
    #[error("`{key}`: {source}")]
    Include {
        /// The key holding the include's path.
        key: String,
        /// The included file's own error.
        source: Box<LoadError>,
    },
}

/// An error loading a scene or asset file.
#[derive(Debug)]
pub struct LoadError {
    /// The file the error is in.
    pub path: PathBuf,
    /// Where in the file, when known.
    pub location: Option<Location>,
    /// What went wrong.
    pub kind: LoadErrorKind,
}

impl LoadError {
    /// An error in `path` at an optional location.
    pub fn new(path: &Path, location: Option<Location>, kind: LoadErrorKind) -> LoadError {
        LoadError {
            path: path.to_path_buf(),
            location,
            kind,
        }
    }

    /// An `Invalid` error for `key` at `location`.
    pub fn invalid(
        path: &Path,
        location: Option<Location>,
        key: impl Into<String>,
        message: impl Into<String>,
    ) -> LoadError {
        LoadError::new(
            path,
            location,
            LoadErrorKind::Invalid {
                key: key.into(),
                message: message.into(),
            },
        )
    }
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(l) = self.location {
            write!(f, ":{}:{}", l.line, l.column)?;
        }
        write!(f, ": {}", self.kind)
    }
}

/// No `source()`: the message already ends with the cause (the I/O error, the included file's own
/// error), so a printer that walks the chain (anyhow's `{:#}`) would say it twice. The cause is
/// still there to match on in [`LoadError::kind`].
impl std::error::Error for LoadError {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locations_count_lines_and_columns_from_one() {
        let text = "a = 1\nbb = 2\n";
        assert_eq!(
            Location::from_offset(text, 0),
            Location { line: 1, column: 1 }
        );
        assert_eq!(
            Location::from_offset(text, 8),
            Location { line: 2, column: 3 }
        );
        assert_eq!(
            Location::from_offset(text, 999),
            Location { line: 3, column: 1 }
        );
    }

    #[test]
    fn display_names_file_line_and_key() {
        let e = LoadError::invalid(
            Path::new("s.toml"),
            Some(Location { line: 3, column: 5 }),
            "sphere[0].radius",
            "must be positive",
        );
        assert_eq!(
            e.to_string(),
            "s.toml:3:5: `sphere[0].radius`: must be positive"
        );
    }
}
