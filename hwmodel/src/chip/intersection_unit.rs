//! The list and intersection unit coupled to one traversal unit: it takes a packet
//! standing at leaves and runs it as stages — list fetch, triangle fetch, vertex fetch
//! (each dependent level its own round trip through the list/triangle cache), then the
//! test pipeline: groups of `lanes_per_cycle` ray–triangle tests enter every
//! `initiation_interval` cycles and leave `latency` cycles later. Up to
//! `intersection.jobs` packets are in flight at once, so one packet's memory wait
//! overlaps another's tests. A leaf shared by several rays (a packet's shared walk) is
//! fetched once for all of them; each triangle once per job. In a two-level scene each
//! lane's leaf and rays are its instance's bottom image's, read at that image's address.
//!
//! Ports: `leaves` in, `results` out, and a memory port with a list/triangle cache.

use std::marker::PhantomData;

use raypipe_core::intersect::triangle::Intersector;
use raypipe_core::traverse::walk::{test_fetched, Leaf};
use raypipe_core::DataClass;

use crate::chip::fifo::Fifo;
use crate::chip::jobs::{lanes, LeafJob, Query};
use crate::chip::scene::ChipScene;
use crate::config::HwConfig;
use crate::memory::port::{Fetch, MemPort, Recorder};
use crate::observe::stall::Stall;
use crate::observe::unit_stats::{Activity, UnitStats};

/// Where a job stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    /// Its lists, triangles and vertices are being fetched.
    Fetching,
    /// Its data is there; waiting for the datapath.
    Queued,
    /// Its tests entered the pipeline; the last result leaves at the cycle.
    Pipeline(u64),
}

/// A job in the unit.
struct Job {
    job: Box<LeafJob>,
    fetch: Fetch,
    stage: Stage,
    /// Ray–triangle tests the job runs.
    tests: u64,
    data_at: u64,
}

/// A list and intersection unit.
pub struct IntersectionUnit<I: Intersector> {
    /// Unit number (that of its traversal unit).
    pub id: usize,
    packet_size: u64,
    latency: u64,
    interval: u64,
    lanes_per_cycle: u64,
    max_jobs: usize,
    /// The jobs, oldest first (to the datapath and out in that order).
    jobs: Vec<Job>,
    /// Test groups enter the pipeline until this cycle (exclusive).
    busy_until: u64,
    /// The list/triangle port.
    pub port: MemPort,
    /// Activity and SIMD lanes.
    pub stats: UnitStats,
    /// Ray–triangle tests run.
    pub tests: u64,
    _kernel: PhantomData<I>,
}

impl<I: Intersector> IntersectionUnit<I> {
    /// Zeroes the statistics (jobs, caches and memory keep their state).
    pub fn reset_stats(&mut self) {
        self.stats.reset();
        self.tests = 0;
        self.port.reset_stats();
    }

    /// An idle unit.
    pub fn new(id: usize, cfg: &HwConfig) -> IntersectionUnit<I> {
        let q = cfg.memory.port_staging();
        IntersectionUnit {
            id,
            packet_size: cfg.packet_size as u64,
            latency: cfg.intersection.latency as u64,
            interval: cfg.intersection.initiation_interval.max(1) as u64,
            lanes_per_cycle: cfg.intersection.lanes_per_cycle.max(1) as u64,
            max_jobs: cfg.intersection.jobs.max(1) as usize,
            jobs: Vec::new(),
            busy_until: 0,
            port: {
                let name = format!("intersection{id}");
                let (lists, triangles) = (DataClass::PrimLists as usize, DataClass::Triangles as usize);
                if cfg.cache.lists_share_triangle_cache {
                    MemPort::with_caches(name.clone(), &[(name, &cfg.cache.triangles, &[lists, triangles])], q)
                } else {
                    MemPort::with_caches(
                        name.clone(),
                        &[
                            (format!("{name}.triangles"), &cfg.cache.triangles, &[triangles]),
                            (format!("{name}.lists"), &cfg.cache.lists, &[lists]),
                        ],
                        q,
                    )
                }
            },
            stats: UnitStats::default(),
            tests: 0,
            _kernel: PhantomData,
        }
    }

    /// True if no job is in the unit.
    pub fn is_empty(&self) -> bool {
        self.jobs.is_empty()
    }

    /// The first cycle after `now` at which time alone changes something.
    pub fn next_wake(&self, now: u64) -> Option<u64> {
        // The datapath's end changes the unit's activity (busy to stalled) as well.
        self.jobs
            .iter()
            .filter_map(|j| match j.stage {
                Stage::Fetching => self.port.wake_of(&j.fetch, now),
                Stage::Pipeline(done) => Some(done),
                Stage::Queued => None,
            })
            .chain(Some(self.busy_until))
            .filter(|&w| w > now)
            .min()
    }

    /// One line describing the unit (for the watchdog).
    pub fn describe(&self) -> String {
        let n = |s: fn(&Stage) -> bool| self.jobs.iter().filter(|j| s(&j.stage)).count();
        format!(
            "intersection{}: {} jobs fetching, {} queued, {} in the pipeline",
            self.id,
            n(|s| *s == Stage::Fetching),
            n(|s| *s == Stage::Queued),
            n(|s| matches!(s, Stage::Pipeline(_)))
        )
    }

    /// Runs a job's kernels at once (functional first) and records its reads by level:
    /// list entries, then each distinct triangle's record and its vertices.
    fn accept(&mut self, scene: &ChipScene<'_>, mut job: Box<LeafJob>, now: u64) -> Job {
        let mut rec = Recorder::default();
        // Distinct leaves (of distinct bottoms) and the rays at each.
        let mut groups: Vec<((u32, Leaf), u64)> = Vec::new();
        for i in crate::lane_iter(job.lanes) {
            let key = (job.bottoms[i], job.leaves[i]);
            match groups.iter_mut().find(|(l, _)| *l == key) {
                Some((_, m)) => *m |= 1 << i,
                None => groups.push((key, 1 << i)),
            }
        }
        let mut tris: Vec<((u32, u32), I::Triangle)> = Vec::new();
        let any_hit = job.query == Query::AnyHit;
        let mut tests = 0u64;
        for ((bottom, leaf), mask) in groups {
            let (view, base) = match scene {
                ChipScene::Flat(v) => (v, 0),
                ChipScene::Instanced(s) => match s.bottom(bottom) {
                    Some(b) => b,
                    None => continue,
                },
            };
            rec.base = base;
            let mut prims = Vec::new();
            let mut k = 0;
            loop {
                rec.at_level(0);
                let Some(prim) = leaf.entry(view, k, &mut rec) else { break };
                prims.push(prim);
                k += 1;
            }
            for &prim in &prims {
                if !tris.iter().any(|(p, _)| *p == (bottom, prim)) {
                    rec.at_level(1);
                    tris.push(((bottom, prim), I::fetch(view, prim, &mut rec)));
                }
            }
            for i in crate::lane_iter(mask) {
                let ray = job.rays[i];
                let prep = I::prepare(&ray);
                for &prim in &prims {
                    let Some((_, tri)) = tris.iter().find(|(p, _)| *p == (bottom, prim)) else { continue };
                    tests += 1;
                    job.tests[i] += 1;
                    if test_fetched::<I>(&prep, &ray, any_hit, tri, prim, &mut job.best[i]) {
                        break;
                    }
                }
            }
        }
        self.tests += tests;
        job.bytes = rec.reads().map(|a| a.bytes as u64).sum();
        self.stats.issue(lanes(job.lanes), self.packet_size);
        Job { job, fetch: Fetch::new(rec.into_levels()), stage: Stage::Fetching, tests, data_at: now }
    }

    /// One cycle. Returns true if anything moved.
    pub fn tick(
        &mut self,
        now: u64,
        scene: &ChipScene<'_>,
        leaves: &mut Fifo<Box<LeafJob>>,
        results: &mut Fifo<Box<LeafJob>>,
    ) -> bool {
        let mut moved = false;
        // The oldest job whose results are out goes back (one per cycle).
        let done = self.jobs.iter().position(|j| matches!(j.stage, Stage::Pipeline(d) if d <= now));
        let mut output_blocked = false;
        if let Some(k) = done {
            if results.can_push() {
                let j = self.jobs.remove(k);
                let _ = results.push(j.job);
                moved = true;
            } else {
                results.note_full();
                output_blocked = true;
            }
        }
        // The datapath takes the oldest job whose data is there.
        if self.busy_until <= now {
            let next = self.jobs.iter().position(|j| j.stage == Stage::Queued);
            if let Some(k) = next {
                let j = &mut self.jobs[k];
                debug_assert!(j.data_at <= now, "triangles tested before their data arrived");
                let groups = j.tests.div_ceil(self.lanes_per_cycle).max(1);
                self.busy_until = now + groups * self.interval;
                j.stage = Stage::Pipeline(now + (groups - 1) * self.interval + self.latency);
                moved = true;
            }
        }
        // A new job, if there is room.
        if self.jobs.len() < self.max_jobs {
            if let Some(job) = leaves.pop() {
                let j = self.accept(scene, job, now);
                self.jobs.push(j);
                moved = true;
            }
        }
        // Fetches, oldest job first.
        // Jobs are kept oldest first.
        for j in self.jobs.iter_mut().filter(|j| j.stage == Stage::Fetching) {
            let (progress, data) = self.port.step_fetch(&mut j.fetch, now);
            moved |= progress;
            if let Some(at) = data {
                j.data_at = at;
                j.stage = Stage::Queued;
                moved = true;
            }
        }
        let activity = if self.busy_until > now {
            Activity::Busy
        } else if self.jobs.is_empty() {
            Activity::Idle
        } else {
            Activity::Stalled(self.stall_reason(output_blocked))
        };
        self.stats.cycle(activity);
        moved
    }

    fn stall_reason(&self, output_blocked: bool) -> Stall {
        let fetching = self.jobs.iter().find(|j| j.stage == Stage::Fetching);
        if let Some(j) = fetching {
            return self.port.stall_of(&j.fetch, Stall::TriangleData);
        }
        if output_blocked {
            Stall::OutputFull
        } else {
            Stall::PipelineLatency
        }
    }
}
