//! A time-aligned table of named signals, read from and written to CSV.
//!
//! The CSV contract (DESIGN.md §4.1): a header row, the first column is `time` (seconds as a
//! number), every other column is a named signal. Errors name the file, line and column so that
//! an engineer can find the bad cell in a historian export.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Errors from reading, building or writing a [`Table`].
#[derive(Debug, thiserror::Error)]
pub enum TableError {
    /// The file could not be opened or read.
    #[error("cannot read {path}: {source}")]
    Open {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The CSV layer failed (bad quoting, uneven rows, I/O).
    #[error("{path}: {source}")]
    Csv {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: csv::Error,
    },
    /// The header does not start with `time`.
    #[error("{path}: the first column must be `time`, found `{found}`")]
    NoTimeColumn {
        /// The file.
        path: PathBuf,
        /// What the header held instead.
        found: String,
    },
    /// A cell is not a number.
    #[error("{path}, line {line}, column `{column}`: `{value}` is not a number")]
    NotANumber {
        /// The file.
        path: PathBuf,
        /// The 1-based line number in the file (the header is line 1).
        line: u64,
        /// The column name.
        column: String,
        /// The cell's text.
        value: String,
    },
    /// A row has a different number of cells from the header.
    #[error("{path}, line {line}: {found} cells, the header has {expected}")]
    RaggedRow {
        /// The file.
        path: PathBuf,
        /// The 1-based line number.
        line: u64,
        /// Cells in the header.
        expected: usize,
        /// Cells in this row.
        found: usize,
    },
    /// A requested column is absent.
    #[error("no column `{name}`; the columns are: {available}")]
    NoSuchColumn {
        /// The requested name.
        name: String,
        /// The names that exist, comma separated.
        available: String,
    },
    /// A column was added with a length different from the time axis.
    #[error("column `{name}` has {found} values, the time axis has {expected}")]
    LengthMismatch {
        /// The column.
        name: String,
        /// Length of the time axis.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// A column name is used twice.
    #[error("column `{0}` appears twice")]
    DuplicateColumn(String),
    /// Writing failed.
    #[error("cannot write CSV: {0}")]
    Write(#[from] std::io::Error),
}

/// Named signals on a common time axis (seconds).
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    time: Vec<f64>,
    names: Vec<String>,
    columns: Vec<Vec<f64>>,
}

impl Table {
    /// An empty table on the given time axis.
    pub fn new(time: Vec<f64>) -> Self {
        Self { time, names: Vec::new(), columns: Vec::new() }
    }

    /// Adds a column; its length must equal the time axis and its name must be new.
    pub fn push_column(&mut self, name: impl Into<String>, values: Vec<f64>) -> Result<(), TableError> {
        let name = name.into();
        if values.len() != self.time.len() {
            return Err(TableError::LengthMismatch { name, expected: self.time.len(), found: values.len() });
        }
        if self.names.contains(&name) {
            return Err(TableError::DuplicateColumn(name));
        }
        self.names.push(name);
        self.columns.push(values);
        Ok(())
    }

    /// The time axis.
    pub fn time(&self) -> &[f64] {
        &self.time
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// True when the table has no rows.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// The signal names, in file order (without `time`).
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// One signal by name; the error lists the columns that do exist.
    pub fn column(&self, name: &str) -> Result<&[f64], TableError> {
        self.names.iter().position(|n| n == name).map(|i| self.columns[i].as_slice()).ok_or_else(|| {
            TableError::NoSuchColumn { name: name.to_string(), available: self.names.join(", ") }
        })
    }

    /// Reads a CSV file whose first column is `time`.
    pub fn read_csv(path: &Path) -> Result<Self, TableError> {
        let file = std::fs::File::open(path)
            .map_err(|source| TableError::Open { path: path.to_path_buf(), source })?;
        Self::from_reader(file, path)
    }

    /// Reads CSV text from any reader; `path` is only used in error messages.
    pub fn from_reader(reader: impl std::io::Read, path: &Path) -> Result<Self, TableError> {
        let csv_err = |source| TableError::Csv { path: path.to_path_buf(), source };
        let mut rdr = csv::ReaderBuilder::new().flexible(true).trim(csv::Trim::All).from_reader(reader);
        let header = rdr.headers().map_err(csv_err)?.clone();
        let first = header.get(0).unwrap_or("");
        if !first.eq_ignore_ascii_case("time") {
            return Err(TableError::NoTimeColumn { path: path.to_path_buf(), found: first.to_string() });
        }
        let names: Vec<String> = header.iter().skip(1).map(str::to_string).collect();
        for (i, n) in names.iter().enumerate() {
            if names[..i].contains(n) {
                return Err(TableError::DuplicateColumn(n.clone()));
            }
        }
        let mut time = Vec::new();
        let mut columns = vec![Vec::new(); names.len()];
        for (row, record) in rdr.records().enumerate() {
            let record = record.map_err(csv_err)?;
            let line = record.position().map_or(row as u64 + 2, |p| p.line());
            if record.len() != header.len() {
                return Err(TableError::RaggedRow {
                    path: path.to_path_buf(),
                    line,
                    expected: header.len(),
                    found: record.len(),
                });
            }
            for (c, cell) in record.iter().enumerate() {
                let value: f64 = cell.parse().map_err(|_| TableError::NotANumber {
                    path: path.to_path_buf(),
                    line,
                    column: header.get(c).unwrap_or("?").to_string(),
                    value: cell.to_string(),
                })?;
                if c == 0 {
                    time.push(value);
                } else {
                    columns[c - 1].push(value);
                }
            }
        }
        Ok(Self { time, names, columns })
    }

    /// Writes the table as CSV. Numbers use Rust's shortest round-trip form, so a table written
    /// and read back is bit-identical and one seed always gives the same bytes.
    pub fn write_csv(&self, mut out: impl Write) -> Result<(), TableError> {
        let mut line = String::from("time");
        for n in &self.names {
            line.push(',');
            line.push_str(n);
        }
        writeln!(out, "{line}")?;
        for r in 0..self.time.len() {
            line.clear();
            line.push_str(&self.time[r].to_string());
            for c in &self.columns {
                line.push(',');
                line.push_str(&c[r].to_string());
            }
            writeln!(out, "{line}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_is_exact() {
        let mut t = Table::new(vec![0.0, 0.1, 0.2]);
        t.push_column("u1", vec![1.0, -1.0, 1.0 / 3.0]).unwrap();
        t.push_column("e1", vec![1e-300, 2.5, -0.0]).unwrap();
        let mut buf = Vec::new();
        t.write_csv(&mut buf).unwrap();
        let back = Table::from_reader(buf.as_slice(), Path::new("mem.csv")).unwrap();
        assert_eq!(back, t);
    }

    #[test]
    fn errors_name_line_and_column() {
        let text = "time,u1,e1\n0,1,2\n1,x,3\n";
        let err = Table::from_reader(text.as_bytes(), Path::new("rec.csv")).unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("rec.csv") && msg.contains("line 3") && msg.contains("`u1`"), "{msg}");
        let err = Table::from_reader("t,u\n0,1\n".as_bytes(), Path::new("a.csv")).unwrap_err();
        assert!(matches!(err, TableError::NoTimeColumn { .. }));
        let err = Table::from_reader("time,u\n0,1,2\n".as_bytes(), Path::new("a.csv")).unwrap_err();
        assert!(matches!(err, TableError::RaggedRow { line: 2, .. }), "{err}");
    }

    #[test]
    fn missing_column_lists_the_others() {
        let mut t = Table::new(vec![0.0]);
        t.push_column("y1", vec![1.0]).unwrap();
        let msg = t.column("y2").unwrap_err().to_string();
        assert!(msg.contains("y2") && msg.contains("y1"), "{msg}");
        assert!(t.push_column("y3", vec![]).is_err());
        assert!(t.push_column("y1", vec![2.0]).is_err());
    }
}
