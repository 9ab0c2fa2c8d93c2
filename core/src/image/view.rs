//! [`SceneView`]: the validated, zero-copy view of a scene image.

use glam::Vec3;

use super::crc32::crc32_with_hole;
use super::error::SceneError;
use super::header::{
    AccelKind, Header, SectionKind, CHECKSUM_OFFSET, FLAG_DEFAULT_LIGHT, FORMAT_VERSION, KNOWN_FLAGS, MAGIC,
};
use super::limits::IMAGE_ALIGN;
use super::margin::grow_bounds;
use super::records::{
    CameraRecord, LightAlias, LightRecord, MaterialRecord, Position, ShadingVertex, TextureRecord, TriBlock4,
    TriangleRecord, WaldTriangle, NULL_INDEX,
};
use super::sections::Sections;
use super::structure_views::{Bvh4View, Bvh8View, BvhView, GridView, KdTreeView};
use super::validate;
use crate::probe::{DataClass, MemoryProbe};

mod levels;
mod update;
pub use levels::{GridLevel, MAX_LEVELS};
pub use update::FrameGeometry;

/// A validated scene image, borrowed in place. Cheap to copy.
#[derive(Clone, Copy, Debug)]
pub struct SceneView<'a> {
    header: &'a Header,
    bytes: &'a [u8],
    positions: &'a [Position],
    triangles: &'a [TriangleRecord],
    grid: Option<GridView<'a>>,
    // The levels of a hierarchical grid with wrap-around (an animated mesh's frame only;
    // validated by `with_levels`, kept as the caller's slice so the view stays small).
    levels: &'a [GridLevel<'a>],
    bvh: Option<BvhView<'a>>,
    bvh4: Option<Bvh4View<'a>>,
    bvh8: Option<Bvh8View<'a>>,
    kd: Option<KdTreeView<'a>>,
    // Every tree keeps its leaves' triangle ids here (validated with the tree).
    prim_lists: &'a [u32],
    shading: &'a [ShadingVertex],
    wald: &'a [WaldTriangle],
    tri_blocks: &'a [TriBlock4],
    tri_materials: &'a [u32],
    materials: &'a [MaterialRecord],
    tri_objects: &'a [u32],
    tri_ids: &'a [u32],
    scene_bounds: Option<(Vec3, Vec3)>,
    textures: &'a [TextureRecord],
    texels: &'a [u32],
    lights: &'a [LightRecord],
    area_lights: u32,
    light_alias: &'a [LightAlias],
    camera: Option<&'a CameraRecord>,
    positions_addr: u32,
    triangles_addr: u32,
    shading_addr: u32,
    tri_materials_addr: u32,
    materials_addr: u32,
    texels_addr: u32,
    lights_addr: u32,
    light_alias_addr: u32,
    prim_lists_addr: u32,
    wald_addr: u32,
    tri_blocks_addr: u32,
}

impl<'a> SceneView<'a> {
    /// Validates `bytes` once — magic, version, checksum, section bounds and alignment,
    /// counts, every offset and index — and returns a view that kernels can use without
    /// any further check. `bytes` may be longer than the image (e.g. a flash partition).
    pub fn parse(bytes: &'a [u8]) -> Result<SceneView<'a>, SceneError> {
        let head = bytes.get(..64).ok_or(SceneError::Truncated { needed: 64, len: bytes.len() })?;
        let misalign = bytes.as_ptr() as usize % IMAGE_ALIGN;
        if misalign != 0 {
            return Err(SceneError::Misaligned { offset: misalign, required: IMAGE_ALIGN });
        }
        let header: &Header = bytemuck::try_from_bytes(head)
            .map_err(|_| SceneError::Misaligned { offset: misalign, required: IMAGE_ALIGN })?;
        if header.magic != MAGIC {
            return Err(SceneError::BadMagic);
        }
        if header.version != FORMAT_VERSION {
            return Err(SceneError::UnsupportedVersion { found: header.version, supported: FORMAT_VERSION });
        }
        let total = header.total_size as usize;
        if bytes.len() < total || total < 64 {
            return Err(SceneError::Truncated { needed: total.max(64), len: bytes.len() });
        }
        let bytes = &bytes[..total];
        let computed = crc32_with_hole(bytes, CHECKSUM_OFFSET);
        if computed != header.checksum {
            return Err(SceneError::ChecksumMismatch { stored: header.checksum, computed });
        }
        if header.flags & !KNOWN_FLAGS != 0 {
            return Err(SceneError::UnknownFlags(header.flags & !KNOWN_FLAGS));
        }
        let accel = AccelKind::from_u32(header.accel).ok_or(SceneError::UnknownAccel(header.accel))?;

        let sections = Sections::read(header, bytes)?;
        Self::from_sections(header, bytes, &sections, accel)
    }

    /// Validates every section (one validator each, in `validate/`) and keeps what they
    /// return.
    fn from_sections(
        header: &'a Header,
        bytes: &'a [u8],
        s: &Sections<'a>,
        accel: AccelKind,
    ) -> Result<SceneView<'a>, SceneError> {
        use SectionKind as K;
        let geometry = validate::geometry::geometry(header, s)?;
        let (positions, triangles) = (geometry.positions, geometry.triangles);
        let (bmin, bmax) = (geometry.bounds_min, geometry.bounds_max);
        let (nv, nt) = (positions.len() as u32, triangles.len() as u32);

        let (mut grid, mut bvh, mut kd, mut bvh4, mut bvh8) = (None, None, None, None, None);
        match accel {
            AccelKind::None => {}
            AccelKind::Grid => grid = Some(validate::grid::grid(s, nt, bmin, bmax)?),
            AccelKind::Bvh => bvh = Some(validate::bvh::bvh(s, nt)?),
            AccelKind::KdTree => kd = Some(validate::kdtree::kdtree(s, nt, bmin, bmax)?),
            AccelKind::Bvh4 => bvh4 = Some(validate::wide_bvh::wide_bvh(s, nt)?),
            AccelKind::Bvh8 => bvh8 = Some(validate::wide_bvh::wide_bvh(s, nt)?),
        }

        let shading = validate::shading::shading(s, nv, nt)?;
        let wald = validate::wald::wald(s, nt)?;
        let prim_lists: &[u32] = s.slice(K::PrimLists)?;
        let tri_blocks: &[TriBlock4] = s.slice(K::TriBlocks)?;
        validate::tri_blocks::tri_blocks(tri_blocks, prim_lists, triangles, positions)?;
        let lights = validate::lights::lights(s, nt)?;
        let cameras: &[CameraRecord] = s.slice(K::Camera)?;
        if cameras.len() > 1 {
            return Err(SceneError::CountMismatch { section: K::Camera, expected: 1, found: cameras.len() as u32 });
        }

        Ok(SceneView {
            header,
            bytes,
            positions,
            triangles,
            grid,
            levels: &[],
            bvh,
            bvh4,
            bvh8,
            kd,
            prim_lists,
            shading: shading.vertices,
            wald,
            tri_blocks,
            tri_materials: shading.tri_materials,
            tri_objects: shading.tri_objects,
            tri_ids: shading.tri_ids,
            scene_bounds: validate::geometry::scene_bounds(s)?,
            materials: shading.materials,
            textures: shading.textures,
            texels: shading.texels,
            lights: lights.lights,
            area_lights: lights.area_lights,
            light_alias: lights.alias,
            camera: cameras.first(),
            positions_addr: s.addr(K::Positions),
            triangles_addr: s.addr(K::Triangles),
            shading_addr: s.addr(K::ShadingVertices),
            tri_materials_addr: s.addr(K::TriangleMaterials),
            materials_addr: s.addr(K::Materials),
            texels_addr: s.addr(K::Texels),
            lights_addr: s.addr(K::Lights),
            light_alias_addr: s.addr(K::LightAlias),
            wald_addr: s.addr(K::WaldTriangles),
            tri_blocks_addr: s.addr(K::TriBlocks),
            prim_lists_addr: s.addr(K::PrimLists),
        })
    }

    /// Entries of PRIM_LISTS, the list the trees' leaves index (0 without a tree). A ray
    /// through any tree tests at most this many triangles (the parse bounds the leaves).
    pub fn prim_list_len(&self) -> usize {
        self.prim_lists.len()
    }

    /// The 8-wide BVH, if the image holds one.
    pub fn bvh8(&self) -> Option<&Bvh8View<'a>> {
        self.bvh8.as_ref()
    }

    /// The 4-wide BVH, if the image holds one.
    pub fn bvh4(&self) -> Option<&Bvh4View<'a>> {
        self.bvh4.as_ref()
    }

    /// The BVH, if the image holds one.
    pub fn bvh(&self) -> Option<&BvhView<'a>> {
        self.bvh.as_ref()
    }

    /// The kd-tree, if the image holds one.
    pub fn kdtree(&self) -> Option<&KdTreeView<'a>> {
        self.kd.as_ref()
    }

    /// The header.
    pub fn header(&self) -> &'a Header {
        self.header
    }

    /// The image's bytes (exactly `total_size` of them).
    pub fn bytes(&self) -> &'a [u8] {
        self.bytes
    }

    /// Which acceleration structure the image holds.
    pub fn accel(&self) -> AccelKind {
        AccelKind::from_u32(self.header.accel).unwrap_or(AccelKind::None)
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> u32 {
        self.triangles.len() as u32
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> u32 {
        self.positions.len() as u32
    }

    /// Scene bounds from the header.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (Vec3::from(self.header.bounds_min), Vec3::from(self.header.bounds_max))
    }

    /// The bounds of the whole scene: a brick's SCENE_BOUNDS, else [`SceneView::bounds`].
    /// Shading offsets new rays off a surface in proportion to this extent, so a brick
    /// shades exactly as the flat image does.
    pub fn scene_bounds(&self) -> (Vec3, Vec3) {
        self.scene_bounds.unwrap_or_else(|| self.bounds())
    }

    /// The scene bounds grown by the builders' margin: the box for Purcell's early
    /// bounding-box test, which must never end a ray that a kernel would report a hit for.
    pub fn test_bounds(&self) -> (Vec3, Vec3) {
        let (lo, hi) = self.bounds();
        grow_bounds(lo, hi)
    }

    /// The uniform grid, if the image holds one.
    pub fn grid(&self) -> Option<&GridView<'a>> {
        self.grid.as_ref()
    }

    /// Level `k` of a hierarchical grid (finest first), if the view has one
    /// ([`SceneView::with_levels`]).
    #[inline]
    pub fn level(&self, k: usize) -> Option<GridView<'a>> {
        let level = self.levels.get(k)?;
        // Each level's reads are labelled after the image and the levels before it.
        let before: u64 = self.levels[..k].iter().map(|l| 4 * (l.cells.len() + l.lists.len()) as u64).sum();
        Some(levels::level_view(level, (self.bytes.len() as u64).wrapping_add(before) as u32))
    }

    /// Bytes of the hierarchical grid's cells and lists, which lie beside the image
    /// (their reads are labelled from the image's end on).
    pub fn level_bytes(&self) -> u64 {
        self.levels.iter().map(|l| 4 * (l.cells.len() + l.lists.len()) as u64).sum()
    }

    /// The default camera record, if the image holds one.
    pub fn camera(&self) -> Option<&'a CameraRecord> {
        self.camera
    }

    /// Number of lights.
    pub fn light_count(&self) -> u32 {
        self.lights.len() as u32
    }

    /// Number of area lights (emissive triangles), counted at parse. They are the last
    /// lights: area light `k` is light `shading_light_count() + k`.
    pub fn area_light_count(&self) -> u32 {
        self.area_lights
    }

    /// Number of lights before the area lights: all that ray casting, the shadow caster
    /// and Whitted's shader read (their cost does not grow with the emitters).
    pub fn shading_light_count(&self) -> u32 {
        self.lights.len() as u32 - self.area_lights
    }

    /// Picks an area light with probability proportional to its power from two uniform
    /// numbers in `[0, 1)` (one read of the alias table; uniformly without one): the
    /// area-light number and the probability it had. `None` without area lights.
    #[inline]
    pub fn pick_area_light<P: MemoryProbe>(&self, u: f32, v: f32, probe: &mut P) -> Option<(u32, f32)> {
        let n = self.area_lights;
        if n == 0 {
            return None;
        }
        let i = ((u * n as f32) as u32).min(n - 1);
        let Some(entry) = self.light_alias.get(i as usize) else {
            return Some((i, 1.0 / n as f32));
        };
        probe.read(DataClass::Shading, self.light_alias_addr.wrapping_add(i.wrapping_mul(16)), 16);
        Some(if v < entry.keep { (i, entry.pdf) } else { (entry.alias, entry.alias_pdf) })
    }

    /// The probability that [`SceneView::pick_area_light`] picks area light `k` (one read
    /// of the alias table), or `None` when the image has no alias table and the pick is
    /// uniform.
    #[inline]
    pub fn area_light_probability<P: MemoryProbe>(&self, k: u32, probe: &mut P) -> Option<f32> {
        let entry = self.light_alias.get(k as usize)?;
        probe.read(DataClass::Shading, self.light_alias_addr.wrapping_add(k.wrapping_mul(16)), 16);
        Some(entry.pdf)
    }

    /// Reads light `index` (a default black ambient light if out of range).
    #[inline]
    pub fn light<P: MemoryProbe>(&self, index: u32, probe: &mut P) -> LightRecord {
        probe.read(DataClass::Shading, self.lights_addr.wrapping_add(index.wrapping_mul(32)), 32);
        self.lights.get(index as usize).copied().unwrap_or(LightRecord {
            position: [0.0; 3],
            kind: LightRecord::AMBIENT,
            color: [0.0; 3],
            triangle: 0,
        })
    }

    /// The materials.
    pub fn materials(&self) -> &'a [MaterialRecord] {
        self.materials
    }

    /// True when the image has shading vertices (normals, texture coordinates, colours).
    pub fn has_shading_vertices(&self) -> bool {
        !self.shading.is_empty()
    }

    /// True when the image's point light is raypipe's default, placed for the image's
    /// camera ([`FLAG_DEFAULT_LIGHT`]).
    pub fn has_default_light(&self) -> bool {
        self.header.flags & FLAG_DEFAULT_LIGHT != 0
    }

    /// Number of textures.
    pub fn texture_count(&self) -> u32 {
        self.textures.len() as u32
    }

    /// Texture `index` (validated: its texels lie inside TEXELS).
    pub fn texture(&self, index: u32) -> Option<TextureRecord> {
        self.textures.get(index as usize).copied()
    }

    /// Texel `(x, y)` of texture `t` as RGBA bytes (sRGB), `x`, `y` already wrapped.
    #[inline]
    pub fn texel<P: MemoryProbe>(&self, t: &TextureRecord, x: u32, y: u32, probe: &mut P) -> [u8; 4] {
        let i = t.first.wrapping_add(y.wrapping_mul(t.width)).wrapping_add(x);
        probe.read(DataClass::Shading, self.texels_addr.wrapping_add(i.wrapping_mul(4)), 4);
        self.texels.get(i as usize).copied().unwrap_or(0).to_le_bytes()
    }

    /// Reads PRIM_LISTS entry `pos` of a tree leaf (kd-tree, BVH, 4- or 8-wide BVH: all
    /// keep their leaves' triangle ids in that one section).
    #[inline]
    pub fn leaf_prim<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        probe.read(DataClass::PrimLists, self.prim_lists_addr.wrapping_add(pos.wrapping_mul(4)), 4);
        self.prim_lists.get(pos as usize).copied().unwrap_or(0)
    }

    /// Reads triangle `prim` and its three vertex positions (intersection data).
    #[inline]
    pub fn triangle<P: MemoryProbe>(&self, prim: u32, probe: &mut P) -> [Vec3; 3] {
        probe.read(DataClass::Triangles, self.triangles_addr.wrapping_add(prim.wrapping_mul(12)), 12);
        let idx = self.triangles.get(prim as usize).map_or([0; 3], |t| t.0);
        // The vertices' addresses come from the record just read.
        probe.dependent();
        idx.map(|i| self.position(i, probe))
    }

    #[inline]
    fn position<P: MemoryProbe>(&self, index: u32, probe: &mut P) -> Vec3 {
        probe.read(DataClass::Triangles, self.positions_addr.wrapping_add(index.wrapping_mul(12)), 12);
        self.positions.get(index as usize).map_or(Vec3::ZERO, |p| Vec3::from(p.0))
    }

    /// Reads triangle `prim`'s precomputed Wald record, if the image has that layout.
    #[inline]
    pub fn wald_triangle<P: MemoryProbe>(&self, prim: u32, probe: &mut P) -> Option<WaldTriangle> {
        if self.wald.is_empty() {
            return None;
        }
        probe.read(DataClass::Triangles, self.wald_addr.wrapping_add(prim.wrapping_mul(48)), 48);
        self.wald.get(prim as usize).copied()
    }

    /// Reads block `block` of TRI_BLOCKS (the triangles of PRIM_LISTS entries
    /// `4·block` to `4·block + 3`), if the image has that section and the block.
    #[inline(always)]
    pub fn tri_block<P: MemoryProbe>(&self, block: u32, probe: &mut P) -> Option<&'a TriBlock4> {
        const SIZE: u32 = core::mem::size_of::<TriBlock4>() as u32;
        probe.read(DataClass::Triangles, self.tri_blocks_addr.wrapping_add(block.wrapping_mul(SIZE)), SIZE);
        self.tri_blocks.get(block as usize)
    }

    /// True if the image stores its leaf triangles in blocks of four (TRI_BLOCKS).
    pub fn has_tri_blocks(&self) -> bool {
        !self.tri_blocks.is_empty()
    }

    /// True if the image stores Wald's precomputed triangles.
    pub fn has_wald_triangles(&self) -> bool {
        !self.wald.is_empty()
    }

    /// The vertex indices of triangle `prim` (not probed: shading re-reads them from its
    /// own copy of the index data in hardware; here they come with the shading fetch).
    #[inline]
    pub fn triangle_indices(&self, prim: u32) -> [u32; 3] {
        self.triangles.get(prim as usize).map_or([0; 3], |t| t.0)
    }

    /// Reads the shading data of vertex `index`, if the image has shading data.
    #[inline]
    pub fn shading_vertex<P: MemoryProbe>(&self, index: u32, probe: &mut P) -> Option<ShadingVertex> {
        if self.shading.is_empty() {
            return None;
        }
        probe.read(DataClass::Shading, self.shading_addr.wrapping_add(index.wrapping_mul(32)), 32);
        self.shading.get(index as usize).copied()
    }

    /// The material number of triangle `prim` (`None` without materials).
    #[inline]
    pub fn material_id<P: MemoryProbe>(&self, prim: u32, probe: &mut P) -> Option<u32> {
        probe.read(DataClass::Shading, self.tri_materials_addr.wrapping_add(prim.wrapping_mul(4)), 4);
        self.tri_materials.get(prim as usize).copied()
    }

    /// The object triangle `prim` came from (0 without TRIANGLE_OBJECTS).
    pub fn object_of(&self, prim: u32) -> u32 {
        self.tri_objects.get(prim as usize).copied().unwrap_or(0)
    }

    /// The scene-wide id of triangle `prim`: its TRIANGLE_IDS entry in a brick of a
    /// bricked scene, `prim` itself in a flat image.
    #[inline]
    pub fn scene_triangle_id(&self, prim: u32) -> u32 {
        if self.tri_ids.is_empty() {
            return prim;
        }
        self.tri_ids.get(prim as usize).copied().unwrap_or(prim)
    }

    /// True if this image is a brick of a bricked scene (it carries TRIANGLE_IDS).
    pub fn is_brick(&self) -> bool {
        !self.tri_ids.is_empty()
    }

    /// The number of objects: one more than the largest object id (1 without
    /// TRIANGLE_OBJECTS: the whole scene is object 0).
    pub fn object_count(&self) -> u32 {
        self.tri_objects.iter().max().map_or(1, |&m| m.saturating_add(1))
    }

    /// Reads the material of triangle `prim` ([`MaterialRecord::DEFAULT`] if none).
    #[inline]
    pub fn material_of<P: MemoryProbe>(&self, prim: u32, probe: &mut P) -> MaterialRecord {
        if self.tri_materials.is_empty() {
            return MaterialRecord::DEFAULT;
        }
        probe.read(DataClass::Shading, self.tri_materials_addr.wrapping_add(prim.wrapping_mul(4)), 4);
        let id = self.tri_materials.get(prim as usize).copied().unwrap_or(NULL_INDEX);
        probe.read(DataClass::Shading, self.materials_addr.wrapping_add(id.wrapping_mul(64)), 64);
        self.materials.get(id as usize).copied().unwrap_or(MaterialRecord::DEFAULT)
    }
}
