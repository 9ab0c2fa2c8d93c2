//! The optional shading sections — SHADING_VERTICES, MATERIALS, TRIANGLE_MATERIALS,
//! TRIANGLE_OBJECTS, TRIANGLE_IDS, TEXTURES and TEXELS — absent, or matching the geometry: one record
//! per vertex or triangle, material and texture indices in range, texture chains inside
//! TEXELS.

use crate::image::error::SceneError;
use crate::image::header::SectionKind;
use crate::image::records::{MaterialRecord, ShadingVertex, TextureRecord};
use crate::image::sections::Sections;

use super::indices::indices_below;

/// The validated shading data.
pub(in crate::image) struct Shading<'a> {
    pub vertices: &'a [ShadingVertex],
    pub materials: &'a [MaterialRecord],
    pub tri_materials: &'a [u32],
    pub tri_objects: &'a [u32],
    pub tri_ids: &'a [u32],
    pub textures: &'a [TextureRecord],
    pub texels: &'a [u32],
}

/// An optional section with one record per vertex or triangle: absent, or all of them.
fn one_each(section: SectionKind, found: usize, expected: u32) -> Result<(), SceneError> {
    if found != 0 && found as u32 != expected {
        return Err(SceneError::CountMismatch { section, expected, found: found as u32 });
    }
    Ok(())
}

/// The shading data of an image with `nv` vertices and `nt` triangles.
pub(in crate::image) fn shading<'a>(s: &Sections<'a>, nv: u32, nt: u32) -> Result<Shading<'a>, SceneError> {
    use SectionKind as K;
    let vertices: &[ShadingVertex] = s.slice(K::ShadingVertices)?;
    one_each(K::ShadingVertices, vertices.len(), nv)?;
    let materials: &[MaterialRecord] = s.slice(K::Materials)?;
    let tri_materials: &[u32] = s.slice(K::TriangleMaterials)?;
    one_each(K::TriangleMaterials, tri_materials.len(), nt)?;
    let nm = materials.len() as u32;
    indices_below(K::TriangleMaterials, tri_materials.iter().copied(), nm, false)?;
    let tri_objects: &[u32] = s.slice(K::TriangleObjects)?;
    one_each(K::TriangleObjects, tri_objects.len(), nt)?;
    let tri_ids: &[u32] = s.slice(K::TriangleIds)?;
    one_each(K::TriangleIds, tri_ids.len(), nt)?;
    // Strictly increasing, so that a brick orders equal distances by local index exactly
    // as the flat image orders them by scene-wide index.
    // Pairs by zip, not `windows`: no index to check, so no panic path in the parse.
    if let Some(i) = tri_ids.iter().zip(tri_ids.iter().skip(1)).position(|(a, b)| b <= a) {
        return Err(SceneError::NotIncreasing { section: K::TriangleIds, record: i as u32 + 1 });
    }
    let textures: &[TextureRecord] = s.slice(K::Textures)?;
    let texels: &[u32] = s.slice(K::Texels)?;
    for (i, t) in textures.iter().enumerate() {
        let levels_ok = t.levels >= 1 && t.levels <= TextureRecord::full_chain(t.width, t.height);
        let end = (t.first as u64).saturating_add(TextureRecord::chain_texels(t.width, t.height, t.levels));
        if t.width == 0 || t.height == 0 || !levels_ok || end > texels.len() as u64 || t.wrap > TextureRecord::CLAMP {
            return Err(SceneError::BadTexture { texture: i as u32 });
        }
    }
    indices_below(K::Materials, materials.iter().map(|m| m.texture), textures.len() as u32, true)?;
    Ok(Shading { vertices, materials, tri_materials, tri_objects, tri_ids, textures, texels })
}
