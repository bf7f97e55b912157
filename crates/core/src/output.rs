//! Output folders and writers: CSV tables with a header line, JSON summaries.
//!
//! Files are written to a temporary name and renamed into place, so an interrupted write never
//! leaves a truncated file that looks complete. An [`OutputDir`] refuses to write into a folder
//! that already holds results unless asked to overwrite.
//!
//! Every number is written finite or not at all: a value that is not finite (NaN, ±inf) is
//! written as an empty CSV field (JSON: `null`), never as `NaN` or `inf` text, and the writers
//! of an [`OutputDir`] record where they met one ([`NonFinite`]: file, column, rows), so that
//! the run's `summary.json` can say which quantities are missing and why.

use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
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

/// Where a writer met numbers that are not finite: they are written as empty fields.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct NonFinite {
    /// File, relative to the output folder.
    pub file: String,
    /// Column.
    pub column: String,
    /// How many rows hold a non-finite value in that column.
    pub rows: usize,
    /// The first such data row (0-based).
    pub first_row: usize,
    /// Why, where the method said ([`OutputDir::explain`]); else `None` (not written).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// The [`NonFinite`] entries of one output folder, shared by its clones and its logs.
#[derive(Debug, Clone, Default)]
pub struct NonFiniteRecord(Arc<Mutex<(Vec<NonFinite>, Vec<Reason>)>>);

/// The reason a method gave for a column's numbers that are not finite: file, column, reason.
type Reason = (String, String, String);

impl NonFiniteRecord {
    /// Replace what was recorded for `file` (a file written whole) by `found`.
    fn set_file(&self, file: &str, found: Vec<NonFinite>) {
        let v = &mut self.0.lock().unwrap_or_else(|e| e.into_inner()).0;
        v.retain(|n| n.file != file);
        v.extend(found);
    }

    /// Add rows appended to `file` (a log).
    fn add(&self, found: Vec<NonFinite>) {
        let v = &mut self.0.lock().unwrap_or_else(|e| e.into_inner()).0;
        for f in found {
            match v
                .iter_mut()
                .find(|n| n.file == f.file && n.column == f.column)
            {
                Some(n) => n.rows += f.rows,
                None => v.push(f),
            }
        }
    }

    /// Everything recorded, by file and column.
    pub fn entries(&self) -> Vec<NonFinite> {
        let (mut v, why) = self.0.lock().unwrap_or_else(|e| e.into_inner()).clone();
        v.sort_by(|a, b| (&a.file, &a.column).cmp(&(&b.file, &b.column)));
        for n in &mut v {
            n.reason = why
                .iter()
                .find(|(f, c, _)| *f == n.file && *c == n.column)
                .map(|w| w.2.clone());
        }
        v
    }
}

/// A folder that receives a run's outputs.
#[derive(Debug, Clone)]
pub struct OutputDir {
    root: PathBuf,
    non_finite: NonFiniteRecord,
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
        Ok(Self::at(root))
    }

    /// The folder another process writes (rank 0 of a run decomposed over MPI ranks): only its
    /// path, which nothing here touches.
    pub fn unwritten(root: impl Into<PathBuf>) -> Self {
        Self::at(root.into())
    }

    fn at(root: PathBuf) -> Self {
        Self {
            root,
            non_finite: NonFiniteRecord::default(),
        }
    }

    /// The numbers that were not finite in the tables written so far (written as empty
    /// fields), by file and column.
    pub fn non_finite(&self) -> Vec<NonFinite> {
        self.non_finite.entries()
    }

    /// Say why `column` of `file` may hold numbers that are not finite (e.g. "no colloids"):
    /// [`Self::non_finite`] gives the reason with the entry.
    pub fn explain(&self, file: &str, column: &str, reason: &str) {
        let w = &mut self
            .non_finite
            .0
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .1;
        w.retain(|(f, c, _)| !(f == file && c == column));
        w.push((file.into(), column.into(), reason.into()));
    }

    /// The reason given with [`Self::explain`] for `column` of `file`, if any (for
    /// `summary.json`, the column is the value's path, as `viscosity` or `momentum[2]`).
    pub fn reason(&self, file: &str, column: &str) -> Option<String> {
        let w = &self
            .non_finite
            .0
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .1;
        w.iter()
            .find(|(f, c, _)| f == file && c == column)
            .map(|w| w.2.clone())
    }

    /// The record the folder's writers add to (for a [`CsvLog`] of this folder).
    pub fn non_finite_record(&self) -> &NonFiniteRecord {
        &self.non_finite
    }

    /// Open an existing folder to continue writing into it (restarts).
    pub fn reopen(root: impl Into<PathBuf>) -> Result<Self, OutputError> {
        let root = root.into();
        fs::metadata(&root).map_err(io_err(&root))?;
        Ok(Self::at(root))
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
        let (bytes, found) = table_bytes_counted(name, columns)?;
        let path = self.write_bytes(name, &bytes)?;
        self.non_finite.set_file(name, found);
        Ok(path)
    }

    /// Write rows of `header.len()` numbers as a CSV table ([`rows_bytes`]).
    pub fn write_rows(
        &self,
        name: &str,
        header: &[&str],
        rows: &[Vec<f64>],
    ) -> Result<PathBuf, OutputError> {
        check_row_lengths(name, header, rows)?;
        let (bytes, found) = encode(name, Some(header), header.len(), rows.len(), |i, j| {
            rows[i][j]
        })?;
        let path = self.write_bytes(name, &bytes)?;
        self.non_finite.set_file(name, found);
        Ok(path)
    }

    /// Write `value` as pretty JSON (numbers that are not finite become `null`).
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

/// Encode columns as CSV with a header line. Numbers use Rust's shortest round-trip format;
/// a number that is not finite is an empty field.
pub fn table_bytes(name: &str, columns: &[(&str, &[f64])]) -> Result<Vec<u8>, OutputError> {
    Ok(table_bytes_counted(name, columns)?.0)
}

fn table_bytes_counted(
    name: &str,
    columns: &[(&str, &[f64])],
) -> Result<(Vec<u8>, Vec<NonFinite>), OutputError> {
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
    let header: Vec<&str> = columns.iter().map(|c| c.0).collect();
    encode(name, Some(&header), header.len(), rows, |i, j| {
        columns[j].1[i]
    })
}

/// The same CSV as [`table_bytes`], from rows of `header.len()` numbers.
pub fn rows_bytes(name: &str, header: &[&str], rows: &[Vec<f64>]) -> Result<Vec<u8>, OutputError> {
    check_row_lengths(name, header, rows)?;
    Ok(
        encode(name, Some(header), header.len(), rows.len(), |i, j| {
            rows[i][j]
        })?
        .0,
    )
}

fn check_row_lengths(name: &str, header: &[&str], rows: &[Vec<f64>]) -> Result<(), OutputError> {
    match rows.iter().position(|r| r.len() != header.len()) {
        Some(i) => Err(OutputError::Ragged {
            file: name.to_string(),
            column: format!("row {i}"),
            got: rows[i].len(),
            expected: header.len(),
        }),
        None => Ok(()),
    }
}

/// The CSV field of a number: Rust's shortest round-trip form, or empty when not finite.
pub fn field(x: f64) -> String {
    if x.is_finite() {
        x.to_string()
    } else {
        String::new()
    }
}

/// CSV records: the header (when given) and `rows` rows of `width` numbers `cell(row, column)`,
/// with the columns that held numbers that are not finite (named by the header, else by index).
fn encode(
    name: &str,
    header: Option<&[&str]>,
    width: usize,
    rows: usize,
    cell: impl Fn(usize, usize) -> f64,
) -> Result<(Vec<u8>, Vec<NonFinite>), OutputError> {
    let path = PathBuf::from(name);
    let mut w = csv::Writer::from_writer(Vec::new());
    let csv_err = |source| OutputError::Csv {
        path: path.clone(),
        source,
    };
    if let Some(h) = header {
        w.write_record(h).map_err(csv_err)?;
    }
    let mut rec = Vec::with_capacity(width);
    let mut found: Vec<Option<NonFinite>> = vec![None; width];
    for i in 0..rows {
        rec.clear();
        for (j, slot) in found.iter_mut().enumerate() {
            let x = cell(i, j);
            if !x.is_finite() {
                match slot {
                    Some(n) => n.rows += 1,
                    None => {
                        *slot = Some(NonFinite {
                            file: name.to_string(),
                            column: header
                                .and_then(|h| h.get(j))
                                .map_or_else(|| format!("column {j}"), |c| c.to_string()),
                            rows: 1,
                            first_row: i,
                            reason: None,
                        })
                    }
                }
            }
            rec.push(field(x));
        }
        w.write_record(&rec).map_err(csv_err)?;
    }
    let bytes = w.into_inner().map_err(|e| OutputError::Io {
        path: path.clone(),
        source: e.into_error(),
    })?;
    Ok((bytes, found.into_iter().flatten().collect()))
}

/// A CSV table written row by row while a run goes on, so that a user can follow it
/// (`tail -f`): each row is appended and handed to the operating system at once, as one
/// write. Unlike the other outputs it is not written atomically: a run that stops leaves
/// the rows written so far. The bytes are those [`rows_bytes`] gives for the same rows.
#[derive(Debug)]
pub struct CsvLog {
    path: PathBuf,
    header: Vec<String>,
    file: Option<fs::File>,
    /// The folder's record of numbers that are not finite, and the file's name in it.
    record: Option<(NonFiniteRecord, String)>,
    /// Data rows in the file.
    rows: usize,
}

impl CsvLog {
    /// The log `path` with these columns; nothing is written until the first row (a run that
    /// writes no row leaves no file).
    pub fn new(path: impl Into<PathBuf>, header: &[&str]) -> Self {
        Self {
            path: path.into(),
            header: header.iter().map(|h| h.to_string()).collect(),
            file: None,
            record: None,
            rows: 0,
        }
    }

    /// The log `name` of the folder `out` ([`Self::start`]); the numbers that are not finite
    /// in its rows are recorded with the folder's ([`OutputDir::non_finite`]).
    pub fn start_in(
        out: &OutputDir,
        name: &str,
        header: &[&str],
        fresh: bool,
        rows: impl FnOnce() -> Vec<Vec<f64>>,
    ) -> Result<Self, OutputError> {
        let mut log = Self::new(out.join(name), header);
        log.record = Some((out.non_finite.clone(), name.to_string()));
        if !fresh {
            log.reset(&rows())?;
        }
        Ok(log)
    }

    /// The log of a run continued from a checkpoint that kept `rows`: the file is brought to
    /// exactly those rows ([`Self::reset`]) and the next row is appended after them.
    pub fn resume(
        path: impl Into<PathBuf>,
        header: &[&str],
        rows: &[Vec<f64>],
    ) -> Result<Self, OutputError> {
        let mut log = Self::new(path, header);
        log.reset(rows)?;
        Ok(log)
    }

    /// A fresh run's log ([`Self::new`]), or a continued run's ([`Self::resume`]).
    pub fn start(
        path: impl Into<PathBuf>,
        header: &[&str],
        fresh: bool,
        rows: impl FnOnce() -> Vec<Vec<f64>>,
    ) -> Result<Self, OutputError> {
        if fresh {
            Ok(Self::new(path, header))
        } else {
            Self::resume(path, header, &rows())
        }
    }

    fn name(&self) -> String {
        self.path.display().to_string()
    }

    /// The file's name as the folder's record knows it.
    fn record_name(&self) -> String {
        self.record
            .as_ref()
            .map_or_else(|| self.name(), |(_, n)| n.clone())
    }

    /// Bring the file to exactly `rows` (a restart: rows a killed run wrote after its
    /// checkpoint are dropped), atomically; without rows the file is removed.
    pub fn reset(&mut self, rows: &[Vec<f64>]) -> Result<(), OutputError> {
        self.file = None;
        self.rows = 0;
        if let Some((r, name)) = &self.record {
            r.set_file(name, Vec::new());
        }
        if rows.is_empty() {
            match fs::remove_file(&self.path) {
                Err(e) if e.kind() != io::ErrorKind::NotFound => {
                    return Err(io_err(&self.path)(e));
                }
                _ => return Ok(()),
            }
        }
        let header: Vec<&str> = self.header.iter().map(String::as_str).collect();
        check_row_lengths(&self.name(), &header, rows)?;
        let (bytes, found) = encode(
            &self.record_name(),
            Some(&header),
            header.len(),
            rows.len(),
            |i, j| rows[i][j],
        )?;
        write_atomic(&self.path, &bytes)?;
        if let Some((r, name)) = &self.record {
            r.set_file(name, found);
        }
        self.rows = rows.len();
        self.file = Some(
            fs::OpenOptions::new()
                .append(true)
                .open(&self.path)
                .map_err(io_err(&self.path))?,
        );
        Ok(())
    }

    /// Append one row (the first creates the file with its header line).
    pub fn append(&mut self, row: &[f64]) -> Result<(), OutputError> {
        let name = self.name();
        if row.len() != self.header.len() {
            return Err(OutputError::Ragged {
                file: name,
                column: "appended row".into(),
                got: row.len(),
                expected: self.header.len(),
            });
        }
        let mut bytes = Vec::new();
        if self.file.is_none() {
            let header: Vec<&str> = self.header.iter().map(String::as_str).collect();
            bytes = encode(&name, Some(&header), 0, 0, |_, _| 0.0)?.0;
            self.file = Some(fs::File::create(&self.path).map_err(io_err(&self.path))?);
        }
        let (line, mut found) = encode(&name, None, row.len(), 1, |_, j| row[j])?;
        bytes.extend(line);
        if let Some((_, file)) = &self.record {
            for n in &mut found {
                n.file = file.clone();
                n.first_row = self.rows;
                let j = n
                    .column
                    .strip_prefix("column ")
                    .and_then(|j| j.parse::<usize>().ok());
                if let Some(name) = j.and_then(|j| self.header.get(j)) {
                    n.column = name.clone();
                }
            }
        }
        let f = self.file.as_mut().expect("opened above");
        f.write_all(&bytes).map_err(io_err(&self.path))?;
        if let Some((r, _)) = &self.record {
            r.add(found);
        }
        self.rows += 1;
        Ok(())
    }
}

/// Read a numeric CSV table with a header line; returns the header and the columns. An empty
/// field reads as NaN (what the writers write for a number that is not finite).
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
            // An empty field is a number that was not finite ([`field`]).
            if field.is_empty() {
                cols[j].push(f64::NAN);
                continue;
            }
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

    #[test]
    fn no_writer_lets_a_number_that_is_not_finite_through() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = OutputDir::create(tmp.path().join("out"), false).unwrap();
        let x = [0.5, 1.0, 1.5];
        let y = [f64::NAN, 2.0, f64::INFINITY];
        let p = dir.write_table("t.csv", &[("x", &x), ("y", &y)]).unwrap();
        let text = fs::read_to_string(&p).unwrap();
        assert_eq!(text, "x,y\n0.5,\n1,2\n1.5,\n");
        let rows = dir
            .write_rows("r.csv", &["a", "b"], &[vec![f64::NEG_INFINITY, 1.0]])
            .unwrap();
        assert_eq!(fs::read_to_string(&rows).unwrap(), "a,b\n,1\n");
        let mut log = CsvLog::start_in(&dir, "log.csv", &["s", "T"], true, Vec::new).unwrap();
        log.append(&[1.0, f64::NAN]).unwrap();
        log.append(&[2.0, 3.0]).unwrap();
        log.append(&[3.0, f64::NAN]).unwrap();
        assert_eq!(
            fs::read_to_string(dir.join("log.csv")).unwrap(),
            "s,T\n1,\n2,3\n3,\n"
        );
        let j = dir.write_json("s.json", &[f64::NAN, 1.0]).unwrap();
        let json = fs::read_to_string(&j).unwrap();
        assert!(!json.contains("NaN") && json.contains("null"), "{json}");
        dir.explain("log.csv", "T", "nothing to average");
        let entry = |file: &str, column: &str, rows, first_row| NonFinite {
            file: file.into(),
            column: column.into(),
            rows,
            first_row,
            reason: (file == "log.csv").then(|| "nothing to average".to_string()),
        };
        assert_eq!(
            dir.non_finite(),
            vec![
                entry("log.csv", "T", 2, 0),
                entry("r.csv", "a", 1, 0),
                entry("t.csv", "y", 2, 0),
            ]
        );
        // A file written again replaces its entries; the empty fields read back as NaN.
        dir.write_table("t.csv", &[("x", &x), ("y", &x)]).unwrap();
        assert_eq!(dir.non_finite().len(), 2);
        let (_, c) = read_table(&rows).unwrap();
        assert!(c[0][0].is_nan());
    }

    #[test]
    fn csv_log_is_readable_after_every_row_and_ends_as_the_table() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("thermo.csv");
        let header = ["step", "T"];
        let rows = [
            vec![10.0, 1.0 / 3.0],
            vec![20.0, f64::NAN],
            vec![30.0, 1e-300],
        ];
        let mut log = CsvLog::new(&path, &header);
        assert!(!path.exists(), "nothing is written before the first row");
        for (k, r) in rows.iter().enumerate() {
            log.append(r).unwrap();
            // Every row is on disk as soon as it is appended, with nothing after it.
            let now = fs::read(&path).unwrap();
            assert_eq!(now, rows_bytes("thermo.csv", &header, &rows[..=k]).unwrap());
        }
        let t: Vec<f64> = rows.iter().map(|r| r[1]).collect();
        let steps: Vec<f64> = rows.iter().map(|r| r[0]).collect();
        let table = table_bytes("thermo.csv", &[("step", &steps), ("T", &t)]).unwrap();
        assert_eq!(fs::read(&path).unwrap(), table);
        // A restart keeps the checkpoint's rows only, then appends after them.
        log.reset(&rows[..1]).unwrap();
        log.append(&rows[1]).unwrap();
        assert_eq!(
            fs::read(&path).unwrap(),
            rows_bytes("thermo.csv", &header, &rows[..2]).unwrap()
        );
        log.reset(&[]).unwrap();
        assert!(!path.exists());
        assert!(log.append(&[1.0]).is_err());
    }
}
