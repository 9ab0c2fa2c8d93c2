//! One ray's registers in a two-level scene (Wald & Slusallek 2001 §8.3): its top-level
//! walk over the instances' boxes (core's `InstanceWalk`) and, while inside an instance,
//! its object-space ray and the walk of that instance's bottom structure (core's `Walk`).
//! Between the two, the transformation unit carries the ray into object space: a lane
//! whose top-level step handed out an instance waits for it ([`InstancedLane::enter`]).

use raypipe_core::traverse::boxes::datapath::NodeTests;
use raypipe_core::traverse::instanced::{InstanceEvent, InstanceHit, InstanceWalk};
use raypipe_core::traverse::walk::{Leaf, Walk, WalkEvent};
use raypipe_core::{Hit, Ray};

use crate::chip::scene::InstancedScene;
use crate::memory::port::Recorder;

/// What one step of a lane produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LaneEvent {
    /// A node (either level) was read, or the ray left an instance; step again.
    Inner,
    /// A bottom leaf: its triangles go to the intersection unit.
    Leaf(Leaf),
    /// An instance was handed out: the ray waits for the transformation unit.
    Enter,
    /// The walk is over.
    Done,
}

/// The registers of one ray.
#[derive(Clone, Debug)]
pub struct InstancedLane<D: NodeTests> {
    top: InstanceWalk,
    /// Inside an instance: its bottom, the ray in its object space, the bottom's walk.
    inside: Option<(u32, Ray, Walk<D>)>,
}

impl<D: NodeTests> InstancedLane<D> {
    /// `ray` at the top-level root.
    pub fn start(ray: &Ray, any_hit: bool) -> InstancedLane<D> {
        InstancedLane { top: InstanceWalk::start(ray, any_hit), inside: None }
    }

    /// One step: of the bottom walk while inside an instance (its reads at the bottom's
    /// address), else of the top level.
    pub fn step(&mut self, scene: &InstancedScene<'_>, rec: &mut Recorder) -> LaneEvent {
        if let Some((b, ray, walk)) = &mut self.inside {
            let Some((view, base)) = scene.bottom(*b) else {
                self.leave();
                return LaneEvent::Inner;
            };
            rec.base = base;
            let event = walk.step(view, ray, rec);
            rec.base = 0;
            return match event {
                WalkEvent::Inner => LaneEvent::Inner,
                WalkEvent::Leaf(leaf) => LaneEvent::Leaf(leaf),
                WalkEvent::Done => {
                    self.leave();
                    LaneEvent::Inner
                }
            };
        }
        match self.top.step(&scene.top, rec) {
            InstanceEvent::Inner => LaneEvent::Inner,
            InstanceEvent::Instance(_) => LaneEvent::Enter,
            InstanceEvent::Done => LaneEvent::Done,
        }
    }

    /// The transformation unit's result: the world ray `ray` carried into the pending
    /// instance's object space (the interval ending at the best hit so far), and the
    /// bottom's walk started on it.
    pub fn enter(&mut self, scene: &InstancedScene<'_>, ray: &Ray) {
        match self.top.object_ray(ray).and_then(|(b, r)| scene.bottom(b).map(|(view, _)| (b, r, view))) {
            Some((b, object, view)) => self.inside = Some((b, object, Walk::start(view, &object))),
            // A record naming no bottom (validation forbids it): nothing to hit there.
            None => self.top.finish_instance(None),
        }
    }

    /// The bottom walk is over: its hit goes to the top level.
    fn leave(&mut self) {
        let best = self.inside.take().and_then(|(_, _, walk)| walk.best());
        self.top.finish_instance(best);
    }

    /// The bottom and object ray of the leaf a lane stands at, and its best hit there.
    pub fn at_leaf(&self) -> Option<(u32, Ray, Option<Hit>)> {
        self.inside.as_ref().map(|(b, ray, walk)| (*b, *ray, walk.best()))
    }

    /// The intersection unit's result for the lane's leaf. Returns true when the lane's
    /// walk is over (an any-hit ray that was blocked).
    pub fn finish_leaf(&mut self, best: Option<Hit>) -> bool {
        let Some((_, _, walk)) = &mut self.inside else { return false };
        *walk.best_mut() = best;
        if self.top.is_any_hit() && best.is_some() {
            // Blocked: the instance ends here, and with it the shadow ray's walk.
            self.leave();
            return true;
        }
        walk.finish_leaf();
        false
    }

    /// The ray's hit (once its walk is over).
    pub fn best(&self) -> Option<InstanceHit> {
        self.top.best()
    }
}
