//! What both MPCD methods use: the solvent's checkpoint state, GSD frames, the thermo table,
//! building and restoring solvent and colloids, and the engine a script steps by hand.

use crate::keys::Spec;
use crate::keys::{Reader, SEED_KEY};
use anyhow::{Context, Result, bail};
use colloidsim_core::ParamError;
use colloidsim_core::exchange::Exchange;
use colloidsim_core::output::OutputDir;
use colloidsim_core::param::show;
use colloidsim_md::mpcd::colloid::{ColloidState, DiscreteColloids, Region, VERTICES};
use colloidsim_md::mpcd::drying::remove_excess;
use colloidsim_md::mpcd::{Acceleration, Confinement, Srd};
use colloidsim_md::mpcd::{SrdParams, theory};
use colloidsim_particles::gsd::GsdWriter;
use colloidsim_particles::{Particles, SimBox};
use serde::{Deserialize, Serialize};

/// The exact state of the solvent, as checkpoints hold it.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct SolventState {
    pub(crate) step: u64,
    pub(crate) sort_every: u64,
    pub(crate) pos: Vec<[u32; 3]>,
    pub(crate) vel: Vec<[f64; 3]>,
}

impl SolventState {
    /// The whole solvent in the canonical order ([`Srd::gathered_state`]; collective when
    /// decomposed), for a bulk run, whose steps do not depend on the storage order: the same
    /// checkpoint on any number of ranks.
    pub(crate) fn gathered(srd: &Srd) -> Self {
        let (pos, vel) = srd.gathered_state();
        Self {
            step: srd.step(),
            sort_every: srd.sort_every(),
            pos,
            vel,
        }
    }

    pub(crate) fn engine(
        self,
        params: colloidsim_md::mpcd::SrdParams,
        sbox: SimBox,
    ) -> Result<Srd> {
        let mut srd = Srd::from_raw(params, sbox, &self.pos, &self.vel, self.step)
            .context("checkpoint.bin: the solvent state")?;
        srd.set_sort_every(self.sort_every);
        Ok(srd)
    }
}

/// A GSD frame of the solvent (type `S`, diameter 0.2 cells, velocities and masses) at the
/// given positions and velocities.
pub(crate) fn solvent_frame(
    w: &mut GsdWriter,
    srd: &Srd,
    pos: Vec<[f64; 3]>,
    vel: Vec<[f64; 3]>,
    log: &[(&str, f64)],
) -> Result<()> {
    let n = pos.len();
    let mut p = Particles::monodisperse(pos, 0.2 * srd.params().cell);
    p.type_names = vec!["S".into()];
    p.vel = vel;
    p.mass = vec![srd.params().mass; n];
    w.write_frame(srd.step(), srd.sbox(), &p, false, log)?;
    Ok(())
}

/// The positions and velocities of the solvent in a frame.
pub(crate) type SolventFrame = (Vec<[f64; 3]>, Vec<[f64; 3]>);

/// A GSD frame with colloids: the centres (types `A`, `B`, ... of the species, their
/// diameters), the vertices (type `V`) and, when given, the solvent (type `S`).
pub(crate) fn colloid_frame(
    w: &mut GsdWriter,
    srd: &Srd,
    col: &DiscreteColloids,
    solvent: Option<SolventFrame>,
    log: &[(&str, f64)],
) -> Result<()> {
    let sbox = *srd.sbox();
    let cp = col.params();
    let ns = col.mixture().len() as u32;
    let mut pos: Vec<[f64; 3]> = col.centre_positions().to_vec();
    let mut vel: Vec<[f64; 3]> = col.centre_velocities().to_vec();
    let mut typeid = col.species().to_vec();
    let mut diameter = col.diameters();
    let mut mass = vec![cp.centre_mass; pos.len()];
    for (x, v) in col.vertex_positions().iter().zip(col.vertex_velocities()) {
        let mut x = *x;
        let mut image = [0; 3];
        sbox.wrap(&mut x, &mut image);
        pos.push(x);
        vel.push(*v);
        typeid.push(ns);
        diameter.push(0.25 * srd.params().cell);
        mass.push(cp.vertex_mass);
    }
    if let Some((sp, sv)) = solvent {
        let n = sp.len();
        pos.extend(sp);
        vel.extend(sv);
        typeid.extend(std::iter::repeat_n(ns + 1, n));
        diameter.extend(std::iter::repeat_n(0.2 * srd.params().cell, n));
        mass.extend(std::iter::repeat_n(srd.params().mass, n));
    }
    let n = pos.len();
    let mut type_names = col.mixture().names.clone();
    type_names.extend(["V".into(), "S".into()]);
    let frame = Particles {
        pos,
        image: vec![[0; 3]; n],
        typeid,
        diameter,
        vel,
        mass,
        type_names,
    };
    w.write_frame(srd.step(), &sbox, &frame, false, log)?;
    Ok(())
}

/// Open (fresh) or reopen (restart) the trajectory when frames are due.
pub(crate) fn open_trajectory(
    out: &OutputDir,
    every: u64,
    fresh: bool,
) -> Result<Option<GsdWriter>> {
    if every == 0 {
        return Ok(None);
    }
    Ok(Some(
        crate::output::trajectory::writer(&out.join("trajectory.gsd"), !fresh)?.with_velocities(),
    ))
}

/// The first position at or after `pos` past which a regular checkpoint (every ~10 %) is due.
pub(crate) fn tenth_after(pos: u64, total: u64) -> Option<u64> {
    let every = (total / 10).max(1);
    let next = (pos / every + 1) * every;
    (next < total).then_some(next)
}
/// A fresh solvent in the cube of edge `l`; over the ranks of `comm`, each drawing and holding
/// its share only.
pub(crate) fn new_solvent(
    params: colloidsim_md::mpcd::SrdParams,
    l: f64,
    conf: &Confinement,
    comm: Option<Box<dyn Exchange>>,
) -> Result<Srd> {
    Ok(match comm {
        None => Srd::new(params, SimBox::cube(l), conf, 0.0)?,
        Some(c) => Srd::new_decomposed(params, SimBox::cube(l), conf, 0.0, c)?,
    })
}
/// `n` colloids placed by random sequential addition in `region` of the cube of edge `l`
/// (none when `n = 0`).
pub(crate) fn place_colloids(
    n: usize,
    params: colloidsim_md::mpcd::colloid::ColloidParams,
    l: f64,
    region: Region,
    kt: f64,
    seed: u32,
) -> Result<Option<DiscreteColloids>> {
    if n == 0 {
        return Ok(None);
    }
    Ok(Some(DiscreteColloids::random(
        params,
        SimBox::cube(l),
        n,
        region,
        kt,
        seed,
    )?))
}

/// The colloids a checkpoint holds, checked against the scenario's `n`.
pub(crate) fn restore_colloids(
    saved: Option<&ColloidState>,
    n: usize,
    params: colloidsim_md::mpcd::colloid::ColloidParams,
    l: f64,
) -> Result<Option<DiscreteColloids>> {
    match saved {
        Some(state) if state.centre_pos.len() == n && n > 0 => Ok(Some(
            DiscreteColloids::from_state(params, SimBox::cube(l), state)
                .context("checkpoint.bin: the colloids")?,
        )),
        None if n == 0 => Ok(None),
        _ => bail!("checkpoint: its colloids do not fit the scenario"),
    }
}
/// Under several ranks: the solvent decomposed over them (the colloids, few, are replicated
/// on every rank).
pub(crate) fn decompose(srd: Srd, comm: Option<Box<dyn Exchange>>) -> Result<Srd> {
    match comm {
        None => Ok(srd),
        Some(comm) => Ok(srd.decomposed(comm)?),
    }
}
/// A row of `thermo.csv` (bulk or droplet).
pub(crate) trait ThermoRow {
    /// The columns.
    const COLUMNS: &'static [&'static str];
    /// The row, with the collision time `tau`.
    fn values(&self, tau: f64) -> Vec<f64>;
}

pub(crate) fn thermo_rows<R: ThermoRow>(tau: f64, rows: &[R]) -> Vec<Vec<f64>> {
    rows.iter().map(|r| r.values(tau)).collect()
}

/// `thermo.csv` complete (it is also appended row by row as the run goes).
pub(crate) fn write_thermo<R: ThermoRow>(out: &OutputDir, tau: f64, rows: &[R]) -> Result<()> {
    out.write_rows("thermo.csv", R::COLUMNS, &thermo_rows(tau, rows))?;
    Ok(())
}
/// The solvent stepped by hand: one step is one streaming step, the removal of the excess
/// solvent of a confined droplet, and one collision (the bulk's viscosity drive acts, the
/// measurement's rescaling without the cell thermostat does not).
pub(crate) struct SolventEngine {
    pub(crate) srd: Srd,
    /// The discrete-particle colloids, if any.
    pub(crate) colloids: Option<DiscreteColloids>,
    /// The droplet's interface on the colloid centres (droplet-mpcd).
    pub(crate) interface: Option<colloidsim_particles::potential::SpeciesInterface>,
    pub(crate) method: &'static str,
    pub(crate) conf: Confinement,
    pub(crate) drive: Acceleration,
    pub(crate) scratch: Vec<(u32, u32)>,
}

impl crate::Engine for SolventEngine {
    fn method(&self) -> &str {
        self.method
    }
    fn dimensions(&self) -> usize {
        3
    }
    fn particles(&self) -> usize {
        self.srd.len() + self.colloids.as_ref().map_or(0, |c| c.particle_count())
    }
    fn step(&mut self, steps: u64) -> Result<()> {
        let tau = self.srd.params().tau;
        for _ in 0..steps {
            let t = (self.srd.step() + 1) as f64 * tau;
            let step = self.srd.step();
            self.srd.stream(t, &self.conf, &self.drive)?;
            if let Some(col) = self.colloids.as_mut() {
                match &self.interface {
                    Some(h) => col.advance(t - tau, tau, h)?,
                    None => col.advance(t - tau, tau, &colloidsim_particles::NoExternal)?,
                }
            }
            if !matches!(self.conf, Confinement::None) {
                let l = self.srd.sbox().l;
                let n = self.srd.params().density / self.srd.params().cell.powi(3);
                let expected = (n * self.conf.volume(t, l)).round() as usize;
                remove_excess(&mut self.srd, expected, step, &mut self.scratch);
            }
            let emb = self.colloids.as_mut().map(|c| c.embedded());
            self.srd.collide(t, &self.conf, emb);
        }
        Ok(())
    }
    fn steps(&self) -> u64 {
        self.srd.step()
    }
    fn time(&self) -> f64 {
        self.srd.step() as f64 * self.srd.params().tau
    }
    fn dt(&self) -> f64 {
        self.srd.params().tau
    }
    /// The solvent's, then the colloids' centres (unwrapped), then their vertices.
    fn positions(&self) -> Vec<f64> {
        let mut x = self.srd.positions();
        if let Some(c) = &self.colloids {
            x.extend(c.unwrapped_centres());
            let (centres, unwrapped) = (c.centre_positions(), c.unwrapped_centres());
            for i in 0..c.len() {
                let (a, b) = (centres[i], unwrapped[i]);
                for v in &c.vertex_positions()[c.vertex_range(i)] {
                    x.push(std::array::from_fn(|k| v[k] - a[k] + b[k]));
                }
            }
        }
        crate::engine::flat(&x)
    }
    fn velocities(&self) -> Option<Vec<f64>> {
        let mut v = self.srd.velocities();
        if let Some(c) = &self.colloids {
            v.extend_from_slice(c.centre_velocities());
            v.extend_from_slice(c.vertex_velocities());
        }
        Some(crate::engine::flat(&v))
    }
    /// Zero on the solvent (it streams freely between collisions); on the colloids' particles
    /// the bonds, the WCA between centres and the droplet's interface.
    fn forces(&self) -> Result<Vec<f64>> {
        let mut f = vec![[0.0; 3]; self.srd.len()];
        if let Some(c) = &self.colloids {
            let t = self.time();
            f.extend(match &self.interface {
                Some(h) => c.forces_at(t, h),
                None => c.forces_at(t, &colloidsim_particles::NoExternal),
            });
        }
        Ok(crate::engine::flat(&f))
    }
    fn box_lengths(&self) -> Vec<f64> {
        self.srd.sbox().l.to_vec()
    }
    fn seed(&self) -> u32 {
        self.srd.params().seed
    }
    /// The arrays laid out as `positions` gives them (solvent, colloid centres unwrapped,
    /// vertices); the solvent keeps its number (a drying droplet's shrinks as it goes).
    fn set_state(&mut self, change: crate::StateChange) -> Result<()> {
        use crate::engine::rows;
        change.check(self.particles(), 3, true, self.method)?;
        let ns = self.srd.len();
        let (mut pos, mut vel) = (self.srd.positions(), self.srd.velocities());
        if let Some(x) = &change.positions {
            pos = rows(&x[..3 * ns]);
        }
        if let Some(v) = &change.velocities {
            vel = rows(&v[..3 * ns]);
        }
        let step = change.step.unwrap_or(self.srd.step());
        let mut params = *self.srd.params();
        params.seed = change.seed.unwrap_or(params.seed);
        let srd = Srd::from_state(params, *self.srd.sbox(), &pos, &vel, step)
            .map_err(|e| anyhow::anyhow!("positions: {e}"))?;
        let colloids = match &self.colloids {
            None => None,
            Some(c) => {
                let mut state = c.state();
                state.step = step;
                let (nc, sbox) = (c.len(), *self.srd.sbox());
                if let Some(x) = &change.positions {
                    let centres = rows(&x[3 * ns..3 * (ns + nc)]);
                    let vertices = rows(&x[3 * (ns + nc)..]);
                    for (i, u) in centres.iter().enumerate() {
                        let (mut a, mut img) = (*u, [0; 3]);
                        sbox.wrap(&mut a, &mut img);
                        for (v, w) in state.vertex_pos[c.vertex_range(i)]
                            .iter_mut()
                            .zip(&vertices[c.vertex_range(i)])
                        {
                            *v = std::array::from_fn(|k| w[k] - u[k] + a[k]);
                        }
                        (state.centre_pos[i], state.centre_image[i]) = (a, img);
                    }
                }
                if let Some(v) = &change.velocities {
                    state.centre_vel = rows(&v[3 * ns..3 * (ns + nc)]);
                    state.vertex_vel = rows(&v[3 * (ns + nc)..]);
                }
                Some(
                    DiscreteColloids::from_state_mixture(*c.params(), c.mixture(), sbox, &state)
                        .map_err(|e| anyhow::anyhow!("positions: {e}"))?,
                )
            }
        };
        (self.srd, self.colloids) = (srd, colloids);
        Ok(())
    }
}

// ------------------------------------------------------------------------------------------
// What both methods' parameters share.

/// Resolved description of a solvent, as `summary.json` records it.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SolventParams {
    /// The engine's parameters (`angle` in radians).
    pub srd: SrdParams,
    /// Rotation angle in degrees.
    pub angle_degrees: f64,
    /// Number density `M / a^3`.
    pub number_density: f64,
    /// Mass density `M m / a^3`.
    pub mass_density: f64,
    /// Kikuchi et al.'s shear viscosity of this solvent (kinetic + collisional).
    pub viscosity_theory: f64,
}

impl SolventParams {
    /// The solvent `srd` described.
    pub fn of(srd: SrdParams) -> Self {
        let n = srd.density / srd.cell.powi(3);
        Self {
            srd,
            angle_degrees: srd.angle.to_degrees(),
            number_density: n,
            mass_density: n * srd.mass,
            viscosity_theory: theory::viscosity(&srd).total(),
        }
    }
}

/// The seed of the run: `seed` when given (e.g. `--seed`), else the scenario's.
pub(crate) fn run_seed(r: &Reader, seed: Option<u64>) -> Result<u32> {
    let given = r.count(&SEED_KEY)? as u32;
    match seed {
        Some(s) => crate::seed32(s),
        None => Ok(given),
    }
}

/// Peak bytes of a solvent of `n` particles in `cells` cells: `Srd::new` holds the particles
/// in `f64` before encoding them (about twice the 56 bytes per particle of a running engine).
pub(crate) fn ensure_solvent_fits(key: &Spec, n: f64, cells: f64) -> Result<()> {
    colloidsim_core::resources::ensure_fits(
        key.path,
        &format!("{n:e} solvent particles"),
        solvent_bytes(n, cells),
    )?;
    Ok(())
}

/// Peak bytes of a solvent (see [`ensure_solvent_fits`]).
pub(crate) fn solvent_bytes(n: f64, cells: f64) -> f64 {
    112.0 * n + 8.0 * cells
}

/// Bytes of `n` discrete-particle colloids: 43 particles each with positions, velocities,
/// forces and masses, their checkpoint copies and the placement grid (about 200 B a particle).
pub(crate) fn colloid_bytes(n: f64) -> f64 {
    n * (1 + VERTICES) as f64 * 200.0
}

/// Refuse `n` colloids of `particles` particles in all (key `key`) beside a solvent of
/// `solvent` bytes when both do not fit.
pub(crate) fn ensure_colloids_fit(
    key: &Spec,
    n: usize,
    particles: usize,
    solvent: f64,
) -> Result<()> {
    colloidsim_core::resources::ensure_fits(
        key.path,
        &match particles == n * (1 + VERTICES) {
            true => format!(
                "{n} colloids of {} particles beside the solvent",
                1 + VERTICES
            ),
            false => format!("{n} colloids of {particles} particles in all beside the solvent"),
        },
        solvent + colloid_bytes(particles as f64 / (1 + VERTICES) as f64),
    )?;
    Ok(())
}

/// Box edge `l` (key `key`) as a whole number of cells of edge `a`, at least `min` cells.
pub(crate) fn box_edge(key: &Spec, l: f64, a: f64, min: usize) -> Result<f64> {
    let cells = l / a;
    if (cells - cells.round()).abs() > 1e-9 * cells.max(1.0) {
        return Err(ParamError::new(
            key.path,
            format!(
                "{} is not a whole number of cells of edge solvent.cell = {}",
                show(l),
                show(a)
            ),
        )
        .into());
    }
    if (cells.round() as usize) < min {
        return Err(ParamError::new(
            key.path,
            format!("must hold at least {min} cells, got {}", show(cells)),
        )
        .into());
    }
    if cells > 4096.0 {
        return Err(ParamError::new(
            key.path,
            format!("at most 4096 cells per edge, got {}", show(cells)),
        )
        .into());
    }
    Ok(cells.round() * a)
}

/// The period of `thermo.csv` (`observe.every`; default 200 rows over the run).
pub(crate) fn thermo_every(r: &Reader, key: &Spec, collisions: u64) -> Result<u64> {
    Ok(r.opt_count(key)?.unwrap_or((collisions / 200).max(1)))
}
