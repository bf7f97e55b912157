//! The GSD file layer as colloidsim writes it: a writer whose byte layout depends only on the
//! frames written (never on when they were synced), an index reader that lists every chunk,
//! and the cut back to the state the writer left after a frame ([`Layout`]), so that a run
//! continued from a checkpoint writes the same bytes as one that never stopped.
//!
//! The layout follows the GSD 2 specification: a 256-byte header, an index of 32-byte
//! entries sorted by (frame, name id) and ended by a zero location, a name list of
//! null-terminated names in 64-byte blocks, and the chunk data. Each frame is written whole at
//! [`GsdFileWriter::end_frame`]: its data at the end of the file, then its new names, then its
//! index entries; an index or name list that would overflow moves to the end of the file, after
//! the frame's data, at twice its size (and the header is rewritten last). So the file after
//! frame `k` is a function of frames `0..=k` alone, and a process killed at any moment leaves
//! a readable file of whole frames.

use super::GsdError;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::fs::{File, OpenOptions};
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

const MAGIC: u64 = 0x65df_65df_65df_65df;
const HEADER: u64 = 256;
const ENTRY: u64 = 32;
const NAME_BLOCK: u64 = 64;
/// GSD file format 2.1.
const GSD_VERSION: u32 = (2 << 16) | 1;
const INITIAL_ENTRIES: u64 = 128;
const INITIAL_NAME_BLOCKS: u64 = 16;

/// Where a GSD file's index and name list lie and how much of them and of the file is in use
/// after its last frame: what a restart needs to cut a longer file back to that state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Layout {
    /// Frames.
    pub frames: u64,
    /// File length in bytes.
    pub len: u64,
    /// Index: byte offset, allocated entries, entries in use.
    pub index_location: u64,
    /// Index entries allocated.
    pub index_allocated: u64,
    /// Index entries in use.
    pub entries: u64,
    /// Name list: byte offset.
    pub names_location: u64,
    /// Name list: 64-byte blocks allocated.
    pub names_allocated: u64,
    /// Name list: bytes in use.
    pub names_len: u64,
}

impl Layout {
    /// A new file's: no frame yet.
    pub const INITIAL: Layout = Layout {
        frames: 0,
        len: HEADER + ENTRY * INITIAL_ENTRIES + NAME_BLOCK * INITIAL_NAME_BLOCKS,
        index_location: HEADER,
        index_allocated: INITIAL_ENTRIES,
        entries: 0,
        names_location: HEADER + ENTRY * INITIAL_ENTRIES,
        names_allocated: INITIAL_NAME_BLOCKS,
        names_len: 0,
    };
}

/// A value type GSD stores, with its type code.
pub trait Value: Copy {
    /// GSD type code.
    const CODE: u8;
    /// Append the native-endian bytes.
    fn put(&self, out: &mut Vec<u8>);
}

macro_rules! value {
    ($($t:ty => $c:expr),*) => {$(
        impl Value for $t {
            const CODE: u8 = $c;
            fn put(&self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_ne_bytes());
            }
        }
    )*};
}
value!(u8 => 1, u16 => 2, u32 => 3, u64 => 4, i8 => 5, i16 => 6, i32 => 7, i64 => 8, f32 => 9,
    f64 => 10);

/// Bytes per element of a GSD type code (11: a string, one byte per character).
fn size_of(code: u8) -> Option<u64> {
    Some(match code {
        1 | 5 | 11 => 1,
        2 | 6 => 2,
        3 | 7 | 9 => 4,
        4 | 8 | 10 => 8,
        _ => return None,
    })
}

/// One index entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Entry {
    /// Frame.
    pub frame: u64,
    /// Rows.
    pub rows: u64,
    /// Byte offset of the data.
    pub location: u64,
    /// Columns.
    pub columns: u32,
    /// Name id (position in the name list).
    pub id: u16,
    /// GSD type code.
    pub code: u8,
}

impl Entry {
    fn to_bytes(self) -> [u8; ENTRY as usize] {
        let mut b = [0u8; ENTRY as usize];
        b[0..8].copy_from_slice(&self.frame.to_ne_bytes());
        b[8..16].copy_from_slice(&self.rows.to_ne_bytes());
        b[16..24].copy_from_slice(&self.location.to_ne_bytes());
        b[24..28].copy_from_slice(&self.columns.to_ne_bytes());
        b[28..30].copy_from_slice(&self.id.to_ne_bytes());
        b[30] = self.code;
        b
    }

    fn from_bytes(b: &[u8]) -> (Self, u8) {
        let u64_at = |i: usize| u64::from_ne_bytes(b[i..i + 8].try_into().expect("8 bytes"));
        (
            Self {
                frame: u64_at(0),
                rows: u64_at(8),
                location: u64_at(16),
                columns: u32::from_ne_bytes(b[24..28].try_into().expect("4 bytes")),
                id: u16::from_ne_bytes(b[28..30].try_into().expect("2 bytes")),
                code: b[30],
            },
            b[31],
        )
    }

    /// Bytes of data (`None`: unknown type or too large).
    pub fn bytes(&self) -> Option<u64> {
        size_of(self.code)?
            .checked_mul(self.rows)?
            .checked_mul(self.columns as u64)
    }
}

fn u64_at(b: &[u8], i: usize) -> u64 {
    u64::from_ne_bytes(b[i..i + 8].try_into().expect("8 bytes"))
}

/// A GSD file's header, name list and index, read and checked (every entry inside the file,
/// sorted, naming a known name), for listing and reading chunks byte for byte.
pub struct GsdIndex {
    file: File,
    path: PathBuf,
    header: [u8; HEADER as usize],
    /// The file's layout after its last frame.
    pub layout: Layout,
    /// Names by id.
    pub names: Vec<String>,
    /// Every index entry in use, in file order.
    pub entries: Vec<Entry>,
}

impl GsdIndex {
    /// Open and check `path`.
    pub fn open(path: &Path) -> Result<Self, GsdError> {
        Self::open_with(path, false)
    }

    fn open_with(path: &Path, write: bool) -> Result<Self, GsdError> {
        let bad = |message: String| GsdError::Open {
            path: path.to_path_buf(),
            message,
        };
        let io = |e: std::io::Error| bad(e.to_string());
        let file = OpenOptions::new()
            .read(true)
            .write(write)
            .open(path)
            .map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        let mut header = [0u8; HEADER as usize];
        if len < HEADER {
            return Err(bad(
                "not a readable GSD file: shorter than its header".into()
            ));
        }
        file.read_exact_at(&mut header, 0).map_err(io)?;
        if u64_at(&header, 0) != MAGIC {
            return Err(bad("not a readable GSD file: no GSD magic number".into()));
        }
        let version = u32::from_ne_bytes(header[44..48].try_into().expect("4 bytes"));
        if version >> 16 != 2 {
            return Err(bad(format!(
                "not a readable GSD file: format {}.{} (this build reads 2.x)",
                version >> 16,
                version & 0xffff
            )));
        }
        let (index_location, index_allocated) = (u64_at(&header, 8), u64_at(&header, 16));
        let (names_location, names_allocated) = (u64_at(&header, 24), u64_at(&header, 32));
        let inside = |at: u64, n: u64, size: u64| {
            n > 0
                && n.checked_mul(size)
                    .and_then(|b| b.checked_add(at))
                    .is_some_and(|end| end <= len)
        };
        if !inside(index_location, index_allocated, ENTRY)
            || !inside(names_location, names_allocated, NAME_BLOCK)
        {
            return Err(bad(
                "damaged GSD file: its header names an index or name list past the end of the file (truncated?)".into(),
            ));
        }
        let mut list = vec![0u8; (names_allocated * NAME_BLOCK) as usize];
        file.read_exact_at(&mut list, names_location).map_err(io)?;
        if list.last() != Some(&0) {
            return Err(bad(
                "damaged GSD file: its name list is not terminated".into()
            ));
        }
        let mut names = Vec::new();
        let mut at = 0usize;
        while at < list.len() && list[at] != 0 {
            let end = at + list[at..].iter().position(|&c| c == 0).expect("terminated");
            let name = std::str::from_utf8(&list[at..end])
                .map_err(|_| bad("damaged GSD file: a chunk name is not UTF-8".into()))?;
            names.push(name.to_string());
            at = end + 1;
        }
        if names.len() > u16::MAX as usize {
            return Err(bad("damaged GSD file: too many chunk names".into()));
        }
        // Entries in use: up to the first with location 0, read in blocks.
        let mut entries = Vec::new();
        let mut block = vec![0u8; 4096 * ENTRY as usize];
        let mut k = 0u64;
        'read: while k < index_allocated {
            let n = (index_allocated - k).min(4096);
            let buf = &mut block[..(n * ENTRY) as usize];
            file.read_exact_at(buf, index_location + k * ENTRY)
                .map_err(io)?;
            for c in buf.chunks_exact(ENTRY as usize) {
                let (e, flags) = Entry::from_bytes(c);
                if e.location == 0 {
                    break 'read;
                }
                let ok = flags == 0
                    && (e.id as usize) < names.len()
                    && e.bytes()
                        .and_then(|b| b.checked_add(e.location))
                        .is_some_and(|end| end <= len)
                    && entries
                        .last()
                        .is_none_or(|p: &Entry| (p.frame, p.id) < (e.frame, e.id));
                if !ok {
                    return Err(bad(format!(
                        "damaged GSD file: index entry {} is invalid",
                        entries.len()
                    )));
                }
                entries.push(e);
            }
            k += n;
        }
        let frames = entries.last().map_or(0, |e| e.frame + 1);
        let names_len = at as u64;
        Ok(Self {
            file,
            path: path.to_path_buf(),
            header,
            layout: Layout {
                frames,
                len,
                index_location,
                index_allocated,
                entries: entries.len() as u64,
                names_location,
                names_allocated,
                names_len,
            },
            names,
            entries,
        })
    }

    /// The entries of frames `a..b` (a slice of [`Self::entries`]).
    pub fn frames(&self, a: u64, b: u64) -> &[Entry] {
        let i = self.entries.partition_point(|e| e.frame < a);
        let j = self.entries.partition_point(|e| e.frame < b);
        &self.entries[i..j]
    }

    /// The data of `e` into `buf` (replacing its contents).
    pub fn read(&self, e: &Entry, buf: &mut Vec<u8>) -> Result<(), GsdError> {
        let n = e.bytes().unwrap_or(0) as usize;
        buf.clear();
        buf.resize(n, 0);
        self.file
            .read_exact_at(buf, e.location)
            .map_err(|x| GsdError::Content {
                path: self.path.clone(),
                message: format!("frame {}: {x}", e.frame),
            })
    }

    fn names_bytes(&self) -> Vec<u8> {
        let mut b = Vec::new();
        for n in &self.names {
            b.extend_from_slice(n.as_bytes());
            b.push(0);
        }
        b
    }
}

/// Cut the GSD file `path` back to the state its writer left after frame `to.frames - 1`
/// (`to` recorded then, [`GsdIndex::layout`]): the frames and bytes written after it are
/// dropped, the index and name list are where and as long as they were. The file must still
/// hold those frames as they were (the index and names are compared); `to` = the current
/// layout changes nothing.
pub fn restore_layout(path: &Path, to: &Layout) -> Result<(), GsdError> {
    let g = GsdIndex::open_with(path, true)?;
    let bad = |message: String| GsdError::Content {
        path: path.to_path_buf(),
        message,
    };
    if g.layout == *to {
        return Ok(());
    }
    let now = &g.layout;
    let fits = |at: u64, n: u64, size: u64| at.saturating_add(n.saturating_mul(size)) <= to.len;
    let consistent = now.len >= to.len
        && now.frames >= to.frames
        && g.entries.len() as u64 >= to.entries
        && g.frames(0, to.frames).len() as u64 == to.entries
        && now.names_len >= to.names_len
        && to.entries <= to.index_allocated
        && to.names_len <= to.names_allocated * NAME_BLOCK
        && fits(to.index_location, to.index_allocated, ENTRY)
        && fits(to.names_location, to.names_allocated, NAME_BLOCK)
        && to.index_location >= HEADER
        && to.names_location >= HEADER;
    if !consistent {
        return Err(bad(format!(
            "cannot be cut back to its first {} frames as the checkpoint recorded them \
             ({} bytes): it holds {} frames in {} bytes",
            to.frames, to.len, now.frames, now.len
        )));
    }
    // The index and names in use then, where they were then, must be those of the file now.
    let io = |e: std::io::Error| bad(e.to_string());
    let mut then = vec![0u8; (to.entries * ENTRY) as usize];
    g.file
        .read_exact_at(&mut then, to.index_location)
        .map_err(io)?;
    let expected: Vec<u8> = g.entries[..to.entries as usize]
        .iter()
        .flat_map(|e| e.to_bytes())
        .collect();
    let mut names_then = vec![0u8; to.names_len as usize];
    g.file
        .read_exact_at(&mut names_then, to.names_location)
        .map_err(io)?;
    if then != expected || names_then[..] != g.names_bytes()[..to.names_len as usize] {
        return Err(bad(format!(
            "its index or name list differs from the one the checkpoint recorded at frame {}",
            to.frames
        )));
    }
    let zero_from = |at: u64, end: u64| -> Result<(), GsdError> {
        let zeros = vec![0u8; (end - at).min(1 << 20) as usize];
        let mut p = at;
        while p < end {
            let n = (end - p).min(zeros.len() as u64) as usize;
            g.file.write_all_at(&zeros[..n], p).map_err(io)?;
            p += n as u64;
        }
        Ok(())
    };
    zero_from(
        to.index_location + to.entries * ENTRY,
        to.index_location + to.index_allocated * ENTRY,
    )?;
    zero_from(
        to.names_location + to.names_len,
        to.names_location + to.names_allocated * NAME_BLOCK,
    )?;
    g.file.set_len(to.len).map_err(io)?;
    let mut header = g.header;
    write_layout(&mut header, to);
    g.file.write_all_at(&header, 0).map_err(io)?;
    g.file.sync_all().map_err(io)?;
    Ok(())
}

fn write_layout(header: &mut [u8; HEADER as usize], l: &Layout) {
    header[8..16].copy_from_slice(&l.index_location.to_ne_bytes());
    header[16..24].copy_from_slice(&l.index_allocated.to_ne_bytes());
    header[24..32].copy_from_slice(&l.names_location.to_ne_bytes());
    header[32..40].copy_from_slice(&l.names_allocated.to_ne_bytes());
}

/// Writes frames to a GSD file whose bytes depend only on the frames (module docs).
pub struct GsdFileWriter {
    file: File,
    path: PathBuf,
    header: [u8; HEADER as usize],
    layout: Layout,
    ids: HashMap<String, u16>,
    /// This frame: its data, its entries (location relative to the data) and its new names.
    data: Vec<u8>,
    pending: Vec<Entry>,
    new_names: Vec<u8>,
    new_ids: Vec<String>,
}

impl GsdFileWriter {
    /// Create `path` (an existing file is an error) with `application` and the data schema
    /// `schema` of version `version` in its header.
    pub fn create_new(
        path: &Path,
        application: &str,
        schema: &str,
        version: (u16, u16),
    ) -> Result<Self, GsdError> {
        let open = |message: String| GsdError::Open {
            path: path.to_path_buf(),
            message,
        };
        if application.len() >= 64 || schema.len() >= 64 {
            return Err(open("application or schema name too long".into()));
        }
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(path)
            .map_err(|e| open(e.to_string()))?;
        let layout = Layout::INITIAL;
        let mut header = [0u8; HEADER as usize];
        header[0..8].copy_from_slice(&MAGIC.to_ne_bytes());
        write_layout(&mut header, &layout);
        let sv = (u32::from(version.0) << 16) | u32::from(version.1);
        header[40..44].copy_from_slice(&sv.to_ne_bytes());
        header[44..48].copy_from_slice(&GSD_VERSION.to_ne_bytes());
        header[48..48 + application.len()].copy_from_slice(application.as_bytes());
        header[112..112 + schema.len()].copy_from_slice(schema.as_bytes());
        let io = |e: std::io::Error| open(e.to_string());
        file.set_len(layout.len).map_err(io)?;
        file.write_all_at(&header, 0).map_err(io)?;
        Ok(Self::with(file, path, header, layout, HashMap::new()))
    }

    /// Open `path` to append frames after its last.
    pub fn append(path: &Path) -> Result<Self, GsdError> {
        let g = GsdIndex::open_with(path, true)?;
        let ids = g
            .names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.clone(), i as u16))
            .collect();
        let GsdIndex {
            file,
            header,
            layout,
            ..
        } = g;
        Ok(Self::with(file, path, header, layout, ids))
    }

    fn with(
        file: File,
        path: &Path,
        header: [u8; HEADER as usize],
        layout: Layout,
        ids: HashMap<String, u16>,
    ) -> Self {
        Self {
            file,
            path: path.to_path_buf(),
            header,
            layout,
            ids,
            data: Vec::new(),
            pending: Vec::new(),
            new_names: Vec::new(),
            new_ids: Vec::new(),
        }
    }

    /// Frames written (complete).
    pub fn n_frames(&self) -> u64 {
        self.layout.frames
    }

    /// The layout after the last complete frame.
    pub fn layout(&self) -> Layout {
        self.layout
    }

    fn chunk(&mut self, name: &str, code: u8, columns: u32, rows: u64) -> Result<(), GsdError> {
        let id = match self.ids.get(name) {
            Some(&id) => id,
            None => {
                let id = u16::try_from(self.ids.len())
                    .ok()
                    .filter(|&i| i < u16::MAX)
                    .ok_or_else(|| self.error("too many chunk names".into()))?;
                if name.is_empty() || name.contains('\0') {
                    return Err(self.error(format!("invalid chunk name {name:?}")));
                }
                self.ids.insert(name.to_string(), id);
                self.new_names.extend_from_slice(name.as_bytes());
                self.new_names.push(0);
                self.new_ids.push(name.to_string());
                id
            }
        };
        if self.pending.iter().any(|e| e.id == id) {
            return Err(self.error(format!("chunk {name} written twice in one frame")));
        }
        self.pending.push(Entry {
            frame: self.layout.frames,
            rows,
            location: 0,
            columns,
            id,
            code,
        });
        Ok(())
    }

    fn error(&self, message: String) -> GsdError {
        GsdError::Write {
            path: self.path.clone(),
            message,
        }
    }

    /// Add a one-column chunk to the current frame.
    pub fn write_scalars<T: Value>(
        &mut self,
        name: &str,
        data: impl IntoIterator<Item = T>,
    ) -> Result<(), GsdError> {
        let start = self.data.len();
        for v in data {
            v.put(&mut self.data);
        }
        let rows = ((self.data.len() - start) / std::mem::size_of::<T>()) as u64;
        self.place(name, T::CODE, 1, rows, start)
    }

    /// Add an `M`-column chunk to the current frame.
    pub fn write_arrays<T: Value, const M: usize>(
        &mut self,
        name: &str,
        data: impl IntoIterator<Item = [T; M]>,
    ) -> Result<(), GsdError> {
        let start = self.data.len();
        for row in data {
            for v in row {
                v.put(&mut self.data);
            }
        }
        let rows = ((self.data.len() - start) / (M * std::mem::size_of::<T>())) as u64;
        self.place(name, T::CODE, M as u32, rows, start)
    }

    fn place(
        &mut self,
        name: &str,
        code: u8,
        columns: u32,
        rows: u64,
        start: usize,
    ) -> Result<(), GsdError> {
        match self.chunk(name, code, columns, rows) {
            Ok(()) => {
                self.pending.last_mut().expect("pushed").location = start as u64;
                Ok(())
            }
            Err(e) => {
                self.data.truncate(start);
                Err(e)
            }
        }
    }

    /// Write the current frame to the file (module docs); the next chunks go to the next
    /// frame. On an error the frame is dropped and the file keeps its frames before it.
    pub fn end_frame(&mut self) -> Result<(), GsdError> {
        let r = self.write_frame();
        self.data.clear();
        self.pending.clear();
        if r.is_err() {
            for n in self.new_ids.drain(..) {
                self.ids.remove(&n);
            }
        }
        self.new_names.clear();
        self.new_ids.clear();
        r
    }

    fn write_frame(&mut self) -> Result<(), GsdError> {
        let io = |e: std::io::Error| e.to_string();
        let was = self.layout;
        let mut l = was;
        let start = l.len;
        let mut end = start + self.data.len() as u64;
        // A name list or index that would overflow moves after the frame's data, doubled.
        let names_need = l.names_len + self.new_names.len() as u64;
        let names_moved = names_need > l.names_allocated * NAME_BLOCK;
        if names_moved {
            while l.names_allocated * NAME_BLOCK <= names_need {
                l.names_allocated *= 2;
            }
            l.names_location = end;
            end += l.names_allocated * NAME_BLOCK;
        }
        let entries_need = l.entries + self.pending.len() as u64;
        let index_moved = entries_need > l.index_allocated;
        if index_moved {
            while l.index_allocated <= entries_need {
                l.index_allocated *= 2;
            }
            l.index_location = end;
            end += l.index_allocated * ENTRY;
        }
        let mut entries = std::mem::take(&mut self.pending);
        for e in &mut entries {
            e.location += start;
        }
        entries.sort_by_key(|e| e.id);
        let index: Vec<u8> = entries.iter().flat_map(|e| e.to_bytes()).collect();
        let written = (|| -> Result<(), String> {
            let f = &self.file;
            f.set_len(end).map_err(io)?;
            f.write_all_at(&self.data, start).map_err(io)?;
            if names_moved {
                copy(f, was.names_location, l.names_location, was.names_len).map_err(io)?;
            }
            if index_moved {
                copy(f, was.index_location, l.index_location, was.entries * ENTRY).map_err(io)?;
            }
            f.write_all_at(&self.new_names, l.names_location + l.names_len)
                .map_err(io)?;
            f.write_all_at(&index, l.index_location + l.entries * ENTRY)
                .map_err(io)?;
            if names_moved || index_moved {
                let mut header = self.header;
                write_layout(&mut header, &l);
                f.write_all_at(&header, 0).map_err(io)?;
                self.header = header;
            }
            Ok(())
        })();
        if let Err(message) = written {
            // Leave the file as it was after the last frame, as far as it can be.
            let f = &self.file;
            let _ = f.write_all_at(&self.header_of(&was), 0);
            if !index_moved {
                let _ = f.write_all_at(&vec![0; index.len()], l.index_location + l.entries * ENTRY);
            }
            if !names_moved {
                let _ = f.write_all_at(
                    &vec![0; self.new_names.len()],
                    l.names_location + l.names_len,
                );
            }
            let _ = f.set_len(was.len);
            return Err(self.error(message));
        }
        l.len = end;
        l.names_len = names_need;
        l.entries = entries_need;
        l.frames += 1;
        self.layout = l;
        Ok(())
    }

    fn header_of(&self, l: &Layout) -> [u8; HEADER as usize] {
        let mut h = self.header;
        write_layout(&mut h, l);
        h
    }

    /// Bring every frame written to the disk.
    pub fn sync_all(&mut self) -> Result<(), GsdError> {
        self.file
            .sync_all()
            .map_err(|e| self.error(format!("cannot sync: {e}")))
    }
}

/// Copy `n` bytes within `f` from `from` to `to` (regions that do not overlap).
fn copy(f: &File, from: u64, to: u64, n: u64) -> std::io::Result<()> {
    let mut buf = vec![0u8; n.min(1 << 20) as usize];
    let mut done = 0;
    while done < n {
        let k = (n - done).min(buf.len() as u64) as usize;
        f.read_exact_at(&mut buf[..k], from + done)?;
        f.write_all_at(&buf[..k], to + done)?;
        done += k as u64;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use hoomd_gsd::file_layer::{GsdFile, Mode};

    fn frame(w: &mut GsdFileWriter, k: u64) {
        w.write_scalars("configuration/step", [k * 10]).unwrap();
        w.write_arrays(
            "particles/position",
            (0..k % 7).map(|i| [i as f32, 1.0, 2.0]),
        )
        .unwrap();
        // A new name now and then, written before names of lower id.
        if k % 5 == 3 {
            w.write_scalars(&format!("log/extra/{k}"), [k as f64])
                .unwrap();
        }
        w.write_scalars("particles/N", [(k % 7) as u32]).unwrap();
        w.end_frame().unwrap();
    }

    /// The bytes depend on the frames only: synced or not, and cut back to any frame's layout
    /// and continued, the file is the same; hoomd-gsd reads every chunk back.
    #[test]
    fn layout_depends_on_the_frames_only_and_cuts_back_exactly() {
        let tmp = tempfile::tempdir().unwrap();
        let write = |name: &str, frames: u64, sync: bool| {
            let path = tmp.path().join(name);
            let mut w = GsdFileWriter::create_new(&path, "test", "hoomd", (1, 4)).unwrap();
            let mut layouts = vec![w.layout()];
            for k in 0..frames {
                frame(&mut w, k);
                if sync {
                    w.sync_all().unwrap();
                }
                layouts.push(w.layout());
            }
            (path, layouts)
        };
        let (a, layouts) = write("a.gsd", 200, false);
        let (b, _) = write("b.gsd", 200, true);
        let bytes = std::fs::read(&a).unwrap();
        assert_eq!(bytes, std::fs::read(&b).unwrap());
        assert_eq!(layouts[200], GsdIndex::open(&a).unwrap().layout);
        let f = GsdFile::open(&a, Mode::Read).unwrap();
        assert_eq!(f.n_frames(), 200);
        for k in [0u64, 57, 199] {
            let x: Vec<u64> = f.iter_scalars(k, "configuration/step").unwrap().collect();
            assert_eq!(x, [k * 10]);
            let p: Vec<[f32; 3]> = f.iter_arrays(k, "particles/position").unwrap().collect();
            assert_eq!(p.len() as u64, k % 7);
        }
        assert!(f.find_chunk(53, "log/extra/53").is_some());
        // Cut back (from a longer file with trailing bytes) and continued: the same file.
        for cut in [0u64, 1, 9, 100, 130, 199] {
            let (c, _) = write("c.gsd", 200, false);
            {
                let mut w = GsdFileWriter::append(&c).unwrap();
                frame(&mut w, 200);
            }
            let mut tail = std::fs::OpenOptions::new().append(true).open(&c).unwrap();
            std::io::Write::write_all(&mut tail, b"junk").unwrap();
            restore_layout(&c, &layouts[cut as usize]).unwrap();
            let mut w = GsdFileWriter::append(&c).unwrap();
            assert_eq!(w.n_frames(), cut);
            for k in cut..200 {
                frame(&mut w, k);
            }
            drop(w);
            assert!(std::fs::read(&c).unwrap() == bytes, "cut at {cut}");
            std::fs::remove_file(&c).unwrap();
        }
        // A layout the file cannot have had is refused.
        let mut wrong = layouts[50];
        wrong.entries += 1;
        assert!(restore_layout(&a, &wrong).is_err());
        assert_eq!(std::fs::read(&a).unwrap(), bytes);
    }
}
