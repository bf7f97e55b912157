//! Dissipative particle dynamics of hard colloids in an explicit solvent (the DPD notes,
//! docs/references.md).
//!
//! Velocity Verlet with the DPD pair forces as the thermostat (the dissipative force sees the
//! half-step velocities, as in LAMMPS `pair_style dpd` + `fix nve` and HOOMD). Every pair force
//! acts on the surface gap `h = r - (a_i + a_j)` with `a = 0` for solvent beads:
//!
//! - solvent–solvent: conservative `A w`, dissipative `-gamma w^2 (e.v)`, random
//!   `sqrt(2 gamma kT / dt) w theta`, `w = 1 - h / rc`, `A = repulsion kT / rc`;
//! - colloid–solvent: the same on the surface cut-off `rc' = (rc^3 + a^3)^(1/3) - a` with
//!   `A = repulsion kT / rc'`;
//! - colloid–colloid: no conservative DPD force; contact, Morse and squeeze lubrication
//!   ([`forces::ColloidForces`]) plus dissipative and random forces on the colloid cut-off, with
//!   the lubrication noise chosen by [`LubricationNoise`].
//!
//! **Neighbours and determinism.** Particles are kept sorted by cell (z-major), cells at least
//! the solvent/colloid–solvent range plus skin wide; each z-layer of cells is a *slab*. Solvent
//! and colloid–solvent pairs are stored once (half list) with the particle whose slab comes
//! first along z, so a slab's pairs touch only itself and the next slab: each slab sums into its
//! own force buffer and a halo buffer for the next slab, and the two are added in a fixed order.
//! Colloid–colloid pairs use a full list ([`NeighborList`]) summed per colloid. The pair random
//! number is a hash of (seed, step, pair of tags). Results are therefore bitwise independent of
//! the number of threads.
//!
//! **Lees–Edwards shear** ([`DpdParams::shear_rate`] `gamma_dot > 0`; Lees & Edwards 1972,
//! Allen & Tildesley sec. 11.3). Flow along x, gradient along y. The image of the box above
//! (`y + L_y`) is displaced along x by `delta(t) = gamma_dot L_y t mod L_x` (eq. LE-0) and moves
//! with `+gamma_dot L_y` along x. `delta` is a function of the step alone
//! ([`Dpd::shear_offset`]), so a restart at a step restores it bitwise. Pair separations use
//! [`SimBox::min_image_sheared`] (eq. LE-1: `d_y -= n L_y, d_x -= n delta`); the dissipative
//! force of a pair across the boundary sees `v_i - v_j - n gamma_dot L_y e_x` (eq. LE-2); a
//! particle crossing it is moved by [`SimBox::wrap_sheared`] (eq. LE-3: `x -+= delta`,
//! `v_x -+= gamma_dot L_y`). The cells sit inside the z-slabs, and the y boundary inside every
//! slab, so the slab/halo structure is unchanged; the half stencil of a cell next to the y
//! boundary scans the whole x row across it (`cells::scan_layer_sheared`). Verlet lists: a pair
//! across the y boundary moves by the change of `delta`, so the lists (solvent and colloid) are
//! rebuilt when `2 max|displacement| + |gamma_dot| L_y (t - t_build) > skin` (eq. LE-4: every
//! pair within range has `|n| <= 1`, its separation changes by at most the two displacements
//! plus the change of `delta`; the displacement is measured with the Lees–Edwards minimum
//! image, which follows a particle through the boundary). The DPD thermostat is pair-based and
//! Galilean invariant, so no profile is imposed on it; the kinetic temperature and the kinetic
//! stress use the peculiar velocities `v - gamma_dot y e_x` (eq. LE-5). A decomposition over
//! ranks (z-slabs) is untouched: every owner applies eq. LE-3 to its particles before they
//! migrate or are copied as ghosts. With `gamma_dot = 0` every step takes the code path of the
//! plain box.

mod domain;
pub mod forces;
pub mod setup;
pub mod viscosity;

use crate::cells::{CellSort, permute, scan_layer_sheared};
use crate::domain::Domain;
use crate::neighbor::{BoxTooSmall, NeighborList};
use crate::state::{Particles, SimBox};
use colloidsim_core::exchange::Exchange;
pub use forces::{ColloidForces, LubricationNoise, colloid_solvent_cutoff, pair_noise, step_key};
use rayon::prelude::*;
use std::collections::HashMap;
pub use viscosity::StressAcf;

/// Parameters of a DPD colloid simulation (DPD units: lengths in `rc`, energies in `kT`
/// multiples as noted, masses in solvent-bead masses).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DpdParams {
    /// Thermal energy `kT`.
    pub kt: f64,
    /// Dissipation `gamma` (all pairs).
    pub gamma: f64,
    /// Solvent–solvent cut-off `rc` (also the base of the colloid–solvent cut-off).
    pub rc: f64,
    /// Solvent–solvent repulsion in units of `kT / rc` (25 for water at density 3).
    pub repulsion: f64,
    /// Colloid–solvent repulsion in units of `kT / rc'` (the notes use 25).
    pub repulsion_cs: f64,
    /// Colloid–colloid surface cut-off of the dissipative, random, Morse and lubrication forces.
    pub colloid_cutoff: f64,
    /// Contact, Morse and lubrication.
    pub colloid: ColloidForces,
    /// Weighting of the lubrication noise.
    pub lubrication_noise: LubricationNoise,
    /// Time step.
    pub dt: f64,
    /// Verlet skin of the neighbour lists.
    pub skin: f64,
    /// Cells or Verlet lists for the solvent pairs.
    pub neighbors: NeighborMode,
    /// Seed of the pair random numbers.
    pub seed: u32,
    /// Lees–Edwards shear rate `gamma_dot` (1 / DPD time; 0: no shear, the plain periodic box):
    /// flow along x, gradient along y, streaming profile `u_x(y) = gamma_dot y` (see
    /// [`Dpd`]'s module docs).
    pub shear_rate: f64,
    /// The grid of ranks `[py, pz]` (columns along y by slabs along z) of a decomposed run;
    /// `None`: the grid with the fewest ghost cells per rank ([`crate::domain`]). Not physics:
    /// the run is the same on any grid.
    pub rank_grid: Option<[usize; 2]>,
}

impl DpdParams {
    /// DPD water: kT = 1, gamma = 4.5, rc = 1, repulsion 25, no colloid forces, dt = 0.04.
    pub fn water(dt: f64, seed: u32) -> Self {
        Self {
            kt: 1.0,
            gamma: 4.5,
            rc: 1.0,
            repulsion: 25.0,
            repulsion_cs: 25.0,
            colloid_cutoff: 1.0,
            colloid: ColloidForces {
                contact: 0.0,
                contact_range: 1e-3,
                morse_depth: 0.0,
                morse_kappa: 30.0,
                morse_r0: 0.0,
                eta0: 0.0,
                lubrication_gap: 1e-3,
            },
            lubrication_noise: LubricationNoise::Exact,
            dt,
            skin: 0.4,
            neighbors: NeighborMode::Auto,
            seed,
            shear_rate: 0.0,
            rank_grid: None,
        }
    }
}

/// Why a DPD run cannot go on.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
pub enum DpdError {
    /// Inconsistent input.
    #[error("invalid DPD input: {0}")]
    Invalid(String),
    /// The box is too small for the interaction ranges.
    #[error(transparent)]
    BoxTooSmall(#[from] BoxTooSmall),
    /// A position or velocity became NaN or infinite.
    #[error(
        "the run went non-finite at step {step}: particle {tag} ({what}); reduce `dt` or check the forces"
    )]
    NonFinite {
        /// Step at which it was detected.
        step: u64,
        /// Particle tag (index in the input).
        tag: u32,
        /// What went non-finite.
        what: &'static str,
    },
    /// A particle moved further than half the solvent cut-off in one step: the forces change
    /// over a step and the integration is meaningless (the neighbour lists stay valid, as they are
    /// rebuilt after every drift that needs it).
    #[error(
        "particle {tag} moved {distance:.3} in one step at step {step} (more than half the cut-off, {limit}): the time step is too large for these forces; reduce `dt`"
    )]
    Unstable {
        /// Step.
        step: u64,
        /// Particle tag.
        tag: u32,
        /// Distance moved in the step.
        distance: f64,
        /// The limit, `rc / 2`.
        limit: f64,
    },
}

/// The parts of [`Dpd::pressure_parts`], in order.
pub const PRESSURE_PARTS: [&str; 10] = [
    "kinetic_solvent",
    "kinetic_colloid",
    "conservative_solvent",
    "conservative_colloid",
    "dissipative_solvent",
    "dissipative_colloid",
    "random",
    "contact",
    "morse",
    "lubrication",
];

/// Virial `sum_pairs r_ij (x) F_ij` (xx, yy, zz, xy, xz, yz) of each force class and the
/// potential energies, accumulated on thermo steps.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PairVirial {
    /// Conservative DPD force.
    pub conservative: [f64; 6],
    /// Dissipative DPD force (`-gamma w^2 e.v`).
    pub dissipative: [f64; 6],
    /// Random force (all pairs, lubrication noise included).
    pub random: [f64; 6],
    /// Colloid contact force.
    pub contact: [f64; 6],
    /// Morse force.
    pub morse: [f64; 6],
    /// Squeeze lubrication friction (`-a_sq e.v`).
    pub lubrication: [f64; 6],
    /// Conservative DPD energy `A rc (1 - h/rc)^2 / 2`.
    pub energy_conservative: f64,
    /// Contact energy.
    pub energy_contact: f64,
    /// Morse energy.
    pub energy_morse: f64,
    /// The part of `conservative` from colloid–solvent pairs (included in `conservative`).
    pub conservative_colloid: [f64; 6],
    /// The part of `dissipative` from pairs with a colloid (colloid–solvent and
    /// colloid–colloid; included in `dissipative`).
    pub dissipative_colloid: [f64; 6],
}

/// Numbers in [`PairVirial::write`].
const VIRIAL_NUMBERS: usize = 51;

impl PairVirial {
    /// The parts in a flat row of [`VIRIAL_NUMBERS`] numbers (six tensors, three energies).
    fn write(&self, r: &mut [f64]) {
        for (p, part) in [
            &self.conservative,
            &self.dissipative,
            &self.random,
            &self.contact,
            &self.morse,
            &self.lubrication,
        ]
        .into_iter()
        .enumerate()
        {
            r[6 * p..6 * p + 6].copy_from_slice(part);
        }
        r[36] = self.energy_conservative;
        r[37] = self.energy_contact;
        r[38] = self.energy_morse;
        r[39..45].copy_from_slice(&self.conservative_colloid);
        r[45..51].copy_from_slice(&self.dissipative_colloid);
    }

    /// The inverse of [`Self::write`].
    fn read(r: &[f64]) -> Self {
        let t = |p: usize| -> [f64; 6] { std::array::from_fn(|k| r[6 * p + k]) };
        Self {
            conservative: t(0),
            dissipative: t(1),
            random: t(2),
            contact: t(3),
            morse: t(4),
            lubrication: t(5),
            energy_conservative: r[36],
            energy_contact: r[37],
            energy_morse: r[38],
            conservative_colloid: std::array::from_fn(|k| r[39 + k]),
            dissipative_colloid: std::array::from_fn(|k| r[45 + k]),
        }
    }

    /// Sum of all parts (the colloid subsets counted once, inside their classes).
    pub fn total(&self) -> [f64; 6] {
        let mut t = [0.0; 6];
        for p in [
            &self.conservative,
            &self.dissipative,
            &self.random,
            &self.contact,
            &self.morse,
            &self.lubrication,
        ] {
            for k in 0..6 {
                t[k] += p[k];
            }
        }
        t
    }
}

#[inline(always)]
fn outer(v: &mut [f64; 6], d: [f64; 3], f: f64, e: [f64; 3]) {
    // r (x) F with F = f e and r = d.
    v[0] += d[0] * f * e[0];
    v[1] += d[1] * f * e[1];
    v[2] += d[2] * f * e[2];
    v[3] += d[0] * f * e[1];
    v[4] += d[0] * f * e[2];
    v[5] += d[1] * f * e[2];
}

/// Thermodynamic state after a step.
#[derive(Debug, Clone, PartialEq)]
pub struct Thermo {
    /// Step.
    pub step: u64,
    /// Kinetic temperature of each type, `sum m v^2 / (3 N_type)`.
    pub temperature_by_type: Vec<f64>,
    /// Kinetic temperature of all particles, `sum m v^2 / (3 N - 3)` (momentum is conserved).
    pub temperature: f64,
    /// Kinetic part of the pressure tensor `sum m v (x) v / V` (xx, yy, zz, xy, xz, yz).
    pub kinetic: [f64; 6],
    /// Virial parts (divide by V for the pressure contribution).
    pub virial: PairVirial,
    /// Pressure tensor `(kinetic + virial) / V` (xx, yy, zz, xy, xz, yz).
    pub pressure: [f64; 6],
    /// Total potential energy.
    pub potential_energy: f64,
    /// Total momentum.
    pub momentum: [f64; 3],
}

/// Per-particle constants, stored by tag.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Props {
    typeid: u32,
    colloid: bool,
    mass: f64,
    diameter: f64,
    /// Force radius (0 for solvent).
    radius: f64,
    /// Colloid–solvent surface cut-off `rc'` of this colloid.
    cs_cut: f64,
    /// `1 / rc'`.
    cs_inv_cut: f64,
    /// Colloid–solvent repulsion amplitude `A = repulsion_cs kT / rc'`.
    cs_amp: f64,
}

impl Props {
    /// The constants as bits, to find equal ones.
    fn bits(&self) -> (u32, bool, [u64; 6]) {
        let f = [
            self.mass,
            self.diameter,
            self.radius,
            self.cs_cut,
            self.cs_inv_cut,
            self.cs_amp,
        ];
        (self.typeid, self.colloid, f.map(f64::to_bits))
    }
}

/// [`Props`] by tag, each distinct set stored once (the solvent beads of a type share one, a
/// colloid of another size has its own): 4 bytes a particle, on every rank of a decomposed run.
#[derive(Debug, Clone, Default)]
struct PropsTable {
    kinds: Vec<Props>,
    /// The kind of each tag.
    kind: Vec<u32>,
}

impl PropsTable {
    /// Append the constants of the next tag (`seen`: the kinds so far, by their bits).
    fn push(&mut self, q: Props, seen: &mut HashMap<(u32, bool, [u64; 6]), u32>) {
        let kinds = &mut self.kinds;
        let k = *seen.entry(q.bits()).or_insert_with(|| {
            kinds.push(q);
            kinds.len() as u32 - 1
        });
        self.kind.push(k);
    }

    /// The constants of every tag, in tag order.
    fn iter(&self) -> impl Iterator<Item = &Props> + '_ {
        self.kind.iter().map(|&k| &self.kinds[k as usize])
    }
}

impl std::ops::Index<usize> for PropsTable {
    type Output = Props;

    #[inline(always)]
    fn index(&self, tag: usize) -> &Props {
        &self.kinds[self.kind[tag] as usize]
    }
}

/// Bit of [`Dpd::key`] that marks a colloid (the low bits are the tag).
const COLLOID_BIT: u32 = 1 << 31;

/// How solvent and colloid–solvent pairs are found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NeighborMode {
    /// Cells when the lists would be rebuilt within about three steps (DPD water at dt ~ 0.04),
    /// Verlet lists otherwise (colloids at dt ~ 0.001). Under shear the lifetime also counts the
    /// Lees–Edwards offset's drift `gamma_dot L_y dt` a step (eq. LE-4): cells when
    /// `skin < 3 (2 x fastest step + drift)`.
    #[default]
    Auto,
    /// Verlet lists with a skin, rebuilt when a particle has moved half the skin.
    Verlet,
    /// No lists: particles are re-sorted into cells of the interaction range every step and the
    /// forces are summed over a half stencil of cells.
    Cells,
}

/// One z-layer of cells: its particles, their half neighbour list and force buffers.
#[derive(Debug, Clone, Default)]
struct Slab {
    start: usize,
    end: usize,
    /// `nbr[nbr_start[k]..nbr_start[k+1]]` are the partners of particle `start + k`
    /// (Verlet mode).
    nbr_start: Vec<u32>,
    nbr: Vec<u32>,
    /// Candidate pairs of one particle (scratch).
    cand: Vec<(u32, [f64; 3])>,
    /// Forces on this slab's particles from its own pairs.
    force: Vec<[f64; 3]>,
    /// Forces on the next slab's particles from this slab's pairs.
    halo: Vec<[f64; 3]>,
    /// The virial of the pairs met from each row of cells (along y) of this slab, by the row
    /// of the particle that meets them: summed row by row in the global order of the rows, the
    /// total is the same whether the rows are on one rank or on several.
    row_virial: Vec<PairVirial>,
    /// Whether `row_virial` holds a thermo step's sums (else it is zero).
    virial_set: bool,
}

/// A DPD simulation of solvent beads and colloids.
pub struct Dpd {
    /// Periodic box.
    pub sbox: SimBox,
    params: DpdParams,
    /// Steps done.
    pub step: u64,
    type_names: Vec<String>,
    is_colloid_type: Vec<bool>,
    // Storage order (sorted by cell, ties by tag).
    pos: Vec<[f64; 3]>,
    vel: Vec<[f64; 3]>,
    image: Vec<[i32; 3]>,
    /// Tag, with [`COLLOID_BIT`] set for colloids.
    key: Vec<u32>,
    inv_mass: Vec<f64>,
    /// Constants by tag.
    props: PropsTable,
    /// Storage index of each tag.
    by_tag: Vec<u32>,
    cells_mode: bool,
    /// Every this many steps all lists are rebuilt whether needed or not (0: never), so that a
    /// run restarted at such a step sums its forces in the same order.
    sync_every: u64,
    ref_pos: Vec<[f64; 3]>,
    slab_of: Vec<u32>,
    slabs: Vec<Slab>,
    slab_start: Vec<usize>,
    grid: CellSort,
    /// Colloid–colloid full list over colloid slots (colloid tags in increasing order).
    cc_list: NeighborList,
    cc_pos: Vec<[f64; 3]>,
    cc_tag: Vec<u32>,
    /// Colloid slot of each tag (`u32::MAX` for solvent).
    cc_slot: Vec<u32>,
    /// Velocities of the colloid slots (with `cc_pos`, refreshed every step: on every rank of
    /// a decomposed run).
    cc_vel: Vec<[f64; 3]>,
    /// Number of particles (on all ranks).
    n_total: usize,
    /// Storage range of the layers this rank integrates: its own particles and, when the run
    /// is cut along y, the ghosts of its fringe rows ([`Self::ghost`]).
    own: (usize, usize),
    /// Whether each slot is a ghost (empty when the run is not decomposed).
    ghost: Vec<bool>,
    /// This rank's layers when the run is decomposed over ranks.
    domain: Option<Domain>,
    /// Per-row sums of this rank and of all ranks, and where each row's sum lies among them
    /// (buffers of [`Self::sum_rows`]).
    layer_sums: std::cell::RefCell<(Vec<f64>, Vec<f64>, Vec<usize>)>,
    /// Range of the cells: interaction range, plus the skin in Verlet mode.
    cell_range: f64,
    builds: u64,
    /// Step of the last build of the solvent lists (Verlet mode) and of the colloid list: the
    /// change of the Lees–Edwards offset since then enters the rebuild criterion (eq. LE-4).
    list_step: u64,
    cc_list_step: u64,
    scratch3: Vec<[f64; 3]>,
    scratch_img: Vec<[i32; 3]>,
    scratch_u32: Vec<u32>,
    scratch_f64: Vec<f64>,
}

/// Everything a force evaluation reads.
struct Ctx<'a> {
    pos: &'a [[f64; 3]],
    vel: &'a [[f64; 3]],
    key: &'a [u32],
    props: &'a PropsTable,
    cc_list: &'a NeighborList,
    cc_pos: &'a [[f64; 3]],
    cc_vel: &'a [[f64; 3]],
    cc_tag: &'a [u32],
    cc_slot: &'a [u32],
    cell_start: &'a [u32],
    n_cells: [usize; 3],
    cells_mode: bool,
    cell_range: f64,
    sbox: SimBox,
    noise_key: u64,
    rc2: f64,
    inv_rc: f64,
    rc: f64,
    a_ss: f64,
    gamma: f64,
    /// `sqrt(2 gamma kT / dt)`.
    sigma: f64,
    two_kt_over_dt: f64,
    cc_cut: f64,
    inv_cc_cut: f64,
    colloid: ColloidForces,
    authors_noise: bool,
    /// Lees–Edwards offset `delta` of this step (0 without shear).
    shear_offset: f64,
    /// `gamma_dot L_y`: the x velocity of the image above.
    shear_velocity: f64,
    /// `1 / L_y`.
    inv_ly: f64,
}

impl Dpd {
    /// A simulation of `particles` (tags = input order) at `step`; `is_colloid_type[t]` says
    /// which types are colloids (force radius = diameter / 2); the others are solvent beads
    /// (point particles in the forces). Masses and velocities are taken from `particles`.
    pub fn new(
        particles: Particles,
        sbox: SimBox,
        params: DpdParams,
        is_colloid_type: Vec<bool>,
        step: u64,
    ) -> Result<Self, DpdError> {
        Self::build(particles, sbox, params, is_colloid_type, step, None)
    }

    /// The share of rank `comm.rank()` of a run decomposed over `comm.size()` ranks (module
    /// `domain`): every rank passes all `particles` (the same on every rank) and keeps those in
    /// its layers. Every method is then collective: all ranks call them in the same order. The
    /// run is bitwise the one of [`Self::new`] on one rank. One rank is the plain run.
    pub fn decomposed(
        particles: Particles,
        sbox: SimBox,
        params: DpdParams,
        is_colloid_type: Vec<bool>,
        step: u64,
        comm: Box<dyn Exchange>,
    ) -> Result<Self, DpdError> {
        Self::build(particles, sbox, params, is_colloid_type, step, Some(comm))
    }

    fn build(
        particles: Particles,
        sbox: SimBox,
        params: DpdParams,
        is_colloid_type: Vec<bool>,
        step: u64,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<Self, DpdError> {
        particles.check().map_err(DpdError::Invalid)?;
        let p = &params;
        for (name, v) in [
            ("kT", p.kt),
            ("gamma", p.gamma),
            ("rc", p.rc),
            ("dt", p.dt),
            ("skin", p.skin),
            ("colloid cut-off", p.colloid_cutoff),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(DpdError::Invalid(format!("{name} = {v} must be > 0")));
            }
        }
        if !p.shear_rate.is_finite() {
            return Err(DpdError::Invalid(format!(
                "shear rate = {} must be finite",
                p.shear_rate
            )));
        }
        if is_colloid_type.len() != particles.n_types() {
            return Err(DpdError::Invalid(format!(
                "{} colloid flags for {} types",
                is_colloid_type.len(),
                particles.n_types()
            )));
        }
        let n = particles.len();
        if n < 2 || n >= COLLOID_BIT as usize {
            return Err(DpdError::Invalid(format!(
                "{n} particles (need at least 2, fewer than 2^31)"
            )));
        }
        let mut props = PropsTable::default();
        let mut kinds_seen = HashMap::new();
        let mut max_cs_centre: f64 = 0.0;
        let mut max_radius: f64 = 0.0;
        let mut min_mass = f64::INFINITY;
        for i in 0..n {
            let colloid = is_colloid_type[particles.typeid[i] as usize];
            let m = particles.mass[i];
            if !(m.is_finite() && m > 0.0) {
                return Err(DpdError::Invalid(format!("particle {i} has mass {m}")));
            }
            min_mass = min_mass.min(m);
            let d = particles.diameter[i];
            let radius = if colloid { 0.5 * d } else { 0.0 };
            if colloid && !(radius.is_finite() && radius > 0.0) {
                return Err(DpdError::Invalid(format!("colloid {i} has diameter {d}")));
            }
            let cs_cut = if colloid {
                colloid_solvent_cutoff(p.rc, radius)
            } else {
                p.rc
            };
            max_cs_centre = max_cs_centre.max(radius + cs_cut);
            max_radius = max_radius.max(radius);
            let q = Props {
                typeid: particles.typeid[i],
                colloid,
                mass: m,
                diameter: d,
                radius,
                cs_cut,
                cs_inv_cut: 1.0 / cs_cut,
                cs_amp: p.repulsion_cs * p.kt / cs_cut,
            };
            props.push(q, &mut kinds_seen);
        }
        // Cells or lists: a Verlet list pays off when it lasts a few steps. The fastest of N
        // particles moves about 5 thermal velocities sqrt(kT / m) per unit time.
        let fast_step = 5.0 * p.dt * (p.kt / min_mass).sqrt();
        let cells_mode = match p.neighbors {
            NeighborMode::Cells => true,
            NeighborMode::Verlet => false,
            // Under shear pairs across the y boundary also move by gamma_dot L_y dt a step
            // (eq. LE-4: rebuild when 2 max|disp| + offset change > skin).
            NeighborMode::Auto if p.shear_rate != 0.0 => {
                let drift = p.shear_rate.abs() * sbox.l[1] * p.dt;
                p.skin < 3.0 * (2.0 * fast_step + drift)
            }
            NeighborMode::Auto => 0.5 * p.skin < 3.0 * fast_step,
        };
        let interaction = p.rc.max(max_cs_centre);
        let cell_range = if cells_mode {
            interaction
        } else {
            interaction + p.skin
        };
        let cc_range = if max_radius > 0.0 {
            p.colloid_cutoff + 2.0 * max_radius
        } else {
            0.0
        };
        let mut pos = particles.pos;
        let mut image = particles.image;
        let mut vel = particles.vel;
        if p.shear_rate != 0.0 {
            let offset = shear_offset_at(p, &sbox, step);
            let sv = p.shear_rate * sbox.l[1];
            for ((x, v), img) in pos.iter_mut().zip(vel.iter_mut()).zip(image.iter_mut()) {
                sbox.wrap_sheared(x, v, img, offset, sv);
            }
        } else {
            for (x, img) in pos.iter_mut().zip(image.iter_mut()) {
                sbox.wrap(x, img);
            }
        }
        let key = (0..n as u32)
            .map(|t| {
                if props[t as usize].colloid {
                    t | COLLOID_BIT
                } else {
                    t
                }
            })
            .collect();
        let inv_mass = props.iter().map(|q| 1.0 / q.mass).collect();
        let mut cc_slot = vec![u32::MAX; n];
        let mut cc_tag = Vec::new();
        for (t, q) in props.iter().enumerate() {
            if q.colloid {
                cc_slot[t] = cc_tag.len() as u32;
                cc_tag.push(t as u32);
            }
        }
        let edge = sbox.l.iter().cloned().fold(f64::INFINITY, f64::min);
        if edge < 3.0 * cell_range {
            return Err(DpdError::BoxTooSmall(BoxTooSmall {
                edge,
                minimum: 3.0 * cell_range,
                range: cell_range,
            }));
        }
        let mut s = Self {
            sbox,
            params,
            step,
            type_names: particles.type_names,
            is_colloid_type,
            pos,
            vel,
            image,
            key,
            inv_mass,
            props,
            by_tag: (0..n as u32).collect(),
            cells_mode,
            sync_every: 0,
            ref_pos: Vec::new(),
            slab_of: Vec::new(),
            slabs: Vec::new(),
            slab_start: Vec::new(),
            grid: CellSort::default(),
            cc_list: NeighborList::new(cc_range, p.skin),
            cc_pos: Vec::new(),
            cc_tag,
            cc_slot,
            cc_vel: Vec::new(),
            n_total: n,
            own: (0, n),
            ghost: Vec::new(),
            domain: None,
            layer_sums: Default::default(),
            cell_range,
            builds: 0,
            list_step: step,
            cc_list_step: step,
            scratch3: Vec::new(),
            scratch_img: Vec::new(),
            scratch_u32: Vec::new(),
            scratch_f64: Vec::new(),
        };
        if let Some(comm) = comm.filter(|c| c.size() > 1) {
            let nc = CellSort::cells_for(&sbox, cell_range);
            let sheared = p.shear_rate != 0.0;
            let grid = match p.rank_grid {
                Some([py, _]) if py > 1 && sheared => {
                    return Err(DpdError::Invalid(format!(
                        "rank grid {py} x {} (y x z): a sheared run is cut along z only (py = 1)",
                        comm.size() / py
                    )));
                }
                Some(g) => g,
                None => Domain::choose_grid(comm.size(), nc, !sheared),
            };
            let d = Domain::grid(comm, [nc[1], nc[2]], grid, cell_range).map_err(|e| {
                let key = if p.rank_grid.is_some() {
                    "`rank_grid`: "
                } else {
                    ""
                };
                DpdError::Invalid(format!("{key}{e}"))
            });
            s.domain = Some(d?);
            s.keep_own();
            s.migrate_and_fetch_ghosts()?;
        }
        s.sort_into_cells();
        if !s.cells_mode {
            s.build_lists();
        }
        s.update_colloid_list(true)?;
        s.compute_forces::<false>(s.step);
        s.exchange_halo();
        Ok(s)
    }

    /// Continue a run from a checkpoint taken right after step `step`: `particles` (positions,
    /// velocities, images, in tag order) and the forces of that step ([`Self::forces`]). When
    /// `step` is a multiple of the synchronisation period ([`Self::set_sync_every`], which the
    /// interrupted run must have used too), the continuation is bitwise identical to the
    /// uninterrupted run.
    pub fn restart(
        particles: Particles,
        forces: &[[f64; 3]],
        sbox: SimBox,
        params: DpdParams,
        is_colloid_type: Vec<bool>,
        step: u64,
        sync_every: u64,
    ) -> Result<Self, DpdError> {
        let types = is_colloid_type;
        Self::restart_on(
            particles, forces, sbox, params, types, step, sync_every, None,
        )
    }

    /// [`Self::restart`], decomposed over the ranks of `comm` when given (as in
    /// [`Self::decomposed`]): a checkpoint of a run on any number of ranks continues on any
    /// other, bitwise.
    #[allow(clippy::too_many_arguments)]
    pub fn restart_on(
        particles: Particles,
        forces: &[[f64; 3]],
        sbox: SimBox,
        params: DpdParams,
        is_colloid_type: Vec<bool>,
        step: u64,
        sync_every: u64,
        comm: Option<Box<dyn Exchange>>,
    ) -> Result<Self, DpdError> {
        if forces.len() != particles.len() {
            return Err(DpdError::Invalid(format!(
                "{} forces for {} particles",
                forces.len(),
                particles.len()
            )));
        }
        let mut s = Self::build(particles, sbox, params, is_colloid_type, step, comm)?;
        s.sync_every = sync_every;
        for i in s.own.0..s.own.1 {
            let k = s.key[i];
            let z = s.slab_of[i] as usize;
            let start = s.slabs[z].start;
            s.slabs[z].force[i - start] = forces[(k & !COLLOID_BIT) as usize];
        }
        for slab in &mut s.slabs {
            slab.halo.iter_mut().for_each(|h| *h = [0.0; 3]);
            slab.row_virial
                .iter_mut()
                .for_each(|v| *v = PairVirial::default());
        }
        Ok(s)
    }

    /// Rebuild every list at each multiple of `k` steps (0: only when needed), so that runs can
    /// be restarted bitwise from checkpoints taken at those steps.
    pub fn set_sync_every(&mut self, k: u64) {
        self.sync_every = k;
    }

    /// Parameters.
    pub fn params(&self) -> &DpdParams {
        &self.params
    }

    /// Number of particles (on all ranks).
    pub fn len(&self) -> usize {
        self.n_total
    }

    /// No particles (never true for a constructed simulation).
    pub fn is_empty(&self) -> bool {
        self.n_total == 0
    }

    /// The ranks of a decomposed run (`None`: not decomposed), for the collective steps of a
    /// run path around the engine.
    pub fn exchange(&self) -> Option<&dyn Exchange> {
        self.domain.as_ref().map(|d| &*d.comm)
    }

    /// Number of particles this rank integrates (all without a decomposition).
    pub fn owned(&self) -> usize {
        let (o0, o1) = self.own;
        o1 - o0 - self.ghost[o0..o1].iter().filter(|&&g| g).count()
    }

    /// This rank and the number of ranks the run is decomposed over (`(0, 1)`: not
    /// decomposed).
    pub fn rank(&self) -> (usize, usize) {
        self.domain
            .as_ref()
            .map_or((0, 1), |d| (d.comm.rank(), d.comm.size()))
    }

    /// Time `step * dt`.
    pub fn time(&self) -> f64 {
        self.step as f64 * self.params.dt
    }

    /// The Lees–Edwards offset `delta = gamma_dot L_y t mod L_x` of the current step (eq. LE-0;
    /// 0 without shear).
    pub fn shear_offset(&self) -> f64 {
        shear_offset_at(&self.params, &self.sbox, self.step)
    }

    /// Whether the box is sheared (`shear_rate != 0`).
    pub fn sheared(&self) -> bool {
        self.params.shear_rate != 0.0
    }

    /// Add the x velocities of all particles into `sum[b]` and their number into `count[b]`,
    /// `b` the bin of `y` among `sum.len()` equal bins over `[-L_y/2, L_y/2)` (summed layer by
    /// layer in storage order, then over the layers in order: bitwise independent of the
    /// threads and of the ranks; collective in a decomposed run). Under shear the mean is the
    /// streaming profile `gamma_dot y`. Allocates (a sample, not a step).
    pub fn add_velocity_profile(&self, sum: &mut [f64], count: &mut [f64]) {
        let bins = sum.len().min(count.len());
        if bins == 0 {
            return;
        }
        let ly = self.sbox.l[1];
        let mut total = vec![0.0; 2 * bins];
        self.sum_rows(
            2 * bins,
            |(a, b, _), r| {
                for (x, v) in self.pos[a..b].iter().zip(&self.vel[a..b]) {
                    let k = CellSort::cell_coordinate(x[1], ly, bins);
                    r[k] += v[0];
                    r[bins + k] += 1.0;
                }
            },
            &mut total,
        );
        for k in 0..bins {
            sum[k] += total[k];
            count[k] += total[bins + k];
        }
    }

    /// Number of Verlet-list builds so far (solvent lists in Verlet mode, colloid lists in
    /// both modes).
    pub fn neighbor_builds(&self) -> u64 {
        self.builds
    }

    /// Whether solvent pairs are found from cells every step (instead of Verlet lists).
    pub fn uses_cells(&self) -> bool {
        self.cells_mode
    }

    /// Number of slabs (z-layers of cells) the force pass is split into.
    pub fn slabs(&self) -> usize {
        self.slabs.len()
    }

    /// The particles in input (tag) order, with velocities.
    pub fn snapshot(&self) -> Particles {
        let n = self.len();
        let mut p = Particles {
            pos: vec![[0.0; 3]; n],
            image: vec![[0; 3]; n],
            typeid: self.props.iter().map(|q| q.typeid).collect(),
            diameter: self.props.iter().map(|q| q.diameter).collect(),
            vel: vec![[0.0; 3]; n],
            mass: self.props.iter().map(|q| q.mass).collect(),
            type_names: self.type_names.clone(),
        };
        if self.domain.is_none() {
            for (i, &k) in self.key.iter().enumerate() {
                let t = (k & !COLLOID_BIT) as usize;
                p.pos[t] = self.pos[i];
                p.image[t] = self.image[i];
                p.vel[t] = self.vel[i];
            }
            return p;
        }
        let rows = self.gather_own(10, |i, r| {
            r.push((self.key[i] & !COLLOID_BIT) as f64);
            r.extend_from_slice(&self.pos[i]);
            r.extend_from_slice(&self.vel[i]);
            r.extend(self.image[i].iter().map(|&k| k as f64));
        });
        for m in rows.chunks_exact(10) {
            let t = m[0] as usize;
            p.pos[t] = [m[1], m[2], m[3]];
            p.vel[t] = [m[4], m[5], m[6]];
            p.image[t] = [m[7] as i32, m[8] as i32, m[9] as i32];
        }
        p
    }

    /// Unwrapped positions of the particles with tags `tags`, in that order, into `out`.
    pub fn unwrapped(&self, tags: &[u32], out: &mut Vec<[f64; 3]>) {
        out.clear();
        if self.domain.is_none() {
            out.extend(tags.iter().map(|&t| {
                let i = self.by_tag[t as usize] as usize;
                self.sbox.unwrap(self.pos[i], self.image[i])
            }));
            return;
        }
        let rows = self.gather_own(4, |i, r| {
            r.push((self.key[i] & !COLLOID_BIT) as f64);
            r.extend_from_slice(&self.sbox.unwrap(self.pos[i], self.image[i]));
        });
        let mut by_tag = vec![[0.0; 3]; self.n_total];
        for m in rows.chunks_exact(4) {
            by_tag[m[0] as usize] = [m[1], m[2], m[3]];
        }
        out.extend(tags.iter().map(|&t| by_tag[t as usize]));
    }

    /// The forces of the last evaluation (positions and half-step velocities of the current
    /// step, noise of the current step), in tag order.
    pub fn forces(&self) -> Vec<[f64; 3]> {
        let n_slabs = self.slabs.len();
        let rows = self.gather_own(4, |i, r| {
            r.push((self.key[i] & !COLLOID_BIT) as f64);
            r.extend_from_slice(&total_force(&self.slabs, &self.slab_of, n_slabs, i));
        });
        let mut f = vec![[0.0; 3]; self.len()];
        for m in rows.chunks_exact(4) {
            f[m[0] as usize] = [m[1], m[2], m[3]];
        }
        f
    }

    /// Which types are colloids.
    pub fn colloid_types(&self) -> &[bool] {
        &self.is_colloid_type
    }

    /// Total momentum (summed layer by layer, in layer order).
    pub fn momentum(&self) -> [f64; 3] {
        let mut m = [0.0; 3];
        self.sum_rows(
            3,
            |(a, b, _), r| {
                for (v, w) in self.vel[a..b].iter().zip(&self.inv_mass[a..b]) {
                    for k in 0..3 {
                        r[k] += v[k] / w;
                    }
                }
            },
            &mut m,
        );
        m
    }

    /// Advance `n` steps.
    pub fn run(&mut self, n: u64) -> Result<(), DpdError> {
        for _ in 0..n {
            self.advance()?;
        }
        Ok(())
    }

    /// One velocity-Verlet step.
    pub fn advance(&mut self) -> Result<(), DpdError> {
        self.step_inner::<false>().map(|_| ())
    }

    /// One step that also accumulates the virial and energies and returns the thermodynamic
    /// state at its end.
    pub fn advance_with_thermo(&mut self) -> Result<Thermo, DpdError> {
        self.step_inner::<true>()?;
        Ok(self.thermo())
    }

    /// One step that also accumulates the virial and returns the pressure tensor at its end,
    /// `(sum m v (x) v + sum_pairs r_ij (x) F_ij) / V` (xx, yy, zz, xy, xz, yz; all pair forces,
    /// random and dissipative included), without allocating: the input of [`StressAcf`].
    /// The trajectory is the same as with [`Self::advance`].
    pub fn advance_with_pressure(&mut self) -> Result<[f64; 6], DpdError> {
        self.step_inner::<true>()?;
        Ok(self.pressure_tensor())
    }

    /// The thermodynamic state at the current step with its virial, where no step was taken
    /// with it (the first frame of a run): the forces of this step are computed again with the
    /// virial, the same forces (the pair noise is keyed by the step), so the trajectory does
    /// not change. Collective.
    pub fn thermo_with_virial(&mut self) -> Thermo {
        self.compute_forces::<true>(self.step);
        self.exchange_halo();
        self.thermo()
    }

    /// The pressure tensor from the current velocities and the virial of the last step taken
    /// with it ([`Self::thermo`]'s `pressure`, without the rest).
    pub fn pressure_tensor(&self) -> [f64; 6] {
        let mut t = [0.0; 12];
        self.sum_rows(
            12,
            |(a, b, virial), r| {
                self.kinetic_tensor(a, b, &mut r[..6]);
                r[6..].copy_from_slice(&virial.total());
            },
            &mut t,
        );
        let vol = self.sbox.volume();
        std::array::from_fn(|k| (t[k] + t[6 + k]) / vol)
    }

    /// The pressure tensor split into [`PRESSURE_PARTS`] (each xx, yy, zz, xy, xz, yz, over
    /// the volume): the kinetic tensor of the solvent and of the colloids (peculiar velocities
    /// under shear), then the pair virial by force class, the conservative and dissipative
    /// classes split into solvent–solvent pairs and pairs with a colloid. Their sum is
    /// [`Self::pressure_tensor`] to round-off; the virial is the last step taken with it
    /// ([`Self::advance_with_pressure`] or [`Self::advance_with_thermo`]). Collective.
    pub fn pressure_parts(&self) -> [[f64; 6]; PRESSURE_PARTS.len()] {
        const W: usize = 6 * PRESSURE_PARTS.len();
        let mut t = [0.0; W];
        self.sum_rows(
            W,
            |(a, b, v), r| {
                for (i, &k) in (a..b).zip(&self.key[a..b]) {
                    let c = usize::from(k & COLLOID_BIT != 0);
                    self.kinetic_tensor(i, i + 1, &mut r[6 * c..6 * c + 6]);
                }
                let minus = |a: &[f64; 6], b: &[f64; 6]| -> [f64; 6] {
                    std::array::from_fn(|k| a[k] - b[k])
                };
                for (p, part) in [
                    minus(&v.conservative, &v.conservative_colloid),
                    v.conservative_colloid,
                    minus(&v.dissipative, &v.dissipative_colloid),
                    v.dissipative_colloid,
                    v.random,
                    v.contact,
                    v.morse,
                    v.lubrication,
                ]
                .iter()
                .enumerate()
                {
                    r[12 + 6 * p..18 + 6 * p].copy_from_slice(part);
                }
            },
            &mut t,
        );
        let vol = self.sbox.volume();
        std::array::from_fn(|p| std::array::from_fn(|k| t[6 * p + k] / vol))
    }

    fn step_inner<const THERMO: bool>(&mut self) -> Result<(), DpdError> {
        let dt = self.params.dt;
        let half = 0.5 * dt;
        let sbox = self.sbox;
        let verlet = !self.cells_mode;
        let (o0, o1) = self.own;
        let shear = self.params.shear_rate != 0.0;
        // The Lees–Edwards offset of the step being taken (0 without shear).
        let offset = shear_offset_at(&self.params, &sbox, self.step + 1);
        let shear_velocity = self.params.shear_rate * sbox.l[1];
        // First half kick and drift of this rank's particles; largest step and largest
        // displacement from the list's reference (Verlet mode).
        let (max_step2, fast, max_disp2) = {
            let slabs = &self.slabs;
            let slab_of = &self.slab_of;
            let inv_mass = &self.inv_mass;
            let ref_pos = &self.ref_pos;
            let ghost = &self.ghost;
            let decomposed = self.domain.is_some();
            let n_slabs = slabs.len();
            self.pos[o0..o1]
                .par_iter_mut()
                .zip(self.vel[o0..o1].par_iter_mut())
                .zip(self.image[o0..o1].par_iter_mut())
                .enumerate()
                .with_min_len(1024)
                .map(|(k, ((x, v), img))| {
                    let i = o0 + k;
                    if decomposed && ghost[i] {
                        return (0.0, usize::MAX, 0.0);
                    }
                    let f = total_force(slabs, slab_of, n_slabs, i);
                    let im = inv_mass[i] * half;
                    let mut step2 = 0.0;
                    for k in 0..3 {
                        v[k] += im * f[k];
                        let dx = dt * v[k];
                        x[k] += dx;
                        step2 += dx * dx;
                    }
                    if shear {
                        sbox.wrap_sheared(x, v, img, offset, shear_velocity);
                    } else {
                        sbox.wrap(x, img);
                    }
                    let disp2 = if verlet {
                        let q = ref_pos[i];
                        let d = [x[0] - q[0], x[1] - q[1], x[2] - q[2]];
                        // Under shear the Lees–Edwards image follows a particle through the y
                        // boundary: the displacement of its continuous trajectory.
                        let d = if shear {
                            sbox.min_image_sheared(d, offset).0
                        } else {
                            sbox.min_image(d)
                        };
                        d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
                    } else {
                        0.0
                    };
                    (step2, i, disp2)
                })
                .reduce(
                    || (0.0, usize::MAX, 0.0),
                    |a, b| {
                        let (s, i) = if b.0 > a.0 || (b.0 == a.0 && b.1 < a.1) {
                            (b.0, b.1)
                        } else {
                            (a.0, a.1)
                        };
                        (s, i, a.2.max(b.2))
                    },
                )
        };
        self.step += 1;
        let tag_of = |i: usize| {
            if i == usize::MAX {
                -1.0
            } else {
                (self.key[i] & !COLLOID_BIT) as f64
            }
        };
        // The first particle gone non-finite, in storage order (-1: none).
        let bad = if !max_step2.is_finite() || !max_disp2.is_finite() {
            (o0..o1)
                .find(|&i| {
                    let (x, v) = (self.pos[i], self.vel[i]);
                    !self.ghost[i] && x.iter().chain(&v).any(|a| !a.is_finite())
                })
                .map_or(-1.0, tag_of)
        } else {
            -1.0
        };
        let fast_tag = tag_of(fast);
        // Every rank must agree on errors and on rebuilding the lists.
        // Verlet lists: the ghosts are refreshed in the same exchange (used unless a sort
        // follows).
        let [max_step2, fast_tag, max_disp2, bad] =
            self.agree_and_refresh([max_step2, fast_tag, max_disp2, bad], verlet);
        if !max_step2.is_finite() || !max_disp2.is_finite() {
            return Err(DpdError::NonFinite {
                step: self.step,
                tag: bad.max(0.0) as u32,
                what: "position",
            });
        }
        let limit = 0.5 * self.params.rc;
        if max_step2 > limit * limit {
            return Err(DpdError::Unstable {
                step: self.step,
                tag: fast_tag as u32,
                distance: max_step2.sqrt(),
                limit,
            });
        }
        let sync = self.sync_every > 0 && self.step.is_multiple_of(self.sync_every);
        let stale = if shear {
            // Eq. LE-4: the lists hold while 2 max|disp| + |gamma_dot| L_y (t - t_build) <= skin.
            let moved = self.shear_moved(self.list_step);
            let lim = 0.5 * (self.params.skin - moved);
            lim <= 0.0 || max_disp2 > lim * lim
        } else {
            max_disp2 > 0.25 * self.params.skin * self.params.skin
        };
        if self.cells_mode {
            self.migrate_and_fetch_ghosts()?;
            self.sort_into_cells();
            self.update_colloid_list(sync)?;
        } else if sync || stale {
            self.migrate_and_fetch_ghosts()?;
            self.sort_into_cells();
            self.build_lists();
            self.update_colloid_list(true)?;
        } else {
            // The same slots as at the last sort: the ghosts came with the agreement; refresh
            // the colloid copies.
            if self.cc_tag.len() >= 2 {
                self.gather_colloids();
            }
        }
        self.compute_forces::<THERMO>(self.step);
        self.exchange_halo();
        // Second half kick.
        let (o0, o1) = self.own;
        let bad = {
            let slabs = &self.slabs;
            let slab_of = &self.slab_of;
            let inv_mass = &self.inv_mass;
            let key = &self.key;
            let ghost = &self.ghost;
            let decomposed = self.domain.is_some();
            let n_slabs = slabs.len();
            self.vel[o0..o1]
                .par_iter_mut()
                .enumerate()
                .with_min_len(1024)
                .map(|(k, v)| {
                    let i = o0 + k;
                    if decomposed && ghost[i] {
                        return u32::MAX;
                    }
                    let f = total_force(slabs, slab_of, n_slabs, i);
                    let im = inv_mass[i] * half;
                    for k in 0..3 {
                        v[k] += im * f[k];
                    }
                    if v.iter().all(|a| a.is_finite()) {
                        u32::MAX
                    } else {
                        key[i] & !COLLOID_BIT
                    }
                })
                .min()
                .unwrap_or(u32::MAX)
        };
        let (lost, bad) = match self.domain.as_mut() {
            None => (u32::MAX, bad),
            Some(d) => {
                let lost = std::mem::replace(&mut d.lost_tag, u32::MAX);
                d.agree_min(lost, bad)
            }
        };
        if lost != u32::MAX {
            return Err(DpdError::Invalid(format!(
                "particle {lost} crossed more than one domain in a step at step {}; reduce `dt`",
                self.step
            )));
        }
        if bad != u32::MAX {
            return Err(DpdError::NonFinite {
                step: self.step,
                tag: bad,
                what: "velocity",
            });
        }
        Ok(())
    }

    /// How far the Lees–Edwards offset has moved (unwrapped) since `step`:
    /// `|gamma_dot| L_y (t - t_step)`.
    fn shear_moved(&self, step: u64) -> f64 {
        self.params.shear_rate.abs()
            * self.sbox.l[1]
            * (self.step.saturating_sub(step) as f64 * self.params.dt)
    }

    /// The velocity of storage slot `i`, minus the streaming profile `gamma_dot y e_x` under
    /// shear (the peculiar velocity, eq. LE-5).
    #[inline(always)]
    fn peculiar(&self, i: usize) -> [f64; 3] {
        let v = self.vel[i];
        if self.params.shear_rate != 0.0 {
            [v[0] - self.params.shear_rate * self.pos[i][1], v[1], v[2]]
        } else {
            v
        }
    }

    /// `sum m v (x) v` over the storage slots `a..b` (xx, yy, zz, xy, xz, yz), added to `t`;
    /// peculiar velocities under shear (eq. LE-5).
    fn kinetic_tensor(&self, a: usize, b: usize, t: &mut [f64]) {
        for (i, &k) in (a..b).zip(&self.key[a..b]) {
            let v = self.peculiar(i);
            let m = self.props[(k & !COLLOID_BIT) as usize].mass;
            t[0] += m * v[0] * v[0];
            t[1] += m * v[1] * v[1];
            t[2] += m * v[2] * v[2];
            t[3] += m * v[0] * v[1];
            t[4] += m * v[0] * v[2];
            t[5] += m * v[1] * v[2];
        }
    }

    /// Thermodynamic state from the current velocities and the virial of the last
    /// [`Self::advance_with_thermo`] (zero virial after a plain [`Self::advance`]).
    pub fn thermo(&self) -> Thermo {
        // Per layer: kinetic tensor (6), momentum (3), kinetic energy and count by type
        // (2 nt), the virial (6 x 6 + 3).
        let nt = self.type_names.len().max(1);
        let width = 9 + 2 * nt + VIRIAL_NUMBERS;
        let mut sums = vec![0.0; width];
        self.sum_rows(
            width,
            |(a, b, virial), r| {
                self.kinetic_tensor(a, b, &mut r[..6]);
                for (i, &k) in (a..b).zip(&self.key[a..b]) {
                    let q = &self.props[(k & !COLLOID_BIT) as usize];
                    let m = q.mass;
                    let (v, u) = (self.vel[i], self.peculiar(i));
                    r[9 + q.typeid as usize] += m * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
                    r[9 + nt + q.typeid as usize] += 1.0;
                    for k in 0..3 {
                        r[6 + k] += m * v[k];
                    }
                }
                virial.write(&mut r[9 + 2 * nt..]);
            },
            &mut sums,
        );
        let kin: [f64; 6] = std::array::from_fn(|k| sums[k]);
        let mom = [sums[6], sums[7], sums[8]];
        let ke = &sums[9..9 + nt];
        let count = &sums[9 + nt..9 + 2 * nt];
        let virial = PairVirial::read(&sums[9 + 2 * nt..]);
        let n = self.len();
        let temperature = ke.iter().sum::<f64>() / (3.0 * n as f64 - 3.0);
        let temperature_by_type = ke
            .iter()
            .zip(count)
            .map(|(e, &c)| if c > 0.0 { e / (3.0 * c) } else { f64::NAN })
            .collect();
        let vol = self.sbox.volume();
        let w = virial.total();
        let mut pressure = [0.0; 6];
        for k in 0..6 {
            pressure[k] = (kin[k] + w[k]) / vol;
        }
        Thermo {
            step: self.step,
            temperature_by_type,
            temperature,
            kinetic: kin.map(|x| x / vol),
            potential_energy: virial.energy_conservative
                + virial.energy_contact
                + virial.energy_morse,
            virial,
            pressure,
            momentum: mom,
        }
    }

    /// Sort particles into cells (z-major; ties by tag, so the order is a function of the
    /// positions alone) and split them into slabs (z-layers of cells).
    fn sort_into_cells(&mut self) {
        self.grid
            .sort(&self.sbox, &self.pos, &self.key, self.cell_range);
        let [_, _, nz] = self.grid.n_cells;
        let perm = &self.grid.perm;
        permute(&mut self.pos, perm, &mut self.scratch3);
        permute(&mut self.vel, perm, &mut self.scratch3);
        permute(&mut self.image, perm, &mut self.scratch_img);
        permute(&mut self.key, perm, &mut self.scratch_u32);
        permute(&mut self.inv_mass, perm, &mut self.scratch_f64);
        for (i, &k) in self.key.iter().enumerate() {
            self.by_tag[(k & !COLLOID_BIT) as usize] = i as u32;
        }
        self.slabs.resize_with(nz, Slab::default);
        for z in 0..nz {
            (self.slabs[z].start, self.slabs[z].end) = self.grid.layer(z);
        }
        self.grid.layer_of_slots(&mut self.slab_of);
        self.slab_start.clear();
        self.slab_start.extend(self.slabs.iter().map(|s| s.start));
        let ny = self.grid.n_cells[1];
        for z in 0..nz {
            let next = &self.slabs[(z + 1) % nz];
            let m = next.end - next.start;
            let own = self.slabs[z].end - self.slabs[z].start;
            let s = &mut self.slabs[z];
            s.force.resize(own, [0.0; 3]);
            s.halo.resize(m, [0.0; 3]);
            s.row_virial.resize_with(ny, PairVirial::default);
        }
        self.set_own_range();
    }

    /// Verlet mode: half lists of solvent and colloid–solvent pairs within range + skin, slab
    /// by slab in parallel, over the half stencil of cells.
    fn build_lists(&mut self) {
        self.builds += 1;
        self.list_step = self.step;
        let shear = (self.params.shear_rate != 0.0).then(|| self.shear_offset());
        self.ref_pos.clear();
        self.ref_pos.extend_from_slice(&self.pos);
        let pos = &self.pos;
        let key = &self.key;
        let props = &self.props;
        let cell_start = &self.grid.cell_start;
        let n_cells = self.grid.n_cells;
        let sbox = self.sbox;
        let rc_range2 = (self.params.rc + self.params.skin).powi(2);
        let skin = self.params.skin;
        let cell_range = self.cell_range;
        self.slabs.par_iter_mut().enumerate().for_each(|(z, slab)| {
            slab.nbr_start.clear();
            slab.nbr.clear();
            slab.nbr_start.push(0);
            let Slab {
                nbr_start,
                nbr,
                cand,
                ..
            } = slab;
            scan_layer_sheared(
                z,
                pos,
                cell_start,
                n_cells,
                &sbox,
                cell_range,
                shear,
                cand,
                |i, cands| {
                    let ki = key[i];
                    let ci = ki & COLLOID_BIT != 0;
                    let ext_i = if ci {
                        let q = &props[(ki & !COLLOID_BIT) as usize];
                        q.radius + q.cs_cut
                    } else {
                        0.0
                    };
                    for &(j, d) in cands {
                        let kj = key[j as usize];
                        let cj = kj & COLLOID_BIT != 0;
                        if ci & cj {
                            continue;
                        }
                        let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                        let lim2 = if ci {
                            (ext_i + skin) * (ext_i + skin)
                        } else if cj {
                            let q = &props[(kj & !COLLOID_BIT) as usize];
                            (q.radius + q.cs_cut + skin).powi(2)
                        } else {
                            rc_range2
                        };
                        if r2 < lim2 {
                            nbr.push(j);
                        }
                    }
                    nbr_start.push(nbr.len() as u32);
                },
            );
        });
    }

    /// Refresh the storage indices of the colloid slots and rebuild the colloid–colloid list
    /// when `force` or when a colloid has moved half the skin since its last build.
    fn update_colloid_list(&mut self, force: bool) -> Result<(), DpdError> {
        if self.cc_tag.len() < 2 {
            return Ok(());
        }
        self.gather_colloids();
        if self.params.shear_rate != 0.0 {
            // Eq. LE-4 for the colloid list.
            let offset = self.shear_offset();
            let moved = self.shear_moved(self.cc_list_step);
            if force
                || self
                    .cc_list
                    .needs_rebuild_sheared(&self.sbox, &self.cc_pos, offset, moved)
            {
                self.cc_list
                    .build_sheared(&self.sbox, &self.cc_pos, &self.cc_tag, offset)?;
                self.cc_list_step = self.step;
                if self.cells_mode {
                    self.builds += 1;
                }
            }
            return Ok(());
        }
        if force || self.cc_list.needs_rebuild(&self.sbox, &self.cc_pos) {
            self.cc_list.build(&self.sbox, &self.cc_pos, &self.cc_tag)?;
            if self.cells_mode {
                self.builds += 1;
            }
        }
        Ok(())
    }

    fn compute_forces<const THERMO: bool>(&mut self, step: u64) {
        let p = &self.params;
        let ctx = Ctx {
            pos: &self.pos,
            vel: &self.vel,
            key: &self.key,
            props: &self.props,
            cc_list: &self.cc_list,
            cc_pos: &self.cc_pos,
            cc_vel: &self.cc_vel,
            cc_tag: &self.cc_tag,
            cc_slot: &self.cc_slot,
            cell_start: &self.grid.cell_start,
            n_cells: self.grid.n_cells,
            cells_mode: self.cells_mode,
            cell_range: self.cell_range,
            sbox: self.sbox,
            noise_key: step_key(p.seed, step),
            rc2: p.rc * p.rc,
            inv_rc: 1.0 / p.rc,
            rc: p.rc,
            a_ss: p.repulsion * p.kt / p.rc,
            gamma: p.gamma,
            sigma: (2.0 * p.gamma * p.kt / p.dt).sqrt(),
            two_kt_over_dt: 2.0 * p.kt / p.dt,
            cc_cut: p.colloid_cutoff,
            inv_cc_cut: 1.0 / p.colloid_cutoff,
            colloid: p.colloid,
            authors_noise: p.lubrication_noise == LubricationNoise::Authors,
            shear_offset: shear_offset_at(p, &self.sbox, step),
            shear_velocity: p.shear_rate * self.sbox.l[1],
            inv_ly: 1.0 / self.sbox.l[1],
        };
        let shear = p.shear_rate != 0.0;
        let has_cc = self.cc_tag.len() >= 2;
        let nz = self.slabs.len();
        let starts = &self.slab_start;
        // This rank's layers (all without a decomposition).
        let (z0, z1) = self.domain.as_ref().map_or((0, nz), |d| (d.z0, d.z1));
        self.slabs[z0..z1]
            .par_iter_mut()
            .enumerate()
            .for_each(|(k, slab)| {
                let z = z0 + k;
                let next_start = starts[(z + 1) % nz];
                if shear {
                    slab_forces::<THERMO, true>(&ctx, z, slab, next_start, has_cc);
                } else {
                    slab_forces::<THERMO, false>(&ctx, z, slab, next_start, has_cc);
                }
            });
    }
}

/// The Lees–Edwards offset `delta = gamma_dot L_y t mod L_x` at `step` (`t = step dt`; eq. LE-0),
/// in `[0, L_x)`.
fn shear_offset_at(p: &DpdParams, sbox: &SimBox, step: u64) -> f64 {
    if p.shear_rate == 0.0 {
        return 0.0;
    }
    let d = (p.shear_rate * sbox.l[1] * (step as f64 * p.dt)).rem_euclid(sbox.l[0]);
    // rem_euclid can round up to L_x itself.
    if d >= sbox.l[0] { 0.0 } else { d }
}

/// Force on particle `i`: its slab's own sum plus the previous slab's halo.
#[inline(always)]
fn total_force(slabs: &[Slab], slab_of: &[u32], n_slabs: usize, i: usize) -> [f64; 3] {
    let z = slab_of[i] as usize;
    let s = &slabs[z];
    let mut f = s.force[i - s.start];
    if n_slabs > 1 {
        let prev = &slabs[(z + n_slabs - 1) % n_slabs];
        let h = prev.halo[i - s.start];
        for k in 0..3 {
            f[k] += h[k];
        }
    }
    f
}

/// Forces of one slab's pairs: solvent and colloid–solvent pairs from the half list or the
/// half stencil of cells (into the slab's buffer and the next slab's halo), colloid–colloid
/// pairs from the full list (each colloid sums its own).
/// `SHEAR`: Lees–Edwards separations and velocities (eqs. LE-1, LE-2).
fn slab_forces<const THERMO: bool, const SHEAR: bool>(
    c: &Ctx,
    z: usize,
    slab: &mut Slab,
    next_start: usize,
    has_cc: bool,
) {
    let Slab {
        start,
        end,
        nbr_start,
        nbr,
        force,
        halo,
        row_virial,
        virial_set,
        cand,
    } = slab;
    let (start, end) = (*start, *end);
    force.iter_mut().for_each(|f| *f = [0.0; 3]);
    halo.iter_mut().for_each(|f| *f = [0.0; 3]);
    // A thermo step sums the virial afresh; a plain step leaves it zero (as `thermo` reports
    // after `advance`), which costs a pass only after a thermo step.
    if THERMO || *virial_set {
        row_virial
            .iter_mut()
            .for_each(|v| *v = PairVirial::default());
        *virial_set = THERMO;
    }
    let mut vir = PairVirial::default();
    let [nx, ny, _] = c.n_cells;
    let mut out = Out {
        start,
        end,
        next_start,
        force,
        halo,
        vir: &mut vir,
        rows: Rows {
            virial: row_virial,
            row: 0,
            stop: c.cell_start[(z * ny + 1) * nx] as usize,
            cell_start: c.cell_start,
            first_cell: z * ny * nx,
            nx,
        },
    };
    if c.cells_mode {
        scan_layer_sheared(
            z,
            c.pos,
            c.cell_start,
            c.n_cells,
            &c.sbox,
            c.cell_range,
            SHEAR.then_some(c.shear_offset),
            cand,
            |i, cands| {
                particle_forces::<THERMO, SHEAR>(
                    c,
                    i,
                    cands.iter().map(|&(j, d)| (j as usize, d)),
                    &mut out,
                    has_cc,
                )
            },
        );
    } else {
        for i in start..end {
            let xi = c.pos[i];
            let k0 = nbr_start[i - start] as usize;
            let k1 = nbr_start[i - start + 1] as usize;
            let pairs = nbr[k0..k1].iter().map(|&j| {
                let q = c.pos[j as usize];
                let d = [xi[0] - q[0], xi[1] - q[1], xi[2] - q[2]];
                let d = if SHEAR {
                    c.sbox.min_image_sheared(d, c.shear_offset).0
                } else {
                    c.sbox.min_image(d)
                };
                (j as usize, d)
            });
            particle_forces::<THERMO, SHEAR>(c, i, pairs, &mut out, has_cc);
        }
    }
    if THERMO {
        let Out { rows, vir, .. } = out;
        rows.virial[rows.row] = std::mem::take(vir);
    }
}

/// The virial of each row of cells of a slab: the pairs a particle meets go to its row's
/// accumulator (storage is by row, so the accumulator moves on at each row's last slot).
struct Rows<'a> {
    virial: &'a mut [PairVirial],
    /// The row being summed, and the slot after its last.
    row: usize,
    stop: usize,
    cell_start: &'a [u32],
    /// The slab's first cell, and cells per row.
    first_cell: usize,
    nx: usize,
}

/// Where one slab's forces go.
struct Out<'a> {
    start: usize,
    end: usize,
    next_start: usize,
    force: &'a mut [[f64; 3]],
    halo: &'a mut [[f64; 3]],
    vir: &'a mut PairVirial,
    rows: Rows<'a>,
}

impl Out<'_> {
    /// Thermo steps: move the virial accumulator on to the row of slot `i`.
    #[inline(always)]
    fn enter_row(&mut self, i: usize) {
        let r = &mut self.rows;
        while i >= r.stop {
            r.virial[r.row] = std::mem::take(&mut *self.vir);
            r.row += 1;
            r.stop = r.cell_start[r.first_cell + (r.row + 1) * r.nx] as usize;
        }
    }
}

/// All forces of particle `i`'s pairs: solvent and colloid–solvent pairs `(j, x_i - x_j)` from
/// `pairs` (each pair once: the reaction goes to `j`), colloid–colloid pairs from the full list.
///
/// `SHEAR`: `pairs` carry Lees–Edwards separations; the image index of a pair is recovered as
/// `n = round((y_i - y_j - d_y) / L_y)` and its dissipative force sees
/// `v_i - v_j - n gamma_dot L_y e_x` (eq. LE-2).
#[inline(always)]
fn particle_forces<const THERMO: bool, const SHEAR: bool>(
    c: &Ctx,
    i: usize,
    pairs: impl Iterator<Item = (usize, [f64; 3])>,
    out: &mut Out,
    has_cc: bool,
) {
    if THERMO {
        out.enter_row(i);
    }
    let (start, end, next_start) = (out.start, out.end, out.next_start);
    let xi = c.pos[i];
    let vi = c.vel[i];
    let ki = c.key[i];
    let mut fi = [0.0; 3];
    let vir = &mut *out.vir;
    for (j, d) in pairs {
        let kj = c.key[j];
        if ki & kj & COLLOID_BIT != 0 {
            continue;
        }
        let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let (h, r, inv_cut, amp, cut) = if (ki | kj) & COLLOID_BIT == 0 {
            if r2 >= c.rc2 {
                continue;
            }
            let r = r2.sqrt();
            (r, r, c.inv_rc, c.a_ss, c.rc)
        } else {
            let kc = if ki & COLLOID_BIT != 0 { ki } else { kj };
            let q = &c.props[(kc & !COLLOID_BIT) as usize];
            let r = r2.sqrt();
            let h = r - q.radius;
            if h >= q.cs_cut {
                continue;
            }
            (h, r, q.cs_inv_cut, q.cs_amp, q.cs_cut)
        };
        let inv_r = 1.0 / r;
        let e = [d[0] * inv_r, d[1] * inv_r, d[2] * inv_r];
        let mut vj = c.vel[j];
        if SHEAR {
            let n = ((xi[1] - c.pos[j][1] - d[1]) * c.inv_ly).round();
            vj[0] += n * c.shear_velocity;
        }
        let ev = e[0] * (vi[0] - vj[0]) + e[1] * (vi[1] - vj[1]) + e[2] * (vi[2] - vj[2]);
        let w = 1.0 - h * inv_cut;
        let theta = pair_noise(c.noise_key, ki & !COLLOID_BIT, kj & !COLLOID_BIT);
        let fc = amp * w;
        let fd = -c.gamma * w * w * ev;
        let fr = c.sigma * w * theta;
        let f = fc + fd + fr;
        let fv = [f * e[0], f * e[1], f * e[2]];
        fi[0] += fv[0];
        fi[1] += fv[1];
        fi[2] += fv[2];
        let fj = if (start..end).contains(&j) {
            &mut out.force[j - start]
        } else {
            &mut out.halo[j - next_start]
        };
        fj[0] -= fv[0];
        fj[1] -= fv[1];
        fj[2] -= fv[2];
        if THERMO {
            outer(&mut vir.conservative, d, fc, e);
            outer(&mut vir.dissipative, d, fd, e);
            outer(&mut vir.random, d, fr, e);
            if (ki | kj) & COLLOID_BIT != 0 {
                outer(&mut vir.conservative_colloid, d, fc, e);
                outer(&mut vir.dissipative_colloid, d, fd, e);
            }
            vir.energy_conservative += 0.5 * amp * cut * w * w;
        }
    }
    if has_cc && ki & COLLOID_BIT != 0 {
        let ti = (ki & !COLLOID_BIT) as usize;
        let pi = &c.props[ti];
        let slot = c.cc_slot[ti] as usize;
        let cf = &c.colloid;
        for &k in c.cc_list.neighbors(slot) {
            let k = k as usize;
            let tj = c.cc_tag[k];
            let pj = &c.props[tj as usize];
            let xj = c.cc_pos[k];
            let dx = [xi[0] - xj[0], xi[1] - xj[1], xi[2] - xj[2]];
            let (d, n_img) = if SHEAR {
                c.sbox.min_image_sheared(dx, c.shear_offset)
            } else {
                (c.sbox.min_image(dx), 0.0)
            };
            let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let h = r - (pi.radius + pj.radius);
            if h >= c.cc_cut {
                continue;
            }
            let abar = 0.5 * (pi.radius + pj.radius);
            let inv_r = 1.0 / r;
            let e = [d[0] * inv_r, d[1] * inv_r, d[2] * inv_r];
            let mut vj = c.cc_vel[k];
            if SHEAR {
                vj[0] += n_img * c.shear_velocity;
            }
            let ev = e[0] * (vi[0] - vj[0]) + e[1] * (vi[1] - vj[1]) + e[2] * (vi[2] - vj[2]);
            let w = 1.0 - h * c.inv_cc_cut;
            let f_con = cf.contact_force(h, abar);
            let f_morse = if cf.morse_depth != 0.0 {
                cf.morse_force(h)
            } else {
                0.0
            };
            let a_sq = if cf.eta0 > 0.0 {
                cf.squeeze_coefficient(h, abar)
            } else {
                0.0
            };
            let theta = pair_noise(c.noise_key, ki & !COLLOID_BIT, tj);
            let noise = if c.authors_noise {
                (c.two_kt_over_dt * (c.gamma + a_sq)).sqrt() * w
            } else {
                (c.two_kt_over_dt * (c.gamma * w * w + a_sq)).sqrt()
            };
            let fd = -c.gamma * w * w * ev;
            let flub = -a_sq * ev;
            let fr = noise * theta;
            let f = f_con + f_morse + fd + flub + fr;
            fi[0] += f * e[0];
            fi[1] += f * e[1];
            fi[2] += f * e[2];
            if THERMO {
                // Each pair is visited from both colloids: count half.
                outer(&mut vir.contact, d, 0.5 * f_con, e);
                outer(&mut vir.morse, d, 0.5 * f_morse, e);
                outer(&mut vir.dissipative, d, 0.5 * fd, e);
                outer(&mut vir.dissipative_colloid, d, 0.5 * fd, e);
                outer(&mut vir.lubrication, d, 0.5 * flub, e);
                outer(&mut vir.random, d, 0.5 * fr, e);
                vir.energy_contact += 0.5 * cf.contact_energy(h, abar);
                if cf.morse_depth != 0.0 {
                    vir.energy_morse += 0.5 * cf.morse_energy(h);
                }
            }
        }
    }
    let f = &mut out.force[i - start];
    f[0] += fi[0];
    f[1] += fi[1];
    f[2] += fi[2];
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Equal constants are stored once; every tag reads its own.
    #[test]
    fn the_props_table_stores_each_kind_once() {
        let bead = Props {
            typeid: 0,
            colloid: false,
            mass: 1.0,
            diameter: 1.0,
            radius: 0.0,
            cs_cut: 1.0,
            cs_inv_cut: 1.0,
            cs_amp: 25.0,
        };
        let colloid = |r: f64| Props {
            typeid: 1,
            colloid: true,
            radius: r,
            diameter: 2.0 * r,
            ..bead
        };
        let by_tag = [bead, colloid(1.0), bead, colloid(1.5), colloid(1.0), bead];
        let mut t = PropsTable::default();
        let mut seen = HashMap::new();
        for q in by_tag {
            t.push(q, &mut seen);
        }
        assert_eq!(t.kinds.len(), 3);
        for (tag, q) in by_tag.iter().enumerate() {
            assert_eq!(&t[tag], q, "tag {tag}");
        }
        assert!(t.iter().eq(by_tag.iter()));
    }
}
