//! Import errors: every one names the file and, where there is one, the place (line, column, byte, element, id).

use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: the file is empty")]
    Empty { path: PathBuf },
    /// A problem at a known place in the input: `line 12, column 5 (byte 345), in <way id="7">`.
    #[error("{path}: {place}: {message}")]
    At {
        path: PathBuf,
        place: String,
        message: String,
    },
    /// A problem with the file as a whole (wrong kind of file, nothing to import, a bad option).
    #[error("{path}: {message}")]
    Unsupported { path: PathBuf, message: String },
    #[error(transparent)]
    Graph(#[from] mapc_graph::GraphFileError),
}

impl ImportError {
    pub(crate) fn io(path: &Path, source: std::io::Error) -> ImportError {
        ImportError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
    pub(crate) fn unsupported(path: &Path, message: impl Into<String>) -> ImportError {
        ImportError::Unsupported {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

/// A parse error before it is tied to a file: the byte offset is turned into a line and column by [`Located`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ParseError {
    pub byte: u64,
    /// The element being read, e.g. `<node id="42">`.
    pub element: Option<String>,
    pub message: String,
}

impl ParseError {
    pub fn new(byte: u64, element: Option<String>, message: impl Into<String>) -> ParseError {
        ParseError {
            byte,
            element,
            message: message.into(),
        }
    }
}

/// Line (1-based) and column (1-based, in bytes) of a byte offset in `text`.
pub(crate) fn line_and_column(text: &[u8], byte: u64) -> (usize, usize) {
    let end = (byte as usize).min(text.len());
    let before = &text[..end];
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |p| p + 1);
    (line, end - line_start + 1)
}

/// Where the input came from, to turn byte offsets into lines when an error is reported.
pub(crate) enum Located<'a> {
    File(&'a Path),
    Bytes(&'a Path, &'a [u8]),
}

impl Located<'_> {
    pub fn path(&self) -> &Path {
        match self {
            Located::File(p) | Located::Bytes(p, _) => p,
        }
    }

    pub fn error(&self, e: ParseError) -> ImportError {
        let (line, column) = match self {
            // Reading the file again only happens on the error path, so the happy path stays streaming.
            Located::File(p) => match mapc_graph::input::read(p) {
                Ok(text) => line_and_column(&text, e.byte),
                Err(_) => (0, 0),
            },
            Located::Bytes(_, text) => line_and_column(text, e.byte),
        };
        let mut place = if line > 0 {
            format!("line {line}, column {column} (byte {})", e.byte)
        } else {
            format!("byte {}", e.byte)
        };
        if let Some(el) = e.element {
            place.push_str(&format!(", in {el}"));
        }
        ImportError::At {
            path: self.path().to_path_buf(),
            place,
            message: e.message,
        }
    }
}
