//! KD_NODES of the kd-tree: finite split planes, leaves inside PRIM_LISTS, and a root box
//! grown from the scene bounds as the builders grow theirs.

use glam::Vec3;

use crate::image::error::SceneError;
use crate::image::header::SectionKind;
use crate::image::limits::MAX_TREE_DEPTH;
use crate::image::records::KdNode;
use crate::image::sections::Sections;
use crate::image::structure_views::KdTreeView;

use super::prim_lists::prim_lists;
use super::tree::{pair, validate_tree, Children};
use crate::image::margin::grow_bounds;

/// The kd-tree of an image whose scene bounds are `bmin..bmax` and which holds `nt`
/// triangles.
pub(in crate::image) fn kdtree<'a>(
    s: &Sections<'a>,
    nt: u32,
    bmin: Vec3,
    bmax: Vec3,
) -> Result<KdTreeView<'a>, SceneError> {
    // The root box is the scene bounds grown like the builders grow their boxes, so a
    // hit that rounding puts a hair outside the bounds is not clipped away.
    let (rmin, rmax) = grow_bounds(bmin, bmax);
    let nodes: &[KdNode] = s.required(SectionKind::KdNodes)?;
    let prims = prim_lists(s, nt)?;
    let np = prims.len() as u64;
    validate_tree(nodes.len(), SectionKind::KdNodes, MAX_TREE_DEPTH, np, |i| {
        let n = nodes.get(i).ok_or(())?;
        if n.axis() == KdNode::LEAF {
            if n.index() as u64 + n.value as u64 <= np {
                Ok((Children::new(), n.value as u64))
            } else {
                Err(())
            }
        } else if n.split().is_finite() {
            Ok((pair(n.index()), 0))
        } else {
            Err(())
        }
    })?;
    Ok(KdTreeView {
        nodes,
        prims,
        nodes_addr: s.addr(SectionKind::KdNodes),
        prims_addr: s.addr(SectionKind::PrimLists),
        min: rmin,
        max: rmax,
    })
}
