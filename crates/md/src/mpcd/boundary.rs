//! Walls of the MPCD solvent: the drying droplet's sphere R(t) and, for validation, a planar
//! slab; bounce-back during streaming and the cells they cut (virtual particles).
//!
//! A solvent particle that ends a streaming step outside the fluid region is returned to the
//! point where it crossed the wall, its velocity is reflected relative to the wall velocity `V`
//! at that point (the drying-droplet paper, docs/references.md; Whitmer & Luijten, J. Phys.: Condens. Matter 22, 104106
//! (2010)):
//!
//! - slip: `v' = v - 2 ((v - V) . n) n` (the normal part of the relative velocity reversed),
//! - no-slip: `v' = 2 V - v` (the whole relative velocity reversed; `V = V_n n` for the sphere),
//!
//! and it streams on with `v'` for the time it spent outside. For the moving sphere the wall's
//! radial velocity is taken as its mean over the streaming step, so that the crossing time is
//! the smaller root of a quadratic (the paper's Eqs. 22–23).

use crate::potential::SphereAreaLaw;
use serde::{Deserialize, Serialize};

/// How the solvent meets a wall.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum WallKind {
    /// Only the normal part of the velocity relative to the wall is reversed.
    Slip,
    /// The whole velocity relative to the wall is reversed.
    NoSlip,
}

/// What confines the solvent (besides the periodic box).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Confinement {
    /// Nothing: the solvent fills the periodic box.
    None,
    /// The inside of a sphere centred on the origin whose radius follows `law` (the droplet).
    Sphere {
        /// Radius against time.
        law: SphereAreaLaw,
        /// Boundary condition.
        kind: WallKind,
    },
    /// Between the static planes `z = -half_width` and `z = +half_width` (validation).
    Slab {
        /// Half the distance between the walls.
        half_width: f64,
        /// Boundary condition.
        kind: WallKind,
    },
}

/// Most reflections of one particle in one streaming step before it is put back by hand
/// (counted in [`Bounce::stuck`]).
pub const MAX_BOUNCES: u32 = 16;

/// The outcome of streaming one particle against a wall.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounce {
    /// Reflections in this step.
    pub count: u32,
    /// The particle was still outside after [`MAX_BOUNCES`] reflections and was placed just
    /// inside along the wall normal.
    pub stuck: bool,
}

impl Confinement {
    /// Is `x` inside the fluid region at time `t` (the wall itself counts as inside)?
    #[inline(always)]
    pub fn inside(&self, x: [f64; 3], t: f64) -> bool {
        match *self {
            Confinement::None => true,
            Confinement::Sphere { law, .. } => {
                let r = law.radius(t);
                x[0] * x[0] + x[1] * x[1] + x[2] * x[2] <= r * r
            }
            Confinement::Slab { half_width, .. } => x[2].abs() <= half_width,
        }
    }

    /// The wall kind, if there is a wall.
    pub fn kind(&self) -> Option<WallKind> {
        match *self {
            Confinement::None => None,
            Confinement::Sphere { kind, .. } | Confinement::Slab { kind, .. } => Some(kind),
        }
    }

    /// Volume of the fluid region at time `t` in a box of edges `l` (for the sphere, the
    /// droplet volume; the box must hold it).
    pub fn volume(&self, t: f64, l: [f64; 3]) -> f64 {
        match *self {
            Confinement::None => l[0] * l[1] * l[2],
            Confinement::Sphere { law, .. } => {
                4.0 / 3.0 * std::f64::consts::PI * law.radius(t).powi(3)
            }
            Confinement::Slab { half_width, .. } => l[0] * l[1] * 2.0 * half_width,
        }
    }

    /// Stream a particle that was inside at `t1 - dt` to `t1`: `x` and `v` hold the position
    /// and velocity at the start and are replaced by those at `t1` (no wrapping), reflecting
    /// from the wall on the way.
    #[inline]
    pub fn stream(&self, x: &mut [f64; 3], v: &mut [f64; 3], t1: f64, dt: f64) -> Bounce {
        for k in 0..3 {
            x[k] += v[k] * dt;
        }
        match *self {
            Confinement::None => Bounce {
                count: 0,
                stuck: false,
            },
            Confinement::Sphere { law, kind } => {
                let r1 = law.radius(t1);
                // The wall's mean radial velocity over the step.
                let speed = (r1 - law.radius(t1 - dt)) / dt;
                bounce_sphere(x, v, r1, speed, dt, kind)
            }
            Confinement::Slab { half_width, kind } => bounce_slab(x, v, half_width, dt, kind),
        }
    }
}

/// Reflect `v` at a wall point with unit normal `n` moving with velocity `wall` (a vector).
#[inline(always)]
pub fn reflect(v: [f64; 3], n: [f64; 3], wall: [f64; 3], kind: WallKind) -> [f64; 3] {
    match kind {
        WallKind::Slip => {
            let vn = (v[0] - wall[0]) * n[0] + (v[1] - wall[1]) * n[1] + (v[2] - wall[2]) * n[2];
            [
                v[0] - 2.0 * vn * n[0],
                v[1] - 2.0 * vn * n[1],
                v[2] - 2.0 * vn * n[2],
            ]
        }
        WallKind::NoSlip => [
            2.0 * wall[0] - v[0],
            2.0 * wall[1] - v[1],
            2.0 * wall[2] - v[2],
        ],
    }
}

/// Bounce-back from the inside of a sphere centred on the origin whose radius is `r1` at the
/// end of the step and moves with the constant radial velocity `speed` (`dR/dt`); `x` is the
/// position at the end of free streaming over `dt` with velocity `v`.
///
/// Going back in time by `s` from the end, the particle is at `x - v s` and the wall at radius
/// `r1 - speed s`; the most recent crossing is the smallest positive root of
/// `(v.v - speed^2) s^2 - 2 (x.v - r1 speed) s + (x.x - r1^2) = 0`, written as
/// `s = C / (B + sqrt(B^2 - A C))` (stable, and the limit `A -> 0` needs no special case).
pub fn bounce_sphere(
    x: &mut [f64; 3],
    v: &mut [f64; 3],
    r1: f64,
    speed: f64,
    dt: f64,
    kind: WallKind,
) -> Bounce {
    let mut count = 0;
    // Time left in the step after the last reflection (the particle is inside before it).
    let mut left = dt;
    loop {
        let c = x[0] * x[0] + x[1] * x[1] + x[2] * x[2] - r1 * r1;
        if c <= 0.0 {
            return Bounce {
                count,
                stuck: false,
            };
        }
        if count == MAX_BOUNCES {
            let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
            let f = r1 * (1.0 - 1e-12) / r;
            for k in 0..3 {
                x[k] *= f;
            }
            return Bounce { count, stuck: true };
        }
        let a = v[0] * v[0] + v[1] * v[1] + v[2] * v[2] - speed * speed;
        let b = x[0] * v[0] + x[1] * v[1] + x[2] * v[2] - r1 * speed;
        let disc = (b * b - a * c).max(0.0);
        let denom = b + disc.sqrt();
        let s = if denom > 0.0 {
            (c / denom).min(left)
        } else {
            left
        };
        let xc = [x[0] - v[0] * s, x[1] - v[1] * s, x[2] - v[2] * s];
        let rc = (xc[0] * xc[0] + xc[1] * xc[1] + xc[2] * xc[2]).sqrt();
        let n = if rc > 0.0 {
            [xc[0] / rc, xc[1] / rc, xc[2] / rc]
        } else {
            [0.0, 0.0, 1.0]
        };
        let wall_v = [speed * n[0], speed * n[1], speed * n[2]];
        *v = reflect(*v, n, wall_v, kind);
        for k in 0..3 {
            x[k] = xc[k] + v[k] * s;
        }
        left = s;
        count += 1;
    }
}

/// Bounce-back between the static planes `z = -h` and `z = +h`; `x` is the position at the
/// end of free streaming over `dt` with velocity `v`.
pub fn bounce_slab(x: &mut [f64; 3], v: &mut [f64; 3], h: f64, dt: f64, kind: WallKind) -> Bounce {
    let mut count = 0;
    let mut left = dt;
    loop {
        let over = x[2].abs() - h;
        if over <= 0.0 {
            return Bounce {
                count,
                stuck: false,
            };
        }
        if count == MAX_BOUNCES || v[2] == 0.0 {
            x[2] = h.copysign(x[2]) * (1.0 - 1e-12);
            return Bounce { count, stuck: true };
        }
        let s = (over / v[2].abs()).min(left);
        let n = [0.0, 0.0, x[2].signum()];
        let xc = [x[0] - v[0] * s, x[1] - v[1] * s, x[2] - v[2] * s];
        *v = reflect(*v, n, [0.0; 3], kind);
        for k in 0..3 {
            x[k] = xc[k] + v[k] * s;
        }
        left = s;
        count += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }

    /// A particle crossing a moving sphere ends inside with the reflected relative velocity:
    /// checked against the crossing point found by bisection on the exact kinematics.
    #[test]
    fn a_particle_crossing_a_moving_sphere_ends_inside_with_the_reflected_relative_velocity() {
        let dt = 0.1;
        for (speed, kind) in [
            (-0.4, WallKind::Slip),
            (-0.4, WallKind::NoSlip),
            (0.3, WallKind::Slip),
            (0.0, WallKind::NoSlip),
        ] {
            let r1 = 5.0;
            let r0 = r1 - speed * dt;
            let x0 = [0.3, 4.2, 1.9];
            assert!(dot(x0, x0).sqrt() < r0);
            let v0 = [1.5, 9.0, 3.0];
            let mut x = x0;
            let mut v = v0;
            for k in 0..3 {
                x[k] += v[k] * dt;
            }
            let out = bounce_sphere(&mut x, &mut v, r1, speed, dt, kind);
            assert_eq!(out.count, 1, "{kind:?} {speed}");
            assert!(!out.stuck);
            assert!(dot(x, x).sqrt() <= r1, "ends inside");
            // The crossing time by bisection: g(t) = |x0 + v0 t| - (r0 + speed t).
            let g = |t: f64| {
                let p = [x0[0] + v0[0] * t, x0[1] + v0[1] * t, x0[2] + v0[2] * t];
                dot(p, p).sqrt() - (r0 + speed * t)
            };
            let (mut lo, mut hi) = (0.0, dt);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if g(mid) < 0.0 { lo = mid } else { hi = mid }
            }
            let tc = 0.5 * (lo + hi);
            let xc = [x0[0] + v0[0] * tc, x0[1] + v0[1] * tc, x0[2] + v0[2] * tc];
            let rc = dot(xc, xc).sqrt();
            let n = [xc[0] / rc, xc[1] / rc, xc[2] / rc];
            let wall = [speed * n[0], speed * n[1], speed * n[2]];
            let rel_in = [v0[0] - wall[0], v0[1] - wall[1], v0[2] - wall[2]];
            let rel_out = [v[0] - wall[0], v[1] - wall[1], v[2] - wall[2]];
            // Normal part reversed in both cases.
            assert!((dot(rel_out, n) + dot(rel_in, n)).abs() < 1e-9, "{kind:?}");
            let tang = |r: [f64; 3]| {
                let s = dot(r, n);
                [r[0] - s * n[0], r[1] - s * n[1], r[2] - s * n[2]]
            };
            let (ti, to) = (tang(rel_in), tang(rel_out));
            for k in 0..3 {
                match kind {
                    WallKind::Slip => assert!((to[k] - ti[k]).abs() < 1e-9),
                    WallKind::NoSlip => assert!((to[k] + ti[k]).abs() < 1e-9),
                }
            }
            // It streamed on from the crossing point for the rest of the step.
            for k in 0..3 {
                assert!(
                    (x[k] - (xc[k] + v[k] * (dt - tc))).abs() < 1e-9,
                    "{kind:?} {k}"
                );
            }
            // A particle that stays inside is untouched.
            let (mut xi, mut vi) = ([0.1, 0.2, 0.3], [1.0, 1.0, 1.0]);
            assert_eq!(
                bounce_sphere(&mut xi, &mut vi, r1, speed, dt, kind).count,
                0
            );
            assert_eq!(vi, [1.0, 1.0, 1.0]);
        }
    }

    #[test]
    fn a_particle_overtaken_by_a_shrinking_wall_is_pushed_inside() {
        // At rest just inside a wall that moves in faster than the particle: the crossing root
        // with A = v.v - V^2 < 0.
        let (dt, speed, r1) = (0.1, -2.0, 5.0);
        let x = [0.0, 0.0, 5.1];
        let v = [0.0, 0.0, 0.05];
        for kind in [WallKind::Slip, WallKind::NoSlip] {
            let (mut xx, mut vv) = (x, v);
            let b = bounce_sphere(&mut xx, &mut vv, r1, speed, dt, kind);
            assert!(b.count >= 1 && !b.stuck);
            assert!(xx[2] <= r1);
            // Relative normal velocity reversed: v' - V = -(v - V) along z.
            assert!((vv[2] - speed + (0.05 - speed)).abs() < 1e-12, "{vv:?}");
        }
        // And the slab (static): a slow particle that starts just inside.
        let mut x = [0.0, 0.0, 4.999 + 0.05 * dt];
        let mut v = [0.0, 0.0, 0.05];
        let b = bounce_slab(&mut x, &mut v, 5.0, dt, WallKind::NoSlip);
        assert_eq!(b.count, 1);
        assert!(x[2] <= 5.0 && v[2] == -0.05);
        assert!((x[2] - (5.0 - 0.004)).abs() < 1e-12, "{x:?}");
    }

    /// Many random crossings of a shrinking, a static and a growing sphere: every particle
    /// ends inside, at the distance from the crossing point that the rest of the step gives,
    /// and with the relative velocity reflected (its magnitude kept; slip: tangential part
    /// kept; no-slip: reversed).
    #[test]
    fn random_crossings_of_a_moving_sphere_obey_the_reflection_laws() {
        use rand::RngExt;
        let mut rng = colloidsim_core::rng::stream(9, 0, colloidsim_core::rng::Purpose::Moves, 0);
        let (dt, r1) = (0.1, 4.0);
        let mut single = 0;
        for trial in 0..20_000 {
            let speed = [-1.5, 0.0, 0.8][trial % 3];
            let kind = if trial % 2 == 0 {
                WallKind::Slip
            } else {
                WallKind::NoSlip
            };
            let r0 = r1 - speed * dt;
            // Start inside the sphere of the start of the step, near its wall.
            let dir = {
                let d: [f64; 3] = std::array::from_fn(|_| rng.random::<f64>() - 0.5);
                let n = dot(d, d).sqrt();
                d.map(|x| x / n)
            };
            let x0 = dir.map(|x| x * r0 * (1.0 - 0.1 * rng.random::<f64>()));
            let v0: [f64; 3] = std::array::from_fn(|_| 20.0 * (rng.random::<f64>() - 0.5));
            let (mut x, mut v) = (x0, v0);
            for k in 0..3 {
                x[k] += v[k] * dt;
            }
            let b = bounce_sphere(&mut x, &mut v, r1, speed, dt, kind);
            assert!(!b.stuck);
            assert!(dot(x, x).sqrt() <= r1 * (1.0 + 1e-12), "{trial}: {x:?}");
            if b.count != 1 {
                continue;
            }
            single += 1;
            // Crossing by bisection on g(t) = |x0 + v0 t| - (r0 + speed t), inside at t = 0.
            let g = |t: f64| {
                let p = [x0[0] + v0[0] * t, x0[1] + v0[1] * t, x0[2] + v0[2] * t];
                dot(p, p).sqrt() - (r0 + speed * t)
            };
            let (mut lo, mut hi) = (0.0, dt);
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if g(mid) < 0.0 { lo = mid } else { hi = mid }
            }
            let tc = 0.5 * (lo + hi);
            let xc = [x0[0] + v0[0] * tc, x0[1] + v0[1] * tc, x0[2] + v0[2] * tc];
            let n = xc.map(|c| c / dot(xc, xc).sqrt());
            let wall = n.map(|c| speed * c);
            let rel_in = [v0[0] - wall[0], v0[1] - wall[1], v0[2] - wall[2]];
            let rel_out = [v[0] - wall[0], v[1] - wall[1], v[2] - wall[2]];
            let tol = 1e-7 * (1.0 + dot(v0, v0).sqrt());
            assert!((dot(rel_out, rel_out).sqrt() - dot(rel_in, rel_in).sqrt()).abs() < tol);
            assert!((dot(rel_out, n) + dot(rel_in, n)).abs() < tol, "{trial}");
            for k in 0..3 {
                let (ti, to) = (
                    rel_in[k] - dot(rel_in, n) * n[k],
                    rel_out[k] - dot(rel_out, n) * n[k],
                );
                match kind {
                    WallKind::Slip => assert!((to - ti).abs() < tol, "{trial}"),
                    WallKind::NoSlip => assert!((to + ti).abs() < tol, "{trial}"),
                }
                assert!((x[k] - (xc[k] + v[k] * (dt - tc))).abs() < 1e-7, "{trial}");
            }
        }
        // Many trials crossed exactly once (about a third).
        assert!(single > 3_000, "{single}");
    }

    /// Through [`Confinement::stream`], the wall speed is the mean of the area law over the
    /// step: a particle at rest just inside a shrinking droplet is hit and moves with twice
    /// the wall's velocity (no-slip) or its normal velocity reversed about it (slip).
    #[test]
    fn the_drying_droplet_wall_pushes_a_resting_particle_inward() {
        let law = SphereAreaLaw {
            r0: 6.0,
            alpha: 40.0,
        };
        let (t1, dt) = (2.0, 0.1);
        let (ra, rb) = (law.radius(t1 - dt), law.radius(t1));
        let speed = (rb - ra) / dt;
        assert!(speed < 0.0);
        for kind in [WallKind::Slip, WallKind::NoSlip] {
            let conf = Confinement::Sphere { law, kind };
            let mut x = [0.0, 0.5 * (ra + rb), 0.0];
            let mut v = [0.0; 3];
            let b = conf.stream(&mut x, &mut v, t1, dt);
            assert_eq!(b.count, 1);
            assert!(conf.inside(x, t1));
            // Hit halfway through the step: v' = 2 V n either way (no tangential motion).
            assert!(
                (v[1] - 2.0 * speed).abs() < 1e-12 && v[0] == 0.0 && v[2] == 0.0,
                "{v:?}"
            );
            assert!(
                (x[1] - (0.5 * (ra + rb) + v[1] * 0.5 * dt)).abs() < 1e-9,
                "{x:?}"
            );
        }
    }

    #[test]
    fn slab_walls_reflect_slip_and_no_slip() {
        let conf = |kind| Confinement::Slab {
            half_width: 2.0,
            kind,
        };
        for kind in [WallKind::Slip, WallKind::NoSlip] {
            let mut x = [0.0, 0.0, 1.95];
            let mut v = [1.0, -2.0, 1.0];
            let b = conf(kind).stream(&mut x, &mut v, 0.1, 0.1);
            assert_eq!(b.count, 1);
            // Crossing after 0.05, then 0.05 back down.
            assert!((x[2] - 1.95).abs() < 1e-12, "{x:?}");
            match kind {
                WallKind::Slip => {
                    assert_eq!(v, [1.0, -2.0, -1.0]);
                    assert!((x[0] - 0.1).abs() < 1e-12);
                }
                WallKind::NoSlip => {
                    assert_eq!(v, [-1.0, 2.0, -1.0]);
                    assert!(x[0].abs() < 1e-12 && x[1].abs() < 1e-12);
                }
            }
        }
    }
}
