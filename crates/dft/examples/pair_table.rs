//! Tables of the pair correlation the RPY DDFT can use (docs/theory-droplet.md):
//! `g_r.csv` (`x = r/d` from 0.9 to 3.9 in steps of 0.005, then Trokhymchuk's `g` at
//! eta = 0.1 ... 0.55), `contact.csv` (`eta`, Trokhymchuk's contact value `g(d+)`, Carnahan and
//! Starling's `(Z_CS - 1) / (4 eta)`) and `sedimentation.csv` (`phi`, the bulk sedimentation
//! coefficient of the RPY flux with the dilute `g`, `1 - 5 phi`, and with Trokhymchuk's,
//! `1 - 5 phi + 12 phi int_1^8 x h dx`).
//!
//! `cargo run --release -p colloidsim-dft --example pair_table -- OUTDIR [ETAS]`
//!
//! `ETAS`, a comma-separated list of packing fractions in `[0, 0.6]` (e.g. `0.05,0.1,0.3`),
//! replaces the default columns of `g_r.csv` and `contact.csv`, and the table then reaches
//! `x = 6` (what scripts/plot_dilute_g.py compares with the Monte Carlo g(r), Fig. S9). Below
//! eta = 0.105 the `g` is the blend of the exact low-density limit into the fit
//! (`colloidsim_dft::radial::pair::TotalCorrelation`).

use std::fmt::Write as _;

use colloidsim_dft::radial::pair::{TotalCorrelation, bulk_sedimentation};
use colloidsim_dft::radial::rpy::PAIR_RANGE;

fn main() {
    let usage = "usage: pair_table OUTDIR [ETA,ETA,...]";
    let dir = std::path::PathBuf::from(std::env::args().nth(1).expect(usage));
    let chosen: Option<Vec<f64>> = std::env::args().nth(2).map(|list| {
        list.split(',')
            .map(|e| {
                e.trim()
                    .parse::<f64>()
                    .unwrap_or_else(|_| panic!("{usage}: '{e}' is not a number"))
            })
            .collect()
    });
    let (etas, points) = match chosen {
        Some(etas) => (etas, 1020),
        None => (vec![0.1, 0.2, 0.3, 0.4, 0.471, 0.55], 600),
    };
    let hs: Vec<TotalCorrelation> = etas
        .iter()
        .map(|&e| TotalCorrelation::new(e).unwrap_or_else(|err| panic!("{usage}: {err}")))
        .collect();
    std::fs::create_dir_all(&dir).expect("output folder");
    let mut g = String::from("x");
    for e in &etas {
        write!(g, ",g_{e}").unwrap();
    }
    g.push('\n');
    for k in 0..=points {
        let x = 0.9 + k as f64 * 0.005;
        write!(g, "{x:.4}").unwrap();
        for h in &hs {
            write!(g, ",{:.6}", h.h(x) + 1.0).unwrap();
        }
        g.push('\n');
    }
    std::fs::write(dir.join("g_r.csv"), g).expect("write g_r.csv");
    let mut c = String::from("eta,trokhymchuk,carnahan_starling\n");
    for h in &hs {
        let e = h.eta();
        let z_cs = (1.0 + e + e * e - e.powi(3)) / (1.0 - e).powi(3);
        let cs = if e > 0.0 {
            (z_cs - 1.0) / (4.0 * e)
        } else {
            1.0
        };
        writeln!(c, "{e},{:.6},{cs:.6}", h.h(1.0) + 1.0).unwrap();
    }
    std::fs::write(dir.join("contact.csv"), c).expect("write contact.csv");
    let mut s = String::from("phi,k_dilute,k_trokhymchuk\n");
    for k in 0..=60 {
        let phi = k as f64 * 0.01;
        let kt = if phi == 0.0 {
            1.0
        } else {
            bulk_sedimentation(phi, PAIR_RANGE).expect("eta")
        };
        writeln!(s, "{phi:.2},{:.6},{kt:.6}", 1.0 - 5.0 * phi).unwrap();
    }
    std::fs::write(dir.join("sedimentation.csv"), s).expect("write sedimentation.csv");
    println!(
        "wrote g_r.csv, contact.csv and sedimentation.csv in {}",
        dir.display()
    );
}
