//! Lays out an instanced scene file from built bottom images, instances and a globals
//! image (docs/scene-format.md, "Instanced scenes"): the index, then each bottom image
//! on a 64-byte boundary. The inverse of `InstancedView::parse`.

use anyhow::{anyhow, bail, Result};
use raypipe_core::image::instanced::{
    BottomRecord, InstanceRecord, InstancedHeader, InstancedView, INSTANCED_CHECKSUM_OFFSET, INSTANCED_MAGIC,
    INSTANCED_VERSION,
};
use raypipe_core::image::{crc32_with_hole, BvhNode};
use raypipe_core::SceneView;

use crate::platform::aligned::AlignedBytes;

fn align64(x: u64) -> u64 {
    x.div_ceil(64) * 64
}

/// Writes the file's bytes. `bottoms` are validated scene images; `nodes` and `list` the
/// top-level tree over `instances`' boxes.
pub fn write_instanced(
    bottoms: &[&[u8]],
    instances: &[InstanceRecord],
    nodes: &[BvhNode],
    list: &[u32],
    globals: &[u8],
    bounds: ([f32; 3], [f32; 3]),
) -> Result<AlignedBytes> {
    let (ni, nb) = (instances.len() as u64, bottoms.len() as u64);
    let dir_at = 128 + 128 * ni;
    let nodes_at = dir_at + 64 * nb;
    let list_at = nodes_at + 32 * nodes.len() as u64;
    let globals_offset = align64(list_at + 4 * ni);
    let index_size = align64(globals_offset + globals.len() as u64);
    let mut records = Vec::with_capacity(bottoms.len());
    let mut at = index_size;
    for (b, bytes) in bottoms.iter().enumerate() {
        let view = SceneView::parse(bytes).map_err(|e| anyhow!("internal error: bottom image {b}: {e}"))?;
        let h = view.header();
        records.push(BottomRecord {
            offset: at,
            size: bytes.len() as u64,
            bounds_min: h.bounds_min,
            bounds_max: h.bounds_max,
            triangle_count: h.triangle_count,
            vertex_count: h.vertex_count,
            accel: h.accel,
            reserved: [0; 3],
        });
        at = align64(at + bytes.len() as u64);
    }
    let total_size = at;
    if usize::try_from(total_size).is_err() {
        bail!("the instanced scene would be {total_size} bytes, more than this machine addresses");
    }
    let count = |b: u32| records.get(b as usize).map_or(0, |r| r.triangle_count as u64);
    let mut header = InstancedHeader {
        magic: INSTANCED_MAGIC,
        version: INSTANCED_VERSION,
        flags: 0,
        instance_count: ni as u32,
        bottom_count: nb as u32,
        node_count: nodes.len() as u32,
        index_checksum: 0,
        index_size,
        total_size,
        globals_offset,
        globals_size: globals.len() as u64,
        bounds_min: bounds.0,
        bounds_max: bounds.1,
        triangle_count: instances.iter().map(|i| count(i.bottom)).sum(),
        stored_triangles: records.iter().map(|r| r.triangle_count as u64).sum(),
        reserved: [0; 6],
    };
    let mut out = AlignedBytes::zeroed(total_size as usize);
    let mut put = |at: u64, bytes: &[u8]| out[at as usize..at as usize + bytes.len()].copy_from_slice(bytes);
    put(0, bytemuck::bytes_of(&header));
    put(128, bytemuck::cast_slice(instances));
    put(dir_at, bytemuck::cast_slice(&records));
    put(nodes_at, bytemuck::cast_slice(nodes));
    put(list_at, bytemuck::cast_slice(list));
    put(globals_offset, globals);
    for (r, bytes) in records.iter().zip(bottoms) {
        put(r.offset, bytes);
    }
    header.index_checksum = crc32_with_hole(&out[..index_size as usize], INSTANCED_CHECKSUM_OFFSET);
    out[INSTANCED_CHECKSUM_OFFSET..INSTANCED_CHECKSUM_OFFSET + 4].copy_from_slice(&header.index_checksum.to_le_bytes());
    if let Err(e) = InstancedView::parse(&out) {
        bail!("internal error: wrote an invalid instanced scene: {e}");
    }
    Ok(out)
}
