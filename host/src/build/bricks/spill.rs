//! Spill files: triangle records on disk, written and read back in order, for the
//! partition of a scene larger than memory (Wald & Slusallek 2001 §6.4: "an out-of-core
//! algorithm is required to spatially sort and decompose the initial model").

use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

use anyhow::{anyhow, Result};

use super::tri_record::{TriRecord, COMPACT_BYTES, FULL_BYTES};

/// A file of records, with what is known of them.
#[derive(Clone, Debug)]
pub struct SpillFile {
    /// Where it is.
    pub path: PathBuf,
    /// Records.
    pub count: u64,
    /// Box of the records' centroids.
    pub centroids: ([f64; 3], [f64; 3]),
    /// Box of the records' vertices.
    pub bounds: ([f32; 3], [f32; 3]),
    /// Records carry shading data.
    pub shading: bool,
}

/// Writes records to a new spill file.
pub struct SpillWriter {
    out: BufWriter<File>,
    file: SpillFile,
}

impl SpillWriter {
    /// Starts `path`.
    pub fn create(path: &Path, shading: bool) -> Result<SpillWriter> {
        let f = File::create(path).map_err(|e| anyhow!("{}: cannot create a spill file: {e}", path.display()))?;
        Ok(SpillWriter {
            out: BufWriter::with_capacity(1 << 20, f),
            file: SpillFile {
                path: path.to_path_buf(),
                count: 0,
                centroids: ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
                bounds: ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
                shading,
            },
        })
    }

    /// Appends one record.
    pub fn push(&mut self, r: &TriRecord) -> Result<()> {
        self.out
            .write_all(r.spilled(self.file.shading))
            .map_err(|e| anyhow!("{}: cannot write a spill file: {e}", self.file.path.display()))?;
        let f = &mut self.file;
        f.count += 1;
        for a in 0..3 {
            let c = r.centroid(a);
            f.centroids.0[a] = f.centroids.0[a].min(c);
            f.centroids.1[a] = f.centroids.1[a].max(c);
            for p in &r.p {
                f.bounds.0[a] = f.bounds.0[a].min(p[a]);
                f.bounds.1[a] = f.bounds.1[a].max(p[a]);
            }
        }
        Ok(())
    }

    /// Flushes and closes the file.
    pub fn finish(mut self) -> Result<SpillFile> {
        self.out.flush().map_err(|e| anyhow!("{}: cannot write a spill file: {e}", self.file.path.display()))?;
        Ok(self.file)
    }
}

impl SpillFile {
    /// Bytes of one record on disk.
    pub fn record_bytes(&self) -> usize {
        if self.shading {
            FULL_BYTES
        } else {
            COMPACT_BYTES
        }
    }

    /// Reads every record in order.
    pub fn for_each(&self, mut f: impl FnMut(TriRecord) -> Result<()>) -> Result<()> {
        let file =
            File::open(&self.path).map_err(|e| anyhow!("{}: cannot read a spill file: {e}", self.path.display()))?;
        let mut r = BufReader::with_capacity(1 << 20, file);
        let size = self.record_bytes();
        let mut buf = vec![0u8; size];
        for _ in 0..self.count {
            r.read_exact(&mut buf).map_err(|e| anyhow!("{}: cannot read a spill file: {e}", self.path.display()))?;
            f(TriRecord::from_spilled(&buf))?;
        }
        Ok(())
    }

    /// Reads every record into memory.
    pub fn load(&self) -> Result<Vec<TriRecord>> {
        let mut v = Vec::with_capacity(self.count as usize);
        self.for_each(|r| {
            v.push(r);
            Ok(())
        })?;
        Ok(v)
    }

    /// Deletes the file.
    pub fn remove(&self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Where to split a file's records: a plane near the median of their `key`s (which lie
/// in `range`), found with histograms (each a pass over the file), narrowed three times
/// at most. `None` when the keys cannot be told apart.
pub fn median_plane(file: &SpillFile, range: (f64, f64), key: impl Fn(&TriRecord) -> f64) -> Result<Option<f64>> {
    const BINS: usize = 4096;
    let (mut lo, mut hi) = range;
    let mut below = 0u64;
    let half = file.count / 2;
    for _ in 0..3 {
        if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
            return Ok(None);
        }
        let width = (hi - lo) / BINS as f64;
        let mut bins = vec![0u64; BINS];
        file.for_each(|r| {
            let c = key(&r);
            if c >= lo && c <= hi {
                let k = (((c - lo) / width) as usize).min(BINS - 1);
                bins[k] += 1;
            }
            Ok(())
        })?;
        // The bin where the running count passes half.
        let mut run = below;
        let mut k = 0;
        while k < BINS && run + bins[k] <= half {
            run += bins[k];
            k += 1;
        }
        let k = k.min(BINS - 1);
        let plane = lo + width * k as f64;
        // A plane at the bin's lower edge splits well unless the bin itself holds most.
        if bins[k] <= file.count / 4 && run > 0 {
            return Ok(Some(plane));
        }
        below = run;
        (lo, hi) = (plane, lo + width * (k + 1) as f64);
    }
    Ok((below > 0 && below < file.count).then_some(lo))
}
