//! End-to-end tests of `colloidsim ensemble` (one process; the MPI tests are in `mpi.rs`).

use std::path::Path;
use std::process::Output;

use crate::common;
use common::{TINY_BCD as TINY, text};

fn run(args: &[&str]) -> Output {
    common::cli(args, &[])
}

fn table(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    colloidsim_core::output::read_table(path).unwrap()
}

#[test]
fn replicas_are_plain_runs_and_their_averages_are_mean_and_standard_error() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join("tiny.toml");
    std::fs::write(&sc, TINY).unwrap();
    let out = tmp.path().join("ens");
    let (s, o) = (sc.to_str().unwrap(), out.to_str().unwrap());
    let r = run(&[
        "ensemble",
        s,
        "--out",
        o,
        "--replicas",
        "3",
        "--threads",
        "1",
    ]);
    assert!(r.status.success());
    assert!(text(&r).contains("ran 3 member(s) (1 point(s) x 3 replica(s))"));
    // A member is bitwise the run of its seed.
    let plain = tmp.path().join("plain");
    let p = run(&[
        "run",
        s,
        "--out",
        plain.to_str().unwrap(),
        "--seed",
        "12",
        "--quiet",
        "--threads",
        "1",
    ]);
    assert!(p.status.success());
    common::assert_same_outputs(
        &out.join("replica-1"),
        &plain,
        &["wall_seconds", "particle_steps_per_second"],
    );
    // The averaged density: mean and s / sqrt(n) over the three members, recomputed here.
    let (h, avg) = table(&out.join("density.csv"));
    let members: Vec<_> = (0..3)
        .map(|r| table(&out.join(format!("replica-{r}/density.csv"))).1)
        .collect();
    let (mh, _) = table(&out.join("replica-0/density.csv"));
    assert_eq!(h[0], mh[0]);
    assert_eq!(h[1], mh[1]);
    assert_eq!(h[2], format!("{}_err", mh[1]));
    assert_eq!(mh[2], "err");
    assert_eq!(
        h.len(),
        3,
        "the members' own error column is replaced by the spread: {h:?}"
    );
    let mut spread = 0.0;
    for i in 0..avg[0].len() {
        let v: Vec<f64> = members.iter().map(|m| m[1][i]).collect();
        let mean = v.iter().sum::<f64>() / 3.0;
        let err = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 2.0 / 3.0).sqrt();
        assert!(
            (avg[1][i] - mean).abs() <= 1e-12 * mean.abs().max(1.0),
            "bin {i}"
        );
        assert!((avg[2][i] - err).abs() <= 1e-9 * err.max(1e-12), "bin {i}");
        spread += err;
    }
    assert!(spread > 0.0, "three seeds gave identical densities");
    // The summary's numbers, averaged.
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["completed"], true);
    assert_eq!(summary["members"], 3);
    let obs = std::fs::read_to_string(out.join("observables.csv")).unwrap();
    assert!(obs.starts_with("point,observable,mean,err,n\n"), "{obs}");
    assert!(obs.lines().count() > 1);
    // The folder is not overwritten.
    let again = run(&["ensemble", s, "--out", o, "--replicas", "2"]);
    assert!(!again.status.success());
}

#[test]
fn sweeps_are_validated_before_anything_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join("tiny.toml");
    std::fs::write(&sc, TINY).unwrap();
    let out = tmp.path().join("ens");
    let (s, o) = (sc.to_str().unwrap(), out.to_str().unwrap());
    let bad = run(&[
        "ensemble",
        s,
        "--out",
        o,
        "--replicas",
        "2",
        "--vary",
        "run.dt=[1e-3, -1.0]",
    ]);
    assert!(!bad.status.success());
    let msg = text(&bad);
    assert!(msg.contains("sweep point 1") && msg.contains("dt"), "{msg}");
    assert!(!out.exists(), "a folder was written for bad input");
    for (args, needle) in [
        (vec!["--vary", "run.dt"], "--vary"),
        (vec!["--vary", "seed=[1, 2]"], "--replicas"),
        (vec!["--replicas", "0"], "--replicas"),
        (
            vec![
                "--replicas",
                "10000",
                "--vary",
                "run.dt=[1e-3, 2e-3, 3e-3, 4e-3, 5e-3, 6e-3, 7e-3, 8e-3, 9e-3, 1e-2, 2e-2]",
            ],
            "more than 100000 members",
        ),
    ] {
        let mut a = vec!["ensemble", s, "--out", o];
        a.extend(args);
        let r = run(&a);
        assert!(!r.status.success());
        assert!(text(&r).contains(needle), "{}", text(&r));
        assert!(!out.exists());
    }
}

#[test]
fn a_sweep_writes_one_folder_per_point() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join("tiny.toml");
    std::fs::write(&sc, TINY).unwrap();
    let out = tmp.path().join("ens");
    let r = run(&[
        "ensemble",
        sc.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--replicas",
        "2",
        "--vary",
        "system.particles=[4, 6]",
        "--quiet",
    ]);
    assert!(r.status.success());
    assert!(r.stdout.is_empty(), "--quiet printed a closing line");
    for p in 0..2 {
        assert!(out.join(format!("point-{p}/density.csv")).exists());
        assert!(
            out.join(format!("point-{p}/replica-1/summary.json"))
                .exists()
        );
    }
    let obs = std::fs::read_to_string(out.join("observables.csv")).unwrap();
    assert!(obs.starts_with("point,system.particles,observable,mean,err,n\n"));
    assert!(obs.lines().any(|l| l.starts_with("1,6,")), "{obs}");
    let ran: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("point-1/replica-0/summary.json")).unwrap())
            .unwrap();
    assert_eq!(ran["parameters"]["system"]["particles"], 6, "{ran}");
}

#[test]
fn an_interrupted_ensemble_continues_to_the_uninterrupted_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join("tiny.toml");
    std::fs::write(&sc, TINY).unwrap();
    let s = sc.to_str().unwrap();
    let (reference, out) = (tmp.path().join("reference"), tmp.path().join("ens"));
    let args = [
        "--replicas",
        "3",
        "--vary",
        "system.particles=[4, 5]",
        "--quiet",
    ];
    let mut a = vec!["ensemble", s, "--out", reference.to_str().unwrap()];
    a.extend(args);
    assert!(run(&a).status.success());
    let mut a = vec!["ensemble", s, "--out", out.to_str().unwrap()];
    a.extend(args);
    let o = common::cli(&a, &[("COLLOIDSIM_INTERRUPT_AT_STEP", "1000")]);
    assert!(!o.status.success());
    assert!(
        text(&o).contains(&format!("colloidsim ensemble --restart {}", out.display())),
        "{}",
        text(&o)
    );
    assert!(out.join("point-0/replica-0/checkpoint.bin").exists());
    assert!(
        !out.join("summary.json").exists(),
        "an interrupted ensemble wrote a summary"
    );
    let o = out.to_str().unwrap();
    let bad = run(&["ensemble", "--restart", o, "--set", "run.dt=2e-3"]);
    assert!(!bad.status.success());
    assert!(
        run(&["ensemble", "--restart", o, "--quiet"])
            .status
            .success()
    );
    common::assert_same_tree(&reference, &out);
    let again = run(&["ensemble", "--restart", o]);
    assert!(!again.status.success());
    assert!(text(&again).contains("complete"), "{}", text(&again));
    let none = run(&["ensemble", "--restart", tmp.path().to_str().unwrap()]);
    assert!(text(&none).contains("ensemble.json"), "{}", text(&none));
}

/// A BCD sweep (2 points x 2 replicas) writes its headline observables (`Method::headline`):
/// one row per point, the swept key first, then every declared observable and its error, each
/// the mean and standard error s / sqrt(n) of the members' summary.json values, recomputed
/// here; and one picture per observable against the swept key.
#[test]
fn a_sweep_writes_the_headline_observables_with_the_replicas_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join("tiny.toml");
    std::fs::write(&sc, TINY).unwrap();
    let out = tmp.path().join("ens");
    let r = run(&[
        "ensemble",
        sc.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--replicas",
        "2",
        "--vary",
        "potential.cosine.amplitude=[1.0, 3.0]",
        "--set",
        "observe.current=true",
        "--set",
        "observe.contact_density={ bins = 10, window = 0.05 }",
        "--quiet",
    ]);
    assert!(r.status.success(), "{}", text(&r));
    let (h, rows) = table(&out.join("headline.csv"));
    let bcd = colloidsim_run::registry::find("bcd").unwrap();
    let mut want = vec!["potential.cosine.amplitude".to_string(), "replicas".into()];
    for d in bcd.headline() {
        want.push(d.name.to_string());
        want.push(format!("{}_err", d.name));
    }
    assert_eq!(h, want);
    assert_eq!(rows[0], [1.0, 3.0], "the swept key's values");
    assert_eq!(rows[1], [2.0, 2.0], "the replicas per point");
    for (p, amplitude) in ["1.0", "3.0"].iter().enumerate() {
        let members: Vec<serde_json::Value> = (0..2)
            .map(|r| {
                let f = out.join(format!("point-{p}/replica-{r}/summary.json"));
                serde_json::from_slice(&std::fs::read(f).unwrap()).unwrap()
            })
            .collect();
        for (k, d) in bcd.headline().iter().enumerate() {
            let v: Vec<f64> = members
                .iter()
                .map(|m| {
                    colloidsim_run::method::at(m, d.path)
                        .unwrap()
                        .as_f64()
                        .unwrap()
                })
                .collect();
            let mean = (v[0] + v[1]) / 2.0;
            // s / sqrt(2) with s^2 = sum (v - mean)^2 / (2 - 1)
            let err = (((v[0] - mean).powi(2) + (v[1] - mean).powi(2)) / 2.0).sqrt();
            let (m, e) = (rows[2 + 2 * k][p], rows[3 + 2 * k][p]);
            assert!(m.is_finite() && e.is_finite(), "{} at {amplitude}", d.name);
            assert!(
                (m - mean).abs() <= 1e-12 * mean.abs().max(1e-300),
                "{} at {amplitude}: {m} against the members' mean {mean}",
                d.name
            );
            assert!(
                (e - err).abs() <= 1e-9 * err.max(1e-300),
                "{} at {amplitude}: {e} against the members' standard error {err}",
                d.name
            );
        }
    }
    for d in bcd.headline() {
        assert!(
            out.join(format!("headline_{}.png", d.name)).exists(),
            "no picture of {}",
            d.name
        );
    }
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["headline"][1]["name"], "theory_l1");
    assert!(summary["points"][1]["headline"]["peak_density"]["mean"].is_f64());
}
