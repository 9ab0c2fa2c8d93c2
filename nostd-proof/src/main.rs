//! A `#![no_std]`, `#![no_main]` program, as firmware would be, and a proof at link time
//! that raypipe-core cannot panic.
//!
//! It embeds the tetrahedron scene built with every structure (`include_scene!`),
//! validates each image, and for every eye ray of the image's camera runs every kernel a
//! firmware would call: the structure's single-ray walk and the generic walk with two
//! intersectors, brute force as the reference, the any-hit query, Lambert, Whitted and
//! path shading, and packets of 16 rays through the structure's packet kernel and the
//! step kernels (the hardware model's). It checks that they agree, prints the stack each
//! kernel took (measured by painting, `stack.rs`) and exits with 0.
//!
//! The panic handler calls a function that exists nowhere. The program is built with
//! link-time optimisation, so a panic path the kernels make impossible is removed; any
//! path that survives makes the link fail ("undefined symbol: raypipe_core_can_panic").
//! So a successful build proves that no panic is reachable from these kernels, on any
//! image `parse` accepts and any ray: the images and rays pass through `black_box`, so
//! the optimiser cannot use their contents.
//!
//! It runs on the build machine (linking the C library's start-up code), and as
//! bare-metal firmware on QEMU's Cortex-M4F board (`mps2-an386`) and RISC-V `virt`
//! board, started by cortex-m-rt or riscv-rt, reporting through semihosting (see
//! `build.rs` and `.cargo/config.toml`). With `--no-default-features --features <s>` it
//! holds one structure's image and kernel only: the smallest firmware of that structure.
#![no_std]
#![no_main]

mod out;
mod stack;

use core::hint::black_box;

use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::shade::lambert::shade;
use raypipe_core::shade::ray_cone::RayCone;
use raypipe_core::traverse::brute_force::trace_brute_force;
use raypipe_core::{Hit, NoProbe, Ray, RayCounters, SceneView, Vec3};

/// The triangle test of the structure's own walk: the watertight test in `f32`, or with
/// the `fixed` feature the fixed-point datapath in Q16.16 (its box and triangle tests;
/// for the BVHs only, whose box tests it has).
#[cfg(all(feature = "fixed", any(feature = "grid", feature = "kd")))]
compile_error!("the fixed-point datapath has box tests for the BVHs only: build it with bvh, bvh4 or bvh8");
#[cfg(not(feature = "fixed"))]
type Datapath = raypipe_core::Watertight;
#[cfg(feature = "fixed")]
type Datapath = raypipe_core::Q16_16;

/// The tetrahedron with each structure (`raypipe build fixtures/tetra.obj --accel …`).
static IMAGES: &[(&str, &[u8])] = &[
    #[cfg(feature = "grid")]
    ("grid", raypipe_core::include_scene!("../../fixtures/tetra.rpsi")),
    #[cfg(feature = "kd")]
    ("kd", raypipe_core::include_scene!("../../fixtures/tetra-kd.rpsi")),
    #[cfg(feature = "bvh")]
    ("bvh", raypipe_core::include_scene!("../../fixtures/tetra-bvh.rpsi")),
    #[cfg(feature = "bvh4")]
    ("bvh4", raypipe_core::include_scene!("../../fixtures/tetra-bvh4.rpsi")),
    #[cfg(feature = "bvh8")]
    ("bvh8", raypipe_core::include_scene!("../../fixtures/tetra-bvh8.rpsi")),
];

#[cfg(not(feature = "find-panics"))]
extern "C" {
    /// Defined nowhere: if any panic path survives optimisation, the link fails.
    fn raypipe_core_can_panic() -> !;
}

#[cfg(not(feature = "find-panics"))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // SAFETY: never runs. The symbol does not exist, so a program that could call this
    // does not link.
    unsafe { raypipe_core_can_panic() }
}

#[cfg(feature = "find-panics")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    #[allow(clippy::empty_loop)]
    loop {}
}

/// The precompiled `core` still names the unwinding personality routine even with
/// `panic = "abort"`; with nothing to unwind it is never called.
#[cfg(not(target_os = "none"))]
#[no_mangle]
pub extern "C" fn rust_eh_personality() {}

fn same(a: &Option<Hit>, b: &Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => a.bits_eq(b),
        _ => false,
    }
}

/// The structure's own single-ray kernel (only those of the structures built in).
#[inline(never)]
fn trace_structure(view: &SceneView<'_>, ray: &Ray) -> Option<Hit> {
    let (p, c) = (&mut NoProbe, &mut RayCounters::default());
    #[cfg(feature = "grid")]
    if let Some(g) = view.grid() {
        return raypipe_core::traverse::grid::trace_grid::<Datapath, _>(view, g, ray, p, c);
    }
    #[cfg(feature = "kd")]
    if let Some(t) = view.kdtree() {
        return raypipe_core::traverse::kdtree::trace_kdtree::<Datapath, _>(view, t, ray, p, c);
    }
    #[cfg(feature = "bvh4")]
    if let Some(t) = view.bvh4() {
        return raypipe_core::traverse::wide_bvh::node4::trace_bvh4::<Datapath, _>(view, t, ray, p, c);
    }
    #[cfg(feature = "bvh8")]
    if let Some(t) = view.bvh8() {
        return raypipe_core::traverse::wide_bvh::node8::trace_bvh8::<Datapath, _>(view, t, ray, p, c);
    }
    #[cfg(feature = "bvh")]
    if let Some(t) = view.bvh() {
        return raypipe_core::traverse::bvh::trace_bvh::<Datapath, _>(view, t, ray, p, c);
    }
    let _ = (view, ray, p, c);
    None
}

/// Lambert shading of a hit (a call of its own, so that its stack is measured apart).
#[inline(never)]
fn shade_hit(view: &SceneView<'_>, ray: &Ray, hit: Option<Hit>) -> Vec3 {
    shade(view, ray, RayCone::POINT, hit, Vec3::ZERO, &mut NoProbe)
}

/// The rest of the kernels, in the full build.
#[cfg(feature = "all")]
mod full {
    use super::*;
    use raypipe_core::packet::bvh::trace_bvh_packet;
    use raypipe_core::packet::bvh4::trace_bvh4_packet;
    use raypipe_core::packet::grid::trace_grid_packet;
    use raypipe_core::packet::kdtree::trace_kdtree_packet;
    use raypipe_core::packet::step::trace_packet_steps;
    use raypipe_core::packet::{PacketCounters, RayPacket};
    use raypipe_core::shade::path::PathOptions;
    use raypipe_core::shade::ray_record::RayRecord;
    use raypipe_core::shade::shader::Shader;
    use raypipe_core::shade::whitted::WhittedOptions;
    use raypipe_core::traverse::occlusion::occluded;
    use raypipe_core::traverse::walk::trace_walk;
    use raypipe_core::{MollerTrumbore, Watertight};

    /// The generic walk with two intersectors agrees with `want`, and so does any-hit.
    #[inline(never)]
    pub fn walks_agree(view: &SceneView<'_>, ray: &Ray, want: &Option<Hit>) -> bool {
        let p = &mut NoProbe;
        same(&trace_walk::<Watertight, _>(view, ray, p), want)
            && same(&trace_walk::<MollerTrumbore, _>(view, ray, p).and(*want), want)
    }

    /// The fixed-point datapath in Q16.16 and Q12.12: on a BVH (or none) the generic walk
    /// gives the fixed-point brute-force hit. (On a grid or kd-tree, whose steps are f32
    /// and not conservative for it, it runs for the link-time proof only.)
    #[inline(never)]
    pub fn fixed_agrees(view: &SceneView<'_>, ray: &Ray) -> bool {
        fn one<I: raypipe_core::Intersector>(view: &SceneView<'_>, ray: &Ray) -> bool {
            let got = trace_walk::<I, _>(view, ray, &mut NoProbe);
            if view.grid().is_some() || view.kdtree().is_some() {
                black_box(got);
                return true;
            }
            same(&got, &trace_brute_force::<I, _>(view, ray, &mut NoProbe, &mut RayCounters::default()))
        }
        one::<raypipe_core::Q16_16>(view, ray) && one::<raypipe_core::Q12_12>(view, ray)
    }

    #[inline(never)]
    pub fn any_hit(view: &SceneView<'_>, ray: &Ray) -> bool {
        occluded::<Watertight, _>(view, ray, &mut NoProbe, &mut RayCounters::default())
    }

    /// Whitted and path shading of a primary hit: their radiance, and records emitted.
    #[inline(never)]
    pub fn shaders(view: &SceneView<'_>, ray: Ray, pixel: u32, hit: Option<Hit>) -> (Vec3, u32) {
        let whitted = Shader::Whitted(WhittedOptions { max_depth: 2, background: Vec3::ZERO });
        let path = Shader::Path(PathOptions::new(2, true, Vec3::ZERO));
        let rec = RayRecord::primary(ray, pixel);
        let (mut radiance, mut records) = (Vec3::ZERO, 0u32);
        for shader in [&whitted, &path] {
            radiance += shader.shade(view, &rec, hit, &mut NoProbe, &mut |r| {
                records += 1;
                black_box(r);
            });
        }
        (radiance, records)
    }

    /// The structure's packet kernel (none for the 8-wide BVH: its packets are the step
    /// kernels') and the step kernels on a packet of 16: both agree with `want`.
    #[inline(never)]
    pub fn packets_agree(view: &SceneView<'_>, rays: &[Ray; 16], active: u64, want: &[Option<Hit>; 16]) -> bool {
        let mut packet = RayPacket::<16>::new();
        for (i, r) in rays.iter().enumerate() {
            if active & (1 << i) != 0 {
                packet.set(i, r);
            }
        }
        let (p, c) = (&mut NoProbe, &mut PacketCounters::default());
        let mut got = [None; 16];
        let ran = if let Some(g) = view.grid() {
            trace_grid_packet::<Watertight, _, 16>(view, g, &packet, &mut got, p, c);
            true
        } else if let Some(t) = view.kdtree() {
            trace_kdtree_packet::<Watertight, _, 16>(view, t, &packet, &mut got, p, c);
            true
        } else if let Some(t) = view.bvh4() {
            trace_bvh4_packet::<Watertight, _, 16>(view, t, &packet, &mut got, p, c);
            true
        } else if let Some(t) = view.bvh() {
            trace_bvh_packet::<Watertight, _, 16>(view, t, &packet, &mut got, p, c);
            true
        } else {
            false
        };
        if ran && !got.iter().zip(want).all(|(a, b)| same(a, b)) {
            return false;
        }
        trace_packet_steps::<Watertight, _, 16>(view, rays, packet.active, &mut got, p);
        got.iter().zip(want).all(|(a, b)| same(a, b))
    }
}

/// The most stack any kernel took, per kernel kind, in bytes.
#[derive(Default)]
struct Depths {
    walk: usize,
    any_hit: usize,
    packet: usize,
    shading: usize,
}

/// Exit codes: 0 all good; 2 an image rejected; 3 no camera; 4 a kernel disagrees with
/// brute force; 5 the any-hit query disagrees; 6 a packet disagrees; 7 implausible hits;
/// 8 the fixed-point walk disagrees with fixed-point brute force; 9 (from [`run`]) the
/// guaranteed range is not the one this build documents.
fn check(image: &[u8], depths: &mut Depths) -> i32 {
    let Ok(view) = SceneView::parse(image) else { return 2 };
    let Some(cam) = view.camera() else { return 3 };
    let Ok(eye) = EyeRays::new(&Camera::from(cam)) else { return 3 };
    #[cfg_attr(not(feature = "all"), allow(unused_mut))]
    let (mut hits, mut records) = (0u32, 0u32);
    let mut radiance = Vec3::ZERO;
    for y in 0..eye.height {
        for x in 0..eye.width {
            let ray = black_box(eye.ray(x, y));
            let want = trace_brute_force::<Datapath, _>(&view, &ray, &mut NoProbe, &mut RayCounters::default());
            let mut got = None;
            depths.walk = depths.walk.max(stack::depth_of(|| got = trace_structure(&view, &ray)));
            if !same(&got, &want) {
                return 4;
            }
            hits += want.is_some() as u32;
            let mut color = Vec3::ZERO;
            depths.shading = depths.shading.max(stack::depth_of(|| color = shade_hit(&view, &ray, want)));
            radiance += color;
            #[cfg(feature = "all")]
            {
                if !full::walks_agree(&view, &ray, &want) {
                    return 4;
                }
                if !full::fixed_agrees(&view, &ray) {
                    return 8;
                }
                let mut any = false;
                depths.any_hit = depths.any_hit.max(stack::depth_of(|| any = full::any_hit(&view, &ray)));
                if any != want.is_some() {
                    return 5;
                }
                let mut shaded = (Vec3::ZERO, 0);
                let d = stack::depth_of(|| shaded = full::shaders(&view, ray, y * eye.width + x, want));
                depths.shading = depths.shading.max(d);
                radiance += shaded.0;
                records += shaded.1;
            }
        }
    }
    #[cfg(feature = "all")]
    for by in 0..eye.height.div_ceil(4) {
        for bx in 0..eye.width.div_ceil(4) {
            let mut rays = [Ray::new(Vec3::ZERO, Vec3::X); 16];
            let mut active = 0u64;
            for (i, r) in rays.iter_mut().enumerate() {
                let (x, y) = (bx * 4 + i as u32 % 4, by * 4 + i as u32 / 4);
                if x < eye.width && y < eye.height {
                    *r = black_box(eye.ray(x, y));
                    active |= 1 << i;
                }
            }
            let want: [Option<Hit>; 16] = core::array::from_fn(|i| {
                let ray = rays.get(i).filter(|_| active & (1 << i) != 0)?;
                trace_brute_force::<raypipe_core::Watertight, _>(&view, ray, &mut NoProbe, &mut RayCounters::default())
            });
            let mut ok = false;
            depths.packet =
                depths.packet.max(stack::depth_of(|| ok = full::packets_agree(&view, &rays, active, &want)));
            if !ok {
                return 6;
            }
        }
    }
    // The floor fills the lower part of the view: some rays hit, some miss; the shaders
    // lit something (and, in the full build, emitted shadow rays).
    let total = eye.width * eye.height;
    let emitted = records > 0 || cfg!(not(feature = "all"));
    if hits == 0 || hits == total || !emitted || radiance.x.is_nan() || radiance.x <= 0.0 {
        return 7;
    }
    0
}

/// Checks every image built in and prints the stack each kind of kernel took.
fn run() -> i32 {
    // Without f64-fallback (the default) the guaranteed range ends 4096 extents from the
    // origin, where an edge function rounding to exactly 0 could lie outside the
    // triangle's box; with it there is no such end (exit code 9 if the range says
    // otherwise).
    use raypipe_core::range::{check_bounds, OutOfRange, F64_FALLBACK};
    let unit = Vec3::splat(1.0);
    let near = check_bounds(Vec3::splat(4095.0), Vec3::splat(4095.0) + unit);
    let far = check_bounds(Vec3::splat(1e5), Vec3::splat(1e5) + unit);
    let want_far = if F64_FALLBACK { Ok(()) } else { Err(OutOfRange::FarFromOrigin) };
    if near.is_err() || far != want_far {
        out::line(format_args!("the guaranteed range does not end where this build documents"));
        return 9;
    }
    out::line(format_args!("structure  walk B  any-hit B  packet16 B  shading B"));
    for (name, image) in IMAGES {
        let mut d = Depths::default();
        let code = check(black_box(image), &mut d);
        out::line(format_args!("{name:<9} {:>7} {:>10} {:>11} {:>10}", d.walk, d.any_hit, d.packet, d.shading));
        if code != 0 {
            out::line(format_args!("{name}: check failed with code {code}"));
            return code;
        }
    }
    out::line(format_args!("every kernel agreed on every structure: ok"));
    0
}

#[cfg(not(target_os = "none"))]
#[no_mangle]
pub extern "C" fn main(_argc: i32, _argv: *const *const u8) -> i32 {
    run()
}

#[cfg(target_arch = "arm")]
#[cortex_m_rt::entry]
fn entry() -> ! {
    // The Cortex-M4F's FPU is off after reset; the kernels' f32 code needs it.
    // SAFETY: CPACR (0xE000_ED88) enables coprocessors 10 and 11 (the FPU), full access.
    unsafe {
        let cpacr = 0xE000_ED88 as *mut u32;
        core::ptr::write_volatile(cpacr, core::ptr::read_volatile(cpacr) | (0xF << 20));
        core::arch::asm!("dsb", "isb");
    }
    semihosting::process::exit(run())
}

#[cfg(target_arch = "riscv32")]
#[riscv_rt::entry]
fn entry() -> ! {
    semihosting::process::exit(run())
}
