//! The optional instruction sets the CPU has, as the host reports them: a `no_std`
//! library cannot ask the operating system, so the host detects them and says so once
//! (`raypipe`'s `isa::report_cpu`). Until then, and on other architectures, every kernel
//! runs its portable form. Either form gives the same bits.

#[cfg(target_arch = "x86_64")]
use core::sync::atomic::{AtomicBool, Ordering};

#[cfg(target_arch = "x86_64")]
static AVX: AtomicBool = AtomicBool::new(false);

/// Records that the CPU has AVX, so that the 8-wide BVH's node test and the packets'
/// leaf entry test may use it.
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
    #[cfg(target_arch = "x86_64")]
    return AVX.load(Ordering::Relaxed);
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// Whether this CPU has AVX, asked of the operating system: for the unit tests that
/// compare the AVX forms with the portable ones (core itself cannot ask, see above).
#[cfg(test)]
pub(crate) fn detected_avx() -> bool {
    extern crate std;
    #[cfg(target_arch = "x86_64")]
    return std::is_x86_feature_detected!("avx");
    #[cfg(not(target_arch = "x86_64"))]
    false
}

#[cfg(target_arch = "x86_64")]
pub(crate) mod watertight8;
