//! The drying droplet's RPY DDFT with the pair correlation measured by hard-sphere Monte Carlo at
//! the DDFT's own density (issue #15, item 4; docs/reports/theory-droplet-validation.md, "The
//! Monte Carlo g2 in the flux").
//!
//! ```text
//! cargo run --release -p colloidsim-mc --example ddft_mc_g2 -- OUT [key=value ...]
//! ```
//!
//! Keys (defaults in brackets): `mode` [mc] = mc | eq17 | trokhymchuk | dilute; `r0` [25]
//! (initial radius, d); `phi0` [0.05] or `particles` (N; then `phi0 = N / (8 r0^3)`); `phi_end`
//! [0.5]; `pe` [10]; `dr` [0.02] (DDFT grid, d); `stages` [10]; `warmup` [2000], `sweeps` [4000],
//! `every` [5] (MC sweeps per stage, sweeps between samples); `r_bin` [0.1], `s_bin` [0.1],
//! `s_max` [3] (the g2 table, d); `min_pairs` [50]; `range` [8] (trokhymchuk mode's h range);
//! `seed` [1]; `spacing` [phi] = phi | time (stage boundaries equally spaced in ln(mean phi), so
//! that the dense end, where the density changes fastest, gets as many stages as the start; or
//! equally in time).
//!
//! Modes: `mc` — at the start of each of `stages` stages (see `spacing`), the
//! DDFT's profile `rho(r)` at radius `R_s` is made an equilibrium profile by the potential
//! `beta U = -ln rho - beta mu_ex[rho]` (Rosenfeld FMT; held at its value where the interface
//! potential passes 20 kT, plus the interface potential; a hard wall where that reaches 40 kT);
//! hard-sphere Monte Carlo in that potential (chained from the previous stage's configuration)
//! measures `g2(r1, r2, s)` on the table's bins (`colloidsim_mc::radial_pairs`); bins with fewer
//! than `min_pairs` expected pairs take Eq. 17 (Trokhymchuk's `g` at the mean of the two bins'
//! packing fractions). The RPY kernel of that table (`colloidsim_dft::radial::g2`) drives the
//! DDFT through the stage, read at `r + (R_s - R(t))` and rebuilt every `r_bin / 2` of shrinkage.
//! `eq17` — the same stages, bins and kernel, but the table is Eq. 17 with Trokhymchuk's `g` at the
//! DDFT's bin densities (no Monte Carlo): it separates the effect of the measured `g2` from that
//! of the staging and binning. `trokhymchuk`, `dilute` — the existing kernels (`--pair`).
//!
//! Writes `OUT/fractions.csv` (every 1 % of the drying time: mean phi, largest `n3`, fractions of
//! the particles beyond 0.7 R(t) and 0.85 R(t)), `OUT/profile_<f>.csv` (`r,r_over_R,phi`, 50 bins
//! of `[0, R(t)]`, and `OUT/theory_profile_<f>.csv`, `r,rho` on the DDFT grid, at 25/50/75/100 %), `OUT/stages.csv` (per stage: radius, Monte Carlo time and
//! acceptance, DDFT-vs-MC profile difference), `OUT/g2_stage<k>.csv` (`r,s,h_mc,h_eq17,expected`
//! for pairs in one radial bin) and `OUT/summary.txt`.

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::time::Instant;

use colloidsim_dft::radial::{
    Ddft, DdftOptions, DropletSetup, DryingSchedule, EquilibriumOptions, HarmonicInterface,
    Hydrodynamics, PairCorrelation, PairTable, RadialError, RadialGrid, Rosenfeld, TabulatedPair,
    bin_average, pair::TotalCorrelation, solve_equilibrium,
};
use colloidsim_mc::radial_pairs::RadialPairs;
use colloidsim_mc::{Geometry, HardSphereMc, McParams, RadialPotential, init};

#[derive(Clone, Copy, PartialEq)]
enum Mode {
    Mc,
    Eq17,
    Trokhymchuk,
    Dilute,
}

struct Config {
    mode: Mode,
    r0: f64,
    particles: f64,
    phi_end: f64,
    pe: f64,
    dr: f64,
    stages: usize,
    warmup: u64,
    sweeps: u64,
    every: u64,
    r_bin: f64,
    s_bin: f64,
    s_max: f64,
    min_pairs: f64,
    range: f64,
    seed: u32,
    /// Stage boundaries equally spaced in ln(mean phi) (else in time).
    log_phi: bool,
}

fn fail(msg: String) -> ! {
    eprintln!("ddft_mc_g2: {msg}");
    std::process::exit(2)
}

fn parse(args: &[String]) -> Config {
    let mut c = Config {
        mode: Mode::Mc,
        r0: 25.0,
        particles: 0.0,
        phi_end: 0.5,
        pe: 10.0,
        dr: 0.02,
        stages: 10,
        warmup: 2000,
        sweeps: 4000,
        every: 5,
        r_bin: 0.1,
        s_bin: 0.1,
        s_max: 3.0,
        min_pairs: 50.0,
        range: 8.0,
        seed: 1,
        log_phi: true,
    };
    let mut phi0 = 0.05;
    let mut n = None;
    for a in args {
        let Some((k, v)) = a.split_once('=') else {
            fail(format!("arguments are key=value, got {a:?}"))
        };
        let num = |lo: f64, hi: f64| -> f64 {
            match v.parse::<f64>() {
                Ok(x) if x.is_finite() && x >= lo && x <= hi => x,
                _ => fail(format!("{k} must be a number in [{lo}, {hi}], got {v:?}")),
            }
        };
        match k {
            "mode" => {
                c.mode = match v {
                    "mc" => Mode::Mc,
                    "eq17" => Mode::Eq17,
                    "trokhymchuk" => Mode::Trokhymchuk,
                    "dilute" => Mode::Dilute,
                    _ => fail(format!(
                        "mode must be mc, eq17, trokhymchuk or dilute, got {v:?}"
                    )),
                }
            }
            "r0" => c.r0 = num(2.0, 200.0),
            "phi0" => phi0 = num(1e-4, 0.6),
            "particles" => n = Some(num(1.0, 1e6).round()),
            "phi_end" => c.phi_end = num(1e-4, 0.64),
            "pe" => c.pe = num(1e-3, 1e3),
            "dr" => c.dr = num(1e-3, 0.1),
            "stages" => c.stages = num(1.0, 1000.0) as usize,
            "warmup" => c.warmup = num(0.0, 1e7) as u64,
            "sweeps" => c.sweeps = num(1.0, 1e7) as u64,
            "every" => c.every = num(1.0, 1e6) as u64,
            "r_bin" => c.r_bin = num(0.01, 1.0),
            "s_bin" => c.s_bin = num(0.01, 1.0),
            "s_max" => c.s_max = num(1.0, 10.0),
            "min_pairs" => c.min_pairs = num(0.0, 1e9),
            "range" => c.range = num(2.0, 30.0),
            "seed" => c.seed = num(0.0, u32::MAX as f64) as u32,
            "spacing" => {
                c.log_phi = match v {
                    "phi" => true,
                    "time" => false,
                    _ => fail(format!("spacing must be phi or time, got {v:?}")),
                }
            }
            _ => fail(format!("unknown key {k:?}")),
        }
    }
    c.particles = n.unwrap_or_else(|| (8.0 * phi0 * c.r0.powi(3)).round());
    if c.sweeps < c.every {
        fail(format!(
            "sweeps ({}) must be at least every ({})",
            c.sweeps, c.every
        ));
    }
    if ((1.0 / c.s_bin) - (1.0 / c.s_bin).round()).abs() > 1e-9 {
        fail(format!("s_bin must divide d = 1, got {}", c.s_bin));
    }
    c
}

/// Fraction of the particles with centres beyond `rc` (cells piecewise constant).
fn beyond(grid: &RadialGrid, rho: &[f64], rc: f64, n: f64) -> f64 {
    let f = grid.faces();
    let mut acc = 0.0;
    for i in 0..grid.len() {
        if f[i + 1] <= rc {
            continue;
        }
        let a = f[i].max(rc);
        acc += rho[i] * 4.0 / 3.0 * PI * (f[i + 1].powi(3) - a.powi(3));
    }
    acc / n
}

/// Eq. 17's `h`: Trokhymchuk's at the mean of two packing fractions (clamped to [0, 0.6]).
fn eq17(eta1: f64, eta2: f64, s: f64) -> f64 {
    if s < 1.0 {
        return -1.0;
    }
    let e = (0.5 * (eta1 + eta2)).clamp(0.0, 0.6);
    TotalCorrelation::new(e).expect("eta in range").h(s)
}

struct Stage {
    table: TabulatedPair,
    radius: f64,
    line: String,
}

/// The g2 table of the current DDFT state (mode mc or eq17); writes `g2_stage<k>.csv`.
fn stage_table(
    c: &Config,
    k: usize,
    ddft: &mut Ddft,
    interface: &HarmonicInterface,
    mc_state: &mut Option<Vec<[f64; 3]>>,
    out: &str,
) -> Result<Stage, RadialError> {
    let grid = ddft.grid().clone();
    let radius = ddft.radius()?;
    let rho = ddft.rho().to_vec();
    let mu = ddft.excess_chemical_potential()?;
    let cut = radius + interface.offset + interface.reach(40.0);
    let r_bins = (cut / c.r_bin).ceil() as usize + 2;
    let s_bins = (c.s_max / c.s_bin).round() as usize;
    // The DDFT's packing fraction on the table's radial bins.
    let edges: Vec<f64> = (0..=r_bins).map(|i| i as f64 * c.r_bin).collect();
    let eta_ddft: Vec<f64> = bin_average(&grid, &rho, &edges)
        .iter()
        .map(|r| PI / 6.0 * r)
        .collect();
    let mut h = vec![0.0; r_bins * r_bins * s_bins];
    let mut expected = vec![0.0; r_bins * r_bins * s_bins];
    let mut eta_mc = eta_ddft.clone();
    let mut line = String::new();
    let mut measured = vec![f64::NAN; r_bins * r_bins * s_bins];
    if c.mode == Mode::Mc {
        let start = Instant::now();
        // beta U = -ln rho - beta mu_ex where the interface potential is below 20 kT (held
        // beyond), plus the interface potential.
        let centres = grid.centres();
        let mut dv = vec![0.0; grid.len()];
        let mut last = 0.0;
        for i in 0..grid.len() {
            let vi = interface.potential(centres[i], radius);
            if vi < 20.0 && rho[i] > 1e-250 {
                last = -rho[i].ln() - mu[i] - vi;
            }
            dv[i] = last;
        }
        // Chained configurations may hold centres beyond the new cut: the hard wall goes to the
        // farthest, and the (linear, steep) interface potential pushes them in.
        let far = mc_state
            .as_ref()
            .map(|p| {
                p.iter()
                    .map(|q| (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt())
                    .fold(0.0, f64::max)
            })
            .unwrap_or(0.0);
        let wall = cut.max(far + 1e-9);
        let nodes = (wall / grid.dr()).ceil() as usize + 2;
        let mut values: Vec<f64> = (0..nodes)
            .map(|j| {
                let r = j as f64 * grid.dr();
                // Cell-centre values interpolated to the node.
                let t = (r / grid.dr() - 0.5).max(0.0);
                let i = (t as usize).min(grid.len() - 2);
                let f = (t - i as f64).min(1.0);
                dv[i] + f * (dv[i + 1] - dv[i]) + interface.potential(r, radius)
            })
            .collect();
        let floor = values.iter().cloned().fold(f64::INFINITY, f64::min);
        values.iter_mut().for_each(|v| *v -= floor);
        let potential =
            RadialPotential::new(grid.dr(), values, wall, radius).map_err(RadialError::from)?;
        let n = ddft.initial_particles().round() as usize;
        let positions = match mc_state.take() {
            Some(p) => p,
            None => init::shuffled(
                init::fcc_in_sphere(n, 1.0, radius + interface.offset)
                    .unwrap_or_else(|e| fail(format!("initial lattice: {e}"))),
                c.seed,
            ),
        };
        let params = McParams {
            diameter: 1.0,
            geometry: Geometry::tabulated(potential),
            seed: c.seed.wrapping_add(k as u32),
            delta: 0.2,
            mixture: None,
        };
        let mut mc = HardSphereMc::new(&params, &positions, "stage configuration")
            .unwrap_or_else(|e| fail(format!("stage {k}: {e}")));
        mc.warm_up(c.warmup, 100, 0.3);
        let mut acc =
            RadialPairs::new(c.r_bin, r_bins, c.s_bin, s_bins, 10).map_err(RadialError::from)?;
        let mut stats = colloidsim_mc::SweepStats::default();
        for _ in 0..c.sweeps / c.every {
            let st = mc.run(c.every);
            stats += st;
            acc.sample(&mc);
        }
        let (hm, ex) = acc.total_correlation(c.min_pairs);
        measured = hm;
        expected = ex;
        // The MC's packing fraction on the radial bins (from its thin shells).
        let fine = acc.density();
        for (i, e) in eta_mc.iter_mut().enumerate() {
            *e = PI / 6.0 * fine[i * 10..(i + 1) * 10].iter().sum::<f64>() / 10.0;
        }
        // Profile check: DDFT against MC on bins of 5 r_bin, where the DDFT holds particles.
        let (mut s2, mut m, mut worst) = (0.0, 0usize, 0.0f64);
        for b in 0..r_bins / 5 {
            let vol = |i: usize| {
                4.0 / 3.0 * PI * (((i + 1) as f64 * c.r_bin).powi(3) - (i as f64 * c.r_bin).powi(3))
            };
            let (mut a1, mut a2, mut v) = (0.0, 0.0, 0.0);
            for i in 5 * b..5 * b + 5 {
                a1 += eta_ddft[i] * vol(i);
                a2 += eta_mc[i] * vol(i);
                v += vol(i);
            }
            if a1 / v > 1e-3 {
                let dlt = (a1 - a2) / v;
                s2 += dlt * dlt;
                m += 1;
                worst = worst.max(dlt.abs());
            }
        }
        *mc_state = Some((0..mc.len()).map(|i| mc.position(i)).collect());
        let wall = start.elapsed().as_secs_f64();
        write!(
            line,
            "{:.3},{:.3},{:.4},{:.4},{:.4},{:.4},{}",
            wall,
            stats.acceptance(),
            mc.delta(),
            (s2 / m.max(1) as f64).sqrt(),
            worst,
            measured.iter().filter(|v| v.is_finite()).count() as f64 / measured.len() as f64,
            acc.samples()
        )
        .unwrap();
    }
    let mut csv = String::from("r,s,h_mc,h_eq17,expected\n");
    for i in 0..r_bins {
        for j in 0..r_bins {
            for kk in 0..s_bins {
                let b = (i * r_bins + j) * s_bins + kk;
                let s = (kk as f64 + 0.5) * c.s_bin;
                let e17 = eq17(eta_mc[i], eta_mc[j], s);
                h[b] = if measured[b].is_finite() {
                    measured[b]
                } else {
                    e17
                };
                if i == j {
                    writeln!(
                        csv,
                        "{:.4},{:.4},{},{:.5},{:.2}",
                        (i as f64 + 0.5) * c.r_bin,
                        s,
                        if measured[b].is_finite() {
                            format!("{:.5}", measured[b])
                        } else {
                            String::new()
                        },
                        e17,
                        expected[b]
                    )
                    .unwrap();
                }
            }
        }
    }
    if c.mode == Mode::Mc {
        std::fs::write(format!("{out}/g2_stage{k}.csv"), csv).expect("write g2");
    }
    let table =
        TabulatedPair::new(1.0, c.r_bin, r_bins, c.s_bin, s_bins, h).map_err(RadialError::from)?;
    Ok(Stage {
        table,
        radius,
        line,
    })
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(out) = args.first().cloned() else {
        fail("usage: ddft_mc_g2 OUT [key=value ...]".into())
    };
    let c = parse(&args[1..]);
    std::fs::create_dir_all(&out).expect("output folder");
    let t0 = Instant::now();
    let d0 = 1.0;
    let schedule = DryingSchedule::from_peclet(c.r0, c.pe, d0).expect("schedule");
    let phi0 = c.particles / (8.0 * c.r0.powi(3));
    let r_end = c.r0 * (phi0 / c.phi_end).cbrt();
    let t_end = schedule.time_at_radius(r_end);
    let interface = HarmonicInterface::new(50.0, 0.5, -0.5).expect("interface");
    let setup = DropletSetup {
        particles: c.particles,
        diameter: 1.0,
        d0,
        r0: c.r0,
        alpha: schedule.alpha,
        interface,
        t_end,
        dr: c.dr,
        hydrodynamics: Hydrodynamics::Rpy,
        pair: match c.mode {
            Mode::Trokhymchuk => PairCorrelation::Trokhymchuk,
            _ => PairCorrelation::Dilute,
        },
    };
    setup
        .validate()
        .unwrap_or_else(|e| fail(format!("setup: {e}")));
    let mut opts = DdftOptions::new(d0, 1.0);
    opts.hydrodynamics = Hydrodynamics::Rpy;
    opts.pair = setup.pair;
    opts.pair_table = PairTable {
        range: c.range,
        eta_max: 0.6,
    };
    let grid = setup.grid(opts.potential_cutoff).expect("grid");
    let mut fmt = Rosenfeld::new(&grid, 1.0).expect("fmt");
    let mut v = vec![0.0; grid.len()];
    interface.fill(grid.centres(), c.r0, &mut v);
    let eq = solve_equilibrium(
        &grid,
        &mut fmt,
        &v,
        c.particles,
        None,
        &EquilibriumOptions::default(),
    )
    .expect("initial equilibrium");
    let mut ddft = Ddft::new(grid.clone(), 1.0, interface, schedule, &eq.rho, opts).expect("ddft");
    let staged = matches!(c.mode, Mode::Mc | Mode::Eq17);
    let mut fractions = String::from("fraction,t,R,mean_phi,max_n3,beyond_0.7R,beyond_0.85R\n");
    let mut stages_csv = String::from(
        "stage,fraction,R,mean_phi,mc_wall_s,acceptance,delta,profile_rms,profile_max,measured_bins,samples,kernel_builds\n",
    );
    let mut mc_state = None;
    let mut outcome = String::from("completed");
    let mut kernel_s = 0.0;
    let mut builds = 0usize;
    let mut last_n3 = 0.0;
    let result: Result<(), RadialError> = (|| {
        let mut stage: Option<Stage> = None;
        let mut shift_built = f64::NAN;
        let mut next_stage = 0usize;
        let boundary = |k: usize| {
            if c.log_phi {
                let phi = phi0 * (c.phi_end / phi0).powf(k as f64 / c.stages as f64);
                schedule.time_at_radius(c.r0 * (phi0 / phi).cbrt())
            } else {
                k as f64 / c.stages as f64 * t_end
            }
        };
        for pct in 1..=100 {
            let t_out = pct as f64 / 100.0 * t_end;
            while ddft.time() < t_out * (1.0 - 1e-14) {
                if staged
                    && next_stage < c.stages
                    && ddft.time() >= boundary(next_stage) - 1e-9 * t_end
                {
                    let k = next_stage;
                    let frac = ddft.time() / t_end;
                    let st = stage_table(&c, k, &mut ddft, &interface, &mut mc_state, &out)?;
                    let mean = phi0 * (c.r0 / st.radius).powi(3);
                    writeln!(
                        stages_csv,
                        "{k},{frac:.4},{:.4},{mean:.4},{},{builds}",
                        st.radius,
                        if st.line.is_empty() {
                            ",,,,,,"
                        } else {
                            &st.line
                        }
                    )
                    .unwrap();
                    println!(
                        "stage {k} at {:.1} %: R = {:.3}, mean phi {mean:.4} [{}] ({:.0} s)",
                        100.0 * frac,
                        st.radius,
                        st.line,
                        t0.elapsed().as_secs_f64()
                    );
                    stage = Some(st);
                    shift_built = f64::NAN;
                    next_stage += 1;
                }
                let mut t_next = t_out;
                if staged && next_stage < c.stages {
                    t_next = t_next.min(boundary(next_stage));
                }
                if let Some(s) = &stage {
                    let shift = s.radius - ddft.radius()?;
                    if shift_built.is_nan() || (shift - shift_built).abs() > 0.25 * c.r_bin {
                        let kt = Instant::now();
                        let kern =
                            s.table
                                .kernel_active(ddft.grid(), shift, ddft.active_cells())?;
                        ddft.set_rpy_kernel(kern)?;
                        kernel_s += kt.elapsed().as_secs_f64();
                        builds += 1;
                        shift_built = shift;
                    }
                    // Rebuild once R has shrunk by r_bin / 2 beyond the built shift.
                    let r_target = s.radius - shift_built - 0.5 * c.r_bin;
                    if r_target > 0.0 {
                        t_next = t_next.min(schedule.time_at_radius(r_target));
                    }
                }
                ddft.advance_to(t_next, |_| {})?;
            }
            let r = ddft.radius()?;
            let n3 = ddft.packing_fraction()?;
            last_n3 = n3.iter().cloned().fold(0.0, f64::max);
            let rho = ddft.rho();
            writeln!(
                fractions,
                "{:.2},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5}",
                pct as f64 / 100.0,
                ddft.time(),
                r,
                phi0 * (c.r0 / r).powi(3),
                last_n3,
                beyond(&grid, rho, 0.7 * r, c.particles),
                beyond(&grid, rho, 0.85 * r, c.particles)
            )
            .unwrap();
            if pct % 25 == 0 {
                let edges: Vec<f64> = (0..=50).map(|i| i as f64 * r / 50.0).collect();
                let phi = bin_average(&grid, rho, &edges);
                let mut csv = String::from("r,r_over_R,phi\n");
                for (i, p) in phi.iter().enumerate() {
                    let rm = 0.5 * (edges[i] + edges[i + 1]);
                    writeln!(csv, "{rm:.5},{:.5},{:.6}", rm / r, PI / 6.0 * p).unwrap();
                }
                std::fs::write(format!("{out}/profile_{:.2}.csv", pct as f64 / 100.0), csv)
                    .expect("write profile");
                let mut fine = String::from("r,rho\n");
                for (x, v) in grid.centres().iter().zip(rho) {
                    writeln!(fine, "{x:.5},{v:.6e}").unwrap();
                }
                std::fs::write(
                    format!("{out}/theory_profile_{:.2}.csv", pct as f64 / 100.0),
                    fine,
                )
                .expect("write profile");
            }
        }
        Ok(())
    })();
    if let Err(e) = result {
        let frac = ddft.time() / t_end;
        let r = ddft.radius().unwrap_or(f64::NAN);
        outcome = match e {
            RadialError::Unphysical { message, .. } => format!(
                "ejected at {:.1} % of the drying time (mean phi {:.4}, max n3 {:.3} at the last 1 % snapshot): {message}",
                100.0 * frac,
                phi0 * (c.r0 / r).powi(3),
                last_n3
            ),
            other => format!("failed at {:.1} %: {other}", 100.0 * frac),
        };
    }
    let wall = t0.elapsed().as_secs_f64();
    std::fs::write(format!("{out}/fractions.csv"), &fractions).expect("write");
    std::fs::write(format!("{out}/stages.csv"), &stages_csv).expect("write");
    let summary = format!(
        "mode {}; N = {}, R0 = {}, phi {:.4} -> {}, Pe = {}, dr = {}, stages {}, MC {}+{} sweeps every {}, bins r {} s {} to {}, min_pairs {}\noutcome: {outcome}\nmax n3 at the last snapshot: {last_n3:.3}\nwall {wall:.1} s (kernel builds {builds}: {kernel_s:.1} s)\n",
        match c.mode {
            Mode::Mc => "mc",
            Mode::Eq17 => "eq17",
            Mode::Trokhymchuk => "trokhymchuk",
            Mode::Dilute => "dilute",
        },
        c.particles,
        c.r0,
        phi0,
        c.phi_end,
        c.pe,
        c.dr,
        c.stages,
        c.warmup,
        c.sweeps,
        c.every,
        c.r_bin,
        c.s_bin,
        c.s_max,
        c.min_pairs
    );
    print!("{summary}");
    std::fs::write(format!("{out}/summary.txt"), summary).expect("write");
}
