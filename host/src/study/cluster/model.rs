//! A discrete-event model of a cluster rendering the frames of a recording (Wald &
//! Slusallek 2001 §6.5–6.7): a master that hands out tiles from the same [`TilePool`]
//! the real master uses, `N` workers each holding `in_flight` tiles, a network of given
//! bandwidth and latency between them, and a model server whose link every missing
//! brick crosses. What a tile costs, and which bricks it needs, come from the
//! recording; the rest is the model's.
//!
//! What it assumes, and so where it errs:
//! - a tile costs on a worker what it cost in the recorded run (less the time its rays
//!   waited for bricks), scaled by the worker's speed and by how many workers share a
//!   host's cores (processor sharing, fixed for the run);
//! - a tile's missing bricks are requested when it starts, each taken by the worker's
//!   first free loader, which asks the server, waits for the brick and decompresses it;
//!   the tile's rays overlap perfectly with the loads: it ends no sooner than its
//!   compute, nor than the last brick's arrival plus that brick's share of the compute;
//! - decompressing runs on the cores the tracers use, so a tile's compute grows by the
//!   decompression of the bricks it missed;
//! - every message crosses the sender's link, then the receiver's, each first come first
//!   served at its bandwidth, plus one latency; links are full duplex;
//! - the master takes its recorded time per tile, one tile at a time; writing the image
//!   and the frame's start are free.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap, VecDeque};

use super::recording::{Recording, TileRecord};
use crate::distributed::tile_pool::TilePool;

/// The cluster modelled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cluster {
    /// Worker ranks.
    pub workers: usize,
    /// Workers per host: they share its cores (each would use them all alone).
    pub workers_per_host: usize,
    /// A worker's speed against the recorded one's (2 = twice as fast).
    pub speed: f64,
    /// A worker's link, bytes per second each way.
    pub client_bandwidth: f64,
    /// The master's (and model server's) link, bytes per second each way.
    pub server_bandwidth: f64,
    /// One message's latency, seconds.
    pub latency: f64,
    /// A worker's brick cache, decompressed bytes.
    pub cache_bytes: u64,
    /// Decompression, bytes out per second (one loader).
    pub decompress_rate: f64,
    /// A worker's loader threads: bricks it fetches and decompresses at once.
    pub loaders: usize,
    /// Bricks come from the model server (served); else from local storage, free.
    pub served: bool,
}

/// What the model predicts for one cluster.
#[derive(Clone, Debug, PartialEq)]
pub struct Prediction {
    /// Each frame's seconds.
    pub frame_seconds: Vec<f64>,
    /// Bytes crossing the network per frame (tiles, assignments and bricks).
    pub frame_bytes: Vec<u64>,
    /// Each frame's brick cache hit rate over all workers (1 when nothing was needed).
    pub hit_rate: Vec<f64>,
    /// Share of the workers' time spent rendering.
    pub busy: f64,
}

impl Prediction {
    /// Frames per second over the frames after the first (warm), or the first alone.
    pub fn warm_fps(&self) -> f64 {
        let warm = if self.frame_seconds.len() > 1 { &self.frame_seconds[1..] } else { &self.frame_seconds[..] };
        frame_rate(warm)
    }

    /// Frames per second over every frame.
    pub fn fps(&self) -> f64 {
        frame_rate(&self.frame_seconds)
    }

    /// The first frame's rate (cold caches).
    pub fn cold_fps(&self) -> f64 {
        1.0 / self.frame_seconds[0].max(1e-12)
    }
}

/// Frames per second of frames that took `seconds` each.
pub fn frame_rate(seconds: &[f64]) -> f64 {
    seconds.len() as f64 / seconds.iter().sum::<f64>().max(1e-12)
}

/// Seconds, as an orderable event time.
#[derive(Clone, Copy, Debug)]
struct Time(f64);

impl PartialEq for Time {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o).is_eq()
    }
}

impl Eq for Time {}

impl PartialOrd for Time {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}

impl Ord for Time {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}

/// Something that happens at a time; ties go in the order they were scheduled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Event {
    /// A worker's assignment arrives.
    Assigned { worker: usize, tile: usize },
    /// A worker finished a tile.
    Rendered { worker: usize, tile: usize },
    /// A tile's message reached the master.
    Arrived { worker: usize, tile: usize },
}

/// A full-duplex link: its bandwidth (bytes per second each way) and when each
/// direction is next free.
#[derive(Clone, Copy, Debug)]
struct Link {
    bandwidth: f64,
    up: f64,
    down: f64,
}

impl Link {
    fn new(bandwidth: f64) -> Link {
        Link { bandwidth: bandwidth.max(1.0), up: 0.0, down: 0.0 }
    }
}

/// A worker's brick cache, least recently used first out; a brick is in it from the
/// moment it is asked for, ready when it arrives.
#[derive(Default)]
struct Lru {
    bytes: u64,
    clock: u64,
    // Brick → (last use, when it is ready).
    used: HashMap<u32, (u64, f64)>,
    order: std::collections::BTreeMap<u64, u32>,
}

impl Lru {
    /// When `b` is ready, if it is in the cache (and now the most recent).
    fn touch(&mut self, b: u32) -> Option<f64> {
        let (t, ready) = self.used.get_mut(&b)?;
        self.order.remove(t);
        self.clock += 1;
        *t = self.clock;
        self.order.insert(self.clock, b);
        Some(*ready)
    }

    fn insert(&mut self, b: u32, size: u64, ready: f64, capacity: u64, sizes: &[(u64, u64)]) {
        while self.bytes + size > capacity {
            let Some((_, old)) = self.order.pop_first() else { break };
            self.used.remove(&old);
            self.bytes -= sizes[old as usize].1;
        }
        self.clock += 1;
        self.used.insert(b, (self.clock, ready));
        self.order.insert(self.clock, b);
        self.bytes += size;
    }
}

/// One worker's state.
struct Worker {
    queue: VecDeque<usize>,
    // A tile is being rendered (its end is an event in the queue).
    rendering: bool,
    busy: f64,
    link: Link,
    cache: Lru,
    hits: u64,
    misses: u64,
    /// When each loader is next free.
    loaders: Vec<f64>,
}

/// Bytes of an assignment message.
const ASSIGN_BYTES: u64 = 8;

/// Runs the recording's frames on `cluster`.
pub fn predict(rec: &Recording, cluster: &Cluster) -> Prediction {
    let n = cluster.workers.max(1);
    let per_frame = rec.tiles_per_frame() as usize;
    let mut pool = TilePool::new(per_frame, n);
    let mut workers: Vec<Worker> = (0..n)
        .map(|_| Worker {
            queue: VecDeque::new(),
            rendering: false,
            busy: 0.0,
            link: Link::new(cluster.client_bandwidth),
            cache: Lru::default(),
            hits: 0,
            misses: 0,
            loaders: vec![0.0; cluster.loaders.max(1)],
        })
        .collect();
    let mut master_link = Link::new(cluster.server_bandwidth);
    let mut out = Prediction { frame_seconds: Vec::new(), frame_bytes: Vec::new(), hit_rate: Vec::new(), busy: 0.0 };
    // Processor sharing: each worker would use all its host's cores, so `k` workers on
    // a host each run at 1/k. The recorded tile times were measured with the
    // recording's workers per host.
    let recorded_share = rec.run.workers.div_ceil(rec.run.hosts.max(1)).max(1) as f64;
    let here_share = cluster.workers_per_host.clamp(1, n) as f64;
    let slowdown = here_share / recorded_share / cluster.speed.max(1e-9);
    let mut now = 0.0;
    let mut total_busy = 0.0;
    for tiles in rec.by_frame() {
        let start = now;
        let mut bytes = 0u64;
        let (hits0, misses0): (u64, u64) =
            (workers.iter().map(|w| w.hits).sum(), workers.iter().map(|w| w.misses).sum());
        let busy0: f64 = workers.iter().map(|w| w.busy).sum();
        pool.start_frame();
        let mut events: BinaryHeap<Reverse<(Time, u64, Event)>> = BinaryHeap::new();
        let mut seq = 0u64;
        let mut push = |events: &mut BinaryHeap<Reverse<(Time, u64, Event)>>, t: f64, e: Event| {
            seq += 1;
            events.push(Reverse((Time(t), seq, e)));
        };
        // The first assignments, `in_flight` to each worker, round by round.
        let mut master_free = start;
        for _ in 0..rec.run.in_flight.max(1) {
            for (w, worker) in workers.iter_mut().enumerate() {
                if let Some((t, _)) = pool.next_for(w) {
                    let at = send(&mut master_link, &mut worker.link, master_free, ASSIGN_BYTES, cluster.latency);
                    bytes += ASSIGN_BYTES;
                    push(&mut events, at, Event::Assigned { worker: w, tile: t });
                }
            }
        }
        let mut received = 0;
        while let Some(Reverse((Time(t), _, e))) = events.pop() {
            match e {
                Event::Assigned { worker, tile } => {
                    workers[worker].queue.push_back(tile);
                    if !workers[worker].rendering {
                        if let Some((done, b)) =
                            start_next(&mut workers, worker, t, &tiles, rec, cluster, slowdown, &mut master_link)
                        {
                            bytes += b;
                            push(&mut events, done.0, Event::Rendered { worker, tile: done.1 });
                        }
                    }
                }
                Event::Rendered { worker, tile } => {
                    workers[worker].rendering = false;
                    let size = tiles[tile].bytes;
                    let at = send(&mut workers[worker].link, &mut master_link, t, size, cluster.latency);
                    bytes += size;
                    push(&mut events, at, Event::Arrived { worker, tile });
                    if let Some((done, b)) =
                        start_next(&mut workers, worker, t, &tiles, rec, cluster, slowdown, &mut master_link)
                    {
                        bytes += b;
                        push(&mut events, done.0, Event::Rendered { worker, tile: done.1 });
                    }
                }
                Event::Arrived { worker, .. } => {
                    master_free = master_free.max(t) + rec.run.master_seconds_per_tile;
                    received += 1;
                    if let Some((next, _)) = pool.next_for(worker) {
                        let at = send(
                            &mut master_link,
                            &mut workers[worker].link,
                            master_free,
                            ASSIGN_BYTES,
                            cluster.latency,
                        );
                        bytes += ASSIGN_BYTES;
                        push(&mut events, at, Event::Assigned { worker, tile: next });
                    }
                    if received == per_frame {
                        now = master_free;
                    }
                }
            }
        }
        let secs = (now - start).max(1e-12);
        out.frame_seconds.push(secs);
        out.frame_bytes.push(bytes);
        let hits: u64 = workers.iter().map(|w| w.hits).sum::<u64>() - hits0;
        let misses: u64 = workers.iter().map(|w| w.misses).sum::<u64>() - misses0;
        out.hit_rate.push(if hits + misses == 0 { 1.0 } else { hits as f64 / (hits + misses) as f64 });
        total_busy += workers.iter().map(|w| w.busy).sum::<f64>() - busy0;
    }
    out.busy = total_busy / (now.max(1e-12) * n as f64);
    out
}

/// A message of `size` bytes sent at `at` from `from`'s link to `to`'s: when it
/// arrives. It leaves when the sender's link is free and enters when the receiver's
/// is, streaming through both at once; the slower sets the pace.
fn send(from: &mut Link, to: &mut Link, at: f64, size: u64, latency: f64) -> f64 {
    let out_start = at.max(from.up);
    from.up = out_start + size as f64 / from.bandwidth;
    let in_start = out_start.max(to.down);
    to.down = in_start + size as f64 / to.bandwidth;
    from.up.max(to.down) + latency
}

/// Starts the worker's next queued tile at `now`, if any: when it ends, which tile, and
/// the brick bytes it fetched.
#[allow(clippy::too_many_arguments)]
fn start_next(
    workers: &mut [Worker],
    w: usize,
    now: f64,
    tiles: &[&TileRecord],
    rec: &Recording,
    c: &Cluster,
    slowdown: f64,
    server: &mut Link,
) -> Option<((f64, usize), u64)> {
    let tile = workers[w].queue.pop_front()?;
    let t = tiles[tile];
    let compute = (t.seconds - t.waited).max(0.0) * slowdown;
    let mut last_ready = now;
    let mut fetched = 0;
    let mut decompressing = 0.0;
    let worker = &mut workers[w];
    for &b in &t.bricks {
        if let Some(ready) = worker.cache.touch(b) {
            // Resident, or on its way for an earlier tile.
            worker.hits += 1;
            last_ready = last_ready.max(ready);
            continue;
        }
        worker.misses += 1;
        let (stored, image) = rec.run.bricks[b as usize];
        let loader = (0..worker.loaders.len()).min_by(|&x, &y| worker.loaders[x].total_cmp(&worker.loaders[y]))?;
        let start = now.max(worker.loaders[loader]);
        let arrived = if c.served {
            fetched += stored + ASSIGN_BYTES;
            // The request crosses to the server, the brick comes back over both links.
            let asked = send(&mut worker.link, server, start, ASSIGN_BYTES, c.latency);
            send(server, &mut worker.link, asked, stored, c.latency)
        } else {
            start
        };
        let unpack = image as f64 / c.decompress_rate.max(1.0);
        decompressing += unpack;
        let ready = arrived + unpack;
        worker.loaders[loader] = ready;
        last_ready = last_ready.max(ready);
        worker.cache.insert(b, image, ready, c.cache_bytes, &rec.run.bricks);
    }
    // The loaders decompress on the cores the tracers use: the tile pays for it.
    let compute = compute + decompressing;
    let share = compute / t.bricks.len().max(1) as f64;
    let done = (now + compute).max(last_ready + share);
    worker.busy += compute;
    worker.rendering = true;
    Some(((done, tile), fetched))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::cluster::recording::{RunRecord, TileRecord};

    /// `frames` frames of 64 × 64 in 16-pixel tiles (16 tiles), each tile costing
    /// `seconds` and needing `bricks` of `size` bytes.
    fn recording(frames: u32, seconds: f64, bricks: &[u32], size: u64) -> Recording {
        let run = RunRecord {
            identity: "test".into(),
            workers: 1,
            host_threads: 2,
            hosts: 1,
            width: 64,
            height: 64,
            tile: 16,
            in_flight: 4,
            batch: 2,
            frame_seconds: vec![1.0; frames as usize],
            master_seconds_per_tile: 0.0,
            bricks: vec![(size, size); 8],
        };
        let tiles = (0..frames)
            .flat_map(|frame| {
                (0..16).map(move |tile| TileRecord {
                    frame,
                    tile,
                    rank: 1,
                    seconds,
                    waited: 0.0,
                    bytes: 16 * 16 * 12,
                    bricks: Vec::new(),
                })
            })
            .map(|mut t| {
                t.bricks = bricks.to_vec();
                t
            })
            .collect();
        Recording { run, tiles }
    }

    fn free_network(workers: usize) -> Cluster {
        Cluster {
            workers,
            workers_per_host: 1,
            speed: 1.0,
            client_bandwidth: 1e15,
            server_bandwidth: 1e15,
            latency: 0.0,
            cache_bytes: 1 << 30,
            decompress_rate: 1e15,
            loaders: 2,
            served: true,
        }
    }

    #[test]
    fn one_worker_on_a_free_network_takes_the_sum_of_its_tiles() {
        let p = predict(&recording(2, 0.01, &[], 0), &free_network(1));
        for s in &p.frame_seconds {
            assert!((s - 0.16).abs() < 1e-9, "{s}");
        }
        assert!((p.busy - 1.0).abs() < 1e-9);
    }

    #[test]
    fn workers_share_the_tiles_and_a_host_shares_its_cores() {
        let rec = recording(1, 0.01, &[], 0);
        let four = predict(&rec, &free_network(4));
        assert!((four.frame_seconds[0] - 0.04).abs() < 1e-9, "{:?}", four.frame_seconds);
        // Four workers on one host run at a quarter of the speed: no faster than one.
        let shared = predict(&rec, &Cluster { workers_per_host: 4, ..free_network(4) });
        assert!((shared.frame_seconds[0] - 0.16).abs() < 1e-9, "{:?}", shared.frame_seconds);
        let fast = predict(&rec, &Cluster { speed: 2.0, ..free_network(4) });
        assert!((fast.frame_seconds[0] - 0.02).abs() < 1e-9);
    }

    #[test]
    fn a_slow_master_link_bounds_the_frame_rate() {
        let rec = recording(1, 1e-6, &[], 0);
        // 16 tiles of 3,072 bytes through 1 MB/s: at least 49 ms.
        let p = predict(&rec, &Cluster { server_bandwidth: 1e6, ..free_network(8) });
        let floor = 16.0 * 3072.0 / 1e6;
        assert!(p.frame_seconds[0] >= floor && p.frame_seconds[0] < floor * 1.1, "{:?}", p.frame_seconds);
        assert_eq!(p.frame_bytes[0], 16 * 3072 + 16 * ASSIGN_BYTES);
    }

    #[test]
    fn warm_caches_fetch_nothing_and_cold_ones_pay_for_the_server() {
        let rec = recording(2, 0.001, &[0, 1, 2], 1_000_000);
        let c = Cluster { server_bandwidth: 10e6, ..free_network(1) };
        let p = predict(&rec, &c);
        // Frame 0 fetches the three bricks once (0.3 s through the server's link), frame 1
        // finds them all.
        assert!(p.frame_seconds[0] > 0.3 && p.frame_seconds[1] < 0.02, "{:?}", p.frame_seconds);
        assert!(p.hit_rate[1] == 1.0 && p.hit_rate[0] < 1.0);
        // A cache of one brick thrashes: every frame fetches again.
        let small = predict(&rec, &Cluster { cache_bytes: 1_000_000, ..c });
        assert!(small.frame_seconds[1] > 0.3, "{:?}", small.frame_seconds);
        // Bricks read locally cost no network time.
        let local = predict(&rec, &Cluster { served: false, ..c });
        assert!(local.frame_seconds[0] < 0.02, "{:?}", local.frame_seconds);
    }
}
