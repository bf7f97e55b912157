//! Equilibrium is unchanged by hydrodynamics: in a static droplet (`drying.peclet = 0`) the
//! radial profile sampled with the RPY mobility equals the free-draining one within the
//! statistical error of the two runs. The RPY mobility is divergence-free, so the BD step has
//! no drift term and samples the same Boltzmann distribution as free draining; a spurious drift
//! (or noise that does not match the mobility) would change the profile.

use colloidsim_md::hydro::{HydroMethod, HydroModel, HydroParams};
use colloidsim_md::{DropletParams, HydroBdParams};

/// A static droplet of `N` WCA spheres at phi0 = 0.2 (R0 = 3.42 d) in the harmonic interface,
/// with the scenario lines `extra` added.
const N: usize = 64;
fn static_droplet(extra: &str) -> DropletParams {
    let text = format!(
        "method = \"droplet-bd\"\nseed = 11\n[system]\nparticles = {N}\nphi0 = 0.2\n\
         [drying]\npeclet = 0\nduration = 1.0\n[run]\ndt = {DT}\n{extra}"
    );
    droplet_params(&text)
}

/// Time step: 2e-4 d^2 / D0 (as examples/droplet/drying-bd.toml; D0 = kT / (3 pi eta d) =
/// 0.106 d^2 per unit time). At 5e-4 d^2 / D0 the free-draining run blows up at phi = 0.2.
const DT: f64 = 1.885e-3;
/// Steps discarded at the start (random insertion is not the equilibrium layering at the wall),
/// and sampled afterwards (every [`EVERY`] steps) in [`BLOCKS`] consecutive blocks.
const EQUILIBRATE: u64 = 4000;
const SAMPLED: u64 = 30_000;
const EVERY: u64 = 10;
/// Blocks of 3000 steps (5.7 time units, 0.6 d^2 / D0): blocks twice as long give standard
/// errors larger by 0-40% in some shells (the slowest mode is about as long as a block), so the
/// thresholds below are set at p = 0.001 rather than tighter.
const BLOCKS: usize = 10;
/// Shells of equal width from the centre to R0 + offset + range (where the interface
/// potential ends).
const SHELLS: usize = 12;

/// Mean particle count per shell and its standard error from the scatter of the block means.
struct Profile {
    mean: Vec<f64>,
    se: Vec<f64>,
}

/// Sample the shell counts of a run: `advance(k)` moves the run k steps, `positions()` gives
/// the current centres (the droplet is centred on the origin).
fn sample(
    p: &DropletParams,
    mut advance: impl FnMut(u64),
    positions: impl Fn() -> Vec<[f64; 3]>,
) -> Profile {
    let r_max = p.r0 + p.offset + p.range;
    let shell = |x: &[f64; 3]| {
        let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt() / r_max;
        ((r * SHELLS as f64) as usize).min(SHELLS)
    };
    advance(EQUILIBRATE);
    let per_block = SAMPLED / EVERY / BLOCKS as u64;
    let mut blocks = vec![vec![0.0; SHELLS]; BLOCKS];
    for block in blocks.iter_mut() {
        for _ in 0..per_block {
            advance(EVERY);
            for x in positions() {
                let s = shell(&x);
                // Beyond r_max (deep in the interface): not counted.
                if s < SHELLS {
                    block[s] += 1.0;
                }
            }
        }
        block.iter_mut().for_each(|c| *c /= per_block as f64);
    }
    let b = BLOCKS as f64;
    let mean: Vec<f64> = (0..SHELLS)
        .map(|s| blocks.iter().map(|c| c[s]).sum::<f64>() / b)
        .collect();
    let se = (0..SHELLS)
        .map(|s| {
            let var = blocks.iter().map(|c| (c[s] - mean[s]).powi(2)).sum::<f64>() / (b - 1.0);
            (var / b).sqrt()
        })
        .collect();
    Profile { mean, se }
}

fn free_draining(p: &DropletParams) -> Profile {
    let sim = std::cell::RefCell::new(p.build_replica(0).unwrap());
    sample(
        p,
        |k| sim.borrow_mut().run(k).unwrap(),
        || sim.borrow().snapshot().pos,
    )
}

/// RPY in an unbounded fluid (direct sums), with the noise at `noise_kt` (kT of the scenario:
/// the fluctuation-dissipation theorem holds).
fn rpy(p: &DropletParams, noise_kt: f64) -> Profile {
    // `model = "rpy"`, `method = "direct"`, the other keys at their defaults.
    let h = HydroParams {
        model: HydroModel::Rpy,
        method: Some(HydroMethod::Direct),
        tolerance: 1e-3,
        splitting: 1.0 / p.diameter,
        box_factor: 2.0,
        max_iterations: 200,
    };
    let built = p.build_hydro_replica(0, &h).unwrap();
    let params = HydroBdParams {
        kt: noise_kt,
        ..*built.params()
    };
    let sim = p
        .restart_hydro_replica(built.particles().clone(), &h, params, 0)
        .unwrap();
    let sim = std::cell::RefCell::new(sim);
    sample(
        p,
        |k| sim.borrow_mut().run(k).unwrap(),
        || sim.borrow().particles().pos.clone(),
    )
}

/// `sum_s (mean_a - mean_b)^2 / (se_a^2 + se_b^2)` over the shells.
fn chi2(a: &Profile, b: &Profile) -> f64 {
    (0..SHELLS)
        .map(|s| (a.mean[s] - b.mean[s]).powi(2) / (a.se[s].powi(2) + b.se[s].powi(2)))
        .sum()
}

/// The 0.999 quantile of chi^2 with 12 degrees of freedom (one per shell; their counts nearly
/// sum to N, so 11 would be closer: the bound is lenient by one degree of freedom).
const CHI2_12_999: f64 = 32.91;

/// The free-draining and RPY profiles of `p` agree: chi^2 over the shells below its 0.999
/// quantile, and the outermost shell (the contact layer: the part of the profile most
/// sensitive to noise that does not match the mobility, to a drift, or to a wall that does not
/// move the neighbours of the sphere it reflects) alone within 3.5 standard errors, resolved
/// to 6 %.
fn same_profiles(p: &DropletParams) {
    assert!(p.is_static());
    let fd = free_draining(p);
    let hi = rpy(p, p.kt);
    for s in 0..SHELLS {
        eprintln!(
            "shell {s}: free draining {:.3} +- {:.3}, RPY {:.3} +- {:.3}",
            fd.mean[s], fd.se[s], hi.mean[s], hi.se[s]
        );
    }
    let x2 = chi2(&fd, &hi);
    eprintln!("chi^2 = {x2:.2} over {SHELLS} shells (0.999 quantile {CHI2_12_999})");
    assert!(
        x2 < CHI2_12_999,
        "RPY profile differs from free draining: chi^2 = {x2}"
    );
    let o = SHELLS - 1;
    let (diff, se) = (hi.mean[o] - fd.mean[o], fd.se[o].hypot(hi.se[o]));
    assert!(se < 0.06 * fd.mean[o], "outer shell too noisy: {se}");
    assert!(
        diff.abs() < 3.5 * se,
        "outer shell: RPY {} vs free draining {} (+- {se})",
        hi.mean[o],
        fd.mean[o]
    );
}

/// In the harmonic interface the outermost shell lies beyond R0 + offset: its occupation is
/// the Boltzmann tail.
#[test]
fn a_static_droplet_has_the_same_profile_with_rpy_as_free_draining() {
    same_profiles(&static_droplet(""));
}

/// Behind a hard wall (`interface.hard`) the outermost shell is the layer in contact with it:
/// RPY's reflection along the mobility keeps the equilibrium of free draining's along the
/// normal (reflecting RPY steps along the normal alone presses pairs at the wall together).
#[test]
fn a_static_droplet_behind_a_hard_wall_has_the_same_profile_with_rpy_as_free_draining() {
    let p = static_droplet("[interface]\nhard = true\n");
    assert!(p.hard_interface);
    same_profiles(&p);
}

/// A `droplet-bd` scenario read by the run layer (its keys through their declarations).
fn droplet_params(text: &str) -> colloidsim_md::DropletParams {
    colloidsim_run::methods::droplet_bd::params::read(
        &toml::from_str(text).unwrap(),
        std::path::Path::new("."),
        None,
    )
    .unwrap()
}
