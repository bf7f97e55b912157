//! A run's folder reruns the run: `--seed` (and an ensemble member's seed) is written into the
//! saved `scenario.toml` and checkpoint, and a restart accepts the scenario with or without it.

use colloidsim_run::{Control, RunOptions, Scenario};
use std::path::Path;

const RODS: &str = "method = \"bcd\"\nseed = 3\n[system]\nlength = 10.0\nparticles = 5\n\
                    diameter = 0.5\n[run]\ndt = 1e-4\ntime = 0.05\n";

fn run(sc: &Scenario, out: &Path, seed: Option<u64>) {
    let opts = RunOptions {
        out: Some(out.to_path_buf()),
        seed,
        force: false,
    };
    colloidsim_run::run(sc, &opts, &Control::default()).unwrap();
}

fn final_positions(out: &Path) -> String {
    std::fs::read_to_string(out.join("final_configuration.csv")).unwrap()
}

#[test]
fn the_saved_scenario_of_a_run_with_a_seed_override_reruns_it() {
    let dir = tempfile::tempdir().unwrap();
    let sc = Scenario::from_toml(RODS, dir.path()).unwrap();
    let (first, again, plain) = (
        dir.path().join("seed9"),
        dir.path().join("again"),
        dir.path().join("seed3"),
    );
    run(&sc, &first, Some(9));
    let saved = Scenario::from_path(&first.join("scenario.toml")).unwrap();
    assert_eq!(saved.seed().unwrap(), 9, "{}", saved.text());
    run(&saved, &again, None);
    assert_eq!(final_positions(&first), final_positions(&again));
    // The override matters: the scenario's own seed gives another run.
    run(&sc, &plain, None);
    assert_ne!(final_positions(&first), final_positions(&plain));
    // Without an override (or with the scenario's own seed) the text is saved as given.
    assert_eq!(
        std::fs::read_to_string(plain.join("scenario.toml")).unwrap(),
        RODS
    );
}

#[test]
fn an_interrupted_run_with_a_seed_override_continues_from_either_scenario() {
    let dir = tempfile::tempdir().unwrap();
    let sc = Scenario::from_toml(RODS, dir.path()).unwrap();
    let whole = dir.path().join("whole");
    run(&sc, &whole, Some(9));
    for given in ["original", "saved", "none"] {
        let out = dir.path().join(given);
        let ctl = Control::default();
        ctl.interrupt();
        let opts = RunOptions {
            out: Some(out.clone()),
            seed: Some(9),
            force: false,
        };
        let e = colloidsim_run::run(&sc, &opts, &ctl).unwrap_err();
        assert!(e.downcast_ref::<colloidsim_run::Interrupted>().is_some());
        let saved = Scenario::from_path(&out.join("scenario.toml")).unwrap();
        let s = match given {
            "original" => Some(&sc),
            "saved" => Some(&saved),
            _ => None,
        };
        colloidsim_run::resume(&out, s, Some(9), &Control::default())
            .unwrap_or_else(|e| panic!("{given}: {e:#}"));
        assert_eq!(final_positions(&out), final_positions(&whole), "{given}");
    }
}
