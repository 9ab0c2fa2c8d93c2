//! POSITIONS and TRIANGLES: the counts the header declares, finite vertices inside the
//! declared bounds, and vertex indices in range.

use glam::Vec3;

use crate::image::error::SceneError;
use crate::image::header::{Header, SectionKind};
use crate::image::records::{Position, TriangleRecord};
use crate::image::sections::{finite3, Sections};

/// The validated geometry and the scene bounds it lies in.
pub(in crate::image) struct Geometry<'a> {
    pub positions: &'a [Position],
    pub triangles: &'a [TriangleRecord],
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
}

/// The image's vertices and triangles, checked against its header.
pub(in crate::image) fn geometry<'a>(header: &Header, s: &Sections<'a>) -> Result<Geometry<'a>, SceneError> {
    use SectionKind as K;
    let positions: &[Position] = s.required(K::Positions)?;
    let triangles: &[TriangleRecord] = s.required(K::Triangles)?;
    let nv = positions.len() as u32;
    let nt = triangles.len() as u32;
    if header.vertex_count != nv {
        return Err(SceneError::CountMismatch { section: K::Positions, expected: header.vertex_count, found: nv });
    }
    if header.triangle_count != nt {
        return Err(SceneError::CountMismatch { section: K::Triangles, expected: header.triangle_count, found: nt });
    }
    if !finite3(header.bounds_min) || !finite3(header.bounds_max) {
        return Err(SceneError::NonFinite { section: K::Positions, record: u32::MAX });
    }
    let (bmin, bmax) = (Vec3::from(header.bounds_min), Vec3::from(header.bounds_max));
    if nv > 0 && !bmin.cmple(bmax).all() {
        return Err(SceneError::OutOfBounds { section: K::Positions, record: u32::MAX });
    }
    for (i, p) in positions.iter().enumerate() {
        if !finite3(p.0) {
            return Err(SceneError::NonFinite { section: K::Positions, record: i as u32 });
        }
        let v = Vec3::from(p.0);
        if !(v.cmpge(bmin).all() && v.cmple(bmax).all()) {
            return Err(SceneError::OutOfBounds { section: K::Positions, record: i as u32 });
        }
    }
    for (i, t) in triangles.iter().enumerate() {
        if let Some(&bad) = t.0.iter().find(|&&x| x >= nv) {
            return Err(SceneError::IndexOutOfRange { section: K::Triangles, record: i as u32, value: bad, limit: nv });
        }
    }
    Ok(Geometry { positions, triangles, bounds_min: bmin, bounds_max: bmax })
}

/// A brick's SCENE_BOUNDS: absent, or one finite, ordered box.
pub(in crate::image) fn scene_bounds(s: &Sections<'_>) -> Result<Option<(Vec3, Vec3)>, SceneError> {
    let kind = SectionKind::SceneBounds;
    let boxes: &[[[f32; 3]; 2]] = s.slice(kind)?;
    match boxes {
        [] => Ok(None),
        [[lo, hi]] => {
            let (l, h) = (Vec3::from(*lo), Vec3::from(*hi));
            if !(finite3(*lo) && finite3(*hi)) {
                return Err(SceneError::NonFinite { section: kind, record: 0 });
            }
            if !l.cmple(h).all() {
                return Err(SceneError::OutOfBounds { section: kind, record: 0 });
            }
            Ok(Some((l, h)))
        }
        _ => Err(SceneError::CountMismatch { section: kind, expected: 1, found: boxes.len() as u32 }),
    }
}
