//! One ray's state between kernel invocations: what Purcell's multipass machine keeps in
//! its state textures (§3.2) and the branching machine in registers. The two kernels a
//! ray alternates between are raypipe-core's: [`GridTraversal::step`] (one 3D-DDA step
//! and one cell read, §3.1.2) and one [`test_triangle`] (§3.1.3), sequenced exactly as
//! [`raypipe_core::traverse::grid::trace_grid`] sequences them, so every ray ends with
//! the host's hit.
//!
//! The list pointer is read ahead: the traversal kernel that finds a non-empty cell also
//! reads the first entry of its list, and each intersection reads the entry after the
//! triangle it tests, so a ray knows at the end of the pass whether its list is done and
//! the entries read equal the host's (each list's null terminator included).

use raypipe_core::image::{GridView, NULL_INDEX};
use raypipe_core::intersect::triangle::test_triangle;
use raypipe_core::traverse::dda::Voxel;
use raypipe_core::traverse::grid::{GridEvent, GridTraversal};
use raypipe_core::{Hit, Intersector, MemoryProbe, Ray, SceneView};

use crate::stream::stencil::RayStage;

/// Words of the per-ray state textures (a word is 4 bytes, a texture channel; the
/// textures are RGBA, so a kernel reads and writes whole texels of 4 words). Only what
/// cannot be recomputed bit for bit from the ray is stored, because a pass writes at
/// most two RGBA outputs (§2.2) — see [`crate::stream::config::StreamConfig`]'s
/// `output_words`.
pub mod words {
    use super::*;
    /// The ray: origin and `t_min`, direction and `t_max` (two texels).
    pub const RAY: u64 = (core::mem::size_of::<Ray>() / 4) as u64;
    /// The 3D-DDA's per-ray registers kept between passes: the cell, the next boundary
    /// on each axis and `t_enter` (7 words). The step signs, 1/d and `t_end` are
    /// recomputed from the ray by each traversal pass (the same operations on the same
    /// words, so the same bits); the walk's end needs no flag — the next step finds
    /// the boundary past `t_end` or the cell outside the grid; the exit of the voxel
    /// being tested is the next voxel's `t_enter`, or `t_end`.
    pub const TRAVERSAL: u64 = 7;
    /// The best hit so far: `t`, `u`, `v`, triangle.
    pub const HIT: u64 = (core::mem::size_of::<Hit>() / 4) as u64;
    /// The voxel list being tested: the position of the entry to test next (in the
    /// DDA's second texel). The entry itself is read again by the multipass
    /// intersection kernel rather than stored.
    pub const LIST: u64 = 1;
    /// A pixel's colour (RGBA) or a ray's weight.
    pub const COLOR: u64 = 4;
}

/// One ray in the stream.
pub struct StreamRay<I: Intersector> {
    /// The ray.
    pub ray: Ray,
    prep: I::Prepared,
    trav: GridTraversal,
    /// Any-hit query (shadow rays): done at the first hit in range.
    any_hit: bool,
    /// The voxel whose list is being tested.
    voxel: Option<Voxel>,
    /// Position of the entry read ahead, and that entry.
    pos: u32,
    next_prim: u32,
    /// Where the ray is.
    pub stage: RayStage,
}

impl<I: Intersector> Clone for StreamRay<I> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<I: Intersector> Copy for StreamRay<I> {}

impl<I: Intersector> StreamRay<I> {
    /// The traversal-setup kernel: the DDA's first voxel and registers; a ray that
    /// misses the grid is done at once.
    pub fn setup(grid: &GridView<'_>, ray: Ray, any_hit: bool) -> StreamRay<I> {
        let trav = GridTraversal::new(grid, &ray);
        let stage = if trav.missed_bounds() { RayStage::Done } else { RayStage::Traverse };
        StreamRay { ray, prep: I::prepare(&ray), trav, any_hit, voxel: None, pos: 0, next_prim: NULL_INDEX, stage }
    }

    /// The closest hit (or, for an any-hit ray, some hit in range) once done.
    pub fn hit(&self) -> Option<Hit> {
        self.trav.best
    }

    /// Runs the kernel of the ray's stage once (a traversal step or a triangle test);
    /// returns that stage, or `None` for a ray not waiting for either.
    pub fn run_kernel<P: MemoryProbe>(
        &mut self,
        scene: &SceneView<'_>,
        grid: &GridView<'_>,
        probe: &mut P,
    ) -> Option<RayStage> {
        let stage = self.stage;
        match stage {
            RayStage::Traverse => self.traverse(grid, probe),
            RayStage::Intersect => self.intersect(scene, grid, probe),
            _ => return None,
        }
        Some(stage)
    }

    /// One traversal step (a ray in [`RayStage::Traverse`]).
    pub fn traverse<P: MemoryProbe>(&mut self, grid: &GridView<'_>, probe: &mut P) {
        debug_assert_eq!(self.stage, RayStage::Traverse);
        match self.trav.step(grid, probe) {
            GridEvent::Done => self.stage = RayStage::Done,
            GridEvent::Empty(voxel) => self.end_voxel(voxel),
            GridEvent::Cell { voxel, list } => {
                probe.dependent();
                let first = grid.list_entry(list, probe);
                if first == NULL_INDEX {
                    self.end_voxel(voxel);
                } else {
                    (self.voxel, self.pos, self.next_prim) = (Some(voxel), list, first);
                    self.stage = RayStage::Intersect;
                }
            }
        }
    }

    /// The multipass machine's read of the entry to test, which it does not keep
    /// between passes ([`words::LIST`]): the same word as the read-ahead copy.
    pub fn reread_entry<P: MemoryProbe>(&self, grid: &GridView<'_>, probe: &mut P) {
        if self.stage == RayStage::Intersect {
            let entry = grid.list_entry(self.pos, probe);
            debug_assert_eq!(entry, self.next_prim);
        }
    }

    /// One intersection: tests the entry read ahead and reads the one after it (a ray in
    /// [`RayStage::Intersect`]).
    pub fn intersect<P: MemoryProbe>(&mut self, scene: &SceneView<'_>, grid: &GridView<'_>, probe: &mut P) {
        debug_assert_eq!(self.stage, RayStage::Intersect);
        let prim = self.next_prim;
        probe.dependent();
        let tri = I::fetch(scene, prim, probe);
        test_triangle::<I>(&self.prep, &self.ray, &tri, prim, &mut self.trav.best);
        if self.any_hit && self.trav.best.is_some() {
            self.stage = RayStage::Done;
            return;
        }
        self.pos = self.pos.wrapping_add(1);
        self.next_prim = grid.list_entry(self.pos, probe);
        if self.next_prim == NULL_INDEX {
            if let Some(voxel) = self.voxel.take() {
                self.end_voxel(voxel);
            }
        }
    }

    /// A voxel is done: the walk goes on, unless the best hit lies inside it.
    fn end_voxel(&mut self, voxel: Voxel) {
        self.trav.finish_voxel(&voxel);
        self.stage = if self.trav.is_done() { RayStage::Done } else { RayStage::Traverse };
    }
}
