//! PRIM_LISTS of the trees: every entry names a triangle.

use crate::image::error::SceneError;
use crate::image::header::SectionKind;
use crate::image::sections::Sections;

use super::indices::indices_below;

/// The trees' leaf lists, each entry below `nt`.
pub(in crate::image) fn prim_lists<'a>(s: &Sections<'a>, nt: u32) -> Result<&'a [u32], SceneError> {
    let prims: &[u32] = s.required(SectionKind::PrimLists)?;
    indices_below(SectionKind::PrimLists, prims.iter().copied(), nt, false)?;
    Ok(prims)
}
