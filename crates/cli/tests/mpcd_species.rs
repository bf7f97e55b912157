//! droplet-mpcd with two colloid sizes (issue 43): the run with a slip and a no-slip boundary
//! writes droplet-bd's per-species files, holds every surface inside the interface, writes the
//! species into the trajectory, restarts bitwise (the checkpoint keeps each colloid's species);
//! what has no support is refused naming the key.

use std::path::Path;

use crate::common;
use common::{assert_same_outputs, cli, text};

const VOLATILE: &[&str] = &["wall_seconds", "particle_updates_per_second", "threads"];

/// 10 small (d = 2) and 2 large (d = 4, 162 vertices) colloids in R0 = 6 cells, 100 collisions.
fn scenario(boundary: &str, extra: &str) -> String {
    format!(
        "method = \"droplet-mpcd\"\nseed = 5\nboundary = \"{boundary}\"\n\
         [system]\nparticles = 12\nradius = 6\n{extra}\n\
         [drying]\npeclet = 20\nduration = 10\n\
         [observe.profile]\nbins = 6\nfractions = [0.0, 1.0]\n\
         [observe.solvent]\nwindow = 20\n[observe.trajectory]\nevery = 50\n"
    )
}

const SPECIES: &str = "[system.species]\ndiameters = [2.0, 4.0]\ncounts = [10, 2]";

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn a_bidisperse_mpcd_droplet_writes_species_outputs_and_restarts_bitwise() {
    for boundary in ["slip", "no-slip"] {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        let sc = d.join("s.toml");
        std::fs::write(&sc, scenario(boundary, SPECIES)).unwrap();
        let a = d.join("a");
        let o = cli(
            &[
                "run",
                sc.to_str().unwrap(),
                "--out",
                a.to_str().unwrap(),
                "--quiet",
            ],
            &[],
        );
        assert!(o.status.success(), "{}", text(&o));
        let s = summary(&a);
        assert_eq!(
            s["parameters"]["species"]["counts"],
            serde_json::json!([10, 2])
        );
        let c = &s["colloids"];
        // Each colloid's surface within a fraction of d_min of its (shifted) wall.
        let excursion = c["max_excursion_beyond_wall"].as_f64().unwrap();
        assert!(excursion < 0.5, "{boundary}: {excursion}");
        assert_eq!(c["centres_beyond_R_at_end"], 0);
        let st = &s["stratification"];
        assert!(
            st["radius_difference"]["mean"]
                .as_f64()
                .unwrap()
                .is_finite(),
            "{st}"
        );
        for f in [
            "species_profile_0.00.csv",
            "species_profile_1.00.csv",
            "species_profiles.png",
            "stratification.csv",
            "stratification.png",
            "profile_1.00.csv",
        ] {
            assert!(a.join(f).exists(), "{boundary}: {f}");
        }
        let (names, cols) =
            colloidsim_core::output::read_table(&a.join("species_profile_1.00.csv")).unwrap();
        assert_eq!(names, ["r", "rho_v_A", "err_A", "rho_v_B", "err_B"]);
        assert!(cols[1].iter().sum::<f64>() > 0.0 && cols[3].iter().sum::<f64>() > 0.0);
        // The trajectory names the species: A, B, then the vertices and the solvent.
        let f = colloidsim_particles::gsd::read_frame(&a.join("trajectory.gsd"), Some(0)).unwrap();
        let part = &f.particles;
        assert_eq!(part.type_names, ["A", "B", "V", "S"]);
        assert_eq!(&part.typeid[..12], &[0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 1]);
        assert_eq!(part.diameter[11], 4.0);
        assert_eq!(part.pos.len(), 10 * 43 + 2 * 163);
        // Killed mid-run: the restart gives the same files (species kept in the checkpoint).
        let k = d.join("k");
        let o = cli(
            &[
                "run",
                sc.to_str().unwrap(),
                "--out",
                k.to_str().unwrap(),
                "--quiet",
            ],
            &[("COLLOIDSIM_KILL_AT_STEP", "63")],
        );
        assert!(!o.status.success(), "{}", text(&o));
        let o = cli(&["run", "--restart", k.to_str().unwrap(), "--quiet"], &[]);
        assert!(o.status.success(), "{}", text(&o));
        assert_same_outputs(&a, &k, VOLATILE);
    }
}

#[test]
fn unsupported_mixtures_are_refused_naming_the_key() {
    let tmp = tempfile::tempdir().unwrap();
    for (extra, key) in [
        (
            "[system.species]\ndiameters = [1.0, 4.5]\ncounts = [10, 2]",
            "system.species.diameters: species B of diameter 4.5 is 4.5000 times the smallest",
        ),
        (
            "diameter = 2\n[system.species]\ndiameters = [2.0, 4.0]\ncounts = [10, 2]",
            "system.diameter: give the diameters in system.species.diameters",
        ),
        (
            "[system.species]\ndiameters = [2.0, 4.0]\ncounts = [10, 3]",
            "system.species.counts:",
        ),
        (
            "[system.species]\ndiameters = [2.0, 6.5]\ncounts = [11, 1]",
            "system.radius: the initial droplet radius 6 is smaller than a colloid diameter 6.5",
        ),
    ] {
        let sc = tmp.path().join("s.toml");
        std::fs::write(&sc, scenario("slip", extra)).unwrap();
        let o = cli(&["check", sc.to_str().unwrap()], &[]);
        assert!(!o.status.success());
        assert!(text(&o).contains(key), "{extra}: {}", text(&o));
    }
}
