//! The clock: every cycle each unit ticks (reading only state committed at the previous
//! edge), then the edge commits every FIFO and hands the cycle's memory requests to the
//! memory in a fixed port order. A cycle in which nothing moved repeats itself until the
//! earliest cycle at which some wait is over (a datum arrives, a pipeline empties): the
//! clock skips there, accounting the skipped cycles like the last one. A watchdog stops a
//! run in which nothing moved and nothing is awaited — no datum, latency or queue slot can
//! ever change it — after `watchdog_cycles`, naming every unit's state and every FIFO's
//! occupancy. So a legitimate wait, however long, never trips it, and the verdict is the
//! same whether the clock skips or ticks every cycle.

use raypipe_core::camera::EyeRays;
use raypipe_core::intersect::triangle::Intersector;
use raypipe_core::shade::shader::Shader;
use raypipe_core::{SceneView, Vec3};

use crate::chip::fifo::{AnyFifo, Fifo};
use crate::chip::intersection_unit::IntersectionUnit;
use crate::chip::jobs::{HitPacket, LeafJob, RayPacketJob};
use crate::chip::rgs::Rgs;
use crate::chip::scene::ChipScene;
use crate::chip::traversal_unit::TraversalUnit;
use crate::config::HwConfig;
use crate::memory::port::{LatencyStats, MemPort};
use crate::memory::traffic::CLASSES;
use crate::memory::Memory;
use crate::observe::energy::NodeTest;
use crate::observe::report::{Report, Sources};
use crate::observe::waves::{TraceLog, Waves};

/// A unit, for the tick order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum UnitRef {
    Rgs,
    Traversal(usize),
    Intersection(usize),
}

/// The modelled chip with its scene and frame.
pub struct Simulator<'s, I: Intersector> {
    pub(crate) cfg: HwConfig,
    scene: ChipScene<'s>,
    pub(crate) rgs: Rgs,
    pub(crate) tus: Vec<TraversalUnit<I::Nodes>>,
    pub(crate) ius: Vec<IntersectionUnit<I>>,
    pub(crate) ray_fifos: Vec<Fifo<Box<RayPacketJob>>>,
    pub(crate) leaf_fifos: Vec<Fifo<Box<LeafJob>>>,
    pub(crate) result_fifos: Vec<Fifo<Box<LeafJob>>>,
    pub(crate) hit_fifos: Vec<Fifo<Box<HitPacket>>>,
    pub(crate) memory: Memory,
    /// Scene bytes read at least once, one bit per 4-byte word.
    touched: Vec<u64>,
    order: Vec<UnitRef>,
    shuffle: Option<u64>,
    skip: bool,
    now: u64,
    /// The cycle statistics were last zeroed at (warm-up, region of interest, a new
    /// frame): the report covers `stats_from..`.
    stats_from: u64,
    /// Waveforms being written, if asked for.
    pub(crate) waves: Option<Waves>,
    /// The trace being recorded, if asked for.
    pub(crate) trace: Option<TraceLog>,
    /// Frames started (walkthroughs), for the trace.
    pub(crate) frame: u32,
    /// Requests the memory accepted in the last cycle (a waveform signal).
    pub(crate) accepted: u64,
}

impl<'s, I: Intersector> Simulator<'s, I> {
    /// Builds the chip of `cfg` (validated first) for the frame `eye` of `scene`, ray
    /// casting.
    pub fn new(scene: SceneView<'s>, eye: EyeRays, background: Vec3, cfg: &HwConfig) -> Result<Self, String> {
        Self::with_shader(scene, eye, background, None, cfg)
    }

    /// The same with a ray-emitting shader (Whitted ray tracing, path tracing) in the
    /// shading unit: its shadow and secondary rays go round the chip as packets too.
    pub fn with_shader(
        scene: SceneView<'s>,
        eye: EyeRays,
        background: Vec3,
        shader: Option<Shader>,
        cfg: &HwConfig,
    ) -> Result<Self, String> {
        Self::for_scene(ChipScene::Flat(scene), eye, background, shader, cfg)
    }

    /// The chip for the frame `eye` of `scene`, flat or two-level: in a two-level scene
    /// rays walk the top level, enter instances through the transformation units and
    /// walk their bottoms; ray casting or Whitted (`shader`).
    pub fn for_scene(
        scene: ChipScene<'s>,
        eye: EyeRays,
        background: Vec3,
        shader: Option<Shader>,
        cfg: &HwConfig,
    ) -> Result<Self, String> {
        if let ChipScene::Instanced(_) = scene {
            if let Some(Shader::Path(_)) = shader {
                return Err("path tracing samples emitters by triangle id, which instances share".into());
            }
            if cfg.datapath != crate::Datapath::F32 {
                return Err(format!(
                    "datapath {}: the top level's box test is f32; a two-level scene needs datapath f32",
                    cfg.datapath.name()
                ));
            }
        }
        cfg.validate()?;
        let units = cfg.traversal.units as usize;
        let f = &cfg.fifo;
        let mut order = vec![UnitRef::Rgs];
        order.extend((0..units).map(UnitRef::Traversal));
        order.extend((0..units).map(UnitRef::Intersection));
        let words = scene.size().div_ceil(4) as usize;
        let bounds = scene.test_bounds();
        Ok(Simulator {
            cfg: cfg.clone(),
            scene,
            rgs: Rgs::new(eye, bounds, background, shader, cfg),
            tus: (0..units).map(|u| TraversalUnit::new(u, cfg)).collect(),
            ius: (0..units).map(|u| IntersectionUnit::new(u, cfg)).collect(),
            ray_fifos: (0..units).map(|u| Fifo::new(format!("rays{u}"), f.rays)).collect(),
            leaf_fifos: (0..units).map(|u| Fifo::new(format!("leaves{u}"), f.leaves)).collect(),
            result_fifos: (0..units).map(|u| Fifo::new(format!("results{u}"), f.results)).collect(),
            hit_fifos: (0..units).map(|u| Fifo::new(format!("hits{u}"), f.hits)).collect(),
            memory: Memory::new(cfg)?,
            touched: vec![0; words.div_ceil(64)],
            order,
            shuffle: None,
            skip: true,
            now: 0,
            stats_from: 0,
            waves: None,
            trace: None,
            frame: 0,
            accepted: 0,
        })
    }

    /// The shadow caster: primary visibility comes from rasterized G-buffers (each
    /// eye ray's hit, row-major and sample-major), so only shadow rays are traced on the chip.
    pub fn set_visibility(&mut self, hits: Vec<Option<raypipe_core::Hit>>) {
        self.rgs.set_visibility(hits);
    }

    /// Ticks the units in a pseudo-random order, reshuffled every cycle (for the test
    /// that proves the order cannot matter).
    pub fn shuffle_tick_order(&mut self, seed: u64) {
        self.shuffle = Some(seed | 1);
    }

    /// Ticks every cycle instead of skipping cycles in which nothing can change (for the
    /// test that proves skipping changes no result).
    pub fn tick_every_cycle(&mut self) {
        self.skip = false;
    }

    /// Runs the frame to the end; `progress(done, total)` is called now and then with
    /// packets shaded.
    pub fn run(&mut self, progress: impl FnMut(usize, usize)) -> Result<(), String> {
        self.run_until(None, progress).map(|_| ())
    }

    /// True when the frame is done: every packet shaded and every request (the last
    /// framebuffer writes) gone from its port and answered.
    pub fn is_done(&self) -> bool {
        self.rgs.is_done() && !self.any_staged() && self.memory.is_idle()
    }

    /// True for a two-level scene (the transformation units take part).
    pub fn is_two_level(&self) -> bool {
        matches!(self.scene, ChipScene::Instanced(_))
    }

    /// Packets of primary rays in the frame.
    pub fn packet_count(&self) -> usize {
        self.rgs.packet_count()
    }

    /// The current cycle.
    pub fn now(&self) -> u64 {
        self.now
    }

    /// Runs until the frame is done or, with `stop`, until cycle `stop` (the cycles
    /// before it ticked, none after): true when the frame is done. The clock never skips
    /// past `stop`, so statistics taken there cover exactly `..stop`.
    pub fn run_until(&mut self, stop: Option<u64>, mut progress: impl FnMut(usize, usize)) -> Result<bool, String> {
        let mut quiet = 0u64;
        let total = self.rgs.packet_count();
        let mut last_done = usize::MAX;
        while !self.is_done() {
            if stop.is_some_and(|s| self.now >= s) {
                return Ok(false);
            }
            // The last cycle the clock may account before stopping.
            let room = stop.map_or(u64::MAX, |s| s - self.now - 1);
            let moved = self.cycle();
            let wake = if moved { None } else { self.next_wake() };
            let mut skipped = 0;
            if moved {
                quiet = 0;
            } else if let Some(w) = wake {
                quiet = 0;
                if self.skip {
                    skipped = w.saturating_sub(self.now + 1).min(room);
                }
            } else {
                // Nothing moved and nothing is awaited: nothing can ever move again.
                quiet += 1;
                if self.skip {
                    skipped = (self.cfg.watchdog_cycles.saturating_sub(quiet) + 1).min(room);
                    quiet += skipped;
                }
                if quiet > self.cfg.watchdog_cycles {
                    self.repeat_last(skipped);
                    self.now += 1 + skipped;
                    return Err(self.deadlock());
                }
            }
            self.repeat_last(skipped);
            self.now += 1 + skipped;
            if self.rgs.packets_done != last_done && self.rgs.packets_done.is_multiple_of(64) {
                last_done = self.rgs.packets_done;
                progress(last_done, total);
            }
        }
        self.memory.finish_frame();
        progress(total, total);
        Ok(true)
    }

    /// Zeroes every statistic — units, FIFOs, caches, memory, the distinct-data map —
    /// while the chip keeps its state (work in flight, cache lines, open rows): gem5's
    /// `resetstats`, for warm-up and regions of interest. The report then covers the
    /// cycles from now on.
    pub fn reset_stats(&mut self) {
        self.rgs.reset_stats();
        self.tus.iter_mut().for_each(|t| t.reset_stats());
        self.ius.iter_mut().for_each(|i| i.reset_stats());
        self.fifos_mut().for_each(|f| f.reset_stats());
        self.memory.reset_stats();
        self.touched.iter_mut().for_each(|w| *w = 0);
        self.stats_from = self.now;
    }

    /// Starts the next frame of a walkthrough (`eye`: its view; the same view again for
    /// a warm-up frame) once this one is done. Caches keep their lines and the DRAM its
    /// open rows; statistics start over.
    pub fn next_frame(&mut self, eye: EyeRays) -> Result<(), String> {
        if !self.is_done() {
            return Err("next_frame: the current frame is not done".into());
        }
        // The next frame starts once the last one's data is in (the report's end).
        self.now = self.now.max(self.memory.resume_at());
        self.frame += 1;
        self.rgs.next_frame(eye, &self.cfg);
        self.reset_stats();
        Ok(())
    }

    /// One clock cycle: every unit ticks, then the edge. Returns whether anything moved.
    fn cycle(&mut self) -> bool {
        let now = self.now;
        if let Some(state) = self.shuffle.as_mut() {
            // Fisher–Yates with xorshift64.
            for i in (1..self.order.len()).rev() {
                *state ^= *state << 13;
                *state ^= *state >> 7;
                *state ^= *state << 17;
                self.order.swap(i, (*state % (i as u64 + 1)) as usize);
            }
        }
        let mut moved = false;
        for k in 0..self.order.len() {
            moved |= match self.order[k] {
                UnitRef::Rgs => self.rgs.tick(now, &self.scene, &mut self.ray_fifos, &mut self.hit_fifos),
                UnitRef::Traversal(u) => self.tus[u].tick(
                    now,
                    &self.scene,
                    &mut self.ray_fifos[u],
                    &mut self.leaf_fifos[u],
                    &mut self.result_fifos[u],
                    &mut self.hit_fifos[u],
                ),
                UnitRef::Intersection(u) => {
                    self.ius[u].tick(now, &self.scene, &mut self.leaf_fifos[u], &mut self.result_fifos[u])
                }
            };
        }
        // The edge: FIFOs commit, then the channel takes this cycle's requests in port
        // order (shading, traversal units, intersection units).
        for f in self.fifos_mut() {
            moved |= f.commit();
        }
        let mut ports: Vec<&mut MemPort> = std::iter::once(&mut self.rgs.port)
            .chain(self.tus.iter_mut().map(|t| &mut t.port))
            .chain(self.ius.iter_mut().map(|i| &mut i.port))
            .collect();
        for port in ports.iter_mut() {
            mark_touched(&mut self.touched, port);
        }
        // Requests taken this cycle: a waveform signal, counted only when one is written.
        let counting = self.waves.is_some();
        let before: u64 = if counting { self.memory.stats.requests.iter().sum() } else { 0 };
        moved |= self.memory.accept(now, &mut ports);
        if counting {
            self.accepted = self.memory.stats.requests.iter().sum::<u64>() - before;
        }
        if self.trace.is_some() {
            self.record_trace(now);
        }
        if let Some(mut w) = self.waves.take() {
            let mut buf = std::mem::take(&mut w.scratch);
            self.sample_signals(&mut buf);
            w.scratch = buf;
            w.sample(now);
            self.waves = Some(w);
        }
        moved
    }

    /// Every FIFO: ray, leaf, result and hit FIFOs, unit by unit.
    pub(crate) fn fifos(&self) -> impl Iterator<Item = &dyn AnyFifo> {
        let (r, l) =
            (self.ray_fifos.iter().map(|f| f as &dyn AnyFifo), self.leaf_fifos.iter().map(|f| f as &dyn AnyFifo));
        let (q, h) =
            (self.result_fifos.iter().map(|f| f as &dyn AnyFifo), self.hit_fifos.iter().map(|f| f as &dyn AnyFifo));
        r.chain(l).chain(q).chain(h)
    }

    /// Every FIFO, to commit or account.
    pub(crate) fn fifos_mut(&mut self) -> impl Iterator<Item = &mut dyn AnyFifo> {
        let r = self.ray_fifos.iter_mut().map(|f| f as &mut dyn AnyFifo);
        let l = self.leaf_fifos.iter_mut().map(|f| f as &mut dyn AnyFifo);
        let q = self.result_fifos.iter_mut().map(|f| f as &mut dyn AnyFifo);
        let h = self.hit_fifos.iter_mut().map(|f| f as &mut dyn AnyFifo);
        r.chain(l).chain(q).chain(h)
    }

    /// The earliest cycle after now at which some unit's wait is over.
    fn next_wake(&self) -> Option<u64> {
        let now = self.now;
        let units = self.tus.iter().map(|t| t.next_wake(now)).chain(self.ius.iter().map(|i| i.next_wake(now)));
        let staged = self.any_staged();
        std::iter::once(self.rgs.next_wake(now))
            .chain(units)
            .chain(std::iter::once(self.memory.next_wake(now, staged)))
            .flatten()
            .min()
    }

    /// True if some port holds requests the memory has not accepted yet.
    fn any_staged(&self) -> bool {
        self.rgs.port.has_staged()
            || self.tus.iter().any(|t| t.port.has_staged())
            || self.ius.iter().any(|i| i.port.has_staged())
    }

    /// Accounts `n` cycles exactly like the last one, for every unit and FIFO.
    fn repeat_last(&mut self, n: u64) {
        if n == 0 {
            return;
        }
        self.rgs.gen_stats.repeat_last(n);
        self.rgs.shade_stats.repeat_last(n);
        self.tus.iter_mut().for_each(|t| t.repeat_last(n));
        self.ius.iter_mut().for_each(|i| i.stats.repeat_last(n));
        self.fifos_mut().for_each(|f| f.repeat_last(n));
    }

    /// The watchdog's message: every unit's state and every FIFO's occupancy.
    fn deadlock(&self) -> String {
        let mut parts = vec![self.rgs.describe()];
        parts.extend(self.tus.iter().map(|t| t.describe()));
        parts.extend(self.ius.iter().map(|i| i.describe()));
        let fifos = self
            .fifos()
            .map(|f| format!("{} {}/{}", f.name(), f.occupancy(), f.depth()))
            .collect::<Vec<_>>()
            .join(", ");
        format!(
            "watchdog: no unit made progress for {} cycles at cycle {}; {}; FIFOs: {fifos}",
            self.cfg.watchdog_cycles,
            self.now,
            parts.join("; ")
        )
    }

    /// The rendered image, row-major.
    pub fn framebuffer(&self) -> Vec<[u8; 3]> {
        self.rgs.image()
    }

    /// The image as linear radiance, row-major.
    pub fn radiance_image(&self) -> Vec<Vec3> {
        self.rgs.radiance_image()
    }

    /// Each pixel's cost, row-major: cycles its packets were in flight, ray–node tests,
    /// ray–triangle tests, scene bytes read for it (see `Rgs::cost`).
    pub fn cost_image(&self) -> &[[f64; 4]] {
        &self.rgs.cost
    }

    /// Each pixel's closest hit, row-major.
    pub fn hits(&self) -> &[Option<raypipe_core::Hit>] {
        &self.rgs.hits
    }

    /// Test hook: a traversal unit that never ticks again, to prove the watchdog fires.
    #[doc(hidden)]
    pub fn freeze_traversal_unit(&mut self, unit: usize) {
        self.order.retain(|u| *u != UnitRef::Traversal(unit));
    }

    /// Cycles of the frame so far (of the statistics, since they were last zeroed):
    /// at the end, until the last pixel was shaded and the memory drained.
    pub fn cycles(&self) -> u64 {
        let end = if self.is_done() { self.now.max(self.memory.drained_at()) } else { self.now };
        end.saturating_sub(self.stats_from)
    }

    /// The report of the run so far.
    pub fn report(&self) -> Report {
        let mut units =
            vec![("rgs.generate".to_string(), &self.rgs.gen_stats), ("rgs.shade".to_string(), &self.rgs.shade_stats)];
        units.extend(self.tus.iter().map(|t| (format!("traversal{}", t.id), &t.stats)));
        units.extend(self.ius.iter().map(|i| (format!("intersection{}", i.id), &i.stats)));
        let two_level = self.is_two_level();
        let transform_units = self.tus.iter().filter(|_| two_level).map(|t| &t.transform);
        let transform: Vec<_> = transform_units.map(|t| (format!("transform{}", t.id), &t.tstats)).collect();
        units.extend(self.tus.iter().filter(|_| two_level).map(|t| (format!("transform{}", t.id), &t.transform.stats)));
        let fifos = self.fifos().map(|f| (f.name().to_string(), f.depth(), f.stats())).collect();
        let ports: Vec<&MemPort> = std::iter::once(&self.rgs.port)
            .chain(self.tus.iter().map(|t| &t.port))
            .chain(self.ius.iter().map(|i| &i.port))
            .collect();
        let caches = ports.iter().flat_map(|p| p.caches.iter().map(|(name, c)| (name.clone(), c))).collect();
        let requested = ports.iter().map(|p| p.requested.iter().sum::<u64>()).sum();
        let delivered = ports.iter().map(|p| p.delivered.iter().sum::<u64>()).sum();
        let mut latency: Vec<LatencyStats> = vec![LatencyStats::default(); CLASSES];
        for p in &ports {
            for (k, l) in p.latency.iter().enumerate() {
                latency[k].count += l.count;
                latency[k].sum += l.sum;
                for (b, n) in l.histogram.iter().enumerate() {
                    latency[k].histogram[b] += n;
                }
            }
        }
        let view = self.scene.structure_view();
        let node = if view.grid().is_some() {
            NodeTest::Grid
        } else if view.bvh4().is_some() {
            NodeTest::Boxes(4)
        } else if view.bvh8().is_some() {
            NodeTest::Boxes(8)
        } else if view.bvh().is_some() {
            NodeTest::Boxes(2)
        } else if view.kdtree().is_some() {
            NodeTest::Kd
        } else {
            NodeTest::None
        };
        let port_name = port_label;
        let mut report = Report::gather(Sources {
            cfg: &self.cfg,
            size: self.rgs.size(),
            cycles: self.cycles(),
            units,
            traversal: self.tus.iter().map(|t| (format!("traversal{}", t.id), &t.tstats)).collect(),
            transform,
            port_bytes: ports.iter().map(|p| (port_name(p), p.delivered.iter().sum())).collect(),
            latency,
            utilization: self.memory.utilization(self.cycles(), self.cfg.clock_mhz),
            delivered,
            dram: self.memory.dram(),
            dramsim3: self.dramsim3_report(),
            fifos,
            caches,
            channel: &self.memory.stats,
            requested,
            distinct: self.touched.iter().map(|w| w.count_ones() as u64).sum::<u64>() * 4,
            rays: (self.rgs.rays_issued, self.rgs.rays_retired),
            tests: self.ius.iter().map(|i| i.tests).sum(),
            rays_by_kind: self.rgs.rays_by_kind,
            queue_peak: self.rgs.queue_peak,
        });
        report.energy = Some(self.cfg.energy.estimate(&self.cfg, &report, node));
        report
    }
}

impl<I: Intersector> Simulator<'_, I> {
    /// Records every request the memory model serves from now on (`cycle addr bytes
    /// R|W`), to replay them against another memory (`memory::replay`).
    pub fn record_memory_stream(&mut self) {
        self.memory.stream = Some(Vec::new());
    }

    /// The requests recorded so far.
    pub fn take_memory_stream(&mut self) -> Option<Vec<crate::memory::replay::StreamRequest>> {
        self.memory.stream.take()
    }

    /// DRAMsim3's report over the frame so far, if that is the memory.
    fn dramsim3_report(&self) -> Option<crate::observe::dramsim3_report::Dramsim3Report> {
        #[cfg(feature = "dramsim3")]
        if let Some(d) = self.memory.dramsim3() {
            let frame_ns = self.cycles() as f64 * 1e3 / self.cfg.clock_mhz;
            return Some(crate::observe::dramsim3_report::Dramsim3Report::of(d, frame_ns));
        }
        None
    }
}

/// Marks the 4-byte words a port read this cycle (scene data only).
fn mark_touched(touched: &mut [u64], port: &mut MemPort) {
    for (addr, bytes) in port.read_log.drain(..) {
        let (first, last) = (addr as usize / 4, (addr as usize + bytes.max(1) as usize - 1) / 4);
        for word in first / 64..=last / 64 {
            let lo = if word == first / 64 { first % 64 } else { 0 };
            let hi = if word == last / 64 { last % 64 } else { 63 };
            let mask = (u64::MAX >> (63 - hi)) & (u64::MAX << lo);
            if let Some(slot) = touched.get_mut(word) {
                *slot |= mask;
            }
        }
    }
}

/// A port's name in reports and traces: its unit's name.
pub(crate) fn port_label(p: &MemPort) -> String {
    if p.name == "shading" {
        "rgs.shade".to_string()
    } else {
        p.name.clone()
    }
}
