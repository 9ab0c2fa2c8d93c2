//! The shade pipeline of the ray generation & shading unit: finished packets come back
//! — up to `rgs.shade_jobs` at once — and core's shading kernel runs on them at once; its
//! reads are fetched through the shading cache, `shade_per_cycle` rays are shaded per
//! cycle once the data has arrived, and only then is the framebuffer written (a posted
//! write per packet) and the rays the shader emitted released. A hit in a two-level
//! scene is shaded from its instance's world-space surface with the globals image's
//! lights ([`raypipe_core::shade::instance_surface`]), as the host shades it.

use raypipe_core::shade::escaped::eye_escaped;
use raypipe_core::shade::instance_surface::instance_surface;
use raypipe_core::shade::lambert::{shade, shade_surface};
use raypipe_core::shade::ray_record::{RayKind, RayRecord};
use raypipe_core::shade::shader::Shader;
use raypipe_core::shade::whitted::shade_whitted_surface;
use raypipe_core::traverse::instanced::InstanceHit;
use raypipe_core::{Hit, Vec3};

use super::shade_job::{ShadeJob, Stage};
use super::{Rgs, FRAMEBUFFER_BASE};
use crate::chip::fifo::Fifo;
use crate::chip::jobs::{lanes, HitPacket};
use crate::chip::scene::{ChipScene, InstancedScene};
use crate::memory::port::{Fetch, Recorder};
use crate::memory::traffic::FRAMEBUFFER;
use crate::observe::stall::Stall;
use crate::observe::unit_stats::Activity;

/// What a finished trace leaves for its shading job.
struct Shaded {
    /// Lane → pixel (`u32::MAX`: no pixel), for the cost images.
    pixels: Vec<u32>,
    /// The shading kernel's reads.
    probe: Recorder,
    /// Rays to shade.
    rays: u64,
    /// Records the shader emitted.
    emitted: Vec<RayRecord>,
    /// Framebuffer bytes to write when done, at this address.
    write: (u64, u32),
    /// A packet of primary rays.
    primary: bool,
}

impl Rgs {
    /// The shader's cycle: jobs done leave (framebuffer write, emitted rays released), the
    /// datapath takes the oldest job whose data is there, a new packet comes in if a job
    /// slot is free, and waiting jobs fetch. Returns true if anything moved.
    pub(super) fn tick_shade(&mut self, now: u64, scene: &ChipScene<'_>, hits: &mut [Fifo<Box<HitPacket>>]) -> bool {
        let mut moved = false;
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
                    self.queue.push(r);
                }
                self.queue_peak = self.queue_peak.max(self.queue.len());
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
    fn shade(&mut self, now: u64, scene: &ChipScene<'_>, packet: &HitPacket) {
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
            let scene = match scene {
                ChipScene::Flat(v) => v,
                ChipScene::Instanced(two) => {
                    let hit = packet.hits[j].map(|h| (h, packet.instances[j]));
                    let value = match ray {
                        Some(ray) => {
                            let rec = RayRecord::eye_sample(ray, pixel as u32, s, samples, self.eye.cone());
                            let c = self.shade_instanced(two, &rec, hit, &mut probe, &mut |r| emitted.push(r));
                            if self.shader.is_some() {
                                c
                            } else {
                                c / samples as f32
                            }
                        }
                        None => {
                            probe.base = two.globals_base();
                            let (x_y_s, bg) = ((x, y, s), self.background);
                            eye_escaped(&two.globals, &self.eye, x_y_s, bg, &mut probe) / samples as f32
                        }
                    };
                    match self.radiance.get_mut(pixel) {
                        Some(sum) => sum.add(value),
                        None => self.framebuffer[pixel] = value,
                    }
                    if s == 0 {
                        self.hits[pixel] = if packet.lanes & (1 << j) != 0 { packet.hits[j] } else { None };
                    }
                    continue;
                }
            };
            match (&self.shader, ray) {
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
                // Ray casting, or an eye ray that missed the scene's box (any shader).
                (_, ray) => {
                    let color = match ray {
                        Some(ray) => shade(scene, &ray, self.eye.cone(), packet.hits[j], self.background, &mut probe),
                        None => eye_escaped(scene, &self.eye, (x, y, s), self.background, &mut probe),
                    };
                    match self.radiance.get_mut(pixel) {
                        Some(sum) => sum.add(color * share),
                        None => self.framebuffer[pixel] = color,
                    }
                }
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
        let done = Shaded { pixels: lane_pixels, probe, rays: pixels, emitted, write, primary: true };
        self.push_job(now, packet, done);
    }

    /// Starts a shading job for the reads `probe` recorded.
    fn push_job(&mut self, now: u64, packet: &HitPacket, done: Shaded) {
        let Shaded { pixels, probe, rays, emitted, write, primary } = done;
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
    /// Takes a secondary packet back: unblocked shadow rays add their weight, the others
    /// are shaded (and may emit more records).
    fn shade_secondary(&mut self, now: u64, scene: &ChipScene<'_>, packet: &HitPacket) {
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
                continue;
            }
            match (scene, &self.shader) {
                (ChipScene::Flat(view), Some(shader)) => {
                    slot.add(shader.shade(view, rec, hit, &mut probe, &mut |r| emitted.push(r)))
                }
                (ChipScene::Instanced(two), Some(_)) => {
                    let hit = hit.map(|h| (h, packet.instances[j]));
                    let c = self.shade_instanced(two, rec, hit, &mut probe, &mut |r| emitted.push(r));
                    if let Some(slot) = self.radiance.get_mut(rec.pixel as usize) {
                        slot.add(c);
                    }
                }
                (_, None) => {}
            }
        }
        self.rays_retired += lanes(packet.lanes);
        self.shade_stats.issue(lanes(packet.lanes), self.packet_size);
        let rays = records.len() as u64;
        let lane_pixels = records.iter().map(|r| r.pixel).collect();
        let done = Shaded { pixels: lane_pixels, probe, rays, emitted, write: (0, 0), primary: false };
        self.push_job(now, packet, done);
    }

    /// The radiance of `rec`, which hit `hit` (in that instance) or nothing, as the host
    /// shades a two-level scene: the instance's surface read in its bottom image, lit
    /// with the globals image (ray casting's colour, or Whitted's with its records
    /// emitted).
    fn shade_instanced(
        &self,
        two: &InstancedScene<'_>,
        rec: &RayRecord,
        hit: Option<(Hit, u32)>,
        probe: &mut Recorder,
        emit: &mut impl FnMut(RayRecord),
    ) -> Vec3 {
        let surface = hit.and_then(|(hit, instance)| {
            let bottom = two.top.instances().get(instance as usize)?.bottom;
            probe.base = two.bottom(bottom)?.1;
            let (top, bottoms, globals) = (&two.top, &two.bottoms, &two.globals);
            instance_surface(top, bottoms, globals, &rec.ray, &InstanceHit { hit, instance }, rec.cone, probe)
        });
        probe.base = two.globals_base();
        match &self.shader {
            Some(Shader::Whitted(o)) => shade_whitted_surface(&two.globals, rec, surface, o, probe, emit),
            _ => shade_surface(&two.globals, &rec.ray, surface, self.background, probe),
        }
    }
}
