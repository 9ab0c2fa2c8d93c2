//! The views of a scene image's acceleration structures — the uniform grid, the binary
//! BVH, the wide BVHs and the kd-tree — each borrowed from a validated image, with the
//! reads a kernel makes reported to its memory probe.

use glam::Vec3;

use super::records::{Bvh4Node, Bvh8Node, BvhNode, KdNode, WideNode, NULL_INDEX};
use crate::probe::{DataClass, MemoryProbe};

/// The uniform grid of a scene image (Purcell 2002, Figure 4).
#[derive(Clone, Copy, Debug)]
pub struct GridView<'a> {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
    /// Size of one cell.
    pub cell_size: Vec3,
    /// Cells per axis.
    pub dims: [u32; 3],
    pub(in crate::image) cells: &'a [u32],
    pub(in crate::image) lists: &'a [u32],
    pub(in crate::image) cells_addr: u32,
    pub(in crate::image) lists_addr: u32,
    /// A wrapped grid (a level of Reinhard's hierarchical grid): `dims` are the logical
    /// box's cells, `cells` the physical grid's.
    pub(in crate::image) wrap: Option<GridWrap>,
}

/// How a wrapped grid's logical cells land on its physical cells (Reinhard, Smits &
/// Hansen 2000): logical cell `c` is physical cell `(c + offset) mod dims`, so objects
/// that leave the physical box re-enter it on the other side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridWrap {
    /// Physical cells per axis.
    pub dims: [u32; 3],
    /// The physical cell of logical cell 0, per axis.
    pub offset: [i32; 3],
}

impl<'a> GridView<'a> {
    /// Reads the cell of logical cell `cell` (index `index` in an unwrapped grid): the
    /// offset of its list, or [`NULL_INDEX`].
    #[inline]
    pub fn voxel_cell<P: MemoryProbe>(&self, index: u32, cell: [i32; 3], probe: &mut P) -> u32 {
        let Some(w) = self.wrap else { return self.cell(index, probe) };
        let at = |a: usize| (cell[a] as i64 + w.offset[a] as i64).rem_euclid(w.dims[a].max(1) as i64) as u32;
        let physical = at(0) + w.dims[0] * (at(1) + w.dims[1] * at(2));
        self.cell(physical, probe)
    }

    /// Number of cells.
    pub fn cell_count(&self) -> usize {
        self.cells.len()
    }

    /// Number of primitive-list entries, terminators included.
    pub fn list_entry_count(&self) -> usize {
        self.lists.len()
    }

    /// Reads cell `index`: the offset of its list in PRIM_LISTS, or [`NULL_INDEX`].
    #[inline]
    pub fn cell<P: MemoryProbe>(&self, index: u32, probe: &mut P) -> u32 {
        probe.read(DataClass::Nodes, self.cells_addr.wrapping_add(index.wrapping_mul(4)), 4);
        self.cells.get(index as usize).copied().unwrap_or(NULL_INDEX)
    }

    /// Reads primitive-list entry `pos`: a triangle index or [`NULL_INDEX`] (end of list).
    #[inline]
    pub fn list_entry<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        probe.read(DataClass::PrimLists, self.lists_addr.wrapping_add(pos.wrapping_mul(4)), 4);
        self.lists.get(pos as usize).copied().unwrap_or(NULL_INDEX)
    }

    /// All cells, for statistics (not an observed kernel read).
    pub fn cells(&self) -> &'a [u32] {
        self.cells
    }
}

/// A bounding volume hierarchy of a scene image.
#[derive(Clone, Copy, Debug)]
pub struct BvhView<'a> {
    pub(in crate::image) nodes: &'a [BvhNode],
    pub(in crate::image) prims: &'a [u32],
    pub(in crate::image) nodes_addr: u32,
    pub(in crate::image) prims_addr: u32,
}

impl<'a> BvhView<'a> {
    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// All nodes (for statistics; not an observed kernel read).
    pub fn nodes(&self) -> &'a [BvhNode] {
        self.nodes
    }

    /// Reads node `index`.
    #[inline]
    pub fn node<P: MemoryProbe>(&self, index: u32, probe: &mut P) -> BvhNode {
        probe.read(DataClass::Nodes, self.nodes_addr.wrapping_add(index.wrapping_mul(32)), 32);
        self.nodes.get(index as usize).copied().unwrap_or(BvhNode { min: [0.0; 3], first: 0, max: [0.0; 3], count: 0 })
    }

    /// Reads primitive-list entry `pos`.
    #[inline]
    pub fn prim<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        probe.read(DataClass::PrimLists, self.prims_addr.wrapping_add(pos.wrapping_mul(4)), 4);
        self.prims.get(pos as usize).copied().unwrap_or(0)
    }
}

/// A wide (4- or 8-wide) BVH of a scene image.
#[derive(Clone, Copy, Debug)]
pub struct WideBvhView<'a, N: WideNode> {
    pub(in crate::image) nodes: &'a [N],
    pub(in crate::image) prims: &'a [u32],
    pub(in crate::image) nodes_addr: u32,
    pub(in crate::image) prims_addr: u32,
}

/// A 4-wide BVH of a scene image.
pub type Bvh4View<'a> = WideBvhView<'a, Bvh4Node>;
/// An 8-wide BVH of a scene image.
pub type Bvh8View<'a> = WideBvhView<'a, Bvh8Node>;

impl<'a, N: WideNode> WideBvhView<'a, N> {
    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Reads node `index`.
    #[inline]
    pub fn node<P: MemoryProbe>(&self, index: u32, probe: &mut P) -> &'a N {
        let size = core::mem::size_of::<N>() as u32;
        probe.read(DataClass::Nodes, self.nodes_addr.wrapping_add(index.wrapping_mul(size)), size);
        self.nodes.get(index as usize).unwrap_or_else(|| N::empty())
    }

    /// Reads primitive-list entry `pos`.
    #[inline]
    pub fn prim<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        probe.read(DataClass::PrimLists, self.prims_addr.wrapping_add(pos.wrapping_mul(4)), 4);
        self.prims.get(pos as usize).copied().unwrap_or(0)
    }
}

/// A kd-tree of a scene image; its root box is the scene bounds.
#[derive(Clone, Copy, Debug)]
pub struct KdTreeView<'a> {
    pub(in crate::image) nodes: &'a [KdNode],
    pub(in crate::image) prims: &'a [u32],
    pub(in crate::image) nodes_addr: u32,
    pub(in crate::image) prims_addr: u32,
    /// Lower corner of the root box.
    pub min: Vec3,
    /// Upper corner of the root box.
    pub max: Vec3,
}

impl<'a> KdTreeView<'a> {
    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// All nodes (for statistics; not an observed kernel read).
    pub fn nodes(&self) -> &'a [KdNode] {
        self.nodes
    }

    /// Reads node `index`.
    #[inline]
    pub fn node<P: MemoryProbe>(&self, index: u32, probe: &mut P) -> KdNode {
        probe.read(DataClass::Nodes, self.nodes_addr.wrapping_add(index.wrapping_mul(8)), 8);
        self.nodes.get(index as usize).copied().unwrap_or(KdNode::leaf(0, 0))
    }

    /// Reads primitive-list entry `pos`.
    #[inline]
    pub fn prim<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        probe.read(DataClass::PrimLists, self.prims_addr.wrapping_add(pos.wrapping_mul(4)), 4);
        self.prims.get(pos as usize).copied().unwrap_or(0)
    }
}

impl crate::traverse::tree_step::PrimLists for BvhView<'_> {
    #[inline(always)]
    fn prim<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        BvhView::prim(self, pos, probe)
    }
}

impl<N: WideNode> crate::traverse::tree_step::PrimLists for WideBvhView<'_, N> {
    #[inline(always)]
    fn prim<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        WideBvhView::prim(self, pos, probe)
    }
}

impl crate::traverse::tree_step::PrimLists for KdTreeView<'_> {
    #[inline(always)]
    fn prim<P: MemoryProbe>(&self, pos: u32, probe: &mut P) -> u32 {
        KdTreeView::prim(self, pos, probe)
    }
}
