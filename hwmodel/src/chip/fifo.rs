//! A bounded FIFO between two units, with registered (edge-committed) semantics.
//!
//! Within a cycle the producer sees only the occupancy committed at the previous edge
//! ("ready"), and the consumer only the entries committed then ("valid"): a push is
//! staged and lands at [`Fifo::commit`]; a pop takes the head at once but frees its slot
//! only at the edge. So neither side can observe what the other did this cycle, and the
//! order in which units tick cannot matter. One push and one pop per cycle; a full FIFO
//! stalls its producer.

use serde::Serialize;

/// Largest configurable depth (the fixed-capacity storage).
pub const MAX_FIFO_DEPTH: usize = 64;

/// What a FIFO saw over a run.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct FifoStats {
    /// Entries pushed.
    pub pushes: u64,
    /// Entries popped.
    pub pops: u64,
    /// Cycles the producer had an entry but the FIFO was full.
    pub full_stall_cycles: u64,
    /// Cycles the consumer wanted an entry but the FIFO was empty.
    pub empty_stall_cycles: u64,
    /// `occupancy[k]`: cycles that ended with `k` entries.
    pub occupancy: Vec<u64>,
}

/// Tracing: how an entry is numbered, and what entered (true) or left.
type EntryLog<T> = (fn(&T) -> u32, Vec<(bool, u32)>);

/// A bounded FIFO of packets or jobs.
#[derive(Debug)]
pub struct Fifo<T> {
    /// Name for reports and the watchdog.
    pub name: String,
    depth: usize,
    items: heapless::Deque<T, MAX_FIFO_DEPTH>,
    committed_len: usize,
    staged: Option<T>,
    popped: bool,
    full_noted: bool,
    empty_noted: bool,
    // The stalls of the last committed cycle (repeated when the clock skips ahead).
    last_stalls: (bool, bool),
    /// Statistics.
    pub stats: FifoStats,
    /// Tracing: the packet number of an entry, and what entered (true) or left since
    /// the log was last taken.
    log: Option<EntryLog<T>>,
}

impl<T> Fifo<T> {
    /// An empty FIFO of `depth` entries (1 ..= [`MAX_FIFO_DEPTH`], checked by the config).
    pub fn new(name: String, depth: u32) -> Fifo<T> {
        let depth = (depth as usize).clamp(1, MAX_FIFO_DEPTH);
        Fifo {
            name,
            depth,
            items: heapless::Deque::new(),
            committed_len: 0,
            staged: None,
            popped: false,
            full_noted: false,
            empty_noted: false,
            last_stalls: (false, false),
            stats: FifoStats { occupancy: vec![0; depth + 1], ..FifoStats::default() },
            log: None,
        }
    }

    /// Logs what enters and leaves, as `tag` numbers it (tracing).
    pub fn enable_log(&mut self, tag: fn(&T) -> u32) {
        self.log = Some((tag, Vec::new()));
    }

    /// Ready: the producer may push this cycle.
    pub fn can_push(&self) -> bool {
        self.committed_len < self.depth && self.staged.is_none()
    }

    /// Stages `item` for the edge; gives it back (and counts a full stall) if not ready.
    pub fn push(&mut self, item: T) -> Result<(), T> {
        if !self.can_push() {
            if !self.full_noted {
                self.full_noted = true;
                self.stats.full_stall_cycles += 1;
            }
            return Err(item);
        }
        self.staged = Some(item);
        Ok(())
    }

    /// Valid: the committed head, if it was not popped this cycle.
    pub fn peek(&self) -> Option<&T> {
        if self.popped {
            None
        } else {
            self.items.front()
        }
    }

    /// Takes the committed head (its slot frees at the edge); counts an empty stall if
    /// there is none.
    pub fn pop(&mut self) -> Option<T> {
        if self.popped {
            return None;
        }
        let item = self.items.pop_front();
        match &item {
            Some(it) => {
                self.popped = true;
                if let Some((tag, log)) = self.log.as_mut() {
                    log.push((false, tag(it)));
                }
            }
            None if !self.empty_noted => {
                self.empty_noted = true;
                self.stats.empty_stall_cycles += 1;
            }
            None => {}
        }
        item
    }

    /// Counts a cycle in which the producer had an entry but did not try (the FIFO was
    /// known to be full).
    pub fn note_full(&mut self) {
        if !self.full_noted {
            self.full_noted = true;
            self.stats.full_stall_cycles += 1;
        }
    }

    /// The clock edge: the staged push lands, the popped slot frees. Returns whether
    /// anything moved.
    pub fn commit(&mut self) -> bool {
        let moved = self.popped || self.staged.is_some();
        if self.popped {
            self.stats.pops += 1;
        }
        if let Some(item) = self.staged.take() {
            if let Some((tag, log)) = self.log.as_mut() {
                log.push((true, tag(&item)));
            }
            // Cannot fail: `can_push` checked the committed occupancy.
            let _ = self.items.push_back(item);
            self.stats.pushes += 1;
        }
        self.popped = false;
        self.last_stalls = (self.full_noted, self.empty_noted);
        self.full_noted = false;
        self.empty_noted = false;
        self.committed_len = self.items.len();
        if let Some(c) = self.stats.occupancy.get_mut(self.committed_len) {
            *c += 1;
        }
        moved
    }

    /// Accounts `cycles` more cycles exactly like the last one (when the clock skips
    /// cycles in which nothing can change): same occupancy, same stalls.
    pub fn repeat_last(&mut self, cycles: u64) {
        if let Some(c) = self.stats.occupancy.get_mut(self.committed_len) {
            *c += cycles;
        }
        self.stats.full_stall_cycles += cycles * self.last_stalls.0 as u64;
        self.stats.empty_stall_cycles += cycles * self.last_stalls.1 as u64;
    }

    /// Zeroes the statistics (the entries stay).
    pub fn reset_stats(&mut self) {
        self.stats = FifoStats { occupancy: vec![0; self.depth + 1], ..FifoStats::default() };
    }

    /// Committed entries.
    pub fn len(&self) -> usize {
        self.committed_len
    }

    /// No committed entries.
    pub fn is_empty(&self) -> bool {
        self.committed_len == 0
    }

    /// Configured depth.
    pub fn depth(&self) -> usize {
        self.depth
    }
}

/// What the clock, the watchdog and the report need of any FIFO, whatever it carries.
pub trait AnyFifo {
    /// Name for reports and the watchdog.
    fn name(&self) -> &str;
    /// Committed entries.
    fn occupancy(&self) -> usize;
    /// Configured depth.
    fn depth(&self) -> usize;
    /// Statistics.
    fn stats(&self) -> &FifoStats;
    /// The clock edge (see [`Fifo::commit`]).
    fn commit(&mut self) -> bool;
    /// See [`Fifo::repeat_last`].
    fn repeat_last(&mut self, cycles: u64);
    /// Zeroes the statistics.
    fn reset_stats(&mut self);
    /// Moves what entered and left since the last call into `out` (tracing).
    fn take_log(&mut self, out: &mut Vec<(bool, u32)>);
}

impl<T> AnyFifo for Fifo<T> {
    fn name(&self) -> &str {
        &self.name
    }
    fn occupancy(&self) -> usize {
        Fifo::len(self)
    }
    fn depth(&self) -> usize {
        Fifo::depth(self)
    }
    fn stats(&self) -> &FifoStats {
        &self.stats
    }
    fn commit(&mut self) -> bool {
        Fifo::commit(self)
    }
    fn repeat_last(&mut self, cycles: u64) {
        Fifo::repeat_last(self, cycles)
    }
    fn reset_stats(&mut self) {
        Fifo::reset_stats(self)
    }
    fn take_log(&mut self, out: &mut Vec<(bool, u32)>) {
        if let Some((_, log)) = self.log.as_mut() {
            out.append(log);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pushes_land_at_the_edge_and_a_full_fifo_stalls() {
        let mut f = Fifo::new("f".into(), 2);
        assert!(f.push(1).is_ok());
        assert_eq!(f.peek(), None, "not visible before the edge");
        assert!(f.push(2).is_err(), "one push per cycle");
        f.commit();
        assert_eq!(f.peek(), Some(&1));
        assert!(f.push(2).is_ok());
        f.commit();
        assert!(!f.can_push(), "full");
        assert!(f.push(3).is_err());
        // A pop this cycle does not make room for a push in the same cycle.
        assert_eq!(f.pop(), Some(1));
        assert!(!f.can_push());
        assert_eq!(f.pop(), None, "one pop per cycle");
        f.commit();
        assert!(f.can_push());
        assert_eq!(f.pop(), Some(2));
        f.commit();
        assert_eq!(f.pop(), None);
        f.commit();
        assert_eq!(f.stats.pushes, 2);
        assert_eq!(f.stats.pops, 2);
        assert_eq!(f.stats.full_stall_cycles, 2);
        assert_eq!(f.stats.empty_stall_cycles, 1);
        assert_eq!(f.stats.occupancy, vec![2, 2, 1]);
    }
}
