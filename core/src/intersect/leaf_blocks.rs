//! A leaf's triangles tested four at a time: the vertices come from TRI_BLOCKS, copies
//! of the leaf's triangles in the order of PRIM_LISTS and in SIMD lanes (Embree's
//! `Triangle4` leaves), so the ray meets four triangles per test and follows no index
//! from list entry to triangle to vertex. The hit kept is the one
//! [`crate::traverse::tree_step::test_leaf`] keeps: each lane computes the one-triangle test's
//! bits, and the closest hit is chosen under the same `(t, prim)` order.

use crate::hit::{keep_closest, Hit};
use crate::image::{SceneView, TriBlock4};
use crate::intersect::triangle::{in_range, test_triangle, Intersector};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::tree_step::{test_leaf, PrimLists};

/// PRIM_LISTS entries `first .. first + count` of `view` tested against `ray` from the
/// scene's TRI_BLOCKS (which the caller has checked are present), keeping the closest
/// hit in `best`. The triangle id is read from the list only for a lane that hits. With
/// `ANY` (the any-hit query, which needs some hit, not the closest) the test ends after
/// the first block that yields one.
#[inline(always)]
pub fn test_leaf_blocks<I: Intersector, P: MemoryProbe, V: PrimLists, const ANY: bool>(
    scene: &SceneView<'_>,
    view: &V,
    prep: &I::Prepared,
    ray: &Ray,
    (first, count): (u32, u32),
    best: &mut Option<Hit>,
    probe: &mut P,
) {
    let end = first.saturating_add(count);
    let mut base = first & !3;
    while base < end {
        // The lanes of this block inside the leaf's range.
        let lo = first.max(base) - base;
        let hi = end.min(base.saturating_add(4)) - base;
        let lanes = (0xF >> (4 - hi)) & (0xF << lo) & 0xF;
        let block = base / 4;
        let Some(tris) = scene.tri_block(block, probe) else {
            // Unreachable for a validated image (the blocks cover the lists).
            test_leaf::<I, P, V>(scene, view, prep, ray, (base + lo, hi - lo), best, probe);
            base = base.saturating_add(4);
            continue;
        };
        let r = I::intersect_block4(prep, tris);
        let mut hit = r.hit & lanes;
        while hit != 0 {
            let k = hit.trailing_zeros() as usize & 3;
            hit &= hit - 1;
            let prim = view.prim(base + k as u32, probe);
            if let Some(h) = in_range(ray, Some((r.t[k], r.u[k], r.v[k])), prim) {
                keep_closest(best, h);
            }
        }
        // Lanes the four-lane form leaves to the one-triangle test (an edge function of
        // exactly zero: its double-precision recomputation).
        let mut redo = r.redo & lanes;
        while redo != 0 {
            let k = redo.trailing_zeros();
            redo &= redo - 1;
            let prim = view.prim(base + k, probe);
            let tri = I::fetch(scene, prim, probe);
            test_triangle::<I>(prep, ray, &tri, prim, best);
        }
        if ANY && best.is_some() {
            return;
        }
        base = base.saturating_add(4);
    }
}

/// List entry `e`'s triangle in the test's form, for a loop over a leaf's entries in
/// order from `first`: from its block where the image has blocks and the test reads them
/// (`blocks`; each block read once, kept in `block`), else through the list and the
/// vertex indices.
#[inline(always)]
pub(crate) fn entry_triangle<'s, I: Intersector, P: MemoryProbe, V: PrimLists>(
    scene: &SceneView<'s>,
    view: &V,
    (e, first): (u32, u32),
    blocks: bool,
    block: &mut Option<&'s TriBlock4>,
    probe: &mut P,
) -> I::Triangle {
    if blocks && (e == first || e % 4 == 0) {
        *block = scene.tri_block(e / 4, probe);
    }
    match block.and_then(|b| I::block_triangle(b, e as usize % 4)) {
        Some(tri) => tri,
        None => I::fetch(scene, view.prim(e, probe), probe),
    }
}
