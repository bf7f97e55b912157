//! The trajectory every method writes, shared: what a checkpoint vouches for in
//! `trajectory.gsd` ([`FrameDigest`]) and how a restart trims it to the checkpoint's frames
//! ([`trim_trajectory`]).
//!
//! The digest is a CRC-32 over the frames written up to
//! the checkpoint, so that a restart refuses a trajectory damaged or changed since (GSD files
//! carry no checksum of their own), and keeps exactly the frames the checkpoint counted.
//!
//! The digest covers, per frame, the step, the positions (`particles/position`) and every
//! double-precision scalar log (`log/*`: the unwrapped rod positions, the droplet radius and
//! time, the DPD time): the data a user analyses. It is extended at each checkpoint over the
//! frames written since the last one (read back from the synced file), so its cost is that of
//! reading each frame once.

use anyhow::{Context, Result, anyhow, bail};
use colloidsim_md::gsd::{self, GsdWriter, open_checked, quietly};
use hoomd_gsd::file_layer::{DataType, GsdFile, Mode};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// CRC-32 of the first `frames` frames of a trajectory.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct FrameDigest {
    /// Frames covered.
    pub frames: u64,
    /// Their CRC-32 (IEEE).
    pub crc: u32,
}

impl FrameDigest {
    /// The digest of the first `frames` frames of `path`.
    pub fn of(path: &Path, frames: u64) -> Result<Self> {
        let mut d = Self::default();
        d.extend(path, frames)?;
        Ok(d)
    }

    /// Extend the digest over frames `self.frames..frames` of `path` (a file whose writer has
    /// synced); nothing to do when it already covers them.
    pub fn extend(&mut self, path: &Path, frames: u64) -> Result<()> {
        if frames <= self.frames {
            return Ok(());
        }
        let file = open_checked(path, Mode::Read)?;
        if file.n_frames() < frames {
            bail!(
                "{}: holds {} frames, {frames} were written",
                path.display(),
                file.n_frames()
            );
        }
        let mut h = crc32fast::Hasher::new_with_initial(self.crc);
        let mut buf = Vec::new();
        for k in self.frames..frames {
            quietly(|| hash_frame(&file, k, &mut buf, &mut h))
                .map_err(|_| anyhow!("{}: frame {k}: damaged chunk", path.display()))?
                .with_context(|| format!("{}: frame {k}", path.display()))?;
        }
        self.frames = frames;
        self.crc = h.finalize();
        Ok(())
    }

    /// Before a restart appends to `path`: [`Self::verify`] it, then let `trim` (the method's
    /// own writer) keep only the first `self.frames` frames, dropping any a killed run wrote
    /// after the checkpoint.
    pub fn restore(&self, path: &Path, trim: impl FnOnce(&Path, u64) -> Result<()>) -> Result<()> {
        self.verify(path)?;
        if path.exists() {
            trim(path, self.frames)?;
        }
        Ok(())
    }

    /// Check that `path` holds at least the frames this digest covers and that they are the
    /// frames the checkpoint saw.
    pub fn verify(&self, path: &Path) -> Result<()> {
        if self.frames == 0 {
            return Ok(());
        }
        if !path.exists() {
            bail!(
                "{} is missing (the checkpoint expects {} frames)",
                path.display(),
                self.frames
            );
        }
        let have = colloidsim_md::gsd::frame_count(path)?;
        if have < self.frames {
            bail!(
                "{}: holds {have} frames, the checkpoint expects {}; the trajectory was damaged",
                path.display(),
                self.frames
            );
        }
        let now = Self::of(path, self.frames)?;
        if now.crc != self.crc {
            bail!(
                "{}: its first {} frames differ from those the checkpoint recorded (CRC-32 \
                 {:08x}, expected {:08x}): the trajectory was damaged or changed after the \
                 checkpoint; restore it, or start a new run",
                path.display(),
                self.frames,
                now.crc,
                self.crc
            );
        }
        Ok(())
    }
}

/// Feed frame `k` (step, positions, double-precision scalar logs in name order) to `h`.
fn hash_frame(file: &GsdFile, k: u64, buf: &mut Vec<u8>, h: &mut crc32fast::Hasher) -> Result<()> {
    buf.clear();
    for s in file.iter_scalars::<u64>(k, "configuration/step")? {
        buf.extend_from_slice(&s.to_le_bytes());
    }
    if file.find_chunk(k, "particles/position").is_some() {
        for p in file.iter_arrays::<f32, 3>(k, "particles/position")? {
            for c in p {
                buf.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    let mut logs: Vec<&String> = file
        .name_id()
        .keys()
        .filter(|n| n.starts_with("log/"))
        .collect();
    logs.sort();
    for name in logs {
        if let Some(e) = file.find_chunk(k, name)
            && e.columns() == 1
            && e.data_type() == Some(DataType::F64)
        {
            buf.extend_from_slice(name.as_bytes());
            for v in file.iter_scalars::<f64>(k, name)? {
                buf.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    h.update(buf);
    Ok(())
}

/// Keep the first `frames` frames of the trajectory (a run killed after its last checkpoint
/// may have written more), so that the continuation appends exactly where the checkpoint stood.
/// The frames are written again as [`GsdWriter`] wrote them, with the scalars `log/NAME` of
/// `logs` and, with `velocities`, the velocities and masses: byte for byte the same file.
pub(crate) fn trim_trajectory(
    path: &Path,
    frames: u64,
    logs: &[&str],
    velocities: bool,
) -> Result<()> {
    let have = gsd::frame_count(path)?;
    if have == frames {
        return Ok(());
    }
    if have < frames {
        bail!(
            "{}: holds {have} frames, the checkpoint expects {frames}; the trajectory was damaged",
            path.display()
        );
    }
    let tmp = path.with_extension("gsd.trim");
    let _ = std::fs::remove_file(&tmp);
    {
        let file = gsd::open_checked(path, Mode::Read)?;
        let mut w = GsdWriter::create_new(&tmp)?;
        if velocities {
            w = w.with_velocities();
        }
        for k in 0..frames {
            let mut f = gsd::read_frame(path, Some(k))?;
            let e = |e: hoomd_gsd::file_layer::ReadError| {
                anyhow::anyhow!("{}: frame {k}: {e}", path.display())
            };
            if velocities {
                f.particles.vel = file
                    .iter_arrays::<f32, 3>(k, "particles/velocity")
                    .map_err(e)?
                    .map(|v| [v[0] as f64, v[1] as f64, v[2] as f64])
                    .collect();
                if f.particles.vel.len() != f.particles.len() {
                    bail!("{}: frame {k}: velocities missing", path.display());
                }
            }
            let values = logs
                .iter()
                .map(|name| -> Result<(&str, Vec<f64>)> {
                    let v: Vec<f64> = file
                        .iter_scalars::<f64>(k, &format!("log/{name}"))
                        .map_err(e)?
                        .collect();
                    if v.is_empty() {
                        bail!("{}: frame {k}: no log/{name}", path.display());
                    }
                    Ok((*name, v))
                })
                .collect::<Result<Vec<_>>>()?;
            let values: Vec<(&str, &[f64])> = values.iter().map(|(n, v)| (*n, &v[..])).collect();
            w.write_frame_log(f.step, &f.sbox, &f.particles, &values)?;
        }
        w.sync()?;
    }
    std::fs::rename(&tmp, path).with_context(|| format!("{}", path.display()))?;
    Ok(())
}
