//! Image tiles traced as packets: a tile is cut into blocks of 2×2, 4×4 or 8×8 pixels,
//! each traced as one packet in lock-step (or pixel by pixel for single rays). Every
//! pixel gets the same hit either way.

use raypipe_core::camera::EyeRays;
use raypipe_core::packet::{PacketCounters, RayPacket};
use raypipe_core::{Hit, Intersector, NoProbe, Ray, RayCounters, SceneView, Vec3};

use crate::tracer::{trace, trace_packet};

/// How rays are grouped.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum PacketSize {
    /// One ray at a time.
    #[default]
    #[value(name = "1")]
    Single,
    /// 2×2 packets.
    #[value(name = "4")]
    P4,
    /// 4×4 packets.
    #[value(name = "16")]
    P16,
    /// 8×8 packets.
    #[value(name = "64")]
    P64,
}

impl PacketSize {
    /// Every choice, smallest first.
    pub const ALL: [PacketSize; 4] = [PacketSize::Single, PacketSize::P4, PacketSize::P16, PacketSize::P64];

    /// Side of the square pixel block.
    pub fn side(self) -> u32 {
        match self {
            PacketSize::Single => 1,
            PacketSize::P4 => 2,
            PacketSize::P16 => 4,
            PacketSize::P64 => 8,
        }
    }

    /// Rays per packet.
    pub fn rays(self) -> usize {
        (self.side() * self.side()) as usize
    }

    /// The faster grouping for primary rays of the structure the image holds, as measured
    /// with `raypipe bench --packet 1,4,16,64` on the bunny, Sponza and the conference
    /// room: 8×8 frustum packets for the 4-wide BVH, 4×4 lock-step packets for the grid,
    /// single rays for the kd-tree and the binary BVH.
    pub fn auto_for(scene: &SceneView<'_>) -> PacketSize {
        if scene.bvh4().is_some() {
            PacketSize::P64
        } else if scene.grid().is_some() {
            PacketSize::P16
        } else {
            PacketSize::Single
        }
    }

    /// A label for reports.
    pub fn label(self) -> &'static str {
        match self {
            PacketSize::Single => "single",
            PacketSize::P4 => "2x2",
            PacketSize::P16 => "4x4",
            PacketSize::P64 => "8x8",
        }
    }
}

/// Calls `f(x, y, ray, hit)` for every pixel of the tile, tracing as `size` says; rays
/// that miss the scene bounds (Purcell's test) come as `None`.
#[allow(clippy::too_many_arguments)]
pub fn trace_tile<I: Intersector>(
    scene: &SceneView<'_>,
    eye: &EyeRays,
    bounds: (Vec3, Vec3),
    tile: (u32, u32, u32, u32),
    size: PacketSize,
    counters: &mut RayCounters,
    packet_counters: &mut PacketCounters,
    f: &mut impl FnMut(u32, u32, Option<Ray>, Option<Hit>),
) {
    match size {
        PacketSize::Single => {
            let (x0, y0, x1, y1) = tile;
            for y in y0..y1 {
                for x in x0..x1 {
                    match eye.ray_in_scene(x, y, bounds.0, bounds.1) {
                        Some(ray) => {
                            let hit = trace::<I, _>(scene, &ray, &mut NoProbe, counters);
                            f(x, y, Some(ray), hit);
                        }
                        None => f(x, y, None, None),
                    }
                }
            }
        }
        PacketSize::P4 => blocks::<I, 4>(scene, eye, bounds, tile, 2, packet_counters, f),
        PacketSize::P16 => blocks::<I, 16>(scene, eye, bounds, tile, 4, packet_counters, f),
        PacketSize::P64 => blocks::<I, 64>(scene, eye, bounds, tile, 8, packet_counters, f),
    }
}

fn blocks<I: Intersector, const N: usize>(
    scene: &SceneView<'_>,
    eye: &EyeRays,
    (lo, hi): (Vec3, Vec3),
    (x0, y0, x1, y1): (u32, u32, u32, u32),
    side: u32,
    counters: &mut PacketCounters,
    f: &mut impl FnMut(u32, u32, Option<Ray>, Option<Hit>),
) {
    let mut hits = [None; N];
    for by in (y0..y1).step_by(side as usize) {
        for bx in (x0..x1).step_by(side as usize) {
            let mut packet = RayPacket::<N>::new();
            let mut rays = [None; N];
            for j in 0..side {
                for i in 0..side {
                    let (x, y) = (bx + i, by + j);
                    if x < x1 && y < y1 {
                        let lane = (j * side + i) as usize;
                        if let Some(r) = eye.ray_in_scene(x, y, lo, hi) {
                            packet.set(lane, &r);
                            rays[lane] = Some(r);
                        }
                    }
                }
            }
            trace_packet::<I, _, N>(scene, &packet, &mut hits, &mut NoProbe, counters);
            for j in 0..side {
                for i in 0..side {
                    let (x, y) = (bx + i, by + j);
                    if x < x1 && y < y1 {
                        let lane = (j * side + i) as usize;
                        f(x, y, rays[lane], hits[lane]);
                    }
                }
            }
        }
    }
}
