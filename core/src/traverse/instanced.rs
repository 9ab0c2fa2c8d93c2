//! The two-level walk of an instanced scene (Wald & Slusallek 2001 §8.3; the SaarCOR
//! prototype's transformation unit): a top-level BVH over the instances' world boxes,
//! visited front to back, and in each instance its bottom image's own structure, which
//! the ray enters through the instance's world-to-object map.
//!
//! [`InstanceWalk`] holds a ray's top-level registers. Each [`InstanceWalk::step`] reads
//! one top-level node, or an instance record and reports [`InstanceEvent::Instance`]; the
//! driver traces [`InstanceWalk::object_ray`] through that bottom image with any of its
//! kernels and hands the hit to [`InstanceWalk::finish_instance`].
//!
//! One hit whatever the path: the object-space ray is computed by one function
//! ([`affine::object_ray`]) with the interval ending at the best hit so far (inclusive),
//! `t` means the same point in both spaces, and the walk keeps the smallest
//! `(t, instance, triangle)` ([`InstanceHit::is_closer_than`]); a bottom's kernel
//! returns its smallest `(t, triangle)` in any interval that holds it. So every driver,
//! in any order of instances, finds the same hit bit for bit.

use crate::counters::RayCounters;
use crate::hit::{keep_closest, Hit};
use crate::image::instanced::{InstanceRecord, TopLevel};
use crate::image::SceneView;
use crate::intersect::triangle::Intersector;
use crate::math::affine;
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::slab::RayBox;
use crate::traverse::bvh::BvhTraversal;
use crate::traverse::occlusion::occluded;
use crate::traverse::tree_step::TreeEvent;
use crate::traverse::walk::trace_walk;

/// A hit in an instanced scene: the bottom image's hit (`prim` is its triangle index,
/// `t` the world ray's parameter) and the instance it belongs to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceHit {
    /// The hit, in the bottom image's terms.
    pub hit: Hit,
    /// The instance.
    pub instance: u32,
}

impl InstanceHit {
    /// The one order of instanced hits: smallest `(t, instance, prim)`.
    #[inline]
    pub fn is_closer_than(&self, other: &InstanceHit) -> bool {
        let (a, b) = (&self.hit, &other.hit);
        a.t < b.t || (a.t == b.t && (self.instance, a.prim) < (other.instance, b.prim))
    }

    /// Bit-exact equality.
    pub fn bits_eq(&self, other: &InstanceHit) -> bool {
        self.instance == other.instance && self.hit.bits_eq(&other.hit)
    }
}

/// Keeps the closer of `best` and `candidate` under the `(t, instance, prim)` order.
#[inline]
pub fn keep_closest_instance(best: &mut Option<InstanceHit>, candidate: InstanceHit) {
    match best {
        Some(b) if !candidate.is_closer_than(b) => {}
        _ => *best = Some(candidate),
    }
}

/// What one top-level step produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InstanceEvent {
    /// A top-level node was read; step again.
    Inner,
    /// The ray must visit this instance next: trace [`InstanceWalk::object_ray`] through
    /// its bottom image and call [`InstanceWalk::finish_instance`].
    Instance(u32),
    /// The walk is over; [`InstanceWalk::best`] is the ray's hit.
    Done,
}

/// One ray's top-level registers: the BVH walk over instance boxes, the leaf being
/// handed out, the instance record fetched, and the best hit so far.
#[derive(Clone, Debug)]
pub struct InstanceWalk {
    bvh: BvhTraversal<RayBox>,
    // The leaf being handed out: (first list entry, count, next entry).
    leaf: Option<(u32, u32, u32)>,
    // The instance handed out and not yet finished, with its record.
    pending: Option<(u32, InstanceRecord)>,
    any_hit: bool,
    done: bool,
    best: Option<InstanceHit>,
}

impl InstanceWalk {
    /// Starts `ray` at the top-level root; `any_hit` ends the walk at the first hit in
    /// range (shadow rays).
    pub fn start(ray: &Ray, any_hit: bool) -> InstanceWalk {
        InstanceWalk { bvh: BvhTraversal::new(ray), leaf: None, pending: None, any_hit, done: false, best: None }
    }

    /// One step: the instance still pending, the next instance of the current leaf (its
    /// record read), or one top-level node.
    #[inline]
    pub fn step<P: MemoryProbe>(&mut self, top: &TopLevel<'_>, probe: &mut P) -> InstanceEvent {
        if let Some((i, _)) = self.pending {
            return InstanceEvent::Instance(i);
        }
        if self.done {
            return InstanceEvent::Done;
        }
        if let Some((first, count, k)) = self.leaf {
            if k < count {
                let i = top.list_instance(first.wrapping_add(k), probe);
                // The record's address comes from the list entry.
                probe.dependent();
                let rec = top.instance(i, probe);
                self.leaf = Some((first, count, k + 1));
                self.pending = Some((i, rec));
                return InstanceEvent::Instance(i);
            }
            self.leaf = None;
            self.bvh.finish_leaf();
        }
        match self.bvh.step(top.tree(), probe) {
            TreeEvent::Inner => InstanceEvent::Inner,
            TreeEvent::Leaf { first, count } => {
                self.leaf = Some((first, count, 0));
                InstanceEvent::Inner
            }
            TreeEvent::Done => {
                self.done = true;
                InstanceEvent::Done
            }
        }
    }

    /// The pending instance's bottom image and `ray` in its object space, the interval
    /// ending at the best hit so far (inclusive, so a hit at the same distance with a
    /// smaller id is still found). `None` when no instance is pending.
    #[inline]
    pub fn object_ray(&self, ray: &Ray) -> Option<(u32, Ray)> {
        let (_, rec) = self.pending?;
        Some((rec.bottom, affine::object_ray(&rec.to_object, &bounded(ray, self.best))))
    }

    /// The pending instance's record.
    pub fn pending(&self) -> Option<(u32, InstanceRecord)> {
        self.pending
    }

    /// The pending instance's result: its bottom's closest hit (any hit in range for an
    /// any-hit walk).
    #[inline]
    pub fn finish_instance(&mut self, hit: Option<Hit>) {
        let Some((instance, _)) = self.pending.take() else { return };
        let Some(hit) = hit else { return };
        keep_closest_instance(&mut self.best, InstanceHit { hit, instance });
        // The top level skips boxes entered beyond the best hit.
        keep_closest(&mut self.bvh.best, Hit { prim: 0, ..hit });
        if self.any_hit {
            self.done = true;
            self.leaf = None;
        }
    }

    /// The best hit so far (the ray's hit once the walk is done).
    pub fn best(&self) -> Option<InstanceHit> {
        self.best
    }

    /// True for an any-hit walk (a shadow ray's).
    pub fn is_any_hit(&self) -> bool {
        self.any_hit
    }
}

/// `ray` with its interval ending at `best`'s distance when that is nearer.
#[inline]
pub fn bounded(ray: &Ray, best: Option<InstanceHit>) -> Ray {
    match best {
        Some(b) if b.hit.t < ray.t_max => Ray { t_max: b.hit.t, ..*ray },
        _ => *ray,
    }
}

/// Drives an [`InstanceWalk`] for `ray` to its end, tracing each instance's bottom image
/// (`bottoms[bottom]`) with `bottom_trace` (object ray, bottom view, any-hit → hit).
#[inline]
pub fn run_instanced<P: MemoryProbe>(
    top: &TopLevel<'_>,
    bottoms: &[SceneView<'_>],
    ray: &Ray,
    any_hit: bool,
    probe: &mut P,
    mut bottom_trace: impl FnMut(&SceneView<'_>, &Ray, &mut P) -> Option<Hit>,
) -> Option<InstanceHit> {
    let mut walk = InstanceWalk::start(ray, any_hit);
    loop {
        match walk.step(top, probe) {
            InstanceEvent::Inner => {}
            InstanceEvent::Instance(_) => {
                let hit = walk
                    .object_ray(ray)
                    .and_then(|(b, r)| bottoms.get(b as usize).and_then(|view| bottom_trace(view, &r, probe)));
                walk.finish_instance(hit);
            }
            InstanceEvent::Done => return walk.best(),
        }
    }
}

/// The closest hit of `ray` in the instanced scene, each bottom traced with its own
/// structure's step kernel ([`trace_walk`]): the reference driver.
pub fn trace_instanced<I: Intersector, P: MemoryProbe>(
    top: &TopLevel<'_>,
    bottoms: &[SceneView<'_>],
    ray: &Ray,
    probe: &mut P,
) -> Option<InstanceHit> {
    run_instanced(top, bottoms, ray, false, probe, |view, r, p| trace_walk::<I, P>(view, r, p))
}

/// True if anything lies on `ray` within its interval (shadow rays): the bottoms'
/// any-hit query ([`occluded`]), ending at the first instance that blocks.
pub fn occluded_instanced<I: Intersector, P: MemoryProbe>(
    top: &TopLevel<'_>,
    bottoms: &[SceneView<'_>],
    ray: &Ray,
    probe: &mut P,
) -> bool {
    let blocked = run_instanced(top, bottoms, ray, true, probe, |view, r, p| {
        occluded::<I, P>(view, r, p, &mut RayCounters::default()).then_some(Hit { t: r.t_max, u: 0.0, v: 0.0, prim: 0 })
    });
    blocked.is_some()
}
