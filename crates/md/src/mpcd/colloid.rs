//! Colloids as discrete particles (the drying-droplet paper's MPCD colloid model,
//! docs/references.md): the surface of a sphere of diameter `d` is a regular icosahedron subdivided once,
//! its 42 vertices projected onto the sphere ([`Geometry`]); every vertex is bonded to its
//! nearest neighbours on the mesh (120 edges) and to a central particle (42 spokes) by harmonic
//! bonds `U = k/2 (r - r0)^2` with `r0` the bond's length in the ideal shape. Centres repel by
//! WCA (`epsilon = kT`, `sigma = d`, cut at `2^(1/6) d`) and may feel the droplet's
//! [`HarmonicInterface`](crate::potential::HarmonicInterface) at `R(t)`, or its hard-wall limit
//! (the whole colloid reflected when its centre crosses, [`SpeciesInterface::hard`]). Between
//! two collisions the `43 N` particles move by velocity Verlet with `md_steps` steps of
//! `dt = tau / md_steps`; in the collisions only the VERTICES
//! join the cells ([`DiscreteColloids::embedded`]; the paper: "the colloidal particles were
//! coupled to the solvent by including the vertex particles in the collision step"); the
//! solvent streams through the colloids (no excluded region). [`MpcdSystem`] does one
//! streaming step, the colloids' MD over it and the collision.
//!
//! **Layout and determinism.** One array per quantity: centres (`N`) and vertices (`42 N`,
//! colloid by colloid) apart, as `[f64; 3]` rows so that the vertices can be lent to
//! [`Srd::collide`] as they are. The 43 particles of a colloid are stored as one unwrapped
//! rigid-ish cluster around its centre; when the centre leaves the box the whole colloid is
//! shifted by a box edge and the centre's image counter moves. Bonds act within a colloid, so
//! forces are summed colloid by colloid (rayon over colloids, each writes only its own rows);
//! the WCA force on a centre is gathered from a cell list of the centres built in index order,
//! so a step is bitwise the same on any number of threads. Nothing is allocated per step.

use super::boundary::Confinement;
use super::srd::{Acceleration, CollisionStats, Embedded, Srd, StreamStats};
use super::{Draw, MpcdError, draw};
use crate::potential::{External, LennardJones, LjParams, NoExternal, Pair, SpeciesInterface};
use crate::state::SimBox;
use colloidsim_core::rng::Ziggurat;
use colloidsim_particles::Mixture;
use rand::RngExt;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Vertices per colloid.
pub const VERTICES: usize = 42;
/// Mesh edges per colloid (vertex-vertex bonds).
pub const EDGES: usize = 120;
/// Most trial positions per colloid in a random placement.
pub const MAX_PLACEMENT_TRIALS: u64 = 1_000_000;

/// The ideal shape on the unit sphere: 42 vertices (the 12 of a regular icosahedron, then the
/// 30 edge midpoints) and the 120 edges of the once-subdivided mesh (`i < j`, sorted).
#[derive(Debug, Clone, PartialEq)]
pub struct Geometry {
    /// Unit vectors of the vertices.
    pub vertices: Vec<[f64; 3]>,
    /// Mesh edges (vertex pairs).
    pub edges: Vec<[usize; 2]>,
}

impl Geometry {
    /// The once-subdivided icosahedron: the icosahedron's vertices `(0, +-1, +-phi)` and their
    /// cyclic permutations, its 20 faces (triples of vertices at mutual distance 2), each face
    /// cut into 4 by its edge midpoints, all 42 points projected onto the unit sphere.
    pub fn subdivided_icosahedron() -> Self {
        let phi = 0.5 * (1.0 + 5f64.sqrt());
        let mut ico = Vec::with_capacity(12);
        for s1 in [-1.0, 1.0] {
            for s2 in [-phi, phi] {
                ico.push([0.0, s1, s2]);
                ico.push([s1, s2, 0.0]);
                ico.push([s2, 0.0, s1]);
            }
        }
        let dist2 = |a: [f64; 3], b: [f64; 3]| {
            (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
        };
        // Icosahedron edges have length 2 (squared 4); the next distance is 2 phi.
        let adjacent = |i: usize, j: usize| (dist2(ico[i], ico[j]) - 4.0).abs() < 1e-9;
        let mut ico_edges = Vec::new();
        for i in 0..12 {
            for j in i + 1..12 {
                if adjacent(i, j) {
                    ico_edges.push([i, j]);
                }
            }
        }
        let midpoint = |i: usize, j: usize| -> usize {
            12 + ico_edges
                .iter()
                .position(|e| *e == [i.min(j), i.max(j)])
                .expect("an icosahedron edge")
        };
        let mut vertices: Vec<[f64; 3]> = ico.clone();
        for e in &ico_edges {
            let (a, b) = (ico[e[0]], ico[e[1]]);
            vertices.push([
                0.5 * (a[0] + b[0]),
                0.5 * (a[1] + b[1]),
                0.5 * (a[2] + b[2]),
            ]);
        }
        for v in &mut vertices {
            let r = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            *v = v.map(|x| x / r);
        }
        let mut edges = std::collections::BTreeSet::new();
        let mut add = |i: usize, j: usize| {
            edges.insert([i.min(j), i.max(j)]);
        };
        for i in 0..12 {
            for j in i + 1..12 {
                for k in j + 1..12 {
                    if adjacent(i, j) && adjacent(j, k) && adjacent(i, k) {
                        let (ij, jk, ik) = (midpoint(i, j), midpoint(j, k), midpoint(i, k));
                        for (a, b) in [(i, ij), (ij, j), (j, jk), (jk, k), (k, ik), (ik, i)] {
                            add(a, b);
                        }
                        add(ij, jk);
                        add(jk, ik);
                        add(ik, ij);
                    }
                }
            }
        }
        Self {
            vertices,
            edges: edges.into_iter().collect(),
        }
    }
}

/// Highest subdivision frequency of a shell ([`Geometry::geodesic`]): 642 vertices, a size
/// ratio up to 4.25 against the smallest species.
pub const MAX_FREQUENCY: usize = 8;

impl Geometry {
    /// The icosahedron's faces cut into `frequency^2` triangles (class-I geodesic sphere): on
    /// each face the points `A + (a (B - A) + b (C - A)) / frequency` (`a, b >= 0`,
    /// `a + b <= frequency`) projected onto the unit sphere, neighbours on the triangular grid
    /// bonded: `10 f^2 + 2` vertices (the 12 of the icosahedron first) and `30 f^2` edges.
    /// Frequency 2 is [`Self::subdivided_icosahedron`] itself (the single-size model, bit for
    /// bit).
    pub fn geodesic(frequency: usize) -> Self {
        assert!(
            (1..=MAX_FREQUENCY).contains(&frequency),
            "frequency 1..={MAX_FREQUENCY}"
        );
        if frequency == 2 {
            return Self::subdivided_icosahedron();
        }
        let base = Self::subdivided_icosahedron();
        let ico = &base.vertices[..12];
        let dist2 = |a: [f64; 3], b: [f64; 3]| {
            (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
        };
        // Unit-sphere icosahedron edges: the 12 corners' nearest neighbours.
        let edge2 = (0..12)
            .flat_map(|i| (i + 1..12).map(move |j| (i, j)))
            .map(|(i, j)| dist2(ico[i], ico[j]))
            .fold(f64::INFINITY, f64::min);
        let adjacent = |i: usize, j: usize| (dist2(ico[i], ico[j]) - edge2).abs() < 1e-9;
        let f = frequency as f64;
        let mut vertices: Vec<[f64; 3]> = ico.to_vec();
        // Points met on several faces (edges, corners) are found again by their rounded position.
        let key = |v: [f64; 3]| v.map(|x| (x * 1e9).round() as i64);
        let mut index: std::collections::BTreeMap<[i64; 3], usize> = vertices
            .iter()
            .enumerate()
            .map(|(i, v)| (key(*v), i))
            .collect();
        let mut edges = std::collections::BTreeSet::new();
        for i in 0..12 {
            for j in i + 1..12 {
                for k in j + 1..12 {
                    if !(adjacent(i, j) && adjacent(j, k) && adjacent(i, k)) {
                        continue;
                    }
                    let (a, b, c) = (ico[i], ico[j], ico[k]);
                    let mut point = |u: usize, w: usize| -> usize {
                        let (x, y) = (u as f64 / f, w as f64 / f);
                        let p: [f64; 3] =
                            std::array::from_fn(|q| a[q] + x * (b[q] - a[q]) + y * (c[q] - a[q]));
                        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                        let p = p.map(|x| x / r);
                        *index.entry(key(p)).or_insert_with(|| {
                            vertices.push(p);
                            vertices.len() - 1
                        })
                    };
                    for u in 0..frequency {
                        for w in 0..frequency - u {
                            let (p, q, s) = (point(u, w), point(u + 1, w), point(u, w + 1));
                            for (m, n) in [(p, q), (p, s), (q, s)] {
                                edges.insert([m.min(n), m.max(n)]);
                            }
                        }
                    }
                }
            }
        }
        Self {
            vertices,
            edges: edges.into_iter().collect(),
        }
    }

    /// The frequency of the shell of diameter `diameter` beside the smallest species'
    /// (`reference`, frequency 2): `round(2 d / d_min)`, so that neighbouring vertices stay as
    /// far apart as on the smallest shell (about `0.55 d_min / 2`) and a larger shell is as
    /// dense a net in the solvent's collision cells as the smallest.
    pub fn frequency_for(diameter: f64, reference: f64) -> usize {
        let f = (2.0 * diameter / reference).round();
        if f.is_finite() {
            (f as usize).max(2)
        } else {
            usize::MAX
        }
    }

    /// Vertices of the shell of `frequency`: `10 f^2 + 2`.
    pub fn vertex_count(frequency: usize) -> usize {
        10 * frequency * frequency + 2
    }

    /// The shortest edge on the unit sphere.
    fn shortest_edge(&self) -> f64 {
        self.edges
            .iter()
            .map(|&[i, j]| dist(self.vertices[i], self.vertices[j]))
            .fold(f64::INFINITY, f64::min)
    }
}

/// Largest thermal bond strain [`ColloidParams::thermal_bond_strain`] accepted: 10 % of the
/// shortest bond (the default `k = 5000 kT / a^2` keeps it at 10 % down to `d = 0.52 a`).
pub const MAX_BOND_STRAIN: f64 = 0.1;

/// Parameters of the discrete-particle colloids (MPCD units: lengths in the cell edge `a`,
/// masses in the solvent mass `m`, energies in `kT`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ColloidParams {
    /// Diameter `d` of the sphere the vertices lie on (also the WCA `sigma` of the centres).
    pub diameter: f64,
    /// Mass of each vertex particle.
    pub vertex_mass: f64,
    /// Mass of the central particle.
    pub centre_mass: f64,
    /// Spring constant `k` of every bond (energy / length^2).
    pub bond_k: f64,
    /// Velocity-Verlet steps per collision time (`dt = tau / md_steps`).
    pub md_steps: u32,
    /// WCA `epsilon` between centres (energy; 0 switches it off).
    pub wca_epsilon: f64,
}

impl ColloidParams {
    /// Defaults for diameter `d` at temperature `kt` (all CHOSEN, the paper's values were lost
    /// in our copy; see docs/mpcd.md, "Colloids"): every particle of mass `5 m` (the solvent
    /// mass of one cell at density 5), `k = 5000 kT / a^2` (bond-length fluctuations about 1 %),
    /// 50 Verlet steps per `tau` (`dt = 0.002` at `tau = 0.1`), `epsilon = kT`.
    pub fn standard(diameter: f64, kt: f64) -> Self {
        Self {
            diameter,
            vertex_mass: 5.0,
            centre_mass: 5.0,
            bond_k: 5000.0 * kt,
            md_steps: 50,
            wca_epsilon: kt,
        }
    }

    /// Every parameter at its edge; the message names the key and its allowed range.
    pub fn check(&self) -> Result<(), MpcdError> {
        for (key, v) in [
            ("colloid diameter", self.diameter),
            ("colloid vertex_mass", self.vertex_mass),
            ("colloid centre_mass", self.centre_mass),
            ("bond k", self.bond_k),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(MpcdError::Invalid(format!(
                    "{key} = {v} must be a finite number > 0"
                )));
            }
        }
        if !(self.wca_epsilon.is_finite() && self.wca_epsilon >= 0.0) {
            return Err(MpcdError::Invalid(format!(
                "colloid wca_epsilon = {} must be a finite number >= 0",
                self.wca_epsilon
            )));
        }
        if !(1..=100_000).contains(&self.md_steps) {
            return Err(MpcdError::Invalid(format!(
                "md_steps = {} must lie in 1..=100000",
                self.md_steps
            )));
        }
        Ok(())
    }

    /// Root-mean-square thermal stretch `sqrt(kT / k)` of one bond at temperature `kt`
    /// (equipartition), divided by the shortest rest length of the mesh: the fraction by which
    /// the colloid's shape fluctuates. Above [`MAX_BOND_STRAIN`] the bonds no longer hold a sphere
    /// of diameter `d` (a tiny `d` or a soft `k`).
    pub fn thermal_bond_strain(&self, kt: f64) -> f64 {
        self.thermal_bond_strain_of(kt, self.diameter, 2)
    }

    /// [`Self::thermal_bond_strain`] of a shell of diameter `diameter` and `frequency`
    /// ([`Geometry::geodesic`]).
    pub fn thermal_bond_strain_of(&self, kt: f64, diameter: f64, frequency: usize) -> f64 {
        let shortest = Geometry::geodesic(frequency).shortest_edge() * 0.5 * diameter;
        (kt / self.bond_k).sqrt() / shortest
    }

    /// The highest normal-mode frequency `omega` of one colloid's bond network (the 120 edges
    /// and 42 spokes as harmonic springs `k` about the rest shape, vertex and centre masses):
    /// the square root of the largest eigenvalue of `M^(-1/2) H M^(-1/2)`, `H` the Hessian
    /// `k sum_bonds (e e^T)` over the bonds' unit vectors `e`, by power iteration from a fixed
    /// start (500 products, converged to 1e-6 for every mass ratio tried against a full
    /// diagonalisation). It does not depend on `d`. Velocity Verlet is stable for `omega dt < 2`.
    pub fn highest_bond_frequency(&self) -> f64 {
        self.highest_bond_frequency_of(2)
    }

    /// [`Self::highest_bond_frequency`] of the shell of `frequency` ([`Geometry::geodesic`]).
    pub fn highest_bond_frequency_of(&self, frequency: usize) -> f64 {
        let geo = Geometry::geodesic(frequency);
        let nv = geo.vertices.len();
        let n = nv + 1;
        let mut pos = geo.vertices.clone();
        pos.push([0.0; 3]);
        let bonds: Vec<(usize, usize, [f64; 3])> = geo
            .edges
            .iter()
            .map(|&[i, j]| (i, j))
            .chain((0..nv).map(|i| (i, nv)))
            .map(|(i, j)| {
                let e = [0, 1, 2].map(|c| pos[i][c] - pos[j][c]);
                let len = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
                (i, j, e.map(|x| x / len))
            })
            .collect();
        let inv_sqrt_m: Vec<f64> = (0..n)
            .map(|i| match i < nv {
                true => 1.0 / self.vertex_mass.sqrt(),
                false => 1.0 / self.centre_mass.sqrt(),
            })
            .collect();
        let mut v: Vec<[f64; 3]> = (0..n)
            .map(|i| [0, 1, 2].map(|c| (1.0 + (3 * i + c) as f64).sin()))
            .collect();
        let mut w = vec![[0.0; 3]; n];
        let mut lambda = 0.0;
        for _ in 0..500 {
            w.iter_mut().for_each(|x| *x = [0.0; 3]);
            for &(i, j, e) in &bonds {
                let (a, b) = (
                    v[i].map(|x| x * inv_sqrt_m[i]),
                    v[j].map(|x| x * inv_sqrt_m[j]),
                );
                let s = (0..3).map(|c| e[c] * (a[c] - b[c])).sum::<f64>();
                for c in 0..3 {
                    w[i][c] += s * e[c] * inv_sqrt_m[i];
                    w[j][c] -= s * e[c] * inv_sqrt_m[j];
                }
            }
            let dot = |x: &[[f64; 3]], y: &[[f64; 3]]| {
                x.iter()
                    .zip(y)
                    .map(|(p, q)| p[0] * q[0] + p[1] * q[1] + p[2] * q[2])
                    .sum::<f64>()
            };
            lambda = dot(&v, &w) / dot(&v, &v);
            let norm = dot(&w, &w).sqrt();
            for (x, y) in v.iter_mut().zip(&w) {
                *x = y.map(|c| c / norm);
            }
        }
        (self.bond_k * lambda).sqrt()
    }

    /// WCA cut-off `2^(1/6) d`.
    pub fn wca_cut(&self) -> f64 {
        2f64.powf(1.0 / 6.0) * self.diameter
    }

    /// Mass of one colloid (centre and vertices).
    pub fn colloid_mass(&self) -> f64 {
        self.centre_mass + VERTICES as f64 * self.vertex_mass
    }
}

/// Where random colloids go.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Region {
    /// Anywhere in the periodic box.
    Box,
    /// Centres within `radius - d/2` of the origin (the whole sphere of diameter `d` inside
    /// the droplet of radius `radius`).
    Sphere {
        /// Droplet radius.
        radius: f64,
    },
}

/// The exact state of the colloids (for checkpoints): with the same [`ColloidParams`], species
/// and box, [`DiscreteColloids::from_state_mixture`] continues bitwise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ColloidState {
    /// Centre positions (in the box).
    pub centre_pos: Vec<[f64; 3]>,
    /// Centre velocities.
    pub centre_vel: Vec<[f64; 3]>,
    /// Box crossings of each centre.
    pub centre_image: Vec<[i32; 3]>,
    /// Vertex positions, colloid by colloid (42 for the smallest species), unwrapped about
    /// their centre.
    pub vertex_pos: Vec<[f64; 3]>,
    /// Vertex velocities.
    pub vertex_vel: Vec<[f64; 3]>,
    /// MD blocks (collision times) done.
    pub step: u64,
    /// Colloids of each species, stored species by species (the species of every colloid).
    pub species_counts: Vec<usize>,
}

/// A bond of the ideal shape: vertex indices (or the centre for spokes) and rest length.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Edge {
    i: usize,
    j: usize,
    r0: f64,
}

/// Cells per axis of a grid over a box of edges `l` for `n` centres, cells at least `width`
/// wide (at least `min` per axis): as many as fit, but no more than about `max(8 n, 32^3)` in
/// all (more cells would only be empty, and a tiny `width` would ask for an unbounded grid).
fn grid_cells(l: [f64; 3], width: f64, n: usize, min: usize) -> [usize; 3] {
    let cap = ((8.0 * n as f64).max(32768.0)).cbrt().floor() as usize;
    std::array::from_fn(|k| {
        let fit = l[k] / width;
        // Non-finite (width 0 or a NaN) or beyond the cap: the cap.
        let fit = if fit.is_finite() {
            fit.floor().max(0.0)
        } else {
            f64::MAX
        };
        (fit.min(cap as f64) as usize).max(min)
    })
}

/// The shell of one species: its mesh scaled to its diameter, and where its colloids lie.
#[derive(Debug, Clone)]
struct Shell {
    diameter: f64,
    /// Vertices per colloid.
    vertices: usize,
    /// The ideal shape (offsets of the vertices from the centre).
    shape: Vec<[f64; 3]>,
    edges: Vec<Edge>,
    /// Rest length of the spokes (`d/2`).
    spoke: f64,
    /// First colloid of the species and its count (colloids are stored species by species).
    first: usize,
    count: usize,
    /// First vertex of the species.
    first_vertex: usize,
}

impl Shell {
    /// Mass of one colloid of this shell.
    fn mass(&self, p: &ColloidParams) -> f64 {
        p.centre_mass + self.vertices as f64 * p.vertex_mass
    }
}

/// `N` discrete-particle colloids in the periodic box of the solvent (see the module docs),
/// of one or more species stored species by species.
#[derive(Debug, Clone)]
pub struct DiscreteColloids {
    params: ColloidParams,
    mixture: Mixture,
    sbox: SimBox,
    /// One per species.
    shells: Vec<Shell>,
    /// Species of each colloid.
    species: Vec<u32>,
    /// First vertex of each colloid (and the total at the end).
    vertex_start: Vec<usize>,
    /// WCA of each species pair at the pair's mean diameter.
    wca: LennardJones,
    /// Largest WCA cut-off.
    cut_max: f64,
    centre_pos: Vec<[f64; 3]>,
    centre_vel: Vec<[f64; 3]>,
    centre_image: Vec<[i32; 3]>,
    centre_force: Vec<[f64; 3]>,
    vertex_pos: Vec<[f64; 3]>,
    vertex_vel: Vec<[f64; 3]>,
    vertex_force: Vec<[f64; 3]>,
    /// Vertex masses (one value repeated, lent to the collisions).
    vertex_mass: Vec<f64>,
    /// Cell list of the centres: cells per axis (0: all pairs), starts and members.
    cells: [usize; 3],
    cell_start: Vec<u32>,
    cell_members: Vec<u32>,
    cell_of: Vec<u32>,
    step: u64,
}

impl DiscreteColloids {
    /// Colloids of one species (diameter `params.diameter`) centred at `centres`; see
    /// [`Self::new_mixture`].
    pub fn new(
        params: ColloidParams,
        sbox: SimBox,
        centres: &[[f64; 3]],
        kt: f64,
        seed: u32,
    ) -> Result<Self, MpcdError> {
        let one = Mixture::one(params.diameter, centres.len());
        Self::new_mixture(params, &one, sbox, centres, kt, seed)
    }

    /// Colloids of the species of `mixture` (stored species by species, `centres` in that
    /// order; `params.diameter` the smallest diameter) centred at `centres` (any periodic
    /// image) with random orientations and Maxwell–Boltzmann velocities at `kt` for every
    /// particle of each, from the stream `(seed, 0, Colloid, i)` of colloid `i`; the total
    /// momentum of all colloid particles is then removed (the solvent of [`Srd::new`] has none
    /// either, so the whole system starts at rest). Overlaps are not checked here.
    pub fn new_mixture(
        params: ColloidParams,
        mixture: &Mixture,
        sbox: SimBox,
        centres: &[[f64; 3]],
        kt: f64,
        seed: u32,
    ) -> Result<Self, MpcdError> {
        params.check()?;
        if !(kt.is_finite() && kt > 0.0) {
            return Err(MpcdError::Invalid(format!(
                "colloid kT = {kt} must be a finite number > 0"
            )));
        }
        if centres.len() != mixture.total() {
            return Err(MpcdError::Invalid(format!(
                "{} colloid centres for species of {:?} colloids",
                centres.len(),
                mixture.counts
            )));
        }
        if let Some(i) = centres
            .iter()
            .position(|x| x.iter().any(|c| !c.is_finite()))
        {
            return Err(MpcdError::NonFinite {
                step: 0,
                what: "colloid",
                index: i,
            });
        }
        let mut me = Self::empty(params, mixture, sbox)?;
        let zig = Ziggurat::get();
        let n = centres.len();
        let shells = me.shells.clone();
        let (mp, mc) = (params.vertex_mass, params.centre_mass);
        let (sd_c, sd_v) = ((kt / mc).sqrt(), (kt / mp).sqrt());
        for (i, c) in centres.iter().enumerate() {
            let shell = &shells[me.species[i] as usize];
            let v0 = me.vertex_start[i];
            let mut rng = draw(seed, 0, Draw::Colloid, i as u64);
            // A uniform random rotation: the unit quaternion of four normal deviates.
            let rot = loop {
                let q: [f64; 4] = std::array::from_fn(|_| zig.sample(&mut rng));
                let norm = (q.iter().map(|x| x * x).sum::<f64>()).sqrt();
                if norm > 1e-6 {
                    break rotation_of(q.map(|x| x / norm));
                }
            };
            let mut x = *c;
            let mut image = [0; 3];
            sbox.wrap(&mut x, &mut image);
            me.centre_pos[i] = x;
            me.centre_vel[i] = std::array::from_fn(|_| sd_c * zig.sample(&mut rng));
            for (k, s) in shell.shape.iter().enumerate() {
                let r = apply(&rot, *s);
                me.vertex_pos[v0 + k] = [x[0] + r[0], x[1] + r[1], x[2] + r[2]];
                me.vertex_vel[v0 + k] = std::array::from_fn(|_| sd_v * zig.sample(&mut rng));
            }
        }
        if n > 0 {
            let p = me.momentum();
            let m = shells
                .iter()
                .map(|s| s.count as f64 * s.mass(&params))
                .sum::<f64>();
            let u = p.map(|x| x / m);
            for v in me.centre_vel.iter_mut().chain(me.vertex_vel.iter_mut()) {
                for k in 0..3 {
                    v[k] -= u[k];
                }
            }
        }
        me.compute_forces(0.0, &NoExternal);
        Ok(me)
    }

    /// `n` colloids of one species at random non-overlapping positions; see
    /// [`Self::random_mixture`].
    pub fn random(
        params: ColloidParams,
        sbox: SimBox,
        n: usize,
        region: Region,
        kt: f64,
        seed: u32,
    ) -> Result<Self, MpcdError> {
        let one = Mixture::one(params.diameter, n);
        Self::random_mixture(params, &one, sbox, region, kt, seed)
    }

    /// The colloids of `mixture` at random non-overlapping positions (centres of species `a`
    /// and `b` at least `(d_a + d_b) / 2` apart, periodic) in `region` (each colloid wholly
    /// inside a sphere), by random sequential addition, the largest species first: colloid `i`
    /// (storage index) tries positions from the stream `(seed, 0, Colloid, 2^48 + i)` until one
    /// fits (at most [`MAX_PLACEMENT_TRIALS`]); orientations and velocities as
    /// [`Self::new_mixture`].
    pub fn random_mixture(
        params: ColloidParams,
        mixture: &Mixture,
        sbox: SimBox,
        region: Region,
        kt: f64,
        seed: u32,
    ) -> Result<Self, MpcdError> {
        params.check()?;
        let n = mixture.total();
        let d_max = mixture.d_max();
        let l = sbox.l;
        let reach = |d: f64| match region {
            Region::Box => None,
            Region::Sphere { radius } => Some(radius - 0.5 * d),
        };
        if let Region::Sphere { radius } = region {
            let half = 0.5 * l.iter().cloned().fold(f64::INFINITY, f64::min);
            if !(radius.is_finite() && radius > 0.5 * d_max && radius <= half) {
                return Err(MpcdError::Invalid(format!(
                    "colloid placement radius = {radius} must lie in (d/2, L/2] = ({}, {half}]",
                    0.5 * d_max
                )));
            }
        }
        if n >= 1 << 40 {
            return Err(MpcdError::Invalid(format!(
                "{n} colloids: at most 2^40 are supported"
            )));
        }
        let diameter: Vec<f64> = mixture.particle_diameters();
        // A grid of cells at least d_max wide over the box for the overlap checks (no more
        // cells than the colloids need: a tiny d must not make a grid of 1024^3 empty cells).
        let nc = grid_cells(l, d_max, n, 1);
        let cell = |x: [f64; 3]| -> [usize; 3] {
            std::array::from_fn(|k| {
                (((x[k] / l[k] + 0.5) * nc[k] as f64).floor() as usize).min(nc[k] - 1)
            })
        };
        let mut grid: Vec<Vec<u32>> = vec![Vec::new(); nc[0] * nc[1] * nc[2]];
        let mut centres: Vec<[f64; 3]> = vec![[0.0; 3]; n];
        // The largest species first (stable: one species in storage order).
        let mut order: Vec<usize> = (0..mixture.len()).collect();
        order.sort_by(|&a, &b| mixture.diameters[b].total_cmp(&mixture.diameters[a]));
        let starts: Vec<usize> = mixture
            .counts
            .iter()
            .scan(0, |acc, &c| {
                let s = *acc;
                *acc += c;
                Some(s)
            })
            .collect();
        for i in order
            .iter()
            .flat_map(|&s| starts[s]..starts[s] + mixture.counts[s])
        {
            let di = diameter[i];
            let mut rng = draw(seed, 0, Draw::Colloid, (1 << 48) + i as u64);
            let mut placed = false;
            for _ in 0..MAX_PLACEMENT_TRIALS {
                let mut x: [f64; 3] = std::array::from_fn(|k| (rng.random::<f64>() - 0.5) * l[k]);
                if let Some(rmax) = reach(di) {
                    // Uniform in the ball: rejection from the cube of edge 2 rmax.
                    x = std::array::from_fn(|k| (2.0 * x[k] / l[k]) * rmax);
                    if x[0] * x[0] + x[1] * x[1] + x[2] * x[2] > rmax * rmax {
                        continue;
                    }
                    let mut image = [0; 3];
                    sbox.wrap(&mut x, &mut image);
                }
                let c = cell(x);
                let mut free = true;
                'search: for dz in -1i64..=1 {
                    for dy in -1i64..=1 {
                        for dx in -1i64..=1 {
                            let q = [dx, dy, dz];
                            let cc: [usize; 3] = std::array::from_fn(|k| {
                                (c[k] as i64 + q[k]).rem_euclid(nc[k] as i64) as usize
                            });
                            for &j in &grid[(cc[2] * nc[1] + cc[1]) * nc[0] + cc[0]] {
                                let y = centres[j as usize];
                                let r = sbox.min_image([x[0] - y[0], x[1] - y[1], x[2] - y[2]]);
                                let contact = 0.5 * (di + diameter[j as usize]);
                                if r[0] * r[0] + r[1] * r[1] + r[2] * r[2] < contact * contact {
                                    free = false;
                                    break 'search;
                                }
                            }
                        }
                    }
                }
                if free {
                    grid[(c[2] * nc[1] + c[1]) * nc[0] + c[0]].push(i as u32);
                    centres[i] = x;
                    placed = true;
                    break;
                }
            }
            if !placed {
                return Err(MpcdError::Invalid(format!(
                    "could not place colloid {i} of {n} without overlap in {MAX_PLACEMENT_TRIALS} trials: lower the number of colloids or enlarge the region"
                )));
            }
        }
        Self::new_mixture(params, mixture, sbox, &centres, kt, seed)
    }

    /// Colloids of one species in a saved state; see [`Self::from_state_mixture`].
    pub fn from_state(
        params: ColloidParams,
        sbox: SimBox,
        state: &ColloidState,
    ) -> Result<Self, MpcdError> {
        let one = Mixture::one(params.diameter, state.centre_pos.len());
        Self::from_state_mixture(params, &one, sbox, state)
    }

    /// Colloids of `mixture` in a saved state (see [`ColloidState`]); its species counts must
    /// be the mixture's.
    pub fn from_state_mixture(
        params: ColloidParams,
        mixture: &Mixture,
        sbox: SimBox,
        state: &ColloidState,
    ) -> Result<Self, MpcdError> {
        params.check()?;
        if state.species_counts != mixture.counts {
            return Err(MpcdError::Invalid(format!(
                "colloid state: species of {:?} colloids, but the run has {:?}",
                state.species_counts, mixture.counts
            )));
        }
        let mut me = Self::empty(params, mixture, sbox)?;
        let n = me.len();
        let nv = me.vertex_pos.len();
        if state.centre_pos.len() != n
            || state.centre_vel.len() != n
            || state.centre_image.len() != n
            || state.vertex_pos.len() != nv
            || state.vertex_vel.len() != nv
        {
            return Err(MpcdError::Invalid(format!(
                "colloid state: {n} centres need {n} positions, velocities and images and {nv} vertex positions and velocities (got {}, {}, {}, {}, {})",
                state.centre_pos.len(),
                state.centre_vel.len(),
                state.centre_image.len(),
                state.vertex_pos.len(),
                state.vertex_vel.len()
            )));
        }
        me.centre_pos.copy_from_slice(&state.centre_pos);
        me.centre_vel.copy_from_slice(&state.centre_vel);
        me.centre_image.copy_from_slice(&state.centre_image);
        me.vertex_pos.copy_from_slice(&state.vertex_pos);
        me.vertex_vel.copy_from_slice(&state.vertex_vel);
        me.step = state.step;
        if let Some(i) = me.first_non_finite() {
            return Err(MpcdError::NonFinite {
                step: me.step,
                what: "colloid",
                index: i,
            });
        }
        Ok(me)
    }

    /// The state, exactly (for checkpoints).
    pub fn state(&self) -> ColloidState {
        ColloidState {
            centre_pos: self.centre_pos.clone(),
            centre_vel: self.centre_vel.clone(),
            centre_image: self.centre_image.clone(),
            vertex_pos: self.vertex_pos.clone(),
            vertex_vel: self.vertex_vel.clone(),
            step: self.step,
            species_counts: self.mixture.counts.clone(),
        }
    }

    /// The shells and storage of `mixture`'s colloids; `params.diameter` must be its smallest
    /// diameter (the species of frequency 2, [`Geometry::frequency_for`]).
    fn empty(params: ColloidParams, mixture: &Mixture, sbox: SimBox) -> Result<Self, MpcdError> {
        if mixture
            .diameters
            .iter()
            .any(|d| !(d.is_finite() && *d > 0.0))
        {
            return Err(MpcdError::Invalid(format!(
                "colloid diameters {:?} must be finite numbers > 0",
                mixture.diameters
            )));
        }
        if params.diameter != mixture.d_min() {
            return Err(MpcdError::Invalid(format!(
                "colloid diameter {} must be the smallest species diameter {}",
                params.diameter,
                mixture.d_min()
            )));
        }
        let cut = 2f64.powf(1.0 / 6.0) * mixture.d_max();
        if let Some(k) = (0..3).find(|&k| sbox.l[k] <= 2.0 * cut) {
            return Err(MpcdError::Invalid(format!(
                "box edge {} must exceed twice the WCA cut-off 2^(1/6) d = {cut} (colloid diameter {})",
                sbox.l[k],
                mixture.d_max()
            )));
        }
        let mut shells = Vec::with_capacity(mixture.len());
        let (mut first, mut first_vertex) = (0, 0);
        for (s, (&d, &count)) in mixture.diameters.iter().zip(&mixture.counts).enumerate() {
            let frequency = Geometry::frequency_for(d, params.diameter);
            if frequency > MAX_FREQUENCY {
                return Err(MpcdError::Invalid(format!(
                    "colloid species {} of diameter {d} is {:.4} times the smallest ({}): its shell would need frequency {frequency}, at most {MAX_FREQUENCY} ({} vertices; a size ratio up to {})",
                    mixture.names[s],
                    d / params.diameter,
                    params.diameter,
                    Geometry::vertex_count(MAX_FREQUENCY),
                    (MAX_FREQUENCY as f64 + 0.5) / 2.0
                )));
            }
            let geo = Geometry::geodesic(frequency);
            let r = 0.5 * d;
            let shape: Vec<[f64; 3]> = geo.vertices.iter().map(|v| v.map(|x| r * x)).collect();
            let edges = geo
                .edges
                .iter()
                .map(|&[i, j]| {
                    let (a, b) = (shape[i], shape[j]);
                    let r0 =
                        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2))
                            .sqrt();
                    Edge { i, j, r0 }
                })
                .collect();
            let vertices = shape.len();
            shells.push(Shell {
                diameter: d,
                vertices,
                shape,
                edges,
                spoke: r,
                first,
                count,
                first_vertex,
            });
            first += count;
            first_vertex += count * vertices;
        }
        let n = first;
        let mut species = Vec::with_capacity(n);
        let mut vertex_start = Vec::with_capacity(n + 1);
        for (s, sh) in shells.iter().enumerate() {
            for k in 0..sh.count {
                species.push(s as u32);
                vertex_start.push(sh.first_vertex + k * sh.vertices);
            }
        }
        vertex_start.push(first_vertex);
        let ns = mixture.len();
        let pairs: Vec<LjParams> = (0..ns)
            .flat_map(|a| (a..ns).map(move |b| (a, b)))
            .map(|(a, b)| {
                let sigma = 0.5 * (mixture.diameters[a] + mixture.diameters[b]);
                LjParams {
                    epsilon: params.wca_epsilon,
                    sigma,
                    r_cut: 2f64.powf(1.0 / 6.0) * sigma,
                }
            })
            .collect();
        // Cells at least the cut-off wide; fewer than 3 per axis: all pairs.
        let nc = grid_cells(sbox.l, cut, n, 0);
        let cells = if nc.iter().all(|&c| c >= 3) && n > 1 {
            nc
        } else {
            [0; 3]
        };
        let n_cells = cells[0] * cells[1] * cells[2];
        Ok(Self {
            params,
            mixture: mixture.clone(),
            sbox,
            shells,
            species,
            vertex_start,
            wca: LennardJones::new(ns, &pairs),
            cut_max: cut,
            centre_pos: vec![[0.0; 3]; n],
            centre_vel: vec![[0.0; 3]; n],
            centre_image: vec![[0; 3]; n],
            centre_force: vec![[0.0; 3]; n],
            vertex_pos: vec![[0.0; 3]; first_vertex],
            vertex_vel: vec![[0.0; 3]; first_vertex],
            vertex_force: vec![[0.0; 3]; first_vertex],
            vertex_mass: vec![params.vertex_mass; first_vertex],
            cells,
            cell_start: vec![0; n_cells + 1],
            cell_members: vec![0; if n_cells > 0 { n } else { 0 }],
            cell_of: vec![0; if n_cells > 0 { n } else { 0 }],
            step: 0,
        })
    }

    /// Parameters.
    pub fn params(&self) -> &ColloidParams {
        &self.params
    }

    /// The species (diameters and counts).
    pub fn mixture(&self) -> &Mixture {
        &self.mixture
    }

    /// Species of each colloid.
    pub fn species(&self) -> &[u32] {
        &self.species
    }

    /// Diameter of each colloid.
    pub fn diameters(&self) -> Vec<f64> {
        self.mixture.particle_diameters()
    }

    /// Vertices of a colloid of species `s`.
    pub fn vertices_of_species(&self, s: usize) -> usize {
        self.shells[s].vertices
    }

    /// The vertices of colloid `i` (indices into [`Self::vertex_positions`]).
    pub fn vertex_range(&self, i: usize) -> std::ops::Range<usize> {
        self.vertex_start[i]..self.vertex_start[i + 1]
    }

    /// Every particle of the colloids (centres and vertices).
    pub fn particle_count(&self) -> usize {
        self.len() + self.vertex_pos.len()
    }

    /// Number of colloids.
    pub fn len(&self) -> usize {
        self.centre_pos.len()
    }

    /// No colloids?
    pub fn is_empty(&self) -> bool {
        self.centre_pos.is_empty()
    }

    /// MD blocks (collision times) done.
    pub fn step(&self) -> u64 {
        self.step
    }

    /// Rest lengths of the mesh bonds of the first species (120 for its 42 vertices; the
    /// spokes have `d/2`).
    pub fn rest_lengths(&self) -> Vec<f64> {
        self.shells[0].edges.iter().map(|e| e.r0).collect()
    }

    /// Centre positions in the box.
    pub fn centre_positions(&self) -> &[[f64; 3]] {
        &self.centre_pos
    }

    /// Unwrapped centre positions (position plus image times the box edges).
    pub fn unwrapped_centres(&self) -> Vec<[f64; 3]> {
        self.centre_pos
            .iter()
            .zip(&self.centre_image)
            .map(|(x, i)| self.sbox.unwrap(*x, *i))
            .collect()
    }

    /// Centre velocities.
    pub fn centre_velocities(&self) -> &[[f64; 3]] {
        &self.centre_vel
    }

    /// Vertex positions (colloid by colloid, unwrapped about their centre).
    pub fn vertex_positions(&self) -> &[[f64; 3]] {
        &self.vertex_pos
    }

    /// The forces at the current positions at time `t` (bonds on all particles, WCA and
    /// `external` on the centres), the centres' then the vertices' (colloid by colloid);
    /// computed on a copy, for readers (Python's engines), not in the time step.
    pub fn forces_at<E: External>(&self, t: f64, external: &E) -> Vec<[f64; 3]> {
        let mut copy = self.clone();
        copy.compute_forces(t, external);
        let mut f = copy.centre_force;
        f.extend_from_slice(&copy.vertex_force);
        f
    }

    /// Vertex velocities.
    pub fn vertex_velocities(&self) -> &[[f64; 3]] {
        &self.vertex_vel
    }

    /// The vertices as embedded particles of a collision ([`Srd::collide`]): positions,
    /// velocities (replaced by the collision) and masses, borrowed (no copy). The centres do
    /// not join the collisions (the paper's model).
    pub fn embedded(&mut self) -> Embedded<'_> {
        Embedded {
            pos: &self.vertex_pos,
            vel: &mut self.vertex_vel,
            mass: &self.vertex_mass,
        }
    }

    /// Centre-of-mass velocity of each colloid (centre and vertices, mass-weighted).
    pub fn com_velocities(&self) -> Vec<[f64; 3]> {
        let mut out = Vec::with_capacity(self.len());
        self.com_velocities_into(&mut out);
        out
    }

    /// Mass of colloid `i`.
    fn mass_of(&self, i: usize) -> f64 {
        self.shells[self.species[i] as usize].mass(&self.params)
    }

    /// [`Self::com_velocities`] into `out` (cleared first), for callers that sample every
    /// collision without allocating.
    pub fn com_velocities_into(&self, out: &mut Vec<[f64; 3]>) {
        let (mc, mv) = (self.params.centre_mass, self.params.vertex_mass);
        out.clear();
        out.extend((0..self.len()).map(|i| {
            let mut p = self.centre_vel[i].map(|x| mc * x);
            for v in &self.vertex_vel[self.vertex_range(i)] {
                for k in 0..3 {
                    p[k] += mv * v[k];
                }
            }
            let m = self.mass_of(i);
            p.map(|x| x / m)
        }));
    }

    /// Total momentum of all colloid particles (summed in index order).
    pub fn momentum(&self) -> [f64; 3] {
        let (mc, mv) = (self.params.centre_mass, self.params.vertex_mass);
        let mut p = [0.0; 3];
        for v in &self.centre_vel {
            for k in 0..3 {
                p[k] += mc * v[k];
            }
        }
        for v in &self.vertex_vel {
            for k in 0..3 {
                p[k] += mv * v[k];
            }
        }
        p
    }

    /// Kinetic energy of all colloid particles.
    pub fn kinetic_energy(&self) -> f64 {
        let sq = |v: &[f64; 3]| v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        0.5 * self.params.centre_mass * self.centre_vel.iter().map(sq).sum::<f64>()
            + 0.5 * self.params.vertex_mass * self.vertex_vel.iter().map(sq).sum::<f64>()
    }

    /// Potential energy: bonds and WCA between centres (no external field; a diagnostic, the
    /// WCA part by all pairs, O(N^2)).
    pub fn potential_energy(&self) -> f64 {
        let k = self.params.bond_k;
        let mut u = 0.0;
        for i in 0..self.len() {
            let sh = &self.shells[self.species[i] as usize];
            let (c, vs) = (self.centre_pos[i], &self.vertex_pos[self.vertex_range(i)]);
            for e in &sh.edges {
                let r = dist(vs[e.i], vs[e.j]);
                u += 0.5 * k * (r - e.r0).powi(2);
            }
            for v in vs {
                u += 0.5 * k * (dist(*v, c) - sh.spoke).powi(2);
            }
            for j in i + 1..self.len() {
                let y = self.centre_pos[j];
                let d = self.sbox.min_image([c[0] - y[0], c[1] - y[1], c[2] - y[2]]);
                u += self.wca.energy(
                    d[0] * d[0] + d[1] * d[1] + d[2] * d[2],
                    self.species[i],
                    self.species[j],
                    0.0,
                    0.0,
                );
            }
        }
        u
    }

    /// Kinetic temperature of all colloid particles, `sum m v^2 / (3 N_particles)`.
    pub fn temperature(&self) -> f64 {
        2.0 * self.kinetic_energy() / (3.0 * self.particle_count() as f64)
    }

    /// Kinetic temperature of the colloids' centre-of-mass velocities, `sum M V^2 / (3 N)`.
    pub fn com_temperature(&self) -> f64 {
        let v = self.com_velocities();
        v.iter()
            .enumerate()
            .map(|(i, v)| self.mass_of(i) * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]))
            .sum::<f64>()
            / (3.0 * self.len() as f64)
    }

    /// Root-mean-square relative deviation `(r - r0) / r0` over all bonds (mesh and spokes).
    pub fn bond_strain_rms(&self) -> f64 {
        let (mut s, mut bonds) = (0.0, 0usize);
        for i in 0..self.len() {
            let sh = &self.shells[self.species[i] as usize];
            let (c, vs) = (self.centre_pos[i], &self.vertex_pos[self.vertex_range(i)]);
            for e in &sh.edges {
                s += (dist(vs[e.i], vs[e.j]) / e.r0 - 1.0).powi(2);
            }
            for v in vs {
                s += (dist(*v, c) / sh.spoke - 1.0).powi(2);
            }
            bonds += sh.edges.len() + sh.vertices;
        }
        (s / bonds as f64).sqrt()
    }

    /// Velocity Verlet over one collision time: `md_steps` steps of `dt = tau / md_steps` from
    /// time `t0`, forces from the bonds, WCA between centres and `external` on the centres
    /// (e.g. the droplet's [`HarmonicInterface`](crate::potential::HarmonicInterface) or, for
    /// several sizes, its [`SpeciesInterface`]: `External::force_on` with each colloid's
    /// diameter, evaluated at the time of each force evaluation); a colloid whose centre a drift
    /// leaves beyond a hard wall of `external` (`External::overshoot`) is reflected whole, in
    /// the frame of the moving wall. The forces at `t0` are recomputed from the positions, so
    /// the state is the positions and velocities alone. Advances the step counter.
    pub fn advance<E: External>(
        &mut self,
        t0: f64,
        tau: f64,
        external: &E,
    ) -> Result<(), MpcdError> {
        if self.is_empty() {
            self.step += 1;
            return Ok(());
        }
        let steps = self.params.md_steps;
        let dt = tau / steps as f64;
        let (hc, hv) = (
            0.5 * dt / self.params.centre_mass,
            0.5 * dt / self.params.vertex_mass,
        );
        self.compute_forces(t0, external);
        for s in 0..steps {
            let sbox = self.sbox;
            // The end of this drift, where a hard wall of `external` reflects a centre.
            let t = t0 + (s + 1) as f64 * dt;
            let wall_speed = external.wall_speed(t);
            let masses = (self.params.centre_mass, self.params.vertex_mass);
            for sh in &self.shells {
                let (c, v) = (
                    sh.first..sh.first + sh.count,
                    sh.first_vertex..sh.first_vertex + sh.count * sh.vertices,
                );
                let diameter = sh.diameter;
                self.centre_pos[c.clone()]
                    .par_iter_mut()
                    .zip(self.centre_vel[c.clone()].par_iter_mut())
                    .zip(self.centre_image[c.clone()].par_iter_mut())
                    .zip(self.centre_force[c].par_iter())
                    .zip(self.vertex_pos[v.clone()].par_chunks_mut(sh.vertices))
                    .zip(self.vertex_vel[v.clone()].par_chunks_mut(sh.vertices))
                    .zip(self.vertex_force[v].par_chunks(sh.vertices))
                    .for_each(|((((((x, v), image), f), xs), vs), fs)| {
                        kick_drift(x, v, f, hc, dt);
                        for ((x, v), f) in xs.iter_mut().zip(vs.iter_mut()).zip(fs) {
                            kick_drift(x, v, f, hv, dt);
                        }
                        if let Some((over, n)) = external.overshoot(*x, t, diameter) {
                            let colloid = Body {
                                x,
                                v,
                                xs: &mut *xs,
                                vs: &mut *vs,
                            };
                            colloid.reflect_at_wall(over, n, wall_speed, masses);
                        }
                        // Wrap the whole colloid with its centre.
                        let before = *x;
                        sbox.wrap(x, image);
                        let shift = [x[0] - before[0], x[1] - before[1], x[2] - before[2]];
                        if shift != [0.0; 3] {
                            for y in xs.iter_mut() {
                                for k in 0..3 {
                                    y[k] += shift[k];
                                }
                            }
                        }
                    });
            }
            self.compute_forces(t, external);
            for sh in &self.shells {
                let (c, v) = (
                    sh.first..sh.first + sh.count,
                    sh.first_vertex..sh.first_vertex + sh.count * sh.vertices,
                );
                self.centre_vel[c.clone()]
                    .par_iter_mut()
                    .zip(self.centre_force[c].par_iter())
                    .zip(self.vertex_vel[v.clone()].par_chunks_mut(sh.vertices))
                    .zip(self.vertex_force[v].par_chunks(sh.vertices))
                    .for_each(|(((v, f), vs), fs)| {
                        kick(v, f, hc);
                        for (v, f) in vs.iter_mut().zip(fs) {
                            kick(v, f, hv);
                        }
                    });
            }
        }
        self.step += 1;
        if let Some(i) = self.first_non_finite() {
            return Err(MpcdError::NonFinite {
                step: self.step,
                what: "colloid",
                index: i,
            });
        }
        Ok(())
    }

    /// The lowest colloid index with a non-finite position or velocity.
    fn first_non_finite(&self) -> Option<usize> {
        let bad = |x: &[f64; 3]| !(x[0].is_finite() && x[1].is_finite() && x[2].is_finite());
        (0..self.len()).into_par_iter().find_first(|&i| {
            let v = self.vertex_range(i);
            bad(&self.centre_pos[i])
                || bad(&self.centre_vel[i])
                || self.vertex_pos[v.clone()]
                    .iter()
                    .chain(&self.vertex_vel[v])
                    .any(bad)
        })
    }

    /// Sort the centres into the cells (index order within a cell).
    fn build_cells(&mut self) {
        let nc = self.cells;
        let l = self.sbox.l;
        self.cell_start.fill(0);
        for (i, x) in self.centre_pos.iter().enumerate() {
            let c: [usize; 3] = std::array::from_fn(|k| {
                let u = (x[k] / l[k] + 0.5) * nc[k] as f64;
                // Non-finite positions land in cell 0 (caught after the block).
                (if u.is_finite() {
                    u.max(0.0) as usize
                } else {
                    0
                })
                .min(nc[k] - 1)
            });
            let cell = (c[2] * nc[1] + c[1]) * nc[0] + c[0];
            self.cell_of[i] = cell as u32;
            self.cell_start[cell + 1] += 1;
        }
        for c in 0..nc[0] * nc[1] * nc[2] {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        // Fill in index order, using the starts as cursors, then restore them.
        for i in 0..self.len() {
            let c = self.cell_of[i] as usize;
            self.cell_members[self.cell_start[c] as usize] = i as u32;
            self.cell_start[c] += 1;
        }
        for c in (1..=nc[0] * nc[1] * nc[2]).rev() {
            self.cell_start[c] = self.cell_start[c - 1];
        }
        self.cell_start[0] = 0;
    }

    /// Forces at time `t`: bonds on all particles, WCA and `external` on the centres (each
    /// with its colloid's diameter, `External::force_on`).
    fn compute_forces<E: External>(&mut self, t: f64, external: &E) {
        let wca_on = self.params.wca_epsilon > 0.0 && self.len() > 1;
        if wca_on && self.cells[0] > 0 {
            self.build_cells();
        }
        let k = self.params.bond_k;
        let (sbox, wca, rc2) = (self.sbox, &self.wca, self.cut_max.powi(2));
        let (centres, species) = (&self.centre_pos, &self.species);
        let (nc, start, members) = (self.cells, &self.cell_start, &self.cell_members);
        let n = centres.len();
        for sh in &self.shells {
            let (c, v) = (
                sh.first..sh.first + sh.count,
                sh.first_vertex..sh.first_vertex + sh.count * sh.vertices,
            );
            let (edges, spoke, diameter) = (&sh.edges, sh.spoke, sh.diameter);
            self.centre_force[c]
                .par_iter_mut()
                .zip(self.vertex_force[v.clone()].par_chunks_mut(sh.vertices))
                .zip(self.vertex_pos[v].par_chunks(sh.vertices))
                .enumerate()
                .for_each(|(m, ((fc, fs), xs))| {
                    let i = sh.first + m;
                    let c = centres[i];
                    let ti = species[i];
                    fs.fill([0.0; 3]);
                    let mut f = external.force_on(c, t, diameter);
                    for e in edges {
                        let (a, b) = (xs[e.i], xs[e.j]);
                        let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                        // Force on a: k (r - r0) d / r (pulled towards b when stretched).
                        let g = k * (r - e.r0) / r;
                        for q in 0..3 {
                            fs[e.i][q] += g * d[q];
                            fs[e.j][q] -= g * d[q];
                        }
                    }
                    for (fv, x) in fs.iter_mut().zip(xs) {
                        let d = [c[0] - x[0], c[1] - x[1], c[2] - x[2]];
                        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                        let g = k * (r - spoke) / r;
                        for q in 0..3 {
                            fv[q] += g * d[q];
                            f[q] -= g * d[q];
                        }
                    }
                    if wca_on {
                        let mut pair = |j: usize| {
                            if j == i {
                                return;
                            }
                            let y = centres[j];
                            let d = sbox.min_image([c[0] - y[0], c[1] - y[1], c[2] - y[2]]);
                            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                            if r2 < rc2 {
                                // Zero beyond the pair's own cut-off.
                                let g = wca.force_over_r(r2, ti, species[j], 0.0, 0.0);
                                for q in 0..3 {
                                    f[q] += g * d[q];
                                }
                            }
                        };
                        if nc[0] == 0 {
                            (0..n).for_each(&mut pair);
                        } else {
                            let l = sbox.l;
                            let own: [i64; 3] = std::array::from_fn(|q| {
                                let u = (c[q] / l[q] + 0.5) * nc[q] as f64;
                                (if u.is_finite() {
                                    u.max(0.0) as usize
                                } else {
                                    0
                                })
                                .min(nc[q] - 1) as i64
                            });
                            for dz in -1..=1 {
                                for dy in -1..=1 {
                                    for dx in -1..=1 {
                                        let o = [dx, dy, dz];
                                        let cc: [usize; 3] = std::array::from_fn(|q| {
                                            (own[q] + o[q]).rem_euclid(nc[q] as i64) as usize
                                        });
                                        let cell = (cc[2] * nc[1] + cc[1]) * nc[0] + cc[0];
                                        for &j in
                                            &members[start[cell] as usize..start[cell + 1] as usize]
                                        {
                                            pair(j as usize);
                                        }
                                    }
                                }
                            }
                        }
                    }
                    *fc = f;
                });
        }
    }
}

#[inline(always)]
fn kick_drift(x: &mut [f64; 3], v: &mut [f64; 3], f: &[f64; 3], half_dt_over_m: f64, dt: f64) {
    for k in 0..3 {
        v[k] += half_dt_over_m * f[k];
        x[k] += dt * v[k];
    }
}

/// One colloid's centre and shell, lent for a reflection.
struct Body<'a> {
    x: &'a mut [f64; 3],
    v: &'a mut [f64; 3],
    xs: &'a mut [[f64; 3]],
    vs: &'a mut [[f64; 3]],
}

impl Body<'_> {
    /// The colloid whose centre lies `over` beyond a hard wall of outward normal `n` moving at
    /// `wall_speed` along it, reflected as a rigid body by an infinitely massive wall: every
    /// particle moved by `-2 over n` and given the same velocity change, which reverses the
    /// centre of mass's normal velocity in the wall's frame, `V.n -> 2 w - V.n` (elastic:
    /// the bonds are untouched and, at rest, the kinetic energy is kept). A colloid already
    /// moving in faster than the wall is only moved back. `masses`: centre and vertex.
    #[inline]
    fn reflect_at_wall(self, over: f64, n: [f64; 3], wall_speed: f64, masses: (f64, f64)) {
        let (mc, mv) = masses;
        let mut p = [mc * self.v[0], mc * self.v[1], mc * self.v[2]];
        for u in self.vs.iter() {
            for k in 0..3 {
                p[k] += mv * u[k];
            }
        }
        let m = mc + self.vs.len() as f64 * mv;
        let vn = (p[0] * n[0] + p[1] * n[1] + p[2] * n[2]) / m;
        let dv = 2.0 * (vn - wall_speed).max(0.0);
        let (dx, dv) = (n.map(|c| -2.0 * over * c), n.map(|c| -dv * c));
        for (y, u) in std::iter::once((&mut *self.x, &mut *self.v))
            .chain(self.xs.iter_mut().zip(self.vs.iter_mut()))
        {
            for k in 0..3 {
                y[k] += dx[k];
                u[k] += dv[k];
            }
        }
    }
}

#[inline(always)]
fn kick(v: &mut [f64; 3], f: &[f64; 3], half_dt_over_m: f64) {
    for k in 0..3 {
        v[k] += half_dt_over_m * f[k];
    }
}

#[inline(always)]
fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The rotation matrix of the unit quaternion `(w, x, y, z)`.
fn rotation_of(q: [f64; 4]) -> [[f64; 3]; 3] {
    let [w, x, y, z] = q;
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

fn apply(r: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2])
}

/// What one coupled step did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepStats {
    /// The solvent's streaming.
    pub stream: StreamStats,
    /// The collision.
    pub collision: CollisionStats,
}

/// The solvent and its colloids, advanced together one collision time at a time:
/// stream the solvent, move the colloids by MD over the same interval, collide (solvent and
/// vertices). Time is `srd.step() * tau`.
#[derive(Debug)]
pub struct MpcdSystem {
    /// The solvent.
    pub srd: Srd,
    /// The colloids.
    pub colloids: DiscreteColloids,
    /// Walls of the solvent.
    pub confinement: Confinement,
    /// The droplet's interface on the colloid centres, if any (placed for the smallest
    /// colloids, met by each at its own size).
    pub interface: Option<SpeciesInterface>,
}

impl MpcdSystem {
    /// Solvent and colloids in the same box, at the same step.
    pub fn new(
        srd: Srd,
        colloids: DiscreteColloids,
        confinement: Confinement,
        interface: Option<SpeciesInterface>,
    ) -> Result<Self, MpcdError> {
        if srd.sbox() != &colloids.sbox {
            return Err(MpcdError::Invalid(format!(
                "solvent box {:?} and colloid box {:?} differ",
                srd.sbox().l,
                colloids.sbox.l
            )));
        }
        if srd.step() != colloids.step() {
            return Err(MpcdError::Invalid(format!(
                "solvent at step {} but colloids at step {}",
                srd.step(),
                colloids.step()
            )));
        }
        Ok(Self {
            srd,
            colloids,
            confinement,
            interface,
        })
    }

    /// Time at the start of the next step.
    pub fn time(&self) -> f64 {
        self.srd.step() as f64 * self.srd.params().tau
    }

    /// First half of a step: stream the solvent from `time()` to `time() + tau` (driven by
    /// `accel`) and move the colloids over the same interval. The caller may then act on the
    /// streamed solvent (e.g. [`Srd::remove`] some of [`Srd::bounced`]) before
    /// [`Self::collide`].
    pub fn stream_and_move(&mut self, accel: &Acceleration) -> Result<StreamStats, MpcdError> {
        let tau = self.srd.params().tau;
        let t0 = self.time();
        let st = self.srd.stream(t0 + tau, &self.confinement, accel)?;
        match &self.interface {
            Some(w) => self.colloids.advance(t0, tau, w)?,
            None => self.colloids.advance(t0, tau, &NoExternal)?,
        }
        Ok(st)
    }

    /// Second half: the collision at the end of the streaming step, the vertices embedded.
    pub fn collide(&mut self) -> CollisionStats {
        let t = (self.srd.step() + 1) as f64 * self.srd.params().tau;
        let emb = self.colloids.embedded();
        self.srd.collide(t, &self.confinement, Some(emb))
    }

    /// One whole step: [`Self::stream_and_move`] then [`Self::collide`].
    pub fn step(&mut self, accel: &Acceleration) -> Result<StepStats, MpcdError> {
        let stream = self.stream_and_move(accel)?;
        let collision = self.collide();
        Ok(StepStats { stream, collision })
    }

    /// Total momentum of solvent and colloids.
    pub fn momentum(&self) -> [f64; 3] {
        let (a, b) = (self.srd.momentum(), self.colloids.momentum());
        [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mpcd::SrdParams;
    use crate::potential::HarmonicInterface;

    /// A periodic cube of edge `l` with standard solvent and `n` random colloids of diameter `d`.
    fn system(l: f64, d: f64, n: usize, thermostat: bool, seed: u32) -> MpcdSystem {
        let mut p = SrdParams::standard(seed);
        p.thermostat = thermostat;
        let sbox = SimBox::cube(l);
        let srd = Srd::new(p, sbox, &Confinement::None, 0.0).unwrap();
        let c = DiscreteColloids::random(
            ColloidParams::standard(d, p.kt),
            sbox,
            n,
            Region::Box,
            p.kt,
            seed,
        )
        .unwrap();
        MpcdSystem::new(srd, c, Confinement::None, None).unwrap()
    }

    fn bits(v: &[[f64; 3]]) -> Vec<[u64; 3]> {
        v.iter().map(|x| x.map(f64::to_bits)).collect()
    }

    #[test]
    fn the_subdivided_icosahedron_has_42_vertices_and_120_nearest_neighbour_edges() {
        let g = Geometry::subdivided_icosahedron();
        assert_eq!(g.vertices.len(), VERTICES);
        assert_eq!(g.edges.len(), EDGES);
        let mut degree = [0usize; VERTICES];
        for &[i, j] in &g.edges {
            assert!(i < j);
            degree[i] += 1;
            degree[j] += 1;
        }
        assert_eq!(degree.iter().filter(|&&k| k == 5).count(), 12);
        assert_eq!(degree.iter().filter(|&&k| k == 6).count(), 30);
        // The edges join nearest neighbours: every edge is shorter than every non-edge.
        let (mut longest_edge, mut shortest_other) = (0f64, f64::INFINITY);
        for i in 0..VERTICES {
            assert!((dist(g.vertices[i], [0.0; 3]) - 1.0).abs() < 1e-15);
            for j in i + 1..VERTICES {
                let r = dist(g.vertices[i], g.vertices[j]);
                if g.edges.contains(&[i, j]) {
                    longest_edge = longest_edge.max(r);
                } else {
                    shortest_other = shortest_other.min(r);
                }
            }
        }
        assert!(
            longest_edge < 0.9 * shortest_other,
            "{longest_edge} {shortest_other}"
        );
        // Built colloids: vertices at d/2 from the centre, the ideal shape free of force.
        let d = 4.0;
        let c = DiscreteColloids::new(
            ColloidParams::standard(d, 1.0),
            SimBox::cube(12.0),
            &[[5.9, -5.9, 0.3], [0.0, 0.0, 0.0]],
            1.0,
            7,
        )
        .unwrap();
        for i in 0..2 {
            for v in &c.vertex_positions()[i * VERTICES..][..VERTICES] {
                let r = dist(*v, c.centre_positions()[i]);
                assert!((r - 0.5 * d).abs() < 1e-12, "{r}");
            }
        }
        for f in c.vertex_force.iter().chain(&c.centre_force) {
            assert!(f.iter().all(|x| x.abs() < 1e-10), "{f:?}");
        }
        // Two lengths of mesh bond (the projected midpoints), both near 0.55 d/2.
        let r0 = c.rest_lengths();
        let (lo, hi) = r0
            .iter()
            .fold((f64::INFINITY, 0f64), |(a, b), &r| (a.min(r), b.max(r)));
        assert!(lo > 0.5 * 0.5 * d && hi < 0.65 * 0.5 * d, "{lo} {hi}");
    }

    #[test]
    fn parameters_out_of_range_are_rejected_naming_the_key_and_range() {
        let ok = ColloidParams::standard(3.0, 1.0);
        let sbox = SimBox::cube(10.0);
        let msg = |p: ColloidParams| {
            DiscreteColloids::new(p, sbox, &[[0.0; 3]], 1.0, 1)
                .unwrap_err()
                .to_string()
        };
        for (key, bad) in [
            (
                "colloid diameter",
                ColloidParams {
                    diameter: 0.0,
                    ..ok
                },
            ),
            (
                "colloid diameter",
                ColloidParams {
                    diameter: f64::NAN,
                    ..ok
                },
            ),
            (
                "colloid vertex_mass",
                ColloidParams {
                    vertex_mass: -1.0,
                    ..ok
                },
            ),
            (
                "colloid centre_mass",
                ColloidParams {
                    centre_mass: 0.0,
                    ..ok
                },
            ),
            (
                "bond k",
                ColloidParams {
                    bond_k: f64::INFINITY,
                    ..ok
                },
            ),
        ] {
            let m = msg(bad);
            assert!(m.contains(&format!("{key} = ")) && m.contains("> 0"), "{m}");
        }
        let m = msg(ColloidParams { md_steps: 0, ..ok });
        assert!(
            m.contains("md_steps = 0") && m.contains("1..=100000"),
            "{m}"
        );
        let m = msg(ColloidParams {
            wca_epsilon: -1.0,
            ..ok
        });
        assert!(
            m.contains("colloid wca_epsilon") && m.contains(">= 0"),
            "{m}"
        );
        // A box too small for the WCA cut-off, a bad kT, a non-finite centre.
        let m = DiscreteColloids::new(ok, SimBox::cube(6.5), &[[0.0; 3]], 1.0, 1)
            .unwrap_err()
            .to_string();
        assert!(
            m.contains("box edge 6.5") && m.contains("twice the WCA cut-off"),
            "{m}"
        );
        let m = DiscreteColloids::new(ok, sbox, &[[0.0; 3]], 0.0, 1)
            .unwrap_err()
            .to_string();
        assert!(m.contains("colloid kT = 0"), "{m}");
        let e =
            DiscreteColloids::new(ok, sbox, &[[0.0; 3], [f64::NAN, 0.0, 0.0]], 1.0, 1).unwrap_err();
        assert_eq!(
            e,
            MpcdError::NonFinite {
                step: 0,
                what: "colloid",
                index: 1
            }
        );
        let m = DiscreteColloids::random(ok, sbox, 3, Region::Sphere { radius: 1.0 }, 1.0, 1)
            .unwrap_err()
            .to_string();
        assert!(
            m.contains("placement radius = 1") && m.contains("(1.5, 5]"),
            "{m}"
        );
        // Too many colloids for the region.
        let m = DiscreteColloids::random(ok, sbox, 200, Region::Box, 1.0, 1)
            .unwrap_err()
            .to_string();
        assert!(m.contains("could not place colloid"), "{m}");
    }

    /// A stiff spring with one Verlet step per collision time blows up; the error names the
    /// step and the colloid.
    #[test]
    fn a_blown_up_colloid_is_reported_with_its_step_and_index() {
        let p = ColloidParams {
            bond_k: 1e7,
            md_steps: 1,
            ..ColloidParams::standard(3.0, 1.0)
        };
        let mut c =
            DiscreteColloids::new(p, SimBox::cube(10.0), &[[0.0; 3], [4.0, 0.0, 0.0]], 1.0, 3)
                .unwrap();
        let mut err = None;
        for _ in 0..1000 {
            if let Err(e) = c.advance(0.0, 0.1, &NoExternal) {
                err = Some(e);
                break;
            }
        }
        match err {
            Some(MpcdError::NonFinite { step, what, index }) => {
                assert_eq!(what, "colloid");
                assert!(step >= 1 && index < 2, "{step} {index}");
            }
            e => panic!("{e:?}"),
        }
    }

    /// Random placement: no two centres closer than d (periodic), all inside the sphere,
    /// the same configuration for the same seed.
    #[test]
    fn the_highest_bond_frequency_is_that_of_a_full_diagonalisation() {
        // Reference: numpy.linalg.eigvalsh of M^(-1/2) H M^(-1/2) for the same mesh, k = 1.
        for (vertex_mass, centre_mass, omega) in [
            (5.0, 5.0, 1.7357901671408973),
            (1.0, 100.0, 2.2646890118825485),
            (100.0, 1.0, 3.742994302345232),
            (5.0, 0.01, 37.41924672390337),
        ] {
            let p = ColloidParams {
                bond_k: 1.0,
                vertex_mass,
                centre_mass,
                ..ColloidParams::standard(4.0, 1.0)
            };
            let got = p.highest_bond_frequency();
            assert!(
                (got / omega - 1.0).abs() < 1e-6,
                "{vertex_mass} {centre_mass}: {got}"
            );
        }
        // omega scales as sqrt(k) and does not depend on d.
        let p = ColloidParams::standard(0.7, 1.0);
        assert!(
            (p.highest_bond_frequency() / (1.7357901671408973 * 5000f64.sqrt()) - 1.0).abs() < 1e-6
        );
    }

    #[test]
    fn grids_over_the_colloids_stay_small_for_any_diameter() {
        let l = [10.0; 3];
        // A tiny or vanishing width: no more cells than the cap, at least `min` per axis.
        for width in [1e-300, 0.0, f64::NAN, 1e-6] {
            let nc = grid_cells(l, width, 1, 1);
            assert!(nc.iter().all(|&c| (1..=32).contains(&c)), "{width}: {nc:?}");
        }
        assert_eq!(grid_cells(l, 4.0, 1, 1), [2; 3]);
        assert_eq!(grid_cells(l, 20.0, 1, 1), [1; 3]);
        assert_eq!(grid_cells(l, 20.0, 1, 0), [0; 3]);
        assert_eq!(grid_cells([1e6; 3], 1.0, 1_000_000, 0), [200; 3]);
    }

    /// One colloid of diameter 1e-300 in a box of 10: a placement grid of 1024^3 cells
    /// (24 GiB, an abort) before the grid was bounded by the number of colloids.
    #[test]
    fn tiny_colloids_are_placed_without_a_huge_grid() {
        let p = ColloidParams::standard(1e-300, 1.0);
        for n in [1, 2] {
            let c =
                DiscreteColloids::random(p, SimBox::cube(10.0), n, Region::Box, 1.0, 3).unwrap();
            assert_eq!(c.len(), n);
        }
    }

    #[test]
    fn random_placement_does_not_overlap_and_stays_in_the_region() {
        let (d, radius) = (2.0, 9.0);
        let p = ColloidParams::standard(d, 1.0);
        let sbox = SimBox::cube(20.0);
        let region = Region::Sphere { radius };
        // 100 colloids of d = 2 in a sphere of radius 8 (centres): phi about 0.2.
        let a = DiscreteColloids::random(p, sbox, 100, region, 1.0, 5).unwrap();
        let b = DiscreteColloids::random(p, sbox, 100, region, 1.0, 5).unwrap();
        assert_eq!(bits(a.centre_positions()), bits(b.centre_positions()));
        assert_eq!(bits(a.vertex_velocities()), bits(b.vertex_velocities()));
        let x = a.centre_positions();
        for i in 0..x.len() {
            let r = dist(x[i], [0.0; 3]);
            assert!(r <= radius - 0.5 * d + 1e-12, "{r}");
            for j in 0..i {
                let s = sbox.min_image([x[i][0] - x[j][0], x[i][1] - x[j][1], x[i][2] - x[j][2]]);
                assert!(dist(s, [0.0; 3]) >= d, "{i} {j}");
            }
        }
        // The colloids' total momentum is removed.
        let m = a.momentum();
        assert!(m.iter().all(|c| c.abs() < 1e-10), "{m:?}");
    }

    /// The WCA forces from the cell list equal the all-pairs sum with minimum images, obey
    /// Newton's third law, and vanish beyond the cut-off.
    #[test]
    fn wca_forces_from_the_cell_list_match_all_pairs() {
        let d = 2.0;
        let p = ColloidParams::standard(d, 1.0);
        let sbox = SimBox::cube(14.0);
        // Close pairs across the periodic boundary and inside.
        let mut c = DiscreteColloids::random(p, sbox, 120, Region::Box, 1.0, 9).unwrap();
        assert!(c.cells[0] >= 3);
        // Push some pairs into range: move every other colloid towards its predecessor.
        let mut x = c.centre_positions().to_vec();
        for i in (1..x.len()).step_by(2) {
            let s = sbox.min_image([
                x[i - 1][0] - x[i][0],
                x[i - 1][1] - x[i][1],
                x[i - 1][2] - x[i][2],
            ]);
            let r = dist(s, [0.0; 3]);
            let target = 0.95 * d + 0.15 * d * (i % 3) as f64;
            for k in 0..3 {
                x[i][k] += s[k] * (1.0 - target / r);
            }
        }
        let mut state = c.state();
        for (i, y) in x.iter().enumerate() {
            let mut y = *y;
            let mut image = [0; 3];
            sbox.wrap(&mut y, &mut image);
            let shift = [
                y[0] - state.centre_pos[i][0],
                y[1] - state.centre_pos[i][1],
                y[2] - state.centre_pos[i][2],
            ];
            state.centre_pos[i] = y;
            for v in &mut state.vertex_pos[i * VERTICES..][..VERTICES] {
                for k in 0..3 {
                    v[k] += shift[k];
                }
            }
        }
        c = DiscreteColloids::from_state(p, sbox, &state).unwrap();
        c.compute_forces(0.0, &NoExternal);
        let wca = LennardJones::wca(1.0, d);
        let x = c.centre_positions();
        let mut pairs = 0;
        let mut total = [0.0; 3];
        for i in 0..x.len() {
            // Bond part: the ideal shape exerts none, so the centre force is WCA alone.
            let mut f = [0.0; 3];
            for j in 0..x.len() {
                if j == i {
                    continue;
                }
                let s = sbox.min_image([x[i][0] - x[j][0], x[i][1] - x[j][1], x[i][2] - x[j][2]]);
                let r2 = s[0] * s[0] + s[1] * s[1] + s[2] * s[2];
                let g = wca.force_over_r(r2, 0, 0, 0.0, 0.0);
                if g != 0.0 {
                    pairs += 1;
                }
                for k in 0..3 {
                    f[k] += g * s[k];
                }
            }
            let got = c.centre_force[i];
            for k in 0..3 {
                assert!(
                    (got[k] - f[k]).abs() < 1e-9 * (1.0 + f[k].abs()),
                    "{i}: {got:?} {f:?}"
                );
                total[k] += got[k];
            }
        }
        assert!(pairs >= 40, "{pairs}");
        // Newton's third law to round-off of the largest forces (close pairs).
        let scale: f64 = c
            .centre_force
            .iter()
            .map(|f| f[0].abs() + f[1].abs() + f[2].abs())
            .sum();
        assert!(
            total.iter().all(|t| t.abs() < 1e-13 * scale),
            "{total:?} {scale}"
        );
    }

    /// An isolated colloid (no solvent): velocity Verlet keeps the energy within a bounded
    /// error of order `dt^2` (a quarter of it at half the step: the integrator's error, not a
    /// force that is not the gradient of the energy) and the momentum exactly.
    #[test]
    fn an_isolated_colloid_conserves_energy_and_momentum() {
        let error = |md_steps: u32| {
            let p = ColloidParams {
                md_steps,
                ..ColloidParams::standard(4.0, 1.0)
            };
            let mut c =
                DiscreteColloids::new(p, SimBox::cube(12.0), &[[1.0, 2.0, 3.0]], 1.0, 4).unwrap();
            let e0 = c.kinetic_energy() + c.potential_energy();
            let p0 = c.momentum();
            let mut spread: f64 = 0.0;
            for _ in 0..200 {
                c.advance(0.0, 0.1, &NoExternal).unwrap();
                let e = c.kinetic_energy() + c.potential_energy();
                spread = spread.max((e - e0).abs());
            }
            let p1 = c.momentum();
            assert!(
                (0..3).all(|k| (p1[k] - p0[k]).abs() < 1e-11),
                "{p0:?} {p1:?}"
            );
            spread
        };
        let (e50, e100) = (error(50), error(100));
        eprintln!("largest energy error over 200 tau: {e50} (50 steps), {e100} (100 steps)");
        // 43 particles started at kT: about 64.5 kT of kinetic energy.
        assert!(e50 < 0.3, "{e50}");
        let ratio = e100 / e50;
        assert!(ratio > 0.15 && ratio < 0.4, "{ratio}");
    }

    /// Without the cell thermostat the total momentum of solvent and colloids is conserved to
    /// round-off, while the colloids' own momentum changes (they exchange momentum with the
    /// solvent).
    #[test]
    fn solvent_and_colloids_conserve_the_total_momentum_without_the_thermostat() {
        let mut sys = system(12.0, 3.0, 6, false, 31);
        let p0 = sys.momentum();
        let c0 = sys.colloids.momentum();
        let mut changed: f64 = 0.0;
        for _ in 0..60 {
            sys.step(&Acceleration::None).unwrap();
            let c = sys.colloids.momentum();
            changed = changed.max((c[0] - c0[0]).abs());
        }
        let p1 = sys.momentum();
        for k in 0..3 {
            assert!((p1[k] - p0[k]).abs() < 1e-10, "{p0:?} {p1:?}");
        }
        assert!(changed > 1.0, "{changed}");
    }

    /// The same run on 1 and on 2 threads gives the same bits (colloids with WCA contacts,
    /// cell list and storage sorts of the solvent).
    #[test]
    fn results_do_not_depend_on_the_thread_count() {
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| {
                    let mut sys = system(14.0, 2.0, 60, true, 17);
                    for _ in 0..12 {
                        sys.step(&Acceleration::None).unwrap();
                    }
                    (
                        sys.srd.raw_positions(),
                        sys.srd.velocities(),
                        sys.colloids.state(),
                    )
                })
        };
        let (a, b) = (on(1), on(2));
        assert_eq!(a.0, b.0);
        assert_eq!(bits(&a.1), bits(&b.1));
        assert_eq!(bits(&a.2.vertex_pos), bits(&b.2.vertex_pos));
        assert_eq!(bits(&a.2.vertex_vel), bits(&b.2.vertex_vel));
        assert_eq!(bits(&a.2.centre_pos), bits(&b.2.centre_pos));
        assert_eq!(bits(&a.2.centre_vel), bits(&b.2.centre_vel));
    }

    /// 2k steps in one go, or k steps, a checkpoint (solvent raw state, colloid state), a
    /// rebuild and k more: the same bits.
    #[test]
    fn a_restart_from_the_state_continues_bitwise() {
        let k = 15;
        let mut one = system(12.0, 3.0, 5, true, 23);
        for _ in 0..2 * k {
            one.step(&Acceleration::None).unwrap();
        }
        let mut first = system(12.0, 3.0, 5, true, 23);
        for _ in 0..k {
            first.step(&Acceleration::None).unwrap();
        }
        let (p, sbox) = (*first.srd.params(), *first.srd.sbox());
        let srd = Srd::from_raw(
            p,
            sbox,
            &first.srd.raw_positions(),
            &first.srd.velocities(),
            first.srd.step(),
        )
        .unwrap();
        let state = first.colloids.state();
        drop(first);
        let colloids =
            DiscreteColloids::from_state(ColloidParams::standard(3.0, 1.0), sbox, &state).unwrap();
        let mut two = MpcdSystem::new(srd, colloids, Confinement::None, None).unwrap();
        for _ in 0..k {
            two.step(&Acceleration::None).unwrap();
        }
        assert_eq!(one.srd.raw_positions(), two.srd.raw_positions());
        assert_eq!(bits(&one.srd.velocities()), bits(&two.srd.velocities()));
        assert_eq!(one.colloids.state(), two.colloids.state());
        let (a, b) = (one.colloids.state(), two.colloids.state());
        assert_eq!(bits(&a.vertex_vel), bits(&b.vertex_vel));
        assert_eq!(bits(&a.centre_pos), bits(&b.centre_pos));
    }

    /// An external force acts on the centres only and enters the momentum exactly: a constant
    /// force `F` on `N` free colloids adds `N F tau` per collision time (no solvent).
    #[test]
    fn an_external_force_on_the_centres_adds_its_impulse() {
        let f = [0.3, -0.1, 0.05];
        let mut c = DiscreteColloids::new(
            ColloidParams::standard(2.0, 1.0),
            SimBox::cube(10.0),
            &[[0.0; 3], [3.0, 3.0, 3.0], [-3.0, 2.0, 0.0]],
            1.0,
            8,
        )
        .unwrap();
        let p0 = c.momentum();
        for _ in 0..10 {
            c.advance(0.0, 0.1, &crate::potential::ConstantForce(f))
                .unwrap();
        }
        let p1 = c.momentum();
        for k in 0..3 {
            let expect = p0[k] + 3.0 * f[k] * 10.0 * 0.1;
            assert!((p1[k] - expect).abs() < 1e-12, "{p1:?} vs {expect}");
        }
    }

    /// A drying droplet of `n` colloids of diameter `d` in a sphere of initial radius `r0`
    /// (slip wall, `alpha = 10`) in a cubic box of edge `edge`, solvent and colloids seeded by
    /// `seed`, held by a harmonic interface (100 kT/d^2, range d/2, offset -d/2) on their
    /// centres, or with `hard` by a hard wall at `R(t) - d/2`.
    fn drying_droplet(
        d: f64,
        r0: f64,
        edge: f64,
        n: usize,
        seed: u32,
        hard: bool,
    ) -> (MpcdSystem, crate::potential::SphereAreaLaw) {
        use crate::mpcd::WallKind;
        use crate::potential::SphereAreaLaw;
        let law = SphereAreaLaw { r0, alpha: 10.0 };
        let conf = Confinement::Sphere {
            law,
            kind: WallKind::Slip,
        };
        let p = SrdParams::standard(seed);
        let sbox = SimBox::cube(edge);
        let srd = Srd::new(p, sbox, &conf, 0.0).unwrap();
        let c = DiscreteColloids::random(
            ColloidParams::standard(d, p.kt),
            sbox,
            n,
            Region::Sphere { radius: r0 },
            p.kt,
            seed,
        )
        .unwrap();
        let interface = HarmonicInterface {
            centre: [0.0; 3],
            radius: law,
            stiffness: 100.0,
            range: 0.5 * d,
            offset: -0.5 * d,
        };
        let interface = SpeciesInterface {
            interface,
            reference_diameter: d,
            hard,
        };
        (MpcdSystem::new(srd, c, conf, Some(interface)).unwrap(), law)
    }

    /// A drying droplet with colloids: solvent in the sphere (slip wall, virtual particles),
    /// colloids placed inside and held by the harmonic interface on their centres at R(t);
    /// they stay inside while the sphere shrinks.
    #[test]
    fn colloids_in_a_drying_droplet_stay_inside_the_interface() {
        let (d, r0) = (2.0, 7.0);
        let (mut sys, law) = drying_droplet(d, r0, 18.0, 20, 12, false);
        let mut virt = 0;
        for _ in 0..100 {
            virt += sys
                .step(&Acceleration::None)
                .unwrap()
                .collision
                .virtual_particles;
        }
        assert!(virt > 0);
        let r = law.radius(sys.time());
        assert!(r < 0.95 * r0, "{r}");
        for x in sys.colloids.centre_positions() {
            // Within the interface (the spring lets them in by a fraction of d).
            assert!(dist(*x, [0.0; 3]) < r - 0.5 * d + 0.25 * d, "{x:?} {r}");
        }
    }

    /// Behind a hard wall (`SpeciesInterface::hard`) no centre is ever beyond `R(t) - d/2` at
    /// the end of a step while the droplet dries (the spring of the test above lets them a
    /// quarter diameter in), and the colloids are carried in with the wall.
    #[test]
    fn colloids_behind_a_hard_wall_never_cross_it_while_drying() {
        let (d, r0) = (2.0, 7.0);
        let (mut sys, law) = drying_droplet(d, r0, 18.0, 20, 12, true);
        let mut deepest: f64 = f64::NEG_INFINITY;
        for _ in 0..100 {
            sys.step(&Acceleration::None).unwrap();
            let wall = law.radius(sys.time()) - 0.5 * d;
            for x in sys.colloids.centre_positions() {
                deepest = deepest.max(dist(*x, [0.0; 3]) - wall);
            }
        }
        assert!(law.radius(sys.time()) < 0.95 * r0);
        assert!(deepest <= 1e-12, "a centre {deepest} beyond the wall");
        // Some centre reached the wall (it was met, not avoided).
        assert!(deepest > -0.1 * d, "{deepest}");
    }

    /// The reflection at a wall moving at `w`: the colloid's centre-of-mass normal velocity
    /// becomes `2 w - V.n` (elastic in the wall's frame), its tangential velocity and the
    /// velocities of its particles relative to each other are kept, every particle is moved by
    /// the centre's mirror image in the wall; a colloid moving in faster than the wall is only
    /// moved back.
    #[test]
    fn a_hard_wall_reflects_the_colloid_in_its_own_frame() {
        let n = [0.6, 0.8, 0.0];
        let t = [-0.8, 0.6, 0.0];
        let at = |a: f64, b: f64, c: f64| -> [f64; 3] {
            std::array::from_fn(|k| a * n[k] + b * t[k] + [0.0, 0.0, c][k])
        };
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        // Centre of mass 2, vertices of mass 1: V = (2 v + v1 + v2) / 4.
        let masses = (2.0, 1.0);
        let com = |v: [f64; 3], vs: &[[f64; 3]]| -> [f64; 3] {
            std::array::from_fn(|k| (2.0 * v[k] + vs[0][k] + vs[1][k]) / 4.0)
        };
        for w in [0.0, -0.05] {
            let (mut x, mut v) = (at(3.1, 0.5, 0.2), at(0.1, 0.3, -0.2));
            let mut xs = [at(3.6, 0.5, 0.2), at(2.6, 0.5, 0.2)];
            let mut vs = [at(0.3, 0.1, 0.0), at(-0.1, 0.5, 0.0)];
            let (v0, vs0) = (v, vs);
            let body = Body {
                x: &mut x,
                v: &mut v,
                xs: &mut xs,
                vs: &mut vs,
            };
            body.reflect_at_wall(0.1, n, w, masses);
            assert!((dot(x, n) - 2.9).abs() < 1e-12 && (dot(x, t) - 0.5).abs() < 1e-12);
            assert!((dot(xs[0], n) - 3.4).abs() < 1e-12 && (dot(xs[1], n) - 2.4).abs() < 1e-12);
            let (before, after) = (com(v0, &vs0), com(v, &vs));
            assert!((dot(before, n) - 0.1).abs() < 1e-12);
            assert!((dot(after, n) - (2.0 * w - 0.1)).abs() < 1e-12, "{after:?}");
            assert!(
                (dot(after, t) - dot(before, t)).abs() < 1e-12
                    && (after[2] - before[2]).abs() < 1e-12
            );
            for k in 0..3 {
                assert!(((vs[0][k] - v[k]) - (vs0[0][k] - v0[k])).abs() < 1e-12);
                assert!(((vs[1][k] - v[k]) - (vs0[1][k] - v0[k])).abs() < 1e-12);
            }
        }
        let (mut x, mut v) = (at(3.1, 0.0, 0.0), at(-0.2, 0.0, 0.0));
        let (mut xs, mut vs) = ([at(3.1, 0.0, 0.0); 2], [at(-0.2, 0.0, 0.0); 2]);
        let body = Body {
            x: &mut x,
            v: &mut v,
            xs: &mut xs,
            vs: &mut vs,
        };
        body.reflect_at_wall(0.1, n, -0.05, masses);
        assert!((dot(x, n) - 2.9).abs() < 1e-12 && (dot(v, n) + 0.2).abs() < 1e-12);
        assert!((dot(xs[1], n) - 2.9).abs() < 1e-12 && (dot(vs[1], n) + 0.2).abs() < 1e-12);
    }

    /// A hard wall at `R(t) - d/2` for colloids of diameter `d` (no spring).
    fn hard_wall(law: crate::potential::SphereAreaLaw, d: f64) -> SpeciesInterface {
        SpeciesInterface {
            interface: HarmonicInterface {
                centre: [0.0; 3],
                radius: law,
                stiffness: 0.0,
                range: 0.0,
                offset: -0.5 * d,
            },
            reference_diameter: d,
            hard: true,
        }
    }

    /// An isolated colloid sent at a static hard wall bounces back and forth inside it: it
    /// never ends a step beyond the wall, its momentum turns at every bounce, and its energy
    /// stays within velocity Verlet's bounded error (the reflection is elastic and leaves the
    /// bonds as they were).
    #[test]
    fn an_isolated_colloid_bounces_elastically_off_a_static_hard_wall() {
        use crate::potential::SphereAreaLaw;
        let p = ColloidParams::standard(2.0, 1.0);
        let sbox = SimBox::cube(12.0);
        let c = DiscreteColloids::new(p, sbox, &[[0.0; 3]], 1.0, 4).unwrap();
        // The whole colloid moving at 1 along x (far above its thermal speed).
        let mut st = c.state();
        for v in st.centre_vel.iter_mut().chain(st.vertex_vel.iter_mut()) {
            v[0] += 1.0;
        }
        let mut c = DiscreteColloids::from_state(p, sbox, &st).unwrap();
        let wall = hard_wall(
            SphereAreaLaw {
                r0: 4.0,
                alpha: 0.0,
            },
            2.0,
        );
        let e0 = c.kinetic_energy() + c.potential_energy();
        let (mut spread, mut turns, mut last): (f64, usize, f64) = (0.0, 0, 1.0);
        for _ in 0..300 {
            c.advance(0.0, 0.1, &wall).unwrap();
            let e = c.kinetic_energy() + c.potential_energy();
            spread = spread.max((e - e0).abs());
            let x = c.centre_positions()[0];
            assert!(dist(x, [0.0; 3]) <= 3.0 + 1e-12, "{x:?}");
            let px = c.momentum()[0];
            if px * last < 0.0 {
                turns += 1;
            }
            last = px;
        }
        eprintln!("{turns} turns, energy error {spread} of {e0}");
        // 30 time units at speed 1 across a free path of 2 x 3: about 5 bounces.
        assert!(turns >= 4, "{turns}");
        assert!(spread < 0.01 * e0, "{spread} of {e0}");
    }

    /// One colloid in the solvent behind the static hard wall of a droplet samples the
    /// uniform density of its centre inside the wall, `<r^2> = 3 w^2 / 5` (w = R0 - d/2),
    /// within 4 standard errors of 20 block means: the reflection keeps the equilibrium of a
    /// colloid thermalised by the solvent. The solvent fills the periodic box (no boundary of
    /// its own, which would add the solvent's structure at a surface), so the wall alone
    /// confines the colloid. Long (about two minutes at the default 2e5 collisions;
    /// `HARD_WALL_COLLISIONS` sets them); docs/mpcd.md records a run.
    #[test]
    #[ignore]
    fn one_colloid_behind_a_static_hard_wall_fills_it_uniformly() {
        use crate::potential::SphereAreaLaw;
        let collisions: usize = std::env::var("HARD_WALL_COLLISIONS")
            .ok()
            .map_or(200_000, |s| s.parse().unwrap());
        let (d, r0) = (2.0, 2.0);
        let law = SphereAreaLaw { r0, alpha: 0.0 };
        let conf = Confinement::None;
        let p = SrdParams::standard(17);
        let sbox = SimBox::cube(8.0);
        let srd = Srd::new(p, sbox, &conf, 0.0).unwrap();
        let c = DiscreteColloids::new(ColloidParams::standard(d, p.kt), sbox, &[[0.0; 3]], 1.0, 17)
            .unwrap();
        let interface = hard_wall(law, d);
        let mut sys = MpcdSystem::new(srd, c, conf, Some(interface)).unwrap();
        for _ in 0..2000 {
            sys.step(&Acceleration::None).unwrap();
        }
        let mut r2 = Vec::with_capacity(collisions);
        for _ in 0..collisions {
            sys.step(&Acceleration::None).unwrap();
            let x = sys.colloids.centre_positions()[0];
            r2.push(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        }
        let (m, e) = block_mean(&r2, 20);
        let w = r0 - 0.5 * d;
        let exact = 0.6 * w * w;
        eprintln!("<r^2> = {m} +- {e} against 3 w^2 / 5 = {exact} ({collisions} collisions)");
        assert!(
            (m - exact).abs() < 4.0 * e && e < 0.05 * exact,
            "{m} +- {e} vs {exact}"
        );
    }

    /// FNV-1a over the bits of the rows.
    fn digest(h: &mut u64, rows: &[[f64; 3]]) {
        for x in rows.iter().flatten() {
            for b in x.to_bits().to_le_bytes() {
                *h = (*h ^ b as u64).wrapping_mul(0x100_0000_01b3);
            }
        }
    }

    /// A short drying droplet with colloids (slip wall, interface, WCA contacts): the digest of
    /// its final state, the same bits as the single-size model before species existed (the
    /// constant was printed by this test on that code, commit 59068cd).
    #[test]
    fn one_species_reproduces_the_single_size_model_bitwise() {
        let (mut sys, _) = drying_droplet(2.0, 6.0, 16.0, 25, 5, false);
        for _ in 0..8 {
            sys.step(&Acceleration::None).unwrap();
        }
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        digest(&mut h, &sys.srd.velocities());
        let s = sys.colloids.state();
        for rows in [&s.centre_pos, &s.centre_vel, &s.vertex_pos, &s.vertex_vel] {
            digest(&mut h, rows);
        }
        eprintln!("digest {h:#018x}");
        assert_eq!(h, DIGEST_BEFORE_SPECIES, "{h:#018x}");
    }

    /// [`one_species_reproduces_the_single_size_model_bitwise`] on the code before species.
    const DIGEST_BEFORE_SPECIES: u64 = 0x1b96_f31b_df16_6364;

    /// Geodesic shells of every frequency: `10 f^2 + 2` unit vertices (12 of degree 5, the
    /// rest 6), `30 f^2` edges between nearest neighbours; scaled to `d = f d_min / 2` their
    /// shortest and longest edges stay near the smallest shell's (the net is as fine).
    #[test]
    fn geodesic_shells_keep_the_vertex_spacing_of_the_smallest() {
        let small = Geometry::geodesic(2);
        let lengths = |g: &Geometry| -> (f64, f64) {
            g.edges
                .iter()
                .map(|&[i, j]| dist(g.vertices[i], g.vertices[j]))
                .fold((f64::INFINITY, 0f64), |(a, b), r| (a.min(r), b.max(r)))
        };
        let (lo2, hi2) = lengths(&small);
        for f in 1..=MAX_FREQUENCY {
            let g = Geometry::geodesic(f);
            assert_eq!(g.vertices.len(), Geometry::vertex_count(f), "{f}");
            assert_eq!(g.edges.len(), 30 * f * f, "{f}");
            let mut degree = vec![0usize; g.vertices.len()];
            for &[i, j] in &g.edges {
                assert!(i < j);
                degree[i] += 1;
                degree[j] += 1;
            }
            assert_eq!(degree.iter().filter(|&&k| k == 5).count(), 12, "{f}");
            assert!(degree.iter().all(|&k| k == 5 || k == 6), "{f}");
            assert!(
                g.vertices
                    .iter()
                    .all(|v| (dist(*v, [0.0; 3]) - 1.0).abs() < 1e-14)
            );
            // On a shell of diameter f/2 times the smallest's: edges within 25 % of its.
            let (lo, hi) = lengths(&g);
            let scale = f as f64 / 2.0;
            assert!(
                lo * scale > 0.75 * lo2 && hi * scale < 1.25 * hi2,
                "{f}: {lo} {hi}"
            );
        }
        assert_eq!(Geometry::frequency_for(4.0, 4.0), 2);
        assert_eq!(Geometry::frequency_for(8.0, 4.0), 4);
        assert_eq!(Geometry::frequency_for(6.0, 4.0), 3);
        assert_eq!(Geometry::frequency_for(16.0, 4.0), 8);
    }

    /// Two species, A (d = 2) and B (d = 4), in a drying droplet with a slip or a no-slip
    /// wall: the B shells have 162 vertices; placement and the run keep every pair apart at
    /// its contact distance (d_a + d_b) / 2 (to within the WCA's soft core at eps = kT) and
    /// every colloid's surface inside the interface (the SpeciesInterface shift); the shape
    /// holds.
    #[test]
    fn a_bidisperse_droplet_keeps_contacts_and_surfaces_inside() {
        use crate::mpcd::WallKind;
        use crate::potential::SphereAreaLaw;
        let r0 = 7.0;
        let mix = Mixture::new(vec![2.0, 4.0], vec![16, 4]);
        let law = SphereAreaLaw { r0, alpha: 30.0 };
        for kind in [WallKind::Slip, WallKind::NoSlip] {
            let conf = Confinement::Sphere { law, kind };
            let p = SrdParams::standard(31);
            let sbox = SimBox::cube(18.0);
            let srd = Srd::new(p, sbox, &conf, 0.0).unwrap();
            let c = DiscreteColloids::random_mixture(
                ColloidParams::standard(2.0, p.kt),
                &mix,
                sbox,
                Region::Sphere { radius: r0 },
                p.kt,
                31,
            )
            .unwrap();
            assert_eq!(c.vertices_of_species(1), 162);
            assert_eq!(c.particle_count(), 16 * 43 + 4 * 163);
            let interface = HarmonicInterface {
                centre: [0.0; 3],
                radius: law,
                stiffness: 100.0,
                range: 1.0,
                offset: -1.0,
            };
            let interface = SpeciesInterface {
                interface,
                reference_diameter: 2.0,
                hard: false,
            };
            let mut sys = MpcdSystem::new(srd, c, conf, Some(interface)).unwrap();
            // The closest pair over its contact distance, the farthest surface beyond R(t).
            let check = |sys: &MpcdSystem| -> (f64, f64) {
                let c = &sys.colloids;
                let (x, d) = (c.centre_positions(), c.diameters());
                let r = law.radius(sys.time());
                let (mut closest, mut beyond) = (f64::INFINITY, f64::NEG_INFINITY);
                for i in 0..x.len() {
                    beyond = beyond.max(dist(x[i], [0.0; 3]) + 0.5 * d[i] - r);
                    for j in i + 1..x.len() {
                        closest = closest.min(dist(x[i], x[j]) / (0.5 * (d[i] + d[j])));
                    }
                }
                (closest, beyond)
            };
            let (mut closest, mut beyond) = check(&sys);
            assert!(closest >= 1.0 && beyond <= 0.0, "{closest} {beyond}");
            for _ in 0..100 {
                sys.step(&Acceleration::None).unwrap();
                let (c, b) = check(&sys);
                (closest, beyond) = (closest.min(c), beyond.max(b));
            }
            let r = law.radius(sys.time());
            assert!(r < 0.75 * r0, "{r}");
            eprintln!(
                "{kind:?}: closest pair / contact {closest:.3}, surface beyond R {beyond:.3}"
            );
            assert!(closest > 0.8, "{kind:?}: {closest}");
            // The spring lets a surface out by a fraction of d_min (the fast drying presses).
            assert!(beyond < 0.4 * 2.0, "{kind:?}: {beyond}");
            assert!(sys.colloids.bond_strain_rms() < 0.03);
        }
    }

    /// The forces of a mixture at rest in its ideal shapes: the WCA of an A-B pair reaches to
    /// `2^(1/6) (d_A + d_B) / 2` and no further; the interface pulls each centre back as soon
    /// as its colloid's SURFACE passes the wall (`k s` with `s` the surface's excursion).
    #[test]
    fn mixture_forces_act_at_the_pairs_contact_and_at_each_surface() {
        let mix = Mixture::new(vec![2.0, 4.0], vec![1, 1]);
        let cp = ColloidParams::standard(2.0, 1.0);
        let sbox = SimBox::cube(30.0);
        let rc = 2f64.powf(1.0 / 6.0) * 3.0;
        for (gap, acting) in [(0.999, true), (1.001, false)] {
            let x = [[0.0; 3], [rc * gap, 0.0, 0.0]];
            let c = DiscreteColloids::new_mixture(cp, &mix, sbox, &x, 1.0, 3).unwrap();
            let f = c.forces_at(0.0, &NoExternal);
            assert_eq!(f[0][0] < -1e-6, acting, "{gap}: {:?}", f[0]);
        }
        // The wall for the small ones at R - d_A/2 (offset -1), shifted to R - d_B/2 for B.
        let interface = SpeciesInterface {
            interface: HarmonicInterface {
                centre: [0.0; 3],
                radius: crate::potential::SphereAreaLaw {
                    r0: 12.0,
                    alpha: 0.0,
                },
                stiffness: 100.0,
                range: 1.0,
                offset: -1.0,
            },
            reference_diameter: 2.0,
            hard: false,
        };
        let x = [[0.0, 0.0, 12.0 - 1.0 + 0.3], [12.0 - 2.0 + 0.3, 0.0, 0.0]];
        let c = DiscreteColloids::new_mixture(cp, &mix, sbox, &x, 1.0, 3).unwrap();
        let f = c.forces_at(0.0, &interface);
        assert!((f[0][2] + 30.0).abs() < 1e-6, "{:?}", f[0]);
        assert!((f[1][0] + 30.0).abs() < 1e-6, "{:?}", f[1]);
    }

    /// A mixture restarts bitwise from its state; a state of other species counts is refused;
    /// so are a shell beyond MAX_FREQUENCY and a reference diameter that is not the smallest.
    #[test]
    fn mixtures_restart_bitwise_and_unsupported_ones_are_refused() {
        let mix = Mixture::new(vec![2.0, 3.0], vec![5, 3]);
        let sbox = SimBox::cube(14.0);
        let p = SrdParams::standard(9);
        let cp = ColloidParams::standard(2.0, p.kt);
        let build = || {
            let srd = Srd::new(p, sbox, &Confinement::None, 0.0).unwrap();
            let c = DiscreteColloids::random_mixture(cp, &mix, sbox, Region::Box, p.kt, 9).unwrap();
            MpcdSystem::new(srd, c, Confinement::None, None).unwrap()
        };
        let mut one = build();
        for _ in 0..10 {
            one.step(&Acceleration::None).unwrap();
        }
        let mut first = build();
        for _ in 0..5 {
            first.step(&Acceleration::None).unwrap();
        }
        let state = first.colloids.state();
        assert_eq!(state.species_counts, vec![5, 3]);
        let srd = Srd::from_raw(
            p,
            sbox,
            &first.srd.raw_positions(),
            &first.srd.velocities(),
            first.srd.step(),
        )
        .unwrap();
        let c = DiscreteColloids::from_state_mixture(cp, &mix, sbox, &state).unwrap();
        let mut two = MpcdSystem::new(srd, c, Confinement::None, None).unwrap();
        for _ in 0..5 {
            two.step(&Acceleration::None).unwrap();
        }
        assert_eq!(one.colloids.state(), two.colloids.state());
        assert_eq!(bits(&one.srd.velocities()), bits(&two.srd.velocities()));
        let other = Mixture::new(vec![2.0, 3.0], vec![4, 4]);
        let e = DiscreteColloids::from_state_mixture(cp, &other, sbox, &state).unwrap_err();
        assert!(e.to_string().contains("species of [5, 3]"), "{e}");
        let big = Mixture::new(vec![2.0, 8.6], vec![1, 1]);
        let e = DiscreteColloids::new_mixture(
            cp,
            &big,
            SimBox::cube(30.0),
            &[[0.0; 3], [10.0, 0.0, 0.0]],
            1.0,
            1,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("frequency 9, at most 8"), "{e}");
        let e = DiscreteColloids::new_mixture(
            ColloidParams::standard(3.0, 1.0),
            &mix,
            sbox,
            &[[0.0; 3]; 8],
            1.0,
            1,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("smallest species diameter 2"), "{e}");
    }

    /// Mean and standard error of a correlated series from `blocks` block means.
    fn block_mean(x: &[f64], blocks: usize) -> (f64, f64) {
        let len = x.len() / blocks;
        let means: Vec<f64> = (0..blocks)
            .map(|b| x[b * len..(b + 1) * len].iter().sum::<f64>() / len as f64)
            .collect();
        let m = means.iter().sum::<f64>() / blocks as f64;
        let var = means.iter().map(|y| (y - m).powi(2)).sum::<f64>() / (blocks - 1) as f64;
        (m, (var / blocks as f64).sqrt())
    }

    /// In a thermostatted solvent the colloids reach kT: the temperature of their
    /// centre-of-mass velocities and of all their particles within 3 standard errors
    /// (block averages); the bonds keep the shape (rms strain below 3 %).
    #[test]
    fn colloids_in_a_thermostatted_solvent_reach_kt() {
        let mut sys = system(16.0, 4.0, 8, true, 41);
        for _ in 0..200 {
            sys.step(&Acceleration::None).unwrap();
        }
        let (mut com, mut all, mut strain) = (Vec::new(), Vec::new(), 0f64);
        for _ in 0..2000 {
            sys.step(&Acceleration::None).unwrap();
            com.push(sys.colloids.com_temperature());
            all.push(sys.colloids.temperature());
            strain = strain.max(sys.colloids.bond_strain_rms());
        }
        let (tc, sc) = block_mean(&com, 20);
        let (ta, sa) = block_mean(&all, 20);
        eprintln!("T(com) = {tc} +- {sc}, T(all) = {ta} +- {sa}, max rms strain {strain}");
        assert!(
            (tc - 1.0).abs() < 3.0 * sc && sc < 0.05,
            "T(com) = {tc} +- {sc}"
        );
        assert!(
            (ta - 1.0).abs() < 3.0 * sa && sa < 0.01,
            "T(all) = {ta} +- {sa}"
        );
        assert!(strain < 0.03, "{strain}");
    }

    /// One colloid in a periodic box of the standard solvent (cell thermostat): its
    /// long-time diffusion coefficient against Stokes–Einstein with Hasimoto's finite-size
    /// correction in the issue's (and Dünweg & Kremer's) first-order form,
    /// `D_L = kT / (6 pi eta a_h) (1 - 2.837297 a_h / L)`, with `a_h = d/2` and the solvent's
    /// measured viscosity (docs/mpcd.md, long run at L = 16: 3.9438 +- 0.0057), within 5 %.
    /// The full series (`+ 4.19 x^3 - 27.4 x^6`) is printed beside it.
    ///
    /// `D` by Green–Kubo from the colloid's centre-of-mass velocity relative to the mean
    /// velocity of the solvent, `V - P_solvent / M_solvent`, the frame of Hasimoto's theory
    /// (the solvent streams through the shell and fills the box). With the total momentum
    /// zero it is `V / (1 - M / M_total)` exactly; the lab-frame `D` is printed too.
    /// Only the collisions change these velocities (the bonds are internal forces), so they
    /// are constant between collisions and `D = (tau / 3) (C_0 / 2 + sum_{k >= 1} C_k)`
    /// exactly, with `C_k = <V_n . V_{n+k}>` (the discrete form of the integral of the
    /// velocity autocorrelation). The sum runs to 5 decay times of the slowest transverse mode
    /// of the box, `L^2 / (4 pi^2 nu)` (the tail beyond, below 0.3 % of D, is left out); error
    /// from 20 blocks. The slope of the mean squared displacement between 5 and 12 decay times
    /// is printed as a check (noisier). `COLLOID_L`, `COLLOID_D`, `COLLOID_TIME` (time units)
    /// override the size; see docs/mpcd.md, "Colloids".
    #[test]
    #[ignore]
    fn colloid_diffusion_long() {
        let env = |k: &str, v: f64| std::env::var(k).ok().map_or(v, |s| s.parse().unwrap());
        let (l, d, time) = (
            env("COLLOID_L", 16.0),
            env("COLLOID_D", 4.0),
            env("COLLOID_TIME", 80000.0),
        );
        let seed = env("COLLOID_SEED", 2026.0) as u32;
        let clock = std::time::Instant::now();
        let p = SrdParams::standard(seed);
        let sbox = SimBox::cube(l);
        let srd = Srd::new(p, sbox, &Confinement::None, 0.0).unwrap();
        let cp = ColloidParams::standard(d, p.kt);
        let c = DiscreteColloids::new(cp, sbox, &[[0.3, -0.2, 0.1]], p.kt, seed).unwrap();
        let mut sys = MpcdSystem::new(srd, c, Confinement::None, None).unwrap();
        let warm = 1000;
        for _ in 0..warm {
            sys.step(&Acceleration::None).unwrap();
        }
        let steps = (time / p.tau) as usize;
        // Relative to the solvent's mean velocity (`vel`), and in the lab frame (`lab`).
        let (mut vel, mut lab) = (Vec::with_capacity(steps), Vec::with_capacity(steps));
        let solvent_mass = sys.srd.len() as f64 * p.mass;
        let (mut t_all, mut strain) = (0.0, 0f64);
        for _ in 0..steps {
            sys.step(&Acceleration::None).unwrap();
            let (v, ps) = (sys.colloids.com_velocities()[0], sys.srd.momentum());
            vel.push(std::array::from_fn(|k| v[k] - ps[k] / solvent_mass));
            lab.push(v);
            t_all += sys.colloids.temperature() / steps as f64;
            strain = strain.max(sys.colloids.bond_strain_rms());
        }
        let p_total = sys.momentum();
        let nu = 3.9438 / p.density;
        let slowest = l * l / (4.0 * std::f64::consts::PI.powi(2) * nu);
        let kmax = (5.0 * slowest / p.tau).round() as usize;
        let green_kubo = |v: &[[f64; 3]]| -> f64 {
            let mut sum = 0.0;
            for k in 0..=kmax {
                let n = v.len() - k;
                let c = (0..n)
                    .map(|i| v[i][0] * v[i + k][0] + v[i][1] * v[i + k][1] + v[i][2] * v[i + k][2])
                    .sum::<f64>()
                    / n as f64;
                sum += if k == 0 { 0.5 * c } else { c };
            }
            p.tau * sum / 3.0
        };
        let blocks = 20;
        let len = vel.len() / blocks;
        let block_gk = |v: &[[f64; 3]]| -> (f64, f64) {
            let ds: Vec<f64> = (0..blocks)
                .map(|b| green_kubo(&v[b * len..(b + 1) * len]))
                .collect();
            let m = ds.iter().sum::<f64>() / blocks as f64;
            let var = ds.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (blocks - 1) as f64;
            (m, (var / blocks as f64).sqrt())
        };
        let (dm, se) = block_gk(&vel);
        let (d_lab, se_lab) = block_gk(&lab);
        let colloid_mass = cp.colloid_mass();
        // The check: the MSD slope from the centre-of-mass trajectory x_n = tau sum V.
        let mut x = vec![[0.0; 3]; vel.len() + 1];
        for (n, v) in vel.iter().enumerate() {
            x[n + 1] = std::array::from_fn(|k| x[n][k] + p.tau * v[k]);
        }
        let msd = |lag: usize| -> f64 {
            let n = x.len() - lag;
            (0..n)
                .map(|i| {
                    let (a, b) = (x[i], x[i + lag]);
                    (b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)
                })
                .sum::<f64>()
                / n as f64
        };
        let (k1, k2) = (kmax, (12.0 * slowest / p.tau).round() as usize);
        let d_msd = (msd(k2) - msd(k1)) / (6.0 * (k2 - k1) as f64 * p.tau);
        let eta = 3.9438;
        let hasimoto = |a: f64| 1.0 - 2.837297 * a / l;
        let series = |a: f64| {
            let x = a / l;
            hasimoto(a) + 4.19 * x.powi(3) - 27.4 * x.powi(6)
        };
        let stokes = |a: f64| p.kt / (6.0 * std::f64::consts::PI * eta * a) * hasimoto(a);
        let a = 0.5 * d;
        let theory = stokes(a);
        let theory_series = theory / hasimoto(a) * series(a);
        // The radius that would match: bisection on the decreasing stokes(a).
        let (mut lo, mut hi) = (0.1 * a, 3.0 * a);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if stokes(mid) > dm { lo = mid } else { hi = mid }
        }
        eprintln!(
            "L = {l}, d = {d}, {time} time units ({} collisions after {warm}) in {:.0} s; Green-Kubo to {:.1}",
            steps,
            clock.elapsed().as_secs_f64(),
            kmax as f64 * p.tau
        );
        let f = colloid_mass / (colloid_mass + solvent_mass);
        eprintln!(
            "D relative to the solvent = {dm:.6} +- {se:.6} (MSD slope {d_msd:.6}); lab frame {d_lab:.6} +- {se_lab:.6} (times 1/(1 - M/M_total)^2 = {:.6}, M/M_total = {f:.5})",
            d_lab / (1.0 - f).powi(2)
        );
        eprintln!(
            "Stokes-Einstein-Hasimoto with a = d/2: {theory:.6} (factor {:.4}); D / theory - 1 = {:+.2} % +- {:.2} %; matching radius {:.3}; full series {theory_series:.6} (factor {:.4}): {:+.2} % +- {:.2} %",
            hasimoto(a),
            100.0 * (dm / theory - 1.0),
            100.0 * se / theory,
            0.5 * (lo + hi),
            series(a),
            100.0 * (dm / theory_series - 1.0),
            100.0 * se / theory_series,
        );
        eprintln!(
            "colloid T(all) mean {t_all:.4}, largest rms strain {strain:.4}, total momentum {p_total:?}"
        );
        assert!(se / dm < 0.035, "too noisy: {se} of {dm}");
        assert!(
            (dm / theory - 1.0).abs() < 0.05,
            "D = {dm} +- {se} vs {theory}"
        );
    }
}
