//! Hostile input, for every method: scenarios with keys set to extreme or wrong values, damaged
//! GSD input files and damaged checkpoints must give a clean error or a valid run, never a
//! panic or an abort (proptest reports a panic as a failure with the input that caused it).
//!
//! The cases are drawn from a fixed seed, so that every run (CI's too) checks the same inputs;
//! `COLLOIDSIM_FUZZ_RANDOM=1 cargo test -p colloidsim-run --test fuzz` draws new ones, and a
//! failure found so is saved in `fuzz.proptest-regressions` and replayed by every later run.

use colloidsim_run::{Control, RunOptions, Scenario};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use std::path::Path;

/// `cases` cases from the fixed seed, or from a random one with `COLLOIDSIM_FUZZ_RANDOM` set.
fn fuzz_config(cases: u32) -> ProptestConfig {
    let rng_seed = if std::env::var_os("COLLOIDSIM_FUZZ_RANDOM").is_some() {
        RngSeed::Random
    } else {
        RngSeed::Fixed(20_261_202)
    };
    ProptestConfig {
        cases,
        rng_seed,
        ..ProptestConfig::default()
    }
}

/// Small, fast scenarios of each method (the mutations start from these); every registered
/// method has one (tested), and the keys mutated are the registry's declarations.
const BASES: [&str; 11] = [
    r#"method = "bcd"
seed = 3
[system]
length = 20.0
particles = 10
diameter = 0.5
[potential]
cosine = { amplitude = 6.0, wavelength = 1.0 }
[run]
dt = 1e-4
time = 0.01
[observe]
density = { bins = 20 }
contact_density = { bins = 20, window = 0.1 }
msd = { points = 5 }
clusters = true
current = true
"#,
    r#"method = "bcd"
[system]
length = 10.0
particles = 5
diameter = 1.0
boundary = "walls"
[potential]
harmonic = { stiffness = 1.0 }
[interaction]
sticky = { gamma = 1.0 }
[run]
dt = 1e-5
time = 0.001
[observe]
density = { bins = 10 }
"#,
    r#"method = "droplet-bd"
[system]
particles = 30
phi0 = 0.05
[drying]
peclet = 5.0
final_volume_fraction = 0.06
[observe.profile]
bins = 10
fractions = [0.0, 1.0]
"#,
    r#"method = "droplet-bd"
[system]
particles = 30
phi0 = 0.05
[drying]
peclet = 5.0
final_volume_fraction = 0.06
[hydrodynamics]
model = "rpy"
method = "direct"
[observe.profile]
bins = 10
fractions = [0.0, 1.0]
"#,
    r#"method = "droplet-bd"
[system]
particles = 30
phi0 = 0.05
[drying]
peclet = 5.0
final_volume_fraction = 0.06
[hydrodynamics]
model = "rpy"
method = "pse"
[observe.profile]
bins = 10
fractions = [0.0, 1.0]
"#,
    r#"method = "bd"
[system]
particles = 20
box_length = 8.0
body_force = [0.0, 0.0, -1.0]
[run]
dt = 0.01
time = 0.4
[observe.trajectory]
every = 10
[hydrodynamics]
model = "rpy"
"#,
    r#"method = "bd"
[system]
particles = 30
box_length = 6.0
[run]
dt = 0.01
time = 0.4
integrator = "lm"
"#,
    r#"method = "dpd"
[system]
box_length = 7.0
phi = 0.05
[run]
steps = 20
[observe]
thermo_every = 5
structure_every = 10
"#,
    r#"method = "mpcd"
[system]
box = 6.0
[run]
collisions = 20
[viscosity]
[observe.trajectory]
every = 10
solvent = true
"#,
    r#"method = "droplet-mpcd"
boundary = "no-slip"
[system]
radius = 3.0
[drying]
duration = 5.0
[observe.solvent]
window = 5
"#,
    r#"method = "hs-mc"
[system]
geometry = "hard-wall"
particles = 20
radius = 3.0
[mc]
sweeps = 20
warmup_sweeps = 10
blocks = 2
[output]
profile_bins = 10
"#,
];

/// The method a base scenario names.
fn method_of(text: &str) -> String {
    let t: toml::Table = toml::from_str(text).unwrap();
    t["method"].as_str().unwrap().to_string()
}

#[test]
fn every_registered_method_has_a_base_scenario() {
    for m in colloidsim_run::registry::all() {
        assert!(
            BASES
                .iter()
                .any(|b| m.names().contains(&method_of(b).as_str())),
            "no base scenario of {}",
            m.names()[0]
        );
    }
}

/// Values a hostile user types.
fn hostile() -> impl Strategy<Value = toml::Value> {
    use toml::Value as V;
    prop_oneof![
        Just(V::Integer(0)),
        Just(V::Integer(-1)),
        Just(V::Integer(1)),
        Just(V::Integer(i64::MAX)),
        Just(V::Integer(1 << 40)),
        Just(V::Float(0.0)),
        Just(V::Float(-1e-300)),
        Just(V::Float(1e300)),
        Just(V::Float(-1e300)),
        Just(V::Float(f64::NAN)),
        Just(V::Float(f64::INFINITY)),
        Just(V::Float(1e-12)),
        Just(V::Float(1e12)),
        (-3.0f64..3.0).prop_map(V::Float),
        (0i64..100_000).prop_map(V::Integer),
        Just(V::String(String::new())),
        Just(V::String("walls".into())),
        Just(V::String("no-such-file.gsd".into())),
        Just(V::Boolean(true)),
        Just(V::Array(vec![])),
        Just(V::Array(vec![V::Float(1e300)])),
        Just(V::Array(vec![V::Float(0.5), V::Float(0.5), V::Float(0.5)])),
        Just(V::Table(Default::default())),
    ]
}

/// Set `path` (dotted) in `t`, replacing whatever is in the way.
fn set(t: &mut toml::Table, path: &str, v: toml::Value) {
    let mut parts: Vec<&str> = path.split('.').collect();
    let last = parts.pop().unwrap();
    let mut t = t;
    for p in parts {
        let e = t
            .entry(p.to_string())
            .or_insert_with(|| toml::Value::Table(Default::default()));
        if !e.is_table() {
            *e = toml::Value::Table(Default::default());
        }
        t = e.as_table_mut().unwrap();
    }
    t.insert(last.to_string(), v);
}

/// Check the scenario; when valid and small, build its engine and step it, and run it.
fn exercise(doc: &toml::Table) {
    let Ok(sc) = Scenario::from_table(doc, Path::new(".")) else {
        return;
    };
    if colloidsim_run::check(&sc).is_err() {
        return;
    }
    let Ok(mut e) = colloidsim_run::engine(&sc, None) else {
        return;
    };
    if e.particles() <= 20_000 {
        let _ = e.step(3);
        let _ = (e.positions(), e.velocities(), e.forces());
    }
}

proptest! {
    #![proptest_config(fuzz_config(192))]

    #[test]
    fn hostile_scenarios_are_refused_or_run_never_panic(
        base in 0..BASES.len(),
        picks in proptest::collection::vec((any::<prop::sample::Index>(), hostile()), 1..4),
    ) {
        let text = BASES[base];
        let spec = colloidsim_run::registry::find(&method_of(text)).unwrap().keys();
        let mut doc: toml::Table = toml::from_str(text).unwrap();
        for (k, v) in picks {
            set(&mut doc, k.get(spec).path, v);
        }
        exercise(&doc);
    }
}

/// A small GSD frame of a droplet, then every truncation and byte flips of it as
/// `system.initial`: refused with an error naming the file, or accepted; no panic.
#[test]
fn damaged_initial_gsd_files_are_refused_not_panicked_on() {
    let dir = tempfile::tempdir().unwrap();
    let base = BASES[2];
    let sc = Scenario::from_toml(base, dir.path()).unwrap();
    let opts = RunOptions {
        out: Some(dir.path().join("run")),
        ..Default::default()
    };
    // A trajectory to start from: one run with frames.
    let traj_sc = Scenario::from_toml(
        &format!("{base}[observe.trajectory]\nevery = 50\n"),
        dir.path(),
    )
    .unwrap();
    drop(sc);
    colloidsim_run::run(&traj_sc, &opts, &Control::default()).unwrap();
    let good = std::fs::read(dir.path().join("run/trajectory.gsd")).unwrap();
    let start = base.replace("phi0 = 0.05\n", "phi0 = 0.05\ninitial = \"initial.gsd\"\n");
    let sc = Scenario::from_toml(&start, dir.path()).unwrap();
    let path = dir.path().join("initial.gsd");
    std::fs::write(&path, &good).unwrap();
    colloidsim_run::check(&sc).expect("the undamaged file is accepted");
    let mut refused = 0;
    let n = good.len();
    let cuts = (0..n).step_by((n / 97).max(1));
    for cut in cuts {
        std::fs::write(&path, &good[..cut]).unwrap();
        refused += usize::from(colloidsim_run::check(&sc).is_err());
    }
    for i in (0..n).step_by((n / 61).max(1)) {
        let mut b = good.clone();
        b[i] ^= 0xA5;
        std::fs::write(&path, &b).unwrap();
        let _ = colloidsim_run::check(&sc);
    }
    assert!(refused > 90, "only {refused} truncations refused");
}

/// A real checkpoint with a flipped byte anywhere is refused by the restart.
#[test]
fn damaged_checkpoints_are_refused_by_the_restart() {
    let dir = tempfile::tempdir().unwrap();
    let text = BASES[0].replace("time = 0.01", "time = 0.05");
    let sc = Scenario::from_toml(&text, dir.path()).unwrap();
    let out = dir.path().join("run");
    let ctl = Control::default();
    // Interrupt at once: the driver writes a checkpoint and stops.
    ctl.interrupt();
    let opts = RunOptions {
        out: Some(out.clone()),
        ..Default::default()
    };
    let e = colloidsim_run::run(&sc, &opts, &ctl).unwrap_err();
    assert!(
        e.downcast_ref::<colloidsim_run::Interrupted>().is_some(),
        "{e:#}"
    );
    let ck = out.join("checkpoint.bin");
    let good = std::fs::read(&ck).unwrap();
    for i in (0..good.len()).step_by((good.len() / 53).max(1)) {
        let mut b = good.clone();
        b[i] ^= 0x10;
        std::fs::write(&ck, &b).unwrap();
        let r = colloidsim_run::resume(&out, None, None, &Control::default());
        assert!(r.is_err(), "a flip of byte {i} was accepted");
    }
    // The undamaged checkpoint continues.
    std::fs::write(&ck, &good).unwrap();
    colloidsim_run::resume(&out, None, None, &Control::default()).unwrap();
}

/// Lines of a CSV table a hostile user (or a damaged disk) gives: numbers of every kind,
/// missing or extra fields, text, nothing.
fn csv_line() -> impl Strategy<Value = String> {
    let number = prop_oneof![
        (-5.0f64..15.0).prop_map(|x| x.to_string()),
        Just("nan".to_string()),
        Just("inf".to_string()),
        Just("-inf".to_string()),
        Just("1e300".to_string()),
        Just("-1e-320".to_string()),
        Just("0".to_string()),
        Just(String::new()),
        Just("x".to_string()),
        "[ -~]{0,6}",
    ];
    proptest::collection::vec(number, 0..4).prop_map(|v| v.join(","))
}

/// Contents of an input table: a header the reader expects (or not) and hostile lines, or
/// raw bytes.
fn csv_file() -> impl Strategy<Value = Vec<u8>> {
    let header = prop_oneof![
        Just("x,U"),
        Just("r,f"),
        Just("x"),
        Just("U,x"),
        Just(""),
        Just("# comment"),
    ];
    prop_oneof![
        (header, proptest::collection::vec(csv_line(), 0..12)).prop_map(|(h, lines)| format!(
            "{h}\n{}\n",
            lines.join("\n")
        )
        .into_bytes()),
        proptest::collection::vec(any::<u8>(), 0..200),
    ]
}

/// Scenarios reading a table: a periodic potential, a pair force, initial positions.
const TABLE_SCENARIOS: [&str; 3] = [
    r#"method = "bcd"
[system]
length = 10.0
particles = 4
diameter = 0.5
[potential]
table = "table.csv"
[run]
dt = 1e-4
time = 0.001
[observe]
density = { bins = 10 }
"#,
    r#"method = "bcd"
[system]
length = 10.0
particles = 4
diameter = 0.5
[interaction]
table = "table.csv"
[run]
dt = 1e-4
time = 0.001
[observe]
density = { bins = 10 }
"#,
    r#"method = "bcd"
[system]
length = 10.0
particles = 4
diameter = 0.5
[initial]
placement = "file"
file = "table.csv"
[run]
dt = 1e-4
time = 0.001
[observe]
density = { bins = 10 }
"#,
];

proptest! {
    #![proptest_config(fuzz_config(256))]

    /// Every CSV input of a scenario (potential and pair tables, initial positions): a clean
    /// error naming the file, or a valid run; never a panic.
    #[test]
    fn hostile_input_tables_are_refused_or_run_never_panic(
        which in 0..TABLE_SCENARIOS.len(),
        content in csv_file(),
    ) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("table.csv"), &content).unwrap();
        let Ok(sc) = Scenario::from_toml(TABLE_SCENARIOS[which], dir.path()) else {
            return Ok(());
        };
        match colloidsim_run::check(&sc) {
            Err(e) => {
                let msg = format!("{e:#}");
                prop_assert!(msg.contains("table.csv"), "the error names the file: {msg}");
            }
            Ok(_) => {
                let mut e = colloidsim_run::engine(&sc, None).unwrap();
                let _ = e.step(10);
            }
        }
    }
}

/// The mutations start from valid scenarios (else they would test nothing but the refusal).
#[test]
fn every_base_scenario_is_valid_and_steps() {
    for text in BASES {
        let sc = Scenario::from_toml(text, Path::new(".")).unwrap();
        colloidsim_run::check(&sc).unwrap_or_else(|e| panic!("{e:#}\n{text}"));
        let mut e = colloidsim_run::engine(&sc, None).unwrap();
        e.step(3).unwrap();
    }
}
