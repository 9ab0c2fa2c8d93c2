//! A packet's lanes as the set bits of its masks: iterators over the lane indices.

/// Iterates the set bits of a mask, lowest first.
#[derive(Clone, Copy, Debug)]
pub struct Lanes(pub u64);

impl Iterator for Lanes {
    type Item = usize;

    #[inline]
    fn next(&mut self) -> Option<usize> {
        if self.0 == 0 {
            return None;
        }
        let i = self.0.trailing_zeros() as usize;
        self.0 &= self.0 - 1;
        Some(i)
    }
}

/// The set bits of a mask that lie below `N`, in increasing order: lane indices that a
/// `[T; N]` can be indexed with. The bound is part of the iterator, so the compiler sees
/// `i < N` at every use and keeps no bounds check (and no panic path); stray bits at or
/// above `N` end the iteration.
#[derive(Clone, Copy, Debug)]
pub struct LanesOf<const N: usize>(pub u64);

impl<const N: usize> Iterator for LanesOf<N> {
    type Item = usize;

    #[inline]
    fn next(&mut self) -> Option<usize> {
        // 64 for an empty mask, which is at least N.
        let i = self.0.trailing_zeros() as usize;
        if i >= N {
            return None;
        }
        self.0 &= self.0 - 1;
        Some(i)
    }
}
