//! The brick cache (Wald & Slusallek 2001, §6.3): a fixed byte budget of decompressed
//! bricks, least recently used evicted first, filled by loader threads that read and
//! decompress bricks while the tracers keep working on rays whose bricks are resident.
//!
//! A brick being traced is pinned (its `Arc` is held) and never evicted; a loader that
//! finds no room waits until a tracer lets one go. The budget therefore holds at every
//! moment: the bytes of resident bricks never exceed it.

use std::collections::{BTreeMap, VecDeque};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Duration;

use anyhow::{anyhow, bail, Result};

use crate::input::bricked::{BrickedScene, ResidentBrick};

/// What the cache did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CacheStats {
    /// Brick visits served by a resident brick.
    pub hits: u64,
    /// Bricks requested that were not resident (each counted once per load).
    pub misses: u64,
    /// Bricks evicted to make room.
    pub evictions: u64,
    /// Bricks loaded.
    pub loads: u64,
    /// Bytes read from the file.
    pub bytes_read: u64,
    /// Bytes decompressed.
    pub bytes_decompressed: u64,
    /// Seconds the loaders spent reading.
    pub read_seconds: f64,
    /// Seconds the loaders spent decompressing and validating.
    pub decompress_seconds: f64,
    /// The most bytes resident at once.
    pub peak_bytes: u64,
}

impl CacheStats {
    /// Brick visits served by resident bricks, over all visits.
    pub fn hit_rate(&self) -> f64 {
        self.hits as f64 / (self.hits + self.misses).max(1) as f64
    }

    /// The counts since `before` (a snapshot of the same cache).
    pub fn since(&self, before: &CacheStats) -> CacheStats {
        CacheStats {
            hits: self.hits - before.hits,
            misses: self.misses - before.misses,
            evictions: self.evictions - before.evictions,
            loads: self.loads - before.loads,
            bytes_read: self.bytes_read - before.bytes_read,
            bytes_decompressed: self.bytes_decompressed - before.bytes_decompressed,
            read_seconds: self.read_seconds - before.read_seconds,
            decompress_seconds: self.decompress_seconds - before.decompress_seconds,
            peak_bytes: self.peak_bytes,
        }
    }
}

enum Slot {
    Absent,
    Queued,
    Loading,
    // `fresh`: loaded and not yet taken by a tracer; not evicted before it is (else two
    // tracers waiting on two bricks with room for one could evict each other's forever).
    Resident { brick: Arc<ResidentBrick>, used: u64, fresh: bool },
}

struct State {
    slots: Vec<Slot>,
    // Resident bricks by last use.
    lru: BTreeMap<u64, u32>,
    queue: VecDeque<u32>,
    bytes: u64,
    clock: u64,
    // Bumped on every load finished (or failed): waiters watch it.
    generation: u64,
    stats: CacheStats,
    error: Option<String>,
    stop: bool,
}

/// A byte-budgeted LRU cache of a bricked scene's bricks.
pub struct BrickCache<'s> {
    scene: &'s BrickedScene,
    capacity: u64,
    state: Mutex<State>,
    // Signalled when a load finishes, a pin is released or the cache stops.
    changed: Condvar,
    // Signalled when a brick is queued.
    work: Condvar,
}

impl<'s> BrickCache<'s> {
    /// A cache of `capacity` bytes for `scene`; an error if the largest brick does not fit.
    pub fn new(scene: &'s BrickedScene, capacity: u64) -> Result<BrickCache<'s>> {
        let largest = scene.view().header().max_brick_size;
        if capacity < largest {
            bail!(
                "{}: a cache of {capacity} bytes cannot hold the largest brick ({largest} bytes); give --cache at least that",
                scene.name
            );
        }
        let n = scene.view().brick_count() as usize;
        let state = State {
            slots: (0..n).map(|_| Slot::Absent).collect(),
            lru: BTreeMap::new(),
            queue: VecDeque::new(),
            bytes: 0,
            clock: 0,
            generation: 0,
            stats: CacheStats::default(),
            error: None,
            stop: false,
        };
        Ok(BrickCache { scene, capacity, state: Mutex::new(state), changed: Condvar::new(), work: Condvar::new() })
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        // A poisoned lock means a loader panicked; its state is still consistent enough to
        // report the error the panic left.
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The brick, pinned while the `Arc` is held, if resident; otherwise `None`, and the
    /// brick is queued for loading.
    pub fn get(&self, b: u32) -> Option<Arc<ResidentBrick>> {
        let mut s = self.lock();
        s.clock += 1;
        let now = s.clock;
        let st = &mut *s;
        match st.slots.get_mut(b as usize)? {
            Slot::Resident { brick, used, fresh } => {
                *fresh = false;
                let brick = brick.clone();
                st.lru.remove(used);
                *used = now;
                st.lru.insert(now, b);
                st.stats.hits += 1;
                Some(brick)
            }
            slot @ Slot::Absent => {
                *slot = Slot::Queued;
                st.queue.push_back(b);
                st.stats.misses += 1;
                self.work.notify_one();
                None
            }
            Slot::Queued | Slot::Loading => None,
        }
    }

    /// Waits until some load finishes (or `timeout` passes); returns the first load
    /// error, which ends the frame.
    pub fn wait(&self, seen: &mut u64, timeout: Duration) -> Result<()> {
        let mut s = self.lock();
        if let Some(e) = &s.error {
            return Err(anyhow!("{e}"));
        }
        if s.generation == *seen {
            s = self.changed.wait_timeout(s, timeout).map(|(g, _)| g).unwrap_or_else(|p| p.into_inner().0);
        }
        *seen = s.generation;
        match &s.error {
            Some(e) => Err(anyhow!("{e}")),
            None => Ok(()),
        }
    }

    /// The load generation now (for [`BrickCache::wait`]).
    pub fn generation(&self) -> u64 {
        self.lock().generation
    }

    /// A tracer let a brick go: a loader waiting for room may find some.
    pub fn released(&self) {
        self.changed.notify_all();
    }

    /// The statistics so far.
    pub fn stats(&self) -> CacheStats {
        self.lock().stats
    }

    /// Ends the loaders' loops.
    pub fn stop(&self) {
        self.lock().stop = true;
        self.work.notify_all();
        self.changed.notify_all();
    }

    /// One loader thread's loop: take a queued brick, load it, make room, insert it.
    pub fn loader(&self) {
        loop {
            let b = {
                let mut s = self.lock();
                loop {
                    if s.stop {
                        return;
                    }
                    if let Some(b) = s.queue.pop_front() {
                        s.slots[b as usize] = Slot::Loading;
                        break b;
                    }
                    s = self.work.wait(s).unwrap_or_else(|p| p.into_inner());
                }
            };
            let loaded = self.scene.load(b);
            let mut s = self.lock();
            match loaded {
                Ok((brick, cost)) => {
                    let size = brick.bytes();
                    let Some(room) = self.make_room(s, size) else { return };
                    s = room;
                    s.clock += 1;
                    let now = s.clock;
                    s.lru.insert(now, b);
                    s.slots[b as usize] = Slot::Resident { brick: Arc::new(brick), used: now, fresh: true };
                    s.bytes += size;
                    s.stats.peak_bytes = s.stats.peak_bytes.max(s.bytes);
                    s.stats.loads += 1;
                    s.stats.bytes_read += cost.bytes_read;
                    s.stats.bytes_decompressed += cost.bytes_decompressed;
                    s.stats.read_seconds += cost.read_seconds;
                    s.stats.decompress_seconds += cost.decompress_seconds;
                }
                Err(e) => {
                    s.slots[b as usize] = Slot::Absent;
                    s.error.get_or_insert(format!("{e:#}"));
                }
            }
            s.generation += 1;
            self.changed.notify_all();
        }
    }

    /// Evicts least recently used unpinned bricks until `size` more bytes fit, waiting
    /// for tracers to let pinned ones go. `None` if the cache stopped meanwhile.
    fn make_room<'g>(&'g self, mut s: MutexGuard<'g, State>, size: u64) -> Option<MutexGuard<'g, State>> {
        while s.bytes + size > self.capacity {
            let victim = s.lru.iter().map(|(&t, &b)| (t, b)).find(|&(_, b)| match &s.slots[b as usize] {
                Slot::Resident { brick, fresh, .. } => !*fresh && Arc::strong_count(brick) == 1,
                _ => false,
            });
            match victim {
                Some((t, b)) => {
                    s.lru.remove(&t);
                    if let Slot::Resident { brick, .. } = std::mem::replace(&mut s.slots[b as usize], Slot::Absent) {
                        s.bytes -= brick.bytes();
                    }
                    s.stats.evictions += 1;
                }
                None => {
                    if s.stop {
                        return None;
                    }
                    // Every resident brick is being traced: wait for a tracer to let one go.
                    s = self
                        .changed
                        .wait_timeout(s, Duration::from_millis(50))
                        .map(|(g, _)| g)
                        .unwrap_or_else(|p| p.into_inner().0);
                }
            }
        }
        Some(s)
    }
}

/// Runs `f` with a cache of `capacity` bytes over `scene` and `loaders` loader threads,
/// which end with it.
pub fn with_cache<T>(
    scene: &BrickedScene,
    capacity: u64,
    loaders: usize,
    f: impl FnOnce(&BrickCache<'_>) -> Result<T>,
) -> Result<T> {
    let cache = BrickCache::new(scene, capacity)?;
    std::thread::scope(|s| {
        for _ in 0..loaders.max(1) {
            s.spawn(|| cache.loader());
        }
        let r = f(&cache);
        cache.stop();
        r
    })
}
