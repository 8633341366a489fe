//! Reading CSV input by column name, with errors that name the file, the line and the column.

use crate::VizError;
use std::path::{Path, PathBuf};

/// A CSV file opened for reading, its header known.
pub struct CsvInput {
    pub path: PathBuf,
    pub headers: Vec<String>,
    reader: csv::Reader<Box<dyn std::io::Read>>,
}

impl CsvInput {
    pub fn open(path: &Path) -> Result<CsvInput, VizError> {
        let file = mapc_graph::input::open(path).map_err(|source| VizError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        CsvInput::from_reader(path, Box::new(file))
    }

    /// CSV text from any reader (a trace made in memory); `path` names it in errors.
    pub fn from_reader(path: &Path, input: Box<dyn std::io::Read>) -> Result<CsvInput, VizError> {
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(true)
            .flexible(false)
            .from_reader(input);
        let headers: Vec<String> = reader
            .headers()
            .map_err(|e| csv_error(path, e))?
            .iter()
            .map(|h| h.trim().to_string())
            .collect();
        if headers.iter().all(|h| h.is_empty()) {
            return Err(VizError::Input {
                path: path.to_path_buf(),
                message: "empty file: no CSV header".into(),
            });
        }
        Ok(CsvInput {
            path: path.to_path_buf(),
            headers,
            reader,
        })
    }

    /// The column's index, if the header has it.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.headers.iter().position(|h| h == name)
    }

    /// The indices of `names`, or an error listing every missing one and the header found.
    pub fn require(&self, names: &[&str]) -> Result<Vec<usize>, VizError> {
        let missing: Vec<&str> = names
            .iter()
            .copied()
            .filter(|n| self.column(n).is_none())
            .collect();
        if !missing.is_empty() {
            return Err(VizError::Input {
                path: self.path.clone(),
                message: format!(
                    "line 1: missing column{} {} (header is `{}`)",
                    if missing.len() > 1 { "s" } else { "" },
                    missing
                        .iter()
                        .map(|m| format!("`{m}`"))
                        .collect::<Vec<_>>()
                        .join(", "),
                    self.headers.join(",")
                ),
            });
        }
        Ok(names
            .iter()
            .map(|n| self.column(n).expect("checked above"))
            .collect())
    }

    /// Call `each` with every data row and its line number.
    pub fn for_each_row(
        &mut self,
        mut each: impl FnMut(&csv::StringRecord, u64) -> Result<(), VizError>,
    ) -> Result<(), VizError> {
        let mut record = csv::StringRecord::new();
        loop {
            match self.reader.read_record(&mut record) {
                Ok(true) => {
                    let line = record.position().map_or(0, |p| p.line());
                    // A blank trailing line reads as one empty field; it is not data.
                    if record.len() == 1 && record[0].trim().is_empty() {
                        continue;
                    }
                    each(&record, line)?;
                }
                Ok(false) => return Ok(()),
                Err(e) => return Err(csv_error(&self.path, e)),
            }
        }
    }

    /// Field parsers that do not borrow the reader, for use inside [`CsvInput::for_each_row`].
    pub fn fields(&self) -> Fields {
        Fields {
            path: self.path.clone(),
        }
    }
}

/// Parsing of single fields, every error naming the file, line and column.
#[derive(Clone, Debug)]
pub struct Fields {
    pub path: PathBuf,
}

impl Fields {
    /// A number in column `name` (index `idx`); `None` when the field is empty.
    pub fn number(
        &self,
        record: &csv::StringRecord,
        idx: usize,
        name: &str,
        line: u64,
    ) -> Result<Option<f64>, VizError> {
        let text = record.get(idx).unwrap_or("").trim();
        if text.is_empty() {
            return Ok(None);
        }
        text.parse::<f64>()
            .map(Some)
            .map_err(|_| self.error(line, name, format!("`{text}` is not a number")))
    }

    /// Like [`Fields::number`] but the field must be there and finite.
    pub fn required(
        &self,
        record: &csv::StringRecord,
        idx: usize,
        name: &str,
        line: u64,
    ) -> Result<f64, VizError> {
        match self.number(record, idx, name, line)? {
            Some(v) if v.is_finite() => Ok(v),
            Some(v) => Err(self.error(line, name, format!("`{v}` is not a finite number"))),
            None => Err(self.error(line, name, "empty field".to_string())),
        }
    }

    /// `true`/`false` (also `1`/`0`, any case; empty is false).
    pub fn boolean(
        &self,
        record: &csv::StringRecord,
        idx: usize,
        name: &str,
        line: u64,
    ) -> Result<bool, VizError> {
        let text = record.get(idx).unwrap_or("").trim();
        match text.to_ascii_lowercase().as_str() {
            "true" | "1" => Ok(true),
            "false" | "0" | "" => Ok(false),
            _ => Err(self.error(line, name, format!("`{text}` is not true or false"))),
        }
    }

    pub fn error(&self, line: u64, column: &str, message: String) -> VizError {
        VizError::Field {
            path: self.path.clone(),
            line,
            column: column.to_string(),
            message,
        }
    }
}

fn csv_error(path: &Path, e: csv::Error) -> VizError {
    let line = e.position().map(|p| p.line());
    let message = match e.kind() {
        csv::ErrorKind::UnequalLengths {
            expected_len, len, ..
        } => {
            format!("{len} fields where the header has {expected_len}")
        }
        csv::ErrorKind::Utf8 { .. } => "not UTF-8 text".to_string(),
        csv::ErrorKind::Io(io) => io.to_string(),
        _ => e.to_string(),
    };
    match line {
        Some(line) => VizError::Input {
            path: path.to_path_buf(),
            message: format!("line {line}: {message}"),
        },
        None => VizError::Input {
            path: path.to_path_buf(),
            message,
        },
    }
}
