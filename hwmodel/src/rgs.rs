//! Ray generation & shading (RGS): the generator emits packets of primary rays, one
//! square pixel block per packet in tile order, with Purcell's scene-bounds test deciding
//! which lanes carry a ray; packets go round-robin to the traversal units' ray FIFOs.
//! The shader takes finished packets back, runs core's shading kernel (its reads go
//! through the shading cache) and writes the framebuffer (a posted write per packet).
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

use crate::config::HwConfig;
use crate::fifo::Fifo;
use crate::jobs::{lanes, HitPacket, Query, RayPacketJob, NO_RAY};
use crate::mem_port::{MemPort, PortProbe, Wait};
use crate::traffic::FRAMEBUFFER;
use crate::unit_stats::{Activity, UnitStats};

/// Pixels per tile side (packets are issued tile by tile, as the host renders).
pub const TILE: u32 = 16;

/// A packet being shaded.
struct Shading {
    wait: Wait,
    busy_until: u64,
    primary: bool,
}

/// The ray generation & shading unit.
pub struct Rgs {
    eye: EyeRays,
    bounds: (Vec3, Vec3),
    background: Vec3,
    side: u32,
    packet_size: u64,
    rays_per_cycle: u64,
    shade_per_cycle: u64,
    /// Pixel block origins, in issue order.
    blocks: Vec<(u32, u32)>,
    next_block: usize,
    generated: Option<(Box<RayPacketJob>, u64)>,
    next_unit: usize,
    next_hits: usize,
    shading: Option<Shading>,
    /// The image, row-major.
    pub framebuffer: Vec<[u8; 3]>,
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
    /// Each pixel's radiance (ray-emitting shaders), summed exactly in any order.
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
    pub rays_by_kind: [u64; 5],
    /// Rays issued to traversal.
    pub rays_issued: u64,
    /// Rays shaded after traversal.
    pub rays_retired: u64,
}

impl Rgs {
    /// A generator for the view `eye` of the scene with bounds `bounds` (Purcell's test),
    /// shading hits with `shader` (`None`: ray casting).
    pub fn new(eye: EyeRays, bounds: (Vec3, Vec3), background: Vec3, shader: Option<Shader>, cfg: &HwConfig) -> Rgs {
        let side = cfg.packet_side();
        let mut blocks = Vec::new();
        for ty in (0..eye.height).step_by(TILE as usize) {
            for tx in (0..eye.width).step_by(TILE as usize) {
                for by in (ty..(ty + TILE).min(eye.height)).step_by(side as usize) {
                    for bx in (tx..(tx + TILE).min(eye.width)).step_by(side as usize) {
                        blocks.push((bx, by));
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
            shading: None,
            framebuffer: vec![[0; 3]; pixels],
            hits: vec![None; pixels],
            port: MemPort::new("shading".into(), &cfg.cache.shading),
            gen_stats: UnitStats::default(),
            shade_stats: UnitStats::default(),
            packets_done: 0,
            shader,
            radiance: if shader.is_some() { vec![RadianceSum::default(); pixels] } else { Vec::new() },
            stream: RayStream::default(),
            in_flight: HashMap::new(),
            next_secondary: 0,
            stream_peak: 0,
            visibility: None,
            direct: VecDeque::new(),
            rays_by_kind: [0; 5],
            rays_issued: 0,
            rays_retired: 0,
        }
    }

    /// Number of packets in the frame.
    pub fn packet_count(&self) -> usize {
        self.blocks.len()
    }

    /// Takes primary visibility from a G-buffer (row-major hits) instead of tracing it.
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
            && self.shading.is_none()
            && self.direct.is_empty()
    }

    /// The image: the framebuffer (ray casting), or the summed radiance of each pixel.
    pub fn image(&self) -> Vec<[u8; 3]> {
        match self.shader {
            None => self.framebuffer.clone(),
            Some(_) => self.radiance.iter().map(|r| rgb8(r.value())).collect(),
        }
    }

    /// The first cycle after `now` at which time alone changes something (a packet is
    /// generated, a shaded packet is written); `None` if only FIFO traffic can.
    pub fn next_wake(&self, now: u64) -> Option<u64> {
        let generated = self.generated.as_ref().map(|(_, ready)| *ready);
        let shaded = self.shading.as_ref().map(|s| self.port.resolve(&s.wait).map_or(now + 1, |r| r.max(s.busy_until)));
        [generated, shaded].into_iter().flatten().filter(|&w| w > now).min()
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
            if self.shading.is_some() { "busy" } else { "free" }
        )
    }

    /// Pixel of lane `j` of block `b`, if inside the image.
    fn pixel(&self, b: usize, j: usize) -> Option<(u32, u32)> {
        let (bx, by) = *self.blocks.get(b)?;
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
        // Generator: send the packet made earlier, or make the next one.
        let gen_activity = match self.generated.take() {
            Some((job, ready)) if ready <= now => {
                let n = rays.len();
                match (0..n).map(|k| (self.next_unit + k) % n).find(|&u| rays[u].can_push()) {
                    Some(u) => {
                        self.rays_issued += lanes(job.lanes);
                        let _ = rays[u].push(job);
                        self.next_unit = (u + 1) % n;
                        moved = true;
                        Activity::Busy
                    }
                    None => {
                        rays.iter_mut().for_each(|f| f.note_full());
                        self.generated = Some((job, ready));
                        Activity::Stalled
                    }
                }
            }
            Some(pending) => {
                self.generated = Some(pending);
                Activity::Busy
            }
            // Secondary rays first (so the stream stays short), then the next block.
            None if !self.stream.is_empty() => {
                let job = self.pack_secondary();
                self.gen_stats.issue(lanes(job.lanes), self.packet_size);
                let cycles = (lanes(job.lanes)).div_ceil(self.rays_per_cycle).max(1);
                self.generated = Some((job, now + cycles));
                moved = true;
                Activity::Busy
            }
            None if self.next_block < self.blocks.len() && self.visibility.is_some() => {
                // The shadow caster: the block's hits are read from the G-buffer.
                let b = self.next_block;
                let mut packet = Box::new(HitPacket { index: b as u32, lanes: 0, hits: [None; 64] });
                for j in 0..self.packet_size as usize {
                    if let (Some((x, y)), Some(vis)) = (self.pixel(b, j), &self.visibility) {
                        packet.lanes |= 1 << j;
                        packet.hits[j] = vis.get((y * self.eye.width + x) as usize).copied().flatten();
                    }
                }
                self.gen_stats.issue(lanes(packet.lanes), self.packet_size);
                self.direct.push_back(packet);
                self.next_block += 1;
                moved = true;
                Activity::Busy
            }
            None if self.next_block < self.blocks.len() => {
                let b = self.next_block;
                let mut job =
                    Box::new(RayPacketJob { index: b as u32, query: Query::Closest, lanes: 0, rays: [NO_RAY; 64] });
                for j in 0..self.packet_size as usize {
                    if let Some((x, y)) = self.pixel(b, j) {
                        if let Some(ray) = self.eye.ray_in_scene(x, y, self.bounds.0, self.bounds.1) {
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
                Activity::Busy
            }
            None => Activity::Idle,
        };
        self.gen_stats.cycle(gen_activity);

        // Shader: finish the packet being shaded, or take the next finished one.
        if let Some(s) = &self.shading {
            if self.port.resolve(&s.wait).is_some_and(|r| r.max(s.busy_until) <= now) {
                if s.primary {
                    self.packets_done += 1;
                }
                self.shading = None;
                moved = true;
            }
        }
        let shade_activity = if self.shading.is_some() {
            Activity::Stalled
        } else {
            let n = hits.len();
            if let Some(packet) = self.direct.pop_front() {
                self.shade(now, scene, &packet);
                moved = true;
                Activity::Busy
            } else {
                match (0..n).map(|k| (self.next_hits + k) % n).find(|&u| hits[u].peek().is_some()) {
                    Some(u) => {
                        self.next_hits = (u + 1) % n;
                        let packet = hits[u].pop().expect("peeked");
                        if (packet.index as usize) < self.blocks.len() {
                            self.shade(now, scene, &packet);
                        } else {
                            self.shade_secondary(now, scene, &packet);
                        }
                        moved = true;
                        Activity::Busy
                    }
                    None => Activity::Idle,
                }
            }
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
        let mut probe = PortProbe { port: &mut self.port, now, wait: Wait::default() };
        let mut pixels = 0u64;
        for (j, p) in where_.iter().enumerate() {
            let Some((x, y)) = *p else { continue };
            pixels += 1;
            let pixel = (y * self.eye.width + x) as usize;
            let ray = if packet.lanes & (1 << j) == 0 {
                None
            } else if self.visibility.is_some() {
                Some(self.eye.ray(x, y))
            } else {
                self.eye.ray_in_scene(x, y, self.bounds.0, self.bounds.1)
            };
            match (&self.shader, ray) {
                (None, Some(ray)) => {
                    self.framebuffer[pixel] = rgb8(shade(scene, &ray, packet.hits[j], self.background, &mut probe))
                }
                (None, None) => self.framebuffer[pixel] = rgb8(self.background),
                (Some(shader), Some(ray)) => {
                    let stream = &mut self.stream;
                    let sum = &mut self.radiance[pixel];
                    shader.shade_primary(
                        scene,
                        RayRecord::primary(ray, pixel as u32),
                        packet.hits[j],
                        sum,
                        &mut probe,
                        &mut |r| stream.push(r),
                    );
                }
                (Some(_), None) => self.radiance[pixel].add(self.background),
            }
            self.hits[pixel] = if packet.lanes & (1 << j) != 0 { packet.hits[j] } else { None };
        }
        self.stream_peak = self.stream_peak.max(self.stream.len());
        let wait = probe.wait;
        self.port.write(FRAMEBUFFER, 4 * pixels as u32);
        if self.visibility.is_none() {
            self.rays_retired += lanes(packet.lanes);
        }
        self.shade_stats.issue(lanes(packet.lanes), self.packet_size);
        self.shading = Some(Shading { wait, busy_until: now + pixels.div_ceil(self.shade_per_cycle), primary: true });
    }

    /// Packs waiting records of one kind — the kind of the oldest record — into a packet,
    /// oldest first (shadow rays want any hit, the others the closest).
    fn pack_secondary(&mut self) -> Box<RayPacketJob> {
        let records = self.stream.take_oldest_kind(self.packet_size as usize);
        let kind = records.first().map_or(RayKind::Shadow, |r| r.kind);
        let query = if kind == RayKind::Shadow { Query::AnyHit } else { Query::Closest };
        let index = self.blocks.len() as u32 + self.next_secondary;
        self.next_secondary = self.next_secondary.wrapping_add(1);
        let mut job = Box::new(RayPacketJob { index, query, lanes: 0, rays: [NO_RAY; 64] });
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
        let mut probe = PortProbe { port: &mut self.port, now, wait: Wait::default() };
        for (j, rec) in records.iter().enumerate() {
            let hit = packet.hits[j];
            let Some(slot) = self.radiance.get_mut(rec.pixel as usize) else { continue };
            if rec.kind == RayKind::Shadow {
                if hit.is_none() {
                    slot.add(rec.weight);
                }
            } else if let Some(shader) = &self.shader {
                let stream = &mut self.stream;
                slot.add(shader.shade(scene, rec, hit, &mut probe, &mut |r| stream.push(r)));
            }
        }
        self.stream_peak = self.stream_peak.max(self.stream.len());
        self.rays_retired += lanes(packet.lanes);
        self.shade_stats.issue(lanes(packet.lanes), self.packet_size);
        let busy_until = now + (records.len() as u64).div_ceil(self.shade_per_cycle).max(1);
        self.shading = Some(Shading { wait: probe.wait, busy_until, primary: false });
    }
}

/// The records the shader emitted, one first-in first-out queue per kind, so that a
/// packet gathers rays of one kind (Wald & Slusallek 2001: shadow rays toward the same
/// light are coherent, reflections of neighbouring pixels too); each record keeps its
/// emission number so that the oldest kind goes first.
#[derive(Default)]
struct RayStream {
    queues: [VecDeque<(u64, RayRecord)>; 5],
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
