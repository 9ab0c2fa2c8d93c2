//! Any bytes as an instanced scene: `InstancedView::parse` returns an error or a view;
//! on a view every bottom image is validated, and the reference walk, its any-hit form
//! and the packet walk run on rays made from the input — no panic, and one hit from
//! every path.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raypipe::platform::aligned::AlignedBytes;
use raypipe_core::image::instanced::InstancedView;
use raypipe_core::packet::instanced::trace_instanced_packet;
use raypipe_core::packet::RayPacket;
use raypipe_core::traverse::instanced::{occluded_instanced, trace_instanced};
use raypipe_core::traverse::walk::trace_walk;
use raypipe_core::{NoProbe, Ray, SceneView, Vec3, Watertight};

fuzz_target!(|data: &[u8]| {
    let bytes = AlignedBytes::from_slice(data);
    let Ok(view) = InstancedView::parse(&bytes) else { return };
    let Ok(bottoms) = (0..view.bottom_count()).map(|b| view.bottom(b)).collect::<Result<Vec<SceneView<'_>>, _>>()
    else {
        return;
    };
    let top = view.top();
    let (lo, hi) = view.bounds();
    let centre = (lo + hi) * 0.5;
    let rays = [
        Ray::new(centre + Vec3::new(0.3, 0.7, 5.0) * (hi - lo + Vec3::ONE), Vec3::new(-0.05, -0.1, -1.0)),
        Ray::new(lo - Vec3::ONE, hi - lo + Vec3::ONE),
        Ray::new(centre, Vec3::X),
        Ray::new(hi + Vec3::ONE, lo - hi - Vec3::ONE),
    ];
    let mut packet = RayPacket::<4>::new();
    packet.fill(&rays);
    let mut hits = [None; 4];
    let mut c = Default::default();
    trace_instanced_packet(top, &bottoms, &packet, false, &mut hits, &mut NoProbe, &mut c, |v, p, h, probe, _| {
        for i in 0..4 {
            h[i] = if p.live() & (1 << i) != 0 { trace_walk::<Watertight, _>(v, &p.ray(i), probe) } else { None };
        }
    });
    for (k, ray) in rays.iter().enumerate() {
        let one = trace_instanced::<Watertight, _>(top, &bottoms, ray, &mut NoProbe);
        let key = |h: Option<raypipe_core::traverse::instanced::InstanceHit>| {
            h.map(|h| (h.hit.t.to_bits(), h.instance, h.hit.prim))
        };
        assert_eq!(key(one), key(hits[k]));
        assert_eq!(occluded_instanced::<Watertight, _>(top, &bottoms, ray, &mut NoProbe), one.is_some());
    }
});
