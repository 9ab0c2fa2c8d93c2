//! The one module of raypipe-core with `unsafe` code: the x86-64 AVX forms of six
//! kernels and the AVX-512 forms of two of them, and the switches that let them run. Every other
//! module is `#[forbid(unsafe_code)]` (see `lib.rs`).
//!
//! A `no_std` library cannot ask the operating system which instruction sets the CPU
//! has, so the host detects them and says so once ([`assume_avx`], `raypipe`'s
//! `isa::report_cpu`). Until then, and on other architectures, every kernel runs its
//! portable form. Either form gives the same bits (each AVX form has a test comparing it
//! with the portable one lane for lane), but for the fused node test, which is
//! conservative as the portable one is (tested against an exact `f64` box test): it may
//! let a walk visit a node more, never lose a hit.
//!
//! The AVX forms are `#[target_feature(enable = "avx")]` functions, which are unsafe to
//! call. Each is reached only through a safe function of this module that takes an
//! [`Avx`] token, and a token exists only once the host has reported AVX: holding one is
//! the proof every `unsafe` block here relies on. The forms:
//!
//! * `slab8`: the 8-wide BVH's node test (one register per plane, one move-mask), and
//!   with an [`AvxFma`] token (AVX and FMA) its fused form, one multiply-subtract per
//!   plane — conservative like the portable form, not bit for bit the same;
//! * `leaf_entries`: which rays of a packet enter a leaf's box, eight lanes at a time;
//! * `transpose`: eight rays into a packet's lanes by one 8×8 transpose;
//! * `watertight8`: the watertight test on eight rays against a leaf's shared
//!   triangles;
//!
//! and, with a [`Wide16`] token, `rays16`: sixteen rays of many origins against a 4-wide
//! node's boxes and against one triangle (shadow packets of 16, as Embree's
//! `rtcOccluded16` tests sixteen rays at once): in one AVX-512 register per quantity
//! where the CPU has AVX-512 F, else in two AVX registers.

/// The watertight test's edge functions `[U, V, W]` (`intersect::watertight`'s
/// `shear_edges` with the frame's axes 0, 1, 2: Woop et al. 2013, Fig. 1 lines 15–29) in
/// the intrinsics of one register width, `$sub` and `$mul`, on vertices `$a`, `$b`, `$c`
/// relative to the rays' origins and the shear `$sx`, `$sy`: the operations of the
/// one-ray test in its order, hence its bits in every lane. Written once for the AVX and
/// AVX-512 forms.
#[cfg(target_arch = "x86_64")]
macro_rules! watertight_edges {
    ($sub:ident, $mul:ident, $a:expr, $b:expr, $c:expr, $sx:expr, $sy:expr) => {{
        let (a, b, c, sx, sy) = ($a, $b, $c, $sx, $sy);
        let ax = $sub(a[0], $mul(sx, a[2]));
        let ay = $sub(a[1], $mul(sy, a[2]));
        let bx = $sub(b[0], $mul(sx, b[2]));
        let by = $sub(b[1], $mul(sy, b[2]));
        let cx = $sub(c[0], $mul(sx, c[2]));
        let cy = $sub(c[1], $mul(sy, c[2]));
        [$sub($mul(cx, by), $mul(cy, bx)), $sub($mul(ax, cy), $mul(ay, cx)), $sub($mul(bx, ay), $mul(by, ax))]
    }};
}

/// The watertight test's scaled distance (`scaled_distance`: `U·sz·az + V·sz·bz +
/// W·sz·cz`, in that order) in the intrinsics `$add` and `$mul` of one register width.
#[cfg(target_arch = "x86_64")]
macro_rules! watertight_scaled_distance {
    ($add:ident, $mul:ident, [$eu:expr, $ev:expr, $ew:expr], [$az:expr, $bz:expr, $cz:expr], $sz:expr) => {{
        let sz = $sz;
        $add($add($mul($eu, $mul(sz, $az)), $mul($ev, $mul(sz, $bz))), $mul($ew, $mul(sz, $cz)))
    }};
}

#[cfg(target_arch = "x86_64")]
pub(crate) mod leaf_entries;
#[cfg(target_arch = "x86_64")]
pub(crate) mod rays16;
#[cfg(target_arch = "x86_64")]
pub(crate) mod slab8;
#[cfg(target_arch = "x86_64")]
pub(crate) mod transpose;
#[cfg(target_arch = "x86_64")]
pub(crate) mod watertight8;

#[cfg(target_arch = "x86_64")]
use core::sync::atomic::{AtomicBool, Ordering};

#[cfg(target_arch = "x86_64")]
static AVX: AtomicBool = AtomicBool::new(false);

#[cfg(target_arch = "x86_64")]
static AVX512: AtomicBool = AtomicBool::new(false);
#[cfg(target_arch = "x86_64")]
static FMA: AtomicBool = AtomicBool::new(false);
// Set by `assume_avx16`: the sixteen-lane tests may take their AVX form.
#[cfg(target_arch = "x86_64")]
static AVX16: AtomicBool = AtomicBool::new(false);

/// Proof that the CPU has AVX: made only by [`Avx::reported`] once the host has called
/// [`assume_avx`] (or, in the unit tests, by asking the operating system). The AVX
/// forms of this module take one, so their callers need no `unsafe`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Avx(());

impl Avx {
    /// The token, if the host has reported AVX; `None` until then and on every other
    /// architecture.
    #[inline(always)]
    pub fn reported() -> Option<Avx> {
        #[cfg(target_arch = "x86_64")]
        if AVX.load(Ordering::Relaxed) {
            return Some(Avx(()));
        }
        None
    }

    /// The token, if the operating system says this CPU has AVX: for the unit tests
    /// that compare the AVX forms with the portable ones (core itself cannot ask).
    #[cfg(test)]
    pub(crate) fn detected() -> Option<Avx> {
        extern crate std;
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx") {
            return Some(Avx(()));
        }
        None
    }
}

/// Records that the CPU has AVX, so that the kernels may take their AVX forms.
///
/// # Safety
///
/// The CPU this process runs on must support AVX (e.g. `is_x86_feature_detected!("avx")`).
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
pub unsafe fn assume_avx() {
    AVX.store(true, Ordering::Relaxed);
}

/// True once [`assume_avx`] has been called.
#[inline(always)]
pub fn has_avx() -> bool {
    Avx::reported().is_some()
}

/// Proof that the CPU has AVX-512 F: made only by [`Avx512::reported`] once the host has
/// called [`assume_avx512`] (or, in the unit tests, by asking the operating system).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Avx512(());

impl Avx512 {
    /// The token, if the host has reported AVX-512 F; `None` until then and on every
    /// other architecture.
    #[inline(always)]
    pub fn reported() -> Option<Avx512> {
        #[cfg(target_arch = "x86_64")]
        if AVX512.load(Ordering::Relaxed) {
            return Some(Avx512(()));
        }
        None
    }

    /// The token, if the operating system says this CPU has AVX-512 F (unit tests).
    #[cfg(test)]
    pub(crate) fn detected() -> Option<Avx512> {
        extern crate std;
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx512f") {
            return Some(Avx512(()));
        }
        None
    }
}

/// Records that the CPU has AVX-512 F, so that the kernels may take their AVX-512 forms;
/// `false` takes them back (the portable and AVX forms run again), for comparisons.
///
/// # Safety
///
/// With `on`, the CPU this process runs on must support AVX-512 F
/// (`is_x86_feature_detected!("avx512f")`).
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
pub unsafe fn assume_avx512(on: bool) {
    AVX512.store(on, Ordering::Relaxed);
}

/// True once [`assume_avx512`] has been called (and not taken back).
#[inline(always)]
pub fn has_avx512() -> bool {
    Avx512::reported().is_some()
}

/// Proof that the sixteen-lane tests (`rays16`) may run, and in which form: with AVX-512
/// F one register per quantity, with AVX two (lanes 0–7 and 8–15). Both forms take the
/// four-lane forms' operations lane by lane, hence the same bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wide16 {
    /// AVX-512 F: sixteen lanes per instruction.
    Avx512(Avx512),
    /// AVX: eight lanes per instruction, each test run on both halves.
    Avx(Avx),
}

impl Wide16 {
    /// The widest form the host has reported: AVX-512, or AVX where [`assume_avx16`]
    /// allows it; `None` otherwise and on every other architecture.
    #[inline(always)]
    pub fn reported() -> Option<Wide16> {
        if let Some(t) = Avx512::reported() {
            return Some(Wide16::Avx512(t));
        }
        #[cfg(target_arch = "x86_64")]
        if AVX16.load(Ordering::Relaxed) {
            return Avx::reported().map(Wide16::Avx);
        }
        None
    }

    /// The forms the operating system says this CPU can run (unit tests).
    #[cfg(test)]
    pub(crate) fn detected_forms() -> [Option<Wide16>; 2] {
        [Avx512::detected().map(Wide16::Avx512), Avx::detected().map(Wide16::Avx)]
    }
}

/// Lets the sixteen-lane tests take their AVX form (two registers per quantity) where
/// the CPU has no AVX-512 (`on`), or keeps such packets on the four-lane groups; for
/// comparisons.
///
/// # Safety
///
/// With `on`, the CPU this process runs on must support AVX
/// (`is_x86_feature_detected!("avx")`).
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
pub unsafe fn assume_avx16(on: bool) {
    AVX16.store(on, Ordering::Relaxed);
}

/// Proof that the CPU has AVX and FMA: made only by [`AvxFma::reported`] once the host
/// has called [`assume_avx`] and [`assume_fma`] (or, in the unit tests, by asking the
/// operating system).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AvxFma(());

impl AvxFma {
    /// The token, if the host has reported AVX and FMA; `None` until then and on every
    /// other architecture.
    #[inline(always)]
    pub fn reported() -> Option<AvxFma> {
        #[cfg(target_arch = "x86_64")]
        if AVX.load(Ordering::Relaxed) && FMA.load(Ordering::Relaxed) {
            return Some(AvxFma(()));
        }
        None
    }

    /// The token, if the operating system says this CPU has AVX and FMA (unit tests).
    #[cfg(test)]
    pub(crate) fn detected() -> Option<AvxFma> {
        extern crate std;
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx") && std::is_x86_feature_detected!("fma") {
            return Some(AvxFma(()));
        }
        None
    }
}

/// Records that the CPU has FMA (with AVX: [`assume_avx`]), so that the 8-wide node test
/// may take its fused form; `false` takes it back, for comparisons.
///
/// # Safety
///
/// With `on`, the CPU this process runs on must support FMA
/// (`is_x86_feature_detected!("fma")`).
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
pub unsafe fn assume_fma(on: bool) {
    FMA.store(on, Ordering::Relaxed);
}
