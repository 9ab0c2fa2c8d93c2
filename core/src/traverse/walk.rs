//! One ray's walk through whichever structure the scene image holds, one step at a time:
//! the interface a hardware traversal unit drives ([design.md](https://github.com/raypipe/raypipe/blob/main/docs/design.md), "kernels are steps over
//! plain data"). Each [`Walk::step`] reads one node or voxel and reports an event; at a
//! [`Leaf`] the intersection side reads the leaf's triangle ids with [`Leaf::entry`],
//! tests them into [`Walk::best_mut`], and calls [`Walk::finish_leaf`]. The walks are the
//! structures' own step kernels (grid, kd-tree, BVH, 4- and 8-wide BVH), so a driver of `Walk`
//! finds exactly the host's hit.

use crate::hit::Hit;
use crate::image::{SceneView, NULL_INDEX};
use crate::intersect::triangle::{in_range, test_triangle, Intersector};
use crate::probe::MemoryProbe;
use crate::ray::Ray;
use crate::traverse::boxes::datapath::{FloatNodes, NodeTests};
use crate::traverse::bvh::BvhTraversal;
use crate::traverse::dda::Voxel;
use crate::traverse::grid::{GridEvent, GridTraversal};
use crate::traverse::kdtree::KdTraversal;
use crate::traverse::tree_step::TreeEvent;
use crate::traverse::wide_bvh::node4::Bvh4Traversal;
use crate::traverse::wide_bvh::node8::Bvh8Traversal;

/// Where a leaf's triangle ids are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Leaf {
    /// A grid cell's null-terminated list starting at PRIM_LISTS entry `start`.
    List {
        /// First list entry.
        start: u32,
    },
    /// A tree leaf: PRIM_LISTS entries `first .. first + count`.
    Range {
        /// First list entry.
        first: u32,
        /// Number of triangles.
        count: u32,
    },
    /// No structure: triangles `0 .. count` themselves (the brute-force reference).
    All {
        /// Number of triangles.
        count: u32,
    },
    /// A cell of level `level` of a hierarchical grid: its null-terminated list starting
    /// at entry `start` of the level's lists.
    Level {
        /// The level.
        level: u8,
        /// First list entry.
        start: u32,
    },
}

impl Leaf {
    /// The `k`-th triangle id of the leaf, or `None` past its end. A grid list's
    /// terminator is a real read, as on the host.
    #[inline]
    pub fn entry<P: MemoryProbe>(&self, scene: &SceneView<'_>, k: u32, probe: &mut P) -> Option<u32> {
        match *self {
            Leaf::List { start } => {
                let grid = scene.grid()?;
                match grid.list_entry(start.wrapping_add(k), probe) {
                    NULL_INDEX => None,
                    prim => Some(prim),
                }
            }
            Leaf::Range { first, count } => {
                if k >= count {
                    return None;
                }
                Some(scene.leaf_prim(first.wrapping_add(k), probe))
            }
            Leaf::All { count } => (k < count).then_some(k),
            Leaf::Level { level, start } => match scene.level(level as usize)?.list_entry(start.wrapping_add(k), probe)
            {
                NULL_INDEX => None,
                prim => Some(prim),
            },
        }
    }
}

impl Leaf {
    /// The leaf kernel: tests the leaf's triangles against `ray` into `best` — every one
    /// for a closest-hit query, only up to the first hit in range for an any-hit query
    /// (shadow rays). Returns how many it tested.
    #[inline]
    pub fn test<I: Intersector, P: MemoryProbe>(
        &self,
        scene: &SceneView<'_>,
        prep: &I::Prepared,
        ray: &Ray,
        any_hit: bool,
        best: &mut Option<Hit>,
        probe: &mut P,
    ) -> u32 {
        let mut k = 0;
        while let Some(prim) = self.entry(scene, k, probe) {
            // The triangle's address comes from the list entry.
            probe.dependent();
            let verts = I::fetch(scene, prim, probe);
            k += 1;
            if test_fetched::<I>(prep, ray, any_hit, &verts, prim, best) {
                break;
            }
        }
        k
    }
}

/// One fetched leaf triangle against one ray, the body of [`Leaf::test`]: a closest-hit
/// query keeps the closest hit in `best`; an any-hit query takes the first hit in range
/// and returns true (the ray needs no more tests).
#[inline]
pub fn test_fetched<I: Intersector>(
    prep: &I::Prepared,
    ray: &Ray,
    any_hit: bool,
    tri: &I::Triangle,
    prim: u32,
    best: &mut Option<Hit>,
) -> bool {
    if any_hit {
        if let Some(hit) = in_range(ray, I::intersect(prep, tri), prim) {
            *best = Some(hit);
            return true;
        }
        false
    } else {
        test_triangle::<I>(prep, ray, tri, prim, best);
        false
    }
}

/// What one walk step produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WalkEvent {
    /// A node or an empty voxel was read; step again.
    Inner,
    /// A leaf (or a full voxel): test its triangles, then [`Walk::finish_leaf`].
    Leaf(Leaf),
    /// The walk is over; [`Walk::best`] is the ray's hit.
    Done,
}

/// The traversal registers of one ray, for the structure the scene holds, with the box
/// tests `D` in the BVHs (the `f32` ones, or the fixed-point one: see
/// [`crate::traverse::boxes::datapath`]; take them from the triangle test, `I::Nodes`). The
/// grid's and the kd-tree's steps are `f32` whatever `D`: they have no box test to swap,
/// and with a fixed-point triangle test they are not conservative (a hit half a unit
/// across a cell boundary can be missed).
// The 4-wide BVH's stack makes its variant the largest; core has no heap to box it in,
// and a walk is a fixed-size register file anyway.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum Walk<D: NodeTests = FloatNodes> {
    /// Uniform grid: the DDA registers and the voxel whose list is being tested.
    Grid(GridTraversal, Option<Voxel>),
    /// kd-tree.
    Kd(KdTraversal),
    /// Binary BVH.
    Bvh(BvhTraversal<D::Binary>),
    /// 4-wide BVH.
    Bvh4(Bvh4Traversal<D::Wide>),
    /// 8-wide BVH.
    Bvh8(Bvh8Traversal<D::Wide>),
    /// A hierarchical grid with wrap-around ([`SceneView::with_levels`]): its levels
    /// walked one after the other, each seeded with the best hit of those before.
    Levels {
        /// The level being walked.
        level: u8,
        /// Its grid walk.
        trav: GridTraversal,
        /// The voxel whose list is being tested.
        voxel: Option<Voxel>,
    },
    /// No structure: one leaf of every triangle.
    All {
        /// The single leaf was handed out.
        visited: bool,
        /// Closest hit so far.
        best: Option<Hit>,
    },
}

impl<D: NodeTests> Walk<D> {
    /// Starts `ray` in the scene's structure. (An eye ray's bounding-box test comes
    /// before this, in the ray generator.)
    pub fn start(scene: &SceneView<'_>, ray: &Ray) -> Walk<D> {
        if let Some(level) = scene.level(0) {
            Walk::Levels { level: 0, trav: GridTraversal::new(&level, ray), voxel: None }
        } else if let Some(grid) = scene.grid() {
            Walk::Grid(GridTraversal::new(grid, ray), None)
        } else if scene.bvh4().is_some() {
            Walk::Bvh4(Bvh4Traversal::new(ray))
        } else if scene.bvh8().is_some() {
            Walk::Bvh8(Bvh8Traversal::new(ray))
        } else if scene.bvh().is_some() {
            Walk::Bvh(BvhTraversal::new(ray))
        } else if let Some(kd) = scene.kdtree() {
            Walk::Kd(KdTraversal::new(kd, ray))
        } else {
            Walk::All { visited: !ray.is_valid(), best: None }
        }
    }

    /// One step: reads one node (or voxel) of the structure.
    #[inline]
    pub fn step<P: MemoryProbe>(&mut self, scene: &SceneView<'_>, ray: &Ray, probe: &mut P) -> WalkEvent {
        let tree = |e: TreeEvent| match e {
            TreeEvent::Inner => WalkEvent::Inner,
            TreeEvent::Leaf { first, count } => WalkEvent::Leaf(Leaf::Range { first, count }),
            TreeEvent::Done => WalkEvent::Done,
        };
        match self {
            Walk::Grid(trav, voxel) => {
                let Some(grid) = scene.grid() else { return WalkEvent::Done };
                match trav.step(grid, probe) {
                    GridEvent::Done => WalkEvent::Done,
                    GridEvent::Empty(v) => {
                        trav.finish_voxel(&v);
                        WalkEvent::Inner
                    }
                    GridEvent::Cell { voxel: v, list } => {
                        *voxel = Some(v);
                        WalkEvent::Leaf(Leaf::List { start: list })
                    }
                }
            }
            Walk::Kd(trav) => match scene.kdtree() {
                Some(kd) => tree(trav.step(kd, ray, probe)),
                None => WalkEvent::Done,
            },
            Walk::Bvh(trav) => match scene.bvh() {
                Some(bvh) => tree(trav.step(bvh, probe)),
                None => WalkEvent::Done,
            },
            Walk::Bvh4(trav) => match scene.bvh4() {
                Some(bvh) => tree(trav.step(bvh, probe)),
                None => WalkEvent::Done,
            },
            Walk::Bvh8(trav) => match scene.bvh8() {
                Some(bvh) => tree(trav.step(bvh, probe)),
                None => WalkEvent::Done,
            },
            Walk::Levels { level, trav, voxel } => {
                let Some(grid) = scene.level(*level as usize) else { return WalkEvent::Done };
                match trav.step(&grid, probe) {
                    GridEvent::Empty(v) => {
                        trav.finish_voxel(&v);
                        WalkEvent::Inner
                    }
                    GridEvent::Cell { voxel: v, list } => {
                        *voxel = Some(v);
                        WalkEvent::Leaf(Leaf::Level { level: *level, start: list })
                    }
                    GridEvent::Done => match scene.level(*level as usize + 1) {
                        // The next level, the best hit so far carried over.
                        Some(next) => {
                            let best = trav.best;
                            *trav = GridTraversal::new(&next, ray);
                            trav.best = best;
                            *level += 1;
                            WalkEvent::Inner
                        }
                        None => WalkEvent::Done,
                    },
                }
            }
            Walk::All { visited, .. } => {
                if *visited {
                    WalkEvent::Done
                } else {
                    *visited = true;
                    WalkEvent::Leaf(Leaf::All { count: scene.triangle_count() })
                }
            }
        }
    }

    /// After a leaf's triangles were tested into [`Walk::best_mut`].
    #[inline]
    pub fn finish_leaf(&mut self) {
        match self {
            Walk::Grid(trav, voxel) | Walk::Levels { trav, voxel, .. } => {
                if let Some(v) = voxel.take() {
                    trav.finish_voxel(&v);
                }
            }
            Walk::Kd(trav) => trav.finish_leaf(),
            Walk::Bvh(trav) => trav.finish_leaf(),
            Walk::Bvh4(trav) => trav.finish_leaf(),
            Walk::Bvh8(trav) => trav.finish_leaf(),
            Walk::All { .. } => {}
        }
    }

    /// The closest hit so far.
    pub fn best(&self) -> Option<Hit> {
        match self {
            Walk::Grid(trav, _) | Walk::Levels { trav, .. } => trav.best,
            Walk::Kd(trav) => trav.best,
            Walk::Bvh(trav) => trav.best,
            Walk::Bvh4(trav) => trav.best,
            Walk::Bvh8(trav) => trav.best,
            Walk::All { best, .. } => *best,
        }
    }

    /// The closest hit so far, for the intersection kernel to update.
    pub fn best_mut(&mut self) -> &mut Option<Hit> {
        match self {
            Walk::Grid(trav, _) | Walk::Levels { trav, .. } => &mut trav.best,
            Walk::Kd(trav) => &mut trav.best,
            Walk::Bvh(trav) => &mut trav.best,
            Walk::Bvh4(trav) => &mut trav.best,
            Walk::Bvh8(trav) => &mut trav.best,
            Walk::All { best, .. } => best,
        }
    }
}

/// Traces `ray` by driving its [`Walk`] to the end: what the hardware model does, in one
/// loop (tests compare it with the structures' own tracers).
pub fn trace_walk<I: Intersector, P: MemoryProbe>(scene: &SceneView<'_>, ray: &Ray, probe: &mut P) -> Option<Hit> {
    let prep = I::prepare(ray);
    let mut walk = Walk::<I::Nodes>::start(scene, ray);
    loop {
        match walk.step(scene, ray, probe) {
            WalkEvent::Inner => {}
            WalkEvent::Leaf(leaf) => {
                leaf.test::<I, P>(scene, &prep, ray, false, walk.best_mut(), probe);
                walk.finish_leaf();
            }
            WalkEvent::Done => return walk.best(),
        }
    }
}
