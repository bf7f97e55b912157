//! Output folders and writers: CSV tables with a header line, JSON summaries.
//!
//! Files are written to a temporary name and renamed into place, so an interrupted write never
//! leaves a truncated file that looks complete. An [`OutputDir`] refuses to write into a folder
//! that already holds results unless asked to overwrite.

use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Errors of the output layer.
#[derive(Debug, Error)]
pub enum OutputError {
    /// The folder already holds files and overwriting was not allowed.
    #[error(
        "output folder {0} already exists and is not empty; choose another --out, pass --force to overwrite, or --restart to continue"
    )]
    Exists(PathBuf),
    /// Columns of a table differ in length.
    #[error("table {file}: column '{column}' has {got} rows, expected {expected}")]
    Ragged {
        /// File being written.
        file: String,
        /// Offending column.
        column: String,
        /// Its length.
        got: usize,
        /// Length of the first column.
        expected: usize,
    },
    /// An I/O error with the path involved.
    #[error("{path}: {source}")]
    Io {
        /// Path involved.
        path: PathBuf,
        /// Underlying error.
        source: io::Error,
    },
    /// CSV encoding error.
    #[error("{path}: {source}")]
    Csv {
        /// Path involved.
        path: PathBuf,
        /// Underlying error.
        source: csv::Error,
    },
    /// JSON encoding error.
    #[error("{path}: {source}")]
    Json {
        /// Path involved.
        path: PathBuf,
        /// Underlying error.
        source: serde_json::Error,
    },
}

fn io_err(path: &Path) -> impl FnOnce(io::Error) -> OutputError + '_ {
    move |source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// A folder that receives a run's outputs.
#[derive(Debug, Clone)]
pub struct OutputDir {
    root: PathBuf,
}

impl OutputDir {
    /// Create (or, with `overwrite`, reuse) the folder `root`. A folder that exists and is
    /// not empty is refused unless `overwrite` is true.
    pub fn create(root: impl Into<PathBuf>, overwrite: bool) -> Result<Self, OutputError> {
        let root = root.into();
        if root.exists() {
            let non_empty = fs::read_dir(&root).map_err(io_err(&root))?.next().is_some();
            if non_empty && !overwrite {
                return Err(OutputError::Exists(root));
            }
        }
        fs::create_dir_all(&root).map_err(io_err(&root))?;
        Ok(Self { root })
    }

    /// Open an existing folder to continue writing into it (restarts).
    pub fn reopen(root: impl Into<PathBuf>) -> Result<Self, OutputError> {
        let root = root.into();
        fs::metadata(&root).map_err(io_err(&root))?;
        Ok(Self { root })
    }

    /// The folder's path.
    pub fn path(&self) -> &Path {
        &self.root
    }

    /// Path of `name` inside the folder.
    pub fn join(&self, name: &str) -> PathBuf {
        self.root.join(name)
    }

    /// Write `bytes` to `name` atomically (temporary file, then rename).
    pub fn write_bytes(&self, name: &str, bytes: &[u8]) -> Result<PathBuf, OutputError> {
        let path = self.join(name);
        write_atomic(&path, bytes)?;
        Ok(path)
    }

    /// Write a CSV table: a header line of column names, then one row per index.
    pub fn write_table(
        &self,
        name: &str,
        columns: &[(&str, &[f64])],
    ) -> Result<PathBuf, OutputError> {
        let bytes = table_bytes(name, columns)?;
        self.write_bytes(name, &bytes)
    }

    /// Write `value` as pretty JSON.
    pub fn write_json<T: serde::Serialize>(
        &self,
        name: &str,
        value: &T,
    ) -> Result<PathBuf, OutputError> {
        let path = self.join(name);
        let mut bytes = serde_json::to_vec_pretty(value).map_err(|source| OutputError::Json {
            path: path.clone(),
            source,
        })?;
        bytes.push(b'\n');
        self.write_bytes(name, &bytes)
    }
}

/// Write `bytes` to `path` through a temporary sibling and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let tmp = path.with_extension("partial");
    let written = (|| {
        let mut f = fs::File::create(&tmp).map_err(io_err(&tmp))?;
        f.write_all(bytes).map_err(io_err(&tmp))?;
        f.sync_all().map_err(io_err(&tmp))?;
        fs::rename(&tmp, path).map_err(io_err(path))
    })();
    if written.is_err() {
        // A full disk: leave no partial file behind (the previous file, if any, is intact).
        let _ = fs::remove_file(&tmp);
    }
    written
}

/// Encode columns as CSV with a header line. Numbers use Rust's shortest round-trip format.
pub fn table_bytes(name: &str, columns: &[(&str, &[f64])]) -> Result<Vec<u8>, OutputError> {
    let path = PathBuf::from(name);
    let rows = columns.first().map_or(0, |c| c.1.len());
    for (col, data) in columns {
        if data.len() != rows {
            return Err(OutputError::Ragged {
                file: name.to_string(),
                column: col.to_string(),
                got: data.len(),
                expected: rows,
            });
        }
    }
    let mut w = csv::Writer::from_writer(Vec::new());
    let csv_err = |source| OutputError::Csv {
        path: path.clone(),
        source,
    };
    w.write_record(columns.iter().map(|c| c.0))
        .map_err(csv_err)?;
    let mut rec = Vec::with_capacity(columns.len());
    for i in 0..rows {
        rec.clear();
        rec.extend(columns.iter().map(|c| c.1[i].to_string()));
        w.write_record(&rec).map_err(csv_err)?;
    }
    w.into_inner().map_err(|e| OutputError::Io {
        path: path.clone(),
        source: e.into_error(),
    })
}

/// Read a numeric CSV table with a header line; returns the header and the columns.
pub fn read_table(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>), String> {
    let mut r = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    let header: Vec<String> = r
        .headers()
        .map_err(|e| format!("{}: {e}", path.display()))?
        .iter()
        .map(str::to_string)
        .collect();
    let mut cols = vec![Vec::new(); header.len()];
    for (line, rec) in r.records().enumerate() {
        let rec = rec.map_err(|e| format!("{}: {e}", path.display()))?;
        for (j, field) in rec.iter().enumerate() {
            let v: f64 = field.parse().map_err(|_| {
                format!(
                    "{}: data row {}, column '{}': '{field}' is not a number",
                    path.display(),
                    line + 1,
                    header.get(j).map_or("?", |s| s.as_str())
                )
            })?;
            cols[j].push(v);
        }
    }
    Ok((header, cols))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_to_overwrite_and_round_trips_tables() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = OutputDir::create(tmp.path().join("out"), false).unwrap();
        let x = [0.1, 0.2, 1.0 / 3.0];
        let y = [1.0, 2.0, 3.0];
        let p = dir.write_table("t.csv", &[("x", &x), ("rho", &y)]).unwrap();
        let (h, c) = read_table(&p).unwrap();
        assert_eq!(h, vec!["x", "rho"]);
        assert_eq!(c[0], x.to_vec()); // bitwise round trip
        assert!(matches!(
            OutputDir::create(tmp.path().join("out"), false),
            Err(OutputError::Exists(_))
        ));
        assert!(OutputDir::create(tmp.path().join("out"), true).is_ok());
        assert!(
            dir.write_table("bad.csv", &[("x", &x), ("y", &y[..2])])
                .is_err()
        );
    }
}
