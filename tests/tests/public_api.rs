//! The public packet API cannot panic: bits of `RayPacket::active` past
//! the packet's lanes, lane indices past the end (`set`, `set4`, `ray`) and every packet
//! kernel on such packets. (`RayPacket<0>` and `RayPacket<65>` do not compile, through
//! `new` or `Default`.)

use raypipe::scene::{self, Accel, BuildOptions};
use raypipe_core::packet::bvh::trace_bvh_packet;
use raypipe_core::packet::bvh4::trace_bvh4_packet;
use raypipe_core::packet::bvh8::trace_bvh8_packet;
use raypipe_core::packet::grid::trace_grid_packet;
use raypipe_core::packet::kdtree::trace_kdtree_packet;
use raypipe_core::packet::step::trace_packet_steps;
use raypipe_core::packet::{PacketCounters, RayPacket};
use raypipe_core::{NoProbe, Ray, SceneView, Vec3, Vec4, Watertight};

fn packet<const N: usize>() -> RayPacket<N> {
    let mut p = RayPacket::<N>::new();
    for i in 0..N {
        let d = Vec3::new(-0.2 + 0.4 * i as f32 / N as f32, -0.3, -1.0);
        p.set(i, &Ray::new(Vec3::new(0.0, 1.0, 3.0), d));
    }
    p
}

fn every_kernel_on<const N: usize>() {
    let mut p = packet::<N>();
    let want: Vec<_> = {
        let img = scene::load_default(&BuildOptions { accel: Accel::Bvh, ..Default::default() }).unwrap().image;
        let view = SceneView::parse(&img).unwrap();
        let mut hits = [None; N];
        trace_bvh_packet::<Watertight, _, N>(
            &view,
            view.bvh().unwrap(),
            &p,
            &mut hits,
            &mut NoProbe,
            &mut PacketCounters::default(),
        );
        hits.to_vec()
    };
    // Every bit set: the lanes past N must be ignored, the real ones traced as before.
    p.active = u64::MAX;
    for accel in [Accel::Grid, Accel::Kd, Accel::Bvh, Accel::Bvh4, Accel::Bvh8] {
        let img = scene::load_default(&BuildOptions { accel, ..Default::default() }).unwrap().image;
        let view = SceneView::parse(&img).unwrap();
        let mut hits = [None; N];
        let c = &mut PacketCounters::default();
        match accel {
            Accel::Grid => {
                trace_grid_packet::<Watertight, _, N>(&view, view.grid().unwrap(), &p, &mut hits, &mut NoProbe, c)
            }
            Accel::Kd => {
                trace_kdtree_packet::<Watertight, _, N>(&view, view.kdtree().unwrap(), &p, &mut hits, &mut NoProbe, c)
            }
            Accel::Bvh => {
                trace_bvh_packet::<Watertight, _, N>(&view, view.bvh().unwrap(), &p, &mut hits, &mut NoProbe, c)
            }
            Accel::Bvh4 => {
                trace_bvh4_packet::<Watertight, _, N>(&view, view.bvh4().unwrap(), &p, &mut hits, &mut NoProbe, c)
            }
            Accel::Bvh8 => {
                trace_bvh8_packet::<Watertight, _, N>(&view, view.bvh8().unwrap(), &p, &mut hits, &mut NoProbe, c)
            }
            _ => {}
        }
        assert_eq!(hits.to_vec(), want, "{accel:?}, N = {N}");
        // The step kernels (the hardware model's) with stray bits too.
        let rays: [Ray; N] = core::array::from_fn(|i| p.ray(i));
        let mut step_hits = [None; N];
        trace_packet_steps::<Watertight, _, N>(&view, &rays, u64::MAX, &mut step_hits, &mut NoProbe);
        assert_eq!(step_hits.to_vec(), want, "steps, {accel:?}, N = {N}");
    }
}

#[test]
fn stray_active_bits_are_ignored_by_every_packet_kernel() {
    every_kernel_on::<1>();
    every_kernel_on::<4>();
    every_kernel_on::<16>();
    every_kernel_on::<64>();
}

#[test]
fn lane_indices_past_the_end_do_nothing() {
    let mut p = packet::<4>();
    let before = p;
    let r = Ray::new(Vec3::ZERO, Vec3::X);
    p.set(4, &r);
    p.set(usize::MAX, &r);
    p.set4(usize::MAX - 1, Vec3::ZERO, [Vec4::ONE; 3], 0.0, 1.0, 0xF);
    p.set4(1, Vec3::ZERO, [Vec4::ONE; 3], 0.0, 1.0, 0xF);
    assert_eq!(p.active, before.active);
    assert_eq!(p.ox, before.ox);
    // Past the end, `ray` answers with the last lane's ray.
    assert_eq!(p.ray(usize::MAX).dir, p.ray(3).dir);
    let mut one = RayPacket::<1>::new();
    one.set4(0, Vec3::ZERO, [Vec4::ONE; 3], 0.0, 1.0, 0xF);
    assert_eq!(one.active, 0);
}
