//! Hostile input, for every method: scenarios with keys set to extreme or wrong values, damaged
//! GSD input files and damaged checkpoints must give a clean error or a valid run, never a
//! panic or an abort (proptest reports a panic as a failure with the input that caused it).
//!
//! The cases are drawn from a fixed seed, so that every run (CI's too) checks the same inputs;
//! `COLLOIDSIM_FUZZ_RANDOM=1 cargo test -p colloidsim-run --test integration fuzz::` draws new ones, and a
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

/// Values a user could type for the key `spec`, drawn from its declaration: the ends of its
/// allowed range, points inside it (log-uniform over many decades for an open-ended range, where
/// a value such as kT = 1e300 is allowed but may still make nonsense), every allowed word,
/// mixed with [`hostile`] values.
fn declared(spec: &colloidsim_run::keys::Spec) -> BoxedStrategy<toml::Value> {
    use colloidsim_run::keys::Allowed as A;
    use toml::Value as V;
    let log = |lo: f64, hi: f64| {
        (lo.log10()..hi.log10())
            .prop_map(|e| V::Float(10f64.powf(e)))
            .boxed()
    };
    let within = |lo: f64, hi: f64| {
        prop_oneof![
            Just(V::Float(lo)),
            Just(V::Float(hi)),
            (lo..=hi).prop_map(V::Float),
        ]
        .boxed()
    };
    let own = match spec.allowed {
        A::Positive => prop_oneof![
            log(1e-6, 1e6),
            Just(V::Float(1e-300)),
            Just(V::Float(1e300)),
            Just(V::Float(9.223372036854776e18)),
        ]
        .boxed(),
        A::NonNegative => {
            prop_oneof![Just(V::Float(0.0)), log(1e-6, 1e6), Just(V::Float(1e300))].boxed()
        }
        A::Finite => prop_oneof![
            Just(V::Float(0.0)),
            log(1e-6, 1e6),
            log(1e-6, 1e6).prop_map(|v| V::Float(-v.as_float().unwrap())),
            Just(V::Float(1e300)),
            Just(V::Float(-1e300)),
        ]
        .boxed(),
        A::Closed(lo, hi) | A::LeftOpen(lo, hi) => within(lo, hi),
        A::Integer(lo, hi) => {
            let top = hi.min(1 << 20);
            prop_oneof![
                Just(V::Integer(lo)),
                Just(V::Integer(hi)),
                Just(V::Integer(lo.saturating_add(1).min(hi))),
                (lo..=top.max(lo)).prop_map(V::Integer),
            ]
            .boxed()
        }
        A::OneOf(words) => proptest::sample::select(words)
            .prop_map(|w| V::String(w.to_string()))
            .boxed(),
        A::Bool => any::<bool>().prop_map(V::Boolean).boxed(),
        A::Numbers(lo, hi, len) => {
            proptest::collection::vec(lo..=hi, len.unwrap_or(1)..=len.unwrap_or(4))
                .prop_map(|v| V::Array(v.into_iter().map(V::Float).collect()))
                .boxed()
        }
        A::Path | A::Table => hostile().boxed(),
    };
    prop_oneof![3 => own, 1 => hostile()].boxed()
}

/// `v` as a scenario would write it, floats in the shortest form (`1e-300`, not 300 digits).
fn show(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(x) => format!("{x:e}"),
        toml::Value::Array(a) => format!("[{}]", a.iter().map(show).collect::<Vec<_>>().join(", ")),
        other => other.to_string(),
    }
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

/// A progress sink that asks a fuzzed run to stop (as Ctrl-C would) once it has taken
/// `seconds` of wall time: a mutated key may make a run long, and its interim outputs must be
/// finite as well.
struct Deadline {
    start: std::time::Instant,
    seconds: f64,
}

impl colloidsim_run::Progress for Deadline {
    fn poll(&self) -> bool {
        self.start.elapsed().as_secs_f64() > self.seconds
    }
}

/// The non-finite numbers in the files of `dir` (CSV fields, JSON numbers, GSD
/// floating-point chunks), one line each; empty when every number is finite.
fn non_finite_outputs(dir: &Path) -> Vec<String> {
    let mut bad = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return bad;
    };
    for e in entries.flatten() {
        let path = e.path();
        let name = e.file_name().to_string_lossy().into_owned();
        let Ok(bytes) = std::fs::read(&path) else {
            continue;
        };
        if name.ends_with(".csv") {
            let text = String::from_utf8_lossy(&bytes);
            for (line, row) in text.lines().enumerate() {
                for field in row.split(',') {
                    if let Ok(x) = field.trim().parse::<f64>()
                        && !x.is_finite()
                    {
                        bad.push(format!("{name} line {}: {field}", line + 1));
                    }
                }
            }
        } else if name.ends_with(".json") {
            // serde_json writes a non-finite number as null; a bare NaN or Infinity (a writer
            // formatting its own JSON) makes the file unreadable to every JSON reader.
            match serde_json::from_slice::<serde_json::Value>(&bytes) {
                Err(_) => bad.push(format!("{name}: not valid JSON")),
                // Every null of a summary (a number that was not finite, or a value not
                // measured) has its reason in `nulls`.
                Ok(v) if name == "summary.json" => {
                    for path in unexplained_nulls(&v) {
                        bad.push(format!("{name}: {path} is null without a reason in nulls"));
                    }
                    // Every table column with empty fields (numbers that were not finite) has
                    // its reason.
                    for n in v["non_finite"].as_array().into_iter().flatten() {
                        if !n["reason"].is_string() {
                            bad.push(format!("{name}: non_finite without a reason: {n}"));
                        }
                    }
                }
                Ok(_) => {}
            }
        } else if name.ends_with(".gsd") {
            bad.extend(non_finite_gsd(&path, &name));
        }
    }
    bad
}

/// The paths of the nulls of `summary` that its `nulls` does not list (the resolved
/// `parameters`, `error` and the texts `why_null`, `note`, `*_note` aside).
fn unexplained_nulls(summary: &serde_json::Value) -> Vec<String> {
    use serde_json::Value;
    fn walk(v: &Value, path: String, found: &mut Vec<String>) {
        match v {
            Value::Null => found.push(path),
            Value::Object(m) => {
                for (k, x) in m {
                    let text = k == "why_null" || k == "note" || k.ends_with("_note");
                    if !(x.is_null() && text) {
                        let p = if path.is_empty() {
                            k.clone()
                        } else {
                            format!("{path}.{k}")
                        };
                        walk(x, p, found);
                    }
                }
            }
            Value::Array(a) => {
                for (i, x) in a.iter().enumerate() {
                    walk(x, format!("{path}[{i}]"), found);
                }
            }
            _ => {}
        }
    }
    let mut found = Vec::new();
    if let Some(m) = summary.as_object() {
        for (k, v) in m {
            if !["parameters", "error", "nulls", "non_finite"].contains(&k.as_str()) {
                walk(v, k.clone(), &mut found);
            }
        }
    }
    found.retain(|p| summary["nulls"].get(p).is_none());
    found
}

/// The floating-point chunks of a GSD file with a non-finite value, as `file frame k: chunk`.
fn non_finite_gsd(path: &Path, name: &str) -> Vec<String> {
    use hoomd_gsd::file_layer::{DataType, GsdFile, Mode};
    let Ok(file) = GsdFile::open(path, Mode::Read) else {
        return vec![format!("{name}: not a readable GSD file")];
    };
    fn finite<T: hoomd_gsd::file_layer::Type + Into<f64>, const M: usize>(
        file: &GsdFile,
        k: u64,
        chunk: &str,
    ) -> bool {
        file.iter_arrays::<T, M>(k, chunk)
            .map(|mut it| it.all(|row| row.into_iter().all(|x| x.into().is_finite())))
            .unwrap_or(true)
    }
    let mut bad = Vec::new();
    let mut names: Vec<&String> = file.name_id().keys().collect();
    names.sort();
    for k in 0..file.n_frames() {
        for chunk in &names {
            let Some(e) = file.find_chunk(k, chunk) else {
                continue;
            };
            let ok = match (e.data_type(), e.columns()) {
                (Some(DataType::F32), 1) => finite::<f32, 1>(&file, k, chunk),
                (Some(DataType::F32), 3) => finite::<f32, 3>(&file, k, chunk),
                (Some(DataType::F32), 4) => finite::<f32, 4>(&file, k, chunk),
                (Some(DataType::F32), 6) => finite::<f32, 6>(&file, k, chunk),
                (Some(DataType::F64), 1) => finite::<f64, 1>(&file, k, chunk),
                (Some(DataType::F64), 3) => finite::<f64, 3>(&file, k, chunk),
                _ => true,
            };
            if !ok {
                bad.push(format!("{name} frame {k}: {chunk}"));
            }
        }
    }
    bad
}

/// Run the mutated scenario `doc` to its end (or to an interrupt after a few seconds) in a
/// fresh folder, if `check` accepts it; every number of every output must then be finite,
/// whether the run completed, was interrupted or stopped with an error. `Ok(true)`: it ran;
/// `Ok(false)`: refused; `Err` names what is wrong.
fn run_checked(doc: &toml::Table) -> Result<bool, String> {
    let sc = match Scenario::from_table(doc, Path::new(".")) {
        Ok(sc) => sc,
        Err(e) => {
            if std::env::var_os("FUZZ_DEBUG").is_some() {
                eprintln!("unreadable: {e:#}");
            }
            return Ok(false);
        }
    };
    if let Err(e) = colloidsim_run::check(&sc) {
        if std::env::var_os("FUZZ_DEBUG").is_some() {
            eprintln!("refused: {e:#}");
        }
        return Ok(false);
    }
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    let out = dir.path().join("run");
    let opts = RunOptions {
        out: Some(out.clone()),
        ..RunOptions::default()
    };
    let ctl = Control::new(std::sync::Arc::new(Deadline {
        start: std::time::Instant::now(),
        seconds: 0.5,
    }));
    let ended = colloidsim_run::run(&sc, &opts, &ctl);
    let bad = non_finite_outputs(&out);
    if !bad.is_empty() {
        return Err(format!(
            "non-finite numbers written ({}): {}",
            match &ended {
                Ok(_) => "completed".to_string(),
                Err(e) => format!("{e:#}"),
            },
            bad.iter().take(4).cloned().collect::<Vec<_>>().join("; ")
        ));
    }
    Ok(true)
}

/// The fuzz of one method, in CI: every key it declares (taken from the declarations, so that
/// a new key is fuzzed without anyone listing it), set in each of the method's base scenarios
/// to values drawn from its declaration ([`declared`]) with a fixed seed, must give a clean refusal or a run whose
/// every output is finite. `per_key` values a key.
fn fuzz_every_key(method: &str, per_key: u32) {
    use proptest::strategy::ValueTree;
    let spec = colloidsim_run::registry::find(method).unwrap().keys();
    let bases: Vec<&str> = BASES
        .iter()
        .copied()
        .filter(|b| method_of(b) == method)
        .collect();
    assert!(!bases.is_empty(), "no base scenario of {method}");
    let mut runner = proptest::test_runner::TestRunner::new(fuzz_config(per_key));
    let mut failures = Vec::new();
    let (mut cases, mut ran) = (0, 0);
    for key in spec {
        for (b, text) in bases.iter().enumerate() {
            for _ in 0..per_key {
                let v = declared(key).new_tree(&mut runner).unwrap().current();
                let mut doc: toml::Table = toml::from_str(text).unwrap();
                set(&mut doc, key.path, v.clone());
                let case = format!("base {b} of {method}, {} = {}", key.path, show(&v));
                cases += 1;
                let t0 = std::time::Instant::now();
                let outcome = std::panic::catch_unwind(|| run_checked(&doc));
                let secs = t0.elapsed().as_secs_f64();
                if secs > 2.0 {
                    eprintln!("slow ({secs:.1} s): {case}");
                }
                match outcome {
                    Ok(Ok(r)) => ran += usize::from(r),
                    Ok(Err(why)) => failures.push(format!("{case}: {why}")),
                    Err(_) => failures.push(format!("{case}: panicked")),
                }
            }
        }
    }
    eprintln!("{method}: {cases} mutated scenarios, {ran} accepted and run");
    assert!(
        failures.is_empty(),
        "{} of the fuzzed {method} scenarios failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
    // Most mutations are refused; the fuzz must still run many (else it tests the refusal only).
    assert!(ran * 10 >= cases, "{method}: only {ran} of {cases} ran");
}

/// One fuzz test per registered method (each is listed: a method without one fails
/// `every_method_is_fuzzed_key_by_key`).
macro_rules! fuzz_methods {
    ($($test:ident => $method:literal),* $(,)?) => {
        $(
            #[test]
            fn $test() {
                fuzz_every_key($method, 2);
            }
        )*
        const FUZZED: &[&str] = &[$($method),*];
    };
}

fuzz_methods! {
    every_bcd_key_fuzzed => "bcd",
    every_droplet_bd_key_fuzzed => "droplet-bd",
    every_bd_key_fuzzed => "bd",
    every_dpd_key_fuzzed => "dpd",
    every_mpcd_key_fuzzed => "mpcd",
    every_droplet_mpcd_key_fuzzed => "droplet-mpcd",
    every_hs_mc_key_fuzzed => "hs-mc",
}

/// The output check finds what it is for (a check that passes on anything would hide them).
#[test]
fn the_output_check_finds_non_finite_numbers() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("ok.csv"), "x,y\n1,2.5e-3\n").unwrap();
    std::fs::write(
        dir.path().join("ok.json"),
        "{\"a\": null, \"b\": \"information\"}",
    )
    .unwrap();
    assert!(non_finite_outputs(dir.path()).is_empty());
    std::fs::write(dir.path().join("bad.csv"), "x,y\n1,inf\nNaN,2\n").unwrap();
    std::fs::write(dir.path().join("bad.json"), "{\"a\": NaN}").unwrap();
    let mut g =
        hoomd_gsd::file_layer::GsdFile::create(dir.path().join("bad.gsd"), "test", "hoomd", (1, 4))
            .unwrap();
    g.write_arrays("particles/position", [[0.0f32, f32::NAN, 0.0]])
        .unwrap();
    g.end_frame().unwrap();
    drop(g);
    let bad = non_finite_outputs(dir.path());
    assert_eq!(bad.len(), 4, "{bad:?}");
}

#[test]
fn every_method_is_fuzzed_key_by_key() {
    for m in colloidsim_run::registry::all() {
        assert!(
            m.names().iter().any(|n| FUZZED.contains(n)),
            "{} has no key-by-key fuzz test",
            m.names()[0]
        );
    }
}
