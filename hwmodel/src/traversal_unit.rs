//! The traversal unit: several packets in flight ("threads", to hide memory latency),
//! one traversal step of one ready packet issued per cycle for all of its lanes that are
//! not waiting at a leaf (lanes step in lock-step; the active fraction is the SIMD
//! efficiency). Each lane's registers are core's [`Walk`] — the structures' own step
//! kernels — so the model computes exactly the host's hits. When no lane can step any
//! more, the packet goes to the coupled intersection unit with the lanes' leaves and
//! comes back with their best hits (Wald & Slusallek 2001 §7.3).
//!
//! Ports: `rays` in (from ray generation), `leaves` out and `results` in (to and from
//! the intersection unit), `hits` out (to shading), and a memory port with a node cache.

use raypipe_core::traverse::walk::{Leaf, Walk, WalkEvent};
use raypipe_core::{Ray, SceneView};

use crate::config::HwConfig;
use crate::fifo::Fifo;
use crate::jobs::{lanes, HitPacket, LeafJob, Query, RayPacketJob, NO_RAY};
use crate::mem_port::{MemPort, PortProbe, Wait};
use crate::unit_stats::{Activity, UnitStats};

/// What a thread does next once its wait is over.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Next {
    Step,
    SendLeaf,
    Finish,
}

/// A thread's control state; the unit keeps one bit mask of threads per state, so that
/// picking a thread is a find-first-set, as in hardware.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Free = 0,
    /// Waiting for a step's data (memory) and its pipeline latency.
    Waiting = 1,
    Ready = 2,
    SendLeaf = 3,
    AtIntersection = 4,
    Finished = 5,
}

const STATES: usize = 6;

/// One packet's registers (its control state is its bit in the unit's state masks).
struct Thread {
    /// While waiting: for what, until when, and what comes next.
    wait: Wait,
    not_before: u64,
    then: Next,
    index: u32,
    query: Query,
    traced: u64,
    /// Lanes whose walk is not over.
    live: u64,
    /// Lanes waiting at a leaf.
    at_leaf: u64,
    rays: Box<[Ray; 64]>,
    walks: Vec<Walk>,
    leaves: [Leaf; 64],
}

/// A traversal unit.
pub struct TraversalUnit {
    /// Unit number.
    pub id: usize,
    packet_size: u64,
    step_latency: u64,
    threads: Vec<Thread>,
    /// `masks[s]`: the threads in state `s`.
    masks: [u64; STATES],
    next_issue: u32,
    /// The node port.
    pub port: MemPort,
    /// Activity and SIMD lanes.
    pub stats: UnitStats,
}

/// The lowest set bit of `mask` at or after `start` (wrapping), if any.
fn first_from(mask: u64, start: u32) -> Option<usize> {
    if mask == 0 {
        return None;
    }
    let rotated = mask.rotate_right(start);
    Some(((rotated.trailing_zeros() + start) % 64) as usize)
}

impl TraversalUnit {
    /// A unit with `cfg.traversal.threads` free threads.
    pub fn new(id: usize, cfg: &HwConfig) -> TraversalUnit {
        let n = cfg.traversal.threads.clamp(1, 64) as usize;
        let threads = (0..n)
            .map(|_| Thread {
                wait: Wait::default(),
                not_before: 0,
                then: Next::Step,
                index: 0,
                query: Query::Closest,
                traced: 0,
                live: 0,
                at_leaf: 0,
                rays: Box::new([NO_RAY; 64]),
                walks: vec![Walk::All { visited: true, best: None }; 64],
                leaves: [Leaf::All { count: 0 }; 64],
            })
            .collect();
        let mut masks = [0u64; STATES];
        masks[State::Free as usize] = if n == 64 { u64::MAX } else { (1u64 << n) - 1 };
        TraversalUnit {
            id,
            packet_size: cfg.packet_size as u64,
            step_latency: cfg.traversal.step_latency as u64,
            threads,
            masks,
            next_issue: 0,
            port: MemPort::new(format!("traversal{id}"), &cfg.cache.nodes),
            stats: UnitStats::default(),
        }
    }

    fn set(&mut self, k: usize, state: State) {
        let bit = 1u64 << k;
        for m in &mut self.masks {
            *m &= !bit;
        }
        self.masks[state as usize] |= bit;
    }

    /// True if no packet is in flight.
    pub fn is_empty(&self) -> bool {
        self.masks[State::Free as usize].count_ones() as usize == self.threads.len()
    }

    /// The first cycle after `now` at which time alone changes something (a step's data
    /// and latency are over); `None` if only FIFO traffic can.
    pub fn next_wake(&self, now: u64) -> Option<u64> {
        crate::lane_iter(self.masks[State::Waiting as usize])
            .map(|k| {
                let t = &self.threads[k];
                self.port.resolve(&t.wait).map_or(now + 1, |r| r.max(t.not_before))
            })
            .filter(|&w| w > now)
            .min()
    }

    /// One line describing the threads (for the watchdog).
    pub fn describe(&self) -> String {
        let count = |s: State| self.masks[s as usize].count_ones();
        format!(
            "traversal{}: {} free, {} waiting, {} ready, {} to send to intersection, {} at intersection, {} finished",
            self.id,
            count(State::Free),
            count(State::Waiting),
            count(State::Ready),
            count(State::SendLeaf),
            count(State::AtIntersection),
            count(State::Finished),
        )
    }

    /// One cycle. Returns true if anything moved.
    pub fn tick(
        &mut self,
        now: u64,
        scene: &SceneView<'_>,
        rays: &mut Fifo<Box<RayPacketJob>>,
        leaves: &mut Fifo<Box<LeafJob>>,
        results: &mut Fifo<Box<LeafJob>>,
        hits: &mut Fifo<Box<HitPacket>>,
    ) -> bool {
        let mut moved = false;
        // A packet back from the intersection unit: its lanes finish their leaves.
        if self.masks[State::AtIntersection as usize] != 0 {
            if let Some(job) = results.pop() {
                let k = job.thread as usize;
                if k < self.threads.len() {
                    let t = &mut self.threads[k];
                    for i in crate::lane_iter(job.lanes) {
                        *t.walks[i].best_mut() = job.best[i];
                        if t.query == Query::AnyHit && job.best[i].is_some() {
                            // Blocked: a shadow ray needs no more of the walk.
                            t.live &= !(1 << i);
                        } else {
                            t.walks[i].finish_leaf();
                        }
                    }
                    t.at_leaf &= !job.lanes;
                    self.set(k, State::Ready);
                }
                moved = true;
            }
        }
        // A finished packet to shading.
        if let Some(k) = first_from(self.masks[State::Finished as usize], 0) {
            if hits.can_push() {
                let t = &self.threads[k];
                let mut out = Box::new(HitPacket { index: t.index, lanes: t.traced, hits: [None; 64] });
                for i in crate::lane_iter(t.traced) {
                    out.hits[i] = t.walks[i].best();
                }
                let _ = hits.push(out);
                self.set(k, State::Free);
                moved = true;
            } else {
                hits.note_full();
            }
        }
        // A packet at its leaves to the intersection unit.
        if let Some(k) = first_from(self.masks[State::SendLeaf as usize], 0) {
            if leaves.can_push() {
                let t = &self.threads[k];
                let mut job = Box::new(LeafJob {
                    thread: k as u8,
                    lanes: t.at_leaf,
                    query: t.query,
                    leaves: t.leaves,
                    rays: *t.rays,
                    best: [None; 64],
                });
                for i in crate::lane_iter(t.at_leaf) {
                    job.best[i] = t.walks[i].best();
                }
                let _ = leaves.push(job);
                self.set(k, State::AtIntersection);
                moved = true;
            } else {
                leaves.note_full();
            }
        }
        // A new packet into a free thread.
        if let Some(k) = first_from(self.masks[State::Free as usize], 0) {
            if let Some(job) = rays.pop() {
                let t = &mut self.threads[k];
                t.index = job.index;
                t.query = job.query;
                t.traced = job.lanes;
                t.live = job.lanes;
                t.at_leaf = 0;
                *t.rays = job.rays;
                for i in crate::lane_iter(job.lanes) {
                    t.walks[i] = Walk::start(scene, &job.rays[i]);
                }
                self.set(k, if job.lanes == 0 { State::Finished } else { State::Ready });
                moved = true;
            }
        }
        // Steps whose data has arrived.
        for k in crate::lane_iter(self.masks[State::Waiting as usize]) {
            let t = &self.threads[k];
            if self.port.resolve(&t.wait).is_some_and(|r| r.max(t.not_before) <= now) {
                let next = match t.then {
                    Next::Step => State::Ready,
                    Next::SendLeaf => State::SendLeaf,
                    Next::Finish => State::Finished,
                };
                self.set(k, next);
                moved = true;
            }
        }
        // Issue one step of one ready packet (round robin).
        let activity = if let Some(k) = first_from(self.masks[State::Ready as usize], self.next_issue) {
            self.next_issue = (k as u32 + 1) % 64;
            let t = &mut self.threads[k];
            let stepping = t.live & !t.at_leaf;
            let mut probe = PortProbe { port: &mut self.port, now, wait: Wait::default() };
            for i in crate::lane_iter(stepping) {
                match t.walks[i].step(scene, &t.rays[i], &mut probe) {
                    WalkEvent::Inner => {}
                    WalkEvent::Leaf(leaf) => {
                        t.leaves[i] = leaf;
                        t.at_leaf |= 1 << i;
                    }
                    WalkEvent::Done => t.live &= !(1 << i),
                }
            }
            t.then = if t.live & !t.at_leaf != 0 {
                Next::Step
            } else if t.at_leaf != 0 {
                Next::SendLeaf
            } else {
                Next::Finish
            };
            t.wait = probe.wait;
            t.not_before = now + self.step_latency;
            self.set(k, State::Waiting);
            self.stats.issue(lanes(stepping), self.packet_size);
            moved = true;
            Activity::Busy
        } else if self.is_empty() {
            Activity::Idle
        } else {
            Activity::Stalled
        };
        self.stats.cycle(activity);
        moved
    }
}
