//! Every example scenario, shortened (a few seconds in all), writes the same files as the colloidsim of before the
//! one-declaration redesign (issue 41): each output file's length and CRC-32 against
//! `tests/data/examples_golden.txt`, summary.json without its timings. A change of the key
//! layer, of a method's folder or of the shared writers that moves one byte of an example's
//! outputs fails here.
//!
//! The reference was written by the binary of commit 705c480 with
//! `COLLOIDSIM_BLESS=1 cargo test -p colloidsim-cli --test integration examples_golden::`; bless again only
//! for a change that is meant to change outputs, and say so in the commit.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// summary.json fields that depend on the machine and the moment (at any depth): timings,
/// threads, and the software's version.
fn volatile(key: &str) -> bool {
    key == "threads"
        || key == "ranks"
        || key == "software"
        || key.ends_with("seconds")
        || key.ends_with("_per_second")
}

/// Every example, with the overrides that make it take a second or less.
const EXAMPLES: &[(&str, &[&str])] = &[
    (
        "droplet/bidisperse-bd.toml",
        &["replicas=2", "drying.final_volume_fraction=0.06"],
    ),
    (
        "droplet/bidisperse-mpcd.toml",
        &[
            "system.particles=9",
            "system.species.counts=[8, 1]",
            "drying.final_volume_fraction=0.11",
            "observe.solvent.window=10",
        ],
    ),
    (
        "droplet/bidisperse-rpy.toml",
        &[
            "replicas=1",
            "system.particles=90",
            "system.species.counts=[80, 10]",
            "drying.final_volume_fraction=0.06",
        ],
    ),
    (
        "bcd/channel-trap.toml",
        &[
            "run.equilibrate=0.05",
            "run.time=0.5",
            "observe.trajectory.every=1000",
        ],
    ),
    (
        "bcd/contact-density.toml",
        &[
            "run.equilibrate=0.0005",
            "run.time=0.002",
            "observe.every=8",
        ],
    ),
    (
        "bcd/hard-rods-cosine.toml",
        &["run.equilibrate=0.05", "run.time=0.5"],
    ),
    (
        "bcd/single-file.toml",
        &[
            "run.equilibrate=1.0",
            "run.time=4.0",
            "observe.msd.max_lag=2.0",
        ],
    ),
    (
        "bcd/sticky-rods.toml",
        &["run.equilibrate=0.01", "run.time=0.1"],
    ),
    (
        "bcd/sticky-single-file.toml",
        &[
            "run.equilibrate=0.01",
            "run.time=0.2",
            "observe.msd.max_lag=0.1",
        ],
    ),
    (
        "bcd/sticky-washboard-msd.toml",
        &[
            "run.equilibrate=0.01",
            "run.time=0.2",
            "observe.msd.max_lag=0.1",
        ],
    ),
    (
        "bcd/tilted-washboard.toml",
        &["run.equilibrate=0.05", "run.time=0.5"],
    ),
    ("bd/hasimoto.toml", &["run.time=20"]),
    (
        "bd/sedimentation.toml",
        &[
            "run.time=2",
            "run.equilibrate=0.5",
            "observe.trajectory.every=100",
        ],
    ),
    (
        "dpd/colloids-equilibrium.toml",
        &[
            "run.steps=100",
            "observe.trajectory_every=50",
            "observe.msd_every=10",
            "observe.structure_every=50",
            "observe.thermo_every=10",
        ],
    ),
    (
        "dpd/colloids-gel.toml",
        &[
            "run.steps=100",
            "observe.trajectory_every=50",
            "observe.msd_every=10",
            "observe.structure_every=50",
            "observe.thermo_every=10",
        ],
    ),
    (
        "dpd/shear.toml",
        &["run.steps=200", "observe.thermo_every=20"],
    ),
    (
        "droplet/drying-bd-paper.toml",
        &[
            "system.particles=300",
            "drying.final_volume_fraction=0.06",
            "replicas=2",
        ],
    ),
    (
        "droplet/drying-bd.toml",
        &[
            "system.particles=300",
            "drying.final_volume_fraction=0.06",
            "replicas=2",
        ],
    ),
    (
        "droplet/drying-rpy.toml",
        &["system.particles=200", "drying.final_volume_fraction=0.06"],
    ),
    (
        "droplet/static-equilibrium.toml",
        &["system.particles=200", "drying.duration=1.0"],
    ),
    (
        "droplet/drying-mpcd-solvent.toml",
        &["drying.duration=2", "observe.solvent.window=10"],
    ),
    (
        "droplet/drying-mpcd.toml",
        &[
            "system.particles=10",
            "drying.final_volume_fraction=0.11",
            "observe.solvent.window=10",
        ],
    ),
    (
        "mc/bulk.toml",
        &[
            "mc.sweeps=200",
            "mc.warmup_sweeps=50",
            "system.particles=256",
            "mc.blocks=4",
            "output.gr_max=3.0",
        ],
    ),
    (
        "mc/charged-spheres.toml",
        &[
            "mc.sweeps=200",
            "mc.warmup_sweeps=50",
            "system.particles=300",
            "system.box=14.42",
            "mc.blocks=4",
            "output.gr_max=3.0",
        ],
    ),
    (
        "mc/droplet-static.toml",
        &[
            "mc.sweeps=200",
            "mc.warmup_sweeps=50",
            "system.particles=300",
            "mc.blocks=4",
        ],
    ),
    (
        "mpcd/colloid-diffusion.toml",
        &[
            "run.collisions=300",
            "run.equilibrate=10",
            "observe.every=10",
            "observe.vacf_lags=20",
        ],
    ),
    ("mpcd/viscosity.toml", &["run.collisions=200"]),
];

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn reference() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/examples_golden.txt")
}

/// `name length crc32` of every file under `dir` (summary.json without its timings, keys sorted).
fn fingerprints(dir: &Path, prefix: &str, out: &mut BTreeMap<String, String>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        let name = format!(
            "{prefix}{}",
            path.file_name().unwrap().to_string_lossy().into_owned()
        );
        if path.is_dir() {
            fingerprints(&path, &format!("{name}/"), out);
            continue;
        }
        let mut bytes = std::fs::read(&path).unwrap();
        if name.ends_with("summary.json") {
            let v: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
            bytes = canonical(&v).into_bytes();
        }
        out.insert(
            name,
            format!("{} {:08x}", bytes.len(), crc32fast::hash(&bytes)),
        );
    }
}

/// JSON with every object's keys sorted (whatever order serde_json keeps them in), the
/// volatile ones left out.
fn canonical(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Object(m) => {
            let mut keys: Vec<_> = m.keys().filter(|k| !volatile(k)).collect();
            keys.sort();
            let items: Vec<String> = keys
                .into_iter()
                .map(|k| {
                    format!(
                        "{}:{}",
                        serde_json::Value::from(k.as_str()),
                        canonical(&m[k])
                    )
                })
                .collect();
            format!("{{{}}}\n", items.join(","))
        }
        serde_json::Value::Array(a) => {
            let items: Vec<String> = a.iter().map(canonical).collect();
            format!("[{}]", items.join(","))
        }
        other => other.to_string(),
    }
}

/// Every headline observable its method declares (`Method::headline`, what `colloidsim
/// ensemble` tabulates) sits in the example's summary.json: a number, or null with its reason
/// in `nulls`; a labelled one as a list as long as its labels. Returns the method's name.
fn headline_in_summary(example: &str, out: &Path) -> &'static str {
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let m = colloidsim_run::registry::find(summary["method"].as_str().unwrap()).unwrap();
    assert!(
        !m.headline().is_empty(),
        "method '{}' declares no headline observable",
        m.names()[0]
    );
    let at = colloidsim_run::method::at;
    for h in m.headline() {
        let v = at(&summary, h.path).unwrap_or_else(|| {
            panic!(
                "{example}: headline {} ({}) is not in summary.json",
                h.name, h.path
            )
        });
        let (values, paths): (Vec<&serde_json::Value>, Vec<String>) = match h.labels {
            None => (vec![v], vec![h.path.to_string()]),
            Some(l) => {
                let labels = at(&summary, l).and_then(|l| l.as_array());
                let list = v.as_array();
                assert!(
                    labels.is_some()
                        && list.is_some()
                        && labels.unwrap().len() == list.unwrap().len(),
                    "{example}: headline {}: {} and {l} are not lists of one length",
                    h.name,
                    h.path
                );
                let list = list.unwrap();
                (
                    list.iter().collect(),
                    (0..list.len())
                        .map(|i| format!("{}[{i}]", h.path))
                        .collect(),
                )
            }
        };
        for (v, path) in values.into_iter().zip(paths) {
            assert!(
                v.as_f64().is_some_and(f64::is_finite)
                    || (v.is_null() && summary["nulls"][&path].is_string()),
                "{example}: headline {} at {path} is {v}, neither a number nor null with a reason",
                h.name
            );
        }
    }
    m.names()[0]
}

#[test]
fn every_example_writes_the_outputs_of_before() {
    let tmp = tempfile::tempdir().unwrap();
    let mut got = BTreeMap::new();
    let mut covered = std::collections::BTreeSet::new();
    for (example, overrides) in EXAMPLES {
        let stem = example.trim_end_matches(".toml").replace('/', "-");
        let out = tmp.path().join(&stem);
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_colloidsim"));
        // One thread: the outputs do not depend on it, and the runs stay light beside the
        // other tests.
        cmd.env("RAYON_NUM_THREADS", "1");
        cmd.arg("run")
            .arg(examples().join(example))
            .arg("--out")
            .arg(&out)
            .arg("--quiet");
        for o in *overrides {
            cmd.arg("--set").arg(o);
        }
        let o = cmd.output().unwrap();
        assert!(
            o.status.success(),
            "{example}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        covered.insert(headline_in_summary(example, &out));
        let mut files = BTreeMap::new();
        fingerprints(&out, "", &mut files);
        for (name, fp) in files {
            got.insert(format!("{stem}/{name}"), fp);
        }
    }
    // Every registered method's headline observables were checked against an example's summary.
    for m in colloidsim_run::registry::all() {
        assert!(
            covered.contains(m.names()[0]),
            "no example of method '{}' checks its headline observables",
            m.names()[0]
        );
    }
    let text: String = got.iter().map(|(k, v)| format!("{k} {v}\n")).collect();
    if std::env::var_os("COLLOIDSIM_BLESS").is_some() {
        std::fs::create_dir_all(reference().parent().unwrap()).unwrap();
        std::fs::write(reference(), &text).unwrap();
        return;
    }
    let want = std::fs::read_to_string(reference()).unwrap();
    let want: BTreeMap<&str, &str> = want.lines().map(|l| l.split_once(' ').unwrap()).collect();
    let got: BTreeMap<&str, &str> = text.lines().map(|l| l.split_once(' ').unwrap()).collect();
    let differ: Vec<String> = want
        .keys()
        .chain(got.keys())
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .filter(|k| want.get(*k) != got.get(*k))
        .map(|k| format!("{k}: before {:?}, now {:?}", want.get(k), got.get(k)))
        .collect();
    assert!(differ.is_empty(), "outputs changed:\n{}", differ.join("\n"));
}
