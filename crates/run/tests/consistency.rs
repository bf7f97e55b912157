//! What `check` and `run` accept, `theory` accepts too: the edges of the key ranges.

use colloidsim_run::{Control, Scenario, TheoryOptions};

const DROPLET: &str = r#"
method = "droplet-bd"
seed = 1
[system]
particles = 200
phi0 = 0.05
[drying]
peclet = 10
final_volume_fraction = FINAL
[run]
dt = 0.004
[observe]
profile = { bins = 10, fractions = [0, 1.0] }
"#;

#[test]
fn a_drying_to_close_packing_is_accepted_by_check_and_by_theory() {
    let dir = tempfile::tempdir().unwrap();
    // 0.64 is the upper end of drying.final_volume_fraction; beyond it both refuse.
    for (phi, accepted) in [("0.64", true), ("0.65", false)] {
        let sc = Scenario::from_toml(&DROPLET.replace("FINAL", phi), dir.path()).unwrap();
        assert_eq!(
            colloidsim_run::check(&sc).is_ok(),
            accepted,
            "check at {phi}"
        );
        let opts = TheoryOptions {
            out: Some(dir.path().join(format!("theory-{phi}"))),
            dx: Some(0.1),
            force: false,
            hydrodynamics: None,
            pair: None,
        };
        let t = colloidsim_run::theory(&sc, &opts, &Control::default());
        assert_eq!(t.is_ok(), accepted, "theory at {phi}: {:?}", t.err());
    }
}
