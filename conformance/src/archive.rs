//! Opening an `.fmu` that nobody vouches for.
//!
//! An FMU file is untrusted input: a zip archive whose entry names, sizes and contents are
//! whatever its author wrote. Everything that reads one goes through this module:
//!
//! - [`open`] opens the archive (no entry is read yet);
//! - [`read_model_description`] reads `modelDescription.xml`, bounded in size, and checks that
//!   it is well-formed UTF-8 XML; errors give line and column;
//! - [`extract_private`] unpacks every entry into a new private folder (mode 0700) that is
//!   removed when the returned [`PrivateDir`] is dropped. It refuses entry names with `..`
//!   components, absolute names (`/x`, `C:x`), backslashes and NUL bytes, names that would land
//!   outside the folder, duplicates, symbolic links and other non-regular entries, more than
//!   [`Limits::max_entries`] entries, and more than [`Limits::max_total_bytes`] bytes in all,
//!   counted as the bytes actually written (a header may lie about the uncompressed size).

use quick_xml::Reader;
use quick_xml::events::Event;
use std::collections::HashSet;
use std::ffi::OsStr;
use std::fs::File;
use std::io::{Read, Write};
#[cfg(unix)]
use std::os::unix::ffi::OsStrExt;
#[cfg(unix)]
use std::os::unix::fs::{DirBuilderExt, OpenOptionsExt};
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Bounds on what an archive may unpack to.
#[derive(Debug, Clone, Copy)]
pub struct Limits {
    /// Bytes written for all entries together.
    pub max_total_bytes: u64,
    pub max_entries: usize,
    /// Bytes of `modelDescription.xml` that [`read_model_description`] reads.
    pub max_model_description_bytes: u64,
}

impl Default for Limits {
    fn default() -> Limits {
        Limits {
            max_total_bytes: 1 << 30,
            max_entries: 10_000,
            max_model_description_bytes: 64 << 20,
        }
    }
}

/// An opened `.fmu` (zip) archive.
pub struct Archive {
    path: PathBuf,
    zip: zip::ZipArchive<File>,
}

impl Archive {
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The raw names of every entry, lossily decoded, in archive order.
    pub fn entry_names(&self) -> Vec<String> {
        (0..self.zip.len())
            .filter_map(|i| self.zip.name_for_index(i).and_then(|n| n.ok()).map(|n| n.into_owned()))
            .collect()
    }

    pub fn has_entry(&self, name: &str) -> bool {
        self.zip.index_for_name(name).is_some()
    }

    /// The bytes of entry `name` (at most the default limit of a model description), or
    /// `None` when the archive has no such entry.
    pub fn read_entry(&mut self, name: &str) -> Result<Option<Vec<u8>>, String> {
        self.read_entry_within(name, Limits::default().max_model_description_bytes)
    }

    /// [`Archive::read_entry`] of at most `max` bytes.
    pub fn read_entry_within(&mut self, name: &str, max: u64) -> Result<Option<Vec<u8>>, String> {
        let mut entry = match self.zip.by_name(name) {
            Ok(e) => e,
            Err(zip::result::ZipError::FileNotFound) => return Ok(None),
            Err(e) => return Err(format!("{}: {name}: {e}", self.path.display())),
        };
        let read = read_at_most(&mut entry, name, max);
        drop(entry);
        read.map_err(|e| self.at(e)).map(Some)
    }

    fn at(&self, e: impl std::fmt::Display) -> String {
        format!("{}: {e}", self.path.display())
    }
}

/// Opens the archive at `path`: the file must exist and be a zip archive.
pub fn open(path: &Path) -> Result<Archive, String> {
    let at = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let file = File::open(path).map_err(|e| at(&e))?;
    let zip = zip::ZipArchive::new(file).map_err(|e| at(&format!("not a readable zip archive: {e}")))?;
    Ok(Archive {
        path: path.to_path_buf(),
        zip,
    })
}

/// Reads `modelDescription.xml` (at the archive's root), at most
/// [`Limits::max_model_description_bytes`] of the default limits, and checks that it is UTF-8
/// and well-formed XML. The error of a malformed file says where: line and column.
pub fn read_model_description(archive: &mut Archive) -> Result<String, String> {
    read_model_description_within(archive, &Limits::default())
}

pub fn read_model_description_within(archive: &mut Archive, limits: &Limits) -> Result<String, String> {
    let max = limits.max_model_description_bytes;
    let mut entry = match archive.zip.by_name("modelDescription.xml") {
        Ok(e) => e,
        Err(e) => {
            let at = format!(
                "{}: no modelDescription.xml at the archive's root ({e})",
                archive.path.display()
            );
            return Err(at);
        }
    };
    if entry.size() > max {
        let size = entry.size();
        drop(entry);
        return Err(archive.at(format!(
            "modelDescription.xml has {size} bytes, more than the {max} read"
        )));
    }
    let read = read_at_most(&mut entry, "modelDescription.xml", max);
    drop(entry);
    let bytes = read.map_err(|e| archive.at(e))?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let valid = e.utf8_error().valid_up_to();
        let prefix = String::from_utf8_lossy(&e.as_bytes()[..valid]).into_owned();
        let (line, col) = line_column(&prefix, valid);
        archive.at(format!("modelDescription.xml:{line}:{col}: not UTF-8"))
    })?;
    check_well_formed(&text).map_err(|e| archive.at(format!("modelDescription.xml:{e}")))?;
    Ok(text)
}

/// Line and column of a byte offset: the description reader's, so that the archive's errors and
/// the description's count alike.
pub use md_reader::line_column;

/// Parses the whole document; an error is `line:column: what`.
pub fn check_well_formed(xml: &str) -> Result<(), String> {
    let mut reader = Reader::from_str(xml);
    let mut depth = 0usize;
    let mut roots = 0usize;
    loop {
        match reader.read_event() {
            Err(e) => {
                let (line, col) = line_column(xml, reader.error_position() as usize);
                return Err(format!("{line}:{col}: {e}"));
            }
            Ok(Event::Eof) => break,
            Ok(Event::Start(_)) => {
                if depth == 0 {
                    roots += 1;
                }
                depth += 1;
            }
            Ok(Event::End(_)) => depth = depth.saturating_sub(1),
            Ok(Event::Empty(_)) if depth == 0 => roots += 1,
            Ok(Event::Text(t)) if depth == 0 && !t.iter().all(u8::is_ascii_whitespace) => {
                let (line, col) = line_column(xml, reader.buffer_position() as usize - t.len());
                return Err(format!("{line}:{col}: text outside the root element"));
            }
            Ok(_) => {}
        }
        if roots > 1 {
            let (line, col) = line_column(xml, reader.buffer_position() as usize);
            return Err(format!("{line}:{col}: a second root element"));
        }
    }
    if depth > 0 {
        let (line, col) = line_column(xml, xml.len());
        return Err(format!("{line}:{col}: the document ends inside an element"));
    }
    if roots == 0 {
        return Err("1:1: no root element".into());
    }
    Ok(())
}

/// A folder of this process, created with mode 0700 under a parent folder, removed (with
/// everything in it) when dropped.
#[derive(Debug)]
pub struct PrivateDir {
    path: PathBuf,
}

impl PrivateDir {
    /// A new, empty folder with a name no other process or call uses.
    pub fn new_in(parent: &Path) -> Result<PrivateDir, String> {
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        let mut last = String::new();
        for _ in 0..100 {
            let n = COUNTER.fetch_add(1, Ordering::Relaxed);
            let path = parent.join(format!("fmi2-check-{}-{nanos:08x}-{n}", std::process::id()));
            #[cfg_attr(not(unix), allow(unused_mut))]
            let mut builder = std::fs::DirBuilder::new();
            #[cfg(unix)]
            builder.mode(0o700);
            match builder.create(&path) {
                Ok(()) => return Ok(PrivateDir { path }),
                Err(e) => last = format!("{}: {e}", path.display()),
            }
        }
        Err(format!("cannot create a private folder: {last}"))
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Keeps the folder: it is not removed on drop.
    pub fn keep(self) -> PathBuf {
        let path = self.path.clone();
        std::mem::forget(self);
        path
    }
}

impl Drop for PrivateDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.path);
    }
}

/// A name's bytes as an OS string: any bytes on Unix, UTF-8 only elsewhere (Windows).
#[cfg(unix)]
fn os_str(bytes: &[u8]) -> Option<&OsStr> {
    Some(OsStr::from_bytes(bytes))
}

#[cfg(not(unix))]
fn os_str(bytes: &[u8]) -> Option<&OsStr> {
    std::str::from_utf8(bytes).ok().map(OsStr::new)
}

/// The relative path an entry name stands for, or why the name is refused.
pub fn check_entry_name(raw: &[u8]) -> Result<PathBuf, String> {
    let shown = String::from_utf8_lossy(raw);
    let refuse = |why: &str| Err(format!("entry '{}': {why}", shown.escape_debug()));
    if raw.is_empty() {
        return refuse("empty name");
    }
    if raw.contains(&0) {
        return refuse("the name contains a NUL byte");
    }
    if raw.contains(&b'\\') {
        return refuse("the name contains a backslash (zip entry names use '/')");
    }
    if raw[0] == b'/' {
        return refuse("absolute name");
    }
    if raw.len() >= 2 && raw[1] == b':' && raw[0].is_ascii_alphabetic() {
        return refuse("absolute name (drive letter)");
    }
    let mut rel = PathBuf::new();
    for part in raw.split(|b| *b == b'/') {
        match part {
            b"" | b"." => {}
            b".." => return refuse("the name has a '..' component"),
            p => rel.push(os_str(p).ok_or_else(|| format!("entry '{}': the name is not UTF-8", shown.escape_debug()))?),
        }
    }
    if rel.components().any(|c| !matches!(c, Component::Normal(_))) {
        return refuse("the name would land outside the folder");
    }
    if rel.as_os_str().is_empty() {
        return refuse("the name has no file name");
    }
    Ok(rel)
}

/// Unpacks every entry into a new private folder under `parent` (see the module
/// documentation for what is refused). On an error nothing is left behind.
pub fn extract_private(archive: &mut Archive, parent: &Path, limits: &Limits) -> Result<PrivateDir, String> {
    let dir = PrivateDir::new_in(parent)?;
    let n = archive.zip.len();
    if n > limits.max_entries {
        return Err(archive.at(format!("{n} entries, more than the {} allowed", limits.max_entries)));
    }
    let root = dir
        .path()
        .canonicalize()
        .map_err(|e| format!("{}: {e}", dir.path().display()))?;
    let mut total = 0u64;
    let mut seen = HashSet::new();
    for i in 0..n {
        extract_entry(archive, i, &root, limits, &mut total, &mut seen).map_err(|e| archive.at(e))?;
    }
    Ok(dir)
}

fn extract_entry(
    archive: &mut Archive,
    i: usize,
    root: &Path,
    limits: &Limits,
    total: &mut u64,
    seen: &mut HashSet<PathBuf>,
) -> Result<(), String> {
    let mut entry = archive.zip.by_index(i).map_err(|e| format!("entry {i}: {e}"))?;
    let raw = entry.name_raw().to_vec();
    let rel = check_entry_name(&raw)?;
    let shown = String::from_utf8_lossy(&raw).into_owned();
    if entry.is_symlink() {
        return Err(format!("entry '{shown}': a symbolic link"));
    }
    // The file type bits of a Unix mode: only regular files and directories.
    if let Some(mode) = entry.unix_mode() {
        let kind = mode & 0o170000;
        if kind != 0 && kind != 0o100000 && kind != 0o040000 {
            return Err(format!("entry '{shown}': not a regular file or folder (mode {mode:o})"));
        }
    }
    if !seen.insert(rel.clone()) {
        return Err(format!("entry '{shown}': a second entry of that name"));
    }
    let dest = root.join(&rel);
    if !dest.starts_with(root) {
        return Err(format!("entry '{shown}': would land outside the folder"));
    }
    let made = if entry.is_dir() {
        dest.as_path()
    } else {
        dest.parent().unwrap_or(root)
    };
    std::fs::create_dir_all(made).map_err(|e| format!("entry '{shown}': {e}"))?;
    // Nothing above it may lead elsewhere (no entry makes a link, but check what was made).
    let real = made.canonicalize().map_err(|e| format!("entry '{shown}': {e}"))?;
    if !real.starts_with(root) {
        return Err(format!("entry '{shown}': would land outside the folder"));
    }
    if entry.is_dir() {
        return Ok(());
    }
    let remaining = limits.max_total_bytes - *total;
    let declared = entry.size();
    if declared > remaining {
        return Err(format!(
            "entry '{shown}': {declared} bytes uncompressed; with the entries before it more than the {} allowed",
            limits.max_total_bytes
        ));
    }
    let mut options = std::fs::OpenOptions::new();
    options.write(true).create_new(true);
    #[cfg(unix)]
    options.mode(0o600);
    let mut out = options.open(&dest).map_err(|e| format!("entry '{shown}': {e}"))?;
    let written = copy_bounded(&mut entry, &mut out, remaining).map_err(|e| match e {
        Copy::TooLong => format!(
            "entry '{shown}' unpacks to more than the {} bytes allowed in all (its header says {declared}): refused as a zip bomb",
            limits.max_total_bytes
        ),
        Copy::Io(e) => format!("entry '{shown}': {e}"),
    })?;
    if written != declared {
        return Err(format!(
            "entry '{shown}': {written} bytes unpacked, its header says {declared}"
        ));
    }
    *total += written;
    Ok(())
}

enum Copy {
    TooLong,
    Io(std::io::Error),
}

/// Copies at most `limit` bytes, counted as they are written (a header's size is only a
/// claim); more is an error, and the copy stops there.
fn copy_bounded(from: &mut impl Read, to: &mut impl Write, limit: u64) -> Result<u64, Copy> {
    let mut written = 0u64;
    let mut buf = vec![0u8; 64 * 1024];
    loop {
        let k = from.read(&mut buf).map_err(Copy::Io)?;
        if k == 0 {
            return Ok(written);
        }
        written += k as u64;
        if written > limit {
            return Err(Copy::TooLong);
        }
        to.write_all(&buf[..k]).map_err(Copy::Io)?;
    }
}

/// The bytes of the entry `name`, read up to `max` (one more tells a longer entry, refused).
fn read_at_most(entry: &mut impl Read, name: &str, max: u64) -> Result<Vec<u8>, String> {
    let mut bytes = vec![];
    entry
        .take(max + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("{name}: {e}"))?;
    if bytes.len() as u64 > max {
        return Err(format!("{name} is longer than the {max} bytes read"));
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An endless stream of zeros: what a decompressor of a zip bomb produces.
    struct Zeros;
    impl Read for Zeros {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            buf.fill(0);
            Ok(buf.len())
        }
    }

    #[test]
    fn the_copy_stops_at_the_limit_of_bytes_actually_written() {
        let mut out = vec![];
        assert!(matches!(
            copy_bounded(&mut Zeros, &mut out, 1 << 20),
            Err(Copy::TooLong)
        ));
        assert!(out.len() <= 1 << 20, "wrote {} bytes past a limit of 1 MiB", out.len());
        let mut out = vec![];
        assert!(matches!(copy_bounded(&mut &[1u8; 1000][..], &mut out, 1000), Ok(1000)));
        assert!(matches!(
            copy_bounded(&mut &[1u8; 1001][..], &mut vec![], 1000),
            Err(Copy::TooLong)
        ));
    }
}
