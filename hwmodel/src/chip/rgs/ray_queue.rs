//! The shading unit's queue of ray records waiting to be packed into packets.

use std::collections::VecDeque;

use raypipe_core::shade::ray_record::{RayKind, RayRecord};

/// The records the shader emitted, one first-in first-out queue per kind, so that a
/// packet gathers rays of one kind (Wald & Slusallek 2001: shadow rays toward the same
/// light are coherent, reflections of neighbouring pixels too); each record keeps its
/// emission number so that the oldest kind goes first.
#[derive(Default)]
pub(super) struct RayQueue {
    queues: [VecDeque<(u64, RayRecord)>; RayKind::COUNT],
    next: u64,
}

impl RayQueue {
    pub(super) fn push(&mut self, r: RayRecord) {
        self.queues[r.kind as usize].push_back((self.next, r));
        self.next += 1;
    }

    pub(super) fn len(&self) -> usize {
        self.queues.iter().map(VecDeque::len).sum()
    }

    pub(super) fn is_empty(&self) -> bool {
        self.queues.iter().all(VecDeque::is_empty)
    }

    /// Up to `n` records of the kind whose oldest record is the oldest of all.
    pub(super) fn take_oldest_kind(&mut self, n: usize) -> Vec<RayRecord> {
        let Some(k) =
            (0..self.queues.len()).filter(|&k| !self.queues[k].is_empty()).min_by_key(|&k| self.queues[k][0].0)
        else {
            return Vec::new();
        };
        let q = &mut self.queues[k];
        q.drain(..n.min(q.len())).map(|(_, r)| r).collect()
    }
}
