//! [`SceneView::with_levels`]: an animated mesh's frame whose triangles are kept in a
//! hierarchical grid with wrap-around (Reinhard, Smits & Hansen 2000; Wald & Slusallek
//! 2001 §8.2). Each triangle lives in the one level whose cells match its size, so
//! moving it touches a constant number of cells; each level's *physical* grid is walked
//! over the *logical* box that holds the triangles now, logical cell `c` reading physical
//! cell `(c + offset) mod dims`, so a triangle that left the physical box re-enters it on
//! the other side and nothing is rebuilt until the logical box has drifted too far.
//!
//! Every triangle is in exactly one level, in every logical cell its (margin-grown) box
//! touches; each level's walk is Purcell's grid walk, so the closest hit over the levels
//! is the closest hit of the mesh, the same as any other structure's.

use glam::Vec3;

use super::SceneView;
use crate::image::error::SceneError;
use crate::image::header::{Header, SectionKind};
use crate::image::records::{Position, NULL_INDEX};
use crate::image::sections::finite3;
use crate::image::structure_views::{GridView, GridWrap};
use crate::image::validate::indices::indices_below;
use crate::image::view::update::FrameGeometry;

/// Most levels of a hierarchical grid.
pub const MAX_LEVELS: usize = 6;

/// Most cells along one axis of a level's logical box (the walk's length bound).
const MAX_DIM: u32 = 1 << 16;

/// One level of a hierarchical grid, as the host keeps it.
#[derive(Clone, Copy, Debug)]
pub struct GridLevel<'b> {
    /// The logical box's lower corner.
    pub min: [f32; 3],
    /// Logical cells per axis.
    pub dims: [u32; 3],
    /// Side of a (cubic) cell.
    pub cell: f32,
    /// The physical grid and where logical cell 0 lands in it.
    pub wrap: GridWrap,
    /// Physical cells, x fastest: [`NULL_INDEX`] or the first entry of the cell's list.
    pub cells: &'b [u32],
    /// Null-terminated lists of triangle ids.
    pub lists: &'b [u32],
}

impl<'a> SceneView<'a> {
    /// This unstructured image with the frame's vertices ([`SceneView::with_geometry`])
    /// and `levels` (finest first, at most [`MAX_LEVELS`]) as its structure. Checks each
    /// level as `parse` checks a grid — finite corner, positive cell, bounded dims,
    /// cells that match the physical grid and start lists inside it, lists that end with
    /// a null entry and name triangles — and that its logical box holds the frame's
    /// bounds, so no triangle is outside the walk. The view keeps `levels` (a slice:
    /// the view stays as small as any other).
    pub fn with_levels<'b>(
        &self,
        header: &'b Header,
        positions: &'b [Position],
        levels: &'b [GridLevel<'b>],
    ) -> Result<SceneView<'b>, SceneError>
    where
        'a: 'b,
    {
        let view = self.with_geometry(FrameGeometry { header, positions, nodes: &[], prims: &[] })?;
        if self.grid.is_some() || self.bvh.is_some() || levels.len() > MAX_LEVELS {
            return Err(SceneError::BadGrid);
        }
        let bounds = (Vec3::from(header.bounds_min), Vec3::from(header.bounds_max));
        for level in levels {
            check_level(level, self.triangles.len() as u32, bounds)?;
        }
        Ok(SceneView { levels, ..view })
    }
}

/// Checks one level.
fn check_level(l: &GridLevel<'_>, nt: u32, (lo, hi): (Vec3, Vec3)) -> Result<(), SceneError> {
    use SectionKind as K;
    if !finite3(l.min) || !l.cell.is_finite() || l.cell <= 0.0 {
        return Err(SceneError::NonFinite { section: K::Grid, record: 0 });
    }
    let dims_ok = l.dims.iter().chain(&l.wrap.dims).all(|&d| (1..=MAX_DIM).contains(&d));
    let physical = l.wrap.dims.iter().try_fold(1u32, |acc, &d| acc.checked_mul(d));
    if !dims_ok || physical != Some(l.cells.len() as u32) || l.cells.len() as u32 >= NULL_INDEX {
        return Err(SceneError::BadGrid);
    }
    let (min, max) = corners(l);
    if !(min.cmple(lo).all() && max.cmpge(hi).all() && max.is_finite()) {
        return Err(SceneError::OutOfBounds { section: K::Grid, record: 0 });
    }
    let nl = l.lists.len() as u32;
    for (i, &c) in l.cells.iter().enumerate() {
        if c != NULL_INDEX && c >= nl {
            return Err(SceneError::IndexOutOfRange { section: K::GridCells, record: i as u32, value: c, limit: nl });
        }
    }
    // A walk from any offset ends at a null entry inside the lists.
    if l.lists.last().is_some_and(|&e| e != NULL_INDEX) {
        return Err(SceneError::UnterminatedList);
    }
    indices_below(K::PrimLists, l.lists.iter().copied(), nt, true)
}

/// The logical box of a level.
fn corners(l: &GridLevel<'_>) -> (Vec3, Vec3) {
    let min = Vec3::from(l.min);
    (min, min + Vec3::new(l.dims[0] as f32, l.dims[1] as f32, l.dims[2] as f32) * l.cell)
}

/// A checked level's grid view, its reads labelled from `addr` on.
#[inline]
pub(super) fn level_view<'b>(l: &GridLevel<'b>, addr: u32) -> GridView<'b> {
    let (min, max) = corners(l);
    GridView {
        min,
        max,
        cell_size: Vec3::splat(l.cell),
        dims: l.dims,
        cells: l.cells,
        lists: l.lists,
        cells_addr: addr,
        lists_addr: addr.wrapping_add(4 * l.cells.len() as u32),
        wrap: Some(l.wrap),
    }
}
