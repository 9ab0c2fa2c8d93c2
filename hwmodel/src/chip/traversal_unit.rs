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
//! intersection unit; when the walk is over, to shading. In a two-level scene each ray
//! walks alone, and rays whose step handed out an instance go through the unit's
//! transformation unit ([`crate::chip::transform_unit`]) before the packet steps again.
//! The registers and the kernels a step runs are the thread's
//! ([`crate::chip::traversal_thread`]).
//!
//! Ports: `rays` in, `leaves` out, `results` in, `hits` out, and a memory port with a node
//! cache.

use std::collections::VecDeque;

use raypipe_core::traverse::boxes::datapath::{FloatNodes, NodeTests};
use raypipe_core::DataClass;
use serde::Serialize;

use crate::chip::fifo::Fifo;
use crate::chip::jobs::{lanes, HitPacket, LeafJob, RayPacketJob};
use crate::chip::scene::ChipScene;
use crate::chip::transform_unit::TransformUnit;
use crate::chip::traversal_thread::{Next, Thread};
use crate::config::HwConfig;
use crate::memory::port::{Fetch, MemPort, Recorder};
use crate::observe::stall::Stall;
use crate::observe::unit_stats::{Activity, UnitStats};

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
    /// Some of its rays entered instances: waiting for or in the transformation unit.
    Transforming = 5,
    SendLeaf = 6,
    AtIntersection = 7,
    Finished = 8,
}

const STATES: usize = 9;

/// Report names of the thread states.
pub const STATE_NAMES: [&str; STATES] = [
    "free",
    "ready",
    "fetching",
    "queued_for_datapath",
    "step_pipeline",
    "transforming",
    "send_leaf",
    "at_intersection",
    "finished",
];

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
    /// The transformation unit (two-level scenes).
    pub transform: TransformUnit,
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
        let threads = (0..n).map(|_| Thread::new()).collect();
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
            transform: TransformUnit::new(id, cfg),
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
        self.count(State::Free) as usize == self.threads.len() && self.transform.is_empty()
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
        let transform = self.transform.next_wake(now);
        fetching.chain(pipeline).chain(datapath).chain(transform).filter(|&w| w > now).min()
    }

    /// One line describing the threads (for the watchdog).
    pub fn describe(&self) -> String {
        let parts: Vec<String> =
            (0..STATES).map(|s| format!("{} {}", self.masks[s].count_ones(), STATE_NAMES[s])).collect();
        format!("traversal{}: {}; {}", self.id, parts.join(", "), self.transform.describe())
    }

    /// Issues one step of thread `k`: the kernels run now, their reads are recorded for
    /// the fetch; the result is used once they have arrived.
    fn issue(&mut self, k: usize, now: u64, scene: &ChipScene<'_>) {
        let t = &mut self.threads[k];
        let mut rec = Recorder::default();
        let tested = t.step(scene, &mut rec);
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
            Next::Transform => State::Transforming,
            Next::SendLeaf => State::SendLeaf,
            Next::Finish => State::Finished,
        }
    }

    /// Moves thread `k` on once its step's result is there; rays entering instances
    /// ask the transformation unit.
    fn advance(&mut self, k: usize) {
        let next = self.after_step(k);
        if next == State::Transforming {
            self.transform.request(k, lanes(self.threads[k].entering));
        }
        self.set(k, next);
    }

    /// One cycle. Returns true if anything moved.
    pub fn tick(
        &mut self,
        now: u64,
        scene: &ChipScene<'_>,
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
        moved |= self.transform_rays(now, scene);
        moved |= self.start_datapath(now);
        moved |= self.issue_step(now, scene);
        moved |= self.fetch_nodes(now);
        self.account(now);
        moved
    }

    /// A packet back from the intersection unit: its rays finish the leaf. Returns true
    /// if anything moved.
    fn take_results(&mut self, results: &mut Fifo<Box<LeafJob>>) -> bool {
        if self.masks[State::AtIntersection as usize] == 0 {
            return false;
        }
        let Some(job) = results.pop() else { return false };
        let k = job.thread as usize;
        if k < self.threads.len() {
            self.threads[k].take_results(&job);
            self.set(k, State::Ready);
        }
        true
    }

    /// A finished packet to shading. Returns true if anything moved.
    fn send_finished(&mut self, hits: &mut Fifo<Box<HitPacket>>) -> bool {
        let Some(k) = first_from(self.masks[State::Finished as usize], 0) else { return false };
        if !hits.can_push() {
            hits.note_full();
            return false;
        }
        let _ = hits.push(self.threads[k].hit_packet());
        self.set(k, State::Free);
        true
    }

    /// A packet at its leaves to the intersection unit. Returns true if anything moved.
    fn send_leaves(&mut self, leaves: &mut Fifo<Box<LeafJob>>) -> bool {
        let Some(k) = first_from(self.masks[State::SendLeaf as usize], 0) else { return false };
        if !leaves.can_push() {
            leaves.note_full();
            return false;
        }
        let _ = leaves.push(self.threads[k].leaf_job(k as u8));
        self.set(k, State::AtIntersection);
        true
    }

    /// A new packet into a free thread. Returns true if anything moved.
    fn take_packet(&mut self, scene: &ChipScene<'_>, rays: &mut Fifo<Box<RayPacketJob>>) -> bool {
        let Some(k) = first_from(self.masks[State::Free as usize], 0) else { return false };
        let Some(job) = rays.pop() else { return false };
        self.threads[k].start(scene, &job);
        self.set(k, if job.lanes == 0 { State::Finished } else { State::Ready });
        true
    }

    /// The transformation unit's cycle: a thread whose rays are in object space moves on.
    /// Returns true if anything moved.
    fn transform_rays(&mut self, now: u64, scene: &ChipScene<'_>) -> bool {
        let (done, moved) = self.transform.tick(now);
        if let Some(k) = done {
            let next = self.threads[k].entered(scene);
            self.threads[k].then = next;
            let state = self.after_step(k);
            self.set(k, state);
        }
        moved
    }

    /// Results out of the step pipeline. Returns true if anything moved.
    fn retire_steps(&mut self, now: u64) -> bool {
        let mut moved = false;
        for k in crate::lane_iter(self.masks[State::Pipeline as usize]) {
            if self.threads[k].result_at <= now {
                self.advance(k);
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
    fn issue_step(&mut self, now: u64, scene: &ChipScene<'_>) -> bool {
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
                    self.advance(k);
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
        } else if self.count(State::Transforming) > 0 {
            Stall::Transform
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
        self.transform.reset_stats();
    }

    /// Accounts `n` more cycles like the last one (the clock skipped them).
    pub fn repeat_last(&mut self, n: u64) {
        self.stats.repeat_last(n);
        self.transform.repeat_last(n);
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
