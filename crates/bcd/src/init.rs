//! Initial configurations of N rods of length sigma on [0, L).

use crate::engine::{BcdConfig, Boundary};
use colloidsim_core::ParamError;
use colloidsim_core::rng::{Purpose, stream};
use rand::RngExt;

/// Equilibrium hard-rod configuration without a field: the free length `L - N sigma` (between
/// walls `L - N sigma`, rods touching a wall allowed) is shared by N uniform points, which is the
/// exact Tonks-gas distribution. On the ring a uniform random offset is added.
pub fn random(cfg: &BcdConfig, n: usize, seed: u32) -> Result<Vec<f64>, ParamError> {
    cfg.validate(n)?;
    let free = cfg.length - n as f64 * cfg.sigma;
    let mut rng = stream(seed, 0, Purpose::Initial, 0);
    let mut u: Vec<f64> = (0..n).map(|_| rng.random::<f64>() * free).collect();
    u.sort_by(f64::total_cmp);
    let offset = match cfg.boundary {
        Boundary::Periodic => rng.random::<f64>() * cfg.length,
        Boundary::Walls => 0.5 * cfg.sigma,
    };
    Ok(u.iter()
        .enumerate()
        .map(|(i, ui)| offset + ui + i as f64 * cfg.sigma)
        .collect())
}

/// Evenly spaced rods, centres at `(i + 1/2) L / N`.
pub fn lattice(cfg: &BcdConfig, n: usize) -> Result<Vec<f64>, ParamError> {
    cfg.validate(n)?;
    let a = cfg.length / n as f64;
    Ok((0..n).map(|i| (i as f64 + 0.5) * a).collect())
}

/// Prepare positions read from a file: sort them and, on the ring, fold them into [0, L).
/// Overlaps are reported by the engine with the rods concerned.
pub fn from_positions(cfg: &BcdConfig, mut x: Vec<f64>) -> Result<Vec<f64>, ParamError> {
    cfg.validate(x.len())?;
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(ParamError::new(
            "positions",
            format!("position #{i} is not a finite number"),
        ));
    }
    if cfg.boundary == Boundary::Periodic {
        for v in &mut x {
            *v = v.rem_euclid(cfg.length);
        }
    }
    x.sort_by(f64::total_cmp);
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::Update;

    fn cfg(boundary: Boundary) -> BcdConfig {
        BcdConfig {
            length: 10.0,
            sigma: 0.9,
            mobility: 1.0,
            kt: 1.0,
            dt: 1e-3,
            boundary,
            seed: 1,
            update: Update::Premerge,
        }
    }

    #[test]
    fn random_configurations_respect_the_hard_core() {
        for b in [Boundary::Periodic, Boundary::Walls] {
            let c = cfg(b);
            let x = random(&c, 11, 3).unwrap();
            assert!(x.windows(2).all(|w| w[1] - w[0] >= c.sigma - 1e-12));
            if b == Boundary::Walls {
                assert!(x[0] >= 0.45 && x[10] <= 10.0 - 0.45 + 1e-12);
            } else {
                assert!(x[0] + c.length - x[10] >= c.sigma - 1e-12);
            }
        }
        assert!(random(&cfg(Boundary::Periodic), 12, 3).is_err()); // 12 * 0.9 > 10
    }
}
