//! [`SceneView::with_geometry`]: a validated image whose vertices have moved and whose
//! binary BVH was refitted or rebuilt — an animated mesh's frame — checked for what
//! changed only (Wald & Slusallek 2001 §8: the structure follows the geometry every
//! frame; validating it once per frame keeps the kernels' guarantees).

use glam::Vec3;

use super::SceneView;
use crate::image::error::SceneError;
use crate::image::header::{AccelKind, Header, SectionKind};
use crate::image::records::{BvhNode, Position};
use crate::image::sections::finite3;
use crate::image::structure_views::BvhView;
use crate::image::validate::bvh::bvh_tree;
use crate::image::validate::indices::indices_below;

/// What moves in an animated mesh's frame: its header (only the bounds may differ from
/// the image's), its vertices, and its binary BVH's nodes and leaf list.
#[derive(Clone, Copy, Debug)]
pub struct FrameGeometry<'b> {
    /// The image's header with the frame's bounds.
    pub header: &'b Header,
    /// The frame's vertices, as many as the image has.
    pub positions: &'b [Position],
    /// The frame's BVH; node 0 is the root.
    pub nodes: &'b [BvhNode],
    /// The triangle ids its leaves index.
    pub prims: &'b [u32],
}

impl<'a> SceneView<'a> {
    /// This image with the frame's geometry in place of its own: the same triangles,
    /// shading data, materials and lights, and `frame`'s vertices and binary BVH (or,
    /// for an image without a structure, no nodes and no list: every ray tests every
    /// triangle, Parker's moving objects). The image must hold a binary BVH or no
    /// structure, and no copy of its vertices (Wald triangles or
    /// triangle blocks, which the move would leave stale); `frame.header` may differ
    /// from the image's in its bounds only. Checks what moved — every vertex finite and
    /// inside the bounds, the tree's shape, boxes and leaves, the list's ids — in one
    /// pass over each, as `parse` would.
    pub fn with_geometry<'b>(&self, frame: FrameGeometry<'b>) -> Result<SceneView<'b>, SceneError>
    where
        'a: 'b,
    {
        let (old, new) = (self.header, frame.header);
        let same_header = Header { bounds_min: old.bounds_min, bounds_max: old.bounds_max, ..*new } == *old;
        if !same_header || !self.wald.is_empty() || !self.tri_blocks.is_empty() {
            return Err(SceneError::StaleCopy { section: SectionKind::Positions, record: u32::MAX });
        }
        let unstructured = old.accel == AccelKind::None as u32;
        if !(old.accel == AccelKind::Bvh as u32 || unstructured) {
            return Err(SceneError::UnknownAccel(old.accel));
        }
        if unstructured && !(frame.nodes.is_empty() && frame.prims.is_empty()) {
            return Err(SceneError::StaleCopy { section: SectionKind::BvhNodes, record: 0 });
        }
        let nv = self.positions.len() as u32;
        if frame.positions.len() as u32 != nv || frame.positions.len() != self.positions.len() {
            let found = frame.positions.len() as u32;
            return Err(SceneError::CountMismatch { section: SectionKind::Positions, expected: nv, found });
        }
        if !finite3(new.bounds_min) || !finite3(new.bounds_max) {
            return Err(SceneError::NonFinite { section: SectionKind::Positions, record: u32::MAX });
        }
        let (lo, hi) = (Vec3::from(new.bounds_min), Vec3::from(new.bounds_max));
        for (i, p) in frame.positions.iter().enumerate() {
            if !finite3(p.0) {
                return Err(SceneError::NonFinite { section: SectionKind::Positions, record: i as u32 });
            }
            let v = Vec3::from(p.0);
            if !(v.cmpge(lo).all() && v.cmple(hi).all()) {
                return Err(SceneError::OutOfBounds { section: SectionKind::Positions, record: i as u32 });
            }
        }
        if unstructured {
            return Ok(SceneView { header: frame.header, positions: frame.positions, ..*self });
        }
        indices_below(SectionKind::PrimLists, frame.prims.iter().copied(), self.triangles.len() as u32, false)?;
        bvh_tree(frame.nodes, frame.prims)?;
        let old_bvh = self.bvh.unwrap_or(BvhView { nodes: &[], prims: &[], nodes_addr: 0, prims_addr: 0 });
        let bvh = BvhView {
            nodes: frame.nodes,
            prims: frame.prims,
            nodes_addr: old_bvh.nodes_addr,
            prims_addr: old_bvh.prims_addr,
        };
        Ok(SceneView {
            header: frame.header,
            positions: frame.positions,
            bvh: Some(bvh),
            prim_lists: frame.prims,
            ..*self
        })
    }
}
