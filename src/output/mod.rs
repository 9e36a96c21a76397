//! Result files: `results.csv`, `summary.json` and `plot.png`.
//!
//! A [`Recorder`] collects one row per output instant (time first, then one
//! value per column) and writes the files of the `cablesim run` contract.
//! Non-finite values are kept in the CSV (as `NaN`, `inf`) and skipped by the
//! statistics and the plot, so the rows computed before a divergence can
//! still be written.

mod plot;
mod summary;

use std::path::{Path, PathBuf};

pub use self::summary::ColumnStats;

/// An error while writing a result file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// The file could not be created or written.
    #[error("cannot write {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The CSV writer failed.
    #[error("cannot write {}: {source}", path.display())]
    Csv {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: csv::Error,
    },
    /// JSON serialisation failed.
    #[error("cannot write {}: {source}", path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: serde_json::Error,
    },
    /// Drawing or encoding the plot failed.
    #[error("cannot draw {}: {message}", path.display())]
    Plot {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A row with the wrong number of values was pushed.
    #[error("row has {found} values, expected {expected} (one per column)")]
    RowLength {
        /// Number of columns.
        expected: usize,
        /// Number of values given.
        found: usize,
    },
    /// A plot panel names a column that does not exist.
    #[error("plot panel `{panel}` refers to column {index}, but there are {columns} columns")]
    Column {
        /// The panel title.
        panel: String,
        /// The bad column index.
        index: usize,
        /// Number of columns.
        columns: usize,
    },
}

/// `results.csv` written row by row ([`Recorder::stream_csv`]).
#[derive(Debug)]
pub struct CsvStream {
    w: csv::Writer<std::fs::File>,
    path: PathBuf,
}

impl CsvStream {
    /// Writes the row `time, values…` and flushes it to the file.
    pub fn append(&mut self, time: f64, values: &[f64]) -> Result<(), OutputError> {
        let mut row = Vec::with_capacity(values.len() + 1);
        row.push(time);
        row.extend_from_slice(values);
        self.write(&row)?;
        self.flush()
    }

    /// Writes one full row (time first), buffered.
    fn write(&mut self, row: &[f64]) -> Result<(), OutputError> {
        self.w.write_record(row.iter().map(|x| x.to_string())).map_err(|source| OutputError::Csv { path: self.path.clone(), source })
    }

    fn flush(&mut self) -> Result<(), OutputError> {
        self.w.flush().map_err(|source| OutputError::Io { path: self.path.clone(), source })
    }
}

/// Rows of recorded values against time.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Recorder {
    columns: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Recorder {
    /// An empty recorder for `columns` (the names after `time`).
    pub fn new(columns: Vec<String>) -> Self {
        Recorder { columns, rows: Vec::new() }
    }

    /// Column names after `time`.
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// The rows, each `[time, value per column...]`.
    pub fn rows(&self) -> &[Vec<f64>] {
        &self.rows
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// True if no row was pushed.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Append a row at `time` with one value per column.
    pub fn push_row(&mut self, time: f64, values: &[f64]) -> Result<(), OutputError> {
        if values.len() != self.columns.len() {
            return Err(OutputError::RowLength { expected: self.columns.len(), found: values.len() });
        }
        let mut row = Vec::with_capacity(values.len() + 1);
        row.push(time);
        row.extend_from_slice(values);
        self.rows.push(row);
        Ok(())
    }

    /// `(time, value)` of column `index` (0 = first column after `time`),
    /// all rows including non-finite values.
    pub fn series(&self, index: usize) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.rows.iter().filter_map(move |r| Some((*r.first()?, *r.get(index + 1)?)))
    }

    /// One plot panel per probe: columns `NAME.x`, `NAME.y`, `NAME.z` that
    /// follow each other share a panel titled `NAME`; every other column has
    /// its own panel.
    pub fn default_panels(&self) -> Vec<(String, Vec<usize>)> {
        let mut panels: Vec<(String, Vec<usize>)> = Vec::new();
        let mut i = 0;
        while i < self.columns.len() {
            let name = &self.columns[i];
            let stem = name.strip_suffix(".x");
            let is_vec = stem.is_some_and(|s| {
                self.columns.get(i + 1).is_some_and(|c| *c == format!("{s}.y")) && self.columns.get(i + 2).is_some_and(|c| *c == format!("{s}.z"))
            });
            match stem {
                Some(s) if is_vec => {
                    panels.push((s.to_string(), vec![i, i + 1, i + 2]));
                    i += 3;
                }
                _ => {
                    panels.push((name.clone(), vec![i]));
                    i += 1;
                }
            }
        }
        panels
    }

    /// Write `results.csv`: header `time,<columns>`, then one line per row.
    pub fn write_csv(&self, path: &Path) -> Result<(), OutputError> {
        let mut stream = self.stream_csv(path)?;
        for row in &self.rows {
            stream.write(row)?;
        }
        stream.flush()
    }

    /// Starts `results.csv` at `path` for streaming: writes the header now
    /// and each row as it is appended ([`CsvStream::append`]), so an
    /// interrupted run keeps the rows made so far. Same format as
    /// [`Recorder::write_csv`].
    pub fn stream_csv(&self, path: &Path) -> Result<CsvStream, OutputError> {
        let csv_err = |source| OutputError::Csv { path: path.to_path_buf(), source };
        let mut w = csv::Writer::from_path(path).map_err(csv_err)?;
        let header = std::iter::once("time").chain(self.columns.iter().map(String::as_str));
        w.write_record(header).map_err(csv_err)?;
        let mut stream = CsvStream { w, path: path.to_path_buf() };
        stream.flush()?;
        Ok(stream)
    }

    /// Write `summary.json`: min/max/mean/final per column, the number of
    /// steps, simulated and wall-clock seconds and their ratio.
    pub fn write_summary(&self, path: &Path, steps: u64, simulated_s: f64, wall_s: f64) -> Result<(), OutputError> {
        summary::write(self, path, steps, simulated_s, wall_s)
    }

    /// Statistics of column `index` over its finite values (`final` is the
    /// last row's value, finite or not).
    pub fn stats(&self, index: usize) -> ColumnStats {
        summary::stats(self.series(index).map(|(_, v)| v))
    }

    /// Write `plot.png`: one panel per entry of `panels` (title, column
    /// indices as in [`Recorder::series`]) against time, a legend where a
    /// panel has several columns. Non-finite points are skipped.
    pub fn write_plot<S: AsRef<str>>(&self, path: &Path, panels: &[(S, Vec<usize>)]) -> Result<(), OutputError> {
        plot::write(self, path, panels)
    }
}
