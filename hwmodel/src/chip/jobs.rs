//! What travels through the FIFOs: whole packets (structure of lanes with an active
//! mask), boxed so that a FIFO slot is a pointer, as a hardware FIFO of packet tags into
//! a packet register file would be.

use raypipe_core::traverse::walk::Leaf;
use raypipe_core::{Hit, Ray};

use crate::config::MAX_PACKET;

const LANES: usize = MAX_PACKET as usize;

/// A ray that is never traced (inactive lanes).
pub const NO_RAY: Ray = Ray { origin: raypipe_core::Vec3::ZERO, dir: raypipe_core::Vec3::ZERO, t_min: 0.0, t_max: 0.0 };

/// What a packet asks of the traversal: the closest hit, or whether anything is hit at
/// all (shadow rays; a lane ends at its first hit).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    /// Closest hit.
    Closest,
    /// Any hit.
    AnyHit,
}

/// Ray generator → traversal unit: a packet of rays.
#[derive(Clone, Debug)]
pub struct RayPacketJob {
    /// Packet number: its pixel block (in tile order) for primary rays, then the
    /// shading unit's numbering of secondary packets.
    pub index: u32,
    /// Closest or any hit.
    pub query: Query,
    /// Lanes with a ray (inside the image and passing the scene-bounds test).
    pub lanes: u64,
    /// The rays.
    pub rays: [Ray; LANES],
    /// Cycle the generator started the packet (for cost images and traces).
    pub issued: u64,
}

/// What one packet cost, lane by lane (the simulator's per-pixel cost images).
#[derive(Clone, Debug)]
pub struct PacketCost {
    /// Cycle the generator started the packet.
    pub issued: u64,
    /// Ray–node tests of each lane.
    pub steps: [u32; LANES],
    /// Ray–triangle tests of each lane.
    pub tests: [u32; LANES],
    /// Scene bytes the kernels read for the packet (traversal and intersection).
    pub bytes: u64,
}

impl PacketCost {
    /// Nothing yet, for a packet started at `issued`.
    pub fn new(issued: u64) -> PacketCost {
        PacketCost { issued, steps: [0; LANES], tests: [0; LANES], bytes: 0 }
    }
}

/// Traversal unit → intersection unit: a packet standing at leaves.
#[derive(Clone, Debug)]
pub struct LeafJob {
    /// Packet number.
    pub packet: u32,
    /// The traversal thread the packet belongs to.
    pub thread: u8,
    /// Lanes at a leaf.
    pub lanes: u64,
    /// Any-hit lanes stop at their first hit in range.
    pub query: Query,
    /// Each lane's leaf.
    pub leaves: [Leaf; LANES],
    /// Each lane's bottom image, in a two-level scene (its leaf is in that image).
    pub bottoms: [u32; LANES],
    /// The rays (in a two-level scene, each in its instance's object space).
    pub rays: [Ray; LANES],
    /// Each lane's best hit so far (updated by the intersection unit).
    pub best: [Option<Hit>; LANES],
    /// Ray–triangle tests of each lane in this job.
    pub tests: [u32; LANES],
    /// Scene bytes the job's kernels read.
    pub bytes: u64,
}

/// Traversal unit → shading: a finished packet.
#[derive(Clone, Debug)]
pub struct HitPacket {
    /// Packet number.
    pub index: u32,
    /// Lanes that were traced.
    pub lanes: u64,
    /// Their closest hits (any-hit packets: any hit, or `None` if unblocked).
    pub hits: [Option<Hit>; LANES],
    /// In a two-level scene, the instance of each lane's hit.
    pub instances: [u32; LANES],
    /// What tracing it cost.
    pub cost: Box<PacketCost>,
}

/// Lane count of a mask.
pub fn lanes(mask: u64) -> u64 {
    mask.count_ones() as u64
}
