//! The Lennard-Jones equation of state of Johnson, Zollweg and Gubbins (Mol. Phys. 78, 591,
//! 1993; docs/references.md): the pressure of the full (untruncated) LJ fluid, a modified
//! Benedict–Webb–Rubin fit to simulations over `0.7 <= T* <= 6`, and the mean-field pressure
//! the part of the potential beyond a cut-off adds. In reduced units (`epsilon = sigma = k = 1`).
//!
//! The bulk BD's virial pressure of the cut-and-shifted LJ fluid (`pair.kind = "lj"`) plus
//! [`lj_tail_pressure`] is compared with [`jzg_pressure`] (docs/bd.md).

/// The 32 parameters `x_1 .. x_32` of the MBWR fit (the paper's Table 10).
#[allow(clippy::excessive_precision)]
const X: [f64; 32] = [
    0.8623085097507421,
    2.976218765822098,
    -8.402230115796038,
    0.1054136629203555,
    -0.8564583828174598,
    1.582759470107601,
    0.7639421948305453,
    1.753173414312048,
    2.798291772190376e3,
    -4.8394220260857657e-2,
    0.9963265197721935,
    -3.698000291272493e1,
    2.084012299434647e1,
    8.305402124717285e1,
    -9.574799715203068e2,
    -1.477746229234994e2,
    6.398607852471505e1,
    1.603993673294834e1,
    6.805916615864377e1,
    -2.791293578795945e3,
    -6.245128304568454,
    -8.116836104958410e3,
    1.488735559561229e1,
    -1.059346754655084e4,
    -1.131607632802822e2,
    -8.867771540418822e3,
    -3.986982844450543e1,
    -4.689270299917261e3,
    2.593535277438717e2,
    -2.694523589434903e3,
    -7.218487631550215e2,
    1.721802063863269e2,
];

/// The nonlinear parameter `gamma` of the exponential terms.
const GAMMA: f64 = 3.0;

/// The pressure of the full LJ fluid at reduced temperature `t` and density `rho` (the paper's
/// MBWR form; its parameters `x_i` are those of its Table 10):
///
/// `P = rho T + sum_{i=1..8} a_i rho^(i+1) + exp(-gamma rho^2) sum_{i=1..6} b_i rho^(2i+1)`.
pub fn jzg_pressure(rho: f64, t: f64) -> f64 {
    let x = |i: usize| X[i - 1];
    let (t2, t3, t4) = (t * t, t * t * t, t * t * t * t);
    let a = [
        x(1) * t + x(2) * t.sqrt() + x(3) + x(4) / t + x(5) / t2,
        x(6) * t + x(7) + x(8) / t + x(9) / t2,
        x(10) * t + x(11) + x(12) / t,
        x(13),
        x(14) / t + x(15) / t2,
        x(16) / t,
        x(17) / t + x(18) / t2,
        x(19) / t2,
    ];
    let b = [
        x(20) / t2 + x(21) / t3,
        x(22) / t2 + x(23) / t4,
        x(24) / t2 + x(25) / t3,
        x(26) / t2 + x(27) / t4,
        x(28) / t2 + x(29) / t3,
        x(30) / t2 + x(31) / t3 + x(32) / t4,
    ];
    let f = (-GAMMA * rho * rho).exp();
    let mut p = rho * t;
    for (i, ai) in a.iter().enumerate() {
        p += ai * rho.powi(i as i32 + 2);
    }
    for (i, bi) in b.iter().enumerate() {
        p += f * bi * rho.powi(2 * i as i32 + 3);
    }
    p
}

/// What the LJ potential beyond the cut-off `rc` adds to the pressure of the fluid cut and
/// shifted at `rc`, to first order (the pair distribution taken as 1 beyond `rc`):
///
/// `P_tail = (16/3) pi rho^2 [(2/3) rc^-9 - rc^-3]`
///
/// (Allen & Tildesley, Computer Simulation of Liquids). The same mean field gives this for
/// the cut-and-shifted fluid: the constant `u(rc)` removed inside `rc` adds
/// `(2/3) pi rho^2 rc^3 u(rc)` to the energy route's tail, and the two make this.
pub fn lj_tail_pressure(rho: f64, rc: f64) -> f64 {
    16.0 / 3.0 * std::f64::consts::PI * rho * rho * (2.0 / 3.0 * rc.powi(-9) - rc.powi(-3))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The LJ second virial coefficient `B2(T) = -2 pi int_0^inf (exp(-u/T) - 1) r^2 dr` by the
    /// midpoint rule.
    fn b2(t: f64) -> f64 {
        let (n, r_max) = (400_000, 40.0);
        let h = r_max / n as f64;
        let mut s = 0.0;
        for k in 0..n {
            let r = (k as f64 + 0.5) * h;
            let u = 4.0 * (r.powi(-12) - r.powi(-6));
            s += ((-u / t).exp() - 1.0) * r * r;
        }
        -2.0 * std::f64::consts::PI * s * h
    }

    #[test]
    fn the_jzg_pressure_has_the_lj_second_virial_coefficient_and_critical_point() {
        // Dilute: (P - rho T) / rho^2 -> a_1 = T B2(T), within the fit's accuracy.
        for t in [1.5, 2.0, 3.0] {
            let rho = 1e-4;
            let a1 = (jzg_pressure(rho, t) - rho * t) / (rho * rho);
            let exact = t * b2(t);
            assert!(
                (a1 - exact).abs() < 0.05 * exact.abs(),
                "T = {t}: a1 {a1} vs T B2 {exact}"
            );
        }
        // The paper's critical point: T_c = 1.313, rho_c = 0.310, P_c = 0.13.
        let pc = jzg_pressure(0.310, 1.313);
        assert!((pc - 0.13).abs() < 0.01, "P_c = {pc}");
        // The ideal gas at vanishing density.
        assert_eq!(jzg_pressure(0.0, 2.0), 0.0);
    }

    #[test]
    fn the_tail_pressure_is_the_virial_integral_beyond_the_cut() {
        // -(2 pi / 3) rho^2 int_rc^inf r^3 u'(r) dr by the midpoint rule.
        let (rho, rc) = (0.5, 2.5);
        let (n, r_max) = (200_000, 200.0);
        let h = (r_max - rc) / n as f64;
        let mut s = 0.0;
        for k in 0..n {
            let r: f64 = rc + (k as f64 + 0.5) * h;
            let du = 4.0 * (-12.0 * r.powi(-13) + 6.0 * r.powi(-7));
            s += r.powi(3) * du;
        }
        let integral = -2.0 / 3.0 * std::f64::consts::PI * rho * rho * s * h;
        let tail = lj_tail_pressure(rho, rc);
        assert!((tail - integral).abs() < 1e-6, "{tail} vs {integral}");
    }
}
