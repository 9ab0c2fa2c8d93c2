//! Lays out a scene image: header, section table, 64-byte-aligned sections, checksum.
//! The inverse of `raypipe_core::SceneView::parse`; docs/scene-format.md describes the bytes.

use anyhow::{bail, Result};
use bytemuck::Pod;
use raypipe_core::image::{
    crc32, AccelKind, CameraRecord, Header, LightAlias, LightRecord, Position, SectionEntry, SectionKind,
    TextureRecord, TriangleRecord, FORMAT_VERSION, MAGIC, SECTION_ALIGN,
};

use raypipe_core::image::{TriBlock4, WaldTriangle, WideNode};
use raypipe_core::Vec3;

use crate::build::bvh::BuiltBvh;
use crate::build::grid::BuiltGrid;
use crate::build::kdtree::BuiltKd;
use crate::build::wide_bvh::BuiltWideBvh;
use crate::input::mesh::Mesh;
use crate::platform::aligned::AlignedBytes;

/// Sections collected before layout.
#[derive(Default)]
pub struct ImageWriter {
    accel: u32,
    bounds: ([f32; 3], [f32; 3]),
    counts: (u32, u32),
    sections: Vec<(SectionKind, Vec<u8>, u32)>,
    /// Header flags.
    pub flags: u32,
}

/// The vertex indices written for triangle `t`. A zero-area triangle is written with
/// three equal indices: every intersection kernel then computes exactly zero area and
/// never reports a hit, whereas three distinct collinear vertices can give a "hit" made
/// of rounding noise, at a distance no structure can be conservative about.
fn stored(mesh: &Mesh, t: [u32; 3]) -> [u32; 3] {
    if mesh.is_degenerate(t) {
        [t[0]; 3]
    } else {
        t
    }
}

/// The header's scene bounds: the vertices' box, grown for a brick by the whole
/// scene's margin (the kd-tree's root box is the header's box, and must stay as
/// conservative as the flat image's).
fn header_bounds(mesh: &Mesh) -> ([f32; 3], [f32; 3]) {
    let (lo, hi) = mesh.bounds();
    if mesh.margin_bounds.is_none() || mesh.positions.is_empty() {
        return (lo, hi);
    }
    crate::build::bvh::grow_by_margin((lo, hi), crate::build::bvh::box_margin(mesh))
}

impl ImageWriter {
    /// The header's scene bounds (for an image with no vertices, whose own are empty:
    /// a bricked scene's globals image carries the scene's).
    pub fn set_bounds(&mut self, lo: [f32; 3], hi: [f32; 3]) -> &mut Self {
        self.bounds = (lo, hi);
        self
    }

    /// Adds the whole scene's bounds (a brick's SCENE_BOUNDS).
    pub fn scene_bounds(&mut self, lo: [f32; 3], hi: [f32; 3]) -> &mut Self {
        self.add(SectionKind::SceneBounds, &[[lo, hi]]);
        self
    }

    /// Adds the scene-wide id of each triangle (a brick's TRIANGLE_IDS).
    pub fn triangle_ids(&mut self, ids: &[u32]) -> &mut Self {
        self.add(SectionKind::TriangleIds, ids);
        self
    }

    /// Starts an image for `mesh`: geometry and shading sections.
    pub fn new(mesh: &Mesh) -> ImageWriter {
        let mut w = ImageWriter {
            accel: AccelKind::None as u32,
            bounds: header_bounds(mesh),
            counts: (mesh.triangles.len() as u32, mesh.positions.len() as u32),
            sections: Vec::new(),
            flags: 0,
        };
        let positions: Vec<Position> = mesh.positions.iter().map(|&p| Position(p)).collect();
        let triangles: Vec<TriangleRecord> = mesh.triangles.iter().map(|&t| TriangleRecord(stored(mesh, t))).collect();
        w.add(SectionKind::Positions, &positions);
        w.add(SectionKind::Triangles, &triangles);
        if !mesh.shading.is_empty() {
            w.add(SectionKind::ShadingVertices, &mesh.shading);
        }
        if !mesh.materials.is_empty() {
            w.add(SectionKind::Materials, &mesh.materials);
            w.add(SectionKind::TriangleMaterials, &mesh.tri_materials);
        }
        // One object needs no table.
        if mesh.objects.iter().any(|&o| o != 0) {
            w.add(SectionKind::TriangleObjects, &mesh.objects);
        }
        if !mesh.lights.is_empty() {
            w.add(SectionKind::Lights, &mesh.lights);
            let alias = crate::build::light_distribution::mesh_alias_table(mesh);
            if !alias.is_empty() {
                w.add(SectionKind::LightAlias, &alias);
            }
        }
        if !mesh.textures.is_empty() {
            let mut records = Vec::new();
            let mut texels: Vec<u32> = Vec::new();
            for t in &mesh.textures {
                records.push(TextureRecord {
                    width: t.width,
                    height: t.height,
                    first: texels.len() as u32,
                    wrap: t.wrap,
                    levels: TextureRecord::full_chain(t.width, t.height),
                    _pad: [0; 3],
                });
                texels.extend(crate::build::mipmap::chain(t));
            }
            w.add(SectionKind::Textures, &records);
            w.add(SectionKind::Texels, &texels);
        }
        w
    }

    fn add<T: Pod>(&mut self, kind: SectionKind, records: &[T]) {
        debug_assert_eq!(std::mem::size_of::<T>() as u32, kind.record_size());
        self.sections.push((kind, bytemuck::cast_slice(records).to_vec(), records.len() as u32));
    }

    /// Adds Wald's precomputed projection triangles, one per triangle.
    pub fn wald_triangles(&mut self, mesh: &Mesh) -> &mut Self {
        let recs: Vec<WaldTriangle> = mesh
            .triangles
            .iter()
            .map(|t| WaldTriangle::from_vertices(&t.map(|i| Vec3::from(mesh.positions[i as usize]))))
            .collect();
        self.add(SectionKind::WaldTriangles, &recs);
        self
    }

    /// Adds the uniform grid.
    pub fn grid(&mut self, grid: &BuiltGrid) -> &mut Self {
        self.accel = AccelKind::Grid as u32;
        self.add(SectionKind::Grid, &[grid.record]);
        self.add(SectionKind::GridCells, &grid.cells);
        self.add(SectionKind::PrimLists, &grid.lists);
        self
    }

    /// Adds a BVH.
    pub fn bvh(&mut self, bvh: &BuiltBvh) -> &mut Self {
        self.accel = AccelKind::Bvh as u32;
        self.add(SectionKind::BvhNodes, &bvh.nodes);
        self.add(SectionKind::PrimLists, &bvh.prims);
        self
    }

    /// Adds a wide (4- or 8-wide) BVH, in its width's section.
    pub fn wide_bvh<N: WideNode>(&mut self, bvh: &BuiltWideBvh<N>) -> &mut Self {
        self.accel = N::ACCEL as u32;
        self.add(N::SECTION, &bvh.nodes);
        self.add(SectionKind::PrimLists, &bvh.prims);
        self
    }

    /// Adds copies of the vertices of the triangles in `prims` (the trees' PRIM_LISTS) in
    /// blocks of four SIMD lanes; lanes past the end repeat the last triangle.
    pub fn tri_blocks(&mut self, mesh: &Mesh, prims: &[u32]) -> &mut Self {
        let blocks: Vec<TriBlock4> = prims
            .chunks(TriBlock4::LANES)
            .map(|chunk| {
                let mut b = TriBlock4 { v: [[[0.0; 4]; 3]; 3] };
                for lane in 0..TriBlock4::LANES {
                    let prim = chunk[lane.min(chunk.len() - 1)];
                    let tri = stored(mesh, mesh.triangles[prim as usize]);
                    for (i, &vi) in tri.iter().enumerate() {
                        for a in 0..3 {
                            b.v[i][a][lane] = mesh.positions[vi as usize][a];
                        }
                    }
                }
                b
            })
            .collect();
        self.add(SectionKind::TriBlocks, &blocks);
        self
    }

    /// Adds a kd-tree.
    pub fn kdtree(&mut self, kd: &BuiltKd) -> &mut Self {
        self.accel = AccelKind::KdTree as u32;
        self.add(SectionKind::KdNodes, &kd.nodes);
        self.add(SectionKind::PrimLists, &kd.prims);
        self
    }

    /// Adds the default camera.
    pub fn camera(&mut self, camera: &CameraRecord) -> &mut Self {
        self.add(SectionKind::Camera, &[*camera]);
        self
    }

    /// A copy of the valid image `image` with LIGHTS and LIGHT_ALIAS replaced and the
    /// header flags `flags`: every other section's bytes as they are, laid out anew.
    pub fn replace_lights(
        image: &[u8],
        lights: &[LightRecord],
        alias: &[LightAlias],
        flags: u32,
    ) -> Result<AlignedBytes> {
        let header: Header = bytemuck::pod_read_unaligned(&image[..64]);
        let mut w = ImageWriter {
            accel: header.accel,
            bounds: (header.bounds_min, header.bounds_max),
            counts: (header.triangle_count, header.vertex_count),
            sections: Vec::new(),
            flags,
        };
        for k in 0..header.section_count as usize {
            let e: SectionEntry = bytemuck::pod_read_unaligned(&image[64 + 16 * k..80 + 16 * k]);
            let Some(kind) = SectionKind::from_u32(e.kind) else { bail!("unknown section kind {}", e.kind) };
            if matches!(kind, SectionKind::Lights | SectionKind::LightAlias) {
                continue;
            }
            let bytes = image.get(e.offset as usize..e.offset as usize + e.size as usize);
            let Some(bytes) = bytes else { bail!("section {} lies outside the image", kind.name()) };
            w.sections.push((kind, bytes.to_vec(), e.count));
        }
        if !lights.is_empty() {
            w.add(SectionKind::Lights, lights);
        }
        if !alias.is_empty() {
            w.add(SectionKind::LightAlias, alias);
        }
        w.finish()
    }

    /// Lays the sections out and computes the checksum.
    pub fn finish(&self) -> Result<AlignedBytes> {
        let align = SECTION_ALIGN as u64;
        let table_end = 64 + 16 * self.sections.len() as u64;
        let mut offset = table_end.div_ceil(align) * align;
        let mut table = Vec::new();
        for (kind, bytes, count) in &self.sections {
            table.push(SectionEntry {
                kind: *kind as u32,
                offset: offset as u32,
                size: bytes.len() as u32,
                count: *count,
            });
            offset = (offset + bytes.len() as u64).div_ceil(align) * align;
            if offset > u32::MAX as u64 {
                bail!(
                    "the scene image would pass 4 GiB, the most a flat image's 32-bit offsets address; build a bricked scene (--bricks), whose offsets are 64-bit"
                );
            }
        }
        let total = offset as usize;
        let header = Header {
            magic: MAGIC,
            version: FORMAT_VERSION,
            flags: self.flags,
            accel: self.accel,
            section_count: self.sections.len() as u32,
            total_size: total as u32,
            checksum: 0,
            bounds_min: self.bounds.0,
            bounds_max: self.bounds.1,
            triangle_count: self.counts.0,
            vertex_count: self.counts.1,
        };
        let mut out = AlignedBytes::from_slice(&vec![0u8; total]);
        out[..64].copy_from_slice(bytemuck::bytes_of(&header));
        out[64..table_end as usize].copy_from_slice(bytemuck::cast_slice(&table));
        for ((_, bytes, _), entry) in self.sections.iter().zip(&table) {
            let o = entry.offset as usize;
            out[o..o + bytes.len()].copy_from_slice(bytes);
        }
        let checksum = crc32(&out);
        out[28..32].copy_from_slice(&checksum.to_le_bytes());
        Ok(out)
    }
}
