//! The list and intersection unit coupled to one traversal unit: it takes a packet
//! standing at leaves, reads each lane's primitive list and triangles through its cache,
//! and runs core's ray–triangle kernel for every (lane, triangle) pair through a
//! pipelined datapath (one test enters every `initiation_interval` cycles, results leave
//! `latency` cycles later); the packet goes back with each lane's closest hit updated.
//!
//! Ports: `leaves` in, `results` out, and a memory port with a list/triangle cache.

use std::marker::PhantomData;

use raypipe_core::intersect::triangle::Intersector;
use raypipe_core::{DataClass, SceneView};

use crate::config::HwConfig;
use crate::fifo::Fifo;
use crate::jobs::{lanes, LeafJob, Query};
use crate::mem_port::{MemPort, PortProbe, Wait};
use crate::unit_stats::{Activity, UnitStats};

/// The job in the datapath.
struct Current {
    job: Box<LeafJob>,
    wait: Wait,
    /// The cycle the last test enters the pipeline.
    last_issue: u64,
    /// When the results are out (known once the data's arrival is).
    done_at: Option<u64>,
}

/// A list and intersection unit.
pub struct IntersectionUnit<I: Intersector> {
    /// Unit number (that of its traversal unit).
    pub id: usize,
    packet_size: u64,
    latency: u64,
    interval: u64,
    current: Option<Current>,
    /// The list/triangle port.
    pub port: MemPort,
    /// Activity and SIMD lanes.
    pub stats: UnitStats,
    /// Ray–triangle tests run.
    pub tests: u64,
    _kernel: PhantomData<I>,
}

impl<I: Intersector> IntersectionUnit<I> {
    /// An idle unit.
    pub fn new(id: usize, cfg: &HwConfig) -> IntersectionUnit<I> {
        IntersectionUnit {
            id,
            packet_size: cfg.packet_size as u64,
            latency: cfg.intersection.latency as u64,
            interval: cfg.intersection.initiation_interval as u64,
            current: None,
            port: {
                let name = format!("intersection{id}");
                let (lists, triangles) = (DataClass::PrimLists as usize, DataClass::Triangles as usize);
                if cfg.cache.lists_share_triangle_cache {
                    MemPort::with_caches(name.clone(), &[(name, &cfg.cache.triangles, &[lists, triangles])])
                } else {
                    MemPort::with_caches(
                        name.clone(),
                        &[
                            (format!("{name}.lists"), &cfg.cache.lists, &[lists]),
                            (format!("{name}.triangles"), &cfg.cache.triangles, &[triangles]),
                        ],
                    )
                }
            },
            stats: UnitStats::default(),
            tests: 0,
            _kernel: PhantomData,
        }
    }

    /// True if no job is in the datapath.
    pub fn is_empty(&self) -> bool {
        self.current.is_none()
    }

    /// The first cycle after `now` at which time alone changes something (the last test
    /// entered, the results are out); `None` if only FIFO traffic can.
    pub fn next_wake(&self, now: u64) -> Option<u64> {
        let c = self.current.as_ref()?;
        let done = c.done_at.or_else(|| self.port.resolve(&c.wait).map(|r| c.last_issue.max(r) + self.latency));
        [Some(c.last_issue + 1), done.or(Some(now + 1))].into_iter().flatten().filter(|&w| w > now).min()
    }

    /// One line describing the datapath (for the watchdog).
    pub fn describe(&self) -> String {
        match &self.current {
            None => format!("intersection{}: idle", self.id),
            Some(c) => format!(
                "intersection{}: job of {} lanes, data {}, done at {}",
                self.id,
                lanes(c.job.lanes),
                if self.port.resolve(&c.wait).is_some() { "scheduled" } else { "requested" },
                c.done_at.map_or("?".to_string(), |d| d.to_string())
            ),
        }
    }

    /// One cycle. Returns true if anything moved.
    pub fn tick(
        &mut self,
        now: u64,
        scene: &SceneView<'_>,
        leaves: &mut Fifo<Box<LeafJob>>,
        results: &mut Fifo<Box<LeafJob>>,
    ) -> bool {
        let mut moved = false;
        let mut issued = false;
        if let Some(cur) = self.current.as_mut() {
            if cur.done_at.is_none() {
                if let Some(arrived) = self.port.resolve(&cur.wait) {
                    // A test can enter once its data is there; the last result leaves
                    // `latency` cycles after the last test entered.
                    cur.done_at = Some(cur.last_issue.max(arrived) + self.latency);
                    moved = true;
                }
            }
            if cur.done_at.is_some_and(|d| d <= now) {
                if let Some(c) = self.current.take() {
                    match results.push(c.job) {
                        Ok(()) => moved = true,
                        Err(job) => self.current = Some(Current { job, ..c }),
                    }
                }
            }
        }
        if self.current.is_none() {
            if let Some(mut job) = leaves.pop() {
                let mut probe = PortProbe { port: &mut self.port, now, wait: Wait::default() };
                let mut tests = 0u64;
                let any_hit = job.query == Query::AnyHit;
                for i in crate::lane_iter(job.lanes) {
                    let ray = job.rays[i];
                    let prep = I::prepare(&ray);
                    let leaf = job.leaves[i];
                    tests += leaf.test::<I, _>(scene, &prep, &ray, any_hit, &mut job.best[i], &mut probe) as u64;
                }
                self.tests += tests;
                self.stats.issue(lanes(job.lanes), self.packet_size);
                let last_issue = now + tests.saturating_sub(1) * self.interval;
                self.current = Some(Current { job, wait: probe.wait, last_issue, done_at: None });
                moved = true;
                issued = true;
            }
        }
        let activity = match &self.current {
            _ if issued => Activity::Busy,
            None => Activity::Idle,
            // Tests still entering the pipeline.
            Some(c) if now <= c.last_issue => Activity::Busy,
            Some(_) => Activity::Stalled,
        };
        self.stats.cycle(activity);
        moved
    }
}
