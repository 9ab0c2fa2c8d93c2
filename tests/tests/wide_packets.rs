//! The wide BVHs' packet walks against the single-ray walk on a camera's pixel blocks:
//! the same hits, bit for bit, from a walk the packet takes together.

use raypipe::render::tracer::trace;
use raypipe::scene::{Accel, TriangleLayout};
use raypipe_core::{NoProbe, Ray, RayCounters, Vec3, Watertight};
use raypipe_tests::build_soup_layout;

/// The 8-wide BVH's packet walk is taken by a camera's 8×8 pixel blocks (not ray by ray):
/// the packets visit far fewer nodes than their rays alone, and every ray's hit is the
/// single ray's, bit for bit.
#[test]
fn bvh8_eye_ray_packets_walk_the_tree_together() {
    use raypipe::render::tracer::trace_packet;
    use raypipe_core::camera::{Camera, EyeRays};
    use raypipe_core::packet::{PacketCounters, RayPacket};
    // A bumpy 12×12 sheet of quads (288 triangles).
    let n = 12u32;
    let positions: Vec<[f32; 3]> = (0..=n)
        .flat_map(|y| {
            (0..=n).map(move |x| [x as f32 / 3.0 - 2.0, y as f32 / 3.0 - 2.0, ((x * 7 + y * 3) % 5) as f32 * 0.05])
        })
        .collect();
    let at = |x: u32, y: u32| y * (n + 1) + x;
    let triangles: Vec<[u32; 3]> = (0..n)
        .flat_map(|y| {
            (0..n).flat_map(move |x| {
                [[at(x, y), at(x + 1, y), at(x, y + 1)], [at(x + 1, y), at(x + 1, y + 1), at(x, y + 1)]]
            })
        })
        .collect();
    for layout in [TriangleLayout::Indexed, TriangleLayout::Blocks] {
        let scene = build_soup_layout(positions.clone(), triangles.clone(), Accel::Bvh8, layout);
        let view = scene.view().unwrap();
        assert!(view.bvh8().is_some());
        let cam = Camera {
            eye: Vec3::new(0.3, 0.2, -5.0),
            look_at: Vec3::ZERO,
            up: Vec3::Y,
            vfov_deg: 60.0,
            width: 64,
            height: 64,
        };
        let eye = EyeRays::new(&cam).unwrap();
        let (mut packet_visits, mut single_visits, mut hits) = (0u64, 0u64, 0u32);
        for by in 0..8 {
            for bx in 0..8 {
                let rays: Vec<Ray> = (0..64).map(|i| eye.ray(8 * bx + i % 8, 8 * by + i / 8)).collect();
                let mut packet = RayPacket::<64>::new();
                packet.fill(&rays);
                let mut got = [None; 64];
                let mut pc = PacketCounters::default();
                trace_packet::<Watertight, _, 64>(&view, &packet, &mut got, &mut NoProbe, &mut pc);
                packet_visits += pc.visits;
                for (r, h) in rays.iter().zip(got) {
                    let mut c = RayCounters::default();
                    let single = trace::<Watertight, _>(&view, r, &mut NoProbe, &mut c);
                    single_visits += u64::from(c.nodes) + u64::from(c.leaves);
                    hits += single.is_some() as u32;
                    let same = match (h, single) {
                        (None, None) => true,
                        (Some(a), Some(b)) => a.bits_eq(&b),
                        _ => false,
                    };
                    assert!(same, "{layout:?}: packet {h:?} != single {single:?} for {r:?}");
                }
            }
        }
        assert!(hits > 1500, "{layout:?}: only {hits} of 4096 rays hit the sheet");
        // Ray by ray, the packets would make exactly the single rays' visits.
        assert!(
            packet_visits * 3 < single_visits,
            "{layout:?}: packets {packet_visits} visits, rays alone {single_visits}"
        );
    }
}
