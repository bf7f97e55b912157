//! GSD input and output in the HOOMD schema (via `hoomd-gsd`).
//!
//! Frames hold `configuration/step`, `configuration/box`, `configuration/dimensions`,
//! `particles/N`, `particles/types`, `particles/typeid`, `particles/diameter`,
//! `particles/position` (f32, as the schema says) and `particles/image`, which the `gsd`
//! Python package, freud and OVITO read. Checkpoint frames add the exact double-precision
//! positions as `log/particles/position_f64`, and the Brownian engine's storage order and
//! neighbour-list reference positions ([`ListState`]), so that a restart continues bitwise
//! identically.
//! Readers fall back to frame 0 for chunks a frame lacks, as the schema specifies, and to the
//! schema's defaults after that.

use crate::state::{Particles, SimBox};
use hoomd_gsd::file_layer::{GsdFile, Mode};
use std::path::{Path, PathBuf};

mod layer;
pub use layer::{Entry, GsdFileWriter, GsdIndex, Layout, Value, restore_layout};

const NAME_LEN: usize = 64;
const POS64: &str = "log/particles/position_f64";
const BOX64: &str = "log/configuration/box_f64";
const ORDER: &str = "log/particles/storage_order";
const REFERENCE: &str = "log/particles/list_reference_position_f64";
const STORED_POS: &str = "log/particles/stored_position_f64";
const STORED_IMAGE: &str = "log/particles/stored_image";

/// What a Brownian-dynamics checkpoint needs besides the particles to continue bitwise: the
/// engine's storage order, its positions and image counts exactly as stored (not wrapped since
/// the last list build), and the positions at that build, all in storage order. The engine
/// (`colloidsim_md::Brownian`) makes and takes it; checkpoint frames store it.
#[derive(Debug, Clone, PartialEq)]
pub struct ListState {
    /// Input index of each stored particle (`Brownian::order`).
    pub order: Vec<u32>,
    /// Positions of the stored particles when the lists were last built (wrapped then).
    pub reference: Vec<[f64; 3]>,
    /// Current positions as stored.
    pub positions: Vec<[f64; 3]>,
    /// Current image counts as stored.
    pub images: Vec<[i32; 3]>,
}

/// A GSD error with the file involved.
#[derive(Debug, thiserror::Error)]
pub enum GsdError {
    /// Opening or creating the file failed.
    #[error("{path}: {message}")]
    Open {
        /// File.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// Writing failed.
    #[error("{path}: cannot write frame: {message}")]
    Write {
        /// File.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A frame's positions or velocities are not finite (or too large for the schema's f32):
    /// nothing of the frame is written.
    #[error(
        "{path}: the state went non-finite at step {step}: particle {particle} has {what}; no frame is written"
    )]
    NonFinite {
        /// File.
        path: PathBuf,
        /// Step of the frame.
        step: u64,
        /// Index of the first such particle.
        particle: usize,
        /// What is not finite, with its value.
        what: String,
    },
    /// The file is readable but does not hold what a configuration needs.
    #[error("{path}: {message}")]
    Content {
        /// File.
        path: PathBuf,
        /// What is missing or inconsistent.
        message: String,
    },
}

fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut src = e.source();
    while let Some(x) = src {
        s.push_str(": ");
        s.push_str(&x.to_string());
        src = x.source();
    }
    s
}

/// Appends frames to a GSD file ([`GsdFileWriter`]: its bytes depend on the frames alone).
pub struct GsdWriter {
    file: GsdFileWriter,
    path: PathBuf,
    dynamics: bool,
}

impl GsdWriter {
    /// Create a new file; an existing file is an error (nothing is overwritten).
    pub fn create_new(path: &Path) -> Result<Self, GsdError> {
        let application = format!("colloidsim {}", env!("CARGO_PKG_VERSION"));
        let file = GsdFileWriter::create_new(path, &application, "hoomd", (1, 4))?;
        Ok(Self {
            file,
            path: path.to_path_buf(),
            dynamics: false,
        })
    }

    /// Open an existing file to append frames (restarts).
    pub fn append(path: &Path) -> Result<Self, GsdError> {
        let file = GsdFileWriter::append(path)?;
        Ok(Self {
            file,
            path: path.to_path_buf(),
            dynamics: false,
        })
    }

    /// Also write `particles/velocity` and `particles/mass` in every frame (inertial methods).
    pub fn with_velocities(mut self) -> Self {
        self.dynamics = true;
        self
    }

    /// Number of frames in the file.
    pub fn frames(&self) -> u64 {
        self.file.n_frames()
    }

    /// Append one frame; `exact` adds double-precision positions for restarts, `log` adds
    /// scalars as `log/NAME`.
    pub fn write_frame(
        &mut self,
        step: u64,
        sbox: &SimBox,
        p: &Particles,
        exact: bool,
        log: &[(&str, f64)],
    ) -> Result<(), GsdError> {
        let log = scalars(log);
        self.write_inner(step, sbox, p, exact, None, &log)
    }

    /// Append one frame whose logged quantities may be arrays (`log/NAME` with one value per
    /// row, as HOOMD-blue writes e.g. `pressure_tensor`).
    pub fn write_frame_log(
        &mut self,
        step: u64,
        sbox: &SimBox,
        p: &Particles,
        log: &[(&str, &[f64])],
    ) -> Result<(), GsdError> {
        self.write_inner(step, sbox, p, false, None, log)
    }

    /// Append a checkpoint frame: exact positions and box plus the engine's storage order and
    /// list reference positions (`Brownian::list_state`), everything `Brownian::restart` needs
    /// to continue bitwise.
    pub fn write_checkpoint(
        &mut self,
        step: u64,
        sbox: &SimBox,
        p: &Particles,
        list: &ListState,
        log: &[(&str, f64)],
    ) -> Result<(), GsdError> {
        let log = scalars(log);
        self.write_inner(step, sbox, p, true, Some(list), &log)
    }

    /// Refuse a frame whose positions (or, for dynamics, velocities) are not finite or do not
    /// fit the schema's f32.
    fn check_finite(&self, step: u64, p: &Particles) -> Result<(), GsdError> {
        let bad = |v: &[f64; 3]| v.iter().any(|&x| !(x as f32).is_finite());
        let found = match p.pos.iter().position(bad) {
            Some(i) => Some((i, format!("position {:?}", p.pos[i]))),
            None if self.dynamics => p
                .vel
                .iter()
                .position(bad)
                .map(|i| (i, format!("velocity {:?}", p.vel[i]))),
            None => None,
        };
        match found {
            Some((particle, what)) => Err(GsdError::NonFinite {
                path: self.path.clone(),
                step,
                particle,
                what,
            }),
            None => Ok(()),
        }
    }

    fn write_inner(
        &mut self,
        step: u64,
        sbox: &SimBox,
        p: &Particles,
        exact: bool,
        list: Option<&ListState>,
        log: &[(&str, &[f64])],
    ) -> Result<(), GsdError> {
        self.check_finite(step, p)?;
        self.write_frame_data(step, sbox, p, exact, list, log)
            .map_err(|message| GsdError::Write {
                path: self.path.clone(),
                message,
            })
    }

    fn write_frame_data(
        &mut self,
        step: u64,
        sbox: &SimBox,
        p: &Particles,
        exact: bool,
        list: Option<&ListState>,
        log: &[(&str, &[f64])],
    ) -> Result<(), String> {
        let f = &mut self.file;
        let e = |e: GsdError| match e {
            GsdError::Write { message, .. } => message,
            other => other.to_string(),
        };
        f.write_scalars("configuration/step", [step]).map_err(e)?;
        f.write_scalars("configuration/dimensions", [3u8])
            .map_err(e)?;
        f.write_scalars(
            "configuration/box",
            [
                sbox.l[0] as f32,
                sbox.l[1] as f32,
                sbox.l[2] as f32,
                0.0,
                0.0,
                0.0,
            ],
        )
        .map_err(e)?;
        let n = u32::try_from(p.len()).map_err(|_| "too many particles".to_string())?;
        f.write_scalars("particles/N", [n]).map_err(e)?;
        let names: Vec<[u8; NAME_LEN]> = p
            .type_names
            .iter()
            .map(|s| {
                let mut a = [0u8; NAME_LEN];
                for (k, b) in s.bytes().take(NAME_LEN - 1).enumerate() {
                    a[k] = b;
                }
                a
            })
            .collect();
        f.write_arrays("particles/types", names).map_err(e)?;
        f.write_scalars("particles/typeid", p.typeid.iter().copied())
            .map_err(e)?;
        f.write_scalars("particles/diameter", p.diameter.iter().map(|&d| d as f32))
            .map_err(e)?;
        f.write_arrays(
            "particles/position",
            p.pos
                .iter()
                .map(|x| [x[0] as f32, x[1] as f32, x[2] as f32]),
        )
        .map_err(e)?;
        f.write_arrays("particles/image", p.image.iter().copied())
            .map_err(e)?;
        if self.dynamics {
            f.write_arrays(
                "particles/velocity",
                p.vel
                    .iter()
                    .map(|v| [v[0] as f32, v[1] as f32, v[2] as f32]),
            )
            .map_err(e)?;
            f.write_scalars("particles/mass", p.mass.iter().map(|&m| m as f32))
                .map_err(e)?;
        }
        if exact {
            f.write_arrays(POS64, p.pos.iter().copied()).map_err(e)?;
            f.write_scalars(BOX64, sbox.l).map_err(e)?;
        }
        if let Some(ls) = list {
            f.write_scalars(ORDER, ls.order.iter().copied())
                .map_err(e)?;
            f.write_arrays(REFERENCE, ls.reference.iter().copied())
                .map_err(e)?;
            f.write_arrays(STORED_POS, ls.positions.iter().copied())
                .map_err(e)?;
            f.write_arrays(STORED_IMAGE, ls.images.iter().copied())
                .map_err(e)?;
        }
        for (name, v) in log {
            f.write_scalars(&format!("log/{name}"), v.iter().copied())
                .map_err(e)?;
        }
        f.end_frame().map_err(e)?;
        Ok(())
    }

    /// Flush buffered frames to the file system.
    pub fn sync(&mut self) -> Result<(), GsdError> {
        self.file.sync_all()
    }
}

/// Scalar log quantities as one-value arrays.
fn scalars<'a>(log: &'a [(&'a str, f64)]) -> Vec<(&'a str, &'a [f64])> {
    log.iter()
        .map(|(name, v)| (*name, std::slice::from_ref(v)))
        .collect()
}

/// A configuration read from a GSD frame.
#[derive(Debug, Clone)]
pub struct GsdFrame {
    /// `configuration/step`.
    pub step: u64,
    /// Box (tilt factors must be zero).
    pub sbox: SimBox,
    /// Particles (velocities zero, masses one unless stored).
    pub particles: Particles,
    /// Whether exact (f64) positions were present.
    pub exact: bool,
    /// Storage order and list reference positions saved by a checkpoint.
    pub list: Option<ListState>,
}

/// Number of frames in a GSD file.
pub fn frame_count(path: &Path) -> Result<u64, GsdError> {
    Ok(open_read(path)?.n_frames())
}

fn open_read(path: &Path) -> Result<GsdFile, GsdError> {
    open_checked(path, Mode::Read)
}

/// Run `f`, turning a panic into `Err` without printing it (the panic hook is silenced for the
/// call). For the GSD reader, which asserts on some damaged files (a chunk that reaches past
/// the end of a truncated file) where it should report.
pub fn quietly<T>(f: impl FnOnce() -> T) -> std::thread::Result<T> {
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    std::panic::set_hook(hook);
    r
}

/// Open a GSD file, refusing a damaged one with a message naming it (never a panic).
pub fn open_checked(path: &Path, mode: Mode) -> Result<GsdFile, GsdError> {
    let open = |message: String| GsdError::Open {
        path: path.to_path_buf(),
        message,
    };
    match quietly(|| GsdFile::open(path, mode)) {
        Ok(Ok(f)) => Ok(f),
        Ok(Err(e)) => Err(open(format!("not a readable GSD file: {}", chain(&e)))),
        Err(_) => Err(open(
            "damaged GSD file: its index names data past the end of the file (truncated?)".into(),
        )),
    }
}

/// Read frame `frame` (default: the last) of a GSD file.
pub fn read_frame(path: &Path, frame: Option<u64>) -> Result<GsdFrame, GsdError> {
    let f = open_read(path)?;
    let content = |message: String| GsdError::Content {
        path: path.to_path_buf(),
        message,
    };
    let frames = f.n_frames();
    if frames == 0 {
        return Err(content("the file holds no frames".into()));
    }
    let k = frame.unwrap_or(frames - 1);
    if k >= frames {
        return Err(content(format!(
            "frame {k} requested, the file holds {frames}"
        )));
    }
    // A chunk missing from frame k is taken from frame 0 (HOOMD schema).
    let at = |name: &str| -> Option<u64> {
        if f.find_chunk(k, name).is_some() {
            Some(k)
        } else if f.find_chunk(0, name).is_some() {
            Some(0)
        } else {
            None
        }
    };
    let rd = |e: hoomd_gsd::file_layer::ReadError| content(chain(&e));
    let step = match at("configuration/step") {
        Some(fr) => f
            .iter_scalars::<u64>(fr, "configuration/step")
            .map_err(rd)?
            .next()
            .unwrap_or(0),
        None => 0,
    };
    let fr = at("configuration/box").ok_or_else(|| content("no configuration/box".into()))?;
    let b: Vec<f32> = f
        .iter_scalars::<f32>(fr, "configuration/box")
        .map_err(rd)?
        .collect();
    if b.len() != 6 {
        return Err(content(format!(
            "configuration/box has {} values, expected 6",
            b.len()
        )));
    }
    if b[3] != 0.0 || b[4] != 0.0 || b[5] != 0.0 {
        return Err(content(
            "triclinic boxes (non-zero tilt factors) are not supported".into(),
        ));
    }
    if !(b[..3].iter().all(|x| x.is_finite() && *x > 0.0)) {
        return Err(content(format!("invalid box edges {:?}", &b[..3])));
    }
    let mut sbox = SimBox::new([b[0] as f64, b[1] as f64, b[2] as f64]);
    if f.find_chunk(k, BOX64).is_some() {
        let l: Vec<f64> = f.iter_scalars::<f64>(k, BOX64).map_err(rd)?.collect();
        if l.len() == 3 && l.iter().all(|x| x.is_finite() && *x > 0.0) {
            sbox = SimBox::new([l[0], l[1], l[2]]);
        }
    }
    let n = match at("particles/N") {
        Some(fr) => f
            .iter_scalars::<u32>(fr, "particles/N")
            .map_err(rd)?
            .next()
            .unwrap_or(0) as usize,
        None => 0,
    };
    let exact = f.find_chunk(k, POS64).is_some();
    let pos: Vec<[f64; 3]> = if exact {
        f.iter_arrays::<f64, 3>(k, POS64).map_err(rd)?.collect()
    } else {
        let fr = at("particles/position").ok_or_else(|| content("no particles/position".into()))?;
        f.iter_arrays::<f32, 3>(fr, "particles/position")
            .map_err(rd)?
            .map(|x| [x[0] as f64, x[1] as f64, x[2] as f64])
            .collect()
    };
    if pos.len() != n {
        return Err(content(format!(
            "particles/N = {n} but {} positions",
            pos.len()
        )));
    }
    let image: Vec<[i32; 3]> = match at("particles/image") {
        Some(fr) => f
            .iter_arrays::<i32, 3>(fr, "particles/image")
            .map_err(rd)?
            .collect(),
        None => vec![[0; 3]; n],
    };
    let typeid: Vec<u32> = match at("particles/typeid") {
        Some(fr) => f
            .iter_scalars::<u32>(fr, "particles/typeid")
            .map_err(rd)?
            .collect(),
        None => vec![0; n],
    };
    // Per-particle float columns (stored as f32 in the HOOMD schema), with their defaults.
    let column = |name: &str, default: f64| -> Result<Vec<f64>, _> {
        Ok(match at(name) {
            Some(fr) => f
                .iter_scalars::<f32>(fr, name)
                .map_err(rd)?
                .map(|d| d as f64)
                .collect(),
            None => vec![default; n],
        })
    };
    let diameter = column("particles/diameter", 1.0)?;
    let mass = column("particles/mass", 1.0)?;
    let n_types = typeid.iter().map(|&t| t as usize + 1).max().unwrap_or(1);
    let mut type_names: Vec<String> = match at("particles/types") {
        Some(fr) => match f.iter_arrays::<u8, NAME_LEN>(fr, "particles/types") {
            Ok(it) => it
                .map(|a| {
                    let end = a.iter().position(|&c| c == 0).unwrap_or(NAME_LEN);
                    String::from_utf8_lossy(&a[..end]).into_owned()
                })
                .collect(),
            Err(_) => Vec::new(),
        },
        None => Vec::new(),
    };
    while type_names.len() < n_types {
        type_names.push(((b'A' + (type_names.len() % 26) as u8) as char).to_string());
    }
    let particles = Particles {
        vel: vec![[0.0; 3]; n],
        pos,
        image,
        typeid,
        diameter,
        mass,
        type_names,
    };
    particles
        .check()
        .map_err(|m| content(format!("frame {k}: {m}")))?;
    let has = |name| f.find_chunk(k, name).is_some();
    let list = if [ORDER, REFERENCE, STORED_POS, STORED_IMAGE]
        .into_iter()
        .all(has)
    {
        Some(ListState {
            order: f.iter_scalars::<u32>(k, ORDER).map_err(rd)?.collect(),
            reference: f.iter_arrays::<f64, 3>(k, REFERENCE).map_err(rd)?.collect(),
            positions: f
                .iter_arrays::<f64, 3>(k, STORED_POS)
                .map_err(rd)?
                .collect(),
            images: f
                .iter_arrays::<i32, 3>(k, STORED_IMAGE)
                .map_err(rd)?
                .collect(),
        })
    } else {
        None
    };
    Ok(GsdFrame {
        step,
        sbox,
        particles,
        exact,
        list,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_exact_and_refuses_to_overwrite() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.gsd");
        let sbox = SimBox::new([10.0, 11.0, 12.0]);
        let mut p = Particles::monodisperse(vec![[0.1, 0.2, 0.3], [-1.0 / 3.0, 4.0, -5.5]], 1.5);
        p.image[1] = [1, -2, 3];
        {
            let mut w = GsdWriter::create_new(&path).unwrap();
            w.write_frame(7, &sbox, &p, false, &[]).unwrap();
            w.write_frame(9, &sbox, &p, true, &[("droplet/radius", 3.5)])
                .unwrap();
        }
        assert!(GsdWriter::create_new(&path).is_err());
        let f = read_frame(&path, None).unwrap();
        assert_eq!(f.step, 9);
        assert!(f.exact);
        assert_eq!(f.particles.pos, p.pos);
        assert_eq!(f.particles.image, p.image);
        assert_eq!(f.particles.type_names, vec!["A".to_string()]);
        assert_eq!(f.sbox, sbox);
        let f0 = read_frame(&path, Some(0)).unwrap();
        assert!(!f0.exact && (f0.particles.pos[1][0] + 1.0 / 3.0).abs() < 1e-6);
        assert_eq!(frame_count(&path).unwrap(), 2);
        // Unreadable files give a clear error naming the file.
        let bad = dir.path().join("bad.gsd");
        std::fs::write(&bad, b"this is not a gsd file at all").unwrap();
        let e = read_frame(&bad, None).unwrap_err().to_string();
        assert!(
            e.contains("bad.gsd") && e.contains("not a readable GSD file"),
            "{e}"
        );
        assert!(read_frame(&path, Some(5)).is_err());
    }

    #[test]
    fn a_state_that_is_not_finite_is_never_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.gsd");
        let sbox = SimBox::new([10.0, 10.0, 10.0]);
        let mut p = Particles::monodisperse(vec![[0.1, 0.2, 0.3], [1.0, 2.0, 3.0]], 1.0);
        let mut w = GsdWriter::create_new(&path).unwrap();
        w.write_frame(1, &sbox, &p, false, &[]).unwrap();
        // Finite in f64 but beyond the schema's f32, and NaN: refused naming step and particle.
        for bad in [1e300, f64::NAN] {
            p.pos[1][2] = bad;
            let e = w.write_frame(2, &sbox, &p, true, &[]).unwrap_err();
            assert!(
                matches!(
                    e,
                    GsdError::NonFinite {
                        step: 2,
                        particle: 1,
                        ..
                    }
                ),
                "{e}"
            );
        }
        drop(w);
        assert_eq!(frame_count(&path).unwrap(), 1);
    }
}
