//! A `#![no_std]`, `#![no_main]` program, as firmware would be, and a proof at link time
//! that raypipe-core cannot panic.
//!
//! It embeds the tetrahedron scene built with every structure (`include_scene!`),
//! validates each image, and for every eye ray of the image's camera runs every kernel a
//! firmware would call: the structure's single-ray walk and the generic walk with two
//! intersectors, brute force as the reference, the any-hit query, Lambert, Whitted and
//! path shading, and packets of 16 rays through the structure's packet kernel and the
//! step kernels (the hardware model's). It checks that they agree and returns 0.
//!
//! The panic handler calls a function that exists nowhere. The program is built with
//! link-time optimisation, so a panic path the kernels make impossible is removed; any
//! path that survives makes the link fail ("undefined symbol: raypipe_core_can_panic").
//! So a successful build proves that no panic is reachable from these kernels, on any
//! image `parse` accepts and any ray: the images and rays pass through `black_box`, so
//! the optimiser cannot use their contents.
//!
//! It links only `core`; on a hosted build machine it takes the C library's start-up
//! code (`main`), on a bare-metal target its own (see `build.rs`).
#![no_std]
#![no_main]

use core::hint::black_box;

use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::packet::bvh::trace_bvh_packet;
use raypipe_core::packet::bvh4::trace_bvh4_packet;
use raypipe_core::packet::grid::trace_grid_packet;
use raypipe_core::packet::kdtree::trace_kdtree_packet;
use raypipe_core::packet::step::trace_packet_steps;
use raypipe_core::packet::{PacketCounters, RayPacket};
use raypipe_core::shade::lambert::shade;
use raypipe_core::shade::path::PathOptions;
use raypipe_core::shade::ray_record::RayRecord;
use raypipe_core::shade::shader::Shader;
use raypipe_core::shade::whitted::WhittedOptions;
use raypipe_core::traverse::brute_force::trace_brute_force;
use raypipe_core::traverse::bvh::trace_bvh;
use raypipe_core::traverse::bvh4::trace_bvh4;
use raypipe_core::traverse::bvh8::trace_bvh8;
use raypipe_core::traverse::grid::trace_grid;
use raypipe_core::traverse::kdtree::trace_kdtree;
use raypipe_core::traverse::occlusion::occluded;
use raypipe_core::traverse::walk::trace_walk;
use raypipe_core::{Hit, MollerTrumbore, NoProbe, Ray, RayCounters, SceneView, Vec3, Watertight};

/// The tetrahedron with each structure (`raypipe build fixtures/tetra.obj --accel …`).
static IMAGES: [&[u8]; 5] = [
    raypipe_core::include_scene!("../../fixtures/tetra.rpsi"),
    raypipe_core::include_scene!("../../fixtures/tetra-kd.rpsi"),
    raypipe_core::include_scene!("../../fixtures/tetra-bvh.rpsi"),
    raypipe_core::include_scene!("../../fixtures/tetra-bvh4.rpsi"),
    raypipe_core::include_scene!("../../fixtures/tetra-bvh8.rpsi"),
];

extern "C" {
    /// Defined nowhere: if any panic path survives optimisation, the link fails.
    fn raypipe_core_can_panic() -> !;
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // SAFETY: never runs. The symbol does not exist, so a program that could call this
    // does not link.
    unsafe { raypipe_core_can_panic() }
}

/// The precompiled `core` still names the unwinding personality routine even with
/// `panic = "abort"`; with nothing to unwind it is never called.
#[no_mangle]
pub extern "C" fn rust_eh_personality() {}

fn same(a: &Option<Hit>, b: &Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => a.bits_eq(b),
        _ => false,
    }
}

/// The structure's own single-ray kernel.
fn trace_structure(view: &SceneView<'_>, ray: &Ray) -> Option<Hit> {
    let (p, c) = (&mut NoProbe, &mut RayCounters::default());
    if let Some(g) = view.grid() {
        trace_grid::<Watertight, _>(view, g, ray, p, c)
    } else if let Some(t) = view.kdtree() {
        trace_kdtree::<Watertight, _>(view, t, ray, p, c)
    } else if let Some(t) = view.bvh4() {
        trace_bvh4::<Watertight, _>(view, t, ray, p, c)
    } else if let Some(t) = view.bvh8() {
        trace_bvh8::<Watertight, _>(view, t, ray, p, c)
    } else if let Some(t) = view.bvh() {
        trace_bvh::<Watertight, _>(view, t, ray, p, c)
    } else {
        None
    }
}

/// The structure's packet kernel on `packet` (none for the 8-wide BVH: its packets are
/// the step kernels').
fn trace_packet(view: &SceneView<'_>, packet: &RayPacket<16>, hits: &mut [Option<Hit>; 16]) -> bool {
    let (p, c) = (&mut NoProbe, &mut PacketCounters::default());
    if let Some(g) = view.grid() {
        trace_grid_packet::<Watertight, _, 16>(view, g, packet, hits, p, c);
    } else if let Some(t) = view.kdtree() {
        trace_kdtree_packet::<Watertight, _, 16>(view, t, packet, hits, p, c);
    } else if let Some(t) = view.bvh4() {
        trace_bvh4_packet::<Watertight, _, 16>(view, t, packet, hits, p, c);
    } else if let Some(t) = view.bvh() {
        trace_bvh_packet::<Watertight, _, 16>(view, t, packet, hits, p, c);
    } else {
        return false;
    }
    true
}

/// Exit codes: 0 all good; 2 an image rejected; 3 no camera; 4 a kernel disagrees with
/// brute force; 5 the any-hit query disagrees; 6 a packet disagrees; 7 implausible hits.
fn check(image: &[u8]) -> i32 {
    let Ok(view) = SceneView::parse(image) else { return 2 };
    let Some(cam) = view.camera() else { return 3 };
    let Ok(eye) = EyeRays::new(&Camera::from(cam)) else { return 3 };
    let whitted = Shader::Whitted(WhittedOptions { max_depth: 2, background: Vec3::ZERO });
    let path = Shader::Path(PathOptions { bounces: 2, samples: 1, roulette: true, background: Vec3::ZERO });
    let (mut hits, mut records) = (0u32, 0u32);
    let mut radiance = Vec3::ZERO;
    for y in 0..eye.height {
        for x in 0..eye.width {
            let ray = black_box(eye.ray(x, y));
            let (p, c) = (&mut NoProbe, &mut RayCounters::default());
            let want = trace_brute_force::<Watertight, _>(&view, &ray, p, c);
            let kernels = [
                trace_structure(&view, &ray),
                trace_walk::<Watertight, _>(&view, &ray, p),
                trace_walk::<MollerTrumbore, _>(&view, &ray, p).and(want),
            ];
            if !kernels.iter().all(|h| same(h, &want)) {
                return 4;
            }
            if occluded::<Watertight, _>(&view, &ray, p, c) != want.is_some() {
                return 5;
            }
            hits += want.is_some() as u32;
            radiance += shade(&view, &ray, want, Vec3::ZERO, p);
            let rec = RayRecord::primary(ray, y * eye.width + x);
            for shader in [&whitted, &path] {
                radiance += shader.shade(&view, &rec, want, p, &mut |r| {
                    records += 1;
                    black_box(r);
                });
            }
        }
    }
    // Packets of 4 × 4 pixels: the structure's packet kernel and the step kernels.
    for by in 0..eye.height.div_ceil(4) {
        for bx in 0..eye.width.div_ceil(4) {
            let mut packet = RayPacket::<16>::new();
            let mut rays = [Ray::new(Vec3::ZERO, Vec3::X); 16];
            for (i, r) in rays.iter_mut().enumerate() {
                let (x, y) = (bx * 4 + i as u32 % 4, by * 4 + i as u32 / 4);
                if x < eye.width && y < eye.height {
                    *r = black_box(eye.ray(x, y));
                    packet.set(i, r);
                }
            }
            let want: [Option<Hit>; 16] = core::array::from_fn(|i| {
                if packet.active & (1 << i) == 0 {
                    return None;
                }
                trace_brute_force::<Watertight, _>(&view, &rays[i], &mut NoProbe, &mut RayCounters::default())
            });
            let mut got = [None; 16];
            if trace_packet(&view, &packet, &mut got) && !got.iter().zip(&want).all(|(a, b)| same(a, b)) {
                return 6;
            }
            trace_packet_steps::<Watertight, _, 16>(&view, &rays, packet.active, &mut got, &mut NoProbe);
            if !got.iter().zip(&want).all(|(a, b)| same(a, b)) {
                return 6;
            }
        }
    }
    // The floor fills the lower part of the view: some rays hit, some miss; the shaders
    // emitted shadow rays and lit something.
    let total = eye.width * eye.height;
    if hits == 0 || hits == total || records == 0 || radiance.x.is_nan() || radiance.x <= 0.0 {
        return 7;
    }
    0
}

#[no_mangle]
pub extern "C" fn main(_argc: i32, _argv: *const *const u8) -> i32 {
    for image in IMAGES {
        let code = check(black_box(image));
        if code != 0 {
            return code;
        }
    }
    0
}
