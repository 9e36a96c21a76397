//! `summary.json`.

use std::path::Path;

use serde_json::{json, Map, Value};

use super::{OutputError, Recorder};

/// Statistics of one column.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColumnStats {
    /// Smallest finite value (NaN if there is none).
    pub min: f64,
    /// Largest finite value (NaN if there is none).
    pub max: f64,
    /// Mean of the finite values (NaN if there is none).
    pub mean: f64,
    /// Value in the last row (NaN for an empty recorder).
    pub last: f64,
}

/// Statistics over `values`, skipping non-finite ones except for `last`.
pub(crate) fn stats(values: impl Iterator<Item = f64>) -> ColumnStats {
    let (mut min, mut max, mut sum, mut n, mut last) = (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0usize, f64::NAN);
    for v in values {
        last = v;
        if v.is_finite() {
            min = min.min(v);
            max = max.max(v);
            sum += v;
            n += 1;
        }
    }
    if n == 0 {
        return ColumnStats { min: f64::NAN, max: f64::NAN, mean: f64::NAN, last };
    }
    ColumnStats { min, max, mean: sum / n as f64, last }
}

/// A JSON number, or `null` when not finite.
fn num(x: f64) -> Value {
    serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)
}

pub(crate) fn write(rec: &Recorder, path: &Path, steps: u64, simulated_s: f64, wall_s: f64) -> Result<(), OutputError> {
    let mut probes = Map::new();
    for (i, name) in rec.columns().iter().enumerate() {
        let s = rec.stats(i);
        probes.insert(name.clone(), json!({ "min": num(s.min), "max": num(s.max), "mean": num(s.mean), "final": num(s.last) }));
    }
    let doc = json!({
        "probes": Value::Object(probes),
        "steps": steps,
        "simulated_s": num(simulated_s),
        "wall_s": num(wall_s),
        "real_time_factor": num(simulated_s / wall_s),
    });
    let mut text = serde_json::to_string_pretty(&doc).map_err(|source| OutputError::Json { path: path.to_path_buf(), source })?;
    text.push('\n');
    std::fs::write(path, text).map_err(|source| OutputError::Io { path: path.to_path_buf(), source })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_stats_skip_non_finite() {
        let s = stats([1.0, f64::NAN, 3.0, f64::INFINITY, 2.0].into_iter());
        assert_eq!((s.min, s.max, s.mean, s.last), (1.0, 3.0, 2.0, 2.0));
        let s = stats([f64::NAN].into_iter());
        assert!(s.min.is_nan() && s.mean.is_nan() && s.last.is_nan());
    }
}
