//! The trajectory every method writes, shared: what a checkpoint vouches for in
//! `trajectory.gsd` ([`FrameDigest`]) and how a restart cuts it back to the checkpoint's frames
//! ([`FrameDigest::restore`]).
//!
//! The digest is a CRC-32 over the frames written up to the checkpoint, so that a restart
//! refuses a trajectory damaged or changed since (GSD files carry no checksum of their own).
//! It covers every chunk of every frame: its name, type, shape and bytes. It is extended at
//! each checkpoint over the frames written since the last one (read back from the synced
//! file), so its cost is that of reading each frame once.
//!
//! With the digest the checkpoint keeps the file's layout after those frames
//! ([`colloidsim_particles::gsd::Layout`]). The GSD writer's bytes depend on the frames alone,
//! so a restart that cuts the file back to that layout (dropping what a killed run wrote after
//! the checkpoint) and appends the same frames writes the file an uninterrupted run writes,
//! byte for byte.

use anyhow::{Result, bail};
use colloidsim_particles::gsd::{GsdIndex, GsdWriter, Layout, restore_layout};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The writer of a run's trajectory `path`: appending to it when `append` and the file is
/// there (a restart: [`FrameDigest::restore`] has cut it back to the checkpoint's frames), else
/// a new file (a fresh run, or a restart whose run had written no frame yet).
pub fn writer(path: &Path, append: bool) -> Result<GsdWriter> {
    Ok(if append && path.exists() {
        GsdWriter::append(path)?
    } else {
        GsdWriter::create_new(path)?
    })
}

/// CRC-32 of the first `frames` frames of a trajectory, and the file's layout after them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FrameDigest {
    /// Frames covered.
    pub frames: u64,
    /// Their CRC-32 (IEEE).
    pub crc: u32,
    /// The file's layout after them.
    pub layout: Layout,
}

impl Default for FrameDigest {
    fn default() -> Self {
        Self {
            frames: 0,
            crc: 0,
            layout: Layout::INITIAL,
        }
    }
}

impl FrameDigest {
    /// The digest of the first `frames` frames of `path`.
    pub fn of(path: &Path, frames: u64) -> Result<Self> {
        let mut d = Self::default();
        d.extend(path, frames)?;
        Ok(d)
    }

    /// Extend the digest over frames `self.frames..frames` of `path` (a file whose writer has
    /// synced and written exactly `frames` frames); nothing to do when it already covers them.
    pub fn extend(&mut self, path: &Path, frames: u64) -> Result<()> {
        if frames <= self.frames {
            return Ok(());
        }
        let g = GsdIndex::open(path)?;
        if g.layout.frames != frames {
            bail!(
                "{}: holds {} frames, {frames} were written",
                path.display(),
                g.layout.frames
            );
        }
        self.crc = crc_of(&g, self.frames, frames, self.crc)?;
        self.frames = frames;
        self.layout = g.layout;
        Ok(())
    }

    /// Before a restart appends to `path`: [`Self::verify`] it, then cut it back to the
    /// layout it had after the checkpoint's frames, dropping any frame or byte a killed run
    /// wrote after the checkpoint.
    pub fn restore(&self, path: &Path) -> Result<()> {
        self.verify(path)?;
        if path.exists() {
            restore_layout(path, &self.layout)?;
        }
        Ok(())
    }

    /// Check that `path` holds at least the frames this digest covers and that they are the
    /// frames the checkpoint saw, every chunk of them.
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
        let g = GsdIndex::open(path)?;
        let have = g.layout.frames;
        if have < self.frames {
            bail!(
                "{}: holds {have} frames, the checkpoint expects {}; the trajectory was damaged",
                path.display(),
                self.frames
            );
        }
        let crc = crc_of(&g, 0, self.frames, 0)?;
        if crc != self.crc {
            bail!(
                "{}: its first {} frames differ from those the checkpoint recorded (CRC-32 \
                 {crc:08x}, expected {:08x}): the trajectory was damaged or changed after the \
                 checkpoint; restore it, or start a new run",
                path.display(),
                self.frames,
                self.crc
            );
        }
        Ok(())
    }
}

/// Continue the CRC-32 `crc` over every chunk of frames `a..b` of `g`: per chunk its name, type
/// code, rows, columns and bytes.
fn crc_of(g: &GsdIndex, a: u64, b: u64, crc: u32) -> Result<u32> {
    let mut h = crc32fast::Hasher::new_with_initial(crc);
    let mut buf = Vec::new();
    for e in g.frames(a, b) {
        h.update(&e.frame.to_le_bytes());
        h.update(g.names[e.id as usize].as_bytes());
        h.update(&[0, e.code]);
        h.update(&e.rows.to_le_bytes());
        h.update(&e.columns.to_le_bytes());
        g.read(e, &mut buf)?;
        h.update(&buf);
    }
    Ok(h.finalize())
}
