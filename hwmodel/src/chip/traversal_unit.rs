//! The traversal unit (SaarCOR's, Schmittler, Wald & Slusallek 2002; Wald & Slusallek
//! 2001 §7.3): `traversal.threads` packets in flight to hide memory latency, each a
//! thread with its registers.
//!
//! A packet in a tree shares one walk (core's `PacketWalk`: one node per step for the
//! whole packet, one stack): a step fetches that node once, and the rays that need it are
//! tested on a datapath of `traversal.lanes_per_cycle` ray–node tests per cycle, so a step
//! of `n` active rays occupies it `ceil(n / lanes_per_cycle)` cycles. A packet in the
//! uniform grid keeps per-ray lock-step (Purcell's 3D-DDA: its rays leave a voxel at
//! different distances), each ray stepping its own walk and reading its own cell.
//!
//! A step goes through three stages: *issue* (one per cycle; the core kernel runs and its
//! reads are recorded), *fetch* (the port replays the reads through the node cache), and
//! *test* once the data has arrived (the datapath, then `step_latency` cycles of pipeline).
//! Only then is its result used. When the packet stands at a leaf it goes to the coupled
//! intersection unit; when the walk is over, to shading.
//!
//! Ports: `rays` in, `leaves` out, `results` in, `hits` out, and a memory port with a node
//! cache.

use std::collections::VecDeque;

use raypipe_core::packet::step::{PacketEvent, PacketStep, PacketWalk};
use raypipe_core::traverse::boxes::datapath::{FloatNodes, NodeTests};
use raypipe_core::traverse::walk::{Leaf, Walk, WalkEvent};
use raypipe_core::{DataClass, Ray, SceneView};
use serde::Serialize;

use crate::chip::fifo::Fifo;
use crate::chip::jobs::{lanes, HitPacket, LeafJob, PacketCost, Query, RayPacketJob, NO_RAY};
use crate::config::HwConfig;
use crate::memory::port::{Fetch, MemPort, Recorder};
use crate::observe::stall::Stall;
use crate::observe::unit_stats::{Activity, UnitStats};

/// What a thread does once its step's result is there.
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
    /// Its next step may issue.
    Ready = 1,
    /// Its step's node data is being fetched.
    Fetching = 2,
    /// Its data is there; waiting for the datapath.
    Queued = 3,
    /// Its tests ran; the result is in the step pipeline.
    Pipeline = 4,
    SendLeaf = 5,
    AtIntersection = 6,
    Finished = 7,
}

const STATES: usize = 8;

/// Report names of the thread states.
pub const STATE_NAMES: [&str; STATES] =
    ["free", "ready", "fetching", "queued_for_datapath", "step_pipeline", "send_leaf", "at_intersection", "finished"];

/// The walk registers of one packet.
enum Regs<D: NodeTests> {
    /// A tree: one walk for the packet.
    Shared(Box<PacketWalk<64>>),
    /// The grid (or no structure), or any structure with a datapath whose box tests are
    /// not the packet walk's `f32` ones (fixed point): one walk per ray.
    PerRay(Vec<Walk<D>>),
}

/// One packet's registers (its control state is its bit in the unit's state masks).
struct Thread<D: NodeTests> {
    index: u32,
    query: Query,
    traced: u64,
    /// Lanes whose walk is not over (any-hit lanes leave at their first hit).
    live: u64,
    /// Lanes waiting at a leaf.
    at_leaf: u64,
    rays: Box<[Ray; 64]>,
    regs: Regs<D>,
    leaves: Box<[Leaf; 64]>,
    then: Next,
    fetch: Fetch,
    /// Ray–node tests of the step in flight.
    tested: u64,
    /// What the packet has cost so far.
    cost: Box<PacketCost>,
    data_at: u64,
    result_at: u64,
}

/// Counters of the traversal unit beyond activity.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct TraversalStats {
    /// Packet steps issued.
    pub steps: u64,
    /// Node records read by the steps' kernels (a shared packet step reads one).
    pub node_reads: u64,
    /// Cycles × threads in each state (`STATE_NAMES`).
    pub thread_state_cycles: [u64; STATES],
}

/// A traversal unit, whose datapath tests boxes with `D` (the `f32` tests, or the
/// fixed-point test: `raypipe_core::traverse::boxes::datapath`).
pub struct TraversalUnit<D: NodeTests = FloatNodes> {
    /// Unit number.
    pub id: usize,
    packet_size: u64,
    step_latency: u64,
    lanes_per_cycle: u64,
    threads: Vec<Thread<D>>,
    /// `masks[s]`: the threads in state `s`.
    masks: [u64; STATES],
    next_issue: u32,
    /// Threads whose data is there, oldest first.
    queued: VecDeque<usize>,
    /// The datapath runs tests until this cycle (exclusive).
    busy_until: u64,
    /// The node port.
    pub port: MemPort,
    /// Activity and SIMD lanes.
    pub stats: UnitStats,
    /// Steps, node reads, thread states.
    pub tstats: TraversalStats,
    last_states: [u64; STATES],
}

/// The lowest set bit of `mask` at or after `start` (wrapping), if any.
fn first_from(mask: u64, start: u32) -> Option<usize> {
    if mask == 0 {
        return None;
    }
    let rotated = mask.rotate_right(start);
    Some(((rotated.trailing_zeros() + start) % 64) as usize)
}

impl<D: NodeTests> TraversalUnit<D> {
    /// A unit with `cfg.traversal.threads` free threads (validated: 1 to 64).
    pub fn new(id: usize, cfg: &HwConfig) -> TraversalUnit<D> {
        let n = cfg.traversal.threads.clamp(1, 64) as usize;
        let threads = (0..n)
            .map(|_| Thread {
                index: 0,
                query: Query::Closest,
                traced: 0,
                live: 0,
                at_leaf: 0,
                rays: Box::new([NO_RAY; 64]),
                regs: Regs::PerRay(Vec::new()),
                leaves: Box::new([Leaf::All { count: 0 }; 64]),
                then: Next::Step,
                fetch: Fetch::default(),
                tested: 0,
                cost: Box::new(PacketCost::new(0)),
                data_at: 0,
                result_at: 0,
            })
            .collect();
        let mut masks = [0u64; STATES];
        masks[State::Free as usize] = if n == 64 { u64::MAX } else { (1u64 << n) - 1 };
        TraversalUnit {
            id,
            packet_size: cfg.packet_size as u64,
            step_latency: cfg.traversal.step_latency as u64,
            lanes_per_cycle: cfg.traversal.lanes_per_cycle.max(1) as u64,
            threads,
            masks,
            next_issue: 0,
            queued: VecDeque::new(),
            busy_until: 0,
            port: MemPort::new(format!("traversal{id}"), &cfg.cache.nodes, cfg.memory.port_staging()),
            stats: UnitStats::default(),
            tstats: TraversalStats::default(),
            last_states: [0; STATES],
        }
    }

    fn set(&mut self, k: usize, state: State) {
        let bit = 1u64 << k;
        for m in &mut self.masks {
            *m &= !bit;
        }
        self.masks[state as usize] |= bit;
    }

    fn count(&self, s: State) -> u32 {
        self.masks[s as usize].count_ones()
    }

    /// True if no packet is in flight.
    pub fn is_empty(&self) -> bool {
        self.count(State::Free) as usize == self.threads.len()
    }

    /// The first cycle after `now` at which time alone changes something (data arrives,
    /// an MSHR frees, the datapath frees, a result leaves the pipeline); `None` if only
    /// FIFO traffic can.
    pub fn next_wake(&self, now: u64) -> Option<u64> {
        let fetching = crate::lane_iter(self.masks[State::Fetching as usize])
            .filter_map(|k| self.port.wake_of(&self.threads[k].fetch, now));
        let pipeline = crate::lane_iter(self.masks[State::Pipeline as usize]).map(|k| self.threads[k].result_at);
        // The datapath's end frees it for a queued step and changes the unit's activity.
        let datapath = Some(self.busy_until);
        fetching.chain(pipeline).chain(datapath).filter(|&w| w > now).min()
    }

    /// One line describing the threads (for the watchdog).
    pub fn describe(&self) -> String {
        let parts: Vec<String> =
            (0..STATES).map(|s| format!("{} {}", self.masks[s].count_ones(), STATE_NAMES[s])).collect();
        format!("traversal{}: {}", self.id, parts.join(", "))
    }

    /// Sets up thread `k` for a new packet.
    fn start(&mut self, k: usize, scene: &SceneView<'_>, job: &RayPacketJob) {
        let t = &mut self.threads[k];
        t.index = job.index;
        *t.cost = PacketCost::new(job.issued);
        t.query = job.query;
        t.traced = job.lanes;
        t.live = job.lanes;
        t.at_leaf = 0;
        *t.rays = job.rays;
        // The packet walk's box tests are f32: another datapath walks each ray alone.
        let shared = if D::FLOAT { PacketWalk::<64>::start(scene, &job.rays, job.lanes) } else { None };
        t.regs = match shared {
            Some(w) => Regs::Shared(Box::new(w)),
            None => {
                let mut walks = match std::mem::replace(&mut t.regs, Regs::PerRay(Vec::new())) {
                    Regs::PerRay(w) if w.len() == 64 => w,
                    _ => vec![Walk::All { visited: true, best: None }; 64],
                };
                for i in crate::lane_iter(job.lanes) {
                    walks[i] = Walk::start(scene, &job.rays[i]);
                }
                Regs::PerRay(walks)
            }
        };
    }

    /// Issues one step of thread `k`: the kernel runs now, its reads are recorded for the
    /// fetch; its result is used once they have arrived.
    fn issue(&mut self, k: usize, now: u64, scene: &SceneView<'_>) {
        let t = &mut self.threads[k];
        let mut rec = Recorder::default();
        let mut tested = 0u64;
        match &mut t.regs {
            Regs::Shared(w) => match w.step(scene, &t.rays[..], &mut rec) {
                PacketEvent::Node { lanes } => {
                    tested = lanes;
                    t.then = Next::Step;
                }
                PacketEvent::Leaf { leaf, lanes } => {
                    let at = lanes & t.live;
                    if at == 0 {
                        // Every ray here is blocked (any-hit): nothing to intersect.
                        w.finish_leaf();
                        t.then = Next::Step;
                    } else {
                        for i in crate::lane_iter(at) {
                            t.leaves[i] = leaf;
                        }
                        t.at_leaf = at;
                        t.then = Next::SendLeaf;
                    }
                }
                PacketEvent::Done => t.then = Next::Finish,
            },
            Regs::PerRay(walks) => {
                let stepping = t.live & !t.at_leaf;
                for i in crate::lane_iter(stepping) {
                    rec.at_level(0);
                    match walks[i].step(scene, &t.rays[i], &mut rec) {
                        WalkEvent::Inner => {}
                        WalkEvent::Leaf(leaf) => {
                            t.leaves[i] = leaf;
                            t.at_leaf |= 1 << i;
                        }
                        WalkEvent::Done => t.live &= !(1 << i),
                    }
                }
                tested = stepping;
                t.then = if t.live & !t.at_leaf != 0 {
                    Next::Step
                } else if t.at_leaf != 0 {
                    Next::SendLeaf
                } else {
                    Next::Finish
                };
            }
        }
        self.tstats.steps += 1;
        for i in crate::lane_iter(tested) {
            t.cost.steps[i] += 1;
        }
        t.cost.bytes += rec.reads().map(|a| a.bytes as u64).sum::<u64>();
        self.tstats.node_reads += rec.reads().filter(|a| a.class == DataClass::Nodes as usize).count() as u64;
        if tested != 0 {
            self.stats.issue(lanes(tested), self.packet_size);
        }
        t.tested = tested;
        t.fetch = Fetch::new(rec.into_levels());
        t.data_at = now;
        self.set(k, State::Fetching);
    }

    /// The state a thread goes to once its step's result is there.
    fn after_step(&self, k: usize) -> State {
        match self.threads[k].then {
            Next::Step => State::Ready,
            Next::SendLeaf => State::SendLeaf,
            Next::Finish => State::Finished,
        }
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
        // The stages in the order their effects must be seen within a cycle.
        let mut moved = self.take_results(results);
        moved |= self.send_finished(hits);
        moved |= self.send_leaves(leaves);
        moved |= self.take_packet(scene, rays);
        moved |= self.retire_steps(now);
        moved |= self.start_datapath(now);
        moved |= self.issue_step(now, scene);
        moved |= self.fetch_nodes(now);
        self.account(now);
        moved
    }

    /// A packet back from the intersection unit: its rays finish the leaf. Returns true if anything moved.
    fn take_results(&mut self, results: &mut Fifo<Box<LeafJob>>) -> bool {
        let mut moved = false;
        if self.masks[State::AtIntersection as usize] != 0 {
            if let Some(job) = results.pop() {
                let k = job.thread as usize;
                if k < self.threads.len() {
                    let t = &mut self.threads[k];
                    for i in crate::lane_iter(job.lanes) {
                        t.cost.tests[i] += job.tests[i];
                    }
                    t.cost.bytes += job.bytes;
                    match &mut t.regs {
                        Regs::Shared(w) => {
                            for i in crate::lane_iter(job.lanes) {
                                if let Some(b) = w.best_mut(i) {
                                    *b = job.best[i];
                                }
                                if t.query == Query::AnyHit && job.best[i].is_some() {
                                    t.live &= !(1 << i);
                                }
                            }
                            w.finish_leaf();
                        }
                        Regs::PerRay(walks) => {
                            for i in crate::lane_iter(job.lanes) {
                                *walks[i].best_mut() = job.best[i];
                                if t.query == Query::AnyHit && job.best[i].is_some() {
                                    // Blocked: a shadow ray needs no more of the walk.
                                    t.live &= !(1 << i);
                                } else {
                                    walks[i].finish_leaf();
                                }
                            }
                        }
                    }
                    t.at_leaf &= !job.lanes;
                    self.set(k, State::Ready);
                }
                moved = true;
            }
        }
        moved
    }

    /// A finished packet to shading. Returns true if anything moved.
    fn send_finished(&mut self, hits: &mut Fifo<Box<HitPacket>>) -> bool {
        let mut moved = false;
        if let Some(k) = first_from(self.masks[State::Finished as usize], 0) {
            if hits.can_push() {
                let t = &self.threads[k];
                let cost = t.cost.clone();
                let mut out = Box::new(HitPacket { index: t.index, lanes: t.traced, hits: [None; 64], cost });
                for i in crate::lane_iter(t.traced) {
                    out.hits[i] = match &t.regs {
                        Regs::Shared(w) => w.best(i),
                        Regs::PerRay(walks) => walks[i].best(),
                    };
                }
                let _ = hits.push(out);
                self.set(k, State::Free);
                moved = true;
            } else {
                hits.note_full();
            }
        }
        moved
    }

    /// A packet at its leaves to the intersection unit. Returns true if anything moved.
    fn send_leaves(&mut self, leaves: &mut Fifo<Box<LeafJob>>) -> bool {
        let mut moved = false;
        if let Some(k) = first_from(self.masks[State::SendLeaf as usize], 0) {
            if leaves.can_push() {
                let t = &self.threads[k];
                let mut job = Box::new(LeafJob {
                    packet: t.index,
                    thread: k as u8,
                    lanes: t.at_leaf,
                    query: t.query,
                    leaves: *t.leaves,
                    rays: *t.rays,
                    best: [None; 64],
                    tests: [0; 64],
                    bytes: 0,
                });
                for i in crate::lane_iter(t.at_leaf) {
                    job.best[i] = match &t.regs {
                        Regs::Shared(w) => w.best(i),
                        Regs::PerRay(walks) => walks[i].best(),
                    };
                }
                let _ = leaves.push(job);
                self.set(k, State::AtIntersection);
                moved = true;
            } else {
                leaves.note_full();
            }
        }
        moved
    }

    /// A new packet into a free thread. Returns true if anything moved.
    fn take_packet(&mut self, scene: &SceneView<'_>, rays: &mut Fifo<Box<RayPacketJob>>) -> bool {
        let mut moved = false;
        if let Some(k) = first_from(self.masks[State::Free as usize], 0) {
            if let Some(job) = rays.pop() {
                self.start(k, scene, &job);
                self.set(k, if job.lanes == 0 { State::Finished } else { State::Ready });
                moved = true;
            }
        }
        moved
    }

    /// Results out of the step pipeline. Returns true if anything moved.
    fn retire_steps(&mut self, now: u64) -> bool {
        let mut moved = false;
        for k in crate::lane_iter(self.masks[State::Pipeline as usize]) {
            if self.threads[k].result_at <= now {
                let next = self.after_step(k);
                self.set(k, next);
                moved = true;
            }
        }
        moved
    }

    /// The datapath takes the oldest step whose data is there. Returns true if anything moved.
    fn start_datapath(&mut self, now: u64) -> bool {
        let mut moved = false;
        if self.busy_until <= now {
            if let Some(k) = self.queued.pop_front() {
                let t = &mut self.threads[k];
                debug_assert!(t.data_at <= now, "a step tested before its node arrived");
                let cycles = t.tested.count_ones().max(1) as u64;
                let cycles = cycles.div_ceil(self.lanes_per_cycle);
                self.busy_until = now + cycles;
                t.result_at = now + cycles - 1 + self.step_latency;
                self.set(k, State::Pipeline);
                moved = true;
            }
        }
        moved
    }

    /// Issue one step of one ready packet (round robin). Returns true if anything moved.
    fn issue_step(&mut self, now: u64, scene: &SceneView<'_>) -> bool {
        let mut moved = false;
        if let Some(k) = first_from(self.masks[State::Ready as usize], self.next_issue) {
            self.next_issue = (k as u32 + 1) % 64;
            self.issue(k, now, scene);
            moved = true;
        }
        moved
    }

    /// Fetches: lookups while the port has them, oldest thread first. Returns true if anything moved.
    fn fetch_nodes(&mut self, now: u64) -> bool {
        let mut moved = false;
        for k in crate::lane_iter(self.masks[State::Fetching as usize]) {
            let (progress, data) = self.port.step_fetch(&mut self.threads[k].fetch, now);
            moved |= progress;
            if let Some(at) = data {
                self.threads[k].data_at = at;
                if self.threads[k].tested != 0 {
                    self.queued.push_back(k);
                    self.set(k, State::Queued);
                } else {
                    let next = self.after_step(k);
                    self.set(k, next);
                }
                moved = true;
            }
        }
        moved
    }

    /// The cycle's accounting: activity and threads by state.
    fn account(&mut self, now: u64) {
        let activity = if self.busy_until > now {
            Activity::Busy
        } else if self.is_empty() {
            Activity::Idle
        } else {
            Activity::Stalled(self.stall_reason())
        };
        self.stats.cycle(activity);
        for s in 0..STATES {
            self.last_states[s] = self.masks[s].count_ones() as u64;
            self.tstats.thread_state_cycles[s] += self.last_states[s];
        }
    }

    /// Why the unit stalls this cycle: what its waiting work waits for, memory first.
    fn stall_reason(&self) -> Stall {
        let mut memory: Option<Stall> = None;
        for k in crate::lane_iter(self.masks[State::Fetching as usize]) {
            let f = &self.threads[k].fetch;
            let r = self.port.stall_of(f, Stall::NodeData);
            // Rank: an MSHR or the queue says more than "waiting for data".
            memory = Some(match memory {
                Some(m) if rank(m) >= rank(r) => m,
                _ => r,
            });
        }
        if let Some(m) = memory {
            m
        } else if self.count(State::Pipeline) + self.count(State::Queued) > 0 {
            Stall::StepLatency
        } else if self.count(State::Ready) > 0 {
            Stall::IssueSlot
        } else if self.count(State::SendLeaf) + self.count(State::Finished) > 0 {
            Stall::OutputFull
        } else {
            Stall::AtIntersection
        }
    }

    /// Threads in each state (`STATE_NAMES`) at the last tick.
    pub fn thread_states(&self) -> [u64; STATES] {
        self.last_states
    }

    /// Zeroes the statistics (threads, caches and memory keep their state).
    pub fn reset_stats(&mut self) {
        self.stats.reset();
        self.tstats = TraversalStats::default();
        self.port.reset_stats();
    }

    /// Accounts `n` more cycles like the last one (the clock skipped them).
    pub fn repeat_last(&mut self, n: u64) {
        self.stats.repeat_last(n);
        for s in 0..STATES {
            self.tstats.thread_state_cycles[s] += n * self.last_states[s];
        }
    }
}

/// Rank of memory stall reasons (higher is reported first).
fn rank(s: Stall) -> u8 {
    match s {
        Stall::Mshr => 4,
        Stall::MemoryQueue => 3,
        Stall::CachePort => 2,
        _ => 1,
    }
}
