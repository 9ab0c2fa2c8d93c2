//! The shadow cache: the leaf in which the last shadow ray was found blocked, tested
//! first by the next one (Haines & Greenberg 1986, "The Light Buffer"). Shadow rays to
//! one light from neighbouring hits "operate on almost the same data" (Wald & Slusallek
//! 2001 §5.1): they are mostly blocked by the same few triangles (a ceiling, a wall), so
//! one leaf test often answers a ray that would otherwise walk from the root.
//!
//! The answer stays the walk's: the any-hit query asks whether *some* triangle is hit in
//! the ray's interval, and the structure is conservative (the walk reaches every triangle
//! the ray hits), so a hit in the cached leaf — by the very leaf test the walk uses — is
//! a hit the walk would have found. A miss there costs one leaf test, and the walk runs.

use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::SceneView;
use crate::intersect::leaf_blocks::entry_triangle;
use crate::intersect::triangle::Intersector;
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::tree_step::PrimLists;
use glam::{Vec3, Vec4};

use super::test_wide_leaf;

/// The leaf (its PRIM_LISTS entries `first .. first + count`) where an any-hit walk last
/// found its ray blocked, and how far it is trusted; empty at first. Only a walk fills
/// it, from a node of the image it walked, so a leaf's size is one the image's validation
/// bounded. Keep one per image and thread. (Used with another image, its leaf names list
/// entries of that image, read bounds-checked; in the images raypipe builds every entry
/// belongs to some leaf, even the padding before a leaf block, so the answers stay exact.)
///
/// The trust is a two-bit saturating counter, as a branch predictor's: the leaf is tested
/// only while the last rays would mostly have been answered by it. Scattered shadow rays
/// (a path tracer's, from later bounces) seldom are, and a leaf test each cost them a
/// fifth of their rate (the conference room's path shadow rays, 8.3 against 6.5 Mrays/s).
/// A ray that skips the test still tells whether it would have hit: the walk finds it
/// blocked in the cached leaf, or not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LastOccluder {
    leaf: Option<(u32, u32)>,
    trust: u8,
    /// A packet's second chance: another leaf where a walk recently found rays blocked,
    /// and its own trust (as `trust`).
    second: Option<(u32, u32)>,
    second_trust: u8,
}

impl Default for LastOccluder {
    /// Empty, and trusted as soon as it holds a leaf: coherent rays gain from the second.
    fn default() -> Self {
        LastOccluder { leaf: None, trust: Self::TEST_FROM, second: None, second_trust: Self::TEST_FROM }
    }
}

impl LastOccluder {
    /// The counter's top and the least value at which the leaf is tested.
    const MOST: u8 = 3;
    const TEST_FROM: u8 = 2;

    /// The cached leaf as `(first entry, count)`, if any.
    #[inline(always)]
    pub fn leaf(&self) -> Option<(u32, u32)> {
        self.leaf
    }

    /// The packets' second leaf to test, where the first did not block all their rays:
    /// another leaf a walk found rays blocked in (packets of shadow rays from a block of
    /// pixels meet two or three occluders, a wall and the floor).
    #[inline(always)]
    pub fn second(&self) -> Option<(u32, u32)> {
        self.second.filter(|&s| Some(s) != self.leaf && self.second_trust >= Self::TEST_FROM)
    }

    /// A vote on the second leaf: a test of it blocked some of the packet's rays (`up`),
    /// or did not.
    /// (The conference room's packets that the first leaf does not answer hold rays that
    /// reach the light: a second leaf tested for them cost 3% of its shadow rays' rate.)
    #[inline(always)]
    pub(crate) fn second_voted(&mut self, up: bool) {
        self.second_trust = counted(self.second_trust, up);
    }

    /// A packet's walk found rays blocked in `leaf`: with `replace`, it becomes the first
    /// leaf ([`LastOccluder::blocked_in`], `tested` as there) and the first the second;
    /// else it is kept as the second.
    #[inline(always)]
    pub(crate) fn packet_blocked_in(&mut self, leaf: (u32, u32), replace: bool, tested: bool) {
        if !replace {
            self.also_blocked_in(leaf);
            return;
        }
        if let Some(old) = self.leaf.filter(|&l| l != leaf) {
            self.also_blocked_in(old);
        }
        self.blocked_in(leaf.0, leaf.1, tested);
    }

    /// `leaf` kept as the second leaf if it is not the first.
    #[inline(always)]
    fn also_blocked_in(&mut self, leaf: (u32, u32)) {
        if Some(leaf) != self.leaf && Some(leaf) != self.second {
            // A new leaf: tested at once, its trust its own.
            self.second = Some(leaf);
            self.second_trust = Self::TEST_FROM;
        }
    }

    /// The leaf to test before the walk: the cached one, while it is trusted.
    #[inline(always)]
    pub fn to_test(&self) -> Option<(u32, u32)> {
        self.leaf.filter(|_| self.trust >= Self::TEST_FROM)
    }

    #[inline(always)]
    fn vote(&mut self, up: bool) {
        self.trust = counted(self.trust, up);
    }

    /// The outcome of a ray's test of the cached leaf.
    #[inline(always)]
    pub(crate) fn tested(&mut self, hit: bool) {
        self.vote(hit);
    }

    /// A walk found its ray blocked in leaf `(first, count)`; `tested`: the ray tested
    /// (and missed) the cached leaf first, and has voted already.
    #[inline(always)]
    pub(crate) fn blocked_in(&mut self, first: u32, count: u32, tested: bool) {
        // (An empty cache could not have answered: no vote, so that it is trusted from
        // the first leaf it holds.)
        if !tested && self.leaf.is_some() {
            self.vote(self.leaf == Some((first, count)));
        }
        self.leaf = Some((first, count));
    }

    /// A walk found its ray free; `tested` as for [`LastOccluder::blocked_in`].
    #[inline(always)]
    pub(crate) fn free(&mut self, tested: bool) {
        if !tested {
            self.vote(false);
        }
    }
}

/// A two-bit saturating counter `trust` after a vote `up` or down.
#[inline(always)]
fn counted(trust: u8, up: bool) -> u8 {
    if up {
        (trust + 1).min(LastOccluder::MOST)
    } else {
        trust.saturating_sub(1)
    }
}

/// `ray` against the leaf `cache` trusts (by the walks' own leaf test), its outcome
/// voted: a hit there is the answer. Kept out of line, away from the walks' loops: inlined
/// before them it cost the conference room's path shadow rays 11% (8.3 against 7.4
/// Mrays/s) with the test never taken, the loops' registers reshuffled.
#[inline(never)]
pub(super) fn test_cached_leaf<I: Intersector, P: MemoryProbe, V: PrimLists>(
    scene: &SceneView<'_>,
    view: &V,
    ray: &Ray,
    cache: &mut LastOccluder,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    let leaf = cache.to_test()?;
    let best = test_leaf_alone::<I, P, V>(scene, view, ray, leaf, probe, counters);
    cache.tested(best.is_some());
    best
}

/// Some hit of `ray` in `leaf` (PRIM_LISTS entries `first .. first + count` of `view`),
/// by the walks' own any-hit leaf test, with the ray's own intersection constants: a
/// leaf tested with no walk around it (the cache's), counted as one leaf.
#[inline(always)]
pub(crate) fn test_leaf_alone<I: Intersector, P: MemoryProbe, V: PrimLists>(
    scene: &SceneView<'_>,
    view: &V,
    ray: &Ray,
    leaf: (u32, u32),
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    let mut best = None;
    let prep = I::prepare(ray);
    test_wide_leaf::<I, P, _, true>(scene, view, &prep, ray, leaf, &mut best, scene.has_tri_blocks(), probe);
    counters.leaves = counters.leaves.saturating_add(1);
    counters.tri_tests = counters.tri_tests.saturating_add(leaf.1);
    best
}

/// Four rays against the leaf `cache` trusts (see [`leaf_blocks4`]). Returns the rays
/// tested (none where the cache is not trusted, or the rays cannot share one frame) and
/// those blocked; each tested ray votes, as a ray alone does. Out of line, as
/// [`test_cached_leaf`].
#[inline(never)]
pub(super) fn test_cached_leaf4<I: Intersector, P: MemoryProbe, V: PrimLists>(
    scene: &SceneView<'_>,
    view: &V,
    rays: &[&Ray; 4],
    lanes: u32,
    cache: &mut LastOccluder,
    probe: &mut P,
    counters: &mut RayCounters,
) -> (u32, u32) {
    let Some(leaf) = cache.to_test() else {
        return (0, 0);
    };
    let Some(blocked) = leaf_blocks4::<I, P, V>(scene, view, rays, lanes, leaf, probe, counters) else {
        return (0, 0);
    };
    for k in 0..4 {
        if lanes & (1 << k) != 0 {
            cache.tested(blocked & (1 << k) != 0);
        }
    }
    (lanes, blocked)
}

/// The rays of `lanes` among four against `leaf` (PRIM_LISTS entries `first .. first +
/// count` of `view`), four lanes at a time: each of the leaf's triangles read once and
/// tested against them by the four-ray test ([`Intersector::intersect_rays4`]: lane by
/// lane the one-ray test's bits; a lane it leaves undecided gets the one-ray test), until
/// every such ray is blocked. The rays blocked, or `None` where the four cannot share
/// one frame (nothing tested). Counted as one leaf a ray.
#[inline(always)]
pub(crate) fn leaf_blocks4<I: Intersector, P: MemoryProbe, V: PrimLists>(
    scene: &SceneView<'_>,
    view: &V,
    rays: &[&Ray; 4],
    lanes: u32,
    (first, count): (u32, u32),
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<u32> {
    let [a, b, c, d] = rays;
    let axis = |f: fn(&Ray) -> Vec3| -> [Vec4; 3] {
        let (a, b, c, d) = (f(a), f(b), f(c), f(d));
        [Vec4::new(a.x, b.x, c.x, d.x), Vec4::new(a.y, b.y, c.y, d.y), Vec4::new(a.z, b.z, c.z, d.z)]
    };
    let four = I::prepare_rays4(axis(|r| r.origin), axis(|r| r.dir))?;
    let mut blocked = 0u32;
    let blocks = I::BLOCKS && scene.has_tri_blocks();
    let mut block = None;
    for e in first..first.saturating_add(count) {
        // From the leaf's blocks where the image has them (no index to follow).
        let tri = entry_triangle::<I, P, V>(scene, view, (e, first), blocks, &mut block, probe);
        let r = I::intersect_rays4(&four, &tri);
        let mut decide = lanes & !blocked & (r.hit | r.redo);
        if decide == 0 {
            continue;
        }
        let prim = view.prim(e, probe);
        while decide != 0 {
            let k = decide.trailing_zeros() as usize & 3;
            decide &= decide - 1;
            let ray = rays[k];
            let hit = r.lane_hit::<I>(k, ray, prim, || I::prepare(ray), || tri);
            blocked |= (hit.is_some() as u32) << k;
        }
        if blocked == lanes {
            break;
        }
    }
    let n = lanes.count_ones();
    counters.leaves = counters.leaves.saturating_add(n);
    counters.tri_tests = counters.tri_tests.saturating_add(count.saturating_mul(n));
    Some(blocked)
}

#[cfg(test)]
mod tests {
    use super::LastOccluder;

    /// The counter trusts a leaf that keeps answering and drops one that does not, each
    /// ray voting once, whether it tested the leaf or the walk told.
    #[test]
    fn trusts_a_leaf_while_it_would_answer() {
        let mut c = LastOccluder::default();
        assert_eq!(c.to_test(), None, "empty");
        c.blocked_in(8, 4, false);
        assert_eq!(c.to_test(), Some((8, 4)), "trusted from its first leaf");
        c.tested(false);
        assert_eq!(c.to_test(), None, "one miss from the threshold");
        c.blocked_in(8, 4, false);
        assert_eq!(c.to_test(), Some((8, 4)), "the walk says the leaf would have answered");
        c.tested(true);
        c.tested(true);
        c.free(false);
        assert_eq!(c.to_test(), Some((8, 4)), "saturated at three, one free ray leaves two");
        for _ in 0..5 {
            c.free(false);
        }
        assert_eq!(c.to_test(), None, "free rays vote it down");
        c.blocked_in(12, 4, false);
        assert_eq!((c.leaf(), c.to_test()), (Some((12, 4)), None), "replaced, still distrusted");
        c.blocked_in(12, 4, false);
        c.blocked_in(12, 4, false);
        assert_eq!(c.to_test(), Some((12, 4)));
        // A ray that tested and missed has voted: its walk's outcome does not vote again.
        c.tested(false);
        c.blocked_in(16, 4, true);
        c.free(true);
        assert_eq!((c.leaf(), c.to_test()), (Some((16, 4)), None));
        c.tested(true);
        assert_eq!(c.to_test(), Some((16, 4)));
    }

    /// The packets' second leaf: another leaf a walk found rays blocked in, never the
    /// first, tested while its tests block rays, trusted afresh when it is replaced.
    #[test]
    fn keeps_a_second_leaf_for_packets() {
        let mut c = LastOccluder::default();
        assert_eq!(c.second(), None, "empty");
        c.blocked_in(8, 4, false);
        c.packet_blocked_in((8, 4), false, false);
        assert_eq!(c.second(), None, "the first leaf is not the second");
        c.packet_blocked_in((20, 3), false, false);
        assert_eq!((c.to_test(), c.second()), (Some((8, 4)), Some((20, 3))));
        c.second_voted(false);
        assert_eq!(c.second(), None, "one miss from the threshold");
        c.packet_blocked_in((20, 3), false, false);
        assert_eq!(c.second(), None, "the same leaf keeps its trust");
        c.packet_blocked_in((24, 2), false, false);
        assert_eq!(c.second(), Some((24, 2)), "a new leaf is trusted afresh");
        c.second_voted(true);
        c.second_voted(true);
        c.second_voted(false);
        assert_eq!(c.second(), Some((24, 2)), "saturated at three, one miss leaves two");
        // The walk makes the second leaf the first: it is not tested twice.
        c.blocked_in(24, 2, false);
        assert_eq!((c.leaf(), c.second()), (Some((24, 2)), None));
        // A packet's walk replaces the first leaf: the first becomes the second.
        c.packet_blocked_in((30, 4), true, false);
        assert_eq!((c.leaf(), c.second()), (Some((30, 4)), Some((24, 2))));
    }
}
