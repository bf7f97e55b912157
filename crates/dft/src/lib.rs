//! Classical density functional theory for colloidsim.
//!
//! - [`rods`]: exact 1D equilibrium of hard and sticky rods (Percus; Baxter) and 1D DDFT.
//! - [`radial`]: Rosenfeld fundamental-measure theory in spherical symmetry (drying droplet).

mod anderson;
pub mod radial;
pub mod rods;
