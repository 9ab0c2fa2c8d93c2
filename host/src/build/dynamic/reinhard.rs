//! Reinhard, Smits & Hansen's dynamic hierarchical grid (Eurographics Workshop on
//! Rendering 2000; Wald & Slusallek 2001 §8.2, Figure 18): each triangle lives in the one
//! level whose cells match its size — level `k`'s cells are `2^k` times the finest — so
//! it touches at most two cells per axis, and moving it is a delete and an insert in
//! constant time. Each level's physical grid stays where it was built; a triangle that
//! leaves it wraps around to the other side (physical cell = lattice cell mod the
//! level's cells per axis), and rays walk the *logical* box that holds the triangles now
//! (core's `SceneView::with_levels`). Only when that box has grown past
//! [`REBUILD_GROWTH`] times the physical box on some axis is the grid built anew.

use glam::Vec3A;
use raypipe_core::image::{GridLevel, GridWrap, Position, MAX_LEVELS, NULL_INDEX};

use super::refit::{bounds_of, margin_for};

/// The logical box may grow to this many times the physical box, per axis, before the
/// grid is rebuilt around the triangles (Reinhard et al.'s "differs too much").
pub const REBUILD_GROWTH: f32 = 2.0;

/// Most physical cells per axis of a level.
const MAX_CELLS_PER_AXIS: u32 = 1 << 10;

/// A triangle's place: its level and the lattice cells (inclusive) its grown box touches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Place {
    level: u8,
    lo: [i64; 3],
    hi: [i64; 3],
}

/// One level's physical grid and the lists its cells hold.
#[derive(Clone, Debug)]
struct Level {
    /// Cell side.
    cell: f32,
    /// Physical cells per axis.
    dims: [u32; 3],
    /// Each physical cell's triangles.
    cells: Vec<Vec<u32>>,
    /// The flattened form handed to the kernels (rebuilt each frame from `cells`).
    flat_cells: Vec<u32>,
    flat_lists: Vec<u32>,
    /// The logical box's first lattice cell and cells per axis.
    first: [i64; 3],
    span: [u32; 3],
}

/// A deforming mesh's hierarchical grid.
#[derive(Clone, Debug, Default)]
pub struct HierGrid {
    /// The lattice's origin (the physical box's lower corner when built).
    origin: Vec3A,
    /// The physical box's extent when built.
    extent: Vec3A,
    levels: Vec<Level>,
    places: Vec<Place>,
    margin: f32,
}

/// The box of triangle `t`, grown by `margin`.
fn tri_box(positions: &[Position], t: &[u32; 3], margin: f32) -> (Vec3A, Vec3A) {
    let p = |k: usize| Vec3A::from_array(positions[t[k] as usize].0);
    let (lo, hi) = (p(0).min(p(1)).min(p(2)), p(0).max(p(1)).max(p(2)));
    (lo - margin, hi + margin)
}

impl HierGrid {
    /// Builds the grid around the triangles where they are now.
    pub fn build(positions: &[Position], triangles: &[[u32; 3]]) -> HierGrid {
        let (lo, hi) = bounds_of(positions);
        let margin = margin_for(lo, hi);
        let extent = (hi - lo).max(Vec3A::splat(margin));
        let n = triangles.len().max(1) as f32;
        // The finest cells: about one per triangle over the box (the flattest axis no
        // thinner than a thousandth of the widest, so a planar mesh gets cells too).
        let e = extent.max(Vec3A::splat(extent.max_element() / 1000.0));
        let finest = ((e.x * e.y * e.z) / n).cbrt().max(extent.max_element() / MAX_CELLS_PER_AXIS as f32);
        let mut levels = Vec::new();
        let mut cell = finest;
        while levels.len() < MAX_LEVELS {
            let dims = [0, 1, 2].map(|a| ((extent[a] / cell).ceil() as u32).clamp(1, MAX_CELLS_PER_AXIS));
            let count = dims.iter().map(|&d| d as usize).product();
            let top = dims.iter().all(|&d| d <= 2);
            levels.push(Level {
                cell,
                dims,
                cells: vec![Vec::new(); count],
                flat_cells: Vec::new(),
                flat_lists: Vec::new(),
                first: [0; 3],
                span: [1; 3],
            });
            if top {
                break;
            }
            cell *= 2.0;
        }
        let mut grid = HierGrid { origin: lo - margin, extent, levels, places: Vec::new(), margin };
        grid.places = triangles
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let place = grid.place(tri_box(positions, t, margin));
                grid.insert(i as u32, &place);
                place
            })
            .collect();
        grid
    }

    /// Where a box goes: the finest level whose cell is at least its widest side (the
    /// coarsest level for anything wider), and the lattice cells it touches there.
    fn place(&self, (lo, hi): (Vec3A, Vec3A)) -> Place {
        let size = (hi - lo).max_element();
        let last = self.levels.len() - 1;
        let level = self.levels.iter().position(|l| l.cell >= size).unwrap_or(last);
        let cell = self.levels[level].cell;
        let at = |v: Vec3A| [0, 1, 2].map(|a| ((v[a] - self.origin[a]) / cell).floor() as i64);
        Place { level: level as u8, lo: at(lo), hi: at(hi) }
    }

    /// The physical cells a place covers (each once, however far it reaches).
    fn physical(&self, p: &Place) -> Vec<usize> {
        let l = &self.levels[p.level as usize];
        let axis = |a: usize| {
            let n = (p.hi[a] - p.lo[a] + 1).clamp(1, l.dims[a] as i64);
            (0..n).map(move |k| (p.lo[a] + k).rem_euclid(l.dims[a] as i64) as usize)
        };
        let (nx, ny) = (l.dims[0] as usize, l.dims[1] as usize);
        let mut out = Vec::new();
        for z in axis(2) {
            for y in axis(1) {
                out.extend(axis(0).map(|x| x + nx * (y + ny * z)));
            }
        }
        out
    }

    fn insert(&mut self, tri: u32, p: &Place) {
        for c in self.physical(p) {
            self.levels[p.level as usize].cells[c].push(tri);
        }
    }

    fn remove(&mut self, tri: u32, p: &Place) {
        for c in self.physical(p) {
            let cell = &mut self.levels[p.level as usize].cells[c];
            if let Some(k) = cell.iter().position(|&t| t == tri) {
                cell.swap_remove(k);
            }
        }
    }

    /// Moves the triangles whose cells changed (a delete and an insert each), or builds
    /// the grid anew when the triangles' box has outgrown [`REBUILD_GROWTH`] times the
    /// physical box. Returns true when it was built anew.
    pub fn update(&mut self, positions: &[Position], triangles: &[[u32; 3]]) -> bool {
        let (lo, hi) = bounds_of(positions);
        if ((hi - lo) - REBUILD_GROWTH * self.extent).max_element() > 0.0 {
            *self = HierGrid::build(positions, triangles);
            return true;
        }
        for (i, t) in triangles.iter().enumerate() {
            let place = self.place(tri_box(positions, t, self.margin));
            let old = self.places[i];
            if place != old {
                self.remove(i as u32, &old);
                self.insert(i as u32, &place);
                self.places[i] = place;
            }
        }
        false
    }

    /// Lays the levels out for the kernels over the logical box `lo..hi` (the frame's
    /// bounds): each level's cells flattened into null-terminated lists.
    pub fn flatten(&mut self, lo: Vec3A, hi: Vec3A) {
        let (origin, margin) = (self.origin, self.margin);
        for l in &mut self.levels {
            let at = |v: f32, a: usize| ((v - origin[a]) / l.cell).floor() as i64;
            // One cell more on each side than the box needs: the lattice corner is then
            // below the frame's bounds and the far corner above them whatever the
            // rounding of `origin + first * cell`.
            l.first = [0, 1, 2].map(|a| at(lo[a] - margin, a) - 1);
            l.span = [0, 1, 2].map(|a| ((at(hi[a] + margin, a) + 1 - l.first[a] + 1).max(1)) as u32);
            l.flat_cells.clear();
            l.flat_lists.clear();
            for c in &l.cells {
                if c.is_empty() {
                    l.flat_cells.push(NULL_INDEX);
                } else {
                    l.flat_cells.push(l.flat_lists.len() as u32);
                    l.flat_lists.extend_from_slice(c);
                    l.flat_lists.push(NULL_INDEX);
                }
            }
            if l.flat_lists.is_empty() {
                l.flat_lists.push(NULL_INDEX);
            }
        }
    }

    /// The levels as last flattened, finest first.
    pub fn levels(&self) -> Vec<GridLevel<'_>> {
        let origin = self.origin;
        self.levels
            .iter()
            .map(|l| GridLevel {
                min: [0, 1, 2].map(|a| origin[a] + l.first[a] as f32 * l.cell),
                dims: l.span,
                cell: l.cell,
                wrap: GridWrap {
                    dims: l.dims,
                    offset: [0, 1, 2].map(|a| l.first[a].rem_euclid(l.dims[a] as i64) as i32),
                },
                cells: &l.flat_cells,
                lists: &l.flat_lists,
            })
            .collect()
    }
}
