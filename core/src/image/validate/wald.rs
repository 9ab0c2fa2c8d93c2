//! WALD_TRIANGLES: Wald's projection records, absent or one per triangle, each finite
//! with a projection axis below 3.

use crate::image::error::SceneError;
use crate::image::header::SectionKind;
use crate::image::records::WaldTriangle;
use crate::image::sections::Sections;

/// The projection triangles of an image that holds `nt` triangles.
pub(in crate::image) fn wald<'a>(s: &Sections<'a>, nt: u32) -> Result<&'a [WaldTriangle], SceneError> {
    let section = SectionKind::WaldTriangles;
    let wald: &[WaldTriangle] = s.slice(section)?;
    if !wald.is_empty() && wald.len() as u32 != nt {
        return Err(SceneError::CountMismatch { section, expected: nt, found: wald.len() as u32 });
    }
    for (i, w) in wald.iter().enumerate() {
        let vals = [w.n_u, w.n_v, w.n_d, w.b_nu, w.b_nv, w.b_d, w.n_scale, w.c_nu, w.c_nv, w.c_d];
        if w.k > 3 || vals.iter().any(|v| !v.is_finite()) {
            return Err(SceneError::NonFinite { section, record: i as u32 });
        }
    }
    Ok(wald)
}
