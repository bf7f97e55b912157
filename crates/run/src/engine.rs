//! Engines a script steps by hand (Python's engine classes): build from a scenario, step,
//! read and set positions, velocities, the step and the seed, add forces of the script's own.

use anyhow::{Result, bail};

/// A method's engine, stepped by hand. Arrays are copies, particle-major (`N x dimensions`,
/// flattened), in the particles' input order.
pub trait Engine: Send {
    /// The scenario's method.
    fn method(&self) -> &str;
    /// Spatial dimensions of a position (1 for rods, 3 for spheres).
    fn dimensions(&self) -> usize;
    /// Number of particles.
    fn particles(&self) -> usize;
    /// Advance `steps` steps.
    fn step(&mut self, steps: u64) -> Result<()>;
    /// Steps done.
    fn steps(&self) -> u64;
    /// Simulated time.
    fn time(&self) -> f64;
    /// Time step.
    fn dt(&self) -> f64;
    /// Positions (unwrapped where the engine keeps them so).
    fn positions(&self) -> Vec<f64>;
    /// Velocities, where the engine has them (DPD); Brownian engines have none.
    fn velocities(&self) -> Option<Vec<f64>>;
    /// The systematic (non-random) forces at the current positions.
    fn forces(&self) -> Result<Vec<f64>>;
    /// The periodic box or system length (`[L]` for rods, `[Lx, Ly, Lz]` for spheres).
    fn box_lengths(&self) -> Vec<f64>;
    /// The seed of the counter-based random streams.
    fn seed(&self) -> u32;
    /// Each particle's type and diameter (input order) and the types' names, where the
    /// particles are spheres or rods of known types (not MPCD's solvent and vertices).
    fn types(&self) -> Option<ParticleTypes> {
        None
    }
    /// Replace part of the state (what `change` holds), as if the engine had been built from
    /// it at that step: the engine is set up afresh (particles sorted, lists built), so the run
    /// goes on as a fresh start from that state would. Checked before anything changes: on an
    /// error the engine is as it was, and the error names the field (`positions`,
    /// `velocities`, `step`, `seed`).
    fn set_state(&mut self, change: StateChange) -> Result<()>;
    /// Forces of the script's own added to the systematic forces of every step until replaced
    /// (input order, `N x dimensions` flattened; empty: none). Brownian engines only.
    fn set_extra_forces(&mut self, forces: &[f64]) -> Result<()> {
        let _ = forces;
        bail!(
            "forces: the {} engine takes no forces of a script's own (Brownian dynamics, \
             `bd` and `droplet-bd`, does)",
            self.method()
        )
    }
}

/// Each particle's type (an index into `names`) and diameter.
#[derive(Debug, Clone, PartialEq)]
pub struct ParticleTypes {
    /// Type names (GSD `particles/types`).
    pub names: Vec<String>,
    /// Type of each particle.
    pub typeid: Vec<u32>,
    /// Diameter of each particle.
    pub diameter: Vec<f64>,
}

impl ParticleTypes {
    /// The types of `p`.
    pub(crate) fn of(p: &colloidsim_particles::Particles) -> Self {
        Self {
            names: p.type_names.clone(),
            typeid: p.typeid.clone(),
            diameter: p.diameter.clone(),
        }
    }
}

/// Part of an engine's state to replace ([`Engine::set_state`]); what is `None` is kept.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StateChange {
    /// Positions laid out as [`Engine::positions`] returns them (any periodic image: they are
    /// the unwrapped positions from now on).
    pub positions: Option<Vec<f64>>,
    /// Velocities, where the engine has them.
    pub velocities: Option<Vec<f64>>,
    /// Steps done (the time is `step * dt`; the random streams are keyed by it).
    pub step: Option<u64>,
    /// Seed of the random streams.
    pub seed: Option<u32>,
}

impl StateChange {
    /// Check the arrays' lengths (`n` rows of `dimensions`) and that every number is finite;
    /// `velocities` are refused by an engine without them (`method`).
    pub(crate) fn check(
        &self,
        n: usize,
        dimensions: usize,
        has_velocities: bool,
        method: &str,
    ) -> Result<()> {
        if self.velocities.is_some() && !has_velocities {
            bail!("velocities: the {method} engine has none (it moves particles by displacements)");
        }
        for (name, a) in [
            ("positions", &self.positions),
            ("velocities", &self.velocities),
        ] {
            if let Some(a) = a {
                check_array(name, a, n, dimensions)?;
            }
        }
        Ok(())
    }
}

/// `a` holds `n` rows of `dimensions` finite numbers; the error names the array `name`.
pub(crate) fn check_array(name: &str, a: &[f64], n: usize, dimensions: usize) -> Result<()> {
    if a.len() != n * dimensions {
        bail!(
            "{name}: {n} particles need {n} x {dimensions} = {} numbers, got {}",
            n * dimensions,
            a.len()
        );
    }
    if let Some(i) = a.iter().position(|x| !x.is_finite()) {
        bail!(
            "{name}: particle {} has a non-finite value ({})",
            i / dimensions,
            a[i]
        );
    }
    Ok(())
}

/// `[x, y, z]` rows of a flattened array.
pub(crate) fn rows(v: &[f64]) -> Vec<[f64; 3]> {
    v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
}

/// Flatten `[x, y, z]` rows (the engines' particle-major arrays).
pub(crate) fn flat(v: &[[f64; 3]]) -> Vec<f64> {
    v.iter().flatten().copied().collect()
}

/// Spheres (`positions` flattened `N x 3`, any periodic image; each particle's `typeid` into
/// `type_names`, its diameter) in a box of edges `box_lengths`, written to a new file `path`
/// as the exact GSD frame at `step` that `system.initial` reads: how a script builds an engine
/// from arrays. An existing file is never replaced.
pub fn write_initial_gsd(
    path: &std::path::Path,
    box_lengths: [f64; 3],
    positions: &[f64],
    typeid: &[u32],
    type_names: &[String],
    diameters: &[f64],
    step: u64,
) -> Result<()> {
    use colloidsim_particles::{Particles, SimBox, gsd::GsdWriter};
    let n = typeid.len();
    check_array("positions", positions, n, 3)?;
    if diameters.len() != n {
        bail!(
            "diameters: {n} particles need {n} diameters, got {}",
            diameters.len()
        );
    }
    if let Some(i) = typeid.iter().position(|&t| t as usize >= type_names.len()) {
        bail!(
            "types: particle {i} has typeid {}, but there are {} types",
            typeid[i],
            type_names.len()
        );
    }
    if let Some(i) = diameters.iter().position(|d| !(d.is_finite() && *d > 0.0)) {
        bail!(
            "diameters: particle {i} has diameter {}, must be > 0",
            diameters[i]
        );
    }
    if box_lengths.iter().any(|l| !(l.is_finite() && *l > 0.0)) {
        bail!("box: edges must be finite and > 0, got {box_lengths:?}");
    }
    let sbox = SimBox::new(box_lengths);
    let mut p = Particles::monodisperse(rows(positions), 1.0);
    for (q, img) in p.pos.iter_mut().zip(&mut p.image) {
        sbox.wrap(q, img);
    }
    p.typeid = typeid.to_vec();
    p.diameter = diameters.to_vec();
    p.type_names = type_names.to_vec();
    let mut w = GsdWriter::create_new(path)?;
    w.write_frame(step, &sbox, &p, true, &[])?;
    w.sync()?;
    Ok(())
}
