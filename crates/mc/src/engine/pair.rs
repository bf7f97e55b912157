//! Pair interactions in place of the hard cores: the spheres sample `exp(-U / kT)` with `U` the
//! sum over pairs of the [`Interaction`] the Brownian-dynamics engines integrate (the same
//! `[pair]` of a scenario, docs/species.md), so a Monte Carlo run and a BD run of one scenario
//! sample one distribution.
//!
//! A local move of sphere `p` from `x` to `x'` is accepted with the Metropolis probability
//! `min(1, exp(-beta [U(x') - U(x)] - beta [V(x') - V(x)]))`, `U` summed over the spheres of
//! the 27 cells around `p`'s cell and `V` the container's energy (Metropolis et al., J. Chem.
//! Phys. 21, 1087 (1953); Frenkel & Smit, Understanding Molecular Simulation, Alg. 1). The
//! cells are at least the interaction's range `r_c` wide, so every sphere within `r_c` of
//! `x` or `x'` (both in `p`'s cell) lies in those cells, and the layers updated at once are a
//! cell apart: the checkerboard's detailed balance holds as for hard spheres
//! ([`crate::engine`]). An infinite or undefined energy difference is a rejection.
//!
//! Observables: the pair energy and the pair virial `W = sum_{i<j} r_ij F(r_ij)`, whence the
//! bulk pressure `beta P / rho = 1 + beta W / (3 N)` (Allen & Tildesley, Computer Simulation of
//! Liquids, Eq. 2.61).

use super::{Frozen, HardSphereMc, Pass};
use crate::geometry::Geometry;
use colloidsim_core::ParamError;
use colloidsim_particles::potential::Pair;
use colloidsim_particles::{Interaction, PairSpec};

/// A built pair interaction, `1 / kT` and its range.
#[derive(Debug, Clone)]
pub(crate) struct SoftPair {
    pub(crate) u: Interaction,
    pub(crate) beta: f64,
    /// The largest cut-off over species pairs.
    pub(crate) r_cut: f64,
}

impl SoftPair {
    /// `spec` for species of `diameters` at `kt`; errors name the parameter (`kT` or the
    /// spec's own).
    pub(crate) fn new(spec: &PairSpec, diameters: &[f64], kt: f64) -> Result<Self, ParamError> {
        if !(kt.is_finite() && kt > 0.0) {
            return Err(ParamError::new(
                "kT",
                format!("must be a finite number > 0, got {kt}"),
            ));
        }
        let u = spec.build(diameters, kt)?;
        let r_cut = u.r_cut_max();
        Ok(Self {
            u,
            beta: 1.0 / kt,
            r_cut,
        })
    }

    /// Check that the cells of side `side` and the box of edge `edge` around `geometry` resolve
    /// the range: `r_c <= s`, and in a droplet `r_c` at most the margin of eight largest
    /// diameters between the container and its periodic images ([`Geometry::box_edge_of`]).
    /// The error names `box` in bulk, `pair_range` in a droplet (whose box follows from it).
    pub(crate) fn check_range(
        &self,
        geometry: &Geometry,
        edge: f64,
        side: f64,
        d_max: f64,
    ) -> Result<(), ParamError> {
        let rc = self.r_cut;
        let bulk = matches!(geometry, Geometry::Bulk { .. });
        if !(rc.is_finite() && rc > 0.0) {
            return Err(ParamError::new(
                "pair_range",
                format!("the pair interaction's range must be finite and > 0, got {rc}"),
            ));
        }
        if !bulk && rc > 8.0 * d_max {
            return Err(ParamError::new(
                "pair_range",
                format!(
                    "the pair interaction reaches {rc:.6}, beyond 8 of the largest diameters ({:.6}): the box around a droplet keeps its periodic images that far apart",
                    8.0 * d_max
                ),
            ));
        }
        if rc > side {
            return Err(ParamError::new(
                if bulk { "box" } else { "pair_range" },
                format!(
                    "the periodic box edge {edge:.6} is shorter than twice the pair interaction's range {rc:.6}: a sphere would meet its own image"
                ),
            ));
        }
        Ok(())
    }
}

/// What a soft pass reads besides the slots: the interaction and each slot's species (through
/// its particle), both fixed during a sweep.
#[derive(Clone, Copy)]
pub(crate) struct SoftPass<'a> {
    pub(crate) pair: &'a SoftPair,
    pub(crate) tag: &'a [u32],
    pub(crate) types: &'a [u32],
}

impl Pass {
    /// `beta [U(x') - U(x)]` of the move of the sphere in slot `p` (of the active layer, whose
    /// first slot has global index `layer_base`) from `old` to `new` (positions relative to the
    /// corner of its cell, whose first slot is `own`), summed over the spheres within the range
    /// of either position: the 27 cells `base` around, those of the layer in `layer`, the others
    /// in `frozen` ([`Pass::cell_moves`]).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn pair_energy_change(
        &self,
        soft: &SoftPass<'_>,
        (p, old, new): (usize, [f64; 3], [f64; 3]),
        own: usize,
        base: &[usize; 27],
        layer: [&[f64]; 3],
        layer_base: usize,
        radii: &[f64],
        counts: &[u32],
        frozen: &Frozen<'_>,
    ) -> f64 {
        let s = self.side;
        let [lx, ly, lz] = layer;
        let (pair, rc) = (&soft.pair.u, soft.pair.r_cut);
        let rc2 = rc * rc;
        let species = |global: usize| soft.types[soft.tag[global] as usize];
        let (tp, dp) = (species(layer_base + p), 2.0 * radii[layer_base + p]);
        let mut du = 0.0;
        // The occupied slots of one cell (`first`: its global slot index; `shift`: its offset
        // from our cell), `skip`: the moving sphere's slot in it.
        let mut add = |x: &[f64], y: &[f64], z: &[f64], first: usize, shift: [f64; 3], skip| {
            for j in 0..x.len() {
                if Some(j) == skip {
                    continue;
                }
                let q = [x[j] + shift[0], y[j] + shift[1], z[j] + shift[2]];
                let d2 = |u: [f64; 3]| {
                    let (a, b, c) = (u[0] - q[0], u[1] - q[1], u[2] - q[2]);
                    a * a + b * b + c * c
                };
                let (r2_new, r2_old) = (d2(new), d2(old));
                if r2_new >= rc2 && r2_old >= rc2 {
                    continue;
                }
                let g = first + j;
                let (tq, dq) = (species(g), 2.0 * radii[g]);
                du += pair.energy(r2_new, tp, tq, dp, dq) - pair.energy(r2_old, tp, tq, dp, dq);
            }
        };
        // Along each axis the lower (upper) neighbours only when either position is within
        // r_c of that face.
        let lo = |a: usize| usize::from(old[a].min(new[a]) >= rc);
        let hi = |a: usize| 1 + usize::from(old[a].max(new[a]) > s - rc);
        for dz in lo(2)..=hi(2) {
            for dy in lo(1)..=hi(1) {
                for dx in lo(0)..=hi(0) {
                    let k = 9 * dz + 3 * dy + dx;
                    let n = counts[base[k] / self.cap] as usize;
                    if n == 0 {
                        continue;
                    }
                    let shift = [
                        (dx as f64 - 1.0) * s,
                        (dy as f64 - 1.0) * s,
                        (dz as f64 - 1.0) * s,
                    ];
                    if dz == 1 {
                        // Our own cell (k = 13) starts at `own`.
                        let b = base[k] - layer_base;
                        let skip = (k == 13).then(|| p - own);
                        let r = b..b + n;
                        add(
                            &lx[r.clone()],
                            &ly[r.clone()],
                            &lz[r],
                            layer_base + b,
                            shift,
                            skip,
                        );
                    } else {
                        let [x, y, z] = frozen.cell(base[k], n);
                        add(x, y, z, base[k], shift, None);
                    }
                }
            }
        }
        soft.pair.beta * du
    }
}

impl HardSphereMc {
    /// The pair interaction in place of the hard cores (`None`: hard spheres).
    pub fn pair(&self) -> Option<&Interaction> {
        self.pair.as_ref().map(|p| &p.u)
    }

    /// The total pair energy `U` and the pair virial `W = sum_{i<j} r_ij F(r_ij)` of the
    /// current positions (`None` for hard spheres). Call [`Self::bin`] first after event
    /// chains (which have no pair interactions, so never needed with one).
    pub fn pair_energy_and_virial(&self) -> Option<(f64, f64)> {
        let soft = self.pair.as_ref()?;
        let d = &self.diameters;
        let t = &self.types;
        let (mut u, mut w) = (0.0, 0.0);
        self.for_each_pair(soft.r_cut, |i, j, r2| {
            let (ti, tj) = (t[i], t[j]);
            let (di, dj) = (d[ti as usize], d[tj as usize]);
            u += soft.u.energy(r2, ti, tj, di, dj);
            w += r2 * soft.u.force_over_r(r2, ti, tj, di, dj);
        });
        Some((u, w))
    }

    /// The sum of the pair energy changes of the last sweep's accepted moves (`None` for hard
    /// spheres, or before a sweep): the total pair energy's change over the sweep, up to
    /// rounding (a check that no neighbour is missed).
    pub fn last_pair_energy_change(&self) -> Option<f64> {
        self.last_pair_energy_change
    }

    /// The force of the pair interaction on each sphere (`None` for hard spheres): the sum of
    /// `F(r_ij) r_ij / r_ij` over its neighbours, `r_ij` the minimum image in bulk.
    pub fn pair_forces(&self) -> Option<Vec<[f64; 3]>> {
        let soft = self.pair.as_ref()?;
        let (d, t, l) = (&self.diameters, &self.types, self.edge);
        let bulk = matches!(self.geometry, Geometry::Bulk { .. });
        let mut f = vec![[0.0; 3]; self.len()];
        self.for_each_pair(soft.r_cut, |i, j, r2| {
            let (ti, tj) = (t[i], t[j]);
            let g = soft
                .u
                .force_over_r(r2, ti, tj, d[ti as usize], d[tj as usize]);
            for k in 0..3 {
                let mut v = self.pos[k][i] - self.pos[k][j];
                if bulk {
                    v -= l * (v / l).round();
                }
                f[i][k] += g * v;
                f[j][k] -= g * v;
            }
        });
        Some(f)
    }

    /// The first pair of spheres whose pair energy is not finite (indices and distance).
    pub(crate) fn first_infinite_energy(&self) -> Option<(usize, usize, f64)> {
        let soft = self.pair.as_ref()?;
        let (d, t) = (&self.diameters, &self.types);
        let mut found = None;
        self.for_each_pair(soft.r_cut, |i, j, r2| {
            let (ti, tj) = (t[i], t[j]);
            let e = soft.u.energy(r2, ti, tj, d[ti as usize], d[tj as usize]);
            if found.is_none() && !e.is_finite() {
                found = Some((i.min(j), i.max(j), r2.sqrt()));
            }
        });
        found
    }
}
