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

use raypipe_core::walk::{Leaf, Walk, WalkEvent};
use raypipe_core::{Ray, SceneView};

use crate::config::HwConfig;
use crate::fifo::Fifo;
use crate::jobs::{lanes, HitPacket, LeafJob, RayPacketJob, NO_RAY};
use crate::mem_port::{MemPort, PortProbe, Wait};
use crate::unit_stats::{Activity, UnitStats};

/// What a thread does next once its wait is over.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Next {
    Step,
    SendLeaf,
    Finish,
}

/// A thread's control state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    Free,
    /// Waiting for a step's data (memory) and its pipeline latency.
    Waiting {
        wait: Wait,
        not_before: u64,
        then: Next,
    },
    Ready,
    SendLeaf,
    AtIntersection,
    Finished,
}

/// One packet's registers.
struct Thread {
    state: State,
    index: u32,
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
    next_issue: usize,
    /// The node port.
    pub port: MemPort,
    /// Activity and SIMD lanes.
    pub stats: UnitStats,
    /// Rays received (active lanes of packets taken in).
    pub rays_in: u64,
    /// Rays sent on to shading.
    pub rays_out: u64,
}

impl TraversalUnit {
    /// A unit with `cfg.traversal.threads` free threads.
    pub fn new(id: usize, cfg: &HwConfig) -> TraversalUnit {
        let threads = (0..cfg.traversal.threads)
            .map(|_| Thread {
                state: State::Free,
                index: 0,
                traced: 0,
                live: 0,
                at_leaf: 0,
                rays: Box::new([NO_RAY; 64]),
                walks: vec![Walk::All { visited: true, best: None }; 64],
                leaves: [Leaf::All { count: 0 }; 64],
            })
            .collect();
        TraversalUnit {
            id,
            packet_size: cfg.packet_size as u64,
            step_latency: cfg.traversal.step_latency as u64,
            threads,
            next_issue: 0,
            port: MemPort::new(format!("traversal{id}"), &cfg.cache.nodes),
            stats: UnitStats::default(),
            rays_in: 0,
            rays_out: 0,
        }
    }

    /// True if no packet is in flight.
    pub fn is_empty(&self) -> bool {
        self.threads.iter().all(|t| t.state == State::Free)
    }

    /// One line describing the threads (for the watchdog).
    pub fn describe(&self) -> String {
        let count = |f: &dyn Fn(&State) -> bool| self.threads.iter().filter(|t| f(&t.state)).count();
        format!(
            "traversal{}: {} free, {} waiting, {} ready, {} to send to intersection, {} at intersection, {} finished",
            self.id,
            count(&|s| *s == State::Free),
            count(&|s| matches!(s, State::Waiting { .. })),
            count(&|s| *s == State::Ready),
            count(&|s| *s == State::SendLeaf),
            count(&|s| *s == State::AtIntersection),
            count(&|s| *s == State::Finished),
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
        if self.threads.iter().any(|t| t.state == State::AtIntersection) {
            if let Some(job) = results.pop() {
                if let Some(t) = self.threads.get_mut(job.thread as usize) {
                    for i in crate::lane_iter(job.lanes) {
                        *t.walks[i].best_mut() = job.best[i];
                        t.walks[i].finish_leaf();
                    }
                    t.at_leaf &= !job.lanes;
                    t.state = State::Ready;
                }
                moved = true;
            }
        }
        // A finished packet to shading.
        if let Some(k) = self.threads.iter().position(|t| t.state == State::Finished) {
            let t = &mut self.threads[k];
            let mut out = Box::new(HitPacket { index: t.index, lanes: t.traced, hits: [None; 64] });
            for i in crate::lane_iter(t.traced) {
                out.hits[i] = t.walks[i].best();
            }
            if hits.push(out).is_ok() {
                self.rays_out += lanes(t.traced);
                t.state = State::Free;
                moved = true;
            }
        }
        // A packet at its leaves to the intersection unit.
        if let Some(k) = self.threads.iter().position(|t| t.state == State::SendLeaf) {
            let t = &mut self.threads[k];
            let mut job = Box::new(LeafJob {
                thread: k as u8,
                lanes: t.at_leaf,
                leaves: t.leaves,
                rays: *t.rays,
                best: [None; 64],
            });
            for i in crate::lane_iter(t.at_leaf) {
                job.best[i] = t.walks[i].best();
            }
            if leaves.push(job).is_ok() {
                t.state = State::AtIntersection;
                moved = true;
            }
        }
        // A new packet into a free thread.
        if let Some(k) = self.threads.iter().position(|t| t.state == State::Free) {
            if let Some(job) = rays.pop() {
                let t = &mut self.threads[k];
                t.index = job.index;
                t.traced = job.lanes;
                t.live = job.lanes;
                t.at_leaf = 0;
                *t.rays = job.rays;
                for i in crate::lane_iter(job.lanes) {
                    t.walks[i] = Walk::start(scene, &job.rays[i]);
                }
                t.state = if job.lanes == 0 { State::Finished } else { State::Ready };
                self.rays_in += lanes(job.lanes);
                moved = true;
            }
        }
        // Steps whose data has arrived.
        for t in &mut self.threads {
            if let State::Waiting { wait, not_before, then } = t.state {
                if self.port.resolve(&wait).is_some_and(|r| r.max(not_before) <= now) {
                    t.state = match then {
                        Next::Step => State::Ready,
                        Next::SendLeaf => State::SendLeaf,
                        Next::Finish => State::Finished,
                    };
                }
            }
        }
        // Issue one step of one ready packet (round robin).
        let n = self.threads.len();
        let pick = (0..n).map(|k| (self.next_issue + k) % n).find(|&k| self.threads[k].state == State::Ready);
        let activity = if let Some(k) = pick {
            self.next_issue = (k + 1) % n;
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
            let then = if t.live & !t.at_leaf != 0 {
                Next::Step
            } else if t.at_leaf != 0 {
                Next::SendLeaf
            } else {
                Next::Finish
            };
            t.state = State::Waiting { wait: probe.wait, not_before: now + self.step_latency, then };
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
