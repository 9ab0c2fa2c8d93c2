//! Image tiles traced as packets: a tile is cut into blocks of 2×2, 4×4 or 8×8 pixels,
//! each traced as one packet in lock-step (or pixel by pixel for single rays). Every
//! pixel gets the same hit either way.

use raypipe_core::camera::EyeRays;
use raypipe_core::packet::{PacketCounters, RayPacket};
use raypipe_core::{Hit, Intersector, NoProbe, Ray, RayCounters, SceneView, Vec3, Vec4};

use crate::render::tracer::{has_packet_kernel, trace_each, trace_packet};

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

    /// Rays per packet.
    pub fn lanes(self) -> usize {
        (self.side() * self.side()) as usize
    }

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
    /// single rays for the kd-tree, the binary BVH and the 8-wide BVH (which has no packet
    /// kernel).
    pub fn auto_for(scene: &SceneView<'_>) -> PacketSize {
        if scene.bvh4().is_some() {
            PacketSize::P64
        } else if scene.grid().is_some() {
            PacketSize::P16
        } else {
            PacketSize::Single
        }
    }

    /// The grouping `scene` is traced with when `self` is asked for: a structure without
    /// a packet kernel (none, the 8-wide BVH) traces its rays one by one — the same hits,
    /// and its fastest path (packing rays only to trace them singly measured 2.4× slower
    /// on Sponza).
    pub fn usable_for(self, scene: &SceneView<'_>) -> PacketSize {
        if has_packet_kernel(scene) {
            self
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

/// Calls `f(x, y, ray, hit)` for every pixel of the tile with the pixel's eye ray
/// `sample`, tracing as `size` says; rays that miss the scene bounds (Purcell's test)
/// come as `None`.
pub fn trace_tile<I: Intersector>(
    scene: &SceneView<'_>,
    rays: TileRays<'_>,
    size: PacketSize,
    counters: &mut RayCounters,
    packet_counters: &mut PacketCounters,
    f: &mut impl FnMut(u32, u32, Option<Ray>, Option<Hit>),
) {
    crate::platform::isa::report_cpu();
    match size.usable_for(scene) {
        PacketSize::Single => singles::<I>(scene, rays, counters, f),
        PacketSize::P4 => blocks::<I, 4>(scene, rays, 2, packet_counters, f),
        PacketSize::P16 => blocks::<I, 16>(scene, rays, 4, packet_counters, f),
        PacketSize::P64 => blocks::<I, 64>(scene, rays, 8, packet_counters, f),
    }
}

/// The eye rays of one tile: the camera's, clipped by the scene bounds `bounds`
/// (Purcell's test), for the pixels `tile` = `(x0, y0, x1, y1)` (exclusive ends), eye ray
/// `sample` of each.
#[derive(Clone, Copy, Debug)]
pub struct TileRays<'e> {
    /// The camera's eye rays.
    pub eye: &'e EyeRays,
    /// The scene bounds of the bounding-box test.
    pub bounds: (Vec3, Vec3),
    /// The tile's pixels.
    pub tile: (u32, u32, u32, u32),
    /// Which of each pixel's eye rays.
    pub sample: u32,
}

/// The tile's rays one by one.
#[inline(always)]
fn singles<I: Intersector>(
    scene: &SceneView<'_>,
    rays: TileRays<'_>,
    counters: &mut RayCounters,
    f: &mut impl FnMut(u32, u32, Option<Ray>, Option<Hit>),
) {
    let TileRays { eye, bounds: (lo, hi), tile: (x0, y0, x1, y1), sample } = rays;
    // Pixels in rows, `i` counting from the tile's corner.
    let w = x1.saturating_sub(x0);
    let n = (w * y1.saturating_sub(y0)) as usize;
    let w = w.max(1);
    let pixel = |i: usize| (x0 + i as u32 % w, y0 + i as u32 / w);
    // The rays made four at a time (`EyeRays::rays4`, `clip_rays4`: the same rays and
    // verdicts as `ray_in_scene` one by one), handed out one by one.
    let mut quad = (usize::MAX, [None; 4]);
    let ray = |i: usize| {
        if quad.0 != i / 4 {
            let at: [(u32, u32); 4] = core::array::from_fn(|k| pixel(i / 4 * 4 + k));
            let (eye_at, dirs, seen) = eye.sample_rays4_in_scene(at.map(|p| p.0), at.map(|p| p.1), sample, lo, hi);
            let rays = core::array::from_fn(|k| (seen & (1 << k) != 0).then(|| lane_ray(eye_at, &dirs, k)));
            quad = (i / 4, rays);
        }
        quad.1[i % 4]
    };
    trace_each::<I, _, _>(scene, n, ray, &mut NoProbe, counters, |i, ray, hit| {
        let (x, y) = pixel(i);
        f(x, y, ray, hit)
    });
}

fn blocks<I: Intersector, const N: usize>(
    scene: &SceneView<'_>,
    rays: TileRays<'_>,
    side: u32,
    counters: &mut PacketCounters,
    f: &mut impl FnMut(u32, u32, Option<Ray>, Option<Hit>),
) {
    let TileRays { eye, bounds: (lo, hi), tile: (x0, y0, x1, y1), sample } = rays;
    let mut hits = [None; N];
    // Each lane's pixel in the block, worked out once.
    let offsets: [(u32, u32); N] = core::array::from_fn(|lane| lane_pixel(lane as u32, side));
    for by in (y0..y1).step_by(side as usize) {
        for bx in (x0..x1).step_by(side as usize) {
            let mut packet = RayPacket::<N>::new();
            let mut rays = [None; N];
            // Four lanes (a 2×2 quad of pixels) at a time: their eye rays and their test
            // against the scene's bounds in SIMD lanes (`EyeRays::rays4`, `clip_rays4`),
            // the same rays and verdicts as `EyeRays::ray_in_scene` pixel by pixel.
            for quad in (0..side * side).step_by(4) {
                let pixel: [(u32, u32); 4] = core::array::from_fn(|k| {
                    let (i, j) = offsets[(quad as usize + k) % N];
                    (bx + i, by + j)
                });
                let (eye_at, dirs, seen) =
                    eye.sample_rays4_in_scene(pixel.map(|p| p.0), pixel.map(|p| p.1), sample, lo, hi);
                let mut keep = 0;
                for (k, &(x, y)) in pixel.iter().enumerate() {
                    if x < x1 && y < y1 && seen & (1 << k) != 0 {
                        keep |= 1 << k;
                        if let Some(slot) = rays.get_mut(quad as usize + k) {
                            *slot = Some(lane_ray(eye_at, &dirs, k));
                        }
                    }
                }
                packet.set4(quad as usize, eye_at, dirs, 0.0, f32::INFINITY, keep);
            }
            trace_packet::<I, _, N>(scene, &packet, &mut hits, &mut NoProbe, counters);
            for ((&(i, j), ray), hit) in offsets.iter().zip(&rays).zip(&hits).take((side * side) as usize) {
                let (x, y) = (bx + i, by + j);
                if x < x1 && y < y1 {
                    f(x, y, *ray, *hit);
                }
            }
        }
    }
}

/// Lane `k`'s ray of four rays from `origin` (directions `dirs`, one lane per ray).
#[inline(always)]
fn lane_ray(origin: Vec3, dirs: &[Vec4; 3], k: usize) -> Ray {
    Ray::new(origin, Vec3::new(dirs[0][k % 4], dirs[1][k % 4], dirs[2][k % 4]))
}

/// The pixel `(i, j)` of lane `lane` in a square block of side `side`: Z-order (Morton)
/// when the side is a power of two, so that each run of four lanes is a 2×2 pixel quad
/// and each run of sixteen a 4×4 block — the lane groups a packet's SIMD leaf tests take
/// together are then as compact as they can be; row by row otherwise.
pub fn lane_pixel(lane: u32, side: u32) -> (u32, u32) {
    if !side.is_power_of_two() {
        return (lane % side.max(1), lane / side.max(1));
    }
    (compact_even_bits(lane), compact_even_bits(lane >> 1))
}

/// Bits 0, 2, 4, … 30 of `x` gathered into bits 0 … 15 (a Morton code's x), by halving
/// steps rather than a loop of sixteen (which, per lane of every packet, took a tenth of
/// `raypipe bench`'s packet time).
fn compact_even_bits(x: u32) -> u32 {
    let x = x & 0x5555_5555;
    let x = (x ^ (x >> 1)) & 0x3333_3333;
    let x = (x ^ (x >> 2)) & 0x0f0f_0f0f;
    let x = (x ^ (x >> 4)) & 0x00ff_00ff;
    (x ^ (x >> 8)) & 0x0000_ffff
}

#[cfg(test)]
mod tests {
    use super::lane_pixel;

    #[test]
    fn lanes_cover_the_block_once_in_z_order() {
        // The bit trick against the definition: bit 2b of the lane is bit b of i, bit
        // 2b + 1 is bit b of j.
        for lane in (0..1u32 << 20).step_by(7).chain([u32::MAX, 0xAAAA_AAAA, 0x5555_5555]) {
            let (mut i, mut j) = (0, 0);
            for b in 0..16 {
                i |= ((lane >> (2 * b)) & 1) << b;
                j |= ((lane >> (2 * b + 1)) & 1) << b;
            }
            assert_eq!(lane_pixel(lane, 8), (i, j), "lane {lane:#x}");
        }
        for side in [1, 2, 3, 4, 8] {
            let mut seen = vec![false; (side * side) as usize];
            for lane in 0..side * side {
                let (i, j) = lane_pixel(lane, side);
                assert!(i < side && j < side);
                assert!(!std::mem::replace(&mut seen[(j * side + i) as usize], true));
            }
        }
        // Runs of four are 2×2 quads.
        assert_eq!((0..4).map(|l| lane_pixel(l, 8)).collect::<Vec<_>>(), [(0, 0), (1, 0), (0, 1), (1, 1)]);
        assert_eq!(lane_pixel(4, 8), (2, 0));
        assert_eq!(lane_pixel(63, 8), (7, 7));
    }
}
