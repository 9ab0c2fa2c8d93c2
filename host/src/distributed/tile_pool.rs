//! The master's pool of image tiles (Wald & Slusallek 2001 §6.5): tiles are handed out
//! on demand, one at a time, to the worker that asks; a worker is offered first the
//! tiles it rendered in the previous frame, so that the bricks and cache lines those
//! tiles touch are still warm in its memory; then unowned tiles in screen-locality
//! order (a Z-order curve over the tile grid, so that a worker's consecutive tiles lie
//! side by side); and when both run dry it takes from the end of the longest list of
//! another worker's previous tiles (work stealing, as OSPRay's distributed load
//! balancer does), leaving that worker the tiles it would reach first.

/// A tile: `(x0, y0, x1, y1)` in pixels, the upper bounds exclusive.
pub type Rect = (u32, u32, u32, u32);

/// The tiles of a `w × h` image of `size`-pixel tiles, in Z-order of the tile grid.
pub fn tile_grid(w: u32, h: u32, size: u32) -> Vec<Rect> {
    let size = size.max(1);
    let (nx, ny) = (w.div_ceil(size), h.div_ceil(size));
    let mut cells: Vec<(u32, u32)> = (0..ny).flat_map(|y| (0..nx).map(move |x| (x, y))).collect();
    cells.sort_by_key(|&(x, y)| morton(x, y));
    cells.into_iter().map(|(x, y)| (x * size, y * size, ((x + 1) * size).min(w), ((y + 1) * size).min(h))).collect()
}

/// Interleaves the bits of `x` and `y` (Z-order).
fn morton(x: u32, y: u32) -> u64 {
    let spread = |v: u32| {
        let mut v = u64::from(v);
        v = (v | (v << 16)) & 0x0000_FFFF_0000_FFFF;
        v = (v | (v << 8)) & 0x00FF_00FF_00FF_00FF;
        v = (v | (v << 4)) & 0x0F0F_0F0F_0F0F_0F0F;
        v = (v | (v << 2)) & 0x3333_3333_3333_3333;
        (v | (v << 1)) & 0x5555_5555_5555_5555
    };
    spread(x) | (spread(y) << 1)
}

/// How one tile went to its worker.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Handout {
    /// The worker rendered it the frame before.
    Kept,
    /// No worker had it the frame before.
    Fresh,
    /// Another worker had it the frame before.
    Stolen,
}

/// One frame's pool over a fixed set of tiles, remembering who rendered which tile in
/// the frame before.
#[derive(Clone, Debug)]
pub struct TilePool {
    workers: usize,
    /// Who rendered each tile last frame.
    previous: Vec<Option<usize>>,
    /// Who has each tile this frame.
    owner: Vec<Option<usize>>,
    /// Per worker, the tiles it had last frame and has not been given yet, in order.
    affinity: Vec<std::collections::VecDeque<usize>>,
    /// The next tile (in order) to look at for fresh tiles.
    cursor: usize,
    left: usize,
}

impl TilePool {
    /// A pool of `tiles` tiles for `workers` workers, before any frame.
    pub fn new(tiles: usize, workers: usize) -> TilePool {
        TilePool {
            workers,
            previous: vec![None; tiles],
            owner: vec![None; tiles],
            affinity: vec![Default::default(); workers],
            cursor: 0,
            left: 0,
        }
    }

    /// Starts a frame: every tile back in the pool, each worker's list made of the tiles
    /// it rendered in the frame before.
    pub fn start_frame(&mut self) {
        if self.owner.iter().any(Option::is_some) {
            self.previous = std::mem::replace(&mut self.owner, vec![None; self.previous.len()]);
        }
        for a in &mut self.affinity {
            a.clear();
        }
        for (t, p) in self.previous.iter().enumerate() {
            if let Some(w) = *p {
                self.affinity[w].push_back(t);
            }
        }
        self.cursor = 0;
        self.left = self.owner.len();
    }

    /// Tiles not yet handed out this frame.
    pub fn left(&self) -> usize {
        self.left
    }

    /// The next tile for `worker`, and how it came to it; `None` when the pool is empty.
    pub fn next_for(&mut self, worker: usize) -> Option<(usize, Handout)> {
        if self.left == 0 || worker >= self.workers {
            return None;
        }
        if let Some(t) = pop_unowned(&mut self.affinity[worker], &self.owner, false) {
            return Some(self.give(t, worker, Handout::Kept));
        }
        while self.cursor < self.owner.len() {
            let t = self.cursor;
            self.cursor += 1;
            if self.owner[t].is_none() && self.previous[t].is_none() {
                return Some(self.give(t, worker, Handout::Fresh));
            }
        }
        // Steal from the back of the longest list of another worker.
        let victim = (0..self.workers)
            .filter(|&w| w != worker)
            .max_by_key(|&w| (self.affinity[w].iter().filter(|&&t| self.owner[t].is_none()).count(), usize::MAX - w))?;
        let t = pop_unowned(&mut self.affinity[victim], &self.owner, true)?;
        Some(self.give(t, worker, Handout::Stolen))
    }

    fn give(&mut self, t: usize, worker: usize, how: Handout) -> (usize, Handout) {
        self.owner[t] = Some(worker);
        self.left -= 1;
        (t, how)
    }
}

/// The first (or last) tile of `list` that nobody has this frame.
fn pop_unowned(list: &mut std::collections::VecDeque<usize>, owner: &[Option<usize>], back: bool) -> Option<usize> {
    loop {
        let t = if back { list.pop_back()? } else { list.pop_front()? };
        if owner[t].is_none() {
            return Some(t);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_covers_the_image_once_in_z_order() {
        let tiles = tile_grid(100, 70, 32);
        assert_eq!(tiles.len(), 4 * 3);
        let area: u32 = tiles.iter().map(|&(x0, y0, x1, y1)| (x1 - x0) * (y1 - y0)).sum();
        assert_eq!(area, 100 * 70);
        assert_eq!(&tiles[..4], &[(0, 0, 32, 32), (32, 0, 64, 32), (0, 32, 32, 64), (32, 32, 64, 64)]);
    }

    #[test]
    fn every_tile_once_per_frame_and_workers_keep_their_tiles() {
        let mut pool = TilePool::new(20, 3);
        let mut rng = 12345u32;
        let mut had: Vec<Vec<usize>> = vec![Vec::new(); 3];
        for frame in 0..4 {
            pool.start_frame();
            let mut seen = [false; 20];
            let mut mine: Vec<Vec<usize>> = vec![Vec::new(); 3];
            let mut kept = 0;
            // Workers ask in a pseudo-random order, at uneven speeds.
            while pool.left() > 0 {
                rng = rng.wrapping_mul(1_103_515_245).wrapping_add(12345);
                let w = (rng >> 16) as usize % 3;
                let (t, how) = pool.next_for(w).expect("a tile while some are left");
                assert!(!seen[t], "tile {t} handed out twice");
                seen[t] = true;
                if how == Handout::Kept {
                    assert!(had[w].contains(&t));
                    kept += 1;
                }
                if frame == 0 {
                    assert_eq!(how, Handout::Fresh);
                }
                mine[w].push(t);
            }
            assert!(seen.iter().all(|&s| s));
            assert_eq!(pool.next_for(0), None);
            if frame > 0 {
                assert!(kept >= 10, "frame {frame}: only {kept} of 20 tiles stayed with their worker");
            }
            had = mine;
        }
    }

    #[test]
    fn an_idle_worker_steals_from_the_busiest() {
        let mut pool = TilePool::new(8, 2);
        pool.start_frame();
        for _ in 0..8 {
            pool.next_for(0);
        }
        pool.start_frame();
        // Worker 1 had nothing: it steals from the back of worker 0's list.
        assert_eq!(pool.next_for(1), Some((7, Handout::Stolen)));
        assert_eq!(pool.next_for(0), Some((0, Handout::Kept)));
    }
}
