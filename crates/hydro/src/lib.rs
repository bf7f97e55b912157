//! colloidsim-hydro: the hydrodynamic mobility of a configuration of spheres.
//!
//! One interface, [`Mobility`]: the product `U = M F` (3N velocities from 3N forces) and a
//! Brownian displacement `sqrt(2 kT dt) M^(1/2) z` with covariance `2 kT dt M`, for the
//! Brownian dynamics step `dx = M F dt + sqrt(2 kT dt) M^(1/2) z` (Ermak & McCammon 1978).
//! The mobilities here are divergence-free (`sum_j d/dx_j . M_ij = 0`: free draining
//! trivially, the Rotne–Prager–Yamakawa tensor by construction — it is the Stokeslet
//! averaged over two sphere surfaces), so the step needs no `kT div M dt` drift term.
//!
//! - [`FreeDraining`]: `M = I / (6 pi eta a_i)`.
//! - [`DirectRpy`]: the RPY tensor ([`rpy`]) in an unbounded fluid, both branches, equal or
//!   unequal radii; the O(N^2) matrix-free product and a Lanczos square root ([`lanczos`]).
//! - [`Pse`]: positively split Ewald (Fiore, Balboa Usabiaga, Donev & Swan, J. Chem. Phys. 146,
//!   124116 (2017)) for the RPY tensor in a periodic cube, O(N log N); unequal radii by one sinc
//!   filter per species ([`Pse::with_radii`]).
//! - [`ewald`]: Beenakker's Ewald sum of the RPY tensor (J. Chem. Phys. 85, 1581 (1986)) as a
//!   dense reference for small N, also for unequal radii.
//!
//! Random numbers come from the counter-based streams of `colloidsim_core::rng`, keyed by
//! (seed, step, particle) ([`noise`]); every sum runs in a fixed order, so results do not
//! depend on the thread count.

pub mod bench;
pub mod direct;
pub mod ewald;
mod fft3;
pub mod lanczos;
pub mod noise;
pub mod params;
pub mod pse;
pub mod rpy;

pub use direct::{DirectRpy, FreeDraining};
pub use lanczos::{LanczosError, LanczosParams, SqrtReport};
pub use noise::NoiseKey;
pub use params::{HydroMethod, HydroModel, HydroParams};
pub use pse::{Pse, PseGeometry, PseParams, PseTimes};

use colloidsim_core::ParamError;

/// Why a mobility could not be set up or applied.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HydroError {
    /// The Brownian square root failed at a step.
    #[error("step {step}: {source}")]
    Lanczos {
        /// Time step of the noise.
        step: u64,
        /// What went wrong.
        source: LanczosError,
    },
    /// Too many particles for the direct method.
    #[error(
        "method: {particles} particles exceed the direct method's limit of {max} \
         ({pairs:.2e} pair tensors per product, each Lanczos step one product; a stored 3N x 3N \
         matrix would need {matrix_gib:.1} GiB); use method = \"pse\" (periodic, O(N log N))"
    )]
    TooManyParticles {
        /// Particles requested.
        particles: usize,
        /// Allowed maximum.
        max: usize,
        /// Pair evaluations per product.
        pairs: f64,
        /// Memory of a dense mobility matrix.
        matrix_gib: f64,
    },
    /// A parameter outside its range.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// Inconsistent input.
    #[error("{0}")]
    Invalid(String),
}

/// A mobility operator for a configuration of N spheres.
///
/// Vectors are 3N numbers stored as `[f64; 3]` per particle, in the order of the positions
/// last given to [`Mobility::set_positions`].
pub trait Mobility: Send + Sync {
    /// Number of particles.
    fn len(&self) -> usize;

    /// No particles?
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Take new positions (any periodic image: periodic methods wrap them).
    fn set_positions(&mut self, pos: &[[f64; 3]]) -> Result<(), HydroError>;

    /// `out = M f`.
    fn apply(&mut self, f: &[[f64; 3]], out: &mut [[f64; 3]]);

    /// `out = scale M^(1/2) z`, with `z` the standard normal noise of `key`
    /// (covariance `scale^2 M`; for Brownian dynamics `scale = sqrt(2 kT dt)`).
    fn brownian(
        &mut self,
        key: NoiseKey,
        scale: f64,
        out: &mut [[f64; 3]],
    ) -> Result<SqrtReport, HydroError>;

    /// One Brownian-dynamics displacement `out = dt M f + sqrt(2 kT dt) M^(1/2) z(key)`
    /// (Ermak & McCammon 1978, without the `kT div M dt` term: see the crate docs).
    ///
    /// Provided: `out = sqrt(2 kT dt) M^(1/2) z` by [`Mobility::brownian`], `u = M f` by
    /// [`Mobility::apply`] into [`Mobility::displacement_scratch`], then `out += dt u` per
    /// component. Operators that fuse the two products override it.
    fn displacement(
        &mut self,
        f: &[[f64; 3]],
        dt: f64,
        kt: f64,
        key: NoiseKey,
        out: &mut [[f64; 3]],
    ) -> Result<SqrtReport, HydroError> {
        let rep = self.brownian(key, (2.0 * kt * dt).sqrt(), out)?;
        let mut u = self
            .displacement_scratch()
            .map(std::mem::take)
            .unwrap_or_default();
        u.resize(out.len(), [0.0; 3]);
        self.apply(f, &mut u);
        for (o, u) in out.iter_mut().zip(&u) {
            for k in 0..3 {
                o[k] += dt * u[k];
            }
        }
        if let Some(s) = self.displacement_scratch() {
            *s = u;
        }
        Ok(rep)
    }

    /// The buffer of `M f` that the provided [`Mobility::displacement`] reuses from step to
    /// step; `None` (the default) makes it allocate one per call.
    fn displacement_scratch(&mut self) -> Option<&mut Vec<[f64; 3]>> {
        None
    }

    /// Self-mobility of an isolated particle `i` in an unbounded fluid, `1 / (6 pi eta a_i)`.
    fn stokes_mobility(&self, i: usize) -> f64;

    /// The block `M_ij = A I + B r̂r̂` of two particles `i != j` at the positions last given,
    /// with the unit separation `r̂`: the engines' hard-wall reflection solves with it. The
    /// RPY operators give the unbounded fluid's pair tensor (a periodic one: of the nearest
    /// image, without the other images' share); the default, free draining's, is zero.
    fn pair_block(&self, _i: usize, _j: usize) -> ([f64; 3], rpy::PairTensor) {
        ([0.0, 0.0, 1.0], rpy::PairTensor { a: 0.0, b: 0.0 })
    }

    /// Bytes of memory the operator holds (buffers, lists, grids).
    fn bytes(&self) -> usize;
}

/// One of the mobilities, chosen at run time (the scenario's `[hydrodynamics]`): the engines
/// call it once per step, so the dispatch costs nothing next to the product.
#[derive(Debug)]
pub enum AnyMobility {
    /// Free draining.
    FreeDraining(FreeDraining),
    /// RPY, direct free-space sums (boxed, like PSE: the variants stay small).
    Direct(Box<DirectRpy>),
    /// RPY, positively split Ewald in a periodic cube (boxed: it holds the grids).
    Pse(Box<Pse>),
}

impl AnyMobility {
    fn inner(&mut self) -> &mut dyn Mobility {
        match self {
            Self::FreeDraining(m) => m,
            Self::Direct(m) => m.as_mut(),
            Self::Pse(m) => m.as_mut(),
        }
    }

    fn inner_ref(&self) -> &dyn Mobility {
        match self {
            Self::FreeDraining(m) => m,
            Self::Direct(m) => m.as_ref(),
            Self::Pse(m) => m.as_ref(),
        }
    }

    /// The PSE operator, if that is the method.
    pub fn pse(&self) -> Option<&Pse> {
        match self {
            Self::Pse(m) => Some(m),
            _ => None,
        }
    }

    /// The PSE operator, if that is the method (mutable, e.g. to reset its timers).
    pub fn pse_mut(&mut self) -> Option<&mut Pse> {
        match self {
            Self::Pse(m) => Some(m),
            _ => None,
        }
    }
}

impl Mobility for AnyMobility {
    fn len(&self) -> usize {
        self.inner_ref().len()
    }
    fn set_positions(&mut self, pos: &[[f64; 3]]) -> Result<(), HydroError> {
        self.inner().set_positions(pos)
    }
    fn apply(&mut self, f: &[[f64; 3]], out: &mut [[f64; 3]]) {
        self.inner().apply(f, out)
    }
    fn brownian(
        &mut self,
        key: NoiseKey,
        scale: f64,
        out: &mut [[f64; 3]],
    ) -> Result<SqrtReport, HydroError> {
        self.inner().brownian(key, scale, out)
    }
    // Forwarded, not the provided method: each operator's own (possibly fused) displacement.
    fn displacement(
        &mut self,
        f: &[[f64; 3]],
        dt: f64,
        kt: f64,
        key: NoiseKey,
        out: &mut [[f64; 3]],
    ) -> Result<SqrtReport, HydroError> {
        self.inner().displacement(f, dt, kt, key, out)
    }
    fn stokes_mobility(&self, i: usize) -> f64 {
        self.inner_ref().stokes_mobility(i)
    }
    fn pair_block(&self, i: usize, j: usize) -> ([f64; 3], rpy::PairTensor) {
        self.inner_ref().pair_block(i, j)
    }
    fn bytes(&self) -> usize {
        self.inner_ref().bytes()
    }
}
