//! BVH_NODES of the binary BVH: a tree of finite, ordered boxes whose leaves lie inside
//! PRIM_LISTS.

use glam::Vec3;

use crate::image::error::SceneError;
use crate::image::header::SectionKind;
use crate::image::limits::MAX_TREE_DEPTH;
use crate::image::records::BvhNode;
use crate::image::sections::{finite3, Sections};
use crate::image::structure_views::BvhView;

use super::prim_lists::prim_lists;
use super::tree::{pair, validate_tree, Children};

/// The binary BVH of an image that holds `nt` triangles.
pub(in crate::image) fn bvh<'a>(s: &Sections<'a>, nt: u32) -> Result<BvhView<'a>, SceneError> {
    let nodes: &[BvhNode] = s.required(SectionKind::BvhNodes)?;
    let prims = prim_lists(s, nt)?;
    bvh_tree(nodes, prims)?;
    Ok(BvhView { nodes, prims, nodes_addr: s.addr(SectionKind::BvhNodes), prims_addr: s.addr(SectionKind::PrimLists) })
}

/// The shape of a binary BVH whose leaves index `prims` (entries checked by the
/// caller): finite ordered boxes, children after parents, bounded depth and leaves.
pub(in crate::image) fn bvh_tree(nodes: &[BvhNode], prims: &[u32]) -> Result<(), SceneError> {
    let np = prims.len() as u64;
    validate_tree(nodes.len(), SectionKind::BvhNodes, MAX_TREE_DEPTH, np, |i| {
        let n = nodes.get(i).ok_or(())?;
        let (lo, hi) = (Vec3::from(n.min), Vec3::from(n.max));
        if !(finite3(n.min) && finite3(n.max) && lo.cmple(hi).all()) {
            return Err(());
        }
        if n.count == 0 {
            Ok((pair(n.first), 0))
        } else if n.first as u64 + n.count as u64 <= np {
            Ok((Children::new(), n.count as u64))
        } else {
            Err(())
        }
    })
}
