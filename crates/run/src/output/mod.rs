//! The writers every session shares: the GSD trajectory (its opener, frame digest and trim on
//! restart: [`trajectory`]), pictures ([`plot`]), the per-species profiles of a mixture ([`species`]) and the drying droplet's profile names (of
//! droplet-bd, its theory and droplet-mpcd). Tables, thermo logs (`CsvLog`), JSON and the
//! atomic writes under them, with the rule that every number is finite or empty with its
//! reason, are `colloidsim_core::output`'s, which the engine crates use too.

pub mod plot;
pub mod species;
pub mod trajectory;

/// Most wave numbers of `sq.csv` (its transform costs wave numbers x g(r) bins; q d reaches
/// 1000 pi d / r_max, far beyond the structure's first peaks).
pub const MAX_Q_POINTS: usize = 1000;

/// The pair structure of spheres as runs and `colloidsim analyse` write it.
pub struct PairStructure<'a> {
    /// Bin mid-points of g(r).
    pub r: &'a [f64],
    /// g(r), averaged over samples.
    pub g: &'a [f64],
    /// Its standard error over the samples.
    pub err: &'a [f64],
    /// The diameter lengths are counted in (`r_over_diameter`, `q_diameter`).
    pub diameter: f64,
    /// Number density, for S(q).
    pub rho: f64,
    /// Range of g(r), for the wave numbers of S(q).
    pub r_max: f64,
    /// The hard-sphere Percus–Yevick solution to draw beside g, if any.
    pub percus_yevick: Option<&'a colloidsim_dft::oz::PySolution>,
    /// Legend of the measured g.
    pub label: &'a str,
    /// Title of the picture.
    pub title: &'a str,
    /// Its x axis.
    pub xlabel: &'a str,
}

/// Write `gr.csv` (g(r) with its standard error), `sq.csv` (S(q) from g with the Lorch window,
/// at most [`MAX_Q_POINTS`] wave numbers `q_k = k pi / r_max`), `gr_percus_yevick.csv` where
/// given, and `gr.png`; the names join `files` in that order.
pub fn write_pair_structure(
    out: &colloidsim_core::output::OutputDir,
    p: &PairStructure,
    files: &mut Vec<String>,
    warnings: &mut Vec<String>,
) -> anyhow::Result<()> {
    use colloidsim_analysis::{Window, default_q_grid, structure_factor_windowed};
    use plot::{Scale, Series, Style, line_plot_styled, picture};
    let r_over_d: Vec<f64> = p.r.iter().map(|x| x / p.diameter).collect();
    out.write_table(
        "gr.csv",
        &[
            ("r", p.r),
            ("r_over_diameter", &r_over_d),
            ("g", p.g),
            ("err", p.err),
        ],
    )?;
    files.push("gr.csv".into());
    let q = default_q_grid(p.r_max, p.g.len().min(MAX_Q_POINTS));
    let sq = structure_factor_windowed(p.r, p.g, p.rho, &q, Window::Lorch);
    let q_d: Vec<f64> = q.iter().map(|x| x * p.diameter).collect();
    out.write_table("sq.csv", &[("q", &q), ("q_diameter", &q_d), ("S", &sq)])?;
    files.push("sq.csv".into());
    let py = p.percus_yevick.map(|s| s.g_at(&r_over_d));
    let mut series = vec![Series {
        label: p.label,
        x: &r_over_d,
        y: p.g,
        points: false,
    }];
    if let Some(py) = &py {
        out.write_table(
            "gr_percus_yevick.csv",
            &[("r", p.r), ("r_over_diameter", &r_over_d), ("g", py)],
        )?;
        files.push("gr_percus_yevick.csv".into());
        series.push(Series {
            label: "hard spheres, Percus-Yevick",
            x: &r_over_d,
            y: py,
            points: false,
        });
    }
    picture(
        line_plot_styled(
            &out.join("gr.png"),
            p.title,
            p.xlabel,
            "g(r)",
            &series,
            &[Some(p.err), None],
            Scale::Linear,
            Style {
                legend_outside: true,
            },
        ),
        "gr.png",
        files,
        warnings,
    );
    Ok(())
}

/// File name of the profile at `fraction` of the drying time: `profile_0.25.csv` (two decimals,
/// more when the fraction needs them).
pub fn profile_name(fraction: f64) -> String {
    if ((fraction * 100.0).round() - fraction * 100.0).abs() < 1e-9 {
        format!("profile_{fraction:.2}.csv")
    } else {
        format!("profile_{fraction}.csv")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profile_names_match_the_fractions() {
        assert_eq!(profile_name(0.0), "profile_0.00.csv");
        assert_eq!(profile_name(0.25), "profile_0.25.csv");
        assert_eq!(profile_name(1.0), "profile_1.00.csv");
        assert_eq!(profile_name(0.125), "profile_0.125.csv");
    }
}
