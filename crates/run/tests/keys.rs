//! The key tables of `colloidsim keys` against the methods' parsers and defaults: a key the
//! parser knows but the table lacks (or the reverse), or a documented default that is not the
//! one the method uses, fails here.

use colloidsim_run::Scenario;
use colloidsim_run::keys::{Allowed, Spec};
use std::collections::BTreeSet;
use std::path::Path;

/// Scenarios with every table present (and valid), one per method.
const BCD: &str = r#"
method = "bcd"
seed = 1
[system]
length = 20.0
particles = 10
diameter = 0.5
mobility = 1.0
kT = 1.0
boundary = "periodic"
[potential]
drive = 0.0
cosine = { amplitude = 1.0, wavelength = 1.0 }
harmonic = { stiffness = 0.1, centre = 10.0 }
fourier = { wavelength = 2.0, cos = [0.1], sin = [0.2] }
[interaction]
sticky = { gamma = 1.0, range = 0.05, order = 3.0 }
yukawa = { strength = 1.0, screening = 0.5, cutoff = 2.0 }
[initial]
placement = "random"
[run]
dt = 1e-5
equilibrate = 0.0
time = 0.01
checkpoint_every = 1000
[observe]
every = 1
current = false
clusters = false
density = { bins = 10 }
contact_density = { bins = 10, window = 0.1 }
msd = { points = 40, max_lag = 0.005 }
trajectory = { every = 10, equilibration = false }
"#;

const DROPLET: &str = r#"
method = "droplet-bd"
seed = 1
replicas = 1
[system]
particles = 100
diameter = 1.0
kT = 1.0
viscosity = 1.0
phi0 = 0.05
[drying]
peclet = 10.0
[interface]
stiffness = 50.0
range = 0.5
offset = -0.5
[run]
dt = 1e-4
skin = 0.6
[observe.profile]
bins = 50
fractions = [0.0, 0.25, 0.5, 0.75, 1.0]
[observe.trajectory]
every = 0
[observe.cross_section]
width = 1.0
[hydrodynamics]
model = "rpy"
method = "pse"
tolerance = 1e-3
splitting = 1.0
box_factor = 2.0
max_iterations = 200
"#;

const BULK: &str = r#"
method = "bd"
seed = 1
replicas = 1
[system]
particles = 20
box_length = 8.0
diameter = 1.0
kT = 1.0
viscosity = 1.0
body_force = [0.0, 0.0, -1.0]
[run]
time = 8.0
dt = 0.01
equilibrate = 0.0
skin = 0.6
integrator = "euler"
[observe]
blocks = 8
[observe.msd]
points = 30
max_lag = 0.5
[observe.trajectory]
every = 0
[hydrodynamics]
model = "rpy"
method = "pse"
tolerance = 1e-3
splitting = 1.0
max_iterations = 200
"#;

const DPD: &str = r#"
method = "dpd"
seed = 1
[system]
box_length = 8.0
density = 3.0
phi = 0.05
kT = 0.1
colloid_radius = 1.0
radius_distribution = "monodisperse"
radius_spread = 0.0
solvent_mass = 1.0
[dpd]
cutoff = 1.0
repulsion = 25.0
repulsion_colloid_solvent = 25.0
gamma = 4.5
[colloids]
cutoff = 1.0
contact = 10000.0
contact_range = 0.001
morse_depth = 0.0
morse_kappa = 30.0
morse_r0 = 0.0
eta0 = 0.3
lubrication = true
lubrication_gap = 0.001
lubrication_noise = "exact"
[run]
dt = 0.001
steps = 10000
skin = 0.4
max_temperature_drift = 0.1
temperature_window = 1000
neighbors = "auto"
[observe]
thermo_every = 100
trajectory_every = 1000
msd_every = 100
msd_solvent_beads = 1000
structure_every = 1000
gr_bins = 200
viscosity_every = 0
viscosity_time = 5.0
"#;

const MC: &str = r#"
method = "hs-mc"
seed = 1
[system]
geometry = "interface"
particles = 100
radius = 5.0
diameter = 1.0
kT = 1.0
[interface]
stiffness = 50.0
range = 0.5
offset = -0.5
[mc]
sweeps = 1000
warmup_sweeps = 2000
target_acceptance = 0.3
tune_every = 100
sample_every = 10
delta = 0.1
blocks = 20
[output]
profile_bins = 50
gr_bins = 200
gr_max = 3.0
trajectory_every = 0
rho2_r_bins = 4
rho2_cos_bins = 20
"#;

const MPCD: &str = r#"
method = "mpcd"
seed = 1
[solvent]
density = 5.0
angle = 130.0
tau = 0.1
kT = 1.0
mass = 1.0
cell = 1.0
thermostat = true
[system]
box = 8.0
colloids = 0
diameter = 4.0
[run]
collisions = 400
equilibrate = 100
[viscosity]
drive = 0.01
blocks = 10
[colloid]
vertex_mass = 5.0
centre_mass = 5.0
bond_k = 5000.0
md_steps = 50
[observe]
every = 10
vacf_lags = 100
[observe.trajectory]
every = 0
solvent = false
"#;

const DROPLET_MPCD: &str = r#"
method = "droplet-mpcd"
seed = 1
boundary = "slip"
[solvent]
density = 5.0
angle = 130.0
tau = 0.1
kT = 1.0
mass = 1.0
cell = 1.0
thermostat = true
[system]
particles = 0
diameter = 4.0
radius = 4.0
box = 12.0
[drying]
peclet = 10.0
duration = 10.0
[interface]
stiffness = 3.125
range = 2.0
offset = -2.0
[colloid]
vertex_mass = 5.0
centre_mass = 5.0
bond_k = 5000.0
md_steps = 50
[observe]
every = 10
[observe.profile]
bins = 50
fractions = [0.0, 0.25, 0.5, 0.75, 1.0]
[observe.solvent]
bins = 20
window = 10
[observe.trajectory]
every = 0
solvent = false
"#;

/// How a method's parser meets an unknown key: serde's "unknown field" message for the methods
/// still parsed by serde structs, `None` for those that read through their declarations
/// ([`keys::Reader`]; their own tests check that every declared key is read).
type Parse = Option<fn(&str) -> Result<(), String>>;

/// Every registered method's full scenario, its keys (from the registry) and its parser.
fn methods() -> Vec<(&'static str, &'static [Spec], Parse)> {
    let spec = |name| colloidsim_run::registry::find(name).unwrap().keys();
    let all: Vec<(&str, &[Spec], Parse)> = vec![
        (BCD, spec("bcd"), None),
        (DROPLET, spec("droplet-bd"), None),
        (BULK, spec("bd"), None),
        (DPD, spec("dpd"), None),
        (MC, spec("hs-mc"), None),
        (MPCD, spec("mpcd"), None),
        (DROPLET_MPCD, spec("droplet-mpcd"), None),
    ];
    assert_eq!(
        all.len(),
        colloidsim_run::registry::all().len(),
        "a registered method has no full scenario here"
    );
    all
}

/// The table at `path` (created on the way).
fn table_at<'a>(t: &'a mut toml::Table, path: &str) -> &'a mut toml::Table {
    if path.is_empty() {
        return t;
    }
    let mut t = t;
    for part in path.split('.') {
        t = t
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(Default::default()))
            .as_table_mut()
            .unwrap();
    }
    t
}

/// The field names serde lists in its "unknown field `x`, expected one of `a`, `b`" message.
fn expected_fields(msg: &str) -> BTreeSet<String> {
    let tail = &msg[msg.find("expected").unwrap_or_else(|| panic!("{msg}"))..];
    let tail = tail.lines().next().unwrap();
    tail.split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

#[test]
fn every_key_the_parser_knows_is_listed_and_nothing_else() {
    for (text, spec, parse) in methods() {
        let Some(parse) = parse else { continue };
        parse(text).unwrap_or_else(|e| panic!("the full scenario does not parse: {e}"));
        let tables: Vec<&str> = std::iter::once("")
            .chain(
                spec.iter()
                    .filter(|s| matches!(s.allowed, Allowed::Table))
                    .map(|s| s.path),
            )
            .collect();
        for t in tables {
            let mut doc: toml::Table = toml::from_str(text).unwrap();
            table_at(&mut doc, t).insert("zzz_unknown".into(), toml::Value::Integer(1));
            let e = parse(&toml::to_string(&doc).unwrap()).unwrap_err();
            let parser: BTreeSet<String> = expected_fields(&e);
            let listed: BTreeSet<String> = spec
                .iter()
                .filter_map(|s| {
                    let rest = if t.is_empty() {
                        s.path
                    } else {
                        s.path.strip_prefix(t)?.strip_prefix('.')?
                    };
                    (!rest.contains('.')).then(|| rest.to_string())
                })
                .collect();
            assert_eq!(parser, listed, "the keys of [{t}] ({e})");
        }
    }
}

#[test]
fn documented_defaults_are_the_defaults_the_methods_use() {
    let mut tested = 0;
    for (text, spec, _) in methods() {
        let full: toml::Table = toml::from_str(text).unwrap();
        let check = |doc: &toml::Table| {
            colloidsim_run::check(&Scenario::from_table(doc, Path::new(".")).unwrap())
                .unwrap_or_else(|e| panic!("{e:#}"))
                .resolved
        };
        for s in spec {
            let Ok(value) = toml::from_str::<toml::Table>(&format!("v = {}", s.default.describe()))
                .map(|mut t| t.remove("v").unwrap())
            else {
                continue; // required, or derived from other keys
            };
            let (parent, name) = s.path.rsplit_once('.').unwrap_or(("", s.path));
            let mut with = full.clone();
            let mut without = full.clone();
            if !matches!(s.allowed, Allowed::Table) {
                table_at(&mut with, parent).insert(name.into(), value);
                table_at(&mut without, parent).remove(name);
                assert_eq!(check(&with), check(&without), "default of {}", s.path);
                tested += 1;
            }
        }
    }
    assert!(tested > 40, "only {tested} defaults compared");
}

#[test]
fn a_value_outside_each_range_is_refused_naming_the_key() {
    for (text, spec, _) in methods() {
        let full: toml::Table = toml::from_str(text).unwrap();
        // `method` is the registry's: an unknown one names the methods there.
        for s in spec.iter().filter(|s| s.path != "method") {
            let bad = match s.allowed {
                Allowed::Positive => toml::Value::Float(0.0),
                Allowed::NonNegative => toml::Value::Float(-1e-9),
                Allowed::Finite => toml::Value::Float(f64::INFINITY),
                Allowed::Closed(_, hi) | Allowed::LeftOpen(_, hi) => {
                    toml::Value::Float(hi * 1.000001 + 1e-9)
                }
                Allowed::Integer(lo, _) if lo > i64::MIN => toml::Value::Integer(lo - 1),
                Allowed::OneOf(_) => toml::Value::String("no-such-word".into()),
                Allowed::Bool => toml::Value::Integer(1),
                _ => continue,
            };
            let (parent, name) = s.path.rsplit_once('.').unwrap_or(("", s.path));
            let mut doc = full.clone();
            table_at(&mut doc, parent).insert(name.into(), bad.clone());
            let e = colloidsim_run::check(&Scenario::from_table(&doc, Path::new(".")).unwrap())
                .map(|_| ())
                .unwrap_err();
            let msg = format!("{e:#}");
            assert!(
                msg.contains(&format!("{}: must", s.path)),
                "{} = {bad}: {msg}",
                s.path
            );
        }
    }
}
