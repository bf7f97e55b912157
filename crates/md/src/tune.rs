//! A Verlet skin (and, for DPD, lists or cells) chosen from measured step times.
//!
//! A larger skin makes the neighbour list longer (pair work `~ (r_cut + skin)^3`) and its
//! builds rarer (a build is due when a particle has moved half the skin: for diffusion after
//! `~ skin^2 / (8 D dt ln N)` steps); which one wins depends on the density, the time step, the
//! interaction and the machine. [`tune_skin`] times each candidate skin on its own copy of the
//! system, from the same start, over the same steps, in interleaved rounds (so that other load on
//! the machine hits every candidate alike), and picks the skin with the least median time per
//! step. The copies are then dropped: a run continued with the chosen skin is bitwise the run
//! whose scenario names that skin.

use serde::{Deserialize, Serialize};
use std::time::Instant;

/// How long each candidate is timed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TunePlan {
    /// Untimed steps before the timed ones (buffers and lists reach their size; the start's
    /// relaxation).
    pub warmup: u64,
    /// Timed steps per candidate and round, at least: the timed stretch starts right after a
    /// list build and ends with one (whole build cycles, so that every candidate pays its
    /// builds in proportion; at most four times this many steps). A candidate without a
    /// build within this many steps after the warm-up (cells, or a list that outlasts it) is
    /// timed over this many steps.
    pub steps: u64,
    /// Interleaved rounds over the candidates; the median time of each is compared.
    pub rounds: usize,
}

/// One candidate's measurement.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SkinTrial {
    /// The skin.
    pub skin: f64,
    /// No lists: cells every step (DPD's `NeighborMode::Cells`; false: Verlet lists).
    pub cells: bool,
    /// Median wall time per step over the rounds (s).
    pub seconds_per_step: f64,
    /// Neighbour-list builds in the timed steps (of the last round).
    pub builds: u64,
    /// Timed steps (of the last round).
    pub steps: u64,
}

/// The skin chosen and what it was chosen from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SkinTuning {
    /// The chosen skin: the least median time per step.
    pub skin: f64,
    /// The chosen candidate is cells every step ([`SkinTrial::cells`]).
    pub cells: bool,
    /// Every candidate, in increasing skin.
    pub trials: Vec<SkinTrial>,
    /// How they were timed.
    pub plan: TunePlan,
    /// Wall time the tuning took (s).
    pub seconds: f64,
}

impl SkinTuning {
    /// The chosen candidate.
    pub fn choice(&self) -> Candidate {
        Candidate {
            skin: self.skin,
            cells: self.cells,
        }
    }
}

/// Candidate skins `factors x unit` that leave a neighbour range `r_cut + skin` of at most
/// `max_range` (the box's limit), in increasing order; at least the smallest factor.
pub fn candidate_skins(unit: f64, factors: &[f64], r_cut: f64, max_range: f64) -> Vec<f64> {
    let mut out: Vec<f64> = factors
        .iter()
        .map(|f| f * unit)
        .filter(|&s| r_cut + s <= max_range)
        .collect();
    if out.is_empty() {
        out.extend(factors.iter().map(|f| f * unit).reduce(f64::min));
    }
    out
}

/// A candidate: a skin, with Verlet lists or (`cells`) cells every step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// The skin.
    pub skin: f64,
    /// Cells every step instead of lists.
    pub cells: bool,
}

/// Verlet-list candidates of `skins`.
pub fn lists(skins: &[f64]) -> Vec<Candidate> {
    skins
        .iter()
        .map(|&skin| Candidate { skin, cells: false })
        .collect()
}

/// Time each of `candidates` (by `build` from the same start, `run` for a number of steps)
/// under `plan` and choose the fastest; `builds` counts a system's neighbour-list builds so
/// far.
pub fn tune_skin<T, E>(
    candidates: &[Candidate],
    plan: TunePlan,
    build: impl FnMut(Candidate) -> Result<T, E>,
    run: impl FnMut(&mut T, u64) -> Result<(), E>,
    builds: impl Fn(&T) -> u64,
) -> Result<SkinTuning, E> {
    let origin = Instant::now();
    let clock = || origin.elapsed().as_secs_f64();
    tune_with_clock(candidates, plan, build, run, builds, clock)
}

/// [`tune_skin`] with the time read from `clock` (s).
fn tune_with_clock<T, E>(
    skins: &[Candidate],
    plan: TunePlan,
    mut build: impl FnMut(Candidate) -> Result<T, E>,
    mut run: impl FnMut(&mut T, u64) -> Result<(), E>,
    builds: impl Fn(&T) -> u64,
    clock: impl Fn() -> f64,
) -> Result<SkinTuning, E> {
    let start = clock();
    let mut times = vec![Vec::with_capacity(plan.rounds); skins.len()];
    let mut counts = vec![(0, 0); skins.len()];
    // Candidates the system cannot be built with (a box too small for their range) are left
    // out; the error is returned only when none can be built.
    let mut usable = vec![true; skins.len()];
    let mut first_error = None;
    for round in 0..plan.rounds.max(1) {
        for (k, &c) in skins.iter().enumerate() {
            if !usable[k] {
                continue;
            }
            let mut sim = match build(c) {
                Ok(sim) => sim,
                Err(e) if round == 0 => {
                    usable[k] = false;
                    first_error.get_or_insert(e);
                    continue;
                }
                Err(e) => return Err(e),
            };
            run(&mut sim, plan.warmup)?;
            // Up to the next build (untimed), then whole build cycles (timed).
            let before = builds(&sim);
            let mut synced = false;
            for _ in 0..plan.steps {
                run(&mut sim, 1)?;
                if builds(&sim) > before {
                    synced = true;
                    break;
                }
            }
            let b0 = builds(&sim);
            let t0 = clock();
            let mut steps = 0;
            if synced {
                while steps < 4 * plan.steps {
                    let b = builds(&sim);
                    run(&mut sim, 1)?;
                    steps += 1;
                    if steps >= plan.steps && builds(&sim) > b {
                        break;
                    }
                }
            } else {
                run(&mut sim, plan.steps)?;
                steps = plan.steps;
            }
            times[k].push((clock() - t0) / steps.max(1) as f64);
            counts[k] = (builds(&sim) - b0, steps);
        }
    }
    if !usable.contains(&true)
        && let Some(e) = first_error
    {
        return Err(e);
    }
    let trials: Vec<SkinTrial> = skins
        .iter()
        .zip(times.iter_mut())
        .zip(counts)
        .zip(&usable)
        .filter(|(_, ok)| **ok)
        .map(|(((c, t), (builds, steps)), _)| SkinTrial {
            skin: c.skin,
            cells: c.cells,
            seconds_per_step: median(t),
            builds,
            steps,
        })
        .collect();
    let best = trials
        .iter()
        .min_by(|a, b| a.seconds_per_step.total_cmp(&b.seconds_per_step));
    Ok(SkinTuning {
        skin: best.map_or(f64::NAN, |t| t.skin),
        cells: best.is_some_and(|t| t.cells),
        trials,
        plan,
        seconds: clock() - start,
    })
}

/// The median of `x` (sorted in place; NaN when empty).
fn median(x: &mut [f64]) -> f64 {
    x.sort_by(f64::total_cmp);
    match x.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => x[n / 2],
        n => 0.5 * (x[n / 2 - 1] + x[n / 2]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    /// A fake system on a fake clock: a step costs `cost(skin)` seconds, and the lists are
    /// rebuilt every fifth step.
    struct Fake {
        skin: f64,
        builds: u64,
        steps: u64,
    }

    #[test]
    fn the_cheapest_candidate_is_chosen_and_every_one_is_reported() {
        // List work grows with the skin, builds shrink with it: least at 0.6; one round of
        // 0.4 is slowed down by other load, which the median of three rounds leaves out.
        let now = Cell::new(0.0);
        let trial = Cell::new(0);
        let cost = |s: f64| (s - 0.6f64).powi(2) + 1.0;
        let plan = TunePlan {
            warmup: 2,
            steps: 20,
            rounds: 3,
        };
        let skins = [0.2, 0.4, 0.6, 0.8, 1.2];
        let t = tune_with_clock(
            &lists(&skins),
            plan,
            |c| {
                trial.set(trial.get() + 1);
                Ok::<_, ()>(Fake {
                    skin: c.skin,
                    builds: 1,
                    steps: 0,
                })
            },
            |f, n| {
                let load = if trial.get() == 2 { 10.0 } else { 1.0 };
                for _ in 0..n {
                    now.set(now.get() + load * cost(f.skin));
                    f.steps += 1;
                    if f.steps % 5 == 0 {
                        f.builds += 1;
                    }
                }
                Ok(())
            },
            |f| f.builds,
            || now.get(),
        )
        .unwrap();
        assert_eq!((t.skin, t.cells), (0.6, false), "{t:?}");
        let per_step: Vec<f64> = t.trials.iter().map(|x| x.seconds_per_step).collect();
        let expected: Vec<f64> = skins.iter().map(|&s| cost(s)).collect();
        assert!(
            per_step
                .iter()
                .zip(&expected)
                .all(|(a, b)| (a - b).abs() < 1e-12),
            "{per_step:?} against {expected:?}"
        );
        // Warm-up to step 2, untimed to the build at step 5, then timed from step 6 to the
        // build at step 25: 20 steps, 4 builds.
        assert!(
            t.trials.iter().all(|x| x.builds == 4 && x.steps == 20),
            "{t:?}"
        );
        assert_eq!(t.plan, plan);
        assert!((t.seconds - now.get()).abs() < 1e-9);
    }

    #[test]
    fn a_failing_build_is_returned() {
        let plan = TunePlan {
            warmup: 0,
            steps: 1,
            rounds: 1,
        };
        let r = tune_skin(
            &lists(&[0.3]),
            plan,
            |_| Err::<(), _>("box too small"),
            |_, _| Ok(()),
            |_| 0,
        );
        assert_eq!(r.unwrap_err(), "box too small");
        // One candidate that cannot be built is left out.
        let r = tune_skin(
            &lists(&[0.3, 0.5]),
            plan,
            |c| {
                if c.skin > 0.4 {
                    Err("box too small")
                } else {
                    Ok(())
                }
            },
            |_, _| Ok(()),
            |_| 0,
        )
        .unwrap();
        assert_eq!(r.trials.len(), 1);
        assert_eq!(r.skin, 0.3);
    }

    #[test]
    fn candidates_respect_the_box() {
        let s = candidate_skins(2.0, &[0.1, 0.3, 0.6, 1.0], 2.2, 3.5);
        assert_eq!(s, vec![0.2, 0.6, 1.2]);
        // Nothing fits: the smallest is kept (the engine's own check then speaks).
        assert_eq!(candidate_skins(1.0, &[0.3, 0.1], 5.0, 1.0), vec![0.1]);
    }
}
