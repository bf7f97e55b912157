//! The start of a DPD run: the colloid radii drawn from their distribution, the colloids placed
//! by random insertion, the solvent on a jittered lattice between them, and the engine built on
//! them ([`DpdSetup`], whose values the run layer reads from a scenario).

use super::{Dpd, DpdError, DpdParams, NeighborMode, colloid_solvent_cutoff};
use crate::state::{Particles, SimBox};
use crate::tune::{Candidate, SkinTuning, TunePlan, lists, tune_skin};
use colloidsim_core::exchange::Exchange;
use colloidsim_core::rng::{Purpose, stream};
use rand::RngExt;
use rand_distr::StandardNormal;
use std::f64::consts::PI;

/// Radii of the colloids.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RadiusDistribution {
    /// All equal.
    Monodisperse,
    /// Normal with relative standard deviation `spread` (truncated at +-3 sd).
    Gaussian(f64),
    /// Log-normal with relative standard deviation `spread` of the radius.
    LogNormal(f64),
    /// Uniform on `mean (1 +- spread)`.
    Uniform(f64),
}

/// Verlet-list skins of [`DpdSetup::measure_neighbors`], in units of rc.
pub const DPD_SKIN_FACTORS: [f64; 6] = [0.1, 0.2, 0.3, 0.45, 0.6, 0.8];

/// How [`DpdSetup::measure_neighbors`] times each candidate: 20 steps to settle, then whole list
/// cycles of at least 100 steps ([`TunePlan`]), three interleaved rounds (a DPD step of 81,000
/// beads takes ~40 ms on one core).
pub const DPD_TUNE_PLAN: TunePlan = TunePlan {
    warmup: 20,
    steps: 100,
    rounds: 3,
};

/// The candidates of [`DpdSetup::measure_neighbors`]: cells every step (at `params.skin`, which
/// the colloid list keeps), then Verlet lists at [`DPD_SKIN_FACTORS`] `x rc`.
pub fn neighbour_candidates(params: &DpdParams) -> Vec<Candidate> {
    let mut c = vec![Candidate {
        skin: params.skin,
        cells: true,
    }];
    c.extend(lists(&DPD_SKIN_FACTORS.map(|f| f * params.rc)));
    c
}

/// `params` with the neighbour search of candidate `c` (a tuning's choice included).
pub fn with_candidate(mut params: DpdParams, c: Candidate) -> DpdParams {
    params.skin = c.skin;
    params.neighbors = if c.cells {
        NeighborMode::Cells
    } else {
        NeighborMode::Verlet
    };
    params
}

/// A DPD system before its start is drawn: the engine's parameters, the box, the particle
/// numbers and sizes.
#[derive(Debug, Clone, PartialEq)]
pub struct DpdSetup {
    /// Engine parameters.
    pub params: DpdParams,
    /// Box.
    pub sbox: SimBox,
    /// Number of colloids.
    pub colloids: usize,
    /// Number of solvent beads.
    pub solvent: usize,
    /// Mean colloid radius.
    pub radius: f64,
    /// Radius distribution.
    pub distribution: RadiusDistribution,
    /// Solvent density.
    pub density: f64,
    /// Solvent bead mass.
    pub solvent_mass: f64,
    /// Stokes–Einstein diffusion coefficient `D0 = kT / (6 pi eta0 R_c)` of a bare colloid.
    pub d0: f64,
    /// Colloid diffusion time `tau_D = R_c^2 / D0`: the unit of the reported times.
    pub tau: f64,
}

/// The colloids overlap more deeply than the contact range allows.
pub fn check_overlaps(
    p: &Particles,
    sbox: &SimBox,
    is_colloid_type: &[bool],
    contact_range: f64,
) -> Result<(), DpdError> {
    let idx: Vec<usize> = (0..p.len())
        .filter(|&i| is_colloid_type[p.typeid[i] as usize])
        .collect();
    for (a, &i) in idx.iter().enumerate() {
        for &j in &idx[..a] {
            let (x, y) = (p.pos[i], p.pos[j]);
            let d = sbox.min_image([x[0] - y[0], x[1] - y[1], x[2] - y[2]]);
            let h = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
                - 0.5 * (p.diameter[i] + p.diameter[j]);
            if h < -contact_range {
                return Err(DpdError::Invalid(format!(
                    "colloids {j} and {i} overlap by {:.4} at the start, more than the contact range {contact_range}",
                    -h
                )));
            }
        }
    }
    Ok(())
}

impl DpdSetup {
    /// Colloid type index (solvent is type 0 `"S"`, colloids type 1 `"C"`).
    pub const COLLOID_TYPE: u32 = 1;

    /// Radii drawn from the distribution (largest first), deterministic in the seed.
    pub fn radii(&self) -> Vec<f64> {
        let mut rng = stream(self.params.seed, 0, Purpose::Initial, 1);
        let r = self.radius;
        let mut out: Vec<f64> = (0..self.colloids)
            .map(|_| match self.distribution {
                RadiusDistribution::Monodisperse => r,
                RadiusDistribution::Gaussian(s) => loop {
                    let z: f64 = rng.sample(StandardNormal);
                    if z.abs() <= 3.0 && 1.0 + s * z > 0.05 {
                        break r * (1.0 + s * z);
                    }
                },
                RadiusDistribution::LogNormal(s) => {
                    let sig2 = (1.0 + s * s).ln();
                    let z: f64 = rng.sample(StandardNormal);
                    r * (z * sig2.sqrt() - 0.5 * sig2).exp()
                }
                RadiusDistribution::Uniform(s) => r * (1.0 + s * (2.0 * rng.random::<f64>() - 1.0)),
            })
            .collect();
        out.sort_by(|a, b| b.total_cmp(a));
        out
    }

    /// Place the colloids by random sequential insertion (no overlaps), the solvent uniformly in
    /// the space they leave, Maxwell–Boltzmann velocities at kT with zero total momentum.
    pub fn initial_particles(&self) -> Result<Particles, DpdError> {
        let sbox = self.sbox;
        let l = sbox.l;
        let radii = self.radii();
        let amax = radii.first().copied().unwrap_or(0.0);
        let mut rng = stream(self.params.seed, 0, Purpose::Initial, 2);
        // Cell grid for overlap checks, cells >= 2 amax.
        let cell = (2.0 * amax).max(1e-9);
        let nc = l.map(|x| ((x / cell).floor() as usize).clamp(1, 256));
        let cell_of = |x: [f64; 3]| -> [usize; 3] {
            let mut c = [0; 3];
            for k in 0..3 {
                c[k] = ((((x[k] / l[k]) + 0.5) * nc[k] as f64) as usize).min(nc[k] - 1);
            }
            c
        };
        let mut grid: Vec<Vec<u32>> = vec![Vec::new(); nc[0] * nc[1] * nc[2]];
        let index = |c: [usize; 3]| (c[2] * nc[1] + c[1]) * nc[0] + c[0];
        let mut cpos: Vec<[f64; 3]> = Vec::with_capacity(radii.len());
        let near = |grid: &Vec<Vec<u32>>, x: [f64; 3], mut f: Box<dyn FnMut(u32) -> bool + '_>| {
            let c = cell_of(x);
            let span = |n: usize| {
                if n >= 3 {
                    [n - 1, 0, 1].to_vec()
                } else {
                    (0..n).collect()
                }
            };
            for dz in span(nc[2]) {
                for dy in span(nc[1]) {
                    for dx in span(nc[0]) {
                        let cc = [
                            if nc[0] >= 3 { (c[0] + dx) % nc[0] } else { dx },
                            if nc[1] >= 3 { (c[1] + dy) % nc[1] } else { dy },
                            if nc[2] >= 3 { (c[2] + dz) % nc[2] } else { dz },
                        ];
                        for &j in &grid[index(cc)] {
                            if !f(j) {
                                return false;
                            }
                        }
                    }
                }
            }
            true
        };
        for (k, &a) in radii.iter().enumerate() {
            let mut placed = false;
            for _ in 0..200_000 {
                let x = [
                    (rng.random::<f64>() - 0.5) * l[0],
                    (rng.random::<f64>() - 0.5) * l[1],
                    (rng.random::<f64>() - 0.5) * l[2],
                ];
                let ok = near(
                    &grid,
                    x,
                    Box::new(|j| {
                        let y = cpos[j as usize];
                        let d = sbox.min_image([x[0] - y[0], x[1] - y[1], x[2] - y[2]]);
                        let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                        r2 >= (a + radii[j as usize]).powi(2)
                    }),
                );
                if ok {
                    grid[index(cell_of(x))].push(k as u32);
                    cpos.push(x);
                    placed = true;
                    break;
                }
            }
            if !placed {
                return Err(DpdError::Invalid(format!(
                    "random insertion placed only {k} of {} colloids; lower the volume fraction phi",
                    radii.len()
                )));
            }
        }
        let mut pos = Vec::with_capacity(self.solvent + radii.len());
        let mut typeid = Vec::with_capacity(pos.capacity());
        let mut diameter = Vec::with_capacity(pos.capacity());
        let mut mass = Vec::with_capacity(pos.capacity());
        for (x, &a) in cpos.iter().zip(&radii) {
            pos.push(*x);
            typeid.push(Self::COLLOID_TYPE);
            diameter.push(2.0 * a);
            mass.push(4.0 / 3.0 * PI * a.powi(3) * self.density * self.solvent_mass);
        }
        // Solvent on a jittered simple-cubic lattice over the free volume (a random start
        // overlaps beads strongly, and the energy it releases heats the system for several
        // DPD times): sites inside a colloid or within half its colloid-solvent cut-off of the
        // surface are left empty, the lattice is refined until enough sites remain, and a
        // random subset of them is used.
        let free_vol = (sbox.volume()
            - radii
                .iter()
                .map(|a| {
                    4.0 / 3.0 * PI * (a + 0.5 * colloid_solvent_cutoff(self.params.rc, *a)).powi(3)
                })
                .sum::<f64>())
        .max(0.05 * sbox.volume());
        let mut spacing = (free_vol / self.solvent.max(1) as f64).cbrt();
        let mut sites: Vec<[f64; 3]> = Vec::new();
        for _ in 0..200 {
            sites.clear();
            let n = l.map(|x| ((x / spacing).ceil() as usize).max(1));
            let h = [l[0] / n[0] as f64, l[1] / n[1] as f64, l[2] / n[2] as f64];
            for iz in 0..n[2] {
                for iy in 0..n[1] {
                    for ix in 0..n[0] {
                        let mut x = [
                            (ix as f64 + 0.5) * h[0] - 0.5 * l[0],
                            (iy as f64 + 0.5) * h[1] - 0.5 * l[1],
                            (iz as f64 + 0.5) * h[2] - 0.5 * l[2],
                        ];
                        for k in 0..3 {
                            x[k] += 0.2 * h[k] * (rng.random::<f64>() - 0.5);
                        }
                        let free = radii.is_empty()
                            || near(
                                &grid,
                                x,
                                Box::new(|j| {
                                    let a = radii[j as usize];
                                    let y = cpos[j as usize];
                                    let d = sbox.min_image([x[0] - y[0], x[1] - y[1], x[2] - y[2]]);
                                    let excl = a + 0.5 * colloid_solvent_cutoff(self.params.rc, a);
                                    d[0] * d[0] + d[1] * d[1] + d[2] * d[2] >= excl * excl
                                }),
                            );
                        if free {
                            sites.push(x);
                        }
                    }
                }
            }
            if sites.len() >= self.solvent {
                break;
            }
            spacing *= 0.98;
        }
        if sites.len() < self.solvent {
            return Err(DpdError::Invalid(format!(
                "could not fit {} solvent beads between the colloids",
                self.solvent
            )));
        }
        // Keep a random subset of `solvent` sites (partial Fisher-Yates), in lattice order.
        let mut keep: Vec<u32> = (0..sites.len() as u32).collect();
        for k in 0..self.solvent {
            let r = k + (rng.random::<f64>() * (sites.len() - k) as f64) as usize;
            keep.swap(k, r.min(sites.len() - 1));
        }
        keep.truncate(self.solvent);
        keep.sort_unstable();
        for &k in &keep {
            pos.push(sites[k as usize]);
            typeid.push(0);
            diameter.push(1.0);
            mass.push(self.solvent_mass);
        }
        let n = pos.len();
        let kt = self.params.kt;
        let mut vrng = stream(self.params.seed, 0, Purpose::Initial, 3);
        let mut vel: Vec<[f64; 3]> = mass
            .iter()
            .map(|m| {
                let sd = (kt / m).sqrt();
                [
                    sd * vrng.sample::<f64, _>(StandardNormal),
                    sd * vrng.sample::<f64, _>(StandardNormal),
                    sd * vrng.sample::<f64, _>(StandardNormal),
                ]
            })
            .collect();
        let mtot: f64 = mass.iter().sum();
        let mut p = [0.0; 3];
        for (v, m) in vel.iter().zip(&mass) {
            for k in 0..3 {
                p[k] += m * v[k];
            }
        }
        for v in vel.iter_mut() {
            for k in 0..3 {
                v[k] -= p[k] / mtot;
            }
        }
        // Under shear the start has the streaming profile u_x = gamma_dot y (y wrapped).
        let shear = self.params.shear_rate;
        if shear != 0.0 {
            let ly = self.sbox.l[1];
            for (v, x) in vel.iter_mut().zip(&pos) {
                let y = x[1] - ly * (x[1] / ly + 0.5).floor();
                v[0] += shear * y;
            }
        }
        Ok(Particles {
            pos,
            image: vec![[0; 3]; n],
            typeid,
            diameter,
            vel,
            mass,
            type_names: vec!["S".into(), "C".into()],
        })
    }

    /// Which types are colloids: `[false, true]` (solvent `"S"`, colloid `"C"`).
    pub fn colloid_types() -> Vec<bool> {
        vec![false, true]
    }

    /// The engine on a fresh configuration.
    pub fn build(&self) -> Result<Dpd, DpdError> {
        let p = self.initial_particles()?;
        self.build_from(p, 0)
    }

    /// The engine on given particles (types `"S"`, `"C"`) at `step`, after checking colloid
    /// overlaps.
    pub fn build_from(&self, p: Particles, step: u64) -> Result<Dpd, DpdError> {
        self.build_on(p, step, None)
    }

    /// [`Self::build`] decomposed over the ranks of `comm` ([`Dpd::decomposed`]): every rank
    /// generates the same start and keeps its layers.
    pub fn build_decomposed(&self, comm: Box<dyn Exchange>) -> Result<Dpd, DpdError> {
        let p = self.initial_particles()?;
        self.build_on(p, 0, Some(comm))
    }

    /// Time the neighbour search of this system ([`crate::tune`], [`DPD_TUNE_PLAN`], each
    /// candidate on its own copy from step 0, lists rebuilt at least every `sync_every` steps
    /// as in the run): cells every step, and Verlet lists with the skins [`DPD_SKIN_FACTORS`]
    /// `x rc` that fit the box; the caller sets `skin` and `neighbors` from the result.
    pub fn measure_neighbors(&self, sync_every: u64) -> Result<SkinTuning, DpdError> {
        tune_skin(
            &neighbour_candidates(&self.params),
            DPD_TUNE_PLAN,
            |c| {
                let mut s = self.clone();
                s.params = with_candidate(s.params, c);
                let mut sim = s.build()?;
                sim.set_sync_every(sync_every);
                Ok(sim)
            },
            |sim, n| sim.run(n),
            |sim| sim.neighbor_builds(),
        )
    }

    fn build_on(
        &self,
        p: Particles,
        step: u64,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<Dpd, DpdError> {
        check_overlaps(
            &p,
            &self.sbox,
            &Self::colloid_types(),
            self.params.colloid.contact_range,
        )?;
        let (sbox, params, types) = (self.sbox, self.params, Self::colloid_types());
        match comm {
            None => Dpd::new(p, sbox, params, types, step),
            Some(c) => Dpd::decomposed(p, sbox, params, types, step, c),
        }
    }
}
