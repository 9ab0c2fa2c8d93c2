//! The rays' intersection constants, made the first time a ray or a group of four
//! needs them at a leaf (most rays of a frame never reach one).

use crate::intersect::triangle::Intersector;
use crate::packet::{Lanes, RayPacket};
use glam::Vec4;

use super::groups::{groups_of, Groups, GROUPS, GROUP_LANES};

/// The rays' intersection constants, computed for a group of four lanes the first time
/// one of its rays enters a leaf (most rays of a frame never do), as four SIMD lanes for
/// the intersector's four-ray form; one ray's own constants only when it is tested alone.
pub(in crate::packet) struct Preps<I: Intersector, const N: usize> {
    // Per group of four lanes.
    pub(in crate::packet) fours: Fours<I>,
    // Per lane: only lanes tested one by one (redone lanes, lone rays, groups without a
    // four-ray form) need them.
    pub(in crate::packet) ones: Ones<I, N>,
}

impl<I: Intersector, const N: usize> Preps<I, N> {
    #[inline(always)]
    pub(in crate::packet) fn new() -> Self {
        Preps {
            fours: Fours { four: heapless::Vec::new(), four_slot: [0; GROUPS], ready: 0 },
            ones: Ones { one: heapless::Vec::new(), one_slot: [0; N], one_ready: 0 },
        }
    }
}

/// The four-ray constants of the groups that have needed them. (Computed constants are
/// kept in the order they were asked for, and per group the index of its entry: nothing
/// is written for groups that never need constants; the arrays of every lane's record,
/// initialised per packet, cost packets that miss the scene a tenth of their time.)
pub(in crate::packet) struct Fours<I: Intersector> {
    pub(in crate::packet) four: heapless::Vec<Option<I::Prepared4>, GROUPS>,
    pub(in crate::packet) four_slot: [u8; GROUPS],
    // Groups whose constants are computed.
    pub(in crate::packet) ready: u32,
}

impl<I: Intersector> Fours<I> {
    /// Group `g`'s four-ray constants, if ready and the intersector has them.
    #[inline(always)]
    pub(in crate::packet) fn get(&self, g: usize) -> Option<&I::Prepared4> {
        if self.ready & (1 << (g % GROUPS)) == 0 {
            return None;
        }
        self.four.get(self.four_slot[g % GROUPS] as usize).and_then(|p| p.as_ref())
    }

    /// Makes the constants of every group with a lane in `enter` ready.
    #[inline(always)]
    pub(in crate::packet) fn prepare<const N: usize>(
        &mut self,
        packet: &RayPacket<N>,
        q: &Groups,
        mask: u64,
        enter: u64,
    ) {
        for g in Lanes(groups_of(enter) & !(self.ready as u64)) {
            let m4 = (mask >> (4 * g)) & 0xF;
            self.ready |= 1 << g;
            // Inactive lanes borrow an active lane's ray (their results are unused).
            let any = 4 * g + m4.trailing_zeros() as usize;
            let act = GROUP_LANES[m4 as usize];
            // A group with all four lanes active (most of them) takes its registers as
            // they are, with one load each.
            let pick = |v: Vec4, a: &[f32; N]| {
                if m4 == 0xF {
                    v
                } else {
                    Vec4::select(act, v, Vec4::splat(a.get(any).copied().unwrap_or(0.0)))
                }
            };
            let lanes = |a: &[f32; N]| match a.get(4 * g..4 * g + 4) {
                Some(l) => Vec4::from_slice(l),
                None => Vec4::from_array(core::array::from_fn(|k| a.get(4 * g + k).copied().unwrap_or(0.0))),
            };
            let org = [pick(q.org[0][g], &packet.ox), pick(q.org[1][g], &packet.oy), pick(q.org[2][g], &packet.oz)];
            let dir = [&packet.dx, &packet.dy, &packet.dz].map(|d| pick(lanes(d), d));
            if let Some(slot) = self.four_slot.get_mut(g) {
                *slot = self.four.len() as u8;
                // Cannot be full: one entry per group.
                let _ = self.four.push(I::prepare_rays4(org, dir));
            }
        }
    }
}

/// The one-ray constants of the lanes that have needed them (as [`Fours`] keeps them).
pub(in crate::packet) struct Ones<I: Intersector, const N: usize> {
    pub(in crate::packet) one: heapless::Vec<I::Prepared, N>,
    one_slot: [u8; N],
    // Lanes whose constants are computed.
    pub(in crate::packet) one_ready: u64,
}

impl<I: Intersector, const N: usize> Ones<I, N> {
    /// Ray `i`'s one-ray constants, computed the first time they are asked for.
    #[inline(always)]
    pub(in crate::packet) fn get(&mut self, packet: &RayPacket<N>, i: usize) -> I::Prepared {
        let i = i.min(N - 1);
        if self.one_ready & (1 << i) == 0 {
            self.one_slot[i] = self.one.len() as u8;
            // Cannot be full: one entry per lane.
            let _ = self.one.push(I::prepare(&packet.ray(i)));
            self.one_ready |= 1 << i;
        }
        // Always present (pushed above); the fallback keeps the kernel free of panics.
        match self.one.get(self.one_slot[i] as usize) {
            Some(p) => *p,
            None => I::prepare(&packet.ray(i)),
        }
    }
}
