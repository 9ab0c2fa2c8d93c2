//! Where an output goes, and how it gets there without harm: a regular file (or a new
//! one) is written to a temporary file beside it, flushed to disk and renamed over it;
//! a character device or FIFO (`/dev/null`, `/dev/stdout`, a named pipe) is written
//! through, never replaced; anything else is refused with one line.
//!
//! Durability: the temporary file is `fsync`ed before the rename and its folder after,
//! so once a command says it wrote a file, the file survives a power loss (on a file
//! system that honours `fsync`).
//!
//! Temporary files are named `.NAME.raypipe-PID@HOST-XXXXXX` beside their target `NAME`,
//! so a killed run's leftovers are found next to what they were for; the next run on the
//! same machine that writes into the folder removes those whose process is gone.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, Result};

/// What a path to be written is now.
#[derive(Debug, PartialEq, Eq)]
pub enum Target {
    /// A regular file or nothing yet: write beside it and rename. Holds the path to
    /// rename to (a symbolic link's target, so the link stays a link).
    Replace(PathBuf),
    /// A character device or a FIFO: open it and write through.
    WriteThrough,
}

/// Classifies `path` for writing, or says in one line why it cannot be written.
pub fn classify(path: &Path) -> Result<Target> {
    let name = path.display();
    match std::fs::metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            // A dangling symbolic link is written through to where it points.
            let resolved = match std::fs::read_link(path) {
                Ok(to) => dir_of(path).join(to),
                Err(_) => path.to_path_buf(),
            };
            check_parent(&resolved)?;
            Ok(Target::Replace(resolved))
        }
        Err(e) => Err(anyhow!("{name}: cannot be written: {e}")),
        Ok(m) if m.is_file() => {
            let resolved = if path.is_symlink() {
                std::fs::canonicalize(path).map_err(|e| anyhow!("{name}: cannot resolve the link: {e}"))?
            } else {
                path.to_path_buf()
            };
            Ok(Target::Replace(resolved))
        }
        Ok(m) if m.is_dir() => Err(anyhow!("{name}: is a directory, not a file")),
        Ok(m) => special_kind(&m)
            .map(|_| Target::WriteThrough)
            .map_err(|kind| anyhow!("{name}: is a {kind}; outputs go to regular files, character devices or FIFOs")),
    }
}

/// `Ok` for the kinds written through; otherwise the kind's name.
#[cfg(unix)]
fn special_kind(m: &std::fs::Metadata) -> Result<(), &'static str> {
    use std::os::unix::fs::FileTypeExt;
    let t = m.file_type();
    if t.is_char_device() || t.is_fifo() {
        Ok(())
    } else if t.is_block_device() {
        Err("block device")
    } else if t.is_socket() {
        Err("socket")
    } else {
        Err("special file")
    }
}

#[cfg(not(unix))]
fn special_kind(_: &std::fs::Metadata) -> Result<(), &'static str> {
    Err("special file")
}

/// The directory `path` is written in (`.` for a bare file name).
pub(crate) fn dir_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Checks that `path` can be written — its directory exists, and it is not a directory,
/// block device or socket — so that a command writing several outputs refuses before
/// it writes any.
pub fn check_writable(path: &Path) -> Result<()> {
    classify(path).map(drop)
}

fn check_parent(path: &Path) -> Result<()> {
    let dir = dir_of(path);
    if !dir.is_dir() {
        return Err(anyhow!("{}: directory {} does not exist", path.display(), dir.display()));
    }
    Ok(())
}

/// A file on its way to its name: a temporary file beside the target, or the opened
/// device it writes through to.
pub struct Pending {
    path: PathBuf,
    sink: Sink,
}

enum Sink {
    Temporary { tmp: tempfile::NamedTempFile, to: PathBuf },
    Device(File),
}

impl Pending {
    /// Starts writing `path`.
    pub fn create(path: &Path) -> Result<Pending> {
        let name = path.display();
        let sink = match classify(path)? {
            Target::WriteThrough => {
                let file = std::fs::OpenOptions::new()
                    .write(true)
                    .open(path)
                    .map_err(|e| anyhow!("{name}: cannot open for writing: {e}"))?;
                Sink::Device(file)
            }
            Target::Replace(to) => {
                let dir = dir_of(&to);
                remove_stale(dir);
                let tmp = tempfile::Builder::new()
                    .prefix(&format!("{}{}@{}-", temp_stem(&to), std::process::id(), host()))
                    .rand_bytes(6)
                    .tempfile_in(dir)
                    .map_err(|e| anyhow!("{name}: cannot create a file in {}: {e}", dir.display()))?;
                Sink::Temporary { tmp, to }
            }
        };
        Ok(Pending { path: path.to_path_buf(), sink })
    }

    /// The file to write to.
    pub fn file(&mut self) -> &mut File {
        match &mut self.sink {
            Sink::Temporary { tmp, .. } => tmp.as_file_mut(),
            Sink::Device(f) => f,
        }
    }

    /// The path the output is for.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Makes the contents durable (the temporary file's data on disk) without naming it
    /// yet: the slow, failing part of [`Pending::commit`], done first for every output
    /// of a command before any is renamed.
    pub fn sync(&mut self) -> Result<()> {
        let name = self.path.display();
        match &mut self.sink {
            Sink::Temporary { tmp, .. } => {
                let f = tmp.as_file_mut();
                f.flush().map_err(|e| anyhow!("{name}: cannot write: {e}"))?;
                // A temporary file is created 0600; the output gets what any new file would.
                super::set_default_permissions(f).map_err(|e| anyhow!("{name}: cannot set permissions: {e}"))?;
                f.sync_all().map_err(|e| anyhow!("{name}: cannot write: {e}"))
            }
            Sink::Device(f) => f.flush().map_err(|e| anyhow!("{name}: cannot write: {e}")),
        }
    }

    /// Gives the file its name, durably (the folder is synced after the rename).
    pub fn commit(mut self) -> Result<()> {
        self.sync()?;
        self.rename()
    }

    /// The rename alone, after [`Pending::sync`].
    pub(crate) fn rename(self) -> Result<()> {
        let name = self.path.display().to_string();
        if let Sink::Temporary { tmp, to } = self.sink {
            tmp.persist(&to).map_err(|e| anyhow!("{name}: cannot write: {}", e.error))?;
            sync_dir(dir_of(&to));
        }
        Ok(())
    }
}

/// A scratch folder beside the output `to` (spill files of a long build), named as its
/// temporary files are, so that a killed run's is removed by the next run writing there;
/// removed with its contents when dropped.
pub fn scratch_dir(to: &Path) -> Result<tempfile::TempDir> {
    let dir = dir_of(to);
    remove_stale(dir);
    tempfile::Builder::new()
        .prefix(&format!("{}{}@{}-", temp_stem(to), std::process::id(), host()))
        .rand_bytes(6)
        .tempdir_in(dir)
        .map_err(|e| anyhow!("{}: cannot create a scratch folder in {}: {e}", to.display(), dir.display()))
}

/// `.NAME.raypipe-`: the start of every temporary file for `NAME`.
fn temp_stem(to: &Path) -> String {
    let file = to.file_name().map_or_else(|| "output".into(), |s| s.to_string_lossy().into_owned());
    format!(".{file}.raypipe-")
}

/// Removes `dir`'s temporaries whose writing process no longer runs (a run killed
/// before its rename), once per folder and process: a sweep writing a million reports
/// into one folder reads it once, not a million times. Best effort: whatever cannot be
/// read or removed stays.
fn remove_stale(dir: &Path) {
    static SCANNED: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());
    let Ok(mut scanned) = SCANNED.lock() else { return };
    if scanned.iter().any(|d| d == dir) {
        return;
    }
    scanned.push(dir.to_path_buf());
    drop(scanned);
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let file = e.file_name();
        let Some(name) = file.to_str().filter(|f| f.starts_with('.')) else { continue };
        let Some((_, rest)) = name.rsplit_once(".raypipe-") else { continue };
        // PID@HOST-XXXXXX: only this machine's processes can be asked whether they run
        // (a folder on a cluster's shared file system holds other machines' too).
        let Some((owner, _)) = rest.rsplit_once('-') else { continue };
        let Some((pid, at)) = owner.split_once('@') else { continue };
        let Ok(pid) = pid.parse::<u32>() else { continue };
        if at == host() && !process_alive(pid) {
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                let _ = std::fs::remove_dir_all(e.path());
            } else {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
}

/// This machine's name, as temporary files carry it (`-` and `/` would confuse the
/// name's parts; they become `_`).
fn host() -> String {
    let mut buf = [0u8; 256];
    #[cfg(unix)]
    // SAFETY: gethostname writes at most `buf.len()` bytes into `buf`.
    let ok = unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) } == 0;
    #[cfg(not(unix))]
    let ok = false;
    let len = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
    let name = if ok { String::from_utf8_lossy(&buf[..len]).into_owned() } else { "localhost".into() };
    name.replace(['-', '/', '@'], "_")
}

#[cfg(unix)]
fn process_alive(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else { return true };
    // SAFETY: kill with signal 0 only checks that the process exists.
    let r = unsafe { libc::kill(pid, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
}

#[cfg(not(unix))]
fn process_alive(_: u32) -> bool {
    true
}

/// Syncs a folder so that a rename in it survives a power loss. Best effort: some file
/// systems refuse to sync a folder, and the data itself is already on disk.
fn sync_dir(dir: &Path) {
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
}
