//! The packet regrouped as SIMD registers of four lanes, with their reciprocal
//! directions and best-hit ends: what a leaf's box and triangle tests read.

use crate::hit::Hit;
use crate::packet::{Lanes, PacketHits, RayPacket, MAX_PACKET};
use crate::traverse::boxes::slab::recip4;
use glam::{BVec4A, Vec4};

/// Lanes of a group of four as a SIMD mask, by the group's 4 bits of the active mask.
pub(in crate::packet) const GROUP_LANES: [BVec4A; 16] = {
    let mut t = [BVec4A::new(false, false, false, false); 16];
    let mut m = 0;
    while m < 16 {
        t[m] = BVec4A::new(m & 1 != 0, m & 2 != 0, m & 4 != 0, m & 8 != 0);
        m += 1;
    }
    t
};

/// Groups of four lanes in the largest packet.
pub(crate) const GROUPS: usize = MAX_PACKET / 4;

/// The packet regrouped as SIMD registers of four lanes each, with reciprocal
/// directions: loaded once, so that a leaf's box test per group is six aligned loads.
pub(crate) struct Groups {
    pub(crate) org: [[Vec4; GROUPS]; 3],
    pub(crate) inv: [[Vec4; GROUPS]; 3],
    pub(crate) t_min: [Vec4; GROUPS],
    /// Each lane's best-hit distance so far (or its ray's end).
    pub(crate) ends: [Vec4; GROUPS],
    /// Per group, the largest end of its active lanes (−∞ without any).
    pub(in crate::packet) group_end: [f32; GROUPS],
    /// Some active lane has a zero direction component.
    pub(in crate::packet) zero_dir: bool,
}

impl Groups {
    /// No lanes yet: every group's end −∞.
    pub(in crate::packet) const EMPTY: Groups = Groups {
        org: [[Vec4::ZERO; GROUPS]; 3],
        inv: [[Vec4::ZERO; GROUPS]; 3],
        t_min: [Vec4::ZERO; GROUPS],
        ends: [Vec4::ZERO; GROUPS],
        group_end: [f32::NEG_INFINITY; GROUPS],
        zero_dir: false,
    };

    /// The packet's lanes, by value (for tests).
    #[cfg(test)]
    pub(in crate::packet) fn new<const N: usize>(p: &RayPacket<N>, groups: usize, mask: u64) -> Groups {
        let mut slot = None;
        Groups::fill(&mut slot, p, groups, mask);
        slot.unwrap_or(Groups::EMPTY)
    }

    /// The packet's lanes written into `slot` in place (built elsewhere and moved in,
    /// the two kilobytes were copied once more per packet: 1% of the bunny's packet time).
    #[inline(always)]
    pub(in crate::packet) fn fill<'s, const N: usize>(
        slot: &'s mut Option<Groups>,
        p: &RayPacket<N>,
        groups: usize,
        mask: u64,
    ) -> &'s mut Groups {
        let lanes = |a: &[f32; N], g: usize| match a.get(4 * g..4 * g + 4) {
            // One load; only a packet of fewer than four rays takes the other arm.
            Some(l) => Vec4::from_slice(l),
            None => Vec4::from_array(core::array::from_fn(|k| a.get(4 * g + k).copied().unwrap_or(0.0))),
        };
        let q = slot.insert(Groups::EMPTY);
        for g in 0..groups.min(GROUPS) {
            let act = GROUP_LANES[((mask >> (4 * g)) & 0xF) as usize];
            for (a, (o, d)) in [(&p.ox, &p.dx), (&p.oy, &p.dy), (&p.oz, &p.dz)].into_iter().enumerate() {
                let d = lanes(d, g);
                q.org[a][g] = lanes(o, g);
                q.inv[a][g] = recip4(d);
                q.zero_dir |= (d.cmpeq(Vec4::ZERO) & act).any();
            }
            q.t_min[g] = lanes(&p.t_min, g);
            q.ends[g] = lanes(&p.t_max, g);
            q.update_end(g, mask);
        }
        q
    }

    // `largest_end` reads the ends as four registers.
    pub(in crate::packet) const _FOUR_QUADS: () = assert!(GROUPS == 16);

    /// The largest end of the groups' active lanes: how far any ray of the packet still
    /// looks. (Groups past the packet's have no active lane: their end stays −∞.)
    #[inline(always)]
    pub(in crate::packet) fn largest_end(&self) -> f32 {
        let e = &self.group_end;
        let quad = |k: usize| Vec4::new(e[4 * k], e[4 * k + 1], e[4 * k + 2], e[4 * k + 3]);
        quad(0).max(quad(1)).max(quad(2).max(quad(3))).max_element()
    }

    /// Recomputes group `g`'s largest end.
    #[inline(always)]
    pub(in crate::packet) fn update_end(&mut self, g: usize, mask: u64) {
        let act = GROUP_LANES[((mask >> (4 * g)) & 0xF) as usize];
        self.group_end[g] = Vec4::select(act, self.ends[g], Vec4::NEG_INFINITY).max_element();
    }

    /// After a leaf: the ends of the groups with a lane in `entered`, all four lanes from
    /// their hits (the other lanes' hits are unchanged, and inactive lanes have none:
    /// their ends stay their rays' ends), with the active lanes of `mask`; returns how far
    /// any ray of the packet still looks.
    #[inline(always)]
    pub(in crate::packet) fn update_ends<const N: usize>(
        &mut self,
        entered: u64,
        mask: u64,
        hits: &PacketHits<N>,
        packet: &RayPacket<N>,
    ) -> f32 {
        for g in Lanes(groups_of(entered)) {
            let end = |k: usize| {
                let i = (4 * g + k).min(N - 1);
                hits[i].map_or(packet.t_max[i], |h: Hit| h.t)
            };
            if let Some(e) = self.ends.get_mut(g) {
                *e = Vec4::new(end(0), end(1), end(2), end(3));
                self.update_end(g, mask);
            }
        }
        self.largest_end()
    }
}

/// Bit `g` set when some lane of group `g` (lanes `4g .. 4g + 4`) is in `lanes`.
#[inline(always)]
pub(in crate::packet) fn groups_of(lanes: u64) -> u64 {
    // Each group's four bits folded into its lowest (bit 4g), then those gathered to bit
    // g in halving steps: a dozen operations instead of a loop of sixteen tests.
    let x = lanes | (lanes >> 1);
    let x = (x | (x >> 2)) & 0x1111_1111_1111_1111;
    let x = (x | (x >> 3)) & 0x0303_0303_0303_0303;
    let x = (x | (x >> 6)) & 0x000F_000F_000F_000F;
    let x = (x | (x >> 12)) & 0x0000_00FF_0000_00FF;
    (x | (x >> 24)) & 0xFFFF
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::test_lcg::Lcg;

    /// The bit trick gives the definition's groups: bit `g` where some lane of `4g .. 4g
    /// + 4` is set.
    #[test]
    fn groups_of_marks_the_groups_with_a_lane() {
        let mut g = Lcg(3);
        for case in 0..20_000u64 {
            // Sparse masks too, so that groups with one lane (each of the four) occur.
            let lanes = match case % 3 {
                0 => g.next(),
                1 => g.next() & g.next() & g.next(),
                _ => 1 << (case % 64),
            };
            let want = (0..GROUPS).fold(0u64, |m, k| m | ((((lanes >> (4 * k)) & 0xF) != 0) as u64) << k);
            assert_eq!(groups_of(lanes), want, "lanes {lanes:#x}");
        }
    }
}
