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

mod generate;
mod ray_queue;
mod shade;
mod shade_job;

use ray_queue::RayQueue;
use shade_job::{ShadeJob, Stage};

use raypipe_core::camera::EyeRays;
use raypipe_core::shade::color::rgb8;
use raypipe_core::shade::radiance_sum::RadianceSum;
use raypipe_core::shade::ray_record::{RayKind, RayRecord};
use raypipe_core::shade::shader::Shader;
use raypipe_core::Vec3;

use crate::chip::fifo::Fifo;
use crate::chip::jobs::{HitPacket, RayPacketJob};
use crate::chip::scene::ChipScene;
use crate::config::HwConfig;
use crate::memory::port::MemPort;
use crate::observe::unit_stats::UnitStats;

/// Pixels per tile side (packets are issued tile by tile, as the host renders).
pub const TILE: u32 = 16;

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
    queue: RayQueue,
    /// Secondary packets in flight: their lanes' records.
    in_flight: HashMap<u32, Vec<RayRecord>>,
    next_secondary: u32,
    /// Most records waiting at once.
    pub queue_peak: usize,
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
            port: MemPort::new("shading".into(), &cfg.cache.shading, cfg.memory.port_staging()),
            gen_stats: UnitStats::default(),
            shade_stats: UnitStats::default(),
            packets_done: 0,
            shader,
            radiance: if shader.is_some() || eye.samples() > 1 {
                vec![RadianceSum::default(); pixels]
            } else {
                Vec::new()
            },
            queue: RayQueue::default(),
            in_flight: HashMap::new(),
            next_secondary: 0,
            queue_peak: 0,
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
        self.queue_peak = self.queue.len();
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
            && self.queue.is_empty()
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
            self.queue.len(),
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

    /// One cycle: the generate pipeline's stage, then the shade pipeline's. Returns true
    /// if anything moved.
    pub fn tick(
        &mut self,
        now: u64,
        scene: &ChipScene<'_>,
        rays: &mut [Fifo<Box<RayPacketJob>>],
        hits: &mut [Fifo<Box<HitPacket>>],
    ) -> bool {
        let generated = self.tick_generate(now, rays);
        let shaded = self.tick_shade(now, scene, hits);
        generated || shaded
    }
}
