//! Writes a bricked scene file: bricks are stored (compressed) into a payload file in
//! the order they finish, then the file is laid out — the index first, then the bricks
//! in id order — under a temporary name, synced, and renamed. The output is the same
//! bytes whatever the thread count (docs/scene-format.md, "Bricked scenes").

use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::Path;

use anyhow::{anyhow, bail, Result};
use raypipe_core::image::bricked::{
    BrickRecord, BrickedHeader, Codec, BRICKED_MAGIC, BRICKED_VERSION, INDEX_CHECKSUM_OFFSET,
};
use raypipe_core::image::{crc32, crc32_with_hole, BvhNode};

use super::brick_image::BuiltBrick;
use crate::output::Streamed;

/// A brick already stored in the payload file.
#[derive(Clone, Copy, Debug)]
struct Stored {
    at: u64,
    record: BrickRecord,
}

/// The stored bricks, before the file is laid out.
pub struct PayloadWriter {
    file: File,
    len: u64,
    bricks: Vec<Option<Stored>>,
}

/// The whole scene's part of the index.
pub struct IndexParts<'a> {
    /// Codec of every brick.
    pub codec: Codec,
    /// The scene's bounds.
    pub bounds: ([f32; 3], [f32; 3]),
    /// The top-level BVH, leaves naming list entries.
    pub nodes: &'a [BvhNode],
    /// The top-level list: brick ids.
    pub list: &'a [u32],
    /// The globals scene image (camera, lights, no triangles).
    pub globals: &'a [u8],
    /// The scene's triangles (each counted once, however many bricks share it).
    pub triangles: u64,
}

fn align64(x: u64) -> u64 {
    x.div_ceil(64) * 64
}

impl PayloadWriter {
    /// A payload for `bricks` bricks in `file` (a temporary file; the caller keeps it).
    pub fn new(file: File, bricks: usize) -> PayloadWriter {
        PayloadWriter { file, len: 0, bricks: vec![None; bricks] }
    }

    /// Makes room for `n` bricks in all.
    pub fn grow(&mut self, n: usize) {
        if self.bricks.len() < n {
            self.bricks.resize(n, None);
        }
    }

    /// Stores brick `id`: `stored` are its compressed bytes.
    pub fn add(&mut self, id: usize, stored: &[u8], built: &BuiltBrick) -> Result<()> {
        self.file.write_all(stored).map_err(|e| anyhow!("cannot write a brick to the spill folder: {e}"))?;
        let record = BrickRecord {
            offset: 0,
            stored_size: stored.len() as u64,
            image_size: built.image.len() as u64,
            checksum: crc32(stored),
            triangle_count: built.triangles,
            bounds_min: built.header_bounds.0,
            bounds_max: built.header_bounds.1,
            vertex_count: built.vertices,
            reserved: 0,
        };
        let slot = self.bricks.get_mut(id).ok_or_else(|| anyhow!("internal error: brick {id} out of range"))?;
        *slot = Some(Stored { at: self.len, record });
        self.len += stored.len() as u64;
        Ok(())
    }

    /// Lays out `out`: header, directory, nodes, list, globals, then the bricks in id
    /// order (each starting on a 64-byte boundary). Returns the file's size.
    pub fn finish(mut self, out: &Path, parts: &IndexParts<'_>, progress: &indicatif::ProgressBar) -> Result<u64> {
        let name = out.display();
        let mut bricks = Vec::with_capacity(self.bricks.len());
        for (i, b) in self.bricks.iter().enumerate() {
            bricks.push(b.ok_or_else(|| anyhow!("internal error: brick {i} was never stored"))?);
        }
        let nb = bricks.len() as u64;
        let nodes_at = 128 + 64 * nb;
        let list_at = nodes_at + 32 * parts.nodes.len() as u64;
        let globals_offset = align64(list_at + 4 * nb);
        let index_size = align64(globals_offset + parts.globals.len() as u64);
        let mut at = index_size;
        for b in &mut bricks {
            b.record.offset = at;
            at = align64(at + b.record.stored_size);
        }
        let total_size = bricks.last().map_or(index_size, |b| b.record.offset + b.record.stored_size);
        let mut header = BrickedHeader {
            magic: BRICKED_MAGIC,
            version: BRICKED_VERSION,
            flags: 0,
            brick_count: nb as u32,
            node_count: parts.nodes.len() as u32,
            index_size,
            total_size,
            triangle_count: parts.triangles,
            vertex_count: bricks.iter().map(|b| b.record.vertex_count as u64).sum(),
            globals_offset,
            globals_size: parts.globals.len() as u64,
            bounds_min: parts.bounds.0,
            bounds_max: parts.bounds.1,
            codec: parts.codec as u32,
            index_checksum: 0,
            max_brick_size: bricks.iter().map(|b| b.record.image_size).max().unwrap_or(0),
            reference_count: bricks.iter().map(|b| b.record.triangle_count as u64).sum(),
            reserved: [0; 2],
        };
        let mut index = Vec::with_capacity(index_size as usize);
        index.extend_from_slice(bytemuck::bytes_of(&header));
        for b in &bricks {
            index.extend_from_slice(bytemuck::bytes_of(&b.record));
        }
        index.extend_from_slice(bytemuck::cast_slice(parts.nodes));
        index.extend_from_slice(bytemuck::cast_slice(parts.list));
        index.resize(globals_offset as usize, 0);
        index.extend_from_slice(parts.globals);
        index.resize(index_size as usize, 0);
        header.index_checksum = crc32_with_hole(&index, INDEX_CHECKSUM_OFFSET);
        index[INDEX_CHECKSUM_OFFSET..INDEX_CHECKSUM_OFFSET + 4].copy_from_slice(&header.index_checksum.to_le_bytes());

        let mut file = Streamed::create(out)?;
        let w = file.file();
        let err = |e: std::io::Error| anyhow!("{name}: cannot write: {e}");
        w.write_all(&index).map_err(err)?;
        progress.set_length(nb);
        let mut written = index_size;
        let mut buf = Vec::new();
        for b in &bricks {
            w.write_all(&vec![0; (b.record.offset - written) as usize]).map_err(err)?;
            buf.resize(b.record.stored_size as usize, 0);
            self.file
                .seek(SeekFrom::Start(b.at))
                .and_then(|_| self.file.read_exact(&mut buf))
                .map_err(|e| anyhow!("cannot read a brick back from the spill folder: {e}"))?;
            w.write_all(&buf).map_err(err)?;
            written = b.record.offset + b.record.stored_size;
            progress.inc(1);
        }
        if written != total_size {
            bail!("internal error: wrote {written} bytes of {total_size}");
        }
        file.commit()?;
        Ok(total_size)
    }
}
