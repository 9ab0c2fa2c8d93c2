//! raypipe-core for C firmware: a small `extern "C"` surface over the kernels, with no
//! heap and no panics (the library's own panic handler names a symbol that exists
//! nowhere, so a C program links only if no panic path survived link-time optimisation,
//! the same proof as `nostd-proof/`).
//!
//! The scene image stays where the caller keeps it (flash, RAM): `rp_scene_parse`
//! validates it once and writes the view into caller-provided storage (`RpScene`, a
//! fixed-size opaque record). The image must outlive the view and not move.
//!
//! Every function checks its pointers for null and its counts, and answers with a code
//! or "no hit"; none can fail in any other way.
#![no_std]

use core::mem::{align_of, size_of, MaybeUninit};

use raypipe_core::camera::{Camera, EyeRays};
use raypipe_core::packet::step::trace_packet_steps;
use raypipe_core::shade::lambert::shade;
use raypipe_core::shade::ray_cone::RayCone;
use raypipe_core::traverse::brute_force::trace_brute_force;
use raypipe_core::traverse::occlusion::occluded;
use raypipe_core::traverse::walk::trace_walk;
use raypipe_core::{Hit, NoProbe, Ray, RayCounters, SceneError, SceneView, Vec3, Watertight};

/// Words of storage a parsed scene takes (`RpScene`).
pub const RP_SCENE_WORDS: usize = 82;

/// A parsed scene: opaque storage for the validated view of an image. Fill it with
/// `rp_scene_parse`; it borrows the image, which must stay in place.
// `u64` words give it 8-byte alignment in C as in Rust.
#[repr(C)]
pub struct RpScene {
    /// Opaque.
    pub opaque: [u64; RP_SCENE_WORDS],
}

const _: () = assert!(size_of::<SceneView<'static>>() <= size_of::<RpScene>());
const _: () = assert!(align_of::<SceneView<'static>>() <= align_of::<RpScene>());

/// A ray: origin, direction (need not be unit length) and the interval `[t_min, t_max]`
/// (`0 <= t_min <= t_max`; `t_max` may be infinite). Any other ray hits nothing.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct RpRay {
    /// Origin.
    pub origin: [f32; 3],
    /// Direction.
    pub dir: [f32; 3],
    /// Interval start.
    pub t_min: f32,
    /// Interval end.
    pub t_max: f32,
}

/// A hit: distance along the ray, barycentric coordinates of the second and third
/// vertex, the triangle (its index in the image), its geometric normal, its material
/// and the object it came from (as Embree's `RTCHit` has `Ng`, `primID`, `geomID`).
#[repr(C)]
#[derive(Clone, Copy, Default)]
pub struct RpHit {
    /// Distance along the ray (in units of the direction's length).
    pub t: f32,
    /// Barycentric weight of the triangle's second vertex.
    pub u: f32,
    /// Barycentric weight of the third vertex.
    pub v: f32,
    /// Triangle index.
    pub prim: u32,
    /// Geometric normal, not normalized: `(b − a) × (c − a)` of the triangle's vertices
    /// `a b c` (its length is twice the triangle's area; it faces the side the winding
    /// is counter-clockwise from).
    pub ng: [f32; 3],
    /// Material number (an index into the image's materials; `RP_NO_MATERIAL` when the
    /// image has none).
    pub material: u32,
    /// The object the triangle came from (an OBJ `o`/`g`, a glTF node; 0 when the image
    /// does not record objects).
    pub object: u32,
}

/// A linear RGB colour.
#[repr(C)]
#[derive(Clone, Copy, Default)]
pub struct RpRgb {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
}

/// `RpHit::material` of an image without materials.
pub const RP_NO_MATERIAL: u32 = u32::MAX;

/// Success.
pub const RP_OK: i32 = 0;
/// A null pointer or an impossible count was passed.
pub const RP_ERR_ARGUMENT: i32 = 1;
/// The image is shorter than its header says, or than a header.
pub const RP_ERR_TRUNCATED: i32 = 2;
/// The image does not start on a 16-byte boundary.
pub const RP_ERR_MISALIGNED: i32 = 3;
/// Not a raypipe scene image, or a version or feature this library does not read.
pub const RP_ERR_NOT_AN_IMAGE: i32 = 4;
/// The checksum does not match: the image is corrupted.
pub const RP_ERR_CHECKSUM: i32 = 5;
/// A section, record, index or structure of the image is invalid.
pub const RP_ERR_INVALID: i32 = 6;
/// The image has no camera (`rp_camera_ray`), or its camera is unusable.
pub const RP_ERR_NO_CAMERA: i32 = 7;

fn ray_of(r: &RpRay) -> Ray {
    Ray { origin: Vec3::from(r.origin), dir: Vec3::from(r.dir), t_min: r.t_min, t_max: r.t_max }
}

fn hit_of(view: &SceneView<'_>, h: &Hit) -> RpHit {
    let [a, b, c] = view.triangle(h.prim, &mut NoProbe);
    RpHit {
        t: h.t,
        u: h.u,
        v: h.v,
        prim: h.prim,
        ng: (b - a).cross(c - a).to_array(),
        material: view.material_id(h.prim, &mut NoProbe).unwrap_or(RP_NO_MATERIAL),
        object: view.object_of(h.prim),
    }
}

/// The library's version, `major << 16 | minor << 8 | patch` (0.1.0 is 0x000100).
#[no_mangle]
pub extern "C" fn rp_version() -> u32 {
    let part = |s: &str| s.parse::<u32>().unwrap_or(0) & 0xff;
    let (major, minor, patch) = (
        part(env!("CARGO_PKG_VERSION_MAJOR")),
        part(env!("CARGO_PKG_VERSION_MINOR")),
        part(env!("CARGO_PKG_VERSION_PATCH")),
    );
    major << 16 | minor << 8 | patch
}

/// The library's version as text ("0.1.0"), a static NUL-terminated string.
#[no_mangle]
pub extern "C" fn rp_version_string() -> *const core::ffi::c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

/// What a status code means, as a static NUL-terminated English sentence (for logs);
/// an unknown code gets "unknown status code".
#[no_mangle]
pub extern "C" fn rp_status_string(code: i32) -> *const core::ffi::c_char {
    let text: &'static str = match code {
        RP_OK => "ok\0",
        RP_ERR_ARGUMENT => "a null pointer or an impossible count or pixel was passed\0",
        RP_ERR_TRUNCATED => "the image is shorter than its header says\0",
        RP_ERR_MISALIGNED => "the image does not start on a 16-byte boundary\0",
        RP_ERR_NOT_AN_IMAGE => "not a raypipe scene image, or a version this library does not read\0",
        RP_ERR_CHECKSUM => "the image's checksum does not match: it is corrupted\0",
        RP_ERR_INVALID => "a section, record, index or structure of the image is invalid\0",
        RP_ERR_NO_CAMERA => "the image has no camera, or its camera is unusable\0",
        _ => "unknown status code\0",
    };
    text.as_ptr().cast()
}

fn code_of(e: &SceneError) -> i32 {
    match e {
        SceneError::Truncated { .. } => RP_ERR_TRUNCATED,
        SceneError::Misaligned { .. } => RP_ERR_MISALIGNED,
        SceneError::BadMagic
        | SceneError::UnsupportedVersion { .. }
        | SceneError::UnknownFlags(_)
        | SceneError::UnknownAccel(_) => RP_ERR_NOT_AN_IMAGE,
        SceneError::ChecksumMismatch { .. } => RP_ERR_CHECKSUM,
        _ => RP_ERR_INVALID,
    }
}

/// The view in `scene`, if `rp_scene_parse` filled it.
///
/// # Safety
/// `scene` is null or points to an `RpScene` that `rp_scene_parse` filled, whose image
/// is still in place.
unsafe fn view<'a>(scene: *const RpScene) -> Option<&'a SceneView<'a>> {
    // SAFETY: the caller's contract; the storage is large and aligned enough (asserted).
    unsafe { scene.cast::<SceneView<'a>>().as_ref() }
}

/// Validates the scene image of `len` bytes at `bytes` (16-byte aligned, in place) and
/// writes its view into `*out`. Returns `RP_OK` or an `RP_ERR_*` code.
///
/// # Safety
/// `bytes` points to `len` readable bytes that stay in place and unchanged while `*out`
/// is used; `out` points to writable storage for an `RpScene`.
#[no_mangle]
pub unsafe extern "C" fn rp_scene_parse(bytes: *const u8, len: usize, out: *mut RpScene) -> i32 {
    if bytes.is_null() || out.is_null() {
        return RP_ERR_ARGUMENT;
    }
    // SAFETY: the caller's contract: `len` readable bytes, unchanged while in use.
    let image: &'static [u8] = unsafe { core::slice::from_raw_parts(bytes, len) };
    match SceneView::parse(image) {
        Ok(v) => {
            // SAFETY: `out` is writable storage of an `RpScene`, which holds a view.
            unsafe { out.cast::<MaybeUninit<SceneView<'static>>>().write(MaybeUninit::new(v)) };
            RP_OK
        }
        Err(e) => code_of(&e),
    }
}

/// The number of triangles of a parsed scene (0 for a null scene).
///
/// # Safety
/// `scene` is null or filled by `rp_scene_parse`, its image still in place.
#[no_mangle]
pub unsafe extern "C" fn rp_triangle_count(scene: *const RpScene) -> u32 {
    // SAFETY: the caller's contract.
    unsafe { view(scene) }.map_or(0, |v| v.triangle_count())
}

/// The size the image's camera was built for (`raypipe build --size`), written to
/// `*width` and `*height`. Returns `RP_OK`, `RP_ERR_NO_CAMERA` or `RP_ERR_ARGUMENT`.
///
/// # Safety
/// `scene` is null or filled by `rp_scene_parse`; `width` and `height` are null or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn rp_camera_size(scene: *const RpScene, width: *mut u32, height: *mut u32) -> i32 {
    // SAFETY: the caller's contract.
    let (Some(v), Some(w), Some(h)) = (unsafe { view(scene) }, unsafe { width.as_mut() }, unsafe { height.as_mut() })
    else {
        return RP_ERR_ARGUMENT;
    };
    let Some(cam) = v.camera() else { return RP_ERR_NO_CAMERA };
    (*w, *h) = (cam.width, cam.height);
    RP_OK
}

/// The eye ray through pixel `(x, y)` of a `width × height` image seen by the scene's
/// camera. Returns `RP_OK`, `RP_ERR_NO_CAMERA` or `RP_ERR_ARGUMENT` (null pointers,
/// pixel outside the image).
///
/// # Safety
/// `scene` is null or filled by `rp_scene_parse`; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn rp_camera_ray(
    scene: *const RpScene,
    x: u32,
    y: u32,
    width: u32,
    height: u32,
    out: *mut RpRay,
) -> i32 {
    // SAFETY: the caller's contract.
    let (Some(v), Some(out)) = (unsafe { view(scene) }, unsafe { out.as_mut() }) else {
        return RP_ERR_ARGUMENT;
    };
    if x >= width || y >= height {
        return RP_ERR_ARGUMENT;
    }
    let Some(cam) = v.camera() else { return RP_ERR_NO_CAMERA };
    let mut cam = *cam;
    (cam.width, cam.height) = (width, height);
    let Ok(eye) = EyeRays::new(&Camera::from(&cam)) else { return RP_ERR_NO_CAMERA };
    let r = eye.ray(x, y);
    *out = RpRay { origin: r.origin.to_array(), dir: r.dir.to_array(), t_min: r.t_min, t_max: r.t_max };
    RP_OK
}

/// The closest hit of `*ray` (watertight test, the image's structure). Returns whether
/// it hit; `*hit` is written only then.
///
/// # Safety
/// `scene` is null or filled by `rp_scene_parse`; `ray` is null or readable; `hit` is
/// null or writable.
#[no_mangle]
pub unsafe extern "C" fn rp_trace(scene: *const RpScene, ray: *const RpRay, hit: *mut RpHit) -> bool {
    // SAFETY: the caller's contract.
    let (Some(v), Some(r), Some(out)) = (unsafe { view(scene) }, unsafe { ray.as_ref() }, unsafe { hit.as_mut() })
    else {
        return false;
    };
    match trace_walk::<Watertight, _>(v, &ray_of(r), &mut NoProbe) {
        Some(h) => {
            *out = hit_of(v, &h);
            true
        }
        None => false,
    }
}

/// The closest hit by testing every triangle: the reference every structure agrees with.
///
/// # Safety
/// As `rp_trace`.
#[no_mangle]
pub unsafe extern "C" fn rp_trace_brute_force(scene: *const RpScene, ray: *const RpRay, hit: *mut RpHit) -> bool {
    // SAFETY: the caller's contract.
    let (Some(v), Some(r), Some(out)) = (unsafe { view(scene) }, unsafe { ray.as_ref() }, unsafe { hit.as_mut() })
    else {
        return false;
    };
    match trace_brute_force::<Watertight, _>(v, &ray_of(r), &mut NoProbe, &mut RayCounters::default()) {
        Some(h) => {
            *out = hit_of(v, &h);
            true
        }
        None => false,
    }
}

/// Whether anything lies on `*ray` within its interval (any hit: shadow rays).
///
/// # Safety
/// `scene` is null or filled by `rp_scene_parse`; `ray` is null or readable.
#[no_mangle]
pub unsafe extern "C" fn rp_occluded(scene: *const RpScene, ray: *const RpRay) -> bool {
    // SAFETY: the caller's contract.
    let (Some(v), Some(r)) = (unsafe { view(scene) }, unsafe { ray.as_ref() }) else { return false };
    occluded::<Watertight, _>(v, &ray_of(r), &mut NoProbe, &mut RayCounters::default())
}

/// Traces `count` rays (at most 64) as packets of 16 sharing one walk (the hardware
/// model's step kernels): `hits[i]` receives ray `i`'s closest hit and bit `i` of the
/// result says whether it hit. 0 for null pointers or more than 64 rays.
///
/// # Safety
/// `scene` is null or filled by `rp_scene_parse`; `rays` is null or points to `count`
/// readable rays; `hits` is null or points to `count` writable hits.
#[no_mangle]
pub unsafe extern "C" fn rp_trace_packet(
    scene: *const RpScene,
    rays: *const RpRay,
    count: u32,
    hits: *mut RpHit,
) -> u64 {
    // SAFETY: the caller's contract.
    let Some(v) = (unsafe { view(scene) }) else { return 0 };
    if rays.is_null() || hits.is_null() || count > 64 {
        return 0;
    }
    // SAFETY: the caller's contract: `count` readable rays, `count` writable hits.
    let (rays, hits) = unsafe {
        (core::slice::from_raw_parts(rays, count as usize), core::slice::from_raw_parts_mut(hits, count as usize))
    };
    let mut mask = 0u64;
    for (chunk, (rays, hits)) in rays.chunks(16).zip(hits.chunks_mut(16)).enumerate() {
        let lanes: [Ray; 16] = core::array::from_fn(|i| rays.get(i).map_or(Ray::new(Vec3::ZERO, Vec3::ZERO), ray_of));
        let mut found = [None; 16];
        trace_packet_steps::<Watertight, _, 16>(v, &lanes, (1u64 << rays.len()) - 1, &mut found, &mut NoProbe);
        for (i, (slot, h)) in hits.iter_mut().zip(found).enumerate() {
            if let Some(h) = h {
                *slot = hit_of(v, &h);
                mask |= 1 << (16 * chunk + i);
            }
        }
    }
    mask
}

/// Lambert shading of a ray's hit (`hit` null: what a ray that escapes sees — the
/// image's sky, else `background`) in linear RGB, written to `*out`. Textures are read
/// at their finest mipmap level (the ray carries no cone).
///
/// # Safety
/// `scene` is null or filled by `rp_scene_parse`; `ray` is null or readable; `hit` is
/// null or readable; `out` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn rp_shade(
    scene: *const RpScene,
    ray: *const RpRay,
    hit: *const RpHit,
    background: RpRgb,
    out: *mut RpRgb,
) -> i32 {
    // SAFETY: the caller's contract.
    let (Some(v), Some(r), Some(out)) = (unsafe { view(scene) }, unsafe { ray.as_ref() }, unsafe { out.as_mut() })
    else {
        return RP_ERR_ARGUMENT;
    };
    // SAFETY: the caller's contract.
    let h = unsafe { hit.as_ref() }.map(|h| Hit { t: h.t, u: h.u, v: h.v, prim: h.prim });
    // A hit on a triangle the image does not have is no hit.
    let h = h.filter(|h| h.prim < v.triangle_count());
    let bg = Vec3::new(background.r, background.g, background.b);
    let [r, g, b] = shade(v, &ray_of(r), RayCone::POINT, h, bg, &mut NoProbe).to_array();
    *out = RpRgb { r, g, b };
    RP_OK
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    extern "C" {
        /// Defined nowhere: a program using this library links only if no panic path
        /// survived link-time optimisation.
        fn raypipe_capi_can_panic() -> !;
    }
    // SAFETY: never runs (see above).
    unsafe { raypipe_capi_can_panic() }
}
