//! Software prefetch of the rays a batch streams through. Each ray of a batch is read
//! once, from memory rather than from a cache (32 MiB for 1024² rays), and a single ray's
//! walk cannot start before its record arrives: the out-of-order core does not reach
//! the next ray, hundreds of instructions on. Asking for a ray some rays ahead hides that
//! wait. (Packets gain nothing: their fill reads 64 rays in a row, which the hardware
//! prefetcher follows.)

/// Asks the CPU to bring the cache line holding the start of `item` into the L1 cache.
/// A hint only: it never faults and changes no result.
#[inline(always)]
pub fn prefetch<T>(item: Option<&T>) {
    #[cfg(target_arch = "x86_64")]
    if let Some(item) = item {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // SAFETY: the address is that of a live reference; a prefetch reads nothing
        // architecturally and cannot fault.
        unsafe { _mm_prefetch::<_MM_HINT_T0>((item as *const T).cast::<i8>()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = item;
}
