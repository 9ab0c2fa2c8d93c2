//! A heap buffer aligned to 64 bytes, so a scene image read from disk can be parsed in
//! place (`SceneView::parse` requires an aligned start).

use bytemuck::{Pod, Zeroable};

#[repr(C, align(64))]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Line([u8; 64]);

/// Bytes starting on a 64-byte boundary.
#[derive(Clone, Default)]
pub struct AlignedBytes {
    lines: Vec<Line>,
    len: usize,
}

impl AlignedBytes {
    /// A copy of `bytes`, aligned.
    pub fn from_slice(bytes: &[u8]) -> AlignedBytes {
        let mut lines = vec![Line([0; 64]); bytes.len().div_ceil(64)];
        bytemuck::cast_slice_mut::<Line, u8>(&mut lines)[..bytes.len()].copy_from_slice(bytes);
        AlignedBytes { lines, len: bytes.len() }
    }

    /// `len` zero bytes, aligned.
    pub fn zeroed(len: usize) -> AlignedBytes {
        AlignedBytes { lines: vec![Line([0; 64]); len.div_ceil(64)], len }
    }

    /// Reads the first `len` bytes of `f` (a whole file, opened by the caller) into an
    /// aligned buffer.
    pub fn read_file(mut f: std::fs::File, len: u64) -> std::io::Result<AlignedBytes> {
        use std::io::Read;
        let len = usize::try_from(len).map_err(|_| std::io::Error::other("too large for this machine"))?;
        let mut lines = crate::platform::huge_pages::filled_vec(len.div_ceil(64), Line([0; 64]));
        let buf = &mut bytemuck::cast_slice_mut::<Line, u8>(&mut lines)[..len];
        f.read_exact(buf)?;
        Ok(AlignedBytes { lines, len })
    }
}

impl std::ops::Deref for AlignedBytes {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        &bytemuck::cast_slice::<Line, u8>(&self.lines)[..self.len]
    }
}

impl std::ops::DerefMut for AlignedBytes {
    fn deref_mut(&mut self) -> &mut [u8] {
        &mut bytemuck::cast_slice_mut::<Line, u8>(&mut self.lines)[..self.len]
    }
}
