//! The generate pipeline of the ray generation & shading unit: a packet of primary rays
//! per pixel block (Purcell's scene-bounds test picks the lanes), or of the shader's
//! waiting records, `rays_per_cycle` rays a cycle, sent round-robin to the traversal
//! units' ray FIFOs; for the shadow caster, the block's hits read from the G-buffer.

use raypipe_core::shade::ray_record::RayKind;

use super::Rgs;
use crate::chip::fifo::Fifo;
use crate::chip::jobs::{lanes, HitPacket, PacketCost, Query, RayPacketJob, NO_RAY};
use crate::observe::stall::Stall;
use crate::observe::unit_stats::Activity;

impl Rgs {
    /// The generator's cycle: send the packet made earlier once it is complete; the next
    /// one starts in the same cycle. Returns true if anything moved.
    pub(super) fn tick_generate(&mut self, now: u64, rays: &mut [Fifo<Box<RayPacketJob>>]) -> bool {
        let mut moved = false;
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
            if !self.queue.is_empty() {
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
                    instances: [0; 64],
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
        moved
    }

    /// Packs waiting records of one kind — the kind of the oldest record — into a packet,
    /// oldest first (shadow rays want any hit, the others the closest).
    fn pack_secondary(&mut self) -> Box<RayPacketJob> {
        let records = self.queue.take_oldest_kind(self.packet_size as usize);
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
}
