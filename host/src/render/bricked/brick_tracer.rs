//! Tracing rays through a bricked scene with a brick cache, hiding the loads' latency
//! as Wald & Slusallek 2001 §6.3 do: every ray walks the top level until it needs a
//! brick, rays are grouped by the brick they wait for, groups whose brick is resident
//! are traced (one by one or as packets) while the missing bricks load, and a ray whose
//! brick is missing stays parked — its [`TopWalk`] is plain data — until it arrives.
//! The tracer waits only when every ray it holds is parked.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Result;
use raypipe_core::image::bricked::BrickedView;
use raypipe_core::packet::{PacketCounters, RayPacket};
use raypipe_core::traverse::occlusion::occluded;
use raypipe_core::traverse::two_level::{BrickHit, TopEvent, TopWalk};
use raypipe_core::{Intersector, NoProbe, Ray, RayCounters, SceneView};

use super::brick_cache::BrickCache;
use crate::input::bricked::ResidentBrick;
use crate::platform::isa::with_avx2;
use crate::render::packets::PacketSize;
use crate::render::tracer::{trace, trace_packet};

/// What the tracer did, besides the cache's own counts.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TraceStats {
    /// Rays traced.
    pub rays: u64,
    /// Brick visits (a ray traced through one brick).
    pub brick_visits: u64,
    /// Top-level nodes visited.
    pub top_steps: u64,
    /// Nodes (or voxels) visited inside bricks.
    pub steps: u64,
    /// Ray–triangle tests.
    pub tests: u64,
    /// Ray-seconds spent parked on a missing brick (summed over rays).
    pub parked_ray_seconds: f64,
    /// Seconds the tracer had nothing to do (every ray it held was parked).
    pub idle_seconds: f64,
}

impl TraceStats {
    /// Adds another tracer's counts.
    pub fn add(&mut self, o: &TraceStats) {
        self.rays += o.rays;
        self.brick_visits += o.brick_visits;
        self.top_steps += o.top_steps;
        self.steps += o.steps;
        self.tests += o.tests;
        self.parked_ray_seconds += o.parked_ray_seconds;
        self.idle_seconds += o.idle_seconds;
    }
}

/// Work waiting for one brick.
struct Group<T> {
    items: Vec<T>,
    since: Instant,
    waited: bool,
}

/// One worker's tracer over a bricked scene.
pub struct BrickTracer<'c, 's> {
    cache: &'c BrickCache<'s>,
    index: &'c BrickedView<'s>,
    packet: PacketSize,
    /// What it did so far.
    pub stats: TraceStats,
    /// The bricks it asked the cache for (a set: sorted, each once).
    touched: BTreeSet<u32>,
}

impl<'c, 's> BrickTracer<'c, 's> {
    /// A tracer drawing bricks from `cache` (of the scene `index` describes), tracing
    /// each brick's rays as `packet` says.
    pub fn new(cache: &'c BrickCache<'s>, index: &'c BrickedView<'s>, packet: PacketSize) -> Self {
        BrickTracer { cache, index, packet, stats: TraceStats::default(), touched: BTreeSet::new() }
    }

    /// Brick `b` from the cache, pinned, if resident (else queued); noted as touched.
    fn get(&mut self, b: u32) -> Option<Arc<ResidentBrick>> {
        self.touched.insert(b);
        self.cache.get(b)
    }

    /// The bricks it needed, in order: a distributed run's record of a tile's working
    /// set, from which a cluster model replays other workers' caches.
    pub fn touched(&self) -> Vec<u32> {
        self.touched.iter().copied().collect()
    }

    /// Hands each group of `pending` to `visit` once its brick is resident, with the
    /// brick's view; `visit` may queue more work on any brick. Returns when no work is
    /// left, or with the first load error.
    pub fn grouped<T>(
        &mut self,
        work: Vec<(u32, T)>,
        mut visit: impl FnMut(&mut Self, &SceneView<'_>, Vec<T>, &mut Vec<(u32, T)>),
    ) -> Result<()> {
        let mut pending: BTreeMap<u32, Group<T>> = BTreeMap::new();
        let now = Instant::now();
        for (b, item) in work {
            pending.entry(b).or_insert_with(|| Group { items: Vec::new(), since: now, waited: false }).items.push(item);
        }
        let mut seen = self.cache.generation();
        while !pending.is_empty() {
            let mut progressed = false;
            let keys: Vec<u32> = pending.keys().copied().collect();
            for b in keys {
                let Some(brick) = self.get(b) else {
                    if let Some(g) = pending.get_mut(&b) {
                        g.waited = true;
                    }
                    continue;
                };
                let Some(g) = pending.remove(&b) else { continue };
                if g.waited {
                    self.stats.parked_ray_seconds += g.since.elapsed().as_secs_f64() * g.items.len() as f64;
                }
                let mut more = Vec::new();
                visit(self, brick.view(), g.items, &mut more);
                drop(brick);
                self.cache.released();
                let now = Instant::now();
                for (b, item) in more {
                    pending
                        .entry(b)
                        .or_insert_with(|| Group { items: Vec::new(), since: now, waited: false })
                        .items
                        .push(item);
                }
                progressed = true;
            }
            if !progressed {
                let t = Instant::now();
                self.cache.wait(&mut seen, Duration::from_millis(20))?;
                self.stats.idle_seconds += t.elapsed().as_secs_f64();
            }
        }
        Ok(())
    }

    /// The scene's index.
    pub fn index(&self) -> &'c BrickedView<'s> {
        self.index
    }

    /// Steps `walk` until it needs a brick (returned) or ends (`None`).
    fn advance(&mut self, walk: &mut TopWalk) -> Option<u32> {
        loop {
            match walk.step(self.index, &mut NoProbe) {
                TopEvent::Inner => self.stats.top_steps += 1,
                TopEvent::Brick(b) => return Some(b),
                TopEvent::Done => return None,
            }
        }
    }

    /// Traces `rays` (closest hit, or any hit for the rays whose `any_hit` is set) to
    /// the end; returns each ray's hit. For an any-hit ray the hit says only "blocked".
    /// Single rays go depth first, each through every resident brick it reaches at
    /// once; packets go brick by brick, a group of rays waiting on each.
    pub fn trace_batch<I: Intersector>(&mut self, rays: &[Ray], any_hit: &[bool]) -> Result<Vec<Option<BrickHit>>> {
        let n = rays.len();
        self.stats.rays += n as u64;
        let mut walks: Vec<TopWalk> = rays.iter().zip(any_hit).map(|(r, &a)| TopWalk::start(r, a)).collect();
        let mut out: Vec<Option<BrickHit>> = vec![None; n];
        if self.packet != PacketSize::Single {
            let mut work = Vec::new();
            for (i, walk) in walks.iter_mut().enumerate() {
                match self.advance(walk) {
                    Some(b) => work.push((b, i)),
                    None => out[i] = walk.best(),
                }
            }
            self.grouped(work, |tracer, view, items, more| {
                tracer.trace_group::<I>(view, &items, rays, any_hit, &mut walks);
                for i in items {
                    match tracer.advance(&mut walks[i]) {
                        Some(b) => more.push((b, i)),
                        None => out[i] = walks[i].best(),
                    }
                }
            })?;
            return Ok(out);
        }
        let mut pins: HashMap<u32, Arc<ResidentBrick>> = HashMap::new();
        let mut parked: BTreeMap<u32, Group<usize>> = BTreeMap::new();
        for i in 0..n {
            if let Some(b) = self.depth_first::<I>(&mut pins, &mut walks[i], &rays[i], &mut out[i]) {
                park(&mut parked, b, i);
            }
        }
        let mut seen = self.cache.generation();
        while !parked.is_empty() {
            let mut progressed = false;
            let keys: Vec<u32> = parked.keys().copied().collect();
            for b in keys {
                if let std::collections::hash_map::Entry::Vacant(e) = pins.entry(b) {
                    match self.get(b) {
                        Some(brick) => {
                            e.insert(brick);
                        }
                        None => continue,
                    }
                }
                let Some(g) = parked.remove(&b) else { continue };
                self.stats.parked_ray_seconds += g.since.elapsed().as_secs_f64() * g.items.len() as f64;
                progressed = true;
                for i in g.items {
                    if let Some(next) = self.depth_first::<I>(&mut pins, &mut walks[i], &rays[i], &mut out[i]) {
                        park(&mut parked, next, i);
                    }
                }
            }
            if !progressed {
                // Let every brick go before waiting: a loader may need the room.
                pins.clear();
                self.cache.released();
                let t = Instant::now();
                self.cache.wait(&mut seen, Duration::from_millis(20))?;
                self.stats.idle_seconds += t.elapsed().as_secs_f64();
            }
        }
        pins.clear();
        self.cache.released();
        Ok(out)
    }

    /// Runs one ray through every brick it reaches that is resident (pinned in `pins`,
    /// or taken from the cache and pinned); returns the missing brick it must wait for,
    /// or `None` once its walk is done (its hit in `out`).
    fn depth_first<I: Intersector>(
        &mut self,
        pins: &mut HashMap<u32, Arc<ResidentBrick>>,
        walk: &mut TopWalk,
        ray: &Ray,
        out: &mut Option<BrickHit>,
    ) -> Option<u32> {
        let mut c = RayCounters::default();
        let parked = loop {
            let Some(b) = self.advance(walk) else {
                *out = walk.best();
                break None;
            };
            let brick = match pins.get(&b) {
                Some(brick) => brick,
                None => match self.get(b) {
                    Some(brick) => pins.entry(b).or_insert(brick),
                    None => break Some(b),
                },
            };
            self.stats.brick_visits += 1;
            through_brick::<I>(brick.view(), walk, ray, &mut c);
        };
        self.stats.steps += c.nodes as u64;
        self.stats.tests += c.tri_tests as u64;
        parked
    }

    /// Traces the rays `items` through the resident brick `view` and finishes their
    /// walks' brick.
    fn trace_group<I: Intersector>(
        &mut self,
        view: &SceneView<'_>,
        items: &[usize],
        rays: &[Ray],
        any_hit: &[bool],
        walks: &mut [TopWalk],
    ) {
        self.stats.brick_visits += items.len() as u64;
        let mut c = RayCounters::default();
        let (shadow, closest): (Vec<usize>, Vec<usize>) = items.iter().partition(|&&i| any_hit[i]);
        for i in shadow {
            through_brick::<I>(view, &mut walks[i], &rays[i], &mut c);
        }
        match self.packet.usable_for(view) {
            PacketSize::P4 => self.packets::<I, 4>(view, &closest, rays, walks),
            PacketSize::P16 => self.packets::<I, 16>(view, &closest, rays, walks),
            PacketSize::P64 => self.packets::<I, 64>(view, &closest, rays, walks),
            _ => {
                for &i in &closest {
                    through_brick::<I>(view, &mut walks[i], &rays[i], &mut c);
                }
            }
        }
        self.stats.steps += c.nodes as u64;
        self.stats.tests += c.tri_tests as u64;
    }

    /// The closest-hit rays `items` through `view` as packets of `N`.
    fn packets<I: Intersector, const N: usize>(
        &mut self,
        view: &SceneView<'_>,
        items: &[usize],
        rays: &[Ray],
        walks: &mut [TopWalk],
    ) {
        let mut pc = PacketCounters::default();
        for chunk in items.chunks(N) {
            let mut packet = RayPacket::<N>::new();
            for (lane, &i) in chunk.iter().enumerate() {
                packet.set(lane, &walks[i].brick_ray(&rays[i]));
            }
            let mut hits = [None; N];
            trace_packet::<I, _, N>(view, &packet, &mut hits, &mut NoProbe, &mut pc);
            for (lane, &i) in chunk.iter().enumerate() {
                walks[i].finish_brick(view, hits[lane]);
            }
        }
    }
}

/// Parks ray `i` on brick `b`.
fn park(parked: &mut BTreeMap<u32, Group<usize>>, b: u32, i: usize) {
    parked.entry(b).or_insert_with(|| Group { items: Vec::new(), since: Instant::now(), waited: true }).items.push(i);
}

/// One ray through the resident brick its walk is waiting on: the brick's any-hit query
/// or its closest-hit walk (with the CPU's widest instructions, as the flat tracer's),
/// and the walk told the result.
#[inline(always)]
fn through_brick<I: Intersector>(view: &SceneView<'_>, walk: &mut TopWalk, ray: &Ray, c: &mut RayCounters) {
    let r = walk.brick_ray(ray);
    if walk.is_any_hit() {
        let blocked = occluded::<I, _>(view, &r, &mut NoProbe, c);
        walk.finish_brick_occluded(view, ray, blocked);
    } else {
        let hit = with_avx2(
            #[inline(always)]
            || trace::<I, _>(view, &r, &mut NoProbe, c),
        );
        walk.finish_brick(view, hit);
    }
}
