//! `colloidsim render RUN`: pictures of particles from a run's `trajectory.gsd` (or any GSD file
//! in the HOOMD schema), so that a user sees what happened before opening OVITO.
//!
//! - Spheres (3D frames): a perspective view, each sphere a shaded disc drawn far to near
//!   (painter's order), coloured by type, by distance from the centre or by diameter; `cut`
//!   removes the half facing the camera to show the inside of a droplet. The box's edges are
//!   drawn when the particles fill it.
//! - Rods on a line (BCD's 2D frames with every particle on the x axis): the snapshot is a
//!   space-time picture (one row per frame, time downwards, each rod a bar of its length), the
//!   animation the line itself, walls drawn.
//!
//! Pictures are drawn under a temporary name and renamed into place (docs/render.md).

use crate::analyse::Frames;
use crate::output::plot::{COLOURS, tick_label};
use anyhow::{Context, Result, anyhow, bail};
use colloidsim_particles::gsd::{frame_count, open_checked};
use hoomd_gsd::file_layer::Mode;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Most frames an animation or a space-time picture holds (more are thinned evenly).
const MAX_FRAMES: usize = 400;

/// What colours a sphere.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Colour {
    /// Its type (one colour per type name).
    #[default]
    Type,
    /// Its distance from the centre of the picture, on a colour scale.
    Distance,
    /// Its diameter, on a colour scale.
    Diameter,
}

impl std::str::FromStr for Colour {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "type" => Ok(Self::Type),
            "distance" => Ok(Self::Distance),
            "diameter" => Ok(Self::Diameter),
            _ => bail!("--colour: expected type, distance or diameter, got '{s}'"),
        }
    }
}

/// What `colloidsim render` draws, and where.
#[derive(Debug, Clone)]
pub struct RenderOptions {
    /// Picture file (default: `snapshot.png`, or `movie.gif` with `animate`, beside the
    /// trajectory).
    pub out: Option<PathBuf>,
    /// Overwrite an existing picture.
    pub force: bool,
    /// The snapshot's frame (default: the last).
    pub frame: Option<u64>,
    /// Draw an animated GIF of `frames` instead of one snapshot.
    pub animate: bool,
    /// Frames of the animation and of a rods' space-time picture.
    pub frames: Frames,
    /// What colours the spheres.
    pub colour: Colour,
    /// Leave out the half of the spheres facing the camera.
    pub cut: bool,
    /// Picture width in pixels (the height is 3/4 of it for spheres).
    pub width: u32,
    /// Animation frames per second.
    pub fps: u32,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            out: None,
            force: false,
            frame: None,
            animate: false,
            frames: Frames::default(),
            colour: Colour::Type,
            cut: false,
            width: 800,
            fps: 10,
        }
    }
}

/// One frame as drawn: box edges (Lz = 0 in 2D), positions, diameters, type indices.
struct Shot {
    step: u64,
    edges: [f64; 3],
    pos: Vec<[f64; 3]>,
    diameter: Vec<f64>,
    typeid: Vec<u32>,
    types: Vec<String>,
    walls: Option<[f64; 2]>,
}

/// Read frame `k` of a GSD file: what a picture needs, 2D boxes (BCD's) included.
fn read_shot(path: &Path, k: u64) -> Result<Shot> {
    let f = open_checked(path, Mode::Read)?;
    let at = |name: &str| -> Option<u64> {
        [k, 0]
            .into_iter()
            .find(|&fr| f.find_chunk(fr, name).is_some())
    };
    let bad = |m: String| anyhow!("{}: frame {k}: {m}", path.display());
    let step = match at("configuration/step") {
        Some(fr) => f
            .iter_scalars::<u64>(fr, "configuration/step")?
            .next()
            .unwrap_or(0),
        None => 0,
    };
    let b: Vec<f32> = match at("configuration/box") {
        Some(fr) => f.iter_scalars::<f32>(fr, "configuration/box")?.collect(),
        None => return Err(bad("no configuration/box".into())),
    };
    if b.len() != 6 || b[..3].iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
        return Err(bad(format!("configuration/box {b:?} is not a box")));
    }
    let pos: Vec<[f64; 3]> = match at("particles/position") {
        Some(fr) => f
            .iter_arrays::<f32, 3>(fr, "particles/position")?
            .map(|x| [x[0] as f64, x[1] as f64, x[2] as f64])
            .collect(),
        None => return Err(bad("no particles/position".into())),
    };
    if let Some(i) = pos.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
        return Err(bad(format!(
            "particle {i} has a position that is not finite"
        )));
    }
    let n = pos.len();
    let diameter: Vec<f64> = match at("particles/diameter") {
        Some(fr) => f
            .iter_scalars::<f32>(fr, "particles/diameter")?
            .map(|d| d as f64)
            .collect(),
        None => vec![1.0; n],
    };
    let typeid: Vec<u32> = match at("particles/typeid") {
        Some(fr) => f.iter_scalars::<u32>(fr, "particles/typeid")?.collect(),
        None => vec![0; n],
    };
    if diameter.len() != n || typeid.len() != n {
        return Err(bad("particle arrays of different lengths".into()));
    }
    if let Some(i) = diameter.iter().position(|d| !(d.is_finite() && *d >= 0.0)) {
        return Err(bad(format!("particle {i} has diameter {}", diameter[i])));
    }
    let n_types = typeid.iter().map(|&t| t as usize + 1).max().unwrap_or(1);
    let mut types: Vec<String> = match at("particles/types") {
        Some(fr) => f
            .iter_arrays::<u8, 64>(fr, "particles/types")
            .map(|it| {
                it.map(|a| {
                    let end = a.iter().position(|&c| c == 0).unwrap_or(64);
                    String::from_utf8_lossy(&a[..end]).into_owned()
                })
                .collect()
            })
            .unwrap_or_default(),
        None => Vec::new(),
    };
    while types.len() < n_types {
        types.push(((b'A' + (types.len() % 26) as u8) as char).to_string());
    }
    let walls = f.find_chunk(k, "log/bcd/walls").and_then(|_| {
        let w: Vec<f64> = f.iter_scalars::<f64>(k, "log/bcd/walls").ok()?.collect();
        (w.len() == 2).then(|| [w[0], w[1]])
    });
    Ok(Shot {
        step,
        edges: [b[0] as f64, b[1] as f64, b[2] as f64],
        pos,
        diameter,
        typeid,
        types,
        walls,
    })
}

impl Shot {
    /// Rods on a line: every particle on the x axis.
    fn on_a_line(&self) -> bool {
        self.pos.iter().all(|p| p[1] == 0.0 && p[2] == 0.0)
    }
}

/// Evenly thinned frame indices of `frames` within a file of `total` frames.
fn frame_list(frames: Frames, total: u64) -> Result<Vec<u64>> {
    let last = frames.last.unwrap_or(total - 1);
    if frames.first >= total || last >= total || last < frames.first {
        bail!(
            "--frames: frames {}..={last} requested, the file holds frames 0..={}",
            frames.first,
            total - 1
        );
    }
    let all: Vec<u64> = (frames.first..=last)
        .step_by(frames.stride as usize)
        .collect();
    if all.len() <= MAX_FRAMES {
        return Ok(all);
    }
    let m = all.len();
    Ok((0..MAX_FRAMES)
        .map(|i| all[i * (m - 1) / (MAX_FRAMES - 1)])
        .collect())
}

/// A perceptually ordered scale (viridis' end points and three stops between), `t` in [0, 1].
fn scale_colour(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * 4.0;
    let i = (x.floor() as usize).min(3);
    let w = x - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let mix = |p: f64, q: f64| (p + w * (q - p)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

fn shade(c: RGBColor, light: f64, white: f64) -> RGBColor {
    let f = |v: u8| ((v as f64 * light) + 255.0 * white).clamp(0.0, 255.0) as u8;
    RGBColor(f(c.0), f(c.1), f(c.2))
}

/// The camera of a sphere picture: fixed by the first frame drawn, so that an animation shows
/// the particles move (a droplet shrink) against a still view.
struct Camera {
    centre: [f64; 3],
    extent: f64,
    eye: [f64; 3],
    forward: [f64; 3],
    right: [f64; 3],
    up: [f64; 3],
    focal: f64,
    show_box: bool,
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

impl Camera {
    /// Looking at the middle of the particles' bounding box from azimuth 35 degrees and
    /// elevation 25 degrees, far enough that their enclosing sphere fills the picture.
    fn fit(shot: &Shot, size: (u32, u32)) -> Self {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &shot.pos {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let centre = [
            0.5 * (lo[0] + hi[0]),
            0.5 * (lo[1] + hi[1]),
            0.5 * (lo[2] + hi[2]),
        ];
        let d_max = shot.diameter.iter().cloned().fold(0.0, f64::max);
        let extent = shot
            .pos
            .iter()
            .map(|p| dot(sub(*p, centre), sub(*p, centre)).sqrt())
            .fold(0.0, f64::max)
            + 0.5 * d_max;
        let extent = extent.max(1e-9);
        // The particles fill the box: draw its edges.
        let show_box = (0..3).all(|k| hi[k] - lo[k] > 0.8 * shot.edges[k]);
        let (az, el) = (35f64.to_radians(), 25f64.to_radians());
        let towards_eye = [el.cos() * az.sin(), el.sin(), el.cos() * az.cos()];
        let distance = 3.5 * extent;
        let eye = [
            centre[0] + distance * towards_eye[0],
            centre[1] + distance * towards_eye[1],
            centre[2] + distance * towards_eye[2],
        ];
        let forward = [-towards_eye[0], -towards_eye[1], -towards_eye[2]];
        // right = forward x y-axis, up = right x forward.
        let r = [-forward[2], 0.0, forward[0]];
        let rn = dot(r, r).sqrt();
        let right = [r[0] / rn, r[1] / rn, r[2] / rn];
        let up = [
            right[1] * forward[2] - right[2] * forward[1],
            right[2] * forward[0] - right[0] * forward[2],
            right[0] * forward[1] - right[1] * forward[0],
        ];
        let half = 0.5 * size.0.min(size.1) as f64;
        // The enclosing sphere seen from `distance` subtends extent / sqrt(d^2 - extent^2).
        let focal = 0.9 * half * (distance * distance - extent * extent).sqrt() / extent;
        Self {
            centre,
            extent,
            eye,
            forward,
            right,
            up,
            focal,
            show_box,
        }
    }

    /// Screen position (pixels from the picture's centre, y down), depth and the scale
    /// (pixels per length) at that depth.
    fn project(&self, p: [f64; 3]) -> (f64, f64, f64, f64) {
        let v = sub(p, self.eye);
        let depth = dot(v, self.forward).max(1e-9);
        let s = self.focal / depth;
        (dot(v, self.right) * s, -dot(v, self.up) * s, depth, s)
    }
}

/// Draw the spheres of `shot` into `area` as `camera` sees them.
fn draw_spheres<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    shot: &Shot,
    camera: &Camera,
    opts: &RenderOptions,
    title: &str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("{x}");
    area.fill(&WHITE).map_err(e)?;
    let (w, h) = area.dim_in_pixel();
    let (cx, cy) = (w as f64 / 2.0, h as f64 / 2.0 + 10.0);
    let (d_lo, d_hi) = shot
        .diameter
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &d| {
            (a.min(d), b.max(d))
        });
    let towards_eye = [-camera.forward[0], -camera.forward[1], -camera.forward[2]];
    let mut order: Vec<(f64, usize)> = shot
        .pos
        .iter()
        .enumerate()
        .filter(|(_, p)| !opts.cut || dot(sub(**p, camera.centre), towards_eye) <= 0.0)
        .map(|(i, p)| (camera.project(*p).2, i))
        .collect();
    // Far to near; ties by index, so that the picture does not depend on the sort.
    order.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    if camera.show_box {
        let l = shot.edges;
        let corner = |m: usize| {
            [
                ((m & 1) as f64 - 0.5) * l[0],
                (((m >> 1) & 1) as f64 - 0.5) * l[1],
                (((m >> 2) & 1) as f64 - 0.5) * l[2],
            ]
        };
        for a in 0..8usize {
            for bit in [1, 2, 4] {
                let b = a | bit;
                if b != a {
                    let (x0, y0, _, _) = camera.project(corner(a));
                    let (x1, y1, _, _) = camera.project(corner(b));
                    area.draw(&PathElement::new(
                        vec![
                            ((cx + x0) as i32, (cy + y0) as i32),
                            ((cx + x1) as i32, (cy + y1) as i32),
                        ],
                        RGBColor(120, 120, 120).stroke_width(1),
                    ))
                    .map_err(e)?;
                }
            }
        }
    }
    for &(_, i) in &order {
        let p = shot.pos[i];
        let (x, y, _, s) = camera.project(p);
        let r = (0.5 * shot.diameter[i] * s).max(0.8);
        let base = match opts.colour {
            Colour::Type => COLOURS[shot.typeid[i] as usize % COLOURS.len()],
            Colour::Distance => scale_colour(
                dot(sub(p, camera.centre), sub(p, camera.centre)).sqrt() / camera.extent,
            ),
            Colour::Diameter => scale_colour(if d_hi > d_lo {
                (shot.diameter[i] - d_lo) / (d_hi - d_lo)
            } else {
                0.5
            }),
        };
        // A disc lit from the upper left: concentric discs shifted toward the light, each
        // lighter and smaller, over a dark rim.
        let (px, py) = (cx + x, cy + y);
        area.draw(&Circle::new(
            (px as i32, py as i32),
            r.round() as i32,
            shade(base, 0.45, 0.0).filled(),
        ))
        .map_err(e)?;
        const LAYERS: usize = 5;
        for k in 0..LAYERS {
            let t = k as f64 / LAYERS as f64;
            let rk = r * (0.92 - 0.75 * t);
            let off = 0.35 * r * t;
            area.draw(&Circle::new(
                ((px - off) as i32, (py - off) as i32),
                rk.round().max(0.0) as i32,
                shade(base, 0.7 + 0.35 * t, 0.35 * t * t).filled(),
            ))
            .map_err(e)?;
        }
    }
    // Text and legend scaled with the picture (sizes in px at 800 px wide).
    let u = w as f64 / 800.0;
    let px = |v: f64| (v * u).round() as i32;
    let title_font = ("sans-serif", (18.0 * u).max(9.0))
        .into_font()
        .color(&BLACK);
    area.draw_text(title, &title_font, (px(12.0), px(8.0)))
        .map_err(e)?;
    // Legend: the types, or the scale.
    let font = ("sans-serif", (14.0 * u).max(8.0))
        .into_font()
        .color(&BLACK);
    match opts.colour {
        Colour::Type => {
            let mut used: Vec<u32> = shot.typeid.clone();
            used.sort_unstable();
            used.dedup();
            for (row, &t) in used.iter().enumerate() {
                let y = 36.0 + 20.0 * row as f64;
                area.draw(&Circle::new(
                    (px(20.0), px(y + 7.0)),
                    px(6.0).max(2),
                    COLOURS[t as usize % COLOURS.len()].filled(),
                ))
                .map_err(e)?;
                let name = shot.types.get(t as usize).cloned().unwrap_or_default();
                area.draw_text(&name, &font, (px(32.0), px(y))).map_err(e)?;
            }
        }
        Colour::Distance | Colour::Diameter => {
            let (label, lo, hi) = match opts.colour {
                Colour::Distance => ("distance from the centre", 0.0, camera.extent),
                _ => ("diameter", d_lo, d_hi),
            };
            for k in 0..100 {
                let x = 12.0 + 2.0 * k as f64;
                area.draw(&Rectangle::new(
                    [(px(x), px(36.0)), (px(x + 2.0), px(50.0))],
                    scale_colour(k as f64 / 99.0).filled(),
                ))
                .map_err(e)?;
            }
            area.draw_text(&format!("{lo:.3}"), &font, (px(12.0), px(54.0)))
                .map_err(e)?;
            area.draw_text(&format!("{hi:.3}"), &font, (px(190.0), px(54.0)))
                .map_err(e)?;
            area.draw_text(label, &font, (px(12.0), px(72.0)))
                .map_err(e)?;
        }
    }
    Ok(())
}

/// A rod's colour: its type's, or, with one type, one cycling with its index, so that each
/// rod's path can be followed (the order of rods on a line does not change).
fn rod_colour(shot: &Shot, i: usize) -> RGBColor {
    let k = if shot.types.len() > 1 {
        shot.typeid[i] as usize
    } else {
        i
    };
    COLOURS[k % COLOURS.len()]
}

/// Each rod of `shot` as a bar of its length between heights `y`, clipped to `x`; a rod that
/// crosses the ring's seam is drawn on both ends.
fn rod_bars(
    shot: &Shot,
    x: (f64, f64),
    y: (f64, f64),
) -> impl Iterator<Item = Rectangle<(f64, f64)>> + '_ {
    let (lo, hi) = x;
    shot.pos.iter().enumerate().flat_map(move |(i, p)| {
        let half = 0.5 * shot.diameter[i];
        let c = rod_colour(shot, i);
        [-(hi - lo), 0.0, hi - lo]
            .into_iter()
            .filter_map(move |shift| {
                let (a, b) = (p[0] - half + shift, p[0] + half + shift);
                (b > lo && a < hi)
                    .then(|| Rectangle::new([(a.max(lo), y.0), (b.min(hi), y.1)], c.filled()))
            })
    })
}

/// The x range a line of rods is drawn over: between the walls, else the box.
fn line_range(shot: &Shot) -> (f64, f64) {
    match shot.walls {
        Some([a, b]) => (a, b),
        None => (-0.5 * shot.edges[0], 0.5 * shot.edges[0]),
    }
}

/// One line of rods (an animation frame).
fn draw_line<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    shot: &Shot,
    title: &str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("{x}");
    area.fill(&WHITE).map_err(e)?;
    let (lo, hi) = line_range(shot);
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(36)
        .build_cartesian_2d(lo..hi, -1.0..1.0)
        .map_err(e)?;
    let dx = (hi - lo) * 1e-6;
    chart
        .configure_mesh()
        .disable_y_axis()
        .disable_mesh()
        .x_desc("x (rod length unit)")
        .x_label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 13))
        .x_label_formatter(&|v| tick_label(*v, dx))
        .draw()
        .map_err(e)?;
    chart
        .draw_series(rod_bars(shot, (lo, hi), (-0.3, 0.3)))
        .map_err(e)?;
    if shot.walls.is_some() {
        for x in [lo, hi] {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(x, -0.8), (x, 0.8)],
                    BLACK.stroke_width(4),
                )))
                .map_err(e)?;
        }
    }
    Ok(())
}

/// Rods of many frames: one row per frame, time downwards.
fn draw_space_time<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    shots: &[Shot],
    title: &str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("{x}");
    area.fill(&WHITE).map_err(e)?;
    let (lo, hi) = line_range(&shots[0]);
    let (s0, s1) = (shots[0].step as f64, shots[shots.len() - 1].step as f64);
    let row = if shots.len() > 1 {
        (s1 - s0) / (shots.len() - 1) as f64
    } else {
        1.0
    };
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(70)
        .build_cartesian_2d(lo..hi, (s1 + 0.5 * row)..(s0 - 0.5 * row))
        .map_err(e)?;
    let (dx, dy) = ((hi - lo) * 1e-6, (s1 - s0).abs().max(1.0) * 1e-6);
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x (rod length unit)")
        .y_desc("step")
        .x_label_formatter(&|v| tick_label(*v, dx))
        .y_label_formatter(&|v| tick_label(*v, dy))
        .draw()
        .map_err(e)?;
    for shot in shots {
        let y = shot.step as f64;
        chart
            .draw_series(rod_bars(shot, (lo, hi), (y - 0.45 * row, y + 0.45 * row)))
            .map_err(e)?;
    }
    Ok(())
}

/// Draw into `path` through a temporary sibling renamed into place.
fn atomically(path: &Path, draw: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    // The extension stays last: the bitmap encoder is chosen by it.
    let tmp = path.with_file_name(format!(".{name}.partial.{ext}"));
    let r = draw(&tmp)
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| anyhow!("{}: {e}", path.display())));
    if r.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    r
}

/// Draw the picture `opts` ask for from the trajectory at `input` (a run's folder or a GSD
/// file); returns the picture's path.
pub fn render(input: &Path, opts: &RenderOptions) -> Result<PathBuf> {
    crate::output::plot::register_font();
    if !(200..=4000).contains(&opts.width) {
        bail!(
            "--width: must lie in [200, 4000] pixels, got {}",
            opts.width
        );
    }
    if !(1..=50).contains(&opts.fps) {
        bail!("--fps: must lie in [1, 50], got {}", opts.fps);
    }
    let gsd = if input.is_dir() {
        let t = input.join("trajectory.gsd");
        if !t.exists() {
            bail!(
                "{}: no trajectory.gsd in this folder (a run writes one with observe.trajectory.every > 0)",
                input.display()
            );
        }
        t
    } else {
        input.to_path_buf()
    };
    let total = frame_count(&gsd)?;
    if total == 0 {
        bail!("{}: the file holds no frames", gsd.display());
    }
    let folder = gsd.parent().map(Path::to_path_buf).unwrap_or_default();
    let out = opts.out.clone().unwrap_or_else(|| {
        folder.join(if opts.animate {
            "movie.gif"
        } else {
            "snapshot.png"
        })
    });
    let ext = out.extension().map(|e| e.to_string_lossy().to_lowercase());
    match (opts.animate, ext.as_deref()) {
        (true, Some("gif")) | (false, Some("png")) => {}
        (true, _) => bail!("--out: an animation is a .gif file, got {}", out.display()),
        (false, _) => bail!("--out: a snapshot is a .png file, got {}", out.display()),
    }
    if out.exists() && !opts.force {
        bail!(
            "{} exists: choose another --out, or --force to replace it",
            out.display()
        );
    }
    let name = gsd
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let snapshot = opts.frame.unwrap_or(total - 1);
    if snapshot >= total {
        bail!(
            "--frame: frame {snapshot} requested, the file holds frames 0..={}",
            total - 1
        );
    }
    let first = read_shot(
        &gsd,
        if opts.animate {
            opts.frames.first.min(total - 1)
        } else {
            snapshot
        },
    )
    .context("reading the trajectory")?;
    if first.pos.is_empty() {
        bail!("{}: the frame holds no particles", gsd.display());
    }
    let line = first.on_a_line();
    let width = opts.width;
    if line {
        let list = if opts.animate || opts.frame.is_none() {
            frame_list(opts.frames, total)?
        } else {
            vec![snapshot]
        };
        let shots: Vec<Shot> = list
            .iter()
            .map(|&k| read_shot(&gsd, k))
            .collect::<Result<_>>()?;
        if opts.animate {
            let size = (width, (width / 4).max(120));
            let delay = 1000 / opts.fps;
            atomically(&out, |tmp| {
                let area = BitMapBackend::gif(tmp, size, delay)?.into_drawing_area();
                for s in &shots {
                    draw_line(
                        &area,
                        s,
                        &format!("{name}: {} rods, step {}", s.pos.len(), s.step),
                    )?;
                    area.present()?;
                }
                Ok(())
            })?;
        } else {
            let size = (width, width * 3 / 4);
            atomically(&out, |tmp| {
                let area = BitMapBackend::new(tmp, size).into_drawing_area();
                draw_space_time(
                    &area,
                    &shots,
                    &format!(
                        "{name}: {} rods, {} frames (time downwards)",
                        first.pos.len(),
                        shots.len()
                    ),
                )?;
                area.present()?;
                Ok(())
            })?;
        }
        return Ok(out);
    }
    if first.edges[2] == 0.0 {
        bail!(
            "{}: a two-dimensional frame that is not a line of rods: not supported",
            gsd.display()
        );
    }
    let size = (width, width * 3 / 4);
    let camera = Camera::fit(&first, size);
    let title = |s: &Shot| {
        format!(
            "{name}: {} particles, step {}{}",
            s.pos.len(),
            s.step,
            if opts.cut {
                " (near half cut away)"
            } else {
                ""
            }
        )
    };
    if opts.animate {
        let list = frame_list(opts.frames, total)?;
        let delay = 1000 / opts.fps;
        atomically(&out, |tmp| {
            let area = BitMapBackend::gif(tmp, size, delay)?.into_drawing_area();
            for &k in &list {
                let s = read_shot(&gsd, k)?;
                draw_spheres(&area, &s, &camera, opts, &title(&s))?;
                area.present()?;
            }
            Ok(())
        })?;
    } else {
        atomically(&out, |tmp| {
            let area = BitMapBackend::new(tmp, size).into_drawing_area();
            draw_spheres(&area, &first, &camera, opts, &title(&first))?;
            area.present()?;
            Ok(())
        })?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_and_frame_lists() {
        assert_eq!(scale_colour(0.0), RGBColor(68, 1, 84));
        assert_eq!(scale_colour(1.0), RGBColor(253, 231, 37));
        assert_eq!(scale_colour(f64::NAN), RGBColor(68, 1, 84));
        assert!("colour".parse::<Colour>().is_err());
        let f = Frames {
            first: 0,
            last: None,
            stride: 1,
        };
        assert_eq!(frame_list(f, 5).unwrap(), vec![0, 1, 2, 3, 4]);
        let thinned = frame_list(f, 1000).unwrap();
        assert_eq!(thinned.len(), MAX_FRAMES);
        assert_eq!((thinned[0], thinned[MAX_FRAMES - 1]), (0, 999));
        assert!(
            frame_list(
                Frames {
                    first: 5,
                    last: None,
                    stride: 1
                },
                5
            )
            .is_err()
        );
    }

    #[test]
    fn the_camera_sees_the_centre_in_the_middle_and_near_spheres_larger() {
        let shot = Shot {
            step: 0,
            edges: [20.0; 3],
            pos: vec![
                [-3.0, 0.0, 0.0],
                [3.0, 0.0, 0.0],
                [0.0, 0.0, 3.0],
                [0.0, 0.0, -3.0],
            ],
            diameter: vec![1.0; 4],
            typeid: vec![0; 4],
            types: vec!["A".into()],
            walls: None,
        };
        let cam = Camera::fit(&shot, (800, 600));
        let (x, y, _, _) = cam.project(cam.centre);
        assert!(x.abs() < 1e-9 && y.abs() < 1e-9);
        // The camera sits at +z (azimuth 35 degrees from z): the sphere at z = 3 is nearer.
        let near = cam.project([0.0, 0.0, 3.0]);
        let far = cam.project([0.0, 0.0, -3.0]);
        assert!(near.2 < far.2 && near.3 > far.3);
        // The enclosing sphere fits the picture.
        for p in &shot.pos {
            let (x, y, _, _) = cam.project(*p);
            assert!(x.abs() < 300.0 && y.abs() < 300.0);
        }
        assert!(!cam.show_box);
    }

    /// Drawn into memory: of two spheres on the line of sight through the centre, the near
    /// one (red) covers the far one (blue), a cut view leaves the near one out, and the corners
    /// stay white.
    #[test]
    fn spheres_cover_the_middle_and_the_cut_removes_the_near_half() {
        crate::output::plot::register_font();
        let (az, el) = (35f64.to_radians(), 25f64.to_radians());
        let t = [el.cos() * az.sin(), el.sin(), el.cos() * az.cos()];
        let shot = Shot {
            step: 0,
            edges: [20.0; 3],
            pos: vec![
                [-4.0 * t[0], -4.0 * t[1], -4.0 * t[2]],
                [4.0 * t[0], 4.0 * t[1], 4.0 * t[2]],
            ],
            diameter: vec![2.0, 1.0],
            typeid: vec![0, 1],
            types: vec!["A".into(), "B".into()],
            walls: None,
        };
        let size = (400u32, 300u32);
        let camera = Camera::fit(&shot, size);
        let draw = |cut: bool| {
            let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
            {
                let area = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
                let opts = RenderOptions {
                    cut,
                    ..Default::default()
                };
                draw_spheres(&area, &shot, &camera, &opts, "").unwrap();
                area.present().unwrap();
            }
            buf
        };
        let pixel = |buf: &[u8], p: (f64, f64)| {
            let (x, y) = ((p.0 + 200.0) as usize, (p.1 + 160.0) as usize);
            let k = 3 * (y * 400 + x);
            [buf[k], buf[k + 1], buf[k + 2]]
        };
        let near = camera.project(shot.pos[1]);
        assert!(near.0.abs() < 1e-6 && near.1.abs() < 1e-6);
        let whole = draw(false);
        let cut = draw(true);
        let at = pixel(&whole, (near.0, near.1));
        assert!(at[0] > at[2], "{at:?}");
        let at = pixel(&cut, (near.0, near.1));
        assert!(at[2] > at[0] && at != [255, 255, 255], "{at:?}");
        assert_eq!(pixel(&whole, (-199.0, 139.0)), [255, 255, 255]);
    }
}
