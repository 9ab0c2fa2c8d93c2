//! Transparent huge pages for the large arrays a trace streams through (the scene image,
//! the rays, the hits). Where the kernel hands out huge pages only on request (Linux's
//! `madvise` mode, the common default), each 2 MiB of a fresh array otherwise costs 512
//! page faults and as many TLB entries. NumPy asks for huge pages for every array of
//! 4 MiB or more; this asks for the same, for the same arrays.

/// Arrays smaller than this keep ordinary pages (NumPy's threshold).
const MIN_BYTES: usize = 4 << 20;

/// A vector of `n` copies of `value`, its memory advised to use huge pages before it is
/// first written.
pub fn filled_vec<T: Clone>(n: usize, value: T) -> Vec<T> {
    let mut v = empty_vec(n);
    v.resize(n, value);
    v
}

/// A vector of `n` copies of `zero`, a value whose bits are all zero, its memory advised
/// to use huge pages. The standard library allocates such a vector zeroed, which for a
/// large one is fresh pages nobody has written: they are faulted in, 2 MiB at a time,
/// by the threads that first write them, not here.
pub fn zeroed_vec<T: Clone>(n: usize, zero: T) -> Vec<T> {
    let mut v = vec![zero; n];
    advise(v.as_mut_ptr() as usize, n.saturating_mul(std::mem::size_of::<T>()));
    v
}

/// An empty vector with room for `n` elements, its memory advised to use huge pages.
pub fn empty_vec<T>(n: usize) -> Vec<T> {
    let mut v: Vec<T> = Vec::with_capacity(n);
    advise(v.as_mut_ptr() as usize, n.saturating_mul(std::mem::size_of::<T>()));
    v
}

/// Advises the kernel to back the whole pages of `[start, start + len)` with huge pages.
#[cfg(target_os = "linux")]
fn advise(start: usize, len: usize) {
    const PAGE: usize = 4096;
    if len < MIN_BYTES {
        return;
    }
    let (lo, hi) = (start.next_multiple_of(PAGE), (start + len) / PAGE * PAGE);
    if hi > lo {
        // SAFETY: the range lies inside an allocation this process owns (the vector's
        // buffer), and MADV_HUGEPAGE changes neither its contents nor its mapping's
        // validity; if the kernel declines, nothing changes.
        #[allow(unsafe_code)]
        unsafe {
            libc::madvise(lo as *mut libc::c_void, hi - lo, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn advise(_start: usize, _len: usize) {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn advised_vectors_hold_what_they_were_given() {
        for n in [0, 1, 1000, (MIN_BYTES / 4) + 12345] {
            let v = filled_vec(n, 7u32);
            assert_eq!(v.len(), n);
            assert!(v.iter().all(|&x| x == 7));
            let z = zeroed_vec(n, [0.0f32; 3]);
            assert!(z.len() == n && z.iter().all(|p| *p == [0.0; 3]));
            let e: Vec<u64> = empty_vec(n);
            assert!(e.is_empty() && e.capacity() >= n);
        }
    }
}
