//! Validation of the exact 1D rods solver against exact results (METHODS.md section 2).

// Inside `mod rods` so that `cargo test -p colloidsim-dft rods` selects these tests.
mod rods {
    use colloidsim_dft::rods::{
        BetaPotential, Domain, Equilibrium, RodInteraction, RodsError, RodsProblem, bulk,
        equilibrium,
    };
    use std::f64::consts::TAU;

    fn cosine(u0: f64) -> BetaPotential {
        BetaPotential::from_fn(1.0, move |x| 0.5 * u0 * (TAU * x).cos())
    }

    fn periodic(sigma: f64, rho: f64, dx: f64) -> RodsProblem {
        RodsProblem::new(sigma, rho, Domain::Periodic { period: 1.0 }).with_dx(dx)
    }

    fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
    }

    fn max(a: &[f64]) -> f64 {
        a.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
    }

    /// Tonks gas, written out here independently of `bulk`.
    fn tonks_beta_mu(sigma: f64, rho: f64) -> f64 {
        let e = rho * sigma;
        (rho / (1.0 - e)).ln() + e / (1.0 - e)
    }

    #[test]
    fn homogeneous_hard_rods_reproduce_the_tonks_gas() {
        // With U = 0 the uniform profile is an exact fixed point of the discrete equation (window
        // integrals and interpolation are exact for constants), so beta mu and the contact value must
        // agree to rounding: a tolerance of 1e-9 leaves room for the 1e-10 residual only.
        for &(sigma, rho) in &[(0.2, 0.5), (0.5, 0.5), (0.8, 0.8), (0.37, 2.5)] {
            let eq = equilibrium(&periodic(sigma, rho, sigma / 23.7)).unwrap();
            assert!(eq.residual < 1e-10);
            assert!(
                (eq.beta_mu - tonks_beta_mu(sigma, rho)).abs() < 1e-9,
                "{sigma} {rho}"
            );
            assert!((eq.beta_mu - bulk::beta_mu(sigma, 0.0, rho)).abs() < 1e-9);
            for (&r, &c) in eq.rho.iter().zip(&eq.contact_density) {
                assert!((r / rho - 1.0).abs() < 1e-10);
                assert!((c / (rho * rho) - 1.0 / (1.0 - rho * sigma)).abs() < 1e-9);
            }
            assert!(eq.bonded_pair_density.is_none());
        }
    }

    #[test]
    fn window_estimator_expectation_is_the_tonks_law_and_tends_to_eq24() {
        // Without a field: rho (1 - exp(-a w)) / w with a = rho / (1 - rho sigma), to rounding.
        let (sigma, rho, w) = (0.5, 0.5, 0.02);
        let eq = equilibrium(&periodic(sigma, rho, sigma / 23.7)).unwrap();
        let a = rho / (1.0 - rho * sigma);
        let tonks = rho * (1.0 - (-a * w).exp()) / w;
        for v in eq.window_contact_average(10, 1.0, w).unwrap().unwrap() {
            assert!((v / tonks - 1.0).abs() < 1e-9, "{v} vs {tonks}");
        }
        // In the paper's 6 kT wells: a narrow window reads Eq. 24 (to first order in w), a
        // window of 0.02 differs by several per cent where the density is steep.
        let eq =
            equilibrium(&periodic(sigma, rho, sigma / 400.0).with_potential(cosine(6.0))).unwrap();
        let b = eq.bin_average(50, 1.0).unwrap();
        let narrow = eq.window_contact_average(50, 1.0, 1e-5).unwrap().unwrap();
        let wide = eq.window_contact_average(50, 1.0, 0.02).unwrap().unwrap();
        let rel = |x: &[f64]| {
            x.iter()
                .zip(&b.contact_density)
                .map(|(v, c)| (v / c - 1.0).abs())
                .fold(0.0, f64::max)
        };
        assert!(rel(&narrow) < 1e-4, "narrow window {:.2e}", rel(&narrow));
        assert!(rel(&wide) > 0.02, "wide window {:.2e}", rel(&wide));
        // Sticky rods have no such closed form here.
        let sticky = equilibrium(
            &periodic(sigma, rho, sigma / 40.0)
                .with_interaction(RodInteraction::Sticky { gamma: 1.0 }),
        )
        .unwrap();
        assert!(sticky.window_contact_average(10, 1.0, w).unwrap().is_none());
    }

    #[test]
    fn homogeneous_sticky_rods_reproduce_the_baxter_equation_of_state() {
        // Exact 1D sticky rods (isobaric solution, see `bulk`): beta p (1 + gamma beta p) = rho/(1 - rho sigma),
        // beta mu = beta p sigma + ln(beta p / (1 + gamma beta p)), contact rho beta p / (1 + gamma beta p).
        // Written out here in the textbook root form, independently of `bulk`.
        for &(sigma, rho, gamma) in &[
            (0.5f64, 0.5f64, 1.0f64),
            (0.8, 0.8, 10.0),
            (0.2, 0.2, 0.1),
            (0.5, 1.5, 3.0),
        ] {
            let x = rho / (1.0 - rho * sigma);
            let p = (-1.0 + (1.0 + 4.0 * gamma * x).sqrt()) / (2.0 * gamma);
            let mu = p * sigma + (p / (1.0 + gamma * p)).ln();
            let eq = equilibrium(
                &periodic(sigma, rho, sigma / 31.3)
                    .with_interaction(RodInteraction::Sticky { gamma }),
            )
            .unwrap();
            assert!((eq.beta_mu - mu).abs() < 1e-9, "{} vs {mu}", eq.beta_mu);
            assert!((eq.beta_mu - bulk::beta_mu(sigma, gamma, rho)).abs() < 1e-9);
            let c = rho * p / (1.0 + gamma * p);
            for &cc in &eq.contact_density {
                assert!((cc / c - 1.0).abs() < 1e-9);
            }
            let b = eq.bonded_pair_density.as_ref().unwrap();
            assert!((b[0] / (gamma * c) - 1.0).abs() < 1e-9);
        }
    }

    /// Force balance (first YBG equation) of hard rods, an exact identity independent of the
    /// functional: `rho'(x) = -beta U'(x) rho(x) + rho2(x - sigma, x) - rho2(x, x + sigma)`.
    /// Returns max |lhs - rhs| / max |rho'| on the grid (central differences for rho').
    fn force_balance_defect(eq: &Equilibrium, sigma: f64, u0: f64) -> f64 {
        let m = eq.x.len();
        let dx = eq.dx;
        let shift = sigma / dx;
        let c = &eq.contact_density;
        let interp = |v: &[f64], s: f64| {
            // periodic linear interpolation at fractional index s
            let k = s.floor();
            let t = s - k;
            let j = (k as isize).rem_euclid(m as isize) as usize;
            (1.0 - t) * v[j] + t * v[(j + 1) % m]
        };
        let mut worst: f64 = 0.0;
        let mut scale: f64 = 0.0;
        for i in 0..m {
            let x = eq.x[i];
            // fourth-order central difference, so that the checker's own error is negligible
            let r = |k: isize| eq.rho[(i as isize + k).rem_euclid(m as isize) as usize];
            let drho = (8.0 * (r(1) - r(-1)) - (r(2) - r(-2))) / (12.0 * dx);
            let du = -0.5 * u0 * TAU * (TAU * x).sin();
            let rhs = -du * eq.rho[i] + interp(c, i as f64 - shift) - c[i];
            worst = worst.max((drho - rhs).abs());
            scale = scale.max(drho.abs());
        }
        worst / scale
    }

    #[test]
    fn hard_rods_satisfy_the_exact_force_balance_and_a_wrong_sigma_is_caught() {
        // Paper cases sigma in {0.2, 0.5, 0.8} at density 0.5 / 0.8, U0 = 6. All discretisation errors
        // are O(dx^2): halving dx must divide the defect by about 4 (> 3 required), and at
        // sigma/dx = 200 the defect is below 1e-4 of the profile's slope (observed 3e-6 to 7e-6).
        for &(sigma, rho) in &[(0.2, 0.8), (0.5, 0.5), (0.8, 0.8)] {
            let d1 = force_balance_defect(
                &equilibrium(&periodic(sigma, rho, sigma / 100.0).with_potential(cosine(6.0)))
                    .unwrap(),
                sigma,
                6.0,
            );
            let eq2 = equilibrium(&periodic(sigma, rho, sigma / 200.0).with_potential(cosine(6.0)))
                .unwrap();
            let d2 = force_balance_defect(&eq2, sigma, 6.0);
            assert!(
                d1 / d2 > 3.0 && d2 < 1e-4,
                "sigma {sigma} rho {rho}: defects {d1:.2e} {d2:.2e}"
            );
            // The same check with sigma off by 10% in the checker must fail clearly: the defect is
            // then a modelling error, not the O(dx^2) one (observed: 25x to 2e4x larger).
            let wrong = force_balance_defect(&eq2, 1.1 * sigma, 6.0);
            assert!(
                wrong > 10.0 * d2,
                "sigma {sigma}: wrong-sigma defect {wrong:.2e} vs {d2:.2e}"
            );
        }
    }

    #[test]
    fn ideal_limit_sigma_to_zero_gives_boltzmann() {
        // To first order in sigma, ln rho = beta mu - beta U - 2 sigma rho(x), so
        // |rho - rho_B| <= 2 sigma max(rho_B)^2 (normalisation shift included), and the deviation must
        // halve with sigma (ratio in [1.8, 2.2]).
        let u0 = 6.0;
        let rho = 0.5;
        let z: f64 = {
            let n = 20000;
            (0..n)
                .map(|i| (-0.5 * u0 * (TAU * i as f64 / n as f64).cos()).exp())
                .sum::<f64>()
                / n as f64
        };
        let boltz = |x: f64| rho * (-0.5 * u0 * (TAU * x).cos()).exp() / z;
        let mut prev: Option<f64> = None;
        for &sigma in &[0.02, 0.01, 0.005] {
            let eq = equilibrium(&periodic(sigma, rho, sigma / 20.0).with_potential(cosine(u0)))
                .unwrap();
            let dev =
                eq.x.iter()
                    .zip(&eq.rho)
                    .map(|(&x, &r)| (r - boltz(x)).abs())
                    .fold(0.0, f64::max);
            let bmax = boltz(0.5);
            assert!(dev < 2.0 * sigma * bmax * bmax, "sigma {sigma}: {dev}");
            if let Some(p) = prev {
                let ratio = p / dev;
                assert!((1.8..2.2).contains(&ratio), "ratio {ratio}");
            }
            prev = Some(dev);
        }
    }

    #[test]
    fn sticky_rods_tend_continuously_to_hard_rods() {
        let base = periodic(0.5, 0.8, 0.5 / 40.0).with_potential(cosine(6.0));
        let hard = equilibrium(&base).unwrap();
        // gamma = 0 is the hard rod exactly (same code path).
        let zero = equilibrium(
            &base
                .clone()
                .with_interaction(RodInteraction::Sticky { gamma: 0.0 }),
        )
        .unwrap();
        assert_eq!(hard.rho, zero.rho);
        // Deviation linear in gamma: each decade of gamma divides it by ~10 (8..12).
        let mut prev: Option<(f64, f64)> = None;
        for &gamma in &[1e-2, 1e-3, 1e-4] {
            let eq = equilibrium(
                &base
                    .clone()
                    .with_interaction(RodInteraction::Sticky { gamma }),
            )
            .unwrap();
            let d = max_abs_diff(&eq.rho, &hard.rho) / max(&hard.rho);
            let dc = max_abs_diff(&eq.contact_density, &hard.contact_density)
                / max(&hard.contact_density);
            assert!(d > 0.0 && dc > 0.0);
            if let Some((p, pc)) = prev {
                assert!((8.0..12.0).contains(&(p / d)), "gamma {gamma}: {p} / {d}");
                assert!(
                    (8.0..12.0).contains(&(pc / dc)),
                    "gamma {gamma}: {pc} / {dc}"
                );
            }
            prev = Some((d, dc));
        }
    }

    #[test]
    fn fractional_sigma_over_dx_converges_at_second_order() {
        // sigma/dx = 41.3 vs the reference at sigma/dx = 400 (integral): error must fall by > 3 when
        // dx halves (second order), for sticky rods, which use every window operation.
        let make = |dx: f64| {
            periodic(0.5, 0.8, dx)
                .with_potential(cosine(6.0))
                .with_interaction(RodInteraction::Sticky { gamma: 1.0 })
        };
        let fine = equilibrium(&make(0.5 / 400.0)).unwrap();
        let probe = |eq: &Equilibrium| {
            let b = eq.bin_average(50, 1.0).unwrap();
            b.rho
        };
        let reference = probe(&fine);
        let e1 = max_abs_diff(
            &probe(&equilibrium(&make(0.5 / 20.65)).unwrap()),
            &reference,
        );
        let e2 = max_abs_diff(&probe(&equilibrium(&make(0.5 / 41.3)).unwrap()), &reference);
        assert!(e1 / e2 > 3.0, "errors {e1:.2e} {e2:.2e}");
    }

    #[test]
    fn walls_obey_the_contact_theorem_and_bulk_density_far_away() {
        // Hard walls: the density at wall contact equals the bulk pressure beta p = rho_b/(1 - rho_b sigma)
        // (contact theorem), and the middle of a wide box is bulk. The wall jump is smeared over one
        // cell, so the contact value converges at first order: the error must halve with dx and be
        // below 2% at sigma/dx = 40.
        let sigma = 1.0;
        let mut prev: Option<f64> = None;
        for &dx in &[sigma / 20.0, sigma / 40.0] {
            let eq = equilibrium(
                &RodsProblem::new(sigma, 0.5, Domain::Walls { length: 20.0 }).with_dx(dx),
            )
            .unwrap();
            let m = eq.x.len();
            assert!((eq.x[0] - 0.5 * sigma).abs() < 1e-12 && (eq.x[m - 1] - 19.5).abs() < 1e-9);
            let mid = eq.rho[m / 2];
            let p = mid / (1.0 - mid * sigma);
            let err = (eq.rho[0] / p - 1.0).abs();
            let sym = (eq.rho[0] - eq.rho[m - 1]).abs() / eq.rho[0];
            assert!(sym < 1e-9, "mirror symmetry {sym}");
            if let Some(pe) = prev {
                assert!(pe / err > 1.7, "errors {pe} {err}");
                assert!(err < 0.02, "contact error {err}");
            }
            prev = Some(err);
            // particle number: integral of the interpolant (bins over the whole box)
            let b = eq.bin_average(400, 20.0).unwrap();
            let n: f64 = b.rho.iter().sum::<f64>() * 20.0 / 400.0;
            assert!((n / 10.0 - 1.0).abs() < 1e-9, "N = {n}");
        }
    }

    #[test]
    fn a_dense_short_box_converges_from_separated_peaks() {
        // 2.85 rods of length 0.8 between walls 3 apart (3 fit): the uniform start overlaps
        // (eta = 1.03), the solver starts from separated peaks instead.
        let eq =
            equilibrium(&RodsProblem::new(0.8, 0.95, Domain::Walls { length: 3.0 }).with_dx(0.005))
                .unwrap();
        let m = eq.rho.len();
        assert!(eq.residual < 1e-10);
        assert!((eq.rho[0] - eq.rho[m - 1]).abs() < 1e-8 * eq.rho[0]);
        let n: f64 = eq.bin_average(300, 3.0).unwrap().rho.iter().sum::<f64>() * 0.01;
        assert!((n / 2.85 - 1.0).abs() < 1e-9, "{n}");
    }

    #[test]
    fn sticky_rods_at_walls_obey_the_contact_theorem() {
        // The hard-wall contact theorem rho(contact) = beta p(bulk) holds for any rod-rod
        // interaction; with the Baxter pressure beta p(1 + gamma beta p) = rho/(1 - rho sigma).
        // First order in dx (smeared wall jump): 3% at sigma/dx = 40.
        let eq = equilibrium(
            &RodsProblem::new(1.0, 0.5, Domain::Walls { length: 20.0 })
                .with_dx(1.0 / 40.0)
                .with_interaction(RodInteraction::Sticky { gamma: 1.0 }),
        )
        .unwrap();
        let mid = eq.rho[eq.x.len() / 2];
        let p = bulk::beta_pressure(1.0, 1.0, mid);
        let err = (eq.rho[0] / p - 1.0).abs();
        assert!(err < 0.03, "{err}");
    }

    #[test]
    fn sampled_potential_gives_the_same_profile_as_the_closure() {
        // 2000 points: the closure uses grid sequencing, the samples do not; both must meet the
        // same 1e-10 residual, so the profiles agree to ~1e-9 relative.
        let base =
            periodic(0.5, 0.8, 0.0005).with_interaction(RodInteraction::Sticky { gamma: 1.0 });
        let a = equilibrium(&base.clone().with_potential(cosine(6.0))).unwrap();
        let x = base.grid_points().unwrap();
        let samples = x.iter().map(|&x| 3.0 * (TAU * x).cos()).collect();
        let b = equilibrium(&base.with_potential(BetaPotential::OnGrid(samples))).unwrap();
        assert!(a.levels > 1 && b.levels == 1);
        assert!(max_abs_diff(&a.rho, &b.rho) / max(&a.rho) < 1e-8);
    }

    #[test]
    fn bin_average_conserves_mass_and_repeats_over_periods() {
        let eq = equilibrium(&periodic(0.3, 1.2, 0.3 / 17.0).with_potential(cosine(4.0))).unwrap();
        // L = 3 periods, 700 bins (not commensurate with the grid): total mass = 3 * 1.2.
        let b = eq.bin_average(700, 3.0).unwrap();
        let n: f64 = b.rho.iter().sum::<f64>() * 3.0 / 700.0;
        assert!((n - 3.6).abs() < 1e-9, "{n}");
        assert!((b.centres[0] - 1.5 / 700.0).abs() < 1e-15);
        // periodic continuation: 600 bins over 3 periods repeat every 200 bins
        let b = eq.bin_average(600, 3.0).unwrap();
        for k in 0..200 {
            assert!(
                (b.rho[k] - b.rho[k + 200]).abs() < 1e-12
                    && (b.rho[k] - b.rho[k + 400]).abs() < 1e-12
            );
        }
        assert!(eq.bin_average(0, 1.0).is_err());
    }

    #[test]
    fn bad_input_is_rejected_with_the_parameter_named() {
        let msg = |p: RodsProblem| match equilibrium(&p) {
            Err(RodsError::Param(e)) => e.to_string(),
            other => panic!("expected a parameter error, got {other:?}"),
        };
        assert!(msg(periodic(0.5, 2.0, 0.01)).contains("mean_density"));
        assert!(msg(periodic(0.5, 2.5, 0.01)).contains("close packing"));
        assert!(msg(periodic(0.5, 0.5, 0.1)).contains("sigma / dx >= 10"));
        assert!(msg(periodic(0.5, 0.5, 0.01).with_tolerance(0.0)).contains("tolerance"));
        assert!(msg(periodic(-0.5, 0.5, 0.01)).contains("sigma"));
        assert!(
            msg(
                periodic(0.5, 0.5, 0.01).with_potential(BetaPotential::from_fn(1.0, |x| {
                    if x > 0.5 { f64::INFINITY } else { 0.0 }
                }))
            )
            .contains("beta_u")
        );
        assert!(
            msg(periodic(0.5, 0.5, 0.01).with_interaction(RodInteraction::Sticky { gamma: -1.0 }))
                .contains("gamma")
        );
        assert!(
            msg(RodsProblem::new(1.0, 0.5, Domain::Walls { length: 0.9 }).with_dx(0.01))
                .contains("length")
        );
        // 3.6 rods of length 0.8 between walls 3 apart: only 3 fit
        assert!(
            msg(RodsProblem::new(0.8, 1.2, Domain::Walls { length: 3.0 }).with_dx(0.01))
                .contains("at most 3 rods")
        );
        // potential period 2 on a domain of period 1
        assert!(
            msg(periodic(0.5, 0.5, 0.01)
                .with_potential(BetaPotential::from_fn(1.0, |x| { (0.5 * TAU * x).cos() })))
            .contains("period")
        );
        // a tilted washboard has no equilibrium
        let field = colloidsim_core::field1d::ExternalField {
            terms: vec![],
            drive: 1.0,
        };
        match BetaPotential::for_equilibrium(&field, 1.0) {
            Err(RodsError::Param(e)) => assert_eq!(e.key, "field.drive"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn strongly_layered_dense_states_converge() {
        // Several rods per potential well (sigma << period), dense and strongly modulated: states
        // from a random parameter sweep on which the first version (Anderson memory 8, fixed
        // mixing, history reset after every overlapping step) stalled.
        for &(sigma, rho, gamma, u0, dx) in &[
            (0.057, 8.4386, 0.28, 3.89, 1.33e-3),
            (0.084, 5.083, 1.11, 5.63, 1.87e-3),
            (0.112, 6.90, 1.88, 6.35, 3.02e-3),
        ] {
            let p = periodic(sigma, rho, dx)
                .with_potential(cosine(u0))
                .with_interaction(RodInteraction::Sticky { gamma });
            let eq = equilibrium(&p).unwrap_or_else(|e| panic!("sigma {sigma}: {e}"));
            assert!(eq.residual < 1e-10);
        }
    }

    #[test]
    fn non_convergence_is_an_error_with_the_residual() {
        let mut p = periodic(0.8, 0.8, 0.8 / 40.0)
            .with_potential(cosine(6.0))
            .with_interaction(RodInteraction::Sticky { gamma: 10.0 });
        p.max_iterations = 3;
        match equilibrium(&p) {
            Err(RodsError::NotConverged {
                residual,
                iterations,
                ..
            }) => {
                // 3 iterations, then 3 more in the robust retry (memory 40, mixing 0.1)
                assert!(residual > 1e-10 && residual.is_finite() && iterations == 6);
                let msg = equilibrium(&p).unwrap_err().to_string();
                assert!(msg.contains("did not converge") && msg.contains("residual"));
            }
            other => panic!("expected NotConverged, got {other:?}"),
        }
    }
}

/// The paper's parameter grid (Secs. III C and IV B): sigma in {0.2, 0.5, 0.8} x mean density in
/// {0.2, 0.5, 0.8}, U0 = 6, hard and sticky gamma in {0.1, 1, 10}; every case must converge to
/// 1e-10 (these are the profiles `colloidsim theory` computes next to BCD runs).
mod paper_cases {
    use colloidsim_dft::rods::{BetaPotential, Domain, RodInteraction, RodsProblem, equilibrium};
    use std::f64::consts::TAU;

    fn all_converge(dx: f64) {
        for &sigma in &[0.2, 0.5, 0.8] {
            for &rho in &[0.2, 0.5, 0.8] {
                for &gamma in &[0.0, 0.1, 1.0, 10.0] {
                    let p = RodsProblem::new(sigma, rho, Domain::Periodic { period: 1.0 })
                        .with_dx(dx)
                        .with_interaction(RodInteraction::Sticky { gamma })
                        .with_potential(BetaPotential::from_fn(1.0, |x| 3.0 * (TAU * x).cos()));
                    let eq = equilibrium(&p)
                        .unwrap_or_else(|e| panic!("sigma {sigma} rho {rho} gamma {gamma}: {e}"));
                    assert!(eq.residual < 1e-10);
                    let n: f64 = eq.rho.iter().sum::<f64>() * eq.dx;
                    assert!((n / rho - 1.0).abs() < 1e-9, "normalisation {n}");
                }
            }
        }
    }

    #[test]
    fn rods_paper_cases_converge_at_dx_1e_3() {
        all_converge(1e-3);
    }

    #[test]
    fn rods_paper_cases_converge_at_dx_1e_4() {
        all_converge(1e-4);
    }
}
