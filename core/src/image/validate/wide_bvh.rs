//! BVH4_NODES and BVH8_NODES of the wide BVHs: every slot a finite box, empty slots in
//! exactly the builder's encoding, leaves inside PRIM_LISTS.

use glam::Vec3;

use crate::image::error::SceneError;
use crate::image::header::SectionKind;
use crate::image::limits::MAX_WIDE_DEPTH;
use crate::image::records::{WideNode, NULL_INDEX};
use crate::image::sections::{finite3, Sections};
use crate::image::structure_views::WideBvhView;

use super::prim_lists::prim_lists;
use super::tree::{validate_tree, Children};

/// The wide BVH (4 or 8 children per node) of an image that holds `nt` triangles.
pub(in crate::image) fn wide_bvh<'a, N: WideNode>(s: &Sections<'a>, nt: u32) -> Result<WideBvhView<'a, N>, SceneError> {
    let section = N::SECTION;
    let nodes: &[N] = s.required(section)?;
    let prims = prim_lists(s, nt)?;
    let np = prims.len() as u64;
    validate_tree(nodes.len(), section, MAX_WIDE_DEPTH, np, |i| {
        let node = nodes.get(i).ok_or(())?;
        let mut inner = Children::new();
        let mut entries = 0u64;
        for k in 0..N::WIDTH {
            let (lo, hi, c, count) = node.slot(k);
            if !(finite3(lo) && finite3(hi)) {
                return Err(());
            }
            if c == NULL_INDEX {
                // Empty slots are exactly the builder's encoding: the most inverted box
                // (which no slab test accepts, however it grows a box) and no leaf. An
                // almost-inverted box with a count would be entered as a leaf of up to
                // 2^32 entries.
                if lo != [f32::MAX; 3] || hi != [-f32::MAX; 3] || count != 0 {
                    return Err(());
                }
            } else if !Vec3::from(lo).cmple(Vec3::from(hi)).all() {
                return Err(());
            } else if count > 0 {
                if c as u64 + count as u64 > np {
                    return Err(());
                }
                entries += count as u64;
            } else if inner.push(c).is_err() {
                return Err(());
            }
        }
        Ok((inner, entries))
    })?;
    Ok(WideBvhView { nodes, prims, nodes_addr: s.addr(section), prims_addr: s.addr(SectionKind::PrimLists) })
}
