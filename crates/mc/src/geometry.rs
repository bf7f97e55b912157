//! The three containers of the hard-sphere Monte Carlo: a periodic cube, a hard spherical wall
//! and the harmonic interface of the Brownian-dynamics droplet.
//!
//! Convention (the same as `droplet-bd`, docs/droplet.md): positions are measured from the
//! droplet's centre (the box centre in bulk); the droplet radius `R` is where the colloids'
//! *surfaces* stop. A hard wall of radius `R` therefore confines the *centres* to
//! `|r| <= R - d/2`; the BD interface with its default `offset = -d/2` starts pushing exactly at
//! that centre distance (`s = |r| - (R + offset) > 0`), so the hard wall is the BD droplet in the
//! limit of an infinitely stiff interface.

use colloidsim_core::ParamError;
use colloidsim_core::param::{finite, positive};
use colloidsim_md::potential::{External, HarmonicInterface, SphereAreaLaw};

/// Interface energy (in kT) beyond which the interface geometry places a hard outer wall: a
/// Boltzmann factor of 4e-18, so no sampled configuration can tell.
pub const INTERFACE_CUT_KT: f64 = 40.0;

/// Where the hard spheres live.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Geometry {
    /// Periodic cube of edge `edge` centred on the origin.
    Bulk {
        /// Box edge L.
        edge: f64,
    },
    /// Hard spherical wall of radius `radius` (the droplet): centres within `radius - d/2`.
    HardWall {
        /// Droplet radius R (surface of the colloids at contact).
        radius: f64,
    },
    /// The harmonic droplet interface of `colloidsim_md::potential::HarmonicInterface`
    /// (static), sampled by Metropolis on its energy; centres with more than
    /// [`INTERFACE_CUT_KT`] of interface energy are refused outright (`cutoff`).
    Interface {
        /// The BD interface (centre at the origin, `alpha = 0`).
        interface: HarmonicInterface,
        /// Thermal energy kT (the interface's stiffness is in energy / length^2).
        kt: f64,
        /// Largest centre distance from the origin ever accepted.
        cutoff: f64,
    },
}

impl Geometry {
    /// The BD droplet interface of radius `radius` (`V = k s^2 / 2` for `0 <= s < range`, linear
    /// beyond, `s = |r| - (radius + offset)`), with the outer cut where `V = 40 kT`. Keys
    /// `interface.stiffness`, `interface.range`, `interface.offset`, `system.radius`, `system.kT`.
    pub fn interface(
        radius: f64,
        stiffness: f64,
        range: f64,
        offset: f64,
        kt: f64,
    ) -> Result<Self, ParamError> {
        positive("system.radius", radius)?;
        positive("interface.stiffness", stiffness)?;
        positive("interface.range", range)?;
        finite("interface.offset", offset)?;
        positive("system.kT", kt)?;
        if radius + offset <= 0.0 {
            return Err(ParamError::new(
                "interface.offset",
                format!(
                    "must exceed -system.radius = {} (the wall would sit at or behind the centre)",
                    -radius
                ),
            ));
        }
        let interface = HarmonicInterface {
            centre: [0.0; 3],
            radius: SphereAreaLaw {
                r0: radius,
                alpha: 0.0,
            },
            stiffness,
            range,
            offset,
        };
        // Bisect the md crate's own energy for the distance where it reaches the cut (the
        // energy grows monotonically beyond the wall).
        let wall = radius + offset;
        let energy = |r: f64| interface.energy([r, 0.0, 0.0], 0.0) / kt;
        let mut hi = wall + range;
        while energy(hi) < INTERFACE_CUT_KT {
            hi = wall + 2.0 * (hi - wall);
        }
        let mut lo = wall;
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if energy(mid) < INTERFACE_CUT_KT {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Ok(Geometry::Interface {
            interface,
            kt,
            cutoff: hi,
        })
    }

    /// Largest distance of a centre from the origin (`None` in bulk).
    pub fn confinement(&self, diameter: f64) -> Option<f64> {
        match *self {
            Geometry::Bulk { .. } => None,
            Geometry::HardWall { radius } => Some(radius - 0.5 * diameter),
            Geometry::Interface { cutoff, .. } => Some(cutoff),
        }
    }

    /// Edge of the periodic box the cells tile: the bulk box, or the droplet with four
    /// diameters to spare on each side, so that no pair ever interacts across the box boundary
    /// and no cell straddling it holds a sphere (a cell is shorter than 4 d, see
    /// [`crate::engine`]).
    pub fn box_edge(&self, diameter: f64) -> f64 {
        match *self {
            Geometry::Bulk { edge } => edge,
            _ => 2.0 * self.confinement(diameter).unwrap_or(0.0) + 8.0 * diameter,
        }
    }

    /// Volume available to the colloids in the sense of the mean volume fraction: the box in
    /// bulk, `4 pi R^3 / 3` in the droplet (`phi = N d^3 / (8 R^3)`, as in droplet-bd).
    pub fn volume(&self) -> f64 {
        match *self {
            Geometry::Bulk { edge } => edge.powi(3),
            Geometry::HardWall { radius } => 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3),
            Geometry::Interface { interface, .. } => {
                4.0 / 3.0 * std::f64::consts::PI * interface.radius.r0.powi(3)
            }
        }
    }

    /// Interface energy / kT at distance `r` from the centre (0 unless [`Geometry::Interface`]).
    #[inline(always)]
    pub fn beta_energy(&self, r: [f64; 3]) -> f64 {
        match self {
            Geometry::Interface { interface, kt, .. } => interface.energy(r, 0.0) / kt,
            _ => 0.0,
        }
    }
}
