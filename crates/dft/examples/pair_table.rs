//! Tables of the pair correlation the RPY DDFT can use (docs/theory-droplet.md):
//! `g_r.csv` (`x = r/d`, then Trokhymchuk's `g` at eta = 0.1 ... 0.6) and `sedimentation.csv`
//! (`phi`, the bulk sedimentation coefficient of the RPY flux with the dilute `g`, `1 - 5 phi`,
//! and with Trokhymchuk's, `1 - 5 phi + 12 phi int_1^8 x h dx`).
//!
//! `cargo run --release -p colloidsim-dft --example pair_table -- OUTDIR`

use std::fmt::Write as _;

use colloidsim_dft::radial::pair::{TotalCorrelation, bulk_sedimentation};
use colloidsim_dft::radial::rpy::PAIR_RANGE;

fn main() {
    let dir = std::path::PathBuf::from(std::env::args().nth(1).expect("usage: pair_table OUTDIR"));
    std::fs::create_dir_all(&dir).expect("output folder");
    let etas = [0.1, 0.2, 0.3, 0.4, 0.471, 0.55];
    let hs: Vec<TotalCorrelation> = etas
        .iter()
        .map(|&e| TotalCorrelation::new(e).expect("eta"))
        .collect();
    let mut g = String::from("x");
    for e in etas {
        write!(g, ",g_{e}").unwrap();
    }
    g.push('\n');
    for k in 0..=600 {
        let x = 0.9 + k as f64 * 0.005;
        write!(g, "{x:.4}").unwrap();
        for h in &hs {
            write!(g, ",{:.6}", h.h(x) + 1.0).unwrap();
        }
        g.push('\n');
    }
    std::fs::write(dir.join("g_r.csv"), g).expect("write g_r.csv");
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
    println!("wrote g_r.csv and sedimentation.csv in {}", dir.display());
}
