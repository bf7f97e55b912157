//! Draw the table of `dt_errors` (its `--csv` file) as error against dt on log axes, Euler
//! against Leimkuhler–Matthews: `cargo run --release -p colloidsim-bcd --example
//! dt_errors_plot -- TABLE.csv OUT.png`.
//!
//! Left: the density's L1 error for the force-only case (`dilute`), two of the hard-rods paper's
//! Fig. 3 cases and the collision-only case (`gravity`). Right: the contact density's error in
//! the Tonks gas (collisions only) for two windows, with Siegmund's prediction for Euler.
//! Thin lines on the right: Siegmund's leading-order boundary layer for Euler; grey lines on the
//! left: slopes dt, dt^2 and dt^1/2. Filled circles and solid lines: Euler; open circles and
//! dashed lines: LM. Points whose error
//! is not resolved (L1 below twice its noise floor; |error| below twice its standard error) are
//! drawn as crosses at that bound: the true error lies below them.

use plotters::prelude::*;
use std::collections::BTreeMap;

static FONT: &[u8] = include_bytes!("../../run/assets/DejaVuSans.ttf");

/// One point: dt, value, error, whether resolved.
type Point = (f64, f64, f64, bool);

/// A prediction drawn as a thin line: the function of dt and its colour.
type Prediction = (Box<dyn Fn(f64) -> f64>, RGBColor);

const COLOURS: [RGBColor; 5] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().collect();
    let (input, output) = match (a.get(1), a.get(2)) {
        (Some(i), Some(o)) => (i, o),
        _ => return Err("usage: dt_errors_plot TABLE.csv OUT.png".into()),
    };
    let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    let text = std::fs::read_to_string(input)?;
    // (case, scheme, observable) -> points, from the columns of dt_errors' CSV.
    let mut series: BTreeMap<(String, String, String), Vec<Point>> = BTreeMap::new();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if f.len() < 11 {
            continue;
        }
        let num = |i: usize| f[i].parse::<f64>().unwrap_or(f64::NAN);
        let (dt, l1, l1_err, floor, peak, peak_err) =
            (num(2), num(6), num(7), num(8), num(9), num(10));
        let point = if f[5] == "density" {
            (dt, l1, l1_err, l1 > 2.0 * floor)
        } else {
            // The contact densities of the Tonks gas are flat: one bin, the signed error.
            (dt, peak.abs(), peak_err, peak.abs() > 2.0 * peak_err)
        };
        let point = if point.3 {
            point
        } else {
            let bound = if f[5] == "density" {
                2.0 * floor
            } else {
                2.0 * peak_err
            };
            (dt, bound, 0.0, false)
        };
        series
            .entry((f[0].to_string(), f[1].to_string(), f[5].to_string()))
            .or_default()
            .push(point);
    }

    let root = BitMapBackend::new(output, (1500, 620)).into_drawing_area();
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(760);
    let density = [
        ("dilute", "dilute (forces only)"),
        ("hard-0.5-0.5", "sigma = rho = 0.5"),
        ("hard-0.8-0.8", "sigma = rho = 0.8"),
        ("gravity", "sediment (collisions only)"),
    ];
    let curves: Vec<(String, Vec<Point>, Vec<Point>)> = density
        .iter()
        .map(|(case, label)| {
            let get = |s: &str| {
                series
                    .get(&(case.to_string(), s.to_string(), "density".to_string()))
                    .cloned()
                    .unwrap_or_default()
            };
            (label.to_string(), get("euler"), get("lm"))
        })
        .collect();
    panel(
        &left,
        "density: L1 error against the exact theory",
        "L1 error of rho(x)",
        (1e-4, 1.0),
        &curves,
        &[(1.0, "dt", 0.8), (2.0, "dt^2", 0.06), (0.5, "dt^1/2", 0.8)],
        None,
        SeriesLabelPosition::UpperLeft,
    )?;
    let contact = [
        ("1e-1", "Tonks gas, w = 0.1"),
        ("1e-2", "Tonks gas, w = 0.01"),
    ];
    let curves: Vec<(String, Vec<Point>, Vec<Point>)> = contact
        .iter()
        .map(|(w, label)| {
            let get = |s: &str| {
                series
                    .get(&("tonks".to_string(), s.to_string(), format!("contact w={w}")))
                    .cloned()
                    .unwrap_or_default()
            };
            (label.to_string(), get("euler"), get("lm"))
        })
        .collect();
    // Siegmund's leading-order boundary layer for Euler: rho2 too high by a delta / (1 - e^{-a w}),
    // delta = 0.5826 sqrt(4 D dt), a = rho / (1 - rho sigma) = 2/3 (rho = sigma = 0.5).
    let siegmund = |w: f64| {
        move |dt: f64| {
            let a = 0.5 / (1.0 - 0.25);
            a * 0.582_597 * (4.0 * dt).sqrt() / (1.0 - (-a * w).exp())
        }
    };
    panel(
        &right,
        "contact density (collisions only): relative error",
        "relative error of rho2",
        (1e-2, 3e2),
        &curves,
        &[],
        Some([
            (
                Box::new(siegmund(0.1)) as Box<dyn Fn(f64) -> f64>,
                COLOURS[0],
            ),
            (Box::new(siegmund(0.01)), COLOURS[1]),
        ]),
        SeriesLabelPosition::LowerRight,
    )?;
    root.present()?;
    Ok(())
}

/// One log-log panel: for each curve Euler (filled, solid) and LM (open, dashed); grey guide
/// slopes; optional thin lines of predictions.
fn panel(
    area: &DrawingArea<BitMapBackend, plotters::coord::Shift>,
    title: &str,
    ylabel: &str,
    (ymin, ymax): (f64, f64),
    curves: &[(String, Vec<Point>, Vec<Point>)],
    slopes: &[(f64, &str, f64)],
    predictions: Option<[Prediction; 2]>,
    legend: SeriesLabelPosition,
) -> Result<(), Box<dyn std::error::Error>> {
    let (xmin, xmax): (f64, f64) = (7e-6, 1.4e-2);
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(75)
        .build_cartesian_2d((xmin..xmax).log_scale(), (ymin..ymax).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("time step dt")
        .y_desc(ylabel)
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 15))
        .draw()?;
    let grey = RGBColor(160, 160, 160);
    for &(p, label, at) in slopes {
        // Guides through (1e-2, at).
        let f = |dt: f64| at * (dt / 1e-2).powf(p);
        let pts: Vec<(f64, f64)> = (0..=60)
            .map(|k| xmin * (xmax / xmin).powf(k as f64 / 60.0))
            .map(|dt| (dt, f(dt)))
            .filter(|&(_, y)| y > ymin && y < ymax)
            .collect();
        chart.draw_series(LineSeries::new(pts.clone(), grey.stroke_width(1)))?;
        // The label a third of the way along the visible part of the guide.
        if let Some(&(x, y)) = pts.get(pts.len() / 3) {
            chart.draw_series(std::iter::once(Text::new(
                label.to_string(),
                (x, y * 1.15),
                ("sans-serif", 14).into_font().color(&grey),
            )))?;
        }
    }
    if let Some(preds) = &predictions {
        for (f, c) in preds {
            let pts: Vec<(f64, f64)> = (0..=60)
                .map(|k| xmin * (xmax / xmin).powf(k as f64 / 60.0))
                .map(|dt| (dt, f(dt)))
                .collect();
            chart.draw_series(LineSeries::new(pts, c.mix(0.5).stroke_width(1)))?;
        }
    }
    for (k, (label, euler, lm)) in curves.iter().enumerate() {
        let c = COLOURS[k % COLOURS.len()];
        for (points, lm_style) in [(euler, false), (lm, true)] {
            let resolved: Vec<(f64, f64)> =
                points.iter().filter(|p| p.3).map(|p| (p.0, p.1)).collect();
            let line = if lm_style {
                dashed(&resolved)
            } else {
                vec![resolved.clone()]
            };
            for seg in line {
                chart.draw_series(LineSeries::new(seg, c.stroke_width(2)))?;
            }
            for p in points {
                if p.3 {
                    let lo = (p.1 - p.2).max(ymin);
                    chart.draw_series(std::iter::once(PathElement::new(
                        vec![(p.0, lo), (p.0, p.1 + p.2)],
                        c.stroke_width(1),
                    )))?;
                    let style = if lm_style {
                        c.stroke_width(2)
                    } else {
                        c.filled()
                    };
                    chart.draw_series(std::iter::once(Circle::new((p.0, p.1), 5, style)))?;
                } else {
                    chart.draw_series(std::iter::once(Cross::new(
                        (p.0, p.1),
                        4,
                        c.stroke_width(1),
                    )))?;
                }
            }
        }
        chart
            .draw_series(std::iter::once(Circle::new((xmin, ymin), 0, c.filled())))?
            .label(format!("{label}: Euler (filled), LM (open)"))
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, c.filled()));
    }
    chart
        .configure_series_labels()
        .position(legend)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()?;
    Ok(())
}

/// A polyline cut into dashes (for the LM curves), in log coordinates.
fn dashed(points: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
    let mut out = Vec::new();
    for w in points.windows(2) {
        let (a, b) = (w[0], w[1]);
        let steps = 12;
        for k in (0..steps).step_by(2) {
            let t0 = k as f64 / steps as f64;
            let t1 = (k + 1) as f64 / steps as f64;
            let at = |t: f64| {
                (
                    (a.0.ln() + t * (b.0.ln() - a.0.ln())).exp(),
                    (a.1.ln() + t * (b.1.ln() - a.1.ln())).exp(),
                )
            };
            out.push(vec![at(t0), at(t1)]);
        }
    }
    out
}
