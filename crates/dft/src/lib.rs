//! Classical density functional theory for colloidsim.
//!
//! - [`rods`]: exact 1D equilibrium of hard and sticky rods (Percus; Baxter) and 1D DDFT.
//! - [`oz`]: the Ornstein–Zernike equation of bulk hard spheres with the Percus–Yevick closure.
//! - [`radial`]: Rosenfeld fundamental-measure theory in spherical symmetry (drying droplet).

mod anderson;
pub mod oz;
pub mod radial;
pub mod rods;
