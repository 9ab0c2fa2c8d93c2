//! Ray packets (Wald & Slusallek 2001 §4): up to 64 rays as a structure of arrays with an
//! active mask, traversed and intersected in lock-step. A packet descends into a node if
//! any of its active rays needs it, and carries on with exactly those rays (the node's
//! mask), so each ray still meets every triangle the single-ray kernel would test — the
//! hits are the same bit for bit — while node fetches and stack work are shared.

use glam::Vec3;

use crate::hit::Hit;
use crate::ray::Ray;

/// Largest packet (the active mask is a `u64`).
pub const MAX_PACKET: usize = 64;

/// `N` rays as a structure of arrays.
#[derive(Clone, Copy, Debug)]
pub struct RayPacket<const N: usize> {
    /// Origin x of each ray.
    pub ox: [f32; N],
    /// Origin y.
    pub oy: [f32; N],
    /// Origin z.
    pub oz: [f32; N],
    /// Direction x.
    pub dx: [f32; N],
    /// Direction y.
    pub dy: [f32; N],
    /// Direction z.
    pub dz: [f32; N],
    /// Interval start.
    pub t_min: [f32; N],
    /// Interval end.
    pub t_max: [f32; N],
    /// Bit `i` set: ray `i` takes part.
    pub active: u64,
}

impl<const N: usize> Default for RayPacket<N> {
    fn default() -> Self {
        RayPacket {
            ox: [0.0; N],
            oy: [0.0; N],
            oz: [0.0; N],
            dx: [0.0; N],
            dy: [0.0; N],
            dz: [0.0; N],
            t_min: [0.0; N],
            t_max: [0.0; N],
            active: 0,
        }
    }
}

impl<const N: usize> RayPacket<N> {
    const CHECK: () = assert!(N >= 1 && N <= MAX_PACKET, "packets hold 1 to 64 rays");

    /// An empty packet.
    pub fn new() -> Self {
        let () = Self::CHECK;
        Self::default()
    }

    /// Stores ray `i` and marks it active; invalid rays stay inactive (they miss).
    #[inline]
    pub fn set(&mut self, i: usize, r: &Ray) {
        if i >= N {
            return;
        }
        self.store(i, r);
        if r.is_valid() {
            self.active |= 1 << i;
        } else {
            self.active &= !(1 << i);
        }
    }

    /// Stores `rays` in lanes `0 ..` (at most `N`) and makes exactly their valid ones
    /// active, as [`RayPacket::set`] one by one would after clearing the mask.
    #[inline]
    pub fn fill(&mut self, rays: &[Ray]) {
        let mut active = 0u64;
        for (i, r) in rays.iter().take(N).enumerate() {
            self.store(i, r);
            active |= (r.is_valid() as u64) << i;
        }
        self.active = active;
    }

    /// Writes ray `r` into lane `i < N`.
    #[inline(always)]
    fn store(&mut self, i: usize, r: &Ray) {
        self.ox[i] = r.origin.x;
        self.oy[i] = r.origin.y;
        self.oz[i] = r.origin.z;
        self.dx[i] = r.dir.x;
        self.dy[i] = r.dir.y;
        self.dz[i] = r.dir.z;
        self.t_min[i] = r.t_min;
        self.t_max[i] = r.t_max;
    }

    /// Ray `i`.
    #[inline]
    pub fn ray(&self, i: usize) -> Ray {
        let i = i.min(N - 1);
        Ray {
            origin: Vec3::new(self.ox[i], self.oy[i], self.oz[i]),
            dir: Vec3::new(self.dx[i], self.dy[i], self.dz[i]),
            t_min: self.t_min[i],
            t_max: self.t_max[i],
        }
    }
}

/// Per-packet work counters; the SIMD efficiency is `active_lanes / (visits · N)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PacketCounters {
    /// Node (and leaf) visits by the packet.
    pub visits: u64,
    /// Sum over visits of the rays that needed the node.
    pub active_lanes: u64,
    /// Ray–triangle tests.
    pub tri_tests: u64,
}

impl PacketCounters {
    /// Adds another packet's counters.
    pub fn add(&mut self, o: &PacketCounters) {
        self.visits += o.visits;
        self.active_lanes += o.active_lanes;
        self.tri_tests += o.tri_tests;
    }
}

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

/// The best hit of each ray of a packet.
pub type PacketHits<const N: usize> = [Option<Hit>; N];
