//! Ray generation & shading (RGS): the generator emits packets of primary rays, one
//! square pixel block per packet in tile order, with Purcell's scene-bounds test deciding
//! which lanes carry a ray; packets go round-robin to the traversal units' ray FIFOs.
//! The generator is pipelined: a packet of `n` rays takes `n / rays_per_cycle` cycles,
//! and the next one starts the cycle the previous one leaves.
//! The shader takes finished packets back — up to `rgs.shade_jobs` at once — runs core's
//! shading kernel at once (its reads are recorded and fetched through the shading cache),
//! shades `shade_per_cycle` rays per cycle once the data has arrived, and only then
//! writes the framebuffer (a posted write per packet) and releases the rays it emitted.
//!
//! Ports: `rays` out (one FIFO per traversal unit), `hits` in (one per traversal unit),
//! and a memory port with the shading cache.

use std::collections::{HashMap, VecDeque};

use raypipe_core::camera::EyeRays;
use raypipe_core::shade::color::rgb8;
use raypipe_core::shade::lambert::shade;
use raypipe_core::shade::radiance_sum::RadianceSum;
use raypipe_core::shade::ray_record::{RayKind, RayRecord};
use raypipe_core::shade::shader::Shader;
use raypipe_core::{SceneView, Vec3};

use crate::chip::fifo::Fifo;
use crate::chip::jobs::{lanes, HitPacket, PacketCost, Query, RayPacketJob, NO_RAY};
use crate::config::HwConfig;
use crate::memory::port::{Fetch, MemPort, Recorder};
use crate::memory::traffic::FRAMEBUFFER;
use crate::observe::stall::Stall;
use crate::observe::unit_stats::{Activity, UnitStats};

/// Pixels per tile side (packets are issued tile by tile, as the host renders).
pub const TILE: u32 = 16;

/// Where a shading job stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    Fetching,
    Queued,
    Shading(u64),
}

/// A packet being shaded.
struct ShadeJob {
    /// Packet number (for traces).
    packet: u32,
    /// Cycle the packet was started, and the pixels its lanes belong to (cost images).
    issued: u64,
    pixels: Vec<u32>,
    /// Shading bytes the job reads.
    bytes: u64,
    fetch: Fetch,
    stage: Stage,
    data_at: u64,
    primary: bool,
    /// Rays to shade (cycles in the datapath: `rays / shade_per_cycle`).
    rays: u64,
    /// Records the shader emitted, released when the job is done.
    emitted: Vec<RayRecord>,
    /// Framebuffer bytes written when done, at this address.
    write: (u64, u32),
}

/// Framebuffer writes go to their own address space, above any scene image.
const FRAMEBUFFER_BASE: u64 = 1 << 40;

/// The ray generation & shading unit.
pub struct Rgs {
    eye: EyeRays,
    bounds: (Vec3, Vec3),
    background: Vec3,
    side: u32,
    packet_size: u64,
    rays_per_cycle: u64,
    shade_per_cycle: u64,
    /// Pixel block origins and the eye ray of their pixels, in issue order.
    blocks: Vec<(u32, u32, u32)>,
    next_block: usize,
    generated: Option<(Box<RayPacketJob>, u64)>,
    next_unit: usize,
    next_hits: usize,
    /// Packets being shaded, oldest first.
    shading: Vec<ShadeJob>,
    shade_jobs: usize,
    /// The shading datapath is busy until this cycle (exclusive).
    shade_busy_until: u64,
    /// The image, row-major.
    pub framebuffer: Vec<Vec3>,
    /// Each pixel's closest hit (what the equivalence tests compare with the host).
    pub hits: Vec<Option<raypipe_core::Hit>>,
    /// The shading port.
    pub port: MemPort,
    /// Generator activity.
    pub gen_stats: UnitStats,
    /// Shader activity.
    pub shade_stats: UnitStats,
    /// Primary packets shaded and written.
    pub packets_done: usize,
    /// The ray-emitting shader (Whitted, path tracing), or `None` for ray casting.
    shader: Option<Shader>,
    /// Each pixel's radiance (ray-emitting shaders, or several eye rays per pixel),
    /// summed exactly in any order.
    radiance: Vec<RadianceSum>,
    /// Records the shader emitted, waiting to be packed (first in, first out).
    stream: RayStream,
    /// Secondary packets in flight: their lanes' records.
    in_flight: HashMap<u32, Vec<RayRecord>>,
    next_secondary: u32,
    /// Most records waiting at once.
    pub stream_peak: usize,
    /// The shadow caster's visibility: each pixel's hit from a rasterized G-buffer (then
    /// no primary ray is traced: blocks go straight to shading).
    visibility: Option<Vec<Option<raypipe_core::Hit>>>,
    /// Blocks whose hits came from the G-buffer, waiting for the shader.
    direct: VecDeque<Box<HitPacket>>,
    /// Rays sent to traversal, by kind (`RayKind as usize`).
    pub rays_by_kind: [u64; RayKind::COUNT],
    /// Rays issued to traversal.
    pub rays_issued: u64,
    /// Rays shaded after traversal.
    pub rays_retired: u64,
    /// Packets whose shading finished this cycle (when tracing).
    pub done_log: Option<Vec<u32>>,
    /// Per pixel: cycles its packets were in flight (from generation to the end of
    /// shading, summed over its rays' packets), ray–node tests, ray–triangle tests, and
    /// scene bytes the kernels read for it (a packet's shared reads split evenly among
    /// its lanes).
    pub cost: Vec<[f64; 4]>,
}

impl Rgs {
    /// A generator for the view `eye` of the scene with bounds `bounds` (Purcell's test),
    /// shading hits with `shader` (`None`: ray casting).
    pub fn new(eye: EyeRays, bounds: (Vec3, Vec3), background: Vec3, shader: Option<Shader>, cfg: &HwConfig) -> Rgs {
        let side = cfg.packet_side();
        let mut blocks = Vec::new();
        for ty in (0..eye.height).step_by(TILE as usize) {
            for tx in (0..eye.width).step_by(TILE as usize) {
                // A tile's blocks for each eye ray of its pixels in turn (one sample: the
                // pixel centres).
                for s in 0..eye.samples() {
                    for by in (ty..(ty + TILE).min(eye.height)).step_by(side as usize) {
                        for bx in (tx..(tx + TILE).min(eye.width)).step_by(side as usize) {
                            blocks.push((bx, by, s));
                        }
                    }
                }
            }
        }
        let pixels = (eye.width * eye.height) as usize;
        Rgs {
            eye,
            bounds,
            background,
            side,
            packet_size: cfg.packet_size as u64,
            rays_per_cycle: cfg.rgs.rays_per_cycle as u64,
            shade_per_cycle: cfg.rgs.shade_per_cycle as u64,
            blocks,
            next_block: 0,
            generated: None,
            next_unit: 0,
            next_hits: 0,
            shading: Vec::new(),
            shade_jobs: cfg.rgs.shade_jobs.max(1) as usize,
            shade_busy_until: 0,
            framebuffer: vec![Vec3::ZERO; pixels],
            hits: vec![None; pixels],
            port: MemPort::new("shading".into(), &cfg.cache.shading, cfg.memory.queue_depth),
            gen_stats: UnitStats::default(),
            shade_stats: UnitStats::default(),
            packets_done: 0,
            shader,
            radiance: if shader.is_some() || eye.samples() > 1 {
                vec![RadianceSum::default(); pixels]
            } else {
                Vec::new()
            },
            stream: RayStream::default(),
            in_flight: HashMap::new(),
            next_secondary: 0,
            stream_peak: 0,
            visibility: None,
            direct: VecDeque::new(),
            rays_by_kind: [0; RayKind::COUNT],
            rays_issued: 0,
            rays_retired: 0,
            done_log: None,
            cost: vec![[0.0; 4]; pixels],
        }
    }

    /// Starts the frame `eye` (a walkthrough's next view, or the same one again) when the
    /// last one is done: the shading cache keeps its lines, everything else starts over.
    pub fn next_frame(&mut self, eye: EyeRays, cfg: &HwConfig) {
        let port = std::mem::replace(&mut self.port, MemPort::new(String::new(), &cfg.cache.shading, 1));
        let last = (self.gen_stats.last, self.shade_stats.last);
        let log = self.done_log.take();
        *self = Rgs::new(eye, self.bounds, self.background, self.shader, cfg);
        self.port = port;
        self.done_log = log;
        (self.gen_stats.last, self.shade_stats.last) = last;
    }

    /// Zeroes the statistics (work in flight and the cache's lines stay).
    pub fn reset_stats(&mut self) {
        self.gen_stats.reset();
        self.shade_stats.reset();
        self.port.reset_stats();
        self.rays_by_kind = [0; RayKind::COUNT];
        self.rays_issued = 0;
        self.rays_retired = 0;
        self.stream_peak = self.stream.len();
    }

    /// Number of packets in the frame.
    pub fn packet_count(&self) -> usize {
        self.blocks.len()
    }

    /// Takes primary visibility from G-buffers (hits of every eye ray, row-major and
    /// sample-major: `hits[s * pixels + p]`) instead of tracing it.
    pub fn set_visibility(&mut self, hits: Vec<Option<raypipe_core::Hit>>) {
        self.visibility = Some(hits);
    }

    /// Image size.
    pub fn size(&self) -> (u32, u32) {
        (self.eye.width, self.eye.height)
    }

    /// Every packet shaded, and no ray left to trace.
    pub fn is_done(&self) -> bool {
        self.packets_done == self.blocks.len()
            && self.stream.is_empty()
            && self.in_flight.is_empty()
            && self.generated.is_none()
            && self.shading.is_empty()
            && self.direct.is_empty()
    }

    /// The image, 8-bit sRGB.
    pub fn image(&self) -> Vec<[u8; 3]> {
        self.radiance_image().into_iter().map(rgb8).collect()
    }

    /// The image, linear: the framebuffer (ray casting, one eye ray per pixel), or the
    /// summed radiance of each pixel.
    pub fn radiance_image(&self) -> Vec<Vec3> {
        if self.radiance.is_empty() {
            self.framebuffer.clone()
        } else {
            self.radiance.iter().map(RadianceSum::value).collect()
        }
    }

    /// The first cycle after `now` at which time alone changes something (a packet is
    /// generated, a shaded packet is written); `None` if only FIFO traffic can.
    pub fn next_wake(&self, now: u64) -> Option<u64> {
        let generated = self.generated.as_ref().map(|(_, ready)| *ready);
        let jobs = self.shading.iter().filter_map(|j| match j.stage {
            Stage::Fetching => self.port.wake_of(&j.fetch, now),
            Stage::Shading(done) => Some(done),
            Stage::Queued => None,
        });
        jobs.chain(generated).chain(Some(self.shade_busy_until)).filter(|&w| w > now).min()
    }

    /// One line describing the unit (for the watchdog).
    pub fn describe(&self) -> String {
        format!(
            "rgs: {}/{} packets generated, {} waiting to be sent, {} shaded, {} rays waiting, {} secondary packets out, shader {}",
            self.next_block,
            self.blocks.len(),
            self.generated.is_some() as u32,
            self.packets_done,
            self.stream.len(),
            self.in_flight.len(),
            if self.shading.is_empty() { "free" } else { "busy" }
        )
    }

    /// The eye ray (sample) block `b` traces for its pixels.
    fn sample_of(&self, b: usize) -> u32 {
        self.blocks.get(b).map_or(0, |blk| blk.2)
    }

    /// Pixels in the image.
    fn pixel_count(&self) -> usize {
        self.eye.width as usize * self.eye.height as usize
    }

    /// Pixel of lane `j` of block `b`, if inside the image.
    fn pixel(&self, b: usize, j: usize) -> Option<(u32, u32)> {
        let (bx, by, _) = *self.blocks.get(b)?;
        let (x, y) = (bx + j as u32 % self.side, by + j as u32 / self.side);
        (x < self.eye.width && y < self.eye.height).then_some((x, y))
    }

    /// One cycle. Returns true if anything moved.
    pub fn tick(
        &mut self,
        now: u64,
        scene: &SceneView<'_>,
        rays: &mut [Fifo<Box<RayPacketJob>>],
        hits: &mut [Fifo<Box<HitPacket>>],
    ) -> bool {
        let mut moved = false;
        // Generator: send the packet made earlier once it is complete; the next one starts
        // in the same cycle.
        let mut gen_activity = Activity::Idle;
        if let Some((job, ready)) = self.generated.take() {
            if ready <= now {
                let n = rays.len();
                match (0..n).map(|k| (self.next_unit + k) % n).find(|&u| rays[u].can_push()) {
                    Some(u) => {
                        self.rays_issued += lanes(job.lanes);
                        let _ = rays[u].push(job);
                        self.next_unit = (u + 1) % n;
                        moved = true;
                    }
                    None => {
                        rays.iter_mut().for_each(|f| f.note_full());
                        self.generated = Some((job, ready));
                        gen_activity = Activity::Stalled(Stall::OutputFull);
                    }
                }
            } else {
                self.generated = Some((job, ready));
                gen_activity = Activity::Busy;
            }
        }
        if self.generated.is_none() {
            // Secondary rays first (so the stream stays short), then the next block.
            if !self.stream.is_empty() {
                let mut job = self.pack_secondary();
                job.issued = now;
                self.gen_stats.issue(lanes(job.lanes), self.packet_size);
                let cycles = (lanes(job.lanes)).div_ceil(self.rays_per_cycle).max(1);
                self.generated = Some((job, now + cycles));
                moved = true;
                gen_activity = Activity::Busy;
            } else if self.next_block < self.blocks.len() && self.visibility.is_some() {
                // The shadow caster: the block's hits are read from the G-buffer.
                let b = self.next_block;
                let mut packet = Box::new(HitPacket {
                    index: b as u32,
                    lanes: 0,
                    hits: [None; 64],
                    cost: Box::new(PacketCost::new(now)),
                });
                for j in 0..self.packet_size as usize {
                    if let (Some((x, y)), Some(vis)) = (self.pixel(b, j), &self.visibility) {
                        packet.lanes |= 1 << j;
                        let at = self.sample_of(b) as usize * self.pixel_count() + (y * self.eye.width + x) as usize;
                        packet.hits[j] = vis.get(at).copied().flatten();
                    }
                }
                self.gen_stats.issue(lanes(packet.lanes), self.packet_size);
                self.direct.push_back(packet);
                self.next_block += 1;
                moved = true;
                gen_activity = Activity::Busy;
            } else if self.next_block < self.blocks.len() {
                let b = self.next_block;
                let mut job = Box::new(RayPacketJob {
                    index: b as u32,
                    query: Query::Closest,
                    lanes: 0,
                    rays: [NO_RAY; 64],
                    issued: now,
                });
                for j in 0..self.packet_size as usize {
                    if let Some((x, y)) = self.pixel(b, j) {
                        let s = self.sample_of(b);
                        if let Some(ray) = self.eye.sample_ray_in_scene(x, y, s, self.bounds.0, self.bounds.1) {
                            job.rays[j] = ray;
                            job.lanes |= 1 << j;
                        }
                    }
                }
                self.rays_by_kind[RayKind::Primary as usize] += lanes(job.lanes);
                self.gen_stats.issue(lanes(job.lanes), self.packet_size);
                let cycles = self.packet_size.div_ceil(self.rays_per_cycle);
                self.generated = Some((job, now + cycles));
                self.next_block += 1;
                moved = true;
                gen_activity = Activity::Busy;
            }
        }
        self.gen_stats.cycle(gen_activity);

        // Shader: jobs done leave (framebuffer write, emitted rays released).
        let mut k = 0;
        while k < self.shading.len() {
            if matches!(self.shading[k].stage, Stage::Shading(d) if d <= now) {
                let j = self.shading.remove(k);
                if let Some(log) = self.done_log.as_mut() {
                    log.push(j.packet);
                }
                let share = j.bytes as f64 / j.pixels.iter().filter(|&&p| p != u32::MAX).count().max(1) as f64;
                for &p in &j.pixels {
                    if let Some(c) = self.cost.get_mut(p as usize) {
                        c[0] += now.saturating_sub(j.issued) as f64;
                        c[3] += share;
                    }
                }
                if j.primary {
                    self.packets_done += 1;
                }
                for r in j.emitted {
                    self.stream.push(r);
                }
                self.stream_peak = self.stream_peak.max(self.stream.len());
                if j.write.1 > 0 {
                    self.port.write(FRAMEBUFFER, j.write.0, j.write.1, now);
                }
                moved = true;
            } else {
                k += 1;
            }
        }
        // The datapath takes the oldest job whose data is there.
        if self.shade_busy_until <= now {
            let next = self.shading.iter().position(|j| j.stage == Stage::Queued);
            if let Some(k) = next {
                let j = &mut self.shading[k];
                debug_assert!(j.data_at <= now, "shaded before the shading data arrived");
                let cycles = j.rays.div_ceil(self.shade_per_cycle).max(1);
                self.shade_busy_until = now + cycles;
                j.stage = Stage::Shading(now + cycles);
                moved = true;
            }
        }
        // A new packet to shade, if a job slot is free.
        if self.shading.len() < self.shade_jobs {
            let n = hits.len();
            if let Some(packet) = self.direct.pop_front() {
                self.shade(now, scene, &packet);
                moved = true;
            } else if let Some(u) = (0..n).map(|k| (self.next_hits + k) % n).find(|&u| hits[u].peek().is_some()) {
                self.next_hits = (u + 1) % n;
                if let Some(packet) = hits[u].pop() {
                    if (packet.index as usize) < self.blocks.len() {
                        self.shade(now, scene, &packet);
                    } else {
                        self.shade_secondary(now, scene, &packet);
                    }
                    moved = true;
                }
            }
        }
        // Jobs are kept oldest first.
        for j in self.shading.iter_mut().filter(|j| j.stage == Stage::Fetching) {
            let (progress, data) = self.port.step_fetch(&mut j.fetch, now);
            moved |= progress;
            if let Some(at) = data {
                j.data_at = at;
                j.stage = Stage::Queued;
                moved = true;
            }
        }
        let shade_activity = if self.shade_busy_until > now {
            Activity::Busy
        } else if self.shading.is_empty() {
            Activity::Idle
        } else {
            let fetching = self.shading.iter().find(|j| j.stage == Stage::Fetching);
            Activity::Stalled(match fetching {
                Some(j) => self.port.stall_of(&j.fetch, Stall::ShadingData),
                None => Stall::PipelineLatency,
            })
        };
        self.shade_stats.cycle(shade_activity);
        moved
    }

    /// Shades one finished packet into the framebuffer.
    fn shade(&mut self, now: u64, scene: &SceneView<'_>, packet: &HitPacket) {
        let b = packet.index as usize;
        let mut where_: [Option<(u32, u32)>; 64] = [None; 64];
        for (j, p) in where_.iter_mut().enumerate().take(self.packet_size as usize) {
            *p = self.pixel(b, j);
        }
        // Lane → pixel, for the cost images (`u32::MAX`: no pixel).
        let lane_pixels: Vec<u32> = where_[..self.packet_size as usize]
            .iter()
            .map(|p| p.map_or(u32::MAX, |(x, y)| y * self.eye.width + x))
            .collect();
        let mut probe = Recorder::default();
        let mut emitted = Vec::new();
        let mut pixels = 0u64;
        let mut first_pixel = None;
        for (j, p) in where_.iter().enumerate() {
            let Some((x, y)) = *p else { continue };
            pixels += 1;
            // Each pixel's reads are a chain of their own.
            probe.at_level(0);
            let pixel = (y * self.eye.width + x) as usize;
            first_pixel.get_or_insert(pixel);
            let (s, samples) = (self.sample_of(b), self.eye.samples());
            let ray = if packet.lanes & (1 << j) == 0 {
                None
            } else if self.visibility.is_some() {
                Some(self.eye.sample_ray(x, y, s))
            } else {
                self.eye.sample_ray_in_scene(x, y, s, self.bounds.0, self.bounds.1)
            };
            let share = 1.0 / samples as f32;
            match (&self.shader, ray) {
                (None, Some(ray)) => {
                    let color = shade(scene, &ray, self.eye.cone(), packet.hits[j], self.background, &mut probe);
                    match self.radiance.get_mut(pixel) {
                        Some(sum) => sum.add(color * share),
                        None => self.framebuffer[pixel] = color,
                    }
                }
                (None, None) => match self.radiance.get_mut(pixel) {
                    Some(sum) => sum.add(self.background * share),
                    None => self.framebuffer[pixel] = self.background,
                },
                (Some(shader), Some(ray)) => {
                    let sum = &mut self.radiance[pixel];
                    shader.shade_primary(
                        scene,
                        RayRecord::eye_sample(ray, pixel as u32, s, samples, self.eye.cone()),
                        packet.hits[j],
                        sum,
                        &mut probe,
                        &mut |r| emitted.push(r),
                    );
                }
                (Some(_), None) => self.radiance[pixel].add(self.background * share),
            }
            if s == 0 {
                self.hits[pixel] = if packet.lanes & (1 << j) != 0 { packet.hits[j] } else { None };
            }
        }
        if self.visibility.is_none() {
            self.rays_retired += lanes(packet.lanes);
        }
        self.shade_stats.issue(lanes(packet.lanes), self.packet_size);
        let write = (FRAMEBUFFER_BASE + 4 * first_pixel.unwrap_or(0) as u64, 4 * pixels as u32);
        self.push_job(now, packet, lane_pixels, probe, pixels, emitted, write, true);
    }

    /// Starts a shading job for the reads `probe` recorded.
    #[allow(clippy::too_many_arguments)]
    fn push_job(
        &mut self,
        now: u64,
        packet: &HitPacket,
        pixels: Vec<u32>,
        probe: Recorder,
        rays: u64,
        emitted: Vec<RayRecord>,
        write: (u64, u32),
        primary: bool,
    ) {
        // The trace's cost: each lane's own tests, the shared reads split evenly.
        let share = packet.cost.bytes as f64 / lanes(packet.lanes).max(1) as f64;
        for (j, &p) in pixels.iter().enumerate() {
            if let (Some(c), true) = (self.cost.get_mut(p as usize), packet.lanes & (1 << j) != 0) {
                c[1] += packet.cost.steps[j] as f64;
                c[2] += packet.cost.tests[j] as f64;
                c[3] += share;
            }
        }
        let bytes = probe.reads().map(|a| a.bytes as u64).sum();
        self.shading.push(ShadeJob {
            packet: packet.index,
            issued: packet.cost.issued,
            pixels,
            bytes,
            fetch: Fetch::new(probe.into_levels()),
            stage: Stage::Fetching,
            data_at: now,
            primary,
            rays,
            emitted,
            write,
        });
    }

    /// Packs waiting records of one kind — the kind of the oldest record — into a packet,
    /// oldest first (shadow rays want any hit, the others the closest).
    fn pack_secondary(&mut self) -> Box<RayPacketJob> {
        let records = self.stream.take_oldest_kind(self.packet_size as usize);
        let kind = records.first().map_or(RayKind::Shadow, |r| r.kind);
        let query = if kind == RayKind::Shadow { Query::AnyHit } else { Query::Closest };
        let index = self.blocks.len() as u32 + self.next_secondary;
        self.next_secondary = self.next_secondary.wrapping_add(1);
        let mut job = Box::new(RayPacketJob { index, query, lanes: 0, rays: [NO_RAY; 64], issued: 0 });
        for (j, r) in records.iter().enumerate() {
            job.rays[j] = r.ray;
            job.lanes |= 1 << j;
            self.rays_by_kind[r.kind as usize] += 1;
        }
        self.in_flight.insert(index, records);
        job
    }

    /// Takes a secondary packet back: unblocked shadow rays add their weight, the others
    /// are shaded (and may emit more records).
    fn shade_secondary(&mut self, now: u64, scene: &SceneView<'_>, packet: &HitPacket) {
        let records = self.in_flight.remove(&packet.index).unwrap_or_default();
        let mut probe = Recorder::default();
        let mut emitted = Vec::new();
        for (j, rec) in records.iter().enumerate() {
            probe.at_level(0);
            let hit = packet.hits[j];
            let Some(slot) = self.radiance.get_mut(rec.pixel as usize) else { continue };
            if rec.kind == RayKind::Shadow {
                if hit.is_none() {
                    slot.add(rec.weight);
                }
            } else if let Some(shader) = &self.shader {
                slot.add(shader.shade(scene, rec, hit, &mut probe, &mut |r| emitted.push(r)));
            }
        }
        self.rays_retired += lanes(packet.lanes);
        self.shade_stats.issue(lanes(packet.lanes), self.packet_size);
        let rays = records.len() as u64;
        let lane_pixels = records.iter().map(|r| r.pixel).collect();
        self.push_job(now, packet, lane_pixels, probe, rays, emitted, (0, 0), false);
    }
}

/// The records the shader emitted, one first-in first-out queue per kind, so that a
/// packet gathers rays of one kind (Wald & Slusallek 2001: shadow rays toward the same
/// light are coherent, reflections of neighbouring pixels too); each record keeps its
/// emission number so that the oldest kind goes first.
#[derive(Default)]
struct RayStream {
    queues: [VecDeque<(u64, RayRecord)>; RayKind::COUNT],
    next: u64,
}

impl RayStream {
    fn push(&mut self, r: RayRecord) {
        self.queues[r.kind as usize].push_back((self.next, r));
        self.next += 1;
    }

    fn len(&self) -> usize {
        self.queues.iter().map(VecDeque::len).sum()
    }

    fn is_empty(&self) -> bool {
        self.queues.iter().all(VecDeque::is_empty)
    }

    /// Up to `n` records of the kind whose oldest record is the oldest of all.
    fn take_oldest_kind(&mut self, n: usize) -> Vec<RayRecord> {
        let Some(k) =
            (0..self.queues.len()).filter(|&k| !self.queues[k].is_empty()).min_by_key(|&k| self.queues[k][0].0)
        else {
            return Vec::new();
        };
        let q = &mut self.queues[k];
        q.drain(..n.min(q.len())).map(|(_, r)| r).collect()
    }
}
