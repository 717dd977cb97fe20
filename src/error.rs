//! The library's one error type.
//!
//! Every error a user can cause names the file, where in it (a line for text
//! formats, an element for binary ones) and what is wrong, so the message alone
//! tells them what to fix.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in a file a problem was found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Location {
    /// 1-based line of a text file.
    Line(usize),
    /// An element of a binary or structured file, e.g. "vertex 12", "byte 84".
    Element(String),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(n) => write!(f, "line {n}"),
            Location::Element(e) => f.write_str(e),
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The file could not be opened, read or written.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The file's content is malformed.
    #[error("{}: {}{msg}", path.display(), at.as_ref().map(|a| format!("{a}: ")).unwrap_or_default())]
    Format {
        path: PathBuf,
        at: Option<Location>,
        msg: String,
    },
    /// The data is well-formed but cannot be processed (a non-manifold edge,
    /// a mesh whose faces all have zero area, ...). `path` is filled in by
    /// callers that know which file the data came from.
    #[error("{}{msg}", path.as_ref().map(|p| format!("{}: ", p.display())).unwrap_or_default())]
    Invalid { path: Option<PathBuf>, msg: String },
    /// The mesh has elements a half-edge topology cannot hold. `first` names
    /// the first offending element, `summary` counts all of them;
    /// `mesh::repair::make_manifold` splits them.
    #[error("{}{first} ({summary})", path.as_ref().map(|p| format!("{}: ", p.display())).unwrap_or_default())]
    NotManifold {
        path: Option<PathBuf>,
        first: String,
        summary: String,
    },
    /// The user cancelled a long operation.
    #[error("cancelled")]
    Cancelled,
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    pub fn at_line(path: &Path, line: usize, msg: impl Into<String>) -> Self {
        Error::Format {
            path: path.to_path_buf(),
            at: Some(Location::Line(line)),
            msg: msg.into(),
        }
    }

    pub fn at_element(path: &Path, element: impl Into<String>, msg: impl Into<String>) -> Self {
        Error::Format {
            path: path.to_path_buf(),
            at: Some(Location::Element(element.into())),
            msg: msg.into(),
        }
    }

    pub fn format(path: &Path, msg: impl Into<String>) -> Self {
        Error::Format {
            path: path.to_path_buf(),
            at: None,
            msg: msg.into(),
        }
    }

    pub fn invalid(msg: impl Into<String>) -> Self {
        Error::Invalid {
            path: None,
            msg: msg.into(),
        }
    }

    /// `path`'s extension is none of `known`: "unknown KIND format '.x'
    /// (organtex VERB .a, .b)".
    pub fn unknown_format(path: &Path, kind: &str, verb: &str, known: &[&str]) -> Self {
        let ext = extension(path);
        let shown = if ext.is_empty() {
            "(no extension)".to_string()
        } else {
            format!(".{ext}")
        };
        let known: Vec<String> = known.iter().map(|e| format!(".{e}")).collect();
        Error::format(
            path,
            format!(
                "unknown {kind} format '{shown}' (organtex {verb} {})",
                known.join(", ")
            ),
        )
    }

    /// The error as one in `what` ("node 'uterus': tet mesh"), named before
    /// its message; a cancel stays a cancel (Ctrl-C is nobody's fault).
    pub fn within(self, what: impl std::fmt::Display) -> Self {
        match self {
            Error::Cancelled => self,
            e => Error::invalid(format!("{what}: {e}")),
        }
    }

    /// Attach the file the data came from, if the error does not name one yet.
    pub fn in_file(self, file: &Path) -> Self {
        match self {
            Error::Invalid { path: None, msg } => Error::Invalid {
                path: Some(file.to_path_buf()),
                msg,
            },
            Error::NotManifold {
                path: None,
                first,
                summary,
            } => Error::NotManifold {
                path: Some(file.to_path_buf()),
                first,
                summary,
            },
            other => other,
        }
    }
}

/// A file's extension in lower case ("" when it has none): what readers
/// and writers pick their format by.
pub fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}
