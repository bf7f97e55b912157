//! Shared by the engine tests: the DPD force model summed by brute force, ranks as threads.
#![allow(dead_code)]

use colloidsim_core::exchange::{Exchange, LocalRanks};
use colloidsim_md::dpd::DpdParams;
use colloidsim_md::{Particles, SimBox};

/// Every pair force by brute force over all pairs, from the model's definitions (METHODS.md
/// section 4), for the same positions, velocities and pair noise as the engine, over the
/// Lees–Edwards images when sheared (`SimBox::min_image_sheared` with the x offset `offset`,
/// image velocity `v_j + n gamma_dot L_y e_x`; `offset = 0` and no shear: the plain periodic
/// box).
pub fn brute_force(
    p: &Particles,
    sbox: &SimBox,
    prm: &DpdParams,
    step: u64,
    offset: f64,
) -> Vec<[f64; 3]> {
    use colloidsim_md::dpd::{colloid_solvent_cutoff, pair_noise, step_key};
    let n = p.len();
    let key = step_key(prm.seed, step);
    let sv = prm.shear_rate * sbox.l[1];
    let a: Vec<f64> = (0..n)
        .map(|i| {
            if p.typeid[i] == 1 {
                0.5 * p.diameter[i]
            } else {
                0.0
            }
        })
        .collect();
    let mut f = vec![[0.0; 3]; n];
    for i in 0..n {
        for j in 0..n {
            if i == j {
                continue;
            }
            let (x, y) = (p.pos[i], p.pos[j]);
            let (d, img) = sbox.min_image_sheared([x[0] - y[0], x[1] - y[1], x[2] - y[2]], offset);
            let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let e = [d[0] / r, d[1] / r, d[2] / r];
            let vj = [p.vel[j][0] + img * sv, p.vel[j][1], p.vel[j][2]];
            let dv: Vec<f64> = (0..3).map(|k| p.vel[i][k] - vj[k]).collect();
            let ev = e[0] * dv[0] + e[1] * dv[1] + e[2] * dv[2];
            let h = r - a[i] - a[j];
            let theta = pair_noise(key, i as u32, j as u32);
            let mag = if a[i] > 0.0 && a[j] > 0.0 {
                if h >= prm.colloid_cutoff {
                    continue;
                }
                let w = 1.0 - h / prm.colloid_cutoff;
                let c = &prm.colloid;
                let abar = 0.5 * (a[i] + a[j]);
                let asq = if c.eta0 > 0.0 {
                    c.squeeze_coefficient(h, abar)
                } else {
                    0.0
                };
                c.contact_force(h, abar) + c.morse_force(h) - (prm.gamma * w * w + asq) * ev
                    + (2.0 * prm.kt * (prm.gamma * w * w + asq) / prm.dt).sqrt() * theta
            } else {
                let big = a[i].max(a[j]);
                let (cut, amp) = if big > 0.0 {
                    let c = colloid_solvent_cutoff(prm.rc, big);
                    (c, prm.repulsion_cs * prm.kt / c)
                } else {
                    (prm.rc, prm.repulsion * prm.kt / prm.rc)
                };
                if h >= cut {
                    continue;
                }
                let w = 1.0 - h / cut;
                amp * w - prm.gamma * w * w * ev
                    + (2.0 * prm.gamma * prm.kt / prm.dt).sqrt() * w * theta
            };
            for k in 0..3 {
                f[i][k] += mag * e[k];
            }
        }
    }
    f
}

/// `f(rank)` on `ranks` threads, each with its endpoint; the results in rank order.
pub fn on_ranks<T: Send>(ranks: usize, f: impl Fn(Box<dyn Exchange>) -> T + Sync) -> Vec<T> {
    let f = &f;
    std::thread::scope(|s| {
        let handles: Vec<_> = LocalRanks::new(ranks)
            .into_iter()
            .map(|c| s.spawn(move || f(Box::new(c))))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    })
}
