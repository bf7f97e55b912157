//! Pair interactions between colloid species, declared per kind and built into one [`Pair`]
//! table indexed by the two particles' species.
//!
//! With `sigma_ij = (d_i + d_j) / 2` the pair's contact distance (additive diameters) and
//! `a_i = d_i / 2`:
//!
//! - `wca`: `4 eps_ij [(sigma_ij/r)^12 - (sigma_ij/r)^6] + eps_ij` for `r < 2^(1/6) sigma_ij`
//!   (Weeks, Chandler & Andersen 1971);
//! - `lj`: Lennard-Jones with `sigma_ij`, cut at `cutoff sigma_ij`, shifted to zero there;
//! - `yukawa`: a WCA core (eps = kT) plus the DLVO screened Coulomb repulsion of charged spheres
//!   (Verwey & Overbeek 1948; Russel, Saville & Schowalter, Colloidal Dispersions, Eq. 4.10.16)
//!   `U = kT l_B Z_i Z_j [e^(kappa a_i) / (1 + kappa a_i)] [e^(kappa a_j) / (1 + kappa a_j)]
//!   e^(-kappa r) / r` with `kappa = 1 / debye_length`, cut at `r_c` and shifted;
//! - `morse`: `D [e^(-2 k (h - h0)) - 2 e^(-k (h - h0))]` on the surface distance
//!   `h = r - sigma_ij`, cut at `h_cut` and shifted (as DPD's Morse);
//! - `ao`: a WCA core (eps = kT) plus the Asakura–Oosawa depletion attraction of an ideal
//!   depletant of diameter `sigma_p` at reservoir volume fraction `phi_p`
//!   (Asakura & Oosawa 1954; Vrij 1976): `U = -n_p kT V_ov(r)` with `n_p = 6 phi_p / (pi sigma_p^3)`
//!   and `V_ov` the lens in which the depletion spheres of radii `A = a_i + sigma_p/2`,
//!   `B = a_j + sigma_p/2` overlap, `V_ov = pi (A + B - r)^2 (r^2 + 2 r (A + B) - 3 (A - B)^2) / (12 r)`
//!   for `|A - B| < r < A + B`;
//! - `table`: energy and force per species pair on a uniform grid of r, linearly interpolated;
//!   zero beyond the last point; below the first point the first force (and the energy
//!   continued linearly), so a pair pushed inside the table still feels its repulsion.

use crate::potential::{LennardJones, LjParams, Pair};
use colloidsim_core::ParamError;
use std::f64::consts::PI;

/// The WCA cut-off `2^(1/6)` in units of sigma.
pub const WCA_CUTOFF: f64 = 1.122_462_048_309_373;

/// What the pair interaction of every species pair is: one kind per run, parameters per species
/// (charges) or per unordered species pair (energies), diameters from the species.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PairSpec {
    /// WCA at the pair's contact distance, well depth per unordered pair.
    Wca {
        /// `eps_ij` per unordered pair (AA, AB, ..., BB, ...).
        epsilon: Vec<f64>,
    },
    /// Lennard-Jones at the pair's contact distance, cut at `cutoff` contact distances.
    Lj {
        /// `eps_ij` per unordered pair.
        epsilon: Vec<f64>,
        /// Cut-off in units of `sigma_ij`.
        cutoff: f64,
    },
    /// WCA core plus DLVO screened Coulomb.
    Yukawa {
        /// Charge number Z of each species.
        charges: Vec<f64>,
        /// Bjerrum length l_B.
        bjerrum_length: f64,
        /// Debye length 1 / kappa.
        debye_length: f64,
        /// Cut-off beyond contact, `r_c = sigma_ij + range`.
        range: f64,
    },
    /// Morse on the surface distance.
    Morse {
        /// Well depth D.
        depth: f64,
        /// Inverse range k.
        kappa: f64,
        /// Surface distance of the minimum h0.
        h0: f64,
        /// Surface-distance cut-off.
        h_cut: f64,
    },
    /// WCA core plus Asakura–Oosawa depletion.
    Ao {
        /// Depletant diameter sigma_p.
        depletant_diameter: f64,
        /// Depletant reservoir volume fraction phi_p.
        depletant_fraction: f64,
    },
    /// Tabulated energy and force.
    Table {
        /// Uniform grid of r (at least two points).
        r: Vec<f64>,
        /// Energy per unordered pair, on the grid.
        energy: Vec<Vec<f64>>,
        /// Force `-dU/dr` per unordered pair, on the grid.
        force: Vec<Vec<f64>>,
    },
}

impl PairSpec {
    /// The kind's name (as in a scenario).
    pub fn kind(&self) -> &'static str {
        match self {
            PairSpec::Wca { .. } => "wca",
            PairSpec::Lj { .. } => "lj",
            PairSpec::Yukawa { .. } => "yukawa",
            PairSpec::Morse { .. } => "morse",
            PairSpec::Ao { .. } => "ao",
            PairSpec::Table { .. } => "table",
        }
    }

    /// WCA with `eps = kT` for every pair: the hard-sphere-like default.
    pub fn wca(kt: f64, species: usize) -> Self {
        PairSpec::Wca {
            epsilon: vec![kt; species * (species + 1) / 2],
        }
    }

    /// The interaction of species of diameters `diameters` at thermal energy `kt`; the error
    /// names the parameter.
    pub fn build(&self, diameters: &[f64], kt: f64) -> Result<Interaction, ParamError> {
        let n = diameters.len();
        let pairs = n * (n + 1) / 2;
        let per_pair = |name: &str, v: &[f64]| -> Result<(), ParamError> {
            if v.len() != pairs {
                return Err(ParamError::new(
                    name,
                    format!(
                        "needs one value per unordered species pair ({pairs} for {n} species: AA, AB, ...), got {}",
                        v.len()
                    ),
                ));
            }
            match v.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
                Some(x) => Err(ParamError::new(
                    name,
                    format!("must be finite and >= 0, got {x}"),
                )),
                None => Ok(()),
            }
        };
        let positive = |name: &str, x: f64| {
            if x.is_finite() && x > 0.0 {
                Ok(x)
            } else {
                Err(ParamError::new(
                    name,
                    format!("must be a finite number > 0, got {x}"),
                ))
            }
        };
        let sigma = |a: usize, b: usize| 0.5 * (diameters[a] + diameters[b]);
        let lj = |epsilon: &[f64], cutoff: f64| {
            let mut p = Vec::with_capacity(pairs);
            for a in 0..n {
                for b in a..n {
                    let s = sigma(a, b);
                    p.push(LjParams {
                        epsilon: epsilon[p.len()],
                        sigma: s,
                        r_cut: cutoff * s,
                    });
                }
            }
            LennardJones::new(n, &p)
        };
        let table = |f: &dyn Fn(usize, usize) -> [f64; 4]| {
            let mut t = vec![[0.0; 4]; n * n];
            for a in 0..n {
                for b in 0..n {
                    t[a * n + b] = f(a, b);
                }
            }
            t
        };
        let core = || lj(&vec![kt; pairs], WCA_CUTOFF);
        let d_max = diameters.iter().copied().fold(0.0, f64::max);
        Ok(match self {
            PairSpec::Wca { epsilon } => {
                per_pair("epsilon", epsilon)?;
                Interaction::Lj(lj(epsilon, WCA_CUTOFF))
            }
            PairSpec::Lj { epsilon, cutoff } => {
                per_pair("epsilon", epsilon)?;
                if !(cutoff.is_finite() && *cutoff >= 1.0) {
                    return Err(ParamError::new(
                        "cutoff",
                        format!("must be at least 1 contact distance, got {cutoff}"),
                    ));
                }
                Interaction::Lj(lj(epsilon, *cutoff))
            }
            PairSpec::Yukawa {
                charges,
                bjerrum_length,
                debye_length,
                range,
            } => {
                if charges.len() != n || charges.iter().any(|z| !z.is_finite()) {
                    return Err(ParamError::new(
                        "charges",
                        format!(
                            "needs one finite charge number per species ({n}), got {charges:?}"
                        ),
                    ));
                }
                let lb = positive("bjerrum_length", *bjerrum_length)?;
                let kappa = 1.0 / positive("debye_length", *debye_length)?;
                let range = positive("range", *range)?;
                let g: Vec<f64> = diameters
                    .iter()
                    .map(|d| (0.5 * kappa * d).exp() / (1.0 + 0.5 * kappa * d))
                    .collect();
                let amp = |a: usize, b: usize| kt * lb * charges[a] * charges[b] * g[a] * g[b];
                if let Some(a) = (0..n).find(|&a| !amp(a, a).is_finite()) {
                    return Err(ParamError::new(
                        "debye_length",
                        format!(
                            "the DLVO prefactor of species {a} overflows (kappa a = {:.4e}): a Debye length this \
                             short against the diameter screens the charge completely; use a longer one",
                            0.5 * kappa * diameters[a]
                        ),
                    ));
                }
                Interaction::Yukawa {
                    core: core(),
                    n,
                    kappa,
                    table: table(&|a, b| {
                        let rc = sigma(a, b) + range;
                        let shift = amp(a, b) * (-kappa * rc).exp() / rc;
                        [amp(a, b), rc * rc, shift, 0.0]
                    }),
                    r_cut_max: d_max + range,
                }
            }
            PairSpec::Morse {
                depth,
                kappa,
                h0,
                h_cut,
            } => {
                if !(depth.is_finite() && *depth >= 0.0) {
                    return Err(ParamError::new(
                        "depth",
                        format!("must be finite and >= 0, got {depth}"),
                    ));
                }
                let kappa = positive("kappa", *kappa)?;
                if !h0.is_finite()
                    || *h0 <= -0.5 * diameters.iter().copied().fold(f64::INFINITY, f64::min)
                {
                    return Err(ParamError::new(
                        "h0",
                        format!(
                            "must be finite and above minus half the smallest diameter, got {h0}"
                        ),
                    ));
                }
                if !(h_cut.is_finite() && *h_cut > *h0) {
                    return Err(ParamError::new(
                        "range",
                        format!("the cut-off must lie beyond h0 = {h0}, got {h_cut}"),
                    ));
                }
                Interaction::Morse {
                    n,
                    depth: *depth,
                    kappa,
                    h0: *h0,
                    h_cut: *h_cut,
                    shift: morse_u(*depth, kappa, h_cut - h0),
                    sigma: table(&|a, b| [sigma(a, b), 0.0, 0.0, 0.0]),
                    r_cut_max: d_max + h_cut,
                }
            }
            PairSpec::Ao {
                depletant_diameter,
                depletant_fraction,
            } => {
                let sp = positive("depletant_diameter", *depletant_diameter)?;
                if !(depletant_fraction.is_finite() && *depletant_fraction >= 0.0) {
                    return Err(ParamError::new(
                        "depletant_fraction",
                        format!("must be finite and >= 0, got {depletant_fraction}"),
                    ));
                }
                let np_kt = kt * 6.0 * depletant_fraction / (PI * sp.powi(3));
                Interaction::Ao {
                    core: core(),
                    n,
                    np_kt,
                    table: table(&|a, b| {
                        let (ra, rb) = (0.5 * (diameters[a] + sp), 0.5 * (diameters[b] + sp));
                        [ra, rb, (ra + rb) * (ra + rb), 0.0]
                    }),
                    r_cut_max: d_max + sp,
                }
            }
            PairSpec::Table { r, energy, force } => {
                Interaction::Table(Tabulated::new(n, r, energy, force)?)
            }
        })
    }
}

/// Morse energy at surface distance `x = h - h0` from the minimum.
#[inline(always)]
fn morse_u(depth: f64, kappa: f64, x: f64) -> f64 {
    let e = (-kappa * x).exp();
    depth * (e * e - 2.0 * e)
}

/// Volume of the lens in which spheres of radii `a` and `b` at centre distance `r` overlap.
#[inline(always)]
pub fn lens_volume(a: f64, b: f64, r: f64) -> f64 {
    if r >= a + b {
        0.0
    } else if r <= (a - b).abs() {
        4.0 / 3.0 * PI * a.min(b).powi(3)
    } else {
        let s = a + b - r;
        PI * s * s * (r * r + 2.0 * r * (a + b) - 3.0 * (a - b) * (a - b)) / (12.0 * r)
    }
}

/// `-dV_ov/dr` of [`lens_volume`] (zero outside the partial overlap).
#[inline(always)]
fn lens_volume_slope(a: f64, b: f64, r: f64) -> f64 {
    if r >= a + b || r <= (a - b).abs() {
        return 0.0;
    }
    // dV/dr = -pi (r^2 - (a - b)^2)((a + b)^2 - r^2) / (4 r^2) ... written from V above.
    let (p, m) = ((a + b) * (a + b), (a - b) * (a - b));
    PI * (r * r - m) * (p - r * r) / (4.0 * r * r)
}

/// A tabulated pair interaction (see the module documentation).
#[derive(Debug, Clone)]
pub struct Tabulated {
    n: usize,
    r0: f64,
    dr: f64,
    r_last: f64,
    /// Per ordered species pair, `(U, F)` on the grid.
    rows: Vec<Vec<[f64; 2]>>,
}

impl Tabulated {
    fn new(
        n: usize,
        r: &[f64],
        energy: &[Vec<f64>],
        force: &[Vec<f64>],
    ) -> Result<Self, ParamError> {
        let pairs = n * (n + 1) / 2;
        if r.len() < 2 {
            return Err(ParamError::new("table", "needs at least two rows of r"));
        }
        if energy.len() != pairs || force.len() != pairs {
            return Err(ParamError::new(
                "table",
                format!(
                    "needs an energy and a force column per unordered species pair ({pairs}), got {} and {}",
                    energy.len(),
                    force.len()
                ),
            ));
        }
        let dr = (r[r.len() - 1] - r[0]) / (r.len() - 1) as f64;
        if !(r[0].is_finite() && r[0] > 0.0 && dr.is_finite() && dr > 0.0) {
            return Err(ParamError::new(
                "table",
                format!(
                    "r must start above 0 and increase, got r from {} to {}",
                    r[0],
                    r[r.len() - 1]
                ),
            ));
        }
        if let Some(k) = (0..r.len()).find(|&k| (r[k] - (r[0] + k as f64 * dr)).abs() > 1e-6 * dr) {
            return Err(ParamError::new(
                "table",
                format!(
                    "r must be uniformly spaced (spacing {dr:.6e}); row {} has r = {}",
                    k + 1,
                    r[k]
                ),
            ));
        }
        for (c, col) in energy.iter().chain(force).enumerate() {
            if col.len() != r.len() {
                return Err(ParamError::new(
                    "table",
                    format!(
                        "column {c} has {} values for {} values of r",
                        col.len(),
                        r.len()
                    ),
                ));
            }
            if let Some(k) = col.iter().position(|x| !x.is_finite()) {
                return Err(ParamError::new(
                    "table",
                    format!("row {} holds a value that is not finite", k + 1),
                ));
            }
        }
        let mut rows = vec![Vec::new(); n * n];
        let mut k = 0;
        for a in 0..n {
            for b in a..n {
                let row: Vec<[f64; 2]> = energy[k]
                    .iter()
                    .zip(&force[k])
                    .map(|(u, f)| [*u, *f])
                    .collect();
                rows[a * n + b] = row.clone();
                rows[b * n + a] = row;
                k += 1;
            }
        }
        Ok(Self {
            n,
            r0: r[0],
            dr,
            r_last: r[r.len() - 1],
            rows,
        })
    }

    /// `(U, F)` at distance `r` for the ordered pair `(ti, tj)`.
    #[inline(always)]
    fn at(&self, r: f64, ti: u32, tj: u32) -> (f64, f64) {
        if r >= self.r_last {
            return (0.0, 0.0);
        }
        let row = &self.rows[ti as usize * self.n + tj as usize];
        if r <= self.r0 {
            let [u, f] = row[0];
            return (u + f * (self.r0 - r), f);
        }
        let x = (r - self.r0) / self.dr;
        let k = (x as usize).min(row.len() - 2);
        let w = x - k as f64;
        let ([u0, f0], [u1, f1]) = (row[k], row[k + 1]);
        (u0 + w * (u1 - u0), f0 + w * (f1 - f0))
    }
}

/// A built pair interaction: the [`Pair`] the engines take.
#[derive(Debug, Clone)]
pub enum Interaction {
    /// WCA or Lennard-Jones per species pair.
    Lj(LennardJones),
    /// WCA core plus DLVO: per ordered pair `[amplitude, r_c^2, shift, -]`.
    Yukawa {
        /// The core.
        core: LennardJones,
        /// Species.
        n: usize,
        /// Inverse Debye length.
        kappa: f64,
        /// Per ordered pair.
        table: Vec<[f64; 4]>,
        /// Largest cut-off.
        r_cut_max: f64,
    },
    /// Morse on the surface distance: per ordered pair `[sigma_ij, -, -, -]`.
    Morse {
        /// Species.
        n: usize,
        /// Depth D.
        depth: f64,
        /// Inverse range.
        kappa: f64,
        /// Minimum's surface distance.
        h0: f64,
        /// Surface-distance cut-off.
        h_cut: f64,
        /// Energy at the cut-off (subtracted).
        shift: f64,
        /// Per ordered pair.
        sigma: Vec<[f64; 4]>,
        /// Largest cut-off.
        r_cut_max: f64,
    },
    /// WCA core plus Asakura–Oosawa: per ordered pair `[A, B, (A + B)^2, -]`.
    Ao {
        /// The core.
        core: LennardJones,
        /// Species.
        n: usize,
        /// `n_p kT`.
        np_kt: f64,
        /// Per ordered pair.
        table: Vec<[f64; 4]>,
        /// Largest cut-off.
        r_cut_max: f64,
    },
    /// Tabulated.
    Table(Tabulated),
}

impl Pair for Interaction {
    fn r_cut_max(&self) -> f64 {
        match self {
            Interaction::Lj(lj) => lj.r_cut_max(),
            Interaction::Yukawa { r_cut_max, .. }
            | Interaction::Morse { r_cut_max, .. }
            | Interaction::Ao { r_cut_max, .. } => *r_cut_max,
            Interaction::Table(t) => t.r_last,
        }
    }

    #[inline(always)]
    fn force_over_r(&self, r2: f64, ti: u32, tj: u32, di: f64, dj: f64) -> f64 {
        match self {
            Interaction::Lj(lj) => lj.force_over_r(r2, ti, tj, di, dj),
            Interaction::Yukawa {
                core,
                n,
                kappa,
                table,
                ..
            } => {
                let [amp, rc2, _, _] = table[ti as usize * n + tj as usize];
                let mut f = core.force_over_r(r2, ti, tj, di, dj);
                if r2 < rc2 {
                    let r = r2.sqrt();
                    // -dU/dr = A e^(-kappa r) (1 + kappa r) / r^2.
                    f += amp * (-kappa * r).exp() * (1.0 + kappa * r) / (r2 * r);
                }
                f
            }
            Interaction::Morse {
                n,
                depth,
                kappa,
                h0,
                h_cut,
                sigma,
                ..
            } => {
                let r = r2.sqrt();
                let h = r - sigma[ti as usize * n + tj as usize][0];
                if h >= *h_cut {
                    return 0.0;
                }
                let e = (-kappa * (h - h0)).exp();
                // -dU/dh = 2 D k (e^2 - e).
                2.0 * depth * kappa * (e * e - e) / r
            }
            Interaction::Ao {
                core,
                n,
                np_kt,
                table,
                ..
            } => {
                let [a, b, c2, _] = table[ti as usize * n + tj as usize];
                let mut f = core.force_over_r(r2, ti, tj, di, dj);
                if r2 < c2 {
                    let r = r2.sqrt();
                    // F = -dU/dr = n_p kT dV_ov/dr = -n_p kT (lens slope).
                    f -= np_kt * lens_volume_slope(a, b, r) / r;
                }
                f
            }
            Interaction::Table(t) => {
                let r = r2.sqrt();
                t.at(r, ti, tj).1 / r
            }
        }
    }

    fn energy(&self, r2: f64, ti: u32, tj: u32, di: f64, dj: f64) -> f64 {
        match self {
            Interaction::Lj(lj) => lj.energy(r2, ti, tj, di, dj),
            Interaction::Yukawa {
                core,
                n,
                kappa,
                table,
                ..
            } => {
                let [amp, rc2, shift, _] = table[ti as usize * n + tj as usize];
                let mut u = core.energy(r2, ti, tj, di, dj);
                if r2 < rc2 {
                    let r = r2.sqrt();
                    u += amp * (-kappa * r).exp() / r - shift;
                }
                u
            }
            Interaction::Morse {
                n,
                depth,
                kappa,
                h0,
                h_cut,
                shift,
                sigma,
                ..
            } => {
                let h = r2.sqrt() - sigma[ti as usize * n + tj as usize][0];
                if h >= *h_cut {
                    return 0.0;
                }
                morse_u(*depth, *kappa, h - h0) - shift
            }
            Interaction::Ao {
                core,
                n,
                np_kt,
                table,
                ..
            } => {
                let [a, b, _, _] = table[ti as usize * n + tj as usize];
                core.energy(r2, ti, tj, di, dj) - np_kt * lens_volume(a, b, r2.sqrt())
            }
            Interaction::Table(t) => t.at(r2.sqrt(), ti, tj).0,
        }
    }
}

/// Second virial coefficient `B2 = -2 pi int_0^rc (e^(-U/kT) - 1) r^2 dr` of the pair
/// `(ti, tj)` (diameters `di`, `dj`) by the composite Simpson rule on `steps` intervals (even).
pub fn second_virial(
    p: &impl Pair,
    ti: u32,
    tj: u32,
    di: f64,
    dj: f64,
    kt: f64,
    steps: usize,
) -> f64 {
    let rc = p.r_cut_max();
    let h = rc / steps as f64;
    let f = |r: f64| {
        if r == 0.0 {
            return 0.0;
        }
        let u = p.energy(r * r, ti, tj, di, dj);
        ((-u / kt).exp() - 1.0) * r * r
    };
    let mut s = f(0.0) + f(rc);
    for k in 1..steps {
        s += f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    -2.0 * PI * s * h / 3.0
}

/// Third virial coefficient of a one-component fluid from its Mayer function
/// `f(r) = e^(-U(r)/kT) - 1` (zero beyond `r_max`):
/// `B3 = -(1/3) int int f(r12) f(r13) f(r23) dr2 dr3`, in bipolar coordinates
/// `B3 = -(8 pi^2 / 3) int_0^rmax dr int_0^rmax ds r s f(r) f(s) int_|r-s|^(r+s) t f(t) dt`
/// (e.g. Hansen & McDonald, Theory of Simple Liquids, Sec. 3.9), by the trapezoidal rule on
/// `steps` intervals: the inner integral is a difference of the cumulative sum of `t f(t)`
/// at grid nodes, so the cost is `steps^2` products.
pub fn third_virial(mayer: impl Fn(f64) -> f64, r_max: f64, steps: usize) -> f64 {
    let h = r_max / steps as f64;
    let tf: Vec<f64> = (0..=steps)
        .map(|k| k as f64 * h * mayer(k as f64 * h))
        .collect();
    // cum[k] = int_0^(k h) t f(t) dt; beyond r_max, f = 0.
    let mut cum = vec![0.0; 2 * steps + 1];
    for k in 1..cum.len() {
        cum[k] = cum[k - 1]
            + if k <= steps {
                0.5 * h * (tf[k - 1] + tf[k])
            } else {
                0.0
            };
    }
    let weight = |k: usize| if k == 0 || k == steps { 0.5 } else { 1.0 };
    let mut sum = 0.0;
    for i in 0..=steps {
        let mut row = 0.0;
        for j in 0..=steps {
            row += weight(j) * tf[j] * (cum[i + j] - cum[i.abs_diff(j)]);
        }
        sum += weight(i) * tf[i] * row;
    }
    -8.0 * PI * PI / 3.0 * sum * h * h
}

#[cfg(test)]
mod tests {
    use super::*;

    const D: [f64; 2] = [1.0, 2.0];

    fn all_kinds() -> Vec<PairSpec> {
        let r: Vec<f64> = (0..200).map(|k| 0.8 + 0.01 * k as f64).collect();
        let col = |s: f64| -> (Vec<f64>, Vec<f64>) {
            r.iter()
                .map(|x| {
                    let e = (-(x - s)).exp();
                    (e, e)
                })
                .unzip()
        };
        let (u0, f0) = col(1.0);
        let (u1, f1) = col(1.5);
        let (u2, f2) = col(2.0);
        vec![
            PairSpec::wca(1.0, 2),
            PairSpec::Lj {
                epsilon: vec![1.0, 0.5, 2.0],
                cutoff: 2.5,
            },
            PairSpec::Yukawa {
                charges: vec![20.0, 50.0],
                bjerrum_length: 0.1,
                debye_length: 0.3,
                range: 2.0,
            },
            PairSpec::Morse {
                depth: 3.0,
                kappa: 8.0,
                h0: 0.05,
                h_cut: 0.6,
            },
            PairSpec::Ao {
                depletant_diameter: 0.3,
                depletant_fraction: 0.2,
            },
            PairSpec::Table {
                r: r.clone(),
                energy: vec![u0, u1, u2],
                force: vec![f0, f1, f2],
            },
        ]
    }

    #[test]
    fn every_force_is_minus_the_gradient_of_its_energy() {
        for spec in all_kinds() {
            let p = spec.build(&D, 1.0).unwrap();
            for (ti, tj) in [(0u32, 0u32), (0, 1), (1, 0), (1, 1)] {
                let (di, dj) = (D[ti as usize], D[tj as usize]);
                let s = 0.5 * (di + dj);
                for k in 0..200 {
                    let r = s * 0.97 + (p.r_cut_max() - s * 0.97) * (k as f64 + 0.5) / 200.0;
                    let h = 1e-6 * r;
                    let du = (p.energy((r + h) * (r + h), ti, tj, di, dj)
                        - p.energy((r - h) * (r - h), ti, tj, di, dj))
                        / (2.0 * h);
                    let f = p.force_over_r(r * r, ti, tj, di, dj) * r;
                    // The table's force is its own column (-dU/dr of e^-(r - s)) interpolated, its
                    // energy's slope the secant of a cell: they differ by up to dr |U''| / 2 =
                    // 0.5 % here; the others are analytic.
                    let tol = if spec.kind() == "table" { 6e-3 } else { 2e-5 };
                    assert!(
                        (f + du).abs() <= tol * (1.0 + du.abs()),
                        "{}: pair {ti}{tj}, r {r}: F {f} vs -dU/dr {}",
                        spec.kind(),
                        -du
                    );
                }
                // Continuous at the cut-off, zero beyond it.
                let rc = p.r_cut_max();
                assert_eq!(p.force_over_r(rc * rc * 1.0001, ti, tj, di, dj), 0.0);
                assert_eq!(p.energy(rc * rc * 1.0001, ti, tj, di, dj), 0.0);
            }
        }
    }

    #[test]
    fn one_species_wca_is_todays_wca_bit_for_bit() {
        assert_eq!(WCA_CUTOFF, 2f64.powf(1.0 / 6.0));
        let Interaction::Lj(lj) = PairSpec::wca(1.3, 1).build(&[1.7], 1.3).unwrap() else {
            panic!()
        };
        let old = LennardJones::wca(1.3, 1.7);
        for k in 0..100 {
            let r2 = (1.4 + 0.005 * k as f64).powi(2);
            assert_eq!(
                lj.force_over_r(r2, 0, 0, 1.7, 1.7).to_bits(),
                old.force_over_r(r2, 0, 0, 1.7, 1.7).to_bits()
            );
        }
    }

    /// The bipolar quadrature against the exact hard-sphere value `B3 = 5 pi^2 sigma^6 / 18`
    /// (sigma = 1.5) at two grid sizes, converging at first order in the step (the Mayer
    /// function's jump).
    #[test]
    fn third_virial_of_hard_spheres_is_exact() {
        let exact = 5.0 * PI * PI / 18.0 * 1.5f64.powi(6);
        let hs = |r: f64| if r < 1.5 { -1.0 } else { 0.0 };
        let err = |steps| third_virial(hs, 3.0, steps) / exact - 1.0;
        let (coarse, fine) = (err(1000), err(4000));
        assert!(coarse.abs() < 8e-3 && fine.abs() < 2e-3, "{coarse}, {fine}");
        // First order: four times the points, a quarter of the error.
        assert!((3.5..4.5).contains(&(coarse / fine)), "{coarse}, {fine}");
        // Broken on purpose: a diameter 1 % larger is outside the tolerance.
        let b3 = third_virial(|r| if r < 1.515 { -1.0 } else { 0.0 }, 3.0, 4000);
        assert!((b3 / exact - 1.0).abs() > 0.05, "{b3}");
    }

    #[test]
    fn lennard_jones_second_virial_against_the_exact_series() {
        // Full LJ, from the one cut and shifted at r_c = 12 sigma with its two corrections to first
        // order: the shift delta = U(r_c) (+2 pi delta/kT r_c^3 / 3) and the tail beyond r_c
        // (-8 pi eps sigma^6 / (3 kT r_c^3)). B2 / (2 pi sigma^3 / 3) =
        // -sum_j 2^(j + 1/2) / (4 j!) Gamma((2j - 1)/4) T^(-(2j + 1)/4) (e.g. Hirschfelder,
        // Curtiss & Bird 1954, Eq. 3.6-9), at T* = 1 and 2, for the AB pair of diameters 1 and 2.
        fn gamma(x: f64) -> f64 {
            // Lanczos (g = 7, n = 9), with reflection below 1/2.
            const C: [f64; 9] = [
                0.999_999_999_999_809_9,
                676.520_368_121_885_1,
                -1_259.139_216_722_402_8,
                771.323_428_777_653_1,
                -176.615_029_162_140_6,
                12.507_343_278_686_905,
                -0.138_571_095_265_720_12,
                9.984_369_578_019_572e-6,
                1.505_632_735_149_311_6e-7,
            ];
            if x < 0.5 {
                return PI / ((PI * x).sin() * gamma(1.0 - x));
            }
            let x = x - 1.0;
            let mut a = C[0];
            let t = x + 7.5;
            for (i, c) in C.iter().enumerate().skip(1) {
                a += c / (x + i as f64);
            }
            (2.0 * PI).sqrt() * t.powf(x + 0.5) * (-t).exp() * a
        }
        for t in [1.0f64, 2.0] {
            let mut series = 0.0;
            let mut fact = 1.0;
            for j in 0..60 {
                if j > 0 {
                    fact *= j as f64;
                }
                series -= 2f64.powf(j as f64 + 0.5) / (4.0 * fact)
                    * gamma((2.0 * j as f64 - 1.0) / 4.0)
                    * t.powf(-(2.0 * j as f64 + 1.0) / 4.0);
            }
            let p = PairSpec::Lj {
                epsilon: vec![t.recip(); 3],
                cutoff: 12.0,
            }
            .build(&D, 1.0)
            .unwrap();
            let s: f64 = 1.5;
            let (rc, eps) = (12.0 * s, t.recip());
            let delta = 4.0 * eps * ((s / rc).powi(12) - (s / rc).powi(6));
            let b2 = (second_virial(&p, 0, 1, 1.0, 2.0, 1.0, 400_000)
                + 2.0 * PI * delta * rc.powi(3) / 3.0
                - 8.0 * PI * eps * s.powi(6) / (3.0 * rc.powi(3)))
                / (2.0 * PI * s.powi(3) / 3.0);
            assert!(
                (b2 - series).abs() < 1e-5,
                "T* {t}: B2* {b2} vs series {series}"
            );
        }
    }

    #[test]
    fn ao_lens_volume_against_a_numerical_integral() {
        // Cylindrical slices of the lens of spheres of radii a (at 0) and b (at r) along the axis.
        for (a, b, r) in [
            (0.65f64, 1.15f64, 1.6f64),
            (0.65, 0.65, 1.1),
            (1.15, 1.15, 2.05),
            (0.6, 1.2, 0.7),
        ] {
            let m = 200_000;
            let (lo, hi) = ((r - b).max(-a), a.min(r + b));
            let h = (hi - lo) / m as f64;
            let mut v = 0.0;
            for k in 0..m {
                let x = lo + (k as f64 + 0.5) * h;
                let ra = a * a - x * x;
                let rb = b * b - (x - r) * (x - r);
                v += PI * ra.min(rb).max(0.0) * h;
            }
            assert!(
                (lens_volume(a, b, r) - v).abs() < 1e-6 * v,
                "{a} {b} {r}: {} vs {v}",
                lens_volume(a, b, r)
            );
        }
        // The monodisperse AO contact value -phi_p kT (1 + 1/q)^3 [1 - 3 (1 + q) ... ] at q = 0.3:
        // U(d) = -n_p kT V_ov(d) with V_ov(d) = (pi/12)(d_p)^2 (2 R_d + ... ) checked through the lens.
        let p = PairSpec::Ao {
            depletant_diameter: 0.3,
            depletant_fraction: 0.2,
        }
        .build(&[1.0], 1.0)
        .unwrap();
        let (q, phi) = (0.3f64, 0.2);
        // Closed form at contact r = d = 1 for equal spheres (Lekkerkerker & Tuinier 2011, Eq. 2.11
        // with r = sigma): U = -phi_p kT ((1 + q)/q)^3 [1 - 3/(2(1 + q)) + 1/(2 (1 + q)^3)].
        let closed =
            -phi * ((1.0 + q) / q).powi(3) * (1.0 - 1.5 / (1.0 + q) + 0.5 / (1.0 + q).powi(3));
        let wca_at_contact = 1.0;
        assert!((p.energy(1.0, 0, 0, 1.0, 1.0) - (closed + wca_at_contact)).abs() < 1e-12);
    }

    #[test]
    fn dlvo_prefactor_and_refusals() {
        let p = PairSpec::Yukawa {
            charges: vec![10.0, -5.0],
            bjerrum_length: 0.7,
            debye_length: 0.5,
            range: 3.0,
        }
        .build(&D, 2.0)
        .unwrap();
        let (k, r) = (2.0f64, 2.0);
        let g = |d: f64| (0.5 * k * d).exp() / (1.0 + 0.5 * k * d);
        let rc = 1.5 + 3.0;
        let want =
            2.0 * 0.7 * 10.0 * -5.0 * g(1.0) * g(2.0) * ((-k * r).exp() / r - (-k * rc).exp() / rc);
        assert!((p.energy(r * r, 0, 1, 1.0, 2.0) - want).abs() < 1e-12 * want.abs());
        for (spec, key) in [
            (
                PairSpec::Wca {
                    epsilon: vec![1.0, 1.0],
                },
                "epsilon",
            ),
            (
                PairSpec::Lj {
                    epsilon: vec![1.0; 3],
                    cutoff: 0.5,
                },
                "cutoff",
            ),
            (
                PairSpec::Yukawa {
                    charges: vec![1.0],
                    bjerrum_length: 1.0,
                    debye_length: 1.0,
                    range: 1.0,
                },
                "charges",
            ),
            (
                PairSpec::Yukawa {
                    charges: vec![1.0, 1.0],
                    bjerrum_length: 1.0,
                    debye_length: 1e-5,
                    range: 1.0,
                },
                "debye_length",
            ),
            (
                PairSpec::Ao {
                    depletant_diameter: 0.0,
                    depletant_fraction: 0.1,
                },
                "depletant_diameter",
            ),
            (
                PairSpec::Table {
                    r: vec![1.0, 1.1, 1.3],
                    energy: vec![vec![0.0; 3]; 3],
                    force: vec![vec![0.0; 3]; 3],
                },
                "table",
            ),
        ] {
            let e = spec.build(&D, 1.0).unwrap_err();
            assert_eq!(e.key, key, "{e}");
        }
    }
}
