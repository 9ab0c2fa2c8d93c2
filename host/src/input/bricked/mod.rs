//! Reading bricked scenes: the index mapped in place and validated once, each brick read
//! with a positioned read, its checksum checked, decompressed and validated when a ray
//! first needs it (Wald & Slusallek 2001, §6.3).
//!
//! Bricks are read with `pread`, not through the map: a read error on a mapped page is a
//! `SIGBUS` that kills the process, while a failed read is one line of error naming the
//! file and the brick.

pub mod codec;

use std::fs::File;
use std::path::Path;
use std::time::Instant;

use anyhow::{anyhow, bail, Result};
use memmap2::{Mmap, MmapOptions};
use raypipe_core::image::bricked::{BrickedHeader, BrickedView, BRICKED_MAGIC};
use raypipe_core::image::crc32;
use raypipe_core::SceneView;

use crate::platform::aligned::AlignedBytes;

/// An open bricked scene: its index validated, and where its bricks' stored bytes come
/// from.
pub struct BrickedScene {
    // Borrows `index`'s bytes, which stay where they are until they are dropped, after
    // it (fields drop in order).
    view: BrickedView<'static>,
    index: IndexBytes,
    stored: Stored,
    /// What the user called it.
    pub name: String,
}

/// The index's bytes: mapped from the file, or received (from a model server).
enum IndexBytes {
    Mapped(Mmap),
    Owned(AlignedBytes),
}

/// Reads brick `b`'s `size` stored bytes from wherever they are kept.
pub type FetchStored = Box<dyn Fn(u32, u64) -> Result<Vec<u8>> + Send + Sync>;

/// Where the bricks' stored bytes come from.
enum Stored {
    File(File),
    Fetched(FetchStored),
}

/// A brick in memory: its decompressed scene image and the validated view of it.
pub struct ResidentBrick {
    // Borrows `image`'s heap buffer, which never moves or changes once built and is
    // dropped after it.
    view: SceneView<'static>,
    image: AlignedBytes,
}

/// What reading one brick cost.
#[derive(Clone, Copy, Debug, Default)]
pub struct LoadCost {
    /// Stored bytes read (from the file, or the model server).
    pub bytes_read: u64,
    /// Bytes decompressed.
    pub bytes_decompressed: u64,
    /// Seconds spent reading.
    pub read_seconds: f64,
    /// Seconds spent decompressing and validating.
    pub decompress_seconds: f64,
}

impl ResidentBrick {
    /// The brick's validated view.
    pub fn view(&self) -> &SceneView<'_> {
        &self.view
    }

    /// Its scene image's bytes.
    pub fn image(&self) -> &[u8] {
        &self.image
    }

    /// Bytes it occupies.
    pub fn bytes(&self) -> u64 {
        self.image.len() as u64
    }
}

/// True if `path` begins like a bricked scene.
pub fn is_bricked(path: &Path) -> bool {
    use std::io::Read;
    let Ok(mut f) = File::open(path) else { return false };
    let mut head = [0u8; 8];
    matches!(f.read(&mut head), Ok(8)) && head == BRICKED_MAGIC
}

impl BrickedScene {
    /// Opens and validates the bricked scene at `path` (the index only; bricks are
    /// checked as they load).
    pub fn open(path: &Path) -> Result<BrickedScene> {
        let name = path.display().to_string();
        let (file, len) = crate::input::read_file::open_regular(path)?;
        let mut head = [0u8; 128];
        read_at(&file, &mut head, 0).map_err(|e| anyhow!("{name}: cannot read the header: {e}"))?;
        let header: BrickedHeader = bytemuck::pod_read_unaligned(&head);
        if header.magic != BRICKED_MAGIC {
            bail!("{name}: not a bricked scene (bad magic)");
        }
        let index_len = header.index_size.min(len);
        if index_len < 128 {
            bail!("{name}: truncated: {len} bytes");
        }
        let index_len = usize::try_from(index_len).map_err(|_| anyhow!("{name}: the index is too large"))?;
        // SAFETY: the map is read only. If another process truncates or rewrites the file
        // while it is open, reads of the index may see the change or fault; raypipe never
        // writes a scene in place (outputs are renamed over), so its own runs cannot.
        let map = unsafe { MmapOptions::new().len(index_len).map(&file) }
            .map_err(|e| anyhow!("{name}: cannot map the index: {e}"))?;
        let view = BrickedView::parse(&map, len).map_err(|e| anyhow!("{name}: {e}"))?;
        // SAFETY: the view borrows the mapped pages, which stay in place while `map`
        // lives; `map` is stored beside it and dropped after it, and never handed out.
        let view: BrickedView<'static> = unsafe { std::mem::transmute::<BrickedView<'_>, BrickedView<'static>>(view) };
        Ok(BrickedScene { view, index: IndexBytes::Mapped(map), stored: Stored::File(file), name })
    }

    /// A scene whose index came as `index` (of a file `file_len` bytes long) and whose
    /// bricks' stored bytes `fetch` brings: a model server's scene, seen by a worker.
    pub fn from_index(name: String, index: &[u8], file_len: u64, fetch: FetchStored) -> Result<BrickedScene> {
        let bytes = AlignedBytes::from_slice(index);
        let view = BrickedView::parse(&bytes, file_len).map_err(|e| anyhow!("{name}: {e}"))?;
        // SAFETY: the view borrows the aligned buffer's heap bytes, which do not move
        // when `bytes` moves and are never written; they are stored beside the view and
        // dropped after it.
        let view: BrickedView<'static> = unsafe { std::mem::transmute::<BrickedView<'_>, BrickedView<'static>>(view) };
        Ok(BrickedScene { view, index: IndexBytes::Owned(bytes), stored: Stored::Fetched(fetch), name })
    }

    /// The index's bytes, as a model server sends them.
    pub fn index_bytes(&self) -> &[u8] {
        match &self.index {
            IndexBytes::Mapped(m) => &m[..],
            IndexBytes::Owned(b) => b,
        }
    }

    /// Brick `b`'s stored bytes (compressed, unchecked), as a model server sends them.
    pub fn read_stored(&self, b: u32) -> Result<Vec<u8>> {
        let name = &self.name;
        let rec = *self.view.brick(b).ok_or_else(|| anyhow!("{name}: brick {b} does not exist"))?;
        match &self.stored {
            Stored::File(file) => {
                let mut stored = vec![0u8; rec.stored_size as usize];
                read_at(file, &mut stored, rec.offset).map_err(|e| anyhow!("{name}: brick {b}: cannot read: {e}"))?;
                Ok(stored)
            }
            Stored::Fetched(fetch) => {
                let stored = fetch(b, rec.stored_size)?;
                if stored.len() as u64 != rec.stored_size {
                    bail!("{name}: brick {b}: {} bytes came, not {}", stored.len(), rec.stored_size);
                }
                Ok(stored)
            }
        }
    }

    /// The validated index.
    pub fn view(&self) -> &BrickedView<'_> {
        &self.view
    }

    /// Reads brick `b`, checks its stored bytes' checksum, decompresses and validates it.
    pub fn load(&self, b: u32) -> Result<(ResidentBrick, LoadCost)> {
        let name = &self.name;
        let rec = *self.view.brick(b).ok_or_else(|| anyhow!("{name}: brick {b} does not exist"))?;
        let t0 = Instant::now();
        let stored = self.read_stored(b)?;
        let t1 = Instant::now();
        let sum = crc32(&stored);
        let mut image = AlignedBytes::zeroed(rec.image_size as usize);
        if sum == rec.checksum {
            codec::decompress(self.view.codec(), &stored, &mut image)
                .map_err(|e| anyhow!("{name}: brick {b}: cannot decompress: {e}"))?;
        }
        let view = self.view.check_brick(b, sum, &image).map_err(|e| anyhow!("{name}: {e}"))?;
        // SAFETY: the view borrows `image`'s heap buffer, which does not move when the
        // `AlignedBytes` value moves and is never written again: `ResidentBrick` keeps it
        // beside the view, hands out only shared borrows, and drops it after the view.
        let view: SceneView<'static> = unsafe { std::mem::transmute::<SceneView<'_>, SceneView<'static>>(view) };
        let cost = LoadCost {
            bytes_read: rec.stored_size,
            bytes_decompressed: rec.image_size,
            read_seconds: (t1 - t0).as_secs_f64(),
            decompress_seconds: t1.elapsed().as_secs_f64(),
        };
        Ok((ResidentBrick { view, image }, cost))
    }
}

#[cfg(unix)]
fn read_at(file: &File, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(file, buf, offset)
}

#[cfg(not(unix))]
fn read_at(file: &File, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
    use std::io::{Read, Seek, SeekFrom};
    let mut f = file.try_clone()?;
    f.seek(SeekFrom::Start(offset))?;
    f.read_exact(buf)
}
