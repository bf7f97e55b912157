//! `colloidsim` under `mpirun -n 1, 2, 4` (built with `--features mpi`; `.ci/run` runs these
//! with Open MPI): an ensemble's folder, and a DPD, free-draining Brownian-dynamics or MPCD run
//! decomposed in space, are byte for byte
//! the single-process ones on any number of ranks, also when continued on another number of
//! ranks, and a failure on one rank stops every rank with its message instead of a hang.
#![cfg(feature = "mpi")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;
use common::{TINY_BCD as TINY, assert_same_tree, text};

/// `colloidsim ARGS` on `ranks` MPI ranks (oversubscribed; at most two minutes, so that a
/// hang fails the test with status 124), with extra environment variables.
fn mpirun_env(ranks: usize, args: &[&str], env: &[(&str, &str)]) -> Output {
    let o = Command::new("timeout")
        .args([
            "120",
            "mpirun",
            "--allow-run-as-root",
            "--oversubscribe",
            "-n",
        ])
        .arg(ranks.to_string())
        .arg(env!("CARGO_BIN_EXE_colloidsim"))
        .args(args)
        .envs(env.iter().copied())
        .output()
        .expect("mpirun (Open MPI) must be installed to run the MPI tests");
    eprintln!("{}", text(&o));
    assert_ne!(o.status.code(), Some(124), "mpirun -n {ranks} hung");
    o
}

fn mpirun(ranks: usize, args: &[&str]) -> Output {
    mpirun_env(ranks, args, &[])
}

/// The tiny scenario, written into `dir`.
fn tiny(dir: &Path) -> PathBuf {
    let sc = dir.join("tiny.toml");
    std::fs::write(&sc, TINY).unwrap();
    sc
}

/// The tiny scenario written into `dir`, and its ensemble with `args` run in one process on one
/// thread into `dir/serial`: (scenario path, reference folder).
fn serial_reference(dir: &Path, args: &[&str]) -> (String, PathBuf) {
    let sc = tiny(dir);
    let (s, reference) = (sc.to_str().unwrap().to_string(), dir.join("serial"));
    let mut a = vec![
        "ensemble",
        &s,
        "--out",
        reference.to_str().unwrap(),
        "--threads",
        "1",
    ];
    a.extend(args);
    assert!(common::cli(&a, &[]).status.success());
    (s, reference)
}

#[test]
fn an_ensemble_on_1_2_and_4_ranks_is_the_single_process_one() {
    let tmp = tempfile::tempdir().unwrap();
    let common_args = [
        "--replicas",
        "3",
        "--vary",
        "system.particles=[4, 5]",
        "--quiet",
    ];
    let (s, reference) = serial_reference(tmp.path(), &common_args);
    let s = s.as_str();
    for ranks in [1, 2, 4] {
        let out = tmp.path().join(format!("ranks-{ranks}"));
        let mut args = vec!["ensemble", s, "--out", out.to_str().unwrap()];
        args.extend(common_args);
        let o = mpirun(ranks, &args);
        assert!(o.status.success(), "mpirun -n {ranks}");
        assert_same_tree(&reference, &out);
    }
}

#[test]
fn bad_input_stops_every_rank_with_one_message() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tiny(tmp.path());
    let out = tmp.path().join("ens");
    let o = mpirun(
        3,
        &[
            "ensemble",
            sc.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--set",
            "run.dt=-1",
        ],
    );
    assert!(!o.status.success());
    let t = text(&o);
    assert_eq!(t.matches("error:").count(), 1, "{t}");
    assert!(t.contains("dt"), "{t}");
    assert!(!out.exists());
}

#[test]
fn a_member_failing_on_one_rank_stops_all_ranks_without_averages() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tiny(tmp.path());
    let out = tmp.path().join("ens");
    // Member 1 (rank 1 of 2) cannot create its folder: a file holds its name.
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("replica-1"), b"in the way").unwrap();
    let o = mpirun(
        2,
        &[
            "ensemble",
            sc.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--replicas",
            "4",
            "--force",
            "--quiet",
        ],
    );
    assert!(!o.status.success());
    let t = text(&o);
    assert!(
        t.contains("1 of 4 members failed") && t.contains("replica-1"),
        "{t}"
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["completed"], false);
    assert_eq!(summary["failed"][0]["member"], 1);
    assert!(
        !out.join("density.csv").exists(),
        "averages written despite a failed member"
    );
    assert!(
        out.join("replica-3/summary.json").exists(),
        "rank 1's other member did not run"
    );
}

#[test]
fn run_refuses_several_ranks_for_a_method_not_decomposed() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tiny(tmp.path());
    let out = tmp.path().join("run");
    let o = mpirun(
        2,
        &["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()],
    );
    assert!(!o.status.success());
    let t = text(&o);
    assert_eq!(t.matches("error:").count(), 1, "{t}");
    assert!(
        t.contains("runs on one rank") && t.contains("colloidsim ensemble"),
        "{t}"
    );
    assert!(!out.exists());
    let one = mpirun(
        1,
        &[
            "run",
            sc.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ],
    );
    assert!(one.status.success());
}

/// DPD colloids (12 colloids in 1382 solvent beads, Verlet lists) for 400 steps, observing
/// everything: the decomposed runs.
const TINY_DPD: &str = r#"
method = "dpd"
seed = 5
[system]
box_length = 8.0
phi = 0.1
[run]
steps = 400
[observe]
thermo_every = 20
trajectory_every = 100
msd_every = 50
"#;

#[test]
fn a_dpd_run_on_1_2_3_and_4_ranks_writes_the_single_process_folder() {
    // The box has 4 layers of cells: on 3 ranks one rank owns two layers. The reference ran
    // on one thread.
    let tmp = tempfile::tempdir().unwrap();
    let (s, reference) = reference(tmp.path(), "dpd", TINY_DPD);
    for ranks in [1, 2, 3, 4] {
        let out = tmp.path().join(format!("ranks-{ranks}"));
        // Ranks times threads: two ranks of two threads each.
        let threads = if ranks == 2 { "2" } else { "1" };
        let o = mpirun(
            ranks,
            &[
                "run",
                &s,
                "--out",
                out.to_str().unwrap(),
                "--threads",
                threads,
            ],
        );
        assert!(o.status.success(), "mpirun -n {ranks}");
        // One report, from rank 0.
        assert_eq!(text(&o).matches("wrote ").count(), 1, "{}", text(&o));
        assert_same_tree(&reference, &out);
        let summary: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
        assert_eq!(summary["ranks"], ranks);
    }
}

#[test]
fn a_dpd_run_on_a_grid_of_2_x_2_ranks_writes_the_single_process_folder() {
    // Cut along y as well as z (`run.rank_grid`): each rank holds fringe rows of ghosts and
    // computes the pairs across the y cut itself; the folder is still the single-process one.
    let tmp = tempfile::tempdir().unwrap();
    let text_2x2 = TINY_DPD.replace("steps = 400", "steps = 400\nrank_grid = [2, 2]");
    let (s, reference) = reference(tmp.path(), "dpd-grid", &text_2x2);
    let out = tmp.path().join("grid");
    let o = mpirun(4, &["run", &s, "--out", out.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", text(&o));
    assert_same_tree(&reference, &out);
    // A grid that is not the number of ranks: refused once, naming the key.
    let out = tmp.path().join("three");
    let o = mpirun(3, &["run", &s, "--out", out.to_str().unwrap(), "--quiet"]);
    assert!(!o.status.success());
    let t = text(&o);
    assert_eq!(t.matches("error:").count(), 1, "{t}");
    assert!(
        t.contains("run.rank_grid") && t.contains("for 3 ranks"),
        "{t}"
    );
}

/// DPD water sheared by Lees–Edwards boundaries (`examples/dpd/shear.toml`, shortened): 1536
/// beads in a box of 8 layers of cells, 600 steps.
const SHEARED_DPD: &str = r#"
method = "dpd"
seed = 1
[system]
box_length = 8.0
density = 3.0
phi = 0.0
kT = 1.0
[run]
dt = 0.01
steps = 600
shear_rate = 0.5
[observe]
thermo_every = 50
trajectory_every = 200
msd_every = 0
structure_every = 0
profile_bins = 16
"#;

#[test]
fn a_sheared_dpd_run_on_2_and_3_ranks_writes_the_single_process_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let (s, reference) = reference(tmp.path(), "shear", SHEARED_DPD);
    assert!(reference.join("velocity_profile.csv").exists());
    for ranks in [2, 3] {
        let out = tmp.path().join(format!("ranks-{ranks}"));
        let o = mpirun(
            ranks,
            &["run", &s, "--out", out.to_str().unwrap(), "--quiet"],
        );
        assert!(o.status.success(), "mpirun -n {ranks}");
        assert_same_tree(&reference, &out);
    }
}

#[test]
fn a_dpd_run_interrupted_on_2_ranks_continues_on_1_and_4() {
    let tmp = tempfile::tempdir().unwrap();
    let (s, reference) = reference(tmp.path(), "dpd", TINY_DPD);
    for ranks in [1, 4] {
        let out = tmp.path().join(format!("continued-on-{ranks}"));
        interrupted_on_2_continued_on(ranks, &s, &out, "150");
        assert_same_tree(&reference, &out);
    }
}

/// Run scenario `s` into `out` on 2 ranks, interrupted at step `at`, and continue it on
/// `ranks` ranks (in one process for 1).
fn interrupted_on_2_continued_on(ranks: usize, s: &str, out: &Path, at: &str) {
    let o = mpirun_env(
        2,
        &["run", s, "--out", out.to_str().unwrap(), "--quiet"],
        &[("COLLOIDSIM_INTERRUPT_AT_STEP", at)],
    );
    assert!(!o.status.success());
    let t = text(&o);
    assert!(t.contains("mpirun -n N colloidsim run --restart"), "{t}");
    assert_eq!(t.matches("error:").count(), 1, "{t}");
    assert!(out.join("checkpoint.bin").exists());
    let args = ["run", "--restart", out.to_str().unwrap(), "--quiet"];
    let r = if ranks == 1 {
        common::cli(&args, &[])
    } else {
        mpirun(ranks, &args)
    };
    assert!(r.status.success(), "restart on {ranks} ranks: {}", text(&r));
}

#[test]
fn a_failing_decomposed_run_stops_every_rank_with_one_message() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join("dpd.toml");
    std::fs::write(&sc, TINY_DPD).unwrap();
    let s = sc.to_str().unwrap();
    // Rank 0 alone cannot create the folder (it holds a file): the job ends with its message.
    let taken = tmp.path().join("taken");
    std::fs::create_dir_all(&taken).unwrap();
    std::fs::write(taken.join("notes.txt"), b"mine").unwrap();
    let o = mpirun(3, &["run", s, "--out", taken.to_str().unwrap(), "--quiet"]);
    assert!(!o.status.success());
    let t = text(&o);
    assert_eq!(t.matches("error:").count(), 1, "{t}");
    assert!(t.contains("already exists"), "{t}");
    assert_eq!(std::fs::read_dir(&taken).unwrap().count(), 1);
    // More ranks than layers of cells: refused on every rank, said once.
    let out = tmp.path().join("many");
    let o = mpirun(5, &["run", s, "--out", out.to_str().unwrap(), "--quiet"]);
    assert!(!o.status.success());
    let t = text(&o);
    assert_eq!(t.matches("error:").count(), 1, "{t}");
    assert!(t.contains("5 ranks for 4 layers of cells"), "{t}");
    assert!(!out.exists());
    // A time step far too large: every rank stops at the same step, rank 0 writes the outputs
    // so far and a summary saying so, and the message comes once.
    let out = tmp.path().join("unstable");
    let o = mpirun(
        2,
        &[
            "run",
            s,
            "--out",
            out.to_str().unwrap(),
            "--quiet",
            "--set",
            "run.dt=0.3",
        ],
    );
    assert!(!o.status.success());
    let t = text(&o);
    assert_eq!(t.matches("error:").count(), 1, "{t}");
    assert!(t.contains("reduce run.dt"), "{t}");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["completed"], false);
}

#[test]
fn an_ensemble_interrupted_on_2_ranks_continues_on_1_and_4() {
    let tmp = tempfile::tempdir().unwrap();
    let args = ["--replicas", "5", "--quiet"];
    let (s, reference) = serial_reference(tmp.path(), &args);
    let s = s.as_str();
    for ranks in [1, 4] {
        let out = tmp.path().join(format!("continued-on-{ranks}"));
        let mut a = vec!["ensemble", s, "--out", out.to_str().unwrap()];
        a.extend(args);
        let o = mpirun_env(2, &a, &[("COLLOIDSIM_INTERRUPT_AT_STEP", "1000")]);
        assert!(!o.status.success());
        assert!(text(&o).contains("--restart"), "{}", text(&o));
        assert!(out.join("replica-1/checkpoint.bin").exists());
        let r = mpirun(
            ranks,
            &["ensemble", "--restart", out.to_str().unwrap(), "--quiet"],
        );
        assert!(r.status.success(), "restart on {ranks} ranks");
        assert_same_tree(&reference, &out);
    }
}

/// A drying droplet, free draining: 400 colloids, 2 replicas of 6166 steps, profiles, a
/// trajectory of replica 0 and its cross-section; its box has 14 layers of cells, most of
/// them empty at first.
const TINY_DROPLET: &str = r#"
method = "droplet-bd"
seed = 5
replicas = 2
[system]
particles = 400
phi0 = 0.1
[drying]
peclet = 10
final_volume_fraction = 0.3
[run]
dt = 0.0025
[observe]
profile = { bins = 12, fractions = [0, 0.5, 1.0] }
trajectory = { every = 100 }
cross_section = { width = 1.0 }
"#;

/// Bulk Brownian dynamics, free draining (Leimkuhler–Matthews) under a body force: 400
/// spheres, 2 replicas of 1100 steps, MSD blocks and a trajectory of replica 0.
const TINY_BULK_BD: &str = r#"
method = "bd"
seed = 4
replicas = 2
[system]
particles = 400
box_length = 10.0
body_force = [1.0, 0.0, -2.0]
[run]
dt = 0.002
time = 2.0
equilibrate = 0.2
integrator = "lm"
[observe.trajectory]
every = 100
"#;

/// `scenario` as `dir/NAME.toml` and its run in one process on one thread into
/// `dir/NAME-serial`.
fn reference(dir: &Path, name: &str, scenario: &str) -> (String, PathBuf) {
    let sc = dir.join(format!("{name}.toml"));
    std::fs::write(&sc, scenario).unwrap();
    let reference = dir.join(format!("{name}-serial"));
    let (s, r) = (sc.to_str().unwrap(), reference.to_str().unwrap());
    let o = common::cli(&["run", s, "--out", r, "--threads", "1", "--quiet"], &[]);
    assert!(o.status.success(), "{}", text(&o));
    (s.to_string(), reference)
}

#[test]
fn a_droplet_bd_run_on_1_2_3_and_4_ranks_writes_the_single_process_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let (s, reference) = reference(tmp.path(), "droplet", TINY_DROPLET);
    for ranks in [1, 2, 3, 4] {
        let out = tmp.path().join(format!("ranks-{ranks}"));
        let threads = if ranks == 2 { "2" } else { "1" };
        let o = mpirun(
            ranks,
            &[
                "run",
                &s,
                "--out",
                out.to_str().unwrap(),
                "--threads",
                threads,
            ],
        );
        assert!(o.status.success(), "mpirun -n {ranks}");
        assert_eq!(text(&o).matches("outputs in").count(), 1, "{}", text(&o));
        assert_same_tree(&reference, &out);
        assert!(out.join("cross_section.csv").exists());
        let summary: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
        assert_eq!(summary["ranks"], ranks);
    }
}

#[test]
fn bd_runs_interrupted_on_2_ranks_continue_on_1_and_3() {
    let tmp = tempfile::tempdir().unwrap();
    // Interrupted in replica 1 (droplet) and in replica 1's sampling (bulk).
    for (name, scenario, at) in [
        ("droplet", TINY_DROPLET, "7000"),
        ("bulk", TINY_BULK_BD, "1500"),
    ] {
        let (s, reference) = reference(tmp.path(), name, scenario);
        if name == "bulk" {
            let out = tmp.path().join("bulk-on-3");
            let o = mpirun(3, &["run", &s, "--out", out.to_str().unwrap(), "--quiet"]);
            assert!(o.status.success());
            assert_same_tree(&reference, &out);
        }
        for ranks in [1, 3] {
            let out = tmp.path().join(format!("{name}-continued-on-{ranks}"));
            interrupted_on_2_continued_on(ranks, &s, &out, at);
            assert_same_tree(&reference, &out);
        }
    }
}

#[test]
fn a_failing_bd_run_on_ranks_stops_every_rank_with_one_message() {
    let tmp = tempfile::tempdir().unwrap();
    let sc = tmp.path().join("droplet.toml");
    std::fs::write(&sc, TINY_DROPLET).unwrap();
    let s = sc.to_str().unwrap();
    // A time step too large: the single-process run's message and outputs, once.
    let unstable = ["--quiet", "--set", "run.dt=0.005"];
    let one = tmp.path().join("one");
    let o = common::cli(
        &[&["run", s, "--out", one.to_str().unwrap()][..], &unstable].concat(),
        &[],
    );
    assert!(!o.status.success());
    let want = text(&o);
    let want = want.lines().find(|l| l.starts_with("error:")).unwrap();
    let out = tmp.path().join("unstable");
    let o = mpirun(
        2,
        &[&["run", s, "--out", out.to_str().unwrap()][..], &unstable].concat(),
    );
    assert!(!o.status.success());
    let t = text(&o);
    assert_eq!(t.matches("error:").count(), 1, "{t}");
    assert!(t.contains(want), "{t}");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["completed"], false);
    // Hydrodynamics is not decomposed: refused on every rank before anything is written.
    let rpy = tmp.path().join("rpy.toml");
    std::fs::write(
        &rpy,
        "method = \"bd\"\n[system]\nparticles = 20\nbox_length = 8.0\n[run]\ndt = 0.01\ntime = 0.5\n[hydrodynamics]\nmodel = \"rpy\"\n",
    )
    .unwrap();
    let out = tmp.path().join("rpy");
    let o = mpirun(
        2,
        &["run", rpy.to_str().unwrap(), "--out", out.to_str().unwrap()],
    );
    assert!(!o.status.success());
    let t = text(&o);
    assert_eq!(t.matches("error:").count(), 1, "{t}");
    assert!(t.contains("runs on one rank"), "{t}");
    assert!(!out.exists());
}

/// The SRD solvent (2560 particles in 8 x 8 x 8 cells) in periodic Poiseuille flow for 300
/// collisions, with a trajectory of the solvent: the decomposed MPCD runs.
const TINY_MPCD: &str = r#"
method = "mpcd"
seed = 3
[system]
box = 8
[run]
collisions = 300
[viscosity]
[observe]
every = 10
[observe.trajectory]
every = 100
solvent = true
"#;

#[test]
fn an_mpcd_solvent_on_1_to_4_ranks_writes_the_single_process_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let (s, reference) = reference(tmp.path(), "mpcd", TINY_MPCD);
    for ranks in [1, 2, 3, 4] {
        let out = tmp.path().join(format!("ranks-{ranks}"));
        let threads = if ranks == 2 { "2" } else { "1" };
        let args = [
            "run",
            &s,
            "--out",
            out.to_str().unwrap(),
            "--threads",
            threads,
        ];
        let o = mpirun(ranks, &args);
        assert!(o.status.success(), "mpirun -n {ranks}");
        assert_same_tree(&reference, &out);
    }
    // Without the cell thermostat the flow's heat leaves by a global rescaling (a sum over
    // all ranks every collision).
    let cold = ["--set", "solvent.thermostat=false", "--quiet"];
    let one = tmp.path().join("no-thermostat");
    let o = common::cli(
        &[&["run", &s, "--out", one.to_str().unwrap()][..], &cold].concat(),
        &[],
    );
    assert!(o.status.success(), "{}", text(&o));
    let three = tmp.path().join("no-thermostat-3");
    let o = mpirun(
        3,
        &[&["run", &s, "--out", three.to_str().unwrap()][..], &cold].concat(),
    );
    assert!(o.status.success());
    assert_same_tree(&one, &three);
    // Interrupted on 2 ranks, continued on 1 and on 3.
    for ranks in [1, 3] {
        let out = tmp.path().join(format!("continued-on-{ranks}"));
        interrupted_on_2_continued_on(ranks, &s, &out, "150");
        assert_same_tree(&reference, &out);
    }
}

/// Two colloids of the default diameter (42 vertices each) in the solvent of a cube of 10
/// cells for 200 collisions, their velocity autocorrelation and a trajectory with the solvent.
const TINY_MPCD_COLLOIDS: &str = r#"
method = "mpcd"
seed = 4
[system]
box = 10
colloids = 2
[run]
collisions = 200
[observe]
vacf_lags = 10
[observe.trajectory]
every = 100
solvent = true
"#;

/// `scenario` under `mpirun` on each of `ranks`, and interrupted on 2 ranks at `at` and
/// continued on `continued`: every folder is the single-process one.
fn writes_the_single_process_folder(
    name: &str,
    scenario: &str,
    ranks: &[usize],
    at: &str,
    continued: usize,
) {
    let tmp = tempfile::tempdir().unwrap();
    let (s, reference) = reference(tmp.path(), name, scenario);
    for &r in ranks {
        let out = tmp.path().join(format!("ranks-{r}"));
        let o = mpirun(r, &["run", &s, "--out", out.to_str().unwrap(), "--quiet"]);
        assert!(o.status.success(), "mpirun -n {r}");
        assert_same_tree(&reference, &out);
    }
    let out = tmp.path().join(format!("continued-on-{continued}"));
    interrupted_on_2_continued_on(continued, &s, &out, at);
    assert_same_tree(&reference, &out);
}

#[test]
fn mpcd_with_colloids_on_2_and_3_ranks_writes_the_single_process_folder() {
    writes_the_single_process_folder("colloids", TINY_MPCD_COLLOIDS, &[2, 3], "120", 3);
}

#[test]
fn an_mpcd_droplet_on_2_and_3_ranks_writes_the_single_process_folder() {
    // With the solvent in the trajectory (the last section).
    let droplet = format!("{}solvent = true\n", common::MPCD_DROPLET_COLLOIDS);
    writes_the_single_process_folder("droplet-mpcd", &droplet, &[2, 3], "170", 1);
}

#[test]
fn a_dpd_run_on_2_ranks_stops_within_its_budget_with_one_status_and_continues_on_1() {
    // On the fake clock (1/8 s a step, docs/cluster.md): 30 s less the 10 s margin hold at
    // most 160 steps; both ranks stop at the same synchronised step, exit with 83, and one
    // message names the command that continues.
    let tmp = tempfile::tempdir().unwrap();
    let (s, reference) = reference(tmp.path(), "dpd", TINY_DPD);
    let out = tmp.path().join("budget");
    let o = mpirun_env(
        2,
        &[
            "run",
            &s,
            "--out",
            out.to_str().unwrap(),
            "--walltime",
            "30",
            "--quiet",
        ],
        &[("COLLOIDSIM_FAKE_STEP_SECONDS", "0.125")],
    );
    let t = text(&o);
    assert_eq!(o.status.code(), Some(83), "{t}");
    assert_eq!(t.matches("error:").count(), 1, "{t}");
    assert!(
        t.contains(&format!(
            "mpirun -n N colloidsim run --restart {} --walltime 30",
            out.display()
        )),
        "{t}"
    );
    assert!(out.join("checkpoint.bin").exists());
    let r = common::cli(&["run", "--restart", out.to_str().unwrap(), "--quiet"], &[]);
    assert!(r.status.success());
    assert_same_tree(&reference, &out);
}

#[test]
fn sigusr1_to_mpirun_stops_every_rank_of_a_dpd_run_at_one_checkpoint() {
    // mpirun passes SIGUSR1 on to every rank (Open MPI; srun does too): the ranks, waiting at
    // step 100 (test hook), agree on the stop and exit with 82.
    use std::io::{BufRead, BufReader, Read};
    let tmp = tempfile::tempdir().unwrap();
    let (s, reference) = reference(tmp.path(), "dpd", TINY_DPD);
    let out = tmp.path().join("signalled");
    let mut child = Command::new("mpirun")
        .args(["--allow-run-as-root", "--oversubscribe", "-n", "2"])
        .arg(env!("CARGO_BIN_EXE_colloidsim"))
        .args(["run", &s, "--out", out.to_str().unwrap(), "--quiet"])
        .env("COLLOIDSIM_PAUSE_AT_STEP", "100")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut seen = String::new();
    while seen.matches("(test hook)").count() < 2 {
        let mut line = String::new();
        assert!(err.read_line(&mut line).unwrap() > 0, "{seen}");
        seen.push_str(&line);
    }
    let pid = child.id().to_string();
    assert!(
        Command::new("kill")
            .args(["-s", "USR1", &pid])
            .status()
            .unwrap()
            .success()
    );
    err.read_to_string(&mut seen).unwrap();
    let status = child.wait().unwrap();
    eprintln!("{seen}");
    assert_eq!(status.code(), Some(82), "{seen}");
    assert!(seen.contains("stopped by SIGUSR1 at step 100"), "{seen}");
    assert!(out.join("checkpoint.bin").exists());
    let r = common::cli(&["run", "--restart", out.to_str().unwrap(), "--quiet"], &[]);
    assert!(r.status.success());
    assert_same_tree(&reference, &out);
}
