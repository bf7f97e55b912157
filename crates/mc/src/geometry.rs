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
use colloidsim_core::param::{finite, positive, show};
use colloidsim_particles::potential::{External, HarmonicInterface, SphereAreaLaw};

/// Interface energy (in kT) beyond which the interface geometry places a hard outer wall: a
/// Boltzmann factor of 4e-18, so no sampled configuration can tell.
pub const INTERFACE_CUT_KT: f64 = 40.0;

/// The smallest interface range per wall distance (radius + offset): `1e-9`, some 4.5 million
/// f64 steps of a position at the wall.
pub const MIN_RANGE_PER_RADIUS: f64 = 1e-9;

/// A tabulated spherically symmetric external potential `beta U(r)` (in kT), linear between the
/// nodes `r_k = k dr`, with a hard outer wall at `cutoff` (issue #15 item 4: the potential that
/// makes a DDFT profile the equilibrium one, `beta U = beta mu - ln rho - beta mu_ex[rho]`).
#[derive(Debug, Clone, PartialEq)]
pub struct RadialPotential {
    dr: f64,
    values: Vec<f64>,
    cutoff: f64,
    radius: f64,
}

impl RadialPotential {
    /// Nodes `values[k] = beta U(k dr)`; beyond the last node the last value; centres beyond
    /// `cutoff` are refused; `radius` is the droplet radius of the mean volume fraction
    /// `N d^3 / (8 R^3)`. Errors name the parameter (`dr`, `values`, `cutoff`, `radius`).
    pub fn new(dr: f64, values: Vec<f64>, cutoff: f64, radius: f64) -> Result<Self, ParamError> {
        positive("dr", dr)?;
        positive("cutoff", cutoff)?;
        positive("radius", radius)?;
        if values.len() < 2 || values.iter().any(|v| !v.is_finite()) {
            return Err(ParamError::new(
                "values",
                format!("needs at least 2 finite values, got {}", values.len()),
            ));
        }
        Ok(Self {
            dr,
            values,
            cutoff,
            radius,
        })
    }

    /// `beta U` at distance `r` from the centre.
    #[inline]
    pub fn at(&self, r: f64) -> f64 {
        let t = r / self.dr;
        let last = self.values.len() - 1;
        if t >= last as f64 {
            return self.values[last];
        }
        let k = t as usize;
        let f = t - k as f64;
        self.values[k] + f * (self.values[k + 1] - self.values[k])
    }
}

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
    /// The harmonic droplet interface of `colloidsim_particles::potential::HarmonicInterface`
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
    /// A tabulated radial potential, sampled by Metropolis on its energy (built once per table
    /// with [`Geometry::tabulated`], which keeps the table for the rest of the program so that
    /// the geometry stays `Copy`).
    Tabulated {
        /// The potential.
        potential: &'static RadialPotential,
    },
}

impl Geometry {
    /// The BD droplet interface of radius `radius` (`V = k s^2 / 2` for `0 <= s < range`, linear
    /// beyond, `s = |r| - (radius + offset)`), with the outer cut where `V = 40 kT`. Errors name
    /// the parameter: `stiffness`, `range`, `offset`, `radius`, `kt`.
    pub fn interface(
        radius: f64,
        stiffness: f64,
        range: f64,
        offset: f64,
        kt: f64,
    ) -> Result<Self, ParamError> {
        positive("radius", radius)?;
        positive("stiffness", stiffness)?;
        positive("range", range)?;
        finite("offset", offset)?;
        positive("kt", kt)?;
        if radius + offset <= 0.0 {
            return Err(ParamError::new(
                "offset",
                format!(
                    "must exceed -radius = {} (the wall would sit at or behind the centre)",
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
        // Bisect the interface's own energy for the distance where it reaches the cut (the
        // energy grows monotonically beyond the wall).
        let wall = radius + offset;
        // Positions near the wall are numbers of about `wall`, spaced `wall * 2^-52` apart: the
        // harmonic range must span many of those steps (else `wall + range == wall`, and the
        // search below would never leave the wall).
        if range < MIN_RANGE_PER_RADIUS * wall {
            return Err(ParamError::new(
                "range",
                format!(
                    "{} is not resolved at the wall's distance radius + offset = {} (f64 positions there are {:.1e} apart): need range >= {MIN_RANGE_PER_RADIUS:e} (radius + offset) = {:.3e}, or a smaller radius or offset",
                    show(range),
                    show(wall),
                    wall * f64::EPSILON,
                    MIN_RANGE_PER_RADIUS * wall
                ),
            ));
        }
        let energy = |r: f64| interface.energy([r, 0.0, 0.0], 0.0) / kt;
        let mut hi = wall + range;
        // Each doubling at least doubles the distance beyond the wall: at most some 2100 of
        // them reach infinity, which a stiffness too weak to reach the cut ends at.
        while energy(hi) < INTERFACE_CUT_KT && hi.is_finite() {
            hi = wall + 2.0 * (hi - wall);
        }
        if !hi.is_finite() {
            return Err(ParamError::new(
                "stiffness",
                format!(
                    "{} is too weak: the interface energy reaches {INTERFACE_CUT_KT} kT at no finite distance",
                    show(stiffness)
                ),
            ));
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

    /// The tabulated geometry of `potential`. The table is leaked (kept until the program ends):
    /// a few kilobytes per table, for programs that build a handful of them.
    pub fn tabulated(potential: RadialPotential) -> Self {
        Geometry::Tabulated {
            potential: Box::leak(Box::new(potential)),
        }
    }

    /// Does a move pay an external energy (Metropolis), beyond the hard constraints?
    #[inline(always)]
    pub fn is_soft(&self) -> bool {
        matches!(
            self,
            Geometry::Interface { .. } | Geometry::Tabulated { .. }
        )
    }

    /// Largest distance of a centre from the origin (`None` in bulk).
    pub fn confinement(&self, diameter: f64) -> Option<f64> {
        match *self {
            Geometry::Bulk { .. } => None,
            Geometry::HardWall { radius } => Some(radius - 0.5 * diameter),
            Geometry::Interface { cutoff, .. } => Some(cutoff),
            Geometry::Tabulated { potential } => Some(potential.cutoff),
        }
    }

    /// Whether the confinement of a centre shrinks as its sphere grows: the hard wall (centres
    /// within `R - d/2`) and the interface (its wall at `R + offset`, the offset given for one
    /// diameter); not the bulk box, nor the tabulated potential (which acts on centres).
    #[inline(always)]
    pub fn shrinks(&self) -> bool {
        matches!(self, Geometry::HardWall { .. } | Geometry::Interface { .. })
    }

    /// Largest distance from the origin of the centre of a sphere of diameter `diameter` in a
    /// mixture whose geometry was given for spheres of diameter `reference` (`None` in bulk):
    /// `confinement(reference) - (diameter - reference) / 2` where the geometry
    /// [`shrinks`](Self::shrinks) (the hard wall's `R - d/2` per sphere; the interface's wall
    /// moved in by half the extra diameter, so that every species' surface meets the same
    /// interface, as `offset = -d/2` makes it for one species), else `confinement(reference)`.
    /// Equal to `confinement(reference)` for `diameter == reference`, exactly.
    pub fn confinement_of(&self, diameter: f64, reference: f64) -> Option<f64> {
        let c = self.confinement(reference)?;
        Some(if self.shrinks() {
            c - (0.5 * diameter - 0.5 * reference)
        } else {
            c
        })
    }

    /// [`Self::box_edge`] for a mixture of `diameters` whose geometry was given for `reference`:
    /// the bulk box, or the largest confinement of any species ([`Self::confinement_of`]) with
    /// four of the largest diameters to spare on each side. One species of `reference`:
    /// `box_edge(reference)`, exactly.
    pub fn box_edge_of(&self, reference: f64, diameters: &[f64]) -> f64 {
        match *self {
            Geometry::Bulk { edge } => edge,
            _ => {
                let d_max = diameters.iter().fold(0.0f64, |m, &d| m.max(d));
                let c = diameters
                    .iter()
                    .map(|&d| self.confinement_of(d, reference).unwrap_or(0.0))
                    .fold(f64::NEG_INFINITY, f64::max);
                2.0 * c + 8.0 * d_max
            }
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
            Geometry::Tabulated { potential } => {
                4.0 / 3.0 * std::f64::consts::PI * potential.radius.powi(3)
            }
        }
    }

    /// External energy / kT at position `r` of a sphere whose radius exceeds the reference
    /// one (see [`Self::confinement_of`]) by `h`: the interface acts on it with its wall moved
    /// in by `h` (`offset - h`); the tabulated potential acts on centres whatever the radius.
    /// `h = 0` gives [`Self::beta_energy`] exactly.
    #[inline(always)]
    pub fn beta_energy_of(&self, r: [f64; 3], h: f64) -> f64 {
        match self {
            Geometry::Interface { interface, kt, .. } => {
                let shifted = HarmonicInterface {
                    offset: interface.offset - h,
                    ..*interface
                };
                shifted.energy(r, 0.0) / kt
            }
            _ => self.beta_energy(r),
        }
    }

    /// External energy / kT at position `r` (0 unless [`Geometry::Interface`] or
    /// [`Geometry::Tabulated`]).
    #[inline(always)]
    pub fn beta_energy(&self, r: [f64; 3]) -> f64 {
        match self {
            Geometry::Interface { interface, kt, .. } => interface.energy(r, 0.0) / kt,
            Geometry::Tabulated { potential } => {
                potential.at((r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt())
            }
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{HardSphereMc, McParams, init};

    /// Nearly ideal spheres (N = 10, d = 0.1 in a ball of radius 1: centre packing 0.005) in the
    /// tabulated `beta U = 2 r` (nodes every 0.25, exact under linear interpolation): the
    /// fraction of centres within r < 0.5 is the Boltzmann one,
    /// `int_0^0.5 r^2 e^{-2r} / int_0^1 r^2 e^{-2r} = 0.248` (uniform: 0.125), within 4 standard
    /// errors of 20 blocks of 1000 sweeps after 1000 of warm-up (measured 0.2425 +- 0.0086; 40
    /// blocks with another seed 0.2472 +- 0.0076). Broken on purpose (the tabulated geometry not
    /// treated as soft: no Metropolis step): 0.113 +- 0.006, fails.
    #[test]
    fn tabulated_potential_samples_its_boltzmann_distribution() {
        let dr = 0.25;
        let values: Vec<f64> = (0..=4).map(|k| 2.0 * k as f64 * dr).collect();
        let potential = RadialPotential::new(dr, values, 1.0, 1.0).unwrap();
        assert!((potential.at(0.3) - 0.6).abs() < 1e-12);
        assert_eq!(potential.at(10.0), 2.0);
        let params = McParams {
            diameter: 0.1,
            geometry: Geometry::tabulated(potential),
            seed: 5,
            delta: 0.05,
            mixture: None,
        };
        let start = init::fcc_in_sphere(10, 0.1, 0.95).unwrap();
        let mut mc = HardSphereMc::new(&params, &start, "positions").unwrap();
        mc.warm_up(1000, 100, 0.4);
        let mut blocks = Vec::new();
        for _ in 0..20 {
            let (mut inside, mut total) = (0usize, 0usize);
            for _ in 0..100 {
                mc.run(10);
                for i in 0..mc.len() {
                    let p = mc.position(i);
                    let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                    assert!(r <= 1.0 + 1e-12);
                    inside += usize::from(r < 0.5);
                    total += 1;
                }
            }
            blocks.push(inside as f64 / total as f64);
        }
        let (f, se) = crate::observe::mean_and_error(&blocks);
        // int_0^x r^2 e^{-2r} dr = 1/4 - e^{-2x} (x^2/2 + x/2 + 1/4).
        let cum = |x: f64| 0.25 - (-2.0 * x).exp() * (0.5 * x * x + 0.5 * x + 0.25);
        let p = cum(0.5) / cum(1.0);
        println!("fraction within r < 0.5: {f:.4} +- {se:.4} vs {p:.4}");
        assert!((f - p).abs() < 4.0 * se, "{f} +- {se} vs {p}");
    }

    /// The cut-off search never left the wall when `wall + range` rounded to `wall`.
    #[test]
    fn an_interface_range_unresolved_at_the_wall_is_refused() {
        let big = 9_223_372_036_854_775_807.0;
        for (radius, range, offset) in [(big, 0.5, -0.5), (5.0, 1e-300, -0.5), (5.0, 0.5, big)] {
            let e = Geometry::interface(radius, 50.0, range, offset, 1.0).unwrap_err();
            assert_eq!(e.key, "range", "{e}");
            assert!(e.message.contains("not resolved at the wall"), "{e}");
        }
        assert!(Geometry::interface(5.0, 50.0, 1e-8, -0.5, 1.0).is_ok());
    }
}
