//! TRI_BLOCKS: each leaf triangle's vertices copied four to a record, exactly.

use crate::image::error::SceneError;
use crate::image::header::SectionKind;
use crate::image::records::{Position, TriBlock4, TriangleRecord};

/// TRI_BLOCKS, when present, covers PRIM_LISTS in blocks of four and holds exactly
/// the vertices of the triangles listed there: a leaf tested from its blocks then
/// gives the bits it gives tested through the lists (lanes past the lists' end are
/// never tested).
pub(in crate::image) fn tri_blocks(
    blocks: &[TriBlock4],
    prims: &[u32],
    triangles: &[TriangleRecord],
    positions: &[Position],
) -> Result<(), SceneError> {
    use SectionKind as K;
    if blocks.is_empty() {
        return Ok(());
    }
    const LANES: usize = TriBlock4::LANES;
    let expected = prims.len().div_ceil(LANES) as u32;
    if blocks.len() as u32 != expected {
        return Err(SceneError::CountMismatch { section: K::TriBlocks, expected, found: blocks.len() as u32 });
    }
    for (e, &prim) in prims.iter().enumerate() {
        let (record, lane) = (e / LANES, e % LANES);
        let stale = SceneError::StaleCopy { section: K::TriBlocks, record: record as u32 };
        let block = blocks.get(record).ok_or(stale)?;
        // A list terminator (grid lists): no triangle to copy.
        let Some(tri) = triangles.get(prim as usize) else { continue };
        let same = (0..3).all(|i| {
            let p = positions.get(tri.0[i] as usize).map_or([f32::NAN; 3], |p| p.0);
            (0..3).all(|a| block.v[i][a][lane].to_bits() == p[a].to_bits())
        });
        if !same {
            return Err(stale);
        }
    }
    Ok(())
}
