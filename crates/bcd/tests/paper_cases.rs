//! The hard-rods paper's validation set (Sec. III C and IV B): density profiles of hard rods for
//! sigma in {0.2, 0.5, 0.8} x mean density in {0.2, 0.5, 0.8}, and sticky rods gamma in
//! {0.1, 1, 10}, against the exact theory. Long: `cargo test -p colloidsim-bcd --test paper_cases
//! --release -- --ignored --nocapture`; the table it prints is in docs/validation.md.

mod common;

use common::{Case, compare};

fn case(sigma: f64, rho: f64, gamma: Option<f64>, seed: u32) -> Case {
    // Denser systems collide more often per unit time: smaller steps, as in the paper.
    let dt = if rho * sigma > 0.3 || gamma.is_some_and(|g| g > 1.0) {
        2e-5
    } else {
        1e-4
    };
    let block_steps = (2.0 / dt) as u64;
    Case {
        sigma,
        rho,
        gamma,
        length: 100.0,
        dt,
        bins: 50,
        equilibrate_steps: block_steps,
        blocks: 10,
        block_steps,
        seed,
    }
}

#[test]
#[ignore = "long: the full paper set, about half an hour on one core"]
fn paper_density_profiles_match_exact_theory() {
    let mut cases = Vec::new();
    for &sigma in &[0.2, 0.5, 0.8] {
        for &rho in &[0.2, 0.5, 0.8] {
            cases.push(case(sigma, rho, None, cases.len() as u32 + 1));
        }
    }
    for &gamma in &[0.1, 1.0, 10.0] {
        cases.push(case(0.5, 0.5, Some(gamma), cases.len() as u32 + 1));
    }
    println!(
        "| sigma | rho | gamma | dt | largest deviation (std. errors) | chi^2 for sigma x 1.1 (bins) |"
    );
    println!("|---|---|---|---|---|---|");
    let mut failures = Vec::new();
    for c in &cases {
        let o = compare(c);
        println!(
            "| {} | {} | {} | {:e} | {:.2} | {:.0} ({}) |",
            c.sigma,
            c.rho,
            c.gamma.map_or("hard".to_string(), |g| g.to_string()),
            c.dt,
            o.worst,
            o.chi2_wrong_sigma,
            o.bins
        );
        // Hard rods must agree within 5 standard errors in every bin; sticky rods carry the
        // finite-eps bias of the power-law representation (eps = 0.05), reported, not asserted.
        if c.gamma.is_none() && o.worst > 5.0 {
            failures.push((c.sigma, c.rho, o.worst));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}
