//! The time-step error of BCD, Euler against Leimkuhler–Matthews (issue #21) and the reflecting
//! collisions (`reflect`, issue #44): density and
//! contact density against the exact theory as functions of dt, with error bars from
//! independent seeds.
//!
//! ```text
//! nice -n 10 cargo run --release -p colloidsim-bcd --example dt_errors -- \
//!     [--cases NAME,..] [--dt 1e-2,1e-3,..] [--seeds 8] [--time 200] [--steps 2000000]
//!     [--relax 2] [--schemes euler,lm,reflect] [--csv FILE]
//! ```
//!
//! Cases (`--cases`, default all):
//!
//! - `hard-S-R`: the hard-rods paper's Fig. 3 set, rods of length S at mean density R on a ring
//!   of L = 100 in `U = 3 cos(2 pi x)` kT (U0 = 6 kT), S, R in {0.2, 0.5, 0.8};
//! - `hard-0.5-1`: the case of issue #21, 100 rods of length 0.5 on L = 100 (packing 0.5; the
//!   issue compares colloidsim and the authors' code there at dt = 1e-3);
//! - `sticky`: Baxter rods, sigma = rho = 0.5, gamma = 1, power law p = 3 over eps = 0.05
//!   (paper Fig. 6), against the exact eps -> 0 theory (so a finite-eps offset remains at dt -> 0);
//! - `dilute`: 100 rods of length 0.5 on L = 10^4 in the same potential, one rod per hundred wells:
//!   collisions are rare, so this isolates the **force-discretisation** bias;
//! - `tonks`: no potential (U0 = 0), sigma = rho = 0.5: the free motion is exact for both schemes
//!   and the one-body density is flat by symmetry, so the contact density isolates the
//!   **collision** bias (the exact windowed value is `rho (1 - exp(-a w)) / w`, `a = rho / (1 - rho
//!   sigma)`);
//! - `gravity`: 20 rods of length 0.5 between walls at 0 and 20 under a constant force -0.5 kT
//!   per length (a sediment packed to about 0.8 at the bottom wall, layered there): a constant
//!   force is integrated exactly by both schemes, so the one-body density error here is
//!   collisions (rod–rod and rod–wall) alone.
//!
//! Each seed starts from an exact hard-rod configuration without field, relaxes for 40 time
//! units (`gravity`: 400, the sediment settles) at dt = 1e-4 (Leimkuhler–Matthews), and from
//! there each scheme and dt relaxes `--relax` (default 2) more time units before sampling `min(time / dt, steps)` steps, every `max(1, 1e-3 / dt)` steps.
//! Errors: density L1 `sum |rho - rho_exact| / sum rho_exact` over the bins (error by jackknife
//! over the seeds; "floor" is the L1 that the statistical noise alone would give,
//! `sqrt(2/pi) sum se / sum rho_exact`) and the relative error of the bin holding the exact
//! maximum (error from the seeds' spread); the same for the contact density in windows w.
//! The rows go to stdout as a markdown table and, with `--csv`, to a file for `dt_errors_plot`.

use colloidsim_bcd::forces::Field;
use colloidsim_bcd::forces::{NoPair, PairForce, Sticky};
use colloidsim_bcd::observe::{ContactDensity, DensityProfile};
use colloidsim_bcd::{Bcd, BcdConfig, BcdState, Boundary, Integrator, Update, init};
use colloidsim_core::field1d::{ExternalField, FieldTerm};
use colloidsim_dft::rods::{self, BetaPotential, Domain, RodInteraction, RodsProblem};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::time::Instant;

/// What acts on the rods besides the hard core.
#[derive(Clone, Copy, Debug)]
enum Potential {
    /// `U = (u0 / 2) cos(2 pi x)`.
    Cosine(f64),
    /// Constant force `-g` (potential `g x`), between walls.
    Gravity(f64),
    /// Nothing.
    None,
}

#[derive(Clone, Debug)]
struct Case {
    name: String,
    sigma: f64,
    n: usize,
    length: f64,
    boundary: Boundary,
    potential: Potential,
    gamma: Option<f64>,
    /// Bins of the density (over one period, or over L).
    bins: usize,
    /// Contact windows w of the contact density (over the same bins).
    windows: Vec<f64>,
}

impl Case {
    fn period(&self) -> f64 {
        match self.potential {
            Potential::Cosine(_) => 1.0,
            _ => self.length,
        }
    }

    fn field(&self) -> ExternalField {
        match self.potential {
            Potential::Cosine(u0) => ExternalField {
                terms: vec![FieldTerm::Cosine {
                    amplitude: u0,
                    wavelength: 1.0,
                }],
                drive: 0.0,
            },
            Potential::Gravity(g) => ExternalField {
                terms: vec![],
                drive: -g,
            },
            Potential::None => ExternalField::default(),
        }
    }

    fn config(&self, dt: f64, seed: u32) -> BcdConfig {
        BcdConfig {
            length: self.length,
            sigma: self.sigma,
            mobility: 1.0,
            kt: 1.0,
            dt,
            boundary: self.boundary,
            seed,
            update: Update::Premerge,
        }
    }

    /// Exact density and contact densities (one per window) on the case's bins.
    fn theory(&self) -> (Vec<f64>, Vec<Vec<f64>>) {
        let rho = self.n as f64 / self.length;
        if let Potential::None = self.potential {
            // Tonks gas: flat density; the nearest-neighbour gap is exponential with rate a.
            let a = rho / (1.0 - rho * self.sigma);
            let contact = self
                .windows
                .iter()
                .map(|&w| vec![rho * (1.0 - (-a * w).exp()) / w; self.bins])
                .collect();
            return (vec![rho; self.bins], contact);
        }
        let (domain, beta_u) = match self.potential {
            Potential::Cosine(u0) => (
                Domain::Periodic { period: 1.0 },
                BetaPotential::from_fn(1.0, move |x| 0.5 * u0 * (std::f64::consts::TAU * x).cos()),
            ),
            Potential::Gravity(g) => (
                Domain::Walls {
                    length: self.length,
                },
                BetaPotential::from_fn(1.0, move |x| g * x),
            ),
            Potential::None => unreachable!(),
        };
        let interaction = match self.gamma {
            Some(gamma) => RodInteraction::Sticky { gamma },
            None => RodInteraction::Hard,
        };
        let p = RodsProblem::new(self.sigma, rho, domain)
            .with_dx(1e-3_f64.min(self.sigma / 50.0))
            .with_potential(beta_u)
            .with_interaction(interaction);
        let eq = rods::equilibrium(&p).expect("exact theory");
        let b = eq.bin_average(self.bins, self.period()).expect("bins");
        // The window estimator averages the pair density over [sigma, sigma + w); for w small
        // against the field's length scale this is the contact value.
        let contact = self
            .windows
            .iter()
            .map(|_| b.contact_density.clone())
            .collect();
        (b.rho, contact)
    }
}

fn cases() -> Vec<Case> {
    let mut v = Vec::new();
    for sigma in [0.2, 0.5, 0.8] {
        for rho in [0.2, 0.5, 0.8] {
            v.push(Case {
                name: format!("hard-{sigma}-{rho}"),
                sigma,
                n: (100.0 * rho) as usize,
                length: 100.0,
                boundary: Boundary::Periodic,
                potential: Potential::Cosine(6.0),
                gamma: None,
                bins: 50,
                windows: vec![1e-3],
            });
        }
    }
    v.push(Case {
        name: "hard-0.5-1".into(),
        sigma: 0.5,
        n: 100,
        length: 100.0,
        boundary: Boundary::Periodic,
        potential: Potential::Cosine(6.0),
        gamma: None,
        bins: 50,
        windows: vec![1e-3],
    });
    v.push(Case {
        name: "sticky".into(),
        sigma: 0.5,
        n: 50,
        length: 100.0,
        boundary: Boundary::Periodic,
        potential: Potential::Cosine(6.0),
        gamma: Some(1.0),
        bins: 50,
        windows: vec![],
    });
    v.push(Case {
        name: "dilute".into(),
        sigma: 0.5,
        n: 100,
        length: 1e4,
        boundary: Boundary::Periodic,
        potential: Potential::Cosine(6.0),
        gamma: None,
        bins: 50,
        windows: vec![],
    });
    v.push(Case {
        name: "tonks".into(),
        sigma: 0.5,
        n: 50,
        length: 100.0,
        boundary: Boundary::Periodic,
        potential: Potential::None,
        gamma: None,
        bins: 1,
        windows: vec![1e-3, 1e-2, 1e-1],
    });
    v.push(Case {
        name: "gravity".into(),
        sigma: 0.5,
        n: 20,
        length: 20.0,
        boundary: Boundary::Walls,
        potential: Potential::Gravity(0.5),
        gamma: None,
        bins: 200,
        windows: vec![],
    });
    v
}

/// Sampled profiles of one seed: density, then one contact density per window.
type Profiles = (Vec<f64>, Vec<Vec<f64>>);

fn pair_of(case: &Case) -> Option<Sticky> {
    case.gamma
        .map(|g| Sticky::new(g, 0.05, 3.0, case.sigma, 1.0).expect("sticky"))
}

/// Relax one seed from a field-free equilibrium configuration (40 time units, 400 for the
/// sediment; dt = 1e-4, LM).
fn prepare(case: &Case, seed: u32) -> BcdState {
    let cfg = case.config(1e-4, seed);
    let x0 = init::random(&cfg, case.n, seed).expect("initial configuration");
    let field = Field::new(&case.field());
    let time = match case.potential {
        Potential::Gravity(_) => 400.0,
        _ => 40.0,
    };
    let steps = (time / cfg.dt) as u64;
    match pair_of(case) {
        Some(st) => relax(cfg, x0, field, st, steps),
        None => relax(cfg, x0, field, NoPair, steps),
    }
}

fn relax<P: PairForce>(cfg: BcdConfig, x0: Vec<f64>, f: Field, p: P, steps: u64) -> BcdState {
    let mut b = Bcd::new(cfg, x0, f, p)
        .expect("engine")
        .with_integrator(Integrator::Lm);
    b.run(steps).expect("relaxation");
    b.state().clone()
}

/// Continue `state` with `scheme` at `dt`: `relax` time units of relaxation, then `steps`
/// sampled.
fn sample(
    case: &Case,
    state: &BcdState,
    (scheme, dt): (Integrator, f64),
    seed: u32,
    (relax, steps): (f64, u64),
) -> Profiles {
    let field = Field::new(&case.field());
    match pair_of(case) {
        Some(st) => sample_with(case, state, (scheme, dt), seed, (relax, steps), field, st),
        None => sample_with(
            case,
            state,
            (scheme, dt),
            seed,
            (relax, steps),
            field,
            NoPair,
        ),
    }
}

fn sample_with<P: PairForce>(
    case: &Case,
    state: &BcdState,
    (scheme, dt): (Integrator, f64),
    seed: u32,
    (relax, steps): (f64, u64),
    field: Field,
    pair: P,
) -> Profiles {
    // A fresh noise sequence for every scheme and dt (the seed's relaxation used `seed`).
    let which = match scheme {
        Integrator::Euler => 0,
        Integrator::Lm => 1,
        Integrator::Reflect => 2,
    };
    let key = seed ^ 0x5bd1_e995 ^ (dt.to_bits() as u32) ^ which;
    let mut st = state.clone();
    st.step = 0;
    let mut b = Bcd::from_state(case.config(dt, key), st, field, pair)
        .expect("engine")
        .with_integrator(scheme);
    b.run((relax / dt).round() as u64).expect("relaxation");
    let period = case.period();
    let mut d = DensityProfile::new(case.bins, period, case.length);
    let mut c: Vec<ContactDensity> = case
        .windows
        .iter()
        .map(|&w| ContactDensity::new(case.bins, w, period, case.sigma, case.length, case.boundary))
        .collect();
    let every = ((1e-3 / dt).round() as u64).max(1);
    let mut done = 0;
    while done < steps {
        let k = every.min(steps - done);
        b.run(k).expect("run");
        done += k;
        let x = b.positions();
        d.sample(x);
        for ci in &mut c {
            ci.sample(x);
        }
    }
    (d.profile().1, c.iter().map(|ci| ci.profile().1).collect())
}

/// Relative L1 error of the seeds' mean profile, its jackknife error, the noise floor, and
/// the relative error (with its error) of the bin where the exact profile peaks.
struct Errors {
    l1: f64,
    l1_err: f64,
    floor: f64,
    peak: f64,
    peak_err: f64,
}

fn errors(samples: &[&Vec<f64>], exact: &[f64]) -> Errors {
    let s = samples.len();
    let bins = exact.len();
    let norm: f64 = exact.iter().sum();
    let mean_without = |skip: Option<usize>| -> Vec<f64> {
        let k = (s - usize::from(skip.is_some())) as f64;
        (0..bins)
            .map(|i| {
                samples
                    .iter()
                    .enumerate()
                    .filter(|(j, _)| Some(*j) != skip)
                    .map(|(_, p)| p[i])
                    .sum::<f64>()
                    / k
            })
            .collect()
    };
    let l1_of = |m: &[f64]| m.iter().zip(exact).map(|(a, b)| (a - b).abs()).sum::<f64>() / norm;
    let mean = mean_without(None);
    let l1 = l1_of(&mean);
    let jack: Vec<f64> = (0..s).map(|j| l1_of(&mean_without(Some(j)))).collect();
    let jm = jack.iter().sum::<f64>() / s as f64;
    let l1_err =
        ((s as f64 - 1.0) / s as f64 * jack.iter().map(|v| (v - jm).powi(2)).sum::<f64>()).sqrt();
    let se: Vec<f64> = (0..bins)
        .map(|i| {
            let var = samples
                .iter()
                .map(|p| (p[i] - mean[i]).powi(2))
                .sum::<f64>()
                / (s as f64 - 1.0);
            (var / s as f64).sqrt()
        })
        .collect();
    let floor = (2.0 / std::f64::consts::PI).sqrt() * se.iter().sum::<f64>() / norm;
    let top = (0..bins)
        .max_by(|&a, &b| exact[a].total_cmp(&exact[b]))
        .expect("bins");
    Errors {
        l1,
        l1_err,
        floor,
        peak: mean[top] / exact[top] - 1.0,
        peak_err: se[top] / exact[top],
    }
}

struct Args {
    cases: Option<Vec<String>>,
    dts: Vec<f64>,
    seeds: u32,
    time: f64,
    steps: u64,
    relax: f64,
    /// Integrators to measure (`--schemes`).
    schemes: Vec<Integrator>,
    csv: Option<String>,
}

fn args() -> Args {
    let mut a = Args {
        cases: None,
        dts: vec![1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5],
        seeds: 8,
        time: 200.0,
        steps: 2_000_000,
        relax: 2.0,
        schemes: vec![Integrator::Euler, Integrator::Lm, Integrator::Reflect],
        csv: None,
    };
    let v: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i < v.len() {
        let val = v.get(i + 1).cloned().unwrap_or_default();
        match v[i].as_str() {
            "--cases" => a.cases = Some(val.split(',').map(str::to_string).collect()),
            "--dt" => a.dts = val.split(',').map(|s| s.parse().expect("--dt")).collect(),
            "--seeds" => a.seeds = val.parse().expect("--seeds"),
            "--time" => a.time = val.parse().expect("--time"),
            "--steps" => a.steps = val.parse::<f64>().expect("--steps") as u64,
            "--relax" => a.relax = val.parse().expect("--relax"),
            "--csv" => a.csv = Some(val),
            "--schemes" => {
                a.schemes = val
                    .split(',')
                    .map(|s| match s {
                        "euler" => Integrator::Euler,
                        "lm" => Integrator::Lm,
                        "reflect" => Integrator::Reflect,
                        _ => panic!("--schemes: euler, lm or reflect, got {s}"),
                    })
                    .collect()
            }
            other => panic!("unknown option {other} (see the example's doc comment)"),
        }
        i += 2;
    }
    assert!(a.seeds >= 2, "--seeds: at least 2 for error bars");
    a
}

fn main() {
    let a = args();
    let start = Instant::now();
    let mut csv = String::from(
        "case,scheme,dt,steps_per_seed,seeds,observable,l1,l1_err,floor,peak,peak_err\n",
    );
    println!(
        "| case | scheme | dt | steps/seed | observable | L1 error | noise floor | peak error |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for case in cases() {
        if a.cases.as_ref().is_some_and(|c| !c.contains(&case.name)) {
            continue;
        }
        let (rho_exact, contact_exact) = case.theory();
        let seeds: Vec<u32> = (1..=a.seeds).collect();
        let states: Vec<BcdState> = seeds.par_iter().map(|&s| prepare(&case, s)).collect();
        for &scheme in &a.schemes {
            // The reflecting integrator refuses sticky rods.
            if scheme == Integrator::Reflect && pair_of(&case).is_some() {
                continue;
            }
            for &dt in &a.dts {
                if let Some(st) = pair_of(&case) {
                    // Hard-rods paper Eq. 34, mu max|f| dt << eps: the scenario refuses steps
                    // that move a rod by more than eps.
                    if st.max_force() * dt > st.eps {
                        continue;
                    }
                }
                let steps = ((a.time / dt).round() as u64).min(a.steps);
                let runs: Vec<Profiles> = seeds
                    .par_iter()
                    .zip(&states)
                    .map(|(&s, st)| sample(&case, st, (scheme, dt), s, (a.relax, steps)))
                    .collect();
                let name = match scheme {
                    Integrator::Euler => "euler",
                    Integrator::Lm => "lm",
                    Integrator::Reflect => "reflect",
                };
                let mut report = |obs: &str, samples: Vec<&Vec<f64>>, exact: &[f64]| {
                    let e = errors(&samples, exact);
                    println!(
                        "| {} | {name} | {dt:e} | {steps} | {obs} | {:.2e} ± {:.1e} | {:.1e} | {:+.2e} ± {:.1e} |",
                        case.name, e.l1, e.l1_err, e.floor, e.peak, e.peak_err
                    );
                    writeln!(
                        csv,
                        "{},{name},{dt:e},{steps},{},{obs},{:e},{:e},{:e},{:e},{:e}",
                        case.name, a.seeds, e.l1, e.l1_err, e.floor, e.peak, e.peak_err
                    )
                    .expect("string");
                };
                if !matches!(case.potential, Potential::None) {
                    report("density", runs.iter().map(|r| &r.0).collect(), &rho_exact);
                }
                for (k, &w) in case.windows.iter().enumerate() {
                    let obs = format!("contact w={w:e}");
                    report(
                        &obs,
                        runs.iter().map(|r| &r.1[k]).collect(),
                        &contact_exact[k],
                    );
                }
            }
        }
        eprintln!(
            "{} done after {:.0} s",
            case.name,
            start.elapsed().as_secs_f64()
        );
        // Rewritten after every case, so that an interrupted sweep keeps what it measured.
        if let Some(path) = &a.csv {
            std::fs::write(path, &csv).expect("write --csv");
        }
    }
    eprintln!("total {:.0} s", start.elapsed().as_secs_f64());
}
