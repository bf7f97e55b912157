//! 1D DDFT of rods: particle conservation, relaxation onto the equilibrium solver's profile,
//! and the driven steady state.

// Inside `mod rods` so that `cargo test -p colloidsim-dft rods` selects these tests.
mod rods {
    use colloidsim_dft::rods::{
        BetaPotential, DdftProblem, Domain, InitialProfile, RodInteraction, RodsError, RodsProblem,
        ddft, equilibrium, ideal_washboard_current,
    };
    use std::f64::consts::TAU;

    fn cosine(u0: f64) -> BetaPotential {
        BetaPotential::from_fn(1.0, move |x| 0.5 * u0 * (TAU * x).cos())
    }

    /// Runs DDFT to `t_end` and returns (final rho, max relative mass change, final stationarity).
    fn relax(rods: RodsProblem, dt: f64, t_end: f64) -> (Vec<f64>, f64, f64) {
        let problem = DdftProblem {
            rods,
            diffusion: 1.0,
            beta_drive: 0.0,
            dt,
            step_tolerance: None,
            output_times: vec![0.0, 0.5 * t_end, t_end],
            initial: InitialProfile::Uniform,
        };
        let mut last = Vec::new();
        let mut stat = f64::NAN;
        let summary = ddft(&problem, |f| {
            last = f.rho.to_vec();
            stat = f.stationarity;
        })
        .unwrap();
        (last, summary.max_relative_mass_change, stat)
    }

    fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
        let scale = b.iter().cloned().fold(0.0, f64::max);
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
            / scale
    }

    #[test]
    fn ddft_conserves_particles_and_relaxes_to_the_equilibrium_profile() {
        // Periodic hard and sticky rods in the paper's cosine potential, and hard rods between
        // walls. The stationary state of the scheme satisfies the discrete structure equation
        // exactly, so the only difference to the direct solver after many relaxation times is the
        // remaining exponential decay and the solver tolerance: require < 1e-7 relative.
        // Particle number: flux form, so only rounding (observed < 1e-13 after 2e4 steps): < 1e-12.
        let cases = [
            RodsProblem::new(0.5, 0.8, Domain::Periodic { period: 1.0 })
                .with_dx(0.5 / 25.0)
                .with_potential(cosine(6.0)),
            RodsProblem::new(0.5, 0.8, Domain::Periodic { period: 1.0 })
                .with_dx(0.5 / 25.0)
                .with_potential(cosine(6.0))
                .with_interaction(RodInteraction::Sticky { gamma: 1.0 }),
            RodsProblem::new(0.5, 0.6, Domain::Walls { length: 3.0 })
                .with_dx(0.5 / 20.0)
                .with_potential(cosine(2.0)),
        ];
        for rods in cases {
            let eq = equilibrium(&rods).unwrap();
            let (rho, dm, stat) = relax(rods.clone(), 2e-4, 4.0);
            let d = rel_diff(&rho, &eq.rho);
            assert!(dm < 1e-12, "mass drift {dm:e}");
            assert!(d < 1e-7, "{:?}: DDFT vs equilibrium {d:e}", rods.domain);
            assert!(stat < 1e-7);
        }
    }

    #[test]
    fn stabilised_fixed_steps_relax_stiff_sticky_rods() {
        // gamma = 10, rho sigma = 0.64, U0 = 6 (the benchmark state): without the
        // stabilising term, fixed steps above ~1e-5 (dx = 0.01) are unstable; with it, steps of
        // 1e-3 relax onto the direct solution (steady state unchanged by the stabilisation).
        let rods = RodsProblem::new(0.8, 0.8, Domain::Periodic { period: 1.0 })
            .with_dx(0.01)
            .with_potential(cosine(6.0))
            .with_interaction(RodInteraction::Sticky { gamma: 10.0 });
        let eq = equilibrium(&rods).unwrap();
        let (rho, dm, stat) = relax(rods, 1e-3, 3.0);
        assert!(dm < 1e-12);
        assert!(rel_diff(&rho, &eq.rho) < 1e-8 && stat < 1e-8);
    }

    #[test]
    fn step_size_control_handles_stiff_sticky_rods() {
        // Step doubling with local tolerance 1e-5 from a first step of 1e-2 must keep the state
        // within 10x that tolerance of the direct solution once relaxed, and conserve N.
        let rods = RodsProblem::new(0.8, 0.8, Domain::Periodic { period: 1.0 })
            .with_dx(0.04)
            .with_potential(cosine(6.0))
            .with_interaction(RodInteraction::Sticky { gamma: 10.0 });
        let eq = equilibrium(&rods).unwrap();
        let problem = DdftProblem {
            rods,
            diffusion: 1.0,
            beta_drive: 0.0,
            dt: 1e-2,
            step_tolerance: Some(1e-5),
            output_times: vec![1.0, 2.0],
            initial: InitialProfile::Uniform,
        };
        let mut diffs = Vec::new();
        let s = ddft(&problem, |f| diffs.push(rel_diff(f.rho, &eq.rho))).unwrap();
        assert!(s.max_relative_mass_change < 1e-12);
        assert!(s.rejected_steps > 0 && s.min_step < 1e-3);
        assert!(s.max_stabilization > 0.0);
        for d in diffs {
            assert!(d < 1e-4, "{d}");
        }
    }

    #[test]
    fn a_wrong_sigma_is_caught_by_the_ddft_comparison() {
        // sigma 10% off relaxes to a different profile, far outside the 1e-7 tolerance above.
        let rods = RodsProblem::new(0.5, 0.8, Domain::Periodic { period: 1.0 })
            .with_dx(0.5 / 25.0)
            .with_potential(cosine(6.0));
        let eq = equilibrium(&rods).unwrap();
        let mut wrong = rods.clone();
        wrong.sigma *= 1.1;
        let (rho, _, _) = relax(wrong, 2e-4, 4.0);
        let d = rel_diff(&rho, &eq.rho);
        assert!(d > 1e-3, "{d}");
    }

    #[test]
    fn driven_steady_state_current_tends_to_the_ideal_limit() {
        // Tilted washboard, short rods: the current differs from the exact ideal-gas result at
        // first order in rho sigma, so the deviation must stay below 2 rho sigma and halve when
        // sigma halves (ratio in [1.7, 2.3]); the state must be stationary and N conserved
        // (flux form: rounding only, below 1e-14 per step).
        let (u0, f, rho) = (2.0, 3.0, 0.5);
        let exact = ideal_washboard_current(u0, f, rho, 1.0);
        let mut prev: Option<f64> = None;
        for &sigma in &[0.01, 0.005] {
            let rods = RodsProblem::new(sigma, rho, Domain::Periodic { period: 1.0 })
                .with_dx(sigma / 10.0)
                .with_potential(cosine(u0));
            let problem = DdftProblem {
                rods,
                diffusion: 1.0,
                beta_drive: f,
                dt: 1e-3,
                step_tolerance: None,
                output_times: vec![1.5, 2.0],
                initial: InitialProfile::Boltzmann,
            };
            let mut currents = Vec::new();
            let s = ddft(&problem, |fr| currents.push(fr.mean_current)).unwrap();
            assert!(s.max_relative_mass_change < 1e-14 * s.steps as f64);
            assert!(
                (currents[1] / currents[0] - 1.0).abs() < 1e-6,
                "not stationary"
            );
            let dev = (currents[1] / exact - 1.0).abs();
            assert!(
                dev < 2.0 * rho * sigma,
                "sigma {sigma}: {} vs {exact}",
                currents[1]
            );
            if let Some(p) = prev {
                assert!((1.7..2.3).contains(&(p / dev)), "ratio {}", p / dev);
            }
            prev = Some(dev);
        }
    }

    #[test]
    fn ddft_rejects_bad_input() {
        let rods = RodsProblem::new(0.5, 0.5, Domain::Periodic { period: 1.0 }).with_dx(0.01);
        let base = DdftProblem {
            rods,
            diffusion: 1.0,
            beta_drive: 0.0,
            dt: 1e-3,
            step_tolerance: None,
            output_times: vec![0.1],
            initial: InitialProfile::Uniform,
        };
        let err = |p: DdftProblem| match ddft(&p, |_| {}) {
            Err(RodsError::Param(e)) => e.key,
            other => panic!("expected a parameter error, got {other:?}"),
        };
        assert_eq!(
            err(DdftProblem {
                dt: 0.0,
                ..base.clone()
            }),
            "dt"
        );
        assert_eq!(
            err(DdftProblem {
                diffusion: -1.0,
                ..base.clone()
            }),
            "diffusion"
        );
        assert_eq!(
            err(DdftProblem {
                output_times: vec![0.2, 0.1],
                ..base.clone()
            }),
            "output_times"
        );
        assert_eq!(
            err(DdftProblem {
                initial: InitialProfile::Given(vec![1.0; 3]),
                ..base.clone()
            }),
            "initial"
        );
    }
}
