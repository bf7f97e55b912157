//! Pictures of the main observables (PNG, text rendered with the embedded DejaVu Sans font).

use anyhow::{Result, anyhow};
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

static REGISTER: Once = Once::new();

fn register_font() {
    REGISTER.call_once(|| {
        // The font is embedded, so registration cannot fail for a missing file.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// One curve of a line plot.
pub struct Series<'a> {
    /// Legend label.
    pub label: &'a str,
    /// Abscissae.
    pub x: &'a [f64],
    /// Ordinates.
    pub y: &'a [f64],
    /// Draw points instead of a line.
    pub points: bool,
}

/// Axis scaling.
#[derive(Clone, Copy, PartialEq)]
pub enum Scale {
    /// Linear axes.
    Linear,
    /// Both axes logarithmic.
    LogLog,
}

const COLOURS: [RGBColor; 5] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
];

/// Draw `series` into a PNG at `path` (800x500 px). The picture is drawn under a temporary
/// name and renamed into place, so a failed or interrupted drawing never leaves a truncated
/// picture under the final name.
pub fn line_plot(
    path: &Path,
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[Series],
    scale: Scale,
) -> Result<()> {
    line_plot_with_errors(path, title, xlabel, ylabel, series, &[], scale)
}

/// [`line_plot`] with error bars: `errors[k]`, when given, holds the standard error of each
/// point of `series[k]`, drawn as a vertical bar `y +- err` (on a log axis a bar reaching zero
/// is cut at `y / 100`).
pub fn line_plot_with_errors(
    path: &Path,
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[Series],
    errors: &[Option<&[f64]>],
    scale: Scale,
) -> Result<()> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    // The extension stays .png: the encoder is chosen by it.
    let tmp = path.with_file_name(format!(".{name}.partial.png"));
    let drawn = draw_line_plot(&tmp, title, xlabel, ylabel, series, errors, scale)
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| anyhow!("{}: {e}", path.display())));
    if drawn.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    drawn.map_err(|e| anyhow!("{}: {e:#}", path.display()))
}

fn draw_line_plot(
    path: &Path,
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[Series],
    errors: &[Option<&[f64]>],
    scale: Scale,
) -> Result<()> {
    register_font();
    let finite = |v: f64| v.is_finite() && (scale == Scale::Linear || v > 0.0);
    let mut xr = (f64::INFINITY, f64::NEG_INFINITY);
    let mut yr = (f64::INFINITY, f64::NEG_INFINITY);
    for s in series {
        for (&x, &y) in s.x.iter().zip(s.y) {
            if finite(x) && finite(y) {
                xr = (xr.0.min(x), xr.1.max(x));
                yr = (yr.0.min(y), yr.1.max(y));
            }
        }
    }
    if xr.0 >= xr.1 {
        return Err(anyhow!("no finite data to draw"));
    }
    if yr.0 >= yr.1 {
        yr = flat_range(yr.0);
    }
    let root = BitMapBackend::new(path, (800, 500)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| anyhow!("plot: {e}"))?;
    macro_rules! draw {
        ($chart:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .x_desc(xlabel)
                .y_desc(ylabel)
                .label_style(("sans-serif", 16))
                .draw()
                .map_err(|e| anyhow!("plot: {e}"))?;
            for (k, s) in series.iter().enumerate() {
                let c = COLOURS[k % COLOURS.len()];
                if let Some(Some(err)) = errors.get(k) {
                    let bars =
                        s.x.iter()
                            .zip(s.y)
                            .zip(err.iter())
                            .filter(|((x, y), e)| finite(**x) && finite(**y) && e.is_finite())
                            .map(|((x, y), e)| {
                                let lo = if scale == Scale::LogLog && y - e <= 0.0 {
                                    0.01 * y
                                } else {
                                    y - e
                                };
                                PathElement::new(vec![(*x, lo), (*x, y + e)], c.stroke_width(1))
                            });
                    chart.draw_series(bars).map_err(|e| anyhow!("plot: {e}"))?;
                }
                let data =
                    s.x.iter()
                        .zip(s.y)
                        .filter(|(x, y)| finite(**x) && finite(**y))
                        .map(|(x, y)| (*x, *y));
                if s.points {
                    chart
                        .draw_series(data.map(|p| Circle::new(p, 2, c.filled())))
                        .map_err(|e| anyhow!("plot: {e}"))?
                        .label(s.label)
                        .legend(move |(x, y)| Circle::new((x + 10, y), 3, c.filled()));
                } else {
                    chart
                        .draw_series(LineSeries::new(data, c.stroke_width(2)))
                        .map_err(|e| anyhow!("plot: {e}"))?
                        .label(s.label)
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                        });
                }
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .label_font(("sans-serif", 16))
                .draw()
                .map_err(|e| anyhow!("plot: {e}"))?;
        }};
    }
    let mut builder = ChartBuilder::on(&root);
    builder
        .caption(title, ("sans-serif", 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70);
    match scale {
        Scale::Linear => {
            let pad = 0.05 * (yr.1 - yr.0);
            draw!(
                builder
                    .build_cartesian_2d(xr.0..xr.1, (yr.0 - pad)..(yr.1 + pad))
                    .map_err(|e| anyhow!("plot: {e}"))?
            )
        }
        Scale::LogLog => draw!(
            builder
                .build_cartesian_2d(
                    (xr.0..xr.1).log_scale(),
                    (yr.0 * 0.8..yr.1 * 1.25).log_scale()
                )
                .map_err(|e| anyhow!("plot: {e}"))?
        ),
    }
    root.present().map_err(|e| anyhow!("plot: {e}"))?;
    Ok(())
}

/// One disc of a cross-section: centre and radius in data units, and which colour (an index
/// into the palette).
pub struct Disc {
    /// Centre.
    pub x: f64,
    /// Centre.
    pub y: f64,
    /// Radius.
    pub r: f64,
    /// Colour index.
    pub colour: usize,
}

/// Draw `discs` (e.g. the sections of spheres cut by a slab) inside a circle of radius `outline`
/// centred on the origin, with equal scales on both axes, into a square PNG at `path`
/// (600x600 px; drawn under a temporary name and renamed into place).
pub fn cross_section(path: &Path, title: &str, discs: &[Disc], outline: f64) -> Result<()> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.partial.png"));
    let drawn = draw_cross_section(&tmp, title, discs, outline)
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| anyhow!("{}: {e}", path.display())));
    if drawn.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    drawn.map_err(|e| anyhow!("{}: {e:#}", path.display()))
}

fn draw_cross_section(path: &Path, title: &str, discs: &[Disc], outline: f64) -> Result<()> {
    register_font();
    let reach = discs
        .iter()
        .map(|d| d.x.abs().max(d.y.abs()) + d.r)
        .fold(outline, f64::max);
    if !(reach.is_finite() && reach > 0.0) {
        return Err(anyhow!("no finite data to draw"));
    }
    let e = |e| anyhow!("plot: {e}");
    let lim = 1.05 * reach;
    let root = BitMapBackend::new(path, (600, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(-lim..lim, -lim..lim)
        .map_err(e)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x")
        .y_desc("y")
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(e)?;
    let ring = |x: f64, y: f64, r: f64, k: usize| -> Vec<(f64, f64)> {
        (0..k)
            .map(|i| {
                let t = 2.0 * std::f64::consts::PI * i as f64 / k as f64;
                (x + r * t.cos(), y + r * t.sin())
            })
            .collect()
    };
    chart
        .draw_series(discs.iter().map(|d| {
            let c = COLOURS[d.colour % COLOURS.len()];
            Polygon::new(ring(d.x, d.y, d.r, 24), c.mix(0.85).filled())
        }))
        .map_err(e)?;
    let mut edge = ring(0.0, 0.0, outline, 360);
    edge.push(edge[0]);
    chart
        .draw_series(std::iter::once(PathElement::new(
            edge,
            BLACK.stroke_width(2),
        )))
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}

/// A picture is a companion of the data: when it cannot be drawn (say, no finite value), the
/// run's tables stand and a warning says so; `name` joins `files` only when it was written.
pub fn picture(
    result: Result<()>,
    name: &str,
    files: &mut Vec<String>,
    warnings: &mut Vec<String>,
) {
    match result {
        Ok(()) => files.push(name.to_string()),
        Err(e) => warnings.push(format!("{name} not drawn: {e:#}")),
    }
}

/// The labels of a picture: title, x axis, y axis (each with its unit).
pub struct Labels<'a> {
    /// Title.
    pub title: &'a str,
    /// x axis.
    pub x: &'a str,
    /// y axis.
    pub y: &'a str,
}

/// [`line_plot`] of `series` into `dir/name` as a [`picture`] of the run's outputs.
pub fn linear_picture(
    dir: &std::path::Path,
    name: &str,
    labels: &Labels,
    series: &[Series],
    files: &mut Vec<String>,
    warnings: &mut Vec<String>,
) {
    let drawn = line_plot(
        &dir.join(name),
        labels.title,
        labels.x,
        labels.y,
        series,
        Scale::Linear,
    );
    picture(drawn, name, files, warnings);
}

/// The y range of a flat curve at `y`: 10 % of its value either side (a flat density keeps a
/// positive axis), or [-1, 1] around zero.
fn flat_range(y: f64) -> (f64, f64) {
    let m = y.abs();
    if m > 0.0 {
        (y - 0.1 * m, y + 0.1 * m)
    } else {
        (-1.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::flat_range;

    #[test]
    fn a_flat_positive_curve_keeps_a_positive_axis() {
        assert_eq!(flat_range(0.5), (0.45, 0.55));
        assert!(flat_range(1e-6).0 > 0.0);
        assert_eq!(flat_range(0.0), (-1.0, 1.0));
        assert!(flat_range(-2.0).1 < 0.0);
    }
}
