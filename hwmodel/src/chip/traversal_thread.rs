//! One traversal thread: a packet's registers and what its kernels do when a step
//! issues, when a leaf's results come back, and when it leaves. The traversal unit
//! ([`crate::chip::traversal_unit`]) decides *when*; this decides *what*.
//!
//! A packet in a tree shares one walk (core's `PacketWalk`); in the grid, with a
//! fixed-point datapath or in a two-level scene each ray walks alone (lock-step per ray):
//! in a two-level scene the rays of a packet enter different instances.

use raypipe_core::packet::step::{PacketEvent, PacketStep, PacketWalk};
use raypipe_core::traverse::boxes::datapath::NodeTests;
use raypipe_core::traverse::walk::{Leaf, Walk, WalkEvent};
use raypipe_core::{Hit, Ray};

use crate::chip::instanced_lane::{InstancedLane, LaneEvent};
use crate::chip::jobs::{HitPacket, LeafJob, PacketCost, Query, RayPacketJob, NO_RAY};
use crate::chip::scene::ChipScene;
use crate::memory::port::{Fetch, Recorder};

/// What a thread does once its step's result is there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Next {
    Step,
    /// Some rays entered instances: to the transformation unit first.
    Transform,
    SendLeaf,
    Finish,
}

/// The walk registers of one packet.
enum Regs<D: NodeTests> {
    /// A tree: one walk for the packet.
    Shared(Box<PacketWalk<64>>),
    /// The grid (or no structure), or any structure with a datapath whose box tests are
    /// not the packet walk's `f32` ones (fixed point): one walk per ray.
    PerRay(Vec<Walk<D>>),
    /// A two-level scene: each ray's top-level and bottom walks.
    Instanced(Vec<InstancedLane<D>>),
}

/// One packet's registers (its control state is its bit in the unit's state masks).
pub(crate) struct Thread<D: NodeTests> {
    pub index: u32,
    pub query: Query,
    pub traced: u64,
    /// Lanes whose walk is not over (any-hit lanes leave at their first hit).
    pub live: u64,
    /// Lanes waiting at a leaf.
    pub at_leaf: u64,
    /// Lanes waiting for the transformation unit.
    pub entering: u64,
    rays: Box<[Ray; 64]>,
    regs: Regs<D>,
    leaves: Box<[Leaf; 64]>,
    pub then: Next,
    pub fetch: Fetch,
    /// Ray–node tests of the step in flight.
    pub tested: u64,
    /// What the packet has cost so far.
    pub cost: Box<PacketCost>,
    pub data_at: u64,
    pub result_at: u64,
}

impl<D: NodeTests> Thread<D> {
    /// A free thread.
    pub fn new() -> Thread<D> {
        Thread {
            index: 0,
            query: Query::Closest,
            traced: 0,
            live: 0,
            at_leaf: 0,
            entering: 0,
            rays: Box::new([NO_RAY; 64]),
            regs: Regs::PerRay(Vec::new()),
            leaves: Box::new([Leaf::All { count: 0 }; 64]),
            then: Next::Step,
            fetch: Fetch::default(),
            tested: 0,
            cost: Box::new(PacketCost::new(0)),
            data_at: 0,
            result_at: 0,
        }
    }

    /// Sets up the thread for a new packet.
    pub fn start(&mut self, scene: &ChipScene<'_>, job: &RayPacketJob) {
        self.index = job.index;
        *self.cost = PacketCost::new(job.issued);
        self.query = job.query;
        self.traced = job.lanes;
        self.live = job.lanes;
        self.at_leaf = 0;
        self.entering = 0;
        *self.rays = job.rays;
        let view = match scene {
            ChipScene::Flat(v) => v,
            ChipScene::Instanced(_) => {
                let any = job.query == Query::AnyHit;
                let lanes = (0..64).map(|i| InstancedLane::start(&job.rays[i], any)).collect();
                self.regs = Regs::Instanced(lanes);
                return;
            }
        };
        // The packet walk's box tests are f32: another datapath walks each ray alone.
        let shared = if D::FLOAT { PacketWalk::<64>::start(view, &job.rays, job.lanes) } else { None };
        self.regs = match shared {
            Some(w) => Regs::Shared(Box::new(w)),
            None => {
                let mut walks = match std::mem::replace(&mut self.regs, Regs::PerRay(Vec::new())) {
                    Regs::PerRay(w) if w.len() == 64 => w,
                    _ => vec![Walk::All { visited: true, best: None }; 64],
                };
                for i in crate::lane_iter(job.lanes) {
                    walks[i] = Walk::start(view, &job.rays[i]);
                }
                Regs::PerRay(walks)
            }
        };
    }

    /// Runs the kernels of one step (their reads into `rec`); sets what comes next and
    /// returns the lanes whose ray–node tests the step ran.
    pub fn step(&mut self, scene: &ChipScene<'_>, rec: &mut Recorder) -> u64 {
        let mut tested = 0u64;
        match (&mut self.regs, scene) {
            (Regs::Shared(w), ChipScene::Flat(view)) => match w.step(view, &self.rays[..], rec) {
                PacketEvent::Node { lanes } => {
                    tested = lanes;
                    self.then = Next::Step;
                }
                PacketEvent::Leaf { leaf, lanes } => {
                    let at = lanes & self.live;
                    if at == 0 {
                        // Every ray here is blocked (any-hit): nothing to intersect.
                        w.finish_leaf();
                        self.then = Next::Step;
                    } else {
                        for i in crate::lane_iter(at) {
                            self.leaves[i] = leaf;
                        }
                        self.at_leaf = at;
                        self.then = Next::SendLeaf;
                    }
                }
                PacketEvent::Done => self.then = Next::Finish,
            },
            (Regs::PerRay(walks), ChipScene::Flat(view)) => {
                tested = self.live & !self.at_leaf;
                for i in crate::lane_iter(tested) {
                    rec.at_level(0);
                    match walks[i].step(view, &self.rays[i], rec) {
                        WalkEvent::Inner => {}
                        WalkEvent::Leaf(leaf) => {
                            self.leaves[i] = leaf;
                            self.at_leaf |= 1 << i;
                        }
                        WalkEvent::Done => self.live &= !(1 << i),
                    }
                }
                self.then = self.after_lanes();
            }
            (Regs::Instanced(lanes), ChipScene::Instanced(s)) => {
                tested = self.live & !self.at_leaf;
                for i in crate::lane_iter(tested) {
                    rec.at_level(0);
                    match lanes[i].step(s, rec) {
                        LaneEvent::Inner => {}
                        LaneEvent::Enter => self.entering |= 1 << i,
                        LaneEvent::Leaf(leaf) => {
                            self.leaves[i] = leaf;
                            self.at_leaf |= 1 << i;
                        }
                        LaneEvent::Done => self.live &= !(1 << i),
                    }
                }
                self.then = if self.entering != 0 { Next::Transform } else { self.after_lanes() };
            }
            // Registers set up for another kind of scene (cannot happen): end the packet.
            _ => self.then = Next::Finish,
        }
        tested
    }

    /// Per-ray walks: step while some ray can, then the leaves, then done.
    fn after_lanes(&self) -> Next {
        if self.live & !self.at_leaf & !self.entering != 0 {
            Next::Step
        } else if self.at_leaf != 0 {
            Next::SendLeaf
        } else {
            Next::Finish
        }
    }

    /// The transformation unit's result: the entering rays are in object space. Returns
    /// what the thread does next.
    pub fn entered(&mut self, scene: &ChipScene<'_>) -> Next {
        if let (Regs::Instanced(lanes), ChipScene::Instanced(s)) = (&mut self.regs, scene) {
            for i in crate::lane_iter(self.entering) {
                lanes[i].enter(s, &self.rays[i]);
            }
        }
        self.entering = 0;
        self.after_lanes()
    }

    /// The lane's best hit so far.
    fn best(&self, i: usize) -> Option<Hit> {
        match &self.regs {
            Regs::Shared(w) => w.best(i),
            Regs::PerRay(walks) => walks[i].best(),
            Regs::Instanced(lanes) => lanes[i].best().map(|h| h.hit),
        }
    }

    /// The packet at its leaves, for the intersection unit.
    pub fn leaf_job(&self, thread: u8) -> Box<LeafJob> {
        let mut job = Box::new(LeafJob {
            packet: self.index,
            thread,
            lanes: self.at_leaf,
            query: self.query,
            leaves: *self.leaves,
            bottoms: [0; 64],
            rays: *self.rays,
            best: [None; 64],
            tests: [0; 64],
            bytes: 0,
        });
        for i in crate::lane_iter(self.at_leaf) {
            job.best[i] = match &self.regs {
                Regs::Instanced(lanes) => match lanes[i].at_leaf() {
                    Some((b, ray, best)) => {
                        (job.bottoms[i], job.rays[i]) = (b, ray);
                        best
                    }
                    None => None,
                },
                _ => self.best(i),
            };
        }
        job
    }

    /// A leaf job back: its rays' best hits go into their walks.
    pub fn take_results(&mut self, job: &LeafJob) {
        for i in crate::lane_iter(job.lanes) {
            self.cost.tests[i] += job.tests[i];
        }
        self.cost.bytes += job.bytes;
        let any_hit = self.query == Query::AnyHit;
        match &mut self.regs {
            Regs::Shared(w) => {
                for i in crate::lane_iter(job.lanes) {
                    if let Some(b) = w.best_mut(i) {
                        *b = job.best[i];
                    }
                    if any_hit && job.best[i].is_some() {
                        self.live &= !(1 << i);
                    }
                }
                w.finish_leaf();
            }
            Regs::PerRay(walks) => {
                for i in crate::lane_iter(job.lanes) {
                    *walks[i].best_mut() = job.best[i];
                    if any_hit && job.best[i].is_some() {
                        // Blocked: a shadow ray needs no more of the walk.
                        self.live &= !(1 << i);
                    } else {
                        walks[i].finish_leaf();
                    }
                }
            }
            Regs::Instanced(lanes) => {
                for i in crate::lane_iter(job.lanes) {
                    if lanes[i].finish_leaf(job.best[i]) {
                        self.live &= !(1 << i);
                    }
                }
            }
        }
        self.at_leaf &= !job.lanes;
    }

    /// The finished packet, for shading.
    pub fn hit_packet(&self) -> Box<HitPacket> {
        let mut out = Box::new(HitPacket {
            index: self.index,
            lanes: self.traced,
            hits: [None; 64],
            instances: [0; 64],
            cost: self.cost.clone(),
        });
        for i in crate::lane_iter(self.traced) {
            match &self.regs {
                Regs::Instanced(lanes) => {
                    let best = lanes[i].best();
                    out.hits[i] = best.map(|h| h.hit);
                    out.instances[i] = best.map_or(0, |h| h.instance);
                }
                _ => out.hits[i] = self.best(i),
            }
        }
        out
    }
}
