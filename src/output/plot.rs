//! `plot.png`: one panel per probe against time.
//!
//! Text uses DejaVu Sans embedded in the binary (`assets/fonts/`), so the
//! plot works on machines without system fonts.

use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use super::{OutputError, Recorder};

/// DejaVu Sans (license: `assets/fonts/DejaVuSans-LICENSE.txt`).
static DEJAVU_SANS: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Register the embedded font as plotters' `sans-serif` (once).
fn register() -> bool {
    static DONE: OnceLock<bool> = OnceLock::new();
    *DONE.get_or_init(|| register_font("sans-serif", FontStyle::Normal, DEJAVU_SANS).is_ok())
}

/// Line colours of the series in a panel.
const COLORS: [RGBColor; 6] =
    [RGBColor(31, 119, 180), RGBColor(214, 39, 40), RGBColor(44, 160, 44), RGBColor(148, 103, 189), RGBColor(255, 127, 14), RGBColor(23, 190, 207)];

/// Width and height of one panel, px.
const PANEL: (u32, u32) = (900, 300);

/// `lo..hi` of the finite values, padded; a usable range when there are
/// none or all are equal.
fn range(values: impl Iterator<Item = f64>, pad_fraction: f64) -> Range<f64> {
    let (lo, hi) = values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo > hi {
        return 0.0..1.0;
    }
    let span = hi - lo;
    if span <= 0.0 || !span.is_finite() {
        let pad = if lo == 0.0 || !lo.is_finite() { 1.0 } else { lo.abs() * 0.1 };
        return lo - pad..hi + pad;
    }
    lo - span * pad_fraction..hi + span * pad_fraction
}

/// Short tick labels.
fn tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if v.abs() >= 1e5 || v.abs() < 1e-3 {
        return format!("{v:.2e}");
    }
    let s = format!("{v:.4}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// The runs of consecutive finite points of column `index`.
fn runs(rec: &Recorder, index: usize) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    for (t, v) in rec.series(index) {
        if t.is_finite() && v.is_finite() {
            if let Some(run) = out.last_mut() {
                run.push((t, v));
            }
        } else if out.last().is_some_and(|r| !r.is_empty()) {
            out.push(Vec::new());
        }
    }
    out.retain(|r| !r.is_empty());
    out
}

pub(crate) fn write<S: AsRef<str>>(rec: &Recorder, path: &Path, panels: &[(S, Vec<usize>)]) -> Result<(), OutputError> {
    let columns = rec.columns().len();
    for (title, cols) in panels {
        if let Some(&index) = cols.iter().find(|&&c| c >= columns) {
            return Err(OutputError::Column { panel: title.as_ref().to_string(), index, columns });
        }
    }
    let fail = |e: &dyn std::fmt::Display| OutputError::Plot { path: path.to_path_buf(), message: e.to_string() };
    if !register() {
        return Err(fail(&"the embedded font could not be loaded"));
    }
    let n = panels.len().max(1);
    let grid_cols = if n > 4 { 2 } else { 1 };
    let grid_rows = n.div_ceil(grid_cols);
    let size = (PANEL.0 * grid_cols as u32, PANEL.1 * grid_rows as u32);
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(&e))?;
    let areas = root.split_evenly((grid_rows, grid_cols));
    let x_range = range(rec.rows().iter().filter_map(|r| r.first().copied()), 0.0);

    for (area, (title, cols)) in areas.iter().zip(panels) {
        let title = title.as_ref();
        let y_range = range(cols.iter().flat_map(|&c| rec.series(c).map(|(_, v)| v)), 0.05);
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(80)
            .build_cartesian_2d(x_range.clone(), y_range)
            .map_err(|e| fail(&e))?;
        chart
            .configure_mesh()
            .x_desc("time [s]")
            .y_desc(title)
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .draw()
            .map_err(|e| fail(&e))?;
        for (k, &c) in cols.iter().enumerate() {
            let color = COLORS[k % COLORS.len()];
            let name = rec.columns().get(c).cloned().unwrap_or_default();
            for (r, run) in runs(rec, c).into_iter().enumerate() {
                let anno = if run.len() == 1 {
                    chart.draw_series(run.into_iter().map(|p| Circle::new(p, 3, color.filled())))
                } else {
                    chart.draw_series(LineSeries::new(run, color.stroke_width(2)))
                }
                .map_err(|e| fail(&e))?;
                if r == 0 {
                    anno.label(name.clone()).legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
                }
            }
        }
        if cols.len() > 1 {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(|e| fail(&e))?;
        }
    }
    root.present().map_err(|e| fail(&e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_plot_ranges_are_usable() {
        assert_eq!(range([2.0, 2.0].into_iter(), 0.05), 1.8..2.2);
        assert_eq!(range([0.0].into_iter(), 0.05), -1.0..1.0);
        assert_eq!(range([f64::NAN].into_iter(), 0.05), 0.0..1.0);
        assert_eq!(range([0.0, 10.0, f64::INFINITY].into_iter(), 0.0), 0.0..10.0);
        assert_eq!(tick(2.50), "2.5");
        assert_eq!(tick(2e7), "2.00e7");
    }
}
