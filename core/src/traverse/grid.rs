//! Uniform-grid traversal: Purcell 2002 §3.1.2–3.1.3 over his Figure 4 layout.
//!
//! The traversal kernel walks voxels with the 3D-DDA; a voxel whose cell is not null
//! hands its triangle list to the intersection kernel. A hit found in a voxel may lie
//! beyond that voxel (the triangle spans several), so it is final only once the walk has
//! passed its distance (§3.1.3): the loop stops when the best hit is nearer than the
//! current voxel's exit.

use crate::counters::RayCounters;
use crate::hit::Hit;
use crate::image::{GridView, SceneView, NULL_INDEX};
use crate::intersect::triangle::{test_triangle, Intersector};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::dda::{Dda, Voxel};

/// What one traversal step produced (the event a hardware traversal unit emits).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GridEvent {
    /// The voxel has triangles: its list starts at `list` in PRIM_LISTS.
    Cell {
        /// The voxel.
        voxel: Voxel,
        /// First entry of its list.
        list: u32,
    },
    /// The voxel is empty.
    Empty(Voxel),
    /// The ray left the grid, passed `t_max`, or its hit became final.
    Done,
}

/// Traversal state of one ray: the DDA registers plus the best hit so far.
#[derive(Clone, Copy, Debug)]
pub struct GridTraversal {
    dda: Option<Dda>,
    /// Closest hit found so far.
    pub best: Option<Hit>,
}

impl GridTraversal {
    /// Starts a ray; a ray missing the grid box is done at once.
    pub fn new(grid: &GridView<'_>, ray: &Ray) -> GridTraversal {
        GridTraversal { dda: Dda::new(grid, ray), best: None }
    }

    /// True if the ray missed the grid's bounding box (Purcell's early termination).
    pub fn missed_bounds(&self) -> bool {
        self.dda.is_none()
    }

    /// True once the walk has ended: the ray missed the grid, or its hit became final at
    /// [`GridTraversal::finish_voxel`] or at a step.
    pub fn is_done(&self) -> bool {
        self.dda.is_none()
    }

    /// One traversal step: reads one cell and reports it.
    #[inline]
    pub fn step<P: MemoryProbe>(&mut self, grid: &GridView<'_>, probe: &mut P) -> GridEvent {
        let Some(dda) = self.dda.as_mut() else {
            return GridEvent::Done;
        };
        let Some(voxel) = dda.step() else {
            self.dda = None;
            return GridEvent::Done;
        };
        // The hit is final once the walk has passed it.
        if self.best.is_some_and(|b| b.t < voxel.t_enter) {
            self.dda = None;
            return GridEvent::Done;
        }
        match grid.voxel_cell(voxel.index, voxel.cell, probe) {
            NULL_INDEX => GridEvent::Empty(voxel),
            list => GridEvent::Cell { voxel, list },
        }
    }

    /// Called after a voxel's list is done: ends the walk if the best hit lies inside
    /// the voxel, saving the next cell read.
    #[inline]
    pub fn finish_voxel(&mut self, voxel: &Voxel) {
        if self.best.is_some_and(|b| b.t < voxel.t_exit) {
            self.dda = None;
        }
    }
}

/// Traces one ray through the grid to its closest hit: the host's loop over the step
/// kernels. `counters` receives Purcell's per-ray statistics.
#[inline]
pub fn trace_grid<I: Intersector, P: MemoryProbe>(
    scene: &SceneView<'_>,
    grid: &GridView<'_>,
    ray: &Ray,
    probe: &mut P,
    counters: &mut RayCounters,
) -> Option<Hit> {
    let mut trav = GridTraversal::new(grid, ray);
    if trav.missed_bounds() {
        return None;
    }
    let prep = I::prepare(ray);
    let (mut voxels, mut full, mut entries, mut tests) = (0u32, 0u32, 0u32, 0u32);
    loop {
        match trav.step(grid, probe) {
            GridEvent::Done => break,
            GridEvent::Empty(voxel) => {
                voxels += 1;
                trav.finish_voxel(&voxel);
            }
            GridEvent::Cell { voxel, list } => {
                voxels += 1;
                full += 1;
                let mut pos = list;
                loop {
                    let prim = grid.list_entry(pos, probe);
                    entries += 1;
                    if prim == NULL_INDEX {
                        break;
                    }
                    tests += 1;
                    let verts = I::fetch(scene, prim, probe);
                    test_triangle::<I>(&prep, ray, &verts, prim, &mut trav.best);
                    pos = pos.wrapping_add(1);
                }
                trav.finish_voxel(&voxel);
            }
        }
    }
    counters.nodes = counters.nodes.saturating_add(voxels);
    counters.leaves = counters.leaves.saturating_add(full);
    counters.list_entries = counters.list_entries.saturating_add(entries);
    counters.tri_tests = counters.tri_tests.saturating_add(tests);
    trav.best
}
