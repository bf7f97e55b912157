//! Dissipative particle dynamics of hard colloids in an explicit solvent (METHODS.md section 4,
//! `papers/dpd-colloids.md`).
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

pub mod forces;
pub mod scenario;

use crate::neighbor::{BoxTooSmall, NeighborList};
use crate::state::{Particles, SimBox};
pub use forces::{ColloidForces, LubricationNoise, colloid_solvent_cutoff, pair_noise, step_key};
use rayon::prelude::*;

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
    /// Seed of the pair random numbers.
    pub seed: u32,
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
            seed,
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
        "the run went non-finite at step {step}: particle {tag} ({what}); reduce run.dt or check the forces"
    )]
    NonFinite {
        /// Step at which it was detected.
        step: u64,
        /// Particle tag (index in the input).
        tag: u32,
        /// What went non-finite.
        what: &'static str,
    },
    /// A particle moved further in one step than the neighbour skin allows.
    #[error(
        "particle {tag} moved {distance:.3} in one step at step {step} (more than the skin {skin}): the time step is too large for these forces; reduce run.dt"
    )]
    Unstable {
        /// Step.
        step: u64,
        /// Particle tag.
        tag: u32,
        /// Distance moved in the step.
        distance: f64,
        /// The skin.
        skin: f64,
    },
}

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
}

impl PairVirial {
    fn add(&mut self, o: &Self) {
        for (a, b) in [
            (&mut self.conservative, &o.conservative),
            (&mut self.dissipative, &o.dissipative),
            (&mut self.random, &o.random),
            (&mut self.contact, &o.contact),
            (&mut self.morse, &o.morse),
            (&mut self.lubrication, &o.lubrication),
        ] {
            for k in 0..6 {
                a[k] += b[k];
            }
        }
        self.energy_conservative += o.energy_conservative;
        self.energy_contact += o.energy_contact;
        self.energy_morse += o.energy_morse;
    }

    /// Sum of all parts.
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

/// Per-particle constants, permuted with the particles.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Props {
    tag: u32,
    typeid: u32,
    colloid: bool,
    mass: f64,
    inv_mass: f64,
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

/// One z-layer of cells: its particles, their half neighbour list and force buffers.
#[derive(Debug, Clone, Default)]
struct Slab {
    start: usize,
    end: usize,
    /// `nbr[nbr_start[k]..nbr_start[k+1]]` are the partners of particle `start + k`.
    nbr_start: Vec<u32>,
    nbr: Vec<u32>,
    /// Forces on this slab's particles from its own pairs.
    force: Vec<[f64; 3]>,
    /// Forces on the next slab's particles from this slab's pairs.
    halo: Vec<[f64; 3]>,
    virial: PairVirial,
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
    pos: Vec<[f64; 3]>,
    vel: Vec<[f64; 3]>,
    image: Vec<[i32; 3]>,
    props: Vec<Props>,
    ref_pos: Vec<[f64; 3]>,
    slab_of: Vec<u32>,
    slabs: Vec<Slab>,
    slab_start: Vec<usize>,
    n_cells: [usize; 3],
    cell_start: Vec<u32>,
    cell_key: Vec<u32>,
    by_tag: Vec<u32>,
    /// Colloid-colloid full list over colloid slots.
    cc_list: NeighborList,
    cc_pos: Vec<[f64; 3]>,
    cc_tag: Vec<u32>,
    /// Storage index of each colloid slot.
    cc_index: Vec<u32>,
    /// Colloid slot of each particle (`u32::MAX` for solvent).
    cc_slot: Vec<u32>,
    fluid_range: f64,
    builds: u64,
    scratch3: Vec<[f64; 3]>,
    scratch_img: Vec<[i32; 3]>,
    scratch_props: Vec<Props>,
    perm: Vec<u32>,
}

/// Everything a force evaluation reads.
struct Ctx<'a> {
    pos: &'a [[f64; 3]],
    vel: &'a [[f64; 3]],
    props: &'a [Props],
    cc_list: &'a NeighborList,
    cc_index: &'a [u32],
    cc_slot: &'a [u32],
    sbox: SimBox,
    key: u64,
    rc: f64,
    rc2: f64,
    inv_rc: f64,
    a_ss: f64,
    gamma: f64,
    /// `sqrt(2 gamma kT / dt)`.
    sigma: f64,
    two_kt_over_dt: f64,
    cc_cut: f64,
    inv_cc_cut: f64,
    cc_amp: f64,
    colloid: ColloidForces,
    authors_noise: bool,
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
        if is_colloid_type.len() != particles.n_types() {
            return Err(DpdError::Invalid(format!(
                "{} colloid flags for {} types",
                is_colloid_type.len(),
                particles.n_types()
            )));
        }
        let n = particles.len();
        if n < 2 || n > u32::MAX as usize / 2 {
            return Err(DpdError::Invalid(format!(
                "{n} particles (need at least 2)"
            )));
        }
        let mut props = Vec::with_capacity(n);
        let mut max_cs_centre: f64 = 0.0;
        let mut max_radius: f64 = 0.0;
        for i in 0..n {
            let colloid = is_colloid_type[particles.typeid[i] as usize];
            let m = particles.mass[i];
            if !(m.is_finite() && m > 0.0) {
                return Err(DpdError::Invalid(format!("particle {i} has mass {m}")));
            }
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
            props.push(Props {
                tag: i as u32,
                typeid: particles.typeid[i],
                colloid,
                mass: m,
                inv_mass: 1.0 / m,
                diameter: d,
                radius,
                cs_cut,
                cs_inv_cut: 1.0 / cs_cut,
                cs_amp: p.repulsion_cs * p.kt / cs_cut,
            });
        }
        let fluid_range = p.rc.max(max_cs_centre) + p.skin;
        let cc_range = if max_radius > 0.0 {
            p.colloid_cutoff + 2.0 * max_radius
        } else {
            0.0
        };
        let mut pos = particles.pos;
        let mut image = particles.image;
        for (x, img) in pos.iter_mut().zip(image.iter_mut()) {
            sbox.wrap(x, img);
        }
        let mut s = Self {
            sbox,
            params,
            step,
            type_names: particles.type_names,
            is_colloid_type,
            pos,
            vel: particles.vel,
            image,
            props,
            ref_pos: Vec::new(),
            slab_of: Vec::new(),
            slabs: Vec::new(),
            slab_start: Vec::new(),
            n_cells: [0; 3],
            cell_start: Vec::new(),
            cell_key: Vec::new(),
            by_tag: Vec::new(),
            cc_list: NeighborList::new(cc_range, p.skin),
            cc_pos: Vec::new(),
            cc_tag: Vec::new(),
            cc_index: Vec::new(),
            cc_slot: Vec::new(),
            fluid_range,
            builds: 0,
            scratch3: Vec::new(),
            scratch_img: Vec::new(),
            scratch_props: Vec::new(),
            perm: Vec::new(),
        };
        let edge = sbox.l.iter().cloned().fold(f64::INFINITY, f64::min);
        if edge < 3.0 * fluid_range {
            return Err(DpdError::BoxTooSmall(BoxTooSmall {
                edge,
                range: 1.5 * fluid_range,
            }));
        }
        s.rebuild()?;
        s.compute_forces::<false>(s.step);
        Ok(s)
    }

    /// Parameters.
    pub fn params(&self) -> &DpdParams {
        &self.params
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// No particles (never true for a constructed simulation).
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    /// Time `step * dt`.
    pub fn time(&self) -> f64 {
        self.step as f64 * self.params.dt
    }

    /// Number of neighbour-list builds so far.
    pub fn neighbor_builds(&self) -> u64 {
        self.builds
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
            typeid: vec![0; n],
            diameter: vec![0.0; n],
            vel: vec![[0.0; 3]; n],
            mass: vec![0.0; n],
            type_names: self.type_names.clone(),
        };
        for (i, q) in self.props.iter().enumerate() {
            let t = q.tag as usize;
            p.pos[t] = self.pos[i];
            p.image[t] = self.image[i];
            p.typeid[t] = q.typeid;
            p.diameter[t] = q.diameter;
            p.vel[t] = self.vel[i];
            p.mass[t] = q.mass;
        }
        p
    }

    /// Unwrapped positions of the particles with tags `tags`, in that order, into `out`.
    pub fn unwrapped(&self, tags: &[u32], out: &mut Vec<[f64; 3]>) {
        out.clear();
        out.extend(tags.iter().map(|&t| {
            let i = self.by_tag[t as usize] as usize;
            self.sbox.unwrap(self.pos[i], self.image[i])
        }));
    }

    /// The forces of the last evaluation (positions and half-step velocities of the current
    /// step, noise of the current step), in tag order.
    pub fn forces(&self) -> Vec<[f64; 3]> {
        let mut f = vec![[0.0; 3]; self.len()];
        for (i, q) in self.props.iter().enumerate() {
            f[q.tag as usize] = total_force(&self.slabs, &self.slab_of, self.slabs.len(), i);
        }
        f
    }

    /// Which types are colloids.
    pub fn colloid_types(&self) -> &[bool] {
        &self.is_colloid_type
    }

    /// Total momentum.
    pub fn momentum(&self) -> [f64; 3] {
        let mut m = [0.0; 3];
        for (v, q) in self.vel.iter().zip(&self.props) {
            for k in 0..3 {
                m[k] += q.mass * v[k];
            }
        }
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

    fn step_inner<const THERMO: bool>(&mut self) -> Result<(), DpdError> {
        let dt = self.params.dt;
        let half = 0.5 * dt;
        let sbox = self.sbox;
        let skin = self.params.skin;
        // First half kick and drift; largest displacement from the list's reference.
        let (max_step2, fast, max_disp2) = {
            let slabs = &self.slabs;
            let slab_of = &self.slab_of;
            let props = &self.props;
            let ref_pos = &self.ref_pos;
            let n_slabs = slabs.len();
            self.pos
                .par_iter_mut()
                .zip(self.vel.par_iter_mut())
                .zip(self.image.par_iter_mut())
                .enumerate()
                .with_min_len(1024)
                .map(|(i, ((x, v), img))| {
                    let f = total_force(slabs, slab_of, n_slabs, i);
                    let im = props[i].inv_mass * half;
                    let mut step2 = 0.0;
                    for k in 0..3 {
                        v[k] += im * f[k];
                        let dx = dt * v[k];
                        x[k] += dx;
                        step2 += dx * dx;
                    }
                    sbox.wrap(x, img);
                    let q = ref_pos[i];
                    let d = sbox.min_image([x[0] - q[0], x[1] - q[1], x[2] - q[2]]);
                    (step2, i, d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
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
        if !max_step2.is_finite() || !max_disp2.is_finite() {
            let i = self
                .pos
                .iter()
                .zip(&self.vel)
                .position(|(x, v)| x.iter().chain(v).any(|a| !a.is_finite()))
                .unwrap_or(0);
            return Err(DpdError::NonFinite {
                step: self.step,
                tag: self.props[i].tag,
                what: "position",
            });
        }
        if max_step2 > skin * skin {
            return Err(DpdError::Unstable {
                step: self.step,
                tag: self.props[fast].tag,
                distance: max_step2.sqrt(),
                skin,
            });
        }
        if max_disp2 > 0.25 * skin * skin {
            self.rebuild()?;
        }
        self.compute_forces::<THERMO>(self.step);
        // Second half kick.
        let bad = {
            let slabs = &self.slabs;
            let slab_of = &self.slab_of;
            let props = &self.props;
            let n_slabs = slabs.len();
            self.vel
                .par_iter_mut()
                .enumerate()
                .with_min_len(1024)
                .map(|(i, v)| {
                    let f = total_force(slabs, slab_of, n_slabs, i);
                    let im = props[i].inv_mass * half;
                    for k in 0..3 {
                        v[k] += im * f[k];
                    }
                    if v.iter().all(|a| a.is_finite()) {
                        u32::MAX
                    } else {
                        props[i].tag
                    }
                })
                .min()
                .unwrap_or(u32::MAX)
        };
        if bad != u32::MAX {
            return Err(DpdError::NonFinite {
                step: self.step,
                tag: bad,
                what: "velocity",
            });
        }
        Ok(())
    }

    /// Thermodynamic state from the current velocities and the virial of the last
    /// [`Self::advance_with_thermo`] (zero virial after a plain [`Self::advance`]).
    pub fn thermo(&self) -> Thermo {
        let nt = self.type_names.len().max(1);
        let mut ke = vec![0.0; nt];
        let mut count = vec![0usize; nt];
        let mut kin = [0.0; 6];
        let mut mom = [0.0; 3];
        for (v, q) in self.vel.iter().zip(&self.props) {
            let m = q.mass;
            ke[q.typeid as usize] += m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            count[q.typeid as usize] += 1;
            kin[0] += m * v[0] * v[0];
            kin[1] += m * v[1] * v[1];
            kin[2] += m * v[2] * v[2];
            kin[3] += m * v[0] * v[1];
            kin[4] += m * v[0] * v[2];
            kin[5] += m * v[1] * v[2];
            for k in 0..3 {
                mom[k] += m * v[k];
            }
        }
        let n = self.len();
        let temperature = ke.iter().sum::<f64>() / (3.0 * n as f64 - 3.0);
        let temperature_by_type = ke
            .iter()
            .zip(&count)
            .map(|(e, &c)| {
                if c > 0 {
                    e / (3.0 * c as f64)
                } else {
                    f64::NAN
                }
            })
            .collect();
        let mut virial = PairVirial::default();
        for s in &self.slabs {
            virial.add(&s.virial);
        }
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

    /// Sort particles into cells, split them into slabs and rebuild both neighbour lists.
    /// The result depends only on the positions (ties broken by tag), so a run that rebuilds at
    /// the same steps sums its forces in the same order.
    fn rebuild(&mut self) -> Result<(), DpdError> {
        self.builds += 1;
        let n = self.len();
        let range = self.fluid_range;
        let l = self.sbox.l;
        let mut nc = [0usize; 3];
        for k in 0..3 {
            nc[k] = (l[k] / range).floor() as usize;
        }
        self.n_cells = nc;
        let [nx, ny, nz] = nc;
        let total = nx * ny * nz;
        let scale = [nx as f64 / l[0], ny as f64 / l[1], nz as f64 / l[2]];
        // Cell of every particle (z-major), counting sort in tag order.
        self.by_tag.resize(n, 0);
        for (i, q) in self.props.iter().enumerate() {
            self.by_tag[q.tag as usize] = i as u32;
        }
        self.cell_key.resize(n, 0);
        for (c, x) in self.cell_key.iter_mut().zip(&self.pos) {
            let cx = (((x[0] + 0.5 * l[0]) * scale[0]).max(0.0) as usize).min(nx - 1);
            let cy = (((x[1] + 0.5 * l[1]) * scale[1]).max(0.0) as usize).min(ny - 1);
            let cz = (((x[2] + 0.5 * l[2]) * scale[2]).max(0.0) as usize).min(nz - 1);
            *c = ((cz * ny + cy) * nx + cx) as u32;
        }
        self.cell_start.clear();
        self.cell_start.resize(total + 1, 0);
        for &c in &self.cell_key {
            self.cell_start[c as usize + 1] += 1;
        }
        for c in 0..total {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.perm.resize(n, 0);
        {
            // Reuse slab_of as the fill pointer of each cell.
            let fill = &mut self.slab_of;
            fill.clear();
            fill.extend_from_slice(&self.cell_start[..total]);
            for &i in &self.by_tag {
                let c = self.cell_key[i as usize] as usize;
                self.perm[fill[c] as usize] = i;
                fill[c] += 1;
            }
        }
        permute(&mut self.pos, &self.perm, &mut self.scratch3);
        permute(&mut self.vel, &self.perm, &mut self.scratch3);
        permute(&mut self.image, &self.perm, &mut self.scratch_img);
        permute(&mut self.props, &self.perm, &mut self.scratch_props);
        for (k, q) in self.props.iter().enumerate() {
            self.by_tag[q.tag as usize] = k as u32;
        }
        self.ref_pos.clear();
        self.ref_pos.extend_from_slice(&self.pos);
        // Slabs = z-layers of cells.
        let layer = nx * ny;
        self.slabs.resize_with(nz, Slab::default);
        self.slab_of.clear();
        self.slab_of.resize(n, 0);
        for z in 0..nz {
            let (a, b) = (
                self.cell_start[z * layer] as usize,
                self.cell_start[(z + 1) * layer] as usize,
            );
            self.slabs[z].start = a;
            self.slabs[z].end = b;
            self.slab_of[a..b].iter_mut().for_each(|s| *s = z as u32);
        }
        self.slab_start.clear();
        self.slab_start.extend(self.slabs.iter().map(|s| s.start));
        for z in 0..nz {
            let next = &self.slabs[(z + 1) % nz];
            let m = next.end - next.start;
            let own = self.slabs[z].end - self.slabs[z].start;
            let s = &mut self.slabs[z];
            s.force.resize(own, [0.0; 3]);
            s.halo.resize(m, [0.0; 3]);
        }
        // Half lists, slab by slab in parallel.
        let pos = &self.pos;
        let props = &self.props;
        let cell_start = &self.cell_start;
        let sbox = self.sbox;
        let rc_range2 = (self.params.rc + self.params.skin).powi(2);
        let skin = self.params.skin;
        self.slabs.par_iter_mut().enumerate().for_each(|(z, slab)| {
            slab.nbr_start.clear();
            slab.nbr.clear();
            slab.nbr_start.push(0);
            for i in slab.start..slab.end {
                let x = pos[i];
                let pi = props[i];
                let cx = (((x[0] + 0.5 * l[0]) * scale[0]).max(0.0) as usize).min(nx - 1);
                let cy = (((x[1] + 0.5 * l[1]) * scale[1]).max(0.0) as usize).min(ny - 1);
                let cz = z;
                let own = (cz * ny + cy) * nx + cx;
                let mut scan = |c: usize, first: usize| {
                    for j in first..cell_start[c + 1] as usize {
                        let pj = props[j];
                        if pi.colloid && pj.colloid {
                            continue;
                        }
                        let q = pos[j];
                        let d = sbox.min_image([x[0] - q[0], x[1] - q[1], x[2] - q[2]]);
                        let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                        let lim2 = if pi.colloid {
                            (pi.radius + pi.cs_cut + skin).powi(2)
                        } else if pj.colloid {
                            (pj.radius + pj.cs_cut + skin).powi(2)
                        } else {
                            rc_range2
                        };
                        if r2 < lim2 {
                            slab.nbr.push(j as u32);
                        }
                    }
                };
                // Half stencil: later members of the own cell, then 13 of the 26 neighbour
                // cells (+x; +y row; the whole +z layer), so each pair is found once, in the
                // own slab or the next one.
                scan(own, i + 1);
                for &[dx, dy, dz] in &HALF_STENCIL {
                    let xx = (cx + nx + dx - 1) % nx;
                    let yy = (cy + ny + dy - 1) % ny;
                    let zz = (cz + nz + dz - 1) % nz;
                    let c = (zz * ny + yy) * nx + xx;
                    scan(c, cell_start[c] as usize);
                }
                slab.nbr_start.push(slab.nbr.len() as u32);
            }
        });
        // Colloid-colloid full list.
        self.cc_pos.clear();
        self.cc_tag.clear();
        self.cc_index.clear();
        self.cc_slot.clear();
        self.cc_slot.resize(n, u32::MAX);
        for (i, q) in self.props.iter().enumerate() {
            if q.colloid {
                self.cc_slot[i] = self.cc_index.len() as u32;
                self.cc_index.push(i as u32);
                self.cc_pos.push(self.pos[i]);
                self.cc_tag.push(q.tag);
            }
        }
        if self.cc_index.len() >= 2 {
            self.cc_list.build(&self.sbox, &self.cc_pos, &self.cc_tag)?;
        }
        Ok(())
    }

    fn compute_forces<const THERMO: bool>(&mut self, step: u64) {
        let p = &self.params;
        let ctx = Ctx {
            pos: &self.pos,
            vel: &self.vel,
            props: &self.props,
            cc_list: &self.cc_list,
            cc_index: &self.cc_index,
            cc_slot: &self.cc_slot,
            sbox: self.sbox,
            key: step_key(p.seed, step),
            rc: p.rc,
            rc2: p.rc * p.rc,
            inv_rc: 1.0 / p.rc,
            a_ss: p.repulsion * p.kt / p.rc,
            gamma: p.gamma,
            sigma: (2.0 * p.gamma * p.kt / p.dt).sqrt(),
            two_kt_over_dt: 2.0 * p.kt / p.dt,
            cc_cut: p.colloid_cutoff,
            inv_cc_cut: 1.0 / p.colloid_cutoff,
            cc_amp: 0.0,
            colloid: p.colloid,
            authors_noise: p.lubrication_noise == LubricationNoise::Authors,
        };
        let has_cc = self.cc_index.len() >= 2;
        let nz = self.slabs.len();
        let starts = &self.slab_start;
        self.slabs.par_iter_mut().enumerate().for_each(|(z, slab)| {
            let next_start = starts[(z + 1) % nz];
            slab_forces::<THERMO>(&ctx, slab, next_start, has_cc);
        });
    }
}

/// The 13 neighbour cells of the half stencil, as offsets + 1 in x, y, z.
const HALF_STENCIL: [[usize; 3]; 13] = [
    [2, 1, 1],
    [0, 2, 1],
    [1, 2, 1],
    [2, 2, 1],
    [0, 0, 2],
    [1, 0, 2],
    [2, 0, 2],
    [0, 1, 2],
    [1, 1, 2],
    [2, 1, 2],
    [0, 2, 2],
    [1, 2, 2],
    [2, 2, 2],
];

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

fn permute<T: Copy>(v: &mut Vec<T>, perm: &[u32], scratch: &mut Vec<T>) {
    scratch.clear();
    scratch.extend(perm.iter().map(|&k| v[k as usize]));
    std::mem::swap(v, scratch);
}

/// Forces of one slab's pairs: solvent and colloid–solvent pairs from the half list (into the
/// slab's buffer and the next slab's halo), colloid–colloid pairs from the full list (each
/// colloid sums its own).
fn slab_forces<const THERMO: bool>(c: &Ctx, slab: &mut Slab, next_start: usize, has_cc: bool) {
    slab.force.iter_mut().for_each(|f| *f = [0.0; 3]);
    slab.halo.iter_mut().for_each(|f| *f = [0.0; 3]);
    let mut vir = PairVirial::default();
    let start = slab.start;
    let end = slab.end;
    for i in start..end {
        let xi = c.pos[i];
        let vi = c.vel[i];
        let pi = c.props[i];
        let mut fi = [0.0; 3];
        let k0 = slab.nbr_start[i - start] as usize;
        let k1 = slab.nbr_start[i - start + 1] as usize;
        for &j in &slab.nbr[k0..k1] {
            let j = j as usize;
            let pj = c.props[j];
            let xj = c.pos[j];
            let d = c
                .sbox
                .min_image([xi[0] - xj[0], xi[1] - xj[1], xi[2] - xj[2]]);
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            let (h, inv_cut, amp, cut) = if !(pi.colloid | pj.colloid) {
                if r2 >= c.rc2 {
                    continue;
                }
                (r2.sqrt(), c.inv_rc, c.a_ss, c.rc)
            } else {
                let q = if pi.colloid { pi } else { pj };
                let h = r2.sqrt() - q.radius;
                if h >= q.cs_cut {
                    continue;
                }
                (h, q.cs_inv_cut, q.cs_amp, q.cs_cut)
            };
            let r = h + pi.radius + pj.radius;
            let inv_r = 1.0 / r;
            let e = [d[0] * inv_r, d[1] * inv_r, d[2] * inv_r];
            let vj = c.vel[j];
            let ev = e[0] * (vi[0] - vj[0]) + e[1] * (vi[1] - vj[1]) + e[2] * (vi[2] - vj[2]);
            let w = 1.0 - h * inv_cut;
            let theta = pair_noise(c.key, pi.tag, pj.tag);
            let fc = amp * w;
            let fd = -c.gamma * w * w * ev;
            let fr = c.sigma * w * theta;
            let f = fc + fd + fr;
            let fv = [f * e[0], f * e[1], f * e[2]];
            fi[0] += fv[0];
            fi[1] += fv[1];
            fi[2] += fv[2];
            let fj = if (start..end).contains(&j) {
                &mut slab.force[j - start]
            } else {
                // j lies in the next slab (possibly slab 0 across the periodic boundary).
                &mut slab.halo[j - next_start]
            };
            fj[0] -= fv[0];
            fj[1] -= fv[1];
            fj[2] -= fv[2];
            if THERMO {
                outer(&mut vir.conservative, d, fc, e);
                outer(&mut vir.dissipative, d, fd, e);
                outer(&mut vir.random, d, fr, e);
                vir.energy_conservative += 0.5 * amp * cut * w * w;
            }
        }
        if has_cc && pi.colloid {
            let slot = c.cc_slot[i] as usize;
            let cf = &c.colloid;
            for &k in c.cc_list.neighbors(slot) {
                let j = c.cc_index[k as usize] as usize;
                let pj = c.props[j];
                let xj = c.pos[j];
                let d = c
                    .sbox
                    .min_image([xi[0] - xj[0], xi[1] - xj[1], xi[2] - xj[2]]);
                let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                let h = r - (pi.radius + pj.radius);
                if h >= c.cc_cut {
                    continue;
                }
                let abar = 0.5 * (pi.radius + pj.radius);
                let inv_r = 1.0 / r;
                let e = [d[0] * inv_r, d[1] * inv_r, d[2] * inv_r];
                let vj = c.vel[j];
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
                let theta = pair_noise(c.key, pi.tag, pj.tag);
                let noise = if c.authors_noise {
                    (c.two_kt_over_dt * (c.gamma + a_sq)).sqrt() * w
                } else {
                    (c.two_kt_over_dt * (c.gamma * w * w + a_sq)).sqrt()
                };
                let fcons = c.cc_amp * w;
                let fd = -c.gamma * w * w * ev;
                let flub = -a_sq * ev;
                let fr = noise * theta;
                let f = fcons + f_con + f_morse + fd + flub + fr;
                fi[0] += f * e[0];
                fi[1] += f * e[1];
                fi[2] += f * e[2];
                if THERMO {
                    // Each pair is visited from both colloids: count half.
                    outer(&mut vir.conservative, d, 0.5 * fcons, e);
                    outer(&mut vir.contact, d, 0.5 * f_con, e);
                    outer(&mut vir.morse, d, 0.5 * f_morse, e);
                    outer(&mut vir.dissipative, d, 0.5 * fd, e);
                    outer(&mut vir.lubrication, d, 0.5 * flub, e);
                    outer(&mut vir.random, d, 0.5 * fr, e);
                    vir.energy_contact += 0.5 * cf.contact_energy(h, abar);
                    if cf.morse_depth != 0.0 {
                        vir.energy_morse += 0.5 * cf.morse_energy(h);
                    }
                }
            }
        }
        let f = &mut slab.force[i - start];
        f[0] += fi[0];
        f[1] += fi[1];
        f[2] += fi[2];
    }
    slab.virial = if THERMO { vir } else { PairVirial::default() };
}
