//! `checkpoint.bin`: versioned, checksummed, verified before use.
//!
//! Layout (bincode): the version string `0.1.0+checkpointF`, then the CRC-32 of the rest and
//! its length, then the [`Envelope`]. A restart refuses a checkpoint of another format (naming
//! both versions), one whose checksum or length disagrees (a flipped bit anywhere), and one
//! whose scenario or resolved parameters differ from the run it would continue.

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use std::io::Cursor;
use std::path::{Path, PathBuf};

/// The checkpoint's file name in a run folder.
pub const CHECKPOINT: &str = "checkpoint.bin";

/// Checkpoint format: bumped whenever a checkpoint's layout, or the random streams that a
/// continuation draws, change, so that a restart across such a change is refused instead of
/// silently continuing a different run. 2: the 1024-strip ziggurat; 3: the run path's
/// envelope with a checksum; 4: the CRC-32 of the trajectory frames written so far; 5: the BCD
/// density and contact density keep their block counts (for the standard errors); 6: a BD
/// replica's checkpoint no longer copies its engine parameters (a restart takes them from the
/// scenario, as every method's does); 7: the trajectory digest covers every chunk of every
/// frame and keeps the file's layout (a restart cuts the file back to it, byte for byte).
pub const FORMAT: u32 = 7;

/// The version string that leads every checkpoint: the package version and the format.
pub fn version() -> String {
    format!("{}+checkpoint{FORMAT}", env!("CARGO_PKG_VERSION"))
}

/// What every checkpoint holds besides the method's own state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Envelope {
    /// The scenario's `method`.
    pub method: String,
    /// The scenario text the run started with.
    pub scenario: String,
    /// The folder relative paths of the scenario are taken from.
    pub base: PathBuf,
    /// The seed of the run.
    pub seed: u64,
    /// The resolved parameters with the seed (JSON), compared on restart.
    pub resolved: String,
    /// Progress units done (steps over all replicas).
    pub position: u64,
    /// Wall seconds of every session so far.
    pub wall_seconds: f64,
    /// The method's own state.
    pub payload: Vec<u8>,
}

/// Encode a checkpoint.
pub fn encode(env: &Envelope) -> Result<Vec<u8>> {
    let body = bincode::serialize(env)?;
    let mut bytes = bincode::serialize(&version())?;
    bytes.extend(bincode::serialize(&(
        crc32fast::hash(&body),
        body.len() as u64,
    ))?);
    bytes.extend(body);
    Ok(bytes)
}

/// bincode as `bincode::serialize` writes it (fixed-width integers, little endian), reading
/// at most `limit` bytes: a damaged length prefix is refused instead of allocating whatever it
/// says.
fn limited(limit: usize) -> impl bincode::Options {
    use bincode::Options;
    bincode::DefaultOptions::new()
        .with_fixint_encoding()
        .allow_trailing_bytes()
        .with_limit(limit as u64)
}

/// Decode a method's payload (read no more than its own bytes).
pub fn decode_payload<T: serde::de::DeserializeOwned>(payload: &[u8]) -> Result<T> {
    use bincode::Options;
    limited(payload.len())
        .deserialize(payload)
        .map_err(|e| anyhow::anyhow!("checkpoint: the method's state cannot be decoded ({e})"))
}

/// Decode and verify checkpoint bytes read from `path` (named in every message).
pub fn decode(bytes: &[u8], path: &Path) -> Result<Envelope> {
    use bincode::Options;
    let opts = || limited(bytes.len());
    let mut cur = Cursor::new(bytes);
    let unreadable = |e: bincode::Error| {
        anyhow::anyhow!(
            "{}: not a colloidsim checkpoint, or damaged ({e})",
            path.display()
        )
    };
    let version: String = opts().deserialize_from(&mut cur).map_err(unreadable)?;
    let ours = self::version();
    if version != ours {
        bail!(
            "{}: written by colloidsim {version}, this build writes {ours}; the state layout or the random streams differ, so the run cannot be continued bitwise. Start it again, or continue it with the build that wrote it",
            path.display()
        );
    }
    let (crc, len): (u32, u64) = opts().deserialize_from(&mut cur).map_err(unreadable)?;
    let body = &bytes[cur.position() as usize..];
    if body.len() as u64 != len {
        bail!(
            "{}: damaged checkpoint: {} bytes of state, the header says {len} (truncated or extended)",
            path.display(),
            body.len()
        );
    }
    let found = crc32fast::hash(body);
    if found != crc {
        bail!(
            "{}: damaged checkpoint: checksum {found:08x}, written as {crc:08x}; it cannot be trusted. Start the run again",
            path.display()
        );
    }
    opts().deserialize(body).map_err(unreadable)
}

/// Read and verify `path`.
pub fn read(path: &Path) -> Result<Envelope> {
    let bytes = std::fs::read(path).with_context(|| format!("{}", path.display()))?;
    decode(&bytes, path)
}

/// CRC-32 of a file's bytes (for the files a checkpoint names beside it).
pub fn file_crc(path: &Path) -> Result<u32> {
    let bytes = std::fs::read(path).with_context(|| format!("{}", path.display()))?;
    Ok(crc32fast::hash(&bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Envelope {
        Envelope {
            method: "bcd".into(),
            scenario: "method = \"bcd\"\n".into(),
            base: ".".into(),
            seed: 7,
            resolved: "{}".into(),
            position: 1234,
            wall_seconds: 1.5,
            payload: (0..200u8).collect(),
        }
    }

    #[test]
    fn checkpoints_round_trip_and_every_flipped_bit_is_refused() {
        let env = sample();
        let bytes = encode(&env).unwrap();
        let path = Path::new("run/checkpoint.bin");
        assert_eq!(decode(&bytes, path).unwrap(), env);
        for i in 0..bytes.len() {
            for bit in [0u8, 3, 7] {
                let mut b = bytes.clone();
                b[i] ^= 1 << bit;
                assert!(
                    decode(&b, path).is_err(),
                    "a flip of bit {bit} of byte {i} was accepted"
                );
            }
        }
        for cut in [0, 5, bytes.len() / 2, bytes.len() - 1] {
            assert!(decode(&bytes[..cut], path).is_err(), "truncated at {cut}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(decode(&longer, path).is_err());
    }

    #[test]
    fn checkpoints_of_another_format_are_refused_by_name() {
        let old = bincode::serialize(&("0.1.0+checkpoint2".to_string(), 7u64)).unwrap();
        let e = decode(&old, Path::new("c.bin")).unwrap_err().to_string();
        assert!(
            e.contains("colloidsim 0.1.0+checkpoint2") && e.contains(&version()),
            "{e}"
        );
        assert!(decode(&[1, 2], Path::new("c.bin")).is_err());
    }
}
