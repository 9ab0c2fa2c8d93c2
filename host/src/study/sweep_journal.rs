//! A sweep's journal, `PREFIX.jsonl`: one row per finished point, appended as each
//! finishes, so that a stopped sweep resumes where it was. Several runs share a prefix
//! (the shards of a Slurm array writing one file in turn), so a run
//!
//! - holds `PREFIX.jsonl.lock` (an advisory `flock`, released when the process ends, by
//!   kill -9 too) for as long as it writes: a second run on the prefix is refused with
//!   one line instead of doing the work twice and orphaning one journal;
//! - keeps every row it did not write: rows of other shards of the spec stay in the
//!   journal and the table; rows that are no point of the spec (another spec's results)
//!   make it refuse, unless `--restart` says to replace them.

use std::collections::HashSet;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Result};

use crate::study::sweep::Point;
use crate::study::sweep_table::{self, Row};

/// The rows a run starts from, and the lock it holds.
pub struct Journal {
    /// The journal file.
    pub path: PathBuf,
    /// Rows of this run's points already done (resumed, not run again).
    pub done: Vec<Row>,
    /// Rows of the spec's other shards: kept as they are.
    pub others: Vec<Row>,
    _lock: File,
}

impl Journal {
    /// Locks the journal at `path` and reads it: `all` are the spec's points, `ours`
    /// those this run (shard) runs; with `restart` this run's rows and rows of no point
    /// of the spec are dropped.
    pub fn open(path: &Path, all: &[Point], ours: &[&Point], restart: bool) -> Result<Journal> {
        let lock = lock(path)?;
        let (mut done, mut others) = (Vec::new(), Vec::new());
        if path.exists() {
            let mine: HashSet<(usize, String)> = ours.iter().map(|p| (p.index, p.id())).collect();
            let spec: HashSet<(usize, String)> = all.iter().map(|p| (p.index, p.id())).collect();
            let mut foreign = 0;
            for r in sweep_table::read_rows(path)? {
                let key = (r.index, r.point.clone());
                if mine.contains(&key) {
                    if !restart {
                        done.push(r);
                    }
                } else if spec.contains(&key) {
                    others.push(r);
                } else {
                    foreign += 1;
                }
            }
            if foreign > 0 && !restart {
                bail!(
                    "{}: {foreign} rows are not points of this spec (another spec's results?); \
                     write to another prefix with -o, or replace them with --restart",
                    path.display()
                );
            }
            if foreign > 0 {
                eprintln!("note: {}: --restart drops {foreign} rows that are not points of this spec", path.display());
            }
        }
        let done = sweep_table::normalize(done);
        let others = sweep_table::normalize(others);
        Ok(Journal { path: path.to_path_buf(), done, others, _lock: lock })
    }

    /// Writes the journal afresh with the rows kept, and opens it for appending.
    pub fn start(&self) -> Result<File> {
        crate::output::write_atomic(&self.path, |w| {
            for r in self.others.iter().chain(&self.done) {
                writeln!(w, "{}", r.to_line())?;
            }
            Ok(())
        })?;
        std::fs::OpenOptions::new().append(true).open(&self.path).map_err(|e| anyhow!("{}: {e}", self.path.display()))
    }
}

impl Journal {
    /// Writes the journal and the table (`PREFIX.jsonl`, `PREFIX.csv`) of every row kept
    /// and `new` — still under the lock — and returns them, in point order.
    pub fn finish(self, prefix: &Path, new: Vec<Row>) -> Result<Vec<Row>> {
        let rows = sweep_table::normalize(self.others.into_iter().chain(self.done).chain(new).collect());
        sweep_table::write(prefix, &rows)?;
        Ok(rows)
    }
}

/// Takes `PATH.lock`, writing this process's id into it, or says who holds it.
#[cfg(unix)]
fn lock(path: &Path) -> Result<File> {
    use std::io::Read;
    use std::os::unix::io::AsRawFd;
    let mut name = path.as_os_str().to_owned();
    name.push(".lock");
    let lock_path = PathBuf::from(name);
    let mut file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&lock_path)
        .map_err(|e| anyhow!("{}: cannot create: {e}", lock_path.display()))?;
    // SAFETY: flock on a descriptor this function owns.
    if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
        let mut holder = String::new();
        let _ = file.read_to_string(&mut holder);
        let holder = holder.trim();
        let who = if holder.is_empty() { String::new() } else { format!(" (process {holder})") };
        bail!("{}: another sweep{who} is writing this journal; wait for it, or use another -o prefix", path.display());
    }
    file.set_len(0)
        .and_then(|_| write!(file, "{}", std::process::id()))
        .map_err(|e| anyhow!("{}: {e}", lock_path.display()))?;
    Ok(file)
}

#[cfg(not(unix))]
fn lock(path: &Path) -> Result<File> {
    let mut name = path.as_os_str().to_owned();
    name.push(".lock");
    File::create(PathBuf::from(name)).map_err(|e| anyhow!("{}: {e}", path.display()))
}
