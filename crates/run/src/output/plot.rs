//! Pictures of the main observables (PNG, SVG or both as `observe.figure_format` says; text
//! rendered with the embedded DejaVu Sans font).
//!
//! Every picture is named by the run as `NAME.png`; the format registered for its folder
//! ([`set_figure_format`], by the driver from the scenario) decides whether `NAME.png`,
//! `NAME.svg` or both are written, each under a temporary name renamed into place.

use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, Once};

static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

static REGISTER: Once = Once::new();

pub(crate) fn register_font() {
    REGISTER.call_once(|| {
        // The font is embedded, so registration cannot fail for a missing file.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// The format of a run's pictures (`observe.figure_format`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FigureFormat {
    /// `NAME.png` (raster, 800 px wide).
    #[default]
    Png,
    /// `NAME.svg` (vector, text as text).
    Svg,
    /// Both.
    Both,
}

impl FigureFormat {
    /// The format named `word` ("png", "svg" or "both").
    pub fn from_word(word: &str) -> Option<Self> {
        match word {
            "png" => Some(Self::Png),
            "svg" => Some(Self::Svg),
            "both" => Some(Self::Both),
            _ => None,
        }
    }

    /// The extensions written.
    pub fn extensions(self) -> &'static [&'static str] {
        match self {
            Self::Png => &["png"],
            Self::Svg => &["svg"],
            Self::Both => &["png", "svg"],
        }
    }
}

/// The formats of the output folders of this process, by canonical path (a folder not listed
/// gets PNG).
static FORMATS: Mutex<BTreeMap<PathBuf, FigureFormat>> = Mutex::new(BTreeMap::new());

fn folder_key(dir: &Path) -> PathBuf {
    dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf())
}

/// The pictures written into the folder `dir` from now on are in `format`.
pub fn set_figure_format(dir: &Path, format: FigureFormat) {
    let mut formats = FORMATS.lock().unwrap_or_else(|e| e.into_inner());
    formats.insert(folder_key(dir), format);
}

/// The format of the pictures in the folder `dir` (PNG unless [`set_figure_format`] said else).
pub fn figure_format(dir: &Path) -> FigureFormat {
    let formats = FORMATS.lock().unwrap_or_else(|e| e.into_inner());
    formats.get(&folder_key(dir)).copied().unwrap_or_default()
}

/// The files a picture the run names `name` (`NAME.png`) is written as in the folder `dir`:
/// `NAME.png`, `NAME.svg` or both. Other names are themselves.
pub fn picture_files(dir: &Path, name: &str) -> Vec<String> {
    match name.strip_suffix(".png") {
        Some(stem) => figure_format(dir)
            .extensions()
            .iter()
            .map(|ext| format!("{stem}.{ext}"))
            .collect(),
        None => vec![name.to_string()],
    }
}

/// `NAME.png` for `NAME.svg` (the name the run gives the picture), else `None`.
pub fn png_name(name: &str) -> Option<String> {
    name.strip_suffix(".svg").map(|stem| format!("{stem}.png"))
}

/// Draw a picture of `size` px at `path` (`NAME.png`) in the formats of its folder: `png`
/// draws it with the bitmap backend, `svg` with the SVG one (the same generic drawing, see
/// `save!`), each under a temporary name renamed into place, so that a failed or
/// interrupted drawing never leaves a truncated picture under the final name.
fn save(
    path: &Path,
    size: (u32, u32),
    png: impl FnOnce(DrawingArea<BitMapBackend, Shift>) -> Result<()>,
    svg: impl FnOnce(DrawingArea<SVGBackend, Shift>) -> Result<()>,
) -> Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let format = figure_format(dir);
    let (mut png, mut svg) = (Some(png), Some(svg));
    for ext in format.extensions() {
        let target = path.with_extension(ext);
        let name = target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        // The extension stays last: the bitmap encoder is chosen by it.
        let tmp = target.with_file_name(format!(".{name}.partial.{ext}"));
        let drawn = match *ext {
            "svg" => svg.take().map_or(Ok(()), |draw| {
                draw(SVGBackend::new(&tmp, size).into_drawing_area())
            }),
            _ => png.take().map_or(Ok(()), |draw| {
                draw(BitMapBackend::new(&tmp, size).into_drawing_area())
            }),
        }
        .and_then(|()| {
            std::fs::rename(&tmp, &target).map_err(|e| anyhow!("{}: {e}", target.display()))
        });
        if drawn.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        drawn.map_err(|e| anyhow!("{}: {e:#}", target.display()))?;
    }
    Ok(())
}

/// [`save`] with one generic drawing `|area| draw(area, ...)` for both backends.
macro_rules! save {
    ($path:expr, $size:expr, |$area:ident| $draw:expr) => {
        save($path, $size, |$area| $draw, |$area| $draw)
    };
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

/// The colours of curves (and of types in `colloidsim render`), in order.
pub(crate) const COLOURS: [RGBColor; 5] = [
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
    line_plot_styled(
        path,
        title,
        xlabel,
        ylabel,
        series,
        errors,
        scale,
        Style::default(),
    )
}

/// How a line plot is laid out beyond its data.
#[derive(Debug, Clone, Copy, Default)]
pub struct Style {
    /// The legend in a column right of the axes (the picture is 1000 px wide), where it covers
    /// no data; else inside the axes, upper left.
    pub legend_outside: bool,
}

/// [`line_plot_with_errors`] laid out as `style` says.
#[allow(clippy::too_many_arguments)]
pub fn line_plot_styled(
    path: &Path,
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[Series],
    errors: &[Option<&[f64]>],
    scale: Scale,
    style: Style,
) -> Result<()> {
    let width = if style.legend_outside {
        800 + legend_width(series)
    } else {
        800
    };
    save!(path, (width, 500), |area| draw_line_plot(
        area, title, xlabel, ylabel, series, errors, scale, style, false
    ))
}

/// An observable against a swept parameter (`colloidsim ensemble`'s `headline_NAME.png`):
/// [`line_plot_with_errors`] with each series' points marked and joined, the x axis padded so
/// that no point sits on its edge (a single x value gets an axis about it), and the legend
/// right of the axes.
pub fn sweep_plot(
    path: &Path,
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[Series],
    errors: &[Option<&[f64]>],
) -> Result<()> {
    // The legend beside the axes, where it hides no point or bar.
    let style = Style {
        legend_outside: true,
    };
    save!(path, (800 + legend_width(series), 500), |area| {
        draw_line_plot(
            area,
            title,
            xlabel,
            ylabel,
            series,
            errors,
            Scale::Linear,
            style,
            true,
        )
    })
}

#[allow(clippy::too_many_arguments)]
fn draw_line_plot<DB: DrawingBackend>(
    whole: DrawingArea<DB, Shift>,
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[Series],
    errors: &[Option<&[f64]>],
    scale: Scale,
    style: Style,
    sweep: bool,
) -> Result<()> {
    register_font();
    let finite = |v: f64| v.is_finite() && (scale == Scale::Linear || v > 0.0);
    let (xr, yr) = data_ranges(series, errors, scale);
    if xr.0 > xr.1 || (xr.0 == xr.1 && !sweep) {
        return Err(anyhow!("no finite data to draw"));
    }
    let (xr, yr) = (widened(xr), widened(yr));
    let xr = if sweep {
        let pad = 0.05 * (xr.1 - xr.0);
        (xr.0 - pad, xr.1 + pad)
    } else {
        xr
    };
    whole.fill(&WHITE).map_err(|e| anyhow!("plot: {e}"))?;
    let (root, side) = if style.legend_outside {
        let (l, r) = whole.split_horizontally(800);
        (l, Some(r))
    } else {
        (whole.clone(), None)
    };
    macro_rules! draw {
        ($chart:expr) => {{
            let mut chart = $chart;
            let (xres, yres) = match scale {
                Scale::Linear => (1e-6 * (xr.1 - xr.0), 1e-6 * (yr.1 - yr.0)),
                Scale::LogLog => (f64::NAN, f64::NAN),
            };
            let tick =
                |v: &f64, res: f64| tick_label(*v, if res.is_nan() { 1e-6 * v.abs() } else { res });
            let xfmt = |v: &f64| tick(v, xres);
            let yfmt = |v: &f64| tick(v, yres);
            chart
                .configure_mesh()
                .x_desc(xlabel)
                .y_desc(ylabel)
                .x_label_formatter(&xfmt)
                .y_label_formatter(&yfmt)
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
                if s.points && sweep {
                    chart
                        .draw_series(LineSeries::new(data.clone(), c.stroke_width(1)))
                        .map_err(|e| anyhow!("plot: {e}"))?;
                    chart
                        .draw_series(data.map(|p| Circle::new(p, 4, c.filled())))
                        .map_err(|e| anyhow!("plot: {e}"))?
                        .label(s.label)
                        .legend(move |(x, y)| Circle::new((x + 10, y), 4, c.filled()));
                } else if s.points {
                    chart
                        .draw_series(data.map(|p| Circle::new(p, 2, c.filled())))
                        .map_err(|e| anyhow!("plot: {e}"))?
                        .label(s.label)
                        .legend(move |(x, y)| Circle::new((x + 10, y), 3, c.filled()));
                } else {
                    // A curve of one point is drawn as a dot (a line through it is nothing).
                    let lone = data.clone().count() == 1;
                    chart
                        .draw_series(
                            data.clone()
                                .filter(|_| lone)
                                .map(|p| Circle::new(p, 3, c.filled())),
                        )
                        .map_err(|e| anyhow!("plot: {e}"))?;
                    chart
                        .draw_series(LineSeries::new(data, c.stroke_width(2)))
                        .map_err(|e| anyhow!("plot: {e}"))?
                        .label(s.label)
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                        });
                }
            }
            if side.is_none() {
                chart
                    .configure_series_labels()
                    .position(SeriesLabelPosition::UpperLeft)
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .label_font(("sans-serif", 16))
                    .draw()
                    .map_err(|e| anyhow!("plot: {e}"))?;
            }
        }};
    }
    let mut builder = ChartBuilder::on(&root);
    builder
        .caption(title, ("sans-serif", caption_size(title)))
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
    if let Some(side) = side {
        // The legend beside the axes: one row per curve, its mark and its label.
        for (k, s) in series.iter().enumerate() {
            let c = COLOURS[k % COLOURS.len()];
            let y = 60 + 24 * k as i32;
            if s.points {
                side.draw(&Circle::new((18, y), 3, c.filled()))
            } else {
                side.draw(&PathElement::new(vec![(8, y), (28, y)], c.stroke_width(2)))
            }
            .map_err(|e| anyhow!("plot: {e}"))?;
            side.draw(&Text::new(
                s.label.to_string(),
                (36, y - 9),
                ("sans-serif", 15),
            ))
            .map_err(|e| anyhow!("plot: {e}"))?;
        }
    }
    whole.present().map_err(|e| anyhow!("plot: {e}"))?;
    Ok(())
}

/// A tick label: `v` rounded to the fewest significant digits (at most 15) that keep it within
/// `resolution` of itself, printed as the shortest decimal of that rounded value (so a tick at
/// 0.1 + 0.2 reads "0.3", not "0.30000000000000004"); a value within `resolution / 2` of zero
/// reads "0"; magnitudes below 1e-4 or from 1e6 up in scientific notation ("2.5e-5").
/// `resolution` is a millionth of the axis' span on a linear axis, of the value on a log one.
pub fn tick_label(v: f64, resolution: f64) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    let res = if resolution.is_finite() && resolution > 0.0 {
        resolution
    } else {
        v.abs() * 1e-12
    };
    if v.abs() <= 0.5 * res {
        return "0".into();
    }
    let mut digits = 15;
    let mut rounded = v;
    for p in 1..=15 {
        // Rounding to p significant digits through the decimal text is exact to the last bit.
        let r: f64 = format!("{:.*e}", p - 1, v).parse().unwrap_or(v);
        if (r - v).abs() <= res {
            digits = p;
            rounded = r;
            break;
        }
    }
    let m = rounded.abs();
    if !(1e-4..1e6).contains(&m) {
        format!("{:.*e}", digits - 1, rounded)
    } else {
        format!("{rounded}")
    }
}

/// The width in px of a legend beside the axes: its longest label at about 7 px a character
/// (15 px DejaVu Sans) after the 36 px of the mark, at least 240.
fn legend_width(series: &[Series]) -> u32 {
    let chars = series
        .iter()
        .map(|s| s.label.chars().count())
        .max()
        .unwrap_or(0);
    (48 + 7 * chars as u32).max(240)
}

/// The shells of a radial profile merged from the centre outwards until each merged shell is
/// expected to hold at least `particles` particle centres over all `samples` (replicas or
/// frames averaged): a shell of volume `V` at the profile's mean volume fraction `phi_mean`
/// holds `phi_mean V / v` centres per sample (`v` the particle volume). `r` are the mid-points
/// of shells of equal width from 0, `phi` their volume fractions; a merged shell's value is
/// the volume-weighted mean of its shells, drawn at its volume-weighted mean radius. The
/// innermost shells of equal-width bins are tiny (the first of 30 over R holds R^3 / 27000 of
/// the volume) and read one particle as a volume fraction of several; merged, the picture keeps
/// its axis on the profile. Shells already large enough stay as they are.
pub fn merged_shells(
    r: &[f64],
    phi: &[f64],
    particle_volume: f64,
    samples: f64,
    particles: f64,
) -> (Vec<f64>, Vec<f64>) {
    let n = r.len().min(phi.len());
    if n < 2 {
        return (r[..n].to_vec(), phi[..n].to_vec());
    }
    let dr = r[1] - r[0];
    let shell = |i: usize| {
        let (lo, hi) = ((r[i] - 0.5 * dr).max(0.0), r[i] + 0.5 * dr);
        4.0 / 3.0 * std::f64::consts::PI * (hi.powi(3) - lo.powi(3))
    };
    let total: f64 = (0..n).map(shell).sum();
    let filled: f64 = (0..n)
        .filter(|&i| phi[i].is_finite())
        .map(|i| phi[i] * shell(i))
        .sum();
    let phi_mean = filled / total;
    if !(phi_mean > 0.0 && particle_volume > 0.0 && samples > 0.0) {
        return (r[..n].to_vec(), phi[..n].to_vec());
    }
    let need = particles * particle_volume / (phi_mean * samples);
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    let (mut v, mut vr, mut vphi) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let s = shell(i);
        v += s;
        vr += s * r[i];
        vphi += s * phi[i];
        if v >= need || i + 1 == n {
            xs.push(vr / v);
            ys.push(vphi / v);
            (v, vr, vphi) = (0.0, 0.0, 0.0);
        }
    }
    (xs, ys)
}

/// Centres a merged point of [`merged_shells`] must expect: 10, a relative counting noise of
/// about 30 % in a dilute shell and far less in a dense one.
pub const SHELL_PARTICLES: f64 = 10.0;

/// The x and y ranges of the finite points of `series` (positive ones on log axes), the y range
/// widened to hold their error bars.
fn data_ranges(
    series: &[Series],
    errors: &[Option<&[f64]>],
    scale: Scale,
) -> ((f64, f64), (f64, f64)) {
    let finite = |v: f64| v.is_finite() && (scale == Scale::Linear || v > 0.0);
    let mut xr = (f64::INFINITY, f64::NEG_INFINITY);
    let mut yr = (f64::INFINITY, f64::NEG_INFINITY);
    for (k, s) in series.iter().enumerate() {
        let err = errors.get(k).copied().flatten();
        for (i, (&x, &y)) in s.x.iter().zip(s.y).enumerate() {
            if finite(x) && finite(y) {
                xr = (xr.0.min(x), xr.1.max(x));
                yr = (yr.0.min(y), yr.1.max(y));
                // The error bars stay inside the axes (on a log axis only their upper ends).
                if let Some(e) = err.and_then(|e| e.get(i)).filter(|e| e.is_finite()) {
                    if finite(y + e) {
                        yr.1 = yr.1.max(y + e);
                    }
                    if finite(y - e) {
                        yr.0 = yr.0.min(y - e);
                    }
                }
            }
        }
    }
    (xr, yr)
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

/// What the marks of a [`cross_section`] mean: one legend entry per disc colour (by index),
/// one for the outline, and the axes' labels with their unit.
pub struct SectionLabels<'a> {
    /// Legend entry of the discs of colour `k`.
    pub colours: &'a [&'a str],
    /// Legend entry of the outline circle.
    pub outline: &'a str,
    /// x axis, with its unit.
    pub x: &'a str,
    /// y axis, with its unit.
    pub y: &'a str,
}

/// Draw `discs` (e.g. the sections of spheres cut by a slab) inside a circle of radius `outline`
/// centred on the origin, with equal scales on both axes, into a PNG at `path` (a 600x600 px
/// square of axes and a legend column right of it, as `labels` say; drawn under a temporary
/// name and renamed into place).
pub fn cross_section(
    path: &Path,
    title: &str,
    discs: &[Disc],
    outline: f64,
    labels: &SectionLabels,
) -> Result<()> {
    let chars = labels
        .colours
        .iter()
        .chain([&labels.outline])
        .map(|l| l.chars().count())
        .max()
        .unwrap_or(0);
    let side_width = (48 + 7 * chars as u32).max(160);
    save!(path, (600 + side_width, 600), |area| draw_cross_section(
        area, title, discs, outline, labels
    ))
}

fn draw_cross_section<DB: DrawingBackend>(
    whole: DrawingArea<DB, Shift>,
    title: &str,
    discs: &[Disc],
    outline: f64,
    labels: &SectionLabels,
) -> Result<()> {
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
    whole.fill(&WHITE).map_err(e)?;
    let (root, side) = whole.split_horizontally(600);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(55)
        .build_cartesian_2d(-lim..lim, -lim..lim)
        .map_err(e)?;
    let fmt = |v: &f64| tick_label(*v, 2e-6 * lim);
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(labels.x)
        .y_desc(labels.y)
        .x_label_formatter(&fmt)
        .y_label_formatter(&fmt)
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
    // The legend beside the axes: a disc per colour, a line for the outline.
    for (k, label) in labels.colours.iter().enumerate() {
        let (c, y) = (COLOURS[k % COLOURS.len()], 60 + 24 * k as i32);
        side.draw(&Circle::new((18, y), 7, c.mix(0.85).filled()))
            .map_err(e)?;
        side.draw(&Text::new(
            label.to_string(),
            (36, y - 9),
            ("sans-serif", 15),
        ))
        .map_err(e)?;
    }
    let y = 60 + 24 * labels.colours.len() as i32;
    side.draw(&PathElement::new(
        vec![(8, y), (28, y)],
        BLACK.stroke_width(2),
    ))
    .map_err(e)?;
    side.draw(&Text::new(
        labels.outline.to_string(),
        (36, y - 9),
        ("sans-serif", 15),
    ))
    .map_err(e)?;
    whole.present().map_err(e)?;
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

/// The font size of a line plot's title: 20 px, smaller for a title longer than 64 characters
/// so that it fits the picture's width (down to 12 px).
fn caption_size(title: &str) -> u32 {
    let n = title.chars().count().max(1) as u32;
    if n <= 64 { 20 } else { (20 * 64 / n).max(12) }
}

/// `r` itself, or [`flat_range`] about its middle when it is empty or narrower than a
/// billionth of its magnitude (points that differ only in their last bits would otherwise span
/// the axis, its ticks reading 0.7490234374999999 and 0.7490234375000001).
fn widened(r: (f64, f64)) -> (f64, f64) {
    if r.1 - r.0 > 1e-9 * r.0.abs().max(r.1.abs()) {
        r
    } else {
        flat_range(if r.0 >= r.1 { r.0 } else { 0.5 * (r.0 + r.1) })
    }
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
    use super::{Scale, Series, data_ranges, flat_range, merged_shells, tick_label, widened};

    /// The y axis holds the error bars, not only the points; a series without errors and the
    /// lower ends on a log axis that would reach zero leave it as the points make it.
    #[test]
    fn the_axes_hold_the_error_bars() {
        let (x, y, e) = ([1.0, 2.0, 3.0], [1.0, 2.0, 1.5], [0.5, 0.25, 2.0]);
        let s = [Series {
            label: "",
            x: &x,
            y: &y,
            points: true,
        }];
        let (xr, yr) = data_ranges(&s, &[Some(&e)], Scale::Linear);
        assert_eq!(xr, (1.0, 3.0));
        assert_eq!(yr, (-0.5, 3.5));
        assert_eq!(data_ranges(&s, &[None], Scale::Linear).1, (1.0, 2.0));
        assert_eq!(data_ranges(&s, &[Some(&e)], Scale::LogLog).1, (0.5, 3.5));
    }

    /// Merging keeps a uniform profile uniform, keeps the volume-weighted total, merges only
    /// the small inner shells, and draws a single particle in the first shell at a sane value.
    #[test]
    fn merged_shells_pool_the_small_inner_shells() {
        let bins = 30;
        let radius = 6.3;
        let dr = radius / bins as f64;
        let r: Vec<f64> = (0..bins).map(|b| (b as f64 + 0.5) * dr).collect();
        let v = std::f64::consts::PI / 6.0;
        let flat = vec![0.5; bins];
        let (x, y) = merged_shells(&r, &flat, v, 4.0, 10.0);
        assert!(y.iter().all(|p| (p - 0.5).abs() < 1e-12), "{y:?}");
        assert!(x.len() < bins && x.len() > bins - 10, "{}", x.len());
        assert!(x.windows(2).all(|w| w[0] < w[1]));
        // The outer shells are kept as they were.
        assert!((x[x.len() - 1] - r[bins - 1]).abs() < 1e-12);
        // One particle in the innermost shell of volume 0.04 (phi 3.35 there over 4 droplets).
        let shell0 = 4.0 / 3.0 * std::f64::consts::PI * dr.powi(3);
        let mut spike = flat.clone();
        spike[0] = v / shell0 / 4.0;
        assert!(spike[0] > 3.0, "{}", spike[0]);
        let (_, y) = merged_shells(&r, &spike, v, 4.0, 10.0);
        assert!(y[0] < 0.7, "{}", y[0]);
    }

    /// A range of a few ulps is an axis about its value; a true range is kept.
    #[test]
    fn an_axis_a_few_ulps_wide_is_widened() {
        let x = 0.7490234375;
        assert_eq!(widened((x - 1e-16, x + 1e-16)), flat_range(x));
        assert_eq!(widened((x, x)), flat_range(x));
        assert_eq!(widened((0.0, 1e-12)), (0.0, 1e-12));
        assert_eq!(widened((1.0, 1.001)), (1.0, 1.001));
    }

    #[test]
    fn a_flat_positive_curve_keeps_a_positive_axis() {
        assert_eq!(flat_range(0.5), (0.45, 0.55));
        assert!(flat_range(1e-6).0 > 0.0);
        assert_eq!(flat_range(0.0), (-1.0, 1.0));
        assert!(flat_range(-2.0).1 < 0.0);
    }

    /// Tick labels are the shortest decimals of the ticks at the axis' resolution.
    #[test]
    fn tick_labels_are_short_decimals() {
        let res = 1e-6;
        assert_eq!(tick_label(0.1 + 0.2, res), "0.3");
        assert_eq!(tick_label(0.30000000000000004, res), "0.3");
        assert_eq!(tick_label(3.0 * 0.1, res), "0.3");
        assert_eq!(tick_label(1.0, res), "1");
        assert_eq!(tick_label(-0.7000000000000001, res), "-0.7");
        assert_eq!(tick_label(2.5, res), "2.5");
        assert_eq!(tick_label(120.0, 1e-4), "120");
        // A tick at zero computed as a tiny remainder.
        assert_eq!(tick_label(5.551115123125783e-17, res), "0");
        // Small and large magnitudes in scientific notation, still short.
        assert_eq!(tick_label(2.5e-5 + 1e-21, 1e-11), "2.5e-5");
        assert_eq!(tick_label(3.0e7 * 1.0000000000000002, 10.0), "3e7");
        // A fine axis keeps the digits it needs.
        assert_eq!(tick_label(1.0001, 1e-7), "1.0001");
        assert_eq!(tick_label(f64::NAN, res), "NaN");
    }

    /// A cross-section carries its legend in a column beside the square axes: the picture is
    /// wider than the 600 px square by the column, which grows with the longest label.
    #[test]
    fn a_cross_section_has_a_legend_column() {
        let dir = tempfile::tempdir().unwrap();
        let discs = [
            super::Disc {
                x: 0.0,
                y: 0.0,
                r: 0.5,
                colour: 0,
            },
            super::Disc {
                x: 2.0,
                y: 0.0,
                r: 0.5,
                colour: 1,
            },
        ];
        let width = |labels: &super::SectionLabels| {
            let path = dir.path().join("s.png");
            super::cross_section(&path, "t", &discs, 2.6, labels).unwrap();
            let png = std::fs::read(&path).unwrap();
            // IHDR: width and height, big-endian, at bytes 16..24.
            let w = u32::from_be_bytes(png[16..20].try_into().unwrap());
            let h = u32::from_be_bytes(png[20..24].try_into().unwrap());
            assert_eq!(h, 600);
            w
        };
        let short = super::SectionLabels {
            colours: &["a", "b"],
            outline: "R",
            x: "x / d",
            y: "y / d",
        };
        let long = super::SectionLabels {
            colours: &[
                "a label of some sixty characters, longer than the column",
                "b",
            ],
            ..short
        };
        let (ws, wl) = (width(&short), width(&long));
        assert!(ws >= 760, "{ws}");
        assert!(wl > ws, "{wl} <= {ws}");
    }
}
