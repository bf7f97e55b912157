//! Engines a script steps by hand (Python's engine classes): build from a scenario, step,
//! read positions, velocities and forces.

use anyhow::Result;

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
}

/// Flatten `[x, y, z]` rows (the engines' particle-major arrays).
pub(crate) fn flat(v: &[[f64; 3]]) -> Vec<f64> {
    v.iter().flatten().copied().collect()
}
