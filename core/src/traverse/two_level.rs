//! The two-level walk of a bricked scene (Wald & Slusallek 2001, §6.3): a top-level BVH
//! over bricks, visited front to back, and in each brick the brick's own structure.
//!
//! [`TopWalk`] holds a ray's top-level registers. Each [`TopWalk::step`] reads one
//! top-level node or reports the next brick the ray must visit, [`TopEvent::Brick`]; the
//! driver then either traces [`TopWalk::brick_ray`] through that brick — if it is
//! resident — and hands the result to [`TopWalk::finish_brick`], or parks the walk (it is
//! plain data: clone it, store it) until the brick arrives and steps it again, which
//! reports the same brick: the ray resumes exactly where it stopped. Only the rays that
//! reach a missing brick wait; the driver keeps tracing the others.
//!
//! One hit whatever the path: a brick reports its closest hit with its scene-wide id
//! (TRIANGLE_IDS, strictly increasing, so equal distances are ordered inside a brick as
//! in the flat image), the walk keeps the smallest `(t, id)` over bricks, and a brick is
//! skipped only when its box is entered beyond the best hit. Every point of every
//! triangle lies in the top-level box of a brick that holds the triangle (a triangle
//! reaching across the partition's regions is held by each brick it reaches into, and
//! gives the same `t` and id in each), so the result is the flat image's hit bit for
//! bit.

use crate::hit::{keep_closest, Hit};
use crate::image::bricked::BrickedView;
use crate::image::SceneView;
use crate::intersect::triangle::Intersector;
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::slab::RayBox;
use crate::traverse::bvh::BvhTraversal;
use crate::traverse::occlusion::occluded;
use crate::traverse::tree_step::TreeEvent;
use crate::traverse::walk::trace_walk;
use crate::RayCounters;

/// A hit in a bricked scene: the hit with its scene-wide triangle id (what the flat
/// image reports), and where the triangle lives, for shading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BrickHit {
    /// The hit; `prim` is the scene-wide triangle id.
    pub hit: Hit,
    /// The brick holding the triangle.
    pub brick: u32,
    /// The triangle's index inside that brick.
    pub local: u32,
}

impl BrickHit {
    /// The hit as the brick's own view knows it (its local triangle index), for shading
    /// with that view.
    pub fn local_hit(&self) -> Hit {
        Hit { prim: self.local, ..self.hit }
    }
}

/// What one top-level step produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TopEvent {
    /// A top-level node was read; step again.
    Inner,
    /// The ray must visit this brick next: trace [`TopWalk::brick_ray`] through it and
    /// call [`TopWalk::finish_brick`] — or, if it is not resident, park the walk and step
    /// it again once it is (it reports the same brick).
    Brick(u32),
    /// The walk is over; [`TopWalk::best`] is the ray's hit.
    Done,
}

/// One ray's top-level registers: the binary BVH walk over brick boxes, the leaf being
/// handed out, and the best hit so far.
#[derive(Clone, Debug)]
pub struct TopWalk {
    bvh: BvhTraversal<RayBox>,
    // The leaf being handed out: (first list entry, count, next entry).
    leaf: Option<(u32, u32, u32)>,
    // The brick handed out and not yet finished.
    pending: Option<u32>,
    any_hit: bool,
    done: bool,
    best: Option<BrickHit>,
}

impl TopWalk {
    /// Starts `ray` at the top-level root; `any_hit` ends the walk at the first hit in
    /// range (shadow rays).
    pub fn start(ray: &Ray, any_hit: bool) -> TopWalk {
        TopWalk { bvh: BvhTraversal::new(ray), leaf: None, pending: None, any_hit, done: false, best: None }
    }

    /// One step: the brick still pending, the next brick of the current leaf, or one
    /// top-level node.
    #[inline]
    pub fn step<P: MemoryProbe>(&mut self, index: &BrickedView<'_>, probe: &mut P) -> TopEvent {
        if let Some(b) = self.pending {
            return TopEvent::Brick(b);
        }
        if self.done {
            return TopEvent::Done;
        }
        if let Some((first, count, k)) = self.leaf {
            if k < count {
                let b = index.list_brick(first.wrapping_add(k), probe);
                self.leaf = Some((first, count, k + 1));
                self.pending = Some(b);
                return TopEvent::Brick(b);
            }
            self.leaf = None;
            self.bvh.finish_leaf();
        }
        match self.bvh.step(index.top(), probe) {
            TreeEvent::Inner => TopEvent::Inner,
            TreeEvent::Leaf { first, count } => {
                self.leaf = Some((first, count, 0));
                TopEvent::Inner
            }
            TreeEvent::Done => {
                self.done = true;
                TopEvent::Done
            }
        }
    }

    /// The ray to trace through the pending brick: `ray` with its interval ending at the
    /// best hit so far (inclusive, so a hit at the same distance with a smaller id is
    /// still found).
    #[inline]
    pub fn brick_ray(&self, ray: &Ray) -> Ray {
        match self.best {
            Some(b) if b.hit.t < ray.t_max => Ray { t_max: b.hit.t, ..*ray },
            _ => *ray,
        }
    }

    /// The pending brick's result: its closest hit (a local triangle index of `brick`'s
    /// view), or for an any-hit walk any hit in range.
    #[inline]
    pub fn finish_brick(&mut self, brick: &SceneView<'_>, hit: Option<Hit>) {
        let Some(b) = self.pending.take() else { return };
        let Some(h) = hit else { return };
        let global = Hit { prim: brick.scene_triangle_id(h.prim), ..h };
        let candidate = BrickHit { hit: global, brick: b, local: h.prim };
        match self.best {
            Some(best) if !global.is_closer_than(&best.hit) => {}
            _ => self.best = Some(candidate),
        }
        // The top level skips boxes entered beyond the best hit.
        keep_closest(&mut self.bvh.best, global);
        if self.any_hit {
            self.done = true;
            self.leaf = None;
        }
    }

    /// The pending brick's any-hit result (`blocked`: something lies in the brick ray's
    /// interval): ends the walk when blocked. [`TopWalk::best`] then holds a hit at the
    /// interval's end that says only "blocked".
    #[inline]
    pub fn finish_brick_occluded(&mut self, brick: &SceneView<'_>, ray: &Ray, blocked: bool) {
        let r = self.brick_ray(ray);
        self.finish_brick(brick, blocked.then_some(Hit { t: r.t_max, u: 0.0, v: 0.0, prim: 0 }));
    }

    /// The best hit so far (the ray's hit once the walk is done).
    pub fn best(&self) -> Option<BrickHit> {
        self.best
    }

    /// True for an any-hit walk (a shadow ray's).
    pub fn is_any_hit(&self) -> bool {
        self.any_hit
    }

    /// The brick handed out and not yet finished, if any.
    pub fn pending(&self) -> Option<u32> {
        self.pending
    }
}

/// How [`run_two_level`] ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TwoLevelOutcome {
    /// The walk is over with this hit.
    Done(Option<BrickHit>),
    /// The walk waits for this brick; step it again once the brick is resident.
    Missing(u32),
}

/// Drives `walk` for `ray` until it ends or reaches a brick that `resident` does not
/// provide (the driver's cache: brick id → its validated view). Resident bricks are
/// traced with their own structure's step kernel ([`trace_walk`]), or its any-hit query
/// ([`occluded`]) for an any-hit walk. The reference driver of the two-level walk: the
/// host's tracer runs the same [`TopWalk`] with its faster per-structure kernels.
pub fn run_two_level<'s, I: Intersector, P: MemoryProbe>(
    walk: &mut TopWalk,
    index: &BrickedView<'_>,
    ray: &Ray,
    resident: &mut impl FnMut(u32) -> Option<SceneView<'s>>,
    probe: &mut P,
) -> TwoLevelOutcome {
    loop {
        match walk.step(index, probe) {
            TopEvent::Inner => {}
            TopEvent::Brick(b) => {
                let Some(view) = resident(b) else { return TwoLevelOutcome::Missing(b) };
                let r = walk.brick_ray(ray);
                if walk.any_hit {
                    // Any hit in range will do; shading needs no hit record of it.
                    let blocked = occluded::<I, P>(&view, &r, probe, &mut RayCounters::default());
                    walk.finish_brick_occluded(&view, ray, blocked);
                } else {
                    let hit = trace_walk::<I, P>(&view, &r, probe);
                    walk.finish_brick(&view, hit);
                }
            }
            TopEvent::Done => return TwoLevelOutcome::Done(walk.best()),
        }
    }
}
