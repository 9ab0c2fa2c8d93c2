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

/// An open bricked scene: the file, and its index mapped and validated.
pub struct BrickedScene {
    // Borrows `map`'s pages, which stay where they are until the map is dropped, after
    // it (fields drop in order).
    view: BrickedView<'static>,
    _map: Mmap,
    file: File,
    /// What the user called it.
    pub name: String,
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
    /// Bytes read from the file.
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
        Ok(BrickedScene { view, _map: map, file, name })
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
        let mut stored = vec![0u8; rec.stored_size as usize];
        read_at(&self.file, &mut stored, rec.offset).map_err(|e| anyhow!("{name}: brick {b}: cannot read: {e}"))?;
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
