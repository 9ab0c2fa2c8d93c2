//! A scene image's bytes: built in memory, or a file mapped in place (memmap2) and used
//! where it lies — no copy before the first ray (Wald & Slusallek 2001 §6.2 map their
//! scene file the same way).

use std::ops::Deref;
use std::sync::Arc;

use memmap2::Mmap;

use crate::platform::aligned::AlignedBytes;

/// An image's bytes, 64-byte aligned (a map starts on a page).
#[derive(Clone)]
pub enum ImageBytes {
    /// Built or read into memory.
    Owned(AlignedBytes),
    /// A file mapped read-only.
    Mapped(Arc<Mmap>),
}

impl Deref for ImageBytes {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        match self {
            ImageBytes::Owned(b) => b,
            ImageBytes::Mapped(m) => m,
        }
    }
}

impl From<AlignedBytes> for ImageBytes {
    fn from(b: AlignedBytes) -> ImageBytes {
        ImageBytes::Owned(b)
    }
}

impl ImageBytes {
    /// Maps the first `len` bytes of `file` read-only.
    pub fn map(file: &std::fs::File, len: u64) -> std::io::Result<ImageBytes> {
        let len = usize::try_from(len).map_err(|_| std::io::Error::other("too large for this machine"))?;
        // SAFETY: the map is read only. If another process truncates or rewrites the file
        // while it is mapped, reads may see the change or fault; raypipe never writes a
        // scene in place (its outputs are renamed over), so its own runs cannot.
        let map = unsafe { memmap2::MmapOptions::new().len(len).map(file) }?;
        Ok(ImageBytes::Mapped(Arc::new(map)))
    }
}

impl From<ImageBytes> for AlignedBytes {
    /// The bytes in memory: moved if they are, copied from the map if not.
    fn from(b: ImageBytes) -> AlignedBytes {
        match b {
            ImageBytes::Owned(b) => b,
            ImageBytes::Mapped(m) => AlignedBytes::from_slice(&m),
        }
    }
}
