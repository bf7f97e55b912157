//! `colloidsim._colloidsim`: the run path of `colloidsim-run` for Python.
//!
//! Everything crosses the boundary as plain strings (TOML, JSON) and bytes (little-endian
//! `f64` arrays that numpy reads without a copy); the Python package `colloidsim` wraps it.
//! Long calls run on a thread of their own while the calling thread waits without the GIL,
//! polling Python's signals: Ctrl-C sets the run's interrupt flag, the run writes its
//! checkpoint, and the call raises `KeyboardInterrupt`.

mod analysis;
mod hydro;

use colloidsim_run::{AnalyseOptions, Control, RunOptions, Scenario, TheoryOptions};
use pyo3::exceptions::{PyKeyboardInterrupt, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

pyo3::create_exception!(
    _colloidsim,
    ColloidsimError,
    PyRuntimeError,
    "A colloidsim call failed; the message is the one the CLI prints."
);

/// The Python exception for a run-path error: an interrupted run raises `KeyboardInterrupt`
/// (its message says where the checkpoint is), every other error `ColloidsimError`.
fn to_py(e: anyhow::Error) -> PyErr {
    if let Some(i) = e.downcast_ref::<colloidsim_run::Interrupted>() {
        return PyKeyboardInterrupt::new_err(format!(
            "{i}. Continue with: colloidsim.resume({:?})",
            i.out.display().to_string()
        ));
    }
    if let Some(i) = e.downcast_ref::<StepInterrupted>() {
        return PyKeyboardInterrupt::new_err(i.to_string());
    }
    ColloidsimError::new_err(format!("{e:#}"))
}

/// A pool of `n` worker threads, built once per size and kept (an engine stepped one step at
/// a time calls [`blocking`] every step).
fn pool_of(n: usize) -> PyResult<Arc<rayon::ThreadPool>> {
    /// Pools by their number of threads.
    type Pools = Vec<(usize, Arc<rayon::ThreadPool>)>;
    static POOLS: std::sync::OnceLock<Mutex<Pools>> = std::sync::OnceLock::new();
    let mut pools = POOLS
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    if let Some((_, p)) = pools.iter().find(|(k, _)| *k == n) {
        return Ok(p.clone());
    }
    let p = Arc::new(
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| ColloidsimError::new_err(format!("thread pool: {e}")))?,
    );
    pools.push((n, p.clone()));
    Ok(p)
}

/// Run `f` on a thread of its own (inside a pool of `threads` workers if given) while this
/// thread waits without the GIL and polls Python's signals every 20 ms (it wakes as soon as
/// `f` returns).
fn blocking<T: Send>(
    py: Python<'_>,
    threads: Option<usize>,
    f: impl FnOnce(&Control) -> anyhow::Result<T> + Send,
) -> PyResult<T> {
    let pool = match threads {
        Some(0) => return Err(PyValueError::new_err("threads: must be at least 1, got 0")),
        Some(n) => Some(pool_of(n)?),
        None => None,
    };
    let ctl = Control::default();
    let (done, finished) = std::sync::mpsc::channel::<()>();
    // (a Receiver is not Sync: the waits borrow it through a lock only this thread takes)
    let finished = Mutex::new(finished);
    let (joined, signal) = std::thread::scope(|s| {
        let worker_ctl = ctl.clone();
        let h = s.spawn(move || {
            let r = match &pool {
                Some(p) => p.install(|| f(&worker_ctl)),
                None => f(&worker_ctl),
            };
            let _ = done.send(());
            r
        });
        let mut signal = None;
        while let Err(std::sync::mpsc::RecvTimeoutError::Timeout) = py.detach(|| {
            let rx = finished.lock().unwrap_or_else(|e| e.into_inner());
            rx.recv_timeout(Duration::from_millis(20))
        }) {
            if signal.is_none()
                && let Err(e) = py.check_signals()
            {
                ctl.interrupt();
                signal = Some(e);
            }
        }
        (h.join(), signal)
    });
    match joined {
        Ok(Ok(v)) => match signal {
            // The run reached its end before it could stop: its result stands.
            None | Some(_) => Ok(v),
        },
        Ok(Err(e)) => Err(to_py(e)),
        Err(_) => Err(ColloidsimError::new_err(
            "internal error: the run panicked (please report it with the scenario)",
        )),
    }
}

/// The scenario of a call: a file (read as the CLI reads it) or TOML text with the folder
/// relative paths are taken from, then the overrides (a JSON object of key paths).
fn scenario(
    text: &str,
    base: &str,
    name: &str,
    origin: Option<&str>,
    overrides_json: &str,
) -> anyhow::Result<Scenario> {
    let sc = match origin {
        Some(p) => Scenario::from_path(Path::new(p))?,
        None => Scenario::from_toml(text, Path::new(base))?.named(name),
    };
    let items: Vec<serde_json::Value> =
        serde_json::from_str(overrides_json).map_err(|e| anyhow::anyhow!("overrides: {e}"))?;
    let mut sc = sc;
    for item in items {
        sc = match item {
            // "key.path=value", read as the CLI's --set.
            serde_json::Value::String(s) => sc.with_overrides(&[s])?,
            pair => {
                let (key, value): (String, toml::Value) = serde_json::from_value(pair.clone())
                    .map_err(|e| anyhow::anyhow!("overrides: {pair}: {e}"))?;
                sc.with_values(&[(key, value)])?
            }
        };
    }
    Ok(sc)
}

fn report_json(r: &colloidsim_run::Report) -> String {
    serde_json::json!({
        "out": r.out,
        "summary": r.summary,
        "files": r.files,
        "warnings": r.warnings,
        "message": r.message,
    })
    .to_string()
}

/// Run a scenario; returns the report as JSON.
#[pyfunction]
#[pyo3(signature = (text, base, name, origin, overrides_json, out=None, seed=None, threads=None, force=false))]
#[allow(clippy::too_many_arguments)]
fn run(
    py: Python<'_>,
    text: &str,
    base: &str,
    name: &str,
    origin: Option<&str>,
    overrides_json: &str,
    out: Option<PathBuf>,
    seed: Option<u64>,
    threads: Option<usize>,
    force: bool,
) -> PyResult<String> {
    let sc = scenario(text, base, name, origin, overrides_json).map_err(to_py)?;
    let opts = RunOptions { out, seed, force };
    let r = blocking(py, threads, |ctl| colloidsim_run::run(&sc, &opts, ctl))?;
    Ok(report_json(&r))
}

/// Replicas and sweeps of a scenario (`colloidsim ensemble`, in this process); `vary_json` is a
/// JSON list of `[key, [values...]]`. Returns the report as JSON.
#[pyfunction]
#[pyo3(signature = (text, base, name, origin, overrides_json, vary_json, replicas=4, out=None, threads=None, force=false))]
#[allow(clippy::too_many_arguments)]
fn ensemble(
    py: Python<'_>,
    text: &str,
    base: &str,
    name: &str,
    origin: Option<&str>,
    overrides_json: &str,
    vary_json: &str,
    replicas: u32,
    out: Option<PathBuf>,
    threads: Option<usize>,
    force: bool,
) -> PyResult<String> {
    let sc = scenario(text, base, name, origin, overrides_json).map_err(to_py)?;
    let vary: Vec<(String, Vec<toml::Value>)> =
        serde_json::from_str(vary_json).map_err(|e| PyValueError::new_err(format!("vary: {e}")))?;
    let opts = colloidsim_run::EnsembleOptions {
        out,
        replicas,
        vary,
        force,
    };
    let r = blocking(py, threads, |ctl| colloidsim_run::ensemble(&sc, &opts, ctl))?;
    Ok(report_json(&r))
}

/// Continue the interrupted ensemble in `folder` (`colloidsim ensemble --restart`); returns
/// the report as JSON.
#[pyfunction]
#[pyo3(signature = (folder, threads=None))]
fn resume_ensemble(py: Python<'_>, folder: PathBuf, threads: Option<usize>) -> PyResult<String> {
    let r = blocking(py, threads, |ctl| {
        colloidsim_run::resume_ensemble(&folder, ctl)
    })?;
    Ok(report_json(&r))
}

/// Continue the interrupted run in `folder`; returns the report as JSON.
#[pyfunction]
#[pyo3(signature = (folder, seed=None, threads=None))]
fn resume(
    py: Python<'_>,
    folder: PathBuf,
    seed: Option<u64>,
    threads: Option<usize>,
) -> PyResult<String> {
    let r = blocking(py, threads, |ctl| {
        colloidsim_run::resume(&folder, None, seed, ctl)
    })?;
    Ok(report_json(&r))
}

/// The theory counterpart of a scenario; returns the report as JSON.
#[pyfunction]
#[pyo3(signature = (text, base, name, origin, overrides_json, out=None, dx=None, force=false, hydrodynamics=None, pair=None, threads=None))]
#[allow(clippy::too_many_arguments)]
fn theory(
    py: Python<'_>,
    text: &str,
    base: &str,
    name: &str,
    origin: Option<&str>,
    overrides_json: &str,
    out: Option<PathBuf>,
    dx: Option<f64>,
    force: bool,
    hydrodynamics: Option<String>,
    pair: Option<String>,
    threads: Option<usize>,
) -> PyResult<String> {
    let sc = scenario(text, base, name, origin, overrides_json).map_err(to_py)?;
    let opts = TheoryOptions {
        out,
        dx,
        force,
        hydrodynamics,
        pair,
    };
    let r = blocking(py, threads, |ctl| colloidsim_run::theory(&sc, &opts, ctl))?;
    Ok(report_json(&r))
}

/// Analyse a GSD trajectory (`colloidsim analyse`); returns the report as JSON. Options are
/// named as the Python function's arguments in its errors.
#[pyfunction]
#[pyo3(signature = (trajectory, out=None, force=false, types=None, frames=None, r_max=None, bins=None, contact_gap=None, centre=None, profile_bins=None, dt=None, percus_yevick=false, threads=None))]
#[allow(clippy::too_many_arguments)]
fn analyse(
    py: Python<'_>,
    trajectory: PathBuf,
    out: Option<PathBuf>,
    force: bool,
    types: Option<Vec<String>>,
    frames: Option<String>,
    r_max: Option<f64>,
    bins: Option<usize>,
    contact_gap: Option<f64>,
    centre: Option<String>,
    profile_bins: Option<usize>,
    dt: Option<f64>,
    percus_yevick: bool,
    threads: Option<usize>,
) -> PyResult<String> {
    // The CLI's option names in the messages become the arguments' names.
    let pythonic = |e: anyhow::Error| {
        let mut m = format!("{e:#}");
        for flag in [
            "--frames",
            "--centre",
            "--r-max",
            "--bins",
            "--contact-gap",
            "--profile-bins",
            "--dt",
            "--types",
            "--percus-yevick",
        ] {
            m = m.replace(flag, &flag[2..].replace('-', "_"));
        }
        anyhow::anyhow!(m)
    };
    let parsed = || -> anyhow::Result<AnalyseOptions> {
        Ok(AnalyseOptions {
            out,
            force,
            types,
            frames: frames
                .as_deref()
                .map(str::parse)
                .transpose()?
                .unwrap_or_default(),
            r_max,
            bins,
            contact_gap,
            centre: centre.as_deref().map(str::parse).transpose()?,
            profile_bins,
            dt,
            percus_yevick,
        })
    };
    let opts = parsed().map_err(|e| to_py(pythonic(e)))?;
    let r = blocking(py, threads, |_| {
        colloidsim_run::analyse(&trajectory, &opts).map_err(pythonic)
    })?;
    Ok(report_json(&r))
}

/// Validate a scenario; returns `{"resolved": ..., "warnings": [...]}` as JSON.
#[pyfunction]
fn check(
    text: &str,
    base: &str,
    name: &str,
    origin: Option<&str>,
    overrides_json: &str,
) -> PyResult<String> {
    let sc = scenario(text, base, name, origin, overrides_json).map_err(to_py)?;
    let c = colloidsim_run::check(&sc).map_err(to_py)?;
    Ok(serde_json::json!({ "resolved": c.resolved, "warnings": c.warnings }).to_string())
}

/// The TOML text of a scenario given as JSON (a Python dict).
#[pyfunction]
fn toml_from_json(json: &str) -> PyResult<String> {
    let table: toml::Table =
        serde_json::from_str(json).map_err(|e| PyValueError::new_err(format!("scenario: {e}")))?;
    toml::to_string(&table).map_err(|e| PyValueError::new_err(format!("scenario: {e}")))
}

/// The keys of a method as JSON.
#[pyfunction]
fn keys(method: &str) -> PyResult<String> {
    let k = colloidsim_run::keys(method).map_err(to_py)?;
    serde_json::to_string(&k).map_err(|e| ColloidsimError::new_err(e.to_string()))
}

/// The registered methods as JSON: names, one line, docs.
#[pyfunction]
fn methods() -> String {
    let m: Vec<serde_json::Value> = colloidsim_run::registry::all()
        .iter()
        .map(|m| serde_json::json!({ "names": m.names(), "about": m.about(), "docs": m.docs() }))
        .collect();
    serde_json::Value::Array(m).to_string()
}

/// `f64` values as little-endian bytes.
fn le_bytes<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyBytes> {
    let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
    PyBytes::new(py, &bytes)
}

/// Little-endian `f64` bytes as numbers (the Python side sends numpy arrays so).
fn from_le_bytes(name: &str, b: &[u8]) -> PyResult<Vec<f64>> {
    if !b.len().is_multiple_of(8) {
        return Err(ColloidsimError::new_err(format!(
            "{name}: {} bytes are not a whole number of f64 values",
            b.len()
        )));
    }
    Ok(b.chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect())
}

/// A method's engine built from a scenario, stepped by hand.
#[pyclass(module = "colloidsim._colloidsim")]
struct Engine {
    inner: Mutex<Box<dyn colloidsim_run::Engine>>,
}

impl Engine {
    fn with<T>(&self, f: impl FnOnce(&mut dyn colloidsim_run::Engine) -> T) -> T {
        let mut g = self.inner.lock().unwrap_or_else(|e| e.into_inner());
        f(&mut **g)
    }
}

#[pymethods]
impl Engine {
    #[new]
    #[pyo3(signature = (text, base, name, origin, overrides_json, seed=None))]
    fn new(
        text: &str,
        base: &str,
        name: &str,
        origin: Option<&str>,
        overrides_json: &str,
        seed: Option<u64>,
    ) -> PyResult<Self> {
        let sc = scenario(text, base, name, origin, overrides_json).map_err(to_py)?;
        let e = colloidsim_run::engine(&sc, seed).map_err(to_py)?;
        Ok(Self {
            inner: Mutex::new(e),
        })
    }

    /// Advance `steps` steps (without the GIL; Ctrl-C stops between chunks of steps, at a
    /// whole step, and raises KeyboardInterrupt).
    #[pyo3(signature = (steps=1, threads=None))]
    fn step(&self, py: Python<'_>, steps: u64, threads: Option<usize>) -> PyResult<()> {
        let inner = &self.inner;
        blocking(py, threads, |ctl| {
            let mut g = inner.lock().unwrap_or_else(|e| e.into_inner());
            let mut left = steps;
            let mut chunk = 1u64;
            while left > 0 {
                if ctl.interrupted() {
                    anyhow::bail!(StepInterrupted(g.steps()));
                }
                let k = chunk.min(left);
                let t = std::time::Instant::now();
                g.step(k)?;
                left -= k;
                if t.elapsed() < Duration::from_millis(50) {
                    chunk = (chunk * 2).min(1 << 20);
                }
            }
            Ok(())
        })
    }

    /// The scenario's method.
    #[getter]
    fn method(&self) -> String {
        self.with(|e| e.method().to_string())
    }
    /// Spatial dimensions of a position.
    #[getter]
    fn dimensions(&self) -> usize {
        self.with(|e| e.dimensions())
    }
    /// Number of particles.
    #[getter]
    fn particles(&self) -> usize {
        self.with(|e| e.particles())
    }
    /// Steps done.
    #[getter]
    fn steps(&self) -> u64 {
        self.with(|e| e.steps())
    }
    /// Simulated time.
    #[getter]
    fn time(&self) -> f64 {
        self.with(|e| e.time())
    }
    /// Time step.
    #[getter]
    fn dt(&self) -> f64 {
        self.with(|e| e.dt())
    }
    /// Box lengths.
    #[getter]
    fn box_lengths(&self) -> Vec<f64> {
        self.with(|e| e.box_lengths())
    }
    /// Positions as little-endian f64 bytes.
    fn positions_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        let v = self.with(|e| e.positions());
        le_bytes(py, &v)
    }
    /// Velocities as little-endian f64 bytes, or None.
    fn velocities_bytes<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyBytes>> {
        self.with(|e| e.velocities()).map(|v| le_bytes(py, &v))
    }
    /// Forces as little-endian f64 bytes.
    fn forces_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let v = self.with(|e| e.forces()).map_err(to_py)?;
        Ok(le_bytes(py, &v))
    }
    /// Each particle's type and diameter and the type names: `(names, typeid, diameter)`,
    /// or None where the engine has no such types (MPCD).
    #[allow(clippy::type_complexity)]
    fn types(&self) -> Option<(Vec<String>, Vec<u32>, Vec<f64>)> {
        self.with(|e| e.types())
            .map(|t| (t.names, t.typeid, t.diameter))
    }
    /// Seed of the random streams.
    #[getter]
    fn seed(&self) -> u32 {
        self.with(|e| e.seed())
    }
    /// Replace what is given of the state (arrays as little-endian f64 bytes); the engine is
    /// set up afresh from it, or left as it was on an error.
    #[pyo3(signature = (positions=None, velocities=None, step=None, seed=None))]
    fn set_state(
        &self,
        positions: Option<&[u8]>,
        velocities: Option<&[u8]>,
        step: Option<u64>,
        seed: Option<u64>,
    ) -> PyResult<()> {
        let change = colloidsim_run::StateChange {
            positions: positions
                .map(|b| from_le_bytes("positions", b))
                .transpose()?,
            velocities: velocities
                .map(|b| from_le_bytes("velocities", b))
                .transpose()?,
            step,
            seed: seed
                .map(colloidsim_run::seed32)
                .transpose()
                .map_err(to_py)?,
        };
        self.with(|e| e.set_state(change)).map_err(to_py)
    }
    /// Forces added to the systematic forces of every step (little-endian f64 bytes, N x 3;
    /// empty: none).
    fn set_extra_forces(&self, forces: &[u8]) -> PyResult<()> {
        let f = from_le_bytes("forces", forces)?;
        self.with(|e| e.set_extra_forces(&f)).map_err(to_py)
    }
}

/// Spheres as the exact GSD frame `system.initial` reads (an engine built from arrays).
#[pyfunction]
#[pyo3(signature = (path, box_lengths, positions, typeid, type_names, diameters, step=0))]
fn write_initial_gsd(
    path: PathBuf,
    box_lengths: [f64; 3],
    positions: &[u8],
    typeid: Vec<u32>,
    type_names: Vec<String>,
    diameters: Vec<f64>,
    step: u64,
) -> PyResult<()> {
    let x = from_le_bytes("positions", positions)?;
    colloidsim_run::engine::write_initial_gsd(
        &path,
        box_lengths,
        &x,
        &typeid,
        &type_names,
        &diameters,
        step,
    )
    .map_err(to_py)
}

/// Engine stepping stopped by Ctrl-C at a whole step.
#[derive(Debug)]
struct StepInterrupted(u64);

impl std::fmt::Display for StepInterrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "interrupted by Ctrl-C at step {}", self.0)
    }
}

impl std::error::Error for StepInterrupted {}

#[pymodule]
fn _colloidsim(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("ColloidsimError", m.py().get_type::<ColloidsimError>())?;
    m.add("version", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(resume, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble, m)?)?;
    m.add_function(wrap_pyfunction!(resume_ensemble, m)?)?;
    m.add_function(wrap_pyfunction!(theory, m)?)?;
    m.add_function(wrap_pyfunction!(analyse, m)?)?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add_function(wrap_pyfunction!(keys, m)?)?;
    m.add_function(wrap_pyfunction!(methods, m)?)?;
    m.add_function(wrap_pyfunction!(toml_from_json, m)?)?;
    m.add_function(wrap_pyfunction!(write_initial_gsd, m)?)?;
    m.add_class::<Engine>()?;
    m.add_class::<hydro::HydroOperator>()?;
    m.add_function(wrap_pyfunction!(analysis::analysis_rdf, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::analysis_msd, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::analysis_contacts, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::analysis_cluster_labels, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::analysis_radial_profile, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::analysis_structure_factor, m)?)?;
    Ok(())
}
