//! The hard-rods paper's Fig. 5: (a) the sticky contact force f_p(r) of Eq. 33 for several
//! orders p (eps = 0.05, gamma = 1, sigma = 0.2), (b) its largest magnitude against p for
//! eps = 0.025, 0.05 and 0.1, which sets the time step by Eq. 34:
//! `cargo run --release -p colloidsim-bcd --example sticky_force -- OUT.png`.
//! Prints the order with the smallest maximum for each eps (2.95 at eps = 0.05, as in the paper).

use colloidsim_bcd::forces::{PairForce, Sticky};
use plotters::prelude::*;

static FONT: &[u8] = include_bytes!("../../run/assets/DejaVuSans.ttf");

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let output = std::env::args()
        .nth(1)
        .ok_or("usage: sticky_force OUT.png")?;
    let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    let (sigma, gamma, kt) = (0.2, 1.0, 1.0);
    let sticky = |p: f64, eps: f64| Sticky::new(gamma, eps, p, sigma, kt);
    let root = BitMapBackend::new(&output, (1200, 500)).into_drawing_area();
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(600);

    // (a) f_p(r) over the contact range and a little beyond.
    let orders = [1.5, 2.0, 2.95, 4.0, 6.0];
    let mut chart = ChartBuilder::on(&left)
        .caption(
            "(a) sticky force, eps = 0.05, gamma = 1, sigma = 0.2",
            ("sans-serif", 18),
        )
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.195..0.26, -260.0..10.0)?;
    chart
        .configure_mesh()
        .x_desc("r (length)")
        .y_desc("f_p(r) (kT / length)")
        .draw()?;
    for (k, &p) in orders.iter().enumerate() {
        let st = sticky(p, 0.05)?;
        let colour = Palette99::pick(k).to_rgba();
        let curve = (0..=600).map(|i| {
            let r = sigma + 0.06 * i as f64 / 600.0;
            (r, st.force(r))
        });
        chart
            .draw_series(LineSeries::new(curve, colour.stroke_width(2)))?
            .label(format!("p = {p}"))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;

    // (b) max |f_p| against p.
    let mut chart = ChartBuilder::on(&right)
        .caption("(b) largest |f_p| against the order p", ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(1.2..8.0, (30.0..1000.0).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("p")
        .y_desc("max |f_p| (kT / length)")
        .draw()?;
    for (k, &eps) in [0.025, 0.05, 0.1].iter().enumerate() {
        let colour = Palette99::pick(k).to_rgba();
        let curve: Vec<(f64, f64)> = (0..=680)
            .map(|i| {
                let p = 1.2 + i as f64 / 100.0;
                (p, sticky(p, eps).map(|s| s.max_force()).unwrap_or(f64::NAN))
            })
            .collect();
        let best = curve
            .iter()
            .copied()
            .fold((0.0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
        println!(
            "eps = {eps}: smallest max|f| = {:.2} kT/length at p = {:.2}",
            best.1, best.0
        );
        chart
            .draw_series(LineSeries::new(curve, colour.stroke_width(2)))?
            .label(format!("eps = {eps}"))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(2)));
        chart.draw_series(std::iter::once(Circle::new(best, 5, colour.filled())))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}
